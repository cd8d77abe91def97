"""Progress: tqdm bars on a terminal (bytes for ingest, tau for the sampler), log lines else."""

from __future__ import annotations

import io
import logging
import sys

import pytest

import rigtools.pipeline.progress as progress_module
from rigtools.pipeline.progress import LOGGER_NAME, Progress


def test_bars_count_bytes_and_show_tau(capsys: pytest.CaptureFixture[str]) -> None:
    prog = Progress(bars=True)
    with prog.stage("ingest", 3 * 1024 * 1024, unit="B", items=2) as bar:
        bar.advance(1024 * 1024, label="LS1: read")
        bar.advance(2 * 1024 * 1024, label="LS2: read")
    with prog.stage("calibrate", 400, unit="step") as bar:
        bar.steps(200, 400, 12.34)
    err = capsys.readouterr().err
    assert "ingest" in err and "3.00M/3.00M" in err
    assert "calibrate" in err and "200/400" in err and "tau 12.3" in err


def test_without_a_terminal_every_run_is_a_log_line_and_sampling_by_tenths_or_10_s(
        caplog: pytest.LogCaptureFixture, capsys: pytest.CaptureFixture[str],
        monkeypatch: pytest.MonkeyPatch) -> None:
    clock = [1000.0]
    monkeypatch.setattr(progress_module.time, "monotonic", lambda: clock[0])
    caplog.set_level(logging.INFO, logger=LOGGER_NAME)
    prog = Progress(bars=False)
    with prog.stage("ingest", 300, unit="B", items=2) as bar:
        bar.advance(100, label="LS1: read in 0.1 s")
        bar.advance(200, label="LS2: FAILED")
    with prog.stage("calibrate", 4000, unit="step") as bar:
        bar.steps(100, 4000, None)        # the first check
        bar.steps(200, 4000, 11.0)        # no line: neither a tenth of the cap nor 10 s on
        clock[0] += 10.0
        bar.steps(300, 4000, 12.34)       # 10 s on
        clock[0] += 1.0
        bar.steps(350, 4000, 12.5)        # no line
        bar.steps(400, 4000, 12.5)        # a tenth of the cap
        bar.steps(4000, 4000, 12.6)       # the last step always
    assert [r.getMessage() for r in caplog.records] == [
        "ingest [1/2] LS1: read in 0.1 s", "ingest [2/2] LS2: FAILED",
        "calibrate: step 100/4000 (tau n/a)", "calibrate: step 300/4000 (tau 12.3)",
        "calibrate: step 400/4000 (tau 12.5)", "calibrate: step 4000/4000 (tau 12.6)"]
    assert capsys.readouterr().err == ""


class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_by_default_bars_only_on_a_terminal(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert Progress().bars is False
    monkeypatch.setattr(sys, "stderr", _Terminal())
    assert Progress().bars is True
    assert Progress(bars=False).bars is False
