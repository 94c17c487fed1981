"""The console's HTTP API off the happy path: each wrong request is refused with a
message naming what is wrong (and the console goes on); a manager that appears after
the console, or restarts while its task runs, is followed; a port in use is one line."""

import json
import re
import sys
from pathlib import Path

from skillbus.waiting import wait_until
from test_skills import mgr_binary, start_system, start_wm

PROBE = Path(__file__).parent / "console_api.py"


def console(sandbox, *extra: str) -> tuple[object, str]:
    p = sandbox.start(f"console-{len(sandbox.procs)}", [sys.executable, "-m", "skillbus.cli", "console", "--port", "0",
                                                        *extra])
    return p, p.wait_for(re.compile(r"skillbus console: (http://\S+)"), 30, stream="stdout").group(1)


def ask(sandbox, url: str, *requests) -> list:
    p = sandbox.start(f"ask-{len(sandbox.procs)}", [sys.executable, str(PROBE), url, json.dumps(requests)])
    assert sandbox.wait(p, 60) == 0, p.stderr()
    return json.loads(p.stdout())


def test_wrong_requests_are_refused_naming_what_is_wrong(sandbox, tmp_path):
    start_wm(sandbox, tmp_path / "wm")
    start_system(sandbox, "flow_skills")
    proc, url = console(sandbox)
    wait_until(lambda: ask(sandbox, url, ["GET", "/api/managers", None])[0][1], 20, "the console finds the manager")
    (lst,) = ask(sandbox, url, ["GET", "/api/skills", None])
    assert lst[0] == 200 and {"Chain", "Wait"} <= {s["type"] for s in lst[1]}, lst
    (read,) = ask(sandbox, url, ["GET", "/api/world/element/skiros:Cube-2", None])
    assert read[0] == 200 and read[1]["label"] == "red", read
    token = read[1]["read"]
    replies = ask(
        sandbox, url,
        ["POST", "/api/tasks", {"skill": "NoSuchSkill"}],
        ["POST", "/api/tasks", {"skill": "Wait", "params": {"Ticks": "many"}}],
        ["POST", "/api/tasks", {"skill": "Wait", "params": {"Nope": "1"}}],
        ["POST", "/api/tasks", {"skill": "Wait", "robot": "r9"}],
        ["POST", "/api/tasks", {"params": []}],
        ["POST", "/api/tasks/999/pause", None],
        ["POST", "/api/tasks/1/dance", None],
        ["GET", "/api/world/element/skiros:Cube-99", None],
        ["POST", "/api/world/edit", {"op": "set_label", "read": "forged", "label": "x"}],
        ["POST", "/api/world/edit", {"op": "set_property", "read": token, "key": "skiros:Size", "values": ["big"]}],
        ["POST", "/api/world/edit", {"op": "set_property", "read": token, "key": "skiros:Shiny", "values": ["1"]}],
        ["POST", "/api/world/edit", {"op": "relate", "read": token, "subject": "skiros:Table-1",
                                     "predicate": "skiros:contain", "object": "skiros:Bin-5"}],
        ["POST", "/api/world/edit", {"op": "teleport", "read": token}],
        ["POST", "/api/world/edit", {"op": "add", "type": "skiros:Cube", "parent": "skiros:Nowhere-1"}],
        ["POST", "/api/replay/open", {"path": str(tmp_path / "missing.lcmlog")}],
        ["POST", "/api/replay/open", {"path": "/etc/passwd"}],
        ["GET", "/api/replay/frame/3", None],
    )
    (not_on_disk := tmp_path / "not_a_log.lcmlog").write_bytes(b"\x00garbage" * 100)
    replies += ask(sandbox, url, ["POST", "/api/replay/open", {"path": str(not_on_disk)}])
    expected = [
        (400, "unknown skill NoSuchSkill"),
        (400, "Ticks"),
        (400, "Nope"),
        (400, "no skill manager of robot r9"),
        (400, "a start needs"),
        (400, "no running or queued task 999"),
        (400, "unknown command 'dance'"),
        (400, "unknown element id 'skiros:Cube-99'"),
        (400, "names no element read by this console"),
        (400, "'big' is not a float"),
        (400, "has no property skiros:Shiny: say its value type"),
        (400, "needs a predicate and skiros:Cube-2 at one end"),
        (400, "unknown edit 'teleport'"),
        (400, "skiros:Nowhere-1"),
        (400, "no log file"),
        (400, "the console replays LCM logs, named *.lcmlog"),
        (404, "no log open"),
        (400, "not"),
    ]
    assert len(replies) == len(expected)
    for (status, reply), (want_status, want_text) in zip(replies, expected):
        assert status == want_status and want_text in reply["error"], (status, reply, want_text)
        print(status, reply["error"])
    # nothing refused changed the world, and the console still answers
    (again,) = ask(sandbox, url, ["GET", "/api/world/element/skiros:Cube-2", None])
    assert again[1]["read"] == token and again[1]["label"] == "red", again
    assert proc.returncode is None
    # A log that lacks a frame (its recorder dropped it): asked for that frame, the console
    # answers the nearest one before it and says which was asked; the page shows both.
    gap = clocks_log(tmp_path / "gap.lcmlog", [f for f in range(10) if f != 4])
    opened, at4, at5, at99 = ask(sandbox, url, ["POST", "/api/replay/open", {"path": str(gap)}],
                                 ["GET", "/api/replay/frame/4", None], ["GET", "/api/replay/frame/5", None],
                                 ["GET", "/api/replay/frame/99", None])
    assert opened[0] == 200 and opened[1]["frames"] == 9 and opened[1]["last"] == 9, opened
    assert (at4[1]["frame"], at4[1]["asked"], round(at4[1]["sim_time_s"], 6)) == (3, 4, 0.06), at4
    assert (at5[1]["frame"], at5[1]["asked"]) == (5, 5), at5
    assert (at99[1]["frame"], at99[1]["asked"]) == (9, 99), at99


