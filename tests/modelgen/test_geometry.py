"""Geometry files: presets load, every bad input gives a typed error naming the key."""

from __future__ import annotations

import copy
import math
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given
from hypothesis import strategies as st

from modelgen import PRESETS, GeometryError, load_geometry, parse_geometry
from modelgen.geometry import Geometry, preset_path

GOOD: dict[str, Any] = {
    "name": "my-link",
    "link": {"length": 0.6, "youngs_modulus": 69e9, "density": 2700.0, "width": 0.03, "thickness": 0.002},
    "hub": {"inertia": 0.002, "viscous_damping": 0.0, "coulomb_friction": 0.0},
    "payload": {"mass": 0.05, "inertia": 2e-5},
    "damping": {"ratio": 0.0},
    "model": {"modes": 2, "mode_shapes": "clamped-mass"},
}


def with_change(path: str, value: Any, base: dict[str, Any] | None = None) -> dict[str, Any]:
    """A copy of ``base`` (default :data:`GOOD`) with one key changed or deleted."""
    data = copy.deepcopy(GOOD if base is None else base)
    *parents, last = path.split(".")
    node = data
    for p in parents:
        node = node[p]
    if value is _DELETE:
        del node[last]
    else:
        node[last] = value
    return data


_DELETE = object()


@pytest.mark.parametrize("name", PRESETS)
def test_presets_load(name: str) -> None:
    g = load_geometry(name)
    assert g.name == name
    assert preset_path(name).is_file()


def test_paper_exp_material_conversion() -> None:
    g = load_geometry("paper-exp")
    # EI = E b t^3 / 12 and rho = density b t (section 8's stainless steel strip)
    assert g.flexural_rigidity == pytest.approx(200e9 * 0.0381 * 8.890e-4**3 / 12, rel=1e-14)
    assert g.linear_density == pytest.approx(7900 * 0.0381 * 8.890e-4, rel=1e-14)
    assert (g.hub_viscous_damping, g.hub_coulomb_friction, g.modes) == (0.32, 0.45, 1)


def test_good_file_round_trip(tmp_path: Path) -> None:
    path = tmp_path / "link.toml"
    path.write_text(
        'name = "my-link"\n[link]\nlength = 0.6\nflexural_rigidity = 1.5\nlinear_density = 0.2\n'
        "[hub]\ninertia = 0.002\n"
    )
    g = load_geometry(path)
    assert (g.length, g.flexural_rigidity, g.linear_density, g.payload_mass, g.modes) == (0.6, 1.5, 0.2, 0.0, 2)


BAD_CASES = [
    ("link.length", -1.0, "link.length"),
    ("link.length", 0.0, "link.length"),
    ("link.length", math.inf, "link.length"),
    ("link.length", math.nan, "link.length"),
    ("link.length", "long", "link.length"),
    ("link.length", True, "link.length"),
    ("link.length", _DELETE, "link.length"),
    ("link.density", -2700.0, "link.density"),
    ("link.width", _DELETE, "link.width"),
    ("link.flexural_rigidity", 3.0, "link"),  # both descriptions
    ("hub.inertia", -0.1, "hub.inertia"),
    ("hub.inertia", _DELETE, "hub.inertia"),
    ("hub.viscous_damping", -1.0, "hub.viscous_damping"),
    ("hub.coulomb_friction", "high", "hub.coulomb_friction"),
    ("payload.mass", -0.1, "payload.mass"),
    ("payload.inertia", math.inf, "payload.inertia"),
    ("damping.ratio", 1.0, "damping.ratio"),
    ("damping.ratio", -0.01, "damping.ratio"),
    ("model.modes", 0, "model.modes"),
    ("model.modes", 2.5, "model.modes"),
    ("model.modes", 99, "model.modes"),
    ("model.mode_shapes", "fourier", "model.mode_shapes"),
    ("link.colour", "red", "link.colour"),
    ("hub.mass", 1.0, "hub.mass"),
    ("extra", {"a": 1}, "extra"),
    ("name", "a/b", "name"),
    ("name", "", "name"),
    ("link", "steel", "link"),
]


