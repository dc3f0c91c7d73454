#define _POSIX_C_SOURCE 200809L
/* test_adaptive.c - adaptive sampling (pdftrace.h section 8) and the scene-feature skip switches
   (PT_SKIP_*, section 7).

   adaptive: easy pixels stop and noisy ones keep sampling, and a quiet pixel beside noisy ones
   keeps sampling (its noise is planned from its neighbours); the allocation is per pixel, finer
   than 4x4 blocks; samples go to pixels in proportion to the square root
   of their noise (Neyman) and the image reaches the threshold, by the test's own error estimate
   from the film's half-buffers; the default, planned from a discarded pilot, is unbiased (a
   paired t-test on a scene where re-planning from a pixel's own samples is ~30 % dark, which the
   same test must catch), its film is the uniform render's first n_i samples and its plan ignores
   the film's samples; with PT_ADAPTIVE_NEIGHBOURS the image mean agrees with a
   uniform render (z-tests, with most pixels stopped early on a scene with caustics), and with
   PT_ADAPTIVE_OWN_SAMPLES it is within the documented stopping bias and takes
   fewer samples; a pixel that drew a firefly samples on with own samples and stops with
   neighbours only (its 24 neighbours sample on instead); films are bit-identical across thread counts, tile sizes and host
   parallel-fors; threshold 0 is the uniform path bit for bit (checked against a render rebuilt
   here from pt_trace_path); invalid settings are rejected before anything is rendered.
   skips: each PT_SKIP_* bit's general path gives the same image: bit for bit where the skip is
   exact, within noise (per-region z-tests) where it draws random numbers differently.

   Statistical checks use fixed seeds. The z-tests of this file form one family: alpha = 0.01,
   Sidak-corrected over ADAPTIVE_Z_TESTS comparisons; pilot_unbiased's t-test is its own, at
   alpha = 0.01. */
#include "test_util.h"

#ifndef PDFTRACE_NO_THREADS
#include <pthread.h>
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define ADAPTIVE_Z_TESTS 160 /* 16 regions x (1 adaptive-vs-uniform + 9 skip comparisons) */
#define FAMILY_ALPHA 0.01

static double z_limit(void) { return tu_z_two_sided(tu_sidak(FAMILY_ALPHA, ADAPTIVE_Z_TESTS)); }

/* Per-region z-tests (4 x 4 regions, channel 1) between two renders of the same expectation.
   Returns the number of regions with |z| above the family limit; *worst gets the largest |z|. */
static int compare_regions(const pt_film *a, const pt_film *b, double *worst)
{
    tu_region ra[16], rb[16];
    int i, fails = 0;
    double zlim = z_limit();
    tu_film_regions(a, 4, 4, ra);
    tu_film_regions(b, 4, 4, rb);
    for (i = 0; i < 16; i++) {
        double se = sqrt(ra[i].se[1] * ra[i].se[1] + rb[i].se[1] * rb[i].se[1]);
        double z = tu_z_floor(ra[i].mean[1], rb[i].mean[1], se, TU_FLOAT_FLOOR * fabs(rb[i].mean[1]));
        if (z > *worst) *worst = z;
        fails += z > zlim;
    }
    return fails;
}

/* The test's own error estimate for the pixels of [x0,x1) x [y0,y1), from the film's sums: the mean
   over pixels and channels of Var(I)/(I^2 + 0.01), Var(I) estimated from the half means A (even
   sample indices) and B (odd) as (A - B)^2 nA nB / n^2. */
static double block_estimate(const pt_film *f, int x0, int y0, int x1, int y1)
{
    double acc = 0;
    int x, y, c, terms = 0;
    for (y = y0; y < y1 && y < f->height; y++)
        for (x = x0; x < x1 && x < f->width; x++) {
            size_t i = (size_t)y * f->width + x;
            double n = f->count[i], nb = (double)(f->count[i] / 2), na = n - nb;
            for (c = 0; c < 3; c++) {
                double sb = f->sum_odd[3 * i + c], s = f->sum[3 * i + c];
                double a = (s - sb) / na, b = sb / nb, m = s / n;
                acc += (a - b) * (a - b) * na * nb / (n * n) / (m * m + 0.01);
                terms++;
            }
        }
    return acc / terms;
}

/* ------------------------------------------------------------------------------------------ */
/* scenes                                                                                      */

/* A wall z = 0 seen head-on (screen right is -x) under a sky of radiance 1: its part on the
   image's left (x > 0) is a two-sided emitter of radiance 1 (every sample exactly 1: zero
   variance), the rest a Lambertian wall with a checker far finer than a pixel (albedo 0.1 or 0.9
   at random under the pixel jitter; every bounce sees radiance 1, so a sample is its albedo:
   noisy). The image is 64 x 16, the boundary at the centre of pixel column 32, so columns 0-31
   of each row see only the emitter. */
/* A Lambertian material with a checker far finer than a pixel (the pixel jitter picks `a` or
   `b` with probability 1/2 each). */
static int fine_checker(pt_scene *s, float a, float b)
{
    pt_material_desc md;
    int tex = pt_scene_add_checker(s, pt_v3(a, a, a), pt_v3(b, b, b), 0.0013f);
    if (tex < 0) return tex;
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_LAMBERTIAN;
    md.albedo_texture = tex;
    return pt_scene_add_material(s, &md);
}

/* The view both wall scenes below are rendered with: 64 x 16 pixels, 64 spp, vfov 30 from
   z = -10 towards the wall at z = 0, MATERIAL, a white background. */
static void stripes_desc(pt_render_desc *d, uint64_t seed)
{
    *d = tu_base_desc(64, 16, 64, seed);
    d->camera.look_from = pt_v3(0, 0, -10);
    d->camera.look_at = pt_v3(0, 0, 0);
    d->camera.vfov_degrees = 30;
    d->strategy = PT_STRATEGY_MATERIAL;
    d->background = pt_v3(1, 1, 1);
}

/* The wall of half_easy_scene with materials left (image left, x > 0) and right. */
static pt_scene *two_halves_scene(pt_render_desc *d, int left_glows, float la, float lb)
{
    pt_scene *s = pt_scene_create();
    int glow, wall, rc;
    float half_w;
    if (!s) return NULL;
    glow = left_glows ? pt_scene_add_emitter(s, pt_v3(1, 1, 1), 1) : fine_checker(s, la, lb);
    wall = fine_checker(s, 0.1f, 0.9f);
    /* vfov 30 at distance 10: half height 10 tan 15deg, half width 4x that (64 x 16 pixels) */
    half_w = 4.0f * 10.0f * (float)tan(15.0 * TU_PI / 180.0);
    /* the boundary: half a pixel right of the image centre, at x = -(pixel width 2 half_w / 64) / 2 */
    rc = pt_scene_add_quad(s, pt_v3(-half_w / 64.0f, -50, 0), pt_v3(50, 0, 0), pt_v3(0, 100, 0), glow);
    rc |= pt_scene_add_quad(s, pt_v3(-50, -50, 0), pt_v3(50.0f - half_w / 64.0f, 0, 0), pt_v3(0, 100, 0), wall);
    if (glow < 0 || wall < 0 || rc < 0 || pt_scene_commit(s) != PT_OK) { pt_scene_destroy(s); return NULL; }
    stripes_desc(d, 99);
    return s;
}
static pt_scene *half_easy_scene(pt_render_desc *d) { return two_halves_scene(d, 1, 0, 0); }

/* A small box room lit by a quad light, with a mirror, a glass and a white sphere: noise that
   varies over the image, every skip but "no emitters" and "no triangles" applicable. */
