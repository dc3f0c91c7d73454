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
            if (cs > 0.0f && (sn < cs * l.tan_in || sn > cs * l.tan_out)) ++fast;
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

/* pt__sincos_turn (sin and cos of 2 pi u, the sphere light's azimuth) against double sin and cos
   at 2^21 + 1 evenly spaced u in [0, 1], at each quarter turn's and each reduction boundary's
   neighbours (u = k/8 +- a few ulps) and at u = 0, 1: within 1.5e-7 of the exact values (the
   outputs' rounding, 6e-8, plus that of 2 pi and of its product with the reduced u, 2e-8 and
   4e-8 at pi/4; the Taylor polynomials' 2e-9). With AVX2, pt__sincos_turn8 gives the scalar
   bits lane by lane at all of them, and a NaN gives NaNs in both. */
static void ti_turn_check(test_ctx *t, float u, double *worst, int *bad)
{
    float s, c;
    double es, ec, e;
    pt__sincos_turn(u, &s, &c);
    es = sin(6.283185307179586 * (double)u);
    ec = cos(6.283185307179586 * (double)u);
    e = fabs((double)s - es) > fabs((double)c - ec) ? fabs((double)s - es) : fabs((double)c - ec);
    if (e > *worst) *worst = e;
    if (!(e <= 1.5e-7) && !CHECK(t, (*bad)++ > 3, "u = %.9g: sin %.9g (exact %.9g), cos %.9g (exact %.9g)", (double)u,
                               (double)s, es, (double)c, ec)) {}
}
#ifdef PT__WIDE
PT__TARGET_AVX2 static void ti_turn8(const float *u, float *sv, float *cv)
{
    __m256 s, c;
    pt__sincos_turn8(_mm256_loadu_ps(u), &s, &c);
    _mm256_storeu_ps(sv, s);
    _mm256_storeu_ps(cv, c);
}
#endif
static void sincos_turn(test_ctx *t)
{
    const long n = 1L << 21;
    double worst = 0.0;
    int bad = 0, k, j;
    long i;
    float edge[8 * 9 * 2 + 3];
    int nedge = 0;
    for (i = 0; i <= n; ++i) ti_turn_check(t, (float)((double)i / (double)n), &worst, &bad);
    for (k = 0; k <= 8; ++k) {
        float u = (float)k / 8.0f, a = u, b = u;
        for (j = 0; j < 8; ++j) {
            a = nextafterf(a, 2.0f);
            b = nextafterf(b, -1.0f);
            if (a <= 1.0f) edge[nedge++] = a;
            if (b >= 0.0f) edge[nedge++] = b;
        }
        edge[nedge++] = u;
    }
    for (k = 0; k < nedge; ++k) ti_turn_check(t, edge[k], &worst, &bad);
    CHECK(t, bad == 0, "%d arguments off by more than 1.5e-7 (worst %.3g)", bad, worst);
    {
        float s, c;
        pt__sincos_turn((float)NAN, &s, &c);
        CHECK(t, s != s && c != c, "a NaN gives sin %g, cos %g (want NaNs)", (double)s, (double)c);
    }
#ifdef PT__WIDE
    if (pt_simd_cpu_level() >= PT_SIMD_AVX2) {
        float u[8], sv[8], cv[8];
        long m = 0;
        int vbad = 0;
        for (i = 0; i <= n + nedge + 1; i += 8) {
            for (j = 0; j < 8; ++j) {
                const long q = i + j;
                u[j] = q <= n ? (float)((double)q / (double)n) : q - n - 1 < nedge ? edge[q - n - 1] : (float)NAN;
            }
            ti_turn8(u, sv, cv);
            for (j = 0; j < 8; ++j) {
                float s, c;
                pt__sincos_turn(u[j], &s, &c);
                ++m;
                if ((memcmp(&s, &sv[j], sizeof s) != 0 || memcmp(&c, &cv[j], sizeof c) != 0) && !(s != s && sv[j] != sv[j] && c != c && cv[j] != cv[j]) &&
                    !CHECK(t, vbad++ > 3, "u = %.9g: 8 lanes give sin %.9g cos %.9g, the scalar code %.9g %.9g", (double)u[j],
                           (double)sv[j], (double)cv[j], (double)s, (double)c)) {}
            }
        }
        CHECK(t, vbad == 0, "%d of %ld lanes differ from the scalar code", vbad, m);
    } else {
        test_note(t, "no AVX2 on this CPU: the 8-lane version was not run");
    }
#endif
    test_note(t, "worst error %.3g", worst);
}

/* Stage 2s (pt__sphere_sample8) gives pt__sphere_light_sample's and pt__light_target's bits for
   every lane it takes, and takes nearly every lane outside its sphere: 40 000 groups of 8 lanes,
   spheres of radius 10^-7 (below float's angular resolution: rounded samples) to 3 at distances
   from just outside (1 + 10^-6 radii) to 10^4 radii, a sixth of the points inside or on their
   sphere (left to the scalar code), draws including 0 and 1 - 2^-24. Deterministic (fixed seed). */
