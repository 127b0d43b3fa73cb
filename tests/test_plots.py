"""Figures that read well (issue 25): long titles wrapped inside the figure, not clipped."""

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
