"""The console's web server: a FastAPI app between the bus and browsers.

HTTP for what a page asks (skills, a start, a task command, the world model and its
edits); one WebSocket, ``/api/live``, for what happens: a first message with the
managers and every task's tree, then each change of a tree (only the nodes that
changed). A browser that falls behind by more than LIVE_QUEUE events is told to reload
rather than silently missing changes (the trees are whole again at the reload).
"""

from __future__ import annotations

import asyncio
import json
import logging
from pathlib import Path
from typing import Any, Callable

from fastapi import FastAPI, HTTPException, Request, WebSocket, WebSocketDisconnect
from fastapi.exceptions import RequestValidationError
from fastapi.responses import FileResponse, JSONResponse
from fastapi.staticfiles import StaticFiles

from skillbus.console.bus_worker import BusWorker
from skillbus.console.live import (CATCH_UP_S, FLUSH_PERIOD_S, PROBE_PERIOD_S, ConsoleError, ConsoleTimeout, LiveSkills,
                                   text_field)
from skillbus.console.world import LiveWorld

log = logging.getLogger("skillbus.console")
STATIC = Path(__file__).parent / "static"
LIVE_QUEUE = 10000
JOB_TIMEOUT_S = 15.0


class Broadcaster:
    """Fans events out to every connected browser. The bus thread collects events
    (:meth:`emit`) and hands them over in one batch per period (:meth:`send`): one wake-up
    of the server's event loop, not one per event. With no browser connected nothing is
    kept: a browser that connects starts from a snapshot."""

    def __init__(self) -> None:
        self.loop: asyncio.AbstractEventLoop | None = None
        self.queues: set[asyncio.Queue] = set()
        self._batch: list[dict[str, Any]] = []
        self.sent = 0

    @property
    def watched(self) -> bool:
        return bool(self.queues)  # (read from the bus thread: a set's truth is one atomic read)

    def emit(self, event: dict[str, Any]) -> None:  # on the bus thread
        if self.watched:
            self._batch.append(event)

    def send(self) -> None:  # chore on the bus thread
        if self._batch and self.loop is not None:
            batch, self._batch = self._batch, []
            self.loop.call_soon_threadsafe(self._put, batch)

    def _put(self, batch: list[dict[str, Any]]) -> None:
        self.sent += len(batch)
        for q in list(self.queues):
            for event in batch:
                try:
                    q.put_nowait(event)
                except asyncio.QueueFull:
                    self.queues.discard(q)
                    q.put_nowait_overflow = True  # type: ignore[attr-defined]
                    break


def error_status(e: BaseException) -> int:
    """The HTTP status of what went wrong on the bus thread: 400 a request the console
    cannot do (ConsoleError) or a value no message can carry (a text that is no UTF-8, an
    integer beyond 64 bits); 504 a server that did not answer, where what was asked may or
    may not have been done (ConsoleTimeout, RpcTimeout); 502 a server that answered with an
    error the console did not expect (RpcError, WorldModelError); 500 anything else.

    >>> error_status(ConsoleTimeout("x")), error_status(ConsoleError("x")), error_status(ValueError("x"))
    (504, 400, 500)
    """
    import struct

    from skillbus.rpc import RpcError, RpcTimeout
    from skillbus.world.client import WorldModelError
    if isinstance(e, (ConsoleTimeout, RpcTimeout)):
        return 504
    if isinstance(e, ConsoleError):
        return 400
    if isinstance(e, (UnicodeError, struct.error, OverflowError)):
        return 400
    if isinstance(e, (RpcError, WorldModelError)):
        return 502
    return 500


THREE_JS = Path("/usr/share/javascript/three")  # Debian's libjs-three (deploy/setup.sh installs it)


