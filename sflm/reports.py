"""Plain-text summaries of inversions and simulations for the command line."""

from __future__ import annotations

from typing import Any

from .formatting import table

__all__ = ["comparison_text", "exploration_text", "inversion_text", "simulation_text"]


def _member(settings: dict[str, Any]) -> str:
    """``"5 segments, h = 2, Cdec = (0.0001, 1), paper"`` from a settings block (and its end when not free)."""
    segments = settings["segments"]
    count = segments if isinstance(segments, int) else len(segments) - 1
    fast, slow = settings["cdec"]
    end = settings.get("end", "free")
    ending = "" if end == "free" else f", {end} end"
    return f"{count} segment{'s' if count != 1 else ''}, h = {settings['h']}, Cdec = ({fast:g}, {slow:g}), {settings['joining']}{ending}"


def _with_files(lines: list[str], files: list[str]) -> str:
    """The report's lines and, when something was written, the files."""
    return "\n".join(lines + (["", "wrote " + ", ".join(files)] if files else []))


def _reaches_the_link(s: dict[str, Any]) -> list[str]:
    """The lines of what reaches the link (:mod:`inversion.acceptance`): torque against a rigid body's need, the link after
    the feedforward ends, more modes, the held table -- each beside the bound it is judged by."""
    v = s["verification"]
    move = s["move"] if s["move"] > 0 else 1.0
    after = v.get("after_end")
    lines = [f"  torque needed       {s['rigid_torque']:.4g} by a rigid body along y_d: the peak is {s['torque_ratio']:.3g} x that"]
    if after is not None:
        post = s.get("post_actuation_time")
        lasts = f" (the feedforward lasts {post:.3g} s after tf)" if post else ""
        lines.append(f"  after the move      the tip strays {after['max_tip_excursion']:.3g} m ({100 * after['max_tip_excursion'] / move:.3g} % "
                     f"of the move) in the {after['window']:g} s after the feedforward ends{lasts}, keeping {after['drift']:.3g} m/s")
    trunc = v.get("truncation")
    if trunc is not None:
        lines.append(f"  with {trunc['modes']} modes        the tip is within {trunc['tip_error']:.3g} m of y_d "
                     f"({100 * trunc['tip_error'] / move:.3g} % of the move)")
    robust = s.get("robustness")
    if robust is not None:
        worst, sets = _perturbed_sets(robust)
        lines.append(f"  perturbed links     in the closed loop (k_P {robust['gains']['kp']:.4g}, k_D {robust['gains']['kd']:.4g}) the tip "
                     f"strays up to {100 * robust['worst_case_error']:.3g} % of the move ({robust['uncertainty']}, {sets}; worst at "
                     f"{worst}); nominal {100 * robust['nominal_error']:.3g} %")
        choice = robust.get("choice")
        if choice is not None:
            lines.append(f"  robust choice       the least worst case of {choice['candidates']} verified members ({choice['explored']} "
                         f"explored): {100 * robust['worst_case_error']:.3g} % against the default member's "
                         f"{100 * choice['default_worst_case_error']:.3g} % (peak {choice['default_peak_torque']:.4g} N m)")
    held = s.get("sampled")
    if held is not None:
        lines.append(f"  held at {held['period']:g} s     ({held['hold']}) the plant follows y~ to {held['max_tracking_error']:.2g} m "
                     f"({held['relative_tracking_error']:.2g} of the move); its tip is within {held['max_tip_error']:.3g} m of y_d")
    return lines


def _perturbed_sets(robust: dict[str, Any]) -> tuple[str, str]:
    """A ``robustness`` block's worst parameter set (``key x factor``, ...; empty if it has none) and its sets judged
    (``4 corners and 16 samples``)."""
    worst = ", ".join(f"{k} x {v:.3g}" for k, v in robust.get("worst_factors", {}).items())
    return worst, f"{robust['corners']} corners" + (f" and {robust['samples']} samples" if robust["samples"] else "")


