"""What the scripts that write test glTF files share: a PNG encoder and a binary buffer of
accessors. Import it with sys.path pointing at this folder (tests/scenes)."""
import struct
import zlib


def png(width, height, rows):
    """An 8-bit RGB PNG from rows of bytes."""
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))
    raw = b"".join(b"\0" + bytes(row) for row in rows)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


class GltfBuffer:
    """One buffer's bytes with its buffer views and accessors, as lists for the glTF JSON."""

    def __init__(self):
        self.data = bytearray()
        self.views = []
        self.accessors = []

    def add(self, values, kind, component=5126, fmt="f"):
        """An accessor of `values` (tuples for VEC2/VEC3, numbers for SCALAR), 4-byte aligned;
        VEC3 gets its min and max. Returns its index."""
        flat = [c for v in values for c in (v if isinstance(v, (tuple, list)) else (v,))]
        offset = len(self.data)
        self.data.extend(struct.pack("<%d%s" % (len(flat), fmt), *flat))
        while len(self.data) % 4:
            self.data.append(0)
        self.views.append({"buffer": 0, "byteOffset": offset,
                           "byteLength": len(flat) * struct.calcsize(fmt)})
        accessor = {"bufferView": len(self.views) - 1, "componentType": component,
                    "count": len(values), "type": kind}
        if kind == "VEC3":
            accessor["min"] = [min(v[i] for v in values) for i in range(3)]
            accessor["max"] = [max(v[i] for v in values) for i in range(3)]
        self.accessors.append(accessor)
        return len(self.accessors) - 1
