"""On the wall clock a skill names an arm driver that went silent (test_named_faults). A
process that was itself not running (a loaded machine, a long handler) must not call a
live driver silent: the driver's states kept coming into its socket. Silence is measured
up to the last moment the process had read everything that had come (Bus.caught_up_at)."""

import sys
import textwrap

from conftest import last_json

DRIVER = textwrap.dedent("""
    import sys, time
    from skillbus.bus import open_bus
    from skillbus.robot.messages import arm_state_channel
    bus = open_bus()
    print("publishing", flush=True)
    while True:  # (until the test kills it)
        bus.publish(arm_state_channel(), b"state")  # (the Arm decodes a state only when asked)
        time.sleep(0.01)
""")

CHECKER = textwrap.dedent("""
    import json, time
    from skillbus.bus import open_bus
    from skillbus.robot.arm import Arm
    from skillbus.waiting import poll_until
    bus = open_bus()
    arm = Arm(bus)
    def pump(seconds):
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            bus.handle(0.01)
    out = {}
    end = time.monotonic() + 20
    while arm.silence().startswith("no robot arm state") and time.monotonic() < end:
        bus.handle(0.05)
    pump(0.3)
    out["hearing"] = arm.silence()
    time.sleep(1.5)                 # this process starved: nothing read, the driver goes on
    out["after_starving"] = arm.silence()
    print("starved", flush=True)    # (the test kills the driver now)
    poll_until(lambda: arm.silence() != "", 30, interval=0.01, step=bus.handle)
    out["driver_gone"] = arm.silence()
    print(json.dumps(out))
""")


def test_a_starved_process_does_not_call_a_live_arm_driver_silent_and_names_a_dead_one(sandbox):
    checker = sandbox.start("checker", [sys.executable, "-c", CHECKER])
    driver = sandbox.start("driver", [sys.executable, "-c", DRIVER])
    checker.wait_for("starved", 60, stream="stdout")
    sandbox.kill(driver)
    assert sandbox.wait(checker, 60) == 0, checker.stderr()[-2000:]
    r = last_json(checker.stdout())
    assert r["hearing"] == "", r
    assert r["after_starving"] == "", r  # (before: "went silent ... for 1.5 s")
    assert r["driver_gone"].startswith("the robot arm's driver went silent"), r
