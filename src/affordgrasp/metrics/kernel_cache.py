"""The numba cache locator under its former name: :mod:`affordgrasp.kernel_cache`.

The locator serves the kernels of every stage (hands, grasp, metrics, vision), so it lives
with the package's infrastructure; this name is the same module object, so that its state
(the installed locator, the light-loading switch) is one.
"""

from __future__ import annotations

import sys

from .. import kernel_cache as _kernel_cache

sys.modules[__name__] = _kernel_cache
