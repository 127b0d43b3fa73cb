"""The bounded causal limit: the least error any causal feedforward within the drive's torque and rate bounds reaches."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import modelgen
from inversion import InversionError, SettingsError, invert, smoothstep
from inversion.acceptance import Bounds
from inversion.baselines.bounded_limit import bounded_limit
from inversion.baselines.ocp import ocp_inversion
from inversion.lti.causal_limit import causal_limit

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def thin() -> modelgen.Model:
    # the 3 mm strip (issue 34's cliff): zeros 49.6 and 132; 0.5 m in 0.6 s
    return modelgen.load(str(ROOT / "tests/data/steel-strip-3mm.toml"))


def test_the_automatic_choice_refuses_the_cliff_with_the_exact_reason(thin) -> None:  # type: ignore[no-untyped-def]
    # 7.31601e-3 m: this programme solved by HiGHS's interior point and by its dual simplex (7.3160111e-3 both), and with
    # the whole move's duration after it instead of a third (the same to eight digits)
    with pytest.raises(InversionError, match="no causal feedforward within the bounds exists") as caught:
        invert(thin, smoothstep(0.5, 0.6, 2))
    record = caught.value.bounded_limit  # type: ignore[attr-defined]
    assert record["error"] == pytest.approx(7.31601e-3, rel=1e-4)
    assert record["period"] == 1e-3 and record["bound"] == pytest.approx(0.005)
    message = str(caught.value)
    assert "1.46 % of the move" in message and message.count("0.329 % of the move") == 1  # the causal limit quoted once
    stages = {stage["method"]: stage for stage in caught.value.stages}  # type: ignore[attr-defined]
    assert stages["ocp"]["status"] == "skipped"  # beyond the bounded limit: no solve (it used to fail after 15 s)
    assert "beyond the bounded causal limit" in stages["ocp"]["message"]


def test_a_long_refusal_has_its_exact_reason_too() -> None:
    # the very flexible strip's 0.4 m in 3 s, at 1 ms: within the causal limit (0.746 %), but 4 000 periods of 6 states
    # and the input; kept every third period the bounded limit is 1.18e-2 (2.95 %), so the automatic choice refuses with
    # it in 13 s, where without it optimal control ran out of iterations and the refusal had no reason (48 s)
    strip = modelgen.load(str(Path(__file__).resolve().parents[2] / "data" / "flexible-strip.toml"))
    with pytest.raises(InversionError, match="no causal feedforward within the bounds exists") as caught:
        invert(strip, smoothstep(0.4, 3.0, 2))
    record = caught.value.bounded_limit  # type: ignore[attr-defined]
    assert record["rows_apart"] == 3 and record["error"] == pytest.approx(1.180092e-2, rel=1e-4)
    assert "at one row in 3" in str(caught.value)
    stages = {stage["method"]: stage for stage in caught.value.stages}  # type: ignore[attr-defined]
    assert stages["ocp"]["status"] == "skipped" and "programme's rows" not in stages["ocp"]["message"]


def test_freed_bounds_approach_the_causal_limit(thin) -> None:  # type: ignore[no-untyped-def]
    # with the drive's bounds lifted, the held feedforward at 1 ms errs a little more than the causal limit of any
    # (continuous) causal input here: 1.694e-3 against 1.647e-3 (measured; not a law -- bounded at the rows alone, inputs
    # large enough can fall below it, docs/method.md 7a)
    move = smoothstep(0.5, 0.6, 2)
    free = bounded_limit(thin, move, Bounds(max_error=0.005, period=1e-3, max_torque=1e6, max_torque_rate=1e6))
    limit = causal_limit(thin, move, 0.005).error
    assert limit <= free.error <= 1.1 * limit
    assert not free.exceeds


def test_the_rate_bound_is_what_binds(thin) -> None:  # type: ignore[no-untyped-def]
    move = smoothstep(0.5, 0.6, 2)
    rate_free = bounded_limit(thin, move, Bounds(max_error=0.005, period=1e-3, max_torque_rate=math.inf))
    assert rate_free.error == pytest.approx(4.79082e-3, rel=1e-3)  # below the bound: the rate bound is what binds (1.46 %)
    assert not rate_free.exceeds and "0.958 % of the move" in rate_free.sentence()


def test_optimal_control_meets_a_bound_just_above_it_and_errs_no_less() -> None:
    # the 4 mm strip's 0.6 s move at 2 ms, the torque free and the change bounded (what the optimal-control feedforward
    # asks): the limit is 2.895e-3 m; at 1.05 of it optimal control has a feedforward, whose error is not below it
    model = modelgen.load(str(ROOT / "tests/data/steel-strip.toml"))
    move = smoothstep(0.5, 0.6, 2)
    least = bounded_limit(model, move, Bounds(max_error=0.005, period=2e-3, max_torque=math.inf))
    assert least.error == pytest.approx(2.8954e-3, rel=1e-3)
    E = 1.05 * least.error
    result = ocp_inversion(model, move, period=2e-3, max_error=E, end="free", bounds=Bounds(max_error=E, period=2e-3))
    assert least.error <= result.summary["ocp"]["max_error_at_samples"] <= E  # at the rows, as the limit bounds
    change = np.abs(np.diff(np.concatenate([[0.0], result.tau, [0.0]]))).max()
    assert change <= least.max_torque_rate * (1 + 1e-6)  # within the same change bound the limit was computed with


def test_a_programme_too_large_is_refused_by_name(thin) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(SettingsError, match="period"):
        bounded_limit(thin, smoothstep(0.5, 5.0, 2), Bounds(max_error=0.005, period=1e-3))


def test_a_long_programme_bounds_the_tip_at_fewer_rows_and_stays_a_bound(monkeypatch: pytest.MonkeyPatch) -> None:
    # (2 - s)/((s + 1)(s + 3)), 1 in 4 s at 2 ms: 2 667 periods of 2 states and the input. Kept every period it is 3.4389e-2;
    # with a size of 6 000 the states are kept (and the tip bounded) every second period: fewer rows, no larger (3.4379e-2)
    import inversion.baselines.bounded_limit as module
    control = pytest.importorskip("control")
    s = control.tf("s")
    system, move = (2 - s) / ((s + 1) * (s + 3)), smoothstep(1.0, 4.0, 6)
    full = bounded_limit(system, move, Bounds(max_error=0.01, period=2e-3))
    monkeypatch.setattr(module, "MAX_SIZE", 6000)
    kept = bounded_limit(system, move, Bounds(max_error=0.01, period=2e-3))
    assert (full.rows_apart, kept.rows_apart) == (1, 2) and kept.as_dict()["rows_apart"] == 2
    assert kept.error <= full.error * (1 + 1e-7) and kept.error == pytest.approx(full.error, rel=1e-3)
    assert "at one row in 2" in kept.sentence() and "at the rows" in full.sentence()
    monkeypatch.setattr(module, "MAX_SIZE", 5000)  # inputs alone more than half of it
    with pytest.raises(SettingsError, match=r"period.*at least 0\.00213 s"):
        bounded_limit(system, move, Bounds(max_error=0.01, period=2e-3))


def test_a_result_of_optimal_control_carries_it_and_errs_no_less() -> None:
    # the heavy payload's 0.3 m in 0.343 s: the family fails, the limit within the bounds is 0.157 % of the move at 1 ms,
    # and optimal control returns a table whose error at the rows is not below it
    model = modelgen.load(str(ROOT / "tests/data/heavy-payload.toml"))
    result = invert(model, smoothstep(0.3, 0.343, 2))
    auto = result.summary["auto"]
    assert result.summary["method"] == "ocp" and not auto["bounded_limit"]["error"] > auto["bounded_limit"]["bound"]
    assert auto["bounded_limit"]["error"] == pytest.approx(4.7129e-4, rel=1e-3)
    assert auto["bounded_limit"]["error"] <= result.summary["ocp"]["max_error_at_samples"] <= 0.003
    from sflm.summaries import inversion_text

    assert "bounded causal limit: 0.157 % of the move at the rows, held at 1 ms" in inversion_text(result, [])


def test_a_refusal_the_limit_does_not_explain_says_so(thin) -> None:  # type: ignore[no-untyped-def]
    # every method failed, yet the bounded limit is within the bound: the refusal says the bounds do not rule one out
    from inversion.api import _no_method
    from inversion.baselines.bounded_limit import BoundedLimit

    limit = causal_limit(thin, smoothstep(0.5, 0.6, 2), 0.005)
    bounded = BoundedLimit(error=0.004, move=0.5, period=1e-3, max_torque=18.9, max_torque_rate=1.0, bound=0.005)
    exc = _no_method([{"name": "the family", "message": f"none passes; {limit.sentence()}"}], limit, bounded)
    text = str(exc)
    assert text.startswith("no causal method found a feedforward within the bounds (the bounded causal limit does not rule "
                           "one out: held at 1 ms")
    assert text.count(limit.sentence()) == 1 and exc.bounded_limit["error"] == 0.004  # type: ignore[attr-defined]
