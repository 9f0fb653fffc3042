/* varmesh/surface_io.h: surface mesh formats (STL ASCII and binary, OBJ,
 * OFF, PLY ASCII and binary) installed on a context as format handlers. */
#ifndef VARMESH_SURFACE_IO_H
#define VARMESH_SURFACE_IO_H

#include "varmesh/ctx.h"
#include "varmesh/io.h"
#include "varmesh/mesh.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Install readers and writers for VM_FMT_STL, VM_FMT_OBJ, VM_FMT_OFF and
 * VM_FMT_PLY on ctx, so vm_mesh_read / vm_mesh_write handle .stl, .obj, .off
 * and .ply. Returns VM_OK, or VM_ERR_ARG if ctx is NULL.
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
 * silently, so this module parses and writes the formats itself. */
int vm_surface_register_formats(vm_ctx *ctx);

#ifdef __cplusplus
}
#endif
#endif
