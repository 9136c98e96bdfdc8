"""Brute force over grasps x use points: cut grasps on a dagger from 400 simulations.

The third Python example of the README; run it with ``python examples/best_pairs.py``.
"""

from affordgrasp.search.pairs import PairSearchSettings, best_pairs

settings = PairSearchSettings("cut", grasps=400, uses=3000, seed=0, top=3)
found = best_pairs("dagger", settings)
print(found.candidates, found.table["value"].to_pylist())  # pairs with F_T > -inf; top 3
