/*
 * canproto_dbc.c - config/trajd.dbc from the layouts of lib/proto/canproto.h: the
 * description tables and the DBC text (test and build-time scaffolding, not product).
 */
#include "canproto_dbc.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ---- description tables ------------------------------------------------------------------ */

/* Range of a raw field in physical units. */
#define U_MAX(bits) ((double)((1ull << (bits)) - 1))
#define S_MIN(bits) (-(double)(1ull << ((bits)-1)))
#define S_MAX(bits) ((double)((1ull << ((bits)-1)) - 1))
#define SIG_U(name, mux, start, bits, factor, unit)                                                \
    {                                                                                              \
        name, mux, start, bits, 0, factor, 0, 0, U_MAX(bits) * (factor), unit                      \
    }
#define SIG_S(name, mux, start, bits, factor, unit)                                                \
    {                                                                                              \
        name, mux, start, bits, 1, factor, 0, S_MIN(bits) * (factor), S_MAX(bits) * (factor), unit \
    }

static const canproto_signal_t sig_wp[] = {
    SIG_U("WP_Mux", -2, 0, 8, 1, ""),
    SIG_U("WP_Seq", -1, 8, 8, 1, ""),
    SIG_U("WP_Time", CANPROTO_MUX_TIME, 16, 48, CANPROTO_WP_T_S_PER_BIT, "s"),
    SIG_S("WP_X", CANPROTO_MUX_X, 16, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WP_Y", CANPROTO_MUX_Y, 16, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WP_Z", CANPROTO_MUX_Z, 16, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_U("WP_Command", CANPROTO_MUX_COMMAND, 16, 8, 1, ""),
    SIG_U("WP_CommandArg", CANPROTO_MUX_COMMAND, 24, 8, 1, "%"),
    SIG_S("WP_VX", CANPROTO_MUX_VELOCITY, 16, 16, CANPROTO_WP_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("WP_VY", CANPROTO_MUX_VELOCITY, 32, 16, CANPROTO_WP_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("WP_VZ", CANPROTO_MUX_VELOCITY, 48, 16, CANPROTO_WP_VEL_M_S_PER_BIT, "m/s"),
};
static const canproto_signal_t sig_wpfd[] = {
    SIG_U("WPFD_Mux", -2, 0, 8, 1, ""),
    SIG_U("WPFD_Seq", -1, 8, 8, 1, ""),
    SIG_U("WPFD_Time", -1, 16, 48, CANPROTO_WP_T_S_PER_BIT, "s"),
    SIG_S("WPFD_X", -1, 64, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WPFD_Y", -1, 112, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WPFD_Z", -1, 160, 48, CANPROTO_WP_POS_M_PER_BIT, "m"),
    SIG_S("WPFD_VX", CANPROTO_MUX_FD_WAYPOINT_VEL, 208, 16, CANPROTO_WP_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("WPFD_VY", CANPROTO_MUX_FD_WAYPOINT_VEL, 224, 16, CANPROTO_WP_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("WPFD_VZ", CANPROTO_MUX_FD_WAYPOINT_VEL, 240, 16, CANPROTO_WP_VEL_M_S_PER_BIT, "m/s"),
};
static const canproto_signal_t sig_sp[] = {
    SIG_U("SP_Axis", -2, 0, 2, 1, ""),
    SIG_U("SP_State", -1, 4, 3, 1, ""),
    SIG_U("SP_Hold", -1, 7, 1, 1, ""),
    SIG_U("SP_Cycle", -1, 8, 8, 1, ""),
    SIG_S("SP_X_Pos", 0, 16, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SP_X_Vel", 0, 48, 16, CANPROTO_SP_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("SP_Y_Pos", 1, 16, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SP_Y_Vel", 1, 48, 16, CANPROTO_SP_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("SP_Z_Pos", 2, 16, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SP_Z_Vel", 2, 48, 16, CANPROTO_SP_VEL_M_S_PER_BIT, "m/s"),
};
static const canproto_signal_t sig_spfd[] = {
    SIG_U("SPFD_Cycle", -1, 0, 32, 1, ""),
    SIG_S("SPFD_X", -1, 32, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SPFD_Y", -1, 64, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SPFD_Z", -1, 96, 32, CANPROTO_SP_POS_M_PER_BIT, "m"),
    SIG_S("SPFD_VX", -1, 128, 32, CANPROTO_SPFD_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("SPFD_VY", -1, 160, 32, CANPROTO_SPFD_VEL_M_S_PER_BIT, "m/s"),
    SIG_S("SPFD_VZ", -1, 192, 32, CANPROTO_SPFD_VEL_M_S_PER_BIT, "m/s"),
    SIG_U("SPFD_State", -1, 224, 8, 1, ""),
    SIG_U("SPFD_Flags", -1, 232, 8, 1, ""),
    SIG_U("SPFD_Track", -1, 240, 16, 1, ""),
};
static const canproto_signal_t sig_st[] = {
    SIG_U("ST_State", -1, 0, 3, 1, ""),      SIG_U("ST_Clamped", -1, 3, 1, 1, ""),
    SIG_U("ST_BusDown", -1, 4, 1, 1, ""),    SIG_U("ST_TxDrop", -1, 5, 1, 1, ""),
    SIG_U("ST_OutFault", -1, 6, 1, 1, ""),   SIG_U("ST_SafetyFault", -1, 7, 1, 1, ""),
    SIG_U("ST_LastSeq", -1, 8, 8, 1, ""),    SIG_U("ST_Free", -1, 16, 8, 1, ""),
    SIG_U("ST_Lost", -1, 24, 8, 1, ""),      SIG_U("ST_Rejected", -1, 32, 8, 1, ""),
    SIG_U("ST_Malformed", -1, 40, 8, 1, ""), SIG_U("ST_Dropped", -1, 48, 8, 1, ""),
    SIG_U("ST_LastErr", -1, 56, 8, 1, ""),
};
static const canproto_signal_t sig_st2[] = {
    SIG_U("ST2_Page", -2, 0, 8, 1, ""),
    SIG_U("ST2_OutLost", CANPROTO_ST2_FAULTS, 8, 24, 1, ""),
    SIG_U("ST2_OutErrors", CANPROTO_ST2_FAULTS, 32, 16, 1, ""),
    SIG_U("ST2_CmdRefused", CANPROTO_ST2_FAULTS, 48, 16, 1, ""),
    SIG_U("ST2_BusState", CANPROTO_ST2_BUS, 8, 8, 1, ""),
    SIG_U("ST2_TxErr", CANPROTO_ST2_BUS, 16, 8, 1, ""),
    SIG_U("ST2_RxErr", CANPROTO_ST2_BUS, 24, 8, 1, ""),
    SIG_U("ST2_BusOffs", CANPROTO_ST2_BUS, 32, 16, 1, ""),
    SIG_U("ST2_ErrFrames", CANPROTO_ST2_BUS, 48, 16, 1, ""),
    SIG_U("ST2_RejBackwards", CANPROTO_ST2_REJECTED, 8, 8, 1, ""),
    SIG_U("ST2_RejSameTime", CANPROTO_ST2_REJECTED, 16, 8, 1, ""),
    SIG_U("ST2_RejSpeed", CANPROTO_ST2_REJECTED, 24, 8, 1, ""),
    SIG_U("ST2_RejAccel", CANPROTO_ST2_REJECTED, 32, 8, 1, ""),
    SIG_U("ST2_RejUnconfirmed", CANPROTO_ST2_REJECTED, 40, 8, 1, ""),
    SIG_U("ST2_RejStale", CANPROTO_ST2_REJECTED, 48, 8, 1, ""),
    SIG_U("ST2_RejOther", CANPROTO_ST2_REJECTED, 56, 8, 1, ""),
    SIG_S("ST2_Age", CANPROTO_ST2_CLOCK, 8, 24, CANPROTO_ST2_AGE_S_PER_BIT, "s"),
    SIG_S("ST2_Drift", CANPROTO_ST2_CLOCK, 32, 16, CANPROTO_ST2_DRIFT_PPM_PER_BIT, "ppm"),
    SIG_U("ST2_Clocked", CANPROTO_ST2_CLOCK, 48, 8, 1, ""),
    SIG_S("ST2_TimeT", CANPROTO_ST2_TIME, 8, 56, CANPROTO_ST2_TIME_S_PER_BIT, "s"),
    SIG_U("ST2_StateX", CANPROTO_ST2_DRIVE, 8, 4, 1, ""),
    SIG_U("ST2_StateY", CANPROTO_ST2_DRIVE, 12, 4, 1, ""),
    SIG_U("ST2_StateZ", CANPROTO_ST2_DRIVE, 16, 4, 1, ""),
    SIG_U("ST2_HbLost", CANPROTO_ST2_DRIVE, 22, 1, 1, ""),
    SIG_U("ST2_Held", CANPROTO_ST2_DRIVE, 23, 1, 1, ""),
    SIG_U("ST2_Statusword", CANPROTO_ST2_DRIVE, 24, 16, 1, ""),
    SIG_U("ST2_Nmt", CANPROTO_ST2_DRIVE, 40, 8, 1, ""),
    SIG_U("ST2_Emcy", CANPROTO_ST2_DRIVE, 48, 16, 1, ""),
    SIG_U("ST2_Underruns", CANPROTO_ST2_MOTION, 8, 16, 1, ""),
    SIG_U("ST2_DelayGrown", CANPROTO_ST2_MOTION, 24, 8, 1, ""),
    SIG_U("ST2_TransfersMoving", CANPROTO_ST2_MOTION, 32, 8, 1, ""),
    SIG_U("ST2_ReserveSlowed", CANPROTO_ST2_MOTION, 40, 8, 1, ""),
    SIG_U("ST2_AxisBeyond", CANPROTO_ST2_MOTION, 48, 8, 1, ""),
    SIG_U("ST2_AxisLagStops", CANPROTO_ST2_MOTION, 56, 8, 1, ""),
};
static const canproto_signal_t sig_rpdo[] = {
    SIG_S("Target_Position_607A", -1, 0, 32, 1, "inc"),
};
static const canproto_signal_t sig_rpdo_cw[] = {
    SIG_U("Controlword_6040", -1, 0, 16, 1, ""),
    SIG_S("Target_Position_607A", -1, 16, 32, 1, "inc"),
};
static const canproto_signal_t sig_tpdo_fb[] = {
    SIG_U("Statusword_6041", -1, 0, 16, 1, ""),
    SIG_S("Position_Actual_6064", -1, 16, 32, 1, "inc"),
};

static const canproto_message_t canproto_msgs[] = {
    {"TRAJD_WAYPOINT", CANPROTO_ID_WAYPOINT_BASE, CANPROTO_WP_DLEN, 0, "SENDER", sig_wp,
     sizeof sig_wp / sizeof sig_wp[0]},
    {"TRAJD_WAYPOINT_FD", CANPROTO_ID_WAYPOINT_FD_BASE, CANPROTO_WP_FD_DLEN, 1, "SENDER", sig_wpfd,
     sizeof sig_wpfd / sizeof sig_wpfd[0]},
    {"TRAJD_SETPOINT", CANPROTO_ID_SETPOINT_BASE, CANPROTO_SP_DLEN, 0, "TRAJD", sig_sp,
     sizeof sig_sp / sizeof sig_sp[0]},
    {"TRAJD_SETPOINT_FD", CANPROTO_ID_SETPOINT_FD_BASE, CANPROTO_SP_FD_DLEN, 1, "TRAJD", sig_spfd,
     sizeof sig_spfd / sizeof sig_spfd[0]},
    {"TRAJD_STATUS", CANPROTO_ID_STATUS_BASE, CANPROTO_STATUS_DLEN, 0, "TRAJD", sig_st,
     sizeof sig_st / sizeof sig_st[0]},
    {"TRAJD_STATUS2", CANPROTO_ID_STATUS2_BASE, CANPROTO_STATUS2_DLEN, 0, "TRAJD", sig_st2,
     sizeof sig_st2 / sizeof sig_st2[0]},
    {"SYNC", CANPROTO_ID_SYNC_DEFAULT, 0, 0, "TRAJD", NULL, 0},
    {"RPDO1_NODE1", CANPROTO_CIA402_RPDO1_BASE + 1, 4, 0, "TRAJD", sig_rpdo, 1},
    {"RPDO1_NODE2", CANPROTO_CIA402_RPDO1_BASE + 2, 4, 0, "TRAJD", sig_rpdo, 1},
    {"RPDO1_NODE3", CANPROTO_CIA402_RPDO1_BASE + 3, 4, 0, "TRAJD", sig_rpdo, 1},
    {"RPDO_CW_NODE1", CANPROTO_CIA402_RPDO2_BASE + 1, 6, 0, "TRAJD", sig_rpdo_cw, 2},
    {"RPDO_CW_NODE2", CANPROTO_CIA402_RPDO2_BASE + 2, 6, 0, "TRAJD", sig_rpdo_cw, 2},
    {"RPDO_CW_NODE3", CANPROTO_CIA402_RPDO2_BASE + 3, 6, 0, "TRAJD", sig_rpdo_cw, 2},
    {"TPDO1_NODE1", CANPROTO_CIA402_TPDO1_BASE + 1, 6, 0, "SENDER", sig_tpdo_fb, 2},
    {"TPDO1_NODE2", CANPROTO_CIA402_TPDO1_BASE + 2, 6, 0, "SENDER", sig_tpdo_fb, 2},
    {"TPDO1_NODE3", CANPROTO_CIA402_TPDO1_BASE + 3, 6, 0, "SENDER", sig_tpdo_fb, 2},
};

const canproto_message_t *canproto_messages(unsigned *count)
{
    *count = sizeof canproto_msgs / sizeof canproto_msgs[0];
    return canproto_msgs;
}

/* snprintf into buf at *pos, tracking the length needed even when it does not fit. */
#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
static void
emit(char *buf, size_t len, size_t *pos, const char *fmt, ...);

static void emit(char *buf, size_t len, size_t *pos, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(*pos < len ? buf + *pos : NULL, *pos < len ? len - *pos : 0, fmt, ap);
    va_end(ap);
    if (n > 0)
        *pos += (size_t)n;
}

int canproto_dbc(char *buf, size_t len)
{
    size_t pos = 0;
    unsigned n;
    const canproto_message_t *m = canproto_messages(&n);

    if (len)
        buf[0] = '\0';
    emit(buf, len, &pos,
         "VERSION \"trajd\"\n\n"
         "NS_ :\n\tCM_\n\tBA_DEF_\n\tBA_\n\tBA_DEF_DEF_\n\tVAL_\n\n"
         "BS_:\n\n"
         "BU_: TRAJD SENDER\n\n");
    for (unsigned i = 0; i < n; i++) {
        emit(buf, len, &pos, "BO_ %u %s: %u %s\n", (unsigned)m[i].id, m[i].name, m[i].dlen,
             m[i].sender);
        for (unsigned k = 0; k < m[i].nsignals; k++) {
            const canproto_signal_t *s = &m[i].signals[k];
            char mux[16] = "";
            if (s->mux == -2)
                snprintf(mux, sizeof mux, " M");
            else if (s->mux >= 0)
                snprintf(mux, sizeof mux, " m%d", s->mux);
            emit(buf, len, &pos, " SG_ %s%s : %u|%u@1%c (%.15g,%.15g) [%.15g|%.15g] \"%s\" %s\n",
                 s->name, mux, s->start_bit, s->bits, s->is_signed ? '-' : '+', s->factor,
                 s->offset, s->min, s->max, s->unit,
                 strcmp(m[i].sender, "TRAJD") ? "TRAJD" : "SENDER");
        }
        emit(buf, len, &pos, "\n");
    }
    emit(buf, len, &pos,
         "CM_ \"trajd CAN protocol, generated from lib/proto/canproto.h by canproto_dbc(); ids are "
         "the defaults of object 0 (object n: + n), RPDOs for CiA 402 nodes 1..3 (RPDO_CW: the "
         "layout sent with can.cia402_controlword = yes, shown on the RPDO2 ids 0x301..0x303; "
         "TPDO1: the drive feedback trajd reads, statusword 0x6041 and position actual value "
         "0x6064). Setpoint positions 0x80000000: no position yet, do not move.\";\n"
         "CM_ SG_ %u WP_Command \"1 finish, 2 stop now (latched until start or clear), 3 "
         "clear, 4 reset counters, 5 feed override, 6 start\";\n"
         "CM_ SG_ %u WP_CommandArg \"feed override in percent (0..200) for command 5, else 0\";\n"
         "CM_ SG_ %u ST_LastErr \"1..13 engine_error of the last rejected waypoint, 0x40 "
         "malformed, 0x41 lost, 0x42 out of order, 0x43 setpoints dropped, 0x44 bus down, 0x45 "
         "csv/stdout output lost lines, 0x46 safety monitor fault (object held until clear), 0x47 "
         "a CiA 402 "
         "drive left Operation Enabled, 0x48 a command refused (object not writable, or held: an "
         "override above 0 during a feed hold)\";\n"
         "CM_ SG_ %u ST2_Page \"STATUS2 page: 1 faults, 2 rejected waypoints per reason, 3 clock, "
         "4 drive, 5 bus, 6 time, 7 motion; "
         "counters saturate at their maximum\";\n"
         "CM_ SG_ %u ST2_OutLost \"setpoint lines lost by the object's csv/stdout outputs\";\n"
         "CM_ SG_ %u ST2_OutErrors \"failed writes of the object's csv/stdout outputs\";\n"
         "CM_ SG_ %u ST2_CmdRefused \"command frames refused: the object is not writable, or held "
         "(an override above 0 during a feed hold)\";\n"
         "CM_ SG_ %u ST2_RejSpeed \"waypoints refused per reason (engine_error: backwards 3, "
         "same time 4, speed 5, acceleration 11, unconfirmed 12, stale 13; other: not finite 1, "
         "out of range 2, numeric 10), saturating at 255; exact counts in the Modbus diagnostics "
         "block\";\n"
         "CM_ SG_ %u ST2_BusState \"CAN bus state from the controller's error frames\";\n"
         "CM_ SG_ %u ST2_TxErr \"TX error counter, as last reported (CAN_ERR_CNT)\";\n"
         "CM_ SG_ %u ST2_RxErr \"RX error counter, as last reported (CAN_ERR_CNT)\";\n"
         "CM_ SG_ %u ST2_BusOffs \"entries into bus-off\";\n"
         "CM_ SG_ %u ST2_ErrFrames \"error frames received\";\n",
         CANPROTO_ID_WAYPOINT_BASE, CANPROTO_ID_WAYPOINT_BASE, CANPROTO_ID_STATUS_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE);
    emit(buf, len, &pos,
         "CM_ SG_ %u ST2_Age \"page 3: data age now - t_s of the setpoint on the sender's time "
         "base (lib/engine/CLOCK.md; D when on time, negative while waiting for the clock to "
         "reach the start), -8388.608: none (relative time, no position), saturating at "
         "+-8388.607\";\n"
         "CM_ SG_ %u ST2_Drift \"page 3: sender clock drift absorbed by the play-out clock (+ = "
         "sender fast), one estimate per daemon; -3276.8: none\";\n"
         "CM_ SG_ %u ST2_Clocked \"page 3: 0 relative time, 1 on the daemon's clock, 2 "
         "undecided (clock = auto: the first waypoint decides)\";\n"
         "CM_ SG_ %u ST2_TimeT \"page 6: track time t_s of the setpoint (the waypoints' time "
         "base, as WP_Time), -36028797018.963968: none\";\n"
         "CM_ SG_ %u ST2_Statusword \"page 4: statusword 0x6041 of the first drive axis not in "
         "Operation Enabled, else of the first\";\n"
         "CM_ SG_ %u ST2_Nmt \"page 4: heartbeat NMT state of the same node\";\n"
         "CM_ SG_ %u ST2_Held \"page 4: a drive left Operation Enabled: no target sent, drives "
         "disabled until the command clear\";\n"
         "CM_ SG_ %u ST2_HbLost \"page 4: a drive's heartbeat not heard within "
         "can.cia402_heartbeat_ms\";\n"
         "CM_ SG_ %u ST2_Emcy \"page 4: error code of the last EMCY from the object's drives, 0: "
         "none\";\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE);
    emit(buf, len, &pos,
         "CM_ SG_ %u ST2_Underruns \"page 7: transitions into underrun (the newest waypoint "
         "passed before the next came)\";\n"
         "CM_ SG_ %u ST2_DelayGrown \"page 7: the delay D stated anew, longer (the input's "
         "intervals, top speed or arrival jitter grew beyond what D was sized for)\";\n"
         "CM_ SG_ %u ST2_TransfersMoving \"page 7: re-anchors joined moving: the output met the "
         "new trajectory's curve without braking to rest\";\n"
         "CM_ SG_ %u ST2_ReserveSlowed \"page 7: slowdowns of an object faster than the speed "
         "the stop reserve of D was sized for, on input that came on time (not underruns)\";\n"
         "CM_ SG_ %u ST2_AxisBeyond \"page 7: stops before a segment the per-axis limits "
         "(axis_max_*) cannot follow: over 100 times faster on an axis than its limit\";\n"
         "CM_ SG_ %u ST2_AxisLagStops \"page 7: stops because the lag the per-axis limits "
         "made passed max_lag_s (time lost to them: Modbus diagnostics)\";\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE,
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE, CANPROTO_ID_STATUS2_BASE);
    emit(buf, len, &pos,
         "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\","
         "\"J1939PG\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\","
         "\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"StandardCAN_FD\","
         "\"ExtendedCAN_FD\";\n"
         "BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";\n");
    for (unsigned i = 0; i < n; i++)
        if (m[i].fd)
            emit(buf, len, &pos, "BA_ \"VFrameFormat\" BO_ %u 14;\n", (unsigned)m[i].id);
    /* value tables of every enum field, from the enums of canproto.h / motion.h */
    const char *states = "0 \"waiting\" 1 \"streaming\" 2 \"underrun\" 3 \"finished\"";
    emit(buf, len, &pos,
         "VAL_ %u WP_Mux %d \"time\" %d \"x\" %d \"y\" %d \"z\" %d \"command\" %d \"velocity\" ;\n",
         CANPROTO_ID_WAYPOINT_BASE, CANPROTO_MUX_TIME, CANPROTO_MUX_X, CANPROTO_MUX_Y,
         CANPROTO_MUX_Z, CANPROTO_MUX_COMMAND, CANPROTO_MUX_VELOCITY);
    emit(buf, len, &pos,
         "VAL_ %u WPFD_Mux %d \"whole waypoint\" %d \"whole waypoint with velocity\" ;\n",
         CANPROTO_ID_WAYPOINT_FD_BASE, CANPROTO_MUX_FD_WAYPOINT, CANPROTO_MUX_FD_WAYPOINT_VEL);
    emit(buf, len, &pos,
         "VAL_ %u WP_Command %d \"finish\" %d \"stop\" %d \"clear\" %d \"reset counters\" %d "
         "\"feed override\" %d \"start\" ;\n",
         CANPROTO_ID_WAYPOINT_BASE, CANPROTO_CMD_FINISH, CANPROTO_CMD_STOP, CANPROTO_CMD_CLEAR,
         CANPROTO_CMD_RESET_COUNTERS, CANPROTO_CMD_OVERRIDE, CANPROTO_CMD_START);
    emit(buf, len, &pos, "VAL_ %u SP_Axis 0 \"x\" 1 \"y\" 2 \"z\" ;\n", CANPROTO_ID_SETPOINT_BASE);
    emit(buf, len, &pos, "VAL_ %u SP_State %s ;\n", CANPROTO_ID_SETPOINT_BASE, states);
    emit(buf, len, &pos, "VAL_ %u SPFD_State %s ;\n", CANPROTO_ID_SETPOINT_FD_BASE, states);
    emit(buf, len, &pos, "VAL_ %u ST_State %s ;\n", CANPROTO_ID_STATUS_BASE, states);
    emit(buf, len, &pos,
         "VAL_ %u ST_LastErr 0 \"ok\" 1 \"not finite\" 2 \"out of range\" 3 \"backwards\" 4 \"same "
         "time\" 5 \"speed\" 6 \"full\" 7 \"config\" 8 \"no memory\" 9 \"state\" 10 \"numeric\" 11 "
         "\"acceleration\" 12 \"unconfirmed\" 13 \"stale\" %d \"malformed\" %d \"lost\" %d \"out "
         "of order\" %d \"setpoints dropped\" %d \"bus down\" %d \"output lost lines\" %d \"safety "
         "fault\" %d \"drive not enabled\" %d \"command refused\" ;\n",
         CANPROTO_ID_STATUS_BASE, CANPROTO_STERR_MALFORMED, CANPROTO_STERR_LOST,
         CANPROTO_STERR_OUT_OF_ORDER, CANPROTO_STERR_TX_DROPPED, CANPROTO_STERR_BUS_DOWN,
         CANPROTO_STERR_OUTPUT, CANPROTO_STERR_SAFETY, CANPROTO_STERR_DRIVE,
         CANPROTO_STERR_REFUSED);
    emit(buf, len, &pos,
         "VAL_ %u ST2_Page %d \"faults\" %d \"rejected\" %d \"clock\" %d \"drive\" %d \"bus\" "
         "%d \"time\" %d \"motion\" ;\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ST2_FAULTS, CANPROTO_ST2_REJECTED, CANPROTO_ST2_CLOCK,
         CANPROTO_ST2_DRIVE, CANPROTO_ST2_BUS, CANPROTO_ST2_TIME, CANPROTO_ST2_MOTION);
    emit(buf, len, &pos,
         "VAL_ %u ST2_Clocked %d \"relative\" %d \"on the clock\" %d \"undecided\" ;\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_ST2_CLOCK_RELATIVE, CANPROTO_ST2_CLOCK_ON,
         CANPROTO_ST2_CLOCK_UNDECIDED);
    emit(buf, len, &pos,
         "VAL_ %u ST2_BusState 1 \"error-active\" 2 \"error-warning\" 3 \"error-passive\" "
         "4 \"bus-off\" 5 \"down\" ;\n",
         CANPROTO_ID_STATUS2_BASE);

    for (unsigned a = 0; a < 3; a++)
        emit(buf, len, &pos,
             "VAL_ %u ST2_State%c 0 \"not ready to switch on\" 1 \"switch on disabled\" "
             "2 \"ready to switch on\" 3 \"switched on\" 4 \"operation enabled\" "
             "5 \"quick stop active\" 6 \"fault reaction active\" 7 \"fault\" 8 \"not heard\" "
             "%u \"no drive\" ;\n",
             CANPROTO_ID_STATUS2_BASE, "XYZ"[a], CANPROTO_S2_NO_DRIVE);
    emit(buf, len, &pos,
         "VAL_ %u ST2_Nmt 0 \"boot-up\" 4 \"stopped\" 5 \"operational\" 127 "
         "\"pre-operational\" %u \"none heard\" ;\n",
         CANPROTO_ID_STATUS2_BASE, CANPROTO_S2_NMT_NONE);
    for (unsigned k = 1; k <= 3; k++)
        emit(buf, len, &pos,
             "VAL_ %u Controlword_6040 0 \"disable voltage\" 2 \"quick stop\" 6 \"shutdown\" "
             "7 \"switch on\" 15 \"enable operation\" 128 \"fault reset\" ;\n",
             CANPROTO_CIA402_RPDO2_BASE + k);
    return pos > (size_t)INT32_MAX ? -1 : (int)pos;
}
