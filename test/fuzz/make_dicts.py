#!/usr/bin/env python3
"""test/fuzz/make_dicts.py: write the libFuzzer dictionaries dict/<reader>.dict
from the keywords quoted in each reader's source plus a few hand-picked
tokens. Run: python3 test/fuzz/make_dicts.py"""
import os
import re

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.join(HERE, "..", "..")


def words(rel, extra=()):
    with open(os.path.join(ROOT, rel)) as f:
        s = f.read()
    w = set(re.findall(r'"([A-Za-z_$][A-Za-z_0-9]*)"', s))
    return sorted(w) + list(extra)


def esc(tok):
    b = tok.encode("latin-1") if isinstance(tok, str) else tok
    out = ""
    for c in b:
        if c in (0x22, 0x5C):
            out += "\\" + chr(c)
        elif 0x20 <= c < 0x7F:
            out += chr(c)
        else:
            out += "\\x%02X" % c
    return '"' + out + '"'


def write(name, toks, what):
    with open(os.path.join(HERE, "dict", name + ".dict"), "w") as f:
        f.write("# test/fuzz/dict/%s.dict: %s (make_dicts.py)\n" % (name, what))
        seen = set()
        for t in toks:
            if t not in seen:
                seen.add(t)
                f.write(esc(t) + "\n")


os.makedirs(os.path.join(HERE, "dict"), exist_ok=True)
write("vmsht", words("lib/io/src/vmsh.c", ["vmsht 1 0", "\n", "nan", "inf", "-0", "1e308", "1e-320"]),
      "keywords of the .vmsht text format")
write("vmsh", ["VMSH", "MESH", "VERT", "VFLG", "ELEM", "FILD", "ATTR", b"\0\0\0\0",
               b"\xff\xff\xff\xff", b"\xff\xff\xff\x7f", b"\0\0\0\0\0\0\xf0\x7f"],
      "binary .vmsh chunk tags and awkward values")
write("vtk", words("lib/io/src/vtk.c", ["# vtk DataFile Version 3.0\n", "double", "float", "int",
                                     "vtktypeint64", "unsigned_char", "default", "\n", "1e308",
                                     "-1"]),
      "legacy VTK keywords")
write("vtu", ["<VTKFile", "</VTKFile>", "<UnstructuredGrid>", "<Piece", "</Piece>", "<Points>",
              "<Cells>", "<PointData>", "<CellData>", "<DataArray", "</DataArray>",
              "<AppendedData", "</AppendedData>", "<!--", "-->", "<?xml", "/>", 'type="',
              'Name="', 'format="ascii"', 'format="binary"', 'format="appended"', 'offset="',
              'NumberOfComponents="', 'NumberOfPoints="', 'NumberOfCells="',
              'header_type="UInt64"', 'header_type="UInt32"',
              'compressor="vtkZLibDataCompressor"', 'byte_order="BigEndian"',
              'byte_order="LittleEndian"', 'encoding="raw"', 'encoding="base64"', "Float32",
              "Float64", "Int8", "Int16", "Int32", "Int64", "UInt8", "UInt16", "UInt32",
              "UInt64", "connectivity", "offsets", "types", "&amp;", "&quot;", "=", b"x\x9c"],
      "VTK XML tags and attributes")
write("msh", words("lib/io/src/msh.c", ["$MeshFormat", "$EndMeshFormat", "$Nodes", "$EndNodes",
                                     "$Elements", "$EndElements", "$Entities", "$EndEntities",
                                     "$PhysicalNames", "$EndPhysicalNames", "$NodeData",
                                     "$EndNodeData", "$ElementData", "$EndElementData",
                                     "$Comments", "4.1 0 8", "4.1 1 8", "2.2 0 8", "2.2 1 8",
                                     b"\x01\0\0\0"]),
      "Gmsh .msh section names")
write("medit", words("lib/io/src/medit.c", ["\n", "MeshVersionFormatted 2", "Dimension 3", "#"]),
      "MEDIT keywords")
write("stl", words("lib/io/src/stl.c", ["outer loop", "facet normal", b"\0"]), "STL keywords")
write("obj", words("lib/io/src/obj.c", ["/", "//", "-1", "\\\n"]), "OBJ keywords")
write("off", words("lib/io/src/off.c", ["COFF", "NOFF", "4OFF", "nOFF", "#"]), "OFF keywords")
write("ply", words("lib/io/src/ply.c", ["ply\n", "end_header\n",
                                            "property list uchar int vertex_indices",
                                            "format binary_little_endian 1.0",
                                            "format ascii 1.0", "element vertex ",
                                            "element face "]),
      "PLY header keywords")
write("su2", ["NDIME=", "NELEM=", "NPOIN=", "NMARK=", "MARKER_TAG=", "MARKER_ELEMS=", "NZONE=",
              "IZONE=", "FFD_NBOX=", "FFD_NLEVEL=", "%", "\n", "\r\n", " 3", " 5", " 9", " 10",
              " 12", " 13", " 14", "nan", "1e308", "-1", "2147483647"],
      "SU2 keywords and element type ids")
