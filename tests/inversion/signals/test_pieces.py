"""Pieces is SciPy's PPoly, bit for bit, where a move uses it: values, derivatives, breakpoints, extrapolation."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
from scipy.interpolate import PPoly

from inversion.signals import pieces as pieces_module
from inversion.signals.pieces import Pieces
from inversion.signals.trajectory import smoothstep, stretched


def _pair(seed: int, degree: int, pieces: int) -> tuple[PPoly, Pieces]:
    rng = np.random.default_rng(seed)
    c = rng.normal(size=(degree + 1, pieces)) * 10.0 ** rng.uniform(-3, 3, size=(degree + 1, 1))
    x = np.cumsum(np.r_[rng.uniform(-1, 1), rng.uniform(0.05, 2.0, size=pieces)])
    return PPoly(c, x), Pieces(c, x)


@pytest.mark.parametrize("seed, degree, pieces", [(0, 0, 1), (1, 3, 1), (2, 5, 4), (3, 11, 1), (4, 7, 9), (5, 13, 3)])
def test_values_and_derivatives_are_ppoly_bit_for_bit(seed: int, degree: int, pieces: int) -> None:
    reference, ours = _pair(seed, degree, pieces)
    x = reference.x
    inside = np.linspace(x[0], x[-1], 997)
    at_breakpoints = np.r_[x, np.nextafter(x, -np.inf), np.nextafter(x, np.inf)]
    outside = np.r_[x[0] - 3.0, x[0] - 1e-9, x[-1] + 1e-9, x[-1] + 5.0]
    t = np.r_[inside, at_breakpoints, outside]
    for nu in range(degree + 3):  # beyond the degree: zero
        expected = reference.derivative(nu)(t) if nu else reference(t)
        got = ours.derivative(nu)(t) if nu else ours(t)
        np.testing.assert_array_equal(got, expected, err_msg=f"derivative {nu}")
        # a few times at once take the whole-array path: the same bits
        few = t[::40]
        assert few.size <= pieces_module._FEW < t.size
        np.testing.assert_array_equal(ours.derivative(nu)(few), expected[::40], err_msg=f"derivative {nu}, few times")
    # any shape of times, as PPoly
    grid = t[:24].reshape(2, 3, 4)
    np.testing.assert_array_equal(ours(grid), reference(grid))
    assert ours(np.float64(x[0])).shape == ()


def test_nan_time_gives_nan() -> None:
    reference, ours = _pair(7, 5, 3)
    assert np.isnan(ours(np.array([np.nan]))[0]) and np.isnan(reference(np.array([np.nan]))[0])


def test_bad_shapes_are_refused() -> None:
    with pytest.raises(ValueError, match="breakpoints"):
        Pieces(np.ones((3, 2)), [0.0, 1.0])
    with pytest.raises(ValueError, match="increasing"):
        Pieces(np.ones((3, 2)), [0.0, 2.0, 1.0])


def test_smoothstep_and_its_stretch_are_the_ppoly_they_were() -> None:
    # the paper's simulation move (Eq. (37)): its values and every derivative as PPoly gave them before Pieces
    for move in (smoothstep(1.57, 5.5, 5), stretched(smoothstep(0.5, 0.6, 2), 0.8371), smoothstep(0.3, 0.1, 2, start=0.25)):
        reference = PPoly(move.ppoly.c, move.ppoly.x)
        t = np.linspace(move.t0 - 0.1, move.tf + 0.1, 1201)
        for k in range(move.ppoly.c.shape[0] + 1):
            np.testing.assert_array_equal(move.ppoly.derivative(k)(t), reference.derivative(k)(t) if k else reference(t))


def test_a_smoothstep_run_imports_no_scipy_interpolate() -> None:
    # the point of Pieces: ``sflm invert paper-sim`` (a smoothstep move) without scipy.interpolate's 0.15 s
    code = ("import sys; from inversion.signals.trajectory import trajectory_from_spec; "
            "m = trajectory_from_spec('smoothstep:0.5:0.6:2'); m.derivative([0.1, 0.3], 4); "
            "print('scipy.interpolate' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert out == "False"