def clocks_log(path: Path, frames: list[int]) -> Path:
    """An LCM log of a lockstep session's clocks only (20 ms frames), for `frames`."""
    from skillbus.dds_record import LogWriter
    from skillbus.msgs import header_t, lockstep_clock_t
    out = LogWriter(path)
    for f in frames:
        c = lockstep_clock_t()
        c.header = header_t()
        c.header.frame, c.header.sim_time_ns, c.header.sender = f, f * 20_000_000, "sim"
        c.frame_period_ns, c.participants, c.num_participants = 20_000_000, ["gripper"], 1
        out.write("SB_LOCKSTEP_CLOCK", c.encode())
    out.close()
    return path


def test_without_the_token_the_api_and_the_live_feed_are_refused(sandbox):
    proc, url = console(sandbox)
    assert "?token=" in url
    replies = ask(sandbox, url, ["GET", "/api/managers", None, ""], ["POST", "/api/tasks", {"skill": "Wait"}, "guess"],
                  ["GET", "/api/managers", None], ["GET", "/", None, ""])
    assert replies[0][0] == 401 and "needs its token" in replies[0][1]["error"], replies[0]
    assert replies[1][0] == 401, replies[1]
    assert replies[2] == [200, []]
    assert replies[3][0] == 200 and "skillbus console" in replies[3][1]  # the page itself holds nothing
    for given, said in ((url.split("?")[0], "HTTP 403"), (url, '"kind":"hello"')):  # the live feed
        feed = sandbox.start(f"feed-{len(sandbox.procs)}", [sys.executable, "-c", FEED, given])
        assert sandbox.wait(feed, 30) == 0, feed.stderr()
        assert said in feed.stdout(), feed.stdout()


FEED = """
import sys
from websockets.sync.client import connect
base, _, query = sys.argv[1].partition("?")
try:
    with connect(base.replace("http", "ws") + "api/live?" + query) as ws:
        print(ws.recv())
except Exception as e:
    print("refused", e)
"""


