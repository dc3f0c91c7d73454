/* test_analytic.c - issue 3's analytic images and furnaces: every strategy against closed forms,
   pixel by pixel.

   Analytic images (tu_plane_scene in test_util.h): a Lambertian plane (rho = 0.5) lit by a sphere, a
   quad or a triangle light of radiance 1, direct light only (max_depth 1), 64 x 64 pixels, rendered
   with each strategy (MIS, MATERIAL, LIGHT, MIXTURE at light weight 0.5) and compared per pixel with
   the footprint mean of rho E / pi (Lambert's polygon formula in double precision; E = pi L sin^2(a)
   cos(t) for the sphere). Acceptance (issue 3): at least 99.5 % of the pixels pass a two-sided z-test
   at alpha = 0.001 (|z| <= 3.29, z from the pixel's sample variance of the mean, beyond the 1e-4
   relative float floor of test_util.h), and the image mean lies within 3 standard errors.

   False-failure rates. A pixel's z uses its sample variance (a t statistic): with the sample counts
   below every pixel holds >= ~100 light hits even for MATERIAL, whose samples are Bernoulli (rho L
   or 0), and the two tails of the t statistic of such a mean at n p >= 100 add up to at most
   ~0.0016 instead of 0.001 (Poisson tail sums). The number of rejected pixels is then ~Binomial(4096,
   <= 0.0016), mean <= 6.6, and the threshold 0.5 % allows 20: P(fail) < 1e-5 per image. The image
   mean test at 3 standard errors fails with probability 0.0027 per image; 12 images: ~3.2 %. The
   reference's quadrature error is checked to stay below 5 % of every pixel's standard error.

   Furnaces: inside a closed sphere of albedo 0.5 emitting 0.5 (two-sided) the radiance is
   Le / (1 - rho) = 1 everywhere; a mirror and a glass sphere inside a uniform two-sided emitter of
   radiance 1 (a real emitter, sampled as a light by MIS/LIGHT/MIXTURE) return 1. */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define IMAGE_W 64
#define IMAGE_H 64
#define PIXEL_ALPHA 0.001
#define ACCEPT_FRACTION 0.995
#define IMAGE_Z 3.0

static const char *strategy_name(int s)
{
    return s == PT_STRATEGY_MIS ? "MIS" : s == PT_STRATEGY_MATERIAL ? "MATERIAL" : s == PT_STRATEGY_LIGHT ? "LIGHT" : "MIXTURE";
}

/* Samples per pixel by strategy: MATERIAL finds the light only by hitting it (probability ~0.1-0.3
   per sample here), so it needs the most for >= 100 hits per pixel. */
static int strategy_spp(int s) { return s == PT_STRATEGY_MATERIAL ? 1024 : s == PT_STRATEGY_LIGHT ? 128 : 256; }

static void analytic_image(test_ctx *t, int kind, const char *light_name, uint64_t seed)
{
    tu_plane_scene ps;
    int strat;
    double zpix = tu_z_two_sided(PIXEL_ALPHA);
    if (!CHECK(t, tu_plane_scene_create(&ps, kind, IMAGE_W, IMAGE_H), "%s scene setup failed", light_name)) {
        tu_plane_scene_destroy(&ps);
        return;
    }
    for (strat = 0; strat < 4; strat++) {
        pt_render_desc d;
        tu_image_stats st;
        memset(&d, 0, sizeof d);
        d.samples_per_pixel = strategy_spp(strat);
        d.strategy = (pt_strategy)strat;
        d.seed = seed + (uint64_t)strat;
        tu_plane_render_compare(&ps, &d, zpix, &st);
        if (!CHECK(t, st.rc == PT_OK, "%s, %s: pt_render returned %d", light_name, strategy_name(strat), st.rc)) continue;
        CHECK(t, st.nonfinite == 0, "%s, %s: %llu non-finite samples", light_name, strategy_name(strat),
              (unsigned long long)st.nonfinite);
        CHECK(t, st.accepted >= ACCEPT_FRACTION * st.pixels,
              "%s, %s: only %d of %d pixels (%.2f %%) pass the z-test at alpha %.3g (need %.1f %%); mean rel error %+.2e, mean z %+.2f",
              light_name, strategy_name(strat), st.accepted, st.pixels, 100.0 * st.accepted / st.pixels, PIXEL_ALPHA,
              100 * ACCEPT_FRACTION, st.mean_rel, st.mean_z);
        CHECK(t, fabs(st.image_z) <= IMAGE_Z, "%s, %s: image mean %.7f +- %.2g, reference %.7f (z = %+.2f, limit %.0f)",
              light_name, strategy_name(strat), st.image_mean, st.image_se, st.image_ref, st.image_z, IMAGE_Z);
        CHECK(t, st.worst_qerr_over_se < 0.05,
              "%s, %s: the reference's quadrature error reaches %.3f of a pixel's standard error", light_name,
              strategy_name(strat), st.worst_qerr_over_se);
        test_note(t, "%s %d spp: %.2f %% accepted, mean rel err %+.1e, mean z %+.3f, image z %+.2f", strategy_name(strat),
                  d.samples_per_pixel, 100.0 * st.accepted / st.pixels, st.mean_rel, st.mean_z, st.image_z);
        if (tu_verbose())
            printf("    %s %s: %d spp, %d/%d accepted, max |z| %.2f, image %.7f +- %.2g ref %.7f, qerr/se %.3g, %.2f s\n",
                   light_name, strategy_name(strat), d.samples_per_pixel, st.accepted, st.pixels, st.max_abs_z,
                   st.image_mean, st.image_se, st.image_ref, st.worst_qerr_over_se, st.seconds);
    }
    tu_plane_scene_destroy(&ps);
}

