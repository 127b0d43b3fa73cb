"""Calibration on a record as a bench makes it (issue 61): the hub angle through a 4096-count encoder, the tip sensor
with 2 % noise and a drift of 2 % of its range over the record, both read 0.5 ms late.

The truth is the exact continuum beam of ``beam_truth.py`` (written apart from the assumed-mode model the fit uses), the
glass-fibre rod of ``test_fit_beam.py`` driven by its doublet. Before, these records gave confident wrong answers: the
delay moved the payload inertia 1.9 half-widths on average (0 of 6 inside), the drift the payload mass 14 (0 of 6). Now
each channel's delay, offset and drift are fitted beside the link (``modelgen.fit._channel``), an encoder's
quantisation enters its channel's noise, and each channel's residuals are weighed by their own variance and
correlation.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from modelgen.errors import SettingsError
from modelgen.fit import TimeSeries, fit, read_data
from modelgen.record import correlation_time, lag_one, resolution

from test_fit_beam import BEAM, NOMINAL, TRUTH, _DOUBLET, _T, _misses

#: The bench: the delay (s), the encoder's counts a turn, the tip sensor's noise and drift (shares of its range)
DELAY, COUNTS, TIP_NOISE, DRIFT = 5e-4, 4096, 0.02, 0.02
_CLEAN = BEAM.record(_T, _DOUBLET)
#: The same record 0.5 ms late, exactly: the beam at twice the rate (the torque held alike), every other sample from the
#: second (a linear interpolation between the 1 kHz samples would add an error of its own)
_FINE = BEAM.record(np.arange(0.0, 3.0, 5e-4), np.repeat(_DOUBLET, 2))
_LATE = tuple(np.concatenate([[0.0], s[1:-1:2]]) for s in _FINE)


def _bench(seed: int, delay: float = DELAY, encoder: bool = True, drift: float = DRIFT) -> TimeSeries:
    """The beam's doublet record as the bench gives it (each artefact can be left out)."""
    rng = np.random.default_rng(seed)
    assert delay in (0.0, DELAY)
    theta, y = _LATE if delay else _CLEAN  # read late: the value DELAY s before
    if encoder:
        q = 2 * np.pi / COUNTS
        theta = np.round(theta / q) * q
    else:
        theta = theta + 0.01 * np.ptp(theta) * rng.standard_normal(_T.size)
    span = np.ptp(y)
    y = y + TIP_NOISE * span * rng.standard_normal(_T.size) + drift * span * (_T - _T[0]) / (_T[-1] - _T[0])
    return TimeSeries(_T, _DOUBLET, theta, y)


#: Draws of each record. Twenty is the issue's measure, but a right 95 % interval falls short of 17 of 20 now and then:
#: the payload mass's, measured at 95.5 % (below), holds the truth in at least 17 of 20 in 98 % of sets of twenty, and
#: seeds 300-319 are among the other 2 % (16 of 20 with the encoder, then 18, 18 and 18: 70 of 80). Eighty draws at the
#: same 85 % (68 of 80) is the stronger test: a right interval fails it about once in a thousand.
DRAWS = 80


@pytest.mark.slow  # eighty fits of each record: about 8 min of CPU each; the tests below fit one record of each
@pytest.mark.parametrize("artefacts", ["delay", "encoder", "drift", "all"])
def test_bench_records_hold_the_truth_within_their_intervals(artefacts: str) -> None:
    """Eighty draws of each: the truth inside every returned parameter's 95 % interval in at least 85 % of the draws
    that return it (before: 0 % for the payload inertia with the delay, the payload mass with the drift; every record
    refused with the encoder); each parameter returned in at least 90 % of them (the payload inertia, at the edge of
    what a doublet tells, is held in 3 of 80 with the delay or the drift: its part then widens the others' intervals);
    the errors not all on one side."""
    make = {"delay": dict(encoder=False, drift=0.0), "encoder": dict(delay=0.0, drift=0.0),
            "drift": dict(delay=0.0, encoder=False), "all": {}}[artefacts]
    misses: dict[str, list[float]] = {}
    for seed in range(DRAWS):
        for key, miss in _misses(fit(NOMINAL, _bench(300 + seed, **make)), TRUTH).items():  # type: ignore[arg-type]
            misses.setdefault(key, []).append(miss)
    for key, m in misses.items():
        assert len(m) >= 0.9 * DRAWS, (artefacts, key, f"returned in {len(m)} of {DRAWS}")
        assert np.mean(np.abs(m) <= 1.0) >= 0.85, (artefacts, key, np.round(m, 2))
        assert abs(np.mean(m)) < 0.6, (artefacts, key, np.mean(m))  # no bias of more than ~half a half-width


