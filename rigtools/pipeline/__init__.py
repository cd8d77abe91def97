"""The pipeline of ``rigtools run``: ingest -> observe -> calibrate -> report, into one OUTDIR.

Modules: ``stems`` (:func:`run_file_stem`, the file stem of a run id), ``atomic`` (atomic
writes), ``cache`` (stage keys), ``progress`` (tqdm bars or log lines), ``executor`` (in
process, process pool, dask), ``run_tasks`` (ingest and observe of one run, sent to workers),
``stages`` (the four stages), ``runup_stage`` (the run-up part of the calibrate stage),
``result`` (:class:`PipelineResult`, ``pipeline.json``),
``errors`` and ``run`` (:func:`run_campaign`).

:func:`run_campaign` and :class:`PipelineResult` are imported on first use: a worker process
that only ingests and observes runs does not load the calibration, the figures or the report.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from rigtools.lazy_exports import lazy_exports
from rigtools.pipeline.errors import PipelineError
from rigtools.pipeline.stems import run_file_stem

if TYPE_CHECKING:
    from rigtools.pipeline.result import STAGES, PipelineResult, RunStatus
    from rigtools.pipeline.run import run_campaign

__all__ = ["STAGES", "PipelineError", "PipelineResult", "RunStatus", "run_campaign",
           "run_file_stem"]

#: Names whose modules load the calibration and the report, imported on first access.
_ON_FIRST_USE = {
    "STAGES": "rigtools.pipeline.result",
    "PipelineResult": "rigtools.pipeline.result",
    "RunStatus": "rigtools.pipeline.result",
    "run_campaign": "rigtools.pipeline.run",
}


__getattr__, __dir__ = lazy_exports(__name__, globals(), _ON_FIRST_USE, __all__)
