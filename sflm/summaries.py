"""Plain-text summaries of inversions and simulations for the command line."""

from __future__ import annotations

from typing import Any

from inversion.family.method import member_text as _member
from inversion.result import report_row, summary_words
from inversion.methods.ocp import LOOP_NAME

from .formatting import table

__all__ = ["comparison_text", "exploration_text", "inversion_text", "simulation_text"]


def _method_of(summary: dict[str, Any]) -> Any:
    """The registered method a summary is of (the registry's: each method writes its own first lines), or the base
    class's neutral words for a method not registered here."""
    from inversion.options import InversionMethod, method_named
    from modelgen.errors import SettingsError

    try:
        return method_named(str(summary.get("method", "ssef")))
    except SettingsError:
        return InversionMethod


def _with_files(lines: list[str], files: list[str]) -> str:
    """The report's lines and, when something was written, the files."""
    return "\n".join(lines + (["", "wrote " + ", ".join(files)] if files else []))


#: A report line: its label in a column of 20 characters, then the text (:func:`inversion.result.report_row`).
_row = report_row
#: The words of a report: a link's or a generic system's (:func:`inversion.result.summary_words`).
words = summary_words


_PARAMETER_WORDS = {"link.flexural_rigidity": "EI", "payload.mass": "payload", "gain": "gain", "time_scale": "time scale"}


def _drift_out(held: dict[str, Any], bound: float | None, out: str) -> str:
    """When the rate the plant keeps after the table carries the output past the bound within an hour: about when."""
    drift, excursion = abs(float(held.get("drift") or 0.0)), float(held["after_end_excursion"])
    if bound is None or not drift > 0 or not excursion <= bound:
        return ""
    later = (bound - excursion) / drift
    return f": left alone, at that rate the {out} is past the bound about {later:.2g} s after the window" if later < 3600 else ""


def _loop_drive_lines(pd: dict[str, Any], bounds: dict[str, Any]) -> list[str]:
    """What the motor delivers in the joint PD loop (the table and the PD's correction) against the drive's bounds (no
    line where the bounds are the rule's, relative to the move: not a motor's)."""
    if "peak_torque" not in pd:
        return []
    top, rate = pd["drive"]
    held = [f"{value:.4g} N m, {bounds.get(rule)}" for value, rule in ((top, "max_torque_rule"), (rate, "max_torque_rate_rule"))
            if value is not None]
    text = (f"the table and the PD together: up to {pd['peak_torque']:.4g} N m, stepping by up to {pd['torque_rate']:.4g} N m at a row "
            f"(bounds {'; '.join(held)})")
    if not pd.get("within_drive", True):
        over = [f"{name} {100 * (value / limit - 1):.3g} % above its bound" for name, value, limit in
                (("the peak", pd["peak_torque"], top), ("the step", pd["torque_rate"], rate))
                if limit is not None and value > limit * (1 + 1e-12)]
        text += (f": beyond the drive in the loop ({', '.join(over)}): the drive cannot deliver what the PD adds; the table "
                 "alone is within it -- a --max-torque and --max-torque-rate below the drive's leave the PD its share")
    return [_row("motor in the loop", text)]


def _beyond_aimed(shortest: dict[str, Any]) -> str:
    """What the shortest move's tries above the aimed duration cost, and why (a table that failed, or lost the margin
    to what the bounded limit does not bound: the joint PD loop and its motor)."""
    beyond = float(shortest.get("beyond_aimed") or 0.0)
    if not beyond > 0:
        return ""
    why = {t["status"] for t in shortest.get("tried", [])} - {"passed"}
    if not why:  # (the fastest move's: the rows its rest end needs, not a table refused)
        return ""
    words = " or ".join((["could not keep the margin (the joint PD loop, its motor within the drive)"] if "margin" in why else [])
                        + (["failed"] if why - {"margin"} else []))
    return f"; the moves nearer it {words}: {100 * beyond:.2g} % more"


def _against_drive(drive: dict[str, Any] | None) -> str:
    """A simulation's peak torque against the drive's bound, where the link has one."""
    if drive is None:
        return ""
    if drive["within"]:
        return f" (within the drive's {drive['max_torque']:.4g} N m, {drive['source']})"
    return (f": {100 * (drive['peak_torque'] / drive['max_torque'] - 1):.3g} % beyond the drive's {drive['max_torque']:.4g} N m "
            f"({drive['source']}): the plant was driven without the limit, the motor could not deliver that")


