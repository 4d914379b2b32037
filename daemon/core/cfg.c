/*
 * cfg.c - parse and check trajd's INI configuration (see cfg.h).
 *
 * libinih does the INI syntax; this file reads the lines for it (so it knows
 * the line number of everything, including section headers and sections
 * with no keys, which inih never reports) and stops at the first error.
 */
#include "cfg.h"
#include "delay.h"
#include "cfg_box.h"
#include "cfg_files.h"

#include <ctype.h>
#include <errno.h>
#include <grp.h>
#include <ini.h>
#include <math.h>
#include <pwd.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <syslog.h>

#include "engine_settings.h"
#include "log.h"
#include "transport.h"

/* inih reads a line into a buffer of INI_MAX_LINE bytes; longer lines would be
 * split and misparsed silently, so they are refused. */
#define CFG_LINE_MAX INI_MAX_LINE

/* ---- parser state ---------------------------------------------------- */

enum sec_kind { SEC_NONE, SEC_DAEMON, SEC_RT, SEC_OBJ, SEC_TRANSPORT };

typedef struct {
    char key[96]; /* "section\nkey" */
} seen_t;

typedef struct {
    cfg_t *c;
    FILE *fp;     /* the source (load_stream) */
    int line;     /* lines read so far */
    int indented; /* the line just read starts with blanks (inih: a continuation) */
    /* current section */
    enum sec_kind kind;
    int sec_index; /* object index or transport index */
    char sec_name[64];
    int sec_line;
    /* per-object: first line of a "T." key, by transport, to report keys for
     * transports the object does not use */
    int tkey_line[CFG_OBJECTS_MAX][CFG_TRANSPORTS_MAX];
    int rate_line;
    int clock_line;
    /* duplicates */
    seen_t *seen;
    size_t nseen, capseen;
    /* first error */
    int err;
    int err_line;
    char msg[CFG_WHY_MAX + 128];
} parse_t;

static void fail(parse_t *p, int code, int line, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void fail(parse_t *p, int code, int line, const char *fmt, ...)
{
    if (p->err)
        return; /* keep the first */
    p->err = code;
    p->err_line = line;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(p->msg, sizeof p->msg, fmt, ap);
    va_end(ap);
    /* the file's own text in it (a name, a value) as printable text: a log
     * line must not carry control characters */
    for (unsigned char *c = (unsigned char *)p->msg; *c; c++)
        if (*c < 0x20 || *c == 0x7f)
            *c = '?';
}

/* Returns 1 if (section, key) was already seen, else records it. */
static int seen_before(parse_t *p, const char *section, const char *key)
{
    char k[96];
    snprintf(k, sizeof k, "%s\n%s", section, key);
    for (size_t i = 0; i < p->nseen; i++)
        if (strcmp(p->seen[i].key, k) == 0)
            return 1;
    if (p->nseen == p->capseen) {
        size_t cap = p->capseen ? p->capseen * 2 : 32;
        seen_t *s = realloc(p->seen, cap * sizeof *s);
        if (!s)
            return 0; /* cannot record: duplicate detection degrades, parsing goes on */
        p->seen = s;
        p->capseen = cap;
    }
    snprintf(p->seen[p->nseen++].key, sizeof p->seen[0].key, "%s", k);
    return 0;
}

static int valid_name(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= CFG_NAME_MAX)
        return 0;
    for (size_t i = 0; i < n; i++)
        if (!isalnum((unsigned char)s[i]) && s[i] != '_' && s[i] != '-')
            return 0;
    return 1;
}

static int alloc_block(void **slot, size_t size, void (*dflt)(void *))
{
    if (!size)
        return 0;
    *slot = calloc(1, size);
    if (!*slot)
        return -CFG_ENOMEM;
    if (dflt)
        dflt(*slot);
    return 0;
}

