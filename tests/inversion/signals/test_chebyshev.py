"""The member's signals as piecewise Chebyshev series (inversion.signals.chebyshev): what the samples and the C evaluate."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from numpy.polynomial import chebyshev

import modelgen
from inversion import invert, smoothstep
from inversion.signals.chebyshev import DEGREE, _clenshaw

ROOT = Path(__file__).resolve().parents[3]


def test_clenshaw_is_numpys_chebyshev_series() -> None:
    rng = np.random.default_rng(4)
    c = rng.normal(size=(5, DEGREE + 1))
    x = rng.uniform(-1.0, 1.0, size=5)
    expected = np.array([chebyshev.chebval(xi, ci) for xi, ci in zip(x, c)])
    np.testing.assert_allclose(_clenshaw(c, x), expected, rtol=1e-14, atol=1e-14)


def test_pieces_join_and_resolve_the_boundary_layers() -> None:
    # the own link's automatic member: a stable zero at -51.8 1/s among the exponents
    # (with the rate free and the edges the paper's: the member of least torque the issue measured)
    result = invert(modelgen.load(str(ROOT / "tests" / "data" / "own-aluminium.toml")), smoothstep(0.5, 2.0, 2), max_torque_rate=np.inf,
                    edges="match")
    signals = result.signals
    assert signals is not None and signals.names == ("tau", "theta_d", "thetadot_d")
    K = signals.bounds.size - 1
    assert signals.pieces >= K and np.all(np.diff(signals.piece_start) >= 1)
    # every piece's series has converged: its last coefficients are at the rounding of the values
    tail = np.abs(signals.coefficients[:, :, -3:]).max(axis=2) / signals.peaks
    assert tail.max() <= 1e-12
    # inside a segment the signals are continuous: the pieces meet to rounding
    for k in range(K):
        first, last = signals.piece_start[k], signals.piece_start[k + 1]
        for p in range(first + 1, last):
            t = signals.bounds[k] + signals.edges[p + k]
            left, right = signals.evaluate([np.nextafter(t, -np.inf)]), signals.evaluate([t])
            for m, name in enumerate(signals.names):
                assert abs(left[name][0] - right[name][0]) <= 1e-12 * signals.peaks[m], (k, p, name)
    # outside the span the series are clipped to its ends
    ends = signals.evaluate([signals.bounds[0] - 1.0, signals.bounds[-1] + 1.0])
    np.testing.assert_allclose(ends["tau"], [result.tau[0], result.tau[-1]], rtol=0, atol=1e-15 * signals.peaks[0])


@pytest.mark.parametrize("few", [0, 10**9], ids=["piece by piece", "every point at once"])
def test_the_fast_evaluation_is_clenshaws_recurrence(few: int, monkeypatch: pytest.MonkeyPatch) -> None:
    # what the samples compute (Chebyshev polynomials by their recurrence, one product per piece -- or, where the pieces
    # are many and short, as a held table's, every point's own series at once) against Clenshaw's recurrence, which the
    # exported C runs: the same series to rounding
    import inversion.signals.chebyshev as module

    monkeypatch.setattr(module, "_FEW_POINTS", few)
    result = invert(modelgen.load("paper-exp"), smoothstep(0.1, 0.6, 2), segments=6, h=2, cdec=(1e-3, 1.0), joining="anchored",
                    max_torque=np.inf, max_torque_rate=np.inf)  # a member with a fast start: the series, not its use
    signals = result.signals
    assert signals is not None
    t = np.sort(np.random.default_rng(2).uniform(signals.bounds[0], signals.bounds[-1], 5000))
    fast = signals.evaluate(t)
    k, p, s = signals.locate(t)
    a, b = signals.edges[p + k], signals.edges[p + k + 1]
    x = (2.0 * s - a - b) / (b - a)
    for m, name in enumerate(signals.names):
        clenshaw = _clenshaw(signals.coefficients[p, m, :], x)
        assert np.abs(fast[name] - clenshaw).max() <= 1e-15 * signals.peaks[m]
    shuffled = np.random.default_rng(3).permutation(t.size)  # unsorted times: the same values
    np.testing.assert_allclose(signals.evaluate(t[shuffled])["tau"], fast["tau"][shuffled], rtol=0, atol=1e-15 * signals.peaks[0])
