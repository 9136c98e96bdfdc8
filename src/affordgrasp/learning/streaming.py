"""Training batches streamed from a sharded dataset (conventions: Vision): the images are
never all in memory.

The rows of the training objects are known (their object, sample, p0, d and target: about
100 bytes a row); their depth images (3–8 kB a row stored, 32 kB decoded) are read, or
rendered, shard by shard every epoch. Each epoch draws the same rows as training in memory
does (a classifier: every positive and as many negatives, redrawn each epoch, seeded by
(seed, epoch)), reads the dataset in chunks keeping the drawn rows, and shuffles them in a
buffer of ``buffer_rows`` before cutting batches: memory is that of the buffer, whatever the
dataset's size.
"""

from __future__ import annotations

import numpy as np

from ..dataset.handle import Dataset
from .data import Samples, balanced_indices, reads_depth
from .targets import Target
from .training import Inputs


class StreamedEpochs:
    """The training batches of each epoch, read from the dataset (``train_model``'s
    ``epoch_batches``).

    Parameters
    ----------
    dataset : Dataset
        The dataset the rows come from (opened by the caller).
    config : dict
        The model config (what inputs to build).
    train : Samples
        The training rows, without depth images.
    batch_size : int
        Rows per batch.
    buffer_rows : int
        Rows shuffled together before batches are cut (memory: about 35 kB a row).
    sensor : SensorModel, optional
        Apply a depth sensor model to the images
        (:func:`~affordgrasp.learning.data.sensed_depth_mm`).
    chunk_rows : int
        Rows read from the dataset at a time.
    """

    def __init__(
        self,
        dataset: Dataset,
        config: dict,
        train: Samples,
        *,
        batch_size: int,
        buffer_rows: int = 4096,
        sensor=None,
        chunk_rows: int = 4096,
    ):
        self.dataset = dataset
        self.config = config
        self.train = train
        self.batch_size = int(batch_size)
        self.buffer_rows = max(int(buffer_rows), self.batch_size)
        self.sensor = sensor
        self.chunk_rows = int(chunk_rows)
        self.target = Target.from_dict(config["target"])
        self.needs_depth = reads_depth(config)
        self._index = {
            (str(o), int(s)): i
            for i, (o, s) in enumerate(zip(train.object, train.sample, strict=True))
        }
        self.max_buffered = 0

    def rows_of_epoch(self, epoch: int, seed: int) -> np.ndarray:
        """Indices into ``train`` of the rows an epoch trains on.

        Parameters
        ----------
        epoch : int
            1-based.
        seed : int
            The training seed.

        Returns
        -------
        (k,) int64 ndarray
            Sorted.
        """
        if self.target.kind != "classification":
            return np.arange(len(self.train))
        rng = np.random.default_rng(np.random.SeedSequence([seed, epoch, 1]))
        return balanced_indices(self.train.y, seed=int(rng.integers(2**31)))

    def __call__(self, epoch: int, seed: int):
        """The batches of one epoch and how many there are.

        Parameters
        ----------
        epoch, seed : int
            As for :meth:`rows_of_epoch`.

        Returns
        -------
        batches : iterator of (Inputs, (b,) int ndarray, torch.Tensor)
            Inputs of a buffer, the batch's positions in it, and their targets ([0, 1]).
        n_batches : int
        """
        rows = self.rows_of_epoch(epoch, seed)
        per_buffer = []  # the number of rows of each full buffer, to count the batches
        n = len(rows)
        while n > 0:
            per_buffer.append(min(n, self.buffer_rows))
            n -= self.buffer_rows
        n_batches = sum(-(-k // self.batch_size) for k in per_buffer)
        return self._batches(rows, epoch, seed), n_batches

    def _batches(self, rows: np.ndarray, epoch: int, seed: int):
        from .torch_support import require_torch

        torch = require_torch()
        wanted = np.zeros(len(self.train), dtype=bool)
        wanted[rows] = True
        rng = np.random.default_rng(np.random.SeedSequence([seed, epoch, 2]))
        buffer: list[Samples] = []
        buffered = 0
        for part in self._chunks(wanted):
            buffer.append(part)
            buffered += len(part)
            while buffered >= self.buffer_rows:
                merged = _concat(buffer)
                head = merged.take(np.arange(self.buffer_rows))
                rest = merged.take(np.arange(self.buffer_rows, len(merged)))
                buffer, buffered = ([rest] if len(rest) else []), len(rest)
                yield from self._cut(head, rng, torch)
        if buffered:
            yield from self._cut(_concat(buffer), rng, torch)

    def _cut(self, samples: Samples, rng, torch):
        self.max_buffered = max(self.max_buffered, len(samples))
        inputs = Inputs(self.config, samples)
        y = torch.from_numpy(self.target.normalise(samples.y))
        order = rng.permutation(len(samples))
        for i in range(0, len(order), self.batch_size):
            idx = order[i : i + self.batch_size]
            yield inputs, idx, y[idx]

    def _chunks(self, wanted: np.ndarray):
        """The wanted training rows, chunk by chunk, with their depth images."""
        from ..vision.depth import decode_depth_column, depth_to_mm
        from .data import render_samples_depth, sensed_depth_mm

        stored = self.dataset.depth
        columns = ["object", "sample"] + (["depth_mm"] if stored and self.needs_depth else [])
        objects = sorted(set(self.train.object.tolist()))
        for batch in self.dataset.batches(
            columns=columns, objects=objects, batch_size=self.chunk_rows
        ):
            names = batch.column(0).to_pylist()
            ids = batch.column(1).to_numpy()
            pos, at = [], []
            for j, (o, s) in enumerate(zip(names, ids, strict=True)):
                i = self._index.get((o, int(s)))
                if i is not None and wanted[i]:
                    pos.append(j)
                    at.append(i)
            if not at:
                continue
            part = self.train.take(np.asarray(at))
            if self.needs_depth:
                if stored:
                    images = decode_depth_column(batch.column(2).take(np.asarray(pos)))
                    part.depth_mm = depth_to_mm(images)
                else:
                    part.depth_mm = render_samples_depth(part, self.dataset)
                if self.sensor is not None:
                    part.depth_mm = sensed_depth_mm(part, self.sensor)
            yield part


def _concat(parts: list[Samples]) -> Samples:
    if len(parts) == 1:
        return parts[0]
    depth = None if parts[0].depth_mm is None else np.concatenate([p.depth_mm for p in parts])
    return Samples(
        np.concatenate([p.object for p in parts]),
        np.concatenate([p.family for p in parts]),
        np.concatenate([p.sample for p in parts]),
        np.concatenate([p.p0 for p in parts]),
        np.concatenate([p.use_dir for p in parts]),
        np.concatenate([p.y for p in parts]),
        depth,
        dict(parts[0].meta),
    )
