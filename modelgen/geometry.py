"""Geometry files: the physical description of a single flexible link manipulator.

A geometry is a TOML file in SI units (docs/method.md section 1)::

    name = "my-link"
    [link]
    length = 0.6
    # either flexural_rigidity (N m^2) and linear_density (kg/m),
    # or youngs_modulus (Pa), density (kg/m^3), width (m), thickness (m)
    youngs_modulus = 69e9
    density = 2700
    width = 0.03
    thickness = 0.002
    [hub]
    inertia = 0.002          # kg m^2
    viscous_damping = 0.0    # N m s/rad (optional)
    coulomb_friction = 0.0   # N m       (optional)
    [payload]                # optional
    mass = 0.05
    inertia = 2e-5
    [damping]                # optional
    ratio = 0.0              # Rayleigh: damping ratio of the first flexible mode (or modal = [z1, z2, ...])
    [model]                  # optional
    modes = 2
    mode_shapes = "clamped-mass"

Every value is validated; a bad file raises :class:`~modelgen.errors.GeometryError`
naming the key, the value and what is accepted.
"""

from __future__ import annotations

import math
import re
from dataclasses import asdict, dataclass, replace
from importlib import resources
from pathlib import Path
from typing import Any, Mapping

from .errors import GeometryError
from .files import DocumentError, read_document

__all__ = [
    "Geometry",
    "MODE_FAMILIES",
    "MAX_MODES",
    "PRESETS",
    "load_geometry",
    "parse_geometry",
    "preset_names",
    "preset_path",
    "PARAMETER_KEYS",
    "is_parameter_key",
    "modal_mode",
    "parameter_value",
    "scaled",
    "relative_values",
]

#: Mode-shape families offered (docs/method.md section 1, "Mode shapes").
MODE_FAMILIES: tuple[str, ...] = ("clamped-mass", "clamped-free", "polynomial")
#: Largest number of assumed modes accepted.
MAX_MODES = 20

#: Shipped presets (TOML files inside the package); users copy them.
PRESETS: tuple[str, ...] = ("paper-sim", "paper-exp", "hyperbolic", "near-non-hyperbolic")

_POSITIVE = "a finite number > 0"
_NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}")
_NAME_ACCEPTED = "a name of letters, digits, '.', '_' or '-' (at most 64, used in folder names)"
_NONNEG = "a finite number >= 0"

#: The geometry's parameters by their dotted names (what `--uncertainty` and `sflm fit --params` take) and their fields.
PARAMETER_KEYS: dict[str, str] = {
    "link.length": "length",
    "link.flexural_rigidity": "flexural_rigidity",
    "link.linear_density": "linear_density",
    "hub.inertia": "hub_inertia",
    "hub.viscous_damping": "hub_viscous_damping",
    "hub.coulomb_friction": "hub_coulomb_friction",
    "payload.mass": "payload_mass",
    "payload.inertia": "payload_inertia",
    "damping.ratio": "damping_ratio",
}

#: A modal damping ratio's key: ``damping.modal_K``, mode ``K``'s ratio (``[damping] modal``, the list's last for the
#: modes after it).
_MODAL_KEY = re.compile(r"damping\.modal_([1-9][0-9]*)")


def modal_mode(key: str) -> int | None:
    """The mode a ``damping.modal_K`` key names.

    Its ``K``; None for another key.

    Parameters
    ----------
    key : str
        A parameter's dotted name.
    """
    match = _MODAL_KEY.fullmatch(key)
    return int(match.group(1)) if match else None


def is_parameter_key(key: str) -> bool:
    """Whether ``key`` names a parameter of a geometry.

    A dotted name of :data:`PARAMETER_KEYS`, or ``damping.modal_K`` for a mode ``K`` up to :data:`MAX_MODES`.

    Parameters
    ----------
    key : str
        A parameter's dotted name.
    """
    mode = modal_mode(key)
    return key in PARAMETER_KEYS or (mode is not None and mode <= MAX_MODES)


