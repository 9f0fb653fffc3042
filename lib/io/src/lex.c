/* lib/io/src/lex.c: whitespace tokenizer with line numbers for text readers. */
#include "lex_private.h"

#include <ctype.h>
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

void vm_lex_init(vm_lex *lx, vm_ctx *ctx, const char *name, const void *buf, size_t len) {
  lx->ctx = ctx;
  lx->name = name;
  lx->p = (const char *)buf;
  lx->end = lx->p + len;
  lx->line = 1;
  lx->comment = 0;
}

int vm_lex_fail(vm_lex *lx, const char *fmt, ...) {
  char msg[700];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  return vm_error(lx->ctx, VM_ERR_FORMAT, "%s: line %lld: %s", lx->name, (long long)lx->line, msg);
}

int vm_lex_eof(vm_lex *lx) {
  for (;;) {
    while (lx->p < lx->end && (isspace((unsigned char)*lx->p) || *lx->p == 0)) {
      if (*lx->p == '\n') lx->line++;
      lx->p++;
    }
    if (lx->p < lx->end && lx->comment && *lx->p == lx->comment) {
      while (lx->p < lx->end && *lx->p != '\n') lx->p++;
      continue;
    }
    return lx->p >= lx->end;
  }
}

int vm_lex_word(vm_lex *lx, const char **s, size_t *n, const char *what) {
  if (vm_lex_eof(lx)) return vm_lex_fail(lx, "unexpected end of file, expected %s", what);
  const char *b = lx->p;
  while (lx->p < lx->end && !isspace((unsigned char)*lx->p) && *lx->p != 0) lx->p++;
  *s = b;
  *n = (size_t)(lx->p - b);
  return VM_OK;
}

int vm_tok_is(const char *s, size_t n, const char *word) {
  return strlen(word) == n && strncasecmp(s, word, n) == 0;
}

int vm_lex_peek_is(vm_lex *lx, const char *word) {
  if (vm_lex_eof(lx)) return 0;
  const char *q = lx->p;
  while (q < lx->end && !isspace((unsigned char)*q) && *q != 0) q++;
  return vm_tok_is(lx->p, (size_t)(q - lx->p), word);
}

int vm_lex_expect(vm_lex *lx, const char *word) {
  const char *s;
  size_t n;
  int st = vm_lex_word(lx, &s, &n, word);
  if (st) return st;
  if (!vm_tok_is(s, n, word))
    return vm_lex_fail(lx, "expected '%s', found '%.*s'", word, (int)(n > 40 ? 40 : n), s);
  return VM_OK;
}

int vm_lex_int(vm_lex *lx, int64_t *v, const char *what) {
  const char *s;
  size_t n;
  int st = vm_lex_word(lx, &s, &n, what);
  if (st) return st;
  char buf[32];
  if (n == 0 || n >= sizeof buf)
    return vm_lex_fail(lx, "%s: '%.*s' is not an integer", what, (int)(n > 40 ? 40 : n), s);
  memcpy(buf, s, n);
  buf[n] = 0;
  char *e;
  errno = 0;
  long long x = strtoll(buf, &e, 10);
  if (*e || errno) return vm_lex_fail(lx, "%s: '%s' is not an integer", what, buf);
  *v = x;
  return VM_OK;
}

int vm_lex_double(vm_lex *lx, double *v, const char *what) {
  const char *s;
  size_t n;
  int st = vm_lex_word(lx, &s, &n, what);
  if (st) return st;
  char buf[64];
  if (n == 0 || n >= sizeof buf)
    return vm_lex_fail(lx, "%s: '%.*s' is not a number", what, (int)(n > 40 ? 40 : n), s);
  memcpy(buf, s, n);
  buf[n] = 0;
  char *e;
  double x = strtod(buf, &e);
  if (*e) return vm_lex_fail(lx, "%s: '%s' is not a number", what, buf);
  *v = x;
  return VM_OK;
}

void vm_lex_line(vm_lex *lx, const char **s, size_t *n) {
  const char *b = lx->p;
  while (lx->p < lx->end && *lx->p != '\n') lx->p++;
  const char *e = lx->p;
  if (e > b && e[-1] == '\r') e--;
  *s = b;
  *n = (size_t)(e - b);
  if (lx->p < lx->end) {
    lx->p++;
    lx->line++;
  }
}
