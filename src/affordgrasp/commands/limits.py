"""The ranges of the commands' numeric options, checked before a command runs.

Each command declares ``LIMITS`` in its module: option (as its dest) -> (lowest, highest,
why the highest). ``cli.main`` checks them (:func:`check_limits`) before the command runs;
None leaves that side to the command's own check, which names it its own way; a callable
highest is computed then (from the memory this machine has). Every numeric option of every
command has an entry (tests/test_hostile_options.py). The memory a command may hold is
measured here too: a count whose items would not fit is refused before any work.
"""

from __future__ import annotations

import math

from ..errors import InputError

MAX_SEED = 2**63 - 1
SEED = (0, MAX_SEED, "seeds are 64-bit")
ROBUST = (None, 1000, "K copies of each grasp are simulated and held together")
USES = (0, 50_000, "each use point is ray cast and held with its metrics, ~10 kB each")
WORKER_BYTES = 256 * 1024**2  # one worker process, measured at ~170 MB


def memory_cap(bytes_each: int, default: int = 1024):
    """The largest count of items that fits in half the memory available, for ``LIMITS``.

    Parameters
    ----------
    bytes_each : int
        Bytes one item takes.
    default : int
        The count where the system does not say how much memory is available.

    Returns
    -------
    callable
        ``cap() -> int``, computed when called.
    """

    def cap() -> int:
        available = available_memory()
        return default if available is None else max(1, available // 2 // bytes_each)

    return cap


WORKERS = (None, memory_cap(WORKER_BYTES), "each worker process holds about 200 MB")
# Open on both sides: the command, or what it builds (the mesh loader, DepthCamera, the
# settings), checks the range itself, in words of its own (a share, a probability, pixels).
OWN_CHECK = (None, None, "the command's own check")
SIZE_M = OWN_CHECK
SEED_BITS = (None, MAX_SEED, "seeds are 64-bit")


def check_limits(args, limits: dict) -> None:
    """Refuse a numeric option outside its ``LIMITS``, before the command does any work.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed command line.
    limits : dict
        Option dest -> (lowest, highest, why), as described above.

    Raises
    ------
    InputError
        Naming the option, its range and the reason for its maximum.
    """
    for dest, (low, high, why) in limits.items():
        value = getattr(args, dest, None)
        if not isinstance(value, int | float) or isinstance(value, bool):
            continue  # not given
        high = high() if callable(high) else high
        finite = math.isfinite(value) or (low is None and high is None)
        if finite and (low is None or value >= low) and (high is None or value <= high):
            continue

        def text(x) -> str:
            return "2**63 - 1" if x == MAX_SEED else f"{x:,}" if isinstance(x, int) else f"{x:g}"

        kind = "an integer" if isinstance(value, int) else "a finite number"
        if low is not None and high is not None:
            bounds = f"in [{text(low)}, {text(high)}]"
        else:
            bounds = f"at most {text(high)}" if low is None else f"at least {text(low)}"
        raise InputError(f"--{dest.replace('_', '-')} must be {kind} {bounds}, got {value} ({why})")


# Bytes of memory per evaluated sample while a command holds its table: ~0.9 kB per row
# with the metric columns (measured, pyarrow), twice while the batches are assembled.
ROW_BYTES = 2 * 1024


def available_memory() -> int | None:
    """Memory available to new allocations (Linux ``MemAvailable``).

    Returns
    -------
    int or None
        Bytes; None where the system does not say.
    """
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def check_table_fits(samples: int) -> None:
    """Refuse a sample count whose in-memory table would not fit, before any work.

    ``evaluate``, ``simulate`` and the object sources of ``show``/``plots`` hold every row
    in memory (they summarise and write it at the end); ``generate`` streams shards to disk
    and is the command for runs of any size. Refusing is chosen over streaming here: the
    summary tables and ``--out`` need the whole table, and a dataset already does the rest.

    Parameters
    ----------
    samples : int

    Raises
    ------
    InputError
        When ``samples`` × ``ROW_BYTES`` exceeds half the available memory; the message
        gives both numbers and the largest count that fits.
    """
    check_fits_in_memory(
        "--samples",
        samples,
        ROW_BYTES,
        what="of rows ",
        advice=" here, or 'affordgrasp generate' (streams to disk)",
    )


def check_fits_in_memory(
    option: str, count: int, bytes_each: int, *, what: str = "", advice: str = ""
) -> None:
    """Refuse a count whose items would take more than half the available memory.

    Parameters
    ----------
    option : str
        The command-line option that set ``count`` (named in the message).
    count : int
        Items the command would hold at once.
    bytes_each : int
        Bytes one item takes.
    what : str
        Words after "GB" in the message (e.g. ``"of rows "``).
    advice : str
        Words after the largest count that fits.

    Raises
    ------
    InputError
        Naming the need, the memory available and the largest count that fits.
    """
    available = available_memory()
    if available is None or count < 1:
        return
    budget = available // 2
    need = int(count) * bytes_each
    if need > budget:
        raise InputError(
            f"{option} {count} would hold about {need / 1e9:.3g} GB {what}in memory, more "
            f"than half of the {available / 1e9:.3g} GB available; use at most "
            f"{budget // bytes_each}{advice}"
        )
