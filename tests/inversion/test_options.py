"""Each method's options are a frozen type: what it takes is its fields, and anything else is refused by the type."""

from __future__ import annotations

import dataclasses

import pytest

import modelgen
from inversion import SettingsError, invert, smoothstep
from inversion.options import (
    SHARED_OPTIONS,
    FamilyOptions,
    OcpOptions,
    PolynomialOptions,
    ShapingOptions,
    StableOptions,
    method_options,
)

KINDS = {"ssef": FamilyOptions, "polynomial": PolynomialOptions, "stable": StableOptions, "ocp": OcpOptions, "zv": ShapingOptions,
         "zvd": ShapingOptions}
EVERY = sorted({f.name for kind in set(KINDS.values()) for f in dataclasses.fields(kind)})
EXAMPLE = {"settings": {"segments": 4}, "auto": True, "segments": 4, "h": 2, "cdec": (1e-3, 1.0), "joining": "anchored", "eps": 1e-9,
           "end": "rest", "edges": "rest", "initial_internal_state": [0.0], "solver": "lstsq", "tol": 1e-9, "zeros": "physical",
           "objective": "energy", "preview": 1.0, "ramp": 20}


@pytest.mark.parametrize("method", sorted(KINDS))
def test_a_method_takes_its_fields_and_refuses_the_rest(method: str) -> None:
    kind = KINDS[method]
    own = {f.name for f in dataclasses.fields(kind)}
    for name in EVERY:
        if name in own:
            assert getattr(method_options(method, {name: EXAMPLE[name]}), name) == EXAMPLE[name]
        else:
            with pytest.raises(SettingsError, match=rf"^{name} = .*nothing: .*takes"):
                method_options(method, {name: EXAMPLE[name]})
    assert isinstance(method_options(method, {name: None for name in EVERY}), kind)  # None is "not given"
    assert not set(SHARED_OPTIONS) & own  # the bounds and the sampling are every method's, not one's


def test_options_are_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        method_options("ocp", {"end": "free"}).end = "rest"  # type: ignore[misc]


def test_invert_refuses_an_option_the_method_does_not_take() -> None:
    model = modelgen.load("paper-sim")
    with pytest.raises(SettingsError, match=r"^edges = 'rest'.*the optimal-control feedforward takes objective, end, ramp only"):
        invert(model, smoothstep(1.57, 5.5, 5), method="ocp", edges="rest", period=0.05)
    with pytest.raises(SettingsError, match=r"^preview = .*method='polynomial'"):  # preview is refused before, with its reason
        invert(model, smoothstep(1.57, 5.5, 5), method="polynomial", preview=1.0)
