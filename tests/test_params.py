"""The parameter sheet: every number has a source, and the derived geometry fits the inertias."""

import dataclasses

import numpy as np

import cobra_ref as cr
from cobra_ref.params import SOURCES, UNITS, CobraParameters, parameter_table


def test_every_parameter_has_a_source_and_a_unit():
    names = {f.name for f in dataclasses.fields(CobraParameters)}
    assert names == set(SOURCES) == set(UNITS)
    for name, _, _, source in parameter_table():
        assert source.split(":")[0].split(" ")[0] in {"paper", "derived", "datasheet", "assumption"}, name


def test_cylinder_geometry_reproduces_the_paper_inertias():
    """A solid cylinder of the derived (L, r) and 0.5 kg has the paper's inertias within 2 %.

    I_xx = m r^2 / 2, I_yy = I_zz = m (3 r^2 + L^2) / 12 (assumption A1). The paper's Iyy and Izz
    differ by <= 5 %, so the cylinder (Iyy = Izz) matches their mean.
    """
    p = CobraParameters()
    for L, r, I in [(p.length_link, p.radius_link, p.inertia_link), (p.length_head, p.radius_head, p.inertia_head),
                    (p.length_tail, p.radius_tail, p.inertia_tail)]:
        m = 0.5
        np.testing.assert_allclose(m * r**2 / 2, I[0], rtol=0.02)
        np.testing.assert_allclose(m * (3 * r**2 + L**2) / 12, (I[1] + I[2]) / 2, rtol=0.02)


def test_total_length_is_the_reported_1_7_m():
    """Head + 10 links + tail + 11 gaps = 1.695 m, the 1.7 m of arXiv 2512.05008 (assumption A2)."""
    np.testing.assert_allclose(CobraParameters().total_length, 1.695, atol=1e-12)
    np.testing.assert_allclose(CobraParameters().total_length, 1.7, atol=0.01)


def test_model_has_six_yaw_and_five_pitch_joints_with_j5_pitch_and_j6_yaw(cobra):
    types = cobra.joint_type[1:12]
    assert types.count("Rz") == 6 and types.count("Ry") == 5
    assert cobra.joint_type[cobra.joint_names.index("J5")] == "Ry"
    assert cobra.joint_type[cobra.joint_names.index("J6")] == "Rz"


def test_model_masses_and_box(cobra):
    assert np.allclose(cobra.mass[:12], 0.5) and cobra.mass[12] == 0.5
    np.testing.assert_allclose(np.diag(cobra.I_com[12]), 0.5 * 0.1**2 / 6)
    assert (cobra.nq, cobra.nv) == (25, 23)


def test_straight_snake_spans_the_total_length(cobra):
    """From the head's front face to the tail's back face along x: 1.695 m - nothing lost."""
    kin = cr.forward_kinematics(cobra, cr.neutral_q(cobra))
    p = CobraParameters()
    front = kin.o[0][0] + p.length_head / 2
    tail_back = kin.o[11][0] + cobra.com[11][0] - p.length_tail / 2
    np.testing.assert_allclose(front - tail_back, p.total_length, atol=1e-12)