def _margin_lines(margin: dict[str, Any]) -> list[str]:
    """The margin block (:mod:`inversion.methods.margin`): the share of the bound kept free and the plant errors tolerated."""
    kept = [margin[k] for k in ("held", "after", "more_modes") if margin.get(k) is not None]
    aimed = (f"aimed within {margin['aimed']:.4g}" + (f" ({100 * margin['asked']:g} % asked" + (
        f", the bounded limit leaving {100 * margin['room']:.3g} % of the bound" if margin.get("room") is not None else "") + ")"
        if margin.get("asked") else "")) if margin.get("aimed") is not None and margin["aimed"] < margin["bound"] else "at the bound"
    lines = [_row("margin", f"{100 * min(kept):.3g} % of the bound {margin['bound']:.4g} free at the rows, after the move and with "
                  f"more modes ({aimed})")] if kept else []
    radius = margin.get("radius") or {}

    def tolerated(loop: dict[str, Any]) -> str:
        parts = []
        for key, word in _PARAMETER_WORDS.items():
            entry = loop.get(key)
            if not isinstance(entry, dict) or "lower" not in entry:
                continue
            if entry["lower"] is None:
                parts.append(f"{word}: none (the nominal plant is {loop['nominal_error']:.3g} from y_d)")
                continue
            low = ("<= " if entry["lower_beyond_span"] else "") + f"{100 * entry['lower']:+.3g} %"
            high = (">= " if entry["upper_beyond_span"] else "") + f"{100 * entry['upper']:+.3g} %"
            parts.append(f"{word} {low} / {high}")
        return ", ".join(parts)

    if "feedforward" in radius:
        lines.append(f"{'':22s}the table holds the bound with {tolerated(radius['feedforward'])} (the feedforward alone)")
    if "pd" in radius:
        gains = radius["pd"]["gains"]
        lines.append(f"{'':22s}with the joint PD (k_P {gains['kp']:.4g}, k_D {gains['kd']:.4g}): {tolerated(radius['pd'])}")
    return lines


