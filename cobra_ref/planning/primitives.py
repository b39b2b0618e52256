"""Motion primitives a planner steers with, and the joint reference they make one after another.

Implements: the gait families of [COBRA] sec. "Results" (lateral rolling in C, S and J shapes,
sidewinding; :mod:`cobra_ref.gaits`) cut into primitives that a receding-horizon planner
(:mod:`cobra_ref.planning.receding`) chooses one period at a time. Each primitive is a shape
function of the gait phase phi, f(phi) -> q (11,), and a phase rate omega = 2 pi f (f < 0: the same shape rolls the other way)::

    rolling:      q_i = kappa_i (1 + b (s_i - 1/2)) cos phi   (yaw joints)
                  q_i = kappa_i (1 + b (s_i - 1/2)) sin phi   (pitch joints)
    sidewinding:  q_i = A sin(phi - Omega i + delta_i)          (``gaits.SidewindingGait``)
    stop:         the shape of the primitive before it, omega = 0

with the bend profiles kappa of ``gaits.RollingGait`` (C, S, J) and the mirrors (S-mirror,
J-mirror and sidewinding-mirror: yaw joints negated, the robot's reflection in the vertical plane
of its axis, which turns the other way: :mod:`cobra_ref.planning.locomotion`), and the taper b in
[-1, 1]: one end of the body bends more than the other, a continuous steering parameter for
lateral rolling (the analogue of conical sidewinding's taper; its effect is measured, not assumed).

``PlanReference`` chains primitives that start at times t_0 = 0 < t_1 < ...: primitive k applies
on (t_k, t_k+1]. Across a switch the phase stays continuous and both the shape and the phase rate
blend by a smoothstep r over ``BLEND_TIME``::

    phi(t)  = phi_k + omega_(k-1) tau + (omega_k - omega_(k-1)) R(tau),   tau = t - t_k, R = integral of r
    q(t)    = (1 - r(tau)) f_(k-1)(phi) + r(tau) f_k(phi)

so q_ref, qd_ref are continuous (qdd_ref jumps with r'', as in the gaits' ramp): switching makes no
impact of its own. The first primitive starts from rest in its own shape (omega_(-1) = 0, f_(-1) =
f_0), as the gaits' ramp does. The reference on (t_k, t_k+1] depends only on primitives 0..k, so a
plan extended while it runs gives, up to each time, the reference a replay of the whole plan gives.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..gaits import N_JOINTS, Q_MAX, S, YAW, RollingGait, SidewindingGait, rolling_shape, smoothstep

BLEND_TIME = 0.25  # [s] a switch's blend of shape and phase rate (the optimizer's ramp, RAMP_TIME)
ROLLING = ("C", "S", "S-mirror", "J", "J-mirror")
SIDEWINDING = ("sidewinding", "sidewinding-mirror")
FAMILIES = ROLLING + SIDEWINDING + ("stop",)


class PrimitiveError(ValueError):
    """A primitive or plan that cannot be used (the message names the field)."""


@dataclass(frozen=True)
class Primitive:
    """One primitive: a family (``FAMILIES``) and its parameters (module docstring)."""

    family: str = "C"
    amplitude: float = 0.5  # A [rad]
    frequency: float = 0.5  # f [Hz]; negative rolls (or winds) the other way; a stop's is ignored
    taper: float = 0.0  # b, rolling only
    s_J: float = 0.5  # J and J-mirror only: the hook spans s_i <= s_J

    def __post_init__(self):
        if self.family not in FAMILIES:
            raise PrimitiveError(f"family must be one of {', '.join(FAMILIES)}, got {self.family!r}")
        for name, low, high in (("amplitude", 0.0, Q_MAX), ("frequency", -10.0, 10.0), ("taper", -1.0, 1.0),
                                ("s_J", 0.0, 1.0)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not low <= value <= high:
                raise PrimitiveError(f"{name} must be a number in [{low:g}, {high:g}], got {value!r}")
        # the tapered bend stays within the joints' range
        if self.family in ROLLING and self.amplitude * (1 + abs(self.taper) / 2) > Q_MAX:
            raise PrimitiveError(f"amplitude {self.amplitude:g} with taper {self.taper:g} bends a joint by "
                                 f"{self.amplitude * (1 + abs(self.taper) / 2):.3g} rad, beyond q_max = {Q_MAX:.4g}")

    @property
    def omega(self) -> float:
        """The phase rate 2 pi f [rad/s] (0 for a stop)."""
        return 0.0 if self.family == "stop" else 2 * np.pi * self.frequency

    def to_dict(self) -> dict:
        """The primitive as a JSON-ready dict (``Primitive(**d)`` reads it back)."""
        return asdict(self)


class _Shape:
    """f(phi), f'(phi), f''(phi) of one primitive (module docstring)."""

    def __init__(self, p: Primitive):
        if p.family in ROLLING:
            # the bend profile of the unmirrored shape (a zero amplitude is a straight body)
            unit = RollingGait(shape=p.family.replace("-mirror", ""), amplitude=1.0, s_J=p.s_J).kappa()
            kappa = p.amplitude * unit * (1 + p.taper * (S - 0.5))
            self.kappa = np.where(YAW, -kappa, kappa) if p.family.endswith("-mirror") else kappa
            self.sidewinding = None
        else:
            self.kappa, self.sidewinding = None, SidewindingGait(amplitude_yaw=p.amplitude, amplitude_pitch=p.amplitude)
        self.sign = np.where(YAW, -1.0, 1.0) if p.family == "sidewinding-mirror" else None

    def __call__(self, phi: float):
        f, df = rolling_shape(self.kappa, phi) if self.kappa is not None else self.sidewinding.shape(phi)
        if self.sign is not None:  # sidewinding-mirror: the yaw joints negated
            f, df = self.sign * f, self.sign * df
        return f, df, -f


