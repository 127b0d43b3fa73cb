"""What reaches the link (issue 20): a feedforward judged by the plant a controller drives, held at its
period, after the move, with more modes, and beside the torque the move needs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.signal as sg

import modelgen
from inversion import InversionError, export_c, invert, smoothstep, trajectory_from_spec
from inversion.acceptance import Criteria, after_end, held_table, window_length
from inversion.lti.system import NormalForm
from sflm.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"


def _rigid(model: modelgen.Model, trajectory) -> float:  # type: ignore[no-untyped-def]
    """max |J yddot_d + b_h ydot_d| / L, J = I_h + rho L^3/3 + m_t L^2 + I_t: a rigid link of the same inertia and hub
    damping (METHOD.md section 6, with the hub's viscous damping)."""
    g = model.geometry
    J = g.hub_inertia + g.linear_density * g.length**3 / 3 + g.payload_mass * g.length**2 + g.payload_inertia
    t = np.linspace(trajectory.t0, trajectory.tf, 20_001)
    need = J * trajectory.derivative(t, 2) + g.hub_viscous_damping * trajectory.derivative(t, 1)
    return float(np.abs(need).max() / g.length)


def _free_tip(model, state, seconds: float, points: int = 4001):  # type: ignore[no-untyped-def]
    """The tip of the linear plant left alone from ``state`` for ``seconds`` (an independent ODE integration)."""
    from scipy.integrate import solve_ivp

    t = np.linspace(0.0, seconds, points)
    sol = solve_ivp(lambda _, x: model.A @ x, (0.0, seconds), state, t_eval=t, method="DOP853", rtol=1e-11, atol=1e-14)
    return model.C_out @ sol.y


@pytest.fixture(scope="module")
def steel_auto(steel):  # type: ignore[no-untyped-def]
    return invert(steel, smoothstep(0.5, 0.6, 2))


def test_a_steel_strip_gets_a_feedforward_it_can_apply(steel, steel_auto) -> None:  # type: ignore[no-untyped-def]
    # issue 20: a steel strip, 0.5 m in 0.6 s (its first mode 6.6 Hz). Before, the automatic choice
    # returned members whose link kept turning after t_f (6-11 cm/s) or 10-100 x the rigid need
    s = steel_auto.summary
    move = 0.5
    assert s["relative_redefinition_error"] <= 0.01 and s["torque_ratio"] <= 3
    assert s["rigid_torque"] == pytest.approx(_rigid(steel, smoothstep(0.5, 0.6, 2)), rel=1e-9)
    assert s["verification"]["after_end"]["max_tip_excursion"] <= 0.01 * move
    assert s["verification"]["truncation"]["tip_error"] <= 0.01 * move
    assert s["sampled"]["max_tip_error"] <= 0.01 * move
    # measured: a settle end, 7.26 N m (1.05 x the rigid 6.93 N m), 0.79 % of the move, 0.3 s of post-actuation
    assert steel_auto.settings.end == "settle" and s["post_actuation_time"] > 0
    # independently: the plant driven by the whole feedforward (the tail included), then left alone,
    # stays on y_d(t_f) (the closed form's torque as a spline, the plant stepped exactly; DOP853 for the 2 s after it)
    from _helpers import linear_plant_output

    y, X = linear_plant_output(steel, steel_auto)
    assert np.abs(y - steel_auto.y).max() <= 1e-6 * move
    tip = _free_tip(steel, X[-1], 2.0)
    assert np.abs(tip - 0.5).max() <= 1e-6 * move


def test_the_same_member_ending_free_would_leave_the_link_turning(steel, steel_auto) -> None:  # type: ignore[no-untyped-def]
    # the free end of the chosen member: the torque stops at t_f with the link's internal state
    # excited. Asked for, it is refused (its output strays beyond the 5 % gate after t_f), naming
    # the ends that hold it; with the gate lifted its figures are reported, and an independent
    # integration agrees with them
    with pytest.raises(InversionError, match="with the torque ended after the table, the tip strays.*end='settle' or end='rest'"):
        invert(steel, smoothstep(0.5, 0.6, 2), settings=steel_auto.settings, end="free")
    free = invert(steel, smoothstep(0.5, 0.6, 2), settings=steel_auto.settings, end="free", max_error=np.inf, max_torque_rate=np.inf)
    after = free.summary["verification"]["after_end"]
    assert after["max_tip_excursion"] > 0.01 * 0.5 and abs(after["drift"]) > 0.01
    tip = _free_tip(steel, free.X[-1], after["window"])
    assert np.abs(tip - 0.5).max() == pytest.approx(after["max_tip_excursion"], rel=1e-3)
    n1 = steel.n + 1
    assert after["drift"] == pytest.approx(steel.output_at * (steel.M[0] @ free.X[-1, n1:]) / steel.M[0, 0], rel=1e-9)


def test_a_fast_move_of_a_very_flexible_strip_is_refused_with_its_alternatives() -> None:
    # issue 20: 1.5 m of 20 x 1 mm aluminium, 0.5 m in 0.5 s (first mode 0.71 Hz): before, 13 394 N m
    # with exit 0. Issue 33: no causal feedforward from rest holds it closer than 33.7 % of the move (zeros 7.36 and
    # 19.6 1/s, docs/method.md section 7): refused at once, with the shortest duration of the same move that meets 1 %
    strip = modelgen.load(str(DATA / "flexible-strip.toml"))
    with pytest.raises(InversionError, match=r"closer than .*33\.7 % of the move") as failure:
        invert(strip, smoothstep(0.5, 0.5, 2))
    message = str(failure.value)
    assert "needs at least 2.69 s" in message and "method='stable'" in message
    # the same refusal on the command line, in one line with its flags: test_judged_to_the_end's
    # test_a_move_past_its_limit_is_refused_in_seconds_quoting_it (the same link and move)
    # a bound above the limit: within the torque and rate bounds at 1 ms no feedforward comes closer than 72.6 % of the
    # move (the bounded causal limit; its horizon's end bounded by the zero directions -- 2 s of horizon after the move give
    # the same, 0.3631975 m; with a sixth of a second and no end condition it was 61.4 %): refused before any search, with
    # the duration the same move needs within the same bounds, then the causal limit
    with pytest.raises(InversionError, match=r"^no causal feedforward within the bounds exists: .*72\.6 % of the move.*"
                                             r"0\.888 s meets it.*no causal feedforward from rest"):
        invert(strip, smoothstep(0.5, 0.5, 2), max_error=0.2)


def test_a_non_minimum_phase_system_is_refused_rather_than_diverging() -> None:
    # issue 20: G = (2 - s)/(s + 1)^3: before, 19 561 at t_f and y -> -39 122 after it. An
    # optimal-control feedforward needs 6.2 x the static inverse's input for 1 % (measured), above
    # the default limit of 3 x: within it and the rate bound no held input comes closer than 1.66 % (the bounded causal
    # limit), refused at once (it took 19 CPU-s of search, issue 46), with the 6.79 s the same move needs within them (more than 6.65 s: the bracket 2 % wide)
    control = pytest.importorskip("control")
    s = control.tf("s")
    G = (2 - s) / (s + 1) ** 3
    with pytest.raises(InversionError, match=r"^no causal feedforward within the bounds exists.*1\.66 % of the move.*needs more than 6\.65 s, "
                       r"and 6\.79 s meets it"):
        invert(G, smoothstep(1.0, 6.0, 5))
    # given room, a member that ends at rest on the equilibrium input: the output stays on y_f
    r = invert(G, smoothstep(1.0, 6.0, 5), max_error=0.03, max_torque=10.0)
    after = r.summary["verification"]["after_end"]
    assert after["max_tip_excursion"] <= 0.03 and r.summary["torque_ratio"] <= 20


@pytest.mark.parametrize("case", [("paper-sim", 2), ("hyperbolic", 3), ("paper-exp", 1)])
def test_returned_members_meet_every_bound_or_the_call_fails(case: tuple[str, int]) -> None:
    # never exit 0 with a figure beyond its bound
    name, n = case
    model = modelgen.load(name, modes=n)
    trajectory = trajectory_from_spec("paper-exp" if name == "paper-exp" else "paper-sim")
    try:
        r = invert(model, trajectory, auto=True)
    except InversionError:
        return
    s = r.summary
    bound = 0.01 * s["move"]
    assert s["torque_ratio"] <= 3 * (1 + 1e-12) and s["max_redefinition_error"] <= bound
    assert s["verification"]["after_end"]["max_tip_excursion"] <= bound
    assert s["verification"]["truncation"]["tip_error"] <= bound and s["sampled"]["max_tip_error"] <= bound


def test_the_paper_members_reproduce_the_paper_and_report_what_follows() -> None:
    # METHOD.md section 4: 5.73 mm, y~(5.5) = 1.56427 m, 0.4310 N m -- the paper's member, reported
    # with what reaches the link: the linear plant left at t_f drifts (-1.38 mm/s, measured)
    model = modelgen.load("paper-sim")
    r = invert(model, trajectory_from_spec("paper-sim"))
    s = r.summary
    assert s["max_redefinition_error"] == pytest.approx(5.73e-3, abs=5e-6)
    assert s["final_redefined_output"] == pytest.approx(1.56427, abs=5e-6)
    assert s["peak_torque"] == pytest.approx(0.4310, abs=5e-5)
    after = s["verification"]["after_end"]
    assert after["window"] == 2.0 and after["drift"] == pytest.approx(-1.377e-3, rel=1e-3)
    tip = _free_tip(model, r.X[-1], 2.0)
    assert np.abs(tip - 1.57).max() == pytest.approx(after["max_tip_excursion"], rel=1e-3)
    assert s["torque_ratio"] == pytest.approx(s["peak_torque"] / _rigid(model, trajectory_from_spec("paper-sim")), rel=1e-9)
    assert "auto" not in s  # the paper's member, not the automatic choice


@pytest.mark.parametrize("hold", ["point", "zoh"])
def test_the_held_figure_is_what_an_independent_zoh_simulation_measures(hold: str) -> None:
    # the exactly discretised plant driven by the held table: scipy.signal's ZOH discretisation and
    # dlsim, independent of inversion.lti.discrete, within 2x of the reported figure (issue 20)
    model = modelgen.load("paper-sim")
    r = invert(model, trajectory_from_spec("paper-sim"), hold=hold, period=1e-3)
    reported = r.summary["sampled"]
    period = 1e-3
    t, values = held_table(r.signals, 0.0, 5.5, period, hold, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0])  # type: ignore[arg-type]
    if hold == "zoh":
        assert r.t.size == t.size and np.array_equal(r.tau, values["tau"])  # the result's samples are the held table
    Ad, Bd, Cd, Dd, _ = sg.cont2discrete((model.A, model.B[:, None], model.C_out[None, :], np.zeros((1, 1))), period, method="zoh")
    _, y, _ = sg.dlsim((Ad, Bd, Cd, Dd, period), np.append(values["tau"], 0.0), x0=r.X[0])
    times = np.append(t, t[-1] + period)
    y_redef = r.evaluate(np.clip(times, 0.0, 5.5))["y"]
    measured = float(np.abs(y[:, 0] - y_redef).max())
    assert 0.5 * measured <= reported["max_tracking_error"] <= 2 * measured
    # measured (issue 20): 2.5e-4 of the move holding the point values, 3e-8 holding the period means
    assert reported["relative_tracking_error"] <= (3e-4 if hold == "point" else 5e-8)
    assert reported["period"] == period and reported["hold"] == hold


