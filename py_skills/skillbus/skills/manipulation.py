"""Manipulation skills: Locate, MoveArm, LiftArm, and the compounds Pick, Place and
ClearTable. MoveArm and LiftArm need a skill process started with ``--arm
--world-model``, Locate one with a camera (``--interface camera=skillbus.robot.camera
--world-model``); the gripper skills (skillbus.skills.gripper) need ``--gripper``.

Tool poses: the tool points straight down; its yaw follows the target's yaw, folded to
within 45 degrees (a cube looks the same every 90 degrees), so the wrist turns least.
Poses come from the world model replica (skillbus.world.poses), never from a server
call, so a skill decides the same way on every run.
"""

from __future__ import annotations

import logging
import math
import time
from typing import Any

from skillbus import tick_context
from skillbus.robot import arm as arm_service
from skillbus.robot import camera as camera_service
from skillbus.perception import depth_camera as depth_service
from skillbus.perception import map_client as map_service
from skillbus.perception.depth_camera import CameraError
from skillbus.perception.segment import SegmentError, detect
from skillbus.skills.perceived import Known, match
from skillbus.skill import (ConditionRelation, Element, ParamTypes, PrimitiveBase, RetryOnFail, SelectorStar,
                            SerialStar, SkillBase, SkillDescription, State)
from skillbus.msgs import wm_op_t
from skillbus.rpc import RpcError
from skillbus.world.convert import op
from skillbus.quat import qmul, yaw_of
from skillbus.world.poses import (parent_of, reparent, reparent_ops, set_world_pose, world_pose,
                                  world_pose_op)

DOWN = (0.0, 1.0, 0.0, 0.0)  # tool z pointing down: half a turn about y
MOVE_TIMEOUT_S = 20.0
APPROACH, GRASP_HEIGHT, LIFT = 0.10, 0.005, 0.10      # m, tool above the object's centre
BIN_ABOVE, BIN_RELEASE = 0.45, 0.30                     # m, tool above the bin's origin
BIN_RADIUS = 0.15  # m: what a depth camera's Locate in a bin looks at (the demo bin's inside, 0.30 m square)
BIN_FLOOR_CLEAR, SPOT_CLEARANCE = 0.035, 0.015  # m: a spot's column starts over the bin's floor (mid-voxel: clear of the floor's top voxel, 0.02-0.03); free margin around it
BIN_RELEASE_AT_SPOT = 0.14  # m, tool above the bin's origin: a held 5 cm cube's bottom 6 cm over its floor


def top_down(yaw: float) -> tuple[float, float, float, float]:
    return qmul((0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)), DOWN)


def fold(yaw: float) -> float:
    """The yaw within [-45, 45] degrees that grasps a square the same way."""
    return (yaw + math.pi / 4) % (math.pi / 2) - math.pi / 4


log = logging.getLogger("skillbus.skills")


def command_id(label: str) -> str:
    tick = tick_context.current_tick()
    return f"{label}@{tick.frame}" if tick is not None else f"{label}@{time.monotonic_ns()}"


# -- descriptions ---------------------------------------------------------------------
class Locate(SkillDescription):
    def createDescription(self):
        self.addParam("Location", Element("skiros:Location"), ParamTypes.Required)
        self.addParam("Radius", 0.35, ParamTypes.Optional,
                      description="depth camera: look for objects within this distance of the Location's origin, m")


class MoveArm(SkillDescription):
    def createDescription(self):
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)
        self.addParam("Target", Element("skiros:PhysicalObject"), ParamTypes.Required)
        self.addParam("Height", 0.1, ParamTypes.Optional, description="tool above the target's origin, m")
        self.addParam("Cartesian", False, ParamTypes.Optional, description="along a straight line")
        self.addParam("Spot", 0.0, ParamTypes.Optional,
                      description="> 0: over a free spot of the Target for a footprint this wide (m), from the "
                                  "occupancy map (the map interface), not over its origin")


class LiftArm(SkillDescription):
    def createDescription(self):
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)
        self.addParam("Height", 0.1, ParamTypes.Optional, description="straight up by this much, m")


