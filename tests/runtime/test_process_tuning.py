"""The settings of the processes affordgrasp owns (affordgrasp.runtime.process_tuning)."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

import affordgrasp
from affordgrasp.runtime import process_tuning

SRC = str(Path(affordgrasp.__file__).resolve().parents[1])
GLIBC = sys.platform.startswith("linux") and os.confstr("CS_GNU_LIBC_VERSION").startswith("glibc")

# A batch's pattern: ten 4 MB arrays live together, then all freed; 20 batches. Prints the
# page faults the batches after the first took.
CHURN = """
import resource, sys
import numpy as np
from affordgrasp.runtime.process_tuning import keep_freed_memory
taken = keep_freed_memory() if sys.argv[1] == "keep" else None

def batch():
    arrays = [np.ones(1 << 19) for _ in range(10)]
    return sum(a[-1] for a in arrays)

batch()
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(20):
    batch()
print(taken, resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def churn(mode: str) -> tuple[str, int]:
    proc = subprocess.run(
        [sys.executable, "-c", CHURN, mode],
        capture_output=True,
        text=True,
        check=True,
        env={"PYTHONPATH": SRC, "PATH": "/usr/bin:/bin", "OPENBLAS_NUM_THREADS": "1"},
    )
    taken, faults = proc.stdout.split()
    return taken, int(faults)


@pytest.mark.skipif(not GLIBC, reason="glibc's allocator only")
def test_freed_blocks_are_reused_instead_of_faulted_in_again():
    _, default = churn("default")
    taken, kept = churn("keep")
    assert taken == "True"
    # By default glibc trims the heap's top above twice the largest block freed (8 MB): each
    # batch faults most of its 10 x 1024 pages in again; kept, they are reused
    assert default > 40_000  # 102,000 with glibc 2.36
    assert kept < default / 10


def test_keep_freed_memory_answers_once():
    first = process_tuning.keep_freed_memory()
    assert process_tuning.keep_freed_memory() is first
    assert first is GLIBC


def test_one_blas_thread_leaves_a_users_setting(monkeypatch):
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    assert process_tuning.one_blas_thread()
    assert os.environ["OPENBLAS_NUM_THREADS"] == "1"
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "4")
    assert not process_tuning.one_blas_thread()
    assert os.environ["OPENBLAS_NUM_THREADS"] == "4"


def test_the_command_line_sets_one_blas_thread_before_numpy():
    # numpy is not imported until main runs (it reads the setting when it loads OpenBLAS)
    code = (
        "import sys; from affordgrasp.cli import main; assert 'numpy' not in sys.modules;"
        "main(['--version']);"
        "import os; print(os.environ.get('OPENBLAS_NUM_THREADS'));"
        "print('numpy' in sys.modules)"
    )
    env = {"PYTHONPATH": SRC, "PATH": "/usr/bin:/bin"}
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env
    ).stdout.split()
    assert out[-2:] == ["1", "True"]
