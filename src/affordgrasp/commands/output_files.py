"""Output files and folders: checked before the work that fills them, tables written whole."""

from __future__ import annotations

from ..errors import InputError


def check_output_file(path: str, option: str, suffix: str | None = None) -> None:
    """Refuse an output file that cannot be written, before the work that fills it.

    Parameters
    ----------
    path : str
        The file.
    option : str
        The option that named it (``--out``), for the message.
    suffix : str, optional
        The extension the file must have (``".parquet"``, ``".safetensors"``), so that
        nothing is written in silence under a name that promises another format.

    Raises
    ------
    InputError
        When ``path`` is a directory, has another extension than ``suffix``, or its folder
        is missing or not writable (:func:`affordgrasp.runtime.writing.check_output_path`).
    """
    from ..runtime.writing import check_output_path

    check_output_path(path, option, kind="file")
    if suffix is not None and not str(path).endswith(suffix):
        raise InputError(f"{option} {str(path)!r} must end in {suffix}")


def check_output_dir(path: str, option: str) -> None:
    """Refuse an output directory that cannot be created or written, before any work.

    Parameters
    ----------
    path : str
        The directory (created, with its parents, when missing).
    option : str
        The option that named it (``--out``, ``--report``), for the message.

    Raises
    ------
    InputError
        When ``path`` is a file, or it (or its nearest existing folder) is not writable.
    """
    from ..runtime.writing import check_output_path

    check_output_path(path, option, kind="dir", create_parents=True)


def write_table(table, path: str | None, out) -> None:
    """Write rows to a Parquet file, whole or not at all, and say so.

    Parameters
    ----------
    table : pyarrow.Table
    path : str or None
        The file; nothing is written when None or empty.
    out : Output
        The command's output.

    Raises
    ------
    InputError
        When the file cannot be written.
    """
    if not path:
        return

    import pyarrow.parquet as pq

    from ..runtime.writing import atomic_write

    atomic_write(path, lambda fh: pq.write_table(table, fh), fsync=False)
    out.text(f"wrote {table.num_rows} rows to {path}")
