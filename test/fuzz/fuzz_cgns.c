/* test/fuzz/fuzz_cgns.c: structure-aware libFuzzer harness for the CGNS
 * reader. libcgns and HDF5 parse the container; what varmesh's reader must
 * survive is hostile *content* in a well-formed file: zone sizes that lie,
 * sections that overlap or leave gaps, connectivity out of range, element
 * types it does not know, MIXED streams whose offsets disagree, boundary
 * conditions on ranges, lists and vertices that point anywhere, family
 * names, coordinates that are not finite, solutions of any length. The
 * fuzz input is a program: its bytes choose each of these, the harness
 * writes the file with libcgns (its own writer's checks may refuse a part:
 * that part is left out) and hands the file's bytes to the reader through
 * vm_mesh_read_memory, with the contract of fuzz_common.h (one-line errors,
 * no leaks, injected allocation failures, round trip through .vmsh) and one
 * more: no file descriptor left open (libcgns leaks one when cg_open fails,
 * which the reader must close). Seeds: corpus/cgns (hand_seeds.py). */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cgnslib.h>

#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct {
  const uint8_t *p;
  size_t n, i;
} prog;

static unsigned take(prog *b) { return b->i < b->n ? b->p[b->i++] : 0; }

/* a small signed integer, now and then an extreme one */
static cgsize_t take_int(prog *b, cgsize_t typical) {
  unsigned c = take(b);
  switch (c) {
  case 255: return -1;
  case 254: return 0;
  case 253: return (cgsize_t)0x7fffffff;
  case 252: return (cgsize_t)-0x7fffffff - 1;
  case 251: return typical < 0x7fffffff ? typical + 1 : typical;
  default: return (cgsize_t)((int64_t)c % ((int64_t)typical + 3)) - 1;
  }
}

static double take_coord(prog *b) {
  unsigned c = take(b);
  switch (c) {
  case 255: return (double)NAN;
  case 254: return (double)INFINITY;
  case 253: return 1e300;
  case 252: return -0.0;
  default: return ((int)c - 128) / 16.0;
  }
}

static void quiet(int is_error, char *msg) {
  (void)is_error;
  (void)msg;
}

static const CGNS_ENUMT(ElementType_t) types[] = {
    CGNS_ENUMV(TRI_3),   CGNS_ENUMV(QUAD_4),  CGNS_ENUMV(TETRA_4), CGNS_ENUMV(PYRA_5),
    CGNS_ENUMV(PENTA_6), CGNS_ENUMV(HEXA_8),  CGNS_ENUMV(MIXED),   CGNS_ENUMV(NODE),
    CGNS_ENUMV(BAR_2),   CGNS_ENUMV(TRI_6),   CGNS_ENUMV(HEXA_27), CGNS_ENUMV(NGON_n),
    CGNS_ENUMV(NFACE_n), CGNS_ENUMV(TETRA_10)};
enum { NTYPES = (int)(sizeof types / sizeof types[0]) };

static const char *const names[] = {"wall", "farfield", "symmetry", "outer", "Tetrahedra", "x"};

