"""The landing figure: what the causal feedforward buys, beside the rigid-body feedforward an engineer writes first.

``python docs/landing_figure.py [PATH]`` writes ``docs/figures/own-aluminium-feedforward.png`` (the README's and the
documentation's first figure): the tutorial's aluminium link (``tests/data/own-aluminium.toml``, 0.8 m), its tip
0.5 m in 2 s, driven by the table ``sflm invert`` returns and by the rigid body's computed torque ``tau = J theta_d''`` (``J`` the link's whole inertia about
the hub, ``theta_d = y_d / x_out``), each held at the controller's 1 ms with the joint PD closed (the gains ``sflm simulate`` uses,
the references held with the torque) on the linear model exactly discretised; above the feedforward torques, below the
tip's error during the move and 2.5 s after it.
Every figure in the caption is printed by this script.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
FIGURE = ROOT / "docs" / "figures" / "own-aluminium-feedforward.png"
AFTER = 2.5  # seconds shown after the move
#: The link and the move: the tutorial's (docs/guide/tutorial.md), a 0.8 m aluminium link of our own, 0.5 m in 2 s.
MODEL, MOVE = "tests/data/own-aluminium.toml", "smoothstep:0.5:2:2"


def responses() -> dict[str, np.ndarray]:
    """The two feedforwards' tables and the tip's error under each with the joint PD closed, at the controller's rows."""
    import modelgen
    from inversion import Problem, invert, trajectory_from_spec
    from inversion.acceptance import closed_loop
    from inversion.lti.discrete import recurrence, zero_order_hold
    from modelgen.joint_pd import loop_gains

    model = modelgen.load(str(ROOT / MODEL))
    move = trajectory_from_spec(MOVE)
    result = invert(Problem(model, move))
    period = float(result.summary["sampled"]["period"])
    A, B, C = (np.asarray(m, dtype=float) for m in (model.A, model.B, model.C_out))
    B, C = B.reshape(-1), C.reshape(-1)
    gains = loop_gains(model)
    t = move.t0 + np.arange(int(round((move.duration + AFTER) / period)) + 1) * period
    inertia, reach = float(model.M[0, 0]), float(C[0])  # the rigid body's inertia about the hub; y = x_out theta at rest
    tables = {}
    # the causal table as it runs (the family's may settle a little past t_f), the rigid one over the move
    ends = {"causal": int(np.searchsorted(t, float(result.t[-1]) - 1e-9)), "rigid": int(round(move.duration / period))}
    rows = ends["causal"]
    tables["causal"] = (np.interp(t[:rows], result.t, result.tau), np.interp(t[:rows], result.t, result.theta_d),
                        np.interp(t[:rows], result.t, result.thetadot_d))
    grid = np.clip(t[: ends["rigid"]], move.t0, move.tf)
    tables["rigid"] = (inertia * move.derivative(grid, 2) / reach, move.derivative(grid, 0) / reach, move.derivative(grid, 1) / reach)
    desired = move.derivative(np.clip(t, move.t0, move.tf), 0)
    out = {"t": t, "tf": np.array(move.tf)}
    for name, (tau, theta, thetadot) in tables.items():
        rows = ends[name]
        A_c, u_c, after = closed_loop(A, B, gains, tau, theta, thetadot, 0.0, move.derivative([move.tf], 0)[0] / reach, 0.0)
        Ad, Bd = zero_order_hold(A_c, B, period)
        X, _ = recurrence(Ad, Bd[:, None], np.zeros(A.shape[0]), np.append(u_c, np.full(t.size - 1 - rows, after))[:, None])
        out[name] = np.append(tau, np.zeros(t.size - rows))
        out[f"{name}_error"] = X @ C - desired
    return out


def draw(path: Path = FIGURE) -> dict[str, float]:
    """Draw the figure at ``path``; its figures (the largest tip errors during and after the move, the peak torques)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    r = responses()
    t, tf = r["t"], float(r["tf"])
    after = t > tf
    figures = {f"{name}_{part}": float(np.abs(r[f"{name}_error"][mask]).max()) for name in ("causal", "rigid")
               for part, mask in (("during", ~after), ("after", after))}
    figures.update({f"{name}_peak": float(np.abs(r[name]).max()) for name in ("causal", "rigid")})
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5.2), sharex=True, gridspec_kw={"height_ratios": [1, 1.3]})
    for name, label, style in (("rigid", "rigid-body feedforward", {"color": "0.55", "ls": "--"}),
                               ("causal", "sflm's causal feedforward", {"color": "C0"})):
        top.plot(t, r[name], label=label, **style)
        bottom.plot(t, 1e3 * r[f"{name}_error"], label=label, **style)
    for ax in (top, bottom):
        ax.axvspan(tf, t[-1], color="0.93", lw=0)
        ax.axhline(0.0, color="0.7", lw=0.6)
    top.set(ylabel="feedforward (N m)", title="0.5 m in 2 s on a 0.8 m aluminium link, held at 1 ms, joint PD closed")
    reach = 1.15e3 * figures["rigid_during"]
    bottom.set(xlabel="time (s)", ylabel="tip error (mm)", ylim=(-reach, reach))
    bottom.text(tf + 0.05, 0.95 * reach, "after the move", va="top", fontsize=9, color="0.3")
    top.legend(loc="upper right", fontsize=9)
    bottom.legend(loc="lower right", fontsize=9)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return figures


if __name__ == "__main__":
    target = Path(sys.argv[1]) if len(sys.argv) > 1 else FIGURE
    for key, value in draw(target).items():
        print(f"{key:15s} {value:.4g}")
    print(f"wrote {target}")
