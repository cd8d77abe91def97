"""Compiled (numba) parsing of fixed-layout text-log lines: digits and hex fields per row.

:mod:`rigtools.ingest.can.candump` and :mod:`rigtools.ingest.can.asc_lines` gather the lines
that share one layout (the same field widths, e.g. ``(SSSSSSSSSS.FFFFFF) CHAN III#DDDD...``)
into a character matrix, one row per line. Their NumPy versions looked each character up in
a table over the whole matrix (a temporary per field, a row gather per check); these kernels
read every row once and give the same numbers: whether each row's fields are what the layout
says, its identifier, its time stamp as an integer count of the last fraction digit, and its
payload bytes. A stamp ``SSS.FFF`` becomes the integer ``SSSFFF`` exactly (at most 18 digits
for candump, 15 for ASC: within int64, and below 2**53 where it is made a float), as the
NumPy dot products with powers of ten did.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["parse_asc_rows", "parse_fixed_rows"]


@njit(cache=True, nogil=True)
def parse_fixed_rows(m: np.ndarray, il: int, fl: int, cl: int, idl: int, fdk: int,
                     remote: int, dl: int, c_chan: int, c_id: int, c_data: int,
                     hex_value: np.ndarray, ok: np.ndarray, can_id: np.ndarray,
                     total: np.ndarray, data: np.ndarray) -> None:  # pragma: no cover
    """Parse the rows of ``m`` (uint8, one line of layout columns per row) in place.

    Parameters
    ----------
    m : numpy.ndarray
        ``(n, width)`` characters (any strides).
    il, fl, cl, idl, fdk, remote, dl, c_chan, c_id, c_data : int
        The layout (``candump._columns``): integer and fraction digits of the stamp, channel
        name length, identifier hex digits, CAN FD flag, remote frame, data characters, and
        the columns where the channel, identifier and data start.
    hex_value : numpy.ndarray
        uint8 per byte: its value as a hex digit, 255 when it is none
        (:data:`rigtools.ingest.can.text_digits.HEX_VALUE`).
    ok, can_id, total, data : numpy.ndarray
        Outputs: bool ``(n,)`` the row's fields are well formed; int64 ``(n,)`` identifier
        bits (the error flag included); int64 ``(n,)`` the stamp's digits as one integer;
        uint8 ``(n, >= dl // 2)`` payload bytes (untouched for a remote frame). Rows that are
        not ``ok`` hold partial values.
    """
    n = m.shape[0]
    nb = dl // 2
    for r in range(n):
        good = True
        t = np.int64(0)
        for j in range(il):
            v = np.int64(m[r, 1 + j]) - 48
            if v < 0 or v > 9:
                good = False
            t = t * 10 + v
        for j in range(fl):
            v = np.int64(m[r, 2 + il + j]) - 48
            if v < 0 or v > 9:
                good = False
            t = t * 10 + v
        total[r] = t
        for j in range(cl):
            ch = m[r, c_chan + j]
            if ch < 33 or ch > 126:
                good = False
        ident = np.int64(0)
        for j in range(idl):
            v = np.int64(hex_value[m[r, c_id + j]])
            if v > 15:
                good = False
            ident = (ident << 4) | (v & 15)
        can_id[r] = ident
        if fdk and hex_value[m[r, c_data - 1]] > 15:
            good = False
        if remote:
            for j in range(1, dl):
                v = np.int64(m[r, c_data + j]) - 48
                if v < 0 or v > 9:
                    good = False
        else:
            for b in range(nb):
                hi = hex_value[m[r, c_data + 2 * b]]
                lo = hex_value[m[r, c_data + 2 * b + 1]]
                if hi > 15 or lo > 15:
                    good = False
                data[r, b] = ((hi & 15) << 4) | (lo & 15)
        ok[r] = good


@njit(cache=True, nogil=True)
def parse_asc_rows(rows: np.ndarray, cols: np.ndarray, classes: np.ndarray, table: np.ndarray,
                   ts_digits: np.ndarray, ch_digits: np.ndarray, id_hex: np.ndarray,
                   data_hex: np.ndarray, hex_value: np.ndarray, ok: np.ndarray,
                   mantissa: np.ndarray, channel: np.ndarray, can_id: np.ndarray,
                   data: np.ndarray) -> None:  # pragma: no cover - compiled
    """Parse the rows of ``rows`` (one ASC frame line of a known layout each) in place.

    Parameters
    ----------
    rows : numpy.ndarray
        ``(n, width)`` uint8 characters.
    cols, classes, table : numpy.ndarray
        The columns checked, the class of each and the (classes, 256) table of the characters
        a class allows (``asc_lines._Layout``).
    ts_digits, ch_digits, id_hex, data_hex : numpy.ndarray
        Positions in ``cols`` of the stamp's digits, the channel's digits, the identifier's
        hex digits and the data bytes' high and low hex digits.
    hex_value : numpy.ndarray
        uint8 per byte: its value as a hex digit, 255 when it is none.
    ok, mantissa, channel, can_id, data : numpy.ndarray
        Outputs: bool, every checked character of its class; float64 stamp digits as one
        integer; int64 channel number as written; int64 identifier; uint8 ``(n, >= dlc)``
        payload bytes. Rows that are not ``ok`` hold partial values.
    """
    n = rows.shape[0]
    for r in range(n):
        good = True
        for k in range(cols.size):
            if not table[classes[k], rows[r, cols[k]]]:
                good = False
        m = np.int64(0)
        for j in ts_digits:
            m = m * 10 + (np.int64(rows[r, cols[j]]) - 48)
        mantissa[r] = m
        ch = np.int64(0)
        for j in ch_digits:
            ch = ch * 10 + (np.int64(rows[r, cols[j]]) - 48)
        channel[r] = ch
        ident = np.int64(0)
        for j in id_hex:
            ident = (ident << 4) | (np.int64(hex_value[rows[r, cols[j]]]) & 15)
        can_id[r] = ident
        for b in range(data_hex.size // 2):
            hi = hex_value[rows[r, cols[data_hex[2 * b]]]] & 15
            lo = hex_value[rows[r, cols[data_hex[2 * b + 1]]]] & 15
            data[r, b] = (hi << 4) | lo
        ok[r] = good