@pytest.mark.slow  # one fit and a thousand residuals: 12 s
def test_the_encoder_record_s_intervals_are_its_estimates_spread(monkeypatch: pytest.MonkeyPatch) -> None:
    """The noise part of each interval is the estimate's own spread over the tip sensor's noise (the encoder's rounding
    is the same in every draw): the fit linearised at its solution, ``dx = -(J^T J)^-1 J^T dr`` for the residual ``dr``
    each draw's noise adds at the truth, over 1 000 draws, has each parameter's standard deviation within 10 % of the
    one the fit states (the standard error of a deviation from 1 000 draws is 2.2 %). Measured: 1.027, 0.987, 1.022 and
    0.982 for EI, the payload mass, the hub inertia and the damping ratio (over seeds 300-1299: 1.015, 1.025, 1.015 and
    1.007; over seeds 300-379 alone, the eighty draws above, the payload mass's 1.15). The linearisation is checked on
    the worst of those draws (seed 301, the payload mass 2.66 of its deviations off): it predicts the full fit's error
    to 0.019 of a deviation (0.05 asserted)."""
    import modelgen.fit as F

    solved: dict[str, object] = {}
    solve = F._solve

    def kept(geometry, data, keys, starts):  # type: ignore[no-untyped-def]
        solution = solve(geometry, data, keys, starts)
        solved.setdefault("first", (geometry, keys, solution))  # the reported intervals are the first model's
        return solution

    monkeypatch.setattr(F, "_solve", kept)
    record = _bench(301, delay=0.0, drift=0.0)
    fit(NOMINAL, record)
    geometry, keys, solution = solved["first"]  # type: ignore[misc]
    truth = np.log([F.parameter_value(TRUTH, k) / F.parameter_value(geometry, k) for k in keys])
    at_truth = F._with(geometry, keys, np.exp(truth))
    J = F._jacobian(geometry, record, keys, solution.x)
    deviation = np.sqrt(np.diag(solution.cov))
    q = 2 * np.pi / COUNTS
    rounded = TimeSeries(_T, _DOUBLET, np.round(_CLEAN[0] / q) * q, _CLEAN[1])  # the record without the tip's noise
    fixed = F._residuals(at_truth, rounded)

    def linearised(data: TimeSeries, noise_only: bool = True) -> np.ndarray:
        r = F._residuals(at_truth, data) - (fixed if noise_only else 0.0)
        return -np.linalg.solve(J.T @ J, J.T @ r) / deviation

    own = (solution.x - truth) / deviation
    assert np.abs(linearised(record, noise_only=False) - own).max() < 0.05, (own, linearised(record, noise_only=False))
    spread = np.std([linearised(_bench(seed, delay=0.0, drift=0.0)) for seed in range(1000, 2000)], axis=0)
    assert np.all(np.abs(spread - 1.0) < 0.1), dict(zip(keys, np.round(spread, 3)))


def test_a_spectrum_start_that_does_not_settle_is_no_start(monkeypatch: pytest.MonkeyPatch) -> None:
    """A bench doublet's three peaks (draw 301, every artefact) do not tell three parameters: their fit ran to the old
    limit of 600 evaluations, to EI x 0.06 and the payload x 0.001 (5 of the fit's 12 s), and that start probed far worse
    than the nominal one. Now it gives up after 20 evaluations a parameter, and no start is made of it; the fit is the
    one the draw had before (its misses, measured: 0.916, -1.367, 1.09, 0.819 half-widths)."""
    import modelgen.fit as F

    spent: list[int] = []
    made: list[object] = []
    residuals, start = F._residuals, F._spectrum_start

    def counted(geometry, data):  # type: ignore[no-untyped-def]
        spent.append(1)
        return residuals(geometry, data)

    def spectrum(geometry, data, keys):  # type: ignore[no-untyped-def]
        monkeypatch.setattr(F, "_residuals", counted)
        try:
            made.append(start(geometry, data, keys))
        finally:
            monkeypatch.setattr(F, "_residuals", residuals)
        return made[-1]

    monkeypatch.setattr(F, "_spectrum_start", spectrum)
    result = fit(NOMINAL, _bench(301))
    assert len(made) == 1 and made[0] is None, made
    assert len(spent) <= (F.SPECTRUM_EVALUATIONS * 3 + 1) * 4  # each evaluation and its Jacobian's three differences
    misses = _misses(result, TRUTH)
    assert np.allclose([misses[k] for k in ("link.flexural_rigidity", "payload.mass", "hub.inertia", "damping.ratio")],
                       [0.916, -1.367, 1.09, 0.819], atol=5e-3), misses


