#!/usr/bin/python3
"""bench/peer_gmsh_extrude.py: the peer of vm-prism, measured in the same run:
Gmsh's boundary-layer extrusion of the same closed STL wall, as a user
without varmesh would do it (Debian's python3-gmsh): the wall merged as a
discrete surface, extruded along Gmsh's mesh normals
(gmsh.model.geo.extrudeBoundaryLayer, recombined: prisms) with the layer
heights vm-prism uses (total T, N layers, geometric growth G from the wall).

Prints one line of JSON: prisms, wall triangles, CPU seconds (user + sys of
this process, Gmsh's work only: from the merge to the mesh), wall seconds,
peak memory (MiB), and the prisms whose volume is not positive (signed volume
of the prism's three corner tets at the wall triangle's corners, the same
corner test vm-quality uses for M): Gmsh does not untangle; and the prisms
not positive in every 3-tet split (a tet of two bottom and two top vertices
off a side face with a non-positive volume, as vm_prism_split_check counts).

usage: peer_gmsh_extrude.py WALL.stl T N [G]   (T absolute)"""
import json
import resource
import sys
import time

import gmsh
import numpy as np


def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    path, T, n = sys.argv[1], float(sys.argv[2]), int(sys.argv[3])
    g = float(sys.argv[4]) if len(sys.argv) > 4 else 1.2
    h = [g ** k for k in range(n)]
    s = T / sum(h)
    heights = list(np.cumsum([s * x for x in h]))

    c0, w0 = cpu(), time.time()
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.merge(path)
    gmsh.option.setNumber("Geometry.ExtrudeReturnLateralEntities", 0)
    gmsh.model.geo.extrudeBoundaryLayer(gmsh.model.getEntities(2), [1] * n, heights, True)
    gmsh.model.geo.synchronize()
    gmsh.model.mesh.generate(3)
    c1, w1 = cpu(), time.time()

    tags, coord, _ = gmsh.model.mesh.getNodes()
    X = np.zeros((int(tags.max()) + 1, 3))
    X[tags.astype(np.int64)] = coord.reshape(-1, 3)
    types, _, nodes = gmsh.model.mesh.getElements(3)
    nprism, bad, ntri, split = 0, 0, 0, 0
    for t, nd in zip(types, nodes):
        if gmsh.model.mesh.getElementProperties(t)[3] != 6:
            continue
        P = X[nd.astype(np.int64).reshape(-1, 6)]
        nprism += len(P)
        # corner tets at the bottom triangle's corners (Gmsh's prism order:
        # 0 1 2 bottom, 3 4 5 top); the sign follows the bottom's orientation
        vols = []
        for a, b, c, d in ((0, 1, 2, 3), (1, 2, 0, 4), (2, 0, 1, 5)):
            vols.append(np.einsum("ij,ij->i", np.cross(P[:, b] - P[:, a], P[:, c] - P[:, a]),
                                  P[:, d] - P[:, a]))
        V = np.array(vols)
        sign = np.sign(np.median(V[0]))
        bad += int(np.sum(np.any(V * sign <= 0, axis=0)))
        # the tets of the 3-tet splits that are not corner tets, each
        # ordered to be positive on the right prism (as vm_prism_split_check)
        S = []
        for a, b, c, d in ((0, 1, 5, 4), (0, 1, 5, 3), (1, 2, 3, 4), (1, 2, 3, 5), (0, 2, 3, 4),
                           (0, 2, 5, 4)):
            S.append(np.einsum("ij,ij->i", np.cross(P[:, b] - P[:, a], P[:, c] - P[:, a]),
                               P[:, d] - P[:, a]))
        S = np.array(S)
        split += int(np.sum(np.any(np.concatenate([V, S]) * sign <= 0, axis=0)))
    types2, _, nodes2 = gmsh.model.mesh.getElements(2)
    for t, nd in zip(types2, nodes2):
        if gmsh.model.mesh.getElementProperties(t)[3] == 3:
            ntri += len(nd) // 3
    gmsh.finalize()
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({"peer": "gmsh %s extrudeBoundaryLayer" % gmsh.__version__,
                      "prisms": nprism, "triangles_2d": ntri, "cpu_s": round(c1 - c0, 2),
                      "wall_s": round(w1 - w0, 2), "peak_mib": round(peak, 1),
                      "not_positive_prisms": bad, "split_negative_prisms": split}))


if __name__ == "__main__":
    main()
