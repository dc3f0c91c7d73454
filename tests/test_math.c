/* test_math.c - section 1 of pdftrace.h: vectors, rays, affine transforms (including normals) and the
   orthonormal basis. All expected values come from independent double-precision math (Rodrigues'
   rotation formula, the defining properties of the inverse transpose, orthonormality). */
#include "test_util.h"

#include <float.h>
#include <stdio.h>
#include <string.h>

static int v3_near(pt_vec3 a, dv3 b, double tol)
{
    return fabs(a.x - b.x) <= tol && fabs(a.y - b.y) <= tol && fabs(a.z - b.z) <= tol;
}

static int v3_finite(pt_vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }

static void vector_ops(test_ctx *t)
{
    pt_vec3 a = pt_v3(1.5f, -2.0f, 4.0f), b = pt_v3(0.5f, 3.0f, -1.0f), c;
    /* exact in binary floating point */
    CHECK(t, v3_near(pt_add(a, b), dv(2.0, 1.0, 3.0), 0), "pt_add");
    CHECK(t, v3_near(pt_sub(a, b), dv(1.0, -5.0, 5.0), 0), "pt_sub");
    CHECK(t, v3_near(pt_mul(a, b), dv(0.75, -6.0, -4.0), 0), "pt_mul");
    CHECK(t, v3_near(pt_scale(a, 2.0f), dv(3.0, -4.0, 8.0), 0), "pt_scale");
    CHECK(t, v3_near(pt_neg(a), dv(-1.5, 2.0, -4.0), 0), "pt_neg");
    CHECK(t, v3_near(pt_madd(a, b, 2.0f), dv(2.5, 4.0, 2.0), 0), "pt_madd");
    CHECK(t, pt_dot(a, b) == 0.75f - 6.0f - 4.0f, "pt_dot %g", pt_dot(a, b));
    CHECK(t, pt_length2(a) == 2.25f + 4.0f + 16.0f, "pt_length2");
    CHECK(t, pt_max_component(a) == 4.0f && pt_max_component(b) == 3.0f &&
                 pt_max_component(pt_v3(-1.0f, -3.0f, -2.0f)) == -1.0f, "pt_max_component");
    /* right-handed cross product: x cross y = z, and the general formula */
    CHECK(t, v3_near(pt_cross(pt_v3(1, 0, 0), pt_v3(0, 1, 0)), dv(0, 0, 1), 0), "x cross y != z");
    CHECK(t, v3_near(pt_cross(pt_v3(0, 1, 0), pt_v3(0, 0, 1)), dv(1, 0, 0), 0), "y cross z != x");
    c = pt_cross(a, b);
    CHECK(t, v3_near(c, dcross(dv_from(a), dv_from(b)), 1e-6), "pt_cross(a, b) = (%g, %g, %g)", c.x, c.y, c.z);
    /* normalize: unit length; zero stays zero, never NaN */
    c = pt_normalize(pt_v3(3.0f, 4.0f, 12.0f));
    CHECK(t, v3_near(c, dv(3.0 / 13, 4.0 / 13, 12.0 / 13), 1e-7), "pt_normalize(3,4,12)");
    c = pt_normalize(pt_v3(0, 0, 0));
    CHECK(t, c.x == 0.0f && c.y == 0.0f && c.z == 0.0f, "pt_normalize(0) = (%g, %g, %g)", c.x, c.y, c.z);
    c = pt_normalize(pt_v3(1e-30f, 0.0f, 0.0f));
    CHECK(t, v3_finite(c), "pt_normalize of a tiny vector is not finite");
    {
        pt_ray r;
        pt_vec3 p;
        r.origin = pt_v3(1, 2, 3);
        r.dir = pt_v3(0.5f, 0, -2);
        p = pt_ray_at(r, 2.0f);
        CHECK(t, v3_near(p, dv(2, 2, -1), 0), "pt_ray_at");
    }
}