/* A "[name]" line was read at p->line. */
static void begin_section(parse_t *p, const char *name)
{
    cfg_t *c = p->c;
    snprintf(p->sec_name, sizeof p->sec_name, "%s", name);
    p->sec_line = p->line;
    p->kind = SEC_NONE;
    if (seen_before(p, "", name)) {
        fail(p, CFG_EDUP, p->line, "[%s]: section given twice", name);
        return;
    }
    if (strcmp(name, "daemon") == 0) {
        p->kind = SEC_DAEMON;
    } else if (strcmp(name, "realtime") == 0) {
        p->kind = SEC_RT;
    } else if (strncmp(name, "object.", 7) == 0) {
        const char *on = name + 7;
        if (!valid_name(on)) {
            fail(p, CFG_EVALUE, p->line,
                 "[%s]: object name must be 1-%d characters of A-Z a-z 0-9 _ -", name,
                 CFG_NAME_MAX - 1);
            return;
        }
        if (c->nobj == CFG_OBJECTS_MAX) {
            fail(p, CFG_EVALUE, p->line, "[%s]: more than %d objects", name, CFG_OBJECTS_MAX);
            return;
        }
        cfg_obj_t *o = &c->obj[c->nobj];
        memset(o, 0, sizeof *o);
        /* valid_name() bounded it: strlen(on) < CFG_NAME_MAX = sizeof o->name */
        memcpy(o->name, on, strlen(on) + 1);
        o->line = p->line;
        engine_config_default(&o->engine);
        o->safety_max_step_m = o->safety_max_speed_m_s = o->safety_max_accel_m_s2 = -1;
        o->writable = -1;
        o->id = -1;
        for (unsigned t = 0; transport_table[t]; t++)
            if (alloc_block(&o->tcfg[t], transport_table[t]->obj_cfg_size,
                            transport_table[t]->obj_cfg_default) < 0) {
                fail(p, CFG_ENOMEM, p->line, "out of memory");
                return;
            }
        p->sec_index = (int)c->nobj++;
        p->kind = SEC_OBJ;
    } else {
        const transport_t *t = transport_find(name);
        if (!t || !t->cfg_key) {
            fail(p, CFG_EUNKNOWN, p->line,
                 "unknown section [%s] (expected [daemon], [realtime], [object.NAME] or a "
                 "transport's section)",
                 name);
            return;
        }
        p->sec_index = transport_index(t);
        c->tline[p->sec_index] = p->line;
        p->kind = SEC_TRANSPORT;
    }
}

/* inih's reader: one line per call; spots section headers and long lines. */
static char *reader(char *str, int num, void *stream)
{
    parse_t *p = stream;
    if (p->err)
        return NULL; /* stop at the first error */
    size_t n = 0;
    int nul = 0;
    /* byte by byte (not fgets): a NUL byte must not hide the rest of its line */
    int ch;
    while (n + 1 < (size_t)num && (ch = getc(p->fp)) != EOF) {
        nul |= ch == '\0';
        str[n++] = (char)ch;
        if (ch == '\n')
            break;
    }
    str[n] = 0;
    if (n == 0)
        return NULL;
    p->line++;
    if (p->line == 1 && (unsigned char)str[0] == 0xEF && (unsigned char)str[1] == 0xBB &&
        (unsigned char)str[2] == 0xBF)
        memmove(str, str + 3, n - 2); /* a UTF-8 byte order mark (issue 24), and its NUL */
    if (nul) {
        fail(p, CFG_ESYNTAX, p->line, "NUL byte (binary file?)");
        return NULL;
    }
    int at_eof = feof(p->fp) || (ungetc(getc(p->fp), p->fp) == EOF);
    if (n && str[n - 1] != '\n' && !at_eof) {
        fail(p, CFG_ESYNTAX, p->line, "line longer than %d characters", CFG_LINE_MAX - 2);
        return NULL;
    }
    p->indented = str[0] == ' ' || str[0] == '\t';
    /* section header? (inih accepts "[name]" with optional spaces around) */
    const char *s = str;
    while (isspace((unsigned char)*s))
        s++;
    if (*s == '[') {
        const char *e = strchr(s, ']');
        if (e) {
            char name[64];
            const char *a = s + 1;
            while (a < e && isspace((unsigned char)*a))
                a++;
            const char *b = e;
            while (b > a && isspace((unsigned char)b[-1]))
                b--;
            size_t len = (size_t)(b - a);
            if (len >= sizeof name) {
                fail(p, CFG_EVALUE, p->line, "section name too long");
                return NULL;
            }
            memcpy(name, a, len);
            name[len] = 0;
            begin_section(p, name);
        }
    }
    return str;
}

/* "0,2-3" into a cpu_set_t. */
static int get_cpus(const cfg_kv_t *kv, cpu_set_t *set, char *why, size_t whylen)
{
    CPU_ZERO(set);
    const char *s = kv->value;
    int any = 0;
    while (*s) {
        char *end;
        long a = strtol(s, &end, 10), b;
        if (end == s || a < 0 || a >= CPU_SETSIZE)
            goto bad;
        b = a;
        s = end;
        if (*s == '-') {
            b = strtol(s + 1, &end, 10);
            if (end == s + 1 || b < a || b >= CPU_SETSIZE)
                goto bad;
            s = end;
        }
        for (long i = a; i <= b; i++)
            CPU_SET((int)i, set);
        any = 1;
        while (isspace((unsigned char)*s))
            s++;
        if (*s == ',')
            s++;
        else if (*s)
            goto bad;
        while (isspace((unsigned char)*s))
            s++;
    }
    if (any)
        return 0;
bad:
    return cfg_why(why, whylen, "expected a CPU list like 1 or 0,2-3, got '%s'", kv->value);
}

