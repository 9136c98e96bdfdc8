"""Data at scale (SPEC §2.6): the per-sample schema, generation, reading, argmax.

* ``schema``: the columns of a sample row (SPEC §2.9);
* ``generate``: sharded, deterministic, resumable Parquet datasets (``layout`` on disk,
  ``engines`` for local processes or Ray, ``card`` for the dataset card);
* ``reading``: a dataset directory as one Arrow dataset;
* ``best``: brute-force argmax of a task over a dataset.

See docs/dataset.md.
"""