def create_app(open_bus: Callable[[], Any], scene: Path | None = None, log: Path | None = None,
               token: str | None = None) -> FastAPI:
    """The console app on a bus opened by `open_bus` (on the bus thread); the 3D view
    draws `scene` (default: the demo's); `log` is opened for replay at once; with `token`
    only its holders use the API (console.access)."""
    from fastapi.responses import RedirectResponse

    from skillbus.console import access
    from skillbus import paths
    from skillbus.console.replay import ReplayError, ReplayLog
    from skillbus.console.scene3d import Scene3D
    from skillbus.console.views3d import SEND_PERIOD_S, LiveSim, frame_view

    app = FastAPI(title="skillbus console", docs_url="/api/docs", redoc_url=None)
    worker = BusWorker(open_bus)
    hub = Broadcaster()
    state: dict[str, Any] = {"scene": Scene3D(scene or paths.demo_scene()), "replay": None}

    def setup() -> None:  # on the bus thread
        state["skills"] = LiveSkills(worker.bus, hub.emit)
        state["world"] = LiveWorld(worker.bus, state["skills"].emit)
        state["sim"] = LiveSim(worker.bus, state["scene"], state["skills"].emit)
        worker.every(0.5, state["world"].say_version)
        worker.every(PROBE_PERIOD_S, state["skills"].probe)
        worker.every(CATCH_UP_S / 2, state["skills"].catch_up_quiet_tasks)
        # What only a page needs is done only while one is open: the physics state is not
        # even heard without one (it comes every frame), trees are updated every 2 s.
        worker.every(SEND_PERIOD_S, lambda: state["sim"].send(hub.watched))
        worker.every(FLUSH_PERIOD_S, lambda: state["skills"].flush(idle_period_s=None if hub.watched else 2.0))
        worker.every(FLUSH_PERIOD_S, hub.send)

    def open_replay(path: Path) -> dict[str, Any]:
        """Reads a log (in a worker thread: seconds for a long run); its summary."""
        if path.suffix != ".lcmlog":
            raise ConsoleError(f"{path}: the console replays LCM logs, named *.lcmlog")
        try:
            r = ReplayLog(path)
        except ReplayError as e:
            raise ConsoleError(str(e)) from None
        scenes = sorted((path.parent / "scene").glob("*.scene.json"))  # a `skillbus demo` run folder's
        r.scene = state["scene"]
        if scenes:
            try:
                r.scene = Scene3D(scenes[0])
            except (OSError, ValueError, KeyError) as e:  # (a run folder moved: its scene names models not here)
                r.scene_note = f"the run's scene {scenes[0]} cannot be drawn ({type(e).__name__}: {e}): " \
                               f"the console's scene is drawn instead"
                logging.getLogger("skillbus.console").warning("%s", r.scene_note)
        state["replay"] = r
        return r.summary()

    if log is not None:
        open_replay(Path(log))

    @app.on_event("startup")
    async def _start() -> None:
        hub.loop = asyncio.get_running_loop()
        worker.start()
        await asyncio.wrap_future(worker.submit(setup))

    @app.on_event("shutdown")
    async def _stop() -> None:
        worker.stop()

    async def on_bus(fn: Callable[[], Any]) -> Any:
        """Runs fn on the bus thread; what goes wrong is an HTTP error naming it (error_status)."""
        try:
            return await asyncio.wait_for(asyncio.wrap_future(worker.submit(fn)), JOB_TIMEOUT_S)
        except asyncio.TimeoutError:
            raise HTTPException(status_code=504, detail=f"the bus did not answer within {JOB_TIMEOUT_S:g} s") from None
        except Exception as e:
            status = error_status(e)
            if status == 500:
                raise
            unsendable = status == 400 and not isinstance(e, ConsoleError)
            raise HTTPException(status_code=status,
                                detail=f"a value no message can carry: {e}" if unsendable else str(e)) from None

    @app.middleware("http")
    async def _token(request: Request, call_next):
        if request.url.path.startswith("/api/") and not access.allowed(
                token, access.presented(request.headers, dict(request.query_params), request.cookies, token)):
            return JSONResponse({"error": access.NEEDS_TOKEN}, status_code=401)
        return await call_next(request)

    @app.exception_handler(HTTPException)
    async def _http_error(request: Request, exc: HTTPException) -> JSONResponse:
        return JSONResponse({"error": exc.detail}, status_code=exc.status_code)

    @app.exception_handler(RequestValidationError)
    async def _bad_request(request: Request, exc: RequestValidationError) -> JSONResponse:
        # (FastAPI's 422 {"detail": [...]}: the page shows {"error": ...}, as for every refusal)
        first = exc.errors()[0] if exc.errors() else {}
        where = ".".join(str(x) for x in first.get("loc", ()) if x != "body") or "the request"
        return JSONResponse({"error": f"{where}: {first.get('msg', 'not a valid request')}"}, status_code=400)

    @app.exception_handler(Exception)
    async def _internal(request: Request, exc: Exception) -> JSONResponse:
        logging.getLogger("skillbus.console").error("%s %s failed", request.method, request.url.path, exc_info=exc)
        return JSONResponse({"error": f"the console failed: {type(exc).__name__}: {exc} (its log has the details)"},
                            status_code=500)

    @app.get("/")
    async def index(request: Request):
        given = request.query_params.get("token", "")
        if given and token is not None and access.allowed(token, given):
            # the token into a cookie, out of the address bar (and of the history)
            r = RedirectResponse("/", status_code=303)
            r.set_cookie(access.cookie_name(token), given, httponly=True, samesite="strict")
            return r
        return FileResponse(STATIC / "index.html")

    app.mount("/static", StaticFiles(directory=STATIC), name="static")
    if THREE_JS.is_dir():
        app.mount("/vendor/three", StaticFiles(directory=THREE_JS), name="three")

    @app.get("/api/scene3d")
    async def scene3d(replay: bool = False) -> dict[str, Any]:
        r = state["replay"]
        sc = r.scene if replay and r is not None else state["scene"]
        return {"scene": str(sc.path), "bodies": sc.shapes(), "three": THREE_JS.is_dir()}

    @app.get("/api/sim")
    async def sim_now() -> dict[str, Any]:
        latest = await on_bus(lambda: state["sim"].latest())
        if latest is None:
            raise HTTPException(404, "no physics state heard yet (SB_SIM_STATE)")
        return latest

    @app.post("/api/replay/open")
    async def replay_open(body: dict[str, Any]) -> dict[str, Any]:
        path = Path(str(body.get("path", ""))).expanduser()
        try:
            return await asyncio.get_running_loop().run_in_executor(None, open_replay, path)
        except ConsoleError as e:
            raise HTTPException(400, str(e)) from None

    @app.get("/api/replay")
    async def replay_summary() -> dict[str, Any]:
        if state["replay"] is None:
            raise HTTPException(404, "no log open")
        return state["replay"].summary()

    @app.get("/api/replay/frame/{frame}")
    async def replay_frame(frame: int) -> dict[str, Any]:
        r = state["replay"]
        if r is None:
            raise HTTPException(404, "no log open")
        f = r.nearest_frame(frame)
        sim = r.sim_at(f)
        try:
            view = frame_view(r.scene, sim, r.arm_cmd_at(f), f) if sim is not None else None
        except ValueError:
            view = None  # (a recorded state that cannot be drawn)
        # `asked` beside `frame`: a frame the log lacks (its logger dropped it) is shown as
        # the nearest recorded one before it, and the page says so.
        return {"frame": f, "asked": frame, "sim_time_s": r.sim_time_ns[f] * 1e-9, "tasks": r.tasks_at(f),
                "world": r.world_at(f).tree(),
                "sim": view}

    @app.get("/api/managers")
    async def managers() -> list[dict[str, Any]]:
        return await on_bus(lambda: state["skills"].manager_list())

    @app.get("/api/skills")
    async def skills() -> list[dict[str, Any]]:
        return await on_bus(lambda: state["skills"].skills())

    @app.get("/api/tasks")
    async def tasks() -> list[dict[str, Any]]:
        return await on_bus(lambda: state["skills"].tasks())

    @app.post("/api/tasks")
    async def start(body: dict[str, Any]) -> dict[str, Any]:
        params = body.get("params") or {}
        if not isinstance(params, dict) or not isinstance(body.get("skill"), str):
            raise HTTPException(400, "a start needs {\"skill\": NAME, \"robot\": NAME, \"params\": {KEY: VALUE}}")
        try:  # (a null robot became "None")
            robot, skill, label = text_field(body, "robot", ""), body["skill"], text_field(body, "label", "")
        except ConsoleError as e:
            raise HTTPException(400, str(e)) from None
        text = {str(k): v if isinstance(v, str) else json.dumps(v) for k, v in params.items()}
        task = await on_bus(lambda: state["skills"].start(robot, skill, label, text))
        return {"robot": robot, "task": task}

    @app.post("/api/tasks/{task}/{verb}")
    async def command(task: int, verb: str, robot: str = "") -> dict[str, Any]:
        message = await on_bus(lambda: state["skills"].command(robot, task, verb))
        return {"robot": robot, "task": task, "message": message}

    @app.get("/api/world/tree")
    async def world_tree() -> dict[str, Any]:
        return await on_bus(lambda: state["world"].tree())

    @app.get("/api/world/search")
    async def world_search(type: str = "", label: str = "") -> list[dict[str, Any]]:
        return await on_bus(lambda: state["world"].search(type, label))

    @app.get("/api/world/element/{eid}")
    async def world_element(eid: str) -> dict[str, Any]:
        return await on_bus(lambda: state["world"].element(eid))

    @app.post("/api/world/edit")
    async def world_edit(body: dict[str, Any]) -> dict[str, Any]:
        return await on_bus(lambda: state["world"].edit(body))

    @app.websocket("/api/live")
    async def live(ws: WebSocket) -> None:
        if not access.allowed(token, access.presented(ws.headers, dict(ws.query_params), ws.cookies, token)):
            await ws.close(code=4401, reason="token needed")
            return
        await ws.accept()
        q: asyncio.Queue = asyncio.Queue(LIVE_QUEUE)
        hub.queues.add(q)  # (before the snapshot: what happens after it is queued)
        try:
            # The snapshot's seq: events queued before it (seq <= it) are in it already.
            first = await asyncio.wrap_future(worker.submit(lambda: state["skills"].snapshot()))
            await ws.send_json(first)
            while True:
                event = await q.get()
                if event.get("seq", 0) > first["seq"]:
                    await ws.send_json(event)
                if getattr(q, "put_nowait_overflow", False) and q.empty():
                    await ws.send_json({"kind": "overflow", "message": "this page fell behind: reload it"})
                    break
        except WebSocketDisconnect:
            pass
        finally:
            hub.queues.discard(q)

    app.state.worker, app.state.hub, app.state.live = worker, hub, state
    return app
