"""The polynomial redefinition baseline (the paper's Eq. (2)): one solution per segmentation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import make_interp_spline

import modelgen
from inversion import InversionError, SettingsError, invert, trajectory_from_spec


@pytest.mark.parametrize("preset,kwargs", [
    ("near-non-hyperbolic", {}),  # the paper's segmentation and h
    ("paper-exp", {"segments": 3, "h": 1, "joining": "position"}),
    ("hyperbolic", {"segments": 3, "h": 1, "joining": "position"}),
])
def test_the_plant_reproduces_its_redefined_output(preset: str, kwargs: dict[str, object]) -> None:
    model = modelgen.load(preset)
    # the torque and its rate left free: the polynomial's steps at its joints are not what this test is about
    result = invert(model, trajectory_from_spec(preset if preset.startswith("paper") else "paper-sim"), method="polynomial",
                    max_torque=np.inf, max_torque_rate=np.inf, **kwargs)  # type: ignore[arg-type]
    assert result.summary["method"] == "polynomial"
    torque = make_interp_spline(result.t, result.tau, k=5)
    sol = solve_ivp(lambda t, x: model.A @ x + model.B * torque(t), (result.t[0], result.t[-1]), result.X[0], t_eval=result.t,
                    method="DOP853", rtol=1e-11, atol=1e-14)
    y = sol.y[: model.n + 1].T @ model.D
    assert np.abs(y - result.y).max() <= 1e-6 * result.summary["move"]
    assert result.summary["relative_redefinition_error"] <= 0.05
    # the redefined acceleration is a polynomial in each segment: joined smoothly at the joints
    k = np.searchsorted(result.t, [1 / 3 * result.t[-1]])
    assert np.all(np.isfinite(result.yddot)) and np.ptp(result.yddot[k[0] - 2 : k[0] + 2]) < 0.05 * np.ptp(result.yddot)


def test_a_carried_unstable_state_that_diverges_is_refused_with_its_figure() -> None:
    # paper-sim with the paper's segmentation: the polynomial cannot keep the unstable state
    # bounded from segment to segment; the result is metres away and refused, not returned
    with pytest.raises(InversionError, match=r"m from the desired output .* % of the 1.57 m move"):
        invert(modelgen.load("paper-sim"), trajectory_from_spec("paper-sim"), method="polynomial")


def test_polynomial_settings() -> None:
    model = modelgen.load("paper-exp")
    traj = trajectory_from_spec("paper-exp")
    with pytest.raises(SettingsError, match="cdec"):
        invert(model, traj, method="polynomial", cdec=(1e-3, 1.0))
    with pytest.raises(SettingsError, match="joining"):
        invert(model, traj, method="polynomial", joining="anchored")
    free = {"max_torque": np.inf, "max_torque_rate": np.inf}
    once = invert(model, traj, method="polynomial", segments=3, h=1, joining="position", **free)
    again = invert(model, traj, method="polynomial", segments=3, h=1, joining="position", **free)
    np.testing.assert_array_equal(once.tau, again.tau)  # one solution: nothing to choose


def test_the_compared_member_has_the_least_redefinition_error_of_the_grid() -> None:
    # sflm compare ranks the grid by the cheap figure and inverts only the best: the figure is the full inversion's,
    # and no member of the grid is closer to y_d than the one it returns
    import itertools
    import math

    from inversion import Bounds, Polynomial, Problem
    from inversion.api import resolve
    from inversion.methods.polynomial import COMPARE_H, COMPARE_SEGMENTS, POLYNOMIAL_JOININGS, polynomial_redefinition_error

    model, trajectory = modelgen.load("paper-exp"), trajectory_from_spec("smoothstep:0.5:1.0:5")
    for k, h, joining in [(5, 2, "paper"), (3, 1, "position")]:
        full = invert(model, trajectory, method="polynomial", segments=k, h=h, joining=joining, max_error=math.inf, max_torque=math.inf,
                      max_torque_rate=math.inf)
        assert polynomial_redefinition_error(model, trajectory, k, h, joining) == full.summary["max_redefinition_error"]
    best, note = Polynomial().compared(Problem(model, trajectory, bounds=Bounds(max_error=math.inf)), resolve)
    errors = [polynomial_redefinition_error(model, trajectory, k, h, j)
              for k, h, j in itertools.product(COMPARE_SEGMENTS, COMPARE_H, POLYNOMIAL_JOININGS)]
    assert best.summary["max_redefinition_error"] == min(errors) and "36 members" in note
    with pytest.raises(SettingsError, match="joining"):
        polynomial_redefinition_error(model, trajectory, 5, 2, "velocity")
