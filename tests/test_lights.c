/* test_lights.c - point, spot and directional lights (pt_scene_add_light, section 4 of pdftrace.h).

   Delta lights have no density over directions, so there is no chi-square test of their sampling:
   what is tested is the estimate. Analytic images (tu_plane_scene of test_util.h): the Lambertian
   plane (rho = 0.5) under each kind of light, direct light only, every strategy, compared per pixel
   with the footprint mean of rho E / pi, E = I falloff cos(theta) / d^2 (point, spot) or E0 cos(theta)
   (directional). A delta light's estimate at a plane point has no variance (one shadow ray, always
   unoccluded), so a pixel's variance is that of E over its footprint only; the test is the same
   z-test as test_analytic.c's (alpha = 0.001 per pixel, at least 99.3 % of the pixels), and the image
   mean within 3.5 standard errors. Three point lights of different powers test the pick by power; a
   point light beside a sphere light tests the two next-event estimates added together, under every
   strategy (MATERIAL and MIXTURE reach delta lights only through their own estimate).
   False-failure rate: the image mean within 3.5 standard errors fails with probability 4.7e-4 per
   image; 21 images here: ~1 %. The pixel rule at 32 x 32 (at most 7 of 1024 pixels rejected where
   ~1 is expected) adds ~1e-5 per image under normality (Poisson(1.02) >= 8), 2e-4 over the 21.

   The environment light (pt_scene_set_environment; env_* and image_environment_*): its errors and
   lookup convention, bit-identical films with 1 and 2 threads, and a plane under constant and
   non-constant environments against rho E / pi, E integrated from the map (tu_env_irradiance);
   its images are their own family (ENV_IMAGES, below). */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define IMAGE_W 32
#define IMAGE_H 32
#define PIXEL_ALPHA 0.001
#define ACCEPT_FRACTION 0.993
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

/* ------------------------------------------------------------------------------------------ */
/* the environment light (pt_scene_set_environment)                                            */

/* A w x h map of grey value v (rgb malloc'd). */
static int env_flat(pt_image *img, int w, int h, float v)
{
    size_t i;
    img->width = w;
    img->height = h;
    img->rgb = (float *)malloc(sizeof(float) * 3 * (size_t)w * (size_t)h);
    if (!img->rgb) return 0;
    for (i = 0; i < 3 * (size_t)w * (size_t)h; i++) img->rgb[i] = v;
    return 1;
}

/* The map's documented radiance in double: bilinear between pixel centres, periodic in u, held
   beyond the first and last rows' centres. */
static double env_bilinear(const pt_image *m, double scale, double u, double v, int ch)
{
    double fx = u * m->width - 0.5, fy = v * m->height - 0.5, x0f = floor(fx), y0f = floor(fy), tx = fx - x0f, ty = fy - y0f;
    int x0 = (((int)x0f % m->width) + m->width) % m->width, x1 = (x0 + 1) % m->width, y0 = (int)y0f, y1 = y0 + 1;
    double a, b, c, d;
    y0 = y0 < 0 ? 0 : y0 > m->height - 1 ? m->height - 1 : y0;
    y1 = y1 < 0 ? 0 : y1 > m->height - 1 ? m->height - 1 : y1;
    a = m->rgb[3 * (y0 * m->width + x0) + ch];
    b = m->rgb[3 * (y0 * m->width + x1) + ch];
    c = m->rgb[3 * (y1 * m->width + x0) + ch];
    d = m->rgb[3 * (y1 * m->width + x1) + ch];
    return scale * ((1.0 - ty) * ((1.0 - tx) * a + tx * b) + ty * ((1.0 - tx) * c + tx * d));
}

static int env_expect_error(pt_scene *s, const pt_environment_desc *d, const char *want)
{
    int rc = pt_scene_set_environment(s, d);
    return rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), want) != NULL;
}

/* Misuse of pt_scene_set_environment returns PT_ERROR_INVALID_ARGUMENT with a message naming the
   field, and leaves the environment set before it in place; NULL desc and NULL map remove it. */
