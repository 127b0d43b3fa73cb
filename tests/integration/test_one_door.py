"""One typed problem at the door, each method an object of one registry (issue 55).

* a method registered here, in this file alone, is in ``compare``'s rows, the command line's ``--method`` choices and
  help, the summary and its text, the figures' words and the exported C's header;
* the library writes the run the command line reads back (``sflm simulate --feedforward``);
* the last release's flat keywords still work, with a warning naming the new spelling, and give the same result;
* ``invert`` takes at most eight parameters, ``inversion/api.py`` is at most 500 lines.
"""

from __future__ import annotations

import contextlib
import dataclasses
import inspect
import io
import json
import warnings
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping

import pytest

import inversion
import modelgen
from inversion import Bounds, Family, InversionMethod, Problem, Sampling, Stable, invert, register
from inversion.options import unregister
from sflm.cli import main

ROOT = Path(__file__).resolve().parents[2]


@dataclasses.dataclass(frozen=True)
class Toy(InversionMethod):
    """A method of this test alone: stable inversion's table under another name (what matters is where it shows)."""

    name = "toy"
    label = "the toy method"
    title = "toy feedforward"
    help = "a method registered by a test"
    rank = 50.0

    def solve(self, problem: Problem, say: Callable[[str], None]) -> Any:
        result = Stable().solve(problem, say)
        result.summary["method"] = self.name
        result.summary["settings"] = {**result.summary["settings"], "method": self.name}
        return result

    def settings_text(self, summary: Mapping[str, Any]) -> str:
        return "the toy's own settings"

    def c_text(self, summary: Mapping[str, Any]) -> str:
        return "toy method: registered by tests/integration/test_one_door.py"


@pytest.fixture
def toy() -> Iterator[type[Toy]]:
    register(Toy)
    try:
        yield Toy
    finally:
        unregister("toy")


