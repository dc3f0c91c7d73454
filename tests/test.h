/* test.h - a tiny test framework for the pdftrace unit tests.

   A test is a function void name(test_ctx *t). It records failures with CHECK(t, cond, fmt, ...),
   which returns the truth of cond (so a test can stop early with `if (!CHECK(...)) goto done;`)
   and keeps the first failure's reason and location. test_note appends free text to the line
   printed for a passing test. test_skip marks the test skipped (it could not run here: a
   library not compiled in, a missing platform feature): it prints `SKIP name: reason` and is
   counted as skipped, never as passed; a skipped test whose CHECKs failed still fails. Each
   section file exports a table of test_case terminated by {NULL, NULL}; test_main.c lists the
   sections. */
#ifndef PDFTRACE_TEST_H
#define PDFTRACE_TEST_H

#include <stddef.h>

#if defined(__GNUC__) || defined(__clang__)
#define TEST_PRINTF(fmt_index, first_arg) __attribute__((format(printf, fmt_index, first_arg)))
#else
#define TEST_PRINTF(fmt_index, first_arg)
#endif

typedef struct test_ctx {
    int failures;          /* CHECKs that failed */
    int checks;            /* CHECKs evaluated */
    char reason[768];      /* first failure */
    const char *file;      /* location of the first failure */
    int line;
    char notes[1024];      /* details printed with PASS (and with FAIL, after the reason) */
    char more[5][320];     /* the next few failures, printed below the FAIL line */
    int skipped;           /* test_skip was called */
    char skip_reason[256]; /* its reason (the first call's) */
} test_ctx;

typedef void (*test_fn)(test_ctx *t);

typedef struct test_case {
    const char *name;
    test_fn fn;
} test_case;

#define TEST_CASE(fn) { #fn, fn }
#define TEST_END { NULL, NULL }

/* Records one check. Returns ok. fmt describes the failure. */
int test_check_(test_ctx *t, int ok, const char *file, int line, const char *fmt, ...) TEST_PRINTF(5, 6);
/* Appends "; text" (or "text" first) to the notes. */
void test_note(test_ctx *t, const char *fmt, ...) TEST_PRINTF(2, 3);
/* Marks the test skipped; fmt says why. The test should return after it. */
void test_skip(test_ctx *t, const char *fmt, ...) TEST_PRINTF(2, 3);

#define CHECK(t, cond, ...) test_check_((t), (cond) ? 1 : 0, __FILE__, __LINE__, __VA_ARGS__)
/* The same, for helpers that report at their caller's location. */
#define CHECK_AT(t, file, line, cond, ...) test_check_((t), (cond) ? 1 : 0, (file), (line), __VA_ARGS__)

/* The sections (one file each). */
extern const test_case test_math_cases[];
extern const test_case test_rng_cases[];
extern const test_case test_pdf_cases[];
extern const test_case test_geometry_cases[];
extern const test_case test_materials_cases[];
extern const test_case test_bvh_cases[];
extern const test_case test_render_cases[];
extern const test_case test_adaptive_cases[]; /* adaptive sampling and PT_SKIP_* switches */
extern const test_case test_sampler_cases[];  /* pt_render_desc.sampler: PT_SAMPLER_SOBOL */
extern const test_case test_split_cases[];    /* splitting a render: pt_render_desc.split_parts, pt_film_add */
extern const test_case test_guide_cases[];    /* path guiding: pt_guide, PT_PDF_GUIDE, pt_render_desc.guiding */
extern const test_case test_output_cases[];
extern const test_case test_exr_cases[];    /* OpenEXR (one skipped test without PDFTRACE_OPENEXR) */
extern const test_case test_embree_cases[]; /* backends; Embree's tests with PDFTRACE_EMBREE */
extern const test_case test_analytic_cases[];
extern const test_case test_lights_cases[];  /* point, spot and directional lights */
extern const test_case test_regress_cases[];
extern const test_case test_origin_cases[];  /* scenes far from (0, 0, 0) */
extern const test_case test_stress_cases[];  /* numerical stress (tests/stress/, fast sizes) */
extern const test_case test_scenefile_cases[]; /* pdftrace_scene.h: pt_obj_load, pt_scene_add_obj */
extern const test_case test_pov_cases[];       /* pdftrace_scene.h: the POV-Ray exporter against hostile scenes */
extern const test_case test_mitsuba_cases[];   /* pdftrace_scene.h: the Mitsuba 3 exporter */
extern const test_case test_textures_cases[]; /* (u, v) and image textures */
extern const test_case test_microfacet_cases[]; /* the rough conductor (GGX, visible normals) */
extern const test_case test_plastic_cases[];    /* the rough plastic (Mitsuba's roughplastic) */
extern const test_case test_suite_cases[];  /* last: summaries over the whole run */

#endif