/* Rodrigues' rotation formula in double: v cos + (k x v) sin + k (k.v)(1 - cos). */
static dv3 rodrigues(dv3 k, double degrees, dv3 v)
{
    double a = degrees * TU_PI / 180.0, c = cos(a), s = sin(a);
    k = dnorm(k);
    return dadd(dadd(dscale(v, c), dscale(dcross(k, v), s)), dscale(k, ddot(k, v) * (1.0 - c)));
}

static void transform_basics(test_ctx *t)
{
    pt_transform id = pt_transform_identity(), tr = pt_transform_translate(pt_v3(1, -2, 3));
    pt_transform sc = pt_transform_scale(pt_v3(2, 3, -4)), m;
    pt_vec3 p = pt_v3(0.5f, 0.25f, -1.0f), q;
    q = pt_transform_point(&id, p);
    CHECK(t, v3_near(q, dv_from(p), 0), "identity moved a point");
    q = pt_transform_point(&tr, p);
    CHECK(t, v3_near(q, dv(1.5, -1.75, 2.0), 0), "translate point = (%g, %g, %g)", q.x, q.y, q.z);
    q = pt_transform_vector(&tr, p);
    CHECK(t, v3_near(q, dv_from(p), 0), "translate moved a vector: (%g, %g, %g)", q.x, q.y, q.z);
    q = pt_transform_point(&sc, p);
    CHECK(t, v3_near(q, dv(1.0, 0.75, 4.0), 0), "scale point = (%g, %g, %g)", q.x, q.y, q.z);
    /* a * b applies b first: translate(scale(p)) vs scale(translate(p)) */
    m = pt_transform_mul(tr, sc);
    q = pt_transform_point(&m, p);
    CHECK(t, v3_near(q, dv(2.0, -1.25, 7.0), 1e-6), "mul(translate, scale) applied = (%g, %g, %g), want (2, -1.25, 7)",
          q.x, q.y, q.z);
    m = pt_transform_mul(sc, tr);
    q = pt_transform_point(&m, p);
    CHECK(t, v3_near(q, dv(3.0, -5.25, -8.0), 1e-6), "mul(scale, translate) applied = (%g, %g, %g), want (3, -5.25, -8)",
          q.x, q.y, q.z);
    /* the matrix layout is documented: p' = M p + t, t in column 3 */
    CHECK(t, tr.m[0][3] == 1.0f && tr.m[1][3] == -2.0f && tr.m[2][3] == 3.0f && sc.m[0][0] == 2.0f &&
                 sc.m[1][1] == 3.0f && sc.m[2][2] == -4.0f && sc.m[0][1] == 0.0f,
          "pt_transform layout is not M | t (row-major 3x4)");
}

