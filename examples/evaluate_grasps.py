"""Simulate 200 grasps of a mug, compute their metrics and score the task "pick".

The first Python example of the README; run it with ``python examples/evaluate_grasps.py``.
"""

import affordgrasp as ag

mug = ag.load_object("mug")  # a family, "mug:7" or a mesh path
result = ag.evaluate(mug, samples=200, seed=0)  # simulate + metric vector, one row per grasp
scores = result.scores("pick")  # (200,) float: p_pick, the probability that the grasp holds it
best = result.table.take([int(scores.argmax())])  # result.table is a pyarrow.Table
print(best["status"][0], best["hold_effort_px"][0], best["p_pick"][0])
