"""The definitions an MCAP file's records make: Schema, Channel and Metadata records, settled.

A part of :class:`~rigtools.ingest.mcap.container.ContainerScanner`, which provides the
attributes and the warning methods declared here. :class:`DefinitionTable` keeps the first
definition of each schema and channel id, prefers the copy in the CRC-checked summary section
(read first, :meth:`DefinitionTable._read_summary`) over a differing data-section copy, holds
a Channel record whose Schema record has not come yet, and holds the messages of a channel not
defined yet (up to :data:`MAX_DEFERRED_BYTES`) until the end of the file.
"""

from __future__ import annotations

import zlib
from typing import Any, Final, TypeVar

from rigtools.ingest.mcap.records import (
    FOOTER_AND_MAGIC_BYTES,
    MAGIC,
    OP_CHANNEL,
    OP_SCHEMA,
    RECORD_HEADER,
    RECORD_HEADER_BYTES,
    ChannelRecord,
    MalformedRecordError,
    SchemaRecord,
    parse_channel,
    parse_footer,
    parse_metadata,
    parse_schema,
)
from rigtools.ingest.mcap.source import ByteSource
from rigtools.ingest.mcap.walk import ScannedMessage
from rigtools.ingest.recording import IngestReport

__all__ = ["MAX_DEFERRED_BYTES", "DefinitionTable"]

#: Messages naming a channel not (yet) defined are held, up to this many payload bytes
#: (64 MiB), until the summary's repeated Channel records may define it.
MAX_DEFERRED_BYTES: Final = 64 << 20

_Record = TypeVar("_Record", SchemaRecord, ChannelRecord)


