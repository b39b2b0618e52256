"""The verdict map over the paper's unknowns (``reproduce.claims_map``): its set-ups change one unknown
each, its runs are the figures' own where they can be, its cells are the claims' verdicts, and
``--check`` compares them."""

import os

import pytest

from cobra_ref.reproduce import claims as claims_mod
from cobra_ref.reproduce.check import compare_claims
from cobra_ref.reproduce.claims_map import (MAP_GAITS, SETUPS, all_hold, check_entries, judge, map_specs, markdown,
                                            where_claims_hold)
from cobra_ref.reproduce.ensemble import members
from cobra_ref.reproduce.map_figure import draw_map, grid
from cobra_ref.reproduce.regenerate import ensemble_specs
from cobra_ref.reproduce.runs import RunSpec


@pytest.fixture(scope="module")
def specs():
    figure = ensemble_specs(n_members=8)
    return figure, map_specs(figure)


def test_the_set_ups_are_three_values_of_three_unknowns_and_the_placement_rules():
    values = {}
    for s in SETUPS:
        for name in ("box_size", "box_mass", "mu_robot_box", "placement"):
            values.setdefault(name, set()).add(getattr(s, name))
    assert values["box_size"] == {0.10, 0.20, 0.30} and values["box_mass"] == {0.25, 0.5, 2.0}
    assert values["mu_robot_box"] == {0.3, 0.5, 1.0} and values["placement"] == {"per gait", "travel"}
    # a slice changes one unknown of the nominal set-up (the corner two)
    nominal = SETUPS[0]
    for s in SETUPS[1:]:
        changed = [n for n in ("box_size", "box_mass", "mu_robot_box", "placement")
                   if getattr(s, n) != getattr(nominal, n)]
        assert len(changed) == (2 if s.unknown == "corner" else 1), s


def test_the_nominal_set_up_is_the_figures_own_runs_and_every_other_changes_its_unknown(specs):
    figure, mapped = specs
    assert set(mapped["nominal"]) == set(MAP_GAITS), "J-mirror (J reflected) is not mapped"
    for g in MAP_GAITS:
        assert mapped["nominal"][g] == figure[g][:4]
    big = mapped["box 0.30 m with mu_rb 1.0"]["J"]
    assert [s.member.index if s.member else 0 for s in big] == [m.index for m in members("J", 4)]
    p = big[2].cobra_parameters()
    assert p.box_size == 0.30 and p.mu_robot_box == pytest.approx(1.0 * big[2].member.mu_scale)
    assert {s.duration for s in big} == {figure["J"][1].duration}, "every member runs the figures' window"
    heavy = mapped["box 2 kg"]["C"][0]
    assert heavy.cobra_parameters().box_mass == 2.0 and heavy.cobra_parameters().box_size == 0.10


def test_a_value_at_the_models_default_adds_nothing_to_the_key_and_sidewinding_has_one_placement(specs):
    figure, mapped = specs
    assert RunSpec("C", box_size=None, box_mass=None, placement="per gait").key() == RunSpec("C").key()
    assert RunSpec("C", box_size=0.3).key() != RunSpec("C").key()
    # sidewinding's own rule is the travelling one: the travel set-up reuses its runs
    travel = mapped["travel placement"]
    assert travel["sidewinding"][1].key() == figure["sidewinding"][1].key()
    assert travel["J"][1].key() != figure["J"][1].key() and travel["J"][1].travels
    with pytest.raises(ValueError, match="placement = 'ahead' is not a placement rule"):
        RunSpec("C", placement="ahead")


def _map(cells: dict) -> dict:
    """A hand-made map: {set-up name: {claim: (held, n)}}."""
    rows = []
    for s in SETUPS:
        if s.name not in cells:
            continue
        claims = {}
        for cid, (held, n) in cells[s.name].items():
            word = "holds" if held >= 0.8 * n else ("does not hold" if held <= 0.2 * n else "undecided")
            claims[cid] = {"verdict": word, "holds": {"holds": True, "does not hold": False}.get(word), "n": n,
                           "held": held, "fraction": held / n}
        rows.append({**s.as_dict(), "claims": claims})
    return {"setups": rows, "members": 4, "window (s)": 6.0, "gaits": list(MAP_GAITS), "gait parameters": "x"}


def test_where_each_claim_holds_and_whether_one_set_up_makes_them_all_hold():
    m = _map({"nominal": {"WB": (0, 4), "E": (4, 4)}, "box 0.30 m": {"WB": (4, 4), "E": (4, 4)},
              "mu_rb 1.0": {"WB": (2, 4), "E": (1, 4)}})
    where = where_claims_hold(m)
    assert where["WB"] == {"does not hold": ["nominal"], "holds": ["box 0.30 m"], "undecided": ["mu_rb 1.0"]}
    assert all_hold(m) == ["box 0.30 m"]
    text = markdown(m)
    assert "| set-up | box (m) | box (kg) | mu_rb | placement | WB | E |" in text
    assert "| mu_rb 1.0 | 0.1 | 0.5 | 1 | per gait | undecided 2/4 | undecided 1/4 |" in text
    assert "Every claim holds together at: box 0.30 m." in text
    assert "threshold" not in text, "no claim here has thresholds"


