"""Raw round trip between two Python processes (the peer of the lockstep benchmark).
  pingpong.py VIA pong             echo every SB_BENCH_PING back on SB_BENCH_PONG, until killed
  pingpong.py VIA ping N SIZE      time N round trips of SIZE-byte messages; print JSON

VIA is `lcm`: the LCM library as a user of LCM has it (lcm.LCM: publish, subscribe,
handle_timeout; LCM receives on a thread of its own), or `bus`: skillbus's bus without a
key, on the bus $SKILLBUS_BUS_URL names (udpm://: LCM publishes, the datagram is read on
the dispatching thread; dds://: Cyclone DDS; docs/transport.md)."""

import json
import sys
import time

import lcm

from skillbus.bus import check_multicast_interface, open_bus, receive_buffer_url, resolve_url


class RawLcm:
    def __init__(self) -> None:
        check_multicast_interface(resolve_url())  # (as open_bus: on this host only)
        self.lc = lcm.LCM(receive_buffer_url(resolve_url()))

    def publish(self, ch: str, data: bytes) -> None:
        self.lc.publish(ch, data)

    def subscribe(self, ch: str, handler) -> None:
        self.lc.subscribe(ch, handler).set_queue_capacity(10000)

    def handle(self, timeout: float) -> bool:
        return self.lc.handle_timeout(int(timeout * 1000)) > 0


def main() -> int:
    via, mode = sys.argv[1], sys.argv[2]
    bus = RawLcm() if via == "lcm" else open_bus()
    if mode == "pong":
        bus.subscribe("SB_BENCH_PING", lambda ch, data: bus.publish("SB_BENCH_PONG", data))
        while True:
            bus.handle(1.0)
    n, size = int(sys.argv[3]), int(sys.argv[4])
    got = []
    bus.subscribe("SB_BENCH_PONG", lambda ch, data: got.append(data))
    payload = bytes(size)
    # Wait for the echo to be there before timing.
    deadline = time.monotonic() + 10
    while not got and time.monotonic() < deadline:
        bus.publish("SB_BENCH_PING", payload)
        bus.handle(0.1)
    if not got:
        print(json.dumps({"error": "no pong within 10 s"}))
        return 1
    while bus.handle(0.05):
        pass
    samples = []
    for _ in range(n):
        got.clear()
        t0 = time.perf_counter()
        bus.publish("SB_BENCH_PING", payload)
        while not got:
            bus.handle(1.0)
        samples.append(time.perf_counter() - t0)
    samples.sort()
    print(json.dumps({"round_trips": n, "mean_us": 1e6 * sum(samples) / n,
                      "median_us": 1e6 * samples[n // 2], "p99_us": 1e6 * samples[int(n * 0.99)]}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
