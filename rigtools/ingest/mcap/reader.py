"""MCAP reader: the entry points the registry and :func:`rigtools.ingest.read` use.

The layers below it are listed in :mod:`rigtools.ingest.mcap`; this module chooses a handler
per channel and drives the streaming walk (:func:`ingest`), and states the format's entry in
the registry (:data:`READER`, a :class:`McapReader`).

Every message is either decoded or counted in the :class:`IngestReport` (``units`` is
``"messages"``) under one of these reasons:

=========================  ===================================================================
reason                     what happened
=========================  ===================================================================
``no_decoder``             no decoder for the channel's message encoding and schema
``not_in_mapping``         a mapping was given and does not name the topic
``bad_schema``             the schema names a known type but does not parse or differs
``decode_error``           the payload does not decode under its schema (a JSON rigtools message
                           is checked against its JSON Schema: fields, types, ranges), or a
                           mapped field holds no number
``missing_field``          a message lacks a field the mapping names (other messages have it)
``empty_batch``            an AccelBatch with no values
``no_sample_rate``         too few distinct Imu stamps to estimate a rate
``inconsistent_unit``      a slow point in another unit than its signal's earlier points
``unknown_channel``        a message names a channel id no Channel record in the file defines
``absurd_chunk_size``      a chunk claims an uncompressed size beyond the limits
``chunk_crc_mismatch``     a chunk's data does not match its ``uncompressed_crc``
``chunk_decompression_``   the compressed data of a chunk does not decompress
``error``
``chunk_size_mismatch``    a chunk decompresses to another size than it states
``unknown_compression``    a chunk compression other than ``""``, ``zstd``, ``lz4``
``bad_chunk``              a chunk record too short for its own header fields
``bad_chunk_record``       a record inside a chunk runs past the chunk's end
``bad_record``             a record too short for its own fields
``oversized_record``       a top-level record longer than :data:`MAX_RECORD_BYTES` (skipped)
``truncated_record``       the file ends inside a record, or before its DataEnd record
``lost_sync``              a record's length field points past the end of the file or off the
                           record chain; the bytes up to the next plausible record are skipped
                           (counted once, whatever they held)
=========================  ===================================================================

The first position of each reason names the chunk and the message record's offset in it.
A ``.mcap.gz`` whose gzip stream breaks off is read up to the break (``truncated_stream``,
counted by :func:`rigtools.ingest.files.open_source`): the complete chunks before it are
kept. AccelBatch payloads that name the same channel on several topics are kept apart as
``<channel>@<topic>`` (with a warning).

The limits are :data:`~rigtools.ingest.mcap.decompress.MAX_CHUNK_UNCOMPRESSED_BYTES`,
:data:`~rigtools.ingest.mcap.decompress.MAX_CHUNK_RATIO` (above
:data:`~rigtools.ingest.mcap.decompress.FREE_CHUNK_BYTES`),
:data:`~rigtools.ingest.mcap.container.MAX_RECORD_BYTES` and
:data:`~rigtools.ingest.mcap.container.MAX_DEFERRED_BYTES`. How the
messages of a refused chunk are counted, and when a message that comes before its Channel
record is still read, and how lying length fields and damaged Schema/Channel records are
handled, is told in :mod:`rigtools.ingest.mcap.container`.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import BinaryIO, Final, TypeVar

from rigtools.errors import MappingError, SchemaUnusableError
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.contract import ReadRequest
from rigtools.ingest.layout import ChannelMapping, SlowSpec, UniformSpec
from rigtools.ingest.mcap.container import ContainerScanner
from rigtools.ingest.mcap.decoders import (
    ACCEL_BATCH_SCHEMA_NAME,
    SLOW_VALUE_SCHEMA_NAME,
    decoder_for,
)
from rigtools.ingest.mcap.handlers import (
    BatchHandler,
    ChannelHandler,
    HandlerContext,
    ImuHandler,
    MappedHandler,
    RejectHandler,
    ScalarHandler,
    SlowValueHandler,
)
from rigtools.ingest.mcap.records import MAGIC, ChannelRecord, SchemaRecord
from rigtools.ingest.recording import IngestReport
from rigtools.ingest.stream_reader import Decoded, StreamReader

__all__ = ["NAME", "READER", "RUN_METADATA_NAME", "McapReader", "ingest", "sniff"]

#: Format name in :data:`rigtools.ingest.registry.READERS`.
NAME: Final = "mcap"
#: Name of the Metadata record holding run metadata (keys ``run_id``, ``rig``, ``gear_set``,
#: ``conditions.<name_with_unit>``; values as strings).
RUN_METADATA_NAME: Final = "rigtools.run"

_Spec = TypeVar("_Spec", UniformSpec, SlowSpec)


def sniff(head: bytes) -> bool:
    r"""True when ``head`` starts with the MCAP magic ``\x89MCAP0\r\n``."""
    return head[: len(MAGIC)] == MAGIC


# --------------------------------------------------------------------------------------
# Choosing a handler per channel
# --------------------------------------------------------------------------------------


def _handler_for(ctx: HandlerContext, ch: ChannelRecord, schema: SchemaRecord | None,
                 by_topic: dict[str, list[UniformSpec | SlowSpec]]) -> ChannelHandler:
    """The handler of one channel, from its decoder and the mapping's entries for its topic."""
    sname = schema.name if schema else "(none)"
    senc = schema.encoding if schema else "(none)"
    if by_topic and ch.topic not in by_topic:
        ctx.warn_once("not_in_mapping", ch.id, f"{ctx.path}: topic {ch.topic!r} is not "
                      "in the mapping; its messages are counted as not_in_mapping")
        return RejectHandler(ctx, ch, "not_in_mapping")
    specs = by_topic.get(ch.topic, [])
    try:
        dec = decoder_for(ch.message_encoding, schema)
        if specs and (dec is None or dec.kind not in ("batch", "slow")):
            dec = decoder_for(ch.message_encoding, schema, generic=True)
    except SchemaUnusableError as exc:
        ctx.warn_once("bad_schema", ch.id, f"{ctx.path}: topic {ch.topic!r}: schema "
                      f"{sname!r} ({senc}) not usable: {exc}; its messages are counted "
                      "as bad_schema")
        return RejectHandler(ctx, ch, "bad_schema")
    if dec is None:
        ctx.warn_once("no_decoder", ch.id, f"{ctx.path}: no decoder for topic "
                      f"{ch.topic!r} (channel {ch.id}): message encoding "
                      f"{ch.message_encoding!r}, schema {sname!r} ({senc}); its messages "
                      "are counted as no_decoder")
        return RejectHandler(ctx, ch, "no_decoder")
    if dec.kind == "batch":
        batch_spec = _only_spec(ctx, ch, specs, UniformSpec, "values",
                                ACCEL_BATCH_SCHEMA_NAME) if specs else None
        return BatchHandler(ctx, ch, dec, batch_spec)
    if dec.kind == "slow":
        slow_spec = _only_spec(ctx, ch, specs, SlowSpec, "value",
                               SLOW_VALUE_SCHEMA_NAME) if specs else None
        return SlowValueHandler(ctx, ch, dec, slow_spec)
    if specs:
        return MappedHandler(ctx, ch, dec, specs)
    if dec.kind == "imu":
        return ImuHandler(ctx, ch, dec)
    return ScalarHandler(ctx, ch, dec)


