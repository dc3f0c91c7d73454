/* test_materials.c - section 4 of pdftrace.h: materials and textures.

   Checker parity against floor(x/s)+floor(y/s)+floor(z/s); delta flags; furnace-like scenes lit only
   by a uniform background (glass, mirror and Lambertian spheres must render to their exact values);
   Fresnel reflectance of a glass slab against the exact unpolarised Fresnel equations; a perfect
   mirror reflecting an emitter; one- and two-sided emission.

   Statistical checks share alpha = 0.01, Sidak-corrected over MAT_STAT_TESTS comparisons. */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAT_STAT_TESTS 200
#define FILE_ALPHA 0.01

static double alpha_each(void) { return tu_sidak(FILE_ALPHA, MAT_STAT_TESTS); }


static void checker_parity(test_ctx *t)
{
    /* odd where floor(x/s) + floor(y/s) + floor(z/s) is odd, in world space, negative coordinates too */
    pt_scene *s = pt_scene_create();
    pt_color even = pt_v3(0.1f, 0.2f, 0.3f), odd = pt_v3(0.9f, 0.8f, 0.7f);
    const float scale = 0.37f;
    int tex, i, bad = 0, checked = 0, n_odd = 0;
    pt_rng rng;
    if (!CHECK(t, s != NULL, "scene")) return;
    tex = pt_scene_add_checker(s, even, odd, scale);
    CHECK(t, tex >= 1, "checker id %d", tex);
    pt_rng_seed(&rng, 2001, 1);
    for (i = 0; i < 20000; i++) {
        pt_vec3 p = pt_v3((float)(20 * tu_rand(&rng) - 10), (float)(20 * tu_rand(&rng) - 10), (float)(20 * tu_rand(&rng) - 10));
        double q[3] = { p.x / (double)scale, p.y / (double)scale, p.z / (double)scale }, sum = 0;
        int k, near = 0, is_odd;
        pt_color c;
        for (k = 0; k < 3; k++) {
            double f = floor(q[k]);
            if (q[k] - f < 1e-4 || f + 1 - q[k] < 1e-4) near = 1;
            sum += f;
        }
        if (near) continue;
        is_odd = fmod(fabs(sum), 2.0) == 1.0;
        n_odd += is_odd;
        c = pt_scene_eval_texture(s, tex, p);
        checked++;
        if (is_odd ? (c.x != odd.x || c.y != odd.y || c.z != odd.z) : (c.x != even.x || c.y != even.y || c.z != even.z)) {
            if (bad++ == 0)
                test_note(t, "first mismatch at (%g, %g, %g): got (%g, %g, %g), want %s", p.x, p.y, p.z, c.x, c.y, c.z,
                          is_odd ? "odd" : "even");
        }
    }
    CHECK(t, bad == 0, "%d of %d points have the wrong checker colour", bad, checked);
    CHECK(t, n_odd > checked / 3 && n_odd < 2 * checked / 3, "odd cells %d of %d", n_odd, checked);
    test_note(t, "%d points", checked);
    pt_scene_destroy(s);
}

