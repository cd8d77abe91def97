"""Linux ``candump -L`` logs, parsed a block of lines at a time with NumPy.

A line reads ``(1700000000.123456) can0 123#DEADBEEF`` (optionally followed by `` R`` or
`` T``, as python-can's ``CanutilsLogWriter`` writes): timestamp in seconds, interface,
identifier (extended when it has more than 3 hex digits, as python-can's
``CanutilsLogReader`` decides), ``#`` and the payload in hex; ``123#R`` (optionally ``R4``) is
a remote frame, ``123##1DEADBEEF`` a CAN FD frame with a flags nibble after the second ``#``;
identifiers with ``CAN_ERR_FLAG`` (0x20000000) are error frames.

The file is read in blocks of whole lines (:data:`BLOCK_BYTES`). In a block the structural
characters (``(``, ``)``, spaces, ``#``, ``.``) are located with NumPy, every line gets a layout
key (the lengths of its fields), and the lines sharing a layout, usually nearly all of them,
are parsed together as a fixed-width character matrix, each row read once by a compiled loop
(:func:`~rigtools.ingest.can.text_kernels.parse_fixed_rows`): digits and hex nibbles checked
and read, timestamps as exact integers divided by a power of ten. Lines the fast path does not
recognise go through a line-by-line parser that follows python-can's reader rule for rule; a
line neither accepts is counted, never skipped silently:

==================  ==============================================================
reason              what
==================  ==============================================================
``error_frame``     identifier with ``CAN_ERR_FLAG`` set (python-can calls it an
                    error frame only with ``CAN_ERR_BUSERROR`` too; here any SocketCAN
                    error class counts, and no error frame becomes a data frame)
``remote_frame``    ``ID#R`` lines
``unparsable_line`` anything else that is not blank: garbage, bad hex, an odd number
                    of payload digits (python-can would invent a byte), more than 64
                    payload bytes, a timestamp ``float`` cannot read, invalid UTF-8, a
                    line longer than :data:`MAX_LINE_BYTES`
==================  ==============================================================

Blank lines carry nothing and are skipped, as python-can skips them. The FD flags character
after ``##`` is read as a hex digit (candump writes ``%X``; python-can reads it as a decimal
digit and fails on ``A``..``F``).

Positions are 1-based line numbers (``position_unit = "line"``). Frames come out exactly as
python-can yields them (timestamps bit for bit: ``float`` of the text), except that the channel
is the number python-can's ``channel2int`` makes of the interface name (``can0`` -> 0,
``vcan1`` -> 1, -1 when it has no number), since a batch holds integer channels.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from typing import BinaryIO, Final

import numpy as np

from rigtools.errors import RecordingFormatError
from rigtools.ingest.can.frames import CanFrameBatch, byte_rows
from rigtools.ingest.can.reader import CanLogReader
from rigtools.ingest.can.text_digits import HEX_VALUE
from rigtools.ingest.can.text_kernels import parse_fixed_rows
from rigtools.ingest.recording import IngestReport

__all__ = ["BLOCK_BYTES", "MAX_LINE_BYTES", "NAME", "READER", "iter_batches", "sniff"]

NAME = "candump"

#: Bytes read per block (whole lines are parsed together).
BLOCK_BYTES = 8 << 20
#: Longer lines are unparsable and are not buffered (bytes).
MAX_LINE_BYTES = 1 << 16

_CAN_ERR_FLAG = 0x20000000
_SNIFF = re.compile(rb"\s*\(\s*\d+(\.\d*)?\)\s+\S+\s+[0-9A-Fa-f]{1,8}##?[0-9A-Fa-fRr]?")

# kinds of a parsed line
_DATA, _ERROR, _REMOTE, _BAD, _BLANK = 0, 1, 2, 3, 4


def sniff(head: bytes) -> bool:
    """True when the first non-blank line of ``head`` looks like a ``candump -L`` line."""
    for line in head.splitlines():
        if line.strip():
            return _SNIFF.match(line) is not None
    return False


def _channel_number(name: bytes) -> int:
    """python-can's ``channel2int``: the number ending an interface name, or -1."""
    m = re.match(rb".*?(\d+)$", name)
    if m is None:
        return -1
    v = int(m.group(1))
    return v if v <= 32767 else -1


