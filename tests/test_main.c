#define _POSIX_C_SOURCE 200809L
/* test_main.c - the pdftrace unit-test runner.

   Usage: test_runner [FILTER]... [--skip SUBSTRING]...
   Runs every test whose "section.name" contains one of the FILTERs (all tests without one) and
   none of the --skip substrings ("--skip pdf." leaves out the pdf section). Prints one line
   per test, "PASS name (details)", "SKIP name: reason (details)" or "FAIL name: reason
   (file:line)", a summary per section, and as its last line "N passed, M failed, K skipped".
   A skipped test is not a pass; one with failed checks is a failure. Exit code 0 iff no test
   failed.

   This file compiles the library implementation (PDFTRACE_IMPLEMENTATION). */
#define PDFTRACE_IMPLEMENTATION
#define PDFTRACE_SCENE_IMPLEMENTATION /* the embree and sampler sections load the scenes of scenes/ */
#include "pdftrace_scene.h"
#ifdef PDFTRACE_OPENEXR /* make OPENEXR=1: the EXR header of the family */
#define PDFTRACE_EXR_IMPLEMENTATION
#include "pdftrace_exr.h"
#endif

#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "test.h"
/* The internals section calls the implementation's static functions and compares them bit for
   bit, so it is compiled as the implementation is: without FMA contraction (pdftrace.h). */
PT__CONTRACT_OFF
#include "test_internals.h"
PT__CONTRACT_RESTORE

int test_check_(test_ctx *t, int ok, const char *file, int line, const char *fmt, ...)
{
    t->checks++;
    if (!ok) {
        va_list ap;
        va_start(ap, fmt);
        if (t->failures == 0) {
            vsnprintf(t->reason, sizeof t->reason, fmt, ap);
            t->file = file;
            t->line = line;
        } else if (t->failures <= 5) {
            char *dst = t->more[t->failures - 1];
            int n = vsnprintf(dst, sizeof t->more[0], fmt, ap);
            if (n >= 0 && (size_t)n < sizeof t->more[0])
                snprintf(dst + n, sizeof t->more[0] - (size_t)n, " (%s:%d)", file, line);
        }
        va_end(ap);
        t->failures++;
    }
    return ok;
}

void test_note(test_ctx *t, const char *fmt, ...)
{
    size_t len = strlen(t->notes);
    va_list ap;
    if (len + 3 >= sizeof t->notes) return;
    if (len > 0) {
        t->notes[len++] = ';';
        t->notes[len++] = ' ';
        t->notes[len] = '\0';
    }
    va_start(ap, fmt);
    vsnprintf(t->notes + len, sizeof t->notes - len, fmt, ap);
    va_end(ap);
}

void test_skip(test_ctx *t, const char *fmt, ...)
{
    va_list ap;
    if (t->skipped) return;
    t->skipped = 1;
    va_start(ap, fmt);
    vsnprintf(t->skip_reason, sizeof t->skip_reason, fmt, ap);
    va_end(ap);
}

static double now_seconds(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_MONOTONIC, &ts) != 0) return (double)clock() / CLOCKS_PER_SEC;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct section {
    const char *name;
    const test_case *cases;
} section;

/* Whether the command line selects test `full`: it contains a filter (or there is none) and no
   --skip substring. */
static int selected(const char *full, int argc, char **argv)
{
    int i, filters = 0, matched = 0;
    for (i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--skip") == 0) {
            if (i + 1 < argc && strstr(full, argv[i + 1])) return 0;
            i++;
        } else {
            filters++;
            matched |= strstr(full, argv[i]) != NULL;
        }
    }
    return filters == 0 || matched;
}

int main(int argc, char **argv)
{
    static const section sections[] = {
        { "math", test_math_cases },
        { "rng", test_rng_cases },
        { "pdf", test_pdf_cases },
        { "geometry", test_geometry_cases },
        { "materials", test_materials_cases },
        { "microfacet", test_microfacet_cases },
        { "plastic", test_plastic_cases },
        { "textures", test_textures_cases },
        { "bvh", test_bvh_cases },
        { "render", test_render_cases },
        { "adaptive", test_adaptive_cases },
        { "sampler", test_sampler_cases },
        { "split", test_split_cases },
        { "guide", test_guide_cases },
        { "output", test_output_cases },
        { "exr", test_exr_cases },
        { "embree", test_embree_cases },
        { "analytic", test_analytic_cases },
        { "lights", test_lights_cases },
        { "internals", test_internals_cases },
        { "regress", test_regress_cases },
        { "origin", test_origin_cases },
        { "stress", test_stress_cases },
        { "scenefile", test_scenefile_cases },
        { "pov", test_pov_cases },
        { "mitsuba", test_mitsuba_cases },
        { "suite", test_suite_cases },
    };
    int passed = 0, failed = 0, skipped = 0;
    size_t s;
    double start = now_seconds();

    if (argc > 1 && strcmp(argv[argc - 1], "--skip") == 0) {
        fprintf(stderr, "usage: %s [FILTER]... [--skip SUBSTRING]...: --skip needs a substring\n", argv[0]);
        return 2;
    }
    setvbuf(stdout, NULL, _IOLBF, 0);
    for (s = 0; s < sizeof sections / sizeof sections[0]; s++) {
        const test_case *c;
        int sp = 0, sf = 0, ss = 0;
        double s0 = now_seconds();
        for (c = sections[s].cases; c->name != NULL; c++) {
            char full[256];
            test_ctx t;
            double t0, dt;
            snprintf(full, sizeof full, "%s.%s", sections[s].name, c->name);
            if (!selected(full, argc, argv)) continue;
            memset(&t, 0, sizeof t);
            t0 = now_seconds();
            c->fn(&t);
            dt = now_seconds() - t0;
            if (t.failures == 0 && t.skipped) {
                printf("SKIP %s: %s (%s%s%.2f s)\n", full, t.skip_reason, t.notes, t.notes[0] ? "; " : "", dt);
                ss++;
            } else if (t.failures == 0) {
                printf("PASS %s (%s%s%.2f s)\n", full, t.notes, t.notes[0] ? "; " : "", dt);
                sp++;
            } else {
                int k;
                printf("FAIL %s: %s (%s:%d)\n", full, t.reason, t.file, t.line);
                for (k = 0; k < 5 && k + 1 < t.failures; k++) printf("     also: %s\n", t.more[k]);
                printf("     [%d of %d checks failed; %s%s%.2f s]\n", t.failures, t.checks, t.notes,
                       t.notes[0] ? "; " : "", dt);
                sf++;
            }
        }
        if (sp + sf + ss > 0)
            printf("-- section %s: %d passed, %d failed, %d skipped (%.2f s)\n", sections[s].name, sp, sf, ss,
                   now_seconds() - s0);
        passed += sp;
        failed += sf;
        skipped += ss;
    }
    printf("-- total time %.2f s\n", now_seconds() - start);
    printf("%d passed, %d failed, %d skipped\n", passed, failed, skipped);
    return failed == 0 ? 0 : 1;
}
