"""The segment problem: output redefinition by a summation of stable exponential functions.

In segment ``k`` (local time ``s = t - t_k`` in ``[0, T]``) the desired acceleration is
replaced by (Eq. (29))::

    yddot~(s) = sum_{j=1}^{r} c_j exp(mu_j s),   mu_j <= 0

with ``mu_j`` equally spaced from ``ln(Cdec_s)/T`` to ``ln(Cdec_f)/T`` (Eqs. (34)-(36)).
The ``r`` coefficients solve one linear condition per exponential. Three *joinings*
choose the conditions:

``paper`` -- the paper's, Eqs. (30)-(31), ``r = 2(h+1) + n_u``:

1. smooth joining, ``p = 0..h``: ``yddot~^(p)`` equals ``yddot_d^(p)`` at ``t_k+`` and
   ``t_{k+1}-``;
2. bounded unstable modes with continuity (conditions 3-2 and 3-3): for ``i`` in ``U``,
   ``sum_j beta_i c_j / (mu_j - lambda_i) = z_i(t_k)`` -- the complementary part of
   ``z_i`` vanishes and it starts where the previous segment ended. A complex pair gives
   the real and imaginary parts of one member, so ``c`` stays real.

``y~`` and ``ydot~`` are carried from segment to segment and drift from ``y_d``; so is the
unstable state, which short segments amplify geometrically.

``position`` -- the paper's conditions plus ``ydot~(t_{k+1}) = ydot_d(t_{k+1})`` and
``y~(t_{k+1}) = y_d(t_{k+1})`` at every joint (``r = 2(h+1) + 2 + n_u``): no drift of the
output, but the unstable state is still carried.

``anchored`` -- smooth and position joining as ``position``, and the unstable modes start
and end every segment on the exact-tracking values ``z*`` of :mod:`inversion.family.anchors`
(a finite-horizon condition instead of 3-2)::

    z_i(t_k) + beta_i int_0^T exp(-lambda_i u) yddot~(u) du = exp(-lambda_i T) z*_i(t_{k+1})

The segments then pass no unstable state to each other (nothing to amplify), ``y_d``
satisfies the conditions of every interior segment, and the systems are independent. An
unstable zero much faster than the slow exponentials (``|lambda| > 2 |mu_f|``) makes its
condition nearly a combination of the smooth-joining rows (it only sees the first
``1/|lambda|`` seconds of the segment); for such zeros the basis takes *matched*
exponentials in place of as many slow ones: ``-|lambda|`` for a real zero,
``-2|lambda|/3`` and ``-4|lambda|/3`` for a complex pair. That keeps the segment systems of
models with many modes solvable in double precision (condition numbers of 1e6-1e9 where
the equally spaced basis reaches 1e15-1e18).

``end="rest"`` (the paper's Remark 2) adds to the last segment ``y~(t_f) = y_d(t_f)``,
``ydot~(t_f) = ydot_d(t_f)`` (the ``paper`` joining lacks them) and ``X_I(t_f) = 0`` -- zero
deflections and rates -- for every mode not anchored already: as many more exponentials
there. The other segments keep the same number of columns, the extra ones held at zero by
identity rows (and absent from every other row), so that all systems still solve in one batch.

Everything then follows in closed form (no ODE is integrated): ``ydot~``, ``y~``, and each
internal mode ``z_i(s) = sum_j W_ji exp(mu_j s) + K_i exp(lambda_i (s - a_i))`` with
``W_ji = beta_i c_j/(mu_j - lambda_i)``, anchored at ``a_i = 0`` (stable modes: ``K_i``
from ``z_i(0)``), at ``a_i = T`` (anchored unstable modes: from ``z*_i(t_{k+1})``) or
without a complementary part (``K_i = 0``, the paper's unstable modes).

The assembly and the evaluation work in double or in extended precision (the inputs'
``dtype``); :mod:`inversion.family.verify` uses that to re-evaluate a result.

The package holds one idea a module: the exponents (:mod:`~inversion.family.ssef.basis`), the plan
of a batch (:mod:`~inversion.family.ssef.plan`), the conditions (:mod:`~inversion.family.ssef.conditions`),
the solve (:mod:`~inversion.family.ssef.solve`) and the closed-form evaluator
(:mod:`~inversion.family.ssef.evaluate`).
"""

from __future__ import annotations

from typing import Literal

from .basis import JOININGS, MATCH_RATIO, exponents, matched_exponents, row_count
from .conditions import segment_matrices
from .evaluate import Coefficients, SegmentSolution
from .plan import SegmentPlan, build_plan
from .solve import PlanSolution, SolverName, solve_plan

__all__ = [
    "JOININGS",
    "MATCH_RATIO",
    "Joining",
    "SolverName",
    "SegmentPlan",
    "SegmentSolution",
    "Coefficients",
    "exponents",
    "matched_exponents",
    "row_count",
    "PlanSolution",
    "build_plan",
    "segment_matrices",
    "solve_plan",
]

Joining = Literal["paper", "position", "anchored"]
