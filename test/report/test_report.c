/* test/report/test_report.c: the report library: every figure on generated
 * meshes (rotated cube, aircraft), the page and its links, PNGs decoded
 * back with cairo, the same pictures bit for bit on a second run, argument
 * errors, and an allocation failure at every allocation of every figure.
 * usage: test_report                 the unit tests
 *        test_report --png FILE...   decode each PNG, exit 1 unless every
 *                                    one is a non-empty, non-uniform image
 *        test_report --png-red N FILE...  and has N strongly red pixels
 *                                    (a figure, not just text) */
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "varmesh/aircraft.h"
#include "varmesh/ctx.h"
#include "varmesh/rotcube.h"
#include "varmesh/mesh.h"
#include "varmesh/quality.h"
#include "varmesh/report.h"
#include "vmtest.h"

#if VM_HAVE_CAIRO
#include <cairo.h>

/* Decode a PNG: its size, the number of distinct pixel values seen (stops
 * counting at 2) and, if `red` is not NULL, the number of strongly red
 * pixels (red above green and blue by 96 or more: the M curve of the
 * convergence plot, inverted elements; not text, grey or link blue).
 * Returns 0 if cairo could read it. */
static int png_info(const char *path, int *w, int *h, int *distinct, long *red) {
  cairo_surface_t *s = cairo_image_surface_create_from_png(path);
  if (cairo_surface_status(s) != CAIRO_STATUS_SUCCESS) {
    cairo_surface_destroy(s);
    return 1;
  }
  *w = cairo_image_surface_get_width(s);
  *h = cairo_image_surface_get_height(s);
  int stride = cairo_image_surface_get_stride(s);
  cairo_format_t fmt = cairo_image_surface_get_format(s);
  const unsigned char *d = cairo_image_surface_get_data(s);
  uint32_t first = 0, mask = fmt == CAIRO_FORMAT_ARGB32 ? 0xffffffffu : 0x00ffffffu;
  *distinct = 0;
  if (red) {
    *red = 0;
    for (int y = 0; y < *h; y++)
      for (int x = 0; x < *w; x++) {
        uint32_t px;
        memcpy(&px, d + (size_t)y * (size_t)stride + 4 * (size_t)x, 4);
        int r = (px >> 16) & 255, g = (px >> 8) & 255, b = px & 255;
        *red += r - (g > b ? g : b) >= 96;
      }
  }
  for (int y = 0; y < *h && *distinct < 2; y++)
    for (int x = 0; x < *w; x++) {
      uint32_t px;
      memcpy(&px, d + (size_t)y * (size_t)stride + 4 * (size_t)x, 4);
      px &= mask;
      if (*distinct == 0) {
        first = px;
        *distinct = 1;
      } else if (px != first) {
        *distinct = 2;
        break;
      }
    }
  cairo_surface_destroy(s);
  return 0;
}

/* min_red > 0: also require that many strongly red pixels. */
static int check_pngs(int n, char **paths, long min_red) {
  int bad = 0;
  for (int i = 0; i < n; i++) {
    int w, h, distinct;
    long red = 0;
    if (png_info(paths[i], &w, &h, &distinct, min_red > 0 ? &red : NULL)) {
      printf("FAIL: %s: not a PNG cairo can read\n", paths[i]);
      bad = 1;
    } else if (w < 1 || h < 1 || distinct < 2) {
      printf("FAIL: %s: %dx%d, %s\n", paths[i], w, h, distinct < 2 ? "one colour" : "empty");
      bad = 1;
    } else if (red < min_red) {
      printf("FAIL: %s: %ld strongly red pixels, fewer than %ld\n", paths[i], red, min_red);
      bad = 1;
    } else {
      printf("ok: %s: %dx%d PNG, more than one colour", paths[i], w, h);
      if (min_red > 0) printf(", %ld strongly red pixels", red);
      putchar('\n');
    }
  }
  return bad;
}

static char *slurp(const char *path, long *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  *len = ftell(f);
  fseek(f, 0, SEEK_SET);
  char *s = malloc((size_t)*len + 1);
  if (s && fread(s, 1, (size_t)*len, f) != (size_t)*len) {
    free(s);
    s = NULL;
  }
  if (s) s[*len] = 0;
  fclose(f);
  return s;
}

