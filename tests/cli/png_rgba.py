"""The 8-bit RGBA PNGs blvd writes (frames, object ids), read with the standard
library alone, for the shell tests' checks."""
import struct
import zlib


def read(path):
    """Returns (width, height, rows): each row a bytearray of width * 4 bytes."""
    b = open(path, "rb").read()
    w, h, depth, ctype = struct.unpack(">IIBB", b[16:26])
    assert (depth, ctype) == (8, 6), "%s: not 8-bit RGBA (depth %d, colour type %d)" % (path, depth, ctype)
    pos, idat = 8, b""
    while pos < len(b):
        n, = struct.unpack(">I", b[pos:pos + 4])
        if b[pos + 4:pos + 8] == b"IDAT":
            idat += b[pos + 8:pos + 8 + n]
        pos += 12 + n
    raw, stride, prev, rows = zlib.decompress(idat), w * 4, bytearray(w * 4), []
    for y in range(h):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for x in range(stride):
            a = line[x - 4] if x >= 4 else 0
            c = prev[x - 4] if x >= 4 else 0
            p = a + prev[x] - c
            pred = [0, a, prev[x], (a + prev[x]) // 2,
                    a if abs(p - a) <= abs(p - prev[x]) and abs(p - a) <= abs(p - c)
                    else (prev[x] if abs(p - prev[x]) <= abs(p - c) else c)][f]
            line[x] = (line[x] + pred) & 255
        rows.append(line)
        prev = line
    return w, h, rows
