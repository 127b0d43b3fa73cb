"""Where the output is measured (issue 10, item 3): ``modelgen.load(..., output_at=X)``,
``y = X theta + w(X)``, against the tip model and the finite-element reference."""

from __future__ import annotations

import json

import numpy as np
import pytest

import modelgen
from _helpers import linear_plant_output, run_cli
from inversion import invert, smoothstep, trajectory_from_spec
from inversion.problem import paper_case
from modelgen.continuum import continuum_reference, output_row
from modelgen.errors import GeometryError
from modelgen.geometry import load_geometry

PRESETS = ["paper-sim", "paper-exp", "hyperbolic", "near-non-hyperbolic"]


@pytest.mark.parametrize("preset", PRESETS)
def test_at_the_tip_the_model_is_the_default_one_bit_for_bit(preset: str) -> None:
    default = modelgen.load(preset)
    tip = modelgen.load(preset, output_at=default.geometry.length)
    assert default.output_at == tip.output_at == default.geometry.length
    for name in ("parameters", "A", "B", "C_out", "CA2", "AI", "BI", "T", "Tinv", "zeros"):
        assert np.array_equal(getattr(default, name), getattr(tip, name)), name
    assert default.CAB == tip.CAB
    # the paper's case keeps the paper's member and gives the same torque
    trajectory = trajectory_from_spec(preset if preset.startswith("paper") else "paper-sim")
    if preset.startswith("paper"):
        assert paper_case(tip, trajectory) is not None
        assert np.array_equal(invert(default, trajectory).tau, invert(tip, trajectory).tau)


def test_the_output_row_measures_at_x() -> None:
    model = modelgen.load("paper-exp", modes=3)
    L = model.geometry.length
    x = 0.37 * L
    inner = modelgen.load("paper-exp", modes=3, output_at=x)
    phi = model.shapes(np.array([x]), 0)[:, 0]
    n1 = model.n + 1
    assert np.allclose(inner.C_out[:n1], np.r_[x, phi], rtol=1e-15, atol=0)
    assert np.array_equal(inner.C_out[n1:], np.zeros(n1))
    # the plant is the same link: only the output row and what depends on it change
    for name in ("M", "K", "C", "H", "A", "B"):
        assert np.array_equal(getattr(inner, name), getattr(model, name)), name
    # the compiled tip_output measures where C_out does
    X = np.random.default_rng(1).normal(size=2 * n1)
    y, ydot = inner.compiled_functions.call("tip_output", inner.parameters, X)
    assert float(np.ravel(y)[0]) == pytest.approx(float(inner.C_out @ X), rel=1e-13)
    assert float(np.ravel(ydot)[0]) == pytest.approx(float(inner.C_out @ inner.A @ X), rel=1e-12)
    assert not paper_case(inner, trajectory_from_spec("paper-exp"))  # another model: not the paper's case


@pytest.mark.parametrize("preset", ["paper-sim", "paper-exp", "hyperbolic"])
@pytest.mark.parametrize("fraction", [0.75, 0.5, 0.25])
def test_the_lowest_zeros_follow_the_finite_element_reference_along_the_link(preset: str, fraction: float) -> None:
    # six assumed modes against the converged finite-element model measured at the same x
    # (cubic Hermite interpolation inside an element); measured agreement 3e-7..3e-5 of the
    # zero, the reference's own mesh-halving estimate up to 1.3e-5
    geometry = load_geometry(preset)
    x = fraction * geometry.length
    reference = continuum_reference(geometry, count=4, output_at=x)
    model = modelgen.load(preset, modes=6, output_at=x)
    for zero, error in zip(reference.zeros[:2], reference.zero_error[:2]):
        assert error <= 1e-4 * abs(zero)  # the reference itself is converged
        assert np.min(np.abs(model.zeros - zero)) <= 1e-4 * abs(zero)