def parameter_value(geometry: "Geometry", key: str) -> float:
    """The value ``key`` names in ``geometry``.

    A field of :data:`PARAMETER_KEYS`, or mode ``K``'s modal damping ratio (zero for Rayleigh damping).

    Parameters
    ----------
    geometry : Geometry
        The link.
    key : str
        A parameter's dotted name (:func:`is_parameter_key`).
    """
    if key in PARAMETER_KEYS:
        return float(getattr(geometry, PARAMETER_KEYS[key]))
    mode = modal_mode(key)
    assert mode is not None, key
    ratios = geometry.modal_ratios(mode)
    return float(ratios[-1]) if ratios else 0.0


def relative_values(spec: str, option: str, accepted: str, low: float, high: float, zero: bool = False) -> list[tuple[str, float]]:
    """Geometry keys with relative values, from ``KEY=R[,KEY=R...]``.

    Each key with its relative value (``10%`` or ``0.1``), in the order given. What ``--uncertainty`` (a parameter's
    range) and ``sflm fit --held-spread`` (a held parameter's plausible error) take.

    Parameters
    ----------
    spec : str
        The list, e.g. ``link.flexural_rigidity=10%,payload.mass=0.2``.
    option : str
        The option's name, for the messages (``"uncertainty"``).
    accepted : str
        What a value may be, in words (the messages' accepted range).
    low, high : float
        A value must be above ``low`` (at least, with ``zero``) and below ``high``.
    zero : bool, optional
        Whether ``low`` itself is accepted.

    Raises
    ------
    SettingsError
        For an item that is not ``KEY=R``, a key that names no parameter (:func:`is_parameter_key`), a value out of range,
        a key given twice.
    """
    from .errors import SettingsError

    if not isinstance(spec, str) or not spec.strip():
        raise SettingsError(option, spec, "KEY=RANGE[,KEY=RANGE...], e.g. link.flexural_rigidity=10%,payload.mass=20%")
    values: list[tuple[str, float]] = []
    for item in spec.split(","):
        key, sep, value = item.strip().partition("=")
        key = key.strip()
        if not is_parameter_key(key):
            raise SettingsError(f"{option} key", key, "one of " + ", ".join(PARAMETER_KEYS) + f", or damping.modal_K (K = 1.."
                                f"{MAX_MODES}: a geometry damped per mode)")
        if not sep:
            raise SettingsError(f"{option} {key}", item, "KEY=RANGE with a range such as 10%")
        text = value.strip()
        try:
            fraction = float(text[:-1]) / 100.0 if text.endswith("%") else float(text)
        except ValueError:
            raise SettingsError(f"{option} {key}", value, "a relative range such as 10% or 0.1") from None
        if not (math.isfinite(fraction) and (low <= fraction if zero else low < fraction) and fraction < high):
            raise SettingsError(f"{option} {key}", value, accepted)
        if any(k == key for k, _ in values):
            raise SettingsError(f"{option} key", key, "each key once")
        values.append((key, fraction))
    return values


def scaled(geometry: "Geometry", factors: Mapping[str, float]) -> "Geometry":
    """``geometry`` with each named parameter multiplied by its factor.

    Exactly the geometry an edited file gives. Modal ratios: the list made as long as the highest mode named (the last
    ratio repeated for the modes between), each named mode's ratio multiplied by its own factor.

    Parameters
    ----------
    geometry : Geometry
        The link.
    factors : Mapping[str, float]
        Multipliers by dotted name (:func:`is_parameter_key`).
    """
    changes: dict[str, Any] = {PARAMETER_KEYS[k]: getattr(geometry, PARAMETER_KEYS[k]) * float(f)
                               for k, f in factors.items() if k in PARAMETER_KEYS}
    modal = {modal_mode(k): float(f) for k, f in factors.items() if k not in PARAMETER_KEYS}
    if modal:
        ratios = list(geometry.modal_ratios(max(len(geometry.modal_damping), *(m for m in modal if m is not None))))
        for mode, factor in modal.items():
            assert mode is not None
            ratios[mode - 1] *= factor
        changes["modal_damping"] = tuple(ratios)
    return replace(geometry, **changes)

