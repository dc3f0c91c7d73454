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
    TEST_CASE(spot_falloff_shortcut),
    TEST_CASE(rayctx_axes),
    TEST_CASE(sincos_turn),
    TEST_CASE(sphere_sample8),
    TEST_CASE(lighttree_level_widths),
    TEST_CASE(lighttree_picks_interleaved),
    TEST_END
};

#endif
