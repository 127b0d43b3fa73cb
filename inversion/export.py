"""The feedforward for a real-time controller: self-contained C and lookup tables.

:func:`export_c` writes ``feedforward.c`` and ``feedforward.h``: C99 that needs only
libm, allocates nothing and evaluates, at any time ``t``, the closed form of the chosen
member -- not a table. It computes what the inversion computes for ``inversion.csv``, in
the same order and with the same cancellation-free kernels (docs/method.md, section 2),
so the two agree to rounding: in segment ``k``, at local time ``s``,

* ``yddot~ = sum_j c_j e^{mu_j s}``, ``ydot~ = ydot~_k + s sum_j c_j phi1(mu_j s)``,
  ``y~ = y~_k + ydot~_k s + s^2 sum_j c_j phi2(mu_j s)`` (Eq. (29) and its integrals);
* ``X_I = sum_j e^{mu_j s} G_j + Re sum_i e^{lambda_i (s - a_i)} K_i`` (the internal modes:
  particular parts and complementary parts) ``+ Re sum_q d_q v_q`` for the exponents
  within ``0.2/T`` of a zero, ``d_q`` their ``(e^{alpha u} - e^{beta u})/(alpha - beta)``
  by its series (``u = s``, or ``T - s`` for a mode anchored at the segment's end);
* ``X = T^-1 [y~; ydot~; X_I]``, ``theta_d = X_0``, ``thetadot_d = X_{n+1}`` and
  ``tau_l = (yddot~ - C A^2 X)/CAB`` (Eq. (12)).

:func:`export_table` writes the sampled signals as ``const double`` arrays instead.
"""

from __future__ import annotations

import hashlib
import math
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import NDArray

from modelgen.model import Model

from .errors import SettingsError
from .exponentials import _SERIES, _inverse_factorials, _terms
from .ssef import _ANCHORED

if TYPE_CHECKING:
    from .piecewise import InversionResult, InversionSummary

__all__ = ["FeedforwardData", "feedforward_data", "rounding_bounds", "export_c", "export_table", "check_prefix", "DEFAULT_PREFIX"]

#: Default prefix of the exported C symbols (``sflm_feedforward_eval``).
DEFAULT_PREFIX = "sflm_feedforward"
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,62}")


@dataclass(frozen=True)
class FeedforwardData:
    """The closed form of a member, reduced to the numbers the C evaluates (module docstring).

    Arrays run over segments ``k`` (``K``), exponents ``j`` (``r``), internal states ``n``
    (``2n``) and states (``N = 2(n+1)``).

    Attributes
    ----------
    bounds : ndarray, shape (K+1,)
        Joints ``t_0 .. t_K`` (s).
    durations : ndarray, shape (K,)
        ``T_k`` (s), the clip of the local time.
    mu, c : ndarray, shape (K, r)
        Exponents (1/s) and coefficients (m/s^2) of Eq. (29).
    y0, ydot0 : ndarray, shape (K,)
        ``y~`` and ``ydot~`` at the segments' starts.
    G : ndarray, shape (K, r, 2n)
        Coefficients of ``e^{mu_j s}`` in ``X_I``.
    comp_start : ndarray of int, shape (K+1,)
        Complementary terms of segment ``k``: ``comp_start[k] .. comp_start[k+1]``.
    comp_rate, comp_anchor, comp_vector : ndarray
        Their ``lambda_i`` (complex), ``a_i`` (s) and ``K_i`` (complex, shape (., 2n)).
    close_start : ndarray of int, shape (K+1,)
        Near-zero terms of segment ``k``.
    close_alpha, close_beta, close_reversed, close_vector : ndarray
        Their exponents (complex), whether ``u = T - s``, and ``v_q`` (complex, shape (., 2n)).
    Tinv : ndarray, shape (N, N)
        ``X = T^-1 [y; ydot; X_I]``.
    CA2 : ndarray, shape (N,)
        ``C A^2``.
    CAB : float
        ``C A B``.
    initial, final : ndarray, shape (3,)
        ``tau, theta_d, thetadot_d`` before ``t_0`` (``tau = 0`` and the joint's initial angle
        and rate) and after ``t_f`` (``0, y_d(t_f)/L, 0``).
    """

    bounds: NDArray[np.float64]
    durations: NDArray[np.float64]
    mu: NDArray[np.float64]
    c: NDArray[np.float64]
    y0: NDArray[np.float64]
    ydot0: NDArray[np.float64]
    G: NDArray[np.float64]
    comp_start: NDArray[np.intp]
    comp_rate: NDArray[np.complex128]
    comp_anchor: NDArray[np.float64]
    comp_vector: NDArray[np.complex128]
    close_start: NDArray[np.intp]
    close_alpha: NDArray[np.complex128]
    close_beta: NDArray[np.complex128]
    close_reversed: NDArray[np.bool_]
    close_vector: NDArray[np.complex128]
    Tinv: NDArray[np.float64]
    CA2: NDArray[np.float64]
    CAB: float
    initial: NDArray[np.float64]
    final: NDArray[np.float64]

    def digest(self) -> str:
        """SHA-256 of every number (identifies the feedforward in the generated header)."""
        h = hashlib.sha256()
        for value in vars(self).values():
            h.update(np.ascontiguousarray(value).tobytes())
        return h.hexdigest()