def run_cli(*args: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(list(args))
    return status, out.getvalue(), err.getvalue()


def test_a_method_registered_here_is_everywhere(toy: type[Toy], tmp_path: Path) -> None:
    from inversion.studies.compare import compare_rows
    from sflm.cli import parser
    from sflm.plots import _inversion_words

    assert "toy" in inversion.method_names() and "toy" in [name for name, _ in compare_rows()]
    sub = next(a for a in parser()._actions if isinstance(a, __import__("argparse")._SubParsersAction))
    method = next(a for a in sub.choices["invert"]._actions if "--method" in a.option_strings)
    assert "toy" in method.choices and "toy: a method registered by a test" in (method.help or "")
    status, out, err = run_cli("invert", "paper-exp", "--method", "toy", "--export-c", str(tmp_path / "c"), "--out", str(tmp_path / "run"),
                               "-q")
    assert status == 0, err
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["method"] == "toy" and out.startswith("paper-exp: the toy method (the toy's own settings)")
    assert "toy method: registered by tests/integration/test_one_door.py" in (tmp_path / "c" / "feedforward.h").read_text()
    result = inversion.read_run(tmp_path / "run", modelgen.load("paper-exp"))
    assert _inversion_words(result)["what"] == "toy feedforward"
    comparison = inversion.studies.compare.compare(Problem(modelgen.load("paper-exp"), inversion.trajectory_from_spec("paper-exp")))
    (row,) = [r for r in comparison.rows if r["method"] == "toy"]
    assert row["status"] == "ok" and row["settings"] == "the toy's own settings"


def test_a_method_needs_a_name_of_its_own() -> None:
    @dataclasses.dataclass(frozen=True)
    class Impostor(InversionMethod):
        name = "ocp"

    with pytest.raises(ValueError, match="'ocp' is OptimalControl's"):
        register(Impostor)
    with pytest.raises(ValueError, match="a method needs a name"):
        register(type("Nameless", (InversionMethod,), {}))


def test_the_library_writes_the_run_the_command_line_reads(tmp_path: Path) -> None:
    model = modelgen.load("paper-exp")
    result = invert(Problem(model, inversion.trajectory_from_spec("paper-exp")))
    files = inversion.write_run(result, tmp_path / "run")
    assert [f.name for f in files] == ["inversion.csv", "summary.json"]
    record = json.loads((tmp_path / "run" / "summary.json").read_text())["run"]
    assert set(record["files"]) == {"inversion.csv"}
    status, out, err = run_cli("simulate", "paper-exp", "--feedforward", str(tmp_path / "run"), "--plant", "linear", "--controller", "none", "--coulomb-friction", "0",
                               "--t-end", "1.0", "--out", str(tmp_path / "sim"), "--json", "-q")
    assert status == 0, err
    simulated = json.loads(out)
    # the linear plant driven by the run's held table from rest: the tip within the table's own held error of y_d
    assert simulated["max_tracking_error"] <= result.summary["sampled"]["max_tip_error"] * 1.01 + 1e-9


def test_the_flat_keywords_still_work_with_the_new_spelling_named() -> None:
    model = modelgen.load("paper-sim")
    move = inversion.smoothstep(1.57, 5.5, 5)
    with pytest.warns(DeprecationWarning, match=r"max_error= -> inversion\.Bounds\(max_error=\.\.\.\).*segments= -> "
                                                 r"method=inversion\.Family\(segments=\.\.\.\)"):
        old = invert(model, move, segments=5, h=2, cdec=(1e-4, 1.0), max_error=0.01, period=0.002)
    new = invert(Problem(model, move, bounds=Bounds(max_error=0.01), sampling=Sampling(period=0.002)),
                 method=Family(segments=5, h=2, cdec=(1e-4, 1.0)))
    same = {k: v for k, v in old.summary.items() if k != "auto"}
    assert same == {k: v for k, v in new.summary.items() if k != "auto"}
    assert (old.tau == new.tau).all()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        invert(model, move)  # a model and its move: the problem of the defaults, no warning
    with pytest.raises(inversion.SettingsError, match=r"^max_error = 0\.01 .*None with a Problem: inversion\.Bounds"):
        invert(Problem(model, move), max_error=0.01)
    with pytest.raises(inversion.SettingsError, match=r"^colour = 'red'.*a keyword of inversion\.invert"):
        invert(model, move, colour="red")


def test_the_door_is_narrow_and_its_module_short() -> None:
    assert len(inspect.signature(invert).parameters) <= 8
    assert len((ROOT / "inversion" / "api.py").read_text().splitlines()) <= 500


def test_the_problem_names_what_it_refuses() -> None:
    model = modelgen.load("paper-exp")
    move = inversion.smoothstep(0.1, 0.6, 2)
    for make, pattern in [
        (lambda: Bounds(max_torque=float("nan")), r"^max_torque = nan"),
        (lambda: Bounds(max_torque_rate=0), r"^max_torque_rate = 0 .*> 0"),
        (lambda: Sampling(period=-1e-3), r"^period = -0\.001 .*finite number > 0"),
        (lambda: Sampling(hold="sample"), r"^hold = 'sample' .*point, zoh"),
        (lambda: Problem(model, move, sampling=Sampling(period=0.5)), r"^period = 0\.5 .*at most half the move"),
        (lambda: Problem(model, move, margin=0.7), r"^margin = 0\.7 .*\[0, 0\.5\]"),
        (lambda: Problem(model, move, preview=-1.0), r"^preview = -1\.0"),
        (lambda: Problem(model, move, loop=inversion.Loop(controller="pid")), r"^controller = 'pid'"),
        (lambda: Problem(model, move, loop=inversion.Loop(controller="pd", gains=(-1.0, 0.0))), r"^gains = "),
        (lambda: Problem(model, move, bounds=0.01), r"^bounds = 0\.01 .*inversion\.Bounds"),  # type: ignore[arg-type]
    ]:
        with pytest.raises(inversion.SettingsError, match=pattern):
            make()
