/* libFuzzer entry point for one harness of tests/fuzz/harness.c, chosen at compile time:
   clang -fsanitize=fuzzer,address,undefined -DPT_FUZZ_ENTRY=pt_fuzz_scene ... (make fuzz). */
#include "harness.h"

#ifndef PT_FUZZ_ENTRY
#error "define PT_FUZZ_ENTRY (pt_fuzz_scene, pt_fuzz_obj or pt_fuzz_exr)"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return PT_FUZZ_ENTRY(data, size); }
