"""The paper's cases: every number sflm takes from the paper, and every value it assumes where the paper is silent.

Source: "Piece-wise causal inversion by output redefinition for a flexible link
manipulator", Trans. CSME 33(2), 2009, sections 7 (simulation) and 8 (experiment); see
``docs/method.md`` section 7. Each value carries its provenance: where the paper gives it
(a table, an equation, a section), or ``"assumed: ..."`` with the reason. The link's own
parameters are in the preset files (``modelgen/presets``); the values here are the cases'
settings, the simulated plant where it differs from the model, and what the paper reports
(for comparison only, never used in a computation).

This module holds data only; the layers read it (:func:`inversion.settings.paper_settings`,
:mod:`simulation.cases`, :mod:`sflm.reproduce`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

__all__ = ["Value", "PaperCase", "CASES", "case_named", "preset_case", "shipped_case", "TRUNCATION_NOTE", "REFERENCE"]


@dataclass(frozen=True)
class Value:
    """A number of a case with its unit and provenance.

    Attributes
    ----------
    value : Any
        The value.
    unit : str
        Its unit ("" for none).
    source : str
        Where the paper gives it ("Table 1", "Eq. (37)", "section 8"), or
        ``"assumed: <why>"`` where it does not.
    """

    value: Any
    unit: str
    source: str

    @property
    def assumed(self) -> bool:
        """Whether the paper does not give this value."""
        return self.source.startswith("assumed")

    def as_dict(self) -> dict[str, Any]:
        """JSON-ready."""
        value = list(self.value) if isinstance(self.value, tuple) else self.value
        return {"value": value, "unit": self.unit, "source": self.source}


@dataclass(frozen=True)
class PaperCase:
    """One of the paper's cases.

    Attributes
    ----------
    name : str
        The preset it applies to.
    description : str
        The sections, equations and figures of the paper.
    modes : int
        The number of assumed modes the paper uses.
    trajectory : Value
        The desired trajectory (a specification of :func:`inversion.trajectory_from_spec`).
    segments, h, cdec : Value
        The paper's member of the family (Eqs. (28)-(36)).
    kp, kd : Value
        Joint PD gains (Eq. (40)).
    friction_compensation : Value
        The average dry friction added in the direction of the desired motion (N m).
    t_end : Value
        End of the closed-loop simulations (s).
    model : dict of str to Value
        Values of the model (the preset) the paper does not give.
    plant : dict of str to Value
        The simulated plant where ``reproduce`` makes it differ from the model: assumptions
        fitted to what the paper observed (never a default of the library).
    pulse : dict of str to Value
        The pulse-width law of the two-stage controller (the paper gives no details).
    reported : dict of str to Value
        What the paper reports, for comparison.
    """

    name: str
    description: str
    modes: int
    trajectory: Value
    segments: Value
    h: Value
    cdec: Value
    kp: Value
    kd: Value
    friction_compensation: Value
    t_end: Value
    model: dict[str, Value] = field(default_factory=dict)
    plant: dict[str, Value] = field(default_factory=dict)
    pulse: dict[str, Value] = field(default_factory=dict)
    reported: dict[str, Value] = field(default_factory=dict)

    def values(self) -> dict[str, Value]:
        """Every value of the case by name (settings, model, plant, pulse)."""
        out = {name: getattr(self, name) for name in ("trajectory", "segments", "h", "cdec", "kp", "kd",
                                                       "friction_compensation", "t_end")}
        out.update({f"model.{k}": v for k, v in self.model.items()})
        out.update({f"plant.{k}": v for k, v in self.plant.items()})
        out.update({f"pulse.{k}": v for k, v in self.pulse.items()})
        return out

    def assumptions(self) -> dict[str, Value]:
        """The values the paper does not give."""
        return {k: v for k, v in self.values().items() if v.assumed}


_SIM = PaperCase(
    name="paper-sim",
    description="section 7 (Table 1, Eqs. (37)-(40), Figs. 3-6)",
    modes=2,
    trajectory=Value("paper-sim", "", "Eq. (37), Fig. 3: 1.57 m in 5.5 s, the degree-11 rest-to-rest polynomial"),
    segments=Value(5, "", "section 7: 5 equal segments of 1.1 s"),
    h=Value(2, "", "section 7"),
    cdec=Value((1e-4, 1.0), "", "section 7: (Cdec_f, Cdec_s)"),
    kp=Value(15.0, "N m/rad", "section 7, Fig. 4"),
    kd=Value(30.0, "N m s/rad", "section 7, Fig. 4"),
    friction_compensation=Value(0.0, "N m", "section 7: the simulated link has no dry friction"),
    t_end=Value(15.0, "s", "assumed: long enough for the PD to settle after t_f = 5.5 s; the text does not give the span of Figs. 4-6"),
    model={
        "payload.mass": Value(0.0, "kg", "assumed: Table 1 gives the payload's inertia only"),
        "damping.ratio": Value(0.0, "", "assumed: not given; the paper counts 3 unstable zeros, which needs zeta = 0"),
    },
    reported={
        "zeros": Value((61.25, -61.25, 54.34j, -54.34j), "rad/s", "section 7, Table 1"),
        "n_unstable": Value(3, "", "section 7"),
    },
)

_EXP = PaperCase(
    name="paper-exp",
    description="section 8 (Eq. (41), Figs. 8-16)",
    modes=1,
    trajectory=Value("paper-exp", "", "section 8, Figs. 8-9: C1 piecewise cubic acceleration, peak 2.5 m/s^2, 0.1 m in 0.6 s"),
    segments=Value(6, "", "Eq. (41): 6 equal segments of 0.1 s"),
    h=Value(2, "", "section 8"),
    cdec=Value((0.01, 1.0), "", "section 8: (Cdec_f, Cdec_s)"),
    kp=Value(1.4, "N m/rad", "section 8"),
    kd=Value(0.40, "N m s/rad", "section 8"),
    friction_compensation=Value(0.45, "N m", "section 8: the measured average joint dry friction"),
    t_end=Value(10.0, "s", "assumed: long enough for the pulses of stage 2; the text does not give the span of Figs. 10-16"),
    model={
        "link.youngs_modulus": Value(200e9, "Pa", "assumed: typical of stainless steel (section 8 names the material only)"),
        "link.density": Value(7900.0, "kg/m^3", "assumed: typical of stainless steel"),
        "damping.ratio": Value(0.0, "", "assumed: not given"),
    },
    plant={
        "coulomb_friction": Value(0.55, "N m", "assumed, fitted to the paper's observation: with the sliding friction 20 % "
                                  "above the compensated average (0.45 N m), PD alone stops about 10 mm short (section 8, Fig. 12); "
                                  "the paper calls the friction hard to model exactly"),
        "breakaway_friction": Value(0.60, "N m", "assumed, fitted with the sliding friction: the static level a little above it"),
        "zeta": Value(0.01, "", "assumed, fitted to the paper's observation of a slowly vanishing vibration (Figs. 15-16): the "
                      "link's material damping, not given"),
    },
    pulse={
        "amplitude": Value(0.9, "N m", "assumed: the paper gives no details of its pulse-width control (its reference [26])"),
        "gain": Value(0.8, "", "assumed: each pulse aims at 80 % of the hub error"),
        "tolerance": Value(2e-4, "m", "assumed: stop within 0.2 mm of tip-equivalent hub error"),
        "period": Value(0.25, "s", "assumed: time from one pulse to the next decision"),
    },
    reported={
        "zeros": Value((212.0, -212.0), "rad/s", "section 8"),
        "n_unstable": Value(1, "", "section 8"),
        "second_frequency_hz": Value(54.0, "Hz", "section 8"),
        "steady_tip_error_pd": Value(0.010, "m", "section 8, Fig. 12: 'about 0.01 m'"),
        "steady_tip_error_two_stage": Value(0.001, "m", "section 8, Fig. 16: 'about 0.001 m'"),
    },
)

#: The paper's cases by preset name. ``hyperbolic`` and ``near-non-hyperbolic`` are the
#: simulation link's variants (the preset files say how) with the simulation's settings.
CASES: dict[str, PaperCase] = {
    "paper-sim": _SIM,
    "paper-exp": _EXP,
    "hyperbolic": replace(
        _SIM, name="hyperbolic", description="section 7, the link without payload inertia (hyperbolic internal dynamics)",
        model={"payload.mass": _SIM.model["payload.mass"],
               "payload.inertia": Value(0.0, "kg m^2", "the variant's definition: Table 1 without the payload")},
        reported={},
    ),
    "near-non-hyperbolic": replace(
        _SIM, name="near-non-hyperbolic", description="section 7 with 1 % Rayleigh damping (near non-hyperbolic internal dynamics)",
        model={"payload.mass": _SIM.model["payload.mass"],
               "damping.ratio": Value(0.01, "", "the variant's definition: 1 % damping of the first mode")},
        reported={},
    ),
}

#: Reference values of an independent implementation (docs/method.md section 7), for reports.
REFERENCE: dict[str, dict[str, float]] = {
    "paper-sim": {"max_redefinition_error": 5.73e-3, "final_redefined_output": 1.56427, "peak_torque": 0.4310},
    "paper-exp": {"max_redefinition_error": 1.355e-3},
}

TRUNCATION_NOTE = (
    "The paper's mode shapes come from a reference not at hand and its zeros differ from "
    "ours by a few percent; assumed-mode truncation moves zeros too (see --convergence): "
    "the structure (which zeros are real, which imaginary, how many unstable) is what "
    "must agree."
)


def case_named(name: str) -> PaperCase | None:
    """The case of a preset name (``None`` for any other).

    Parameters
    ----------
    name : str
        A preset's name.
    """
    return CASES.get(name)


def preset_case(geometry: Any, output_at: float) -> PaperCase | None:
    """The paper's case of a model, or ``None``.

    The paper's case of a model, decided once when it is loaded: its preset *as shipped*, or ``None``.

    "As shipped": a preset's geometry with its number of modes and mode-shape family,
    measured at the tip (``paper-sim`` with three modes, or its output at 0.5 m, is another
    model). Whether the trajectory is the case's own is the inversion's to decide
    (:func:`inversion.problem.paper_case`).

    Parameters
    ----------
    geometry : Any
        The model's geometry.
    output_at : float
        Where its output is measured (m from the hub).
    """
    if output_at != geometry.length:
        return None
    return shipped_case(geometry, any_modes=False)


def shipped_case(geometry: Any, any_modes: bool = True) -> PaperCase | None:
    """The paper's case of a shipped preset's values, or ``None``.

    The paper's case of a geometry whose values are a shipped preset's, or ``None``. The name alone does not decide: a
    file named ``paper-sim`` with other values is another link, and what the paper reports of its case (Table 1's
    zeros) is not to be printed beside it (issue 59, item 2).

    Parameters
    ----------
    geometry : Any
        A geometry (:class:`modelgen.geometry.Geometry`).
    any_modes : bool, optional
        Whether the number of modes, their family and the file it was read from may differ from the shipped preset's
        (``sflm info`` shows the paper's zeros beside a preset's link with any number of modes; the loader's paper case,
        :func:`preset_case`, is the preset as shipped).
    """
    from .geometry import PRESETS, load_geometry

    case = case_named(geometry.name)
    if case is None or geometry.name not in PRESETS:
        return None
    shipped = load_geometry(geometry.name)
    if any_modes:
        geometry = replace(geometry, modes=shipped.modes, mode_shapes=shipped.mode_shapes, source=shipped.source)
    return case if geometry == shipped else None
