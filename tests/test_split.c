#define _POSIX_C_SOURCE 200809L
/* test_split.c - splitting a render (pdftrace.h section 8, "Splitting a render"; the core of the
   MPI driver, which make mpi-test checks end to end).

   film_exact_sums: pt_film's sums are exact, so random samples added one by one, in another
   order, or as films in other groupings give the same bytes (and a plain double sum of the same
   samples does not, on this data: the test can tell); pt_film_add refuses a count overflow.
   split_uniform_equals_whole: 2 and 3 parts rendered apart and added in part order with
   pt_film_add equal the whole render byte for byte (sums, squares, half-buffers, low words,
   counts), for the independent and Sobol samplers, MIS and mixture, with and without splitting,
   and into a film that already holds samples; a part alone is not the whole render.
   split_adaptive_equals_whole: adaptive sampling (pilot and own-samples modes) split over 2 and 3
   parts, run at once on threads with an in-process merge hook, gives part 0 the whole render's
   film byte for byte, for both samplers.
   split_errors: guiding is refused (PT_ERROR_UNSUPPORTED, named), adaptive without a merge hook and
   a bad split_part are refused before rendering, a failing hook fails the render with a message. */
#include "test_util.h"
#include "pdftrace_scene.h"

#ifndef PDFTRACE_NO_THREADS
#include <pthread.h>
#endif
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static pt_scene *load_cornell(test_ctx *t, pt_render_desc *d)
{
    pt_scenefile sd;
    pt_scene *s = NULL;
    char err[512];
    if (!CHECK(t, pt_scenefile_load("scenes/cornell.scene", &sd, err, sizeof err) == PT_OK, "cornell.scene: %s", err))
        return NULL;
    if (!CHECK(t, pt_scenefile_build(&sd, &s, d, err, sizeof err) == PT_OK, "cornell.scene: %s", err)) s = NULL;
    pt_scenefile_free(&sd);
    d->width = 20;
    d->height = 15;
    d->threads = 2;
    return s;
}

static int low_equal(const pt_film *a, const pt_film *b)
{
    size_t n = (size_t)a->width * (size_t)a->height;
    return memcmp(a->low, b->low, n * 9 * sizeof(double)) == 0;
}

/* sum, sum_sq, sum_odd and count (not the low words) */
static int hi_equal(const pt_film *a, const pt_film *b)
{
    size_t n = (size_t)a->width * (size_t)a->height;
    return memcmp(a->sum, b->sum, n * 3 * sizeof(double)) == 0 && memcmp(a->sum_sq, b->sum_sq, n * 3 * sizeof(double)) == 0 &&
           memcmp(a->sum_odd, b->sum_odd, n * 3 * sizeof(double)) == 0 && memcmp(a->count, b->count, n * 4) == 0;
}

/* The low words of sum and sum_odd alone (those of the squares are exact over a narrower range of
   sample values: pt_film). */
static int low_sums_equal(const pt_film *a, const pt_film *b)
{
    size_t i, n = (size_t)a->width * (size_t)a->height;
    int c;
    for (i = 0; i < n; i++)
        for (c = 0; c < 3; c++)
            if (a->low[9 * i + (size_t)c] != b->low[9 * i + (size_t)c] || a->low[9 * i + 6 + (size_t)c] != b->low[9 * i + 6 + (size_t)c])
                return 0;
    return 1;
}

