"""``Model.to_control()``: the linear model as a python-control ``StateSpace`` (issue 10, item 2)."""

from __future__ import annotations

import sys

import numpy as np
import pytest

import modelgen
from _helpers import assert_same_zeros
from modelgen.errors import ModelError

control = pytest.importorskip("control")


@pytest.mark.parametrize(("preset", "modes"), [("paper-sim", 2), ("paper-exp", 3), ("hyperbolic", 4)])
def test_zeros_and_frequency_response_are_the_models(preset: str, modes: int) -> None:
    model = modelgen.load(preset, modes=modes)
    system = model.to_control()
    assert system.ninputs == 1 and system.noutputs == 1 and system.nstates == 2 * modes + 2
    assert system.input_labels == ["tau"] and system.output_labels == ["y"]
    assert system.state_labels == model.state_names and system.state_labels[0] == "theta"
    assert system.state_labels[modes + 1] == "thetadot"
    # python-control computes its own zeros (a different algorithm from eig(A_I)): to 1e-9 of the largest
    assert_same_zeros(control.zeros(system), model.zeros, rtol=1e-9)
    A, B, C = np.asarray(model.A), np.asarray(model.B).reshape(-1), np.asarray(model.C_out).reshape(-1)
    for w in np.logspace(-1, 3.5, 12):  # avoid s = 0: the rigid mode's double integrator
        direct = C @ np.linalg.solve(1j * w * np.eye(A.shape[0]) - A, B)
        assert abs(complex(system(1j * w)) - direct) <= 1e-10 * abs(direct)


def test_without_python_control_a_model_error_says_how_to_install(monkeypatch: pytest.MonkeyPatch) -> None:
    model = modelgen.load("paper-sim")
    monkeypatch.setitem(sys.modules, "control", None)  # `import control` raises ImportError
    with pytest.raises(ModelError, match=r"sflm\[control\]"):
        model.to_control()
