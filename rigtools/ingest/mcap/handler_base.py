"""The base of the MCAP channel handlers: shared context, decoding and message positions.

:class:`ChannelHandler` is what every handler of :mod:`rigtools.ingest.mcap.handlers` is;
:class:`DecodingHandler` decodes each payload with its channel's decoder and counts those
that do not decode as ``decode_error``.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

from rigtools.errors import PayloadDecodeError
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.mcap.decoders import Decoder
from rigtools.ingest.mcap.records import (
    MESSAGE_HEADER_BYTES,
    RECORD_HEADER_BYTES,
    ChannelRecord,
)
from rigtools.ingest.mcap.walk import MessageBlock, ScannedMessage
from rigtools.ingest.recording import IngestReport

__all__ = [
    "ChannelHandler",
    "DecodingHandler",
    "HandlerContext",
    "RejectHandler",
    "message_position",
]


@dataclass
class HandlerContext:
    """What every handler of one ingest shares.

    Attributes
    ----------
    path : str
        Source path, for messages.
    builder : RecordingBuilder
        Receives uniform channels and slow signals.
    report : IngestReport
        Receives the tallies and warnings.
    mapping_source : str
        Where the mapping came from, for :class:`~rigtools.errors.MappingError`.
    clock : str
        ``"header"`` or ``"log_time"``: the clock that places a channel whose messages have
        a header stamp; the other is handed to the builder as a second clock
        (:meth:`~rigtools.ingest.builder.RecordingBuilder.add_other_clock`).
    """

    path: str
    builder: RecordingBuilder
    report: IngestReport
    mapping_source: str
    clock: str = "header"
    _warned: set[tuple[str, object]] = field(default_factory=set)

    def warn_once(self, reason: str, key: object, text: str) -> None:
        """Warn with ``text`` the first time ``(reason, key)`` comes up."""
        if (reason, key) not in self._warned:
            self._warned.add((reason, key))
            self.report.warn(text)


class ChannelHandler:
    """Turns the messages of one channel into builder input; subclasses per payload kind.

    Parameters
    ----------
    ctx : HandlerContext
    channel : ChannelRecord
    """

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord) -> None:
        self.ctx = ctx
        self.channel = channel

    def add(self, block: MessageBlock) -> None:
        """Take one block of the channel's messages (in file order).

        ``block.where`` tells where it was found, for tallies; ``block.buf`` is the block's
        common buffer (a chunk's uncompressed data) when it has one.
        """
        raise NotImplementedError

    def finish(self) -> None:
        """Hand anything collected over the whole file to the builder."""


class RejectHandler(ChannelHandler):
    """A channel none of whose messages is used: each counts under ``reason``."""

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, reason: str) -> None:
        super().__init__(ctx, channel)
        self.reason = reason

    def add(self, block: MessageBlock) -> None:
        """Count the block's messages."""
        self.ctx.report.reject(self.reason, len(block), block.where)


#: Bytes of a Message record ahead of its payload (record header and message header).
_PAYLOAD_OFFSET = RECORD_HEADER_BYTES + MESSAGE_HEADER_BYTES


def message_position(where: str, i: int, m: ScannedMessage) -> str:
    """Where message ``m`` (the ``i``-th of a block found at ``where``) lies, for tallies.

    ``"chunk at byte 1234 +567"`` (the chunk's position in the file, the message record's
    offset in its uncompressed records) for a chunk's message; for messages found outside
    chunks, the block's position and the message's rank in it.
    """
    if m[5] >= 0:
        return f"chunk at {where} +{m[5] - _PAYLOAD_OFFSET}"
    return f"{where}, message {i + 1} from there"


class DecodingHandler(ChannelHandler):
    """A handler that decodes each payload with its channel's decoder."""

    def __init__(self, ctx: HandlerContext, channel: ChannelRecord, decoder: Decoder) -> None:
        super().__init__(ctx, channel)
        self.decode = decoder.decode

    def _decoded(self, block: MessageBlock) -> Iterator[tuple[int, ScannedMessage, Any]]:
        """Each message (rank in the block, message, decoded payload); failures are counted.

        Besides :class:`PayloadDecodeError`, a payload whose numbers overflow or whose
        nesting exhausts the recursion limit counts as ``decode_error``: no such exception
        leaves the reader.
        """
        decode = self.decode
        for i, m in enumerate(block.messages()):
            try:
                payload = decode(m[4])
            except (PayloadDecodeError, OverflowError, RecursionError) as exc:
                self._decode_error(exc, message_position(block.where, i, m))
                continue
            yield i, m, payload

    def _decode_error(self, exc: Exception, where: str) -> None:
        self.ctx.report.reject("decode_error", 1, where)
        self.ctx.warn_once("decode_error", self.channel.id,
                           f"{self.ctx.path}: topic {self.channel.topic!r}: payload does not "
                           f"decode ({exc}) at {where}; such messages are counted as "
                           "decode_error")