class _Rows:
    """Per-line results of one block, filled by the fast and the slow path."""

    def __init__(self, n: int) -> None:
        self.kind = np.full(n, _BAD, np.uint8)
        self.ts = np.zeros(n, np.float64)
        self.can_id = np.zeros(n, np.uint32)
        self.ext = np.zeros(n, bool)
        self.fd = np.zeros(n, bool)
        self.length = np.zeros(n, np.uint8)
        self.data = np.zeros((n, 8), np.uint8)
        self.channel = np.full(n, -1, np.int16)

    def widen(self) -> None:
        if self.data.shape[1] < 64:
            wide = np.zeros((self.data.shape[0], 64), np.uint8)
            wide[:, :8] = self.data
            self.data = wide


def _first_at_or_after(positions: np.ndarray, at: np.ndarray, big: int) -> tuple[np.ndarray,
                                                                                  np.ndarray]:
    """For each ``at``, the first position >= it (``big`` when none) and its rank."""
    i = np.searchsorted(positions, at)
    ext = np.append(positions, big)
    return ext[i], i


def _slow_line(text: str) -> tuple | None:
    """One line as python-can's ``CanutilsLogReader`` reads it; None when it would fail.

    Returns ``(kind, ts, id, extended, fd, data, channel_name)``.
    """
    try:
        temp = text.strip()
        if not temp:
            return (_BLANK,)
        if temp[-2:].lower() in (" r", " t"):
            ts_s, chan, frame, _ = temp.split()
        else:
            ts_s, chan, frame = temp.split()
        ts = float(ts_s[1:-1])
        id_s, data = frame.split("#", maxsplit=1)
        ext = len(id_s) > 3
        can_id = int(id_s, 16)
        fd = False
        if data and data[0] == "#":
            fd = True
            int(data[1], 16)
            data = data[2:]
        if can_id & _CAN_ERR_FLAG:
            return (_ERROR,)
        if data and data[0].lower() == "r":
            if len(data) > 1:
                int(data[1:])
            return (_REMOTE,)
        if len(data) % 2 or len(data) > 128:
            return None
        payload = bytes.fromhex(data) if data else b""
        if len(payload) * 2 != len(data):
            return None
        return (_DATA, ts, can_id & 0x1FFFFFFF, ext, fd, payload, chan.encode())
    except (ValueError, IndexError, UnicodeError):
        return None


