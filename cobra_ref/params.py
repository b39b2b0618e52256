"""Every number of the COBRA + box model, with its source.

Sources are keyed as in ``../shared/notes/paper-facts.md``:

* **paper**   -- [COBRA] arXiv 2404.08714, section "Simulation Setup" (the seed LaTeX).
* **derived** -- computed from paper numbers; the arithmetic is in the notes, Part B.
* **datasheet** -- ROBOTIS XH540-W270 e-manual (notes A4).
* **assumption** -- the paper is silent; the documented choice of notes Part C (C1..C21).

The seed LaTeX has three typos that we record here instead of silently fixing them:

1. head inertia printed as "I_xx - 4.4562e-4": read as "=" (notes A1);
2. contact stiffness printed as "1e-4 N/m": physically impossible (4.9e4 m static sinkage
   for one link); most likely the Simscape transition width 1e-4 m (notes B4). Our hard
   contact model (issue 3) has no stiffness; the compliant reading k = 1e6 N/m is kept here
   for the record only;
3. "ode45 with a fixed timestep of 1e-4 s": ode45 is variable-step; read as max step 1e-4 s
   (notes C14). Our velocity-level stepper uses dt = 1e-3 s (notes C15).

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
    # --- environment and contact --------------------------------------------------------------
    gravity: float = 9.81
    mu: float = 1.0
    mu_robot_box: float = 0.5
    mu_static: float = 1.3
    # --- the paper's compliant-contact settings, kept for the record (not used by the hard model)
    paper_contact_stiffness: float = 1e-4
    paper_contact_damping: float = 1e3
    paper_v_crit: float = 1e-3
    paper_dt: float = 1e-4

    @property
    def total_length(self) -> float:
        """Head + 10 links + tail + 11 joint gaps (derived, notes B2): 1.695 m."""
        n = self.n_body_links
        return self.length_head + n * self.length_link + self.length_tail + (n + 1) * self.joint_gap

    @property
    def n_joints(self) -> int:
        return self.n_body_links + 1

    @property
    def box_inertia(self) -> float:
        """Solid cube about any central axis: I = m a^2 / 6 (derived, notes C8)."""
        return self.box_mass * self.box_size**2 / 6.0


SOURCES: dict[str, str] = {
    "n_body_links": "paper: 11 actuated joints; head + L1..L10 + tail = 12 bodies (notes A1, A3, B3)",
    "mass_head": "paper: 'Each link is modeled as a rigid body weighing 0.5 kg'",
    "mass_link": "paper: 'Each link is modeled as a rigid body weighing 0.5 kg'",
    "mass_tail": "paper: 'Each link is modeled as a rigid body weighing 0.5 kg'",
    "inertia_head": "paper: (Ixx, Iyy, Izz) principal, x = long axis; seed typo 'Ixx -' read as '='",
    "inertia_link": "paper: (Ixx, Iyy, Izz) principal, x = long axis",
    "inertia_tail": "paper: (Ixx, Iyy, Izz) principal, x = long axis",
    "length_head": "derived: solid cylinder from the head inertias, mean of Iyy/Izz (notes B1, C1)",
    "radius_head": "derived: r = sqrt(2 Ixx / m) (notes B1, C1)",
    "length_link": "derived: L = sqrt(12 Izz/m - 3 r^2) (notes B1, C1)",
    "radius_link": "derived: r = sqrt(2 Ixx / m) (notes B1, C1)",
    "length_tail": "derived: solid cylinder from the tail inertias (notes B1, C1)",
    "radius_tail": "derived: r = sqrt(2 Ixx / m) (notes B1, C1)",
    "joint_gap": "derived: (1.7 m reported length - 1.427 m of cylinders) / 11 joints (notes B2, C2)",
    "q_max": "assumption C4: +-pi/2 rad ('range of motion mimicking the real robot', not given)",
    "tau_max": "datasheet: XH540-W270 stall torque 9.2 N m at 11.1 V (notes A4, C5)",
    "qd_max": "datasheet: XH540-W270 no-load 36 rpm at 11.1 V = 3.77 rad/s (notes A4, C6)",
    "box_size": "assumption C8: 0.10 m cube (paper gives only the mass)",
    "box_mass": "paper: 'solid box of weight 0.5 kg'",
    "gravity": "assumption C20: 9.81 m/s^2, flat ground z = 0",
    "mu": "paper: dynamic friction coefficient 1.0 (single mu of the hard model, notes C13)",
    "mu_robot_box": "assumption C22: 0.5 (paper: one mu for all pairs); with mu = 1 a rolling link "
                    "wedges the box into the ground (README 'Pushing the box')",
    "mu_static": "paper: static friction coefficient 1.3 (compliant models only)",
    "paper_contact_stiffness": "paper (typo): '1e-4 N/m'; compliant reading 1e6 N/m (notes B4, C12)",
    "paper_contact_damping": "paper: 1e3 N s/m (compliant models only)",
    "paper_v_crit": "paper: stick-slip critical velocity 1e-3 m/s (compliant models only)",
    "paper_dt": "paper: 'ode45 with a fixed timestep of 1e-4 s' (typo: ode45 is variable-step, C14)",
}

UNITS: dict[str, str] = {
    "n_body_links": "-", "mass_head": "kg", "mass_link": "kg", "mass_tail": "kg",
    "inertia_head": "kg m^2", "inertia_link": "kg m^2", "inertia_tail": "kg m^2",
    "length_head": "m", "radius_head": "m", "length_link": "m", "radius_link": "m",
    "length_tail": "m", "radius_tail": "m", "joint_gap": "m", "q_max": "rad",
    "tau_max": "N m", "qd_max": "rad/s", "box_size": "m", "box_mass": "kg",
    "gravity": "m/s^2", "mu": "-", "mu_robot_box": "-", "mu_static": "-", "paper_contact_stiffness": "N/m",
    "paper_contact_damping": "N s/m", "paper_v_crit": "m/s", "paper_dt": "s",
}


def parameter_table(params: CobraParameters | None = None) -> list[tuple[str, object, str, str]]:
    """Rows (name, value, unit, source) for every field of ``params``.

    Helper: the parameter table of cobra-ref info.
    """
    params = params or CobraParameters()
    return [(f.name, getattr(params, f.name), UNITS[f.name], SOURCES[f.name]) for f in fields(params)]