static void transform_rotate(test_ctx *t)
{
    pt_rng rng;
    int i, bad = 0;
    double worst = 0;
    pt_transform r = pt_transform_rotate_y(90.0f), r2;
    pt_vec3 q = pt_transform_vector(&r, pt_v3(1, 0, 0));
    /* right-handed about +y: +x goes to -z */
    CHECK(t, v3_near(q, dv(0, 0, -1), 1e-6), "rotate_y(90) maps +x to (%g, %g, %g), want (0, 0, -1)", q.x, q.y, q.z);
    q = pt_transform_vector(&r, pt_v3(0, 0, 1));
    CHECK(t, v3_near(q, dv(1, 0, 0), 1e-6), "rotate_y(90) maps +z to (%g, %g, %g), want (1, 0, 0)", q.x, q.y, q.z);
    r = pt_transform_rotate(pt_v3(0, 0, 1), 90.0f);
    q = pt_transform_vector(&r, pt_v3(1, 0, 0));
    CHECK(t, v3_near(q, dv(0, 1, 0), 1e-6), "rotate(z, 90) maps +x to (%g, %g, %g), want +y", q.x, q.y, q.z);
    pt_rng_seed(&rng, 1234, 1);
    for (i = 0; i < 2000; i++) {
        dv3 k = tu_rand_dir(&rng), v = dscale(tu_rand_dir(&rng), 10.0 * tu_rand(&rng)), want;
        float deg = (float)(720.0 * tu_rand(&rng) - 360.0);
        pt_vec3 kf = pt_normalize(dv_to(k)), vf = dv_to(v), got;
        dv3 tt = dv(tu_rand(&rng) - 0.5, tu_rand(&rng) - 0.5, tu_rand(&rng) - 0.5);
        pt_transform m;
        double err;
        r = pt_transform_rotate(kf, deg);
        want = rodrigues(dv_from(kf), deg, dv_from(vf));
        got = pt_transform_vector(&r, vf);
        err = dlen(dsub(dv_from(got), want)) / fmax(1.0, dlen(want));
        worst = fmax(worst, err);
        if (err > 2e-6) bad++;
        /* rotation then translation, composed */
        m = pt_transform_mul(pt_transform_translate(dv_to(tt)), r);
        got = pt_transform_point(&m, vf);
        err = dlen(dsub(dv_from(got), dadd(want, dv_from(dv_to(tt))))) / fmax(1.0, dlen(want));
        if (err > 4e-6) bad++;
    }
    CHECK(t, bad == 0, "%d of 4000 rotated vectors differ from Rodrigues' formula (worst rel %.3g)", bad, worst);
    r = pt_transform_rotate_y(33.0f);
    r2 = pt_transform_rotate(pt_v3(0, 1, 0), 33.0f);
    q = pt_transform_vector(&r, pt_v3(0.3f, -0.7f, 0.2f));
    CHECK(t, v3_near(q, dv_from(pt_transform_vector(&r2, pt_v3(0.3f, -0.7f, 0.2f))), 1e-6),
          "rotate_y(33) differs from rotate((0,1,0), 33)");
    test_note(t, "worst rel error %.2g", worst);
}

static void transform_normal(test_ctx *t)
{
    pt_rng rng;
    int i, bad = 0, rc;
    double worst = 0;
    pt_transform m;
    pt_vec3 out;
    pt_rng_seed(&rng, 99, 3);
    for (i = 0; i < 2000; i++) {
        /* a random affine map: rotation * non-uniform scale * rotation, plus translation */
        dv3 s = dv(0.2 + 3 * tu_rand(&rng), 0.2 + 3 * tu_rand(&rng), 0.2 + 3 * tu_rand(&rng));
        pt_transform a = pt_transform_rotate(pt_normalize(dv_to(tu_rand_dir(&rng))), (float)(360 * tu_rand(&rng)));
        pt_transform b = pt_transform_rotate(pt_normalize(dv_to(tu_rand_dir(&rng))), (float)(360 * tu_rand(&rng)));
        dv3 n = tu_rand_dir(&rng), e1, e2, n2;
        pt_vec3 nf = pt_normalize(dv_to(n)), me1, me2, mn;
        double d1, d2, d3;
        if (tu_rand(&rng) < 0.3) s.x = -s.x; /* mirror too */
        m = pt_transform_mul(pt_transform_translate(pt_v3(5, -3, 2)),
                             pt_transform_mul(a, pt_transform_mul(pt_transform_scale(dv_to(s)), b)));
        rc = pt_transform_normal(&m, nf, &out);
        if (rc != PT_OK || !v3_finite(out)) { bad++; continue; }
        /* the transformed normal is perpendicular to the transformed tangent plane, and points to the
           same side as the transformed normal vector (n' . M n = n . n > 0 for n' = M^-T n) */
        tu_frame(dv_from(nf), &e1, &e2);
        me1 = pt_transform_vector(&m, dv_to(e1));
        me2 = pt_transform_vector(&m, dv_to(e2));
        mn = pt_transform_vector(&m, nf);
        n2 = dnorm(dv_from(out));
        d1 = fabs(ddot(n2, dnorm(dv_from(me1))));
        d2 = fabs(ddot(n2, dnorm(dv_from(me2))));
        d3 = ddot(n2, dv_from(mn));
        worst = fmax(worst, fmax(d1, d2));
        if (d1 > 1e-4 || d2 > 1e-4 || !(d3 > 0)) bad++;
    }
    CHECK(t, bad == 0, "%d of 2000 transformed normals not perpendicular to the transformed surface (worst |cos| %.3g)",
          bad, worst);
    m = pt_transform_scale(pt_v3(1, 0, 1));
    out = pt_v3(9, 9, 9);
    rc = pt_transform_normal(&m, pt_v3(0, 1, 0), &out);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "singular transform: pt_transform_normal returned %d", rc);
    test_note(t, "worst |n'.Mt| %.2g", worst);
}

