"""Output paths checked before work, and atomic writes that leave nothing behind."""

from __future__ import annotations

import errno
import io
import os
from pathlib import Path

import pytest

from affordgrasp.cli import main
from affordgrasp.errors import InputError
from affordgrasp.runtime import writing
from affordgrasp.runtime.writing import atomic_write, check_output_path, temporary_name


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


@pytest.mark.parametrize("code", [errno.ENOSPC, errno.EDQUOT, errno.EROFS])
def test_a_refused_write_is_an_input_error_naming_the_path_and_leaves_nothing(
    tmp_path, monkeypatch, code
):
    path = tmp_path / "f.bin"
    atomic_write(path, b"old")

    def refused(fd):
        raise OSError(code, os.strerror(code))

    monkeypatch.setattr(os, "fsync", refused)  # the data reaches the disk: it is full
    with pytest.raises(InputError) as error:
        atomic_write(path, b"new" * 1000)
    message = str(error.value)
    assert repr(str(path)) in message and os.strerror(code) in message, message
    assert "\n" not in message
    assert path.read_bytes() == b"old"
    assert sorted(os.listdir(tmp_path)) == ["f.bin"]


@pytest.mark.parametrize(
    "command",
    [
        ["depth", "knife", "--sample", "0", "-o", "{out}/knife.npy"],
        ["depth", "knife", "--sample", "0", "-o", "{out}/knife.png"],
        ["objects", "export", "knife", "-o", "{out}/knife.stl"],
    ],
)
def test_a_command_on_a_full_disk_exits_2_naming_the_file_and_leaves_nothing(
    tmp_path, monkeypatch, capsys, command
):
    out = tmp_path / "out"
    out.mkdir()
    real_write = writing.write_file

    def full_disk(path, content, fsync=True):
        if not Path(path).is_relative_to(out):  # the object cache: a disk with room
            return real_write(path, content, fsync=fsync)
        buffer = io.BytesIO()
        content(buffer) if callable(content) else buffer.write(content)
        with open(path, "wb") as fh:
            fh.write(buffer.getvalue()[: len(buffer.getvalue()) // 2])  # what a full disk leaves
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(writing, "write_file", full_disk)
    argv = [a.format(out=out) for a in command]
    assert main(argv) == 2
    lines = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert len(lines) == 1, lines
    assert argv[-1] in lines[0] and "No space left on device" in lines[0], lines[0]
    assert "shards" not in lines[0]
    assert list(out.iterdir()) == []