def _only_spec(ctx: HandlerContext, ch: ChannelRecord, specs: list[UniformSpec | SlowSpec],
               spec_type: type[_Spec], field: str, schema_name: str) -> _Spec:
    """The one mapping entry a topic of a rigtools message may have: the whole payload.

    Raises
    ------
    MappingError
        More than one entry, an entry of the other kind, or a field other than ``field``.
    """
    only = specs[0] if len(specs) == 1 else None
    if not isinstance(only, spec_type) or only.field != field:
        section = "[[uniform]]" if spec_type is UniformSpec else "[[slow]]"
        raise MappingError(ctx.mapping_source, f"topic {ch.topic!r}",
                           f"one {section} entry with field = \"{field}\" for a "
                           f"{schema_name} topic",
                           ", ".join(f"{type(s).__name__} field {s.field!r}" for s in specs))
    return only


def _keep_channels_apart(ctx: HandlerContext, handlers: Iterable[ChannelHandler]) -> None:
    """Rename AccelBatch channels that payloads on several topics name alike.

    Two sensors both saying ``accel_1`` on ``/accel/a`` and ``/accel/b`` would otherwise
    fall into one channel, half their samples dropped as duplicates: each becomes
    ``accel_1@/accel/a``, ``accel_1@/accel/b``, with a warning. Messages of one topic on
    several MCAP channels stay together.
    """
    batch = [h for h in handlers if isinstance(h, BatchHandler) and h.spec is None]
    topics: dict[str, set[str]] = {}
    for h in batch:
        for name in h.channel_names():
            topics.setdefault(name, set()).add(h.channel.topic)
    shared = {name for name, where in topics.items() if len(where) > 1}
    if not shared:
        return
    for name in sorted(shared):
        ctx.report.warn(f"{ctx.path}: channel {name!r} is named by the AccelBatch payloads of "
                        f"topics {', '.join(map(repr, sorted(topics[name])))}; kept apart as "
                        + ", ".join(repr(f"{name}@{t}") for t in sorted(topics[name])))
    for h in batch:
        h.rename_shared(shared)


