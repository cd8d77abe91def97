"""Channel layouts: which CAN signals or MCAP fields make which rigtools channel.

Two sources:

* the DBC itself, through three message attributes of the reference layout
  (``data_schemas/rig_reference.dbc``): ``RigSampleRate`` (Hz) marks a message as a uniform
  channel, ``RigChannel`` names it, ``RigCounter`` names its sample counter; the remaining
  signals of such a message are consecutive samples in start-bit order. Every signal of a
  message without ``RigSampleRate`` becomes a slow signal named after the signal;
* a user mapping file (TOML, schema ``data_schemas/channel_mapping.schema.json``) for any other
  DBC or MCAP layout, which then replaces the DBC's own description.
"""

from __future__ import annotations

import functools
import math
import re
import tomllib
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from rigtools.errors import DbcError, MappingError
from rigtools.ingest.recording import RunMetadata
from rigtools.schemas import iter_errors

__all__ = [
    "CanLayout",
    "ChannelMapping",
    "SlowSpec",
    "UniformSpec",
    "can_layout",
    "load_mapping",
]


@dataclass(frozen=True)
class UniformSpec:
    """A uniform channel built from CAN signals or an MCAP field.

    Attributes
    ----------
    channel : str
    sample_rate_Hz : float
    message : str or int or None
        CAN: DBC message name or frame id.
    samples : tuple of str
        CAN: signals holding consecutive samples, in time order.
    counter : str or None
        CAN: counter signal (one tick per frame).
    topic, field : str or None
        MCAP: topic and dotted field path.
    unit : str or None
        Unit after ``scale``/``offset``; None keeps the source's unit.
    scale, offset : float
        Conversion at the edge: ``value * scale + offset``.
    """

    channel: str
    sample_rate_Hz: float
    message: str | int | None = None
    samples: tuple[str, ...] = ()
    counter: str | None = None
    topic: str | None = None
    field: str | None = None
    unit: str | None = None
    scale: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class SlowSpec:
    """A slow signal from one CAN signal or one MCAP field (see :class:`UniformSpec`)."""

    name: str
    message: str | int | None = None
    signal: str | None = None
    topic: str | None = None
    field: str | None = None
    unit: str | None = None
    scale: float = 1.0
    offset: float = 0.0


