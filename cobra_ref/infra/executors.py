"""Where independent simulations run: worker processes, a serial executor, and their shutdown.

Shared by the figure command's gait runs (``reproduce``) and the shooting optimizer (``planning``).
Anything that is a ``concurrent.futures.Executor`` (a process pool, the serial executor, a Dask
client's executor) can run the rollouts; the results do not depend on it.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
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


def worker_init(parent: int | None = None) -> None:
    """Pool worker initializer.

    One BLAS thread; the signals of a helper process (``helper_init``); file descriptor 1 to
    /dev/null (OSQP prints "Polishing not needed ..." there even with verbose off, once per solve;
    the workers print nothing else)."""
    limit_blas_threads(1)
    helper_init(parent)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    os.close(devnull)


def helper_init(parent: int | None = None) -> None:
    """Initializer of a helper process (a pool worker, the progress queue's server).

    Ctrl-C goes to the main process only, which ends its helpers (SIGINT ignored); SIGTERM ends the
    helper at once (its default: a forked helper would otherwise inherit the command's handler,
    ``signals.stop_signals``). With ``parent`` (the main process's id) on Linux the kernel also
    kills the helper when the main process dies, even by SIGKILL (``prctl(PR_SET_PDEATHSIG)``,
    bound to the thread that started the helper); a helper whose parent is already gone exits.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if parent is None or not sys.platform.startswith("linux"):
        return
    import ctypes

    pr_set_pdeathsig = 1  # <linux/prctl.h>
    try:
        ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, int(signal.SIGKILL), 0, 0, 0)
    except (OSError, AttributeError):  # no prctl in this C library: no guard
        return
    if os.getppid() != parent:
        os._exit(1)


def _main_pid() -> int | None:
    """This process's id when called from its main thread (the thread that forks the helpers and
    whose end fires ``helper_init``'s guard), else None (no guard)."""
    return os.getpid() if threading.current_thread() is threading.main_thread() else None


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
    ignoring Ctrl-C (``optimize`` ends them), ending on SIGTERM and with this process (``worker_init``).
    """
    return ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1, initializer=worker_init,
                               initargs=(_main_pid(),))


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
    """Shut down our own pool; after an interrupt (Ctrl-C, SIGTERM), end its worker processes at
    once (``end_processes``) instead of waiting for their work.
    """
    if interrupted:
        # the pool's own worker processes (a private attribute of ProcessPoolExecutor)
        workers = list((getattr(executor, "_processes", None) or {}).values())
        executor.shutdown(wait=False, cancel_futures=True)
        end_processes(workers)
    else:
        executor.shutdown(wait=True)


def end_processes(processes, grace: float = 3.0) -> None:
    """SIGTERM each ``multiprocessing`` process, wait ``grace`` seconds in all for them to end, then
    SIGKILL any still running."""
    for process in processes:
        process.terminate()
    deadline = time.monotonic() + grace
    for process in processes:
        process.join(max(deadline - time.monotonic(), 0.0))
    for process in processes:
        if process.is_alive():
            process.kill()
            process.join(1.0)


@contextmanager
def progress_queue():
    """A queue that pool workers can put on and this process read, for a ``with`` block: a
    ``multiprocessing`` manager's, whose server process is a helper (``helper_init``) shut down on
    leaving the block (at most about a second, then ended)."""
    from multiprocessing.managers import SyncManager

    manager = SyncManager()
    manager.start(helper_init, (_main_pid(),))
    try:
        yield manager.Queue()
    finally:
        manager.shutdown()
