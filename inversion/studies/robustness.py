"""The link the user does not know exactly: a feedforward judged on perturbed models in the closed loop.

A feedforward is computed for a model and applied to a link whose flexural rigidity, payload or
hub differ from it. ``SPEC`` names geometry keys with relative ranges,
``link.flexural_rigidity=10%,payload.mass=20%``; :func:`robustness` builds the perturbed
geometries -- every corner of the box (``2^k``) and, with ``samples``, a seeded Latin hypercube
inside it (:class:`scipy.stats.qmc.LatinHypercube`) -- and their linear models
(:func:`modelgen.linear.linear_model`: the geometry with the value changed, exactly as an edited
geometry file would give, no code generated), and drives each in the closed loop of the paper's
Fig. 1: the feedforward plus the joint PD on its references (the gains :func:`simulation.simulate`
uses: the paper's for its cases, else :func:`modelgen.joint_pd.rule_gains`)::

    u = tau + k_P (theta_d - theta) + k_D (thetadot_d - thetadot)

The loop is linear, so each perturbed plant is ``x' = (A - B K) x + B (tau + k_P theta_d + k_D
thetadot_d)``, driven exactly by the result's Chebyshev series (:func:`inversion.acceptance.drive_series`)
from rest, then left with the references held at their ends over the after-end window. The
figure is the largest ``|y - y_d|`` during the move and after it, relative to the move; the
worst over the parameter sets is ``worst_case_error``, with the set that gives it.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from modelgen.geometry import MAX_MODES, PARAMETER_KEYS, modal_mode, parameter_value, relative_values, scaled

from ..acceptance import drive_series, free_peaks, rest_angle, window_length
from ..errors import SettingsError
from ..signals.chebyshev import PiecewiseChebyshev

__all__ = ["Uncertainty", "parse_uncertainty", "robustness", "judge_robustness", "judge_family", "robust_choice", "UNCERTAIN_KEYS",
           "MAX_CORNERS"]

FloatArray = NDArray[np.float64]
#: The geometry keys an uncertainty may name, and the fields they are (:data:`modelgen.geometry.PARAMETER_KEYS` but the
#: hub's dry friction: the perturbed links are judged on the linear model, which has none, so a spread of it would
#: perturb nothing). Besides them, ``damping.modal_K``: mode ``K``'s ratio of a geometry damped per mode.
UNCERTAIN_KEYS = {k: v for k, v in PARAMETER_KEYS.items() if k != "hub.coulomb_friction"}
#: At most this many keys (``2^k`` corners).
MAX_CORNERS = 2**8
#: Most Latin-hypercube samples.
MAX_SAMPLES = 10_000


@dataclass(frozen=True)
class Uncertainty:
    """Relative ranges of geometry keys and a sample count.

    Relative ranges of geometry keys (module docstring), and how many seeded samples inside them.

    Attributes
    ----------
    ranges : tuple[tuple[str, float], ...]
        Each geometry key with its relative range.
    samples : int, optional
        Seeded samples inside the ranges, beside the corners.
    seed : int, optional
        The samples' seed.
    """

    ranges: tuple[tuple[str, float], ...]
    samples: int = 0
    seed: int = 0

    def spec(self) -> str:
        """The SPEC it was parsed from.

        The SPEC it was parsed from (``link.flexural_rigidity=10%,...``).
        """
        return ",".join(f"{k}={100 * r:g}%" for k, r in self.ranges)

    def factors(self) -> FloatArray:
        """The multipliers of every parameter set.

        The multipliers of every parameter set: the corners, then the samples (shape (sets, keys)).
        """
        r = np.array([v for _, v in self.ranges])
        corners = np.array(list(itertools.product(*[(-1.0, 1.0)] * r.size))) if r.size else np.zeros((1, 0))
        sets = [1.0 + corners * r]
        if self.samples:
            from scipy.stats import qmc

            unit = qmc.LatinHypercube(d=r.size, seed=self.seed).random(self.samples)
            sets.append(1.0 + (2.0 * unit - 1.0) * r)
        return np.vstack(sets)

    def check(self, model: Any) -> None:
        """Refuse what this uncertainty cannot perturb.

        Refuse what this uncertainty cannot perturb: a generic system (no geometry), or a key whose value is zero in the
        link's geometry (a relative spread of zero is zero: every set would be the nominal link, reported as a spread).

        Parameters
        ----------
        model : Any
            The model to perturb.

        Raises
        ------
        SettingsError
            Naming the key, or the model.
        """
        from modelgen.model import Model

        if not isinstance(model, Model):
            raise SettingsError("uncertainty", self.spec(), "a link model: a generic system has no geometry keys to perturb "
                                "(perturb its coefficients and invert each instead)")
        modal = bool(model.geometry.modal_damping)
        for key, _ in self.ranges:
            if modal_mode(key) is not None and not modal:
                raise SettingsError(f"uncertainty {key}", key, f"damping.ratio: {model.name}'s geometry has Rayleigh damping "
                                    "(damping.modal_K is a ratio of a geometry damped per mode, [damping] modal)")
            if (modal_mode(key) or 0) > model.n:
                raise SettingsError(f"uncertainty {key}", key, f"damping.modal_K with K = 1..{model.n}: {model.name} has "
                                    f"{model.n} modes, and a ratio of a mode it does not have perturbs nothing")
            if key == "damping.ratio" and modal:
                raise SettingsError(f"uncertainty {key}", key, f"damping.modal_K (K = 1..{model.n}): {model.name}'s geometry is "
                                    "damped per mode ([damping] modal), and Rayleigh's ratio is not one of its parameters")
            if parameter_value(model.geometry, key) == 0.0:
                raise SettingsError(f"uncertainty {key}", f"{key}={self.spec().split(key + '=')[1].split(',')[0]}",
                                    f"a parameter that is not zero in {model.name}'s geometry: it is 0 there, and a relative range "
                                    "of zero perturbs nothing (give the link a nominal value first)")

    def output_at(self, model: Any, geometry: Any) -> float:
        """Where a perturbed link's output is measured.

        At its own tip where the nominal one's is at the tip (a sensor on the tip stays on it when the link is longer or
        shorter), elsewhere at the same distance from the hub.

        Parameters
        ----------
        model : Model
            The nominal model.
        geometry : Geometry
            A perturbed geometry (:meth:`perturbed`).

        Raises
        ------
        SettingsError
            Where a shorter link ends before the output point: naming this uncertainty, not the output point.
        """
        nominal = float(model.output_at)
        if abs(nominal - float(model.geometry.length)) <= 1e-12 * float(model.geometry.length):
            return float(geometry.length)
        if nominal > float(geometry.length):
            raise SettingsError("uncertainty", self.spec(), f"a range that keeps the link longer than its output point: the output at "
                                f"{nominal:g} m is beyond the perturbed link's end at {float(geometry.length):g} m")
        return nominal

    def corner_plants(self, model: Any) -> list[tuple[str, tuple[FloatArray, FloatArray, FloatArray]]]:
        """The corners' linear plants, named.

        What :func:`inversion.invert`'s optimal-control and re-planned programmes hold at once.

        Parameters
        ----------
        model : Model
            The nominal link (checked, :meth:`check`).

        Returns
        -------
        list of (str, (A, B, C))
            ``"link.flexural_rigidity x 0.95, ..."`` and the perturbed geometry's model (:func:`modelgen.linear.linear_model`,
            its output where :meth:`output_at` puts it), the samples left out.
        """
        from modelgen.linear import linear_model

        self.check(model)
        out = []
        for factors, geometry in Uncertainty(self.ranges).perturbed(model.geometry):
            m = linear_model(geometry, model.n, self.output_at(model, geometry))
            out.append((", ".join(f"{key} x {factor:.4g}" for key, factor in factors.items()),
                        (np.asarray(m["A"], dtype=float), np.asarray(m["B"], dtype=float).reshape(-1),
                         np.asarray(m["C_out"], dtype=float).reshape(-1))))
        return out

    def perturbed(self, geometry: Any) -> list[tuple[dict[str, float], Any]]:
        """Every parameter set applied to ``geometry``.

        Every parameter set applied to ``geometry``: ``(factors by key, the geometry with the values changed)``, the corners
        first -- each exactly the geometry an edited TOML gives (tested).

        Parameters
        ----------
        geometry : Any
            The nominal geometry.
        """
        return [({k: float(x) for (k, _), x in zip(self.ranges, row)},
                 scaled(geometry, {k: float(x) for (k, _), x in zip(self.ranges, row)})) for row in self.factors()]


def parse_uncertainty(spec: str, samples: int = 0, seed: int = 0) -> Uncertainty:
    """An :class:`Uncertainty` from its SPEC.

    ``link.flexural_rigidity=10%,payload.mass=20%`` (a ``%`` or a fraction: ``0.1``) as an :class:`Uncertainty`; or
    ``fit:CALIBRATED.toml``, the 95 % intervals ``sflm fit`` recorded in a calibrated geometry file.

    Parameters
    ----------
    spec : str
        The SPEC.
    samples : int, optional
        Seeded samples inside the ranges, beside the corners.
    seed : int, optional
        The samples' seed.

    Raises
    ------
    SettingsError
        For an unknown key, a range outside ``(0, 100 %)``, a repeated key, more than 8 keys, or samples out of range.

    Examples
    --------
    >>> parse_uncertainty("link.flexural_rigidity=10%,payload.mass=0.2").ranges
    (('link.flexural_rigidity', 0.1), ('payload.mass', 0.2))
    """
    if isinstance(spec, str) and spec.startswith("fit:"):  # a calibrated geometry file: its fitted parameters' 95 % intervals (modelgen.fit)
        from modelgen.fit import spread_of_calibration

        spec = spread_of_calibration(spec[4:])
    ranges = relative_values(spec, "uncertainty", "a relative range above 0 and below 100 %", 0.0, 1.0)
    if any(key == "hub.coulomb_friction" for key, _ in ranges):
        raise SettingsError("uncertainty key", "hub.coulomb_friction", "one of " + ", ".join(UNCERTAIN_KEYS) + f", or damping.modal_K "
                            f"(K = 1..{MAX_MODES}: a geometry damped per mode)")
    if 2 ** len(ranges) > MAX_CORNERS:
        raise SettingsError("uncertainty", spec, f"at most {int(math.log2(MAX_CORNERS))} keys ({MAX_CORNERS} corners)")
    if isinstance(samples, bool) or not isinstance(samples, int) or not 0 <= samples <= MAX_SAMPLES:
        raise SettingsError("samples", samples, f"an integer in 0..{MAX_SAMPLES}")
    return Uncertainty(tuple(ranges), samples, seed)


def _combined(signals: PiecewiseChebyshev, kp: float, kd: float) -> PiecewiseChebyshev:
    """The loop's input ``tau + k_P theta_d + k_D thetadot_d`` as one series (the series are linear in their coefficients)."""
    c = signals.coefficients
    u = c[:, 0:1, :] + kp * c[:, 1:2, :] + kd * c[:, 2:3, :]
    peak = float(signals.peaks[0] + kp * signals.peaks[1] + kd * signals.peaks[2])
    return replace(signals, names=("u",), coefficients=u, peaks=np.array([peak]))