def feedforward_data(result: InversionResult) -> FeedforwardData:
    """The numbers :func:`export_c` writes, from a result's solved member.

    Raises
    ------
    SettingsError
        For a result without a closed form (built without its redefinition).
    """
    model = _link_only(result, "--export-c")[0]
    redef = result.redefinition
    if redef is None:
        raise SettingsError("--export-c", f"a {result.summary.get('method', 'non-causal')} inversion",
                            "a causal inversion (method 'ssef'), whose closed form the C evaluates; "
                            "--export-table writes any result's samples")
    stack, form = redef.stack, redef.form
    flat = redef.offset + np.arange(redef.plan.count)
    n1 = model.n + 1
    nI = form.n_internal

    comp_start, comp_rate, comp_anchor, comp_vector = [0], [], [], []
    for f in flat:
        active = np.flatnonzero(stack.Kc[f] != 0)  # none for the paper's free unstable modes
        comp_rate += list(stack.rate[active])
        comp_anchor += list(stack.anchor[f, active])
        comp_vector += list(stack.KV[f, active])
        comp_start.append(len(comp_rate))

    close_start, alpha, beta, reversed_, close_vector = [0], [], [], [], []
    tk, tj, ti = stack.close
    for f in flat:
        for q in np.flatnonzero(tk == f):
            j, i = tj[q], ti[q]
            weight = stack.beta[i] * stack.c[f, j]
            if stack.kinds[i] == _ANCHORED:  # -w e^{mu T} (e^{-lam u} - e^{-mu u})/(mu - lam), u = T - s
                alpha.append(-stack.lam[i])
                beta.append(-stack.mu[f, j])
                reversed_.append(True)
                close_vector.append(-weight * np.exp(stack.mu[f, j] * stack.T[f]) * stack.V[:, i])
            else:  # from the start: w (e^{mu s} - e^{lam s})/(mu - lam), u = s
                alpha.append(stack.mu[f, j])
                beta.append(stack.lam[i])
                reversed_.append(False)
                close_vector.append(weight * stack.V[:, i])
        close_start.append(len(alpha))

    X0 = result.X[0]
    theta_final = float(result.trajectory.derivative([result.trajectory.tf], 0, "-")[0]) / model.output_at  # at rest y = x_out theta
    return FeedforwardData(
        bounds=np.asarray(redef.plan.bounds, dtype=float),
        durations=np.asarray(stack.T[flat], dtype=float),
        mu=np.asarray(stack.mu[flat], dtype=float),
        c=np.asarray(stack.c[flat], dtype=float),
        y0=np.asarray(stack.y0[flat], dtype=float),
        ydot0=np.asarray(stack.ydot0[flat], dtype=float),
        G=np.asarray(stack.G[flat], dtype=float),
        comp_start=np.asarray(comp_start, dtype=np.intp),
        comp_rate=np.asarray(comp_rate, dtype=complex),
        comp_anchor=np.asarray(comp_anchor, dtype=float),
        comp_vector=np.asarray(comp_vector, dtype=complex).reshape(-1, nI),
        close_start=np.asarray(close_start, dtype=np.intp),
        close_alpha=np.asarray(alpha, dtype=complex),
        close_beta=np.asarray(beta, dtype=complex),
        close_reversed=np.asarray(reversed_, dtype=bool),
        close_vector=np.asarray(close_vector, dtype=complex).reshape(-1, nI),
        Tinv=np.asarray(form.Tinv, dtype=float),
        CA2=np.asarray(form.CA2, dtype=float).reshape(-1),
        CAB=float(form.CAB),
        initial=np.array([0.0, float(X0[0]), float(X0[n1])]),
        final=np.array([0.0, theta_final, 0.0]),
    )


