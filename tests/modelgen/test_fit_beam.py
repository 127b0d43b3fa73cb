"""Calibration judged on data sflm's model did not make (issue 48): an exact Euler-Bernoulli beam on a rotating hub
(``beam_truth.py``, written apart: its own boundary-value problem, no assumed modes) gives a glass-fibre rod's frequency
response, time records and natural frequencies; ``fit`` with its default parameters and modes must hold the truth
within the intervals it reports, neither too narrow nor too wide, or refuse."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.signal as ss

from modelgen.continuum import fe_frequencies_zeros, fe_matrices
from modelgen.fit import FitError, FrequencyData, FrequencyResponse, TimeSeries, _solve, fit, predicted
from modelgen.geometry import PARAMETER_KEYS, load_geometry, parse_geometry
from modelgen.record import lag_one, noise_level, resonances, torque_band

from beam_truth import Beam

DATA = Path(__file__).resolve().parents[1] / "data"
NOMINAL = load_geometry(DATA / "glass-fibre-rod.toml")  # two modes, 1 % damping
#: The rod on the bench: 6 % stiffer, a lighter payload, a heavier hub and payload inertia, more damping than its file.
TRUTH = replace(NOMINAL, flexural_rigidity=NOMINAL.flexural_rigidity * 1.06, payload_mass=0.092, hub_inertia=0.0055,
                payload_inertia=2.2e-5, damping_ratio=0.013)


def _beam(geometry=TRUTH) -> Beam:  # type: ignore[no-untyped-def]
    g = geometry
    beam = Beam(g.length, g.flexural_rigidity, g.linear_density, g.hub_inertia, g.payload_mass, g.payload_inertia)
    return beam.with_first_ratio(g.damping_ratio)


BEAM = _beam()


def _response(seed: int) -> FrequencyResponse:
    """300 points 2-60 Hz (the first two modes), 2 % complex noise, as an analyser's."""
    f = np.geomspace(2.0, 60.0, 300)
    rng = np.random.default_rng(seed)
    G = BEAM.response(f) * (1 + 0.02 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2))
    return FrequencyResponse(f, np.abs(G), np.rad2deg(np.angle(G)))


#: The same rod damped per mode (1.2 % in the first, 2 % in the others: not Rayleigh's proportion), and its file's
#: modal damping (1 %): a ratio per mode the response reaches is fitted.
MODAL_TRUTH = {"damping.modal_1": 0.012, "damping.modal_2": 0.02}
MODAL_NOMINAL = replace(NOMINAL, damping_ratio=0.0, modal_damping=(0.01,))


def _modal_response(seed: int) -> FrequencyResponse:
    """As :func:`_response`, of the rod damped per mode."""
    f = np.geomspace(2.0, 60.0, 300)
    rng = np.random.default_rng(seed)
    G = BEAM.modal_response(f, np.array([0.012, 0.02]))
    G = G * (1 + 0.02 * (rng.standard_normal(f.size) + 1j * rng.standard_normal(f.size)) / np.sqrt(2))
    return FrequencyResponse(f, np.abs(G), np.rad2deg(np.angle(G)))


_T = np.arange(0.0, 3.0, 1e-3)
_DOUBLET = 0.2 * ((_T < 0.01) * 1.0 - ((_T >= 0.01) & (_T < 0.02)))
_CLEAN = BEAM.record(_T, _DOUBLET)


def _record(seed: int) -> TimeSeries:
    """A 1 kHz torque doublet of 10 ms pulses, 3 s, 1 % noise on the hub angle and the tip."""
    rng = np.random.default_rng(seed)
    theta, y = _CLEAN
    return TimeSeries(_T, _DOUBLET, theta + 0.01 * np.ptp(theta) * rng.standard_normal(_T.size),
                      y + 0.01 * np.ptp(y) * rng.standard_normal(_T.size))


