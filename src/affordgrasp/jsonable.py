"""Results as JSON-ready data: numbers, arrays and nested containers, inf and NaN spelled out.

Every JSON document the package writes (``--json`` output, reports, cards) goes through
:func:`to_jsonable`, so that NaN and ±inf, which JSON lacks, read the same everywhere.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["to_jsonable"]


def to_jsonable(value):
    """Numbers, arrays and nested containers as JSON; inf/NaN as the strings JSON lacks.

    Parameters
    ----------
    value : object

    Returns
    -------
    object
        dicts, lists, ints, floats and strs only; NaN becomes None, ±inf ``"inf"``/``"-inf"``.
    """
    if isinstance(value, dict):
        return {str(k): to_jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [to_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return to_jsonable(value.tolist())
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        if math.isnan(v):
            return None
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return v
    return value