@dataclass(frozen=True)
class ChannelMapping:
    """A user mapping file, parsed and validated."""

    uniform: tuple[UniformSpec, ...] = ()
    slow: tuple[SlowSpec, ...] = ()
    run: RunMetadata | None = None
    source: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form (recorded in provenance)."""
        return {
            "source": self.source,
            "uniform": [asdict(u) for u in self.uniform],
            "slow": [asdict(s) for s in self.slow],
        }


def _line_of(text: str, key: str) -> str | None:
    for i, line in enumerate(text.splitlines(), 1):
        if re.match(rf"\s*{re.escape(key)}\s*=", line) or re.match(
            rf"\s*\[\[?\s*{re.escape(key)}\s*\]\]?", line
        ):
            return f"line {i}"
    return None


def load_mapping(path: str | Path) -> ChannelMapping:
    """Read and validate a mapping file.

    Raises
    ------
    MappingError
        Not TOML, or a key or value the schema does not allow; the message names the key and
        its line.
    """
    p = Path(path)
    try:
        st = p.stat()
    except OSError:
        return _load_mapping(p)  # raises the error of a missing or unreadable file
    if not p.is_file():
        return _load_mapping(p)
    m = _load_mapping_cached(str(p), st.st_mtime_ns, st.st_size)
    if m.run is None:
        return m
    # the run metadata holds dicts a caller may change: each read gets its own
    run = m.run
    return ChannelMapping(m.uniform, m.slow, RunMetadata(run.run_id, run.rig, run.gear_set,
                                                         dict(run.conditions),
                                                         dict(run.extra)), m.source)


@functools.lru_cache(maxsize=8)
def _load_mapping_cached(path: str, mtime_ns: int, size: int) -> ChannelMapping:
    """A mapping file parsed and validated once per file version (the result is frozen)."""
    return _load_mapping(Path(path))


def _load_mapping(p: Path) -> ChannelMapping:
    """Read and validate a mapping file (see :func:`load_mapping`)."""
    try:
        text = p.read_text(encoding="utf-8")
        doc = tomllib.loads(text)
    except FileNotFoundError:
        raise MappingError(p, None, "a mapping file", "no such file") from None
    except IsADirectoryError:
        raise MappingError(p, None, "a mapping file", "a directory") from None
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise MappingError(p, None, "a TOML mapping file", None, str(exc)) from exc
    errors = iter_errors(doc, "channel_mapping.schema.json")
    if errors:
        where, msg = errors[0]
        m = re.search(r"'([^']+)' was unexpected", msg)
        key = m.group(1) if m else where.rsplit(".", 1)[-1].split("[")[0]
        raise MappingError(p, _line_of(text, key), "keys and values allowed by "
                           "data_schemas/channel_mapping.schema.json", f"{where}: {msg}")
    uniform = tuple(
        UniformSpec(
            channel=u["channel"],
            sample_rate_Hz=float(u["sample_rate_Hz"]),
            message=u.get("message"),
            samples=tuple(u.get("samples", ())),
            counter=u.get("counter"),
            topic=u.get("topic"),
            field=u.get("field"),
            unit=u.get("unit"),
            scale=float(u.get("scale", 1.0)),
            offset=float(u.get("offset", 0.0)),
        )
        for u in doc.get("uniform", [])
    )
    slow = tuple(
        SlowSpec(
            name=s["name"],
            message=s.get("message"),
            signal=s.get("signal"),
            topic=s.get("topic"),
            field=s.get("field"),
            unit=s.get("unit"),
            scale=float(s.get("scale", 1.0)),
            offset=float(s.get("offset", 0.0)),
        )
        for s in doc.get("slow", [])
    )
    for kind, entries in (("uniform", uniform), ("slow", slow)):
        for i, e in enumerate(entries):
            for attr in ("sample_rate_Hz", "scale", "offset"):
                v = getattr(e, attr, 0.0)
                if not math.isfinite(v):
                    raise MappingError(p, _line_of(text, attr), f"a finite number for "
                                       f"{kind}[{i}].{attr}", repr(v))
    if "run" in doc:
        for k, v in doc["run"].get("conditions", {}).items():
            if not math.isfinite(float(v)):
                raise MappingError(p, _line_of(text, "conditions"),
                                   f"a finite number for run.conditions.{k}", repr(v))
    names = [u.channel for u in uniform] + [s.name for s in slow]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise MappingError(p, _line_of(text, "channel"), "unique channel names", f"{dup}")
    run = RunMetadata.from_dict(doc["run"]) if "run" in doc else None
    return ChannelMapping(uniform, slow, run, str(p))


@dataclass(frozen=True)
class CanUniform:
    """A resolved uniform CAN channel: the cantools message and signal objects."""

    spec: UniformSpec
    message: Any
    samples: tuple[Any, ...]
    counter: Any | None
    unit: str


@dataclass(frozen=True)
class CanSlow:
    """A resolved slow CAN signal."""

    spec: SlowSpec
    message: Any
    signal: Any
    unit: str


@dataclass(frozen=True)
class CanLayout:
    """Everything the CAN assembler needs, resolved against a loaded DBC.

    Attributes
    ----------
    db : cantools.database.can.Database
    uniform : tuple of CanUniform
    slow : tuple of CanSlow
    description : dict
        JSON-ready description for provenance.
    """

    db: Any
    uniform: tuple[CanUniform, ...]
    slow: tuple[CanSlow, ...]
    description: dict[str, Any] = field(default_factory=dict)

    def messages_used(self) -> dict[tuple[int, bool], Any]:
        """(frame id, extended) -> cantools message, for every message the layout reads."""
        used: dict[tuple[int, bool], Any] = {}
        for u in self.uniform:
            used[(u.message.frame_id, bool(u.message.is_extended_frame))] = u.message
        for s in self.slow:
            used[(s.message.frame_id, bool(s.message.is_extended_frame))] = s.message
        return used


def _attr(message: Any, name: str) -> Any:
    if message.dbc is None or name not in message.dbc.attributes:
        return None
    return message.dbc.attributes[name].value


def _find_message(db: Any, ref: str | int, where: str) -> Any:
    try:
        if isinstance(ref, int):
            return db.get_message_by_frame_id(ref)
        return db.get_message_by_name(ref)
    except KeyError:
        raise MappingError(where, None, "a message that exists in the DBC",
                           f"no message {ref!r}") from None


def _find_signal(message: Any, name: str, where: str) -> Any:
    try:
        return message.get_signal_by_name(name)
    except KeyError:
        raise MappingError(where, None, f"a signal of message {message.name!r}",
                           f"no signal {name!r}") from None


def can_layout(db: Any, mapping: ChannelMapping | None = None, dbc_path: str = "") -> CanLayout:
    """Resolve the channel layout for a DBC, from a mapping or from the DBC's attributes."""
    uniform: list[CanUniform] = []
    slow: list[CanSlow] = []
    if mapping is not None and (mapping.uniform or mapping.slow):
        where = mapping.source or "<mapping>"
        for u in mapping.uniform:
            if u.message is None:
                continue  # an MCAP entry in a shared mapping
            msg = _find_message(db, u.message, where)
            sigs = tuple(_find_signal(msg, s, where) for s in u.samples)
            cnt = _find_signal(msg, u.counter, where) if u.counter else None
            unit = u.unit if u.unit is not None else (sigs[0].unit or "")
            uniform.append(CanUniform(u, msg, sigs, cnt, unit))
        for s in mapping.slow:
            if s.message is None:
                continue
            msg = _find_message(db, s.message, where)
            sig = _find_signal(msg, s.signal or "", where)
            slow.append(CanSlow(s, msg, sig, s.unit if s.unit is not None else (sig.unit or "")))
        if not uniform and not slow:
            raise MappingError(mapping.source or "<mapping>", None,
                               "[[uniform]] or [[slow]] entries naming a DBC message",
                               "only MCAP entries (topic/field), and this file is a CAN log")
        desc = {"source": "mapping", "mapping": mapping.to_dict(), "dbc": dbc_path}
        return CanLayout(db, tuple(uniform), tuple(slow), desc)
    for msg in db.messages:
        rate = _attr(msg, "RigSampleRate")
        if rate:
            counter_name = _attr(msg, "RigCounter") or None
            counter = None
            if counter_name:
                try:
                    counter = msg.get_signal_by_name(counter_name)
                except KeyError:
                    raise DbcError(dbc_path, f"message {msg.name!r}",
                                   "RigCounter to name a signal of the message",
                                   repr(counter_name)) from None
            samples = tuple(
                sorted((s for s in msg.signals if s is not counter), key=lambda s: s.start)
            )
            if not samples:
                raise DbcError(dbc_path, f"message {msg.name!r}",
                               "sample signals in a RigSampleRate message", "none")
            name = _attr(msg, "RigChannel") or msg.name
            spec = UniformSpec(
                channel=name,
                sample_rate_Hz=float(rate),
                message=msg.name,
                samples=tuple(s.name for s in samples),
                counter=counter_name,
            )
            uniform.append(CanUniform(spec, msg, samples, counter, samples[0].unit or ""))
        else:
            for sig in msg.signals:
                if sig.is_multiplexer:
                    continue
                spec_s = SlowSpec(name=sig.name, message=msg.name, signal=sig.name)
                slow.append(CanSlow(spec_s, msg, sig, sig.unit or ""))
    counts: dict[str, int] = {}
    for c in slow:
        counts[c.spec.name] = counts.get(c.spec.name, 0) + 1
    slow = [
        CanSlow(SlowSpec(f"{c.message.name}.{c.spec.name}", c.message.name, c.spec.signal),
                c.message, c.signal, c.unit) if counts[c.spec.name] > 1 else c
        for c in slow
    ]
    desc = {"source": "dbc-attributes", "dbc": dbc_path}
    return CanLayout(db, tuple(uniform), tuple(slow), desc)