class Pick(SkillDescription):
    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Required)
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addPreCondition(ConditionRelation("NotHolding", "skiros:contain", "Gripper", "Object", False))
        self.addPostCondition(ConditionRelation("Holding", "skiros:contain", "Gripper", "Object", True))


class Place(SkillDescription):
    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Required)
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)
        self.addParam("Object", Element("skiros:Product"), ParamTypes.Required)
        self.addParam("Location", Element("skiros:Location"), ParamTypes.Required)
        self.addPreCondition(ConditionRelation("Holding", "skiros:contain", "Gripper", "Object", True))
        self.addPostCondition(ConditionRelation("Contains", "skiros:contain", "Location", "Object", True))


class TransferProducts(SkillDescription):
    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Required)
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)
        self.addParam("From", Element("skiros:Location"), ParamTypes.Required)
        self.addParam("To", Element("skiros:Location"), ParamTypes.Required)
        self.addParam("Retries", 1, ParamTypes.Optional, description="retries per object (RetryOnFail); 0: none")


class ClearTable(SkillDescription):
    def createDescription(self):
        self.addParam("Gripper", Element("skiros:Gripper"), ParamTypes.Required)
        self.addParam("Arm", Element("skiros:Arm"), ParamTypes.Required)
        self.addParam("Table", Element("skiros:Table"), ParamTypes.Required)
        self.addParam("Bin", Element("skiros:Bin"), ParamTypes.Required)
        self.addParam("Retries", 1, ParamTypes.Optional, description="retries per object (RetryOnFail); 0: none")


