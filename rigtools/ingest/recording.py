"""The Recording: one faithful, format-independent model of a rig run.

A :class:`Recording` holds

* uniform-rate channels (:class:`Channel`): name, unit, nominal sample rate, the time of
  sample index 0, the absolute sample index of the first value, the values and a per-sample
  validity mask (``False`` in gaps and for non-finite or rejected samples, whose value is NaN
  in a gap and kept as received otherwise);
* slow signals (:class:`SlowSignal`): irregular time series with a unit (speed, torque,
  temperatures);
* run metadata (:class:`RunMetadata`): rig, gear set, run id, conditions;
* provenance (:class:`Provenance`): source path and SHA-256, reader and library versions, and
  the :class:`IngestReport` with decoded counts, rejections by reason and the gaps found.

Nothing here knows about file formats; readers fill a :class:`RecordingBuilder`
(``rigtools.ingest.builder``) and get one of these back.
"""

from __future__ import annotations

import dataclasses
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = [
    "SAMPLE_REASONS",
    "Channel",
    "Gap",
    "IngestReport",
    "Provenance",
    "Recording",
    "RunMetadata",
    "SlowSignal",
    "counts_samples",
]

#: Endings of rejection reasons that count samples or points, not frames or messages
#: (``non_finite_sample``, ``duplicate_sample``, ``implausible_sample_index``,
#: ``non_finite_timestamp``, ``inconsistent_channel_layout``).
SAMPLE_REASONS = ("_sample", "_sample_index", "_timestamp", "inconsistent_channel_layout")


def counts_samples(reason: str) -> bool:
    """True when a rejection ``reason`` counts samples (or slow-signal points), not frames."""
    return reason.endswith(SAMPLE_REASONS)


@dataclass(frozen=True, eq=False)
class Channel:
    """A uniformly sampled channel.

    Attributes
    ----------
    name : str
        Channel name, e.g. ``"accel_1"``.
    unit : str
        Unit of ``values``, e.g. ``"m/s^2"``.
    sample_rate_Hz : float
        Nominal sample rate (Hz).
    start_time_s : float
        Time of sample index 0 on the logger clock (s, UNIX epoch where the source has one).
    first_index : int
        Absolute sample index of ``values[0]`` (from the source's sample counter).
    values : numpy.ndarray
        Samples, float64, shape ``(n,)``. NaN where no sample was received (gaps).
    valid : numpy.ndarray
        Boolean mask, shape ``(n,)``: ``True`` where ``values`` holds a received, finite sample.
    """

    name: str
    unit: str
    sample_rate_Hz: float
    start_time_s: float
    first_index: int
    values: np.ndarray
    valid: np.ndarray

    def __len__(self) -> int:
        return int(self.values.shape[0])

    @property
    def duration_s(self) -> float:
        """Span covered from the first to one past the last sample (s)."""
        return len(self) / self.sample_rate_Hz

    @property
    def time_s(self) -> np.ndarray:
        """Sample times on the logger clock (s), rebuilt from the indices and the nominal rate."""
        idx = self.first_index + np.arange(len(self), dtype=np.float64)
        return self.start_time_s + idx / self.sample_rate_Hz

    def equals(self, other: Channel) -> bool:
        """Exact equality, bit for bit (NaN equal to NaN)."""
        return (
            self.name == other.name
            and self.unit == other.unit
            and self.sample_rate_Hz == other.sample_rate_Hz
            and self.start_time_s == other.start_time_s
            and self.first_index == other.first_index
            and _same_floats(self.values, other.values)
            and np.array_equal(self.valid, other.valid)
        )


@dataclass(frozen=True, eq=False)
class SlowSignal:
    """An irregularly sampled signal (speed, torque, temperature).

    Attributes
    ----------
    name : str
        Signal name, e.g. ``"PinionSpeed_rpm"``.
    unit : str
        Unit of ``values``.
    time_s : numpy.ndarray
        Sample times on the logger clock (s), non-decreasing.
    values : numpy.ndarray
        Values, float64.
    """

    name: str
    unit: str
    time_s: np.ndarray
    values: np.ndarray

    def __len__(self) -> int:
        return int(self.values.shape[0])

    def equals(self, other: SlowSignal) -> bool:
        """Exact equality, bit for bit (NaN equal to NaN)."""
        return (
            self.name == other.name
            and self.unit == other.unit
            and _same_floats(self.time_s, other.time_s)
            and _same_floats(self.values, other.values)
        )