static int check_onb(test_ctx *t, pt_vec3 n, double tol, double *worst)
{
    pt_onb b = pt_onb_from_normal(n);
    dv3 s = dv_from(b.s), tt = dv_from(b.t), nn = dv_from(b.n), c = dcross(s, tt);
    double e = 0;
    pt_vec3 l = pt_v3(0.3f, -0.5f, 0.81240384f), w, back;
    if (!v3_finite(b.s) || !v3_finite(b.t) || !v3_finite(b.n)) {
        CHECK(t, 0, "basis of (%.9g, %.9g, %.9g) is not finite", n.x, n.y, n.z);
        return 0;
    }
    e = fmax(e, fabs(dlen(s) - 1));
    e = fmax(e, fabs(dlen(tt) - 1));
    e = fmax(e, fabs(ddot(s, tt)));
    e = fmax(e, fabs(ddot(s, nn)));
    e = fmax(e, fabs(ddot(tt, nn)));
    e = fmax(e, dlen(dsub(c, nn)));           /* right-handed: s x t = n */
    e = fmax(e, dlen(dsub(nn, dv_from(n)))); /* n is the input normal */
    w = pt_onb_to_world(&b, l);
    back = pt_onb_to_local(&b, w);
    e = fmax(e, dlen(dsub(dv_from(back), dv_from(l))));
    if (e > *worst) *worst = e;
    return CHECK(t, e <= tol, "basis of n = (%.9g, %.9g, %.9g): error %.3g > %.1g; s = (%.9g, %.9g, %.9g) t = (%.9g, %.9g, %.9g)",
                 n.x, n.y, n.z, e, tol, b.s.x, b.s.y, b.s.z, b.t.x, b.t.y, b.t.z);
}

static void onb_duff(test_ctx *t)
{
    /* Duff et al. 2017: the branch-free basis must be exact to a few ulps everywhere, including
       z = -1 and z = -0.99999988 where Frisvad's original method loses all precision. */
    const float zs[] = { -1.0f, -0.99999988f, -0.99999994f, -0.9999999f, -0.999999f, -0.9999f, 1.0f, 0.99999988f, 0.0f };
    double worst = 0;
    int i, k, bad = 0;
    pt_rng rng;
    for (i = 0; i < (int)(sizeof zs / sizeof zs[0]); i++) {
        double r = sqrt(fmax(0.0, 1.0 - (double)zs[i] * zs[i]));
        for (k = 0; k < 8; k++) {
            double phi = 2 * TU_PI * k / 8.0 + 0.1;
            pt_vec3 n = pt_normalize(pt_v3((float)(r * cos(phi)), (float)(r * sin(phi)), zs[i]));
            if (zs[i] == -1.0f || zs[i] == 1.0f) n = pt_v3(0, 0, zs[i]);
            if (!check_onb(t, n, 1e-6, &worst)) bad++;
        }
    }
    {
        const pt_vec3 axes[] = { { 1, 0, 0 }, { -1, 0, 0 }, { 0, 1, 0 }, { 0, -1, 0 }, { 0, 0, 1 }, { 0, 0, -1 } };
        for (i = 0; i < 6; i++)
            if (!check_onb(t, axes[i], 1e-6, &worst)) bad++;
    }
    /* -0.99999988 exactly with x only, the case in the paper */
    if (!check_onb(t, pt_normalize(pt_v3(4.8828125e-4f, 0.0f, -0.99999988f)), 1e-6, &worst)) bad++;
    /* -0.0 z must behave like +0 */
    if (!check_onb(t, pt_v3(1.0f, 0.0f, -0.0f), 1e-6, &worst)) bad++;
    pt_rng_seed(&rng, 7, 7);
    for (i = 0; i < 100000 && bad < 5; i++) {
        pt_vec3 n = pt_normalize(dv_to(tu_rand_dir(&rng)));
        if (!check_onb(t, n, 1e-6, &worst)) bad++;
    }
    test_note(t, "100000 random + 82 special normals, worst error %.2g (limit 1e-6)", worst);
}

