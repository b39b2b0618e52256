"""The figure command's cache entries, each checked on read against its key and its content.

Every entry under the cache directory (a gait run's NPZ, an optimum's replayed box path, the
MuJoCo comparison's rows) records the key it was computed for and a SHA-256 of its content
(``content_sha256``), both written when it is stored. On read (``verified``) an entry must load,
hold every array it needs with consistent shapes, carry exactly the requested key, match its
content hash and be finite where a simulation's states are. An entry that fails is named on
stderr in one line ("cache entry X is damaged (reason): recomputing"), removed, and the caller
computes and stores it anew: a truncated, empty or foreign file, or another run's numbers under
this run's name, never reaches the figures or the claims.
"""

from __future__ import annotations

import hashlib
import json
import os
import sys

import numpy as np

from ..infra.output import write_binary, write_text
from ..trajectory import CONTACT_KEYS, STEP_KEYS, Trajectory

# the arrays of a run that must be finite: a simulation stops before it logs a non-finite state
FINITE = ("t", "q", "qd", "tau", "box_pose")


class CacheDamage(ValueError):
    """A cache entry that cannot be used (the message is the reason)."""


def content_sha256(arrays: dict) -> str:
    """SHA-256 of named arrays: each name, dtype, shape and bytes, in name order."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(np.asarray(arrays[name]))
        h.update(f"{name}:{a.dtype.str}:{a.shape}".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def file_sha256(path: str) -> str:
    """SHA-256 of the bytes of the file ``path``."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def verified(path: str, read):
    """``read(path)``, or None when the entry is damaged (``CacheDamage`` or any failure to read
    it): then it is named on stderr and removed, and the caller recomputes it."""
    try:
        return read(path)
    except CacheDamage as exc:
        reason = str(exc)
    except Exception as exc:  # any failure to read: BadZipFile, EOFError, KeyError, zlib.error, ...
        reason = f"unreadable: {type(exc).__name__}: {exc}"
    sys.stderr.write(f"cache entry {path} is damaged ({reason}): recomputing\n")
    sys.stderr.flush()
    try:
        os.remove(path)
    except OSError:
        pass  # a read-only cache: the entry is replaced when the new one is stored (or that fails and says so)
    return None


def check_key(found, key: str) -> None:
    """``CacheDamage`` unless the key an entry records is ``key``."""
    if found != key:
        shown = found[:16] if isinstance(found, str) else repr(found)
        raise CacheDamage(f"it was computed for key {shown}..., not this entry's {key[:16]}...")


def check_content(found, arrays: dict) -> None:
    """``CacheDamage`` unless ``found`` is the ``content_sha256`` of ``arrays``."""
    if found != content_sha256(arrays):
        raise CacheDamage("its content does not match the SHA-256 stored with it")


def trajectory_arrays(traj: Trajectory) -> dict:
    """Every array of a run (states, steps, contact log, dt) by name: what its content hash covers."""
    return {"dt": np.float64(traj.dt), "t": traj.t, "q": traj.q, "qd": traj.qd, "tau": traj.tau,
            "box_pose": traj.box_pose, **traj.steps, **traj.contacts}


def seal_trajectory(traj: Trajectory, key: str) -> None:
    """Record ``key`` and the content hash in the run's ``meta`` before it is stored."""
    traj.meta["cache_key"] = key
    traj.meta["content_sha256"] = content_sha256(trajectory_arrays(traj))


def read_trajectory(path: str, key: str) -> Trajectory:
    """The run stored in ``path`` if it is the run of ``key`` and whole; ``CacheDamage`` otherwise."""
    with np.load(path, allow_pickle=False) as z:
        missing = [k for k in ("dt", "t", "q", "qd", "tau", "box_pose", "meta", "error", "wall_time")
                   + STEP_KEYS + CONTACT_KEYS if k not in z.files]
    if missing:
        raise CacheDamage(f"not a run: no {', '.join(missing[:3])}{' ...' if len(missing) > 3 else ''}")
    traj = Trajectory.from_npz(path)
    check_key(traj.meta.get("cache_key"), key)
    arrays = trajectory_arrays(traj)
    check_content(traj.meta.get("content_sha256"), arrays)
    n = len(traj.tau)
    lengths = {k: len(arrays[k]) for k in ("t", "q", "qd", "box_pose")} | {k: len(arrays[k]) + 1 for k in STEP_KEYS}
    rows = {len(arrays[k]) for k in CONTACT_KEYS}
    if set(lengths.values()) != {n + 1} or len(rows) != 1:
        raise CacheDamage("its arrays have inconsistent lengths")
    bad = [k for k in FINITE if not np.all(np.isfinite(arrays[k]))]
    if bad or not np.isfinite(traj.dt):
        raise CacheDamage(f"non-finite values in {', '.join(bad) or 'dt'}")
    return traj


def write_rows(path: str, key: str, rows: list) -> None:
    """Store plain-JSON ``rows`` in ``path`` with their key and content hash (``read_rows`` reads them)."""
    write_text(path, json.dumps({"key": key, "sha256": rows_sha256(rows), "rows": rows}), "cache entry")


def read_rows(path: str, key: str) -> list:
    """The rows stored as JSON in ``path`` (``{"key", "sha256", "rows"}``) if they are the rows of
    ``key`` and whole; ``CacheDamage`` otherwise."""
    with open(path, encoding="utf-8") as f:
        entry = json.load(f)
    if not isinstance(entry, dict) or not isinstance(entry.get("rows"), list) or not entry["rows"]:
        raise CacheDamage("not a list of rows")
    check_key(entry.get("key"), key)
    if entry.get("sha256") != rows_sha256(entry["rows"]):
        raise CacheDamage("its content does not match the SHA-256 stored with it")
    return entry["rows"]


def rows_sha256(rows: list) -> str:
    """SHA-256 of plain-JSON rows (keys sorted): what a rows entry stores and is checked against."""
    return hashlib.sha256(json.dumps(rows, sort_keys=True).encode()).hexdigest()


def write_path(path: str, key: str, xy: np.ndarray) -> None:
    """Store the (n, 2) path ``xy`` in the NPZ ``path`` with its key and content hash (``read_path`` reads it)."""
    arrays = {"key": np.array(key), "xy": xy, "content_sha256": np.array(content_sha256({"xy": xy}))}
    write_binary(path, lambda f: np.savez(f, **arrays), "cache entry")


def read_path(path: str, key: str) -> np.ndarray:
    """The (n, 2) path stored in the NPZ ``path`` (``key``, ``xy``, ``content_sha256``) if it is the
    path of ``key`` and whole; ``CacheDamage`` otherwise."""
    with np.load(path, allow_pickle=False) as z:
        if not {"key", "xy", "content_sha256"} <= set(z.files):
            raise CacheDamage("not a stored path: it lacks key, xy or content_sha256")
        found, xy, digest = str(z["key"]), z["xy"], str(z["content_sha256"])
    check_key(found, key)
    check_content(digest, {"xy": xy})
    if xy.ndim != 2 or xy.shape[1] != 2 or len(xy) == 0 or not np.all(np.isfinite(xy)):
        raise CacheDamage(f"not a finite (n, 2) path: shape {xy.shape}")
    return xy
