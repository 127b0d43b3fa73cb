"""What is derived from a link's values, kept beside its compiled models (issue 56, item 4): the continuum reference
computed once and read back bit for bit, a new key for other values, and never a failure of its own."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import modelgen
import modelgen.continuum as continuum
from modelgen.derived import FOLDER


@pytest.fixture
def counted(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> list[int]:
    """A cache root of its own, and each mesh the continuum reference solves counted."""
    monkeypatch.setenv("SFLM_CACHE_DIR", str(tmp_path / "cache"))
    meshes: list[int] = []
    solve = continuum.fe_frequencies_zeros

    def counting(geometry, elements, output_at=None):  # type: ignore[no-untyped-def]
        meshes.append(elements)
        return solve(geometry, elements, output_at)

    monkeypatch.setattr(continuum, "fe_frequencies_zeros", counting)
    return meshes


def _same(a: continuum.ContinuumReference, b: continuum.ContinuumReference) -> None:
    for name in ("natural_frequencies_hz", "zeros", "frequency_error_hz", "zero_error"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.dtype == y.dtype and x.shape == y.shape, name
        np.testing.assert_array_equal(x, y)
    assert a.elements == b.elements


def test_the_continuum_reference_is_computed_once_and_read_back_bit_for_bit(counted: list[int], tmp_path: Path) -> None:
    geometry = modelgen.load_geometry("paper-sim")
    first = continuum.continuum_reference(geometry, count=5)
    assert counted == [240, 120]
    again = continuum.continuum_reference(geometry, count=5)
    assert counted == [240, 120]  # read back: no mesh solved
    _same(first, again)
    assert first.zeros.dtype == np.complex128 and first.zeros.size == 10
    # other values, another count, another output point: each its own entry, computed
    stiffer = replace(geometry, flexural_rigidity=geometry.flexural_rigidity * 1.01)
    moved = continuum.continuum_reference(stiffer, count=5)
    assert counted == [240, 120, 240, 120] and not np.array_equal(moved.natural_frequencies_hz, first.natural_frequencies_hz)
    continuum.continuum_reference(geometry, count=4)
    continuum.continuum_reference(geometry, count=5, output_at=0.5)
    assert len(counted) == 8
    assert len(list((tmp_path / "cache" / FOLDER).glob("continuum-*.npz"))) == 4
    assert not list((tmp_path / "cache" / FOLDER).glob(".*"))  # no temporary file left


def test_a_damaged_file_is_computed_again_and_replaced(counted: list[int], tmp_path: Path) -> None:
    geometry = modelgen.load_geometry("paper-exp")
    first = continuum.continuum_reference(geometry, count=3)
    (kept,) = (tmp_path / "cache" / FOLDER).glob("continuum-*.npz")
    kept.write_bytes(kept.read_bytes()[:100])  # cut short, as by a full disk
    _same(continuum.continuum_reference(geometry, count=3), first)
    assert counted == [240, 120, 240, 120]
    _same(continuum.continuum_reference(geometry, count=3), first)  # replaced: read back
    assert len(counted) == 4


def test_a_cache_that_cannot_be_written_costs_the_computation_only(counted: list[int], tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch) -> None:
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setenv("SFLM_CACHE_DIR", str(blocked / "cache"))
    geometry = modelgen.load_geometry("paper-sim")
    first = continuum.continuum_reference(geometry, count=3)
    _same(continuum.continuum_reference(geometry, count=3), first)
    assert len(counted) == 4  # computed each time, no error
