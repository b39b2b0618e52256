"""Gap functions g_i of [COBRA] eq. (2)-(3), as worked examples on spheres, boxes and the ground.

Convention (cobra_ref/gaps.py): A is the sphere (or box corner), B the plane or box; g > 0 means
separated; n points from B to A; point_A - point_B = g n.
"""

import itertools

import numpy as np
import pytest

from cobra_ref.gaps import (
    box_corner_plane_gaps,
    box_corners,
    contact_frame,
    sphere_box_gap,
    sphere_plane_gap,
)
from cobra_ref.quaternion import quat_to_rot

# A box that is not a cube, so the three axes are told apart: half extents h [m].
HALF = np.array([0.3, 0.2, 0.1])
RADIUS = 0.05


def _random_rotation(rng):
    q = rng.normal(size=4)
    return quat_to_rot(q / np.linalg.norm(q))


def _rot_x(theta):
    """Box -> world rotation by theta about x."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _axis_aligned_gap(c_b, radius=RADIUS, half=HALF):
    return sphere_box_gap(c_b, radius, np.eye(3), np.zeros(3), half)


# ----------------------------------------------------------------------------------- plane


def test_sphere_above_the_plane_has_gap_height_minus_radius():
    """A sphere of radius r centred at height z = 0.3 above z = 0: g = 0.3 - r = 0.25, n = e_z.

    The closest point of the sphere is straight below the centre, c - r e_z = (0.1, -0.2, 0.25),
    and its foot on the plane is (0.1, -0.2, 0); their difference is g e_z.
    """
    gap = sphere_plane_gap([0.1, -0.2, 0.3], RADIUS)
    np.testing.assert_allclose(gap.g, 0.25, atol=1e-15)
    np.testing.assert_allclose(gap.n, [0, 0, 1], atol=0)
    np.testing.assert_allclose(gap.point_A, [0.1, -0.2, 0.25], atol=1e-15)
    np.testing.assert_allclose(gap.point_B, [0.1, -0.2, 0.0], atol=0)
    np.testing.assert_allclose(gap.point_A - gap.point_B, gap.g * gap.n, atol=1e-15)


def test_sphere_sinking_into_the_plane_has_negative_gap():
    """Centre at z = 0.02 < r = 0.05: the sphere is 0.03 m deep, g = 0.02 - 0.05 = -0.03."""
    gap = sphere_plane_gap([0.0, 0.0, 0.02], RADIUS)
    np.testing.assert_allclose(gap.g, -0.03, atol=1e-15)
    np.testing.assert_allclose(gap.point_A, [0.0, 0.0, -0.03], atol=1e-15)
    np.testing.assert_allclose(gap.point_A - gap.point_B, gap.g * gap.n, atol=1e-15)


# ------------------------------------------------------------------------------ sphere-box


@pytest.mark.parametrize("k, s", list(itertools.product(range(3), (-1.0, 1.0))))
def test_sphere_facing_each_box_face_is_distance_to_face_minus_radius(k, s):
    """Centre c_b = s (h_k + 0.07) e_k + (a lateral offset inside the face): g = 0.07 - r = 0.02.

    The closest box point is the centre's projection on the face x_k = s h_k (the lateral
    offset 0.4 h is inside the face, so clipping only touches component k); the distance is
    0.07 and n = s e_k, the outward normal of that face.
    """
    e_k = np.eye(3)[k]
    lateral = 0.4 * HALF * np.array([1.0, -1.0, 1.0]) * (1.0 - e_k)
    c_b = s * (HALF[k] + 0.07) * e_k + lateral
    gap = _axis_aligned_gap(c_b)
    np.testing.assert_allclose(gap.g, 0.07 - RADIUS, atol=1e-14, err_msg=f"face {s:+.0f}e_{k}")
    np.testing.assert_allclose(gap.n, s * e_k, atol=1e-15, err_msg=f"face {s:+.0f}e_{k}")
    np.testing.assert_allclose(gap.point_B, s * HALF[k] * e_k + lateral, atol=1e-15)
    np.testing.assert_allclose(gap.point_A - gap.point_B, gap.g * gap.n, atol=1e-14)


def test_sphere_near_a_box_edge_measures_distance_to_the_edge_line():
    """Centre (h_x + a, h_y + b, z) with |z| < h_z: closest box point is (h_x, h_y, z) on the edge.

    With a = 0.03, b = 0.04 the distance is sqrt(a^2 + b^2) = 0.05, so g = 0.05 - r = 0 (touching),
    and n = (a, b, 0) / 0.05 = (0.6, 0.8, 0).
    """
    a, b, z = 0.03, 0.04, 0.06
    gap = _axis_aligned_gap([HALF[0] + a, HALF[1] + b, z])
    np.testing.assert_allclose(gap.g, np.hypot(a, b) - RADIUS, atol=1e-15)
    np.testing.assert_allclose(gap.n, [0.6, 0.8, 0.0], atol=1e-14)
    np.testing.assert_allclose(gap.point_B, [HALF[0], HALF[1], z], atol=0)


def test_sphere_near_a_box_corner_measures_distance_to_the_corner():
    """Centre h + (a, b, c) with a, b, c > 0: closest point is the corner h itself.

    With (a, b, c) = (0.02, 0.03, 0.06): d = sqrt(4 + 9 + 36) cm = 7 cm, g = 0.07 - 0.05 = 0.02,
    n = (2, 3, 6) / 7. Mirrored to the (-, +, -) corner the normal mirrors with it.
    """
    offset = np.array([0.02, 0.03, 0.06])
    for signs in ([1.0, 1.0, 1.0], [-1.0, 1.0, -1.0]):
        signs = np.array(signs)
        gap = _axis_aligned_gap(signs * (HALF + offset))
        np.testing.assert_allclose(gap.g, 0.02, atol=1e-15, err_msg=f"corner {signs}")
        np.testing.assert_allclose(gap.n, signs * np.array([2, 3, 6]) / 7, atol=1e-15)
        np.testing.assert_allclose(gap.point_B, signs * HALF, atol=0)


def test_sphere_centre_inside_the_box_is_pushed_out_through_the_least_deep_face():
    """Inside the box, g = -(depth of the least-deep face) - r and n is that face's normal.

    c_b = (0.25, -0.05, 0.02): depths h - |c_b| = (0.05, 0.15, 0.08), least is +x:
        g = -0.05 - 0.05 = -0.10, n = +e_x, point_B = (0.3, -0.05, 0.02).
    c_b = (0.10, -0.17, 0.00): depths (0.20, 0.03, 0.10), least is -y:
        g = -0.03 - 0.05 = -0.08, n = -e_y, point_B = (0.10, -0.2, 0.0).
    """
    gap = _axis_aligned_gap([0.25, -0.05, 0.02])
    np.testing.assert_allclose(gap.g, -0.10, atol=1e-15)
    np.testing.assert_allclose(gap.n, [1.0, 0.0, 0.0], atol=0)
    np.testing.assert_allclose(gap.point_B, [0.3, -0.05, 0.02], atol=0)
    gap = _axis_aligned_gap([0.10, -0.17, 0.00])
    np.testing.assert_allclose(gap.g, -0.08, atol=1e-15)
    np.testing.assert_allclose(gap.n, [0.0, -1.0, 0.0], atol=0)
    np.testing.assert_allclose(gap.point_B, [0.10, -0.2, 0.0], atol=0)
    np.testing.assert_allclose(gap.point_A - gap.point_B, gap.g * gap.n, atol=1e-15)


def test_sphere_centre_at_the_box_centre_gets_a_unit_normal_and_no_nan():
    """c_b = 0: depths = h, the thinnest axis (z, h_z = 0.1) wins and sign(0) := +1.

    g = -h_z - r = -0.15, n = +e_z. For a cube every face ties; argmin takes the first, +e_x.
    """
    gap = _axis_aligned_gap(np.zeros(3))
    assert np.all(np.isfinite(gap.n)) and np.all(np.isfinite(gap.frame))
    np.testing.assert_allclose(gap.g, -0.15, atol=1e-15)
    np.testing.assert_allclose(gap.n, [0.0, 0.0, 1.0], atol=0)
    cube = _axis_aligned_gap(np.zeros(3), half=np.full(3, 0.2))
    np.testing.assert_allclose(np.linalg.norm(cube.n), 1.0, atol=1e-15)
    np.testing.assert_allclose(cube.n, [1.0, 0.0, 0.0], atol=0)
    np.testing.assert_allclose(cube.g, -0.25, atol=1e-15)


def test_rotated_translated_box_gives_the_transformed_axis_aligned_result(rng):
    """Gaps are invariant under a rigid motion (R, p) of sphere and box together.

    For c = p + R c_b: g is unchanged, n = R n_0, and both witness points map as x -> p + R x,
    where (g, n_0, ...) is the axis-aligned result at c_b. Checked outside (face, edge, corner)
    and inside.
    """
    R, p = _random_rotation(rng), rng.normal(size=3)
    for c_b in ([0.37, 0.01, -0.02], [0.33, 0.24, 0.0], [-0.33, 0.22, 0.15], [0.2, -0.1, 0.03]):
        ref = _axis_aligned_gap(np.array(c_b))
        gap = sphere_box_gap(p + R @ c_b, RADIUS, R, p, HALF)
        np.testing.assert_allclose(gap.g, ref.g, atol=1e-14, err_msg=f"c_b = {c_b}")
        np.testing.assert_allclose(gap.n, R @ ref.n, atol=1e-14, err_msg=f"c_b = {c_b}")
        np.testing.assert_allclose(gap.point_A, p + R @ ref.point_A, atol=1e-14)
        np.testing.assert_allclose(gap.point_B, p + R @ ref.point_B, atol=1e-14)


# ---------------------------------------------------------------- derivatives and witnesses


def _random_outside_point(rng):
    """A box-coordinate point outside the box (rejection sampling in [-2h, 2h]^3)."""
    while True:
        c_b = rng.uniform(-2.0, 2.0, size=3) * HALF
        if np.any(np.abs(c_b) > HALF + 1e-3):
            return c_b


def _random_inside_point(rng):
    """A box-coordinate point inside, >= 1e-3 deep and with the two least depths >= 1e-3 apart."""
    while True:
        c_b = rng.uniform(-1.0, 1.0, size=3) * HALF
        depth = np.sort(HALF - np.abs(c_b))
        if depth[0] > 1e-3 and depth[1] - depth[0] > 1e-3:
            return c_b


def _central_difference(f, x, eps=1e-7):
    return np.array([(f(x + eps * e) - f(x - eps * e)) / (2 * eps) for e in np.eye(3)])


@pytest.mark.parametrize("where", ["outside", "inside"])
def test_gap_gradient_is_the_normal_for_the_sphere_and_minus_the_normal_for_the_box(rng, where):
    """dg/dc = n and dg/dp_box = -n: W_i = dg_i/dq of [COBRA] eq. (2) is built from n.

    Outside, g = |c_b - clip(c_b)| - r is a distance to a convex set, whose gradient is the unit
    direction from the closest point; inside, g = |c_b,k*| - h_k* - r, whose gradient is
    sign(c_b,k*) e_k* (no ties, so k* is locally constant). Moving the box by dp is the same as
    moving the sphere by -dp. Central differences, eps = 1e-7, at 20 random points each.
    """
    sample = _random_outside_point if where == "outside" else _random_inside_point
    for trial in range(20):
        R, p = _random_rotation(rng), rng.normal(size=3)
        c = p + R @ sample(rng)
        gap = sphere_box_gap(c, RADIUS, R, p, HALF)
        dg_dc = _central_difference(lambda x: sphere_box_gap(x, RADIUS, R, p, HALF).g, c)
        dg_dp = _central_difference(lambda x: sphere_box_gap(c, RADIUS, R, x, HALF).g, p)
        np.testing.assert_allclose(dg_dc, gap.n, atol=1e-6, err_msg=f"{where} trial {trial}")
        np.testing.assert_allclose(dg_dp, -gap.n, atol=1e-6, err_msg=f"{where} trial {trial}")


def test_sphere_plane_gap_gradient_is_the_ground_normal(rng):
    """g = c_z - r is linear in c, so dg/dc = e_z exactly (central differences, eps = 1e-7)."""
    c = rng.normal(size=3)
    dg_dc = _central_difference(lambda x: sphere_plane_gap(x, RADIUS).g, c)
    np.testing.assert_allclose(dg_dc, [0.0, 0.0, 1.0], atol=1e-7)


def test_witness_points_differ_by_gap_times_normal(rng):
    """point_A - point_B = g n: A's point is c - r n and B's point is c - (g + r) n.

    Outside: c - point_B = R (c_b - q_b) = d n and g = d - r. Inside the box the same identity
    holds with d replaced by the signed distance -depth.
    """
    for trial in range(20):
        R, p = _random_rotation(rng), rng.normal(size=3)
        for c_b in (_random_outside_point(rng), _random_inside_point(rng)):
            gap = sphere_box_gap(p + R @ c_b, RADIUS, R, p, HALF)
            np.testing.assert_allclose(gap.point_A - gap.point_B, gap.g * gap.n, atol=1e-14,
                                       err_msg=f"trial {trial}, c_b = {c_b}")
            np.testing.assert_allclose(np.linalg.norm(gap.n), 1.0, atol=1e-14)
        gap = sphere_plane_gap(rng.normal(size=3), RADIUS)
        np.testing.assert_allclose(gap.point_A - gap.point_B, gap.g * gap.n, atol=1e-14)


# ---------------------------------------------------------------------------- contact frame


def _assert_right_handed_frame(C, n, msg=""):
    np.testing.assert_allclose(C.T @ C, np.eye(3), atol=1e-14, err_msg=msg)
    np.testing.assert_allclose(np.linalg.det(C), 1.0, atol=1e-14, err_msg=msg)
    np.testing.assert_allclose(C[:, 0], n, atol=1e-15, err_msg=msg)


def test_contact_frame_is_orthonormal_right_handed_with_the_normal_first(rng):
    """C = [n, t1, t2]: C^T C = 1, det C = +1, C e_1 = n, for random n and for n = +-e_x, e_z.

    The default tangent for the ground normal is e_x, so C(e_z) = [e_z, e_x, e_y]; for n = e_x the
    default switches to e_y, giving [e_x, e_y, e_z].
    """
    normals = [rng.normal(size=3) for _ in range(20)] + [np.eye(3)[0], -np.eye(3)[0], np.eye(3)[2]]
    for n in normals:
        n = n / np.linalg.norm(n)
        _assert_right_handed_frame(contact_frame(n), n, msg=f"n = {n}")
    np.testing.assert_allclose(contact_frame([0, 0, 1]), np.eye(3)[:, [2, 0, 1]], atol=0)
    np.testing.assert_allclose(contact_frame([1, 0, 0]), np.eye(3), atol=0)


def test_contact_frame_aligns_t1_with_the_sliding_hint(rng):
    """t1 = normalised (t_hint - (t_hint . n) n): the hint's part in the tangent plane.

    Ground normal e_z with hint (3, 4, 7): tangent part (3, 4, 0), t1 = (0.6, 0.8, 0),
    t2 = e_z x t1 = (-0.8, 0.6, 0). A hint parallel to n has no tangent part and the default is used.
    """
    C = contact_frame([0, 0, 1], t_hint=[3.0, 4.0, 7.0])
    np.testing.assert_allclose(C[:, 1], [0.6, 0.8, 0.0], atol=1e-15)
    np.testing.assert_allclose(C[:, 2], [-0.8, 0.6, 0.0], atol=1e-15)
    parallel_hint = contact_frame([0, 0, 1], t_hint=[0, 0, -2.0])
    np.testing.assert_allclose(parallel_hint, contact_frame([0, 0, 1]), atol=0)
    for trial in range(20):
        n, t_hint = rng.normal(size=(2, 3))
        n = n / np.linalg.norm(n)
        C = contact_frame(n, t_hint)
        _assert_right_handed_frame(C, n, msg=f"trial {trial}")
        t_perp = t_hint - (t_hint @ n) * n
        np.testing.assert_allclose(C[:, 1], t_perp / np.linalg.norm(t_perp), atol=1e-14)
    gap = sphere_box_gap([0.4, 0.0, 0.0], RADIUS, np.eye(3), np.zeros(3), HALF, t_hint=[1.0, 0.0, 1.0])
    np.testing.assert_allclose(gap.frame[:, 1], [0.0, 0.0, 1.0], atol=1e-15)


# ------------------------------------------------------------------------------ box corners


def test_box_corners_follow_the_itertools_product_sign_order():
    """Corner k = p + R (s_k * h), s_k from itertools.product((-1, 1), repeat=3): corner 0 is
    p - h, corner 1 is p + (-h_x, -h_y, +h_z), corner 7 is p + h (axis-aligned box)."""
    p = np.array([1.0, 2.0, 3.0])
    X = box_corners(np.eye(3), p, HALF)
    assert X.shape == (8, 3)
    np.testing.assert_allclose(X[0], p - HALF, atol=0)
    np.testing.assert_allclose(X[1], p + [-0.3, -0.2, 0.1], atol=0)
    np.testing.assert_allclose(X[7], p + HALF, atol=0)


def test_box_resting_flat_has_four_touching_corners_and_four_at_twice_the_height():
    """A cube of half side h centred at (0.4, -0.1, h) lies flat on z = 0.

    Its bottom corners (s_z = -1, indices 0, 2, 4, 6) are at z = h - h = 0, its top corners at
    z = h + h = 2h. Every normal is e_z and point_B is the corner's foot on the ground.
    """
    h = 0.15
    gaps = box_corner_plane_gaps(np.eye(3), [0.4, -0.1, h], np.full(3, h))
    np.testing.assert_allclose([gap.g for gap in gaps], [0, 2 * h] * 4, atol=1e-15)
    for gap in gaps:
        np.testing.assert_allclose(gap.n, [0, 0, 1], atol=0)
        np.testing.assert_allclose(gap.point_A - gap.point_B, gap.g * gap.n, atol=1e-15)
        _assert_right_handed_frame(gap.frame, gap.n)


def test_box_tilted_45_degrees_about_x_stands_on_its_lower_edge():
    """Half extents (a, b, c) = (0.3, 0.2, 0.1) rotated 45 deg about x: a corner's height above
    the centre is (s_y b + s_z c) / sqrt(2), i.e. -(b+c)/sqrt2, -+(b-c)/sqrt2, (b+c)/sqrt2.

    With the centre at z = (b + c)/sqrt2 the box stands on the edge s_y = s_z = -1 (corners 0
    and 4, g = 0); corners (s_y, s_z) = (-, +) are at sqrt2 c, (+, -) at sqrt2 b, and (+, +) at
    sqrt2 (b + c).
    """
    a, b, c = HALF
    gaps = box_corner_plane_gaps(_rot_x(np.pi / 4), [0.0, 0.0, (b + c) / np.sqrt(2)], HALF)
    sqrt2 = np.sqrt(2)
    expected = {(-1, -1): 0.0, (-1, 1): sqrt2 * c, (1, -1): sqrt2 * b, (1, 1): sqrt2 * (b + c)}
    for k, (s_x, s_y, s_z) in enumerate(itertools.product((-1, 1), repeat=3)):
        np.testing.assert_allclose(gaps[k].g, expected[(s_y, s_z)], atol=1e-15, err_msg=f"corner {k}")
        np.testing.assert_allclose(gaps[k].point_A[0], s_x * a, atol=1e-15, err_msg=f"corner {k}")


# -------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda: sphere_plane_gap([0, 0, 1], -0.1), "radius"),
        (lambda: sphere_box_gap([0, 0, 1], 0.0, np.eye(3), np.zeros(3), HALF), "radius"),
        (lambda: sphere_box_gap([0, 0, 1], np.nan, np.eye(3), np.zeros(3), HALF), "radius"),
        (lambda: sphere_box_gap([0, 0, 1], RADIUS, 2 * np.eye(3), np.zeros(3), HALF), "R_box"),
        (lambda: sphere_box_gap([0, 0, 1], RADIUS, np.diag([1.0, 1.0, -1.0]), np.zeros(3), HALF), "R_box"),
        (lambda: box_corners(np.eye(3), np.zeros(3), [0.3, 0.0, 0.1]), "half"),
        (lambda: box_corner_plane_gaps(np.eye(3), np.zeros(3), [0.3, 0.2]), "half"),
        (lambda: sphere_box_gap([0, 0, np.inf], RADIUS, np.eye(3), np.zeros(3), HALF), "center"),
        (lambda: contact_frame([0.0, 0.0, 0.0]), "nonzero"),
    ],
    ids=["negative radius", "zero radius", "nan radius", "scaled R", "reflection R", "zero half",
         "two half extents", "infinite centre", "zero normal"],
)
def test_bad_geometry_raises_value_error_naming_the_problem(call, message):
    """Negative or zero radii, non-rotations and degenerate boxes are rejected, not silently used."""
    with pytest.raises(ValueError, match=message):
        call()