/* origin = lat,lon,alt */
static int get_origin(cfg_daemon_t *d, const cfg_kv_t *kv, char *why, size_t wl)
{
    int rc;
    char *end = NULL;
    const char *q = kv->value;
    if (!q[0]) { /* empty: the default, the first fix of the lowest id */
        d->origin_given = 0;
        return 0;
    }
    for (int a = 0; a < 3; a++) {
        d->origin[a] = strtod(q, &end);
        if (end == q || (a < 2 ? *end != ',' : *end != '\0'))
            return cfg_why(why, wl, "expected lat,lon,alt (degrees, degrees, metres), got '%s'",
                           kv->value);
        q = end + 1;
    }
    rc = geo_check(d->origin[0], d->origin[1], d->origin[2]);
    if (rc < 0)
        return cfg_why(why, wl, "%s", geo_strerror(rc));
    d->origin_given = 1;
    d->origin_line = kv->line;
    return 0;
}

/* [daemon] user and control_group name a user and a group of this system, looked up
 * when the file is read (and by --check-config), not first when the sockets are open
 * and privileges dropped (exit 77 then, with no file:line).  Empty: none. */
static int user_exists(const char *name, char *why, size_t wl)
{
    struct passwd pw, *r = NULL;
    char buf[4096];
    if (!name[0])
        return 0;
    int e = getpwnam_r(name, &pw, buf, sizeof buf, &r);
    if (r)
        return 0;
    return cfg_why(why, wl, "no user '%s' on this system%s%s", name, e ? ": " : "",
                   e ? strerror(e) : "");
}

static int group_exists(const char *name, char *why, size_t wl)
{
    struct group gr, *r = NULL;
    char buf[16384];
    if (!name[0])
        return 0;
    int e = getgrnam_r(name, &gr, buf, sizeof buf, &r);
    if (r)
        return 0;
    return cfg_why(why, wl, "no group '%s' on this system%s%s", name, e ? ": " : "",
                   e ? strerror(e) : "");
}

static int key_daemon(cfg_t *c, parse_t *p, const cfg_kv_t *kv, char *why, size_t wl)
{
    cfg_daemon_t *d = &c->daemon;
    int rc;
    if (strcmp(kv->key, "rate_hz") == 0) {
        /* the engine's period limits, as a rate */
        rc = cfg_get_double(kv, 1e9 / (double)ENGINE_PERIOD_NS_MAX,
                            1e9 / (double)ENGINE_PERIOD_NS_MIN, &d->rate_hz, why, wl);
        p->rate_line = kv->line;
        return rc;
    }
    if (strcmp(kv->key, "speed") == 0)
        return cfg_get_double(kv, 0.001, 1000, &d->speed, why, wl);
    if (strcmp(kv->key, "status_interval_s") == 0)
        return cfg_get_double(kv, 0, 86400, &d->status_interval_s, why, wl);
    if (strcmp(kv->key, "stop_timeout_s") == 0)
        return cfg_get_double(kv, 0, 3600, &d->stop_timeout_s, why, wl);
    if (strcmp(kv->key, "exit_when_done") == 0)
        return cfg_get_bool(kv, &d->exit_when_done, why, wl);
    if (strcmp(kv->key, "origin") == 0)
        return get_origin(d, kv, why, wl);
    if (strcmp(kv->key, "clock") == 0) {
        static const char *const ck[] = {"auto", "epoch", "relative", NULL};
        p->clock_line = kv->line;
        return cfg_get_enum(kv, ck, &d->clock, why, wl);
    }
    if (strcmp(kv->key, "delay_s") == 0)
        return cfg_get_double(kv, 0, 3600, &d->delay_s, why, wl);
    if (strcmp(kv->key, "catchup") == 0)
        return cfg_get_double(kv, 0, 1, &d->catchup, why, wl);
    if (strcmp(kv->key, "drift_max_ppm") == 0)
        return cfg_get_double(kv, 0, 1000, &d->drift_max_ppm, why, wl);
    if (strcmp(kv->key, "clock_window_s") == 0)
        return cfg_get_double(kv, 1, 1e9, &d->clock_window_s, why, wl);
    if (strcmp(kv->key, "control_socket") == 0) /* 108: sizeof sockaddr_un.sun_path */
        return !kv->value[0] || cfg_get_path(kv, d->control_socket, 108, why, wl) == 0
                   ? 0
                   : cfg_why(why, wl, "expected a path of at most 107 bytes (a Unix socket's)");
    if (strcmp(kv->key, "control_group") == 0) {
        if (strlen(kv->value) >= sizeof d->control_group)
            return cfg_why(why, wl, "expected a group name of at most %zu characters",
                           sizeof d->control_group - 1);
        snprintf(d->control_group, sizeof d->control_group, "%s", kv->value);
        return group_exists(d->control_group, why, wl);
    }
    if (strcmp(kv->key, "user") == 0) {
        if (strlen(kv->value) >= sizeof d->user)
            return cfg_why(why, wl, "expected a user name of at most %zu characters",
                           sizeof d->user - 1);
        snprintf(d->user, sizeof d->user, "%s", kv->value);
        return user_exists(d->user, why, wl);
    }
    if (strcmp(kv->key, "log_level") == 0) {
        static const char *const lv[] = {"err", "warning", "notice", "info", "debug", NULL};
        static const int lvv[] = {LOG_ERR, LOG_WARNING, LOG_NOTICE, LOG_INFO, LOG_DEBUG};
        int i;
        rc = cfg_get_enum(kv, lv, &i, why, wl);
        if (rc == 0)
            d->log_level = lvv[i];
        return rc;
    }
    return -CFG_EUNKNOWN;
}

