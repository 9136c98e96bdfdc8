"""``affordgrasp plots``: metric distributions, status counts and affordances as PNG.

SOURCE is a dataset directory or an object (then ``--samples`` grasps are evaluated first);
several may be given and are plotted together. Writes ``metrics.png``, ``status.png`` and,
for the tasks asked (default beat, cut, pick), ``affordances.png`` into OUTDIR.
"""

from __future__ import annotations

from .batches import check_counts
from .limits import OWN_CHECK
from .object_options import check_mesh_files
from .output_files import check_output_dir
from .show import SOURCE, add_source_arguments, open_sources
from .task_options import add_task_arguments, parse_tasks

DEFAULT_TASKS = "beat,cut,pick"


# Of the numeric options: see limits.check_limits.
LIMITS = {**SOURCE, "bins": OWN_CHECK}


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp plots`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    add_source_arguments(p)
    add_task_arguments(p, required=False)
    p.add_argument("--bins", type=int, default=40, help="histogram bins (default 40)")
    p.add_argument("--no-tasks", action="store_true", help="skip the affordance plot")


def _combined(sources):
    """One schema and one scan over several sources (columns a source lacks are NaN)."""
    import numpy as np
    import pyarrow as pa

    schema = pa.unify_schemas([s.schema() for s in sources], promote_options="permissive")

    def scan(columns):
        for s in sources:
            have = set(s.schema().names)
            for table in s.scan([c for c in columns if c in have]):
                for c in columns:
                    if c not in have:
                        typ = schema.field(c).type
                        filler = (
                            pa.array(np.full(table.num_rows, np.nan), pa.float64())
                            if pa.types.is_floating(typ) or pa.types.is_integer(typ)
                            else pa.nulls(table.num_rows, typ)
                        )
                        table = table.append_column(c, filler)
                yield table

    return schema, scan


def run(args, out) -> None:
    """Run ``affordgrasp plots``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    from ..errors import InputError
    from ..viz.plots import save_plots, summarize

    check_counts(args)
    check_mesh_files(args)
    check_output_dir(args.out, "--out")
    if not 5 <= args.bins <= 500:
        raise InputError(f"--bins must be between 5 and 500, got {args.bins}")
    tasks, thresholds = [], {}
    if not args.no_tasks:
        tasks, thresholds = parse_tasks(args.task or [DEFAULT_TASKS], args.mode, args.threshold)
    sources = open_sources(args, out)
    schema, scan = _combined(sources)
    if tasks and not _has_metrics(schema):
        out.text("the sources hold no metric columns: skipping the affordance plot")
        tasks = []
    with out.progress("plots (two passes)", total=2 * _rows(sources)) as advance:
        summary = summarize(
            scan,
            schema,
            tasks,
            mode=args.mode,
            thresholds=thresholds,
            bins=args.bins,
            robust=bool(args.robust),
            stored=_stored(sources, tasks, bool(args.robust)),
            progress=advance,
        )
    if summary.rows == 0:
        raise InputError("the sources hold no rows; nothing to plot")
    files = save_plots(summary, args.out, mode=args.mode)
    rows = []
    for obj in sorted(summary.status):
        counts = summary.status[obj]
        total = sum(counts.values())
        row = [obj, total] + [counts.get(s, 0) for s in ("grasped", "touched", "missed")]
        for t in tasks:
            row.append(f"{100.0 * summary.accepted(t.name, obj) / max(total, 1):.1f}%")
        rows.append(row)
    out.table(
        f"samples per object ({summary.rows:,} rows)",
        ["object", "rows", "grasped", "touched", "missed"]
        + [f"{t.name} {'p>=0.5' if t.probability else 'ok'}" for t in tasks],
        rows,
    )
    for path in files.values():
        out.text(f"wrote {path}")
    out.result(
        {
            "files": {k: str(v) for k, v in files.items()},
            "rows": summary.rows,
            "mode": args.mode,
            "status": summary.status,
            "tasks": {
                t.name: {
                    obj: {"rows": s.n, "accepted": summary.accepted(t.name, obj)}
                    for obj, s in summary.affordances[t.name].items()
                }
                for t in tasks
            },
            "metrics": {
                name: {
                    "finite": s.finite,
                    "pos_inf": s.pos_inf,
                    "neg_inf": s.neg_inf,
                    "nan": s.nan,
                    "min": s.lo if s.finite else None,
                    "max": s.hi if s.finite else None,
                    "scale": s.scale,
                }
                for name, s in summary.metrics.items()
            },
        }
    )


def _rows(sources) -> int:
    """Rows of the sources, for the progress bar."""
    return sum(s.count_rows() for s in sources)


def _stored(sources, tasks, robust: bool) -> list[str]:
    """The task probabilities every source carries from the models in use: a dataset's
    recorded ones (search.best.stored_probabilities), or rows just evaluated."""
    from ..search.best import stored_probabilities
    from ..viz.sources import DatasetSource

    names = {t.name for t in tasks if t.probability}
    for s in sources:
        if isinstance(s, DatasetSource):
            if s.dataset is None:  # loose Parquet files: nothing says which models wrote them
                return []
            names &= set(stored_probabilities(s.dataset, tasks, robust))
        elif not all(f"p_{t}" in s.schema().names for t in names):
            return []
    return sorted(names)


def _has_metrics(schema) -> bool:
    return "epsilon" in schema.names
