/* varmesh/io.h: reading and writing meshes in every format the project
 * knows (one table of readers and writers, registered by the library
 * itself), dispatch by extension, and atomic (temporary file + rename)
 * output. */
#ifndef VARMESH_IO_H
#define VARMESH_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
  VM_FMT_AUTO = 0,  /* from the file name's extension */
  VM_FMT_VMSH,      /* .vmsh  binary (docs/vmsh.md) */
  VM_FMT_VMSH_TEXT, /* .vmsht text variant */
  VM_FMT_VTK,       /* .vtk   legacy VTK, ASCII or binary */
  VM_FMT_VTU,       /* .vtu   VTK XML unstructured grid */
  VM_FMT_MSH,       /* .msh   Gmsh 4.1 (read 2.2 too) */
  VM_FMT_MEDIT,     /* .mesh  MEDIT / mmg / TetGen */
  VM_FMT_STL,       /* .stl   ASCII or binary (surfaces) */
  VM_FMT_OBJ,       /* .obj   Wavefront (surfaces) */
  VM_FMT_OFF,       /* .off   (surfaces) */
  VM_FMT_PLY,       /* .ply   ASCII or binary (surfaces) */
  VM_FMT_SU2,       /* .su2   SU2's native mesh, ASCII (volume meshes, markers) */
  VM_FMT_CGNS,      /* .cgns  CGNS unstructured zone through libcgns */
  VM_FMT_FOAM,      /* .foam  OpenFOAM case directory (constant/polyMesh), write only */
  VM_FMT_COUNT
} vm_format;

/* Format from a path's extension (case-insensitive); VM_FMT_AUTO if unknown. */
int vm_format_from_path(const char *path);
/* Format from a name ("vtk", "vtu", "msh", "mesh", "vmsh", "vmsht", "stl", ...). */
int vm_format_from_name(const char *name);
const char *vm_format_name(int format);
/* 1 if this build was made with libcgns (VM_FMT_CGNS), 0 if not. */
int vm_have_cgns(void);

typedef struct vm_write_opts {
  int binary;      /* VTK legacy, .msh, STL, PLY, OpenFOAM: 1 binary, 0 ASCII
                      (default 0; VTU always writes base64 binary) */
  int msh_version; /* 41 (default) or 22 */
} vm_write_opts;

/* Default options: ASCII, msh 4.1. */
vm_write_opts vm_write_opts_default(void);

/* Reader from memory: `name` is used only in error messages. */
typedef int (*vm_reader_fn)(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len,
                            vm_mesh **out);
/* Writer to a path (the writer must use vm_outfile for atomicity). */
typedef int (*vm_writer_fn)(vm_ctx *ctx, const vm_mesh *m, const char *path,
                            const vm_write_opts *opts);

/* Read a mesh. format VM_FMT_AUTO guesses from the extension. Files larger
 * than the host can hold are refused; every count is checked against the
 * file size before allocating. Errors are one line: "path: record: what". */
int vm_mesh_read(vm_ctx *ctx, const char *path, int format, vm_mesh **out);
/* The same from a buffer (fuzzing, tests). */
int vm_mesh_read_memory(vm_ctx *ctx, const char *name, const uint8_t *buf, size_t len, int format,
                        vm_mesh **out);
/* Write a mesh atomically: either the complete file appears at `path` or
 * nothing there changes (VM_FMT_FOAM writes a directory: see "OpenFOAM"
 * below). Returns VM_WARN_LOSSY (> 0) if the format could not carry
 * something (each loss is logged at VM_LOG_WARN). opts may be NULL. */
int vm_mesh_write(vm_ctx *ctx, const vm_mesh *m, const char *path, int format,
                  const vm_write_opts *opts);

/* Read a whole file into a new buffer (freed with vm_free). */
int vm_read_file(vm_ctx *ctx, const char *path, uint8_t **buf, size_t *len);

/* Atomic output: writes go to "<path>.tmp.<pid>.<n>", commit renames it over
 * path; abort (or a failed commit) removes the temporary file. */