#: Three frequencies cannot tell five parameters: the fit holds the least determined at the file's values, and its
#: answer assumes them. Here they are right: the payload is the file's (weighed), the rod and its hub are not.
KNOWN_PAYLOAD = replace(TRUTH, payload_mass=NOMINAL.payload_mass, payload_inertia=NOMINAL.payload_inertia)
#: What the user says of it (issue 62, item 3): weighed, known exactly -- else each held value is assumed within 30 % and
#: its part widens the fitted intervals.
WEIGHED = {"payload.mass": 0.0, "payload.inertia": 0.0}


def _frequencies(seed: int) -> FrequencyData:
    """The first three natural frequencies read to 0.02 Hz (stated), on a rod whose payload is the file's."""
    beam = _beam(KNOWN_PAYLOAD)
    rng = np.random.default_rng(seed)
    return FrequencyData(beam.frequencies(3) + 0.02 * rng.standard_normal(3), "hub-free", 0.02)


def _misses(result, truth) -> dict[str, float]:  # type: ignore[no-untyped-def]
    """Each fitted parameter's error over its stated 95 % half-width."""
    return {k: (v - (getattr(truth, PARAMETER_KEYS[k]) if k in PARAMETER_KEYS else MODAL_TRUTH[k])) / result.intervals[k]
            for k, v in result.values.items()}


# -- the reference itself, against the finite-element beam of modelgen.continuum --------------------------------------


def test_the_beam_agrees_with_a_fine_finite_element_model() -> None:
    """The determinant's frequencies and the boundary-value problem's response agree with 200 Hermite elements to
    1e-6; the modal record with the elements' own modes, each discretised exactly, to 1e-6 of its range."""
    frequencies, _ = fe_frequencies_zeros(TRUTH, 200)
    np.testing.assert_allclose(BEAM.frequencies(6), frequencies[:6], rtol=1e-6)
    M, K, hub, tip = fe_matrices(TRUTH, 200)
    unit = np.zeros(M.shape[0])
    unit[hub] = 1.0
    for f in (2.0, 16.0, 43.0, 100.0):
        s = 2j * np.pi * f
        x = np.linalg.solve(s * s * M + (1 + BEAM.a * s) * K, unit)
        np.testing.assert_allclose(BEAM.response([f])[0], x[hub], rtol=1e-6)
        np.testing.assert_allclose(BEAM.response([f], "y")[0], x[tip], rtol=1e-6)
    # the record: the 120-element mesh's modes, each exactly discretised (its whole state matrix is too stiff for expm)
    M, K, hub, _ = fe_matrices(TRUTH, 120)
    w2, V = sla.eigh(K, M)
    w2[0] = 0.0  # the rigid body (the solver leaves it at rounding times the largest eigenvalue: a slow drift)
    blocks = [sla.expm(np.block([[np.array([[0.0, 1.0], [-lam, -BEAM.a * lam]]), np.array([[0.0], [V[hub, i]]])],
                                 [np.zeros((1, 3))]]) * 1e-3) for i, lam in enumerate(np.clip(w2, 0.0, None))]
    Ad = np.array([E[:2, :2] for E in blocks])
    Bd = np.array([E[:2, 2] for E in blocks])
    x = np.zeros((len(blocks), 2))
    theta = np.zeros(_T.size)
    for k, u in enumerate(_DOUBLET):
        theta[k] = V[hub] @ x[:, 0]
        x = np.einsum("mij,mj->mi", Ad, x) + Bd * u
    assert np.abs(theta - _CLEAN[0]).max() < 1e-6 * np.ptp(_CLEAN[0])


# -- what the record says by itself ------------------------------------------------------------------------------------


