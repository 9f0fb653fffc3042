/* surface/src/surface_run.c: the surface stage's pipeline (repair, uniform
 * remeshing, curvature, adaptation) behind one call, vm_surface_run. */
#include "varmesh/surface.h"

#include <stdlib.h>
#include <string.h>

#include "varmesh/features.h"
#include "varmesh/project.h"

vm_surface_opts vm_surface_opts_default(void) {
  vm_surface_opts o;
  memset(&o, 0, sizeof o);
  o.step = VM_SURFACE_ALL;
  o.repair = VM_SURFACE_AUTO;
  o.remesh = VM_SURFACE_AUTO;
  o.sliver_angle = 15;
  o.repair_opts = vm_repair_opts_default();
  o.remesh_opts = vm_remesh_opts_default();
  o.adapt = vm_adapt_opts_default();
  return o;
}

const char *vm_surface_step_name(vm_surface_step step) {
  static const char *const names[] = {"all", "repair", "remesh", "curvature", "adapt"};
  return (unsigned)step < 5 ? names[step] : "?";
}

static int cmp_u64(const void *a, const void *b) {
  uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
  return x < y ? -1 : x > y;
}

/* A border edge (an element side no other element shares) of a surface
 * mesh: 1 and its vertices, 0 if the surface is closed, VM_ERR_NOMEM. */
static int border_edge(vm_ctx *ctx, const vm_mesh *m, int32_t *a, int32_t *b) {
  size_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) n += (size_t)vm_elem_nverts(m->etype[e]);
  uint64_t *key = vm_alloc_array(ctx, n ? n : 1, sizeof *key);
  if (!key) return VM_ERR_NOMEM;
  n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    int k = vm_elem_nverts(m->etype[e]);
    const int32_t *c = m->conn + m->eoff[e];
    for (int i = 0; i < k; i++) {
      uint32_t p = (uint32_t)c[i], q = (uint32_t)c[(i + 1) % k];
      key[n++] = (uint64_t)(p < q ? p : q) << 32 | (p < q ? q : p);
    }
  }
  qsort(key, n, sizeof *key, cmp_u64);
  int found = 0;
  for (size_t i = 0; i < n && !found;) {
    size_t j = i;
    while (j + 1 < n && key[j + 1] == key[i]) j++;
    if (j == i) {
      *a = (int32_t)(key[i] >> 32);
      *b = (int32_t)(key[i] & 0xffffffffu);
      found = 1;
    }
    i = j + 1;
  }
  vm_free(ctx, key);
  return found;
}

static int repair(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *o, vm_surface_summary *s) {
  vm_repair_report *rr = &s->repair;
  int st = vm_surface_repair(m, &o->repair_opts, rr);
  if (st < 0) return st;
  s->repaired = 1;
  vm_log(ctx, VM_LOG_INFO,
         "repair: %lld vertices, %lld triangles; merged %lld points, removed %lld "
         "invalid/duplicate and %lld degenerate faces and %lld isolated vertices, reoriented "
         "%lld faces, stitched %lld edges; %s, %lld components%s",
         (long long)rr->nv, (long long)rr->nf, (long long)rr->merged_vertices,
         (long long)rr->removed_polygons, (long long)rr->removed_degenerate,
         (long long)rr->removed_isolated, (long long)rr->reoriented, (long long)rr->stitched,
         rr->border_edges ? "open" : "closed", (long long)rr->components,
         rr->self_intersections > 0 ? ", SELF-INTERSECTING" : "");
  return VM_OK;
}

/* Isotropic remeshing of m; *input keeps m as it was (the reference surface
 * of the adaptation). */
static int remesh(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *o, vm_surface_summary *s,
                  vm_mesh **input) {
  vm_remesh_opts mo = o->remesh_opts;
  if (mo.target_edge_length <= 0) mo.target_edge_length = vm_surface_mean_edge(m);
  s->nv_before_remesh = m->nv;
  vm_surface_features f;
  memset(&f, 0, sizeof f);
  int st = vm_mesh_clone(m, input);
  if (!st) st = vm_surface_detect_features(m, o->adapt.feature_angle, o->adapt.corner_angle, &f);
  if (!st) st = vm_surface_remesh(m, &f, &mo, o->adapt.corner_angle);
  vm_surface_features_free(ctx, &f);
  if (st < 0) return st;
  s->remeshed = 1;
  s->target_edge_length = mo.target_edge_length;
  vm_log(ctx, VM_LOG_INFO,
         "remesh: target edge length %g: %lld -> %lld vertices, smallest angle %.2f -> %.2f deg",
         mo.target_edge_length, (long long)s->nv_before_remesh, (long long)m->nv,
         s->min_angle_input, vm_surface_min_angle(m));
  return VM_OK;
}

/* The curvature fields alone, filtered as the adaptation would. */
static int curvature(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *o, vm_surface_summary *s) {
  double lo[3], hi[3], h = vm_surface_mean_edge(m), diag = vm_mesh_bounds(m, lo, hi);
  vm_curvature_filter f = o->adapt.filter;
  if (f.threshold < 0) f.threshold = -f.threshold / diag;
  if (f.cap < 0) f.cap = h > 0 ? -f.cap / h : 0;
  s->threshold = f.threshold;
  s->cap = f.cap;
  vm_curvature_stats *cs = &s->curvature_stats;
  int st = vm_surface_curvature(m, &f, cs);
  if (st < 0) return st;
  s->curvature = 1;
  vm_log(ctx, VM_LOG_INFO,
         "curvature: H in [%g, %g], mean |H| %g; filter: threshold %g, cap %g, %d smoothing "
         "passes",
         cs->min, cs->max, cs->mean_abs, f.threshold, f.cap, f.smooth);
  return VM_OK;
}

