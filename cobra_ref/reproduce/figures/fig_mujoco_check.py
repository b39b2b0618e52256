"""The MuJoCo rollout cross-check as a picture: each gait's box displacement, ours and MuJoCo's.

Helper: the figure of the MuJoCo cross-check (``mujoco_rollout.cross_check``):
one arrow per simulator and gait from the box's start, in the robot's start frame (head at the
origin facing +x), with the angle between the two and the ratio of their lengths; the caption
states the tolerance band (``mujoco_rollout.compare``).
"""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .common import save  # noqa: E402

STEM = "fig_mujoco_check"


def make(rows: list[dict], out_dir: str) -> list[str]:
    """Write ``fig_mujoco_check.png`` / ``.pdf`` from the cross-check rows; return the paths.

    Helper: the cross-check figure (module docstring).
    """
    n = max(len(rows), 1)
    fig, axes = plt.subplots(1, n, figsize=(1.6 * n + 0.6, 2.6), squeeze=False)
    for ax, row in zip(axes[0], rows):
        ours, mj = row.get("ours_displacement"), row["mujoco_displacement"]
        lim = 1.15 * max([abs(v) for v in (*mj, *(ours or (0.0, 0.0)))] + [0.005])
        if ours is not None:
            ax.annotate("", xy=ours, xytext=(0, 0), arrowprops=dict(arrowstyle="->", color="tab:blue", lw=1.8))
        ax.annotate("", xy=mj, xytext=(0, 0), arrowprops=dict(arrowstyle="->", color="tab:orange", lw=1.8))
        ax.set_xlim(-lim, lim)
        ax.set_ylim(-lim, lim)
        ax.set_aspect("equal")
        ax.axhline(0, color="0.85", lw=0.6)
        ax.axvline(0, color="0.85", lw=0.6)
        ax.set_xlabel("box dx [m]")
        verdict = "" if "holds" not in row else ("agree" if row["holds"] else "DIFFER")
        extra = "" if "angle_deg" not in row or row["angle_deg"] is None else \
            f"\n{row['angle_deg']:.0f} deg, x{row['ratio']:.2f}"
        ax.set_title(f"{row['gait']}: {verdict}{extra}", fontsize=8)
        ax.tick_params(labelsize=7)
    axes[0][0].set_ylabel("box dy [m]")
    axes[0][0].plot([], [], color="tab:blue", label="cobra_ref (rigid)")
    axes[0][0].plot([], [], color="tab:orange", label="MuJoCo (soft)")
    fig.legend(loc="lower center", ncol=2, fontsize=7, frameon=False)
    band = rows[0].get("band", "") if rows else ""
    fig.suptitle(f"Box displacement over {rows[0]['duration']:g} s, MuJoCo vs cobra_ref" if rows else "", fontsize=9)
    if band:
        fig.text(0.5, 0.09, f"band: {band}", ha="center", fontsize=6, wrap=True)
    fig.tight_layout(rect=(0, 0.14, 1, 0.95))
    paths = save(fig, out_dir, STEM)
    plt.close(fig)
    return paths
