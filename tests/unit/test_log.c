/*
 * test_log.c - where log lines go (daemon/core/log.h), with stderr on a real
 * pseudo-terminal and on a real pipe:
 *   a terminal, no JOURNAL_STREAM          -> plain text, "warning: " word, no "<N>";
 *   JOURNAL_STREAM naming stderr's dev:ino -> "<N>" prefix (journald), even on a tty;
 *   JOURNAL_STREAM naming another stream   -> not journald: plain on a terminal;
 *   a pipe                                 -> "<N>" prefix;
 *   syslog mode (detached)                 -> nothing on stderr.
 */
#include "test.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "log.h"

static int saved_stderr = -1;

/* Log one warning with fd as stderr; return what came out (up to len-1 bytes). */
static void log_into(int wfd, int rfd, char *out, size_t len)
{
    fflush(stderr);
    saved_stderr = dup(STDERR_FILENO);
    assert_true(saved_stderr >= 0);
    assert_true(dup2(wfd, STDERR_FILENO) >= 0);
    log_set_mode(LOG_MODE_AUTO);
    log_msg(LOG_WARNING, "speed %d m/s", 7);
    log_msg(LOG_DEBUG, "not shown at the default level");
    dup2(saved_stderr, STDERR_FILENO);
    close(saved_stderr);
    int fl = fcntl(rfd, F_GETFL);
    fcntl(rfd, F_SETFL, fl | O_NONBLOCK);
    ssize_t n = read(rfd, out, len - 1);
    out[n > 0 ? n : 0] = '\0';
}

static void open_pty(int *master, int *slave)
{
    *master = posix_openpt(O_RDWR | O_NOCTTY);
    if (*master < 0)
        skip();
    assert_int_equal(grantpt(*master), 0);
    assert_int_equal(unlockpt(*master), 0);
    *slave = open(ptsname(*master), O_RDWR | O_NOCTTY);
    assert_true(*slave >= 0);
}

static void set_journal_stream(int fd)
{
    struct stat st;
    char v[64];
    assert_int_equal(fstat(fd, &st), 0);
    snprintf(v, sizeof v, "%llu:%llu", (unsigned long long)st.st_dev,
             (unsigned long long)st.st_ino);
    setenv("JOURNAL_STREAM", v, 1);
}

static void test_tty_is_plain(void **state)
{
    (void)state;
    int m, s;
    char out[256];
    open_pty(&m, &s);
    unsetenv("JOURNAL_STREAM");
    log_into(s, m, out, sizeof out);
    assert_string_equal(out, "warning: speed 7 m/s\r\n"); /* the tty adds \r (ONLCR) */
    close(s);
    close(m);
}

static void test_journal_stream_has_priority(void **state)
{
    (void)state;
    int m, s, p[2];
    char out[256];
    open_pty(&m, &s);
    set_journal_stream(s);
    log_into(s, m, out, sizeof out);
    assert_string_equal(out, "<4>speed 7 m/s\r\n");
    /* JOURNAL_STREAM inherited but naming another stream: still a terminal */
    assert_int_equal(pipe(p), 0);
    set_journal_stream(p[0]);
    log_into(s, m, out, sizeof out);
    assert_string_equal(out, "warning: speed 7 m/s\r\n");
    unsetenv("JOURNAL_STREAM");
    close(p[0]);
    close(p[1]);
    close(s);
    close(m);
}

static void test_pipe_has_priority(void **state)
{
    (void)state;
    int p[2];
    char out[256];
    assert_int_equal(pipe(p), 0);
    unsetenv("JOURNAL_STREAM");
    log_into(p[1], p[0], out, sizeof out);
    assert_string_equal(out, "<4>speed 7 m/s\n");
    close(p[0]);
    close(p[1]);
}

static void test_syslog_mode_leaves_stderr(void **state)
{
    (void)state;
    int p[2];
    char out[256];
    assert_int_equal(pipe(p), 0);
    fflush(stderr);
    saved_stderr = dup(STDERR_FILENO);
    dup2(p[1], STDERR_FILENO);
    log_set_mode(LOG_MODE_SYSLOG);
    log_msg(LOG_WARNING, "to syslog");
    log_set_mode(LOG_MODE_AUTO);
    dup2(saved_stderr, STDERR_FILENO);
    close(saved_stderr);
    fcntl(p[0], F_SETFL, O_NONBLOCK);
    ssize_t n = read(p[0], out, sizeof out);
    assert_true(n <= 0);
    close(p[0]);
    close(p[1]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_tty_is_plain),
        cmocka_unit_test(test_journal_stream_has_priority),
        cmocka_unit_test(test_pipe_has_priority),
        cmocka_unit_test(test_syslog_mode_leaves_stderr),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