static int key_rt(cfg_t *c, const cfg_kv_t *kv, char *why, size_t wl)
{
    long long ll;
    if (strcmp(kv->key, "fifo_priority") == 0) {
        int rc = cfg_get_int(kv, 0, 99, &ll, why, wl);
        if (rc == 0)
            c->rt.fifo_priority = (int)ll;
        return rc;
    }
    if (strcmp(kv->key, "mlockall") == 0)
        return cfg_get_bool(kv, &c->rt.mlockall, why, wl);
    if (strcmp(kv->key, "cpu_affinity") == 0) {
        if (!kv->value[0]) {
            c->rt.affinity_set = 0;
            return 0;
        }
        int rc = get_cpus(kv, &c->rt.affinity, why, wl);
        if (rc == 0)
            c->rt.affinity_set = 1;
        return rc;
    }
    return -CFG_EUNKNOWN;
}

/* "replay, csv, ..." : the names of the transports that have role, for messages. */
static void transport_names(unsigned role, char *list, size_t len)
{
    list[0] = '\0';
    for (unsigned k = 0; transport_table[k]; k++)
        if (transport_table[k]->roles & role) {
            size_t m = strlen(list);
            snprintf(list + m, len - m, "%s%s", m ? ", " : "", transport_table[k]->name);
        }
}

/* The safety monitor's and the start position's keys (not engine settings). */
static int key_obj_drive(cfg_obj_t *o, const cfg_kv_t *kv, char *why, size_t wl)
{
    if (strcmp(kv->key, "safety_max_step_m") == 0)
        return cfg_get_double(kv, 0, 1e9, &o->safety_max_step_m, why, wl);
    if (strcmp(kv->key, "safety_max_speed_m_s") == 0)
        return cfg_get_double(kv, 0, 1e9, &o->safety_max_speed_m_s, why, wl);
    if (strcmp(kv->key, "safety_max_accel_m_s2") == 0)
        return cfg_get_double(kv, 0, 1e9, &o->safety_max_accel_m_s2, why, wl);
    if (strcmp(kv->key, "initial_position") == 0) {
        double v[ENGINE_AXES];
        char *end = NULL;
        const char *q = kv->value;
        for (int a = 0; a < ENGINE_AXES; a++) {
            v[a] = strtod(q, &end);
            if (end == q || !isfinite(v[a]) || fabs(v[a]) > 1e9 ||
                (a < ENGINE_AXES - 1 ? *end != ',' : *end != '\0'))
                return cfg_why(why, wl, "expected x,y,z in metres, got '%s'", kv->value);
            q = end + 1;
        }
        memcpy(o->initial_position_m, v, sizeof v);
        o->has_initial_position = 1;
        o->initial_position_line = kv->line;
        return 0;
    }
    return -CFG_EUNKNOWN;
}

static int key_obj(parse_t *p, cfg_obj_t *o, const cfg_kv_t *kv, char *why, size_t wl)
{
    const char *dot = strchr(kv->key, '.');
    if (dot) { /* "T.key": transport T's */
        char tname[32];
        size_t n = (size_t)(dot - kv->key);
        if (n >= sizeof tname)
            return -CFG_EUNKNOWN;
        memcpy(tname, kv->key, n);
        tname[n] = 0;
        const transport_t *t = transport_find(tname);
        if (!t || !t->obj_key)
            return -CFG_EUNKNOWN;
        int ti = transport_index(t);
        cfg_kv_t sub = *kv;
        sub.key = dot + 1;
        if (!p->tkey_line[p->sec_index][ti])
            p->tkey_line[p->sec_index][ti] = kv->line;
        return t->obj_key(o->tcfg[ti], &sub, why, wl);
    }
    if (strncmp(kv->key, "safety_", 7) == 0 || strcmp(kv->key, "initial_position") == 0)
        return key_obj_drive(o, kv, why, wl);
    if (strncmp(kv->key, "position_m", 10) == 0)
        return cfg_box_key(o, kv, why, wl);
    if (strcmp(kv->key, "writable") == 0)
        return cfg_get_bool(kv, &o->writable, why, wl);
    if (strcmp(kv->key, "id") == 0) {
        long long v;
        int rc = cfg_get_int(kv, 0, CFG_ID_MAX, &v, why, wl);
        if (rc == 0) {
            o->id = (int)v;
            o->id_line = kv->line;
        }
        return rc;
    }
    if (strcmp(kv->key, "input") == 0) {
        const transport_t *t = transport_find(kv->value);
        if (!t || !(t->roles & TRANSPORT_INPUT)) {
            char list[160];
            transport_names(TRANSPORT_INPUT, list, sizeof list);
            return cfg_why(why, wl, "expected one of %s, got '%s'", list, kv->value);
        }
        o->input = t;
        return 0;
    }
    if (strcmp(kv->key, "output") == 0) {
        char buf[CFG_LINE_MAX];
        snprintf(buf, sizeof buf, "%s", kv->value);
        o->noutput = 0;
        for (char *save = NULL, *tok = strtok_r(buf, ", \t", &save); tok;
             tok = strtok_r(NULL, ", \t", &save)) {
            const transport_t *t = transport_find(tok);
            if (!t || !(t->roles & TRANSPORT_OUTPUT)) {
                char list[160];
                transport_names(TRANSPORT_OUTPUT, list, sizeof list);
                return cfg_why(why, wl, "unknown output '%s' (outputs: %s)", tok, list);
            }
            for (unsigned k = 0; k < o->noutput; k++)
                if (o->output[k] == t)
                    return cfg_why(why, wl, "output '%s' listed twice", tok);
            if (o->noutput == CFG_OUTPUTS_MAX)
                return cfg_why(why, wl, "more than %d outputs", CFG_OUTPUTS_MAX);
            o->output[o->noutput++] = t;
        }
        if (!o->noutput)
            return cfg_why(why, wl, "expected at least one output");
        return 0;
    }
    /* engine settings: lib/engine/engine_settings.h's table */
    const engine_setting_t *es = engine_setting_find(kv->key);
    if (es && !(es->flags & ENGINE_SETTING_DERIVED)) {
        size_t k = (size_t)(es - engine_settings);
        if (k < CFG_ENGINE_KEYS)
            o->eng_line[k] = kv->line;
        return engine_setting_parse(es, kv->value, &o->engine, why, wl) < 0 ? -CFG_EVALUE : 0;
    }
    return -CFG_EUNKNOWN;
}

