"""An independent walker over MCAP files, for locating what the hostile tests damage.

Deliberately not rigtools' reader: the tests must find chunk fields without the code they test.
"""

import struct

HDR = struct.Struct("<BQ")  # record opcode, content length


def records(data: bytes) -> list[tuple[int, int, int]]:
    """(opcode, offset, content length) of every top-level record up to and including Footer."""
    out, pos = [], 8
    while pos + 9 <= len(data):
        op, length = HDR.unpack_from(data, pos)
        out.append((op, pos, length))
        pos += 9 + length
        if op == 0x02:
            break
    return out


def chunks(data: bytes) -> list[dict[str, int | str]]:
    """Offsets of the fields of every Chunk record."""
    out = []
    for op, pos, length in records(data):
        if op != 0x06:
            continue
        c = pos + 9
        clen = struct.unpack_from("<I", data, c + 28)[0]
        rlen_at = c + 32 + clen
        rlen = struct.unpack_from("<Q", data, rlen_at)[0]
        out.append({"pos": pos, "end": pos + 9 + length, "usize_at": c + 16, "crc_at": c + 24,
                    "clen_at": c + 28, "compression": data[c + 32 : c + 32 + clen].decode(),
                    "comp_at": c + 32,
                    "records_at": rlen_at + 8, "records_len": rlen})
    return out
