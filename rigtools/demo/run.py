"""The demo job: write a synthetic run in the reference formats, ingest, inspect, analyse.

Until the demo campaign of the pipeline issue exists, this is what ``rigtools demo`` runs:

1. a synthetic run (:mod:`rigtools.demo.synthetic`) written as MCAP (protobuf batches, zstd
   chunks), Vector BLF and candump, the CAN files in the reference DBC layout;
2. each file ingested with :func:`rigtools.ingest.read`, written as a normalized Parquet
   recording and read back (exact round trip checked), its ``info`` printed;
3. the formats compared sample for sample (CAN exact; MCAP carries float32 samples, so it is
   compared with the truth rounded to float32);
4. the analysis of the ingested data (:mod:`rigtools.analysis`: Welch PSD, RMS, the structural
   mode by a single-DOF fit with uncertainties, mesh orders 1-3 and Arms by order tracking on
   the speed signal) against the known truth.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

from rigtools.analysis import analyse_recording, step_levels_from_recording
from rigtools.demo.can_writer import encode_reference_frames, write_can_log
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.demo.synthetic import SyntheticRun, synthetic_run
from rigtools.ingest import Recording, RunMetadata, read, read_parquet, write_parquet
from rigtools.recording_summary import format_info

__all__ = ["analyse_demo", "run_demo"]


def analyse_demo(rec: Recording, f_mesh: float, z1: int) -> dict[str, dict[str, float]]:
    """Per channel: RMS, the structural mode, mesh-order amplitudes A1..A3 and Arms.

    The mode is the fitted f_n and zeta with 1-sigma uncertainties; the orders come from order
    tracking on the speed signal. Uses :func:`rigtools.analysis.analyse_recording` (Welch PSD,
    peaks, single-DOF fit) and
    :func:`rigtools.analysis.step_levels_from_recording` (angular resampling on
    ``PinionSpeed_rpm``).
    """
    ra = analyse_recording(rec, mesh_frequency_Hz=f_mesh,
                           shaft_frequencies_Hz=(f_mesh / z1,))
    out: dict[str, dict[str, float]] = {}
    for name, ca in ra.channels.items():
        if ca.rms is None or ca.peaks is None:  # the channel could not be analysed
            out[name] = {}
            continue
        row: dict[str, float] = {"rms": float(ca.rms.rms_time)}
        structural = [p for p in ca.peaks.peaks if p.kind == "structural" and p.mode]
        if structural:
            m = max(structural, key=lambda p: p.psd_per_Hz).mode
            assert m is not None
            row.update(f_n_Hz=m.f_n_Hz, f_n_std_Hz=m.f_n_std_Hz, zeta=m.zeta,
                       zeta_std=m.zeta_std)
        steps = step_levels_from_recording(rec, name, "PinionSpeed_rpm", z1)
        if steps.steps:  # one speed step in the demo run: its order amplitudes and Arms
            for k, a in enumerate(np.asarray(steps.amplitude)[0, :3], 1):
                row[f"A{k}"] = float(a)
            row["Arms"] = float(np.asarray(steps.arms)[0])
        out[name] = row
    return out


def _files(run: SyntheticRun, out: Path) -> dict[str, Path]:
    out.mkdir(parents=True, exist_ok=True)
    md = RunMetadata(
        run_id=str(run.metadata["run_id"]), rig=str(run.metadata["rig"]),
        gear_set=str(run.metadata["gear_set"]),
        conditions=dict(run.metadata["conditions"]),
    )
    mcap = write_accel_mcap(
        out / "demo_run.mcap",
        {k: (v, run.sample_rate_Hz, "m/s^2", 0, run.start_time_s) for k, v in run.channels.items()},
        run.slow, md, encoding="protobuf", compression="zstd",
    )
    slow_vals = {name: vals for name, (_, vals, _) in run.slow.items()}
    frames = encode_reference_frames(
        [run.channels[f"accel_{i + 1}"] for i in range(len(run.channels))],
        slow_vals, start_time_s=run.start_time_s, rng=1,
    )
    blf = write_can_log(out / "demo_run.blf", frames, "blf", engine="rigtools")
    log = write_can_log(out / "demo_run.log", frames, "log", engine="rigtools")
    return {"mcap": mcap, "blf": blf, "candump": log}


def _compare(rec: Recording, run: SyntheticRun, exact: bool) -> float:
    worst = 0.0
    for name, truth in run.channels.items():
        ch = rec.channels[name]
        want = truth if exact else truth.astype(np.float32).astype(np.float64)
        got = ch.values[: truth.size]
        if ch.first_index != 0 or len(ch) != truth.size or not ch.valid.all():
            return float("inf")
        worst = max(worst, float(np.max(np.abs(got - want))))
    return worst


def run_demo(output: str | Path, *, duration_s: float = 4.0, seed: int = 0) -> int:
    """Run the demo job; print what it does; return the exit code (0 when all checks hold)."""
    out = Path(output)
    run = synthetic_run(duration_s, rng=seed)
    print(f"rigtools demo: synthetic run of {duration_s:g} s, {len(run.channels)} accelerometers "
          f"at {run.sample_rate_Hz:g} Hz, mesh frequency {run.truth['mesh_frequency_Hz']:g} Hz, "
          f"resonance {run.truth['f_n_Hz']:g} Hz (zeta {run.truth['zeta']:g})")
    files = _files(run, out)
    summary: dict[str, Any] = {"truth": run.truth, "formats": {}}
    ok = True
    recs = {}
    for fmt, path in files.items():
        rec = read(path)
        pq_path = write_parquet(rec, path.with_suffix(path.suffix + ".parquet"))
        same = read_parquet(pq_path).equals(rec)
        err = _compare(rec, run, exact=fmt != "mcap")
        ok &= same and err == 0.0
        recs[fmt] = rec
        print()
        print(f"== {fmt}: {path}  ->  {pq_path.name}")
        print(format_info(rec))
        print(f"parquet round trip exact: {same};  max |sample - truth| = {err:g} m/s^2")
        summary["formats"][fmt] = {"file": str(path), "parquet": str(pq_path),
                                   "round_trip_exact": same, "max_abs_error": err,
                                   "report": rec.report.to_dict()}
    rec = recs["blf"]
    print()
    print("== analysis (BLF recording): rigtools.analysis spectra, peaks, order tracking")
    print(f"{'channel':<10}{'RMS':>9}{'A1':>8}{'A2':>8}{'A3':>8}{'Arms':>8}"
          f"{'f_n Hz':>16}{'zeta':>18}")
    analysis = analyse_demo(rec, run.truth["mesh_frequency_Hz"], int(run.metadata["z1"]))
    nan = float("nan")
    for name, a in analysis.items():
        print(f"{name:<10}{a.get('rms', nan):>9.3f}{a.get('A1', nan):>8.3f}{a.get('A2', nan):>8.3f}"
              f"{a.get('A3', nan):>8.3f}{a.get('Arms', nan):>8.3f}"
              f"{a.get('f_n_Hz', nan):>9.1f} ± {a.get('f_n_std_Hz', nan):<4.1f}"
              f"{a.get('zeta', nan):>10.4f} ± {a.get('zeta_std', nan):.4f}")
    t = run.truth
    print(f"{'truth':<10}{'':>9}{t['A1']:>8.3f}{t['A2']:>8.3f}{t['A3']:>8.3f}"
          f"{math.sqrt(t['A1']**2 + t['A2']**2 + t['A3']**2):>8.3f}{t['f_n_Hz']:>9.1f}"
          f"{'':7}{t['zeta']:>10.4f}   (amplitudes scaled by 1/(1+0.3 k) on channel k+1)")
    summary["analysis"] = analysis
    (out / "summary.json").write_text(json.dumps(summary, indent=2, default=float))
    print()
    print(f"summary written to {out / 'summary.json'}")
    if not ok:
        print("rigtools demo: FAILED: formats disagree or a round trip was not exact",
              file=sys.stderr)
        return 1
    print("rigtools demo: all formats agree sample for sample; round trips exact")
    return 0
