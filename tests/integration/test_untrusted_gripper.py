"""Untrusted input to the real gripper device process (docs/transport.md, "Untrusted
input"): physics states forged by another process on the bus, with a finger width that is
infinite, NaN or far outside the travel and a force that is NaN, are counted and not acted
on; the device keeps running, logs each kind once (the value escaped), counts them (its
summary at Ctrl-C) and still answers CANopen: PDOs, SDO, heartbeat. (It used to die at the first infinite width: OverflowError
turning it into micrometres.)"""

from __future__ import annotations

import re
import signal
import sys
import time

import canopen

from conftest import last_json, python_tool
from skillbus.can import cia402
from skillbus.can.driver import GripperDriver
from skillbus.waiting import poll_until
from test_gripper_can import wait_status
from test_gripper_recovery import start_hub

FORGED = {"finger_width": ["inf", "-inf", "nan", "1e300", "-0.5"], "finger_force": ["nan", "1e9"]}
EACH = 5  # states of each forged value


def test_forged_physics_states_are_counted_and_the_device_still_answers_canopen(sandbox, tmp_path):
    path = tmp_path / "grip.sock"
    start_hub(sandbox, path)
    device = sandbox.start("device", [sys.executable, "-m", "skillbus.cli", "gripper-device", "--channel", path,
                                      "--node-id", "5", "--physics", "--name", "gripper"])
    device.wait_for('"physics": true', 30, stream="stdout")  # subscribed to SB_SIM_STATE, booted
    net = canopen.Network()
    net.connect(interface="skillbus_vcan", channel=str(path))
    driver = GripperDriver(net, 5)
    try:
        driver.start(timeout=10)
        good = sandbox.start("good", python_tool("sim_state_forger.py", "finger_width=0.04:1"),
                             env={"SKILLBUS_IDENTITY": "sim"})
        assert sandbox.wait(good, 30) == 0, good.stderr()
        wait_status(driver, lambda s: s.position_um == 40_000)  # the device uses a sane state

        args = [f"{field}={v}:{EACH}" for field, values in FORGED.items() for v in values]
        # A holder of the bus key may claim any identity: this one claims the physics
        # server's, so the bus hands its states on and only the device's checks stand.
        forger = sandbox.start("forger", python_tool("sim_state_forger.py", *args), env={"SKILLBUS_IDENTITY": "sim"})
        assert sandbox.wait(forger, 60) == 0, forger.stderr()
        expected = {f"SB_SIM_STATE: {field}": EACH * len(values) for field, values in FORGED.items()}
        poll_until(lambda: all(f"rejected SB_SIM_STATE: {f}=" in device.stderr() for f in FORGED) or
                   device.returncode is not None, 10, interval=0.05)
        time.sleep(0.3)  # the rest of the burst
        assert device.returncode is None, f"the device died:\n{device.stderr()[-3000:]}"

        # Logged once per kind, the first value as repr; nothing else went wrong.
        err = device.stderr()
        assert len(re.findall(r"rejected SB_SIM_STATE: finger_width=", err)) == 1, err[-3000:]
        assert "rejected SB_SIM_STATE: finger_width=inf: not a finite number -- dropped" in err
        assert len(re.findall(r"rejected SB_SIM_STATE: finger_force=", err)) == 1
        assert "rejected SB_SIM_STATE: finger_force=nan: not a finite number" in err
        assert "Traceback" not in err

        # Still a CANopen device: the fingers as the last sane state had them, TPDOs,
        # heartbeat and SDO answered, and a set-point taken.
        updates = driver.status().updates
        s = wait_status(driver, lambda s: s.updates > updates + 5)
        assert (s.state, s.position_um, s.faults) == (cia402.OPERATION_ENABLED, 40_000, [])
        assert driver.node.sdo[0x6064].raw == 40_000
        assert driver.node.sdo[0x1017].raw == 100
        driver.command(30_000)
        wait_status(driver, lambda s: s.fresh and s.statusword & cia402.SW_SET_POINT_ACK)
        assert driver.malformed == 0
    finally:
        driver.close()
        net.disconnect()

    sandbox.kill(device, signal.SIGINT)  # it ends, printing what it counted
    assert sandbox.wait(device, 10) == 0, device.stderr()[-3000:]
    summary = last_json(device.stdout())
    assert summary["rejected"] == expected, summary
    assert summary["bad_input"] == sum(expected.values()) and summary["rpdo_errors"] == 0
