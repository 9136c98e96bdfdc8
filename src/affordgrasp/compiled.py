"""The compiled kernels as a whole: load them (or compile them) at once, and build caches.

The simulation and the metrics run in numba kernels. numba compiles a kernel at its first
call and caches the machine code on disk (see :mod:`affordgrasp.metrics.kernel_cache`), so
only the very first run on a machine pays the compilation (about a minute on one core).
Building the package runs ``python -m affordgrasp.compiled`` (see ``setup.py``), so an
installed package ships with the caches of the machine it was built on and its first run
only loads them (about a second). A cache built elsewhere (another CPU, another numba) is
ignored and the kernels compile on first use, as before.

:func:`warm_up` loads or compiles every kernel of the pipeline up front, so that a command
can time its work apart from this one-time cost and say what the cost was.
"""

from __future__ import annotations

import time
from dataclasses import dataclass


@dataclass(frozen=True)
class KernelLoad:
    """What making the kernels ready cost.

    Attributes
    ----------
    seconds : float
        Wall time, s.
    compiled : bool
        True when at least one kernel was compiled (no usable cache).
    """

    seconds: float
    compiled: bool

    def describe(self) -> str:
        """The load in words, for a summary line.

        Returns
        -------
        str
            E.g. ``"kernels 0.4 s (loaded from cache)"``.
        """
        how = "compiled, now cached for later runs" if self.compiled else "loaded from cache"
        return f"kernels {self.seconds:.1f} s ({how})"


def _dispatchers() -> list:
    from .grasp import kernels
    from .hands import kinematics
    from .metrics import phi

    return [
        kernels.simulate_batch,
        kinematics.link_poses,
        kinematics.shape_poses,
        phi.contact_metrics_batch,
    ]


def warm_up() -> KernelLoad:
    """Load (or compile) every kernel the pipeline calls, by running it on a small object.

    The object is the built-in tumbler: after the first run it comes from the cache of
    prepared objects, so warming up imports neither trimesh nor scipy.

    Returns
    -------
    KernelLoad
    """
    from .objects import load_object
    from .pipeline import evaluate_samples

    started = time.perf_counter()
    misses_before = sum(sum(d.stats.cache_misses.values()) for d in _dispatchers())
    evaluate_samples(load_object("tumbler"), 6, seed=0)
    misses = sum(sum(d.stats.cache_misses.values()) for d in _dispatchers()) - misses_before
    return KernelLoad(time.perf_counter() - started, misses > 0)


def main() -> None:
    """Warm the kernels up and print what it cost (``python -m affordgrasp.compiled``)."""
    load = warm_up()
    print(f"affordgrasp: {load.describe()}")


if __name__ == "__main__":
    main()