def _parse_block(block: bytes, first_line: int, dominant: bool = True) -> tuple[_Rows,
                                                                              np.ndarray]:
    r"""Parse a block of whole lines.

    Parameters
    ----------
    block : bytes
        Whole lines, each ending with ``\\n``.
    first_line : int
        1-based line number of the first line.
    dominant : bool
        Parse the lines of the most common length as one matrix when they are most of the
        block (:func:`_parse_dominant`); the rest go the general way.

    Returns
    -------
    rows : _Rows
        Kind and fields of every line.
    line_no : numpy.ndarray
        Line numbers (int64).
    """
    a = np.frombuffer(block, np.uint8)
    nl = np.flatnonzero(a == 10)
    n = nl.size
    starts = np.empty(n, np.int64)
    starts[0] = 0
    starts[1:] = nl[:-1] + 1
    ends = nl.astype(np.int64)
    cr = (ends > starts) & (a[np.maximum(ends - 1, 0)] == 13)
    ends = ends - cr
    rows = _Rows(n)
    line_no = first_line + np.arange(n, dtype=np.int64)
    chan_cache: dict[bytes, int] = {}
    step = int(nl[0]) + 1
    if n > 1 and step * n == len(block) and bool((np.diff(nl) == step).all()):
        # Every line has the same length: try one layout for the whole block, zero-copy.
        line = block[: step - 1]
        cr = line.endswith(b"\r")
        k = _layout_key(line[:-1] if cr else line)
        if k is not None:
            m = a.reshape(n, step)[:, : step - 1 - cr]
            if (not cr or bool((a[step - 2 :: step] == 13).all())) and _uniform_ok(m, k):
                back = _parse_group(m, k, np.arange(n), rows, chan_cache)
                if back is None:
                    return rows, line_no
                rows.kind[back] = _BAD  # re-parsed below with every other line
    if dominant and n >= _DOMINANT_MIN_LINES:
        todo = _parse_dominant(block, a, starts, nl, rows, chan_cache)
        if todo is not None:
            if todo.size:
                _parse_subset(block, starts, nl, todo, rows, chan_cache)
            return rows, line_no
    big = len(block) + 1
    length = ends - starts
    rows.kind[length == 0] = _BLANK
    ok = length > 0
    ok &= a[np.minimum(starts, len(block) - 1)] == ord("(")
    p_rp = np.flatnonzero(a == ord(")"))
    p_sp = np.flatnonzero(a == ord(" "))
    p_hash = np.flatnonzero(a == ord("#"))
    p_dot = np.flatnonzero(a == ord("."))
    rp, _ = _first_at_or_after(p_rp, starts, big)
    sp1, i1 = _first_at_or_after(p_sp, starts, big)
    sp_ext = np.append(p_sp, [big, big])
    sp2 = sp_ext[np.minimum(i1 + 1, p_sp.size + 1)]
    sp3 = sp_ext[np.minimum(i1 + 2, p_sp.size + 1)]
    dot, _ = _first_at_or_after(p_dot, starts, big)
    hs, _ = _first_at_or_after(p_hash, np.minimum(sp2, big - 1), big)
    suffix = sp3 < ends
    frame_end = np.where(suffix, sp3, ends)
    ok &= (sp1 == rp + 1) & (sp2 < ends) & (dot < rp) & (hs < frame_end)
    ok &= ~suffix | (ends == sp3 + 2)
    if suffix.any():
        sfx = a[np.minimum(sp3 + 1, len(block) - 1)] | 0x20  # lower case
        ok &= ~suffix | (sfx == ord("r")) | (sfx == ord("t"))
    il = dot - starts - 1
    fl = rp - dot - 1
    cl = sp2 - sp1 - 1
    idl = hs - sp2 - 1
    c1 = a[np.minimum(hs + 1, len(block) - 1)]
    has1 = hs + 1 < frame_end
    fdk = has1 & (c1 == ord("#"))
    c_after = np.where(fdk, a[np.minimum(hs + 3, len(block) - 1)], c1)
    has_after = np.where(fdk, hs + 3 < frame_end, has1)
    remote = has_after & ((c_after | 0x20) == ord("r"))
    dstart = np.where(fdk, hs + 3, hs + 1)
    dl = frame_end - dstart
    ok &= (il >= 1) & (il <= 15) & (fl >= 1) & (fl <= 15) & (il + fl <= 18) & (cl >= 1) & (
        cl <= 31)
    ok &= (idl >= 1) & (idl <= 8) & (dl >= 0) & (dl <= 128) & (~fdk | (hs + 3 <= frame_end))
    ok &= remote | (dl % 2 == 0)
    key = (il | (fl << 4) | (cl << 8) | (idl << 13) | (fdk.astype(np.int64) << 17)
           | (remote.astype(np.int64) << 18) | (dl << 19) | (suffix.astype(np.int64) << 27))
    fast = np.flatnonzero(ok)
    bad_fast: list[np.ndarray] = []
    if fast.size:
        fkeys = key[fast]
        uniq, inv = np.unique(fkeys, return_inverse=True)
        order = np.argsort(inv, kind="stable")
        bounds = np.searchsorted(inv[order], np.arange(uniq.size + 1))
        for g, k in enumerate(uniq.tolist()):
            idx = fast[order[bounds[g] : bounds[g + 1]]]
            m = byte_rows(a, starts[idx], _columns(k)[-1])
            rejected = _parse_group(m, k, idx, rows, chan_cache)
            if rejected is not None:
                bad_fast.append(rejected)
    slow = np.flatnonzero(~ok & (rows.kind != _BLANK))
    if bad_fast:
        slow = np.union1d(slow, np.concatenate(bad_fast))
    for i in slow.tolist():
        text = block[starts[i] : ends[i]]
        try:
            got = _slow_line(text.decode("utf-8"))
        except UnicodeDecodeError:
            got = None
        if got is None:
            rows.kind[i] = _BAD
            continue
        rows.kind[i] = got[0]
        if got[0] != _DATA:
            continue
        _, ts, can_id, ext, fd, payload, chan = got
        rows.ts[i] = ts
        rows.can_id[i] = can_id
        rows.ext[i] = ext
        rows.fd[i] = fd
        rows.length[i] = len(payload)
        if len(payload) > 8:
            rows.widen()
        rows.data[i, : len(payload)] = np.frombuffer(payload, np.uint8)
        c = chan_cache.get(chan)
        if c is None:
            c = chan_cache[chan] = _channel_number(chan)
        rows.channel[i] = c
    return rows, line_no


#: Blocks with fewer lines go the general way only.
_DOMINANT_MIN_LINES = 64