# section -> key -> (required, accepted-description, unit)
_SCHEMA: dict[str, dict[str, tuple[bool, str, str]]] = {
    "link": {
        "length": (True, _POSITIVE, "m"),
        "flexural_rigidity": (False, _POSITIVE, "N m^2"),
        "linear_density": (False, _POSITIVE, "kg/m"),
        "youngs_modulus": (False, _POSITIVE, "Pa"),
        "density": (False, _POSITIVE, "kg/m^3"),
        "width": (False, _POSITIVE, "m"),
        "thickness": (False, _POSITIVE, "m"),
    },
    "hub": {
        "inertia": (True, _NONNEG, "kg m^2"),
        "viscous_damping": (False, _NONNEG, "N m s/rad"),
        "coulomb_friction": (False, _NONNEG, "N m"),
    },
    "payload": {
        "mass": (False, _NONNEG, "kg"),
        "inertia": (False, _NONNEG, "kg m^2"),
    },
    "damping": {
        "ratio": (False, "a finite number in [0, 1)", ""),
        "modal": (False, "a list of ratios in [0, 1), one per flexible mode (the last for the modes after it)", ""),
    },
    "drive": {
        "max_torque": (False, _POSITIVE, "N m"),
        "max_torque_rate": (False, _POSITIVE, "N m a row"),
    },
    "model": {
        "modes": (False, f"an integer in 1..{MAX_MODES}", ""),
        "mode_shapes": (False, "one of " + ", ".join(repr(f) for f in MODE_FAMILIES), ""),
    },
}
_REQUIRED_SECTIONS = ("link", "hub")
_DIRECT = ("flexural_rigidity", "linear_density")
_MATERIAL = ("youngs_modulus", "density", "width", "thickness")


