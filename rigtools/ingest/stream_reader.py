"""The read every stream format shares: a file decoded into a builder, hashed, provenance kept.

CAN logs (:class:`rigtools.ingest.can.reader.CanLogReader`) and MCAP
(:class:`rigtools.ingest.mcap.reader.McapReader`) differ only in how they decode the bytes of
the file into a :class:`~rigtools.ingest.builder.RecordingBuilder`; :class:`StreamReader` holds
everything around that (a template method: the shared read here, the one hook
:meth:`StreamReader.decode` in each subclass): the file opened with gzip unwrapped and its
damage counted, the SHA-256 computed in a second thread, the Recording built with its
provenance and run metadata, and a file holding no data refused.
"""

from __future__ import annotations

import contextlib
import dataclasses
import functools
import json
import math
import re
import sys
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path
from typing import Any, BinaryIO, Final

from rigtools.errors import NoDataError
from rigtools.ingest.builder import RecordingBuilder
from rigtools.ingest.contract import ReadRequest
from rigtools.ingest.files import open_source, source_sha256
from rigtools.ingest.layout import ChannelMapping, load_mapping
from rigtools.ingest.recording import IngestReport, Provenance, Recording, RunMetadata

__all__ = ["PROGRESS_INTERVAL_S", "Decoded", "StreamReader", "versions"]

#: Time between two progress reports of a read (s).
PROGRESS_INTERVAL_S: Final = 0.2

# Condition keys carry their unit (data_schemas/run_metadata.schema.json).
_CONDITION_KEY = re.compile(r"^[a-z][a-z0-9_]*_(Nm|C|K|rpm|Hz|s|m|um|kW|bar|Pa)$")


@functools.cache
def _versions() -> tuple[tuple[str, str], ...]:
    out = [("python", sys.version.split()[0])]
    for dist in ("rigtools", "numpy", "pyarrow", "mcap", "mcap-ros2-support", "python-can",
                 "cantools", "protobuf"):
        try:
            out.append((dist, version(dist)))
        except PackageNotFoundError:
            out.append((dist, "not installed"))
    return tuple(out)


def versions() -> dict[str, str]:
    """Versions of rigtools, Python and the libraries readers use."""
    return dict(_versions())


@dataclass(frozen=True)
class Decoded:
    """What a stream decoder tells the shared read besides the blocks it gave the builder.

    Attributes
    ----------
    layout : dict
        The channel layout used (DBC path and hash, or the mapping), JSON-ready; kept in the
        provenance.
    metadata : dict of str to str
        Run metadata the file carries (``run_id``, ``rig``, ``gear_set``,
        ``conditions.<name_with_unit>``); empty when it carries none.
    """

    layout: dict[str, Any]
    metadata: dict[str, str] = field(default_factory=dict)


