#!/usr/bin/env python3
"""test/fuzz/hand_seeds.py: write the hand-made seeds of the reader fuzzers
(test/fuzz/corpus/<reader>/hand-*): variants the library's writers never
produce (zlib-compressed and appended VTU, big-endian PLY, OBJ with slashes
and negative indices, MEDIT keywords, msh sections, comments) and edge cases
(empty, header only); for CGNS, programs of the structure-aware harness
fuzz_cgns.c that describe valid meshes. Run: python3 test/fuzz/hand_seeds.py"""
import base64
import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))


def put(reader, name, data):
    d = os.path.join(HERE, "corpus", reader)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, "hand-" + name), "wb") as f:
        f.write(data)


def vtu_zlib(appended, hfmt):
    htype = "UInt64" if hfmt == "Q" else "UInt32"
    pts = struct.pack("<12d", 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1)
    arrays = [("Points", 'type="Float64" NumberOfComponents="3"', pts),
              ("Cells", 'type="Int32" Name="connectivity"', struct.pack("<4i", 0, 1, 2, 3)),
              ("Cells", 'type="Int32" Name="offsets"', struct.pack("<i", 4)),
              ("Cells", 'type="UInt8" Name="types"', bytes([10])),
              ("PointData", 'type="Float32" Name="w"', struct.pack("<4f", 1, 2, 3, 4))]
    out = ['<?xml version="1.0"?>',
           '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
           'header_type="%s" compressor="vtkZLibDataCompressor">' % htype,
           '<UnstructuredGrid><Piece NumberOfPoints="4" NumberOfCells="1">']
    app = b""
    for sec in ("PointData", "Points", "Cells"):
        out.append("<%s>" % sec)
        for s, attrs, data in arrays:
            if s != sec:
                continue
            comp = zlib.compress(data, 6)
            head = struct.pack("<" + hfmt * 4, 1, len(data), len(data), len(comp))
            enc = base64.b64encode(head) + base64.b64encode(comp)
            if appended:
                out.append('<DataArray %s format="appended" offset="%d"/>' % (attrs, len(app)))
                app += enc
            else:
                out.append('<DataArray %s format="binary">%s</DataArray>' % (attrs, enc.decode()))
        out.append("</%s>" % sec)
    out.append("</Piece></UnstructuredGrid>")
    if appended:
        out.append('<AppendedData encoding="base64">_%s</AppendedData>' % app.decode())
    out.append("</VTKFile>")
    return "\n".join(out) + "\n"


VTU_ASCII = """<?xml version="1.0"?>
<!-- a comment -->
<VTKFile type="UnstructuredGrid" version="0.1" byte_order="BigEndian">
<UnstructuredGrid><Piece NumberOfPoints="5" NumberOfCells="1">
<Points><DataArray type="Float32" NumberOfComponents="3" format="ascii">
0 0 0 1 0 0 1 1 0 0 1 0 .5 .5 1e0</DataArray></Points>
<Cells><DataArray type="Int64" Name="connectivity" format="ascii">0 1 2 3 4</DataArray>
<DataArray type="Int64" Name="offsets" format="ascii">5</DataArray>
<DataArray type="UInt8" Name="types" format="ascii">14</DataArray></Cells>
<CellData><DataArray type="Int32" Name="layer" format="ascii">7</DataArray></CellData>
</Piece></UnstructuredGrid></VTKFile>
"""


def vtu_raw():
    conn = struct.pack("<I3i", 12, 0, 1, 2)
    pts = struct.pack("<I9d", 72, 0, 0, 0, 1, 0, 0, 0, 1, 0)
    off = struct.pack("<Ii", 4, 3)
    typ = struct.pack("<IB", 1, 5)
    app = b""
    offs = []
    for blk in (pts, conn, off, typ):
        offs.append(len(app))
        app += blk
    head = ('<?xml version="1.0"?>\n<VTKFile type="UnstructuredGrid" version="1.0" '
            'byte_order="LittleEndian" header_type="UInt32">\n'
            '<UnstructuredGrid><Piece NumberOfPoints="3" NumberOfCells="1">\n'
            '<Points><DataArray type="Float64" NumberOfComponents="3" format="appended" offset="%d"/></Points>\n'
            '<Cells><DataArray type="Int32" Name="connectivity" format="appended" offset="%d"/>\n'
            '<DataArray type="Int32" Name="offsets" format="appended" offset="%d"/>\n'
            '<DataArray type="UInt8" Name="types" format="appended" offset="%d"/></Cells>\n'
            '</Piece></UnstructuredGrid>\n<AppendedData encoding="raw">\n_' % tuple(offs))
    return head.encode() + app + b"\n</AppendedData>\n</VTKFile>\n"


