"""Arguments and summaries shared by the simulate and evaluate commands."""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from ..errors import InputError

MODE_HELP = (
    "threshold mode: default, no-robustness, extra-robustness, paper (the paper's literal "
    "τ_ε = 0.3) or paper-extra-robustness (default: default)"
)
HAND_HELP = "barrett (default), parallel_jaw or a .json/.toml hand file"


def add_sampling_arguments(p) -> None:
    """The object and sampling options of ``simulate`` and ``evaluate``.

    ``OBJECT``, ``--samples``, ``--seed``, ``--hand``, the scale options, ``--out`` and the
    hidden ``--batch``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, extended in place.
    """
    p.add_argument("object", help="family (knife), family:seed (knife:7) or a mesh path")
    p.add_argument("--samples", type=int, default=1000, help="number of grasps (default 1000)")
    p.add_argument("--seed", type=int, default=0, help="sampling seed (default 0)")
    p.add_argument("--hand", default="barrett", help=HAND_HELP)
    add_scale_arguments(p)
    p.add_argument("--out", default=None, help="write one row per sample to this Parquet file")
    add_metrics_argument(p)
    p.add_argument("--batch", type=int, default=250, help=argparse.SUPPRESS)


# Metrics computed only on request, beyond the paper's Φ: ``--metrics +NAME``.
OPTIONAL_METRICS = ("volume",)


def add_metrics_argument(p) -> None:
    """``--metrics +volume``: the optional metrics (the GWS volume) to compute as well.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    """
    p.add_argument(
        "--metrics",
        default=None,
        metavar="+NAME",
        help="also compute an optional metric: +volume (the GWS volume, column gws_volume; "
        "not in the paper's metric vector, it costs the full 6-D hull of every "
        "force-closure grasp; null when not asked for)",
    )


def optional_metrics(args) -> set[str]:
    """The optional metrics a parsed command line asks for (``--metrics +volume``).

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    set of str
        Names from :data:`OPTIONAL_METRICS`; empty when the option is absent.

    Raises
    ------
    InputError
        For a word that is not ``+NAME`` of a known optional metric, or a value that names
        none.
    """
    wanted = set()
    given = getattr(args, "metrics", None)
    for word in [] if given is None else names_of("--metrics", given.replace(" ", ","), "+volume"):
        name = word[1:] if word.startswith("+") else None
        if name not in OPTIONAL_METRICS:
            raise InputError(
                f"--metrics {word!r} is not one of "
                + ", ".join(f"+{m}" for m in OPTIONAL_METRICS)
                + " (the paper's metric vector is always computed; e.g. --metrics +volume)"
            )
        wanted.add(name)
    return wanted


def add_scale_arguments(p) -> None:
    """``--size-m`` / ``--units`` (mesh files only) and ``--materials`` (families only) for
    every command that takes an object.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    """
    p.add_argument(
        "--size-m",
        type=float,
        default=None,
        metavar="M",
        help="rescale mesh files so that their longest extent is M metres",
    )
    p.add_argument(
        "--units", default=None, help="length unit of mesh files: m (default), cm, mm, in, ft"
    )
    p.add_argument(
        "--materials",
        action="store_true",
        help="mass properties of the built-in families from their per-part materials (steel, "
        "wood, ...) instead of uniform unit density, the paper's default",
    )


def scale_options(args) -> dict:
    """The scale options of a parsed command line as keyword arguments of ``load_object``.

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    dict
        ``size_m`` and ``units``, None where not given (or the command has no such option).
    """
    return {"size_m": getattr(args, "size_m", None), "units": getattr(args, "units", None)}


def materials_option(args) -> bool:
    """Whether the parsed command line asks for per-part materials (``--materials``).

    Parameters
    ----------
    args : argparse.Namespace

    Returns
    -------
    bool
        False when not given (or the command has no such option).
    """
    return bool(getattr(args, "materials", False))


