"""The data codes of ``Element.getData / setData / hasData``: SkiROS2's spatial reasoner
(AauSpatialReasoner, in skiros2_std_reasoners) reads and writes an element's pose and size
properties through them. Here they work on the properties alone, without ROS or tf.

=====================  ====================================================================
code                   value (getData returns it, setData takes it)
=====================  ====================================================================
``:Position``          ``[x, y, z]`` (skiros:PositionX/Y/Z; None for an unset one)
``:Orientation``       ``[x, y, z, w]``, a quaternion (skiros:OrientationX/Y/Z/W)
``:OrientationEuler``  ``[roll, pitch, yaw]`` in radians (static x, y, z axes, as tf's default)
``:Size``              ``[x, y, z]`` (skiros:SizeX/Y/Z)
``:Pose``              ``(position, orientation)``: the two lists above
``:PoseMsg``           a ``Pose`` named tuple (SkiROS2: geometry_msgs/Pose)
``:PoseStampedMsg``    a ``PoseStamped`` (SkiROS2: geometry_msgs/PoseStamped)
``:TransformMsg``      a ``TransformStamped`` (SkiROS2: geometry_msgs/TransformStamped)
=====================  ====================================================================

Where SkiROS2 returns a ROS message, the named tuples below have the message's field
names, so ``e.getData(":PoseStampedMsg").pose.position.x`` reads as with ROS, yet they are
plain tuples (``position, orientation = e.getData(":PoseMsg")``). A header's ``frame_id``
is skiros:BaseFrameId and its ``stamp`` is skiros:TfTimeStamp in seconds (a float with
ROS 1's ``to_sec()``); ``child_frame_id`` is skiros:FrameId. setData takes these tuples,
ROS messages (anything with those field names) or plain nested sequences.

Unlike SkiROS2, setData converts ints to float (SkiROS2 drops an int, logging an error)
and adds only the properties it writes (SkiROS2 also adds FrameId, BaseFrameId, PublishTf
and TfTimeStamp). Note that skillbus keeps an element's pose relative to the element that
contains it (skiros:contain), whatever skiros:BaseFrameId says: skillbus.world.poses gives
poses in the world frame.

    >>> from skillbus.world.element import Element
    >>> e = Element("skiros:Cube")
    >>> e.hasData(":Pose")
    False
    >>> e.setData(":Pose", ([0.1, 0.2, 0.3], [0.0, 0.0, 0.0, 1.0]))
    >>> e.getData(":Position"), e.hasData(":Pose")
    ([0.1, 0.2, 0.3], True)
    >>> e.getData(":PoseMsg").position.z
    0.3
    >>> e.setData(":OrientationEuler", [0.0, 0.0, 1.5707963267948966])
    >>> [round(c, 4) for c in e.getData(":Orientation")]
    [0.0, 0.0, 0.7071, 0.7071]
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

POSITION = ("skiros:PositionX", "skiros:PositionY", "skiros:PositionZ")
ORIENTATION = ("skiros:OrientationX", "skiros:OrientationY", "skiros:OrientationZ", "skiros:OrientationW")
SIZE = ("skiros:SizeX", "skiros:SizeY", "skiros:SizeZ")
BASE_FRAME, FRAME, STAMP = "skiros:BaseFrameId", "skiros:FrameId", "skiros:TfTimeStamp"

CODES = (":Position", ":Orientation", ":OrientationEuler", ":Size", ":Pose", ":PoseMsg", ":PoseStampedMsg",
         ":TransformMsg")


class Point(NamedTuple):
    x: Any
    y: Any
    z: Any


class Quaternion(NamedTuple):
    x: Any
    y: Any
    z: Any
    w: Any


class Pose(NamedTuple):
    position: Point
    orientation: Quaternion


class Stamp(float):
    """Seconds; ``to_sec()`` as ROS 1's rospy.Time has it."""

    def to_sec(self) -> float:
        return float(self)


class Header(NamedTuple):
    frame_id: str
    stamp: Stamp


class PoseStamped(NamedTuple):
    header: Header
    pose: Pose


class Transform(NamedTuple):
    translation: Point
    rotation: Quaternion


class TransformStamped(NamedTuple):
    header: Header
    child_frame_id: str
    transform: Transform


# -- reading -------------------------------------------------------------------------------
def _values(e: Any, keys: tuple[str, ...]) -> list:
    return [e.getProperty(k).value if e.hasProperty(k) else None for k in keys]


def _all_set(e: Any, keys: tuple[str, ...]) -> bool:
    return all(e.hasProperty(k, not_none=True) for k in keys)


def _text(e: Any, key: str) -> str:
    return str(e.getProperty(key).value) if e.hasProperty(key, not_none=True) else ""