/* inih's handler: one "key = value". */
static int handler(void *user, const char *section, const char *name, const char *value)
{
    parse_t *p = user;
    cfg_t *c = p->c;
    if (p->err)
        return 0;
    (void)section; /* == p->sec_name: the reader saw the header */
    cfg_kv_t kv = {.file = c->path,
                   .dir = c->dir,
                   .section = p->sec_name,
                   .key = name,
                   .value = value,
                   .line = p->line,
                   .object = NULL};
    char why[CFG_WHY_MAX] = "";
    int rc;
    if (p->kind == SEC_NONE && !p->sec_name[0]) {
        fail(p, CFG_ESYNTAX, p->line, "%s: key before any [section]", name);
        return 0;
    }
    if (p->indented) {
        fail(p, CFG_ESYNTAX, p->line,
             "%s: indented line (INI reads it as part of the previous value): do not indent keys",
             name);
        return 0;
    }
    if (seen_before(p, p->sec_name, name)) {
        fail(p, CFG_EDUP, p->line, "[%s] %s: given twice", p->sec_name, name);
        return 0;
    }
    const char *hash = strstr(value, " #");
    if (!hash)
        hash = strstr(value, "\t#");
    if (hash) /* a path takes it whole: said, not silently part of a file name */
        log_msg(LOG_WARNING,
                "%s:%d: [%s] %s: '%s' is taken whole, '#' and all: a comment after a value "
                "starts with ' ;' ('#' starts a comment only at the start of a line)",
                c->path, p->line, p->sec_name, name, value);
    switch (p->kind) {
    case SEC_DAEMON: rc = key_daemon(c, p, &kv, why, sizeof why); break;
    case SEC_RT: rc = key_rt(c, &kv, why, sizeof why); break;
    case SEC_OBJ:
        kv.object = c->obj[p->sec_index].name;
        rc = key_obj(p, &c->obj[p->sec_index], &kv, why, sizeof why);
        break;
    case SEC_TRANSPORT: {
        const transport_t *t = transport_table[p->sec_index];
        rc = t->cfg_key(c->tcfg[p->sec_index], &kv, why, sizeof why);
        break;
    }
    default: return 0; /* the section itself was already reported */
    }
    if (rc == -CFG_EUNKNOWN)
        fail(p, CFG_EUNKNOWN, p->line, "[%s] %s: unknown key", p->sec_name, name);
    else if (rc < 0)
        fail(p, -rc, p->line, "[%s] %s: %s", p->sec_name, name, why[0] ? why : cfg_strerror(rc));
    return rc == 0;
}

/* Every object's id: given (required with more than one object), unique. */
static void check_ids(parse_t *p)
{
    cfg_t *c = p->c;
    for (unsigned i = 0; i < c->nobj && !p->err; i++) {
        cfg_obj_t *o = &c->obj[i];
        if (o->id < 0 && c->nobj == 1) {
            o->id = 0;
            continue;
        }
        if (o->id < 0) {
            fail(p, CFG_EMISSING, o->line,
                 "[object.%s]: 'id' is missing: with more than one object each needs its own "
                 "id = 0..%d (its Modbus block and CAN ids derive from it, never from its place "
                 "in the file)",
                 o->name, CFG_ID_MAX);
            return;
        }
        for (unsigned j = 0; j < i; j++)
            if (c->obj[j].id == o->id) {
                fail(p, CFG_EDUP, o->id_line, "[object.%s] id: %d is also object '%s''s id",
                     o->name, o->id, c->obj[j].name);
                return;
            }
    }
}

