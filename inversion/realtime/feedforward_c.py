"""The feedforward for a real-time controller: self-contained C and lookup tables.

:func:`export_c` writes ``feedforward.c`` and ``feedforward.h``: C99 that needs no library
(not even libm), allocates nothing and evaluates, at any time ``t``, the signals the chosen member
feeds forward -- the torque ``tau_l`` of Eq. (12) and the joint references ``theta_d``,
``thetadot_d`` of a link, the input ``u`` of a generic system -- not a table of samples:

* the segment of ``t`` (binary search over the joints), the local time ``s = t - t_k``;
* the piece of the segment that holds ``s`` and ``x = (2 s - a - b)/(b - a)``;
* each signal's Chebyshev series there, by Clenshaw's recurrence.

The series are the member's closed form (Eq. (29), its integrals, the internal modes'
particular and complementary parts, Eq. (12)) re-expanded per segment in extended
precision (:mod:`inversion.signals.chebyshev`): evaluating the closed form itself in double
precision is uncertain by up to ``1e-9`` of the peak torque on members whose exponentials
are nearly dependent, the series by ``eps`` of the signal. The samples of ``inversion.csv``
evaluate the same series (by the Chebyshev recurrence and one product per piece; the C by
Clenshaw's recurrence), so the C returns them to rounding, and both are
within ``1e-12`` of the exact closed form (``tests/inversion/realtime/test_feedforward_c.py``; 2e-16 to 9e-13 measured). A stable
inversion (:mod:`inversion.methods.stable`) is exported the same way over its whole span, the
pre-actuation before ``t_0`` and the post-actuation after ``t_f`` included: its quadrature
and its decaying tails re-expanded on the pre-actuation, the manoeuvre's pieces and the
post-actuation.

:func:`export_table` writes the sampled signals as ``const double`` arrays instead.
"""

from __future__ import annotations

import hashlib
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Protocol

import numpy as np
from numpy.typing import NDArray

from modelgen.model import Model
from modelgen.quoting import c_comment

from ..config import DEFAULTS
from ..errors import SettingsError
from ..options import method_named
from ..lti.system import NormalForm
from ..signals.chebyshev import PiecewiseChebyshev
from ..signals.trajectory import Trajectory

__all__ = ["FeedforwardData", "FeedforwardSource", "feedforward_data", "rounding_bounds", "export_c", "export_table", "check_prefix",
           "DEFAULT_PREFIX", "comment_safe"]

#: Default prefix of the exported C symbols (``sflm_feedforward_eval``; :data:`inversion.config.DEFAULTS`).
DEFAULT_PREFIX = DEFAULTS.c_prefix


class FeedforwardSource(Protocol):
    """What an export reads of a result.

    What an export reads of a result (:class:`inversion.result.InversionResult` is one).
    """

    @property
    def t(self) -> NDArray[np.float64]: ...
    @property
    def tau(self) -> NDArray[np.float64]: ...
    @property
    def theta_d(self) -> NDArray[np.float64] | None: ...
    @property
    def thetadot_d(self) -> NDArray[np.float64] | None: ...
    @property
    def X(self) -> NDArray[np.float64]: ...
    @property
    def summary(self) -> Mapping[str, Any]: ...
    @property
    def model(self) -> Any: ...
    @property
    def trajectory(self) -> Trajectory: ...
    @property
    def signals(self) -> PiecewiseChebyshev | None: ...
    @property
    def redefinition(self) -> Any: ...  # a family member's inversion.family.redefinition.Redefinition, or None
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,62}")


@dataclass(frozen=True)
class FeedforwardData:
    """What :func:`export_c` writes.

    What :func:`export_c` writes: the member's signals as piecewise Chebyshev series, and their values outside the span.

    Attributes
    ----------
    names : tuple of str
        ``tau, theta_d, thetadot_d`` (a link) or ``u`` (a generic system).
    signals : PiecewiseChebyshev
        The series (:mod:`inversion.signals.chebyshev`).
    initial, final : ndarray, shape (S,)
        The signals before ``t_0`` and after ``t_f``: for a link ``tau = 0`` with the
        joint's initial angle and rate, then ``0, y_d(t_f)/x_out, 0``; for a generic system
        the input that holds the output at ``y_d(t_0)``, then at ``y_d(t_f)`` (``y / G(0)``).
    """

    names: tuple[str, ...]
    signals: PiecewiseChebyshev
    initial: NDArray[np.float64]
    final: NDArray[np.float64]

    def digest(self) -> str:
        """SHA-256 of every number (names the feedforward in the header)."""
        h = hashlib.sha256()
        for value in (self.signals.bounds, self.signals.piece_start, self.signals.edges, self.signals.coefficients,
                      self.initial, self.final):
            h.update(np.ascontiguousarray(value).tobytes())
        return h.hexdigest()


