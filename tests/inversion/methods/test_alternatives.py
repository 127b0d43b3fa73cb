"""The limit and the methods users pick instead (issue 21): the optimal-control feedforward and input shaping,
judged like every result, and each checked against an independent computation."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.signal as sg
from scipy.integrate import solve_ivp
from scipy.interpolate import PPoly

import modelgen
from inversion import InversionError, SettingsError, invert, smoothstep, trajectory_from_spec
from inversion.studies.compare import COMPARE_COLUMNS, METHODS, residual_vibration
from modelgen.joint_pd import rule_gains
from inversion.methods.shaping import _closed_loop, _Loop, closed_loop_modes, convolve, shaper
from inversion.lti.system import NormalForm
from inversion.signals.trajectory import CallableTrajectory
from sflm.cli import main

DATA = Path(__file__).resolve().parents[2] / "data"
STEEL_MOVE = smoothstep(0.5, 0.6, 2)


@pytest.fixture(scope="module")
def steel_ocp(steel):  # type: ignore[no-untyped-def]
    return invert(steel, STEEL_MOVE, method="ocp", period=0.01, controller="none")  # its own properties: the feedforward alone


# ----------------------------------------------------------------------------------------------------------------
# the optimal-control feedforward


def _zoh_tip(model, tau: np.ndarray, period: float, steps: int, refine: int = 1):  # type: ignore[no-untyped-def]
    """The tip of scipy.signal's ZOH discretisation of the linear plant, driven by the held ``tau`` (zero after it) from
    rest for ``steps`` periods, sampled ``refine`` times a period (an independent discretisation)."""
    A, B, C = np.asarray(model.A), np.asarray(model.B).reshape(-1, 1), np.asarray(model.C_out).reshape(1, -1)
    Ad, Bd, *_ = sg.cont2discrete((A, B, C, np.zeros((1, 1))), period / refine, method="zoh")
    x = np.zeros(A.shape[0])
    out = []
    for k in range(steps):
        u = float(tau[k]) if k < tau.size else 0.0
        for _ in range(refine):
            out.append(float((C @ x)[0]))
            x = Ad @ x + Bd[:, 0] * u
    out.append(float((C @ x)[0]))
    return np.asarray(out)


def test_the_optimal_control_feedforward_keeps_the_tip_within_its_bound_at_every_sample(steel, steel_ocp) -> None:  # type: ignore[no-untyped-def]
    # issue 21: the tip within max_error (default 1 % of the move) at the samples of the held table, during the move and for
    # the after-end window with the torque ended -- on an independent ZOH discretisation (scipy.signal)
    s = steel_ocp.summary
    period, E = 0.01, 0.01 * 0.5
    K = int(round(0.6 / period))
    window = s["verification"]["after_end"]["window"]
    tip = _zoh_tip(steel, steel_ocp.tau, period, K + int(round(window / period)))
    t = np.arange(tip.size) * period
    assert np.abs(tip - STEEL_MOVE.derivative(np.clip(t, 0, 0.6), 0)).max() <= E * (1 + 1e-6)
    assert steel_ocp.tau.size == K and np.allclose(np.diff(steel_ocp.t), period)  # one held value a period
    # its peak is the one reported, and the bound is active (an optimum: the error sits on it somewhere) -- between the
    # rows, where the held plant strays a little beyond its value at them (the rows are held inside the bound for it)
    assert np.abs(steel_ocp.tau).max() == pytest.approx(s["peak_torque"], rel=1e-12)
    assert np.abs(tip[: K + 1] - STEEL_MOVE.derivative(t[: K + 1], 0)).max() <= E
    # margin by default (issue 47): the tube is 0.9 of the bound where the bounded limit leaves room, the optimum on it
    assert s["margin"]["aimed"] == pytest.approx(0.9 * E, rel=1e-12) and s["ocp"]["margin"] == 0.1
    assert s["ocp"]["max_error_between_samples"] == pytest.approx(0.9 * E, rel=1e-4)
    assert s["ocp"]["status"] == "solved" and s["ocp"]["solver"] == "hpipm" and s["pre_actuation_time"] == 0.0
    # the figure between the samples is what the plant does there (sampled ten times a period)
    fine = _zoh_tip(steel, steel_ocp.tau, period, K, refine=10)
    t_fine = np.arange(fine.size) * period / 10
    assert np.abs(fine - STEEL_MOVE.derivative(t_fine, 0)).max() == pytest.approx(s["ocp"]["max_error_between_samples"], rel=2e-2)


def test_the_optimal_control_peak_is_below_every_verified_member_at_the_same_bound(steel, steel_ocp) -> None:  # type: ignore[no-untyped-def]
    # the OCP is the limit of any causal feedforward on the model at its period: the automatic member within the same 1 %
    # bound (its acceptance includes the held plant at 1 ms) cannot need less peak torque. Measured: OCP 5.41 N m
    # (0.78 x the rigid 6.93), the automatic member 7.2 N m.
    member = invert(steel, STEEL_MOVE)
    assert member.summary["relative_redefinition_error"] <= 0.01
    assert steel_ocp.summary["peak_torque"] <= member.summary["peak_torque"]
    assert 0.5 < steel_ocp.summary["torque_ratio"] < 1.0  # below the rigid need: the flexibility helps, as the issue measured


def test_the_energy_objective_spends_less_energy_and_more_peak(steel, steel_ocp) -> None:  # type: ignore[no-untyped-def]
    energy = invert(steel, STEEL_MOVE, method="ocp", period=0.01, controller="none", objective="energy")
    assert np.sum(energy.tau**2) <= np.sum(steel_ocp.tau**2) * (1 + 1e-6)
    assert np.abs(energy.tau).max() >= steel_ocp.summary["peak_torque"] * (1 - 1e-6)


def test_a_rest_end_brings_the_link_to_rest(steel) -> None:  # type: ignore[no-untyped-def]
    r = invert(steel, STEEL_MOVE, method="ocp", period=0.01, controller="none", end="rest")
    after = r.summary["verification"]["after_end"]
    assert after["max_tip_excursion"] <= 1e-6 * 0.5 and abs(after["drift"]) <= 1e-6


def test_a_bound_below_the_causal_limit_is_refused_before_any_solve(steel) -> None:  # type: ignore[no-untyped-def]
    # a 0.5 m move in 0.05 s within 0.1 mm: no causal feedforward from rest holds it closer than 38 % of the move
    # (docs/method.md section 7), so the optimal-control problem is not even set up
    with pytest.raises(InversionError, match=r"no causal feedforward from rest can hold this move closer than .*38\.\d % of the move"):
        invert(steel, smoothstep(0.5, 0.05, 2), method="ocp", period=0.01, controller="none", max_error=1e-4)


def test_an_infeasible_bound_is_refused_by_the_bounded_limit_or_by_hpipm_with_its_figures(steel) -> None:  # type: ignore[no-untyped-def]
    # above the causal limit (1.41 cm for 0.5 m in 0.2 s) but held at 10 ms within the torque and rate bounds: no table
    # comes closer than 4.274 cm (the bounded causal limit, solved first): refused without a solve, with the duration
    move = smoothstep(0.5, 0.2, 2)
    with pytest.raises(InversionError, match=r"^no causal feedforward within the bounds exists: .*0\.04274 \(8\.55 % of the move\).*"
                       r"more than 0\.2 s, and 0\.204 s meets it"):
        invert(steel, move, method="ocp", period=0.01, controller="none", max_error=0.0423, end="rest")
    # just above it no table held after the move reaches the bound either (the bounded limit lets the input run on after
    # the move): HPIPM stopped at its least step ending at rest, then the least tube any table within the torque bound
    # holds the tip in, the end free, is asked once and refuses the move with its figure (issue 60, item 3)
    with pytest.raises(InversionError, match=r"no table within the torque bound 187\.1, held after the move, keeps the tip within "
                       r"0\.0428 of y_d: the least tube any holds it in is 0\.0436\d \(1\.02 x the bound.*no causal feedforward from rest"):
        invert(steel, move, method="ocp", period=0.01, controller="none", max_error=0.0428, end="rest")
    assert invert(steel, move, method="ocp", period=0.01, controller="none", max_error=0.05, end="rest").summary["ocp"]["status"] == "solved"


@pytest.mark.parametrize("given", [{"segments": 3}, {"cdec": (1e-3, 1.0)}, {"objective": "error"}, {"edges": "rest"}])
def test_the_optimal_control_refuses_member_settings(steel, given) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(SettingsError, match=next(iter(given))):
        invert(steel, STEEL_MOVE, method="ocp", period=0.01, controller="none", **given)


def test_a_torque_bound_judges_the_optimal_control_feedforward_like_any_other(steel) -> None:  # type: ignore[no-untyped-def]
    # its least peak torque within 1 % is 5.42 N m: within 3 N m no held table comes closer than 24.8 % of the move (the
    # bounded causal limit, the acceptance's bounds at the controller's period), refused before the solve
    with pytest.raises(InversionError, match=r"torque within 3 .* closer than 0\.1239 \(24\.8 % of the move\)"):
        invert(steel, STEEL_MOVE, method="ocp", period=0.01, controller="none", max_torque=3.0)


# ----------------------------------------------------------------------------------------------------------------
# input shaping


def test_shapers_have_their_closed_forms() -> None:
    # Singer & Seering (1990): ZV = [1, K] / (1 + K) at [0, T_d / 2]; ZVD = [1, 2K, K^2] / (1 + K)^2 at [0, T_d / 2, T_d],
    # K = exp(-zeta pi / sqrt(1 - zeta^2)), T_d = 2 pi / omega_d
    omega, zeta = 20.0, 0.1
    K = math.exp(-zeta * math.pi / math.sqrt(1 - zeta**2))
    half = math.pi / (omega * math.sqrt(1 - zeta**2))
    a, t = shaper("zv", omega, zeta)
    np.testing.assert_allclose(a, [1 / (1 + K), K / (1 + K)], rtol=1e-15)
    np.testing.assert_allclose(t, [0, half], rtol=1e-15)
    a, t = shaper("zvd", omega, zeta)
    np.testing.assert_allclose(a, np.array([1, 2 * K, K * K]) / (1 + K) ** 2, rtol=1e-15)
    np.testing.assert_allclose(t, [0, half, 2 * half], rtol=1e-15)
    a, t = shaper("zvd", 2 * math.pi, 0.0)  # undamped 1 Hz: a quarter, a half, a quarter, 0.5 s apart
    np.testing.assert_allclose(a, [0.25, 0.5, 0.25], rtol=1e-15)
    np.testing.assert_allclose(t, [0.0, 0.5, 1.0], rtol=1e-15)


@pytest.mark.parametrize("kind", ["zv", "zvd"])
@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.3])
def test_a_shaper_leaves_its_mode_no_residual_vibration(kind: str, zeta: float) -> None:
    # the residual vibration of a second-order mode after the impulses (Singer & Seering's V): sum A_i e^{-lambda t_i} = 0
    # for lambda = -zeta omega + i omega_d; ZVD also zeroes its derivative in omega (robust to a frequency error)
    omega = 30.0
    a, t = shaper(kind, omega, zeta)
    assert a.sum() == pytest.approx(1.0, rel=1e-15) and np.all(a > 0)

    def residual(w: float) -> float:
        lam = complex(-zeta * w, w * math.sqrt(1 - zeta**2))
        return abs(np.sum(a * np.exp(-lam * t)))

    assert residual(omega) <= 1e-14
    # 5 % off in frequency: ZV's residual is first order in the error (about pi/2 x 0.05), ZVD's second order
    if kind == "zv":
        assert 0.05 < residual(omega * 1.05) < 0.15
    else:
        assert residual(omega * 1.05) < 0.2 * shaper_residual("zv", omega, zeta, 1.05)


def shaper_residual(kind: str, omega: float, zeta: float, ratio: float) -> float:
    a, t = shaper(kind, omega, zeta)
    w = omega * ratio
    lam = complex(-zeta * w, w * math.sqrt(1 - zeta**2))
    return abs(np.sum(a * np.exp(-lam * t)))


def test_two_shapers_in_series_merge_their_impulses() -> None:
    a, t = convolve(shaper("zv", 2 * math.pi), shaper("zv", 2 * math.pi))  # two 0.5 s ZVs: the ZVD of the same mode
    np.testing.assert_allclose(a, [0.25, 0.5, 0.25], rtol=1e-15)
    np.testing.assert_allclose(t, [0.0, 0.5, 1.0], rtol=1e-15)


@pytest.mark.parametrize("given", [(0.0, 0.1), (-1.0, 0.1), (10.0, 1.0), (math.nan, 0.1)])
def test_a_shaper_refuses_a_mode_out_of_range(given) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(SettingsError, match="frequency"):
        shaper("zv", *given)


def test_the_shaped_loop_is_exact(steel) -> None:  # type: ignore[no-untyped-def]
    # the nominal closed loop in the phi-function form against an independent stiff ODE integration of x' = A_cl x + B u(t)
    form = NormalForm.of_model(steel)
    J = float(steel.M[0, 0])
    kp, kd = rule_gains(J, 2 * math.pi * float(steel.natural_frequencies_hz[0]))
    omega, zeta = closed_loop_modes(form, kp, kd, steel.n)[1]
    loop = _Loop(form, STEEL_MOVE, shaper("zv", omega, zeta), (J, form.joint_damping, kp, kd), 1.0)
    A = _closed_loop(form, kp, kd)
    # u(t) = sum_i a_i (J theta'' + (b + k_D) theta' + k_P theta)(t - d_i), theta = y_d / x_out (x_out = 1 here), from the
    # move's own polynomial: one piecewise polynomial, shifted by each impulse's delay (not the loop's reference)
    pp = STEEL_MOVE.ppoly
    degree = pp.c.shape[0]
    coefficients = kp * pp.c
    for order, gain in ((1, form.joint_damping + kd), (2, J)):
        coefficients[order:] += gain * pp.derivative(order).c
    law = PPoly(coefficients, pp.x)
    ends = (kp * float(pp(STEEL_MOVE.t0)), kp * float(pp(STEEL_MOVE.tf)))  # at rest before and after the move
    amplitudes, delays = shaper("zv", omega, zeta)
    assert degree == 6 and np.array_equal(amplitudes, loop.amplitudes) and np.array_equal(delays, loop.delays)

    def u(t: float) -> float:
        total = 0.0
        for a, d in zip(amplitudes, delays):
            s = t - d
            total += a * (ends[0] if s < STEEL_MOVE.t0 else ends[1] if s > STEEL_MOVE.tf else float(law(s)))
        return total

    t_eval = np.linspace(0.0, 1.5, 301)
    sol = solve_ivp(lambda t, x: A @ x + form.B * u(t), (0.0, 1.5), np.zeros(form.n_states), method="Radau", t_eval=t_eval,
                    rtol=1e-11, atol=1e-13, max_step=2e-3, jac=A)  # the exact Jacobian: no differenced columns
    X = loop.sampled(t_eval)
    assert np.abs(X - sol.y.T).max() <= 1e-8 * np.abs(sol.y).max()


def test_shaping_removes_the_shaped_modes_vibration(steel) -> None:  # type: ignore[no-untyped-def]
    # after the shaped reference ends, the shaped mode's transient is gone (exactly, on the nominal loop); unshaped it rings
    r = invert(steel, STEEL_MOVE, method="zv", max_error=0.5)
    sh = r.summary["shaping"]
    assert sh["unshaped_residual_vibration"] > 1e-5  # measured 7.8e-5 m
    assert sh["residual_vibration"] <= 1e-10 * sh["unshaped_residual_vibration"] + 1e-15
    assert r.summary["settings"]["modes"][0]["frequency"] == pytest.approx(102.345, rel=1e-4)  # the ringing mode (zeta 0.068)
    assert sh["shaper_duration"] == pytest.approx(math.pi / (102.345 * math.sqrt(1 - 0.0684**2)), rel=1e-3)


def test_the_shaped_result_drives_the_closed_loop_to_its_nominal_output(steel) -> None:  # type: ignore[no-untyped-def]
    # the two-degree-of-freedom form: the linear plant in the closed loop with the result's torque and joint references
    # follows the nominal loop's output (the PD's nominal terms cancel)
    from simulation import simulate

    r = invert(steel, STEEL_MOVE, method="zvd", max_error=0.5)
    sim = simulate(steel, r, plant="linear", controller="pd", t_end=float(r.t[-1]), rate=1000.0)
    y = np.interp(sim.t, r.t, r.y)
    assert np.abs(sim.y - y).max() <= 1e-6 * 0.5


def test_shaping_fails_when_the_tip_strays_beyond_the_bound(steel) -> None:  # type: ignore[no-untyped-def]
    # the steel strip's fast move: a shaped reference lags the desired one (measured 15 % of the move for ZV)
    with pytest.raises(InversionError, match=r"0\.153 of the move.*does not shape the deflection"):
        invert(steel, STEEL_MOVE, method="zv")


def test_shaping_refuses_what_it_cannot_shape(steel) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(SettingsError, match="link model"):
        invert(([[0.0, 1.0], [-4.0, -0.4]], [[0.0], [1.0]], [[1.0, 0.0]]), smoothstep(1.0, 2.0, 3), method="zv")
    with pytest.raises(SettingsError, match="segments"):
        invert(steel, STEEL_MOVE, method="zvd", segments=3)
    with pytest.raises(SettingsError, match="end"):
        invert(steel, STEEL_MOVE, method="zv", end="rest")
    cosine = CallableTrajectory(lambda t, k: 0.25 * (1 - np.cos(np.pi * t / 0.6)) if k == 0 else
                                0.25 * (np.pi / 0.6) ** k * np.cos(np.pi * t / 0.6 - (k + 1) * np.pi / 2), 0.0, 0.6, 8)
    with pytest.raises(SettingsError, match="piecewise polynomial"):
        invert(steel, cosine, method="zv")


# ----------------------------------------------------------------------------------------------------------------
# the comparison


def test_compare_has_the_alternatives_and_their_seconds(steel, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    # (the columns are extended at their end, never renamed: issue 57 added the move's duration and its certified bound)
    assert METHODS[-4:] == ("ocp", "zv", "zvd", "replan") and COMPARE_COLUMNS[-7:] == ("seconds", "worst_case_error", "period", "hold",
                                                                               "held_tip_error", "duration", "certified_lower_bound")
    # at the bound itself (--margin 0): the limits compared, not the margins kept
    code = main(["compare", str(DATA / "steel-strip.toml"), "--trajectory", "smoothstep:0.5:0.6:2", "--margin", "0", "--out", str(tmp_path),
                 "--plot"])
    assert code == 0
    import csv

    rows = {row["method"]: row for row in csv.DictReader(open(tmp_path / "compare.csv"))}
    assert set(rows) == set(METHODS)
    assert rows["ocp"]["status"] == "ok" and float(rows["ocp"]["peak_torque"]) < float(rows["ssef"]["peak_torque"])
    assert rows["zv"]["status"] == "failed" and "shaped" in rows["zv"]["message"]
    # the re-planned output: near the held optimal-control table's peak, below the family's
    assert rows["replan"]["status"] == "ok"
    assert float(rows["replan"]["peak_torque"]) < min(1.1 * float(rows["ocp"]["peak_torque"]), float(rows["ssef"]["peak_torque"]))
    assert all(float(row["seconds"]) >= 0 for row in rows.values())
    assert (tmp_path / "compare.png").stat().st_size > 10_000


def test_the_residual_vibration_of_a_held_table_holds_its_last_row(steel, steel_ocp) -> None:  # type: ignore[no-untyped-def]
    # the OCP's table ends a period before t_f; its last torque is held until t_f, then the link is free: within the bound
    # (at the samples; between them, measured, 0.3 % beyond it). Unheld, the figure was 0.131 m.
    vibration = residual_vibration(steel_ocp)
    assert vibration <= 2 * 0.005 * 1.02
    # the table of least peak with its traces of variation and energy leaves the link nearly at rest (measured 5e-10 m)
    assert vibration == pytest.approx(2 * steel_ocp.summary["verification"]["after_end"]["max_tip_excursion"], rel=0.05,
                                      abs=1e-8)


def test_the_rigid_need_includes_the_hub_damping() -> None:
    # paper-exp has b_h = 0.32 N m s/rad (its Table 1): a rigid link's need along y_d is J yddot + b ydot, over L
    model = modelgen.load("paper-exp")
    trajectory = trajectory_from_spec("paper-exp")
    g = model.geometry
    assert g.hub_viscous_damping > 0
    J = g.hub_inertia + g.linear_density * g.length**3 / 3 + g.payload_mass * g.length**2 + g.payload_inertia
    t = np.linspace(trajectory.t0, trajectory.tf, 200_001)
    need = np.abs(J * trajectory.derivative(t, 2) + g.hub_viscous_damping * trajectory.derivative(t, 1)).max() / g.length
    form = NormalForm.of_model(model)
    assert form.joint_damping == pytest.approx(g.hub_viscous_damping, rel=1e-6)  # the Rayleigh share is the flexible modes'
    r = invert(model, trajectory, method="ocp", period=0.01, controller="none")
    assert r.summary["rigid_torque"] == pytest.approx(need, rel=1e-6)


def test_a_system_without_zeros_gets_its_limit_or_a_clear_refusal() -> None:
    # a rigid link (a double integrator): no internal dynamics. The optimal control solves it -- its peak for a cubic move
    # of 1 in 1 s within 1 % is below the exact inverse's 6 (|yddot_d| at the ends); the exponential family is refused by name
    A, B, C = np.array([[0.0, 1.0], [0.0, 0.0]]), np.array([[0.0], [1.0]]), np.array([[1.0, 0.0]])
    r = invert((A, B, C), smoothstep(1.0, 1.0, 2), method="ocp", period=0.01)
    assert 3.0 < r.summary["peak_torque"] < 6.0 and r.summary["relative_redefinition_error"] <= 0.01 * (1 + 1e-6)
    for method in ("ssef", "polynomial", "stable"):
        with pytest.raises(SettingsError, match="without zeros"):
            invert((A, B, C), smoothstep(1.0, 1.0, 2), method=method)


def test_the_chain_programme_s_record_is_in_the_summary(steel, steel_ocp) -> None:  # type: ignore[no-untyped-def]
    # HPIPM's status, iterations and residuals (the scaled programme's, within its tolerance of 1e-12): no clock, no
    # attempts of other solvers
    record = steel_ocp.summary["ocp"]
    assert record["solver"] == "hpipm" and record["status"] == "solved" and 10 <= record["iterations"] <= 300
    assert max(record["residuals"].values()) <= 1e-12 and record["attempts"] == []
