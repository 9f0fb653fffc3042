#!/usr/bin/python3
"""bench/surface_shapes.py: the hard generated surfaces of the surface
stage's benchmark (bench/bench_surface_cases.sh), written as ASCII STL.

usage: surface_shapes.py spindle|slivers|inward OUT.stl [SPHERE.off]
  spindle  two cones base to base (tips: cone points), 48 sectors, two
           rings 0.001 apart (a row of needles)
  slivers  the icosphere SPHERE.off with every 37th triangle's first vertex
           pulled 95 % of the way to its second, back onto the sphere
  inward   SPHERE.off with every triangle reversed
"""
import math
import sys


def read_off(fn):
    t = open(fn).read().split()
    assert t[0] == "OFF"
    nv, nf = int(t[1]), int(t[2])
    i = 4
    v = [[float(x) for x in t[i + 3 * k:i + 3 * k + 3]] for k in range(nv)]
    i += 3 * nv
    f = []
    for _ in range(nf):
        n = int(t[i])
        f.append([int(x) for x in t[i + 1:i + 1 + n]])
        i += 1 + n
    return v, f


def write_stl(fn, v, f):
    with open(fn, "w") as o:
        o.write("solid shape\n")
        for a, b, c in f:
            p, q, r = v[a], v[b], v[c]
            u = [q[k] - p[k] for k in range(3)]
            w = [r[k] - p[k] for k in range(3)]
            n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
            ln = math.sqrt(sum(x * x for x in n)) or 1
            o.write(" facet normal %.17g %.17g %.17g\n  outer loop\n" % tuple(x / ln for x in n))
            for x in (p, q, r):
                o.write("   vertex %.17g %.17g %.17g\n" % tuple(x))
            o.write("  endloop\n endfacet\n")
        o.write("endsolid shape\n")


def spindle():
    zs = [-0.8, -0.6, -0.35, -0.1, 0, 0.2, 0.45, 0.451, 0.7, 0.85]
    ns = 48
    v = [[0, 0, -1], [0, 0, 1]]
    for z in zs:
        r = 0.5 * (1 - abs(z))
        for s in range(ns):
            a = 2 * math.pi * s / ns
            v.append([r * math.cos(a), r * math.sin(a), z])
    f = []
    nz = len(zs)
    for s in range(ns):
        f.append([0, 2 + (s + 1) % ns, 2 + s])
        f.append([1, 2 + (nz - 1) * ns + s, 2 + (nz - 1) * ns + (s + 1) % ns])
    for k in range(nz - 1):
        for s in range(ns):
            a, b = 2 + k * ns + s, 2 + k * ns + (s + 1) % ns
            f.append([a, b, b + ns])
            f.append([a, b + ns, a + ns])
    return v, f


def main():
    kind, out = sys.argv[1], sys.argv[2]
    if kind == "spindle":
        v, f = spindle()
    else:
        v, f = read_off(sys.argv[3])
        if kind == "slivers":
            for e in range(0, len(f), 37):
                p, q = v[f[e][0]], v[f[e][1]]
                x = [p[k] + 0.95 * (q[k] - p[k]) for k in range(3)]
                ln = math.sqrt(sum(y * y for y in x))
                v[f[e][0]] = [y / ln for y in x]
        elif kind == "inward":
            f = [[a, c, b] for a, b, c in f]
        else:
            sys.exit("unknown shape " + kind)
    write_stl(out, v, f)


if __name__ == "__main__":
    main()