static void film_exact_sums(test_ctx *t)
{
    enum { N = 4000 };
    pt_film one, rev, parts[3], big;
    pt_rng r = pt_rng_for_sample(7, 1, 2);
    static pt_color v[N];
    double plain_fwd = 0.0, plain_rev = 0.0;
    int i, p, plain_differs;
    memset(parts, 0, sizeof parts);
    if (!CHECK(t, pt_film_init(&one, 1, 1) == PT_OK && pt_film_init(&rev, 1, 1) == PT_OK, "films")) return;
    for (i = 0; i < N; i++) { /* values over 12 decades, as radiance samples with fireflies are */
        float e = (float)(tu_rand(&r) * 12.0 - 6.0);
        v[i] = pt_v3(powf(10.0f, e), (float)tu_rand(&r), i % 7 == 0 ? 0.0f : powf(10.0f, -e));
    }
    for (i = 0; i < N; i++) {
        pt_film_add_sample(&one, 0, 0, (uint32_t)i, v[i]);
        pt_film_add_sample(&rev, 0, 0, (uint32_t)(N - 1 - i), v[N - 1 - i]);
        plain_fwd += v[i].x;
        plain_rev += v[N - 1 - i].x;
    }
    plain_differs = plain_fwd != plain_rev;
    CHECK(t, plain_differs, "a plain double sum of these samples is the same both ways: the test cannot tell");
    CHECK(t, hi_equal(&one, &rev) && low_sums_equal(&one, &rev), "samples in reverse order: another film");
    for (p = 0; p < 3; p++) pt_film_init(&parts[p], 1, 1);
    for (i = 0; i < N; i++) pt_film_add_sample(&parts[(i * 7 + i / 3) % 3], 0, 0, (uint32_t)i, v[i]);
    CHECK(t, pt_film_add(&parts[0], &parts[1]) == PT_OK && pt_film_add(&parts[0], &parts[2]) == PT_OK, "pt_film_add");
    CHECK(t, hi_equal(&one, &parts[0]) && low_sums_equal(&one, &parts[0]), "three interleaved parts added: another film");
    CHECK(t, one.count[0] == N, "count %u, want %d", one.count[0], N);
    /* a count that would wrap is refused, dst unchanged */
    if (CHECK(t, pt_film_init(&big, 1, 1) == PT_OK, "film")) {
        big.count[0] = 0xffffffffu - 10u;
        CHECK(t, pt_film_add(&big, &one) == PT_ERROR_INVALID_ARGUMENT && big.count[0] == 0xffffffffu - 10u,
              "a wrapping count was accepted");
        pt_film_free(&big);
    }
    CHECK(t, pt_film_add(&one, NULL) == PT_ERROR_INVALID_ARGUMENT, "a NULL film was accepted");
    /* over 6 decades the squares' low words are exact too */
    for (p = 0; p < 3; p++) pt_film_clear(&parts[p]);
    pt_film_clear(&one);
    for (i = 0; i < N; i++) {
        pt_color w = pt_v3(powf(v[i].x, 0.5f), v[i].y, powf(v[i].z, 0.5f));
        pt_film_add_sample(&one, 0, 0, (uint32_t)i, w);
        pt_film_add_sample(&parts[i % 3], 0, 0, (uint32_t)i, w);
    }
    pt_film_add(&parts[0], &parts[1]);
    pt_film_add(&parts[0], &parts[2]);
    CHECK(t, tu_film_equal(&one, &parts[0]) && low_equal(&one, &parts[0]), "6 decades, three parts: another film");
    test_note(t, "%d samples over 12 decades (and 6): the same bytes in 3 orders and groupings", N);
    pt_film_free(&one);
    pt_film_free(&rev);
    for (p = 0; p < 3; p++) pt_film_free(&parts[p]);
}

/* Renders d split into n parts into separate films (each started as a copy of `start`), adds them
   in part order into *out (a copy of start plus every part). Returns 1 on success. */
static int render_parts(test_ctx *t, const pt_scene *s, const pt_render_desc *d, int n, const pt_film *start,
                        pt_film *out, pt_film *part0_alone)
{
    int p, ok = 1;
    size_t np = (size_t)d->width * (size_t)d->height;
    if (!CHECK(t, pt_film_init(out, d->width, d->height) == PT_OK, "film")) return 0;
    if (start) pt_film_add(out, start);
    for (p = 0; p < n && ok; p++) {
        pt_render_desc e = *d;
        pt_film f;
        pt_render_stats st;
        int rc;
        e.split_parts = n;
        e.split_part = p;
        if (!CHECK(t, pt_film_init(&f, d->width, d->height) == PT_OK, "film")) return 0;
        if (start) memcpy(f.count, start->count, np * sizeof(uint32_t)); /* the same counts: the same sample indices */
        rc = pt_render(s, &e, &f, &st);
        ok = CHECK(t, rc == PT_OK && st.nonfinite_samples == 0, "part %d of %d: %s", p, n, st.error);
        if (ok && start) { /* the part's own samples: its counts minus start's */
            size_t i;
            for (i = 0; i < np; i++) f.count[i] -= start->count[i];
        }
        if (ok) ok = CHECK(t, pt_film_add(out, &f) == PT_OK, "pt_film_add");
        if (ok && p == 0 && part0_alone) {
            pt_film_init(part0_alone, d->width, d->height);
            pt_film_add(part0_alone, &f);
        }
        pt_film_free(&f);
    }
    return ok;
}

