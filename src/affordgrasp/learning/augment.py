"""More viable training rows near the viable ones: perturbed pregrasps, simulated again.

Uniform sampling finds few viable grasps (5.8 % on the shipped models' dataset), and ΣE_h
is rough in the pregrasp. The shipped regressor's recipe (``tools/train_default_models.py``,
docs/learning.md, "More viable rows per training object") adds rows where they are cheap
to find: each viable training grasp is perturbed by Gaussian noise in p0 (the use
direction kept) and simulated again; the copies that stay viable join the training rows,
with their depth images rendered.
"""

from __future__ import annotations

import numpy as np

from ..errors import InputError


def perturbed_rows(train, *, copies: int, sigma: float, seed: int, origins: bool = False):
    """Viable re-simulations of the training rows' perturbed pregrasps.

    Parameters
    ----------
    train : Samples
        Training rows (``object``, ``family``, ``p0`` (n, 6), ``use_dir`` (n, 2), ``meta``).
    copies : int
        Perturbed copies of each row.
    sigma : float
        Standard deviation of the Gaussian noise added to p0, in p0's own units (the
        position coordinates clipped to [-1, 1], the last to [0, 1]).
    seed : int
        Seed of the noise (one stream over the objects in sorted order).
    origins : bool
        Also return each part's row numbers in ``train``.

    Returns
    -------
    parts : list of Samples
        One per object with viable copies (``sample`` -1, target ``hold_effort_sum``,
        depth in mm).
    tried : int
        Copies simulated.
    sources : list of (k,) int
        Only with ``origins``: the row of ``train`` each copy of each part perturbs.
    """
    from ..objects import load_object
    from ..pipeline import evaluate_inputs
    from ..tasks import MetricColumns, is_viable
    from ..vision import depth_to_mm, renderer_for
    from .data import Samples
    from .targets import target_values

    rng = np.random.default_rng(seed)
    parts = []
    sources = []
    tried = 0
    for name in sorted(set(train.object)):
        rows = np.flatnonzero(train.object == name)
        p0 = np.repeat(train.p0[rows], copies, axis=0)
        use = np.repeat(train.use_dir[rows], copies, axis=0)
        q = p0 + rng.normal(0.0, sigma, p0.shape)
        q[:, :5] = np.clip(q[:, :5], -1.0, 1.0)
        q[:, 5] = np.clip(q[:, 5], 0.0, 1.0)
        table = evaluate_inputs(name, q, use).table
        ok = is_viable(MetricColumns(table))
        tried += len(q)
        if not ok.any():
            continue
        y = target_values("hold_effort_sum", table)[ok]
        images = depth_to_mm(renderer_for(load_object(name)).render(q[ok]))
        sources.append(np.repeat(rows, copies)[ok])
        parts.append(
            Samples(
                np.full(int(ok.sum()), name, dtype=object),
                np.full(int(ok.sum()), train.family[rows[0]], dtype=object),
                np.full(int(ok.sum()), -1, dtype=np.int64),
                q[ok],
                use[ok],
                y,
                images,
                dict(train.meta),
            )
        )
    if origins:
        return parts, tried, sources
    return parts, tried


def concatenate_samples(parts, meta):
    """One :class:`~affordgrasp.learning.data.Samples` of several, rows in order.

    Parameters
    ----------
    parts : sequence of Samples
        At least one.
    meta : dict
        The result's ``meta`` (copied).

    Returns
    -------
    Samples

    Raises
    ------
    InputError
        When ``parts`` is empty (no perturbed copy was viable).
    """
    from .data import Samples

    if not parts:
        raise InputError("no perturbed copy was viable: nothing to add (try a smaller sigma)")
    return Samples(
        *(
            np.concatenate([getattr(p, f) for p in parts])
            for f in Samples.__dataclass_fields__
            if f not in ("meta",)
        ),
        meta=dict(meta),
    )