def feedforward_data(result: FeedforwardSource) -> FeedforwardData:
    """The numbers :func:`export_c` writes, from a result's member.

    Parameters
    ----------
    result : FeedforwardSource
        A result with a closed form.

    Raises
    ------
    SettingsError
        For a result without a closed form (a polynomial inversion).
    """
    signals = result.signals
    if signals is None:
        raise SettingsError("result", f"a {result.summary.get('method', 'polynomial')} inversion without its series",
                            "a result with its signals' series, which the C evaluates; export_table writes any result's samples")
    trajectory = result.trajectory
    y0, yf = trajectory.y_start, trajectory.y_final
    if isinstance(result.model, Model):
        X0 = result.X[0]
        n1 = result.model.n + 1
        initial = np.array([0.0, float(X0[0]), float(X0[n1])])
        final = np.array([0.0, yf / result.model.output_at, 0.0])  # at rest y = x_out theta
    else:
        form = NormalForm.of_system(result.model)
        initial = np.array([form.equilibrium_input(y0)])
        final = np.array([form.equilibrium_input(yf)])
    return FeedforwardData(names=signals.names, signals=signals, initial=initial, final=final)


def rounding_bounds(result: FeedforwardSource) -> dict[str, float]:
    """Rounding bound of the closed form summed in double precision.

    First-order bound of the rounding of the closed form summed in double precision, relative to each signal's peak.

    The closed form sums terms such as ``c_j e^{mu_j s}`` whose size can exceed the result by
    orders of magnitude (nearly dependent exponentials give large coefficients of
    alternating sign). Rounding each term (and each ``exp``) by ``eps`` leaves an error up to
    ``eps`` times the sum of the terms' magnitudes
    (:meth:`inversion.family.redefinition.Redefinition.rounding`): this function returns its
    largest value over the result's samples, divided by the signal's peak (``tau``,
    ``theta_d``, ``thetadot_d``; ``u`` for a generic system). It is why the samples and the
    C evaluate the re-expanded series instead (module docstring).

    Parameters
    ----------
    result : FeedforwardSource
        A result with a closed form.
    """
    redef = result.redefinition
    if redef is None:
        raise SettingsError("result", f"a {result.summary.get('method', 'non-causal')} inversion", "a causal inversion (method 'ssef')")
    bounds = redef.plan.bounds
    k = np.clip(np.searchsorted(bounds, result.t, side="right") - 1, 0, redef.plan.count - 1)
    s = np.clip(result.t - bounds[k], 0.0, redef.plan.durations[k])
    rounding = redef.rounding(k, s)
    signals = [("tau", "tau", result.tau), ("theta_d", "theta", result.theta_d), ("thetadot_d", "thetadot", result.thetadot_d)]
    if result.theta_d is None:
        signals = [("u", "tau", result.tau)]
    out = {}
    for name, key, signal in signals:
        assert signal is not None
        peak = float(np.abs(signal).max())
        out[name] = float(rounding[key].max() / peak) if peak > 0 else 0.0
    return out


def check_prefix(prefix: str | None) -> str:
    """A C identifier checked (``None``: :data:`DEFAULT_PREFIX`).

    A C identifier (letters, digits, ``_``; not starting with a digit; at most 63 characters); ``None``: :data:`DEFAULT_PREFIX`.

    Parameters
    ----------
    prefix : str | None
        The identifier, or ``None``.
    """
    if prefix is None:
        return DEFAULT_PREFIX
    if not isinstance(prefix, str) or not _IDENTIFIER.fullmatch(prefix):
        raise SettingsError("prefix", prefix, "a C identifier: letters, digits and _, not starting with a digit, at most 63 characters")
    return prefix


