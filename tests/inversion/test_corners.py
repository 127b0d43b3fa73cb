"""One table, several plants (issue 47, item 6): with ``uncertainty`` the optimal-control programme holds the nominal link
and every corner of the ranges at once. Checked on each corner with SciPy's own zero-order hold and ``dlsim`` of the
perturbed geometry's model, written apart from the product's chain programme and held plant."""

from __future__ import annotations

import json
import subprocess
import sys
from dataclasses import replace
from itertools import product
from pathlib import Path

import control
import numpy as np
import pytest
from scipy.signal import cont2discrete, dlsim

import modelgen
from inversion import invert, smoothstep
from inversion.errors import InversionError, SettingsError
from inversion.methods.ocp import LOOP_NAME
from inversion.studies.robustness import parse_uncertainty
from modelgen.linear import linear_model

DATA = Path(__file__).resolve().parents[1] / "data"
MOVE = smoothstep(0.5, 0.6, 2)
SPEC = "link.flexural_rigidity=5%,payload.mass=0.5%"
CORNERS = parse_uncertainty(SPEC)
RANGES = {"flexural_rigidity": 0.05, "payload_mass": 0.005}


@pytest.fixture(scope="module")
def heavy():  # type: ignore[no-untyped-def]
    model = modelgen.load(str(DATA / "heavy-payload.toml"))
    return model, invert(model, MOVE, method="ocp"), invert(model, MOVE, method="ocp", uncertainty=CORNERS)


def _corner_errors(model, result, ranges: dict[str, float] = RANGES, move=MOVE) -> list[float]:  # type: ignore[no-untyped-def]
    """The largest ``|y - y_d|`` of each corner plant driven by the result's held rows (then no torque for 2 s), at every
    period: SciPy's zero-order hold and simulation of the perturbed geometry's model. A point table's rows are its
    samples at the controller's rate (``result.tau``, the move's and what follows it)."""
    period = float(result.summary["sampled"]["period"])
    assert result.summary["sampled"]["hold"] == "zoh" or float(result.t[1] - result.t[0]) == pytest.approx(period)
    assert float(result.t[0]) == move.t0  # no pre-actuation
    rows = np.r_[result.tau, np.zeros(int(round(2.0 / period)))]
    t = move.t0 + np.arange(rows.size) * period
    y_d = move.derivative(np.clip(t, move.t0, move.tf), 0)
    errors = []
    for signs in product((-1.0, 1.0), repeat=len(ranges)):
        geometry = replace(model.geometry, **{k: getattr(model.geometry, k) * (1 + s * r) for (k, r), s in zip(ranges.items(), signs)})
        lm = linear_model(geometry, model.n, float(model.output_at))
        A, B, C = (np.asarray(lm[k], dtype=float) for k in ("A", "B", "C_out"))
        system = cont2discrete((A, B.reshape(-1, 1), C.reshape(1, -1), np.zeros((1, 1))), period, "zoh")
        _, y, _ = dlsim(system, rows)
        errors.append(float(np.abs(y[:, 0] - y_d).max()))
    return errors


def test_the_nominal_table_leaves_the_bound_on_a_corner(heavy) -> None:  # type: ignore[no-untyped-def]
    """What the programme is for: the nominal plant's table, measured 1.29 and 1.31 x the bound on the heavier corners."""
    model, nominal, _ = heavy
    assert max(_corner_errors(model, nominal)) > 1.2 * float(nominal.summary["max_error"])