/* Write the file the program describes. */
static void write_program(prog *b, const char *path) {
  int fn, B, Z;
  /* never fails unless files leak (libcgns: "Too many files opened"), and
   * then the rest of the run would test nothing */
  if (cg_open(path, CG_MODE_WRITE, &fn)) {
    fprintf(stderr, "fuzz_cgns: cg_open: %s\n", cg_get_error());
    VM_FUZZ_REQUIRE(0, "cannot open the CGNS file to write");
  }
  int cdim = 1 + (int)(take(b) % 3), pdim = 1 + (int)(take(b) % 3);
  if (cg_base_write(fn, "base", cdim, pdim, &B)) goto done;
  int structured = take(b) % 16 == 0;
  cgsize_t nv = (cgsize_t)(take(b) % 48), ncell = (cgsize_t)(take(b) % 64);
  cgsize_t zsize[9] = {nv, ncell, 0};
  if (structured) /* 2 x 2 x 2 vertices at most: libcgns reads products of these */
    for (int d = 0; d < cdim; d++) zsize[d] = 2, zsize[cdim + d] = 1, zsize[2 * cdim + d] = 0;
  if (cg_zone_write(fn, B, "zone", zsize,
                    structured ? CGNS_ENUMV(Structured) : CGNS_ENUMV(Unstructured), &Z))
    goto done;
  /* coordinates: some of X, Y, Z (a missing one is a hostile file too) */
  static const char *const cname[3] = {"CoordinateX", "CoordinateY", "CoordinateZ"};
  unsigned which = take(b);
  double xyz[48] = {0};
  for (int k = 0; k < 3; k++) {
    if ((which >> k & 1) && which != 255) continue;
    for (cgsize_t v = 0; v < nv; v++) xyz[v] = take_coord(b);
    int C;
    cg_coord_write(fn, B, Z, CGNS_ENUMV(RealDouble), cname[k], xyz, &C);
  }
  /* sections */
  int nsec = (int)(take(b) % 5);
  cgsize_t next = 1;
  for (int s = 0; s < nsec; s++) {
    CGNS_ENUMT(ElementType_t) t = types[take(b) % NTYPES];
    cgsize_t start = take(b) % 4 == 0 ? take_int(b, 8) : next;
    cgsize_t count = (cgsize_t)(take(b) % 12);
    int64_t end64 = (int64_t)start + count - 1; /* cgsize_t is int */
    if (end64 > (int64_t)0x7fffffff || end64 < -(int64_t)0x7fffffff) start = 1;
    cgsize_t end = start + count - 1;
    cgsize_t conn[12 * 28], off[13];
    int S, npe = 0;
    if (t == CGNS_ENUMV(MIXED) || t == CGNS_ENUMV(NGON_n) || t == CGNS_ENUMV(NFACE_n)) {
      /* a stream of (type, nodes) with offsets, or lying offsets */
      cgsize_t k = 0;
      off[0] = 0;
      for (cgsize_t e = 0; e < count; e++) {
        CGNS_ENUMT(ElementType_t) et = types[take(b) % NTYPES];
        int n = 0;
        if (t == CGNS_ENUMV(MIXED)) {
          conn[k++] = take(b) % 8 == 0 ? take_int(b, 60) : (cgsize_t)et;
          if (cg_npe(et, &n) || n < 0 || n > 27) n = 3;
        } else
          n = 1 + (int)(take(b) % 6);
        for (int j = 0; j < n; j++) conn[k++] = take_int(b, nv);
        off[e + 1] = take(b) % 16 == 0 ? take_int(b, k) : k;
      }
      cg_poly_section_write(fn, B, Z, names[s % 6], t, start, end, 0, conn, off, &S);
    } else {
      cg_npe(t, &npe);
      if (npe < 1 || npe > 27) continue;
      for (cgsize_t j = 0; j < count * npe; j++) conn[j] = take_int(b, nv);
      cg_section_write(fn, B, Z, names[s % 6], t, start, end, 0, conn, &S);
    }
    next = end + 1;
  }
  /* boundary conditions, with or without a family */
  int nbc = (int)(take(b) % 4);
  for (int k = 0; k < nbc; k++) {
    static const CGNS_ENUMT(PointSetType_t)
        pts[4] = {CGNS_ENUMV(PointRange), CGNS_ENUMV(PointList), CGNS_ENUMV(ElementRange),
                  CGNS_ENUMV(ElementList)};
    static const CGNS_ENUMT(GridLocation_t) locs[4] = {
        CGNS_ENUMV(FaceCenter), CGNS_ENUMV(Vertex), CGNS_ENUMV(CellCenter), CGNS_ENUMV(EdgeCenter)};
    CGNS_ENUMT(PointSetType_t) pt = pts[take(b) % 4];
    cgsize_t np = (pt == CGNS_ENUMV(PointRange) || pt == CGNS_ENUMV(ElementRange))
                      ? (take(b) % 8 ? 2 : 1 + (cgsize_t)(take(b) % 3))
                      : (cgsize_t)(take(b) % 16);
    cgsize_t pnts[48] = {0}; /* np x the index dimension (3 in a structured zone) */
    for (cgsize_t i = 0; i < np; i++) pnts[i] = take_int(b, next);
    int BC;
    const char *nm = names[take(b) % 6];
    if (cg_boco_write(fn, B, Z, nm, CGNS_ENUMV(FamilySpecified), pt, np, pnts, &BC)) continue;
    cg_boco_gridlocation_write(fn, B, Z, BC, locs[take(b) % 4]);
    if (take(b) % 2 && !cg_goto(fn, B, "Zone_t", Z, "ZoneBC_t", 1, "BC_t", BC, "end"))
      cg_famname_write(names[take(b) % 6]);
  }
  /* a solution at cells or vertices, of the zone's length (whatever that is) */
  if (take(b) % 2) {
    int S, F;
    CGNS_ENUMT(GridLocation_t) loc = take(b) % 2 ? CGNS_ENUMV(CellCenter) : CGNS_ENUMV(Vertex);
    if (!cg_sol_write(fn, B, Z, "sol", loc, &S)) {
      int nf = (int)(take(b) % 3);
      for (int f = 0; f < nf; f++) {
        double d[64];
        int iv[64];
        for (int i = 0; i < 64; i++) d[i] = take_coord(b), iv[i] = (int)take_int(b, 100);
        if (take(b) % 2)
          cg_field_write(fn, B, Z, S, CGNS_ENUMV(RealDouble), names[f], d, &F);
        else
          cg_field_write(fn, B, Z, S, CGNS_ENUMV(Integer), names[f], iv, &F);
      }
    }
  }
done:
  cg_close(fn);
}