def _number(value: float) -> str:
    """A double as a C literal that reads back exactly (the shortest ``repr``)."""
    if not math.isfinite(value):
        raise SettingsError("feedforward", value, "finite numbers only (the result holds a non-finite value)")
    text = repr(float(value))
    return text if any(ch in text for ch in ".e") else text + ".0"


def _array(name: str, values: Any, kind: str = "double") -> str:
    """A ``static const`` C array (one dummy element when empty: C has no empty arrays)."""
    flat = np.asarray(values).reshape(-1)
    items = [str(int(v)) for v in flat] if kind == "int" else [_number(float(v)) for v in flat]
    if not items:
        items = ["0"]
    lines = [", ".join(items[i : i + 4]) for i in range(0, len(items), 4)]
    return f"static const {kind} {name}[{len(items)}] = {{\n    " + ",\n    ".join(lines) + "\n};\n"


def _provenance(result: FeedforwardSource, data: FeedforwardData | None, held: NDArray[np.float64] | None = None) -> list[str]:
    """Lines saying what produced an exported file (``data``: the series, when there is one; ``held``: the judged rows, whose
    peak is quoted beside the closed form's); a summary read back that does not say it (edited: a figure of the wrong type,
    a key removed) is refused in words."""
    try:
        return _provenance_lines(result, data, held)
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as exc:
        what = f"{type(exc).__name__}: {exc}"[:120]
        raise SettingsError("feedforward", "summary.json", f"a summary of sflm invert as it wrote it, which describes the table "
                                                           f"(this one does not: {what}): run sflm invert again") from None


def _provenance_lines(result: FeedforwardSource, data: FeedforwardData | None, held: NDArray[np.float64] | None) -> list[str]:
    """:func:`_provenance`'s lines, on a summary as the inversion wrote it."""
    from modelgen.cache import versions

    s: Any = result.summary
    settings = s["settings"]
    if isinstance(result.model, Model):
        model_hash = getattr(result.model.functions, "manifest", {}).get("hash", "unknown")
        about = (f"model {s['model']} ({s['modes']} mode{'s' if s['modes'] != 1 else ''}, {s['mode_shapes']} shapes, "
                 f"output at {s['output_at']:.6g} m), model hash {model_hash}")
        peak = f"peak torque {s['peak_torque']:.6g} N m"
    else:
        system = s["system"]
        about = f"system {s['model']} ({system['states']} states, relative degree {system['relative_degree']})"
        peak = f"peak |u| {s['peak_torque']:.6g}"
    kind = _registered(s.get("method", "ssef"))
    member = kind().c_text(s) if kind is not None else (  # a method not registered here: what its summary says
        f"method {s.get('method')}: " + ", ".join(f"{k} {v}" for k, v in settings.items() if isinstance(v, (int, float, str))))
    lines = [
        f"generated by sflm {versions()['sflm']} (inversion.realtime.feedforward_c) -- do not edit: regenerate it",
        about,
        f"trajectory {s['trajectory']}",
        member,
        f"max |y~ - y_d| {s['max_redefinition_error']:.6g}, {peak}"
        + ("" if held is None or held.size == 0 else f" (the held table's rows: {float(np.abs(held[:, 0]).max()):.6g})"),
    ]
    if data is not None:
        series = data.signals
        sampling = s["verification"].get("sampling")
        how = ("the closed form re-expanded in extended precision; the closed form summed in double differs by "
               f"{sampling['closed_form_in_double_difference']:.1e} of the peak" if sampling else
               kind.series_text if kind is not None else "its samples re-expanded")
        lines += [
            f"span [{series.bounds[0]:.17g}, {series.bounds[-1]:.17g}] s; feedforward hash {data.digest()}",
            f"{', '.join(data.names)}: Chebyshev series of degree {series.coefficients.shape[2] - 1} on {series.pieces} pieces "
            f"of {series.bounds.size - 1} intervals ({how})",
        ]
    return [comment_safe(line) for line in lines]


def _registered(name: Any) -> Any:
    """The registered method ``name`` (:func:`inversion.options.method_named`), or ``None``."""
    try:
        return method_named(str(name))
    except SettingsError:
        return None