def _link_only(result: InversionResult, option: str) -> tuple[Model, InversionSummary, NDArray[np.float64], NDArray[np.float64]]:
    """The link model, summary and joint references of a result; a generic system's is refused
    (its export, ``u`` in place of ``tau``, is not built yet)."""
    if not isinstance(result.model, Model) or result.theta_d is None or result.thetadot_d is None:
        raise SettingsError(option, f"the inversion of the generic system {result.model.name}",
                            "the inversion of a link model (exporting a generic system's input u is not built yet)")
    return result.model, cast("InversionSummary", result.summary), result.theta_d, result.thetadot_d


def rounding_bounds(result: InversionResult) -> dict[str, float]:
    """First-order bound of the rounding of the closed form in double precision, relative to each signal's peak.

    Any evaluator of the closed form -- the inversion's, or the exported C -- sums terms
    such as ``c_j e^{mu_j s}`` whose size can exceed the result by orders of magnitude
    (nearly dependent exponentials give large coefficients of alternating sign). Rounding
    each term (and each ``exp``) by ``eps`` leaves an error up to ``eps`` times the sum of
    the terms' magnitudes (:meth:`inversion.redefinition.Redefinition.rounding`): this
    function returns its largest value over the result's samples, divided by the signal's
    peak, for ``tau``, ``theta_d`` and ``thetadot_d``. Two evaluators agree to about twice it.
    """
    theta_d, thetadot_d = _link_only(result, "result")[2:]
    redef = result.redefinition
    if redef is None:
        raise SettingsError("result", f"a {result.summary.get('method', 'non-causal')} inversion", "a causal inversion (method 'ssef')")
    bounds = redef.plan.bounds
    k = np.clip(np.searchsorted(bounds, result.t, side="right") - 1, 0, redef.plan.count - 1)
    s = np.clip(result.t - bounds[k], 0.0, redef.plan.durations[k])
    rounding = redef.rounding(k, s)
    out = {}
    for name, key, signal in (("tau", "tau", result.tau), ("theta_d", "theta", theta_d), ("thetadot_d", "thetadot", thetadot_d)):
        peak = float(np.abs(signal).max())
        out[name] = float(rounding[key].max() / peak) if peak > 0 else 0.0
    return out


def check_prefix(prefix: str) -> str:
    """A C identifier (letters, digits, ``_``; not starting with a digit; at most 63 characters)."""
    if not isinstance(prefix, str) or not _IDENTIFIER.fullmatch(prefix):
        raise SettingsError("--c-prefix", prefix, "a C identifier: letters, digits and _, not starting with a digit, at most 63 characters")
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


def _provenance(result: InversionResult, data: FeedforwardData | None) -> list[str]:
    """Lines saying what produced an exported file (``data``: the closed form, when there is one)."""
    from modelgen.cache import versions

    model, s = _link_only(result, "--export-c")[:2]
    settings = s["settings"]
    model_hash = getattr(model.functions, "manifest", {}).get("hash", "unknown")
    modes = f"{s['modes']} mode{'s' if s['modes'] != 1 else ''}"
    if s.get("method") == "stable":
        member = (f"non-causal stable inversion: {s['pre_actuation_time']:.6g} s of pre-actuation, "
                  f"{s['post_actuation_time']:.6g} s of post-actuation")
    else:
        member = (f"member: {len(settings['segments']) - 1} segments, h = {settings['h']}, Cdec = ({settings['cdec'][0]:g}, "
                  f"{settings['cdec'][1]:g}), joining {settings['joining']}")
    lines = [
        f"generated by sflm {versions()['sflm']} (inversion.export) -- do not edit: regenerate it",
        f"model {s['model']} ({modes}, {s['mode_shapes']} shapes), model hash {model_hash}",
        f"trajectory {s['trajectory']}",
        member,
        f"max |y~ - y_d| {s['max_redefinition_error']:.6g} m, peak torque {s['peak_torque']:.6g} N m",
    ]
    if data is not None:
        lines += [
            f"span [{data.bounds[0]:.17g}, {data.bounds[-1]:.17g}] s; feedforward hash {data.digest()}",
            "rounding of the closed form in double precision (any evaluator, relative to the peaks): "
            + ", ".join(f"{name} {value:.1e}" for name, value in rounding_bounds(result).items()),
        ]
    return lines


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