def _closed_loop_error(matrices: dict[str, Any], signals: PiecewiseChebyshev, kp: float, kd: float, trajectory: Any,
                       window: float) -> float:
    """``max |y - y_d|`` of one plant in the closed loop, during the feedforward and over ``window`` after it."""
    A = np.asarray(matrices["A"], dtype=float)
    B = np.asarray(matrices["B"], dtype=float).reshape(-1)
    C = np.asarray(matrices["C_out"], dtype=float).reshape(-1)
    n1 = A.shape[0] // 2
    gain = np.zeros(A.shape[0])
    gain[0], gain[n1] = kp, kd
    A_cl = A - np.outer(B, gain)
    feed = _combined(signals, kp, kd)
    times, y, x_end = drive_series(A_cl, B, np.zeros(A.shape[0]), feed, "u", C)
    y_d = trajectory.derivative(np.clip(times, trajectory.t0, trajectory.tf), 0)
    during = float(np.abs(y - y_d).max())
    y_final = trajectory.y_final
    # after the feedforward the PD holds the joint at rest on y_d(t_f), as the exported C's FINAL and the simulation do
    # (a held table's last row is the joint a period before the end, not where it rests)
    theta_end = rest_angle(C, y_final)
    after = float(free_peaks(A_cl, B, C, x_end[None, :], y_final, kp * theta_end, window)[0])
    return max(during, after)