@dataclass(frozen=True)
class Geometry:
    """Physical parameters of a single flexible link manipulator (SI).

    Attributes
    ----------
    name : str
        Short name, used for output folders.
    length : float
        Link length ``L`` (m).
    flexural_rigidity : float
        ``EI`` (N m^2).
    linear_density : float
        ``rho`` (kg/m).
    hub_inertia : float
        ``I_h`` (kg m^2).
    hub_viscous_damping : float
        ``b_h`` (N m s/rad), acts on the joint angle only.
    hub_coulomb_friction : float
        ``F_c`` (N m), dry friction on the joint; used by the simulation only.
    payload_mass, payload_inertia : float
        Tip payload ``m_t`` (kg) and ``I_t`` (kg m^2).
    damping_ratio : float
        ``zeta`` of Rayleigh damping, Eq. (7).
    modal_damping : tuple of float
        Modal damping instead: the ratio of each flexible mode of the linear model (hub free), the last for the modes
        after it; empty for Rayleigh damping (the two forms are exclusive).
    modes : int
        Number of assumed modes ``n``.
    mode_shapes : str
        Mode-shape family, one of :data:`MODE_FAMILIES`.
    source : str
        Where the geometry came from (preset name or file path).
    drive_max_torque : float or None
        The drive's largest torque (N m; ``[drive] max_torque``): the bound every result is judged by where none is given.
    drive_max_torque_rate : float or None
        The drive's largest change of torque from one controller's row to the next (N m a row; ``[drive]
        max_torque_rate``), likewise.
    """

    name: str
    length: float
    flexural_rigidity: float
    linear_density: float
    hub_inertia: float
    hub_viscous_damping: float = 0.0
    hub_coulomb_friction: float = 0.0
    payload_mass: float = 0.0
    payload_inertia: float = 0.0
    damping_ratio: float = 0.0
    modal_damping: tuple[float, ...] = ()
    modes: int = 2
    mode_shapes: str = "clamped-mass"
    source: str = "<memory>"
    drive_max_torque: float | None = None
    drive_max_torque_rate: float | None = None

    def __post_init__(self) -> None:
        checks: list[tuple[str, float, bool]] = [
            ("link.length", self.length, True),
            ("link.flexural_rigidity", self.flexural_rigidity, True),
            ("link.linear_density", self.linear_density, True),
            ("hub.inertia", self.hub_inertia, False),
            ("hub.viscous_damping", self.hub_viscous_damping, False),
            ("hub.coulomb_friction", self.hub_coulomb_friction, False),
            ("payload.mass", self.payload_mass, False),
            ("payload.inertia", self.payload_inertia, False),
        ]
        checks += [(key, value, True) for key, value in (("drive.max_torque", self.drive_max_torque),
                                                         ("drive.max_torque_rate", self.drive_max_torque_rate)) if value is not None]
        for key, value, positive in checks:
            _check_number(key, value, positive, self.source)
        _check_ratio("damping.ratio", self.damping_ratio, self.source)
        _check_modal(self.modal_damping, self.damping_ratio, self.source)
        _check_modes("model.modes", self.modes, self.source)
        _check_family("model.mode_shapes", self.mode_shapes, self.source)
        if not isinstance(self.name, str) or not _NAME.fullmatch(self.name):
            raise GeometryError("name", self.name, _NAME_ACCEPTED, self.source)

    def modal_ratios(self, count: int) -> tuple[float, ...]:
        """The modal damping ratios of the first ``count`` flexible modes.

        The modal damping ratios of the first ``count`` flexible modes (the list's last for those after it); empty for
        Rayleigh damping.

        Parameters
        ----------
        count : int
            Number of flexible modes.
        """
        if not self.modal_damping:
            return ()
        return tuple(self.modal_damping[min(i, len(self.modal_damping) - 1)] for i in range(count))

    def with_model(self, modes: int | None = None, mode_shapes: str | None = None) -> "Geometry":
        """A copy with model options overridden (``None`` keeps one).

        Parameters
        ----------
        modes : int, optional
            Number of assumed modes, ``1..MAX_MODES``.
        mode_shapes : str, optional
            Mode-shape family (:data:`MODE_FAMILIES`).

        Raises
        ------
        GeometryError
            If ``modes`` is not an integer in ``1..MAX_MODES`` or ``mode_shapes`` is unknown.
        """
        if modes is not None:
            _check_modes("modes", modes, self.source)
        if mode_shapes is not None:
            _check_family("mode_shapes", mode_shapes, self.source)
        return replace(
            self,
            modes=self.modes if modes is None else int(modes),
            mode_shapes=self.mode_shapes if mode_shapes is None else mode_shapes,
        )

    @property
    def payload_mass_ratio(self) -> float:
        """``m_t / (rho L)``: payload mass over link mass."""
        return self.payload_mass / (self.linear_density * self.length)

    @property
    def payload_inertia_ratio(self) -> float:
        """``I_t / (rho L^3)``: payload inertia over the link's ``rho L^3``."""
        return self.payload_inertia / (self.linear_density * self.length**3)

    def as_dict(self) -> dict[str, Any]:
        """All attributes as a plain dictionary (JSON-serialisable)."""
        return asdict(self)


