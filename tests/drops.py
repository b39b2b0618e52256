"""A ball dropped on the ground: the unilateral spring-damper's ODE, our step, and MuJoCo, measured alike.

The ODE of the compliant contact law (assumption A12, ``cobra_ref.compliance``) for a ball of mass m
and radius r whose centre is at height z, penetrating by delta = r - z::

    m z'' = -m g0 + F,    F = max(0, k delta - d z')  while delta > 0,  else 0

A drop starts GAP0 = 0.5 mm above the ground, falling at the speed that reaches the ground at v0
(v^2 = v0^2 - 2 g0 GAP0), so that our step meets the contact apart, as it does in a run. Measured
per drop, the same way on each of the three:

* ``penetration``: the largest delta [m];
* ``duration``: from the first normal force to the force's end [s];
* ``rebound``: the upward speed z' when the normal force ends [m/s]. On a step: the velocity after
  the last step of the FIRST contact episode (consecutive steps with a normal impulse above
  ``IMPULSE_TOL``); a ball that falls back and rests starts a second one.

The table (``table()``) is printed by ``PYTHONPATH=. python tests/drops.py`` and by
``PYTHONPATH=. python -m pytest tests/test_contact_ode.py tests/test_mujoco_drop.py -s``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy.integrate import solve_ivp

from bodies import BALL_RADIUS, GRAVITY, at_height, ball, no_joints
from cobra_ref.step import StepSettings
from cobra_ref.steppers import make_stepper

MASSES = (0.1, 0.25, 1.0, 4.0)  # [kg]: damping ratio d / (2 sqrt(k m)) = 1.58, 1.0, 0.5, 0.25
SPEEDS = (0.2, 0.5)  # [m/s] landing speeds v0
DTS = (1e-3, 2.5e-4, 1e-4, 2.5e-5)  # [s] our step's dt, halved (and more) towards the ODE
MJ_TIMESTEPS = (1e-4, 5e-5, 1e-5)  # [s] MuJoCo's: 0.1 ms, the export's TIMESTEP (0.05 ms), and smaller
GAP0 = 5e-4  # [m] the gap a drop starts at
IMPULSE_TOL = 1e-9  # [N s] a step with a normal impulse above it carries a force
AFTER = 3  # steps taken after the first episode's end (to see that it has ended)


class Drop(NamedTuple):
    penetration: float  # [m] largest delta = r - z
    duration: float  # [s] first force to the force's end
    rebound: float  # [m/s] z' when the force ends


def damping_ratio(mass: float, model=None) -> float:
    """zeta = d / (2 sqrt(k m)) of a ball of ``mass`` on the ground's spring-damper."""
    model = ball(mass=mass) if model is None else model
    return model.contact_damping / (2.0 * np.sqrt(model.contact_stiffness * mass))


def start(v0: float) -> tuple[float, float]:
    """(z, z') of a drop: GAP0 above the ground, falling at the speed that lands at v0."""
    return BALL_RADIUS + GAP0, -np.sqrt(v0**2 - 2.0 * GRAVITY * GAP0)


def ode_drop(mass: float, v0: float) -> Drop:
    """The drop under the exact law, by solve_ivp (rtol 1e-12, max_step 1 us) from touch-down, which
    the fall reaches at z' = -v0 exactly (free fall from ``start``); the force starts there and ends
    at the event k delta - d z' = 0 (it crosses zero before delta does: at delta = 0, -d z' < 0)."""
    model = ball(mass=mass)
    k, d = model.contact_stiffness, model.contact_damping

    def rhs(t, y):  # y = (delta, z'), while the force acts: F = k delta - d z'
        delta, v = y
        return [-v, -GRAVITY + (k * delta - d * v) / mass]

    def force_ends(t, y):
        return k * y[0] - d * y[1]
    force_ends.terminal, force_ends.direction = True, -1

    def deepest(t, y):  # z' = 0: delta is largest
        return y[1]
    sol = solve_ivp(rhs, (0.0, 1.0), [0.0, -v0], method="DOP853", rtol=1e-12, atol=1e-15, max_step=1e-6,
                    events=(force_ends, deepest))
    return Drop(float(sol.y_events[1][0][0]), float(sol.t_events[0][0]), float(sol.y_events[0][0][1]))


def step_drop(mass: float, v0: float, dt: float, stepper: str = "reference", max_time: float = 0.03,
              substeps: int | None = None):
    """(Drop, results): the drop on our step at ``dt`` (the compliant law; ``substeps``: its
    touch-down taken in that many substeps, A33; None: the law's default), stepped until AFTER steps past the first contact
    episode's end (at most ``max_time``: a ball that comes to rest in its first contact has no
    rebound, NaN); ``results``: every StepResult."""
    model = ball(mass=mass)
    z0, v_start = start(v0)
    q, qd = at_height(model, z0, v=(0.0, 0.0, v_start))
    settings = StepSettings(dt=dt, touchdown_substeps=substeps)
    stepping, results = make_stepper(stepper, model, settings), []
    first = last = None
    for n in range(int(round(max_time / dt))):
        res = stepping.step(q, qd, n * dt, no_joints)
        q, qd = res.q, res.qd
        results.append(res)
        loaded = res.contacts.m > 0 and res.p[0] > IMPULSE_TOL
        first = n if loaded and first is None else first
        last = n - 1 if first is not None and last is None and not loaded else last
        if last is not None and n >= last + AFTER:
            break
    impulse = np.array([r.p[0] if r.contacts.m else 0.0 for r in results])
    return _episode(impulse, np.array([r.q[2] for r in results]), np.array([r.qd[2] for r in results]), dt), results