/* Adapt m to the curvature, its vertices kept on ref (and its feature
 * lines). */
static int adapt(vm_ctx *ctx, vm_mesh *m, const vm_mesh *ref, const vm_surface_opts *o,
                 vm_surface_summary *s) {
  /* without the repair nothing has checked that the surface is closed */
  int32_t ba, bb;
  int open = s->repaired || !o->repair_opts.require_closed ? 0 : border_edge(ctx, ref, &ba, &bb);
  if (open < 0) return open;
  if (open) {
    const double *p = ref->xyz + 3 * (int64_t)ba, *q = ref->xyz + 3 * (int64_t)bb;
    s->open = 1;
    return vm_error(ctx, VM_ERR_FORMAT,
                    "open surface: e.g. the border edge (%g, %g, %g)-(%g, %g, %g)", p[0], p[1],
                    p[2], q[0], q[1], q[2]);
  }
  vm_surface_features fin;
  memset(&fin, 0, sizeof fin);
  vm_surface_projector *proj = NULL;
  int st = vm_surface_detect_features(ref, o->adapt.feature_angle, o->adapt.corner_angle, &fin);
  if (!st) st = vm_surface_projector_create(ctx, ref, &fin, &proj);
  if (st >= 0) st = vm_surface_adapt(m, proj, &o->adapt, &s->adapt);
  vm_surface_projector_destroy(&proj);
  vm_surface_features_free(ctx, &fin);
  if (st < 0 && st != VM_ERR_INTERRUPTED) return st;
  s->adapted = 1;
  const vm_adapt_result *ar = &s->adapt;
  vm_log(ctx, VM_LOG_INFO,
         "adapt: %d iterations in %d rounds (%s), F %.8e -> %.8e; c %g, threshold %g, cap %g; "
         "%lld smooth, %lld feature-line vertices on %d lines, %lld fixed; smallest angle %.2f "
         "-> %.2f deg; %lld flipped; %.2f s%s",
         ar->iterations, ar->rounds, ar->stop, ar->F_initial, ar->F, ar->c, ar->threshold, ar->cap,
         (long long)ar->nsmooth, (long long)ar->nline_vertices, ar->nline, (long long)ar->nfixed,
         ar->min_angle_before, ar->min_angle_after, (long long)ar->flipped, ar->elapsed,
         ar->flipped > 0 ? "  -- FLIPPED ELEMENTS" : "");
  return st < 0 ? st : ar->flipped > 0 ? VM_WARN_INVERTED : VM_OK;
}

int vm_surface_run(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *opts,
                   vm_surface_summary *summary) {
  vm_surface_summary local;
  vm_surface_summary *s = summary ? summary : &local;
  memset(s, 0, sizeof *s);
  s->repair.self_intersections = -1;
  vm_surface_opts o = opts ? *opts : vm_surface_opts_default();
  int64_t counts[VM_NTYPES];
  if (!m || vm_mesh_count_types(m, counts) != 2 || m->dim != 3)
    return vm_error(ctx, VM_ERR_ARG,
                    "not a surface mesh in 3D (it needs triangles or quads "
                    "and nothing else)");
  if ((unsigned)o.step > VM_SURFACE_ADAPT)
    return vm_error(ctx, VM_ERR_ARG, "vm_surface_run: unknown step %d", (int)o.step);
  int do_repair = o.step == VM_SURFACE_REPAIR || o.repair == VM_SURFACE_YES ||
                  (o.repair == VM_SURFACE_AUTO &&
                   (o.soup || o.step == VM_SURFACE_ALL || o.step == VM_SURFACE_REMESH));
  int st = do_repair ? repair(ctx, m, &o, s) : VM_OK;
  if (st < 0) return st;
  /* the repair and the remeshing (CGAL) cannot stop half-way: an interrupt
   * during them ends the run after them, with the mesh they made */
  if (vm_ctx_interrupted(ctx)) return VM_ERR_INTERRUPTED;

  s->min_angle_input = vm_surface_min_angle(m);
  vm_mesh *input = NULL; /* before remeshing */
  if (o.step == VM_SURFACE_REMESH ||
      (o.step == VM_SURFACE_ALL &&
       (o.remesh == VM_SURFACE_YES ||
        (o.remesh == VM_SURFACE_AUTO && s->min_angle_input < o.sliver_angle))))
    st = remesh(ctx, m, &o, s, &input);
  if (st >= 0 && vm_ctx_interrupted(ctx)) st = VM_ERR_INTERRUPTED;
  if (st >= 0 && o.step == VM_SURFACE_CURVATURE) st = curvature(ctx, m, &o, s);
  if (st >= 0 && (o.step == VM_SURFACE_ALL || o.step == VM_SURFACE_ADAPT))
    st = adapt(ctx, m, input ? input : m, &o, s);
  vm_mesh_destroy(&input);
  return st;
}