static void image_sphere_light(test_ctx *t) { analytic_image(t, TU_SPHERE, "sphere light", 31000); }
static void image_quad_light(test_ctx *t) { analytic_image(t, TU_QUAD, "quad light", 32000); }
static void image_triangle_light(test_ctx *t) { analytic_image(t, TU_TRIANGLE, "triangle light", 33000); }

/* The plane under the benchmark's tiny bulb (tiny-light.scene: r = 0.02 seen from 3 to 3.6, sin^2
   of the cone 3e-5 .. 4.4e-5), LIGHT and MIS, the same camera and plane as the images above and the
   set-up of tests/tiny_light/mitsuba_analytic.py, where Mitsuba 3.9 comes out +0.07 % bright
   (docs/accuracy.md, "Tiny sphere lights and Mitsuba"). The image mean must lie within 3 standard
   errors beyond the 1e-4 float floor (false failure 0.0027 per strategy) and the pixels pass as
   above; the cancelling 1 - sqrt(1 - s^2) in the cone density fails the image mean (+0.07 %). */
static void image_tiny_sphere_light(test_ctx *t)
{
    static const pt_strategy strats[2] = { PT_STRATEGY_LIGHT, PT_STRATEGY_MIS };
    tu_plane_scene ps;
    tu_light *L = &ps.light[0];
    int floor_m, light_m, rc, k;
    const double zpix = tu_z_two_sided(PIXEL_ALPHA);
    memset(&ps, 0, sizeof ps);
    ps.rho = 0.5;
    ps.light_count = 1;
    L->kind = TU_SPHERE;
    L->p0 = dv(0.11, 3.0, -0.07);
    L->radius = 0.02;
    ps.radiance[0] = 1.0 / (L->radius * L->radius); /* plane radiance rho cos / d^2 ~ 0.05 */
    ps.scene = pt_scene_create();
    floor_m = pt_scene_add_lambertian(ps.scene, pt_v3(0.5f, 0.5f, 0.5f));
    light_m = pt_scene_add_emitter(ps.scene, pt_v3((float)ps.radiance[0], (float)ps.radiance[0], (float)ps.radiance[0]), 0);
    rc = pt_scene_add_quad(ps.scene, pt_v3(-20, 0, -20), pt_v3(0, 0, 40), pt_v3(40, 0, 0), floor_m);
    rc = rc >= 0 ? pt_scene_add_sphere(ps.scene, dv_to(L->p0), (float)L->radius, light_m) : rc;
    if (!CHECK(t, floor_m >= 0 && light_m >= 0 && rc >= 0 && pt_scene_commit(ps.scene) == PT_OK &&
                      tu_plane_scene_finish(&ps, IMAGE_W, IMAGE_H),
               "tiny sphere light: scene setup failed")) {
        tu_plane_scene_destroy(&ps);
        return;
    }
    for (k = 0; k < 2; k++) {
        pt_render_desc d;
        tu_image_stats st;
        memset(&d, 0, sizeof d);
        d.samples_per_pixel = 64;
        d.strategy = strats[k];
        d.seed = 34000 + (uint64_t)k;
        tu_plane_render_compare(&ps, &d, zpix, &st);
        if (!CHECK(t, st.rc == PT_OK, "tiny sphere light, %s: pt_render returned %d", strategy_name(strats[k]), st.rc))
            continue;
        CHECK(t, st.nonfinite == 0 && st.accepted >= ACCEPT_FRACTION * st.pixels && fabs(st.image_z) <= IMAGE_Z,
              "tiny sphere light, %s: image mean %.7f +- %.2g, reference %.7f (%+.4f %%, z beyond the float floor %+.2f, "
              "limit %.0f); %d of %d pixels pass at alpha %.3g; %llu non-finite",
              strategy_name(strats[k]), st.image_mean, st.image_se, st.image_ref,
              100.0 * (st.image_mean / st.image_ref - 1.0), st.image_z, IMAGE_Z, st.accepted, st.pixels, PIXEL_ALPHA,
              (unsigned long long)st.nonfinite);
        test_note(t, "%s: image %+.4f %% +- %.4f %% of the closed form, %.2f %% of pixels accepted",
                  strategy_name(strats[k]), 100.0 * (st.image_mean / st.image_ref - 1.0), 100.0 * st.image_se / st.image_ref,
                  100.0 * st.accepted / st.pixels);
    }
    tu_plane_scene_destroy(&ps);
}

/* ------------------------------------------------------------------------------------------ */
/* furnaces                                                                                    */

typedef struct furnace_stats {
    int pixels, accepted, within;   /* z-test passes; |mean - want| <= tol */
    double max_dev, image_mean, image_se, image_z, mean_sample_sd;
    uint64_t nonfinite, split_paths;
    int rc;
} furnace_stats;

/* Renders and compares every pixel with `want` (green channel; the scenes are grey). pooled: the
   z-test uses the image's mean variance of a pixel mean instead of each pixel's own (see
   furnace_every_pixel). */
