-- trajd.lua - Wireshark/tshark dissector for trajd's CAN frames.
--
-- The layouts of config/trajd.dbc (generated from lib/proto/canproto.h):
-- WAYPOINT, WAYPOINT_FD, SETPOINT, SETPOINT_FD, STATUS and STATUS2 at their
-- default ids for objects 0..15 (0x680+n, 0x690+n, 0x6A0+n, 0x6B0+n, 0x6C0+n,
-- 0x6D0+n).
-- SYNC and the CiA 402 RPDOs are CANopen: Wireshark's own CANopen dissector
-- decodes them.  Every field is named after its DBC signal (trajd.SP_X_Pos,
-- trajd.ST_LastErr, ...) with the DBC's scaling, so a display filter reads
-- like the DBC: `trajd.SP_State == 1 && trajd.obj == 0`.
--
-- Use:
--   tshark -X lua_script:/usr/share/trajd/trajd.lua -r capture.pcap
-- or copy it to ~/.local/lib/wireshark/plugins/.  A capture: `candump -l`
-- (any trajd log_out) turned into a pcap (LINKTYPE_CAN_SOCKETCAN), or a live
-- capture on can0 (`tshark -i can0`).  Tested by tests/e2e/test_dissector.py
-- against canmatrix's decoding of the same frames with config/trajd.dbc.
-- Ids other than the defaults: change BASE below.

local BASE = {WAYPOINT = 0x680, WAYPOINT_FD = 0x690, SETPOINT = 0x6A0, SETPOINT_FD = 0x6B0,
              STATUS = 0x6C0, STATUS2 = 0x6D0}
local OBJECTS = 16

local p = Proto("trajd", "trajd trajectory daemon")

local STATE = {[0] = "waiting", [1] = "streaming", [2] = "underrun", [3] = "finished"}
local VALS = {
    WP_Mux = {[0] = "time", [1] = "x", [2] = "y", [3] = "z", [4] = "command", [6] = "velocity"},
    WPFD_Mux = {[5] = "whole waypoint", [7] = "whole waypoint with velocity"},
    WP_Command = {[1] = "finish", [2] = "stop", [3] = "clear", [4] = "reset counters",
                  [5] = "feed override", [6] = "start"},
    SP_Axis = {[0] = "x", [1] = "y", [2] = "z"},
    SP_State = STATE, SPFD_State = STATE, ST_State = STATE,
    ST_LastErr = {[0] = "ok", [1] = "not finite", [2] = "out of range", [3] = "backwards",
                  [4] = "same time", [5] = "speed", [6] = "full", [7] = "config",
                  [8] = "no memory", [9] = "state", [10] = "numeric", [11] = "acceleration",
                  [12] = "unconfirmed", [13] = "stale",
                  [64] = "malformed", [65] = "lost", [66] = "out of order",
                  [67] = "setpoints dropped", [68] = "bus down", [69] = "output lost lines",
                  [70] = "safety fault", [71] = "drive not enabled", [72] = "command refused"},
    ST2_Page = {[1] = "faults", [2] = "rejected", [3] = "clock", [4] = "drive", [5] = "bus",
                [6] = "time", [7] = "motion"},
    ST2_Clocked = {[0] = "relative", [1] = "on the clock", [2] = "undecided"},
    ST2_BusState = {[1] = "error-active", [2] = "error-warning", [3] = "error-passive",
                    [4] = "bus-off", [5] = "down"},
}

