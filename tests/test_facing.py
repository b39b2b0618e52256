"""Which way the robot can push the box: the push direction and the facing error by hand, and the turning re-plan."""

from dataclasses import replace

import numpy as np
import pytest

from cobra_ref.planning.facing import (FACE_TOL, RECOVERY_BACK, RECOVERY_TAIL, RECOVERY_TURNS, STEER_TOL,
                                       TURN_AMPLITUDES, TURN_PAIR, away, facing, miss, push_direction,
                                       recovery_candidates, steering_candidates, turning_candidates)
from cobra_ref.planning.primitives import Primitive
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


def _target(model, q, r, degrees: float, distance: float = 0.3):
    """A target ``distance`` from the box at ``degrees`` counter-clockwise from r."""
    box = link_centres(model, q)[model.boxes[0].body]
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return box + distance * np.array([c * r[0] - s * r[1], s * r[0] + c * r[1]])


@pytest.mark.parametrize("degrees", [0.0, 45.0, -45.0, 120.0, 180.0])
def test_the_facing_error_is_the_angle_from_the_push_direction_to_the_target(degrees):
    # the box 0.2 m to the right; the target 0.3 m from the box at `degrees` counter-clockwise from r
    model, q, r = _straight_robot_and_box(0.2)
    assert np.degrees(facing(model, q, _target(model, q, r, degrees))) == pytest.approx(degrees, abs=1e-9)


@pytest.mark.parametrize("degrees, factor", [
    (0.0, 1.0),  # on the push line: the distance itself
    (45.0, np.sqrt(0.5 + 9 * 0.5)),  # half of d^2 along, half across (weighted by 3^2)
    (-60.0, np.sqrt(0.25 + 9 * 0.75)),
    (90.0, 3.0), (135.0, 3.0), (180.0, 3.0),  # no straight push brings the box nearer: 3 d
])
def test_the_miss_weights_the_distance_across_the_push_direction(degrees, factor):
    # the box 0.2 m to the right, the target 0.3 m from it: m = 0.3 sqrt(cos^2 + 3^2 sin^2) ahead, 0.9 behind
    model, q, r = _straight_robot_and_box(0.2)
    target = _target(model, q, r, degrees)
    assert miss(model, q, target, w_lateral=3.0) == pytest.approx(0.3 * factor, rel=1e-12)
    assert miss(model, q, target, w_lateral=1.0) == pytest.approx(0.3, rel=1e-12)  # unweighted: d at any angle


def test_turning_candidates_turn_the_way_the_target_lies():
    # counter-clockwise (sidewinding-mirror) for a target to the left of the push direction,
    # clockwise (sidewinding) to its right; forwards-then-backwards and the reverse at each amplitude,
    # then a stop: the plant runs the pair whole (TURN_PAIR periods), its rollout ends at rest
    left, right = turning_candidates(0.5), turning_candidates(-0.5)
    assert {p.family for seq in left for p in seq[:TURN_PAIR]} == {"sidewinding-mirror"}
    assert {p.family for seq in right for p in seq[:TURN_PAIR]} == {"sidewinding"}
    assert all(a.frequency == -b.frequency and a.amplitude == b.amplitude and rest.family == "stop"
               for a, b, rest in left + right)
    assert len(left) == 4 and len({seq for seq in left}) == 4 and TURN_PAIR == 2


def test_a_push_offers_a_turn_first_only_when_the_box_is_off_its_line():
    # within STEER_TOL nothing; beyond it one period of the small turn towards phi, each way, then the push
    push = Primitive("C", 0.4, 0.5)
    assert steering_candidates(0.9 * STEER_TOL, push) == [] and steering_candidates(-0.9 * STEER_TOL, push) == []
    left, right = steering_candidates(1.1 * STEER_TOL, push), steering_candidates(-1.1 * STEER_TOL, push)
    assert [p.family for p, _ in left] == ["sidewinding-mirror"] * 2 and [p.family for p, _ in right] == ["sidewinding"] * 2
    assert sorted(p.frequency for p, _ in left) == [-1.0, 1.0] and all(rest == push for _, rest in left + right)


def test_a_replan_turns_the_robot_while_it_faces_away_from_the_target():
    # the tiny push of tests/test_push.py with the goal to the robot's left (90 deg from where it
    # pushes): the first re-plan offers only turns; a goal ahead offers only pushes
    from cobra_ref.infra.executors import SerialExecutor
    from cobra_ref.planning.receding import push
    from test_push import TINY

    left = push(replace(TINY, goal=(0.0, 0.2), budget=0.2), SerialExecutor())
    first, second = left.cycles
    assert first["mode"] == "turn" and first["facing"] > np.degrees(FACE_TOL)
    assert all(c["pair"][0].startswith("sidewinding-mirror") for c in first["candidates"])
    # the chosen pair runs whole: the second period winds the other way, with no re-plan
    turn, reverse = left.plan.primitives[:2]
    assert turn.family == reverse.family == "sidewinding-mirror" and reverse.frequency == -turn.frequency
    assert second["mode"] == "turn" and second["rollouts"] == 0
    ahead = push(replace(TINY, goal=(0.2, 0.0), budget=0.1), SerialExecutor())
    assert ahead.cycles[0]["mode"] == "push" and abs(ahead.cycles[0]["facing"]) < np.degrees(FACE_TOL)