static void sphere_sample8(test_ctx *t)
{
#ifdef PT__WIDE
    pt_scene *s;
    pt_rng r;
    long lanes = 0, taken = 0, outside = 0;
    int g, j, bad = 0, missed = 0;
    if (pt_simd_cpu_level() < PT_SIMD_AVX2) {
        test_skip(t, "no AVX2 on this CPU");
        return;
    }
    s = pt_scene_create();
    if (!CHECK(t, s != NULL, "scene")) return;
    pt_rng_seed(&r, 5, 9);
    for (g = 0; g < 40000; ++g) {
        float in[PT__SS_IN][8], out[PT__SO_OUT][8];
        pt__prim p[8];
        pt_vec3 o[8];
        int bits;
        for (j = 0; j < 8; ++j) {
            const float rad = powf(10.0f, -7.0f + 7.5f * pt_rng_float(&r)), q = pt_rng_float(&r);
            const float dist = j == 5 ? rad * (q < 0.5f ? q : 1.0f) : rad * (1.0f + powf(10.0f, -6.0f + 10.0f * q));
            const pt_vec3 c = pt_v3(20.0f * pt_rng_float(&r) - 10.0f, 20.0f * pt_rng_float(&r) - 10.0f, 20.0f * pt_rng_float(&r) - 10.0f);
            const pt_vec3 dir = pt_sample_uniform_sphere(pt_rng_float(&r), pt_rng_float(&r));
            memset(&p[j], 0, sizeof p[j]);
            p[j].type = PT__PRIM_SPHERE;
            p[j].p0 = c;
            p[j].p1.x = rad;
            pt__prim_cache(&p[j]);
            o[j] = pt_madd(c, dir, dist);
            in[PT__SS_O][j] = o[j].x;
            in[PT__SS_O + 1][j] = o[j].y;
            in[PT__SS_O + 2][j] = o[j].z;
            in[PT__SS_U1][j] = g % 50 == 0 ? (j & 1 ? 0.0f : 0.99999994f) : pt_rng_float(&r);
            in[PT__SS_U2][j] = g % 70 == 0 ? (j & 1 ? 0.99999994f : 0.0f) : pt_rng_float(&r);
            in[PT__SS_C][j] = c.x;
            in[PT__SS_C + 1][j] = c.y;
            in[PT__SS_C + 2][j] = c.z;
            in[PT__SS_R][j] = rad;
            in[PT__SS_MAG][j] = p[j].mag.x;
            in[PT__SS_MAG + 1][j] = p[j].mag.y;
            in[PT__SS_MAG + 2][j] = p[j].mag.z;
        }
        bits = pt__sphere_sample8(in, out);
        for (j = 0; j < 8; ++j) {
            pt__light_sample ls;
            int ok, inside = pt__sphere_inside(o[j], p[j].p0, p[j].p1.x);
            memset(&ls, 0, sizeof ls);
            ok = pt__sphere_light_sample(o[j], p[j].p0, p[j].p1.x, 1, in[PT__SS_U1][j], in[PT__SS_U2][j], &ls);
            ++lanes;
            outside += !inside;
            if (!((bits >> j) & 1)) {
                missed += !inside && ok && !ls.rounded;
                continue;
            }
            ++taken;
            {
                const pt_vec3 tg = pt__offset_origin(ls.point, ls.normal, pt_neg(ls.dir), pt__prim_magnitude(&p[j], ls.normal));
                const float want[PT__SO_OUT] = {ls.dir.x, ls.dir.y, ls.dir.z, ls.point.x, ls.point.y, ls.point.z,
                                                ls.normal.x, ls.normal.y, ls.normal.z, tg.x, tg.y, tg.z, ls.dist, ls.pdf};
                int k, same = ok && !inside && !ls.rounded;
                for (k = 0; k < PT__SO_OUT; ++k) same &= memcmp(&want[k], &out[k][j], sizeof want[k]) == 0;
                if (!same && !CHECK(t, bad++ > 3, "sphere r %g at distance %g: lane differs (scalar ok %d, rounded %d; "
                                    "dir %.9g %.9g, pdf %.9g %.9g, dist %.9g %.9g)", (double)p[j].p1.x,
                                    (double)pt_length(pt_sub(o[j], p[j].p0)), ok, ls.rounded, (double)ls.dir.x,
                                    (double)out[PT__SO_DIR][j], (double)ls.pdf, (double)out[PT__SO_PDF][j],
                                    (double)ls.dist, (double)out[PT__SO_DIST][j])) {}
            }
        }
    }
    CHECK(t, bad == 0, "%d of %ld lanes taken differ from the scalar sample", bad, taken);
    CHECK(t, missed < outside / 100, "the vector code left %d of %ld valid outside samples to the scalar code", missed, outside);
    test_note(t, "%ld lanes, %ld outside their sphere, %ld taken by the vector code", lanes, outside, taken);
    pt_scene_destroy(s);
#else
    test_skip(t, "built without the wide code (PT__WIDE)");
#endif
}
#ifdef PT__WIDE
static int ti_bits8(int bits)
{
    int j, n = 0;
    for (j = 0; j < 8; ++j) n += (bits >> j) & 1;
    return n;
}
/* One group of 8 environment lookups (stage 1e) against pt__env_eval, lane by lane, bit for bit. */
static int ti_env_eval_group(test_ctx *t, const pt__env *e, const pt_vec3 *w, long *bad)
{
    float in[3][8], out[PT__EO_OUT][8];
    int j, bits;
    for (j = 0; j < 8; ++j) {
        in[0][j] = w[j].x;
        in[1][j] = w[j].y;
        in[2][j] = w[j].z;
    }
    bits = pt__env_eval8(e, in, out);
    for (j = 0; j < 8; ++j) {
        float pm;
        pt_color L;
        if (!((bits >> j) & 1)) continue;
        L = pt__env_eval(e, w[j], &pm);
        if ((memcmp(&L.x, &out[PT__EO_L][j], 4) || memcmp(&L.y, &out[PT__EO_L + 1][j], 4) ||
             memcmp(&L.z, &out[PT__EO_L + 2][j], 4) || memcmp(&pm, &out[PT__EO_PM][j], 4)) &&
            !CHECK(t, (*bad)++ > 3, "%dx%d map, direction (%.9g, %.9g, %.9g): 8 lanes give %.9g %.9g %.9g density %.9g, "
                   "pt__env_eval %.9g %.9g %.9g density %.9g", e->w, e->h, (double)w[j].x, (double)w[j].y, (double)w[j].z,
                   (double)out[PT__EO_L][j], (double)out[PT__EO_L + 1][j], (double)out[PT__EO_L + 2][j],
                   (double)out[PT__EO_PM][j], (double)L.x, (double)L.y, (double)L.z, (double)pm)) {}
    }
    return ti_bits8(bits);
}
/* One group of 8 environment samples (stage 2e) against pt__env_sample with its radiance wanted. */
static int ti_env_sample_group(test_ctx *t, const pt__env *e, float c, const float *u1, const float *u2, long *bad)
{
    float out[PT__EO_OUT][8];
    int j, bits = pt__env_sample8(e, c, u1, u2, out);
    for (j = 0; j < 8; ++j) {
        pt_vec3 w;
        float pdf;
        pt_color L;
        int ok, vok, same;
        if (!((bits >> j) & 1)) continue;
        ok = pt__env_sample(e, c, u1[j], u2[j], &w, &pdf, &L);
        vok = out[PT__EO_PM][j] > 0.0f && pt__isfinite(out[PT__EO_PM][j]);
        same = ok == vok && !memcmp(&w.x, &out[PT__EO_DIR][j], 4) && !memcmp(&w.y, &out[PT__EO_DIR + 1][j], 4) &&
               !memcmp(&w.z, &out[PT__EO_DIR + 2][j], 4) && !memcmp(&pdf, &out[PT__EO_PM][j], 4);
        if (ok) same &= !memcmp(&L.x, &out[PT__EO_L][j], 4) && !memcmp(&L.y, &out[PT__EO_L + 1][j], 4) &&
                        !memcmp(&L.z, &out[PT__EO_L + 2][j], 4);
        if (!same && !CHECK(t, (*bad)++ > 3, "%dx%d map, c %g, u %.9g %.9g: 8 lanes give (%.9g, %.9g, %.9g) pdf %.9g L %.9g, "
                            "pt__env_sample %d (%.9g, %.9g, %.9g) pdf %.9g L %.9g", e->w, e->h, (double)c, (double)u1[j],
                            (double)u2[j], (double)out[PT__EO_DIR][j], (double)out[PT__EO_DIR + 1][j],
                            (double)out[PT__EO_DIR + 2][j], (double)out[PT__EO_PM][j], (double)out[PT__EO_L][j], ok,
                            (double)w.x, (double)w.y, (double)w.z, (double)pdf, (double)L.x)) {}
    }
    return ti_bits8(bits);
}
/* A number near a CDF's entry (the edges of the cells' intervals) or anywhere in [0, 1). */
static float ti_env_draw(pt_rng *r, const float *cdf, int n)
{
    const float q = pt_rng_float(r), x = cdf[pt_rng_u32(r) % (uint32_t)(n + 1)];
    int k = (int)(pt_rng_u32(r) % 5u) - 2;
    float y = x;
    if (q < 0.5f) return pt_rng_float(r);
    if (q < 0.55f) return q < 0.525f ? 0.0f : 0.99999994f;
    for (; k > 0; --k) y = nextafterf(y, 2.0f);
    for (; k < 0; ++k) y = nextafterf(y, -1.0f);
    return y < 0.0f ? 0.0f : (y < 1.0f ? y : 0.99999994f);
}
#endif
/* Stages 1e and 2e (pt__env_eval8, pt__env_sample8) give pt__env_eval's and pt__env_sample's bits
   for every lane they take, and take all but 0.1 % of random ones. Maps of 2 x 2, 37 x 19 and
   256 x 128 pixels (a sky with a sun one pixel wide, rows and columns of zeros: empty CDF
   intervals) and a uniform one of 37 x 24 (its CDF entries on the guide tables' steps k / n, where
   the rounding of u n sends the guide's bracket past the answer), under a rotation; 2^16 groups
   of 8 random directions and directions at and near the poles, on and beside the u seam and along
   the axes, and of draws at random and at the CDFs' entries and their neighbours (the cells'
   edges), 0 and 1 - 2^-24, with uniform shares 0 and 0.3 (a quarter of the groups random
   directions and draws only, for the share taken: the others hold the poles, where pt__atan2f
   goes to libm and so the lanes to the scalar code). Deterministic (fixed seed). */
