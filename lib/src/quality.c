/* lib/src/quality.c: quality figures. */
typedef int vm_quality_placeholder;
