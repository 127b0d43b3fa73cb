"""Leaving the untrusted unstable zeros free (``invert(..., zeros=...)``, issue 13 item 2).

paper-sim with four clamped-mass modes has five unstable zeros: 56.3i-ish and 76.1 converge
to the continuum, 265.4 +- 142.5i (with its stable mirror) is a truncation artefact
(``modelgen.zero_status``). Left free, the artefact follows its bounded particular
solution and has no continuity rows; the torque must still drive the *full* plant along
``y~`` -- checked here independently of the inversion's own verification.
"""

from __future__ import annotations

import json
import warnings

import numpy as np
import pytest

import modelgen
from _helpers import linear_plant_output
from inversion import invert, smoothstep
from inversion.errors import InversionError, SettingsError
from inversion.lti.internal import ModalInternalDynamics
from inversion.lti.system import NormalForm
from inversion.lti.zero_dynamics import free_zeros
from modelgen.zero_status import zero_status
from modelgen.zeros import is_unstable

TRAJECTORY = smoothstep(1.57, 5.5, 5)


@pytest.fixture(scope="module")
def model4() -> modelgen.Model:
    return modelgen.load("paper-sim", modes=4)


@pytest.fixture(scope="module")
def pair(model4: modelgen.Model) -> tuple:
    # the smallest error within the torque limit (objective "error"): both meet the same request closely
    return (invert(model4, TRAJECTORY, auto=True, rate=2000.0, objective="error"),
            invert(model4, TRAJECTORY, auto=True, rate=2000.0, zeros="physical", objective="error"))


def test_physical_frees_exactly_the_unstable_artefacts(model4: modelgen.Model) -> None:
    form = NormalForm.of_model(model4)
    status = zero_status(model4)
    expected = status.zeros[status.artefact & is_unstable(status.zeros)]
    freed = free_zeros(model4, form, "physical").modal()
    assert expected.size == 2  # 265.4 +- 142.5i
    np.testing.assert_allclose(np.sort_complex(freed.lam[freed.free]), np.sort_complex(expected), rtol=1e-10)
    assert freed.n_unstable == form.modal().n_unstable - 2
    assert not np.any(freed.free & freed.unstable)
    converged = free_zeros(model4, form, "converged").modal()
    assert converged.n_unstable == int(np.count_nonzero(status.converged & is_unstable(status.zeros)))


def test_no_artefact_no_change() -> None:
    model = modelgen.load("paper-sim")  # two modes: every zero is physical
    form = NormalForm.of_model(model)
    assert free_zeros(model, form, "physical") is form
    assert free_zeros(model, form, "all") is form


def test_the_full_plant_follows_the_redefined_output(model4: modelgen.Model, pair: tuple) -> None:
    full, physical = pair
    zd = physical.summary["zero_dynamics"]
    assert zd["zeros"] == "physical" and len(zd["free"]) == 2 and zd["n_unstable_model"] == 5 and zd["n_unstable_constrained"] == 3
    assert physical.summary["r"] < full.summary["r"]  # fewer constraint rows: fewer exponentials
    move = physical.summary["move"]
    for result in pair:
        tip, _ = linear_plant_output(model4, result)  # from rest, exactly: independent of the inversion's own check
        assert np.abs(tip - result.y).max() <= 1e-6 * move  # the inversion's PLANT_TOLERANCE
        assert result.summary["verification"]["plant_output_error"] <= 1e-6
    # the same request met by both: the torques agree to the artefacts' share (measured 4e-6 of the peak)
    assert np.abs(physical.tau - full.tau).max() <= 1e-4 * full.summary["peak_torque"]
    assert physical.summary["max_redefinition_error"] <= 1e-6 * move


def test_the_paper_member_solves_once_the_artefacts_are_free(model4: modelgen.Model) -> None:
    # the paper's member (5 segments, h = 2, Cdec = (1e-4, 1), paper joining) fails on four modes
    # with the artefacts constrained; with them free it solves and meets the paper's 5.73 mm
    member = dict(segments=5, h=2, cdec=(1e-4, 1.0), joining="paper")
    with pytest.raises(InversionError, match="constraint residual"):
        invert(model4, TRAJECTORY, **member)
    result = invert(model4, TRAJECTORY, zeros="physical", **member)
    assert 5.0e-3 < result.summary["max_redefinition_error"] < 6.5e-3
    assert result.summary["verification"]["plant_output_error"] <= 1e-6


def test_hostile_options(model4: modelgen.Model) -> None:
    with pytest.raises(SettingsError, match="zeros"):
        invert(model4, TRAJECTORY, zeros="artefacts")
    with pytest.raises(SettingsError, match="zeros.*stable"):
        invert(model4, TRAJECTORY, zeros="physical", method="stable")
    with pytest.raises(SettingsError, match="zeros.*rest"):
        invert(model4, TRAJECTORY, zeros="physical", end="rest")
    form = NormalForm.of_model(model4)
    stable_zero = next(z for z in form.modal().lam if z.real < -1)
    with pytest.raises(InversionError, match="not an unstable zero"):
        ModalInternalDynamics.from_matrices(form.AI, form.BI, 0.0, (stable_zero,))


def test_cli_reports_the_free_zeros(tmp_path, capsys) -> None:
    from sflm.cli import main

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(["invert", "paper-sim", "--modes", "4", "--zeros", "physical", "--segments", "5", "--h", "2", "--cdec", "1e-4", "1",
                     "--joining", "paper", "--json", "--out", str(tmp_path)])
    assert code == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["zero_dynamics"]["n_unstable_constrained"] == 3
    assert [round(v, 1) for v in summary["zero_dynamics"]["free"][0]] in ([265.4, 142.5], [265.4, -142.5])