static pt_scene *room_scene(pt_render_desc *d, int w, int h, int spp)
{
    pt_scene *s = pt_scene_create();
    int white, red, light, mirror, glass, rc;
    if (!s) return NULL;
    white = pt_scene_add_lambertian(s, pt_v3(0.7f, 0.7f, 0.7f));
    red = pt_scene_add_lambertian(s, pt_v3(0.7f, 0.1f, 0.1f));
    light = pt_scene_add_emitter(s, pt_v3(12, 12, 12), 0);
    mirror = pt_scene_add_metal(s, pt_v3(0.9f, 0.9f, 0.9f), 0);
    glass = pt_scene_add_dielectric(s, 1.5f);
    rc = pt_scene_add_quad(s, pt_v3(-2, 0, -2), pt_v3(4, 0, 0), pt_v3(0, 0, 4), white);     /* floor */
    rc |= pt_scene_add_quad(s, pt_v3(-2, 3, -2), pt_v3(0, 0, 4), pt_v3(4, 0, 0), white);    /* ceiling */
    rc |= pt_scene_add_quad(s, pt_v3(-2, 0, 2), pt_v3(4, 0, 0), pt_v3(0, 3, 0), white);     /* back */
    rc |= pt_scene_add_quad(s, pt_v3(-2, 0, -2), pt_v3(0, 0, 4), pt_v3(0, 3, 0), red);      /* left */
    rc |= pt_scene_add_quad(s, pt_v3(2, 0, -2), pt_v3(0, 3, 0), pt_v3(0, 0, 4), white);     /* right */
    rc |= pt_scene_add_quad(s, pt_v3(-0.5f, 2.99f, -0.5f), pt_v3(1, 0, 0), pt_v3(0, 0, 1), light); /* faces down */
    rc |= pt_scene_add_sphere(s, pt_v3(-0.8f, 0.6f, 0.5f), 0.6f, mirror);
    rc |= pt_scene_add_sphere(s, pt_v3(0.9f, 0.5f, -0.2f), 0.5f, glass);
    rc |= pt_scene_add_sphere(s, pt_v3(0.2f, 0.3f, 1.2f), 0.3f, white);
    if (rc < 0 || pt_scene_commit(s) != PT_OK) { pt_scene_destroy(s); return NULL; }
    *d = tu_base_desc(w, h, spp, 7);
    d->camera.look_from = pt_v3(0, 1.5f, -5.5f);
    d->camera.look_at = pt_v3(0, 1.3f, 0);
    d->camera.vfov_degrees = 45;
    d->max_depth = 8;
    return s;
}

/* ------------------------------------------------------------------------------------------ */
/* adaptive sampling                                                                           */

static void easy_region_stops(test_ctx *t)
{
    /* A pixel's noise is planned from the pixels of its 5x5 neighbourhood (itself included: zero
       here for every emitter pixel). Columns 0-29 (every neighbour a zero-variance emitter pixel)
       stop at once: re-planned from the film (own samples) after the first 8 samples; with the
       pilot (the default) the film gets the least, 2, after the pilot's 8. Columns 30 and 31 are
       emitter pixels too, but column 32 (half emitter, half noisy wall) is within reach, so they
       keep sampling (no seam where the noise starts); the noisy pixels would need more than the
       64 samples allowed (relative variance 0.16 / 0.26 per sample over half the image: 123
       samples for T = 0.05) and all sample to the cap (64, or 64 - 8 beside the pilot). */
    int mode;
    for (mode = 0; mode < 2; mode++) {
        pt_render_desc d;
        pt_scene *s = half_easy_scene(&d);
        pt_film f;
        pt_render_stats st;
        const char *name = mode ? "pilot" : "own samples";
        const uint32_t easy = mode ? 2u : 8u, cap = mode ? 56u : 64u;
        int x, y, bad_easy = 0, bad_rest = 0;
        uint64_t below = 0, want_samples = mode ? 1024u * 8u + 30u * 16u * 2u + 34u * 16u * 56u : 30u * 16u * 8u + 34u * 16u * 64u;
        if (!CHECK(t, s != NULL, "scene")) return;
        d.adaptive_threshold = 0.05f;
        d.adaptive_min_spp = 8;
        d.samples_per_pass = 4;
        d.adaptive_mode = mode ? PT_ADAPTIVE_PILOT : PT_ADAPTIVE_OWN_SAMPLES;
        if (tu_render_into(t, s, &d, &f, &st, name)) {
            for (y = 0; y < 16; y++)
                for (x = 0; x < 64; x++) {
                    uint32_t n = f.count[y * 64 + x];
                    below += n < cap;
                    if (x < 30) bad_easy += n != easy;
                    else bad_rest += n != cap;
                }
            CHECK(t, bad_easy == 0, "%s: %d pixels of columns 0-29 got other than %u samples", name, bad_easy, easy);
            CHECK(t, bad_rest == 0, "%s: %d pixels of columns 30-63 (30, 31: near the noise) got other than %u samples",
                  name, bad_rest, cap);
            CHECK(t, st.pixels_converged == below && below == 30u * 16u, "%s: stats.pixels_converged %llu, film: %llu below %u",
                  name, (unsigned long long)st.pixels_converged, (unsigned long long)below, cap);
            CHECK(t, st.min_spp == easy && st.max_spp == cap, "%s: stats spp range %u..%u, want %u..%u", name, st.min_spp,
                  st.max_spp, easy, cap);
            CHECK(t, st.samples == want_samples, "%s: stats.samples %llu, want %llu", name, (unsigned long long)st.samples,
                  (unsigned long long)want_samples);
            test_note(t, "%s: %llu of 1024 pixels stopped at %u spp, %llu samples", name,
                      (unsigned long long)st.pixels_converged, easy, (unsigned long long)st.samples);
        }
        pt_film_free(&f);
        pt_scene_destroy(s);
    }
}

/* The noisy wall of two_halves_scene (64 x 16 pixels) behind stripes of emitter (radiance 1, two
   sided, 0.01 in front of the wall): pixel columns 8s + 1 .. 8s + 6 (s = 0..7) see only emitter
   (every sample exactly 1), columns 8s + 7 and 8s + 8 the noisy checker. Each stripe reaches 0.1 pixel into the
   columns beside it, so float rounding at its edges cannot put a wall sample in a stripe pixel. */
static pt_scene *stripes_scene(pt_render_desc *d)
{
    pt_scene *s = pt_scene_create();
    int glow, wall, rc, k;
    float hw0, hw1;
    if (!s) return NULL;
    glow = pt_scene_add_emitter(s, pt_v3(1, 1, 1), 1);
    wall = fine_checker(s, 0.1f, 0.9f);
    hw0 = 4.0f * 10.0f * (float)tan(15.0 * TU_PI / 180.0); /* half width of the view at the wall */
    hw1 = hw0 * 9.99f / 10.0f;                               /* ... at the stripes */
    rc = pt_scene_add_quad(s, pt_v3(-50, -50, 0), pt_v3(100, 0, 0), pt_v3(0, 100, 0), wall);
    for (k = 0; k < 8; k++) {
        /* screen column c's left edge is at x = hw (1 - 2c / 64) (screen right is -x) */
        float xa = hw1 * (1.0f - 2.0f * (8.0f * (float)k + 7.1f) / 64.0f);
        float xb = hw1 * (1.0f - 2.0f * (8.0f * (float)k + 0.9f) / 64.0f);
        rc |= pt_scene_add_quad(s, pt_v3(xa, -50, -0.01f), pt_v3(xb - xa, 0, 0), pt_v3(0, 100, 0), glow);
    }
    if (glow < 0 || wall < 0 || rc < 0 || pt_scene_commit(s) != PT_OK) { pt_scene_destroy(s); return NULL; }
    stripes_desc(d, 5);
    return s;
}

