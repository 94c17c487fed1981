"""The CANopen gripper driver against the simulated device, over the virtual SocketCAN bus."""

import re
import signal
import sys
import time

import can
import canopen
import pytest

from skillbus.can import cia402
from skillbus.can.driver import GripperDriver
from skillbus.waiting import poll_until, wait_until


def start_hub(sandbox, path):
    """A virtual CAN hub on `path`, once its socket exists."""
    hub = sandbox.start("can-hub", [sys.executable, "-m", "skillbus.cli", "can-hub", "--channel", path])
    wait_until(path.exists, 10, f"the CAN hub's socket {path}", interval=0.02, diagnostic=lambda: hub.stderr()[-2000:])
    return path


def kernel_vcan0() -> str:
    """'' when the kernel's vcan0 is usable (created here if missing), else why not."""
    import socket
    import subprocess
    try:
        socket.socket(socket.AF_CAN, socket.SOCK_RAW, socket.CAN_RAW).close()
    except (OSError, AttributeError) as e:
        return f"this kernel has no SocketCAN (AF_CAN socket: {e})"
    if subprocess.run(["ip", "link", "show", "vcan0"], capture_output=True).returncode != 0:
        made = subprocess.run(["ip", "link", "add", "dev", "vcan0", "type", "vcan"], capture_output=True, text=True)
        if made.returncode != 0:
            return f"cannot create vcan0: {made.stderr.strip()}"
    up = subprocess.run(["ip", "link", "set", "up", "vcan0"], capture_output=True, text=True)
    return "" if up.returncode == 0 else f"cannot bring vcan0 up: {up.stderr.strip()}"


@pytest.fixture(params=["virtual", pytest.param("kernel", marks=pytest.mark.allow_skip)])
def rig(request, sandbox, tmp_path):
    """hub + device (+ object if asked) + a connected driver; returns a factory. Runs on the
    user-space virtual bus, and on the kernel's vcan0 through python-can's socketcan
    where the kernel provides it (skipped with the reason where it does not: a property
    of the machine, so the skip is allowed without SKILLBUS_ALLOW_SKIP)."""
    if request.param == "kernel":
        why = kernel_vcan0()
        if why:
            print(f"kernel vcan0 variant skipped: {why}")
            pytest.skip(why)
        interface, channel, host = "socketcan", "vcan0", True
    else:
        path = start_hub(sandbox, tmp_path / "grip.sock")
        interface, channel, host = "skillbus_vcan", str(path), False
    networks, drivers = [], []

    def make(object_width=None, force_limit=200):
        args = [sys.executable, "-m", "skillbus.cli", "gripper-device", "--channel", channel, "--node-id", "5",
                "--interface", interface]
        if object_width is not None:
            args += ["--object-width", str(object_width)]
        device = sandbox.start("device", args, host_network=host)
        net = canopen.Network()
        net.connect(interface=interface, channel=channel)
        networks.append(net)
        driver = GripperDriver(net, 5, force_limit=force_limit)
        driver.start(timeout=10)
        drivers.append(driver)
        return driver, device, net

    make.interface = interface
    yield make
    for d in drivers:
        d.close()
    for n in networks:
        n.disconnect()


def wait_status(driver, pred, timeout=5.0):
    """The driver's status, once `pred(status)` holds."""
    return wait_until(lambda: pred(s := driver.status()) and s, timeout, "a status of the gripper", interval=0.01,
                      diagnostic=lambda: f"its status: {driver.status()}")


def test_boot_heartbeat_enable_open_close_move_stop(rig):
    driver, _, _ = rig()
    s = driver.status()
    assert s.state == cia402.OPERATION_ENABLED and s.position_um == 80000 and s.updates > 0
    driver.command(80000)  # open (already open: reached at once)
    wait_status(driver, lambda s: s.target_reached and s.position_um == 80000)
    driver.command(0)  # close on nothing
    s = wait_status(driver, lambda s: s.target_reached and s.position_um == 0)
    assert not s.gripped
    driver.command(60000)  # move to a width
    s = wait_status(driver, lambda s: s.target_reached and s.position_um == 60000)
    # A slow close (5 mm/s: 12 s in all), so that the stop lands mid-move on a loaded machine too.
    driver.node.sdo[0x6081].raw = 5_000  # profile velocity
    driver.command(0)
    wait_status(driver, lambda s: s.moving and s.position_um < 58000)
    driver.stop()  # halt mid-move
    s = wait_status(driver, lambda s: not s.moving)
    time.sleep(0.2)
    assert 0 < driver.status().position_um == s.position_um < 60000


