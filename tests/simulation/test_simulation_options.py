"""The closed loop's numerical options are one object: its defaults are the integrator's, keywords override it, and an
option out of range is named."""

from __future__ import annotations

import inspect

import pytest

from inversion.config import DEFAULTS
from modelgen.errors import SettingsError
from simulation import SimulationOptions
from simulation.integrate import integrate
from simulation.options import SIMULATION_DEFAULTS


def test_the_integrator_s_defaults_are_the_options() -> None:
    # one home: integrate's keywords default to SimulationOptions' fields (tolerances 1e-9, 1e-12; CVODES)
    parameters = inspect.signature(integrate).parameters
    assert (parameters["rtol"].default, parameters["atol"].default, parameters["engine"].default) == \
        (SIMULATION_DEFAULTS.rtol, SIMULATION_DEFAULTS.atol, SIMULATION_DEFAULTS.engine) == (1e-9, 1e-12, "cvodes")


def test_keywords_override_and_the_rate_is_the_inversion_layer_s() -> None:
    opts = SimulationOptions(rtol=1e-7).given(atol=1e-10, rtol=None, engine="scipy").checked()
    assert (opts.rtol, opts.atol, opts.engine, opts.rate, opts.max_step) == (1e-7, 1e-10, "scipy", DEFAULTS.rate, None)


@pytest.mark.parametrize("name,value", [("rtol", 0.0), ("atol", -1e-12), ("rate", float("nan")), ("max_step", True),
                                        ("settling_band", float("inf")), ("engine", "euler")])
def test_an_option_out_of_range_is_named(name: str, value: object) -> None:
    with pytest.raises(SettingsError, match=rf"^{name} = "):
        SimulationOptions(**{name: value}).checked()  # type: ignore[arg-type]
