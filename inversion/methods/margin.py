"""The margin a result keeps: how far inside the bound its table holds the tip, and what error in the plant it tolerates.

A table at the bound is the right limit to report and the wrong table to hand an engineer whose model is a few per cent
off. Every result's summary has a ``margin`` block (:func:`margin_block`):

* ``held``, ``after``, ``more_modes``: ``1 - e / E`` for the acceptance's own figures -- the held table at its rows
  during the move, the window after it, the model with more modes -- against the bound ``E`` the caller asked for;
* ``aimed``: the tube the method was asked to hold (``(1 - margin) E`` where the bounded causal limit left room,
  :attr:`inversion.config.Defaults.margin`);
* ``radius``: the **robustness radius** -- for each plant parameter, the largest relative error down and up for which
  the same table, held as the controller holds it, still keeps the tip within ``E`` during the move and through the
  window after it (:func:`robustness_radius`): with the feedforward alone (what ``invert`` judges) and, for a link, in
  the loop it runs in, its joint PD closed (the gains ``sflm simulate`` uses). A link's parameters are its flexural rigidity and its payload's mass
  (the geometry with the value changed, :func:`modelgen.linear.linear_model`, exactly as an edited geometry file gives);
  a generic system's, its gain ``k G(s)`` and its time scale ``G(s / k)`` (every pole and zero scaled).

The radius is found by regula falsi (:func:`_edge`) from the nominal value to
:attr:`~inversion.config.Defaults.radius_span`, to :attr:`~inversion.config.Defaults.radius_resolution`: it assumes the error grows with the parameter's error on each side
(the edge found is checked, not the whole interval).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from modelgen.model import Model

from ..acceptance import closed_loop, demand, free_peaks, held_run, held_table, outside_values, rest_angle, rest_state, window_length
from ..config import DEFAULTS, default
from ..lti.linear_system import LinearSystem
from ..lti.system import normal_form

__all__ = ["margin_block", "robustness_radius", "tolerated", "held_error", "held_rows", "HeldTable", "LINK_PARAMETERS", "SYSTEM_PARAMETERS"]

FloatArray = NDArray[np.float64]
#: A link's parameters the radius is of (geometry keys, :data:`modelgen.geometry.PARAMETER_KEYS`).
LINK_PARAMETERS = {"link.flexural_rigidity": "flexural_rigidity", "payload.mass": "payload_mass"}
#: A generic system's: its gain and its time scale.
SYSTEM_PARAMETERS = ("gain", "time_scale")


def _plant(model: Model | LinearSystem, parameter: str, factor: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    """``(A, B, C)`` of the plant with ``parameter`` multiplied by ``factor``."""
    if isinstance(model, Model):
        from modelgen.linear import linear_model

        geometry = replace(model.geometry, **{LINK_PARAMETERS[parameter]: getattr(model.geometry, LINK_PARAMETERS[parameter]) * factor})
        m = linear_model(geometry, model.n, float(model.output_at))
        return (np.asarray(m["A"], dtype=float), np.asarray(m["B"], dtype=float).reshape(-1),
                np.asarray(m["C_out"], dtype=float).reshape(-1))
    A, B, C = (np.asarray(getattr(model, k), dtype=float) for k in ("A", "B", "C"))
    B, C = B.reshape(-1), C.reshape(-1)
    if parameter == "gain":  # k G(s)
        return A, B * factor, C
    return A * factor, B * factor, C  # G(s / k): every pole and zero times k, the same gain at rest


@dataclass(frozen=True)
class HeldTable:
    """A result's table as the acceptance holds it.

    Read once for many plants (:func:`held_rows`).

    Attributes
    ----------
    u : ndarray
        The input held over each period.
    theta_d, thetadot_d : ndarray or None
        A link's joint references at the rows.
    after : ndarray
        The signals held after the table (the input first).
    period : float
        The controller's period (s).
    desired : ndarray
        ``y_d`` at the rows and at the table's end.
    y0, y_final : float
        The output at the start and at the end of the move.
    window : float
        The window after the table (s).
    link : bool
        Whether the model is a link.
    """

    u: FloatArray
    theta_d: FloatArray | None
    thetadot_d: FloatArray | None
    after: FloatArray
    period: float
    desired: FloatArray
    y0: float
    y_final: float
    window: float
    link: bool


def held_rows(result: Any) -> HeldTable:
    """The table a controller holds, as the acceptance judged it.

    Parameters
    ----------
    result : InversionResult
        The result (its summary's ``sampled`` period and hold).
    """
    model = result.model
    form = normal_form(model)
    trajectory = result.trajectory
    sampled = result.summary.get("sampled") or {}
    settings = result.summary.get("settings") or {}
    period = float(sampled.get("period") or settings.get("period") or 1.0 / float(settings.get("rate", DEFAULTS.rate)))
    hold = str(sampled.get("hold") or settings.get("hold") or DEFAULTS.hold)
    signals = result.signals
    asked = demand(form, trajectory, period)
    start, end = float(signals.bounds[0]), float(signals.bounds[-1])
    outside = (outside_values(signals, start, asked.hold_start), outside_values(signals, end, asked.hold_final))
    t, values = held_table(signals, start, end, period, hold, *outside)
    link = isinstance(model, Model)
    times = np.append(t, t[-1] + period)
    return HeldTable(u=np.asarray(values[signals.names[0]], dtype=float),
                     theta_d=np.asarray(values["theta_d"], dtype=float) if link else None,
                     thetadot_d=np.asarray(values["thetadot_d"], dtype=float) if link else None,
                     after=np.asarray(outside[1], dtype=float), period=period,
                     desired=trajectory.derivative(np.clip(times, trajectory.t0, trajectory.tf), 0),
                     y0=float(trajectory.derivative(np.array([trajectory.t0]), 0)[0]), y_final=float(asked.y_final),
                     window=float(window_length(form, sampled.get("window"))), link=link)


def held_error(result: Any, parameter: str | None = None, factor: float = 1.0, gains: tuple[float, float] | None = None,
               table: HeldTable | None = None) -> tuple[float, float]:
    """The largest tip error of a plant driven by a held table.

    The largest ``|y - y_d|`` of a plant driven by the result's table as the acceptance holds it.

    Parameters
    ----------
    result : InversionResult
        The result.
    parameter : str, optional
        A key of :data:`LINK_PARAMETERS` (a link) or of :data:`SYSTEM_PARAMETERS` (a system); ``None``: the model itself.
    factor : float
        The parameter's value over its nominal one.
    gains : (float, float), optional
        A link's joint PD ``(k_P, k_D)`` closed around the plant (the paper's Fig. 1): the input is then
        ``tau_k + k_P (theta_d,k - theta) + k_D (thetadot_d,k - thetadot)``, the references held with the torque, and
        after the table the references held at their last values. ``None``: the feedforward alone.
    table : HeldTable, optional
        The result's held table (:func:`held_rows`), read once for many plants.

    Returns
    -------
    tuple of float
        The largest error at the rows during the table, and over the window after it (the input then held at what follows
        the feedforward).
    """
    held = held_rows(result) if table is None else table
    if parameter is None:
        form = normal_form(result.model)
        A, B, C = form.A, form.B, form.C
    else:
        A, B, C = _plant(result.model, parameter, factor)
    x0 = rest_state(A, B, C, held.y0, held.link)  # from rest, as the acceptance judges it
    u, after_input = held.u, float(held.after[0])
    if gains is not None and held.link:  # the loop x' = (A - B K) x + B (tau + k_P theta_d + k_D thetadot_d)
        assert held.theta_d is not None and held.thetadot_d is not None
        A, u, after_input = closed_loop(A, B, gains, u, held.theta_d, held.thetadot_d, float(held.after[0]),
                                        rest_angle(C, held.y_final), 0.0)
    y, x_end = held_run(A, B, C, x0, u, held.period)
    during = float(np.abs(y - held.desired).max())
    after = float(free_peaks(A, B, C, x_end[None, :], held.y_final, after_input, held.window)[0])
    return during, after


def robustness_radius(result: Any, bound: float, span: float | None = None, resolution: float | None = None,
                      gains: tuple[float, float] | None = None) -> dict[str, Any]:
    """The plant errors a result's table tolerates within a bound.

    For each plant parameter, the relative errors down and up the result's table tolerates within ``bound``: with the
    feedforward alone (what ``invert`` judges) and, for a link, with its joint PD closed (the loop it runs in, the gains
    ``sflm simulate`` uses).

    Parameters
    ----------
    result : InversionResult
        The result (a link's or a generic system's).
    bound : float
        The tip bound (m, or the output's unit).
    span : float, optional
        The largest relative error searched (:attr:`~inversion.config.Defaults.radius_span`).
    resolution : float, optional
        The search's resolution (:attr:`~inversion.config.Defaults.radius_resolution`).
    gains : (float, float), optional
        A link's joint PD gains (default: :func:`modelgen.joint_pd.loop_gains`, those ``sflm simulate`` uses).

    Returns
    -------
    dict
        ``span``, ``resolution`` and, by loop (``feedforward``; a link's ``pd`` too, with its ``gains``), the loop's
        ``nominal_error`` and by parameter: ``lower`` and ``upper`` (relative, ``lower <= 0 <= upper``; ``None`` where
        the nominal plant itself is beyond the bound), ``lower_beyond_span`` / ``upper_beyond_span`` (the table holds to
        the span's end), the errors at the edges found (``lower_error``, ``upper_error``) and the nominal value;
        ``skipped`` with why for a parameter that is zero (no payload).
    """
    span = float(default("radius_span", span))
    resolution = float(default("radius_resolution", resolution))
    model = result.model
    table = held_rows(result)
    out: dict[str, Any] = {"span": span, "resolution": resolution,
                           "feedforward": _radius(result, table, bound, span, resolution, None)}
    if isinstance(model, Model):  # a link runs with its joint PD: the loop it runs in (the gains simulate uses)
        from modelgen.joint_pd import loop_gains

        gains = loop_gains(model, getattr(result, "case", None)) if gains is None else gains
        out["pd"] = {"gains": {"kp": gains[0], "kd": gains[1]}, **_radius(result, table, bound, span, resolution, gains)}
    return out


def _radius(result: Any, table: HeldTable, bound: float, span: float, resolution: float,
            gains: tuple[float, float] | None) -> dict[str, Any]:
    """:func:`robustness_radius` in one loop."""
    model = result.model
    names: tuple[str, ...] = tuple(LINK_PARAMETERS) if isinstance(model, Model) else SYSTEM_PARAMETERS

    def worst(parameter: str | None, factor: float = 1.0) -> float:
        return max(held_error(result, parameter, factor, gains, table))

    nominal_error = worst(None)
    out: dict[str, Any] = {"nominal_error": nominal_error}
    for name in names:
        if isinstance(model, Model):
            value = float(getattr(model.geometry, LINK_PARAMETERS[name]))
            if value == 0.0:
                out[name] = {"skipped": f"{name} is 0 in the geometry: no relative error of it"}
                continue
        else:
            value = 1.0
        entry: dict[str, Any] = {"nominal": value}
        for side, sign in (("lower", -1.0), ("upper", 1.0)):
            if nominal_error > bound:
                entry[side], entry[f"{side}_error"], entry[f"{side}_beyond_span"] = None, nominal_error, False
                continue
            far = worst(name, 1.0 + sign * span)
            if far <= bound:
                entry[side], entry[f"{side}_error"], entry[f"{side}_beyond_span"] = sign * span, far, True
                continue
            inside, at_inside = _edge(lambda x: worst(name, 1.0 + sign * x), bound, span, nominal_error, far, resolution)
            entry[side], entry[f"{side}_error"], entry[f"{side}_beyond_span"] = sign * inside, at_inside, False
        out[name] = entry
    return out


def _edge(error: Any, bound: float, span: float, at_zero: float, at_span: float, resolution: float) -> tuple[float, float]:
    """Where ``error(x)`` crosses ``bound`` on ``[0, span]`` (``error(0) <= bound < error(span)``), to ``resolution``.

    Regula falsi with the Illinois rule (the end kept twice has its excess halved), each point inside the bracket
    followed by one ``resolution`` further out: a smooth error closes the bracket in four to six evaluations where
    bisection takes nine. Returns the largest ``x`` found within the bound and its error.
    """
    inside, outside, e_in, e_out, kept = 0.0, span, at_zero, at_span, 0
    at_inside = at_zero
    while outside - inside > resolution:
        g_in, g_out = e_in - bound, e_out - bound  # g_in <= 0 < g_out
        x = inside + (outside - inside) * (-g_in) / (g_out - g_in) if g_out > g_in else 0.5 * (inside + outside)
        x = min(max(x, inside + 0.25 * resolution), outside - 0.25 * resolution)
        e = error(x)
        if e <= bound:
            inside, e_in, at_inside = x, e, e
            e_out = bound + 0.5 * (e_out - bound) if kept == 1 else e_out
            kept = 1
            step = inside + 0.99 * resolution  # one resolution further out: the edge is often just there
            if step < outside:
                e = error(step)
                if e <= bound:
                    inside, e_in, at_inside = step, e, e
                else:
                    outside, e_out, kept = step, e, 0
        else:
            outside, e_out = x, e
            e_in = bound + 0.5 * (e_in - bound) if kept == -1 else e_in
            kept = -1
    return inside, at_inside


def tolerated(radius: dict[str, Any], loops: tuple[str, ...] = ("feedforward", "pd")) -> float:
    """The smallest plant error a radius tolerates.

    The smallest relative error of any parameter, down or up, in ``loops``, at which the table breaks the bound (the
    span where it holds throughout; 0 where the nominal plant is beyond it).

    Parameters
    ----------
    radius : dict
        :func:`robustness_radius`'s record.
    loops : tuple of str
        The loops judged (``feedforward``, ``pd``; those absent from ``radius`` are passed over).
    """
    edges = [float(span) for loop in loops if loop in radius for entry in radius[loop].values() if isinstance(entry, dict)
             and "lower" in entry for span in (-(entry["lower"] or 0.0), entry["upper"] or 0.0)]
    return min(edges, default=float(radius["span"]))


def margin_block(result: Any, bound: float, aimed: float | None = None, asked: float | None = None,
                 radius: bool = True, gains: tuple[float, float] | None = None, found: dict[str, Any] | None = None) -> dict[str, Any]:
    """The summary's ``margin`` block (module docstring).

    Parameters
    ----------
    result : InversionResult
        The result.
    bound : float
        The bound the caller asked for (m).
    aimed : float, optional
        The tube the method was asked to hold (default ``bound``).
    asked : float, optional
        The margin asked for (a fraction of ``bound``).
    radius : bool
        Whether to compute the robustness radius (:func:`robustness_radius`).
    gains : (float, float), optional
        A link's joint PD gains the radius's ``pd`` loop closes (default: those ``sflm simulate`` uses).
    found : dict, optional
        The radius, where the caller computed it with the same bound and gains.
    """
    sampled = result.summary.get("sampled") or {}
    after_end = (result.summary.get("verification") or {}).get("after_end") or {}
    held = sampled.get("max_tip_error")
    after = sampled.get("after_end_excursion", after_end.get("max_tip_excursion"))
    more = sampled.get("more_modes_error")

    def kept(e: Any) -> float | None:
        return None if e is None or not math.isfinite(float(e)) or not bound > 0 else 1.0 - float(e) / bound

    block: dict[str, Any] = {"bound": float(bound), "asked": asked, "aimed": float(bound if aimed is None else aimed),
                             "held": kept(held), "after": kept(after), "more_modes": kept(more),
                             "more_modes_count": sampled.get("more_modes")}
    if radius and result.signals is not None:
        block["radius"] = robustness_radius(result, bound, gains=gains) if found is None else found
    return block
