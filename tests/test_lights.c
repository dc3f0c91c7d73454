/* test_lights.c - point, spot and directional lights (pt_scene_add_light, section 4 of pdftrace.h).

   Delta lights have no density over directions, so there is no chi-square test of their sampling:
   what is tested is the estimate. Analytic images (tu_plane_scene of test_util.h): the Lambertian
   plane (rho = 0.5) under each kind of light, direct light only, every strategy, compared per pixel
   with the footprint mean of rho E / pi, E = I falloff cos(theta) / d^2 (point, spot) or E0 cos(theta)
   (directional). A delta light's estimate at a plane point has no variance (one shadow ray, always
   unoccluded), so a pixel's variance is that of E over its footprint only; the test is the same
   z-test as test_analytic.c's (alpha = 0.001 per pixel, at least 99.5 % of the pixels), and the image
   mean within 3.5 standard errors. Three point lights of different powers test the pick by power; a
   point light beside a sphere light tests the two next-event estimates added together, under every
   strategy (MATERIAL and MIXTURE reach delta lights only through their own estimate).
   False-failure rate: the image mean within 3.5 standard errors fails with probability 4.7e-4 per
   image; 21 images here: ~1 %, to which the pixel tests (as test_analytic.c's) add < 1e-4. */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define IMAGE_W 32
#define IMAGE_H 32
#define PIXEL_ALPHA 0.001
#define ACCEPT_FRACTION 0.995
#define IMAGE_Z 3.5

static pt_light_desc desc_of(const tu_light *L, double I)
{
    pt_light_desc d;
    memset(&d, 0, sizeof d);
    d.type = L->kind == TU_POINT ? PT_LIGHT_POINT : L->kind == TU_SPOT ? PT_LIGHT_SPOT : PT_LIGHT_DIRECTIONAL;
    d.position = dv_to(L->p0);
    d.direction = dv_to(L->p1);
    d.intensity = pt_v3((float)I, (float)I, (float)I);
    d.cutoff_angle = (float)L->cutoff;
    d.beam_width = (float)L->beam;
    return d;
}

/* The plane scene with the lights listed (delta lights and at most one sphere light). */
static int lights_scene(tu_plane_scene *ps, const tu_light *lights, const double *intensity, int n)
{
    int i, floor_m, rc;
    memset(ps, 0, sizeof *ps);
    ps->rho = 0.5;
    ps->scene = pt_scene_create();
    if (!ps->scene) return 0;
    floor_m = pt_scene_add_lambertian(ps->scene, pt_v3(0.5f, 0.5f, 0.5f));
    rc = pt_scene_add_quad(ps->scene, pt_v3(-20, 0, -20), pt_v3(0, 0, 40), pt_v3(40, 0, 0), floor_m);
    for (i = 0; i < n && rc >= 0; i++) {
        ps->light[i] = lights[i];
        ps->radiance[i] = intensity[i];
        if (lights[i].kind == TU_SPHERE) {
            int m = pt_scene_add_emitter(ps->scene, pt_v3((float)intensity[i], (float)intensity[i], (float)intensity[i]), 0);
            rc = pt_scene_add_sphere(ps->scene, dv_to(lights[i].p0), (float)lights[i].radius, m);
        } else {
            pt_light_desc d = desc_of(&lights[i], intensity[i]);
            rc = pt_scene_add_light(ps->scene, &d);
        }
    }
    ps->light_count = n;
    if (rc < 0 || pt_scene_commit(ps->scene) != PT_OK) return 0;
    return tu_plane_scene_finish(ps, IMAGE_W, IMAGE_H);
}

