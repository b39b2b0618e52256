"""What the viewer and the renderer show of a saved run: the MJCF scene, the pose at a state, the
contact forces of a step, the box's path and where the camera looks.

Shared by :mod:`cobra_ref.viz.view` and :mod:`cobra_ref.viz.render`. The scene is
``to_mjcf(cobra_model())`` with visual-only additions (a 0.1 m checker ground, opaque body colours,
the contact spheres moved to geom group 3, which MuJoCo hides by default); masses, joints and
contact geometry are untouched, so ``q`` of a run is MuJoCo's ``qpos`` (nq = 25).

The markers come from the run's contact log, never from MuJoCo's own contact detection: at state
k, the rows of step k (the step from t_k to t_k+1; the last state shows the last step). Each row
is an arrow from ``contact_point`` along ``contact_force`` (the force on body A, see
:mod:`cobra_ref.trajectory`), ``force_scale`` metres per newton, and a small sphere at the point,
coloured by ``contact_kind``. MuJoCo is imported inside the functions only, so that the renderer
can choose the OpenGL backend (``MUJOCO_GL``) before the first import.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET

import numpy as np

from ..mjcf import to_mjcf
from ..robots import cobra_model
from ..trajectory import CONTACT_KEYS, Trajectory
from .run_checks import KIND_NAMES, N_POSE, RunError, check_run

FORCE_SCALE = 0.02  # arrow length per newton [m/N]: a link's share of the weight (~5 N) clears its radius
KIND_RGBA = np.array([[0.10, 0.65, 0.20, 1.0],   # robot-ground: green
                      [0.85, 0.10, 0.10, 1.0],   # robot-box: red
                      [0.15, 0.35, 0.90, 1.0]],  # box-ground: blue
                     dtype=np.float32)
PATH_RGBA = np.array([0.0, 0.0, 0.0, 1.0], dtype=np.float32)
# bodies half transparent, so that the arrows of the contacts under and inside them show
HEAD_RGBA, LINK_RGBA, TAIL_RGBA = "0.55 0.18 0.18 0.55", ("0.29 0.44 0.65 0.55", "0.62 0.71 0.84 0.55"), \
    "0.33 0.33 0.33 0.55"
BOX_RGBA = "0.88 0.63 0.25 0.6"
ARROW_WIDTH, POINT_RADIUS = 0.008, 0.008  # [m]
PATH_SEGMENTS = 200  # at most this many line segments for the box's path
BODY_MARGIN = 0.09  # the largest body radius (0.057 m, the tail) or the box's half diagonal (0.087 m) [m]


def load_run(path: str) -> Trajectory:
    """Read a run written by ``cobra-ref simulate --out RUN.npz`` and check what the viewer needs.

    The viewer and the renderer. Raises RunError naming the problem: a missing file, a file that is
    not an NPZ, a missing array, or an array the checks of :func:`run_checks.check_run` refuse.
    """
    if not os.path.isfile(path):
        raise RunError(f"no such run file: {path}")
    try:
        traj = Trajectory.from_npz(path)
    except Exception:  # noqa: BLE001 -- another version's records, or not a run: read what a replay needs
        traj = replay_arrays(path)
    check_run(traj, path)
    return traj


def replay_arrays(path: str) -> Trajectory:
    """A Trajectory holding only what a replay shows: t, q, box_pose and the contact log (qd and
    tau when present); RunError naming the first missing array, or a file numpy cannot read.

    :func:`load_run` for runs whose per-step records differ from this version's.
    """
    try:
        z = np.load(path, allow_pickle=False)
        if not hasattr(z, "files"):  # a .npy file: one array
            raise ValueError("one array, not an NPZ archive of arrays")
        with z:
            missing = [key for key in ("t", "q", "box_pose") + CONTACT_KEYS[:6] if key not in z.files]
            arrays = {} if missing else {key: z[key] for key in z.files}
    except Exception as exc:  # numpy's errors for a non-NPZ file vary: ValueError, OSError, BadZipFile
        raise RunError(f"{path} is not a readable NPZ run ({type(exc).__name__}: {exc})") from None
    if missing:
        raise RunError(f"{path} is not a cobra-ref run: it has no array {missing[0]!r}")
    t = arrays["t"]
    n = len(t) if t.ndim == 1 else 0
    dt = arrays.get("dt", np.array(0.0))
    return Trajectory(float(dt) if dt.size == 1 and np.issubdtype(dt.dtype, np.number) else 0.0, t, arrays["q"], arrays.get("qd", np.zeros((n, 0))),
                      arrays.get("tau", np.zeros((max(n - 1, 0), 0))), arrays["box_pose"], {},
                      {k: arrays[k] for k in CONTACT_KEYS if k in arrays},
                      error=str(arrays["error"]) if "error" in arrays else "")


def scene_xml() -> str:
    """The MJCF of COBRA and the box with the visual additions listed in the module docstring.

    The viewer's and the renderer's model (the physics is that of ``to_mjcf``).
    """
    model = cobra_model()
    root = ET.fromstring(to_mjcf(model))
    visual = ET.Element("visual")
    ET.SubElement(visual, "global", offwidth="1920", offheight="1080")
    ET.SubElement(visual, "headlight", ambient="0.3 0.3 0.3", diffuse="0.4 0.4 0.4")
    asset = ET.Element("asset")
    ET.SubElement(asset, "texture", name="sky", type="skybox", builtin="gradient", rgb1="0.85 0.9 0.95",
                  rgb2="0.55 0.6 0.7", width="64", height="64")
    ET.SubElement(asset, "texture", name="grid", type="2d", builtin="checker", rgb1="0.66 0.66 0.66",
                  rgb2="0.58 0.58 0.58", width="64", height="64")
    ET.SubElement(asset, "material", name="grid", texture="grid", texrepeat="5 5", texuniform="true")
    # after <compiler> and <option>: MJCF sections may come in any order, this keeps the file readable
    root.insert(3, visual)
    root.insert(4, asset)
    for geom in root.iter("geom"):
        name = geom.get("name", "")
        if name == "ground":
            geom.set("material", "grid")
        elif name.startswith("sphere_"):
            geom.set("group", "3")
        elif name.startswith("box_"):
            geom.set("rgba", BOX_RGBA)
        elif name.startswith("visual_"):
            i = int(name.split("_")[1])
            body = model.body_names[i]
            geom.set("rgba", HEAD_RGBA if body == "head" else TAIL_RGBA if body == "tail" else LINK_RGBA[i % 2])
    return ET.tostring(root, encoding="unicode")


def build_scene():
    """``(MjModel, MjData)`` of :func:`scene_xml`, checked to have nq = 25.

    The viewer and the renderer (imports mujoco).
    """
    import mujoco

    m = mujoco.MjModel.from_xml_string(scene_xml())
    if m.nq != N_POSE:
        raise RunError(f"the MJCF scene has nq = {m.nq}, expected {N_POSE}")
    return m, mujoco.MjData(m)


def set_state(m, d, traj: Trajectory, k: int) -> None:
    """Pose the MuJoCo scene at state k: qpos = q[k], time = t[k], then ``mj_forward``.

    One replayed frame (q is MuJoCo's qpos layout, see :mod:`cobra_ref.mjcf`).
    """
    import mujoco

    d.qpos[:] = traj.q[k]
    d.qvel[:] = traj.qd[k] if traj.qd.shape == (len(traj.t), m.nv) else 0.0
    d.time = float(traj.t[k])
    mujoco.mj_forward(m, d)


def state_indices(traj: Trajectory, times) -> np.ndarray:
    """Index of the state nearest to each time (clipped to the run).
    """
    t = np.asarray(traj.t, dtype=float)
    times = np.clip(np.atleast_1d(np.asarray(times, dtype=float)), t[0], t[-1])
    if len(t) == 1:
        return np.zeros(len(times), dtype=int)
    right = np.clip(np.searchsorted(t, times), 1, len(t) - 1)
    left = right - 1
    return np.where(np.abs(times - t[left]) <= np.abs(t[right] - times), left, right)


def frame_times(traj: Trajectory, fps: float, speed: float = 1.0) -> np.ndarray:
    """Times of the frames of a video at ``fps`` frames per second of video, ``speed`` simulated
    seconds per video second (0.25 = four times slower than real time), from the first state to the
    last.
    """
    step = speed / fps
    return traj.t[0] + np.arange(int(np.floor(traj.duration / step + 1e-9)) + 1) * step


def contact_step(traj: Trajectory, k: int) -> int:
    """The step whose contact log is shown at state k: step k, the last step at the last state.
    """
    return min(int(k), max(len(traj.t) - 2, 0))


def contact_arrows(traj: Trajectory, k: int) -> dict:
    """The contact-log rows shown at state k: ``points`` (m, 3), ``forces`` (m, 3) [N], ``kinds``
    (m,) and ``bodies`` (m,), in the log's order.

    The force arrows of the viewer and the renderer.
    """
    c = traj.contacts
    if any(key not in c for key in CONTACT_KEYS[:6]):
        raise RunError("the run has no contact log")
    rows = np.flatnonzero(np.asarray(c["contact_step"]) == contact_step(traj, k))
    return {"points": np.asarray(c["contact_point"], float).reshape(-1, 3)[rows],
            "forces": np.asarray(c["contact_force"], float).reshape(-1, 3)[rows],
            "kinds": np.asarray(c["contact_kind"], int)[rows],
            "bodies": np.asarray(c["contact_body"], int)[rows]}


def box_path(traj: Trajectory, k: int, segments: int = PATH_SEGMENTS) -> np.ndarray:
    """(n, 3) points of the box centre's path up to state k, at most ``segments`` + 1 of them,
    lowered onto the ground (z = 2 mm, above the ground so it is not hidden by it).

    The path line of the viewer and the renderer.
    """
    idx = np.unique(np.linspace(0, k, min(k, segments) + 1).round().astype(int))
    pts = np.array(traj.box_pose[idx, :3], dtype=float)
    pts[:, 2] = 0.002
    return pts


def add_markers(scn, traj: Trajectory, k: int, force_scale: float = FORCE_SCALE) -> int:
    """Append to the MjvScene ``scn`` the contact arrows and points of state k and the box's path;
    return how many geoms were added (fewer when ``scn`` is full).

    The viewer's ``user_scn`` and the renderer's scene. An arrow runs from the contact point to
    point + force_scale * force (``mjv_connector``: its z axis is the force direction, its length
    ``size[2]``).
    """
    import mujoco

    start = scn.ngeom
    eye = np.eye(3).ravel()

    def new_geom():
        if scn.ngeom >= scn.maxgeom:
            return None
        g = scn.geoms[scn.ngeom]
        scn.ngeom += 1
        return g

    arrows = contact_arrows(traj, k)
    for p, f, kind in zip(arrows["points"], arrows["forces"], arrows["kinds"]):
        rgba = KIND_RGBA[kind] if 0 <= kind < len(KIND_RGBA) else PATH_RGBA
        g = new_geom()
        if g is None:
            break
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_ARROW, np.zeros(3), np.zeros(3), eye, rgba)
        mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_ARROW, ARROW_WIDTH, p, p + force_scale * f)
        g = new_geom()
        if g is None:
            break
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_SPHERE, np.full(3, POINT_RADIUS), p, eye, rgba)
    path = box_path(traj, k)
    for a, b in zip(path[:-1], path[1:]):
        g = new_geom()
        if g is None:
            break
        mujoco.mjv_initGeom(g, mujoco.mjtGeom.mjGEOM_LINE, np.zeros(3), np.zeros(3), eye, PATH_RGBA)
        mujoco.mjv_connector(g, mujoco.mjtGeom.mjGEOM_LINE, 2.0, a, b)
    return scn.ngeom - start


def arrows_in_scene(scn, force_scale: float = FORCE_SCALE) -> tuple[np.ndarray, np.ndarray]:
    """The (start point, force) of every arrow geom in ``scn``, read back from the geoms.

    Checks of what a frame draws (force = z axis of the arrow * its length / force_scale).
    """
    import mujoco

    starts, forces = [], []
    for i in range(scn.ngeom):
        g = scn.geoms[i]
        if g.type == mujoco.mjtGeom.mjGEOM_ARROW:
            starts.append(np.array(g.pos, dtype=float))
            forces.append(np.array(g.mat, dtype=float).reshape(3, 3)[:, 2] * float(g.size[2]) / force_scale)
    return np.array(starts).reshape(-1, 3), np.array(forces).reshape(-1, 3)


def scene_points(m, d, traj: Trajectory, k: int) -> dict:
    """World positions at state k (after :func:`set_state`): ``robot`` (12, 3) body frames,
    ``ends`` (24, 3) the two end centres of every body's cylinder, ``box`` (3,) the box centre.

    Camera framing and the renderer's in-frame check.
    """
    import mujoco

    box_id = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, "box")
    robot = [i for i in range(1, m.nbody) if i != box_id]
    cyl = [g for g in range(m.ngeom)
           if m.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER and m.geom_bodyid[g] in robot]
    axis = d.geom_xmat[cyl].reshape(-1, 3, 3)[:, :, 2] * m.geom_size[cyl, 1:2]
    ends = np.vstack([d.geom_xpos[cyl] - axis, d.geom_xpos[cyl] + axis])
    return {"robot": np.array(d.xpos[robot]), "ends": ends, "box": np.array(traj.box_pose[k, :3], dtype=float)}


def camera_axes(azimuth: float, elevation: float) -> np.ndarray:
    """Rows forward, up, right of MuJoCo's free camera with these angles [deg].

    Camera framing (forward = (cos el cos az, cos el sin az, sin el), up is forward turned 90
    degrees upwards in the vertical plane, right = forward x up).
    """
    az, el = np.deg2rad(azimuth), np.deg2rad(elevation)
    forward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    up = np.array([-np.sin(el) * np.cos(az), -np.sin(el) * np.sin(az), np.cos(el)])
    return np.stack([forward, up, np.cross(forward, up)])


def follow_camera(m, d, traj: Trajectory, steps, width: int, height: int) -> dict:
    """A camera that follows the robot and keeps the box in view over the frames ``steps``.

    The renderer's (and the viewer's first) camera. ``lookat`` (n, 3): per frame, the centre of the
    bounding box of the robot's cylinders (their end centres) and the box. ``azimuth`` looks across
    the robot's net travel, from the box's side; ``elevation`` -40 degrees. ``distance``: one value
    for the whole video (no zooming), the smallest at which every cylinder end and the box centre,
    widened by ``BODY_MARGIN`` sideways, falls inside the field of view in every frame, plus 10 %: a
    point at v from ``lookat`` has depth D + v.forward and must satisfy |v.right| + margin <=
    tan(half horizontal fov) * depth, and the same with up and the vertical fov.
    """
    steps = np.atleast_1d(np.asarray(steps, dtype=int))
    lookat, offsets, robot_centre = [], [], []
    for k in steps:
        set_state(m, d, traj, int(k))
        pts = scene_points(m, d, traj, int(k))
        allp = np.vstack([pts["ends"], pts["box"][None]])
        centre = 0.5 * (allp.min(axis=0) + allp.max(axis=0))
        lookat.append(centre)
        offsets.append(allp - centre)
        robot_centre.append(pts["robot"].mean(axis=0))
    lookat, robot_centre, offsets = np.array(lookat), np.array(robot_centre), np.concatenate(offsets)
    travel = robot_centre[-1, :2] - robot_centre[0, :2]
    if np.linalg.norm(travel) < 1e-3:  # no net travel: look across the snake's head-to-tail line
        set_state(m, d, traj, int(steps[0]))
        pts = scene_points(m, d, traj, int(steps[0]))["robot"]
        travel = (pts[0] - pts[-1])[:2]
    heading = np.arctan2(travel[1], travel[0])
    look = heading + np.pi / 2  # across the travel
    to_robot = robot_centre[0, :2] - traj.box_pose[steps[0], :2]
    if np.dot([np.cos(look), np.sin(look)], to_robot) < 0:
        look += np.pi  # look from the box's side towards the robot
    azimuth, elevation = float(np.rad2deg(look) % 360.0), -40.0
    forward, up, right = camera_axes(azimuth, elevation)
    tan_v = np.tan(np.deg2rad(float(m.vis.global_.fovy)) / 2)
    tan_h = tan_v * width / height
    need = np.maximum((np.abs(offsets @ right) + BODY_MARGIN) / tan_h,
                      (np.abs(offsets @ up) + BODY_MARGIN) / tan_v) - offsets @ forward
    return {"lookat": lookat, "distance": 1.1 * float(np.max(need)), "azimuth": azimuth, "elevation": elevation}


def make_camera(camera: dict, i: int = 0):
    """The ``MjvCamera`` (free camera) of frame i of :func:`follow_camera`.
    """
    import mujoco

    cam = mujoco.MjvCamera()
    cam.type = mujoco.mjtCamera.mjCAMERA_FREE
    cam.lookat[:] = camera["lookat"][i]
    cam.distance = camera["distance"]
    cam.azimuth = camera["azimuth"]
    cam.elevation = camera["elevation"]
    return cam


def project(scn, points, width: int, height: int) -> np.ndarray:
    """(n, 3) image coordinates (column, row from the top-left corner [px], depth [m]) of world
    points, through the camera of the MjvScene ``scn`` (after ``mjv_updateScene``).

    Implements: the pinhole projection MuJoCo's renderer applies (the mean of the two eyes'
    GL cameras, ``mjv_averageCamera``; the horizontal half-width of the frustum from the vertical one
    and the image's aspect ratio). A point is in the image when 0 <= column < width,
    0 <= row < height and depth > 0.
    """
    import mujoco

    cam = mujoco.mjv_averageCamera(scn.camera[0], scn.camera[1])
    fwd, up = np.array(cam.forward, float), np.array(cam.up, float)
    right = np.cross(fwd, up)
    v = np.atleast_2d(np.asarray(points, float)) - np.array(cam.pos, float)
    depth = v @ fwd
    near, top, bottom = float(cam.frustum_near), float(cam.frustum_top), float(cam.frustum_bottom)
    half_w = 0.5 * (top - bottom) * width / height
    x = (v @ right) * near / depth
    y = (v @ up) * near / depth
    col = (x - (float(cam.frustum_center) - half_w)) / (2 * half_w) * width
    row = (top - y) / (top - bottom) * height
    return np.stack([col, row, depth], axis=1)
