/* fake_can_io.c - one fake CAN transport for the C tests (see fake_can_io.h). */
#include "fake_can_io.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>

static int fake_send(void *io, const canproto_frame_t *f)
{
    fake_can_io_t *x = io;
    if (!x->up)
        return -ENETDOWN;
    if (x->fail_with)
        return x->fail_with;
    if (x->room_limited) {
        if (!x->room)
            return -ENOBUFS;
        x->room--;
    }
    if (x->nout >= FAKE_CAN_MAX)
        abort(); /* a test sent more than it can look at */
    x->out[x->nout++] = *f;
    return 0;
}

static int fake_recv(void *io, int64_t now_ns, canproto_frame_t *f)
{
    (void)now_ns;
    fake_can_io_t *x = io;
    if (x->next >= x->nin)
        return 0;
    *f = x->in[x->next++];
    return 1;
}

static int fake_maintain(void *io, int64_t now_ns)
{
    (void)now_ns;
    fake_can_io_t *x = io;
    if (!x->up && x->reopen_ok) {
        x->up = 1;
        return 1;
    }
    return 0;
}

static int fake_is_up(const void *io)
{
    return ((const fake_can_io_t *)io)->up;
}

const can_port_io_t fake_can_ops = {fake_send, fake_recv, fake_maintain, fake_is_up};

void fake_can_reset(fake_can_io_t *x)
{
    memset(x, 0, sizeof *x);
    x->up = 1;
}
