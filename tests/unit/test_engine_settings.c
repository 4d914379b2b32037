/* test_engine_settings.c - the table of engine settings (lib/engine/engine_settings.h)
 * covers every field of engine_config_t, so the config parser, trajreplay's
 * options and the reload comparison (engine_config_same) cannot miss one;
 * config/trajd.conf documents every key with its real default; trajreplay
 * --help lists every option.  Run from the repository root with BUILD set
 * (tests/run.sh does). */
#include "test.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg_string.h"
#include "delay.h"
#include "engine_settings.h"

static size_t type_size(engine_setting_type_t t)
{
    switch (t) {
    case ENGINE_SETTING_DOUBLE: return sizeof(double);
    case ENGINE_SETTING_UNSIGNED: return sizeof(unsigned);
    case ENGINE_SETTING_ENUM: return sizeof(int);
    case ENGINE_SETTING_BOOL: return sizeof(int);
    case ENGINE_SETTING_VEC3: return ENGINE_AXES * sizeof(double);
    case ENGINE_SETTING_INT64: return sizeof(int64_t);
    }
    return 0;
}

static size_t type_align(engine_setting_type_t t)
{
    return t == ENGINE_SETTING_VEC3 ? _Alignof(double) : type_size(t);
}

/* Given the table, then its entries follow each other in the struct with
 * only the padding the C ABI puts before each (smaller than its alignment),
 * and the last one ends where the struct ends (but for tail padding): a
 * field of engine_config_t with no entry leaves a hole and fails here. */
static void test_table_tiles_the_struct(void **state)
{
    (void)state;
    size_t end = 0;
    for (size_t i = 0; i < engine_settings_count; i++) {
        const engine_setting_t *s = &engine_settings[i];
        size_t al = type_align(s->type);
        size_t expect = (end + al - 1) / al * al;
        if (s->offset != expect)
            fail_msg("%s at offset %zu, expected %zu (after the previous entry ending at %zu): "
                     "a field of engine_config_t is missing from engine_settings[], or the "
                     "table is out of the struct's order",
                     s->name, s->offset, expect, end);
        if (s->size != type_size(s->type))
            fail_msg("%s: size %zu does not match its type's %zu", s->name, s->size,
                     type_size(s->type));
        end = s->offset + s->size;
    }
    size_t al = _Alignof(engine_config_t);
    if ((end + al - 1) / al * al != sizeof(engine_config_t))
        fail_msg("the table ends at %zu, engine_config_t is %zu bytes: a field at its end is "
                 "missing from engine_settings[]",
                 end, sizeof(engine_config_t));
}

/* Given the struct's declaration in lib/engine/engine.h (read as text, so a
 * field hidden in ABI padding cannot escape), then every field name is a
 * table entry and the table has no entry that is not a field. */
static void test_table_names_every_declared_field(void **state)
{
    (void)state;
    FILE *f = fopen("lib/engine/engine.h", "r");
    assert_non_null(f);
    static char text[1 << 17];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = 0;
    /* the body of the typedef that ends with "} engine_config_t;" */
    char *close = strstr(text, "} engine_config_t;");
    assert_non_null(close);
    *close = 0;
    char *open = strrchr(text, '{');
    assert_non_null(open);
    /* blank out comments */
    for (char *c = open; (c = strstr(c, "/*"));) {
        char *e = strstr(c, "*/");
        assert_non_null(e);
        memset(c, ' ', (size_t)(e + 2 - c));
    }
    size_t fields = 0;
    char *save = NULL;
    for (char *decl = strtok_r(open + 1, ";", &save); decl; decl = strtok_r(NULL, ";", &save)) {
        char *br = strchr(decl, '[');
        if (br)
            *br = 0;
        char *e = decl + strlen(decl);
        while (e > decl && isspace((unsigned char)e[-1]))
            *--e = 0;
        char *b = e;
        while (b > decl && (isalnum((unsigned char)b[-1]) || b[-1] == '_'))
            b--;
        if (!*b)
            continue; /* only blanks after the last ';' */
        fields++;
        if (!engine_setting_find(b))
            fail_msg("engine_config_t field '%s' has no entry in engine_settings[]", b);
    }
    assert_int_equal(fields, engine_settings_count);
}