# -- primitives -----------------------------------------------------------------------
class locate(PrimitiveBase):
    """Writes what the robot sees into the world model, and finishes when its replica
    shows it all.

    With a depth camera (the process's depth_camera interface) it asks for one capture,
    finds the objects on the Location in the cloud (skillbus.perception.segment) and
    writes their perceived poses: each matched to the world model's object on the
    Location nearest to it (skillbus.skills.perceived); one that matches none is added as
    a new product on the Location.

    Otherwise every object the camera interface reports (detections by name, such as the
    physics server's perfect camera) is written with its pose: known elements (by label)
    are updated, and moved into what the camera sees them rest on (its support, by label:
    a table, a bin, the gripper) when the world model says otherwise; unknown ones are
    added as products contained in the Location."""

    CLOUD_TIMEOUT_S = 2.0  # sim time from the request to the whole cloud

    def createDescription(self):
        self.setDescription(Locate(), "locate")

    def onStart(self):
        self.depth = depth_service.depth_camera()
        self.camera = None if self.depth is not None else camera_service.camera()
        self.request: str | None = None
        self.asked_at = 0.0
        self.expected: dict[str, tuple] = {}
        self.adding: dict[int, tuple] = {}  # lockstep: request id -> (name, position, orientation)
        self.added: list[str] = []
        self.started = False
        return True

    def _add(self, name: str, p: tuple, q: tuple, location: str) -> None:
        new = Element("skiros:Product", name)
        if self.wmi.participant is None:  # wall clock: committed at once, with the relation
            new.addRelation(location, "skiros:contain", "-1")
            eid = self.wmi.add_element(new).id
            set_world_pose(self.wmi, eid, p, q)
            self.expected[eid] = (p, None)
        else:  # lockstep: the id comes with the transaction's result, a few frames later
            self.adding[self.wmi.commit_async([op(wm_op_t.ADD_ELEMENT, element=new)])] = (name, p, q)
        self.added.append(name)

    def _move(self, eid: str, support: Element, p: tuple, q: tuple) -> None:
        """The camera sees `eid` resting on (or held by) another element than the world
        model says: a restart, a drop or a crash left the world model behind. The
        containment and the pose change in one write. Held by a gripper: the gripper's pose
        is the tool's now (the arm state), written with it, so a later release carries the
        object from where the tool really holds it."""
        tool = arm_service.tool_pose() if support.type.endswith("Gripper") else None
        if tool is None:
            reparent(self.wmi, eid, support.id, (p, q))
            return
        self.wmi.write([world_pose_op(self.wmi, support.id, *tool),
                        *reparent_ops(self.wmi, eid, support.id, (p, q), parent_pose=tool)])

    def _perceive(self, location: str):
        """The depth camera's path: ask, wait for the cloud, find and match the objects
        and write them. Returns the skill's state while that is not done, else None."""
        if not self.started:
            self.started = True
            self.request = self.depth.camera.request(self.depth.name)
            self.asked_at = tick_context.now_s()
            return self.step(f"capturing with camera {self.depth.name}")
        if self.request is None:
            return None
        try:
            cloud = self.depth.camera.answer(self.request)
        except CameraError as e:
            return self.fail(f"locate: camera {self.depth.name} refused the capture: {e}", -1)
        if cloud is None:
            if tick_context.now_s() - self.asked_at > self.CLOUD_TIMEOUT_S:
                return self.fail(f"locate: no cloud from camera {self.depth.name} within {self.CLOUD_TIMEOUT_S} s "
                                 f"of sim time (is it in the physics server's scene?)", -1)
            return self.step(f"waiting for camera {self.depth.name}'s cloud")
        self.request = None
        radius = float(self.params["Radius"].value)
        try:
            seen = detect(cloud, noise_m=self.depth.noise_m, around=world_pose(self.wmi, location)[0][:2],
                          radius=radius)
        except SegmentError as e:
            return self.fail(f"locate: {e}", -1)
        known = []
        for r in self.wmi.get_relations(location, "skiros:contain", ""):  # (what the Location holds)
            e = self.wmi.get_element(r["dst"])
            size = e.getProperty("skiros:Size").value if e.hasProperty("skiros:Size") else None
            known.append(Known(e.id, world_pose(self.wmi, e.id)[0], float(size) if size is not None else None))
        m = match(known, seen.detections)
        for k, d in m.matches:
            set_world_pose(self.wmi, k.id, d.position, d.quaternion())
            self.expected[k.id] = (d.position, None)
        for d in m.new:
            self._add(f"object-{round(d.position[0] * 1000)}-{round(d.position[1] * 1000)}", d.position,
                      d.quaternion(), location)
        if not self.expected and not self.adding:
            return self.fail(f"located nothing (camera {self.depth.name} sees no objects on the support at "
                             f"z {seen.support_z:.3f} m)", -1)
        self.unseen = [k.id for k in m.unseen]
        return self.step(f"writing {len(self.expected) + len(self.adding)} perceived pose(s)")

    def execute(self):
        location = self.params["Location"].value.id
        if self.depth is not None:
            state = self._perceive(location)
            if state is not None:
                return state
        elif not self.started:
            self.started = True
            by_label = {e.label: e for e in self.wmi.get_elements() if e.label}
            for o in self.camera.objects():
                p, q = tuple(o.pose[:3]), tuple(o.pose[3:])
                e = by_label.get(o.name)
                if e is None:
                    self._add(o.name, p, q, location)
                    continue
                support = by_label.get(o.support) if o.support else None
                if support is not None and support.id != e.id and parent_of(self.wmi, e.id) != support.id:
                    self._move(e.id, support, p, q)
                    self.expected[e.id] = (p, support.id)
                else:
                    set_world_pose(self.wmi, e.id, p, q)
                    self.expected[e.id] = (p, None)
            if not self.expected and not self.adding:
                return self.fail("located nothing (the camera sees no objects)", -1)
            return self.step(f"writing {len(self.expected) + len(self.adding)} object pose(s)")
        for rid, (name, p, q) in list(self.adding.items()):
            r = self.wmi.results.get(rid)
            if r is None:
                continue
            if r.error or not r.ids:
                return self.fail(f"locate: the world model refused {name}: {r.error}", -1)
            eid = r.ids[0]
            try:
                self.wmi.get_element(eid)
            except Exception:
                continue  # the change has not reached the replica yet
            reparent(self.wmi, eid, location, (p, q))  # the containment and the pose in it, in one write
            self.expected[eid] = (p, location)
            del self.adding[rid]
        if self.adding:
            return self.step(f"adding {', '.join(n for n, _, _ in self.adding.values())} to the world model")
        # Done when the replica shows every pose and every containment written: the skill
        # after this one (TransferProducts) decides from the containments.
        for eid, (p, parent) in self.expected.items():
            try:
                got, _ = world_pose(self.wmi, eid)
            except Exception:  # not in the replica yet
                return self.step(f"waiting for the world model to show {eid}")
            if max(abs(a - b) for a, b in zip(got, p)) > 1e-4 or (parent and parent_of(self.wmi, eid) != parent):
                return self.step(f"waiting for the world model to show {eid}")
        extra = f"; new: {', '.join(self.added)}" if self.added else ""
        if getattr(self, "unseen", None):
            extra += f"; not seen: {', '.join(self.unseen)}"
        return self.success(f"located {len(self.expected)} object(s){extra}")


