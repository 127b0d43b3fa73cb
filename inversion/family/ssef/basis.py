"""The exponentials of a segment: their rates (Eqs. (34)-(36)), the matched ones, and how many a joining needs.

In segment ``k`` (local time ``s = t - t_k`` in ``[0, T]``) the desired acceleration is
replaced by ``yddot~(s) = sum_j c_j exp(mu_j s)``, ``mu_j <= 0`` (Eq. (29)), with ``mu_j``
equally spaced from ``ln(Cdec_s)/T`` to ``ln(Cdec_f)/T``. The ``anchored`` joining replaces
slow exponents by rates *matched* to the unstable zeros much faster than them
(:func:`matched_exponents`, docs/method.md section 3).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ...lti.internal import ModalInternalDynamics
from ...options import Joining, values

__all__ = ["JOININGS", "MATCH_RATIO", "exponents", "matched_exponents", "row_count"]

FloatArray = NDArray[np.float64]

#: Joining variants (see the module docstring).
JOININGS: tuple[str, ...] = values(Joining)
#: An unstable zero faster than this multiple of the fastest slow exponent gets a matched
#: exponential in the ``anchored`` joining.
MATCH_RATIO = 2.0
#: Smallest ratio between two matched rates (keeps their columns apart).
_MATCH_GAP = 1.25


def exponents(duration: float, cdec_fast: float, cdec_slow: float, r: int) -> FloatArray:
    """Equally spaced exponents of one segment, Eqs. (34)-(36).

    ``mu_s = ln(Cdec_s)/T``, ``mu_f = ln(Cdec_f)/T``, ``mu_j = mu_s + (mu_f - mu_s)(j-1)/(r-1)``.
    ``Cdec_s = 1`` gives ``mu_1 = 0``: a constant term.

    Parameters
    ----------
    duration : float
        The segment's duration ``T`` (s).
    cdec_fast : float
        ``Cdec_f``.
    cdec_slow : float
        ``Cdec_s``.
    r : int
        Number of exponents.
    """
    mu_s = math.log(cdec_slow) / duration
    mu_f = math.log(cdec_fast) / duration
    return np.asarray(mu_s + (mu_f - mu_s) * np.arange(r) / max(r - 1, 1))


def matched_exponents(modal: ModalInternalDynamics, duration: float, cdec_fast: float) -> FloatArray:
    """Exponents matched to the unstable zeros.

    Exponents matched to the unstable zeros faster than the slow ones (``anchored``).

    A real zero ``lambda`` with ``|lambda| > MATCH_RATIO |ln(Cdec_f)|/T`` gives
    ``-|lambda|``; a complex pair gives ``-2|lambda|/3`` and ``-4|lambda|/3`` (one per
    constraint row). Rates closer than a factor 1.25 are spread to that ratio.

    Parameters
    ----------
    modal : ModalInternalDynamics
        The diagonalised internal dynamics.
    duration : float
        The segment's duration ``T`` (s).
    cdec_fast : float
        ``Cdec_f``.
    """
    fastest = abs(math.log(cdec_fast)) / duration
    pairs = {i for i, part in modal.rows if part == "im"}
    rates: list[float] = []
    for i, part in modal.rows:
        size = float(abs(modal.lam[i]))
        if size <= MATCH_RATIO * fastest:
            continue
        if i not in pairs:
            rates.append(size)
        else:
            rates.append(size * (2.0 / 3.0 if part == "re" else 4.0 / 3.0))
    rates.sort()
    for k in range(1, len(rates)):
        rates[k] = max(rates[k], _MATCH_GAP * rates[k - 1])
    return -np.asarray(rates, dtype=float)


def row_count(joining: str, h: int, n_unstable_rows: int) -> int:
    """``r``: conditions (and exponentials) per segment.

    Parameters
    ----------
    joining : str
        The joining.
    h : int
        The derivatives matched at the edges.
    n_unstable_rows : int
        Conditions the unstable zeros add.
    """
    return 2 * (h + 1) + (0 if joining == Joining.PAPER else 2) + n_unstable_rows