@pytest.mark.parametrize("path,value,key", BAD_CASES)
def test_bad_geometry_names_the_key(path: str, value: Any, key: str) -> None:
    with pytest.raises(GeometryError) as info:
        parse_geometry(with_change(path, value), source="bad.toml")
    assert info.value.key == key
    assert key in str(info.value)
    assert "expected" in str(info.value)


def test_neither_link_description() -> None:
    data = copy.deepcopy(GOOD)
    data["link"] = {"length": 1.0}
    with pytest.raises(GeometryError, match="either flexural_rigidity"):
        parse_geometry(data)


def test_missing_section() -> None:
    data = copy.deepcopy(GOOD)
    del data["hub"]
    with pytest.raises(GeometryError, match=r"\[hub\] is missing"):
        parse_geometry(data)


def test_bad_files(tmp_path: Path) -> None:
    broken = tmp_path / "broken.toml"
    broken.write_text("name = \n")
    with pytest.raises(GeometryError, match="valid TOML"):
        load_geometry(broken)
    with pytest.raises(GeometryError, match="MODEL"):
        load_geometry(tmp_path / "absent.toml")
    with pytest.raises(GeometryError, match="preset"):
        load_geometry("paper-simm")


def test_with_model_overrides() -> None:
    g = load_geometry("paper-sim")
    assert g.with_model(modes=4, mode_shapes="polynomial").modes == 4
    with pytest.raises(GeometryError, match="modes = 0"):  # Python's word: the command line says --modes
        g.with_model(modes=0)
    with pytest.raises(GeometryError, match="mode_shapes = 'bessel'"):
        g.with_model(mode_shapes="bessel")


values = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.integers(min_value=-10**6, max_value=10**6),
    st.text(max_size=5),
    st.booleans(),
    st.none(),
    st.lists(st.integers(), max_size=2),
)
keys = st.sampled_from(
    [
        "link.length",
        "link.youngs_modulus",
        "link.density",
        "link.width",
        "link.thickness",
        "hub.inertia",
        "hub.viscous_damping",
        "hub.coulomb_friction",
        "payload.mass",
        "payload.inertia",
        "damping.ratio",
        "model.modes",
        "model.mode_shapes",
        "name",
        "link.flexural_rigidity",
        "unknown",
    ]
)


@given(st.lists(st.tuples(keys, values), min_size=1, max_size=4))
def test_fuzzed_geometry_gives_geometry_or_typed_error(changes: list[tuple[str, Any]]) -> None:
    data = copy.deepcopy(GOOD)
    for path, value in changes:  # every change applies, on top of the previous ones
        data = with_change(path, value, data)
    try:
        g = parse_geometry(data, source="fuzz")
    except GeometryError as exc:
        assert exc.key and "expected" in str(exc)
        return
    assert isinstance(g, Geometry)
    for attr in ("length", "flexural_rigidity", "linear_density"):
        assert math.isfinite(getattr(g, attr)) and getattr(g, attr) > 0
    # an accepted document is read as written: the last value given to each field is the one used
    last = dict(changes)
    for path, attr in FIELDS.items():
        if path in last and last[path] is not _DELETE:
            assert getattr(g, attr) == last[path], path


FIELDS = {"link.length": "length", "hub.inertia": "hub_inertia", "hub.coulomb_friction": "hub_coulomb_friction",
          "payload.mass": "payload_mass", "damping.ratio": "damping_ratio", "model.modes": "modes",
          "model.mode_shapes": "mode_shapes"}


def test_changes_accumulate() -> None:
    data = with_change("hub.inertia", 0.004, with_change("link.length", 0.9))
    g = parse_geometry(data)
    assert (g.length, g.hub_inertia) == (0.9, 0.004)
    with pytest.raises(GeometryError) as info:  # a bad first change is still there after a good second one
        parse_geometry(with_change("hub.inertia", 0.004, with_change("link.length", -1.0)))
    assert info.value.key == "link.length"


@given(st.dictionaries(st.text(max_size=8), st.one_of(values, st.dictionaries(st.text(max_size=8), values, max_size=3)), max_size=4))
def test_fuzzed_documents_never_raise_raw(doc: dict[str, Any]) -> None:
    with pytest.raises(GeometryError):
        parse_geometry(doc)