class PlanReference:
    """q_ref(t), qd_ref(t), qdd_ref(t) of a chain of primitives (module docstring).

    ``start``: the moving primitive whose shape at phi = 0 the robot holds at rest until the first
    primitive (``extend``) begins; with none, the reference is that hold.
    """

    def __init__(self, start: Primitive = Primitive()):
        if start.family == "stop":
            raise PrimitiveError("the start shape must be a moving primitive's, not a stop")
        self.start = start
        self.primitives: list[Primitive] = []
        self.starts: list[float] = []
        self._hold = _Shape(start)
        self._segments: list[tuple] = []  # (t_k, phi_k, omega_prev, omega_k, shape_prev, shape_k)

    def extend(self, primitive: Primitive, t_start: float) -> None:
        """Primitive ``primitive`` from ``t_start`` on (>= 0, after every primitive so far)."""
        if not (np.isfinite(t_start) and t_start >= 0.0) or (self.starts and not t_start > self.starts[-1]):
            after = f"after the last one ({self.starts[-1]:g} s)" if self.starts else "at t >= 0"
            raise PrimitiveError(f"a primitive must start {after}, got t_start = {t_start!r}")
        if self._segments:
            phi = self._phase(len(self._segments) - 1, t_start)[0][0]
            _, _, _, omega_prev, _, shape_prev = self._segments[-1]
        else:
            phi, omega_prev, shape_prev = 0.0, 0.0, self._hold
        # a stop holds the shape before it
        shape = shape_prev if primitive.family == "stop" else _Shape(primitive)
        self.primitives.append(primitive)
        self.starts.append(float(t_start))
        self._segments.append((float(t_start), phi, omega_prev, primitive.omega, shape_prev, shape))

    def _segment(self, t: float) -> int:
        """The primitive that applies at t: the last with t_k < t (the first at t <= t_0)."""
        return max(int(np.searchsorted(self.starts, t, side="left")) - 1, 0)

    def _phase(self, k: int, t: float):
        """(phi, phi', phi'') and the blend (r, r', r'') at t in segment k."""
        t_k, phi_k, omega_prev, omega_k, _, _ = self._segments[k]
        tau = t - t_k
        r, rd, rdd = smoothstep(tau, BLEND_TIME)
        s = min(max(tau / BLEND_TIME, 0.0), 1.0)
        R = BLEND_TIME * (s**3 - s**4 / 2) + max(tau - BLEND_TIME, 0.0)  # the integral of r
        d_omega = omega_k - omega_prev
        return (phi_k + omega_prev * tau + d_omega * R, omega_prev + d_omega * r, d_omega * rd), (r, rd, rdd)

    def __call__(self, t: float):
        if not self._segments:
            q = self._hold(0.0)[0]
            return q, np.zeros(N_JOINTS), np.zeros(N_JOINTS)
        k = self._segment(t)
        (phi, phid, phidd), (r, rd, rdd) = self._phase(k, t)
        a, da, dda = self._segments[k][4](phi)
        b, db, ddb = self._segments[k][5](phi)
        q = (1 - r) * a + r * b
        dq = (1 - r) * da + r * db  # d q / d phi at a fixed blend
        qd = dq * phid + rd * (b - a)
        qdd = ((1 - r) * dda + r * ddb) * phid**2 + dq * phidd + 2 * rd * (db - da) * phid + rdd * (b - a)
        return q, qd, qdd

    def to_dict(self) -> dict:
        """{"start", "primitives": [{"t_start", "primitive"}, ...]}: the plan as JSON (``from_dict``)."""
        return {"start": self.start.to_dict(),
                "primitives": [{"t_start": t, "primitive": p.to_dict()} for t, p in zip(self.starts, self.primitives)]}

    @classmethod
    def from_dict(cls, d) -> "PlanReference":
        """The plan of ``to_dict``; a ``PrimitiveError`` naming what is malformed."""
        try:
            plan = cls(Primitive(**d["start"]))
            items = list(d["primitives"])
        except (KeyError, TypeError, ValueError) as exc:
            raise PrimitiveError(f"a plan is {{'start': primitive, 'primitives': [...]}}: {exc}") from None
        for i, item in enumerate(items):
            try:
                primitive, t_start = Primitive(**item["primitive"]), float(item["t_start"])
            except (KeyError, TypeError, ValueError) as exc:
                raise PrimitiveError(f"plan entry {i} is malformed: {exc}") from None
            plan.extend(primitive, t_start)
        return plan