typedef struct vm_outfile vm_outfile;
int vm_outfile_open(vm_ctx *ctx, const char *path, vm_outfile **out);
FILE *vm_outfile_fp(vm_outfile *f);
int vm_outfile_commit(vm_outfile **f);
void vm_outfile_abort(vm_outfile **f);

/* Surface formats (STL, OBJ, OFF, PLY).
 *
 * Reading (every format): a mesh with dim = 3, all vertices FREE, no fields,
 * elements VM_TRI and VM_QUAD in file order. Text coordinates are parsed as
 * doubles (all digits kept); binary ones are widened exactly (binary STL
 * float32; PLY float or double). Every input face is kept:
 *  - polygons with 5 to 1024 vertices are ear-clipped into n-2 triangles in
 *    the plane of their Newell normal (orientation kept; one VM_LOG_WARN with
 *    the count); larger ones are refused (VM_ERR_UNSUPPORTED);
 *  - faces with a repeated vertex and edges shared by more than two faces
 *    are kept as read and reported once each at VM_LOG_WARN (repair is the
 *    surface stage's job, not the reader's);
 *  - STL is a triangle soup: corners with identical coordinates (exact
 *    comparison, -0 == +0) become one vertex, numbered in order of first use;
 *    STL facet normals are ignored; nonzero binary attribute words are
 *    dropped with a warning.
 *  - OBJ/OFF/PLY keep the file's vertex numbering (no merging, unused
 *    vertices kept); normals, colors, texture coordinates, groups,
 *    materials and other PLY properties/elements are dropped, one
 *    VM_LOG_WARN per kind.
 * Binary vs ASCII STL: binary iff the size is 84 + 50 n (n from the header),
 * whatever the first bytes say; a file starting with "solid" that contains a
 * NUL byte is treated as a binary STL of the wrong size.
 * Errors (negative status, one line: "name: line N: what" for text,
 * "name: triangle K: what" for binary STL, "name: byte B: face K: what" for
 * binary PLY, "name: what" for whole-file problems): empty input, truncated
 * or lying counts, malformed records, non-finite coordinates, vertex indices
 * out of range, faces with fewer than 3 vertices, OFF variants 4OFF, nOFF
 * and OFF BINARY (VM_ERR_UNSUPPORTED), data after the last record.
 *
 * Writing: atomic (temporary file + rename, via vm_outfile). Coordinates are
 * written with 17 significant digits, so ASCII output reads back bit-exact;
 * binary PLY stores doubles; binary STL stores float32 (rounded to nearest).
 *  - STL: ASCII by default, binary if opts->binary; quads are split into two
 *    triangles (0,1,2),(0,2,3) with a warning. Facet normals are computed.
 *  - OBJ, OFF: triangles and quads, all vertices in mesh order.
 *  - PLY: ASCII by default, binary_little_endian if opts->binary; double
 *    x, y, z and an int vertex_indices list.
 * Only surface elements can be written: a mesh with only volume elements
 * gives VM_ERR_UNSUPPORTED and writes nothing; a mixed mesh has its
 * triangles and quads written (all vertices, numbering kept) and its volume
 * elements dropped with a warning. Fields, vertex flags / slip surface ids
 * and attributes cannot be carried: one VM_LOG_WARN each. Any such loss
 * makes the writer return VM_WARN_LOSSY (> 0) after writing the file.
 *
 * OpenMesh's own I/O is not used: in 9.0 its readers and writers round
 * coordinates to float and its OBJ reader skips unparsable vertex lines
 * silently, so the io library parses and writes these formats itself. */

