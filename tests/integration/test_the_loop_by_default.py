"""A returned table holds in the loop the user will run (issue 60, item 1).

``sflm simulate --feedforward RUN`` closes the joint PD by default; ``invert`` judged the feedforward alone by default, and
returned tables that left the bound once the loop was closed (the paper's experiment's optimal-control table: 1.027 mm
in the PD loop against a 1 mm bound). Now a link's table is judged in both loops unless the feedforward alone is asked
for (``controller="none"``), and the figures are checked here against a closed loop written apart: the linear plant,
the PD on the joint with its references held with the torque, stepped exactly period by period (SciPy's ``expm``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import modelgen
from _helpers import pd_loop
from inversion import Bounds, Loop, Problem, invert, trajectory_from_spec


def closed_loop_tip(model: modelgen.Model, result, kp: float, kd: float) -> tuple[np.ndarray, np.ndarray]:  # type: ignore[no-untyped-def]
    """The tip at the rows during the move, and its excursion from ``y_d(t_f)`` over 2 s after it (20 points a period):
    the PD ``tau = tau_k + k_P (theta_k - theta) + k_D (thetadot_k - thetadot)``, every reference held over the period."""
    C, K, rows, step, fine, references = pd_loop(model, result, kp, kd)
    N = K.size
    x = np.zeros(N)
    tips = []
    for k in range(rows):
        tips.append(C @ x)
        x = (step @ np.append(x, result.tau[k] + K @ references(k)))[:N]
    y_final = float(result.trajectory.y_final)
    rest = np.zeros(N)
    rest[0] = y_final / C[0]  # the joint at rest on y_d(t_f): theta = y / x_out
    after = []
    for _ in range(int(round(2.0 / float(result.summary["sampled"]["period"]))) * 20):
        after.append(C @ x - y_final)
        x = (fine @ np.append(x, K @ rest))[:N]
    return np.asarray(tips), np.abs(np.asarray(after))


@pytest.fixture(scope="module")
def experiment():  # type: ignore[no-untyped-def]
    model = modelgen.load("paper-exp")
    move = trajectory_from_spec("paper-exp")
    return model, invert(Problem(model, move), method="ocp"), invert(Problem(model, move, loop=Loop(controller="none")), method="ocp")


def test_the_default_table_holds_the_bound_in_the_loop_simulate_closes(experiment) -> None:  # type: ignore[no-untyped-def]
    model, both, _ = experiment
    loop, bound = both.summary["loop"], float(both.summary["max_error"])
    tips, after = closed_loop_tip(model, both, loop["kp"], loop["kd"])
    y_d = both.trajectory.derivative(both.t[: tips.size], 0)
    during = float(np.abs(tips - y_d).max())
    assert (loop["kp"], loop["kd"]) == (1.4, 0.4)  # the paper's experiment's gains (section 8)
    assert during == pytest.approx(loop["pd"]["during"], rel=1e-9)  # the acceptance's closed loop, and this one
    assert after.max() <= loop["pd"]["after"] * (1 + 1e-6)  # the exact free response's peak bounds a sampled one
    assert during <= bound and loop["pd"]["after"] <= bound
    assert both.summary["sampled"]["max_tip_error"] <= bound  # and the feedforward alone


def test_the_table_judged_alone_leaves_the_bound_once_the_loop_is_closed(experiment) -> None:  # type: ignore[no-untyped-def]
    # what the default now catches: the table of the feedforward alone (measured 1.027 mm in a 1 mm bound)
    model, both, alone = experiment
    assert "loop" not in alone.summary
    tips, _ = closed_loop_tip(model, alone, 1.4, 0.4)
    y_d = alone.trajectory.derivative(alone.t[: tips.size], 0)
    assert float(np.abs(tips - y_d).max()) > float(alone.summary["max_error"])


def test_a_generic_system_is_judged_alone_by_default() -> None:
    import control

    result = invert(Problem(control.tf([-1.0, 2.0], [1.0, 4.0, 3.0]), trajectory_from_spec("smoothstep:1:8:6")))
    assert "loop" not in result.summary


#: Issue 60, items 1 and 2: a short steel link of our own (``tests/data/short-steel.toml``), 0.2 m in 0.08 s, bound 2 mm.
#: Before the loop entered the optimal-control programme, ``controller="pd"`` (and the default, both loops, with 6
#: modes) refused the move: "no causal method found a feedforward within the bounds" -- the table planned alone was
#: 1.27-1.53 x the bound in the loop, and tightening its tube did not bring it in. The issue's independent LP found a
#: table within 0.8 of both bounds (0.595 % alone and with the PD).
SHORT = Path(__file__).resolve().parents[1] / "data" / "short-steel.toml"


def _holds_both_loops(model: modelgen.Model, result) -> None:  # type: ignore[no-untyped-def]
    loop, bound = result.summary["loop"], float(result.summary["max_error"])
    tips, after = closed_loop_tip(model, result, loop["kp"], loop["kd"])
    y_d = result.trajectory.derivative(result.t[: tips.size], 0)
    assert float(np.abs(tips - y_d).max()) == pytest.approx(loop["pd"]["during"], rel=1e-9)
    assert float(np.abs(tips - y_d).max()) <= bound and after.max() <= bound  # in the PD loop, run apart
    assert result.summary["sampled"]["max_tip_error"] <= bound  # and alone
    assert result.summary["verification"]["after_end"]["max_tip_excursion"] <= bound
    # the table was planned for the loop: the loop is one of the programme's plants, and keeps the margin asked
    planned = {p["name"]: p for p in result.summary["ocp"]["plants"]}
    assert max(planned["the joint PD loop"]["max_tip_error"], planned["the joint PD loop"]["after_end_excursion"]) <= 0.9 * bound


def test_the_pd_loop_is_planned_for_where_tightening_the_tube_failed() -> None:
    model = modelgen.load(str(SHORT))
    result = invert(Problem(model, trajectory_from_spec("smoothstep:0.2:0.08"), bounds=Bounds(max_error=0.002),
                            loop=Loop(controller="pd")))
    assert result.summary["method"] == "ocp"
    _holds_both_loops(model, result)
    # near the least peak alone (10.49 N m measured for the loop's table; 10.27 planned alone, which fails the loop)
    assert float(result.summary["peak_torque"]) <= 0.5 * float(result.summary["rigid_torque"])


@pytest.mark.slow
def test_six_modes_judged_in_both_loops_by_default_return_a_table() -> None:
    model = modelgen.load(str(SHORT), modes=6)
    result = invert(Problem(model, trajectory_from_spec("smoothstep:0.2:0.08"), bounds=Bounds(max_error=0.002)))
    assert result.summary["method"] == "ocp" and result.summary["loop"]["controller"] == "pd"
    _holds_both_loops(model, result)
    # issue 60, item 5: the margin asked (0.1 of the bound) kept where the acceptance judges more modes too (the issue:
    # 0.905 % of the move with a bound of 1 %, 0.095 kept; measured here: 0.1009 with 10 modes)
    margin = result.summary["margin"]
    assert margin["more_modes_count"] > 6 and margin["more_modes"] >= 0.1 * (1 - 1e-3) and margin["held"] >= 0.1 * (1 - 1e-3)
