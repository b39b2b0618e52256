"""One rule set for the model's numbers: what ``CobraParameters`` accepts, ``cobra_model`` (the Model)
accepts too, and what it refuses it refuses with a ValueError that names the field.

Table-driven over every field of ``CobraParameters``: each edge of the field's rule
(``validation.PARAMETER_RULES``), the value at it and the value just past it (the next float).
"""

import dataclasses
import math

import pytest

from cobra_ref.gaits import N_JOINTS
from cobra_ref.infra.validation import INERTIA_RULE, MODEL_NUMBERS, OPTIONAL_PARAMETERS, PARAMETER_RULES
from cobra_ref.model import ModelError
from cobra_ref.params import CobraParameters
from cobra_ref.robots import cobra_model

FIELDS = [f.name for f in dataclasses.fields(CobraParameters)]


def edge_cases(rule):
    """(value, accepted) at and just past each edge of ``rule``: an open edge is refused and the next
    number inside it accepted; a closed edge is accepted and the next number outside it refused."""
    step = (lambda x, to: x + (1 if to > x else -1)) if rule.kind == "int" else math.nextafter
    cases = []
    for edge, is_open, inside, outside in ((rule.low, rule.low_open, math.inf, -math.inf),
                                           (rule.high, rule.high_open, -math.inf, math.inf)):
        if math.isinf(edge):
            continue
        if is_open:
            cases += [(edge, False), (step(edge, inside), True)]
        else:
            cases += [(edge, True), (step(edge, outside), False)]
    return cases


def inertia_cases():
    """(Ixx, Iyy, Izz) at and just past the inertia rule's edges and the triangle inequality."""
    lo, hi = math.nextafter(INERTIA_RULE.low, 1.0), INERTIA_RULE.high
    return [((lo, 1e-3, 1e-3), True), ((INERTIA_RULE.low, 1e-3, 1e-3), False),
            ((hi, hi, hi), True), ((math.nextafter(hi, math.inf), hi, hi), False),
            ((1e-3, 1e-3, 2e-3), True), ((1e-3, 1e-3, 2.1e-3), False)]


def cases():
    out = []
    for name in FIELDS:
        if name.startswith("inertia_"):
            out += [(name, v, ok) for v, ok in inertia_cases()]
            continue
        out += [(name, v, ok) for v, ok in edge_cases(PARAMETER_RULES[name])]
        if name in OPTIONAL_PARAMETERS:
            out.append((name, None, True))
    return out


def test_every_field_has_a_rule():
    assert [n for n in FIELDS if not n.startswith("inertia_") and n not in PARAMETER_RULES] == []
    assert set(MODEL_NUMBERS) <= set(FIELDS)


@pytest.mark.parametrize("name, value, accepted", cases(), ids=lambda x: repr(x) if not isinstance(x, str) else x)
def test_cobra_parameters_and_the_model_agree_at_each_edge(name, value, accepted):
    if accepted:
        params = CobraParameters(**{name: value})
        for with_box in (True, False):
            cobra_model(params, with_box=with_box)  # the Model accepts what CobraParameters accepts
    else:
        with pytest.raises(ValueError, match=name):
            CobraParameters(**{name: value})


def test_the_body_count_is_what_the_gaits_support():
    # the gaits, the reference files and the figures are written for 11 joints: 10 body links
    rule = PARAMETER_RULES["n_body_links"]
    assert rule.low == rule.high == N_JOINTS - 1 == CobraParameters().n_body_links


@pytest.mark.parametrize("name", MODEL_NUMBERS)
def test_the_model_checks_its_numbers_by_the_same_rules(name):
    # a Model built directly (not from CobraParameters) refuses what CobraParameters refuses
    rule = PARAMETER_RULES[name]
    model = cobra_model()
    for value, accepted in edge_cases(rule):
        if accepted:
            dataclasses.replace(model, **{name: value})
        else:
            with pytest.raises(ModelError, match=name):
                dataclasses.replace(model, **{name: value})


def test_the_defaults_are_the_papers():
    # the rules do not move a default: every default is inside its rule
    p = CobraParameters()
    assert (p.n_body_links, p.contact_damping, p.servo_kd, p.box_mass, p.box_size) == (10, 1e3, 5.0, 0.5, 0.10)
