"""One member of the family of redefinitions: the settings that choose it, validated in one place.

The paper's method gives "a family of answers" (its abstract): every segmentation, order
of smooth joining ``h`` and pair of decay constants ``(Cdec_f, Cdec_s)`` gives another
redefined output. :class:`InversionSettings` names one member, checks every value (a bad
one raises :class:`~inversion.errors.SettingsError` naming the key and the accepted
range), and reads and writes the JSON that ``sflm explore`` stores as ``best.json`` and
``sflm invert --settings`` reuses.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np
from numpy.typing import NDArray

from modelgen.files import DocumentError, read_document
from modelgen.paper import PaperCase

from .config import DEFAULTS
from .errors import SettingsError
from .options import Edges, End, Joining, checked, values
from .signals.trajectory import Trajectory

__all__ = ["InversionSettings", "DEFAULT_SETTINGS", "ENDS", "MAX_SEGMENTS", "paper_settings"]

#: Largest number of segments accepted.
MAX_SEGMENTS = 10_000
_KEYS = ("segments", "h", "cdec", "joining", "eps", "end", "edges")
#: How the feedforward ends: the paper's (free), or at rest (its Remark 2).
ENDS = values(End)


def _segments(value: Any) -> int | tuple[float, ...]:
    accepted = f"an integer in 1..{MAX_SEGMENTS} or a list of at least 2 increasing boundaries (s)"
    if isinstance(value, bool):
        raise SettingsError("segments", value, accepted)
    if isinstance(value, (int, np.integer)):
        if not 1 <= int(value) <= MAX_SEGMENTS:
            raise SettingsError("segments", value, accepted)
        return int(value)
    try:
        bounds = tuple(float(v) for v in value)
    except (TypeError, ValueError):
        raise SettingsError("segments", value, accepted) from None
    if len(bounds) < 2 or len(bounds) > MAX_SEGMENTS + 1 or not all(math.isfinite(b) for b in bounds) or any(
        b >= a for a, b in zip(bounds[1:], bounds[:-1])
    ):
        raise SettingsError("segments", list(bounds), accepted)
    return bounds


def _cdec(value: Any) -> tuple[float, float]:
    accepted = "two numbers (Cdec_f, Cdec_s) with 0 < Cdec_f < Cdec_s <= 1"
    try:
        fast, slow = (float(v) for v in value)
    except (TypeError, ValueError):
        raise SettingsError("cdec", value, accepted) from None
    if not (math.isfinite(fast) and math.isfinite(slow) and 0 < fast < slow <= 1):
        raise SettingsError("cdec", value, accepted)
    return fast, slow



def checked_eps(eps: Any) -> float:
    """``eps`` (the margin by which a zero counts as unstable) as a float, or a :class:`SettingsError`.

    Parameters
    ----------
    eps : float
        Zeros with ``Re >= -eps`` count as unstable (1/s).

    Raises
    ------
    SettingsError
        For a value that is not a finite number >= 0.
    """
    if isinstance(eps, bool) or not isinstance(eps, (int, float, np.floating)) or not math.isfinite(eps) or eps < 0:
        raise SettingsError("eps", eps, "a finite number >= 0 (1/s)")
    return float(eps)

@dataclass(frozen=True)
class InversionSettings:
    """A member of the family of redefinitions.

    Parameters
    ----------
    segments : int or tuple of float
        Number of equal segments, or their boundaries ``(t0, ..., tf)`` (Eq. (28)).
    h : int
        Order of smooth joining, Eq. (30): ``yddot~`` matches ``yddot_d`` and its first
        ``h`` derivatives at every joint (``h >= 1``).
    cdec : (float, float)
        ``(Cdec_f, Cdec_s)``: fastest and slowest decay of the exponentials over a
        segment, Eq. (35); ``0 < Cdec_f < Cdec_s <= 1``.
    joining : str
        ``"paper"`` (Eqs. (30)-(31)), ``"position"`` (also ``y~`` and ``ydot~`` at every
        joint) or ``"anchored"`` (also the unstable internal state anchored at every joint);
        see :mod:`inversion.family.ssef`.
    eps : float
        Zeros with ``Re >= -eps`` are treated as unstable (1/s, ``>= 0``).
    end : str
        ``"free"`` (the paper's: the torque stops at ``t_f``), ``"rest"``: the last segment
        also ends on ``y_d(t_f)``, ``ydot_d(t_f)`` with zero deflections and deflection rates,
        so that the torque ends at zero and the plant at rest (the paper's Remark 2;
        :mod:`inversion.family.ssef`), or ``"settle"``: after ``t_f`` the output is held on
        ``y_d(t_f)`` while the internal modes decay (:mod:`inversion.family.settle`; a causal
        post-actuation; with the ``anchored`` joining only, which ends the unstable modes at zero).
    edges : str
        ``"match"`` (the paper's: ``yddot~`` and its first ``h`` derivatives join ``y_d``'s at
        ``t_0`` and ``t_f``) or ``"rest"`` (they join ``yddot_d`` there with the ``h``
        derivatives zero: the torque leaves and reaches rest with zero slope, whatever the move's
        jerk at its ends; :class:`~inversion.options.Edges`).

    Raises
    ------
    SettingsError
        For any value out of range, naming it.

    Examples
    --------
    >>> s = InversionSettings(segments=8, h=2, cdec=(1e-6, 1.0), joining="anchored")
    >>> InversionSettings.from_dict(s.to_dict()) == s
    True
    >>> InversionSettings(joining="glued")
    Traceback (most recent call last):
    ...
    modelgen.errors.SettingsError: joining = 'glued' is not accepted; expected one of paper, position, anchored
    """

    segments: int | tuple[float, ...] = 5
    h: int = 2
    cdec: tuple[float, float] = (1e-4, 1.0)
    joining: str = Joining.ANCHORED  # held as a Joining (a str), checked in __post_init__
    eps: float = DEFAULTS.eps
    end: str = End.FREE  # held as an End
    edges: str = Edges.MATCH  # held as an Edges

    def __post_init__(self) -> None:
        object.__setattr__(self, "segments", _segments(self.segments))
        if isinstance(self.h, bool) or not isinstance(self.h, (int, np.integer)) or not 1 <= int(self.h) <= 20:
            raise SettingsError("h", self.h, "an integer in 1..20")
        object.__setattr__(self, "h", int(self.h))
        object.__setattr__(self, "cdec", _cdec(self.cdec))
        object.__setattr__(self, "joining", checked(Joining, "joining", self.joining))
        object.__setattr__(self, "eps", checked_eps(self.eps))
        object.__setattr__(self, "end", checked(End, "end", self.end))
        object.__setattr__(self, "edges", checked(Edges, "edges", self.edges))
        if self.end == End.SETTLE and self.joining != Joining.ANCHORED:
            raise SettingsError("end", self.end, "'settle' with joining='anchored' (only it ends the unstable internal modes at "
                                "zero, so that the output can be held after t_f); 'free' or 'rest' with this joining")

    @property
    def plan_end(self) -> str:
        """The end the segment systems see: a settle tail follows a free end (the same systems)."""
        return End.REST if self.end == End.REST else End.FREE

    @property
    def segment_count(self) -> int:
        """Number of segments."""
        return self.segments if isinstance(self.segments, int) else len(self.segments) - 1

    def with_changes(self, **changes: Any) -> "InversionSettings":
        """A copy with some values replaced (validated)."""
        return replace(self, **changes)

    def boundaries(self, trajectory: Trajectory, rho: int = 2) -> NDArray[np.float64]:
        """The joints ``t_0 .. t_K`` on ``trajectory``'s interval.

        Parameters
        ----------
        trajectory : Trajectory
            The desired output.
        rho : int
            The relative degree of the system (2 for the link); smooth joining of order
            ``h`` matches ``y^(rho + p)``, ``p <= h``, and needs the trajectory's derivatives up to
            ``h + rho``.

        Raises
        ------
        SettingsError
            If ``h`` needs more derivatives than the trajectory has, or the boundaries do
            not run from ``t0`` to ``tf``.
        """
        t0, tf = trajectory.t0, trajectory.tf
        if trajectory.max_derivative is not None and self.h + rho > trajectory.max_derivative:
            raise SettingsError(
                "h", self.h, f"an integer in 1..{trajectory.max_derivative - rho}: the trajectory {trajectory.name} has "
                f"derivatives up to order {trajectory.max_derivative} and h needs order h + {rho}"
            )
        if isinstance(self.segments, int):
            return np.linspace(t0, tf, self.segments + 1)
        bounds = np.asarray(self.segments, dtype=float)
        if not (
            math.isclose(bounds[0], t0, abs_tol=1e-12 * max(1.0, abs(t0)))
            and math.isclose(bounds[-1], tf, rel_tol=1e-12, abs_tol=1e-12)
        ):
            raise SettingsError(
                "segments", list(bounds), f"strictly increasing finite boundaries from t0 = {t0:g} to tf = {tf:g}"
            )
        bounds[0], bounds[-1] = t0, tf
        return bounds

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready values (``segments`` an integer or a list)."""
        out = asdict(self)
        out["segments"] = self.segments if isinstance(self.segments, int) else list(self.segments)
        out["cdec"] = list(self.cdec)
        return out

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], base: "InversionSettings | None" = None) -> "InversionSettings":
        """Settings from a mapping (``best.json``); missing keys come from ``base``.

        Raises
        ------
        SettingsError
            For an unknown key or a bad value.
        """
        if not isinstance(data, Mapping):
            raise SettingsError("settings", data, "a JSON object with keys " + ", ".join(_KEYS))
        if isinstance(data.get("settings"), Mapping):  # a summary.json: the member is in its "settings"
            return cls.from_dict({k: v for k, v in data["settings"].items() if k in _KEYS}, base)
        unknown = sorted(set(data) - set(_KEYS))
        if unknown:
            raise SettingsError(f"settings key {unknown[0]!r}", data[unknown[0]], "one of " + ", ".join(_KEYS))
        values = (base or cls()).to_dict()
        values.update({k: data[k] for k in _KEYS if k in data})
        segments = values["segments"]
        if isinstance(segments, list) and len(segments) == 1:
            segments = segments[0]
        return cls(
            segments=segments if isinstance(segments, (int, bool)) else tuple(segments),
            h=values["h"],
            cdec=values["cdec"],
            joining=values["joining"],
            eps=values["eps"],
            end=values["end"],
            edges=values["edges"],
        )

    @classmethod
    def from_json(cls, path: str | Path, base: "InversionSettings | None" = None) -> "InversionSettings":
        """Settings from a JSON file (``best.json`` of ``sflm explore``, or a ``summary.json``).

        Raises
        ------
        SettingsError
            For an unreadable file, invalid JSON or bad values.
        """
        try:
            data = read_document(path, "json")
        except OSError as exc:
            raise SettingsError("settings", str(path), f"a readable JSON file ({exc.__class__.__name__})") from None
        except DocumentError as exc:
            raise SettingsError("settings", str(path), f"a JSON member file: this one is {exc}") from None
        if isinstance(data, Mapping) and not (set(data) & set(_KEYS)) and not isinstance(data.get("settings"), Mapping):
            raise SettingsError("settings", str(path), "a member: best.json of sflm explore or a summary.json (an object with "
                                                       "'settings', or some of the keys " + ", ".join(_KEYS) + ")")
        if isinstance(data, Mapping):
            inner = data.get("settings") if isinstance(data.get("settings"), Mapping) else data
            method = data.get("method", inner.get("method", "ssef"))
            if method != "ssef":
                raise SettingsError("settings", str(path), f"a member of the family (a summary or best.json of the sums of exponentials); "
                                    f"this one is of method {method!r}, which has no member to reuse: ask for method={method!r} "
                                    "with its own options instead")
        return cls.from_dict(data, base)


