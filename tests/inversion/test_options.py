"""Each method is an object of one registry: what it takes is its class's fields, anything else is refused by name."""

from __future__ import annotations

import dataclasses
import warnings

import pytest

import modelgen
from inversion import Family, OptimalControl, Problem, SettingsError, invert, smoothstep
from inversion.options import InversionMethod, as_method, method_named, method_names, registered

EXAMPLE = {"settings": {"segments": 4}, "auto": True, "segments": 4, "h": 2, "cdec": (1e-3, 1.0), "joining": "anchored", "eps": 1e-9,
           "end": "rest", "edges": "rest", "initial_internal_state": [0.0], "solver": "lstsq", "tol": 1e-9, "zeros": "physical",
           "objective": "energy", "ramp": 20}


@pytest.mark.parametrize("name", method_names())
def test_a_method_takes_its_fields_and_refuses_the_rest(name: str) -> None:
    kind = method_named(name)
    own = {f.name for f in dataclasses.fields(kind)}  # type: ignore[arg-type]
    for option, value in EXAMPLE.items():
        if option in own:
            if (option, value) in (("zeros", "physical"),) and kind is Family:
                continue  # a Family with zeros 'physical' and end 'rest' is refused: checked below
            assert getattr(as_method(name, {option: value}), option) == value
        else:
            with pytest.raises(SettingsError, match=rf"^{option} = .*nothing: .*takes"):
                as_method(name, {option: value})
    assert isinstance(as_method(name, {option: None for option in EXAMPLE}), kind)  # None is "not given"
    assert not {"max_error", "max_torque", "max_torque_rate", "rate", "period", "hold", "window", "margin"} & own  # the Problem's


def test_the_registry_is_the_only_list_and_in_order() -> None:
    names = method_names()
    assert names == ("ssef", "polynomial", "stable", "ocp", "zv", "zvd", "replan")  # the CLI's choices, as before
    assert all(issubclass(kind, InversionMethod) and kind.label for kind in registered())
    with pytest.raises(SettingsError, match=r"^method = 'polynomial-ish'.*'ssef' or 'polynomial'"):
        method_named("polynomial-ish")


def test_options_are_frozen_and_checked_when_made() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        OptimalControl(end="free").end = "rest"  # type: ignore[misc]
    with pytest.raises(SettingsError, match=r"^tol = 2"):
        Family(tol=2)
    with pytest.raises(SettingsError, match=r"^zeros = 'physical'.*end='rest'"):
        Family(zeros="physical", end="rest")


def test_invert_refuses_an_option_the_method_does_not_take() -> None:
    model = modelgen.load("paper-sim")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        with pytest.raises(SettingsError, match=r"^edges = 'rest'.*the optimal-control feedforward takes objective, end, ramp, "
                                                r"smoothing, loop_first only"):
            invert(model, smoothstep(1.57, 5.5, 5), method="ocp", edges="rest", period=0.05)
        with pytest.raises(SettingsError, match=r"^preview = .*method='polynomial'"):  # preview is refused before, with its reason
            invert(model, smoothstep(1.57, 5.5, 5), method="polynomial", preview=1.0)
    with pytest.raises(SettingsError, match=r"^preview = .*method='polynomial'"):
        invert(Problem(model, smoothstep(1.57, 5.5, 5), preview=1.0), method="polynomial")


def test_the_former_options_classes_are_the_methods_with_a_warning() -> None:
    import inversion.options

    with pytest.warns(DeprecationWarning, match="FamilyOptions is inversion.family.method.Family"):
        assert inversion.options.FamilyOptions is Family  # type: ignore[attr-defined]
    with pytest.warns(DeprecationWarning, match="OcpOptions"):
        assert inversion.options.OcpOptions is OptimalControl  # type: ignore[attr-defined]
