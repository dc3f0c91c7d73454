/* Fuzz harness entry points (tests/fuzz/harness.c). Each takes one input and returns 0; a
   check that fails prints what and where and calls abort(), so libFuzzer and the corpus
   replay (tests/fuzz/replay.c) both see it as a crash. */
#ifndef PT_FUZZ_HARNESS_H
#define PT_FUZZ_HARNESS_H

#include <stddef.h>
#include <stdint.h>

/* Scene text -> pt_scenefile_parse -> pt_scenefile_build -> a tiny render (at most 8x8
   pixels, 1 spp, depth <= 6, one thread) plus BVH-versus-brute-force rays. Meshes are read
   from PT_FUZZ_SCENE_DIR (default "scenes", relative to the repository root); mesh paths
   with '/' are skipped so fuzzed input cannot read other files (/dev/stdin would hang). */
int pt_fuzz_scene(const uint8_t *data, size_t size);
/* Scene text -> pt_scenefile_parse (the scene's name set to the input's first bytes) ->
   pt_scenefile_write_pov to a temporary file: every scene the build refuses is refused with a
   message and no file; an exported text passes tests/fuzz/pov_check.h (no nan/inf, no
   directive or string from input, comments whole lines, braces balanced). Then the same for
   pt_scenefile_export_mitsuba, whose XML must pass tests/fuzz/mitsuba_check.h. */
int pt_fuzz_pov(const uint8_t *data, size_t size);
/* OBJ text -> pt_obj_parse -> a committed scene with the mesh -> rays. */
int pt_fuzz_obj(const uint8_t *data, size_t size);
#ifdef PDFTRACE_OPENEXR
/* EXR bytes -> pt_read_exr_memory (images above 2^20 pixels refused by the harness build). */
int pt_fuzz_exr(const uint8_t *data, size_t size);
#endif

/* The input being run, named in failure messages (the replay sets it; may be NULL). */
extern const char *pt_fuzz_input_name;
/* What the input must do, from its name (the replay sets it): 1 "accept-*": the loader must
   succeed; -1 "reject-*": it must fail with a message; 0: either. */
extern int pt_fuzz_expect;
/* Non-zero: one line per input on stderr saying what happened (replay: PT_FUZZ_VERBOSE=1). */
extern int pt_fuzz_verbose;

#endif