/* spp: per strategy, MIS, MATERIAL, LIGHT, MIXTURE (MATERIAL finds a shaped light only by hitting it) */
static void compare_every_strategy(test_ctx *t, const char *name, const tu_light *lights, const double *intensity, int n,
                                   const int *spp, uint64_t seed)
{
    tu_plane_scene ps;
    int strat;
    double zpix = tu_z_two_sided(PIXEL_ALPHA);
    if (!CHECK(t, lights_scene(&ps, lights, intensity, n), "%s: scene setup failed", name)) {
        tu_plane_scene_destroy(&ps);
        return;
    }
    for (strat = 0; strat < 4; strat++) {
        pt_render_desc d;
        tu_image_stats st;
        memset(&d, 0, sizeof d);
        d.samples_per_pixel = spp[strat];
        d.strategy = (pt_strategy)strat;
        d.light_weight = 0.5f;
        d.seed = seed + (uint64_t)strat;
        tu_plane_render_compare(&ps, &d, zpix, &st);
        if (!CHECK(t, st.rc == PT_OK, "%s, strategy %d: pt_render returned %d", name, strat, st.rc)) continue;
        CHECK(t, st.nonfinite == 0, "%s, strategy %d: %llu non-finite samples", name, strat,
              (unsigned long long)st.nonfinite);
        CHECK(t, st.accepted >= ACCEPT_FRACTION * st.pixels,
              "%s, strategy %d: only %d of %d pixels pass the z-test at alpha %.3g; mean rel error %+.2e, mean z %+.2f",
              name, strat, st.accepted, st.pixels, PIXEL_ALPHA, st.mean_rel, st.mean_z);
        CHECK(t, fabs(st.image_z) <= IMAGE_Z, "%s, strategy %d: image mean %.7f +- %.2g, reference %.7f (z = %+.2f)", name,
              strat, st.image_mean, st.image_se, st.image_ref, st.image_z);
        CHECK(t, st.image_ref > 1e-3, "%s: the reference image is black (%.3g): the test would prove nothing", name,
              st.image_ref);
        if (strat == 0) test_note(t, "MIS: %.2f %% accepted, mean rel err %+.1e, image z %+.2f", 100.0 * st.accepted / st.pixels,
                                  st.mean_rel, st.image_z);
    }
    tu_plane_scene_destroy(&ps);
}

/* Samples per pixel: one delta light has no variance beyond the footprint's; three lights picked by
   power (the weakest picked with probability 1/21) need ~50 picks of it per pixel for the t statistic
   to be near normal; a shaped light under MATERIAL needs >= 100 hits per pixel (test_analytic.c). */
static const int spp_delta[4] = {64, 64, 64, 64};
static const int spp_spot[4] = {256, 256, 256, 256}; /* pixels the cone's edge barely enters need enough
                                                        samples to meet it at least once */
static const int spp_pick[4] = {1024, 1024, 1024, 1024};
static const int spp_shaped[4] = {256, 1024, 128, 256};

static tu_light point_at(double x, double y, double z)
{
    tu_light L;
    memset(&L, 0, sizeof L);
    L.kind = TU_POINT;
    L.p0 = dv(x, y, z);
    return L;
}

static void image_point_light(test_ctx *t)
{
    tu_light L = point_at(0.2, 0.8, -0.1);
    double I = 2.0;
    compare_every_strategy(t, "point", &L, &I, 1, spp_delta, 101);
}

static void image_spot_light(test_ctx *t)
{
    /* tilted, so that the beam, the falloff and the dark outside all fall inside the image */
    tu_light L;
    double I = 3.0, len;
    memset(&L, 0, sizeof L);
    L.kind = TU_SPOT;
    L.p0 = dv(-0.2, 0.9, 0.1);
    L.p1 = dv(0.25, -1.0, 0.1);
    len = sqrt(ddot(L.p1, L.p1));
    L.p1 = dscale(L.p1, 1.0 / len);
    L.cutoff = 25.0;
    L.beam = 12.0;
    compare_every_strategy(t, "spot", &L, &I, 1, spp_spot, 202);
}

static void image_directional_light(test_ctx *t)
{
    tu_light L;
    double E = 1.5, len;
    memset(&L, 0, sizeof L);
    L.kind = TU_DIRECTIONAL;
    L.p1 = dv(0.4, -1.0, 0.3);
    len = sqrt(ddot(L.p1, L.p1));
    L.p1 = dscale(L.p1, 1.0 / len);
    compare_every_strategy(t, "directional", &L, &E, 1, spp_delta, 303);
}