/* Given two equal configurations, when any one field of the table differs
 * (by one bit), then engine_config_same says they differ and the entry of
 * that field is the only one that does. */
static void test_same_notices_every_field(void **state)
{
    (void)state;
    engine_config_t a, b;
    engine_config_default(&a);
    engine_config_default(&b);
    assert_true(engine_config_same(&a, &b));
    for (size_t i = 0; i < engine_settings_count; i++) {
        const engine_setting_t *s = &engine_settings[i];
        for (size_t byte = 0; byte < s->size; byte++) {
            b = a;
            ((unsigned char *)&b)[s->offset + byte] ^= 0x10;
            if (engine_config_same(&a, &b))
                fail_msg("engine_config_same misses byte %zu of %s", byte, s->name);
            for (size_t j = 0; j < engine_settings_count; j++)
                assert_int_equal(engine_setting_same(&engine_settings[j], &a, &b), j != i);
        }
    }
}

/* Given each setting's default written by engine_setting_format, then
 * engine_setting_parse reads back the same bits; a bad value is refused
 * with a message and leaves the field alone. */
static void test_parse_format_round_trip(void **state)
{
    (void)state;
    engine_config_t d, c;
    engine_config_default(&d);
    for (size_t i = 0; i < engine_settings_count; i++) {
        const engine_setting_t *s = &engine_settings[i];
        char text[128], why[160];
        assert_true(engine_setting_format(s, &d, text, sizeof text) < (int)sizeof text);
        memset(&c, 0x5a, sizeof c);
        if (s->flags & ENGINE_SETTING_DERIVED) {
            assert_int_equal(engine_setting_parse(s, text, &c, why, sizeof why), -ENGINE_ECONFIG);
            continue;
        }
        if (engine_setting_parse(s, text, &c, why, sizeof why))
            fail_msg("%s: default '%s' refused: %s", s->name, text, why);
        assert_true(engine_setting_same(s, &c, &d));
        engine_config_t before = c;
        why[0] = 0;
        assert_int_equal(engine_setting_parse(s, "1,2,x", &c, why, sizeof why), -ENGINE_ECONFIG);
        assert_non_null(strstr(why, "expected"));
        assert_memory_equal(&c, &before, sizeof c);
        if (s->type == ENGINE_SETTING_DOUBLE || s->type == ENGINE_SETTING_UNSIGNED) {
            snprintf(text, sizeof text, "%.17g", s->max * 2 + 1);
            assert_int_equal(engine_setting_parse(s, text, &c, why, sizeof why), -ENGINE_ECONFIG);
            snprintf(text, sizeof text, "%.17g", s->min - 1);
            assert_int_equal(engine_setting_parse(s, text, &c, why, sizeof why), -ENGINE_ECONFIG);
            assert_memory_equal(&c, &before, sizeof c);
        }
    }
    /* names and options are unique */
    for (size_t i = 0; i < engine_settings_count; i++)
        for (size_t j = 0; j < i; j++) {
            assert_string_not_equal(engine_settings[i].name, engine_settings[j].name);
            if (engine_settings[i].option && engine_settings[j].option)
                assert_string_not_equal(engine_settings[i].option, engine_settings[j].option);
        }
}

/* Given an [object.NAME] section with one engine key, then the config
 * parser routes every key of the table (valid default: accepted with that
 * value; a bad value: refused at that line naming the key), and refuses the
 * derived period_ns as an unknown key (it comes from rate_hz). */