def _stable_text(result: Any, files: list[str]) -> str:
    """Readable summary of a non-causal stable inversion."""
    s = result.summary
    zeros = ", ".join(f"{re:.4g}{im:+.4g}i" if im else f"{re:.4g}" for re, im in s["zeros"])
    lines = [
        f"{s['model']}: non-causal stable inversion (the baseline; exact tracking), zeros {zeros}",
        f"  trajectory          {s['trajectory']}: y = y_d exactly ({s['move']:.4g} m move)",
        f"  pre-actuation       {s['pre_actuation_time']:.4g} s of torque before t0 "
        f"(tau at the first sample {s['torque_at_start']:.2g} N m)",
        f"  post-actuation      {s['post_actuation_time']:.4g} s of torque after tf "
        f"(tau at the last sample {s['torque_at_end']:.2g} N m); tails cut at {s['settings']['tail_tolerance']:.0e} of the peaks",
        f"  peak |tau_l|        {s['peak_torque']:.5g} N m (at t = {s['time_of_peak_torque']:.4g} s)",
        f"  samples             {s['samples']} at {s['settings']['rate']:g} Hz",
        *_reaches_the_link(s),
    ]
    return _with_files(lines, files)


def _polynomial_text(result: Any, files: list[str]) -> str:
    """Readable summary of a polynomial redefinition."""
    s = result.summary
    st = s["settings"]
    lines = [
        f"{s['model']}: polynomial redefinition (the baseline; one solution), {len(st['segments']) - 1} segments, "
        f"h = {st['h']}, {st['joining']}, degree {s['r'] - 1}",
        f"  trajectory          {s['trajectory']}",
        f"  max |y~ - y_d|      {s['max_redefinition_error']:.4g} m = {100 * s['relative_redefinition_error']:.3g} % of the "
        f"{s['move']:.4g} m move (accepted {s['max_error']:.3g} m)",
        f"  peak |tau_l|        {s['peak_torque']:.5g} N m (at t = {s['time_of_peak_torque']:.4g} s); "
        f"tau_l(tf) = {s['torque_at_end']:.3g} N m",
        f"  segment systems     largest residual {s['max_constraint_residual']:.2g}, "
        f"largest condition number {s['max_condition_number']:.3g}",
        *_reaches_the_link(s),
    ]
    return _with_files(lines, files)


def _ocp_text(result: Any, files: list[str]) -> str:
    """Readable summary of an optimal-control feedforward."""
    s = result.summary
    st, o = s["settings"], s["ocp"]
    what = "peak torque" if st["objective"] == "torque" else "energy"
    lines = [
        f"{s['model']}: optimal-control feedforward, the least {what} keeping the tip within {st['max_error']:.4g} m of y_d at every "
        f"sample ({o['periods']} periods of {st['period']:g} s, {o['after_periods']} more after the move{', ending at rest' if st['end'] == 'rest' else ''})",
        f"  trajectory          {s['trajectory']}",
        f"  tip at the samples  within {o['max_error_at_samples']:.4g} m of y_d ({100 * s['relative_redefinition_error']:.3g} % of the "
        f"{s['move']:.4g} m move); between them {o['max_error_between_samples']:.4g} m",
        f"  peak |tau|          {s['peak_torque']:.5g} N m (at t = {s['time_of_peak_torque']:.4g} s); held one period each, no pre-actuation",
        f"  {o.get('solver', 'ipopt').upper():<19s} {o['status']}{'' if o['iterations'] is None else ' in ' + str(o['iterations']) + ' iterations'}, "
        f"{o['seconds']:.2f} s" + (f" (after {'; '.join(o['attempts'])})" if o.get("attempts") else ""),
        *_reaches_the_link(s),
    ]
    return _with_files(lines, files)


