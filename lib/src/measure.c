/* lib/src/measure.c: distortion measure interface (placeholder until the core lands). */
typedef int vm_measure_placeholder;
