"""The CANopen gripper driver against the simulated device, over the virtual SocketCAN bus."""

import sys
import time

import can
import canopen
import pytest

from skillbus.can import cia402
from skillbus.can.driver import GripperDriver


@pytest.fixture
def rig(sandbox, tmp_path):
    """hub + device (+ object if asked) + a connected driver; returns a factory."""
    path = tmp_path / "grip.sock"
    sandbox.start("can-hub", [sys.executable, "-m", "skillbus.cli", "can-hub", "--channel", path])
    deadline = time.monotonic() + 10
    while not path.exists():
        assert time.monotonic() < deadline
        time.sleep(0.02)
    networks = []

    def make(object_width=None, force_limit=200):
        args = [sys.executable, "-m", "skillbus.cli", "gripper-device", "--channel", path, "--node-id", "5"]
        if object_width is not None:
            args += ["--object-width", str(object_width)]
        device = sandbox.start("device", args)
        net = canopen.Network()
        net.connect(interface="skillbus_vcan", channel=str(path))
        networks.append(net)
        driver = GripperDriver(net, 5, force_limit=force_limit)
        driver.start(timeout=10)
        return driver, device, net

    yield make
    for n in networks:
        n.disconnect()


def wait_until(driver, pred, timeout=5.0):
    deadline = time.monotonic() + timeout
    while not pred(driver.status()):
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out; status {driver.status()}")
        time.sleep(0.01)
    return driver.status()


def test_boot_heartbeat_enable_open_close_move_stop(rig):
    driver, _, _ = rig()
    s = driver.status()
    assert s.state == cia402.OPERATION_ENABLED and s.position_um == 80000 and s.updates > 0
    driver.command(80000)  # open (already open: reached at once)
    wait_until(driver, lambda s: s.target_reached and s.position_um == 80000)
    driver.command(0)  # close on nothing
    s = wait_until(driver, lambda s: s.target_reached and s.position_um == 0)
    assert not s.gripped
    driver.command(60000)  # move to a width
    s = wait_until(driver, lambda s: s.target_reached and s.position_um == 60000)
    driver.command(0)
    wait_until(driver, lambda s: s.moving and s.position_um < 50000)
    driver.stop()  # halt mid-move
    s = wait_until(driver, lambda s: not s.moving)
    time.sleep(0.2)
    assert 0 < driver.status().position_um == s.position_um < 60000


def test_close_on_an_object_grips_it(rig):
    driver, _, _ = rig(object_width=40000)
    driver.command(0)
    s = wait_until(driver, lambda s: s.gripped)
    assert s.position_um == 40000 and not s.faults
    time.sleep(1.2)  # held with the rated force: no fault
    assert driver.status().state == cia402.OPERATION_ENABLED and not driver.status().faults


def test_heartbeat_loss_is_a_fault_within_three_periods(rig, sandbox):
    driver, device, _ = rig()
    sandbox.kill(device)
    killed = time.monotonic()
    while not any(f.startswith("device lost") for f in driver.status().faults):
        driver.poll()
        assert time.monotonic() - killed < 3 * 0.1 + 0.25  # 3 periods (+ the period in flight)
        time.sleep(0.01)


def test_emcy_on_a_blocked_move_then_fault_reset(rig):
    driver, _, _ = rig(object_width=40000, force_limit=500)  # above the rated 40 N
    driver.command(0)
    s = wait_until(driver, lambda s: s.state == cia402.FAULT, timeout=5)
    assert any("EMCY 0x2310: over-current" in f for f in s.faults), s.faults
    driver.fault_reset()
    wait_until(driver, lambda s: s.state == cia402.SWITCH_ON_DISABLED)
    assert not driver.status().faults
    driver.enable()
    driver.command(80000)
    wait_until(driver, lambda s: s.position_um == 80000 and s.target_reached)


def test_malformed_frames_are_ignored_and_counted_by_both_sides(rig, sandbox):
    driver, device, net = rig()
    rogue = can.Bus(interface="skillbus_vcan", channel=net.bus.channel)  # a third node on the bus
    rogue.send(can.Message(arbitration_id=0x205, data=b"\x0f\x00\x01", is_extended_id=False))   # short RPDO
    rogue.send(can.Message(arbitration_id=0x185, data=b"\x27\x06\x00", is_extended_id=False))   # short TPDO
    rogue.send(can.Message(arbitration_id=0x7AB, data=b"\x01", is_extended_id=False))           # unknown COB-ID
    rogue.shutdown()
    with pytest.raises(canopen.SdoAbortedError) as e:
        driver.node.sdo.upload(0x1234, 0)  # an object the device does not have
    assert e.value.code == 0x06020000  # "object does not exist"
    time.sleep(0.2)
    assert driver.malformed == 1
    assert "RPDO1 of 3 bytes (6 expected) ignored" in device.stderr()
    driver.command(30000)  # and both still work
    wait_until(driver, lambda s: s.position_um == 30000 and s.target_reached)
