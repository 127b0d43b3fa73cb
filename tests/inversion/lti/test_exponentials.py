"""The closed form's kernels keep full accuracy through their removable singularities."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest

from inversion.lti.exponentials import exp_difference, exp_integrals, phi1, phi2

mpmath.mp.dps = 40
X = np.r_[0.0, 1e-300, 1e-12, -3e-9, 1e-5, -0.05, 0.1999, -0.2, 0.2001, 0.7, -3.0, -12.0, 8.0, -40.0]


def ref_phi1(x: float) -> float:
    with mpmath.workdps(40):
        return 1.0 if x == 0 else float(mpmath.expm1(mpmath.mpf(x)) / mpmath.mpf(x))


def ref_phi2(x: float) -> float:
    if x == 0:
        return 0.5
    with mpmath.workdps(700):  # expm1(x) - x cancels ~2|log10 x| digits
        m = mpmath.mpf(x)
        return float((mpmath.expm1(m) - m) / m**2)


def test_phi_kernels_against_40_digits() -> None:
    E, p1, p2 = exp_integrals(X)
    r1 = np.array([ref_phi1(x) for x in X])
    r2 = np.array([ref_phi2(x) for x in X])
    np.testing.assert_allclose(p1, r1, rtol=2e-15)
    np.testing.assert_allclose(p2, r2, rtol=1e-14)  # (p1 - 1)/x beyond 0.2: ~10 ulp at worst
    np.testing.assert_allclose(phi1(X), r1, rtol=2e-15)
    np.testing.assert_allclose(phi2(X), r2, rtol=1e-14)
    np.testing.assert_array_equal(E, np.exp(X))


@pytest.mark.parametrize(
    "a,b",
    [(-3.0, -3.0), (-3.0, -3.0 + 1e-13), (-65.26, -65.26 + 1e-7), (0.0, -65.26), (-8.4, -0.76 + 56.3j), (-1.0, -1.0 + 1e-9j), (0.0, 1e-3j)],
)
def test_exp_difference_against_40_digits(a: complex, b: complex) -> None:
    s = np.array([0.0, 1e-6, 0.01, 0.3, 1.1])
    got = exp_difference(a, b, s)
    for value, si in zip(got, s):
        with mpmath.workdps(40):  # the reference at 40 digits whatever another test left mpmath's precision at
            A, B, S = mpmath.mpc(a), mpmath.mpc(b), mpmath.mpf(float(si))
            ref = S * mpmath.exp(B * S) if A == B else (mpmath.exp(A * S) - mpmath.exp(B * S)) / (A - B)
            ref = complex(ref)
        assert abs(value - ref) <= 1e-14 * max(abs(ref), 1e-300) + 1e-300
