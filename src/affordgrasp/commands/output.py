"""Printing results: readable tables for people, one JSON document for scripts."""

from __future__ import annotations

import json
import math
import os
import sys
from contextlib import contextmanager

import numpy as np

from ..jsonable import to_jsonable

UNBOUNDED_WIDTH = 10_000  # columns of a table printed to a pipe or a file


def fmt(value) -> str:
    """A value as the text tables show it (4 significant digits, scientific when tiny or huge).

    Parameters
    ----------
    value : object

    Returns
    -------
    str
    """
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isinf(v) or math.isnan(v):
            return str(v)
        if v != 0 and (abs(v) < 1e-3 or abs(v) >= 1e5):
            return f"{v:.3e}"
        return f"{v:.4g}"
    return str(value)


class Output:
    """Collects what a command reports and prints it the way the user asked.

    Parameters
    ----------
    json_mode : bool
        Print one JSON document at the end instead of text tables.
    """

    def __init__(self, json_mode: bool = False):
        self.json_mode = json_mode
        from rich.console import Console

        # Tables go to stdout; progress bars to stderr so stdout stays parseable. A pipe or a
        # file gets whole numbers and names: rich folds cells at 80 columns where it cannot
        # ask a terminal for its width (COLUMNS still sets it).
        piped = not sys.stdout.isatty() and "COLUMNS" not in os.environ
        self.console = Console(file=sys.stdout, width=UNBOUNDED_WIDTH if piped else None)
        self.err = Console(file=sys.stderr)

    def table(self, title: str, columns: list[str], rows: list[list]) -> None:
        """Print a table (nothing in JSON mode).

        Parameters
        ----------
        title : str
        columns : list of str
            Headers; text columns are left-aligned, numbers right-aligned.
        rows : list of list
            Cells, formatted by :func:`fmt`.
        """
        if self.json_mode:
            return
        from rich.table import Table

        t = Table(title=title, title_justify="left")
        for c in columns:
            left = c in ("status", "task", "name", "quantity", "category", "description")
            t.add_column(c, justify="left" if left else "right", overflow="fold")
        for r in rows:
            t.add_row(*[fmt(v) for v in r])
        self.console.print(t)

    def text(self, message: str) -> None:
        """Print a line of text, with rich markup (nothing in JSON mode).

        Parameters
        ----------
        message : str
        """
        if not self.json_mode:
            self.console.print(message)

    def result(self, document: dict) -> None:
        """The command's result; printed only in JSON mode (the tables already said it).

        Parameters
        ----------
        document : dict
            Made JSON-ready by :func:`to_jsonable` (NaN as null, ±inf as strings).
        """
        if self.json_mode:
            print(json.dumps(to_jsonable(document), indent=2, allow_nan=False))

    @contextmanager
    def progress(self, description: str, total: int):
        """A progress bar with rate and ETA on stderr (a context manager; hidden in JSON mode).

        Parameters
        ----------
        description : str
        total : int
            Units of work.

        Yields
        ------
        callable
            ``advance(n=1)``: n more units done.
        """
        from rich.progress import (
            BarColumn,
            MofNCompleteColumn,
            Progress,
            TextColumn,
            TimeRemainingColumn,
        )

        columns = [
            TextColumn("{task.description}"),
            BarColumn(),
            MofNCompleteColumn(),
            TextColumn("{task.fields[rate]}"),
            TimeRemainingColumn(),
        ]
        with Progress(*columns, console=self.err, transient=True, disable=self.json_mode) as p:
            task = p.add_task(description, total=total, rate="")
            import time

            started = time.perf_counter()

            def advance(n: int = 1) -> None:
                p.advance(task, n)
                done = p.tasks[0].completed
                elapsed = time.perf_counter() - started
                if elapsed > 0:
                    p.update(task, rate=f"{done / elapsed:,.0f} grasps/s")

            yield advance