def test_a_manager_that_starts_later_is_found_and_one_that_restarts_loses_its_task_visibly(sandbox, tmp_path):
    proc, url = console(sandbox)  # before any manager
    assert ask(sandbox, url, ["GET", "/api/managers", None])[0] == [200, []]
    mgr, _ = start_system(sandbox, "flow_skills")
    wait_until(lambda: ask(sandbox, url, ["GET", "/api/managers", None])[0][1], 20, "the console finds the manager")
    (started,) = ask(sandbox, url, ["POST", "/api/tasks", {"skill": "Wait", "params": {"Ticks": "100000"}}])
    assert started[0] == 200, started
    task = started[1]["task"]

    def state() -> str:
        tasks = ask(sandbox, url, ["GET", "/api/tasks", None])[0][1]
        return next((t["state"] for t in tasks if t["task"] == task), "")

    wait_until(lambda: state() == "Running", 20, "the task running in the console")
    sandbox.kill(mgr)
    sandbox.wait(mgr, 10)
    sandbox.start("skill_mgr-again", [mgr_binary(), "--wall-clock"])
    # the new manager registers the skills again and knows no task 1: the console says
    # the task was lost rather than showing it running for ever
    wait_until(lambda: state() == "Failure", 30, "the lost task marked failed")
    tasks = ask(sandbox, url, ["GET", "/api/tasks", None])[0][1]
    root = next(t for t in tasks if t["task"] == task)["nodes"][0]
    assert "no longer knows it" in root["message"], root
    # The new manager numbers its tasks from 1 again: its task of the old one's number is
    # shown (before, the console kept the old, ended tree and ignored the new task's).
    wait_until(lambda: ask(sandbox, url, ["GET", "/api/skills", None])[0][1], 20, "the skills registered again")
    (again,) = ask(sandbox, url, ["POST", "/api/tasks", {"skill": "Wait", "params": {"Ticks": "3"}}])
    assert again[0] == 200 and again[1]["task"] == task, again
    wait_until(lambda: state() == "Success", 30, "the new task's end shown",
               diagnostic=lambda: str(ask(sandbox, url, ["GET", "/api/tasks", None])) + proc.stderr()[-3000:])
    tasks = ask(sandbox, url, ["GET", "/api/tasks", None])[0][1]
    assert next(t for t in tasks if t["task"] == task)["nodes"][0]["message"] == "waited", tasks
    assert proc.returncode is None


def test_a_manager_that_stops_answering_is_dropped_and_its_running_task_lost(sandbox):
    # Before, a killed manager that nobody restarted stayed listed for ever, its task
    # showed Running, and /api/skills failed as a whole (a 400) after its 2 s timeout.
    proc, url = console(sandbox)
    mgr, _ = start_system(sandbox, "flow_skills")
    wait_until(lambda: ask(sandbox, url, ["GET", "/api/managers", None])[0][1], 20, "the console finds the manager")
    (started,) = ask(sandbox, url, ["POST", "/api/tasks", {"skill": "Wait", "params": {"Ticks": "100000"}}])
    task = started[1]["task"]

    def tree() -> dict:
        return next((t for t in ask(sandbox, url, ["GET", "/api/tasks", None])[0][1] if t["task"] == task), {})

    wait_until(lambda: tree().get("state") == "Running", 20, "the task running in the console")
    sandbox.kill(mgr)
    sandbox.wait(mgr, 10)
    (skills,) = ask(sandbox, url, ["GET", "/api/skills", None])  # (not yet dropped: it says it did not answer)
    assert skills[0] == 200 and "did not answer SKILL.list" in skills[1][0]["error"], skills
    wait_until(lambda: ask(sandbox, url, ["GET", "/api/managers", None])[0] == [200, []], 30, "the manager dropped")
    t = tree()
    assert t["state"] == "Failure" and "its skill manager has not answered for 9 s" in t["nodes"][0]["message"], t
    assert proc.returncode is None


def test_a_console_outside_the_namespace_serves_here_and_hears_the_system_there(sandbox):
    """`--netns PID`: the page on this machine's loopback (where a browser is), the bus in
    the system's private network namespace. Asked from this (the test's) network."""
    import urllib.request
    assert sandbox.namespace_pid, "needs a private network namespace"
    start_system(sandbox, "flow_skills")
    p = sandbox.start("console-host", [sys.executable, "-m", "skillbus.cli", "console", "--port", "0", "--netns",
                                       str(sandbox.namespace_pid)], host_network=True)
    url = p.wait_for(re.compile(r"skillbus console: (http://\S+)"), 30, stream="stdout").group(1)
    base, token = url.split("/?token=")

    def managers() -> list:
        req = urllib.request.Request(base + "/api/managers", headers={"X-Skillbus-Token": token})
        with urllib.request.urlopen(req, timeout=10) as r:
            return json.loads(r.read())

    wait_until(managers, 20, "the manager in the namespace, seen from here")
    # the token went into the namespace in the environment, not in arguments every user sees
    import subprocess
    assert token not in subprocess.run(["ps", "-eo", "args"], capture_output=True, text=True).stdout
    p2 = sandbox.start("console-nowhere", [sys.executable, "-m", "skillbus.cli", "console", "--port", "0", "--netns",
                                           "999999999"], host_network=True)
    assert sandbox.wait(p2, 20) == 1 and "--netns 999999999: no such process" in p2.stderr(), p2.stderr()