def test_the_period_mean_is_exact_and_converges_as_the_period_squared() -> None:
    model = modelgen.load("paper-exp")
    r = invert(model, trajectory_from_spec("paper-exp"), hold="zoh", period=2e-3)
    # the held value of a period is the exact mean of the series over it: against composite Gauss-Legendre
    x, w = np.polynomial.legendre.leggauss(40)
    k = np.arange(r.t.size)[::17]
    a, b = r.t[k], np.minimum(r.t[k] + 2e-3, 0.6)
    nodes = (a[:, None] + b[:, None]) / 2 + (b - a)[:, None] / 2 * x[None, :]
    means = (r.signals.evaluate(nodes.ravel())["tau"].reshape(nodes.shape) @ w) / 2 * (b - a) / 2e-3
    assert np.abs(r.tau[k] - means).max() <= 1e-12 * np.abs(r.tau).max()
    coarse = invert(model, trajectory_from_spec("paper-exp"), hold="zoh", period=4e-3).summary["sampled"]["max_tracking_error"]
    fine = r.summary["sampled"]["max_tracking_error"]
    assert 3.0 < coarse / fine < 5.0  # O(DT^2)


def test_the_held_c_table_is_the_python_one(tmp_path: Path) -> None:
    import subprocess

    from modelgen.abi import compiler_command

    cc = compiler_command()
    if cc is None:
        pytest.skip("no C compiler")
    r = invert(modelgen.load("paper-exp"), trajectory_from_spec("paper-exp"), hold="zoh", period=1e-3)
    export_c(r, tmp_path, prefix="ff")
    (tmp_path / "main.c").write_text(r"""
#include <stdio.h>
#include "feedforward.h"
int main(void) {
    for (long k = 0; k < FF_PERIODS; ++k) {
        double tau, theta, thetadot;
        int rc = ff_eval_held(k, &tau, &theta, &thetadot);
        printf("%d %.17g %.17g\n", rc, tau, theta);
    }
    return 0;
}
""")
    exe = tmp_path / "held"
    subprocess.run([cc, "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", f"-I{tmp_path}", "-o", str(exe), str(tmp_path / "main.c"),
                    str(tmp_path / "feedforward.c")], check=True, capture_output=True)
    out = np.array([[float(v) for v in line.split()] for line in subprocess.run([str(exe)], capture_output=True, text=True,
                                                                                  check=True).stdout.splitlines()])
    assert out.shape[0] == r.t.size and np.all(out[:, 0] == 0)
    assert np.abs(out[:, 1] - r.tau).max() <= 1e-12 * np.abs(r.tau).max()
    assert np.abs(out[:, 2] - r.theta_d).max() <= 1e-12 * np.abs(r.theta_d).max()


