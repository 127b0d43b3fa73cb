"""Paper-style figures (matplotlib, written as PNG files)."""

from __future__ import annotations

import textwrap

from pathlib import Path
from typing import Any, Mapping, Sequence

import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.colors  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

__all__ = [
    "acceleration_figure",
    "line_figure",
    "pareto_figure",
    "plot_inversion",
    "plot_simulation",
    "sensitivity_figure",
    "time_figure",
    "tip_error_title",
    "velocity_displacement_figure",
]

#: Characters of a title line at 10 pt on a 6.4 in wide figure: longer ones are wrapped, not clipped.
TITLE_WIDTH = 70


def _save(fig: Any, path: Path, **options: Any) -> None:
    """``fig`` saved to ``path`` whole or not at all (a temporary name renamed: :func:`modelgen.files.replaced`)."""
    from modelgen.files import replaced

    path = Path(path)
    with replaced(path) as temporary:
        fig.savefig(temporary, format=path.suffix.lstrip(".") or "png", **options)


def _fit_title(title: str, width: int) -> str:
    """A title wrapped onto lines of at most ``width`` characters (a long one is not clipped by the figure)."""
    return "\n".join(textwrap.wrap(title, width)) or title


#: One curve: (x, y, label, keyword arguments of ``plot``).
Curve = tuple[Any, Any, str, dict[str, Any]]


def line_figure(
    path: Path,
    curves: Sequence[Curve],
    xlabel: str,
    ylabel: str,
    title: str,
    marks: Sequence[float] = (),
    zero_line: bool = False,
) -> Path:
    """Write one line plot against time.

    Write one line plot: ``curves`` against time, optional vertical marks (segment joints, t_f).

    Parameters
    ----------
    path : Path
        The image to write.
    curves : Sequence[Curve]
        The curves.
    xlabel : str
        The x axis' label.
    ylabel : str
        The y axis' label.
    title : str
        The figure's title.
    marks : Sequence[float], optional
        Times of vertical marks.
    zero_line : bool, optional
        Whether to draw ``y = 0``.
    """
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    for x, y, label, style in curves:
        ax.plot(x, y, label=label, **style)
    for m in marks:
        ax.axvline(m, color="0.82", lw=0.8, zorder=0)
    if zero_line:
        ax.axhline(0.0, color="0.5", lw=0.6, zorder=0)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(_fit_title(title, TITLE_WIDTH), fontsize=10)
    if sum(1 for c in curves if c[2]) > 1:
        ax.legend()
    fig.tight_layout()
    _save(fig, path, dpi=130)
    plt.close(fig)
    return Path(path)


def _method_of(result: Any) -> Any:
    """The registered method a result is of (:func:`inversion.options.method_named`; the family for a result that names none)."""
    from inversion.options import InversionMethod, method_named
    from modelgen.errors import SettingsError

    try:
        return method_named(str(result.summary.get("method", "ssef")))
    except SettingsError:  # a run written by a method not registered here: its figures with neutral words
        return InversionMethod


def _inversion_words(result: Any) -> dict[str, str]:
    """The words a figure of ``result`` uses: a link's (tip, torque in N m) or a generic system's (output, input, no units)."""
    link = result.theta_d is not None
    what = _method_of(result).title  # the registry's: each method names its own feedforward
    if link:
        return {"output": "end-effector displacement (m)", "error": r"$\tilde y_d - y_d$ (mm)", "scale": "1e3", "unit": " mm",
                "input": r"$\tau_l$ (N m)", "input_title": f"{what} torque", "input_unit": " N m", "what": what}
    return {"output": "output y", "error": r"$\tilde y_d - y_d$", "scale": "1", "unit": "", "input": "input u",
            "input_title": f"{what} input", "input_unit": "", "what": what}