def _parse_dominant(block: bytes, a: np.ndarray, starts: np.ndarray, nl: np.ndarray,
                    rows: _Rows, chan_cache: dict[bytes, int]) -> np.ndarray | None:
    """Parse the lines of the most common length that have the layout of the first of them.

    A log mixes a few layouts (a slow message with fewer bytes, error and remote frames)
    among one that makes most of its lines: those are gathered into one character matrix
    and parsed together, without locating the structural characters of every line.

    Returns the indices of the lines left to parse (None, and nothing parsed, when the most
    common length is not that of most lines or its first line has no plain layout).
    """
    n = nl.size
    with_cr = nl - starts  # line lengths without the line feed
    counts = np.bincount(np.minimum(with_cr, 1024))
    width = int(np.argmax(counts))
    if 2 * int(counts[width]) < n or width == 0 or width >= 1024:
        return None
    idx = np.flatnonzero(with_cr == width)
    s0 = int(starts[idx[0]])
    line = block[s0 : s0 + width]
    cr = int(line.endswith(b"\r"))
    k = _layout_key(line[:-1] if cr else line)
    if k is None or _columns(k)[-1] != width - cr:
        return None
    m = byte_rows(a, starts[idx], width)
    ok = _uniform_rows(m, k)
    if cr:
        ok &= m[:, width - 1] == 13
    done = np.zeros(n, bool)
    if bool(ok.all()):
        sel = idx
    else:
        sel, m = idx[ok], m[ok]
    back = _parse_group(m[:, : width - cr], k, sel, rows, chan_cache)
    done[sel] = True
    if back is not None:
        done[back] = False
        rows.kind[back] = _BAD
    return np.flatnonzero(~done)


def _parse_subset(block: bytes, starts: np.ndarray, nl: np.ndarray, todo: np.ndarray,
                  rows: _Rows, chan_cache: dict[bytes, int]) -> None:
    """Parse the lines ``todo`` of a block the general way, into ``rows``."""
    sub_block = b"".join([block[s : e + 1] for s, e in zip(starts[todo].tolist(),
                                                           nl[todo].tolist(), strict=True)])
    sub, _ = _parse_block(sub_block, 1, dominant=False)
    rows.kind[todo] = sub.kind
    rows.ts[todo] = sub.ts
    rows.can_id[todo] = sub.can_id
    rows.ext[todo] = sub.ext
    rows.fd[todo] = sub.fd
    rows.length[todo] = sub.length
    rows.channel[todo] = sub.channel
    if sub.data.shape[1] > rows.data.shape[1]:
        rows.widen()
    rows.data[todo, : sub.data.shape[1]] = sub.data


def _columns(k: int) -> tuple[int, ...]:
    """Unpack a layout key: field lengths and flags, and the columns of the fields."""
    il, fl, cl = k & 15, (k >> 4) & 15, (k >> 8) & 31
    idl, fdk, remote = (k >> 13) & 15, (k >> 17) & 1, (k >> 18) & 1
    dl, suffix = (k >> 19) & 255, (k >> 27) & 1
    c_chan = 4 + il + fl
    c_id = c_chan + cl + 1
    c_data = c_id + idl + 1 + (2 if fdk else 0)
    width = c_data + dl + (2 if suffix else 0)
    return il, fl, cl, idl, fdk, remote, dl, suffix, c_chan, c_id, c_data, width


def _layout_key(line: bytes) -> int | None:
    """The layout key of one line (see :func:`_parse_block`), None when it has no plain layout."""
    m = re.fullmatch(rb"\((\d+)\.(\d+)\) (\S+) ([0-9A-Fa-f]+)#(#[0-9A-Fa-f])?([^ ]*)( [RrTt])?",
                     line)
    if m is None:
        return None
    il, fl, cl, idl = (len(m.group(i)) for i in (1, 2, 3, 4))
    fdk = m.group(5) is not None
    rest = m.group(6)
    remote = rest[:1] in (b"R", b"r")
    dl = len(rest)
    suffix = m.group(7) is not None
    if not (il <= 15 and fl <= 15 and il + fl <= 18 and cl <= 31 and idl <= 8 and dl <= 128
            and (remote or dl % 2 == 0)):
        return None
    return (il | (fl << 4) | (cl << 8) | (idl << 13) | (int(fdk) << 17) | (int(remote) << 18)
            | (dl << 19) | (int(suffix) << 27))