static void furnace_render(const pt_scene *s, pt_render_desc *d, double want, double tol, int pooled, furnace_stats *fs)
{
    pt_film f;
    pt_render_stats st;
    int x, y;
    double zpix = tu_z_two_sided(PIXEL_ALPHA), var = 0.0, pooled_var = 0.0;
    memset(fs, 0, sizeof *fs);
    fs->rc = pt_film_init(&f, d->width, d->height);
    if (fs->rc != PT_OK) return;
    fs->rc = pt_render(s, d, &f, &st);
    fs->nonfinite = st.nonfinite_samples;
    fs->split_paths = st.split_paths;
    if (fs->rc == PT_OK) {
        for (y = 0; y < d->height; y++) {
            for (x = 0; x < d->width; x++) {
                pt_color m, v;
                pt_film_pixel(&f, x, y, &m, &v);
                pooled_var += v.y / (d->width * d->height);
            }
        }
        for (y = 0; y < d->height; y++) {
            for (x = 0; x < d->width; x++) {
                pt_color m, v;
                double dev, z;
                pt_film_pixel(&f, x, y, &m, &v);
                dev = fabs(m.y - want);
                z = tu_z_floor(m.y, want, sqrt(pooled ? pooled_var : v.y), TU_FLOAT_FLOOR * want);
                fs->pixels++;
                fs->accepted += z <= zpix;
                fs->within += dev <= tol;
                fs->max_dev = fmax(fs->max_dev, dev);
                fs->image_mean += m.y;
                fs->mean_sample_sd += sqrt(v.y * d->samples_per_pixel);
                var += v.y;
            }
        }
        fs->image_mean /= fs->pixels;
        fs->mean_sample_sd /= fs->pixels;
        fs->image_se = sqrt(var) / fs->pixels;
        fs->image_z = tu_z_floor(fs->image_mean, want, fs->image_se, TU_FLOAT_FLOOR * want);
    }
    pt_film_free(&f);
}

/* Samples per pixel for the closed furnace with Russian roulette (the default from depth 3), 64 x 64
   pixels: enough for the image mean's standard error to be <= 1e-3 / 3.5 with each strategy's
   per-sample standard deviation (measured: MIS 0.31, MATERIAL 0.41, LIGHT 0.21, MIXTURE 0.41), and
   at least ~300 per pixel so that the skew of a pixel mean stays small (LIGHT at 140 spp rejected
   0.42 %% of the pixels, at 560 spp 0.11 %%). */
static int furnace_rr_spp(int s) { return s == PT_STRATEGY_MIS ? 300 : s == PT_STRATEGY_LIGHT ? 560 : 525; }

/* The closed furnace of tu_add_closed_furnace, or NULL (the failure is a failed check). */
static pt_scene *furnace_scene(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    int rc;
    if (!CHECK(t, s != NULL, "scene")) return NULL;
    rc = tu_add_closed_furnace(s);
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) {
        pt_scene_destroy(s);
        return NULL;
    }
    return s;
}

/* 32 x 32 from inside the closed furnace: every camera ray's first vertex is a diffuse wall. */
static pt_render_desc furnace_view(int spp, uint64_t seed, pt_strategy strategy, pt_sampler sampler)
{
    pt_render_desc d = tu_base_desc(32, 32, spp, seed);
    d.camera.look_from = pt_v3(0.2f, -0.1f, 0.3f);
    d.camera.look_at = pt_v3(1, 0.5f, 0);
    d.camera.vfov_degrees = 90;
    d.strategy = strategy;
    d.sampler = sampler;
    return d;
}

static void furnace_every_pixel(test_ctx *t)
{
    /* Issue 3: inside a closed sphere of albedo 0.5 emitting 0.5 on both sides every pixel converges
       to Le / (1 - rho) = 1 (pbrt-v4's furnace). Camera inside, off-centre, 32 x 32, each strategy.
       Stated as: every pixel passes a z-test against 1 (>= 99.5 %% of them at alpha 0.001) and the
       image mean lies within 1e-3 of 1, with enough samples that 1e-3 is at least 3.5 standard
       errors (false failure < 5e-4 per render; 8 renders: < 0.4 %%).
       (a) Russian roulette off, max_depth 20 (the truncation loses 2^-21), 256 spp. At a shading point exactly
       on the sphere every strategy would be exact (cosine sampling: f/p = rho; area sampling a
       sphere from its own surface: cos cos' / d^2 = 1/(4 R^2), so f L / p = rho Le; MIS's two
       densities coincide), but rays leave from spawn points ~256 ulps inside the surface (Waechter
       & Binder): light samples within ~0.02 of the shading point then carry less than rho Le (a
       relative bias ~1e-5 overall, per sample up to the whole contribution, ~1e-4 of the samples).
       So: MATERIAL, which never samples the light, must be within 1e-5 of 1 in every pixel; with
       the others >= 99.5 %% of the pixels must be within 1e-3 (a rare short light sample moves a
       pixel by <= 0.25 / 256).
       (b) Russian roulette on (the default, from depth 3), 64 x 64, furnace_rr_spp samples per
       pixel. Roulette makes the samples strongly right-skewed (most paths are cut at depth 3, a few
       survive with weight 1/q), and the t statistic of a pixel built on its own sample variance is
       then left-skewed: at 2100 spp 0.27-0.4 %% of the pixels fell below |z| = 3.29 (measured over
       seeds, all with mean below 1 and a variance that missed the rare survivors) instead of 0.1 %%.
       Every pixel of this furnace estimates the same quantity with the same sample distribution
       (after the first hit the process is the same everywhere on the sphere), so the z-test uses
       the image's pooled variance of a pixel mean: measured rejection rates 0.05-0.15 %%, so ~6 of
       4096 pixels expected against the 20 that 99.5 %% allows (false failure ~1e-5 per render).
       (Without roulette the variance comes from rare short light samples, which are exactly what
       a pixel's own variance must see: (a) uses the per-pixel variance.) */
    pt_scene *s = pt_scene_create();
    int rc, strat, rr;
    if (!CHECK(t, s != NULL, "scene")) return;
    rc = tu_add_closed_furnace(s);
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (rr = 0; rr < 2; rr++) {
        for (strat = 0; strat < 4; strat++) {
            pt_render_desc d;
            furnace_stats fs;
            memset(&d, 0, sizeof d);
            d.width = rr == 0 ? 32 : 64;
            d.height = rr == 0 ? 32 : 64;
            d.samples_per_pixel = rr == 0 ? 256 : furnace_rr_spp(strat);
            d.camera.look_from = pt_v3(0.2f, -0.1f, 0.3f);
            d.camera.look_at = pt_v3(1, 0.5f, 0);
            d.camera.vfov_degrees = 90;
            d.strategy = (pt_strategy)strat;
            d.max_depth = rr == 0 ? 20 : 50;
            d.rr_start_depth = rr == 0 ? -1 : 0;
            d.seed = 34000 + (uint64_t)(10 * rr + strat);
            /* without Russian roulette the truncation at depth 20 loses 2^-21 = 4.8e-7 */
            furnace_render(s, &d, rr == 0 ? 1.0 - ldexp(1.0, -21) : 1.0, 1e-3, rr, &fs);
            if (!CHECK(t, fs.rc == PT_OK, "%s: pt_render %d", strategy_name(strat), fs.rc)) continue;
            CHECK(t, fs.nonfinite == 0, "%s: %llu non-finite samples", strategy_name(strat), (unsigned long long)fs.nonfinite);
            CHECK(t, fs.accepted >= ACCEPT_FRACTION * fs.pixels, "%s, RR %s: only %d of %d pixels pass the z-test against 1",
                  strategy_name(strat), rr ? "on" : "off", fs.accepted, fs.pixels);
            CHECK(t, fabs(fs.image_mean - 1.0) <= 1e-3, "%s, RR %s: image mean %.6f +- %.2g, not within 1e-3 of 1",
                  strategy_name(strat), rr ? "on" : "off", fs.image_mean, fs.image_se);
            CHECK(t, 3.5 * fs.image_se <= 1e-3, "%s, RR %s: image standard error %.2g too large to resolve 1e-3",
                  strategy_name(strat), rr ? "on" : "off", fs.image_se);
            if (rr == 0 && strat == PT_STRATEGY_MATERIAL)
                CHECK(t, fs.max_dev <= 1e-5, "MATERIAL, no Russian roulette: a pixel is %.2e from 1 (the estimator is exact)",
                      fs.max_dev);
            if (rr == 0)
                CHECK(t, fs.within >= ACCEPT_FRACTION * fs.pixels,
                      "%s, no Russian roulette: %d of %d pixels farther than 1e-3 from 1 (max deviation %.2e)",
                      strategy_name(strat), fs.pixels - fs.within, fs.pixels, fs.max_dev);
            test_note(t, "RR %s %s %d spp: mean %.5f +- %.1e, %.2f %% z-accepted, %.2f %% within 1e-3, max |pixel - 1| %.1e",
                      rr ? "on" : "off", strategy_name(strat), d.samples_per_pixel, fs.image_mean, fs.image_se,
                      100.0 * fs.accepted / fs.pixels, 100.0 * fs.within / fs.pixels, fs.max_dev);
        }
    }
    pt_scene_destroy(s);
}