def test_the_cli_writes_a_held_table(tmp_path: Path) -> None:
    import json

    assert main(["invert", "paper-exp", "--hold", "zoh", "--period", "0.002", "--out", str(tmp_path), "--json"]) == 0
    rows = (tmp_path / "inversion.csv").read_text().splitlines()
    assert rows[0].split(",")[:6] == ["t", "y_d", "y_redef", "ydot_redef", "yddot_redef", "tau"]
    assert len(rows) - 1 == 300 and float(rows[2].split(",")[0]) == pytest.approx(0.002)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["sampled"]["hold"] == "zoh" and summary["settings"]["period"] == 0.002


@pytest.mark.parametrize(("argv", "named"), [(["--hold", "nearest"], "--hold"), (["--period", "-1"], "period"),
                                             (["--objective", "speed"], "--objective"), (["--window", "0"], "window")])
def test_bad_sampling_options_are_one_line(argv: list[str], named: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    try:
        code = main(["invert", "paper-sim", "--out", str(tmp_path), *argv])
    except SystemExit as exc:  # a choice argparse checks: its one line, status 2
        code = exc.code  # type: ignore[assignment]
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and named in err[0]


def test_the_after_end_window_follows_the_slowest_stable_mode() -> None:
    # 2 s for an undamped link; five time constants of the slowest stable mode if longer (issue 20)
    form = NormalForm.of_model(modelgen.load("paper-sim"))
    assert window_length(form) == 2.0
    control = pytest.importorskip("control")
    slow = NormalForm.of_system(__import__("inversion.lti.linear_system", fromlist=["x"]).as_linear_system(
        control.tf([1.0], [1.0, 0.2])))  # a pole at -0.2: 25 s
    assert window_length(slow) == pytest.approx(25.0)
    at_rest = after_end(form, np.zeros(form.n_states), 5.5, 0.0, 0.0, 2.0)
    assert at_rest.max_tip_excursion == 0.0 and at_rest.drift == 0.0
    assert Criteria(max_error=1.0).torque_limit(2.0) == 6.0 and Criteria(max_error=1.0, max_torque=1.5).torque_limit(2.0) == 1.5


def test_the_closed_loop_drives_the_link_with_the_held_table() -> None:
    # a result held at its period is simulated as the controller applies it (a staircase): the
    # plant, integrated by CVODES through every step, follows y~ as the exact discretisation says
    from simulation import simulate

    model = modelgen.load("paper-sim")
    r = invert(model, trajectory_from_spec("paper-sim"), hold="zoh", period=1e-3)
    sim = simulate(model, r, plant="linear", controller="none", t_end=6.0)
    reported = r.summary["sampled"]["max_tracking_error"]  # measured 4.9e-8 m, and 4.9e-8 m simulated
    assert 0.5 * reported <= sim.summary["max_redefined_tracking_error"] <= 2 * reported


@pytest.mark.parametrize("system, orders, need, rate, holds", [
    # 1/(s (s + 1)): G -> 1/s, the need is y_d' (m = 1); the quintic 2 m in 4 s: max y_d' = 1.875 d/T = 0.9375, its largest
    # change over 1 ms max |y_d''| DT = (10/sqrt(3)) d/T^2 DT = 7.2169e-4; an integrator is held at rest by no input
    (sg.TransferFunction([1], [1, 1, 0]), (1,), 0.9375, 10 / np.sqrt(3) * 2 / 16 * 1e-3, (0.0, 0.0)),
    # 2/((s + 1)(s + 2)): G(0) = 1, the need is y_d itself (m = 0): peak 2, change max |y_d'| DT = 0.9375e-3; held by y/G(0)
    (sg.TransferFunction([2], [1, 3, 2]), (0,), 2.0, 0.9375e-3, (0.0, 2.0)),
])
def test_the_demand_is_the_move_read_by_the_rigid_body(system, orders, need, rate, holds) -> None:  # type: ignore[no-untyped-def]
    from inversion.acceptance import demand
    from inversion.lti.linear_system import as_linear_system

    form = NormalForm.of_system(as_linear_system(system))
    move = smoothstep(2.0, 4.0, 2)
    asked = demand(form, move, 1e-3)
    assert form.need_orders == orders
    assert (asked.y_start, asked.y_final) == (move.y_start, move.y_final) == (0.0, 2.0)
    assert asked.rigid_torque == pytest.approx(need, rel=1e-9)
    assert asked.rigid_rate == pytest.approx(rate, rel=1e-4)  # the 20 001-point grid's resolution of the peak change
    assert (asked.hold_start, asked.hold_final) == pytest.approx(holds, abs=1e-12)
    assert demand(form, move, 1e-3) is asked  # kept for the search that asks again
    assert demand(form, move, 2e-3).rigid_rate == pytest.approx(2 * rate, rel=1e-3)


def test_rest_state_is_at_rest_on_the_output() -> None:
    """A system's rest state is an equilibrium on ``y`` (``A x`` along ``B``, ``C x = y``); a link's turns the joint only."""
    from inversion.acceptance import rest_state

    A = np.array([[0.0, 1.0], [-3.0, -4.0]])
    B, C = np.array([0.0, 1.0]), np.array([2.0, -1.0])
    x = rest_state(A, B, C, 0.7, link=False)
    assert C @ x == pytest.approx(0.7, rel=1e-12)
    drift = A @ x
    assert np.allclose(drift - B * (drift @ B) / (B @ B), 0.0, atol=1e-12)  # held by a constant input alone
    link = rest_state(np.zeros((4, 4)), np.ones(4), np.array([0.5, 0.1, 0.0, 0.0]), 0.25, link=True)
    assert link.tolist() == [0.5, 0.0, 0.0, 0.0]


def test_a_loop_without_gains_is_the_plant() -> None:
    from inversion.acceptance import closed_loop

    A, B = np.arange(16.0).reshape(4, 4), np.array([0.0, 0.0, 1.0, 2.0])
    u, th, thd = np.array([1.0, 2.0]), np.array([0.1, 0.2]), np.array([3.0, 4.0])
    A_c, u_c, after = closed_loop(A, B, (0.0, 0.0), u, th, thd, 0.5, 1.0, 0.0)
    assert np.array_equal(A_c, A) and np.array_equal(u_c, u) and after == 0.5
    A_c, u_c, after = closed_loop(A, B, (2.0, 3.0), u, th, thd, 0.5, 1.0, 0.0)
    assert np.allclose(A_c[:, 0], A[:, 0] - 2.0 * B) and np.allclose(A_c[:, 2], A[:, 2] - 3.0 * B)
    assert np.allclose(u_c, u + 2.0 * th + 3.0 * thd) and after == 2.5


@pytest.mark.parametrize("preset, modes, window", [("paper-sim", 2, 60.0), ("paper-exp", 6, 11.4)])
def test_the_free_response_s_rows_are_the_exponential_at_each_time(preset: str, modes: int, window: float) -> None:
    # the rows y(t_j) = R[j] . [X; 1] of the plant left with its input held, built by doubling (a few products of many
    # rows): each the plant's own exponential at t_j, computed apart (scipy's expm of the whole time), on a link with its
    # rigid hub (the rows grow with time) and one with six modes; 20 000 rows over 60 s
    import scipy.linalg as sla

    from inversion.acceptance import _compute_free_rows
    from inversion.lti.system import normal_form

    form = normal_form(modelgen.load(preset, modes=modes))
    A, B, C = np.asarray(form.A, float), np.asarray(form.B, float), np.asarray(form.C, float)
    times, rows = _compute_free_rows(A, B, C, window, 0.37)
    N = A.shape[0]
    augmented = np.zeros((N + 1, N + 1))
    augmented[:N, :N], augmented[:N, N] = A, B * 0.37
    count = rows.shape[0] - 1
    assert times[-1] == window and count >= 200
    for j in sorted({0, 1, 2, 3, 5, 64, 777, count // 2 + 1, count - 1, count}):
        exact = np.append(C, 0.0) @ sla.expm(augmented * times[j])
        assert np.abs(rows[j] - exact).max() <= 1e-10 * max(np.abs(exact).max(), 1.0), (j, rows[j], exact)
