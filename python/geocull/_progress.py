"""Progress of long work: scene builds, benchmark runs, parameter sweeps.

Every ``progress=`` argument takes the same values (:data:`ProgressLike`):

- ``None`` (the default): shown in notebooks (an IPython kernel is running) for work that lasts
  more than :data:`AUTO_DELAY` seconds, silent in scripts;
- ``True``: a bar, tqdm's when tqdm is installed (``tqdm.auto``: a widget in notebooks), else a
  plain text bar on stderr; ``False``: nothing;
- a callable ``f(fraction: float, message: str)``: called with fractions in [0, 1] that never
  decrease, the first 0.0 and the last exactly 1.0 (when the work finishes; an error or Ctrl-C
  ends it without the 1.0).

Work that runs in the Rust core (the tiles of ``Scene.add_heightfield`` / ``add_mesh``) reports
through :class:`Task`: a task entered on this thread is what the binding finds (``_active``) and
calls from its polling loop, on this thread with the GIL held, with the count of tiles finished.
"""

from __future__ import annotations

import contextvars
import sys
import time
from collections.abc import Callable
from types import TracebackType
from typing import Any, TextIO

__all__ = ["ProgressLike", "ProgressFn", "Task", "task", "resolve", "in_notebook"]

#: A progress callback: ``f(fraction, message)``.
ProgressFn = Callable[[float, str], None]
#: What ``progress=`` accepts.
ProgressLike = bool | ProgressFn | None

_ACTIVE: contextvars.ContextVar[Task | None] = contextvars.ContextVar("geocull_progress", default=None)


def in_notebook() -> bool:
    """True inside a Jupyter (IPython kernel) session. IPython is only looked at when it is
    already imported, so scripts never import it."""
    ipy = sys.modules.get("IPython")
    if ipy is None:
        return False
    try:
        shell = ipy.get_ipython()
    except Exception:
        return False
    return shell is not None and hasattr(shell, "kernel")


class _TextBar:
    """A one-line bar on a text stream (stderr), redrawn in place; nothing is drawn before
    ``delay`` seconds have passed (so that short work stays quiet)."""

    def __init__(self, stream: TextIO | None = None, width: int = 30, delay: float = 0.0) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.start = time.perf_counter() + delay
        self.drawn = False

    def __call__(self, fraction: float, message: str) -> None:
        if time.perf_counter() < self.start and not (self.drawn and fraction >= 1.0):
            return
        if fraction >= 1.0 and not self.drawn:
            return
        self.drawn = True
        n = int(round(fraction * self.width))
        end = "\n" if fraction >= 1.0 else ""
        self.stream.write(f"\r[{'#' * n}{' ' * (self.width - n)}] {fraction * 100:5.1f}% {message[:60]:<60}{end}")
        self.stream.flush()


class _TqdmBar:
    """tqdm (``tqdm.auto``: a widget in notebooks) driven by fractions, in thousandths."""

    def __init__(self, tqdm_cls: Any, delay: float = 0.0) -> None:
        self.bar = tqdm_cls(total=1000, bar_format="{l_bar}{bar}| {elapsed}<{remaining}", leave=True, delay=delay)
        self.n = 0

    def __call__(self, fraction: float, message: str) -> None:
        k = int(round(fraction * 1000))
        if message:
            self.bar.set_description_str(message[:60], refresh=False)
        if k > self.n:  # tqdm redraws (and, past its delay, first shows the bar) on update
            self.bar.update(k - self.n)
            self.n = k
        if fraction >= 1.0:
            self.bar.close()


def _bar(delay: float = 0.0) -> ProgressFn:
    try:
        from tqdm.auto import tqdm
    except ImportError:
        return _TextBar(delay=delay)
    return _TqdmBar(tqdm, delay)


#: Seconds before the bar of ``progress=None`` in a notebook appears (short work shows none).
AUTO_DELAY = 1.0


def resolve(progress: ProgressLike) -> ProgressFn | None:
    """The callback ``progress`` stands for (see the module's docstring), or None for silence.
    ``True`` makes a new bar on each call."""
    if progress is None:
        return _bar(AUTO_DELAY) if in_notebook() else None
    if progress is False:
        return None
    if progress is True:
        return _bar()
    if callable(progress):
        return progress
    from ._errors import InputError

    raise InputError(f"progress: expected None, True, False or a callable f(fraction, message), got {progress!r}")


class Task:
    """One piece of work that reports progress: ``total`` units (> 0), advanced by :meth:`advance`
    or set by :meth:`update`; fractions are clamped to [0, 1), never go down, and reach exactly 1.0
    when the ``with`` block ends without an error. As a context manager it is also the task that
    the Rust core's builds report their tile counts to (:func:`_active`)."""

    def __init__(self, progress: ProgressLike, total: float, message: str = "") -> None:
        self.fn = resolve(progress)
        self.total = float(total) if total and total > 0 else 1.0
        self.message = message
        self.done = 0.0
        self.last = -1.0
        self._token: contextvars.Token[Task | None] | None = None

    @property
    def enabled(self) -> bool:
        return self.fn is not None

    def _emit(self, fraction: float, message: str | None) -> None:
        if self.fn is None:
            return
        changed = message is not None and message != self.message
        if message is not None:
            self.message = message
        if fraction > self.last or changed:
            self.last = max(fraction, self.last)
            self.fn(self.last, self.message)

    def update(self, done: float, message: str | None = None) -> None:
        """``done`` units of ``total`` finished (a lower value than before is ignored)."""
        self.done = max(self.done, float(done))
        self._emit(min(self.done / self.total, 0.999999), message)

    def advance(self, n: float = 1.0, message: str | None = None) -> None:
        """``n`` more units finished."""
        self.update(self.done + n, message)

    def __call__(self, done: int, total: int = 0) -> None:
        """The core's report: ``done`` tiles finished of ``total`` (called from its polling
        loop; ``total`` 0 = not known there, this task's own total stands; else it replaces it:
        an isosurface's tiles are only known once it is extracted)."""
        if total > 0:
            self.total = float(total)
        self.update(done)

    def __enter__(self) -> Task:
        self._token = _ACTIVE.set(self)
        self._emit(0.0, None)
        return self

    def __exit__(
        self, et: type[BaseException] | None, e: BaseException | None, tb: TracebackType | None
    ) -> None:
        if self._token is not None:
            _ACTIVE.reset(self._token)
            self._token = None
        if et is None and self.fn is not None and self.last < 1.0:
            self.last = 1.0
            self.fn(1.0, self.message)


def task(progress: ProgressLike, total: float, message: str = "") -> Task:
    """A :class:`Task` (``with task(progress, n, "building") as t: ... t.advance()``)."""
    return Task(progress, total, message)


def _active() -> Task | None:
    """The task entered on this thread (context), if any and if it shows anything: what the Rust
    binding reports build progress to."""
    t = _ACTIVE.get()
    return t if t is not None and t.enabled else None
