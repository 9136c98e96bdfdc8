"""Splits of a dataset's objects for learning (conventions: Vision).

Splits are by object instance: the objects of the test (and validation) set never appear in
training, and the families (categories) overlap. A split by family holds out whole families
instead. Both are pure functions of the object names, their families and a seed, so a split
is the same wherever it is computed (:meth:`affordgrasp.dataset.handle.Dataset.split`, or
over the rows a target is defined on, as training does).
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["Split", "split_by_family", "split_by_object"]


@dataclass(frozen=True)
class Split:
    """Object names of each part of a split (disjoint).

    Attributes
    ----------
    train, val, test : tuple of str
        Sorted object names.
    kind : str
        ``"object"`` (instances held out) or ``"family"`` (whole families held out).
    """

    train: tuple[str, ...]
    val: tuple[str, ...]
    test: tuple[str, ...]
    kind: str = "object"

    def to_dict(self) -> dict:
        """The split as JSON-ready data.

        Returns
        -------
        dict
            ``kind``, ``train``, ``val``, ``test`` (lists).
        """
        return {
            "kind": self.kind,
            "train": list(self.train),
            "val": list(self.val),
            "test": list(self.test),
        }

    def part_of(self, objects: np.ndarray, part: str) -> np.ndarray:
        """Which objects belong to one part of the split.

        Parameters
        ----------
        objects : (n,) ndarray of str
        part : str
            ``"train"``, ``"val"`` or ``"test"``.

        Returns
        -------
        (n,) bool ndarray
        """
        return np.isin(objects, list(getattr(self, part)))


def split_by_object(
    objects: Sequence[str], families: Sequence[str], *, seed: int = 0, fraction=(0.15, 0.15)
) -> Split:
    """Hold out object instances, family by family, so that categories overlap.

    A family with n >= 3 instances gives max(1, round(f·n)) to validation and to test; one
    with 2 gives one to test; one with 1 goes to training.

    Parameters
    ----------
    objects, families : sequence of str
        Object of each row and its family (repeats allowed).
    seed : int
        Seeds the shuffle within each family.
    fraction : (float, float)
        f of validation and of test.

    Returns
    -------
    Split

    Raises
    ------
    InputError
        When no family has two instances (nothing to test on).
    """
    by_family: dict[str, list[str]] = defaultdict(list)
    for o, f in sorted(set(zip(objects, families, strict=True))):
        by_family[f].append(o)
    rng = np.random.default_rng(seed)
    train, val, test = [], [], []
    for fam in sorted(by_family):
        names = list(by_family[fam])
        rng.shuffle(names)
        n = len(names)
        n_val = max(1, round(fraction[0] * n)) if n >= 3 else 0
        n_test = max(1, round(fraction[1] * n)) if n >= 2 else 0
        test += names[:n_test]
        val += names[n_test : n_test + n_val]
        train += names[n_test + n_val :]
    if not train or not test:
        raise InputError(
            "a split by object needs at least 2 instances of some family (e.g. knife:0 knife:1)"
        )
    return Split(tuple(sorted(train)), tuple(sorted(val)), tuple(sorted(test)), "object")


def split_by_family(
    objects: Sequence[str], families: Sequence[str], test_families: Sequence[str], *, seed=0
) -> Split:
    """Hold out whole families for test; validation takes instances of the remaining families.

    Parameters
    ----------
    objects, families : sequence of str
        Object of each row and its family.
    test_families : sequence of str
        Families of the test set.
    seed : int
        Seeds the validation draw (:func:`split_by_object` with no test fraction).

    Returns
    -------
    Split

    Raises
    ------
    InputError
        When a test family is not in the data, or nothing is left to train or test on.
    """
    pairs = sorted(set(zip(objects, families, strict=True)))
    known = {f for _, f in pairs}
    unknown = sorted(set(test_families) - known)
    if unknown:
        raise InputError(f"families {unknown} are not in the dataset; it holds {sorted(known)}")
    test = [o for o, f in pairs if f in set(test_families)]
    rest = [(o, f) for o, f in pairs if f not in set(test_families)]
    if not rest or not test:
        raise InputError("a split by family needs a family to test on and one to train on")
    inner = split_by_object(
        [o for o, _ in rest], [f for _, f in rest], seed=seed, fraction=(0.15, 0)
    )
    train = [o for o in inner.train] + list(inner.test)
    return Split(tuple(sorted(train)), inner.val, tuple(sorted(test)), "family")
