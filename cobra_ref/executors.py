"""Where independent simulations run: worker processes, a serial executor, and their shutdown.

Helper: shared by the figure command's gait runs (``reproduce``) and the shooting optimizer
(``planning``). Anything that is a ``concurrent.futures.Executor`` (a process pool, the serial
executor, a Dask client's executor) can run the rollouts; the results do not depend on it.
"""

from __future__ import annotations

import os
import signal
from concurrent.futures import Executor, Future, ProcessPoolExecutor


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


class SerialExecutor(Executor):
    """An Executor that runs each call at once in this process (tests, debugging, a single core).

    Helper: same results as a process pool, one rollout at a time.
    """

    def submit(self, fn, /, *args, **kwargs):
        future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as exc:  # KeyboardInterrupt is not caught: it stops the caller
            future.set_exception(exc)
        return future


def default_executor(workers: int | None = None) -> ProcessPoolExecutor:
    """A process pool on the local cores (``os.cpu_count()`` workers), one BLAS thread per worker,
    ignoring Ctrl-C (``optimize`` ends them).

    Helper: the default executor of ``optimize``.
    """
    return ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1, initializer=worker_init)


def shutdown(executor: Executor, interrupted: bool) -> None:
    """Shut down our own pool; after Ctrl-C, end its worker processes (they ignore SIGINT) at once.

    Helper: where independent simulations run.
    """
    if interrupted:
        # the pool's own worker processes (a private attribute of ProcessPoolExecutor)
        workers = dict(getattr(executor, "_processes", None) or {})
        executor.shutdown(wait=False, cancel_futures=True)
        for process in workers.values():
            process.terminate()
    else:
        executor.shutdown(wait=True)