def mujoco_drop(mass: float, v0: float, timestep: float | None = None, max_time: float = 0.03) -> Drop:
    """The drop in MuJoCo on ``to_mjcf(ball(mass))``: the export's contact mapping (assumption A27,
    ``cobra_ref.mjcf``), whose normal force is f = -k r - c v. Measured as ``step_drop`` does, with
    the normal force of each step read from ``mj_contactForce`` (MuJoCo's steps carry no impulse)."""
    import mujoco

    import cobra_ref as cr
    from cobra_ref.mjcf import TIMESTEP
    timestep = TIMESTEP if timestep is None else timestep
    model = ball(mass=mass)
    m = mujoco.MjModel.from_xml_string(cr.to_mjcf(model, timestep=timestep))
    data = mujoco.MjData(m)
    z0, v_start = start(v0)
    data.qpos[:], data.qvel[:] = at_height(model, z0, v=(0.0, 0.0, v_start))
    force, z, v = [], [], []
    wrench = np.zeros(6)
    for _ in range(int(round(max_time / timestep))):
        mujoco.mj_step(m, data)  # the force of this step is the one of data.efc before the position update
        f = 0.0
        for i in range(data.ncon):
            mujoco.mj_contactForce(m, data, i, wrench)
            f += wrench[0]
        force.append(f)
        z.append(data.qpos[2])
        v.append(data.qvel[2])
    force, z, v = map(np.array, (force, z, v))
    return _episode(force * timestep, z, v, timestep)


def _episode(impulse, z, v, dt) -> Drop:
    """Drop of a run's per-step normal impulses, heights and vertical speeds: its first contact episode."""
    loaded = impulse > IMPULSE_TOL
    first = int(np.argmax(loaded))
    if loaded[first:].all():  # the ball came to rest in its first contact: no force's end, no rebound
        return Drop(float(np.max(BALL_RADIUS - z[first:])), np.nan, np.nan)
    last = first + int(np.argmin(loaded[first:])) - 1
    return Drop(float(np.max(BALL_RADIUS - z[first:last + 1])), (last - first + 1) * dt, float(v[last]))


def relative_error(a: Drop, exact: Drop) -> Drop:
    """Drop of the relative errors of ``a`` against ``exact``."""
    return Drop(*((x - e) / abs(e) for x, e in zip(a, exact)))


def table(steps: dict, mujoco: dict | None = None) -> str:
    """The table of ``docs/results.md``: per ball and landing speed, the ODE, then every dt of our
    step ({(mass, v0, dt): Drop}) and of MuJoCo ({(mass, v0, timestep): Drop}), with the errors in %."""
    lines = [f"{'m [kg]':>6} {'zeta':>5} {'v0':>4} {'run':>10} {'delta_max [mm]':>15} {'err':>7} "
             f"{'contact [ms]':>12} {'err':>7} {'rebound [m/s]':>13} {'err':>7}"]
    for mass in MASSES:
        for v0 in SPEEDS:
            exact = ode_drop(mass, v0)
            rows = [("ODE", exact)] + [(f"dt {dt * 1e3:g} ms", steps[mass, v0, dt]) for dt in DTS
                                       if (mass, v0, dt) in steps]
            rows += [(f"MJ {ts * 1e3:g} ms", drop) for (m, v, ts), drop in (mujoco or {}).items()
                     if (m, v) == (mass, v0)]
            for name, drop in rows:
                e = relative_error(drop, exact)
                lines.append(f"{mass:6g} {damping_ratio(mass):5.2f} {v0:4g} {name:>10} {drop.penetration * 1e3:15.4f} "
                             f"{e.penetration:7.1%} {drop.duration * 1e3:12.3f} {e.duration:7.1%} "
                             f"{drop.rebound:13.4f} {e.rebound:7.1%}")
    return "\n".join(lines)


if __name__ == "__main__":
    try:
        import mujoco  # noqa: F401
        mj = {(mass, v0, ts): mujoco_drop(mass, v0, ts) for mass in MASSES for v0 in SPEEDS for ts in MJ_TIMESTEPS}
    except ImportError:
        mj = None
    print(table({(mass, v0, dt): step_drop(mass, v0, dt)[0] for mass in MASSES for v0 in SPEEDS for dt in DTS}, mj))
