"""The linear model of the paper's links: reference values, zeros, invariances."""

from __future__ import annotations

import control
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import modelgen
from modelgen import load_geometry
from modelgen.loader import load_with_shapes
from modelgen.modes import mode_shapes

from _helpers import assert_same_zeros


@pytest.fixture(scope="module")
def sim() -> modelgen.Model:
    return modelgen.load("paper-sim")


def test_paper_sim_reference_values(sim: modelgen.Model) -> None:
    # docs/method.md section 7, independent implementation (clamped-mass modes, n = 2), 1e-4 relative.
    np.testing.assert_allclose(sim.shapes.betas, [1.79449, 3.28133], rtol=1e-4)
    np.testing.assert_allclose(sim.natural_frequencies_hz, [6.6166, 24.1431], rtol=1e-4)
    real = np.sort(sim.zeros[np.abs(sim.zeros.imag) < 1e-9].real)
    imag = np.sort(sim.zeros[np.abs(sim.zeros.real) < 1e-9].imag)
    np.testing.assert_allclose(real, [-65.261, 65.261], rtol=1e-4)
    np.testing.assert_allclose(imag, [-56.314, 56.314], rtol=1e-4)
    assert sim.CAB == pytest.approx(-4.01669, rel=1e-4)
    assert sim.n_unstable == 3  # the paper counts 3: +61.25 and the imaginary pair
    assert sim.internal_dynamics == "non-hyperbolic"


def test_paper_exp_reference_values() -> None:
    # docs/method.md section 7: n = 1 zeros ±232.1; n = 2 second frequency 52.94 Hz. The values
    # are quoted to 4 digits: the tolerance is half a unit of their last digit.
    exp = modelgen.load("paper-exp")
    np.testing.assert_allclose(np.sort(exp.zeros.real), [-232.1, 232.1], atol=0.05)
    assert exp.n_unstable == 1 and exp.internal_dynamics == "hyperbolic"
    exp2 = modelgen.load("paper-exp", modes=2)
    assert exp2.natural_frequencies_hz[1] == pytest.approx(52.94, abs=0.005)


@pytest.mark.parametrize(
    "name,kind,unstable",
    [("hyperbolic", "hyperbolic", 2), ("near-non-hyperbolic", "near-non-hyperbolic", 1), ("paper-sim", "non-hyperbolic", 3)],
)
def test_preset_classification(name: str, kind: str, unstable: int) -> None:
    m = modelgen.load(name)
    assert m.internal_dynamics == kind
    assert m.n_unstable == unstable


def test_state_space_structure(sim: modelgen.Model) -> None:
    n1 = sim.n + 1
    assert sim.C_out @ sim.B == pytest.approx(0.0, abs=1e-14)
    assert sim.C_out @ sim.A @ sim.B == pytest.approx(sim.CAB, rel=1e-12)
    np.testing.assert_allclose(sim.T @ sim.Tinv, np.eye(2 * n1), atol=1e-13)
    np.testing.assert_allclose(sim.CA2, sim.C_out @ sim.A @ sim.A, rtol=1e-12)
    np.testing.assert_allclose(sim.M, sim.M.T, rtol=1e-15)
    assert np.all(np.linalg.eigvalsh(sim.M) > 0)


def test_zeros_agree_with_python_control(sim: modelgen.Model) -> None:
    sys = control.ss(sim.A, sim.B.reshape(-1, 1), sim.C_out.reshape(1, -1), 0)
    assert_same_zeros(sim.zeros, control.zeros(sys), rtol=1e-9)


def test_zeros_are_poles_of_inverse_system(sim: modelgen.Model) -> None:
    # Y(s)/tau(s) = C (sI - A)^-1 B vanishes at every zero.
    for z in sim.zeros:
        G = sim.C_out @ np.linalg.solve(z * np.eye(sim.A.shape[0]) - sim.A, sim.B)
        scale = np.abs(sim.C_out @ np.linalg.solve((abs(z) + 1) * np.eye(sim.A.shape[0]) - sim.A, sim.B))
        assert abs(G) < 1e-9 * scale


@given(st.lists(st.floats(0.05, 20.0) | st.floats(-20.0, -0.05), min_size=2, max_size=2))
def test_invariant_to_mode_shape_scaling(factors: list[float]) -> None:
    g = load_geometry("paper-sim")
    base = load_with_shapes(g, mode_shapes(g))
    scaled = load_with_shapes(g, mode_shapes(g).scaled(factors))
    np.testing.assert_allclose(scaled.natural_frequencies_hz, base.natural_frequencies_hz, rtol=1e-10)
    assert_same_zeros(scaled.zeros, base.zeros, rtol=1e-10)
    assert scaled.CAB == pytest.approx(base.CAB, rel=1e-10)


def test_damping_matrix_is_rayleigh() -> None:
    m = modelgen.load("near-non-hyperbolic")
    omega_1 = 2 * np.pi * m.natural_frequencies_hz[0]
    np.testing.assert_allclose(m.C, 2 * 0.01 / omega_1 * m.K, rtol=1e-13, atol=0)
    e = modelgen.load("paper-exp")
    assert e.C[0, 0] == 0.32


def test_unseen_geometry(tmp_path) -> None:
    path = tmp_path / "alu.toml"
    path.write_text(
        'name = "alu"\n[link]\nlength = 0.6\nyoungs_modulus = 69e9\ndensity = 2700\nwidth = 0.03\n'
        "thickness = 0.002\n[hub]\ninertia = 0.002\n[payload]\nmass = 0.05\ninertia = 2e-5\n"
    )
    m = modelgen.load(path, modes=3)
    assert m.n == 3 and m.natural_frequencies_hz.size == 3
    assert np.all(np.diff(m.natural_frequencies_hz) > 0)
    assert m.n_unstable >= 1
