"""``sflm info``: a model's matrices, frequencies, zeros and their convergence with n."""

from __future__ import annotations

import textwrap
from typing import Any

import numpy as np

from modelgen.convergence import Convergence
from modelgen.model import MATRIX_NAMES, Model
from modelgen.paper import TRUNCATION_NOTE, shipped_case

from .formatting import array_text, fmt, table, zero_pairs

__all__ = ["info_text", "convergence_text", "convergence_json"]


def _reported(geometry: Any) -> tuple[str, dict[str, Any]] | None:
    """Where the paper reports a preset's zeros and what it reports (``None``: it does not, or the geometry is not the
    preset as shipped: a file of the same name with other values is another link)."""
    case = shipped_case(geometry)
    if case is None or "zeros" not in case.reported:
        return None
    where = f"{case.reported['zeros'].source} ({case.modes} mode{'s' if case.modes != 1 else ''})"
    return where, {k: v.value for k, v in case.reported.items()}


def _status_lines(status: Any) -> list[str]:
    """The zeros judged against the continuum (:mod:`modelgen.zero_status`)."""
    def listed(mask: Any) -> str:
        return ", ".join(zero_pairs(status.zeros[mask])) or "none"

    unconverged = ~status.converged & ~status.artefact
    return [
        f"  against the continuum (finite elements, relative tolerance {status.tol:g}):",
        f"    converged         {listed(status.converged)}",
        f"    not yet           {listed(unconverged)}",
        f"    artefacts         {listed(status.artefact)} (complex where the continuum has none: truncation)",
        f"    unstable          {status.n_unstable} counted, {status.n_unstable_converged} converged, "
        f"{status.n_unstable_without_artefacts} without the artefacts"
        + (" (sflm invert --zeros physical leaves the artefacts free)" if status.n_unstable_without_artefacts < status.n_unstable else ""),
    ]


def info_text(model: Model, matrices: bool = False, status: Any = None) -> str:
    """Readable summary of a model (``sflm info``).

    Readable summary of a model (``sflm info``); ``status``: its :class:`~modelgen.zero_status.ZeroStatus`.

    Parameters
    ----------
    model : Model
        A loaded model.
    matrices : bool, optional
        Whether to print the matrices.
    status : Any, optional
        Its zeros' status, if judged.
    """
    g = model.geometry
    lines = [
        f"{model.name}: {model.n} {model.mode_family} mode{'s' if model.n > 1 else ''} (from {g.source})",
        f"  link      L = {fmt(g.length)} m, EI = {fmt(g.flexural_rigidity)} N m^2, rho = {fmt(g.linear_density)} kg/m",
        f"  hub       I_h = {fmt(g.hub_inertia)} kg m^2, b_h = {fmt(g.hub_viscous_damping)} N m s/rad, "
        f"F_c = {fmt(g.hub_coulomb_friction)} N m",
        f"  payload   m_t = {fmt(g.payload_mass)} kg, I_t = {fmt(g.payload_inertia)} kg m^2",
        (f"  damping   zeta = {', '.join(fmt(r) for r in g.modal_ratios(model.n))} (modal, one per flexible mode)" if g.modal_damping
         else f"  damping   zeta = {fmt(g.damping_ratio)} (Rayleigh, first flexible mode)"),
        f"  output    y = x theta + w(x) at x = {fmt(model.output_at)} m"
        + (" (the tip)" if model.output_at == g.length else f" ({model.output_at / g.length:.3g} L; --output-at)"),
        "",
    ]
    rows: list[list[Any]] = []
    if model.shapes.betas.size:
        rows.append(["b_j L", *[f"{b:.5f}" for b in model.shapes.betas]])
    rows.append(["natural frequencies (Hz)", *[f"{f:.4f}" for f in model.natural_frequencies_hz]])
    lines.append(table(["quantity", *[f"mode {j + 1}" for j in range(model.n)]], rows))
    lines += [
        "",
        f"  zeros             {', '.join(zero_pairs(model.zeros))}",
        f"  internal dynamics {model.internal_dynamics}, {model.n_unstable} unstable zero"
        f"{'s' if model.n_unstable != 1 else ''} (Re >= 0, imaginary ones included)",
        f"  CAB               {model.CAB:.6g}  (relative degree 2)",
    ]
    if status is not None:
        lines += _status_lines(status)
    reported = _reported(g) if model.output_at == g.length else None  # the paper measures at the tip
    if reported is not None:
        where, paper = reported
        pz = ", ".join(zero_pairs(np.array(paper["zeros"], dtype=complex), digits=2))
        lines += [
            "",
            f"  paper, {where}: zeros {pz}, {paper['n_unstable']} unstable",
        ]
        if "second_frequency_hz" in paper:
            lines.append(f"    second natural frequency {paper['second_frequency_hz']:g} Hz (ours with 2 modes: sflm info {model.name} --modes 2)")
        lines += textwrap.wrap(TRUNCATION_NOTE, 88, initial_indent="    ", subsequent_indent="    ")
    if matrices:
        for name in MATRIX_NAMES:
            lines += ["", f"{name} =", array_text(getattr(model, name))]
    return "\n".join(lines)