static void checker_in_render(test_ctx *t)
{
    /* A checkered Lambertian floor under a uniform sky of radiance 1, no emitters, one bounce,
       MATERIAL: every cosine-sampled ray escapes (nothing else in the scene), so each sample is
       exactly the albedo at the hit point (MIS would also sample the sky as a light). Pixels whose whole footprint lies in one checker cell must equal that cell's
       colour; the footprint is traced through pt_camera_ray to the plane y = 0. */
    pt_scene *s = pt_scene_create();
    pt_color even = pt_v3(0.2f, 0.3f, 0.4f), odd = pt_v3(0.8f, 0.6f, 0.5f);
    const float scale = 0.5f;
    pt_render_desc d = tu_base_desc(40, 30, 4, 12345);
    pt_material_desc md;
    pt_film film;
    pt_render_stats st;
    pt_camera cam;
    int tex, m, rc, x, y, bad = 0, checked = 0;
    if (!CHECK(t, s != NULL, "scene")) return;
    tex = pt_scene_add_checker(s, even, odd, scale);
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_LAMBERTIAN;
    md.albedo = pt_v3(1, 0, 1);
    md.albedo_texture = tex;
    m = pt_scene_add_material(s, &md);
    rc = pt_scene_add_quad(s, pt_v3(-50, 0, -50), pt_v3(0, 0, 100), pt_v3(100, 0, 0), m);
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    d.camera.look_from = pt_v3(0.3f, 2.0f, -3.0f);
    d.camera.look_at = pt_v3(0.1f, 0.0f, 1.0f);
    d.camera.vfov_degrees = 50;
    d.max_depth = 1;
    d.background = pt_v3(1, 1, 1);
    d.strategy = PT_STRATEGY_MATERIAL;
    d.threads = 1;
    rc = pt_film_init(&film, d.width, d.height);
    if (!CHECK(t, rc == PT_OK, "film")) { pt_scene_destroy(s); return; }
    rc = pt_render(s, &d, &film, &st);
    CHECK(t, rc == PT_OK && st.nonfinite_samples == 0, "render: %d, %llu non-finite", rc, (unsigned long long)st.nonfinite_samples);
    pt_camera_init(&cam, &d.camera, d.width, d.height);
    for (y = 0; y < d.height; y++) {
        for (x = 0; x < d.width; x++) {
            int cell = -1, uniform = 1, a, b;
            pt_color mean, var;
            for (a = 0; a <= 4 && uniform; a++) {
                for (b = 0; b <= 4 && uniform; b++) {
                    pt_ray r = pt_camera_ray(&cam, x + a / 4.0f, y + b / 4.0f, 0.5f, 0.5f);
                    double tt, px, pz, sum;
                    int c, k;
                    if (r.dir.y >= 0) { uniform = 0; break; }
                    tt = -(double)r.origin.y / r.dir.y;
                    px = r.origin.x + tt * r.dir.x;
                    pz = r.origin.z + tt * r.dir.z;
                    sum = floor(px / scale) + floor(0.0 / scale) + floor(pz / scale);
                    c = fmod(fabs(sum), 2.0) == 1.0;
                    for (k = 0; k < 2; k++) {
                        double q = (k == 0 ? px : pz) / scale;
                        if (q - floor(q) < 0.02 || ceil(q) - q < 0.02) uniform = 0;
                    }
                    if (cell >= 0 && c != cell) uniform = 0;
                    cell = c;
                }
            }
            if (!uniform) continue;
            pt_film_pixel(&film, x, y, &mean, &var);
            {
                pt_color want = cell ? odd : even;
                checked++;
                if (fabs(mean.x - want.x) > 1e-4 || fabs(mean.y - want.y) > 1e-4 || fabs(mean.z - want.z) > 1e-4) bad++;
            }
        }
    }
    CHECK(t, bad == 0, "%d of %d pixels inside one checker cell differ from its colour (1e-4)", bad, checked);
    CHECK(t, checked > 200, "only %d pixels checked", checked);
    test_note(t, "%d pixels inside single cells", checked);
    pt_film_free(&film);
    pt_scene_destroy(s);
}

static void delta_flags(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    int lam, mirror, fuzzy, glass, emit;
    if (!CHECK(t, s != NULL, "scene")) return;
    lam = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    mirror = pt_scene_add_metal(s, pt_v3(0.9f, 0.9f, 0.9f), 0.0f);
    fuzzy = pt_scene_add_metal(s, pt_v3(0.9f, 0.9f, 0.9f), 0.3f);
    glass = pt_scene_add_dielectric(s, 1.5f);
    emit = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0);
    CHECK(t, pt_material_is_delta(s, lam) == 0, "Lambertian is delta");
    CHECK(t, pt_material_is_delta(s, mirror) == 1, "mirror (fuzz 0) is not delta");
    CHECK(t, pt_material_is_delta(s, fuzzy) == 0, "fuzzy metal is delta");
    CHECK(t, pt_material_is_delta(s, glass) == 1, "dielectric is not delta");
    CHECK(t, pt_material_is_delta(s, emit) == 1, "an emitter (scatters nothing) is not reported delta");
    pt_scene_destroy(s);
}

