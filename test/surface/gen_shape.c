/* test/surface/gen_shape.c: writes the generated test surfaces of varmesh/shapes.h
 * (and broken variants) to a file, for the vm-surface CLI tests.
 * usage: gen_shape lens|sphere|cube|open|fin|flipped|inward|needle|spindle|assembly OUT */
#include <stdio.h>
#include <string.h>

#include "varmesh/io.h"
#include "varmesh/shapes.h"

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(
        stderr,
        "usage: gen_shape lens|sphere|cube|open|fin|flipped|inward|needle|spindle|assembly OUT\n");
    return 2;
  }
  vm_ctx *ctx = NULL;
  vm_mesh *m = NULL;
  if (vm_ctx_create(&ctx) || vm_mesh_create(ctx, &m)) {
    vm_ctx_destroy(&ctx);
    return 1;
  }
  const char *k = argv[1];
  int st = 0;
  if (!strcmp(k, "lens")) {
    st = vm_gen_lens(m, 1.0, 0.5, 0.1);
  } else if (!strcmp(k, "spindle")) {
    st = vm_gen_spindle(m, 48, 0.001);
  } else if (!strcmp(k, "assembly")) {
    /* parts as published models have them: a sphere (the fuselage), a bar
     * through it (the wing) and a small box inside it, each closed, one
     * file, not united */
    st = vm_gen_icosphere(m, NULL, 1.0, 3, 0, NULL);
    static const double box[2][2][3] = {{{-0.4, -0.2, -0.15}, {1.6, 0.2, 0.15}},
                                        {{-0.5, 0.25, 0.25}, {-0.3, 0.45, 0.45}}};
    static const int q[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};
    for (int b = 0; b < 2 && !st; b++) {
      int32_t v0 = (int32_t)m->nv;
      for (int i = 0; i < 8 && !st; i++)
        st = vm_mesh_add_vertex(m, box[b][i & 1 ? 1 : 0][0], box[b][i & 2 ? 1 : 0][1],
                                box[b][i & 4 ? 1 : 0][2], NULL);
      for (int f = 0; f < 6 && !st; f++) {
        int32_t t1[3] = {v0 + q[f][0], v0 + q[f][1], v0 + q[f][2]},
                t2[3] = {v0 + q[f][0], v0 + q[f][2], v0 + q[f][3]};
        st = vm_mesh_add_element(m, VM_TRI, t1);
        if (!st) st = vm_mesh_add_element(m, VM_TRI, t2);
      }
    }
  } else if (!strcmp(k, "cube") || !strcmp(k, "fin")) {
    st = vm_gen_cube(m, 3);
    if (!st && !strcmp(k, "fin")) { /* a third face on the edge of face 0 */
      int64_t v;
      vm_mesh_add_vertex(m, 0.5, -1, 0.5, &v);
      int32_t t[3] = {m->conn[0], m->conn[1], (int32_t)v};
      st = vm_mesh_add_element(m, VM_TRI, t);
    }
  } else if (!strcmp(k, "sphere") || !strcmp(k, "open") || !strcmp(k, "inward") ||
             !strcmp(k, "flipped") || !strcmp(k, "needle")) {
    st = vm_gen_icosphere(m, NULL, 1.0, 3, 0, NULL);
    if (!st && !strcmp(k, "open")) m->ne -= 2;
    if (!st && !strcmp(k, "inward")) /* every triangle reversed */
      for (int64_t e = 0; e < m->ne; e++) {
        int32_t *c = m->conn + 3 * e, s = c[1];
        c[1] = c[2];
        c[2] = s;
      }
    if (!st && !strcmp(k, "flipped"))
      for (int64_t e = 10; e < 13; e++) {
        int32_t *c = m->conn + 3 * e, s = c[1];
        c[1] = c[2];
        c[2] = s;
      }
    if (!st && !strcmp(k, "needle")) { /* zero-area triangle in a closed surface */
      int32_t a = m->conn[0], b = m->conn[1], c = m->conn[2];
      int64_t mid;
      vm_mesh_add_vertex(m, 0.5 * (m->xyz[3 * a] + m->xyz[3 * b]),
                         0.5 * (m->xyz[3 * a + 1] + m->xyz[3 * b + 1]),
                         0.5 * (m->xyz[3 * a + 2] + m->xyz[3 * b + 2]), &mid);
      m->conn[1] = (int32_t)mid;
      int32_t t2[3] = {(int32_t)mid, b, c}, deg[3] = {a, b, (int32_t)mid};
      st = vm_mesh_add_element(m, VM_TRI, t2);
      if (!st) st = vm_mesh_add_element(m, VM_TRI, deg);
    }
  } else {
    fprintf(stderr, "gen_shape: unknown shape '%s'\n", k);
    vm_mesh_destroy(&m);
    vm_ctx_destroy(&ctx);
    return 2;
  }
  if (!st) st = vm_mesh_write(ctx, m, argv[2], VM_FMT_AUTO, NULL);
  if (st < 0) fprintf(stderr, "gen_shape: %s\n", vm_ctx_error(ctx));
  vm_mesh_destroy(&m);
  vm_ctx_destroy(&ctx);
  return st < 0;
}