static void furnace_mirror_glass_in_emitter(test_ctx *t)
{
    /* Issue 3: a mirror (albedo 1) and a glass sphere (ior 1.5) inside a uniform two-sided emitter
       sphere of radiance 1 (a real emitter, sampled as a light by MIS, LIGHT and MIXTURE) return 1:
       both are lossless, and after a delta vertex the emitter counts at full weight with every
       strategy. Camera inside, 48 x 32. (a) Russian roulette off, max_depth 50: every pixel within
       1e-3 of 1 (exactly 1 but for paths trapped > 50 bounces). (b) Russian roulette on (the default,
       from depth 3): the image mean within 3 standard errors of 1 (false failure 0.27 %% per
       strategy). A per-pixel z-test is not used here: in a glass pixel only ~8 %% of the paths reach
       depth 3 and ~5 %% of those are killed (value 0) while the others carry 1/0.95, so a pixel
       holds ~2 kills on average and its sample variance misses them in ~13 %% of the pixels -- the
       z statistic of such a rare-event mean is far from normal (checked: 4 %% of the glass pixels
       then "fail" at alpha 0.001 although the image is unbiased). */
    pt_scene *s = pt_scene_create();
    int em, mirror, glass, rc, strat, rr;
    if (!CHECK(t, s != NULL, "scene")) return;
    em = pt_scene_add_emitter(s, pt_v3(1, 1, 1), 1);
    mirror = pt_scene_add_metal(s, pt_v3(1, 1, 1), 0.0f);
    glass = pt_scene_add_dielectric(s, 1.5f);
    rc = pt_scene_add_sphere(s, pt_v3(0, 0, 0), 6.0f, em);
    rc = rc >= 0 ? pt_scene_add_sphere(s, pt_v3(-1.1f, 0, 0), 1.0f, mirror) : rc;
    rc = rc >= 0 ? pt_scene_add_sphere(s, pt_v3(1.1f, 0, 0.2f), 1.0f, glass) : rc;
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (rr = 0; rr < 2; rr++) {
        for (strat = 0; strat < 4; strat++) {
            pt_render_desc d;
            furnace_stats fs;
            memset(&d, 0, sizeof d);
            d.width = 48;
            d.height = 32;
            d.samples_per_pixel = rr == 0 ? 16 : 256;
            d.camera.look_from = pt_v3(0.1f, 0.3f, -4.0f);
            d.camera.look_at = pt_v3(0, 0, 0);
            d.camera.vfov_degrees = 60;
            d.strategy = (pt_strategy)strat;
            d.max_depth = 50;
            d.rr_start_depth = rr == 0 ? -1 : 0;
            d.seed = 35000 + (uint64_t)(10 * rr + strat);
            furnace_render(s, &d, 1.0, 1e-3, 0, &fs);
            if (!CHECK(t, fs.rc == PT_OK, "%s: pt_render %d", strategy_name(strat), fs.rc)) continue;
            CHECK(t, fs.nonfinite == 0, "%s: %llu non-finite samples", strategy_name(strat), (unsigned long long)fs.nonfinite);
            if (rr == 0) {
                CHECK(t, fs.within == fs.pixels, "%s, no Russian roulette: %d of %d pixels farther than 1e-3 from 1 (max deviation %.2e)",
                      strategy_name(strat), fs.pixels - fs.within, fs.pixels, fs.max_dev);
                test_note(t, "RR off %s: max |pixel - 1| %.1e", strategy_name(strat), fs.max_dev);
            } else {
                CHECK(t, fs.image_z <= IMAGE_Z, "%s, RR: image mean %.6f +- %.2g, not within 3 standard errors of 1",
                      strategy_name(strat), fs.image_mean, fs.image_se);
                test_note(t, "RR on %s: mean %.5f +- %.1e", strategy_name(strat), fs.image_mean, fs.image_se);
            }
        }
    }
    pt_scene_destroy(s);
}

