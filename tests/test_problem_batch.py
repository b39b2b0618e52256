"""The least-action problems of K members written at once: each member's problem is its own, bit for bit."""

import dataclasses

import numpy as np
import pytest

from cobra_ref.fast.problem_batch import least_action_problems
from cobra_ref.fast.stepper import FastStepper
from cobra_ref.gaits import gait
from cobra_ref.robots import cobra_model
from cobra_ref.simulate import simulate
from cobra_ref.start import initial_state
from cobra_ref.step import StepSettings, least_action_problem

# whole steps: a batch writes its members' whole steps together, each member's touch-down substeps
# (A33, at dt / n) alone
SETTINGS = {"compliant": StepSettings(dt=1e-3, touchdown_substeps=1), "rigid": StepSettings(dt=1e-3, contact="rigid"),
            "prescribed": StepSettings(dt=1e-3, servo="prescribed", touchdown_substeps=1)}


@pytest.fixture(scope="module")
def steps():
    """{settings name: [(G, least_action_problem's other arguments)]} of every step of short runs:
    C meeting its box and sidewinding under the compliant law with the position servo, J under the
    rigid law, sidewinding with prescribed joints."""
    collected = {}
    rows = FastStepper.rows
    runs = [("compliant", "C", 1.5), ("compliant", "sidewinding", 0.3), ("rigid", "J", 0.3),
            ("prescribed", "sidewinding", 0.3)]
    model = cobra_model()
    with pytest.MonkeyPatch.context() as patch:
        for name, gait_name, duration in runs:
            def keep(self, *args, _into=collected.setdefault(name, []), **kwargs):
                found = rows(self, *args, **kwargs)
                _into.append((found.system.G, found.problem_args))
                return found

            patch.setattr(FastStepper, "rows", keep)
            reference, settings = gait(gait_name), SETTINGS[name]
            simulate(model, reference, duration, settings, *initial_state(model, reference, settings))
    return collected


def _same(want, got):
    for name, a, b in zip(want._fields, want, got):
        np.testing.assert_array_equal(b, a, err_msg=name)
        assert np.asarray(b).tobytes() == np.asarray(a).tobytes(), name


@pytest.mark.parametrize("name", list(SETTINGS))
@pytest.mark.parametrize("K", [1, 5, 16])
def test_each_members_batched_problem_is_its_own_bit_for_bit(steps, name, K):
    """Members drawn from the runs' steps, each with its own model: every third with the friction
    coefficients doubled (a member's own friction is read per member); every member's H, c, mu,
    lo, hi and v_s are ``least_action_problem``'s."""
    model = cobra_model()
    slippery = dataclasses.replace(model, mu=2 * model.mu, mu_robot_box=2 * model.mu_rb)
    chosen = np.random.default_rng(K).permutation(len(steps[name]))[:240]
    for i in range(0, len(chosen), K):
        parts = [steps[name][j] for j in chosen[i:i + K]]
        models = [slippery if k % 3 == 2 else model for k in range(len(parts))]
        for own, (G, args), got in zip(models, parts, least_action_problems(models, parts)):
            _same(least_action_problem(own, G, *args), got)


def test_members_whose_servos_differ_get_their_own_problems(steps):
    """A member with stiffer servo gains reads other row laws: the batch writes each member's problem
    alone, and every one is still ``least_action_problem``'s."""
    model = cobra_model()
    stiff = dataclasses.replace(model, servo_kp=2 * model.servo_kp)
    parts, models = steps["compliant"][100:104], [model, stiff, model, model]
    got = least_action_problems(models, parts)
    for own, (G, args), mine in zip(models, parts, got):
        _same(least_action_problem(own, G, *args), mine)
    assert not np.array_equal(got[1].c, least_action_problem(model, parts[1][0], *parts[1][1]).c)
