"""The figures of a member (inversion.family.figures): the same in a batch as alone, and never below the closed form sampled."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st
import pytest

import modelgen
from inversion import smoothstep
from inversion.family.figures import grid_size
from inversion.family.member import evaluate_members
from inversion.settings import InversionSettings
from inversion.lti.system import normal_form

# cdec_fast over nine decades: the members' scanning grids differ (their fast exponentials' boundary layers), so the
# batch is scanned in groups whose peaks are refined together
CDECS = [(1e-10, 1.0), (1e-6, 0.5), (1e-4, 1.0), (1e-2, 0.7), (0.1, 1.0)]


def test_a_batch_gives_each_member_its_own_figures() -> None:
    model = modelgen.load("paper-sim")
    form, move = normal_form(model), smoothstep(1.2, 4.0, 5)
    members = [InversionSettings(segments=6, h=2, cdec=c, joining="anchored", end="free") for c in CDECS]
    together = evaluate_members(form, move, members, max_error=np.inf, verify=False)
    solution = together[0].redefinition.solution  # type: ignore[union-attr]
    assert len(np.unique(grid_size(solution, np.arange(len(CDECS))), axis=0)) >= 2
    for member, batched in zip(members, together):
        alone = evaluate_members(form, move, [member], max_error=np.inf, verify=False)[0]
        assert batched.status == alone.status == "ok"
        a, b = alone.figures, batched.figures
        assert a is not None and b is not None
        assert _figures(b) == pytest.approx(_figures(a), rel=1e-13, abs=1e-15)
        # the refined figures bound the closed form on a grid 20 times finer than the scan's, and are its values where
        # they say they are
        redef = batched.redefinition
        assert redef is not None
        t = np.linspace(move.t0, move.tf, 20 * b.grid_points)
        values = redef.evaluate(t)
        error = np.abs(values["y"] - move.derivative(t, 0)).max()
        torque = np.abs(values["tau"]).max()
        assert error <= b.max_error * (1 + 1e-12) and torque <= b.peak_torque * (1 + 1e-12)
        assert error >= b.max_error * (1 - 1e-4) and torque >= b.peak_torque * (1 - 1e-4)
        at = redef.evaluate(np.array([b.time_of_max_error, b.time_of_peak_torque]))
        assert abs(at["y"][0] - move.derivative(b.time_of_max_error, 0)[0]) == pytest.approx(b.max_error, rel=1e-12)
        assert abs(at["tau"][1]) == pytest.approx(b.peak_torque, rel=1e-12)


def _figures(f):  # type: ignore[no-untyped-def]
    return (f.max_error, f.time_of_max_error, f.peak_torque, f.time_of_peak_torque)


@given(st.integers(1, 5), st.integers(1, 4), st.integers(1, 6), st.integers(0, 40), st.integers(0, 2**31))
def test_the_close_terms_are_summed_as_np_add_at_sums_them(blocks: int, points: int, modes: int, terms: int, seed: int) -> None:
    # the family's closed form sums the terms of each (block, mode) near a zero into one value, once with np.add.at;
    # summed_in_order must give its bits: the same terms in the same order (0 + v1 + v2 + ...), repeats and all, over
    # magnitudes sixteen decades apart (where the order of a sum shows)
    from inversion.family.ssef.evaluate import summed_in_order

    rng = np.random.default_rng(seed)
    q, i = np.sort(rng.integers(0, blocks, terms)), rng.integers(0, modes, terms)
    value = (rng.standard_normal((terms, points)) + 1j * rng.standard_normal((terms, points))) * 10.0 ** rng.integers(-8, 8, (terms, 1))
    expected = np.zeros((blocks, points, modes), dtype=complex)
    np.add.at(expected, (q[:, None], np.arange(points)[None, :], i[:, None]), value)
    out = np.zeros_like(expected)
    summed_in_order(out, q, i, value)
    assert np.array_equal(out.view(float), expected.view(float))
