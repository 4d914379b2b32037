/* test_loop.c - the epoll loop with real kernel objects (pipes, eventfds,
 * timerfds): dispatch, deleting fds from inside callbacks (including one
 * whose event is pending in the same batch, and reusing its number), timers
 * and stop.  The kernel is the reference: readiness comes from real fds. */
#include "test.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include "loop.h"

typedef struct {
    int calls;
    int victim_fd; /* fd this callback deletes (and closes) */
    int *reuse_fd; /* then registers a new eventfd that reuses the slot */
    void *reuse_ctx;
    int stop_after;
} ctx_t;

static void on_ready(loop_t *l, int fd, uint32_t ev, void *p)
{
    ctx_t *c = p;
    uint64_t v;
    (void)ev;
    c->calls++;
    if (read(fd, &v, sizeof v) < 0) { /* drain the eventfd */
    }
    if (c->victim_fd >= 0) {
        assert_int_equal(loop_del(l, c->victim_fd), 0);
        close(c->victim_fd);
        c->victim_fd = -1;
        if (c->reuse_fd) {
            /* a new readable fd, registered at once: it takes the freed slot
             * (and very likely the fd number) of the deleted one */
            *c->reuse_fd = eventfd(1, EFD_NONBLOCK);
            assert_true(*c->reuse_fd >= 0);
            assert_int_equal(loop_add(l, *c->reuse_fd, EPOLLIN, on_ready, c->reuse_ctx), 0);
        }
    }
    if (c->stop_after && c->calls >= c->stop_after)
        loop_stop(l, 42);
}

static int ready_eventfd(void)
{
    int fd = eventfd(1, EFD_NONBLOCK); /* counter 1: readable */
    assert_true(fd >= 0);
    return fd;
}

/* Given two readable fds in one batch, when the first callback deletes the
 * second and registers a new readable fd in its slot, then neither the
 * deleted fd's callback nor the new one runs on the stale event of that
 * batch: the entry's generation changed. */
static void test_delete_pending_in_batch(void **state)
{
    (void)state;
    loop_t *l = loop_new(NULL);
    assert_non_null(l);
    int a = ready_eventfd(), b = ready_eventfd(), reused = -1;
    ctx_t cr = {.victim_fd = -1};
    ctx_t ca = {.victim_fd = b, .reuse_fd = &reused, .reuse_ctx = &cr},
          cb = {.victim_fd = -1, .reuse_fd = &reused, .reuse_ctx = &cr};
    assert_int_equal(loop_add(l, a, EPOLLIN, on_ready, &ca), 0);
    assert_int_equal(loop_add(l, b, EPOLLIN, on_ready, &cb), 0);
    /* whichever epoll reports first deletes the other: make it symmetric */
    cb.victim_fd = a;
    ca.stop_after = 1;
    cb.stop_after = 1;
    int stopper_rc = loop_run(l);
    assert_int_equal(stopper_rc, 42);
    /* exactly one of the two ran; the other was deleted before its turn */
    assert_int_equal(ca.calls + cb.calls, 1);
    assert_int_equal(cr.calls, 0);
    /* registered still: the one that ran, and the new one */
    assert_int_equal(loop_mod(l, ca.calls ? a : b, EPOLLIN), 0);
    assert_int_equal(loop_mod(l, reused, EPOLLIN), 0);
    loop_del(l, reused);
    close(reused);
    close(ca.calls ? a : b);
    loop_free(l);
}

/* Given an fd, then add twice is -EEXIST, mod/del of unknown fds -ENOENT,
 * bad arguments -EINVAL, and a deleted fd is gone. */
static void test_errors(void **state)
{
    (void)state;
    int err = 1;
    loop_t *l = loop_new(&err);
    assert_int_equal(err, 0);
    int a = ready_eventfd();
    ctx_t c = {.victim_fd = -1};
    assert_int_equal(loop_add(l, a, EPOLLIN, on_ready, &c), 0);
    assert_int_equal(loop_add(l, a, EPOLLIN, on_ready, &c), -EEXIST);
    assert_int_equal(loop_add(l, -1, EPOLLIN, on_ready, &c), -EINVAL);
    assert_int_equal(loop_add(l, a + 100, EPOLLIN, NULL, &c), -EINVAL);
    assert_int_equal(loop_mod(l, a + 100, EPOLLIN), -ENOENT);
    assert_int_equal(loop_del(l, a + 100), -ENOENT);
    assert_int_equal(loop_add(l, a + 1000, EPOLLIN, on_ready, &c), -EBADF); /* not an fd */
    assert_int_equal(loop_mod(l, a, EPOLLIN | EPOLLOUT), 0);
    assert_int_equal(loop_del(l, a), 0);
    assert_int_equal(loop_del(l, a), -ENOENT); /* gone */
    assert_int_equal(loop_timer_add(l, 0, NULL, NULL), -EINVAL);
    assert_int_equal(loop_timer_del(l, a), -ENOENT);
    close(a);
    loop_free(l);
    loop_free(NULL);
}

typedef struct {
    uint64_t exp;
    int calls;
} tctx_t;

static void on_timer(loop_t *l, uint64_t exp, void *p)
{
    tctx_t *t = p;
    t->exp += exp;
    if (++t->calls == 3)
        loop_stop(l, 0);
}

/* Given a 2 ms periodic timer, when the loop runs, then it fires (at least
 * 3 expirations over 3 calls) and the loop stops from its callback; the
 * timer is closed by loop_timer_del. */
static void test_timer(void **state)
{
    (void)state;
    loop_t *l = loop_new(NULL);
    tctx_t t = {0};
    int fd = loop_timer_add(l, 2000000, on_timer, &t);
    assert_true(fd > 0);
    assert_int_equal(loop_run(l), 0);
    assert_int_equal(t.calls, 3);
    assert_true(t.exp >= 3);
    assert_int_equal(loop_timer_del(l, fd), 0);
    assert_int_equal(fcntl(fd, F_GETFD), -1); /* closed */
    loop_free(l);
}

/* A pipe: readable only after a write; EPOLLHUP after the writer closes. */
static void on_pipe(loop_t *l, int fd, uint32_t ev, void *p)
{
    uint32_t *seen = p;
    char buf[8];
    *seen |= ev;
    if (read(fd, buf, sizeof buf) == 0 || (ev & EPOLLHUP))
        loop_stop(l, 7);
}

static void test_pipe_events(void **state)
{
    (void)state;
    int p[2];
    assert_int_equal(pipe(p), 0);
    loop_t *l = loop_new(NULL);
    uint32_t seen = 0;
    assert_int_equal(loop_add(l, p[0], EPOLLIN, on_pipe, &seen), 0);
    assert_int_equal(write(p[1], "x", 1), 1);
    close(p[1]);
    assert_int_equal(loop_run(l), 7);
    assert_true(seen & EPOLLIN);
    loop_del(l, p[0]);
    close(p[0]);
    loop_free(l);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_delete_pending_in_batch),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_timer),
        cmocka_unit_test(test_pipe_events),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
