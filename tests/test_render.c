#define _POSIX_C_SOURCE 200809L
/* test_render.c - sections 6-8 of pdftrace.h: camera, integrator strategies, rendering.

   Determinism (bit-identical films across thread counts, tile sizes and host parallel-fors that run
   tiles in reverse or on their own threads), progressive rendering, cancellation, progress reports;
   convergence against analytic references: a closed furnace (radiance Le/(1 - albedo) = 1), direct
   light from a quad on a plane (Lambert's polygon formula) and from a sphere (E = pi L sin^2(a) cos),
   and the four strategies against each other on the Cornell box of Shirley's "Ray Tracing: The Rest
   of Your Life". Every render must report zero non-finite samples.

   Statistical checks use fixed seeds; each test states its comparisons and uses alpha = 0.01
   Sidak-corrected over them (comparisons with an exact reference allow a float-precision floor of
   1e-4 relative first, see tu_z_floor) (the false-failure rate of each test is at most 0.01; the file has
   RENDER_STAT_FAMILIES such tests, so at most ~5% for the file if all were independent). */
#include "test_util.h"
#include "pdftrace_scene.h"

#ifndef PDFTRACE_NO_THREADS
#include <pthread.h>
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RENDER_STAT_FAMILIES 6
#define FAMILY_ALPHA 0.01


/* The Cornell box of "Ray Tracing: The Rest of Your Life" (two rotated boxes; optionally the glass
   sphere), with its camera. */
static pt_scene *cornell(int glass, pt_render_desc *d)
{
    pt_scene *s = pt_scene_create();
    int red, white, green, light, rc;
    pt_transform a, b;
    if (!s) return NULL;
    red = pt_scene_add_lambertian(s, pt_v3(0.65f, 0.05f, 0.05f));
    white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
    green = pt_scene_add_lambertian(s, pt_v3(0.12f, 0.45f, 0.15f));
    light = pt_scene_add_emitter(s, pt_v3(15, 15, 15), 0);
    rc = pt_scene_add_quad(s, pt_v3(555, 0, 0), pt_v3(0, 555, 0), pt_v3(0, 0, 555), green);
    rc |= pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(0, 555, 0), pt_v3(0, 0, 555), red);
    rc |= pt_scene_add_quad(s, pt_v3(343, 554, 332), pt_v3(-130, 0, 0), pt_v3(0, 0, -105), light); /* faces -y */
    rc |= pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(555, 0, 0), pt_v3(0, 0, 555), white);
    rc |= pt_scene_add_quad(s, pt_v3(555, 555, 555), pt_v3(-555, 0, 0), pt_v3(0, 0, -555), white);
    rc |= pt_scene_add_quad(s, pt_v3(0, 0, 555), pt_v3(555, 0, 0), pt_v3(0, 555, 0), white);
    a = pt_transform_mul(pt_transform_translate(pt_v3(265, 0, 295)), pt_transform_rotate_y(15));
    pt_scene_set_transform(s, &a);
    rc |= pt_scene_add_box(s, pt_v3(0, 0, 0), pt_v3(165, 330, 165), white);
    if (glass) {
        pt_scene_set_transform(s, NULL);
        rc |= pt_scene_add_sphere(s, pt_v3(190, 90, 190), 90, pt_scene_add_dielectric(s, 1.5f));
    } else {
        b = pt_transform_mul(pt_transform_translate(pt_v3(130, 0, 65)), pt_transform_rotate_y(-18));
        pt_scene_set_transform(s, &b);
        rc |= pt_scene_add_box(s, pt_v3(0, 0, 0), pt_v3(165, 165, 165), white);
    }
    pt_scene_set_transform(s, NULL);
    if (rc < 0 || pt_scene_commit(s) != PT_OK) { pt_scene_destroy(s); return NULL; }
    d->camera.look_from = pt_v3(278, 278, -800);
    d->camera.look_at = pt_v3(278, 278, 0);
    d->camera.vfov_degrees = 40;
    return s;
}

/* ------------------------------------------------------------------------------------------ */
/* camera                                                                                      */

static void camera_conventions(test_ctx *t)
{
    /* Right-handed pinhole: screen right = forward x up, row 0 at the top, vertical fov, aspect from
       width/height; the thin lens focuses every lens sample of a pixel on one point of the focus
       plane. */
    pt_camera_desc cd;
    pt_camera cam;
    pt_ray r;
    double half = 30.0 * TU_PI / 180.0;
    int rc, i;
    memset(&cd, 0, sizeof cd);
    cd.look_from = pt_v3(1, 2, 3);
    cd.look_at = pt_v3(1, 2, -7);
    cd.vfov_degrees = 60;
    rc = pt_camera_init(&cam, &cd, 40, 20);
    if (!CHECK(t, rc == PT_OK, "pt_camera_init: %d", rc)) return;
    r = pt_camera_ray(&cam, 20, 10, 0.5f, 0.5f);
    CHECK(t, dlen(dsub(dv_from(r.dir), dv(0, 0, -1))) < 1e-6 && dlen(dsub(dv_from(r.origin), dv(1, 2, 3))) < 1e-6,
          "centre ray (%g %g %g) from (%g %g %g)", r.dir.x, r.dir.y, r.dir.z, r.origin.x, r.origin.y, r.origin.z);
    r = pt_camera_ray(&cam, 20, 0, 0.5f, 0.5f); /* top edge: +vfov/2 upwards */
    CHECK(t, dlen(dsub(dv_from(r.dir), dv(0, sin(half), -cos(half)))) < 1e-6, "top-centre ray (%g %g %g)", r.dir.x, r.dir.y, r.dir.z);
    r = pt_camera_ray(&cam, 40, 10, 0.5f, 0.5f); /* right edge: tan(h) = aspect tan(vfov/2), towards +x */
    {
        double h = atan(2.0 * tan(half));
        CHECK(t, dlen(dsub(dv_from(r.dir), dv(sin(h), 0, -cos(h)))) < 1e-6, "right-centre ray (%g %g %g), want (%g 0 %g)",
              r.dir.x, r.dir.y, r.dir.z, sin(h), -cos(h));
    }
    r = pt_camera_ray(&cam, 0, 20, 0.5f, 0.5f); /* bottom-left corner */
    CHECK(t, r.dir.x < 0 && r.dir.y < 0, "bottom-left ray (%g %g %g)", r.dir.x, r.dir.y, r.dir.z);
    CHECK(t, fabs(dlen(dv_from(r.dir)) - 1) < 1e-6, "camera ray not unit length");
    /* thin lens: focus distance 5 */
    cd.lens_radius = 0.5f;
    cd.focus_distance = 5.0f;
    rc = pt_camera_init(&cam, &cd, 40, 20);
    if (CHECK(t, rc == PT_OK, "thin lens init")) {
        dv3 first = dv(0, 0, 0);
        int bad = 0;
        for (i = 0; i < 16; i++) {
            float u1 = (i % 4 + 0.5f) / 4, u2 = (i / 4 + 0.5f) / 4;
            dv3 o, p;
            double tt;
            r = pt_camera_ray(&cam, 13.3f, 7.1f, u1, u2);
            o = dv_from(r.origin);
            tt = (o.z - (3.0 - 5.0)) / -r.dir.z;    /* focus plane z = 3 - 5 */
            p = dadd(o, dscale(dv_from(r.dir), tt));
            if (i == 0) first = p;
            else if (dlen(dsub(p, first)) > 1e-4) bad++;
            if (fabs(o.z - 3) > 1e-5 || dlen(dsub(o, dv(1, 2, 3))) > 0.5 + 1e-5) bad++;
        }
        CHECK(t, bad == 0, "thin lens: %d of 16 lens samples do not meet on the focus plane or leave the lens disk", bad);
    }
    cd.look_at = cd.look_from;
    CHECK(t, pt_camera_init(&cam, &cd, 40, 20) == PT_ERROR_INVALID_ARGUMENT, "look_at == look_from accepted");
    cd.look_at = pt_v3(0, 0, 0);
    CHECK(t, pt_camera_init(&cam, &cd, 0, 20) == PT_ERROR_INVALID_ARGUMENT, "width 0 accepted");
}

/* ------------------------------------------------------------------------------------------ */
/* determinism                                                                                 */

static void host_reverse(void *user, int count, pt_job_fn job, void *job_data)
{
    int i;
    (void)user;
    for (i = count - 1; i >= 0; i--) job(job_data, i);
}

#ifndef PDFTRACE_NO_THREADS
typedef struct host_pool { pthread_mutex_t mu; int next, count; pt_job_fn job; void *data; } host_pool;
/* Each of two threads takes the next index and runs tile count-1-index: all tiles, once, in reverse. */
static void *host_worker_rev(void *arg)
{
    host_pool *p = (host_pool *)arg;
    for (;;) {
        int i;
        pthread_mutex_lock(&p->mu);
        i = p->next++;
        pthread_mutex_unlock(&p->mu);
        if (i >= p->count) break;
        p->job(p->data, p->count - 1 - i);
    }
    return NULL;
}
static void host_threads(void *user, int count, pt_job_fn job, void *job_data)
{
    host_pool p;
    pthread_t th[2];
    int k, started = 0;
    (void)user;
    pthread_mutex_init(&p.mu, NULL);
    p.next = 0;
    p.count = count;
    p.job = job;
    p.data = job_data;
    for (k = 0; k < 2; k++)
        if (pthread_create(&th[k], NULL, host_worker_rev, &p) == 0) started++;
    if (started == 0) host_worker_rev(&p);
    for (k = 0; k < started; k++) pthread_join(th[k], NULL);
    pthread_mutex_destroy(&p.mu);
}
#endif

