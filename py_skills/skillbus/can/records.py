"""python-can messages <-> raw SocketCAN records (the kernel's struct layouts), using
python-can's own builders so that the bytes are exactly what a SocketCAN socket carries."""

from __future__ import annotations

import can
from can.interfaces.socketcan.constants import CAN_EFF_FLAG, CAN_ERR_FLAG, CAN_RTR_FLAG, CANFD_BRS, CANFD_ESI
from can.interfaces.socketcan.socketcan import build_can_frame, dissect_can_frame

CAN_MTU = 16      # sizeof(struct can_frame)
CANFD_MTU = 72    # sizeof(struct canfd_frame)
CAN_SFF_MASK = 0x7FF           # linux/can.h
CAN_EFF_MASK = 0x1FFFFFFF


def to_record(msg: can.Message) -> bytes:
    return build_can_frame(msg)


def check_record(record: bytes) -> None:
    """Raises ValueError unless `record` is a can_frame or canfd_frame whose length byte
    fits its data field (8 bytes, 64 for CAN FD): a longer claim would have receivers read
    padding as data."""
    if len(record) not in (CAN_MTU, CANFD_MTU):
        raise ValueError(f"a SocketCAN record is {CAN_MTU} or {CANFD_MTU} bytes, not {len(record)}")
    fd, length = len(record) == CANFD_MTU, record[4]  # can_dlc / len: the byte after can_id
    if length > (64 if fd else 8):
        raise ValueError(f"a {'CAN FD' if fd else 'CAN'} record with {length} data bytes")


def from_record(record: bytes, timestamp: float = 0.0, channel: str | None = None) -> can.Message:
    """Raises ValueError on a record that is not a can_frame or canfd_frame."""
    check_record(record)
    can_id, length, flags, data = dissect_can_frame(record)
    fd = len(record) == CANFD_MTU
    ext = bool(can_id & CAN_EFF_FLAG)
    return can.Message(
        timestamp=timestamp,
        arbitration_id=can_id & (CAN_EFF_MASK if ext else CAN_SFF_MASK),
        is_extended_id=ext,
        is_remote_frame=bool(can_id & CAN_RTR_FLAG),
        is_error_frame=bool(can_id & CAN_ERR_FLAG),
        is_fd=fd,
        bitrate_switch=fd and bool(flags & CANFD_BRS),
        error_state_indicator=fd and bool(flags & CANFD_ESI),
        dlc=length,
        data=data[:length],
        channel=channel,
    )