/* |a - ref| in units in the last place of ref (libm's value, taken as exact) */
static double ulps_off(double a, double ref)
{
    double r = fabs(ref), u = nextafter(r, HUGE_VAL) - r;
    return fabs(a - ref) / u;
}

/* pt_acos on [-1, 1] and pt_sincos on [-pi/4, 9 pi/4] (the ranges the quad lights' solid-angle
   sampler needs) against libm at 2^21 + 1 evenly spaced arguments each, and at the ends, the
   switches of acos's reduction (+-1/2) and the doubles nearest multiples of pi/2, where sin or cos
   is near 0: within 4 ulps (glibc's are within 1 of the exact value; ours measure 1). */
static void own_acos_sincos(test_ctx *t)
{
    const int n = 1 << 21;
    const double special[] = { -1.0, -0.5, -0.0, 0.0, 0.5, 1.0, 0x1.0000000000001p-1, 0x1.fffffffffffffp-2,
                               -0.7853981633974483, TU_PI / 2, TU_PI, 3 * TU_PI / 2, 2 * TU_PI,
                               7.0685834705770345 };
    double worst_a = 0.0, worst_s = 0.0, worst_c = 0.0, at_a = 0.0, at_s = 0.0, at_c = 0.0;
    int i;
    for (i = 0; i <= n + (int)(sizeof special / sizeof special[0]); i++) {
        double c, x, sn, cs, e;
        if (i <= n) {
            c = -1.0 + 2.0 * i / n;
            x = -0.7853981633974483 + (9.0 * TU_PI / 4.0 + 0.7853981633974483) * i / n;
        } else {
            c = x = special[i - n - 1];
            if (c < -1.0 || c > 1.0) c = 0.25;
            if (x < -0.7853981633974483) x = 0.25; /* (acos's specials below -pi/4) */
        }
        e = ulps_off(pt_acos(c), acos(c));
        if (e > worst_a) { worst_a = e; at_a = c; }
        pt_sincos(x, &sn, &cs);
        e = ulps_off(sn, sin(x));
        if (e > worst_s) { worst_s = e; at_s = x; }
        e = ulps_off(cs, cos(x));
        if (e > worst_c) { worst_c = e; at_c = x; }
    }
    CHECK(t, worst_a <= 4.0, "pt_acos is %.3g ulps off at %.17g", worst_a, at_a);
    CHECK(t, worst_s <= 4.0, "pt_sincos: sin is %.3g ulps off at %.17g", worst_s, at_s);
    CHECK(t, worst_c <= 4.0, "pt_sincos: cos is %.3g ulps off at %.17g", worst_c, at_c);
    { /* outside the ranges the public forms answer as libm (no assertion) */
        double sn, cs;
        CHECK(t, pt_acos(1.5) != pt_acos(1.5), "pt_acos(1.5) = %g, not NaN", pt_acos(1.5));
        pt_sincos(10.0, &sn, &cs);
        CHECK(t, sn == sin(10.0) && cs == cos(10.0), "pt_sincos(10) = (%.17g, %.17g), not libm's", sn, cs);
    }
    test_note(t, "worst: acos %.3g, sin %.3g, cos %.3g ulps (limit 4)", worst_a, worst_s, worst_c);
}