def _shaping_text(result: Any, files: list[str]) -> str:
    """Readable summary of an input-shaped joint reference."""
    s = result.summary
    st, sh = s["settings"], s["shaping"]
    modes = " and ".join(f"{m['frequency']:.4g} rad/s (zeta {m['damping']:.3g})" for m in st["modes"])
    lines = [
        f"{s['model']}: input shaping ({st['method'].upper()}) of the rigid joint reference for {modes}, driven by the joint PD "
        f"(k_P {st['kp']:.4g}, k_D {st['kd']:.4g}) with the rigid body's torque",
        f"  trajectory          {s['trajectory']}; the shaper lasts {sh['shaper_duration']:.4g} s",
        f"  max |y - y_d|       {s['max_redefinition_error']:.4g} m = {100 * s['relative_redefinition_error']:.3g} % of the "
        f"{s['move']:.4g} m move (at t = {s['time_of_max_redefinition_error']:.4g} s; accepted {s['max_error']:.3g} m): input "
        "shaping aims at the vibration after the move, not at the tip during it",
        f"  residual vibration  {sh['residual_vibration']:.3g} m of the tip in the shaped modes after the shaped reference ends "
        f"(unshaped: {sh['unshaped_residual_vibration']:.3g} m); the whole deflection {sh['residual_deflection']:.3g} m "
        f"(unshaped {sh['unshaped_residual_deflection']:.3g} m) as the loop settles in {sh['settle_time']:.3g} s more",
        f"  peak |tau|          {s['peak_torque']:.5g} N m (at t = {s['time_of_peak_torque']:.4g} s) on the nominal plant",
        *_reaches_the_link(s),
    ]
    return _with_files(lines, files)


def inversion_text(result: Any, files: list[str]) -> str:
    """Readable summary of an :class:`inversion.InversionResult`."""
    s = result.summary
    if s.get("method") == "ocp":
        return _ocp_text(result, files)
    if s.get("method") in ("zv", "zvd"):
        return _shaping_text(result, files)
    if s.get("method") == "stable":
        return _stable_text(result, files)
    if s.get("method") == "polynomial":
        return _polynomial_text(result, files)
    st = s["settings"]
    v = s["verification"]
    precision = (f"{max(v['precision_torque_difference'], v['precision_output_difference']):.1g} in extended precision"
                 if v["precision"] == "longdouble" else "extended precision unavailable on this platform")
    lines = [
        f"{s['model']}: piece-wise causal inversion, {_member(st)}, r = {s['r']} "
        f"({s['n_unstable']} unstable zero{'s' if s['n_unstable'] != 1 else ''})",
        f"  trajectory          {s['trajectory']}",
        f"  max |y~ - y_d|      {s['max_redefinition_error']:.4g} m = {100 * s['relative_redefinition_error']:.3g} % of the "
        f"{s['move']:.4g} m move (at t = {s['time_of_max_redefinition_error']:.4g} s; accepted {s['max_error']:.3g} m)",
        f"  y~(tf)              {s['final_redefined_output']:.6g} m (desired {s['final_desired_output']:.6g} m); "
        f"ydot~(tf) {s['final_redefined_velocity']:.3g} m/s",
        f"  peak |tau_l|        {s['peak_torque']:.5g} N m (at t = {s['time_of_peak_torque']:.4g} s)",
        f"  torque at joints    largest jump {s['max_torque_jump']:.2g} N m; tau_l(t0) = {s['torque_at_start']:.2g} N m",
        f"  segment systems     largest residual {s['max_constraint_residual']:.2g}, "
        f"largest condition number {s['max_condition_number']:.3g}",
        f"  verified            solvers agree to {max(v['solver_torque_difference'], v['solver_output_difference']):.1g}, "
        f"{precision}; the linear plant follows y~ to {v['plant_output_error']:.1g} of the move",
        *_reaches_the_link(s),
    ]
    zd = s.get("zero_dynamics")
    if zd:
        free = ", ".join(f"{re:.4g}{im:+.4g}i" if im else f"{re:.4g}" for re, im in zd["free"]) or "none"
        lines.append(f"  zeros ({zd['zeros']})    {zd['n_unstable_constrained']} of the model's {zd['n_unstable_model']} unstable zeros "
                     f"constrained; left free (checked on the full plant above): {free}")
    auto = s.get("auto")
    if auto:
        failed = ", ".join(f"{n} {k}" for k, n in auto["failed"].items()) or "none"
        lines.append(f"  automatic choice    {auto['members']} members in {auto['seconds']:.1f} s (failed: {failed}); "
                     f"{auto['rule']}")
        if auto.get("max_torque") is not None:
            lines.append(f"    torque limit      {auto['max_torque']:.4g} N m ({auto['max_torque_rule']})")
        for alt in auto.get("alternatives", []):
            lines.append(f"    {alt['kind'] + ':':17s} {alt['peak_torque']:.4g} N m with max |y~ - y_d| {alt['max_redefinition_error']:.3g} m "
                         f"({_member(alt['settings'])}; --max-torque {alt['peak_torque'] * 1.001:.4g} --max-error "
                         f"{alt['max_redefinition_error'] * 1.001:.4g})")
    lines.append("")
    rows = [
        [k, f"{seg['t_start']:.4g}", f"{seg['t_end']:.4g}", f"{min(seg['exponents']):.4g} .. {max(seg['exponents']):.4g}",
         f"{seg['residual']:.2g}", f"{seg['condition_number']:.3g}"]
        for k, seg in enumerate(s["segments"])
    ]
    if len(rows) > 12:
        rows = rows[:6] + [["...", "", "", "", "", ""]] + rows[-5:]
    lines.append(table(["segment", "t_k (s)", "t_k+1 (s)", "exponents (1/s)", "residual", "condition"], rows))
    return _with_files(lines, files)


