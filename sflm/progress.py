"""Progress display for long work on the command line (a tqdm bar on a terminal, nothing otherwise)."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from typing import Any, Callable, Iterator

__all__ = ["progress_bar"]


@contextmanager
def progress_bar(label: str, unit: str = "it", enabled: bool = True) -> Iterator[Callable[[int, int], None]]:
    """A callback ``update(done, total)`` that draws a bar on stderr when it is a terminal.

    Parameters
    ----------
    label : str
        Shown before the bar.
    unit : str
        What is counted.
    enabled : bool
        ``False`` gives a silent callback (e.g. with ``--json``).
    """
    if not (enabled and sys.stderr.isatty()):
        yield lambda done, total: None
        return
    from tqdm import tqdm

    bar: Any = None

    def update(done: int, total: int) -> None:
        nonlocal bar
        if bar is None:
            bar = tqdm(total=total, desc=label, unit=f" {unit}", file=sys.stderr, leave=False, dynamic_ncols=True)
        bar.update(done - bar.n)

    try:
        yield update
    finally:
        if bar is not None:
            bar.close()
