"""Small OUTDIRs following the issue 19 contract, for the report tests.

:func:`build_outdir` observes three runs of the demo campaign (size ``"ci"``), calibrates them
with a fast ``[calibration]`` block and writes every file the pipeline writes
(``pipeline.json``, ``ingest/<stem>.json``, ``spectra/<stem>.parquet``,
``observations.parquet``, ``calibration/``, ``demo_truth.json``) -- by hand, so the report is
tested against the contract and not against whatever the pipeline does today. The other helpers
derive variants from a copy: partial OUTDIRs (:func:`drop_calibration`, :func:`fail_run`,
:func:`drop_spectra`) and hostile strings (:func:`plant_hostile`).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import re
import shutil
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from rigtools import __version__
from rigtools.analysis.recording import analyse_recording
from rigtools.calibration import calibrate, write_outputs
from rigtools.campaign import load_campaign, observe_campaign, write_observations
from rigtools.campaign.manifest import Campaign, CampaignRun
from rigtools.demo.campaign import generate_demo_campaign
from rigtools.ingest import read
from rigtools.ingest.reader import versions
from rigtools.ingest.recording import Recording
from rigtools.plots.calibration import calibration_figures

__all__ = ["HOSTILE_CHANNEL", "HOSTILE_NOTES", "HOSTILE_RUN", "KEEP", "build_outdir",
           "drop_calibration", "drop_spectra", "fail_run", "file_stem", "plant_hostile"]

#: The runs kept: three temperatures across the regime flip.
KEEP = ("LS9-30C", "LS7-55C", "LS9-105C")
#: Fast calibration: enough for a posterior to show, not to converge.
CALIBRATION = {"walkers": 16, "max_steps": 2000,
               "compare_variants": ["secant_path", "tangent"]}
REPORT_BLOCK = {"title": "FZG-C demo: validation report",
                "f_n_rel_tolerance": 0.02, "f_n_z_tolerance": 3.0,
                "backlash_range_um": [2.0, 40.0], "min_margin_um": 0.0}
HOSTILE_RUN = '<script>alert(1)</script>" onerror="alert(1)'
HOSTILE_CHANNEL = '<script>alert(1)</script>acc" onerror="alert(1)'
HOSTILE_NOTES = '<img src=x onerror="alert(1)"><script>alert(1)</script>'


def file_stem(run_id: str) -> str:
    """The contract's stem of a run id (the pipeline owns the real one)."""
    digest = hashlib.sha256(run_id.encode("utf-8")).hexdigest()[:8]
    return re.sub(r"[^A-Za-z0-9._-]+", "_", run_id)[:48] + "-" + digest


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _json_dump(obj: Any, path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(obj, indent=2, allow_nan=False) + "\n", encoding="utf-8")


def _ingest_summary(run: CampaignRun, rec: Recording) -> dict[str, Any]:
    rep = rec.report
    gaps = [{"channel": g.channel, "start_s": float(g.time_s), "n_missing": int(g.n_missing)}
            for g in rep.gaps]
    return {
        "run_id": run.id, "file": run.file_as_written, "path": str(run.file),
        "source_sha256": rec.provenance.source_sha256, "reader": rec.provenance.reader,
        "format": rec.provenance.reader, "status": "ok", "error": None, "units": rep.units,
        "n_decoded": int(rep.decoded), "n_rejected": int(sum(rep.rejected.values())),
        "rejected": {str(k): int(v) for k, v in rep.rejected.items()},
        "n_gaps": len(gaps), "n_missing_samples": sum(g["n_missing"] for g in gaps),
        "gaps": gaps[:50], "gaps_truncated": len(gaps) > 50,
        "warnings": list(rep.warnings),
        "channels": {name: {"unit": ch.unit, "n_samples": len(ch.values),
                            "sample_rate_Hz": float(ch.sample_rate_Hz)}
                     for name, ch in rec.channels.items()},
        "slow_signals": sorted(rec.slow), "duration_s": float(rec.duration_s),
        "elapsed_s": 0.25,
    }