class DefinitionTable:
    """The Schema, Channel and Metadata records of a file, settled against its summary.

    A part of :class:`~rigtools.ingest.mcap.container.ContainerScanner`, which provides the
    attributes and the warning methods declared here.
    """

    path: str
    report: IngestReport
    schemas: dict[int, SchemaRecord]
    channels: dict[int, ChannelRecord]
    metadata: dict[str, dict[str, str]]
    _src: ByteSource
    _deferred: list[tuple[ScannedMessage, str]]
    _deferred_bytes: int
    _summary_schemas: dict[int, SchemaRecord]
    _summary_channels: dict[int, ChannelRecord]
    _unsettled: dict[int, ChannelRecord]

    def _warn(self, reason: str, text: str) -> None:
        raise NotImplementedError

    def _malformed(self, kind: str, where: str, exc: MalformedRecordError) -> None:
        raise NotImplementedError

    # -- the summary first ---------------------------------------------------------------

    def _read_summary(self) -> None:
        """Keep the Schema and Channel records of the summary section, if its CRC checks.

        They then win over a differing (damaged) copy in the data section, before any
        message is handed on, so a damaged definition never decides how a channel is read.
        Without a summary CRC (0) nothing is kept: which copy is damaged cannot be told. A
        Footer whose offsets point outside the file is warned about.
        """
        src = self._src
        total = src.size
        if total is None or total < len(MAGIC) + FOOTER_AND_MAGIC_BYTES:
            return
        fpos = total - FOOTER_AND_MAGIC_BYTES
        footer = parse_footer(src.peek(fpos, FOOTER_AND_MAGIC_BYTES))
        if footer is None:
            return
        start, offset_start, crc, footer_head = footer
        for name, at in (("summary start", start), ("summary offset start", offset_start)):
            if at != 0 and not len(MAGIC) <= at <= fpos:
                self.report.warn(f"{self.path}: the Footer's {name} ({at}) points outside the "
                                 f"records of the file (bytes {len(MAGIC)} to {fpos}); the "
                                 "summary section is not used")
                return
        if start == 0 or crc == 0:
            return
        summary = src.peek(start, fpos - start)
        if zlib.crc32(footer_head, zlib.crc32(summary)) != crc:
            self.report.warn(f"{self.path}: the summary section (byte {start}) does not match "
                             "the Footer's CRC; its Schema and Channel records are not preferred")
            return
        p = 0
        while len(summary) - p >= RECORD_HEADER_BYTES:
            op, length = RECORD_HEADER.unpack_from(summary, p)
            body = p + RECORD_HEADER_BYTES
            if length > len(summary) - body:
                break
            try:
                if op == OP_SCHEMA:
                    sch = parse_schema(summary, body, body + length)
                    self._summary_schemas.setdefault(sch.id, sch)
                elif op == OP_CHANNEL:
                    ch = parse_channel(summary, body, body + length)
                    self._summary_channels.setdefault(ch.id, ch)
            except MalformedRecordError:
                pass  # the CRC checks: a writer's fault, met again (and counted) by the walk
            p = body + length

    # -- records -------------------------------------------------------------------------

    def _checked(self, rec: _Record, kind: str, where: str,
                 checked: dict[int, _Record]) -> _Record:
        """``rec``, or its copy in the CRC-checked summary when they differ."""
        good = checked.get(rec.id)
        if good is not None and good != rec:
            self._warn(f"{kind}_damaged", f"{self.path}: {kind} id {rec.id} at {where} differs "
                       "from its copy in the summary section, whose CRC checks; the summary's "
                       "copy is used")
            return good
        return rec

    def _keep_first(self, table: dict[int, _Record], rec: _Record, kind: str,
                    where: str) -> None:
        old = table.setdefault(rec.id, rec)
        if old != rec:
            self._warn(f"{kind}_redefined", f"{self.path}: {kind} id {rec.id} redefined at "
                       f"{where}; the first definition is kept")

    def _schema(self, buf: Any, pos: int, end: int, where: str) -> None:
        try:
            rec = parse_schema(buf, pos, end)
        except MalformedRecordError as exc:
            self._malformed("Schema", where, exc)
            return
        if rec.id != 0:
            rec = self._checked(rec, "schema", where, self._summary_schemas)
            self._keep_first(self.schemas, rec, "schema", where)
            for cid, ch in list(self._unsettled.items()):
                if ch.schema_id == rec.id:
                    self.channels.setdefault(cid, self._unsettled.pop(cid))

    def _channel(self, buf: Any, pos: int, end: int, where: str) -> None:
        try:
            rec = parse_channel(buf, pos, end)
        except MalformedRecordError as exc:
            self._malformed("Channel", where, exc)
            return
        rec = self._checked(rec, "channel", where, self._summary_channels)
        sid = rec.schema_id
        if sid and sid not in self.schemas and rec.id not in self.channels:
            if sid in self._summary_schemas:
                # its Schema record is lost (damaged or missing) before it: the summary's
                # copy settles the schema before any of the channel's messages goes on
                self.schemas[sid] = self._summary_schemas[sid]
                self._warn("schema_from_summary", f"{self.path}: schema id {sid} of channel "
                           f"{rec.id} ({where}) is not defined before it; its copy in the "
                           "summary is used")
            else:
                # held until its Schema record comes (later in the file, or in the summary):
                # its messages are held meanwhile, so they are all read with the schema
                self._unsettled.setdefault(rec.id, rec)
                return
        self._keep_first(self.channels, rec, "channel", where)

    def _metadata(self, buf: bytes, where: str) -> None:
        try:
            name, meta = parse_metadata(buf)
        except MalformedRecordError as exc:
            self._malformed("Metadata", where, exc)
            return
        self.metadata.setdefault(name, {}).update(meta)

    # -- messages whose channel is not defined yet ---------------------------------------

    def _defer(self, cid: int, seq: int, lt: int, pt: int, data: Any, where: str) -> None:
        """Hold a message whose channel is not defined yet.

        Its Channel record may have been in a refused chunk; indexed files repeat every
        Channel record in the summary.
        """
        if self._deferred_bytes + len(data) > MAX_DEFERRED_BYTES:
            self._unknown_channel(cid, where)
            return
        self._deferred_bytes += len(data)
        self._deferred.append(((cid, seq, lt, pt, memoryview(bytes(data)), -1), where))

    def _release_deferred(self) -> list[ScannedMessage]:
        for cid, ch in self._unsettled.items():  # their schema never came: read without
            self.channels.setdefault(cid, ch)
        self._unsettled = {}
        out = []
        for msg, where in self._deferred:
            if msg[0] in self.channels:
                out.append(msg)
            else:
                self._unknown_channel(msg[0], where)
        if out:
            self.report.warn(f"{self.path}: {len(out)} message(s) came before the Channel "
                             "or Schema record defining their channel (found in the summary or "
                             "later in the file); they were read last")
        self._deferred = []
        self._deferred_bytes = 0
        return out

    def _unknown_channel(self, cid: int, where: str) -> None:
        self.report.reject("unknown_channel", 1, where)
        if cid in self._unsettled:
            self._warn("unknown_channel", f"{self.path}: message at {where} of channel id "
                       f"{cid}, whose schema is not defined yet, is beyond the "
                       f"{MAX_DEFERRED_BYTES} bytes held until it is")
            return
        self._warn("unknown_channel", f"{self.path}: message at {where} names channel id {cid}, "
                   "which no Channel record in the file defines")