/* Three point lights whose powers differ 1 : 4 : 16: the pick by power keeps the sum unbiased. */
static void image_three_point_lights(test_ctx *t)
{
    tu_light L[3];
    double I[3] = {0.25, 1.0, 4.0};
    L[0] = point_at(-0.5, 0.6, 0.0);
    L[1] = point_at(0.4, 0.9, 0.3);
    L[2] = point_at(0.0, 2.5, -0.4);
    compare_every_strategy(t, "three points", L, I, 3, spp_pick, 404);
}

/* A sphere light and a point light: the shaped light's estimate (each strategy's own) plus the delta
   light's. The point light stays below the sphere, so neither shadows the other on the plane. */
static void image_point_beside_sphere_light(test_ctx *t)
{
    tu_light L[2];
    double I[2] = {1.0, 0.5};
    memset(L, 0, sizeof L);
    L[0].kind = TU_SPHERE;
    L[0].p0 = dv(0.3, 2.2, 0.1);
    L[0].radius = 1.0;
    L[1] = point_at(-1.5, 1.1, 0.0);
    compare_every_strategy(t, "sphere + point", L, I, 2, spp_shaped, 505);
}

/* 24 small quad lights of different radiance over the plane: with 16 or more emitters the light for
   next-event estimation is picked by the light tree, and a scattered ray that hits a light is
   weighted with the tree's probability of that light (MIS). Every strategy against the sum of
   Lambert's formula over the lights; and the same with the tree switched off (PT_SKIP_LIGHT_TREE). */
static void image_light_tree(test_ctx *t)
{
    tu_plane_scene ps;
    int i, strat, general;
    double zpix = tu_z_two_sided(PIXEL_ALPHA);
    memset(&ps, 0, sizeof ps);
    ps.rho = 0.5;
    ps.scene = pt_scene_create();
    {
        int floor_m = pt_scene_add_lambertian(ps.scene, pt_v3(0.5f, 0.5f, 0.5f)), rc;
        rc = pt_scene_add_quad(ps.scene, pt_v3(-20, 0, -20), pt_v3(0, 0, 40), pt_v3(40, 0, 0), floor_m);
        for (i = 0; i < 24 && rc >= 0; i++) {
            tu_light *L = &ps.light[i];
            float Le = 0.5f + 0.25f * (float)(i % 5);
            int m = pt_scene_add_emitter(ps.scene, pt_v3(Le, Le, Le), 0);
            memset(L, 0, sizeof *L);
            L->kind = TU_QUAD; /* u x v = -y: faces the plane; heights 1.2 .. 2.3 */
            L->p0 = dv(-1.8 + 0.6 * (i % 6), 1.2 + 0.15 * (i % 4) + 0.3 * (i / 12), -1.4 + 0.7 * (i / 6));
            L->p1 = dv(0.25, 0, 0);
            L->p2 = dv(0, 0, 0.25);
            ps.radiance[i] = Le;
            rc = pt_scene_add_quad(ps.scene, dv_to(L->p0), dv_to(L->p1), dv_to(L->p2), m);
        }
        ps.light_count = 24;
        if (!CHECK(t, rc >= 0 && pt_scene_commit(ps.scene) == PT_OK && tu_plane_scene_finish(&ps, IMAGE_W, IMAGE_H),
                   "scene: %s", pt_scene_error_message(ps.scene))) {
            tu_plane_scene_destroy(&ps);
            return;
        }
    }
    for (general = 0; general < 2; general++)
        for (strat = 0; strat < 4; strat++) {
            pt_render_desc d;
            tu_image_stats st;
            if (general && strat != PT_STRATEGY_MIS) continue;
            memset(&d, 0, sizeof d);
            d.samples_per_pixel = strat == PT_STRATEGY_MATERIAL ? 1024 : 128;
            d.strategy = (pt_strategy)strat;
            d.light_weight = 0.5f;
            d.seed = 707 + (uint64_t)strat + 10u * (uint64_t)general;
            d.disable_skips = general ? PT_SKIP_LIGHT_TREE : 0u;
            tu_plane_render_compare(&ps, &d, zpix, &st);
            if (!CHECK(t, st.rc == PT_OK, "strategy %d: pt_render returned %d", strat, st.rc)) continue;
            CHECK(t, st.nonfinite == 0, "strategy %d: %llu non-finite samples", strat, (unsigned long long)st.nonfinite);
            CHECK(t, st.accepted >= ACCEPT_FRACTION * st.pixels,
                  "%s, strategy %d: only %d of %d pixels pass the z-test; mean rel error %+.2e, mean z %+.2f",
                  general ? "by power" : "tree", strat, st.accepted, st.pixels, st.mean_rel, st.mean_z);
            CHECK(t, fabs(st.image_z) <= IMAGE_Z, "%s, strategy %d: image mean %.7f +- %.2g, reference %.7f (z = %+.2f)",
                  general ? "by power" : "tree", strat, st.image_mean, st.image_se, st.image_ref, st.image_z);
            if (strat == 0) test_note(t, "%s MIS: %.2f %% accepted, image z %+.2f", general ? "by power" : "tree",
                                      100.0 * st.accepted / st.pixels, st.image_z);
        }
    tu_plane_scene_destroy(&ps);
}

