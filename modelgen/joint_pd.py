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

import math
from typing import Any

from .errors import SettingsError

__all__ = ["rule_gains", "loop_gains", "check_stiffness", "BANDWIDTH_FRACTION", "GAIN_DAMPING", "MAX_STIFFNESS"]

#: ``omega_c / omega_1`` of the rule's gains: a decade below the first flexible mode.
BANDWIDTH_FRACTION = 0.1
#: Damping ratio of the rigid-body poles of the rule's gains.
GAIN_DAMPING = 1.0
#: The joint PD may make the loop at most this much faster than the model's fastest natural frequency (a pole beyond it
#: is a loop no actuator realises, and an integration without end: ``--kp 1e12`` rang at 1.2e6 rad/s for 10 s).
MAX_STIFFNESS = 100.0


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
    if case is not None:
        return float(case.kp.value), float(case.kd.value)
    return rule_gains(float(model.M[0, 0]), 2 * math.pi * float(model.natural_frequencies_hz[0]))


def check_stiffness(model: Any, kp: float, kd: float) -> None:
    """Refuse gains no actuator realises.

    Refuse gains whose rigid-body loop ``J s^2 + k_D s + k_P`` (``J = M[0, 0]``) has a pole beyond
    :data:`MAX_STIFFNESS` x the model's fastest natural frequency, naming the pole and the largest gains accepted.
    ``invert`` (judging a table in the loop) and ``simulate`` (running it) refuse the same gains.

    Parameters
    ----------
    model : Any
        A loaded model.
    kp, kd : float
        The joint PD's gains (Eq. (40)).

    Raises
    ------
    SettingsError
        For gains that are not finite, or that put a pole beyond the limit.
    """
    J = float(model.M[0, 0])
    fastest = 2 * math.pi * max(float(f) for f in model.natural_frequencies_hz)
    limit = MAX_STIFFNESS * fastest
    if not (math.isfinite(kp) and math.isfinite(kd) and kp >= 0 and kd >= 0):
        raise SettingsError("kp, kd", (kp, kd), "two finite numbers, k_P > 0 and k_D >= 0")
    # the larger |root| of s^2 + 2 a s + b^2 (a = k_D / 2J, b = sqrt(k_P / J)) without squaring a or b: 1e308 gains
    # do not overflow (it was a traceback in the judgement)
    a, b = kd / (2 * J), math.sqrt(kp) / math.sqrt(J)
    pole = a * (1 + math.sqrt(1 - (b / a) ** 2)) if a > b else b
    if not pole <= limit:
        critical = f"critically damped at the limit: k_P = {J * limit**2:.3g}, k_D = {2 * J * limit:.3g}"
        raise SettingsError("kp, kd", (kp, kd), f"gains whose joint loop J s^2 + k_D s + k_P has its poles within {limit:.3g} "
                            f"rad/s ({MAX_STIFFNESS:g} x the fastest mode, {fastest:.4g} rad/s); these put one at {pole:.3g} rad/s "
                            f"({critical})")
