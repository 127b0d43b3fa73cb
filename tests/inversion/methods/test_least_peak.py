"""The least peak input of any causal table within a tube, and the automatic choice that judges its stages by it (issue 60,
item 6): checked against linear programmes written apart (the plant's Markov parameters and HiGHS)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import modelgen
from _helpers import held
from inversion import Bounds, Loop, Problem, Sampling, invert, smoothstep
from inversion.methods.bounded_limit import least_peak

ROOT = Path(__file__).resolve().parents[3]
STRIP = ROOT / "tests" / "data" / "steel-strip-3mm.toml"


def peak_lp(model, move, period: float, tube: float, R: float, rows: int, after: int) -> float:  # type: ignore[no-untyped-def]
    """The least ``max |u_k|`` of inputs held at ``period`` from rest, ``|u_k - u_{k-1}| <= R`` (``u_{-1} = 0``), the first
    ``rows`` free and then zero (its change bounded too), the tip within ``tube`` of the move at every row of the move and
    of ``after`` more: the plant's Markov parameters and HiGHS."""
    from scipy.optimize import linprog

    A, B, C = np.asarray(model.A, float), np.asarray(model.B, float), np.asarray(model.C_out, float).reshape(-1)
    Ad, Bd = held(A, B, period)
    M = rows + after
    markov = np.zeros(M)
    power = Bd.copy()
    for i in range(M):
        markov[i] = C @ power
        power = Ad @ power
    G = np.zeros((M, rows))  # the tip at row i (1..M)
    for i in range(1, M + 1):
        k = np.arange(min(i, rows))
        G[i - 1, k] = markov[i - 1 - k]
    t = move.t0 + period * np.arange(1, M + 1)
    y = move.derivative(np.clip(t, move.t0, move.tf), 0)
    n = rows
    change = np.eye(n) - np.eye(n, k=-1)
    last = np.zeros((1, n))
    last[0, -1] = 1.0
    zero = np.zeros((M, 1))
    one = np.ones((n, 1))
    blocks = [np.hstack([G, zero]), np.hstack([-G, zero]), np.hstack([np.eye(n), -one]), np.hstack([-np.eye(n), -one]),
              np.hstack([change, 0 * one]), np.hstack([-change, 0 * one]), np.hstack([last, [[0.0]]]), np.hstack([-last, [[0.0]]])]
    sides = [y + tube, tube - y, np.zeros(n), np.zeros(n), np.full(n, R), np.full(n, R), [R], [R]]
    out = linprog(np.r_[np.zeros(n), 1.0], A_ub=np.vstack(blocks), b_ub=np.concatenate([np.asarray(s, float) for s in sides]),
                  bounds=[(None, None)] * n + [(0, None)], method="highs")
    assert out.status == 0, out.message
    return float(out.x[-1])


@pytest.fixture(scope="module")
def strip():  # type: ignore[no-untyped-def]
    return modelgen.load(str(STRIP))


def test_the_least_peak_lies_between_two_programmes_written_apart(strip) -> None:  # type: ignore[no-untyped-def]
    # the chain's programme: inputs free through the move and a third of its duration after it, the tip within the tube at
    # every row, the unstable zeros bounded at the last row. Written apart: the same inputs free without that last row's
    # bound (fewer rows: no larger), and a table that ends with the move, its tip held through 2 s more (more rows: no
    # smaller). Measured: 3.28711393 <= 3.28711394 <= 3.28711394 N m (the rate bound binds: the move's end is the same).
    period, tube, R = 0.002, 0.0025, 0.2
    move = smoothstep(0.5, 1.0, 5)
    problem = Problem(strip, move, bounds=Bounds(max_error=tube, max_torque=20.0, max_torque_rate=R), sampling=Sampling(period=period))
    found = least_peak(strip, move, problem.criteria(tube, hold="zoh", loop=None), tube)
    K = round(move.duration / period)
    below = peak_lp(strip, move, period, tube, R, K + math.ceil(move.duration / 3 / period), 0)
    above = peak_lp(strip, move, period, tube, R, K, round(2.0 / period))
    assert below * (1 - 1e-6) <= found <= above * (1 + 1e-6)
    assert above < (1 + 1e-6) * below  # the sandwich is narrow: the figure is the least peak, not any bound
    # a tube a tenth wider needs less
    assert least_peak(strip, move, problem.criteria(1.1 * tube, hold="zoh", loop=None), 1.1 * tube) < found