class NoSpot(RuntimeError):
    pass


def free_spot(location: str, origin: tuple, footprint: float) -> tuple[float, float]:
    """The first free spot for a footprint in a bin (BIN_RADIUS around its origin, from
    BIN_FLOOR_CLEAR over its floor up by the footprint), by the occupancy map as of this
    tick's frame: the same on every run, and the same for every move of one placing (the
    map changes only when a cloud comes in, at a Locate)."""
    world = map_service.occupancy_map()
    if world is None:
        raise NoSpot("Spot needs the occupancy map: --interface map=skillbus.perception.map_client")
    lo = (origin[0] - BIN_RADIUS, origin[1] - BIN_RADIUS, origin[2] + BIN_FLOOR_CLEAR)
    hi = (origin[0] + BIN_RADIUS, origin[1] + BIN_RADIUS, origin[2] + BIN_FLOOR_CLEAR + footprint)
    spots = world.free_spots(lo, hi, (footprint, footprint), clearance=SPOT_CLEARANCE)
    if not spots:
        raise NoSpot(f"no free spot in {location} for a {footprint * 100:.1f} cm footprint (the occupancy map: "
                     f"every place occupied or not seen)")
    return spots[0][0], spots[0][1]


def held_box(wmi: Any, arm_id: str) -> tuple[float, float, float]:
    """The sides (m) of what the gripper of the arm's robot holds, by the world model (a
    cube of its Size); zeros when it holds nothing, or nothing with a Size."""
    for robot in [r["src"] for r in wmi.get_relations("", "skiros:hasA", arm_id)]:
        for part in [r["dst"] for r in wmi.get_relations(robot, "skiros:hasA", "")]:
            for held in [r["dst"] for r in wmi.get_relations(part, "skiros:contain", "")]:
                e = wmi.get_element(held)
                if e.hasProperty("skiros:Size") and e.getProperty("skiros:Size").value:
                    side = float(e.getProperty("skiros:Size").value)
                    return (side, side, side)
    return (0.0, 0.0, 0.0)