def robustness(result: Any, uncertainty: Uncertainty, gains: tuple[float, float]) -> dict[str, Any]:
    """The result judged on the perturbed links in the closed loop.

    The result judged on the perturbed links in the closed loop (module docstring): the summary's ``robustness`` block.

    Parameters
    ----------
    result : InversionResult
        A link's result (its ``signals`` are the feedforward and the joint references).
    uncertainty : Uncertainty
    gains : (float, float)
        ``(k_P, k_D)`` of the joint PD.

    Raises
    ------
    SettingsError
        For a generic system (no geometry to perturb).
    """
    from modelgen.linear import linear_model
    from modelgen.model import Model

    model = result.model
    uncertainty.check(model)
    assert isinstance(model, Model)
    if result.signals is None or tuple(result.signals.names) != ("tau", "theta_d", "thetadot_d"):
        raise SettingsError("uncertainty", uncertainty.spec(), "a result with the link's feedforward series")
    kp, kd = gains
    trajectory = result.trajectory
    move = trajectory.move() if trajectory.move() > 0 else 1.0
    geometry = model.geometry
    keys = [k for k, _ in uncertainty.ranges]
    factors = uncertainty.factors()
    sets = uncertainty.perturbed(geometry)
    nominal_matrices = linear_model(geometry, model.n, model.output_at)
    from ..lti.system import NormalForm

    window = window_length(NormalForm.of_matrices(model.name, nominal_matrices, float(model.output_at)), None)
    nominal = _closed_loop_error(nominal_matrices, result.signals, kp, kd, trajectory, window)
    errors = [_closed_loop_error(linear_model(perturbed, model.n, uncertainty.output_at(model, perturbed)), result.signals, kp, kd,
                                 trajectory, window) for _, perturbed in sets]
    worst = int(np.argmax(errors))
    corners = 2 ** len(keys)
    return {
        "uncertainty": uncertainty.spec(), "corners": corners, "samples": uncertainty.samples, "seed": uncertainty.seed,
        "gains": {"kp": kp, "kd": kd}, "window": window,
        "nominal_error": nominal / move, "worst_case_error": float(errors[worst]) / move,
        "worst_parameters": {k: parameter_value(sets[worst][1], k) for k in keys},
        "worst_factors": {k: float(factors[worst][i]) for i, (k, _) in enumerate(uncertainty.ranges)},
        "corner_errors": [float(e) / move for e in errors[:corners]],
    }