def exploration_text(result: Any, files: list[str]) -> str:
    """Readable summary of an :class:`inversion.explore.Exploration`."""
    s = result.summary
    failed = ", ".join(f"{n} {k}" for k, n in s["failed"].items()) or "none"
    lines = [
        f"{s['model']}: {s['members']} members of the family explored in {s['seconds']:.1f} s on {s['workers']} "
        f"({s['members_per_second']:.0f} per second)",
        f"  trajectory   {s['trajectory']}",
        f"  succeeded    {s['succeeded']}; failed: {failed}",
    ]
    best = s["best"]
    if best is not None:
        lines.append(f"  best         max |y~ - y_d| {best['max_redefinition_error']:.3g} m, peak torque {best['peak_torque']:.4g} N m "
                     f"({best['segments']} segments, h = {best['h']}, Cdec = ({best['cdec_fast']:g}, {best['cdec_slow']:g}), "
                     f"{best['joining']})")
    if best is None:
        advice = " (--end free,rest,settle)" if list(s["grid"]["end"]) == ["free"] and "after" in (s.get("no_choice") or "") else ""
        lines.append(f"  best         none: {s.get('no_choice') or 'no member passes'}{advice}; no best.json written")
    paper = s["paper_member"]
    if paper is not None:
        figures = (f"max |y~ - y_d| {paper['max_redefinition_error']:.3g} m, peak torque {paper['peak_torque']:.4g} N m"
                   if paper["max_redefinition_error"] is not None else f"status {paper['status']}")
        lines.append(f"  the paper's  {figures} ({paper['segments']} segments, h = {paper['h']}, "
                     f"Cdec = ({paper['cdec_fast']:g}, {paper['cdec_slow']:g}))")
    robust = s.get("robustness")
    if robust is not None:
        least = robust["least"]
        judged = (f"{robust['judged']} of the {robust['usable']} members within the bounds judged on {_perturbed_sets(robust)[1]} "
                  f"of {robust['uncertainty']}")
        lines.append(f"  perturbed    {judged}" + ("" if least is None else
                     f"; the least worst case {100 * least['worst_case_error']:.3g} % of the move ({least['segments']} segments, "
                     f"h = {least['h']}, Cdec = ({least['cdec'][0]:g}, {least['cdec'][1]:g}), {least['joining']}, {least['end']} end, "
                     f"peak {least['peak_torque']:.4g} N m)"))
    front = result.front
    if front:
        shown = front if len(front) <= 12 else front[:6] + front[-6:]
        more = "" if len(shown) == len(front) else (f"; the 6 of least error and the 6 of least torque shown, "
                                                     f"{len(front) - len(shown)} between them in explore.csv")
        lines += ["", f"Pareto front ({len(front)} members, error against peak torque{more}):"]
        rows = [[f"{r['max_redefinition_error']:.3g}", f"{r['peak_torque']:.4g}", r["segments"], r["h"], f"{r['cdec_fast']:g}",
                 f"{r['cdec_slow']:g}", r["joining"]] for r in shown]
        lines.append(table(["max |y~-y_d| (m)", "peak torque (N m)", "segments", "h", "Cdec_f", "Cdec_s", "joining"], rows))
    return _with_files(lines, files)