static void threads_bit_identical(test_ctx *t)
{
    pt_render_desc d = tu_base_desc(40, 28, 4, 4242);
    pt_scene *s = cornell(1, &d);
    pt_film ref, f;
    pt_render_stats st;
    int k;
    const char *names[6] = { "threads=2", "threads=3", "tile_size=7", "host parallel_for (reverse)",
                             "host parallel_for (2 threads)", "threads=0 (all cores)" };
    if (!CHECK(t, s != NULL, "Cornell scene")) return;
    d.max_depth = 8;
    d.threads = 1;
    if (!tu_render_into(t, s, &d, &ref, &st, "threads=1")) { pt_scene_destroy(s); return; }
    CHECK(t, st.samples == (uint64_t)40 * 28 * 4, "stats.samples %llu, want %d", (unsigned long long)st.samples, 40 * 28 * 4);
    for (k = 0; k < 6; k++) {
        pt_render_desc e = d;
        e.threads = k == 0 ? 2 : k == 1 ? 3 : k == 5 ? 0 : 1;
        if (k == 2) { e.tile_size = 7; e.threads = 2; }
        if (k == 3) e.parallel_for = host_reverse;
#ifndef PDFTRACE_NO_THREADS
        if (k == 4) e.parallel_for = host_threads;
#else
        if (k == 4) e.parallel_for = host_reverse; /* no threads in this build */
#endif
        if (tu_render_into(t, s, &e, &f, &st, names[k]))
            CHECK(t, tu_film_equal(&ref, &f), "%s: film differs from threads=1", names[k]);
        pt_film_free(&f);
    }
    {   /* and the seed matters */
        pt_render_desc e = d;
        e.seed = d.seed + 1;
        if (tu_render_into(t, s, &e, &f, &st, "seed + 1")) CHECK(t, !tu_film_equal(&ref, &f), "a different seed gave the same film");
        pt_film_free(&f);
    }
    pt_film_free(&ref);
    pt_scene_destroy(s);
    test_note(t, "7 renders of a 40x28 Cornell box with glass, bit-identical");
}

static void progressive_equals_single(test_ctx *t)
{
    /* Two renders of 8 spp into one film = one render of 16 spp in passes of 8, bit for bit; a
       16-spp render in passes of 5 (5+5+5+1) takes exactly 16 samples per pixel. */
    pt_render_desc d = tu_base_desc(24, 24, 8, 4242);
    pt_scene *s = cornell(0, &d);
    pt_film a, b;
    pt_render_stats st;
    int rc, i;
    if (!CHECK(t, s != NULL, "Cornell scene")) return;
    d.max_depth = 6;
    d.threads = 2;
    if (tu_render_into(t, s, &d, &a, &st, "first 8 spp")) {
        rc = pt_render(s, &d, &a, &st);
        CHECK(t, rc == PT_OK && st.nonfinite_samples == 0, "second 8 spp: %d", rc);
    }
    d.samples_per_pixel = 16;
    d.samples_per_pass = 8;
    if (tu_render_into(t, s, &d, &b, &st, "16 spp in passes of 8")) {
        CHECK(t, st.passes == 2, "16 spp in passes of 8 took %d passes", st.passes);
        CHECK(t, tu_film_equal(&a, &b), "8 + 8 spp differs from 16 spp (passes of 8)");
    }
    pt_film_free(&b);
    d.samples_per_pass = 5;
    if (tu_render_into(t, s, &d, &b, &st, "16 spp in passes of 5")) {
        int bad = 0;
        for (i = 0; i < d.width * d.height; i++) bad += b.count[i] != 16;
        CHECK(t, bad == 0, "%d pixels without exactly 16 samples (passes of 5)", bad);
        CHECK(t, st.passes == 4, "16 spp in passes of 5 took %d passes, want 4", st.passes);
        test_note(t, "passes of 5 %s passes of 8", tu_film_equal(&a, &b) ? "also bit-identical to" : "differ in rounding from");
    }
    pt_film_free(&a);
    pt_film_free(&b);
    pt_scene_destroy(s);
}

typedef struct progress_log { int calls, bad_order, cancel_at; uint64_t last_done, total; int pass_count; double last_s; volatile int *flag; int flag_at; } progress_log;
static int on_progress(void *user, const pt_progress *p)
{
    progress_log *l = (progress_log *)user;
    l->calls++;
    if (p->pass != l->calls || p->samples_done <= l->last_done || p->seconds < l->last_s || p->samples_done > p->samples_total)
        l->bad_order++;
    l->last_done = p->samples_done;
    l->last_s = p->seconds;
    l->total = p->samples_total;
    l->pass_count = p->pass_count;
    if (l->flag && p->pass == l->flag_at) *l->flag = 1;
    return l->cancel_at > 0 && p->pass >= l->cancel_at;
}

static void cancellation_and_progress(test_ctx *t)
{
    pt_render_desc d = tu_base_desc(32, 32, 12, 4242);
    pt_scene *s = cornell(0, &d);
    pt_film f;
    pt_render_stats st;
    progress_log log;
    volatile int flag = 0;
    int rc, i, bad;
    if (!CHECK(t, s != NULL, "Cornell scene")) return;
    d.max_depth = 4;
    d.samples_per_pass = 3;
    d.threads = 2;
    /* a full render: 4 passes reported in order */
    memset(&log, 0, sizeof log);
    d.progress = on_progress;
    d.progress_user = &log;
    if (tu_render_into(t, s, &d, &f, &st, "with progress")) {
        CHECK(t, log.calls == 4 && log.pass_count == 4 && log.bad_order == 0, "progress: %d calls, pass_count %d, %d out of order",
              log.calls, log.pass_count, log.bad_order);
        CHECK(t, log.last_done == (uint64_t)32 * 32 * 12 && log.total == (uint64_t)32 * 32 * 12, "samples_done %llu total %llu",
              (unsigned long long)log.last_done, (unsigned long long)log.total);
        CHECK(t, st.passes == 4, "stats.passes %d", st.passes);
    }
    pt_film_free(&f);
    /* the callback cancels after pass 1: exactly one pass in the film */
    memset(&log, 0, sizeof log);
    log.cancel_at = 1;
    pt_film_init(&f, 32, 32);
    rc = pt_render(s, &d, &f, &st);
    CHECK(t, rc == PT_ERROR_CANCELLED, "progress callback cancel: returned %d, want PT_ERROR_CANCELLED", rc);
    for (i = 0, bad = 0; i < 32 * 32; i++) bad += f.count[i] != 3;
    CHECK(t, bad == 0 && log.calls == 1, "after cancelling at pass 1: %d pixels without 3 samples, %d callbacks", bad, log.calls);
    pt_film_free(&f);
    /* *cancel set before the render */
    flag = 1;
    d.cancel = &flag;
    d.progress = NULL;
    pt_film_init(&f, 32, 32);
    rc = pt_render(s, &d, &f, &st);
    CHECK(t, rc == PT_ERROR_CANCELLED, "cancel flag set: returned %d, want PT_ERROR_CANCELLED", rc);
    for (i = 0, bad = 0; i < 32 * 32; i++) bad += f.count[i] > 12;
    CHECK(t, bad == 0, "cancelled film has pixels with more samples than asked");
    pt_film_free(&f);
    /* *cancel set during the render (from the progress callback after pass 2) */
    flag = 0;
    memset(&log, 0, sizeof log);
    log.flag = &flag;
    log.flag_at = 2;
    d.progress = on_progress;
    pt_film_init(&f, 32, 32);
    rc = pt_render(s, &d, &f, &st);
    CHECK(t, rc == PT_ERROR_CANCELLED, "cancel flag set during the render: returned %d", rc);
    for (i = 0, bad = 0; i < 32 * 32; i++) bad += f.count[i] < 6 || f.count[i] >= 12;
    CHECK(t, bad == 0, "cancel after pass 2: %d pixels outside [6, 12) samples", bad);
    pt_film_free(&f);
    pt_scene_destroy(s);
}

static void render_image_matches_film(test_ctx *t)
{
    /* pt_render_image = pt_render into a fresh film + pt_film_resolve, bit for bit */
    pt_render_desc d = tu_base_desc(20, 16, 3, 4242);
    pt_scene *s = cornell(1, &d);
    pt_film f;
    pt_image a, b;
    pt_render_stats st;
    int rc;
    if (!CHECK(t, s != NULL, "scene")) return;
    d.threads = 1;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    rc = pt_render_image(s, &d, &a, &st);
    CHECK(t, rc == PT_OK && st.nonfinite_samples == 0, "pt_render_image: %d", rc);
    if (tu_render_into(t, s, &d, &f, NULL, "pt_render")) {
        rc = pt_film_resolve(&f, &b);
        CHECK(t, rc == PT_OK && a.width == 20 && a.height == 16 && b.width == 20 && b.height == 16 &&
                     memcmp(a.rgb, b.rgb, sizeof(float) * 3 * 20 * 16) == 0,
              "pt_render_image differs from pt_render + pt_film_resolve");
    }
    pt_film_free(&f);
    pt_image_free(&a);
    pt_image_free(&b);
    pt_scene_destroy(s);
}

/* ------------------------------------------------------------------------------------------ */
/* convergence                                                                                 */