def shortest_figure(block: dict[str, Any], path: Path, name: str) -> Path:
    """The bounded causal limit against the move's duration, the bound, and the shortest move returned.

    Parameters
    ----------
    block : dict
        The summary's ``shortest`` block (:mod:`inversion.methods.shortest`).
    path : Path
        The image to write.
    name : str
        The model's name.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    curve = np.array([row for row in block["curve"] if np.isfinite(row[1])], dtype=float)
    free = block.get("profile") == "free"
    least = 1e-3 * block["bound"]  # below a thousandth of the bound the curve is drawn at it (a free move's error is 0 there)
    fig, ax = plt.subplots(figsize=(10.0, 4.4))
    fig.subplots_adjust(left=0.08, right=0.6, bottom=0.12, top=0.88)  # the legend beside the axes
    ax.semilogy(curve[:, 0], 1e3 * np.maximum(curve[:, 1], least), "o-", color="C0",
                label="least tip error after the move, any profile" if free else "least error within the bounds (bounded causal limit)")
    ax.axhline(1e3 * block["bound"], color="C3", lw=1.2, label=f"bound {1e3 * block['bound']:.3g} mm")
    ax.axvline(block["lower_bound"], color="0.4", ls=":", label=f"no table exists: {block['lower_bound']:.4g} s")
    ax.axvline(block["duration"], color="C2", lw=1.6, label=f"returned move: {block['duration']:.4g} s")
    if block["rigid_floor"] > 0:
        ax.axvline(block["rigid_floor"], color="0.6", ls="--", label=f"rigid bang-bang floor: {block['rigid_floor']:.4g} s")
    beside = block.get("beside") or {}
    smooth = beside.get("smoothstep") or {}
    if "lower_bound" in smooth:
        ax.axvline(smooth["upper"], color="C1", ls="-.", label=f"shortest smoothstep (order {smooth['order']}): {smooth['upper']:.4g} s")
    shaped = beside.get("zv_bang_bang")
    if shaped:
        verdict = ["holds the bound" if shaped["holds_bound"] else "misses the bound"]
        verdict += [] if shaped["within_rate"] else ["beyond the rate bound"]
        verdict += ["bends too far"] if shaped.get("within_deflection") is False else []
        ax.axvline(shaped["duration"], color="C4", ls="--", label=f"ZV-shaped bang-bang: {shaped['duration']:.4g} s\n(" + ", ".join(verdict)
                   + ")")
    ax.set_xlabel("duration of the move (s)")
    ax.set_ylabel("tip error (mm)")
    what = "the fastest move of any profile" if free else "the shortest move"
    ax.set_title(_fit_title(f"{name}: {what} within the drive's bounds", TITLE_WIDTH), fontsize=10)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), frameon=False)  # beside: the curve stays clear
    _save(fig, path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return Path(path)


def plot_inversion(result: Any, folder: Path, prefix: str = "") -> list[Path]:
    """Desired and redefined output and the torque (Figs. 3-4, 8-10).

    Desired and redefined output, their difference, the feedforward torque (cf. Figs. 3-4, 8-10).

    A held table (the optimal-control feedforward) is drawn as the steps a controller holds; a
    generic system's figures say output and input, with no units. Returns the files written:
    ``output.png``, ``redefinition_error.png``, ``torque.png``.

    Parameters
    ----------
    result : Any
        An inversion's result.
    folder : Path
        Where the images go.
    prefix : str, optional
        Prefix of the files' names.
    """
    folder = Path(folder)
    joints = list(result.joints[1:-1])
    t = result.t
    s = result.summary
    words = _inversion_words(result)
    scale = float(words["scale"])
    held = s.get("settings", {}).get("hold") == "zoh"  # a held table (one row a period): drawn as the steps a controller holds
    steps = {"drawstyle": "steps-post"} if held else {}
    marks = "; joints in grey" if joints else ""
    extra = [shortest_figure(s["shortest"], folder / f"{prefix}shortest.png", result.model.name)] if s.get("shortest") else []
    return [
        line_figure(
            folder / f"{prefix}output.png",
            [(t, result.y_d, "desired $y_d$", {"lw": 2.2, "color": "0.6"}),
             (t, result.y, r"redefined $\tilde y_d$" if _method_of(result).redefines else "the model's output",
              {"lw": 1.2, "color": "C0"})],
            "time (s)", words["output"], f"{result.model.name}: desired and redefined output", joints,
        ),
        line_figure(
            folder / f"{prefix}redefinition_error.png",
            [(t, (result.y - result.y_d) * scale, "", {"color": "C3"})],
            "time (s)", words["error"],
            f"redefinition error (max {s['max_redefinition_error'] * scale:.3g}{words['unit']}{marks})", joints, True,
        ),
        line_figure(
            folder / f"{prefix}torque.png",
            [(t, result.tau, "", {"color": "C2", **steps})],
            "time (s)", words["input"],
            f"{words['input_title']} (peak {s['peak_torque']:.4g}{words['input_unit']}{marks})", joints, True,
        ),
    ] + extra


def tip_error_title(summary: Any) -> str:
    """A title stating the tip error without hiding a vibration.

    Parameters
    ----------
    summary : Any
        A simulation's summary.
    """
    s = summary
    return (f"tip error {s['final_tip_error'] * 1e3:.3g} mm at {s['t_end']:g} s; last second: mean "
            f"{s['steady_tip_error'] * 1e3:.3g} mm, vibration {s['residual_vibration'] * 1e3:.3g} mm p-p")


def _zoom(sim: Any) -> tuple[float, float] | None:
    """A window on the manoeuvre when it is short against the run (``None``: the whole run shows it)."""
    t0, tf, end = float(sim.t[0]), float(sim.summary["t_final_manoeuvre"]), float(sim.t[-1])
    if tf <= t0 or tf - t0 >= 0.2 * (end - t0):
        return None
    return t0, min(end, t0 + 2.5 * (tf - t0))


def time_figure(
    path: Path,
    curves: Sequence[Curve],
    ylabel: str,
    title: str,
    marks: Sequence[float] = (),
    zero_line: bool = False,
    zoom: tuple[float, float] | None = None,
) -> Path:
    """Curves against time, with an optional zoom panel.

    Curves against time; with ``zoom``, a second panel on that window (a short manoeuvre in a long run).

    Parameters
    ----------
    path : Path
        The image to write.
    curves : Sequence[Curve]
        The curves.
    ylabel : str
        The y axis' label.
    title : str
        The figure's title.
    marks : Sequence[float], optional
        Times of vertical marks.
    zero_line : bool, optional
        Whether to draw ``y = 0``.
    zoom : tuple[float, float] | None, optional
        A window ``(start, end)`` for a second panel, if any.
    """
    if zoom is None:
        return line_figure(path, curves, "time (s)", ylabel, title, marks, zero_line)
    fig, axes = plt.subplots(2, 1, figsize=(6.4, 5.4))
    for ax, window in zip(axes, (None, zoom)):
        for x, y, label, style in curves:
            if window is not None:
                inside = (x >= window[0]) & (x <= window[1])
                x, y = x[inside], y[inside]
            ax.plot(x, y, label=label, **style)
        for m in marks:
            ax.axvline(m, color="0.82", lw=0.8, zorder=0)
        if zero_line:
            ax.axhline(0.0, color="0.5", lw=0.6, zorder=0)
        ax.set_ylabel(ylabel)
    axes[0].set_title(_fit_title(title, TITLE_WIDTH + 8), fontsize=9)
    axes[1].set_xlabel("time (s)")
    axes[1].set_title(f"the manoeuvre and after: {zoom[0]:g} to {zoom[1]:g} s", fontsize=8, color="0.3")
    if sum(1 for c in curves if c[2]) > 1:
        axes[0].legend(fontsize=8)
    fig.tight_layout()
    _save(fig, path, dpi=130)
    plt.close(fig)
    return Path(path)


def plot_simulation(
    sim: Any,
    folder: Path,
    names: tuple[str, str, str] = ("torque.png", "tip.png", "tip_error.png"),
    titles: tuple[str, str, str] | None = None,
) -> list[Path]:
    """Torque, tip and tip error of a simulation (Figs. 4-6, 10-16).

    Applied torque, desired and actual tip displacement, their difference (cf. Figs. 4-6, 10-12, 14-16).

    A manoeuvre shorter than a fifth of the run gets a second panel on it. Returns the
    files written (``names``, in ``folder``).

    Parameters
    ----------
    sim : Any
        A simulation's result.
    folder : Path
        Where the images go.
    names : tuple[str, str, str], optional
        The three files' names.
    titles : tuple[str, str, str] | None, optional
        Their titles (``None``: defaults).
    """
    folder = Path(folder)
    s = sim.summary
    tf = [s["t_final_manoeuvre"]]
    label = f"{s['model']}, {s['plant']['kind']} plant, {s['controller']}"
    titles = titles or (f"applied torque ({label})", f"desired and actual tip ({label})", f"{{error}} ({label})")
    zoom = _zoom(sim)
    return [
        time_figure(folder / names[0], [(sim.t, sim.tau, "", {"color": "C2", "lw": 1.0})],
                    r"applied torque $\tau$ (N m)", titles[0], tf, True, zoom),
        time_figure(folder / names[1],
                    [(sim.t, sim.y_d, "desired $y_d$", {"lw": 2.2, "color": "0.6"}),
                     (sim.t, sim.y, "actual $y$", {"lw": 1.0, "color": "C0"})],
                    "end-effector displacement (m)", titles[1], tf, False, zoom),
        time_figure(folder / names[2], [(sim.t, (sim.y_d - sim.y) * 1e3, "", {"color": "C3", "lw": 1.0})],
                    "error $y_d - y$ (mm)", titles[2].replace("{error}", tip_error_title(s)), tf, True, zoom),
    ]


def sensitivity_figure(path: Path, sweeps: Sequence[tuple[str, str, Sequence[dict[str, Any]]]], title: str) -> Path:
    """Steady tip error of each controller against each plant value.

    Steady tip error of each controller against each swept plant value, the vibration as a band.

    Parameters
    ----------
    sweeps : sequence of (key, label, rows)
        One panel each: rows with ``key`` (the swept value), ``controller``,
        ``steady_tip_error`` and ``residual_vibration`` (m).
    path : Path
        The image to write.
    title : str
        The figure's title.
    """
    fig, axes = plt.subplots(1, len(sweeps), figsize=(4.0 * len(sweeps), 3.6), squeeze=False)
    for ax, (key, label, rows) in zip(axes[0], sweeps):
        for k, controller in enumerate(sorted({r["controller"] for r in rows})):
            mine = sorted((r for r in rows if r["controller"] == controller), key=lambda r: r[key])
            x = [r[key] for r in mine]
            mean = [r["steady_tip_error"] * 1e3 for r in mine]
            half = [r["residual_vibration"] * 1e3 / 2 for r in mine]
            ax.plot(x, mean, marker="o", color=f"C{k}", label=f"{controller}: mean error")
            ax.fill_between(x, [m - h for m, h in zip(mean, half)], [m + h for m, h in zip(mean, half)], color=f"C{k}",
                            alpha=0.2, lw=0, label=f"{controller}: vibration (p-p)")
        ax.set_xlabel(label)
        ax.set_ylabel("tip error, last second (mm)")
        ax.axhline(0.0, color="0.5", lw=0.6, zorder=0)
        ax.legend(fontsize=7)
    fig.suptitle(_fit_title(title, TITLE_WIDTH), fontsize=10)
    fig.tight_layout()
    _save(fig, path, dpi=130)
    plt.close(fig)
    return Path(path)


def acceleration_figure(path: Path, result: Any, title: str) -> Path:
    """Desired and redefined tip acceleration (cf. Fig. 8).

    Parameters
    ----------
    path : Path
        The image to write.
    result : Any
        An inversion's result.
    title : str
        The figure's title.
    """
    t = result.t
    return line_figure(
        path,
        [(t, result.trajectory.derivative(t, 2), r"desired $\ddot y_d$", {"lw": 2.2, "color": "0.6"}),
         (t, result.yddot, "redefined (sum of exponentials)", {"lw": 1.0, "color": "C0"})],
        "time (s)", r"acceleration (m/s$^2$)", title, list(result.joints[1:-1]), True,
    )


def velocity_displacement_figure(path: Path, result: Any, title: str) -> Path:
    """Desired tip velocity and displacement on two axes (cf. Fig. 9).

    Parameters
    ----------
    path : Path
        The image to write.
    result : Any
        An inversion's result.
    title : str
        The figure's title.
    """
    t = result.t
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    ax.plot(t, result.trajectory.derivative(t, 1), color="C0", label="velocity")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("desired velocity (m/s)", color="C0")
    ax2 = ax.twinx()
    ax2.plot(t, result.y_d, color="C1", label="displacement")
    ax2.set_ylabel("desired displacement (m)", color="C1")
    ax.set_title(_fit_title(title, TITLE_WIDTH), fontsize=10)
    fig.tight_layout()
    _save(fig, path, dpi=130)
    plt.close(fig)
    return Path(path)


_JOINING_STYLE = {"paper": ("C0", "o"), "position": ("C1", "s"), "anchored": ("C2", "^")}


def pareto_figure(exploration: Any, path: Path, title: str | None = None, ocp: tuple[list[dict[str, Any]], float] | None = None) -> Path:
    """Redefinition error against peak torque of the members.

    Redefinition error against peak torque of the successful members, the Pareto front highlighted,
    the paper's member and the best one marked (log scales); with ``ocp = (rows, period)`` (:func:`inversion.methods.ocp.ocp_front`)
    the optimal-control front beside them: the least peak torque any causal feedforward needs at each bound.

    Parameters
    ----------
    exploration : Any
        The explored family.
    path : Path
        The image to write.
    title : str | None, optional
        The figure's title (``None``: a default).
    ocp : tuple[list[dict[str, Any]], float] | None, optional
        The optimal-control front and its period, if any.
    """
    rows = exploration.succeeded
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    judged = [r for r in rows if r.get("worst_case_error") is not None]
    for joining, (color, marker) in _JOINING_STYLE.items():
        mine = [r for r in rows if r["joining"] == joining]
        if mine:
            ax.scatter([r["peak_torque"] for r in mine], [r["max_redefinition_error"] for r in mine], s=16,
                       color="0.75" if judged else color, marker=marker, alpha=0.6, lw=0, label=f"{joining} ({len(mine)})")
    if judged:  # explore --uncertainty: the judged members coloured by their worst case on the perturbed links
        worst = [100 * r["worst_case_error"] for r in judged]
        norm = matplotlib.colors.LogNorm(min(worst), max(worst)) if max(worst) > 3 * min(worst) > 0 else None
        points = ax.scatter([r["peak_torque"] for r in judged], [r["max_redefinition_error"] for r in judged], c=worst, norm=norm,
                            cmap="viridis_r", s=46, marker="D", edgecolors="k", lw=0.5, zorder=5,
                            label=f"judged on perturbed links ({len(judged)})")
        fig.colorbar(points, ax=ax, pad=0.02).set_label("worst-case tip error (% of the move)", fontsize=8)
    front = exploration.front
    if front:
        ax.plot([r["peak_torque"] for r in front], [r["max_redefinition_error"] for r in front], color="k", lw=1.0,
                drawstyle="steps-post", label=f"Pareto front ({len(front)})")
        ax.plot([r["peak_torque"] for r in front], [r["max_redefinition_error"] for r in front], "o", color="k", ms=4, mfc="white",
                mew=1.0, zorder=4)  # the front's members themselves, visible above the cloud
    paper = next((r for r in exploration.rows if r["paper"]), None)
    if paper is not None and paper["max_redefinition_error"] is not None:
        ax.scatter([paper["peak_torque"]], [paper["max_redefinition_error"]], s=90, facecolors="none", edgecolors="C3",
                   lw=1.6, label="the paper's member", zorder=5)
    best = exploration.best
    if best is not None:
        ax.scatter([best["peak_torque"]], [best["max_redefinition_error"]], s=110, marker="*", color="gold", edgecolors="k",
                   lw=0.6, label="chosen (the automatic choice's rule)", zorder=6)
    solved = [r for r in (ocp[0] if ocp else []) if r["status"] == "ok"]
    if solved:
        ax.plot([r["peak_torque"] for r in solved], [r["max_error"] for r in solved], "s-", color="C4", ms=6, lw=1.4,
                label=f"optimal control, {ocp[1]:g} s held (the limit)", zorder=7)  # type: ignore[index]
    ax.set_yscale("log")
    torques = [r["peak_torque"] for r in rows] + [r["peak_torque"] for r in solved]
    if torques:
        # the front and its neighbourhood; members with far larger torques are counted, not drawn
        low = min(torques)
        high = max([r["peak_torque"] for r in front] + [r["peak_torque"] for r in solved]
                   + ([paper["peak_torque"]] if paper and paper["peak_torque"] else []))
        high = max(high * 1.5, low * 1.2)
        beyond = sum(1 for t in torques if t > high)
        ax.set_xlim(low - 0.05 * (high - low), high)
        if beyond:
            ax.text(0.99, 0.01, f"{beyond} members beyond {high:.3g} N m not shown", transform=ax.transAxes, ha="right",
                    va="bottom", fontsize=7, color="0.4")
    ax.set_xlabel(r"peak torque $\max|\tau_l|$ (N m)")
    ax.set_ylabel(r"redefinition error $\max|\tilde y_d - y_d|$ (m)")
    ax.set_title(_fit_title(title or f"{exploration.model}: the family of redefinitions ({len(exploration.rows)} members)",
                            TITLE_WIDTH), fontsize=10)
    ax.grid(True, which="major", color="0.9", lw=0.6)
    ax.legend(fontsize=8, loc="best")
    fig.tight_layout()
    _save(fig, path, dpi=130)
    plt.close(fig)
    return Path(path)


def comparison_figure(comparison: Any, path: Path, title: str) -> Path:
    """The torques of the compared methods on one time axis (pre-actuation included) and their tip errors."""
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    peaks = [float(np.abs(r.tau).max()) for r in comparison.results.values() if np.abs(r.tau).max() > 0]
    spans_decades = len(peaks) > 1 and max(peaks) > 10 * min(peaks)
    for k, (method, result) in enumerate(comparison.results.items()):
        label = f"{method}: peak {np.abs(result.tau).max():.3g} N m"
        held = result.summary.get("settings", {}).get("hold") == "zoh"  # a held table: one value a period
        t, tau = (np.append(result.t, result.trajectory.tf), np.append(result.tau, result.tau[-1])) if held else (result.t, result.tau)
        style = {"label": label, "lw": 1.2, "color": f"C{k}", "drawstyle": "steps-post" if held else "default"}
        if spans_decades:  # torques a decade apart: |tau| on a log axis, so that the small ones show
            top.semilogy(t, np.maximum(np.abs(tau), 1e-6 * max(peaks)), **style)
        else:
            top.plot(t, tau, **style)
        bottom.plot(result.t, 1e3 * (result.y - result.y_d), label=method, lw=1.2, color=f"C{k}")
    for row in comparison.rows:  # the methods that failed, in the legend with their reason
        if row["status"] != "ok":
            reason = row["message"] if len(row["message"]) <= 70 else row["message"][:67] + "..."
            top.plot([], [], ls="none", marker="x", color="0.4", label=f"{row['method']} ({row['status']}): {reason}")
    for axis in (top, bottom):
        for edge in {float(r.trajectory.t0) for r in comparison.results.values()} | {float(r.trajectory.tf) for r in comparison.results.values()}:
            axis.axvline(edge, color="0.6", lw=0.8, ls=":")
        axis.grid(True, alpha=0.3)
    top.set_ylabel("|feedforward torque| (N m), log" if spans_decades else "feedforward torque (N m)")
    bottom.set_ylabel("y~ - y_d (mm)")
    bottom.set_xlabel("t (s); dotted: t0 and tf")
    top.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=7, frameon=False)
    top.set_title(_fit_title(title, 60))
    fig.tight_layout()
    _save(fig, path, dpi=120, bbox_inches="tight")  # the legend beside the axes
    plt.close(fig)
    return path


def convergence_figure(families: Mapping[str, Any], reference: Any, path: Path, name: str) -> Path:
    """Frequencies and zeros against n for each mode-shape family, the continuum as dashed lines.

    ``reference``: :func:`modelgen.continuum.continuum_reference` with at least ``N + 3`` zero pairs.

    Zeros are drawn by magnitude: converged ones (within 1e-3 of the continuum) filled,
    truncation artefacts (complex where the continuum has none) as crosses.
    """
    from modelgen.zero_status import zero_status

    fig, (top, bottom) = plt.subplots(1, 2, figsize=(11, 4.5))
    markers = {"clamped-mass": "o", "clamped-free": "s", "polynomial": "^"}
    for k, (family, conv) in enumerate(families.items()):
        colour = f"C{k}"
        for model in conv.models:
            n = model.n
            top.plot(np.full(n, n) + 0.12 * (k - 1), model.natural_frequencies_hz, markers[family], color=colour, ms=4,
                     label=family if n == 1 else None)
            status = zero_status(model, reference=reference)
            size = np.abs(model.zeros)
            x = np.full(size.size, n) + 0.12 * (k - 1)
            bottom.plot(x[status.converged], size[status.converged], markers[family], color=colour, ms=5,
                        label=family if n == 1 else None)
            others = ~status.converged & ~status.artefact
            bottom.plot(x[others], size[others], markers[family], color=colour, ms=5, mfc="none")
            bottom.plot(x[status.artefact], size[status.artefact], "x", color=colour, ms=5)
    for f in reference.natural_frequencies_hz:
        top.axhline(f, color="0.5", lw=0.8, ls="--")
    for z in np.unique(np.round(np.abs(reference.zeros), 6)):
        bottom.axhline(z, color="0.5", lw=0.8, ls="--")
    top.set_yscale("log")
    bottom.set_yscale("log")
    top.set_xlabel("assumed modes n")
    bottom.set_xlabel("assumed modes n")
    top.set_ylabel("natural frequency (Hz)")
    bottom.set_ylabel("|zero| (rad/s): filled converged, open not yet, x artefact")
    top.set_title(f"{name}: frequencies (dashed: continuum)")
    bottom.set_title(f"{name}: zeros (dashed: continuum)")
    top.legend(fontsize=8)
    bottom.legend(fontsize=8)
    for axis in (top, bottom):
        axis.grid(True, alpha=0.3)
    fig.tight_layout()
    _save(fig, path, dpi=120)
    plt.close(fig)
    return path


def fit_figure(result: Any, data_path: str, output: str | None, path: Path, law: tuple[float, float] | None = None) -> Path:
    """The measurement against the nominal and the fitted model (``sflm fit --plot``): the frequencies side by side, the
    frequency response's magnitude and phase, or the time series' hub angle (and tip)."""
    from modelgen.fit import FrequencyData, FrequencyResponse, predicted, read_data

    data = read_data(data_path, output, law)
    nominal, fitted = predicted(result.nominal, data), predicted(result.geometry, data)
    title = f"{result.geometry.name}: measured, nominal and fitted ({result.kind})"
    if isinstance(data, FrequencyData):
        fig, ax = plt.subplots(figsize=(7, 3.6))
        k = np.arange(1, data.frequencies_hz.size + 1)
        ax.plot(k, data.frequencies_hz, "ko", label="measured")
        ax.plot(k, nominal, "x", color="0.5", label="nominal model")
        ax.plot(k, fitted, "+", color="C0", ms=12, label="fitted model")
        ax.set(xlabel="mode", ylabel="natural frequency (Hz)", xticks=k, yscale="log")
    elif isinstance(data, FrequencyResponse):
        fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 5.4), sharex=True)
        measured = data.magnitude * np.exp(1j * np.deg2rad(data.phase_deg))
        late = float(result.artefacts.get(data.output, {}).get("delay", 0.0))  # the fitted model as the analyser read it
        fitted = fitted * np.exp(-2j * np.pi * data.f * late)
        fitted_phase = np.rad2deg(np.unwrap(np.angle(fitted)))
        for values, style, label in ((measured, dict(color="k", lw=2.2, alpha=0.5), "measured"),
                                     (nominal, dict(color="0.5", ls="--"), "nominal model"),
                                     (fitted, dict(color="C0"), f"fitted model, read {1e3 * late:.3g} ms late" if late else "fitted model")):
            top.loglog(data.f, np.abs(values), label=label, **style)
            phase = np.rad2deg(np.unwrap(np.angle(values)))
            # each unwrapped on its own may start a turn apart: drawn on the fitted model's branch, so that a phase
            # that agrees looks it
            phase -= 360.0 * np.round(np.median(phase - fitted_phase) / 360.0)
            bottom.semilogx(data.f, phase, **style)
        top.set(ylabel=f"|{data.output} / tau|")
        from matplotlib.ticker import FormatStrFormatter, LogLocator, NullFormatter

        bottom.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))  # 1, 2, 5 a decade, in Hz as printed
        bottom.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        bottom.xaxis.set_minor_formatter(NullFormatter())  # the default minor labels of a short decade overlap
        bottom.set(xlabel="frequency (Hz)", ylabel="phase (deg)")
        ax = top
    else:
        from modelgen.fit import INPUT_CORRELATION, input_correlations

        fig, (ax, tests) = plt.subplots(2, 1, figsize=(7, 5.6), gridspec_kw={"height_ratios": [3, 2]})
        ax.plot(data.t, data.theta, color="k", lw=2.2, alpha=0.5, label="measured theta")
        ax.plot(data.t, nominal[0], color="0.5", ls="--", label="nominal model")
        ax.plot(data.t, fitted[0], color="C0", label="fitted model")
        ax.set(xlabel="time (s)", ylabel="hub angle (rad)")
        # the residual tests: each channel's residual against the torque, in its standard deviations were the model
        # right, and the limit beyond which the fit is refused
        for colour, (name, (lags, rho, sd)) in enumerate(input_correlations(result.geometry.with_model(result.modes), data).items()):
            tests.plot(1e3 * lags, rho / sd, "o-", ms=2.5, lw=0.8, color=f"C{colour}", label=f"{name} residual")
        tests.axhspan(-INPUT_CORRELATION, INPUT_CORRELATION, color="0.9", zorder=0, label=f"chance (within {INPUT_CORRELATION:g} sd)")
        tests.axhline(0.0, color="0.5", lw=0.6)
        tests.set(xlabel="lag after the torque (ms)", ylabel="correlation / sd")
        tests.legend(fontsize=8, loc="lower left", ncol=3)
    ax.set_title(_fit_title(title, 70), fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    _save(fig, path, dpi=120)
    plt.close(fig)
    return path