@dataclass(frozen=True)
class Gap:
    """A run of missing samples in a uniform channel, found from its sample counter.

    Attributes
    ----------
    channel : str
        Channel name.
    start_index : int
        Absolute sample index of the first missing sample.
    n_missing : int
        Number of samples missing.
    time_s : float
        Logger time of the first missing sample (s).
    kind : str
        ``"gap"`` (counter jumped forward) or ``"restart"`` (counter inconsistent with the
        logger clock, resynchronised from the timestamps).
    """

    channel: str
    start_index: int
    n_missing: int
    time_s: float
    kind: str = "gap"


@dataclass
class IngestReport:
    """What a reader decoded, what it rejected and why, and what it noticed.

    Attributes
    ----------
    units : str
        What ``decoded`` and ``rejected`` count: ``"frames"`` (CAN) or ``"messages"`` (MCAP).
    decoded : int
        Frames or messages that contributed data.
    rejected : collections.Counter
        Frames, messages or samples not used, by reason (e.g. ``"error_frame"``,
        ``"id_not_in_dbc"``, ``"no_decoder"``, ``"truncated_chunk"``). A frame is counted once
        whatever number of channels it feeds; reasons for which :func:`counts_samples` holds
        count samples (:attr:`n_rejected_samples`), the others ``units``
        (:attr:`n_rejected_frames`).
    first_position : dict
        For each reason, where it first happened (byte offset, line, record).
    gaps : list of Gap
        Gaps in sample counters, per channel and in samples: the frames of a message that
        feeds several channels leave one gap in each (:func:`rigtools.ingest.losses.
        loss_tally` counts them once, in frames).
    warnings : list of str
        Everything else worth telling the user (timestamps backwards, clock drift, ...).
    timebase : dict
        Per channel, how the logger timestamps compare with the counter time base. A
        channel with a second clock (an MCAP message's log time beside its header stamp)
        also has an entry ``"<channel>@<clock>"`` with the same statistics, ``start_time_s``
        on that clock and ``offset_s``, its median offset from the channel's clock (s).
    """

    units: str = "frames"
    decoded: int = 0
    rejected: Counter[str] = field(default_factory=Counter)
    first_position: dict[str, str] = field(default_factory=dict)
    gaps: list[Gap] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    timebase: dict[str, dict[str, float]] = field(default_factory=dict)

    def reject(self, reason: str, count: int = 1, position: object = None) -> None:
        """Count ``count`` rejections for ``reason``; remember where the first happened."""
        if count <= 0:
            return
        self.rejected[reason] += int(count)
        if reason not in self.first_position and position is not None:
            self.first_position[reason] = str(position)

    def warn(self, message: str) -> None:
        """Record a warning (kept once)."""
        if message not in self.warnings:
            self.warnings.append(message)

    @property
    def n_rejected(self) -> int:
        """Total count of rejections over all reasons, frames and samples added.

        :attr:`n_rejected_frames` and :attr:`n_rejected_samples` count one kind each.
        """
        return int(sum(self.rejected.values()))

    @property
    def n_rejected_frames(self) -> int:
        """Frames or messages (``units``) rejected, over the reasons that count them."""
        return int(sum(n for r, n in self.rejected.items() if not counts_samples(r)))

    @property
    def n_rejected_samples(self) -> int:
        """Samples (or slow-signal points) rejected, over the reasons that count them."""
        return int(sum(n for r, n in self.rejected.items() if counts_samples(r)))

    @property
    def has_losses(self) -> bool:
        """True when anything was rejected or any gap was found."""
        return bool(self.n_rejected or self.gaps)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "units": self.units,
            "decoded": self.decoded,
            "rejected": dict(sorted(self.rejected.items())),
            "first_position": dict(sorted(self.first_position.items())),
            "gaps": [dataclasses.asdict(g) for g in self.gaps],
            "warnings": list(self.warnings),
            "timebase": self.timebase,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> IngestReport:
        """Inverse of :meth:`to_dict`."""
        return cls(
            units=d["units"],
            decoded=int(d["decoded"]),
            rejected=Counter({k: int(v) for k, v in d["rejected"].items()}),
            first_position=dict(d["first_position"]),
            gaps=[Gap(**g) for g in d["gaps"]],
            warnings=list(d["warnings"]),
            timebase={k: dict(v) for k, v in d["timebase"].items()},
        )


