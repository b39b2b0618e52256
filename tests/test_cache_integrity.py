"""The figure command's cache checks itself: a damaged or foreign entry is named, recomputed and
replaced; a figure file changed since it was drawn is drawn again; ``--cache`` and ``--jobs`` are
refused before any work.

The cache is the smallest real one: one gait run of 10 steps (C, 0.02 s at dt = 2 ms).
"""

import os
import shutil

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.reproduce import optima
from cobra_ref.reproduce.cache import (read_path, read_rows, read_trajectory, seal_trajectory, verified,
                                       write_path, write_rows)
from cobra_ref.reproduce.runs import RunSpec, cached_path, run_all
from cobra_ref.reproduce.stamps import Stamps
from cobra_ref.trajectory import Trajectory

SPEC = RunSpec("C", duration=0.02, dt=0.002)
OTHER = RunSpec("C", duration=0.01, dt=0.002)  # another run: another key


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A cache holding SPEC and OTHER, and SPEC's trajectory as first computed."""
    cache = tmp_path_factory.mktemp("cache")
    runs = run_all([SPEC, OTHER], str(cache), workers=1, progress=False)
    return cache, runs[SPEC]


def truncated(path, cache):
    data = open(path, "rb").read()
    open(path, "wb").write(data[: len(data) // 2])


def empty(path, cache):
    open(path, "wb").close()


def foreign(path, cache):
    with open(path, "wb") as f:
        np.savez(f, x=np.arange(3.0))


def other_key(path, cache):
    shutil.copyfile(cached_path(OTHER, str(cache)), path)


def other_numbers(path, cache):
    traj = Trajectory.from_npz(path)
    traj.q = traj.q + 0.01  # the stored key and content hash left as they were
    traj.to_npz(path)


def non_finite(path, cache):
    traj = Trajectory.from_npz(path)
    traj.q[3, 0] = np.nan
    seal_trajectory(traj, SPEC.key())  # a hash that matches the NaN: the finiteness check finds it
    traj.to_npz(path)


def missing_array(path, cache):
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files if k != "box_pose"}
    with open(path, "wb") as f:
        np.savez(f, **arrays)


# damage, and the words of the reason on stderr
DAMAGES = [
    (truncated, "unreadable"),
    (empty, "unreadable"),
    (foreign, "not a run"),
    (missing_array, "not a run: no box_pose"),
    (other_key, "computed for key"),
    (other_numbers, "does not match the SHA-256"),
    (non_finite, "non-finite values in q"),
]


@pytest.mark.parametrize("damage, reason", DAMAGES, ids=[d.__name__ for d, _ in DAMAGES])
def test_a_damaged_run_is_named_recomputed_and_replaced(damage, reason, pristine, tmp_path, capsys):
    source, first = pristine
    cache = tmp_path / "cache"
    shutil.copytree(source, cache)
    path = cached_path(SPEC, str(cache))
    damage(path, cache)

    again = run_all([SPEC], str(cache), workers=1, progress=False)[SPEC]

    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"cache entry {path} is damaged (")
    assert reason in err[0] and err[0].endswith("): recomputing")
    np.testing.assert_allclose(again.q, first.q, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(again.box_pose, first.box_pose, rtol=1e-12, atol=1e-12)
    # replaced: the entry now reads back whole, without a word
    np.testing.assert_allclose(read_trajectory(path, SPEC.key()).q, first.q, rtol=1e-12, atol=1e-12)
    run_all([SPEC], str(cache), workers=1, progress=False)
    assert capsys.readouterr().err == ""


def test_an_undamaged_entry_is_used_silently(pristine, capsys):
    source, first = pristine
    again = run_all([SPEC], str(source), workers=1, progress=False)[SPEC]
    assert capsys.readouterr().err == ""
    assert again.meta["content_sha256"] == first.meta["content_sha256"]


def test_a_damaged_failed_run_entry_is_recomputed_too(pristine, tmp_path, capsys):
    source, first = pristine
    cache = tmp_path / "cache"
    shutil.copytree(source, cache)
    complete = cached_path(SPEC, str(cache))
    failed = complete[:-4] + ".failed.npz"
    os.replace(complete, failed)
    empty(failed, cache)
    again = run_all([SPEC], str(cache), workers=1, progress=False)[SPEC]
    assert f"cache entry {failed} is damaged" in capsys.readouterr().err
    assert not os.path.exists(failed) and os.path.isfile(complete)
    np.testing.assert_allclose(again.q, first.q, rtol=1e-12, atol=1e-12)


# ---------------------------------------------------------------- the optima's replayed box paths

@pytest.fixture
def replays(monkeypatch, tmp_path):
    """A params JSON and a stand-in replay that counts its calls (the real one simulates seconds)."""
    from cobra_ref.planning import results

    calls = []
    box = np.column_stack([np.linspace(0.0, 0.3, 5), np.zeros(5), np.full(5, 0.05), np.ones(5), np.zeros((5, 3))])

    def replay(path):
        calls.append(path)
        return Trajectory(0.002, np.zeros(5), None, None, None, box, {}, {}), {}

    monkeypatch.setattr(results, "replay", replay)
    params = tmp_path / "C.json"
    params.write_text('{"params": {}}')
    return str(params), calls, box[:, :2]


REPLAY_DAMAGES = [(truncated, "unreadable"), (empty, "unreadable"), (foreign, "not a stored path"),
                  ("other key", "computed for key"), ("other numbers", "does not match the SHA-256")]


@pytest.mark.parametrize("damage, reason", REPLAY_DAMAGES, ids=["truncated", "empty", "foreign", "other-key",
                                                                "other-numbers"])
def test_a_damaged_replay_is_named_recomputed_and_replaced(damage, reason, replays, tmp_path, capsys):
    params, calls, xy = replays
    cache = str(tmp_path / "cache")
    np.testing.assert_array_equal(optima.replayed_box_path(params, cache), xy)
    (entry,) = [os.path.join(cache, f) for f in os.listdir(cache)]
    if damage == "other key":
        write_path(entry, "0" * 64, xy)
    elif damage == "other numbers":
        with np.load(entry) as z:
            arrays = dict(z)
        arrays["xy"] = arrays["xy"] + 1.0
        with open(entry, "wb") as f:
            np.savez(f, **arrays)
    else:
        damage(entry, cache)
    np.testing.assert_array_equal(optima.replayed_box_path(params, cache), xy)
    err = capsys.readouterr().err
    assert err.startswith(f"cache entry {entry} is damaged (") and reason in err and err.count("\n") == 1
    assert len(calls) == 2  # replayed again, once
    np.testing.assert_array_equal(verified(entry, lambda p: read_path(p, optima._replay_key(params))), xy)
    assert optima.replays_submit(None, os.path.dirname(params), ("C",), cache) == []  # nothing left to replay


# ---------------------------------------------------------------- the MuJoCo comparison's rows

ROWS = [{"gait": "C", "ours": 0.12, "mujoco": 0.11}, {"gait": "S", "ours": -0.02, "mujoco": None}]


def replace_text(path, old, new):
    text = open(path).read()
    open(path, "w").write(text.replace(old, new))


@pytest.mark.parametrize("damage, reason", [
    (empty, "unreadable"), (truncated, "unreadable"),
    (lambda p, c: open(p, "w").write('{"rows": 3}'), "not a list of rows"),
    (lambda p, c: write_rows(p, "f" * 64, ROWS), "computed for key"),
    (lambda p, c: replace_text(p, "0.12", "0.13"), "does not match the SHA-256"),
], ids=["empty", "truncated", "foreign", "other-key", "other-numbers"])
def test_damaged_mujoco_rows_are_named_and_not_used(damage, reason, tmp_path, capsys):
    path, key = str(tmp_path / "mujoco-0123.json"), "a" * 64
    write_rows(path, key, ROWS)
    assert verified(path, lambda p: read_rows(p, key)) == ROWS
    damage(path, None)
    assert verified(path, lambda p: read_rows(p, key)) is None  # mujoco_submit computes the rows then
    err = capsys.readouterr().err
    assert err.startswith(f"cache entry {path} is damaged (") and reason in err
    assert not os.path.exists(path)


# ---------------------------------------------------------------- the figures' stamps

def test_a_figure_overwritten_with_garbage_is_drawn_again(tmp_path, capsys):
    from PIL import Image

    png = str(tmp_path / "fig.png")
    Image.new("RGB", (8, 8), "white").save(png)
    Stamps(str(tmp_path)).record("fig", "stamp-1", [png])
    assert Stamps(str(tmp_path)).kept("fig", "stamp-1") == [png]
    open(png, "wb").write(b"garbage")
    assert Stamps(str(tmp_path)).kept("fig", "stamp-1") is None
    assert capsys.readouterr().err == (f"output {png} does not match its stamp (changed since it was written): "
                                       "drawing fig again\n")
    Image.new("RGB", (8, 8), "white").save(png)  # drawn again, and recorded
    Stamps(str(tmp_path)).record("fig", "stamp-1", [png])
    assert Stamps(str(tmp_path)).kept("fig", "stamp-1") == [png]


@pytest.mark.parametrize("text, reason", [("[1, 2]", "not a JSON object"), ('{"fig": ', "unreadable")])
def test_a_damaged_stamps_file_is_named_and_keeps_nothing(text, reason, tmp_path, capsys):
    (tmp_path / ".stamps.json").write_text(text)
    assert Stamps(str(tmp_path)).kept("fig", "stamp-1") is None
    err = capsys.readouterr().err
    assert err.startswith(f"cache entry {tmp_path / '.stamps.json'} is damaged (") and reason in err


# ---------------------------------------------------------------- refused before any work

@pytest.mark.parametrize("option, status, words", [
    (["--jobs", "0"], 2, "--jobs"),
    (["--jobs", "-1"], 2, "--jobs"),
    (["--cache", os.devnull], 1, "is not a directory"),
    (["--cache", "FILE"], 1, "is not a directory"),
    (["--cache", ""], 1, "is empty"),
])
def test_figures_refuses_a_bad_cache_or_jobs_before_any_work(option, status, words, tmp_path, capsys, monkeypatch):
    import cobra_ref.reproduce.regenerate as regenerate

    monkeypatch.setattr(regenerate, "run_all", lambda *a, **k: pytest.fail("a run started"))
    (tmp_path / "FILE").write_text("x")
    option = [str(tmp_path / "FILE") if o == "FILE" else o for o in option]
    with pytest.raises(SystemExit) as exc:
        main(["figures", "--quick", "--out", str(tmp_path / "out"), *option])
    code = exc.value.code
    if status == 2:  # a malformed option: argparse's usage and one error line
        assert code == 2 and words in capsys.readouterr().err.splitlines()[-1]
    else:  # refused after parsing: exit status 1 with one line "error: ..."
        assert code.startswith("error: ") and words in code and "\n" not in code


@pytest.mark.parametrize("workers", [0, -1, 1.5, True])
def test_run_all_refuses_a_bad_worker_count(workers, tmp_path):
    with pytest.raises(ValueError, match="workers"):
        run_all([SPEC], str(tmp_path), workers=workers)


def test_mujoco_submit_computes_rows_whose_entry_is_damaged(tmp_path, monkeypatch, capsys):
    """The MuJoCo job reads its entry through the check: whole, it is used; damaged, the rows are computed."""
    pytest.importorskip("mujoco")
    from types import SimpleNamespace

    from cobra_ref.reproduce import mujoco_job

    key = "b" * 64
    monkeypatch.setattr(mujoco_job, "mujoco_key", lambda boxed, runs, duration: key)
    monkeypatch.setattr(mujoco_job, "_mujoco_compute", lambda side, boxed, runs, duration: ["computing"])
    specs, runs = {"C": ["C#0"]}, {"C#0": SimpleNamespace(error="", duration=1.0)}
    cache = str(tmp_path)
    write_rows(os.path.join(cache, f"mujoco-{key[:16]}.json"), key, ROWS)
    job = mujoco_job.mujoco_submit(None, specs, runs, 1.0, cache, False, False)
    assert job["rows"] == ROWS and job["futures"] == []
    open(job["cached"], "w").write('{"key": "' + key + '", "rows": [')
    job = mujoco_job.mujoco_submit(None, specs, runs, 1.0, cache, False, False)
    assert job["rows"] is None and job["futures"] == ["computing"]
    assert capsys.readouterr().err.startswith(f"cache entry {job['cached']} is damaged (unreadable: JSONDecodeError")


def test_a_single_worker_advances_the_runs_in_batches(tmp_path, monkeypatch):
    # one worker: the runs of one key go as one batch in this process (as a pool's worker runs them)
    from cobra_ref.reproduce import runs

    sizes = []
    real = runs.simulate_specs
    monkeypatch.setattr(runs, "simulate_specs", lambda specs, progress=None: sizes.append(len(specs)) or real(specs))
    third = RunSpec("S", duration=0.02, dt=0.002)
    got = run_all([SPEC, OTHER, third], str(tmp_path), workers=1, progress=False)
    assert sorted(sizes) == [1, 2]  # SPEC and third share a key (box, dt, duration); OTHER is shorter
    assert got[SPEC].error == "" and np.array_equal(got[SPEC].q, runs.simulate_spec(SPEC)[0].q)