def test_close_on_an_object_grips_it(rig):
    driver, _, _ = rig(object_width=40000)
    driver.command(0)
    s = wait_status(driver, lambda s: s.gripped)
    assert s.position_um == 40000 and not s.faults
    time.sleep(1.2)  # held with the rated force: no fault
    assert driver.status().state == cia402.OPERATION_ENABLED and not driver.status().faults


def test_heartbeat_loss_is_a_fault_after_three_periods(rig, sandbox):
    driver, device, _ = rig()
    sandbox.kill(device)

    def lost() -> str | None:  # the driver's own supervision names it: nobody calls poll()
        return next((f for f in driver.status().faults if f.startswith("gripper node 5: heartbeat lost at ")), None)

    # (the three periods exactly, on a clock of the test's: tests/py/test_device_heartbeat.py;
    # here, processes on a loaded machine: named, by the driver's thread, not early)
    fault = wait_until(lost, 10, "the fault 'heartbeat lost'", interval=0.01,
                       diagnostic=lambda: f"its status: {driver.status()}")
    assert int(re.search(r"\(none for (\d+) ms\)", fault).group(1)) >= 3 * 100, fault


def test_emcy_on_a_blocked_move_then_fault_reset(rig):
    driver, _, _ = rig(object_width=40000, force_limit=500)  # above the rated 40 N
    driver.command(0)
    s = wait_status(driver, lambda s: s.state == cia402.FAULT, timeout=5)
    assert any("EMCY 0x2310: over-current" in f for f in s.faults), s.faults
    driver.fault_reset()
    wait_status(driver, lambda s: s.state == cia402.SWITCH_ON_DISABLED)
    assert not driver.status().faults
    driver.enable()
    driver.command(80000)
    wait_status(driver, lambda s: s.position_um == 80000 and s.target_reached)


def test_malformed_frames_are_ignored_and_counted_by_both_sides(rig, sandbox):
    driver, device, net = rig()
    rogue = can.Bus(interface=rig.interface, channel=net.bus.channel)  # a third node on the bus
    rogue.send(can.Message(arbitration_id=0x205, data=b"\x0f\x00\x01", is_extended_id=False))   # short RPDO
    rogue.send(can.Message(arbitration_id=0x185, data=b"\x27\x06\x00", is_extended_id=False))   # short TPDO
    rogue.send(can.Message(arbitration_id=0x7AB, data=b"\x01", is_extended_id=False))           # unknown COB-ID
    rogue.shutdown()
    with pytest.raises(canopen.SdoAbortedError) as e:
        driver.node.sdo.upload(0x1234, 0)  # an object the device does not have
    assert e.value.code == 0x06020000  # "object does not exist"
    # both sides count what reached them
    poll_until(lambda: driver.malformed >= 1 and "RPDO1 of 3 bytes (6 expected) ignored" in device.stderr(), 5,
               interval=0.02)
    assert driver.malformed == 1
    assert "RPDO1 of 3 bytes (6 expected) ignored" in device.stderr()
    driver.command(30000)  # and both still work
    wait_status(driver, lambda s: s.position_um == 30000 and s.target_reached)


