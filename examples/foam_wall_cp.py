#!/usr/bin/env python3
"""examples/foam_wall_cp.py CASE TIME OUT.vtk [PATCH]

The pressure coefficient on a wall patch of an OpenFOAM case, as a
triangle/polygon surface with the cell field Cp, in legacy ASCII VTK (what
`vm-quality --report DIR --report-field Cp OUT.vtk` renders).

Reads CASE/constant/polyMesh (points, faces, owner, boundary; ASCII, as
vm-convert writes it by default) and CASE/TIME/p (kinematic pressure of an
incompressible solver, ASCII). A zeroGradient wall carries no values of
its own: the wall cells' values are used, as OpenFOAM evaluates the patch.
Cp = (p - p_inf) / (0.5 U_inf^2) with p_inf = 0 and U_inf = |U| of the
case's internalField in 0/U (the free stream of examples/foam). Standard
library only. Exit 1 with one line on a file it cannot read.
"""
import math
import os
import re
import sys


def fail(msg):
    sys.stderr.write("foam_wall_cp.py: %s\n" % msg)
    sys.exit(1)


def read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError as e:
        fail("%s: %s" % (path, e.strerror))


def list_body(path, text=None):
    """The body of the first top-level list after the FoamFile header."""
    s = text if text is not None else read(path)
    head = s.find("FoamFile")
    start = s.index("}", head) + 1 if head >= 0 else 0
    m = re.compile(r"(\d+)\s*\(").search(s, start)
    if not m:
        fail("%s: no list" % path)
    n, i = int(m.group(1)), m.end()
    return n, s, i


def numbers(path):
    n, s, i = list_body(path)
    j = s.index(")", i)
    v = s[i:j].split()
    if len(v) != n:
        fail("%s: %d values, the header says %d" % (path, len(v), n))
    return v


def main():
    if len(sys.argv) not in (4, 5):
        sys.stderr.write(__doc__)
        sys.exit(2)
    case, time, out = sys.argv[1], sys.argv[2], sys.argv[3]
    patch = sys.argv[4] if len(sys.argv) == 5 else "wall"
    poly = os.path.join(case, "constant", "polyMesh")
    n, s, i = list_body(os.path.join(poly, "points"))
    pts = re.findall(r"\(\s*(\S+)\s+(\S+)\s+(\S+)\s*\)", s[i:])[:n]
    if len(pts) != n:
        fail("%s: %d points read of %d" % (os.path.join(poly, "points"), len(pts), n))
    bnd = read(os.path.join(poly, "boundary"))
    m = re.search(r"\b%s\s*\{[^}]*?nFaces\s+(\d+);\s*startFace\s+(\d+);" % re.escape(patch), bnd)
    if not m:
        fail("%s: no patch '%s'" % (os.path.join(poly, "boundary"), patch))
    nf, sf = int(m.group(1)), int(m.group(2))
    n, s, i = list_body(os.path.join(poly, "faces"))
    faces = []
    pat = re.compile(r"(\d+)\(([^)]*)\)")
    pos, k = i, 0
    while k < sf + nf:
        fm = pat.search(s, pos)
        if not fm:
            fail("%s: %d faces read, %d needed" % (os.path.join(poly, "faces"), k, sf + nf))
        if k >= sf:
            faces.append([int(x) for x in fm.group(2).split()])
        pos, k = fm.end(), k + 1
    owner = numbers(os.path.join(poly, "owner"))
    ptext = read(os.path.join(case, time, "p"))
    b = ptext.index("boundaryField")
    w = re.search(r"\b%s\s*\{" % re.escape(patch), ptext[b:])
    if not w:
        fail("%s: no patch '%s' in boundaryField" % (os.path.join(case, time, "p"), patch))
    blk = ptext[b + w.end(): ptext.index("}", b + w.end())]
    if "nonuniform" in blk:
        _, bs, bi = list_body(None, blk)
        p = [float(x) for x in bs[bi:bs.index(")", bi)].split()]
    else:
        n, s2, i2 = list_body(os.path.join(case, time, "p"), ptext[ptext.index("internalField"):])
        cells = s2[i2:s2.index(")", i2)].split()
        p = [float(cells[int(owner[sf + q])]) for q in range(nf)]
    if len(p) != nf:
        fail("%s: %d wall values for %d faces" % (os.path.join(case, time, "p"), len(p), nf))
    u = re.search(r"internalField\s+uniform\s+\(\s*(\S+)\s+(\S+)\s+(\S+)\s*\)",
                  read(os.path.join(case, "0", "U")))
    uinf = math.sqrt(sum(float(x) ** 2 for x in u.groups())) if u else 1.0
    q = 0.5 * uinf * uinf if uinf > 0 else 0.5
    used = sorted({v for f in faces for v in f})
    idx = {v: k for k, v in enumerate(used)}
    tmp = out + ".tmp.%d" % os.getpid()
    with open(tmp, "w") as f:
        f.write("# vtk DataFile Version 3.0\nwall Cp of %s at %s\nASCII\n"
                "DATASET UNSTRUCTURED_GRID\n" % (case, time))
        f.write("POINTS %d double\n" % len(used))
        for v in used:
            f.write("%s %s %s\n" % pts[v])
        f.write("CELLS %d %d\n" % (nf, sum(len(c) + 1 for c in faces)))
        for c in faces:
            f.write("%d %s\n" % (len(c), " ".join(str(idx[v]) for v in c)))
        f.write("CELL_TYPES %d\n" % nf)
        for c in faces:
            f.write("%d\n" % (5 if len(c) == 3 else 9 if len(c) == 4 else 7))
        f.write("CELL_DATA %d\nSCALARS Cp double 1\nLOOKUP_TABLE default\n" % nf)
        for x in p:
            f.write("%.9g\n" % (x / q))
    os.replace(tmp, out)
    cp = [x / q for x in p]
    print("%s: %d faces of '%s', Cp from %.3f to %.3f (U_inf %g)" % (out, nf, patch, min(cp),
                                                                    max(cp), uinf))


main()