static void furnace_closed_sphere(test_ctx *t)
{
    /* Inside a closed sphere of Lambertian albedo 0.5 emitting 0.5 on both sides, the radiance is
       Le / (1 - rho) = 1 everywhere (pbrt-v4's furnace; the truncation at max_depth 50 is 2^-51). Every
       shading point lies on the (two-sided) light itself. 16 regions x 4 strategies = 64 z-tests at
       alpha 0.01 Sidak. */
    pt_scene *s = pt_scene_create();
    int rc, strat, i, over3 = 0, n = 0;
    double zlim = tu_z_two_sided(tu_sidak(FAMILY_ALPHA, 64)), worst = 0;
    const char *names[4] = { "MIS", "material", "light", "mixture" };
    if (!CHECK(t, s != NULL, "scene")) return;
    rc = tu_add_closed_furnace(s);
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (strat = 0; strat < 4; strat++) {
        pt_render_desc d = tu_base_desc(16, 16, 45, 4242); /* a non-square count on purpose */
        pt_film f;
        tu_region reg[16];
        d.camera.look_from = pt_v3(0.2f, -0.1f, 0.3f);
        d.camera.look_at = pt_v3(1, 0.5f, 0);
        d.camera.vfov_degrees = 90;
        d.strategy = (pt_strategy)strat;
        d.seed = 500 + strat;
        if (!tu_render_into(t, s, &d, &f, NULL, names[strat])) { pt_film_free(&f); continue; }
        tu_film_regions(&f, 4, 4, reg);
        {
            int fails = 0;
            double img = 0;
            for (i = 0; i < 16; i++) {
                double se = reg[i].se[1], z = tu_z_floor(reg[i].mean[1], 1.0, se, TU_FLOAT_FLOOR);
                n++;
                worst = fmax(worst, z);
                over3 += z > 3;
                fails += z > zlim;
                img += reg[i].mean[1] / 16;
            }
            CHECK(t, fails == 0, "%s: %d of 16 regions differ from 1 (z > %.2f); image mean %.4f", names[strat], fails, zlim, img);
        }
        pt_film_free(&f);
    }
    test_note(t, "%d regions, max |z| %.2f (limit %.2f: alpha 0.01 Sidak over 64), %d above 3", n, worst, zlim, over3);
    pt_scene_destroy(s);
}

static void furnace_one_bounce(test_ctx *t)
{
    /* The same furnace with max_depth 1, one path per sample from a fixed interior point in uniformly
       random directions: the camera ray sees Le = 0.5 and one scattering adds rho Le = 0.25, so every
       strategy must give 0.75. This isolates direct light at shading points on a two-sided sphere
       light (inside it, or numerically just outside its surface). 4 z-tests, alpha 0.01 Sidak. */
    pt_scene *s = pt_scene_create();
    int rc, strat;
    double zlim = tu_z_two_sided(tu_sidak(FAMILY_ALPHA, 4)), worst = 0;
    const char *names[4] = { "MIS", "material", "light", "mixture" };
    if (!CHECK(t, s != NULL, "scene")) return;
    rc = tu_add_closed_furnace(s);
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (strat = 0; strat < 4; strat++) {
        pt_render_desc d = tu_base_desc(1, 1, 1, 4242);
        pt_rng rng, dirs;
        pt_path_stats ps;
        tu_acc acc;
        long i;
        double se, z;
        memset(&acc, 0, sizeof acc);
        memset(&ps, 0, sizeof ps);
        d.max_depth = 1;
        d.strategy = (pt_strategy)strat;
        pt_rng_seed(&rng, 5100 + strat, 1);
        pt_rng_seed(&dirs, 5200 + strat, 1);
        for (i = 0; i < 40000; i++) {
            pt_ray r;
            pt_color L;
            r.origin = pt_v3(0.2f, -0.1f, 0.3f);
            r.dir = pt_normalize(dv_to(tu_rand_dir(&dirs)));
            L = pt_trace_path(s, &d, r, &rng, &ps);
            tu_acc_add(&acc, L.y);
        }
        se = tu_acc_se(&acc);
        z = tu_z_floor(acc.mean, 0.75, se, TU_FLOAT_FLOOR * 0.75);
        worst = fmax(worst, z);
        CHECK(t, z <= zlim && ps.nonfinite_samples == 0, "%s: %.5f +- %.5f, want 0.75 (z = %.2f > %.2f)", names[strat], acc.mean,
              se, z, zlim);
    }
    test_note(t, "max |z| %.2f (limit %.2f: alpha 0.01 Sidak over 4)", worst, zlim);
    pt_scene_destroy(s);
}

static void strategies_agree_cornell(test_ctx *t)
{
    /* The four strategies estimate the same image. Cornell box (two boxes), 48x48, max_depth 8. Per
       region (4x4) and channel, z = (m_s - m_mis) / sqrt(se_s^2 + se_mis^2) with standard errors from
       the films' per-pixel variances; 3 strategies x 16 regions x 3 channels = 144 comparisons at
       alpha 0.01 Sidak. Also reports how many |z| exceed 3. 200 spp. */
    pt_render_desc d = tu_base_desc(48, 48, 200, 4242);
    pt_scene *s = cornell(0, &d);
    pt_film f[4];
    tu_region reg[4][16];
    int strat, i, c, over3 = 0, ok = 1;
    double zlim = tu_z_two_sided(tu_sidak(FAMILY_ALPHA, 144)), worst = 0;
    const char *names[4] = { "MIS", "material", "light", "mixture" };
    if (!CHECK(t, s != NULL, "Cornell scene")) return;
    d.max_depth = 8;
    for (strat = 0; strat < 4; strat++) {
        d.strategy = (pt_strategy)strat;
        d.seed = 900 + strat;
        ok &= tu_render_into(t, s, &d, &f[strat], NULL, names[strat]);
        if (ok) tu_film_regions(&f[strat], 4, 4, reg[strat]);
    }
    if (ok) {
        for (strat = 1; strat < 4; strat++) {
            for (i = 0; i < 16; i++) {
                for (c = 0; c < 3; c++) {
                    double se = sqrt(reg[strat][i].se[c] * reg[strat][i].se[c] + reg[0][i].se[c] * reg[0][i].se[c]);
                    double z = fabs(reg[strat][i].mean[c] - reg[0][i].mean[c]) / se;
                    worst = fmax(worst, z);
                    over3 += z > 3;
                    CHECK(t, z <= zlim, "%s vs MIS, region %d channel %d: %.5f +- %.5f vs %.5f +- %.5f (z = %.2f > %.2f)",
                          names[strat], i, c, reg[strat][i].mean[c], reg[strat][i].se[c], reg[0][i].mean[c], reg[0][i].se[c],
                          z, zlim);
                }
            }
        }
    }
    for (strat = 0; strat < 4; strat++) pt_film_free(&f[strat]);
    test_note(t, "144 comparisons, max |z| %.2f (limit %.2f: alpha 0.01 Sidak over 144), %d above 3", worst, zlim, over3);
    pt_scene_destroy(s);
}

/* Guide for the direct-light test: aims at the quad light from the shading point. */
typedef struct guide_ctx { pt_vec3 q, u, v; long calls; } guide_ctx;
static int quad_guide(void *user, const pt_shading_point *sp, pt_pdf *out)
{
    guide_ctx *g = (guide_ctx *)user;
    g->calls++;
    *out = pt_pdf_quad_light(sp->position, g->q, g->u, g->v, 0);
    return 1;
}

static void direct_light_lambert(test_ctx *t)
{
    /* A Lambertian floor (albedo 0.5) under a 1x1 quad light of radiance 4 at height 2, max_depth 1,
       camera between them looking down. Each pixel's reference is rho E / pi with E from Lambert's
       polygon formula, averaged over a 6x6 grid of pt_camera_ray positions in the pixel (hit with the
       plane in double precision). Four strategies, the mixture with light_weight 0.2, and MIS with a
       user guide PDF aimed at the light: 6 x 16 regions = 96 z-tests at alpha 0.01 Sidak. */
    pt_scene *s = pt_scene_create();
    pt_vec3 q = pt_v3(-0.2f, 2.0f, -0.3f), u = pt_v3(1, 0, 0), v = pt_v3(0, 0, 1); /* u x v = -y */
    dv3 verts[4];
    pt_render_desc d = tu_base_desc(32, 32, 128, 4242);
    pt_camera cam;
    double *ref = NULL, zlim = tu_z_two_sided(tu_sidak(FAMILY_ALPHA, 96)), worst = 0;
    int floor_m, light_m, rc, x, y, k, strat, over3 = 0;
    const double rho = 0.5, L = 4.0;
    const char *names[6] = { "MIS", "material", "light", "mixture", "MIS + guide", "mixture, light_weight 0.2" };
    guide_ctx g;
    if (!CHECK(t, s != NULL, "scene")) return;
    floor_m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    light_m = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0);
    rc = pt_scene_add_quad(s, pt_v3(-20, 0, -20), pt_v3(0, 0, 40), pt_v3(40, 0, 0), floor_m);
    rc = rc >= 0 ? pt_scene_add_quad(s, q, u, v, light_m) : rc;
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    verts[0] = dv_from(q);
    verts[1] = dadd(verts[0], dv_from(u));
    verts[2] = dadd(verts[1], dv_from(v));
    verts[3] = dadd(verts[0], dv_from(v));
    d.camera.look_from = pt_v3(0, 1, 0);
    d.camera.look_at = pt_v3(0, 0, 0);
    d.camera.up = pt_v3(0, 0, -1);
    d.camera.vfov_degrees = 70;
    d.max_depth = 1;
    pt_camera_init(&cam, &d.camera, d.width, d.height);
    ref = (double *)malloc(sizeof(double) * 32 * 32);
    if (!CHECK(t, ref != NULL, "out of memory")) { pt_scene_destroy(s); return; }
    for (y = 0; y < 32; y++) {
        for (x = 0; x < 32; x++) {
            double sum = 0;
            for (k = 0; k < 36; k++) {
                pt_ray r = pt_camera_ray(&cam, x + (k % 6 + 0.5f) / 6, y + (k / 6 + 0.5f) / 6, 0.5f, 0.5f);
                double tt = -(double)r.origin.y / r.dir.y;
                dv3 p = dadd(dv_from(r.origin), dscale(dv_from(r.dir), tt));
                sum += rho / TU_PI * L * tu_lambert_polygon(p, dv(0, 1, 0), verts, 4);
            }
            ref[y * 32 + x] = sum / 36;
        }
    }
    memset(&g, 0, sizeof g);
    g.q = q; g.u = u; g.v = v;
    for (strat = 0; strat < 6; strat++) {
        pt_film f;
        tu_region reg[16];
        int i;
        d.strategy = (pt_strategy)(strat == 4 ? 0 : strat == 5 ? 3 : strat);
        d.seed = 600 + strat;
        d.guide = NULL;
        d.light_weight = strat == 5 ? 0.2f : 0.0f;
        if (strat == 4) { d.guide = quad_guide; d.guide_user = &g; d.guide_weight = 0.5f; }
        if (!tu_render_into(t, s, &d, &f, NULL, names[strat])) { pt_film_free(&f); continue; }
        tu_film_regions(&f, 4, 4, reg);
        for (i = 0; i < 16; i++) {
            double want = 0, z;
            int n = 0;
            for (y = (i / 4) * 8; y < (i / 4) * 8 + 8; y++)
                for (x = (i % 4) * 8; x < (i % 4) * 8 + 8; x++) { want += ref[y * 32 + x]; n++; }
            want /= n;
            z = tu_z_floor(reg[i].mean[1], want, reg[i].se[1], TU_FLOAT_FLOOR * want);
            worst = fmax(worst, z);
            over3 += z > 3;
            CHECK(t, z <= zlim, "%s, region %d: %.6f +- %.6f, Lambert's formula %.6f (z = %.2f > %.2f)", names[strat], i,
                  reg[i].mean[1], reg[i].se[1], want, z, zlim);
        }
        pt_film_free(&f);
    }
    CHECK(t, g.calls > 0, "the guide was never called");
    test_note(t, "96 comparisons, max |z| %.2f (limit %.2f: alpha 0.01 Sidak over 96), %d above 3", worst, zlim, over3);
    free(ref);
    pt_scene_destroy(s);
}