/* The checks of object i alone; -1 when one failed (p->err set). */
/* The line of the engine setting a check's reason starts with ("capacity: must
 * be ...", "delay_s 2 s is ..."), if given; else the object's section line
 * (every engine error named the section's line, the key's maybe far below). */
static int eng_key_line(const cfg_obj_t *o, const char *why)
{
    char key[48];
    size_t n = 0;
    while (why && n + 1 < sizeof key &&
           (islower((unsigned char)why[n]) || isdigit((unsigned char)why[n]) || why[n] == '_')) {
        key[n] = why[n];
        n++;
    }
    key[n] = '\0';
    const engine_setting_t *es = n ? engine_setting_find(key) : NULL;
    size_t k = es ? (size_t)(es - engine_settings) : CFG_ENGINE_KEYS;
    return k < CFG_ENGINE_KEYS && o->eng_line[k] ? o->eng_line[k] : o->line;
}

static int check_obj(parse_t *p, unsigned i)
{
    cfg_t *c = p->c;
    cfg_obj_t *o = &c->obj[i];
    for (unsigned j = 0; j < i; j++)
        if (strcmp(c->obj[j].name, o->name) == 0) {
            fail(p, CFG_EDUP, o->line, "[object.%s]: object given twice", o->name);
            return -1;
        }
    if (!o->input) {
        fail(p, CFG_EMISSING, o->line, "[object.%s]: 'input' is missing", o->name);
        return -1;
    }
    if (!o->noutput) {
        fail(p, CFG_EMISSING, o->line, "[object.%s]: 'output' is missing", o->name);
        return -1;
    }
    for (unsigned t = 0; transport_table[t]; t++)
        if (p->tkey_line[i][t] && !cfg_obj_uses(o, transport_table[t])) {
            fail(p, CFG_EVALUE, p->tkey_line[i][t],
                 "[object.%s] %s.*: keys for transport '%s', which this object does not "
                 "use (input or output)",
                 o->name, transport_table[t]->name, transport_table[t]->name);
            return -1;
        }
    o->engine.period_ns = c->daemon.period_ns;
    cfg_safety_caps(o, c->daemon.period_ns);
    for (size_t k = 0; k < engine_settings_count; k++) { /* set, and no effect: said */
        const char *u = engine_setting_unused(&engine_settings[k], &o->engine);
        if (u)
            log_msg(LOG_WARNING, "%s:%d: [object.%s] %s is set but has no effect: %s", c->path,
                    o->line, o->name, engine_settings[k].name, u);
    }
    const char *ewhy = NULL;
    if (engine_config_check(&o->engine, &ewhy) < 0) {
        fail(p, CFG_EVALUE, eng_key_line(o, ewhy), "[object.%s]: engine settings: %s", o->name,
             ewhy ? ewhy : "invalid");
        return -1;
    }
    char dwhy[320];
    if (engine_delay_check(&o->engine, 0.0, dwhy, sizeof dwhy) < 0 || /* issue 26 */
        engine_axis_jerk_check(&o->engine, dwhy, sizeof dwhy) < 0) {
        fail(p, CFG_EVALUE, eng_key_line(o, dwhy), "[object.%s]: engine settings: %s", o->name,
             dwhy);
        return -1;
    }
    if (o->has_initial_position)
        for (int a = 0; a < ENGINE_AXES; a++)
            if (fabs(o->initial_position_m[a]) > o->engine.max_abs_m) {
                /* engine_set_position would refuse it when the daemon starts */
                fail(p, CFG_EVALUE, o->initial_position_line,
                     "[object.%s] initial_position: |%c| = %g m is above max_abs_m (%g m)", o->name,
                     "xyz"[a], fabs(o->initial_position_m[a]), o -> engine.max_abs_m);
                return -1;
            }
    return 0;
}

/* Position boxes (cfg_box.h), before the transports derive theirs: 1 on failure. */
static int check_boxes(parse_t *p)
{
    char why[CFG_WHY_MAX];
    int line = 0;
    if (cfg_box_check(p->c, &line, why, sizeof why) < 0)
        fail(p, CFG_EVALUE, line, "%s", why);
    return p->err != 0;
}

/* Outputs against inputs and each other, by identity (cfg_files.h). */
static void check_files(parse_t *p)
{
    char why[CFG_WHY_MAX];
    int line = 0;
    if (cfg_files_check(p->c, &line, why, sizeof why) < 0)
        fail(p, CFG_EVALUE, line, "%s", why);
}