static void per_pixel_allocation(test_ctx *t)
{
    /* Noise in 2 of every 8 columns: the middle two columns of each 6-column emitter stripe (no
       noise within their 5x5 neighbourhood) stop at once (own samples: after 8; pilot: the
       film's least, 2, after the pilot's 8); every other pixel (noisy, or near noise) samples to
       the cap (64; 56 beside the pilot: T = 0.03 is out of reach, 25 % of the pixels with
       relative variance 0.62 per sample would need 170). An allocation in 4x4 blocks would stop
       no pixel here (every block holds a noisy column). */
    int mode;
    for (mode = 0; mode < 2; mode++) {
        pt_render_desc d;
        pt_scene *s = stripes_scene(&d);
        pt_film f;
        pt_render_stats st;
        const char *name = mode ? "pilot" : "own samples";
        const uint32_t quiet_n = mode ? 2u : 8u, cap = mode ? 56u : 64u;
        int x, y, bad_quiet = 0, bad_rest = 0;
        if (!CHECK(t, s != NULL, "scene")) return;
        d.adaptive_threshold = 0.03f;
        d.adaptive_min_spp = 8;
        d.samples_per_pass = 4;
        d.adaptive_mode = mode ? PT_ADAPTIVE_PILOT : PT_ADAPTIVE_OWN_SAMPLES;
        if (tu_render_into(t, s, &d, &f, &st, name)) {
            for (y = 0; y < 16; y++)
                for (x = 0; x < 64; x++) {
                    int quiet = x % 8 == 3 || x % 8 == 4;
                    uint32_t n = f.count[y * 64 + x];
                    if (quiet) bad_quiet += n != quiet_n;
                    else bad_rest += n != cap;
                }
            CHECK(t, bad_quiet == 0, "%s: %d of 256 stripe-centre pixels got other than %u samples", name, bad_quiet,
                  quiet_n);
            CHECK(t, bad_rest == 0, "%s: %d of 768 other pixels got other than %u samples", name, bad_rest, cap);
            CHECK(t, st.pixels_converged == 256u, "%s: stats.pixels_converged %llu, want 256", name,
                  (unsigned long long)st.pixels_converged);
            test_note(t, "%s: %llu of 1024 pixels stopped at %u spp", name, (unsigned long long)st.pixels_converged, quiet_n);
        }
        pt_film_free(&f);
        pt_scene_destroy(s);
    }
}

static void neyman_allocation(test_ctx *t)
{
    /* Two halves of known noise: albedo 0.4 or 0.6 (left) and 0.1 or 0.9 (right), each with
       probability 1/2 per sample, so the relative variance of one sample is v = 0.01/0.26 and
       0.16/0.26: the right half needs sqrt(16) = 4 times the samples of the left one (uniform
       sampling would give 1, stopping at equal error 16). Checks the ratio of the mean counts of
       the pixels away from the boundary (2.5 to 6), that every pixel stopped, that the image's
       estimated RMS relative error (stats, and the test's own estimate) is near the threshold
       (0.7 T to 1.1 T), and that pt_film_error agrees with the test's estimator on every block. */
    pt_render_desc d;
    pt_scene *s = two_halves_scene(&d, 0, 0.4f, 0.6f);
    pt_film f;
    pt_render_stats st;
    const float T = 0.05f;
    int x, y, bx, mismatch = 0;
    double nl = 0, nr = 0, ratio, own;
    if (!CHECK(t, s != NULL, "scene")) return;
    d.samples_per_pixel = 512;
    d.samples_per_pass = 4;
    d.adaptive_threshold = T;
    if (tu_render_into(t, s, &d, &f, &st, "adaptive")) {
        for (y = 0; y < 16; y++)
            for (x = 0; x < 64; x++) {
                if (x < 24) nl += f.count[y * 64 + x];
                if (x >= 40) nr += f.count[y * 64 + x];
            }
        ratio = nr / nl;
        for (y = 0; y < 16; y += 4)
            for (bx = 0; bx < 16; bx++) {
                double e = block_estimate(&f, bx * 4, y, bx * 4 + 4, y + 4), lib = -1;
                pt_film_error(&f, bx * 4, y, bx * 4 + 4, y + 4, &lib);
                mismatch += !(fabs(lib - e) <= 1e-9 * e + 1e-300);
            }
        own = sqrt(block_estimate(&f, 0, 0, 64, 16));
        CHECK(t, ratio > 2.5 && ratio < 6.0, "samples right/left %.2f, want ~4 (sqrt of the noise ratio)", ratio);
        CHECK(t, st.pixels_converged == 1024u, "%llu of 1024 pixels stopped", (unsigned long long)st.pixels_converged);
        CHECK(t, fabs(st.estimated_error - own) <= 1e-9 * own, "stats.estimated_error %.6g, test's estimate %.6g",
              st.estimated_error, own);
        CHECK(t, own > 0.7 * T && own < 1.1 * T, "estimated RMS relative error %.4f, threshold %.4f", own, (double)T);
        CHECK(t, mismatch == 0, "pt_film_error differs from the test's estimate in %d blocks", mismatch);
        test_note(t, "spp left %.1f, right %.1f (ratio %.2f), estimated error %.4f for threshold %.2f", nl / (24 * 16),
                  nr / (24 * 16), ratio, own, (double)T);
    }
    pt_film_free(&f);
    pt_scene_destroy(s);
}

static void mean_matches_uniform(test_ctx *t)
{
    /* The re-planning modes' image against a uniform render with another seed (room scene:
       caustics, so rare bright samples; the default, the pilot, is checked by pilot_unbiased).
       PT_ADAPTIVE_NEIGHBOURS: 16 region means (channel 1), z-tests in the file's family (its
       bias, -0.4 % of the image mean over seeds 7-46, is below one render's noise).
       PT_ADAPTIVE_OWN_SAMPLES (a pixel's own samples count) has the stopping bias of section 8: its
       image mean over the neighbours-only one of the same seed (the two share most of their
       noise) was -0.79 % with a standard deviation of 0.24 % over seeds 7-46 (range -1.32 % to
       -0.33 %); it must lie in [-2 %, +0.5 %], 5 standard deviations either side (false failure
       ~1e-6 if normal). Planning a pixel from its own noise alone gives about -3 % and fails
       it. Own samples must also take fewer samples (a pixel that drew no firefly stops at its
       share). */
    pt_render_desc d;
    pt_scene *s = room_scene(&d, 48, 40, 96);
    pt_film a, o, u;
    pt_render_stats sa, so, su;
    double worst = 0;
    int fails;
    if (!CHECK(t, s != NULL, "scene")) return;
    d.adaptive_threshold = 0.18f;
    d.adaptive_min_spp = 16;
    d.adaptive_mode = PT_ADAPTIVE_OWN_SAMPLES;
    if (tu_render_into(t, s, &d, &o, &so, "adaptive (own samples)")) {
        pt_render_desc n = d;
        n.adaptive_mode = PT_ADAPTIVE_NEIGHBOURS;
        if (tu_render_into(t, s, &n, &a, &sa, "adaptive (neighbours only)")) {
            pt_render_desc e = d;
            e.adaptive_threshold = 0;
            e.seed = d.seed + 1000;
            if (tu_render_into(t, s, &e, &u, &su, "uniform")) {
                tu_region ro[1], rn[1];
                double ratio;
                fails = compare_regions(&a, &u, &worst);
                CHECK(t, fails == 0, "neighbours only: %d of 16 regions differ (|z| > %.2f, max %.2f)", fails, z_limit(),
                      worst);
                CHECK(t, sa.pixels_converged > 0 && sa.pixels_converged < 48u * 40u,
                      "%llu of %d pixels stopped early: want some, not all", (unsigned long long)sa.pixels_converged,
                      48 * 40);
                tu_film_regions(&o, 1, 1, ro);
                tu_film_regions(&a, 1, 1, rn);
                ratio = ro[0].mean[1] / rn[0].mean[1];
                CHECK(t, ratio > 0.98 && ratio < 1.005,
                      "own samples: image mean %.4f x the neighbours-only one, want in [0.98, 1.005]", ratio);
                CHECK(t, so.samples < sa.samples, "own samples took %llu samples, neighbours only %llu: want fewer",
                      (unsigned long long)so.samples, (unsigned long long)sa.samples);
                test_note(t, "neighbours only: max |z| %.2f (limit %.2f), %.0f%% of pixels stopped early, %.0f%% of the "
                          "samples; own samples: image mean %+.2f%% against it, %.0f%% of the samples", worst, z_limit(),
                          100.0 * (double)sa.pixels_converged / (48.0 * 40.0), 100.0 * (double)sa.samples / (double)su.samples,
                          100.0 * (ratio - 1.0), 100.0 * (double)so.samples / (double)su.samples);
            }
            pt_film_free(&u);
        }
        pt_film_free(&a);
    }
    pt_film_free(&o);
    pt_scene_destroy(s);
}

