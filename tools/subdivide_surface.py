#!/usr/bin/env python3
"""Loop subdivision of a closed triangle surface, for making fine "scan" surfaces of a known
shape (the embedded-surface benchmark, tools/embedded_bench.sh).

usage: subdivide_surface.py IN OUT.ply [--levels N] [--sqrt3 K] [--scale S] [--split-nonmanifold]

IN: .stl (binary or ASCII; corners welded by exact position), or an ASCII .ply with triangle
faces. Each level splits every triangle in four and smooths with Loop's weights, so the
triangle count grows 4x per level. --sqrt3 K: then K levels of Kobbelt's sqrt(3) subdivision
(a vertex at each triangle's centroid, the old edges flipped, the old vertices smoothed), 3x the
triangles each: for sizes between Loop's (Bunny.stl's 2,728 triangles: --levels 1 --sqrt3 2
gives 98,208, a "100k-triangle scan"). OUT is a binary little-endian PLY (double coordinates).
--split-nonmanifold: a vertex where separate fans of triangles meet (the boundary of SOFA's
Armadillo_Tetra_4406.vtu has one) becomes one vertex per fan, each moved a twentieth of the way
into its own fan, so that the surface is manifold and bounds a volume.
Needs numpy only.
"""
import argparse
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from femreg_tools import DisjointSets, read_surface  # noqa: E402


def split_nonmanifold(vertices, faces):
    """One vertex per fan of triangles around each vertex (fans: triangles joined through an
    edge at the vertex); returns the new arrays and the number of vertices added."""
    faces = faces.copy()
    around = {}
    for f, tri in enumerate(faces):
        for v in tri:
            around.setdefault(int(v), []).append(f)
    out = list(vertices)
    added = 0
    for v, fs in sorted(around.items()):
        fan_of = DisjointSets(fs)
        by_edge = {}
        for f in fs:
            for w in faces[f]:
                if w != v:
                    by_edge.setdefault(int(w), []).append(f)
        for shared in by_edge.values():
            for f in shared[1:]:
                fan_of.union(f, shared[0])
        fans = {}
        for f in fs:
            fans.setdefault(fan_of.find(f), []).append(f)
        if len(fans) < 2:
            continue
        for k, fan in enumerate(sorted(fans.values())):
            ring = np.array([vertices[w] for f in fan for w in faces[f] if w != v])
            moved = vertices[v] + 0.05 * (ring.mean(axis=0) - vertices[v])
            if k == 0:
                out[v] = moved
                continue
            out.append(moved)
            added += 1
            for f in fan:
                faces[f] = [len(out) - 1 if w == v else w for w in faces[f]]
    return np.array(out), faces, added


