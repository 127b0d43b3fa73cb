"""Optimal control's programme rows several periods apart where the plant's shortest time constant spans many of them.

``(2 - s)/((s + 1)(s + 3))`` (poles 1 and 3, zero 2: its shortest time constant 1/3 s) at the controller's 1 ms: a row
every period made an 8 000-stage programme of an 8 s move whose table is smooth over hundreds of periods. Its rows are now
16 periods apart (a twentieth of 1/3 s), the table linear between them and held every period: measured on the 10 s move,
the solve 9 x faster and the least peak 1.3e-5 above every period's. A refusal is never the rows' doing: the programme
is solved again with every period a row before anything is refused.
"""

from __future__ import annotations

import control
import numpy as np
import pytest
import scipy.signal as ss

from inversion import Bounds, InversionError, OptimalControl, Problem, Replan, SettingsError, invert, trajectory_from_spec

NUM, DEN = [-1.0, 2.0], [1.0, 4.0, 3.0]


@pytest.fixture(scope="module")
def tables():  # type: ignore[no-untyped-def]
    problem = Problem(control.tf(NUM, DEN), trajectory_from_spec("smoothstep:1:8:3"))
    return invert(problem, method=OptimalControl()), invert(problem, method=OptimalControl(ramp=1))


def test_the_rows_span_a_twentieth_of_the_plant_s_shortest_time_constant(tables) -> None:  # type: ignore[no-untyped-def]
    apart, every = tables
    assert apart.summary["ocp"]["ramp"] == 16  # floor(1 / (3 x 20 x 0.001))
    assert "ramp" not in every.summary["ocp"]
    assert apart.tau.size == every.tau.size == 8000  # one row a period either way
    # the least peak as every period's, within a ten-thousandth; the held error within the bound alike
    least = [t.summary["ocp"]["smoothing"]["least_peak"] for t in tables]
    assert least[0] == pytest.approx(least[1], rel=1e-4) and least[0] >= least[1] * (1 - 1e-9)
    for t in tables:
        assert t.summary["sampled"]["max_tip_error"] <= 0.01 and t.summary["torque_rate_ratio"] <= 10 * (1 + 1e-6)


def _held_apart(result) -> float:  # type: ignore[no-untyped-def]
    """The largest error of ``result``'s table on SciPy's zero-order hold of the state space at a tenth of the period,
    every row held ten steps, then the static input (1 / G(0) = 1.5) held 10 s: the move's and its end's."""
    A, B, C, D = ss.tf2ss(NUM, DEN)
    Ad, Bd, Cd, _, _ = ss.cont2discrete((A, B, C, D), 1e-4, method="zoh")
    u = np.concatenate([np.repeat(result.tau, 10), np.full(100_000, 1.5)])
    x, y = np.zeros(A.shape[0]), np.empty(u.size)
    for k, uk in enumerate(u):
        y[k] = (Cd @ x).item()
        x = Ad @ x + Bd[:, 0] * uk
    t = np.arange(u.size) * 1e-4
    y_d = result.trajectory.derivative(np.clip(t, result.trajectory.t0, result.trajectory.tf), 0)
    return float(np.abs(y - y_d).max())


def test_the_table_with_its_rows_apart_holds_on_the_system_discretised_apart(tables) -> None:  # type: ignore[no-untyped-def]
    apart, _ = tables
    assert _held_apart(apart) <= 0.01 * (1 + 1e-3)


def test_a_refusal_with_the_rows_apart_is_solved_again_with_every_period(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # the programme with its rows apart refused (as a table it cannot express would be): solved again, every period a row
    import inversion.methods.ocp as ocp

    solve = ocp.ocp_inversion
    asked: list[int] = []

    def refusing(*args, **kwargs):  # type: ignore[no-untyped-def]
        asked.append(kwargs["ramp"])
        if kwargs["ramp"] > 1:
            raise InversionError("the optimal-control feedforward does not exist or was not found: (a stand-in)")
        return solve(*args, **kwargs)

    monkeypatch.setattr(ocp, "ocp_inversion", refusing)
    heard: list[str] = []
    problem = Problem(control.tf(NUM, DEN), trajectory_from_spec("smoothstep:1:8:3"))
    result = invert(problem, method=OptimalControl(), progress=heard.append)
    assert asked == [16, 1] and "ramp" not in result.summary["ocp"]
    assert any("again with every period" in h for h in heard), heard
    # a ramp the caller gives is kept: its refusal is the answer
    asked.clear()
    with pytest.raises(InversionError, match="a stand-in"):
        invert(problem, method=OptimalControl(ramp=4))
    assert asked == [4]


def test_a_table_over_the_torque_bound_at_rows_apart_is_solved_again_with_every_period() -> None:
    # the 10 s move's least peak with no margin: 1.5074562 with the rows 16 apart, 1.5074521 with every period (measured).
    # A torque bound between them: the table with its rows apart is over it, the door would refuse it (it did: "the peak
    # input 1.507 ... accepted 1.507"); every period's holds it
    problem = Problem(control.tf(NUM, DEN), trajectory_from_spec("smoothstep:1:10:3"), margin=0.0,
                      bounds=Bounds(max_torque=1.507454))
    heard: list[str] = []
    result = invert(problem, method=OptimalControl(), progress=heard.append)
    assert any("rows 16 periods apart" in h and "again with every period" in h for h in heard), heard
    assert "ramp" not in result.summary["ocp"] and result.summary["peak_torque"] <= 1.507454
    assert _held_apart(result) <= 0.01 * (1 + 1e-3)


def test_optimal_control_with_its_rows_apart_asks_the_bounded_limit_only_where_it_fails(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # its programme is a fraction of the bounded limit's (one row a period: 13 334 stages for the 10 s move and its third
    # after, 1.8 s where the table took 0.18 s): the limit is asked where the table is refused, and refuses as before
    import inversion.methods.bounded_limit as module

    solve = module.bounded_limit
    asked: list[float] = []

    def counted(*args, **kwargs):  # type: ignore[no-untyped-def]
        asked.append(args[1].duration)
        return solve(*args, **kwargs)

    monkeypatch.setattr(module, "bounded_limit", counted)
    G, move = control.tf(NUM, DEN), trajectory_from_spec("smoothstep:1:10:3")
    result = invert(Problem(G, move), method=OptimalControl())
    assert asked == [] and result.summary["ocp"]["ramp"] == 16
    # beyond the bounds (the input held below the static need): refused with the limit, as when it was asked first
    with pytest.raises(InversionError, match=r"^no causal feedforward within the bounds exists: held at 1 ms with the input "
                                             r"within 1.45 .* closer than 0.0406 "):
        invert(Problem(G, move, bounds=Bounds(max_torque=1.45)), method=OptimalControl())
    assert asked == [10.0]  # once: the door's refusal reads the one optimal control asked for
    # the re-plan refuses a plant of relative degree 1 before the limit is asked
    asked.clear()
    with pytest.raises(SettingsError, match="relative degree 2"):
        invert(Problem(G, move), method=Replan())
    assert asked == []
