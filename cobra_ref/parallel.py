"""Worker processes for independent simulations: one BLAS thread each, quiet, Ctrl-C to the parent.

Helper: shared by the figure command's gait runs (``reproduce``) and the shooting optimizer.
"""

from __future__ import annotations

import os
import signal


def limit_blas_threads(n: int = 1) -> list[str]:
    """Ask every OpenBLAS library loaded in this process to use ``n`` threads; return their paths.

    Helper: a contact step works on 23 x 23 matrices, where OpenBLAS's threads cost far more than
    they save, above all on a shared machine (measured on the 2-core machine with other jobs
    running: a 0.4 s rollout took 9.1 s with OpenBLAS's default threads and 2.1 s with one, with
    bit-identical results). Finds numpy's and scipy's bundled OpenBLAS in /proc/self/maps (Linux;
    elsewhere, or without OpenBLAS, it does nothing and returns []).
    """
    import ctypes
    import re

    try:
        with open("/proc/self/maps") as f:
            paths = sorted(set(re.findall(r"(/\S*openblas\S*\.so\S*)", f.read())))
    except OSError:
        return []
    done = []
    for path in paths:
        lib = ctypes.CDLL(path)
        for symbol in ("scipy_openblas_set_num_threads64_", "scipy_openblas_set_num_threads",
                       "openblas_set_num_threads64_", "openblas_set_num_threads"):
            setter = getattr(lib, symbol, None)
            if setter is not None:
                setter(ctypes.c_int(n))
                done.append(path)
                break
    return done


def worker_init() -> None:
    """Pool worker initializer.

    Helper: one BLAS thread; Ctrl-C goes to the main process only, which ends
    the workers; file descriptor 1 to /dev/null (OSQP prints "Polishing not needed ..." there even
    with verbose off, once per solve; the workers print nothing else)."""
    limit_blas_threads(1)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)
