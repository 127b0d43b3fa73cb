"""``--uncertainty fit:FILE`` on hostile calibrated files (issue 59, item 7): 7 tracebacks and a hang before.

Each file is refused in one :class:`SettingsError` naming the file and the offending table or key; a good file gives
each fitted parameter's interval as a relative range.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from inversion.errors import SettingsError
from inversion.studies.robustness import parse_uncertainty
from modelgen.fit import spread_of_calibration

GOOD = """[calibration.parameters."link.flexural_rigidity"]
value = 1.2
interval_95 = 0.03

[calibration.parameters."payload.mass"]
value = 0.02
interval_95 = 0.0004
"""

#: name -> (the file's text, words its refusal must hold)
HOSTILE: dict[str, tuple[str, str]] = {
    "calibration-a-number": ("calibration = 5\n", "no [calibration.parameters] table"),
    "parameters-a-list": ("[calibration]\nparameters = [1.0, 2.0]\n", "no [calibration.parameters] table"),
    "no-interval": ('[calibration.parameters."payload.mass"]\nvalue = 0.02\n', "interval_95 = 'None', not a finite number"),
    "interval-a-string": ('[calibration.parameters."payload.mass"]\nvalue = 0.02\ninterval_95 = "0.001"\n',
                          "interval_95 = '0.001', not a finite number"),
    "interval-a-bool": ('[calibration.parameters."payload.mass"]\nvalue = 0.02\ninterval_95 = true\n', "not a finite number"),
    "value-zero": ('[calibration.parameters."payload.mass"]\nvalue = 0.0\ninterval_95 = 0.001\n', "a value other than 0"),
    "value-nan": ('[calibration.parameters."payload.mass"]\nvalue = nan\ninterval_95 = 0.001\n', "value = 'nan', not a finite"),
    "a-parameter-a-number": ('[calibration.parameters]\n"payload.mass" = 0.02\n', "is a float, not a table"),
    "not-a-parameter": ('[calibration.parameters."link.colour"]\nvalue = 1.0\ninterval_95 = 0.1\n',
                        '[calibration.parameters."link.colour"] is not a parameter sflm fit calibrates'),
    "wider-than-its-value": ('[calibration.parameters."payload.mass"]\nvalue = 0.02\ninterval_95 = 0.05\n',
                             "payload.mass's 95 % interval +-0.05 is 250 % of its value 0.02"),
    "deep": ("x = " + "[" * 100_000 + "]" * 100_000 + "\n", "nested"),
    "not-toml": ("[calibration\n", "not valid TOML"),
}


@pytest.mark.parametrize("name", list(HOSTILE))
def test_a_hostile_calibration_is_refused_naming_the_file_and_key(name: str, tmp_path: Path) -> None:
    text, words = HOSTILE[name]
    path = tmp_path / f"{name}.toml"
    path.write_text(text)
    with pytest.raises(SettingsError) as caught:
        parse_uncertainty(f"fit:{path}")
    message = str(caught.value)
    assert words in message and str(path) in message and message.startswith("uncertainty = "), message


def test_a_pipe_is_refused_at_once(tmp_path: Path) -> None:
    # fit: a FIFO blocked forever (the read waited for a writer)
    fifo = tmp_path / "cal.toml"
    os.mkfifo(fifo)
    with pytest.raises(SettingsError, match="not a regular file"):
        spread_of_calibration(fifo)


def test_a_good_calibration_gives_its_relative_intervals(tmp_path: Path) -> None:
    path = tmp_path / "cal.toml"
    path.write_text("\ufeff" + GOOD + '\n[calibration.parameters."hub.coulomb_friction"]\nvalue = 0.01\ninterval_95 = 0.02\n')
    # a byte-order mark is read; the hub's dry friction (its interval wider than its value) is left out: the robust
    # judgement's linear loop has none to perturb
    assert dict(parse_uncertainty(f"fit:{path}").ranges) == pytest.approx({"link.flexural_rigidity": 0.025, "payload.mass": 0.02})