static void test_cfg_reads_every_key(void **state)
{
    (void)state;
    engine_config_t d;
    engine_config_default(&d);
    for (size_t i = 0; i < engine_settings_count; i++) {
        const engine_setting_t *s = &engine_settings[i];
        char val[128], text[512], err[512];
        engine_setting_format(s, &d, val, sizeof val);
        snprintf(text, sizeof text,
                 "[object.b]\ninput = replay\nreplay.track = "
                 "tests/data/n2k_furuno_figure8_src52.csv\noutput = stdout\n%s = %s\n",
                 s->name, val);
        cfg_t *c = NULL;
        int rc = cfg_load_string(text, "t.conf", &c, err, sizeof err);
        if (s->flags & ENGINE_SETTING_DERIVED) {
            assert_int_equal(rc, -CFG_EUNKNOWN);
            continue;
        }
        if (rc)
            fail_msg("%s = %s: %s", s->name, val, err);
        assert_true(engine_setting_same(s, &c->obj[0].engine, &d));
        cfg_free(c);
        snprintf(text, sizeof text,
                 "[object.b]\ninput = replay\nreplay.track = "
                 "tests/data/n2k_furuno_figure8_src52.csv\noutput = stdout\n%s = bogus\n",
                 s->name);
        rc = cfg_load_string(text, "t.conf", &c, err, sizeof err);
        assert_int_equal(rc, -CFG_EVALUE);
        char path[sizeof cfg_string_dir + 256], prefix[sizeof path + 128];
        cfg_string_path("t.conf", path, sizeof path);
        snprintf(prefix, sizeof prefix, "%s:5: [object.b] %s: expected", path, s->name);
        if (strncmp(err, prefix, strlen(prefix)) != 0)
            fail_msg("expected '%s...', got '%s'", prefix, err);
    }
}

/* Given config/trajd.conf, then its [object.*] section documents every
 * engine key exactly once as "#key = value", and that value is
 * engine_config_default()'s (compared after parsing, bit for bit); no
 * "#key = value" there names an engine key that does not exist. */
static void test_trajd_conf_documents_every_key(void **state)
{
    (void)state;
    FILE *f = fopen("config/trajd.conf", "r");
    assert_non_null(f);
    engine_config_t d;
    engine_config_default(&d);
    unsigned seen[64] = {0};
    assert_true(engine_settings_count <= 64);
    char line[512];
    int in_obj = 0, lineno = 0;
    while (fgets(line, sizeof line, f)) {
        lineno++;
        line[strcspn(line, "\n")] = 0;
        if (line[0] == '[') {
            in_obj = strncmp(line, "[object.", 8) == 0;
            continue;
        }
        char *eq = strstr(line, " = ");
        if (!in_obj || line[0] != '#' || !islower((unsigned char)line[1]) || !eq)
            continue;
        *eq = 0;
        const char *key = line + 1, *val = eq + 3;
        if (strchr(key, '.') || strcmp(key, "input") == 0 || strcmp(key, "output") == 0)
            continue; /* a transport's key, or the object's wiring */
        if (strncmp(key, "safety_", 7) == 0 || strncmp(key, "position_m", 10) == 0 ||
            strcmp(key, "writable") == 0)
            continue; /* the safety monitor's bounds and box, writable: not engine
                         settings (cfg.h, lib/safety; their defaults are test_cfg's) */
        const engine_setting_t *s = engine_setting_find(key);
        if (!s || (s->flags & ENGINE_SETTING_DERIVED))
            fail_msg("trajd.conf:%d: '%s' is not an engine key", lineno, key);
        seen[s - engine_settings]++;
        engine_config_t c = d;
        char why[160];
        memset((char *)&c + s->offset, 0x5a, s->size);
        if (engine_setting_parse(s, val, &c, why, sizeof why))
            fail_msg("trajd.conf:%d: %s = %s: %s", lineno, key, val, why);
        if (!engine_setting_same(s, &c, &d)) {
            char def[128];
            engine_setting_format(s, &d, def, sizeof def);
            fail_msg("trajd.conf:%d: documents %s = %s, the default is %s", lineno, key, val, def);
        }
    }
    fclose(f);
    for (size_t i = 0; i < engine_settings_count; i++) {
        if (engine_settings[i].flags & ENGINE_SETTING_DERIVED)
            continue;
        if (seen[i] != 1)
            fail_msg("config/trajd.conf documents '#%s = ...' %u times in [object.*] (want 1)",
                     engine_settings[i].name, seen[i]);
    }
}

/* Given trajreplay --help, then it lists every engine option with its key
 * and its default. */
