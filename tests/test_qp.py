"""A Ctrl-C that arrives while OSQP solves stops the run (cobra_ref/qp.py, ``osqp_solve``).

OSQP installs its own SIGINT handler for the length of a solve and returns the status
"interrupted" instead of letting Python see the signal. A run stopped by Ctrl-C must stop wherever
the signal lands, so ``osqp_solve`` hands the signal on to Python's handler; where SIGINT is
ignored (a pool worker, which its main process ends), the solve starts again.
"""

import signal
import threading
from types import SimpleNamespace

import numpy as np
import osqp
import pytest
from scipy import sparse

from cobra_ref.qp import INTERRUPTED, osqp_solve


def endless_box_qp(n: int = 50) -> osqp.OSQP:
    """A box QP that OSQP never stops on its own within the test: termination is never checked."""
    rng = np.random.default_rng(0)
    M = rng.standard_normal((n, n))
    P = sparse.triu(M @ M.T + np.eye(n), format="csc")
    solver = osqp.OSQP()
    solver.setup(P=P, q=rng.standard_normal(n), A=sparse.identity(n, format="csc"), l=-np.ones(n),
                 u=np.ones(n), check_termination=0, max_iter=10**7, verbose=False)
    return solver


def test_a_ctrl_c_during_an_osqp_solve_reaches_python_as_a_keyboard_interrupt():
    """SIGINT sent 0.2 s into a solve that would run for many seconds: ``osqp_solve`` raises
    KeyboardInterrupt at its ``raise_signal`` (OSQP alone returns the status "interrupted")."""
    solver = endless_box_qp()
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.2, signal.raise_signal, (signal.SIGINT,))
    try:
        timer.start()
        with pytest.raises(KeyboardInterrupt) as caught:
            osqp_solve(solver)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert "raise_signal" in str(caught.traceback[-1].statement)


class OnceInterrupted:
    """A stand-in OSQP whose first solve is stopped by Ctrl-C and whose second solves."""

    def __init__(self):
        self.starts, self.solves = [], 0

    def warm_start(self, x, y):
        self.starts.append((x, y))

    def solve(self, raise_error):
        self.solves += 1
        return SimpleNamespace(info=SimpleNamespace(status=INTERRUPTED if self.solves == 1 else "solved"))


def test_where_sigint_is_ignored_an_interrupted_solve_starts_again_from_its_warm_start():
    x0, y0 = np.array([0.5, -0.5]), np.zeros(2)
    solver = OnceInterrupted()
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        res = osqp_solve(solver, x0, y0)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert solver.solves == 2 and res.info.status == "solved"
    assert len(solver.starts) == 2 and all(x is x0 and y is y0 for x, y in solver.starts)
