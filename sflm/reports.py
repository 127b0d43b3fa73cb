"""Plain-text summaries of inversions and simulations for the command line."""

from __future__ import annotations

from typing import Any

from .formatting import table

__all__ = ["inversion_text", "simulation_text"]


def inversion_text(result: Any, files: list[str]) -> str:
    """Readable summary of an :class:`inversion.InversionResult`."""
    s = result.summary
    st = s["settings"]
    fast, slow = st["cdec"]
    lines = [
        f"{s['model']}: piece-wise causal inversion, {len(s['segments'])} segment{'s' if len(s['segments']) != 1 else ''}, "
        f"h = {st['h']}, Cdec = ({fast:g}, {slow:g}), r = {s['r']} ({s['n_unstable']} unstable zero{'s' if s['n_unstable'] != 1 else ''})",
        f"  trajectory          {s['trajectory']}",
        f"  max |y~ - y_d|      {s['max_redefinition_error']:.4g} m",
        f"  y~(tf)              {s['final_redefined_output']:.6g} m (desired {s['final_desired_output']:.6g} m); "
        f"ydot~(tf) {s['final_redefined_velocity']:.3g} m/s",
        f"  peak |tau_l|        {s['peak_torque']:.5g} N m",
        f"  torque at joints    largest jump {s['max_torque_jump']:.2g} N m; tau_l(t0) = {s['torque_at_start']:.2g} N m",
        f"  segment systems     largest residual {s['max_constraint_residual']:.2g}, "
        f"largest condition number {s['max_condition_number']:.3g}",
        "",
    ]
    rows = [
        [k, f"{seg['t_start']:.4g}", f"{seg['t_end']:.4g}", f"{min(seg['exponents']):.4g} .. {max(seg['exponents']):.4g}",
         f"{seg['residual']:.2g}", f"{seg['condition_number']:.3g}"]
        for k, seg in enumerate(s["segments"])
    ]
    lines.append(table(["segment", "t_k (s)", "t_k+1 (s)", "exponents (1/s)", "residual", "condition"], rows))
    if files:
        lines += ["", "wrote " + ", ".join(files)]
    return "\n".join(lines)


def simulation_text(result: Any, files: list[str]) -> str:
    """Readable summary of an :class:`inversion.simulate.SimulationResult`."""
    s = result.summary
    settle = "not within the run" if s["settling_time"] is None else f"{s['settling_time']:.3g} s"
    friction = (
        f"dry friction {s['coulomb_friction']:g} N m sliding, {s['breakaway_friction']:g} N m breakaway"
        if s["breakaway_friction"] > 0 else "no dry friction"
    )
    lines = [
        f"{s['model']}: {s['plant']} plant, controller {s['controller']} (k_P = {s['kp']:g}, k_D = {s['kd']:g}), "
        f"{friction}; compensation {s['friction_compensation']:g} N m",
        f"  final tip error        {s['final_tip_error'] * 1e3:.4g} mm at t = {s['t_end']:g} s",
        f"  steady tip error       {s['steady_tip_error'] * 1e3:.4g} mm (mean over the last second; "
        f"vibration +-{s['residual_vibration'] * 1e3:.3g} mm)",
        f"  max tracking error     {s['max_tracking_error'] * 1e3:.4g} mm (|y - y_d|); "
        f"{s['max_redefined_tracking_error'] * 1e3:.3g} mm from y~ during the manoeuvre",
        f"  peak torque            {s['peak_torque']:.4g} N m",
        f"  settling time          {settle} (band {s['settling_band'] * 1e3:.3g} mm, 2 % of the move)",
    ]
    if s["breakaway_friction"] > 0:
        lines.append(f"  stick-slip             {s['stick_slip_transitions']} transitions, stuck {s['times_stuck']} times")
    if s["controller"] == "two-stage":
        widths = ", ".join(f"{p['width'] * 1e3:.1f}" for p in s["pulses"])
        lines.append(f"  pulses (stage 2)       {len(s['pulses'])}: widths {widths} ms")
    if files:
        lines += ["", "wrote " + ", ".join(files)]
    return "\n".join(lines)
