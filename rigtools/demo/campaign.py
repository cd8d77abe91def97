"""The built-in demo campaign: an FZG-C backlash study generated from the physics, with its truth.

:func:`generate_demo_campaign` writes into a folder everything a test engineer would bring to
rigtools, made from a known truth (:mod:`rigtools.demo.truth`):

* ``runs/``: recordings of an FZG type C pair at 1500 rpm at seed 000's torques (FZG load
  stages 1, 3, 7 and 9: 3.3, 35.3, 183.4 and 302 N m) and bulk temperatures that cross the
  regime flip (``c > c*`` at 30 and 55 degC, ``c < c*`` at 90 and 105 degC; the low torques are
  left out where they would jam). Each run's triaxial bearing-cover accelerometer sees the mesh
  mode at the natural frequency :mod:`models.thermal` gives for it, a housing mode that does
  not move, mesh harmonics with shaft-rate sidebands and sensor noise
  (:mod:`rigtools.demo.run_signals`). Half the runs are MCAP (``rigtools.AccelBatch``,
  protobuf, zstd or lz4 chunks, :func:`rigtools.demo.mcap_writer.write_accel_mcap`), half CAN
  logs (BLF and candump) of another layout than the reference DBC
  (:mod:`rigtools.demo.triax_can`), some with dropped frames;
* ``triax.dbc`` and ``triax-map.toml``: that layout and its mapping file;
* ``campaign.toml``: the campaign file (``data_schemas/campaign.schema.json``) listing every
  run with its conditions; it loads with :func:`rigtools.campaign.load_campaign` and is the
  file to edit and point at one's own recordings;
* ``truth.json``: the truth under the names of the calibration summary (``backlash``,
  ``critical_gap@<T>C``, ``margin@<run id>``, ``flip_temperature_C``, regimes ``rises`` /
  ``falls``) plus, per run, the file, format, mesh-mode frequency, which channels show the
  housing mode taller than the mesh mode, and the frames dropped.

Sizes: ``"full"`` (12 runs of 8 s, three axes at 25.6 kHz; the README's ``rigtools demo``) and
``"ci"`` (8 runs of 3 s at three temperatures, for the test suite).

The two loggers sit in one campaign as they would on a real rig: ``[sensors]`` names the
channels all runs share, and each CAN ``[[run]]`` names its own ``dbc``, ``map`` and
``format`` (the MCAP runs need none).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np

from models.geometry import load_gear_set
from models.thermal import prepare_natural_frequency
from rigtools.campaign.manifest import load_campaign
from rigtools.demo.can_writer import write_can_log
from rigtools.demo.mcap_writer import write_accel_mcap
from rigtools.demo.run_signals import RunSignals, SignalLevels, run_signals
from rigtools.demo.triax_can import (
    ACCEL_CHANNELS,
    ACCEL_LSB_M_S2,
    encode_triax_frames,
    write_triax_layout,
)
from rigtools.demo.truth import (
    CampaignTruth,
    HousingMode,
    RunCondition,
    campaign_truth,
    true_physics,
)
from rigtools.ingest import RunMetadata

__all__ = [
    "DEFAULT_DURATION_S",
    "MCAP_LSB_M_S2",
    "SIZES",
    "DemoCampaign",
    "DemoRun",
    "Size",
    "demo_conditions",
    "generate_demo_campaign",
]

Size = Literal["full", "ci"]
#: The sizes :func:`generate_demo_campaign` makes.
SIZES: Final[tuple[str, ...]] = ("full", "ci")
#: Length of each run by size (s).
DEFAULT_DURATION_S: Final[dict[str, float]] = {"full": 8.0, "ci": 3.0}
#: Step of the MCAP logger's 24-bit converter over +-50 g (m/s^2).
MCAP_LSB_M_S2: Final[float] = 100 * 9.80665 / 2**24
#: FZG load stage -> pinion torque (N m) of the stages seed 000 ran.
_LOAD_STAGES: Final[dict[int, float]] = {1: 3.3, 3: 35.3, 7: 183.4, 9: 302.0}
#: size -> bulk temperature (degC) -> FZG load stages run there.
_DESIGN: Final[dict[str, dict[float, tuple[int, ...]]]] = {
    "full": {30.0: (1, 3, 7, 9), 55.0: (1, 3, 7, 9), 90.0: (7, 9), 105.0: (7, 9)},
    "ci": {30.0: (1, 3, 9), 55.0: (1, 3, 7), 105.0: (7, 9)},
}
_SAMPLE_RATE_HZ: Final[float] = 25_600.0
_FIRST_START_S: Final[float] = 1_763_800_000.0  # logger time of the first run
_RIG: Final[str] = "FZG back-to-back rig (synthetic demo)"
Format = Literal["mcap", "blf", "candump"]


@dataclass(frozen=True)
class DemoRun:
    """One recording of the demo campaign.

    Attributes
    ----------
    run_id : str
    file : pathlib.Path
    format : {'mcap', 'blf', 'candump'}
    dropped_frames : tuple of (int, int)
        ``(first sample index, number of samples)`` of each burst of lost CAN frames.
    housing_taller_on : tuple of str
        Channels where the housing mode's peak is taller than the mesh mode's.
    """

    run_id: str
    file: Path
    format: Format
    dropped_frames: tuple[tuple[int, int], ...]
    housing_taller_on: tuple[str, ...]


@dataclass(frozen=True)
class DemoCampaign:
    """A generated demo campaign.

    Attributes
    ----------
    campaign_path : pathlib.Path
        ``campaign.toml``.
    truth_path : pathlib.Path
        ``truth.json``.
    dbc_path, mapping_path : pathlib.Path
        The CAN runs' DBC and mapping file.
    runs : tuple of DemoRun
    truth : CampaignTruth
    seed : int
    size : {'full', 'ci'}
    duration_s : float
        Length of each run (s).
    """

    campaign_path: Path
    truth_path: Path
    dbc_path: Path
    mapping_path: Path
    runs: tuple[DemoRun, ...]
    truth: CampaignTruth
    seed: int
    size: Size
    duration_s: float

    @property
    def run_files(self) -> dict[str, Path]:
        """Run id -> recording file."""
        return {r.run_id: r.file for r in self.runs}


def demo_conditions(size: Size = "full") -> tuple[RunCondition, ...]:
    """The runs of a size: ids ``LS<stage>-<T>C``, torque (N m), bulk temperature (degC).

    Ordered by temperature, then torque.
    """
    if size not in _DESIGN:
        raise ValueError(f"`size` must be one of {SIZES}, was {size!r}")
    return tuple(RunCondition(f"LS{ls}-{t:g}C", _LOAD_STAGES[ls], t)
                 for t, stages in _DESIGN[size].items() for ls in stages)


def _format_of(index: int, can_index: int) -> Format:
    if index % 2 == 0:
        return "mcap"
    return "candump" if can_index % 3 == 2 else "blf"


def _drops(n: int, gen: np.random.Generator) -> tuple[tuple[int, int], ...]:
    """One to three bursts of 1-40 lost frames, away from the ends and from each other."""
    candidates = np.arange(n // 10, 9 * n // 10, max(64, n // 16))
    k = min(int(gen.integers(1, 4)), candidates.size)
    starts = np.sort(gen.choice(candidates, size=k, replace=False))
    return tuple((int(s), int(gen.integers(1, 41))) for s in starts)


def _write_mcap(path: Path, sig: RunSignals, run_id: str, conditions: dict[str, float],
                compression: Literal["zstd", "lz4"]) -> None:
    md = RunMetadata(run_id=run_id, rig=_RIG, gear_set="fzg-c", conditions=conditions)
    write_accel_mcap(
        path, {c: (v, sig.sample_rate_Hz, "m/s^2", 0, sig.start_time_s)
               for c, v in sig.channels.items()},
        sig.slow, md, encoding="protobuf", compression=compression)


def _write_can(path: Path, sig: RunSignals, dbc: Path, fmt: Format,
               drops: tuple[tuple[int, int], ...], gen: np.random.Generator) -> None:
    lost = [i for s, k in drops for i in range(s, s + k)]
    batch = encode_triax_frames(
        np.column_stack([sig.channels[c] for c in ACCEL_CHANNELS]),
        {name: vals for name, (_t, vals, _u) in sig.slow.items()}, dbc=dbc,
        start_time_s=sig.start_time_s, drop_frames=lost, rng=gen)
    write_can_log(path, batch, "log" if fmt == "candump" else "blf", engine="rigtools")


def _toml_str(s: str) -> str:
    return json.dumps(s, ensure_ascii=False)


def _campaign_text(truth: CampaignTruth, runs: list[DemoRun], *, seed: int, size: str,
                   dbc: Path, mapping: Path, base: Path) -> str:
    p = truth.physics
    lines = [
        "# The built-in demo campaign of rigtools (`rigtools demo`), generated from the physics of",
        f"# models.thermal with a known truth (truth.json); seed {seed}, size {size!r}.",
        "# To study your own rig: copy this file, point each [[run]] file at your recordings,",
        "# state their conditions, and give dbc/map for your CAN layout (in [sensors] for all",
        "# runs, or per [[run]]; MCAP needs neither). Then: rigtools run campaign.toml -o results",
        "",
        "[campaign]",
        'name = "FZG-C demo: backlash and thermal closure"',
        "description = " + _toml_str(
            f"Synthetic FZG type C runs at seed 000's torques and {len(truth.temperatures_C)} "
            "bulk temperatures, made from a known backlash and a linear thermal closure "
            "(truth.json)"),
        'gear_set = "fzg-c"',
        f"rig = {_toml_str(_RIG)}",
        "",
        "[sensors]",
        "# The channels every run has; the CAN runs name their own layout (dbc, map) below.",
        "accel = [" + ", ".join(_toml_str(c) for c in ACCEL_CHANNELS) + "]",
        'speed = "PinionSpeed_rpm"',
        "",
        "[thermal]",
        "# The backlash is stated at the assembly temperature; the housing (centre distance)",
        "# follows the oil temperature each run logs.",
        f"reference_temperature_C = {p.reference_temperature_C!r}",
        'housing = "follows-oil"',
        "",
        "[analysis]",
        "# Accelerometers: fit the acceleration response of a single-DOF mode to each peak;",
        "# search natural frequencies above the third mesh harmonic (1.2 kHz at 1500 rpm).",
        'response = "acceleration"',
        "f_range_Hz = [1000.0, 11000.0]",
    ]
    for r, dr in zip(truth.runs, runs, strict=True):
        note = {"mcap": "MCAP, rigtools.AccelBatch (protobuf)",
                "blf": "Vector BLF, triax layout", "candump": "candump -L log, triax layout"}
        extra = (f"; {sum(k for _s, k in dr.dropped_frames)} frame(s) lost in "
                 f"{len(dr.dropped_frames)} burst(s)" if dr.dropped_frames else "")
        lines += [
            "",
            "[[run]]",
            f"id = {_toml_str(r.run_id)}",
            f"file = {_toml_str(dr.file.relative_to(base).as_posix())}",
            f"torque_Nm = {r.torque_Nm!r}",
            f"bulk_temperature_C = {r.bulk_temperature_C!r}",
            f"oil_temperature_C = {round(r.oil_temperature_C, 2)!r}",
            f"speed_rpm = {r.speed_rpm!r}",
            f"notes = {_toml_str(note[dr.format] + extra)}",
        ]
        if dr.format != "mcap":   # another logger: one frame per sample time, counter + 3 axes
            lines += [
                f"format = {_toml_str(dr.format)}",
                f"dbc = {_toml_str(dbc.relative_to(base).as_posix())}",
                f"map = {_toml_str(mapping.relative_to(base).as_posix())}",
            ]
    return "\n".join(lines) + "\n"


def _signal_facts(sig: RunSignals) -> dict[str, Any]:
    """What truth.json keeps of a run's signals (levels, noise, step; not the samples)."""
    return {"mesh_peak_psd": sig.mesh_peak_psd, "housing_peak_psd": sig.housing_peak_psd,
            "noise_sigma_m_s2": sig.noise_sigma_m_s2, "lsb_m_s2": sig.lsb_m_s2,
            "mesh_frequency_Hz": sig.mesh_frequency_Hz}


