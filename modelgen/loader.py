"""``modelgen.load``: geometry -> mode shapes -> model functions -> :class:`Model`."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from .errors import GeometryError
from .geometry import Geometry, load_geometry
from .interface import CompiledFunctions
from .model import Model, natural_frequencies
from .modes import ModalConstants, ModeShapes, modal_constants
from .modes import mode_shapes as make_mode_shapes
from .paper import preset_case
from .parameters import parameter_names, parameter_values

__all__ = ["load", "load_with_shapes", "build_model", "output_location", "MatrixBackend"]


#: What :func:`build_model` needs from a backend (kept under its former name).
MatrixBackend = CompiledFunctions


def output_location(geometry: Geometry, output_at: Any) -> float:
    """``output_at`` validated against the link (``None``: the tip).

    ``output_at`` validated against the link: a number ``0 < x <= L`` (``None``: the tip, ``L``).

    Parameters
    ----------
    geometry : Geometry
        The link.
    output_at : Any
        The position given (m from the hub), or ``None``.

    Raises
    ------
    GeometryError
        Naming ``output_at`` and the accepted range.
    """
    L = geometry.length
    if output_at is None:
        return float(L)
    if isinstance(output_at, bool) or not isinstance(output_at, (int, float, np.integer, np.floating)):
        raise GeometryError("output_at", output_at, f"a number of metres in (0, {L:g}] (the link length)", geometry.name)
    x = float(output_at)
    if not (math.isfinite(x) and 0.0 < x <= L * (1 + 1e-12)):
        raise GeometryError("output_at", output_at, f"a number of metres in (0, {L:g}] (0: the hub, {L:g}: the tip)", geometry.name)
    return min(x, float(L))


def build_model(
    geometry: Geometry, shapes: ModeShapes, constants: ModalConstants, functions: CompiledFunctions,
    output_at: float | None = None,
) -> Model:
    """Evaluate ``functions`` for a geometry and wrap them in a Model.

    ``omega_1`` of Rayleigh damping (Eq. (7)) is the first flexible natural frequency of
    ``(K_B, M)``, which do not depend on it: they are evaluated first (and give modal damping's matrix,
    :func:`modelgen.damping.modal_damping_matrix`, where the geometry has one). ``output_at``: where
    along the link the output ``y = x theta + w(x)`` is measured (default the tip).

    Parameters
    ----------
    geometry : Geometry
        The link.
    shapes : ModeShapes
        The assumed mode shapes.
    constants : ModalConstants
        Their modal constants.
    functions : CompiledFunctions
        The compiled model functions.
    output_at : float | None, optional
        Where the output is measured (m from the hub; ``None``: the tip).
    """
    x = output_location(geometry, output_at)
    output = None if x == geometry.length else (x, np.asarray(shapes(np.array([x]), 0)[:, 0], dtype=float))
    p = parameter_values(geometry, constants, omega_1=1.0, output=output)
    first = functions.matrices(p)
    omega_1 = float(natural_frequencies(first["K"], first["M"])[0])
    modal = None
    if geometry.modal_damping:
        from .damping import modal_damping_matrix

        modal = modal_damping_matrix(np.asarray(first["M"]), np.asarray(first["K"]), geometry.modal_ratios(shapes.n))
    p = parameter_values(geometry, constants, omega_1=omega_1, output=output, modal=modal)
    mats = functions.matrices(p)
    return Model(
        geometry=geometry,
        shapes=shapes,
        constants=constants,
        parameter_names=tuple(parameter_names(shapes.n)),
        parameters=p,
        M=mats["M"],
        K=mats["K"],
        C=mats["C"],
        D=mats["D"],
        H=mats["H"],
        A=mats["A"],
        B=mats["B"],
        C_out=mats["C_out"],
        CAB=float(mats["CAB"]),
        CA2=mats["CA2"],
        AI=mats["AI"],
        BI=mats["BI"],
        T=mats["T"],
        Tinv=mats["Tinv"],
        functions=functions,
        case=preset_case(geometry, x),
    )


def load(
    model: str | Path | Geometry,
    modes: int | None = None,
    mode_shapes: str | None = None,
    output_at: float | None = None,
) -> Model:
    """Load a model for a preset, a geometry file or a Geometry.

    Parameters
    ----------
    model : str, Path or Geometry
        A preset (``"paper-sim"``, ``"paper-exp"``, ``"hyperbolic"``,
        ``"near-non-hyperbolic"``) or a TOML geometry file.
    modes : int, optional
        Number of assumed modes (overrides the geometry's ``[model] modes``).
    mode_shapes : str, optional
        Mode-shape family (overrides ``[model] mode_shapes``).
    output_at : float, optional
        Where the output is measured, ``0 < x <= L`` (m): ``y = x theta + w(x)``. Default
        the tip, ``L`` (the paper's). The zeros move from non-minimum-phase at the tip
        towards minimum-phase near the hub. The same compiled library serves every ``x``.

    Returns
    -------
    Model

    Raises
    ------
    GeometryError
        For an unknown preset, a missing file or invalid geometry values.
    CodegenError
        If the model cannot be generated or loaded.

    Notes
    -----
    The first load of an ``n``-mode model derives it with SymPy (the Lagrange equations
    as :obj:`sympy.matrices.dense.Matrix`, :mod:`modelgen.lagrange`), generates C with
    CasADi's :class:`casadi.CodeGenerator` and compiles it (a few seconds); later loads,
    for any geometry with ``n`` modes, reuse the cached library (:func:`casadi.external`)
    without importing SymPy.

    Examples
    --------
    >>> m = load("paper-sim")
    >>> m.n_unstable, m.internal_dynamics
    (3, 'non-hyperbolic')
    """
    geometry = load_geometry(model).with_model(modes, mode_shapes)
    output_location(geometry, output_at)  # before anything is derived or compiled
    return load_with_shapes(geometry, make_mode_shapes(geometry), output_at)


def load_with_shapes(geometry: Geometry, shapes: ModeShapes, output_at: float | None = None) -> Model:
    """The model of ``geometry`` built on given shapes.

    Build the model of ``geometry`` on given shapes (e.g. rescaled ones), measured at ``output_at`` (default the tip).

    The model functions come from the compiled-model cache (generated and compiled on
    first use for this number of modes; see :mod:`modelgen.cache`).

    Parameters
    ----------
    geometry : Geometry
        The link.
    shapes : ModeShapes
        The assumed mode shapes.
    output_at : float | None, optional
        Where the output is measured (m from the hub; ``None``: the tip).
    """
    from .cache import ensure_model_functions

    constants = modal_constants(shapes)
    return build_model(geometry, shapes, constants, ensure_model_functions(shapes.n), output_at)