static void env_api_errors(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_image good, bad;
    pt_environment_desc d;
    pt_scene_info info;
    pt_transform xf;
    float px[2 * 5 * 3];
    int i, ok;
    memset(&good, 0, sizeof good);
    memset(&bad, 0, sizeof bad);
    if (!CHECK(t, s != NULL && env_flat(&good, 4, 2, 0.5f), "out of memory")) goto done;
    d.map = &good;
    d.scale = 0.0f;
    CHECK(t, pt_scene_set_environment(NULL, &d) == PT_ERROR_INVALID_ARGUMENT, "NULL scene accepted");
    CHECK(t, pt_scene_set_environment(s, &d) == PT_OK && pt_scene_commit(s) == PT_OK, "a valid 4 x 2 map: %s",
          pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    CHECK(t, info.environment_width == 4 && info.environment_height == 2 && (info.features & PT_FEATURE_ENVIRONMENT),
          "info: environment %d x %d, features %#x", info.environment_width, info.environment_height, info.features);
    for (i = 0; i < 30; i++) px[i] = 1.0f;
    bad.rgb = px;
    bad.width = 1; bad.height = 5; d.map = &bad;
    CHECK(t, env_expect_error(s, &d, "map is 1 x 5"), "a 1 x 5 map: %s", pt_scene_error_message(s));
    bad.width = 5; bad.height = 1;
    CHECK(t, env_expect_error(s, &d, "map is 5 x 1"), "a 5 x 1 map: %s", pt_scene_error_message(s));
    bad.width = 65537; bad.height = 2;
    CHECK(t, env_expect_error(s, &d, "map is 65537 x 2"), "a 65537 x 2 map: %s", pt_scene_error_message(s));
    bad.width = 2; bad.height = 5; bad.rgb = NULL;
    CHECK(t, env_expect_error(s, &d, "rgb"), "NULL rgb: %s", pt_scene_error_message(s));
    bad.rgb = px;
    px[3 * 3 + 1] = -1.0f; /* pixel (1, 1), green */
    CHECK(t, env_expect_error(s, &d, "pixel (1, 1) channel 1"), "a negative pixel: %s", pt_scene_error_message(s));
    px[3 * 3 + 1] = NAN;
    CHECK(t, env_expect_error(s, &d, "pixel (1, 1)"), "a NaN pixel: %s", pt_scene_error_message(s));
    px[3 * 3 + 1] = 1.0f;
    px[3 * 8 + 2] = INFINITY; /* pixel (0, 4), blue */
    CHECK(t, env_expect_error(s, &d, "pixel (0, 4) channel 2"), "an infinite pixel: %s", pt_scene_error_message(s));
    px[3 * 8 + 2] = 1.0f;
    d.scale = -1.0f;
    CHECK(t, env_expect_error(s, &d, "scale"), "scale -1: %s", pt_scene_error_message(s));
    d.scale = NAN;
    CHECK(t, env_expect_error(s, &d, "scale"), "scale NaN: %s", pt_scene_error_message(s));
    d.scale = INFINITY;
    CHECK(t, env_expect_error(s, &d, "scale"), "scale Inf: %s", pt_scene_error_message(s));
    px[0] = 1e30f;
    d.scale = 1e10f; /* finite pixels and a finite scale whose product is not */
    CHECK(t, env_expect_error(s, &d, "scale"), "an overflowing scale: %s", pt_scene_error_message(s));
    px[0] = 1.0f;
    d.scale = 0.0f;
    xf = pt_transform_scale(pt_v3(2, 2, 2));
    pt_scene_set_transform(s, &xf);
    CHECK(t, env_expect_error(s, &d, "transform"), "under a scale: %s", pt_scene_error_message(s));
    xf = pt_transform_identity();
    xf.m[0][1] = 0.3f; /* shear */
    pt_scene_set_transform(s, &xf);
    CHECK(t, env_expect_error(s, &d, "transform"), "under a shear: %s", pt_scene_error_message(s));
    xf = pt_transform_scale(pt_v3(1, -1, 1)); /* orthonormal, but a reflection */
    pt_scene_set_transform(s, &xf);
    CHECK(t, env_expect_error(s, &d, "transform"), "under a reflection: %s", pt_scene_error_message(s));
    pt_scene_set_transform(s, NULL);
    pt_scene_get_info(s, &info);
    CHECK(t, info.environment_width == 4 && info.environment_height == 2 && info.committed,
          "after the failed calls: environment %d x %d, committed %d (the 4 x 2 map must stay, committed)",
          info.environment_width, info.environment_height, info.committed);
    /* removal, by NULL desc and by NULL map; then no density under a black background */
    CHECK(t, pt_scene_set_environment(s, NULL) == PT_OK && pt_scene_commit(s) == PT_OK, "remove (NULL desc): %s",
          pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    CHECK(t, info.environment_width == 0 && info.environment_height == 0 && !(info.features & PT_FEATURE_ENVIRONMENT),
          "after removal: %d x %d, features %#x", info.environment_width, info.environment_height, info.features);
    {
        pt_pdf p = pt_pdf_environment(s, pt_v3(0, 0, 0));
        pt_rng rng;
        pt_vec3 w = pt_v3(1, 1, 1);
        float pv = 1.0f;
        pt_color L = pt_scene_environment_radiance(s, pt_v3(0, 1, 0));
        pt_rng_seed(&rng, 5, 5);
        ok = pt_pdf_sample(&p, &rng, &w, &pv);
        CHECK(t, ok == 0 && pv == 0.0f && w.x == 0.0f && pt_pdf_value(&p, pt_v3(0, 1, 0)) == 0.0f && L.y == 0.0f,
              "no environment, black background: sample %d (pdf %g), value %g, radiance %g", ok, (double)pv,
              (double)pt_pdf_value(&p, pt_v3(0, 1, 0)), (double)L.y);
    }
    d.map = &good;
    CHECK(t, pt_scene_set_environment(s, &d) == PT_OK, "set again: %s", pt_scene_error_message(s));
    {
        pt_pdf p = pt_pdf_environment(s, pt_v3(0, 0, 0));
        CHECK(t, pt_pdf_validate(&p) == PT_ERROR_INVALID_ARGUMENT, "pt_pdf_environment of an uncommitted scene validated");
    }
    d.map = NULL;
    CHECK(t, pt_scene_set_environment(s, &d) == PT_OK && pt_scene_commit(s) == PT_OK, "remove (NULL map): %s",
          pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    CHECK(t, info.environment_width == 0, "after removal by a NULL map: width %d", info.environment_width);
done:
    free(good.rgb);
    if (s) pt_scene_destroy(s);
}

/* pt_scene_environment_radiance follows the documented convention: at every pixel's centre the
   pixel (x scale); at 2000 random directions the bilinear radiance computed here (relative 1e-5 of
   the brightest pixel); +x is u = 1/4 on the equator, -z is u = 0; under a rotation R (and a
   translation, ignored) the radiance along R d is the unturned map's along d. Bad directions and
   no scene give black. */
static void env_radiance_convention(test_ctx *t)
{
    pt_image m;
    pt_scene *s = pt_scene_create(), *r = pt_scene_create();
    pt_environment_desc d;
    pt_transform xf;
    pt_rng rng;
    double R[9], worst = 0.0, worst_rot = 0.0, top = 0.0;
    const double scale = 2.5;
    int x, y, i, c, bad = 0;
    memset(&m, 0, sizeof m);
    if (!CHECK(t, s && r && env_flat(&m, 8, 4, 0.0f), "out of memory")) goto done;
    pt_rng_seed(&rng, 77, 1);
    for (i = 0; i < 8 * 4 * 3; i++) {
        m.rgb[i] = (float)(0.1 + 3.0 * tu_rand(&rng));
        top = fmax(top, scale * m.rgb[i]);
    }
    d.map = &m;
    d.scale = (float)scale;
    tu_rotation(dv(0.3, -1.0, 0.6), 71.0, R, &xf);
    xf = pt_transform_mul(pt_transform_translate(pt_v3(5, 6, -7)), xf);
    CHECK(t, pt_scene_set_environment(s, &d) == PT_OK && pt_scene_commit(s) == PT_OK && pt_scene_set_transform(r, &xf) == PT_OK &&
                 pt_scene_set_environment(r, &d) == PT_OK && pt_scene_commit(r) == PT_OK,
          "set: %s %s", pt_scene_error_message(s), pt_scene_error_message(r));
    for (y = 0; y < 4; y++)
        for (x = 0; x < 8; x++) {
            pt_color L = pt_scene_environment_radiance(s, dv_to(tu_env_dir((x + 0.5) / 8, (y + 0.5) / 4)));
            const float *p = m.rgb + 3 * (y * 8 + x);
            for (c = 0; c < 3; c++) {
                double got = c == 0 ? L.x : c == 1 ? L.y : L.z;
                worst = fmax(worst, fabs(got - scale * p[c]) / top);
            }
        }
    for (i = 0; i < 2000; i++) {
        dv3 w = tu_rand_dir(&rng), wr;
        pt_color L = pt_scene_environment_radiance(s, dv_to(w)), Lr;
        double u, v;
        tu_env_uv(dv_from(dv_to(w)), &u, &v);
        wr = dv(R[0] * w.x + R[1] * w.y + R[2] * w.z, R[3] * w.x + R[4] * w.y + R[5] * w.z, R[6] * w.x + R[7] * w.y + R[8] * w.z);
        Lr = pt_scene_environment_radiance(r, dv_to(wr));
        if (sqrt(w.x * w.x + w.z * w.z) < 1e-3) continue; /* at the poles u is undefined */
        for (c = 0; c < 3; c++) {
            double got = c == 0 ? L.x : c == 1 ? L.y : L.z, gotr = c == 0 ? Lr.x : c == 1 ? Lr.y : Lr.z;
            worst = fmax(worst, fabs(got - env_bilinear(&m, scale, u, v, c)) / top);
            worst_rot = fmax(worst_rot, fabs(gotr - got) / top);
        }
    }
    CHECK(t, worst <= 1e-5, "the radiance differs from the map's bilinear interpolation by %.2g of its brightest pixel", worst);
    CHECK(t, worst_rot <= 1e-4, "turned map: the radiance along R d differs from the unturned map's along d by %.2g", worst_rot);
    {
        /* +x: u = 1/4, v = 1/2: the mean of pixels (1, 1), (2, 1), (1, 2), (2, 2); -z: u = 0, between
           the last and first columns */
        pt_color px_ = pt_scene_environment_radiance(s, pt_v3(1, 0, 0)), mz = pt_scene_environment_radiance(s, pt_v3(0, 0, -1));
        double want_x = scale * 0.25 * (m.rgb[3 * 9 + 1] + m.rgb[3 * 10 + 1] + m.rgb[3 * 17 + 1] + m.rgb[3 * 18 + 1]);
        double want_z = scale * 0.25 * (m.rgb[3 * 15 + 1] + m.rgb[3 * 8 + 1] + m.rgb[3 * 23 + 1] + m.rgb[3 * 16 + 1]);
        CHECK(t, fabs(px_.y - want_x) <= 1e-5 * top && fabs(mz.y - want_z) <= 1e-5 * top,
              "+x: %.7g (want %.7g), -z: %.7g (want %.7g)", (double)px_.y, want_x, (double)mz.y, want_z);
    }
    {
        pt_color z1 = pt_scene_environment_radiance(s, pt_v3(0, 0, 0)), z2 = pt_scene_environment_radiance(s, pt_v3(NAN, 1, 0));
        pt_color z3 = pt_scene_environment_radiance(NULL, pt_v3(0, 1, 0)), z4 = pt_scene_environment_radiance(s, pt_v3(0, 3, 0));
        bad = z1.x != 0.0f || z1.y != 0.0f || z2.y != 0.0f || z3.y != 0.0f;
        CHECK(t, !bad, "zero or NaN direction or no scene: not black");
        CHECK(t, z4.y > 0.0f && fabs(z4.y - pt_scene_environment_radiance(s, pt_v3(0, 1, 0)).y) <= 1e-6 * top,
              "a direction of length 3 is not normalised");
    }
    test_note(t, "worst |radiance - bilinear| %.1e, turned %.1e (of the brightest pixel)", worst, worst_rot);
done:
    free(m.rgb);
    if (s) pt_scene_destroy(s);
    if (r) pt_scene_destroy(r);
}

/* The plane scene of test_util.h (rho 0.5, 64 x 64 pixels looking straight down) lit only by an
   environment: the map (may be NULL) x scale under the rotation R (row-major; NULL: none) and the
   grey background bg. The plane sees the whole upper hemisphere from every point, so every pixel's
   expectation is rho E / pi, E = pi bg + \int map(w) cos(theta) dw (tu_env_irradiance, green). */
#define ENV_IMAGE 64
static int env_plane_scene(tu_plane_scene *ps, const pt_image *map, float scale, const double *R, double bg)
{
    int floor_m, rc = 0, i;
    double E = TU_PI * bg, err = 0.0;
    memset(ps, 0, sizeof *ps);
    ps->rho = 0.5;
    ps->scene = pt_scene_create();
    if (!ps->scene) return 0;
    floor_m = pt_scene_add_lambertian(ps->scene, pt_v3(0.5f, 0.5f, 0.5f));
    rc = pt_scene_add_quad(ps->scene, pt_v3(-20, 0, -20), pt_v3(0, 0, 40), pt_v3(40, 0, 0), floor_m);
    if (rc >= 0 && map) {
        pt_environment_desc d;
        pt_transform xf = pt_transform_identity();
        int a, b;
        if (R)
            for (a = 0; a < 3; a++)
                for (b = 0; b < 3; b++) xf.m[a][b] = (float)R[3 * a + b];
        d.map = map;
        d.scale = scale;
        pt_scene_set_transform(ps->scene, &xf);
        rc = pt_scene_set_environment(ps->scene, &d);
        pt_scene_set_transform(ps->scene, NULL);
    }
    if (rc < 0 || pt_scene_commit(ps->scene) != PT_OK || !tu_plane_scene_finish(ps, ENV_IMAGE, ENV_IMAGE)) return 0;
    if (map) E += tu_env_irradiance(ps->scene, map->width, map->height, R, dv(0, 1, 0), 1, &err);
    for (i = 0; i < ENV_IMAGE * ENV_IMAGE; i++) {
        ps->ref[i] = ps->rho * E / TU_PI;
        ps->qerr[i] = ps->rho * err / TU_PI;
    }
    return 1;
}

/* Renders the environment plane scene with each strategy whose bit is in `strategies` and compares
   it per pixel and as a whole: >= 99.5 % of the pixels pass the z-test at alpha 0.001, the image
   mean within z_image standard errors. spp by strategy (MIS, MATERIAL, LIGHT, MIXTURE). Every pixel
   estimates the same value from the same distribution of samples (the plane is uniform and sees
   the same sky from every point), so a pixel's z uses the image's pooled variance of a pixel mean,
   as test_analytic.c's furnace does: a bright pixel of the map next to dim ones makes the samples
   right-skewed (the bilinear radiance near its corners is up to ~9x the cell density's share;
   skewness ~3 measured on the sky below), and a pixel's own sample variance then misses the rare
   large values often enough to reject ~2-3 % of the pixels at 64 spp although the image is
   unbiased. With the pooled variance the skew of a 64-sample mean (~0.4) raises the rejection rate
   at alpha 0.001 to ~0.0016: ~7 of 4096 pixels expected, 20 allowed. */
static void env_compare(test_ctx *t, const char *name, tu_plane_scene *ps, double bg, unsigned strategies, const int *spp,
                        double z_image, uint64_t seed)
{
    static const char *names[4] = { "MIS", "MATERIAL", "LIGHT", "MIXTURE" };
    double zpix = tu_z_two_sided(PIXEL_ALPHA);
    int strat;
    for (strat = 0; strat < 4; strat++) {
        pt_render_desc d;
        pt_film f;
        pt_render_stats st;
        double pooled = 0.0, mean = 0.0, ref = 0.0, qerr = 0.0, se, z, worst = 0.0;
        int i, n = ps->width * ps->height, accepted = 0;
        if (!(strategies & (1u << strat))) continue;
        memset(&d, 0, sizeof d);
        d.width = ps->width;
        d.height = ps->height;
        d.camera = ps->camera;
        d.max_depth = 1;
        d.samples_per_pixel = spp[strat];
        d.strategy = (pt_strategy)strat;
        d.light_weight = 0.5f;
        d.background = pt_v3((float)bg, (float)bg, (float)bg);
        d.seed = seed + (uint64_t)strat;
        if (!tu_render_into(t, ps->scene, &d, &f, &st, names[strat])) { pt_film_free(&f); continue; }
        for (i = 0; i < n; i++) {
            pt_color m, v;
            pt_film_pixel(&f, i % d.width, i / d.width, &m, &v);
            pooled += v.y / n;
            mean += m.y / n;
            ref += ps->ref[i] / n;
            qerr = fmax(qerr, ps->qerr[i]);
        }
        for (i = 0; i < n; i++) {
            pt_color m, v;
            double zp;
            pt_film_pixel(&f, i % d.width, i / d.width, &m, &v);
            zp = tu_z_floor(m.y, ps->ref[i], sqrt(pooled), TU_FLOAT_FLOOR * ps->ref[i]);
            accepted += zp <= zpix;
            worst = fmax(worst, zp);
        }
        se = sqrt(pooled / n);
        z = tu_z_floor(mean, ref, se, TU_FLOAT_FLOOR * ref);
        CHECK(t, accepted >= ACCEPT_FRACTION * n, "%s, %s: only %d of %d pixels pass the z-test at alpha %.3g (pooled variance)",
              name, names[strat], accepted, n, PIXEL_ALPHA);
        CHECK(t, z <= z_image, "%s, %s: image mean %.7f +- %.2g, reference %.7f (|z| beyond the float floor %.2f, limit %.2f)",
              name, names[strat], mean, se, ref, z, z_image);
        CHECK(t, qerr <= 0.05 * fmax(se, TU_FLOAT_FLOOR * ref),
              "%s, %s: the reference's quadrature error %.2g exceeds 5 %% of the image's standard error %.2g", name,
              names[strat], qerr, se);
        if (tu_verbose())
            printf("    %s %s: %d spp, %d/%d accepted (worst z %.2f), image %.7f +- %.2g ref %.7f (z %.2f), %.2f s\n", name,
                   names[strat], d.samples_per_pixel, accepted, n, worst, mean, se, ref, z, st.seconds);
        pt_film_free(&f);
    }
}

/* False-failure rate of the environment images: 19 images (12 + 4 + 3 below); each image mean at
   the Sidak level for alpha = 0.01 over them; the pixel rule (>= 99.5 % of 4096 pixels at alpha
   0.001: more than 20 rejections where ~4 are expected) fails with probability ~1e-8 per image. */
#define ENV_IMAGES 19
static const int env_spp[4] = { 64, 256, 64, 64 };
static const int env_spp_constant[4] = { 64, 16, 64, 64 }; /* (MATERIAL has no variance there) */

/* A Lambertian plane (rho 0.5) under a constant environment L = 0.8 -- as the background, as a
   constant 4 x 2 map (0.32 x scale 2.5), and as both (background 0.3, map 0.5: the uniform sphere
   and the map mixed by power) -- has radiance rho L (E = pi L) everywhere, under every strategy.
   MATERIAL's estimate (cosine sampling, L constant) has no variance: it must be within the float
   floor. */
static void image_environment_constant(test_ctx *t)
{
    pt_image m;
    const double zi = tu_z_two_sided(tu_sidak(0.01, ENV_IMAGES));
    int k;
    memset(&m, 0, sizeof m);
    if (!CHECK(t, env_flat(&m, 4, 2, 0.32f), "out of memory")) return;
    for (k = 0; k < 3; k++) {
        static const char *names[3] = { "background 0.8", "constant map 0.8", "background 0.3 + map 0.5" };
        tu_plane_scene ps;
        double bg = k == 0 ? 0.8 : k == 1 ? 0.0 : 0.3;
        if (CHECK(t, env_plane_scene(&ps, k == 0 ? NULL : &m, k == 1 ? 2.5f : 1.5625f, NULL, bg), "%s: scene setup failed",
                  names[k])) {
            CHECK(t, fabs(ps.ref[0] - 0.4) < 1e-6, "%s: the reference is %.7f, not rho L = 0.4", names[k], ps.ref[0]);
            env_compare(t, names[k], &ps, bg, 15u, env_spp_constant, zi, 5100 + 10 * (uint64_t)k);
        }
        tu_plane_scene_destroy(&ps);
    }
    free(m.rgb);
    test_note(t, "3 environments x 4 strategies against rho L = 0.4; image mean |z| <= %.2f", zi);
}

/* The plane under maps whose irradiance is computed here from pt_scene_environment_radiance
   (tu_env_irradiance): (a) a 16 x 8 map lit only in its top two rows (radiance 1 + 0.5 sin(2 pi u),
   so the sampling density varies along the rows too), every strategy; (b) a 32 x 16 sky with a sun
   of a few pixels, turned 40 degrees about (1, 0, 0.3) so that part of the sky and the sun's
   neighbourhood lie below the plane's horizon; MIS, LIGHT and MIXTURE (MATERIAL would hit a sun
   of ~0.04 sr about once in 100 samples: too few for a pixel's t statistic). */
static void image_environment_map(test_ctx *t)
{
    pt_image cap, sky;
    tu_plane_scene ps;
    double R[9];
    const double zi = tu_z_two_sided(tu_sidak(0.01, ENV_IMAGES));
    int x, y;
    memset(&cap, 0, sizeof cap);
    memset(&sky, 0, sizeof sky);
    if (!CHECK(t, env_flat(&cap, 16, 8, 0.0f) && tu_env_sky(&sky, 32, 16, tu_env_dir(0.15, 0.3), 0.12, 30.0), "out of memory"))
        goto done;
    for (y = 0; y < 2; y++)
        for (x = 0; x < 16; x++) {
            float v = (float)(1.0 + 0.5 * sin(2.0 * TU_PI * (x + 0.5) / 16));
            float *p = cap.rgb + 3 * (y * 16 + x);
            p[0] = v; p[1] = v; p[2] = v;
        }
    if (CHECK(t, env_plane_scene(&ps, &cap, 0.0f, NULL, 0.0), "cap: scene setup failed")) {
        test_note(t, "cap: rho E / pi = %.5f", ps.ref[0]);
        env_compare(t, "top rows lit", &ps, 0.0, 15u, env_spp, zi, 5200);
    }
    tu_plane_scene_destroy(&ps);
    tu_rotation(dv(1, 0, 0.3), 40.0, R, NULL);
    if (CHECK(t, env_plane_scene(&ps, &sky, 0.0f, R, 0.0), "sky: scene setup failed")) {
        test_note(t, "turned sky: rho E / pi = %.5f", ps.ref[0]);
        env_compare(t, "turned sky and sun", &ps, 0.0, 13u, env_spp, zi, 5300);
    }
    tu_plane_scene_destroy(&ps);
done:
    free(cap.rgb);
    free(sky.rgb);
}

/* Bit-identical films with 1 and 2 threads (both samplers) for a scene lit by an environment map
   and a sphere light, with a sphere casting shadows on a plane (every strategy's environment
   code: next-event estimation with shadow rays to infinity, escapes with MIS weights). */
static void env_threads(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_image sky;
    pt_environment_desc d;
    pt_render_desc rd;
    int smp, strat, m, lamp;
    memset(&sky, 0, sizeof sky);
    if (!CHECK(t, s && tu_env_sky(&sky, 32, 16, tu_env_dir(0.6, 0.25), 0.15, 20.0), "out of memory")) goto done;
    m = pt_scene_add_lambertian(s, pt_v3(0.6f, 0.5f, 0.4f));
    lamp = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0);
    pt_scene_add_quad(s, pt_v3(-5, 0, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), m);
    pt_scene_add_sphere(s, pt_v3(0, 0.7f, 0), 0.7f, m);
    pt_scene_add_sphere(s, pt_v3(1.5f, 2.0f, -1.0f), 0.3f, lamp);
    d.map = &sky;
    d.scale = 0.0f;
    if (!CHECK(t, pt_scene_set_environment(s, &d) == PT_OK && pt_scene_commit(s) == PT_OK, "scene: %s",
               pt_scene_error_message(s)))
        goto done;
    memset(&rd, 0, sizeof rd);
    rd.width = rd.height = 24;
    rd.samples_per_pixel = 8;
    rd.camera.look_from = pt_v3(0, 1.5f, -4);
    rd.camera.look_at = pt_v3(0, 0.5f, 0);
    for (smp = 0; smp < 2; smp++)
        for (strat = 0; strat < 4; strat++) {
            pt_film f1, f2;
            pt_render_stats st;
            rd.sampler = (pt_sampler)smp;
            rd.strategy = (pt_strategy)strat;
            rd.threads = 1;
            if (!tu_render_into(t, s, &rd, &f1, &st, "1 thread")) { pt_film_free(&f1); continue; }
            rd.threads = 2;
            if (tu_render_into(t, s, &rd, &f2, NULL, "2 threads"))
                CHECK(t, tu_film_equal(&f1, &f2), "sampler %d, strategy %d: films differ between 1 and 2 threads", smp, strat);
            if (strat == PT_STRATEGY_MIS || strat == PT_STRATEGY_LIGHT)
                CHECK(t, st.shadow_rays > 0, "sampler %d, strategy %d: no shadow rays", smp, strat);
            pt_film_free(&f1);
            pt_film_free(&f2);
        }
done:
    free(sky.rgb);
    if (s) pt_scene_destroy(s);
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
    TEST_CASE(env_api_errors),
    TEST_CASE(env_radiance_convention),
    TEST_CASE(image_environment_constant),
    TEST_CASE(image_environment_map),
    TEST_CASE(env_threads),
    TEST_END
};
