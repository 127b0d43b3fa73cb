"""Today's outputs held as references: the same commands give the same summary, table and C after any rearrangement.

Each case runs ``sflm`` as a user does (in this process, through :func:`sflm.cli.main`) into a temporary folder and
compares what it wrote with ``tests/data/reference-runs/<case>.json``: the summary (less its run id and the seconds
each stage took, which are the clock's), the SHA-256 of ``inversion.csv`` and of the exported C, or a refusal's JSON
record. The references were written by the code before the door was rearranged (issue 55); a difference fails with
the keys that differ. ``pytest tests/integration/test_reference_runs.py --update-references`` writes them again (after a
change that is meant to change an output: say so in the commit).

The outputs are compared bit for bit, and bits depend on the machine's arithmetic as well as on the code: the kernels
OpenBLAS picks for the CPU (and NumPy's SIMD dispatch) sum in another order, so that the same code gives eigenvalues,
programme solutions and tables that differ in their last digits (on an AMD EPYC, OpenBLAS's Haswell kernels: the zeros
of paper-sim to 1e-15, figures at rounding level such as a drift of 1e-17 m to 100 % of themselves, a re-plan's torque
ratio to 8e-8 -- its linear programme's vertex). So the references are kept by the machine's flavour
(:func:`flavour`): ``reference-runs/<case>.json`` were written on the machines of the earlier sessions, and
``reference-runs/<flavour>/<case>.json`` on a machine of that flavour; a run passes when it is, bit for bit, one of the
sets kept, and ``--update-references`` writes the set of the machine it runs on. A change meant to change an output
writes the set of each flavour again, or removes the sets it could not write (and says so in the commit).
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import json
import re
from pathlib import Path
from typing import Any

import pytest

from sflm.cli import main

DATA = Path(__file__).resolve().parents[1] / "data"
REFERENCES = DATA / "reference-runs"
#: the test data's files as the references spell them (DATA is this folder wherever the clone is)
ALUMINIUM = "DATA/own-aluminium.toml"
STRIP = "DATA/steel-strip-3mm.toml"

#: name -> the command's arguments after ``sflm`` (OUT is the run's folder, DATA the test data's); slow ones marked
CASES: dict[str, tuple[list[str], bool]] = {
    "paper-sim": (["invert", "paper-sim", "--export-c", "OUT/c"], False),
    "paper-sim-rest": (["invert", "paper-sim", "--end", "rest"], False),
    "paper-sim-replan": (["invert", "paper-sim", "--method", "replan"], False),
    "paper-sim-ocp": (["invert", "paper-sim", "--method", "ocp", "--export-c", "OUT/c"], True),
    "paper-exp": (["invert", "paper-exp"], False),
    "paper-exp-stable": (["invert", "paper-exp", "--method", "stable", "--export-c", "OUT/c"], False),
    "paper-exp-zv": (["invert", "paper-exp", "--method", "zv", "--max-error", "inf"], False),
    "paper-exp-ocp": (["invert", "paper-exp", "--method", "ocp"], False),
    "paper-exp-preview": (["invert", "paper-exp", "--trajectory", "smoothstep:0.1:0.3:2", "--preview", "0.2"], True),
    "paper-exp-corners": (["invert", "paper-exp", "--trajectory", "smoothstep:0.1:0.6:2", "--method", "ocp", "--uncertainty",
                           "link.flexural_rigidity=5%"], True),
    "aluminium": (["invert", ALUMINIUM, "--trajectory", "smoothstep:0.5:2:2", "--export-c", "OUT/c"], False),
    "strip-pd": (["invert", STRIP, "--trajectory", "smoothstep:0.5:1.5:2", "--controller", "pd"], False),
    "transfer-function": (["invert", "(s - 1)(s^2 + 4)/((s + 1)^2 (s + 2)^3)", "--trajectory", "smoothstep:1:12:6"], True),
    "refusal": (["invert", "paper-sim", "--max-error", "1e-9", "--json"], False),
    "compare": (["compare", "paper-exp", "--json"], True),
}

#: Keys whose values are the clock's (or a new run's id), removed at any depth before comparing.
CLOCK_KEYS = ("seconds", "run")


#: The clock's figures inside a message ("504 tried in 0.9 s"), masked.
CLOCK_TEXT = re.compile(r"tried in [0-9.]+ s")


def without_clock(value: Any) -> Any:
    """``value`` without the keys of :data:`CLOCK_KEYS` (at any depth) and the clock's figures in its texts."""
    if isinstance(value, str):
        return CLOCK_TEXT.sub("tried in ? s", value)
    if isinstance(value, dict):
        return {k: without_clock(v) for k, v in value.items() if k not in CLOCK_KEYS}
    if isinstance(value, list):
        return [without_clock(v) for v in value]
    return value