static int add_expect_error(pt_scene *s, const pt_light_desc *d, const char *want)
{
    int rc = pt_scene_add_light(s, d);
    return rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), want) != NULL;
}

/* Misuse returns PT_ERROR_INVALID_ARGUMENT with a message naming the field; nothing is added. */
static void api_errors(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_light_desc d, ok;
    pt_scene_info info;
    memset(&ok, 0, sizeof ok);
    ok.type = PT_LIGHT_SPOT;
    ok.position = pt_v3(0, 1, 0);
    ok.direction = pt_v3(0, -1, 0);
    ok.intensity = pt_v3(1, 1, 1);
    CHECK(t, pt_scene_add_light(NULL, &ok) == PT_ERROR_INVALID_ARGUMENT, "NULL scene accepted");
    CHECK(t, add_expect_error(s, NULL, "NULL"), "NULL desc: %s", pt_scene_error_message(s));
    d = ok; d.type = (pt_light_type)7;
    CHECK(t, add_expect_error(s, &d, "type"), "bad type: %s", pt_scene_error_message(s));
    d = ok; d.intensity = pt_v3(1, -1, 1);
    CHECK(t, add_expect_error(s, &d, "intensity"), "negative intensity: %s", pt_scene_error_message(s));
    d = ok; d.intensity = pt_v3(0, 0, 0);
    CHECK(t, add_expect_error(s, &d, "intensity"), "black intensity: %s", pt_scene_error_message(s));
    d = ok; d.intensity.y = NAN;
    CHECK(t, add_expect_error(s, &d, "intensity"), "NaN intensity: %s", pt_scene_error_message(s));
    d = ok; d.position.x = INFINITY;
    CHECK(t, add_expect_error(s, &d, "position"), "infinite position: %s", pt_scene_error_message(s));
    d = ok; d.position.z = 1e30f;
    CHECK(t, add_expect_error(s, &d, "position"), "position 1e30: %s", pt_scene_error_message(s));
    d = ok; d.direction = pt_v3(0, 0, 0);
    CHECK(t, add_expect_error(s, &d, "direction"), "zero direction: %s", pt_scene_error_message(s));
    d = ok; d.type = PT_LIGHT_DIRECTIONAL; d.direction = pt_v3(0, 0, 0);
    CHECK(t, add_expect_error(s, &d, "direction"), "zero directional direction: %s", pt_scene_error_message(s));
    d = ok; d.cutoff_angle = 91.0f;
    CHECK(t, add_expect_error(s, &d, "cutoff_angle"), "cutoff 91: %s", pt_scene_error_message(s));
    d = ok; d.cutoff_angle = -5.0f;
    CHECK(t, add_expect_error(s, &d, "cutoff_angle"), "cutoff -5: %s", pt_scene_error_message(s));
    d = ok; d.cutoff_angle = 10.0f; d.beam_width = 11.0f;
    CHECK(t, add_expect_error(s, &d, "beam_width"), "beam > cutoff: %s", pt_scene_error_message(s));
    d = ok; d.beam_width = NAN;
    CHECK(t, add_expect_error(s, &d, "beam_width"), "NaN beam: %s", pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    CHECK(t, info.delta_light_count == 0, "%u lights were added by failed calls", (unsigned)info.delta_light_count);
    /* a point light ignores direction and cone: any values */
    d = ok; d.type = PT_LIGHT_POINT; d.direction = pt_v3(0, 0, 0); d.cutoff_angle = -1.0f;
    CHECK(t, pt_scene_add_light(s, &d) == 0, "a point light with an unused zero direction was refused: %s",
          pt_scene_error_message(s));
    CHECK(t, pt_scene_get_light(s, 1, &d) == PT_ERROR_INVALID_ARGUMENT, "pt_scene_get_light accepted id 1 of 1");
    CHECK(t, pt_scene_get_light(s, -1, &d) == PT_ERROR_INVALID_ARGUMENT, "pt_scene_get_light accepted id -1");
    CHECK(t, pt_scene_get_light(s, 0, NULL) == PT_ERROR_INVALID_ARGUMENT, "pt_scene_get_light accepted NULL");
    pt_scene_destroy(s);
}

/* Defaults resolved, the transform applied to position and direction, the feature bit and count. */
static void defaults_and_transform(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_light_desc d, got;
    pt_transform xf = pt_transform_translate(pt_v3(1, 2, 3));
    pt_transform r = pt_transform_rotate(pt_v3(0, 0, 1), 90.0f);
    pt_scene_info info;
    int m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    memset(&d, 0, sizeof d);
    d.type = PT_LIGHT_SPOT;
    d.position = pt_v3(0, 1, 0);
    d.direction = pt_v3(0, -2, 0);
    d.intensity = pt_v3(1, 2, 3);
    pt_scene_add_quad(s, pt_v3(-1, 0, -1), pt_v3(0, 0, 2), pt_v3(2, 0, 0), m);
    CHECK(t, pt_scene_add_light(s, &d) == 0, "spot: %s", pt_scene_error_message(s));
    CHECK(t, pt_scene_get_light(s, 0, &got) == PT_OK && got.cutoff_angle == 20.0f && got.beam_width == 15.0f &&
                 got.direction.y == -1.0f,
          "defaults: cutoff %g beam %g direction y %g (want 20, 15, -1)", (double)got.cutoff_angle, (double)got.beam_width,
          (double)got.direction.y);
    xf = pt_transform_mul(xf, r);
    pt_scene_set_transform(s, &xf);
    CHECK(t, pt_scene_add_light(s, &d) == 1, "transformed spot: %s", pt_scene_error_message(s));
    pt_scene_set_transform(s, NULL);
    pt_scene_get_light(s, 1, &got);
    /* rotate +90 about z: (0, 1, 0) -> (-1, 0, 0), then + (1, 2, 3) */
    CHECK(t, fabsf(got.position.x - 0.0f) < 1e-5f && fabsf(got.position.y - 2.0f) < 1e-5f &&
                 fabsf(got.position.z - 3.0f) < 1e-5f && fabsf(got.direction.x - 1.0f) < 1e-5f,
          "transformed: position (%g, %g, %g) direction (%g, %g, %g)", (double)got.position.x, (double)got.position.y,
          (double)got.position.z, (double)got.direction.x, (double)got.direction.y, (double)got.direction.z);
    CHECK(t, pt_scene_commit(s) == PT_OK, "commit: %s", pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    CHECK(t, info.delta_light_count == 2 && (info.features & PT_FEATURE_DELTA_LIGHTS) && info.emitter_count == 0 &&
                 !(info.features & PT_FEATURE_EMITTERS),
          "info: %u delta lights, features %#x, %u emitters", (unsigned)info.delta_light_count, info.features,
          (unsigned)info.emitter_count);
    pt_scene_destroy(s);
}

/* Bit-identical films with 1 and 2 threads (both samplers); then the sun alone above a ceiling that
   hides it: not one sample may reach the floor (any light leaking past the ceiling's edge, or a
   shadow ray of unbounded length that misses, would show). */
static void threads_and_shadows(test_ctx *t)
{
    pt_scene *s = pt_scene_create(), *sun = pt_scene_create();
    pt_light_desc d;
    pt_render_desc rd;
    pt_film f1, f2;
    int m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)), smp, k;
    int m2 = pt_scene_add_lambertian(sun, pt_v3(0.5f, 0.5f, 0.5f));
    memset(&d, 0, sizeof d);
    for (k = 0; k < 2; k++) {
        pt_scene *sc = k ? sun : s;
        int mm = k ? m2 : m;
        pt_scene_add_quad(sc, pt_v3(-5, 0, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), mm);
        pt_scene_add_quad(sc, pt_v3(-50, 2, -50), pt_v3(100, 0, 0), pt_v3(0, 0, 100), mm); /* the ceiling, wide
                                                                                         enough to hide a tilted sun */
    }
    d.type = PT_LIGHT_POINT;
    d.position = pt_v3(0, 1, 0);
    d.intensity = pt_v3(1, 1, 1);
    pt_scene_add_light(s, &d);
    d.type = PT_LIGHT_SPOT;
    d.direction = pt_v3(0.3f, -1, 0);
    pt_scene_add_light(s, &d);
    d.type = PT_LIGHT_DIRECTIONAL;
    d.direction = pt_v3(0.1f, -1, 0.2f);
    d.intensity = pt_v3(100, 100, 100);
    pt_scene_add_light(s, &d);
    pt_scene_add_light(sun, &d);
    if (!CHECK(t, pt_scene_commit(s) == PT_OK && pt_scene_commit(sun) == PT_OK, "commit: %s", pt_scene_error_message(s))) {
        pt_scene_destroy(s);
        pt_scene_destroy(sun);
        return;
    }
    memset(&rd, 0, sizeof rd);
    rd.width = rd.height = 24;
    rd.samples_per_pixel = 8;
    rd.camera.look_from = pt_v3(0, 1.5f, -3);
    rd.camera.look_at = pt_v3(0, 0, 0);
    for (smp = 0; smp < 2; smp++) {
        pt_render_stats st;
        double top = 0.0;
        int x, y;
        rd.sampler = (pt_sampler)smp;
        rd.threads = 1;
        if (!tu_render_into(t, s, &rd, &f1, &st, "1 thread")) { pt_film_free(&f1); break; }
        rd.threads = 2;
        if (!tu_render_into(t, s, &rd, &f2, NULL, "2 threads")) { pt_film_free(&f1); pt_film_free(&f2); break; }
        CHECK(t, tu_film_equal(&f1, &f2), "sampler %d: films differ between 1 and 2 threads", smp);
        CHECK(t, st.shadow_rays > 0, "sampler %d: no shadow rays", smp);
        pt_film_free(&f1);
        pt_film_free(&f2);
        if (!tu_render_into(t, sun, &rd, &f1, NULL, "hidden sun")) { pt_film_free(&f1); break; }
        for (y = 0; y < rd.height; y++)
            for (x = 0; x < rd.width; x++) {
                pt_color mcol, v;
                pt_film_pixel(&f1, x, y, &mcol, &v);
                if (mcol.x > top) top = mcol.x;
                if (mcol.y > top) top = mcol.y;
                if (mcol.z > top) top = mcol.z;
            }
        CHECK(t, top == 0.0, "sampler %d: a sun hidden by the ceiling lights a pixel to %.3g", smp, top);
        pt_film_free(&f1);
    }
    pt_scene_destroy(s);
    pt_scene_destroy(sun);
}

const test_case test_lights_cases[] = {
    TEST_CASE(image_point_light),
    TEST_CASE(image_spot_light),
    TEST_CASE(image_directional_light),
    TEST_CASE(image_three_point_lights),
    TEST_CASE(image_point_beside_sphere_light),
    TEST_CASE(image_light_tree),
    TEST_CASE(api_errors),
    TEST_CASE(defaults_and_transform),
    TEST_CASE(threads_and_shadows),
    TEST_END
};