static void direct_sphere_light_formula(test_ctx *t)
{
    /* A spherical light of radiance L and angular radius a seen at angle theta from the normal of a
       Lambertian floor (rho = 0.5), theta + a < pi/2: outgoing radiance rho L sin^2(a) cos(theta)
       (docs/accuracy.md). One path per sample with pt_trace_path, max_depth 1. sin^2(a) = 0.05
       with every strategy; sin^2(a) = 1e-6 and 1e-8 (radiance scaled to keep the result ~0.05) with
       the strategies that sample lights. Comparisons: 3 points x (4 + 3 + 3) = 30, alpha 0.01 Sidak. */
    const double s2[3] = { 0.05, 1e-6, 1e-8 };
    const dv3 pts[3] = { { 0, 0, 0 }, { 0.7, 0, -0.4 }, { -1.0, 0, 0.9 } };
    const dv3 c = { 0.3, 2.0, 0.1 };
    double zlim = tu_z_two_sided(tu_sidak(FAMILY_ALPHA, 30)), worst = 0;
    int si, pi, strat;
    for (si = 0; si < 3; si++) {
        pt_scene *s = pt_scene_create();
        int fm, lm, rc;
        double L = 1.0 / s2[si];
        if (!CHECK(t, s != NULL, "scene")) return;
        fm = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
        lm = pt_scene_add_emitter(s, pt_v3((float)L, (float)L, (float)L), 0);
        rc = pt_scene_add_quad(s, pt_v3(-20, 0, -20), pt_v3(0, 0, 40), pt_v3(40, 0, 0), fm);
        /* the radius gives sin^2 = s2 at the first point; the other points' sin^2 follow from their
           distances (one light per scene) */
        rc = rc >= 0 ? pt_scene_add_sphere(s, dv_to(c), (float)sqrt(s2[si] * ddot(dsub(c, pts[0]), dsub(c, pts[0]))), lm) : rc;
        rc = rc >= 0 ? pt_scene_commit(s) : rc;
        if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        for (pi = 0; pi < 3; pi++) {
            double R = (float)sqrt(s2[si] * ddot(dsub(c, pts[0]), dsub(c, pts[0])));
            dv3 l = dsub(c, pts[pi]);
            double d2 = ddot(l, l), sin2 = R * R / d2, cos_t = l.y / sqrt(d2);
            double want = 0.5 * (double)(float)L * sin2 * cos_t;
            for (strat = 0; strat < 4; strat++) {
                pt_render_desc d = tu_base_desc(1, 1, 1, 4242);
                pt_rng rng;
                pt_path_stats ps;
                tu_acc acc;
                long i;
                double z;
                if (si > 0 && strat == PT_STRATEGY_MATERIAL) continue; /* the material PDF cannot find a tiny light */
                memset(&acc, 0, sizeof acc);
                memset(&ps, 0, sizeof ps);
                d.max_depth = 1;
                d.strategy = (pt_strategy)strat;
                pt_rng_seed(&rng, 7000 + si * 100 + pi * 10 + strat, 1);
                for (i = 0; i < 20000; i++) {
                    pt_ray r;
                    pt_color col;
                    r.origin = dv_to(dadd(pts[pi], dv(0.05, 0.2, -0.03)));
                    r.dir = dv_to(dnorm(dsub(pts[pi], dadd(pts[pi], dv(0.05, 0.2, -0.03)))));
                    col = pt_trace_path(s, &d, r, &rng, &ps);
                    tu_acc_add(&acc, col.y);
                }
                z = tu_z_floor(acc.mean, want, tu_acc_se(&acc), TU_FLOAT_FLOOR * want);
                worst = fmax(worst, z);
                CHECK(t, z <= zlim && ps.nonfinite_samples == 0,
                      "sin^2 %.0e, point %d, strategy %d: %.6f +- %.6f, want rho L sin^2 cos = %.6f (z = %.2f), %llu non-finite",
                      s2[si], pi, strat, acc.mean, tu_acc_se(&acc), want, z, (unsigned long long)ps.nonfinite_samples);
            }
        }
        pt_scene_destroy(s);
    }
    test_note(t, "max |z| %.2f (limit %.2f: alpha 0.01 Sidak over 30)", worst, zlim);
}

static void no_nonfinite_anywhere(test_ctx *t)
{
    /* Everything at once -- glass, mirror, fuzzy metals (0.3 and 1), a checker texture, a two-sided
       sphere light, a tiny sphere light of huge radiance, a triangle light, a light behind a wall --
       with all strategies and a guide: no non-finite sample, no negative or NaN pixel. */
    pt_render_desc d = tu_base_desc(32, 32, 4, 4242);
    pt_scene *s = pt_scene_create();
    int m_l, m_glass, m_mirror, m_fuzz, m_fuzz1, m_tex, m_emit2, m_emit, m_tiny, tex, rc = 0, strat;
    pt_material_desc md;
    guide_ctx g;
    if (!CHECK(t, s != NULL, "scene")) return;
    m_l = pt_scene_add_lambertian(s, pt_v3(0.7f, 0.7f, 0.7f));
    m_glass = pt_scene_add_dielectric(s, 1.5f);
    m_mirror = pt_scene_add_metal(s, pt_v3(0.9f, 0.9f, 0.9f), 0.0f);
    m_fuzz = pt_scene_add_metal(s, pt_v3(0.9f, 0.6f, 0.3f), 0.3f);
    m_fuzz1 = pt_scene_add_metal(s, pt_v3(0.9f, 0.9f, 0.9f), 1.0f);
    tex = pt_scene_add_checker(s, pt_v3(0.1f, 0.1f, 0.1f), pt_v3(0.8f, 0.8f, 0.8f), 0.5f);
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_LAMBERTIAN;
    md.albedo_texture = tex;
    m_tex = pt_scene_add_material(s, &md);
    m_emit2 = pt_scene_add_emitter(s, pt_v3(3, 3, 3), 1);
    m_emit = pt_scene_add_emitter(s, pt_v3(5, 4, 3), 0);
    m_tiny = pt_scene_add_emitter(s, pt_v3(1e6f, 1e6f, 1e6f), 0);
    rc |= pt_scene_add_quad(s, pt_v3(-10, 0, -10), pt_v3(0, 0, 20), pt_v3(20, 0, 0), m_tex);
    rc |= pt_scene_add_sphere(s, pt_v3(-1.5f, 1, 0), 1, m_glass);
    rc |= pt_scene_add_sphere(s, pt_v3(0.8f, 0.6f, -0.5f), 0.6f, m_mirror);
    rc |= pt_scene_add_sphere(s, pt_v3(1.8f, 0.5f, 1), 0.5f, m_fuzz);
    rc |= pt_scene_add_sphere(s, pt_v3(-0.2f, 0.3f, 1.5f), 0.3f, m_fuzz1);
    rc |= pt_scene_add_sphere(s, pt_v3(0, 3, 0), 0.5f, m_emit2);
    rc |= pt_scene_add_sphere(s, pt_v3(2, 2, -2), 1e-3f, m_tiny);
    rc |= pt_scene_add_triangle(s, pt_v3(-3, 2.5f, -3), pt_v3(-1, 2.5f, -3), pt_v3(-2, 2.5f, -1), m_emit);
    rc |= pt_scene_add_quad(s, pt_v3(-5, 0, 4), pt_v3(10, 0, 0), pt_v3(0, 5, 0), m_l);
    rc |= pt_scene_add_quad(s, pt_v3(-1, 1, 5), pt_v3(2, 0, 0), pt_v3(0, 2, 0), m_emit); /* behind the wall */
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    d.camera.look_from = pt_v3(0, 1.5f, -5);
    d.camera.look_at = pt_v3(0, 1, 0);
    d.camera.vfov_degrees = 60;
    d.max_depth = 12;
    memset(&g, 0, sizeof g);
    g.q = pt_v3(-3, 2.5f, -3); g.u = pt_v3(2, 0, 0); g.v = pt_v3(0, 0, 2);
    for (strat = 0; strat < 5; strat++) {
        pt_film f;
        pt_image img;
        int bad = 0, k;
        d.strategy = (pt_strategy)(strat % 4);
        if (strat == 4) { d.guide = quad_guide; d.guide_user = &g; }
        memset(&img, 0, sizeof img);
        if (tu_render_into(t, s, &d, &f, NULL, "all-features scene") && pt_film_resolve(&f, &img) == PT_OK) {
            for (k = 0; k < 3 * 32 * 32; k++) bad += !(img.rgb[k] >= 0.0f) || !isfinite(img.rgb[k]);
            CHECK(t, bad == 0, "strategy %d: %d negative or non-finite pixel values", strat, bad);
        }
        pt_image_free(&img);
        pt_film_free(&f);
    }
    pt_scene_destroy(s);
}