static int same_file(const char *a, const char *b) {
  long la = 0, lb = 0;
  char *x = slurp(a, &la), *y = slurp(b, &lb);
  int same = x && y && la == lb && !memcmp(x, y, (size_t)la);
  free(x);
  free(y);
  return same;
}

/* Every src="..." of the page exists in dir and decodes; returns the count. */
static int check_links(const char *dir) {
  char path[1024];
  snprintf(path, sizeof path, "%s/index.html", dir);
  long len;
  char *html = slurp(path, &len);
  CHECK(html != NULL, "%s not written", path);
  if (!html) return 0;
  int n = 0;
  for (const char *p = strstr(html, "src=\""); p; p = strstr(p + 1, "src=\"")) {
    const char *a = p + 5, *b = strchr(a, '"');
    if (!b) break;
    char file[1024];
    snprintf(path, sizeof path, "%s/%.*s", dir, (int)(b - a), a);
    snprintf(file, sizeof file, "%.*s", (int)(b - a), a);
    int w, h, distinct;
    int rc = png_info(path, &w, &h, &distinct, NULL);
    CHECK(rc == 0 && distinct == 2, "%s: linked from index.html but missing or blank", path);
    char attr[64];
    snprintf(attr, sizeof attr, " width=\"%d\" height=\"%d\"", rc ? -1 : w, rc ? -1 : h);
    CHECK(!strncmp(b + 1, attr, strlen(attr)),
          "%s: the page's size attributes do not match "
          "the PNG",
          file);
    n++;
  }
  CHECK(strstr(html, "</html>") != NULL, "index.html is complete");
  free(html);
  return n;
}

/* No temporary file left in dir. */
static void check_no_tmp(const char *dir) {
  DIR *d = opendir(dir);
  struct dirent *e;
  int tmp = 0;
  while (d && (e = readdir(d)))
    if (strstr(e->d_name, ".tmp.")) tmp++;
  if (d) closedir(d);
  CHECK(tmp == 0, "%d temporary files left in %s", tmp, dir);
}

static void rm_dir(const char *dir) {
  DIR *d = opendir(dir);
  struct dirent *e;
  char path[1024];
  while (d && (e = readdir(d))) {
    if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
    snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
    remove(path);
  }
  if (d) closedir(d);
  rmdir(dir);
}

static void fill_history(vm_report_history *h) {
  int it = 0;
  for (int i = 0; i < 30; i++)
    vm_report_history_add(h, "untangle", ++it, 50.0 / (i + 1), 400 >> (i / 3), 0.3 * pow(0.7, i));
  for (int i = 0; i < 5; i++) vm_report_history_add(h, "local", ++it, 1.7, 3 - i / 2, 1e-6);
  for (int i = 0; i < 40; i++) vm_report_history_add(h, "optimize", ++it, 1 + exp(-i / 5.0), 0, 0);
}

/* Every figure kind once into report r; returns the first error. */
typedef int (*figure_fn)(vm_report *r, const vm_mesh *cube, const vm_mesh *air,
                         const vm_report_history *h);

static int fig_hist(vm_report *r, const vm_mesh *c, const vm_mesh *a, const vm_report_history *h) {
  (void)a, (void)h;
  return vm_report_histograms(r, "hist", "histograms", c, NULL);
}
static int fig_conv(vm_report *r, const vm_mesh *c, const vm_mesh *a, const vm_report_history *h) {
  (void)a, (void)c;
  return vm_report_convergence(r, "conv", "convergence", h);
}
static int fig_surf(vm_report *r, const vm_mesh *c, const vm_mesh *a, const vm_report_history *h) {
  (void)c, (void)h;
  return vm_report_surface(r, "surf", "surface", a, "height", NULL);
}
static int fig_slice(vm_report *r, const vm_mesh *c, const vm_mesh *a, const vm_report_history *h) {
  (void)a, (void)h;
  return vm_report_slice(r, "slice", "slice", c, 2, NAN, NULL);
}
static int fig_mesh(vm_report *r, const vm_mesh *c, const vm_mesh *a, const vm_report_history *h) {
  (void)h;
  int st = vm_report_mesh(r, "c-", "cube", c, NULL, NULL);
  return st < 0 ? st : vm_report_mesh(r, "a-", "aircraft", a, NULL, NULL);
}
static int fig_write(vm_report *r, const vm_mesh *c, const vm_mesh *a, const vm_report_history *h) {
  int st = vm_report_row(r, "key", "%d", 42);
  if (st >= 0) st = fig_hist(r, c, a, h);
  return st < 0 ? st : vm_report_write(r);
}

