"""Grasps of one object sampled and evaluated in batches (``simulate``, ``evaluate``).

Their options, the counts checked before any work, the run with its progress bar, and the
summaries of what ran (statuses, one-time costs); and the worker and engine options of the
commands that run their batches as jobs (``generate``, ``physics``).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from ..errors import InputError
from .limits import MAX_SEED, OWN_CHECK, check_table_fits
from .object_options import HAND_HELP, add_scale_arguments
from .task_options import add_metrics_argument, optional_metrics, robust_option


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


SAMPLING = {  # add_sampling_arguments; check_counts checks the samples and the seed
    **dict.fromkeys(("samples", "seed", "size_m"), OWN_CHECK),
    "batch": (None, 100_000, "a batch is simulated and held at once"),
}


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


def add_engine_arguments(p) -> None:
    """``--workers K``, ``--engine local|ray`` and ``--address`` of the commands that run jobs.

    Parameters
    ----------
    p : argparse.ArgumentParser
        Extended in place.
    """
    p.add_argument(
        "--workers", type=int, default=None, metavar="K", help="processes/CPUs (default: all)"
    )
    p.add_argument(
        "--engine",
        choices=("local", "ray"),
        default="local",
        help="local worker processes (default) or Ray (pip install 'affordgrasp[cluster]')",
    )
    p.add_argument(
        "--address", default=None, help="an existing Ray cluster (with --engine ray), e.g. auto"
    )


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
