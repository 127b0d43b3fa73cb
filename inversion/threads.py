"""One BLAS thread around the skinny products of the numerics.

The inversion's products are tall and thin (``(N, 12) @ (12, 6)``, many ``(r, r)``
solves): a BLAS pool of threads only spins on them. On two cores the default pools of
NumPy and SciPy made 1e6 samples 1.2 s against 0.3 s on one thread. :func:`one_thread`
holds every BLAS pool loaded in the process to one thread for the duration of a block.

The pools are found once (:class:`threadpoolctl.ThreadpoolController` costs ~5 ms),
then limiting and restoring costs ~30 us. A library loaded after the first call (SciPy's
own BLAS, imported lazily) is picked up at the next call.
"""

from __future__ import annotations

import os
import sys
from contextlib import contextmanager
from typing import Any, Iterator

__all__ = ["one_thread", "available_cores", "worker_count"]

_CONTROLLER: list[Any] = []  # [controller, number of modules loaded when it was built]


def _controller() -> Any:
    from threadpoolctl import ThreadpoolController

    loaded = len(sys.modules)
    if not _CONTROLLER or _CONTROLLER[1] != loaded:
        _CONTROLLER[:] = [ThreadpoolController(), loaded]
    return _CONTROLLER[0]


@contextmanager
def one_thread() -> Iterator[None]:
    """Hold every BLAS thread pool to one thread in the block."""
    with _controller().limit(limits=1, user_api="blas"):
        yield


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
