"""The dt-convergence study (``cobra-ref convergence``): its measures on hand-made cases, and a tiny study."""

import json
import types

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.contact import ROBOT_BOX, ROBOT_GROUND
from cobra_ref.reproduce import convergence as cv
from cobra_ref.trajectory import CONTACT_KEYS


def test_moving_mean_is_the_mean_over_each_window_of_steps():
    # dt = 1 ms, window 2 ms: means of each pair of consecutive steps
    y = np.array([0.0, 2.0, 4.0, 10.0])
    np.testing.assert_allclose(cv.moving_mean(y, 1e-3), [1.0, 3.0, 7.0])
    # a window of one step is the series itself; a series shorter than the window is its mean
    np.testing.assert_allclose(cv.moving_mean(y, 2e-3), y)
    np.testing.assert_allclose(cv.moving_mean(y[:1], 1e-3), [0.0])
    # the mean of a spike of one step over the 2 ms window is half of it: the raw peak of an
    # impulse grows like 1 / dt, its window mean does not
    spike = np.zeros(10)
    spike[4] = 1.0 / 1e-3
    assert cv.moving_mean(spike, 1e-3).max() == pytest.approx(0.5 * spike.max())


def _contact_log(rows):
    """A trajectory's contact log from rows (step, kind, body, force (3,))."""
    log = {k: np.zeros((len(rows), 3)) if k in ("contact_point", "contact_normal", "contact_force") else
           np.zeros(len(rows)) for k in CONTACT_KEYS}
    for i, (step, kind, body, force) in enumerate(rows):
        log["contact_step"][i], log["contact_kind"][i], log["contact_body"][i] = step, kind, body
        log["contact_force"][i] = force
    return log


def test_body_forces_sum_each_bodys_contacts_and_give_the_box_the_reaction(cobra):
    box = cobra.boxes[0].body
    rows = [(0, ROBOT_GROUND, 3, (0.0, 0.0, 4.0)), (0, ROBOT_GROUND, 3, (3.0, 0.0, 0.0)),
            (1, ROBOT_BOX, 5, (1.0, 2.0, 2.0))]
    traj = types.SimpleNamespace(contacts=_contact_log(rows), tau=np.zeros((2, 11)))
    F = cv.body_forces(traj, cobra)
    assert F.shape == (2, cobra.nb)
    # step 0: body 3 carries (3, 0, 4), |.| = 5; step 1: body 5 feels (1, 2, 2), the box its opposite
    assert F[0, 3] == pytest.approx(5.0)
    assert F[1, 5] == pytest.approx(3.0) and F[1, box] == pytest.approx(3.0)
    assert F.sum() == pytest.approx(11.0)


def test_changes_are_relative_from_each_dt_to_the_next_smaller():
    rows = {2e-3: {"a": 10.0, "seconds": 1.0}, 1e-3: {"a": 12.0, "seconds": 2.0}, 5e-4: {"a": 12.6, "seconds": 4.0}}
    ch = cv.changes(rows)
    assert list(ch) == ["a"]
    np.testing.assert_allclose(ch["a"], [0.2, 0.05])


@pytest.fixture(scope="module")
def tiny_study():
    return cv.study("C", duration=0.02, dts=(2e-3, 1e-3), settings=("high-fidelity",))


def test_a_tiny_study_measures_every_metric_at_every_dt(tiny_study):
    rows = tiny_study["high-fidelity"]
    assert sorted(rows) == [1e-3, 2e-3]
    for m in rows.values():
        assert m["force_peak"] >= m["force_peak_2ms"] >= 0.0
        assert m["torque_peak"] >= m["torque_peak_2ms"] >= 0.0
        assert m["power_peak"] >= m["power_peak_2ms"] >= 0.0
        assert m["fixed_point_converged"] == 1.0
    # the robot rests on the ground: its weight, about 6 kg g, is carried at every step
    assert rows[1e-3]["force_p99"] > 0.0
    table = cv.format_table(tiny_study, "C")
    assert "force_peak_2ms" in table and "high-fidelity" in table


def test_the_command_prints_the_table_and_writes_json(tmp_path, capsys):
    out = tmp_path / "conv.json"
    assert main(["convergence", "--gait", "C", "--duration", "0.004", "--settings", "rigid", "--quiet",
                 "--json", str(out)]) == 0
    record = json.loads(out.read_text())
    assert record["gait"] == "C" and set(record["results"]) == {"rigid"}
    assert len(record["results"]["rigid"]) == len(cv.DTS)
    assert "rigid (rigid + prescribed)" in capsys.readouterr().out


def test_the_command_refuses_an_unknown_setting(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["convergence", "--settings", "soft", "--quiet"])
    assert "--settings" in str(exc.value) and "soft" in str(exc.value)