def _spectra(rec: Recording, channels: list[str]
             ) -> dict[str, tuple[np.ndarray, np.ndarray, str]]:
    """Welch spectra of ``channels`` (when the observations did not keep theirs)."""
    analysis = analyse_recording(rec, channels=channels, peaks=False)
    return {ca.name: (np.asarray(ca.spectrum.freq_Hz, dtype=float),
                      np.asarray(ca.spectrum.psd_per_Hz, dtype=float).reshape(-1),
                      f"({ca.unit})^2/Hz")
            for ca in analysis.channels.values() if ca.spectrum is not None}


def _write_spectra(spectra: dict[str, tuple[np.ndarray, np.ndarray, str]], run_id: str,
                   path: Path) -> None:
    names: list[str] = []
    freq, psd, units = [], [], {}
    for name, (f, p, unit) in spectra.items():
        names += [name] * len(f)
        freq.append(np.asarray(f, dtype=float))
        psd.append(np.asarray(p, dtype=float).reshape(-1))
        units[name] = unit
    nperseg = 2 * (len(freq[0]) - 1) if freq else None
    table = pa.table({"channel": pa.array(names, pa.string()),
                      "frequency_Hz": pa.array(np.concatenate(freq), pa.float64()),
                      "psd": pa.array(np.concatenate(psd), pa.float64())})
    meta = {"run_id": run_id, "units": units, "response": dict.fromkeys(units, "acceleration"),
            "nperseg": nperseg}
    table = table.replace_schema_metadata({b"rigtools": json.dumps(meta).encode()})
    path.parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(table, path)


def _pipeline_json(campaign: Campaign, campaign_path: Path, runs: list[dict[str, Any]]
                   ) -> dict[str, Any]:
    resolved = campaign.to_dict()
    resolved["report"] = dict(REPORT_BLOCK)
    return {
        "format": "rigtools pipeline", "rigtools_version": __version__,
        "generated_at": "2026-11-27T04:00:00+00:00",
        "campaign": {"path": str(campaign_path), "name": campaign.name,
                     "sha256": _sha256(campaign_path), "resolved": resolved},
        "settings": {"jobs": 1, "dask": None, "seed": 7},
        "runs": runs,
        "stages": {"ingest": {"key": "i" * 16, "elapsed_s": 1.5, "reused": 0, "computed": 3},
                   "observe": {"key": "o" * 16, "elapsed_s": 9.0, "reused": 0, "computed": 3},
                   "calibrate": {"key": "c" * 16, "elapsed_s": 8.0, "reused": False,
                                 "status": "ok", "error": None},
                   "report": {"elapsed_s": 0.0}},
        "versions": dict(versions()) | {"rigtools": __version__},
    }


def build_outdir(base: Path) -> Path:
    """Write a demo OUTDIR of three runs under ``base`` and return its path (``base/out``)."""
    demo = generate_demo_campaign(base / "campaign", size="ci", runup=False)
    full = load_campaign(demo.campaign_path)
    camp = dataclasses.replace(full, runs=tuple(r for r in full.runs if r.id in KEEP),
                               calibration=dict(CALIBRATION))
    out = base / "out"
    out.mkdir(parents=True, exist_ok=True)
    obs = observe_campaign(camp)
    write_observations(obs, out / "observations.parquet")
    runs = []
    for run, observed in zip(camp.runs, obs.runs, strict=True):
        stem = file_stem(run.id)
        sensors = camp.sensors_for(run)
        rec = read(run.file, dbc=sensors.dbc, mapping=sensors.mapping, fmt=sensors.format)
        _json_dump(_ingest_summary(run, rec), out / "ingest" / f"{stem}.json")
        spectra = dict(getattr(observed, "spectra", None) or {}) or _spectra(
            rec, list(sensors.accel) or list(rec.channels))
        _write_spectra(spectra, run.id, out / "spectra" / f"{stem}.parquet")
        runs.append({"run_id": run.id, "stem": stem, "file": run.file_as_written,
                     "source_sha256": rec.provenance.source_sha256, "status": "ok",
                     "error": None, "stage": None, "ingest_key": "k" * 16,
                     "observe_key": "q" * 16})
    result = calibrate(camp, obs, outdir=out / "calibration")
    write_outputs(result, out / "calibration")
    calibration_figures(result, out / "calibration")
    shutil.copyfile(demo.truth_path, out / "demo_truth.json")
    _json_dump(_pipeline_json(camp, demo.campaign_path, runs), out / "pipeline.json")
    return out


