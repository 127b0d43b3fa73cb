"""``simulate`` runs over the span ``invert`` judged: the feedforward and the after-end window it was judged through.

A free end leaves the link moving when the table ends. ``invert`` judges the tip through the window after it (2 s by
default, ``--window``); ``simulate`` ran 3 s after the move whatever the window. On the 3 mm steel strip with its drive,
``--end free --controller none`` returned a table whose tip ``invert`` judged 4.47 mm from ``y_d(t_f)`` in the 2 s after
it (bound 5 mm), and ``simulate --controller none`` of that run reported 5.919 mm with exit 0: the tip left the bound
in the third second, which nothing had judged. Now the simulation's default end is the feedforward's end plus the
window of the run (:attr:`inversion.InversionResult.window`), and the figures agree with the judged ones.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import modelgen
from inversion import Automatic, Bounds, Family, Loop, Problem, Sampling, invert, read_run, trajectory_from_spec, write_run
from simulation import simulate

DRIVE = Path(__file__).resolve().parents[1] / "data" / "steel-strip-3mm-drive.toml"


@pytest.fixture(scope="module")
def free_end():  # type: ignore[no-untyped-def]
    model = modelgen.load(str(DRIVE))
    move = trajectory_from_spec("smoothstep:0.5:0.8:2")
    problem = Problem(model, move, bounds=Bounds(max_error=0.005), sampling=Sampling(period=0.002), loop=Loop(controller="none"))
    return model, invert(problem, method=Automatic(family=Family(end="free")))


def test_the_free_end_s_run_is_simulated_through_the_window_it_was_judged_through(free_end) -> None:  # type: ignore[no-untyped-def]
    model, result = free_end
    held = result.summary["sampled"]
    assert result.summary["settings"]["end"] == "free" and result.window == held["window"] == 2.0
    # the case: the tip keeps moving after the table, close to the bound by the window's end
    assert held["drift"] > 1e-3 and 0.8 * 0.005 < held["after_end_excursion"] <= 0.005
    sim = simulate(model, result, plant="linear", controller="none")
    feed_end = float(result.summary["verification"]["after_end"]["feed_end"])
    assert sim.summary["t_end"] == pytest.approx(feed_end + 2.0, abs=1e-9)
    judged = max(held["max_tip_error"], held["after_end_excursion"])
    # the linear plant driven by the held rows is the judged one: the same largest error, within the integrator's
    # tolerance (the judged after-end figure is on the window's grid, 4 points a period of the fastest mode)
    assert sim.summary["max_tracking_error"] == pytest.approx(judged, rel=0.02)
    assert sim.summary["max_tracking_error"] <= 0.005


def test_a_run_read_back_keeps_its_window_and_a_longer_window_is_simulated_longer(free_end, tmp_path) -> None:  # type: ignore[no-untyped-def]
    model, result = free_end
    write_run(result, tmp_path / "run")
    again = read_run(tmp_path / "run", model)
    assert again.window == 2.0
    longer = invert(Problem(model, result.trajectory, bounds=Bounds(max_error=np.inf, max_torque_rate=np.inf),
                            sampling=Sampling(period=0.002, window=3.0), loop=Loop(controller="none")),
                    method=Automatic(family=Family(end="free")))
    assert longer.window == 3.0
    sim = simulate(model, longer, plant="linear", controller="none")
    assert sim.summary["t_end"] == pytest.approx(float(longer.summary["verification"]["after_end"]["feed_end"]) + 3.0, abs=1e-9)


def test_the_summary_says_when_the_rate_a_free_end_keeps_carries_the_tip_past_the_bound(free_end) -> None:  # type: ignore[no-untyped-def]
    from sflm.summaries import inversion_text

    model, result = free_end
    held = result.summary["sampled"]
    later = (0.005 - held["after_end_excursion"]) / abs(held["drift"])
    text = inversion_text(result, [])
    assert f"past the bound about {later:.2g} s after the window" in text
    # the linear plant left alone: at the window's end plus that time, give or take the vibration, the tip is past it
    feed_end = float(result.summary["verification"]["after_end"]["feed_end"])
    sim = simulate(model, result, plant="linear", controller="none", t_end=feed_end + 2.0 + later + 1.0)
    assert sim.summary["max_tracking_error"] > 0.005