def _truth_json(truth: CampaignTruth, runs: list[DemoRun], facts: list[dict[str, Any]], *,
                seed: int, size: str, duration_s: float, levels: SignalLevels,
                base: Path) -> dict[str, Any]:
    out = truth.summary()
    for r, dr, fact in zip(truth.runs, runs, facts, strict=True):
        out["runs"][r.run_id].update(
            file=dr.file.relative_to(base).as_posix(), format=dr.format,
            margin_um=r.margin_m * 1e6, critical_gap_um=r.critical_gap_m * 1e6,
            mesh_housing_separation_Hz=r.mesh.f_n_Hz - truth.housing.f_n_Hz,
            housing_taller_on=list(dr.housing_taller_on), **fact,
            dropped_frames=[list(d) for d in dr.dropped_frames])
    out["generator"] = {
        "module": "rigtools.demo.campaign", "seed": seed, "size": size,
        "duration_s": duration_s, "sample_rate_Hz": _SAMPLE_RATE_HZ,
        "channels": list(ACCEL_CHANNELS), "snr_dB": levels.snr_dB,
        "levels": {k: getattr(levels, k) for k in levels.__dataclass_fields__},
        "signal_route": "acceleration response (accelerance with mass-line floor) of the mesh "
                        "and housing modes to independent white forces, per FFT bin; mesh "
                        "harmonics 1-3 amplitude-modulated by both shaft rates; white noise; "
                        "quantised to the format's LSB",
    }
    return out