class StreamReader(ABC):
    """A format decoded from a byte stream into a builder; :meth:`read` is shared.

    Subclasses set :attr:`name` and :attr:`units` and implement :meth:`sniff` and
    :meth:`decode`. The file's SHA-256 for the provenance is computed from the bytes as the
    decoder reads them (:func:`rigtools.ingest.files.source_sha256`): no second pass over the
    file, no thread of its own.

    Attributes
    ----------
    name : str
        Format name (the registry key, the ``reader`` of the provenance).
    units : str
        What the report counts: ``"frames"`` or ``"messages"``.
    """

    name: str
    units: str

    @abstractmethod
    def sniff(self, head: bytes) -> bool:
        """True when the first bytes of a file (gzip unwrapped) are of this format."""

    @abstractmethod
    def decode(
        self,
        stream: BinaryIO,
        path: str,
        builder: RecordingBuilder,
        report: IngestReport,
        mapping: ChannelMapping | None,
        request: ReadRequest,
    ) -> Decoded:
        """Decode the whole stream into ``builder``, counting what is lost in ``report``.

        Parameters
        ----------
        stream : BinaryIO
            The file from its first byte, gzip unwrapped.
        path : str
            File name for messages and errors.
        builder : RecordingBuilder
            Receives the blocks of samples and slow-signal points.
        report : IngestReport
            Receives the tallies.
        mapping : ChannelMapping or None
            The request's mapping, loaded.
        request : ReadRequest
            The other options of the read.
        """

    def read(self, path: Path, request: ReadRequest) -> Recording:
        """Read the file into a Recording (see :func:`rigtools.ingest.read`).

        Raises
        ------
        RecordingFormatError
            The file is unreadable, or damaged so that nothing intact can be returned.
        DbcError, MappingError
            The DBC or the mapping does not load or does not match the file.
        NoDataError
            The file reads but holds no decodable channel or slow signal.
        """
        mapping = request.mapping
        if isinstance(mapping, str | Path):
            mapping = load_mapping(mapping)
        report = IngestReport(units=self.units)
        builder = RecordingBuilder(str(path), report)
        with open_source(path, report) as stream, _watching(stream, path, request.progress):
            decoded = self.decode(stream, str(path), builder, report, mapping, request)
            # CAN logs are read in order, MCAP at positions (its chunk worker too): either way
            # the bytes were hashed as they were read; this hashes only what was left unread
            own_digest = source_sha256(stream)
            assert own_digest is not None  # open_source's streams always hash their file
        meta = _merge_metadata(decoded.metadata, mapping, request.metadata, report)
        # Through JSON once, so the layout compares equal after a Parquet round trip.
        layout_desc = json.loads(json.dumps(decoded.layout))
        placeholder = Provenance(str(path), "", 0, self.name, versions(), report, layout_desc)
        rec = builder.build(meta, placeholder)
        digest, size = own_digest
        rec = dataclasses.replace(rec, provenance=dataclasses.replace(
            rec.provenance, source_sha256=digest, source_size_bytes=size))
        if not rec.channels and not rec.slow:
            reasons = ", ".join(f"{k}: {v}" for k, v in sorted(report.rejected.items())) or "none"
            raise NoDataError(
                path, None, "at least one decodable channel or slow signal",
                f"none ({report.decoded} {report.units} decoded; rejected {reasons})",
            )
        return rec


@contextlib.contextmanager
def _watching(stream: BinaryIO, path: Path, progress: Callable[[int, int], None] | None
              ) -> Iterator[None]:
    """Report how far ``stream`` is read, every :data:`PROGRESS_INTERVAL_S`, from a thread."""
    if progress is None:
        yield
        return
    total = path.stat().st_size
    consumed = getattr(stream, "consumed", None)
    stop = threading.Event()

    def watch() -> None:
        while not stop.wait(PROGRESS_INTERVAL_S):
            if consumed is not None:
                progress(min(int(consumed()), total), total)

    watcher = threading.Thread(target=watch, name="rigtools-progress", daemon=True)
    watcher.start()
    try:
        yield
    finally:
        stop.set()
        watcher.join()
    progress(total, total)


def _merge_metadata(
    extra: dict[str, str],
    mapping: ChannelMapping | None,
    given: RunMetadata | None,
    report: IngestReport,
) -> RunMetadata:
    if given is not None:
        return given
    if mapping is not None and mapping.run is not None:
        return mapping.run
    conditions: dict[str, float] = {}
    rest: dict[str, str] = {}
    for k, v in extra.items():
        if k.startswith("conditions."):
            name = k.removeprefix("conditions.")
            try:
                value = float(v)
            except ValueError:
                value = math.nan
            if _CONDITION_KEY.match(name) and math.isfinite(value):
                conditions[name] = value
            else:  # kept, but not as a condition: no unit in the key, or not a number
                rest[k] = str(v)
                report.warn(f"run metadata {k!r} = {v!r} is not a condition (a finite number "
                            "under a key ending in its unit, e.g. torque_Nm); kept as text")
        elif k not in ("run_id", "rig", "gear_set"):
            rest[k] = v
    return RunMetadata(extra.get("run_id"), extra.get("rig"), extra.get("gear_set"), conditions,
                       rest)
