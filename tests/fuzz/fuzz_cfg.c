/* fuzz_cfg.c - libFuzzer target for the config parser (cfg_load_stream):
 * any text must give either a config or an error message that starts with
 * the file name and, for a line error, a line number within the text;
 * never a crash, a leak or an out-of-bounds access (ASan/UBSan).
 * Relative paths resolve under a directory that does not exist, so the
 * target does not read files (absolute paths still can: a limit). */
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
    int rc = cfg_load_string(text, "f.conf", "/nonexistent-fuzz-dir", &c, err, sizeof err);
    if (rc == 0) {
        if (!c || c->nobj == 0 || c->nobj > CFG_OBJECTS_MAX)
            abort();
        cfg_free(c);
    } else {
        if (c || strncmp(err, "f.conf", 6) != 0)
            abort();
        long line = 0;
        if (err[6] == ':' && sscanf(err + 7, "%ld", &line) == 1 &&
            (line < 1 || (size_t)line > lines))
            abort();
    }
    free(text);
    return 0;
}