static void own_samples_dilute_fireflies(test_ctx *t)
{
    /* The emitter half of half_easy_scene (every sample exactly 1) after 8 uniform samples per
       pixel, plus one injected firefly (a 9th sample of 50) in pixel (10, 8); then adaptive
       sampling into the same film, cap 64 more samples, checks after 2. The noisy half is out of
       reach for T = 0.05, so every pixel with noise > 0 samples to its cap. Own samples:
       the firefly pixel and the pixels whose 5x5 neighbourhood holds it sample to the cap, diluting
       the firefly; neighbours only: the firefly pixel's own noise is not counted, so it stops
       after 2 samples with its firefly undiluted while the 24 around it sample on (a ring).
       Pixels whose 5x5 neighbourhood sees neither the firefly nor the noisy half stop after 2. */
    int mode;
    for (mode = 0; mode < 2; mode++) {
        pt_render_desc d;
        pt_scene *s = half_easy_scene(&d);
        pt_film f;
        pt_render_stats st;
        const int px = 10, py = 8, cap = 8 + 64; /* the others' cap; the firefly pixel's is 9 + 64 */
        const char *name = mode ? "neighbours only" : "own samples";
        int x, y, bad_block = 0, bad_far = 0;
        size_t p = (size_t)py * 64 + px;
        if (!CHECK(t, s != NULL, "scene")) return;
        d.samples_per_pixel = 8;
        if (tu_render_into(t, s, &d, &f, &st, "uniform 8 spp")) {
            int c;
            for (c = 0; c < 3; c++) { /* the 9th sample (index 8: half-buffer A) */
                f.sum[3 * p + c] += 50.0;
                f.sum_sq[3 * p + c] += 2500.0;
            }
            f.count[p] += 1;
            d.samples_per_pixel = 64;
            d.samples_per_pass = 2;
            d.adaptive_threshold = 0.05f;
            d.adaptive_min_spp = 2;
            d.adaptive_mode = mode ? PT_ADAPTIVE_NEIGHBOURS : PT_ADAPTIVE_OWN_SAMPLES;
            d.seed += 1;
            if (CHECK(t, pt_render(s, &d, &f, &st) == PT_OK, "adaptive render: %s", st.error)) {
                double fire = f.sum[3 * p + 1] / (double)f.count[p];
                for (y = 0; y < 16; y++)
                    for (x = 0; x < 28; x++) {
                        uint32_t n = f.count[y * 64 + x];
                        int dx = x - px, dy = y - py, in = dx >= -2 && dx <= 2 && dy >= -2 && dy <= 2;
                        if (x == px && y == py) continue;
                        if (in) bad_block += n != (uint32_t)cap;
                        else bad_far += n != 8u + 2u;
                    }
                if (mode == 0)
                    CHECK(t, f.count[p] == (uint32_t)cap + 1u, "own samples: the firefly pixel took %u samples, want %d",
                          f.count[p], cap + 1);
                else
                    CHECK(t, f.count[p] == 9u + 2u, "neighbours only: the firefly pixel took %u samples, want 11",
                          f.count[p]);
                CHECK(t, bad_block == 0, "%s: %d of the 24 pixels around the firefly did not sample to the cap", name,
                      bad_block);
                CHECK(t, bad_far == 0, "%s: %d quiet pixels far from the firefly did not stop after 2 samples", name,
                      bad_far);
                test_note(t, "%s: firefly pixel %u samples, mean %.2f (true 1)", name, f.count[p], fire);
            }
        }
        pt_film_free(&f);
        pt_scene_destroy(s);
    }
}

/* P(|T| > t) for Student's t with df degrees of freedom, I_{df/(df+t^2)}(df/2, 1/2): the
   regularised incomplete beta function by its continued fraction (Abramowitz & Stegun 26.5.8,
   modified Lentz evaluation; the symmetry I_x(a, b) = 1 - I_{1-x}(b, a) where it converges
   slowly). */
static double beta_cf(double a, double b, double x)
{
    double c = 1.0, d = 1.0 - (a + b) * x / (a + 1.0), f;
    int m;
    d = 1.0 / (fabs(d) < 1e-300 ? 1e-300 : d);
    f = d;
    for (m = 1; m < 500; ++m) {
        double num, delta;
        int half;
        for (half = 0; half < 2; ++half) {
            num = half == 0 ? m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m))
                            : -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0));
            d = 1.0 + num * d;
            c = 1.0 + num / c;
            d = 1.0 / (fabs(d) < 1e-300 ? 1e-300 : d);
            if (fabs(c) < 1e-300) c = 1e-300;
            delta = d * c;
            f *= delta;
        }
        if (fabs(delta - 1.0) < 1e-14) break;
    }
    return f;
}
static double t_two_sided(double t, double df)
{
    double a = 0.5 * df, b = 0.5, x = df / (df + t * t), front;
    if (x >= 1.0) return 1.0;
    front = exp(lgamma(a + b) - lgamma(a) - lgamma(b) + a * log(x) + b * log(1.0 - x));
    if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_cf(a, b, x) / a;
    return 1.0 - front * beta_cf(b, a, 1.0 - x) / b;
}

/* Sparkles: a black view (stripes_desc, background 0) with a small two-sided emitter of radiance
   8 in the middle of each pixel (x, y) with x % 5 == 2 and y % 5 == 2 (39 pixels), half a pixel
   wide and a quarter high: a sample of such a pixel is 8 with probability 1/8, else 0 (mean 1);
   every other pixel is exactly 0. No two sparkle pixels share a 5x5 neighbourhood. */
static pt_scene *sparkle_scene(pt_render_desc *d)
{
    pt_scene *s = pt_scene_create();
    int glow, rc = 0, x, y;
    float hh = 10.0f * (float)tan(15.0 * TU_PI / 180.0), hw = 4.0f * hh, px = 2.0f * hw / 64.0f;
    if (!s) return NULL;
    glow = pt_scene_add_emitter(s, pt_v3(8, 8, 8), 1);
    for (y = 2; y < 16; y += 5)
        for (x = 2; x < 64; x += 5) {
            /* pixel (x, y)'s centre on the plane z = 0 (screen right is -x, row 0 at the top) */
            float cx = hw * (1.0f - 2.0f * ((float)x + 0.5f) / 64.0f), cy = hh * (1.0f - 2.0f * ((float)y + 0.5f) / 16.0f);
            rc |= pt_scene_add_quad(s, pt_v3(cx - px / 4, cy - px / 8, 0), pt_v3(px / 2, 0, 0), pt_v3(0, px / 4, 0), glow);
        }
    if (glow < 0 || rc < 0 || pt_scene_commit(s) != PT_OK) { pt_scene_destroy(s); return NULL; }
    stripes_desc(d, 1);
    d->background = pt_v3(0, 0, 0);
    return s;
}