def _is_number(value: Any) -> bool:
    """A TOML number a double holds (an integer of 400 digits is not: it overflowed in the checks)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        float(value)
    except OverflowError:
        return False
    return True


def _check_number(key: str, value: Any, positive: bool, source: str | None) -> None:
    accepted = _POSITIVE if positive else _NONNEG
    if not _is_number(value) or not math.isfinite(value):
        raise GeometryError(key, value, accepted, source)
    if value < 0 or (positive and value == 0):
        raise GeometryError(key, value, accepted, source)


def _check_ratio(key: str, value: Any, source: str | None) -> None:
    if not _is_number(value) or not math.isfinite(value) or not 0 <= value < 1:
        raise GeometryError(key, value, "a finite number in [0, 1)", source)


def _check_modal(value: Any, ratio: float, source: str | None) -> None:
    accepted = f"a list of 1..{MAX_MODES} ratios in [0, 1), one per flexible mode (the last for the modes after it)"
    if not isinstance(value, (tuple, list)) or len(value) > MAX_MODES:
        raise GeometryError("damping.modal", value, accepted, source)
    for i, item in enumerate(value):
        _check_ratio(f"damping.modal[{i}]", item, source)
    if value and ratio:
        raise GeometryError("damping", {"ratio": ratio, "modal": list(value)}, "one damping form: ratio (Rayleigh: the first "
                            "mode's, stiffness-proportional) or modal (a ratio per mode), not both", source)


def _check_modes(key: str, value: Any, source: str | None) -> None:
    is_int = isinstance(value, int) and not isinstance(value, bool)
    if not is_int or not 1 <= value <= MAX_MODES:
        raise GeometryError(key, value, f"an integer in 1..{MAX_MODES}", source)


def _check_family(key: str, value: Any, source: str | None) -> None:
    if value not in MODE_FAMILIES:
        raise GeometryError(key, value, "one of " + ", ".join(repr(f) for f in MODE_FAMILIES), source)


def _modal(value: Any, source: str) -> tuple[float, ...]:
    if not isinstance(value, (list, tuple)) or (isinstance(value, list) and not value):
        raise GeometryError("damping.modal", value, f"a list of 1..{MAX_MODES} ratios in [0, 1), one per flexible mode", source)
    return tuple(value)


def parse_geometry(data: Mapping[str, Any], source: str = "<memory>") -> Geometry:
    """Validate a geometry mapping (as read from TOML) into a Geometry.

    Parameters
    ----------
    data : Mapping
        The parsed TOML document.
    source : str
        Name of the origin, quoted in error messages.

    Returns
    -------
    Geometry

    Raises
    ------
    GeometryError
        For a missing or unknown key, a non-numeric, non-finite or out-of-range value,
        or when both or neither of the two link descriptions are given.
    """
    if not isinstance(data, Mapping):
        raise GeometryError("<document>", data, "a TOML table", source)
    allowed_top = {"name", "calibration", *(_SCHEMA)}  # calibration: what `sflm fit` recorded (modelgen.fit), not read
    for key in data:
        if key not in allowed_top:
            raise GeometryError(key, data[key], "one of the keys " + ", ".join(sorted(allowed_top)), source)
    if "calibration" in data and not isinstance(data["calibration"], Mapping):
        raise GeometryError("calibration", data["calibration"], "a table (written by sflm fit)", source)
    name = data.get("name", Path(source).stem if source and source != "<memory>" else None)
    if not isinstance(name, str) or not _NAME.fullmatch(name):
        raise GeometryError("name", name, _NAME_ACCEPTED, source)

    sections: dict[str, Mapping[str, Any]] = {}
    for section, keys in _SCHEMA.items():
        table = data.get(section)
        if table is None:
            if section in _REQUIRED_SECTIONS:
                raise GeometryError(f"[{section}]", None, f"a [{section}] table", source)
            table = {}
        if not isinstance(table, Mapping):
            raise GeometryError(section, table, f"a [{section}] table", source)
        for key, value in table.items():
            if key not in keys:
                raise GeometryError(
                    f"{section}.{key}", value, f"one of [{section}]'s keys: {', '.join(f'{section}.{k}' for k in keys)}", source
                )
        for key, (required, _accepted, _unit) in keys.items():
            if required and key not in table:
                raise GeometryError(f"{section}.{key}", None, keys[key][1], source)
        sections[section] = table

    link = sections["link"]
    for key in link:
        if key != "length":
            _check_number(f"link.{key}", link[key], True, source)
    _check_number("link.length", link["length"], True, source)
    direct = [k for k in _DIRECT if k in link]
    material = [k for k in _MATERIAL if k in link]
    both_msg = (
        "either flexural_rigidity and linear_density, or youngs_modulus, density, width "
        "and thickness (not both)"
    )
    if direct and material:
        raise GeometryError("link", f"{', '.join(direct + material)}", both_msg, source)
    if not direct and not material:
        raise GeometryError("link.flexural_rigidity", None, both_msg, source)
    if direct:
        missing = [k for k in _DIRECT if k not in link]
        if missing:
            raise GeometryError(f"link.{missing[0]}", None, f"{_POSITIVE} together with link.{direct[0]}", source)
        flexural_rigidity = float(link["flexural_rigidity"])
        linear_density = float(link["linear_density"])
    else:
        missing = [k for k in _MATERIAL if k not in link]
        if missing:
            raise GeometryError(
                f"link.{missing[0]}", None, f"{_POSITIVE} (youngs_modulus, density, width and thickness go together)", source
            )
        width = float(link["width"])
        thickness = float(link["thickness"])
        flexural_rigidity = float(link["youngs_modulus"]) * width * thickness**3 / 12.0
        linear_density = float(link["density"]) * width * thickness

    hub = sections["hub"]
    payload = sections["payload"]
    damping = sections["damping"]
    model = sections["model"]
    drive = sections["drive"]
    for key, value in drive.items():
        _check_number(f"drive.{key}", value, True, source)
    for key, value in hub.items():
        _check_number(f"hub.{key}", value, False, source)
    for key, value in payload.items():
        _check_number(f"payload.{key}", value, False, source)
    return Geometry(
        name=name,
        length=float(link["length"]),
        flexural_rigidity=flexural_rigidity,
        linear_density=linear_density,
        hub_inertia=float(hub["inertia"]),
        hub_viscous_damping=float(hub.get("viscous_damping", 0.0)),
        hub_coulomb_friction=float(hub.get("coulomb_friction", 0.0)),
        payload_mass=float(payload.get("mass", 0.0)),
        payload_inertia=float(payload.get("inertia", 0.0)),
        damping_ratio=damping.get("ratio", 0.0),
        modal_damping=_modal(damping.get("modal", ()), source),
        modes=model.get("modes", 2),
        mode_shapes=model.get("mode_shapes", "clamped-mass"),
        source=source,
        drive_max_torque=None if "max_torque" not in drive else float(drive["max_torque"]),
        drive_max_torque_rate=None if "max_torque_rate" not in drive else float(drive["max_torque_rate"]),
    )


def preset_names() -> tuple[str, ...]:
    """Names of the shipped presets."""
    return PRESETS


def preset_path(name: str) -> Path:
    """Path of a shipped preset's TOML file.

    Path of a shipped preset's TOML file (copy it to start a geometry of your own).

    Parameters
    ----------
    name : str
        A preset's name (:data:`~modelgen.geometry.PRESETS`).
    """
    if name not in PRESETS:
        raise GeometryError("MODEL", name, "a preset (" + ", ".join(PRESETS) + ") or a .toml geometry file")
    return Path(str(resources.files("modelgen") / "presets" / f"{name}.toml"))


def load_geometry(model: str | Path | Geometry) -> Geometry:
    """A geometry from a preset name, a TOML file or a Geometry.

    Parameters
    ----------
    model : str, Path or Geometry
        A preset name (see :data:`PRESETS`) or the path of a geometry file.

    Returns
    -------
    Geometry

    Raises
    ------
    GeometryError
        If the name is neither a preset nor a readable TOML file, or the file is invalid.

    Examples
    --------
    >>> load_geometry("paper-sim").length
    1.005
    """
    if isinstance(model, Geometry):
        return model
    text_name = str(model)
    if isinstance(model, str) and model in PRESETS:
        path = preset_path(model)
        source = model
    else:
        path = Path(model)
        source = str(model)
        if not path.is_file():
            raise GeometryError(
                "MODEL", text_name, "a preset (" + ", ".join(PRESETS) + ") or an existing .toml geometry file"
            )
    try:
        data = read_document(path, "toml")
    except DocumentError as exc:
        raise GeometryError("<file>", source, f"a readable TOML geometry file: this one is {exc}", source) from None
    except OSError as exc:
        raise GeometryError("<file>", source, f"a readable TOML file ({exc.__class__.__name__})", source) from None
    return parse_geometry(data, source=source)
