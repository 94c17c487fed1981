"""Raw LCM round trip between two Python processes (the peer of the lockstep benchmark).
  pingpong.py pong             echo every SB_BENCH_PING back on SB_BENCH_PONG, until killed
  pingpong.py ping N SIZE      time N round trips of SIZE-byte messages; print JSON"""

import json
import sys
import time

from skillbus.bus import open_bus


def main() -> int:
    bus = open_bus()
    if sys.argv[1] == "pong":
        bus.subscribe("SB_BENCH_PING", lambda ch, data: bus.publish("SB_BENCH_PONG", data))
        while True:
            bus.handle(1.0)
    n, size = int(sys.argv[2]), int(sys.argv[3])
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
