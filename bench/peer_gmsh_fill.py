#!/usr/bin/python3
"""bench/peer_gmsh_fill.py: the peer of vm-fill, measured in the same run:
Gmsh's own fill from files, as a user without varmesh would do it. Reads a
layer mesh exported as Gmsh .msh (vm-convert LAYER.vmsh LAYER.msh), takes
its faces named 'outer' as a discrete surface, adds a far-field box at
FARFIELD model lengths, and meshes the volume between them with HXT and
Gmsh's default sizing (sizes interpolated from the boundary).
Prints one JSON line: tets, seconds (reading excluded), exact (how many of
the envelope's vertices come back bit-identical from the written .msh).
usage: peer_gmsh_fill.py LAYER.msh [FARFIELD]"""
import json
import sys
import time

import gmsh
import meshio
import numpy as np

path = sys.argv[1]
far = float(sys.argv[2]) if len(sys.argv) > 2 else 20.0
m = meshio.read(path)
names = {v[0]: k for k, v in m.field_data.items()} if m.field_data else {}
tris = []
for cb, tag in zip(m.cells, m.cell_data.get("gmsh:physical", [])):
    if cb.type == "triangle":
        tris.append(cb.data[np.asarray(tag) == next(t for t, n in names.items() if n == "outer")])
env = np.vstack(tris)
used = np.unique(env)
P = m.points
wall_lo, wall_hi = P[used].min(0), P[used].max(0)
c, L = (wall_lo + wall_hi) / 2, (wall_hi - wall_lo).max()
H = far * L
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
t0 = time.time()
gmsh.model.add("peer")
s1 = gmsh.model.addDiscreteEntity(2)
gmsh.model.mesh.addNodes(2, s1, (used + 1).tolist(), P[used].ravel().tolist())
gmsh.model.mesh.addElementsByType(s1, 2, [], (env + 1).ravel().tolist())
# the far-field box: a 10 x 10 triangulation of each side
n = 10
ids, nodes, bt = {}, [], []
base = len(P) + 1


def vid(p):
    k = tuple(np.round(p, 9))
    if k not in ids:
        ids[k] = base + len(ids)
        nodes.append(p)
    return ids[k]


for ax in range(3):
    a1, a2 = (ax + 1) % 3, (ax + 2) % 3
    for sgn in (-1, 1):
        for i in range(n):
            for j in range(n):
                q = []
                for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    p = np.array(c, dtype=float)
                    p[ax] += sgn * H
                    p[a1] += -H + 2 * H * (i + di) / n
                    p[a2] += -H + 2 * H * (j + dj) / n
                    q.append(vid(p))
                bt += [q[0], q[1], q[2], q[0], q[2], q[3]]
s2 = gmsh.model.addDiscreteEntity(2)
gmsh.model.mesh.addNodes(2, s2, list(ids.values()), np.array(nodes).ravel().tolist())
gmsh.model.mesh.addElementsByType(s2, 2, [], bt)
loop = gmsh.model.geo.addSurfaceLoop([s1, s2])
gmsh.model.geo.addVolume([loop])
gmsh.model.geo.synchronize()
gmsh.option.setNumber("Mesh.Algorithm3D", 10)
gmsh.model.mesh.generate(3)
dt = time.time() - t0
et, en = gmsh.model.mesh.getElementsByType(4)
# through a file, as the user's next program reads it
import os
import tempfile

fd, out = tempfile.mkstemp(suffix=".msh")
os.close(fd)
gmsh.write(out)
gmsh.finalize()
back = meshio.read(out)
os.remove(out)
have = {tuple(p) for p in back.points}
exact = sum(1 for u in used if tuple(P[u]) in have)
print(json.dumps({"tets": len(et), "seconds": round(dt, 2), "exact": exact, "envelope_vertices": len(used)}))
