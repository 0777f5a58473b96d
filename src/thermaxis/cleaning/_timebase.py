"""Nanosecond time stamps shared by the cleaning steps."""

from __future__ import annotations

import numpy as np
import pandas as pd

__all__ = [
    "MAD_TO_SIGMA",
]

# Scales a median absolute deviation to the standard deviation of normal noise.
MAD_TO_SIGMA = 1.4826
_NS = 1_000_000_000


# ----------------------------------------------------------------------------- helpers


def _as_ns(times) -> np.ndarray:
    """Naive datetimes as int64 nanoseconds (any input resolution)."""
    return np.asarray(pd.to_datetime(times), dtype="datetime64[ns]").astype(np.int64)


def _timestamp_ns(value) -> int:
    return int(pd.Timestamp(value).as_unit("ns").value)


def _iso(ns: int) -> str:
    return pd.Timestamp(int(ns)).isoformat()