/* The feedforward torque tau_l (N m) and the joint references theta_d (rad) and
   thetadot_d (rad/s) at time t (s). Returns 0 for t in [T0, TF]; 1 outside (then
   tau = 0 and the joint references of the start before T0, of the end after TF).
   No allocation, no global state: safe to call from an interrupt. */
int {prefix}_eval(double t, double *tau, double *theta_d, double *thetadot_d);

#ifdef __cplusplus
}}
#endif

#endif /* {guard} */
"""

_C_SOURCE = """\
/*
{provenance}
 */
#include <complex.h>
#include <math.h>

#include "feedforward.h"

#define K {K}      /* segments */
#define R {R}      /* exponentials per segment */
#define TERMS {terms}  /* series terms below |x| = {series} */

/* The three outputs (tau_l, theta_d, thetadot_d) are fixed linear functions of y~, ydot~,
   yddot~ and X_I (rows of T^-1 and Eq. (12)): the coefficients below are already projected
   on them, so that an evaluation sums three numbers per term. */
{arrays}
/* 1/(k+1)! and 1/(k+2)!, k = 0..TERMS */
{factorials}
/* e^(mu s) and its integrals s phi1(mu s) = (e^(mu s) - 1)/mu and s^2 phi2(mu s) =
   (e^(mu s) - 1 - mu s)/mu^2, without cancellation near mu s = 0 (inv_mu = 1/mu) */
static void integrals(double mu, double inv_mu, double s, double *e, double *i1, double *i2)
{{
    const double x = mu * s;
    *e = exp(x);
    if (x == 0.0) {{
        *i1 = s;
        *i2 = 0.5 * s * s;
    }} else if (fabs(x) < {series}) {{
        double s1 = INV1[TERMS], s2 = INV2[TERMS];
        for (int k = TERMS - 1; k >= 0; --k) {{
            s1 = s1 * x + INV1[k];
            s2 = s2 * x + INV2[k];
        }}
        *i1 = s * s1;
        *i2 = s * s * s2;
    }} else {{
        *i1 = (*e - 1.0) * inv_mu;
        *i2 = (*i1 - s) * inv_mu;
    }}
}}

/* (e^(a u) - e^(b u))/(a - b), u e^(b u) when a = b */
static double complex exp_difference(double complex a, double complex b, double u)
{{
    const double complex w = (a - b) * u;
    if (cabs(w) < {series}) {{
        double complex series = 0.0;
        for (int k = TERMS - 1; k >= 0; --k) series = series * w + INV1[k];
        return u * cexp(b * u) * series;
    }}
    return (cexp(a * u) - cexp(b * u)) / (a - b);
}}