-- Signals: name, start bit, length, signed, factor, unit, mux value (nil: always).
-- Little-endian (Intel) bit numbering as in the DBC.
local MSG = {
    WAYPOINT = {mux = "WP_Mux", {"WP_Mux", 0, 8}, {"WP_Seq", 8, 8},
        {"WP_Time", 16, 48, false, 1e-6, "s", 0}, {"WP_X", 16, 48, true, 1e-6, "m", 1},
        {"WP_Y", 16, 48, true, 1e-6, "m", 2}, {"WP_Z", 16, 48, true, 1e-6, "m", 3},
        {"WP_Command", 16, 8, false, 1, "", 4}, {"WP_CommandArg", 24, 8, false, 1, "%", 4},
        {"WP_VX", 16, 16, true, 0.01, "m/s", 6}, {"WP_VY", 32, 16, true, 0.01, "m/s", 6},
        {"WP_VZ", 48, 16, true, 0.01, "m/s", 6}},
    WAYPOINT_FD = {mux = "WPFD_Mux", {"WPFD_Mux", 0, 8}, {"WPFD_Seq", 8, 8},
        {"WPFD_Time", 16, 48, false, 1e-6, "s"}, {"WPFD_X", 64, 48, true, 1e-6, "m"},
        {"WPFD_Y", 112, 48, true, 1e-6, "m"}, {"WPFD_Z", 160, 48, true, 1e-6, "m"},
        {"WPFD_VX", 208, 16, true, 0.01, "m/s", 7}, {"WPFD_VY", 224, 16, true, 0.01, "m/s", 7},
        {"WPFD_VZ", 240, 16, true, 0.01, "m/s", 7}},
    SETPOINT = {mux = "SP_Axis", {"SP_Axis", 0, 2}, {"SP_State", 4, 3}, {"SP_Hold", 7, 1},
        {"SP_Cycle", 8, 8},
        {"SP_X_Pos", 16, 32, true, 1e-4, "m", 0}, {"SP_X_Vel", 48, 16, true, 1e-3, "m/s", 0},
        {"SP_Y_Pos", 16, 32, true, 1e-4, "m", 1}, {"SP_Y_Vel", 48, 16, true, 1e-3, "m/s", 1},
        {"SP_Z_Pos", 16, 32, true, 1e-4, "m", 2}, {"SP_Z_Vel", 48, 16, true, 1e-3, "m/s", 2}},
    SETPOINT_FD = {{"SPFD_Cycle", 0, 32}, {"SPFD_X", 32, 32, true, 1e-4, "m"},
        {"SPFD_Y", 64, 32, true, 1e-4, "m"}, {"SPFD_Z", 96, 32, true, 1e-4, "m"},
        {"SPFD_VX", 128, 32, true, 1e-6, "m/s"}, {"SPFD_VY", 160, 32, true, 1e-6, "m/s"},
        {"SPFD_VZ", 192, 32, true, 1e-6, "m/s"}, {"SPFD_State", 224, 8},
        {"SPFD_Flags", 232, 8}, {"SPFD_Track", 240, 16}},
    STATUS = {{"ST_State", 0, 3}, {"ST_Clamped", 3, 1}, {"ST_BusDown", 4, 1}, {"ST_TxDrop", 5, 1},
        {"ST_OutFault", 6, 1}, {"ST_SafetyFault", 7, 1}, {"ST_LastSeq", 8, 8},
        {"ST_Free", 16, 8}, {"ST_Lost", 24, 8}, {"ST_Rejected", 32, 8},
        {"ST_Malformed", 40, 8}, {"ST_Dropped", 48, 8}, {"ST_LastErr", 56, 8}},
    STATUS2 = {mux = "ST2_Page", {"ST2_Page", 0, 8},
        {"ST2_OutLost", 8, 24, false, 1, "", 1}, {"ST2_OutErrors", 32, 16, false, 1, "", 1},
        {"ST2_CmdRefused", 48, 16, false, 1, "", 1},
        {"ST2_RejBackwards", 8, 8, false, 1, "", 2}, {"ST2_RejSameTime", 16, 8, false, 1, "", 2},
        {"ST2_RejSpeed", 24, 8, false, 1, "", 2}, {"ST2_RejAccel", 32, 8, false, 1, "", 2},
        {"ST2_RejUnconfirmed", 40, 8, false, 1, "", 2}, {"ST2_RejStale", 48, 8, false, 1, "", 2},
        {"ST2_RejOther", 56, 8, false, 1, "", 2},
        {"ST2_Age", 8, 24, true, 1e-3, "s", 3}, {"ST2_Drift", 32, 16, true, 0.1, "ppm", 3},
        {"ST2_Clocked", 48, 8, false, 1, "", 3},
        {"ST2_StateX", 8, 4, false, 1, "", 4}, {"ST2_StateY", 12, 4, false, 1, "", 4},
        {"ST2_StateZ", 16, 4, false, 1, "", 4}, {"ST2_HbLost", 22, 1, false, 1, "", 4},
        {"ST2_Held", 23, 1, false, 1, "", 4}, {"ST2_Statusword", 24, 16, false, 1, "", 4},
        {"ST2_Nmt", 40, 8, false, 1, "", 4}, {"ST2_Emcy", 48, 16, false, 1, "", 4},
        {"ST2_BusState", 8, 8, false, 1, "", 5}, {"ST2_TxErr", 16, 8, false, 1, "", 5},
        {"ST2_RxErr", 24, 8, false, 1, "", 5}, {"ST2_BusOffs", 32, 16, false, 1, "", 5},
        {"ST2_ErrFrames", 48, 16, false, 1, "", 5},
        {"ST2_TimeT", 8, 56, true, 1e-6, "s", 6},
        {"ST2_Underruns", 8, 16, false, 1, "", 7}, {"ST2_DelayGrown", 24, 8, false, 1, "", 7},
        {"ST2_TransfersMoving", 32, 8, false, 1, "", 7},
        {"ST2_ReserveSlowed", 40, 8, false, 1, "", 7},
        {"ST2_AxisBeyond", 48, 8, false, 1, "", 7}, {"ST2_AxisLagStops", 56, 8, false, 1, "", 7}},
}
-- Setpoint positions 0x80000000: no position yet (do not move).
local NO_POSITION = {SP_X_Pos = true, SP_Y_Pos = true, SP_Z_Pos = true, SPFD_X = true,
                     SPFD_Y = true, SPFD_Z = true}