static void split_uniform_equals_whole(test_ctx *t)
{
    pt_render_desc base;
    pt_scene *s = load_cornell(t, &base);
    int cfg, n, cases = 0;
    if (!s) return;
    for (cfg = 0; cfg < 8; cfg++) {
        pt_render_desc d = base;
        pt_film whole;
        d.samples_per_pixel = 6;
        d.samples_per_pass = 2;
        d.seed = 40u + (uint64_t)cfg;
        d.sampler = cfg & 1 ? PT_SAMPLER_SOBOL : PT_SAMPLER_INDEPENDENT;
        d.strategy = cfg & 2 ? PT_STRATEGY_MIXTURE : PT_STRATEGY_MIS;
        d.max_splits = cfg & 4 ? -1 : 0; /* no splitting, or the default (Sobol: 3 indirect paths) */
        if (!tu_render_into(t, s, &d, &whole, NULL, "whole")) break;
        for (n = 2; n <= 3; n++) {
            pt_film merged, alone;
            memset(&alone, 0, sizeof alone);
            if (render_parts(t, s, &d, n, NULL, &merged, &alone)) {
                CHECK(t, tu_film_equal(&whole, &merged) && low_equal(&whole, &merged),
                      "config %d (sampler %d, strategy %d, max_splits %d), %d parts: not the whole render", cfg,
                      (int)d.sampler, (int)d.strategy, d.max_splits, n);
                CHECK(t, !tu_film_equal(&whole, &alone), "config %d: part 0 alone equals the whole render", cfg);
                cases++;
            }
            pt_film_free(&merged);
            pt_film_free(&alone);
        }
        if (cfg == 1) { /* resumed: 6 more samples into a film that holds the first 6 */
            pt_film more, merged;
            if (tu_render_into(t, s, &d, &more, NULL, "whole, 12 samples")) {
                pt_render(s, &d, &more, NULL);
                if (render_parts(t, s, &d, 3, &whole, &merged, NULL))
                    CHECK(t, tu_film_equal(&more, &merged) && low_equal(&more, &merged), "resumed film, 3 parts: not the whole render");
                pt_film_free(&merged);
            }
            pt_film_free(&more);
        }
        pt_film_free(&whole);
    }
    test_note(t, "%d split renders (2 and 3 parts, 2 samplers x 2 strategies x 2 splitting settings)", cases);
    pt_scene_destroy(s);
}

#ifndef PDFTRACE_NO_THREADS
/* An in-process merge hook: the parts run on threads; at each merge every part deposits its
   buffer, part 0 adds the others in part order, and (everyone) the others copy the result. */
typedef struct hub {
    pthread_mutex_t lock;
    pthread_cond_t cond;
    int parts, arrived, generation, calls;
    void *bufs[4];
} hub;
typedef struct hub_part {
    hub *h;
    int part;
    const pt_scene *s;
    pt_render_desc d;
    pt_film film;
    pt_render_stats st;
    int rc;
} hub_part;
static void hub_wait(hub *h) /* a barrier */
{
    int gen;
    pthread_mutex_lock(&h->lock);
    gen = h->generation;
    if (++h->arrived == h->parts) {
        h->arrived = 0;
        h->generation++;
        pthread_cond_broadcast(&h->cond);
    } else {
        while (gen == h->generation) pthread_cond_wait(&h->cond, &h->lock);
    }
    pthread_mutex_unlock(&h->lock);
}
static int hub_merge(void *user, void *buffer, size_t bytes, int everyone, pt_merge_add_fn add, void *ctx)
{
    hub_part *me = (hub_part *)user;
    hub *h = me->h;
    int p;
    h->bufs[me->part] = buffer;
    hub_wait(h);
    if (me->part == 0) {
        for (p = 1; p < h->parts; p++) add(ctx, buffer, h->bufs[p]);
        h->calls++;
    }
    hub_wait(h);
    if (everyone && me->part != 0) memcpy(buffer, h->bufs[0], bytes);
    hub_wait(h);
    return 0;
}
static void *hub_run(void *arg)
{
    hub_part *me = (hub_part *)arg;
    me->rc = pt_render(me->s, &me->d, &me->film, &me->st);
    return NULL;
}
/* Renders d in n parts on threads with hub_merge; *out gets part 0's film. Returns merges made, or -1. */
static int render_hub(test_ctx *t, const pt_scene *s, const pt_render_desc *d, int n, pt_film *out)
{
    hub h;
    hub_part parts[4];
    pthread_t tid[4];
    int p, ok = 1, calls;
    memset(&h, 0, sizeof h);
    pthread_mutex_init(&h.lock, NULL);
    pthread_cond_init(&h.cond, NULL);
    h.parts = n;
    for (p = 0; p < n; p++) {
        memset(&parts[p], 0, sizeof parts[p]);
        parts[p].h = &h;
        parts[p].part = p;
        parts[p].s = s;
        parts[p].d = *d;
        parts[p].d.split_parts = n;
        parts[p].d.split_part = p;
        parts[p].d.threads = 1;
        parts[p].d.merge = hub_merge;
        parts[p].d.merge_user = &parts[p];
        pt_film_init(&parts[p].film, d->width, d->height);
    }
    for (p = 0; p < n; p++) pthread_create(&tid[p], NULL, hub_run, &parts[p]);
    for (p = 0; p < n; p++) pthread_join(tid[p], NULL);
    for (p = 0; p < n; p++) {
        ok &= CHECK(t, parts[p].rc == PT_OK && parts[p].st.nonfinite_samples == 0, "part %d of %d: %s", p, n,
                    parts[p].st.error);
        if (p) pt_film_free(&parts[p].film);
    }
    *out = parts[0].film;
    calls = h.calls;
    pthread_mutex_destroy(&h.lock);
    pthread_cond_destroy(&h.cond);
    return ok ? calls : -1;
}
#endif

