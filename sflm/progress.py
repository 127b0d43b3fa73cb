"""Progress display for long work on the command line (a tqdm bar on a terminal, nothing otherwise)."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from typing import Any, Callable, Iterator

__all__ = ["progress_bar", "SearchProgress", "elapsed"]


@contextmanager
def progress_bar(label: str, unit: str = "it", enabled: bool = True) -> Iterator[Callable[[int, int], None]]:
    """A callback that draws a bar on stderr when it is a terminal.

    A callback ``update(done, total)`` that draws a bar on stderr when it is a terminal.

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
        if total != bar.total:  # a search that refines: its total grows
            bar.total = total
        bar.update(done - bar.n)

    try:
        yield update
    finally:
        if bar is not None:
            bar.close()


class SearchProgress:
    """The automatic choice's progress on stderr.

    The automatic choice's progress on stderr: its one-line stages, and (on a terminal) a bar of the members evaluated
    (:func:`inversion.invert`'s ``progress``, whose ``count(done, total)`` the search calls).

    Parameters
    ----------
    label : str, optional
        The line's label.
    """

    def __init__(self, label: str = "auto") -> None:
        self._label = label
        self._bar: Any = None

    def __call__(self, message: str) -> None:
        if self._bar is not None:
            self._bar.write(message, file=sys.stderr)
        else:
            print(message, file=sys.stderr, flush=True)

    def count(self, done: int, total: int) -> None:
        """Members evaluated so far, of those known.

        Parameters
        ----------
        done : int
            Members evaluated.
        total : int
            Members known.
        """
        if not sys.stderr.isatty():
            return
        if self._bar is None:
            from tqdm import tqdm

            self._bar = tqdm(total=total, desc=self._label, unit=" members", file=sys.stderr, leave=False, dynamic_ncols=True)
        if total != self._bar.total:
            self._bar.total = total
        self._bar.update(done - self._bar.n)

    def close(self) -> None:
        """Remove the bar."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None


@contextmanager
def elapsed(label: str, enabled: bool = True, after: float = 2.0) -> Iterator[None]:
    """A seconds counter on stderr for work without steps.

    A line on stderr, when it is a terminal, that counts the seconds of work that reports no steps of its own (one solve
    of an optimal-control problem): shown from ``after`` seconds on, updated each second, removed at the end.

    Parameters
    ----------
    label : str
        The line's label.
    enabled : bool, optional
        Whether to show anything.
    after : float, optional
        Seconds before it shows.
    """
    if not (enabled and sys.stderr.isatty()):
        yield
        return
    import threading
    import time

    done = threading.Event()
    start = time.monotonic()

    def tick() -> None:
        shown = False
        while not done.wait(1.0 if shown else after):
            shown = True
            print(f"\r{label}: {time.monotonic() - start:.0f} s", end="", file=sys.stderr, flush=True)
        if shown:
            print("\r\033[K", end="", file=sys.stderr, flush=True)

    thread = threading.Thread(target=tick, daemon=True)
    thread.start()
    try:
        yield
    finally:
        done.set()
        thread.join()