static void env_lanes8(test_ctx *t)
{
#ifdef PT__WIDE
    static const int dims[4][2] = { { 2, 2 }, { 37, 19 }, { 256, 128 }, { 37, 24 } };
    pt_rng r;
    long etaken = 0, ebad = 0, eall = 0, staken = 0, sbad = 0, sall = 0, eplain = 0, splain = 0, nplain = 0;
    int m, g, j;
    if (pt_simd_cpu_level() < PT_SIMD_AVX2) {
        test_skip(t, "no AVX2 on this CPU");
        return;
    }
    pt_rng_seed(&r, 31, 7);
    for (m = 0; m < 4; ++m) {
        const int W = dims[m][0], H = dims[m][1];
        pt_scene *s = pt_scene_create();
        pt_image img;
        pt_environment_desc d;
        pt_transform xf = pt_transform_rotate(pt_v3(0.3f, 1.0f, -0.2f), 71.0f);
        int x, y;
        if (!CHECK(t, s != NULL, "scene")) return;
        img.width = W;
        img.height = H;
        img.rgb = (float *)malloc(sizeof(float) * 3 * (size_t)W * (size_t)H);
        if (!CHECK(t, img.rgb != NULL, "map")) {
            pt_scene_destroy(s);
            return;
        }
        for (y = 0; y < H; ++y)
            for (x = 0; x < W; ++x) {
                float *p = img.rgb + 3 * (y * W + x), v = 0.05f + pt_rng_float(&r);
                if (W > 2 && (y == 3 || (x % 11 == 5 && y > H / 2))) v = 0.0f; /* (empty rows and columns) */
                if (x == W / 3 && y == H / 4) v = 5e4f;                          /* (a sun) */
                p[0] = v;
                p[1] = 0.8f * v;
                p[2] = v * pt_rng_float(&r);
                if (m == 3) p[0] = p[1] = p[2] = 1.0f; /* (uniform: the columns' CDF entries on the guide's steps k / n) */
            }
        if (m == 1) xf = pt_transform_identity();
        d.map = &img;
        d.scale = 0.5f;
        if (!CHECK(t, pt_scene_set_transform(s, &xf) == PT_OK && pt_scene_set_environment(s, &d) == PT_OK,
                   "%dx%d map: %s", W, H, pt_scene_error_message(s))) {
            free(img.rgb);
            pt_scene_destroy(s);
            return;
        }
        for (g = 0; g < (1 << 14); ++g) {
            pt_vec3 w[8];
            const int plain = g % 4 == 1;
            float u1[8], u2[8], c = g & 2 ? 0.3f : 0.0f;
            int k;
            for (j = 0; j < 8; ++j) {
                const float a = pt_rng_float(&r), b = pt_rng_float(&r), tiny = powf(10.0f, -40.0f * pt_rng_float(&r));
                pt_vec3 v = pt_sample_uniform_sphere(a, b);
                switch (g % 8 == 0 ? j : 8) {
                case 0: v = pt_v3(0.0f, a < 0.5f ? 1.0f : -1.0f, 0.0f); break;       /* the poles */
                case 1: v = pt_v3(tiny, a < 0.5f ? 1.0f : -1.0f, -tiny); break;     /* beside them */
                case 2: v = pt_v3(0.0f, 2.0f * a - 1.0f, -1.0f); break;             /* the u seam */
                case 3: v = pt_v3(b < 0.5f ? tiny : -tiny, 2.0f * a - 1.0f, -1.0f); break;
                case 4: v = pt_v3(b < 0.5f ? 1.0f : -1.0f, 0.0f, 0.0f); break;      /* the axes */
                case 5: v = pt_v3(0.0f, 0.0f, b < 0.5f ? 1.0f : -1.0f); break;
                default: break;
                }
                w[j] = pt_normalize(v);
                if (m != 1) w[j] = pt_transform_vector(&xf, w[j]); /* (the map's own directions under the turn too) */
                u1[j] = ti_env_draw(&r, s->env->row_cdf, H);
                u2[j] = ti_env_draw(&r, s->env->col_cdf + (pt_rng_u32(&r) % (uint32_t)H) * (uint32_t)(W + 1), W);
                if (plain) {
                    u1[j] = c + (1.0f - c) * pt_rng_float(&r);
                    u2[j] = pt_rng_float(&r);
                }
                sall += u1[j] >= c;
            }
            eall += 8;
            etaken += k = ti_env_eval_group(t, s->env, w, &ebad);
            eplain += plain ? k : 0;
            staken += k = ti_env_sample_group(t, s->env, c, u1, u2, &sbad);
            splain += plain ? k : 0;
            nplain += plain ? 8 : 0;
        }
        free(img.rgb);
        pt_scene_destroy(s);
    }
    CHECK(t, ebad == 0, "%ld of %ld environment lookups taken differ from pt__env_eval", ebad, etaken);
    CHECK(t, sbad == 0, "%ld of %ld environment samples taken differ from pt__env_sample", sbad, staken);
    CHECK(t, eplain >= nplain - nplain / 1000 && splain >= nplain - nplain / 1000,
          "of %ld random lanes the vector code took %ld lookups and %ld samples (want all but 0.1 %%)", nplain, eplain, splain);
    test_note(t, "lookups: %ld of %ld lanes taken; samples: %ld of %ld map samples taken", etaken, eall, staken, sall);
#else
    test_skip(t, "built without the wide code (PT__WIDE)");
#endif
}
#ifdef PT__WIDE
/* A random light-tree node for lighttree_level_widths: children with boxes flat, thin or wide,
   normal cones from a single direction to every direction, and some empty. */
