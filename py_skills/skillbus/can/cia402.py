"""CiA 402 (drive profile) words and states, shared by the driver and the simulated device."""

from __future__ import annotations

# Controlword commands (profile position mode).
CW_SHUTDOWN = 0x0006
CW_SWITCH_ON = 0x0007
CW_ENABLE_OPERATION = 0x000F
CW_NEW_SET_POINT = 0x0010   # bit 4: a rising edge starts a move to the target position
CW_FAULT_RESET = 0x0080     # bit 7: a rising edge resets a fault
CW_HALT = 0x0100            # bit 8

# Statusword bits.
SW_READY_TO_SWITCH_ON = 0x0001
SW_SWITCHED_ON = 0x0002
SW_OPERATION_ENABLED = 0x0004
SW_FAULT = 0x0008
SW_VOLTAGE_ENABLED = 0x0010
SW_QUICK_STOP = 0x0020      # active low: 1 = no quick stop
SW_SWITCH_ON_DISABLED = 0x0040
SW_REMOTE = 0x0200
SW_TARGET_REACHED = 0x0400
SW_SET_POINT_ACK = 0x1000

# States, with the statusword pattern each shows (bits 0-3, 5, 6).
SWITCH_ON_DISABLED = "switch on disabled"
READY_TO_SWITCH_ON = "ready to switch on"
SWITCHED_ON = "switched on"
OPERATION_ENABLED = "operation enabled"
FAULT = "fault"

STATE_WORDS = {
    SWITCH_ON_DISABLED: SW_SWITCH_ON_DISABLED,
    READY_TO_SWITCH_ON: SW_QUICK_STOP | SW_READY_TO_SWITCH_ON,
    SWITCHED_ON: SW_QUICK_STOP | SW_READY_TO_SWITCH_ON | SW_SWITCHED_ON,
    OPERATION_ENABLED: SW_QUICK_STOP | SW_READY_TO_SWITCH_ON | SW_SWITCHED_ON | SW_OPERATION_ENABLED | SW_VOLTAGE_ENABLED,
    FAULT: SW_FAULT,
}


def state_of(statusword: int) -> str:
    """The CiA 402 state a statusword shows (masks as in CiA 402, table 30)."""
    if statusword & 0x004F == SW_SWITCH_ON_DISABLED:
        return SWITCH_ON_DISABLED
    if statusword & 0x004F == SW_FAULT:
        return FAULT
    low = statusword & 0x006F
    if low == 0x0021:
        return READY_TO_SWITCH_ON
    if low == 0x0023:
        return SWITCHED_ON
    if low == 0x0027:
        return OPERATION_ENABLED
    return "not ready"


# Grip state (manufacturer object 0x2000) bits.
GRIP_MOVING = 0x01
GRIP_REACHED = 0x02
GRIP_GRIPPED = 0x04
GRIP_LOST = 0x08

# EMCY codes the device raises (CiA 301/402).
EMCY_OVER_CURRENT = 0x2310     # blocked for too long above the rated force
EMCY_FOLLOWING_ERROR = 0x8611
EMCY_TEXT = {EMCY_OVER_CURRENT: "over-current (blocked too long)", EMCY_FOLLOWING_ERROR: "following error"}

# CiA 301 NMT state codes as sent in a heartbeat, by canopen's state names.
NMT_STATE_CODES = {"INITIALISING": 0x00, "STOPPED": 0x04, "OPERATIONAL": 0x05, "PRE-OPERATIONAL": 0x7F}
