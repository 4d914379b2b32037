/* test_can_logfile.c - the candump log reader of the can_logfile transport:
 * whole lines of any length, every refused line counted and reported with
 * file:line (issue 11: a 511-byte cut once turned the tail of a comment
 * into a CLEAR command). */
#include "test.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "candump.h"
#include "can_logfile.h"

/* Replay len bytes of text as trajd does a log_in file: written to mem.log
 * in a temporary directory and opened with can_logfile_open_mode, with
 * stderr captured into log (NUL-terminated). */
static can_logfile_t *load_bytes(const char *text, size_t len, char *log, size_t loglen)
{
    char dir[] = "/tmp/test_can_logfile.XXXXXX", path[64], err[256];
    assert_non_null(mkdtemp(dir));
    snprintf(path, sizeof path, "%s/mem.log", dir);
    FILE *in = fopen(path, "w");
    assert_non_null(in);
    assert_int_equal(fwrite(text, 1, len, in), len);
    assert_int_equal(fclose(in), 0);
    FILE *cap = tmpfile();
    assert_non_null(cap);
    fflush(stderr);
    int saved = dup(2);
    assert_true(saved >= 0);
    assert_true(dup2(fileno(cap), 2) >= 0);
    can_logfile_t *l = can_logfile_open_mode(path, NULL, "can0", 0, 0, err, sizeof err);
    assert_true(dup2(saved, 2) >= 0);
    close(saved);
    unlink(path);
    rmdir(dir);
    if (!l)
        fail_msg("%s", err);
    rewind(cap);
    size_t n = fread(log, 1, loglen - 1, cap);
    log[n] = '\0';
    fclose(cap);
    return l;
}

static can_logfile_t *load_text(const char *text, char *log, size_t loglen)
{
    return load_bytes(text, strlen(text), log, loglen);
}

static unsigned count_lines_with(const char *log, const char *needle)
{
    unsigned n = 0;
    for (const char *p = log; (p = strstr(p, needle)); p += strlen(needle))
        n++;
    return n;
}

/* Given a comment line of 600 bytes whose bytes from 511 on spell a CLEAR
 * command frame for object 0 (id 0x680), when the log is loaded, then the
 * whole line is one comment and the only frames delivered are the two real
 * ones (the old fgets(512) reader delivered a third: the CLEAR). */
static void test_long_comment_is_not_a_frame(void **state)
{
    (void)state;
    canproto_frame_t clear;
    char frame[64], comment[700], text[2048], log[4096];
    assert_int_equal(canproto_encode_command(0x680, CANPROTO_CMD_CLEAR, &clear), 0);
    assert_true(candump_format_frame(frame, sizeof frame, &clear) > 0);
    memset(comment, 'x', sizeof comment);
    comment[0] = '#';
    int k = snprintf(comment + 511, sizeof comment - 511, "(1.500000) can0 %s ", frame);
    comment[511 + k] = 'x'; /* overwrite the NUL: the line goes on */
    comment[600] = '\0';
    snprintf(text, sizeof text, "(1.000000) can0 123#01\n%s\n(2.000000) can0 124#02\n", comment);
    can_logfile_t *l = load_text(text, log, sizeof log);
    can_logfile_stats_t st;
    can_logfile_stats(l, &st);
    assert_int_equal(st.lines, 3);
    assert_int_equal(st.comments, 1);
    assert_int_equal(st.bad_lines, 0);
    assert_int_equal(st.frames_in, 2);
    canproto_frame_t f;
    assert_int_equal(can_logfile_recv(l, INT64_MAX / 2, &f), 1);
    assert_int_equal(f.id, 0x123);
    assert_int_equal(can_logfile_recv(l, INT64_MAX / 2, &f), 1);
    assert_int_equal(f.id, 0x124);
    assert_int_equal(can_logfile_recv(l, INT64_MAX / 2, &f), 0);
    can_logfile_close(l);
}

/* Given a frame line padded past CAN_LOGFILE_LINE_MAX with a frame at its
 * end, then it is refused whole: one bad line, reported as mem.log:2. */
