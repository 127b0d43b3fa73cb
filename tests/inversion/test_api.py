"""The automatic choice across methods (issue 34, item 1): the family first, the optimal-control feedforward only when no
member passes, stable inversion truncated to ``preview`` when the user allows pre-actuation, and a refusal quoting the
causal limit when no causal method can meet the bound.

Figures measured here (named as such); the causal limit's closed form is docs/method.md section 7.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.signal as sg

import modelgen
from inversion import InversionError, invert, smoothstep
from inversion.errors import SettingsError
from inversion.methods.stable import stable_inversion
from sflm.cli import main

control = pytest.importorskip("control")
s = control.tf("s")
#: One real zero at 2: 1 in 4 s (smoothstep order 6) is beyond the causal limit at 1 % (3.074 %, docs/method.md section 7).
ONE_ZERO = (2 - s) / ((s + 1) * (s + 3))
#: Purely imaginary zeros +-2i and one at 1: the family's nearest member in 12 s is 1.78 % off (issue 34).
IMAGINARY = (s - 1) * (s**2 + 4) / ((s + 1) ** 2 * (s + 2) ** 3)


def _stages(result) -> list[tuple[str, str]]:
    return [(st["method"], st["status"]) for st in result.summary["auto"]["stages"]]


def test_the_family_passes_and_optimal_control_is_asked_for_the_torque() -> None:
    # issue 60, item 6: hyperbolic's 1 rad in 3 s. The family's member passes at 0.854 N m, 34 % above the least peak any
    # causal table within the tube can have (0.639): optimal control is asked, needs 0.671 and tolerates EI within
    # 17.9 % (the member 50 %: more than 10 % either way), and is returned
    result = invert(modelgen.load("hyperbolic"), smoothstep(1.0, 3.0, 5))
    auto = result.summary["auto"]
    assert _stages(result) == [("ssef", "passed"), ("ocp", "passed")]
    member, optimal = (stage["peak_torque"] for stage in auto["stages"])
    least = auto["least_peak"]
    assert member > 1.05 * least["peak_torque"] and optimal * 1.05 < member
    robust = least["robustness"]
    assert robust["kept"] == "ocp" == result.summary["method"] and auto["stages"][1]["chosen"]
    assert 0.1 <= robust["tables"][1]["tolerated"] < 0.5 * robust["tables"][0]["tolerated"]
    assert result.summary["sampled"]["max_tip_error"] <= result.summary["max_error"]


def test_only_the_optimal_control_feedforward_solves() -> None:
    # measured: the family's nearest member is 1.78 % off in 12 s; the optimal-control feedforward at 20 ms holds 1 %
    result = invert(IMAGINARY, smoothstep(1.0, 12.0, 6), period=0.02)
    assert result.summary["method"] == "ocp"
    stages = _stages(result)
    assert stages[0][0] == "ssef" and stages[0][1] != "passed"
    assert stages[-1] == ("ocp", "passed")
    held = result.summary["sampled"]
    assert held["max_tip_error"] <= 0.01 * (1 + 1e-9)  # held at its rows, during the move and after it
    assert result.summary["torque_ratio"] <= 3.0
    assert result.summary["torque_rate_ratio"] <= 10.0 * (1 + 1e-6)
    # the plant driven by the held table from rest, independently (python-control's zero-order-hold discretisation),
    # through the move and 40 s after it with the static input held
    after = 2000
    u = np.append(result.tau, np.full(after, 1.0 / float(IMAGINARY.dcgain())))
    t = np.arange(u.size) * 0.02
    y = control.forced_response(control.sample_system(IMAGINARY, 0.02, "zoh"), T=t, U=u).outputs
    assert np.abs(y - smoothstep(1.0, 12.0, 6).derivative(np.clip(t, 0.0, 12.0), 0)).max() <= 0.01 * (1 + 1e-6)


def test_a_long_move_s_optimal_control_table_is_the_controller_s() -> None:
    # 12 s at the default 1 kHz: the chain programme solves every period of the move and of its window (17 000, HPIPM;
    # the general solvers needed rows 20 periods apart, the table the line through them): its rows change by at most 10 x
    # the static need's change over one period (the default rate bound), where rows held 20 periods each stepped 200 x it
    # (measured before, 13b986d)
    result = invert(IMAGINARY, smoothstep(1.0, 12.0, 6), margin=0)  # the table at the bound (the default keeps 10 % free)
    summary = result.summary
    # (the programme's rows may lie several periods apart where the plant's shortest time constant spans many: the table
    # is linear between them and held every period, as below)
    assert summary["method"] == "ocp" and summary["settings"]["period"] == 0.001
    assert result.tau.size == 12000 and summary["torque_rate_ratio"] <= 10.0 * (1 + 1e-6)
    assert np.abs(np.diff(np.concatenate([[0.0], result.tau, [1.0 / float(IMAGINARY.dcgain())]]))).max() <= \
        10.0 * summary["rigid_torque_rate"] * (1 + 1e-6)
    # the static need is 2 (1 / G(0)); the 1 ms limit 2.09, and the smoothest table within 5 % more
    smoothing = summary["ocp"]["smoothing"]
    assert smoothing["least_peak"] <= 1.1 * 2.0 and smoothing["status"] == "solved"
    assert summary["peak_torque"] <= smoothing["least_peak"] * (1 + 0.05) * (1 + 1e-9)
    # HiGHS's least peak with a trace of the rows' total variation: measured 6.37 from rest to the static input (the
    # least peak alone, a vertex that leaves the peak and comes back at the rate bound: 8.60, at the same peak to 3e-5)
    assert np.abs(np.diff(np.concatenate([[0.0], result.tau, [-2.0]]))).sum() <= 7.0
    # independently: python-control's zero-order hold at 1 ms, through the move and 40 s after it with the static input held
    # (of the state space: the 1 ms transfer function's coefficients lose the digits, 8.5 % off on this table)
    u = np.append(result.tau, np.full(40_000, 1.0 / float(IMAGINARY.dcgain())))
    t = np.arange(u.size) * 0.001
    y = control.forced_response(control.sample_system(control.ss(IMAGINARY), 0.001, "zoh"), T=t, U=u).outputs
    assert np.abs(y - smoothstep(1.0, 12.0, 6).derivative(np.clip(t, 0.0, 12.0), 0)).max() <= 0.01 * (1 + 1e-6)


def test_beyond_the_causal_limit_is_refused_with_it() -> None:
    with pytest.raises(InversionError) as caught:
        invert(ONE_ZERO, smoothstep(1.0, 4.0, 6))
    message = str(caught.value)
    assert "no causal feedforward from rest can hold this move closer than 0.03074" in message
    assert "5.592 s" in message and "preview" in message  # the shortest duration, and pre-actuation as the way out
    assert caught.value.status == "causal-limit"


def test_preview_makes_stable_inversion_the_choice() -> None:
    result = invert(ONE_ZERO, smoothstep(1.0, 4.0, 6), preview=4.0)
    summary = result.summary
    assert summary["method"] == "stable"
    assert ("ssef", "skipped") in _stages(result) and ("stable", "passed") in _stages(result)
    assert 0 < summary["pre_actuation_time"] <= 4.0
    assert summary["settings"]["pre_actuation_needed"] > 4.0  # truncated: the tails wanted more
    assert summary["sampled"]["max_tip_error"] <= 0.01


@pytest.mark.parametrize("preview", [0.0, 0.5, 1.0, 3.0])
def test_a_truncated_preview_reports_the_free_response_the_plant_follows(preview: float) -> None:
    # the plant from rest at t0 - preview, driven by the truncated torque (lsim, independent of the closed form): its
    # output is the result's y, and max |y - y_d| is the reported error
    result = stable_inversion(_system(ONE_ZERO), smoothstep(1.0, 4.0, 6), 1000.0, preview=preview)
    assert result.summary["pre_actuation_time"] == pytest.approx(preview, abs=1e-3)
    _, y, _ = sg.lsim((np.asarray(ONE_ZERO.num[0][0]), np.asarray(ONE_ZERO.den[0][0])), result.tau, result.t - result.t[0],
                      interp=True)
    assert np.abs(y - result.y).max() <= 1e-4
    # and its velocity is the output's own derivative (the free response's, added to y_d's)
    assert np.abs(np.gradient(result.y, result.t) - result.ydot).max() <= 2e-3 * np.abs(result.ydot).max()
    assert result.summary["max_redefinition_error"] == pytest.approx(np.abs(result.y - result.y_d).max(), rel=1e-9)
    # the unstable mode at 2 decays backwards as e^{-2 preview}: the error shrinks with the preview allowed
    assert result.summary["max_redefinition_error"] <= 0.05 * np.exp(-2 * preview) + 1e-6


def test_a_preview_the_tails_do_not_need_changes_nothing() -> None:
    full = stable_inversion(_system(ONE_ZERO), smoothstep(1.0, 4.0, 6), 1000.0)
    roomy = stable_inversion(_system(ONE_ZERO), smoothstep(1.0, 4.0, 6), 1000.0, preview=100.0)
    np.testing.assert_array_equal(full.tau, roomy.tau)
    assert roomy.summary["max_redefinition_error"] == 0.0


@pytest.mark.parametrize("preview", [-1.0, float("nan"), float("inf"), True, "2"])
def test_a_bad_preview_is_named(preview: object) -> None:
    with pytest.raises(SettingsError, match="preview"):
        invert(ONE_ZERO, smoothstep(1.0, 4.0, 6), preview=preview)


def test_preview_belongs_to_the_automatic_choice_or_stable_inversion() -> None:
    with pytest.raises(SettingsError, match="preview"):
        invert(ONE_ZERO, smoothstep(1.0, 12.0, 6), method="ssef", preview=1.0)


def test_method_ssef_keeps_the_family_alone() -> None:
    with pytest.raises(InversionError) as caught:
        invert(IMAGINARY, smoothstep(1.0, 12.0, 6), method="ssef", period=0.02)
    assert "optimal-control feedforward:" not in str(caught.value)


def test_the_command_line_names_the_method_and_the_stages(tmp_path, capsys) -> None:
    code = main(["invert", "(2 - s)/((s + 1)(s + 3))", "--trajectory", "smoothstep:1:4:6", "--preview", "4", "--out", str(tmp_path)])
    out = capsys.readouterr().out
    assert code == 0
    first, second = out.splitlines()[:2]
    assert "stable inversion" in first
    assert "automatic choice across methods" in second
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["method"] == "stable" and [st["method"] for st in summary["auto"]["stages"]] == ["ssef", "stable"]
    assert main(["invert", "(2 - s)/((s + 1)(s + 3))", "--trajectory", "smoothstep:1:4:6", "--out", str(tmp_path)]) == 2
    assert "no causal feedforward from rest" in capsys.readouterr().err


def _system(tf):
    from inversion.lti.linear_system import as_linear_system

    return as_linear_system(tf)


def test_a_preview_on_the_paper_s_case_lets_stable_inversion_compete() -> None:
    # hyperbolic (real zeros): the paper's member and stable inversion truncated to 1 s, the least peak torque returned
    result = invert(modelgen.load("hyperbolic"), smoothstep(1.57, 5.5, 5), preview=1.0)
    stages = result.summary["auto"]["stages"]
    assert [st["method"] for st in stages[:2]] == ["ssef", "stable"] and stages[0]["status"] == stages[1]["status"] == "passed"
    # both need more than 5 % above the least peak (stable 0.4005 N m, the member 0.4034, the least 0.2992): optimal
    # control is asked too (0.3142, both holding EI within 50 %) and returned
    assert [st["method"] for st in stages] == ["ssef", "stable", "ocp"] and result.summary["method"] == "ocp"


def test_a_move_beyond_the_bounded_limit_is_refused_before_optimal_control_is_solved() -> None:
    # (s^2 + 0.2 s + 9)/((s + 1)^2 (s + 2)^2), 1 in 2 s held at 20 ms: neither IPOPT nor HiGHS settled the programme, and
    # the refusal said only that. The bounded causal limit (a chain programme, solved first) proves no input within 3 x the
    # static need and its rate bound holds the output within 1 %: it errs by 48.6 % at least. That is the reason, given
    # before any solve, with the duration the same move would need within the same bounds
    with pytest.raises(InversionError) as info:
        invert(sg.TransferFunction([1.0, 0.2, 9.0], [1.0, 6.0, 13.0, 12.0, 4.0]), smoothstep(1.0, 2.0, 3), method="ocp", period=0.02)
    text = str(info.value)
    assert text.startswith("no causal feedforward within the bounds exists: held at 20 ms")
    assert "optimal-control feedforward does not exist" not in text  # no solve was tried
    bounded = info.value.bounded_limit  # type: ignore[attr-defined]
    assert bounded["period"] == 0.02 and bounded["bound"] == pytest.approx(0.01) and bounded["relative_error"] > 0.4
    assert bounded["shortest_duration"] is not None and bounded["shortest_duration"] > 2.0
    assert f"and {bounded['shortest_duration']:.3g} s meets it" in text


def test_a_move_no_table_can_hold_is_refused_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    # issue 46: paper-sim's 1 in 1e6 s went on to an optimal-control programme of 400 000 rows 2.5 s apart (86 CPU-s, 2 GB,
    # no output): its table at 1 kHz would have 1e9 rows, a hundred times what one result holds. Refused before any
    # programme is built (measured 0.02 s)
    import inversion.chain.programme as programme

    def never(*args: object, **kwargs: object) -> None:
        raise AssertionError("a chain programme was built")

    monkeypatch.setattr(programme.Chain, "stages", never)
    from inversion import SettingsError

    with pytest.raises(SettingsError, match=r"^rate = 1000\.0 is not accepted; expected at most 10 Hz for this trajectory"):
        invert(modelgen.load("paper-sim"), smoothstep(1.0, 1e6, 5))
