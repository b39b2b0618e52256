"""The reliability sweep (``cobra-ref sweep``): its draw, its measures and its checks."""

import json

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.planning.problem import DECISION
from cobra_ref.reproduce import sweep as sw


def test_the_draw_is_reproducible_and_within_the_stated_ranges():
    a, b = sw.scenarios(40, seed=3), sw.scenarios(40, seed=3)
    assert a == b
    assert a != sw.scenarios(40, seed=4)
    for s in a:
        bounds = {p: (lo, hi) for p, lo, hi in DECISION[s.gait]}
        assert set(s.params) == set(bounds)
        assert all(bounds[p][0] <= v <= bounds[p][1] for p, v in s.params.items())
        assert 0.3 <= s.mu <= 1.5 and 0.3 <= s.mu_robot_box <= s.mu
        assert 0.1 <= s.box_mass <= 2.0 and 5e-4 <= s.dt <= 2e-3
    # the servos alternate, the laws take turns in pairs
    assert [s.servo for s in a[:4]] == ["position", "prescribed"] * 2
    mixed = sw.scenarios(4, seed=0, laws=("compliant", "rigid"))
    assert [s.contact for s in mixed] == ["compliant", "compliant", "rigid", "rigid"]
    assert {s.gait for s in a} == set(sw.GAITS)


def _record(index, **measures):
    base = {"steps": 100, "converged": 1.0, "cone_residual": 0.0, "coulomb_residual": 0.0, "complementarity": 0.0,
            "max_penetration": 1e-5, "penetration_error": 1e-5, "ledger_residual": 1e-4, "max_box_tilt_deg": 0.0,
            "worst_tau_N_m": 5.0, "worst_normal_force_N": 30.0, "us_per_step": 1.0, "left_physics": []}
    return {"scenario": {"index": index}, "error": None, **base, **measures}


def test_the_summary_names_every_scenario_that_fails_a_check():
    records = [_record(0), _record(1, converged=0.99), _record(2, cone_residual=2e-3),
               _record(3, penetration_error=2e-3, ledger_residual=0.5),
               {"scenario": {"index": 4}, "error": "step failed", "seconds": 1.0}]
    summary = sw.summarize(records)
    failing = {k: v["failing"] for k, v in summary["checks"].items()}
    assert failing == {"converged": [1], "cone_residual": [2], "penetration_error": [3], "ledger_residual": [3]}
    assert summary["errors"] == [4] and summary["completed"] == 4
    assert summary["measures"]["converged"]["worst"] == 0.99
    # the share of converged steps weighs each scenario by its steps
    assert summary["steps_converged"] == pytest.approx((3 * 100 + 99) / 400)
    assert "fails in scenarios [1]" in sw.format_summary(summary)
    clean = sw.summarize([_record(0), _record(1)])
    assert not any(c["failing"] for c in clean["checks"].values())


def test_scenarios_that_left_physics_are_reported_apart():
    # scenario 1 squeezes the box (a kN force, 14 mm deep, most of it the spring's deflection F / k);
    # scenario 2 needs 100 tau_max and its solve fails a check: listed apart, not in "failing"
    records = [_record(0), _record(1, max_penetration=0.014, penetration_error=2e-4, worst_normal_force_N=1.4e4,
                                      left_physics=["contact_force"]),
               _record(2, worst_tau_N_m=920.0, penetration_error=5e-3, left_physics=["tau", "contact_force"]),
               _record(3, max_penetration=2e-3)]
    summary = sw.summarize(records)
    assert summary["physical"] == 2 and summary["left_physics"] == [1, 2]
    # the statistics of the physical scenarios hold none of the others' values
    assert summary["measures"]["max_penetration"]["worst"] == 2e-3
    assert summary["measures"]["worst_normal_force_N"]["worst"] == 30.0
    assert summary["measures_left_physics"]["worst_tau_N_m"]["worst"] == 920.0
    # the 1 mm line judges the solver's error, not the raw penetration
    check = summary["checks"]["penetration_error"]
    assert check["failing"] == [] and check["failing_left_physics"] == [2]
    text = sw.format_summary(summary)
    assert "2 physical, 2 left physics (A32) [1, 2]" in text and "scenarios that left physics:" in text
    assert "of those that left physics, fails in [2]" in text


def test_one_scenario_runs_and_meets_the_checks():
    scenario = sw.scenarios(1, seed=0)[0]
    record = sw.run_scenario(scenario, duration=0.03)
    assert record["error"] is None
    assert record["steps"] == round(0.03 / scenario.dt)
    # (the ledger's check is relative to the actuators' work, which 30 ms of a gait's ramp hardly does)
    for key, (limit, kind) in sw.CHECKS.items():
        if key != "ledger_residual":
            assert record[key] >= limit if kind == "min" else record[key] <= limit, key
    assert record["contact_dissipation"] > 0
    assert np.isfinite(record["us_per_step"]) and record["us_per_step"] > 0
    assert record["left_physics"] == [] and record["tau_beyond_share"] == 0.0
    assert 0.0 <= record["penetration_error"] <= record["max_penetration"] + 1e-12


def test_the_command_writes_every_record(tmp_path):
    out = tmp_path / "sweep.json"
    code = main(["sweep", "--n", "2", "--duration", "0.01", "--jobs", "1", "--quiet", "--json", str(out)])
    data = json.loads(out.read_text())
    assert len(data["runs"]) == 2 and data["summary"]["completed"] == 2
    # the exit status says whether a scenario failed a check
    failing = any(c["failing"] for c in data["summary"]["checks"].values())
    assert code == (1 if failing else 0)
    assert data["summary"]["seed"] == 0


def test_the_command_refuses_a_bad_count():
    with pytest.raises(SystemExit) as exc:
        main(["sweep", "--n", "0"])
    assert exc.value.code == 2