#define PILOT_SEEDS 64
static void pilot_unbiased(test_ctx *t)
{
    /* The default (PT_ADAPTIVE_PILOT) keeps the uniform render's expectation; re-planning from
       the image's own samples does not. Sparkle scene, cap 64 spp, T = 0.05, pilot / minimum 8
       spp, seeds 1..PILOT_SEEDS. Own samples: a sparkle pixel whose first 8 samples missed its
       emitter (probability (7/8)^8 = 0.34) has zero noise in its whole 5x5 neighbourhood and
       stops with the value 0: the image is about a third too dark. The pilot's film holds the
       first n_i samples of the uniform render of the same seed, n_i fixed by the discarded
       pilot, so D = adaptive image mean - uniform image mean (channel G) is paired, and its
       mean over the seeds is the bias: a one-sample t-test (df = seeds - 1) at alpha 0.01. The
       pilot must pass it and own samples must fail it (the test's power: it fails on the old
       default). */
    double dp[PILOT_SEEDS], dn[PILOT_SEEDS], mean_u = 0.0, samples_p = 0.0, total = 0.0;
    int k;
    for (k = 0; k < PILOT_SEEDS; k++) {
        pt_render_desc d;
        pt_scene *s = sparkle_scene(&d);
        pt_film u, a, o;
        pt_render_stats su, sa, so;
        int ok = 0;
        if (!CHECK(t, s != NULL, "scene")) return;
        d.seed = 1u + (uint64_t)k;
        if (tu_render_into(t, s, &d, &u, &su, "uniform")) {
            pt_render_desc e = d;
            e.adaptive_threshold = 0.05f;
            e.adaptive_min_spp = 8;
            if (tu_render_into(t, s, &e, &a, &sa, "pilot")) {
                e.adaptive_mode = PT_ADAPTIVE_OWN_SAMPLES;
                if (tu_render_into(t, s, &e, &o, &so, "own samples")) {
                    tu_region ru, ra, ro;
                    tu_film_regions(&u, 1, 1, &ru);
                    tu_film_regions(&a, 1, 1, &ra);
                    tu_film_regions(&o, 1, 1, &ro);
                    dp[k] = ra.mean[1] - ru.mean[1];
                    dn[k] = ro.mean[1] - ru.mean[1];
                    mean_u += ru.mean[1] / PILOT_SEEDS;
                    samples_p += (double)sa.samples;
                    total += (double)su.samples;
                    ok = 1;
                }
                pt_film_free(&o);
            }
            pt_film_free(&a);
        }
        pt_film_free(&u);
        pt_scene_destroy(s);
        if (!ok) return;
    }
    {
        tu_acc ap, ao;
        double tp, tn, pp, pn;
        memset(&ap, 0, sizeof ap);
        memset(&ao, 0, sizeof ao);
        for (k = 0; k < PILOT_SEEDS; k++) {
            tu_acc_add(&ap, dp[k]);
            tu_acc_add(&ao, dn[k]);
        }
        tp = tu_acc_se(&ap) > 0 ? ap.mean / tu_acc_se(&ap) : 0.0;
        tn = tu_acc_se(&ao) > 0 ? ao.mean / tu_acc_se(&ao) : 0.0;
        pp = t_two_sided(fabs(tp), PILOT_SEEDS - 1);
        pn = t_two_sided(fabs(tn), PILOT_SEEDS - 1);
        CHECK(t, pp >= 0.01, "pilot: image mean %+.2f %% against uniform (t %.2f, p %.2g < 0.01)", 100.0 * ap.mean / mean_u,
              tp, pp);
        CHECK(t, pn < 0.01 && tn < 0, "own samples: image mean %+.2f %% against uniform (t %.2f, p %.2g): the test "
              "does not see its bias", 100.0 * ao.mean / mean_u, tn, pn);
        test_note(t, "pilot: image mean %+.2f %% (t %.2f, p %.2g; %.0f %% of the samples); own samples %+.1f %% (t %.1f)",
                  100.0 * ap.mean / mean_u, tp, pp, 100.0 * samples_p / total, 100.0 * ao.mean / mean_u, tn);
    }
}

/* Adds pixel pix's samples first .. first + n - 1 (seed d->seed, the documented stream and camera
   ray of threshold_zero_is_uniform) to film g, as pt_render would. */
static void rebuild_samples(const pt_scene *s, const pt_render_desc *d, const pt_camera *cam, pt_film *g, int x, int y,
                            uint32_t first, uint32_t n)
{
    uint32_t pix = (uint32_t)(y * d->width + x), k;
    for (k = first; k < first + n; k++) {
        pt_rng rng = pt_rng_for_sample(d->seed, pix, k);
        float jx = pt_rng_float(&rng), jy = pt_rng_float(&rng);
        float l1 = pt_rng_float(&rng), l2 = pt_rng_float(&rng);
        pt_color L = pt_trace_path(s, d, pt_camera_ray(cam, (float)x + jx, (float)y + jy, l1, l2), &rng, NULL);
        pt_film_add_sample(g, x, y, k, L);
    }
}

static void pilot_film_is_uniform_prefix(test_ctx *t)
{
    /* The pilot's samples are not in the image: pixel i of the film holds exactly the uniform
       render's first n_i samples (rebuilt here from pt_trace_path), 2 <= n_i <= cap - pilot; the
       stats count the pilot's samples too. Also into a film that already holds 3 samples per
       pixel (a resumed render: samples 3 .. 3 + n_i - 1). */
    int resumed;
    for (resumed = 0; resumed < 2; resumed++) {
        pt_render_desc d;
        pt_scene *s = room_scene(&d, 20, 16, 24);
        pt_film f, g;
        pt_render_stats st;
        pt_camera cam;
        int x, y, bad_range = 0;
        uint64_t film_samples = 0;
        const uint32_t base = resumed ? 3u : 0u;
        if (!CHECK(t, s != NULL, "scene")) return;
        d.adaptive_threshold = 0.3f;
        d.adaptive_min_spp = 6;
        d.samples_per_pass = 4;
        if (!CHECK(t, pt_film_init(&f, d.width, d.height) == PT_OK && pt_film_init(&g, d.width, d.height) == PT_OK, "films")) {
            pt_scene_destroy(s);
            return;
        }
        pt_camera_init(&cam, &d.camera, d.width, d.height);
        if (resumed) {
            pt_render_desc u = d;
            u.adaptive_threshold = 0.0f;
            u.samples_per_pixel = 3;
            CHECK(t, pt_render(s, &u, &f, &st) == PT_OK, "the first 3 samples: %s", st.error);
        }
        if (CHECK(t, pt_render(s, &d, &f, &st) == PT_OK, "pilot render: %s", st.error)) {
            for (y = 0; y < d.height; y++)
                for (x = 0; x < d.width; x++) {
                    uint32_t n = f.count[y * d.width + x] - base;
                    bad_range += n < 2u || n > 24u - 6u;
                    film_samples += n;
                    rebuild_samples(s, &d, &cam, &g, x, y, 0, base + n);
                }
            CHECK(t, tu_film_equal(&f, &g), "%s: the film is not the uniform render's first n_i samples",
                  resumed ? "resumed" : "fresh");
            CHECK(t, bad_range == 0, "%d pixels outside 2..18 film samples", bad_range);
            CHECK(t, st.samples == film_samples + 6u * 20u * 16u, "stats.samples %llu, want %llu film + %u pilot samples",
                  (unsigned long long)st.samples, (unsigned long long)film_samples, 6u * 20u * 16u);
            CHECK(t, st.min_spp < st.max_spp, "every pixel got %u samples: no adaptation", st.min_spp);
            test_note(t, "%s: film %u..%u spp, %llu samples with the pilot's", resumed ? "resumed" : "fresh", st.min_spp,
                      st.max_spp, (unsigned long long)st.samples);
        }
        pt_film_free(&f);
        pt_film_free(&g);
        pt_scene_destroy(s);
    }
}