def test_a_port_in_use_is_one_line(sandbox):
    holder = sandbox.start("holder", [sys.executable, "-c", HOLD])
    port = int(holder.wait_for(re.compile(r"(\d+)"), 10, stream="stdout").group(1))
    p = sandbox.start("console-busy", [sys.executable, "-m", "skillbus.cli", "console", "--port", str(port)])
    assert sandbox.wait(p, 30) == 1
    assert f"cannot serve on 127.0.0.1:{port}" in p.stderr() and "Traceback" not in p.stderr(), p.stderr()


HOLD = """
import socket, time
s = socket.socket()
s.bind(("127.0.0.1", 0))
s.listen()
print(s.getsockname()[1], flush=True)
time.sleep(60)
"""


def test_malformed_and_absurd_messages_on_every_channel_it_hears_do_not_break_it(sandbox):
    """Random bytes, truncated messages and decodable ones with absurd values (a node whose
    parent comes after it, a task id of -1, 2,000 nodes, a sim state with NaN joints) on
    each channel the console hears, signed like any holder of the key sends them: the
    console goes on answering and its pages' data stay JSON."""
    start_system(sandbox, "flow_skills")
    proc, url = console(sandbox)
    wait_until(lambda: ask(sandbox, url, ["GET", "/api/managers", None])[0][1], 20, "the console finds the manager")
    # a page open: the console hears the physics state too
    feed = sandbox.start("feed", [sys.executable, "-c", FEED_KEPT, url])
    feed.wait_for("hello", 20, stream="stdout")
    flood = sandbox.start("flood", [sys.executable, "-c", FLOOD])
    flood.wait_for("flooded", 120, stream="stdout")
    wait_until(lambda: any(t["task"] == 99 for t in ask(sandbox, url, ["GET", "/api/tasks", None])[0][1]), 20,
               "the ghost tree in the console")
    assert flood.returncode is None and "Traceback" not in flood.stderr(), flood.stderr()  # still sending
    sandbox.kill(flood)
    replies = ask(sandbox, url, ["GET", "/api/tasks", None], ["GET", "/api/managers", None], ["GET", "/api/sim", None])
    assert replies[0][0] == 200 and isinstance(replies[0][1], list), replies[0]
    assert replies[1][0] == 200 and replies[1][1], replies[1]  # the real manager is still there
    assert replies[2][0] == 404 and "no physics state" in replies[2][1]["error"], replies[2]  # none could be drawn
    (started,) = ask(sandbox, url, ["POST", "/api/tasks", {"skill": "Wait", "params": {"Ticks": "3"}}])
    assert started[0] == 200, started
    assert proc.returncode is None and "Traceback" not in proc.stderr(), proc.stderr()[-3000:]
    sandbox.kill(feed)


FEED_KEPT = """
import sys
from websockets.sync.client import connect
base, _, query = sys.argv[1].partition("?")
with connect(base.replace("http", "ws") + "api/live?" + query) as ws:
    print(ws.recv()[:20], flush=True)
    for m in ws:
        pass
"""


