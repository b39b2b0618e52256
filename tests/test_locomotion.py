"""Where a primitive takes the robot alone: the body frame by hand, and the mirror's symmetry."""

import json

import numpy as np
import pytest

from cobra_ref.planning.locomotion import body_axis, signed_angle, travel
from cobra_ref.planning.primitives import Primitive


def test_the_body_axis_of_points_on_a_line_is_the_line_from_tail_to_head():
    # twelve points on the line through (1, 2) at 30 deg, the head (first point) at the far end
    u = np.array([np.cos(np.pi / 6), np.sin(np.pi / 6)])
    points = np.array([1.0, 2.0]) + np.linspace(0.5, -0.6, 12)[:, None] * u
    np.testing.assert_allclose(body_axis(points), u, atol=1e-12)
    # read from the other end, the same line points the other way
    np.testing.assert_allclose(body_axis(points[::-1]), -u, atol=1e-12)
    # a bend across the line (a C shape, symmetric about its middle) leaves the axis where it was
    bent = points + 0.05 * np.sin(np.linspace(0.0, np.pi, 12))[:, None] * np.array([-u[1], u[0]])
    np.testing.assert_allclose(body_axis(bent), u, atol=1e-12)


@pytest.mark.parametrize("a, b, angle", [((1, 0), (0, 1), 90.0), ((1, 0), (0, -1), -90.0), ((0, 1), (1, 0), -90.0),
                                         ((1, 1), (-1, -1), 180.0), ((2, 0), (1, 1), 45.0)])
def test_signed_angle_is_counter_clockwise_from_a_to_b(a, b, angle):
    assert signed_angle(np.array(a, float), np.array(b, float)) == pytest.approx(angle, abs=1e-12)


@pytest.mark.slow
@pytest.mark.parametrize("family, taper", [("J", 1.0), ("sidewinding", 0.0)])
def test_a_mirrored_primitive_travels_and_turns_as_the_reflection_of_its_own(family, taper):
    # the mirror is the primitive with every yaw joint negated: the robot's reflection in the
    # vertical plane of its axis, which keeps the axis and reverses every angle from it; the
    # distance is the same
    own = travel(Primitive(family, 0.5, 1.0, taper=taper), cycles=1)
    mirror = travel(Primitive(family + "-mirror", 0.5, 1.0, taper=taper), cycles=1)
    assert own.distance > 0.1  # it does travel: 0.4-0.6 m per cycle
    assert mirror.distance == pytest.approx(own.distance, rel=1e-9)
    assert mirror.angle == pytest.approx(-own.angle, abs=1e-6)
    assert mirror.turn == pytest.approx(-own.turn, abs=1e-6)
    assert abs(own.turn) > 1.0  # and it turns, so the turn's sign is tested


def test_a_stop_has_no_travel_to_measure():
    with pytest.raises(ValueError, match="moving primitives"):
        travel(Primitive("stop"))


def test_the_travel_map_command_writes_the_rows_and_prints_the_table(tmp_path, monkeypatch, capsys):
    # the command's plumbing, with the 27 measured primitives replaced by one row
    from cobra_ref.cli import main
    from cobra_ref.planning import locomotion

    row = locomotion.Travel(Primitive("C", 0.5, 0.5), False, 0.3, -90.0, 1.5)
    monkeypatch.setattr(locomotion, "locomotion_map", lambda **kw: [row])
    out = tmp_path / "travel.json"
    assert main(["push", "--travel-map", "--out", str(out), "--workers", "1", "--quiet"]) == 0
    assert json.loads(out.read_text()) == [row.to_dict()]
    assert "| C | +0.0 | +0.5 | 30.0 | -90.0 | +1.50 |" in capsys.readouterr().out