def _reaches_the_link(s: dict[str, Any]) -> list[str]:
    """The lines of what reaches the link (:mod:`inversion.acceptance`), each figure beside the bound it is judged by: the
    torque against a rigid link's need, the held table through the move and the window after it (and with more modes),
    the table's rate, the closed form's own figures, and the causal limit."""
    w = words(s)
    v = s["verification"]
    move = s["move"] if s["move"] > 0 else 1.0
    b = s.get("bounds") or {}

    def pct(x: float) -> str:
        return f"{100 * x / move:.3g} %"

    def bound(key: str) -> str:
        return f" (bound {b[key]:.3g}{w['m']})" if key in b and b[key] is not None else ""

    lines = [_row(f"{w['inp']} needed", f"{s['rigid_torque']:.4g}{w['unit']} by {w['need']} along y_d: the peak is "
                  f"{s['torque_ratio']:.3g} x that" + (f" (bound {b['max_torque']:.4g}{w['unit']}, {b['max_torque_rule']})"
                                                       if "max_torque" in b else ""))]
    held = s.get("sampled")
    if held is not None:
        lines.append(_row(f"held at {held['period']:g} s", f"({held['hold']}) the {w['out']} within {held['max_tip_error']:.3g}{w['m']} of "
                          f"y_d during the move ({pct(held['max_tip_error'])}){bound('max_error')}"))
        if "after_end_excursion" in held:
            lines.append(f"{'':22s}the {w['inp']} ended after the table: {held['after_end_excursion']:.3g}{w['m']} from y_d(t_f) in the "
                         f"{held['window']:g} s after it ({pct(held['after_end_excursion'])}){bound('max_error')}"
                         + (f", keeping {held['drift']:.3g}{w['speed']}" if held["drift"] else "") + _drift_out(held, b.get("max_error"), w["out"]))
        if held.get("more_modes_error") is not None:
            lines.append(f"{'':22s}with {held['more_modes']} modes: {held['more_modes_error']:.3g}{w['m']} from y_d during and after the move "
                         f"({pct(held['more_modes_error'])}){bound('more_modes_error')}")
        if held.get("torque_rate") is not None and "rigid_torque_rate" in held:
            rate = (f" (bound {b['max_torque_rate']:.3g}{w['unit']}, {b['max_torque_rate_rule']})" if "max_torque_rate" in b else "")
            lines.append(_row(f"{w['inp']}'s rate", f"the rows change by up to {held['torque_rate']:.3g}{w['unit']} from one to the "
                              f"next (the first against zero), {held['torque_rate_ratio']:.3g} x {w['needs']}'s largest change over a "
                              f"period ({held['rigid_torque_rate']:.3g}{w['unit']}){rate}"))
    after = v.get("after_end")
    trunc = v.get("truncation")
    if after is not None:
        post = s.get("post_actuation_time")
        lasts = f"; the feedforward lasts {post:.3g} s after tf" if post else ""
        more = (f"; with {trunc['modes']} modes within {trunc['tip_error']:.3g}{w['m']} of y_d ({pct(trunc['tip_error'])})"
                if trunc is not None else "")
        lines.append(_row(f"continuous {w['inp']}", f"after the move the {w['out']} strays {after['max_tip_excursion']:.3g}{w['m']} "
                          f"({pct(after['max_tip_excursion'])}) in {after['window']:g} s{lasts}{more}"))
    limit = s.get("causal_limit")
    if limit is not None and limit.get("method") != "none":
        zeros = ", ".join(f"{re:.4g}" if not im else f"{re:.4g}±{abs(im):.4g}i" for re, im in limit["zeros"])
        lines.append(_row("causal limit", f"no causal feedforward from rest holds this move closer than {limit['error']:.3g}{w['m']} "
                          f"({100 * limit['relative_error']:.3g} % of the move; zeros {zeros}): this result "
                          f"{pct(s['max_redefinition_error'])}"))
    planned = (s.get("ocp") or {}).get("plants") or (s.get("replan") or {}).get("plants") or []
    plants = [p for p in planned if LOOP_NAME not in p["name"]]  # the loop's own row says the loop's figures
    looped = [p for p in planned if LOOP_NAME in p["name"] and p["name"] != LOOP_NAME]  # the others in their loops
    if plants:
        worst = max(plants, key=lambda p: max(p["max_tip_error"], p["after_end_excursion"]))
        lines.append(_row("corner plants", f"the same table holds {len(plants)} more plants within "
                          f"{max(worst['max_tip_error'], worst['after_end_excursion']):.3g}{w['m']} of y_d during and after the move "
                          f"({pct(max(worst['max_tip_error'], worst['after_end_excursion']))}; the worst: {worst['name']})"
                          + ("" if not looped else f", and each in the joint PD loop within "
                             f"{max(max(p['max_tip_error'], p['after_end_excursion']) for p in looped):.3g}{w['m']} (planned)")))
    loop = s.get("loop")
    if loop is not None:
        pd, alone = loop["pd"], loop["feedforward"]
        lines.append(_row("in the loop", f"with the joint PD closed (k_P {loop['kp']:.4g}, k_D {loop['kd']:.4g}: {loop['gains']}) the "
                          f"{w['out']} is {pd['during']:.3g}{w['m']} from y_d during the move ({pct(pd['during'])}) and "
                          f"{pd['after']:.3g}{w['m']} from y_d(t_f) after it ({pct(pd['after'])}); the feedforward alone "
                          f"{alone['during']:.3g}{w['m']} and {alone['after']:.3g}{w['m']} (bound {loop['bound']:.3g}{w['m']})"
                          + ("; the table planned for both loops (the PD's references, the plan's own hub angle and rate, in "
                             "its programme)" if len(planned) > len(plants) else "")))
        lines += _loop_drive_lines(pd, s.get("bounds") or {})
    margin = s.get("margin")
    if margin is not None:
        lines += _margin_lines(margin)
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
    return lines


def _perturbed_sets(robust: dict[str, Any]) -> tuple[str, str]:
    """A ``robustness`` block's worst parameter set (``key x factor``, ...; empty if it has none) and its sets judged
    (``4 corners and 16 samples``)."""
    worst = ", ".join(f"{k} x {v:.3g}" for k, v in robust.get("worst_factors", {}).items())
    return worst, f"{robust['corners']} corners" + (f" and {robust['samples']} samples" if robust["samples"] else "")