def test_the_plant_runs_a_turn_pair_and_a_recovery_s_back_off_and_turns_without_re_planning():
    from cobra_ref.planning.receding import committed

    turn = turning_candidates(0.5)[0]
    assert committed("turn", turn) == [turn[1]]  # the pair's second half; its stop is only the rollout's
    recovery = recovery_candidates(0.5, -1.0)[-1]
    assert committed("recover", recovery) == list(recovery[1:-RECOVERY_TAIL])
    gentle = (Primitive("C", 0.25, 0.25), Primitive("stop"))  # a turning re-plan near the target also offers these
    assert committed("turn", gentle) == [] and committed("push", (Primitive("C"), Primitive("C"))) == []


@pytest.mark.parametrize("side, sign", [(0.2, -1.0), (-0.2, 1.0)])
def test_c_backs_away_from_the_box_at_the_sign_away_gives(side, sign):
    # C at f > 0 travels towards r (tests/test_locomotion.py measures it): away from a box on the right is f < 0
    model, q, _ = _straight_robot_and_box(side)
    assert away(model, q) == sign


def test_a_recovery_backs_off_turns_towards_the_target_rolls_back_and_pushes_gently():
    sequences = recovery_candidates(0.5, -1.0)  # the target to the left of the push direction, the box on the right
    assert len(sequences) == len(RECOVERY_BACK) * len(TURN_AMPLITUDES) * len(RECOVERY_TURNS)
    for seq in sequences:
        back, *turns, again, gentle, stop = seq
        assert seq[-RECOVERY_TAIL:] == (again, gentle, stop)  # re-planned as they come; the rest runs whole
        assert back.family == again.family == gentle.family == "C" and back.frequency < 0 < again.frequency
        assert again.frequency == -back.frequency and 0 < gentle.frequency <= again.frequency and stop.family == "stop"
        assert gentle.amplitude < again.amplitude
        assert {t.family for t in turns} == {"sidewinding-mirror"} and len(turns) in RECOVERY_TURNS
        assert all(a.frequency == -b.frequency for a, b in zip(turns, turns[1:]))  # forwards, backwards, ...
    assert {p.family for seq in recovery_candidates(-0.5, -1.0) for p in seq[1:-RECOVERY_TAIL]} == {"sidewinding"}


@pytest.mark.parametrize("phi, d, may_recover, modes", [
    # may_recover: the push stalled, or the robot faces away (receding.push gives the periods left then)
    (0.5, 0.03, True, {"turn", "recover"}),  # near the target, the box off the line: turns and recoveries
    (0.3, 0.05, True, {"push", "recover"}),  # a stalled push, the box off its line: pushes and recoveries
    (0.5, 0.2, True, {"turn"}),  # too far for a recovery: turn where it stands
    (0.1, 0.03, True, {"push"}),  # stalled on the line: no turn would help
    (0.5, 0.03, False, {"turn"}), (0.5, 0.01, False, {"push"}),  # within 2 cm nothing but pushes and stops
    (0.1, 0.2, False, {"push"}),
])
def test_each_replan_chooses_its_candidates_from_the_measured_state(phi, d, may_recover, modes):
    from cobra_ref.planning.choices import choose_candidates

    def chosen(periods_left):
        return choose_candidates(phi, d, Primitive("C", 0.4, 0.5), np.random.default_rng(0), 2, periods_left,
                                 lambda: -1.0)

    out = chosen(100 if may_recover else None)
    assert {mode for mode, _ in out} == modes
    recoveries = [seq for mode, seq in out if mode == "recover"]
    if recoveries:
        # compared with the turns or pushes, not with standing still (which would rest short of the goal)
        assert ("push", (Primitive("stop"), Primitive("stop"))) not in out
        assert all(len(seq) >= 5 for seq in recoveries)
        # a recovery runs its periods but the final stop whole: only those that end within the budget
        shortest = min(len(seq) for seq in recoveries) - 1
        fitting = [seq for mode, seq in chosen(shortest) if mode == "recover"]
        assert fitting and all(len(seq) - 1 <= shortest for seq in fitting)
        assert "recover" not in {mode for mode, _ in chosen(shortest - 1)}
    if "turn" in modes:
        assert {seq[0].family for mode, seq in out[:4]} == {"sidewinding-mirror"}


@pytest.mark.parametrize("after_first, replanned", [(0.8, False), (0.1, True)])
def test_a_turn_pair_s_second_half_runs_unless_the_first_faced_the_robot_to_the_target(monkeypatch, after_first,
                                                                                         replanned):
    # the facing error read at each period's start is set by hand: 0.8 rad (beyond FACE_TOL: turn),
    # then after_first; still facing away, the pair's second half runs without a re-plan; facing
    # the target already, it is dropped and the next period re-planned as a push
    from cobra_ref.infra.executors import SerialExecutor
    from cobra_ref.planning import receding
    from test_push import TINY

    readings = iter([0.8, after_first])
    monkeypatch.setattr(receding, "facing", lambda model, q, target: next(readings))
    first, second = receding.push(replace(TINY, goal=(0.0, 0.2), budget=0.2), SerialExecutor()).cycles
    assert first["mode"] == "turn" and abs(np.radians(second["facing"]) - after_first) < 1e-12
    assert (second["rollouts"] > 0) == replanned and (second["mode"] == "push") == replanned
