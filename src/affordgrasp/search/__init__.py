"""Searching for the best grasps: every ranking, top-k scan and optimiser of the package.

* :mod:`~affordgrasp.search.ranking`: :class:`TopRows` and :func:`top_indices`, the one ranker
  (highest score first, −∞ and NaN never rank, ties by keys);
* :mod:`~affordgrasp.search.best`: :func:`scan_top`, the one top-k scan over tables and
  datasets (ties: the object named first, then the lower sample, then the lower seed), behind
  :func:`best_grasps` (``affordgrasp best``) and :func:`top_grasps` (``affordgrasp show``);
* :mod:`~affordgrasp.search.cem`: :func:`cem_maximize` (the cross-entropy method over the
  (p0, d) box) and :func:`cem_search` (restarts sharing a budget, then a refinement);
* :mod:`~affordgrasp.search.guidance`: how close an infeasible grasp came to a usable one;
* :mod:`~affordgrasp.search.use_points`: the use points a pair search scores;
* :mod:`~affordgrasp.search.pairs`: grasps × use points, by brute force (:func:`best_pairs`) or
  by the cross-entropy method (:func:`optimize_pairs`), with one parameter list
  (:class:`PairSearchSettings`) and one result (:class:`PairSearch`);
* :mod:`~affordgrasp.search.optimize`: :func:`optimize`, CEM against uniform random sampling
  on a simulation engine (``affordgrasp optimize``).

Every search ranks rows by :func:`affordgrasp.robust.task_scores` (F_T, or the robust score).
"""
