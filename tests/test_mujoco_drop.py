"""Dropping a ball in MuJoCo, like for like: the export's contact mapping against the law's ODE.

``to_mjcf(ball(mass))`` gives MuJoCo the spring-damper f = -k r - c v of assumption A12 through the
mapping of A27 (``cobra_ref.mjcf``: direct solref with the smallest impedance 1e-4 and A_hat = 1 / m).
MuJoCo integrates that force explicitly in the velocity, so a contact whose damping time m / c is
near its timestep is lost: the 0.1 kg ball (m / c = 0.1 ms) stops dead in MuJoCo's first contact
step at the export's TIMESTEP = 0.1 ms and never rebounds. The drops are ``drops.mujoco_drop``,
measured as our step's are (``drops``); the table (with -s) is the one of docs/results.md.
"""

import pytest

import drops
from cobra_ref.mjcf import TIMESTEP

mujoco = pytest.importorskip("mujoco", reason="the MuJoCo comparison needs the optional dependency mujoco")


# measured: MuJoCo's 1 kg ball at 0.2 m/s and 0.1 ms sinks 5.2 % less than the ODE (docs/results.md)
CASES = [pytest.param(m, v, ts, marks=pytest.mark.xfail(strict=True, reason="penetration 5.2 % short at 0.1 ms"))
         if (m, v, ts) == (1.0, 0.2, TIMESTEP) else (m, v, ts)
         for m in (1.0, 4.0) for v in drops.SPEEDS for ts in (TIMESTEP, TIMESTEP / 2)]


@pytest.mark.parametrize("mass,v0,timestep", CASES)
def test_mujoco_drops_the_heavy_balls_as_the_ode_does(mass, v0, timestep):
    """The 1 kg and 4 kg balls (contact 2.5-6.1 ms, 25 or more MuJoCo steps): the largest
    penetration and the rebound speed within 5 % of the ODE's, at the export's timestep 0.1 ms and
    at half of it."""
    drop, exact = drops.mujoco_drop(mass, v0, timestep), drops.ode_drop(mass, v0)
    error = drops.relative_error(drop, exact)
    assert abs(error.penetration) < 0.05, f"penetration {error.penetration:.1%}"
    assert abs(error.rebound) < 0.05, f"rebound {error.rebound:.1%}"
