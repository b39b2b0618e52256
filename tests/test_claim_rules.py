"""The claim rules are fixed in the code before a regeneration: their fingerprint (``reproduce.rules``)
changes with a threshold and not with a docstring or a comment, and CHANGELOG.md names the current
one with the reason the rules changed."""

import os
import re

from cobra_ref.reproduce import rules

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def _sources() -> dict:
    out = {}
    for name in rules.RULE_MODULES:
        with open(os.path.join(ROOT, "cobra_ref", "reproduce", name), encoding="utf-8") as f:
            out[name] = f.read()
    return out


def test_the_fingerprint_changes_with_a_threshold_and_not_with_prose():
    sources = _sources()
    now = rules.fingerprint(sources)
    assert now == rules.fingerprint() and re.fullmatch(r"[0-9a-f]{64}", now)

    def changed(name, old, new):
        assert old in sources[name], (name, old)
        return dict(sources, **{name: sources[name].replace(old, new)})
    assert rules.fingerprint(changed("claims.py", "IMPULSE_SHARE = 0.01  #", "IMPULSE_SHARE = 0.03  #")) != now
    assert rules.fingerprint(changed("steering.py", "GOAL_DISTANCE_SHARE = 0.2", "GOAL_DISTANCE_SHARE = 0.3")) != now
    prose = changed("verdicts.py", '"""The bookkeeping', '"""Reworded: the bookkeeping')
    prose["verdicts.py"] = prose["verdicts.py"].replace("# fraction of members", "# the share of members")
    assert prose["verdicts.py"] != sources["verdicts.py"] and rules.fingerprint(prose) == now


def test_changelog_names_the_current_rules_with_their_reason():
    """The CHANGELOG line that names the first ``SHOWN`` hex digits of the current fingerprint says
    why the claim rules changed ("claim rules ... because ...")."""
    short = rules.fingerprint()[:rules.SHOWN]
    with open(os.path.join(ROOT, "CHANGELOG.md"), encoding="utf-8") as f:
        lines = [line for line in f if short in line]
    assert lines, f"CHANGELOG.md does not name the claim rules' fingerprint {short} (reproduce.rules.fingerprint)"
    assert any("claim rules" in line and "because" in line for line in lines), lines