def comment_safe(text: str) -> str:
    """``text`` fit for a line of a C comment.

    :func:`modelgen.quoting.c_comment`, under its former name.

    Parameters
    ----------
    text : str
        Any text.
    """
    return c_comment(text)


_C_HEADER = """\
/*
{provenance}
 */
#ifndef {guard}
#define {guard}

#ifdef __cplusplus
extern "C" {{
#endif

/* Start and end of the feedforward (s). */
#define {PREFIX}_T0 {t0}
#define {PREFIX}_TF {tf}
/* The controller's period (s) and the periods from T0 until the feedforward ends. */
#define {PREFIX}_PERIOD {period}
#define {PREFIX}_PERIODS {periods}

/* {meaning}
   No allocation, no global state: safe to call from an interrupt. */
int {prefix}_eval(double t, {arguments});

/* The values to hold over period k, [T0 + k PERIOD, T0 + (k+1) PERIOD): row k of the table the
   acceptance judged, bit for bit ({held}). Returns 0 for k in [0, PERIODS), 1 outside (then the
   values before T0, or after the feedforward). */
int {prefix}_eval_held(long k, {arguments});

#ifdef __cplusplus
}}
#endif

#endif /* {guard} */
"""

_C_SOURCE = """\
/*
{provenance}
 */
#include "feedforward.h"

#define K {K}  /* segments */
#define P {P}  /* pieces */
#define S {S}  /* signals: {names} */
#define D {D}  /* degree of the series */

/* BOUNDS: the joints; pieces of segment k: PIECE_START[k] .. PIECE_START[k+1] - 1, piece p
   spans local times EDGES[p + k] .. EDGES[p + k + 1]; COEF[(p S + m)(D + 1) + j]: the
   coefficient of T_j of signal m on piece p. HELD[k S + m]: signal m held over period k, the
   table the acceptance judged. */
{arrays}
static int locate(double t, double *x)  /* the piece of t in the span, and its local coordinate in [-1, 1] */
{{
    int k = 0, hi = K - 1; /* the segment: BOUNDS[k] <= t < BOUNDS[k+1], the last one closed */
    while (k < hi) {{
        const int mid = (k + hi + 1) / 2;
        if (BOUNDS[mid] <= t) k = mid; else hi = mid - 1;
    }}
    double s = t - BOUNDS[k];
    const double length = BOUNDS[k + 1] - BOUNDS[k];
    if (s < 0.0) s = 0.0;
    if (s > length) s = length;
    const int first = PIECE_START[k], count = PIECE_START[k + 1] - first;
    int p = first;
    for (int step = 1; step < count; ++step)
        if (s >= EDGES[first + k + step]) p = first + step;
    const double a = EDGES[p + k], b = EDGES[p + k + 1];
    *x = (2.0 * s - a - b) / (b - a);
    return p;
}}

static double clenshaw(const double *c, int degree, double x)  /* sum_j c[j] T_j(x) */
{{
    double b1 = 0.0, b2 = 0.0;
    for (int j = degree; j > 0; --j) {{
        const double next = 2.0 * x * b1 - b2 + c[j];
        b2 = b1;
        b1 = next;
    }}
    return x * b1 - b2 + c[0];
}}

int {prefix}_eval(double t, {arguments})
{{
    double out[S];
    int rc = 0;
    if (!(t >= BOUNDS[0] && t <= BOUNDS[K])) {{ /* outside the span, or not a number */
        const double *v = (t > BOUNDS[K]) ? FINAL : INITIAL;
        for (int m = 0; m < S; ++m) out[m] = v[m];
        rc = 1;
    }} else {{
        double x;
        const int p = locate(t, &x);
        for (int m = 0; m < S; ++m) out[m] = clenshaw(COEF + (p * S + m) * (D + 1), D, x);  /* Clenshaw's recurrence */
    }}
{assign}    return rc;
}}

int {prefix}_eval_held(long k, {arguments})
{{
    double out[S];
    const double *v = (k < 0) ? INITIAL : (k >= {PREFIX}_PERIODS) ? FINAL : HELD + k * S;  /* the judged rows */
    for (int m = 0; m < S; ++m) out[m] = v[m];
{assign}    return (k < 0 || k >= {PREFIX}_PERIODS) ? 1 : 0;
}}
"""