VTK_POLY = """# vtk DataFile Version 2.0
polydata
ASCII
DATASET POLYDATA
POINTS 5 float
0 0 0 1 0 0 1 1 0 0 1 0 2 2 0
POLYGONS 2 9
3 0 1 2
4 0 1 2 3
POINT_DATA 5
SCALARS s float 1
LOOKUP_TABLE default
1 2 3 4 5
VECTORS v double
1 0 0 0 1 0 0 0 1 1 1 1 0 0 0
"""

VTK_51 = """# vtk DataFile Version 5.1
vtk 5.1 offsets/connectivity
ASCII
DATASET UNSTRUCTURED_GRID
POINTS 4 double
0 0 0 1 0 0 0 1 0 0 0 1
CELLS 2 4
OFFSETS vtktypeint64
0 4
CONNECTIVITY vtktypeint64
0 1 2 3
CELL_TYPES 1
10
CELL_DATA 1
SCALARS id int 1
LOOKUP_TABLE default
3
"""

MEDIT_KW = """MeshVersionFormatted 2
# comment line
Dimension
3
Vertices 4
0 0 0 1
1 0 0 1
0 1 0 2
0 0 1 3
Edges 1
1 2 5
Corners 1
1
Ridges 1
1
RequiredVertices 1
4
Normals 1
0 0 1
NormalAtVertices 1
1 1
Triangles 1
1 2 3 4
Tetrahedra
1
1 2 3 4 9
End
"""

MEDIT_2D = """MeshVersionFormatted 1
Dimension 2
Vertices
3
0 0 1
1 0 1
0 1 1
Triangles
1
1 2 3 0
End
"""

MSH41_ENT = """$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
2
2 1 "wall"
3 2 "fluid"
$EndPhysicalNames
$Entities
0 0 1 1
1 0 0 0 1 1 0 1 1 0
1 0 0 0 1 1 1 1 2 0
$EndEntities
$Nodes
2 4 1 4
2 1 0 3
1
2
3
0 0 0
1 0 0
0 1 0
3 1 0 1
4
0 0 1
$EndNodes
$Elements
2 2 1 2
2 1 2 1
1 1 2 3
3 1 4 1
2 1 2 3 4
$EndElements
$NodeData
1
"t"
1
0
3
0
1
4
1 1.5
2 2.5
3 3.5
4 4.5
$EndNodeData
$Comments
anything
$EndComments
"""

MSH22 = """$MeshFormat
2.2 0 8
$EndMeshFormat
$Nodes
5
1 0 0 0
2 1 0 0
3 1 1 0
4 0 1 0
5 .5 .5 1
$EndNodes
$Elements
2
1 7 2 1 1 1 2 3 4 5
2 3 2 2 2 1 2 3 4
$EndElements
$ElementData
1
"e"
1
0
3
0
1
2
1 10
2 20
$EndElementData
"""

STL_MULTI = """solid a
facet normal 0 0 1
 outer loop
  vertex 0 0 0
  vertex 1 0 0
  vertex 0 1 0
 endloop
endfacet
endsolid a
solid b
facet normal 0 0 0
 outer loop
  vertex 1 0 0
  vertex 1 1 0
  vertex 0 1 0
 endloop
endfacet
endsolid b
"""


def stl_binary_solid_header():
    head = b"solid looks like ascii" + b"\0" * (80 - 22)
    tri = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 7)
    return head + struct.pack("<I", 1) + tri


