"""Rebuild the shipped views model file: the fused views' calibration map and decision
threshold (``src/affordgrasp/learning/pretrained/views.json``).

One command, deterministic:

    python tools/fit_views_model.py --data /tmp/affordgrasp-views-val

1. generates (or resumes) the calibration dataset: 13 families x variant 7 x 512 uniform
   samples, seed 1, each object its own stream (variant 7 is in neither shipped network's
   training objects, variants 0-4 and 9-38, nor in the objects the decisions are judged on,
   variants 5 and 6);
2. simulates every row on the surface fused from ``plan``'s first 64 views of its object,
   with K = 25 perturbed copies (:mod:`affordgrasp.learning.views_model`);
3. fits the isotonic map from the share of viable copies to the true viability, chooses the
   decision threshold of largest F1 on the same rows, and writes the file (or ``--out``).

About 3-4 minutes of CPU on one core for the simulations (docs/learning.md, "The fused
views judged as a model").
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path


def main() -> None:
    from affordgrasp.dataset.generate import generate
    from affordgrasp.learning.views_model import (
        fit_views_config,
        views_config_path,
        write_views_config,
    )
    from affordgrasp.objects import list_families
    from affordgrasp.runtime.engines import default_workers

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, required=True, help="the calibration dataset (resumed)")
    ap.add_argument("--variants", default="7", help="calibration variants (comma-separated)")
    ap.add_argument("--samples", type=int, default=512, help="uniform samples per object")
    ap.add_argument("--seed", type=int, default=1, help="the samples' seed")
    ap.add_argument("--copies", type=int, default=25, help="K perturbed copies per row")
    ap.add_argument("--workers", type=int, default=None, help="processes (default: all cores)")
    ap.add_argument("--out", type=Path, default=None, help="default: the shipped file")
    args = ap.parse_args()
    families = list_families()  # the 13 built-in families
    objects = [f"{f}:{v}" for f in families for v in args.variants.split(",")]
    started = time.perf_counter()
    generate(objects, args.samples, args.data, seed=args.seed, workers=args.workers)
    print(f"dataset {args.data}: {time.perf_counter() - started:.0f} s")
    workers = args.workers or default_workers()
    config = fit_views_config(args.data, objects, copies=args.copies, log=print, workers=workers)
    config["calibration"]["dataset"] = (
        f"{len(families)} families x variants {args.variants} x {args.samples} uniform "
        f"samples, seed {args.seed}, per-object streams"
    )
    out = write_views_config(args.out or views_config_path(), config)
    t = config["decision_threshold"]
    print(
        f"wrote {out}: {config['calibration']['rows']} rows, positive rate "
        f"{config['calibration']['positive_rate']:.3f}, threshold {t['value']:.3f} "
        f"(F1 {t['f1']:.3f}), {time.perf_counter() - started:.0f} s"
    )


if __name__ == "__main__":
    main()
