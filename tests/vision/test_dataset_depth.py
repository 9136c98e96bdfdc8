"""generate --depth: images stored with the samples, equal to render_depth, resumable."""

import numpy as np
import pyarrow.parquet as pq

from affordgrasp.dataset.generate import generate
from affordgrasp.dataset.reading import read_dataset
from affordgrasp.vision import depth_to_mm, render_depth
from affordgrasp.vision.depth import decode_depth_column


def test_generate_with_depth_stores_the_rendered_images(tmp_path):
    out = tmp_path / "ds"
    summary = generate(["hammer:1"], 20, out, seed=2, workers=1, depth=True, shard_size=8)
    assert summary.complete
    table = read_dataset(out, columns=["p0", "depth_mm"])
    p0 = np.asarray(table.column("p0").combine_chunks().flatten()).reshape(-1, 6)
    stored = decode_depth_column(table.column("depth_mm"))
    expected = depth_to_mm(render_depth("hammer:1", p0))
    np.testing.assert_array_equal(depth_to_mm(stored), expected)
    meta = pq.read_metadata(next(out.glob("part-*.parquet")))
    assert meta.num_rows == 8
    # a resume is a no-op; a run without --depth refuses the directory
    again = generate(["hammer:1"], 20, out, seed=2, workers=1, depth=True, shard_size=8)
    assert again.shards_written == 0
    import pytest

    from affordgrasp.errors import DatasetError

    with pytest.raises(DatasetError, match="depth"):
        generate(["hammer:1"], 20, out, seed=2, workers=1, shard_size=8)
