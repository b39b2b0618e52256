"""Where independent simulations run: worker processes, a serial executor, and their shutdown.

Shared by the figure command's gait runs (``reproduce``) and the shooting optimizer (``planning``).
Anything that is a ``concurrent.futures.Executor`` (a process pool, the serial executor, a Dask
client's executor) can run the rollouts; the results do not depend on it.
"""

from __future__ import annotations

import os
import signal
from contextlib import contextmanager
from concurrent.futures import Executor, Future, ProcessPoolExecutor


def _openblas_libraries() -> list:
    """(path, set_num_threads, get_num_threads) of every OpenBLAS loaded in this process (Linux).

    Numpy's and scipy's bundled OpenBLAS, found in /proc/self/maps; elsewhere, or without OpenBLAS,
    [].
    """
    import ctypes
    import re

    import numpy  # noqa: F401  (loads numpy's OpenBLAS, so that it is found below)
    import scipy.linalg  # noqa: F401  (and scipy's)

    try:
        with open("/proc/self/maps") as f:
            paths = sorted(set(re.findall(r"(/\S*openblas\S*\.so\S*)", f.read())))
    except OSError:
        return []
    found = []
    for path in paths:
        lib = ctypes.CDLL(path)
        for prefix in ("scipy_openblas", "openblas"):
            for suffix in ("64_", ""):
                setter = getattr(lib, f"{prefix}_set_num_threads{suffix}", None)
                getter = getattr(lib, f"{prefix}_get_num_threads{suffix}", None)
                if setter is not None and getter is not None:
                    found.append((path, setter, getter))
                    break
            else:
                continue
            break
    return found


def limit_blas_threads(n: int = 1) -> list[str]:
    """Ask every OpenBLAS library loaded in this process to use ``n`` threads; return their paths.

    A contact step works on 23 x 23 matrices, where OpenBLAS's threads cost far more than they save,
    above all on a shared machine (measured on the 2-core machine with other jobs running: a 2 s
    rollout took 17.0 ms per step with OpenBLAS's default threads and 4.6 ms with one, with
    bit-identical results).
    """
    import ctypes

    libraries = _openblas_libraries()
    for _, setter, _ in libraries:
        setter(ctypes.c_int(n))
    return [path for path, _, _ in libraries]


@contextmanager
def one_blas_thread():
    """Run the ``with`` block with one OpenBLAS thread, then restore each library's thread count.

    Used by ``simulate`` so that a script calling it directly runs as fast as the command line
    (which limits the threads once for the whole process).
    """
    import ctypes

    libraries = _openblas_libraries()
    before = [getter() for _, _, getter in libraries]
    for _, setter, _ in libraries:
        setter(ctypes.c_int(1))
    try:
        yield
    finally:
        for (_, setter, _), n in zip(libraries, before):
            setter(ctypes.c_int(n))


def worker_init() -> None:
    """Pool worker initializer.

    One BLAS thread; Ctrl-C goes to the main process only, which ends the workers; file descriptor 1
    to /dev/null (OSQP prints "Polishing not needed ..." there even with verbose off, once per
    solve; the workers print nothing else)."""
    limit_blas_threads(1)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)


class SerialExecutor(Executor):
    """An Executor that runs each call at once in this process (tests, debugging, a single core).

    Same results as a process pool, one rollout at a time.
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
    """
    return ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1, initializer=worker_init)


@contextmanager
def own_pool(workers: int | None = None):
    """``default_executor(workers)`` for a ``with`` block, shut down on leaving it: waiting for its
    work after a normal exit, its workers ended at once after an exception (Ctrl-C included).

    A pool that is made and ended in one place (``shutdown``).
    """
    executor = default_executor(workers)
    try:
        yield executor
    except BaseException:
        shutdown(executor, interrupted=True)
        raise
    shutdown(executor, interrupted=False)


def shutdown(executor: Executor, interrupted: bool) -> None:
    """Shut down our own pool; after Ctrl-C, end its worker processes (they ignore SIGINT) at once.
    """
    if interrupted:
        # the pool's own worker processes (a private attribute of ProcessPoolExecutor)
        workers = dict(getattr(executor, "_processes", None) or {})
        executor.shutdown(wait=False, cancel_futures=True)
        for process in workers.values():
            process.terminate()
    else:
        executor.shutdown(wait=True)
