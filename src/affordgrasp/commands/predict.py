"""``affordgrasp predict``: a model's predictions for every sample of a dataset (Parquet)."""

from __future__ import annotations

import sys

from ..errors import InputError, MissingDependencyError


def add_arguments(p) -> None:
    """Add the options of ``affordgrasp predict`` to its parser.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The subcommand's parser, changed in place.
    """
    p.add_argument(
        "model",
        metavar="MODEL",
        help="a .safetensors model, 'default' (the shipped classifier and regressor), or "
        "'views' (the fused views' classifier and ranker: renders, fuses and simulates each "
        "row on the fused surface, about 8 s of CPU per 512 rows)",
    )
    p.add_argument("dataset", metavar="DATASET", help="a directory written by 'generate'")
    p.add_argument("--out", required=True, metavar="FILE", help="predictions .parquet")
    p.add_argument("--object", action="append", default=None, help="only this object (repeat)")


def load_models(spec: str, *, workers: int = 1):
    """The models named by ``--model``, each with its config.

    Parameters
    ----------
    spec : str
        ``default`` (the shipped classifier and regressor), a shipped model's name, a
        model file (see :func:`affordgrasp.learning.api.resolve_models`), or ``views`` or
        a views model file (the fused views' classifier and ranker,
        :mod:`affordgrasp.learning.views_model`).
    workers : int
        For the views: processes simulating objects side by side.

    Returns
    -------
    list of (torch.nn.Module, dict)

    Raises
    ------
    InputError
        When torch or safetensors is missing (the message says how to install them).
    """
    from ..learning.plan import is_views_spec
    from ..learning.views_model import load_views_models

    if is_views_spec(spec):
        return load_views_models(spec, log=_stderr, workers=workers)
    try:
        from ..learning.api import resolve_models
        from ..learning.io import load_model
        from ..learning.torch_support import require_safetensors, require_torch

        require_torch()
        require_safetensors()
    except MissingDependencyError as exc:
        raise InputError(str(exc)) from None
    return [load_model(path) for path in resolve_models(spec)]


def _stderr(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def run(args, out) -> None:
    """Run ``affordgrasp predict``.

    Parameters
    ----------
    args : argparse.Namespace
        The parsed options.
    out : Output
        Where results go (text or ``--json``).
    """
    import pyarrow.parquet as pq

    from ..dataset.handle import Dataset
    from ..learning.api import predict_dataset
    from ..runtime.writing import atomic_write
    from .output_files import check_output_file

    check_output_file(args.out, "--out", suffix=".parquet")
    models = load_models(args.model)  # a foreign or broken model file: refused first
    dataset = Dataset.open(args.dataset)
    with out.progress("predicting", dataset.count_rows(args.object)) as advance:
        table = predict_dataset(models, dataset, objects=args.object, progress=advance)
    table = table.replace_schema_metadata(
        {
            "affordgrasp_models": ",".join(
                c.get("arch", "") + ":" + c["target"]["name"] for _, c in models
            )
        }
    )
    atomic_write(args.out, lambda fh: pq.write_table(table, fh, compression="zstd"))
    cols = [c for c in table.column_names if c not in ("object", "sample")]
    rows = []
    for c in cols:
        v = table.column(c).to_numpy()
        rows.append([c, float(v.mean()), float(v.min()), float(v.max())])
    out.table(f"{table.num_rows} predictions -> {args.out}", ["name", "mean", "min", "max"], rows)
    out.result({"out": args.out, "rows": table.num_rows, "columns": table.column_names})