class _ArmMotion(PrimitiveBase):
    """Plans with the motion service, sends the trajectory, waits until the arm settles."""

    def createDescription(self):  # bound by the subclasses
        raise NotImplementedError

    def onStart(self):
        self.arm = arm_service.arm()
        self.cmd = None
        self.started_at = tick_context.now_s()
        return True

    def target(self) -> tuple[list[float], bool, str]:
        raise NotImplementedError

    def execute(self):
        if self.cmd is None:
            try:
                pose, cartesian, what = self.target()
            except NoSpot as e:
                return self.fail(f"{self.label}: {e}", -1)
            except RpcError as e:
                return self.fail(f"{self.label}: the occupancy map did not answer ({e})", -5)
            try:
                plan = self.arm.plan(pose, cartesian, held=held_box(self.wmi, self.params["Arm"].value.id))
            except RpcError as e:  # named here, within the tick, not as a tick that never returned
                return self.fail(f"{self.label} to {what}: the motion service did not answer ({e})", -5)
            if not plan.ok:
                return self.fail(f"{self.label} to {what}: {plan.error}", -1)
            self.cmd = command_id(self.label)
            self.what = what
            self.arm.execute(plan, self.cmd)
            return self.step(f"moving to {what}")
        gone = self.arm.silence()
        if gone:  # name the fault now, not as a move that never arrives
            return self.fail(f"{self.label}: {gone}; {self._stop()}", -4)
        done, error = self.arm.finished(self.cmd)
        if error:
            self.stopped = True  # (refused: nothing moves, nothing to stop)
            return self.fail(f"{self.label}: the robot rejected the trajectory: {error}", -2)
        if done:
            return self.success(f"at {self.what}")
        if tick_context.now_s() - self.started_at > MOVE_TIMEOUT_S:
            return self.fail(f"{self.label}: not at {self.what} after {MOVE_TIMEOUT_S:.0f} s; {self._stop()}", -3)
        # Nothing to do before the trajectory's end: no tick until then (the manager still
        # stops or preempts this skill at once).
        until = self.arm.not_done_before(self.cmd)
        if until is not None:
            self.idle_until(min(until, self.started_at + MOVE_TIMEOUT_S))
        return self.step(f"moving to {self.what}")

    def _stop(self) -> str:
        """Holds the arm where it is (once): a failed move must not go on playing its
        trajectory with no skill watching it. What it did, for the failure's message."""
        if self.cmd is None or getattr(self, "stopped", False):
            return ""
        self.stopped = True
        try:
            self.arm.hold(command_id(f"{self.label}-hold"))
        except Exception as e:
            return f"the arm could not be stopped: {e}"
        return "the arm was stopped where it was"

    def onEnd(self):
        """Ended by an exception in execute() (the skill process then fails it): the arm is
        stopped as on any failure on the way, and the log says so (the failure's message is
        the exception's)."""
        if self.state != State.Success and getattr(self, "cmd", None) is not None:
            said = self._stop()
            if said:
                log.warning("%s ended by a failure: %s", self.label, said)
        return True

    def onPreempt(self):
        """Stopped (`skillbus stop`, a broken hold-condition, a parent preempted): the arm
        holds where it is instead of going on with the trajectory."""
        if self.cmd is None:
            return self.fail(f"preempted: {self.label} had not moved yet", -1)
        said = self._stop()
        return self.fail(f"preempted: {self.label} on the way to {self.what}: {said or 'stopped already'}", -1)


class move_arm(_ArmMotion):
    def createDescription(self):
        self.setDescription(MoveArm(), "move_arm")

    def target(self):
        t = self.params["Target"].value
        h = float(self.params["Height"].value)
        p, q = world_pose(self.wmi, t.id)
        spot = float(self.params["Spot"].value)
        where = f"{h * 100:.1f} cm above {t.id}"
        if spot > 0:
            x, y = free_spot(t.id, p, spot)
            p = (x, y, p[2])
            where = f"{h * 100:.1f} cm above a free spot of {t.id} ({x:.3f}, {y:.3f})"
        pose = [p[0], p[1], p[2] + h, *top_down(fold(yaw_of(q)))]
        return pose, bool(self.params["Cartesian"].value), where


class lift_arm(_ArmMotion):
    def createDescription(self):
        self.setDescription(LiftArm(), "lift_arm")

    def target(self):
        tool = list(self.arm.state.tool_pose)
        h = float(self.params["Height"].value)
        tool[2] += h
        return tool, True, f"{h * 100:.1f} cm higher"


# -- compounds ------------------------------------------------------------------------
class pick(SkillBase):
    def createDescription(self):
        self.setDescription(Pick(), "pick")

    def expand(self, skill):
        skill.setProcessor(SerialStar())
        skill(
            self.skill("MoveArm", "", remap={"Target": "Object"}, specify={"Height": APPROACH}),
            self.skill("GripperOpen", ""),
            self.skill("MoveArm", "", remap={"Target": "Object"}, specify={"Height": GRASP_HEIGHT, "Cartesian": True}),
            self.skill("Grasp", ""),
            self.skill("LiftArm", "", specify={"Height": LIFT}),
        )