/* Solver formats (SU2, CGNS, OpenFOAM): volume meshes with named
 * boundaries, and (SU2, CGNS) surface meshes.
 *
 * How faces are grouped. The volume elements of the mesh's top dimension
 * become the cells. Boundary faces (TRI / QUAD elements of the mesh) are
 * grouped by the int element field "gmsh:physical" and named by the
 * attributes "gmsh:physical_name:2:<tag>" ("wall", "outer" for the output
 * of vm_prism_result); a face without a tag, or a tag without a name, goes
 * to a family named "boundary_<tag>". If the mesh has no faces at all,
 * its boundary faces (vm_mesh_boundary) form one family "boundary"
 * (OpenFOAM: the patch "defaultFaces"). The name says the kind of
 * boundary, letter case ignored: a name starting with "wall" is a wall
 * (CGNS BCWall, OpenFOAM type wall), "farfield" a far field (BCFarfield,
 * type patch), "symmetry" a symmetry plane (BCSymmetryPlane, type
 * symmetryPlane); any other, "outer" included (the top of a prism layer is
 * no far field), is left to the user (BCTypeUserDefined, type patch).
 * Element fields of the cells (int or f64, one component; for example
 * "layer") are written where the format can hold them.
 *
 * Surface meshes. A 3D mesh whose top dimension is 2 (triangles and quads,
 * as read from an STL) is written as a surface mesh: its triangles and
 * quads are the cells and there are no boundary families, so the field
 * "gmsh:physical" and the "gmsh:physical_name:..." attributes are lost
 * (VM_WARN_LOSSY, one VM_LOG_WARN each). SU2: NDIME= 3, the faces as NELEM
 * in mesh order (types 5 and 9), NMARK= 0, and one VM_LOG_WARN that SU2's
 * solvers need volume cells (the status stays VM_OK if nothing else is
 * lost). CGNS: a base of cell dimension 2 in physical dimension 3, zone
 * "surface", a TRI_3 section "Triangles" then a QUAD_4 section
 * "Quadrilaterals" (each in mesh order), no Family_t or BC_t, cell fields
 * as for volume meshes. Both read back to the same coordinates bit for bit
 * and the same elements (CGNS: triangles first).
 *
 * SU2 native mesh (.su2, ASCII): NDIME=3, NELEM with VTK type ids and
 * 0-based indices, NPOIN with coordinates printed with 17 significant
 * digits, NMARK with one MARKER_TAG per family. Fields other than
 * "gmsh:physical", attributes other than the family names and vertex flags
 * cannot be stored (VM_WARN_LOSSY after writing, one VM_LOG_WARN each).
 * Atomic.
 * Returns VM_OK, VM_WARN_LOSSY, VM_ERR_ARG (no elements of dimension 2 or
 * 3: nothing written), VM_ERR_UNSUPPORTED (2D meshes), VM_ERR_IO,
 * VM_ERR_NOMEM.
 *
 * SU2 reading: a single-zone ASCII file of "KEY= value" lines (also
 * "KEY=value"; keys case-insensitive), each count followed by its records,
 * one per line; '%' starts a comment line; blank lines and CRLF are fine.
 *  - NDIME= 2 or 3 first (mesh dim 2 has z = 0); then NELEM=, NPOIN= (with
 *    an optional second count, as partitioned files have) and NMARK= in any
 *    order, each once (NMARK= optional). Indices used before NPOIN= are
 *    checked when it comes.
 *  - NELEM records: VTK type id, vertex indices (0-based, VTK order:
 *    prisms are renumbered by vm_elem_vtk_node), an optional trailing
 *    element index (ignored). Cells are 5 triangle and 9 quadrilateral in
 *    2D, 10 tetrahedron, 12 hexahedron, 13 prism and 14 pyramid in 3D; any
 *    other type is refused. In 3D, NELEM may instead hold only triangles
 *    and quadrilaterals (a surface mesh, as the writer writes one); a
 *    NELEM mixing volume cells and surface elements is refused at the
 *    first element that differs, and so is a marker of triangles or quads
 *    in a surface mesh (its markers can only hold lines, which are
 *    dropped). Elements keep the file's order.
 *  - NPOIN records: NDIME coordinates (parsed to the nearest double: the
 *    writer's %.17g reads back bit for bit), then up to two integers
 *    (ignored). Non-finite coordinates are refused.
 *  - Each marker: MARKER_TAG= name (the rest of the line, 1 to 200
 *    characters, blanks kept), MARKER_ELEMS= n, n records: 5 triangle or 9
 *    quadrilateral in 3D, 3 line in 2D and 3D. Triangles and quads are
 *    appended after the cells, marker by marker in file order, with the
 *    element field "gmsh:physical" = marker number (1, 2, ...; cells 0) and
 *    the attribute "gmsh:physical_name:2:<number>" = the name (NMARK= 0:
 *    no field). Lines are
 *    dropped (there is no edge element) with one VM_LOG_WARN; a marker
 *    with no faces keeps only its name. Writing what was read gives the
 *    same file but for the header comment.
 *  - NZONE= / IZONE= other than 1 (multi-zone): VM_ERR_UNSUPPORTED.
 *    FFD_NBOX= / FFD_NLEVEL= 0 are accepted; a nonzero one ends the mesh
 *    (the free-form deformation boxes after it are ignored with a warning).
 *  Errors are VM_ERR_FORMAT with one line "name: line N: what": unknown
 *  keywords and element types, truncated input, counts that cannot fit in
 *  the bytes left (checked before anything is allocated), too few or too
 *  many numbers on a record line, indices out of range, non-finite or
 *  unparsable numbers. Time and memory are linear in the file size.
 *
 * CGNS (.cgns, through libcgns): one base (cell dimension 3; 2 for a
 * surface mesh, see above), one
 * unstructured zone, coordinates in double, one element section per cell
 * type (TETRA_4, PYRA_5, PENTA_6, HEXA_8; 1-based, VTK order equals CGNS
 * order for these types), one section per face family (TRI_3 / QUAD_4),
 * a Family_t per face family (its BC type from the name, see above) and a
 * BC_t per family referring to it by
 * FamilyName with its element range at FaceCenter; cell fields as a
 * cell-centred FlowSolution_t. Atomic (temporary file + rename).
 * Returns VM_OK, VM_WARN_LOSSY (vertex fields, element fields of several
 * components, vertex flags and attributes other than the family names are
 * not written; one VM_LOG_WARN each), VM_ERR_UNSUPPORTED (built without
 * libcgns; 2D meshes), VM_ERR_ARG (no elements of dimension 2 or 3),
 * VM_ERR_IO, VM_ERR_BACKEND (libcgns failed; its message on ctx),
 * VM_ERR_NOMEM.
 *
 * CGNS reading: libcgns opens files by path only, so the buffer is copied
 * to a private temporary file (mkstemp in $TMPDIR, else /tmp) that is
 * unlinked as soon as libcgns has opened it: nothing is left behind on any
 * path, and vm_mesh_read and vm_mesh_read_memory behave alike (a file is
 * read into memory first, so it is copied once more). Accepted: one base
 * of cell and physical dimension 3, or of cell dimension 2 in physical
 * dimension 3 (a surface mesh), with one unstructured zone (other
 * layouts: VM_ERR_UNSUPPORTED); coordinates CoordinateX/Y/Z in single or
 * double (widened exactly); element sections TRI_3, QUAD_4, TETRA_4,
 * PYRA_5, PENTA_6, HEXA_8 and MIXED of these (NODE and BAR_2 are dropped
 * with a warning; other types, higher order or polyhedra,
 * VM_ERR_UNSUPPORTED). Elements become vm elements in element-id order
 * (the writer's file: cells grouped by type, then the families' faces).
 * Face families: each BC_t on elements (ElementRange/List, or
 * PointRange/List at a location other than Vertex) names its faces after
 * its FamilyName, else its own name; names become "gmsh:physical" tags
 * 1, 2, ... in order of first appearance with their
 * "gmsh:physical_name:2:<tag>" attributes; faces in no BC get one family
 * per section, named after the section. BCs given on vertices are ignored
 * with a warning. Solutions: FlowSolution_t at CellCenter (values in
 * cell-element-id order) become element fields (0 on faces), at Vertex
 * vertex fields; Integer as int, RealSingle / RealDouble as f64; others
 * (rind, other locations or types, names starting "gmsh:") are ignored
 * with one warning. Writing what was read gives the same mesh again.
 * Errors: VM_ERR_FORMAT, one line "name: what[: libcgns: message]", for
 * files libcgns cannot open or read, arrays claiming more entries than the
 * file has bytes (checked before allocating), overlapping sections, node
 * indices out of range, non-finite coordinates; VM_ERR_IO if the temporary
 * file cannot be written.
 * A base of cell dimension 2 is a surface mesh: its TRI_3 / QUAD_4
 * elements are the cells (a volume element in it is VM_ERR_FORMAT), NODE
 * and BAR_2 are dropped as above, its BC_t (on edges) are ignored with one
 * warning, no "gmsh:physical" field is made, and CellCenter solutions
 * belong to its triangles and quads.
 * libcgns itself is not hardened against hostile files (it reads the
 * whole node tree at open), is not thread-safe, and
 * its warnings are silenced by a global handler (cg_configure) so that the
 * library prints nothing; do not feed it untrusted input. */

