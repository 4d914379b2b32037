/* can_drive_cfg.c - CiA 402 keys of the "can" transport (see can_drive_cfg.h). */
#include "can_drive_cfg.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int can_cfg_heartbeat(const cfg_kv_t *kv, int *node, int *ms, char *why, size_t wl)
{
    long long v;
    int rc;
    if (!strcmp(kv->key, "heartbeat_node")) {
        rc = cfg_get_int(kv, 0, 127, &v, why, wl);
        *node = (int)v;
        return rc;
    }
    rc = cfg_get_int(kv, 10, 60000, &v, why, wl);
    *ms = (int)v;
    return rc;
}

/* "0x6060:0=8/1, 0x60C2:1=10/1, 0x60C2:2=-3/1": index:sub=value/size bytes. */
int can_cfg_sdo_list(const cfg_kv_t *kv, canproto_ids_t *ids, char *why, size_t wl)
{
    const char *q = kv->value;
    unsigned n = 0;
    while (*q) {
        char *end;
        while (*q == ' ' || *q == ',')
            q++;
        if (!*q)
            break;
        if (n == CANPROTO_CIA402_SDO_MAX) {
            snprintf(why, wl, "at most %d SDO writes", CANPROTO_CIA402_SDO_MAX);
            return -CFG_EVALUE;
        }
        unsigned long idx = strtoul(q, &end, 0);
        if (end == q || *end != ':' || idx > 0xFFFF)
            goto bad;
        q = end + 1;
        unsigned long sub = strtoul(q, &end, 0);
        if (end == q || *end != '=' || sub > 0xFF)
            goto bad;
        q = end + 1;
        long long val = strtoll(q, &end, 0);
        if (end == q || *end != '/')
            goto bad;
        q = end + 1;
        unsigned long size = strtoul(q, &end, 0);
        if (end == q || (size != 1 && size != 2 && size != 4))
            goto bad;
        long long lo = size == 4 ? INT32_MIN : -(1LL << (8 * size - 1));
        long long hi = size == 4 ? UINT32_MAX : (1LL << (8 * size)) - 1;
        if (val < lo || val > hi)
            goto bad;
        q = end;
        ids->cia402_sdo[n].index = (uint16_t)idx;
        ids->cia402_sdo[n].sub = (uint8_t)sub;
        ids->cia402_sdo[n].size = (uint8_t)size;
        ids->cia402_sdo[n].value = (uint32_t)val; /* two's complement for negative values */
        n++;
    }
    ids->cia402_nsdo = n;
    return 0;
bad:
    snprintf(why, wl,
             "expected index:sub=value/size (size 1, 2 or 4 bytes), comma separated, "
             "got '%s'",
             kv->value);
    return -CFG_EVALUE;
}