def decide_auto(case: PaperCase | None, explicit: Mapping[str, Any], settings: Any, auto: bool | None) -> bool:
    """Whether an inversion of the family chooses its member automatically: as asked, or -- when ``auto`` is ``None`` --
    unless a member is given (settings, or any value but ``end`` and ``edges``) or the case is the paper's with its own
    free end and matched edges."""
    if auto is not None:
        return bool(auto)
    member_given = any(k not in ("end", "edges") for k in explicit) or settings is not None
    return not member_given and (case is None or explicit.get("end", End.FREE) != End.FREE
                                 or explicit.get("edges", Edges.MATCH) != Edges.MATCH)


#: The library's neutral defaults for a manual member (the paper's cases use their own).
DEFAULT_SETTINGS = InversionSettings()


def describe(settings: InversionSettings | Sequence[Any]) -> str:
    """``"5 segments, h = 2, Cdec = (1e-4, 1), anchored"``."""
    s = settings if isinstance(settings, InversionSettings) else InversionSettings(*settings)
    k = s.segment_count
    end = {"rest": ", rest end", "settle": ", settle end"}.get(str(s.end), "")
    edges = ", rest edges" if s.edges == Edges.REST else ""
    return f"{k} segment{'s' if k != 1 else ''}, h = {s.h}, Cdec = ({s.cdec[0]:g}, {s.cdec[1]:g}), {s.joining}{edges}{end}"


def paper_settings(case: PaperCase) -> InversionSettings:
    """The paper's member of a case (Eqs. (28)-(36)).

    The paper's member of a case: its segments, ``h``, ``Cdec`` and joining (Eqs. (28)-(36)).

    Parameters
    ----------
    case : PaperCase
        A paper case.
    """
    return InversionSettings(segments=case.segments.value, h=case.h.value, cdec=case.cdec.value, joining="paper")
