"""The paper's validation (§IV-C, Figs. 3-7) as numbers: are the best grasps semantically right?

For each task and each relevant family (:data:`~affordgrasp.validation.judges.TASK_FAMILIES`),
over several seeds (object instances), the top grasps of the default mode are found two ways:

* brute force: every one of ``grasps`` uniform grasps scored with every one of ``uses``
  uniform use points; the top ``top`` distinct grasps, each with its best use point
  (:func:`affordgrasp.search.pairs.best_pairs` with ``per_grasp=True``);
* the optimiser: the cross-entropy method over p0, each grasp with its best use point of
  ``uses`` (:func:`affordgrasp.search.pairs.optimize_pairs`), ``budget`` simulations shared by
  ``restarts`` independent runs; with ``refine`` f the share f of the budget then
  continues the best run around its best point.

and judged by the semantic parts of the families (:mod:`affordgrasp.validation.judges`).
The searches score with ε alone (no GWS volume: ``volume=False``), which leaves every score
unchanged and skips the 6-D hull of enveloping grasps.

``also_grasps`` K repeats the brute force on the first K of the ``grasps`` uniform grasps
(sample i of a run depends only on the run's seed and i, so they are exactly the grasps a
K-grasp brute force draws) and reports it beside the full one (``brute_force_at_K``).

With ``figures``, it also renders one figure per task with the best grasp of each family
(seed 0) in each mode (paper Figs. 3-6), and the paper's threshold-mode comparison on the
knife (Fig. 7). Mass properties: uniform unit density by default (the paper's);
``materials`` gives the families their per-part materials, which moves the centre of mass
(pick's judge) and I, E_h, E_i. Same settings, same numbers: every search is seeded.
"""

from __future__ import annotations

import json
import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import pyarrow as pa
import pyarrow.parquet as pq

from ..errors import InputError, bad_parameter, did_you_mean
from ..objects import load_object
from ..pipeline import evaluate_samples
from ..runtime.writing import atomic_write
from ..search.pairs import PairSearch, PairSearchSettings, best_pairs, optimize_pairs
from .judges import TASK_FAMILIES, scored, working_end_box

logger = logging.getLogger(__name__)

MODES = ("no-robustness", "default", "extra-robustness")
"""The threshold modes of the figures (paper Table I)."""