static void furnace_indirect_paths(test_ctx *t)
{
    /* pt_render_desc.indirect_paths (section 7): each camera sample's path continues from its
       first non-delta vertex as k copies of throughput 1/k, after that vertex's one next-event
       estimate. In the closed furnace (radiance 1 inside; every camera ray's first vertex is a
       diffuse wall), 32 x 32, 64 spp, default depth:
       (a) the default (0: 3 with Sobol, 1 independent), 2 and 8, with MATERIAL, LIGHT and MIS and
       both samplers, roulette
       from depth 1 in (b): the image is 1 by furnace_every_pixel's criteria (pooled per-pixel
       z-test, >= 99.5 %% of the pixels at alpha 0.001; image mean within 3 standard errors), no
       sample is non-finite, and exactly k - 1 extra paths start per camera sample (no
       throughput here reaches the weight window's 2: the furnace's albedo is 0.5). A copy
       weighted 1 instead of 1/k would make the image ~(k + 1)/2 too bright; a copy never
       traced, too dark.
       (b) MATERIAL with roulette from depth 1, whose coin flips are the only randomness in the
       furnace (the emission is 0.5 everywhere): k = 8 must lower the standard deviation per
       camera sample by 10 %% or more against k = 1 with each sampler (the copies' coins are
       independent; it measured 0.092 against 0.26 with either sampler). Copies sharing their random numbers
       would give k = 1's deviation. The deviations are known to ~1 %% (65,536 samples of
       bounded weight). */
    static const struct { pt_strategy strategy; pt_sampler sampler; int k, rr1; } cases[] = {
        {PT_STRATEGY_MIS, PT_SAMPLER_INDEPENDENT, 0, 0},      {PT_STRATEGY_MIS, PT_SAMPLER_SOBOL, 0, 0},
        {PT_STRATEGY_LIGHT, PT_SAMPLER_INDEPENDENT, 8, 0},    {PT_STRATEGY_LIGHT, PT_SAMPLER_SOBOL, 2, 0},
        {PT_STRATEGY_MATERIAL, PT_SAMPLER_INDEPENDENT, 1, 1}, {PT_STRATEGY_MATERIAL, PT_SAMPLER_INDEPENDENT, 8, 1},
        {PT_STRATEGY_MATERIAL, PT_SAMPLER_SOBOL, 1, 1},       {PT_STRATEGY_MATERIAL, PT_SAMPLER_SOBOL, 8, 1},
    };
    pt_scene *s = furnace_scene(t);
    int c;
    double sd[8];
    if (!s) return;
    for (c = 0; c < 8; c++) {
        pt_render_desc d = furnace_view(64, 36000 + (uint64_t)c, cases[c].strategy, cases[c].sampler);
        furnace_stats fs;
        const int k = cases[c].k ? cases[c].k : cases[c].sampler == PT_SAMPLER_SOBOL ? 3 : 1;
        const double want = 1.0;
        char name[64];
        snprintf(name, sizeof name, "%s, %s, indirect_paths %d%s", strategy_name(cases[c].strategy),
                 cases[c].sampler == PT_SAMPLER_SOBOL ? "Sobol" : "independent", cases[c].k,
                 cases[c].rr1 ? ", roulette from depth 1" : "");
        d.indirect_paths = cases[c].k;
        if (cases[c].rr1) d.rr_start_depth = 1;
        furnace_render(s, &d, want, 1e-3, 1, &fs);
        sd[c] = fs.mean_sample_sd;
        if (!CHECK(t, fs.rc == PT_OK, "%s: pt_render %d", name, fs.rc)) continue;
        CHECK(t, fs.nonfinite == 0, "%s: %llu non-finite samples", name, (unsigned long long)fs.nonfinite);
        CHECK(t, fs.split_paths == (uint64_t)(k - 1) * 32u * 32u * 64u, "%s: %llu extra paths, not %d per sample", name,
              (unsigned long long)fs.split_paths, k - 1);
        CHECK(t, fs.accepted >= ACCEPT_FRACTION * fs.pixels, "%s: only %d of %d pixels pass the z-test against %g", name,
              fs.accepted, fs.pixels, want);
        CHECK(t, fabs(fs.image_z) <= IMAGE_Z, "%s: image mean %.6f +- %.2g, not %g (z = %+.2f)", name, fs.image_mean,
              fs.image_se, want, fs.image_z);
        test_note(t, "%s: %.5f +- %.1e, sd %.3g", name, fs.image_mean, fs.image_se, fs.mean_sample_sd);
    }
    CHECK(t, sd[5] <= 0.9 * sd[4], "independent: indirect_paths 8 gives sd per sample %.3g, not 10 %% below %.3g with 1",
          sd[5], sd[4]);
    CHECK(t, sd[7] <= 0.9 * sd[6], "Sobol: indirect_paths 8 gives sd per sample %.3g, not 10 %% below %.3g with 1", sd[7],
          sd[6]);
    pt_scene_destroy(s);
}

