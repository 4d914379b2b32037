/* canproto_dbc_main.c - print config/trajd.dbc (canproto_dbc.h) on stdout. */
#include "canproto_dbc.h"

#include <stdio.h>
#include <stdlib.h>

int main(void)
{
    int n = canproto_dbc(NULL, 0);
    char *buf = n >= 0 ? malloc((size_t)n + 1) : NULL;
    if (!buf || canproto_dbc(buf, (size_t)n + 1) != n ||
        fwrite(buf, 1, (size_t)n, stdout) != (size_t)n || fflush(stdout)) {
        fprintf(stderr, "canproto_dbc: failed\n");
        free(buf);
        return 1;
    }
    free(buf);
    return 0;
}
