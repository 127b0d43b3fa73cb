"""Closed-loop simulation of the flexible link: plant, controllers, the loop in compiled code.

This layer consumes a loaded model (:mod:`modelgen`) and an inversion
(:mod:`inversion`); neither imports it. :func:`simulate` is the entry point.
"""

from .control import Controller, Gains, PulseWidthLaw, default_gains
from .integrate import SimulationError
from .options import SimulationOptions
from .plant import HubFriction, Plant
from .closed_loop import SIMULATION_COLUMNS, SimulationResult, SimulationSummary, simulate
from .uncertain import simulate_uncertain

__all__ = [
    "simulate",
    "simulate_uncertain",
    "SimulationResult",
    "SimulationSummary",
    "SimulationError",
    "SimulationOptions",
    "SIMULATION_COLUMNS",
    "PulseWidthLaw",
    "Gains",
    "default_gains",
    "Controller",
    "HubFriction",
    "Plant",
]