static void pilot_plan_ignores_film(test_ctx *t)
{
    /* The plan depends on the pilot alone: a film holding a firefly (one injected sample of 50
       after 8 uniform ones, as in own_samples_dilute_fireflies) gets exactly the samples per
       pixel that the same film without it gets. With a pilot that leaves no room (pilot + 2 >
       samples_per_pixel) the render is uniform, bit for bit. adaptive_neighbours_only = 1 is
       adaptive_mode PT_ADAPTIVE_NEIGHBOURS, bit for bit. */
    pt_render_desc d;
    pt_scene *s = half_easy_scene(&d);
    pt_film a, b;
    pt_render_stats st;
    int c, diff = 0;
    size_t i, p = 8 * 64 + 10;
    if (!CHECK(t, s != NULL, "scene")) return;
    d.samples_per_pixel = 8;
    if (tu_render_into(t, s, &d, &a, &st, "uniform 8 spp") && tu_render_into(t, s, &d, &b, &st, "uniform 8 spp")) {
        pt_render_desc e = d;
        for (c = 0; c < 3; c++) {
            b.sum[3 * p + c] += 50.0;
            b.sum_sq[3 * p + c] += 2500.0;
        }
        b.count[p] += 1;
        e.samples_per_pixel = 64;
        e.adaptive_threshold = 0.05f;
        e.adaptive_min_spp = 4;
        e.seed += 1;
        if (CHECK(t, pt_render(s, &e, &a, &st) == PT_OK && pt_render(s, &e, &b, &st) == PT_OK, "pilot renders: %s",
                  st.error)) {
            for (i = 0; i < 64u * 16u; i++) diff += b.count[i] - (i == p) != a.count[i];
            CHECK(t, diff == 0, "%d pixels took other counts with a firefly in the film", diff);
            CHECK(t, a.count[p] - 8u < 64u - 4u, "the firefly pixel took %u samples: no adaptation", a.count[p] - 8u);
        }
    }
    pt_film_free(&a);
    pt_film_free(&b);
    {
        pt_render_desc e = d, n;
        pt_film u;
        e.samples_per_pixel = 9;
        e.adaptive_threshold = 0.05f;
        e.adaptive_min_spp = 8;
        n = e;
        n.adaptive_threshold = 0.0f;
        if (tu_render_into(t, s, &e, &a, &st, "pilot, no room") && tu_render_into(t, s, &n, &u, NULL, "uniform"))
            CHECK(t, tu_film_equal(&a, &u) && st.pixels_converged == 0, "pilot without room: not the uniform render");
        pt_film_free(&a);
        pt_film_free(&u);
        e.samples_per_pixel = 32;
        e.adaptive_mode = PT_ADAPTIVE_NEIGHBOURS;
        n = e;
        n.adaptive_mode = PT_ADAPTIVE_PILOT;
        n.adaptive_neighbours_only = 1;
        if (tu_render_into(t, s, &e, &a, NULL, "neighbours") && tu_render_into(t, s, &n, &b, NULL, "neighbours_only 1"))
            CHECK(t, tu_film_equal(&a, &b), "adaptive_neighbours_only = 1 differs from PT_ADAPTIVE_NEIGHBOURS");
        pt_film_free(&a);
        pt_film_free(&b);
    }
    pt_scene_destroy(s);
}

static void host_reverse(void *user, int count, pt_job_fn job, void *job_data)
{
    int i;
    (void)user;
    for (i = count - 1; i >= 0; i--) job(job_data, i);
}

static void threads_bit_identical(test_ctx *t)
{
    /* The adaptive film with threads 1, 2, 3, tile size 5 and a host parallel-for running tiles in
       reverse: identical bit for bit (sums, squares, half-buffers, counts), with stopped pixels,
       in the pilot mode (the default) and the re-planning one (own samples). */
    int mode;
    for (mode = 0; mode < 2; mode++) {
        pt_render_desc d;
        pt_scene *s = room_scene(&d, 40, 32, 32);
        pt_film ref, f;
        pt_render_stats st, st0;
        int k;
        const char *names[4] = { "threads=2", "threads=3", "tile_size=5, threads=2", "host parallel_for (reverse)" };
        const char *mname = mode ? "own samples" : "pilot";
        if (!CHECK(t, s != NULL, "scene")) return;
        d.adaptive_threshold = 0.21f;
        d.adaptive_min_spp = 8;
        d.samples_per_pass = 4;
        d.adaptive_mode = mode ? PT_ADAPTIVE_OWN_SAMPLES : PT_ADAPTIVE_PILOT;
        d.threads = 1;
        if (!tu_render_into(t, s, &d, &ref, &st0, "threads=1")) { pt_film_free(&ref); pt_scene_destroy(s); return; }
        CHECK(t, st0.pixels_converged > 0 && st0.pixels_converged < 40u * 32u, "%s: %llu pixels converged: want some, not all",
              mname, (unsigned long long)st0.pixels_converged);
        for (k = 0; k < 4; k++) {
            pt_render_desc e = d;
            e.threads = k == 1 ? 3 : 2;
            if (k == 2) e.tile_size = 5;
            if (k == 3) { e.parallel_for = host_reverse; e.threads = 1; }
            if (tu_render_into(t, s, &e, &f, &st, names[k])) {
                CHECK(t, tu_film_equal(&ref, &f), "%s, %s: film differs from threads=1", mname, names[k]);
                CHECK(t, st.samples == st0.samples && st.pixels_converged == st0.pixels_converged,
                      "%s, %s: stats differ from threads=1", mname, names[k]);
            }
            pt_film_free(&f);
        }
        test_note(t, "%s: 5 renders, %llu of 1280 pixels stopped early, bit-identical", mname,
                  (unsigned long long)st0.pixels_converged);
        pt_film_free(&ref);
        pt_scene_destroy(s);
    }
}

static void threshold_zero_is_uniform(test_ctx *t)
{
    /* adaptive_threshold 0 is the uniform renderer: the film equals one rebuilt here sample by
       sample from pt_trace_path (the documented stream pt_rng_for_sample(seed, pixel, k), jitter,
       lens, path), and the other adaptive settings are ignored. */
    pt_render_desc d;
    pt_scene *s = room_scene(&d, 20, 16, 6);
    pt_film f, g;
    pt_camera cam;
    int x, y, k, diff = 0;
    if (!CHECK(t, s != NULL, "scene")) return;
    d.samples_per_pass = 4; /* 4 + 2 */
    if (tu_render_into(t, s, &d, &f, NULL, "threshold 0")) {
        pt_camera_init(&cam, &d.camera, d.width, d.height);
        if (CHECK(t, pt_film_init(&g, d.width, d.height) == PT_OK, "film")) {
            for (y = 0; y < d.height; y++)
                for (x = 0; x < d.width; x++) {
                    uint32_t pix = (uint32_t)(y * d.width + x);
                    for (k = 0; k < 6; k++) {
                        pt_rng rng = pt_rng_for_sample(d.seed, pix, (uint32_t)k);
                        float jx = pt_rng_float(&rng), jy = pt_rng_float(&rng);
                        float l1 = pt_rng_float(&rng), l2 = pt_rng_float(&rng);
                        pt_ray r = pt_camera_ray(&cam, (float)x + jx, (float)y + jy, l1, l2);
                        pt_color L = pt_trace_path(s, &d, r, &rng, NULL);
                        pt_film_add_sample(&g, x, y, (uint32_t)k, L);
                    }
                }
            CHECK(t, tu_film_equal(&f, &g), "the render differs from the sample-by-sample rebuild");
            pt_film_free(&g);
        }
        {   /* min spp and check interval are ignored when the threshold is 0 */
            pt_render_desc e = d;
            e.adaptive_min_spp = 2;
            e.adaptive_check_passes = 1;
            if (tu_render_into(t, s, &e, &g, NULL, "threshold 0, other settings")) diff = !tu_film_equal(&f, &g);
            CHECK(t, !diff, "adaptive_min_spp/check_passes changed a render with threshold 0");
            pt_film_free(&g);
        }
    }
    pt_film_free(&f);
    pt_scene_destroy(s);
}

