"""Decoding many ROS 2 (CDR) messages of one constant layout at once.

A driver that publishes one message per sample (``sensor_msgs/msg/Imu`` at 25.6 kHz, or a small
message of the rig's own) writes millions of payloads that differ only in their numbers: the
strings and sequences have the same length in every message (a driver's ``frame_id``), so every
field lies at the same offset in every payload. The MCAP handlers hand this module the payloads
of one channel in one chunk (byte ranges in the chunk's uncompressed data) and get the wanted
fields back as arrays, or None when the messages are not all laid out alike; the handler then
decodes that chunk's messages one by one with the general decoder. Correctness never depends on
the guess: the fast path answers only when it can vouch that the general decoder would give
the same values, bit for bit, for every message.

How a block is read
-------------------
1. *Layout of the first message.* Walked field by field, exactly as ``mcap-ros2-support``'s
   decoder reads it (the same parsed message definitions; ``builtin_interfaces/Time`` as that
   decoder defines it unless the schema does; primitives of 2, 4 and 8 bytes aligned to their
   size counted from the end of the 4-byte encapsulation header; a string or a sequence is a
   ``uint32`` length word followed by its elements; an empty message holds one ``uint8``). The
   walk notes the offset of every length word, every string and every primitive field, and gives
   up (None) on anything the general decoder would refuse or read past the end of the payload.
2. *The same layout in every message*, checked with array operations over all of them: the same
   payload length, the same 4 bytes of encapsulation header (so the same endianness, which the
   header's kind byte states: odd little-endian, even big-endian, as the general decoder takes
   it), and the same 4 bytes at every length word. A string's bytes must be those of the first
   message or all ASCII, so that they decode as UTF-8 as the first message's did (only the
   general decoder reads strings; the Imu reader does not).
3. *The fields*, read at their fixed offsets as NumPy arrays with the header's byte order and
   converted to float64 the way the handlers convert the general decoder's Python numbers
   (``bool`` as 0/1, integers and ``float32`` exactly, ``int64``/``uint64`` rounded to nearest).

When the payloads lie at equal distances in the buffer (one channel alone in its chunk, or
channels taking turns) the fields are strided views of the buffer; otherwise the bytes needed are
gathered with one fancy index. Either way the work in Python is per chunk, not per message.

``sensor_msgs/msg/Imu`` has its own reader (:func:`decode_imu_cdr_many`) that mirrors
:func:`~rigtools.ingest.mcap.ros2.decode_imu_cdr`, which reads the header stamp and the linear
acceleration at the offsets the ``frame_id`` length fixes; any other ``ros2msg`` schema goes
through :class:`Ros2BlockDecoder`, built from the schema text as the general decoder is.

This module holds :class:`Ros2BlockDecoder` and the layout walk; the Imu reader lives in
:mod:`rigtools.ingest.mcap.cdr_imu` and the byte-span checks and field reads both share in
:mod:`rigtools.ingest.mcap.cdr_rows` (their public names are re-exported here).
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final, NamedTuple

import numpy as np

from rigtools.ingest.mcap.cdr_imu import ImuColumns, decode_imu_cdr_many
from rigtools.ingest.mcap.cdr_rows import (
    PRIMITIVES,
    Leaf,
    Rows,
    checked_block,
    float_field,
    int_field,
    same_bytes,
    strings_decode,
)

__all__ = [
    "MAX_LAYOUT_NODES",
    "CdrLayout",
    "ImuColumns",
    "Ros2BlockDecoder",
    "Ros2Columns",
    "decode_imu_cdr_many",
    "path_parts",
]

#: A message whose layout walk visits more fields than this (nested arrays of messages) is
#: left to the general decoder.
MAX_LAYOUT_NODES: Final = 4096

#: Nesting (message in message) deeper than this is left to the general decoder.
_MAX_DEPTH: Final = 64
#: Integer types whose values times 1e9 stay within int64 (header stamp fields).
_SMALL_INTS: Final = frozenset(
    {"int8", "uint8", "byte", "char", "int16", "uint16", "int32", "uint32"}
)
#: Primitive arrays the general decoder hands on as ``bytes`` (not numbers as a whole).
_BYTES_ARRAYS: Final = frozenset({"uint8", "byte"})


@dataclass(frozen=True)
class CdrLayout:
    """Where everything lies in one CDR payload, as :meth:`Ros2BlockDecoder.layout` found it.

    Attributes
    ----------
    length : int
        Payload length (bytes), encapsulation header included.
    little_endian : bool
        From the kind byte of the encapsulation header (odd: little-endian).
    words : tuple of int
        Offsets of the ``uint32`` length words of strings and sequences.
    strings : tuple of (int, int)
        Offset and byte count of each string's characters (its NUL not included).
    leaves : dict
        Field path (tuple of names; element numbers of arrays of messages as decimal
        strings) to the primitive field or primitive array there.
    """

    length: int
    little_endian: bool
    words: tuple[int, ...]
    strings: tuple[tuple[int, int], ...]
    leaves: dict[tuple[str, ...], Leaf]


class Ros2Columns(NamedTuple):
    """Wanted fields of many ROS 2 messages read at once.

    Attributes
    ----------
    stamp_ns : numpy.ndarray or None
        int64 ``header.stamp`` (ns) of each message; None when the message type has no
        ``header.stamp.sec``/``nanosec`` (the handler then uses the MCAP log times).
    values : list of numpy.ndarray
        One float64 array of shape ``(m, k)`` per wanted field (``k`` its element count).
    """

    stamp_ns: np.ndarray | None
    values: list[np.ndarray]


# --------------------------------------------------------------------------------------
# Any ros2msg schema
# --------------------------------------------------------------------------------------


class _LayoutTooBigError(Exception):
    pass


def path_parts(path: str) -> tuple[str, ...]:
    """A dotted field path as :func:`~rigtools.ingest.mcap.ros2.get_field` splits it."""
    parts = []
    for part in re.split(r"\.|\[([0-9]+)\]", path):
        if part:
            parts.append(str(int(part)) if _is_index(part) else part)
    return tuple(parts)


def _is_index(part: str) -> bool:
    """True when a path component is an array index: ASCII digits only (``"²"`` is none)."""
    return part.isascii() and part.isdigit()


class Ros2BlockDecoder:
    """Reads wanted fields of many CDR messages of one ``ros2msg`` schema at once.

    Built from the schema as ``mcap-ros2-support``'s decoder is (the same parser and message
    definitions), so the layout it walks is the one that decoder reads.

    Parameters
    ----------
    schema_name : str
        The schema's name (``pkg/msg/Type``).
    schema_text : str
        The schema's ``ros2msg`` text (the type and its dependencies).

    Raises
    ------
    ValueError
        The schema does not parse or does not define ``schema_name``.
    """

    def __init__(self, schema_name: str, schema_text: str) -> None:
        from mcap_ros2._dynamic import TimeDefinition, _for_each_msgdef

        msgdefs: dict[str, Any] = {
            "builtin_interfaces/Time": TimeDefinition,
            "builtin_interfaces/Duration": TimeDefinition,
        }

        def keep(name: str, short: str, msgdef: Any) -> None:
            msgdefs[name] = msgdef
            msgdefs[short] = msgdef

        try:
            _for_each_msgdef(schema_name, schema_text, keep)
        except Exception as exc:  # the third-party parser's own errors
            raise ValueError(f"the schema does not parse: {type(exc).__name__}: {exc}") from None
        if schema_name not in msgdefs:
            raise ValueError(f"the schema does not define {schema_name!r}")
        self.msgdefs = msgdefs
        self.root = msgdefs[schema_name]

    # ---- the walk of one message ----------------------------------------------------------

    def layout(self, payload: Any) -> CdrLayout | None:
        """Where every field of one CDR payload lies (None when it cannot be vouched for).

        None when the general decoder would refuse the payload (a field past the end, an
        unknown type, a ``wstring``, a string that is not UTF-8), or it has more than
        :data:`MAX_LAYOUT_NODES` fields or messages nested more than 64 deep.
        """
        data = bytes(payload)
        if len(data) < 4:
            return None
        le = data[1] & 1 == 1
        walk = _Walk(data, "<" if le else ">", self.msgdefs)
        try:
            walk.message(self.root, ())
        except (_LayoutTooBigError, ValueError, UnicodeDecodeError, RecursionError):
            return None
        return CdrLayout(len(data), le, tuple(walk.words), tuple(walk.strings), walk.leaves)

    # ---- many messages -------------------------------------------------------------------

    def _block(
        self, buf: Any, starts: np.ndarray, ends: np.ndarray
    ) -> tuple[Rows, CdrLayout, str] | None:
        blk = checked_block(buf, starts, ends)
        if blk is None:
            return None
        mv, s, n = blk
        s0 = int(s[0])
        lay = self.layout(mv[s0 : s0 + n])
        if lay is None:
            return None
        rows = Rows(mv, s, n)
        if not same_bytes(rows, [(0, 4), *((w, 4) for w in lay.words)]):
            return None
        if not strings_decode(rows, lay.strings):
            return None
        return rows, lay, "<" if lay.little_endian else ">"

    def columns(
        self,
        buf: Any,
        starts: np.ndarray,
        ends: np.ndarray,
        paths: Sequence[str],
        scalar: Sequence[bool] = (),
    ) -> Ros2Columns | None:
        """The fields at dotted ``paths`` of every message, and the header stamps.

        Parameters
        ----------
        buf : bytes-like
            A chunk's uncompressed data.
        starts, ends : numpy.ndarray
            Byte range of each payload in ``buf`` (int64).
        paths : sequence of str
            Field paths as a mapping names them (``linear_acceleration.x``, ``data.3``,
            ``data[3]``, ``values`` for a whole numeric array).
        scalar : sequence of bool
            For each path, whether it must hold exactly one number (a slow signal).

        Returns
        -------
        Ros2Columns or None
            None unless every message has the first one's layout (see the module notes) and
            every path names, in it, a number or a numeric array (empty ones too) (not ``uint8`` or
            ``byte``, which the general decoder hands on as ``bytes``); with a header, its
            stamp fields must be integers of at most 32 bits, and a message without one must
            have no top-level ``stamp_ns`` (which the handlers would take for a stamp).
        """
        got = self._block(buf, starts, ends)
        if got is None:
            return None
        rows, lay, e = got
        out = []
        for i, path in enumerate(paths):
            found = _resolve(lay, path_parts(path))
            if found is None:
                return None
            leaf, first, count = found
            if i < len(scalar) and scalar[i] and count != 1:
                return None
            out.append(float_field(rows, leaf, first, count, e))
        sec = lay.leaves.get(("header", "stamp", "sec"))
        nsec = lay.leaves.get(("header", "stamp", "nanosec"))
        if sec is not None and nsec is not None:
            if (
                sec.array
                or nsec.array
                or sec.type not in _SMALL_INTS
                or nsec.type not in _SMALL_INTS
            ):
                return None
            stamp = int_field(rows, sec, e)
            stamp *= 1_000_000_000
            stamp += int_field(rows, nsec, e)
            return Ros2Columns(stamp, out)
        if any(p[:2] == ("header", "stamp") or p[0] == "stamp_ns" for p in lay.leaves):
            return None
        return Ros2Columns(None, out)

    def scalar_many(
        self, buf: Any, starts: np.ndarray, ends: np.ndarray, field: str
    ) -> np.ndarray | None:
        """The one numeric field ``field`` of every message (float64).

        None when :meth:`columns` would answer None, or ``field`` is no numeric scalar.
        """
        got = self._block(buf, starts, ends)
        if got is None:
            return None
        rows, lay, e = got
        leaf = lay.leaves.get((field,))
        if leaf is None or leaf.array or leaf.type == "string":
            return None
        return float_field(rows, leaf, 0, 1, e)[:, 0]


def _resolve(lay: CdrLayout, parts: tuple[str, ...]) -> tuple[Leaf, int, int] | None:
    """The leaf a path names, its first element and element count (None if not numeric)."""
    leaf = lay.leaves.get(parts)
    if leaf is not None:
        if leaf.type == "string" or (leaf.array and leaf.type in _BYTES_ARRAYS):
            return None
        return leaf, 0, leaf.elems
    if len(parts) < 2 or not _is_index(parts[-1]):
        return None
    leaf = lay.leaves.get(parts[:-1])
    if leaf is None or not leaf.array or leaf.type == "string":
        return None
    k = int(parts[-1])
    return (leaf, k, 1) if k < leaf.elems else None


class _Walk:
    """The walk of one payload, as ``mcap-ros2-support``'s ``_read_complex_type`` reads it."""

    def __init__(self, data: bytes, e: str, msgdefs: dict[str, Any]) -> None:
        self.data = data
        self.n = len(data)
        self.e = e
        self.msgdefs = msgdefs
        self.pos = 4
        self.nodes = 0
        self.words: list[int] = []
        self.strings: list[tuple[int, int]] = []
        self.leaves: dict[tuple[str, ...], Leaf] = {}

    def _align(self, size: int) -> None:
        rem = (self.pos - 4) % size
        if rem:
            self.pos += size - rem

    def _take(self, size: int, count: int = 1) -> int:
        """Room for ``count`` aligned primitives of ``size`` bytes: their offset."""
        self.nodes += 1
        if self.nodes > MAX_LAYOUT_NODES:
            raise _LayoutTooBigError
        if count and size > 1:
            self._align(size)
        at = self.pos
        self.pos += size * count
        if self.pos > self.n:
            raise ValueError("past the end")
        return at

    def _u32(self) -> int:
        at = self._take(4)
        self.words.append(at)
        return int.from_bytes(self.data[at : at + 4], "little" if self.e == "<" else "big")

    def _string(self, path: tuple[str, ...]) -> None:
        length = self._u32()
        at = self._take(1, length)
        if length > 1:
            self.data[at : at + length - 1].decode("utf-8")
            self.strings.append((at, length - 1))
        self.leaves[path] = Leaf(at, "string", 1, False)

    def message(self, msgdef: Any, path: tuple[str, ...]) -> None:
        if len(path) > _MAX_DEPTH:  # a schema nesting itself: left to the general decoder
            raise _LayoutTooBigError
        if not msgdef.fields:
            self._take(1)  # ROS 2's structure_needs_at_least_one_member
        for field in msgdef.fields:
            ftype = field.type
            here = (*path, field.name)
            if not ftype.is_primitive_type():
                nested = self.msgdefs.get(f"{ftype.pkg_name}/{ftype.type}")
                if nested is None:
                    raise ValueError(f"no definition of {ftype.type}")
                if ftype.is_array:
                    count = (
                        ftype.array_size
                        if ftype.is_fixed_size_array() and ftype.array_size is not None
                        else self._u32()
                    )
                    for k in range(count):
                        self.message(nested, (*here, str(k)))
                else:
                    self.message(nested, here)
                continue
            name = ftype.type
            if name == "string":
                if ftype.is_array:
                    count = (
                        ftype.array_size
                        if ftype.is_fixed_size_array() and ftype.array_size is not None
                        else self._u32()
                    )
                    for k in range(count):
                        self._string((*here, str(k)))
                    self.leaves[here] = Leaf(0, "string", count, True)
                else:
                    self._string(here)
                continue
            prim = PRIMITIVES.get(name)
            if prim is None:  # wstring and anything else the general decoder refuses
                raise ValueError(f"type {name}")
            if ftype.is_array:
                count = (
                    ftype.array_size
                    if ftype.is_fixed_size_array() and ftype.array_size is not None
                    else self._u32()
                )
                self.leaves[here] = Leaf(self._take(prim[1], count), name, count, True)
            else:
                self.leaves[here] = Leaf(self._take(prim[1]), name, 1, False)