static void render_desc_validation(test_ctx *t)
{
    /* Settings outside their documented ranges are rejected; pt_trace_path is a pure function of
       its rng state. */
    pt_render_desc d = tu_base_desc(8, 8, 1, 4242);
    pt_scene *s = cornell(0, &d);
    pt_film f;
    int rc;
    if (!CHECK(t, s != NULL, "scene")) return;
    if (!CHECK(t, pt_film_init(&f, 8, 8) == PT_OK, "film")) { pt_scene_destroy(s); return; }
    d.light_weight = 1.5f;
    rc = pt_render(s, &d, &f, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "light_weight 1.5: %d", rc);
    d.light_weight = 0;
    d.strategy = (pt_strategy)7;
    rc = pt_render(s, &d, &f, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "strategy 7: %d", rc);
    d.strategy = PT_STRATEGY_MIS;
    d.max_splits = 65537;
    rc = pt_render(s, &d, &f, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "max_splits 65537 (at most 65536): %d", rc);
    d.max_splits = 0;
    d.indirect_paths = 9;
    rc = pt_render(s, &d, &f, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "indirect_paths 9 (at most 8): %d", rc);
    d.indirect_paths = -1;
    rc = pt_render(s, &d, &f, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "indirect_paths -1: %d", rc);
    d.indirect_paths = 0;
    d.background = pt_v3(NAN, 0, 0);
    rc = pt_render(s, &d, &f, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "NaN background: %d", rc);
    d.background = pt_v3(0, 0, 0);
    d.guide = quad_guide;
    d.guide_weight = 1.0f;
    rc = pt_render(s, &d, &f, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "guide_weight 1 (must be < 1): %d", rc);
    d.guide = NULL;
    d.guide_weight = 0;
    rc = pt_render(s, &d, NULL, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "NULL film: %d", rc);
    rc = pt_render(NULL, &d, &f, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "NULL scene: %d", rc);
    {
        pt_film g;
        if (pt_film_init(&g, 9, 8) == PT_OK) {
            rc = pt_render(s, &d, &g, NULL);
            CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "film of another size than the desc: %d", rc);
            pt_film_free(&g);
        }
    }
    rc = pt_render(s, &d, &f, NULL);
    CHECK(t, rc == PT_OK, "valid settings after the invalid ones: %d", rc);
    {
        pt_rng a, b;
        pt_ray r;
        pt_color x, y;
        int i, same = 1;
        pt_rng_seed(&a, 77, 3);
        r.origin = pt_v3(278, 278, -800);
        r.dir = pt_normalize(pt_v3(0.05f, -0.1f, 1));
        for (i = 0; i < 50; i++) {
            b = a;
            x = pt_trace_path(s, &d, r, &a, NULL);
            y = pt_trace_path(s, &d, r, &b, NULL);
            same &= x.x == y.x && x.y == y.y && x.z == y.z && a.state == b.state;
        }
        CHECK(t, same, "pt_trace_path is not a pure function of its rng state");
    }
    pt_film_free(&f);
    pt_scene_destroy(s);
}

/* Sets field k of the 25 render_errors_name_the_field cases to an invalid value; returns the
   message's expected start ("pt_render_desc.<field> = <value>"). */
static const char *break_field(pt_render_desc *d, int k)
{
    switch (k) {
    case 0: d->width = 0; return "pt_render_desc.width = 0:";
    case 1: d->height = -3; return "pt_render_desc.height = -3:";
    case 2: d->samples_per_pixel = -1; return "pt_render_desc.samples_per_pixel = -1:";
    case 3: d->samples_per_pass = -2; return "pt_render_desc.samples_per_pass = -2:";
    case 4: d->threads = -1; return "pt_render_desc.threads = -1:";
    case 5: d->tile_size = -4; return "pt_render_desc.tile_size = -4:";
    case 6: d->strategy = (pt_strategy)7; return "pt_render_desc.strategy = 7:";
    case 7: d->light_weight = 1.5f; return "pt_render_desc.light_weight = 1.5:";
    case 8: d->max_depth = -1; return "pt_render_desc.max_depth = -1:";
    case 9: d->max_splits = 65537; return "pt_render_desc.max_splits = 65537:";
    case 10: d->indirect_paths = 9; return "pt_render_desc.indirect_paths = 9:";
    case 11: d->background = pt_v3(0, -1, 0); return "pt_render_desc.background = (0, -1, 0):";
    case 12: d->guide = quad_guide; d->guide_weight = 1.0f; return "pt_render_desc.guide_weight = 1:";
    case 13: d->disable_skips = 1u << 1; return "pt_render_desc.disable_skips = 0x2:";
    case 14: d->sampler = (pt_sampler)2; return "pt_render_desc.sampler = 2:";
    case 15: d->adaptive_threshold = -0.5f; return "pt_render_desc.adaptive_threshold = -0.5:";
    case 16: d->adaptive_min_spp = 1; return "pt_render_desc.adaptive_min_spp = 1:";
    case 17: d->adaptive_check_passes = -1; return "pt_render_desc.adaptive_check_passes = -1:";
    case 18: d->adaptive_neighbours_only = 2; return "pt_render_desc.adaptive_neighbours_only = 2:";
    case 19: d->camera.vfov_degrees = 180; return "pt_render_desc.camera.vfov_degrees = 180:";
    case 20: d->camera.lens_radius = -1; return "pt_render_desc.camera.lens_radius = -1:";
    case 21: d->camera.focus_distance = -2; return "pt_render_desc.camera.focus_distance = -2:";
    case 22: d->camera.look_from = pt_v3(INFINITY, 0, 0); return "pt_render_desc.camera.look_from = (inf, 0, 0):";
    case 23: d->camera.look_at = d->camera.look_from; return "pt_render_desc.camera.look_at = (278, 278, -800):";
    default: d->camera.up = pt_v3(0, 0, 2); return "pt_render_desc.camera.up = (0, 0, 2):"; /* along the view */
    }
}

static int count_of(const char *text, const char *word)
{
    int n = 0;
    const char *p = text;
    while ((p = strstr(p, word)) != NULL) { n++; p += strlen(word); }
    return n;
}

static void render_errors_name_the_field(test_ctx *t)
{
    /* Every invalid pt_render_desc setting is refused by pt_render and by pt_render_image with a
       message in pt_render_stats.error that names that one field and its value; other misuse (NULL
       arguments, an uncommitted scene, a film of another size, cancellation) is described too, and
       a call that succeeds leaves "" there. */
    pt_render_desc d = tu_base_desc(8, 8, 1, 4242);
    pt_scene *s = cornell(0, &d), *open_scene = pt_scene_create();
    pt_film f, g;
    pt_image img;
    pt_render_stats st;
    volatile int stop = 1;
    int k, rc, fn;
    if (!CHECK(t, s != NULL && open_scene != NULL, "scenes")) { pt_scene_destroy(s); pt_scene_destroy(open_scene); return; }
    if (!CHECK(t, pt_film_init(&f, 8, 8) == PT_OK, "film")) { pt_scene_destroy(s); pt_scene_destroy(open_scene); return; }
    memset(&img, 0, sizeof img);
    for (k = 0; k < 25; k++)
        for (fn = 0; fn < 2; fn++) {
            pt_render_desc e = d;
            const char *want = break_field(&e, k);
            memset(st.error, 'x', sizeof st.error - 1);
            st.error[sizeof st.error - 1] = '\0';
            rc = fn == 0 ? pt_render(s, &e, &f, &st) : pt_render_image(s, &e, &img, &st);
            CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "%s: %s returned %d", want, fn ? "pt_render_image" : "pt_render", rc);
            CHECK(t, strncmp(st.error, want, strlen(want)) == 0 && count_of(st.error, "pt_render_desc.") == 1,
                  "%s: message '%.120s', want '%s ...' naming that field alone", fn ? "pt_render_image" : "pt_render", st.error,
                  want);
            pt_image_free(&img);
        }
    for (k = 0; k < 64; k++) CHECK(t, f.count[k] == 0, "a refused render took samples");
    rc = pt_render(s, &d, NULL, &st);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "film is NULL"), "NULL film: %d '%s'", rc, st.error);
    rc = pt_render(NULL, &d, &f, &st);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "scene is NULL"), "NULL scene: %d '%s'", rc, st.error);
    rc = pt_render_image(s, NULL, &img, &st);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "desc is NULL"), "NULL desc: %d '%s'", rc, st.error);
    rc = pt_render_image(s, &d, NULL, &st);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "image is NULL"), "NULL image: %d '%s'", rc, st.error);
    rc = pt_render_image(open_scene, &d, &img, &st);
    CHECK(t, rc == PT_ERROR_INVALID_STATE && strstr(st.error, "not committed"), "uncommitted scene: %d '%s'", rc, st.error);
    if (pt_film_init(&g, 9, 8) == PT_OK) {
        rc = pt_render(s, &d, &g, &st);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "pt_render_desc.width x height = 8 x 8: the film is 9 x 8"),
              "film of 9 x 8: %d '%s'", rc, st.error);
        pt_film_free(&g);
    }
    {
        pt_render_desc e = d;
        e.cancel = &stop;
        rc = pt_render(s, &e, &f, &st);
        CHECK(t, rc == PT_ERROR_CANCELLED && strstr(st.error, "cancelled"), "cancelled: %d '%s'", rc, st.error);
    }
    rc = pt_render(s, &d, &f, &st);
    CHECK(t, rc == PT_OK && st.error[0] == '\0', "a valid render after the failures: %d, message '%s'", rc, st.error);
    rc = pt_render_image(s, &d, &img, &st);
    CHECK(t, rc == PT_OK && st.error[0] == '\0', "a valid pt_render_image: %d, message '%s'", rc, st.error);
    pt_image_free(&img);
    CHECK(t, pt_scene_error_message(s)[0] == '\0', "renders wrote into the scene's message: '%s'", pt_scene_error_message(s));
    pt_film_free(&f);
    pt_scene_destroy(s);
    pt_scene_destroy(open_scene);
    test_note(t, "25 fields x 2 functions");
}