def _structural_columns(k: int) -> list[tuple[int, int]]:
    """Column and character of each structural character of layout ``k`` (``(``, ``.``, ...).

    The remote-frame ``R`` and the ``R``/``T`` suffix, which come in either case, are not
    among them.
    """
    il, fl, cl, idl, fdk, _, _, suffix, c_chan, c_id, _, width = _columns(k)
    cols = [(0, b"("), (1 + il, b"."), (2 + il + fl, b")"), (3 + il + fl, b" "),
            (c_chan + cl, b" "), (c_id + idl, b"#")]
    if fdk:
        cols.append((c_id + idl + 1, b"#"))
    if suffix:
        cols.append((width - 2, b" "))
    return [(c, ch[0]) for c, ch in cols]


def _uniform_rows(m: np.ndarray, k: int) -> np.ndarray:
    """Rows of a character matrix that have the structural characters of layout ``k``.

    The matrix is at least as wide as the layout; the rows' other characters are not looked at.
    """
    _, _, _, _, _, remote, _, suffix, _, _, c_data, width = _columns(k)
    cols = _structural_columns(k)
    ok = m[:, cols[0][0]] == cols[0][1]
    for c, ch in cols[1:]:
        ok &= m[:, c] == ch
    if remote:
        ok &= (m[:, c_data] | 0x20) == ord("r")
    if suffix:
        ok &= ((m[:, width - 1] | 0x20) == ord("r")) | ((m[:, width - 1] | 0x20) == ord("t"))
    return ok


def _uniform_ok(m: np.ndarray, k: int) -> bool:
    """All rows of a fixed-width matrix have the structural characters of layout ``k``."""
    _, _, _, _, _, remote, _, suffix, _, _, c_data, width = _columns(k)
    if m.shape[1] != width:
        return False
    for c, ch in _structural_columns(k):
        if not bool((m[:, c] == ch).all()):
            return False
    if remote and not bool(((m[:, c_data] | 0x20) == ord("r")).all()):
        return False
    return not suffix or bool(np.isin(m[:, width - 1], np.frombuffer(b"RrTt", np.uint8)).all())


def _parse_group(m: np.ndarray, k: int, idx: np.ndarray, rows: _Rows,
                 chan_cache: dict[bytes, int]) -> np.ndarray | None:
    """Parse lines sharing layout ``k`` (character matrix ``m``, one row per line).

    Returns the line indices that must go the slow way (None when there is none).
    """
    il, fl, cl, idl, fdk, remote, dl, _, c_chan, c_id, c_data, _ = _columns(k)
    n = m.shape[0]
    nb = dl // 2
    good = np.empty(n, bool)
    can_id = np.empty(n, np.int64)
    total = np.empty(n, np.int64)
    payload = np.zeros((n, nb), np.uint8)
    parse_fixed_rows(m, il, fl, cl, idl, fdk, remote, dl, c_chan, c_id, c_data, HEX_VALUE,
                     good, can_id, total, payload)
    back = None
    if not bool(good.all()):
        back = idx[~good]
        idx, m, can_id, total, payload = idx[good], m[good], can_id[good], total[good], \
            payload[good]
        if idx.size == 0:
            return back
    chan_chars = m[:, c_chan : c_chan + cl]
    err = (can_id & _CAN_ERR_FLAG) != 0
    any_err = bool(err.any())
    if remote:
        rows.kind[idx] = np.where(err, _ERROR, _REMOTE) if any_err else _REMOTE
        return back
    rows.kind[idx] = np.where(err, _ERROR, _DATA) if any_err else _DATA
    ts = total.astype(np.float64) / float(10**fl)
    huge = total >= (1 << 53)
    if huge.any():  # beyond exact integers: let float() round the text as python-can does
        for r in np.flatnonzero(huge).tolist():
            ts[r] = float(bytes(m[r, 1 : 2 + il + fl]).decode())
    rows.ts[idx] = ts
    rows.can_id[idx] = (can_id & 0x1FFFFFFF).astype(np.uint32)
    rows.ext[idx] = idl > 3
    rows.fd[idx] = bool(fdk)
    rows.length[idx] = nb
    if nb:
        if nb > rows.data.shape[1]:
            rows.widen()
        if nb == rows.data.shape[1]:  # whole rows: one void item each (take_rows' reason)
            rows.data.view(f"V{nb}")[idx, 0] = payload.view(f"V{nb}")[:, 0]
        else:
            rows.data[idx, :nb] = payload
    if bool((chan_chars == chan_chars[0]).all()):
        name = bytes(chan_chars[0])
        c = chan_cache.get(name)
        if c is None:
            c = chan_cache[name] = _channel_number(name)
        rows.channel[idx] = c
        return back
    chans = np.ascontiguousarray(chan_chars).view(f"S{cl}").ravel()
    uniq, inv = np.unique(chans, return_inverse=True)
    nums = np.empty(uniq.size, np.int16)
    for u, name in enumerate(uniq.tolist()):
        c = chan_cache.get(name)
        if c is None:
            c = chan_cache[name] = _channel_number(name)
        nums[u] = c
    rows.channel[idx] = nums[inv.ravel()]
    return back


