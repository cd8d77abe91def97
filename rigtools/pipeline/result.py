"""What a pipeline run did: per run, per stage, and ``pipeline.json`` (issue 19 contract).

``pipeline.json`` is what the report reads to know the runs, their stems and outcomes, the
stages and the settings. Its fields named ``generated_at`` or ending in ``elapsed_s`` are
volatile; everything else is the same between a cold run and a re-run with nothing changed
apart from the ``reused`` / ``computed`` counts, which say what the re-run reused.
"""

from __future__ import annotations

import datetime as dt
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final, Literal

from rigtools import __version__
from rigtools.campaign import Campaign

__all__ = ["PIPELINE_FILE", "STAGES", "PipelineResult", "RunStatus", "pipeline_document"]

#: The pipeline's own file in OUTDIR.
PIPELINE_FILE: Final = "pipeline.json"
#: The stages, in order.
STAGES: Final = ("ingest", "observe", "calibrate", "report")


@dataclass(frozen=True)
class RunStatus:
    """The outcome of one run.

    Attributes
    ----------
    run_id, stem : str
        The id as written and its file stem (:func:`~rigtools.pipeline.run_file_stem`).
    file : str
        The recording as written in the campaign.
    source_sha256 : str or None
        None when the file could not be read.
    status : {'ok', 'failed'}
    error : str or None
        Why it failed, naming the file.
    stage : {'ingest', 'observe'} or None
        The stage it failed in.
    ingest_key, observe_key : str
    """

    run_id: str
    stem: str
    file: str
    source_sha256: str | None
    status: Literal["ok", "failed"]
    error: str | None
    stage: Literal["ingest", "observe"] | None
    ingest_key: str
    observe_key: str

    def to_dict(self) -> dict[str, Any]:
        """The run's entry of ``pipeline.json``."""
        return {"run_id": self.run_id, "stem": self.stem, "file": self.file,
                "source_sha256": self.source_sha256, "status": self.status,
                "error": self.error, "stage": self.stage, "ingest_key": self.ingest_key,
                "observe_key": self.observe_key}


@dataclass(frozen=True)
class PipelineResult:
    """What :func:`~rigtools.pipeline.run_campaign` did.

    Attributes
    ----------
    outdir : pathlib.Path
    runs : tuple of RunStatus
        In campaign order.
    stages : dict
        The ``stages`` object of ``pipeline.json`` (keys, times, reuse, calibration status).
    summary : dict or None
        ``calibration/summary.json`` when the calibration is ok.
    report : pathlib.Path or None
        ``report.html`` when the report stage ran.
    pipeline_json : pathlib.Path
    warnings : tuple of str
        The calibration's warnings.
    """

    outdir: Path
    runs: tuple[RunStatus, ...]
    stages: dict[str, dict[str, Any]]
    summary: dict[str, Any] | None
    report: Path | None
    pipeline_json: Path
    warnings: tuple[str, ...] = field(default=())

    @property
    def failed_runs(self) -> tuple[RunStatus, ...]:
        """Runs that could not be read or analysed."""
        return tuple(r for r in self.runs if r.status == "failed")

    @property
    def all_failed(self) -> bool:
        """No run could be read and analysed."""
        return not any(r.status == "ok" for r in self.runs)

    @property
    def calibration_status(self) -> str:
        """``"ok"``, ``"failed"`` or ``"skipped"``."""
        return str(self.stages.get("calibrate", {}).get("status", "skipped"))

    @property
    def calibration_error(self) -> str | None:
        """Why the calibration failed or was skipped."""
        return self.stages.get("calibrate", {}).get("error")


def pipeline_document(campaign: Campaign, campaign_sha256: str, settings: dict[str, Any],
                      runs: tuple[RunStatus, ...], stages: dict[str, dict[str, Any]],
                      versions: dict[str, str]) -> dict[str, Any]:
    """The content of ``pipeline.json`` (issue 19 contract).

    Parameters
    ----------
    campaign : Campaign
    campaign_sha256 : str
        SHA-256 of the campaign file.
    settings : dict
        ``jobs``, ``dask``, ``seed``.
    runs : tuple of RunStatus
    stages : dict
    versions : dict
        Python, rigtools and library versions.

    Returns
    -------
    dict
        JSON-ready.
    """
    now = dt.datetime.now(dt.UTC).replace(microsecond=0)
    return {
        "format": "rigtools pipeline",
        "rigtools_version": __version__,
        "generated_at": now.isoformat().replace("+00:00", "Z"),
        "campaign": {"path": str(campaign.path), "name": campaign.name,
                     "sha256": campaign_sha256, "resolved": campaign.to_dict()},
        "settings": dict(settings),
        "runs": [r.to_dict() for r in runs],
        "stages": stages,
        "versions": dict(versions),
    }