static void check_all(parse_t *p)
{
    cfg_t *c = p->c;
    char why[CFG_WHY_MAX];
    if (p->err)
        return;
    c->daemon.period_ns = (int64_t)llround(1e9 / c->daemon.rate_hz);
    if (c->daemon.clock == CFG_CLOCK_EPOCH && fabs(c->daemon.speed - 1.0) > 0) {
        fail(p, CFG_EVALUE, p->clock_line,
             "[daemon] clock = epoch: needs speed = 1 (the play-out clock is real time)");
        return;
    }
    if (c->nobj == 0) {
        fail(p, CFG_EMISSING, 0, "no [object.NAME] section: nothing to do");
        return;
    }
    for (unsigned i = 0; i < c->nobj; i++)
        if (check_obj(p, i) < 0)
            return;
    check_ids(p);
    if (p->err || check_boxes(p))
        return;
    for (unsigned t = 0; transport_table[t]; t++) {
        const transport_t *tr = transport_table[t];
        if (!tr->check || !cfg_uses(c, tr))
            continue;
        why[0] = 0;
        int line = c->tline[t];
        int rc = tr->check(c, &line, why, sizeof why);
        if (rc < 0) {
            /* an object's key names its own section ([object.NAME] key: ...) */
            if (!strncmp(why, "[object.", 8))
                fail(p, rc == -CFG_EMISSING ? CFG_EMISSING : CFG_EVALUE, line, "%s", why);
            else
                fail(p, rc == -CFG_EMISSING ? CFG_EMISSING : CFG_EVALUE, line, "[%s]: %s", tr->name,
                     why[0] ? why : "invalid");
            return;
        }
    }
    check_files(p);
}

static void defaults(cfg_t *c)
{
    c->daemon.rate_hz = 100;
    c->daemon.speed = 1.0;
    c->daemon.status_interval_s = 10;
    c->daemon.stop_timeout_s = 5;
    c->daemon.exit_when_done = 0;
    c->daemon.log_level = LOG_INFO;
    c->daemon.clock = CFG_CLOCK_AUTO;
    c->daemon.delay_s = 10;
    c->daemon.catchup = 0.05;
    c->daemon.drift_max_ppm = 500;
    c->daemon.clock_window_s = 86400;
}

static int parse(parse_t *p, const char *name, const char *dir, cfg_t **out, char *err,
                 size_t errlen)
{
    cfg_t *c = calloc(1, sizeof *c);
    int rc = 0;
    if (!c) {
        snprintf(err, errlen, "%s: out of memory", name);
        return -CFG_ENOMEM;
    }
    p->c = c;
    snprintf(c->path, sizeof c->path, "%s", name);
    snprintf(c->dir, sizeof c->dir, "%s", dir);
    defaults(c);
    for (unsigned t = 0; transport_table[t]; t++)
        if (alloc_block(&c->tcfg[t], transport_table[t]->cfg_size,
                        transport_table[t]->cfg_default) < 0) {
            snprintf(err, errlen, "%s: out of memory", name);
            cfg_free(c);
            return -CFG_ENOMEM;
        }
    int line = ini_parse_stream(reader, p, handler, p);
    if (line > 0 && !p->err)
        fail(p, CFG_ESYNTAX, line, "syntax error (expected [section] or key = value)");
    else if (line > 0 && line < p->err_line) {
        /* inih found a syntax error on an earlier line than ours (e.g. a
         * section header with no ']', and the key after it out of place) */
        p->err = 0;
        fail(p, CFG_ESYNTAX, line, "syntax error (expected [section] or key = value)");
    }
    check_all(p);
    free(p->seen);
    if (p->err) {
        if (p->err_line > 0)
            snprintf(err, errlen, "%s:%d: %s", name, p->err_line, p->msg);
        else
            snprintf(err, errlen, "%s: %s", name, p->msg);
        rc = -p->err;
        cfg_free(c);
        *out = NULL;
        return rc;
    }
    *out = c;
    return 0;
}

/* cfg_load from the open stream fp (read to its end, not closed); name is
 * used in messages, dir for relative paths. */
static int load_stream(FILE *fp, const char *name, const char *dir, cfg_t **out, char *err,
                       size_t errlen)
{
    *out = NULL;
    parse_t *p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(err, errlen, "%s: out of memory", name);
        return -CFG_ENOMEM;
    }
    p->fp = fp;
    int rc = parse(p, name, dir, out, err, errlen);
    if (rc == 0 && ferror(fp)) {
        snprintf(err, errlen, "%s: read error", name);
        cfg_free(*out);
        *out = NULL;
        rc = -CFG_EIO;
    }
    free(p);
    return rc;
}

int cfg_load(const char *path, cfg_t **out, char *err, size_t errlen)
{
    *out = NULL;
    FILE *fp = fopen(path, "r");
    if (!fp) {
        snprintf(err, errlen, "%s: %s", path, strerror(errno));
        return -CFG_EIO;
    }
    struct stat sb;
    if (fstat(fileno(fp), &sb) == 0 && S_ISDIR(sb.st_mode)) {
        /* read as an empty file, it was "no [object.NAME] section" */
        snprintf(err, errlen, "%s: %s", path, strerror(EISDIR));
        fclose(fp);
        return -CFG_EIO;
    }
    char dir[PATH_MAX];
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    int rc = load_stream(fp, path, dir, out, err, errlen);
    fclose(fp);
    return rc;
}

