"""Output paths checked before work, and atomic writes that leave nothing behind."""

from __future__ import annotations

import os

import pytest

from affordgrasp.errors import InputError
from affordgrasp.writing import atomic_write, check_output_path, temporary_name


def test_file_paths(tmp_path):
    assert check_output_path(tmp_path / "a.parquet") == tmp_path / "a.parquet"
    with pytest.raises(InputError, match=r"--out .* is a directory"):
        check_output_path(tmp_path)
    with pytest.raises(InputError, match=r"-o .*missing.* does not exist; create it first"):
        check_output_path(tmp_path / "missing" / "a.png", "-o")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(InputError, match="is a file, not a folder"):
        check_output_path(blocker / "a.png", create_parents=True)
    # parents that the command creates: fine when the nearest folder is writable
    assert check_output_path(tmp_path / "new" / "deeper" / "a.png", create_parents=True)


def test_empty_and_folder_like_names():
    with pytest.raises(InputError, match="--out is empty; give a directory"):
        check_output_path("", kind="dir")
    with pytest.raises(InputError, match="is not a file name"):
        check_output_path("some/folder/")


def test_directory_paths(tmp_path):
    check_output_path(tmp_path, kind="dir")
    check_output_path(tmp_path / "new" / "ds", kind="dir")
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(InputError, match="is a file, not a directory"):
        check_output_path(blocker, kind="dir")
    assert not (tmp_path / "new").exists()  # checking creates nothing


def test_unwritable_folder_is_found_by_trying():
    # /proc takes no new files, even for root (whose permission bits are no guide).
    with pytest.raises(InputError, match=r"cannot write in '/proc'"):
        check_output_path("/proc/affordgrasp-test.obj", "-o")
    with pytest.raises(InputError, match=r"cannot write in '/proc'"):
        check_output_path("/proc/affordgrasp-test/ds", kind="dir")


def test_atomic_write_replaces_whole_or_not_at_all(tmp_path):
    path = tmp_path / "f.bin"
    atomic_write(path, b"old")
    assert path.read_bytes() == b"old"
    atomic_write(path, lambda fh: fh.write(b"new"))
    assert path.read_bytes() == b"new"

    def interrupted(fh):
        fh.write(b"half")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(path, interrupted)
    assert path.read_bytes() == b"new"
    assert sorted(os.listdir(tmp_path)) == ["f.bin"]
    assert temporary_name(path).name == f".f.bin.tmp-{os.getpid()}"