def test_the_delay_and_the_drift_are_reported_with_their_intervals() -> None:
    result = fit(NOMINAL, _bench(7))
    theta, y = result.artefacts["theta"], result.artefacts["y"]
    for channel in (theta, y):
        assert abs(channel["delay"] - DELAY) <= max(channel["delay_95"], 1e-4), channel
    slope = DRIFT * np.ptp(_CLEAN[1]) / (_T[-1] - _T[0])  # m/s
    assert abs(y["drift"] - slope) <= y["drift_95"] and y["drift_95"] < 0.5 * slope, (y, slope)
    assert abs(theta["drift"]) <= 3 * theta["drift_95"]  # the encoder does not drift
    assert result.summary()["artefacts"] == result.artefacts
    assert any("read 0.5" in n and "ms late" in n for n in result.notes), result.notes
    # a clean record: no delay, no drift found
    clean = fit(NOMINAL, _bench(8, delay=0.0, encoder=False, drift=0.0))
    for channel in clean.artefacts.values():
        assert abs(channel["delay"]) <= channel["delay_95"] + 1e-5 and abs(channel["drift"]) <= 3 * channel["drift_95"]


def test_an_encoder_s_resolution_is_read_from_its_levels() -> None:
    q = 2 * np.pi / COUNTS
    theta = np.round(_CLEAN[0] / q) * q
    assert resolution(theta) == pytest.approx(q, rel=1e-9)
    assert resolution(_CLEAN[0]) == 0.0  # smooth: no plateaus
    rng = np.random.default_rng(1)
    assert resolution(_CLEAN[1] + 1e-3 * rng.standard_normal(_T.size)) == 0.0  # noisy: every sample moves


def test_the_correlation_time_of_ar1_noise_and_of_white_noise() -> None:
    # AR(1) with rho = 0.6: (1 + rho) / (1 - rho) = 4, lag_one's widening squared; white noise: 1
    rng = np.random.default_rng(0)
    e = rng.standard_normal(100_000)
    x = np.zeros_like(e)
    for k in range(1, e.size):
        x[k] = 0.6 * x[k - 1] + e[k]
    assert correlation_time(x) == pytest.approx(4.0, rel=0.05)
    assert correlation_time(x) == pytest.approx(lag_one(x, [x.size])[1] ** 2, rel=0.05)
    assert correlation_time(e) == pytest.approx(1.0, abs=0.05)


def _written(path: Path, record: TimeSeries, comments: str) -> Path:
    rows = np.column_stack([record.t, record.tau, record.theta, record.y])
    path.write_text(comments + "t,tau,theta,y\n" + "\n".join(",".join(repr(float(v)) for v in row) for row in rows) + "\n")
    return path


def test_a_delay_the_data_file_states_is_used_and_reported(tmp_path: Path) -> None:
    record = _bench(9, encoder=False, drift=0.0)
    data = read_data(_written(tmp_path / "bench.csv", record, "# from the bench, Friday\n# delay = 0.0005\n"))
    assert isinstance(data, TimeSeries) and data.delays == {"theta": DELAY, "y": DELAY}
    result = fit(NOMINAL, data)
    for channel in result.artefacts.values():
        assert channel["delay_given"] and channel["delay"] == DELAY and channel["delay_95"] == 0.0
    assert any("0.5 ms late (as the data file states)" in n for n in result.notes), result.notes
    for key, miss in _misses(result, TRUTH).items():
        assert abs(miss) <= 1.0, (key, miss)
    # one channel stated, the other fitted
    one = read_data(_written(tmp_path / "one.csv", record, "# delay_y = 0.0005\n"))
    assert isinstance(one, TimeSeries) and one.delays == {"y": DELAY}


@pytest.mark.parametrize("line, words", [("# delay_theta = -1e-3", "delay_theta"), ("# delay = soon", "delay"),
                                         ("# delay_y = 1", r"at most 20 samples \(0.02 s\)")])
def test_a_stated_delay_out_of_range_is_refused_by_name(line: str, words: str, tmp_path: Path) -> None:
    with pytest.raises(SettingsError, match=words):
        read_data(_written(tmp_path / "bad.csv", _bench(1), line + "\n"))


def test_the_calibration_guide_s_record_is_the_first_draw() -> None:
    """``tests/data/bench-doublet.csv`` (the guide's ``sflm fit ... --plot``) is ``_bench(300)`` to its ten digits."""
    data = read_data(Path(__file__).resolve().parents[1] / "data" / "bench-doublet.csv")
    draw = _bench(300)
    assert isinstance(data, TimeSeries) and data.y is not None and draw.y is not None and data.delays == {}
    for ours, theirs in ((data.t, draw.t), (data.tau, draw.tau), (data.theta, draw.theta), (data.y, draw.y)):
        np.testing.assert_allclose(ours, theirs, rtol=1e-9, atol=1e-15)
