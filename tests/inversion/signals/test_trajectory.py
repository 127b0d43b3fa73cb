"""Desired trajectories: exact derivatives, one-sided limits, CSV input, bad input."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from inversion import CallableTrajectory, TrajectoryError, experiment_trajectory, from_csv, smoothstep, trajectory_from_spec


@pytest.mark.parametrize("order", [2, 3, 5, 7])
def test_smoothstep_rest_to_rest(order: int) -> None:
    traj = smoothstep(1.57, 5.5, order)
    ends = np.array([0.0, 5.5])
    np.testing.assert_allclose(traj.derivative(ends, 0), [0.0, 1.57], atol=1e-14)
    for k in range(1, order + 1):  # derivatives 1..order vanish at both ends (Eq. (37) for order 5)
        scale = 1.57 / 5.5**k * math.factorial(2 * order + 1)
        assert np.abs(traj.derivative(ends, k)).max() < 1e-12 * scale
    assert abs(traj.derivative([0.0], order + 1)[0]) > 1e-6  # and no more
    # symmetric: y(T/2) = D/2
    assert traj.derivative([2.75], 0)[0] == pytest.approx(0.785, rel=1e-14)


def test_smoothstep_derivatives_match_finite_differences() -> None:
    traj = smoothstep(2.0, 3.0, 5)
    t = np.linspace(0.3, 2.7, 7)
    h = 1e-5
    for k in range(1, 5):
        fd = (traj.derivative(t + h, k - 1) - traj.derivative(t - h, k - 1)) / (2 * h)
        np.testing.assert_allclose(traj.derivative(t, k), fd, rtol=1e-7, atol=1e-7 * np.abs(fd).max())


def test_trajectory_held_at_rest_outside() -> None:
    traj = smoothstep(1.0, 2.0)
    np.testing.assert_array_equal(traj.derivative([-1.0, 3.0], 0), [0.0, 1.0])
    np.testing.assert_array_equal(traj.derivative([-1.0, 3.0], 2), [0.0, 0.0])


def test_experiment_trajectory() -> None:
    # docs/method.md section 7: y_d(0.6) = 0.1 m, ydot_d(0.6) = 0 for a = 2.5 m/s^2
    traj = experiment_trajectory(2.5, 0.6)
    assert traj.derivative([0.6], 0)[0] == pytest.approx(0.1, rel=1e-13)
    assert abs(traj.derivative([0.6], 1)[0]) < 1e-14
    np.testing.assert_allclose(traj.derivative([0.0, 0.2, 0.4, 0.6], 2), [0.0, 2.5, -2.5, 0.0], atol=1e-13)
    np.testing.assert_allclose(traj.derivative([0.0, 0.2, 0.4, 0.6], 3), 0.0, atol=1e-10)  # zero slopes, C1
    # the jerk's slope jumps at the knots: one-sided limits (cubic Hermite pieces, h = 0.2)
    assert traj.derivative([0.2], 4, "-")[0] == pytest.approx(-6 * 2.5 / 0.2**2)
    assert traj.derivative([0.2], 4, "+")[0] == pytest.approx(-12 * 2.5 / 0.2**2)
    # joints computed as linspace land on the knots up to an ulp: still the right sides
    joint = np.linspace(0, 0.6, 7)[2]
    assert traj.derivative([joint], 4, "+")[0] == pytest.approx(-750.0)


def test_csv_trajectory(tmp_path: Path) -> None:
    ref = smoothstep(0.5, 2.0, 5)
    t = np.linspace(0, 2.0, 401)
    path = tmp_path / "traj.csv"
    path.write_text("t,y\n" + "\n".join(f"{float(a)!r},{float(b)!r}" for a, b in zip(t, ref.derivative(t, 0))))
    traj = from_csv(path)
    assert traj.max_derivative == 5 and (traj.t0, traj.tf) == (0.0, 2.0)
    inner = np.linspace(0.2, 1.8, 9)
    np.testing.assert_allclose(traj.derivative(inner, 0), ref.derivative(inner, 0), atol=1e-10)
    np.testing.assert_allclose(traj.derivative(inner, 2), ref.derivative(inner, 2), atol=1e-5)
    assert trajectory_from_spec(str(path)).name.startswith("traj.csv")


@pytest.mark.parametrize(
    "content,needle",
    [
        ("t,x\n0,1\n", "columns t and y"),
        ("t,y\n0,0\n1,1\n", "at least 7 samples"),
        ("t,y\n" + "\n".join(f"{i},{i}" for i in [0, 1, 2, 2, 3, 4, 5, 6]), "strictly increasing"),
        ("t,y\n" + "\n".join(f"{i},{'nan' if i == 3 else i}" for i in range(9)), "finite"),
        ("t,y\n" + "\n".join(f"{i},abc" for i in range(9)), "numeric"),
    ],
)
def test_bad_csv(tmp_path: Path, content: str, needle: str) -> None:
    path = tmp_path / "bad.csv"
    path.write_text(content)
    with pytest.raises(TrajectoryError, match=needle):
        from_csv(path)


@pytest.mark.parametrize(
    "spec", ["smoothstep:1", "smoothstep:a:b", "smoothstep:1:-2", "smoothstep:1:2:0", "circle", "missing.csv", "smoothstep:nan:1"]
)
def test_bad_specs(spec: str) -> None:
    with pytest.raises(TrajectoryError):
        trajectory_from_spec(spec)


def test_specs() -> None:
    assert trajectory_from_spec("paper-sim").derivative([5.5], 0)[0] == pytest.approx(1.57)
    assert trajectory_from_spec("paper-exp").tf == pytest.approx(0.6)
    assert trajectory_from_spec("smoothstep:0.3:1.5:3").name == "smoothstep(0.3 m, 1.5 s, order 3)"


def test_callable_trajectory_and_non_finite_values() -> None:
    def f(t: np.ndarray, k: int) -> np.ndarray:
        return np.where(t > 0.5, np.nan, np.sin(t + k * np.pi / 2))

    traj = CallableTrajectory(f, 0.0, 1.0, max_derivative=4)
    assert traj.derivative([0.1], 1)[0] == pytest.approx(np.cos(0.1))
    with pytest.raises(TrajectoryError, match="finite"):
        traj.derivative([0.7], 0)
    with pytest.raises(TrajectoryError, match="at most 4"):
        traj.derivative([0.1], 5)
    with pytest.raises(TrajectoryError):
        CallableTrajectory(f, 1.0, 0.0, 4)
