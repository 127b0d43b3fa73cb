"""Held parameters in the fitted ones' intervals (issue 62, item 3).

A 0.4 m steel strip with a 20 g payload (the exact continuum beam of ``beam_truth.py``, written apart from the fit's
model), its first three frequencies read to 0.5 Hz (stated), fitted from a file 20 % low in EI, 20 % high in the hub
inertia and off in the payload mass. Three frequencies cannot tell the payload mass: it is held at the file's value.
Before, the printed intervals ignored it: with the file's payload 30 % heavy, EI missed the truth in 19 of 20 draws
(+2.86 % for a half-width of 1.27 %, measured on the commit before). Now each held parameter's plausible error --
assumed within ``HELD_SPREAD`` (30 %), or the spread the user states -- enters the intervals by the fit's sensitivity.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from modelgen.errors import SettingsError
from modelgen.fit import HELD_SPREAD, FitError, FrequencyData, fit, held_spreads
from modelgen.geometry import parse_geometry

from beam_truth import Beam

TRUTH = parse_geometry({"name": "steel-04", "link": {"length": 0.4, "youngs_modulus": 200e9, "density": 7850, "width": 0.02,
                                                     "thickness": 0.002},
                        "hub": {"inertia": 0.002}, "payload": {"mass": 0.02, "inertia": 2e-6}, "damping": {"ratio": 0.01},
                        "model": {"modes": 3}})
FREQUENCIES = Beam(TRUTH.length, TRUTH.flexural_rigidity, TRUTH.linear_density, TRUTH.hub_inertia, TRUTH.payload_mass,
                   TRUTH.payload_inertia).frequencies(3)
EI = "link.flexural_rigidity"


def _file(payload: float):  # type: ignore[no-untyped-def]
    """The start file: EI 20 % low, the hub inertia 20 % high, the payload mass ``payload`` x the truth."""
    return replace(TRUTH, flexural_rigidity=0.8 * TRUTH.flexural_rigidity, hub_inertia=1.2 * TRUTH.hub_inertia,
                   payload_mass=payload * TRUTH.payload_mass)


def _read(seed: int | None) -> FrequencyData:
    """The three frequencies read to 0.5 Hz (exact where ``seed`` is None)."""
    noise = 0.0 if seed is None else 0.5 * np.random.default_rng(seed).standard_normal(3)
    return FrequencyData(FREQUENCIES + noise, "hub-free", 0.5)


def _ei_inside(payload: float, spread: dict[str, float] | None) -> int:
    inside = 0
    for seed in range(20):
        result = fit(_file(payload), _read(seed), held_spread=spread)
        assert "payload.mass" in result.held and EI in result.values
        inside += abs(result.values[EI] - TRUTH.flexural_rigidity) <= result.intervals[EI]
    return inside


def test_a_held_payload_within_the_assumed_spread_leaves_the_intervals_true() -> None:
    """The file's payload 20 % heavy, inside the 30 % assumed: EI's truth inside its interval in 19 of 20 draws
    (measured 38 of 40 over seeds 0-39; before: 1 of 20 with the payload 30 % heavy)."""
    assert _ei_inside(1.2, None) >= 18


def test_a_spread_the_user_states_is_used() -> None:
    """The payload 30 % heavy, stated within 50 %: 20 of 20 (measured 40 of 40); stated known exactly (0 %), the
    intervals are the noise's alone, as before the issue -- and miss (the file is wrong, the user said it was not)."""
    assert _ei_inside(1.3, {"payload.mass": 0.5}) == 20
    result = fit(_file(1.3), _read(0), held_spread={"payload.mass": 0.0, "payload.inertia": 0.0})
    assert result.held_intervals[EI] == 0.0
    assert result.intervals[EI] == pytest.approx(np.hypot(result.noise_intervals[EI], result.model_intervals[EI]))
    assert result.held_spread["payload.mass"] == {"relative_95": 0.0, "assumed": False}


