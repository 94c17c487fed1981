"""The console's HTTP API answers what goes wrong as {"error": ...} with a status that says
what kind of wrong, never a traceback or FastAPI's own shape. Before: a malformed body or
a non-number task id was a 422 {"detail": [...]} (the page showed "[object Object]"); a
task id beyond 64 bits, an integer property beyond 64 bits or a text that is no UTF-8 was
a 500; a manager that did not answer a start was a 400 "refusal" although the task may
have been started (a retry started it twice); the replay of a run folder moved from
another machine was a 500. The app runs in-process on a bus that never answers (a
stand-in: no server is the case under test), with FastAPI's test client."""

from __future__ import annotations

import hashlib
import json

import pytest

pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from skillbus.msgs import header_t, lockstep_clock_t, skill_manager_info_t, wm_element_t  # noqa: E402
from support.stand_in_bus import StandInBus  # noqa: E402

TOKEN = {"X-Skillbus-Token": "T"}


class SilentBus(StandInBus):
    """Nothing ever arrives: the console's bus thread waits as on a bus no server answers."""

    def handle(self, timeout):
        import time
        time.sleep(min(timeout, 0.01))
        return False

    def caught_up_at(self):
        return float("inf")


class EncodingWorld:
    """A world model client that encodes what it would send (where a value no message can
    carry fails) and sends nothing."""

    def commit(self, ops):
        for op in ops:
            op.encode()
        raise AssertionError("a value that cannot be sent was not refused")


@pytest.fixture(scope="module")
def console():
    from skillbus.console.server import create_app
    app = create_app(SilentBus, token="T")
    with TestClient(app, raise_server_exceptions=False) as client:
        live = app.state.live
        info = skill_manager_info_t()
        info.name, info.incarnation = "skill_mgr", 1
        app.state.worker.submit(lambda: live["skills"]._on_manager("SB_MANAGERS", info.encode())).result(5)
        e = wm_element_t()
        e.id, e.type, e.label = "skiros:Cube-2", "skiros:Cube", "red"
        data = e.encode()
        read = hashlib.sha256(data).hexdigest()[:20]
        live["world"]._reads[read] = data  # (an element this console read: edits name it)
        live["world"]._wmi = EncodingWorld()
        yield client, read


def error(r) -> str:
    body = r.json()
    assert set(body) == {"error"}, body
    return body["error"]


def test_malformed_requests_are_400_with_an_error(console):
    client, _ = console
    r = client.post("/api/tasks/abc/pause", headers=TOKEN)
    assert r.status_code == 400 and error(r).startswith("path.task: "), r.text
    r = client.post("/api/tasks", headers={**TOKEN, "content-type": "application/json"}, content=b"{bad")
    assert r.status_code == 400 and error(r), r.text
    r = client.post("/api/tasks", headers=TOKEN, json=[1])
    assert r.status_code == 400 and error(r), r.text


def test_values_no_message_can_carry_are_400_naming_that(console):
    client, read = console
    r = client.post(f"/api/tasks/{2 ** 64}/stop", headers=TOKEN)
    assert r.status_code == 400 and error(r).startswith("a value no message can carry: "), r.text
    r = client.post("/api/world/edit", headers={**TOKEN, "content-type": "application/json"},
                    content=b'{"op": "set_label", "read": "%s", "label": "\\ud800"}' % read.encode())
    assert r.status_code == 400 and error(r).startswith("a value no message can carry: "), r.text


def test_an_edits_text_field_that_is_missing_or_no_string_is_refused(console):
    # Before, a set_label without a label erased the label, and a null became "None".
    client, read = console
    for body, why in (({"op": "set_label", "read": read}, "this edit needs 'label' (a string)"),
                      ({"op": "set_label", "read": read, "label": None}, "'label' must be a string, not null"),
                      ({"op": "add", "type": 7}, "'type' must be a string, not a number"),
                      ({"op": "relate", "read": read, "subject": ["x"], "predicate": "p"},
                       "'subject' must be a string, not a list")):
        r = client.post("/api/world/edit", headers=TOKEN, json=body)
        assert r.status_code == 400 and error(r) == why, (body, r.text)
    r = client.post("/api/tasks", headers=TOKEN, json={"skill": "Wait", "robot": None})
    assert r.status_code == 400 and error(r) == "'robot' must be a string, not null", r.text


def test_a_server_that_does_not_answer_is_504_and_says_the_outcome_is_unknown(console):
    client, _ = console
    r = client.post("/api/tasks", headers=TOKEN, json={"skill": "Wait", "params": {}})
    assert r.status_code == 504, r.text
    assert "did not answer SKILL.start within 2 s: whether it did it is unknown" in error(r)
    r = client.get("/api/skills", headers=TOKEN)  # (one manager not answering: listed with its error)
    assert r.status_code == 200 and "did not answer SKILL.list" in r.json()[0]["error"], r.text


def test_a_moved_run_folders_replay_opens_with_the_consoles_scene_and_says_so(console, tmp_path):
    client, _ = console
    from skillbus import paths
    from skillbus.dds_record import LogWriter
    scene = json.loads(paths.demo_scene().read_text())
    for body in scene.get("robots", []) + [scene.get("robot", {})]:
        if isinstance(body, dict) and "urdf" in body:
            body["urdf"] = "/nowhere/arm6.urdf"  # (as in a run folder copied from another machine)
    (tmp_path / "scene").mkdir()
    (tmp_path / "scene" / "demo.scene.json").write_text(json.dumps(scene))
    out = LogWriter(tmp_path / "run.lcmlog")
    for f in range(3):
        c = lockstep_clock_t()
        c.header = header_t()
        c.header.frame, c.header.sender = f, "sim"
        c.participants, c.num_participants = ["g"], 1
        out.write("SB_LOCKSTEP_CLOCK", c.encode())
    out.close()
    r = client.post("/api/replay/open", headers=TOKEN, json={"path": str(tmp_path / "run.lcmlog")})
    assert r.status_code == 200, r.text
    assert "cannot be drawn" in r.json()["scene_note"] and "the console's scene is drawn instead" in \
        r.json()["scene_note"], r.json()


def test_the_error_status_of_each_kind():
    from skillbus.console.live import ConsoleError, ConsoleTimeout
    from skillbus.console.server import error_status
    from skillbus.rpc import RpcRemoteError, RpcTimeout
    import struct
    assert [error_status(e) for e in (ConsoleError("x"), ConsoleTimeout("x"), RpcTimeout("x"), RpcRemoteError(1, "x"),
                                      struct.error("x"), UnicodeEncodeError("utf-8", "\ud800", 0, 1, "x"),
                                      KeyError("x"))] == [400, 504, 504, 502, 400, 400, 500]


def test_two_consoles_on_one_machine_keep_their_own_cookies():
    # Cookies belong to the host, not the port: both consoles' cookies had one name, and
    # opening the second console's URL made the first one's page answer 401.
    from skillbus.console import access
    from skillbus.console.server import create_app
    first = create_app(SilentBus, token="first-token")
    with TestClient(first, raise_server_exceptions=False) as client:
        r = client.get("/?token=first-token", follow_redirects=False)
        assert r.status_code == 303 and access.cookie_name("first-token") in r.cookies, r.headers
        client.cookies.set(access.cookie_name("second-token"), "second-token")  # (what the other console set)
        assert client.get("/api/managers").status_code == 200
        assert access.cookie_name("first-token") != access.cookie_name("second-token")
