"""The window after the move, condensed onto the state a period after it (issue 60, item 4).

A lightly damped link rings long after its move: the stiff aluminium bar of ``tests/data/aluminium-bar.toml`` (8 modes,
0.1 % damping) has an 11.4 s window, 11 390 periods at 1 ms, where its 0.3 m in 0.1 s has 100. Every period of that window
was a stage of the optimal-control programme (the input held there, nothing to choose), so the programme planned for
the joint PD loop (two plants, 36 states) was beyond one solve, the tube was tightened instead and failed: the default
path refused the move after 124-135 s ("no causal method found"). The window is now rows on one state
(:func:`inversion.chain.programme.window_rows`): the same programme with 101 stages; the loop is planned for, and the
table is returned in about 20 s. It is checked here on the link run apart (SciPy's ``expm`` of the model's own
matrices, its rows held), alone and with the joint PD closed, through the whole window, and with four modes more.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

import modelgen
from _helpers import held
from inversion import Problem, invert, trajectory_from_spec
from inversion.studies.robustness import parse_uncertainty
from modelgen.linear import linear_model

BAR = Path(__file__).resolve().parents[2] / "data" / "aluminium-bar.toml"


def _run_apart(model: modelgen.Model, tau: np.ndarray, theta: np.ndarray, thetadot: np.ndarray, period: float, window: float,
               gains: tuple[float, float] | None, y_final: float) -> np.ndarray:
    """The tip at every row and half-way between them, the table's rows held and then zero torque through ``window`` s,
    the joint PD (where given) on the references held with the torque, after the move at rest on ``y_d(t_f)``
    (``theta = y_f / x_out``, the exported C's ``FINAL``)."""
    A, B, C = np.asarray(model.A, float), np.asarray(model.B, float).reshape(-1), np.asarray(model.C_out, float).reshape(-1)
    N, n1 = A.shape[0], A.shape[0] // 2
    K = np.zeros(N)
    if gains is not None:
        K[0], K[n1] = gains
    Ad, Bd = held(A - np.outer(B, K), B, period / 2)
    after = int(round(window / period))
    rows = np.concatenate([tau, np.zeros(after)])
    refs = np.zeros((rows.size, N))
    refs[: tau.size, 0], refs[: tau.size, n1] = theta[: tau.size], thetadot[: tau.size]
    refs[tau.size:, 0] = y_final / C[0]
    x, tips = np.zeros(N), []
    for u, ref in zip(rows, refs):
        for _ in range(2):  # two half periods: the row and the point half-way
            tips.append(C @ x)
            x = Ad @ x + Bd * (u + K @ ref)
    tips.append(C @ x)
    return np.asarray(tips)


@pytest.mark.slow
def test_the_ringing_bar_s_table_holds_alone_and_in_the_loop_through_its_window() -> None:
    model = modelgen.load(str(BAR))
    move = trajectory_from_spec("smoothstep:0.3:0.1:2")
    said: list[str] = []
    result = invert(Problem(model, move), progress=said.append)
    s = result.summary
    assert s["method"] == "ocp" and s["settings"]["end"] == "free"  # no table ends at rest here
    assert s["ocp"]["after_periods"] == 11390 and any("planned again, for the loop too" in m for m in said)
    bound, period = float(s["max_error"]), float(s["sampled"]["period"])
    assert bound == pytest.approx(0.003)
    tau = np.asarray(result.tau, dtype=float)
    theta, thetadot = np.asarray(result.theta_d, dtype=float), np.asarray(result.thetadot_d, dtype=float)
    window = float(s["ocp"]["after_periods"]) * period
    times = np.arange(2 * (tau.size + round(window / period)) + 1) * period / 2
    y_d = move.derivative(np.minimum(times, move.tf), 0)
    loop = s["loop"]
    for gains in (None, (float(loop["kp"]), float(loop["kd"]))):
        error = np.abs(_run_apart(model, tau, theta, thetadot, period, window, gains, move.y_final) - y_d)
        # measured: 0.899 % alone during and after the move, 0.897 % / 0.331 % with the PD (the plan aimed within 0.9)
        assert error.max() <= 0.9 * bound * (1 + 1e-3), (gains, error.max() / bound)
    more = modelgen.load(str(BAR), modes=12)  # four modes the plan never saw
    error = np.abs(_run_apart(more, tau, theta, thetadot, period, window, None, move.y_final) - y_d)
    assert error.max() <= bound, error.max() / bound


def test_the_rows_that_bind_give_the_whole_window_s_table(monkeypatch: pytest.MonkeyPatch) -> None:
    # the window's rows a solve starts with, and those the solution breaks added (a cutting plane), against every row of
    # the window from the start: the same table (measured: 660 of the 22 778 rows, two solves, 0.5 s against 1.6 s)
    import inversion.methods.ocp as ocp

    model = modelgen.load(str(BAR))
    move = trajectory_from_spec("smoothstep:0.3:0.1:2")
    cut = ocp.ocp_inversion(model, move, period=1e-3, max_error=0.0027, end="free")
    monkeypatch.setattr(ocp, "_CUT_FIRST", 10**9)
    whole = ocp.ocp_inversion(model, move, period=1e-3, max_error=0.0027, end="free")
    solved, rows = cut.summary["ocp"]["window_rows"]
    assert rows == 2 * 11389 and solved < rows / 10
    # the table re-solved a little inside its tube starts with the rows the first solve found binding: one solve
    assert cut.summary["ocp"]["window_carried"] > 0 and cut.summary["ocp"]["window_solves"] == 1, cut.summary["ocp"]
    assert whole.summary["ocp"]["window_rows"] == [rows, rows] and whole.summary["ocp"]["window_solves"] == 1
    np.testing.assert_allclose(cut.tau, whole.tau, atol=1e-7 * float(np.abs(whole.tau).max()))
    assert float(cut.summary["peak_torque"]) == pytest.approx(float(whole.summary["peak_torque"]), rel=1e-9)


@pytest.mark.slow
def test_the_bar_with_its_stiffness_uncertain_gets_a_table_for_every_corner_in_both_loops() -> None:
    # issue 60, item 4: `--uncertainty link.flexural_rigidity=5%` on the bar printed "the family: failed (1791 s)" at 30
    # minutes; here the default path refused after 263 s (the re-plan's linear programme for the corners about 250 s of
    # it, HiGHS numerically stuck on its 9 516 corner rows; optimal control then beyond one programme). Now each corner is
    # held alone and in its joint PD loop (planned: the loop a perturbed link runs in), checked on the perturbed links run
    # apart through the window.
    model = modelgen.load(str(BAR))
    move = trajectory_from_spec("smoothstep:0.3:0.1:2")
    result = invert(Problem(model, move, uncertainty=parse_uncertainty("link.flexural_rigidity=5%")))
    s = result.summary
    assert s["method"] == "ocp" and len(s["ocp"]["plants"]) == 5  # 2 corners, the loop, the corners in their loops
    bound, period = float(s["max_error"]), float(s["sampled"]["period"])
    tau = np.asarray(result.tau, dtype=float)
    theta, thetadot = np.asarray(result.theta_d, dtype=float), np.asarray(result.thetadot_d, dtype=float)
    window = float(s["ocp"]["after_periods"]) * period
    times = np.arange(2 * (tau.size + round(window / period)) + 1) * period / 2
    y_d = move.derivative(np.minimum(times, move.tf), 0)
    gains = (float(s["loop"]["kp"]), float(s["loop"]["kd"]))
    worst = 0.0
    for factor in (0.95, 1.0, 1.05):
        lm = linear_model(replace(model.geometry, flexural_rigidity=model.geometry.flexural_rigidity * factor), model.n,
                          float(model.output_at))
        plant = SimpleNamespace(A=lm["A"], B=lm["B"], C_out=lm["C_out"])
        for loop in (None, gains):
            error = float(np.abs(_run_apart(plant, tau, theta, thetadot, period, window, loop, move.y_final) - y_d).max())
            worst = max(worst, error)
            assert error <= bound, (factor, loop, error / bound)
    assert worst <= 0.9 * bound * (1 + 1e-3), worst / bound  # the margin kept (measured: 0.899 of the bound)
