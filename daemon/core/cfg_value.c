/* cfg_value.c - the values of trajd.conf's keys: numbers, booleans, names,
 * paths, each checked with the reason it is refused (see cfg.h). */
#include "cfg.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char *const cfg_errors[] = {
    [CFG_OK] = "ok",
    [CFG_EUNKNOWN] = "unknown section or key",
    [CFG_EVALUE] = "bad value",
    [CFG_EMISSING] = "missing key or section",
    [CFG_EIO] = "cannot read the file",
    [CFG_ENOMEM] = "out of memory",
    [CFG_ESYNTAX] = "syntax error",
    [CFG_EDUP] = "given twice",
};

const char *cfg_strerror(int err)
{
    if (err < 0)
        err = -err;
    if (err >= CFG_ERROR_COUNT)
        return "unknown error";
    return cfg_errors[err];
}

/* ---- value helpers ---------------------------------------------------- */

int cfg_why(char *why, size_t whylen, const char *fmt, ...)
{
    if (why && whylen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(why, whylen, fmt, ap);
        va_end(ap);
    }
    return -CFG_EVALUE;
}

int cfg_get_double(const cfg_kv_t *kv, double lo, double hi, double *out, char *why, size_t whylen)
{
    char *end;
    errno = 0;
    double v = strtod(kv->value, &end);
    if (end == kv->value || *end || errno == ERANGE || !isfinite(v) || v < lo || v > hi)
        return cfg_why(why, whylen, "expected a number in [%g, %g], got '%s'", lo, hi, kv->value);
    *out = v;
    return 0;
}

int cfg_get_int(const cfg_kv_t *kv, long long lo, long long hi, long long *out, char *why,
                size_t whylen)
{
    char *end;
    errno = 0;
    const char *s = kv->value;
    int base = (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) ? 16 : 10;
    long long v = strtoll(s, &end, base);
    if (end == s || *end || errno == ERANGE || v < lo || v > hi)
        return cfg_why(why, whylen, "expected an integer in [%lld, %lld], got '%s'", lo, hi,
                       kv->value);
    *out = v;
    return 0;
}

int cfg_get_bool(const cfg_kv_t *kv, int *out, char *why, size_t whylen)
{
    static const char *const yes[] = {"yes", "true", "on", "1", NULL};
    static const char *const no[] = {"no", "false", "off", "0", NULL};
    for (int i = 0; yes[i]; i++) {
        if (strcasecmp(kv->value, yes[i]) == 0) {
            *out = 1;
            return 0;
        }
        if (strcasecmp(kv->value, no[i]) == 0) {
            *out = 0;
            return 0;
        }
    }
    return cfg_why(why, whylen, "expected yes or no, got '%s'", kv->value);
}

int cfg_get_enum(const cfg_kv_t *kv, const char *const *names, int *out, char *why, size_t whylen)
{
    char list[160] = "";
    for (int i = 0; names[i]; i++) {
        if (strcmp(kv->value, names[i]) == 0) {
            *out = i;
            return 0;
        }
        size_t n = strlen(list);
        snprintf(list + n, sizeof list - n, "%s%s", i ? ", " : "", names[i]);
    }
    return cfg_why(why, whylen, "expected one of %s, got '%s'", list, kv->value);
}

int cfg_get_path(const cfg_kv_t *kv, char *out, size_t outlen, char *why, size_t whylen)
{
    int n;
    if (!kv->value[0])
        return cfg_why(why, whylen, "empty path");
    const char *v = kv->value;
    if (v[0] == '/' || !kv->dir || !kv->dir[0]) {
        n = snprintf(out, outlen, "%s", v);
    } else {
        while (v[0] == '.' && v[1] == '/' && v[2]) /* ./a.csv beside the file: not ././a.csv */
            for (v += 2; v[0] == '/';)
                v++;
        n = snprintf(out, outlen, "%s/%s", kv->dir, v);
    }
    if (n < 0 || (size_t)n >= outlen)
        return cfg_why(why, whylen, "path too long");
    return 0;
}