def test_the_held_part_is_what_refitting_with_the_held_value_moved_moves() -> None:
    """First order against the fit itself: on the exact frequencies, EI fitted with the file's payload 30 % heavy less
    EI fitted with the true payload (the shift the held error causes, +2.52 %) is what the held part for a 30 % spread
    predicts (2.45 %), within a tenth; and the summary says the spread was assumed."""
    wrong, right = fit(_file(1.3), _read(None)), fit(_file(1.0), _read(None))
    shift = wrong.values[EI] / right.values[EI] - 1
    part = wrong.held_intervals[EI] / wrong.values[EI]
    assert 0.015 < shift and part == pytest.approx(shift, rel=0.1), (shift, part)
    summary = wrong.summary()
    assert summary["held_spread"]["payload.mass"] == {"relative_95": HELD_SPREAD, "assumed": True}
    assert summary["parameters"][EI]["held_95"] == wrong.held_intervals[EI]
    assert any(note.startswith("payload.mass held at its nominal value, assumed within 30 %") for note in wrong.notes)


def test_parameters_not_listed_are_held_with_their_spread() -> None:
    """``params`` listing EI alone: the others of the default set are held, named, and in EI's interval."""
    result = fit(_file(1.3), _read(0), params=[EI])
    assert result.held["payload.mass"] == "not among --params" and result.held["hub.inertia"] == "not among --params"
    assert result.held_intervals[EI] > result.noise_intervals[EI]


def test_a_held_parameter_that_swamps_a_fitted_one_is_a_refusal_naming_it() -> None:
    """The link's density stated within 300 %: with it, EI could be anything the frequencies' ratio EI / rho allows --
    more than its value. No calibration; the density named."""
    with pytest.raises(FitError, match=r"mostly from link.linear_density held at its nominal value \(stated within 300 %"):
        fit(_file(1.0), _read(0), params=[EI], held_spread={"link.linear_density": 3.0})


@pytest.mark.parametrize("spec, words", [("payload.mass=-1%", ">= 0"), ("payload.mass=1001%", "below 1000 %"),
                                         ("payload.weight=1%", "held-spread key"), ("payload.mass", "KEY=RANGE"),
                                         ("payload.mass=1%,payload.mass=2%", "each key once"), ("", "KEY=RANGE")])
def test_a_spread_out_of_range_is_refused_by_name(spec: str, words: str) -> None:
    with pytest.raises(SettingsError, match=words):
        held_spreads(spec)
    assert held_spreads("payload.mass=2%,hub.inertia=0") == {"payload.mass": 0.02, "hub.inertia": 0.0}


def test_the_command_line_states_a_spread_and_refuses_a_bad_one_in_one_line(tmp_path: Path) -> None:
    import json

    from _helpers import error_lines, run_cli

    data = tmp_path / "tap.toml"
    data.write_text(f"frequencies_hz = {[round(float(f), 2) for f in FREQUENCIES]}\nboundary = 'hub-free'\nuncertainty_hz = 0.5\n")
    link = tmp_path / "steel-04.toml"
    link.write_text('name = "steel-04"\n[link]\nlength = 0.4\nyoungs_modulus = 160e9\ndensity = 7850\nwidth = 0.02\nthickness = 0.002\n'
                    '[hub]\ninertia = 0.0024\n[payload]\nmass = 0.026\ninertia = 2e-6\n[damping]\nratio = 0.01\n[model]\nmodes = 3\n')
    proc = run_cli("fit", str(link), "--data", str(data), "--held-spread", "payload.mass=2%", "--json", "--out", str(tmp_path / "c.toml"))
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["held_spread"]["payload.mass"] == {"relative_95": 0.02, "assumed": False}
    assert summary["held_spread"]["payload.inertia"] == {"relative_95": HELD_SPREAD, "assumed": True}
    assert summary["parameters"][EI]["held_95"] > 0
    import tomllib  # the calibrated file records what its values assume, and how far

    calibration = tomllib.loads((tmp_path / "c.toml").read_text())["calibration"]
    assert calibration["held"]["payload.mass"]["spread_95"] == 0.02 and calibration["held"]["payload.mass"]["spread_assumed"] is False
    assert calibration["held"]["payload.inertia"]["spread_assumed"] is True
    assert calibration["parameters"][EI]["held_95"] == summary["parameters"][EI]["held_95"]
    proc = run_cli("fit", str(link), "--data", str(data), "--held-spread", "payload.mass=two", "--out", str(tmp_path / "c.toml"))
    lines = error_lines(proc.stderr)
    assert proc.returncode == 2 and len(lines) == 1 and "--held-spread payload.mass" in lines[0], proc.stderr
