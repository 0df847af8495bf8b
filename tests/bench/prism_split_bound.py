#!/usr/bin/env python3
"""prism_split_bound.py -- how much better a shell's tets could be with other prism splits.

    /usr/bin/python3 tests/bench/prism_split_bound.py SURFACE.obj|.off SHELL.vtu

Not part of the ctest run. Reads a one-layer shell written by vdb_shell (.vtu with the cell data
`source_triangle` and the point data `inner` and `surface_vertex`) and its surface, and for every
prism with three distinct inner vertices tries all 3-tet splits of its six corners (the 12 cases
of split_prism(), core/assemble/assemble.h, oriented as there; a split with a tet of volume <= 0
is not a candidate) and keeps the one with the largest smallest volume-length ratio. Prints the
shell's quality figures as written and as they would be with every prism split its best way.
The second line is an upper bound on what choosing the splits can give: each prism chooses alone,
whereas neighbours must cut their shared quad the same way, and the new tets must still pass the
overlap and leak checks. Prisms with welded or on-surface corners keep their tets.
The last line describes the prisms of the worst 5% of the tets as written (Q at or below the 5th
percentile) beside all prisms: the median of depth / edge (the mean distance from the outer
corners to their inner ones over the mean outer edge: how tall the prism is for its triangle)
and the share whose inner triangle has collapsed (area under a tenth of the outer one, or an angle
under 5 degrees: traces converging).

Only the Python standard library, numpy and meshio (Debian: python3-numpy, python3-meshio).
"""
import itertools
import sys

import meshio
import numpy as np

# Corner positions of assemble.cpp's reference right prism (outer triangle at z = 0).
REFERENCE = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, -1], [1, 0, -1], [0, 1, -1]], float)


def read_surface(path):
    """Points and triangles of an .obj or .off (polygons fanned); other formats through meshio."""
    if path.lower().endswith(".obj"):
        points, faces = [], []
        with open(path) as f:
            for line in f:
                words = line.split()
                if words and words[0] == "v":
                    points.append([float(x) for x in words[1:4]])
                elif words and words[0] == "f":
                    poly = [int(w.split("/")[0]) - 1 for w in words[1:]]
                    faces += [[poly[0], poly[k], poly[k + 1]] for k in range(1, len(poly) - 1)]
        return np.array(points), np.array(faces, int)
    if path.lower().endswith(".off"):
        with open(path) as f:
            words = [w for line in f for w in line.split("#")[0].split()]
        nv, nf = int(words[1]), int(words[2])
        points = np.array(words[4:4 + 3 * nv], float).reshape(nv, 3)
        faces, k = [], 4 + 3 * nv
        for _ in range(nf):
            c = int(words[k])
            poly = [int(w) for w in words[k + 1:k + 1 + c]]
            faces += [[poly[0], poly[j], poly[j + 1]] for j in range(1, c - 1)]
            k += 1 + c
        return points, np.array(faces, int)
    mesh = meshio.read(path)
    return np.asarray(mesh.points, float), np.asarray(mesh.cells_dict["triangle"], int)


def quality(p):
    """Volume-length ratio of the tet p[0..3] (regular = 1), as core/assemble/quality.cpp."""
    a, b, c, d = p
    volume = np.dot(np.cross(b - a, c - a), d - a) / 6.0
    l2 = sum(np.dot(x - y, x - y) for x, y in itertools.combinations(p, 2)) / 6.0
    return 6.0 * np.sqrt(2.0) * volume / l2 ** 1.5


def min_dihedral_deg(p):
    smallest = 180.0
    for i, j in itertools.combinations(range(4), 2):
        k, m = [x for x in range(4) if x not in (i, j)]
        e = (p[j] - p[i]) / np.linalg.norm(p[j] - p[i])
        u = p[k] - p[i] - e * np.dot(p[k] - p[i], e)
        w = p[m] - p[i] - e * np.dot(p[m] - p[i], e)
        cos = np.dot(u, w) / (np.linalg.norm(u) * np.linalg.norm(w))
        smallest = min(smallest, np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return smallest


def triangle_area(p):
    return 0.5 * np.linalg.norm(np.cross(p[1] - p[0], p[2] - p[0]))


def smallest_angle_deg(p):
    angles = []
    for k in range(3):
        u, w = p[k - 2] - p[k], p[k - 1] - p[k]
        cos = np.dot(u, w) / max(np.linalg.norm(u) * np.linalg.norm(w), 1e-300)
        angles.append(np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))))
    return min(angles)