/* Pixels whose footprint lies entirely on (1) or entirely off (0) the sphere; -1 otherwise. */
static int pixel_on_sphere(const pt_camera *cam, int x, int y, pt_vec3 c, float R)
{
    int a, b, on = 0, off = 0;
    for (a = 0; a <= 2; a++) {
        for (b = 0; b <= 2; b++) {
            pt_ray r = pt_camera_ray(cam, x + a / 2.0f, y + b / 2.0f, 0.5f, 0.5f);
            dv3 o = dv_from(r.origin), d = dnorm(dv_from(r.dir)), l = dsub(dv_from(c), o);
            double tb = ddot(l, d), perp2 = ddot(l, l) - tb * tb;
            if (sqrt(fmax(perp2, 0)) < 0.98 * R && tb > 0) on++;
            else if (sqrt(fmax(perp2, 0)) > 1.02 * R || tb < 0) off++;
        }
    }
    return on == 9 ? 1 : off == 9 ? 0 : -1;
}

static void furnace_spheres(test_ctx *t)
{
    /* A sphere in an empty world with uniform background radiance 1 and no emitters. Clear glass
       (ior 1.5 and 2.4) and a mirror of albedo 1 lose no energy: every pixel is 1. A Lambertian sphere
       of albedo 0.5 is convex, so every scattered ray escapes: its pixels are 0.5. Each region of
       pixels wholly on / off the sphere is compared with its exact value by a z-test with the film's
       standard error, beyond a float-precision floor of 1e-4 relative (test_util.h). With and
       without Russian roulette; every strategy. */
    struct { const char *name; int kind; float param; double expect; } mats[4] = {
        { "glass 1.5", 0, 1.5f, 1.0 }, { "glass 2.4", 0, 2.4f, 1.0 }, { "mirror", 1, 0.0f, 1.0 }, { "Lambertian 0.5", 2, 0.5f, 0.5 } };
    double zmax = tu_z_two_sided(alpha_each()), worst = 0;
    int mi, rr, strat, total_bad = 0, comparisons = 0;
    for (mi = 0; mi < 4; mi++) {
        pt_scene *s = pt_scene_create();
        pt_vec3 c = pt_v3(0, 0, 0);
        float R = 1.0f;
        int m, rc;
        if (!CHECK(t, s != NULL, "scene")) return;
        m = mats[mi].kind == 0 ? pt_scene_add_dielectric(s, mats[mi].param)
                               : mats[mi].kind == 1 ? pt_scene_add_metal(s, pt_v3(1, 1, 1), 0.0f)
                                                   : pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
        rc = pt_scene_add_sphere(s, c, R, m);
        rc = rc >= 0 ? pt_scene_commit(s) : rc;
        if (!CHECK(t, rc == PT_OK, "%s: %s", mats[mi].name, pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        for (rr = 0; rr < 2; rr++) {
            for (strat = 0; strat < 4; strat++) {
                pt_render_desc d = tu_base_desc(24, 24, 16, 12345);
                pt_film film;
                pt_render_stats st;
                pt_camera cam;
                double sum_on = 0, var_on = 0, sum_off = 0, var_off = 0;
                int n_on = 0, n_off = 0, x, y, k;
                if (rr == 0 && strat != 0) continue; /* RR off: MIS only */
                d.camera.look_from = pt_v3(0, 0, -3.2f);
                d.camera.look_at = c;
                d.camera.vfov_degrees = 45;
                d.background = pt_v3(1, 1, 1);
                d.rr_start_depth = rr == 0 ? -1 : 0;
                d.strategy = (pt_strategy)strat;
                d.threads = 2;
                d.seed = 700 + mi * 10 + strat;
                if (pt_film_init(&film, d.width, d.height) != PT_OK) { CHECK(t, 0, "film"); break; }
                rc = pt_render(s, &d, &film, &st);
                CHECK(t, rc == PT_OK && st.nonfinite_samples == 0, "%s: render %d, %llu non-finite samples", mats[mi].name, rc,
                      (unsigned long long)st.nonfinite_samples);
                pt_camera_init(&cam, &d.camera, d.width, d.height);
                for (y = 0; y < d.height; y++) {
                    for (x = 0; x < d.width; x++) {
                        int on = pixel_on_sphere(&cam, x, y, c, R);
                        pt_color mean, var;
                        if (on < 0) continue;
                        pt_film_pixel(&film, x, y, &mean, &var);
                        if (on) { sum_on += mean.y; var_on += var.y; n_on++; }
                        else { sum_off += mean.y; var_off += var.y; n_off++; }
                    }
                }
                for (k = 0; k < 2; k++) {
                    int n = k == 0 ? n_on : n_off;
                    double mean = (k == 0 ? sum_on : sum_off) / n, se = sqrt(k == 0 ? var_on : var_off) / n;
                    double want = k == 0 ? mats[mi].expect : 1.0, z;
                    if (n == 0) { CHECK(t, 0, "%s: no pixels %s the sphere", mats[mi].name, k == 0 ? "on" : "off"); continue; }
                    comparisons++;
                    z = tu_z_floor(mean, want, se, TU_FLOAT_FLOOR * want);
                    if (z > worst) worst = z;
                    if (z > zmax) {
                        total_bad++;
                        CHECK(t, 0, "%s, strategy %d, RR %s: pixels %s the sphere average %.6f +- %.2g, want %.6f",
                              mats[mi].name, strat, rr ? "on" : "off", k == 0 ? "on" : "off", mean, se, want);
                    }
                }
                pt_film_free(&film);
            }
        }
        pt_scene_destroy(s);
    }
    test_note(t, "%d comparisons, max |z| %.2f (limit %.2f, alpha %.2g each: 0.01 Sidak over %d)", comparisons, worst, zmax,
              alpha_each(), MAT_STAT_TESTS);
}

static void dielectric_slab_fresnel(test_ctx *t)
{
    /* A glass slab (a wide box, thickness 1) in front of a large emitter of radiance 1 behind the ray
       origin; the ray meets the slab at theta. Reflected light reaches the emitter, transmitted light
       escapes to a black background. With the unpolarised Fresnel reflectance F(theta) at each
       interface (equal from both sides) and incoherent multiple reflections inside the slab, the
       radiance is R = F + (1-F)^2 F / (1 - F^2) = 2F / (1 + F). Schlick's approximation would be off by
       20% at 60 degrees. ior 0 in pt_material_desc means 1.5. */
    const double angles[3] = { 0.0, 45.0, 60.0 };
    double zmax = tu_z_two_sided(alpha_each()), worst = 0;
    int ai, k;
    for (k = 0; k < 2; k++) {
        pt_scene *s = pt_scene_create();
        pt_material_desc md;
        int glass, emit, rc;
        double ior = k == 0 ? 1.5 : 1.5;
        if (!CHECK(t, s != NULL, "scene")) return;
        if (k == 0) glass = pt_scene_add_dielectric(s, 1.5f);
        else {
            memset(&md, 0, sizeof md);
            md.type = PT_MATERIAL_DIELECTRIC;
            md.ior = 0.0f; /* default: 1.5 */
            glass = pt_scene_add_material(s, &md);
        }
        emit = pt_scene_add_emitter(s, pt_v3(1, 1, 1), 0);
        rc = pt_scene_add_box(s, pt_v3(-50, -50, 0), pt_v3(50, 50, 1), glass);
        rc = rc >= 0 ? pt_scene_add_quad(s, pt_v3(-200, -200, -1), pt_v3(400, 0, 0), pt_v3(0, 400, 0), emit) : rc; /* faces +z */
        rc = rc >= 0 ? pt_scene_commit(s) : rc;
        if (!CHECK(t, rc == PT_OK, "slab scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        for (ai = 0; ai < 3; ai++) {
            double th = angles[ai] * TU_PI / 180.0, F = tu_fresnel_dielectric(cos(th), 1.0, ior), want = 2 * F / (1 + F);
            int strat;
            for (strat = 0; strat < 2; strat++) {
                pt_render_desc d = tu_base_desc(1, 1, 1, 12345);
                pt_rng rng;
                pt_path_stats ps;
                tu_acc acc;
                long i, n = 40000;
                double z, se;
                memset(&acc, 0, sizeof acc);
                memset(&ps, 0, sizeof ps);
                d.strategy = strat == 0 ? PT_STRATEGY_MIS : PT_STRATEGY_MATERIAL;
                pt_rng_seed(&rng, 2100 + ai * 2 + strat + 10 * k, 1);
                for (i = 0; i < n; i++) {
                    pt_ray r;
                    pt_color L;
                    r.origin = pt_v3(-(float)(0.5 * tan(th)), 0.0f, -0.5f);
                    r.dir = pt_v3((float)sin(th), 0.0f, (float)cos(th));
                    L = pt_trace_path(s, &d, r, &rng, &ps);
                    tu_acc_add(&acc, L.y);
                }
                se = tu_acc_se(&acc);
                z = tu_z_floor(acc.mean, want, se, TU_FLOAT_FLOOR * want);
                if (z > worst) worst = z;
                CHECK(t, z <= zmax, "ior %.1f%s at %g degrees, %s: reflectance %.5f +- %.5f, want 2F/(1+F) = %.5f (F = %.5f)",
                      ior, k ? " (default)" : "", angles[ai], strat == 0 ? "MIS" : "material", acc.mean, se, want, F);
                CHECK(t, ps.nonfinite_samples == 0, "non-finite samples");
            }
        }
        pt_scene_destroy(s);
    }
    test_note(t, "12 comparisons, max |z| %.2f (limit %.2f, alpha %.2g each: 0.01 Sidak over %d)", worst, zmax, alpha_each(),
              MAT_STAT_TESTS);
}

static void mirror_reflection(test_ctx *t)
{
    /* A perfect mirror (albedo (0.8, 0.6, 0.4)) at y = 0 reflects a ray at 45 degrees onto a small
       emitter of radiance (2, 3, 4) placed at the exact mirror image position: the path is
       deterministic and carries albedo * radiance. A ray aimed 0.2 beside it sees nothing. */
    pt_scene *s = pt_scene_create();
    int mir, emit, rc, i, bad = 0, bad_miss = 0;
    pt_render_desc d = tu_base_desc(1, 1, 1, 12345);
    pt_rng rng;
    if (!CHECK(t, s != NULL, "scene")) return;
    mir = pt_scene_add_metal(s, pt_v3(0.8f, 0.6f, 0.4f), 0.0f);
    emit = pt_scene_add_emitter(s, pt_v3(2, 3, 4), 1);
    rc = pt_scene_add_quad(s, pt_v3(-10, 0, -10), pt_v3(0, 0, 20), pt_v3(20, 0, 0), mir);
    /* ray from (-2, 2, 0) towards (0, 0, 0) reflects towards (2, 2, 0): a 0.1 x 0.1 emitter there */
    rc = rc >= 0 ? pt_scene_add_quad(s, pt_v3(2, 1.95f, -0.05f), pt_v3(0, 0.1f, 0), pt_v3(0, 0, 0.1f), emit) : rc;
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    pt_rng_seed(&rng, 2200, 1);
    for (i = 0; i < 64; i++) {
        pt_ray r;
        pt_color L;
        d.strategy = (pt_strategy)(i % 4);
        r.origin = pt_v3(-2, 2, 0);
        r.dir = pt_normalize(pt_v3(1, -1, 0));
        L = pt_trace_path(s, &d, r, &rng, NULL);
        if (fabs(L.x - 1.6) > 1e-5 || fabs(L.y - 1.8) > 1e-5 || fabs(L.z - 1.6) > 1e-5) {
            if (bad++ == 0) test_note(t, "strategy %d: got (%g, %g, %g), want (1.6, 1.8, 1.6)", i % 4, L.x, L.y, L.z);
        }
        r.dir = pt_normalize(pt_v3(1, -1, 0.2f));
        L = pt_trace_path(s, &d, r, &rng, NULL);
        if (L.x != 0 || L.y != 0 || L.z != 0) bad_miss++;
    }
    CHECK(t, bad == 0, "%d of 64 mirror paths did not carry albedo * radiance", bad);
    CHECK(t, bad_miss == 0, "%d of 64 paths beside the emitter were not black", bad_miss);
    pt_scene_destroy(s);
}

static void emission_sides(test_ctx *t)
{
    /* Emission is one-sided (the side of the geometric normal) unless two_sided_emission is set; a
       Lambertian material may emit too. Seen directly by a camera ray. */
    pt_scene *s = pt_scene_create();
    pt_material_desc md;
    int one, two, lam_emit, rc, k;
    pt_render_desc d = tu_base_desc(1, 1, 1, 12345);
    pt_rng rng;
    if (!CHECK(t, s != NULL, "scene")) return;
    one = pt_scene_add_emitter(s, pt_v3(1, 2, 3), 0);
    two = pt_scene_add_emitter(s, pt_v3(1, 2, 3), 1);
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_LAMBERTIAN;
    md.albedo = pt_v3(0, 0, 0);
    md.emission = pt_v3(0.5f, 0.25f, 0.125f);
    lam_emit = pt_scene_add_material(s, &md);
    /* three quads facing +z at z = 0, side by side */
    rc = pt_scene_add_quad(s, pt_v3(-3, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 1, 0), one);
    rc = rc >= 0 ? pt_scene_add_quad(s, pt_v3(-1, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 1, 0), two) : rc;
    rc = rc >= 0 ? pt_scene_add_quad(s, pt_v3(1, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 1, 0), lam_emit) : rc;
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    pt_rng_seed(&rng, 2300, 1);
    d.max_depth = 1;
    for (k = 0; k < 6; k++) {
        int quad = k % 3, front = k < 3;
        pt_ray r;
        pt_color L, want;
        r.origin = pt_v3(-2.5f + 2.0f * quad, 0.5f, front ? 2.0f : -2.0f);
        r.dir = pt_v3(0, 0, front ? -1.0f : 1.0f);
        L = pt_trace_path(s, &d, r, &rng, NULL);
        if (quad == 0) want = front ? pt_v3(1, 2, 3) : pt_v3(0, 0, 0);
        else if (quad == 1) want = pt_v3(1, 2, 3);
        else want = front ? pt_v3(0.5f, 0.25f, 0.125f) : pt_v3(0, 0, 0);
        CHECK(t, fabs(L.x - want.x) < 1e-6 && fabs(L.y - want.y) < 1e-6 && fabs(L.z - want.z) < 1e-6,
              "%s quad seen from the %s: (%g, %g, %g), want (%g, %g, %g)",
              quad == 0 ? "one-sided emitter" : quad == 1 ? "two-sided emitter" : "emitting Lambertian",
              front ? "front" : "back", L.x, L.y, L.z, want.x, want.y, want.z);
    }
    pt_scene_destroy(s);
}

/* A glass ball in front of a checkered wall under one light, the glass made by `how`: 0
   pt_scene_add_dielectric(s, 1.5), 1 pt_scene_add_dielectric(s, 0), 2 pt_material_desc with ior 0.
   Returns the render's code; the image in *img. */
static int glass_render(int how, pt_image *img, char *msg, size_t msg_size)
{
    pt_scene *s = pt_scene_create();
    pt_render_desc d = tu_base_desc(12, 12, 8, 77);
    pt_material_desc md;
    int glass, wall, light, rc;
    if (!s) return PT_ERROR_OUT_OF_MEMORY;
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_DIELECTRIC;
    glass = how == 0 ? pt_scene_add_dielectric(s, 1.5f) : how == 1 ? pt_scene_add_dielectric(s, 0.0f)
                                                                    : pt_scene_add_material(s, &md);
    wall = pt_scene_add_lambertian(s, pt_v3(0.7f, 0.6f, 0.5f));
    light = pt_scene_add_emitter(s, pt_v3(6, 6, 6), 0);
    rc = glass < 0 ? glass : pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, glass);
    rc = rc >= 0 ? pt_scene_add_quad(s, pt_v3(-4, -4, -3), pt_v3(8, 0, 0), pt_v3(0, 8, 0), wall) : rc;
    rc = rc >= 0 ? pt_scene_add_quad(s, pt_v3(-1, 3, -1), pt_v3(0, 0, 2), pt_v3(2, 0, 0), light) : rc; /* faces -y */
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    snprintf(msg, msg_size, "%s", pt_scene_error_message(s));
    if (rc == PT_OK) {
        d.camera.look_from = pt_v3(0, 0.5f, 5);
        d.camera.look_at = pt_v3(0, 0, 0);
        d.threads = 1;
        rc = pt_render_image(s, &d, img, NULL);
    }
    pt_scene_destroy(s);
    return rc;
}

static void dielectric_ior_zero(test_ctx *t)
{
    /* ior 0 means 1.5 (pt_material_desc's documented default) for pt_scene_add_dielectric too: all
       three ways of making the glass render the same image bit for bit. Invalid iors are refused
       by both, with a message that gives the value. */
    pt_image img[3];
    char msg[256];
    const float bad[4] = { -1.0f, 1e-4f, (float)NAN, (float)INFINITY };
    int k, rc;
    size_t i, differ = 0;
    memset(img, 0, sizeof img);
    for (k = 0; k < 3; k++) {
        rc = glass_render(k, &img[k], msg, sizeof msg);
        CHECK(t, rc == PT_OK, "%s: %d '%s'", k == 0 ? "add_dielectric(1.5)" : k == 1 ? "add_dielectric(0)" : "desc ior 0",
              rc, msg);
    }
    if (img[0].rgb && img[1].rgb && img[2].rgb) {
        for (i = 0; i < 3u * 12u * 12u; i++) differ += img[0].rgb[i] != img[1].rgb[i] || img[0].rgb[i] != img[2].rgb[i];
        CHECK(t, differ == 0, "%lu of %d values differ from ior 1.5's image", (unsigned long)differ, 3 * 12 * 12);
    }
    for (k = 0; k < 3; k++) pt_image_free(&img[k]);
    for (k = 0; k < 4; k++) {
        pt_scene *s = pt_scene_create();
        pt_material_desc md;
        int a, b;
        char ma[256];
        if (!CHECK(t, s != NULL, "scene")) return;
        memset(&md, 0, sizeof md);
        md.type = PT_MATERIAL_DIELECTRIC;
        md.ior = bad[k];
        a = pt_scene_add_dielectric(s, bad[k]);
        snprintf(ma, sizeof ma, "%s", pt_scene_error_message(s));
        b = pt_scene_add_material(s, &md);
        CHECK(t, a == PT_ERROR_INVALID_ARGUMENT && b == PT_ERROR_INVALID_ARGUMENT && strstr(ma, "ior") &&
                     strstr(pt_scene_error_message(s), "ior"),
              "ior %g: add_dielectric %d '%s', add_material %d '%s'", (double)bad[k], a, ma, b, pt_scene_error_message(s));
        pt_scene_destroy(s);
    }
}

const test_case test_materials_cases[] = {
    TEST_CASE(checker_parity),
    TEST_CASE(checker_in_render),
    TEST_CASE(delta_flags),
    TEST_CASE(furnace_spheres),
    TEST_CASE(dielectric_slab_fresnel),
    TEST_CASE(dielectric_ior_zero),
    TEST_CASE(mirror_reflection),
    TEST_CASE(emission_sides),
    TEST_END
};