#: What the header says each export returns.
_MEANING = {
    ("tau", "theta_d", "thetadot_d"): ("The feedforward torque tau_l (N m) and the joint references theta_d (rad) and\n"
                                       "   thetadot_d (rad/s) at time t (s). Returns 0 for t in [T0, TF]; 1 outside (then\n"
                                       "   tau = 0 and the joint references of the start before T0, of the end after TF)."),
    ("u",): ("The feedforward input u of the system at time t (s). Returns 0 for t in [T0, TF]; 1\n"
             "   outside (then the input that holds the output at rest where y_d starts, before T0,\n"
             "   and where it ends, after TF)."),
}


def export_c(result: FeedforwardSource, folder: str | Path, prefix: str | None = None) -> list[Path]:
    """Write ``feedforward.c`` and ``.h`` for a real-time controller.

    The header declares ``int <prefix>_eval(double t, double *tau, double *theta_d,
    double *thetadot_d)`` for a link, ``int <prefix>_eval(double t, double *u)`` for a
    generic system; the source evaluates the member's signals (module docstring). C99, libm
    not even needed, no allocation, everything else ``static``: several exports with
    different prefixes link into one program.

    Parameters
    ----------
    result : InversionResult
        The inversion to export.
    folder : str or Path
        Where to write (created).
    prefix : str, optional
        Prefix of the exported symbol and macros (a C identifier; default
        :data:`DEFAULT_PREFIX`).

    Returns
    -------
    list of Path
        The two files.

    Raises
    ------
    SettingsError
        For a prefix that is not a C identifier, a result without a closed form, or a folder
        that cannot be written.

    Examples
    --------
    >>> import tempfile, modelgen
    >>> from inversion import invert, smoothstep
    >>> result = invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 5))
    >>> with tempfile.TemporaryDirectory() as folder:
    ...     [path.name for path in export_c(result, folder, prefix="joint1")]
    ['feedforward.c', 'feedforward.h']
    """
    prefix = check_prefix(prefix)
    data = feedforward_data(result)
    series = data.signals
    period, hold, held = judged_rows(result, data)
    provenance = "\n".join(f" * {line}" for line in _provenance(result, data, held))
    arrays = "".join([
        _array("BOUNDS", series.bounds), _array("PIECE_START", series.piece_start, "int"), _array("EDGES", series.edges),
        _array("COEF", series.coefficients), _array("INITIAL", data.initial), _array("FINAL", data.final),
    ])
    arguments = ", ".join(f"double *{name}" for name in data.names)
    assign = "".join(f"    *{name} = out[{m}];\n" for m, name in enumerate(data.names))
    periods = held.shape[0]
    arrays += _array("HELD", held)
    source = _C_SOURCE.format(provenance=provenance, K=series.bounds.size - 1, P=series.pieces, S=len(data.names),
                              D=series.coefficients.shape[2] - 1, names=", ".join(data.names), arrays=arrays, prefix=prefix,
                              PREFIX=prefix.upper(), arguments=arguments, assign=assign)
    guard = f"{prefix.upper()}_FEEDFORWARD_H"
    header = _C_HEADER.format(provenance=provenance, guard=guard, PREFIX=prefix.upper(), prefix=prefix, arguments=arguments,
                              meaning=_MEANING[data.names], t0=_number(series.bounds[0]), tf=_number(series.bounds[-1]),
                              period=_number(period), periods=periods,
                              held=("a point hold: the values at the period's start" if hold == "point" else
                                    f"a zero-order hold: the {dict(tau='torque', u='input')[data.names[0]]} as its exact mean over "
                                    "the period, the others at its start"))
    folder = Path(folder)
    paths = [folder / "feedforward.c", folder / "feedforward.h"]
    try:
        folder.mkdir(parents=True, exist_ok=True)
        paths[0].write_text(source)
        paths[1].write_text(header)
    except OSError as exc:
        raise SettingsError("folder", str(folder), f"a folder that can be created and written ({exc.strerror})") from None
    return paths