def inversion_text(result: Any, files: list[str]) -> str:
    """Readable summary of an :class:`inversion.InversionResult`.

    Readable summary of an :class:`inversion.InversionResult`: its method's own text, and -- from the automatic choice
    across methods -- what was tried, each stage's outcome, under the first line.

    Parameters
    ----------
    result : Any
        An inversion's result.
    files : list[str]
        The files written.
    """
    s = result.summary
    kind = _method_of(s)
    text = _with_files(kind().report(s) + _reaches_the_link(s) + _details(s), files)
    stages = (s.get("auto") or {}).get("stages")
    if not stages:
        return text
    first, _, rest = text.partition("\n")
    rows = [f"  automatic choice across methods: {st['name']} {st['status']}"
            f"{' (chosen)' if st.get('chosen') else ''} in {st['seconds']:.2g} s: {_short(st['message'])}" for st in stages]
    bounded = s["auto"].get("bounded_limit")
    if bounded is not None:  # what any causal feedforward within the bounds reaches, beside what this one does
        apart = int(bounded.get("rows_apart", 1))
        where = "the rows" if apart == 1 else f"one row in {apart}"
        rows.append(f"  bounded causal limit: {100 * bounded['relative_error']:.3g} % of the move at {where}, held at "
                    f"{1e3 * bounded['period']:.3g} ms within the torque {bounded['max_torque']:.4g} and the change "
                    f"{bounded['max_torque_rate']:.4g} a period ({bounded['seconds']:.2g} s)")
    least = s["auto"].get("least_peak")
    if least is not None:  # the yardstick the automatic choice judged the stages' peaks by
        rows.append(f"  least peak input: {least['peak_torque']:.4g} for any causal table within {least['tube']:.4g} at the rows "
                    f"({least['seconds']:.2g} s); a table within {100 * least['tolerance']:.3g} % of the least peak found is kept "
                    "from an earlier stage")
        screened = least.get("screened") or {}
        if screened.get("skipped"):  # the cheaper table not asked for: by this table's sensitivity it would break too soon
            rows.append(f"  robustness: optimal control not asked: a table riding the tube would break the bound at about "
                        f"{100 * screened['predicted']:.2g} % plant error by this table's sensitivity ({screened['factor']:g} x below what "
                        f"a cheaper table must tolerate; this one {100 * screened['earlier']:.3g} %)")
        robust = least.get("robustness")
        if robust is not None:  # the cheaper table against the earlier one, by the plant error each tolerates
            earlier, cheaper = robust["tables"]
            def breaks(table: dict[str, Any]) -> str:
                return (f"holds the bound through every parameter's {100 * table['tolerated']:.3g} % error" if table["tolerated"] >= robust["span"]
                        else f"breaks the bound at a {100 * table['tolerated']:.3g} % error of a parameter")

            rows.append(f"  robustness: {cheaper['method']}'s table ({cheaper['peak_torque']:.4g}) {breaks(cheaper)}, "
                        f"{earlier['method']}'s ({earlier['peak_torque']:.4g}) {breaks(earlier)}: {robust['kept']}'s is returned (the "
                        f"cheaper where it tolerates at least {100 * robust['share']:.3g} % as much, or {100 * robust['enough']:.3g} %)")
    return "\n".join([first, *rows, rest])


def _short(message: str, length: int = 160) -> str:
    """A stage's message on one line of the report (the whole of it is in summary.json)."""
    return message if len(message) <= length else message[: length - 3] + "..."