@dataclass(frozen=True)
class RunMetadata:
    """What the run was: rig, gear set, run id and the logged conditions.

    Attributes
    ----------
    run_id : str or None
    rig : str or None
    gear_set : str or None
    conditions : dict
        Named conditions with the unit in the key (``torque_Nm``, ``bulk_temperature_C``,
        ``speed_rpm``), as logged.
    extra : dict
        Any other key/value metadata found in the source (MCAP Metadata records, ...), as strings.
    """

    run_id: str | None = None
    rig: str | None = None
    gear_set: str | None = None
    conditions: dict[str, float] = field(default_factory=dict)
    extra: dict[str, str] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> RunMetadata:
        """Inverse of :meth:`to_dict`."""
        return cls(
            run_id=d.get("run_id"),
            rig=d.get("rig"),
            gear_set=d.get("gear_set"),
            conditions={k: float(v) for k, v in d.get("conditions", {}).items()},
            extra={k: str(v) for k, v in d.get("extra", {}).items()},
        )


@dataclass(frozen=True)
class Provenance:
    """Where a Recording came from.

    Attributes
    ----------
    source_path : str
    source_sha256 : str
        SHA-256 of the source file's bytes (hex).
    source_size_bytes : int
    reader : str
        Reader name, e.g. ``"blf"``, ``"mcap"``.
    versions : dict
        Versions of rigtools and of the libraries the reader used.
    report : IngestReport
    layout : dict
        The channel layout used (DBC path and hash, or mapping), JSON-ready.
    """

    source_path: str
    source_sha256: str
    source_size_bytes: int
    reader: str
    versions: dict[str, str]
    report: IngestReport
    layout: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return {
            "source_path": self.source_path,
            "source_sha256": self.source_sha256,
            "source_size_bytes": self.source_size_bytes,
            "reader": self.reader,
            "versions": dict(self.versions),
            "report": self.report.to_dict(),
            "layout": self.layout,
        }

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> Provenance:
        """Inverse of :meth:`to_dict`."""
        return cls(
            source_path=d["source_path"],
            source_sha256=d["source_sha256"],
            source_size_bytes=int(d["source_size_bytes"]),
            reader=d["reader"],
            versions=dict(d["versions"]),
            report=IngestReport.from_dict(d["report"]),
            layout=d.get("layout", {}),
        )


@dataclass(frozen=True, eq=False)
class Recording:
    """One rig run, format-independent.

    Attributes
    ----------
    channels : dict of str to Channel
        Uniform-rate channels by name.
    slow : dict of str to SlowSignal
        Slow signals by name.
    metadata : RunMetadata
    provenance : Provenance
    """

    channels: dict[str, Channel]
    slow: dict[str, SlowSignal]
    metadata: RunMetadata
    provenance: Provenance

    @property
    def report(self) -> IngestReport:
        """Shortcut to ``provenance.report``."""
        return self.provenance.report

    @property
    def duration_s(self) -> float:
        """Longest span over channels and slow signals (s)."""
        spans = [c.duration_s for c in self.channels.values()]
        spans += [
            float(s.time_s[-1] - s.time_s[0]) for s in self.slow.values() if len(s) > 1
        ]
        return max(spans, default=0.0)

    def equals(self, other: Recording) -> bool:
        """Exact equality of data, metadata and provenance (bit for bit on arrays)."""
        return (
            self.channels.keys() == other.channels.keys()
            and all(self.channels[k].equals(other.channels[k]) for k in self.channels)
            and self.slow.keys() == other.slow.keys()
            and all(self.slow[k].equals(other.slow[k]) for k in self.slow)
            and self.metadata == other.metadata
            and self.provenance.to_dict() == other.provenance.to_dict()
        )


def _same_floats(a: np.ndarray, b: np.ndarray) -> bool:
    if a.shape != b.shape or a.dtype != b.dtype:
        return False
    return bool(np.array_equal(a.view(np.uint8), b.view(np.uint8)))
