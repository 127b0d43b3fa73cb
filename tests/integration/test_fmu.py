"""The model and the feedforward as FMI 2.0 model-exchange FMUs (issue 25): valid by FMPy, and the same plant."""

from __future__ import annotations

import json
from ctypes import c_double
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import modelgen
from inversion import invert, trajectory_from_spec
from modelgen.errors import CodegenError, SettingsError
from sflm.cli import main
from simulation import simulate

fmpy = pytest.importorskip("fmpy")
from fmpy import read_model_description, simulate_fmu  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

from modelgen.abi import compiler_command  # noqa: E402

MOVE = 1.57  # paper-sim's
#: An FMU is compiled C: without a compiler (SFLM_CC empty) only the refusal is tested.
compiled = pytest.mark.skipif(compiler_command() is None, reason="an FMU needs a C compiler")


@pytest.fixture(scope="module")
def paper() -> tuple[modelgen.Model, object]:
    model = modelgen.load("paper-sim")
    return model, invert(model, trajectory_from_spec("paper-sim"))


def _drive(path: Path, tau, t_end: float, times: np.ndarray) -> np.ndarray:  # type: ignore[no-untyped-def]
    """The FMU's tip ``y`` at ``times``, its states integrated here (DOP853, tight) through the FMI calls with the torque
    ``tau(t)`` set exactly at every evaluation (an importer's input hold would add its own error)."""
    from fmpy import extract
    from fmpy.fmi2 import FMU2Model

    md = read_model_description(str(path))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Model(guid=md.guid, unzipDirectory=extract(str(path)), modelIdentifier=md.modelExchange.modelIdentifier, instanceName="t")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    fmu.enterContinuousTimeMode()
    nx = md.numberOfContinuousStates
    x_buffer, dx_buffer = (c_double * nx)(), (c_double * nx)()

    def set_state(x: np.ndarray) -> None:
        x_buffer[:] = [float(v) for v in x]
        fmu.setContinuousStates(x_buffer, nx)

    def rhs(t: float, x: np.ndarray) -> np.ndarray:
        fmu.setReal([vr["tau"]], [tau(t)])
        set_state(x)
        fmu.getDerivatives(dx_buffer, nx)
        return np.array(dx_buffer[:])

    sol = solve_ivp(rhs, (0.0, t_end), np.zeros(nx), method="DOP853", rtol=1e-11, atol=1e-13, t_eval=times, max_step=1e-2)
    out = []
    for x in sol.y.T:
        set_state(x)
        out.append(fmu.getReal([vr["y"]])[0])
    fmu.terminate()
    fmu.freeInstance()
    return np.array(out)


