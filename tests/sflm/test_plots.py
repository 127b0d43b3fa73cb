"""Figures that read well (issue 25): long titles wrapped, and every figure's text inside its canvas."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from _helpers import assert_figures_inside_the_canvas, beyond_the_canvas, kept_figures
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


@pytest.mark.slow
def test_every_figure_keeps_its_text_inside_the_canvas(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # issue 25: every figure the commands draw, measured against the figure's size once drawn (the saved PNG is that
    # canvas); reproduce's figures are measured by tests/sflm/test_cli_simulate.py's reproductions, compare's by test_compare.py
    from sflm.cli import main

    kept = kept_figures(monkeypatch)
    commands = [
        ["invert", "paper-sim", "--plot"],
        ["simulate", "paper-exp", "--plot", "--paper-plant"],
        # the family coloured by its judged members' worst cases, beside the optimal-control front
        ["explore", "paper-exp", "--segments", "3,6", "--h", "2", "--cdec-fast", "0.01,1e-6", "--cdec-slow", "1", "--joining",
         "paper,anchored", "--workers", "1", "--uncertainty", "payload.mass=20%", "--plot"],
        ["info", "paper-sim", "--convergence", "--max-modes", "3", "--plot"],
    ]
    for k, command in enumerate(commands):
        assert main([*command, "--out", str(tmp_path / str(k))]) == 0, command
    assert len(kept) >= 8
    assert_figures_inside_the_canvas(kept)


def test_the_canvas_check_sees_a_clipped_text() -> None:
    fig, ax = plots.plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1])
    fig.tight_layout()
    assert beyond_the_canvas(fig) == []
    ax.set_title(LONG)  # 1.6x the figure's width, unwrapped
    assert any(side.startswith(("left", "right")) for side in beyond_the_canvas(fig))
    plots.plt.close(fig)
