/* cia402.c - CANopen master side of a CiA 402 drive, pure (see cia402.h). */
#include "cia402.h"

#include <string.h>

static void frame(canproto_frame_t *f, uint32_t id, unsigned len)
{
    memset(f, 0, sizeof *f);
    f->id = id;
    f->len = (uint8_t)len;
}

static int classic(const canproto_frame_t *f)
{
    return !(f->flags & (CANPROTO_F_RTR | CANPROTO_F_ERR | CANPROTO_F_EFF | CANPROTO_F_FD));
}

static uint32_t le(const uint8_t *p, unsigned n)
{
    uint32_t v = 0;
    for (unsigned i = 0; i < n; i++)
        v |= (uint32_t)p[i] << (8 * i);
    return v;
}

cia402_state_t cia402_state(uint16_t sw)
{
    /* CiA 402-2 table 30: (mask, value) per state; the masks differ */
    if ((sw & 0x4F) == 0x00)
        return CIA402_NOT_READY;
    if ((sw & 0x4F) == 0x40)
        return CIA402_SWITCH_ON_DISABLED;
    if ((sw & 0x6F) == 0x21)
        return CIA402_READY;
    if ((sw & 0x6F) == 0x23)
        return CIA402_SWITCHED_ON;
    if ((sw & 0x6F) == 0x27)
        return CIA402_OPERATION_ENABLED;
    if ((sw & 0x6F) == 0x07)
        return CIA402_QUICK_STOP_ACTIVE;
    if ((sw & 0x4F) == 0x0F)
        return CIA402_FAULT_REACTION;
    if ((sw & 0x4F) == 0x08)
        return CIA402_FAULT;
    return CIA402_STATE_UNKNOWN;
}

const char *cia402_state_name(cia402_state_t s)
{
    switch (s) {
    case CIA402_NOT_READY: return "not ready to switch on";
    case CIA402_SWITCH_ON_DISABLED: return "switch on disabled";
    case CIA402_READY: return "ready to switch on";
    case CIA402_SWITCHED_ON: return "switched on";
    case CIA402_OPERATION_ENABLED: return "operation enabled";
    case CIA402_QUICK_STOP_ACTIVE: return "quick stop active";
    case CIA402_FAULT_REACTION: return "fault reaction active";
    case CIA402_FAULT: return "fault";
    default: return "unknown";
    }
}

uint16_t cia402_controlword_towards_enabled(cia402_state_t s, int reset)
{
    switch (s) {
    case CIA402_SWITCH_ON_DISABLED: return CIA402_CW_SHUTDOWN;
    case CIA402_READY: return CIA402_CW_SWITCH_ON;
    case CIA402_SWITCHED_ON:
    case CIA402_OPERATION_ENABLED: return CIA402_CW_ENABLE_OPERATION;
    case CIA402_FAULT: return reset ? CIA402_CW_FAULT_RESET : CIA402_CW_DISABLE_VOLTAGE;
    default: return CIA402_CW_DISABLE_VOLTAGE;
    }
}

uint16_t cia402_controlword_hold(cia402_state_t s)
{
    switch (s) {
    case CIA402_READY: return CIA402_CW_SHUTDOWN;
    case CIA402_SWITCHED_ON: return CIA402_CW_SWITCH_ON;
    case CIA402_OPERATION_ENABLED: return CIA402_CW_ENABLE_OPERATION;
    default: return CIA402_CW_DISABLE_VOLTAGE;
    }
}

void cia402_encode_nmt(uint8_t cmd, uint8_t node, canproto_frame_t *out)
{
    frame(out, CIA402_COB_NMT, 2);
    out->data[0] = cmd;
    out->data[1] = node;
}

void cia402_encode_rpdo(uint32_t cob, int with_cw, uint16_t cw, int32_t target,
                        canproto_frame_t *out)
{
    uint32_t t = (uint32_t)target;
    unsigned k = 0;
    frame(out, cob, with_cw ? 6 : 4);
    if (with_cw) {
        out->data[k++] = (uint8_t)cw;
        out->data[k++] = (uint8_t)(cw >> 8);
    }
    for (unsigned b = 0; b < 4; b++)
        out->data[k++] = (uint8_t)(t >> (8 * b));
}

void cia402_encode_heartbeat(uint8_t node, canproto_frame_t *out)
{
    frame(out, CIA402_COB_HEARTBEAT + node, 1);
    out->data[0] = CIA402_HB_OPERATIONAL;
}

int cia402_encode_sdo_download(uint8_t node, uint16_t index, uint8_t sub, uint32_t value,
                               unsigned size, canproto_frame_t *out)
{
    /* command specifier 001, e = 1, s = 1, n = 4 - size in bits 2..3 */
    if (node < 1 || node > CIA402_NODE_MAX || (size != 1 && size != 2 && size != 4))
        return -CANPROTO_EVALUE;
    frame(out, CIA402_COB_SDO_RX + node, 8);
    out->data[0] = (uint8_t)(0x23 | ((4 - size) << 2));
    out->data[1] = (uint8_t)index;
    out->data[2] = (uint8_t)(index >> 8);
    out->data[3] = sub;
    for (unsigned i = 0; i < size; i++)
        out->data[4 + i] = (uint8_t)(value >> (8 * i));
    return 0;
}

