"""The re-planned output: the move reshaped within its bound so that it is exactly and causally invertible."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.interpolate import make_interp_spline
from scipy.signal import lti

import modelgen
from _helpers import run_cli
from inversion import CallableTrajectory, InversionError, SettingsError, invert, smoothstep
from inversion.methods import replan
from inversion.methods.ocp import ocp_inversion
from inversion.lti.system import normal_form

ROOT = Path(__file__).resolve().parents[3]
STRIP = ROOT / "tests/data/steel-strip.toml"


@pytest.fixture(scope="module")
def strip() -> tuple[modelgen.Model, object, float]:
    # the steel strip's fast move (issue 34): zeros 66.15 and 176.4, 0.5 m in 0.6 s, the bound 1 % of the move
    return modelgen.load(str(STRIP)), smoothstep(0.5, 0.6, 2), 0.005


@pytest.fixture(scope="module")
def planned(strip):  # type: ignore[no-untyped-def]
    model, move, bound = strip
    return replan.replanned_output(normal_form(model), move, bound)


def test_the_output_stays_in_its_tube_and_starts_and_ends_as_the_move(strip, planned) -> None:  # type: ignore[no-untyped-def]
    model, move, bound = strip
    t = np.linspace(move.t0, move.tf, 20001)
    deviation = planned.output.derivative(t, 0) - move.derivative(t, 0)
    # the programme holds the tube at its grid's points; between them the splines overshoot it by a hair, never the bound
    assert np.abs(deviation).max() <= min(replan.TUBE * bound * (1 + 1e-3), bound)
    assert np.abs(deviation).max() >= 0.5 * bound  # it does reshape the move: the saving comes from the tube
    for k in range(5):  # y_r and four derivatives are y_d's at both ends: the input starts and ends continuous
        for at, side in ((move.t0, "+"), (move.tf, "-")):
            scale = np.abs(move.derivative(t, k)).max()
            assert abs(planned.output.derivative([at], k, side)[0] - move.derivative([at], k, side)[0]) <= 1e-9 * scale


def test_its_unstable_modes_start_at_zero_by_independent_quadrature(strip, planned) -> None:  # type: ignore[no-untyped-def]
    # the condition of a causal inverse from rest (docs/method.md section 7): int e^{-lambda t} yddot_r dt = 0 at every zero
    # with Re lambda > 0 -- checked with SciPy's adaptive quadrature, against the same integral of y_d (which is not zero)
    model, move, _ = strip
    for zero in [z for z in normal_form(model).modal(0.0).lam if z.real > 0]:
        def moment(output, zero=zero):  # type: ignore[no-untyped-def]
            return quad(lambda t: np.exp(-zero.real * t) * output.derivative([t], 2)[0], move.t0, move.tf, limit=400,
                        points=list(output.breakpoints)[:300])[0]
        assert abs(moment(move)) > 1e-3
        assert abs(moment(planned.output)) <= 1e-6 * abs(moment(move))  # HiGHS's tolerance, then the quadrature's


def test_the_plant_driven_by_its_torque_follows_the_replanned_output(strip) -> None:  # type: ignore[no-untyped-def]
    # the defining property, by an independent integration of the model (P9) from rest with the samples' torque
    model, move, bound = strip
    result = invert(model, move, method="replan", max_error=bound)
    torque = make_interp_spline(result.t, result.tau, k=3)
    sol = solve_ivp(lambda t, x: model.A @ x + model.B * torque(t), (result.t[0], result.t[-1]), np.zeros(model.A.shape[0]),
                    t_eval=result.t, method="DOP853", rtol=1e-10, atol=1e-13, max_step=1e-3)
    y = sol.y[: model.n + 1].T @ model.D
    assert np.abs(y - result.y).max() <= 0.02 * bound  # the plant is on y_r ...
    assert np.abs(y - result.y_d).max() <= bound  # ... and y_r within the bound of y_d
    assert result.t[0] == move.t0 and abs(result.tau[0]) <= 1e-4  # causal: nothing before t0, no step at it
    assert result.summary["method"] == "replan" and result.summary["pre_actuation_time"] == 0.0


def test_it_is_near_the_optimal_control_limit_and_below_the_family(strip) -> None:  # type: ignore[no-untyped-def]
    # benchmarks/bench_ocp.py's case: the family's least peak within 1 % is 7.72 N m, 1.42 x the optimal-control limit
    # held at 10 ms (5.42 N m); the issue asks for 1.10 x at equal error
    # (at the bound itself: margin=0; the default keeps 10 % of it free, and is near the limit at its own tube)
    model, move, bound = strip
    replanned = invert(model, move, method="replan", max_error=bound, margin=0).summary["peak_torque"]
    family = invert(model, move, method="ssef", auto=True, objective="torque", max_error=bound).summary["peak_torque"]
    limit = ocp_inversion(model, move, period=0.01, max_error=bound).summary["peak_torque"]
    assert replanned <= 1.10 * limit
    assert replanned <= 0.8 * family
    inside = invert(model, move, method="replan", max_error=bound).summary
    assert inside["margin"]["aimed"] == pytest.approx(0.9 * bound) and inside["sampled"]["max_tip_error"] <= 0.9 * bound
    # measured: 6.64 N m, 1.21 x the limit at the same tube (5.48 N m) -- the point hold's lag is a larger share of a
    # narrower tube -- and 1.14 x its own peak at the bound (5.83 N m): the margin's cost, which the summary reports
    assert inside["peak_torque"] <= 1.25 * ocp_inversion(model, move, period=0.01, max_error=0.9 * bound).summary["peak_torque"]


def test_one_programme_allows_for_the_hold_s_lag(strip) -> None:  # type: ignore[no-untyped-def]
    # the tube starts narrower by max |ydot_d| DT / 2 (a point hold at 1 ms lags the input by half a period): the held
    # rows fall inside the bound at the first programme (before: 1.126 x the bound, then a second programme at 0.805)
    model, move, bound = strip
    summary = invert(model, move, method="replan", max_error=bound, margin=0).summary
    lag = 0.5e-3 * np.abs(move.derivative(np.linspace(0.0, 0.6, 4001), 1)).max()  # 1.875 x 0.5 m / 0.6 s x 0.5 ms
    assert lag == pytest.approx(1.875 * 0.5 / 0.6 * 0.5e-3, rel=1e-6)
    (only,) = summary["replan"]["tubes"]
    assert only["tube"] == pytest.approx(0.98 * bound - lag) and only["held_tip_error"] <= 0.98 * bound
    assert summary["sampled"]["max_tip_error"] <= bound


def test_the_automatic_choice_replans_before_optimal_control(strip, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    # where no member of the family passes, the re-planned output is the next stage; optimal control is asked too only
    # where the re-plan's peak is beyond the tolerance above the least any causal table can have (issue 60, item 6)
    import dataclasses

    import inversion.family.method as family
    import inversion.methods.automatic as automatic

    model, move, _ = strip

    def no_member(*args, **kwargs):  # type: ignore[no-untyped-def]
        raise InversionError("no member of the family passes (planted)")

    monkeypatch.setattr(family, "ssef_inversion", no_member)
    result = invert(model, move)
    stages = {stage["method"]: stage for stage in result.summary["auto"]["stages"]}
    least = result.summary["auto"]["least_peak"]
    # measured: the re-plan 6.637 N m, optimal control 5.847, no table within the tube below 5.523
    assert [(name, stage["status"]) for name, stage in stages.items()] == [("ssef", "failed"), ("replan", "passed"), ("ocp", "passed")]
    replanned, optimal = stages["replan"]["peak_torque"], stages["ocp"]["peak_torque"]
    assert least["peak_torque"] <= optimal < replanned / 1.05 and replanned > 1.05 * least["peak_torque"]
    # the cheaper table is returned only where it tolerates at least half the plant error the re-plan's does
    robust = least["robustness"]
    (_, replan_tolerates), (_, ocp_tolerates) = [(t["method"], t["tolerated"]) for t in robust["tables"]]
    kept = "ocp" if ocp_tolerates >= 0.5 * replan_tolerates else "replan"
    assert result.summary["method"] == robust["kept"] == kept and stages[kept]["chosen"]
    # within a wider tolerance the re-plan is kept, and optimal control is not run at all
    monkeypatch.setattr(automatic, "DEFAULTS", dataclasses.replace(automatic.DEFAULTS, torque_tolerance=0.25))
    result = invert(model, move)
    stages = {stage["method"]: stage for stage in result.summary["auto"]["stages"]}
    assert result.summary["method"] == "replan" and list(stages) == ["ssef", "replan"]


def test_a_move_beyond_the_rate_bound_is_refused_with_what_it_would_need() -> None:
    # the 3 mm strip's 0.6 s move: within 1 % its causal inverse must change its torque about 9 x as fast as the bound
    # allows (issue 34's cliff; the optimal-control feedforward needed 100 x the bound's rate as well)
    from inversion.methods.replan import replanned_inversion

    model = modelgen.load(str(ROOT / "tests/data/steel-strip-3mm.toml"))
    with pytest.raises(InversionError, match="as fast as the bound allows"):
        replanned_inversion(model, smoothstep(0.5, 0.6, 2), max_error=0.005)
    # through invert, the bounded causal limit (1.46 % at best within the bounds) refuses it before the programme
    with pytest.raises(InversionError, match="^no causal feedforward within the bounds exists") as caught:
        invert(model, smoothstep(0.5, 0.6, 2), method="replan")
    assert "no causal feedforward from rest can hold this move closer than" in str(caught.value)


def test_a_refusal_tries_the_widest_tube_once_and_explains_only_it(monkeypatch: pytest.MonkeyPatch) -> None:
    # issue 56 / 60: own-aluminium's 2 s move (its rate bound binds) took 106 s to refuse -- three tubes (the margin's,
    # half of it, the bound's), each failure explained by two programmes more: 12 linear programmes. The margin's tube,
    # then the widest (where it fails every narrower one does) with its explanation: 6, and the same refusal
    from inversion import Problem

    import scipy.optimize

    calls = []
    solve = replan._solve
    monkeypatch.setattr(replan, "_solve", lambda *args: calls.append(1) or solve(*args))
    methods = []
    linprog = scipy.optimize.linprog
    monkeypatch.setattr(scipy.optimize, "linprog", lambda *args, **kw: methods.append(kw.get("method")) or linprog(*args, **kw))
    model = modelgen.load(str(ROOT / "tests/data/own-aluminium.toml"))
    with pytest.raises(InversionError) as caught:
        invert(Problem(model, smoothstep(0.5, 2.0, 2)), method="replan")
    message = str(caught.value)
    assert message.startswith("no re-planned output within 0.005 m of y_d meets the conditions of a causal inverse from rest "
                              "within the bound on the change between rows"), message
    assert "without the bound on the input's change it exists, changing 1.66 x as fast as the bound allows" in message
    assert len(calls) <= 6, len(calls)
    # every programme answered by the interior point: the first, as given (rows of 1e-8 to 2e4), stops at its iteration
    # limit, and with its rows of unit size it is found infeasible in 17 iterations; before, the dual simplex after it
    # ran 12 s to "numerical difficulties"
    assert "highs-ds" not in methods and methods.count("highs-ipm") == len(calls) + 1, methods


def test_unit_rows_keep_the_set_and_drop_only_rows_every_point_meets() -> None:
    from scipy import sparse

    rng = np.random.default_rng(3)
    A = rng.standard_normal((6, 4)) * np.array([1e-8, 1.0, 2e4, 3.0, 1.0, 1.0])[:, None]
    A[4] = 0.0  # 0 <= 1: every x meets it, dropped
    A[5] = 0.0  # 0 <= -1: no x meets it, kept (the programme stays infeasible)
    b = np.array([1e-8, 0.5, -3e3, 1.0, 1.0, -1.0])
    scaled, rhs = replan._unit_rows(sparse.csr_matrix(A), b)
    assert scaled.shape == (5, 4) and np.allclose(abs(scaled).max(axis=1).toarray().ravel()[:4], 1.0)
    points = rng.standard_normal((2000, 4)) * 10
    inside = np.all(points @ A[:4].T <= b[:4], axis=1)
    assert inside.any() and not inside.all()
    assert np.array_equal(inside, np.all(points @ scaled[:4].T.toarray() <= rhs[:4] + 1e-12, axis=1))
    assert rhs[4] == -1.0 and not np.any(scaled[4].toarray())  # the impossible zero row kept as it was
    equal, e = replan._unit_rows(sparse.csr_matrix(np.vstack([A[:2], np.zeros((1, 4))])), np.array([1.0, 2.0, 0.0]), drop=False)
    assert equal.shape == (3, 4) and e[2] == 0.0  # an equality's rows are all kept


def test_what_it_cannot_replan_is_refused_by_name(strip) -> None:  # type: ignore[no-untyped-def]
    model, move, _ = strip
    with pytest.raises(SettingsError, match="relative degree 2"):
        invert(lti([-1.0, 2.0], [1.0, 2.0, 1.0]), move, method="replan", max_error=1.0)  # (2 - s)/(s + 1)^2: relative degree 1
    with pytest.raises(SettingsError, match="piecewise polynomial"):
        invert(model, CallableTrajectory(lambda t, k: move.derivative(t, k), move.t0, move.tf, 6, name="a function"), method="replan")
    with pytest.raises(SettingsError, match="'settle' or 'rest'"):
        invert(model, move, method="replan", end="free")
    with pytest.raises(SettingsError, match="segments"):
        invert(model, move, method="replan", segments=3)


def test_rest_holds_every_mode_at_zero_at_the_end(strip) -> None:  # type: ignore[no-untyped-def]
    model, move, bound = strip
    result = invert(model, move, method="replan", end="rest", max_error=bound)
    assert result.summary["settings"]["end"] == "rest"
    assert abs(result.tau[np.searchsorted(result.t, move.tf)]) <= 1e-3 * result.summary["peak_torque"]


def test_the_command_line_returns_it(tmp_path: Path) -> None:
    proc = run_cli("invert", str(STRIP), "--trajectory", "smoothstep:0.5:0.6:2", "--method", "replan", "--json", "--out", str(tmp_path))
    assert proc.returncode == 0, proc.stderr[-2000:]
    summary = json.loads(proc.stdout)
    assert summary["method"] == "replan" and summary["replan"]["splines"] > 10
    assert summary["sampled"]["max_tip_error"] <= summary["bounds"]["max_error"]


def test_purely_imaginary_zeros_are_held_at_rest() -> None:
    # paper-sim's zeros include +-56.31i, whose mode neither decays forwards nor backwards: stable inversion refuses it; the
    # re-planned output holds it at zero at t_f, so nothing rings after the move (the window's excursion and drift)
    model = modelgen.load("paper-sim")
    move = smoothstep(1.0, 3.0, 2)
    assert any(abs(z.real) < 1e-9 * abs(z) for z in normal_form(model).modal(0.0).lam)
    with pytest.raises(InversionError, match="purely imaginary"):
        invert(model, move, method="stable")
    result = invert(model, move, method="replan")
    after = result.summary["verification"]["after_end"]
    assert after["max_tip_excursion"] <= 1e-3 * result.summary["max_error"] and abs(after["drift"]) <= 1e-6
    assert result.summary["sampled"]["max_tip_error"] <= result.summary["bounds"]["max_error"]