def _header(e: Any) -> Header:
    stamp = e.getProperty(STAMP).value if e.hasProperty(STAMP, not_none=True) else 0.0
    return Header(_text(e, BASE_FRAME), Stamp(stamp))


def _pose(e: Any) -> Pose:
    return Pose(Point(*_values(e, POSITION)), Quaternion(*_values(e, ORIENTATION)))


def has_data(e: Any, code: str) -> bool:
    if code == ":Position":
        return _all_set(e, POSITION)
    if code in (":Orientation", ":OrientationEuler"):
        return _all_set(e, ORIENTATION)
    if code == ":Size":
        return _all_set(e, SIZE)
    if code in (":Pose", ":PoseMsg", ":PoseStampedMsg", ":TransformMsg"):
        return _all_set(e, POSITION) and _all_set(e, ORIENTATION)
    raise _unknown(code)


def get_data(e: Any, code: str) -> Any:
    if code == ":Position":
        return _values(e, POSITION)
    if code == ":Orientation":
        return _values(e, ORIENTATION)
    if code == ":OrientationEuler":
        q = _values(e, ORIENTATION)
        return None if None in q else list(euler_from_quaternion(q))
    if code == ":Size":
        return _values(e, SIZE)
    if code == ":Pose":
        return _values(e, POSITION), _values(e, ORIENTATION)
    if code == ":PoseMsg":
        return _pose(e)
    if code == ":PoseStampedMsg":
        return PoseStamped(_header(e), _pose(e))
    if code == ":TransformMsg":
        p = _pose(e)
        return TransformStamped(_header(e), _text(e, FRAME) or e.id, Transform(p.position, p.orientation))
    raise _unknown(code)


# -- writing -------------------------------------------------------------------------------
def _field(obj: Any, name: str, index: int) -> Any:
    """A message's field by name, or a plain sequence's item by position."""
    return getattr(obj, name) if hasattr(obj, name) else obj[index]


def _xyz(v: Any, names: str) -> list:
    return [_field(v, n, i) for i, n in enumerate(names)]


def _seconds(stamp: Any) -> float:
    if hasattr(stamp, "to_sec"):  # ROS 1 rospy.Time (and Stamp)
        return float(stamp.to_sec())
    if hasattr(stamp, "sec"):  # ROS 2 builtin_interfaces/Time
        return stamp.sec + stamp.nanosec * 1e-9
    return float(stamp)


def _set(e: Any, keys: tuple[str, ...], values: Any) -> None:
    values = list(values)
    if len(values) != len(keys):
        raise ValueError(f"{len(keys)} values expected for {', '.join(keys)}, got {values!r}")
    for k, v in zip(keys, values):
        e.setProperty(k, float(v), "xsd:float")


def _set_pose(e: Any, pose: Any) -> None:
    _set(e, POSITION, _xyz(_field(pose, "position", 0), "xyz"))
    _set(e, ORIENTATION, _xyz(_field(pose, "orientation", 1), "xyzw"))


def _set_header(e: Any, header: Any) -> None:
    e.setProperty(BASE_FRAME, str(_field(header, "frame_id", 0)))
    e.setProperty(STAMP, _seconds(_field(header, "stamp", 1)), "xsd:float")


def set_data(e: Any, code: str, data: Any) -> None:
    if code == ":Position":
        _set(e, POSITION, data)
    elif code == ":Orientation":
        _set(e, ORIENTATION, data)
    elif code == ":OrientationEuler":
        _set(e, ORIENTATION, quaternion_from_euler(*data))
    elif code == ":Size":
        _set(e, SIZE, data)
    elif code in (":Pose", ":PoseMsg"):
        _set_pose(e, data)
    elif code == ":PoseStampedMsg":
        _set_header(e, _field(data, "header", 0))
        _set_pose(e, _field(data, "pose", 1))
    elif code == ":TransformMsg":
        _set_header(e, _field(data, "header", 0))
        t = _field(data, "transform", 2)
        _set(e, POSITION, _xyz(_field(t, "translation", 0), "xyz"))
        _set(e, ORIENTATION, _xyz(_field(t, "rotation", 1), "xyzw"))
    else:
        raise _unknown(code)


def _unknown(code: str) -> KeyError:
    # SkiROS2 raises KeyError for a code no reasoner claims; its relation codes (":pX",
    # Allen's interval relations per axis) are not implemented here.
    return KeyError(f"no data code {code!r} (known: {', '.join(CODES)})")


# -- angles (tf's "sxyz": roll about x, then pitch about y, then yaw about z, static axes) ---
def quaternion_from_euler(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy, cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy)


def euler_from_quaternion(q: Any) -> tuple[float, float, float]:
    x, y, z, w = (float(c) for c in q)
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw
