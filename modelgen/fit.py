"""Calibration of a link's model to what was measured on the bench: ``sflm fit``.

A geometry file holds nominal numbers; the link on the bench differs. :func:`fit` adjusts chosen parameters of the
geometry (the dotted names of :data:`modelgen.geometry.PARAMETER_KEYS`, as ``--uncertainty`` takes them) so that the
linear assumed-mode model (:func:`modelgen.linear.linear_model`: no compilation, milliseconds an evaluation) reproduces
one of three kinds of data (:func:`read_data` tells them by the file's keys or header):

* **natural frequencies** -- a TOML file ``frequencies_hz = [f1, f2, ...]`` and ``boundary = "hub-free"`` (the hub free
  to rotate: the frequencies ``sflm info`` reports) or ``"hub-clamped"`` (the hub held: the link alone, its rotation
  removed); residuals ``(f_model - f) / f``;
* **a frequency response** -- a CSV with the header ``f,magnitude,phase`` (Hz, absolute, degrees) from the hub torque
  to ``output`` (``theta``, the hub angle, or ``y``, the tip; a column or :func:`read_data`'s argument); residuals the
  logarithm of the model's response over the measured one (its magnitude's and phase's relative errors), the
  measurement's delay fitted beside the link (:func:`_response_delay`) unless a comment line before the header states
  it (``# delay = S``);
* **a time series** -- a CSV ``t,tau,theta`` and optionally ``y``, an open-loop experiment from rest, the torque held
  between the samples (and the hub's dry friction, ``hub.coulomb_friction``, held over each sample, sticking below
  it: a step-torque record gives it, as the paper measured it); or ``t,tau_ff,theta_d,theta[,y]`` in closed loop under
  a joint PD whose gains are given; residuals the angles' difference over their range. Each channel is modelled as a
  bench reads it, late, from its own zero and drifting: its delay, offset and drift are fitted beside the link
  (:func:`_channel`) and reported with their intervals, unless the file states a channel's delay in a comment line
  before its header (``# delay_theta = 0.0005``, ``# delay_y = ...`` or ``# delay = ...`` for both, in seconds), which is
  then used as given.

A frequency list may state its reading's standard deviation (``uncertainty_hz``): the intervals then come from it, not
from the residuals, and as many parameters as frequencies can be fitted.

Each parameter is fitted as a factor on its nominal value (``x = log(value / nominal)``, so it stays positive) by
:func:`scipy.optimize.least_squares`, on a model with one mode more than the nominal modes inside the data's band (never
fewer than the geometry's), from several starts (:func:`_starts`; a record also where its own spectrum points,
:func:`modelgen.record.resonances`): distinct minima that fit the data as well are a refusal naming them. Its 95 %
interval has three parts: the noise's, from the Jacobian at the solution (``cov = s^2 (J^T J)^-1``, ``s^2 = r^T r / (m -
p)``, widened by ``sqrt((1 + rho) / (1 - rho))`` where the residuals' lag-one correlation ``rho`` shows they follow each
other), the model's, the change of the estimate as modes are added until it stops moving (:data:`CONVERGED`), and
the held parameters', what their plausible errors (:data:`HELD_SPREAD`, or the ``held_spread`` the user states) move
each estimate by (:func:`_held_part`); their root sum of squares is the interval. Before fitting, the Jacobian at the
nominal values and the data's own noise
(:mod:`modelgen.record`) predict each interval: parameters the noise hides, or more than the data's points allow, are
held at their nominal values and named (where the noise cannot be read, two columns correlated beyond
:data:`INSEPARABLE`), unless the user listed them, in which case the fit is refused with the reason.

The fit is a failure, not a model, when the optimiser does not converge, when the residual is far above what the data
allows (a relative RMS above :data:`MAX_RELATIVE_RESIDUAL`, or above :data:`MAX_NOISE_RATIO` times the data's own
noise; data that states its uncertainty -- a frequency list's ``uncertainty_hz`` -- more than :data:`MAX_STATED_RATIO` times
it instead), or when an interval is wider than its value or a parameter runs to its physical bound -- for a parameter the
user listed. One of the default set that this data does not determine is held at its nominal value and named instead,
and the others are fitted again.
"""

from __future__ import annotations

import csv
import hashlib
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from numpy.typing import NDArray

from .errors import GeometryError, SettingsError, SflmError
from .files import DocumentError, read_document
from .geometry import MAX_MODES, PARAMETER_KEYS, Geometry, is_parameter_key, modal_mode, parameter_value, relative_values, scaled
from .quoting import one_line, toml_string

__all__ = ["FrequencyData", "FrequencyResponse", "TimeSeries", "Fit", "FitError", "read_data", "fit", "fit_file", "calibrated_toml",
           "spread_of_calibration", "predicted",
           "DEFAULT_PARAMETERS", "INSEPARABLE", "MAX_RELATIVE_RESIDUAL", "MAX_STATED_RATIO", "MAX_DAMPING_RATIO", "FLIPPED_CORRELATION", "AT_BOUND",
           "SATURATION_BAND", "SATURATION_SAMPLES", "SATURATION_SHARE", "STARTS", "SPREAD", "MORE_MODES", "CONVERGED",
           "MAX_NOISE_RATIO", "NOISE_FLOOR", "SENSITIVITY", "interval_text", "WIDEST_QUOTED", "HELD_SPREAD", "MAX_HELD_SPREAD",
           "held_spreads", "INPUT_LAGS", "INPUT_CORRELATION", "input_correlations"]

FloatArray = NDArray[np.float64]
#: Fitted unless the user says otherwise (those the geometry has at zero, or the data cannot see, are left out and named);
#: with modal damping, ``damping.modal_K`` for each mode ``K`` the data reaches in place of ``damping.ratio``.
DEFAULT_PARAMETERS = ("link.flexural_rigidity", "payload.mass", "payload.inertia", "hub.inertia", "damping.ratio")
#: Two parameters whose sensitivities are correlated beyond this cannot be told apart by data whose noise is unknown.
INSEPARABLE = 0.999
#: A parameter whose predicted 95 % half-width (in ``log(value / nominal)``) at the nominal values is above this is held:
#: the data's noise hides it.
SENSITIVITY = 0.7
#: A flat run at an extreme of an angle, within this share of its range, of at least SATURATION_SAMPLES samples and
#: SATURATION_SHARE of the record, that the record leaves again, is a saturated sensor or drive.
SATURATION_BAND, SATURATION_SAMPLES, SATURATION_SHARE = 1e-9, 8, 0.02
#: The largest damping ratio the optimiser tries (the geometry takes [0, 1); a link this damped has no modes to fit).
MAX_DAMPING_RATIO = 0.9
#: A fitted parameter within this of its bound (``log`` of its factor: 0.1 %) ran to it: the data does not determine it.
AT_BOUND = 1e-3
#: A record whose hub angle correlates with the nominal model's below minus this has its torque's sign flipped.
FLIPPED_CORRELATION = 0.5
#: A relative RMS residual above this is no calibration (the model cannot reproduce the data).
MAX_RELATIVE_RESIDUAL = 0.05
#: A fit that leaves the data more than this many stated standard deviations off (RMS) is no calibration.
MAX_STATED_RATIO = 3.0
#: Most rows a data file may have.
MAX_ROWS = 1_000_000
#: Where the optimiser starts: the nominal values and this many less one Sobol points, each factor within
#: ``[1/SPREAD, SPREAD]`` of the nominal value (a start 20-25 % off still finds the minimum the data points to).
STARTS, SPREAD = 8, 2.0
#: Each start gets this many iterations; one whose cost is then within PROMISING x the lowest is iterated to its minimum
#: (a start that has not come near by then leads to a worse minimum, or to the same).
PROBE, PROMISING = 12, 3.0
#: The fit is repeated with up to this many modes more than it started with, until no estimate moves by more than
#: CONVERGED of its noise interval; the last change is the model's part of the interval.
MORE_MODES, CONVERGED = 3, 0.2
#: A fit that leaves a residual above this many times the noise the data shows by itself (at least NOISE_FLOOR, the
#: relative noise of a good instrument) is no calibration: the model cannot reproduce the data.
MAX_NOISE_RATIO, NOISE_FLOOR = 2.0, 1e-3
#: A record's delay is refined on the model shifted by it up to this many samples (beyond, its first order is kept: a
#: delay of many samples is a record misaligned, not a sensor read late).
MAX_DELAY_SAMPLES = 20
#: A record's comment lines (``# delay_theta = ...``) are read among its first this many lines.
MAX_COMMENTS = 50
#: The longest line of a data CSV read (a row of numbers is a few hundred characters).
MAX_LINE = 100_000
#: What a frequency list refused by MAX_RELATIVE_RESIDUAL is told: a rough list is judged by its stated reading.
_ROUGH = (" -- or, for frequencies read roughly, their reading's standard deviation in the file (uncertainty_hz = HZ), by "
          "which the list is then judged")
#: A parameter held at its nominal value is assumed within this of the link's (relative, 95 %) unless its spread is stated
#: (``held_spread``, ``sflm fit --held-spread``): an assumption, reported as one, whose part enters every fitted interval
#: (issue 62: a payload mass held 30 % off bent EI 2.3 half-widths, the intervals silent about it). A file's nominal values
#: are a datasheet's and a drawing's: 20-30 % off is what the calibration's own tests start from.
HELD_SPREAD = 0.3
#: The largest spread a held parameter may be stated with (relative, 95 %: 1000 %).
MAX_HELD_SPREAD = 10.0
#: A record's residual is tested for correlation with its torque at lags up to this many samples either way
#: (:func:`modelgen.record.input_correlation`); beyond INPUT_CORRELATION standard deviations at any lag the fit is refused
#: with the lag and what it points to. Measured on the beam's doublets, clean and as a bench gives them (80 channel
#: records): at most 3.0; with the hub's dry friction left out of the model, 4.5 (issue 61, item 2). A channel whose residual
#: is below NOISE_FLOOR of its range (an exact record's) is not refused: its correlation is the arithmetic's.
INPUT_LAGS, INPUT_CORRELATION = 50, 4.0


class FitError(SflmError, ValueError):
    """A fit that did not give a model, with its figures.

    A fit that did not give a model: not converged, a residual far above the data's, an interval wider than its value,
    or parameters the data cannot separate -- with its figures.
    """


@dataclass(frozen=True)
class FrequencyData:
    """Measured natural frequencies (Hz) and their boundary.

    Attributes
    ----------
    frequencies_hz : FloatArray
        The measured natural frequencies (Hz), lowest first.
    boundary : str, optional
        The boundary they were measured with (``"hub-free"`` or ``"clamped"``).
    uncertainty_hz : float | None, optional
        The measurement's uncertainty (Hz), if known.
    kind : str, optional
        The kind of data (``"frequencies"``).
    """

    frequencies_hz: FloatArray
    boundary: str = "hub-free"
    uncertainty_hz: float | None = None
    kind: str = "frequencies"


@dataclass(frozen=True)
class FrequencyResponse:
    """A measured frequency response from the hub torque.

    A measured frequency response from the hub torque to ``output`` (``"theta"`` or ``"y"``).

    Attributes
    ----------
    f : FloatArray
        The frequencies (Hz).
    magnitude : FloatArray
        The response's magnitude at ``f``.
    phase_deg : FloatArray
        The response's phase at ``f`` (degrees).
    output : str, optional
        The measured output, ``"theta"`` or ``"y"``.
    kind : str, optional
        The kind of data (``"frequency-response"``).
    delay : float | None, optional
        The measurement's delay the data states (s: the response is ``G(j w) exp(-j w delay)``); ``None``: fitted.
    """

    f: FloatArray
    magnitude: FloatArray
    phase_deg: FloatArray
    output: str = "theta"
    kind: str = "frequency-response"
    delay: float | None = None


@dataclass(frozen=True)
class TimeSeries:
    """An experiment from rest: hub torque, hub angle, tip.

    An experiment from rest: the hub torque ``tau`` (held between the samples), the hub angle ``theta`` and, where
    measured, the tip ``y``. In closed loop, ``tau`` is the feedforward, ``reference`` the joint reference ``theta_d``
    and ``law`` the joint PD's ``(k_P, k_D)``: the hub then gets ``tau + k_P (theta_d - theta) + k_D (thetadot_d -
    thetadot)``.

    Attributes
    ----------
    t : FloatArray
        The sample times (s).
    tau : FloatArray
        The hub torque (N m), held between the samples.
    theta : FloatArray
        The hub angle (rad).
    y : FloatArray | None, optional
        The tip displacement (m), if measured.
    reference : FloatArray | None, optional
        The joint reference ``theta_d`` of a closed-loop record.
    law : tuple[float, float] | None, optional
        The joint PD's ``(k_P, k_D)`` of a closed-loop record.
    kind : str, optional
        The kind of data (``"time-series"``).
    delays : dict[str, float], optional
        The channels' (``theta``, ``y``) measurement delays the data states (s); the others are fitted.
    """

    t: FloatArray
    tau: FloatArray
    theta: FloatArray
    y: FloatArray | None = None
    reference: FloatArray | None = None
    law: tuple[float, float] | None = None
    kind: str = "time-series"
    delays: dict[str, float] = field(default_factory=dict)


Data = FrequencyData | FrequencyResponse | TimeSeries


@dataclass(frozen=True)
class Fit:
    """A calibration: fitted values, intervals, residuals.

    A calibration: the fitted values with their 95 % intervals, the residuals before and after, what was held.

    Attributes
    ----------
    geometry : Geometry
        The calibrated geometry (the nominal one with the fitted values).
    nominal : Geometry
        The geometry it started from.
    values, intervals : dict
        The fitted value of each parameter and the half-width of its 95 % interval (same units).
    held : dict
        The parameters left at their nominal values, and why.
    residual, nominal_residual : float
        The relative RMS residual of the fit and of the nominal model on the same data.
    data_hash : str
        SHA-256 of the data file (or of the data's values).
    kind : str
        What was fitted to (``frequencies``, ``frequency-response``, ``time-series``).
    points : int
        Number of data points fitted.
    evaluations : int
        Number of model evaluations the fit took.
    correlations : dict[str, float], optional
        The fitted parameters' correlations.
    modes : int, optional
        The modes of the fit whose values are reported: the model's, or one more than the nominal modes in the data's
        band.
    checked_modes : int, optional
        The most modes the estimates were fitted with again (until they stopped moving): their change from ``modes`` is
        the model's part of each interval.
    noise_intervals, model_intervals : dict, optional
        Each interval's parts: the noise's (95 %, widened where the residuals are correlated) and the model's (the
        change of the estimate from one mode less); ``intervals`` is their root sum of squares.
    noise : float | None, optional
        The relative noise the data shows by itself (:mod:`modelgen.record`), where it can be read.
    lag_one, widening : float, optional
        The residuals' lag-one autocorrelation and the factor it widened the noise part by.
    starts : int, optional
        How many starts the optimiser took.
    converged : bool, optional
        Whether the estimates stopped moving as modes were added.
    notes : list[str], optional
        What the fit decided on its own (more modes, wider intervals), in words.
    artefacts : dict, optional
        A record's: each channel's (``theta``, ``y``) measurement delay (s), offset and linear drift, fitted beside the
        link's parameters, with 95 % half-widths (``delay_95``, ...); a frequency response's delay (``output``).
    held_intervals : dict, optional
        Each interval's third part: what the held parameters' plausible errors (``held_spread``) move the estimate by
        (95 %, first order: the fit's sensitivity to each held parameter); ``intervals`` has it in its root sum of squares.
    held_spread : dict, optional
        Each held parameter's plausible error (relative, 95 %) and whether it was assumed (:data:`HELD_SPREAD`) or stated.
    residual_tests : dict, optional
        A record's, each channel's: the residual's lag-one autocorrelation and its largest correlation with the torque
        (``input_correlation``, at ``at_lag_s``; ``z``: in standard deviations were the model right, ``limit``:
        :data:`INPUT_CORRELATION`; ``rms``: the residual's, a share of the channel's range).
    """

    geometry: Geometry
    nominal: Geometry
    values: dict[str, float]
    intervals: dict[str, float]
    held: dict[str, str]
    residual: float
    nominal_residual: float
    data_hash: str
    kind: str
    points: int
    evaluations: int
    correlations: dict[str, float] = field(default_factory=dict)
    modes: int = 0
    checked_modes: int = 0
    noise_intervals: dict[str, float] = field(default_factory=dict)
    model_intervals: dict[str, float] = field(default_factory=dict)
    noise: float | None = None
    lag_one: float = 0.0
    widening: float = 1.0
    starts: int = 1
    converged: bool = True
    notes: list[str] = field(default_factory=list)
    artefacts: dict[str, dict[str, float]] = field(default_factory=dict)
    held_intervals: dict[str, float] = field(default_factory=dict)
    held_spread: dict[str, dict[str, Any]] = field(default_factory=dict)
    residual_tests: dict[str, dict[str, float]] = field(default_factory=dict)

    def summary(self) -> dict[str, Any]:
        """What ``sflm fit --json`` prints."""
        return {"kind": self.kind, "points": self.points, "data_sha256": self.data_hash,
                "residual": self.residual, "nominal_residual": self.nominal_residual, "evaluations": self.evaluations,
                "parameters": {k: {"nominal": parameter_value(self.nominal, k), "value": v,
                                   "interval_95": self.intervals[k], "relative_interval": self.intervals[k] / abs(v),
                                   "noise_95": self.noise_intervals.get(k), "model_95": self.model_intervals.get(k),
                                   "held_95": self.held_intervals.get(k, 0.0)}
                               for k, v in self.values.items()},
                "held": self.held, "correlations": self.correlations, "modes": self.modes, "model_modes": self.nominal.modes,
                "checked_modes": self.checked_modes,
                "converged": self.converged, "data_noise": self.noise, "residual_lag_one": self.lag_one,
                "widening": self.widening, "starts": self.starts, "notes": self.notes, "artefacts": self.artefacts,
                "held_spread": self.held_spread, "residual_tests": self.residual_tests}


def _hash(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _finite(name: str, values: Sequence[Any], source: str) -> FloatArray:
    if isinstance(values, (list, tuple)) and any(isinstance(v, bool) for v in values):  # TOML's true is no 1.0
        raise SettingsError(f"{source}: {name}", "true or false among the numbers", "numbers")
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise SettingsError(f"{source}: {name}", "a value that is not a number", "numbers") from None
    if array.ndim != 1 or array.size == 0 or not np.all(np.isfinite(array)):
        raise SettingsError(f"{source}: {name}", "NaN, inf or empty", "finite numbers, at least one")
    return array


def read_data(path: str | Path, output: str | None = None, law: tuple[float, float] | None = None) -> Data:
    """The measurement in ``path``, its kind told by its contents.

    The measurement in ``path``, its kind told by its keys (TOML) or header (CSV); ``law``: the joint PD's
    ``(k_P, k_D)`` of a closed-loop record (header ``t,tau_ff,theta_d,theta[,y]``).

    Parameters
    ----------
    path : str | Path
        A TOML or CSV file of measurements.
    output : str | None, optional
        The measured output of a frequency response, if its file does not say.
    law : tuple[float, float] | None, optional
        The joint PD's ``(k_P, k_D)`` of a closed-loop record.

    Raises
    ------
    SettingsError
        For a file that cannot be read, an unknown header, NaN or infinite values, time not increasing, a frequency list
        not ascending or not positive.
    """
    path = Path(path)
    if not path.is_file():
        raise SettingsError("data", str(path), "an existing .toml (frequencies) or .csv (time series, frequency response) file")
    if path.suffix.lower() == ".toml":
        return _read_frequencies(path, law)
    try:
        with path.open(newline="", encoding="utf-8-sig") as handle:  # a spreadsheet's byte-order mark is no header
            lines = []
            for _ in range(MAX_ROWS + 2 + MAX_COMMENTS):
                line = handle.readline(MAX_LINE + 1)  # a line at a time, each bounded: a 300 MB one-line file was read whole
                if not line:
                    break
                if len(line) > MAX_LINE:
                    raise SettingsError("data", str(path), f"a CSV file of lines at most {MAX_LINE} characters long (line "
                                                           f"{len(lines) + 1} is longer)")
                lines.append(line)
            leading = next((k for k, line in enumerate(lines[:MAX_COMMENTS]) if not line.startswith("#")), 0)
            stated = lines[:leading]  # the comment lines before the header
            rows = list(csv.reader(lines[leading:]))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise SettingsError("data", str(path), f"a readable CSV file ({exc})") from None
    if len(rows) > MAX_ROWS + 1:
        raise SettingsError("data", str(path), f"at most {MAX_ROWS} rows")
    if len(rows) < 3:
        raise SettingsError("data", str(path), "a header and at least two rows")
    header = [h.strip() for h in rows[0]]
    repeated = sorted({h for h in header if header.count(h) > 1})
    if repeated:
        raise SettingsError(f"{path.name}: header", ",".join(header), f"each column once ({', '.join(repeated)} repeated: which one is "
                            "the measurement?)")
    try:
        columns = {name: [float(row[i]) for row in rows[1:]] for i, name in enumerate(header)}
    except (ValueError, IndexError):
        raise SettingsError("data", str(path), "rows of numbers under the header, as many as its columns") from None
    closed = header[:4] == ["t", "tau_ff", "theta_d", "theta"]
    if law is not None and not closed:  # a loop's gains with an open-loop record or a response would be ignored
        raise SettingsError("--kp, --kd", f"{law[0]}, {law[1]}", "only with a closed-loop record (the header "
                            "t,tau_ff,theta_d,theta[,y]); this file's header is " + ",".join(header))
    if header[:3] == ["f", "magnitude", "phase"] and set(header) <= {"f", "magnitude", "phase", "output"}:
        f, mag, phase = (_finite(k, columns[k], path.name) for k in ("f", "magnitude", "phase"))
        if np.any(f <= 0) or np.any(np.diff(f) <= 0) or np.any(mag <= 0):
            raise SettingsError(f"{path.name}: f, magnitude", "not increasing or not positive", "frequencies > 0 ascending, magnitudes > 0")
        chosen = output or "theta"
        if chosen not in ("theta", "y"):
            raise SettingsError("output", chosen, "'theta' (the hub angle) or 'y' (the tip)")
        delays = _stated_delays(stated, path.name, (chosen,), 1.0 / float(f[0]), "a period of its lowest frequency")
        return FrequencyResponse(f, mag, phase, chosen, delay=delays.get(chosen))
    if header[:3] == ["t", "tau", "theta"] and set(header) <= {"t", "tau", "theta", "y"}:
        t, tau, theta = (_finite(k, columns[k], path.name) for k in ("t", "tau", "theta"))
        _evenly(t, path.name)
        y = _finite("y", columns["y"], path.name) if "y" in columns else None
        return TimeSeries(t, tau, theta, y, delays=_stated_delays(stated, path.name, ("theta", "y") if y is not None else ("theta",),
                                                                   MAX_DELAY_SAMPLES * float(t[1] - t[0]), f"{MAX_DELAY_SAMPLES} samples"))
    if header[:4] == ["t", "tau_ff", "theta_d", "theta"] and set(header) <= {"t", "tau_ff", "theta_d", "theta", "y"}:
        if law is None or len(law) != 2 or not all(isinstance(g, (int, float)) and math.isfinite(g) and g >= 0 for g in law):
            raise SettingsError("law", law, "the joint PD's gains (finite, >= 0) of this closed-loop record")
        t, tau, reference, theta = (_finite(k, columns[k], path.name) for k in ("t", "tau_ff", "theta_d", "theta"))
        _evenly(t, path.name)
        y = _finite("y", columns["y"], path.name) if "y" in columns else None
        return TimeSeries(t, tau, theta, y, reference, (float(law[0]), float(law[1])),
                          delays=_stated_delays(stated, path.name, ("theta", "y") if y is not None else ("theta",),
                                                MAX_DELAY_SAMPLES * float(t[1] - t[0]), f"{MAX_DELAY_SAMPLES} samples"))
    raise SettingsError(f"{path.name}: header", ",".join(header), "'f,magnitude,phase' (a frequency response), 't,tau,theta[,y]' "
                        "(a time series) or 't,tau_ff,theta_d,theta[,y]' (in closed loop, with --kp, --kd); or a .toml file "
                        "with frequencies_hz")


def _read_frequencies(path: Path, law: tuple[float, float] | None) -> FrequencyData:
    """:func:`read_data`'s natural frequencies (a TOML file: ``frequencies_hz``, ``boundary``, ``uncertainty_hz``)."""
    if law is not None:
        raise SettingsError("--kp, --kd", f"{law[0]}, {law[1]}", "only with a closed-loop record (a CSV with the header "
                            "t,tau_ff,theta_d,theta[,y]), not with natural frequencies")
    try:
        document = read_document(path, "toml")
    except (DocumentError, OSError) as exc:
        raise SettingsError("data", str(path), f"a TOML file ({str(exc).splitlines()[0] if str(exc) else 'unreadable'})") from None
    unknown = set(document) - {"frequencies_hz", "boundary", "uncertainty_hz", "name", "note"}
    if "frequencies_hz" not in document or unknown:
        raise SettingsError(f"{path.name}: {sorted(unknown)[0] if unknown else 'frequencies_hz'}", "missing or unknown",
                            "frequencies_hz = [f1, f2, ...] and boundary = 'hub-free' or 'hub-clamped'")
    f = _finite("frequencies_hz", document["frequencies_hz"], path.name)
    if np.any(f <= 0) or np.any(np.diff(f) <= 0):
        raise SettingsError(f"{path.name}: frequencies_hz", f.tolist(), "frequencies > 0 in ascending order (Hz)")
    boundary = document.get("boundary", "hub-free")
    if boundary not in ("hub-free", "hub-clamped"):
        near = {"free": "hub-free", "clamped": "hub-clamped", "pinned": "hub-free", "fixed": "hub-clamped"}.get(str(boundary).strip().lower())
        raise SettingsError(f"{path.name}: boundary", boundary, "'hub-free' (the hub free to rotate: the frequencies sflm info "
                            "reports) or 'hub-clamped' (the hub held)" + (f"; {near!r} is the name of {boundary!r}" if near else ""))
    spread = document.get("uncertainty_hz")
    if spread is not None and (isinstance(spread, bool) or not isinstance(spread, (int, float)) or not 0 < spread < math.inf):
        raise SettingsError(f"{path.name}: uncertainty_hz", spread, "a finite number > 0 (Hz: the measurement's standard deviation)")
    return FrequencyData(f, boundary, None if spread is None else float(spread))


def _stated_delays(lines: list[str], name: str, measured: tuple[str, ...], longest: float, words: str) -> dict[str, float]:
    """The delays a data file's comment lines state for its ``measured`` channels (``# delay_theta = S``, ``# delay_y =
    S``, ``# delay = S`` for each: seconds, finite, >= 0, at most ``longest``, ``words`` in the message); other comments
    are the user's own."""
    delays: dict[str, float] = {}
    for line in lines:
        key, sep, value = line.lstrip("#").partition("=")
        key = key.strip()
        if not sep or key not in ("delay", "delay_theta", "delay_y"):
            continue
        try:
            seconds = float(value.strip())
        except ValueError:
            seconds = math.nan
        if not 0 <= seconds <= longest:
            raise SettingsError(f"{name}: {key}", value.strip(), f"a delay in seconds, >= 0 and at most {words} ({longest:g} s)")
        channels = measured if key == "delay" else (key[6:],)
        if channels[0] not in measured:
            raise SettingsError(f"{name}: {key}", value.strip(), f"a delay of a measured channel (this file measures "
                                f"{' and '.join(measured)})")
        delays.update({c: seconds for c in channels})
    return delays


def _evenly(t: FloatArray, name: str) -> None:
    steps = np.diff(t)
    if np.any(steps <= 0):
        raise SettingsError(f"{name}: t", "not increasing", "times in increasing order (s)")
    if np.ptp(steps) > 1e-6 * steps.mean():
        raise SettingsError(f"{name}: t", "unevenly spaced", "evenly spaced samples (the torque is held between them)")


# -- the model's side ----------------------------------------------------------------------------------------------------


def _with(geometry: Geometry, keys: Sequence[str], factors: FloatArray) -> Geometry:
    return scaled(geometry, dict(zip(keys, (float(f) for f in factors))))


def _model_frequencies(geometry: Geometry, boundary: str) -> FloatArray:
    from .linear import linear_model
    from .model import natural_frequencies

    m = linear_model(geometry)
    if boundary == "hub-clamped":
        import scipy.linalg as sla

        w2 = sla.eigh(m["K"][1:, 1:], m["M"][1:, 1:], eigvals_only=True)
        return np.sqrt(np.clip(np.sort(w2), 0.0, None)) / (2 * np.pi)
    return natural_frequencies(m["K"], m["M"]) / (2 * np.pi)


def _output_row(m: dict[str, Any], output: str) -> FloatArray:
    if output == "y":
        return np.asarray(m["C_out"], dtype=float)
    row = np.zeros(np.asarray(m["A"]).shape[0])
    row[0] = 1.0
    return row


def _response(geometry: Geometry, f: FloatArray, output: str) -> NDArray[np.complex128]:
    from .linear import linear_model

    m = linear_model(geometry)
    A, B, C = np.asarray(m["A"], dtype=float), np.asarray(m["B"], dtype=float).reshape(-1), _output_row(m, output)
    pencils = 2j * np.pi * np.asarray(f)[:, None, None] * np.eye(A.shape[0]) - A  # every frequency in one batched solve
    return np.linalg.solve(pencils, np.broadcast_to(B, (len(f), B.size))[..., None])[..., 0] @ C


def _simulate(geometry: Geometry, data: TimeSeries) -> tuple[FloatArray, FloatArray]:
    import scipy.linalg as sla

    from .linear import linear_model

    m = linear_model(geometry)
    A, B = np.asarray(m["A"], dtype=float), np.asarray(m["B"], dtype=float).reshape(-1, 1)
    N = A.shape[0]
    h = float(data.t[1] - data.t[0])
    block = sla.expm(np.block([[A, B], [np.zeros((1, N + 1))]]) * h)
    Ad, Bd = block[:N, :N], block[:N, N]
    rows = np.zeros((2, N))
    rows[0, 0] = 1.0
    rows[1] = np.asarray(m["C_out"], dtype=float)
    friction = float(geometry.hub_coulomb_friction)
    if not friction and data.reference is None:
        return _convolved(Ad, Bd, rows, data.tau)
    x = np.zeros(N)
    states = np.empty((data.t.size, N))
    # the hub's dry friction, held over each sample like the torque: F_c sign(thetadot) while the hub turns; while it is
    # (nearly) still, static friction takes up to F_c of the torque (stuck below it, breaking away above)
    # "nearly": a millionth of the speed the largest torque gives the whole link over the record
    still = 1e-6 * float(np.abs(data.tau).max()) * float(data.t[-1] - data.t[0]) / float(m["M"][0, 0])
    if data.reference is not None and data.law is not None:  # closed loop: the joint PD on the held samples
        kp, kd = data.law
        rates = np.gradient(data.reference, h)
    for k, u in enumerate(data.tau):
        states[k] = x
        if data.reference is not None and data.law is not None:
            u = u + kp * (data.reference[k] - x[0]) + kd * (rates[k] - x[N // 2])
        if friction:
            speed = x[N // 2]
            u = u - (friction * math.copysign(1.0, speed) if abs(speed) > still else float(np.clip(u, -friction, friction)))
        x = Ad @ x + Bd * u
    return states @ rows[0], states @ rows[1]


def _convolved(Ad: FloatArray, Bd: FloatArray, rows: FloatArray, tau: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The outputs ``rows @ x_k`` of ``x_{k+1} = Ad x_k + Bd tau_k`` from rest: the impulse response ``rows Ad^k Bd``
    by doubling (``log2 K`` products, no loop over the samples), then one FFT convolution with the torque."""
    import scipy.signal as ss

    K = tau.size
    powers = rows[None]  # rows @ Ad^k for k < len(powers)
    square = Ad
    while powers.shape[0] < K:
        powers = np.concatenate([powers, powers @ square], axis=0)
        square = square @ square
    impulse = powers[:K] @ Bd  # (K, 2)
    out = np.zeros((K, 2))
    out[1:] = ss.fftconvolve(impulse[: K - 1], tau[: K - 1, None], axes=0)[: K - 1]
    return out[:, 0], out[:, 1]


def _residuals(geometry: Geometry, data: Data) -> FloatArray:
    """The relative residuals of ``geometry``'s model against ``data`` (module docstring)."""
    if isinstance(data, FrequencyData):
        model = _model_frequencies(geometry, data.boundary)
        return (model[: data.frequencies_hz.size] - data.frequencies_hz) / data.frequencies_hz
    if isinstance(data, FrequencyResponse):
        # the logarithm of the model over the measurement: its magnitude's and its phase's relative error. Over the
        # measured magnitude the complex difference weighed the points where noise made |G| small the most, a bias of
        # the noise's variance (0.3 half-widths at 2 %); the logarithm of a response with circular noise is unbiased
        # to second order
        ratio = _response(geometry, data.f, data.output) / (data.magnitude * np.exp(1j * np.deg2rad(data.phase_deg)))
        return np.concatenate([np.log(np.abs(ratio)), _response_delay(ratio, data)[0]])
    channels = _channels(geometry, data)
    weights = _channel_weights(data)
    return np.concatenate([w * _channel(model, measured, data.t, data.delays.get(name))[0]
                           for w, (name, model, measured) in zip(weights, channels)])


def _response_delay(ratio: NDArray[np.complex128], data: FrequencyResponse) -> tuple[FloatArray, float]:
    """A frequency response's phase residual with its measurement's delay taken out, and the delay (s).

    An analyser reads the response late by ``d`` (a sensor's or a drive's delay, a sample-and-hold): it measures ``G(j w)
    exp(-j w d)``, so the model over the measurement has the phase ``w d`` beside the link's own residual -- linear in
    ``d``, projected out at every evaluation (variable projection, as a record's delay: :func:`_channel`) so that the
    link is fitted, and its intervals computed, with the delay free. Issue 62: a 1-80 Hz response read 0.5 ms late was
    refused "more modes" every time. A delay the data states (``data.delay``) is taken out as given. Twice: the second
    pass on the phase with the first estimate removed, so that a phase the delay carries beyond ``pi`` is not wrapped.
    """
    w = 2 * np.pi * data.f
    if data.delay is not None:
        return np.angle(ratio * np.exp(-1j * w * data.delay)), float(data.delay)
    delay = 0.0
    phase = np.angle(ratio)
    for _ in range(2):
        step = float(w @ phase) / float(w @ w)
        delay += step
        phase = np.angle(ratio * np.exp(-1j * w * delay))
    return phase - w * (float(w @ phase) / float(w @ w)), delay + float(w @ phase) / float(w @ w)


def _channel_noise(measured: FloatArray) -> float:
    """A channel's noise relative to its range, a sample's: white noise on a smooth signal
    (:func:`modelgen.record.noise_level`) and an encoder's quantisation (its resolution ``q`` read from the record's
    levels, ``q^2 / 12``) together."""
    from .record import noise_level, resolution

    q = resolution(measured)
    return math.sqrt(noise_level(measured) ** 2 + q * q / 12.0) / max(float(np.ptp(measured)), 1e-300)


def _held_run(measured: FloatArray) -> float:
    """The mean run of samples a quantised channel holds one level for (1 for a channel that is not quantised): a level
    held for ``L`` samples is one rounding error for ``L`` samples, its weight in a fit that of one sample, not ``L``."""
    from .record import resolution

    if resolution(measured) == 0.0:
        return 1.0
    return float(measured.size) / (1.0 + float(np.count_nonzero(np.diff(measured))))


def _channel_weights(data: TimeSeries) -> list[float]:
    """Each channel's weight, so that a coarse encoder's angle and a fine tip sensor each count by what they can tell:
    the least effective noise over the channel's own (:func:`_channel_noise`, times ``sqrt`` of the run a quantised
    channel holds a level for: :func:`_held_run`); equal noises: weights 1, else at most 1."""
    measured = [data.theta] + ([] if data.y is None else [data.y])
    effective = [_channel_noise(c) * math.sqrt(_held_run(c)) for c in measured]
    if not all(math.isfinite(v) and v > 0 for v in effective):
        return [1.0] * len(effective)
    least = min(effective)
    return [least / v for v in effective]


def _channels(geometry: Geometry, data: TimeSeries) -> list[tuple[str, FloatArray, FloatArray]]:
    """Each measured channel of a record beside the model's prediction of it: ``(name, model, measured)``, the hub
    angle first."""
    theta, y = _simulate(geometry, data)
    return [("theta", theta, data.theta)] + ([] if data.y is None else [("y", y, data.y)])


def _channel(model: FloatArray, measured: FloatArray, t: FloatArray,
             given: float | None = None) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """One channel's relative residual with the bench's artefacts taken out, and the artefacts.

    A sensor on a bench reads late, from its own zero, and drifts: the measured channel is modelled as
    ``model(t - d) + o + s (t - t_0)``. To first order in the delay ``d`` (a fraction of a sample to a few samples
    against modes of tens of hertz) that is ``model(t) - d model'(t) + o + s (t - t_0)``, linear in ``(d, o, s)``: they
    are projected out of the residual at every evaluation (variable projection), so that the link's parameters are
    fitted, and their intervals computed, with the artefacts free -- never absorbed into the link (issue 61: a 0.5 ms
    delay moved the payload inertia 2 half-widths, a 2 % drift the payload mass 14).

    A delay the data states (``given``, s) shifts the model by it and is not fitted.

    Returns
    -------
    residual : FloatArray
        ``(model - measured) / ptp(measured)`` less its projection on ``[1, t - t_0, model']``.
    coefficients : FloatArray
        The projection's coefficients (scaled residual units): ``-o``, ``-s``, ``d`` (s).
    inverse : FloatArray
        ``(X^T X)^-1`` of the basis, for the coefficients' covariance.
    scale : float
        ``ptp(measured)``.
    """
    from scipy.interpolate import CubicSpline

    scale = max(float(np.ptp(measured)), 1e-300)
    h = float(t[1] - t[0])

    def projected(prediction: FloatArray, delayed: bool = True) -> tuple[FloatArray, FloatArray, FloatArray]:
        r = (prediction - measured) / scale
        columns = [np.ones_like(t), t - t[0]] + ([np.gradient(prediction / scale, h)] if delayed else [])
        basis = np.column_stack(columns)
        coefficients, *_ = np.linalg.lstsq(basis, r, rcond=None)
        return r - basis @ coefficients, coefficients, basis

    def shift(delay: float) -> FloatArray:  # the model read delay s late, from rest before t_0
        return np.where(t - delay >= t[0], CubicSpline(t, model)(np.maximum(t - delay, t[0])), 0.0)

    if given is not None:
        r, coefficients, basis = projected(shift(given) if given else model, delayed=False)
        inverse = np.asarray(np.linalg.pinv(basis.T @ basis), dtype=float)
        return r, np.array([coefficients[0], coefficients[1], given], dtype=float), inverse, scale
    r, coefficients, basis = projected(model)
    delay = float(coefficients[2])
    if 0 < abs(delay) <= MAX_DELAY_SAMPLES * h:  # once more on the model shifted by it: the delay's second order out
        r, coefficients, basis = projected(shift(delay))
        coefficients = np.array([coefficients[0], coefficients[1], delay + float(coefficients[2])])
    return r, np.asarray(coefficients, dtype=float), np.asarray(np.linalg.pinv(basis.T @ basis), dtype=float), scale


def _artefacts(geometry: Geometry, data: TimeSeries, quantile: float) -> dict[str, dict[str, float]]:
    """The bench's artefacts fitted beside the link's parameters (:func:`_channel`), each channel's delay (s), offset
    (its unit) and drift (its unit a second), with 95 % half-widths (conditional on the fitted link, widened by the
    channel's own correlation)."""
    from .record import correlation_time, lag_one

    out: dict[str, dict[str, float]] = {}
    for name, model, measured in _channels(geometry, data):
        given = data.delays.get(name)
        r, c, inverse, scale = _channel(model, measured, data.t, given)
        variance = float(r @ r) / max(r.size - 3, 1)
        wide = lag_one(r, [r.size])[1]  # the channel's own widening, as in _solve
        if _held_run(measured) > 1.0:
            wide = max(wide, math.sqrt(correlation_time(r)))
        half = quantile * wide * np.sqrt(np.clip(np.diag(inverse) * variance, 0.0, None))
        out[name] = {"delay": float(c[2]), "delay_95": 0.0 if given is not None else float(half[2]),
                     "delay_given": given is not None, "offset": float(-c[0] * scale),
                     "offset_95": float(half[0] * scale), "drift": float(-c[1] * scale), "drift_95": float(half[1] * scale)}
    return out


def input_correlations(geometry: Geometry, data: TimeSeries) -> dict[str, tuple[FloatArray, FloatArray, float]]:
    """Each channel's residual correlation with the torque.

    What :func:`fit` tests a record's fit by. The residual of ``geometry``'s model (the bench's artefacts out: :func:`_channel`) against each measured channel,
    correlated with the torque at lags ``-INPUT_LAGS..INPUT_LAGS`` samples (:func:`modelgen.record.input_correlation`).

    Parameters
    ----------
    geometry : Geometry
        The fitted link, with the fit's modes (``Fit.geometry.with_model(Fit.modes)``).
    data : TimeSeries
        The record.

    Returns
    -------
    dict
        By channel (``theta``, ``y``): the lags (s), the correlations, their standard deviation were the model right.
    """
    return {name: (lags, rho, sd) for name, (lags, rho, sd, _) in _correlated(geometry, data).items()}


def _correlated(geometry: Geometry, data: TimeSeries) -> dict[str, tuple[FloatArray, FloatArray, float, FloatArray]]:
    """:func:`input_correlations`, each channel's residual beside (one simulation of the model)."""
    from .record import input_correlation

    h = float(data.t[1] - data.t[0])
    out: dict[str, tuple[FloatArray, FloatArray, float, FloatArray]] = {}
    for name, model, measured in _channels(geometry, data):
        r = _channel(model, measured, data.t, data.delays.get(name))[0]
        lags, rho, sd = input_correlation(r, data.tau, min(INPUT_LAGS, r.size // 4))
        out[name] = (np.asarray(lags * h, dtype=float), rho, sd, r)
    return out


def _residual_tests(geometry: Geometry, data: TimeSeries) -> dict[str, dict[str, float]]:
    """Each channel's residual tested against what a right model leaves: its lag-one autocorrelation, and its largest
    correlation with the torque (:func:`input_correlations`) in standard deviations."""
    from .record import lag_one

    out: dict[str, dict[str, float]] = {}
    for name, (lags, rho, sd, r) in _correlated(geometry, data).items():
        k = int(np.argmax(np.abs(rho)))
        out[name] = {"lag_one": lag_one(r, [r.size])[0], "input_correlation": float(rho[k]), "at_lag_s": float(lags[k]),
                     "z": float(abs(rho[k]) / sd), "limit": INPUT_CORRELATION, "rms": float(np.sqrt(np.mean(r * r)))}
    return out


def _response_artefacts(geometry: Geometry, data: FrequencyResponse, quantile: float, widening: float) -> dict[str, dict[str, float]]:
    """A frequency response's measurement delay (s) fitted beside the link (:func:`_response_delay`), with its 95 %
    half-width (conditional on the fitted link, widened as the link's intervals are), keyed by the output."""
    ratio = _response(geometry, data.f, data.output) / (data.magnitude * np.exp(1j * np.deg2rad(data.phase_deg)))
    phase, delay = _response_delay(ratio, data)
    w = 2 * np.pi * data.f
    variance = float(phase @ phase) / max(phase.size - 1, 1)
    half = 0.0 if data.delay is not None else quantile * widening * math.sqrt(variance / float(w @ w))
    return {data.output: {"delay": delay, "delay_95": half, "delay_given": data.delay is not None}}


def predicted(geometry: Geometry, data: Data) -> FloatArray | NDArray[np.complex128]:
    """What ``geometry``'s model predicts for ``data``'s measurement.

    What ``geometry``'s model predicts for ``data``'s measurement: its natural frequencies (Hz, as many as measured),
    its complex frequency response at ``data.f``, or its hub angle (and tip, stacked as a second row) at ``data.t``.

    Parameters
    ----------
    geometry : Geometry
        The geometry whose model predicts.
    data : Data
        The measurement.
    """
    if isinstance(data, FrequencyData):
        return _model_frequencies(geometry, data.boundary)[: data.frequencies_hz.size]
    if isinstance(data, FrequencyResponse):
        return _response(geometry, data.f, data.output)
    return np.stack(_simulate(geometry, data))


def _check_data(geometry: Geometry, data: Data) -> None:
    """Data the model can be fitted to: no more frequencies than the largest model can check (:data:`MORE_MODES`); a time
    series long enough to resolve the first mode (two of its periods, ten samples a period)."""
    if isinstance(data, FrequencyData) and data.frequencies_hz.size > MAX_MODES - MORE_MODES - 1:
        raise SettingsError("frequencies_hz", f"{data.frequencies_hz.size} frequencies",
                            f"at most {MAX_MODES - MORE_MODES - 1} (the fit takes one mode more, and more to check convergence, "
                            f"up to {MAX_MODES})")
    if isinstance(data, FrequencyData):  # a list in rad/s is 2 pi x the model's: named, not fitted 39 x stiffer
        count = data.frequencies_hz.size
        nominal = _model_frequencies(geometry.with_model(min(MAX_MODES, max(geometry.modes, count + 1))), data.boundary)[:count]
        ratios = data.frequencies_hz[: nominal.size] / np.maximum(nominal, 1e-300)
        mean = float(np.exp(np.mean(np.log(ratios))))
        if 2 * np.pi / 1.5 <= mean <= 2 * np.pi * 1.5 and np.all(np.abs(np.log(ratios / (2 * np.pi))) <= math.log(2.0)):
            raise SettingsError("frequencies_hz", f"{mean:.3g} x the nominal model's", "frequencies in hertz: these are "
                                f"{mean:.3g} x what the nominal model gives, as if they were in rad/s; sflm fit takes Hz "
                                "(divide them by 2 pi)")
    modes = None if isinstance(data, FrequencyData) else _model_frequencies(geometry, "hub-free")  # read once
    if isinstance(data, TimeSeries):
        first = float(modes[0])
        duration, step = float(data.t[-1] - data.t[0]), float(data.t[1] - data.t[0])
        if duration < 2.0 / first or step > 0.1 / first:
            raise SettingsError("data", f"{duration:.3g} s at {step:.3g} s", f"at least {2 / first:.3g} s sampled every "
                                f"{0.1 / first:.3g} s or faster: two periods of the first mode ({first:.3g} Hz), ten samples each")
    if isinstance(data, FrequencyResponse):
        first = float(modes[0])
        if data.f[-1] < first:
            raise SettingsError("data", f"up to {data.f[-1]:.3g} Hz", f"a response reaching the first mode ({first:.3g} Hz)")
    if modes is not None:
        if isinstance(data, TimeSeries):
            _check_record(data, modes)
        _check_sign(geometry, data, float(modes[0]))


#: The widest interval a message quotes as a figure (per cent); beyond it, "more than" this.
WIDEST_QUOTED = 1e6


def interval_text(half: float) -> str:
    """A predicted 95 % half-width as a message says it.

    In ``log(value / nominal)``: ``+-12.3 %``, or ``more than +-1e+06 %`` where it is wider (computed without overflow:
    ``expm1`` of a half-width of 1e3 is beyond a double).

    Parameters
    ----------
    half : float
        The half-width, in ``log(value / nominal)`` (``inf`` and ``nan`` allowed).
    """
    if not half <= math.log1p(WIDEST_QUOTED / 100):  # also nan
        return f"more than +-{WIDEST_QUOTED:.3g} %"
    return f"+-{100 * math.expm1(half):.3g} %"


def _check_record(data: TimeSeries, modes: FloatArray) -> None:
    """A time series that can calibrate: excited, not clipped, sampled faster than twice the model's ``modes`` (Hz)."""
    signals = {"tau_ff" if data.reference is not None else "tau": data.tau, "theta": data.theta,
               **({} if data.y is None else {"y": data.y})}
    for name, values in signals.items():  # a step torque is constant from the first sample: only none at all is refused
        if not np.ptp(values) > 0 and (name == "theta" or name == "y" or float(values[0]) == 0.0):
            raise SettingsError(f"data: {name}", f"constant at {float(values[0]):.4g}", "a record that moves: the torque drives the "
                                "link and the angles follow (a constant record tells nothing)")
    drive = signals["tau_ff" if data.reference is not None else "tau"]
    # the link at rest before the input moves is rest, not a clipped sensor: the runs are looked for after it
    moving = np.flatnonzero(np.abs(drive - drive[0]) > 1e-12 * max(float(np.ptp(drive)), abs(float(drive[0])), 1e-300))
    start = int(moving[0]) if moving.size else 0
    for name in ("theta", "y"):
        values = signals.get(name)
        if values is None:
            continue
        span = float(np.ptp(values))
        for end, word in ((float(values.max()), "largest"), (float(values.min()), "smallest")):
            at = np.abs(values - end) <= SATURATION_BAND * span
            at[:start] = False
            run = _longest_run(at)
            if (run >= max(SATURATION_SAMPLES, SATURATION_SHARE * values.size) and not _settled(values, at)
                    and not _turning_point(data.t, values, at)):
                raise SettingsError(f"data: {name}", f"flat at its {word} value {end:.4g} for {run} samples",
                                    "a record within the sensor's range: a flat run at an extreme that the record leaves again "
                                    "is the sensor or the drive saturating (the model cannot reproduce it)")
    step = float(data.t[1] - data.t[0])
    nyquist = 0.5 / step
    above = [i for i, f in enumerate(modes) if f > nyquist]
    if above:
        k = above[0]
        raise SettingsError("data", f"sampled every {step:.3g} s (Nyquist {nyquist:.4g} Hz)",
                            f"a record sampled faster than twice the model's mode {k + 1} ({float(modes[k]):.4g} Hz): it aliases "
                            f"there; sample faster, or fit with --modes {k}" if k > 0 else
                            f"a record sampled faster than twice the first mode ({float(modes[0]):.4g} Hz)")


def _longest_run(flags: NDArray[np.bool_]) -> int:
    """The longest run of ``True``."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], flags.astype(np.int8), [0]])))  # starts and ends, in pairs
    return int((edges[1::2] - edges[::2]).max(initial=0))


def _turning_point(t: FloatArray, values: FloatArray, at: NDArray[np.bool_]) -> bool:
    """Whether the longest flat run of ``at`` is a turning point a quantised sensor holds at one count (not a clip).

    A parabola fitted to the record on both sides of the run (a quarter as many samples as the run, on each) predicts the extreme
    the signal turns at: within two of the sensor's steps (its smallest change between samples, an encoder's count) and
    the fit's scatter of the run's level, the plateau is the count the turning point sits on; a clipped signal turns
    well beyond it (its flanks point past the limit).
    """
    edges = np.flatnonzero(np.diff(np.concatenate([[0], at.astype(np.int8), [0]])))
    starts, ends = edges[::2], edges[1::2]
    longest = int(np.argmax(ends - starts))
    i0, i1 = int(starts[longest]), int(ends[longest])  # the run is values[i0:i1]
    width = max(3, (i1 - i0) // 4)  # near the run: a clipped signal's flanks still climb there, a turning point's level off
    left, right = np.arange(max(0, i0 - width), i0), np.arange(i1, min(values.size, i1 + width))
    if left.size < 3 or right.size < 3:
        return False  # no flank to judge by: as before, a flat run at an extreme
    flank = np.concatenate([left, right])
    tc = float(t[i0] + t[i1 - 1]) / 2
    x = t[flank] - tc
    coefficients, residuals, *_ = np.linalg.lstsq(np.column_stack([np.ones_like(x), x, x * x]), values[flank], rcond=None)
    c0, c1, c2 = (float(c) for c in coefficients)
    if c2 == 0.0:
        return False
    vertex = -c1 / (2 * c2)
    if not abs(vertex) <= float(t[i1 - 1] - t[i0]):  # the parabola turns outside the run: not this run's turning point
        return False
    steps = np.abs(np.diff(values))
    moving = steps[steps > 0]
    step = float(moving.min()) if moving.size else 0.0
    scatter = math.sqrt(float(residuals[0]) / flank.size) if np.size(residuals) else 0.0
    level = float(values[i0])
    return abs(c0 - c1 * c1 / (4 * c2) - level) <= 2 * step + 3 * scatter


def _settled(values: FloatArray, at: NDArray[np.bool_]) -> bool:
    """Whether the flat run is where the record ends (a link at rest after a move is not a clipped sensor)."""
    return bool(at[-1]) and not bool(np.any(~at[np.argmax(at):]))


def _check_sign(geometry: Geometry, data: Data, first: float) -> None:
    """Refuse a record whose torque (or response) has the wrong sign.

    A time series whose hub angle the nominal model's runs against (their correlation below ``-FLIPPED_CORRELATION``);
    a frequency response opposite to the nominal model's below half its first mode, where any link is a rigid body
    (``Re(G conj(G_model)) < 0`` at most of those points; ``first``: its frequency, Hz). The nominal parameters may be
    far off near the resonances; they are not off in sign.
    """
    try:
        model = predicted(geometry, data)
    except (ValueError, np.linalg.LinAlgError, SflmError):
        return
    if isinstance(data, TimeSeries):
        theta = np.asarray(model[0], dtype=float)
        if np.ptp(theta) > 0 and np.ptp(data.theta) > 0:
            rho = float(np.corrcoef(theta, data.theta)[0, 1])
            if rho < -FLIPPED_CORRELATION:
                raise SettingsError("data", "the torque's sign flipped?", f"a record with the model's sign conventions: the hub angle "
                                    f"runs against the nominal model's (correlation {rho:.3f}) as if the torque were reversed; a "
                                    "positive torque turns the hub to positive angles")
        _check_units(model, data)
        return
    low = data.f < 0.5 * first
    if not np.any(low):
        return
    G = data.magnitude * np.exp(1j * np.deg2rad(data.phase_deg))
    Gm = np.asarray(model)[low]
    agreement = np.real(G[low] * np.conj(Gm)) / np.maximum(np.abs(G[low]) * np.abs(Gm), 1e-300)  # cos of the phase difference
    if np.mean(agreement < -0.5) > 0.8:  # more than 120 degrees apart at most of them
        raise SettingsError("data", "the response's sign flipped?", f"a response with the model's sign conventions: below half the "
                            f"first mode ({first:.3g} Hz), where the link turns as a rigid body, its phase is 180 degrees off the "
                            f"model's at {int(np.sum(agreement < -0.5))} of {int(np.sum(low))} points (a reversed torque or sensor)")


#: A channel this many times the nominal model's (within UNIT_TOLERANCE of it, the shapes alike) is in other units: the
#: hub angle in degrees, the tip in millimetres (a record in them ran past 150 CPU-s before a refusal that never named it).
UNIT_FACTORS = {"theta": (180.0 / math.pi, "degrees", "radians"), "y": (1000.0, "millimetres", "metres")}
UNIT_TOLERANCE = 2.0
#: ... and its shape alike the prediction's (their correlation above this): a bench's doublet, its hub angle through an
#: encoder and 0.5 ms late, correlates 0.80 with the nominal model's (the rod's record in degrees went on to a 41 s fit and
#: "distinct minima" at 0.9); a scale 57 times off the nominal model with a shape alike is not a stiffer or heavier link.
UNIT_SHAPE = 0.5


def _check_units(model: Any, data: TimeSeries) -> None:
    """Refuse a record whose hub angle or tip is a unit factor off the nominal model's: the least-squares scale of the
    measured channel on the predicted one within :data:`UNIT_TOLERANCE` of a factor of :data:`UNIT_FACTORS`, with the
    shapes alike (correlation above :data:`UNIT_SHAPE`); the nominal parameters are not 57 times off."""
    for name, predicted_channel, measured in (("theta", model[0], data.theta), ("y", model[1], data.y)):
        if measured is None:
            continue
        prediction = np.asarray(predicted_channel, dtype=float)
        power = float(prediction @ prediction)
        if power <= 0 or np.ptp(measured) <= 0:
            continue
        scale = float(prediction @ measured) / power
        factor, unit, wanted = UNIT_FACTORS[name]
        if 1 / UNIT_TOLERANCE <= scale / factor <= UNIT_TOLERANCE and float(np.corrcoef(prediction, measured)[0, 1]) > UNIT_SHAPE:
            raise SettingsError(f"data: {name}", f"{scale:.3g} x the nominal model's", f"a record in the model's units: {name} "
                                f"is {scale:.3g} x what the nominal model predicts, as if it were in {unit}; sflm fit takes "
                                f"{wanted} (divide the column by {factor:.6g})")


def _jacobian(geometry: Geometry, data: Data, keys: Sequence[str], x: FloatArray, step: float = 1e-6) -> FloatArray:
    base = _residuals(_with(geometry, keys, np.exp(x)), data)
    columns = []
    for i in range(len(keys)):
        shifted = x.copy()
        shifted[i] += step
        columns.append((_residuals(_with(geometry, keys, np.exp(shifted)), data) - base) / step)
    return np.stack(columns, axis=1)


def _known_sigma(data: Data) -> FloatArray | None:
    """The residuals' standard deviations where the data states them (a frequency list's ``uncertainty_hz``), else
    ``None`` (estimated from the residuals)."""
    if isinstance(data, FrequencyData) and data.uncertainty_hz is not None:
        return data.uncertainty_hz / data.frequencies_hz
    return None


def _separable(geometry: Geometry, data: Data, keys: list[str], asked: bool,
               noise: float | None = None) -> tuple[list[str], dict[str, str], dict[str, float]]:
    """The parameters the data can tell apart, and those held (with why).

    A column of the Jacobian at the nominal values that is zero is held. Where the data's noise is known (stated, or
    read from the data by :mod:`modelgen.record`: ``noise``, :func:`_data_noise`'s), a parameter whose predicted 95 % interval at the nominal values is
    wider than its value (:data:`SENSITIVITY`) is held, the least determined first; otherwise one correlated beyond
    :data:`INSEPARABLE` with one kept before it. Correlation alone is no reason where the noise is known: a fit of
    correlated parameters has wide intervals, one held at a wrong nominal value bends the others.
    """
    J = _jacobian(geometry, data, keys, np.zeros(len(keys)))
    norms = np.linalg.norm(J, axis=0)
    sigma = _known_sigma(data)
    if sigma is None and noise is not None and math.isfinite(noise):
        sigma = np.full(J.shape[0], max(noise, NOISE_FLOOR))
    kept: list[str] = []
    held: dict[str, str] = {}
    correlations: dict[str, float] = {}
    scale = float(norms.max()) if norms.size else 0.0
    for i, key in enumerate(keys):
        if norms[i] <= 1e-9 * max(scale, 1e-300):
            held[key] = "the data does not depend on it"
            continue
        for other in kept:
            j = keys.index(other)
            rho = float(abs(J[:, i] @ J[:, j]) / (norms[i] * norms[j]))
            correlations[f"{key}~{other}"] = rho
            if rho > INSEPARABLE and sigma is None:
                held[key] = f"cannot be separated from {other} by this data (correlation {rho:.6f})"
                break
        else:
            kept.append(key)
    # an interval needs more residuals than parameters (one to estimate the noise), or as many where the data states
    # its uncertainty; where the noise is known, a parameter it hides is held. Chosen forward: each step adds the
    # candidate that keeps the widest predicted interval of the set narrowest
    most = J.shape[0] if _known_sigma(data) is not None else J.shape[0] - 1
    weighted = J / (1.0 if sigma is None else sigma[:, None])

    def widest(chosen: list[str]) -> float:
        """The widest predicted 95 % half-width (in ``x``) of a set."""
        columns = weighted[:, [keys.index(k) for k in chosen]]
        try:
            return float(1.96 * np.sqrt(np.clip(np.diag(np.linalg.inv(columns.T @ columns)), 0.0, None)).max())
        except np.linalg.LinAlgError:
            return math.inf

    chosen: list[str] = []
    candidates = list(kept)
    while candidates and len(chosen) < most:
        scores = [widest(chosen + [k]) for k in candidates]
        best = int(np.argmin(scores))
        if sigma is not None and not scores[best] <= SENSITIVITY:
            break
        chosen.append(candidates.pop(best))
    for key in candidates:
        if len(chosen) >= most:
            held[key] = f"more parameters than the data's {J.shape[0]} points allow (the least determined held)"
        else:
            half = widest(chosen + [key])
            held[key] = f"the data's noise hides it (its interval would be {interval_text(half)} at the nominal values)"
    kept = [k for k in keys if k in chosen]
    if asked and held:
        key = next(iter(held))
        raise FitError(f"{key} {held[key]}: list fewer parameters (--params), hold one at its nominal value, or add data that "
                       "tells them apart (a frequency response or a time series besides the frequencies)")
    return kept, held, correlations


def _least_squares(residuals: Any, lower: FloatArray, upper: FloatArray, start: FloatArray, iterations: int | None = None) -> Any:
    """:func:`scipy.optimize.least_squares` from ``start`` within the physical bounds (at most ``iterations``, default
    ``200 p``); a trial value the model refuses is the optimiser's excursion, named as such (never the user's file)."""
    import scipy.optimize as so

    try:
        return so.least_squares(residuals, np.clip(start, lower + 1e-9, upper - 1e-9), method="trf", x_scale=1.0,
                                max_nfev=iterations or 200 * lower.size, bounds=(lower, upper))
    except GeometryError as exc:  # a trial value of the optimiser's, not the user's file
        raise FitError(f"the fit failed: the optimiser tried {exc.key} = {exc.value!r} ({exc.accepted}), beyond what the model "
                       "takes: the data pushes that parameter out of its physical range; fix it (--params without it) or add data "
                       "that sees it") from None
    except (ValueError, np.linalg.LinAlgError, SflmError) as exc:
        raise FitError(f"the fit failed: {exc}") from None


def _at_bounds(geometry: Geometry, keys: list[str], x: FloatArray, lower: FloatArray, upper: FloatArray) -> None:
    """Refuse a solution with a parameter at its bound (within :data:`AT_BOUND`): the data does not determine it."""
    pinned = [k for k, xi, lo, hi in zip(keys, x, lower, upper) if min(xi - lo, hi - xi) < AT_BOUND]
    if pinned:
        key = pinned[0]
        value = parameter_value(_with(geometry, keys, np.exp(x)), key)
        exc = FitError(f"the fit ran {key} to its bound ({value:.4g}, {np.exp(x[keys.index(key)]):.3g} x the nominal "
                       f"value): the data does not determine it within physical values; hold it (--params without it) or add "
                       "data that sees it")
        exc.parameter, exc.why = key, f"it ran to its bound, {value:.4g}"  # type: ignore[attr-defined]
        raise exc


def _physical_bounds(geometry: Geometry, keys: Sequence[str]) -> tuple[FloatArray, FloatArray]:
    """The optimiser's bounds on ``log(value / nominal)``: a factor in [1e-3, 1e3], and a damping ratio below
    :data:`MAX_DAMPING_RATIO` (the geometry takes [0, 1))."""
    lower, upper = np.full(len(keys), math.log(1e-3)), np.full(len(keys), math.log(1e3))
    for i, key in enumerate(keys):
        if key == "damping.ratio" or modal_mode(key) is not None:
            upper[i] = min(upper[i], math.log(MAX_DAMPING_RATIO / parameter_value(geometry, key)))
    return lower, upper


def held_spreads(spec: str) -> dict[str, float]:
    """The held parameters' plausible errors a user states.

    ``sflm fit --held-spread``'s list: each held parameter's plausible error, relative, 95 %.

    Parameters
    ----------
    spec : str
        ``KEY=R[,KEY=R...]``, e.g. ``payload.mass=2%,hub.inertia=10%`` (``0`` for a value known exactly).

    Raises
    ------
    SettingsError
        For an unknown key, a value out of ``[0, MAX_HELD_SPREAD)``, a key given twice.
    """
    return dict(relative_values(spec, "--held-spread", f"a relative spread >= 0 and below {100 * MAX_HELD_SPREAD:g} % (95 %: how far "
                                "the file's value may be from the link's)", 0.0, MAX_HELD_SPREAD, zero=True))


def fit(geometry: Geometry, data: Data, params: Sequence[str] | None = None, data_hash: str | None = None,
        held_spread: dict[str, float] | None = None) -> Fit:
    """Fit ``params`` of ``geometry`` to ``data`` (module docstring).

    Parameters
    ----------
    geometry : Geometry
        The nominal link (its ``modes`` are the model's; the fit takes more where the data's band or the estimates'
        convergence asks for them).
    data : FrequencyData, FrequencyResponse or TimeSeries
        The measurement (:func:`read_data`).
    params : sequence of str, optional
        Dotted names (:data:`modelgen.geometry.PARAMETER_KEYS`, and ``damping.modal_K``: mode ``K``'s ratio where the
        geometry has modal damping). Default :data:`DEFAULT_PARAMETERS`, less those zero in the geometry and those the
        data cannot see or separate (held and named). Given explicitly, each must be non-zero and separable, or the fit
        is refused.
    data_hash : str, optional
        The data file's SHA-256 (recorded in the calibration).
    held_spread : dict, optional
        The plausible error (relative, 95 %) of parameters held at their nominal values, by dotted name: ``0`` for a value
        known exactly. Every parameter held (by the data, or not among ``params`` of the default set) whose spread is not
        given is assumed within :data:`HELD_SPREAD`; each one's part enters the fitted intervals (:class:`Fit`'s
        ``held_intervals``) and the report says which were assumed. A parameter given here and fitted is fitted.

    Returns
    -------
    Fit

    Raises
    ------
    SettingsError
        For an unknown or zero parameter, or data the model cannot be fitted to.
    FitError
        When the fit gives no model (module docstring), with its figures.
    """
    from .modes import roots_not_kept
    from .threads import one_thread

    stated = dict(held_spread or {})
    for key, value in stated.items():
        if not is_parameter_key(key):
            raise SettingsError("held_spread key", key, "one of " + ", ".join(PARAMETER_KEYS) + ", or damping.modal_K")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value < MAX_HELD_SPREAD:
            raise SettingsError(f"held_spread {key}", value, f"a relative spread >= 0 and below {MAX_HELD_SPREAD:g}")
    # the fit's products are small: a pool of BLAS threads only spins on them (2.5 x on two cores); its thousand trial
    # links' roots are not kept in the model cache (a file each, never read again)
    with one_thread(), roots_not_kept():
        return _fit(geometry, data, params, data_hash, stated)


def _fit(geometry: Geometry, data: Data, params: Sequence[str] | None, data_hash: str | None,
         stated: dict[str, float]) -> Fit:
    """:func:`fit`, its BLAS on one thread."""
    asked = params is not None
    keys = list(DEFAULT_PARAMETERS if params is None else params)
    inside = _band_modes(geometry, data)  # the nominal modes the data tells of (read once: a model and its eigenvalues)
    if not asked and geometry.modal_damping:  # a ratio per mode the data's band reaches, for Rayleigh's one
        keys = [k for k in keys if k != "damping.ratio"] + [f"damping.modal_{k}" for k in range(1, inside + 1)]
    for key in keys:
        if not is_parameter_key(key):
            raise SettingsError("params", key, "dotted names among " + ", ".join(PARAMETER_KEYS) + f", or damping.modal_K (mode K's "
                                f"damping ratio, K in 1..{MAX_MODES}, for a geometry with [damping] modal)")
        if key not in PARAMETER_KEYS and not geometry.modal_damping:
            raise SettingsError("params", key, "damping.ratio for this geometry's Rayleigh damping (damping.modal_K needs "
                                "[damping] modal = [...] in the geometry)")
        if key == "damping.ratio" and geometry.modal_damping:
            raise SettingsError("params", key, "damping.modal_K for this geometry's modal damping (a ratio per mode)")
    if len(set(keys)) != len(keys) or not keys:
        raise SettingsError("params", ",".join(keys), "at least one name, each once")
    held: dict[str, str] = {}
    for key in list(keys):
        if parameter_value(geometry, key) == 0.0:
            if asked:
                raise SettingsError("params", key, f"a parameter that is not zero in {geometry.name}'s geometry (a factor "
                                    "on zero is zero: give it a nominal value first)")
            held[key] = "zero in the geometry"
            keys.remove(key)
    _check_data(geometry, data)
    model, notes = _modes_for(geometry, data, inside)
    noise = _data_noise(data)  # read once: the choice of parameters and the judgement of the fit both weigh it
    keys, inseparable, correlations = _separable(model, data, keys, asked, noise)
    held.update(inseparable)
    if not keys:
        raise FitError(f"nothing to fit: {'; '.join(f'{k}: {why}' for k, why in held.items())}")
    # the default set not listed, and what the user states a spread for, are held too: their errors bend the fitted ones
    others = list(DEFAULT_PARAMETERS) if not geometry.modal_damping else (
        [k for k in DEFAULT_PARAMETERS if k != "damping.ratio"] + [f"damping.modal_{k}" for k in range(1, inside + 1)])
    for key in others + list(stated):
        if key not in keys and key not in held and parameter_value(geometry, key) != 0.0:
            held[key] = "not among --params" if key in others else "held at its nominal value, its spread stated"
    while True:  # a default parameter this data does not determine is held and named, never the reason of a refusal
        try:
            return _calibrated(geometry, model, data, keys, held, correlations, data_hash, notes, noise, stated)
        except FitError as exc:
            key = getattr(exc, "parameter", None)
            if asked or key is None or len(keys) <= 1:
                raise
            held[key] = f"not determined by this data ({exc.why})"  # type: ignore[attr-defined]
            keys = [k for k in keys if k != key]


def _modes_for(geometry: Geometry, data: Data, inside: int) -> tuple[Geometry, list[str]]:
    """The model the fit starts with: the geometry's modes, or one more than the ``inside`` nominal modes in the data's
    band (:func:`_band_modes`), and why."""
    n = geometry.modes
    band = _band_words(data)
    first = min(MAX_MODES - MORE_MODES, max(n, inside + 1))
    if first <= n:
        return geometry, []
    return geometry.with_model(first), [f"fitted with {first} modes, not the model's {n}: {band} reaches {inside} of its modes"]


def _band_top(data: Data) -> float:
    """The highest frequency (Hz) a response or a record tells of: its last, or its torque's band (at most Nyquist)."""
    from .record import torque_band

    if isinstance(data, FrequencyResponse):
        return float(data.f[-1])
    assert isinstance(data, TimeSeries)
    return min(torque_band(data.t, data.tau), 0.5 / float(data.t[1] - data.t[0]))


def _band_words(data: Data) -> str:
    """The data's band, in words."""
    if isinstance(data, FrequencyData):
        return "its frequencies"
    whose = "its" if isinstance(data, FrequencyResponse) else "its torque's"
    return f"{whose} band (to {_band_top(data):.4g} Hz)"


def _band_modes(geometry: Geometry, data: Data) -> int:
    """How many of the nominal model's flexible modes the data tells of (frequencies: as many as measured)."""
    if isinstance(data, FrequencyData):
        return int(data.frequencies_hz.size)
    nominal = _model_frequencies(geometry.with_model(min(MAX_MODES, max(geometry.modes, 8))), "hub-free")
    return int(np.sum(nominal <= _band_top(data)))


@dataclass(frozen=True)
class _Solution:
    """One least-squares solution in ``x = log(value / nominal)``, its covariance (noise, widened) and judgement."""

    x: FloatArray
    cov: FloatArray
    quantile: float
    rms: float
    nominal_rms: float
    points: int
    evaluations: int
    lag: float
    widening: float
    starts: int

    def half(self) -> FloatArray:
        """The noise part of the 95 % half-widths in ``x``."""
        return self.quantile * np.sqrt(np.clip(np.diag(self.cov), 0.0, None))


def _starts(count: int) -> list[FloatArray]:
    """Where the optimiser starts: the nominal values, then :data:`STARTS` - 1 Sobol points with each factor within
    ``[1/SPREAD, SPREAD]`` (seeded: the same data gives the same answer). A record adds where its spectrum points
    (:func:`_spectrum_start`), second."""
    from scipy.stats import qmc

    points = qmc.Sobol(count, scramble=True, seed=STARTS).random(STARTS)[: STARTS - 1]
    return [np.zeros(count)] + [math.log(SPREAD) * (2 * p - 1) for p in points]


def _solve(geometry: Geometry, data: Data, keys: list[str], starts: list[FloatArray]) -> _Solution:
    """The least-squares solution of ``keys`` from each start, the best judged (module docstring); distinct minima that
    fit the data as well are a refusal naming them."""
    import scipy.stats as st

    nominal_r = _residuals(geometry, data)
    sigma = _known_sigma(data)
    weights = 1.0 if sigma is None else 1.0 / sigma  # a stated uncertainty weighs each residual by it
    evaluations = 0

    def residuals(x: FloatArray) -> FloatArray:
        nonlocal evaluations
        evaluations += 1
        return _residuals(_with(geometry, keys, np.exp(x)), data) * weights

    lower, upper = _physical_bounds(geometry, keys)
    # a few iterations from each start (one start: to its minimum); those that come near the best are finished
    trials = [_least_squares(residuals, lower, upper, start, PROBE if len(starts) > 1 else None) for start in starts]
    lowest = min(float(t.cost) for t in trials)
    solutions = [t if t.status != 0 or float(t.cost) > PROMISING * lowest else _least_squares(residuals, lower, upper, t.x)
                 for t in trials]
    converged = [s for s in solutions if s.status > 0]
    best = min(converged or solutions, key=lambda s: float(s.cost))
    r = best.fun / weights  # the relative residuals themselves
    m, p = r.size, len(keys)
    rms = float(np.sqrt(np.mean(r**2)))
    nominal_rms = float(np.sqrt(np.mean(nominal_r**2)))
    if not converged:
        raise FitError(f"the fit did not converge ({best.message}) after {evaluations} evaluations: residual {rms:.3g}, "
                       f"nominal {nominal_rms:.3g}")
    noise = _data_noise(data) if isinstance(data, TimeSeries) else None
    explained = noise is not None and math.isfinite(noise) and rms <= MAX_NOISE_RATIO * max(noise, NOISE_FLOOR)
    if sigma is None and rms > MAX_RELATIVE_RESIDUAL and not explained:  # a record's own noise (a coarse encoder) may
        # explain a residual above 5 %; data with a stated uncertainty is judged by it (below)
        raise FitError(f"the fitted model cannot reproduce the data: relative RMS residual {rms:.3g} (nominal {nominal_rms:.3g}; "
                       f"a calibration needs at most {MAX_RELATIVE_RESIDUAL:g}): more modes (--modes), other parameters "
                       f"(--params), or data of this link{_ROUGH if isinstance(data, FrequencyData) else ''}")
    _at_bounds(geometry, keys, best.x, lower, upper)
    J = _jacobian(geometry, data, keys, best.x)
    lag, widening = 0.0, 1.0
    if sigma is not None:  # the stated uncertainty: weighted, a normal quantile
        chi = float(np.sqrt(np.mean((r / sigma) ** 2)))
        if m > p and chi > MAX_STATED_RATIO:
            raise FitError(f"the fitted model leaves the data {chi:.3g} x its stated uncertainty (RMS; at most "
                           f"{MAX_STATED_RATIO:g} is accepted): more modes (--modes), other parameters (--params), or a larger "
                           "uncertainty_hz if the readings are rougher than stated")
        information, variance, quantile = (J / sigma[:, None]).T @ (J / sigma[:, None]), 1.0, float(st.norm.ppf(0.975))
        worse = 0.5 * float(st.chi2.ppf(0.95, p))  # the cost (half the weighted squares) a 95 % region allows above the best
    else:
        if m <= p:
            raise FitError(f"{m} residuals for {p} parameters: no interval can be estimated (give more data or fewer --params)")
        from .record import correlation_time, lag_one

        lag, widening = lag_one(r, _segments(data, m))
        information, variance, quantile = J.T @ J, float(r @ r) / (m - p), float(st.t.ppf(0.975, m - p))
        if isinstance(data, TimeSeries) and m > data.t.size:
            # channels of their own noise and correlation (a coarse encoder's angle holds a level for many samples, a tip
            # sensor's noise is white): each channel's information by its own variance and lag-one widening
            information, variance, n = np.zeros((p, p)), 1.0, data.t.size
            lags = []
            measured = [data.theta] + ([] if data.y is None else [data.y])
            for c in range(m // n):
                rc, Jc = r[c * n:(c + 1) * n], J[c * n:(c + 1) * n]
                rho, wide = lag_one(rc, [n])
                if _held_run(measured[c]) > 1.0:  # a rounding error held over runs: correlated beyond lag one
                    wide = max(wide, math.sqrt(correlation_time(rc)))
                lags.append((wide, rho))
                information += Jc.T @ Jc / (float(rc @ rc) / (n - p / (m // n)) * wide**2)
            widening, lag = max(lags)
            widening = 1.0 if widening < 1.0 else widening
            information = information * widening**2  # cov below multiplies by widening^2: the widest channel's, reported
        worse = float(best.cost) * p / (m - p) * float(st.f.ppf(0.95, p, m - p))
    try:
        cov = variance * widening**2 * np.linalg.inv(information)
    except np.linalg.LinAlgError:
        raise FitError("the fit's Jacobian is singular at the solution: the parameters are not determined by this data") from None
    solution = _Solution(best.x, cov, quantile, rms, nominal_rms, m, evaluations, lag, widening, len(starts))
    rivals = [s for s in converged if float(s.cost) - float(best.cost) <= worse and _apart(s.x, best.x, solution.half())
              and min(np.min(s.x - lower), np.min(upper - s.x)) >= AT_BOUND]
    if rivals:
        _refuse_rivals(geometry, keys, best, rivals, weights)
    return solution


#: The evaluations a parameter the fit of a record's resonances (:func:`_spectrum_start`) may spend.
SPECTRUM_EVALUATIONS = 20


def _spectrum_start(geometry: Geometry, data: Data, keys: list[str]) -> FloatArray | None:
    """Where the record's own spectrum points: the parameters its resonances (:func:`modelgen.record.resonances`) can
    tell, fitted to them as frequencies read to the record's resolution; ``None`` where it shows none (or for a record
    in closed loop or with dry friction, whose spectrum is not the link's), or where that fit does not settle within
    :data:`SPECTRUM_EVALUATIONS` a parameter: its resonances then point nowhere in particular (measured: the records
    this start is for are matched in 4-5 evaluations, to 1e-21; a bench doublet's three peaks ran the old limit of 600
    to EI x 0.06 and the payload x 0.001, 5.2 s of an 11.7 s fit, a start whose probe came out far worse than the
    nominal one's)."""
    if not isinstance(data, TimeSeries) or data.reference is not None or geometry.hub_coulomb_friction:
        return None
    from .record import resonances

    peaks = resonances(data.t, data.tau, data.theta)[: max(geometry.modes - 1, 1)]
    if peaks.size == 0:
        return None
    heard = FrequencyData(peaks, "hub-free", 1.0 / float(data.t[-1] - data.t[0]))
    try:
        chosen, _, _ = _separable(geometry, heard, keys, False)
        if not chosen:
            return None
        lower, upper = _physical_bounds(geometry, chosen)
        solution = _least_squares(lambda x: _residuals(_with(geometry, chosen, np.exp(x)), heard), lower, upper,
                                  np.zeros(len(chosen)), SPECTRUM_EVALUATIONS * len(chosen))
    except (SflmError, ValueError, np.linalg.LinAlgError):
        return None
    if not solution.success:  # (the evaluations spent: SciPy's status 0)
        return None
    start = np.zeros(len(keys))
    start[[keys.index(k) for k in chosen]] = solution.x
    return start


def _segments(data: Data, m: int) -> list[int]:
    """The ordered runs of the residuals (no lag crosses from one to the next)."""
    if isinstance(data, FrequencyResponse):
        return [m // 2, m // 2]
    if isinstance(data, TimeSeries):
        return [data.t.size] * (m // data.t.size)
    return [m]


#: Two minima are one point where every parameter agrees to this (relative: the fit's unknowns are logarithms).
DISTINCT = 1e-6


def _apart(x: FloatArray, best: FloatArray, half: FloatArray) -> bool:
    """Whether a minimum at ``x`` is another point than ``best``: beyond the intervals' half-widths and :data:`DISTINCT`
    (exact data's intervals are 1e-14 wide, and two starts' minima of one point differ by more: issue 60, item 9b)."""
    return bool(np.any(np.abs(x - best) > np.maximum(half, DISTINCT)))


def _refuse_rivals(geometry: Geometry, keys: list[str], best: Any, rivals: list[Any], weights: Any) -> None:
    """Refuse the fit: minima with other values fit the data as well as the best one (figures of each)."""

    def described(s: Any) -> str:
        values = _with(geometry, keys, np.exp(s.x))
        rms = float(np.sqrt(np.mean((s.fun / weights) ** 2)))
        return ", ".join(f"{k} = {parameter_value(values, k):.4g}" for k in keys) + f" (residual {rms:.3g})"

    listed = "; ".join(described(s) for s in [best, *sorted(rivals, key=lambda s: float(s.cost))[:2]])
    exc = FitError(f"distinct minima fit this data equally well: {listed}; the data does not tell which is the link: add data "
                   "that separates them (a frequency response, a longer or richer record), or fit fewer --params")
    exc.minima = [best.x, *[s.x for s in rivals]]  # type: ignore[attr-defined]
    raise exc


def _data_noise(data: Data) -> float | None:
    """The relative noise the data shows by itself (:mod:`modelgen.record`), on the scale of :func:`_residuals`; ``None``
    for frequencies (they state theirs, or the fit estimates it)."""
    from .record import response_noise

    if isinstance(data, FrequencyResponse):
        return response_noise(data.magnitude * np.exp(1j * np.deg2rad(data.phase_deg)))
    if isinstance(data, TimeSeries):  # the weighted residuals' (the scale of _residuals)
        levels = [w * _channel_noise(c) for w, c in zip(_channel_weights(data), [data.theta] + ([] if data.y is None else [data.y]))]
        return float(np.sqrt(np.mean(np.square(levels))))
    return None


def _more_modes(model: Geometry, data: Data, keys: list[str], base: _Solution) -> tuple[_Solution, int, bool]:
    """Fit again with one mode more, from the last solution, until no estimate moves by more than :data:`CONVERGED` of
    its noise interval (at most :data:`MORE_MODES` more): the last solution, its modes and whether they converged."""
    current, n = base, model.modes
    while n < min(model.modes + MORE_MODES, MAX_MODES):  # never beyond what the model takes (and the user never asked)
        n += 1
        following = _solve(model.with_model(n), data, keys, [current.x])
        change = np.abs(following.x - current.x)
        current = replace(following, evaluations=current.evaluations + following.evaluations, starts=current.starts)
        if np.all(change <= CONVERGED * current.half()):
            return current, n, True
    return current, n, False


def _held_part(model: Geometry, data: Data, keys: list[str], x: FloatArray, spreads: dict[str, float]) -> FloatArray:
    """What the held parameters' plausible errors move the fitted ones by: ``(p, h)`` 95 % half-widths in ``x``.

    To first order, a held parameter ``h`` off by ``dx_h`` (in ``log(value / nominal)``) moves the least-squares
    solution by ``S dx_h``, ``S = -(J_f^T W J_f)^-1 J_f^T W J_h`` -- the fit's own weights ``W`` -- so its spread
    ``log(1 + R_h)`` (95 %) moves each fitted parameter by ``|S| log(1 + R_h)`` (95 %)."""
    held = list(spreads)
    if not held:
        return np.zeros((len(keys), 0))
    J = _jacobian(model, data, keys + held, np.concatenate([x, np.zeros(len(held))]))
    sigma = _known_sigma(data)
    if sigma is not None:
        J = J / sigma[:, None]
    S = -np.linalg.lstsq(J[:, : len(keys)], J[:, len(keys):], rcond=None)[0]
    return np.abs(S) * np.log1p(np.array([spreads[k] for k in held]))[None, :]


def _intervals(geometry: Geometry, model: Geometry, data: Data, keys: list[str], held: dict[str, str],
               stated: dict[str, float], x: FloatArray, values: dict[str, float], noise_part: dict[str, float],
               model_part: dict[str, float], notes: list[str]) -> tuple[dict[str, float], dict[str, float], dict[str, float]]:
    """Each fitted parameter's held part (:func:`_held_part`; the held ones' spreads: ``stated``, else
    :data:`HELD_SPREAD`) and its interval, the three parts' root sum of squares; a note per held parameter that moves
    one; an interval wider than its value refused (naming the held parameter where its part is the most of it).

    Returns
    -------
    held_part, intervals, spreads : dict
    """
    spreads = {k: stated.get(k, HELD_SPREAD) for k in held  # (a factor on zero is zero; what the data does not see moves nothing)
               if parameter_value(geometry, k) != 0.0 and held[k] != "the data does not depend on it"}
    moved = _held_part(model, data, keys, x, spreads)  # (fitted, held), in x
    held_part = {k: values[k] * float(np.sqrt(np.sum(moved[i] ** 2))) for i, k in enumerate(keys)}
    intervals = {k: float(np.sqrt(noise_part[k] ** 2 + model_part[k] ** 2 + held_part[k] ** 2)) for k in keys}
    wide = [k for k in keys if intervals[k] > abs(values[k])]
    if wide:
        k = wide[0]
        i = keys.index(k)
        if moved.shape[1] and held_part[k] > math.hypot(noise_part[k], model_part[k]):  # the held ones' doing, not the data's
            h = list(spreads)[int(np.argmax(moved[i]))]
            raise FitError(f"the interval of {k} ({values[k]:.4g} +- {intervals[k]:.3g}) is wider than its value, mostly from {h} "
                           f"held at its nominal value ({'assumed' if h not in stated else 'stated'} within "
                           f"{100 * spreads[h]:.3g} %, {k} within {100 * float(moved[i].max()):.3g} % with it): fit {h} "
                           f"too (--params), state its spread if it is known better (--held-spread {h}=R%), or give data that sees it")
        exc = FitError(f"the interval of {k} ({values[k]:.4g} +- {intervals[k]:.3g}) is wider than its value: this data does "
                       "not determine it (fit fewer --params, or give more data)")
        exc.parameter, exc.why = k, f"{values[k]:.4g} +- {intervals[k]:.3g}, an interval wider than its value"  # type: ignore[attr-defined]
        raise exc
    for j, h in enumerate(spreads):
        if not moved[:, j].any():
            continue
        i = int(np.argmax(moved[:, j] * np.array([abs(values[k]) for k in keys])))
        k = keys[i]
        notes.append(f"{h} held at its nominal value, {'assumed' if h not in stated else 'stated'} within {100 * spreads[h]:.3g} % "
                     f"of the link's (95 %{'; an assumption: --held-spread states it' if h not in stated else ''}): its part in "
                     f"{k}'s interval {values[k] * float(moved[i, j]):.3g} (the interval +- {intervals[k]:.3g}, without the held "
                     f"parameters' parts +- {math.hypot(noise_part[k], model_part[k]):.3g})")
    return held_part, intervals, spreads


def _bench_artefacts(fitted: Geometry, data: Data, base: "_Solution", notes: list[str]) -> tuple[dict[str, dict[str, float]], dict[str, dict[str, float]]]:
    """The measurement's artefacts fitted beside the link (a record's delays, offsets and drifts; a response's delay),
    each in a note, and a record's residual tests (:func:`_residual_tests`; one beyond :data:`INPUT_CORRELATION` is a
    refusal naming its lag and what it points to).

    Returns
    -------
    artefacts, tests : dict
    """
    artefacts: dict[str, dict[str, float]] = {}
    tests: dict[str, dict[str, float]] = {}
    if isinstance(data, FrequencyResponse):
        artefacts = _response_artefacts(fitted, data, base.quantile, base.widening)
        a = artefacts[data.output]
        notes.append(f"the response read {1e3 * a['delay']:.3g} ms late" + (" (as the data file states)" if a["delay_given"] else
                     f" +- {1e3 * a['delay_95']:.2g} ms (fitted with the link: the measurement's delay)"))
    if not isinstance(data, TimeSeries):
        return artefacts, tests
    artefacts = _artefacts(fitted, data, base.quantile)
    tests = _residual_tests(fitted, data)
    for name, test in tests.items():
        if test["z"] > INPUT_CORRELATION and test["rms"] > NOISE_FLOOR:  # (a residual below any instrument's noise,
            # an exact record's, is the arithmetic's: systematic, and no misfit)
            lag = test["at_lag_s"]
            where = (f"{1e3 * lag:.3g} ms later: the link does something the model lacks (the hub's dry friction, "
                     "hub.coulomb_friction; a mode above --modes; a delay beyond the 20 samples fitted; a part the "
                     "geometry lacks)") if lag >= 0 else (
                     f"{-1e3 * lag:.3g} ms earlier: the residual leads the torque (the torque recorded late against the "
                     "angles, or a loop closed around the record: its reference and gains, --kp, --kd)")
            raise FitError(f"the fitted model leaves {name}'s residual correlated with the torque {where}: correlation "
                           f"{test['input_correlation']:.3g}, {test['z']:.3g} x its standard deviation were the model right "
                           f"(at most {INPUT_CORRELATION:g} is chance); the values would absorb it -- no calibration")
    for name, a in artefacts.items():
        unit = "rad" if name == "theta" else "m"
        late = (f"{1e3 * a['delay']:.3g} ms late (as the data file states)" if a["delay_given"] else
                f"{1e3 * a['delay']:.3g} +- {1e3 * a['delay_95']:.2g} ms late")
        notes.append(f"{name} read {late}, from {a['offset']:.3g} +- "
                     f"{a['offset_95']:.2g} {unit}, drifting {a['drift']:.3g} +- {a['drift_95']:.2g} {unit}/s (fitted with the "
                     "link: the record's delay, offset and drift)")
    return artefacts, tests


def _calibrated(geometry: Geometry, model: Geometry, data: Data, keys: list[str], held: dict[str, str],
                correlations: dict[str, float], data_hash: str | None, notes: list[str], noise: float | None,
                stated: dict[str, float] | None = None) -> Fit:
    """:func:`fit`'s solve of ``keys`` on ``model`` (several starts), then with more modes, and its judgement (module
    docstring); a parameter the data does not determine raises a :class:`FitError` carrying it (``parameter``,
    ``why``)."""
    starts = _starts(len(keys))
    heard = _spectrum_start(model, data, keys)
    base = _solve(model, data, keys, starts if heard is None else [starts[0], heard, *starts[1:]])
    final, modes, converged = _more_modes(model, data, keys, base)
    change = np.abs(final.x - base.x)  # what the model's truncation moved each estimate by
    notes = list(notes)
    if noise is not None and math.isfinite(noise) and final.rms > MAX_NOISE_RATIO * max(noise, NOISE_FLOOR):
        raise FitError(f"the fitted model cannot reproduce the data: it leaves a relative RMS residual {final.rms:.3g}, "
                       f"{final.rms / max(noise, NOISE_FLOOR):.3g} x the noise the data shows by itself ({noise:.3g}; at most "
                       f"{MAX_NOISE_RATIO:g} x is a calibration): the link differs from the model in form (its damping, its "
                       "shapes, a part the geometry lacks), or the record holds more than its noise (a disturbance, a drift)")
    if base.widening > 1.0:  # the reported intervals are base's
        notes.append(f"intervals widened {base.widening:.3g} x: the residuals follow each other (lag-one correlation "
                     f"{base.lag:.3f}), fewer independent points than samples")
    if not converged and modes == model.modes:
        notes.append(f"the model's part of each interval is not checked: {modes} modes is the most the model takes "
                     f"({MAX_MODES}); with fewer --modes the fit checks it with more")
    elif not converged:
        notes.append(f"the estimates still moved from {modes - 1} to {modes} modes: the model's part of each interval may "
                     "be low")
    factors = np.exp(base.x)
    values = {k: parameter_value(geometry, k) * float(f) for k, f in zip(keys, factors)}
    noise_part = {k: values[k] * float(h) for k, h in zip(keys, base.half())}
    model_part = {k: values[k] * float(c) for k, c in zip(keys, change)}
    stated = stated or {}
    held_part, intervals, spreads = _intervals(geometry, model, data, keys, held, stated, base.x, values, noise_part,
                                               model_part, notes)
    artefacts, tests = _bench_artefacts(_with(model, keys, factors), data, base, notes)
    return Fit(_with(geometry, keys, factors), geometry, values, intervals, held, base.rms, base.nominal_rms, data_hash or "",
               data.kind, base.points, final.evaluations, correlations, modes=model.modes, noise_intervals=noise_part,
               model_intervals=model_part, noise=noise, lag_one=base.lag, widening=base.widening, starts=base.starts,
               converged=converged, notes=notes, checked_modes=modes, artefacts=artefacts, held_intervals=held_part,
               held_spread={k: {"relative_95": spreads[k], "assumed": k not in stated} for k in spreads}, residual_tests=tests)


def fit_file(geometry: Geometry, path: str | Path, params: Sequence[str] | None = None, output: str | None = None,
             law: tuple[float, float] | None = None, held_spread: dict[str, float] | None = None) -> Fit:
    """:func:`fit` to the data in ``path``, its hash recorded.

    :func:`fit` to the data in ``path`` (:func:`read_data`; ``law``: a closed-loop record's PD gains), its hash recorded.

    Parameters
    ----------
    geometry : Geometry
        The nominal geometry.
    path : str | Path
        The data file (:func:`read_data`).
    params : Sequence[str] | None, optional
        The geometry keys to fit (default: by the data's kind).
    output : str | None, optional
        As :func:`read_data`'s.
    law : tuple[float, float] | None, optional
        As :func:`read_data`'s.
    held_spread : dict, optional
        As :func:`fit`'s.
    """
    return fit(geometry, read_data(path, output, law), params, _hash(Path(path)), held_spread)


def calibrated_toml(result: Fit, data_name: str) -> str:
    """The calibrated geometry file, with a ``[calibration]`` table.

    The calibrated geometry file: every value of the geometry (the link as ``flexural_rigidity`` and
    ``linear_density``), the fitted ones replaced, and a ``[calibration]`` table recording the data, the residuals and
    each interval.

    Parameters
    ----------
    result : Fit
        The calibration.
    data_name : str
        The data file's name, recorded in the table.
    """
    g = result.geometry
    lines = [f"# Calibrated by sflm fit from {one_line(data_name)} ({result.kind}); the nominal file was {one_line(g.source)}.",
             f"name = {toml_string(g.name)}", "", "[link]", f"length = {g.length!r}", f"flexural_rigidity = {g.flexural_rigidity!r}",
             f"linear_density = {g.linear_density!r}", "", "[hub]", f"inertia = {g.hub_inertia!r}",
             f"viscous_damping = {g.hub_viscous_damping!r}", f"coulomb_friction = {g.hub_coulomb_friction!r}", "", "[payload]",
             f"mass = {g.payload_mass!r}", f"inertia = {g.payload_inertia!r}", "", "[damping]",
             f"modal = [{', '.join(repr(float(r)) for r in g.modal_damping)}]" if g.modal_damping else f"ratio = {g.damping_ratio!r}", "",
             "[model]", f"modes = {g.modes}", f"mode_shapes = {toml_string(g.mode_shapes)}", "", "[calibration]",
             f"data = {toml_string(data_name)}", f"data_sha256 = {toml_string(result.data_hash)}", f"kind = {toml_string(result.kind)}",
             f"residual = {result.residual!r}", f"nominal_residual = {result.nominal_residual!r}",
             f"modes_fitted = {result.modes or g.modes}", f"modes_checked = {result.checked_modes or g.modes}",
             f"converged = {'true' if result.converged else 'false'}", ""]
    for key, value in result.values.items():
        lines += [f"[calibration.parameters.{toml_string(key)}]", f"nominal = {parameter_value(result.nominal, key)!r}",
                  f"value = {value!r}", f"interval_95 = {result.intervals[key]!r}"]
        lines += [f"{name} = {part[key]!r}" for name, part in (("noise_95", result.noise_intervals), ("model_95", result.model_intervals),
                                                               ("held_95", result.held_intervals)) if key in part] + [""]
    for key, why in result.held.items():  # what the fitted values assume, and how far (assumed, or stated by the user)
        spread = result.held_spread.get(key)
        lines += [f"[calibration.held.{toml_string(key)}]", f"why = {toml_string(why)}"]
        lines += [] if spread is None else [f"spread_95 = {spread['relative_95']!r}", f"spread_assumed = {'true' if spread['assumed'] else 'false'}"]
        lines += [""]
    return "\n".join(lines)


def spread_of_calibration(path: str | Path) -> str:
    """The ``--uncertainty`` SPEC of a calibrated file's intervals.

    The ``--uncertainty`` SPEC a calibrated geometry file's intervals give: each fitted parameter's 95 % interval as
    a relative range (``link.flexural_rigidity=2.1%,...``).

    Parameters
    ----------
    path : str | Path
        A calibrated geometry file.

    Raises
    ------
    SettingsError
        For a file without a ``[calibration]`` table of parameters.
    """
    def refuse(why: str) -> SettingsError:
        return SettingsError("uncertainty", f"fit:{path}", f"a calibrated geometry file written by sflm fit --out ({why})")

    try:
        document = read_document(path, "toml")
    except (DocumentError, OSError) as exc:
        raise refuse(str(exc)) from None
    calibration = document.get("calibration")
    parameters = calibration.get("parameters") if isinstance(calibration, dict) else None
    if not isinstance(parameters, dict) or not parameters:
        raise refuse("this one has no [calibration.parameters] table")
    parts = []
    for key, fitted in parameters.items():
        where = f"[calibration.parameters.{toml_string(key)}]"
        if not is_parameter_key(key):
            raise refuse(f"{where} is not a parameter sflm fit calibrates")
        if not isinstance(fitted, dict):
            raise refuse(f"{where} is a {type(fitted).__name__}, not a table with value and interval_95")
        for name in ("value", "interval_95"):
            number = fitted.get(name)
            if isinstance(number, bool) or not isinstance(number, (int, float)) or not math.isfinite(number):
                raise refuse(f"{where} {name} = {str(number)[:40]!r}, not a finite number")
        value, interval = float(fitted["value"]), float(fitted["interval_95"])
        if value == 0 or interval < 0:
            raise refuse(f"{where} value = {value!r}, interval_95 = {interval!r}: expected a value other than 0 and an "
                         "interval >= 0")
        if key == "hub.coulomb_friction":
            continue  # the robust judgement's linear closed loop has no dry friction to perturb
        share = abs(interval / value)
        if not share < 1:
            raise refuse(f"{key}'s 95 % interval +-{interval:.6g} is {100 * share:.3g} % of its value {value:.6g}: the robust "
                         f"judgement takes a spread below 100 %; refit on a richer record, or give --uncertainty {key}=R% "
                         "yourself")
        parts.append(f"{key}={100 * share:.6g}%")
    if not parts:
        raise refuse("this one fitted the hub's dry friction only, which the robust judgement's linear closed loop does not "
                     "have")
    spec = ",".join(parts)
    return spec