def judged_rows(result: FeedforwardSource, data: FeedforwardData | None = None) -> tuple[float, str, NDArray[np.float64]]:
    """The table the acceptance judged: the controller's period, its hold and one row a period.

    The rows of :func:`inversion.acceptance.held_table` at the summary's ``sampled`` period and hold -- where those are
    the result's own samples (a point hold at the samples' spacing, or a held table's one value a period), those samples
    themselves, bit for bit: what ``inversion.csv`` holds.

    Parameters
    ----------
    result : InversionResult
        The result (its summary's ``sampled`` block, or its settings, give the period and hold).
    data : FeedforwardData, optional
        Its signals (:func:`feedforward_data`).

    Returns
    -------
    tuple
        ``(period, hold, rows)``, ``rows`` of shape ``(periods, signals)``.
    """
    from ..acceptance import held_table

    data = feedforward_data(result) if data is None else data
    summary = result.summary
    sampled = summary.get("sampled") or {}
    settings = summary["settings"]
    period = float(sampled.get("period") or settings.get("period") or 1.0 / float(settings["rate"]))
    hold = str(sampled.get("hold") or settings.get("hold") or "point")
    t = np.asarray(result.t, dtype=float)
    link = data.names == ("tau", "theta_d", "thetadot_d")
    own = np.column_stack([result.tau, result.theta_d, result.thetadot_d]) if link else np.asarray(result.tau, dtype=float)[:, None]
    series = data.signals
    t0, end = float(series.bounds[0]), float(series.bounds[-1])
    count = max(1, math.ceil((end - t0) / period - 1e-9))
    # one sample a period: the result's rows are the judged ones (a point hold's values, a zero-order hold's means, a held
    # table's values), as inversion.csv holds them -- the rows of the periods only: a last sample at the feedforward's end,
    # off the controller's grid, is no period's (the series evaluated again at the same times may differ from the
    # samples by an ulp where the product's summation order follows the machine's BLAS: seen on an AMD EPYC)
    spacing = np.diff(t[:count] if hold == "point" else t)
    held_samples = summary.get("method") == "ocp" or (t.size > 1 and np.allclose(spacing, period, rtol=1e-9, atol=0.0))
    if held_samples and abs(float(t[0]) - t0) <= 1e-12 * max(1.0, abs(t0)) and own.shape[0] >= count:
        return period, hold, np.ascontiguousarray(own[:count])
    times, values = held_table(series, t0, end, period, hold, data.initial, data.final)
    return period, hold, np.column_stack([values[name] for name in data.names])


def export_table(result: FeedforwardSource, path: str | Path, prefix: str | None = None) -> Path:
    """Write the sampled signals as ``static const double`` arrays.

    Write the sampled ``t``, ``tau``, ``theta_d``, ``thetadot_d`` (``t``, ``u`` for a generic system) as ``static const double`` arrays.

    The values are those of ``inversion.csv`` (the same samples at the result's rate, each
    written so that it reads back to the same double).

    Parameters
    ----------
    result : InversionResult
    path : str or Path
        The header file (``.h``).
    prefix : str, optional
        Prefix of the arrays and macros (a C identifier; default :data:`DEFAULT_PREFIX`).

    Raises
    ------
    SettingsError
        For a prefix that is not a C identifier or a file that cannot be written.
    """
    prefix = check_prefix(prefix)
    data = feedforward_data(result) if result.signals is not None else None
    path = Path(path)
    link = result.theta_d is not None
    rate = result.summary["settings"]["rate"]
    guard = f"{prefix.upper()}_TABLE_H"
    lines = ["/*", *(f" * {line}" for line in _provenance(result, data)),
             f" * the samples of inversion.csv at {rate:g} Hz: "
             + ("t (s), tau (N m), theta_d (rad), thetadot_d (rad/s)" if link else "t (s), u (the system's input)"), " */",
             f"#ifndef {guard}", f"#define {guard}", "",
             f"#define {prefix.upper()}_TABLE_SIZE {result.t.size}", f"#define {prefix.upper()}_TABLE_RATE {_number(rate)}", ""]
    body = "\n".join(lines) + "\n"
    columns = (("t", result.t), ("tau", result.tau), ("theta_d", result.theta_d), ("thetadot_d", result.thetadot_d)) if link \
        else (("t", result.t), ("u", result.tau))
    for name, values in columns:
        body += _array(f"{prefix}_table_{name}", values) + "\n"
    body += f"#endif /* {guard} */\n"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(body)
    except OSError as exc:
        raise SettingsError("path", str(path), f"a file that can be written ({exc.strerror})") from None
    return path
