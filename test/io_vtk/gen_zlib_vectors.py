#!/usr/bin/env python3
"""test/io_vtk/gen_zlib_vectors.py: writes zlib_vectors.h, compressed VTU
files (as VTK's vtkZLibDataCompressor lays them out) for test_vtk.c.

Mesh: NP points (i, i/2, i/4), one tet on points 0..3, a point field 'ramp'
= i/8 and a cell field 'id' = 42. Run: python3 gen_zlib_vectors.py > zlib_vectors.h
"""
import base64
import struct
import zlib

NP = 300


def blocks(data, bs, level, hfmt):
    chunks = [data[i:i + bs] for i in range(0, len(data), bs)] or [b""]
    comp = [zlib.compress(c, level) for c in chunks]
    last = len(chunks[-1]) if len(chunks[-1]) != bs else 0
    head = struct.pack("<" + hfmt * (3 + len(comp)), len(comp), bs, last,
                       *[len(c) for c in comp])
    return head, b"".join(comp)


def vtu(level, bs, hfmt, appended):
    htype = "UInt64" if hfmt == "Q" else "UInt32"
    pts = b"".join(struct.pack("<ddd", i, i / 2, i / 4) for i in range(NP))
    arrays = [
        ("PointData", 'type="Float64" Name="ramp"',
         b"".join(struct.pack("<d", i / 8) for i in range(NP))),
        ("CellData", 'type="Int32" Name="id"', struct.pack("<i", 42)),
        ("Points", 'type="Float64" NumberOfComponents="3"', pts),
        ("Cells", 'type="Int32" Name="connectivity"', struct.pack("<4i", 0, 1, 2, 3)),
        ("Cells", 'type="Int32" Name="offsets"', struct.pack("<i", 4)),
        ("Cells", 'type="UInt8" Name="types"', bytes([10])),
    ]
    out = ['<?xml version="1.0"?>',
           '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" '
           'header_type="%s" compressor="vtkZLibDataCompressor">' % htype,
           '<UnstructuredGrid><Piece NumberOfPoints="%d" NumberOfCells="1">' % NP]
    app = b""
    for sec in ("PointData", "CellData", "Points", "Cells"):
        out.append("<%s>" % sec)
        for s, attrs, data in arrays:
            if s != sec:
                continue
            head, body = blocks(data, bs, level, hfmt)
            enc = base64.b64encode(head) + base64.b64encode(body)
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


def cstr(name, text):
    """Pieces of at most 100 characters (C99 only promises 4095 per literal)."""
    lines = ["static const char *const %s[] = {" % name]
    for i in range(0, len(text), 100):
        chunk = text[i:i + 100].replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n")
        lines.append('    "%s",' % chunk)
    lines.append("    0};")
    return "\n".join(lines) + "\n"


print("/* test/io_vtk/zlib_vectors.h: compressed VTU files made by gen_zlib_vectors.py,")
print(" * each as a NULL-terminated list of pieces to concatenate. */")
print("#define ZV_NP %d" % NP)
print(cstr("zv_dynamic", vtu(9, 1 << 15, "I", False)))
print(cstr("zv_blocks", vtu(6, 1000, "Q", False)))
print(cstr("zv_stored", vtu(0, 1 << 15, "I", False)))
print(cstr("zv_fixed_appended", vtu(1, 256, "I", True)))
