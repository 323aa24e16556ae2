"""What the scripts of tools/ share: a union-find, the best rigid fit, and readers of the files
they take (femreg's VTU output, STL and ASCII PLY surfaces).

Only numpy and the standard library, so that the scripts run without the femreg Python module
(which reads tetrahedral meshes and clouds, but neither a VTU's point and cell arrays nor a
triangle surface). A script in tools/ imports it after putting its own folder on sys.path:

    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    import femreg_tools  # noqa: E402
"""
import re
import struct
import zlib

import numpy as np


class DisjointSets:
    """Union-find over integers (or any ordered, hashable items), with path halving; an item
    is its own set until joined."""

    def __init__(self, items=()):
        self.parent = {x: x for x in items}

    def find(self, x):
        parent = self.parent
        parent.setdefault(x, x)
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    def union(self, a, b):
        a, b = self.find(a), self.find(b)
        if a != b:
            self.parent[max(a, b)] = min(a, b)


def components(n, cells):
    """The connected pieces of n vertices joined by cells (rows of vertex indices): one label
    per vertex, 0, 1, ... in the order of each piece's first vertex."""
    sets = DisjointSets(range(n))
    for cell in cells:
        for other in cell[1:]:
            sets.union(cell[0], other)
    roots = {}
    return np.array([roots.setdefault(sets.find(i), len(roots)) for i in range(n)])


def kabsch(a, b):
    """The best rigid fit of points a onto points b (equal weights): (R, t) with b ~ a R^T + t."""
    ca, cb = a.mean(0), b.mean(0)
    u, _, vt = np.linalg.svd((a - ca).T @ (b - cb))
    d = np.sign(np.linalg.det(vt.T @ u.T))
    r = vt.T @ np.diag([1.0, 1.0, d]) @ u.T
    return r, cb - r @ ca


_VTU_TYPES = {"Float32": "<f4", "Float64": "<f8", "Int32": "<i4", "Int64": "<i8", "UInt8": "u1",
              "UInt32": "<u4", "UInt64": "<u8", "Int8": "i1", "Int16": "<i2", "UInt16": "<u2"}


def read_vtu(path):
    """The arrays of a VTU with appended raw data, as femreg writes it (zlib-compressed or not,
    UInt32 or UInt64 headers): {name: numpy array}, the positions as 'Points'."""
    data = open(path, "rb").read()
    start = data.index(b"<AppendedData")
    head = data[:start].decode("utf-8", "replace")
    raw = data[data.index(b"_", start) + 1:]
    header_type = re.search(r'header_type="(\w+)"', head)
    htype = np.dtype(_VTU_TYPES[header_type.group(1)] if header_type else "<u4")
    compressed = "compressor=" in head.split(">", 1)[0]
    arrays = {}
    for tag in re.finditer(r"<DataArray([^>]*)>", head):
        attrs = dict(re.findall(r'(\w+)="([^"]*)"', tag.group(1)))
        if attrs.get("format") != "appended":
            continue
        offset = int(attrs["offset"])
        dtype = np.dtype(_VTU_TYPES[attrs["type"]])
        hs = htype.itemsize
        if compressed:
            nblocks = int(np.frombuffer(raw, htype, 1, offset)[0])
            sizes = np.frombuffer(raw, htype, 3 + nblocks, offset)
            pos = offset + hs * (3 + nblocks)
            chunks = []
            for size in sizes[3:]:
                chunks.append(zlib.decompress(raw[pos:pos + int(size)]))
                pos += int(size)
            payload = b"".join(chunks)
        else:
            nbytes = int(np.frombuffer(raw, htype, 1, offset)[0])
            payload = raw[offset + hs:offset + hs + nbytes]
        values = np.frombuffer(payload, dtype)
        components = int(attrs.get("NumberOfComponents", "1"))
        arrays[attrs.get("Name", "")] = values.reshape(-1, components) if components > 1 else values
    return arrays


def read_stl(path):
    """A binary or ASCII STL as (vertices, triangles), the corners welded by exact position."""
    data = open(path, "rb").read()
    if data[:5] == b"solid" and b"facet" in data[:400]:
        corners = [list(map(float, line.split()[1:4]))
                   for line in data.decode("ascii", "replace").splitlines()
                   if line.strip().startswith("vertex")]
        corners = np.array(corners, dtype=float)
    else:
        n = struct.unpack("<I", data[80:84])[0]
        record = np.dtype([("n", "<3f4"), ("v", "<9f4"), ("a", "<u2")])
        corners = np.frombuffer(data[84:84 + 50 * n], dtype=record)["v"].reshape(-1, 3).astype(float)
    vertices, index = np.unique(corners, axis=0, return_inverse=True)
    return vertices, index.reshape(-1, 3)


def read_ascii_ply(path):
    """An ASCII PLY's vertices (x y z first) and triangle faces, as (vertices, triangles)."""
    lines = open(path).read().splitlines()
    nv = nf = 0
    i = 0
    while lines[i].strip() != "end_header":
        parts = lines[i].split()
        if parts[:2] == ["element", "vertex"]:
            nv = int(parts[2])
        if parts[:2] == ["element", "face"]:
            nf = int(parts[2])
        i += 1
    body = lines[i + 1:]
    vertices = np.array([list(map(float, line.split()[:3])) for line in body[:nv]])
    faces = np.array([list(map(int, line.split()[1:4])) for line in body[nv:nv + nf]])
    return vertices, faces


def read_surface(path):
    """A triangle surface, .stl (binary or ASCII) or ASCII .ply, as (vertices, triangles)."""
    return read_stl(path) if path.lower().endswith(".stl") else read_ascii_ply(path)
