/*
 * cfg_string.h - a configuration text in memory checked as trajd checks a
 * file (daemon/core/cfg.h cfg_load_stream over fmemopen): the config tests
 * and the config fuzz target.  name is used in messages, dir for relative
 * paths.
 */
#ifndef TRAJD_CFG_STRING_H
#define TRAJD_CFG_STRING_H

#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "cfg.h"

static inline int cfg_load_string(const char *text, const char *name, const char *dir, cfg_t **out,
                                  char *err, size_t errlen)
{
    FILE *fp = fmemopen((void *)text, strlen(text), "r");
    if (!fp) {
        *out = NULL;
        snprintf(err, errlen, "%s: %s", name, strerror(errno));
        return -CFG_EIO;
    }
    int rc = cfg_load_stream(fp, name, dir, out, err, errlen);
    fclose(fp);
    return rc;
}

#endif
