"""Mode shapes: frequency roots, cancellation-free evaluation, modal integrals."""

from __future__ import annotations

import mpmath
import numpy as np
import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

from modelgen import load_geometry
from modelgen.continuum import fe_matrices
from modelgen.geometry import Geometry
from modelgen.modes import frequency_roots, modal_constants, mode_shapes, polynomial_shapes
import scipy.linalg as sla


def test_textbook_clamped_free_roots() -> None:
    # Textbook cantilever: bL = 1.87510, 4.69409, 7.85476 (e.g. Blevins, Formulas for
    # Natural Frequency and Mode Shape, table 8-1), to 1e-6.
    np.testing.assert_allclose(frequency_roots(3), [1.875104, 4.694091, 7.854757], atol=1e-6)


def test_clamped_free_high_roots_approach_asymptote() -> None:
    # (2j - 1) pi / 2 is exact to 1e-6 beyond the 6th root (cosh bL cos bL = -1).
    roots = frequency_roots(12)
    j = np.arange(7, 13)
    np.testing.assert_allclose(roots[6:], (2 * j - 1) * np.pi / 2, atol=1e-6)
    assert np.all(np.diff(roots) > 2.8)


def test_paper_sim_roots() -> None:
    # docs/method.md section 7 (independent implementation): bL = 1.79449, 3.28133.
    g = load_geometry("paper-sim")
    roots = frequency_roots(2, g.payload_mass_ratio, g.payload_inertia_ratio)
    np.testing.assert_allclose(roots, [1.79449, 3.28133], rtol=1e-5)


def _clamped_fe_frequencies(mu: float, kappa: float, count: int) -> np.ndarray:
    """bL of a clamped link with tip payload from 200 finite elements (independent)."""
    g = Geometry(name="fe", length=1.0, flexural_rigidity=1.0, linear_density=1.0, hub_inertia=0.0,
                 payload_mass=mu, payload_inertia=kappa)
    M, K, hub, _tip = fe_matrices(g, 200)
    keep = [i for i in range(M.shape[0]) if i != hub]  # clamp the root slope as well
    w2 = sla.eigh(K[np.ix_(keep, keep)], M[np.ix_(keep, keep)], eigvals_only=True)[:count]
    return np.sqrt(np.sqrt(w2))  # omega = (bL)^2 with EI = rho = L = 1


@given(
    st.one_of(st.just(0.0), st.floats(1e-3, 50.0)),
    st.one_of(st.just(0.0), st.floats(1e-4, 5.0)),
)
def test_roots_match_finite_elements_no_root_skipped(mu: float, kappa: float) -> None:
    roots = frequency_roots(6, mu, kappa)
    fe = _clamped_fe_frequencies(mu, kappa, 6)
    np.testing.assert_allclose(roots, fe, rtol=2e-6)


def test_roots_distinct_for_extreme_payloads() -> None:
    for mu, kappa in [(0.0, 0.0), (1e5, 1e4), (1e-4, 1e3), (100.0, 0.0)]:
        roots = frequency_roots(20, mu, kappa)
        assert roots.size == 20 and np.all(np.diff(roots) > 0.05)


def _mp_shape(beta: float, mu: float, kappa: float, xs: np.ndarray) -> np.ndarray:
    """The naive formula in 60-digit arithmetic: the reference for the cancellation-free one."""
    mpmath.mp.dps = 60

    def det(b: mpmath.mpf) -> mpmath.mpf:
        k3, m = kappa * b**3, mu * b
        ch, sh, c, s = mpmath.cosh(b), mpmath.sinh(b), mpmath.cos(b), mpmath.sin(b)
        return 1 + ch * c + m * (c * sh - s * ch) - k3 * (c * sh + s * ch) - k3 * m * (ch * c - 1)

    b = mpmath.findroot(det, mpmath.mpf(beta))
    k3 = kappa * b**3
    a1 = mpmath.cosh(b) + mpmath.cos(b) - k3 * (mpmath.sinh(b) + mpmath.sin(b))
    a2 = mpmath.sinh(b) + mpmath.sin(b) - k3 * (mpmath.cosh(b) - mpmath.cos(b))
    s = a1 / a2

    def phi(x: mpmath.mpf) -> mpmath.mpf:
        return mpmath.cosh(b * x) - mpmath.cos(b * x) - s * (mpmath.sinh(b * x) - mpmath.sin(b * x))

    norm = mpmath.sqrt(mpmath.quad(lambda x: phi(x) ** 2, mpmath.linspace(0, 1, 8)))
    return np.array([float(phi(mpmath.mpf(float(x))) / norm) for x in xs])


@pytest.mark.parametrize("family,mu,kappa", [("clamped-free", 0.0, 0.0), ("clamped-mass", 0.4, 0.02)])
def test_high_modes_are_cancellation_free(family: str, mu: float, kappa: float) -> None:
    g = Geometry(name="t", length=1.0, flexural_rigidity=1.0, linear_density=1.0, hub_inertia=0.0,
                 payload_mass=mu, payload_inertia=kappa, modes=12, mode_shapes=family)
    shapes = mode_shapes(g)
    xs = np.linspace(0, 1, 9)
    values = shapes(xs)
    for j in (3, 7, 11):  # modes 4, 8, 12: bL up to ~36, where the naive form loses ~15 digits
        ref = _mp_shape(float(shapes.betas[j]), mu, kappa, xs)
        # sign convention phi''(0) > 0 is that of the naive formula
        np.testing.assert_allclose(values[j], ref, atol=2e-12)


