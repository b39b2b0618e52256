"""``cobra-ref view`` and ``cobra-ref render``: see a saved run in MuJoCo's viewer, or render it to
a still, a GIF or an MP4.

The command-line side of :mod:`cobra_ref.viz`. Both read the NPZ of ``cobra-ref simulate --out
RUN.npz``. ``render`` prints one JSON line (what was written, by which renderer and OpenGL backend,
how long it took) on stdout and its progress on stderr.
"""

from __future__ import annotations

import json
import sys

from ..infra.output import OutputError
from ..infra.validation import RULES
from .common import check_out


def read_run(path: str):
    """The run at ``path``, or a clear error.
    """
    from ..viz.scene import RunError, load_run

    try:
        traj = load_run(path)
    except RunError as exc:
        raise SystemExit(f"error: {exc}") from None
    if traj.error:
        print(f"note: {path} is a run that stopped early: {traj.error}", file=sys.stderr)
    return traj


def cmd_view(args) -> int:
    """Replay a run in MuJoCo's interactive viewer.
    """
    from ..viz import view

    traj = read_run(args.run)
    try:
        import mujoco  # noqa: F401
    except ImportError:
        raise SystemExit("error: the viewer needs mujoco (pip install mujoco); without it, "
                         f"`cobra-ref render {args.run} --out run.gif` draws the run with matplotlib") from None
    problem = view.display_problem()
    if problem:
        raise SystemExit(f"error: the interactive viewer needs a display ({problem}).\n"
                         f"Render the run to a file instead: cobra-ref render {args.run} --out run.mp4 "
                         f"(or run.gif, or --at 2.5 --out still.png)")
    try:
        shown = view.replay(traj, speed=args.speed, loop=not args.once, follow=not args.no_follow,
                            force_scale=args.force_scale)
    except RuntimeError as exc:  # e.g. macOS, where launch_passive needs mjpython
        raise SystemExit(f"error: the viewer could not start: {exc}") from None
    print(json.dumps({"run": args.run, **shown}))
    return 0


def cmd_render(args) -> int:
    """Render a run offscreen to a PNG still, a GIF or an MP4.
    """
    from ..infra.progress import progress_printer
    from ..viz.render import RenderError, VideoSettings, output_format, render_file

    try:
        output_format(args.out)
    except RenderError as exc:
        raise SystemExit(f"error: {exc}") from None
    check_out(args.out, "--out")
    traj = read_run(args.run)
    try:
        video = VideoSettings(fps=args.fps, width=args.width, height=args.height, speed=args.speed,
                              force_scale=args.force_scale)
        info = render_file(traj, args.out, video, at=args.at, renderer=args.renderer,
                           progress=None if args.quiet else progress_printer(f"render {args.out}"))
    except (RenderError, OutputError) as exc:  # bad input, or a write that failed (a full disk)
        raise SystemExit(f"error: {exc}") from None
    if info["renderer"] == "mujoco":
        where = "" if info["process"] == "this" else " (in a child process: mujoco was imported with another)"
        print(f"render: MuJoCo offscreen, OpenGL backend MUJOCO_GL={info['gl']}{where}", file=sys.stderr)
    elif info["fallback_reason"]:
        print(f"render: MuJoCo cannot render here ({info['fallback_reason']}); "
              f"drew the frames with matplotlib instead", file=sys.stderr)
    info.pop("camera", None)
    print(json.dumps(info))
    return 0


def add_parsers(sub) -> None:
    """The ``view`` and ``render`` subcommands.
    """
    from ..viz.scene import FORCE_SCALE

    p = sub.add_parser("view", help="replay a saved run in MuJoCo's interactive viewer (needs a display)",
                       description="Replay RUN.npz (from `cobra-ref simulate --out`) in MuJoCo's viewer on the "
                                   "exported MJCF: the states of the run (nothing is simulated), the contact "
                                   "points and force arrows of its contact log (green robot-ground, red robot-box, "
                                   "blue box-ground), the box's path and the time. Space pauses. Prints one JSON line on exit: "
                                   "the number of frames shown and the last time shown.")
    p.add_argument("run", metavar="RUN.npz", help="a run written by cobra-ref simulate --out")
    p.add_argument("--speed", type=RULES["speed"].arg("--speed"), default=1.0,
                   help="replay speed: 1 = real time (default), 0.25 = four times slower")
    p.add_argument("--once", action="store_true",
                   help="play the run once, then close the window and exit (default: start again at the end)")
    p.add_argument("--no-follow", action="store_true", help="keep the camera where it is (default: follow the robot)")
    p.add_argument("--force-scale", type=RULES["force_scale"].arg("--force-scale"), default=FORCE_SCALE,
                   help=f"arrow length per newton [m/N] (default {FORCE_SCALE:g})")
    p.set_defaults(func=cmd_view)

    r = sub.add_parser("render", help="render a saved run to a PNG still, a GIF or an MP4 (offscreen)",
                       description="Render RUN.npz offscreen with MuJoCo (OpenGL backend EGL, else OSMesa; "
                                   "matplotlib's 3-D drawing when neither works), with the contact force arrows, "
                                   "the box's path, the time and a camera that follows the robot and keeps the "
                                   "box in view. MP4 needs the optional extra: pip install 'cobra-ref[video]'.")
    r.add_argument("run", metavar="RUN.npz", help="a run written by cobra-ref simulate --out")
    r.add_argument("--out", required=True, metavar="FILE", help="FILE.mp4, FILE.gif, or FILE.png (a still)")
    r.add_argument("--at", type=RULES["at"].arg("--at"), default=None,
                   help="time of the still [s] from the run's start (PNG only; default: the last state)")
    r.add_argument("--fps", type=RULES["fps"].arg("--fps"), default=30.0, help="video frames per second (default 30)")
    r.add_argument("--speed", type=RULES["speed"].arg("--speed"), default=1.0,
                   help="simulated seconds per video second (default 1; 0.25 = slow motion)")
    r.add_argument("--width", type=RULES["width"].arg("--width"), default=640, help="image width [px] (default 640)")
    r.add_argument("--height", type=RULES["height"].arg("--height"), default=480, help="image height [px] (default 480)")
    r.add_argument("--force-scale", type=RULES["force_scale"].arg("--force-scale"), default=FORCE_SCALE,
                   help=f"arrow length per newton [m/N] (default {FORCE_SCALE:g})")
    r.add_argument("--renderer", choices=("auto", "mujoco", "matplotlib"), default="auto",
                   help="auto (default): MuJoCo if an OpenGL backend works, else matplotlib")
    r.add_argument("--quiet", action="store_true", help="no progress line")
    r.set_defaults(func=cmd_render)
