"""No contact force reaches across a gap (assumption A12): in a step whose gap stays positive from
its start to its end, a compliant contact carries no normal force. Checked on a short run of each
rolling gait here, and on every committed figure run (figures/summary.json, made by
``cobra-ref figures`` from each run's contact log).

Worked example of the measure: a log row with g = 0.2 mm at the step's start, g + dt g' = 0.1 mm at
its end and a normal force of 3 N counts 3 N; the same row with the end gap at -0.1 mm (the contact
closes within the step) counts nothing.
"""

import json
import os

import numpy as np
import pytest

from cobra_ref.gaits import gait
from cobra_ref.reproduce import analysis
from cobra_ref.robots import cobra_model
from cobra_ref.simulate import simulate
from cobra_ref.step import StepSettings
from cobra_ref.trajectory import Trajectory

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOLERANCE = 1e-3  # [N] numerically zero beside the gaits' 1-150 N contact forces


class _Log:
    """A contact log of one row per (gap, end gap, force), read as a Trajectory reads its log."""

    contact_normal_force = Trajectory.contact_normal_force

    def __init__(self, gap, gap_end, force):
        n = len(gap)
        self.contacts = {"contact_gap": np.array(gap), "contact_gap_end": np.array(gap_end),
                         "contact_normal": np.tile([0.0, 0.0, 1.0], (n, 1)),
                         "contact_force": np.array([[0.0, 0.0, f] for f in force])}


def test_the_measure_counts_only_gaps_that_stay_open():
    assert analysis.force_across_gap(_Log([2e-4], [1e-4], [3.0])) == 3.0
    assert analysis.force_across_gap(_Log([2e-4], [-1e-4], [3.0])) == 0.0
    assert analysis.force_across_gap(_Log([-2e-4], [1e-4], [3.0])) == 0.0  # penetrating at the start


@pytest.mark.parametrize("name", ["C", "J"])
def test_a_short_run_carries_no_force_across_a_gap(name):
    traj = simulate(cobra_model(), gait(name), 0.5, StepSettings())
    assert analysis.force_across_gap(traj) < TOLERANCE
    assert len(traj.contacts["contact_gap"]) > 0


def test_no_committed_figure_run_carries_a_force_across_a_gap():
    with open(os.path.join(ROOT, "figures", "summary.json")) as f:
        gaits = json.load(f)["gaits"]
    for name, s in gaits.items():
        assert s["max_force_across_gap"] < TOLERANCE, (name, s["max_force_across_gap"])
