"""Rest at the end (the paper's Remark 2): no torque jump when the feedforward stops, no residual vibration."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla

import modelgen
from _helpers import run_cli
from inversion import Family, InversionResult, SettingsError, invert, smoothstep, trajectory_from_spec
from inversion.family.member import REST_TOLERANCE
from inversion.settings import InversionSettings
from inversion.family.verify import plant_run

ROOT = Path(__file__).resolve().parents[3]
OWN = str(ROOT / "tests" / "data" / "own-aluminium.toml")


def _rest(name: str) -> InversionResult:
    if name == "own":
        # a move whose jerk vanishes at its ends: the quintic's jumps, and at rest at t_f the torque would change faster
        # than ten times a rigid link's (the default rate bound) at 1 kHz
        return invert(modelgen.load(OWN), smoothstep(0.5, 2.0, 3), method=Family(end="rest"))
    # the family's members (the automatic choice may return optimal control's table, which ends at rest too, where it
    # needs 5 % less torque: tests/inversion/methods/test_least_peak.py)
    return invert(modelgen.load(name), trajectory_from_spec(name if name.startswith("paper") else "paper-sim"), method=Family(end="rest"))


@pytest.mark.parametrize("name", ["paper-sim", "paper-exp", "hyperbolic", "near-non-hyperbolic", "own"])
def test_rest_end_stops_torque_and_vibration(name: str) -> None:
    result = _rest(name)
    assert result.settings.end == "rest"
    peak = np.abs(result.tau).max()
    assert abs(result.tau[-1]) <= REST_TOLERANCE * peak  # no torque jump (below what a drive resolves) when it stops
    assert abs(result.summary["torque_at_end"]) <= REST_TOLERANCE * peak
    # the linear plant driven from rest by the torque (exact discretisation of a quintic hold),
    # then by zero torque: the tip stays still after t_f
    redef, figures = result.redefinition, result.figures
    assert redef is not None and figures is not None
    output_error, _, _, x_end = plant_run(redef, figures, step=0.05)  # fine steps: a hold error of ~1e-12
    model = result.model
    step = sla.expm(model.A * 0.01)
    tip, x = [], x_end
    for _ in range(201):  # 2 s after t_f
        tip.append(float(model.D @ x[: model.n + 1]))
        x = step @ x
    move = result.summary["move"]
    assert np.ptp(tip) <= REST_TOLERANCE * move
    assert output_error <= 1e-6  # and it followed y~ on the way
    assert abs(tip[0] - result.summary["final_desired_output"]) <= 1e-6 * move


def test_the_paper_member_ends_free_and_moving() -> None:
    # what the rest end removes: paper-exp's own member ends with a torque jump and a moving link
    free = invert(modelgen.load("paper-exp"), trajectory_from_spec("paper-exp"))
    assert free.settings.end == "free"
    assert abs(free.summary["torque_at_end"]) > 1e-3 * free.summary["peak_torque"]
    assert abs(free.summary["final_redefined_velocity"]) > 1e-6


def test_rest_with_each_joining_or_refused_with_figures() -> None:
    model = modelgen.load("paper-sim")
    traj = trajectory_from_spec("paper-sim")
    ok = invert(model, traj, segments=5, h=2, cdec=(1e-2, 1.0), joining="anchored", end="rest")
    assert abs(ok.tau[-1]) <= 1e-9 * np.abs(ok.tau).max()
    assert max(abs(v) for v in ok.summary["final_deflections"] + ok.summary["final_deflection_rates"]) <= 1e-9
    from inversion import InversionError

    with pytest.raises(InversionError, match=r"residual|rest|solver"):  # 13 exponentials on a short range: refused
        invert(model, traj, segments=5, h=1, cdec=(1e-2, 1.0), joining="paper", end="rest")


def test_settings_round_trip_and_bad_end() -> None:
    s = InversionSettings(segments=4, h=1, cdec=(1e-3, 1.0), joining="anchored", end="rest")
    assert InversionSettings.from_dict(s.to_dict()) == s
    with pytest.raises(SettingsError, match="end"):
        InversionSettings(end="stop")
    assert REST_TOLERANCE == 1e-6  # a millionth of the peak: below what a drive resolves (docs/method.md)


def test_cli_end_rest(tmp_path: Path) -> None:
    proc = run_cli("invert", "paper-exp", "--end", "rest", "--json", "--out", str(tmp_path), cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["settings"]["end"] == "rest" and abs(summary["torque_at_end"]) <= REST_TOLERANCE * summary["peak_torque"]
    assert "auto" in summary  # a rest end is not the paper's member: chosen automatically