void cfg_free(cfg_t *c)
{
    if (!c)
        return;
    for (unsigned t = 0; transport_table[t]; t++) {
        const transport_t *tr = transport_table[t];
        /* obj[nobj] may hold blocks of a section that failed half-way */
        unsigned n = c->nobj < CFG_OBJECTS_MAX ? c->nobj + 1 : c->nobj;
        for (unsigned i = 0; i < n; i++) {
            if (c->obj[i].tcfg[t] && tr->obj_cfg_fini)
                tr->obj_cfg_fini(c->obj[i].tcfg[t]);
            free(c->obj[i].tcfg[t]);
        }
        if (c->tcfg[t] && tr->cfg_fini)
            tr->cfg_fini(c->tcfg[t]);
        free(c->tcfg[t]);
    }
    for (unsigned i = 0; c->prebuilt && i < c->nobj; i++)
        engine_free(c->prebuilt[i]);
    free((void *)c->prebuilt);
    if (c->prebuilt_objs && c->prebuilt_objs->objs)
        c->prebuilt_objs->fini(c->prebuilt_objs->objs, c->nobj);
    free(c->prebuilt_objs);
    free(c);
}

engine_t *cfg_take_engine(const cfg_t *c, unsigned i)
{
    engine_t *e = c->prebuilt && i < c->nobj ? c->prebuilt[i] : NULL;
    if (e)
        c->prebuilt[i] = NULL;
    return e;
}

const void *cfg_transport(const cfg_t *c, const transport_t *t)
{
    int i = transport_index(t);
    return i < 0 ? NULL : c->tcfg[i];
}

const void *cfg_obj_transport(const cfg_obj_t *o, const transport_t *t)
{
    int i = transport_index(t);
    return i < 0 ? NULL : o->tcfg[i];
}

int cfg_obj_uses(const cfg_obj_t *o, const transport_t *t)
{
    int r = o->input == t ? 1 : 0;
    for (unsigned k = 0; k < o->noutput; k++)
        if (o->output[k] == t)
            r |= 2;
    return r;
}

int cfg_uses(const cfg_t *c, const transport_t *t)
{
    int i = transport_index(t);
    if (i >= 0 && c->tline[i])
        return 1;
    for (unsigned k = 0; k < c->nobj; k++)
        if (cfg_obj_uses(&c->obj[k], t))
            return 1;
    return 0;
}

const cfg_obj_t *cfg_obj_by_name(const cfg_t *c, const char *name)
{
    for (unsigned k = 0; k < c->nobj; k++)
        if (strcmp(c->obj[k].name, name) == 0)
            return &c->obj[k];
    return NULL;
}

int cfg_reload_check(const cfg_t *old, const cfg_t *nw, char *err, size_t errlen)
{
    for (unsigned k = 0; k < nw->nobj; k++) {
        const cfg_obj_t *o = &nw->obj[k];
        const cfg_obj_t *was = cfg_obj_by_name(old, o->name);
        if (!was || was->id == o->id)
            continue;
        snprintf(err, errlen,
                 "%s:%d: [object.%s] id: %d, running as %d: a reload never moves an object's "
                 "Modbus block or CAN ids (restart trajd to renumber)",
                 nw->path, o->id_line ? o->id_line : o->line, o->name, o->id, was->id);
        return -CFG_EVALUE;
    }
    if (old->datum_set && nw->datum_set &&
        (memcmp(&old->datum.lat0_deg, &nw->datum.lat0_deg, sizeof(double)) != 0 ||
         memcmp(&old->datum.lon0_deg, &nw->datum.lon0_deg, sizeof(double)) != 0 ||
         memcmp(&old->datum.alt0_m, &nw->datum.alt0_m, sizeof(double)) != 0)) {
        snprintf(err, errlen,
                 "%s:%d: the datum would move from %.9f,%.9f,%.3f to %.9f,%.9f,%.3f: every "
                 "geographic object's east/north/up would jump (set [daemon] origin to keep it; "
                 "restart trajd to change it)",
                 nw->path, nw->datum_line, old->datum.lat0_deg, old->datum.lon0_deg,
                 old->datum.alt0_m, nw->datum.lat0_deg, nw->datum.lon0_deg, nw->datum.alt0_m);
        return -CFG_EVALUE;
    }
    for (unsigned t = 0; transport_table[t]; t++) {
        const transport_t *tr = transport_table[t];
        char why[CFG_WHY_MAX] = "";
        int line = 0;
        if (tr->reload_check && tr->reload_check(old, nw, &line, why, sizeof why) < 0) {
            snprintf(err, errlen,
                     "%s:%d: %s (a reload never moves an object's addresses: "
                     "restart trajd to change them)",
                     nw->path, line, why);
            return -CFG_EVALUE;
        }
    }
    return 0;
}
