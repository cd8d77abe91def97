"""A CAN log format in the registry: its frames decoded through a DBC into a Recording.

Each log format module (:mod:`~rigtools.ingest.can.blf`, :mod:`~rigtools.ingest.can.asc`,
:mod:`~rigtools.ingest.can.trc`, :mod:`~rigtools.ingest.can.candump`,
:mod:`~rigtools.ingest.can.csv_log`) parses its files into
:class:`~rigtools.ingest.can.frames.CanFrameBatch` batches and states its ``READER``, a
:class:`CanLogReader` made of its name, its content check and its batch iterator. What is
common to every CAN log lives here: the DBC loaded, the channel layout made of it (or of the
user's mapping) and the frames assembled into channels (:func:`~rigtools.ingest.can.assembly.
assemble_can`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import BinaryIO, TypeAlias

from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.can.assembly import assemble_can
from rigtools.ingest.can.dbc import dbc_digest, load_dbc
from rigtools.ingest.can.frames import CanFrameBatch
from rigtools.ingest.contract import ReadRequest
from rigtools.ingest.layout import ChannelMapping, can_layout
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.stream_reader import Decoded, StreamReader
from rigtools.schemas import schema_path

__all__ = ["BatchIterator", "CanLogReader"]

#: ``iter_batches(stream, path, report)`` of a log format: the frames of the whole stream.
BatchIterator: TypeAlias = Callable[[BinaryIO, str, IngestReport], Iterator[CanFrameBatch]]


class CanLogReader(StreamReader):
    """One CAN log format: the parser of its files, the DBC decoding shared.

    Parameters
    ----------
    name : str
        Format name (``"blf"``, ``"asc"``, ...).
    sniff : callable
        ``sniff(head: bytes) -> bool``, the format's content check.
    iter_batches : callable
        ``iter_batches(stream, path, report)``, the format's frames as batches.
    """

    units = "frames"

    def __init__(self, name: str, sniff: Callable[[bytes], bool],
                 iter_batches: BatchIterator) -> None:
        self.name = name
        self._sniff = sniff
        self.iter_batches = iter_batches

    def __repr__(self) -> str:
        return f"CanLogReader({self.name!r})"

    def sniff(self, head: bytes) -> bool:
        """True when the first bytes of a file (gzip unwrapped) are of this format."""
        return self._sniff(head)

    def decode(
        self,
        stream: BinaryIO,
        path: str,
        builder: RecordingBuilder,
        report: IngestReport,
        mapping: ChannelMapping | None,
        request: ReadRequest,
    ) -> Decoded:
        """Parse the log, decode its frames through the DBC and assemble the channels.

        The DBC is ``request.dbc`` (default: the reference layout); the channel layout is
        the DBC's own attributes, or ``mapping`` when given. See
        :meth:`rigtools.ingest.stream_reader.StreamReader.decode` for the parameters.
        """
        dbc_file = schema_path("rig_reference.dbc") if request.dbc is None else Path(request.dbc)
        db = load_dbc(dbc_file, strict=request.strict_dbc)
        layout = can_layout(db, mapping, str(dbc_file))
        layout_desc = dict(layout.description)
        layout_desc["dbc_sha256"] = dbc_digest(dbc_file)
        assemble_can(self.iter_batches(stream, path, report), layout, builder, report)
        return Decoded(layout_desc)
