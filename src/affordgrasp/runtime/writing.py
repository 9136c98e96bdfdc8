"""Writing files safely: output paths checked before the work, files replaced atomically.

``check_output_path`` is what every command that writes calls on its ``--out`` before it
starts (so an unwritable path costs a second, not the run); ``atomic_write`` is how every
file of the package is written: into a temporary name in the same folder, synced, then
renamed over the target, the temporary removed whatever happens (an error, Ctrl-C,
SIGTERM). A full disk, a quota, a read-only file system or any other refusal of the file
system is an :class:`~affordgrasp.errors.InputError` naming the path (the command exits 2
with one line), and nothing is left behind.
"""

from __future__ import annotations

import contextlib
import errno
import os
from collections.abc import Callable
from pathlib import Path
from typing import BinaryIO

from ..errors import InputError

__all__ = ["atomic_write", "check_output_path", "temporary_name", "write_error", "write_file"]


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


def write_file(
    path: str | os.PathLike, content: bytes | Callable[[BinaryIO], object], *, fsync: bool = True
) -> None:
    """Write a file in place (the one place the package's files are opened for writing).

    Parameters
    ----------
    path : str or path-like
    content : bytes or callable
        The bytes, or ``write(fh)`` that writes them to a binary file object.
    fsync : bool
        Sync the data to the disk before returning.
    """
    with open(path, "wb") as fh:
        if isinstance(content, (bytes, bytearray, memoryview)):
            fh.write(content)
        else:
            content(fh)
        if fsync:
            fh.flush()
            os.fsync(fh.fileno())


def write_error(path: str | os.PathLike, exc: OSError) -> InputError:
    """A one-line InputError for a failed write, naming the path, the reason and the fix.

    Parameters
    ----------
    path : str or path-like
        What could not be written.
    exc : OSError
        Why (no space, a quota, no permission, a read-only file system...).

    Returns
    -------
    InputError
        Not raised.
    """
    reason = exc.strerror or str(exc) or type(exc).__name__
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        fix = "free some space or write elsewhere"
    elif exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        fix = "make it writable or write elsewhere"
    else:
        fix = "check the disk and the path, or write elsewhere"
    return InputError(f"cannot write {str(path)!r}: {reason}; {fix}")


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
        Sync the data, and then the folder's entry, to the disk (survives a power cut).
    before_replace : callable, optional
        Called after the data is written and before the rename (e.g. to record a checksum).

    Returns
    -------
    pathlib.Path
        ``path``.

    Raises
    ------
    InputError
        When the file system refuses the write (:func:`write_error`); the temporary file is
        removed first, as it is on any other exception (KeyboardInterrupt included).
    """
    target = Path(path)
    tmp = temporary_name(target)
    try:
        write_file(tmp, content, fsync=fsync)
        if before_replace is not None:
            before_replace()
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):  # a read-only file system refuses even this
            tmp.unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise write_error(target, exc) from exc
        raise
    if fsync:
        _sync_directory(target.parent)
    return target


def _sync_directory(directory: Path) -> None:
    # Make the rename itself durable (POSIX); not possible (nor needed) on every platform.
    try:
        fd = os.open(directory, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)