/* One of the threads of concurrent_renders: `rounds` times a render that fails in its own way (a
   bad field, or cancelled), then a valid render of the shared scene into its own film. */
typedef struct conc_job {
    const pt_scene *s;
    pt_render_desc d;
    int fail_kind;      /* 0: width 0; 1: max_depth -1; 2: cancelled before it starts; 3: width x height too many */
    int rounds;
    pt_film film;       /* the last valid render */
    int render_rc;      /* the first valid render's failure, else PT_OK */
    int wrong;          /* failing renders whose code or message was not this thread's */
    char seen[300];     /* the first wrong message */
} conc_job;

static void *conc_run(void *arg)
{
    static const char *const want[4] = { "pt_render_desc.width = 0:", "pt_render_desc.max_depth = -1:", "cancelled",
                                         "pt_render_desc.width x height = 65536 x 65536: too many pixels" };
    static const int want_rc[4] = { PT_ERROR_INVALID_ARGUMENT, PT_ERROR_INVALID_ARGUMENT, PT_ERROR_CANCELLED,
                                    PT_ERROR_INVALID_ARGUMENT };
    conc_job *j = (conc_job *)arg;
    volatile int stop = 1;
    int r, rc;
    j->render_rc = PT_OK;
    for (r = 0; r < j->rounds; r++) {
        pt_render_desc e = j->d;
        pt_render_stats st;
        pt_image img;
        memset(&img, 0, sizeof img);
        if (j->fail_kind == 0) e.width = 0;
        else if (j->fail_kind == 1) e.max_depth = -1;
        else if (j->fail_kind == 2) e.cancel = &stop;
        else e.width = e.height = 65536; /* width x height overflows what a film can index */
        rc = pt_render_image(j->s, &e, &img, &st);
        pt_image_free(&img);
        if (rc != want_rc[j->fail_kind] || !strstr(st.error, want[j->fail_kind])) {
            if (!j->wrong++) snprintf(j->seen, sizeof j->seen, "%d '%s'", rc, st.error);
        }
        pt_film_free(&j->film);
        rc = pt_film_init(&j->film, j->d.width, j->d.height);
        if (rc == PT_OK) rc = pt_render(j->s, &j->d, &j->film, &st);
        if (rc != PT_OK && j->render_rc == PT_OK) j->render_rc = rc;
    }
    return NULL;
}

static void concurrent_renders(test_ctx *t)
{
    /* A committed scene rendered from four threads at once (each also with its own render threads
       or none): every film equals the same desc rendered alone, bit for bit, and each thread's failed
       renders are described in its own pt_render_stats, never in another's. Run under
       ThreadSanitizer by make tsan-test. */
    pt_render_desc d = tu_base_desc(32, 24, 8, 4242);
    pt_scene *s = cornell(1, &d);
    conc_job job[4];
    pt_film ref[4];
    int k, started[4] = { 0, 0, 0, 0 };
#ifndef PDFTRACE_NO_THREADS
    pthread_t th[4];
#endif
    if (!CHECK(t, s != NULL, "Cornell scene")) return;
    d.max_depth = 8;
    memset(job, 0, sizeof job);
    memset(ref, 0, sizeof ref);
    for (k = 0; k < 4; k++) {
        job[k].s = s;
        job[k].d = d;
        job[k].d.seed = d.seed + (uint64_t)k;
        job[k].d.threads = k == 1 ? 2 : 1;
        job[k].d.strategy = k == 2 ? PT_STRATEGY_MIXTURE : PT_STRATEGY_MIS;
        job[k].d.sampler = k == 1 ? PT_SAMPLER_SOBOL : PT_SAMPLER_INDEPENDENT;
        job[k].fail_kind = k;
        job[k].rounds = 4;
        if (!tu_render_into(t, s, &job[k].d, &ref[k], NULL, "alone")) goto done;
    }
#ifndef PDFTRACE_NO_THREADS
    for (k = 0; k < 4; k++) started[k] = pthread_create(&th[k], NULL, conc_run, &job[k]) == 0;
    for (k = 0; k < 4; k++)
        if (started[k]) pthread_join(th[k], NULL);
#endif
    for (k = 0; k < 4; k++)
        if (!started[k]) conc_run(&job[k]); /* no threads (in this build): one after the other */
    for (k = 0; k < 4; k++) {
        CHECK(t, job[k].render_rc == PT_OK, "thread %d: a valid render failed: %d", k, job[k].render_rc);
        CHECK(t, job[k].render_rc != PT_OK || tu_film_equal(&ref[k], &job[k].film),
              "thread %d: its film differs from the same desc rendered alone", k);
        CHECK(t, job[k].wrong == 0, "thread %d: %d of %d failed renders got the wrong code or message, first %s", k,
              job[k].wrong, job[k].rounds, job[k].seen);
    }
    CHECK(t, pt_scene_error_message(s)[0] == '\0', "the renders wrote into the scene's message: '%s'",
          pt_scene_error_message(s));
#ifndef PDFTRACE_NO_THREADS
    test_note(t, "4 threads x 4 rounds (a failing and a valid render each), %d started", started[0] + started[1] + started[2] + started[3]);
#else
    test_note(t, "no threads in this build: the four jobs ran one after the other");
#endif
done:
    for (k = 0; k < 4; k++) {
        pt_film_free(&ref[k]);
        pt_film_free(&job[k].film);
    }
    pt_scene_destroy(s);
}

static void render_counts_no_overflow(test_ctx *t)
{
    /* Schedules near INT_MAX: tile_size = INT_MAX (tiles_x = (w + tile - 1) / tile overflowed) and
       samples_per_pixel = INT_MAX with 2 or INT_MAX per pass (passes = (spp + per_pass - 1) /
       per_pass overflowed) returned PT_OK with zero samples and a black image. They must render
       the samples asked for (or be cancelled), and a film whose 32-bit counts the render would wrap
       must be refused naming samples_per_pixel. */
    pt_render_desc d = tu_base_desc(8, 6, 2, 99);
    pt_scene *s = cornell(0, &d);
    pt_film ref, f;
    pt_render_stats st;
    progress_log log;
    volatile int stop = 1;
    int rc;
    memset(&ref, 0, sizeof ref);
    memset(&f, 0, sizeof f);
    if (!CHECK(t, s != NULL, "Cornell scene")) return;
    if (!tu_render_into(t, s, &d, &ref, NULL, "tile_size 0")) goto done;
    {
        pt_render_desc e = d;
        e.tile_size = 2147483647;
        e.threads = 2;
        rc = pt_film_init(&f, e.width, e.height);
        if (rc == PT_OK) rc = pt_render(s, &e, &f, &st);
        CHECK(t, rc == PT_OK && st.samples == 96u, "tile_size = INT_MAX: rc %d, %llu samples (want 96) '%s'", rc,
              (unsigned long long)st.samples, st.error);
        CHECK(t, rc != PT_OK || tu_film_equal(&ref, &f), "tile_size = INT_MAX: the film differs from tile_size 0");
        pt_film_free(&f);
    }
    {
        pt_render_desc e = d;
        memset(&log, 0, sizeof log);
        e.samples_per_pixel = 2147483647;
        e.samples_per_pass = 2;
        e.progress = on_progress;
        e.progress_user = &log;
        log.cancel_at = 1;
        rc = pt_film_init(&f, e.width, e.height);
        if (rc == PT_OK) rc = pt_render(s, &e, &f, &st);
        CHECK(t, rc == PT_ERROR_CANCELLED && st.samples == 96u && log.calls == 1,
              "spp = INT_MAX, 2 per pass, cancelled after pass 1: rc %d, %llu samples (want 96), %d progress calls", rc,
              (unsigned long long)st.samples, log.calls);
        CHECK(t, log.pass_count == 1073741824 && log.total == 48u * 2147483647ull,
              "spp = INT_MAX, 2 per pass: progress says %d passes (want 2^30) and %llu samples in all", log.pass_count,
              (unsigned long long)log.total);
        pt_film_free(&f);
    }
    {
        pt_render_desc e = d;
        e.samples_per_pixel = e.samples_per_pass = 2147483647;
        e.cancel = &stop; /* cancelled before the one pass of INT_MAX samples starts */
        rc = pt_film_init(&f, e.width, e.height);
        if (rc == PT_OK) rc = pt_render(s, &e, &f, &st);
        CHECK(t, rc == PT_ERROR_CANCELLED && st.samples == 0u,
              "spp = samples_per_pass = INT_MAX, cancel set: rc %d (want cancelled, not PT_OK with no samples)", rc);
        pt_film_free(&f);
    }
    {
        rc = pt_film_init(&f, d.width, d.height);
        if (!CHECK(t, rc == PT_OK, "film")) goto done;
        f.count[5] = 0xffffffffu - 1u; /* one more sample fits, two do not */
        rc = pt_render(s, &d, &f, &st);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "pt_render_desc.samples_per_pixel = 2:"),
              "a film with a pixel at 2^32 - 2 samples, 2 more: rc %d '%s'", rc, st.error);
        pt_film_free(&f);
    }