OBJ_SLASH = """# obj with everything
mtllib x.mtl
o thing
g group1
v 0 0 0
v 1 0 0 1.0
v 1 1 0
v 0 1 0
v 2 0.5 0
vt 0 0
vn 0 0 1
usemtl m
s off
f 1/1/1 2/1/1 3/1/1
f -2//1 -4//1 -3//1
f 1 2 5 3 4
l 1 2
"""

OFF_COMMENTS = """OFF
# comment
5 3 0
0 0 0
1 0 0
1 1 0
0 1 0
2 2 2
3 0 1 2 255 0 0
4 0 1 2 3
5 0 1 4 2 3
"""

COFF = """COFF
3 1 0
0 0 0 1 0 0 1
1 0 0 0 1 0 1
0 1 0 0 0 1 1
3 0 1 2
"""


def ply_be():
    head = ("ply\nformat binary_big_endian 1.0\ncomment hand made\n"
            "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "property uchar red\n"
            "element face 2\nproperty list uchar int vertex_indices\n"
            "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n")
    body = b""
    for p in ((0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)):
        body += struct.pack(">3fB", *p, 200)
    body += struct.pack(">B3i", 3, 0, 1, 2) + struct.pack(">B4i", 4, 0, 1, 2, 3)
    body += struct.pack(">2i", 0, 1)
    return head.encode() + body


PLY_ASCII = """ply
format ascii 1.0
obj_info x
element vertex 5
property double x
property double y
property double z
property float nx
element face 2
property list uchar uint vertex_indices
property int flags
end_header
0 0 0 1
1 0 0 1
1 1 0 1
0 1 0 1
2 2 0 1
3 0 1 2 5
5 0 1 4 2 3 6
"""

def vtk_binary_nan():
    """Legacy VTK binary (big-endian) with NaN payloads, -NaN, -0 and a
    subnormal in a point field: round trips through .vmsht keep the sign of
    a NaN but not its payload."""
    pts = struct.pack(">12d", 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1)
    vals = struct.pack(">Q", 0x7FF8000000000001) + struct.pack(">Q", 0xFFF0000000000123) + \
        struct.pack(">d", -0.0) + struct.pack(">Q", 1)
    return (b"# vtk DataFile Version 3.0\nnan payloads\nBINARY\nDATASET UNSTRUCTURED_GRID\n"
            b"POINTS 4 double\n" + pts + b"\nCELLS 1 5\n" + struct.pack(">5i", 4, 0, 1, 2, 3) +
            b"\nCELL_TYPES 1\n" + struct.pack(">i", 10) +
            b"\nPOINT_DATA 4\nSCALARS w double 1\nLOOKUP_TABLE default\n" + vals + b"\n")


put("vtu", "zlib-inline-u64", vtu_zlib(False, "Q"))
put("vtu", "zlib-appended-u32", vtu_zlib(True, "I"))
put("vtu", "ascii-bigendian", VTU_ASCII)
put("vtu", "appended-raw", vtu_raw())
put("vtk", "polydata", VTK_POLY)
put("vtk", "v51-offsets", VTK_51)
put("vtk", "binary-nan-payload", vtk_binary_nan())
put("medit", "keywords", MEDIT_KW)
put("medit", "planar", MEDIT_2D)
put("msh", "v41-entities", MSH41_ENT)
put("msh", "v22-data", MSH22)
put("stl", "multi-solid", STL_MULTI)
put("stl", "binary-solid-header", stl_binary_solid_header())
put("obj", "slashes", OBJ_SLASH)
put("off", "comments", OFF_COMMENTS)
put("off", "coff", COFF)
put("ply", "big-endian", ply_be())
put("ply", "ascii-extra", PLY_ASCII)
put("su2", "general", "% comment\r\nNDIME=3\r\nNPOIN= 7 7\r\n0 0 0 0\r\n1 0 0 1\r\n"
    "0 1 0 2\r\n0 0 1\r\n1 0 1\r\n0 1 1 5\r\n0.25 0.25 2 6\r\n\r\nNELEM= 2\r\n"
    "13 0 2 1 3 5 4 0\r\n10 3 4 5 6\r\nNMARK= 2\r\nMARKER_TAG= bottom wall\r\n"
    "MARKER_ELEMS= 2\r\n5 0 2 1\r\n3 0 1 1\r\nMARKER_TAG=top\r\nMARKER_ELEMS=1\r\n"
    "5 3 4 6\r\n")
