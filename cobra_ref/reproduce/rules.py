"""The fingerprint of the claim rules: SHA-256 of the rule modules' code, docstrings and comments left out.

The claims' statistics and thresholds are fixed in the code before a regeneration (``claims``
module docstring): ``fingerprint`` changes with any change of the code that judges a claim (a
threshold, a condition, a claim's text) and with nothing else (a reworded docstring or comment
leaves it). The regenerated report records it in its settings; CHANGELOG.md names each new
fingerprint by its first ``SHOWN`` hex digits with the reason the rule changed
(tests/test_claim_rules.py).
"""

from __future__ import annotations

import ast
import hashlib
import os

RULE_MODULES = ("claims.py", "steering.py", "verdicts.py")  # in cobra_ref/reproduce/
SHOWN = 12  # hex digits of the fingerprint that CHANGELOG.md names
_HERE = os.path.dirname(os.path.abspath(__file__))


def code_only(source: str) -> str:
    """``source`` as ``ast.unparse`` writes it with every module, class and function docstring
    removed (comments never reach the tree): the code that runs."""
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) \
                    and isinstance(first.value.value, str):
                node.body = node.body[1:] or [ast.Pass()]
    return ast.unparse(tree)


def fingerprint(sources: dict | None = None) -> str:
    """SHA-256 (hex) of ``code_only`` of each rule module, in the order of ``RULE_MODULES``, each
    preceded by its name; ``sources`` {name: source text} replaces the files read (a test changes
    a threshold there)."""
    if sources is None:
        sources = {}
        for name in RULE_MODULES:
            with open(os.path.join(_HERE, name), encoding="utf-8") as f:
                sources[name] = f.read()
    h = hashlib.sha256()
    for name in RULE_MODULES:
        h.update(name.encode() + b"\0" + code_only(sources[name]).encode() + b"\0")
    return h.hexdigest()
