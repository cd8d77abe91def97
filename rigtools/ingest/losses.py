"""What a recording lost, counted in frames (or messages) and in samples, each named as such.

A CAN message that carries three channels and is lost leaves a gap in each of the three
channels: ``report.gaps`` (one :class:`~rigtools.ingest.recording.Gap` per channel, in samples)
then holds three gaps for one lost frame. :func:`loss_tally` counts both ways:

* in frames or messages (``report.units``): the gaps of the channels one source carries (a
  CAN message on one bus, an MCAP topic with one sample per message), as the readers note it
  in ``provenance.layout["carriers"]``, are one :class:`FrameGap` per run of lost frames;
* in samples: per channel, as ``report.gaps`` holds them.

Channels whose carrier the reader could not state (MCAP batches of varying length) are
counted in samples only and listed in :attr:`LossTally.uncounted`.
"""

from __future__ import annotations

from dataclasses import dataclass

from rigtools.ingest.recording import Gap, Recording

__all__ = ["FrameGap", "LossTally", "loss_tally"]


@dataclass(frozen=True)
class FrameGap:
    """A run of lost frames (or messages) of one source, counted once.

    Attributes
    ----------
    source : str
        What carries the channels (``"message 'ACC1'"``, ``"topic '/imu'"``).
    first_frame : int
        Index of the first frame lost, on the source's frame counter (sample index divided by
        the samples per frame).
    n_frames : int
        Frames lost.
    time_s : float
        Logger time of the first missing sample (s).
    channels : tuple of str
        The channels the lost frames carried, each with a gap of ``n_frames`` times its samples
        per frame.
    kind : str
        ``"gap"`` or ``"restart"`` (see :class:`~rigtools.ingest.recording.Gap`).
    """

    source: str
    first_frame: int
    n_frames: int
    time_s: float
    channels: tuple[str, ...]
    kind: str = "gap"


@dataclass(frozen=True)
class LossTally:
    """Losses of a recording, in frames (or messages) and in samples.

    Attributes
    ----------
    units : str
        What the frame counts count: ``"frames"`` (CAN) or ``"messages"`` (MCAP).
    frame_gaps : tuple of FrameGap
        Runs of lost frames, once per source, in order of source and frame.
    n_frames_lost : int
        Frames (messages) lost in them.
    n_sample_gaps : int
        Gaps over all channels (a frame gap counts once in each channel it fed).
    n_samples_missing : int
        Samples missing over all channels.
    by_channel : dict of str to (int, int)
        Per channel with a gap: (gaps, samples missing).
    by_source : dict of str to (int, int)
        Per source with a lost frame: (frame gaps, frames lost).
    uncounted : tuple of str
        Channels with gaps whose carrier is not known: their losses are counted in samples
        only.
    rejected_frames : int
        Frames (messages) rejected at ingest, each counted once
        (:attr:`~rigtools.ingest.recording.IngestReport.n_rejected_frames`).
    rejected_samples : int
        Samples (and slow-signal points) rejected at ingest.
    """

    units: str
    frame_gaps: tuple[FrameGap, ...]
    n_frames_lost: int
    n_sample_gaps: int
    n_samples_missing: int
    by_channel: dict[str, tuple[int, int]]
    by_source: dict[str, tuple[int, int]]
    uncounted: tuple[str, ...]
    rejected_frames: int
    rejected_samples: int

    def to_dict(self) -> dict[str, object]:
        """JSON-ready form."""
        return {
            "units": self.units,
            "frame_gaps": len(self.frame_gaps),
            "frames_lost": self.n_frames_lost,
            "sample_gaps": self.n_sample_gaps,
            "samples_missing": self.n_samples_missing,
            "by_source": {k: {"frame_gaps": g, "frames_lost": n}
                          for k, (g, n) in self.by_source.items()},
            "by_channel": {k: {"gaps": g, "samples_missing": n}
                           for k, (g, n) in self.by_channel.items()},
            "uncounted": list(self.uncounted),
            "rejected_frames": self.rejected_frames,
            "rejected_samples": self.rejected_samples,
        }


def _carriers(rec: Recording) -> dict[str, tuple[str, int]]:
    """Channel -> (source, samples per frame), from the layout the reader recorded."""
    raw = rec.provenance.layout.get("carriers", {})
    out: dict[str, tuple[str, int]] = {}
    if not isinstance(raw, dict):
        return out
    for name, c in raw.items():
        try:
            k = int(c["samples_per_frame"])
            source = str(c["source"])
        except (KeyError, TypeError, ValueError):
            continue
        if k >= 1:
            out[str(name)] = (source, k)
    return out


def loss_tally(rec: Recording) -> LossTally:
    """Count what a recording lost, in frames (or messages) and in samples.

    Parameters
    ----------
    rec : Recording
        A recording as read (or read back from Parquet: the carriers travel in its layout).

    Returns
    -------
    LossTally

    Notes
    -----
    Three channels of one CAN message (one sample each per frame) that lost 37 frames in 31
    runs hold 93 gaps and 111 missing samples: the tally has 31 frame gaps and 37 frames
    lost, and 93 gaps and 111 samples missing over the channels (31 and 37 in each).
    """
    rep = rec.report
    carriers = _carriers(rec)
    by_channel: dict[str, list[int]] = {}
    groups: dict[tuple[str, int, int], list[Gap]] = {}
    uncounted: list[str] = []
    for g in rep.gaps:
        tally = by_channel.setdefault(g.channel, [0, 0])
        tally[0] += 1
        tally[1] += int(g.n_missing)
        carrier = carriers.get(g.channel)
        if carrier is None:
            if g.channel not in uncounted:
                uncounted.append(g.channel)
            continue
        source, k = carrier
        first = int(g.start_index) // k
        n_frames = -(-int(g.n_missing) // k)
        groups.setdefault((source, first, n_frames), []).append(g)
    frame_gaps = tuple(
        FrameGap(source, first, n, min(g.time_s for g in gaps),
                 tuple(dict.fromkeys(g.channel for g in gaps)),
                 "restart" if any(g.kind == "restart" for g in gaps) else "gap")
        for (source, first, n), gaps in sorted(groups.items(), key=lambda kv: kv[0])
    )
    by_source: dict[str, list[int]] = {}
    for fg in frame_gaps:
        t = by_source.setdefault(fg.source, [0, 0])
        t[0] += 1
        t[1] += fg.n_frames
    return LossTally(
        units=rep.units,
        frame_gaps=frame_gaps,
        n_frames_lost=sum(fg.n_frames for fg in frame_gaps),
        n_sample_gaps=len(rep.gaps),
        n_samples_missing=sum(int(g.n_missing) for g in rep.gaps),
        by_channel={k: (v[0], v[1]) for k, v in by_channel.items()},
        by_source={k: (v[0], v[1]) for k, v in by_source.items()},
        uncounted=tuple(uncounted),
        rejected_frames=rep.n_rejected_frames,
        rejected_samples=rep.n_rejected_samples,
    )