static void ti_random_lnode(pt_rng *r, pt__lnodew *n)
{
    int k, a;
    memset(n, 0, sizeof *n);
    for (k = 0; k < PT__LTREE_W; ++k) {
        float lo[3], hi[3], ax[3], len = 0.0f, cos_o;
        unsigned kind = pt_rng_u32(r) % 8u;
        if (kind == 0) { /* empty: as pt__ltree_collapse leaves it */
            n->r2[k] = 1.0f;
            n->cos_o[k] = -1.0f;
            n->child[k] = PT__LCHILD_LIGHT;
            continue;
        }
        for (a = 0; a < 3; ++a) {
            lo[a] = 10.0f * pt_rng_float(r) - 5.0f;
            hi[a] = lo[a] + (kind == 1 && a == 1 ? 0.0f : 2.0f * pt_rng_float(r) * pt_rng_float(r));
            ax[a] = kind == 2 ? (a == 1 ? -1.0f : 0.0f) : pt_rng_float(r) - 0.5f;
            len += ax[a] * ax[a];
        }
        len = sqrtf(len);
        cos_o = kind == 3 ? -1.0f : kind == 2 ? 1.0f : 2.0f * pt_rng_float(r) - 1.0f;
        for (a = 0; a < 3; ++a) {
            n->lo[a][k] = lo[a];
            n->hi[a][k] = hi[a];
            n->centre[a][k] = 0.5f * (lo[a] + hi[a]);
            n->axis[a][k] = ax[a] / len;
        }
        n->r2[k] = 0.25f * ((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                            (hi[2] - lo[2]) * (hi[2] - lo[2]));
        n->cos_o[k] = cos_o;
        n->sin_o[k] = sqrtf(pt__maxf(0.0f, 1.0f - cos_o * cos_o));
        n->cos_e[k] = kind == 4 ? 0.0f : pt_rng_float(r);
        n->pmin[k] = n->axis[0][k] * (n->axis[0][k] > 0.0f ? lo[0] : hi[0]) +
                     n->axis[1][k] * (n->axis[1][k] > 0.0f ? lo[1] : hi[1]) +
                     n->axis[2][k] * (n->axis[2][k] > 0.0f ? lo[2] : hi[2]);
        n->power[k] = kind == 5 ? 1e-30f : 100.0f * pt_rng_float(r);
        n->child[k] = PT__LCHILD_LIGHT | (uint32_t)k;
    }
}
#endif

/* The light tree's level (children's importances, their running sums and the child chosen) is
   the same to the bit in one AVX2 pass as in the SSE passes (or the scalar loop) every SIMD level
   below AVX2 takes: 4000 random nodes, 50 shading points each (some inside a child's box, so at
   distance 0), with no receiver normal, a random one or an axis, and the random number 0 among
   the others. Deterministic (fixed seed);
   skipped where the CPU or the build has no AVX2. */
static void lighttree_level_widths(test_ctx *t)
{
#ifdef PT__WIDE
    pt_rng r;
    long n = 0, bad = 0, zero = 0;
    int i, j;
    if (!__builtin_cpu_supports("avx2")) {
        test_skip(t, "no AVX2 on this CPU");
        return;
    }
    pt_rng_seed(&r, 11, 3);
    for (i = 0; i < 4000; ++i) {
        pt__lnodew node;
        ti_random_lnode(&r, &node);
        for (j = 0; j < 50; ++j) {
            float ia[PT__LTREE_W], ca[PT__LTREE_W], ib[PT__LTREE_W], cb[PT__LTREE_W], u = pt_rng_float(&r);
            int ka = -1, kb = -1, ra, rb, c = (int)(pt_rng_u32(&r) % PT__LTREE_W);
            pt_vec3 p = pt_v3(12.0f * pt_rng_float(&r) - 6.0f, 12.0f * pt_rng_float(&r) - 6.0f, 12.0f * pt_rng_float(&r) - 6.0f);
            pt_vec3 nr = pt_v3(0.0f, 0.0f, 0.0f);
            if (j % 5 == 0) p = pt_v3(node.centre[0][c], node.centre[1][c], node.centre[2][c]);
            if (j % 7 == 3) u = 0.0f; /* a threshold equal to the sums of the children that cannot light p */
            if (j % 3 == 1) nr = pt_normalize(pt_v3(pt_rng_float(&r) - 0.5f, pt_rng_float(&r) - 0.5f, pt_rng_float(&r) - 0.5f));
            if (j % 3 == 2) nr = pt_v3(0.0f, j % 2 ? 1.0f : -1.0f, 0.0f);
            ra = pt__lnodew_level_avx2_call(&node, p, nr, pt__has_normal(nr), u, ia, ca, &ka);
            rb = pt__lnodew_level_narrow(&node, p, nr, pt__has_normal(nr), u, ib, cb, &kb);
            ++n;
            zero += !ra;
            if ((ra != rb || (ra && ka != kb) || memcmp(ia, ib, sizeof ia) != 0 || memcmp(ca, cb, sizeof ca) != 0) &&
                !CHECK(t, bad++ > 3, "node %d, point (%g, %g, %g): AVX2 %d (child %d, total %.9g), narrow %d (child %d, total %.9g)",
                       i, (double)p.x, (double)p.y, (double)p.z, ra, ka, (double)ca[PT__LTREE_W - 1], rb, kb,
                       (double)cb[PT__LTREE_W - 1])) {}
        }
    }
    CHECK(t, bad == 0, "%ld of %ld levels differ between AVX2 and the narrow passes", bad, n);
    CHECK(t, zero < n / 2, "%ld of %ld levels lit by no child: the cases miss the importances", zero, n);
    test_note(t, "%ld levels, %ld lit by no child", n, zero);
#else
    test_skip(t, "built without the wide code (PT__WIDE)");
#endif
}

#if defined(PT__SSE)
/* A random ray for packet_hits: from a point in [-6, 6]^3, a third in a random direction, the
   rest aimed at a random primitive: a quad's point at (a, b) on it, often on or within 10^-6 of an
   edge or corner, or a sphere's silhouette, just inside or outside; directions not unit length. */
static pt_ray ti_packet_ray(pt_rng *r, const pt_scene *s)
{
    static const float edge[6] = {0.0f, 1.0f, -1e-6f, 1e-6f, 1.0f - 1e-6f, 1.0f + 1e-6f};
    pt_vec3 o = pt_v3(12.0f * pt_rng_float(r) - 6.0f, 12.0f * pt_rng_float(r) - 6.0f, 12.0f * pt_rng_float(r) - 6.0f), target;
    const pt__prim *p = &s->prims[pt_rng_u32(r) % s->prim_count];
    const float len = 0.01f + 10.0f * pt_rng_float(r);
    pt_ray ray;
    ray.origin = o;
    if (pt_rng_float(r) < 0.33f) {
        ray.dir = pt_scale(pt_sample_uniform_sphere(pt_rng_float(r), pt_rng_float(r)), len);
        return ray;
    }
    if (p->type == PT__PRIM_QUAD) {
        float a = pt_rng_float(r), b = pt_rng_float(r);
        if (pt_rng_float(r) < 0.6f) a = edge[pt_rng_u32(r) % 6];
        if (pt_rng_float(r) < 0.4f) b = edge[pt_rng_u32(r) % 6];
        target = pt_add(p->p0, pt_add(pt_scale(p->p1, a), pt_scale(p->p2, b)));
    } else {
        pt_vec3 to = pt_sub(p->p0, o), side = pt_cross(to, pt_sample_uniform_sphere(pt_rng_float(r), pt_rng_float(r)));
        const float k = pt_rng_float(r) < 0.5f ? 1.0f : 1.0f + (pt_rng_float(r) - 0.5f) * 4e-6f;
        target = pt_length(side) > 0.0f ? pt_madd(p->p0, pt_normalize(side), p->p1.x * k) : p->p0;
    }
    ray.dir = pt_scale(pt_normalize(pt_sub(target, o)), len);
    return ray;
}

/* A random scene of 1 .. 64 quads and spheres for packet_hits: quads of any orientation and
   size, some twice (equal t: the lower id must win), some side by side (shared edges), some the
   faces of a box (which the 16-ray packets cull under one box, pt__packet_chunks); spheres
   of radius 10^-4 .. 2 (the small ones through pt__hit_sphere's double precision). (Not a
   sphere twice: the BVH's four-sphere blocks break such ties by lane, not by id.) */
static pt_scene *ti_packet_scene(pt_rng *r, int n)
{
    pt_scene *s = pt_scene_create();
    int m, i;
    if (!s) return NULL;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    for (i = 0; i < n; ++i) {
        const pt_vec3 c = pt_v3(8.0f * pt_rng_float(r) - 4.0f, 8.0f * pt_rng_float(r) - 4.0f, 8.0f * pt_rng_float(r) - 4.0f);
        const float k = pt_rng_float(r);
        if (k < 0.3f) {
            pt_scene_add_sphere(s, c, powf(10.0f, -4.0f + 4.3f * pt_rng_float(r)), m);
        } else if (k < 0.45f && i + 6 <= n) { /* a box's six faces (one run under one box) */
            const pt_vec3 e = pt_v3(0.02f + 2.0f * pt_rng_float(r), 0.02f + 2.0f * pt_rng_float(r), 0.02f + 2.0f * pt_rng_float(r));
            const pt_vec3 ex = pt_v3(e.x, 0, 0), ey = pt_v3(0, e.y, 0), ez = pt_v3(0, 0, e.z), f = pt_add(c, e);
            pt_scene_add_quad(s, c, ez, ey, m);
            pt_scene_add_quad(s, f, pt_neg(ey), pt_neg(ez), m);
            pt_scene_add_quad(s, c, ex, ez, m);
            pt_scene_add_quad(s, f, pt_neg(ez), pt_neg(ex), m);
            pt_scene_add_quad(s, c, ey, ex, m);
            pt_scene_add_quad(s, f, pt_neg(ex), pt_neg(ey), m);
            i += 5;
        } else {
            const pt_vec3 u = pt_scale(pt_sample_uniform_sphere(pt_rng_float(r), pt_rng_float(r)), 0.05f + 5.0f * pt_rng_float(r));
            const pt_vec3 v = pt_scale(pt_sample_uniform_sphere(pt_rng_float(r), pt_rng_float(r)), 0.05f + 5.0f * pt_rng_float(r));
            pt_scene_add_quad(s, c, u, v, m);
            if (k < 0.4f && i + 1 < n) pt_scene_add_quad(s, c, u, v, m), ++i;
            else if (k < 0.5f && i + 1 < n) pt_scene_add_quad(s, pt_add(c, u), u, v, m), ++i;
        }
    }
    if (pt_scene_commit(s) != PT_OK) {
        pt_scene_destroy(s);
        return NULL;
    }
    return s;
}

/* One group of n rays through the packets of width w (4, 8 or 16; closest hits, and any hits in
   scenes of at most PT__BVH_SMALL_SCENE primitives): returns how many rays differ from the BVH. */
static int ti_packet_group(const pt_scene *s, const pt__packet_scene *ps, const pt__rayctx *const *rc, int n, int w,
                           const float *tmax, const uint32_t *skip, const int *want_any, const int *want_found,
                           const uint32_t *want_prim, const float *want_t)
{
    int found[16], j, bad = 0, hit = -1;
    uint32_t prim[16];
    float t[16];
    if (w == 4) pt__packet_closest4(s, ps, rc, n, found, prim, t);
#ifdef PT__WIDE
    else if (w == 8) pt__packet_closest8(s, ps, rc, n, found, prim, t);
    else pt__packet_closest16(s, ps, rc, n, found, prim, t);
    if (w > 4 && s->prim_count <= PT__BVH_SMALL_SCENE)
        hit = w == 8 ? pt__packet_any8(s, ps, rc, tmax, skip, n) : pt__packet_any16(s, ps, rc, tmax, skip, n);
#else
    (void)tmax; (void)skip; (void)want_any;
#endif
    for (j = 0; j < n; ++j) {
        int same = found[j] == want_found[j];
        if (same && found[j]) same = prim[j] == want_prim[j] && memcmp(&t[j], &want_t[j], sizeof t[j]) == 0;
        if (hit >= 0 && ((hit >> j) & 1) != want_any[j]) same = 0;
        bad += !same;
    }
    return bad;
}

/* The closest-hit and any-hit packets (pt__packet_closest4/8/16, pt__packet_any8/16) give the
   BVH's answers bit for bit (hit or not, primitive, t; occluded or not): 300 random scenes of 1 to
   64 quads and spheres (ti_packet_scene), 512 rays each (ti_packet_ray), in groups of 1 to the
   packet's width, any hits with tmax the closest hit's t, just above it, random or infinite and
   the skipped primitive the closest hit's, another or none. Every width the CPU runs is tested
   whatever the dispatch level (the BVH's: PDFTRACE_SIMD). Deterministic (fixed seed); the rays must hit often enough, and
   the any-hit limits cut off some of the hits, or the cases were lost. */
static void packet_hits(test_ctx *t)
{
    enum { RAYS = 512 };
    pt_rng r;
    pt__packet_scene *ps = (pt__packet_scene *)malloc(sizeof *ps);
    long rays = 0, hits = 0, cut = 0;
    int k, bad = 0, widths = pt_simd_cpu_level() >= PT_SIMD_AVX512 ? 3 : pt_simd_cpu_level() >= PT_SIMD_AVX2 ? 2 : 1;
    if (!CHECK(t, ps != NULL, "memory")) return;
    pt_rng_seed(&r, 11, 3);
    for (k = 0; k < 300; ++k) {
        pt_scene *s = ti_packet_scene(&r, 1 + (int)(pt_rng_u32(&r) % (k % 2 ? 32u : 64u)));
        static pt__rayctx rcs[RAYS];
        const pt__rayctx *rc[RAYS];
        float want_t[RAYS], tmax[RAYS];
        uint32_t want_prim[RAYS], skip[RAYS];
        int want_found[RAYS], want_any[RAYS], i, wi;
        if (!CHECK(t, s != NULL, "scene %d", k)) break;
        { /* (with PDFTRACE_SIMD=scalar the packets, made all the same, meet the scalar BVH) */
            const int simd = s->simd;
            if (simd == PT_SIMD_SCALAR) s->simd = PT_SIMD_SSE2;
            pt__packet_init(s, ps);
            s->simd = simd;
        }
        if (!CHECK(t, ps->n == (int)s->prim_count, "scene %d: %d of %u primitives in packets", k, ps->n, s->prim_count)) {
            pt_scene_destroy(s);
            break;
        }
        for (i = 0; i < RAYS; ++i) {
            float bary[3];
            const float q = pt_rng_float(&r);
            pt__rayctx_init2(&rcs[i], ti_packet_ray(&r, s), 0);
            rc[i] = &rcs[i];
            want_found[i] = pt__scene_closest(s, &rcs[i], PT__INF, &want_prim[i], &want_t[i], bary);
            tmax[i] = !want_found[i] || q < 0.2f ? PT__INF : q < 0.5f ? want_t[i] : q < 0.7f ? nextafterf(want_t[i], PT__INF)
                                                                                         : 20.0f * pt_rng_float(&r);
            skip[i] = pt_rng_float(&r) < 0.3f ? 0xffffffffu : want_found[i] && pt_rng_float(&r) < 0.6f ? want_prim[i]
                                                                                                 : pt_rng_u32(&r) % s->prim_count;
            want_any[i] = pt__scene_any(s, &rcs[i], tmax[i], skip[i]);
            hits += want_found[i];
            cut += want_found[i] && !want_any[i];
        }
        rays += RAYS;
        for (wi = 0; wi < widths; ++wi) {
            const int w = 4 << wi;
            for (i = 0; i < RAYS;) {
                const int n = 1 + (int)(pt_rng_u32(&r) % (uint32_t)w), m = RAYS - i < n ? RAYS - i : n;
                bad += ti_packet_group(s, ps, rc + i, m, w, tmax + i, skip + i, want_any + i, want_found + i, want_prim + i,
                                       want_t + i);
                i += m;
            }
        }
        pt_scene_destroy(s);
    }
    free(ps);
    CHECK(t, bad == 0, "%d rays' packet answers differ from the BVH's", bad);
    CHECK(t, hits > rays / 3 && cut > hits / 10, "%ld of %ld rays hit, %ld of them not occluded below tmax", hits, rays, cut);
    test_note(t, "%ld rays, %ld hits, %ld cut by tmax or skip, %d widths", rays, hits, cut, widths);
}
#endif

/* With a target that has FMA (make test's fma runner: GNU C, -march=native), the header must
   turn contraction off in its implementation, or this runner's bit-for-bit comparisons of vector
   and scalar code (render.batched_bit_identical, the sections above) fail; without FMA there is
   nothing to guard and they test nothing more than the plain runner does. */
static void fma_guard(test_ctx *t)
{
#if defined(__FP_FAST_FMAF) || defined(__FP_FAST_FMA) || defined(__FMA__)
    int guarded = 0;
#ifdef PT__NO_CONTRACT
    guarded = PT__NO_CONTRACT;
#endif
    CHECK(t, guarded, "the target has FMA but the header did not turn contraction off");
    test_note(t, "the target has FMA; the implementation is compiled without contraction");
#else
    test_skip(t, "the target has no FMA (build with -march=native on a CPU that has it)");
#endif
}

/* Stage 2d's weights (pt__delta_weight8, with the scalar code for the lanes it leaves) equal
   pt__delta_weight's to the bit, and so do the falloffs where the weight is not 0: 3000 lights
   (points, directional lights, spots with beam below or equal to the cutoff, cones from 0.001 to
   90 degrees) at 8 vertices each, half of them aimed near the beam's or the cone's edge, some
   at the light itself (d = 0) or transmitting (|cos|). pt__delta_pick_select picks as the
   branchy loop on weights with zeros among them, small integers among them with u x sum on a
   running sum (ties). Deterministic (fixed seed). */
static void delta_weight8(test_ctx *t)
{
#ifdef PT__WIDE
    const float deg = 0.017453292519943295f;
    pt__material opaque, transmits;
    pt_rng r;
    long n = 0, left = 0, bad = 0, nonzero = 0;
    int k, j;
    if (pt_simd_cpu_level() < PT_SIMD_AVX2) {
        test_skip(t, "no AVX2 on this CPU");
        return;
    }
    memset(&opaque, 0, sizeof opaque);
    memset(&transmits, 0, sizeof transmits);
    transmits.transmits = 1;
    pt_rng_seed(&r, 11, 3);
    for (k = 0; k < 6000; ++k) {
        pt__dlight l;
        pt__vertex v[8];
        float in[PT__DW_IN][8], w[8], fall[8];
        int bits;
        memset(&l, 0, sizeof l);
        l.desc.type = k % 5 == 0 ? PT_LIGHT_POINT : k % 5 == 1 ? PT_LIGHT_DIRECTIONAL : PT_LIGHT_SPOT;
        l.pos = pt_v3(4.0f * pt_rng_float(&r) - 2.0f, 4.0f * pt_rng_float(&r) - 2.0f, 4.0f * pt_rng_float(&r) - 2.0f);
        l.axis = pt_normalize(pt_v3(pt_rng_float(&r) - 0.5f, pt_rng_float(&r) - 0.5f, pt_rng_float(&r) - 0.5f));
        l.mean = 0.1f + 10.0f * pt_rng_float(&r);
        if (l.desc.type == PT_LIGHT_SPOT) {
            const float c = k % 7 == 0 ? 90.0f : k % 11 == 0 ? 0.001f : 0.01f + 89.99f * pt_rng_float(&r);
            const float b = (k & 1) ? c : c * (0.05f + 0.95f * pt_rng_float(&r));
            l.cutoff = c * deg;
            l.beam = b * deg;
            l.inv_transition = b < c ? 1.0f / (l.cutoff - l.beam) : 0.0f;
            pt__spot_bounds(&l);
        }
        for (j = 0; j < 8; ++j) {
            const float e = pt_rng_float(&r), len = 0.01f + 3.0f * pt_rng_float(&r);
            const float edge = (j & 2) ? l.beam : l.cutoff;
            const float ang = j % 2 == 0 ? edge * (1.0f + 2e-3f * (e - 0.5f)) : 3.1415926f * e;
            const pt_vec3 tn = pt_normalize(pt_cross(l.axis, pt_v3(0.3f, 0.7f, -0.2f)));
            const pt_vec3 dir = pt_add(pt_scale(l.axis, cosf(ang)), pt_scale(tn, sinf(ang)));
            memset(&v[j], 0, sizeof v[j]);
            v[j].m = j == 5 ? &transmits : &opaque;
            v[j].p = j == 7 && k % 4 == 0 ? l.pos : pt_madd(l.pos, dir, len); /* (on the light: d = 0) */
            v[j].ng = j == 6 ? pt_neg(dir) : pt_sample_uniform_sphere(pt_rng_float(&r), pt_rng_float(&r));
            in[PT__DW_P][j] = v[j].p.x;
            in[PT__DW_P + 1][j] = v[j].p.y;
            in[PT__DW_P + 2][j] = v[j].p.z;
            in[PT__DW_N][j] = v[j].ng.x;
            in[PT__DW_N + 1][j] = v[j].ng.y;
            in[PT__DW_N + 2][j] = v[j].ng.z;
            in[PT__DW_SG][j] = v[j].m->transmits ? 0.0f : 1.0f;
        }
        bits = pt__delta_weight8(&l, in, w, fall);
        for (j = 0; j < 8; ++j) {
            float f, x;
            ++n;
            if ((bits >> j) & 1) {
                ++left;
                continue;
            }
            x = pt__delta_weight(&v[j], &l, &f);
            nonzero += x > 0.0f;
            if ((memcmp(&x, &w[j], sizeof x) != 0 || (x > 0.0f && memcmp(&f, &fall[j], sizeof f) != 0)) &&
                !CHECK(t, bad++ > 3, "light type %d, cone %g, beam %g rad, lane %d: weight %.9g falloff %.9g, scalar %.9g %.9g",
                       (int)l.desc.type, (double)l.cutoff, (double)l.beam, j, (double)w[j], (double)fall[j], (double)x,
                       (double)f)) {}
        }
    }
    CHECK(t, bad == 0, "%ld of %ld lanes differ from pt__delta_weight", bad, n);
    CHECK(t, left < n / 4 && nonzero > n / 4, "%ld of %ld lanes left to the scalar code, %ld weights above 0", left, n, nonzero);
    for (k = 0; k < 20000; ++k) { /* the pick */
        float w[PT__DELTA_PICK_MAX], sum = 0.0f, acc = 0.0f, u = pt_rng_float(&r);
        uint32_t i, m = 2u + (uint32_t)k % (PT__DELTA_PICK_MAX - 1u), want = 0;
        for (i = 0; i < m; ++i)
            sum += (w[i] = pt_rng_float(&r) < 0.4f ? 0.0f : (k & 1) ? (float)(int)(4.0f * pt_rng_float(&r)) : pt_rng_float(&r));
        if (!(sum > 0.0f)) continue;
        if (k & 1) u = (float)(int)(sum * u) / sum; /* (u x sum a whole number, as are the running sums) */
        for (i = 0; i < m; ++i)
            if (w[i] > 0.0f) {
                want = i;
                acc += w[i];
                if (u * sum < acc) break;
            }
        if (pt__delta_pick_select(w, m, u * sum) != want &&
            !CHECK(t, bad++ > 3, "pick %u of %u lights, u %.9g: %u", (unsigned)want, (unsigned)m, (double)u,
                   (unsigned)pt__delta_pick_select(w, m, u * sum))) {}
    }
    CHECK(t, bad == 0, "%ld picks or weights differ", bad);
    test_note(t, "%ld lanes, %ld left to the scalar code", n, left);
#else
    test_skip(t, "built without the wide code (PT__WIDE)");
#endif
}

/* The light tree's picks made side by side (pt__tree_picks_avx2 and, where the CPU has AVX-512,
   pt__tree_picks_avx512, as the batched integrator's stage 2t makes them) are pt__tree_pick's to
   the bit, at AVX2 and at the narrow levels: the hall of 1024 lamps (bench/scenes/many-tris.scene),
   20000 points in and around it (some on its lamps' plane), with no receiver normal, a random one
   or an axis (the two slots of an AVX-512 pass often differ in having one), and the numbers 0 and
   the largest below 1 among the others; queries in runs of every length from 1 to 11, so slots
   end and refill at every phase. Deterministic (fixed seed); skipped where the CPU or the build has
   no AVX2 (the scene's SIMD level, whatever PDFTRACE_SIMD sets, is set by hand for each pick). */
static void lighttree_picks_interleaved(test_ctx *t)
{
#ifdef PT__WIDE
    pt_scenefile sf;
    pt_scene *s = NULL;
    pt_render_desc base;
    pt__tree_query q[11], q512[11];
    const int avx512 = __builtin_cpu_supports("avx512f");
    pt_rng r;
    char err[512];
    long n = 0, bad = 0, unlit = 0;
    int i, j, run;
    if (!__builtin_cpu_supports("avx2")) {
        test_skip(t, "no AVX2 on this CPU");
        return;
    }
    if (!CHECK(t, pt_scenefile_load("bench/scenes/many-tris.scene", &sf, err, sizeof err) == PT_OK, "%s", err)) return;
    if (!CHECK(t, pt_scenefile_build(&sf, &s, &base, err, sizeof err) == PT_OK, "%s", err)) {
        pt_scenefile_free(&sf);
        return;
    }
    pt_scenefile_free(&sf);
    if (!CHECK(t, s->ltree != NULL, "no light tree")) {
        pt_scene_destroy(s);
        return;
    }
    pt_rng_seed(&r, 23, 5);
    for (i = 0, run = 1; n < 20000; ++i, run = run % 11 + 1) {
        for (j = 0; j < run; ++j) {
            pt__tree_query *x = &q[j];
            const unsigned kind = pt_rng_u32(&r) % 6u;
            x->p = pt_v3(7.0f * pt_rng_float(&r) - 3.5f, 4.4f * pt_rng_float(&r) - 0.2f, 42.0f * pt_rng_float(&r) - 21.0f);
            if (kind == 5) x->p.y = 3.98f; /* the ceiling lamps' plane */
            x->nr = kind == 0 ? pt_v3(0.0f, 0.0f, 0.0f)
                    : kind == 1 ? pt_v3(0.0f, 1.0f, 0.0f)
                    : kind == 2 ? pt_v3(-1.0f, 0.0f, 0.0f)
                    : pt_normalize(pt_v3(pt_rng_float(&r) - 0.5f, pt_rng_float(&r) - 0.5f, pt_rng_float(&r) - 0.5f));
            x->u = j % 7 == 3 ? 0.0f : j % 7 == 5 ? 0.99999994f : pt_rng_float(&r);
            x->ok = -1;
        }
        memcpy(q512, q, sizeof q);
        pt__tree_picks_avx2(s, q, run);
        if (avx512) pt__tree_picks_avx512(s, q512, run);
        for (j = 0; j < run; ++j) {
            const pt__tree_query *x = &q[j];
            uint32_t la = 0xdeadu, lb = 0xdeadu;
            float pa = -1.0f, pb = -1.0f;
            int lv, ra, rb;
            s->simd = PT_SIMD_AVX2;
            ra = pt__tree_pick(s, x->p, x->nr, x->u, &la, &pa);
            for (lv = PT_SIMD_SCALAR; lv < PT_SIMD_AVX2; ++lv) { /* (the narrow levels agree with AVX2) */
                s->simd = lv;
                rb = pt__tree_pick(s, x->p, x->nr, x->u, &lb, &pb);
                if (rb != ra || (ra && (lb != la || memcmp(&pa, &pb, sizeof pa) != 0))) break;
            }
            ++n;
            unlit += !x->ok;
            if (avx512 && (q512[j].ok != x->ok || (x->ok && (q512[j].light != x->light ||
                                                             memcmp(&q512[j].pmf, &x->pmf, sizeof x->pmf) != 0))) &&
                !CHECK(t, bad++ > 3, "point (%g, %g, %g), u %.9g: AVX-512 %d (light %u, pmf %.9g), AVX2 %d (light %u, pmf %.9g)",
                       (double)x->p.x, (double)x->p.y, (double)x->p.z, (double)x->u, q512[j].ok, (unsigned)q512[j].light,
                       (double)q512[j].pmf, x->ok, (unsigned)x->light, (double)x->pmf)) {}
            if ((x->ok != ra || (ra && (x->light != la || memcmp(&x->pmf, &pa, sizeof pa) != 0)) || lv < PT_SIMD_AVX2) &&
                !CHECK(t, bad++ > 3, "point (%g, %g, %g), u %.9g: side by side %d (light %u, pmf %.9g), alone %d (light %u, "
                       "pmf %.9g), level %d", (double)x->p.x, (double)x->p.y, (double)x->p.z, (double)x->u, x->ok,
                       (unsigned)x->light, (double)x->pmf, ra, (unsigned)la, (double)pa, lv)) {}
        }
    }
    CHECK(t, bad == 0, "%ld of %ld picks differ between side by side and alone", bad, n);
    CHECK(t, unlit < n / 4, "%ld of %ld points lit by no light: the cases miss the picks", unlit, n);
    test_note(t, "%ld picks in runs of 1 to 11, %ld lit by no light; AVX-512 %s", n, unlit, avx512 ? "too" : "absent");
    pt_scene_destroy(s);
#else
    test_skip(t, "built without the wide code (PT__WIDE)");
#endif
}

static const test_case test_internals_cases[] = {
    TEST_CASE(fma_guard),
    TEST_CASE(spot_falloff_shortcut),
    TEST_CASE(rayctx_axes),
    TEST_CASE(sincos_turn),
    TEST_CASE(sphere_sample8),
    TEST_CASE(env_lanes8),
    TEST_CASE(lighttree_level_widths),
    TEST_CASE(lighttree_picks_interleaved),
#if defined(PT__SSE)
    TEST_CASE(packet_hits),
#endif
    TEST_CASE(delta_weight8),
    TEST_END
};

#endif
