"""Calibration on bench records of two links, doublets and chirps (issue 61's "done when").

``test_fit_bench_records.py`` holds the glass-fibre rod's doublet; here the same bench -- the hub angle through a
4096-count encoder, the tip with 2 % noise and a drift of 2 % of its range, both read 0.5 ms late; each artefact alone
and all together -- on the rod's logarithmic chirp and on a second link of another scale: a 2 m aluminium strip (50 x 6
mm) with a 1.08 kg payload, its first mode at 3.3 Hz, fitted from a file 20 % low in EI, 20 % high in the payload mass
and the hub inertia, 20 % low in the payload inertia and the damping. The truth is the exact continuum beam of
``beam_truth.py``, written apart from the model the fit uses. Twenty draws each: every returned parameter's 95 %
interval holds the truth in at least 85 % of them, or the fit is refused naming the artefact (none is, measured: 17 to
20 of 20 for every parameter of every case).
"""

from __future__ import annotations

from dataclasses import replace
from functools import lru_cache

import numpy as np
import pytest
import scipy.signal as ss

from modelgen.fit import TimeSeries, fit
from modelgen.geometry import PARAMETER_KEYS, Geometry, parse_geometry

from beam_truth import Beam
from test_fit_beam import NOMINAL as ROD, TRUTH as ROD_TRUTH

ALUMINIUM = parse_geometry({"name": "long-aluminium", "link": {"length": 2.0, "youngs_modulus": 69e9, "density": 2700,
                                                               "width": 0.05, "thickness": 0.006},
                            "hub": {"inertia": 0.1}, "payload": {"mass": 1.08, "inertia": 1e-3}, "damping": {"ratio": 0.01},
                            "model": {"modes": 2}})
LINKS: dict[str, tuple[Geometry, Geometry]] = {  # (the file, the link on the bench)
    "rod": (ROD, ROD_TRUTH),
    "aluminium": (replace(ALUMINIUM, flexural_rigidity=0.8 * ALUMINIUM.flexural_rigidity, payload_mass=1.2 * 1.08,
                          hub_inertia=0.12, payload_inertia=0.8e-3, damping_ratio=0.008), ALUMINIUM),
}


