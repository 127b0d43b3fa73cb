"""Figures that read well (issue 25): long titles wrapped, and every figure's text inside its canvas."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from sflm import plots

LONG = ("paper-sim: tip error 5.73 mm at 15 s; last second: mean 0.0123 mm, vibration 0.456 mm p-p, with the paper's gains "
        "and friction compensation on the fitted plant")


@pytest.mark.parametrize("zoom", [None, (0.0, 2.0)])
def test_a_long_title_stays_inside_the_figure(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, zoom) -> None:  # type: ignore[no-untyped-def]
    kept = []
    monkeypatch.setattr(plots.plt, "close", lambda fig: kept.append(fig))
    t = np.linspace(0.0, 10.0, 101)
    plots.time_figure(tmp_path / "f.png", [(t, np.sin(t), "", {})], "y (m)", LONG, zoom=zoom)
    (fig,) = kept
    renderer = fig.canvas.get_renderer()
    box = fig.axes[0].title.get_window_extent(renderer)
    assert box.x0 >= 0 and box.x1 <= fig.bbox.x1 and box.y1 <= fig.bbox.y1  # measured before: 1.6x the figure's width
    assert "\n" in fig.axes[0].get_title()


def _beyond_the_canvas(fig) -> list[str]:  # type: ignore[no-untyped-def]
    """Where matplotlib's tight bounding box of everything drawn (titles, labels, ticks, legends, colour bars, notes)
    leaves the figure, in inches (empty when it does not)."""
    fig.canvas.draw()
    box = fig.get_tightbbox(fig.canvas.get_renderer())
    width, height = fig.get_size_inches()
    slack = 1.0 / fig.dpi
    sides = {"left": -box.x0, "bottom": -box.y0, "right": box.x1 - width, "top": box.y1 - height}
    return [f"{side} by {excess:.3f} in" for side, excess in sides.items() if excess > slack]


@pytest.mark.slow
def test_every_figure_keeps_its_text_inside_the_canvas(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # issue 25: every figure the commands draw, measured against the figure's size once drawn (the saved PNG is that canvas)
    from sflm.cli import main

    kept = []
    monkeypatch.setattr(plots.plt, "close", lambda fig: kept.append(fig))
    steel = str(Path(__file__).parent / "data" / "steel-strip.toml")
    commands = [
        ["invert", "paper-sim", "--plot"],
        ["simulate", "paper-exp", "--plot", "--paper-plant"],
        ["explore", steel, "--trajectory", "smoothstep:0.5:1.5:2", "--segments", "3,6", "--h", "1", "--cdec-fast", "1e-4,1e-8",
         "--cdec-slow", "1", "--joining", "anchored", "--end", "settle", "--workers", "1", "--uncertainty", "payload.mass=20%", "--plot"],
        ["compare", "hyperbolic", "--plot"],
        ["info", "paper-sim", "--convergence", "--max-modes", "3", "--plot"],
        ["reproduce", "paper-sim"],
    ]
    for k, command in enumerate(commands):
        assert main([*command, "--out", str(tmp_path / str(k))]) == 0, command
    assert len(kept) >= 12
    problems = {fig.axes[0].get_title()[:50] if fig.axes else str(fig): _beyond_the_canvas(fig) for fig in kept}
    assert not {name: texts for name, texts in problems.items() if texts}


def test_the_canvas_check_sees_a_clipped_text() -> None:
    fig, ax = plots.plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1])
    fig.tight_layout()
    assert _beyond_the_canvas(fig) == []
    ax.set_title(LONG)  # 1.6x the figure's width, unwrapped
    assert any(side.startswith(("left", "right")) for side in _beyond_the_canvas(fig))
    plots.plt.close(fig)
