/*
 * cfg_string.h - a configuration text in memory checked as trajd checks its
 * file (daemon/core/cfg.h cfg_load): the text is written to name (a file, or
 * one folder and a file) in a temporary directory of the program's own, then
 * loaded, so messages read "<cfg_string_dir>/name:line: ...".  That directory
 * stands in for the tree's root, where the tests run: relative paths resolve
 * in it, and its tests/ leads to the tree's tests/ (a symbolic link), as
 * tests/data/... did from the tree (unless cfg_string_tree is set to 0
 * before the first load: the fuzz target).  Made at the first load, removed at exit;
 * the file at once after its load.  For the config tests and the config fuzz
 * target; a failure to make the directory or write the file aborts.
 */
#ifndef TRAJD_CFG_STRING_H
#define TRAJD_CFG_STRING_H

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cfg.h"

static char cfg_string_dir[64];
static int cfg_string_tree = 1; /* 0: no tests/ link */

static inline void cfg_string_cleanup(void)
{
    char path[sizeof cfg_string_dir + 8];
    snprintf(path, sizeof path, "%s/tests", cfg_string_dir);
    unlink(path);
    rmdir(cfg_string_dir);
}

/* The path name is loaded from (path: at least sizeof cfg_string_dir + 256). */
static inline void cfg_string_path(const char *name, char *path, size_t len)
{
    if (!cfg_string_dir[0]) {
        char cwd[PATH_MAX], link[sizeof cfg_string_dir + 8];
        snprintf(cfg_string_dir, sizeof cfg_string_dir, "/tmp/trajd_cfg_string.XXXXXX");
        if (!mkdtemp(cfg_string_dir) || !getcwd(cwd, sizeof cwd - 8))
            abort();
        atexit(cfg_string_cleanup);
        snprintf(link, sizeof link, "%s/tests", cfg_string_dir);
        strcat(cwd, "/tests");
        if (cfg_string_tree && symlink(cwd, link) < 0)
            abort();
    }
    snprintf(path, len, "%s/%s", cfg_string_dir, name);
}

static inline int cfg_load_string(const char *text, const char *name, cfg_t **out, char *err,
                                  size_t errlen)
{
    char path[sizeof cfg_string_dir + 256];
    cfg_string_path(name, path, sizeof path);
    char *slash = strrchr(path, '/');
    int sub = slash - path > (long)strlen(cfg_string_dir); /* name has a folder */
    if (sub) {
        *slash = 0;
        if (mkdir(path, 0700) < 0)
            abort();
        *slash = '/';
    }
    FILE *f = fopen(path, "w");
    if (!f || fputs(text, f) < 0 || fclose(f) != 0)
        abort();
    int rc = cfg_load(path, out, err, errlen);
    unlink(path);
    if (sub) {
        *slash = 0;
        rmdir(path);
    }
    return rc;
}

#endif
