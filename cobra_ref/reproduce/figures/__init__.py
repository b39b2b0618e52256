"""Figure scripts of [COBRA] figs. 3-9, the contact points of figs. 4-5 and the GIFs, one module per figure.

Every module in ``FIGURES`` has ``make(results: dict[str, Trajectory], out_dir: str, model,
ensemble=None, goals=None) -> list[str]`` (``ensemble``: {gait: [``analysis.summary`` per member]}, see
``common``; ``goals``: {gait: (dx, dy)} [m], each optimum's goal from the box's start, which the
figures that show goals mark) and runs standalone as ``python -m cobra_ref.reproduce.figures.<module>`` (quick 1 s simulations,
see ``common.main``). ``PAPER_FIGURES`` are the paper's figures (PNG + PDF each); ``FIGURES`` adds
``animate`` (one GIF per gait, and the note ``animations.json`` of how each was rendered) at the
end.
"""

from __future__ import annotations

import importlib

PAPER_FIGURES = ("fig03_snapshots", "fig04_robot_contacts", "fig05_box_contacts", "fig_contact_points",
                 "fig06_work_efficiency",
                 "fig07_power", "fig08_torques", "fig09_box_distance")
FIGURES = PAPER_FIGURES + ("animate",)


def make_all(results: dict, out_dir: str, model, animations: bool = True, ensemble: dict | None = None,
             goals: dict | None = None) -> list[str]:
    """Run every module's ``make`` in ``FIGURES`` order (without the GIFs if ``animations`` is
    False), each with ``ensemble`` and ``goals``, and return all paths written.

    ``results`` = {gait: Trajectory} (e.g. from ``reproduce.run_all``, by gait); gaits missing from
    it are left out of every figure.
    """
    paths = []
    for name in FIGURES if animations else PAPER_FIGURES:
        module = importlib.import_module(f"{__name__}.{name}")
        paths += module.make(results, out_dir, model, ensemble=ensemble, goals=goals)
    return paths


__all__ = ["PAPER_FIGURES", "FIGURES", "make_all"]