def _specs_by_topic(mapping: ChannelMapping | None) -> dict[str, list[UniformSpec | SlowSpec]]:
    """The mapping's MCAP entries (those naming a topic), by topic, in mapping order."""
    by_topic: dict[str, list[UniformSpec | SlowSpec]] = {}
    if mapping is not None:
        specs: list[UniformSpec | SlowSpec] = [*mapping.uniform, *mapping.slow]
        for spec in specs:
            if spec.topic is not None:
                by_topic.setdefault(spec.topic, []).append(spec)
    return by_topic


# --------------------------------------------------------------------------------------
# Ingest
# --------------------------------------------------------------------------------------


def ingest(
    stream: BinaryIO,
    path: str,
    builder: RecordingBuilder,
    report: IngestReport,
    mapping: ChannelMapping | None,
    clock: str = "header",
) -> dict[str, str]:
    """Read an MCAP stream into a builder.

    Parameters
    ----------
    stream : binary file object
        The MCAP data, from its first byte.
    path : str
        Source path, for messages and errors.
    builder : RecordingBuilder
        Receives uniform channels and slow signals.
    report : IngestReport
        Receives the tallies (``units`` set to ``"messages"``).
    mapping : ChannelMapping or None
        When it has MCAP entries (``topic`` and ``field``), only the topics it names are
        read, into the channels it names; otherwise every topic with a known decoder is
        read (see :mod:`rigtools.ingest.mcap.decoders`).
    clock : {"header", "log_time"}
        The clock that places channels whose messages have a header stamp; the other is kept
        as a second clock of the channel (``report.timebase[f"{channel}@{other}"]``). See
        :func:`rigtools.ingest.read` (``mcap_clock``).

    Returns
    -------
    dict of str to str
        The key/values of the Metadata record named ``rigtools.run`` (``run_id``, ``rig``,
        ``gear_set``, ``conditions.<name_with_unit>``); empty when there is none.

    Raises
    ------
    RecordingFormatError
        Empty file, or no MCAP magic at byte 0.
    MappingError
        The mapping names a field none of a topic's messages has, or one that holds no
        number in any of them (messages lacking it among others are counted instead).
    ValueError
        ``clock`` is neither ``"header"`` nor ``"log_time"``.
    """
    report.units = "messages"
    scanner = ContainerScanner(stream, path, report)
    by_topic = _specs_by_topic(mapping)
    source = (mapping.source or "<mapping>") if mapping is not None else "<mapping>"
    if clock not in ("header", "log_time"):
        raise ValueError(f"clock must be 'header' or 'log_time', not {clock!r}")
    ctx = HandlerContext(path, builder, report, source, clock=clock)
    handlers: dict[int, ChannelHandler] = {}
    for block in scanner.blocks():
        for cid, group in block.by_channel():
            h = handlers.get(cid)
            if h is None:
                ch = scanner.channels[cid]
                schema = scanner.schemas.get(ch.schema_id) if ch.schema_id else None
                h = handlers[cid] = _handler_for(ctx, ch, schema, by_topic)
            h.add(group)
    _keep_channels_apart(ctx, handlers.values())
    for h in handlers.values():
        h.finish()
    seen = {ch.topic for ch in scanner.channels.values()}
    for topic in sorted(set(by_topic) - seen):
        report.warn(f"{path}: the mapping names topic {topic!r}, which the file does not have")
    return dict(scanner.metadata.get(RUN_METADATA_NAME, {}))


class McapReader(StreamReader):
    """MCAP in the registry: :func:`sniff`, and :func:`ingest` as the stream decoder."""

    name = NAME
    units = "messages"

    def __repr__(self) -> str:
        return "McapReader()"

    def sniff(self, head: bytes) -> bool:
        r"""True when ``head`` starts with the MCAP magic ``\x89MCAP0\r\n``."""
        return sniff(head)

    def decode(
        self,
        stream: BinaryIO,
        path: str,
        builder: RecordingBuilder,
        report: IngestReport,
        mapping: ChannelMapping | None,
        request: ReadRequest,
    ) -> Decoded:
        """Read the MCAP stream with :func:`ingest` (clock: ``request.mcap_clock``).

        See :meth:`rigtools.ingest.stream_reader.StreamReader.decode` for the parameters.
        """
        metadata = ingest(stream, path, builder, report, mapping, clock=request.mcap_clock)
        layout: dict[str, object] = {"source": "mapping" if mapping else "mcap-schemas"}
        if mapping is not None:
            layout["mapping"] = mapping.to_dict()
        return Decoded(layout, metadata)


#: This format in :data:`rigtools.ingest.registry.READERS`.
READER: Final = McapReader()
