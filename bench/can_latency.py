"""Benchmark of the gripper's CAN path over the user-space virtual SocketCAN bus.

(a) Raw frame ping-pong: one 8-byte frame to an echo process and back, python-can on
    both ends (bench/can_echo.py): the floor any CANopen exchange on this bus pays.
(b) Set-point to status: GripperDriver.command() (two RPDOs) until the driver holds the
    simulated device's TPDO1 that shows the move started (the device answers a set-point
    with an event-driven TPDO at once; canopen decodes both ends).
Both in the same run, medians and 99th percentiles, and their ratio.

Run: .venv/bin/python bench/can_latency.py   (in `make bench`)
"""

from __future__ import annotations

import json
import select
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import can
import canopen

from skillbus.can import cia402 as c
from skillbus.can.driver import GripperDriver

HERE = Path(__file__).resolve().parent
N_RAW, N_SETPOINT = 3000, 400


def pct(xs: list[float], q: float) -> float:
    xs = sorted(xs)
    return xs[min(len(xs) - 1, int(q * len(xs)))]


def start(argv: list[str]) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, *argv], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)


def raw_pingpong(sock: str) -> list[float]:
    echo = start([str(HERE / "can_echo.py"), "skillbus_vcan", sock])
    ready = select.select([echo.stdout], [], [], 10.0)[0]
    if not ready or echo.stdout.readline().strip() != "ready":
        echo.kill()
        raise RuntimeError("the echo process did not start within 10 s")
    bus = can.Bus(interface="skillbus_vcan", channel=sock)
    out = []
    try:
        for i in range(N_RAW + 200):
            t0 = time.perf_counter()
            bus.send(can.Message(arbitration_id=0x100, data=i.to_bytes(8, "little"), is_extended_id=False))
            while True:
                m = bus.recv(2.0)
                if m is None:
                    raise RuntimeError(f"round trip {i}: no echo within 2 s")
                if m.arbitration_id == 0x101:
                    break
            if i >= 200:  # warm-up
                out.append((time.perf_counter() - t0) * 1e6)
        bus.send(can.Message(arbitration_id=0x7FF, data=b"", is_extended_id=False))
    finally:
        bus.shutdown()
        echo.wait(5)
    return out


def setpoint_to_status(sock: str) -> list[float]:
    dev = start(["-m", "skillbus.cli", "gripper-device", "--channel", sock, "--node-id", "5"])
    net = canopen.Network()
    net.connect(interface="skillbus_vcan", channel=sock)
    out = []
    try:
        driver = GripperDriver(net, 5, velocity_um_s=200_000)
        driver.start(timeout=10)
        seen = threading.Event()
        stamp = [0.0]

        def on_tpdo(m) -> None:
            if m["Grip state"].raw & c.GRIP_MOVING and not seen.is_set():
                stamp[0] = time.perf_counter()
                seen.set()

        driver.node.tpdo[1].add_callback(on_tpdo)
        for i in range(N_SETPOINT + 20):
            target = 79_000 if i % 2 == 0 else 80_000
            seen.clear()
            t0 = time.perf_counter()
            driver.command(target)
            if not seen.wait(2.0):
                raise RuntimeError(f"set-point {i}: no moving status within 2 s")
            if i >= 20:
                out.append((stamp[0] - t0) * 1e6)
            deadline = time.monotonic() + 2.0
            while not (driver.status().position_um == target and driver.status().target_reached):
                if time.monotonic() > deadline:
                    raise RuntimeError(f"set-point {i}: never reached {target}")
                time.sleep(0.001)
    finally:
        net.disconnect()
        dev.terminate()
        dev.wait(5)
    return out


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        sock = str(Path(tmp) / "bench.sock")
        hub = start(["-m", "skillbus.cli", "can-hub", "--channel", sock])
        try:
            deadline = time.monotonic() + 10
            while not Path(sock).exists():
                if time.monotonic() > deadline:
                    raise RuntimeError("the hub did not start")
                time.sleep(0.02)
            raw = raw_pingpong(sock)
            sp = setpoint_to_status(sock)
        finally:
            hub.terminate()
            hub.wait(5)
    r = {"raw_rtt_median_us": statistics.median(raw), "raw_rtt_p99_us": pct(raw, 0.99),
         "setpoint_median_us": statistics.median(sp), "setpoint_p99_us": pct(sp, 0.99)}
    r["ratio_median"] = r["setpoint_median_us"] / r["raw_rtt_median_us"]
    print(f"raw frame ping-pong (virtual bus): median {r['raw_rtt_median_us']:.0f} µs, "
          f"p99 {r['raw_rtt_p99_us']:.0f} µs ({N_RAW} round trips)")
    print(f"set-point to status (driver -> device -> driver): median {r['setpoint_median_us']:.0f} µs, "
          f"p99 {r['setpoint_p99_us']:.0f} µs ({N_SETPOINT} set-points); {r['ratio_median']:.2f}x the raw round trip")
    print(json.dumps({"can_latency": r}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
