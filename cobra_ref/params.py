"""Every number of the COBRA + box model, with its source.

Sources:

* **paper** -- [COBRA] arXiv 2404.08714, section "Simulation Setup";
* **derived** -- computed from paper numbers (the arithmetic is in ``docs/assumptions.md``);
* **datasheet** -- the ROBOTIS XH540-W270 e-manual;
* **assumption** -- the paper is silent: a documented choice, with its id (A1, A2, ...) in
  ``docs/assumptions.md``, which gives the choice, the reason and the source.

The paper's text has three typos that are read, not silently fixed (``docs/assumptions.md``):
the head inertia "I_xx - 4.4562e-4" is read as "=" (A23); the contact stiffness "1e-4 N/m"
would sink one link 49 km into the ground and is read as Simscape's default 1e6 N/m (A12);
"ode45 with a fixed timestep of 1e-4 s" is read as a maximum step (A14).

Use ``dataclasses.replace(CobraParameters(), mu=0.8)`` to vary a number; ``cobra-ref info``
prints every value next to its source.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class CobraParameters:
    """Constant description of COBRA, the box and the ground (SI units)."""

    # --- bodies --------------------------------------------------------------------------
    n_body_links: int = 10
    mass_head: float = 0.5
    mass_link: float = 0.5
    mass_tail: float = 0.5
    inertia_head: Vec3 = (4.4562e-4, 1.710e-3, 1.793e-3)
    inertia_link: Vec3 = (7.167e-4, 8.704e-4, 8.626e-4)
    inertia_tail: Vec3 = (8.182e-4, 1.141e-3, 1.109e-3)
    # --- geometry (cylinders along the body x axis) ---------------------------------------
    length_head: float = 0.19
    radius_head: float = 0.042
    length_link: float = 0.110
    radius_link: float = 0.0535
    length_tail: float = 0.13
    radius_tail: float = 0.057
    joint_gap: float = 0.025
    # --- actuators and joints -------------------------------------------------------------
    q_max: float = math.pi / 2
    tau_max: float = 9.2
    qd_max: float = 3.77
    # --- box --------------------------------------------------------------------------------
    box_size: float = 0.10
    box_mass: float = 0.5
    # --- joint servo (position control) ---------------------------------------------------------
    servo_kp: float = 500.0
    servo_kd: float = 5.0
    # --- environment and contact --------------------------------------------------------------
    gravity: float = 9.81
    mu: float = 1.0
    mu_robot_box: float = 0.5
    mu_box_ground: float | None = None
    contact_stiffness: float = 1e6
    contact_damping: float = 1e3
    stiction_velocity: float = 1e-3

    def __post_init__(self):
        """Check every field by its rule (``PARAMETER_RULES`` of :mod:`cobra_ref.infra.validation`,
        the rules ``Model`` checks its numbers by too: finite, in range, in its unit; inertias
        positive and within the triangle inequality); a ``ValidationError`` (a ValueError) names the
        field, the value and the allowed range."""
        from .infra.validation import check_parameters

        check_parameters(self)

    @property
    def total_length(self) -> float:
        """Head + 10 links + tail + 11 joint gaps (derived, A2): 1.695 m."""
        n = self.n_body_links
        return self.length_head + n * self.length_link + self.length_tail + (n + 1) * self.joint_gap

    @property
    def n_joints(self) -> int:
        return self.n_body_links + 1

    @property
    def box_inertia(self) -> float:
        """Solid cube about any central axis: I = m a^2 / 6 (derived, A8)."""
        return self.box_mass * self.box_size**2 / 6.0


SOURCES: dict[str, str] = {
    "n_body_links": "paper: 11 actuated joints; head + L1..L10 + tail = 12 bodies (A3)",
    "mass_head": "paper: 'Each link is modeled as a rigid body weighing 0.5 kg'",
    "mass_link": "paper: 'Each link is modeled as a rigid body weighing 0.5 kg'",
    "mass_tail": "paper: 'Each link is modeled as a rigid body weighing 0.5 kg'",
    "inertia_head": "paper: (Ixx, Iyy, Izz) principal, x = long axis; 'Ixx -' read as '=' (A23)",
    "inertia_link": "paper: (Ixx, Iyy, Izz) principal, x = long axis",
    "inertia_tail": "paper: (Ixx, Iyy, Izz) principal, x = long axis",
    "length_head": "derived: solid cylinder from the head inertias, mean of Iyy/Izz (A1)",
    "radius_head": "derived: r = sqrt(2 Ixx / m) (A1)",
    "length_link": "derived: L = sqrt(12 Izz/m - 3 r^2) (A1)",
    "radius_link": "derived: r = sqrt(2 Ixx / m) (A1)",
    "length_tail": "derived: solid cylinder from the tail inertias (A1)",
    "radius_tail": "derived: r = sqrt(2 Ixx / m) (A1)",
    "joint_gap": "derived: (1.7 m reported length - 1.427 m of cylinders) / 11 joints (A2)",
    "q_max": "assumption A4: +-pi/2 rad ('range of motion mimicking the real robot', not given)",
    "tau_max": "datasheet: XH540-W270 stall torque 9.2 N m at 11.1 V (A5)",
    "qd_max": "datasheet: XH540-W270 no-load 36 rpm at 11.1 V = 3.77 rad/s (A6)",
    "box_size": "assumption A8: 0.10 m cube (the paper gives only the mass)",
    "box_mass": "paper: 'solid box of weight 0.5 kg'",
    "servo_kp": "assumption A7: static error under the stall torque tau_max / kp = 1 degree",
    "servo_kd": "assumption A7: damps a link's swing about its joint (about 0.05 kg m^2) within a few ms",
    "gravity": "assumption A20: 9.81 m/s^2, flat ground z = 0",
    "mu": "paper: dynamic friction coefficient 1.0, robot-ground and box-ground (A13)",
    "mu_robot_box": "assumption A22: 0.5 (the paper: one mu for every pair); with mu = 1 a rolling link "
                    "wedges the box into the ground",
    "mu_box_ground": "paper: the same mu for box-ground as for robot-ground (A13); None = mu",
    "contact_stiffness": "assumption A12: Simscape's default 1e6 N/m (the paper's '1e-4 N/m' is a typo)",
    "contact_damping": "paper: 'damping coefficient 1e3 N s/m'",
    "stiction_velocity": "paper: smooth stick-slip 'critical velocity 1e-3 m/s' (A13)",
}

UNITS: dict[str, str] = {
    "n_body_links": "-", "mass_head": "kg", "mass_link": "kg", "mass_tail": "kg",
    "inertia_head": "kg m^2", "inertia_link": "kg m^2", "inertia_tail": "kg m^2",
    "length_head": "m", "radius_head": "m", "length_link": "m", "radius_link": "m",
    "length_tail": "m", "radius_tail": "m", "joint_gap": "m", "q_max": "rad",
    "tau_max": "N m", "qd_max": "rad/s", "box_size": "m", "box_mass": "kg", "servo_kp": "N m/rad",
    "servo_kd": "N m s/rad", "gravity": "m/s^2", "mu": "-", "mu_robot_box": "-", "mu_box_ground": "-", "contact_stiffness": "N/m",
    "contact_damping": "N s/m", "stiction_velocity": "m/s",
}


def parameter_table(params: CobraParameters | None = None) -> list[tuple[str, object, str, str]]:
    """Rows (name, value, unit, source) for every field of ``params``.
    """
    params = params or CobraParameters()
    return [(f.name, getattr(params, f.name), UNITS[f.name], SOURCES[f.name]) for f in fields(params)]