/* For every n, the n-th allocation of (create, figure, destroy) fails: the
 * call fails with VM_ERR_NOMEM or succeeds, and nothing leaks. */
static void alloc_sweep(vm_ctx *ctx, const char *dir, const char *what, figure_fn fn,
                        const vm_mesh *cube, const vm_mesh *air, const vm_report_history *h) {
  int ok = 0, failed = 0;
  for (long n = 1; n < 100000; n++) {
    long live = vm_ctx_alloc_live(ctx);
    vm_report *r = NULL;
    vm_ctx_set_alloc_fail(ctx, n);
    int st = vm_report_create(ctx, dir, "sweep", &r);
    if (st >= 0) st = fn(r, cube, air, h);
    vm_ctx_set_alloc_fail(ctx, 0);
    vm_report_destroy(&r);
    CHECK(vm_ctx_alloc_live(ctx) == live, "%s: allocation %ld failing leaks %ld blocks", what, n,
          vm_ctx_alloc_live(ctx) - live);
    if (st >= 0) {
      ok = 1;
      break;
    }
    CHECK(st == VM_ERR_NOMEM, "%s: allocation %ld failing gives %d, not VM_ERR_NOMEM (%s)", what, n,
          st, vm_ctx_error(ctx));
    failed++;
  }
  CHECK(ok, "%s: never succeeded", what);
  CHECK(failed > 0, "%s: allocates nothing?", what);
  check_no_tmp(dir);
}

