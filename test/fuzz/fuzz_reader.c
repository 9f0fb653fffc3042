/* test/fuzz/fuzz_reader.c: libFuzzer entry point for one mesh reader, chosen
 * at compile time (-DVM_FUZZ_READER='"vtk"', a corpus folder name), reading
 * through vm_mesh_read_memory and checking the reader's contract. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz_common.h"

#ifndef VM_FUZZ_READER
#error "compile with -DVM_FUZZ_READER='\"<reader>\"', e.g. '\"vtk\"'"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  static const vm_fuzz_reader *r;
  if (!r) {
    for (int i = 0; i < VM_FUZZ_NREADERS; i++)
      if (!strcmp(vm_fuzz_readers[i].dir, VM_FUZZ_READER)) r = &vm_fuzz_readers[i];
    VM_FUZZ_REQUIRE(r != NULL, "unknown reader " VM_FUZZ_READER);
  }
  vm_fuzz_one(r, data, size);
  return 0;
}
