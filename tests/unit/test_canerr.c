/* test_canerr.c - SocketCAN error frames into a bus state and counters.
 * Frames are built with the kernel's own constants (linux/can/error.h) the
 * way drivers build them (drivers/net/can/dev: can_change_state sets
 * CAN_ERR_CRTL with the RX/TX warning or passive bits, can_bus_off sets
 * CAN_ERR_BUSOFF, a restart sends CAN_ERR_RESTARTED; CAN_ERR_CNT carries the
 * TX/RX error counters in data[6], data[7]). */
#include "test.h"

#include <linux/can.h>
#include <linux/can/error.h>
#include <string.h>

#include "canerr.h"

static int frame(canerr_bus_t *b, uint32_t cls, uint8_t crtl, uint8_t tx, uint8_t rx)
{
    uint8_t d[CAN_ERR_DLC] = {0};
    d[1] = crtl;
    d[6] = tx;
    d[7] = rx;
    return canerr_bus_frame(b, cls, d, sizeof d);
}

/* Given an error-active bus, when a controller climbs to warning, passive,
 * bus-off and is restarted, then the state follows each frame and each
 * entry is counted once; frames naming no state leave it. */
static void test_state_sequence(void **state)
{
    (void)state;
    canerr_bus_t b;
    canerr_bus_init(&b);
    assert_int_equal(b.state, CANERR_STATE_ACTIVE);
    assert_int_equal(frame(&b, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING, 0, 0), 1);
    assert_int_equal(b.state, CANERR_STATE_WARNING);
    assert_int_equal(frame(&b, CAN_ERR_CRTL, CAN_ERR_CRTL_TX_WARNING, 0, 0), 0); /* no change */
    assert_int_equal(frame(&b, CAN_ERR_CRTL | CAN_ERR_CNT, CAN_ERR_CRTL_TX_PASSIVE, 128, 7), 1);
    assert_int_equal(b.state, CANERR_STATE_PASSIVE);
    assert_int_equal(b.tx_err, 128);
    assert_int_equal(b.rx_err, 7);
    assert_int_equal(frame(&b, CAN_ERR_BUSOFF, 0, 0, 0), 1);
    assert_int_equal(b.state, CANERR_STATE_BUS_OFF);
    assert_int_equal(frame(&b, CAN_ERR_PROT | CAN_ERR_BUSERROR, 0, 0, 0), 0);
    assert_int_equal(frame(&b, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_OVERFLOW, 0, 0), 0);
    assert_int_equal(b.state, CANERR_STATE_BUS_OFF);
    assert_int_equal(frame(&b, CAN_ERR_RESTARTED, 0, 0, 0), 1);
    assert_int_equal(b.state, CANERR_STATE_ACTIVE);
    /* passive straight from active, then back down to warning, then active */
    assert_int_equal(frame(&b, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_PASSIVE, 0, 0), 1);
    assert_int_equal(frame(&b, CAN_ERR_CRTL, CAN_ERR_CRTL_RX_WARNING, 0, 0), 1);
    assert_int_equal(b.state, CANERR_STATE_WARNING);
    assert_int_equal(frame(&b, CAN_ERR_CRTL, CAN_ERR_CRTL_ACTIVE, 0, 0), 1);
    assert_int_equal(b.state, CANERR_STATE_ACTIVE);
    assert_int_equal(b.frames, 10);
    assert_int_equal(b.warnings, 1); /* passive -> warning is not an entry into warning */
    assert_int_equal(b.passives, 2);
    assert_int_equal(b.bus_offs, 1);
    assert_int_equal(b.restarts, 1);
    assert_int_equal(b.bus_errors, 1);
    assert_int_equal(b.overflows, 1);
    assert_int_equal(b.malformed, 0);
    assert_string_equal(canerr_state_name(b.state), "error-active");
    assert_string_equal(canerr_state_name(CANERR_STATE_BUS_OFF), "bus-off");
}

/* Given frames that are no error report (no class bit, wrong length), when
 * decoded, then they are refused, counted as malformed, and change nothing. */
static void test_malformed(void **state)
{
    (void)state;
    canerr_bus_t b;
    canerr_bus_init(&b);
    uint8_t d[8] = {0, CAN_ERR_CRTL_TX_PASSIVE};
    assert_int_equal(canerr_bus_frame(&b, 0, d, 8), -1);
    assert_int_equal(canerr_bus_frame(&b, CAN_ERR_CRTL, d, 7), -1);
    assert_int_equal(canerr_bus_frame(&b, 0x400, d, 8), -1); /* above CAN_ERR_CNT: none known */
    assert_int_equal(b.malformed, 3);
    assert_int_equal(b.frames, 0);
    assert_int_equal(b.state, CANERR_STATE_ACTIVE);
    /* the flag itself (as a raw can_id carries it) is ignored */
    assert_int_equal(canerr_bus_frame(&b, CAN_ERR_FLAG | CAN_ERR_CRTL, d, 8), 1);
    assert_int_equal(b.state, CANERR_STATE_PASSIVE);
}

/* Given one frame naming several classes, then the worst state wins. */
static void test_worst_wins(void **state)
{
    (void)state;
    canerr_event_t ev;
    uint8_t d[8] = {0, CAN_ERR_CRTL_RX_WARNING | CAN_ERR_CRTL_TX_PASSIVE};
    assert_int_equal(canerr_decode(CAN_ERR_CRTL, d, 8, &ev), 0);
    assert_int_equal(ev.state, CANERR_STATE_PASSIVE);
    assert_int_equal(canerr_decode(CAN_ERR_CRTL | CAN_ERR_BUSOFF, d, 8, &ev), 0);
    assert_int_equal(ev.state, CANERR_STATE_BUS_OFF);
    assert_int_equal(ev.bus_off, 1);
    assert_int_equal(ev.has_counters, 0);
    assert_int_equal(canerr_decode(CAN_ERR_ACK, d, 8, &ev), 0);
    assert_int_equal(ev.state, CANERR_STATE_NONE); /* data[1] is read only with CAN_ERR_CRTL */
    assert_int_equal(ev.bus_error, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_state_sequence),
        cmocka_unit_test(test_malformed),
        cmocka_unit_test(test_worst_wins),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
