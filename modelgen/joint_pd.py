"""The joint PD of the closed loop (Eq. (40)), by one rule: the rigid-body poles critically damped a decade below the first flexible mode.

Without gains of its own (the paper's cases have theirs), a link gets
``k_P = J omega_c^2``, ``k_D = 2 J omega_c`` with ``omega_c = omega_1 / 10``, ``J = M[0, 0]``
(hub, link and payload about the joint) and ``omega_1`` the first flexible natural frequency:
the rigid-body loop ``J s^2 + k_D s + k_P`` critically damped at ``omega_c``. A joint PD is
collocated, so it cannot destabilise the linear model whatever the gains; the rule keeps the
loop a decade below the first flexible mode so that it does not excite it. The closed loop
(:mod:`simulation.control`) and input shaping (:mod:`inversion.methods.shaping`) use the same rule.

>>> kp, kd = rule_gains(inertia=0.5, omega_1=20.0)
>>> round(kp, 6), round(kd, 6)
(2.0, 2.0)
"""

from __future__ import annotations

from typing import Any

__all__ = ["rule_gains", "loop_gains", "BANDWIDTH_FRACTION", "GAIN_DAMPING"]

#: ``omega_c / omega_1`` of the rule's gains: a decade below the first flexible mode.
BANDWIDTH_FRACTION = 0.1
#: Damping ratio of the rigid-body poles of the rule's gains.
GAIN_DAMPING = 1.0


def rule_gains(inertia: float, omega_1: float) -> tuple[float, float]:
    """``(k_P, k_D)`` of the rule for an inertia and first mode.

    ``(k_P, k_D)`` of the rule (module docstring) for ``J = inertia`` (kg m^2) and ``omega_1`` (rad/s).

    Parameters
    ----------
    inertia : float
        The link's inertia about the joint ``J`` (kg m^2).
    omega_1 : float
        The first flexible natural frequency (rad/s).
    """
    omega_c = BANDWIDTH_FRACTION * omega_1
    return inertia * omega_c**2, 2 * GAIN_DAMPING * inertia * omega_c


def loop_gains(model: Any, case: Any = None) -> tuple[float, float]:
    """The gains the closed loop uses for ``model``.

    The gains the closed loop uses for ``model``: the paper case's (``case.kp``, ``case.kd``), else the rule's from
    ``J = M[0, 0]`` and the first natural frequency.

    Parameters
    ----------
    model : Any
        A loaded model.
    case : Any, optional
        Its paper case, if any (:func:`modelgen.paper.preset_case`).
    """
    import math

    if case is not None:
        return float(case.kp.value), float(case.kd.value)
    return rule_gains(float(model.M[0, 0]), 2 * math.pi * float(model.natural_frequencies_hz[0]))