def flavour() -> str:
    """The machine's arithmetic, as far as it decides the outputs' last bits: the BLAS library and the kernels it chose
    for the CPU (threadpoolctl's ``internal_api`` and ``architecture``), and whether NumPy dispatches to AVX-512."""
    from threadpoolctl import threadpool_info

    blas = next((f"{i.get('internal_api')}-{i.get('architecture')}" for i in threadpool_info() if i.get("user_api") == "blas"),
                "blas-unknown")
    try:
        from numpy._core._multiarray_umath import __cpu_features__ as features
    except ImportError:  # NumPy < 2
        from numpy.core._multiarray_umath import __cpu_features__ as features  # type: ignore[no-redef]
    return blas + ("-avx512" if features.get("AVX512F") else "")


def reference_sets(name: str) -> list[Path]:
    """The references of a case kept for each flavour, this machine's first (module docstring)."""
    own = REFERENCES / flavour() / f"{name}.json"
    others = sorted(p for p in REFERENCES.glob(f"*/{name}.json") if p != own)
    return [p for p in (own, *others, REFERENCES / f"{name}.json") if p.is_file()]


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def run_case(argv: list[str], out: Path) -> dict[str, Any]:
    """What one case wrote and printed, as the reference holds it."""
    args = [a.replace("OUT", str(out)).replace("DATA/", f"{DATA}/") for a in argv] + ["--out", str(out), "-q"]
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed), contextlib.redirect_stderr(io.StringIO()):
        status = main(args)
    record: dict[str, Any] = {"argv": argv, "status": status}
    if "--json" in argv:
        record["printed"] = without_clock(json.loads(printed.getvalue()))
    if argv[0] == "invert" and status == 0:
        record["summary"] = without_clock(json.loads((out / "summary.json").read_text()))
        record["files"] = {str(p.relative_to(out)): digest(p) for p in sorted(out.rglob("*"))
                           if p.is_file() and p.name != "summary.json" and p.suffix in (".csv", ".c", ".h")}
    return record


def differences(a: Any, b: Any, where: str = "") -> list[str]:
    """Where two JSON values differ (key paths), the first few."""
    if isinstance(a, dict) and isinstance(b, dict):
        out = [f"{where}/{k}: only in the reference" for k in a.keys() - b.keys()]
        out += [f"{where}/{k}: only in this run" for k in b.keys() - a.keys()]
        for k in a.keys() & b.keys():
            out += differences(a[k], b[k], f"{where}/{k}")
        return out
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in differences(x, y, f"{where}[{i}]")]
    return [] if a == b else [f"{where}: reference {a!r:.120}, this run {b!r:.120}"]


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if slow else n for n, (_, slow) in CASES.items()])
def test_outputs_are_todays(name: str, tmp_path: Path, request: pytest.FixtureRequest) -> None:
    argv, _ = CASES[name]
    found = run_case(argv, tmp_path / "run")
    if request.config.getoption("--update-references"):
        path = REFERENCES / flavour() / f"{name}.json"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(found, indent=1) + "\n")
        return
    found = json.loads(json.dumps(found))  # tuples as lists, as the reference was read
    kept = reference_sets(name)
    assert kept, f"{name}: no reference kept (pytest {Path(__file__).name} --update-references writes this machine's)"
    diffs = {path: differences(json.loads(path.read_text()), found) for path in kept}
    if any(not diff for diff in diffs.values()):
        return
    path, diff = min(diffs.items(), key=lambda item: len(item[1]))
    assert not diff, (f"{name}: {len(diff)} differences from the closest reference ({path.relative_to(REFERENCES)}, of "
                      f"{len(kept)} kept; this machine is {flavour()}); the first: " + "; ".join(sorted(diff)[:8]))
