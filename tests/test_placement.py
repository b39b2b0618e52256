"""The box placement of a travelling gait (sidewinding), worked on a robot whose motion is known."""

from types import SimpleNamespace

import numpy as np
import pytest

from cobra_ref import placement
from cobra_ref.robots import cobra_model
from cobra_ref.start import placed_state


class Straight:
    """A reference that holds every joint at 0: COBRA lies straight along +x."""

    frequency = 0.5

    def __call__(self, t):
        z = np.zeros(11)
        return z, z, z


def _fake_run(monkeypatch, velocity):
    """Replace the box-free run by a rigid translation of the straight start at ``velocity`` (m/s)."""
    def fake_initial_state(model, reference, settings=None, **kw):
        return placed_state(model, reference), np.zeros(model.nv)

    def fake_simulate(model, reference, duration, settings, q0, qd0):
        t = np.arange(int(round(duration / settings.dt)) + 1) * settings.dt
        q = np.repeat(q0[None], len(t), axis=0)
        q[:, :2] += t[:, None] * np.asarray(velocity)
        return SimpleNamespace(q=q)

    monkeypatch.setattr(placement, "initial_state", fake_initial_state)
    monkeypatch.setattr(placement, "simulate", fake_simulate)


def test_a_straight_robot_moving_sideways_gets_its_box_at_the_plain_gap(monkeypatch):
    """Every sphere centre and the centre of mass lie on the body's axis (y = 0), so moving along +y
    the surface reaches the largest sphere radius ahead of the centre of mass: e = max_s r_s, and
    the clearance box_gap = e + gap - r (r: the middle link's radius) exceeds the gap by the
    largest sphere's radius over the middle link's; the direction is +y exactly."""
    _fake_run(monkeypatch, (0.0, 0.1))
    model = cobra_model(with_box=False)
    p = placement.travel_placement(model, Straight(), dt=5e-3, gap=0.05)
    assert p.direction == pytest.approx((0.0, 1.0), abs=1e-12)
    r_mid = max(model.spheres.radius[np.isin(model.spheres.body, [model.nb // 2 - 1, model.nb // 2])])
    assert p.reach == pytest.approx(max(model.spheres.radius), abs=1e-12)
    assert p.box_gap == pytest.approx(max(model.spheres.radius) + 0.05 - r_mid, abs=1e-12)


def test_moving_along_the_body_the_box_goes_beyond_the_leading_end(monkeypatch):
    """Moving along the body's axis, the reach is the leading sphere's surface ahead of the middle:
    max_s (x_s + r_s) - x_m, found here by hand from the start configuration's sphere centres."""
    from cobra_ref.kinematics import forward_kinematics

    model = cobra_model(with_box=False)
    q = placed_state(model, Straight())
    kin, sph = forward_kinematics(model, q), model.spheres
    x = [kin.o[b][0] + (kin.R[b] @ c)[0] + r for b, c, r in zip(sph.body, sph.center, sph.radius)]
    com = [kin.o[i] + kin.R[i] @ model.com[i] for i in range(model.nb)]
    middle = 0.5 * (com[model.nb // 2 - 1] + com[model.nb // 2])
    for sign in (1.0, -1.0):
        _fake_run(monkeypatch, (sign * 0.1, 0.0))
        p = placement.travel_placement(model, Straight(), dt=5e-3, gap=0.05)
        lead = max(x) - middle[0] if sign > 0 else middle[0] - min(np.array(x) - 2 * np.asarray(sph.radius))
        assert p.direction == pytest.approx((sign, 0.0), abs=1e-12)
        assert p.reach == pytest.approx(lead, abs=1e-9)


def test_a_gait_that_does_not_move_cannot_place_a_box(monkeypatch):
    from cobra_ref.step import SimulationError

    _fake_run(monkeypatch, (0.0, 0.0))
    with pytest.raises(SimulationError, match="does not move the robot"):
        placement.travel_placement(cobra_model(with_box=False), Straight(), dt=5e-3)
    with pytest.raises(ValueError, match="without the box"):
        placement.travel_placement(cobra_model(with_box=True), Straight(), dt=5e-3)