def simulation_text(result: Any, files: list[str]) -> str:
    """Readable summary of a :class:`simulation.SimulationResult`."""
    s = result.summary
    settle = "not within the run" if s["settling_time"] is None else f"{s['settling_time']:.3g} s"
    friction = (
        f"dry friction {s['coulomb_friction']:g} N m sliding, {s['breakaway_friction']:g} N m breakaway"
        if s["breakaway_friction"] > 0 else "no dry friction"
    )
    feedback = s["controller"] != "none"
    lines = [
        f"{s['model']}: {s['plant']['kind']} plant, {friction}; controller {s['controller']}"
        + ("" if feedback else " (the feedforward alone, no feedback)"),
    ]
    if feedback:
        lines += [
            f"  gains                  k_P = {s['kp']:.4g}, k_D = {s['kd']:.4g} ({s['gains_source']})",
            f"  compensation           {s['friction_compensation']:g} N m ({s['friction_compensation_source']})",
        ]
    for name, d in s["plant"]["differs_from_model"].items():
        lines.append(f"  plant {name:<16} {d['value']:g} {d['unit']} instead of the model's {d['model']:g} ({d['source']})")
    lines += [
        f"  tip error at the end   {s['final_tip_error'] * 1e3:.4g} mm at t = {s['t_end']:g} s",
        f"  last second            mean error {s['steady_tip_error'] * 1e3:.4g} mm, vibration "
        f"{s['residual_vibration'] * 1e3:.3g} mm peak to peak; {'settled' if s['settled'] else 'not settled'} "
        f"(band {s['settling_band'] * 1e3:.3g} mm, 2 % of the move)",
        f"  max tracking error     {s['max_tracking_error'] * 1e3:.4g} mm (|y - y_d|); "
        f"{s['max_redefined_tracking_error'] * 1e3:.3g} mm from y~ during the manoeuvre",
        f"  peak torque            {s['peak_torque']:.4g} N m",
        f"  settling time          {settle}",
    ]
    if s["breakaway_friction"] > 0:
        lines.append(f"  stick-slip             {s['stick_slip_transitions']} transitions, stuck {s['times_stuck']} times")
    robust = s.get("robustness")
    if robust is not None:
        worst, sets = _perturbed_sets(robust)
        lines.append(f"  perturbed links        the same loop ({robust['plant']} plant, the nominal gains) strays up to "
                     f"{100 * robust['worst_case_error']:.3g} % of the move ({robust['uncertainty']}, {sets}; worst at {worst}); "
                     f"nominal {100 * robust['nominal_error']:.3g} %")
    if s["controller"] == "two-stage":
        widths = ", ".join(f"{p['width'] * 1e3:.1f}" for p in s["pulses"])
        law = s["pulse_law"] or {}
        lines.append(f"  pulses (stage 2)       {len(s['pulses'])} of {law.get('amplitude', 0):g} N m: widths {widths} ms "
                     f"({law.get('source', '')})")
    return _with_files(lines, files)


def comparison_text(result: Any, files: list[str]) -> str:
    """Readable table of an :class:`inversion.compare.Comparison`."""
    def cell(row: dict[str, Any], key: str, fmt: str) -> str:
        value = row.get(key)
        return "-" if value is None else format(value, fmt)

    robust = any(r.get("worst_case_error") is not None for r in result.rows)
    rows = [[r["method"], r["status"], cell(r, "max_redefinition_error", ".3g"), cell(r, "peak_torque", ".4g"),
             cell(r, "torque_at_end", ".3g"), cell(r, "pre_actuation_time", ".3g"), cell(r, "residual_vibration", ".3g"),
             cell(r, "seconds", ".2f")] + ([cell(r, "worst_case_error", ".3g")] if robust else [])
            for r in result.rows]
    lines = [table(["method", "status", "max |y~ - y_d| (m)", "peak torque (N m)", "tau_l(tf) (N m)", "pre-actuation (s)",
                    "vibration after tf (m p-p)", "seconds"] + (["worst case (of the move)"] if robust else []), rows), ""]
    for r in result.rows:
        note = r["settings"] if r["status"] == "ok" else r["message"]
        extra = f"; {r['message']}" if r["status"] == "ok" and r.get("message") else ""
        lines.append(f"  {r['method']:<11s} {note}{extra}")
    return _with_files(lines, files)
