"""The compiled kernels as a whole: load them (or compile them) at once, and build caches.

The simulation and the metrics run in numba kernels. numba compiles a kernel at its first
call and caches the machine code on disk (see :mod:`affordgrasp.runtime.kernel_cache`), so
only the very first run on a machine pays the compilation (about a minute on one core).
Building the package runs ``python -m affordgrasp.kernels`` (see ``setup.py``), so an
installed package ships with the caches of the machine it was built on and its first run
only loads them (about a second). A cache built elsewhere (another CPU, another numba) is
ignored and the kernels compile on first use, as before.

:func:`warm_up` loads or compiles every kernel of the pipeline up front, so that a command
can time its work apart from this one-time cost and say what the cost was; with
``vision=True`` it also makes the depth rasteriser's kernel ready (the build step does, so
the first depth image after an install does not compile either).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np


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


def _vision_dispatchers() -> list:
    from .vision import fusion, raster

    return [raster.rasterise, fusion._carve]


def _misses(dispatchers: list) -> int:
    return sum(sum(d.stats.cache_misses.values()) for d in dispatchers)


class _Compilations:
    """Counts numba's ``numba:compile`` events (one per compiled signature, nested too)."""

    def __init__(self) -> None:
        self.count = 0

    def __enter__(self):
        try:
            from numba.core import event
        except ImportError:  # pragma: no cover - numba without its event API
            return self

        outer = self

        class _Listener(event.Listener):
            def on_start(self, ev):
                outer.count += 1

            def on_end(self, ev):
                pass

        self._listener = _Listener()
        event.register("numba:compile", self._listener)
        return self

    def __exit__(self, *exc) -> None:
        listener = getattr(self, "_listener", None)
        if listener is not None:
            from numba.core import event

            event.unregister("numba:compile", listener)


def _reference_paths() -> None:
    """Run the per-metric functions the batch falls back to when a compiled solver cannot
    certify its answer (rare: see ``metrics.phi``), so that their kernels are ready (and
    ship with the package) before the first grasp that needs them."""
    from .metrics import epsilon, hold_effort, impact_effort, use_force
    from .metrics.contacts import ContactSet

    axes = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1.0]])
    contacts = ContactSet.from_arrays(0.03 * axes, axes, 0.5)
    center = np.zeros(3)
    use_point, use_normal, axis = np.array([0.03, 0.0, 0.0]), axes[0], axes[4]
    for volume in (False, True):
        epsilon(contacts, center, 0.05, volume=volume)
    hold_effort(contacts, center, backend="highs")
    impact_effort(contacts, center, use_point, use_normal, axis, backend="highs")
    use_force(contacts, center, use_point, use_normal, backend="highs")


def warm_up(*, vision: bool = False, reference: bool = False) -> KernelLoad:
    """Load (or compile) every kernel the pipeline calls, by running it on a small object.

    The object is the built-in tumbler: after the first run it comes from the cache of
    prepared objects, so warming up the pipeline imports neither trimesh nor scipy.

    Parameters
    ----------
    vision : bool
        Also render one depth image of the tumbler with the default (raster) engine, which
        loads or compiles the rasteriser's kernel (imports trimesh; the commands that do not
        render leave it out).
    reference : bool
        Also run the per-metric functions that the batch falls back to in rare grasps
        (their own kernels; imports highspy). The build step does, so that they ship too.

    Returns
    -------
    KernelLoad
    """
    from .objects import load_object
    from .pipeline import evaluate_samples

    started = time.perf_counter()
    dispatchers = _dispatchers() + (_vision_dispatchers() if vision else [])
    misses_before = _misses(dispatchers)
    with _Compilations() as compilations:
        obj = load_object("tumbler")
        evaluate_samples(obj, 6, seed=0)
        if reference:
            _reference_paths()
        if vision:
            from .vision.depth import DepthRenderer
            from .vision.fusion import free_space_field

            renderer = DepthRenderer(obj.mesh, engine="raster")
            p0 = np.array([[0.1, -0.2, 0.3, 0.0, 0.5, 0.5], [0.6, 0.4, -0.3, 0.0, 0.0, 0.5]])
            free_space_field(renderer.render(p0), renderer.poses(p0), renderer.camera)
    misses = _misses(dispatchers) - misses_before
    return KernelLoad(time.perf_counter() - started, misses > 0 or compilations.count > 0)


def main() -> None:
    """Warm the kernels up and print what it cost (``python -m affordgrasp.kernels``)."""
    load = warm_up(vision=True, reference=True)
    print(f"affordgrasp: {load.describe()}")


if __name__ == "__main__":
    main()
