"""Learning task metrics from the camera-in-hand view (conventions: Vision, paper §III-B, §IV-D).

* ``targets``: what is learned (``viable``, ``hold_effort_sum``, any column, ``task:NAME``);
* ``data``: rows, depth images and splits by object instance or family from a dataset;
* ``models``: the CNN, PointNet full/slim and pose-only networks (late fusion of p0, d);
* ``training``: Adam, 1/epoch decay, early stopping, seeded and deterministic;
* ``io``: safetensors model files with their JSON config (never pickle);
* ``evaluation``: MSE, comparison accuracy, GMS, precision–recall/AP (numpy only);
* ``api``: train / predict / evaluate over datasets; ``plots``: PNG figures.

PyTorch is optional: ``pip install "affordgrasp[learn]"``. Importing this package does not
import torch; the functions that need it raise a clear error naming the extra. See
docs/learning.md.
"""

from .torch_support import INSTALL_HINT, require_torch

__all__ = ["INSTALL_HINT", "require_torch"]