static void test_trajreplay_help_lists_every_setting(void **state)
{
    (void)state;
    const char *build = getenv("BUILD");
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "'%s/bin/trajreplay' --help", build ? build : "build");
    FILE *p = popen(cmd, "r");
    assert_non_null(p);
    static char help[1 << 16];
    size_t n = fread(help, 1, sizeof help - 1, p);
    help[n] = 0;
    assert_int_equal(pclose(p), 0);
    engine_config_t d;
    engine_config_default(&d);
    for (size_t i = 0; i < engine_settings_count; i++) {
        const engine_setting_t *s = &engine_settings[i];
        if (s->flags & ENGINE_SETTING_DERIVED)
            continue;
        char want[256], def[128];
        snprintf(want, sizeof want, "  --%s %s ", s->option, s->arg);
        if (!strstr(help, want))
            fail_msg("trajreplay --help does not list '%s'", want);
        engine_setting_format(s, &d, def, sizeof def);
        snprintf(want, sizeof want, "(key %s, default %s)", s->name, def);
        if (!strstr(help, want))
            fail_msg("trajreplay --help does not say '%s'", want);
    }
}

/* Given a max_lookahead too short for any fragment, which picks a local
 * method (issue 31), then the stated D says which, by the name the settings
 * table gives it (hermite-c2 at 2, hermite-c2-centred at 3); with the
 * fragments (18) no method is named. */
static void test_delay_names_a_picked_local_method(void **state)
{
    (void)state;
    static const struct {
        unsigned la;
        const char *want;
    } cases[] = {{2, " (method hermite-c2) "}, {3, " (method hermite-c2-centred) "}, {18, NULL}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        engine_config_t c;
        engine_delay_t d;
        char line[400];
        engine_config_default(&c);
        c.max_lookahead = cases[i].la;
        assert_int_equal(engine_delay_of(&c, 0.1, 5.0, &d), 0);
        engine_delay_format(&d, line, sizeof line);
        if (cases[i].want)
            assert_non_null(strstr(line, cases[i].want));
        else
            assert_null(strstr(line, "(method"));
    }
}

/* Given an accuracy tighter than the default that no fragment meets within
 * max_lookahead, then the configuration is refused, saying so (it picked a
 * local method, far less accurate than asked: hermite-c2-centred, 0.93 m on
 * the bundled figure-8 against 5e-8 m for the default cubic); at the
 * default accuracy (and a looser one), a max_lookahead too short for it
 * still picks a local method (issue 31), and one that fits is untouched. */
static void test_accuracy_not_met_is_refused(void **state)
{
    (void)state;
    static const struct {
        const char *accuracy; /* NULL: the default */
        unsigned la;
        int ok;
        int local;
    } cases[] = {{"1e-9", 18, 0, 0}, {"1e-20", 18, 0, 0}, {"1e-9", 2, 0, 0},
                 {NULL, 14, 1, 1},   {NULL, 2, 1, 1},     {"0.1", 2, 1, 1},
                 {"0.1", 6, 1, 0},   {"1e-9", 40, 1, 0},  {"3e-7", 18, 1, 0}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        engine_config_t c, r;
        char why[160];
        const char *w = NULL;
        engine_config_default(&c);
        c.max_lookahead = cases[i].la;
        if (cases[i].accuracy)
            assert_int_equal(engine_setting_parse(engine_setting_find("accuracy"),
                                                  cases[i].accuracy, &c, why, sizeof why),
                             0);
        int rc = engine_config_check(&c, &w);
        if (cases[i].ok != (rc == 0))
            fail_msg("accuracy %s, max_lookahead %u: %s", cases[i].accuracy, cases[i].la,
                     rc == 0 ? "accepted" : w);
        if (!cases[i].ok) {
            assert_non_null(strstr(w, "accuracy"));
            continue;
        }
        assert_int_equal(engine_config_resolve(&c, &r), 0);
        assert_int_equal(r.method >= ENGINE_METHOD_HERMITE, cases[i].local);
    }
}

/* Given fragment set alone, at or below the overlap accuracy picks, then the
 * reason names fragment and says overlap is auto from accuracy (it named
 * overlap, a key the user never set). */
