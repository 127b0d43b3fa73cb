"""Calibration in seconds, honestly (issue 48): ``sflm fit`` on data sflm's model did not make, against one run of the
paper's member.

Run: ``python benchmarks/bench_fit.py [RUNS]``. The data come from the exact beam of ``tests/modelgen/beam_truth.py``
(the glass-fibre rod 6 % stiffer than its file, a lighter payload, a heavier hub, 1.3 % damping), written to CSV files
in a temporary folder; each case is a whole ``sflm fit`` process timed in turn with the baseline, ``sflm invert
paper-sim`` (A B A B ..., after a warm-up of both), and its figure is the median of the pair-by-pair ratios. After the
ratio: the fitted rigidity with its interval and the truth, so that a run beside two CPU burners can be compared with one
on a free machine (no clock decides an answer: the same figures).

Cases: a 2-60 Hz response (300 points, 2 % noise; eight starts, 3 modes checked with 4); a 1 kHz doublet record (3 s,
1 % noise; 6 modes checked with 7, the record by FFT convolution); the same rod damped per mode, its modal ratios fitted;
a lightly damped (0.2 %) record from a file 20 % low in EI and 25 % high in the payload, started where its spectrum
points (the nominal start alone ends in a minimum 5 % off the data).
"""

from __future__ import annotations

import json
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests" / "modelgen"))
from bench_chain import _run  # noqa: E402  (a whole process timed, its output or its last error line)
from beam_truth import Beam  # noqa: E402  (the tests' independent beam)

SFLM = [sys.executable, "-m", "sflm.cli"]
ROD = ROOT / "tests" / "data" / "glass-fibre-rod.toml"
EI = 19.635 * 1.06


def _beam(zeta: float) -> Beam:
    return Beam(0.9, EI, 0.14923, 0.0055, 0.092, 2.2e-5).with_first_ratio(zeta)


def _write(folder: Path) -> list[tuple[str, list[str]]]:
    """The cases' files and commands."""
    rng = np.random.default_rng(1)
    f = np.geomspace(2.0, 60.0, 300)
    noise = 1 + 0.02 * (rng.standard_normal(300) + 1j * rng.standard_normal(300)) / np.sqrt(2)
    for name, G in (("response", _beam(0.013).response(f) * noise),
                    ("modal", Beam(0.9, EI, 0.14923, 0.0055, 0.092, 2.2e-5).modal_response(f, np.array([0.012, 0.02])) * noise)):
        rows = "\n".join(f"{float(a)!r},{float(abs(g))!r},{float(np.degrees(np.angle(g)))!r}" for a, g in zip(f, G))
        (folder / f"{name}.csv").write_text("f,magnitude,phase\n" + rows + "\n")
    t = np.arange(0.0, 3.0, 1e-3)
    tau = 0.2 * ((t < 0.01) * 1.0 - ((t >= 0.01) & (t < 0.02)))
    for name, zeta in (("record", 0.013), ("light", 0.002)):
        theta, y = _beam(zeta).record(t, tau)
        theta = theta + 0.01 * np.ptp(theta) * rng.standard_normal(t.size)
        y = y + 0.01 * np.ptp(y) * rng.standard_normal(t.size)
        rows = "\n".join(",".join(repr(float(v)) for v in row) for row in zip(t, tau, theta, y))
        (folder / f"{name}.csv").write_text("t,tau,theta,y\n" + rows + "\n")
    text = ROD.read_text()
    (folder / "modal-rod.toml").write_text(text.replace('name = "glass-fibre-rod"', 'name = "modal-rod"').replace(
        "ratio = 0.01", "modal = [0.01]"))
    (folder / "off-rod.toml").write_text(text.replace('name = "glass-fibre-rod"', 'name = "off-rod"').replace(
        "flexural_rigidity = 19.635", f"flexural_rigidity = {0.8 * EI!r}").replace("mass = 0.1", "mass = 0.115").replace(
        "ratio = 0.01", "ratio = 0.002"))
    fit = [*SFLM, "fit", "--json", "-q", "--out", str(folder / "out.toml")]
    return [("response 2-60 Hz, 300 points", [*fit, str(ROD), "--data", str(folder / "response.csv")]),
            ("record 1 kHz, 3 s, two outputs", [*fit, str(ROD), "--data", str(folder / "record.csv")]),
            ("response, damped per mode", [*fit, str(folder / "modal-rod.toml"), "--data", str(folder / "modal.csv")]),
            ("light record from 20-25 % off", [*fit, str(folder / "off-rod.toml"), "--data", str(folder / "light.csv")])]


def _figures(output: str) -> str:
    try:
        p = json.loads(output)["parameters"]["link.flexural_rigidity"]
    except (json.JSONDecodeError, KeyError):
        return output[:160]
    return f"EI {p['value']:.5g} +- {p['interval_95']:.2g} (truth {EI:.5g})"


def main(runs: int = 3) -> None:
    baseline = [*SFLM, "invert", "paper-sim", "-q", "--out", tempfile.mkdtemp()]
    with tempfile.TemporaryDirectory() as tmp:
        cases = _write(Path(tmp))
        _run(baseline)
        base_times = []
        print(f"{'case':40s} {'case (s)':>9s} {'ratio':>6s}  figures")
        for name, command in cases:
            _run(command)
            ratios, times, figures = [], [], ""
            for _ in range(runs):
                b, _ = _run(baseline)
                c, out = _run(command)
                base_times.append(b)
                ratios.append(c / b)
                times.append(c)
                figures = _figures(out)
            print(f"{name:40s} {statistics.median(times):9.2f} {statistics.median(ratios):6.2f}  {figures}")
        print(f"baseline: sflm invert paper-sim, {statistics.median(base_times):.2f} s (median)")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 3)