def test_the_automatic_choice_pays_no_more_torque_than_it_must() -> None:
    # issue 60, item 6: paper-sim's move ending at rest. Before: the family's member at 0.4281 N m, where optimal control
    # holds the same bound (and margin) at 0.3360 and no causal table within the tube needs less than 0.3199; both hold
    # the bound through EI +-50 % (the radius's span), alone and with the joint PD. Now optimal control is asked and chosen.
    from inversion import Automatic, Family, trajectory_from_spec

    model = modelgen.load("paper-sim")
    result = invert(Problem(model, trajectory_from_spec("paper-sim")), method=Automatic(family=Family(end="rest")))
    auto = result.summary["auto"]
    stages = {stage["method"]: stage for stage in auto["stages"]}
    least = auto["least_peak"]
    assert result.summary["method"] == "ocp" and stages["ssef"]["status"] == "passed" and least["robustness"]["kept"] == "ocp"
    assert stages["ssef"]["peak_torque"] > 1.2 * stages["ocp"]["peak_torque"]
    assert least["peak_torque"] <= result.summary["peak_torque"] <= 1.06 * least["peak_torque"]  # the least peak, 5 % for smoothness
    # what reaches the link: within the bound held at the rows, after the move, with more modes, at rest
    sampled = result.summary["sampled"]
    assert max(sampled["max_tip_error"], sampled["after_end_excursion"]) <= 0.0157
    assert min(result.summary["margin"]["held"], result.summary["margin"]["more_modes"]) > 0.05


def test_a_cheaper_table_that_breaks_with_a_small_plant_error_is_not_taken() -> None:
    # the steel strip's 0.5 m in 0.6 s within 1 %: optimal control's table needs 5.847 N m against the family's 7.902, but
    # it rides its tube and breaks the bound at a 0.125 % plant error (the member's at 1.64 %): the member is kept, and
    # the record says what each costs and tolerates
    from inversion.methods.margin import robustness_radius, tolerated

    model = modelgen.load(str(ROOT / "tests" / "data" / "steel-strip.toml"))
    result = invert(Problem(model, smoothstep(0.5, 0.6, 2)))
    auto = result.summary["auto"]
    robust = auto["least_peak"]["robustness"]
    family, optimal = robust["tables"]
    assert result.summary["method"] == "ssef" and robust["kept"] == "ssef" and [s["method"] for s in auto["stages"]] == ["ssef", "ocp"]
    assert optimal["peak_torque"] * 1.05 < family["peak_torque"] and optimal["tolerated"] < 0.5 * family["tolerated"]
    assert not auto["least_peak"]["screened"]["skipped"]  # the estimate did not rule it out: it was asked
    # the figure the choice read is the returned table's own radius, recomputed
    assert tolerated(robustness_radius(result, result.summary["max_error"])) == pytest.approx(family["tolerated"], rel=1e-12)


def test_a_cheaper_table_is_not_asked_where_it_would_break_too_soon(strip) -> None:  # type: ignore[no-untyped-def]
    # the 3 mm strip's 0.5 m in 1.5 s within 2.5 mm: the member (1.85 N m) is 19 % above the least peak (1.557), but by its
    # own sensitivity a table riding the 2.25 mm tube would break the bound at about 0.08 % plant error, where a cheaper
    # table must tolerate half the member's 0.66 %: optimal control is not asked. Checked: its table (1.647 N m),
    # computed apart, breaks the bound at 0.054 %.
    from inversion.methods.margin import robustness_radius, tolerated

    problem = Problem(strip, smoothstep(0.5, 1.5, 5), bounds=Bounds(max_error=0.0025), sampling=Sampling(period=0.001))
    result = invert(problem)
    auto = result.summary["auto"]
    screened = auto["least_peak"]["screened"]
    assert result.summary["method"] == "ssef" and [s["method"] for s in auto["stages"]] == ["ssef"] and screened["skipped"]
    asked = 0.5 * screened["earlier"]
    assert 3 * screened["predicted"] < asked
    optimal = invert(problem, method="ocp")
    assert optimal.summary["peak_torque"] * 1.05 < result.summary["peak_torque"]
    assert tolerated(robustness_radius(optimal, 0.0025)) < asked


def test_the_family_is_kept_where_it_is_near_the_least_found(strip) -> None:  # type: ignore[no-untyped-def]
    # a slow move within 0.5 mm: the family's member 8.9 % above the least peak (0.4456 N m), so optimal control is asked;
    # its table needs 0.4680, and the member (0.4851) is within 5 % of that: the member is kept
    move = smoothstep(0.5, 3.0, 5)
    result = invert(Problem(strip, move, bounds=Bounds(max_error=0.0005), sampling=Sampling(period=0.001),
                            loop=Loop(controller="none")))
    auto = result.summary["auto"]
    stages = {stage["method"]: stage for stage in auto["stages"]}
    assert result.summary["method"] == "ssef" and stages["ssef"]["chosen"] and stages["ocp"]["status"] == "passed"
    member, optimal, least = stages["ssef"]["peak_torque"], stages["ocp"]["peak_torque"], auto["least_peak"]["peak_torque"]
    assert least <= optimal < member <= 1.05 * optimal and member > 1.05 * least
