/* test_internals.h - the "internals" section: checks of pdftrace.h's internal (pt__) functions
   that the public API cannot reach, each against the plain computation it replaces. Included
   once, by test_main.c, after the implementation, whose static functions it calls. */
#ifndef PDFTRACE_TEST_INTERNALS_H
#define PDFTRACE_TEST_INTERNALS_H

#include "test.h"
#include <math.h>
#include <string.h>

/* The spot's falloff as atan2f alone gives it (pt__spot_falloff without its shortcuts). */
static float ti_spot_plain(const pt__dlight *l, pt_vec3 w)
{
    float a = atan2f(pt_length(pt_cross(l->axis, w)), pt_dot(l->axis, w));
    if (a <= l->beam) return 1.0f;
    if (!(a < l->cutoff)) return 0.0f;
    return pt__minf(1.0f, (l->cutoff - a) * l->inv_transition);
}

/* pt__spot_falloff's shortcuts (pt__spot_bounds) change no value: 2000 cones (beam below or equal
   to cutoff, some at 90 degrees), 4000 directions each, two in three within 10^-3 of the beam's
   or the cone's edge, at lengths 0.5 .. 3.5; every falloff must equal the plain one to the bit.
   Deterministic (fixed seed). The shortcuts must decide most directions, or they were lost. */
static void spot_falloff_shortcut(test_ctx *t)
{
    const float deg = 0.017453292519943295f;
    pt_rng r;
    long n = 0, bad = 0, fast = 0;
    int k, i;
    pt_rng_seed(&r, 7, 1);
    for (k = 0; k < 2000; ++k) {
        pt__dlight l;
        float c = k % 7 == 0 ? 90.0f : 0.01f + 89.99f * pt_rng_float(&r), b = (k & 1) ? c : c * pt_rng_float(&r);
        pt_vec3 ax = pt_normalize(pt_v3(pt_rng_float(&r) - 0.5f, pt_rng_float(&r) - 0.5f, pt_rng_float(&r) - 0.5f)), tn;
        if (!(b > 0.0f)) continue;
        memset(&l, 0, sizeof l);
        l.axis = ax;
        l.cutoff = c * deg;
        l.beam = b * deg;
        l.inv_transition = b < c ? 1.0f / (l.cutoff - l.beam) : 0.0f;
        pt__spot_bounds(&l);
        tn = pt_normalize(pt_cross(ax, pt_v3(0.3f, 0.7f, -0.2f)));
        for (i = 0; i < 4000; ++i) {
            const float edge = (i & 1) ? l.beam : l.cutoff, e = pt_rng_float(&r), len = 0.5f + 3.0f * pt_rng_float(&r);
            const float ang = i % 3 == 0 ? 3.1415926f * e : edge * (1.0f + 2e-3f * (e - 0.5f));
            const pt_vec3 w = pt_scale(pt_add(pt_scale(ax, cosf(ang)), pt_scale(tn, sinf(ang))), len);
            const float x = pt__spot_falloff(&l, w), y = ti_spot_plain(&l, w);
            const float sn = pt_length(pt_cross(ax, w)), cs = pt_dot(ax, w);
            ++n;
            if (cs > 0.0f && ((double)sn < (double)cs * l.tan_in || (double)sn > (double)cs * l.tan_out)) ++fast;
            if (memcmp(&x, &y, sizeof x) != 0 &&
                !CHECK(t, bad++ > 3, "cone %g, beam %g degrees, angle %.9g rad: falloff %.9g, plain %.9g", (double)c,
                       (double)b, (double)ang, (double)x, (double)y)) {}
        }
    }
    CHECK(t, bad == 0, "%ld of %ld falloffs differ from the plain ones", bad, n);
    CHECK(t, fast > n / 3, "the shortcuts decided only %ld of %ld directions", fast, n);
    test_note(t, "%ld directions, %ld by the shortcuts", n, fast);
}

/* The watertight test's ray set-up as branches give it (pt__rayctx_init2 before it chose its axes
   by selects). */
static void ti_rayctx_plain(pt__rayctx *rc, pt_vec3 d)
{
    float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z), dk;
    const float dv[3] = {d.x, d.y, d.z};
    rc->kz = (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2);
    rc->kx = (rc->kz + 1) % 3;
    rc->ky = (rc->kx + 1) % 3;
    dk = dv[rc->kz];
    if (dk < 0.0f) { int tmp = rc->kx; rc->kx = rc->ky; rc->ky = tmp; }
    if (dk == 0.0f) dk = FLT_MIN;
    rc->sx = dv[rc->kx] / dk;
    rc->sy = dv[rc->ky] / dk;
    rc->sz = 1.0f / dk;
}

/* pt__rayctx_init2 sets up the same axes and shear as the branches did, for random directions and
   for every direction whose components are drawn from {-1, -0, 0, 0.5, 1, NaN} (ties, zeros,
   signed zeros and NaNs among the components). */
static void rayctx_axes(test_ctx *t)
{
    static const float vals[6] = {-1.0f, -0.0f, 0.0f, 0.5f, 1.0f, 0.0f};
    pt_rng r;
    int i, bad = 0;
    pt_rng_seed(&r, 11, 3);
    for (i = 0; i < 200000 + 216; ++i) {
        pt__rayctx a, b;
        pt_ray ray;
        ray.origin = pt_v3(0.0f, 0.0f, 0.0f);
        if (i < 216) {
            float v[3];
            int j;
            for (j = 0; j < 3; ++j) {
                const int q = (i / (j == 0 ? 1 : j == 1 ? 6 : 36)) % 6;
                v[j] = q == 5 ? (float)NAN : vals[q];
            }
            ray.dir = pt_v3(v[0], v[1], v[2]);
        } else {
            ray.dir = pt_v3(2.0f * pt_rng_float(&r) - 1.0f, 2.0f * pt_rng_float(&r) - 1.0f, 2.0f * pt_rng_float(&r) - 1.0f);
        }
        pt__rayctx_init2(&a, ray, 1);
        ti_rayctx_plain(&b, ray.dir);
        if ((a.kx != b.kx || a.ky != b.ky || a.kz != b.kz || memcmp(&a.sx, &b.sx, sizeof a.sx) != 0 ||
             memcmp(&a.sy, &b.sy, sizeof a.sy) != 0 || memcmp(&a.sz, &b.sz, sizeof a.sz) != 0) &&
            !CHECK(t, bad++ > 3, "direction (%g, %g, %g): axes %d %d %d, plain %d %d %d", (double)ray.dir.x,
                   (double)ray.dir.y, (double)ray.dir.z, a.kx, a.ky, a.kz, b.kx, b.ky, b.kz)) {}
    }
    CHECK(t, bad == 0, "%d ray set-ups differ from the plain ones", bad);
}

static const test_case test_internals_cases[] = {
    TEST_CASE(spot_falloff_shortcut),
    TEST_CASE(rayctx_axes),
    TEST_END
};

#endif
