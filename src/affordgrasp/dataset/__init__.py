"""Data at scale (conventions: Datasets): the per-sample schema, generation, reading, argmax.

* ``schema``: the columns of a sample row (conventions: Sample columns);
* ``generate``: sharded, deterministic, resumable Parquet datasets (``layout`` on disk,
  ``engines`` for local processes or Ray, ``card`` for the dataset card);
* ``reading``: a dataset directory as one Arrow dataset;
* ``best``: brute-force argmax of a task over a dataset.

See docs/dataset.md.
"""
