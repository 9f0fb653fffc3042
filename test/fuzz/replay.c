/* test/fuzz/replay.c: run the fuzz harness without libFuzzer over every file
 * of test/fuzz/corpus/<reader>/ and test/fuzz/regress/<reader>/, so each
 * crash the fuzzers ever found stays a regression test.
 * usage: replay [-v] FUZZDIR [READER...]  or  replay [-v] --files READER FILE...
 * (-v: the status and error message of every file). */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define VM_FUZZ_VERBOSE 1
#include "fuzz_common.h"

static int cmp_str(const void *a, const void *b) {
  return strcmp(*(char *const *)a, *(char *const *)b);
}

static int run_file(const vm_fuzz_reader *r, const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "replay: cannot open %s\n", path);
    return 1;
  }
  size_t cap = 1 << 16, len = 0;
  uint8_t *buf = malloc(cap);
  size_t n;
  while (buf && (n = fread(buf + len, 1, cap - len, f)) > 0) {
    len += n;
    if (len == cap) {
      uint8_t *nb = realloc(buf, cap *= 2);
      if (!nb) free(buf);
      buf = nb;
    }
  }
  fclose(f);
  if (!buf) {
    fprintf(stderr, "replay: out of memory reading %s\n", path);
    return 1;
  }
  /* an exact-size copy, so ASan sees reads past the end of the input */
  uint8_t *exact = malloc(len ? len : 1);
  if (!exact) abort();
  memcpy(exact, buf, len);
  free(buf);
  if (vm_fuzz_verbose) fprintf(stderr, "%s\n", path);
  vm_fuzz_one(r, exact, len);
  free(exact);
  return 0;
}

/* Every regular file in dir, in name order. Returns files run, -1 on error. */
static long run_dir(const vm_fuzz_reader *r, const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return 0;
  char **names = NULL;
  size_t nn = 0, cap = 0;
  struct dirent *de;
  while ((de = readdir(d))) {
    if (de->d_name[0] == '.') continue;
    if (nn == cap) {
      cap = cap ? 2 * cap : 64;
      char **nb = realloc(names, cap * sizeof *names);
      if (!nb) abort();
      names = nb;
    }
    names[nn] = strdup(de->d_name);
    if (!names[nn]) abort();
    nn++;
  }
  closedir(d);
  if (nn) qsort(names, nn, sizeof *names, cmp_str);
  long ran = 0;
  for (size_t i = 0; i < nn; i++) {
    size_t pl = strlen(dir) + strlen(names[i]) + 2;
    char *path = malloc(pl);
    if (!path) abort();
    snprintf(path, pl, "%s/%s", dir, names[i]);
    if (run_file(r, path))
      ran = -1;
    else if (ran >= 0)
      ran++;
    free(path);
    free(names[i]);
  }
  free(names);
  return ran;
}

static const vm_fuzz_reader *find_reader(const char *name) {
  for (int i = 0; i < VM_FUZZ_NREADERS; i++)
    if (!strcmp(vm_fuzz_readers[i].dir, name)) return &vm_fuzz_readers[i];
  fprintf(stderr, "replay: unknown reader '%s'\n", name);
  return NULL;
}

int main(int argc, char **argv) {
  if (argc > 1 && !strcmp(argv[1], "-v")) {
    vm_fuzz_verbose = 1;
    argv++;
    argc--;
  }
  if (argc < 2) {
    fprintf(stderr,
            "usage: replay [-v] FUZZDIR [READER...] | replay [-v] --files READER FILE...\n");
    return 2;
  }
  if (!strcmp(argv[1], "--files")) {
    const vm_fuzz_reader *r = argc > 2 ? find_reader(argv[2]) : NULL;
    if (!r) return 2;
    int bad = 0;
    for (int i = 3; i < argc; i++) bad |= run_file(r, argv[i]);
    return bad;
  }
  const char *root = argv[1];
  int bad = 0;
  for (int i = 0; i < VM_FUZZ_NREADERS; i++) {
    const vm_fuzz_reader *r = &vm_fuzz_readers[i];
    if (argc > 2) {
      int want = 0;
      for (int a = 2; a < argc; a++) want |= !strcmp(argv[a], r->dir);
      if (!want) continue;
    }
    long counts[2];
    const char *kinds[2] = {"corpus", "regress"};
    for (int k = 0; k < 2; k++) {
      size_t pl = strlen(root) + strlen(r->dir) + 16;
      char *dir = malloc(pl);
      if (!dir) abort();
      snprintf(dir, pl, "%s/%s/%s", root, kinds[k], r->dir);
      counts[k] = run_dir(r, dir);
      free(dir);
    }
    if (counts[0] < 0 || counts[1] < 0) bad = 1;
    if (counts[0] == 0) {
      fprintf(stderr, "replay: %s: empty or missing corpus in %s/corpus/%s\n", r->dir, root,
              r->dir);
      bad = 1;
    }
    fprintf(stderr, "replay: %-6s %4ld corpus, %4ld regress files ok\n", r->dir, counts[0],
            counts[1] < 0 ? 0 : counts[1]);
  }
  return bad;
}
