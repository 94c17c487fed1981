"""Putting a capture back together from its parts (skillbus.perception.cloud), and the
depth camera client's bookkeeping, without processes (memq://)."""

from __future__ import annotations

import numpy as np
import pytest

from skillbus.bus import open_raw_bus
from skillbus.msgs import camera_cloud_t
from skillbus.perception.cloud import CloudAssembler, CloudError
from skillbus.perception.depth_camera import CameraError, DepthCamera, cloud_channel

W, H = 4, 5


def parts(rows_per_part=2, capture=0, request_id="", pose=(1.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0)):
    """A W x H capture whose point (v, u) is (u, v, 1 + v) in the optical frame, pixel (0, 1) no return."""
    pts = np.array([[[u, v, 1.0 + v] for u in range(W)] for v in range(H)], dtype="<f4")
    pts[0, 1] = np.nan
    out = []
    starts = list(range(0, H, rows_per_part))
    for i, r in enumerate(starts):
        m = camera_cloud_t()
        m.camera, m.request_id, m.capture, m.error = "cam", request_id, capture, ""
        m.width, m.height, m.intrinsics, m.pose = W, H, [10.0, 10.0, 1.5, 2.0], list(pose)
        m.range = [0.05, 3.0]
        m.part, m.num_parts, m.row_start = i, len(starts), r
        m.num_rows = min(rows_per_part, H - r)
        m.points = pts[r:r + m.num_rows].tobytes()
        m.num_bytes = len(m.points)
        m.robot_mask = bytes((m.num_rows * W + 7) // 8)
        m.num_mask_bytes = len(m.robot_mask)
        out.append(m)
    return out, pts


def test_parts_in_any_order_give_the_organized_cloud_and_its_world_points():
    ps, pts = parts()
    a = CloudAssembler()
    assert a.add(ps[2]) is None and a.add(ps[0]) is None
    cloud = a.add(ps[1])
    assert cloud is not None and cloud.points.shape == (H, W, 3)
    assert np.array_equal(cloud.points, pts, equal_nan=True)
    assert cloud.returns == W * H - 1
    world = cloud.world_points()  # identity rotation: shifted by the pose's position
    assert world.shape == (W * H - 1, 3)
    assert world[0].tolist() == [1.0, 2.0, 4.0] and world[1].tolist() == [3.0, 2.0, 4.0]  # (pixel (0, 1) skipped)


def test_a_rotated_camera_maps_its_view_axis_into_the_world():
    # Looking straight down: a half turn about x (optical z = world -z).
    ps, _ = parts(pose=(0.0, 0.0, 2.0, 1.0, 0.0, 0.0, 0.0))
    a = CloudAssembler()
    cloud = [c for c in (a.add(p) for p in ps) if c is not None][0]
    world = cloud.world_points()
    assert world[0].tolist() == pytest.approx([0.0, 0.0, 1.0])  # (u 0, v 0, z 1) -> 1 m below the camera


@pytest.mark.parametrize("field,value,why", [
    ("num_bytes", 7, "bytes of points"),
    ("row_start", 4, "rows 4..5 of a 5-row image"),
    ("part", 3, "part 3 of 3"),
    ("width", 0, "is no image size"),
    ("intrinsics", [0.0, 10.0, 1.0, 1.0], "focal length"),
    ("pose", [float("nan")] * 7, "not finite"),
    ("range", [0.5, 0.5], "not 0 < near < far"),
    ("num_mask_bytes", 9, "bytes of robot mask"),
])
def test_a_part_that_cannot_be_is_refused_saying_why(field, value, why):
    ps, _ = parts()
    setattr(ps[1], field, value)
    with pytest.raises(CloudError, match=why):
        CloudAssembler().add(ps[1])


def test_parts_that_disagree_or_leave_rows_out_are_refused():
    ps, _ = parts()
    other, _ = parts(pose=(9.0, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0))
    a = CloudAssembler()
    a.add(ps[0])
    with pytest.raises(CloudError, match="does not match its other parts"):
        a.add(other[1])
    gap, _ = parts()
    gap[1].row_start = 3  # rows 3..4 twice, row 2 never
    gap[1].num_rows = 2
    b = CloudAssembler()
    b.add(gap[0]), b.add(gap[1])
    with pytest.raises(CloudError, match="starts at row"):
        b.add(gap[2])


def test_incomplete_captures_are_bounded():
    a = CloudAssembler(keep=2)
    for capture in range(5):
        a.add(parts(capture=capture)[0][0])
    assert len(a._open) == 2


def test_the_client_answers_its_own_requests_and_keeps_the_latest_of_each_camera():
    bus = open_raw_bus("memq://")
    cam = DepthCamera(bus, name="me")
    rid = cam.request("cam")
    assert rid.startswith("me:") and rid.endswith("-1") and cam.answer(rid) is None
    # Another client of the same name (or this one's predecessor) asks with other ids.
    assert DepthCamera(open_raw_bus("memq://"), name="me").request("cam") != rid
    for p in parts(request_id=rid)[0]:
        bus.publish(cloud_channel(), p.encode())
    for p in parts(capture=1)[0]:  # a capture at the camera's rate
        bus.publish(cloud_channel(), p.encode())
    refused = camera_cloud_t()
    second = cam.request("x")
    refused.camera, refused.request_id, refused.capture, refused.num_parts = "x", second, -1, 1
    refused.error = "no camera 'x' in the scene (cameras: cam)"
    bus.publish(cloud_channel(), refused.encode())
    bus.publish(cloud_channel(), b"not a cloud")
    while bus.handle(0.01):
        pass
    assert cam.answer(rid).capture == 0
    assert cam.latest["cam"].capture == 1
    with pytest.raises(CameraError, match="no camera 'x'"):
        cam.answer(second)
    assert sum(cam.bad_input.by_channel.values()) == 1
    with pytest.raises(CameraError, match="needs a camera name"):
        cam.request("")