def corner_role(m, i):
    """assemble.cpp's corner_role(): corner V(i+1) of the prism whose smallest corner is m."""
    top = 0 if m < 3 else 3
    return (top if i < 3 else 3 - top) + (m % 3 + i) % 3


def splits():
    """The 12 splits of split_prism() as corner quadruples, positive in the reference prism."""
    out = []
    for m in range(6):
        v = [corner_role(m, i) for i in range(6)]
        for cut in (0, 1):
            tets = ([(v[0], v[1], v[2], v[5]), (v[0], v[1], v[5], v[4]), (v[0], v[4], v[5], v[3])]
                    if cut == 0 else
                    [(v[0], v[1], v[2], v[4]), (v[0], v[4], v[2], v[5]), (v[0], v[4], v[5], v[3])])
            oriented = []
            for t in tets:
                r = REFERENCE[list(t)]
                if np.dot(np.cross(r[1] - r[0], r[2] - r[0]), r[3] - r[0]) < 0:
                    t = (t[0], t[1], t[3], t[2])
                oriented.append(t)
            out.append(oriented)
    return out


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    _, faces = read_surface(sys.argv[1])
    shell = meshio.read(sys.argv[2])
    points, tets = shell.points, shell.cells_dict["tetra"]
    source = np.concatenate(shell.cell_data["source_triangle"]).astype(int)
    inner = shell.point_data["inner"]
    owner = shell.point_data["surface_vertex"].astype(int)
    order = np.argsort(source, kind="stable")
    start = np.searchsorted(source[order], np.arange(len(faces) + 1))
    candidates = splits()
    now_q, now_d, best_q, best_d = [], [], [], []
    tall, collapsed = [], []  # per tet as written: its prism's depth / edge, collapsed or not
    for f, tri in enumerate(faces):
        own = tets[order[start[f]:start[f + 1]]]
        q = [quality(points[t]) for t in own]
        d = [min_dihedral_deg(points[t]) for t in own]
        now_q += q
        now_d += d
        corner = {owner[p]: p for p in set(own.flatten()) if inner[p]}
        if len(own) != 3 or len(corner) != 3 or not all(v in corner for v in tri):
            best_q += q
            best_d += d
            tall += [np.nan] * len(own)
            collapsed += [False] * len(own)
            continue
        corners = points[list(tri) + [corner[v] for v in tri]]
        outer, inside = corners[:3], corners[3:]
        edge = np.mean([np.linalg.norm(outer[k] - outer[k - 1]) for k in range(3)])
        tall += [np.mean(np.linalg.norm(outer - inside, axis=1)) / edge] * 3
        collapsed += [triangle_area(inside) < 0.1 * triangle_area(outer) or
                      smallest_angle_deg(inside) < 5.0] * 3
        best = None
        for split in candidates:
            sq = [quality(corners[list(t)]) for t in split]
            if min(sq) > 0 and (best is None or min(sq) > min(best[0])):
                best = (sq, [min_dihedral_deg(corners[list(t)]) for t in split])
        best_q += best[0] if best else q
        best_d += best[1] if best else d
    for label, qs, ds in (("as written", now_q, now_d), ("best split per prism", best_q, best_d)):
        qs, ds = np.array(qs), np.array(ds)
        print("%-21s min Q %.2g  p5 Q %.4f  median Q %.3f  min dihedral %.3f deg  "
              "tets under 1 deg %d of %d" % (label, qs.min(), np.percentile(qs, 5), np.median(qs),
                                             ds.min(), int((ds < 1.0).sum()), len(ds)))
    now_q, tall, collapsed = np.array(now_q), np.array(tall), np.array(collapsed)
    worst = now_q <= np.percentile(now_q, 5)
    print("worst 5%% of the tets' prisms: depth / edge median %.2f (all %.2f), inner triangle "
          "collapsed %.0f%% (all %.0f%%)" % (np.nanmedian(tall[worst]), np.nanmedian(tall),
                                             100 * collapsed[worst].mean(), 100 * collapsed.mean()))


if __name__ == "__main__":
    main()
