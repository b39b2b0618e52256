"""The re-plan step on a toy: a piston pushing a box to a point, solved by hand.

The piston is a free sphere (r = 3 cm, 0.5 kg) on the ground behind a 10 cm box (0.5 kg, mu = 0.5),
driven along x by a velocity servo, F = c (v_cmd - v_x) with c = 200 N s / m (enough to push the box
against its friction mu m g = 2.45 N within 1.3 cm/s of v_cmd). Its three primitives, each held for a
period of 0.2 s: push (v_cmd = +0.1 m/s), stop (0) and withdraw (-0.1 m/s). A piston can only push,
so the hand-solved plan for a goal ahead of the box is: push while a push brings the box closer, then
stop. A push moves the box by some D > 0, so stop is chosen only when |d - D| >= d, i.e. D >= 2 d:
the box ends within half a push of the goal, and its distance never grows. The re-plan is
``planning.receding.replan``, the push planner's own: the cost of each candidate's rollout from the
plant's state, the cheapest applied for one period (the cost: the box's distance to the goal plus
1 mm per m/s of |v_cmd|, so a stop is preferred to a withdrawal that leaves the box where it is).
"""

from dataclasses import dataclass

import numpy as np

from bodies import BOX_SIDE, no_joints, sphere_and_box
from cobra_ref.planning.receding import replan
from cobra_ref.step import StepSettings
from cobra_ref.steppers import make_stepper

RADIUS, GAIN, PERIOD = 0.03, 200.0, 0.2  # [m], [N s/m], [s]
PRIMITIVES = {"push": 0.1, "stop": 0.0, "withdraw": -0.1}  # v_cmd [m/s]
SETTINGS = StepSettings(dt=1e-3)
MODEL = sphere_and_box(mu=0.5, sphere_radius=RADIUS)


@dataclass(frozen=True)
class Job:
    """One candidate's rollout: the plant's state and stepper memory, the command, the goal."""

    q: np.ndarray
    qd: np.ndarray
    memory: dict | None
    v_cmd: float
    goal_x: float


def advance(q, qd, memory, v_cmd):
    """One period of the piston at v_cmd from (q, qd) and a stepper's memory: (q, qd, memory)."""
    stepping = make_stepper("fast", MODEL, SETTINGS)
    stepping.memory = memory
    for k in range(int(round(PERIOD / SETTINGS.dt))):
        tau_ext = np.zeros(MODEL.nv)
        tau_ext[0] = GAIN * (v_cmd - qd[0])  # the servo's force on the sphere along x
        res = stepping.step(q, qd, k * SETTINGS.dt, no_joints, tau_ext)
        q, qd = res.q, res.qd
    return q, qd, stepping.memory


def predict(job: Job) -> dict:
    """The cost of one candidate: the box's distance to the goal after its period, plus its effort."""
    q, qd, _ = advance(job.q, job.qd, job.memory, job.v_cmd)
    box_x = q[7]
    return {"cost": abs(job.goal_x - box_x) + 1e-3 * abs(job.v_cmd), "box_x": box_x, "q": q}


def start():
    """The piston 1 mm behind the box's face, both resting on the ground, at rest."""
    q = np.zeros(MODEL.nq)
    q[0:7] = [-(BOX_SIDE / 2 + RADIUS + 1e-3), 0.0, RADIUS, 1.0, 0.0, 0.0, 0.0]
    q[7:14] = [0.0, 0.0, BOX_SIDE / 2, 1.0, 0.0, 0.0, 0.0]
    return q, np.zeros(MODEL.nv)


def test_one_replan_step_chooses_the_push_and_the_plant_does_what_its_rollout_predicted():
    """From rest with the goal 3.5 cm ahead: stopping or withdrawing leaves the box 3.5 cm away (the
    box, untouched, only settles by micrometres), pushing brings it closer, so the re-plan chooses
    the push; the plant, applying that push for one period from the same state and stepper memory
    (the toy's plant, like its rollouts, takes each period in a fresh stepper), reaches exactly the
    state the chosen rollout predicted (bit for bit)."""
    q, qd = start()
    jobs = [Job(q, qd, None, v, 0.035) for v in PRIMITIVES.values()]
    best, results = replan(jobs, predict)
    assert list(PRIMITIVES)[best] == "push"
    for name, r in zip(PRIMITIVES, results):
        if name != "push":
            assert abs(r["box_x"]) < 1e-5, f"{name}: the box moved {r['box_x']:.2e} m without being touched"
    assert results[best]["box_x"] > 0.01  # the push moved it more than a centimetre
    executed, _, _ = advance(q, qd, None, PRIMITIVES["push"])
    np.testing.assert_array_equal(executed, results[best]["q"])


def test_re_planning_every_period_pushes_then_stops_within_half_a_push_of_the_goal():
    """The closed loop, period by period from the state reached: push while a push brings the box
    closer, then stop (and from then on, stop again). The box's distance to the goal never grows,
    and where the re-plan stops, the push it turned down would have moved the box by D >= 2 d (up to
    the push's effort, 1e-4 m): the box ends within half a push of the goal."""
    q, qd = start()
    memory, goal, chosen, distance = None, 0.035, [], [0.035]
    for _ in range(5):
        jobs = [Job(q, qd, memory, v, goal) for v in PRIMITIVES.values()]
        best, results = replan(jobs, predict)
        name = list(PRIMITIVES)[best]
        chosen.append(name)
        if name == "stop":
            D = results[0]["box_x"] - q[7]  # the push turned down
            assert distance[-1] <= D / 2 + 1e-4, (distance[-1], D)
        q, qd, memory = advance(q, qd, memory, PRIMITIVES[name])
        distance.append(abs(goal - q[7]))
    first_stop = chosen.index("stop")
    assert first_stop >= 1 and set(chosen[:first_stop]) == {"push"} and set(chosen[first_stop:]) == {"stop"}, chosen
    assert all(b <= a + 1e-6 for a, b in zip(distance, distance[1:])), distance