def judge_robustness(result: Any, uncertainty: str | Uncertainty, samples: int = 0, seed: int = 0) -> dict[str, Any]:
    """:func:`robustness` with the closed loop's gains, stored.

    :func:`robustness` with the gains the closed loop uses for the result's model and trajectory (the paper's for its
    cases, else the rule's), stored in ``result.summary["robustness"]`` and returned.

    Parameters
    ----------
    result : Any
        An inversion's result.
    uncertainty : str | Uncertainty
        The uncertainty, or its SPEC.
    samples : int, optional
        Seeded samples inside the ranges, beside the corners.
    seed : int, optional
        The samples' seed.

    Examples
    --------
    >>> import modelgen
    >>> from inversion import invert, trajectory_from_spec
    >>> r = invert(modelgen.load("paper-sim"), trajectory_from_spec("paper-sim"))
    >>> block = judge_robustness(r, "link.flexural_rigidity=10%,payload.mass=20%")
    >>> block["corners"], block["worst_case_error"] > block["nominal_error"]
    (4, True)
    """
    from modelgen.joint_pd import loop_gains

    from ..problem import paper_case

    if not isinstance(uncertainty, Uncertainty):
        uncertainty = parse_uncertainty(uncertainty, samples, seed)
    uncertainty.check(result.model)
    block = robustness(result, uncertainty, loop_gains(result.model, paper_case(result.model, result.trajectory)))
    result.summary["robustness"] = block
    return block