def copy_outdir(src: Path, dst: Path) -> Path:
    """A copy of an OUTDIR (without report files) to derive a variant from."""
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("report.*", "chains.h5"))
    return dst


def _edit_json(path: Path, edit: Callable[[dict[str, Any]], None]) -> None:
    doc = json.loads(path.read_text(encoding="utf-8"))
    edit(doc)
    _json_dump(doc, path)


def drop_calibration(out: Path, *, status: str = "failed") -> Path:
    """The calibration failed (or was skipped): no ``calibration/`` folder."""
    shutil.rmtree(out / "calibration", ignore_errors=True)

    def edit(doc: dict[str, Any]) -> None:
        doc["stages"]["calibrate"].update(
            status=status, error="calibration.walkers: 4 walkers for 4 free parameters"
            if status == "failed" else None)
    _edit_json(out / "pipeline.json", edit)
    return out


def fail_run(out: Path, run_id: str, error: str) -> Path:
    """``run_id`` failed at ingest: its ingest summary says so and it has no spectrum."""
    doc = json.loads((out / "pipeline.json").read_text(encoding="utf-8"))
    entry = next(r for r in doc["runs"] if r["run_id"] == run_id)
    entry.update(status="failed", error=error, stage="ingest")
    _json_dump(doc, out / "pipeline.json")
    stem = entry["stem"]
    (out / "spectra" / f"{stem}.parquet").unlink(missing_ok=True)

    def edit(ing: dict[str, Any]) -> None:
        ing.update(status="failed", error=error, n_decoded=0, channels={}, gaps=[],
                   n_gaps=0, n_missing_samples=0)
    _edit_json(out / "ingest" / f"{stem}.json", edit)
    return out


def drop_spectra(out: Path) -> Path:
    """No ``spectra/`` folder at all."""
    shutil.rmtree(out / "spectra", ignore_errors=True)
    return out


def _replace(obj: Any, subs: dict[str, str]) -> Any:
    if isinstance(obj, str):
        for old, new in subs.items():
            obj = obj.replace(old, new)
        return obj
    if isinstance(obj, dict):
        return {_replace(k, subs): _replace(v, subs) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_replace(v, subs) for v in obj]
    return obj


def _replace_meta(value: bytes, subs: dict[str, str]) -> bytes:
    try:  # JSON metadata is rewritten as JSON, so quotes in the new strings stay escaped
        return json.dumps(_replace(json.loads(value), subs)).encode("utf-8")
    except ValueError:
        return _replace(value.decode("utf-8"), subs).encode("utf-8")


def _rewrite_parquet(path: Path, subs: dict[str, str]) -> None:
    table = pq.read_table(path)
    meta = {k: _replace_meta(v, subs) for k, v in (table.schema.metadata or {}).items()}
    rows = _replace(table.to_pylist(), subs)
    new = pa.Table.from_pylist(rows, schema=table.schema.remove_metadata())
    pq.write_table(new.replace_schema_metadata(meta), path)


def plant_hostile(out: Path, run_id: str = "LS9-30C", channel: str = "accel_x") -> Path:
    """Give ``run_id``, ``channel`` and the run's notes markup, in every file of ``out``."""
    subs = {run_id: HOSTILE_RUN, channel: HOSTILE_CHANNEL}
    old_stem, new_stem = file_stem(run_id), file_stem(HOSTILE_RUN)
    for path in sorted(out.rglob("*.json")):
        doc = _replace(json.loads(path.read_text(encoding="utf-8")), subs)
        if path.name == "pipeline.json":
            for r in doc["runs"]:  # the stem was rewritten with the id: set it whole
                if r["run_id"] == HOSTILE_RUN:
                    r["stem"] = new_stem
            for r in doc["campaign"]["resolved"]["run"]:
                if r["id"] == HOSTILE_RUN:
                    r["notes"] = HOSTILE_NOTES
        _json_dump(doc, path)
    for path in sorted(out.rglob("*.parquet")):
        _rewrite_parquet(path, subs)
    for folder, suffix in (("ingest", ".json"), ("spectra", ".parquet")):
        src = out / folder / f"{old_stem}{suffix}"
        if src.exists():
            src.rename(out / folder / f"{new_stem}{suffix}")
    return out
