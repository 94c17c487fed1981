"""A python-can client of the virtual SocketCAN hub, for test_vcan.py.
Usage: can_peer.py CHANNEL MY_ID PEER_ID N   sends N frames with id MY_ID (payload: the
sequence number) and receives N from PEER_ID; prints JSON (received in order?, own seen).
A bus keeps nothing for a client not yet connected, so the peers first see each other:
each sends empty "ready" frames until it has seen one from the other, then one more."""

import json
import struct
import sys
import threading
import time

import can


def main() -> int:
    channel, me, peer, n = sys.argv[1], int(sys.argv[2], 16), int(sys.argv[3], 16), int(sys.argv[4])
    bus = can.Bus(interface="skillbus_vcan", channel=channel)
    got, own = [], 0
    done = threading.Event()

    def receive():
        nonlocal own
        while len(got) < n:
            m = bus.recv(timeout=30)
            if m is None:
                break
            if m.dlc == 0:
                continue  # a handshake frame
            if m.arbitration_id == me:
                own += 1
            elif m.arbitration_id == peer:
                got.append(struct.unpack("<I", m.data[:4])[0])
        done.set()

    # Handshake (empty frames); the receiver below ignores empty frames.
    seen_peer = False
    while not seen_peer:
        bus.send(can.Message(arbitration_id=me, data=b"", is_extended_id=False), timeout=5)
        deadline = time.monotonic() + 0.02
        while (left := deadline - time.monotonic()) > 0:
            m = bus.recv(timeout=left)
            if m is not None and m.arbitration_id == peer and m.dlc == 0:
                seen_peer = True
                break
    bus.send(can.Message(arbitration_id=me, data=b"", is_extended_id=False), timeout=5)
    t = threading.Thread(target=receive)
    t.start()
    for i in range(n):
        bus.send(can.Message(arbitration_id=me, data=struct.pack("<I", i) + b"\xaa\xbb\xcc\xdd", is_extended_id=False),
                 timeout=30)
    done.wait(60)
    t.join(5)
    print(json.dumps({"received": len(got), "in_order": got == list(range(len(got))), "own": own}), flush=True)
    bus.shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
