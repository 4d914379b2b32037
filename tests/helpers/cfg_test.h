/*
 * cfg_test.h - loading a config text in the config tests (test_cfg.c,
 * test_cfg_hostile.c): load_ok expects success, load_bad a given error on a
 * given line with a given text; err holds the last message.
 */
#ifndef TRAJD_CFG_TEST_H
#define TRAJD_CFG_TEST_H

#include <stdio.h>
#include <string.h>

#include "cfg_string.h"
#include "test.h"

static char err[1024];

static inline cfg_t *load_ok(const char *text)
{
    cfg_t *c = NULL;
    err[0] = 0;
    int rc = cfg_load_string(text, "t.conf", &c, err, sizeof err);
    if (rc != 0)
        fail_msg("expected success, got %d: %s", rc, err);
    return c;
}

/* Expect failure code, and err to start with "<cfg_string_dir>/t.conf:LINE:"
 * and contain needle. */
static inline void load_bad(const char *text, int code, int line, const char *needle)
{
    cfg_t *c = (cfg_t *)1;
    char path[sizeof cfg_string_dir + 256], prefix[sizeof path + 32];
    err[0] = 0;
    int rc = cfg_load_string(text, "t.conf", &c, err, sizeof err);
    assert_null(c);
    if (rc != -code)
        fail_msg("expected -%d, got %d: %s", code, rc, err);
    cfg_string_path("t.conf", path, sizeof path);
    if (line > 0)
        snprintf(prefix, sizeof prefix, "%s:%d: ", path, line);
    else
        snprintf(prefix, sizeof prefix, "%s: ", path);
    if (strncmp(err, prefix, strlen(prefix)) != 0)
        fail_msg("expected prefix '%s', got '%s'", prefix, err);
    if (needle && !strstr(err, needle))
        fail_msg("expected '%s' in '%s'", needle, err);
}

#endif
