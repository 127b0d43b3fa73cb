"""The contract of the generated code: roles, C symbols, compiler and flags.

Nothing here imports SymPy or CasADi, so a cache hit can be decided without them.
"""

from __future__ import annotations

import os
import shutil
import subprocess

__all__ = ["BATCH_CHUNK", "ROLES", "COMPILE_FLAGS", "symbol", "compiler_command", "compiler_version"]

#: Samples per call of ``inverse_torque_batch`` (``X`` is ``2(n+1) x BATCH_CHUNK``): Eq. (12)
#: with ``C_out A^2`` and ``CAB`` evaluated once per chunk rather than once per sample.
BATCH_CHUNK = 512

#: Role -> (input names, output names). The CasADi/C symbol of a role is ``sflm_<role>``;
#: inputs named ``*_batch`` hold ``BATCH_CHUNK`` samples as columns.
ROLES: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "M": (("p",), ("M",)),
    "K": (("p",), ("K",)),
    "C": (("p",), ("C",)),
    "D": (("p",), ("D",)),
    "H": (("p",), ("H",)),
    "A": (("p",), ("A",)),
    "B": (("p",), ("B",)),
    "C_out": (("p",), ("C_out",)),
    "CAB": (("p",), ("CAB",)),
    "CA2": (("p",), ("CA2",)),
    "AI": (("p",), ("AI",)),
    "BI": (("p",), ("BI",)),
    "T": (("p",), ("T",)),
    "Tinv": (("p",), ("Tinv",)),
    "inverse_torque": (("p", "X", "yddot"), ("tau",)),
    "inverse_torque_batch": (("p", "X_batch", "yddot_batch"), ("tau",)),
    "linear_rhs": (("p", "X", "tau"), ("Xdot",)),
    "nonlinear_rhs": (("p", "X", "tau"), ("Xdot",)),
    "nonlinear_rhs_jacobian": (("p", "X", "tau"), ("dXdot_dX", "dXdot_dtau")),
    "nonlinear_paper_rhs": (("p", "X", "tau"), ("Xdot",)),
    "nonlinear_paper_rhs_jacobian": (("p", "X", "tau"), ("dXdot_dX", "dXdot_dtau")),
    "nonlinear_energy": (("p", "X"), ("E",)),
    "tip_output": (("p", "X"), ("y", "ydot")),
    "energy": (("p", "X"), ("E",)),
}

#: Flags of the shared library. ``-Wunused-parameter`` (part of ``-Wextra``) is disabled:
#: CasADi's calling convention passes work vectors and a memory index that simple
#: functions do not use (casadi/casadi#1875); every other warning is an error.
COMPILE_FLAGS: tuple[str, ...] = ("-O2", "-fPIC", "-shared", "-Wall", "-Wextra", "-Werror", "-Wno-unused-parameter")


def symbol(role: str) -> str:
    """C symbol (and CasADi Function name) of a role.

    Parameters
    ----------
    role : str
        One of :data:`ROLES`.
    """
    return f"sflm_{role}"


def compiler_command() -> str | None:
    """The C compiler the project uses, or ``None`` when there is none.

    The C compiler: ``$SFLM_CC`` if set (empty or not found: no compiler), else ``$CC``,
    else ``cc`` or ``gcc`` on the PATH; ``None`` when there is none.
    """
    explicit = os.environ.get("SFLM_CC")
    if explicit is not None:
        return shutil.which(explicit) if explicit else None
    for candidate in (os.environ.get("CC"), "cc", "gcc"):
        if candidate:
            found = shutil.which(candidate)
            if found:
                return found
    return None


_VERSION_CACHE: dict[str, str] = {}


def compiler_version(command: str | None) -> str:
    """First line of ``command --version`` (``"none"`` without one).

    Parameters
    ----------
    command : str | None
        The compiler's command, or ``None`` for none.
    """
    if command is None:
        return "none"
    if command not in _VERSION_CACHE:
        try:
            out = subprocess.run([command, "--version"], capture_output=True, text=True, timeout=30)
            lines = (out.stdout or out.stderr).splitlines()
            _VERSION_CACHE[command] = lines[0].strip() if out.returncode == 0 and lines else "unknown"
        except (OSError, subprocess.SubprocessError):
            _VERSION_CACHE[command] = "unknown"
    return _VERSION_CACHE[command]
