"""The one primitive behind the gripper skills (skillbus.skills.gripper), in its own
module so that the library registers only its three bindings."""

from __future__ import annotations

from skillbus import tick_context
from skillbus.can import cia402 as c
from skillbus.can import gripper_service
from skillbus.can.driver import GripperError
from skillbus.robot import arm as arm_service
from skillbus.skill import PrimitiveBase
from skillbus.world import poses

OPEN_UM, CLOSED_UM = 80_000, 0
TIMEOUT_S = 10.0
# While the fingers open, the primitive is not ticked before they could be open
# (PrimitiveBase.idle_until), but at most FAULT_NOTICE_S at a time: a device fault, a lost
# heartbeat or a gone bus on the way still fails the skill within that much sim time.
FAULT_NOTICE_S = 0.2
# What the arrival estimate leaves out, taken off it: the status's position is a TPDO that
# moves in steps of 0x2001 (50 um) and the ticks' grid; a tenth of a second is ample.
ARRIVAL_MARGIN_S = 0.1


class GripperPrimitive(PrimitiveBase):
    """The one implementation behind the three gripper skills."""

    def createDescription(self):  # each binding sets its description
        raise NotImplementedError

    def onStart(self):
        try:
            self.gripper = gripper_service.driver()
        except GripperError as e:
            self.message = str(e)
            return False
        self.command = self.params["Command"].value
        if self.command not in ("open", "close", "grasp", "release"):
            self.message = f"unknown gripper command {self.command!r} (open, close, grasp or release)"
            return False
        self.sent = False
        self.written = False
        self.recovering = ""  # the device fault this command found and asked to clear
        self.started_at = tick_context.now_s()
        return True

    def execute(self):
        cmd = self.command
        if tick_context.now_s() - self.started_at > TIMEOUT_S:
            return self.fail(f"{cmd}: no result within {TIMEOUT_S:.0f} s", -2)
        s = self.gripper.status()
        device_only = bool(s.faults) and all(f.startswith("EMCY ") for f in s.faults)  # (the status this tick sees)
        if device_only and not self.sent and not self.recovering:
            # A device fault an earlier command left (a following error, a task cut short by
            # a fault): this command starts by clearing it, as an operator would; a fault
            # that comes back, or one of the bus or the heartbeat, fails it.
            self.recovering = s.faults[-1]
            self.gripper.request_recovery()
            return self.step(f"{cmd}: clearing the gripper fault an earlier command left ({self.recovering})")
        if s.faults and not (self.recovering and not self.sent and s.faults[-1] == self.recovering):
            return self.fail(f"{cmd}: gripper fault: {s.faults[-1]}", -3)
        if s.faults:
            return self.step(f"{cmd}: clearing the gripper fault ({self.recovering})")
        if s.state != c.OPERATION_ENABLED:
            return self.step(f"{cmd}: waiting for the gripper (state {s.state})")
        if not self.sent:
            try:
                self.gripper.command(OPEN_UM if cmd in ("open", "release") else CLOSED_UM)
            except GripperError as e:  # the bus is gone (the supervision names it a moment later)
                return self.fail(f"{cmd}: gripper fault: {e}", -3)
            self.sent = True
            return self.step(f"{cmd}: sent")
        width = f"{s.position_um / 1000:.1f} mm"
        if not s.fresh or s.moving:
            if s.fresh:
                self._idle_while_travelling(s.position_um)
            return self.step(f"{cmd}: moving, width {width}")
        if cmd == "release":
            if not s.target_reached:
                return self.step(f"release: width {width}")
            obj, location = self.params["Object"].value, self.params["Location"].value
            return self._contained(obj, location, f"release: {location.id} contains {obj.id}",
                                   f"release: opened at {width}")
        if cmd != "grasp":
            if s.target_reached:
                return self.success(f"{cmd}: width {width}" + (", holding an object" if s.gripped else ""))
            return self.step(f"{cmd}: width {width}")
        if not s.gripped:
            return self.fail(f"grasp: nothing gripped (the fingers closed to {width})", -1)
        gripper, obj = self.params["Gripper"].value, self.params["Object"].value
        return self._contained(obj, gripper, f"grasp: {gripper.id} holds {obj.id} at {width}",
                               f"grasp: holding {obj.id or obj.label} at {width}")

    def _idle_while_travelling(self, position_um: int) -> None:
        """Fingers opening: the earliest a tick could find them open is after the travel
        left at the speed the driver set (0x6081: the device never moves faster), less
        ARRIVAL_MARGIN_S; no tick before then, FAULT_NOTICE_S at most at a time. The
        status's lag cancels out: the position it shows and the arrival it will show are
        equally late. Fingers that stop on something on the way (a bin's wall) end the
        command there, which the skill then sees FAULT_NOTICE_S late at most, as it does a
        fault. A close or a grasp is ticked as always: it ends where the fingers touch
        something, which may be at any width (a box is wider across the fingers than its
        side when it is turned or tilted)."""
        velocity = float(getattr(self.gripper, "velocity", 0) or 0)  # um/s
        if self.command not in ("open", "release") or velocity <= 0:
            return
        now = tick_context.now_s()
        arrival = now + (OPEN_UM - position_um) / velocity - ARRIVAL_MARGIN_S
        if arrival > now:
            self.idle_until(min(arrival, now + FAULT_NOTICE_S, self.started_at + TIMEOUT_S))

    def onPreempt(self):
        """Stopped: fingers that are moving halt where they are (CiA 402 halt). Fingers that
        grip an object keep their grip: dropping what the robot holds is no way to stop."""
        cmd = self.command
        if not self.sent:
            return self.fail(f"preempted: {cmd} had not moved the fingers", -1)
        s = self.gripper.status()
        if s.gripped:
            return self.fail(f"preempted: {cmd}: the fingers keep their grip", -1)
        try:
            self.gripper.stop()
        except GripperError as e:
            return self.fail(f"preempted: {cmd}: the fingers could not be stopped: {e}", -1)
        return self.fail(f"preempted: {cmd} stopped the fingers at {s.position_um / 1000:.1f} mm", -1)

    def _contained(self, obj, parent, done: str, without_wm: str):
        """Writes that `parent` contains `obj`, with its pose (once), and succeeds when this
        process's replica shows it, so the manager's post-condition sees it too."""
        if self.wmi is None:
            return self.success(f"{without_wm} (no world model)")
        if not self.written:
            self.wmi.write(self._containment_ops(obj.id, parent.id))
            self.written = True
        if self.wmi.get_relations(parent.id, "skiros:contain", obj.id):
            return self.success(done)
        return self.step(f"{self.command}: writing that {parent.id} contains {obj.id}")

    def _containment_ops(self, oid: str, parent: str) -> list:
        """One transaction: the new container and the object's pose in it.

        The gripper's frame is the tool's (the arm state's tool pose: the robot's own
        joints, not a camera). A grasp writes the gripper's pose (the tool pose now) and
        the object's pose relative to it (the grasp offset, from the object's world pose in
        the world model). A release puts the object where the tool has carried it: the
        tool pose now composed with that offset, relative to the location (and writes the
        gripper's pose again). So the world model never holds a pose relative to the old
        container under the new one. Where it falls from there is for an observation to
        say (Place ends with Locate).

        In a process without an arm (no ``--arm``) the tool pose is unknown: the object
        keeps the world pose the world model has for it (where it was grasped), which is
        stale after a carry but never a phantom made of another container's numbers."""
        gripper = self.params["Gripper"].value.id
        tool = arm_service.tool_pose()
        if tool is None:
            return poses.reparent_ops(self.wmi, oid, parent)
        ops = [poses.world_pose_op(self.wmi, gripper, *tool)]
        if self.command == "grasp":
            return ops + poses.reparent_ops(self.wmi, oid, parent, parent_pose=tool)
        if poses.parent_of(self.wmi, oid) == gripper:  # released: carried by the tool
            world = poses.compose(tool, poses.local_pose(self.wmi.get_element(oid)))
        else:  # the world model did not know it was held: it stays where it is
            world = poses.world_pose(self.wmi, oid)
        return ops + poses.reparent_ops(self.wmi, oid, parent, world)

