"""MCAP reader: a streaming container walk, payload decoders and per-channel handlers.

The reader is built in layers, one module each:

===========================================  =====================================================
module                                       what it holds
===========================================  =====================================================
:mod:`~rigtools.ingest.mcap.records`         magic, opcodes, record parsers that check every
                                             length
:mod:`~rigtools.ingest.mcap.source`          sequential reads that never allocate past the data
:mod:`~rigtools.ingest.mcap.decompress`      chunk size limits, bounded zstd/lz4 decompression,
                                             CRC
:mod:`~rigtools.ingest.mcap.walk`            the records inside a chunk, messages by channel
:mod:`~rigtools.ingest.mcap.container`       the streaming record walk (:func:`iter_messages`);
                                             ``definitions`` (Schema/Channel records, summary
                                             first), ``resync`` (lying length fields)
:mod:`~rigtools.ingest.mcap.payloads`        the rigtools message types and the decoder record
:mod:`~rigtools.ingest.mcap.decoders`        payload decoders chosen by message encoding and
                                             schema: ``protobuf``, ``protobuf_batch``, ``json``,
                                             ``ros2``
:mod:`~rigtools.ingest.mcap.cdr`             ROS 2 (CDR) messages of one constant layout read a
                                             chunk at a time (per-sample Imu and sensor
                                             streams); ``cdr_imu`` (Imu), ``cdr_rows`` (block
                                             checks)
:mod:`~rigtools.ingest.mcap.timing`          Imu grids fitted to stamps, counter restarts
:mod:`~rigtools.ingest.mcap.handlers`        per-channel handlers feeding the builder;
                                             ``handler_base``, ``signal_handlers``
:mod:`~rigtools.ingest.mcap.reader`          :func:`sniff`, :func:`ingest` and the format's
                                             entry in the registry (:data:`READER`)
===========================================  =====================================================

This package re-exports the reader's entry points and its limits.
"""

from rigtools.ingest.mcap.container import (
    MAX_DEFERRED_BYTES,
    MAX_RECORD_BYTES,
    RawMessage,
    iter_messages,
)
from rigtools.ingest.mcap.decompress import (
    FREE_CHUNK_BYTES,
    MAX_CHUNK_RATIO,
    MAX_CHUNK_UNCOMPRESSED_BYTES,
)
from rigtools.ingest.mcap.reader import (
    NAME,
    READER,
    RUN_METADATA_NAME,
    McapReader,
    ingest,
    sniff,
)
from rigtools.ingest.mcap.records import MAGIC, ChannelRecord

__all__ = [
    "FREE_CHUNK_BYTES",
    "MAGIC",
    "MAX_CHUNK_RATIO",
    "MAX_CHUNK_UNCOMPRESSED_BYTES",
    "MAX_DEFERRED_BYTES",
    "MAX_RECORD_BYTES",
    "NAME",
    "READER",
    "RUN_METADATA_NAME",
    "ChannelRecord",
    "McapReader",
    "RawMessage",
    "ingest",
    "iter_messages",
    "sniff",
]
