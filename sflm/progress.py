"""Progress of long work on the command line: a tqdm bar on a terminal, plain lines otherwise, nothing when quiet."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from typing import Any, Callable, Iterator

from .formatting import printable

__all__ = ["Reporter"]


class Reporter:
    """One command's progress on stderr.

    Nothing for the command's first ``after`` seconds (a quick command, a quick refusal, prints only its answer); then
    its stage -- the library's latest one-line message (:func:`inversion.invert`'s ``progress``), with the members or
    rows counted so far where a stage counts them -- and the seconds elapsed, at least every ``every`` seconds however
    long one solve takes (a thread keeps time: the solvers release the interpreter). On a terminal it is one tqdm bar,
    redrawn in place; otherwise plain lines. ``enabled=False`` (``--quiet``) says nothing.

    Parameters
    ----------
    command : str
        The command (``invert``), the lines' prefix.
    enabled : bool, optional
        Whether to say anything.
    after, every : float, optional
        Seconds before the first report, and at most between two.
    stream : file, optional
        Where to write (default ``sys.stderr``).
    start : float, optional
        When the command started (:func:`time.monotonic`; default: now): the seconds shown count from it (the quiet
        first ``after`` seconds from the reporter's making, so that a quick refusal after slow imports is one line).
    """

    def __init__(self, command: str, enabled: bool = True, after: float = 2.0, every: float = 5.0, stream: Any = None,
                 start: float | None = None) -> None:
        import threading
        import time

        self._clock = time.monotonic
        self._opened = self._clock()  # the quiet first `after` seconds count from here: a quick refusal stays one line
        self._start = self._opened if start is None else float(start)  # the seconds shown count from the command's start
        self._command, self._enabled, self._after, self._every = command, enabled, after, every
        self._stream = sys.stderr if stream is None else stream
        self._stage = "working"
        self._counts: tuple[int, int, str] | None = None
        self._said = -1.0  # when the last line was written (-1: never)
        self._lock = threading.Lock()
        self._done = threading.Event()
        self._bar: Any = None
        self._thread: Any = None
        if enabled:
            self._thread = threading.Thread(target=self._keep_time, daemon=True)
            self._thread.start()

    @property
    def terminal(self) -> bool:
        """Whether the stream is a terminal (a bar) or not (lines)."""
        return bool(getattr(self._stream, "isatty", lambda: False)())

    def __call__(self, message: str) -> None:
        """A new stage (a one-line message of the library's)."""
        with self._lock:
            self._stage = printable(" ".join(str(message).split()))
            self._counts = None
            if self._clock() - self._opened >= self._after:
                self._report()

    def count(self, done: int, total: int, unit: str = "members") -> None:
        """How far the stage is: ``done`` of ``total``.

        Members, rows, bounds: what the stage counts.

        Parameters
        ----------
        done, total : int
            Done so far, of those known.
        unit : str, optional
            What is counted.
        """
        with self._lock:
            self._counts = (int(done), int(total), unit)
            if self.terminal and self._bar is not None:
                self._report()

    @contextmanager
    def stage(self, label: str, unit: str = "it") -> Iterator[Callable[[int, int], None]]:
        """A stage that counts: its ``update(done, total)``.

        The ``progress`` of :func:`inversion.explore` and the others.

        Parameters
        ----------
        label : str
            The stage.
        unit : str, optional
            What is counted.
        """
        self(label)
        try:
            yield lambda done, total: self.count(done, total, unit)
        finally:
            with self._lock:
                self._counts = None

    def close(self) -> None:
        """Stop keeping time and remove the bar."""
        self._done.set()
        if self._thread is not None:
            self._thread.join()
        with self._lock:
            if self._bar is not None:
                self._bar.close()
                self._bar = None

    def _elapsed(self) -> float:
        return self._clock() - self._start

    def _keep_time(self) -> None:
        while not self._done.wait(0.5 if self.terminal else 0.25):
            with self._lock:
                now = self._elapsed()
                if self._clock() - self._opened < self._after:
                    continue
                if self._said < 0 or self.terminal or now - self._said >= self._every:
                    self._report()

    def _report(self) -> None:
        """Write the stage (the caller holds the lock)."""
        if not self._enabled:
            return
        now = self._elapsed()
        counted = ""
        if self._counts is not None:
            done, total, unit = self._counts
            counted = f", {done} of {total} {unit}"
        if self.terminal:
            if self._bar is None:
                from tqdm import tqdm

                self._bar = tqdm(total=None, bar_format="{desc}", file=self._stream, leave=False, dynamic_ncols=True)
            self._bar.set_description_str(f"sflm {self._command}: {self._stage}{counted} ({now:.0f} s)", refresh=True)
        else:
            print(f"sflm {self._command}: {self._stage}{counted} ({now:.0f} s)", file=self._stream, flush=True)
        self._said = now
