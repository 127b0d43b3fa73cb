"""Modal damping (issue 48, item 4): a damping ratio per flexible mode in the geometry file, beside the Rayleigh form;
the same in the linear model, the generated and compiled one, the finite-element reference and the calibration."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import scipy.linalg as sla
from beam_truth import Beam

import inversion
import modelgen
from inversion.studies.robustness import judge_robustness, parse_uncertainty
from modelgen.continuum import fe_frequencies_zeros
from modelgen.errors import GeometryError, SettingsError
from modelgen.fit import FrequencyResponse, calibrated_toml, fit, spread_of_calibration
from modelgen.geometry import load_geometry, parse_geometry
from modelgen.linear import linear_model
from modelgen.model import sort_zeros

DATA = Path(__file__).resolve().parents[1] / "data"
ROD = load_geometry(DATA / "glass-fibre-rod.toml")
MODAL = replace(ROD, damping_ratio=0.0, modal_damping=(0.01, 0.03))


def _document(**damping: Any) -> dict[str, Any]:
    return {"name": "m", "link": {"length": 0.9, "flexural_rigidity": 19.6, "linear_density": 0.15}, "hub": {"inertia": 0.005},
            "damping": damping}


def test_the_file_takes_a_ratio_per_mode_and_names_what_it_refuses() -> None:
    assert parse_geometry(_document(modal=[0.01, 0.02])).modal_ratios(4) == (0.01, 0.02, 0.02, 0.02)
    assert parse_geometry(_document(ratio=0.01)).modal_ratios(3) == ()
    for damping, key in (({"modal": [0.01], "ratio": 0.02}, "damping"), ({"modal": []}, "damping.modal"),
                         ({"modal": [0.01, 1.0]}, r"damping.modal\[1\]"), ({"modal": [-0.1]}, r"damping.modal\[0\]"),
                         ({"modal": 0.01}, "damping.modal"), ({"modal": ["a"]}, r"damping.modal\[0\]")):
        with pytest.raises(GeometryError, match=key):
            parse_geometry(_document(**damping))


def test_each_mode_of_the_linear_model_has_its_ratio() -> None:
    """The poles' damping ratios are the file's, the last for the modes after it; the rigid body stays undamped."""
    model = linear_model(MODAL.with_model(5))
    poles = np.linalg.eigvals(model["A"])
    oscillating = poles[np.imag(poles) > 1e-6]
    oscillating = oscillating[np.argsort(np.abs(oscillating))]
    np.testing.assert_allclose(-np.real(oscillating) / np.abs(oscillating), [0.01, 0.03, 0.03, 0.03, 0.03], rtol=1e-9)
    assert np.sum(np.abs(poles) < 1e-9) == 2  # theta and thetadot: the rigid body, undamped


def test_the_compiled_model_damps_as_the_linear_one() -> None:
    """The generated and compiled model's matrices are the linear model's (its ``Dm`` parameters carry the matrix)."""
    compiled = modelgen.load(MODAL.with_model(2))
    linear = linear_model(MODAL.with_model(2))
    for name in ("M", "K", "C", "A"):
        np.testing.assert_allclose(np.asarray(compiled.__dict__[name] if name != "A" else compiled.A), linear[name],
                                   rtol=1e-10, atol=1e-12 * np.abs(linear[name]).max())
    assert compiled.C[0, 1] != 0.0  # modal damping couples the hub to the modes (Rayleigh's does not)


def test_the_finite_element_reference_damps_each_of_its_modes() -> None:
    """The mesh's zeros with modal damping agree with the converged assumed-mode model's (the first pair to 1e-5)."""
    _, fe = fe_frequencies_zeros(MODAL, 60)
    model = linear_model(MODAL.with_model(8))
    A, B, C = np.asarray(model["A"]), np.asarray(model["B"]).reshape(-1, 1), np.asarray(model["C_out"]).reshape(1, -1)
    N = A.shape[0]  # the invariant zeros: the finite eigenvalues of the Rosenbrock pencil
    alpha, beta = sla.eigvals(np.block([[A, B], [C, np.zeros((1, 1))]]), np.block([[np.eye(N), np.zeros((N, 1))],
                                                                                  [np.zeros((1, N + 1))]]), homogeneous_eigvals=True)
    zeros = sort_zeros(alpha[np.abs(beta) > 1e-12] / beta[np.abs(beta) > 1e-12])
    np.testing.assert_allclose(fe[:2], zeros[:2], rtol=1e-5)


def test_a_response_fits_a_ratio_per_mode_it_sees(tmp_path: Path) -> None:
    """The exact beam damped 1.2 % in its first mode and 2 % in the others (not Rayleigh's proportion), a 2-60 Hz
    response (two modes) with 2 % noise, the file's modal damping 1 %: each mode's ratio is fitted, the truth within
    every interval; the calibrated file keeps the list, and the robust judgement's spread (``fit:FILE``) takes each
    fitted ratio's interval with the rest."""
    truth = replace(ROD, flexural_rigidity=ROD.flexural_rigidity * 1.06, payload_mass=0.092, hub_inertia=0.0055,
                    payload_inertia=2.2e-5)
    beam = Beam(truth.length, truth.flexural_rigidity, truth.linear_density, truth.hub_inertia, truth.payload_mass,
                truth.payload_inertia)
    f = np.geomspace(2.0, 60.0, 300)
    rng = np.random.default_rng(100)
    G = beam.modal_response(f, np.array([0.012, 0.02])) * (1 + 0.02 * (rng.standard_normal(300) + 1j * rng.standard_normal(300)) / np.sqrt(2))
    result = fit(replace(ROD, damping_ratio=0.0, modal_damping=(0.01,)), FrequencyResponse(f, np.abs(G), np.rad2deg(np.angle(G))))
    expected = {"link.flexural_rigidity": truth.flexural_rigidity, "payload.mass": 0.092, "payload.inertia": 2.2e-5,
                "hub.inertia": 0.0055, "damping.modal_1": 0.012, "damping.modal_2": 0.02}
    assert set(result.values) == set(expected)
    for key, value in result.values.items():
        assert abs(value - expected[key]) <= result.intervals[key], (key, value, result.intervals[key])
    path = tmp_path / "calibrated.toml"
    path.write_text(calibrated_toml(result, "beam.csv"))
    assert load_geometry(path).modal_damping == pytest.approx((result.values["damping.modal_1"], result.values["damping.modal_2"]))
    spread = dict(item.split("=") for item in spread_of_calibration(path).split(","))
    assert {"damping.modal_1", "damping.modal_2", "link.flexural_rigidity"} <= set(spread)
    relative = 100 * result.intervals["damping.modal_2"] / result.values["damping.modal_2"]
    assert float(spread["damping.modal_2"].rstrip("%")) == pytest.approx(relative, rel=1e-5)
    assert dict(parse_uncertainty(f"fit:{path}").ranges)["damping.modal_1"] == pytest.approx(
        result.intervals["damping.modal_1"] / result.values["damping.modal_1"], rel=1e-5)


def test_the_robust_judgement_spreads_each_mode_s_ratio() -> None:
    """``--uncertainty damping.modal_K=R``: mode K's ratio spread, the others as the file has them -- the geometry an
    edited file gives, whose poles carry the spread ratio -- and the judgement sees it (less damping, a larger error).
    Refused by name: on a geometry with Rayleigh damping, Rayleigh's ratio on one damped per mode, a mode the model does
    not have, a mode beyond any model."""
    geometry = parse_geometry(_document(modal=[0.01, 0.03, 0.02])).with_model(3)
    sets = parse_uncertainty("damping.modal_2=50%").perturbed(geometry)
    assert [g.modal_damping for _, g in sets] == [(0.01, 0.015, 0.02), (0.01, 0.045, 0.02)]
    edited = parse_geometry(_document(modal=[0.01, 0.015, 0.02])).with_model(3)
    np.testing.assert_array_equal(linear_model(sets[0][1])["A"], linear_model(edited)["A"])
    poles = np.linalg.eigvals(linear_model(sets[0][1])["A"])
    oscillating = sorted(poles[np.imag(poles) > 1e-6], key=abs)
    np.testing.assert_allclose([-p.real / abs(p) for p in oscillating], [0.01, 0.015, 0.02], rtol=1e-9)

    model = modelgen.load(MODAL.with_model(2))
    result = inversion.invert(model, inversion.smoothstep(0.3, 0.5, 2))
    judged = judge_robustness(result, "damping.modal_1=50%,damping.modal_2=50%")
    assert judged["worst_parameters"] == pytest.approx({"damping.modal_1": 0.005, "damping.modal_2": 0.015})
    assert judged["worst_case_error"] > judged["nominal_error"] * (1 + 1e-3)  # the least damped corner errs most
    assert judged["corner_errors"][0] == judged["worst_case_error"]
    for spec, on, match in (("damping.modal_1=10%", modelgen.load(ROD.with_model(2)), "damping.ratio: .* Rayleigh"),
                            ("damping.ratio=10%", model, r"damping.modal_K \(K = 1..2\)"),
                            ("damping.modal_3=10%", model, "2 modes")):
        with pytest.raises(SettingsError, match=match):
            parse_uncertainty(spec).check(on)
    for key in ("damping.modal_0", "damping.modal_21", "damping.modal_x"):
        with pytest.raises(SettingsError, match="uncertainty key"):
            parse_uncertainty(f"{key}=10%")


def test_a_damping_key_of_the_other_form_is_refused() -> None:
    data = FrequencyResponse(np.geomspace(2.0, 60.0, 50), np.ones(50), np.zeros(50))
    with pytest.raises(SettingsError, match="damping.modal_K needs"):
        fit(ROD, data, ["damping.modal_1"])
    with pytest.raises(SettingsError, match="damping.modal_K for this geometry"):
        fit(MODAL, data, ["damping.ratio"])
