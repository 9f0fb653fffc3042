#!/usr/bin/env python3
# test/io_gmsh/test_msh_meshio.py: .msh written by vm-convert puts element
# data on the right cells for a reader that numbers elements by their place
# in the file (meshio): a legacy VTK file of interleaved cell types
# (tetrahedra, hexahedra, prisms, pyramids, triangles, quadrilaterals) with
# an int cell field is converted, meshio reads the Gmsh 4.1 ASCII and
# binary files and every cell must carry its own value; element tags are
# 1..N in file order in 4.1 and 2.2, and the 2.2 file's $ElementData (read
# here: meshio cannot) is on the right elements. Exit 77 without meshio.
# usage: test_msh_meshio.py VM_CONVERT
import os
import random
import subprocess
import sys
import tempfile

try:
    import meshio
except ImportError:
    print("skip: meshio not importable by", sys.executable)
    sys.exit(77)

conv = sys.argv[1]
fail = 0


def check(ok, what):
    global fail
    print(("ok: " if ok else "FAIL: ") + what)
    fail |= not ok


def vertex(i, j, k):
    return (k * 4 + j) * 4 + i


# cells on a 4 x 4 x 4 lattice, each a distinct vertex set, types interleaved
rnd = random.Random(7)
nverts = {10: 4, 12: 8, 13: 6, 14: 5, 5: 3, 9: 4}
types = [10, 12, 5, 13, 9, 14]
cells, seen = [], set()
while len(cells) < 90:
    t = types[len(cells) % len(types)] if len(cells) % 5 else rnd.choice(types)
    i, j, k = rnd.randrange(3), rnd.randrange(3), rnd.randrange(3)
    cube = [vertex(i, j, k), vertex(i + 1, j, k), vertex(i + 1, j + 1, k), vertex(i, j + 1, k),
            vertex(i, j, k + 1), vertex(i + 1, j, k + 1), vertex(i + 1, j + 1, k + 1),
            vertex(i, j + 1, k + 1)]
    c = rnd.sample(cube, nverts[t])
    if tuple(sorted(c)) in seen:
        continue
    seen.add(tuple(sorted(c)))
    cells.append((t, c))
want = {tuple(sorted(c)): 1000 + 7 * n for n, (t, c) in enumerate(cells)}

with tempfile.TemporaryDirectory() as d:
    src = os.path.join(d, "in.vtk")
    with open(src, "w") as f:
        f.write("# vtk DataFile Version 3.0\ninterleaved\nASCII\nDATASET UNSTRUCTURED_GRID\n")
        f.write("POINTS 64 double\n")
        for k in range(4):
            for j in range(4):
                for i in range(4):
                    f.write("%d %d %d\n" % (i, j, k))
        f.write("CELLS %d %d\n" % (len(cells), sum(1 + len(c) for t, c in cells)))
        for t, c in cells:
            f.write("%d %s\n" % (len(c), " ".join(map(str, c))))
        f.write("CELL_TYPES %d\n" % len(cells))
        for t, c in cells:
            f.write("%d\n" % t)
        f.write("CELL_DATA %d\nSCALARS value int 1\nLOOKUP_TABLE default\n" % len(cells))
        for n in range(len(cells)):
            f.write("%d\n" % (1000 + 7 * n))
    for name, opts in (("a41.msh", []), ("b41.msh", ["--binary"]), ("a22.msh", ["--msh22"])):
        out = os.path.join(d, name)
        r = subprocess.run([conv, "-q"] + opts + [src, out], capture_output=True, text=True)
        check(r.returncode == 0, "vm-convert %s in.vtk %s (%s)" % (" ".join(opts), name,
                                                                   r.stderr.strip()))
        if r.returncode:
            continue
        if name == "a22.msh":
            continue  # read below: meshio 5.0 cannot read 2.2 files whose types interleave
        m = meshio.read(out)
        tot = bad = 0
        for block, vals in zip(m.cells, m.cell_data["value"]):
            for c, v in zip(block.data, vals):
                tot += 1
                bad += want.get(tuple(sorted(int(x) for x in c))) != int(v)
        check(tot == len(cells) and bad == 0,
              "%s: meshio reads %d cells, %d with another cell's value" % (name, tot, bad))
    # the tags of an ASCII 4.1 file, in file order
    tags = []
    with open(os.path.join(d, "a41.msh")) as f:
        lines = f.read().split("\n")
    i = lines.index("$Elements") + 1
    nblk = int(lines[i].split()[0])
    i += 1
    for b in range(nblk):
        n = int(lines[i].split()[3])
        tags += [int(lines[i + 1 + e].split()[0]) for e in range(n)]
        i += 1 + n
    check(tags == list(range(1, len(cells) + 1)),
          "4.1 element tags are 1..%d in file order" % len(cells))
    # 2.2 by hand (meshio 5.0 splits a 2.2 file's element data wrongly when
    # element types interleave, even a file it wrote itself): element
    # numbers 1..N in file order, and each $ElementData value on the
    # element of its number
    with open(os.path.join(d, "a22.msh")) as f:
        lines = f.read().split("\n")
    i = lines.index("$Elements") + 1
    n = int(lines[i])
    elems = [list(map(int, lines[i + 1 + e].split())) for e in range(n)]
    check([e[0] for e in elems] == list(range(1, n + 1)),
          "2.2 element numbers are 1..%d in file order" % n)
    conn = {e[0]: tuple(sorted(x - 1 for x in e[3 + e[2]:])) for e in elems}
    i = lines.index("$ElementData")
    n = int(lines[i + 8])
    vals = [list(map(int, lines[i + 9 + k].split())) for k in range(n)]
    bad = sum(want.get(conn.get(t)) != v for t, v in vals)
    check(n == len(cells) and bad == 0,
          "2.2: %d element values, %d on another element" % (n, bad))
sys.exit(1 if fail else 0)
