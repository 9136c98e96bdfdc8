"""The ``affordgrasp`` command: a thin shell over the Python API.

Each subcommand lives in ``affordgrasp.commands.<name>`` with ``add_arguments(parser)`` and
``run(args, out)``; ``out`` (an ``Output``) prints either a readable table or, with
``--json``, one JSON document on stdout. Exit codes: 0 success, 2 bad input (a one-line
reason on stderr), 1 internal failure.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from ._version import __version__
from .commands import add_verbose_argument  # also used by subcommands' own parsers
from .errors import InputError, cli_message
from .runtime.interrupts import interrupt_in, stop_on_signals
from .runtime.process_tuning import keep_freed_memory, one_blas_thread

COMMANDS = {
    "objects": "list the built-in object families, or export one as a mesh",
    "simulate": "simulate the grasp policy on an object and summarise the outcomes",
    "evaluate": "simulate, compute the metric vector and score tasks on an object",
    "tasks": "list the affordance functions (tasks) and their thresholds",
    "generate": "generate a sharded Parquet dataset of evaluated grasps (resumable)",
    "best": "brute-force argmax of a task over a dataset",
    "optimize": "optimise a task directly in simulation (cross-entropy method)",
    "show": "render the best grasps of a task as PNG grids and an interactive HTML page",
    "plots": "plot metric distributions, status counts and affordances of a dataset",
    "physics": "validate a dataset's grasps in MuJoCo and report how well the metrics predict them",
    "depth": "render the camera-in-hand depth image D(p0, O) of a pregrasp",
    "train": "train a viability classifier or a metric regressor on a dataset",
    "predict": "predict with a trained (or the shipped) model on every sample of a dataset",
    "model-eval": "evaluate a model on held-out objects beside baselines, with plots",
    "plan": "choose a grasp from camera-in-hand views with learned models, and check it",
    "validate": "the paper's validation: judge the best cut, beat and pick grasps by object parts",
}


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line on stderr (and exit code 2)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def build_parser() -> argparse.ArgumentParser:
    """The ``affordgrasp`` argument parser with every subcommand registered.

    Returns
    -------
    argparse.ArgumentParser
    """
    parser = _Parser(
        prog="affordgrasp",
        description="Task-oriented grasp quality: simulate, score, generate datasets, show.",
    )
    parser.add_argument("--version", action="version", version=f"affordgrasp {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress details")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, help_text in COMMANDS.items():
        module = importlib.import_module(f"affordgrasp.commands.{name.replace('-', '_')}")
        p = sub.add_parser(name, help=help_text, description=help_text)
        p.add_argument("--json", action="store_true", help="print one JSON document on stdout")
        add_verbose_argument(p)
        module.add_arguments(p)
        p.set_defaults(_module=module)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line.

    Parameters
    ----------
    argv : list of str, optional
        The arguments without the program name; ``sys.argv[1:]`` when None.

    Returns
    -------
    int
        Exit status: 0 on success, 2 for bad input (one line naming the problem and the
        fix), 1 for any other error, 128 + signum when stopped by a signal.
    """
    one_blas_thread()  # before numpy is imported: see process_tuning
    from .commands.limits import check_limits
    from .commands.output import Output

    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse exits 2 on bad usage, 0 on --help
        return int(exc.code or 0)
    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(levelname)s %(name)s: %(message)s",
    )
    if args.command is None:
        parser.print_help()
        return 2
    out = Output(json_mode=args.json)
    keep_freed_memory()
    try:
        with stop_on_signals():
            check_limits(args, getattr(args._module, "LIMITS", {}))
            args._module.run(args, out)
    except InputError as exc:
        print(f"affordgrasp {args.command}: error: {cli_message(exc)}", file=sys.stderr)
        return 2
    except BaseException as exc:  # noqa: BLE001 - the CLI's last line of defence
        stop = interrupt_in(exc)
        if stop is not None:
            return _interrupted(args.command, stop)
        if not isinstance(exc, Exception):
            raise
        logging.getLogger("affordgrasp").debug("internal failure", exc_info=True)
        print(
            f"affordgrasp {args.command}: internal error: {type(exc).__name__}: {exc} "
            "(run with -v for details; please report it)",
            file=sys.stderr,
        )
        if args.verbose:
            raise
        return 1
    if argv is None:
        _about_to_exit()
    return 0


def _interrupted(command: str, exc: KeyboardInterrupt) -> int:
    """Say that ``command`` was stopped; the exit status for Ctrl-C (130) or the signal."""
    signum = getattr(exc, "signum", None)
    how = f" ({exc})" if signum else ""
    print(f"affordgrasp {command}: interrupted{how}", file=sys.stderr)
    return 128 + signum if signum else 130


def _about_to_exit() -> None:
    """Spare the interpreter's last garbage collections when the process is the command.

    The compiled kernels leave numba's type system (hundreds of thousands of objects) in
    memory, and the collections at interpreter exit walk them all: about 0.2-0.3 s of a
    short command. Freezing them leaves them to the operating system; ``atexit`` handlers
    and module clean-up still run. Only when ``main`` reads ``sys.argv`` (the program),
    not when a caller passes ``argv`` and goes on living.
    """
    import gc

    gc.freeze()


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
