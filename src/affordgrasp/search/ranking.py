"""Ranking rows by a score: the one ranker of the package (conventions: Datasets).

Every search keeps its best rows with :class:`TopRows` (streamed: a dataset larger than
memory) or :func:`top_indices` (one array): highest score first; −∞ (a failed threshold)
and NaN never rank; ties go to the smaller first key, then the next... so the result does
not depend on the order in which rows arrive. Sorting the whole table by (score descending,
keys ascending) and dropping the rows at −∞ gives the same rows.
"""

from __future__ import annotations

import numpy as np

from ..errors import bad_parameter


class TopRows:
    """The ``k`` best rows seen so far, streamed: highest value first, ties by the keys.

    Only values above −∞ rank (−∞ means a threshold failed; NaN never ranks). Ties go to the
    smaller first key, then the smaller second key..., so the result does not depend on the
    order in which rows arrive.

    Parameters
    ----------
    k : int
        How many rows to keep.
    n_keys : int
        Number of tie-breaking key arrays given to ``add``.

    Attributes
    ----------
    values : (j,) float64 ndarray
        The kept values, best first (j <= k).
    keys : tuple of (j,) int64 ndarray
        Their keys, in the same order.
    """

    def __init__(self, k: int, n_keys: int):
        self.k = k
        self.values = np.empty(0)
        self.keys = tuple(np.empty(0, dtype=np.int64) for _ in range(n_keys))

    def add(self, values: np.ndarray, *keys: np.ndarray) -> int:
        """Offer rows; the best ``k`` of all rows offered so far are kept.

        Parameters
        ----------
        values : (n,) float ndarray
            The score of each row; −∞ and NaN never rank.
        *keys : (n,) int ndarray
            The ``n_keys`` tie-breaking keys of each row.

        Returns
        -------
        int
            How many of these rows can rank (value > −∞).
        """
        values = np.asarray(values, dtype=np.float64)
        keep = values > -np.inf  # False for NaN too
        n = int(keep.sum())
        if n:
            v = np.concatenate([self.values, values[keep]])
            ks = [
                np.concatenate([a, np.asarray(b, dtype=np.int64)[keep]])
                for a, b in zip(self.keys, keys, strict=True)
            ]
            order = np.lexsort((*reversed(ks), -v))[: self.k]  # lexsort: last key first
            self.values = v[order]
            self.keys = tuple(a[order] for a in ks)
        return n


def top_indices(values: np.ndarray, k: int, *keys: np.ndarray) -> np.ndarray:
    """Indices of the ``k`` best entries of ``values``, best first.

    The ranking of :class:`TopRows` on one array: −∞ and NaN never rank; ties go to the
    smaller key (``keys``, first key first), then to the smaller index.

    Parameters
    ----------
    values : (n,) float ndarray
        Scores.
    k : int
        How many to return (>= 0); fewer when fewer rank.
    *keys : (n,) int ndarray
        Tie-breaking keys.

    Returns
    -------
    (j,) int64 ndarray
        j = min(k, number of values above −∞).

    Examples
    --------
    >>> top_indices(np.array([1.0, -np.inf, 3.0, np.nan, 3.0]), 2)
    array([2, 4])
    """
    if isinstance(k, bool) or not isinstance(k, int | np.integer) or k < 0:
        raise bad_parameter("k", f"must be a non-negative integer, got {k!r}")
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    best = TopRows(int(k), len(keys) + 1)
    best.add(values, *keys, np.arange(len(values), dtype=np.int64))
    return best.keys[-1]


def best_index(values: np.ndarray) -> int | None:
    """Index of the best entry of ``values`` (the first of ties), None when none ranks.

    Parameters
    ----------
    values : (n,) float ndarray
        Scores; −∞ and NaN never rank.

    Returns
    -------
    int or None
    """
    top = top_indices(values, 1)
    return int(top[0]) if len(top) else None