@lru_cache(maxsize=None)
def _clean(link: str, record: str) -> tuple[np.ndarray, np.ndarray, tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The record's time, torque, and the beam's hub angle and tip read on time and 0.5 ms late: at 1 kHz (2 kHz for a
    link below 2 Hz), at least 3 s and twelve periods of the first mode; a doublet of ten-sample pulses or a logarithmic
    chirp from a fifth of the first mode to eight times it, its torque scaled to the link's inertia."""
    truth = LINKS[link][1]
    beam = Beam(truth.length, truth.flexural_rigidity, truth.linear_density, truth.hub_inertia, truth.payload_mass,
                truth.payload_inertia).with_first_ratio(truth.damping_ratio)
    first = float(beam.frequencies(1)[0])
    h = 1e-3 if first > 2 else 2e-3
    duration = max(3.0, 12 / first)
    t = np.arange(0.0, duration, h)
    inertia = (truth.linear_density * truth.length**3 / 3 + truth.hub_inertia + truth.payload_mass * truth.length**2
               + truth.payload_inertia)
    scale = inertia / 0.0069  # the rod's doublet of 0.2 N m, scaled to the link
    if record == "doublet":
        tau = 0.2 * scale * ((t < 10 * h) * 1.0 - ((t >= 10 * h) & (t < 20 * h)))
    else:
        tau = 0.05 * scale * ss.chirp(t, 0.2 * first, duration, min(8 * first, 0.2 / h), method="logarithmic")
    on_time = beam.record(t, tau)
    fine = beam.record(np.arange(0.0, duration, h / 2), np.repeat(tau, 2))  # 0.5 ms late, exactly: every other sample
    late = (np.concatenate([[0.0], fine[0][1:-1:2]]), np.concatenate([[0.0], fine[1][1:-1:2]]))
    return t, tau, on_time, late


def _bench(link: str, record: str, artefacts: str, seed: int) -> TimeSeries:
    t, tau, on_time, late = _clean(link, record)
    rng = np.random.default_rng(seed)
    theta, y = late if artefacts in ("delay", "all") else on_time
    if artefacts in ("encoder", "all"):
        q = 2 * np.pi / 4096
        theta = np.round(theta / q) * q
    else:
        theta = theta + 0.01 * np.ptp(theta) * rng.standard_normal(t.size)
    span = np.ptp(y)
    drift = 0.02 if artefacts in ("drift", "all") else 0.0
    y = y + 0.02 * span * rng.standard_normal(t.size) + drift * span * (t - t[0]) / (t[-1] - t[0])
    return TimeSeries(t, tau, theta, y)


@pytest.mark.slow
@pytest.mark.parametrize("artefacts", ["delay", "encoder", "drift", "all"])
@pytest.mark.parametrize("link, record", [("rod", "chirp"), ("aluminium", "doublet"), ("aluminium", "chirp")])
def test_bench_records_of_two_links_hold_the_truth(link: str, record: str, artefacts: str) -> None:
    nominal, truth = LINKS[link]
    misses: dict[str, list[float]] = {}
    for seed in range(20):
        result = fit(nominal, _bench(link, record, artefacts, seed))
        for key, value in result.values.items():
            misses.setdefault(key, []).append((value - getattr(truth, PARAMETER_KEYS[key])) / result.intervals[key])
    assert len(misses["link.flexural_rigidity"]) == 20 and len(misses["payload.mass"]) == 20
    for key, m in misses.items():  # a draw where the parameter is held claims nothing of it: only a returned interval
        # that leaves the truth out is a miss (the payload inertia is held in 8-9 of the rod's chirps)
        assert np.sum(np.abs(m) > 1.0) <= 3, (link, record, artefacts, key, np.round(m, 2))


@pytest.mark.slow  # forty fits: 26 s of CPU
def test_four_frequencies_read_to_half_a_hertz_are_fitted_by_their_statement_or_refused_saying_how() -> None:
    """Issue 61, item 3: the aluminium link's first four frequencies (3.3-36.5 Hz, from the beam) read to +-0.5 Hz.
    Stated (``uncertainty_hz = 0.5``): before, refused 16 times in 20 by the 5 % rule, the others 8 % off; now twenty
    fits, the truth inside every returned interval in at least 17 (measured: EI 18, the hub inertia 19; the payload
    held, 20 % off in the file, its part in their intervals). Not stated: refused with the residual and the way out
    (10 of 20, measured), or a fit whose intervals hold the truth."""
    from modelgen.fit import FitError, FrequencyData

    nominal, truth = LINKS["aluminium"]
    exact = Beam(truth.length, truth.flexural_rigidity, truth.linear_density, truth.hub_inertia, truth.payload_mass,
                 truth.payload_inertia).frequencies(4)
    for stated in (0.5, None):
        inside: list[bool] = []
        refusals = 0
        for seed in range(20):
            data = FrequencyData(exact + 0.5 * np.random.default_rng(seed).standard_normal(4), "hub-free", stated)
            try:
                result = fit(nominal, data)
            except FitError as exc:
                # the residual beyond 5 % and the statement that judges a rough list instead; or a held parameter's
                # part beyond a fitted one's value, and how to state it
                assert stated is None and ("uncertainty_hz" in str(exc) or "--held-spread" in str(exc)), exc
                refusals += 1
                continue
            inside += [abs(v - getattr(truth, PARAMETER_KEYS[k])) <= result.intervals[k] for k, v in result.values.items()]
        assert np.mean(inside) >= 0.85, (stated, np.mean(inside))
        assert refusals == 0 if stated else refusals < 20


def test_held_modal_ratios_astronomically_wide_are_said_without_overflow() -> None:
    """Issue 62, item 1: the long link's doublet (read 0.5 ms late) fitted with modal damping in its file, a ratio per
    mode the record reaches: the highest ratios' predicted intervals are beyond a double's ``expm1`` (before: an
    ``OverflowError`` on 86 of 100 such records). Held and said in words; the others fitted."""
    nominal = replace(LINKS["aluminium"][0], damping_ratio=0.0, modal_damping=(0.008,))
    result = fit(nominal, _bench("aluminium", "doublet", "delay", 0))
    wide = [why for key, why in result.held.items() if key.startswith("damping.modal_") and "more than +-1e+06 %" in why]
    assert wide, result.held
    assert "link.flexural_rigidity" in result.values and "damping.modal_1" in result.values


def test_a_record_at_rest_before_its_torque_through_an_encoder_is_no_saturation() -> None:
    """Issue 62, item 2: a 10 ms pulse of 0.1 N m on the rod after 96 samples at rest, its hub angle never a count
    below its rest, through a 4096-count encoder (the beam's record): before, refused "theta = 'flat at its smallest
    value 0 for 107 samples' ... saturating" (measured on the commit before the fix); now fitted."""
    t, tau, _, _ = _clean("rod", "doublet")
    rest = np.where((t >= 0.096) & (t < 0.106), 0.1, 0.0)
    truth = LINKS["rod"][1]
    beam = Beam(truth.length, truth.flexural_rigidity, truth.linear_density, truth.hub_inertia, truth.payload_mass,
                truth.payload_inertia).with_first_ratio(truth.damping_ratio)
    theta, y = beam.record(t, rest)
    q = 2 * np.pi / 4096
    rng = np.random.default_rng(2)
    data = TimeSeries(t, rest, np.round(theta / q) * q, y + 0.02 * np.ptp(y) * rng.standard_normal(t.size))
    assert np.all(data.theta[:96] == 0.0)
    result = fit(LINKS["rod"][0], data)
    assert "link.flexural_rigidity" in result.values
