/* trajreplay_help.h - trajreplay's --help text (daemon/trajreplay.c). */
#ifndef TRAJD_TRAJREPLAY_HELP_H
#define TRAJD_TRAJREPLAY_HELP_H

#include <stdio.h>

#include "engine.h"

/* The usage text, the track formats, every engine setting and the exit statuses. */
void trajreplay_usage(FILE *f);

/* The engine settings refused with the reason on stderr (-1), or accepted
 * (0). */
int trajreplay_check_config(const engine_config_t *cfg);

#endif
