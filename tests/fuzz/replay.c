/*
 * replay.c - a plain main() for the libFuzzer targets, so that `make check`
 * replays their findings and corpora with any C compiler (no clang, no
 * libFuzzer).  Linked with one tests/fuzz/fuzz_<name>.c into
 * $(BUILD)/tests/test_fuzz_<name>; with no arguments it feeds every file of
 * tests/fuzz/regress/fuzz_<name>/ (findings, kept as regression inputs) and
 * tests/fuzz/corpus/fuzz_<name>/ to LLVMFuzzerTestOneInput, from the source
 * tree's root (tests/run.sh runs there).  Arguments name other files or folders.
 * A target reports a violated invariant by abort(), which fails the test.
 */
#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#ifndef FUZZ_NAME
#error "FUZZ_NAME (the target's name, e.g. fuzz_canproto) must be defined"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static unsigned long n_inputs;

static int run_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        return -1;
    }
    size_t cap = 4096, len = 0, n;
    uint8_t *buf = malloc(cap);
    while (buf && (n = fread(buf + len, 1, cap - len, f)) > 0) {
        len += n;
        if (len == cap) {
            uint8_t *nb = realloc(buf, cap *= 2);
            if (!nb)
                free(buf);
            buf = nb;
        }
    }
    int err = ferror(f);
    fclose(f);
    if (!buf || err) {
        fprintf(stderr, "%s: read failed\n", path);
        free(buf);
        return -1;
    }
    /* exactly len bytes, as libFuzzer passes them (ASan sees overreads) */
    uint8_t *in = malloc(len ? len : 1);
    if (!in) {
        free(buf);
        return -1;
    }
    memcpy(in, buf, len);
    free(buf);
    fprintf(stderr, "%s\n", path); /* the last line names the input if it aborts */
    (void)LLVMFuzzerTestOneInput(in, len);
    free(in);
    n_inputs++;
    return 0;
}

static int filter(const struct dirent *d)
{
    return d->d_name[0] != '.';
}

/* A file, or every file of a folder (in name order); a missing folder is empty. */
static int run_path(const char *path, int must_exist)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        if (!must_exist)
            return 0;
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        return -1;
    }
    if (!S_ISDIR(st.st_mode))
        return run_file(path);
    struct dirent **names;
    int n = scandir(path, &names, filter, alphasort), rc = 0;
    if (n < 0) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        return -1;
    }
    for (int i = 0; i < n; i++) {
        char p[4096];
        if (rc == 0 && (size_t)snprintf(p, sizeof p, "%s/%s", path, names[i]->d_name) < sizeof p)
            rc = run_path(p, 1);
        free(names[i]);
    }
    free(names);
    return rc;
}

int main(int argc, char **argv)
{
    int rc = 0;
    if (argc > 1) {
        for (int i = 1; i < argc && rc == 0; i++)
            rc = run_path(argv[i], 1);
    } else {
        rc = run_path("tests/fuzz/regress/" FUZZ_NAME, 0);
        if (rc == 0)
            rc = run_path("tests/fuzz/corpus/" FUZZ_NAME, 0);
    }
    printf("%s: %lu inputs replayed%s\n", FUZZ_NAME, n_inputs, rc ? ", with errors" : "");
    return rc ? 1 : 0;
}