int {prefix}_eval(double t, double *tau, double *theta_d, double *thetadot_d)
{{
    if (!(t >= BOUNDS[0] && t <= BOUNDS[K])) {{ /* outside the span, or not a number */
        const double *v = (t > BOUNDS[K]) ? FINAL : INITIAL;
        *tau = v[0];
        *theta_d = v[1];
        *thetadot_d = v[2];
        return 1;
    }}
    int k = 0, hi = K - 1; /* the segment: BOUNDS[k] <= t < BOUNDS[k+1], the last one closed */
    while (k < hi) {{
        const int mid = (k + hi + 1) / 2;
        if (BOUNDS[mid] <= t) k = mid; else hi = mid - 1;
    }}
    double s = t - BOUNDS[k];
    if (s < 0.0) s = 0.0;
    if (s > DUR[k]) s = DUR[k];
    double out[3];
    for (int m = 0; m < 3; ++m) out[m] = A[3 * k + m] + B[3 * k + m] * s;
    for (int j = 0; j < R; ++j) {{ /* Eq. (29) and its integrals, with the particular parts of the modes */
        const int at = 3 * (R * k + j);
        double e, i1, i2;
        integrals(MU[R * k + j], INV_MU[R * k + j], s, &e, &i1, &i2);
        for (int m = 0; m < 3; ++m) out[m] += P[at + m] * e + Q[at + m] * i1 + RR[at + m] * i2;
    }}
    for (int q = REAL_START[k]; q < REAL_START[k + 1]; ++q) {{ /* complementary parts, real modes */
        const double e = exp(REAL_RATE[q] * (s - REAL_ANCHOR[q]));
        for (int m = 0; m < 3; ++m) out[m] += REAL_W[3 * q + m] * e;
    }}
    for (int q = PAIR_START[k]; q < PAIR_START[k + 1]; ++q) {{ /* complementary parts, complex pairs */
        const double u = s - PAIR_ANCHOR[q], e = exp(PAIR_RE[q] * u), c = cos(PAIR_IM[q] * u), sn = sin(PAIR_IM[q] * u);
        for (int m = 0; m < 3; ++m) out[m] += e * (PAIR_W_RE[3 * q + m] * c - PAIR_W_IM[3 * q + m] * sn);
    }}
    for (int q = CLOSE_START[k]; q < CLOSE_START[k + 1]; ++q) {{ /* exponents within 0.2/T of a zero */
        const double u = CLOSE_REVERSED[q] ? DUR[k] - s : s;
        const double complex d = exp_difference(CLOSE_A_RE[q] + CLOSE_A_IM[q] * I, CLOSE_B_RE[q] + CLOSE_B_IM[q] * I, u);
        for (int m = 0; m < 3; ++m) out[m] += creal((CLOSE_W_RE[3 * q + m] + CLOSE_W_IM[3 * q + m] * I) * d);
    }}
    *tau = out[0];
    *theta_d = out[1];
    *thetadot_d = out[2];
    return 0;
}}
"""


def _projected(data: FeedforwardData) -> dict[str, Any]:
    """The coefficients of the C: every term projected on the three outputs, complementary
    parts split into real modes and merged complex-conjugate pairs (one ``exp``, ``cos``
    and ``sin`` per pair instead of two complex exponentials)."""
    n1 = data.Tinv.shape[0] // 2
    u = np.vstack([-(data.Tinv.T @ data.CA2) / data.CAB, data.Tinv[0], data.Tinv[n1]])  # (3, N): on [y, ydot, X_I]
    g = np.array([1.0 / data.CAB, 0.0, 0.0])  # on yddot (Eq. (12))
    uI = u[:, 2:].T
    out: dict[str, Any] = {
        "P": data.c[:, :, None] * g + data.G @ uI,
        "Q": data.c[:, :, None] * u[:, 1],
        "R": data.c[:, :, None] * u[:, 0],
        "a": data.y0[:, None] * u[:, 0] + data.ydot0[:, None] * u[:, 1],
        "b": data.ydot0[:, None] * u[:, 0],
        "close_w": data.close_vector @ uI,
    }
    real: dict[str, list[Any]] = {"start": [0], "rate": [], "anchor": [], "w": []}
    pair: dict[str, list[Any]] = {"start": [0], "rate": [], "anchor": [], "w": []}
    for k in range(data.durations.size):
        terms = range(data.comp_start[k], data.comp_start[k + 1])
        used: set[int] = set()
        for q in terms:
            if q in used:
                continue
            rate, anchor, w = data.comp_rate[q], data.comp_anchor[q], data.comp_vector[q] @ uI
            if rate.imag == 0.0:
                real["rate"].append(rate.real)
                real["anchor"].append(anchor)
                real["w"].append(w.real)
                continue
            partner = next((p for p in terms if p not in used and p != q and data.comp_rate[p] == np.conj(rate)
                            and data.comp_anchor[p] == anchor), None)
            if partner is not None:  # Re(g H_q) + Re(conj(g) H_p) = Re(g (H_q + conj(H_p)))
                used.add(partner)
                w = w + np.conj(data.comp_vector[partner] @ uI)
            pair["rate"].append(rate)
            pair["anchor"].append(anchor)
            pair["w"].append(w)
        real["start"].append(len(real["rate"]))
        pair["start"].append(len(pair["rate"]))
    out["real"] = {key: np.asarray(v) for key, v in real.items()}
    out["pair"] = {key: np.asarray(v) for key, v in pair.items()}
    return out


def export_c(result: InversionResult, folder: str | Path, prefix: str = DEFAULT_PREFIX) -> list[Path]:
    """Write ``feedforward.c`` and ``feedforward.h`` for a real-time controller.

    The header declares ``int <prefix>_eval(double t, double *tau, double *theta_d,
    double *thetadot_d)``; the source evaluates the member's closed form (module
    docstring). C99, libm only, no allocation, everything else ``static``: several
    exports with different prefixes link into one program.

    Parameters
    ----------
    result : InversionResult
        The inversion to export.
    folder : str or Path
        Where to write (created).
    prefix : str
        Prefix of the exported symbol and macros (a C identifier).

    Returns
    -------
    list of Path
        The two files.

    Raises
    ------
    SettingsError
        For a prefix that is not a C identifier or a folder that cannot be written.

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
    K, r = data.mu.shape
    provenance = "\n".join(f" * {line}" for line in _provenance(result, data))
    pr = _projected(data)
    real, pair = pr["real"], pr["pair"]
    arrays = "".join([
        _array("BOUNDS", data.bounds), _array("DUR", data.durations), _array("MU", data.mu),
        _array("INV_MU", np.divide(1.0, data.mu, out=np.zeros_like(data.mu), where=data.mu != 0)),
        _array("A", pr["a"]), _array("B", pr["b"]), _array("P", pr["P"]), _array("Q", pr["Q"]), _array("RR", pr["R"]),
        _array("REAL_START", real["start"], "int"), _array("REAL_RATE", real["rate"]), _array("REAL_ANCHOR", real["anchor"]),
        _array("REAL_W", real["w"]),
        _array("PAIR_START", pair["start"], "int"), _array("PAIR_RE", np.real(pair["rate"])),
        _array("PAIR_IM", np.imag(pair["rate"])), _array("PAIR_ANCHOR", pair["anchor"]),
        _array("PAIR_W_RE", np.real(pair["w"])), _array("PAIR_W_IM", np.imag(pair["w"])),
        _array("CLOSE_START", data.close_start, "int"), _array("CLOSE_A_RE", data.close_alpha.real),
        _array("CLOSE_A_IM", data.close_alpha.imag), _array("CLOSE_B_RE", data.close_beta.real),
        _array("CLOSE_B_IM", data.close_beta.imag), _array("CLOSE_REVERSED", data.close_reversed.astype(int), "int"),
        _array("CLOSE_W_RE", np.real(pr["close_w"])), _array("CLOSE_W_IM", np.imag(pr["close_w"])),
        _array("INITIAL", data.initial), _array("FINAL", data.final),
    ])
    terms = _terms(np.dtype(np.float64))
    inv = _inverse_factorials(np.dtype(np.float64))
    factorials = _array("INV1", inv[1 : terms + 2]) + _array("INV2", inv[2 : terms + 3])
    source = _C_SOURCE.format(provenance=provenance, K=K, R=r, terms=terms, series=_number(_SERIES), arrays=arrays,
                              factorials=factorials, prefix=prefix)
    guard = f"{prefix.upper()}_FEEDFORWARD_H"
    header = _C_HEADER.format(provenance=provenance, guard=guard, PREFIX=prefix.upper(), prefix=prefix,
                              t0=_number(data.bounds[0]), tf=_number(data.bounds[-1]))
    folder = Path(folder)
    paths = [folder / "feedforward.c", folder / "feedforward.h"]
    try:
        folder.mkdir(parents=True, exist_ok=True)
        paths[0].write_text(source)
        paths[1].write_text(header)
    except OSError as exc:
        raise SettingsError("--export-c", str(folder), f"a folder that can be created and written ({exc.strerror})") from None
    return paths


