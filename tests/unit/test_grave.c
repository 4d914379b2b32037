/* test_grave.c - engines given up in the loop are freed beside it (grave.h,
 * issue 28): every engine handed over is freed once, by the time grave_stop
 * returns, whether the ring took it or (full) the loop freed it at once; the
 * process's mappings and heap (glibc's mallinfo2, the reference) come back
 * to where they stood.  Under AddressSanitizer (make check's second pass) a
 * double free or a leak fails here too. */
#include "test.h"

#include <malloc.h>

#include "engine.h"
#include "grave.h"

/* More than the ring holds (GRAVE_CAP 2048) when put faster than freed. */
#define N_ENGINES 2500

static engine_t *small_engine(void)
{
    engine_config_t c;
    engine_config_default(&c);
    c.capacity = 64; /* a few kB a mapping: 2 500 of them stay small */
    engine_t *e = engine_new(&c, NULL);
    assert_non_null(e);
    return e;
}

static void test_all_freed(void **state)
{
    (void)state;
    for (int round = 0; round < 2; round++) { /* the thread's and the allocator's first */
        grave_put(small_engine());
        grave_stop();
    }
    struct mallinfo2 a = mallinfo2();
    for (int round = 0; round < 2; round++) { /* the thread starts again after a stop */
        for (int i = 0; i < N_ENGINES; i++)
            grave_put(small_engine());
        grave_put(NULL); /* a no-op */
        grave_stop();
    }
    struct mallinfo2 b = mallinfo2();
    print_message("in use before %zu, after %zu bytes; mapped before %zu, after %zu\n", a.uordblks,
                  b.uordblks, a.hblkhd, b.hblkhd);
    assert_true(b.hblkhd <= a.hblkhd);
    /* one engine not freed is more than this (each holds tens of kB), all
     * of them not freed tens of MB; the threads' own bookkeeping less */
    assert_true(b.uordblks <= a.uordblks + 16384);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_all_freed),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