put("su2", "planar", "NDIME= 2\nNELEM= 2\n5 0 1 2 0\n9 1 3 4 2 1\nNPOIN= 5\n0 0\n1 0\n"
    "0 1\n2 0 3\n2 1 4\nNMARK= 1\nMARKER_TAG= far\nMARKER_ELEMS= 2\n3 0 1\n3 1 3\n")
put("su2", "zone-ffd", "NZONE= 1\nIZONE= 1\nNDIME= 3\nNELEM= 1\n12 0 1 2 3 4 5 6 7\n"
    "NPOIN= 8\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
    "NMARK= 1\nMARKER_TAG= box\nMARKER_ELEMS= 2\n9 0 3 2 1\n9 4 5 6 7\nFFD_NBOX= 0\n"
    "FFD_NLEVEL= 0\n")


def cgns_program(cdim, nv, coords, sections, bcs, solution=True):
    """A program for fuzz_cgns.c (its bytes are read in this order): a base,
    an unstructured zone, all three coordinates, sections (type index, element
    nodes; each starting after the last), boundary conditions as element ranges
    with a family, and a cell solution."""
    types = ["TRI_3", "QUAD_4", "TETRA_4", "PYRA_5", "PENTA_6", "HEXA_8"]
    b = [cdim - 1, 2, 1, nv, sum(len(e) for _, e in sections), 0]
    for k in range(3):
        b += [128 + 16 * int(c[k]) for c in coords]
    b.append(len(sections))
    for t, elems in sections:
        b += [types.index(t), 1, len(elems)]
        for e in elems:
            b += [v % (nv + 3) for v in e]  # node v (1-based) is byte v + 1 - 1
    b.append(len(bcs))
    for first, last, fam in bcs:
        b += [2, 1, first + 1, last + 1, 0, 1, fam]
    if solution:
        b += [1, 1, 1] + [128, 3] * 64 + [1]
    return bytes(b)


# the bytes of a node: take_int(b, nv) = c % (nv + 3) - 1, so node v is c = v + 1
def _n(*vs):
    return [v + 1 for v in vs]


put("cgns", "tet", cgns_program(3, 4, [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)],
                                [("TETRA_4", [_n(1, 2, 3, 4)]), ("TRI_3", [_n(1, 3, 2)])],
                                [(2, 2, 0)]))
put("cgns", "prism-pyramid", cgns_program(
    3, 7, [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (0, 1, 1), (1, 1, 0)],
    [("PENTA_6", [_n(1, 2, 3, 4, 5, 6)]), ("TETRA_4", [_n(2, 7, 3, 5)]),
     ("TRI_3", [_n(1, 3, 2), _n(4, 5, 6)])], [(3, 3, 0), (4, 4, 1)]))
put("cgns", "hex", cgns_program(
    3, 8, [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
    [("HEXA_8", [_n(1, 2, 3, 4, 5, 6, 7, 8)]), ("QUAD_4", [_n(1, 4, 3, 2), _n(5, 6, 7, 8)])],
    [(2, 3, 1)], solution=False))
put("cgns", "surface", cgns_program(
    2, 4, [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [("TRI_3", [_n(1, 2, 3), _n(1, 3, 4)])],
    []))
for r in ("vmsh", "vmsht", "vtk", "vtu", "msh", "medit", "stl", "obj", "off", "ply", "su2"):
    put(r, "empty", b"")
put("vmsht", "header-only", "vmsht 1 0\ndim 3\nvertices 0\nelements 0\nfields 0\n")
put("vtk", "header-only", "# vtk DataFile Version 3.0\n\nASCII\nDATASET UNSTRUCTURED_GRID\n")
put("msh", "header-only", "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n")
