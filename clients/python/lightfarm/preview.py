"""The PNG preview of a result, as ``lightfarm fetch -o out.png`` makes it (core/src/image_io.cc):
R, G, B times 2^exposure, through the tone curve (core/src/tone_map.cc), sRGB-encoded in 8 bits.

Pure Python: a reader of the scan-line OpenEXR files the farm writes (float or half channels,
no, ZIPS or ZIP compression) and a PNG writer. The C++ code computes in float32; each 8-bit
value here is found among thresholds computed by the same float32 steps, so the bytes agree.
"""

from __future__ import annotations

import bisect
import functools
import itertools
import math
import struct
import sys
import zlib
from array import array
from typing import Dict, List, Tuple

from .errors import InvalidArgument

TONEMAPS = ("clamp", "filmic")

_EXR_MAGIC = 20000630
_LINES_PER_CHUNK = {0: 1, 2: 1, 3: 16}  # no compression, ZIPS, ZIP
_BYTES = {1: 2, 2: 4}  # HALF, FLOAT


def _f32(x: float) -> float:
    """x rounded to float32, overflowing to infinity as float32 arithmetic does."""
    try:
        return struct.unpack("<f", struct.pack("<f", x))[0]
    except OverflowError:
        return math.copysign(math.inf, x)


def _code(tone: str, x: float) -> int:
    """One value to 8-bit sRGB, as ApplyToneCurve and EncodeSrgb8 do in float32."""
    if tone == "filmic":
        if not x > 0:
            x = 0.0
        elif math.isinf(x):
            x = 1.0
        else:
            num = _f32(x * _f32(_f32(_f32(2.51) * x) + _f32(0.03)))
            den = _f32(_f32(x * _f32(_f32(_f32(2.43) * x) + _f32(0.59))) + _f32(0.14))
            y = _f32(num / den)  # inf / inf is NaN, which fmin(y, 1) makes 1
            x = y if y < 1.0 else 1.0
    v = min(max(x if math.isfinite(x) else 0.0, 0.0), 1.0)
    if v <= _f32(0.0031308):
        s = _f32(_f32(12.92) * v)
    else:
        p = _f32(math.pow(v, _f32(1.0 / _f32(2.4))))
        s = _f32(_f32(_f32(1.055) * p) - _f32(0.055))
    return int(math.floor(_f32(s * 255.0) + 0.5))


@functools.lru_cache(maxsize=None)
def _thresholds(tone: str) -> List[float]:
    """For k = 1..255, the least finite float32 that gives at least k: the code of a finite x is
    the number of thresholds at or below it (the curve is monotone)."""
    def value(bits: int) -> float:
        return struct.unpack("<f", struct.pack("<I", bits))[0]

    out = []
    lo = 0
    for k in range(1, 256):
        hi = 0x7F7FFFFF  # the largest finite float32
        if _code(tone, value(hi)) < k:
            out.append(math.inf)
            continue
        while lo < hi:
            mid = (lo + hi) // 2
            if _code(tone, value(mid)) >= k:
                hi = mid
            else:
                lo = mid + 1
        out.append(value(lo))
    return out