/* open file descriptors of the process: the reader must close what it opens */
static int open_fds(void) {
  DIR *d = opendir("/proc/self/fd");
  int n = 0;
  if (!d) return -1;
  while (readdir(d)) n++;
  closedir(d);
  return n;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static const vm_fuzz_reader r = {"cgns", "fuzz.cgns", VM_FMT_CGNS};
  static int configured;
  if (!configured) {
    void (*handler)(int, char *) = quiet;
    void *hp;
    memcpy(&hp, &handler, sizeof hp);
    cg_configure(CG_CONFIG_ERROR, hp);
    configured = 1;
#ifdef VM_FUZZ_VERBOSE /* status and message of each input: VM_FUZZ_VERBOSE=1 */
    vm_fuzz_verbose = getenv("VM_FUZZ_VERBOSE") != NULL;
#endif
  }
  char path[128];
  snprintf(path, sizeof path, "%s/in.cgns", vm_fuzz_tmpdir());
  int fd0 = open_fds();
  prog b = {data, size, 0};
  write_program(&b, path);
  FILE *f = fopen(path, "rb");
  if (!f) return 0;
  uint8_t *buf = NULL;
  long len = 0;
  if (!fseek(f, 0, SEEK_END) && (len = ftell(f)) > 0 && !fseek(f, 0, SEEK_SET)) {
    buf = (uint8_t *)malloc((size_t)len);
    if (buf && fread(buf, 1, (size_t)len, f) != (size_t)len) len = 0;
  }
  fclose(f);
  remove(path);
  int fd1 = open_fds();
  if (buf && len > 0) vm_fuzz_one(&r, buf, (size_t)len);
  free(buf);
  int fd2 = open_fds();
  VM_FUZZ_REQUIRE(fd2 == fd1, "the reader left a file descriptor open");
  VM_FUZZ_REQUIRE(fd1 == fd0, "libcgns's writer left a file descriptor open");
  return 0;
}

#ifdef VM_FUZZ_REPLAY_MAIN
/* Without libFuzzer (meson test fuzz-replay-cgns): every file named, or every
 * file of the directories named, run once through the harness. */
int main(int argc, char **argv) {
  int n = 0;
  for (int a = 1; a < argc; a++) {
    DIR *d = opendir(argv[a]);
    char **names = NULL;
    int nn = 0;
    if (d) {
      struct dirent *e;
      while ((e = readdir(d)))
        if (e->d_name[0] != '.') {
          names = (char **)realloc(names, (size_t)(nn + 1) * sizeof *names);
          VM_FUZZ_REQUIRE(names != NULL, "out of memory");
          names[nn] = (char *)malloc(strlen(argv[a]) + strlen(e->d_name) + 2);
          VM_FUZZ_REQUIRE(names[nn] != NULL, "out of memory");
          sprintf(names[nn++], "%s/%s", argv[a], e->d_name);
        }
      closedir(d);
    } else {
      names = (char **)malloc(sizeof *names);
      VM_FUZZ_REQUIRE(names != NULL, "out of memory");
      names[nn] = (char *)malloc(strlen(argv[a]) + 1);
      VM_FUZZ_REQUIRE(names[nn] != NULL, "out of memory");
      strcpy(names[nn++], argv[a]);
    }
    for (int i = 0; i < nn; i++) {
      FILE *f = fopen(names[i], "rb");
      VM_FUZZ_REQUIRE(f != NULL, "cannot open an input");
      uint8_t buf[65536];
      size_t len = fread(buf, 1, sizeof buf, f);
      fclose(f);
      uint8_t *exact = (uint8_t *)malloc(len ? len : 1); /* reads past the end are seen */
      VM_FUZZ_REQUIRE(exact != NULL, "out of memory");
      memcpy(exact, buf, len);
      LLVMFuzzerTestOneInput(exact, len);
      free(exact);
      free(names[i]);
      n++;
    }
    free(names);
  }
  printf("fuzz_cgns: %d inputs, contract kept\n", n);
  return n ? 0 : 1;
}
#endif