/* A guide that concentrates 4/5 of the scatter density in a cone of half-angle ~5.7 degrees
   towards the furnace's centre (a virtual sphere of radius 0.1 there), so every other direction
   gets the weight rho / 0.2 = 2.5: path throughputs exceed 2 and splitting must act. */
static int split_guide(void *user, const pt_shading_point *sp, pt_pdf *out)
{
    (void)user;
    if (pt_length(sp->position) < 0.5f) return 0;
    *out = pt_pdf_sphere_light(sp->position, pt_v3(0, 0, 0), 0.1f, 0);
    return 1;
}

static void furnace_splitting(test_ctx *t)
{
    /* Splitting (section 7) in the closed furnace (albedo 0.5, two-sided emission 0.5: radiance 1
       inside), rendered with split_guide at weight 0.8, 32 x 32, 128 spp.
       (a) Default depth and roulette; MATERIAL, LIGHT and MIS with the independent sampler and
       MATERIAL with Sobol (whose split copies use re-keyed sets): paths split (split_paths > 0),
       no sample is non-finite, and the image is 1 by furnace_every_pixel's criteria (pooled
       per-pixel z-test, >= 99.5 %% of the pixels at alpha 0.001; image mean within 3 standard
       errors). A missing 1/k would make the image ~1.5x too bright.
       (b) max_depth 4 without roulette, exact value 0.5 (1 + 1/2 + ... + 1/16) = 0.96875,
       MATERIAL with each sampler, with and without splitting (max_splits < 0: no path may
       split): all four unbiased as in (a) (the two without splitting by their image mean alone),
       and splitting must lower the standard deviation per
       sample by 10 %% or more: it measured 1.21 against 1.57 (both samplers). Copies that shared
       their random numbers would be one path counted k times at weight 1/k each: the same
       variance as no splitting. At 131,072 samples per render and bounded weights (<= 2.5^4),
       the standard deviations are known to ~1 %%, far inside that margin. */
    static const struct { pt_strategy strategy; pt_sampler sampler; int depth, split; const char *name; } cases[] = {
        {PT_STRATEGY_MATERIAL, PT_SAMPLER_INDEPENDENT, 0, 1, "MATERIAL"},
        {PT_STRATEGY_LIGHT, PT_SAMPLER_INDEPENDENT, 0, 1, "LIGHT"},
        {PT_STRATEGY_MIS, PT_SAMPLER_INDEPENDENT, 0, 1, "MIS"},
        {PT_STRATEGY_MATERIAL, PT_SAMPLER_SOBOL, 0, 1, "MATERIAL, Sobol"},
        {PT_STRATEGY_MATERIAL, PT_SAMPLER_INDEPENDENT, 4, 1, "depth 4, MATERIAL"},
        {PT_STRATEGY_MATERIAL, PT_SAMPLER_INDEPENDENT, 4, 0, "depth 4, MATERIAL, no splitting"},
        {PT_STRATEGY_MATERIAL, PT_SAMPLER_SOBOL, 4, 1, "depth 4, MATERIAL, Sobol"},
        {PT_STRATEGY_MATERIAL, PT_SAMPLER_SOBOL, 4, 0, "depth 4, MATERIAL, Sobol, no splitting"},
    };
    pt_scene *s = furnace_scene(t);
    int c;
    double sd[8];
    if (!s) return;
    for (c = 0; c < 8; c++) {
        pt_render_desc d = furnace_view(128, 35000 + (uint64_t)c, cases[c].strategy, cases[c].sampler);
        furnace_stats fs;
        double want = cases[c].depth ? 0.96875 : 1.0;
        d.guide = split_guide;
        d.guide_weight = 0.8f;
        d.max_splits = cases[c].split ? 0 : -1;
        if (cases[c].depth) {
            d.max_depth = cases[c].depth;
            d.rr_start_depth = -1;
        }
        furnace_render(s, &d, want, 1e-3, 1, &fs);
        sd[c] = fs.mean_sample_sd;
        if (!CHECK(t, fs.rc == PT_OK, "%s: pt_render %d", cases[c].name, fs.rc)) continue;
        CHECK(t, fs.nonfinite == 0, "%s: %llu non-finite samples", cases[c].name, (unsigned long long)fs.nonfinite);
        if (cases[c].split) CHECK(t, fs.split_paths > 0, "%s: no path split", cases[c].name);
        else CHECK(t, fs.split_paths == 0, "%s: max_splits < 0, yet %llu paths split", cases[c].name,
                   (unsigned long long)fs.split_paths);
        if (cases[c].split) /* (the controls without splitting are too skewed for a pixel's z-test at 128 spp) */
            CHECK(t, fs.accepted >= ACCEPT_FRACTION * fs.pixels, "%s: only %d of %d pixels pass the z-test against %g",
                  cases[c].name, fs.accepted, fs.pixels, want);
        CHECK(t, fabs(fs.image_z) <= IMAGE_Z, "%s: image mean %.6f +- %.2g, not %g (z = %+.2f)", cases[c].name,
              fs.image_mean, fs.image_se, want, fs.image_z);
        test_note(t, "%s: %.5f +- %.1e, %.2f splits/sample, sd %.3g", cases[c].name, fs.image_mean, fs.image_se,
                  (double)fs.split_paths / (32.0 * 32.0 * 128.0), fs.mean_sample_sd);
    }
    CHECK(t, sd[4] <= 0.9 * sd[5], "independent: splitting gives sd per sample %.3g, not 10 %% below %.3g without",
          sd[4], sd[5]);
    CHECK(t, sd[6] <= 0.9 * sd[7], "Sobol: splitting gives sd per sample %.3g, not 10 %% below %.3g without",
          sd[6], sd[7]);
    pt_scene_destroy(s);
}

