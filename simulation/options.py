"""The closed loop's numerical options in one place: the integrator, its tolerances and largest step, the rate of the
samples, the settling band.

:func:`simulation.simulate` builds one :class:`SimulationOptions` from its keywords (or takes one given) and hands it
on; the integrator's own defaults are this class's. The samples' rate defaults to the inversion layer's
(:data:`inversion.config.DEFAULTS`), so a feedforward and the loop that runs it are sampled alike.

>>> SimulationOptions().rtol, SimulationOptions(rtol=1e-7).checked().rtol
(1e-09, 1e-07)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any, Literal

from inversion.config import default
from modelgen.errors import SettingsError

__all__ = ["SimulationOptions", "Engine", "ENGINES", "SIMULATION_DEFAULTS"]

#: The integrators: SUNDIALS' CVODES through CasADi, or SciPy's LSODA.
Engine = Literal["cvodes", "scipy"]
ENGINES = ("cvodes", "scipy")


@dataclass(frozen=True)
class SimulationOptions:
    """How the closed loop is integrated and sampled.

    Attributes
    ----------
    rate : float or None
        Samples per second of the result (Hz; ``None``: :attr:`inversion.config.Defaults.rate`).
    rtol, atol : float
        The integrator's relative and absolute tolerances.
    engine : {"cvodes", "scipy"}
        The integrator.
    max_step : float or None
        Largest step (s; ``None``: from the plant's fastest mode and the reference's pieces).
    settling_band : float
        The settling time's band, as a fraction of the move.
    """

    rate: float | None = None
    rtol: float = 1e-9
    atol: float = 1e-12
    engine: Engine = "cvodes"
    max_step: float | None = None
    settling_band: float = 0.02

    def given(self, **values: Any) -> "SimulationOptions":
        """These options with the keywords a caller gave.

        These options with the keywords a caller gave (``None`` leaves an option as it is).

        Parameters
        ----------
        **values
            Fields of :class:`SimulationOptions`.
        """
        return replace(self, **{name: value for name, value in values.items() if value is not None})

    def checked(self) -> "SimulationOptions":
        """These options validated, the rate resolved.

        Raises
        ------
        SettingsError
            Naming the first option out of range.
        """
        resolved = replace(self, rate=default("rate", self.rate))
        for name in ("rate", "rtol", "atol", "max_step", "settling_band"):
            value = getattr(resolved, name)
            if value is None and name == "max_step":  # from the plant and the reference, when the loop is built
                continue
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise SettingsError(name, value, "a finite number > 0")
        if self.engine not in ENGINES:
            raise SettingsError("engine", self.engine, "one of " + ", ".join(ENGINES))
        return replace(resolved, rate=float(resolved.rate))


#: The options :func:`simulation.simulate` starts from.
SIMULATION_DEFAULTS = SimulationOptions()