@dataclass(frozen=True)
class ValidationSettings:
    """What :func:`validate_tasks` runs; the defaults are the paper-scale study.

    Attributes
    ----------
    seeds : int
        Object instances per family (seeds 0..seeds-1).
    grasps : int
        Uniform grasps of the brute force per object.
    uses : int
        Use points drawn by surface area, scored with every grasp.
    budget : int
        Simulations of the optimiser per object.
    restarts : int
        Independent cross-entropy runs sharing ``budget``.
    refine : float
        Share of ``budget``, in [0, 1), that continues the best run around its best point.
    also_grasps : int
        Also the brute force on the first K of the ``grasps`` grasps (0: not).
    top : int
        Top grasps judged per object and method.
    tasks : tuple of str
        Tasks to judge, among ``cut``, ``beat``, ``pick``.
    families : tuple of str
        Families to judge (each with the tasks that judge it); empty: all.
    optimizer, brute_force : bool
        Run that search.
    figures : bool
        Render the figures (needs ``brute_force``).
    cell_px : int
        Size of one figure cell, pixels.
    materials : bool
        The families' per-part materials instead of uniform unit density.
    """

    seeds: int = 5
    grasps: int = 1000
    uses: int = 4000
    budget: int = 1000
    restarts: int = 1
    refine: float = 0.0
    also_grasps: int = 0
    top: int = 10
    tasks: tuple[str, ...] = ("cut", "beat", "pick")
    families: tuple[str, ...] = ()
    optimizer: bool = True
    brute_force: bool = True
    figures: bool = True
    cell_px: int = 220
    materials: bool = False

    def check(self) -> ValidationSettings:
        """Refuse settings the study cannot run, before any work.

        Returns
        -------
        ValidationSettings
            ``self``.

        Raises
        ------
        InputError
            Naming the parameter, its value and what it must be.
        """
        for name in ("seeds", "grasps", "uses", "budget", "restarts", "top", "cell_px"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise bad_parameter(name, f"must be a positive integer, got {value!r}")
        if not 0 <= self.also_grasps < self.grasps:
            raise bad_parameter(
                "also_grasps",
                f"must lie in [0, grasps) = [0, {self.grasps}), got {self.also_grasps}",
            )
        if not 0.0 <= self.refine < 1.0:
            raise bad_parameter("refine", f"must lie in [0, 1), got {self.refine}")
        if not self.tasks:
            raise bad_parameter("tasks", f"names no task; choose among {', '.join(TASK_FAMILIES)}")
        for task in self.tasks:
            if task not in TASK_FAMILIES:
                raise bad_parameter(
                    "tasks",
                    f"has {task!r}, which the validation does not judge"
                    f"{did_you_mean(task, TASK_FAMILIES)}; "
                    f"choose among {', '.join(TASK_FAMILIES)}",
                )
        judged = {f for task in self.tasks for f in TASK_FAMILIES[task]}
        for family in self.families:
            if family not in judged:
                raise bad_parameter(
                    "families",
                    f"has {family!r}, which no task of {', '.join(self.tasks)} judges"
                    f"{did_you_mean(family, judged)}; choose among {', '.join(sorted(judged))}",
                )
        if not (self.optimizer or self.brute_force):
            raise InputError("optimizer and brute_force are both False: nothing to run")
        return self

    def families_of(self, task: str) -> tuple[str, ...]:
        """The families judged for ``task``, in :data:`TASK_FAMILIES` order.

        Parameters
        ----------
        task : str
            One of :attr:`tasks`.

        Returns
        -------
        tuple of str
        """
        return tuple(f for f in TASK_FAMILIES[task] if not self.families or f in self.families)

    @property
    def steps(self) -> int:
        """Objects judged: (task, family, seed) triples."""
        return self.seeds * sum(len(self.families_of(t)) for t in self.tasks)


def grasp_table(cache: Path, family: str, seed: int, n: int, materials: bool = False) -> pa.Table:
    """The ``n`` uniform grasps of ``family:seed``, evaluated once and cached (for every task).

    Parameters
    ----------
    cache : pathlib.Path
        Folder of the cached tables (``{family}_{seed}_{n}_{unit|materials}.parquet``).
    family : str
        A built-in family.
    seed : int
        The instance's seed.
    n : int
        Grasps: samples 0..n-1 of run seed 0.
    materials : bool
        Per-part materials instead of unit density.

    Returns
    -------
    pyarrow.Table
        The evaluated rows (ε only: the GWS volume is NaN, the search never reads it).
    """
    mass = "materials" if materials else "unit"
    path = cache / f"{family}_{seed}_{n}_{mass}.parquet"
    if path.exists():
        return pq.read_table(path)
    obj = load_object(f"{family}:{seed}", materials=materials)
    table = evaluate_samples(obj, n, seed=0, volume=False, batch_size=2000).table
    atomic_write(path, lambda fh: pq.write_table(table, fh))
    return table


def brute_force(obj, task: str, table: pa.Table, uses: int, top: int) -> PairSearch:
    """Top ``top`` distinct grasps of ``table`` × ``uses`` use points, each with its best use.

    Parameters
    ----------
    obj : GraspObject
        The object the rows of ``table`` were evaluated on.
    task : str
        A registered task (default mode).
    table : pyarrow.Table
        Evaluated uniform grasps (:func:`grasp_table`).
    uses : int
        Use points drawn by surface area (run 1).
    top : int
        Grasps kept.

    Returns
    -------
    PairSearch
        As :func:`affordgrasp.search.pairs.best_pairs` with ``per_grasp=True``.
    """
    settings = PairSearchSettings(task, uses=uses, seed=0, top=top, per_grasp=True)
    return best_pairs(obj, settings, grasp_table=table)


def validate_tasks(
    settings: ValidationSettings,
    out: str | Path,
    *,
    cache: str | Path | None = None,
    on_object: Callable[[str, str, int, dict[str, Any]], None] | None = None,
) -> dict[str, Any]:
    """Run the validation study and write its report (and figures) to ``out``.

    Parameters
    ----------
    settings : ValidationSettings
        What to run (checked first).
    out : str or path-like
        Folder of ``validation.json`` and, with figures, ``validation_<task>.png``,
        ``validation_modes_knife.png`` and ``modes_knife.json`` (created).
    cache : str or path-like, optional
        Folder of the evaluated grasp tables and the top rows of each search
        (``top_<task>_<family>_<seed>_{bf,opt}.parquet``); ``out/cache`` when None.
        Cached grasp tables are reused by later runs.
    on_object : callable, optional
        ``on_object(task, family, seed, entry)`` after each object is judged; ``entry`` is
        the family's report so far.

    Returns
    -------
    dict
        The report: ``settings``, ``tasks`` (per task: ``families`` with the per-seed
        ``[hits, rows]`` of each method, their fractions, top-1 verdicts and candidate
        counts, and a ``summary`` per method) and ``seconds`` (wall time, s).

    Raises
    ------
    InputError
        For settings the study cannot run (:meth:`ValidationSettings.check`).
    """
    settings.check()
    out = Path(out)
    cache = out / "cache" if cache is None else Path(cache)
    cache.mkdir(parents=True, exist_ok=True)
    out.mkdir(parents=True, exist_ok=True)
    report: dict[str, Any] = {"settings": asdict(settings), "tasks": {}}
    t0 = time.perf_counter()
    also = settings.also_grasps
    methods = ["brute_force", "optimizer", "brute_force_labels", "optimizer_labels"]
    if also:
        methods += [f"brute_force_at_{also}", f"brute_force_at_{also}_labels"]
    for task in settings.tasks:
        per_family = {}
        for family in settings.families_of(task):
            entry = _judge_family(settings, task, family, cache, on_object)
            for method in methods:
                hits = sum(h for h, _ in entry[method])
                total = sum(n for _, n in entry[method])
                entry[f"{method}_fraction"] = hits / total if total else None
            per_family[family] = entry
        summary = {}
        for method in methods:
            hits = sum(h for e in per_family.values() for h, _ in e[method])
            total = sum(n for e in per_family.values() for _, n in e[method])
            summary[method] = {
                "hits": hits,
                "top_grasps": total,
                "fraction": hits / total if total else None,
            }
        report["tasks"][task] = {"families": per_family, "summary": summary}
        logger.info("%s %s", task, json.dumps(summary))
    report["seconds"] = round(time.perf_counter() - t0, 1)
    atomic_write(out / "validation.json", json.dumps(report, indent=1).encode())
    if settings.figures and settings.brute_force:
        render_figures(settings, out, cache, list(report["tasks"]))
    return report


def _judge_family(
    settings: ValidationSettings,
    task: str,
    family: str,
    cache: Path,
    on_object: Callable[[str, str, int, dict[str, Any]], None] | None,
) -> dict[str, Any]:
    """The report entry of one family for one task, over the seeds."""
    also = settings.also_grasps
    entry: dict[str, Any] = {
        "brute_force": [],
        "optimizer": [],
        "brute_force_labels": [],  # beat judged by the part labels alone
        "optimizer_labels": [],
        "top1": {"brute_force": [], "optimizer": []},
        "candidates": [],
        "opt_candidates": [],
        "seeds": [],
    }
    if also:
        entry[f"brute_force_at_{also}"] = []
        entry[f"brute_force_at_{also}_labels"] = []
        entry["top1"][f"brute_force_at_{also}"] = []
    for seed in range(settings.seeds):
        obj = load_object(f"{family}:{seed}", materials=settings.materials)
        com = obj.mass.center_of_mass
        box = working_end_box(obj, family) if task == "beat" else None
        entry["seeds"].append(seed)
        if settings.brute_force:
            table = grasp_table(cache, family, seed, settings.grasps, settings.materials)
            found = brute_force(obj, task, table, settings.uses, settings.top)
            bf = scored(task, family, found.table, com, box)
            entry["brute_force"].append(bf["hits"])
            entry["brute_force_labels"].append(bf["labels"])
            entry["top1"]["brute_force"].append(bf["top1"])
            entry["candidates"].append(found.candidates)
            _write_top(found.table, cache / f"top_{task}_{family}_{seed}_bf.parquet")
            if also:
                head = brute_force(obj, task, table.slice(0, also), settings.uses, settings.top)
                first = scored(task, family, head.table, com, box)
                entry[f"brute_force_at_{also}"].append(first["hits"])
                entry[f"brute_force_at_{also}_labels"].append(first["labels"])
                entry["top1"][f"brute_force_at_{also}"].append(first["top1"])
        if settings.optimizer:
            search = PairSearchSettings(
                task,
                uses=settings.uses,
                seed=seed,
                top=settings.top,
                budget=settings.budget,
                restarts=settings.restarts,
                refine=settings.refine,
            )
            opt = optimize_pairs(obj, search)
            judged = scored(task, family, opt.table, com, box)
            entry["optimizer"].append(judged["hits"])
            entry["optimizer_labels"].append(judged["labels"])
            entry["top1"]["optimizer"].append(judged["top1"])
            entry["opt_candidates"].append(opt.candidates)
            _write_top(opt.table, cache / f"top_{task}_{family}_{seed}_opt.parquet")
        logger.info(
            "%s %s:%d brute force %s optimiser %s",
            task,
            family,
            seed,
            entry["brute_force"][-1] if entry["brute_force"] else "-",
            entry["optimizer"][-1] if entry["optimizer"] else "-",
        )
        if on_object is not None:
            on_object(task, family, seed, entry)
    return entry


def _write_top(table: pa.Table, path: Path) -> None:
    """Write a search's top rows (a reader sees the old file or the new one)."""
    atomic_write(path, lambda fh: pq.write_table(table, fh))


def render_figures(
    settings: ValidationSettings, out: str | Path, cache: str | Path, tasks: Sequence[str]
) -> list[Path]:
    """The validation's figures: per task, the best grasp of each family in each mode.

    Per task, the brute force's best grasp of the first five families of the task (seed 0)
    in each threshold mode (paper Figs. 3-6); then beat and cut on ``knife:0`` in the three
    modes (paper Fig. 7), whose numbers also go to ``modes_knife.json``.

    Parameters
    ----------
    settings : ValidationSettings
        ``grasps``, ``uses``, ``cell_px`` and ``materials`` are read.
    out : str or path-like
        Folder of the PNG and JSON files (exists).
    cache : str or path-like
        Folder of the evaluated grasp tables (:func:`grasp_table`).
    tasks : sequence of str
        Tasks to draw.

    Returns
    -------
    list of pathlib.Path
        The files written.
    """
    from ..viz.grid import save_grid

    out, cache = Path(out), Path(cache)
    written = []
    mass = ", with the materials" if settings.materials else ""
    for task in tasks:
        families = TASK_FAMILIES[task][:5]
        rows = []
        for family in families:
            obj = load_object(f"{family}:0", materials=settings.materials)
            table = grasp_table(cache, family, 0, settings.grasps, settings.materials)
            cells = []
            for mode in MODES:
                search = PairSearchSettings(task, mode=mode, uses=settings.uses, top=1)
                found = best_pairs(obj, search, grasp_table=table)
                caption = ""
                if found.table.num_rows:
                    r = found.table.slice(0, 1).to_pylist()[0]
                    caption = f"ε {r['epsilon']:.3f} · U on {r['use_part'] or '-'}"
                cells.append(_cell(obj, found.table, settings.cell_px, caption))
            rows.append(cells)
        path = out / f"validation_{task}.png"
        save_grid(
            rows,
            path,
            row_labels=list(families),
            col_labels=list(MODES),
            title=f"best {task} grasp per mode (brute force{mass})",
        )
        written.append(path)
    # Fig. 7: beat and cut on the knife, three robustness requirements
    obj = load_object("knife:0", materials=settings.materials)
    table = grasp_table(cache, "knife", 0, settings.grasps, settings.materials)
    rows, numbers = [], {}
    for task in ("beat", "cut"):
        cells = []
        for mode in MODES:
            search = PairSearchSettings(task, mode=mode, uses=settings.uses, top=1)
            found = best_pairs(obj, search, grasp_table=table)
            r = found.table.slice(0, 1).to_pylist()[0] if found.table.num_rows else None
            numbers[f"{task}/{mode}"] = (
                None
                if r is None
                else {
                    "value": r["value"],
                    "epsilon": r["epsilon"],
                    "use_part": r["use_part"],
                    "contact_parts": sorted(set(r["contact_parts"])),
                }
            )
            caption = "" if r is None else f"ε {r['epsilon']:.3f} · {r['use_part']}"
            cells.append(_cell(obj, found.table, settings.cell_px, caption))
        rows.append(cells)
    path = out / "validation_modes_knife.png"
    save_grid(
        rows,
        path,
        row_labels=["beat", "cut"],
        col_labels=list(MODES),
        title="knife: robustness modes (paper Fig. 7)",
    )
    written.append(path)
    atomic_write(out / "modes_knife.json", json.dumps(numbers, indent=1).encode())
    written.append(out / "modes_knife.json")
    return written


def _cell(obj, table: pa.Table, size: int, caption: str):
    """The image of a table's first row, or a note when the task found no grasp."""
    from ..viz.overlays import grasp_image
    from ..viz.scene import grasp_scene

    if table.num_rows == 0:
        return "no grasp above −∞"
    row = table.slice(0, 1).to_pylist()[0]
    image, _ = grasp_image(grasp_scene(obj, row), size_px=size, caption=caption)
    return image