/* Bounces per camera sample in the closed furnace (albedo 0.5: a cosine-sampled bounce has weight
   exactly 0.5, so the throughput is a known function of the depth) under section 7's roulette
   q = min(0.95, sqrt(gain b)) from depth 3 on: expectation and variance of the count N, from
   P(N >= n) = q_0 ... q_{n-1} (q_d = 1 below the start). */
static void roulette_bounces(double gain, int max_depth, double *mean, double *var)
{
    double b = 1.0, surv = 1.0, m = 0.0, m2 = 0.0;
    int d;
    for (d = 0; d < max_depth; d++) {
        double q = d + 1 >= 3 ? fmin(0.95, sqrt(gain * b)) : 1.0;
        surv *= q;                       /* P(N >= d + 1) */
        m += surv;
        m2 += (2.0 * (d + 1) - 1.0) * surv;
        b = 0.5 * b / q;
    }
    *mean = m;
    *var = m2 - m * m;
}

static void roulette_per_sampler(test_ctx *t)
{
    /* Russian roulette's survival probability q = min(0.95, sqrt(gain max(beta_in))) has gain 1
       with independent numbers and 2 (b_ref = 1/2) with Sobol (section 7). In the closed furnace
       (MATERIAL, no splitting, max_depth 50, 32 x 32 x 64 samples) the number of bounce rays per
       camera sample must match the exact expectation for the sampler's gain, 3.000 and 3.600:
       z-test at alpha = 0.01, Sidak over the two samplers, with the count's exact variance (Sobol's
       stratified coins only lower the true error, which makes the test more lenient for it). The
       two expectations are ~100 standard errors apart, so the wrong gain fails. The image is
       checked unbiased by the furnace tests above. */
    static const pt_sampler samplers[2] = {PT_SAMPLER_INDEPENDENT, PT_SAMPLER_SOBOL};
    pt_scene *s = furnace_scene(t);
    int c, rc;
    double zmax = tu_z_two_sided(tu_sidak(0.01, 2));
    if (!s) return;
    for (c = 0; c < 2; c++) {
        pt_render_desc d = furnace_view(64, 37000 + (uint64_t)c, PT_STRATEGY_MATERIAL, samplers[c]);
        pt_film f;
        pt_render_stats st;
        double want, var, got, z, n;
        d.indirect_paths = 1;
        roulette_bounces(c == 1 ? 2.0 : 1.0, 50, &want, &var);
        if (!CHECK(t, pt_film_init(&f, d.width, d.height) == PT_OK, "film")) break;
        rc = pt_render(s, &d, &f, &st);
        pt_film_free(&f);
        if (!CHECK(t, rc == PT_OK, "%s: pt_render %d", c ? "Sobol" : "independent", rc)) continue;
        n = (double)st.samples;
        got = (double)st.bounce_rays / n;
        z = (got - want) / sqrt(var / n);
        CHECK(t, st.split_paths == 0 && st.camera_rays == st.samples, "%s: %llu split paths, %llu camera rays for %llu samples",
              c ? "Sobol" : "independent", (unsigned long long)st.split_paths, (unsigned long long)st.camera_rays,
              (unsigned long long)st.samples);
        CHECK(t, fabs(z) <= zmax, "%s: %.4f bounce rays per sample, expected %.4f +- %.4f (z = %+.2f)",
              c ? "Sobol" : "independent", got, want, sqrt(var / n), z);
        test_note(t, "%s: %.4f bounces per sample (exact %.4f, z = %+.2f)", c ? "Sobol" : "independent", got, want, z);
    }
    pt_scene_destroy(s);
}

/* 1 if every ray through the pixel's 3 x 3 points hits the sphere (c, R) well inside its rim, 0 if
   every one misses it well outside, -1 for pixels on the rim. */
static int pixel_on_sphere(const pt_camera *cam, int x, int y, pt_vec3 c, float R)
{
    int a, b, on = 0, off = 0;
    for (a = 0; a <= 2; a++) {
        for (b = 0; b <= 2; b++) {
            pt_ray r = pt_camera_ray(cam, x + a / 2.0f, y + b / 2.0f, 0.5f, 0.5f);
            dv3 o = dv_from(r.origin), d = dnorm(dv_from(r.dir)), l = dsub(dv_from(c), o);
            double tb = ddot(l, d), perp = sqrt(fmax(ddot(l, l) - tb * tb, 0.0));
            if (perp < 0.98 * R && tb > 0) on++;
            else if (perp > 1.02 * R || tb < 0) off++;
        }
    }
    return on == 9 ? 1 : off == 9 ? 0 : -1;
}

