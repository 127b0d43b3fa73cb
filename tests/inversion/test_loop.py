"""Judged in the loop it runs in (issue 47, item 7): ``invert(controller="pd")`` holds the table to the bound with the
joint PD of Eq. (40) closed as well, during the move and after it, and reports both loops; the figures are checked
against the closed-loop simulation (CasADi's integrator on the linear plant, :mod:`simulation`), written apart from
the acceptance's exactly discretised loop."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import control
import pytest

import modelgen
from inversion import invert, smoothstep
from inversion.errors import SettingsError
from inversion.methods.margin import held_error
from modelgen.joint_pd import loop_gains

DATA = Path(__file__).resolve().parents[1] / "data"
#: The heavy payload's 0.5 m in 0.343 s: the automatic choice is optimal control. Measured (2026-12-03): with the
#: feedforward alone judged, the default table (10 % inside the bound) is 1.085 x the bound in the PD loop
#: (k_P 207.9, k_D 37.82, the rule's); planned for the loop too, 0.899 x, its peak 38.23 N m against 37.70.
HEAVY = ("heavy-payload.toml", smoothstep(0.5, 0.343, 2))


#: What the default run (both loops) said as it went.
SAID: list[str] = []


@pytest.fixture(scope="module")
def heavy():  # type: ignore[no-untyped-def]
    model = modelgen.load(str(DATA / HEAVY[0]))
    SAID.clear()
    # alone as asked; the default: both loops
    return model, invert(model, HEAVY[1], controller="none"), invert(model, HEAVY[1], progress=SAID.append)


def test_the_feedforward_alone_is_not_enough_in_the_loop(heavy) -> None:  # type: ignore[no-untyped-def]
    """The default table, judged alone, leaves the bound once the joint PD is closed: what the loop check is for."""
    model, alone, _ = heavy
    bound = float(alone.summary["max_error"])
    during, after = held_error(alone, gains=loop_gains(model))
    assert "loop" not in alone.summary and "loop_error" not in alone.summary["sampled"]
    assert max(during, after) > bound  # measured 1.085 x


def test_judged_in_the_loop_the_table_holds_the_bound_in_both(heavy) -> None:  # type: ignore[no-untyped-def]
    model, alone, looped = heavy
    loop = looped.summary["loop"]
    bound = float(looped.summary["max_error"])
    assert loop["controller"] == "pd" and (loop["kp"], loop["kd"]) == pytest.approx(loop_gains(model))
    assert loop["bound"] == bound
    assert max(loop["pd"]["during"], loop["pd"]["after"]) <= bound
    assert max(loop["feedforward"]["during"], loop["feedforward"]["after"]) <= bound
    # the same figures as the margin module's own loop, and as the summary's held block
    assert (loop["pd"]["during"], loop["pd"]["after"]) == pytest.approx(held_error(looped, gains=loop_gains(model)), rel=1e-9)
    assert looped.summary["sampled"]["loop_error"] == pytest.approx(loop["pd"]["during"], rel=1e-12)
    # the table planned for the loop (the PD's references in the programme, issue 60, item 2): the margin asked kept in
    # both loops at a little more peak (measured 38.23 against 37.70 N m; tightening the tube instead took 38.86)
    assert float(looped.summary["peak_torque"]) <= 1.03 * float(alone.summary["peak_torque"])
    assert looped.summary["method"] == "ocp" and looped.summary["ocp"]["margin"] == alone.summary["ocp"]["margin"] == 0.1
    assert max(loop["pd"]["during"], loop["pd"]["after"]) <= 0.9 * bound * (1 + 1e-3)


def test_the_table_planned_again_is_the_only_one_smoothed(heavy) -> None:  # type: ignore[no-untyped-def]
    """Only the table returned needs its smoothing pass (issue 56, item 3): the least-peak table planned alone is judged
    in the loop first (measured 1.206 x the bound there, where its smoothed table was 1.085 x: both past the half of the
    margin that sends it to be planned again), so one programme fewer is solved, and the table returned is the same."""
    model, alone, looped = heavy
    again = next(i for i, m in enumerate(SAID) if "planned again, for the loop too" in m)
    smoothed = [i for i, m in enumerate(SAID) if "the smoothest under the peak" in m]
    assert smoothed and min(smoothed) > again and len(smoothed) == 1  # the loop's table only
    assert "smoothest under the peak" in " ".join(m for m in SAID if "solved in" in m)
    assert looped.summary["ocp"]["smoothing"]["status"] == "solved" and alone.summary["ocp"]["smoothing"]["status"] == "solved"
    # the message's figure is the least-peak table's in the loop, past the margin's half (aimed 0.9: 0.95 of the bound)
    said = float(SAID[again].split("the tip is ")[1].split(" of the bound")[0])
    assert said > 0.95
    # ... and not the smoothed table's (the one returned alone: 1.085 x in the loop)
    smoothed_alone = max(held_error(alone, gains=loop_gains(model))) / float(alone.summary["max_error"])
    assert abs(said - smoothed_alone) > 0.05


def test_the_loop_figures_are_the_simulated_closed_loop(heavy) -> None:  # type: ignore[no-untyped-def]
    """The closed-loop simulation (CasADi's integrator, the references held as the table holds them) of the returned
    table on the linear plant: its largest tip error is the acceptance's loop figure."""
    from simulation import simulate

    model, _, looped = heavy
    simulated = simulate(model, looped, plant="linear", controller="pd")
    assert simulated.summary["max_tracking_error"] == pytest.approx(looped.summary["loop"]["pd"]["during"], rel=0.02)
    assert simulated.summary["max_tracking_error"] <= float(looped.summary["max_error"])


def test_a_family_member_passes_in_the_loop_as_it_is() -> None:
    """Where the family's member holds in the loop (the steel strip's 1 m in 0.6 s: 0.804 of the bound both ways) the
    loop changes nothing but the report."""
    model = modelgen.load(str(DATA / "steel-strip.toml"))
    alone = invert(model, smoothstep(1.0, 0.6, 2))
    looped = invert(model, smoothstep(1.0, 0.6, 2), controller="pd")
    assert looped.summary["method"] == alone.summary["method"] == "ssef"
    assert looped.summary["peak_torque"] == pytest.approx(alone.summary["peak_torque"], rel=1e-12)
    assert looped.summary["loop"]["pd"]["during"] <= looped.summary["max_error"]


def test_no_gains_is_the_feedforward_alone(heavy) -> None:  # type: ignore[no-untyped-def]
    """A loop with k_P = k_D = 0 is the plant alone: the closed loop's figures reduce to the acceptance's."""
    _, alone, _ = heavy
    during, after = held_error(alone, gains=(0.0, 0.0))
    assert during == pytest.approx(alone.summary["sampled"]["max_tip_error"], rel=1e-9)
    assert after == pytest.approx(held_error(alone)[1], abs=1e-12)


def test_given_gains_are_used_and_a_missing_one_is_the_default() -> None:
    model = modelgen.load("paper-sim")
    result = invert(model, smoothstep(1.57, 5.5, 5), controller="pd", gains=(20.0, None))
    assert (result.summary["loop"]["kp"], result.summary["loop"]["kd"]) == (20.0, 30.0)  # the paper's k_D
    assert result.summary["loop"]["gains"] == "given"
    assert result.summary["margin"]["radius"]["pd"]["gains"] == {"kp": 20.0, "kd": 30.0}


@pytest.mark.parametrize("kwargs,parameter", [
    ({"controller": "pid"}, "controller"),
    ({"controller": "none", "gains": (10.0, 1.0)}, "gains"),
    ({"controller": "pd", "gains": (-1.0, 1.0)}, "gains"),
    ({"controller": "pd", "gains": (float("nan"), 1.0)}, "gains"),
    ({"controller": "pd", "gains": (1.0,)}, "gains"),
    ({"controller": "pd", "gains": "fast"}, "gains"),
])
def test_bad_loops_are_refused_by_name(kwargs: dict, parameter: str) -> None:  # type: ignore[type-arg]
    with pytest.raises(SettingsError) as info:
        invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 5), **kwargs)
    assert info.value.parameter == parameter


def test_a_system_has_no_joint_to_close() -> None:
    with pytest.raises(SettingsError, match="no joint"):
        invert(control.tf([-1.0, 2.0], [1.0, 4.0, 3.0]), smoothstep(1.0, 8.0, 6), controller="pd")


def _sflm(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "sflm", *args], capture_output=True, text=True, timeout=600)


def test_the_command_line_judges_in_the_loop(tmp_path: Path) -> None:
    run = _sflm("invert", "paper-sim", "--controller", "pd", "--kp", "20", "--json", "-q", "--out", str(tmp_path))
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert summary["loop"]["kp"] == 20.0 and summary["loop"]["pd"]["during"] <= summary["max_error"]
    text = _sflm("invert", "paper-sim", "--controller", "pd", "-q", "--out", str(tmp_path / "text"))
    assert "in the loop" in text.stdout and "k_P 15" in text.stdout


def test_a_gain_without_the_loop_is_one_line() -> None:
    run = _sflm("invert", "paper-sim", "--controller", "none", "--kp", "20", "-q")
    assert run.returncode == 2
    assert run.stderr.strip().count("\n") == 0 and "--kp" in run.stderr and "--controller none" in run.stderr