def _details(s: dict[str, Any]) -> list[str]:
    """What a summary holds beyond its method's first lines and what reaches the link: the zeros left free, a family's
    search, its segments (read from the summary's keys, whatever the method)."""
    w = words(s)
    m, unit = w["m"], w["unit"]
    lines: list[str] = []
    zd = s.get("zero_dynamics")
    if zd:
        free = ", ".join(f"{re:.4g}{im:+.4g}i" if im else f"{re:.4g}" for re, im in zd["free"]) or "none"
        lines.append(f"  zeros ({zd['zeros']})    {zd['n_unstable_constrained']} of the model's {zd['n_unstable_model']} unstable zeros "
                     f"constrained; left free (checked on the full plant above): {free}")
    auto = s.get("auto")
    if auto and "members" in auto:
        failed = ", ".join(f"{n} {k}" for k, n in auto["failed"].items()) or "none"
        lines.append(f"  automatic choice    {auto['members']} members in {auto['seconds']:.1f} s (failed: {failed}); "
                     f"{auto['rule']}")
        if auto.get("max_torque") is not None:
            lines.append(f"    {w['inp'] + ' limit':17s} {auto['max_torque']:.4g}{unit} ({auto['max_torque_rule']})")
        for alt in auto.get("alternatives", []):
            lines.append(f"    {alt['kind'] + ':':17s} {alt['peak_torque']:.4g}{unit} with max |y~ - y_d| {alt['max_redefinition_error']:.3g}{m} "
                         f"({_member(alt['settings'])}; --max-torque {alt['peak_torque'] * 1.001:.4g} --max-error "
                         f"{alt['max_redefinition_error'] * 1.001:.4g})")
    shortest = s.get("shortest")
    if shortest:
        free = shortest.get("profile") == "free"
        lines.append(f"  {'fastest move' if free else 'shortest move':19s} no causal feedforward "
                     + ("of any profile holds the tip within " if free else "within the bounds meets ")
                     + f"{shortest['bound']:.3g}{m} in {shortest['lower_bound']:.4g} s ("
                     + ("the least error after the move there" if free else "the bounded limit there")
                     + f" {shortest['lower_bound_error']:.4g}{m}); this table moves in {shortest['duration']:.4g} s "
                     f"({100 * shortest['gap']:.2g} % longer"
                     + (f"; the margin costs {100 * shortest['margin_cost']:.2g} %" if shortest["margin"] else "")
                     + _beyond_aimed(shortest)
                     + f"); a rigid body with the same peak torque needs {shortest['rigid_floor']:.4g} s")
        lines += _beside_lines(shortest.get("beside") or {}, shortest["bound"], m)
        if shortest.get("peak_deflection") is not None:
            within = ("" if shortest.get("max_deflection") is None else
                      f"; bound {shortest['max_deflection']:.3g} m, {shortest.get('max_deflection_rule')}")
            lines.append(f"    bending           the link bends up to {shortest['peak_deflection']:.3g} m at its output on the way "
                         f"({100 * shortest['relative_deflection']:.3g} % of its distance from the hub{within}): the linear model "
                         "assumes small deflections; sflm simulate --feedforward RUN --plant nonlinear-large shows what the link does")
    segments = s.get("segments") or []
    if segments and "exponents" in segments[0]:
        lines.append("")
        rows = [
            [k, f"{seg['t_start']:.4g}", f"{seg['t_end']:.4g}", f"{min(seg['exponents']):.4g} .. {max(seg['exponents']):.4g}",
             f"{seg['residual']:.2g}", f"{seg['condition_number']:.3g}"]
            for k, seg in enumerate(segments)
        ]
        if len(rows) > 12:
            rows = rows[:6] + [["...", "", "", "", "", ""]] + rows[-5:]
        lines.append(table(["segment", "t_k (s)", "t_k+1 (s)", "exponents (1/s)", "residual", "condition"], rows))
    return lines


def _beside_lines(beside: dict[str, Any], bound: float, m: str) -> list[str]:
    """The fastest move's other answers (the shortest smoothstep, the ZV-shaped bang-bang), a line each."""
    lines = []
    smooth = beside.get("smoothstep") or {}
    if "lower_bound" in smooth:
        lines.append(f"    smoothstep        of order {smooth['order']}: none holds the bound in {smooth['lower_bound']:.4g} s, one may in "
                     f"{smooth['upper']:.4g} s (the bounded limit)")
    elif smooth:
        lines.append(f"    smoothstep        of order {smooth['order']}: {smooth['status']}")
    shaped = beside.get("zv_bang_bang")
    if shaped:
        lines.append(f"    ZV bang-bang      the rigid bang-bang shaped on the first mode ({shaped['mode_frequency']:.3g} Hz): "
                     f"{shaped['duration']:.4g} s, the tip {shaped['error_after']:.3g}{m} from the target after it ("
                     + ("within" if shaped["holds_bound"] else "beyond") + f" {bound:.3g}{m}), its torque changing by "
                     f"{shaped['largest_change']:.3g} a row (" + ("within" if shaped["within_rate"] else "beyond")
                     + f" the rate bound), the link bending {shaped['peak_deflection']:.3g} m"
                     + ("" if shaped.get("within_deflection") is None else
                        " (within the deflection bound)" if shaped["within_deflection"] else " (beyond the deflection bound)"))
    return lines