/* OpenFOAM (VM_FMT_FOAM, "foam"; write only). `path` is a case directory
 * (a path ending in ".foam" is one, suffix and all; trailing '/' ignored);
 * the writer makes path/constant/polyMesh/{points, faces, owner, neighbour,
 * boundary} with FoamFile headers (version 2.0; class vectorField,
 * faceList, labelList, polyBoundaryMesh; location "constant/polyMesh";
 * owner and neighbour note nPoints, nCells, nFaces, nInternalFaces).
 * ASCII by default: points with 17 significant digits (they read back bit
 * for bit). opts->binary: OpenFOAM's binary format (arch
 * "LSB;label=32;scalar=64" on this machine's byte order; faces as a
 * faceCompactList; boundary stays text).
 *  - Cells: the tetrahedra, pyramids, prisms and hexahedra in mesh order;
 *    points: the vertices cells use, in vertex order (others dropped,
 *    warned).
 *  - Faces: each face shared by two cells once, owner the lower cell,
 *    neighbour the higher, vertices in the owner's order (right-hand
 *    normal from owner to neighbour), in upper-triangular order (owner,
 *    then neighbour, increasing); then the boundary faces patch by patch,
 *    each oriented as its cell has it (out of the domain).
 *  - Patches: the families above in tag order (faces matched to the
 *    cells' boundary faces by vertex set, in mesh order), names made
 *    OpenFOAM words (other characters '_', "patch_" before a name not
 *    starting with a letter or '_'; equal names share a patch; warned);
 *    types wall (inGroups wall), symmetryPlane (if its faces are flat to
 *    OpenFOAM's tolerance; else symmetry, warned) or patch. Boundary faces
 *    no element covers form the patch "defaultFaces" (type patch; warned).
 *  - Atomic: a new case is built in a temporary directory beside path and
 *    renamed into place, with a minimal system/controlDict, fvSchemes and
 *    fvSolution (so that checkMesh runs on it). In an existing case only
 *    constant/polyMesh is replaced (built as constant/.polyMesh.tmp.*, the
 *    old one moved aside, then removed; put back if the rename fails);
 *    missing system/ files are added, nothing else is touched.
 * Returns VM_OK, VM_WARN_LOSSY (fields, vertex flags, attributes other
 * than the boundary names, unused vertices, boundary elements between two
 * cells or on no cell or repeated, renamed boundaries; one VM_LOG_WARN
 * each), VM_ERR_UNSUPPORTED (no volume cells: "OpenFOAM needs 3D cells";
 * more than 2^31 - 1 cell faces), VM_ERR_ARG (a face of three or more
 * cells, a cell with a repeated vertex), VM_ERR_IO (path is a file, or
 * writing failed: nothing changed), VM_ERR_NOMEM. */

/* Remove every temporary file an output is being written to (the files
 * that become OUT on success). Async-signal-safe: for a signal handler
 * that ends the program, so that no OUT.tmp.* is left behind. */
void vm_io_remove_temporaries(void);

#ifdef __cplusplus
}
#endif
#endif
