"""Inverting a model without constraining the zeros it cannot be trusted with.

An assumed-mode model's highest zeros are truncation effects, and from ``n = 3-4`` on its
undamped models carry complex quadruplets the continuum does not have
(:mod:`modelgen.zero_status`). Counted as unstable they add constraint rows and
exponentials to every segment system for nothing the physics contains. :func:`free_zeros`
keeps constrained

* ``"all"`` -- every unstable zero (the model as it is; the default);
* ``"physical"`` -- all but the truncation artefacts;
* ``"converged"`` -- only the zeros converged to the continuum's;

and leaves the others **free**: such a mode follows its bounded particular solution
``z_i = sum_j beta_i c_j e^{mu_j s} / (mu_j - lambda_i)`` inside each segment (Eq. (17)
without its growing complementary part) and has no continuity row, so it jumps a little at
the joints and at ``t_0``. The plant is *not* reduced: the verification drives the full
model's plant from its true initial state (:func:`inversion.family.verify.plant_run`) and the
member is accepted only if the tip follows ``y~`` to ``PLANT_TOLERANCE`` of the move, as
for any member. What leaving a zero free costs is therefore measured on the full model,
never assumed.

Truncating the dropped modes instead (a reduced internal dynamics with their coordinates
held at zero) was measured and rejected: it changes the plant's poles (paper-sim with four
clamped-mass modes: the first flexible mode moves from 41.5 to 48.9 rad/s) and the full
plant driven by its torque ends metres from ``y~``.
"""

from __future__ import annotations

import dataclasses
from typing import TYPE_CHECKING, Any

import numpy as np

from ..config import DEFAULTS
from ..errors import SettingsError
from ..options import ZeroSet, values
from .system import NormalForm

if TYPE_CHECKING:
    from modelgen.model import Model

__all__ = ["ZERO_SETS", "free_zeros", "zero_dynamics_summary"]

#: Which unstable zeros the inversion constrains (module docstring).
ZERO_SETS = values(ZeroSet)


def free_zeros(model: "Model", form: NormalForm, which: str, tol: float | None = None) -> NormalForm:
    """``form`` with the unstable zeros outside ``which`` left free.

    The zeros are judged by :func:`modelgen.zero_status.zero_status` against the continuum
    (about 0.3 s); ``"all"`` returns ``form`` itself.

    Parameters
    ----------
    model : Model
        The model of ``form`` (its geometry gives the continuum).
    form : NormalForm
    which : {"all", "physical", "converged"}
    tol : float, optional
        Relative tolerance of "converged" (default :data:`modelgen.zero_status.DEFAULT_ZERO_TOL`).

    Raises
    ------
    SettingsError
        For an unknown ``which``.
    """
    if which not in ZERO_SETS:
        raise SettingsError("zeros", which, " or ".join(repr(z) for z in ZERO_SETS))
    if which == ZeroSet.ALL:
        return form
    from modelgen.zero_status import zero_status  # lazy: the continuum needs SciPy
    from modelgen.zeros import is_unstable

    status = zero_status(model, tol)
    trusted = status.converged if which == "converged" else ~status.artefact
    unstable = is_unstable(status.zeros)
    released = tuple(complex(z) for z in status.zeros[unstable & ~trusted & (status.zeros.imag >= 0)])
    if not released:
        return form
    return dataclasses.replace(form, name=f"{form.name} ({which} zeros)", free_zeros=released, _modal={})


def zero_dynamics_summary(form: NormalForm, which: str, eps: float = DEFAULTS.eps) -> dict[str, Any]:
    """JSON-ready ``summary["zero_dynamics"]``.

    JSON-ready ``summary["zero_dynamics"]``: the set kept, the zeros left free, the unstable counts.

    Parameters
    ----------
    form : NormalForm
        The plant's normal form.
    which : str
        The set of unstable zeros constrained.
    eps : float, optional
        The unstable-set tolerance.
    """
    modal = form.modal(eps)
    free = modal.lam[modal.free]
    return {
        "zeros": which,
        "free": [[float(z.real), float(z.imag)] for z in free],
        "n_unstable_constrained": modal.n_unstable,
        "n_unstable_model": modal.n_unstable + int(np.count_nonzero(modal.free)),
    }
