import can
import pytest

from skillbus.can.records import CAN_MTU, CANFD_MTU, from_record, to_record


def test_classic_and_fd_frames_round_trip_as_socketcan_records():
    for msg in (can.Message(arbitration_id=0x123, data=b"\\x01\\x02", is_extended_id=False),
                can.Message(arbitration_id=0x1ABCDE, data=bytes(8), is_extended_id=True),
                can.Message(arbitration_id=0x7FF, is_remote_frame=True, dlc=3, is_extended_id=False),
                can.Message(arbitration_id=0x10, data=bytes(range(48)), is_fd=True, bitrate_switch=True,
                            is_extended_id=False)):
        rec = to_record(msg)
        assert len(rec) == (CANFD_MTU if msg.is_fd else CAN_MTU)
        back = from_record(rec)
        assert (back.arbitration_id, back.is_extended_id, back.is_remote_frame, back.is_fd, back.dlc,
                bytes(back.data)) == (msg.arbitration_id, msg.is_extended_id, msg.is_remote_frame, msg.is_fd,
                                      msg.dlc, bytes(msg.data))


def test_records_of_other_sizes_or_lengths_are_refused():
    with pytest.raises(ValueError, match="16 or 72 bytes, not 11"):
        from_record(b"not a frame")
    bad = bytearray(to_record(can.Message(arbitration_id=1, data=b"", is_extended_id=False)))
    bad[4] = 9  # a classic frame claiming 9 data bytes
    with pytest.raises(ValueError, match=r"a CAN record with \d+ data bytes"):
        from_record(bytes(bad))
