/* libFuzzer entry point for one harness of tests/fuzz/harness.c, chosen at compile time:
   clang -fsanitize=fuzzer,address,undefined -DPT_FUZZ_ENTRY=pt_fuzz_scene ... (make fuzz).
   With PT_FUZZ_FPTRAP=1 in the environment (glibc), FE_INVALID and FE_DIVBYZERO trap, so an
   invalid operation is a crash (SIGFPE) that libFuzzer saves and minimises. */
#define _GNU_SOURCE 1
#include <fenv.h>
#include <stdlib.h>

#include "harness.h"

#ifndef PT_FUZZ_ENTRY
#error "define PT_FUZZ_ENTRY (pt_fuzz_scene, pt_fuzz_obj or pt_fuzz_exr)"
#endif

int LLVMFuzzerInitialize(int *argc, char ***argv);
int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    const char *e = getenv("PT_FUZZ_FPTRAP");
    (void)argc;
    (void)argv;
#if defined(__GLIBC__) && defined(FE_INVALID) && defined(FE_DIVBYZERO)
    if (e && e[0] == '1') feenableexcept(FE_INVALID | FE_DIVBYZERO);
#else
    (void)e;
#endif
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return PT_FUZZ_ENTRY(data, size); }