done:
    pt_film_free(&ref);
    pt_scene_destroy(s);
}


/* The batched integrator (pt_render_desc.integrator) renders the same film as the scalar one, bit
   for bit, over scene files that between them hold every feature the integrator branches on (glass
   and a diffuse ball, environment maps (one with a sun), delta lights, textures, a rough dielectric, triangles,
   many lights, a guide's scene), under every strategy, both samplers, indirect paths, splitting
   (mixture with light weight 0.75), adaptive sampling and guiding (its training iterations too,
   with Sobol and with independent numbers and 4 indirect paths); with Sobol, split copies run as
   lanes of the batch, and with 8 indirect paths and a budget of 12 also depth first (no free lane)
   with budgets ending within a camera sample's paths; the stats say which integrator ran (every
   sample batched, training included), how many copies ran as lanes, and which the default picks,
   and a bad value is refused naming the field. */
/* Quad lights sampled by solid angle from near and at grazing angles (the batched integrator sets
   their spherical rectangles up 4 at a time): one lying just above the floor and one upright, both
   two-sided, the whole ceiling (solid angles past PT__SPHERICAL_MAX near it), and a slanted
   parallelogram (not a rectangle: sampled by area). The same under scenes/sky.pfm: light sampling
   then picks the environment or a quad (the batched integrator's quads still 8 and 4 at a time). */
#define QUAD_LIGHTS_TEXT                                                                                                       \
    "camera look_from 0 1.2 -2.5 look_at 0 0.8 1 vfov 75\n"                                                                  \
    "material floor lambertian 0.7 0.7 0.7\nmaterial wall lambertian 0.6 0.5 0.4\n"                                         \
    "material lamp emitter 4 4 4\nmaterial lamp2 emitter 2 3 4 two_sided\n"                                                 \
    "quad -2 0 -3   0 0 6   4 0 0   floor\nquad -2 0 3   4 0 0   0 2.5 0   wall\nquad -2 0 -3   0 2.5 0   0 0 6   wall\n"  \
    "quad -2 2.5 -3   4 0 0   0 0 6   lamp\nquad -1.5 0.02 0.5   1 0 0   0 0 1   lamp2\n"                                   \
    "quad 1.2 0.3 -1   0 1.5 0   0 0 2   lamp2\nquad 0.3 0.05 1.2   0.8 0.3 0   0.1 0 0.9   lamp\n"
static const char quad_lights_scene[] = QUAD_LIGHTS_TEXT;
static const char quad_sky_scene[] = QUAD_LIGHTS_TEXT "environment sky.pfm 0.5\n";
/* Sphere lights (the batched integrator samples their cones 8 at a time): a two-sided one around
   the camera (every vertex inside it: area sampling), a one-sided one cutting the wall, one a hair
   above the floor (rims seen at grazing angles), a small one, and one of radius 10^-7 (narrower
   than float's angular resolution: rounded samples). */
static const char sphere_lights_scene[] =
    "camera look_from 0 1.2 -2.5 look_at 0 0.8 1 vfov 75\n"
    "material floor lambertian 0.7 0.7 0.7\nmaterial wall lambertian 0.6 0.5 0.4\n"
    "material bulb emitter 30 28 25\nmaterial glow emitter 0.8 0.9 1 two_sided\nmaterial dot emitter 1e7 1e7 1e7\n"
    "quad -2 0 -3   0 0 6   4 0 0   floor\nquad -2 0 3   4 0 0   0 2.5 0   wall\nquad -2 0 -3   0 2.5 0   0 0 6   wall\n"
    "sphere 0.8 1.6 -0.5 0.15 bulb\nsphere 0 1 -1 2 glow\nsphere -1.9 1 -1 0.2 bulb\nsphere 1 0.3001 0.5 0.3 bulb\n"
    "sphere 0.2 2.2 -1.5 0.01 bulb\nsphere 1 2.2 -0.5 1e-7 dot\n";

/* Enough lights for the light tree (the batched integrator makes its picks several at a time,
   stage 2t): eight small triangles facing down from the ceiling in two brightnesses, six quads
   (upright on the walls, two of them two-sided, one lying on the floor) and four small spheres;
   the same under scenes/sky.pfm (the pick's number then rescaled past the environment's share). */
#define TREE_LIGHTS_TEXT                                                                                                    \
    "camera look_from 0 1.2 -2.5 look_at 0 0.8 1 vfov 75\n"                                                                 \
    "material floor lambertian 0.7 0.7 0.7\nmaterial wall lambertian 0.6 0.5 0.4\n"                                         \
    "material tlo emitter 8 7 6\nmaterial thi emitter 40 38 34\nmaterial qlamp emitter 3 3 4 two_sided\n"                   \
    "material bulb emitter 30 28 25\n"                                                                                      \
    "quad -2 0 -3   0 0 6   4 0 0   floor\nquad -2 0 3   4 0 0   0 2.5 0   wall\nquad -2 0 -3   0 2.5 0   0 0 6   wall\n"   \
    "triangle -1.60 2.49 -2.50   -1.40 2.49 -2.50   -1.60 2.49 -2.30   tlo\n"                                               \
    "triangle -0.60 2.49 -2.50   -0.40 2.49 -2.50   -0.60 2.49 -2.30   thi\n"                                               \
    "triangle 0.40 2.49 -2.50   0.60 2.49 -2.50   0.40 2.49 -2.30   tlo\n"                                                  \
    "triangle 1.40 2.49 -2.50   1.60 2.49 -2.50   1.40 2.49 -2.30   thi\n"                                                  \
    "triangle -1.60 2.49 1.00   -1.40 2.49 1.00   -1.60 2.49 1.20   thi\n"                                                  \
    "triangle -0.60 2.49 1.00   -0.40 2.49 1.00   -0.60 2.49 1.20   tlo\n"                                                  \
    "triangle 0.40 2.49 1.00   0.60 2.49 1.00   0.40 2.49 1.20   thi\n"                                                     \
    "triangle 1.40 2.49 1.00   1.60 2.49 1.00   1.40 2.49 1.20   tlo\n"                                                     \
    "quad -1.99 1 -2   0 0.3 0   0 0 0.3   qlamp\nquad -1.99 1 0   0 0.3 0   0 0 0.3   qlamp\n"                             \
    "quad -1.99 1 2   0 0.3 0   0 0 0.3   bulb\nquad -0.5 1.5 2.99   0 0.3 0   0.4 0 0   bulb\n"                            \
    "quad 0.5 1.5 2.99   0 0.3 0   0.4 0 0   bulb\nquad 0.5 0.02 0   0 0 0.4   0.4 0 0   bulb\n"                            \
    "sphere 0.8 1.6 -0.5 0.1 bulb\nsphere -1 0.4 1.5 0.15 bulb\nsphere 1.5 2 2 0.05 bulb\nsphere 0 0.2 -1 0.1 bulb\n"
static const char tree_lights_scene[] = TREE_LIGHTS_TEXT;
static const char tree_sky_scene[] = TREE_LIGHTS_TEXT "environment sky.pfm 0.5\n";

