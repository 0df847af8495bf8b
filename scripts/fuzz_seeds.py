#!/usr/bin/env python3
"""Writes fuzz seeds for scripts/fuzz.sh: a tetrahedron with its corners written per face (seams
stored twice, which validation welds), two tetrahedra sharing a vertex and two nested ones
into SEEDS/obj; every .obj under SEEDS/obj converted to PLY
(binary and ASCII), STL (binary and ASCII) and OFF; the tetrahedron in the variants meshio does
not write (binary OFF, PLY triangle strips, big-endian PLY, 4OFF); and the shared meshes under
64 kB.
Usage: fuzz_seeds.py SEEDS SHARED_MESHES"""
import glob
import os
import shutil
import struct
import sys

import meshio

seeds, shared = sys.argv[1], sys.argv[2]
corners = [(0, 0, 0), (2, 0, 0), (0, 2, 0), (0, 0, 2)]
faces = [(0, 2, 1), (0, 1, 3), (1, 2, 3), (2, 0, 3)]
with open(os.path.join(seeds, "obj", "tet_apart.obj"), "w") as f:
    f.write("".join("v %g %g %g\n" % corners[v] for t in faces for v in t))
    f.write("".join("f %d %d %d\n" % (3 * k + 1, 3 * k + 2, 3 * k + 3) for k in range(4)))
# Two tetrahedra sharing only a vertex, the second inside out (split there, then turned), and a
# tetrahedron inside another, both facing out (the inner one turned to face the cavity).
below = [(0, 0, 0), (-2, 0, 0), (0, -2, 0), (0, 0, -2)]
with open(os.path.join(seeds, "obj", "tets_pinched.obj"), "w") as f:
    f.write("".join("v %g %g %g\n" % c for c in corners + below[1:]))
    f.write("".join("f %d %d %d\n" % tuple(v + 1 for v in t) for t in faces))
    f.write("".join("f %d %d %d\n" % tuple(1 if v == 0 else v + 4 for v in t) for t in faces))
with open(os.path.join(seeds, "obj", "tets_nested.obj"), "w") as f:
    inner = [tuple(0.25 * x + 0.2 for x in c) for c in corners]
    f.write("".join("v %g %g %g\n" % c for c in corners + inner))
    f.write("".join("f %d %d %d\n" % tuple(v + 1 + 4 * k for v in t) for k in (0, 1) for t in faces))
for path in sorted(glob.glob(os.path.join(seeds, "obj", "*.obj"))):
    name = os.path.splitext(os.path.basename(path))[0]
    mesh = meshio.read(path)
    meshio.write(os.path.join(seeds, "ply", name + ".ply"), mesh, binary=True)
    meshio.write(os.path.join(seeds, "ply", name + "_ascii.ply"), mesh, binary=False)
    meshio.write(os.path.join(seeds, "stl", name + ".stl"), mesh, binary=True)
    meshio.write(os.path.join(seeds, "stl", name + "_ascii.stl"), mesh, binary=False)
    meshio.write(os.path.join(seeds, "off", name + ".off"), mesh)

with open(os.path.join(seeds, "off", "tet_binary.off"), "wb") as f:
    f.write(b"OFF BINARY\n" + struct.pack(">3i", 4, 4, 6))
    for c in corners:
        f.write(struct.pack(">3f", *c))
    for t in faces:
        f.write(struct.pack(">5i", 3, *t, 0))
with open(os.path.join(seeds, "off", "tet_4off.off"), "w") as f:
    f.write("4OFF\n4 4 6\n" + "".join("%g %g %g 2\n" % tuple(2 * v for v in c) for c in corners))
    f.write("".join("3 %d %d %d\n" % t for t in faces))
header = ("ply\nformat %s 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
          "property float z\nelement tristrips 1\nproperty list int int vertex_indices\n"
          "end_header\n")
with open(os.path.join(seeds, "ply", "tet_strips.ply"), "wb") as f:
    f.write((header % "binary_little_endian").encode())
    for c in corners:
        f.write(struct.pack("<3f", *c))
    f.write(struct.pack("<7i", 6, 0, 2, 1, 3, 0, 2))
with open(os.path.join(seeds, "ply", "tet_strips_ascii.ply"), "w") as f:
    f.write(header % "ascii" + "".join("%g %g %g\n" % c for c in corners) + "6 0 2 1 3 0 2\n")
with open(os.path.join(seeds, "ply", "tet_big.ply"), "wb") as f:
    f.write(("ply\nformat binary_big_endian 1.0\nelement vertex 4\nproperty double x\n"
             "property double y\nproperty double z\nelement face 4\n"
             "property list uchar uint vertex_indices\nend_header\n").encode())
    for c in corners:
        f.write(struct.pack(">3d", *c))
    for t in faces:
        f.write(struct.pack(">B3I", 3, *t))

for path in sorted(glob.glob(os.path.join(shared, "*"))):
    ext = os.path.splitext(path)[1][1:]
    if ext in ("obj", "off", "ply", "stl") and os.path.getsize(path) < 65536:
        shutil.copy(path, os.path.join(seeds, ext, os.path.basename(path)))