/* |a - ref| in units in the last place of ref rounded to float (ref: the exact value, from double) */
static double ulps_off_f(float a, double ref)
{
    float r = fabsf((float)ref), u = nextafterf(r, HUGE_VALF) - r;
    return fabs((double)a - ref) / (double)u;
}

/* pt_atan2f against double atan2 at 2^21 + 1 directions evenly spaced in angle over [-pi, pi]
   (scaled by 1, 1e-20, 1e20, 1e-35 and 1e35 in turn: the last two take libm's path), at y = 1,
   x = +-2^k for k = -149 .. 127 (tiny and huge ratios) and at the octants' edges: within 3 ulps
   (it measures 2.06, near pi/4, where the pi/6 reduction's rounding and the final one add up).
   On the pairs of +-0, +-inf, NaN, +-1, a denormal and +-FLT_MAX holding a zero, infinity or
   NaN: libm's atan2f to the bit (the signs of zero and pi included). */
static void own_atan2f(test_ctx *t)
{
    const int n = 1 << 21;
    const float scale[5] = { 1.0f, 1e-20f, 1e20f, 1e-35f, 1e35f };
    const float sp[11] = { 0.0f, -0.0f, HUGE_VALF, -HUGE_VALF, NAN, 1.0f, -1.0f, 1e-40f, FLT_MAX, -FLT_MAX, 0.5f };
    double worst = 0.0;
    float at_y = 0.0f, at_x = 0.0f;
    int i, j, bad = 0;
    for (i = 0; i <= n + 2 * 277 + 8; i++) {
        float y, x, r;
        double e;
        if (i <= n) {
            double a = -TU_PI + 2.0 * TU_PI * i / n;
            y = (float)sin(a) * scale[i % 5];
            x = (float)cos(a) * scale[i % 5];
        } else if (i <= n + 2 * 277) {
            int k = (i - n - 1) / 2 - 149;
            y = 1.0f;
            x = ldexpf((i - n) % 2 ? 1.0f : -1.0f, k);
        } else { /* the diagonals and the reduction's switch at tan(pi/12) */
            int k = i - n - 2 * 277 - 1;
            y = k & 1 ? -1.0f : 1.0f;
            x = k & 2 ? -1.0f : 1.0f;
            if (k & 4) y *= 0.26794919f;
        }
        r = pt_atan2f(y, x);
        e = ulps_off_f(r, atan2((double)y, (double)x));
        if (!(e <= worst)) { worst = e; at_y = y; at_x = x; }
    }
    CHECK(t, worst <= 3.0, "pt_atan2f is %.3g ulps off at (%.9g, %.9g)", worst, at_y, at_x);
    for (i = 0; i < 11; i++) {
        for (j = 0; j < 11; j++) {
            float y = sp[i], x = sp[j], r = pt_atan2f(y, x), l = atan2f(y, x);
            int special = i < 5 || j < 5;
            if (special && !(memcmp(&r, &l, sizeof r) == 0 || (r != r && l != l))) {
                if (bad++ < 4) CHECK(t, 0, "pt_atan2f(%g, %g) = %.9g, libm's %.9g", y, x, r, l);
            } else if (!special) {
                double e = ulps_off_f(r, atan2((double)y, (double)x));
                if (e > 3.0 && bad++ < 4) CHECK(t, 0, "pt_atan2f(%g, %g) = %.9g is %.3g ulps off", y, x, r, e);
            }
        }
    }
    test_note(t, "worst: %.3g ulps (limit 3) at (%.9g, %.9g)", worst, at_y, at_x);
}

const test_case test_math_cases[] = {
    TEST_CASE(vector_ops),
    TEST_CASE(transform_basics),
    TEST_CASE(transform_rotate),
    TEST_CASE(transform_normal),
    TEST_CASE(onb_duff),
    TEST_CASE(own_acos_sincos),
    TEST_CASE(own_atan2f),
    TEST_END
};
