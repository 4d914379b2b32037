/* test_cfg_lines.c - config lines as inih reads them (issue 11): libinih
 * (Debian 55) reads each line into a stack buffer of INI_MAX_LINE = 200
 * bytes (INI_USE_STACK 1, INI_ALLOW_REALLOC 0) and would split a longer
 * line, parsing its tail as a line of its own; it also goes on after an
 * error (INI_STOP_ON_FIRST_ERROR 0).  daemon/core/cfg.c's reader therefore
 * refuses a line longer than INI_MAX_LINE - 2 = 198 characters, and a line
 * holding a NUL byte, with file:line, and stops there. */
#include "test.h"

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cfg.h"

static char err[1024], path[PATH_MAX];

/* Write len bytes of text to a temp file and load it; returns cfg_load's code. */
static int load_bytes(const char *text, size_t len)
{
    snprintf(path, sizeof path, "/tmp/trajd-cfg-lines-%ld.conf", (long)getpid());
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(text, 1, len, f), len);
    fclose(f);
    cfg_t *c = NULL;
    err[0] = 0;
    int rc = cfg_load(path, &c, err, sizeof err);
    cfg_free(c);
    unlink(path);
    return rc;
}

/* The minimal object, with the track given by its absolute path (the
 * config is in /tmp) and one more line of n characters after "log_level =". */
static size_t conf_with(char *buf, size_t cap, size_t n, int newline_at_end)
{
    char cwd[PATH_MAX];
    assert_non_null(getcwd(cwd, sizeof cwd));
    int k = snprintf(buf, cap,
                     "[object.a]\ninput = replay\nreplay.track = %s/tests/data/demo.path\n"
                     "output = stdout\n[daemon]\nlog_level = info",
                     cwd);
    assert_true(k > 0 && (size_t)k + n < cap);
    size_t len = (size_t)k, pad = n - strlen("log_level = info");
    memset(buf + len, ' ', pad); /* inih strips trailing blanks */
    len += pad;
    if (newline_at_end)
        buf[len++] = '\n';
    buf[len] = 0;
    return len;
}

/* conf_with into buf, then load_bytes: cfg_load's code. */
static int load_conf_with(size_t n, int newline_at_end)
{
    static char buf[1024];
    size_t len = conf_with(buf, sizeof buf, n, newline_at_end);
    return load_bytes(buf, len);
}

/* Given a line of 198 characters, then accepted; 199, then refused at its
 * line (6), whether or not the file ends there. */
static void test_longest_line(void **state)
{
    (void)state;
    assert_int_equal(load_conf_with(198, 1), 0);
    assert_int_equal(load_conf_with(198, 0), 0);
    assert_int_equal(load_conf_with(199, 1), -CFG_ESYNTAX);
    assert_non_null(strstr(err, ".conf:6: line longer than 198 characters"));
    assert_int_equal(load_conf_with(250, 0), -CFG_ESYNTAX);
    assert_non_null(strstr(err, ".conf:6: line longer than 198 characters"));
}

/* Given a long comment whose tail after 198 characters reads as a key, then
 * the line is refused, not split into a key. */
static void test_long_comment_not_split(void **state)
{
    (void)state;
    char buf[1024];
    size_t len = conf_with(buf, sizeof buf, 20, 1);
    char line[300];
    memset(line, '#', sizeof line);
    snprintf(line + 198, sizeof line - 198, "log_level = debug\n");
    memcpy(buf + len, line, strlen(line) + 1);
    assert_int_equal(load_bytes(buf, strlen(buf)), -CFG_ESYNTAX);
    assert_non_null(strstr(err, ".conf:7: line longer than 198 characters"));
}

/* Given a NUL byte inside line 6, then that line is refused as such (fgets
 * hid everything after the NUL and called it a line too long). */
static void test_nul_byte(void **state)
{
    (void)state;
    char buf[1024];
    size_t len = conf_with(buf, sizeof buf, 20, 1);
    char *p = strstr(buf, "log_level = info");
    p[strlen("log_level = info")] = '\0';
    assert_int_equal(load_bytes(buf, len), -CFG_ESYNTAX);
    if (!strstr(err, ".conf:6: NUL byte"))
        fail_msg("got '%s'", err);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_longest_line),
        cmocka_unit_test(test_long_comment_not_split),
        cmocka_unit_test(test_nul_byte),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
