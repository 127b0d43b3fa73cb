"""One BLAS thread around the skinny products of the numerics.

The products of the numerics are tall and thin (``(N, 12) @ (12, 6)``, many ``(r, r)``
solves, a fit's small eigenproblems): a BLAS pool of threads only spins on them. On two
cores the default pools of NumPy and SciPy made 1e6 samples 1.2 s against 0.3 s on one
thread, and a calibration's model evaluation 11.6 ms against 4.7 ms. :func:`one_thread`
holds every BLAS pool loaded in the process to one thread for the duration of a block.

The pools are found once (:class:`threadpoolctl.ThreadpoolController` costs ~5 ms),
then limiting and restoring costs ~30 us. A library loaded after the first call (SciPy's
own BLAS, imported lazily) is picked up at the next call.
"""

from __future__ import annotations

import sys
from contextlib import contextmanager
from typing import Any, Iterator

__all__ = ["one_thread"]

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
