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


def test_richardson_recovers_the_limit_and_order_of_a_second_order_error():
    # sidewinding's 2 s box at dt = 1, 0.5, 0.25 ms [mm]; x(dt) = 13.3 - 0.9 dt^2 (dt in ms) is exactly second order
    exact = {dt: {"box": 13.3 - 0.9 * (dt * 1e3) ** 2, "jumps": j, "seconds": 1.0}
             for dt, j in ((2e-3, 3.0), (1e-3, 5.0), (5e-4, 4.0), (2.5e-4, 4.5))}
    fit = cv.richardson(exact)
    assert fit["box"][0] == pytest.approx(2.0, abs=1e-9) and fit["box"][1] == pytest.approx(13.3, abs=1e-12)
    # the three finest go up, down: no order, no limit
    assert all(np.isnan(v) for v in fit["jumps"])
    # a first-order sequence, 10 - 2 dt: order 1, its limit; a peak growing like 1 / dt: no limit
    first = cv.richardson({dt: {"a": 10 - 2e3 * dt, "b": 1 / dt} for dt in (1e-3, 5e-4, 2.5e-4)})
    assert first["a"] == pytest.approx((1.0, 10.0)) and first["b"][0] < 0 and np.isnan(first["b"][1])
    # dt that do not halve: nothing to say
    assert all(np.isnan(v) for v in cv.richardson({dt: {"a": dt} for dt in (3e-3, 1e-3, 5e-4)})["a"])
    table = cv.format_table({"high-fidelity": exact}, "sidewinding").splitlines()
    assert table[1].split()[-2:] == ["order", "limit"]
    assert table[2].split()[-2:] == ["2.00", "13.3"] and table[3].split()[-2:] == ["-", "-"]


@pytest.fixture(scope="module")
def tiny_study():
    return cv.study("C", duration=0.02, dts=(2e-3, 1e-3), settings=("high-fidelity",))


def test_a_tiny_study_measures_every_metric_at_every_dt(tiny_study):
    rows = tiny_study["high-fidelity"]
    assert sorted(rows) == [1e-3, 2e-3]
    for m in rows.values():
        # a mean is at most the peak (to rounding: a mean over one step is that step's value, summed)
        for q in ("force", "torque", "power"):
            assert m[f"{q}_peak"] * (1 + 1e-12) >= m[f"{q}_peak_2ms"] >= 0.0
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
    # each metric's observed order and limit, as the table's last two columns
    assert set(record["richardson"]["rigid"]) == set(record["changes"]["rigid"])
    assert set(record["richardson"]["rigid"]["box_displacement"]) == {"order", "limit"}
    assert "rigid (rigid + prescribed)" in capsys.readouterr().out


def test_the_command_refuses_an_unknown_setting(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["convergence", "--settings", "soft", "--quiet"])
    assert "--settings" in str(exc.value) and "soft" in str(exc.value)


def test_a_run_restarted_from_its_own_state_at_T_continues_it(cobra):
    # the restart of the study: the state at T and the reference shifted by T give the same
    # run from T on as the uninterrupted one (the fixed point's warm start is the only thing lost)
    from cobra_ref.gaits import gait
    from cobra_ref.simulate import simulate
    from cobra_ref.start import initial_state
    from cobra_ref.step import StepSettings

    ref, s = gait("C"), StepSettings(dt=1e-3)
    whole = simulate(cobra, ref, 0.03, s, *initial_state(cobra, ref, s))
    k = 10  # T = 0.01 s
    tail = simulate(cobra, cv.Shifted(ref, 0.01), 0.02, s, whole.q[k], whole.qd[k])
    np.testing.assert_allclose(cv.Shifted(ref, 0.01)(0.005)[0], ref(0.015)[0])
    np.testing.assert_allclose(tail.q, whole.q[k:], atol=1e-9)
    np.testing.assert_allclose(tail.tau, whole.tau[k:], atol=1e-6)


