/* lib/io/src/lex_private.h: a whitespace tokenizer over an in-memory text
 * buffer with line tracking, shared by the text readers. The buffer need not
 * be NUL-terminated. Errors are recorded as "name: line N: what". */
#ifndef VARMESH_LEX_PRIVATE_H
#define VARMESH_LEX_PRIVATE_H

#include <stddef.h>
#include <stdint.h>

#include "varmesh/ctx.h"

typedef struct vm_lex {
  vm_ctx *ctx;
  const char *name;
  const char *p, *end;
  int64_t line; /* 1-based line of p */
  char comment; /* lines starting (after blanks) with this are skipped; 0 none */
} vm_lex;

void vm_lex_init(vm_lex *lx, vm_ctx *ctx, const char *name, const void *buf, size_t len);
/* Skip blanks, newlines and comment lines; nonzero if nothing is left. */
int vm_lex_eof(vm_lex *lx);
/* Next token (not NUL-terminated). At end of input: error naming `what`. */
int vm_lex_word(vm_lex *lx, const char **s, size_t *n, const char *what);
/* Compare the next token to `word` (case-insensitive) without consuming it. */
int vm_lex_peek_is(vm_lex *lx, const char *word);
/* Consume the next token, which must equal `word` (case-insensitive). */
int vm_lex_expect(vm_lex *lx, const char *word);
/* Integers reject trailing garbage and overflow; doubles accept nan/inf
 * (callers reject non-finite values where they matter). */
int vm_lex_int(vm_lex *lx, int64_t *v, const char *what);
int vm_lex_double(vm_lex *lx, double *v, const char *what);
/* The rest of the current line (without the newline), consumed. */
void vm_lex_line(vm_lex *lx, const char **s, size_t *n);
/* Record "name: line N: <message>" as VM_ERR_FORMAT and return it. */
int vm_lex_fail(vm_lex *lx, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
/* Token equality helper (case-insensitive). */
int vm_tok_is(const char *s, size_t n, const char *word);

#endif
