"""Which way the robot can push the box: the push direction and the facing error by hand, and the turning re-plan."""

from dataclasses import replace

import numpy as np
import pytest

from cobra_ref.planning.facing import FACE_TOL, facing, push_direction, turning_candidates
from cobra_ref.planning.locomotion import body_axis, link_centres
from cobra_ref.robots import cobra_model, neutral_q


def _straight_robot_and_box(side: float):
    """A straight robot (zero joint angles) and its box ``side`` metres to the right of its middle
    link (negative: to its left); the right normal r of its axis."""
    model = cobra_model()
    q = neutral_q(model)
    box = model.boxes[0].body
    robot = np.delete(link_centres(model, q), box, axis=0)
    a = body_axis(robot)
    r = np.array([a[1], -a[0]])
    i = model.q_idx[box].start
    q[i:i + 2] = robot[len(robot) // 2] + side * r
    return model, q, r


@pytest.mark.parametrize("side", [0.2, -0.2])
def test_the_push_direction_is_across_the_axis_towards_the_box(side):
    model, q, r = _straight_robot_and_box(side)
    np.testing.assert_allclose(push_direction(model, q), np.sign(side) * r, atol=1e-12)


@pytest.mark.parametrize("degrees", [0.0, 45.0, -45.0, 120.0, 180.0])
def test_the_facing_error_is_the_angle_from_the_push_direction_to_the_target(degrees):
    # the box 0.2 m to the right; the target 0.3 m from the box at `degrees` counter-clockwise from r
    model, q, r = _straight_robot_and_box(0.2)
    box = link_centres(model, q)[model.boxes[0].body]
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    target = box + 0.3 * np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]])
    assert np.degrees(facing(model, q, target)) == pytest.approx(degrees, abs=1e-9)


def test_turning_candidates_turn_the_way_the_target_lies():
    # counter-clockwise (sidewinding-mirror) for a target to the left of the push direction,
    # clockwise (sidewinding) to its right; forwards-then-backwards and the reverse at each amplitude
    left, right = turning_candidates(0.5), turning_candidates(-0.5)
    assert {p.family for pair in left for p in pair} == {"sidewinding-mirror"}
    assert {p.family for pair in right for p in pair} == {"sidewinding"}
    assert all(a.frequency == -b.frequency and a.amplitude == b.amplitude for a, b in left)
    assert len(left) == 4 and len({pair for pair in left}) == 4


def test_a_replan_turns_the_robot_while_it_faces_away_from_the_target():
    # the tiny push of tests/test_push.py with the goal to the robot's left (90 deg from where it
    # pushes): the first re-plan offers only turns; a goal ahead offers only pushes
    from cobra_ref.infra.executors import SerialExecutor
    from cobra_ref.planning.receding import push
    from test_push import TINY

    left = push(replace(TINY, goal=(0.0, 0.2), budget=0.1), SerialExecutor())
    first = left.cycles[0]
    assert first["mode"] == "turn" and first["facing"] > np.degrees(FACE_TOL)
    assert left.plan.primitives[0].family == "sidewinding-mirror"
    assert all(c["pair"][0].startswith("sidewinding-mirror") for c in first["candidates"])
    ahead = push(replace(TINY, goal=(0.2, 0.0), budget=0.1), SerialExecutor())
    assert ahead.cycles[0]["mode"] == "push" and abs(ahead.cycles[0]["facing"]) < np.degrees(FACE_TOL)
