"""A geometry whose model double precision cannot hold is refused in its own words (issue 59, item 13).

Before: ``youngs_modulus = 1e300`` and ``length = 1e-9`` were refused as "zeros: eig(A_I) gives 4, the Rosenbrock
pencil 0" (the numerics' internals), a 1e12 kg payload as "CAB = 2.47e-13 is zero to rounding". Now each names the
link's natural frequencies or its inertia ratio, the geometry's values and what to check.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import modelgen
from modelgen.errors import ModelError

DATA = Path(__file__).resolve().parents[1] / "data"


def _changed(tmp_path: Path, key: str, value: str) -> Path:
    lines = (DATA / "own-aluminium.toml").read_text().splitlines()
    out = [f"{key} = {value}" if line.split("=")[0].strip() == key else line for line in lines]
    assert out != lines
    path = tmp_path / "changed.toml"
    path.write_text("\n".join(out) + "\n")
    return path


@pytest.mark.parametrize("key,value,words", [
    ("youngs_modulus", "1e300", r"natural frequencies reach 4\.92e\+145 Hz \(EI = 1\.667e\+289 N m\^2"),
    ("length", "1e-9", r"natural frequencies reach 7\.16e\+18 Hz .*length 1e-09 m"),
    ("mass", "1e12", r"inertia about the hub, 6\.4e\+11 kg m\^2, is 2\.78e\+13 x the link's own .*payload 1e\+12 kg"),
])
def test_a_model_beyond_double_precision_is_refused_in_the_geometry_s_words(tmp_path: Path, key: str, value: str, words: str) -> None:
    with pytest.raises(ModelError, match=words) as info:
        modelgen.load(str(_changed(tmp_path, key, value)))
    assert "eig(A_I)" not in str(info.value) and "CAB" not in str(info.value) and "units" in str(info.value)


def test_the_links_of_the_test_data_are_within_both_scales() -> None:
    for path in sorted(DATA.glob("*.toml")):
        if path.name.startswith("bench"):
            continue
        modelgen.load(str(path))  # no refusal: every real link is far inside both limits