def generate_demo_campaign(
    outdir: str | Path,
    *,
    seed: int = 0,
    size: Size = "full",
    duration_s: float | None = None,
    levels: SignalLevels | None = None,
    housing: HousingMode | None = None,
    on_run: Callable[[DemoRun], None] | None = None,
) -> DemoCampaign:
    """Write the demo campaign (recordings, layout, ``campaign.toml``, ``truth.json``).

    Parameters
    ----------
    outdir : str or pathlib.Path
        Folder to write into (created; files of the same names are replaced).
    seed : int
        Seed of every random draw (forces, noise, phases, slow-signal scatter, dropped
        frames, logger jitter): the same seed gives the same files.
    size : {'full', 'ci'}
        ``"full"``: 12 runs of 8 s; ``"ci"``: 8 runs of 3 s (module notes).
    duration_s : float, optional
        Length of each run (s); default by size.
    levels : SignalLevels, optional
        Signal levels and mode shapes; default :class:`~rigtools.demo.run_signals.SignalLevels`.
    housing : HousingMode, optional
        The housing mode; default 4.9 kHz, ``zeta = 0.012`` (320 Hz from the mesh mode at
        55 degC / 35.3 N m).
    on_run : callable, optional
        Called with each :class:`DemoRun` once its file is written (progress).

    Returns
    -------
    DemoCampaign

    Raises
    ------
    ValueError
        An unknown size, a non-positive duration or a negative seed.
    """
    if size not in SIZES:
        raise ValueError(f"`size` must be one of {SIZES}, was {size!r}")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise ValueError(f"`seed` must be an integer >= 0, was {seed!r}")
    dur = DEFAULT_DURATION_S[size] if duration_s is None else float(duration_s)
    if not (math.isfinite(dur) and dur > 0):
        raise ValueError(f"`duration_s` must be > 0, was {duration_s!r}")
    lv = levels or SignalLevels()
    base = Path(outdir)
    (base / "runs").mkdir(parents=True, exist_ok=True)
    gear_set = load_gear_set("fzg-c")
    pair = gear_set.pair
    model = prepare_natural_frequency(pair)
    truth = campaign_truth(model, gear_set, demo_conditions(size),
                           true_physics(model, gear_set), housing=housing)
    dbc, mapping = write_triax_layout(base)
    n = round(dur * _SAMPLE_RATE_HZ)
    generators = [np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(
        len(truth.runs))]
    runs: list[DemoRun] = []
    facts: list[dict[str, Any]] = []
    n_can = 0
    for i, (r, gen) in enumerate(zip(truth.runs, generators, strict=True)):
        fmt = _format_of(i, n_can)
        lsb = MCAP_LSB_M_S2 if fmt == "mcap" else ACCEL_LSB_M_S2
        sig = run_signals(r, truth.housing, z1=int(pair.pinion.teeth), z2=int(pair.wheel.teeth),
                          duration_s=dur, sample_rate_Hz=_SAMPLE_RATE_HZ, lsb_m_s2=lsb,
                          start_time_s=_FIRST_START_S + 1800.0 * i, channels=ACCEL_CHANNELS,
                          levels=lv, rng=gen)
        stem = r.run_id.lower().replace("-", "_")
        drops: tuple[tuple[int, int], ...] = ()
        if fmt == "mcap":
            path = base / "runs" / f"{stem}.mcap"
            _write_mcap(path, sig, r.run_id, {
                "torque_Nm": r.torque_Nm, "bulk_temperature_C": r.bulk_temperature_C,
                "oil_temperature_C": round(r.oil_temperature_C, 2), "speed_rpm": r.speed_rpm},
                "zstd" if (i // 2) % 2 == 0 else "lz4")
        else:
            path = base / "runs" / (f"{stem}.log" if fmt == "candump" else f"{stem}.blf")
            if n_can % 2 == 0:
                drops = _drops(n, gen)
            _write_can(path, sig, dbc, fmt, drops, gen)
            n_can += 1
        dr = DemoRun(r.run_id, path, fmt, drops, sig.housing_taller_on())
        runs.append(dr)
        facts.append(_signal_facts(sig))
        if on_run is not None:
            on_run(dr)
    campaign_path = base / "campaign.toml"
    campaign_path.write_text(_campaign_text(truth, runs, seed=seed, size=size, dbc=dbc,
                                            mapping=mapping, base=base), encoding="utf-8")
    load_campaign(campaign_path)  # the file must be valid: fail here, not in the user's hands
    truth_path = base / "truth.json"
    truth_path.write_text(json.dumps(_truth_json(truth, runs, facts, seed=seed, size=size,
                                                 duration_s=dur, levels=lv, base=base),
                                     indent=2) + "\n", encoding="utf-8")
    return DemoCampaign(campaign_path=campaign_path, truth_path=truth_path, dbc_path=dbc,
                        mapping_path=mapping, runs=tuple(runs), truth=truth, seed=seed,
                        size=size, duration_s=dur)
