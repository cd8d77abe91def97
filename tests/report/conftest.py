"""Fixtures of the report tests: one demo OUTDIR per session, copies to derive variants from."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
import report_cases

from rigtools.report import ReportPaths, build_report


@pytest.fixture(scope="session")
def demo_outdir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A complete OUTDIR of three demo runs (built once; copy it before changing it)."""
    return report_cases.build_outdir(tmp_path_factory.mktemp("report-demo"))


@pytest.fixture(scope="session")
def demo_report(demo_outdir: Path, tmp_path_factory: pytest.TempPathFactory) -> ReportPaths:
    """The report of a copy of the demo OUTDIR."""
    out = report_cases.copy_outdir(demo_outdir, tmp_path_factory.mktemp("report-built") / "out")
    return build_report(out)


@pytest.fixture
def outdir_copy(demo_outdir: Path, tmp_path: Path) -> Path:
    """A fresh copy of the demo OUTDIR for one test."""
    return report_cases.copy_outdir(demo_outdir, tmp_path / "out")


@pytest.fixture
def bare_outdir(tmp_path: Path) -> Path:
    """An OUTDIR holding only a pipeline.json whose calibration failed (fast to report)."""
    out = tmp_path / "bare"
    out.mkdir()
    doc = {"format": "rigtools pipeline", "rigtools_version": "0.1.0",
           "generated_at": "2026-11-27T04:00:00+00:00",
           "campaign": {"path": "c.toml", "name": "bare", "sha256": "0" * 64,
                        "resolved": {"campaign": {"name": "bare"}, "run": []}},
           "settings": {"jobs": 1, "dask": None, "seed": None},
           "runs": [{"run_id": "R1", "stem": report_cases.file_stem("R1"), "file": "r1.blf",
                     "source_sha256": None, "status": "failed", "stage": "ingest",
                     "error": "r1.blf: expected a recording file, found no such file",
                     "ingest_key": "a", "observe_key": "b"}],
           "stages": {"calibrate": {"key": "", "elapsed_s": 0.0, "reused": False,
                                    "status": "failed", "error": "no usable run"}},
           "versions": {"python": "3"}}
    (out / "pipeline.json").write_text(json.dumps(doc), encoding="utf-8")
    return out
