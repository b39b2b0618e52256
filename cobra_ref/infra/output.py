"""Safe output: every file cobra_ref writes goes through ``atomic_write`` (checked by ``check_output``).

The rules, for every command and writer (the NPZ of a run, the MJCF, the params JSON, the
bench JSON, the figures):

* **the exact name**: the file is written under the name asked for, nothing appended (``--out run``
  writes an NPZ named ``run``; numpy's habit of adding ``.npz`` is defeated by writing through a
  private temporary directory and checking that the writer produced exactly that name);
* **atomic**: the content goes to a temporary file in a private directory beside the target and is
  renamed onto it, so a reader never sees half a file (the target holds the old content or the
  new); on every failure the temporary directory and all in it are removed;
* **regular files only**: a target that is a directory, a device, a pipe or a socket is refused
  (nothing is written); a symbolic link is followed and its target written, the link kept;
* **checked early**: ``check_output`` (called by the commands before their long run) refuses an
  empty name, a missing directory, a target of the wrong kind, and a directory where no file can
  be created, by a real probe (a temporary file created and removed: ``os.access`` answers "yes"
  for root even on a read-only file system).

Failures raise ``OutputError`` (an ``OSError``) with a message that names the path and the problem:
also a write that fails late (a full disk, a quota, an I/O error), whose message adds the
system's reason and that the previous file is unchanged.
"""

from __future__ import annotations

import errno
import os
import shutil
import stat
import tempfile

_KINDS = ((stat.S_ISDIR, "a directory"), (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
          (stat.S_ISFIFO, "a named pipe"), (stat.S_ISSOCK, "a socket"))


class OutputError(OSError):
    """An output file that cannot be written (the message names the path and the reason)."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else "output error"


def _kind(mode: int) -> str:
    """What a non-regular file is, in words."""
    for test, name in _KINDS:
        if test(mode):
            return name
    return "not a regular file"


def resolve_output(path, what: str = "output") -> str:
    """The file that writing ``path`` must replace: ``path`` itself, or the end of its symbolic
    links; an ``OutputError`` if it cannot be a regular file there (checks without writing).

    Safe output (module docstring). Refuses an empty or non-text name, a name ending in a path
    separator, a target that exists and is not a regular file (directory, device, pipe, socket), a
    symbolic-link loop and a missing parent directory.
    """
    if isinstance(path, os.PathLike):
        path = os.fspath(path)
    if not isinstance(path, str) or not path.strip():
        raise OutputError(f"{what} path is empty: give a file name, e.g. run.npz")
    if "\0" in path:
        raise OutputError(f"{what} path {path!r} contains a NUL character")
    if path.endswith(os.sep) or (os.altsep and path.endswith(os.altsep)):
        raise OutputError(f"{what} path {path!r} names a directory (it ends with '{os.sep}'): give a file name")
    target = os.path.realpath(path) if os.path.islink(path) else os.path.abspath(path)
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            raise OutputError(f"{what} path {path!r} is a loop of symbolic links") from None
        raise OutputError(f"{what} path {path!r} cannot be examined: {exc.strerror}") from None
    if mode is not None and not stat.S_ISREG(mode):
        via = f" (the target of the link {path!r})" if target != os.path.abspath(path) else ""
        raise OutputError(f"{what} path {target!r}{via} is {_kind(mode)}, not a regular file: refusing to "
                          "replace it; give a file name")
    directory = os.path.dirname(target)
    if not os.path.isdir(directory):
        raise OutputError(f"output directory does not exist: {directory} (for {what} {path!r})")
    return target


def check_output(path, what: str = "output") -> str:
    """Check before a long run that ``path`` can be written; return the file that will be written.

    Safe output (module docstring). ``resolve_output``'s checks, then a probe: a temporary file is
    created in the target's directory and removed (``OutputError`` naming the directory and the
    system's reason if that fails).
    """
    target = resolve_output(path, what)
    directory = os.path.dirname(target)
    try:
        fd, probe = tempfile.mkstemp(dir=directory, prefix=".cobra_ref_probe_")
    except OSError as exc:
        raise OutputError(f"cannot write in output directory {directory} (for {what} {path!r}): "
                          f"{exc.strerror or exc}") from None
    os.close(fd)
    os.unlink(probe)
    return target


def atomic_write(path, write, what: str = "output") -> None:
    """Call ``write(tmp_path)``, where ``tmp_path`` has the target's own file name inside a private
    temporary directory beside it, then rename that file onto the target (module docstring).

    Safe output. The writer may choose the format by the name's extension; if it writes under
    another name (numpy's ``np.save``/``np.savez`` append a suffix), nothing is replaced and an
    ``OutputError`` says so. The file gets the permissions of an ordinary new file. The temporary
    directory is removed on success and on every failure (the error is re-raised).
    """
    target = resolve_output(path, what)
    directory = os.path.dirname(target)
    try:
        staging = tempfile.mkdtemp(dir=directory, prefix=".tmp_")
    except OSError as exc:
        raise OutputError(f"cannot write in output directory {directory} (for {what} {path!r}): "
                          f"{exc.strerror or exc}") from None
    try:
        tmp = os.path.join(staging, os.path.basename(target))
        write(tmp)
        if not os.path.isfile(tmp):
            made = ", ".join(sorted(os.listdir(staging))) or "nothing"
            raise OutputError(f"the writer of {what} {path!r} did not write the file under its name "
                              f"(it wrote: {made}); nothing was replaced")
        os.replace(tmp, target)
    except OutputError:
        raise
    except OSError as exc:  # a full disk, a quota, an I/O error: while writing or renaming
        raise write_error(path, what, exc) from exc
    finally:
        shutil.rmtree(staging, ignore_errors=True)


def write_error(path, what: str, exc: OSError) -> OutputError:
    """The ``OutputError`` of a write that failed with ``exc``: one line naming the file, the
    system's reason and that the file as it was is kept (the writes are atomic).
    """
    # the system's reason; a writer's own message (ffmpeg's, over many lines) by its first line
    cause = exc.strerror or next(iter(str(exc).strip().splitlines()), "") or type(exc).__name__
    kept = "its previous content is unchanged" if os.path.lexists(path) else "nothing was written"
    return OutputError(f"cannot write {what} {os.fspath(path)!r}: {cause}; {kept}")


def write_text(path, text: str, what: str = "output") -> None:
    """Write ``text`` to ``path`` atomically (UTF-8).

    Safe text output (claims, summaries, MJCF, JSON).
    """

    def write(tmp):
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)

    atomic_write(path, write, what)


def write_binary(path, write_file, what: str = "output") -> None:
    """Write ``path`` atomically through a binary file object: ``write_file(f)`` fills it.

    Safe output for writers that would change a name (``np.savez(f, ...)`` given a file object
    writes exactly there, nothing appended).
    """

    def write(tmp):
        with open(tmp, "wb") as f:
            write_file(f)

    atomic_write(path, write, what)
