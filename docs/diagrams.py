"""The guide's two drawings: the link with its coordinates, and the feedforward with the joint PD around it.

``python docs/diagrams.py [FOLDER]`` writes ``link-sketch.png`` and ``loop-diagram.png`` (default ``docs/figures``); the
guide's models and closed-loop pages show them. The link is drawn from the paper's own description (section 2): a
hub turned by the torque ``tau``, the link's rigid line at the hub angle ``theta``, its deflection ``w(x, t)`` from that
line (the assumed modes ``sum phi_i(x) delta_i(t)``), the tip's position ``y = x_out theta + w(x_out, t)`` along the
arc; the loop from Fig. 1 and Eq. (40): ``tau = tau_ff + k_P (theta_d - theta) + k_D (thetadot_d - thetadot)``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

FOLDER = Path(__file__).resolve().parent / "figures"


def link_sketch(path: Path) -> Path:
    """The link seen from above: hub, rigid line, deflected link, tip and payload, with the coordinates' names."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Arc, Circle, FancyArrowPatch

    fig, ax = plt.subplots(figsize=(7.0, 4.2))
    theta, length = np.radians(32.0), 4.0
    direction, normal = np.array([np.cos(theta), np.sin(theta)]), np.array([-np.sin(theta), np.cos(theta)])
    x = np.linspace(0.0, length, 200)
    w = 1.0 * ((x / length) ** 2 * (3 - x / length) / 2)  # a first mode's shape, clamped at the hub, drawn bent back
    bent = x[:, None] * direction[None, :] - w[:, None] * normal[None, :]
    ax.plot([0, 5.2], [0, 0], color="0.6", lw=0.8, ls=":")  # the angle's zero
    ax.plot(*(np.outer([0.0, length + 0.5], direction).T), color="0.45", lw=1.0, ls="--")  # the rigid line
    ax.plot(bent[:, 0], bent[:, 1], color="C0", lw=4.0, solid_capstyle="round")  # the link
    ax.add_patch(Circle((0.0, 0.0), 0.32, facecolor="0.85", edgecolor="0.2", lw=1.2, zorder=3))  # the hub
    tip = bent[-1]
    ax.add_patch(Circle(tuple(tip), 0.17, facecolor="C1", edgecolor="0.2", lw=1.0, zorder=4))  # the payload
    ax.add_patch(Arc((0.0, 0.0), 2.6, 2.6, theta1=0.0, theta2=np.degrees(theta), color="0.2", lw=1.0))
    ax.text(1.45 * np.cos(theta / 2), 1.45 * np.sin(theta / 2), r"$\theta$", fontsize=13, va="center")
    ax.add_patch(FancyArrowPatch((0.55, -0.35), (-0.35, 0.55), connectionstyle="arc3,rad=-0.6", arrowstyle="-|>",
                                 mutation_scale=14, color="C3", lw=1.4))
    ax.text(0.55, -0.62, r"$\tau$ (the hub's torque)", color="C3", fontsize=11)
    at = 0.62 * length  # the deflection's dimension, at a point along the link
    on_line, on_link = at * direction, bent[int(0.62 * (x.size - 1))]
    ax.annotate("", xy=tuple(on_link), xytext=tuple(on_line), arrowprops={"arrowstyle": "<->", "color": "0.2", "lw": 1.0})
    ax.text(*(on_link + np.array([0.35, -0.55])), r"deflection $w(x,t) = \sum_i \phi_i(x)\,\delta_i(t)$", fontsize=11)
    ax.text(*(tip + np.array([0.3, 0.15])), "tip (payload)\n" + r"$y = x_\mathrm{out}\,\theta + w(x_\mathrm{out}, t)$", fontsize=11)
    ax.text(*(length * direction + 0.55 * direction + np.array([-0.2, 0.12])), "rigid line", color="0.45", fontsize=10)
    ax.text(0.0, -0.75, "hub (inertia)", ha="center", fontsize=10)
    ax.set(xlim=(-1.2, 6.6), ylim=(-1.1, 3.3), aspect="equal")
    ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def loop_diagram(path: Path) -> Path:
    """The feedforward table and the joint PD around the link (Fig. 1, Eq. 40) as a block diagram."""
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, FancyBboxPatch

    fig, ax = plt.subplots(figsize=(8.6, 3.6))

    def box(x: float, y: float, w: float, h: float, text: str, colour: str = "0.93") -> None:
        ax.add_patch(FancyBboxPatch((x - w / 2, y - h / 2), w, h, boxstyle="round,pad=0.05", facecolor=colour, edgecolor="0.2"))
        ax.text(x, y, text, ha="center", va="center", fontsize=10)

    def arrow(a: tuple[float, float], b: tuple[float, float], text: str = "", where: str = "above") -> None:
        ax.annotate("", xy=b, xytext=a, arrowprops={"arrowstyle": "-|>", "color": "0.2", "lw": 1.1, "shrinkA": 0, "shrinkB": 0})
        if text:
            mid = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2 + (0.18 if where == "above" else -0.22))
            ax.text(*mid, text, ha="center", va="center", fontsize=10)

    box(1.0, 2.0, 1.5, 0.8, "desired tip\n" + r"$y_d(t)$")
    box(3.4, 2.0, 1.9, 0.9, "sflm invert\n(the table, offline)", colour="#dbe9f6")
    box(6.4, 1.0, 1.3, 0.7, r"joint PD" + "\n" + r"$k_P,\ k_D$")
    box(8.6, 2.0, 1.5, 0.9, "flexible link\n(plant)", colour="#fde3c8")
    ax.add_patch(Circle((7.3, 2.0), 0.16, facecolor="white", edgecolor="0.2"))
    ax.text(7.3, 2.0, "+", ha="center", va="center", fontsize=11)
    arrow((1.75, 2.0), (2.45, 2.0))
    arrow((4.35, 2.0), (7.14, 2.0), r"$\tau_\mathrm{ff}$ (held a period)")
    ax.plot([3.4, 3.4, 5.75], [1.55, 1.0, 1.0], color="0.2", lw=1.1)
    arrow((5.5, 1.0), (5.75, 1.0))
    ax.text(4.55, 0.78, r"$\theta_d,\ \dot\theta_d$", ha="center", fontsize=10)
    ax.plot([7.05, 7.3], [1.0, 1.0], color="0.2", lw=1.1)
    arrow((7.3, 1.0), (7.3, 1.84))
    arrow((7.46, 2.0), (7.85, 2.0), r"$\tau$")
    arrow((9.35, 2.0), (10.3, 2.0), "tip $y$")
    ax.plot([8.6, 8.6, 6.4], [1.55, 0.25, 0.25], color="0.2", lw=1.1)
    arrow((6.4, 0.25), (6.4, 0.65))
    ax.text(7.6, 0.05, r"hub encoder: $\theta,\ \dot\theta$", ha="center", fontsize=10)
    ax.text(5.3, 3.05, r"$\tau = \tau_\mathrm{ff} + k_P\,(\theta_d - \theta) + k_D\,(\dot\theta_d - \dot\theta)$  (Eq. 40)",
            ha="center", fontsize=11)
    ax.set(xlim=(0.0, 10.6), ylim=(-0.2, 3.35), aspect="equal")
    ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def draw(folder: Path = FOLDER) -> list[Path]:
    """Both drawings into ``folder``."""
    import matplotlib

    matplotlib.use("Agg")
    folder.mkdir(parents=True, exist_ok=True)
    return [link_sketch(folder / "link-sketch.png"), loop_diagram(folder / "loop-diagram.png")]


if __name__ == "__main__":
    for written in draw(Path(sys.argv[1]) if len(sys.argv) > 1 else FOLDER):
        print(f"wrote {written}")
