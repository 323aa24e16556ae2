#!/usr/bin/env python3
"""Does `femreg mesh --edge-length L` give edges of L? Meshes real surfaces at two or three L
each, with the surface remeshed first (the default) and without (--no-remesh), and prints a
Markdown table: vertices, mean edge against L, dihedral angles, the share of slivers, time.

The surfaces: the public Bunny.stl (a scan's surface), the boundaries of the public polyfem
bunny, armadillo and raptor tetrahedral meshes (written here as OBJ; the last two are not
2-manifold and are refused either way), and a closed dome made here (a hemisphere of radius
7.5 cm on a flat base, about 1,500 triangles, in metres).

  python3 tools/mesh_sizes.py [BUILD_DIR] [MESHES_DIR]   # defaults: build, ../shared/data/meshes
"""
import json
import math
import os
import subprocess
import sys
import tempfile


def dome(radius=0.075, spacing=0.0084):
    """A hemisphere on a disk, rings of points about `spacing` apart, triangles facing out."""
    points = []
    rings = []  # lists of (index, azimuth)

    def ring(r, z, stagger):
        if r < 1e-12:
            points.append((0.0, 0.0, z))
            return [(len(points) - 1, 0.0)]
        n = max(6, round(2 * math.pi * r / spacing))
        out = []
        for i in range(n):
            a = 2 * math.pi * (i + 0.5 * stagger) / n
            points.append((r * math.cos(a), r * math.sin(a), z))
            out.append((len(points) - 1, a))
        return out

    k_cap = max(2, round(0.5 * math.pi * radius / spacing))
    for k in range(k_cap + 1):  # the pole to the equator
        t = 0.5 * math.pi * k / k_cap
        rings.append(ring(radius * math.sin(t), radius * math.cos(t), k % 2))
    k_base = max(2, round(radius / spacing))
    for k in range(1, k_base + 1):  # the equator's inside to the base's centre
        rings.append(ring(radius * (1 - k / k_base), 0.0, (k_cap + k) % 2))

    triangles = []
    for a, b in zip(rings, rings[1:]):
        if len(a) == 1 or len(b) == 1:
            centre, rim = (a, b) if len(a) == 1 else (b, a)
            for i in range(len(rim)):
                triangles.append((centre[0][0], rim[i][0], rim[(i + 1) % len(rim)][0]))
            continue
        # Walk both rings by azimuth, always advancing the one whose next point comes first.
        i = j = 0
        while i < len(a) or j < len(b):
            ai = a[i % len(a)][1] + 2 * math.pi * (i // len(a))
            bj = b[j % len(b)][1] + 2 * math.pi * (j // len(b))
            next_a = a[(i + 1) % len(a)][1] + 2 * math.pi * ((i + 1) // len(a))
            next_b = b[(j + 1) % len(b)][1] + 2 * math.pi * ((j + 1) // len(b))
            if j >= len(b) or (i < len(a) and next_a - bj < next_b - ai):
                triangles.append((a[i % len(a)][0], b[j % len(b)][0], a[(i + 1) % len(a)][0]))
                i += 1
            else:
                triangles.append((a[i % len(a)][0], b[j % len(b)][0], b[(j + 1) % len(b)][0]))
                j += 1
    # The dome is convex: face each triangle away from a point inside.
    inside = (0.0, 0.0, 0.3 * radius)
    oriented = []
    for t in triangles:
        p = [points[v] for v in t]
        u = [p[1][k] - p[0][k] for k in range(3)]
        w = [p[2][k] - p[0][k] for k in range(3)]
        n = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
        c = [sum(q[k] for q in p) / 3 - inside[k] for k in range(3)]
        oriented.append(t if sum(n[k] * c[k] for k in range(3)) > 0 else (t[0], t[2], t[1]))
    return points, oriented


def read_tets(path):
    """Points and tetrahedra of an ASCII VTU or a Gmsh 4.1 ASCII file."""
    text = open(path).read()
    if path.endswith(".vtu"):
        def array(name):
            start = text.index(">", text.index(name)) + 1
            return text[start:text.index("</DataArray>", start)].split()
        pts = list(map(float, array('NumberOfComponents="3"')))
        conn = list(map(int, array('Name="connectivity"')))
        points = [tuple(pts[i:i + 3]) for i in range(0, len(pts), 3)]
        return points, [tuple(conn[i:i + 4]) for i in range(0, len(conn), 4)]
    lines = text.split("\n")
    points, index, tets = [], {}, []
    i = lines.index("$Nodes") + 2
    while not lines[i].startswith("$EndNodes"):
        _, _, _, n = map(int, lines[i].split())
        tags = [int(lines[i + 1 + k]) for k in range(n)]
        for k, tag in enumerate(tags):
            index[tag] = len(points)
            points.append(tuple(map(float, lines[i + 1 + n + k].split()[:3])))
        i += 1 + 2 * n
    i = lines.index("$Elements") + 2
    while not lines[i].startswith("$EndElements"):
        _, _, kind, n = map(int, lines[i].split())
        for k in range(n):
            if kind == 4:
                tets.append(tuple(index[int(v)] for v in lines[i + 1 + k].split()[1:5]))
        i += 1 + n
    return points, tets


def boundary(points, tets):
    """The faces in one tetrahedron only, facing away from it."""
    count = {}
    for t in tets:
        p = [points[v] for v in t]
        d = [[p[k][m] - p[0][m] for m in range(3)] for k in (1, 2, 3)]
        vol = (d[0][0] * (d[1][1] * d[2][2] - d[1][2] * d[2][1]) -
               d[0][1] * (d[1][0] * d[2][2] - d[1][2] * d[2][0]) +
               d[0][2] * (d[1][0] * d[2][1] - d[1][1] * d[2][0]))
        a, b, c, e = t if vol > 0 else (t[0], t[2], t[1], t[3])
        for f in ((b, c, e), (a, e, c), (a, b, e), (a, c, b)):
            key = tuple(sorted(f))
            count[key] = (count.get(key, (0, f))[0] + 1, f)
    faces = [f for n, f in count.values() if n == 1]
    used = sorted({v for f in faces for v in f})
    new = {v: i for i, v in enumerate(used)}
    return [points[v] for v in used], [tuple(new[v] for v in f) for f in faces]


def write_obj(path, points, faces):
    with open(path, "w") as out:
        out.writelines(f"v {p[0]:.9g} {p[1]:.9g} {p[2]:.9g}\n" for p in points)
        out.writelines(f"f {f[0] + 1} {f[1] + 1} {f[2] + 1}\n" for f in faces)


def main():
    build = sys.argv[1] if len(sys.argv) > 1 else "build"
    meshes = sys.argv[2] if len(sys.argv) > 2 else "../shared/data/meshes"
    femreg = os.path.join(build, "femreg")
    work = tempfile.mkdtemp()
    surfaces = []  # (name, path, [L...])
    points, faces = dome()
    write_obj(os.path.join(work, "dome.obj"), points, faces)
    surfaces.append(("dome (made here, m)", os.path.join(work, "dome.obj"), [0.006, 0.012, 0.02]))
    surfaces.append(("Bunny.stl", os.path.join(meshes, "Bunny.stl"), [0.25, 0.5, 1.0]))
    for name, lengths in (("creatures_bunny.msh", [0.1, 0.2, 0.4]),
                          ("Armadillo_Tetra_4406.vtu", [1.0]),
                          ("raptorTetra_8418.vtu", [0.5])):
        points, faces = boundary(*read_tets(os.path.join(meshes, name)))
        path = os.path.join(work, name + ".obj")
        write_obj(path, points, faces)
        surfaces.append((name + " (boundary)", path, lengths))

    print("| surface | triangles | L | mode | vertices | tets | mean edge | mean / L | "
          "dihedral min..max | < 10 deg | volume change | s |")
    print("|---|---:|---:|---|---:|---:|---:|---:|---|---:|---:|---:|")
    for name, path, lengths in surfaces:
        for length in lengths:
            modes = [("TetGen alone", ["--no-remesh"]), ("remeshed", [])]
            if "creatures" in name:  # creases that make poor feature lines
                modes.append(("remeshed, --feature-angle 180", ["--feature-angle", "180"]))
            for mode, extra in modes:
                out = os.path.join(work, "out.vtu")
                cmd = [femreg, "mesh", path, "--out", out, "--force", "--json",
                       "--edge-length", str(length)] + extra
                run = subprocess.run(cmd, capture_output=True, text=True)
                r = json.loads(run.stdout)
                if not r["ok"]:
                    error = r["error"].replace(path, "").replace("\n", " ").replace("|", "/")
                    print(f"| {name} | {r['input']['triangles']} | {length:g} | {mode} | "
                          f"refused: {error[:160]} |")
                    continue
                m = r["mesh"]
                q = m["quality"]
                change = (m["volume"] - r["surface"]["volume"]) / r["surface"]["volume"]
                print(f"| {name} | {r['input']['triangles']} | {length:g} | {mode} | "
                      f"{m['vertices']} | {m['tetrahedra']} | {m['edge_length']['mean']:.4g} | "
                      f"{m['edge_length']['mean'] / length:.2f} | "
                      f"{q['min_dihedral_deg']:.1f}..{q['max_dihedral_deg']:.1f} | "
                      f"{100 * q['share_below_10_deg']:.2f} % | {100 * change:+.2f} % | "
                      f"{r['seconds']['total']:.2f} |")


if __name__ == "__main__":
    main()