def _usable(family: Any, bound: float) -> list[dict[str, Any]]:
    """The explored members within the bound during and after the move and within the torque limit, by peak torque."""
    limit = family.summary["max_torque"]
    usable = [r for r in family.rows if r["status"] == "ok" and r["max_redefinition_error"] <= bound
              and (r["after_end_excursion"] is None or r["after_end_excursion"] <= bound) and r["peak_torque"] <= limit]
    return sorted(usable, key=lambda r: r["peak_torque"])


def _spread(rows: list[dict[str, Any]], count: int) -> list[dict[str, Any]]:
    """At most ``count`` of ``rows``, spread evenly over them (the first and the last among them)."""
    return rows if len(rows) <= count else [rows[int(round(i))] for i in np.linspace(0, len(rows) - 1, count)]


def _judge_row(model: Any, trajectory: Any, row: dict[str, Any], uncertainty: Uncertainty, gains: tuple[float, float], bound: float,
               limit: float) -> tuple[dict[str, Any], Any] | None:
    """One explored member inverted as given (verified) and judged by :func:`robustness`, or ``None`` if it is not within
    the bound after the move and the torque limit once verified."""
    from ..api import invert
    from ..errors import InversionError
    from ..family.method import Family
    from ..problem import Bounds, Problem

    member = Family(segments=row["segments"], h=row["h"], cdec=(row["cdec_fast"], row["cdec_slow"]), joining=row["joining"],
                    end=row["end"])
    try:
        result = invert(Problem(model, trajectory, bounds=Bounds(max_error=bound)), method=member)
    except (InversionError, SettingsError):
        return None
    s = result.summary
    if not (s["peak_torque"] <= limit and s["verification"]["after_end"]["max_tip_excursion"] <= bound):
        return None
    return robustness(result, uncertainty, gains), result


def _worker_judge(link: tuple[Any, int, str, float], trajectory: Any, row: dict[str, Any], uncertainty: Uncertainty,
                  gains: tuple[float, float], bound: float, limit: float) -> tuple[dict[str, Any], dict[str, Any]] | None:
    """:func:`_judge_row` in a worker process or on a Dask worker: the link loaded there from its geometry (a cache hit
    after the first), the block and the member's description sent back (a result holds compiled functions)."""
    from modelgen import load

    from ..threads import one_thread

    geometry, modes, shapes, output_at = link
    with one_thread():
        judged = _judge_row(load(geometry, modes=modes, mode_shapes=shapes, output_at=output_at), trajectory, row, uncertainty, gains,
                            bound, limit)
    return None if judged is None else (judged[0], _described(judged[1]))


def _judged_members(model: Any, trajectory: Any, rows: list[dict[str, Any]], uncertainty: Uncertainty, gains: tuple[float, float],
                    bound: float, limit: float, progress: Any = None, workers: int | None = None, executor: Any = None,
                    results: dict[int, Any] | None = None) -> list[tuple[dict[str, Any], dict[str, Any], dict[str, Any]]]:
    """Each row judged (:func:`_judge_row`): ``(block, row, description)`` of those still within the bounds once verified,
    in the rows' order; each row's ``worst_case_error`` set (``None`` if not). In this process (``workers=1``, or a single
    row; then ``results``, if given, gets each judged row's result by ``id(row)``), on local processes (``workers``,
    default all cores) or on ``executor`` (a Dask client, or any with ``submit``)."""
    import concurrent.futures

    from ..threads import worker_count

    for row in rows:
        row["worst_case_error"] = None
    count = worker_count(workers)
    outcomes: dict[int, tuple[dict[str, Any], dict[str, Any]] | None] = {}
    if executor is None and (count <= 1 or len(rows) <= 1):
        for k, row in enumerate(rows):
            judged = _judge_row(model, trajectory, row, uncertainty, gains, bound, limit)
            outcomes[k] = None if judged is None else (judged[0], _described(judged[1]))
            if judged is not None and results is not None:
                results[id(row)] = judged[1]
            if progress is not None:
                progress(k + 1, len(rows))
    else:
        link = (model.geometry, model.n, model.mode_family, model.output_at)
        pool = concurrent.futures.ProcessPoolExecutor(max_workers=min(count, len(rows))) if executor is None else None
        submit = (pool or executor).submit
        try:
            futures = {submit(_worker_judge, link, trajectory, row, uncertainty, gains, bound, limit): k for k, row in enumerate(rows)}
            for future in futures:  # in order: the progress counts what is done
                outcomes[futures[future]] = future.result()
                if progress is not None:
                    progress(len(outcomes), len(rows))
        finally:
            if pool is not None:
                pool.shutdown()
    judged_rows = []
    for k, row in enumerate(rows):
        outcome = outcomes[k]
        if outcome is not None:
            row["worst_case_error"] = outcome[0]["worst_case_error"]
            judged_rows.append((outcome[0], row, outcome[1]))
    return judged_rows


