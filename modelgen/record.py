"""What a measurement tells of itself, before any model: its noise, its band, how its residuals are correlated.

The calibration (:mod:`modelgen.fit`) judges a fit against these figures, never against its own residual alone: a
residual far above the noise the record shows by itself is a model that cannot reproduce the data, and residuals that
follow each other (a systematic misfit) carry fewer independent points than samples.

* :func:`noise_level` -- the standard deviation of white noise on a smooth signal, from the median absolute value of
  its ``k``-th differences (a smooth signal's high differences vanish; white noise's have variance ``C(2k, k)
  sigma^2``). Robust to a few samples where the signal itself changes fast.
* :func:`response_noise` -- the same for a frequency response's relative noise: on ``log G`` along the frequencies,
  whose real and imaginary parts carry the relative error of the magnitude and the phase.
* :func:`torque_band` -- the frequency below which a torque record holds all but :data:`BAND_SHARE` of its energy.
* :func:`resonances` -- the frequencies where a record's response to its torque peaks: the modes it shows, read
  before any model (where the optimiser starts on a long record, whose residual has a minimum at every frequency a
  whole number of cycles off).
* :func:`lag_one` -- the lag-one autocorrelation of residuals, segment by segment, and the variance inflation of an
  AR(1) sequence it implies.
* :func:`input_correlation` -- the residuals' correlation with the input at positive and negative lags, against its
  standard deviation were the model right: what the model misses of what the input does (a test of every system
  identification toolbox's, Ljung's "System Identification", section 16.6).
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from numpy.typing import NDArray

__all__ = ["noise_level", "resolution", "correlation_time", "response_noise", "torque_band", "lag_one", "resonances", "BAND_SHARE", "DIFFERENCE_ORDER",
           "input_correlation",
           "PROMINENCE", "DRIVEN", "ABOVE_NOISE"]

FloatArray = NDArray[np.float64]
#: The order of the differences the noise is read from (a smooth signal's fourth differences are far below noise).
DIFFERENCE_ORDER = 4
#: The share of a torque's energy left above its band.
BAND_SHARE = 1e-3
#: A resonance stands out of the record's spectrum (median-filtered over five bins) by at least this in natural log
#: magnitude: 4.5 x its surroundings (a lightly damped mode's peak is 1 / (2 zeta); noise's log magnitude varies by ~0.6).
PROMINENCE = 1.5
#: The spectrum is read where the torque's magnitude is at least this share of its largest (near a notch of the torque
#: the ratio is noise over nothing).
DRIVEN = 0.1
#: A resonance's response stands this many times above the record's noise.
ABOVE_NOISE = 10.0
#: Median absolute deviation of a standard normal variable.
_MAD = 0.6744897501960817


def noise_level(values: FloatArray, order: int = DIFFERENCE_ORDER) -> float:
    """The standard deviation of white noise on a smooth signal.

    Parameters
    ----------
    values : FloatArray
        The samples, evenly spaced, many to a period of the fastest motion they hold.
    order : int, optional
        Order of the differences (default :data:`DIFFERENCE_ORDER`).

    Returns
    -------
    float
        ``median |diff^k v| / 0.6745 / sqrt(C(2k, k))``; ``nan`` for fewer than ``4 k`` samples.
    """
    values = np.asarray(values, dtype=float)
    if values.size < 4 * order:
        return math.nan
    d = np.diff(values, n=order)
    return float(np.median(np.abs(d)) / _MAD / math.sqrt(math.comb(2 * order, order)))


def resolution(values: FloatArray) -> float:
    """An encoder's resolution, read from its record.

    The step of the lattice the samples sit on, 0 for a signal that is not quantised. A quantised signal holds its levels for runs of samples and moves between them by whole counts. Its step is the
    smallest change between samples; the record is taken as quantised when every sample sits on the lattice of that
    step (within 1 % of it) and at least a fifth of the changes are zero (a smooth signal with noise has none).

    Parameters
    ----------
    values : FloatArray
        The samples.

    Returns
    -------
    float
        The step (the signal's unit), or 0 for a signal that is not quantised.
    """
    values = np.asarray(values, dtype=float)
    d = np.abs(np.diff(values))
    moving = d[d > 0]
    if values.size < 16 or moving.size < 4 or np.mean(d == 0) < 0.2:
        return 0.0
    step = float(moving.min())
    counts = (values - values[0]) / step
    return step if float(np.max(np.abs(counts - np.round(counts)))) <= 0.01 else 0.0


def response_noise(response: NDArray[np.complex128], order: int = DIFFERENCE_ORDER) -> float:
    """The relative noise of a measured frequency response.

    Parameters
    ----------
    response : ndarray of complex
        The measured response, on a grid of ascending frequencies dense enough that it is smooth from point to point.
    order : int, optional
        Order of the differences.

    Returns
    -------
    float
        The standard deviation of each of the real and imaginary parts of ``log G`` (the log-magnitude and phase
        residuals :mod:`modelgen.fit` forms), read from their differences; ``nan`` for too few points.
    """
    logs = np.log(np.asarray(response, dtype=complex))
    logs = np.real(logs) + 1j * np.unwrap(np.imag(logs))
    parts = [noise_level(np.real(logs), order), noise_level(np.imag(logs), order)]
    return float(np.sqrt(np.mean(np.square(parts))))


def torque_band(t: FloatArray, tau: FloatArray, share: float = BAND_SHARE) -> float:
    """The band of a torque: all but ``share`` of its energy below.

    Parameters
    ----------
    t : FloatArray
        Sample times (s), evenly spaced.
    tau : FloatArray
        The torque.
    share : float, optional
        The share of the energy left above (default :data:`BAND_SHARE`).
    """
    tau = np.asarray(tau, dtype=float)
    power = np.abs(np.fft.rfft(tau - tau[-1])) ** 2  # a torque held at its last value has no energy after the record
    f = np.fft.rfftfreq(tau.size, float(t[1] - t[0]))
    total = float(power.sum())
    if not total > 0:
        return float(f[-1])
    cumulative = np.cumsum(power) / total
    return float(f[min(int(np.searchsorted(cumulative, 1.0 - share)), f.size - 1)])


def lag_one(residuals: FloatArray, segments: Sequence[int]) -> tuple[float, float]:
    """Residuals' lag-one correlation and the widening it implies.

    Parameters
    ----------
    residuals : FloatArray
        The residuals, segment after segment (each an ordered sequence: a record's samples, a response's points).
    segments : sequence of int
        The lengths of the segments (summing to ``residuals.size``); no lag crosses a segment's end.

    Returns
    -------
    rho : float
        The pooled lag-one autocorrelation.
    widening : float
        ``sqrt((1 + rho) / (1 - rho))`` where ``rho`` is positive beyond its noise (``2 / sqrt(m)``), else 1: the
        standard deviation of a smooth estimate from an AR(1) sequence against independent points (the effective
        number of independent points is ``m (1 - rho) / (1 + rho)``).
    """
    r = np.asarray(residuals, dtype=float)
    products, squares, start = 0.0, 0.0, 0
    for length in segments:
        part = r[start:start + length]
        part = part - part.mean() if part.size else part
        products += float(part[1:] @ part[:-1]) if part.size > 1 else 0.0
        squares += float(part @ part)
        start += length
    rho = products / squares if squares > 0 else 0.0
    rho = min(rho, 0.99)
    widening = math.sqrt((1 + rho) / (1 - rho)) if rho > 2.0 / math.sqrt(max(r.size, 1)) else 1.0
    return rho, widening


def correlation_time(residuals: FloatArray) -> float:
    """How many samples of a sequence count as one independent one.

    ``1 + 2 sum_k rho_k`` over the lags while the sum of consecutive pairs ``rho_k + rho_(k+1)`` stays positive (Geyer's
    initial positive sequence), at least 1. For AR(1) noise it is ``(1 + rho) / (1 - rho)``, the square of
    :func:`lag_one`'s widening; for a rounding error held over runs of samples (an encoder on a slow motion) it sees the
    correlation beyond lag one that an AR(1) model misses.

    Parameters
    ----------
    residuals : FloatArray
        An ordered sequence (a record's samples).
    """
    r = np.asarray(residuals, dtype=float)
    r = r - r.mean()
    n = r.size
    if n < 8 or not np.any(r):
        return 1.0
    spectrum = np.fft.rfft(r, 2 * n)
    rho = np.fft.irfft(spectrum * np.conj(spectrum))[:n]
    rho = rho / rho[0]
    total = 1.0
    for k in range(1, n - 1, 2):
        pair = rho[k] + rho[k + 1]
        if pair <= 0:
            break
        total += 2 * pair
    return max(total, 1.0)


def input_correlation(residuals: FloatArray, inputs: FloatArray, lags: int) -> tuple[NDArray[np.int64], FloatArray, float]:
    """The residuals' correlation with the input, lag by lag.

    At lags ``-lags..lags``, with its standard deviation were the two independent: ``rho(k) = sum_t r(t) u(t - k) /
    sqrt(sum r^2 sum u^2)`` (both less their means). At a positive lag, the residual follows the input ``k`` samples
    later -- dynamics the model lacks; at a negative one it leads it -- the input recorded late, or feedback. Were the
    residual independent of the input, ``rho(k)`` would be zero with the variance
    ``(1 / N) sum_j rho_r(j) rho_u(j)`` (Bartlett's formula for two independent series, each autocorrelated: a chirp's or
    a doublet's autocorrelation is long, and ``1 / N`` alone would call chance a misfit), summed over ``|j| < N / 4``
    and never below ``1 / N``.

    Parameters
    ----------
    residuals, inputs : FloatArray
        Sequences of the same length ``N`` (a record's residual of one channel, its torque).
    lags : int
        The largest lag, in samples.

    Returns
    -------
    lags : NDArray[np.int64]
        ``-lags..lags``.
    rho : FloatArray
        The correlation at each lag.
    sd : float
        Its standard deviation were the residual independent of the input.
    """
    r = np.asarray(residuals, dtype=float) - float(np.mean(residuals))
    u = np.asarray(inputs, dtype=float) - float(np.mean(inputs))
    n = r.size
    shifts = np.arange(-lags, lags + 1)
    norm = math.sqrt(float(r @ r) * float(u @ u))
    if n < 8 or norm == 0.0:
        return shifts, np.zeros(shifts.size), 1.0 / math.sqrt(max(n, 1))
    size = 1 << (2 * n).bit_length()
    R, U = np.fft.rfft(r, size), np.fft.rfft(u, size)
    rho = np.fft.irfft(R * np.conj(U), size)[shifts % size] / norm
    auto_r = np.fft.irfft(np.abs(R) ** 2, size)[: n // 4] / float(r @ r)
    auto_u = np.fft.irfft(np.abs(U) ** 2, size)[: n // 4] / float(u @ u)
    variance = (1.0 + 2.0 * float(auto_r[1:] @ auto_u[1:])) / n
    return shifts, rho, math.sqrt(max(variance, 1.0 / n))


def resonances(t: FloatArray, tau: FloatArray, values: FloatArray) -> FloatArray:
    """Where a record's response to its torque peaks (Hz).

    Parameters
    ----------
    t : FloatArray
        Sample times (s), evenly spaced, from rest.
    tau : FloatArray
        The torque, held between the samples.
    values : FloatArray
        The response (a hub angle).

    Returns
    -------
    FloatArray
        The peaks of ``|DFT(diff values)| / |DFT(tau)|`` (the response's rate over its torque: the rigid body's drift
        removed) between two cycles of the record and the torque's band (:func:`torque_band`), where the torque has
        energy (:data:`DRIVEN`), standing out by :data:`PROMINENCE` in log magnitude and :data:`ABOVE_NOISE` times above the
        noise (:func:`noise_level`); empty where none does.
    """
    import scipy.signal as ss

    step = float(t[1] - t[0])
    rate = np.fft.rfft(np.diff(np.asarray(values, dtype=float)))
    drive = np.fft.rfft(np.asarray(tau, dtype=float)[:-1])
    f = np.fft.rfftfreq(len(tau) - 1, step)
    strong = np.abs(drive) > DRIVEN * float(np.abs(drive).max(initial=0.0))  # not near a notch of the torque
    inside = (f > 2.0 / float(t[-1] - t[0])) & (f <= torque_band(t, tau)) & strong
    if np.count_nonzero(inside) < 8:
        return np.zeros(0)
    gain = np.log(np.abs(rate[inside]) / np.abs(drive[inside]) + 1e-300)
    gain = ss.medfilt(gain, 5)  # a few noisy bins are no resonance
    peaks, _ = ss.find_peaks(gain, prominence=PROMINENCE)
    # above the noise: white noise of deviation sigma, differenced, has the spectrum 2 |sin(pi f h)| sigma sqrt(N)
    floor = 2 * np.abs(np.sin(np.pi * f[inside][peaks] * step)) * noise_level(values) * math.sqrt(len(tau) - 1)
    heard = np.abs(ss.medfilt(np.abs(rate[inside]), 5)[peaks]) > ABOVE_NOISE * floor
    return np.sort(f[inside][peaks[heard]])