FLOOD = """
import math, random, struct
from skillbus.bus import open_bus
from skillbus.msgs import (skill_progress_t, skill_node_progress_t, skill_manager_info_t, sim_state_t, sim_object_t,
                           robot_arm_cmd_t, joint_traj_point_t, wm_change_t)
bus = open_bus()
rnd = random.Random(7)
channels = ["SB_SKILL_PROGRESS", "SB_MANAGERS", "SB_SIM_STATE", "SB_ROBOT_ARM_CMD", "SB_WM_CHANGES", "SB_SKILL_REP",
            "SB_WM_REP"]

def absurd(ch):
    if ch == "SB_SKILL_PROGRESS":
        p = skill_progress_t(); p.task = rnd.choice([-1, 0, 2**62, 7]); p.tick = rnd.choice([-5, 0, 2**40])
        p.state = rnd.choice([0, 2, 3, 4, 99, -3]); n = rnd.choice([0, 1, 3, 2000])
        for i in range(n):
            x = skill_node_progress_t(); x.id = rnd.choice([i, -1, 10**6]); x.parent = rnd.choice([-1, i + 1, -7, i - 1])
            x.state = rnd.choice([2, 77]); x.progress = rnd.choice([0.5, math.nan, -math.inf]); x.message = "\\u00ff" * rnd.choice([0, 300]); x.params = "a=b\\n=\\nnoeq"
            p.nodes.append(x)
        p.num_nodes = len(p.nodes); return p.encode()
    if ch == "SB_MANAGERS":
        m = skill_manager_info_t(); m.robot = rnd.choice(["", "r1", "x" * 500]); m.name = "ghost"
        m.incarnation = rnd.randint(0, 5); return m.encode()
    if ch == "SB_SIM_STATE":
        s = sim_state_t(); s.joint_names = ["joint1", "joint2", "nope"]; s.num_joints = 3
        s.position = [math.nan, math.inf, 1e300]; s.velocity = [0.0] * 3; s.effort = [0.0] * 3
        o = sim_object_t(); o.name = "red"; o.pose = [math.nan] * 7; s.objects = [o]; s.num_objects = 1
        return s.encode()
    if ch == "SB_ROBOT_ARM_CMD":
        c = robot_arm_cmd_t(); c.joint_names = ["joint1"] * 2; c.num_joints = 2
        pt = joint_traj_point_t(); pt.num_positions = 2; pt.positions = [math.nan, 1.0]; pt.num_velocities = 2; pt.velocities = [0.0, 0.0]
        c.points = [pt] * 50; c.num_points = 50; return c.encode()
    w = wm_change_t(); w.version = rnd.choice([-1, 2**60]); return w.encode()

for i in range(6000):
    ch = rnd.choice(channels)
    kind = i % 3
    if kind == 0:
        data = bytes(rnd.getrandbits(8) for _ in range(rnd.choice([0, 7, 40, 300])))
    else:
        data = absurd(ch)
        if kind == 2:
            data = data[: rnd.randint(0, len(data))]
    try:
        bus.publish(ch, data)
    except Exception:
        pass
    if i % 200 == 0:
        bus.handle(0.01)
# last, for certain: a physics state and a tree whose numbers JSON cannot carry. Sent again
# until the test has seen the tree: the flood may have filled the console's queue (LCM drops
# what a full subscription queue cannot hold), and the test is about surviving, not delivery.
p = skill_progress_t(); p.task, p.tick, p.state = 99, 1, 2
x = skill_node_progress_t(); x.parent, x.state, x.type, x.progress = -1, 2, "Ghost", math.nan
p.nodes, p.num_nodes = [x], 1
print("flooded", flush=True)
for _ in range(240):
    bus.publish("SB_SIM_STATE", absurd("SB_SIM_STATE"))
    bus.publish("SB_SKILL_PROGRESS", p.encode())
    bus.handle(0.25)
"""


def test_a_search_over_more_elements_than_one_reply_holds_is_read_in_pages(sandbox, tmp_path):
    # Before, searching a type of 3,000 elements (the start form's element picker) was
    # refused by the server ("ask for it in pages") and the console answered 400.
    from test_wm_scale import scene
    ttl = tmp_path / "big.ttl"
    ttl.write_text(scene(3000))
    start_wm(sandbox, tmp_path / "wm", scene=ttl)
    proc, url = console(sandbox)
    (found,) = ask(sandbox, url, ["GET", "/api/world/search?type=skiros:Cube&label=c3002", None])
    assert found[0] == 200 and [e["id"] for e in found[1]] == ["skiros:Cube-3002"], found
    (every,) = ask(sandbox, url, ["GET", "/api/world/search?type=skiros:Cube", None])
    assert every[0] == 200 and len(every[1]) == 3000, (every[0], len(every[1]))
