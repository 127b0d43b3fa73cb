"""inversion: piece-wise causal inversion by output redefinition (the numeric layer).

Consumes a loaded :class:`modelgen.Model` (compiled functions) and never imports SymPy.

One problem at the door (:class:`Problem`: the model, the move, the :class:`Bounds`, the controller's
:class:`Sampling`, the :class:`Loop`), one method object of the registry (:class:`Family`, :class:`OptimalControl`,
:class:`Replan`, :class:`Stable`, :class:`Polynomial`, :class:`ZV`, :class:`ZVD`, or :class:`Automatic`, the default),
one judged result (:class:`InversionResult`), written as a run (:func:`write_run`) that ``sflm simulate --feedforward``
reads back (:func:`read_run`):

>>> import modelgen, inversion
>>> problem = inversion.Problem(modelgen.load("paper-sim"), inversion.smoothstep(1.57, 5.5))
>>> result = inversion.invert(problem)
"""

from __future__ import annotations

from .api import invert
from .methods.ocp import OptimalControl
from .methods.polynomial import Polynomial
from .methods.replan import Replan
from .methods.shaping import ZV, ZVD
from .methods.stable import Stable
from .methods.automatic import Automatic
from .methods.shortest import ShortestMove, shortest_move
from .methods.fastest import fastest_move
from .errors import InversionError, SettingsError, TrajectoryError
from .family.explore import Exploration, explore
from .family.method import Family
from .options import InversionMethod, method_names, register, registered
from .problem import Bounds, Loop, Problem, Sampling
from .realtime.feedforward_c import export_c, export_table
from .realtime.runs import read_run, write_run
from .result import CSV_COLUMNS, InversionResult, InversionSummary
from .settings import InversionSettings
from .signals.trajectory import (
    CallableTrajectory,
    PolynomialTrajectory,
    Trajectory,
    experiment_trajectory,
    from_csv,
    smoothstep,
    trajectory_from_spec,
)

__all__ = [
    "Automatic",
    "Bounds",
    "CSV_COLUMNS",
    "Family",
    "InversionMethod",
    "Loop",
    "OptimalControl",
    "Polynomial",
    "Problem",
    "Replan",
    "Sampling",
    "ShortestMove",
    "Stable",
    "ZV",
    "ZVD",
    "method_names",
    "read_run",
    "register",
    "registered",
    "shortest_move",
    "fastest_move",
    "write_run",
    "CallableTrajectory",
    "Exploration",
    "InversionError",
    "InversionResult",
    "InversionSummary",
    "InversionSettings",
    "PolynomialTrajectory",
    "SettingsError",
    "Trajectory",
    "TrajectoryError",
    "experiment_trajectory",
    "explore",
    "export_c",
    "export_table",
    "from_csv",
    "invert",
    "smoothstep",
    "trajectory_from_spec",
]


#: Modules that moved when the layer was arranged in rooms (issue 35), old name -> new: importing the old name still
#: works for this release, with a DeprecationWarning that names the new one (CHANGELOG.md lists them).
MOVED = {f"inversion.{old}": f"inversion.{new}" for old, new in (
    ("anchors", "family.anchors"), ("auto", "family.auto"), ("causal_limit", "lti.causal_limit"), ("chebyshev", "signals.chebyshev"),
    ("compare", "studies.compare"), ("discrete", "lti.discrete"), ("explore", "family.explore"),
    ("exponentials", "lti.exponentials"), ("figures", "family.figures"), ("internal", "lti.internal"),
    ("linear_system", "lti.linear_system"), ("member", "family.member"), ("ocp", "methods.ocp"),
    ("piecewise", "family.piecewise"), ("polynomial", "methods.polynomial"), ("redefinition", "family.redefinition"),
    ("robustness", "studies.robustness"), ("settle", "family.settle"), ("shaping", "methods.shaping"),
    ("ssef", "family.ssef"), ("ssef.basis", "family.ssef.basis"), ("ssef.conditions", "family.ssef.conditions"),
    ("ssef.evaluate", "family.ssef.evaluate"), ("ssef.plan", "family.ssef.plan"), ("ssef.solve", "family.ssef.solve"),
    ("stable", "methods.stable"), ("system", "lti.system"), ("trajectory", "signals.trajectory"), ("verify", "family.verify"),
    ("zero_dynamics", "lti.zero_dynamics"), ("export", "realtime.feedforward_c"), ("fmu", "realtime.feedforward_fmu"),
    ("realtime.export", "realtime.feedforward_c"), ("realtime.fmu", "realtime.feedforward_fmu"),
    ("baselines", "methods"), ("margin", "methods.margin"),
    *((f"baselines.{m}", f"methods.{m}") for m in ("bounded_limit", "ocp", "polynomial", "replan", "shaping", "stable")),
)}


def _moved_finder() -> object:
    """A finder that gives a moved module's old name the new module, with a DeprecationWarning."""
    import importlib
    import importlib.abc
    import importlib.util
    import warnings

    class Moved(importlib.abc.MetaPathFinder, importlib.abc.Loader):
        def find_spec(self, fullname: str, path: object, target: object = None) -> object:
            return importlib.util.spec_from_loader(fullname, self) if fullname in MOVED else None

        def create_module(self, spec: object) -> object:
            old = getattr(spec, "name")
            warnings.warn(f"{old} moved to {MOVED[old]}: import it from there (the old name goes with the next release)",
                          DeprecationWarning, stacklevel=2)
            return importlib.import_module(MOVED[old])

        def exec_module(self, module: object) -> None:
            return None

    return Moved()


import sys as _sys  # noqa: E402

if not any(type(f).__name__ == "Moved" and getattr(f, "__module__", "") == __name__ for f in _sys.meta_path):
    _sys.meta_path.insert(0, _moved_finder())  # type: ignore[arg-type]  # before the path finder: it would load the old names