def exploration_text(result: Any, files: list[str]) -> str:
    """Readable summary of an Exploration.

    Parameters
    ----------
    result : Any
        An exploration.
    files : list[str]
        The files written.
    """
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
    """Readable summary of a :class:`simulation.SimulationResult`.

    Parameters
    ----------
    result : Any
        A simulation's result.
    files : list[str]
        The files written.
    """
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
        f"  peak torque            {s['peak_torque']:.4g} N m" + _against_drive(s.get("drive")),
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
    """Readable table of a Comparison.

    Parameters
    ----------
    result : Any
        A comparison.
    files : list[str]
        The files written.
    """
    def cell(row: dict[str, Any], key: str, fmt: str) -> str:
        value = row.get(key)
        return "-" if value is None else format(value, fmt)

    robust = any(r.get("worst_case_error") is not None for r in result.rows)
    timed = any(r.get("certified_lower_bound") is not None for r in result.rows)  # compare --shortest: the moves' durations
    def judged(row: dict[str, Any]) -> str:
        return "-" if row.get("period") is None else f"{1e3 * row['period']:.4g} ms {row.get('hold', '')}".strip()

    rows = [[r["method"], r["status"], cell(r, "max_redefinition_error", ".3g"), cell(r, "peak_torque", ".4g"),
             cell(r, "torque_at_end", ".3g"), cell(r, "pre_actuation_time", ".3g"), cell(r, "residual_vibration", ".3g"),
             judged(r), cell(r, "held_tip_error", ".3g"), cell(r, "seconds", ".2f")] + ([cell(r, "worst_case_error", ".3g")] if robust else [])
            + ([cell(r, "duration", ".4g"), cell(r, "certified_lower_bound", ".4g")] if timed else [])
            for r in result.rows]
    lines = [table(["method", "status", "max |y~ - y_d| (m)", "peak torque (N m)", "tau_l(tf) (N m)", "pre-actuation (s)",
                    "vibration after tf (m p-p)", "judged at", "held tip (m)", "seconds"] + (["worst case (of the move)"] if robust else [])
                   + (["move (s)", "none shorter than (s)"] if timed else []), rows), ""]
    for r in result.rows:
        note = r["settings"] if r["status"] == "ok" else r["message"]
        extra = f"; {r['message']}" if r["status"] == "ok" and r.get("message") else ""
        lines.append(f"  {r['method']:<11s} {note}{extra}")
    return _with_files(lines, files)


def fit_text(result: Any, files: list[str]) -> str:
    """Readable summary of a calibration (:class:`modelgen.fit.Fit`): each parameter's nominal and fitted value with its
    95 % interval (its noise, model and held parts), the residuals before and after against the data's own noise, the
    modes, what was held and why."""
    s = result.summary()
    noise = s.get("data_noise")
    seen = f"; the data's own noise {noise:.3g}" if noise is not None else ""
    lines = [f"{result.geometry.name}: calibrated to {s['kind']} ({s['points']} residuals, {s['evaluations']} model evaluations, "
             f"{s['starts']} starts)",
             _row("residual", f"relative RMS {s['residual']:.3g} (the nominal model's {s['nominal_residual']:.3g}{seen})"),
             _row("modes", f"fitted with {s['modes']} (the model's {s['model_modes']}), checked with up to {s['checked_modes']}"
                  + ("" if s["converged"] else " (not checked: the most modes the model takes)" if s["checked_modes"] == s["modes"]
                     else " (the estimates still moved)")), "",
             table(["parameter", "nominal", "fitted", "95 % interval", "relative", "noise part", "model part", "held part"],
                   [[k, f"{p['nominal']:.6g}", f"{p['value']:.6g}", f"+- {p['interval_95']:.3g}", f"{100 * p['relative_interval']:.3g} %",
                     f"{p['noise_95']:.3g}", f"{p['model_95']:.3g}", f"{p['held_95']:.3g}"]
                    for k, p in s["parameters"].items()])]
    for k, (name, test) in enumerate(s.get("residual_tests", {}).items()):
        lines.insert(3 + k, _row(f"{name} residual", f"lag-one correlation {test['lag_one']:.3g}; with the torque at most "
                             f"{test['input_correlation']:.3g} ({1e3 * test['at_lag_s']:.3g} ms), {test['z']:.3g} sd (at most "
                             f"{test['limit']:g} is chance)"))
    if s["notes"]:
        lines += [""] + [f"note: {note}" for note in s["notes"]]
    if s["held"]:
        spreads = s.get("held_spread", {})

        def spread(key: str) -> str:
            if key not in spreads:
                return ""
            return (f" (assumed within {100 * spreads[key]['relative_95']:.3g} %: --held-spread)" if spreads[key]["assumed"]
                    else f" (stated within {100 * spreads[key]['relative_95']:.3g} %)")

        lines += ["", "held at their nominal values (the fitted values assume them; their spread is in the held part):"] + [
            f"  {k}: {why}{spread(k)}" for k, why in s["held"].items()]
    return _with_files(lines, files)
