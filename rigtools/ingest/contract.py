"""The reader plug-in point: what every file format in the registry provides.

A format is one object satisfying :class:`RecordingReader`: its ``name`` (the key it has in
:data:`rigtools.ingest.registry.READERS` and the ``reader`` of the provenance), a content check
on the first bytes of a file, and the read of a whole file into a
:class:`~rigtools.ingest.recording.Recording`. :func:`rigtools.ingest.read` chooses the object
by content and hands it the file and a :class:`ReadRequest`; it never asks what kind of format
it holds. The registry is typed against the protocol, so mypy checks every reader against it.

Readers that decode a byte stream into a :class:`~rigtools.ingest.builder.RecordingBuilder`
(CAN logs, MCAP) share that read in :class:`rigtools.ingest.stream_reader.StreamReader`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from rigtools.ingest.layout import ChannelMapping
from rigtools.ingest.recording import Recording, RunMetadata

__all__ = ["ReadRequest", "RecordingReader"]


@dataclass(frozen=True)
class ReadRequest:
    """What the caller of :func:`rigtools.ingest.read` asks beyond the file.

    Each reader takes what applies to its format and leaves the rest (a normalized recording
    takes none of it).

    Attributes
    ----------
    dbc : str or pathlib.Path or None
        DBC for CAN logs; None: the reference layout ``data_schemas/rig_reference.dbc``.
    mapping : str or pathlib.Path or ChannelMapping or None
        User mapping of signals or MCAP fields to channels (a TOML file or a loaded mapping).
    metadata : RunMetadata or None
        Run metadata overriding what the file or the mapping carries.
    strict_dbc : bool
        Refuse DBCs with overlapping or oversized signals (cantools ``strict``).
    mcap_clock : {"header", "log_time"}
        MCAP only: the clock that places channels whose messages carry a header stamp.
    progress : callable or None
        ``progress(bytes_read, file_bytes)`` a few times a second while a stream reader
        decodes (from another thread), and once at the end; readers that load the file whole
        (Parquet) call it once at the end.
    """

    dbc: str | Path | None = None
    mapping: str | Path | ChannelMapping | None = None
    metadata: RunMetadata | None = None
    strict_dbc: bool = True
    mcap_clock: str = "header"
    progress: Callable[[int, int], None] | None = None


class RecordingReader(Protocol):
    """One file format: recognised by its content, read whole into a Recording."""

    @property
    def name(self) -> str:
        """Format name: the registry key and the ``reader`` of the provenance (``"blf"``)."""
        ...

    def sniff(self, head: bytes) -> bool:
        """True when the first bytes of a file (gzip unwrapped) are of this format.

        Parameters
        ----------
        head : bytes
            Up to the first 8192 bytes of the file; possibly empty or cut anywhere.
        """
        ...

    def read(self, path: Path, request: ReadRequest) -> Recording:
        """Read the file into a Recording.

        Parameters
        ----------
        path : pathlib.Path
            The file, detected as this format (possibly gzipped).
        request : ReadRequest
            The options of the read; those that do not apply to the format are ignored.

        Raises
        ------
        RigtoolsError
            A subclass naming the file, the position and what was expected, when nothing
            intact can be returned (and for a DBC or mapping that does not load or fit).
        """
        ...
