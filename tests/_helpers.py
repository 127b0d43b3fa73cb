"""Small assertions shared by tests."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import linear_sum_assignment


def assert_same_zeros(actual: ArrayLike, desired: ArrayLike, rtol: float) -> None:
    """Two sets of complex numbers agree, matched one-to-one (order-free), to ``rtol`` of the largest."""
    a = np.asarray(actual, dtype=complex)
    d = np.asarray(desired, dtype=complex)
    assert a.size == d.size, f"{a.size} values vs {d.size}"
    cost = np.abs(a[:, None] - d[None, :])
    rows, cols = linear_sum_assignment(cost)
    worst = cost[rows, cols].max(initial=0.0)
    scale = max(np.abs(d).max(initial=0.0), 1.0)
    assert worst <= rtol * scale, f"zeros differ by {worst:.3e} (> {rtol:g} x {scale:.3g}): {a} vs {d}"