static void split_adaptive_equals_whole(test_ctx *t)
{
#ifdef PDFTRACE_NO_THREADS
    test_skip(t, "the in-process merge hook runs the parts on threads (built with PDFTRACE_NO_THREADS)");
#else
    pt_render_desc base;
    pt_scene *s = load_cornell(t, &base);
    int cfg, n, cases = 0, most_merges = 0;
    if (!s) return;
    for (cfg = 0; cfg < 4; cfg++) {
        pt_render_desc d = base;
        pt_film whole;
        d.samples_per_pixel = 48;
        d.seed = 90u + (uint64_t)cfg;
        d.sampler = cfg & 1 ? PT_SAMPLER_SOBOL : PT_SAMPLER_INDEPENDENT;
        d.strategy = cfg & 1 ? PT_STRATEGY_MIXTURE : PT_STRATEGY_MIS;
        d.adaptive_threshold = 0.05f;
        d.adaptive_min_spp = 8;
        d.adaptive_mode = cfg & 2 ? PT_ADAPTIVE_OWN_SAMPLES : PT_ADAPTIVE_PILOT;
        if (!tu_render_into(t, s, &d, &whole, NULL, "whole")) break;
        for (n = 2; n <= 3; n++) {
            pt_film merged;
            int merges = render_hub(t, s, &d, n, &merged);
            if (merges >= 0) {
                CHECK(t, tu_film_equal(&whole, &merged) && low_equal(&whole, &merged),
                      "adaptive mode %d, sampler %d, %d parts: part 0's film is not the whole render's", (int)d.adaptive_mode,
                      (int)d.sampler, n);
                CHECK(t, merges >= 2, "%d merges: the plan was not made from a merged film", merges);
                if (merges > most_merges) most_merges = merges;
                cases++;
            }
            pt_film_free(&merged);
        }
        pt_film_free(&whole);
    }
    test_note(t, "%d split adaptive renders (pilot and own-samples, both samplers), up to %d merges each", cases, most_merges);
    pt_scene_destroy(s);
#endif
}

static int failing_merge(void *user, void *buffer, size_t bytes, int everyone, pt_merge_add_fn add, void *ctx)
{
    (void)user; (void)buffer; (void)bytes; (void)everyone; (void)add; (void)ctx;
    return 1;
}

static void split_errors(test_ctx *t)
{
    pt_render_desc base;
    pt_scene *s = load_cornell(t, &base);
    pt_film f;
    pt_render_stats st;
    int rc;
    if (!s) return;
    if (!CHECK(t, pt_film_init(&f, base.width, base.height) == PT_OK, "film")) { pt_scene_destroy(s); return; }
    base.samples_per_pixel = 4;
    {
        pt_render_desc d = base;
        d.split_parts = 2;
        d.guiding = PT_GUIDING_ON;
        rc = pt_render(s, &d, &f, &st);
        CHECK(t, rc == PT_ERROR_UNSUPPORTED && strstr(st.error, "guiding") && f.count[0] == 0, "guiding split: %d (%s)", rc,
              st.error);
    }
    {
        pt_render_desc d = base;
        d.split_parts = 3;
        d.adaptive_threshold = 0.1f;
        rc = pt_render(s, &d, &f, &st);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "merge") && f.count[0] == 0,
              "adaptive split without a hook: %d (%s)", rc, st.error);
    }
    {
        pt_render_desc d = base;
        d.split_parts = 2;
        d.split_part = 2;
        rc = pt_render(s, &d, &f, &st);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "split_part = 2"), "split_part 2 of 2: %d (%s)", rc,
              st.error);
        d.split_parts = -1;
        d.split_part = 0;
        rc = pt_render(s, &d, &f, &st);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "split_parts = -1"), "split_parts -1: %d (%s)", rc,
              st.error);
    }
    {
        pt_render_desc d = base;
        d.split_parts = 2;
        d.merge = failing_merge;
        rc = pt_render(s, &d, &f, &st);
        CHECK(t, rc == PT_ERROR_IO && strstr(st.error, "merge hook"), "a failing hook: %d (%s)", rc, st.error);
    }
    pt_film_free(&f);
    pt_scene_destroy(s);
}

const test_case test_split_cases[] = {
    TEST_CASE(film_exact_sums),
    TEST_CASE(split_uniform_equals_whole),
    TEST_CASE(split_adaptive_equals_whole),
    TEST_CASE(split_errors),
    TEST_END
};
