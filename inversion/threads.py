"""The cores the numerics may use, and one BLAS thread around their skinny products.

:func:`one_thread` lives in :mod:`modelgen.threads` (the calibration uses it too) and is
re-exported here for the inversion's modules.
"""

from __future__ import annotations

import os

from modelgen.threads import one_thread

__all__ = ["one_thread", "available_cores", "worker_count"]


def available_cores() -> int:
    """The cores this process may run on.

    The cores this process may run on (its affinity where the system tells it), the default number of workers.
    """
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def worker_count(workers: int | None) -> int:
    """The local processes to start for ``workers``.

    The local processes to start for ``workers`` (``None``: all cores): at most the cores this process may run on.

    More processes than cores only contend for them (``workers=1000`` started 185 processes before the first finished):
    a larger request is capped, with a one-line warning saying so.

    Parameters
    ----------
    workers : int | None
        The processes asked for, or ``None``.
    """
    cores = available_cores()
    if workers is None:
        return cores
    if workers > cores:
        from modelgen.errors import warn

        warn(f"workers = {workers} is more than the {cores} cores this process may run on: {cores} local processes")
        return cores
    return workers
