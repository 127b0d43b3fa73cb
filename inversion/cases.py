"""The paper's cases: trajectories and settings used as defaults for the shipped presets.

Numbers from the paper (sections 7 and 8; docs/method.md section 7). The presets
``hyperbolic`` and ``near-non-hyperbolic`` are the simulation link's variants and use
the simulation's trajectory and settings.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .settings import InversionSettings

__all__ = ["PaperCase", "CASES", "case_for", "paper_case"]


@dataclass(frozen=True)
class PaperCase:
    """Trajectory, settings and simulated plant of one of the paper's cases.

    ``plant_coulomb``, ``plant_breakaway`` and ``plant_damping`` describe the simulated
    plant where it differs from the model (``None``: as the model). For the experiment
    they are assumptions: the paper compensates the *measured average* dry friction
    (0.45 N m) and says the friction is hard to model exactly; a true friction about 20 %
    higher (0.55 N m sliding, 0.60 N m breakaway) is what leaves PD alone about a
    centimetre short, as the paper reports, and the link's material damping (not given)
    is taken as 1 %.
    """

    trajectory: str
    segments: int
    h: int
    cdec: tuple[float, float]
    kp: float
    kd: float
    t_end: float
    friction_compensation: float
    description: str
    plant_coulomb: float | None = None
    plant_breakaway: float | None = None
    plant_damping: float | None = None

    @property
    def settings(self) -> InversionSettings:
        """The paper's member of the family: its segments, ``h``, ``Cdec`` and joining (Eqs. (30)-(31))."""
        return InversionSettings(segments=self.segments, h=self.h, cdec=self.cdec, joining="paper")

    def simulation_settings(self) -> dict[str, Any]:
        """Keyword arguments of :func:`inversion.simulate.simulate` for this case."""
        return {
            "kp": self.kp,
            "kd": self.kd,
            "t_end": self.t_end,
            "coulomb_friction": self.plant_coulomb,
            "breakaway_friction": self.plant_breakaway,
            "friction_compensation": self.friction_compensation,
            "plant_overrides": None if self.plant_damping is None else {"zeta": self.plant_damping},
        }


CASES: dict[str, PaperCase] = {
    "paper-sim": PaperCase(
        trajectory="paper-sim", segments=5, h=2, cdec=(1e-4, 1.0), kp=15.0, kd=30.0, t_end=15.0,
        friction_compensation=0.0, description="section 7 (Table 1, Eqs. (37)-(40), Figs. 3-6)",
    ),
    "paper-exp": PaperCase(
        trajectory="paper-exp", segments=6, h=2, cdec=(0.01, 1.0), kp=1.4, kd=0.40, t_end=10.0,
        friction_compensation=0.45, description="section 8 (Eq. (41), Figs. 8-16)",
        plant_coulomb=0.55, plant_breakaway=0.60, plant_damping=0.01,
    ),
}
CASES["hyperbolic"] = CASES["paper-sim"]
CASES["near-non-hyperbolic"] = CASES["paper-sim"]


def case_for(name: str) -> PaperCase | None:
    """The case of a preset name (``None`` for a geometry of the user's)."""
    return CASES.get(name)


def paper_case(model: Any, trajectory: Any) -> PaperCase | None:
    """The paper's case when ``model`` is a shipped preset as shipped and ``trajectory`` its own.

    "As shipped": the preset's geometry with its number of modes and mode-shape family
    (``paper-sim`` with ``--modes 3`` is another model, not the paper's). Then the paper's
    settings reproduce the paper; anything else is the user's own case.
    """
    from modelgen.geometry import PRESETS, load_geometry

    from .trajectory import trajectory_from_spec

    case = CASES.get(model.name)
    if case is None or model.name not in PRESETS or model.geometry != load_geometry(model.name):
        return None
    return case if trajectory.name == trajectory_from_spec(case.trajectory).name else None
