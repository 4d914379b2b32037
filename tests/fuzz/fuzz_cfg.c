/* fuzz_cfg.c - libFuzzer target for the config parser, through cfg_load as
 * trajd loads its file (tests/helpers/cfg_string.h: the text written to
 * f.conf in a temporary directory): any text must give either a config or
 * an error message that starts with the file name and, for a line error, a
 * line number within the text; never a crash, a leak or an out-of-bounds
 * access (ASan/UBSan).  Relative paths resolve in that directory, which
 * holds only f.conf itself (no tests/ link: cfg_string_tree = 0), so the
 * target reads no other file by them (absolute paths still can: a limit). */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cfg_string.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1);
    if (!text)
        return 0;
    memcpy(text, data, size);
    text[size] = 0; /* inih reads up to the first NUL */
    size_t lines = 1;
    for (size_t i = 0; text[i]; i++)
        lines += text[i] == '\n';
    cfg_t *c = NULL;
    char err[1024] = "";
    char path[sizeof cfg_string_dir + 256];
    cfg_string_tree = 0;
    cfg_string_path("f.conf", path, sizeof path);
    size_t pl = strlen(path);
    int rc = cfg_load_string(text, "f.conf", &c, err, sizeof err);
    if (rc == 0) {
        if (!c || c->nobj == 0 || c->nobj > CFG_OBJECTS_MAX)
            abort();
        cfg_free(c);
    } else {
        if (c || strncmp(err, path, pl) != 0)
            abort();
        long line = 0;
        if (err[pl] == ':' && sscanf(err + pl + 1, "%ld", &line) == 1 &&
            (line < 1 || (size_t)line > lines))
            abort();
    }
    free(text);
    return 0;
}