def test_one_table_holds_every_corner(heavy) -> None:  # type: ignore[no-untyped-def]
    model, nominal, robust = heavy
    bound = float(robust.summary["max_error"])
    independent = _corner_errors(model, robust)
    # within the tube the margin asks (0.9 of the bound), as the programme's own figures say
    assert max(independent) <= 0.9 * bound * (1 + 1e-6)
    plants = [p for p in robust.summary["ocp"]["plants"] if LOOP_NAME not in p["name"]]  # (and the loops where planned)
    assert len(plants) == 4 and all("link.flexural_rigidity x" in p["name"] for p in plants)
    # with the joint PD judged and the loop planned, each corner in its loop too (checked apart on the aluminium bar,
    # tests/inversion/methods/test_ocp_window.py), within the same tube by the programme's own figures
    looped = [p for p in robust.summary["ocp"]["plants"] if p["name"].endswith(" in " + LOOP_NAME)]
    assert [p["name"] for p in looped] in ([], [f"{p['name']} in {LOOP_NAME}" for p in plants])
    assert all(max(p["max_tip_error"], p["after_end_excursion"]) <= 0.9 * bound * (1 + 1e-6) for p in looped)
    ours = sorted(p["max_tip_error"] for p in plants)
    assert np.allclose(ours, sorted(independent), rtol=1e-6, atol=1e-9)
    # the nominal plant ends at rest and is judged as every result is, at a peak a few per cent above the nominal table's
    assert robust.summary["sampled"]["max_tip_error"] <= bound and abs(robust.summary["sampled"]["drift"]) < 1e-6
    assert 1.0 < robust.summary["peak_torque"] / nominal.summary["peak_torque"] < 1.1  # measured 1.038


def test_the_replanned_output_holds_every_corner_too() -> None:
    """The steel strip's 0.5 m in 0.6 s re-planned for EI within 10 %: the nominal table leaves the bound on the softer
    and the stiffer link (measured 1.005 and 1.16 x); the one that holds both stays within 0.88 of it (peak +5.7 %)."""
    model = modelgen.load(str(DATA / "steel-strip.toml"))
    ranges = {"flexural_rigidity": 0.1}
    nominal = invert(model, MOVE, method="replan")
    robust = invert(model, MOVE, method="replan", uncertainty=parse_uncertainty("link.flexural_rigidity=10%"))
    bound = float(robust.summary["max_error"])
    assert robust.summary["settings"]["end"] == "rest"
    assert max(_corner_errors(model, nominal, ranges)) > bound
    independent = _corner_errors(model, robust, ranges)
    assert max(independent) <= 0.9 * bound
    figures = robust.summary["replan"]["plants"]
    assert [p["name"] for p in figures] == ["link.flexural_rigidity x 0.9", "link.flexural_rigidity x 1.1"]
    assert np.allclose(independent, [max(p["max_tip_error"], p["after_end_excursion"]) for p in figures], rtol=1e-6, atol=1e-9)
    assert robust.summary["peak_torque"] < 1.1 * nominal.summary["peak_torque"]


def test_ranges_no_table_holds_are_refused_with_the_plants_named() -> None:
    model = modelgen.load(str(DATA / "heavy-payload.toml"))
    with pytest.raises(InversionError, match="others at once.*the least tube one table holds them in is"):
        invert(model, MOVE, method="ocp", uncertainty=parse_uncertainty("link.flexural_rigidity=10%,payload.mass=10%"))


@pytest.mark.parametrize("system,spec", [
    (control.tf([-1.0, 2.0], [1.0, 4.0, 3.0]), parse_uncertainty("link.flexural_rigidity=5%")),  # no geometry to perturb
    (None, "link.flexural_rigidity=5%"),  # a SPEC, not parsed: the message names parse_uncertainty
    (None, 0.05),
])
def test_bad_uncertainty_is_refused_by_name(system, spec) -> None:  # type: ignore[no-untyped-def]
    model = modelgen.load("paper-sim") if system is None else system
    move = smoothstep(1.57, 5.5, 5) if system is None else smoothstep(1.0, 8.0, 6)
    with pytest.raises(SettingsError) as info:
        invert(model, move, method="ocp", uncertainty=spec)
    assert info.value.parameter == "uncertainty"


def test_the_command_line_holds_and_reports_the_corners(tmp_path: Path) -> None:
    run = subprocess.run([sys.executable, "-m", "sflm", "invert", str(DATA / "heavy-payload.toml"), "--trajectory", "smoothstep:0.5:0.6:2",
                          "--method", "ocp", "--uncertainty", SPEC, "--out", str(tmp_path), "-q"], capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, run.stderr
    assert "corner plants" in run.stdout and "4 more plants" in run.stdout
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert len([p for p in summary["ocp"]["plants"] if p["name"] != LOOP_NAME]) == 4 and "robustness" in summary