def load_objects(specs, args) -> list:
    """Resolve object specs with ``--size-m`` / ``--units`` applied to the mesh files and
    ``--materials`` to the families.

    Families are built at their real size; the scale options apply to the mesh files among
    ``specs`` and are refused when there is none; ``--materials`` is refused when every
    spec is a mesh file.

    Parameters
    ----------
    specs : sequence of str
        Families, ``family:seed`` or mesh paths.
    args : argparse.Namespace
        The parsed command line (its scale options).

    Returns
    -------
    list of GraspObject
        In the order of ``specs``.

    Raises
    ------
    InputError
        When a scale option is given and every spec is a family.
    """
    from ..objects import load_object
    from ..objects.resolve import is_family_spec

    materials = materials_option(args)
    if materials and not any(is_family_spec(s) for s in specs):
        load_object(specs[0], materials=True)  # refused for a mesh file, saying why
    scale = scale_options(args)
    if all(v is None for v in scale.values()):
        return [load_object(s, materials=materials and is_family_spec(s)) for s in specs]
    if all(is_family_spec(s) for s in specs):
        given = " and ".join(f"--{k.replace('_', '-')}" for k, v in scale.items() if v is not None)
        raise InputError(
            f"{given} rescale mesh files, and {', '.join(map(repr, specs))} "
            + ("is a built-in family" if len(specs) == 1 else "are built-in families")
            + " (made at real size in metres); drop the option or name a mesh file"
        )
    return [
        load_object(s, materials=materials) if is_family_spec(s) else load_object(s, **scale)
        for s in specs
    ]


MAX_SEED = 2**63 - 1

# The limits of a command's numeric options, ``LIMITS`` in its module: option (as its dest)
# -> (lowest, highest, why the highest). ``cli.main`` checks them before the command runs;
# None leaves that side to the command's own check, which names it its own way; a callable
# highest is computed then (from the memory this machine has). Every numeric option of
# every command has an entry (tests/test_hostile_options.py).
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
SIZE_M = (None, None, "the mesh loader: a plausible object size")
SAMPLING = {  # add_sampling_arguments
    "samples": (None, None, "check_counts: positive, and the rows must fit in memory"),
    "seed": (None, None, "check_counts: a 64-bit seed"),
    "size_m": SIZE_M,
    "batch": (None, 100_000, "a batch is simulated and held at once"),
}


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


def check_counts(args) -> None:
    """Sample count, seed and batch size, before any work is done.

    Parameters
    ----------
    args : argparse.Namespace
        With ``samples``, ``seed`` and optionally ``batch``.

    Raises
    ------
    InputError
        Naming the option: ``--samples`` and ``--batch`` must be positive, ``--seed`` in
        [0, 2**63 - 1], ``--metrics`` a known ``+NAME``.
    """
    if args.samples <= 0:
        raise InputError(f"--samples must be a positive integer, got {args.samples}")
    if not 0 <= args.seed <= MAX_SEED:
        raise InputError(f"--seed must be an integer in [0, 2**63 - 1], got {args.seed}")
    if getattr(args, "batch", 1) <= 0:
        raise InputError(f"--batch must be a positive integer, got {args.batch}")
    optional_metrics(args)
    check_table_fits(args.samples)


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


def check_mesh_files(args) -> None:
    """Refuse ``--mesh`` paths that are not mesh files, and SOURCE files that are neither
    mesh files nor datasets, before any work.

    ``--mesh`` files are read only when a dataset object is not a built-in family, so
    without this check a mistyped path would be ignored in silence.

    Parameters
    ----------
    args : argparse.Namespace
        With a ``mesh`` list and ``source`` (``show``, ``plots``); other commands pass
        through.

    Raises
    ------
    InputError
        Naming the path and what is wrong with it.
    """
    import os

    from ..objects.loading import SUPPORTED_EXTENSIONS

    for path in getattr(args, "source", None) or []:
        ext = os.path.splitext(path)[1].lower()
        if os.path.isfile(path) and ext not in SUPPORTED_EXTENSIONS:
            raise InputError(
                f"SOURCE {path!r} is a file but not a mesh file ({ext or 'no extension'}); give "
                "a dataset directory (the folder of a _manifest.json or of Parquet files), a "
                f"family (e.g. knife) or a mesh file ({', '.join(SUPPORTED_EXTENSIONS)})"
            )
    for path in getattr(args, "mesh", None) or []:
        if not os.path.isfile(path):
            what = "is a directory" if os.path.isdir(path) else "does not exist"
            raise InputError(f"--mesh {path!r} {what}; give the mesh file of a dataset object")
        ext = os.path.splitext(path)[1].lower()
        if ext not in SUPPORTED_EXTENSIONS:
            raise InputError(
                f"--mesh {path!r} is not a mesh file ({ext or 'no extension'}); supported "
                f"formats: {', '.join(SUPPORTED_EXTENSIONS)}"
            )


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


