"""Read the files of an OUTDIR into plain dataclasses, and nothing else.

The report reads only what the stages wrote (issue 19 contract): ``pipeline.json``,
``ingest/<stem>.json``, ``spectra/<stem>.parquet``, ``observations.parquet``,
``calibration/summary.json`` and its PNGs, ``demo_truth.json``. Stems come from
``pipeline.json``; the report never recomputes them.

What is missing is not an error: it becomes ``None`` (or an absent key) and a line in
:attr:`ReportInputs.notes`, and the report says so. A JSON file that is present but malformed
is an error (:class:`~rigtools.report.errors.ReportInputError`, naming the file, line and
column). A Parquet file that cannot be read is noted and left out (one damaged spectrum does not
hide the rest of the report). Nothing is unpickled or executed: JSON is parsed, Parquet read
with pyarrow, PNGs kept as bytes after their signature is checked.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from rigtools.report.errors import ReportInputError

__all__ = [
    "CALIBRATION_FIGURES",
    "ReportInputs",
    "RunSpectra",
    "read_inputs",
    "read_json_object",
    "run_list",
]

#: The calibration figures the report embeds, in page order (``calibration/<name>.png``).
CALIBRATION_FIGURES: Final = ("f_n_vs_torque", "stiffness_vs_torque", "corner", "traces")
_PNG_SIGNATURE: Final = b"\x89PNG\r\n\x1a\n"
#: A stem as the pipeline writes it; anything else could point outside OUTDIR.
_STEM: Final = re.compile(r"[A-Za-z0-9_-][A-Za-z0-9._-]{0,80}")
#: Largest figure embedded (bytes); a bigger file is noted and left out.
_MAX_FIGURE_BYTES: Final = 20 * 1024 * 1024


@dataclass(frozen=True)
class RunSpectra:
    """The Welch spectra of one run (``spectra/<stem>.parquet``, long format).

    Attributes
    ----------
    channels : dict of str to (numpy.ndarray, numpy.ndarray)
        Channel -> (frequency (Hz), one-sided PSD (unit^2/Hz)), in file order.
    units : dict of str to str
        Channel -> PSD unit, from the file's ``rigtools`` metadata.
    nperseg : int or None
        Welch window length (samples).
    """

    channels: dict[str, tuple[np.ndarray, np.ndarray]]
    units: dict[str, str] = field(default_factory=dict)
    nperseg: int | None = None


@dataclass(frozen=True)
class ReportInputs:
    """Everything the report reads from an OUTDIR.

    Attributes
    ----------
    outdir : pathlib.Path
    pipeline : dict or None
        ``pipeline.json``.
    ingest : dict of str to dict
        Run id -> ``ingest/<stem>.json`` (runs whose file is absent are not keys).
    spectra : dict of str to RunSpectra
        Run id -> spectra (runs without a readable file are not keys).
    observations : list of dict or None
        Rows of ``observations.parquet`` (column -> value, NaN as None).
    summary : dict or None
        ``calibration/summary.json``.
    figures : dict of str to bytes
        Calibration figure name -> PNG bytes (:data:`CALIBRATION_FIGURES`).
    truth : dict or None
        ``demo_truth.json`` (the demo only).
    notes : tuple of str
        What is absent or unreadable, one sentence each.
    """

    outdir: Path
    pipeline: dict[str, Any] | None
    ingest: dict[str, dict[str, Any]]
    spectra: dict[str, RunSpectra]
    observations: list[dict[str, Any]] | None
    summary: dict[str, Any] | None
    figures: dict[str, bytes]
    truth: dict[str, Any] | None
    notes: tuple[str, ...] = ()


def read_json_object(path: Path) -> dict[str, Any] | None:
    """A JSON object from ``path``; None when the file does not exist.

    Raises
    ------
    ReportInputError
        The file is not UTF-8, not JSON, or not an object (file, line and column named).
    """
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        return None
    except IsADirectoryError:
        raise ReportInputError(path, None, "a JSON file", "a directory") from None
    except UnicodeDecodeError as exc:
        raise ReportInputError(path, exc.start, "UTF-8 text",
                               f"the byte {exc.object[exc.start]:#04x}") from None
    try:
        obj = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ReportInputError(path, f"line {exc.lineno} column {exc.colno}", "valid JSON",
                               repr(exc.msg)) from None
    if not isinstance(obj, dict):
        raise ReportInputError(path, None, "a JSON object", f"a JSON {type(obj).__name__}")
    return obj


def _cell(v: Any) -> Any:
    if isinstance(v, float) and not math.isfinite(v):
        return None
    return v


def _read_observations(path: Path, notes: list[str]) -> list[dict[str, Any]] | None:
    if not path.is_file():
        notes.append("observations.parquet is absent: no peaks are listed")
        return None
    try:
        table = pq.read_table(path)
    except (pa.ArrowException, OSError) as exc:
        notes.append(f"observations.parquet is unreadable ({exc}): no peaks are listed")
        return None
    return [{k: _cell(v) for k, v in row.items()} for row in table.to_pylist()]


def _read_spectra(path: Path, run_id: str, notes: list[str], *, expected: bool
                  ) -> RunSpectra | None:
    name = f"spectra/{path.name}"
    if not path.is_file():
        if expected:
            notes.append(f"run {run_id!r}: no spectrum file ({name})")
        return None
    try:
        table = pq.read_table(path)
    except (pa.ArrowException, OSError) as exc:
        notes.append(f"run {run_id!r}: {name} is unreadable ({exc})")
        return None
    cols = set(table.column_names)
    if not {"channel", "frequency_Hz", "psd"} <= cols:
        notes.append(f"run {run_id!r}: {name} lacks the columns channel, frequency_Hz, psd "
                     f"(found {sorted(cols)})")
        return None
    meta: dict[str, Any] = {}
    raw = (table.schema.metadata or {}).get(b"rigtools")
    if raw is not None:
        try:
            loaded = json.loads(raw)
            meta = loaded if isinstance(loaded, dict) else {}
        except (json.JSONDecodeError, UnicodeDecodeError):
            notes.append(f"run {run_id!r}: {name} has malformed 'rigtools' metadata (ignored)")
    channel = [str(c) for c in table.column("channel").to_pylist()]
    freq = np.asarray(table.column("frequency_Hz").to_numpy(zero_copy_only=False), dtype=float)
    psd = np.asarray(table.column("psd").to_numpy(zero_copy_only=False), dtype=float)
    out: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    names = np.asarray(channel, dtype=object)
    for ch in dict.fromkeys(channel):
        sel = names == ch
        order = np.argsort(freq[sel], kind="stable")
        out[ch] = (freq[sel][order], psd[sel][order])
    units = meta.get("units") if isinstance(meta.get("units"), dict) else {}
    nperseg = meta.get("nperseg")
    return RunSpectra(channels=out, units={str(k): str(v) for k, v in (units or {}).items()},
                      nperseg=int(nperseg) if isinstance(nperseg, int) else None)


def _read_figures(folder: Path, notes: list[str]) -> dict[str, bytes]:
    figs: dict[str, bytes] = {}
    for name in CALIBRATION_FIGURES:
        p = folder / f"{name}.png"
        if not p.is_file():
            continue
        if p.stat().st_size > _MAX_FIGURE_BYTES:
            notes.append(f"calibration/{name}.png is larger than {_MAX_FIGURE_BYTES} bytes: "
                         "not embedded")
            continue
        data = p.read_bytes()
        if not data.startswith(_PNG_SIGNATURE):
            notes.append(f"calibration/{name}.png is not a PNG file: not embedded")
            continue
        figs[name] = data
    return figs


def run_list(pipeline: dict[str, Any] | None, summary: dict[str, Any] | None,
             observations: list[dict[str, Any]] | None) -> list[dict[str, Any]]:
    """The runs in campaign order: ``pipeline.json`` runs, else those the other files name.

    Each entry has at least ``run_id`` (and ``stem`` when the pipeline gave a usable one).
    """
    runs: list[dict[str, Any]] = []
    if pipeline is not None and isinstance(pipeline.get("runs"), list):
        runs = [dict(r) for r in pipeline["runs"] if isinstance(r, dict)
                and isinstance(r.get("run_id"), str)]
    seen = {r["run_id"] for r in runs}
    extra: list[str] = []
    if summary is not None and isinstance(summary.get("runs"), dict):
        extra += [str(k) for k in summary["runs"]]
    for row in observations or []:
        if row.get("quantity") == "run" and isinstance(row.get("run_id"), str):
            extra.append(row["run_id"])
    for rid in dict.fromkeys(extra):
        if rid not in seen:
            runs.append({"run_id": rid})
            seen.add(rid)
    return runs


def read_inputs(outdir: str | Path) -> ReportInputs:
    """Read every file of ``outdir`` the report uses.

    Parameters
    ----------
    outdir : str or pathlib.Path

    Returns
    -------
    ReportInputs

    Raises
    ------
    ReportInputError
        A JSON file present but malformed, or ``outdir`` not a folder.
    """
    base = Path(outdir)
    if not base.is_dir():
        raise ReportInputError(base, None, "an OUTDIR folder",
                               "a file" if base.exists() else "nothing")
    notes: list[str] = []
    pipeline = read_json_object(base / "pipeline.json")
    if pipeline is None:
        notes.append("pipeline.json is absent: no data quality or provenance from the pipeline")
    summary = read_json_object(base / "calibration" / "summary.json")
    truth = read_json_object(base / "demo_truth.json")
    observations = _read_observations(base / "observations.parquet", notes)
    ingest: dict[str, dict[str, Any]] = {}
    spectra: dict[str, RunSpectra] = {}
    for run in run_list(pipeline, summary, observations):
        rid, stem = run["run_id"], run.get("stem")
        if not isinstance(stem, str):
            continue
        if not _STEM.fullmatch(stem) or stem in {".", ".."}:
            notes.append(f"run {rid!r}: pipeline.json gives the stem {stem!r}, which is not a "
                         "plain file name: its files are not read")
            continue
        ing = read_json_object(base / "ingest" / f"{stem}.json")
        if ing is None:
            notes.append(f"run {rid!r}: no ingest summary (ingest/{stem}.json)")
        else:
            ingest[rid] = ing
        sp = _read_spectra(base / "spectra" / f"{stem}.parquet", rid, notes,
                           expected=run.get("status") != "failed")
        if sp is not None:
            spectra[rid] = sp
    figures = _read_figures(base / "calibration", notes) if summary is not None else {}
    return ReportInputs(outdir=base, pipeline=pipeline, ingest=ingest, spectra=spectra,
                        observations=observations, summary=summary, figures=figures,
                        truth=truth, notes=tuple(notes))
