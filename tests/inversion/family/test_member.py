"""The family of redefinitions on the user's own case: quality gate, robust joinings, verification, automatic choice.

Reference values are measured with this implementation unless a source is named; the
tolerances say what they guard.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import mpmath
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import modelgen
import inversion.family.ssef.basis as ssef  # the exponents: where MATCH_RATIO is read
from inversion import (
    CallableTrajectory, Family, InversionError, InversionSettings, SettingsError, experiment_trajectory, invert, smoothstep,
)
from inversion.family.anchors import exponential_moments, tracking_anchors
from inversion.family.member import evaluate_member
from inversion.lti.system import NormalForm

from _helpers import linear_plant_output

DATA = Path(__file__).resolve().parents[2] / "data"
PAPER_SIM = dict(segments=5, h=2, cdec=(1e-4, 1.0))  # section 7


@pytest.fixture(scope="module")
def own() -> modelgen.Model:
    return modelgen.load(DATA / "own-aluminium.toml")


QUINTIC = smoothstep(0.5, 2.0, 2)  # the textbook quintic: jerk 3.75 m/s^3 at both ends


# -- the quality gate -------------------------------------------------------------------


def test_quality_gate_refuses_the_paper_settings_on_an_own_link(own: modelgen.Model) -> None:
    # The issue's report: the own link's quintic with the paper's member ends metres away
    # (measured here: 1.17 m off a 0.5 m move) -- refused, with the figure and the hint.
    with pytest.raises(InversionError) as info:
        invert(own, QUINTIC, joining="paper", **PAPER_SIM)
    assert info.value.status == "max-error"  # type: ignore[attr-defined]
    message = str(info.value)
    assert "m from the desired one" in message and "% of the 0.5 m move" in message and "auto" in message
    # inf accepts anything (the torque and its rate are bounds too: inf for them as well)
    accepted = invert(own, QUINTIC, joining="paper", max_error=math.inf, max_torque=math.inf, max_torque_rate=math.inf, **PAPER_SIM)
    assert accepted.summary["relative_redefinition_error"] > 1.0
    assert accepted.summary["max_error"] == math.inf


def test_one_segment_with_zero_targets_is_refused() -> None:
    # One segment on the paper's trajectory: every joining target is zero, so y~ = 0 -- no
    # motion at all, the whole move of error (the issue's "success" that was not one).
    with pytest.raises(InversionError, match=r"1\.57 m from the desired one \(100 %"):
        invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 5), segments=1, h=2, cdec=(1e-4, 1.0), joining="paper")


def test_gate_default_is_five_percent_of_the_move() -> None:
    model = modelgen.load("paper-sim")
    r = invert(model, smoothstep(1.57, 5.5, 5))  # the paper's case and member
    s = r.summary
    assert s["settings"]["joining"] == "paper" and "auto" not in s
    assert s["move"] == pytest.approx(1.57, rel=1e-12)
    assert s["max_error"] == pytest.approx(0.05 * 1.57)
    assert s["relative_redefinition_error"] == pytest.approx(5.7333e-3 / 1.57, rel=1e-4)  # 0.37 % (the issue)
    with pytest.raises(InversionError, match="accepted 0.001 m"):
        invert(model, smoothstep(1.57, 5.5, 5), max_error=1e-3)


def test_paper_experiment_passes_the_gate() -> None:
    r = invert(modelgen.load("paper-exp"), experiment_trajectory())
    assert r.summary["relative_redefinition_error"] == pytest.approx(0.01355, abs=5e-6)  # 1.35 % (the issue)


def test_summary_figures_come_from_the_closed_form_not_the_samples() -> None:
    # At 1 Hz the samples of a 5.5 s manoeuvre miss the peaks; the summary does not.
    model = modelgen.load("paper-sim")
    fine = invert(model, smoothstep(1.57, 5.5, 5), rate=20_000.0, period=1e-3)
    coarse = invert(model, smoothstep(1.57, 5.5, 5), rate=1.0, period=1e-3)  # the controller's period is another matter
    for key in ("max_redefinition_error", "peak_torque", "time_of_peak_torque", "time_of_max_redefinition_error"):
        assert coarse.summary[key] == pytest.approx(fine.summary[key], rel=1e-12), key
    assert np.abs(coarse.tau).max() < 0.99 * coarse.summary["peak_torque"]  # the 7 samples miss the peak by 4 %
    # and the refined figures bound the densest samples from above, within their resolution
    assert np.abs(fine.tau).max() <= fine.summary["peak_torque"] <= np.abs(fine.tau).max() * (1 + 1e-8)
    assert np.abs(fine.y - fine.y_d).max() <= fine.summary["max_redefinition_error"]


# -- the robust formulation -------------------------------------------------------------


def test_anchored_joining_meets_its_conditions_at_every_joint() -> None:
    model = modelgen.load("paper-sim")
    traj = smoothstep(1.57, 5.5, 5)
    r = invert(model, traj, segments=10, h=2, cdec=(1e-4, 1.0), joining="anchored")
    redef = r.redefinition
    assert redef is not None
    anchors = tracking_anchors(r.modal, traj, r.joints)
    unstable = r.modal.unstable
    for seg in r.segments:
        end = redef.evaluate_local(seg.index, [seg.duration])
        start = redef.evaluate_local(seg.index, [0.0])
        for values, t in ((start, seg.t_start), (end, seg.t_end)):
            # position and velocity joining: y~ and ydot~ equal y_d and ydot_d at the joints
            assert values["y"][0] == pytest.approx(traj.derivative([t], 0)[0], abs=1e-12 * 1.57)
            assert values["ydot"][0] == pytest.approx(traj.derivative([t], 1)[0], abs=1e-12)
        # the unstable modes start and end on the exact-tracking anchors z*
        z_start = seg.evaluate([0.0])[3][0]
        z_end = seg.evaluate([seg.duration])[3][0]
        scale = np.abs(anchors[:, unstable]).max()
        np.testing.assert_allclose(z_end[unstable], anchors[seg.index + 1, unstable], rtol=0, atol=1e-10 * scale)
        if seg.index > 0:
            np.testing.assert_allclose(z_start[unstable], anchors[seg.index, unstable], rtol=0, atol=1e-10 * scale)
    assert r.summary["amplification"] is None  # nothing carried, nothing to amplify
    assert r.summary["max_output_jump"] < 1e-12 and r.summary["max_torque_jump"] < 1e-10


@pytest.mark.parametrize("lam", [65.26, 56.31j, 300 + 400j])
def test_anchor_moments_against_40_digit_quadrature(lam: complex) -> None:
    # int_0^T exp(-lambda u) yddot_d(t_k + u) du: composite Gauss-Legendre against mpmath
    traj = experiment_trajectory()  # has breakpoints at 0.2 and 0.4 s inside [0.1, 0.5]
    got = exponential_moments(traj, 0.1, 0.5, np.array([lam]))[0]
    mpmath.mp.dps = 40
    f = lambda u: mpmath.exp(-mpmath.mpc(lam) * u) * traj.derivative([0.1 + float(u)], 2)[0]  # noqa: E731
    ref = complex(mpmath.quad(f, [0, 0.1, 0.3, 0.4]))
    assert abs(got - ref) <= 1e-13 * max(abs(ref), 1e-3)


def test_anchors_are_the_backward_integral_of_the_desired_acceleration() -> None:
    model = modelgen.load("paper-sim")
    traj = smoothstep(1.57, 5.5, 3)
    modal = NormalForm.of_model(model).modal()
    bounds = np.linspace(0.0, 5.5, 6)
    anchors = tracking_anchors(modal, traj, bounds)
    i = int(np.flatnonzero(modal.unstable & (np.abs(modal.lam.imag) > 1))[0])  # the imaginary zero
    lam, beta = complex(modal.lam[i]), complex(modal.beta[i])
    mpmath.mp.dps = 30
    integrand = lambda s: mpmath.exp(mpmath.mpc(lam) * (2.2 - s)) * traj.derivative([float(s)], 2)[0]  # noqa: E731
    ref = -beta * complex(mpmath.quad(integrand, np.linspace(2.2, 5.5, 12).tolist()))
    assert abs(anchors[2, i] - ref) <= 1e-12 * abs(ref)
    assert np.all(anchors[-1] == 0) and np.all(anchors[:, ~modal.unstable] == 0)


def test_matched_exponentials_keep_a_six_mode_model_solvable(monkeypatch: pytest.MonkeyPatch) -> None:
    # paper-sim with 6 modes has unstable zeros of 300-800 rad/s, far faster than the slow
    # exponentials: with the equally spaced basis alone the segment systems reach condition
    # numbers of 5e11-3e17 and fail; with the matched exponentials 6e6-2e8, verified.
    model = modelgen.load("paper-sim", modes=6)
    form = NormalForm.of_model(model)
    traj = smoothstep(1.57, 5.5, 2)
    members = [InversionSettings(30, 1, (1e-12, 1.0), "anchored"), InversionSettings(10, 1, (1e-8, 1.0), "anchored"),
               InversionSettings(4, 1, (1e-4, 1.0), "anchored")]
    for s in members:
        r = evaluate_member(form, traj, s)
        assert r.ok, r.message
        assert r.max_condition_number < 1e9
        assert r.checks is not None and r.checks.solver_torque < 1e-9 and r.checks.precision_torque < 1e-9
    monkeypatch.setattr(ssef, "MATCH_RATIO", math.inf)
    for s in members:
        r = evaluate_member(form, traj, s)
        assert not r.ok and r.max_condition_number > 1e11


# -- acceptance that matches correctness ------------------------------------------------


def test_the_solver_dependent_member_of_the_issue_is_refused_or_consistent() -> None:
    # The issue: near-non-hyperbolic, n = 3, 3 segments, h = 2, Cdec (0.1, 0.5) -- LU and
    # least squares differed by 26 % of the torque and both passed the residual check.
    model = modelgen.load("near-non-hyperbolic", modes=3)
    kwargs = dict(segments=3, h=2, cdec=(0.1, 0.5), joining="paper", max_error=math.inf)
    try:
        lu = invert(model, smoothstep(1.57, 5.5, 5), **kwargs)
    except InversionError as exc:
        assert exc.status in ("solver", "precision", "residual")  # type: ignore[attr-defined]
        return
    lstsq = invert(model, smoothstep(1.57, 5.5, 5), solver="lstsq", **kwargs)
    assert np.abs(lu.tau - lstsq.tau).max() <= 1e-6 * np.abs(lu.tau).max()


def test_every_returned_result_is_verified() -> None:
    r = invert(modelgen.load("hyperbolic"), smoothstep(1.57, 5.5, 5))
    v = r.summary["verification"]
    assert v["solver_torque_difference"] <= 1e-6 and v["solver_output_difference"] <= 1e-6
    assert v["precision"] == "longdouble" and v["precision_torque_difference"] <= 1e-6
    assert v["plant_output_error"] <= 1e-6 and v["plant_steps"] > 1000


# -- the settings type ------------------------------------------------------------------


def test_settings_round_trip_and_bad_values(tmp_path: Path) -> None:
    s = InversionSettings(segments=12, h=3, cdec=(1e-6, 0.5), joining="position", eps=0.1)
    assert InversionSettings.from_dict(json.loads(json.dumps(s.to_dict()))) == s
    path = tmp_path / "best.json"
    path.write_text(json.dumps({"settings": s.to_dict(), "model": "x"}))
    assert InversionSettings.from_json(path) == s
    with pytest.raises(SettingsError, match="'colour'"):
        InversionSettings.from_dict({"colour": 3})
    with pytest.raises(SettingsError, match="joining"):
        InversionSettings(joining="glued")
    with pytest.raises(SettingsError, match="^settings = .*not valid JSON"):  # Python's word; the command line says --settings
        path.write_text("{not json")
        InversionSettings.from_json(path)
    with pytest.raises(SettingsError, match="segments"):
        InversionSettings(segments=0)


def test_a_summary_reproduces_its_member(own: modelgen.Model, tmp_path: Path) -> None:
    first = invert(own, QUINTIC, segments=8, h=2, cdec=(1e-6, 1.0), edges="rest", max_torque_rate=math.inf)
    path = tmp_path / "summary.json"
    first.write_summary(path)
    again = invert(own, QUINTIC, settings=path, max_torque_rate=math.inf)
    assert again.settings.edges == "rest" and again.settings.segment_count == 8  # the edges are part of the member
    np.testing.assert_array_equal(again.tau, first.tau)


# -- the automatic choice ---------------------------------------------------------------


@pytest.fixture(scope="module")
def own_auto(own: modelgen.Model):  # type: ignore[no-untyped-def]
    # the smallest error within the torque limit (objective "error"): the choice these tests judge. The torque's rate is
    # left unbounded here: on this quintic the rate bound (10 x the rigid need's) leaves one member family-wide, and these
    # tests are of the trade between error and torque (test_reaches_the_link.py holds the rate bound)
    return invert(own, QUINTIC, objective="error", max_torque_rate=math.inf)


@pytest.fixture(scope="module")
def own_least_torque(own: modelgen.Model):  # type: ignore[no-untyped-def]
    return invert(own, QUINTIC)  # a geometry file's own trajectory: automatic by default, the least torque within 1 %


def test_auto_by_default_is_the_least_torque_that_reaches_the_link(own: modelgen.Model, own_least_torque, own_auto) -> None:  # type: ignore[no-untyped-def]
    # issue 20: the default objective is the engineer's -- the least peak torque whose redefinition
    # is within 1 % of the move -- and what reaches the link meets the same bound: after the move,
    # with four more modes, held at 1 kHz; the torque within 3 x what a rigid link needs
    s = own_least_torque.summary
    move = s["move"]
    assert s["auto"]["objective"] == "torque" and s["relative_redefinition_error"] <= 0.01
    assert s["torque_ratio"] <= 3 and s["peak_torque"] <= 3 * s["rigid_torque"]
    assert s["verification"]["after_end"]["max_tip_excursion"] <= 0.01 * move
    assert s["verification"]["truncation"]["modes"] == 6 and s["verification"]["truncation"]["tip_error"] <= 0.01 * move
    assert s["sampled"]["period"] == 1e-3 and s["sampled"]["max_tip_error"] <= 0.01 * move
    assert s["torque_rate_ratio"] <= 10 and s["sampled"]["after_end_excursion"] <= 0.01 * move  # the held table's rate and window
    free = invert(own, QUINTIC, max_torque_rate=math.inf)
    assert free.summary["peak_torque"] <= own_auto.summary["peak_torque"]  # the least torque: no more than the error objective's
    # a rigid link of the same inertia: J max |yddot_d| / L, J = I_h + rho L^3/3 + m_t L^2 + I_t
    g = own.geometry
    J = g.hub_inertia + g.linear_density * g.length**3 / 3 + g.payload_mass * g.length**2 + g.payload_inertia
    t = np.linspace(0.0, 2.0, 20_001)
    assert s["rigid_torque"] == pytest.approx(J * np.abs(QUINTIC.derivative(t, 2)).max() / g.length, rel=1e-9)
    y, _ = linear_plant_output(own, own_least_torque, rate=40_000.0)
    assert np.abs(y - own_least_torque.y).max() < 1e-6 * move


def test_auto_on_the_own_link_quintic(own: modelgen.Model, own_auto) -> None:  # type: ignore[no-untyped-def]
    # The issue: 1.38 m with the defaults before; with the "error" objective the chosen member is
    # within 0.05 % of the move, with at most 1.5 x the least torque the family needs within the
    # bound (no doubling: issue 20).
    s = own_auto.summary
    assert s["relative_redefinition_error"] < 5e-4
    assert s["auto"]["objective"] == "error" and s["auto"]["max_torque_rule"].startswith("1.5 x the least peak torque")
    assert s["peak_torque"] <= s["auto"]["max_torque"]
    assert s["auto"]["members"] > 300 and s["auto"]["verified"] >= 1 and "failed" in s["auto"]  # a coarse grid, then its refinement
    assert s["settings"]["joining"] in ("position", "anchored")
    # an integrator that knows nothing of the closed form agrees: the plant follows y~
    y, _ = linear_plant_output(own, own_auto, rate=40_000.0)
    assert np.abs(y - own_auto.y).max() < 1e-6 * 0.5


def test_auto_results_do_not_depend_on_the_solver_or_the_data_rounding(own: modelgen.Model, own_auto) -> None:  # type: ignore[no-untyped-def]
    chosen = own_auto.settings
    peak = own_auto.summary["peak_torque"]
    lstsq = invert(own, QUINTIC, settings=chosen, solver="lstsq", max_torque_rate=math.inf)
    assert np.abs(lstsq.tau - own_auto.tau).max() <= 1e-6 * peak
    # a perturbation at the level of the data's rounding moves the torque by no more
    nudged = invert(own, smoothstep(0.5 * (1 + 4e-16), 2.0, 2), settings=chosen, max_torque_rate=math.inf)
    assert np.abs(nudged.tau - own_auto.tau).max() <= 1e-6 * peak


def test_auto_respects_the_torque_limit(own: modelgen.Model, own_auto) -> None:  # type: ignore[no-untyped-def]
    limit = 0.06
    r = invert(own, QUINTIC, max_torque=limit, objective="error", max_torque_rate=math.inf)
    assert r.summary["peak_torque"] <= limit < own_auto.summary["peak_torque"]
    assert r.summary["max_redefinition_error"] >= own_auto.summary["max_redefinition_error"]
    assert r.summary["auto"]["max_torque_rule"] == "given"
    # lifting the budget buys a smaller error with (much) more torque: the trade is recorded
    free = invert(own, QUINTIC, max_torque=math.inf, objective="error", max_torque_rate=math.inf)
    assert free.summary["max_redefinition_error"] < own_auto.summary["max_redefinition_error"]
    assert free.summary["peak_torque"] > 5 * own_auto.summary["peak_torque"]
    alternatives = own_auto.summary["auto"]["alternatives"]
    assert alternatives and all(a["peak_torque"] < own_auto.summary["peak_torque"] for a in alternatives
                                if a["kind"] == "less torque")


def test_auto_keeps_the_dimensions_it_is_given(own: modelgen.Model) -> None:
    r = invert(own, QUINTIC, auto=True, segments=8, joining="anchored")
    assert r.settings.segment_count == 8 and r.settings.joining == "anchored"
    assert r.summary["auto"]["fixed"] == {"segments": 8, "joining": "anchored"}
    sampled = CallableTrajectory(QUINTIC.derivative, 0.0, 2.0, max_derivative=5, name="quintic to order 5")
    with pytest.raises(SettingsError, match="h = 4"):
        invert(own, sampled, auto=True, h=4)  # h needs yddot's 4th derivative, order 6


@pytest.mark.slow  # 13 s, the search for a 15 s move's duration; the same refusal's path: test_bounded_limit's cliff, 3 s
def test_auto_with_an_impossible_torque_limit_fails_clearly(own: modelgen.Model) -> None:
    # refused before any member is tried: within a torque of 1e-3 no causal feedforward comes within 1 % (95.5 % at best)
    with pytest.raises(InversionError, match=r"^no causal feedforward within the bounds exists: held at 1 ms with the torque "
                       r"within 0.001 .* closer than 0.4773 \(95.5 % of the move\)"):
        invert(own, QUINTIC, max_torque=1e-3)


_E = {"aluminium": (69e9, 2700.0), "steel": (200e9, 7900.0), "titanium": (110e9, 4500.0)}


@pytest.mark.slow
@settings(max_examples=6, deadline=None)
@given(
    material=st.sampled_from(sorted(_E)),
    length=st.floats(0.3, 1.5),
    width=st.floats(0.01, 0.05),
    thickness=st.floats(0.001, 0.004),
    hub=st.floats(1e-3, 5e-2),
    payload=st.floats(0.0, 0.3),
    tip_inertia=st.floats(0.0, 1e-3),
    damping=st.sampled_from([0.0, 0.01]),
    modes=st.integers(1, 4),
    distance=st.floats(0.05, 1.0),
    duration=st.floats(0.5, 6.0),
    order=st.integers(2, 5),
)
def test_auto_on_plausible_links_returns_verified_results_or_fails_clearly(
    material: str, length: float, width: float, thickness: float, hub: float, payload: float, tip_inertia: float,
    damping: float, modes: int, distance: float, duration: float, order: int,
) -> None:
    E, density = _E[material]
    geometry = modelgen.parse_geometry({
        "name": "fuzz",
        "link": {"length": length, "youngs_modulus": E, "density": density, "width": width, "thickness": thickness},
        "hub": {"inertia": hub},
        "payload": {"mass": payload, "inertia": tip_inertia},
        "damping": {"ratio": damping},
        "model": {"modes": modes},
    })
    model = modelgen.load(geometry)
    try:
        r = invert(model, smoothstep(distance, duration, order), auto=True)
    except InversionError as exc:
        assert "no member of the family passes" in str(exc)
        return
    s = r.summary
    assert s["relative_redefinition_error"] <= 0.05
    v = s["verification"]
    assert v["plant_output_error"] <= 1e-6 and v["solver_torque_difference"] <= 1e-6
    assert v["precision"] != "longdouble" or v["precision_torque_difference"] <= 1e-6
    assert np.all(np.isfinite(r.tau)) and s["max_torque_jump"] <= 1e-6 * s["peak_torque"]


@pytest.mark.slow
@pytest.mark.parametrize("preset,modes,distance,duration,limit", [("paper-exp", 4, 0.1, 0.6, 1.0), ("paper-sim", 6, 1.57, 5.5, None)])
def test_auto_on_many_mode_presets_with_the_quintic(preset: str, modes: int, distance: float, duration: float,
                                                    limit: float | None) -> None:
    # two of the hardest cases of benchmarks/sweep_auto.py: fast unstable zeros, a trajectory whose
    # jerk does not vanish at the ends. paper-exp with four modes: its least torque within 1 % is
    # 0.877 N m, 1.72 x what a rigid link of the same inertia and hub damping (b_h = 0.32 N m s/rad)
    # needs, 0.509 N m -- within the default limit of 3 x (without the damping the need was 0.209 and
    # the member refused); the optimal-control limit at 10 ms is 0.423 N m
    # the quintic's jerk at its start makes every member's torque rise faster than ten times the rigid need's rate at
    # 1 kHz (the default bound: issue 33); these figures are of the family with the rate left free
    if limit is not None:
        r = invert(modelgen.load(preset, modes=modes), smoothstep(distance, duration, 2), auto=True, max_torque_rate=math.inf)
        # 1.72 x when the members matched the quintic's jerk at its ends; meeting y_d's acceleration there with its
        # derivatives zero (edges="rest"), the least torque is what a rigid link needs (measured 1.0009 x)
        assert r.summary["torque_ratio"] <= 1.05
        assert r.summary["rigid_torque"] == pytest.approx(0.5091, rel=1e-3)
    r = invert(modelgen.load(preset, modes=modes), smoothstep(distance, duration, 2), auto=True, max_torque=limit,
               max_torque_rate=math.inf)
    assert r.summary["relative_redefinition_error"] < 1e-2  # the issue's "within 1 % of the move"
    assert r.summary["verification"]["plant_output_error"] <= 1e-6
    assert r.summary["peak_torque"] <= r.summary["auto"]["max_torque"]


def test_the_automatic_choice_reports_its_members_as_it_goes() -> None:
    # issue 25: a search of tens of seconds shows a bar, not two or three lines; the search calls progress.count(done,
    # total) after each batch, total growing when it refines
    class Recorder:
        def __init__(self) -> None:
            self.lines: list[str] = []
            self.counts: list[tuple[int, int]] = []

        def __call__(self, message: str) -> None:
            self.lines.append(message)

        def count(self, done: int, total: int) -> None:
            self.counts.append((done, total))

    recorder = Recorder()
    model = modelgen.load("paper-sim")
    result = invert(model, smoothstep(1.57, 5.5, 3), method=Family(), progress=recorder)  # the family's search
    done = [d for d, _ in recorder.counts]
    assert len(recorder.counts) > 3 and done == sorted(done) and all(d <= t for d, t in recorder.counts)
    first = int(next(line for line in recorder.lines if line.startswith("auto:")).split()[1])  # "auto: 252 members on ..."
    assert recorder.counts[0][1] == first and recorder.counts[-1][0] == recorder.counts[-1][1] >= first
    assert recorder.counts[-1][0] == result.summary["auto"]["members"]