@compiled
def test_the_plant_fmu_is_valid_and_is_the_simulated_plant(paper, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    from modelgen.fmu import build_fmu

    model, result = paper
    path = build_fmu(model, tmp_path / "paper-sim.fmu", "nonlinear")
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    parameters = {v.name: float(v.start) for v in md.modelVariables if v.causality == "parameter"}
    assert list(parameters) == list(model.parameter_names) and np.array_equal(list(parameters.values()), model.parameters)
    assert [v.name for v in md.modelVariables if v.causality == "output"] == ["y", "theta", "thetadot", "delta_1", "delta_2"]
    # driven by the inversion's torque (zero after t_f, a free end) it is simulate's plant without a controller: measured 1.1e-10
    tf = result.trajectory.tf
    sim = simulate(model, result, plant="nonlinear", controller="none", t_end=6.5, rate=200.0)

    def tau(t: float) -> float:
        return float(result.signals.evaluate(np.array([t]))["tau"][0]) if t <= tf else 0.0

    y = _drive(path, tau, tf, sim.t[sim.t <= tf])
    assert np.abs(y - sim.y[sim.t <= tf]).max() <= 1e-6 * MOVE
    # and FMPy's own CVode runs it: within the hold of the input between its output points (1 ms: measured 2.9e-4)
    rows = [*zip(result.t, result.tau), (tf, 0.0), (6.5, 0.0)]
    signals = np.array(rows, dtype=[("time", np.float64), ("tau", np.float64)])
    fmpy_run = simulate_fmu(str(path), stop_time=6.5, input=signals, output=["y"], solver="CVode", relative_tolerance=1e-9,
                            output_interval=1e-3)
    assert np.abs(np.interp(sim.t, fmpy_run["time"], fmpy_run["y"]) - sim.y).max() <= 1e-3 * MOVE


@compiled
def test_the_linear_plant_fmu_is_the_linear_model(paper, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    from modelgen.fmu import build_fmu

    model, result = paper
    path = build_fmu(model, tmp_path / "linear.fmu", "linear")
    assert validate_fmu(str(path)) == []
    t = np.linspace(0.0, 2.0, 201)
    y = _drive(path, lambda s: float(np.sin(3.0 * s)) * 0.2, 2.0, t)
    # the linear model's response to the same torque, by the matrices
    A, B = model.A, model.B.reshape(-1)
    sol = solve_ivp(lambda s, x: A @ x + B * 0.2 * np.sin(3.0 * s), (0.0, 2.0), np.zeros(A.shape[0]), method="DOP853", rtol=1e-11,
                    atol=1e-13, t_eval=t)
    np.testing.assert_allclose(y, model.D @ sol.y[: model.n + 1], rtol=0, atol=1e-9)


@compiled
def test_the_feedforward_fmu_holds_the_judged_rows(paper, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    # issue 47: the FMU gave the series at its time where the controller holds the table the acceptance judged. Now it
    # holds the rows (inversion.csv's, bit for bit: the C's eval_held), each period's start a time event
    from inversion.realtime.feedforward_c import judged_rows
    from inversion.realtime.feedforward_fmu import build_feedforward_fmu

    model, result = paper
    path = build_feedforward_fmu(result, tmp_path / "ff.fmu")
    assert validate_fmu(str(path)) == []
    period, hold, rows = judged_rows(result)
    assert hold == "point" and period == 1e-3 and np.array_equal(rows[:, 0], result.tau[: rows.shape[0]])
    run = simulate_fmu(str(path), start_time=0.0, stop_time=6.0, output_interval=0.37e-3, output=["tau", "theta_d", "thetadot_d"])
    t = run["time"]
    k = np.floor(t / period + 1e-9).astype(int)
    inside = k < rows.shape[0]
    for m, name in enumerate(("tau", "theta_d", "thetadot_d")):
        assert np.array_equal(run[name][inside], rows[k[inside], m])
    assert np.all(run["tau"][~inside] == 0.0)  # the free end: no torque after the table


@compiled
def test_the_fmu_command(paper, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:  # type: ignore[no-untyped-def]
    assert main(["invert", "paper-sim", "--out", str(tmp_path / "inv")]) == 0
    capsys.readouterr()
    assert main(["fmu", "paper-sim", "--feedforward", str(tmp_path / "inv" / "summary.json"), "--out", str(tmp_path / "ff.fmu"),
                 "--json"]) == 0
    held = json.loads(capsys.readouterr().out)
    assert held["outputs"] == ["tau", "theta_d", "thetadot_d"] and held["peak_torque"] == pytest.approx(paper[1].summary["peak_torque"])
    for args, needle in [(["fmu", "paper-sim", "--out", str(tmp_path / "x.zip")], "ending in .fmu"),
                         (["fmu", "(2-s)/(s+1)^3"], "a preset or a geometry file"),
                         (["fmu", "paper-sim", "--trajectory", "paper-sim"], "nothing without --feedforward"),
                         (["fmu", "paper-sim", "--feedforward", str(tmp_path / "nothing.json")], "a readable file")]:
        assert main(args) == 2
        assert needle in capsys.readouterr().err


def test_no_compiler_no_fmu(paper, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:  # type: ignore[no-untyped-def]
    import modelgen.fmu as fmu

    monkeypatch.setattr(fmu, "compiler_command", lambda: None)
    with pytest.raises(CodegenError, match="needs a C compiler"):
        fmu.build_fmu(paper[0], tmp_path / "a.fmu")
    with pytest.raises(SettingsError, match="'linear' or 'nonlinear'"):
        fmu.build_fmu(paper[0], tmp_path / "a.fmu", "nonlinear-large")
