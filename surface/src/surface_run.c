/* surface/src/surface_run.c: the surface stage's pipeline (repair, uniform
 * remeshing, curvature, adaptation) behind one call, vm_surface_run. */
#include "varmesh/surface.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "varmesh/features.h"
#include "varmesh/project.h"
#include "varmesh/surface_mesh.h"
#include "vec3.h"

vm_surface_opts vm_surface_opts_default(void) {
  vm_surface_opts o;
  memset(&o, 0, sizeof o);
  o.step = VM_SURFACE_ALL;
  o.repair = VM_SURFACE_AUTO;
  o.remesh = VM_SURFACE_AUTO;
  o.sliver_angle = 15;
  o.needle_angle = 1;
  o.size = VM_SURFACE_SIZE_INPUT;
  o.cleanup_opts = vm_cleanup_opts_default();
  o.graded_opts = vm_graded_opts_default();
  o.repair_opts = vm_repair_opts_default();
  o.remesh_opts = vm_remesh_opts_default();
  o.adapt = vm_adapt_opts_default();
  o.ortho = vm_ortho2d_opts_default();
  o.wrap = -1;
  o.wrap_offset = VM_SURFACE_WRAP_OFFSET;
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

/* m replaced by its alpha wrap (vm_surface_wrap): alpha F times its
 * bounding box's diagonal, offset R times alpha; said on stderr. */
static int wrap(vm_ctx *ctx, vm_mesh *m, double F, double R, vm_surface_summary *s) {
  double lo[3], hi[3], diag = vm_mesh_bounds(m, lo, hi), alpha = F * diag;
  int nfields = m->nfield;
  int64_t flagged = 0;
  for (int64_t v = 0; m->vflag && v < m->nv; v++) flagged += m->vflag[v] != VM_VERTEX_FREE;
  int st = vm_surface_wrap(m, alpha, R * alpha, &s->wrap);
  if (st < 0) return st;
  s->wrapped = 1;
  vm_log(ctx, VM_LOG_INFO,
         "wrap: %lld faces wrapped in a closed surface of %lld triangles, %lld vertices (alpha "
         "%g, %g of the diagonal: gaps narrower than about twice that closed over; the wrap "
         "lies %g outside the input); %.2f s",
         (long long)s->wrap.nf_in, (long long)s->wrap.nf, (long long)s->wrap.nv, s->wrap.alpha, F,
         s->wrap.offset, s->wrap.elapsed);
  if (nfields > 0 || flagged > 0)
    vm_log(ctx, VM_LOG_WARN,
           "wrap: the input's %d fields and the flags of its %lld fixed or slip vertices are "
           "dropped (the wrap has new vertices and faces)",
           nfields, (long long)flagged);
  return VM_OK;
}

/* Is a model the repair refused for `why` wrapped instead (by default, a
 * non-manifold one, or one crossing itself where the union and the healing
 * were allowed and could not help: a user who turned either off asked for
 * the refusal)? */
static int wraps_refused(const vm_surface_opts *o, int why) {
  return o->wrap < 0 &&
         (why == VM_REPAIR_NONMANIFOLD ||
          (why == VM_REPAIR_CROSSING && o->repair_opts.union_overlaps && o->repair_opts.heal_self));
}

/* The repair; a model it refuses as not closable (open, non-manifold,
 * crossing itself) and not wrapped yet is wrapped instead where
 * wraps_refused says so (said on stderr; m is as it came after a
 * refusal) and repaired again, else the refusal's message names --wrap. */
static int repair(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *o, vm_surface_summary *s) {
  vm_repair_report *rr = &s->repair;
  int st = vm_surface_repair(m, &o->repair_opts, rr);
  int why = rr->refused;
  if (st == VM_ERR_FORMAT && !s->wrapped && m->ne > 0 &&
      (why == VM_REPAIR_OPEN || why == VM_REPAIR_NONMANIFOLD || why == VM_REPAIR_CROSSING)) {
    char msg[1024];
    snprintf(msg, sizeof msg, "%s", vm_ctx_error(ctx));
    if (why == VM_REPAIR_OPEN && s->symmetry.why[0]) {
      vm_error(ctx, st,
               "%s; not a half model either: %s (vm-surface --wrap 0.005 puts a closed surface "
               "around such a model)",
               msg, s->symmetry.why);
    } else if (!wraps_refused(o, why)) {
      vm_error(ctx, st, "%s (vm-surface --wrap 0.005 puts a closed surface around such a model)",
               msg);
    } else {
      vm_ctx_clear_error(ctx);
      vm_log(ctx, VM_LOG_WARN,
             "repair: %s; wrapping the model in a closed surface instead (--wrap F sets its "
             "detail, --wrap 0 refuses such a model)",
             msg);
      s->wrap_auto = 1;
      st = wrap(ctx, m, VM_SURFACE_WRAP_DEFAULT, o->wrap_offset, s);
      if (st >= 0) st = vm_surface_repair(m, &o->repair_opts, rr);
    }
  }
  if (st < 0) {
    s->open = rr->border_edges > 0;
    return st;
  }
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

static int all_triangles(const vm_mesh *m);
static int count_pairs(vm_mesh *m, int64_t *count, int32_t **pairs, double *where);

/* The features of m for the remeshing: by dihedral angle, cone points as
 * corners, and the borders between regions of its int element fields. */
static int features(vm_mesh *m, const vm_surface_opts *o, vm_surface_summary *s,
                    vm_surface_features *f) {
  return vm_surface_detect_features_cones(m, o->adapt.feature_angle, o->adapt.corner_angle,
                                          o->adapt.cone_angle, f, &s->cones);
}

/* The fields of `from` (the surface before a remeshing) onto m (after it;
 * m's own fields of those names replaced): an element's values are those
 * of the element of `from` closest to its centroid (with the region
 * borders kept as lines, the region it lies in); a vertex's F64 values are
 * interpolated linearly at its closest point of `from`; its I32 values
 * (flags, ids: not to be spread) those of the input vertex at exactly its
 * position (a kept corner), else 0. */
static int carry_fields(vm_ctx *ctx, vm_mesh *m, const vm_mesh *from) {
  if (from->nfield == 0) return VM_OK;
  vm_surface_projector *p = NULL;
  int64_t n = m->ne > m->nv ? m->ne : m->nv;
  double *pts = vm_alloc_array(ctx, 3 * (size_t)(n > 0 ? n : 1), sizeof *pts);
  int64_t *ce = vm_alloc_array(ctx, (size_t)(m->ne > 0 ? m->ne : 1), sizeof *ce);
  int64_t *cv = vm_alloc_array(ctx, (size_t)(m->nv > 0 ? m->nv : 1), sizeof *cv);
  double *tmp = vm_alloc_array(ctx, (size_t)(from->nv > 0 ? from->nv : 1), sizeof *tmp);
  double *out = vm_alloc_array(ctx, (size_t)(m->nv > 0 ? m->nv : 1), sizeof *out);
  int st = pts && ce && cv && tmp && out ? VM_OK : VM_ERR_NOMEM;
  if (!st) st = vm_surface_projector_create(ctx, from, NULL, &p);
  /* the closest element of every new element's centroid, and of every
   * new vertex */
  for (int64_t e = 0; !st && e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    int k = (int)(m->eoff[e + 1] - m->eoff[e]);
    double *q = pts + 3 * e;
    q[0] = q[1] = q[2] = 0;
    for (int i = 0; i < k; i++)
      for (int j = 0; j < 3; j++) q[j] += m->xyz[3 * (int64_t)c[i] + j] / k;
  }
  if (!st) st = vm_surface_projector_closest_element(p, m->ne, pts, ce);
  if (!st) st = vm_surface_projector_closest_element(p, m->nv, m->xyz, cv);
  for (int i = 0; !st && i < from->nfield; i++) {
    const vm_field *src = &from->fields[i];
    int vert = src->location == VM_FIELD_VERTEX, nc = src->ncomp;
    vm_mesh_remove_field(m, src->name, src->location);
    vm_field *dst = NULL;
    if ((st = vm_mesh_add_field(m, src->name, src->location, src->type, nc, &dst))) break;
    if (!vert) {
      size_t sz = (size_t)nc * (src->type == VM_FIELD_F64 ? sizeof(double) : sizeof(int32_t));
      for (int64_t e = 0; e < m->ne; e++) {
        if (ce[e] >= 0)
          memcpy((char *)dst->data + (size_t)e * sz, (const char *)src->data + (size_t)ce[e] * sz,
                 sz);
        else
          memset((char *)dst->data + (size_t)e * sz, 0, sz);
      }
    } else if (src->type == VM_FIELD_F64) {
      const double *sd = src->data;
      double *dd = dst->data;
      for (int j = 0; !st && j < nc; j++) {
        for (int64_t v = 0; v < from->nv; v++) tmp[v] = sd[(int64_t)nc * v + j];
        st = vm_surface_projector_interpolate(p, tmp, m->nv, m->xyz, out);
        for (int64_t v = 0; !st && v < m->nv; v++) dd[(int64_t)nc * v + j] = out[v];
      }
    } else {
      const int32_t *sd = src->data;
      int32_t *dd = dst->data;
      for (int64_t v = 0; v < m->nv; v++) {
        int32_t best = -1;
        double bd = INFINITY;
        if (cv[v] >= 0) {
          const int32_t *c = from->conn + from->eoff[cv[v]];
          int k = (int)(from->eoff[cv[v] + 1] - from->eoff[cv[v]]);
          for (int i2 = 0; i2 < k; i2++) {
            double d[3];
            vm_sub3(from->xyz + 3 * (int64_t)c[i2], m->xyz + 3 * v, d);
            double l = vm_dot3(d, d);
            if (l < bd) bd = l, best = c[i2];
          }
        }
        for (int j = 0; j < nc; j++)
          dd[(int64_t)nc * v + j] = best >= 0 && bd == 0 ? sd[(int64_t)nc * best + j] : 0;
      }
    }
  }
  vm_surface_projector_destroy(&p);
  vm_free(ctx, pts);
  vm_free(ctx, ce);
  vm_free(ctx, cv);
  vm_free(ctx, tmp);
  vm_free(ctx, out);
  return st;
}

/* Slivers removed by flips and collapses (f: m's features, updated). */
static int clean(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *o, vm_surface_summary *s,
                 vm_surface_features *f) {
  vm_cleanup_opts co = o->cleanup_opts;
  co.angle = o->sliver_angle < 59 ? o->sliver_angle : 59;
  /* a half model's border lies in its plane: collapsing along it keeps it there */
  co.border_collapse = s->symmetry.found;
  if (!all_triangles(m)) {
    vm_log(ctx, VM_LOG_INFO, "remesh: slivers not removed: the surface has quads");
    return VM_OK;
  }
  int st = vm_surface_cleanup(m, f, &co, &s->cleanup);
  if (st) return st;
  const vm_cleanup_report *c = &s->cleanup;
  s->cleaned = 1;
  char bc[64] = "";
  if (co.border_collapse)
    snprintf(bc, sizeof bc, " (%lld along the border)", (long long)c->border_collapses);
  vm_log(ctx, VM_LOG_INFO,
         "remesh: slivers: %lld flips, %lld collapses%s: %lld -> %lld vertices, %lld -> %lld "
         "triangles under %g deg; smallest angle %.2f -> %.2f deg (%.2f -> %.2f away from %lld "
         "feature corners, %lld of them cone points); surface moved <= %.3g",
         (long long)c->flips, (long long)c->collapses, bc, (long long)c->nv_in, (long long)c->nv,
         (long long)c->below_in, (long long)c->below, co.angle, c->min_angle_in, c->min_angle,
         c->min_angle_free_in, c->min_angle_free, (long long)f->ncorner, (long long)s->cones,
         c->max_dev);
  return VM_OK;
}

static int cmp_xyz(const void *a, const void *b) {
  const double *p = a, *q = b;
  for (int r = 0; r < 3; r++)
    if (p[r] != q[r]) return p[r] < q[r] ? -1 : 1;
  return 0;
}

/* How many of the n points (3 n coordinates) are not vertices of m, bit
 * for bit; *first: the first of them. A negative status on failure. */
static int64_t lost_points(vm_ctx *ctx, const vm_mesh *m, const double *pts, int64_t n,
                           int64_t *first) {
  double *sorted = vm_alloc_array(ctx, 3 * (size_t)(m->nv > 0 ? m->nv : 1), sizeof *sorted);
  if (!sorted) return VM_ERR_NOMEM;
  memcpy(sorted, m->xyz, 3 * (size_t)m->nv * sizeof *sorted);
  qsort(sorted, (size_t)m->nv, 3 * sizeof *sorted, cmp_xyz);
  int64_t lost = 0;
  for (int64_t i = 0; i < n; i++)
    if (!bsearch(pts + 3 * i, sorted, (size_t)m->nv, 3 * sizeof *sorted, cmp_xyz)) {
      if (!lost) *first = i;
      lost++;
    }
  vm_free(ctx, sorted);
  return lost;
}

/* vm_surface_count_opposing against the surface ref. */
static int64_t count_opposing(vm_ctx *ctx, const vm_mesh *m, const vm_mesh *ref, double at[3]) {
  vm_surface_projector *p = NULL;
  int st = vm_surface_projector_create(ctx, ref, NULL, &p);
  if (st) return st;
  int64_t k = vm_surface_count_opposing(m, p, at);
  vm_surface_projector_destroy(&p);
  return k;
}

/* The local deviation of m from ref (the summary's deviation_* figures,
 * cone points as corners by o's angles); pr: a projector onto ref. */
static int deviation(vm_ctx *ctx, const vm_mesh *m, const vm_mesh *ref, vm_surface_projector *pr,
                     const vm_surface_opts *o, vm_surface_summary *s) {
  const int64_t nv = ref->nv;
  vm_surface_features f;
  memset(&f, 0, sizeof f);
  vm_surface_projector *pm = NULL;
  double *h = vm_calloc(ctx, (size_t)(nv > 0 ? nv : 1), sizeof *h);
  int32_t *deg = vm_calloc(ctx, (size_t)(nv > 0 ? nv : 1), sizeof *deg);
  double *dist = vm_alloc_array(ctx, (size_t)(nv > 0 ? nv : 1), sizeof *dist);
  double *ctr = vm_alloc_array(ctx, 3 * (size_t)(m->ne > 0 ? m->ne : 1), sizeof *ctr);
  double *cd = vm_alloc_array(ctx, (size_t)(m->ne > 0 ? m->ne : 1), sizeof *cd);
  double *clen = vm_alloc_array(ctx, (size_t)(m->ne > 0 ? m->ne : 1), sizeof *clen);
  int st = h && deg && dist && ctr && cd && clen ? VM_OK : VM_ERR_NOMEM;
  int64_t ncones = 0;
  if (!st)
    st = vm_surface_detect_features_cones(ref, o->adapt.feature_angle, o->adapt.corner_angle,
                                          o->adapt.cone_angle, &f, &ncones);
  if (!st) st = vm_surface_projector_create(ctx, m, NULL, &pm);
  if (st) goto done;
  /* the local size: each element edge counted from both of its elements
   * (every edge of a closed surface twice, so the mean is unchanged) */
  for (int64_t e = 0; e < ref->ne; e++) {
    const int32_t *c = ref->conn + ref->eoff[e];
    int k = (int)(ref->eoff[e + 1] - ref->eoff[e]);
    for (int i = 0; i < k; i++) {
      int32_t a = c[i], b = c[(i + 1) % k];
      double d[3];
      vm_sub3(ref->xyz + 3 * (int64_t)b, ref->xyz + 3 * (int64_t)a, d);
      double l = vm_norm3(d);
      h[a] += l;
      h[b] += l;
      deg[a]++;
      deg[b]++;
    }
  }
  if ((st = vm_surface_projector_distance(pm, nv, ref->xyz, dist))) goto done;
  for (int64_t e = 0; e < m->ne; e++) {
    const int32_t *c = m->conn + m->eoff[e];
    int k = (int)(m->eoff[e + 1] - m->eoff[e]);
    double *q = ctr + 3 * e, len = 0;
    q[0] = q[1] = q[2] = 0;
    for (int i = 0; i < k; i++) {
      const double *a = m->xyz + 3 * (int64_t)c[i], *b = m->xyz + 3 * (int64_t)c[(i + 1) % k];
      double d[3];
      vm_sub3(b, a, d);
      len += vm_norm3(d) / k;
      for (int j = 0; j < 3; j++) q[j] += a[j] / k;
    }
    clen[e] = len;
  }
  if ((st = vm_surface_projector_distance(pr, m->ne, ctr, cd))) goto done;
  s->deviation_measured = 1;
  s->deviation_features = 0;
  s->corners_moved = 0;
  for (int64_t v = 0; v < nv; v++) {
    if (!deg[v]) continue;
    double hv = h[v] / deg[v], r = hv > 0 ? dist[v] / hv : 0;
    const double *p = ref->xyz + 3 * v;
    if (r > s->deviation_rel) {
      s->deviation_rel = r;
      memcpy(s->deviation_at, p, sizeof s->deviation_at);
    }
    if (dist[v] > s->deviation_abs) s->deviation_abs = dist[v];
    if (f.vclass[v] == VM_FEATURE_SMOOTH) continue;
    s->deviation_features++;
    if (r > s->deviation_feature_rel || s->deviation_features == 1) {
      if (r > s->deviation_feature_rel) s->deviation_feature_rel = r;
      memcpy(s->deviation_feature_at, p, sizeof s->deviation_feature_at);
    }
    if (dist[v] > s->deviation_feature_abs) s->deviation_feature_abs = dist[v];
  }
  for (int64_t e = 0; e < m->ne; e++) {
    double r = clen[e] > 0 ? cd[e] / clen[e] : 0;
    if (r > s->deviation_rel) {
      s->deviation_rel = r;
      memcpy(s->deviation_at, ctr + 3 * e, sizeof s->deviation_at);
    }
    if (cd[e] > s->deviation_abs) s->deviation_abs = cd[e];
  }
  /* corners and cone points: still vertices, bit for bit */
  {
    double *pts = vm_alloc_array(ctx, 3 * (size_t)(f.ncorner + 1), sizeof *pts);
    int64_t n = 0, first = -1;
    if (!pts) {
      st = VM_ERR_NOMEM;
      goto done;
    }
    for (int64_t v = 0; v < nv && n < f.ncorner; v++)
      if (f.vclass[v] == VM_FEATURE_CORNER)
        memcpy(pts + 3 * n++, ref->xyz + 3 * v, 3 * sizeof *pts);
    int64_t lost = lost_points(ctx, m, pts, n, &first);
    vm_free(ctx, pts);
    if (lost < 0)
      st = (int)lost;
    else
      s->corners_moved = lost;
  }
done:
  vm_surface_projector_destroy(&pm);
  vm_surface_features_free(ctx, &f);
  vm_free(ctx, h);
  vm_free(ctx, deg);
  vm_free(ctx, dist);
  vm_free(ctx, ctr);
  vm_free(ctx, cd);
  vm_free(ctx, clen);
  return st;
}

/* The remeshing step: with size INPUT the input's own vertices, slivers
 * removed by flips and collapses; with size UNIFORM CGAL's isotropic
 * remeshing first, then the same. Features, and cone points as corners,
 * are kept. *input keeps m as it was (the reference surface of the
 * adaptation). */
static int remesh_as(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *o, vm_surface_summary *s,
                     vm_mesh **input) {
  vm_remesh_opts mo = o->remesh_opts;
  int uniform = o->size == VM_SURFACE_SIZE_UNIFORM;
  int graded = o->size == VM_SURFACE_SIZE_GRADED || o->size == VM_SURFACE_SIZE_CURVATURE;
  const char *how = o->size == VM_SURFACE_SIZE_CURVATURE ? "curvature-sized"
                    : graded                             ? "graded"
                                                         : "uniform";
  vm_graded_opts go = o->graded_opts;
  go.sizing = o->size == VM_SURFACE_SIZE_CURVATURE ? VM_GRADED_CURVATURE : VM_GRADED_INPUT;
  if (o->triangles > 0) go.triangles = o->triangles;
  if (uniform && mo.target_edge_length <= 0 && o->triangles > 0) {
    /* equilateral triangles of edge L cover the area A with A / (sqrt(3)/4 L^2) */
    double area = 0;
    for (int64_t e = 0; e < m->ne; e++) area += vm_surface_elem_area(m, m->xyz, e);
    mo.target_edge_length = sqrt(area / (0.4330127018922193 * (double)o->triangles));
  }
  if (uniform && mo.target_edge_length <= 0) mo.target_edge_length = vm_surface_mean_edge(m);
  s->nv_before_remesh = m->nv;
  vm_surface_features f;
  memset(&f, 0, sizeof f);
  vm_mesh *m2 = NULL;
  int st = vm_mesh_clone(m, input);
  if (!st) st = features(m, o, s, &f);
  double *keep = NULL; /* the corners' coordinates: the remeshing must keep them */
  int64_t nkeep = 0;
  if (!st && (uniform || graded) && !all_triangles(m)) {
    vm_log(ctx, VM_LOG_WARN, "remesh: the surface has quads: no %s remeshing", how);
    uniform = graded = 0;
  }
  if (!st && (uniform || graded)) {
    keep = vm_alloc_array(ctx, 3 * (size_t)(f.ncorner + 1), sizeof *keep);
    if (!keep) st = VM_ERR_NOMEM;
    for (int64_t v = 0; !st && v < m->nv; v++)
      if (f.vclass[v] == VM_FEATURE_CORNER && nkeep < f.ncorner)
        memcpy(keep + 3 * nkeep++, m->xyz + 3 * v, 3 * sizeof *keep);
  }
  if (!st && (uniform || graded)) {
    /* the fields are carried from *input afterwards (carry_fields), not
     * dropped or zeroed by the remeshers */
    while (!st && m->nfield > 0)
      st = vm_mesh_remove_field(m, m->fields[0].name, m->fields[0].location);
    if (!st)
      st = graded ? vm_surface_remesh_graded(m, &f, &go, &s->graded)
                  : vm_surface_remesh(m, &f, &mo, o->adapt.corner_angle);
    /* CGAL 5.5 can collapse a constrained tip, fold a triangle over where
     * details are far smaller than the edge length, or make the surface
     * intersect itself: the input's own vertices then */
    int64_t lost = 0, first = -1, opposing = 0, pairs = 0, pairs0 = 0;
    double at[3] = {0, 0, 0};
    if (!st) lost = lost_points(ctx, m, keep, nkeep, &first);
    if (lost < 0) st = (int)lost;
    if (!st && lost == 0) opposing = count_opposing(ctx, m, *input, at);
    if (opposing < 0) st = (int)opposing;
    if (!st && lost == 0 && opposing == 0 && all_triangles(*input)) {
      st = count_pairs(m, &pairs, NULL, at);
      if (st >= 0 && pairs > 0) st = count_pairs(*input, &pairs0, NULL, NULL);
      if (pairs <= pairs0) pairs = 0;
    }
    if (!st && (lost > 0 || opposing > 0 || pairs > 0)) {
      const double *p = lost > 0 ? keep + 3 * first : at;
      char why[128];
      if (lost > 0)
        snprintf(why, sizeof why, "lost %lld of %lld corners and tips, e.g. at", (long long)lost,
                 (long long)nkeep);
      else if (opposing > 0)
        snprintf(why, sizeof why, "turned %lld triangles over against the input (folds), e.g. near",
                 (long long)opposing);
      else
        snprintf(why, sizeof why, "intersects itself (%lld triangle pairs), e.g. near",
                 (long long)pairs);
      vm_log(ctx, VM_LOG_WARN,
             "remesh: the %s remeshing %s (%g, %g, %g); going on with the input's own "
             "vertices (--size input)",
             how, why, p[0], p[1], p[2]);
      s->remesh_lost_corners = lost;
      s->remesh_opposing = opposing;
      s->remesh_refused = pairs;
      vm_surface_features_free(ctx, &f);
      vm_mesh_destroy(&m2);
      st = vm_mesh_clone(*input, &m2);
      if (!st) {
        vm_mesh tmp = *m;
        *m = *m2;
        *m2 = tmp;
        st = features(m, o, s, &f);
      }
      uniform = graded = 0;
    }
    if (!st && graded) {
      const vm_graded_report *g = &s->graded;
      s->remeshed = 1;
      vm_log(ctx, VM_LOG_INFO,
             "remesh: %s, sizes %g to %g: %lld -> %lld vertices (%lld splits, %lld "
             "collapses, %lld flips, %lld moves), smallest angle %.2f -> %.2f deg (%.2f -> %.2f "
             "away from feature corners)",
             how, g->h_min, g->h_max, (long long)g->nv_in, (long long)g->nv, (long long)g->splits,
             (long long)g->collapses, (long long)g->flips, (long long)g->moves, g->min_angle_in,
             g->min_angle, g->min_angle_free_in, g->min_angle_free);
    }
    if (!st && uniform) {
      s->remeshed = 1;
      s->target_edge_length = mo.target_edge_length;
      vm_log(ctx, VM_LOG_INFO,
             "remesh: uniform, target edge length %g: %lld -> %lld vertices, smallest angle "
             "%.2f -> %.2f deg",
             mo.target_edge_length, (long long)s->nv_before_remesh, (long long)m->nv,
             s->min_angle_input, vm_surface_min_angle(m));
    }
  }
  if (!st && (uniform || graded)) st = carry_fields(ctx, m, *input);
  if (!st && vm_ctx_interrupted(ctx)) st = VM_ERR_INTERRUPTED;
  if (!st) st = clean(ctx, m, o, s, &f);
  vm_surface_features_free(ctx, &f);
  vm_free(ctx, keep);
  vm_mesh_destroy(&m2);
  return st < 0 ? st : VM_OK;
}

/* Triangles of m under deg degrees. */
static int64_t needles(const vm_mesh *m, double deg) {
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) n += vm_surface_elem_min_angle(m, m->xyz, e) < deg;
  return n;
}

/* The remeshing step (remesh_as); with size INPUT, where the sliver
 * removal leaves needles (o->needle_angle), the repaired input remeshed to
 * sizes from the curvature instead, to about the number of triangles the
 * sliver removal left (o->triangles if given):
 * isotropic triangles where the input had rows of needles, which a prism
 * layer cannot stand on (a CAD-graded wing's trailing edge). */
static int remesh(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *o, vm_surface_summary *s,
                  vm_mesh **input) {
  int st = remesh_as(ctx, m, o, s, input);
  s->size_used = s->remeshed ? o->size : VM_SURFACE_SIZE_INPUT;
  if (st < 0 || o->size != VM_SURFACE_SIZE_INPUT || !(o->needle_angle > 0) || !all_triangles(m))
    return st;
  s->needles_in = needles(m, o->needle_angle);
  if (s->needles_in == 0) return st;
  vm_log(ctx, VM_LOG_INFO,
         "remesh: %lld triangles under %g deg are left after the sliver removal (needles it "
         "cannot remove without moving the surface); remeshing the input to sizes from its "
         "curvature instead (--size input keeps its own vertices)",
         (long long)s->needles_in, o->needle_angle);
  /* as many triangles as the sliver removal left, unless a count was asked
   * for: no more than the input's own vertices would have given */
  int64_t count = o->triangles > 0 ? o->triangles : m->ne;
  vm_mesh *again = NULL, *in2 = NULL;
  st = vm_mesh_clone(*input, &again);
  if (st) return st;
  vm_mesh tmp = *m;
  *m = *again;
  *again = tmp;
  vm_mesh_destroy(&again);
  vm_surface_opts o2 = *o;
  o2.size = VM_SURFACE_SIZE_CURVATURE;
  o2.triangles = count;
  s->cleaned = 0;
  memset(&s->cleanup, 0, sizeof s->cleanup);
  st = remesh_as(ctx, m, &o2, s, &in2);
  vm_mesh_destroy(&in2);
  s->size_used = s->remeshed ? VM_SURFACE_SIZE_CURVATURE : VM_SURFACE_SIZE_INPUT;
  return st;
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

/* The projector onto ref and its features by o->adapt's angles (copied
 * by the projector): the surface the adaptation and the orthogonality
 * relief keep the vertices on. The input's corners and cone points stay
 * fixed wherever they are vertices (vm_surface_projector_assign), also
 * where the sliver removal left one smooth on the mesh. */
static int ref_projector(vm_ctx *ctx, const vm_mesh *ref, const vm_surface_opts *o,
                         vm_surface_projector **proj) {
  vm_surface_features f;
  memset(&f, 0, sizeof f);
  int st = vm_surface_detect_features_cones(ref, o->adapt.feature_angle, o->adapt.corner_angle,
                                            o->adapt.cone_angle, &f, NULL);
  if (!st) st = vm_surface_projector_create(ctx, ref, &f, proj);
  vm_surface_features_free(ctx, &f);
  return st;
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
                    "open surface: e.g. the border edge (%g, %g, %g)-(%g, %g, %g)%s%s", p[0], p[1],
                    p[2], q[0], q[1], q[2], s->symmetry.why[0] ? "; not a half model either: " : "",
                    s->symmetry.why);
  }
  vm_surface_projector *proj = NULL;
  int st = ref_projector(ctx, ref, o, &proj);
  if (st >= 0) st = vm_surface_adapt(m, proj, &o->adapt, &s->adapt);
  vm_surface_projector_destroy(&proj);
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

/* Is m made of triangles only (what the exact self-intersection test takes)? */
static int all_triangles(const vm_mesh *m) {
  for (int64_t e = 0; e < m->ne; e++)
    if (m->etype[e] != VM_TRI) return 0;
  return m->ne > 0;
}

/* Exact count of m's intersecting triangle pairs (vm_surface_self_intersections)
 * and, if where != NULL, a point of the first pair (the first triangle's
 * centroid). */
static int count_pairs(vm_mesh *m, int64_t *count, int32_t **pairs, double *where) {
  int32_t *pp = NULL;
  int st = vm_surface_self_intersections(m, count, &pp);
  if (st < 0) return st;
  if (where && *count > 0) {
    const int32_t *c = m->conn + m->eoff[pp[0]];
    for (int r = 0; r < 3; r++)
      where[r] = (m->xyz[3 * (int64_t)c[0] + r] + m->xyz[3 * (int64_t)c[1] + r] +
                  m->xyz[3 * (int64_t)c[2] + r]) /
                 3;
  }
  if (pairs)
    *pairs = pp;
  else
    vm_free(m->ctx, pp);
  return VM_OK;
}

/* Signed doubled-area normal of 2D element e at x. */
static void elem_normal(const vm_mesh *m, const double *x, int64_t e, double n[3]) {
  int k = vm_elem_nverts(m->etype[e]);
  const int32_t *c = m->conn + m->eoff[e];
  n[0] = n[1] = n[2] = 0;
  for (int a = 0; a < k; a++) {
    double cr[3];
    vm_cross3(x + 3 * (int64_t)c[a], x + 3 * (int64_t)c[(a + 1) % k], cr);
    for (int r = 0; r < 3; r++) n[r] += cr[r];
  }
}

/* Elements of m whose orientation reversed against x0 (their normals at
 * m->xyz and at x0 meet at 90 degrees or more); their vertices are marked
 * in mark if it is not NULL. */
static int64_t reversed(const vm_mesh *m, const double *x0, uint8_t *mark) {
  int64_t n = 0;
  for (int64_t e = 0; e < m->ne; e++) {
    double a[3], b[3];
    elem_normal(m, m->xyz, e, a);
    elem_normal(m, x0, e, b);
    if (vm_dot3(a, b) > 0) continue;
    n++;
    if (!mark) continue;
    const int32_t *c = m->conn + m->eoff[e];
    for (int k = 0; k < vm_elem_nverts(m->etype[e]); k++) mark[c[k]] = 1;
  }
  return n;
}

/* vm_surface_unfold (surface.h): rounds of 1, 2, 4, 8, 16 and 32 rings,
 * then the whole surface. */
int vm_surface_unfold(vm_mesh *m, const double *x0, vm_surface_summary *s) {
  if (!m || !x0 || !s) return VM_ERR_ARG;
  vm_ctx *ctx = m->ctx;
  s->self_intersections = -1;
  if (!all_triangles(m)) return VM_OK;
  int64_t n = 0, nv = m->nv;
  int32_t *pairs = NULL;
  int st = count_pairs(m, &n, &pairs, s->fold_at);
  if (st < 0) return st;
  int64_t flipped = reversed(m, x0, NULL);
  s->self_intersections = n;
  /* what the caller's summary said of the surface before (the adaptation's
   * own count of flipped elements, which keep_angles may have taken back
   * already) is replaced by what is left */
  s->adapt.flipped = flipped;
  s->folds_found = n;
  s->adapt_backed_off = 0;
  if (n == 0 && flipped == 0) {
    vm_free(ctx, pairs);
    return VM_OK;
  }
  /* the surface before: is it free of pairs itself? */
  vm_mesh *before = NULL;
  int64_t n0 = 0;
  st = vm_mesh_clone(m, &before);
  if (!st) memcpy(before->xyz, x0, 3 * (size_t)nv * sizeof *x0);
  if (!st) st = count_pairs(before, &n0, NULL, NULL);
  vm_mesh_destroy(&before);
  if (st < 0 || n0 > 0) {
    vm_free(ctx, pairs);
    return st;
  }
  uint8_t *mark = vm_calloc(ctx, (size_t)(nv > 0 ? nv : 1), sizeof *mark);
  uint8_t *next = vm_calloc(ctx, (size_t)(nv > 0 ? nv : 1), sizeof *next);
  if (!mark || !next) {
    vm_free(ctx, mark);
    vm_free(ctx, next);
    vm_free(ctx, pairs);
    return VM_ERR_NOMEM;
  }
  static const int rings[] = {1, 2, 4, 8, 16, 32};
  const int nround = (int)(sizeof rings / sizeof *rings);
  for (int round = 0; round < nround && (n > 0 || flipped > 0); round++) {
    /* seeds: the offending elements' vertices */
    for (int64_t i = 0; i < 2 * n; i++) {
      const int32_t *c = m->conn + m->eoff[pairs[i]];
      for (int a = 0; a < 3; a++) mark[c[a]] = 1;
    }
    reversed(m, x0, mark);
    /* rings of neighbours, through the elements */
    for (int r = 0; r < rings[round]; r++) {
      memcpy(next, mark, (size_t)nv);
      for (int64_t e = 0; e < m->ne; e++) {
        const int32_t *c = m->conn + m->eoff[e];
        int k = vm_elem_nverts(m->etype[e]), any = 0;
        for (int a = 0; a < k; a++) any |= mark[c[a]];
        if (any)
          for (int a = 0; a < k; a++) next[c[a]] = 1;
      }
      memcpy(mark, next, (size_t)nv);
    }
    for (int64_t v = 0; v < nv; v++)
      if (mark[v]) memcpy(m->xyz + 3 * v, x0 + 3 * v, 3 * sizeof *x0);
    vm_free(ctx, pairs);
    pairs = NULL;
    if ((st = count_pairs(m, &n, &pairs, NULL)) < 0) break;
    flipped = reversed(m, x0, NULL);
  }
  /* the last resort: the surface before the adaptation, free of pairs
   * (checked above). Without it the aircraft at vm-gen's resolution 16
   * came out with 158 pairs and 40 reversed elements left after rounds of
   * up to 8 rings, written with a warning, and vm-prism refused it. */
  int64_t left = n, left_flipped = flipped;
  if (st >= 0 && (n > 0 || flipped > 0)) {
    memcpy(m->xyz, x0, 3 * (size_t)nv * sizeof *x0);
    memset(mark, 1, (size_t)nv);
    n = flipped = 0;
  }
  s->adapt_backed_off = 0;
  for (int64_t v = 0; v < nv; v++) s->adapt_backed_off += mark[v];
  s->self_intersections = n;
  s->adapt.flipped = flipped;
  vm_free(ctx, mark);
  vm_free(ctx, next);
  vm_free(ctx, pairs);
  if (st < 0) return st;
  if (left > 0 || left_flipped > 0)
    vm_log(ctx, VM_LOG_WARN,
           "adapt: the adapted surface folded (%lld intersecting triangle pairs, e.g. near "
           "(%g, %g, %g)) and putting back up to 63 rings around the folds left %lld pairs and "
           "%lld reversed elements: the adaptation is undone (every vertex where it was before "
           "it)",
           (long long)s->folds_found, s->fold_at[0], s->fold_at[1], s->fold_at[2], (long long)left,
           (long long)left_flipped);
  else
    vm_log(ctx, VM_LOG_INFO,
           "adapt: the adapted surface folded (%lld intersecting triangle pairs, e.g. near "
           "(%g, %g, %g)); %lld vertices put back where they were before the adaptation",
           (long long)s->folds_found, s->fold_at[0], s->fold_at[1], s->fold_at[2],
           (long long)s->adapt_backed_off);
  return VM_OK;
}

/* The adaptation may not make the smallest angle worse than `floor`:
 * around the elements whose smallest angle fell below min(floor, their
 * own before), the adaptation's displacement (x - x0) is scaled down
 * smoothly: by 0 at their vertices, d / R at graph distance d < R, not
 * at all further away; R doubles (1, 2, 4, ..., 64) and the seeds
 * gather while elements are left below; then every vertex goes back to
 * x0. *restored: vertices whose displacement was scaled down. */
static int keep_angles(vm_mesh *m, const double *x0, double floor, int64_t *restored) {
  vm_ctx *ctx = m->ctx;
  const int64_t nv = m->nv;
  const size_t n1 = (size_t)(nv > 0 ? nv : 1);
  *restored = 0;
  uint8_t *seed = vm_calloc(ctx, n1, 1);
  int32_t *dist = vm_alloc_array(ctx, n1, sizeof *dist);
  double *xa = vm_alloc_array(ctx, 3 * n1, sizeof *xa);
  if (!seed || !dist || !xa) {
    vm_free(ctx, seed);
    vm_free(ctx, dist);
    vm_free(ctx, xa);
    return VM_ERR_NOMEM;
  }
  memcpy(xa, m->xyz, 3 * (size_t)nv * sizeof *xa);
  int R = 1, bad = 1;
  for (int round = 0; round < 9 && bad; round++) {
    bad = 0;
    for (int64_t e = 0; e < m->ne; e++) {
      if (vm_elem_dim(m->etype[e]) != 2) continue;
      double now = vm_surface_elem_min_angle(m, m->xyz, e);
      /* (rounding aside: 1e-9 degrees) */
      if (now >= floor - 1e-9 || now >= vm_surface_elem_min_angle(m, x0, e) - 1e-9) continue;
      bad++;
      const int32_t *c = m->conn + m->eoff[e];
      for (int a = 0; a < vm_elem_nverts(m->etype[e]); a++) seed[c[a]] = 1;
    }
    vm_log(ctx, VM_LOG_DEBUG, "adapt: angle guard round %d: %d elements below %.3f deg", round, bad,
           floor);
    if (!bad) break;
    if (round == 8) { /* the last resort: the surface before the adaptation */
      memcpy(m->xyz, x0, 3 * (size_t)nv * sizeof *x0);
      *restored = nv;
      break;
    }
    /* graph distance from the seeds, up to R, by sweeps over the elements */
    for (int64_t v = 0; v < nv; v++) dist[v] = seed[v] ? 0 : R;
    for (int d = 0; d + 1 < R; d++) {
      int grew = 0;
      for (int64_t e = 0; e < m->ne; e++) {
        const int32_t *c = m->conn + m->eoff[e];
        int k = vm_elem_nverts(m->etype[e]), near = 0;
        for (int a = 0; a < k; a++) near |= dist[c[a]] == d;
        if (near)
          for (int a = 0; a < k; a++)
            if (dist[c[a]] > d + 1) dist[c[a]] = d + 1, grew = 1;
      }
      if (!grew) break;
    }
    *restored = 0;
    for (int64_t v = 0; v < nv; v++) {
      double t = (double)dist[v] / R;
      if (t < 1) ++*restored;
      for (int r = 0; r < 3; r++)
        m->xyz[3 * v + r] =
            t >= 1 ? xa[3 * v + r] : x0[3 * v + r] + t * (xa[3 * v + r] - x0[3 * v + r]);
    }
    R *= 2;
  }
  vm_free(ctx, seed);
  vm_free(ctx, dist);
  vm_free(ctx, xa);
  return VM_OK;
}

/* The wall's finite-volume orthogonality relief (step all, last), its
 * vertices kept on ref (the surface before the adaptation) and its feature
 * lines; undone if the result intersects itself where the surface before
 * it did not. The curvature fields are measured again where it moved
 * vertices. */
static int ortho(vm_ctx *ctx, vm_mesh *m, const vm_mesh *ref, const vm_surface_opts *o,
                 vm_surface_summary *s) {
  vm_ortho2d_opts oo = o->ortho;
  oo.feature_angle = o->adapt.feature_angle;
  oo.corner_angle = o->adapt.corner_angle;
  oo.cone_angle = o->adapt.cone_angle;
  vm_surface_projector *proj = NULL;
  double *keep = vm_alloc_array(ctx, 3 * (size_t)(m->nv > 0 ? m->nv : 1), sizeof *keep);
  if (!keep) return VM_ERR_NOMEM;
  memcpy(keep, m->xyz, 3 * (size_t)m->nv * sizeof *keep);
  int st = ref_projector(ctx, ref, o, &proj);
  if (!st) st = vm_surface_ortho_relief(m, proj, &oo, &s->ortho);
  vm_surface_projector_destroy(&proj);
  if (st < 0 && st != VM_ERR_INTERRUPTED) {
    vm_free(ctx, keep);
    return st;
  }
  s->ortho_ran = 1;
  const vm_ortho2d_result *r = &s->ortho;
  if (r->moved > 0) {
    int64_t n = 0;
    int b = count_pairs(m, &n, NULL, NULL);
    if (b < 0) {
      vm_free(ctx, keep);
      return b;
    }
    if (n > (s->self_intersections > 0 ? s->self_intersections : 0)) {
      memcpy(m->xyz, keep, 3 * (size_t)m->nv * sizeof *keep);
      s->ortho_undone = 1;
      /* the figures say what the surface is: as before the relief */
      s->ortho.over70_after = s->ortho.over70_before;
      s->ortho.over60_after = s->ortho.over60_before;
      s->ortho.max_after = s->ortho.max_before;
      s->ortho.moved = 0;
      s->ortho.max_shift = 0;
      vm_log(ctx, VM_LOG_WARN,
             "ortho: the relieved surface intersects itself (%lld triangle pairs): the relief "
             "is undone",
             (long long)n);
    }
  }
  vm_free(ctx, keep);
  if (r->moved > 0 && (s->adapted || s->curvature)) {
    vm_curvature_filter f = o->adapt.filter;
    f.threshold = s->adapted ? s->adapt.threshold : s->threshold;
    f.cap = s->adapted ? s->adapt.cap : s->cap;
    int b = vm_surface_curvature(m, &f, NULL);
    if (b < 0) return b;
  }
  vm_log(ctx, VM_LOG_INFO,
         "ortho: wall edges beyond 70 degrees %lld -> %lld (beyond 60: %lld -> %lld) of %lld, "
         "largest %.1f -> %.1f deg; %lld steps in %d sweeps, %lld vertices moved (at most "
         "%.3g)%s; %.2f s",
         (long long)r->over70_before, (long long)r->over70_after, (long long)r->over60_before,
         (long long)r->over60_after, (long long)r->edges, r->max_before, r->max_after,
         (long long)r->moves, r->sweeps, (long long)r->moved, r->max_shift,
         s->ortho_undone ? " (undone)" : "", r->elapsed);
  return st;
}

/* The last step of every step: where the surface folds back on itself (no
 * direction sees every triangle at a vertex, so no prism column can stand
 * there) the folds are taken out by local collapses and flips
 * (vm_surface_unblind; undone if that makes triangles intersect). */
static int unblind(vm_ctx *ctx, vm_mesh *m, vm_surface_summary *s) {
  vm_unblind_report *r = &s->unblind;
  int st = vm_surface_unblind(m, NULL, r);
  /* not a manifold, consistently oriented surface (--repair no): the step
   * does not apply */
  if (st == VM_ERR_ARG) return VM_OK;
  if (st < 0) return st;
  if (r->caps_in > 0)
    vm_log(ctx, VM_LOG_WARN,
           "caps: %lld triangles with an angle within 0.1 degrees of 180 (their apex on their "
           "long edge); %lld flips of that edge %s %lld of them out%s",
           (long long)r->caps_in, (long long)r->cap_flips, r->undone ? "would have taken" : "took",
           (long long)(r->undone ? 0 : r->caps_in - r->caps),
           r->undone ? " (undone: the moves made triangles intersect)" : "");
  if (r->blind_in > 0)
    vm_log(ctx, VM_LOG_WARN,
           "folds: the surface folds back at %lld vertices (no direction sees every incident "
           "triangle there, e.g. at (%g, %g, %g)); %lld edge collapses and %lld flips %s %lld of "
           "them out, moving the surface by at most %g%s",
           (long long)r->blind_in, r->at_in[0], r->at_in[1], r->at_in[2], (long long)r->collapses,
           (long long)r->flips, r->undone ? "would have taken" : "took",
           (long long)(r->blind_in - r->blind), r->max_dev,
           r->undone ? " (undone: they made triangles intersect)" : "");
  return VM_OK;
}

/* A half model's plane "y=0" into buf. */
static const char *plane_name(const vm_surface_summary *s, char *buf, size_t n) {
  return vm_axis_plane_format(s->symmetry.axis, s->symmetry.value, buf, n);
}

/* A half model's border kept in its plane after the step `what`: border
 * vertices a step left off it by rounding (within the tolerance) put back
 * bit for bit; farther ones said (none expected: every step keeps the
 * border as a feature line). */
static int keep_plane(vm_ctx *ctx, vm_mesh *m, vm_surface_summary *s, const char *what) {
  if (!s->symmetry.found) return VM_OK;
  int64_t snapped = 0, off = 0;
  double drift = 0, at[3] = {0, 0, 0};
  int st = vm_symmetry_keep(m, s->symmetry.axis, s->symmetry.value, s->symmetry.tol, &snapped,
                            &drift, &off, at);
  if (st < 0) return st;
  s->symmetry_resnapped += snapped;
  if (drift > s->symmetry_drift) s->symmetry_drift = drift;
  if (snapped)
    vm_log(ctx, VM_LOG_DEBUG, "%s: %lld border vertices put back onto the symmetry plane (%g off)",
           what, (long long)snapped, drift);
  if (off) {
    char pl[64];
    vm_log(ctx, VM_LOG_WARN,
           "%s: %lld border vertices are off the symmetry plane %s by more than %.3g, e.g. (%g, "
           "%g, %g)",
           what, (long long)off, plane_name(s, pl, sizeof pl), s->symmetry.tol, at[0], at[1],
           at[2]);
  }
  return VM_OK;
}

/* A half model after the repair: its border still in the plane, and
 * facing away from the volume it bounds with the plane. */
static int half_after_repair(vm_ctx *ctx, vm_mesh *m, vm_surface_summary *s) {
  char pl[64];
  plane_name(s, pl, sizeof pl);
  int64_t off = 0;
  double at[3] = {0, 0, 0};
  int st = vm_symmetry_keep(m, s->symmetry.axis, s->symmetry.value, s->symmetry.tol, NULL, NULL,
                            &off, at);
  if (st < 0) return st;
  if (off)
    return vm_error(ctx, VM_ERR_FORMAT,
                    "half model (symmetry plane %s): after the repair %lld border vertices are off "
                    "the plane, e.g. (%g, %g, %g): the repair removed faces along the border",
                    pl, (long long)off, at[0], at[1], at[2]);
  if (vm_symmetry_half_volume(m, s->symmetry.axis, s->symmetry.value) < 0) {
    for (int64_t e = 0; e < m->ne; e++) {
      int32_t *c = m->conn + m->eoff[e];
      int k = (int)(m->eoff[e + 1] - m->eoff[e]);
      for (int i = 1, j = k - 1; i < j; i++, j--) {
        int32_t t = c[i];
        c[i] = c[j];
        c[j] = t;
      }
    }
    s->symmetry_reoriented = 1;
    vm_log(ctx, VM_LOG_INFO,
           "symmetry plane %s: the half model faced into the volume it bounds with the plane: "
           "every face turned over",
           pl);
  }
  return VM_OK;
}

static int run(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *opts, vm_surface_summary *summary) {
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
  if (!(o.wrap_offset > 0 && o.wrap_offset <= 1))
    return vm_error(ctx, VM_ERR_ARG, "vm_surface_run: wrap offset %g is not in (0, 1]",
                    o.wrap_offset);
  int do_repair = o.step == VM_SURFACE_REPAIR || o.repair == VM_SURFACE_YES ||
                  (o.repair == VM_SURFACE_AUTO &&
                   (o.soup || o.step == VM_SURFACE_ALL || o.step == VM_SURFACE_REMESH));
  /* a half model: its border open, in the plane, through every step */
  int st = vm_symmetry_detect(m, &o.symmetry, &s->symmetry);
  if (st < 0) return st;
  if (s->symmetry.found) {
    const vm_symmetry_report *y = &s->symmetry;
    char pl[64];
    plane_name(s, pl, sizeof pl);
    if (o.wrap > 0)
      return vm_error(ctx, VM_ERR_ARG,
                      "a half model (symmetry plane %s) is not wrapped: the wrap would close its "
                      "border in the plane",
                      pl);
    o.wrap = 0;
    o.repair_opts.require_closed = 0;
    vm_log(ctx, VM_LOG_INFO,
           "symmetry plane %s (%s): a half model, %lld border edges in %lld loops, the wall on "
           "its %s side; %lld border vertices put onto it exactly (at most %.3g off; tolerance "
           "%.3g)",
           pl,
           y->given == 1   ? "given"
           : y->given == 2 ? "the input's attribute " VM_SYMMETRY_PLANE_ATTR
                           : "found: every border vertex lies in it",
           (long long)y->border_edges, (long long)y->loops, y->side > 0 ? "+" : "-",
           (long long)y->snapped, y->max_offset, y->tol);
  }
  st = o.wrap > 0 ? wrap(ctx, m, o.wrap, o.wrap_offset, s) : VM_OK;
  if (st >= 0 && do_repair) st = repair(ctx, m, &o, s);
  if (st >= 0 && s->symmetry.found) st = half_after_repair(ctx, m, s);
  if (st < 0) return st;
  /* the repair and the remeshing (CGAL) cannot stop half-way: an interrupt
   * during them ends the run after them, with the mesh they made */
  if (vm_ctx_interrupted(ctx)) return VM_ERR_INTERRUPTED;

  s->min_angle_input = vm_surface_min_angle(m);
  vm_mesh *input = NULL; /* before remeshing */
  s->self_intersections = -1;
  if (o.step == VM_SURFACE_REMESH ||
      (o.step == VM_SURFACE_ALL &&
       (o.remesh == VM_SURFACE_YES ||
        (o.remesh == VM_SURFACE_AUTO && s->min_angle_input < o.sliver_angle))))
    st = remesh(ctx, m, &o, s, &input);
  if (st >= 0 && vm_ctx_interrupted(ctx)) st = VM_ERR_INTERRUPTED;
  /* the remeshed surface checked exactly (the uniform remeshing has been
   * already): one that intersects itself is given up for the repaired
   * input, as the remeshing found it */
  if (st >= 0 && (s->remeshed || s->cleaned) && all_triangles(m) && all_triangles(input)) {
    int64_t n = 0, n0 = 0;
    int refused = 0;
    double at[3] = {0, 0, 0};
    st = count_pairs(m, &n, NULL, at);
    if (st >= 0 && n > 0) st = count_pairs(input, &n0, NULL, NULL);
    if (st >= 0 && n > n0) {
      vm_log(ctx, VM_LOG_WARN,
             "remesh: the remeshed surface intersects itself (%lld triangle pairs, e.g. near "
             "(%g, %g, %g)); going on with the repaired input instead",
             (long long)n, at[0], at[1], at[2]);
      vm_mesh tmp = *m;
      *m = *input;
      *input = tmp;
      vm_mesh_destroy(&input);
      s->remeshed = 0;
      s->cleaned = 0;
      s->remesh_refused = n;
      refused = 1;
    }
    if (st >= 0) s->self_intersections = refused ? n0 : n;
  }
  if (st >= 0) st = keep_plane(ctx, m, s, "remesh");
  double *x0 = NULL;
  if (st >= 0 && (o.step == VM_SURFACE_ALL || o.step == VM_SURFACE_ADAPT)) {
    x0 = vm_alloc_array(ctx, 3 * (size_t)(m->nv > 0 ? m->nv : 1), sizeof *x0);
    if (!x0) st = VM_ERR_NOMEM;
    if (x0) memcpy(x0, m->xyz, 3 * (size_t)m->nv * sizeof *x0);
  }
  /* a graded or curvature-sized remeshing has sized the triangles
   * already: the adaptation's own sizing would fight it (on the demo
   * aircraft it folded the wing), so step all stops at the curvature
   * fields; the step adapt runs it on any surface */
  int sized = o.step == VM_SURFACE_ALL && s->remeshed &&
              (s->size_used == VM_SURFACE_SIZE_GRADED || s->size_used == VM_SURFACE_SIZE_CURVATURE);
  if (sized)
    vm_log(ctx, VM_LOG_INFO,
           "adapt: not run: the %s remeshing sized the triangles (the step adapt runs it)",
           s->size_used == VM_SURFACE_SIZE_GRADED ? "graded" : "curvature-sized");
  if (st >= 0 && (o.step == VM_SURFACE_CURVATURE || sized)) st = curvature(ctx, m, &o, s);
  if (st >= 0 && !sized && (o.step == VM_SURFACE_ALL || o.step == VM_SURFACE_ADAPT))
    st = adapt(ctx, m, input ? input : m, &o, s);
  /* the adapted surface's angles: never below the smaller of the
   * surface's before the adaptation and 20 degrees where the adaptation
   * made them so; then checked exactly, folds taken back locally (and the
   * angles once more if that moved anything) */
  if ((st >= 0 || st == VM_ERR_INTERRUPTED) && s->adapted && x0) {
    double floor = s->adapt.min_angle_before < 20 ? s->adapt.min_angle_before : 20;
    int64_t r1 = 0, r2 = 0, flipped0 = s->adapt.flipped;
    int keep = st, b = keep_angles(m, x0, floor, &r1);
    if (b >= 0) b = vm_surface_unfold(m, x0, s);
    if (b >= 0 && s->adapt_backed_off > 0) b = keep_angles(m, x0, floor, &r2);
    s->angle_floor = floor;
    s->angle_restored = r1 > r2 ? r1 : r2;
    if (b < 0)
      st = b;
    else if (keep >= 0)
      st = s->self_intersections > 0 || s->adapt.flipped > 0 ? VM_WARN_INVERTED : VM_OK;
    if (b >= 0 && s->angle_restored > 0)
      vm_log(ctx, VM_LOG_INFO,
             "adapt: the displacement of %lld vertices scaled back where the adaptation made an "
             "angle smaller than "
             "%.2f deg; smallest angle now %.2f deg",
             (long long)s->angle_restored, floor, vm_surface_min_angle(m));
    if (b >= 0 && flipped0 > 0 && s->adapt.flipped == 0 && s->self_intersections == 0)
      vm_log(ctx, VM_LOG_INFO,
             "adapt: none of the %lld elements the adaptation flipped is left reversed, and no "
             "triangles intersect (checked exactly)",
             (long long)flipped0);
    if (b >= 0) b = keep_plane(ctx, m, s, "adapt");
    if (b < 0) st = b;
  }
  /* the wall made fit for a finite-volume layer: the last step of all,
   * its vertices on the surface before the adaptation */
  if (st >= 0 && o.step == VM_SURFACE_ALL && all_triangles(m)) {
    vm_mesh *tmp = NULL;
    int b = VM_OK;
    if (!input && x0) {
      b = vm_mesh_clone(m, &tmp);
      if (!b) memcpy(tmp->xyz, x0, 3 * (size_t)m->nv * sizeof *x0);
    }
    if (!b) b = ortho(ctx, m, input ? input : tmp ? tmp : m, &o, s);
    if (b >= 0) b = keep_plane(ctx, m, s, "ortho");
    vm_mesh_destroy(&tmp);
    if (b < 0) st = b;
  }
  /* and, independently, against the repaired input's normals */
  if (st >= 0 && all_triangles(m) && (input || x0)) {
    vm_mesh *ref = input;
    vm_mesh *tmp = NULL;
    int b = VM_OK;
    if (!ref) {
      b = vm_mesh_clone(m, &tmp);
      if (!b) memcpy(tmp->xyz, x0, 3 * (size_t)m->nv * sizeof *x0);
      ref = tmp;
    }
    /* one projector onto the input for both */
    double at[3] = {0, 0, 0};
    vm_surface_projector *pr = NULL;
    if (!b) b = vm_surface_projector_create(ctx, ref, NULL, &pr);
    int64_t k = b ? b : vm_surface_count_opposing(m, pr, at);
    if (k >= 0) {
      int d = deviation(ctx, m, ref, pr, &o, s);
      if (d < 0) k = d;
    }
    vm_surface_projector_destroy(&pr);
    if (k >= 0)
      vm_log(ctx, VM_LOG_INFO,
             "deviation from the input: at most %.3g of the local edge length (%.3g, near (%g, "
             "%g, %g)); at its %lld feature vertices %.3g (%.3g); corners and tips moved: %lld",
             s->deviation_rel, s->deviation_abs, s->deviation_at[0], s->deviation_at[1],
             s->deviation_at[2], (long long)s->deviation_features, s->deviation_feature_rel,
             s->deviation_feature_abs, (long long)s->corners_moved);
    vm_mesh_destroy(&tmp);
    if (k < 0)
      st = (int)k;
    else {
      s->opposing = k;
      if (k > 0) {
        vm_log(ctx, VM_LOG_WARN,
               "%lld triangles are turned over against the input surface (their normal opposes "
               "the input's at their centroid), e.g. near (%g, %g, %g)",
               (long long)k, at[0], at[1], at[2]);
        st = VM_WARN_INVERTED;
      }
    }
  }
  vm_free(ctx, x0);
  vm_mesh_destroy(&input);
  if (st >= 0 && o.step != VM_SURFACE_CURVATURE && all_triangles(m)) {
    int b = unblind(ctx, m, s);
    if (b >= 0) b = keep_plane(ctx, m, s, "unblind");
    if (b < 0) st = b;
  }
  /* the result's border: every vertex in the plane */
  if (st >= 0 && s->symmetry.found) {
    vm_surf_edges E;
    int b = vm_surf_edges_build(ctx, m, &E);
    if (b < 0) return b;
    uint8_t *seen = vm_calloc(ctx, (size_t)(m->nv > 0 ? m->nv : 1), 1);
    if (!seen) b = VM_ERR_NOMEM;
    for (int64_t e = 0; seen && e < E.ne; e++)
      for (int i = 0; E.nface[e] == 1 && i < 2; i++) {
        int32_t v = E.ev[2 * e + i];
        if (seen[v]) continue;
        seen[v] = 1;
        s->symmetry_border++;
        s->symmetry_off += m->xyz[3 * (int64_t)v + s->symmetry.axis] != s->symmetry.value;
      }
    vm_free(ctx, seen);
    vm_surf_edges_free(ctx, &E);
    /* the plane for the later stages (a remeshing makes a new mesh) */
    if (b >= 0) b = vm_mesh_set_symmetry_plane(m, s->symmetry.axis, s->symmetry.value);
    if (b < 0) return b;
    if (s->symmetry_off) {
      char pl[64];
      vm_log(ctx, VM_LOG_WARN, "%lld of the result's %lld border vertices are not in the plane %s",
             (long long)s->symmetry_off, (long long)s->symmetry_border,
             plane_name(s, pl, sizeof pl));
    }
  }
  return st;
}

int vm_surface_run(vm_ctx *ctx, vm_mesh *m, const vm_surface_opts *opts,
                   vm_surface_summary *summary) {
  vm_surface_summary local;
  vm_surface_summary *s = summary ? summary : &local;
  vm_surface_opts o = opts ? *opts : vm_surface_opts_default();
  /* by default (wrap < 0) a surface the whole stage leaves with needles
   * (triangles under needle_angle that neither the sliver removal nor the
   * curvature-sized remeshing took out: the union of crossing parts, a
   * remeshing refused for its intersections) is made again from the
   * input, wrapped; kept if that leaves fewer needles */
  int fallback =
      o.wrap < 0 && o.step == VM_SURFACE_ALL && o.needle_angle > 0 && m && all_triangles(m);
  vm_mesh *orig = NULL;
  if (fallback) {
    int b = vm_mesh_clone(m, &orig);
    if (b < 0) return b;
  }
  int st = run(ctx, m, &o, s);
  int64_t left =
      st >= 0 && orig && !s->wrapped && !s->symmetry.found && s->needles_in > 0 && all_triangles(m)
          ? needles(m, o.needle_angle)
          : 0;
  if (left > 0 && !vm_ctx_interrupted(ctx)) {
    double amin = vm_surface_min_angle(m);
    vm_log(ctx, VM_LOG_WARN,
           "the surface keeps %lld triangles under %g deg (smallest %.3g) after the repair and "
           "the remeshing; making it again from the input wrapped in a closed surface (--wrap 0 "
           "keeps it as it is)",
           (long long)left, o.needle_angle, amin);
    vm_surface_opts o2 = o;
    o2.wrap = VM_SURFACE_WRAP_DEFAULT;
    vm_surface_summary s2;
    int st2 = run(ctx, orig, &o2, &s2);
    int64_t left2 = st2 >= 0 && all_triangles(orig) ? needles(orig, o.needle_angle) : -1;
    if (st2 >= 0 && left2 >= 0 && left2 < left) {
      vm_mesh tmp = *m;
      *m = *orig;
      *orig = tmp;
      *s = s2;
      s->wrap_auto = 1;
      st = st2;
      vm_log(ctx, VM_LOG_INFO, "wrap: kept: %lld triangles under %g deg left (smallest %.3g)",
             (long long)left2, o.needle_angle, vm_surface_min_angle(m));
    } else if (st2 == VM_ERR_INTERRUPTED) {
      st = st2; /* m: the stage's result without the wrap */
    } else {
      if (st2 < 0) vm_ctx_clear_error(ctx);
      vm_log(ctx, VM_LOG_WARN,
             "wrap: not kept (%s); the surface as the stage made it without the wrap",
             st2 < 0 ? "it failed" : "no fewer needles");
    }
  }
  vm_mesh_destroy(&orig);
  return st;
}