static void invalid_settings(test_ctx *t)
{
    /* Each bad value returns PT_ERROR_INVALID_ARGUMENT, renders nothing and names the setting. */
    pt_render_desc d;
    pt_scene *s = room_scene(&d, 8, 8, 4);
    pt_film f;
    int k, i;
    const char *names[14] = { "threshold -0.1", "threshold NaN", "threshold +Inf", "min_spp -1", "min_spp 1",
                              "check_passes -1", "disable_skips removed bit 1u << 1", "disable_skips ~0",
                              "disable_skips removed bit 1u << 5", "neighbours_only 2", "neighbours_only -1",
                              "adaptive_mode 3", "adaptive_mode -1", "neighbours_only 1 with own samples" };
    if (!CHECK(t, s != NULL, "scene")) return;
    if (!CHECK(t, pt_film_init(&f, 8, 8) == PT_OK, "film")) { pt_scene_destroy(s); return; }
    for (k = 0; k < 14; k++) {
        pt_render_desc e = d;
        pt_render_stats st;
        int rc, touched = 0;
        e.adaptive_threshold = 0.1f;
        if (k == 0) e.adaptive_threshold = -0.1f;
        if (k == 1) e.adaptive_threshold = (float)(0.0 * HUGE_VAL);
        if (k == 2) e.adaptive_threshold = (float)HUGE_VAL;
        if (k == 3) e.adaptive_min_spp = -1;
        if (k == 4) e.adaptive_min_spp = 1;
        if (k == 5) e.adaptive_check_passes = -1;
        if (k == 6) e.disable_skips = 1u << 1; /* was PT_SKIP_LIGHT_SELECTION, removed */
        if (k == 7) e.disable_skips = ~0u;
        if (k == 8) e.disable_skips = 1u << 5; /* was PT_SKIP_NO_TRIANGLES, removed */
        if (k == 9) e.adaptive_neighbours_only = 2;
        if (k == 10) e.adaptive_neighbours_only = -1;
        if (k == 11) e.adaptive_mode = (pt_adaptive_mode)3;
        if (k == 12) e.adaptive_mode = (pt_adaptive_mode)-1;
        if (k == 13) { e.adaptive_neighbours_only = 1; e.adaptive_mode = PT_ADAPTIVE_OWN_SAMPLES; }
        rc = pt_render(s, &e, &f, &st);
        for (i = 0; i < 64; i++) touched += f.count[i] != 0;
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "%s: pt_render returned %d", names[k], rc);
        CHECK(t, touched == 0 && st.samples == 0, "%s: %d pixels rendered", names[k], touched);
        CHECK(t, strstr(st.error, k >= 11 ? "adaptive_mode" : k >= 9 ? "adaptive_neighbours_only" : k >= 6 ? "disable_skips" : "adaptive") != NULL,
              "%s: message '%s'", names[k], st.error);
    }
    {   /* the valid extremes work: every skip disabled, min_spp 2, check every pass, neighbours only */
        pt_render_desc e = d;
        pt_render_stats st;
        e.adaptive_threshold = 0.1f;
        e.adaptive_min_spp = 2;
        e.adaptive_check_passes = 1;
        e.adaptive_neighbours_only = 1;
        e.disable_skips = PT_SKIP_ALL;
        CHECK(t, pt_render(s, &e, &f, &st) == PT_OK, "valid extreme settings rejected: %s", st.error);
    }
    pt_film_free(&f);
    pt_scene_destroy(s);
}

/* ------------------------------------------------------------------------------------------ */
/* scene-feature skips                                                                         */

/* Renders d with and without `bits` disabled; exact: the films must be equal; otherwise 16 region
   z-tests (and the films must differ, showing that the general path ran). */
static void skip_case(test_ctx *t, const pt_scene *s, const pt_render_desc *d, unsigned bits, int exact,
                      const char *what, double *worst)
{
    pt_film a, b;
    pt_render_stats sa, sb;
    pt_render_desc e = *d;
    e.disable_skips = bits;
    if (tu_render_into(t, s, d, &a, &sa, what) && tu_render_into(t, s, &e, &b, &sb, what)) {
        if (exact) {
            CHECK(t, tu_film_equal(&a, &b), "%s: the general path changed the film", what);
        } else {
            int fails = compare_regions(&a, &b, worst);
            CHECK(t, fails == 0, "%s: %d of 16 regions differ (|z| > %.2f, max %.2f)", what, fails, z_limit(), *worst);
            CHECK(t, !tu_film_equal(&a, &b), "%s: the same film: the general path did not run", what);
        }
        if ((bits & PT_SKIP_ZERO_BSDF_SHADOW) && d->strategy == PT_STRATEGY_MIS)
            CHECK(t, sb.shadow_rays > sa.shadow_rays, "%s: %llu shadow rays with the general path, %llu without", what,
                  (unsigned long long)sb.shadow_rays, (unsigned long long)sa.shadow_rays);
    }
    pt_film_free(&a);
    pt_film_free(&b);
}

static void skips_exact(test_ctx *t)
{
    /* Untextured albedo, zero-BSDF shadow rays: the general path changes no random number, so
       the films are bit-identical (MIS and mixture). */
    pt_render_desc d;
    pt_scene *s = room_scene(&d, 24, 20, 8);
    double worst = 0;
    static const unsigned bits[2] = { PT_SKIP_NO_TEXTURES, PT_SKIP_ZERO_BSDF_SHADOW };
    static const char *names[2] = { "no textures", "zero-BSDF shadow" };
    int k, strat;
    if (!CHECK(t, s != NULL, "scene")) return;
    for (strat = 0; strat < 2; strat++)
        for (k = 0; k < 2; k++) {
            char what[96];
            d.strategy = strat ? PT_STRATEGY_MIXTURE : PT_STRATEGY_MIS;
            snprintf(what, sizeof what, "%s (%s)", names[k], strat ? "mixture" : "MIS");
            skip_case(t, s, &d, bits[k], 1, what, &worst);
        }
    test_note(t, "4 pairs of films bit-identical");
    pt_scene_destroy(s);
}

