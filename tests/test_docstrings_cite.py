"""Every public function of the physics modules says what it implements (STYLE.md C4)."""

import importlib
import inspect

import pytest

MODULES = ["progress", "spatial", "quaternion", "joints", "kinematics", "dynamics", "gaps", "contact", "contact_qp",
           "active_set", "mjcf",
           "fastdyn", "stepper", "analysis", "claims", "reproduce", "regenerate", "mujoco_rollout", "atomic",
           "figures.common", "figures.fig03_snapshots", "figures.fig04_robot_contacts", "figures.fig05_box_contacts",
           "figures.fig06_work_efficiency", "figures.fig07_power", "figures.fig08_torques",
           "figures.fig09_box_distance", "figures.animate", "figures.mujoco_check", "shooting", "parallel",
           "cli_optimize"]


@pytest.mark.parametrize("name", MODULES)
def test_public_functions_name_what_they_implement(name):
    module = importlib.import_module(f"cobra_ref.{name}")
    for fname, obj in vars(module).items():
        if fname.startswith("_") or not inspect.isfunction(obj) or obj.__module__ != module.__name__:
            continue
        doc = inspect.getdoc(obj) or ""
        assert doc, f"{name}.{fname} has no docstring"
        assert "Implements:" in doc or "Helper:" in doc, \
            f"{name}.{fname}: docstring has no Implements: or Helper: line"