int main(int argc, char **argv) {
  if (argc > 1 && !strcmp(argv[1], "--png")) return check_pngs(argc - 2, argv + 2, 0);
  if (argc > 2 && !strcmp(argv[1], "--png-red"))
    return check_pngs(argc - 3, argv + 3, atol(argv[2]));
  CHECK(vm_report_available() == 1, "built with cairo");
  char tmpl[] = "/tmp/vm_report_XXXXXX";
  char *base = mkdtemp(tmpl);
  if (!base) {
    perror("mkdtemp");
    return 1;
  }
  char dir[512], dir2[512], sweep[512];
  snprintf(dir, sizeof dir, "%s/report", base);
  snprintf(dir2, sizeof dir2, "%s/again", base);
  snprintf(sweep, sizeof sweep, "%s/sweep", base);
  vm_ctx *ctx;
  if (vm_ctx_create(&ctx) < 0) return 1;

  /* the meshes: a tangled hex cube, and the aircraft with a height field */
  vm_rotcube_opts co = vm_rotcube_opts_default();
  co.n = 6;
  co.alpha = 3.14159265358979323846 / 2;
  vm_mesh *cube = NULL, *air = NULL;
  CHECK(vm_gen_rotated_cube(ctx, &co, &cube, NULL) == VM_OK, "rotated cube");
  vm_aircraft_opts ao = vm_aircraft_opts_default();
  ao.resolution = 1;
  CHECK(vm_gen_aircraft(ctx, &ao, &air) == VM_OK, "aircraft");
  if (!cube || !air) return vmtest_end("report");
  vm_field *hf;
  CHECK(vm_mesh_add_field(air, "height", VM_FIELD_VERTEX, VM_FIELD_F64, 1, &hf) == VM_OK,
        "add a field");
  for (int64_t v = 0; v < air->nv; v++) ((double *)hf->data)[v] = air->xyz[3 * v + 2];
  vm_field *lf; /* a layer index, as the prism stage writes it */
  CHECK(vm_mesh_add_field(cube, "layer", VM_FIELD_ELEMENT, VM_FIELD_I32, 1, &lf) == VM_OK,
        "add a layer field");
  for (int64_t e = 0; e < cube->ne; e++) ((int32_t *)lf->data)[e] = (int32_t)(e % 6);

  /* per-element quality agrees with the summary */
  double *sj = calloc((size_t)cube->ne, sizeof *sj), *phi = calloc((size_t)cube->ne, sizeof *phi);
  vm_quality q;
  CHECK(vm_mesh_element_quality(cube, NULL, &q, sj, phi) == VM_OK, "element quality");
  double smin = INFINITY, pmin = INFINITY;
  for (int64_t e = 0; e < cube->ne; e++) {
    smin = fmin(smin, sj[e]);
    pmin = fmin(pmin, phi[e]);
  }
  CHECK(smin == q.all.sj_min && pmin == q.all.phi_min, "element minima %g %g vs %g %g", smin, pmin,
        q.all.sj_min, q.all.phi_min);
  CHECK(q.all.inverted_elems > 0 && smin < 0 && pmin < 0, "the cube is tangled");
  free(sj);
  free(phi);

  vm_report_history *h;
  CHECK(vm_report_history_create(ctx, &h) == VM_OK, "history");
  fill_history(h);
  CHECK(vm_report_history_count(h) == 75, "75 samples");

  /* one report with every figure */
  vm_report *r = NULL;
  CHECK(vm_report_create(ctx, dir, "test & <report>", &r) == VM_OK, "create: %s",
        vm_ctx_error(ctx));
  if (!r) return vmtest_end("report");
  CHECK(vm_report_row(r, "answer", "%d", 42) == VM_OK, "row");
  CHECK(fig_hist(r, cube, air, h) == VM_OK, "histograms: %s", vm_ctx_error(ctx));
  CHECK(fig_conv(r, cube, air, h) == VM_OK, "convergence: %s", vm_ctx_error(ctx));
  CHECK(vm_report_convergence(r, "conv-empty", NULL, NULL) == VM_OK, "empty convergence");
  CHECK(fig_surf(r, cube, air, h) == VM_OK, "surface: %s", vm_ctx_error(ctx));
  vm_report_view vw = vm_report_view_default();
  vw.azimuth = 200;
  vw.elevation = -30;
  vw.width = 400;
  vw.height = 300;
  vw.edges = 1;
  CHECK(vm_report_surface(r, "surf-quality", "quality", air, NULL, &vw) == VM_OK,
        "surface by quality: %s", vm_ctx_error(ctx));
  CHECK(fig_slice(r, cube, air, h) == VM_OK, "slice: %s", vm_ctx_error(ctx));
  CHECK(vm_report_slice(r, "slice-fixed", "by a vertex field", cube, 0, 0.1, "fixed") == VM_OK,
        "slice by field: %s", vm_ctx_error(ctx));
  CHECK(vm_report_slice(r, "slice-miss", NULL, cube, 1, 7.0, NULL) == VM_OK,
        "a plane missing the mesh");
  CHECK(fig_mesh(r, cube, air, h) == VM_OK, "vm_report_mesh: %s", vm_ctx_error(ctx));
  /* argument errors: nothing written */
  CHECK(vm_report_histograms(r, "../x", NULL, cube, NULL) == VM_ERR_ARG, "bad name");
  CHECK(vm_report_histograms(r, "", NULL, cube, NULL) == VM_ERR_ARG, "empty name");
  CHECK(vm_report_surface(r, "nofield", NULL, air, "nope", NULL) == VM_ERR_ARG, "missing field");
  CHECK(strstr(vm_ctx_error(ctx), "height") != NULL, "the message lists the fields: %s",
        vm_ctx_error(ctx));
  CHECK(vm_report_surface(r, "nofaces", NULL, cube, NULL, NULL) == VM_ERR_ARG, "no 2D elements");
  CHECK(vm_report_slice(r, "novolume", NULL, air, 2, 0, NULL) == VM_ERR_ARG, "no 3D elements");
  CHECK(vm_report_slice(r, "badaxis", NULL, cube, 3, 0, NULL) == VM_ERR_ARG, "bad axis");
  vw.width = 5;
  CHECK(vm_report_surface(r, "tiny", NULL, air, NULL, &vw) == VM_ERR_ARG, "image too small");
  CHECK(vm_report_write(r) == VM_OK, "write: %s", vm_ctx_error(ctx));
  vm_report_destroy(&r);
  CHECK(r == NULL, "destroy clears the pointer");

  char path[1024];
  int nlinks = check_links(dir);
  CHECK(nlinks == 13, "13 figures linked, got %d", nlinks);
  snprintf(path, sizeof path, "%s/c-slice-layer.png", dir);
  CHECK(access(path, F_OK) == 0, "a mesh with a layer field gets a slice by layer");
  snprintf(path, sizeof path, "%s/nofield.png", dir);
  CHECK(access(path, F_OK) != 0, "no picture for a failed figure");
  check_no_tmp(dir);
  long len = 0;
  snprintf(path, sizeof path, "%s/index.html", dir);
  char *html = slurp(path, &len);
  CHECK(html && strstr(html, "test &amp; &lt;report&gt;") && strstr(html, ">42<"),
        "title escaped, rows present");
  free(html);

  /* the same figures again, bit for bit */
  CHECK(vm_report_create(ctx, dir2, "again", &r) == VM_OK, "second report");
  if (r) {
    CHECK(fig_slice(r, cube, air, h) == VM_OK && fig_surf(r, cube, air, h) == VM_OK &&
              fig_hist(r, cube, air, h) == VM_OK && fig_conv(r, cube, air, h) == VM_OK &&
              vm_report_write(r) == VM_OK,
          "second run");
    vm_report_destroy(&r);
  }
  static const char *const same[] = {"slice", "surf", "hist", "conv"};
  for (int i = 0; i < 4; i++) {
    char a[1024], b[1024];
    snprintf(a, sizeof a, "%s/%s.png", dir, same[i]);
    snprintf(b, sizeof b, "%s/%s.png", dir2, same[i]);
    CHECK(same_file(a, b), "%s.png differs between two runs", same[i]);
  }

  /* directories that cannot be used */
  snprintf(path, sizeof path, "%s/no/such/dir", base);
  CHECK(vm_report_create(ctx, path, NULL, &r) == VM_ERR_IO && !r, "missing parent");
  snprintf(path, sizeof path, "%s/report/index.html", base);
  CHECK(vm_report_create(ctx, path, NULL, &r) == VM_ERR_IO && !r, "a file, not a directory");
  CHECK(vm_report_create(ctx, "", NULL, &r) == VM_ERR_ARG && !r, "empty path");

  /* allocation failures */
  alloc_sweep(ctx, sweep, "histograms", fig_hist, cube, air, h);
  alloc_sweep(ctx, sweep, "convergence", fig_conv, cube, air, h);
  alloc_sweep(ctx, sweep, "surface", fig_surf, cube, air, h);
  alloc_sweep(ctx, sweep, "slice", fig_slice, cube, air, h);
  alloc_sweep(ctx, sweep, "mesh", fig_mesh, cube, air, h);
  alloc_sweep(ctx, sweep, "write", fig_write, cube, air, h);
  {
    long live = vm_ctx_alloc_live(ctx);
    vm_report_history *h2 = NULL;
    int failed = 0;
    for (long n = 1; n < 20; n++) {
      CHECK(vm_report_history_create(ctx, &h2) == VM_OK, "history");
      vm_ctx_set_alloc_fail(ctx, n);
      int st = vm_report_history_add(h2, "a", 1, 1, 1, 1);
      vm_ctx_set_alloc_fail(ctx, 0);
      failed += st == VM_ERR_NOMEM;
      CHECK(st == VM_OK || st == VM_ERR_NOMEM, "history add: %d", st);
      vm_report_history_destroy(&h2);
    }
    CHECK(failed == 6, "6 allocations in the first add, %d failed", failed);
    CHECK(vm_ctx_alloc_live(ctx) == live, "history leaks");
  }

  vm_report_history_destroy(&h);
  vm_mesh_destroy(&cube);
  vm_mesh_destroy(&air);
  CHECK(vm_ctx_alloc_live(ctx) == 0, "%ld blocks leaked", vm_ctx_alloc_live(ctx));
  vm_ctx_destroy(&ctx);
  rm_dir(dir);
  rm_dir(dir2);
  rm_dir(sweep);
  rmdir(base);
  return vmtest_end("report");
}

#else /* built without cairo: the library must say so */

int main(int argc, char **argv) {
  if (argc > 1 && !strncmp(argv[1], "--png", 5)) return 77;
  vm_ctx *ctx;
  if (vm_ctx_create(&ctx) < 0) return 1;
  vm_report *r = (vm_report *)&ctx;
  CHECK(vm_report_available() == 0, "no cairo");
  CHECK(vm_report_create(ctx, "/tmp", NULL, &r) == VM_ERR_UNSUPPORTED && r == NULL,
        "create fails with VM_ERR_UNSUPPORTED");
  CHECK(strstr(vm_ctx_error(ctx), "without") != NULL, "message: %s", vm_ctx_error(ctx));
  vm_ctx_destroy(&ctx);
  return vmtest_end("report");
}

#endif