def test_a_restarted_study_starts_every_dt_from_the_finest_state(monkeypatch):
    # the finest dt runs to T once; every dt then starts from its last state, on the reference
    # shifted by T, for duration - T
    calls, simulate = [], cv.simulate

    def recording(model, reference, duration, settings, q0, qd0):
        traj = simulate(model, reference, duration, settings, q0, qd0)
        calls.append((reference, duration, settings.dt, q0.copy(), traj.q[-1].copy()))
        return traj

    monkeypatch.setattr(cv, "simulate", recording)
    result = cv.study("C", duration=0.03, dts=(1e-3, 5e-4), settings=("high-fidelity",), restart=0.01)
    (_, T, dt_head, _, q_T), *runs = calls
    assert (T, dt_head) == (0.01, 5e-4)
    assert [dt for _, _, dt, _, _ in runs] == [1e-3, 5e-4]
    for reference, duration, _, q0, _ in runs:
        assert isinstance(reference, cv.Shifted) and reference.t0 == 0.01
        assert duration == pytest.approx(0.02)
        np.testing.assert_array_equal(q0, q_T)
    rows = result["high-fidelity"]
    assert all(r["fixed_point_converged"] == 1.0 for r in rows.values())
    assert "from the dt = 0.5 ms state at t = 0.01 s" in cv.format_table(result, "C", 0.01)


@pytest.mark.parametrize("restart", [-0.001, 0.03, 0.05, 0.0101])
def test_a_restart_outside_the_run_or_between_steps_is_refused(restart):
    with pytest.raises(ValueError, match="restart must be in"):
        cv.check_restart(restart, 0.03, cv.DTS)


def test_the_command_refuses_a_restart_past_the_duration():
    with pytest.raises(SystemExit) as exc:
        main(["convergence", "--gait", "C", "--duration", "0.01", "--restart", "0.02", "--quiet"])
    assert "restart" in str(exc.value) and "0.02" in str(exc.value)


# ------------------------------------------------------------------------------ the figures' members

def test_each_member_of_the_members_study_is_its_own_figure_run_at_each_dt():
    # member k's row at dt is the metrics of its figure run (its figure start, its parameters and
    # perturbation) shortened to the study's duration and run alone at that dt: the batch changes nothing
    from dataclasses import replace

    from cobra_ref.reproduce import convergence_members as cm
    from cobra_ref.reproduce.runs import figure_start, simulate_spec
    from cobra_ref.simulate import simulate
    from cobra_ref.step import StepSettings

    result = cm.members_study("J", 2, duration=0.02, dts=(2e-3, 1e-3))
    specs = cm.figure_members("J", 2, 0.02)
    assert specs[0].member is None and specs[1].member is not None  # member 0 is the figure run
    figure = simulate_spec(specs[1])[0]  # the figure command's run of member 1, at the figures' 1 ms
    assert result[1e-3][1] == {**cv.metrics(figure, figure_start(specs[1])[0]), "error": ""}
    model, reference, start, _ = figure_start(specs[0])
    alone = simulate(model, reference, 0.02, StepSettings(dt=2e-3), *start)
    assert result[2e-3][0] == {**cv.metrics(alone, model), "error": ""}
    assert result[2e-3][0] != result[2e-3][1]  # the members differ (their box, phase and friction)
    moved = cm.member_changes(result)
    assert len(moved) == 2 and moved[1]["force_p99"] == [
        (result[1e-3][1]["force_p99"] - result[2e-3][1]["force_p99"]) / result[2e-3][1]["force_p99"]]
    assert "member 1" in cm.format_members(result, "J")


def test_the_command_studies_the_figures_members_and_refuses_settings_or_restart(tmp_path, capsys):
    out = tmp_path / "members.json"
    assert main(["convergence", "--gait", "C", "--duration", "0.004", "--members", "2", "--quiet",
                 "--json", str(out)]) == 0
    record = json.loads(out.read_text())
    assert record["members"] == 2 and len(record["changes"]) == 2
    assert [len(rows) for rows in record["results"].values()] == [2] * len(cv.DTS)
    assert "the figures' runs (2 members" in capsys.readouterr().out
    for extra in (["--settings", "rigid"], ["--restart", "0.002"]):
        with pytest.raises(SystemExit) as exc:
            main(["convergence", "--gait", "C", "--duration", "0.004", "--members", "2", "--quiet"] + extra)
        assert "--members" in str(exc.value) and extra[0] in str(exc.value)
    with pytest.raises(SystemExit):
        main(["convergence", "--members", "0", "--quiet"])
    assert "--members = 0 is out of range" in capsys.readouterr().err
