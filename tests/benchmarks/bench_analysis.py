"""Time the analysis of a recording against bare ``scipy.signal.welch`` on the same arrays.

The recording: 60 s, 4 accelerometer channels at 25.6 kHz (:func:`rigtools.demo.synthetic.
synthetic_run`: mesh harmonics, a damped mode, sensor noise, quantised to the reference DBC),
6.1 M samples. The analysis is :func:`rigtools.analysis.analyse_recording` with Welch
(Hann, nperseg 4096, 50 % overlap), the quality checks (validity mask, clipping, constant),
full-band RMS in the time domain and by Parseval, and the peaks with their classification,
half-power damping and SDOF fits. The baseline is one ``scipy.signal.welch`` call on the
four channels stacked ``(4, n)``, the fastest way to get the bare PSDs (four calls, one per
channel, are slower and also shown). The script prints

* the baseline times and the analysis time, and the ratio of the throughputs
  ``t_welch / t_analysis`` (target >= 0.7: the analysis costs at most ~1.4 bare Welch calls);
* the same with one extra band-limited RMS (time domain: an FFT band-pass of each channel)
  and with the channels split by 20 gaps, for information.

Run: ``python tests/benchmarks/bench_analysis.py [--duration 60] [--repeat 7]``, or
``python -m pytest tests/benchmarks/bench_analysis.py -m benchmark -s``. Timings depend on the
machine and its load; the script reports ratios, it does not assert them.
"""

from __future__ import annotations

import argparse
import gc
import sys
import time
from collections.abc import Callable
from typing import TypeVar

import numpy as np
import pytest
from scipy import signal as sps

from rigtools.analysis import analyse_recording
from rigtools.demo.synthetic import synthetic_run
from rigtools.ingest.recording import Channel, IngestReport, Provenance, Recording, RunMetadata

T = TypeVar("T")
NPERSEG = 4096
TARGET = 0.7


def _best(fn: Callable[[], T], repeat: int) -> tuple[float, T]:
    """Best of ``repeat`` timings of one call (s), after one warm-up call."""
    out = fn()
    best = float("inf")
    for _ in range(max(1, repeat)):
        gc.collect()
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def _recording(duration_s: float, n_gaps: int = 0) -> Recording:
    run = synthetic_run(duration_s=duration_s, n_channels=4, rng=1)
    fs = run.sample_rate_Hz
    chans = {}
    for name, v in run.channels.items():
        valid = np.ones(v.size, bool)
        if n_gaps:
            values = v.copy()
            for start in np.linspace(0, v.size, n_gaps + 2)[1:-1].astype(int):
                valid[start: start + 300] = False
            values[~valid] = np.nan
        else:
            values = v
        chans[name] = Channel(name, "m/s^2", fs, run.start_time_s, 0, values, valid)
    prov = Provenance("synthetic", "0" * 64, 0, "synthetic", {}, IngestReport())
    return Recording(chans, {}, RunMetadata(run_id="bench"), prov)


def run(duration_s: float = 60.0, repeat: int = 7,
        out: Callable[[str], object] = print) -> dict[str, float]:
    """Time the baselines and the analysis; print and return the figures."""
    rec = _recording(duration_s)
    fs = next(iter(rec.channels.values())).sample_rate_Hz
    arrays = [c.values for c in rec.channels.values()]
    stacked = np.stack(arrays)
    n = stacked.shape[1]
    out(f"recording: {len(arrays)} channels x {n:,} samples ({duration_s:g} s at {fs:g} Hz); "
        f"Welch Hann nperseg {NPERSEG}, 50 % overlap")
    kw = dict(mesh_frequency_Hz=400.0, shaft_frequencies_Hz=(25.0, 400.0 / 24), nperseg=NPERSEG)

    t_stack, _ = _best(lambda: sps.welch(stacked, fs, nperseg=NPERSEG), repeat)
    t_each, _ = _best(lambda: [sps.welch(a, fs, nperseg=NPERSEG) for a in arrays], repeat)
    t_ours, res = _best(lambda: analyse_recording(rec, **kw), repeat)
    n_peaks = sum(len(c.peaks.peaks) for c in res.channels.values() if c.peaks is not None)
    ratio = t_stack / t_ours
    figures = {"welch_stacked_s": t_stack, "welch_per_channel_s": t_each,
               "analysis_s": t_ours, "ratio": ratio, "ratio_per_channel": t_each / t_ours}
    out(f"{'':38}{'time ms':>10}{'Msamples/s':>12}")
    for label, t in (("scipy.signal.welch, stacked (4, n)", t_stack),
                     ("scipy.signal.welch, per channel", t_each),
                     ("analyse_recording (Welch, RMS, peaks)", t_ours)):
        out(f"{label:38}{t * 1e3:>10.1f}{4 * n / t / 1e6:>12.1f}")
    out(f"{n_peaks} peaks classified and damped over the 4 channels")
    out(f"throughput ratio analysis / bare welch (stacked): {ratio:.2f} "
        f"(per-channel welch: {t_each / t_ours:.2f}); target >= {TARGET} "
        f"({'met' if ratio >= TARGET else 'NOT met'})")

    t_band, _ = _best(lambda: analyse_recording(rec, bands_Hz=[(2000.0, 4000.0)], **kw),
                      max(1, repeat // 2))
    gapped = _recording(duration_s, n_gaps=20)
    t_gaps, gres = _best(lambda: analyse_recording(gapped, **kw), max(1, repeat // 2))
    q = next(iter(gres.channels.values())).quality
    figures |= {"ratio_with_band_rms": t_stack / t_band, "ratio_with_gaps": t_stack / t_gaps}
    out(f"with one band RMS (time domain, FFT band-pass): ratio {t_stack / t_band:.2f}")
    out(f"with 20 gaps ({q.n_segments} segments, {q.n_windows} windows per channel): "
        f"ratio {t_stack / t_gaps:.2f}")
    return figures


@pytest.mark.benchmark
def test_bench_analysis(capsys):
    """The benchmark (excluded from the default run by the ``benchmark`` marker)."""
    with capsys.disabled():
        figures = run(duration_s=60.0, repeat=5)
    assert all(v > 0 for v in figures.values())


def main(argv: list[str] | None = None) -> int:
    """Command-line entry point."""
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--duration", type=float, default=60.0, help="recording length (s)")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args(argv)
    run(args.duration, args.repeat)
    return 0


if __name__ == "__main__":
    sys.exit(main())
