"""A held table's rows are bounded before any work (issue 59, item 9).

``sflm invert|simulate|compare paper-sim --period 1e-7`` grew to 6 GB in 70-93 s under a progress line that said the
model was compiling: 5.5e7 rows, each simulated through the held plant and judged in the loop. Measured on paper-sim
(``/usr/bin/time -v sflm invert paper-sim --period P``): 5.5e5 rows took 1.0 GB and 4.7 s, 5.5e6 rows 5.1 GB and 28 s.
The problem refuses a period whose table has more than ``DEFAULTS.max_held_rows`` rows over the move, naming the
shortest period accepted.
"""

from __future__ import annotations

import pytest

import modelgen
from _helpers import error_lines, run_cli
from inversion import Problem, Sampling, SettingsError, smoothstep
from inversion.config import DEFAULTS


@pytest.fixture(scope="module")
def model() -> modelgen.Model:
    return modelgen.load("paper-sim")


def test_a_period_with_too_many_rows_is_refused_naming_the_shortest(model: modelgen.Model) -> None:
    move = smoothstep(1.0, 2.0, 2)
    shortest = move.duration / DEFAULTS.max_held_rows
    with pytest.raises(SettingsError, match="period") as refused:
        Problem(model, move, sampling=Sampling(period=shortest / 2))
    assert f"{shortest:.3g} s" in str(refused.value) and f"{DEFAULTS.max_held_rows:,}" in str(refused.value)
    # at the edge, and a period a user means, are accepted
    for period in (shortest * 1.001, 1e-3):
        assert Problem(model, move, sampling=Sampling(period=period)).sampling.period == period


@pytest.mark.parametrize("command", ["invert", "simulate", "compare"])
def test_every_command_refuses_it_in_one_line(command: str) -> None:
    done = run_cli(command, "paper-sim", "--period", "1e-7", "-q")
    assert done.returncode == 2 and len(error_lines(done.stderr)) == 1, done.stderr
    assert "--period" in done.stderr and "at least 5.5e-06 s" in done.stderr