def loop(vertices, faces):
    nv = len(vertices)
    edges = np.sort(np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    unique, edge_of = np.unique(edges, axis=0, return_inverse=True)
    nf = len(faces)
    edge_of = edge_of.reshape(3, nf).T  # per face: edges (0,1), (1,2), (2,0)
    # Each edge's two opposite vertices.
    opposite = np.full((len(unique), 2), -1)
    count = np.zeros(len(unique), dtype=int)
    for k, opp in ((0, 2), (1, 0), (2, 1)):
        e = edge_of[:, k]
        for f in range(nf):
            opposite[e[f], count[e[f]]] = faces[f, opp]
            count[e[f]] += 1
    if (count != 2).any():
        sys.exit("the surface is not closed and manifold")
    a, b = unique[:, 0], unique[:, 1]
    edge_points = 0.375 * (vertices[a] + vertices[b]) + 0.125 * (vertices[opposite[:, 0]] + vertices[opposite[:, 1]])
    # Vertex points: Loop's beta over the one-ring.
    ring_sum = np.zeros_like(vertices)
    valence = np.zeros(nv)
    np.add.at(ring_sum, a, vertices[b])
    np.add.at(ring_sum, b, vertices[a])
    np.add.at(valence, a, 1)
    np.add.at(valence, b, 1)
    beta = np.where(valence == 3, 3.0 / 16.0, 3.0 / (8.0 * valence))
    vertex_points = (1 - valence * beta)[:, None] * vertices + beta[:, None] * ring_sum
    out_vertices = np.vstack([vertex_points, edge_points])
    m = nv + edge_of  # per face, the new vertices on its edges
    v0, v1, v2 = faces[:, 0], faces[:, 1], faces[:, 2]
    e01, e12, e20 = m[:, 0], m[:, 1], m[:, 2]
    out_faces = np.vstack([np.stack([v0, e01, e20], 1), np.stack([v1, e12, e01], 1),
                           np.stack([v2, e20, e12], 1), np.stack([e01, e12, e20], 1)])
    return out_vertices, out_faces


def sqrt3(vertices, faces):
    """One level of Kobbelt's sqrt(3) subdivision of a closed manifold surface: 3x the triangles.
    Each half-edge a->b of face f, whose twin b->a is in face g, becomes the triangle
    (a, centroid of g, centroid of f); the old vertices move by Kobbelt's weights."""
    nv, nf = len(vertices), len(faces)
    a = faces.reshape(-1)                      # half-edge h = 3 f + k: corner k -> corner k+1
    b = faces[:, [1, 2, 0]].reshape(-1)
    face_of = np.repeat(np.arange(nf), 3)
    key = a.astype(np.int64) * nv + b
    order = np.argsort(key)
    twin_key = b.astype(np.int64) * nv + a
    at = np.searchsorted(key[order], twin_key)
    if (at >= len(key)).any() or (key[order][np.minimum(at, len(key) - 1)] != twin_key).any():
        sys.exit("the surface is not closed and manifold")
    twin_face = face_of[order[at]]
    centroids = vertices[faces].mean(axis=1)
    ring_sum = np.zeros_like(vertices)
    valence = np.zeros(nv)
    np.add.at(ring_sum, a, vertices[b])  # each half-edge once: every neighbour once
    np.add.at(valence, a, 1)
    alpha = (4.0 - 2.0 * np.cos(2.0 * np.pi / valence)) / 9.0
    moved = (1.0 - alpha)[:, None] * vertices + (alpha / valence)[:, None] * ring_sum
    out_vertices = np.vstack([moved, centroids])
    out_faces = np.stack([a, nv + twin_face, nv + face_of], axis=1)
    return out_vertices, out_faces


def write_ply(path, vertices, faces):
    header = ("ply\nformat binary_little_endian 1.0\ncomment Loop-subdivided surface\n"
              f"element vertex {len(vertices)}\nproperty double x\nproperty double y\nproperty double z\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
    face_record = np.zeros(len(faces), dtype=np.dtype([("n", "u1"), ("v", "<3i4")]))
    face_record["n"] = 3
    face_record["v"] = faces
    with open(path, "wb") as out:
        out.write(header.encode())
        out.write(np.ascontiguousarray(vertices, dtype="<f8").tobytes())
        out.write(face_record.tobytes())


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input")
    p.add_argument("output")
    p.add_argument("--levels", type=int, default=2)
    p.add_argument("--sqrt3", type=int, default=0)
    p.add_argument("--scale", type=float, default=1.0)
    p.add_argument("--split-nonmanifold", action="store_true")
    args = p.parse_args()
    vertices, faces = read_surface(args.input)
    if args.split_nonmanifold:
        vertices, faces, added = split_nonmanifold(vertices, faces)
        print(f"{args.input}: {added} non-manifold vertices split")
    for _ in range(args.levels):
        vertices, faces = loop(vertices, faces)
    for _ in range(args.sqrt3):
        vertices, faces = sqrt3(vertices, faces)
    write_ply(args.output, vertices * args.scale, faces)
    print(f"{args.output}: {len(vertices)} vertices, {len(faces)} triangles")


if __name__ == "__main__":
    main()