def export_table(result: InversionResult, path: str | Path, prefix: str = DEFAULT_PREFIX) -> Path:
    """Write the sampled ``t``, ``tau``, ``theta_d``, ``thetadot_d`` as ``static const double`` arrays.

    The values are those of ``inversion.csv`` (the same samples at the result's rate, each
    written so that it reads back to the same double).

    Parameters
    ----------
    result : InversionResult
    path : str or Path
        The header file (``.h``).
    prefix : str
        Prefix of the arrays and macros (a C identifier).

    Raises
    ------
    SettingsError
        For a prefix that is not a C identifier or a file that cannot be written.
    """
    prefix = check_prefix(prefix)
    _link_only(result, "--export-table")
    data = feedforward_data(result) if result.redefinition is not None else None
    path = Path(path)
    rate = result.summary["settings"]["rate"]
    guard = f"{prefix.upper()}_TABLE_H"
    lines = ["/*", *(f" * {line}" for line in _provenance(result, data)),
             f" * the samples of inversion.csv at {rate:g} Hz: t (s), tau (N m), theta_d (rad), thetadot_d (rad/s)", " */",
             f"#ifndef {guard}", f"#define {guard}", "",
             f"#define {prefix.upper()}_TABLE_SIZE {result.t.size}", f"#define {prefix.upper()}_TABLE_RATE {_number(rate)}", ""]
    body = "\n".join(lines) + "\n"
    for name, values in (("t", result.t), ("tau", result.tau), ("theta_d", result.theta_d), ("thetadot_d", result.thetadot_d)):
        body += _array(f"{prefix}_table_{name}", values) + "\n"
    body += f"#endif /* {guard} */\n"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(body)
    except OSError as exc:
        raise SettingsError("--export-table", str(path), f"a file that can be written ({exc.strerror})") from None
    return path
