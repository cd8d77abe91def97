"""The validation report: ``report.json`` and a self-contained ``report.html`` from an OUTDIR.

Modules: ``inputs`` (the stage files read into plain dataclasses), ``content`` (data quality,
runs, provenance, and the assembled report.json document), ``assessment`` (the calibration
judged against the campaign's checks: verdict, model versus experiment, convergence, truth
comparison), ``runup_section`` (the run-up calibration of the SDOF models: its files and its
section), ``values`` (stage-JSON values turned into report values), ``figures``
(matplotlib figures drawn from the content), ``html`` (the jinja2 page, autoescaped), ``atomic``
(temporary file, fsync, rename), ``build`` (:func:`build_report`), ``errors``.
"""

from rigtools.report.build import REPORT_HTML, REPORT_JSON, ReportPaths, build_report
from rigtools.report.content import report_content
from rigtools.report.errors import ReportInputError
from rigtools.report.inputs import ReportInputs, read_inputs

__all__ = [
    "REPORT_HTML",
    "REPORT_JSON",
    "ReportInputError",
    "ReportInputs",
    "ReportPaths",
    "build_report",
    "read_inputs",
    "report_content",
]
