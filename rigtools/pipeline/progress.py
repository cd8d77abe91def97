"""Progress of the pipeline's stages: tqdm bars on a terminal, log lines otherwise.

:class:`Progress` hands out one :class:`StageProgress` per stage. With bars (stderr is a
terminal, or asked for), each stage gets a tqdm bar on stderr: ingest counts bytes of the
files read, observe counts runs, calibration counts sampler steps with the current
autocorrelation time in the postfix. Without bars, every run, and every tenth of the step cap
or 10 s of sampling (:data:`STEP_LOG_INTERVAL_S`), is one ``logging`` line on the
``rigtools.pipeline`` logger (INFO), which the command line prints on stderr unless
``--quiet``; ``--verbose`` adds the DEBUG lines (cache decisions, keys).
"""

from __future__ import annotations

import logging
import sys
import time
from typing import Any, Final

from tqdm import tqdm

__all__ = ["LOGGER_NAME", "Progress", "StageProgress", "stderr_is_terminal"]

#: Least time between two sampler-progress log lines (s); bars update at every check.
STEP_LOG_INTERVAL_S: Final = 10.0
#: The logger every pipeline line goes to.
LOGGER_NAME: Final = "rigtools.pipeline"
_log = logging.getLogger(LOGGER_NAME)


def stderr_is_terminal() -> bool:
    """Whether stderr is a terminal (bars) rather than a file or a pipe (log lines)."""
    try:
        return sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced or closed stream
        return False


class StageProgress:
    """Progress of one stage: a tqdm bar, or a log line per update.

    Parameters
    ----------
    stage : str
        Shown before every line or on the bar.
    total : int
        Units of work (runs, bytes, steps).
    unit : str
        ``"run"``, ``"B"`` (bytes, scaled to kB/MB on the bar) or ``"step"``.
    bars : bool
        A tqdm bar (True) or log lines (False).
    items : int, optional
        Items behind ``total`` when it counts something else (files behind bytes): the log
        lines count items.
    """

    def __init__(self, stage: str, total: int, *, unit: str = "run", bars: bool,
                 items: int | None = None) -> None:
        self.stage = stage
        self.total = int(total)
        self.items = self.total if items is None else int(items)
        self.done_items = 0
        self._last_line = time.monotonic()
        self._next_step_line = 0
        self._bar: Any = None
        if bars:
            self._bar = tqdm(total=self.total, desc=stage, unit=unit,
                             unit_scale=unit == "B", unit_divisor=1024 if unit == "B" else 1000,
                             file=sys.stderr, leave=True, dynamic_ncols=True)

    def advance(self, n: int = 1, *, label: str = "", item: bool = True) -> None:
        """Record ``n`` units done (and one item, unless ``item`` is False).

        Parameters
        ----------
        n : int
            Units (bytes, runs) done.
        label : str
            What was done (a run id and its outcome), for the log line.
        item : bool
            Count one item in the log line's ``[k/n]``.
        """
        if item:
            self.done_items += 1
        if self._bar is not None:
            self._bar.update(n)
            if label:
                self._bar.set_postfix_str(label[:40], refresh=True)
        else:
            _log.info("%s [%d/%d] %s", self.stage, self.done_items, self.items, label)

    def steps(self, step: int, total: int, tau: float | None) -> None:
        """Sampler progress: ``step`` of ``total`` steps, ``tau`` the current estimate."""
        tau_text = "tau n/a" if tau is None else f"tau {tau:.1f}"
        if self._bar is not None:
            if self._bar.total != total:
                self._bar.total = total
            self._bar.n = min(step, total)
            self._bar.set_postfix_str(tau_text, refresh=True)
        elif (step >= total or step >= self._next_step_line
              or time.monotonic() - self._last_line >= STEP_LOG_INTERVAL_S):
            # a line per tenth of the step cap or every few seconds, not at every convergence
            # check (a log file is read by a person)
            self._last_line = time.monotonic()
            self._next_step_line = (step // max(1, total // 10) + 1) * max(1, total // 10)
            _log.info("%s: step %d/%d (%s)", self.stage, step, total, tau_text)

    def note(self, message: str) -> None:
        """A line about the stage (above the bar, or an INFO log line)."""
        if self._bar is not None:
            self._bar.write(f"{self.stage}: {message}", file=sys.stderr)
        else:
            _log.info("%s: %s", self.stage, message)

    def close(self) -> None:
        """End the bar (a no-op for log lines)."""
        if self._bar is not None:
            self._bar.close()
            self._bar = None

    def __enter__(self) -> StageProgress:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class Progress:
    """Hands out the progress of each stage.

    Parameters
    ----------
    bars : bool or None
        tqdm bars (True), log lines (False), or bars when stderr is a terminal (None).
    """

    def __init__(self, bars: bool | None = None) -> None:
        self.bars = stderr_is_terminal() if bars is None else bool(bars)

    def stage(self, name: str, total: int, *, unit: str = "run",
              items: int | None = None) -> StageProgress:
        """The progress of stage ``name`` (module notes)."""
        return StageProgress(name, total, unit=unit, bars=self.bars, items=items)

    def debug(self, message: str, *args: object) -> None:
        """A DEBUG line (cache decisions)."""
        _log.debug(message, *args)

    def info(self, message: str, *args: object) -> None:
        """An INFO line."""
        _log.info(message, *args)