static void test_long_frame_line_refused_whole(void **state)
{
    (void)state;
    char text[4096], log[4096];
    int k = snprintf(text, sizeof text, "(1.0) can0 123#01\n(1.1) can0 ");
    memset(text + k, ' ', CAN_LOGFILE_LINE_MAX);
    snprintf(text + k + CAN_LOGFILE_LINE_MAX, sizeof text - (size_t)k - CAN_LOGFILE_LINE_MAX,
             "680#03\n");
    can_logfile_t *l = load_text(text, log, sizeof log);
    can_logfile_stats_t st;
    can_logfile_stats(l, &st);
    assert_int_equal(st.lines, 2);
    assert_int_equal(st.bad_lines, 1);
    assert_int_equal(st.first_bad_line, 2);
    assert_int_equal(st.frames_in, 1);
    assert_non_null(strstr(log, "mem.log:2: longer than"));
    can_logfile_close(l);
}

/* Given a line of 100 000 bytes and a last line with no newline, then the
 * long line counts once (not once per buffer) and the last line is read. */
static void test_any_length_counts_once(void **state)
{
    (void)state;
    size_t big = 100000;
    char *text = malloc(big + 64), log[4096];
    assert_non_null(text);
    memset(text, '7', big); /* not a comment: a long bad line */
    strcpy(text + big, "\n(3.000000) can0 125#03");
    can_logfile_t *l = load_text(text, log, sizeof log);
    can_logfile_stats_t st;
    can_logfile_stats(l, &st);
    assert_int_equal(st.lines, 2);
    assert_int_equal(st.bad_lines, 1);
    assert_int_equal(st.first_bad_line, 1);
    assert_int_equal(st.frames_in, 1);
    can_logfile_close(l);
    free(text);
}

/* Given 8 malformed lines among good ones, then all 8 are counted, the
 * first CAN_LOGFILE_REPORT_MAX are each reported with their line number and
 * one summary line gives the total and the first line. */
static void test_bad_lines_reported_rate_limited(void **state)
{
    (void)state;
    char text[1024], log[4096];
    size_t k = 0;
    k += (size_t)snprintf(text + k, sizeof text - k, "# capture\n(0.1) can0 100#00\n");
    for (int i = 0; i < 8; i++)
        k += (size_t)snprintf(text + k, sizeof text - k, "(0.%d) can0 not-a-frame\n", i + 2);
    k += (size_t)snprintf(text + k, sizeof text - k, "(0.1) can0 101#00\n");
    k += (size_t)snprintf(text + k, sizeof text - k, "(0.1) can0 102#0011223344556677889900\n");
    can_logfile_t *l = load_text(text, log, sizeof log);
    can_logfile_stats_t st;
    can_logfile_stats(l, &st);
    assert_int_equal(st.comments, 1);
    assert_int_equal(st.bad_lines, 9); /* 8 syntax + 1 with 11 data bytes */
    assert_int_equal(st.first_bad_line, 3);
    assert_int_equal(st.frames_in, 2);
    assert_int_equal(count_lines_with(log, "line not replayed"), CAN_LOGFILE_REPORT_MAX);
    for (int i = 0; i < CAN_LOGFILE_REPORT_MAX; i++) {
        char want[32];
        snprintf(want, sizeof want, "mem.log:%d: ", 3 + i);
        assert_non_null(strstr(log, want));
    }
    assert_non_null(strstr(log, "mem.log: 9 lines not replayed in all (first at line 3"));
    can_logfile_close(l);
}

/* Given a NUL byte inside a line, then that line is refused (a C-string
 * parser would see only its head). */
static void test_nul_byte_refused(void **state)
{
    (void)state;
    static const char text[] = "(0.1) can0 100#00\n(0.2) can0 101#00\0garbage\n";
    char log[1024];
    can_logfile_t *l = load_bytes(text, sizeof text - 1, log, sizeof log);
    can_logfile_stats_t st;
    can_logfile_stats(l, &st);
    assert_int_equal(st.bad_lines, 1);
    assert_int_equal(st.first_bad_line, 2);
    assert_int_equal(st.frames_in, 1);
    assert_non_null(strstr(log, "mem.log:2: NUL byte"));
    can_logfile_close(l);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_long_comment_is_not_a_frame),
        cmocka_unit_test(test_long_frame_line_refused_whole),
        cmocka_unit_test(test_any_length_counts_once),
        cmocka_unit_test(test_bad_lines_reported_rate_limited),
        cmocka_unit_test(test_nul_byte_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
