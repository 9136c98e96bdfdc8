"""Grids of grasp images (affordgrasp.viz.grid)."""

import numpy as np

from affordgrasp.viz.grid import LABEL_PX, TITLE_PX, grid_image


def test_cells_land_in_their_place():
    size = 64
    colours = [[(255, 0, 0), (0, 255, 0), (0, 0, 255)], [(255, 255, 0), (0, 255, 255), None]]
    cells = [
        [None if c is None else np.full((size, size, 3), c, dtype=np.uint8) for c in row]
        for row in colours
    ]
    cells[1][2] = "nothing here"
    image = grid_image(cells, row_labels=["a", "b"], col_labels=["x", "y", "z"], title="t")
    top = TITLE_PX + LABEL_PX
    assert image.shape[1] == LABEL_PX + 3 * size
    assert image.shape[0] > top + 2 * size
    for i, row in enumerate(colours):
        for j, c in enumerate(row):
            y = top + i * size + size // 2
            x = LABEL_PX + j * size + size // 2
            if c is None:
                assert tuple(image[y, x]) == (255, 255, 255) or image[y, x].min() > 60
            else:
                np.testing.assert_array_equal(
                    image[y - 20 : y + 20, x - 20 : x + 20], np.full((40, 40, 3), c)
                )