int cia402_encode_sdo_upload(uint8_t node, uint16_t index, uint8_t sub, canproto_frame_t *out)
{
    if (node < 1 || node > CIA402_NODE_MAX)
        return -CANPROTO_EVALUE;
    frame(out, CIA402_COB_SDO_RX + node, 8);
    out->data[0] = 0x40; /* initiate upload request, CiA 301 7.2.4.3.6 */
    out->data[1] = (uint8_t)index;
    out->data[2] = (uint8_t)(index >> 8);
    out->data[3] = sub;
    return 0;
}

int cia402_decode_sdo_reply(uint8_t node, const canproto_frame_t *f, cia402_sdo_reply_t *out)
{
    memset(out, 0, sizeof *out);
    if (f->id != CIA402_COB_SDO_TX + node || node < 1 || node > CIA402_NODE_MAX)
        return -CANPROTO_EID;
    if (!classic(f) || f->len != 8)
        return -CANPROTO_ELEN;
    uint8_t cs = f->data[0];
    out->index = (uint16_t)le(&f->data[1], 2);
    out->sub = f->data[3];
    if (cs == 0x60) {
        out->kind = CIA402_SDO_DOWNLOAD_OK;
        return 0;
    }
    if (cs == 0x80) {
        out->kind = CIA402_SDO_ABORT;
        out->abort_code = le(&f->data[4], 4);
        return 0;
    }
    if ((cs & 0xE3) == 0x43) { /* upload response, expedited, size indicated */
        unsigned n = 4 - ((cs >> 2) & 3);
        out->kind = CIA402_SDO_UPLOAD;
        out->value = le(&f->data[4], n);
        return 0;
    }
    return -CANPROTO_EVALUE;
}

const char *cia402_sdo_abort_text(uint32_t code)
{
    static const struct {
        uint32_t code;
        const char *text;
    } t[] = {
        {0x05030000, "toggle bit not alternated"},
        {0x05040000, "SDO protocol timed out"},
        {0x05040001, "client/server command specifier not valid or unknown"},
        {0x05040002, "invalid block size (block mode only)"},
        {0x05040003, "invalid sequence number (block mode only)"},
        {0x05040004, "CRC error (block mode only)"},
        {0x05040005, "out of memory"},
        {0x06010000, "unsupported access to an object"},
        {0x06010001, "attempt to read a write only object"},
        {0x06010002, "attempt to write a read only object"},
        {0x06020000, "object does not exist in the object dictionary"},
        {0x06040041, "object cannot be mapped to the PDO"},
        {0x06040042, "the number and length of the objects to be mapped would exceed PDO length"},
        {0x06040043, "general parameter incompatibility reason"},
        {0x06040047, "general internal incompatibility in the device"},
        {0x06060000, "access failed due to a hardware error"},
        {0x06070010, "data type does not match, length of service parameter does not match"},
        {0x06070012, "data type does not match, length of service parameter too high"},
        {0x06070013, "data type does not match, length of service parameter too low"},
        {0x06090011, "sub-index does not exist"},
        {0x06090030, "invalid value for parameter (download only)"},
        {0x06090031, "value of parameter written too high (download only)"},
        {0x06090032, "value of parameter written too low (download only)"},
        {0x06090036, "maximum value is less than minimum value"},
        {0x060A0023, "resource not available: SDO connection"},
        {0x08000000, "general error"},
        {0x08000020, "data cannot be transferred or stored to the application"},
        {0x08000021,
         "data cannot be transferred or stored to the application because of local control"},
        {0x08000022, "data cannot be transferred or stored to the application because of the "
                     "present device state"},
        {0x08000023,
         "object dictionary dynamic generation fails or no object dictionary is present"},
        {0x08000024, "no data available"},
    };
    for (unsigned i = 0; i < sizeof t / sizeof t[0]; i++)
        if (t[i].code == code)
            return t[i].text;
    return "unknown abort code";
}

int cia402_decode_heartbeat(const canproto_frame_t *f, uint8_t *node, uint8_t *state)
{
    if (f->id <= CIA402_COB_HEARTBEAT || f->id > CIA402_COB_HEARTBEAT + CIA402_NODE_MAX)
        return -CANPROTO_EID;
    if (!classic(f) || f->len != 1)
        return -CANPROTO_ELEN;
    uint8_t s = f->data[0];
    if (s != CIA402_HB_BOOTUP && s != CIA402_HB_STOPPED && s != CIA402_HB_OPERATIONAL &&
        s != CIA402_HB_PREOP)
        return -CANPROTO_EVALUE;
    *node = (uint8_t)(f->id - CIA402_COB_HEARTBEAT);
    *state = s;
    return 0;
}

int cia402_decode_emcy(const canproto_frame_t *f, uint8_t *node, uint16_t *code, uint8_t *reg)
{
    if (f->id <= CIA402_COB_EMCY || f->id > CIA402_COB_EMCY + CIA402_NODE_MAX)
        return -CANPROTO_EID;
    if (!classic(f) || f->len != 8)
        return -CANPROTO_ELEN;
    *node = (uint8_t)(f->id - CIA402_COB_EMCY);
    *code = (uint16_t)le(&f->data[0], 2);
    *reg = f->data[2];
    return 0;
}

int cia402_decode_feedback(const canproto_frame_t *f, uint16_t *statusword, int32_t *pos_inc)
{
    if (!classic(f) || f->len < 6)
        return -CANPROTO_ELEN;
    *statusword = (uint16_t)le(&f->data[0], 2);
    *pos_inc = (int32_t)le(&f->data[2], 4);
    return 0;
}