def _blocks(stream: BinaryIO, block_bytes: int) -> Iterator[bytes]:
    """Blocks of whole lines, each ending with a newline.

    A line longer than :data:`MAX_LINE_BYTES` is not buffered: it arrives as a single NUL
    line, which the parser counts as unparsable.
    """
    carry = b""
    skipping = False
    while True:
        chunk = stream.read(block_bytes)
        if not chunk:
            break
        if skipping:
            cut = chunk.find(b"\n")
            if cut < 0:
                continue
            chunk = chunk[cut + 1 :]
            skipping = False
        buf = carry + chunk if carry else chunk
        cut = buf.rfind(b"\n")
        if cut < 0:
            carry = buf
        else:
            carry = buf[cut + 1 :]
            yield buf[: cut + 1]
        if len(carry) > MAX_LINE_BYTES:
            yield b"\x00\n"
            carry = b""
            skipping = True
    if carry:
        yield carry + b"\n"


def iter_batches(
    stream: BinaryIO,
    path: str,
    report: IngestReport,
    *,
    batch_frames: int = 250_000,
    block_bytes: int = BLOCK_BYTES,
) -> Iterator[CanFrameBatch]:
    """Stream the CAN data frames of a ``candump -L`` log as columnar batches.

    Parameters
    ----------
    stream : BinaryIO
        The file, opened for binary reading (gzip already unwrapped).
    path : str
        File name for messages.
    report : IngestReport
        Receives the counts of error frames, remote frames and unparsable lines, each with the
        first line number.
    batch_frames : int
        Most frames per batch yielded.
    block_bytes : int
        Bytes read and parsed at a time.

    Yields
    ------
    CanFrameBatch
        Data frames in file order; ``position`` holds 1-based line numbers.
    """
    if batch_frames < 1:
        raise ValueError(f"`batch_frames` must be >= 1, was {batch_frames}")
    if block_bytes < 1:
        raise ValueError(f"`block_bytes` must be >= 1, was {block_bytes}")
    line = 1
    content = False
    for block in _blocks(stream, block_bytes):
        content = content or not block.isspace()  # (no copy of the block, as strip makes)
        rows, line_no = _parse_block(block, line)
        line += line_no.size
        for kind, reason in ((_ERROR, "error_frame"), (_REMOTE, "remote_frame"),
                             (_BAD, "unparsable_line")):
            hit = rows.kind == kind
            if hit.any():
                report.reject(reason, int(hit.sum()), f"line {int(line_no[np.argmax(hit)])}")
        keep = np.flatnonzero(rows.kind == _DATA)
        if keep.size == 0:
            continue
        all_rows = keep.size == rows.kind.size
        width = 64 if rows.data.shape[1] > 8 and int(rows.length[keep].max()) > 8 else 8

        def col(x: np.ndarray, keep: np.ndarray = keep, all_rows: bool = all_rows) -> np.ndarray:
            return x if all_rows else x[keep]

        batch = CanFrameBatch(
            col(rows.ts), col(rows.can_id), col(rows.ext), col(rows.fd), col(rows.length),
            np.ascontiguousarray(col(rows.data)[:, :width]), col(rows.channel), col(line_no),
            "line",
        )
        for s in range(0, len(batch), batch_frames):
            yield batch if len(batch) <= batch_frames else batch.take(
                np.arange(s, min(s + batch_frames, len(batch))))
    if not content:
        raise RecordingFormatError(path, "line 1", "a candump -L log",
                                   "an empty file (no line with any content)")


#: This format in :data:`rigtools.ingest.registry.READERS`.
READER: Final = CanLogReader(NAME, sniff, iter_batches)
