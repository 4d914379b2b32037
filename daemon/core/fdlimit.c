/* fdlimit.c - the file descriptors a configuration needs (see fdlimit.h). */
#include "fdlimit.h"

#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>

#include "transport.h"

static unsigned long long lim_of(rlim_t r)
{
    return r == RLIM_INFINITY ? ULLONG_MAX : (unsigned long long)r;
}

void fdlimit_of(const cfg_t *c, fdlimit_t *f)
{
    struct rlimit rl;
    memset(f, 0, sizeof *f);
    f->need = FDLIMIT_CORE;
    for (unsigned i = 0; transport_table[i]; i++)
        if (transport_table[i]->fds)
            f->need += transport_table[i]->fds(c, &f->clients);
    f->soft = f->hard = ULLONG_MAX;
    if (getrlimit(RLIMIT_NOFILE, &rl) == 0) {
        f->soft = lim_of(rl.rlim_cur);
        f->hard = lim_of(rl.rlim_max);
    }
}

static void say(const fdlimit_t *f, unsigned long long lim, const char *which, const char *extra,
                char *why, size_t whylen)
{
    snprintf(why, whylen,
             "the configuration holds about %u file descriptors open (%u more for clients at "
             "most), beyond the %s limit of %llu%s: raise it (ulimit -n, systemd's "
             "LimitNOFILE=)",
             f->need, f->clients, which, lim, extra);
}

int fdlimit_fit(fdlimit_t *f, char *why, size_t whylen)
{
    unsigned long long want = (unsigned long long)f->need + f->clients;
    char extra[96] = "";
    why[0] = 0;
    if (want > f->soft) {
        struct rlimit rl;
        unsigned long long to = want < f->hard ? want : f->hard;
        if (getrlimit(RLIMIT_NOFILE, &rl) == 0) {
            rl.rlim_cur = (rlim_t)to;
            if (setrlimit(RLIMIT_NOFILE, &rl) == 0)
                f->soft = to;
            else
                snprintf(extra, sizeof extra, " (raising it to %llu: %s)", to, strerror(errno));
        }
    }
    if (f->need > f->soft) {
        say(f, f->soft, f->soft < f->hard ? "soft" : "hard", extra, why, whylen);
        return -1;
    }
    if (want > f->soft) {
        snprintf(why, whylen,
                 "%llu file descriptors allowed: room for %llu of the %u clients the "
                 "configuration admits (the rest are refused as they come%s)",
                 f->soft, f->soft - f->need, f->clients, extra);
        return 1;
    }
    return 0;
}

int fdlimit_check(const fdlimit_t *f, char *why, size_t whylen)
{
    why[0] = 0;
    if (f->need <= f->hard)
        return 0;
    say(f, f->hard, "hard", "", why, whylen);
    return -1;
}
