"""Plain classic-CAN data-frame lines of a Vector ASC log, parsed a block at a time with NumPy.

Most lines of an ASC log are classic data frames::

       0.015991 1  120             Rx   d 8 00 01 02 03 04 05 06 07  Length = 228000 ...

:func:`parse_frame_lines` tokenises a block of lines (whitespace-separated tokens located
with NumPy over the bytes) and recognises the lines that python-can's ``ASCReader`` would
turn into a data frame without any doubt: time stamp ``<digits>.<digits>`` (at most 15
digits, an exact float), channel ``<digits>``, identifier of 1 to 8 hex digits with an
optional ``x`` (extended), ``Rx``/``Tx``, ``d``, a DLC ``0``..``8`` and that many two-digit
hex bytes, followed by anything (python-can ignores it), every byte of the line printable
ASCII or a tab, and the identifier within 11 bits (29 when extended). Their fields come out
as python-can gives them (:meth:`FrameLines.batch`: the time stamp ``float`` of the text
plus the measurement start, bit for bit). Every other line (header, comments, events, error
and remote frames, CAN FD frames, ``base dec`` files, anything odd) is left to python-can and
the line accounting of :mod:`rigtools.ingest.can.textlog`. The lines of one length whose
first line has such a layout are gathered as a character matrix and read row by row by a
compiled loop (:func:`~rigtools.ingest.can.text_kernels.parse_asc_rows`), every checked
column against its class.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from rigtools.ingest.can.frames import CanFrameBatch, byte_rows, take_rows
from rigtools.ingest.can.text_digits import HEX_VALUE, POW10
from rigtools.ingest.can.text_kernels import parse_asc_rows

__all__ = ["FrameLines", "parse_frame_lines"]

#: Tokens of a line looked at: time, channel, id, direction, "d", DLC and 8 data bytes.
_TOKENS = 14
#: Longest time stamp token read here (15 digits and the point: an exact float mantissa).
_TS_WIDTH = 16
_CH_WIDTH = 5


@dataclass(frozen=True)
class FrameLines:
    """The plain data-frame lines of a block and their fields (meaningful where ``plain``).

    Attributes
    ----------
    line_end : numpy.ndarray
        int64, offset of each line's line feed in the block.
    plain : numpy.ndarray
        bool per line of the block: a data frame parsed here.
    mantissa : numpy.ndarray
        float64 holding an integer below 2**53 (exact): the time stamp's digits without the
        point.
    scale : numpy.ndarray
        float64, ``10 ** (digits after the point)``: the time stamp is ``mantissa / scale``
        (s, from the measurement start).
    channel, can_id, extended, length, data : numpy.ndarray
        As in :class:`~rigtools.ingest.can.frames.CanFrameBatch` (``channel`` is python-can's
        number: the ASC channel minus 1, -1 beyond int16).
    """

    line_end: np.ndarray
    plain: np.ndarray
    mantissa: np.ndarray
    scale: np.ndarray
    channel: np.ndarray
    can_id: np.ndarray
    extended: np.ndarray
    length: np.ndarray
    data: np.ndarray

    def rows(self, runs: list[tuple[int, int, float]], first_line: int) -> CanFrameBatch:
        """The frames of several runs of lines at once (see :meth:`batch`).

        ``runs`` holds ``(lo, hi, start_time_s)`` of each run, in file order.
        """
        if len(runs) == 1:
            return self.batch(runs[0][0], runs[0][1], first_line, runs[0][2])
        lo = np.array([r[0] for r in runs], np.int64)
        size = np.array([r[1] - r[0] for r in runs], np.int64)
        at = np.repeat(lo - (np.cumsum(size) - size), size) + np.arange(int(size.sum()))
        start = np.repeat(np.array([r[2] for r in runs]), size)
        return CanFrameBatch(
            self.mantissa[at] / self.scale[at] + start, self.can_id[at], self.extended[at],
            np.zeros(at.size, bool), self.length[at], take_rows(self.data, at), self.channel[at],
            at + first_line, "line",
        )

    def batch(self, lo: int, hi: int, first_line: int, start_time_s: float) -> CanFrameBatch:
        """The frames of lines ``lo:hi`` (all plain), python-can's ``ASCReader`` fields.

        Parameters
        ----------
        lo, hi : int
            Line indices in the block.
        first_line : int
            1-based line number of line 0 of the block.
        start_time_s : float
            python-can's measurement start in force at these lines (s).
        """
        sl = slice(lo, hi)
        ts = self.mantissa[sl] / self.scale[sl] + start_time_s
        n = hi - lo
        return CanFrameBatch(
            ts, self.can_id[sl], self.extended[sl], np.zeros(n, bool), self.length[sl],
            self.data[sl], self.channel[sl],
            np.arange(first_line + lo, first_line + hi, dtype=np.int64), "line",
        )


def _right_aligned(a: np.ndarray, start: np.ndarray, end: np.ndarray,
                   width: int) -> tuple[np.ndarray, np.ndarray]:
    """The last ``width`` characters of each token (NUL before its start) and that mask."""
    pos = end[:, None] + np.arange(-width, 0)
    inside = pos >= start[:, None]
    chars = np.where(inside, a[np.maximum(pos, 0)], 0).astype(np.uint8)
    return chars, inside


def _odd_lines(a: np.ndarray, nl: np.ndarray) -> np.ndarray:
    """Lines (indices, repeats possible) holding a byte other than printable ASCII or tab.

    Such a line goes to python-can. ``a`` is the block's bytes, ``nl`` the offsets of its
    line feeds.
    """
    odd = np.flatnonzero((a - np.uint8(32)) > 94)  # not printable ASCII (tab, LF, other)
    odd = odd[(a[odd] != 9) & (a[odd] != 10)]
    return np.searchsorted(nl, odd)


def _parse_tokens(block: bytes) -> FrameLines:
    """Find and parse the plain classic data-frame lines of a block, token by token.

    Parameters and result as :func:`parse_frame_lines`.
    """
    a = np.frombuffer(block, np.uint8)
    nl = np.flatnonzero(a == 10)
    n = nl.size
    sep = (a == 32) | (a == 9) | (a == 10)
    edge = np.flatnonzero(np.diff(sep.view(np.int8), prepend=np.int8(1), append=np.int8(1)))
    # ``edge`` alternates token starts and token ends (a token is a run of non-separators)
    t_start = edge[0::2]
    t_end = edge[1::2]
    before = np.searchsorted(t_start, nl)  # tokens starting before each line feed
    n_tok = np.diff(before, prepend=0)
    first_tok = before - n_tok
    ok = n_tok >= 6
    ok[_odd_lines(a, nl)] = False
    if not ok.any():
        return _empty(nl)
    rank = np.arange(_TOKENS)
    tok = np.minimum(first_tok[:, None] + rank, t_start.size - 1)
    has = rank < n_tok[:, None]
    s = t_start[tok]
    length = np.where(has, t_end[tok] - s, 0)

    # time stamp: digits, one point neither first nor last
    ts_len = length[:, 0]
    ok &= (ts_len >= 3) & (ts_len <= _TS_WIDTH)
    chars, inside = _right_aligned(a, s[:, 0], s[:, 0] + ts_len, _TS_WIDTH)
    digit = chars - np.uint8(48)
    is_dot = chars == 46
    ok &= ~(inside & (digit > 9) & ~is_dot).any(axis=1)
    ok &= is_dot.sum(axis=1) == 1
    dot_col = np.argmax(is_dot, axis=1)
    frac = _TS_WIDTH - 1 - dot_col
    ok &= (frac >= 1) & (dot_col > _TS_WIDTH - ts_len)
    col = np.arange(_TS_WIDTH)
    expo = (_TS_WIDTH - 1 - col)[None, :] - (col[None, :] < dot_col[:, None])
    digit = np.where(inside & ~is_dot, digit, 0).astype(np.int64)
    mantissa = (digit * POW10[np.maximum(expo, 0)]).sum(axis=1).astype(np.float64)
    scale = POW10[np.clip(frac, 0, 18)].astype(np.float64)

    # channel: digits
    ch_len = length[:, 1]
    ok &= (ch_len >= 1) & (ch_len <= _CH_WIDTH)
    chars, inside = _right_aligned(a, s[:, 1], s[:, 1] + ch_len, _CH_WIDTH)
    digit = chars - np.uint8(48)
    ok &= ~(inside & (digit > 9)).any(axis=1)
    digit = np.where(inside, digit, 0).astype(np.int64)
    ch_num = digit @ POW10[_CH_WIDTH - 1 :: -1][:_CH_WIDTH] - 1
    channel = np.where(ch_num <= 32767, ch_num, -1).astype(np.int16)

    # identifier: 1..8 hex digits, then an optional x (extended)
    id_len = length[:, 2]
    last = a[np.maximum(s[:, 2] + id_len - 1, 0)]
    extended = (last | 0x20) == ord("x")
    hex_len = id_len - extended
    ok &= (hex_len >= 1) & (hex_len <= 8)
    chars, inside = _right_aligned(a, s[:, 2], s[:, 2] + hex_len, 8)
    nib = HEX_VALUE[chars]
    ok &= ~(inside & (nib > 15)).any(axis=1)
    nib = np.where(inside, nib, 0).astype(np.int64)
    can_id = np.zeros(n, np.int64)
    for j in range(8):
        can_id = (can_id << 4) | nib[:, j]
    ok &= can_id <= np.where(extended, 0x1FFFFFFF, 0x7FF)

    # direction Rx/Tx, "d", DLC 0..8
    c3 = a[s[:, 3]] | 0x20
    ok &= (length[:, 3] == 2) & ((c3 == ord("r")) | (c3 == ord("t")))
    ok &= (a[np.minimum(s[:, 3] + 1, a.size - 1)] | 0x20) == ord("x")
    ok &= (length[:, 4] == 1) & (a[s[:, 4]] == ord("d"))
    dlc = a[s[:, 5]].astype(np.int64) - 48
    ok &= (length[:, 5] == 1) & (dlc >= 0) & (dlc <= 8)
    dlc = np.where(ok, dlc, 0)
    ok &= n_tok >= 6 + dlc

    # data bytes: two hex digits each
    used = rank[6:][None, :] < (6 + dlc)[:, None]
    ds = s[:, 6:]
    ok &= ~(used & (length[:, 6:] != 2)).any(axis=1)
    hi = HEX_VALUE[a[ds]]
    lo = HEX_VALUE[a[np.minimum(ds + 1, a.size - 1)]]
    ok &= ~(used & ((hi > 15) | (lo > 15))).any(axis=1)
    data = np.where(used, (hi << 4) | (lo & 15), 0).astype(np.uint8)
    return FrameLines(nl.astype(np.int64), ok, mantissa, scale, channel,
                      can_id.astype(np.uint32), extended, dlc.astype(np.uint8),
                      np.ascontiguousarray(data))


def _empty(nl: np.ndarray) -> FrameLines:
    n = nl.size
    return FrameLines(nl.astype(np.int64), np.zeros(n, bool), np.zeros(n), np.ones(n),
                      np.zeros(n, np.int16), np.zeros(n, np.uint32), np.zeros(n, bool),
                      np.zeros(n, np.uint8), np.zeros((n, 8), np.uint8))


# -- lines of one layout -----------------------------------------------------------------------

#: A line length shared by at least this many lines (and this share of the block) is parsed
#: as one character matrix.
_GROUP_MIN_LINES = 64
_GROUP_MIN_SHARE = 0.02
_TOKEN = re.compile(rb"[^ \t]+")
_TS_TOKEN = re.compile(rb"\d+\.\d+")
_CH_TOKEN = re.compile(rb"\d{1,5}")
_ID_TOKEN = re.compile(rb"[0-9A-Fa-f]{1,8}[xX]?")
_DIR_TOKEN = re.compile(rb"[RrTt][Xx]")
_BYTE_TOKEN = re.compile(rb"[0-9A-Fa-f]{2}")
# column classes of a layout: whitespace, digit, hex digit; then one class per exact character
_SEP, _DIGIT, _HEXC = 0, 1, 2
_CLASS_TABLE = np.zeros((3, 256), bool)
_CLASS_TABLE[_SEP, [9, 32]] = True
_CLASS_TABLE[_DIGIT, np.arange(48, 58)] = True
_CLASS_TABLE[_HEXC] = HEX_VALUE < 16


@dataclass(frozen=True)
class _Layout:
    """Columns of the fields of a plain frame line of one shape (see :func:`_layout_of`)."""

    cols: np.ndarray  # every column checked
    classes: np.ndarray  # class of each (rows of ``table``)
    table: np.ndarray  # (classes, 256) bool: characters allowed
    ts_digits: np.ndarray  # positions in ``cols`` of the time stamp's digits
    frac: int  # digits after the point
    ch_digits: np.ndarray
    id_hex: np.ndarray
    extended: bool
    data_hex: np.ndarray  # positions in ``cols``: high and low digit of each byte
    dlc: int


def _layout_of(line: bytes) -> _Layout | None:
    """The layout of a plain frame line (the rules of the token parser), or None."""
    toks = [(m.start(), m.end()) for m in _TOKEN.finditer(line)]
    if len(toks) < 6:
        return None
    text = [line[s:e] for s, e in toks]
    if not (_TS_TOKEN.fullmatch(text[0]) and len(text[0]) <= _TS_WIDTH
            and _CH_TOKEN.fullmatch(text[1]) and _ID_TOKEN.fullmatch(text[2])
            and _DIR_TOKEN.fullmatch(text[3]) and text[4] == b"d"
            and len(text[5]) == 1 and 48 <= text[5][0] <= 56):
        return None
    dlc = text[5][0] - 48
    if len(toks) < 6 + dlc or not all(_BYTE_TOKEN.fullmatch(t) for t in text[6 : 6 + dlc]):
        return None
    cols: list[int] = []
    classes: list[int] = []
    exact: dict[int, int] = {}

    def add(col: int, cls: int) -> int:
        cols.append(col)
        classes.append(cls)
        return len(cols) - 1

    def add_exact(col: int) -> None:
        ch = line[col]
        add(col, exact.setdefault(ch, 3 + len(exact)))

    last = toks[5 + dlc][1]
    for c in range(last + (last < len(line))):  # whitespace around the tokens
        if line[c] in b" \t":
            add(c, _SEP)
    (t0, t1), (c0, c1), (i0, i1) = toks[0], toks[1], toks[2]
    dot = line.index(b".", t0)
    ts_digits = [add(c, _DIGIT) for c in range(t0, t1) if c != dot]
    add_exact(dot)
    ch_digits = [add(c, _DIGIT) for c in range(c0, c1)]
    ext = text[2][-1:] in (b"x", b"X")
    id_hex = [add(c, _HEXC) for c in range(i0, i1 - ext)]
    if ext:
        add_exact(i1 - 1)
    for c in (toks[3][0], toks[3][0] + 1, toks[4][0], toks[5][0]):
        add_exact(c)
    data_hex = [add(c, _HEXC) for s, _ in toks[6 : 6 + dlc] for c in (s, s + 1)]
    table = np.zeros((3 + len(exact), 256), bool)
    table[:3] = _CLASS_TABLE
    for ch, row in exact.items():
        table[row, ch] = True
    return _Layout(np.asarray(cols, np.int64), np.asarray(classes, np.intp), table,
                   np.asarray(ts_digits, np.intp), t1 - dot - 1, np.asarray(ch_digits, np.intp),
                   np.asarray(id_hex, np.intp), ext, np.asarray(data_hex, np.intp), dlc)


def _parse_layout(rows: np.ndarray, lay: _Layout, out: dict[str, np.ndarray],
                  idx: np.ndarray) -> np.ndarray:
    """Parse the lines ``idx`` (character matrix ``rows``) of layout ``lay`` into ``out``.

    Every checked column's character must be of its class
    (:func:`~rigtools.ingest.can.text_kernels.parse_asc_rows`) and the identifier within 11
    or 29 bits. Returns the mask of the lines that have the layout (the others are left alone).
    """
    n = idx.size
    ok = np.empty(n, bool)
    mantissa = np.empty(n)
    ch = np.empty(n, np.int64)
    can_id = np.empty(n, np.int64)
    data = np.zeros((n, 8), np.uint8)
    parse_asc_rows(rows, lay.cols, lay.classes, lay.table, lay.ts_digits, lay.ch_digits,
                   lay.id_hex, lay.data_hex, HEX_VALUE, ok, mantissa, ch, can_id, data)
    ok &= can_id <= (0x1FFFFFFF if lay.extended else 0x7FF)
    sel = idx if bool(ok.all()) else idx[ok]
    if sel.size == 0:
        return ok
    keep = slice(None) if sel is idx else ok
    out["plain"][sel] = True
    out["mantissa"][sel] = mantissa[keep]
    out["scale"][sel] = float(10**lay.frac)
    ch = ch[keep] - 1
    out["channel"][sel] = np.where(ch <= 32767, ch, -1)
    out["can_id"][sel] = can_id[keep]
    out["extended"][sel] = lay.extended
    out["length"][sel] = lay.dlc
    if lay.dlc:
        out["data"].view("V8")[sel, 0] = data[keep].view("V8")[:, 0]
    return ok


def parse_frame_lines(block: bytes) -> FrameLines:
    r"""Find and parse the plain classic data-frame lines of a block.

    The lines of the most common lengths are parsed as character matrices when the first of
    them is a plain frame line (its columns are then checked on every line of that length);
    the other lines are tokenised (:func:`_parse_tokens`). Both follow the same rules.

    Parameters
    ----------
    block : bytes
        Whole lines, each ending with ``\n`` (carriage returns already turned into line
        feeds, as the line reader does).

    Returns
    -------
    FrameLines
        One entry per line.
    """
    a = np.frombuffer(block, np.uint8)
    nl = np.flatnonzero(a == 10)
    n = nl.size
    if n == 0:
        return _empty(nl)
    starts = np.empty(n, np.int64)
    starts[0] = 0
    starts[1:] = nl[:-1] + 1
    lens = nl - starts
    lens[_odd_lines(a, nl)] = -1  # never grouped
    out = {"plain": np.zeros(n, bool), "mantissa": np.zeros(n), "scale": np.ones(n),
           "channel": np.zeros(n, np.int16), "can_id": np.zeros(n, np.uint32),
           "extended": np.zeros(n, bool), "length": np.zeros(n, np.uint8),
           "data": np.zeros((n, 8), np.uint8)}
    counts = np.bincount(np.clip(lens, 0, 1023), minlength=1024)
    counts[0] = 0
    least = max(_GROUP_MIN_LINES, int(_GROUP_MIN_SHARE * n))
    for width in np.argsort(counts)[::-1][:8].tolist():
        if counts[width] < least or width >= 1023:
            break
        idx = np.flatnonzero(lens == width)
        s0 = int(starts[idx[0]])
        lay = _layout_of(block[s0 : s0 + width])
        if lay is None:
            continue
        rows = byte_rows(a, starts[idx], width)
        _parse_layout(rows, lay, out, idx)
    rest = np.flatnonzero(~out["plain"] & (lens >= 14))
    if rest.size:
        sub = _parse_tokens(b"".join([block[s : e + 1] for s, e in
                                      zip(starts[rest].tolist(), nl[rest].tolist(),
                                          strict=True)]))
        got = rest[sub.plain]
        out["plain"][got] = True
        for name in ("mantissa", "scale", "channel", "can_id", "extended", "length", "data"):
            out[name][got] = getattr(sub, name)[sub.plain]
    return FrameLines(nl.astype(np.int64), **out)