static void test_fragment_alone_says_why(void **state)
{
    (void)state;
    engine_config_t c;
    const char *w = NULL;
    char why[160];
    engine_config_default(&c);
    assert_int_equal(
        engine_setting_parse(engine_setting_find("fragment"), "10", &c, why, sizeof why), 0);
    assert_int_equal(engine_config_check(&c, &w), -ENGINE_ECONFIG);
    assert_non_null(strstr(w, "fragment: must be above the overlap, which accuracy picks"));
    /* both given: the overlap's own rule */
    assert_int_equal(
        engine_setting_parse(engine_setting_find("overlap"), "12", &c, why, sizeof why), 0);
    assert_int_equal(engine_config_check(&c, &w), -ENGINE_ECONFIG);
    assert_non_null(strstr(w, "overlap: must be even"));
}

/* Given a per-axis jerk limit, then fragment and overlap set by hand below
 * what accuracy picks are refused with the reason and the overlap to use
 * (with fragment 6 and overlap 2 the junctions' acceleration steps made 57
 * m/s^3 on a 2 m/s^3 axis, and trajd's monitor held the object); left auto,
 * or without a jerk limit, they pass. */
static void test_axis_jerk_needs_the_accuracy_overlap(void **state)
{
    (void)state;
    engine_config_t c;
    char why[240];
    engine_config_default(&c);
    c.fragment = 6;
    c.overlap = 2;
    assert_int_equal(engine_config_check(&c, NULL), 0);
    assert_int_equal(engine_axis_jerk_check(&c, why, sizeof why), 0); /* no jerk limit */
    c.axis_max_jerk_m_s3[0] = 2.0;
    assert_int_equal(engine_axis_jerk_check(&c, why, sizeof why), -ENGINE_ECONFIG);
    assert_non_null(strstr(why, "axis_max_jerk_m_s3 with overlap 2"));
    assert_non_null(strstr(why, "leave fragment and overlap auto"));
    c.fragment = c.overlap = ENGINE_AUTO;
    assert_int_equal(engine_axis_jerk_check(&c, why, sizeof why), 0);
}

/* Given the defaults, then no setting is unused; given start_vel_m_s without
 * ends = clamped, or smooth_ctrl without method = smooth, then each is said to
 * have no effect (they were accepted and ignored unsaid), and not once the
 * setting that uses it is there. */
static void test_unused_settings_said(void **state)
{
    (void)state;
    engine_config_t c;
    char why[160];
    engine_config_default(&c);
    for (size_t i = 0; i < engine_settings_count; i++)
        assert_null(engine_setting_unused(&engine_settings[i], &c));
    const engine_setting_t *sv = engine_setting_find("start_vel_m_s");
    const engine_setting_t *sc = engine_setting_find("smooth_ctrl");
    assert_int_equal(engine_setting_parse(sv, "3,0,0", &c, why, sizeof why), 0);
    assert_int_equal(engine_setting_parse(sc, "5", &c, why, sizeof why), 0);
    assert_non_null(strstr(engine_setting_unused(sv, &c), "ends = clamped"));
    assert_non_null(strstr(engine_setting_unused(sc, &c), "method = smooth"));
    assert_int_equal(
        engine_setting_parse(engine_setting_find("ends"), "clamped", &c, why, sizeof why), 0);
    assert_int_equal(
        engine_setting_parse(engine_setting_find("method"), "smooth", &c, why, sizeof why), 0);
    assert_null(engine_setting_unused(sv, &c));
    assert_null(engine_setting_unused(sc, &c));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_table_tiles_the_struct),
        cmocka_unit_test(test_table_names_every_declared_field),
        cmocka_unit_test(test_same_notices_every_field),
        cmocka_unit_test(test_parse_format_round_trip),
        cmocka_unit_test(test_cfg_reads_every_key),
        cmocka_unit_test(test_trajd_conf_documents_every_key),
        cmocka_unit_test(test_trajreplay_help_lists_every_setting),
        cmocka_unit_test(test_delay_names_a_picked_local_method),
        cmocka_unit_test(test_accuracy_not_met_is_refused),
        cmocka_unit_test(test_fragment_alone_says_why),
        cmocka_unit_test(test_axis_jerk_needs_the_accuracy_overlap),
        cmocka_unit_test(test_unused_settings_said),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