def run_batches(args, out, obj, metrics: bool):
    """Evaluate in batches with a progress bar.

    The one-time costs come first and are timed apart, so that the stages' seconds (and the
    throughput computed from them) are the steady state: ``kernels`` (loading the compiled
    kernels, or compiling them on a machine without caches; ``compiled`` is 1.0 then) and
    ``prepare`` (the object's surface samples).

    Parameters
    ----------
    args : argparse.Namespace
        ``samples``, ``seed``, ``hand`` and ``batch``.
    out : Output
        The command's output (progress bar).
    obj : GraspObject
    metrics : bool
        Compute the metric columns (with the GWS volume when ``--metrics +volume``).

    Returns
    -------
    table : pyarrow.Table
        One row per sample.
    spent : dict of str to float
        Seconds per stage (``simulate``, ``metrics``, ``table``) and the one-time costs
        (``kernels``, ``compiled``, ``prepare``).
    wall : float
        Wall time of the evaluation, s.
    """
    from ..grasp.policy import object_geometry
    from ..kernels import warm_up
    from ..pipeline import evaluate_samples

    load = warm_up()
    t0 = time.perf_counter()
    object_geometry(obj)
    one_time = {
        "kernels": load.seconds,
        "compiled": float(load.compiled),
        "prepare": time.perf_counter() - t0,
    }
    started = time.perf_counter()
    with out.progress(f"{obj.name}", args.samples) as advance:
        result = evaluate_samples(
            obj,
            args.samples,
            seed=args.seed,
            hand=args.hand,
            metrics=metrics,
            batch_size=args.batch,
            progress=advance,
            volume="volume" in optional_metrics(args),
            robust=robust_option(args) if metrics else None,
        )
    wall = time.perf_counter() - started
    return result.table, {**result.timings, **one_time}, wall


def one_time_text(spent: dict) -> str:
    """The one-time costs of :func:`run_batches`, in words, for the summary line.

    Parameters
    ----------
    spent : dict
        The ``spent`` of :func:`run_batches`.

    Returns
    -------
    str
    """
    how = "compiled, cached for later runs" if spent.get("compiled") else "loaded from cache"
    return (
        f"one-time costs, not counted: kernels {spent['kernels']:.1f} s ({how}), "
        f"object preparation {spent['prepare']:.2f} s"
    )


def status_summary(table) -> tuple[list[list], dict]:
    """How many grasps ended in each status, and their mean contact count.

    Parameters
    ----------
    table : pyarrow.Table
        Sample rows (``status``, ``n_contacts``).

    Returns
    -------
    rows : list of list
        Per status of ``STATUSES``: name, count, share as text, mean contacts.
    doc : dict
        Status -> ``{"count", "mean_contacts"}`` for ``--json``.
    """
    from ..grasp.policy import STATUSES
    from ..schema import column_numbers

    status = np.asarray(table.column("status").to_pylist(), dtype=object)
    n_contacts = column_numbers(table.column("n_contacts"))
    rows, doc = [], {}
    for s in STATUSES:
        sel = status == s
        k = int(sel.sum())
        mean_c = float(n_contacts[sel].mean()) if k else 0.0
        rows.append([s, k, f"{100.0 * k / max(len(status), 1):.1f}%", mean_c])
        doc[s] = {"count": k, "mean_contacts": mean_c}
    return rows, doc


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


def parse_thresholds(items: list[str]) -> dict[str, float]:
    """``--threshold`` values as a dict.

    Parameters
    ----------
    items : list of str
        ``NAME=VALUE`` items, e.g. ``["tau_eps=0.1"]``.

    Returns
    -------
    dict of str to float

    Raises
    ------
    InputError
        Naming the first item that is not ``NAME=VALUE`` with a number.
    """
    out = {}
    for item in items:
        name, sep, value = item.partition("=")
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not sep or not name.strip() or math.isnan(number):
            raise InputError(
                f"--threshold {item!r} must be NAME=VALUE with a number, e.g. tau_eps=0.1"
            )
        out[name.strip()] = number
    return out