def judge_family(family: Any, model: Any, trajectory: Any, uncertainty: str | Uncertainty, *, max_error: float | None = None,
                 candidates: int = 16, progress: Any = None, workers: int | None = None, executor: Any = None) -> dict[str, Any]:
    """The explored family's worst cases on the perturbed links.

    The explored family's worst cases (``explore --uncertainty``): the members within the bounds (at most
    ``candidates``, spread over their peak torques) inverted and judged on the perturbed links by :func:`robustness`.

    Sets each row's ``worst_case_error`` (``None`` where it was not judged: outside the bounds, or beyond the
    ``candidates`` spread) and ``family.summary["robustness"]``: ``uncertainty``, ``corners``, ``samples``, ``gains``,
    ``judged``, ``usable``, ``rule`` and ``least`` (the judged member of least worst case, its settings and figures).
    The members are judged in this process (``workers=1``), on local processes (``workers``, default all cores) or on
    ``executor`` (a Dask client), as the explorer's.

    Parameters
    ----------
    family : Any
        The explored family.
    model : Any
        The nominal model.
    trajectory : Any
        The desired output.
    uncertainty : str | Uncertainty
        The uncertainty, or its SPEC.
    max_error : float | None, optional
        The tip's bound (m).
    candidates : int, optional
        Most members judged.
    progress : Any, optional
        A callback ``(done, total)``, or ``None``.
    workers : int | None, optional
        Local processes (``None``: all cores).
    executor : Any, optional
        A Dask client or executor to run on, if given.
    """
    from modelgen.joint_pd import loop_gains

    from ..problem import Bounds, Problem, paper_case

    if not isinstance(uncertainty, Uncertainty):
        uncertainty = parse_uncertainty(uncertainty)
    uncertainty.check(model)
    gains = loop_gains(model, paper_case(model, trajectory))
    bound = Problem(model, trajectory, bounds=Bounds(max_error=max_error)).bound()
    for row in family.rows:
        row["worst_case_error"] = None
    usable = _usable(family, bound)
    judged = _judged_members(model, trajectory, _spread(usable, candidates), uncertainty, gains, bound, family.summary["max_torque"],
                             progress, workers, executor)
    least = min(judged, key=lambda item: item[0]["worst_case_error"], default=None)
    block = {
        "uncertainty": uncertainty.spec(), "corners": 2 ** len(uncertainty.ranges), "samples": uncertainty.samples,
        "gains": {"kp": gains[0], "kd": gains[1]}, "usable": len(usable), "judged": len(judged),
        "rule": f"the members within {bound:.3g} m during and after the move and the torque limit, at most {candidates} spread over "
                "their peak torques, inverted and judged on the perturbed links in the closed loop with the joint PD",
        "least": None if least is None else {"worst_case_error": least[0]["worst_case_error"], **least[2]},
    }
    family.summary["robustness"] = block
    return block