def test_the_bus_is_recorded_in_candump_format_and_decoded(sandbox, tmp_path):
    path = start_hub(sandbox, tmp_path / "grip.sock")
    log_file = tmp_path / "traffic.log"
    recorder = sandbox.start("recorder", [sys.executable, "-m", "skillbus.cli", "can-record", str(log_file),
                                          "--channel", str(path)])
    recorder.wait_for("recording", 30)  # the recorder is on the bus before the device boots
    sandbox.start("device", [sys.executable, "-m", "skillbus.cli", "gripper-device", "--channel", path,
                             "--node-id", "5", "--object-width", "40000"])
    net = canopen.Network()
    net.connect(interface="skillbus_vcan", channel=str(path))
    driver = GripperDriver(net, 5, force_limit=200)
    try:
        driver.start(timeout=10)
        driver.command(0)
        wait_status(driver, lambda s: s.gripped)
        with pytest.raises(canopen.sdo.exceptions.SdoAbortedError):
            driver.node.sdo.upload(0x5555, 0)  # a missing object: the device aborts
        net.send_message(0x123, b"\x01\x02")  # a COB-ID nobody owns
    finally:
        driver.close()
        net.disconnect()
    # (the recorder flushes every 0.1 s: the last frame sent is in the file, so all are)
    wait_until(lambda: "123#0102" in log_file.read_text(), 30, "frame 0x123 in the candump log")
    sandbox.kill(recorder, 2)  # SIGINT: the recorder closes its file
    assert sandbox.wait(recorder, 10) == 0
    raw = log_file.read_text().splitlines()
    assert raw and all(line.startswith("(") and " " in line and "#" in line for line in raw)  # candump -l
    out = sandbox.start("can-log", [sys.executable, "-m", "skillbus.cli", "can-log", str(log_file)])
    assert sandbox.wait(out, 30) == 0, out.stderr()
    text = out.stdout()
    for expected in ("boot-up", "heartbeat PRE-OPERATIONAL", "SDO request download 0x1017 Producer heartbeat time = 100",
                     "SDO answer download ok 0x1017", "SDO answer download ok 0x6073", "NMT start node 5",
                     "heartbeat OPERATIONAL", "RPDO1 Controlword=15, Target position=0",
                     "RPDO1 Controlword=31, Target position=0", "Grip state=6 [operation enabled]",
                     "SDO answer abort 0x5555sub0 (not in the EDS): code 0x06020000",
                     "unknown COB-ID 0x123 (2 bytes)"):
        assert expected in text, f"{expected!r} not in:\n{text[:3000]}"


def test_frames_that_reached_the_recorder_before_its_stop_are_recorded(sandbox, tmp_path):
    path = start_hub(sandbox, tmp_path / "grip.sock")
    log_file = tmp_path / "stop.log"
    recorder = sandbox.start("recorder", [sys.executable, "-m", "skillbus.cli", "can-record", str(log_file),
                                          "--channel", str(path)])
    recorder.wait_for("recording", 30)
    listener = can.Bus(interface="skillbus_vcan", channel=str(path))
    sender = can.Bus(interface="skillbus_vcan", channel=str(path))
    try:
        sandbox.kill(recorder, signal.SIGSTOP)  # (frames wait in its socket while it has no CPU)
        for i in range(20):
            sender.send(can.Message(arbitration_id=0x200 + i, data=bytes([i]), is_extended_id=False))
        got = []  # (the hub forwards in order: once the listener has the last, the recorder's socket has all)
        wait_until(lambda: (m := listener.recv(0.05)) is not None and got.append(m.arbitration_id) is None
                   and got[-1] == 0x213, 30, "the frames through the hub")
        sandbox.kill(recorder, signal.SIGTERM)  # (the stop comes first when it runs again)
        sandbox.kill(recorder, signal.SIGCONT)
        assert sandbox.wait(recorder, 10) == 0, recorder.stderr()
    finally:
        listener.shutdown()
        sender.shutdown()
    ids = [int(line.split()[2].split("#")[0], 16) for line in log_file.read_text().splitlines()]
    assert ids == [0x200 + i for i in range(20)]


def test_can_log_names_a_file_it_cannot_read(sandbox, tmp_path):
    out = sandbox.start("can-log", [sys.executable, "-m", "skillbus.cli", "can-log", str(tmp_path / "none.log")])
    assert sandbox.wait(out, 30) == 2
    assert "none.log" in out.stderr()


def test_can_record_names_what_it_cannot_record_before_it_says_it_records(sandbox, tmp_path):
    # Before, it said "recording" before it opened its file, and ended with a traceback.
    hub = start_hub(sandbox, tmp_path / "grip.sock")
    cases = [(tmp_path / "nohub.sock", tmp_path / "a.log", "CAN channel"),
             (hub, tmp_path / "no" / "b.log", "No such file"),
             (hub, tmp_path / "c.unknown", "unknown")]
    for channel, log, why in cases:
        p = sandbox.start(f"rec-{log.name}", [sys.executable, "-m", "skillbus.cli", "can-record", str(log),
                                              "--channel", str(channel)])
        assert sandbox.wait(p, 30) == 2, p.stderr()
        err = p.stderr()
        assert f"error: can-record {log}" in err and why.lower() in err.lower(), err
        assert "recording" not in err and "Traceback" not in err, err
