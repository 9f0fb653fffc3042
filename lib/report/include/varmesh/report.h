/* varmesh/report.h: reports with pictures: PNG figures drawn with cairo
 * (quality histograms, convergence plots, a rendered surface coloured by a
 * field, a planar slice through a volume mesh) and a self-contained
 * index.html that shows them with a table of the key numbers. */
#ifndef VARMESH_REPORT_H
#define VARMESH_REPORT_H

#include <stdint.h>

#include "varmesh/ctx.h"
#include "varmesh/mesh.h"
#include "varmesh/quality.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct vm_report vm_report;

/* 1 if this build can draw reports (it was built with cairo), else 0. */
int vm_report_available(void);

/* Start a report in directory `dir` (created if missing; its parent must
 * exist). Figures are written as they are added, into a temporary
 * directory (beside `dir` if it is missing, else inside it), made here;
 * vm_report_write writes index.html there and puts everything in place
 * (renames), so a report that fails half-way (a full disk) leaves nothing
 * at `dir`, and vm_report_destroy before a write removes what was drawn.
 * title: the page heading.
 * Returns VM_OK, VM_ERR_UNSUPPORTED (built without cairo), VM_ERR_IO (the
 * directory cannot be made or is not writable), VM_ERR_NOMEM.
 * *out receives the report (NULL on failure); free with vm_report_destroy. */
int vm_report_create(vm_ctx *ctx, const char *dir, const char *title, vm_report **out);
void vm_report_destroy(vm_report **p);

/* Table of key numbers: a heading row, then key/value rows (printf-style
 * value, HTML-escaped). */
int vm_report_heading(vm_report *r, const char *heading);
int vm_report_row(vm_report *r, const char *key, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
/* The rows of a vm_quality: counts, M, phi_min, psi_min, scaled Jacobian
 * per element type and overall, under `heading`. */
int vm_report_quality_rows(vm_report *r, const char *heading, const vm_quality *q);

/* Write DIR/index.html: title, the table, every figure added so far in
 * order with its caption, and move the figures drawn since the last write
 * into DIR with it (index.html last). May be called again after more
 * figures are added. Returns VM_OK or VM_ERR_IO. */
int vm_report_write(vm_report *r);

/* Every figure function below writes DIR/<name>.png (name: letters, digits,
 * '-', '_'; written to a temporary file and renamed), adds it to the page
 * with `caption` (may be NULL), and returns VM_OK, VM_ERR_ARG (bad name or
 * arguments, message on the context), VM_ERR_IO or VM_ERR_NOMEM. */

/* Quality histograms of the elements of the mesh's top dimension: the
 * scaled Jacobian over [-1, 1] (inverted elements in red), and one panel
 * per element type present of phi = min over the element's quadrature
 * simplices of det C/(tr C^T C/d)^{d/2}. opts as for vm_mesh_quality. */
int vm_report_histograms(vm_report *r, const char *name, const char *caption, const vm_mesh *m,
                         const vm_quality_opts *opts);

/* Convergence history: one sample per iteration of an iterative stage. */
typedef struct vm_report_history vm_report_history;

int vm_report_history_create(vm_ctx *ctx, vm_report_history **out);
void vm_report_history_destroy(vm_report_history **p);
/* Append one iteration. phase: a short name ("untangle", "optimize", ...;
 * copied); total_iter: iteration counted over all phases (the x axis);
 * M: inverted quadrature simplices; F: functional; eps: the untangling
 * epsilon (or any positive control parameter; <= 0 or NaN: not drawn). */
int vm_report_history_add(vm_report_history *h, const char *phase, int total_iter, double F,
                          int64_t M, double eps);
int64_t vm_report_history_count(const vm_report_history *h);

/* Three stacked panels against the iteration: M (log scale, M = 0 drawn on
 * a separate baseline), F and eps (log scale when positive), the phases
 * separated by dashed lines and named. An empty history draws empty axes. */
int vm_report_convergence(vm_report *r, const char *name, const char *caption,
                          const vm_report_history *h);

/* View of a rendered surface: orthographic, looking along the direction
 * given by azimuth (about +z, from +x) and elevation (above the xy plane),
 * in degrees. */
typedef struct vm_report_view {
  double azimuth;    /* default -60 */
  double elevation;  /* default 25 */
  int width, height; /* pixels (default 1000 x 700) */
  int edges;         /* draw element edges: 1 always, 0 never, -1 (default)
                        when the mean projected edge is long enough to see */
} vm_report_view;

vm_report_view vm_report_view_default(void);

/* The triangles and quads of m (volume elements are ignored), flat-shaded
 * (Lambert, two-sided, light from the viewer's upper left) times a
 * colormap of `field`: a per-vertex (averaged over each face) or
 * per-element field, component 0; f64 or i32. field NULL: the scaled
 * Jacobian of each face. The colour range is the 2nd to 98th percentile of
 * the values (symmetric around 0 with a diverging map when they change
 * sign), shown in a colour bar. Faces are painted back to front (depth
 * sort, ties broken by face index). VM_ERR_ARG if the field is absent or
 * there are no 2D elements. view may be NULL (defaults). */
int vm_report_surface(vm_report *r, const char *name, const char *caption, const vm_mesh *m,
                      const char *field, const vm_report_view *view);

/* A slice through the volume elements of m by the plane x[axis] = value
 * (axis 0, 1, 2; value NaN: the middle of the bounding box). Each element
 * the plane crosses is cut along its edges (a vertex on the plane counts as
 * above it, so a plane through a layer of vertices shows the faces below
 * it exactly once); the cut polygons are filled in element order, coloured
 * by `field` (a per-element field, e.g. "layer", or a per-vertex field
 * interpolated at the cut points and averaged) or, field NULL, by the
 * element's scaled Jacobian (red: inverted, yellow: degenerate, blue:
 * ideal), with their edges drawn. VM_ERR_ARG if the field is absent or
 * there are no volume elements; a plane that misses the mesh draws an
 * empty frame. */
int vm_report_slice(vm_report *r, const char *name, const char *caption, const vm_mesh *m, int axis,
                    double value, const char *field);

/* The same in a window: only [wlo, whi] along the two in-plane axes is
 * drawn (the cells crossing its border cut at it). wlo, whi NULL: the
 * whole bounding box, as vm_report_slice. */
int vm_report_slice_window(vm_report *r, const char *name, const char *caption, const vm_mesh *m,
                           int axis, double value, const char *field, const double wlo[3],
                           const double whi[3]);

/* The standard pictures of one mesh, named "<prefix>quality", "<prefix>slice",
 * "<prefix>surface": the rows of vm_report_quality_rows under `label`,
 * the histograms, a slice through the middle of the bounding box across its
 * longest side (z on ties) if there are volume elements (and the same slice
 * coloured by the element field "layer", "<prefix>slice-layer", if the mesh
 * has it: prism layers), for a mesh out to a far field (boundaries named
 * "wall" and "farfield") the same two zoomed on the wall ("<prefix>slice-near",
 * "<prefix>slice-near-layer"; a half model, its symmetry plane named in the
 * attribute VM_SYMMETRY_PLANE_ATTR, also the cells on that plane,
 * "<prefix>symmetry"), and a rendered
 * surface if there are triangles or quads in 3D, coloured by
 * `surface_field` (NULL: "mean_curvature_filtered" or else "mean_curvature"
 * if the mesh has it, else the scaled Jacobian). prefix may be "" or NULL. */
int vm_report_mesh(vm_report *r, const char *prefix, const char *label, const vm_mesh *m,
                   const vm_quality_opts *opts, const char *surface_field);

#ifdef __cplusplus
}
#endif
#endif