def robust_choice(model: Any, trajectory: Any, uncertainty: str | Uncertainty, *, max_error: float | None = None,
                  max_torque: float | None = None, candidates: int = 16, workers: int | None = None, executor: Any = None,
                  progress: Any = None, **options: Any) -> Any:
    """The member of least worst-case error on the perturbed links.

    The member of least worst-case error on the perturbed links (``objective="robust"``), within the torque limit.

    The explorer maps the family (:func:`inversion.family.explore.explore`); its members within the bound
    during and after the move and within the torque limit (``max_torque``, default three times the
    rigid need) are the candidates -- at most ``candidates`` of them, spread evenly over their peak
    torques -- together with the default automatic member; each is inverted as given (verified) and
    judged by :func:`robustness`. The one whose worst case is least wins; so the robust member's
    worst case is never above the default member's. The summary's ``robustness`` block gains
    ``choice``: the candidates' settings, peak torques and worst cases, and the default member's. The explorer and the
    judging run in this process (``workers=1``), on local processes or on ``executor`` (a Dask client).

    Parameters
    ----------
    model : Any
        The nominal model.
    trajectory : Any
        The desired output.
    uncertainty : str | Uncertainty
        The uncertainty, or its SPEC.
    max_error : float | None, optional
        The tip's bound (m).
    max_torque : float | None, optional
        The peak torque's bound (N m).
    candidates : int, optional
        Most members judged.
    workers : int | None, optional
        Local processes (``None``: all cores).
    executor : Any, optional
        A Dask client or executor to run on, if given.
    progress : Any, optional
        A callback ``(done, total)``, or ``None``.

    Raises
    ------
    InversionError
        When no candidate is within the bounds (with the explorer's figures).
    """
    from modelgen.joint_pd import loop_gains

    from ..api import invert
    from ..errors import InversionError
    from ..family.explore import explore
    from ..family.method import Family
    from ..problem import Bounds, Problem, paper_case

    if not isinstance(uncertainty, Uncertainty):
        uncertainty = parse_uncertainty(uncertainty)
    uncertainty.check(model)
    gains = loop_gains(model, paper_case(model, trajectory))
    bound = Problem(model, trajectory, bounds=Bounds(max_error=max_error)).bound()
    options.setdefault("end", ("free", "rest", "settle"))  # every end: a rest or settle end leaves the link less to ring
    family = explore(model, trajectory, max_error=bound, max_torque=max_torque, workers=workers, executor=executor, **options)
    limit = family.summary["max_torque"]
    default = invert(Problem(model, trajectory, bounds=Bounds(max_error=bound, max_torque=max_torque)), method=Family(auto=True))
    default_block = robustness(default, uncertainty, gains)
    tried: list[tuple[dict[str, Any], dict[str, Any] | None, dict[str, Any]]] = [
        (default_block, None, {"member": "the automatic choice", **_described(default)})]
    kept: dict[int, Any] = {}
    tried += _judged_members(model, trajectory, _spread(_usable(family, bound), candidates), uncertainty, gains, bound, limit, progress,
                             workers, executor, kept)
    tried.sort(key=lambda item: item[0]["worst_case_error"])
    block, row, _ = tried[0]
    best: Any
    if row is None:
        best = default
    elif id(row) in kept:
        best = kept[id(row)]
    else:  # judged elsewhere: the winner inverted again here (deterministic), its block the one measured
        again = _judge_row(model, trajectory, row, uncertainty, gains, bound, limit)
        if again is None:
            raise InversionError(f"the robust member ({row['segments']} segments, h = {row['h']}) failed when inverted again")
        best = again[1]
    block = dict(block)
    block["choice"] = {
        "objective": "robust", "rule": "least worst-case error on the perturbed links, within the bound and the torque limit",
        "max_torque": limit, "max_error": bound, "explored": len(family.rows), "candidates": len(tried),
        "default_worst_case_error": default_block["worst_case_error"], "default_peak_torque": default.summary["peak_torque"],
        "tried": [{"worst_case_error": b["worst_case_error"], **d} for b, _, d in tried],
    }
    best.summary["robustness"] = block
    return best


def _described(result: Any) -> dict[str, Any]:
    """A candidate's settings and figures for the ``choice`` record."""
    s = result.summary
    st = s["settings"]
    return {"segments": len(st["segments"]) - 1, "h": st["h"], "cdec": list(st["cdec"]), "joining": st["joining"], "end": st["end"],
            "peak_torque": s["peak_torque"], "relative_redefinition_error": s["relative_redefinition_error"]}