static void furnace_environment(test_ctx *t)
{
    /* The open furnace of test_materials.c's furnace_spheres, lit by the environment light: a
       sphere alone under a uniform environment of radiance L = 0.7, given as the background, as a
       constant 2 x 2 map (0.35 x scale 2) and as both (background 0.2, map 0.5: the map and the
       uniform sphere mixed by power). Lossless glass (ior 1.5) and a mirror of albedo 1 return L
       in every pixel; a Lambertian sphere of albedo 0.8 is convex, so every scattered ray escapes
       after one bounce: 0.8 L. Pixels off the sphere see L. MIS for every material; MATERIAL,
       LIGHT and MIXTURE too for the Lambertian sphere (where next-event estimation of the
       environment happens). Russian roulette on (the default), max_depth 64. Each region of
       pixels wholly on / off the sphere (pixel_on_sphere) is compared with its exact value by a
       z-test with the film's standard error beyond the float floor. False-failure rate: 0.01 over
       the 36 comparisons (Sidak). */
    static const struct { const char *name; int kind; double expect; } mats[3] = {
        { "Lambertian 0.8", 0, 0.8 }, { "glass 1.5", 1, 1.0 }, { "mirror", 2, 1.0 } };
    static const char *envs[3] = { "background", "constant map", "background + map" };
    const double L = 0.7, zmax = tu_z_two_sided(tu_sidak(0.01, 36));
    const pt_vec3 c = pt_v3(0, 0, 0);
    const float R = 1.0f;
    pt_image map;
    double worst = 0.0;
    int mi, ei, strat, comparisons = 0, i;
    map.width = map.height = 2;
    map.rgb = (float *)malloc(sizeof(float) * 12);
    if (!CHECK(t, map.rgb != NULL, "out of memory")) return;
    for (i = 0; i < 12; i++) map.rgb[i] = 0.35f;
    for (mi = 0; mi < 3; mi++) {
        for (ei = 0; ei < 3; ei++) {
            pt_scene *s = pt_scene_create();
            pt_environment_desc ed;
            int m, rc;
            if (!CHECK(t, s != NULL, "scene")) break;
            m = mats[mi].kind == 0 ? pt_scene_add_lambertian(s, pt_v3(0.8f, 0.8f, 0.8f))
                                   : mats[mi].kind == 1 ? pt_scene_add_dielectric(s, 1.5f) : pt_scene_add_metal(s, pt_v3(1, 1, 1), 0.0f);
            rc = pt_scene_add_sphere(s, c, R, m);
            ed.map = &map;
            ed.scale = ei == 1 ? 2.0f : 1.0f / 0.7f; /* 0.7 or 0.5 */
            if (rc >= 0 && ei > 0) rc = pt_scene_set_environment(s, &ed);
            rc = rc >= 0 ? pt_scene_commit(s) : rc;
            if (!CHECK(t, rc == PT_OK, "%s, %s: %s", mats[mi].name, envs[ei], pt_scene_error_message(s))) {
                pt_scene_destroy(s);
                continue;
            }
            for (strat = 0; strat < 4; strat++) {
                /* (the Lambertian's estimates vary: 128 spp put its region means within ~0.4 %) */
                pt_render_desc d = tu_base_desc(32, 32, mats[mi].kind == 0 ? 128 : 16, 38000 + (uint64_t)(100 * mi + 10 * ei + strat));
                pt_film film;
                pt_render_stats st;
                pt_camera cam;
                double sum[2] = { 0, 0 }, var[2] = { 0, 0 };
                int n[2] = { 0, 0 }, x, y, k;
                float bg = ei == 0 ? 0.7f : ei == 1 ? 0.0f : 0.2f;
                if (strat != PT_STRATEGY_MIS && mats[mi].kind != 0) continue;
                d.camera.look_from = pt_v3(0.3f, 0.4f, -3.2f);
                d.camera.look_at = c;
                d.camera.vfov_degrees = 45;
                d.background = pt_v3(bg, bg, bg);
                d.max_depth = 64;
                d.strategy = (pt_strategy)strat;
                d.light_weight = 0.5f;
                if (!tu_render_into(t, s, &d, &film, &st, mats[mi].name)) { pt_film_free(&film); continue; }
                pt_camera_init(&cam, &d.camera, d.width, d.height);
                for (y = 0; y < d.height; y++)
                    for (x = 0; x < d.width; x++) {
                        int on = pixel_on_sphere(&cam, x, y, c, R);
                        pt_color mean, v;
                        if (on < 0) continue;
                        pt_film_pixel(&film, x, y, &mean, &v);
                        sum[on] += mean.y;
                        var[on] += v.y;
                        n[on]++;
                    }
                for (k = 0; k < 2; k++) {
                    double want = k == 1 ? mats[mi].expect * L : L, mean, se, z;
                    if (!CHECK(t, n[k] > 0, "%s: no pixels %s the sphere", mats[mi].name, k ? "on" : "off")) continue;
                    mean = sum[k] / n[k];
                    se = sqrt(var[k]) / n[k];
                    z = tu_z_floor(mean, want, se, TU_FLOAT_FLOOR * want);
                    comparisons++;
                    worst = fmax(worst, z);
                    if (tu_verbose())
                        printf("    %s, %s, %s, %s: %.6f +- %.2g (want %.6f, %d pixels)\n", mats[mi].name, envs[ei],
                               strategy_name(strat), k ? "on" : "off", mean, se, want, n[k]);
                    CHECK(t, z <= zmax, "%s, %s, %s: pixels %s the sphere average %.6f +- %.2g, want %.6f (|z| %.2f, limit %.2f)",
                          mats[mi].name, envs[ei], strategy_name(strat), k ? "on" : "off", mean, se, want, z, zmax);
                }
                pt_film_free(&film);
            }
            pt_scene_destroy(s);
        }
    }
    free(map.rgb);
    CHECK(t, comparisons == 36, "%d comparisons made, 36 expected (the Sidak family)", comparisons);
    test_note(t, "%d comparisons, max |z| %.2f (limit %.2f)", comparisons, worst, zmax);
}

const test_case test_analytic_cases[] = {
    TEST_CASE(image_sphere_light),
    TEST_CASE(image_quad_light),
    TEST_CASE(image_triangle_light),
    TEST_CASE(image_tiny_sphere_light),
    TEST_CASE(furnace_every_pixel),
    TEST_CASE(furnace_mirror_glass_in_emitter),
    TEST_CASE(furnace_indirect_paths),
    TEST_CASE(furnace_splitting),
    TEST_CASE(roulette_per_sampler),
    TEST_CASE(furnace_environment),
    TEST_END
};
