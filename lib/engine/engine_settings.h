/*
 * engine_settings.h - one table of the engine's settings (engine_config_t).
 *
 * Every field of engine_config_t has one entry here: its name (which is the
 * config key in [object.NAME] and the field name), its type, where it lives
 * in the struct, its range, its enum names, the long option of trajreplay
 * and a line of help.  Defaults are engine_config_default()'s.  The table
 * drives every face of a setting:
 *   - daemon/core/cfg.c parses [object.NAME] engine keys through it;
 *   - trajreplay generates its engine options and their --help from it;
 *   - daemon/core/core.c decides at reload whether an object keeps its
 *     engine with engine_config_same();
 *   - tests/unit/test_engine_settings.c checks that the table covers every
 *     field of engine_config_t (a field missing here would be kept stale
 *     across a reload), that config/trajd.conf documents every key with its
 *     real default and that trajreplay --help lists every option.
 * Adding a setting: the field and its default in engine.h/engine_settings.c, its
 * entry in engine_settings.c, its documented line in config/trajd.conf.
 *
 * Pure: parsing and formatting of text only, no I/O.
 */
#ifndef TRAJD_ENGINE_SETTINGS_H
#define TRAJD_ENGINE_SETTINGS_H
/* trajd public API: installed as <trajd/engine_settings.h> (make install; pkg-config trajd). */

#include <stddef.h>

#include "engine.h"

typedef enum {
    ENGINE_SETTING_DOUBLE = 0,   /* double, finite, in [min, max] */
    ENGINE_SETTING_UNSIGNED = 1, /* unsigned, an integer in [min, max] (decimal or 0x hex) */
    ENGINE_SETTING_ENUM = 2,     /* an enum (int-sized), one of names[] */
    ENGINE_SETTING_BOOL = 3,     /* int 0/1: yes|no, true|false, on|off, 1|0 */
    ENGINE_SETTING_VEC3 = 4,     /* double[ENGINE_AXES], "x,y,z", each finite */
    ENGINE_SETTING_INT64 = 5,    /* int64_t (period_ns only: derived, not parsed) */
} engine_setting_type_t;

/* Flags of an entry. */
#define ENGINE_SETTING_DERIVED                                                                     \
    0x1u /* not a key nor an option of its own: set by
                                       the program (period_ns = 1e9 / rate_hz) */

/* UNSIGNED that may also be "auto" (ENGINE_AUTO: picked by the engine) */
#define ENGINE_SETTING_AUTO 0x2u

typedef struct {
    const char *name;   /* config key = engine_config_t field name */
    const char *option; /* trajreplay long option, without "--" */
    engine_setting_type_t type;
    unsigned flags;           /* ENGINE_SETTING_* */
    size_t offset;            /* offsetof(engine_config_t, field) */
    size_t size;              /* sizeof the field */
    double min, max;          /* inclusive range (DOUBLE, UNSIGNED) */
    const char *const *names; /* ENUM: names by value, NULL-terminated */
    const char *arg;          /* the value in --help ("M_S", "VX,VY,VZ") */
    const char *help;         /* one line, without the default */
} engine_setting_t;

/* The table, in engine_config_t order, and its length. */
extern const engine_setting_t engine_settings[];
extern const size_t engine_settings_count;

/* The entry of config key name (any entry, DERIVED ones too), or NULL. */
const engine_setting_t *engine_setting_find(const char *name);

/* The entry whose trajreplay option is opt (without "--"), or NULL. */
const engine_setting_t *engine_setting_find_option(const char *opt);

/*
 * Parse text into s's field of cfg (nothing else changes, nor the field on
 * error).  Returns 0, or -ENGINE_ECONFIG with why (may be NULL) set to a
 * message such as "expected an integer in [4, 1024], got 'x'".  Whole-config
 * rules (overlap < fragment, ...) are engine_config_check's.  DERIVED and
 * INT64 entries are refused ("set by the program").
 */
int engine_setting_parse(const engine_setting_t *s, const char *text, engine_config_t *cfg,
                         char *why, size_t whylen);

/*
 * Write s's value in cfg as text that engine_setting_parse reads back to the
 * same bits ("60", "1e+07" is written "10000000", "0,0,0", "cubic", "yes").
 * Returns the length written (snprintf's: >= len means truncated).
 */
int engine_setting_format(const engine_setting_t *s, const engine_config_t *cfg, char *buf,
                          size_t len);

/* Name of an ENUM entry's value v, or "?" if out of range. */
const char *engine_setting_enum_name(const engine_setting_t *s, int v);

/* 1 if s's field is the same in a and b (doubles compared bit for bit). */
/* Why s, set away from its default in cfg, has no effect with cfg's other
 * settings (start_vel_m_s and end_vel_m_s without ends = clamped,
 * smooth_window and smooth_ctrl without method = smooth), for a warning; NULL
 * if it has one or is at its default. */
const char *engine_setting_unused(const engine_setting_t *s, const engine_config_t *cfg);

int engine_setting_same(const engine_setting_t *s, const engine_config_t *a,
                        const engine_config_t *b);

/* 1 if every field of the table is the same in a and b. */
int engine_config_same(const engine_config_t *a, const engine_config_t *b);

/*
 * A per-axis jerk limit (axis_max_jerk_m_s3) with fragment or overlap set by
 * hand below what accuracy picks: refused (trajd's configuration check,
 * trajreplay's options).  The fragments' junctions step the curve's
 * acceleration by about rho^(O/2) of its range (DESIGN.md), which the
 * accuracy's own pick keeps below the limit; with fragment 6 and overlap 2
 * the steps made 57 m/s^3 on a 2 m/s^3 axis, and trajd's monitor held the
 * object.  The engine itself (engine_config_check) takes such settings, for
 * the tests that drive it there.  Returns 0, or -ENGINE_ECONFIG with why.
 */
int engine_axis_jerk_check(const engine_config_t *cfg, char *why, size_t whylen);

#endif
