"""Paper-style figures (matplotlib, written as PNG files)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

__all__ = ["plot_inversion", "save"]


def save(fig: Any, path: Path) -> Path:
    """Write a figure and close it."""
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)
    return path


def _joints(ax: Any, joints: np.ndarray) -> None:
    for tk in joints[1:-1]:
        ax.axvline(tk, color="0.8", lw=0.8, zorder=0)


def plot_inversion(result: Any, folder: Path, prefix: str = "") -> list[Path]:
    """Desired and redefined output, their difference, the feedforward torque (cf. Figs. 3-4, 8-10).

    Returns the files written: ``output.png``, ``redefinition_error.png``, ``torque.png``.
    """
    folder = Path(folder)
    joints = result.joints
    t = result.t
    out = []
    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    ax.plot(t, result.y_d, label="desired $y_d$", lw=2.2, color="0.6")
    ax.plot(t, result.y, label=r"redefined $\tilde y_d$", lw=1.2, color="C0")
    _joints(ax, joints)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("end-effector displacement (m)")
    ax.set_title(f"{result.model.name}: desired and redefined output")
    ax.legend()
    out.append(save(fig, folder / f"{prefix}output.png"))

    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    ax.plot(t, (result.y - result.y_d) * 1e3, color="C3")
    _joints(ax, joints)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(r"$\tilde y_d - y_d$ (mm)")
    ax.set_title(f"redefinition error (max {result.summary['max_redefinition_error'] * 1e3:.3g} mm)")
    out.append(save(fig, folder / f"{prefix}redefinition_error.png"))

    fig, ax = plt.subplots(figsize=(6.4, 3.6))
    ax.plot(t, result.tau, color="C2")
    _joints(ax, joints)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(r"$\tau_l$ (N m)")
    ax.set_title(f"causal feedforward torque (peak {result.summary['peak_torque']:.4g} N m; joints in grey)")
    out.append(save(fig, folder / f"{prefix}torque.png"))
    return out