def convergence_text(conv: Convergence) -> str:
    """Frequencies and zeros for n = 1..N beside the reference.

    Frequencies and lowest zeros for n = 1..N beside the finite-element reference.

    Parameters
    ----------
    conv : Convergence
        The convergence study.
    """
    ref = conv.reference
    header = ["n", "f1 (Hz)", "f2 (Hz)", "f3 (Hz)", "lowest zeros"]
    rows: list[list[Any]] = []
    for m in conv.models:
        f = list(m.natural_frequencies_hz[:3])
        cells = [f"{v:.4f}" for v in f] + ["-"] * (3 - len(f))
        rows.append([m.n, *cells, ", ".join(zero_pairs(m.zeros[:4]))])
    rows.append(
        [
            "FE",
            *[f"{v:.4f}" for v in ref.natural_frequencies_hz[:3]],
            ", ".join(zero_pairs(ref.zeros[:4])),
        ]
    )
    last = conv.models[-1]
    k = min(3, last.n)
    fdev = np.abs(last.natural_frequencies_hz[:k] / ref.natural_frequencies_hz[:k] - 1)
    zl = last.zeros[:4]
    zdev = [float(np.min(np.abs(ref.zeros - z)) / abs(z)) for z in zl]
    lines = [
        f"{conv.geometry.name}: convergence of the {conv.geometry.mode_shapes} assumed-mode model with n",
        table(header, rows),
        "",
        f"FE: converged finite-element reference ({ref.elements} cubic Hermite elements; estimated error "
        f"{ref.frequency_error_hz.max():.1e} Hz, zeros {ref.zero_error[:4].max():.1e} 1/s)",
        f"n = {last.n}: frequencies differ from FE by "
        + ", ".join(f"{100 * d:.3f}%" for d in fdev)
        + "; lowest zeros by "
        + ", ".join(f"{100 * d:.3f}%" for d in zdev),
    ]
    reported = _reported(conv.geometry)
    if reported is not None:
        where, paper = reported
        pz = ", ".join(zero_pairs(np.array(paper["zeros"], dtype=complex), digits=2))
        lines += ["", f"paper, {where}: zeros {pz}.", *textwrap.wrap(TRUNCATION_NOTE, 88)]
    return "\n".join(lines)


def convergence_json(conv: Convergence) -> dict[str, Any]:
    """The ``convergence`` entry of ``sflm info --convergence --json``.

    Parameters
    ----------
    conv : Convergence
        The convergence study.
    """
    ref = conv.reference
    return {
        "rows": [
            {
                "n": m.n,
                "natural_frequencies_hz": m.natural_frequencies_hz.tolist(),
                "zeros": [[float(z.real), float(z.imag)] for z in m.zeros],
            }
            for m in conv.models
        ],
        "continuum": {
            "method": "finite elements (cubic Hermite)",
            "elements": ref.elements,
            "natural_frequencies_hz": ref.natural_frequencies_hz.tolist(),
            "frequency_error_hz": ref.frequency_error_hz.tolist(),
            "zeros": [[float(z.real), float(z.imag)] for z in ref.zeros],
            "zero_error": ref.zero_error.tolist(),
        },
    }