class place(SkillBase):
    def createDescription(self):
        self.setDescription(Place(), "place")

    def expand(self, skill):
        # With an occupancy map: down into the location over a free spot of it, released
        # just above its floor (objects side by side), and back up out of it; else
        # released over its origin from BIN_RELEASE.
        spot, release, lift = 0.0, BIN_RELEASE, LIFT
        if map_service.occupancy_map() is not None:
            obj = self.params["Object"].value
            size = obj.getProperty("skiros:Size").value if obj.hasProperty("skiros:Size") else None
            spot, release = float(size) if size else 0.05, BIN_RELEASE_AT_SPOT
            lift = BIN_ABOVE - release
        skill.setProcessor(SerialStar())
        skill(
            self.skill("MoveArm", "", remap={"Target": "Location"}, specify={"Height": BIN_ABOVE, "Spot": spot}),
            self.skill("MoveArm", "", remap={"Target": "Location"},
                       specify={"Height": release, "Cartesian": True, "Spot": spot}),
            self.skill("Release", ""),
            self.skill("LiftArm", "", specify={"Height": lift}),
            # The object fell from the fingers (released BIN_RELEASE above the location's
            # origin): the world model learns where it landed from an observation.
            self.skill("Locate", "", specify={"Radius": BIN_RADIUS}),
        )


class transfer_products(SkillBase):
    """Every product the world model has in From into To, each Pick-and-Place retried on
    failure (RetryOnFail(Retries)); a product the Gripper already holds (a task or an
    attempt cut short by a fault left it there) is placed without a Pick. The products are read when this skill
    starts, so a Locate just before it decides them."""

    def createDescription(self):
        self.setDescription(TransferProducts(), "transfer_products")

    def expand(self, skill):
        gripper = self.params["Gripper"].value
        source = self.params["From"].value
        retries = int(self.params["Retries"].value)

        def contents(eid: str) -> list[str]:
            return [r["dst"] for r in self.wmi.get_relations(eid, "skiros:contain", "")] if self.wmi else []

        def retried(node):
            return self.skill(RetryOnFail(retries))(node) if retries > 0 else node

        steps = []
        for oid in contents(gripper.id):
            obj = self.wmi.get_element(oid)
            steps.append(retried(self.skill("Place", "", remap={"Location": "To"}, specify={"Object": obj})))
        for oid in contents(source.id):
            obj = self.wmi.get_element(oid)
            # Place it if the gripper holds it, else Pick and Place it: an attempt that
            # failed after the grasp (a release cut short by a gripper fault) leaves the
            # product in the gripper, where a second Pick would fail its NotHolding
            # pre-condition. SelectorStar: the choice is made once per attempt.
            steps.append(retried(self.skill(SelectorStar())(
                self.skill("Place", "", remap={"Location": "To"}, specify={"Object": obj}),
                self.skill(SerialStar())(
                    self.skill("Pick", "", specify={"Object": obj}),
                    self.skill("Place", "", remap={"Location": "To"}, specify={"Object": obj}),
                ),
            )))
        skill.setProcessor(SerialStar())
        skill(*steps)


class clear_table(SkillBase):
    """Locate (which also tells the world model what rests where, so a world model left
    behind by a fault agrees with what is seen), then every product on the table into the
    bin (TransferProducts, which decides the products after that Locate, and first places
    one still in the gripper), then Locate again for the final poses."""

    def createDescription(self):
        self.setDescription(ClearTable(), "clear_table")

    def expand(self, skill):
        skill.setProcessor(SerialStar())
        skill(
            self.skill("Locate", "", remap={"Location": "Table"}),
            self.skill("TransferProducts", "", remap={"From": "Table", "To": "Bin"}),
            self.skill("Locate", "", remap={"Location": "Bin"}, specify={"Radius": BIN_RADIUS}),
        )