static void batched_bit_identical(test_ctx *t)
{
    static const char *const scenes[] = { "scenes/cornell.scene", "scenes/cornell-diffuse.scene", "scenes/env.scene",
                                          "scenes/lights.scene", "scenes/textured.scene", "scenes/rough-glass.scene",
                                          "scenes/mesh.scene", "bench/scenes/sun-sky.scene", "bench/scenes/many-lights.scene",
                                          "bench/scenes/door.scene",
                                          "bench/scenes/rooms.scene", "quad lights", "quad lights under a sky",
                                          "sphere lights", "tree lights", "tree lights under a sky" };
    static const char *const configs[] = { "MIS", "material", "light", "mixture", "MIS sobol",
                                           "mixture 0.75 sobol", "indirect_paths 4", "adaptive", "guiding sobol, roulette from 1",
                                           "sobol, indirect_paths 8, mixture 0.75, max_splits 12",
                                           "guiding, indirect_paths 4" };
    const int nscenes = (int)(sizeof scenes / sizeof scenes[0]), nconfigs = (int)(sizeof configs / sizeof configs[0]);
    const int trees = nscenes - 2, spheres = nscenes - 3, quads = nscenes - 5, rooms = nscenes - 6; /* (the scenes
                                                            of quad, sphere and many lights are the last) */
    int i, c, renders = 0, split = 0, lane_copies = 0, inline_copies = 0;
    char err[512];
    for (i = 0; i < nscenes; ++i) {
        pt_scenefile sf;
        pt_scene *s = NULL;
        pt_render_desc base;
        int r = i == quads       ? pt_scenefile_parse(quad_lights_scene, sizeof quad_lights_scene - 1, scenes[i], ".", &sf, err,
                                                      sizeof err)
                : i == quads + 1 ? pt_scenefile_parse(quad_sky_scene, sizeof quad_sky_scene - 1, scenes[i], "scenes", &sf, err,
                                                      sizeof err)
                : i == spheres   ? pt_scenefile_parse(sphere_lights_scene, sizeof sphere_lights_scene - 1, scenes[i], ".", &sf,
                                                      err, sizeof err)
                : i == trees     ? pt_scenefile_parse(tree_lights_scene, sizeof tree_lights_scene - 1, scenes[i], ".", &sf, err,
                                                      sizeof err)
                : i == trees + 1 ? pt_scenefile_parse(tree_sky_scene, sizeof tree_sky_scene - 1, scenes[i], "scenes", &sf, err,
                                                      sizeof err)
                                 : pt_scenefile_load(scenes[i], &sf, err, sizeof err);
        if (!CHECK(t, r == PT_OK, "%s: %s", scenes[i], err)) continue;
        if (!CHECK(t, pt_scenefile_build(&sf, &s, &base, err, sizeof err) == PT_OK, "%s: %s", scenes[i], err)) {
            pt_scenefile_free(&sf);
            continue;
        }
        pt_scenefile_free(&sf);
        base.width = 14;
        base.height = 10;
        base.samples_per_pixel = 8;
        base.threads = 2;
        base.seed = 77;
        for (c = 0; c < nconfigs; ++c) {
            pt_render_desc d = base, e;
            pt_film a, b;
            pt_render_stats sa, sb;
            d.strategy = c == 1 ? PT_STRATEGY_MATERIAL : c == 2 ? PT_STRATEGY_LIGHT : c == 3 || c == 5 ? PT_STRATEGY_MIXTURE
                                                                                                        : PT_STRATEGY_MIS;
            if (c == 4 || c == 5 || c == 8 || c == 9) d.sampler = PT_SAMPLER_SOBOL;
            if (c == 5 || c == 9) d.light_weight = 0.75f;
            if (c == 9) { d.strategy = PT_STRATEGY_MIXTURE; d.indirect_paths = 8; d.max_splits = 12; }
            if (c == 6) d.indirect_paths = 4;
            if (c == 10) { d.guiding = PT_GUIDING_ON; d.samples_per_pixel = 16; d.indirect_paths = 4; }
            if (c == 7) { d.adaptive_threshold = 0.2f; d.samples_per_pixel = 12; d.adaptive_min_spp = 4; }
            if (c == 8) { d.guiding = PT_GUIDING_ON; d.samples_per_pixel = 16; d.rr_start_depth = 1; } /* (guided
                roulette at the first vertex, where it splits) */
            d.integrator = PT_INTEGRATOR_SCALAR;
            e = d;
            e.integrator = PT_INTEGRATOR_BATCHED;
            e.threads = 1;
            if (tu_render_into(t, s, &d, &a, &sa, "scalar") && tu_render_into(t, s, &e, &b, &sb, "batched")) {
                CHECK(t, tu_film_equal(&a, &b), "%s, %s: the batched film differs from the scalar one", scenes[i],
                      configs[c]);
                CHECK(t, sa.batched_samples == 0, "%s, %s: scalar render reports %llu batched samples", scenes[i],
                      configs[c], (unsigned long long)sa.batched_samples);
                CHECK(t, sb.batched_samples == sb.samples && sb.batched_samples > 0,
                      "%s, %s: batched_samples %llu of %llu (training %llu)", scenes[i], configs[c],
                      (unsigned long long)sb.batched_samples, (unsigned long long)sb.samples,
                      (unsigned long long)sb.guiding_samples);
                CHECK(t, sa.camera_rays == sb.camera_rays && sa.bounce_rays == sb.bounce_rays &&
                             sa.shadow_rays == sb.shadow_rays && sa.split_paths == sb.split_paths &&
                             sa.guided_vertices == sb.guided_vertices,
                      "%s, %s: ray counts differ", scenes[i], configs[c]);
                /* with Sobol split copies run as lanes of the batch (the rest, and every copy with
                   independent numbers, depth first in the scalar integrator) */
                CHECK(t, sa.batched_split_paths == 0 && sb.batched_split_paths <= sb.split_paths &&
                             (d.sampler == PT_SAMPLER_SOBOL) == (sb.batched_split_paths > 0),
                      "%s, %s: batched_split_paths %llu of %llu", scenes[i], configs[c],
                      (unsigned long long)sb.batched_split_paths, (unsigned long long)sb.split_paths);
                lane_copies += sb.batched_split_paths > 0;
                inline_copies += d.sampler == PT_SAMPLER_SOBOL && sb.batched_split_paths < sb.split_paths;
                split += sb.split_paths > 0;
                renders += 2;
                if (c == 0 && (i == 0 || i == 6)) { /* the default on the built-in BVH: batched with AVX2, in a
                                                        small scene (the Cornell box) and among triangles (mesh.scene) */
                    pt_film f;
                    pt_render_stats sd;
                    int want = pt_simd_get_level() >= PT_SIMD_AVX2;
                    d.integrator = PT_INTEGRATOR_DEFAULT;
                    if (tu_render_into(t, s, &d, &f, &sd, "default")) {
                        CHECK(t, tu_film_equal(&a, &f), "%s: the default integrator's film differs", scenes[i]);
                        CHECK(t, sd.batched_samples == (want ? sd.samples : 0u), "%s: default ran %s, want %s", scenes[i],
                              sd.batched_samples ? "batched" : "scalar", want ? "batched" : "scalar");
                    }
                    pt_film_free(&f);
                }
                if ((c == 4 || c == 0) && (i <= 3 || i == 7 || i >= rooms)) { /* Sobol's draws made ahead (stage
                    1b), the Lambertian directions made ahead (stage 3b, Sobol and independent numbers), quad
                    lights' samples (stages 2b and 2c, on rooms and the quad lights, with and without an
                    environment the pick can choose), sphere lights' (stage 2s) and the shadow rays' packets
                    (stage 3; the Cornell boxes' and the rooms' occluders, and the delta lights' rays of
                    scenes/lights.scene, scenes[3]), the environment's lookups and samples (stages 1e and 2e,
                    scenes/env.scene and sun-sky, scenes[2] and [7]): AVX2's 8 (or 4) at a time and the scalar
                    code below that level give the same film */
                    int level;
                    for (level = PT_SIMD_SCALAR; level < (int)pt_simd_cpu_level(); ++level) {
                        pt_film f;
                        memset(&f, 0, sizeof f);
                        if (!CHECK(t, pt_simd_set_cap((pt_simd_level)level) == PT_OK && pt_scene_commit(s) == PT_OK,
                                   "cap %s: commit", pt_simd_level_name((pt_simd_level)level)))
                            break;
                        if (tu_render_into(t, s, &e, &f, NULL, pt_simd_level_name((pt_simd_level)level))) {
                            CHECK(t, tu_film_equal(&a, &f), "%s, %s, batched at SIMD level %s: the film differs from the scalar one",
                                  scenes[i], configs[c], pt_simd_level_name((pt_simd_level)level));
                        }
                        pt_film_free(&f);
                    }
                    CHECK(t, pt_simd_set_cap(PT_SIMD_AVX512) == PT_OK && pt_scene_commit(s) == PT_OK, "uncapped commit");
                }
                if (c == 0 && i >= quads) { /* quads by area only (stage 2c without 2b), and shadow rays
                    traced where the material reflects nothing (pt__nee_prepare's general path) */
                    pt_film f, g;
                    memset(&f, 0, sizeof f);
                    memset(&g, 0, sizeof g);
                    d.disable_skips = e.disable_skips = PT_SKIP_SOLID_ANGLE_QUADS | PT_SKIP_ZERO_BSDF_SHADOW;
                    if (tu_render_into(t, s, &d, &f, NULL, "scalar, general") &&
                        tu_render_into(t, s, &e, &g, NULL, "batched, general"))
                        CHECK(t, tu_film_equal(&f, &g), "%s, %s, quads by area: the batched film differs from the scalar one",
                              scenes[i], configs[c]);
                    pt_film_free(&f);
                    pt_film_free(&g);
                }
            }
            pt_film_free(&a);
            pt_film_free(&b);
        }
        pt_scene_destroy(s);
    }
    CHECK(t, split > 0, "no configuration split a path: the splitting branch went untested");
    CHECK(t, lane_copies > 0 && inline_copies > 0,
          "Sobol renders with copies as lanes: %d, with copies also inline (no free lane): %d; both must be tested",
          lane_copies, inline_copies);
    {   /* a bad value names the field */
        pt_render_desc d = tu_base_desc(4, 4, 1, 1);
        pt_scene *s = cornell(0, &d);
        pt_film f;
        pt_render_stats st;
        if (CHECK(t, s != NULL, "Cornell scene")) {
            d.integrator = (pt_integrator)3;
            if (pt_film_init(&f, 4, 4) == PT_OK) {
                CHECK(t, pt_render(s, &d, &f, &st) == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "pt_render_desc.integrator = 3"),
                      "integrator 3: '%s'", st.error);
                pt_film_free(&f);
            }
            pt_scene_destroy(s);
        }
    }
    test_note(t, "%d renders of %d scenes x %d settings: batched = scalar bit for bit", renders, nscenes, nconfigs);
}

const test_case test_render_cases[] = {
    TEST_CASE(camera_conventions),
    TEST_CASE(threads_bit_identical),
    TEST_CASE(batched_bit_identical),
    TEST_CASE(progressive_equals_single),
    TEST_CASE(cancellation_and_progress),
    TEST_CASE(render_image_matches_film),
    TEST_CASE(render_desc_validation),
    TEST_CASE(render_errors_name_the_field),
    TEST_CASE(concurrent_renders),
    TEST_CASE(render_counts_no_overflow),
    TEST_CASE(furnace_closed_sphere),
    TEST_CASE(furnace_one_bounce),
    TEST_CASE(strategies_agree_cornell),
    TEST_CASE(direct_light_lambert),
    TEST_CASE(direct_sphere_light_formula),
    TEST_CASE(no_nonfinite_anywhere),
    TEST_END
};