def test_the_zeros_migrate_from_the_tip_towards_the_hub() -> None:
    # paper-exp: a real (non-minimum-phase) pair at the tip, only imaginary ones inside the link,
    # the lowest pair falling towards the clamped-link frequency as x -> 0
    geometry = load_geometry("paper-exp")
    lowest = []
    for fraction in (1.0, 0.75, 0.5, 0.25):
        reference = continuum_reference(geometry, count=3, output_at=fraction * geometry.length)
        lowest.append(reference.zeros[0])
    assert abs(lowest[0].imag) < 1e-9 * abs(lowest[0]) and lowest[0].real > 0  # +-321.8 at the tip
    assert all(abs(z.real) <= 1e-9 * abs(z) for z in lowest[1:])  # imaginary inside
    assert abs(lowest[1]) > abs(lowest[2]) > abs(lowest[3])


def test_the_finite_element_output_row_interpolates_cubics_exactly() -> None:
    geometry = load_geometry("paper-sim")
    L, elements = geometry.length, 40
    nodes = np.linspace(0.0, L, elements + 1)
    field = lambda x: 0.3 * x - 0.7 * x**2 + 1.9 * x**3  # noqa: E731  (u(0) = 0: a cubic the elements hold exactly)
    slope = lambda x: 0.3 - 1.4 * x + 5.7 * x**2  # noqa: E731
    dofs = np.empty(2 * (elements + 1))
    dofs[0::2], dofs[1::2] = field(nodes), slope(nodes)
    for x in (1e-3, 0.2 * L, L / 3, 0.999 * L, L):
        assert output_row(geometry, elements, x) @ dofs[1:] == pytest.approx(field(x), rel=1e-12)
    assert np.array_equal(output_row(geometry, elements), np.eye(2 * elements + 1)[2 * elements - 1])  # the tip: u_N
    default = continuum_reference(geometry, count=3)
    tip = continuum_reference(geometry, count=3, output_at=L)
    assert np.array_equal(default.zeros, tip.zeros)


def test_the_plant_measured_at_x_follows_the_redefined_output() -> None:
    model = modelgen.load("paper-sim", output_at=0.6)
    result = invert(model, smoothstep(1.0, 5.5, 5), segments=5, h=1, cdec=(1e-3, 1.0), joining="anchored", max_error=np.inf)
    assert result.summary["output_at"] == 0.6
    y, _ = linear_plant_output(model, result)  # the plant on (A, B, C_out at x)
    assert np.abs(y - result.y).max() <= 1e-6 * result.summary["move"]


@pytest.mark.parametrize("value", [0.0, -0.1, 1.2, float("nan"), float("inf"), "tip", True])
def test_an_output_location_off_the_link_is_refused(value: object) -> None:
    with pytest.raises(GeometryError, match="output_at") as info:
        modelgen.load("paper-sim", output_at=value)  # type: ignore[arg-type]
    assert info.value.key == "output_at" and "(0, 1.005]" in str(info.value)


def test_sflm_info_shows_where_the_output_is_measured() -> None:
    run = ["info", "paper-sim", "--output-at", "0.5"]
    text = run_cli(*run).stdout
    assert "at x = 0.5 m" in text and "paper, section" not in text  # the paper's zeros are the tip's
    info = json.loads(run_cli(*run, "--json").stdout)
    assert info["output_at"] == 0.5
    assert info["zeros"] == [[float(z.real), float(z.imag)] for z in modelgen.load("paper-sim", output_at=0.5).zeros]
    bad = run_cli(*run[:-1], "2")
    assert bad.returncode == 2 and bad.stderr.count("\n") == 1 and "--output-at" in bad.stderr


def test_the_closed_loop_holds_the_output_measured_at_x() -> None:
    # the PD reference ends on theta = y_f / x (not y_f / L): the measured point comes to rest on y_f
    from simulation import simulate

    model = modelgen.load("paper-sim", output_at=0.6)
    result = invert(model, smoothstep(0.5, 3.0, 5), objective="error")  # the closest member: what is measured is the PD's hold
    sim = simulate(model, result, t_end=6.0)
    assert abs(sim.summary["final_tip_error"]) <= 1e-6 * 0.5  # measured 1.9e-10 m
    assert sim.summary["residual_vibration"] <= 1e-6 * 0.5
