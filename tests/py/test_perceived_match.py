"""Matching detections to the world model's objects (skillbus.skills.perceived)."""

from __future__ import annotations

from skillbus.perception.segment import Detection
from skillbus.skills.perceived import Known, match


def det(x, y, side=0.05):
    return Detection((x, y, 0.425), 0.0, (side, side, 0.05), 100)


def test_nearest_pairs_first_and_what_is_left_is_new_or_unseen():
    known = [Known("skiros:Cube-2", (0.40, 0.15, 0.425), 0.05), Known("skiros:Cube-3", (0.50, -0.10, 0.425), 0.05),
             Known("skiros:Cube-4", (0.90, 0.90, 0.425), 0.05)]
    # Cube-2 moved 3 cm; Cube-3 moved 6 cm toward Cube-2's spot, but Cube-2's detection is nearer to Cube-2.
    dets = [det(0.52, -0.05), det(0.43, 0.15), det(0.2, -0.3)]
    m = match(known, dets)
    assert [(k.id, d.position[:2]) for k, d in m.matches] == [("skiros:Cube-2", (0.43, 0.15)),
                                                             ("skiros:Cube-3", (0.52, -0.05))]
    assert [d.position[:2] for d in m.new] == [(0.2, -0.3)]   # nothing known within 10 cm
    assert [k.id for k in m.unseen] == ["skiros:Cube-4"]


def test_a_detection_of_another_size_is_not_the_object():
    known = [Known("skiros:Cube-2", (0.40, 0.15, 0.425), 0.05), Known("skiros:Box-9", (0.6, 0.0, 0.425), None)]
    m = match(known, [det(0.40, 0.15, side=0.08), det(0.61, 0.0, side=0.12)])
    assert [k.id for k, _ in m.matches] == ["skiros:Box-9"]  # (no Size: any size)
    assert len(m.new) == 1 and m.new[0].size[0] == 0.08
    assert [k.id for k in m.unseen] == ["skiros:Cube-2"]


def test_the_same_inputs_give_the_same_matches_in_any_order():
    known = [Known(f"skiros:Cube-{i}", (0.1 * i, 0.0, 0.4), 0.05) for i in range(5)]
    dets = [det(0.1 * i + 0.01, 0.0) for i in range(5)]
    a = match(known, dets)
    b = match(list(reversed(known)), dets)
    assert [(k.id, d.position) for k, d in a.matches] == [(k.id, d.position) for k, d in b.matches]
    assert len(a.matches) == 5
