"""The ``cobra-ref`` command: one subcommand per user-facing job (``cobra-ref --help``).

Helper: each subcommand lives in its own module with an ``add_parsers(sub)`` function; this
module only assembles them. ``python -m cobra_ref`` runs the same command.
"""

from __future__ import annotations

import argparse

from ..infra.executors import limit_blas_threads
from . import bench, convergence, figures, info, optimize, simulate, sweep, view

SUBCOMMANDS = (info, simulate, optimize, figures, view, bench, convergence, sweep)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of ``cobra-ref`` with every subcommand.

    Helper: the command line (cobra-ref).
    """
    parser = argparse.ArgumentParser(
        prog="cobra-ref",
        description="Reference implementation of COBRA's non-impulsive contact-implicit "
                    "loco-manipulation (arXiv 2404.08714).",
    )
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for module in SUBCOMMANDS:
        module.add_parsers(sub)
    return parser


def main(argv=None) -> int:
    """Entry point of ``cobra-ref``: parse, then run the subcommand.

    Helper: the command line (cobra-ref).
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    # one BLAS thread: the matrices are 23 x 23, where threads cost more than they save
    # (executors.limit_blas_threads; bit-identical results)
    limit_blas_threads(1)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    return args.func(args)