def add_task_arguments(
    p,
    *,
    several: bool = True,
    required: bool = True,
    thresholds: bool = True,
    help: str | None = None,
) -> None:
    """The task options of every command: ``--task``, ``--mode`` and ``--threshold``.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    several : bool
        ``--task`` is repeatable and takes comma lists (``--task beat,cut``); else one task
        name.
    required : bool
        ``--task`` must be given.
    thresholds : bool
        Add ``--threshold NAME=VALUE``.
    help : str, optional
        Help text of ``--task``.
    """
    if several:
        p.add_argument(
            "--task",
            action="append",
            required=required,
            default=None,
            metavar="TASK[,TASK...]",
            help=help or "task(s) to rank by, e.g. cut or beat,cut,pick (see 'affordgrasp tasks')",
        )
    else:
        p.add_argument(
            "--task", required=required, help=help or "task name (see 'affordgrasp tasks')"
        )
    p.add_argument(
        "--mode",
        default="default",
        help=MODE_HELP,
    )
    if thresholds:
        p.add_argument(
            "--threshold",
            action="append",
            default=[],
            metavar="NAME=VALUE",
            help="override a threshold of the task(s) that have it, e.g. tau_eps=0.1 (repeatable)",
        )


def names_of(option: str, text: str, example: str) -> list[str]:
    """The names of a comma-separated option value, refused when it names none.

    Parameters
    ----------
    option : str
        The option (``--task``), for the message.
    text : str
        Its value (``"beat,cut"``).
    example : str
        A value to suggest (``"cut"``).

    Returns
    -------
    list of str
        The names, stripped, in order.

    Raises
    ------
    InputError
        For a value with no name in it (``''``, ``','``): an empty option would otherwise
        run as if it had not been given.
    """
    names = [n.strip() for n in text.split(",") if n.strip()]
    if not names:
        raise InputError(f"{option} {text!r} names nothing; give a name, e.g. {option} {example}")
    return names


def task_names(values: list[str] | str | None) -> list[str]:
    """Task names from ``--task`` values (repeated and/or comma-separated).

    Parameters
    ----------
    values : list of str, str or None
        The option's values.

    Returns
    -------
    list of str
        In order, the first of duplicates kept.

    Raises
    ------
    InputError
        For a value that names no task (``--task ''``).
    """
    if isinstance(values, str):
        values = [values]
    names: list[str] = []
    for value in values or []:
        names.extend(names_of("--task", value, "cut (see 'affordgrasp tasks')"))
    return list(dict.fromkeys(names))


def parse_tasks(values: list[str] | None, mode: str, threshold_items: list[str]):
    """Task objects, and per-task threshold overrides, from the command line.

    Parameters
    ----------
    values : list of str or None
        ``--task`` values.
    mode : str
        ``--mode`` (checked against every task now).
    threshold_items : list of str
        ``--threshold`` items.

    Returns
    -------
    tasks : list of Task
    per_task : dict of str to dict of str to float
        Task name -> the overrides of its thresholds.

    Raises
    ------
    InputError
        Without a task name, or for a threshold no task has; a TaskError for an unknown
        task or mode.
    """
    from ..tasks import get_task

    names = task_names(values)
    if not names:
        raise InputError(
            "--task needs at least one task name, e.g. --task cut (see 'affordgrasp tasks')"
        )
    tasks = [get_task(n) for n in names]
    overrides = parse_thresholds(threshold_items)
    per_task: dict[str, dict[str, float]] = {}
    for name, value in overrides.items():
        having = [t for t in tasks if name in t.thresholds_for(mode)]
        if not having:
            raise InputError(
                f"--threshold {name}: none of the tasks {', '.join(t.name for t in tasks)} has a "
                "threshold of that name (see 'affordgrasp tasks')"
            )
        for t in having:
            per_task.setdefault(t.name, {})[name] = value
    for t in tasks:
        t.thresholds_for(mode, **per_task.get(t.name, {}))  # checks the mode now
    return tasks, per_task


ROBUST_HELP = (
    "K perturbed re-simulations per grasp (hand pose 5 mm / 3°, friction ±0.1, centre of "
    "mass 2.5 mm) and the robust_* columns; tasks rank by their robust score (default 0: "
    "plain, the paper's behaviour)"
)


def add_robust_argument(p, help: str = ROBUST_HELP) -> None:
    """The ``--robust K`` option.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    help : str
        Its help text.
    """
    p.add_argument("--robust", type=int, default=0, metavar="K", help=help)


def robust_option(args):
    """``--robust K`` as settings (None when K = 0), refused when negative.

    Parameters
    ----------
    args : argparse.Namespace
        With ``robust`` (absent: 0) and optionally ``mode``.

    Returns
    -------
    RobustSettings or None
    """
    from ..robust import RobustSettings

    k = getattr(args, "robust", 0) or 0
    if k < 0:
        raise InputError(f"--robust must be an integer >= 0 (copies per grasp), got {k}")
    mode = getattr(args, "mode", None) or "default"
    return RobustSettings(copies=k, mode=mode) if k > 0 else None