def _read_exr(data: bytes, what: str) -> Tuple[int, int, Dict[str, List[float]]]:
    """Width, height and the R, G, B channels (row by row) of a scan-line OpenEXR file."""
    def bad(why: str) -> InvalidArgument:
        return InvalidArgument(f"{what}: cannot make a PNG of this OpenEXR file: {why}")

    if len(data) < 8 or struct.unpack_from("<i", data, 0)[0] != _EXR_MAGIC:
        raise bad("not an OpenEXR file")
    if struct.unpack_from("<i", data, 4)[0] & 0x1A00:
        raise bad("tiled, deep or multi-part")
    at = 8
    attrs: Dict[str, Tuple[str, bytes]] = {}
    while data[at] != 0:
        name_end = data.index(b"\0", at)
        type_end = data.index(b"\0", name_end + 1)
        size = struct.unpack_from("<i", data, type_end + 1)[0]
        start = type_end + 5
        attrs[data[at:name_end].decode()] = (data[name_end + 1:type_end].decode(),
                                              data[start:start + size])
        at = start + size
    at += 1
    channels = []  # (name, type) in file order
    chlist = attrs["channels"][1]
    c = 0
    while chlist[c] != 0:
        end = chlist.index(b"\0", c)
        pixel_type, _, xs, ys = struct.unpack_from("<iB3xii", chlist, end + 1)
        if pixel_type not in _BYTES or xs != 1 or ys != 1:
            raise bad(f"channel {chlist[c:end].decode()} is not float or half at full size")
        channels.append((chlist[c:end].decode(), pixel_type))
        c = end + 17
    compression = attrs["compression"][1][0]
    if compression not in _LINES_PER_CHUNK:
        raise bad(f"compression {compression} (the farm writes ZIP)")
    x0, y0, x1, y1 = struct.unpack("<4i", attrs["dataWindow"][1])
    width, height = x1 - x0 + 1, y1 - y0 + 1
    names = [n for n, _ in channels]
    for n in ("R", "G", "B"):
        if n not in names:
            raise bad(f"no {n} channel")
    lines = _LINES_PER_CHUNK[compression]
    chunks = (height + lines - 1) // lines
    offsets = struct.unpack_from(f"<{chunks}Q", data, at)
    planes: Dict[str, bytearray] = {n: bytearray() for n in names}
    for y, offset in sorted((struct.unpack_from("<i", data, o)[0], o) for o in offsets):
        size = struct.unpack_from("<i", data, offset + 4)[0]
        rows = min(lines, y1 - y + 1)
        expected = rows * width * sum(_BYTES[t] for _, t in channels)
        block = data[offset + 8:offset + 8 + size]
        if compression != 0 and size < expected:
            t = bytes(itertools.accumulate(zlib.decompress(block),
                                           lambda a, b: (a + b - 128) & 0xFF))
            raw = bytearray(len(t))
            half = (len(t) + 1) // 2
            raw[0::2] = t[:half]
            raw[1::2] = t[half:]
            block = bytes(raw)
        if len(block) != expected:
            raise bad(f"the block at line {y} holds {len(block)} bytes, not {expected}")
        p = 0
        for _ in range(rows):
            for name, t in channels:
                n = width * _BYTES[t]
                planes[name] += block[p:p + n]
                p += n
    out = {}
    for name in ("R", "G", "B"):
        t = dict(channels)[name]
        if t == 2:
            values = array("f")
            values.frombytes(bytes(planes[name]))
            if sys.byteorder == "big":
                values.byteswap()
            out[name] = values.tolist()
        else:
            out[name] = list(struct.unpack(f"<{width * height}e", bytes(planes[name])))
    return width, height, out


def _png(width: int, height: int, rgb: bytes) -> bytes:
    def chunk(kind: bytes, body: bytes) -> bytes:
        return (struct.pack(">I", len(body)) + kind + body +
                struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF))

    stride = width * 3
    rows = b"".join(b"\0" + rgb[y * stride:(y + 1) * stride] for y in range(height))
    return (b"\x89PNG\r\n\x1a\n" +
            chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)) +
            chunk(b"sRGB", b"\0") + chunk(b"IDAT", zlib.compress(rows, 6)) +
            chunk(b"IEND", b""))


def exr_to_png(exr: bytes, *, exposure: float = 0.0, tonemap: str = "clamp",
               what: str = "result") -> bytes:
    """The PNG preview of an OpenEXR file's bytes (``what`` names it in errors)."""
    if tonemap not in TONEMAPS:
        raise InvalidArgument(f"tonemap {tonemap!r}: expected clamp or filmic")
    if not (math.isfinite(exposure) and abs(exposure) <= 64):
        raise InvalidArgument(f"exposure {exposure}: expected -64 to 64 (EV)")
    width, height, channels = _read_exr(exr, what)
    thresholds = _thresholds(tonemap)
    scale = _f32(math.pow(2.0, exposure))
    planes = []
    for name in ("R", "G", "B"):
        values = channels[name]
        if scale != 1.0:
            values = array("f", [v * scale for v in values]).tolist()  # float32, as C++
        planes.append(bytes(bisect.bisect_right(thresholds, v) if math.isfinite(v)
                            else _code(tonemap, v) for v in values))
    rgb = bytearray(width * height * 3)
    for k, plane in enumerate(planes):
        rgb[k::3] = plane
    return _png(width, height, bytes(rgb))
