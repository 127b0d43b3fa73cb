"""The non-causal stable inversion baseline (Bayo 1987; Kwon & Book 1994; Devasia, Chen & Paden 1996)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import make_interp_spline

import modelgen
from _helpers import error_lines, run_cli
from inversion import InversionError, InversionSummary, SettingsError, export_table, invert, trajectory_from_spec
from inversion.methods.stable import DEFAULT_TAIL_TOLERANCE

ROOT = Path(__file__).resolve().parents[3]


def _stable(preset: str):  # type: ignore[no-untyped-def]
    traj = trajectory_from_spec(preset if preset.startswith("paper") else "paper-sim")
    return invert(modelgen.load(preset), traj, method="stable")


@pytest.mark.parametrize("preset", ["hyperbolic", "paper-exp"])
def test_the_plant_from_the_first_sample_follows_y_d(preset: str) -> None:
    # the defining property: the linear plant, driven from (nearly) rest at the first sample by
    # the torque, follows y_d itself -- before, during and after the manoeuvre
    result = _stable(preset)
    model = result.model
    torque = make_interp_spline(result.t, result.tau, k=5)
    sol = solve_ivp(lambda t, x: model.A @ x + model.B * torque(t), (result.t[0], result.t[-1]), np.zeros(model.A.shape[0]),
                    t_eval=result.t, method="DOP853", rtol=1e-11, atol=1e-14)
    y = sol.y[: model.n + 1].T @ model.D
    move = result.summary["move"]
    assert np.abs(y - result.y_d).max() <= 1e-6 * move
    np.testing.assert_array_equal(result.y, result.y_d)  # no redefinition: y~ = y_d


@pytest.mark.parametrize("preset", ["hyperbolic", "paper-exp"])
def test_torque_before_t0_and_tails_cut(preset: str) -> None:
    result = _stable(preset)
    t0, tf = result.trajectory.t0, result.trajectory.tf
    peak = np.abs(result.tau).max()
    s = result.summary
    assert s["pre_actuation_time"] > 0 and s["post_actuation_time"] > 0
    assert result.t[0] == pytest.approx(t0 - s["pre_actuation_time"]) and result.t[-1] == pytest.approx(tf + s["post_actuation_time"])
    # pre-actuation: torque before the motion (small for a trajectory whose first five derivatives
    # start at zero, but far above the tails' cut), and post-actuation after it
    assert np.abs(result.tau[result.t < t0]).max() > 1000 * DEFAULT_TAIL_TOLERANCE * peak
    assert np.abs(result.tau[result.t > tf]).max() > 1000 * DEFAULT_TAIL_TOLERANCE * peak
    for end in (result.tau[0], result.tau[-1]):  # the tails end where they fall below the stated tolerance
        assert abs(end) <= 10 * DEFAULT_TAIL_TOLERANCE * peak
    assert np.all(np.diff(result.t) > 0)


def test_purely_imaginary_zeros_are_refused() -> None:
    with pytest.raises(InversionError, match=r"purely imaginary") as info:
        _stable("paper-sim")
    assert "56.31" in str(info.value) and "ssef" in str(info.value)


def test_near_imaginary_zeros_need_long_tails() -> None:
    # near-non-hyperbolic: stable zeros -0.76 +- 56.3i ring down slowly after t_f
    result = _stable("near-non-hyperbolic")
    hyperbolic = _stable("hyperbolic")
    assert result.summary["post_actuation_time"] > 30 * hyperbolic.summary["post_actuation_time"]
    assert result.summary["post_actuation_time"] > 5.0


def test_summary_keys_are_the_contract() -> None:
    result = _stable("hyperbolic")
    allowed = set(InversionSummary.__required_keys__) | set(InversionSummary.__optional_keys__)  # type: ignore[attr-defined]
    assert set(InversionSummary.__required_keys__) <= set(result.summary) <= allowed  # type: ignore[attr-defined]
    assert result.summary["method"] == "stable" and result.summary["max_redefinition_error"] == 0.0


def test_member_settings_are_refused() -> None:
    model = modelgen.load("hyperbolic")
    traj = trajectory_from_spec("paper-sim")
    for kwargs in ({"segments": 3}, {"cdec": (1e-3, 1.0)}, {"auto": True}, {"joining": "anchored"}):
        with pytest.raises(SettingsError, match="stable inversion takes no option of its own"):
            invert(model, traj, method="stable", **kwargs)  # type: ignore[arg-type]
    with pytest.raises(SettingsError, match="method"):
        invert(model, traj, method="polynomial-ish")


def test_cli(tmp_path: Path) -> None:
    ok = run_cli("invert", "hyperbolic", "--method", "stable", "--json", "--out", str(tmp_path), cwd=ROOT)
    assert ok.returncode == 0, ok.stderr
    summary = json.loads(ok.stdout)
    assert summary["pre_actuation_time"] > 0
    first = (tmp_path / "inversion.csv").read_text().splitlines()[1]
    assert float(first.split(",")[0]) < 0  # rows before t0 are the pre-actuation
    refused = run_cli("invert", "paper-sim", "--method", "stable", "--out", str(tmp_path), cwd=ROOT)
    lines = error_lines(refused.stderr)
    assert refused.returncode == 2 and len(lines) == 1 and "purely imaginary" in lines[0]


def test_a_stable_result_is_simulated_and_tabled_with_its_pre_actuation(tmp_path: Path) -> None:
    # the closed loop starts where the feedforward does, before t0 (measured: the linear plant
    # without friction follows y_d to 8e-10 m of the 0.1 m move)
    from simulation import simulate

    result = _stable("paper-exp")
    sim = simulate(result.model, result, controller="none", plant="linear", coulomb_friction=0.0, t_end=2.0)
    assert sim.t[0] == pytest.approx(-result.summary["pre_actuation_time"])
    assert sim.summary["max_tracking_error"] <= 1e-6 * result.summary["move"]
    table = export_table(result, tmp_path / "table.h")  # the samples, pre-actuation included
    assert f"TABLE_SIZE {result.t.size}" in table.read_text()