def test_clamped_mass_modes_are_orthogonal() -> None:
    # Eigenfunctions of the clamped link with payload are orthogonal in the mass inner product
    # that includes the payload, and in the stiffness one: M_d and K_d are diagonal.
    g = load_geometry("paper-exp").with_model(modes=8)
    c = modal_constants(mode_shapes(g))
    Md = g.linear_density * c.N + g.payload_mass * np.outer(c.phi_L, c.phi_L) + g.payload_inertia * np.outer(c.dphi_L, c.dphi_L)
    off = Md - np.diag(np.diag(Md))
    assert np.abs(off).max() < 1e-11 * np.abs(Md).max()
    offG = c.G - np.diag(np.diag(c.G))
    assert np.abs(offG).max() < 1e-11 * np.abs(c.G).max()


def test_quadrature_converged() -> None:
    g = load_geometry("paper-sim").with_model(modes=12)
    shapes = mode_shapes(g)
    base = modal_constants(shapes)
    fine = modal_constants(shapes, nodes=2 * base.nodes)
    for name in ("S", "N", "G"):
        a, b = getattr(base, name), getattr(fine, name)
        assert np.abs(a - b).max() <= 1e-13 * np.abs(b).max(), name


def test_polynomial_integrals_exact() -> None:
    # Closed form by SymPy: int x (x/L)^(j+1), int (x/L)^(i+j+2), int phi_i'' phi_j''.
    L = 0.8
    c = modal_constants(polynomial_shapes(4, L, monomial=True))
    x = sp.Symbol("x")
    Ls = sp.Rational(4, 5)
    phi = [(x / Ls) ** (j + 1) for j in range(1, 5)]
    S = [float(sp.integrate(x * f, (x, 0, Ls))) for f in phi]
    N = [[float(sp.integrate(f * h, (x, 0, Ls))) for h in phi] for f in phi]
    G = [[float(sp.integrate(f.diff(x, 2) * h.diff(x, 2), (x, 0, Ls))) for h in phi] for f in phi]
    # exact up to the round-off of a ~50-term quadrature sum (a few 1e-16 per term)
    np.testing.assert_allclose(c.S, S, rtol=5e-14)
    np.testing.assert_allclose(c.N, N, rtol=5e-14)
    np.testing.assert_allclose(c.G, G, rtol=5e-14)
    np.testing.assert_allclose(c.phi_L, 1.0, rtol=1e-15)
    np.testing.assert_allclose(c.dphi_L, [(j + 1) / L for j in range(1, 5)], rtol=1e-14)


def test_derivatives_consistent_with_finite_differences() -> None:
    g = load_geometry("paper-sim").with_model(modes=5)
    shapes = mode_shapes(g)
    x = np.linspace(0.1, 0.9, 5) * g.length
    h = 1e-4
    for k in range(1, 4):
        fd = (shapes(x + h, k - 1) - shapes(x - h, k - 1)) / (2 * h)
        np.testing.assert_allclose(shapes(x, k), fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())


def test_clamped_root_conditions() -> None:
    g = load_geometry("paper-sim").with_model(modes=6)
    for family in ("clamped-mass", "clamped-free", "polynomial"):
        shapes = mode_shapes(g, family=family)
        assert np.abs(shapes(np.array([0.0]), 0)).max() < 1e-13
        assert np.abs(shapes(np.array([0.0]), 1)).max() < 1e-12


def test_polynomial_family_spans_the_monomials() -> None:
    # phi_j = (x/L)^2 P_{j-1}(2x/L - 1), normalised: orthonormal-free but spanning x^2..x^(n+1)
    L = 0.8
    g = Geometry(name="p", length=L, flexural_rigidity=1.0, linear_density=1.0, hub_inertia=0.0,
                 modes=5, mode_shapes="polynomial")
    shapes = mode_shapes(g)
    c = modal_constants(shapes)
    np.testing.assert_allclose(np.diag(c.N), L, rtol=1e-13)
    x = np.linspace(0, L, 40)
    mono = np.array([(x / L) ** (j + 1) for j in range(1, 6)])
    coef, *_ = np.linalg.lstsq(mono.T, shapes(x).T, rcond=None)
    np.testing.assert_allclose(mono.T @ coef, shapes(x).T, atol=1e-12)


def test_kept_roots_are_checked_not_trusted(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # issue 56: the frequency equation's roots are kept with the compiled models (a load finds them again without
    # scipy.optimize); a kept file is no authority: a root outside its bracket, or off the sign change, is found again
    import json

    from modelgen.modes import _roots_file, frequency_roots

    monkeypatch.setenv("SFLM_CACHE_DIR", str(tmp_path))
    exact = frequency_roots(3, 0.3, 0.01)  # found, and kept
    path, key = _roots_file(3, 0.3, 0.01)
    assert json.loads(path.read_text())["roots"] == exact.tolist()
    assert np.array_equal(frequency_roots(3, 0.3, 0.01), exact)  # read back
    for bad in ([1.0, 2.0, 3.0], [exact[0] * (1 + 1e-9), exact[1], exact[2]], "roots"):
        path.write_text(json.dumps({"key": key, "roots": bad}))
        assert np.array_equal(frequency_roots(3, 0.3, 0.01), exact), bad


def test_a_load_from_the_cache_needs_no_optimiser() -> None:
    import subprocess
    import sys

    code = "import sys, modelgen; modelgen.load('paper-sim'); print('scipy.optimize' in sys.modules)"
    subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)  # the first: compiled and kept
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True)
    assert out.stdout.strip() == "False"
