"""Object-level parsing of BLF log objects: the walk over a block and vectorised frame decoding.

The part of :mod:`rigtools.ingest.can.blf` below the container level: the blocks of
decompressed data waiting to be parsed, the walk over the object headers of a block and the
decoding of the frame fields over all objects of a type at once. The object layouts and the
reading of their fields are :mod:`rigtools.ingest.can.blf_records`;
:mod:`rigtools.ingest.can.blf` streams the containers and feeds this module.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rigtools.ingest.can.blf_kernels import plain_frame_columns, walk_sound_objects
from rigtools.ingest.can.blf_records import (
    CAN_FD_MESSAGE,
    CAN_FD_MESSAGE_64,
    ERROR_TYPES,
    FRAME_TYPES,
    HEADER_REST,
    LOBJ,
    OBJ_BASE,
    RECORD_DTYPES,
    read_records,
    tick_seconds,
)
from rigtools.ingest.can.frames import CanFrameBatch, byte_rows, take_rows
from rigtools.ingest.recording import IngestReport

__all__ = [
    "ContainerOrigin",
    "FrameColumns",
    "ObjectParser",
    "ParseBlock",
]

@dataclass
class ParseBlock:
    """Decompressed data waiting to be parsed, with the container each byte came from."""

    parts: list[bytes | bytearray] = field(default_factory=list)
    starts: list[int] = field(default_factory=list)  # offset in the joined block
    origins: list[int] = field(default_factory=list)  # container byte offset in the file
    size: int = 0
    need: int = 0  # bytes the first (unfinished) object needs before parsing is worth it

    def add(self, data: bytes | bytearray, origin: int) -> None:
        """Append decompressed data of the container at file offset ``origin`` (bytes)."""
        if not data:
            return
        self.parts.append(data)
        self.starts.append(self.size)
        self.origins.append(origin)
        self.size += len(data)


@dataclass
class FrameColumns:
    """Decoded frame columns waiting to be cut into batches."""

    cols: list[tuple[np.ndarray, ...]] = field(default_factory=list)
    n: int = 0

    def add(self, cols: tuple[np.ndarray, ...]) -> None:
        """Append the columns of decoded frames (none when they hold no frame)."""
        if cols[0].size:
            self.cols.append(cols)
            self.n += int(cols[0].size)

    def take(self, batch_frames: int, final: bool) -> Iterator[CanFrameBatch]:
        """Batches of ``batch_frames`` frames while there are that many; the rest if ``final``."""
        while self.n and (self.n >= batch_frames or final):
            width = max(c[5].shape[1] for c in self.cols)
            joined = []
            for k in range(8):
                if k == 5:
                    data = np.zeros((self.n, width), np.uint8)
                    row = 0
                    for c in self.cols:
                        data[row : row + c[5].shape[0], : c[5].shape[1]] = c[5]
                        row += c[5].shape[0]
                    joined.append(data)
                else:
                    arrs = [c[k] for c in self.cols]
                    joined.append(arrs[0] if len(arrs) == 1 else np.concatenate(arrs))
            m = min(batch_frames, self.n)
            j = [a[:m] for a in joined]
            yield CanFrameBatch(j[0], j[1], j[2], j[3], j[4], j[5], j[6], j[7], "byte")
            rest = tuple(a[m:] for a in joined)
            self.cols = [rest] if m < self.n else []
            self.n -= m


class ObjectParser:
    """State of one BLF read: the report, the carry-over between blocks and the counters."""

    def __init__(self, path: str, report: IngestReport, start_s: float,
                 max_object: int) -> None:
        self.path = path
        self.report = report
        self.start_s = start_s
        self.max_object = max_object
        self.resync = False
        self.warned_dlc = False
        self.warned_channel = False
        self.stop = 0
        self.plain: tuple[np.ndarray, ...] | None = None

    # -- walking object headers --------------------------------------------------------------
    def walk(
        self, buf: bytes | bytearray, origin_of: ContainerOrigin, final: bool = True,
        decode: bool = False,
    ) -> tuple[np.ndarray, ...] | None:
        """Locate the complete objects of ``buf``.

        Returns the offsets, types, header versions, object sizes and header sizes of the
        objects found (None when there is none) and sets ``self.stop`` to where the unfinished
        remainder begins. With ``decode``, the plain classic frames the compiled walk meets
        are decoded on the way into ``self.plain`` (block offset, position, timestamp,
        identifier, extended flag, length, data, channel; None when there is none) and left
        out of the objects returned. The walk goes object by object, as python-can does: the next
        ``LOBJ`` must start within 8 bytes of the end of the previous object (padding). Sound
        objects are walked by a compiled loop
        (:func:`~rigtools.ingest.can.blf_kernels.walk_sound_objects`); where it stops, this
        loop decides (damage, resynchronisation, objects cut at the block's end), taking
        consecutive objects of one type and size arithmetically, their headers checked by
        NumPy in growing runs.
        """
        n = len(buf)
        unpack = OBJ_BASE.unpack_from
        find = buf.find
        starts: list[int] = []
        strides: list[int] = []
        counts: list[int] = []
        kinds: list[tuple[int, int, int, int]] = []
        pos = 0
        cooldown = 0
        run_step = 16  # objects checked at once when a run starts
        short_runs = 0  # short runs in a row: the object-by-object stretch after one doubles
        max_object = self.max_object
        arr = np.frombuffer(buf, np.uint8)
        # objects the compiled walk took (a classic CAN object takes 48 bytes; grown if full):
        # the plain frames it decoded, the other objects' headers
        frames = plain_frame_columns(n // 40 + 16 if decode else 0)
        sound = np.empty((n // (400 if decode else 40) + 16, 5), np.int64)
        n_sound = n_frames = 0
        while True:
            if not self.resync:
                got, got_frames, pos = walk_sound_objects(
                    arr, pos, max_object, sound, n_sound, decode, origin_of.starts,
                    origin_of.origins, self.start_s, frames, n_frames)
                n_sound += got
                n_frames += got_frames
                if n_sound == sound.shape[0]:
                    sound = np.concatenate([sound, np.empty_like(sound)])
                    continue
                if decode and n_frames == frames[0].shape[0]:
                    frames = tuple(np.concatenate([c, np.empty_like(c)]) for c in frames)
                    continue
            if self.resync:
                j = find(LOBJ, pos)
                if j < 0:
                    pos = max(pos, n - 3)
                    break
                pos = j
                if j + 16 > n:
                    break
                _, hs, hv, osize, otype = unpack(buf, j)
                if hv not in HEADER_REST or not 16 + HEADER_REST[hv] <= osize <= max_object:
                    pos = j + 1
                    continue
                self.resync = False
            else:
                j = find(LOBJ, pos, pos + 8)
                if j < 0:
                    if pos + 8 > n:
                        break
                    self.report.reject("corrupt_object", 1, f"byte {origin_of(pos)}")
                    self.resync = True
                    continue
                if j + 16 > n:
                    break
                _, hs, hv, osize, otype = unpack(buf, j)
                if osize < 16 or osize > max_object:
                    self.report.reject("corrupt_object", 1, f"byte {origin_of(j)}")
                    self.resync = True
                    pos = j + 4
                    continue
                end = j + osize
                if (end > n and final) or (end + 8 <= n and find(LOBJ, end, end + 8) < 0):
                    # The object does not end where another begins: a size field that lies
                    # would swallow the objects after it. A plausible header inside the body
                    # gives the lie away; resynchronise there. An object that runs past a
                    # buffer with more data to come is looked at again once it is whole (a
                    # payload that happens to hold "LOBJ" is no lie). The search starts
                    # right after the signature: the head of an object cut off by a reordered
                    # container may be shorter than a header, the next object inside it.
                    k = self._inner_header(buf, j + 4, min(end, n))
                    if k >= 0:
                        self.report.reject("corrupt_object", 1, f"byte {origin_of(j)}")
                        self.resync = True
                        pos = k
                        continue
            if j + osize > n:
                break
            nxt = j + osize
            count = 1
            stride = osize
            if cooldown:
                cooldown -= 1
            else:
                k = find(LOBJ, nxt, nxt + 8)
                if k >= 0:
                    stride = k - j
                    # the 16 header bytes every object of the run repeats
                    head = np.frombuffer(buf, "V16", 1, j)[0]
                    head_bytes = buf[j : j + 16]
                    step = run_step
                    while True:
                        first = j + stride * count
                        if first + osize > n or buf[first : first + 16] != head_bytes:
                            break  # (a lone object of its kind: no array for it)
                        m = min(step, (n - osize - first) // stride + 1)
                        v = np.ndarray((m,), "V16", buffer=buf, offset=first,
                                       strides=(stride,))
                        ok = v == head
                        if ok.all():
                            count += m
                            step = min(step * 4, 1 << 16)
                            continue
                        count += int(np.argmin(ok))
                        break
                    # start the next run's check at about this run's length
                    run_step = 16
                    while run_step * 4 <= min(count, 1 << 16):
                        run_step *= 4
                    if count < 4:
                        # Objects of mixed types: walk a few one by one before looking for a
                        # run again (more after each short run, up to 32). A lone object of
                        # another type (an error frame) costs one short run, not 32 objects.
                        short_runs += 1
                        cooldown = min(32, (1 << short_runs) - 1)
                    else:
                        short_runs = 0
                    last_end = j + stride * (count - 1) + osize
                    if count > 1 and last_end + 8 <= n and find(LOBJ, last_end, last_end + 8) < 0:
                        # The run's last header is sound but the object does not end where
                        # another begins (the head of an object whose container was moved):
                        # leave it to the object-by-object check of the next round.
                        count -= 1
            starts.append(j)
            strides.append(stride)
            counts.append(count)
            kinds.append((otype, hv, osize, hs))
            pos = j + stride * (count - 1) + osize
        self.stop = pos
        self.plain = tuple(c[:n_frames] for c in frames) if n_frames else None
        walked = self._runs(starts, strides, counts, kinds)
        if n_sound == 0:
            return walked
        took = sound[:n_sound]
        if walked is None:
            return tuple(np.ascontiguousarray(took[:, c]) for c in range(5))
        merged = np.concatenate([took, np.stack(walked, axis=1)])
        merged = merged[np.argsort(merged[:, 0], kind="stable")]
        return tuple(np.ascontiguousarray(merged[:, c]) for c in range(5))

    @staticmethod
    def _runs(starts: list[int], strides: list[int], counts: list[int],
              kinds: list[tuple[int, int, int, int]]) -> tuple[np.ndarray, ...] | None:
        """The objects of the runs the Python walk took, as per-object columns."""
        if not starts:
            return None
        if len(starts) == 1:
            offsets = starts[0] + strides[0] * np.arange(counts[0], dtype=np.int64)
            kd = np.asarray(kinds, np.int64)
            return (offsets, *(np.full(counts[0], kd[0, c], np.int64) for c in range(4)))
        ct = np.asarray(counts, np.int64)
        total = int(ct.sum())
        if len(starts) == total:
            offsets = np.asarray(starts, np.int64)
            kd = np.asarray(kinds, np.int64)
        else:
            first_of_run = np.repeat(np.cumsum(ct) - ct, ct)
            offsets = np.repeat(np.asarray(starts, np.int64), ct) + np.repeat(
                np.asarray(strides, np.int64), ct) * (np.arange(total) - first_of_run)
            kd = np.repeat(np.asarray(kinds, np.int64), ct, axis=0)
        return offsets, kd[:, 0], kd[:, 1], kd[:, 2], kd[:, 3]

    def _inner_header(self, buf: bytes | bytearray, start: int, stop: int) -> int:
        """Offset of the first plausible object header in ``buf[start:stop]``, or -1."""
        j = buf.find(LOBJ, start, stop)
        while j >= 0 and j + 16 <= len(buf):
            _, _hs, hv, osize, _t = OBJ_BASE.unpack_from(buf, j)
            if hv in HEADER_REST and 16 + HEADER_REST[hv] <= osize <= self.max_object:
                return j
            j = buf.find(LOBJ, j + 1, stop)
        return -1

    # -- decoding ----------------------------------------------------------------------------
    def parse(self, block: ParseBlock, out: FrameColumns, final: bool) -> ParseBlock:
        """Decode the complete objects of ``block``; return the block of the remainder.

        With ``final``, an unfinished remainder is counted as ``truncated_object``.
        """
        if block.size == 0:
            return ParseBlock()
        buf = block.parts[0] if len(block.parts) == 1 else b"".join(block.parts)
        origin_of = ContainerOrigin(np.asarray(block.starts, np.int64),
                            np.asarray(block.origins, np.int64))
        walked = self.walk(buf, origin_of, final, decode=True)
        self._decode(buf, walked, origin_of, out)
        rest = ParseBlock()
        if self.stop < len(buf):
            tail = buf[self.stop :]
            origin = origin_of(self.stop)
            if final:
                # Zero bytes are padding; anything else is the start of an object cut short.
                if tail.strip(b"\x00") and (not self.resync or tail.find(LOBJ) >= 0):
                    self.report.reject("truncated_object", 1, f"byte {origin}")
            else:
                rest.add(tail, origin)
                j = tail.find(LOBJ, 0, 8)
                if j >= 0 and j + 16 <= len(tail):  # parse again once it can be complete
                    rest.need = j + OBJ_BASE.unpack_from(tail, j)[3]
        return rest

    def _decode(self, buf: bytes | bytearray, walked: tuple[np.ndarray, ...] | None,
                origin_of: ContainerOrigin, out: FrameColumns) -> None:
        """Frame columns of the plain frames and of the objects walked, in object order."""
        pieces: list[tuple[np.ndarray, ...]] = []  # (block offset, *columns, position)
        if self.plain is not None:
            off, position, ts, ident, ext, length, data, channel = self.plain
            pieces.append((off, ts, ident, ext, np.zeros(off.size, bool), length, data,
                           channel, position))
            self.plain = None
        if walked is not None:
            self._decode_objects(buf, walked, origin_of, pieces)
        if not pieces:
            return
        if len(pieces) == 1:
            out.add(pieces[0][1:])
            return
        seq = np.concatenate([p[0] for p in pieces])
        order = np.argsort(seq, kind="stable")
        width = max(p[6].shape[1] for p in pieces)
        merged: list[np.ndarray] = []
        for k in range(1, 9):
            if k == 6:
                d = np.zeros((seq.size, width), np.uint8)
                row = 0
                for p in pieces:
                    d[row : row + p[6].shape[0], : p[6].shape[1]] = p[6]
                    row += p[6].shape[0]
                merged.append(d[order])
            else:
                merged.append(np.concatenate([p[k] for p in pieces])[order])
        out.add(tuple(merged))

    def _decode_objects(self, buf: bytes | bytearray, walked: tuple[np.ndarray, ...],
                        origin_of: ContainerOrigin, pieces: list[tuple[np.ndarray, ...]]
                        ) -> None:
        """Report the objects walked that are no frame; append the frames' columns by type."""
        offsets, types, versions, sizes, hsizes = walked
        report = self.report
        key = types * 4 + versions
        if bool((key == key[0]).all()):
            uniq = key[:1]
        elif int(key.max()) < 1 << 12:  # object types of 0..1023: counted, not sorted
            uniq = np.flatnonzero(np.bincount(key))
        else:
            uniq = np.unique(key)
        a = np.frombuffer(buf, np.uint8)
        for kv in uniq.tolist():
            t, v = divmod(kv, 4)
            idx = None if uniq.size == 1 else np.flatnonzero(key == kv)

            def take(arr: np.ndarray, idx: np.ndarray | None = idx) -> np.ndarray:
                return arr if idx is None else arr[idx]

            offs = take(offsets)
            where = f"byte {origin_of(int(offs[0]))}"
            if t in ERROR_TYPES:
                report.reject("error_frame", offs.size, where)
                continue
            if v not in HEADER_REST:
                report.reject("corrupt_object", offs.size, where)
                continue
            if t not in FRAME_TYPES:
                report.reject(f"blf_object_type_{t}", offs.size, where)
                continue
            dt = RECORD_DTYPES[(t, v)]
            small = take(sizes) < dt.itemsize
            if small.any():
                report.reject("corrupt_object", int(small.sum()),
                              f"byte {origin_of(int(offs[np.argmax(small)]))}")
                keep = np.flatnonzero(~small)
                idx = keep if idx is None else idx[keep]
                if idx.size == 0:
                    continue
                offs = offsets[idx]
            rec = read_records(buf, offs, t, v)
            got = self._frame_columns(t, v, rec, a, offs, take(sizes, idx), take(hsizes, idx),
                                      origin_of)
            if got is None:
                continue
            keep_rows, cols = got
            if keep_rows is not None:
                offs = offs[keep_rows]
            pieces.append((offs, *cols, origin_of(offs)))

    def _frame_columns(
        self, t: int, v: int, rec: Any, a: np.ndarray, offs: np.ndarray,
        osz: np.ndarray, hsz: np.ndarray, origin_of: ContainerOrigin,
    ) -> tuple[np.ndarray | None, tuple[np.ndarray, ...]] | None:
        """Columns (timestamp, id, extended, fd, length, data, channel) of one object type."""
        report = self.report

        def first(mask: np.ndarray) -> str:
            return f"byte {origin_of(int(offs[np.argmax(mask)]))}"

        if t == CAN_FD_MESSAGE_64:
            fdfl = rec["fdfl"]
            bad = (fdfl & 0x0010) != 0
            is_fd = (fdfl & 0x1000) != 0
        else:
            bad = (rec["fl"] & 0x80) != 0
            is_fd = ((rec["fdfl"] & 0x01) != 0 if t == CAN_FD_MESSAGE
                     else np.zeros(offs.size, bool))
        if bad.any():
            report.reject("remote_frame", int(bad.sum()), first(bad))
        if t == CAN_FD_MESSAGE_64:
            valid = rec["valid"].astype(np.int64)
            over = (valid > 64) & ~bad
            if over.any():
                report.reject("invalid_length", int(over.sum()), first(over))
                bad = bad | over
            ext = rec["ext"].astype(np.int64)
            span = np.where(ext != 0, ext, osz) - hsz - 40
            dfl = np.clip(np.minimum(valid, span), 0, 64)
            start = offs + (16 + HEADER_REST[v] + 40)
            padded = np.concatenate([a, np.zeros(64, np.uint8)])
            data = byte_rows(padded, start, 64)
            data = np.where(np.arange(64) < dfl[:, None], data, 0).astype(np.uint8)
            length = np.minimum(valid, 64).astype(np.uint8)
        elif t == CAN_FD_MESSAGE:
            length = np.minimum(rec["valid"], 64).astype(np.uint8)
            data = rec["data"]
        else:
            dlc = rec["dlc"]
            length = np.minimum(dlc, 8).astype(np.uint8)
            big = dlc > 15
            if not self.warned_dlc and big.any():
                self.warned_dlc = True
                report.warn(f"{self.path}: classic CAN frame(s) with DLC above 15 (first: DLC "
                            f"{int(dlc[np.argmax(big)])} at {first(big)}); kept with their "
                            "8 data bytes")
            data = rec["data"]
        keep = None
        raw_id, ch, flags, ts = rec["id"], rec["ch"], rec["flags"], rec["ts"]
        if bad.any():
            keep = np.flatnonzero(~bad)
            if keep.size == 0:
                return None
            # fields one by one: indexing the strided records would copy every field
            raw_id, ch, flags, ts = raw_id[keep], ch[keep], flags[keep], ts[keep]
            data, length, is_fd = take_rows(data, keep), length[keep], is_fd[keep]
        if length.size and data.shape[1] == 64 and int(length.max()) <= 8:
            data = data[:, :8]
        width = data.shape[1]
        data = np.ascontiguousarray(data)
        short = np.flatnonzero(length < width)
        if short.size:
            if data.base is not None or not data.flags.writeable:
                data = data.copy()
            data[short] *= np.arange(width) < length[short, None]
        channel = ch.astype(np.int32) - 1
        wide = channel > 32767
        if wide.any():
            if not self.warned_channel:
                self.warned_channel = True
                report.warn(f"{self.path}: BLF channel numbers above 32768 set to -1")
            channel[wide] = -1
        cols = (
            tick_seconds(flags, ts, self.start_s),
            (raw_id & 0x1FFFFFFF).astype(np.uint32),
            (raw_id & 0x80000000) != 0,
            np.ascontiguousarray(is_fd),
            length,
            data,
            channel.astype(np.int16),
        )
        return keep, cols


class ContainerOrigin:
    """Map byte offsets of a parse block to the file offset of the container they came from."""

    def __init__(self, starts: np.ndarray, origins: np.ndarray) -> None:
        self.starts = starts
        self.origins = origins

    def __call__(self, p: int | np.ndarray) -> Any:
        """File offset of the container of block offset(s) ``p`` (int, or int64 array)."""
        if self.starts.size == 1:
            if isinstance(p, np.ndarray):
                return np.full(p.shape, self.origins[0], np.int64)
            return int(self.origins[0])
        if isinstance(p, np.ndarray):
            if p.size > 64 and bool(np.all(p[1:] >= p[:-1])):
                # sorted offsets: count the objects of each segment instead of a search each
                counts = np.diff(np.searchsorted(p, self.starts, side="left"), append=p.size)
                counts[0] += int(np.searchsorted(p, self.starts[0]))
                return np.repeat(self.origins, counts)
            return self.origins[np.searchsorted(self.starts, p, side="right") - 1]
        return int(self.origins[np.searchsorted(self.starts, p, side="right") - 1])
