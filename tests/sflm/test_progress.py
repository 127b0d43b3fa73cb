"""The command line's progress (issue 46): nothing for a quick command, past 2 s the stage at least every 5 s."""

from __future__ import annotations

import io
import time

import pytest

from sflm.cli import main
from sflm.progress import Reporter


class _Clock:
    """A clock the test moves (the reporter's thread reads it)."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _reporter(stream: io.StringIO, clock: _Clock, enabled: bool = True) -> Reporter:
    reporter = Reporter("invert", enabled=enabled, stream=stream)
    reporter._clock = clock  # type: ignore[method-assign]
    reporter._start = reporter._opened = 0.0  # type: ignore[attr-defined]
    return reporter


def _wait_for(condition, seconds: float = 5.0) -> None:  # type: ignore[no-untyped-def]
    end = time.monotonic() + seconds
    while not condition() and time.monotonic() < end:
        time.sleep(0.02)


def test_a_quick_command_says_nothing_and_a_long_one_its_stage_at_least_every_five_seconds() -> None:
    stream, clock = io.StringIO(), _Clock()
    reporter = _reporter(stream, clock)
    reporter("the bounded causal limit")
    clock.now = 1.9
    time.sleep(0.6)  # the thread has looked: before 2 s nothing
    assert stream.getvalue() == ""
    reporter("auto: 252 members on the first grid")
    clock.now = 2.1
    _wait_for(lambda: stream.getvalue().count("\n") == 1)
    assert stream.getvalue() == "sflm invert: auto: 252 members on the first grid (2 s)\n"
    reporter.count(40, 252)
    clock.now = 6.0  # less than 5 s since the last line: nothing new
    time.sleep(0.6)
    assert stream.getvalue().count("\n") == 1
    clock.now = 7.2  # a solve that says nothing: its stage again, with what it counted, every 5 s
    _wait_for(lambda: stream.getvalue().count("\n") == 2)
    assert stream.getvalue().splitlines()[-1] == "sflm invert: auto: 252 members on the first grid, 40 of 252 members (7 s)"
    reporter("ocp: 2 400 periods")  # a new stage past 2 s is written at once
    assert stream.getvalue().splitlines()[-1] == "sflm invert: ocp: 2 400 periods (7 s)"
    reporter.close()


def test_quiet_says_nothing() -> None:
    stream, clock = io.StringIO(), _Clock()
    reporter = _reporter(stream, clock, enabled=False)
    clock.now = 30.0
    reporter("a long stage")
    time.sleep(0.4)
    reporter.close()
    assert stream.getvalue() == ""


@pytest.mark.parametrize("command", ["info", "generate", "invert", "explore", "compare", "simulate", "reproduce", "fmu", "fit"])
def test_every_command_takes_quiet(command: str, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(SystemExit) as done:
        main([command, "--help"])
    assert done.value.code == 0 and "--quiet" in capsys.readouterr().out


def test_the_stage_leaves_loading_once_the_model_is_loaded() -> None:
    # issue 59, item 12: work after the load was reported as "loading paper-sim ... (118 s)"
    import argparse

    from sflm.cli.common import load_model

    said: list[str] = []
    args = argparse.Namespace(model="paper-sim", modes=None, mode_shapes=None, output_at=None, command="invert",
                              reporter=said.append)
    load_model(args)
    assert said[0].startswith("loading paper-sim") and said[-1] == "paper-sim loaded; sflm invert at work"


def test_the_seconds_count_from_the_command_s_start_not_from_after_its_imports() -> None:
    # issue 60, item 10: the first line came 4.5-13.7 s after the start reading "(2 s)" (the clock started after the
    # imports); now the seconds shown count from when the process reached the package (sflm.STARTED), while the quiet
    # first seconds still count from the reporter's making (a quick refusal after slow imports stays one line)
    import sflm

    stream, clock = io.StringIO(), _Clock()
    reporter = _reporter(stream, clock)
    reporter._start = -7.0  # the command started 7 s before the reporter was made  # type: ignore[attr-defined]
    try:
        reporter("loading the model")
        assert stream.getvalue() == ""  # within its first `after` seconds: nothing, however long the imports took
        clock.now = 3.0
        reporter("the family")
        assert "sflm invert: the family (10 s)" in stream.getvalue()
    finally:
        reporter.close()
    assert sflm.STARTED <= time.monotonic()


def test_the_figures_are_said_before_they_are_drawn(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from types import SimpleNamespace

    from sflm.cli.common import emit

    said: list[str] = []
    args = SimpleNamespace(plot=False, json=True, command="invert", reporter=None)

    class _Say:
        def __call__(self, message: str) -> None:
            said.append(message)

        def stage(self, label: str, unit: str = "it"):  # type: ignore[no-untyped-def]
            import contextlib

            said.append(label)
            return contextlib.nullcontext(lambda done, total: None)

    from inversion import invert, smoothstep
    import modelgen

    args.reporter, args.plot = _Say(), True
    result = invert(modelgen.load("paper-sim"), smoothstep(1.57, 5.5, 5), method="ssef")
    emit(args, result, tmp_path / "run", "inversion.csv", "plot_inversion", lambda r, files: "")
    assert said[:2] == ["writing inversion.csv", "drawing the figures"]
