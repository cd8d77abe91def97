"""``rigtools.ingest.read``: any supported recording file to a :class:`Recording`.

The format is detected by :func:`~rigtools.ingest.registry.detect_format`, and its reader (a
:class:`~rigtools.ingest.contract.RecordingReader` of :data:`~rigtools.ingest.registry.READERS`)
reads the file with the options of a :class:`~rigtools.ingest.contract.ReadRequest`.
:func:`versions` (kept in every provenance) lives in :mod:`rigtools.ingest.stream_reader`.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from rigtools.ingest.contract import ReadRequest
from rigtools.ingest.layout import ChannelMapping
from rigtools.ingest.recording import Recording, RunMetadata
from rigtools.ingest.registry import READERS, detect_format
from rigtools.ingest.stream_reader import versions

__all__ = ["read", "versions"]


def read(
    path: str | Path,
    *,
    dbc: str | Path | None = None,
    mapping: str | Path | ChannelMapping | None = None,
    metadata: RunMetadata | None = None,
    fmt: str | None = None,
    strict_dbc: bool = True,
    mcap_clock: str = "header",
    progress: Callable[[int, int], None] | None = None,
) -> Recording:
    """Read a recording file into a :class:`~rigtools.ingest.recording.Recording`.

    Parameters
    ----------
    path : str or pathlib.Path
        MCAP, BLF, ASC, TRC, candump ``.log``, python-can CSV (any of them gzipped), or a
        normalized recording written by :func:`rigtools.ingest.write_parquet`. The reader is
        chosen by content; the suffix is used only when the content says nothing (see
        :func:`rigtools.ingest.registry.detect_format` for the table).
    dbc : str or pathlib.Path, optional
        DBC for CAN logs. Default: the reference layout ``data_schemas/rig_reference.dbc``.
    mapping : str, pathlib.Path or ChannelMapping, optional
        User mapping of signals or MCAP fields to channels (TOML); replaces the DBC's own
        layout attributes, or the default MCAP decoding.
    metadata : RunMetadata, optional
        Run metadata; overrides what the file or the mapping carries.
    fmt : str, optional
        Force a format by name instead of detecting it.
    strict_dbc : bool
        Refuse DBCs with overlapping or oversized signals (cantools ``strict``).
    mcap_clock : {"header", "log_time"}
        MCAP only: the clock that places a channel whose messages carry a header stamp
        (Imu channels, mapped fields). ``"header"`` (default): the header stamp (the log time
        where a message has none, or where every Imu header stamp is zero); ``"log_time"``:
        the MCAP log time. The other clock is kept in the report as a second clock of the
        channel: ``recording.report.timebase[f"{channel}@log_time"]`` (or ``@header``) holds
        its statistics, its ``start_time_s`` and ``offset_s``, its median offset from the
        clock that placed the channel (s). Slow signals (topic scalars, log time only) are
        unaffected except mapped slow fields, timed by the chosen clock.
    progress : callable, optional
        ``progress(bytes_read, file_bytes)``, called a few times a second from another thread
        while the file is decoded, and once at the end (a progress bar's update).

    Returns
    -------
    Recording
        Channels, slow signals, metadata and provenance; ``recording.report`` tallies what
        was decoded, rejected (by reason) and the gaps found.

    Raises
    ------
    RecordingFormatError
        The file is empty, unreadable, or damaged so that nothing intact can be returned.
    UnsupportedFormatError
        Neither content nor suffix names a supported format.
    DbcError, MappingError
        The DBC or the mapping does not load or does not match the file.
    ValueError
        ``mcap_clock`` is neither ``"header"`` nor ``"log_time"``.
    NoDataError
        The file reads but holds no decodable channel or slow signal.
    """
    if mcap_clock not in ("header", "log_time"):
        raise ValueError(f"mcap_clock must be 'header' or 'log_time', not {mcap_clock!r}")
    p = Path(path)
    reader = READERS[detect_format(p, fmt)]
    return reader.read(p, ReadRequest(dbc, mapping, metadata, strict_dbc, mcap_clock,
                                      progress))
