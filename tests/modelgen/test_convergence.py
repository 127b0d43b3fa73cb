"""Truncation error: the assumed-mode model converges to the continuum as n grows."""

from __future__ import annotations

import numpy as np
import pytest

import modelgen
from modelgen import load_geometry
import scipy.linalg as sla

from modelgen.continuum import continuum_reference, fe_frequencies_zeros, fe_matrices, output_row, quadratic_pairs
from modelgen.loader import load_with_shapes
from modelgen.modes import normalised, polynomial_shapes

from _helpers import assert_same_zeros


@pytest.fixture(scope="module")
def reference() -> object:
    return continuum_reference(load_geometry("paper-sim"), count=3)


def test_fe_reference_is_converged(reference) -> None:
    assert reference.frequency_error_hz.max() < 1e-5 * reference.natural_frequencies_hz.max()
    assert reference.zero_error[:4].max() < 1e-5 * np.abs(reference.zeros[:4]).max()


def test_damped_zeros_are_the_first_order_pencils() -> None:
    # near-non-hyperbolic (1 % Rayleigh damping), 12 elements, output at 0.6 L: the pairs of s^2 - a lam s - lam = 0
    # are the eigenvalues of the 2m x 2m first-order pencil of (s^2 M_z + s a K_z + K_z) v = 0, where that pencil is
    # well conditioned (a small mesh)
    g = load_geometry("near-non-hyperbolic")
    M, K, hub, _ = fe_matrices(g, 12)
    omega1 = np.sqrt(np.sort(sla.eigh(K, M, eigvals_only=True))[1])
    a = 2 * g.damping_ratio / omega1
    c = output_row(g, 12, 0.6 * g.length)
    pivot = int(np.argmax(np.abs(c)))
    rows, cols = [i for i in range(len(M)) if i != hub], [j for j in range(len(M)) if j != pivot]
    P = np.eye(len(M))[:, cols]
    P[pivot] = -c[cols] / c[pivot]
    Mz, Kz = M[rows] @ P, K[rows] @ P
    m = len(Mz)
    first_order = sla.eigvals(np.block([[np.zeros((m, m)), np.eye(m)], [-Kz, -a * Kz]]), np.block([[np.eye(m), np.zeros((m, m))], [np.zeros((m, m)), Mz]]))
    zeros = fe_frequencies_zeros(g, 12, 0.6 * g.length)[1]
    assert_same_zeros(zeros, first_order[np.isfinite(first_order)], rtol=1e-7)
    # no cancellation: a root far below |lam| keeps its digits (s = -1/a for a huge lam, s^2 ~ lam for a small one)
    big, small = quadratic_pairs(a, np.array([-1e16 + 0j])), quadratic_pairs(a, np.array([-1e-6 + 0j]))
    assert np.min(np.abs(big + 1 / a)) <= 1e-6 / a and np.allclose(np.sort_complex(small), np.sort_complex(np.sqrt(-1e-6 + 0j) * np.array([-1, 1])), rtol=1e-6)


def test_damped_finite_element_zeros_converge_with_the_mesh() -> None:
    # the four lowest zeros of the damped link on 48 and 96 elements agree to 1e-7 (measured 3e-8; the first-order
    # form's 2m x 2m pencil moved the lowest pair by 2.7e-7 between the two meshes: its conditioning grows with the
    # mesh's fastest modes)
    g = load_geometry("near-non-hyperbolic")
    coarse, fine = (fe_frequencies_zeros(g, n)[1][:4] for n in (48, 96))
    assert np.max(np.abs(coarse - fine) / np.abs(fine)) < 1e-7


@pytest.mark.slow
@pytest.mark.parametrize("family", ["clamped-mass", "clamped-free", "polynomial"])
def test_frequencies_are_ritz_upper_bounds_decreasing_with_n(family: str, reference) -> None:
    # Rayleigh-Ritz with nested bases: each frequency is above the exact one and falls as n grows.
    previous = None
    for n in (3, 5, 7):
        f = modelgen.load("paper-sim", modes=n, mode_shapes=family).natural_frequencies_hz[:3]
        # the FE values are themselves upper bounds, within their estimated error of the exact ones
        assert np.all(f >= reference.natural_frequencies_hz - reference.frequency_error_hz)
        if previous is not None:
            assert np.all(f <= previous * (1 + 1e-12))
        previous = f


@pytest.mark.slow
def test_families_converge_to_the_same_frequencies(reference) -> None:
    exact = reference.natural_frequencies_hz
    for family in ("clamped-mass", "polynomial"):
        f = modelgen.load("paper-sim", modes=8, mode_shapes=family).natural_frequencies_hz[:3]
        np.testing.assert_allclose(f, exact, rtol=2e-4, err_msg=family)


@pytest.mark.slow
def test_clamped_free_family_converges_slowly() -> None:
    # Clamped-free shapes have w''(L) = 0, but the payload inertia puts a moment on the tip:
    # every shape violates the true tip condition and the error falls only like ~1/n
    # (measured: 4.3 % at n = 6, 2.1 % at n = 12 for f1).
    ref = continuum_reference(load_geometry("paper-sim"), count=3).natural_frequencies_hz
    err = [
        np.abs(modelgen.load("paper-sim", modes=n, mode_shapes="clamped-free").natural_frequencies_hz[:3] / ref - 1)
        for n in (6, 12)
    ]
    assert np.all(err[1] < 0.6 * err[0])
    assert err[1].max() < 0.05


def test_six_modes_agree_with_continuum(reference) -> None:
    # Issue 2's acceptance: n = 6 within a fraction of a percent (first three frequencies, lowest zeros).
    m = modelgen.load("paper-sim", modes=6)
    np.testing.assert_allclose(m.natural_frequencies_hz[:3], reference.natural_frequencies_hz, rtol=2e-4)
    for z in m.zeros[:4]:
        assert np.min(np.abs(reference.zeros - z)) < 1e-3 * abs(z)


def test_zero_structure_kept_as_n_grows() -> None:
    # paper-sim: a purely imaginary pair and a real pair at the bottom of the spectrum for every n >= 2
    for n in (2, 4, 6):
        z = modelgen.load("paper-sim", modes=n).zeros[:4]
        assert np.sum(np.abs(z.real) < 1e-9 * np.abs(z)) == 2
        assert np.sum(np.abs(z.imag) < 1e-9 * np.abs(z)) == 2


def test_polynomial_basis_is_a_change_of_basis_of_the_monomials() -> None:
    # The model depends on the span only: monomials (x/L)^(j+1) and the Legendre-based basis agree.
    g = load_geometry("paper-sim").with_model(modes=4, mode_shapes="polynomial")
    mono = load_with_shapes(g, normalised(polynomial_shapes(4, g.length, monomial=True)))
    leg = modelgen.load(g)
    np.testing.assert_allclose(mono.natural_frequencies_hz, leg.natural_frequencies_hz, rtol=1e-10)
    assert_same_zeros(mono.zeros, leg.zeros, rtol=1e-9)
    assert mono.CAB == pytest.approx(leg.CAB, rel=1e-10)
