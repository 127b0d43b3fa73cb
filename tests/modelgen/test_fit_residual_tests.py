"""Residual tests that catch what the model of a record does not hold (issue 61, item 2).

After the fit, each channel's residual (the bench's delay, offset and drift taken out) is tested for correlation with
the torque at lags either way (``modelgen.record.input_correlation``, Bartlett's variance for two autocorrelated
series). A record of a link with dry friction fitted by a model without it was a calibration before (residual 1.7 x
the record's noise, under the 2 x rule); its residual follows the torque 39-49 ms later at 4.2-4.6 standard deviations,
and the fit is now refused naming it. The beam's records, clean and as a bench makes them (80 channel records in the
coverage tests of ``test_fit_beam.py`` and ``test_fit_bench_records.py``), stay at most 3.0.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.signal as ss

from modelgen.fit import INPUT_CORRELATION, FitError, TimeSeries, fit, predicted
from modelgen.record import input_correlation

from test_fit_beam import NOMINAL, TRUTH, _DOUBLET, _T, _record


def test_an_independent_residual_stays_within_chance_even_beside_a_long_correlated_input() -> None:
    """A chirp (its autocorrelation long) and an AR(1) residual (rho 0.9) drawn apart: over 40 draws the largest of the
    101 lags stays below the limit, where the white-noise bound ``1 / sqrt(N)`` calls most of them a misfit."""
    t = np.arange(0.0, 3.0, 1e-3)
    u = ss.chirp(t, 0.5, 3.0, 40.0)
    largest, naive = [], []
    for seed in range(40):
        e = np.random.default_rng(seed).standard_normal(t.size)
        r = ss.lfilter([1.0], [1.0, -0.9], e)
        lags, rho, sd = input_correlation(r, u, 50)
        assert lags[0] == -50 and lags[-1] == 50 and rho.size == 101
        largest.append(np.abs(rho).max() / sd)
        naive.append(np.abs(rho).max() * np.sqrt(t.size))
    assert max(largest) < INPUT_CORRELATION, np.round(sorted(largest), 2)
    assert np.mean(np.array(naive) > INPUT_CORRELATION) > 0.5, np.round(sorted(naive), 2)


def test_a_residual_that_follows_the_input_is_found_at_its_lag() -> None:
    rng = np.random.default_rng(3)
    u = rng.standard_normal(3000)
    r = 0.2 * np.roll(u, 7) + rng.standard_normal(3000)  # the residual follows the input 7 samples later
    lags, rho, sd = input_correlation(r, u, 20)
    k = int(np.argmax(np.abs(rho)))
    assert lags[k] == 7 and rho[k] / sd > 8
    assert sd == pytest.approx(1 / np.sqrt(3000), rel=0.1)  # white input: Bartlett's variance is 1 / N
    lags, rho, sd = input_correlation(np.roll(r, -14), u, 20)  # now it leads
    assert lags[int(np.argmax(np.abs(rho)))] == -7


# (the first draw in the quick suite, the other two slow: 8 s each, run in CI)
@pytest.mark.parametrize("seed", [0, pytest.param(1, marks=pytest.mark.slow), pytest.param(2, marks=pytest.mark.slow)])
def test_the_hub_s_dry_friction_left_out_of_the_model_is_a_refusal_naming_it(seed: int) -> None:
    """The rod's doublet with 2 mN m of dry friction at the hub (the fit's plant: it sticks and slips), 1 % noise,
    fitted by the file's model without friction: three draws, each refused with the lag and what it points to."""
    stuck = replace(TRUTH, hub_coulomb_friction=0.002)
    theta, y = predicted(stuck.with_model(6), TimeSeries(_T, _DOUBLET, np.zeros_like(_T)))
    rng = np.random.default_rng(seed)
    data = TimeSeries(_T, _DOUBLET, theta + 0.01 * np.ptp(theta) * rng.standard_normal(_T.size),
                      y + 0.01 * np.ptp(y) * rng.standard_normal(_T.size))
    with pytest.raises(FitError, match=r"correlated with the torque \d+ ms later: .*hub.coulomb_friction.*x its standard "
                                       r"deviation were the model right \(at most 4 is chance\)"):
        fit(NOMINAL, data)


def test_a_right_model_reports_its_tests() -> None:
    result = fit(NOMINAL, _record(100))
    tests = result.summary()["residual_tests"]
    assert set(tests) == {"theta", "y"}
    for test in tests.values():
        assert 0 < test["z"] <= test["limit"] == INPUT_CORRELATION
        assert abs(test["at_lag_s"]) <= 0.05 and abs(test["lag_one"]) < 0.2