def test_the_record_s_own_figures() -> None:
    """Noise read from the differences within 10 % of the truth on a signal that moves; the doublet's band; the AR(1)
    correlation read back; the rod's two first modes heard in its record within the record's resolution."""
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 2.0, 4001)
    smooth = np.sin(2 * np.pi * 3 * t) + 0.3 * np.sin(2 * np.pi * 11 * t)
    assert noise_level(smooth + 0.01 * rng.standard_normal(t.size)) == pytest.approx(0.01, rel=0.1)
    assert 50.0 < torque_band(_T, _DOUBLET) <= 500.0
    e = np.zeros(20000)
    for k in range(1, e.size):
        e[k] = 0.6 * e[k - 1] + rng.standard_normal()
    rho, widening = lag_one(e, [e.size])
    assert rho == pytest.approx(0.6, abs=0.03) and widening == pytest.approx(2.0, rel=0.05)
    assert lag_one(rng.standard_normal(20000), [10000, 10000])[1] == 1.0
    heard = resonances(_T, _DOUBLET, _record(1).theta)
    np.testing.assert_allclose(heard, BEAM.frequencies(2), atol=1.0)  # 1 / 3 s resolution, one bin either way


# -- the fit on it -------------------------------------------------------------------------------------------------------


def test_a_response_a_record_and_frequencies_each_hold_the_truth() -> None:
    """Issue 48's table: the same rod's response, record and frequencies with the defaults -- every reported parameter
    within its interval (the old fit missed the payload inertia by +129 %, +-14 %). One draw each, the first of the
    coverage test's (which makes the statistical claim)."""
    for data, truth in ((_response(100), TRUTH), (_record(100), TRUTH),
                        (_frequencies(100), KNOWN_PAYLOAD)):
        result = fit(NOMINAL, data)
        misses = _misses(result, truth)
        assert misses and all(abs(m) <= 1.0 for m in misses.values()), (data.kind, misses)
        assert result.modes > NOMINAL.modes  # each reaches beyond the file's two modes: the fit takes more, and says so
        assert any("not the model's 2" in note for note in result.notes)