static void skips_within_noise(test_ctx *t)
{
    /* The skips that draw random numbers differently: no emitters (a scene lit by delta lights
       alone, no emitting shape and no environment: MIS, light, mixture), delta vertex (mirror and glass: MIS, light), one-sided light facing away (mixture;
       the ceiling and the light's back are behind it), every skip at once (MIS), and solid-angle
       sampling of a large rectangular light close to a floor (MIS), and the light tree against
       selection by power (40 small lights, MIS). 9 comparisons of 16 regions in the file's family. */
    pt_render_desc d;
    pt_scene *s = room_scene(&d, 32, 24, 48), *sky;
    double worst = 0;
    int k;
    if (!CHECK(t, s != NULL, "scene")) return;
    d.strategy = PT_STRATEGY_MIS;
    skip_case(t, s, &d, PT_SKIP_DELTA_VERTEX, 0, "delta vertex (MIS)", &worst);
    d.strategy = PT_STRATEGY_LIGHT;
    skip_case(t, s, &d, PT_SKIP_DELTA_VERTEX, 0, "delta vertex (light)", &worst);
    d.strategy = PT_STRATEGY_MIXTURE;
    skip_case(t, s, &d, PT_SKIP_FACING_AWAY, 0, "facing away (mixture)", &worst);
    d.strategy = PT_STRATEGY_MIS;
    skip_case(t, s, &d, PT_SKIP_ALL, 0, "all (MIS)", &worst);
    pt_scene_destroy(s);

    /* solid-angle quads: a 2 x 2 light 0.8 above a floor, so every floor point samples it by
       solid angle, and the general path by area */
    s = pt_scene_create();
    if (!CHECK(t, s != NULL, "panel scene")) return;
    {
        int white = pt_scene_add_lambertian(s, pt_v3(0.6f, 0.6f, 0.6f)), lamp = pt_scene_add_emitter(s, pt_v3(2, 2, 2), 0);
        int rc = pt_scene_add_quad(s, pt_v3(-3, 0, -3), pt_v3(0, 0, 6), pt_v3(6, 0, 0), white);
        rc |= pt_scene_add_quad(s, pt_v3(-1, 0.8f, -1), pt_v3(2, 0, 0), pt_v3(0, 0, 2), lamp); /* faces down */
        if (!CHECK(t, rc >= 0 && pt_scene_commit(s) == PT_OK, "panel scene: %s", pt_scene_error_message(s))) {
            pt_scene_destroy(s);
            return;
        }
    }
    d = tu_base_desc(32, 24, 16, 13);
    d.camera.look_from = pt_v3(0, 0.6f, -2.5f);
    d.camera.look_at = pt_v3(0, 0.2f, 0);
    d.max_depth = 3;
    skip_case(t, s, &d, PT_SKIP_SOLID_ANGLE_QUADS, 0, "solid-angle quads (MIS)", &worst);
    pt_scene_destroy(s);

    /* the light tree: 40 small one-sided lights of different powers under a ceiling and on a wall */
    s = pt_scene_create();
    if (!CHECK(t, s != NULL, "many-lights scene")) return;
    {
        int white = pt_scene_add_lambertian(s, pt_v3(0.6f, 0.6f, 0.6f)), rc, j;
        rc = pt_scene_add_quad(s, pt_v3(-3, 0, -3), pt_v3(0, 0, 6), pt_v3(6, 0, 0), white);
        rc |= pt_scene_add_quad(s, pt_v3(-3, 0, 3), pt_v3(6, 0, 0), pt_v3(0, 3, 0), white);
        for (j = 0; j < 40; j++) {
            float L = 1.0f + (float)(j % 7) * 3.0f, x = -2.8f + 0.7f * (float)(j % 8);
            int m = pt_scene_add_emitter(s, pt_v3(L, L, L), 0);
            if (j < 24) rc |= pt_scene_add_quad(s, pt_v3(x, 2.9f, -2.5f + 0.9f * (float)(j / 8)), pt_v3(0.3f, 0, 0),
                                                pt_v3(0, 0, 0.3f), m); /* faces down */
            else rc |= pt_scene_add_quad(s, pt_v3(x, 0.4f + 0.8f * (float)((j - 24) / 8), 2.99f), pt_v3(0, 0.3f, 0),
                                         pt_v3(0.3f, 0, 0), m); /* on the back wall, facing -z */
        }
        if (!CHECK(t, rc >= 0 && pt_scene_commit(s) == PT_OK, "many-lights scene: %s", pt_scene_error_message(s))) {
            pt_scene_destroy(s);
            return;
        }
    }
    d = tu_base_desc(32, 24, 16, 17);
    d.camera.look_from = pt_v3(0, 1.5f, -2.5f);
    d.camera.look_at = pt_v3(0, 1.0f, 3);
    d.max_depth = 3;
    skip_case(t, s, &d, PT_SKIP_LIGHT_TREE, 0, "light tree (MIS)", &worst);
    pt_scene_destroy(s);

    /* no emitters: an open scene (floor, two spheres) lit by a sun and a lamp (delta lights; a sky
       would be an environment light, which next-event estimation samples) */
    sky = pt_scene_create();
    if (!CHECK(t, sky != NULL, "sky scene")) return;
    {
        int white = pt_scene_add_lambertian(sky, pt_v3(0.6f, 0.6f, 0.6f));
        int rc = pt_scene_add_quad(sky, pt_v3(-5, 0, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), white);
        rc |= pt_scene_add_sphere(sky, pt_v3(-0.6f, 0.5f, 0), 0.5f, white);
        rc |= pt_scene_add_sphere(sky, pt_v3(0.6f, 0.5f, 0), 0.5f, pt_scene_add_metal(sky, pt_v3(0.8f, 0.8f, 0.8f), 0.3f));
        {
            pt_light_desc sun, lamp;
            memset(&sun, 0, sizeof sun);
            sun.type = PT_LIGHT_DIRECTIONAL;
            sun.direction = pt_v3(0.3f, -1.0f, 0.4f);
            sun.intensity = pt_v3(2, 2, 2);
            lamp = sun;
            lamp.type = PT_LIGHT_POINT;
            lamp.position = pt_v3(-1.0f, 2.0f, -1.0f);
            lamp.intensity = pt_v3(3, 3, 3);
            rc |= pt_scene_add_light(sky, &sun);
            rc |= pt_scene_add_light(sky, &lamp);
        }
        if (!CHECK(t, rc >= 0 && pt_scene_commit(sky) == PT_OK, "sky scene: %s", pt_scene_error_message(sky))) {
            pt_scene_destroy(sky);
            return;
        }
    }
    d = tu_base_desc(32, 24, 32, 11);
    d.camera.look_from = pt_v3(0, 1.2f, -4);
    d.camera.look_at = pt_v3(0, 0.4f, 0);
    d.max_depth = 6;
    for (k = 0; k < 3; k++) {
        static const pt_strategy st[3] = { PT_STRATEGY_MIS, PT_STRATEGY_LIGHT, PT_STRATEGY_MIXTURE };
        static const char *nm[3] = { "no emitters (MIS)", "no emitters (light)", "no emitters (mixture)" };
        d.strategy = st[k];
        skip_case(t, sky, &d, PT_SKIP_NO_EMITTERS, 0, nm[k], &worst);
    }
    pt_scene_destroy(sky);
    test_note(t, "9 comparisons of 16 regions, max |z| %.2f (limit %.2f: alpha 0.01 Sidak over %d)", worst, z_limit(),
              ADAPTIVE_Z_TESTS);
}

const test_case test_adaptive_cases[] = {
    TEST_CASE(easy_region_stops),
    TEST_CASE(per_pixel_allocation),
    TEST_CASE(neyman_allocation),
    TEST_CASE(mean_matches_uniform),
    TEST_CASE(own_samples_dilute_fireflies),
    TEST_CASE(pilot_unbiased),
    TEST_CASE(pilot_film_is_uniform_prefix),
    TEST_CASE(pilot_plan_ignores_film),
    TEST_CASE(threads_bit_identical),
    TEST_CASE(threshold_zero_is_uniform),
    TEST_CASE(invalid_settings),
    TEST_CASE(skips_exact),
    TEST_CASE(skips_within_noise),
    TEST_END
};
