/* trajreplay_help.h - trajreplay's --help text (daemon/trajreplay.c). */
#ifndef TRAJD_TRAJREPLAY_HELP_H
#define TRAJD_TRAJREPLAY_HELP_H

#include <stdio.h>

/* The usage text, the track formats, every engine setting and the exit statuses. */
void trajreplay_usage(FILE *f);

#endif