def test_a_calibration_keeps_none_of_its_trial_links_in_the_model_cache(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    """A fit tries a link of other payload ratios at every evaluation: their frequency roots were each kept in the model
    cache, a file each (56 000 files, 224 MB after the suite); none is now, and a link loaded after it keeps its own."""
    from modelgen.modes import _roots_file, frequency_roots

    monkeypatch.setenv("SFLM_CACHE_DIR", str(tmp_path))
    result = fit(NOMINAL, _frequencies(100))
    assert result.evaluations > 20
    assert not list(tmp_path.rglob("*.json")), sorted(tmp_path.rglob("*.json"))[:3]
    frequency_roots(3, 0.3, 0.01)
    assert _roots_file(3, 0.3, 0.01)[0].is_file()


@pytest.mark.slow  # twenty fits of each kind: 155 s of CPU; the single fits below check the same paths once
@pytest.mark.parametrize("kind", ["response", "record", "frequencies", "modal"])
def test_coverage_over_twenty_noisy_data_sets(kind: str) -> None:
    """Twenty noisy sets of each kind (and of the rod damped per mode, its ratios fitted per mode): the truth within the 95 % interval at 90 % or more of the (set, parameter)
    pairs, and the intervals not too wide -- the errors over the half-widths spread as 1 / 1.96 would (a 95 % interval
    twice too wide spreads them half as much, yet covers 100 %). With twenty sets a share of 90-98 % per parameter is
    binomial luck (a true 95 % lands at 100 % one time in three), so the width is held by the spread instead."""
    make = {"response": _response, "record": _record, "frequencies": _frequencies, "modal": _modal_response}[kind]
    truth = KNOWN_PAYLOAD if kind == "frequencies" else TRUTH
    nominal = MODAL_NOMINAL if kind == "modal" else NOMINAL
    misses: dict[str, list[float]] = {}
    for seed in range(20):
        for key, miss in _misses(fit(nominal, make(100 + seed), held_spread=WEIGHED if kind == "frequencies" else None),
                                 truth).items():
            misses.setdefault(key, []).append(miss)
    pooled = np.concatenate([np.abs(m) <= 1.0 for m in misses.values()])
    assert 0.90 <= pooled.mean() <= 0.99, pooled.mean()
    for key, m in misses.items():
        assert np.mean(np.abs(m) <= 1.0) >= 0.85, (key, m)
        assert 0.3 <= np.std(m) <= 0.75, (key, np.std(m))  # 1 / 1.96 = 0.51 for a right interval


def test_a_chirp_from_a_start_20_to_25_percent_off_gives_the_truth() -> None:
    """Issue 48: a 6 s logarithmic chirp 0.2-40 Hz at 2 kHz of sflm's own three-mode model (1 % noise on the hub angle
    and the tip), fitted from a file 20 % low in EI and 25 % high in the payload mass, gives back every parameter it
    reports within its interval (the old fit: EI 109.4 +- 3.4 for 24)."""
    truth = parse_geometry({"name": "chirp-link", "link": {"length": 0.9, "flexural_rigidity": 24.0, "linear_density": 0.35},
                            "hub": {"inertia": 0.03}, "payload": {"mass": 0.3, "inertia": 3e-4}, "damping": {"ratio": 0.01},
                            "model": {"modes": 3}})
    t = np.arange(0.0, 6.0, 5e-4)
    tau = 0.5 * ss.chirp(t, 0.2, 6.0, 40.0, method="logarithmic")
    theta, y = predicted(truth, TimeSeries(t, tau, np.zeros_like(t)))
    rng = np.random.default_rng(7)
    data = TimeSeries(t, tau, theta + 0.01 * np.ptp(theta) * rng.standard_normal(t.size),
                      y + 0.01 * np.ptp(y) * rng.standard_normal(t.size))
    result = fit(replace(truth, flexural_rigidity=19.2, payload_mass=0.375), data)
    assert result.modes == 3 and {"link.flexural_rigidity", "payload.mass", "hub.inertia"} <= set(result.values)
    assert all(abs(m) <= 1.0 for m in _misses(result, truth).values()), _misses(result, truth)


@pytest.mark.slow  # one 3 s record at 0.2 % damping, 21 s of fitting from two starts; run in CI
def test_a_long_lightly_damped_record_starts_where_its_spectrum_points() -> None:
    """0.2 % damping, 48 cycles of the first mode in 3 s: from 20 % low in EI and 25 % high in the payload mass, the
    nominal start alone ends in a minimum a few cycles off (refused: 5 % residual); the start the record's resonances
    give finds the minimum at the record's own noise, EI within 0.5 %. (Over forty draws of such records the truth
    fell within the intervals at 92.5-97.5 % per parameter, spreads 0.46-0.54: measured, not asserted here.)"""
    truth = replace(TRUTH, damping_ratio=0.002)
    beam = _beam(truth)
    theta, y = beam.record(_T, _DOUBLET)
    rng = np.random.default_rng(1)
    data = TimeSeries(_T, _DOUBLET, theta + 0.01 * np.ptp(theta) * rng.standard_normal(_T.size),
                      y + 0.01 * np.ptp(y) * rng.standard_normal(_T.size))
    start = replace(NOMINAL, flexural_rigidity=truth.flexural_rigidity * 0.8, payload_mass=truth.payload_mass * 1.25,
                    damping_ratio=0.002)
    keys = ["link.flexural_rigidity", "payload.mass", "payload.inertia", "hub.inertia", "damping.ratio"]
    with pytest.raises(FitError, match="cannot reproduce the data"):
        _solve(start.with_model(6), data, keys, [np.zeros(5)])
    result = fit(start, data)
    assert result.residual <= 1.02 * result.noise  # at the record's own noise: the global minimum's basin
    assert abs(result.values["link.flexural_rigidity"] / truth.flexural_rigidity - 1) < 0.005


def test_modal_damping_the_model_cannot_take_is_refused_with_its_figures() -> None:
    """The rod with 1 % damping in each mode (the model's Rayleigh form gives the second mode 2.7 %): no calibration
    -- a refusal naming the residual -- never parameters bent to absorb the damping's form."""
    f = np.geomspace(2.0, 60.0, 300)
    rng = np.random.default_rng(3)
    G = _beam().modal_response(f, np.array([0.01])) * (1 + 0.02 * (rng.standard_normal(300) + 1j * rng.standard_normal(300)) / np.sqrt(2))
    with pytest.raises(FitError, match=r"cannot reproduce the data: .*residual 0\.0\d"):
        fit(NOMINAL, FrequencyResponse(f, np.abs(G), np.rad2deg(np.angle(G))))


def test_distinct_minima_that_fit_as_well_are_a_refusal_naming_them(monkeypatch: pytest.MonkeyPatch) -> None:
    """A residual with two equal minima (EI at 0.8 and 1.25 of its nominal value): the fit names both and calls neither
    the link."""
    import modelgen.fit as module

    noise = np.random.default_rng(5).standard_normal(200) * 1e-3

    def two_minima(geometry, data):  # type: ignore[no-untyped-def]
        x = np.log(geometry.flexural_rigidity / NOMINAL.flexural_rigidity)
        return (x * x - np.log(1.25) ** 2) * np.ones(200) + noise

    monkeypatch.setattr(module, "_residuals", two_minima)
    with pytest.raises(FitError, match=r"distinct minima fit this data equally well: link.flexural_rigidity = (15.7|24.5)\d*"):
        _solve(NOMINAL, FrequencyData(np.ones(1)), ["link.flexural_rigidity"],
               [np.zeros(1), np.array([-0.4]), np.array([0.4])])


def test_a_frequency_list_is_judged_by_its_stated_uncertainty() -> None:
    # issue 62, item 4: a list read to +-2 Hz (12 % of the first mode), stated, was refused 4 times in 20 by the unweighted
    # 5 % relative-RMS rule though it agrees with its statement; judged by it, every draw is a fit, and the truth is
    # inside its 95 % intervals in 19 of 20 for each parameter (measured)
    beam = _beam(KNOWN_PAYLOAD)
    inside: dict[str, int] = {}
    for seed in range(20):
        rng = np.random.default_rng(seed)
        result = fit(NOMINAL, FrequencyData(beam.frequencies(3) + 2.0 * rng.standard_normal(3), "hub-free", 2.0))
        for key, miss in _misses(result, KNOWN_PAYLOAD).items():
            inside[key] = inside.get(key, 0) + (abs(miss) <= 1.0)
    assert inside and all(count >= 17 for count in inside.values()), inside  # at least 85 %


@pytest.mark.slow
def test_a_single_pulse_s_record_holds_the_truth_within_its_intervals() -> None:
    """Issue 60, item 9a: a 1 kHz record of one 10 ms pulse of 0.2 N m on the rod as its file gives it (the issue's
    truth: EI 19.63, the hub 0.005), 3 s -- the link drifts away after it, a broadband kick. The noise is 3 % of the
    ringing's range (the record less its rigid drift), which gives the issue's interval widths (EI +-0.10, the hub
    +-4.3e-5). The issue measured both outside their intervals (EI 19.46 +- 0.11, the hub 0.004913 +- 5.4e-5); here, as
    for the doublets, the truth is inside at 8 of 10 draws or more for every parameter (measured: 9, 9, 9, 10 of 10 --
    the issue's record itself was not reproduced: neither a one-sample pulse, a pulse off the sample grid, a damping
    ratio per mode nor the hub angle alone moved the estimates off their intervals)."""
    beam = _beam(NOMINAL)
    pulse = 0.2 * (_T < 0.01 - 1e-9)
    theta, y = beam.record(_T, pulse)
    after = _T > 0.51

    def ringing(signal: np.ndarray) -> float:
        line = np.polyfit(_T[after], signal[after], 1)
        return float(np.ptp(signal[after] - np.polyval(line, _T[after])))

    inside: dict[str, int] = {}
    for seed in range(10):
        rng = np.random.default_rng(seed)
        data = TimeSeries(_T, pulse, theta + 0.03 * ringing(theta) * rng.standard_normal(_T.size),
                          y + 0.03 * ringing(y) * rng.standard_normal(_T.size))
        for key, miss in _misses(fit(NOMINAL, data), NOMINAL).items():
            inside[key] = inside.get(key, 0) + (abs(miss) <= 1.0)
    assert {"link.flexural_rigidity", "hub.inertia"} <= set(inside) and all(count >= 8 for count in inside.values()), inside