def test_a_claim_not_tested_anywhere_is_left_out_of_the_map():
    m = _map({"nominal": {"WB": (0, 4)}, "box 2 kg": {"WB": (4, 4)}})
    for row in m["setups"]:
        row["claims"]["GT"] = {"verdict": "not tested", "holds": None, "n": 0, "held": 0, "fraction": None}
    assert "GT" not in markdown(m) and "GT" not in where_claims_hold(m)


def test_check_compares_every_cell_so_a_changed_verdict_or_count_is_a_mismatch():
    before = check_entries(_map({"nominal": {"WB": (0, 4)}, "box 2 kg": {"WB": (4, 4)}}))
    assert [e["id"] for e in before] == ["map:nominal:WB", "map:box 2 kg:WB"]
    assert compare_claims(before, check_entries(_map({"nominal": {"WB": (0, 4)}, "box 2 kg": {"WB": (4, 4)}}))) == []
    flipped = check_entries(_map({"nominal": {"WB": (0, 4)}, "box 2 kg": {"WB": (3, 4)}}))
    assert any("map:box 2 kg:WB" in line for line in compare_claims(before, flipped))


def test_check_catches_a_changed_count_under_an_unchanged_verdict():
    """2 of 4 members and 3 of 4 are both "undecided": the verdicts agree, and only the cell's
    fraction (0.50 committed, 0.75 regenerated) tells the runs apart. --check names it."""
    before = check_entries(_map({"mu_rb 1.0": {"E": (2, 4)}}))
    after = check_entries(_map({"mu_rb 1.0": {"E": (3, 4)}}))
    assert before[0]["verdict"] == after[0]["verdict"] == "undecided"
    lines = compare_claims(before, after)
    assert lines and all("map:mu_rb 1.0:E fraction" in line for line in lines), lines


def test_judge_evaluates_each_set_up_by_the_claims_rules(monkeypatch):
    """Summaries stand in for the runs: sidewinding does the most work on the box only at 0.30 m."""
    class Run:
        def __init__(self, w):
            self.w = w

        def truncated(self, window):
            return self

    def summaries(results):
        (g, run), = results.items()
        return {g: {"box_work": run.w, "error": ""}}

    monkeypatch.setattr(claims_mod, "gait_summaries", summaries)
    monkeypatch.setattr(claims_mod, "ensemble_claims",
                        lambda ens: [claims_mod._rank(ens, "WB", "most work on the box", "box_work")])
    figure = ensemble_specs(n_members=4)
    mapped = map_specs(figure, setups=SETUPS[:3])
    work = {"box 0.30 m": {"sidewinding": 9.0}}
    runs = {s: Run(work.get(name, {}).get(g, 1.0 if g == "sidewinding" else 2.0))
            for name, per in mapped.items() for g, ms in per.items() for s in ms}
    result = judge(mapped, runs, 6.0)
    verdicts = {r["name"]: r["claims"]["WB"]["verdict"] for r in result["setups"]}
    assert verdicts == {"nominal": "does not hold", "box 0.20 m": "does not hold", "box 0.30 m": "holds"}
    assert result["members"] == 4


def test_the_figure_puts_the_nominal_set_up_in_each_row_ordered_by_value(tmp_path):
    m = _map({s.name: {"WB": (i % 5, 4)} for i, s in enumerate(SETUPS)})
    rows = dict(grid(m["setups"]))
    assert [r["box_size"] for r in rows["box size"]] == [0.10, 0.20, 0.30]
    assert [r["box_mass"] for r in rows["box mass"]] == [0.25, 0.5, 2.0]
    assert [r["placement"] for r in rows["placement"]] == ["per gait", "travel"]
    assert [r["name"] for r in rows["corner"]] == ["box 0.30 m with mu_rb 1.0"]
    paths = draw_map(m, str(tmp_path))
    assert [os.path.basename(p) for p in paths] == ["fig_claims_map.png"]
    with open(paths[0], "rb") as f:
        assert f.read(4) == b"\x89PNG"


def test_the_map_files_are_written_and_a_smoke_run_says_so_first(tmp_path):
    import json

    from cobra_ref.reproduce.map_figure import write_map

    m = _map({"nominal": {"WB": (0, 4)}, "box 2 kg": {"WB": (4, 4)}})
    paths = write_map(m, str(tmp_path), note="SMOKE RUN: a test")
    assert sorted(os.path.basename(p) for p in paths) == ["claims_map.json", "claims_map.md", "fig_claims_map.png"]
    with open(tmp_path / "claims_map.json") as f:
        body = json.load(f)
    assert next(iter(body)) == "smoke run" and body["setups"][1]["claims"]["WB"]["held"] == 4
    assert (tmp_path / "claims_map.md").read_text().startswith("**SMOKE RUN: a test**")


def test_claims_md_names_where_each_claim_holds_right_after_its_table():
    from cobra_ref.reproduce.claims_map import where_lines
    from cobra_ref.reproduce.claims_report import to_markdown

    m = _map({"nominal": {"WB": (0, 4)}, "box 0.30 m": {"WB": (4, 4)}})
    entry = {"id": "WB", "claim": "most work", "values": {}, "holds": False, "verdict": "does not hold",
             "ensemble": {"n": 4, "holds": 0}, "details": {}}
    check = dict(entry, id="TL", kind="check")
    text = to_markdown([entry, check], {"C": {}}, {}, where_lines(m))
    assert "- **WB**: does not hold: nominal; holds: box 0.30 m" in text
    assert text.index("- **WB**") < text.index("## Checks of the model")
