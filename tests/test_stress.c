/* test_stress.c - the fast numerical stress cases (tests/stress/stress_cases.c at small sizes;
   `make stress` runs them at full size). One test per case; every row of the case is a check. */
#include "pdftrace.h"
#include "test.h"
#include "stress/stress.h"

#include <stdio.h>
#include <string.h>

static st_ctx g_ctx;
static int g_ready;

static void record(void *user, const char *cas, const char *metric, const char *bound, const char *result, int pass)
{
    test_ctx *t = (test_ctx *)user;
    CHECK(t, pass, "%s: %s: %s (bound %s)", cas, metric, result, bound);
}
static void run(test_ctx *t, void (*fn)(st_ctx *))
{
    int rows, failed;
    if (!g_ready) { st_init(&g_ctx, 0, record, NULL); g_ready = 1; }
    g_ctx.user = t;
    g_ctx.threads = 0;
    rows = g_ctx.rows;
    failed = g_ctx.failed;
    fn(&g_ctx);
    test_note(t, "%d rows, %d failed; family so far %ld z-comparisons at |z| <= %.2f", g_ctx.rows - rows,
              g_ctx.failed - failed, g_ctx.comparisons, g_ctx.z_bound);
}

static void scale_sweep(test_ctx *t) { run(t, st_scale_sweep); }
static void spawn_no_self_hits(test_ctx *t) { run(t, st_spawn); }
static void tiny_sphere_light(test_ctx *t) { run(t, st_tiny_light); }
static void sphere_light_point_limit(test_ctx *t) { run(t, st_point_light); }
static void watertight(test_ctx *t) { run(t, st_watertight); }
static void edges_and_tangents(test_ctx *t) { run(t, st_edges); }
static void light_geometry(test_ctx *t) { run(t, st_light_geometry); }
static void degenerate_input(test_ctx *t) { run(t, st_degenerate); }
static void sliver_triangles(test_ctx *t) { run(t, st_slivers); }
static void cornell_offset(test_ctx *t) { run(t, st_cornell_offset); }
static void guiding(test_ctx *t) { run(t, st_guiding); }
static void delta_lights(test_ctx *t) { run(t, st_delta_lights); }
static void environment(test_ctx *t) { run(t, st_environment); }
static void microfacet(test_ctx *t) { run(t, st_microfacet); }
static void plastic(test_ctx *t) { run(t, st_plastic); }
static void rough_dielectric(test_ctx *t) { run(t, st_rough_dielectric); }
static void family(test_ctx *t) { run(t, st_family); }

const test_case test_stress_cases[] = {
    TEST_CASE(scale_sweep),
    TEST_CASE(spawn_no_self_hits),
    TEST_CASE(tiny_sphere_light),
    TEST_CASE(sphere_light_point_limit),
    TEST_CASE(watertight),
    TEST_CASE(edges_and_tangents),
    TEST_CASE(light_geometry),
    TEST_CASE(degenerate_input),
    TEST_CASE(sliver_triangles),
    TEST_CASE(cornell_offset),
    TEST_CASE(guiding),
    TEST_CASE(delta_lights),
    TEST_CASE(environment),
    TEST_CASE(microfacet),
    TEST_CASE(plastic),
    TEST_CASE(rough_dielectric),
    TEST_CASE(family),
    TEST_END
};
