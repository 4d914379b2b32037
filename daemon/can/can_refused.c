/* can_refused.c - see can_refused.h. */
#include "can_refused.h"

#include <stdio.h>

#include "can_transport.h"
#include "canproto.h"
#include "engine.h"

void can_refused_why(char *buf, size_t len, int err, unsigned cmd, int stopping, const char *name)
{
    if (err == 0)
        snprintf(buf, len,
                 "the object is not writable (writable = yes in [object.%s] lets CAN command it)",
                 name);
    else if (err == -ENGINE_ERANGE && cmd == CANPROTO_CMD_OVERRIDE)
        snprintf(buf, len, "an override above %d %%", CANPROTO_OVERRIDE_MAX_PCT);
    else if (err == -ENGINE_ESTATE && stopping)
        snprintf(buf, len, "the daemon is stopping (SIGTERM)");
    else if (err == -ENGINE_ESTATE)
        snprintf(buf, len,
                 "the object is held (a feed hold: a drive's lost heartbeat or a fault); "
                 "only the command clear releases it");
    else
        snprintf(buf, len, "%s", engine_strerror(-err));
}

unsigned can_transport_fds(const cfg_t *cfg, unsigned *clients)
{
    const can_cfg_t *c = cfg_transport(cfg, &can_transport);
    (void)clients;
    if (!cfg_uses(cfg, &can_transport))
        return 0;
    /* the raw socket (or log_in instead of it), log_out, and a spare for the
     * socket a reopen makes before the old one closes */
    return 2u + (c->log_in[0] != 0) + (c->log_out[0] != 0);
}

void can_transport_files(const cfg_t *cfg, cfg_file_add_fn add, void *ctx)
{
    const can_cfg_t *c = cfg_transport(cfg, &can_transport);
    int line = cfg->tline[transport_index(&can_transport)];
    add(ctx, c->log_in, 0, line, "[can] log_in");
    add(ctx, c->log_out, 1, line, "[can] log_out");
}
