"""Writing files safely: output paths checked before the work, files replaced atomically.

``check_output_path`` is what every command that writes calls on its ``--out`` before it
starts (so an unwritable path costs a second, not the run); ``atomic_write`` is how a file
is written: into a temporary name in the same folder, synced, then renamed over the target,
the temporary removed whatever happens (an error, Ctrl-C, SIGTERM).
"""

from __future__ import annotations

import errno
import os
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

from .errors import InputError

__all__ = ["atomic_write", "check_output_path", "temporary_name"]


def check_output_path(
    path: str | os.PathLike,
    option: str = "--out",
    *,
    kind: str = "file",
    create_parents: bool = False,
) -> Path:
    """Refuse an output path that cannot be written, before any work is done.

    Parameters
    ----------
    path : str or path-like
        The file or directory the command will write.
    option : str
        The option that named it (``--out``, ``-o``), for the message.
    kind : {"file", "dir"}
        ``"file"``: a file is written there (an existing directory is refused). ``"dir"``: a
        directory is written into (created if missing; an existing file is refused).
    create_parents : bool
        Missing parent folders will be created (as the command's documentation says); then
        the nearest existing ancestor must be a writable directory.

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    InputError
        Naming the path and the reason: a directory where a file is expected (or the
        reverse), a missing parent folder, a parent that is a file, a read-only folder.
    """
    if kind not in ("file", "dir"):
        raise ValueError(f"kind must be 'file' or 'dir', not {kind!r}")
    p = Path(path)
    text = str(path)
    if not text.strip():
        raise InputError(f"{option} is empty; give a {'directory' if kind == 'dir' else 'file'}")
    if kind == "file" and text.endswith(("/", os.sep)):
        raise InputError(f"{option} {text!r} is not a file name; give one, e.g. {text}out")
    if kind == "file" and p.is_dir():
        raise InputError(f"{option} {text!r} is a directory; give a file name inside it")
    if kind == "dir" and p.exists() and not p.is_dir():
        raise InputError(f"{option} {text!r} is a file, not a directory; give a directory")
    if kind == "dir" and p.is_dir():
        why = _unwritable(p)
        if why:
            raise InputError(f"{option} {text!r}: cannot write in the directory ({why})")
        return p
    if kind == "file" and p.exists() and not os.access(p, os.W_OK):
        raise InputError(f"{option} {text!r}: the file exists and is not writable")
    parent = p.absolute().parent
    if not create_parents and kind == "file":
        if not parent.exists():
            raise InputError(
                f"{option} {text!r}: the folder {str(parent)!r} does not exist; create it first"
            )
    ancestor = parent
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    if not ancestor.is_dir():
        raise InputError(f"{option} {text!r}: {str(ancestor)!r} is a file, not a folder")
    why = _unwritable(ancestor)
    if why:
        raise InputError(f"{option} {text!r}: cannot write in {str(ancestor)!r} ({why})")
    return p


def _unwritable(folder: Path) -> str:
    """Why no file can be created in ``folder`` ("" when one can), by trying it.

    A real attempt, not ``os.access``: permission bits say nothing for root, a read-only
    mount or a full quota.
    """
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(dir=folder, prefix=".affordgrasp-probe-")
    except OSError as exc:
        if exc.errno == errno.ENOENT:  # an existing folder that takes no files (/proc)
            return "the folder takes no new files"
        return exc.strerror or type(exc).__name__
    os.close(fd)
    os.unlink(probe)
    return ""


def temporary_name(path: str | os.PathLike) -> Path:
    """The temporary file ``atomic_write`` uses for ``path``: hidden, same folder, per process.

    Parameters
    ----------
    path : str or path-like

    Returns
    -------
    pathlib.Path
        ``<folder>/.<name>.tmp-<pid>``.
    """
    p = Path(path)
    return p.with_name(f".{p.name}.tmp-{os.getpid()}")


def atomic_write(
    path: str | os.PathLike,
    content: bytes | Callable[[BinaryIO], object],
    *,
    fsync: bool = True,
    before_replace: Callable[[], object] | None = None,
) -> Path:
    """Write a file all at once or not at all: readers see the old file or the new one.

    Parameters
    ----------
    path : str or path-like
        The target; its folder must exist.
    content : bytes or callable
        The bytes, or ``write(fh)`` that writes them to a binary file object.
    fsync : bool
        Sync the data to the disk before the rename (survives a power cut).
    before_replace : callable, optional
        Called after the data is written and before the rename (e.g. to record a checksum).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    OSError
        As the file system raised it; the temporary file is removed first (also on
        KeyboardInterrupt).
    """
    target = Path(path)
    tmp = temporary_name(target)
    try:
        with open(tmp, "wb") as fh:
            if isinstance(content, (bytes, bytearray, memoryview)):
                fh.write(content)
            else:
                content(fh)
            if fsync:
                fh.flush()
                os.fsync(fh.fileno())
        if before_replace is not None:
            before_replace()
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return target