-- STATUS2 page 3: the field's minimum means no value (data age of a
-- relative-time track or before any position; no drift estimate).
local NOT_AVAILABLE = {ST2_Age = -2 ^ 23, ST2_Drift = -2 ^ 15}

local f_frame = ProtoField.string("trajd.frame", "Frame")
local f_obj = ProtoField.uint8("trajd.obj", "Object")
local f_nopos = ProtoField.bool("trajd.no_position", "No position yet (do not move)")
local f_na = ProtoField.string("trajd.not_available", "Not available")
local fields = {f_frame, f_obj, f_nopos, f_na}
local F = {}
for _, m in pairs(MSG) do
    for _, s in ipairs(m) do
        local name, factor, unit = s[1], s[5] or 1, s[6] or ""
        local label = name .. (unit ~= "" and (" [" .. unit .. "]") or "")
        if factor ~= 1 then
            F[name] = ProtoField.double("trajd." .. name, label)
        elseif s[4] then
            F[name] = ProtoField.int32("trajd." .. name, label)
        else
            F[name] = ProtoField.uint32("trajd." .. name, label, base.DEC, VALS[name])
        end
        fields[#fields + 1] = F[name]
    end
end
p.fields = fields

-- Raw value of a little-endian signal (exact: at most 48 bits in a double).
local function raw(bytes, start, len, signed)
    local v = 0
    for i = len - 1, 0, -1 do
        local bit = start + i
        local b = bytes[math.floor(bit / 8)] or 0
        v = v * 2 + math.floor(b / 2 ^ (bit % 8)) % 2
    end
    if signed and v >= 2 ^ (len - 1) then v = v - 2 ^ len end
    return v
end

local function decode(kind, obj, tvb, pinfo, tree)
    local m = MSG[kind]
    local n = tvb:len()
    local bytes = {}
    for i = 0, n - 1 do bytes[i] = tvb(i, 1):uint() end
    local t = tree:add(p, tvb(), string.format("trajd %s, object %d", kind, obj))
    t:add(f_frame, kind)
    t:add(f_obj, obj)
    local muxv = m.mux and raw(bytes, 0, m.mux == "SP_Axis" and 2 or 8, false)
    local info, na = {}, {}
    for _, s in ipairs(m) do
        local name, start, len, signed, factor = s[1], s[2], s[3], s[4], s[5] or 1
        if (s[7] == nil or s[7] == muxv) and (start + len) <= 8 * n then
            local v = raw(bytes, start, len, signed)
            local range = tvb(math.floor(start / 8), math.ceil((start % 8 + len) / 8))
            if NO_POSITION[name] and v == -2 ^ 31 then
                t:add(f_nopos, range, true)
            elseif NOT_AVAILABLE[name] == v then
                na[#na + 1] = name
                info[#info + 1] = name .. "=n/a"
            elseif factor ~= 1 then
                t:add(F[name], range, v * factor)
                info[#info + 1] = string.format("%s=%.6g", name, v * factor)
            else
                t:add(F[name], range, v)
                if VALS[name] and VALS[name][v] then
                    info[#info + 1] = name .. "=" .. VALS[name][v]
                end
            end
        end
    end
    if #na > 0 then t:add(f_na, table.concat(na, ",")) end
    pinfo.cols.protocol = "trajd"
    pinfo.cols.info = string.format("%s obj %d %s", kind, obj, table.concat(info, " "))
end

local can_id = Field.new("can.id")

function p.dissector(tvb, pinfo, tree)
    local id = can_id()
    if not id then return 0 end
    id = id.value
    for kind, b in pairs(BASE) do
        if id >= b and id < b + OBJECTS then
            decode(kind, id - b, tvb, pinfo, tree)
            return tvb:len()
        end
    end
    return 0
end

local ids = DissectorTable.get("can.id")
for _, b in pairs(BASE) do
    for obj = 0, OBJECTS - 1 do ids:add(b + obj, p) end
end
