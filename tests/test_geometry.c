/* test_geometry.c - section 3 of pdftrace.h: ray/shape intersection, self-intersection offsets,
   transforms of shapes and emitters, the box helper, meshes with normals, scene errors.

   References are double-precision intersections written here (Haines et al.'s perpendicular-distance
   discriminant for spheres, parametric coordinates for planar shapes). Statistical checks (the
   transformed emitters' PDF checks) belong to the chi-square suite's family (test_util.h:
   alpha = 0.01 over the whole suite, Sidak-corrected over TU_SUITE_COMPARISONS). */
#include "test_util.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double alpha_each(void) { return tu_suite_alpha(); }

static pt_ray mkray(dv3 o, dv3 d)
{
    pt_ray r;
    r.origin = dv_to(o);
    r.dir = dv_to(d);
    return r;
}

static double ulpf(double x)
{
    float f = (float)fabs(x);
    return (double)nextafterf(f, INFINITY) - (double)f;
}

/* Double-precision ray/sphere (on the float inputs): smallest t in (0, tmax) or -1. *near when the
   ray is within 1e-5 R of tangent or t is within rounding of 0 or tmax. */
static double ref_sphere(pt_ray r, pt_vec3 cf, double R, double tmax, int *near)
{
    dv3 o = dv_from(r.origin), d = dv_from(r.dir), c = dv_from(cf), l = dsub(c, o);
    double dd = ddot(d, d), b = ddot(l, d) / dd, disc, s, t0, t1;
    dv3 perp = dsub(l, dscale(d, b));
    double p2 = ddot(perp, perp);
    *near = fabs(sqrt(p2) - R) < 1e-5 * R;
    disc = R * R - p2;
    if (disc < 0) return -1;
    s = sqrt(disc / dd);
    t0 = b - s;
    t1 = b + s;
    if (fabs(t0) < 1e-5 * (fabs(b) + s) || fabs(t1) < 1e-5 * (fabs(b) + s)) *near = 1;
    if (t0 > 0 && t0 < tmax) return t0;
    if (t1 > 0 && t1 < tmax) return t1;
    return -1;
}

/* Planar shapes: kind TU_QUAD (p0 = q, p1 = u, p2 = v) or TU_TRIANGLE (a, b, c). */
static double ref_planar(pt_ray r, int kind, pt_vec3 p0, pt_vec3 p1, pt_vec3 p2, double tmax, int *near)
{
    tu_light L;
    dv3 o = dv_from(r.origin), d = dv_from(r.dir), N, e1, e2, rel, p;
    double t, a, b, nn, m, dl = dlen(d);
    memset(&L, 0, sizeof L);
    e1 = kind == TU_QUAD ? dv_from(p1) : dsub(dv_from(p1), dv_from(p0));
    e2 = kind == TU_QUAD ? dv_from(p2) : dsub(dv_from(p2), dv_from(p0));
    N = dcross(e1, e2);
    nn = ddot(N, N);
    *near = 0;
    if (fabs(ddot(d, N)) < 1e-6 * dl * sqrt(nn)) { *near = 1; return -1; }
    t = ddot(dsub(dv_from(p0), o), N) / ddot(d, N);
    p = dadd(o, dscale(d, t));
    rel = dsub(p, dv_from(p0));
    a = ddot(dcross(rel, e2), N) / nn;
    b = ddot(dcross(e1, rel), N) / nn;
    m = kind == TU_QUAD ? fmin(fmin(a, 1 - a), fmin(b, 1 - b)) : fmin(fmin(a, b), 1 - a - b);
    if (fabs(m) < 1e-5) *near = 1;
    if (fabs(t) * dl < 1e-5 * dlen(dsub(o, dv_from(p0))) || fabs(t - tmax) < 1e-5 * t) *near = 1;
    if (m < 0 || t <= 0 || t >= tmax) return -1;
    return t;
}

static void intersect_sphere(test_ctx *t)
{
    pt_ray r;
    float th = -1;
    int hit, near, i, bad = 0, bad_t = 0, checked = 0;
    double worst = 0;
    pt_rng rng;
    /* from outside, unit and non-unit direction (t in units of dir) */
    r = mkray(dv(0, 0, -5), dv(0, 0, 1));
    hit = pt_intersect_sphere(r, pt_v3(0, 0, 0), 1, INFINITY, &th);
    CHECK(t, hit == 1 && fabs(th - 4.0) < 1e-6, "outside: hit %d t %.9g, want 4", hit, th);
    r = mkray(dv(0, 0, -5), dv(0, 0, 2));
    hit = pt_intersect_sphere(r, pt_v3(0, 0, 0), 1, INFINITY, &th);
    CHECK(t, hit == 1 && fabs(th - 2.0) < 1e-6, "non-unit dir: hit %d t %.9g, want 2", hit, th);
    /* from inside: the far side */
    r = mkray(dv(0.2, 0.1, 0), dv(1, 0, 0));
    hit = pt_intersect_sphere(r, pt_v3(0, 0, 0), 1, INFINITY, &th);
    CHECK(t, hit == 1 && fabs(th - (sqrt(1 - 0.01) - 0.2)) < 1e-6, "inside: hit %d t %.9g, want %.9g", hit, th,
          sqrt(0.99) - 0.2);
    /* behind the origin, beside it, beyond tmax */
    r = mkray(dv(0, 0, 5), dv(0, 0, 1));
    CHECK(t, pt_intersect_sphere(r, pt_v3(0, 0, 0), 1, INFINITY, &th) == 0, "sphere behind the ray was hit");
    r = mkray(dv(0, 1.0001, -5), dv(0, 0, 1));
    CHECK(t, pt_intersect_sphere(r, pt_v3(0, 0, 0), 1, INFINITY, &th) == 0, "ray passing 1e-4 outside was hit");
    r = mkray(dv(0, 0.9999, -5), dv(0, 0, 1));
    CHECK(t, pt_intersect_sphere(r, pt_v3(0, 0, 0), 1, INFINITY, &th) == 1, "ray passing 1e-4 inside the rim missed");
    r = mkray(dv(0, 0, -5), dv(0, 0, 1));
    CHECK(t, pt_intersect_sphere(r, pt_v3(0, 0, 0), 1, 3.9f, &th) == 0, "hit beyond tmax reported");
    r = mkray(dv(0, 0, 0), dv(0, 0, 1));
    CHECK(t, pt_intersect_sphere(r, pt_v3(0, 0, 0), 1, 0.5f, &th) == 0, "inside: exit beyond tmax reported");
    /* random rays against the double-precision reference */
    pt_rng_seed(&rng, 1001, 1);
    for (i = 0; i < 20000; i++) {
        dv3 c = dscale(dv(tu_rand(&rng) - 0.5, tu_rand(&rng) - 0.5, tu_rand(&rng) - 0.5), 20.0);
        double R = 0.01 + 3 * tu_rand(&rng), ref, tmax = tu_rand(&rng) < 0.2 ? 5 + 20 * tu_rand(&rng) : INFINITY;
        dv3 o = dadd(c, dscale(tu_rand_dir(&rng), R * (tu_rand(&rng) < 0.2 ? tu_rand(&rng) : 1 + 10 * tu_rand(&rng))));
        dv3 target = dadd(c, dscale(tu_rand_dir(&rng), R * 1.3 * tu_rand(&rng)));
        dv3 d = dscale(dnorm(dsub(target, o)), 0.1 + 5 * tu_rand(&rng));
        float tf = -1;
        r = mkray(o, d);
        ref = ref_sphere(r, dv_to(c), (float)R, tmax, &near);
        hit = pt_intersect_sphere(r, dv_to(c), (float)R, (float)tmax, &tf);
        if (near) continue;
        checked++;
        if (hit != (ref > 0)) { bad++; continue; }
        if (hit) {
            double err = fabs(tf - ref) / fmax(ref, R / dlen(d));
            worst = fmax(worst, err);
            if (err > 1e-5) bad_t++;
        }
    }
    CHECK(t, bad == 0, "%d of %d random rays disagree with the reference on hit/miss", bad, checked);
    CHECK(t, bad_t == 0, "%d of %d random hits have t off by more than 1e-5 relative (worst %.3g)", bad_t, checked, worst);
    test_note(t, "%d random rays, worst rel t error %.2g", checked, worst);
}

static void intersect_sphere_far_tiny(test_ctx *t)
{
    /* R = 1e-2 at distance 1e4: b^2 - c cancels completely in float, so the naive discriminant misses
       or is off by ~R; Haines et al.'s form stays within a few ulps of t. */
    pt_vec3 c = pt_v3(0, 0, 1e4f);
    float R = 1e-2f;
    pt_rng rng;
    int i, miss = 0, false_hit = 0, bad_t = 0, hit;
    double worst = 0;
    pt_rng_seed(&rng, 1002, 1);
    for (i = 0; i < 4000; i++) {
        double ang = 2 * TU_PI * tu_rand(&rng), rad = tu_rand(&rng), ref;
        int inside = i % 2 == 0, near, unit = (i / 2) % 2 == 0;
        double off = inside ? 0.9 * rad * R : R * (1.1 + rad);
        dv3 target = dadd(dv_from(c), dv(off * cos(ang), off * sin(ang), 0));
        dv3 o = dv(0, 0, 0), d = unit ? dnorm(target) : target;
        pt_ray r = mkray(o, d);
        float tf = -1;
        ref = ref_sphere(r, c, R, INFINITY, &near);
        hit = pt_intersect_sphere(r, c, R, INFINITY, &tf);
        if (inside) {
            if (!hit) { miss++; continue; }
            if (ref > 0) {
                double err = fabs(tf - ref);
                worst = fmax(worst, err / ulpf(ref));
                if (err > 8 * ulpf(ref)) bad_t++;
            }
        } else if (hit) {
            false_hit++;
        }
    }
    CHECK(t, miss == 0, "%d of 2000 rays through the inner 90%% of a tiny far sphere missed", miss);
    CHECK(t, false_hit == 0, "%d of 2000 rays passing outside a tiny far sphere hit it", false_hit);
    CHECK(t, bad_t == 0, "%d hits with t more than 8 ulps from the reference (worst %.1f ulps)", bad_t, worst);
    test_note(t, "worst t error %.1f ulps", worst);
}

static void intersect_planar(test_ctx *t)
{
    pt_ray r;
    float th = -1;
    int hit, near, i, k, bad = 0, bad_t = 0, checked = 0;
    double worst = 0;
    pt_rng rng;
    /* quad: centre hit from both sides (intersection is two-sided), miss beside it, parallel ray */
    r = mkray(dv(0.5, 2, 0.5), dv(0, -1, 0));
    hit = pt_intersect_quad(r, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 0, 1), INFINITY, &th);
    CHECK(t, hit == 1 && fabs(th - 2) < 1e-6, "quad from the back: hit %d t %g", hit, th);
    r = mkray(dv(0.5, -3, 0.5), dv(0, 2, 0));
    hit = pt_intersect_quad(r, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 0, 1), INFINITY, &th);
    CHECK(t, hit == 1 && fabs(th - 1.5) < 1e-6, "quad from the front, dir length 2: hit %d t %g", hit, th);
    r = mkray(dv(1.01, 2, 0.5), dv(0, -1, 0));
    CHECK(t, pt_intersect_quad(r, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 0, 1), INFINITY, &th) == 0, "quad: miss beside it was a hit");
    r = mkray(dv(-1, 0, 0.5), dv(1, 0, 0));
    th = -1;
    hit = pt_intersect_quad(r, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 0, 1), INFINITY, &th);
    CHECK(t, hit == 0 || isfinite(th), "quad: ray in its plane gave a non-finite t");
    r = mkray(dv(0.5, 2, 0.5), dv(0, -1, 0));
    CHECK(t, pt_intersect_quad(r, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 0, 1), 1.5f, &th) == 0, "quad hit beyond tmax reported");
    /* triangle */
    r = mkray(dv(0.25, 0.25, 3), dv(0, 0, -1));
    hit = pt_intersect_triangle(r, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 1, 0), INFINITY, &th);
    CHECK(t, hit == 1 && fabs(th - 3) < 1e-6, "triangle: hit %d t %g", hit, th);
    r = mkray(dv(0.6, 0.6, 3), dv(0, 0, -1));
    CHECK(t, pt_intersect_triangle(r, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 1, 0), INFINITY, &th) == 0,
          "triangle: point beyond the hypotenuse was a hit");
    r = mkray(dv(0.25, 0.25, -3), dv(0, 0, 1));
    CHECK(t, pt_intersect_triangle(r, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 1, 0), INFINITY, &th) == 1,
          "triangle: hit from the back missed");
    /* random rays against the reference */
    pt_rng_seed(&rng, 1003, 1);
    for (k = 0; k < 2; k++) {
        for (i = 0; i < 20000; i++) {
            dv3 p0 = dscale(dv(tu_rand(&rng) - 0.5, tu_rand(&rng) - 0.5, tu_rand(&rng) - 0.5), 10);
            dv3 p1 = dscale(tu_rand_dir(&rng), 0.2 + 3 * tu_rand(&rng)), p2 = dscale(tu_rand_dir(&rng), 0.2 + 3 * tu_rand(&rng));
            dv3 o = dadd(p0, dscale(tu_rand_dir(&rng), 1 + 10 * tu_rand(&rng)));
            dv3 target = dadd(p0, dadd(dscale(p1, 1.4 * tu_rand(&rng) - 0.2), dscale(p2, 1.4 * tu_rand(&rng) - 0.2)));
            dv3 d = dscale(dnorm(dsub(target, o)), 0.1 + 5 * tu_rand(&rng));
            double tmax = tu_rand(&rng) < 0.2 ? 10 * tu_rand(&rng) : INFINITY, ref;
            float tf = -1;
            pt_vec3 f0 = dv_to(p0), f1, f2;
            if (k == 1) { p1 = dadd(p0, p1); p2 = dadd(p0, p2); }
            f1 = dv_to(p1);
            f2 = dv_to(p2);
            r = mkray(o, d);
            ref = ref_planar(r, k == 0 ? TU_QUAD : TU_TRIANGLE, f0, f1, f2, tmax, &near);
            hit = k == 0 ? pt_intersect_quad(r, f0, f1, f2, (float)tmax, &tf) : pt_intersect_triangle(r, f0, f1, f2, (float)tmax, &tf);
            if (near) continue;
            checked++;
            if (hit != (ref > 0)) { bad++; continue; }
            if (hit) {
                double err = fabs(tf - ref) / ref;
                worst = fmax(worst, err);
                /* a grazing ray's t is ill-conditioned: the float plane distance (rounding ~ eps times
                   the coordinates involved) divided by the cosine */
                dv3 e1 = k == 0 ? dv_from(f1) : dsub(dv_from(f1), dv_from(f0));
                dv3 e2 = k == 0 ? dv_from(f2) : dsub(dv_from(f2), dv_from(f0));
                double cosv = fabs(ddot(dnorm(dv_from(r.dir)), dnorm(dcross(e1, e2))));
                double scale = dlen(dv_from(r.origin)) + dlen(p0) + dlen(e1) + dlen(e2);
                double tol = 1e-5 + 8.0 * FLT_EPSILON * scale / (cosv * ref * dlen(dv_from(r.dir)));
                if (err > tol) bad_t++;
            }
        }
    }
    CHECK(t, bad == 0, "%d of %d random quad/triangle rays disagree with the reference on hit/miss", bad, checked);
    CHECK(t, bad_t == 0, "%d random hits with t off by more than 1e-5 relative (worst %.3g)", bad_t, worst);
    test_note(t, "%d random rays, worst rel t error %.2g", checked, worst);
}

static void triangle_fan_watertight(test_ctx *t)
{
    /* Woop, Benthin & Wald 2013: rays through the shared edges and the shared vertex of a closed fan
       never miss every triangle. Fans: flat, raised centre, at a large offset; directly with
       pt_intersect_triangle and through a mesh in a scene (BVH). */
    enum { K = 7 };
    pt_rng rng;
    int f, i, j, misses = 0, scene_misses = 0, total = 0, rc;
    pt_rng_seed(&rng, 1004, 1);
    for (f = 0; f < 3; f++) {
        double scale = f == 2 ? 1000.0 : 1.0;
        dv3 off = f == 2 ? dv(12345.0, -6789.0, 4321.0) : dv(0, 0, 0);
        float pos[3 * (K + 1)];
        uint32_t idx[3 * K];
        pt_vec3 v[K + 1];
        pt_scene *s = pt_scene_create();
        pt_mesh_desc md;
        int m;
        if (!CHECK(t, s != NULL, "scene")) return;
        v[0] = dv_to(dadd(off, dv(0.013 * scale, -0.007 * scale, f == 1 ? 0.4 * scale : 0)));
        for (i = 0; i < K; i++) {
            double a = 2 * TU_PI * (i + 0.3 * tu_rand(&rng)) / K, rr = scale * (0.8 + 0.4 * tu_rand(&rng));
            v[i + 1] = dv_to(dadd(off, dv(rr * cos(a), rr * sin(a), 0.05 * scale * tu_rand(&rng))));
        }
        for (i = 0; i <= K; i++) { pos[3 * i] = v[i].x; pos[3 * i + 1] = v[i].y; pos[3 * i + 2] = v[i].z; }
        for (i = 0; i < K; i++) { idx[3 * i] = 0; idx[3 * i + 1] = (uint32_t)(i + 1); idx[3 * i + 2] = (uint32_t)((i + 1) % K + 1); }
        m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
        memset(&md, 0, sizeof md);
        md.positions = pos;
        md.vertex_count = K + 1;
        md.indices = idx;
        md.triangle_count = K;
        md.material = m;
        rc = pt_scene_add_mesh(s, &md);
        rc = rc >= 0 ? pt_scene_commit(s) : rc;
        if (!CHECK(t, rc == PT_OK, "fan mesh: %d %s", rc, pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        for (j = 0; j < 6000; j++) {
            dv3 target, o;
            pt_ray r;
            pt_hit h;
            int any = 0;
            if (j % 10 == 0) {
                target = dv_from(v[0]); /* the shared vertex */
            } else {
                int e = (int)(tu_rand(&rng) * K);
                double lam = tu_rand(&rng);
                target = dadd(dv_from(v[0]), dscale(dsub(dv_from(v[e + 1]), dv_from(v[0])), lam)); /* a shared edge */
            }
            o = dadd(target, dscale(dv(tu_rand(&rng) - 0.5, tu_rand(&rng) - 0.5, 0.5 + tu_rand(&rng)), 3 * scale));
            if (j % 3 == 0) o = dadd(target, dscale(dv(tu_rand(&rng) - 0.5, tu_rand(&rng) - 0.5, -0.5 - tu_rand(&rng)), 3 * scale));
            r = mkray(o, dsub(target, o));
            for (i = 0; i < K && !any; i++) {
                float th;
                any = pt_intersect_triangle(r, v[0], v[i + 1], v[(i + 1) % K + 1], INFINITY, &th);
            }
            total++;
            if (!any) misses++;
            if (pt_scene_intersect(s, r, INFINITY, &h) != 1) scene_misses++;
        }
        pt_scene_destroy(s);
    }
    CHECK(t, misses == 0, "%d of %d rays through shared edges/vertices of a fan missed every triangle", misses, total);
    CHECK(t, scene_misses == 0, "%d of %d such rays missed the fan mesh in a scene", scene_misses, total);
    test_note(t, "%d rays through shared edges and vertices", total);
}

static void sliver_triangle_distance(test_ctx *t)
{
    /* A huge sliver in the plane z = 1 (vertices ~5.5e6 from the origin, 1.5 wide where the ray
       crosses it): float's cancellation gave t = 4.980 where the plane is at 5.099, a point
       outside the triangle's flat bounding box, so the shadow ray pt_scene_occluded(t * 1.0001)
       culled the box and disagreed with the closest hit. All queries must give the plane's t. */
    const pt_vec3 a = { 2568343.0f, 4248663.0f, 1.0f }, b = { -2323722.5f, 6632148.0f, 1.0f };
    const pt_vec3 c = { 0.834053755f, 5499998.5f, 1.0f };
    pt_ray r;
    pt_scene *s;
    pt_hit h, hb;
    double want;
    float tt = 0.0f;
    int m, rc, hi, bf, occ_after, occ_before, single;
    r.origin = pt_v3(0.0f, 5500002.0f, 0.0f);
    r.dir = pt_v3(0.0f, -0.9806f, 0.1961f);
    want = 1.0 / (double)r.dir.z; /* the plane z = 1 from z = 0 */
    single = pt_intersect_triangle(r, a, b, c, INFINITY, &tt);
    CHECK(t, single == 1 && fabs(tt - want) <= 1e-6 * want, "pt_intersect_triangle: %d, t %.9g, want %.9g", single,
          (double)tt, want);
    s = pt_scene_create();
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    rc = pt_scene_add_triangle(s, a, b, c, m);
    if (rc >= 0) rc = pt_scene_set_backend(s, PT_BACKEND_BUILTIN);
    if (rc >= 0) rc = pt_scene_commit(s);
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    memset(&h, 0, sizeof h);
    memset(&hb, 0, sizeof hb);
    hi = pt_scene_intersect(s, r, INFINITY, &h);
    bf = pt_scene_intersect_brute_force(s, r, INFINITY, &hb);
    occ_after = pt_scene_occluded(s, r, (float)(h.t * 1.0001));
    occ_before = pt_scene_occluded(s, r, (float)(h.t * 0.9999));
    CHECK(t, hi == 1 && fabs(h.t - want) <= 1e-6 * want, "pt_scene_intersect: %d, t %.9g, want %.9g", hi, h.t, want);
    CHECK(t, bf == 1 && hb.t == h.t, "brute force: %d, t %.9g (intersect %.9g)", bf, hb.t, h.t);
    CHECK(t, occ_after == 1 && occ_before == 0, "pt_scene_occluded at t * 1.0001: %d (want 1), at t * 0.9999: %d (want 0)",
          occ_after, occ_before);
    CHECK(t, hi != 1 || (fabs(h.point.x) < 1.0f && fabs(h.point.z - 1.0f) < 1e-6f),
          "hit point (%.9g, %.9g, %.9g): want (0, 5499997, 1)", h.point.x, h.point.y, h.point.z);
    test_note(t, "t %.9g, want %.9g", h.t, want);
    pt_scene_destroy(s);
}

static void grazing_edge_hit_on_plane(test_ctx *t)
{
    /* A ray 0.3 degrees from a triangle's plane, crossing the mesh 1e-6 wide next to one of its
       edges (a case of the stress row `spawn x1e-6`): the float edge functions call it inside,
       in double U is -1.8 % of det (just outside). The hit point must still lie on the
       triangle's plane: a bare clamp of the double barycentrics put it 1.2e-8 (8 % of the
       triangle) off it, and a ray spawned from there into the mesh hit the same triangle. */
    const pt_vec3 a = { 6.045085e-07f, 1.50000005e-07f, 4.54508495e-07f };
    const pt_vec3 b = { 5.46890249e-07f, 2.51023209e-07f, 3.80311008e-07f };
    const pt_vec3 c = { 4.93892628e-07f, 2.44095474e-07f, 5.12662723e-07f };
    double e1[3], e2[3], n[3], nl, dist, size;
    pt_ray r;
    pt_scene *s;
    pt_hit h;
    int m, rc, hi;
    r.origin = pt_v3(-0.00358455256f, 0.00263415207f, 0.00281427335f);
    r.dir = pt_v3(0.681078494f, -0.500380754f, -0.534556925f);
    s = pt_scene_create();
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    rc = pt_scene_add_triangle(s, a, b, c, m);
    if (rc >= 0) rc = pt_scene_commit(s);
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    memset(&h, 0, sizeof h);
    hi = pt_scene_intersect(s, r, INFINITY, &h);
    e1[0] = (double)b.x - a.x; e1[1] = (double)b.y - a.y; e1[2] = (double)b.z - a.z;
    e2[0] = (double)c.x - a.x; e2[1] = (double)c.y - a.y; e2[2] = (double)c.z - a.z;
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    size = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    dist = fabs(n[0] * ((double)h.point.x - a.x) + n[1] * ((double)h.point.y - a.y) + n[2] * ((double)h.point.z - a.z)) / nl;
    /* a hit or a miss is a matter of rounding here; a hit's point must be on the plane to a few ulps */
    CHECK(t, hi != 1 || dist <= 1e-5 * size, "hit point (%.9g, %.9g, %.9g) is %.3g off the plane (triangle %.3g wide)",
          h.point.x, h.point.y, h.point.z, dist, size);
    test_note(t, "hit %d, point %.3g off the plane", hi, dist);
    pt_scene_destroy(s);
}

static void offset_ray_origin_scales(test_ctx *t)
{
    /* Waechter & Binder (Ray Tracing Gems ch. 6): a ray leaving a hit point from the offset origin
       never hits the surface it left, at every scale from 1e-3 to 1e5 (and at large offsets from
       the origin); rays refracted into a sphere reach its far side; the offset stays small
       (<= 2^-10 max(|p|_inf, 1/32), ~30x the method's own bound); a surface 1e-3 * scale away is
       not skipped. */
    const double scales[] = { 1e-3, 1e-1, 1, 1e2, 1e4, 1e5 };
    pt_rng rng;
    int si, i, self = 0, far_bad = 0, big = 0, skipped = 0, total = 0, rc, n_far = 0, n_near = 0, n_out = 0;
    pt_rng_seed(&rng, 1005, 1);
    for (si = 0; si < 6; si++) {
        double S = scales[si];
        dv3 C = dscale(dv(0.7, -0.3, 0.5), 3 * S);
        pt_scene *s = pt_scene_create();
        int m, sph, quad, tri, near_q;
        double gap;
        if (!CHECK(t, s != NULL, "scene")) return;
        m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
        sph = pt_scene_add_sphere(s, dv_to(C), (float)S, m);
        quad = pt_scene_add_quad(s, dv_to(dadd(C, dscale(dv(3, -1, -1), S))), dv_to(dscale(dv(0.3, 2, 0), S)),
                                 dv_to(dscale(dv(0, 0.2, 2), S)), m);
        tri = pt_scene_add_triangle(s, dv_to(dadd(C, dscale(dv(-3, -1, -1), S))), dv_to(dadd(C, dscale(dv(-3.2, 1, -1), S))),
                                    dv_to(dadd(C, dscale(dv(-2.9, 0, 1.5), S))), m);
        /* two parallel quads `gap` apart, far from everything else: 1e-3 * S, or 4x the nominal offset
           of Waechter & Binder's method (256 ulps of the coordinate, 1/65536 near the origin) where
           that is larger -- anything closer is unreachable by design */
        gap = fmax(1e-3 * S, 4.0 * fmax(1.0 / 65536, 256.0 * ulpf(fabs(C.y) + 6 * S)));
        near_q = pt_scene_add_quad(s, dv_to(dadd(C, dscale(dv(-1, 6, -1), S))), dv_to(dscale(dv(2, 0, 0), S)),
                                   dv_to(dscale(dv(0, 0, 2), S)), m);
        rc = pt_scene_add_quad(s, dv_to(dadd(C, dv(-S, 6 * S + gap, -S))), dv_to(dscale(dv(2, 0, 0), S)),
                               dv_to(dscale(dv(0, 0, 2), S)), m);
        rc = rc >= 0 ? pt_scene_commit(s) : rc;
        if (!CHECK(t, rc == PT_OK && sph >= 0 && quad >= 0 && tri >= 0 && near_q >= 0, "scene at scale %g: %s", S,
                   pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        for (i = 0; i < 1500; i++) {
            int shape = i % 4;
            dv3 target, o, d, n, w;
            pt_ray r, r2;
            pt_hit h, h2;
            pt_vec3 p, po;
            double lim;
            if (shape == 0) target = dadd(C, dscale(tu_rand_dir(&rng), S));
            else if (shape == 1) target = dadd(C, dscale(dv(3 + 0.3 * tu_rand(&rng), -1 + 2 * tu_rand(&rng), -1 + 2 * tu_rand(&rng)), S));
            else if (shape == 2) target = dadd(C, dscale(dv(-3.05, -0.2 + 0.4 * tu_rand(&rng), -0.5 + tu_rand(&rng)), S));
            else target = dadd(C, dscale(dv(-0.8 + 1.6 * tu_rand(&rng), 6, -0.8 + 1.6 * tu_rand(&rng)), S));
            o = shape == 3 ? dadd(target, dscale(dv(tu_rand(&rng) - 0.5, -2, tu_rand(&rng) - 0.5), S))
                           : dadd(target, dscale(tu_rand_dir(&rng), 2.5 * S));
            if (shape == 0 && dlen(dsub(o, C)) < 1.2 * S) o = dadd(C, dscale(dnorm(dsub(o, C)), 3 * S));
            d = dnorm(dsub(target, o));
            r = mkray(o, d);
            if (pt_scene_intersect(s, r, INFINITY, &h) != 1) continue;
            total++;
            p = h.point;
            n = dv_from(h.geometric_normal);
            if (ddot(n, d) > 0) n = dscale(n, -1); /* the side the ray came from */
            /* reflected: random direction in the hemisphere of n */
            do { w = tu_rand_dir(&rng); } while (ddot(w, n) <= 1e-3);
            if (shape == 0 && i % 8 == 0) w = dscale(w, -1); /* refracted into the sphere */
            if (shape == 3) w = dscale(w, -1);                /* through the lower quad, towards the upper */
            po = pt_offset_ray_origin(p, h.geometric_normal, dv_to(w));
            lim = ldexp(fmax(fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z))), 1.0 / 32), -10);
            if (fabs(po.x - p.x) > lim || fabs(po.y - p.y) > lim || fabs(po.z - p.z) > lim) big++;
            r2.origin = po;
            r2.dir = dv_to(w);
            if (shape == 3) {
                /* towards the other quad, 1e-3 * S above: it must be hit, not skipped */
                dv3 up = dv(0, 1, 0);
                if (h.primitive == (uint32_t)near_q && ddot(w, up) > 0.2) {
                    int got;
                    n_near++;
                    got = pt_scene_intersect(s, r2, INFINITY, &h2);
                    if (got != 1 || fabs(h2.point.y - (C.y + 6 * S + gap)) > 0.1 * gap) skipped++;
                }
                continue;
            }
            {
                /* for the sphere, the side w leaves to decides: outwards must miss it, inwards must
                   reach the far side (a chord of length 2 S |cos| from p); planar shapes: never hit */
                int got = pt_scene_intersect(s, r2, INFINITY, &h2);
                if (h.primitive == (uint32_t)sph) {
                    dv3 outward = dnorm(dsub(dv_from(p), C));
                    double cw = ddot(dnorm(w), outward);
                    if (cw > 0) {
                        n_out++;
                        if (got == 1 && h2.primitive == h.primitive) self++;
                    } else {
                        /* the far side as seen from the offset origin, in double precision */
                        int nr;
                        double chord = 2 * S * fabs(cw), texp = ref_sphere(r2, dv_to(C), (float)S, INFINITY, &nr);
                        n_far++;
                        if (chord > 1e-3 * S &&
                            (got != 1 || h2.primitive != h.primitive || texp < 0 || fabs(h2.t - texp) > 1e-4 * S / dlen(w) + 1e-5 * texp))
                            far_bad++;
                    }
                } else if (got == 1 && h2.primitive == h.primitive) {
                    self++;
                }
            }
        }
        pt_scene_destroy(s);
    }
    CHECK(t, self == 0, "%d of %d rays from offset origins hit the surface they left", self, total);
    CHECK(t, far_bad == 0, "%d refracted rays did not reach the sphere's far side at the right distance", far_bad);
    CHECK(t, big == 0, "%d offsets larger than 2^-10 max(|p|, 1/32)", big);
    CHECK(t, skipped == 0, "%d rays skipped a surface just beyond the offset bound", skipped);
    test_note(t, "%d hit points at scales 1e-3..1e5: %d leaving convex/planar surfaces, %d into the sphere, %d towards a surface just beyond the offset",
              total, total - n_far - n_near, n_far, n_near);
    (void)n_out;
}

/* ------------------------------------------------------------------------------------------ */
/* transforms                                                                                  */

static dv3 rot(dv3 k, double deg, dv3 v)
{
    double a = deg * TU_PI / 180.0, c = cos(a), s = sin(a);
    k = dnorm(k);
    return dadd(dadd(dscale(v, c), dscale(dcross(k, v), s)), dscale(k, ddot(k, v) * (1.0 - c)));
}

typedef struct light_ref2 { tu_light L; dv3 o; } light_ref2;
static double ref_light2(const void *ctx, dv3 w, int *near)
{
    const light_ref2 *c = (const light_ref2 *)ctx;
    return tu_light_density(&c->L, c->o, w, near);
}

static void transformed_emitters(test_ctx *t)
{
    /* An emitter added under rotate + translate (quad) or rotate + uniform scale + translate (sphere)
       is sampled as the world-space shape: the light PDF matches the closed form of the shape
       transformed here in double precision (Rodrigues), integrates to 1, its 1/pdf averages to the
       world solid angle, and every sampled direction hits the emitter. */
    const dv3 axis = dnorm(dv(1, 1, 0.3)), T = dv(1, 2, -3);
    const double deg = 37.0;
    pt_transform xf = pt_transform_mul(pt_transform_translate(dv_to(T)), pt_transform_rotate(dv_to(axis), (float)deg));
    pt_transform xs = pt_transform_mul(pt_transform_translate(pt_v3(-2, 1, 0)),
                                       pt_transform_mul(pt_transform_rotate(dv_to(axis), 50.0f), pt_transform_scale(pt_v3(0.5f, 0.5f, 0.5f))));
    int k;
    for (k = 0; k < 2; k++) {
        pt_scene *s = pt_scene_create();
        pt_scene_info info;
        light_ref2 lr;
        int m, id, rc, i, misses = 0;
        tu_pdf_check c;
        tu_pdf_result res;
        tu_domain dom;
        tu_planar_ctx pc;
        pt_pdf p;
        pt_rng rng;
        if (!CHECK(t, s != NULL, "scene")) return;
        m = pt_scene_add_emitter(s, pt_v3(2, 2, 2), 0);
        memset(&lr, 0, sizeof lr);
        if (k == 0) {
            dv3 q = dv(-0.5, 0, -0.5), u = dv(1, 0, 0), v = dv(0, 0, 0.8); /* local normal u x v = -y */
            pt_scene_set_transform(s, &xf);
            id = pt_scene_add_quad(s, dv_to(q), dv_to(u), dv_to(v), m);
            lr.L.kind = TU_QUAD;
            lr.L.p0 = dadd(rot(axis, deg, q), T);
            lr.L.p1 = rot(axis, deg, u);
            lr.L.p2 = rot(axis, deg, v);
            /* a point 2 below the centre on the emitting side */
            lr.o = dsub(dadd(lr.L.p0, dscale(dadd(lr.L.p1, lr.L.p2), 0.5)), dscale(rot(axis, deg, dv(0, 1, 0)), 2.0));
            lr.o = dadd(lr.o, dv(0.3, 0.1, -0.2));
        } else {
            pt_scene_set_transform(s, &xs);
            id = pt_scene_add_sphere(s, pt_v3(0.4f, 0, 0), 1.0f, m);
            lr.L.kind = TU_SPHERE;
            lr.L.p0 = dadd(dv(-2, 1, 0), dscale(rot(axis, 50.0, dv(0.4, 0, 0)), 0.5));
            lr.L.radius = 0.5;
            lr.o = dv(1, 0.5, 2);
        }
        pt_scene_set_transform(s, NULL);
        rc = id >= 0 ? pt_scene_commit(s) : id;
        if (!CHECK(t, rc == PT_OK, "%s: %d %s", k == 0 ? "quad" : "sphere", rc, pt_scene_error_message(s))) {
            pt_scene_destroy(s);
            return;
        }
        pt_scene_get_info(s, &info);
        CHECK(t, (info.features & PT_FEATURE_TRANSFORMS) != 0, "PT_FEATURE_TRANSFORMS not set");
        CHECK(t, info.emitter_count == 1, "emitter_count %u", (unsigned)info.emitter_count);
        lr.o = dv_from(dv_to(lr.o));
        p = pt_pdf_scene_lights(s, dv_to(lr.o));
        c.label = NULL;
        memset(&c, 0, sizeof c);
        c.label = k == 0 ? "quad emitter under rotate+translate" : "sphere emitter under rotate+scale+translate";
        c.pdf = &p;
        tu_light_cone(&lr.L, lr.o, &c.axis, &c.omc);
        if (k == 0) { tu_planar_domain(&dom, &pc, &lr.L, lr.o); c.domain = &dom; }
        c.expected_mass = 1.0;
        c.support = tu_light_solid_angle(&lr.L, lr.o);
        c.ref = ref_light2;
        c.ref_ctx = &lr;
        c.n_samples = 50000;
        c.n_mass = 20000;
        c.ns = 16;
        c.nphi = 16;
        c.seed = 1100 + k;
        c.alpha = alpha_each();
        TU_CHECK_PDF(t, &c, &res);
        /* the sampled directions hit the emitter */
        pt_rng_seed(&rng, 1110 + k, 1);
        for (i = 0; i < 2000; i++) {
            pt_vec3 d;
            float pv;
            pt_ray r;
            pt_hit h;
            if (!pt_pdf_sample(&p, &rng, &d, &pv)) { misses++; continue; }
            r.origin = dv_to(lr.o);
            r.dir = d;
            if (pt_scene_intersect(s, r, INFINITY, &h) != 1 || h.primitive != (uint32_t)id) misses++;
        }
        CHECK(t, misses == 0, "%s: %d of 2000 light samples do not hit the emitter", c.label, misses);
        test_note(t, "%s max |z| %.2f, chi2 p %.3f (alpha %.2g each: 0.01 Sidak over %d, the chi-square suite)", k == 0 ? "quad" : "sphere",
                  res.max_abs_z, res.chi2_p, alpha_each(), TU_SUITE_COMPARISONS);
        pt_scene_destroy(s);
    }
}

static void box_helper(test_ctx *t)
{
    /* Six outward-facing quads: hits agree with a double-precision slab test, the geometric normal
       is the outward face normal (front_face from outside, not from inside), under a rotation too. */
    pt_scene *s = pt_scene_create();
    pt_scene_info info;
    dv3 lo = dv(-1, 0.5, 2), hi = dv(2, 1.5, 4), center = dscale(dadd(lo, hi), 0.5);
    int m, id, id2, rc, i, k, bad = 0, checked = 0;
    pt_rng rng;
    pt_transform ry = pt_transform_mul(pt_transform_translate(pt_v3(100, 0, 0)), pt_transform_rotate_y(30.0f));
    pt_hit h;
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    id = pt_scene_add_box(s, dv_to(lo), dv_to(hi), m);
    pt_scene_set_transform(s, &ry);
    id2 = pt_scene_add_box(s, dv_to(lo), dv_to(hi), m);
    pt_scene_set_transform(s, NULL);
    rc = id >= 0 && id2 >= 0 ? pt_scene_commit(s) : -1;
    if (!CHECK(t, rc == PT_OK, "box scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    pt_scene_get_info(s, &info);
    CHECK(t, info.quad_count == 12 && info.primitive_count == 12, "two boxes gave %u quads, %u primitives",
          (unsigned)info.quad_count, (unsigned)info.primitive_count);
    CHECK(t, id2 == id + 6, "second box starts at primitive %d, first at %d", id2, id);
    {   /* from outside along -x: the x = hi face, normal +x, front face */
        pt_ray r = mkray(dv(5, 1, 3), dv(-1, 0, 0));
        int got = pt_scene_intersect(s, r, INFINITY, &h);
        CHECK(t, got == 1 && fabs(h.t - 3) < 1e-5 && fabs(h.geometric_normal.x - 1) < 1e-6 && h.front_face == 1,
              "outside hit: got %d t %g n (%g %g %g) front %d", got, h.t, h.geometric_normal.x, h.geometric_normal.y,
              h.geometric_normal.z, h.front_face);
        r = mkray(center, dv(0, 1, 0));
        got = pt_scene_intersect(s, r, INFINITY, &h);
        CHECK(t, got == 1 && fabs(h.t - 0.5) < 1e-5 && fabs(h.geometric_normal.y - 1) < 1e-6 && h.front_face == 0,
              "inside hit: got %d t %g n (%g %g %g) front %d", got, h.t, h.geometric_normal.x, h.geometric_normal.y,
              h.geometric_normal.z, h.front_face);
    }
    pt_rng_seed(&rng, 1200, 1);
    for (k = 0; k < 2; k++) {
        for (i = 0; i < 5000; i++) {
            /* local ray, slab test in local space; the world ray is the local one under the transform */
            dv3 o = dadd(center, dscale(tu_rand_dir(&rng), 1 + 4 * tu_rand(&rng)));
            dv3 target = dadd(center, dv(2 * (tu_rand(&rng) - 0.5) * 2, 2 * (tu_rand(&rng) - 0.5), 2 * (tu_rand(&rng) - 0.5) * 1.5));
            dv3 d = dnorm(dsub(target, o)), wo, wd;
            double tnear = -INFINITY, tfar = INFINITY, tref;
            int axis_near = -1, near = 0, j, got, outside = 0;
            dv3 nref;
            pt_ray r;
            if (i % 5 == 0) o = dadd(center, dv(0.9 * (tu_rand(&rng) - 0.5) * 3, 0.9 * (tu_rand(&rng) - 0.5), 0.9 * (tu_rand(&rng) - 0.5) * 2));
            for (j = 0; j < 3; j++) {
                double oj = j == 0 ? o.x : j == 1 ? o.y : o.z, dj = j == 0 ? d.x : j == 1 ? d.y : d.z;
                double lj = j == 0 ? lo.x : j == 1 ? lo.y : lo.z, hj = j == 0 ? hi.x : j == 1 ? hi.y : hi.z;
                double t0 = (lj - oj) / dj, t1 = (hj - oj) / dj;
                if (t0 > t1) { double tmp = t0; t0 = t1; t1 = tmp; }
                if (t0 > tnear) { tnear = t0; axis_near = j; }
                if (t1 < tfar) tfar = t1;
            }
            /* closest positive boundary crossing */
            if (tnear > 0 && tnear < tfar) tref = tnear;
            else if (tnear <= 0 && tfar > 0) tref = tfar;
            else tref = -1;
            if (fabs(tnear - tfar) < 1e-5 * fabs(tfar) || fabs(tnear) < 1e-6) near = 1;
            if (tref > 0) {
                dv3 p = dadd(o, dscale(d, tref));
                double dmin = INFINITY;
                for (j = 0; j < 3; j++) {
                    double pj = j == 0 ? p.x : j == 1 ? p.y : p.z;
                    double lj = j == 0 ? lo.x : j == 1 ? lo.y : lo.z, hj = j == 0 ? hi.x : j == 1 ? hi.y : hi.z;
                    double e = fmin(fabs(pj - lj), fabs(pj - hj));
                    if (e < dmin) { dmin = e; axis_near = j; }
                }
                nref = dv(axis_near == 0, axis_near == 1, axis_near == 2);
                if (ddot(nref, dsub(p, center)) < 0) nref = dscale(nref, -1);
                outside = ddot(d, nref) < 0; /* arriving against the outward normal */
                /* near an edge the face is ambiguous */
                {
                    int close = 0;
                    for (j = 0; j < 3; j++) {
                        double pj = j == 0 ? p.x : j == 1 ? p.y : p.z;
                        double lj = j == 0 ? lo.x : j == 1 ? lo.y : lo.z, hj = j == 0 ? hi.x : j == 1 ? hi.y : hi.z;
                        if (fmin(fabs(pj - lj), fabs(pj - hj)) < 1e-4) close++;
                    }
                    if (close > 1) near = 1;
                }
            } else {
                nref = dv(0, 0, 0);
            }
            if (near) continue;
            if (k == 0) { wo = o; wd = d; }
            else {
                wo = dadd(rot(dv(0, 1, 0), 30, o), dv(100, 0, 0));
                wd = rot(dv(0, 1, 0), 30, d);
                nref = rot(dv(0, 1, 0), 30, nref);
            }
            r = mkray(wo, wd);
            got = pt_scene_intersect(s, r, 20.0f, &h); /* the other box is 100 away */
            checked++;
            if (got != (tref > 0)) { bad++; continue; }
            if (got) {
                if (fabs(h.t - tref) > 1e-4 * fmax(1, tref) || dlen(dsub(dv_from(h.geometric_normal), nref)) > 1e-4 ||
                    h.front_face != outside || (h.primitive < (uint32_t)(k == 0 ? id : id2)) ||
                    h.primitive >= (uint32_t)(k == 0 ? id : id2) + 6)
                    bad++;
            }
        }
    }
    CHECK(t, bad == 0, "%d of %d random box rays disagree with the slab test (hit, t, outward normal, front_face, primitive)",
          bad, checked);
    test_note(t, "%d random rays", checked);
    pt_scene_destroy(s);
}

static void mesh_with_normals(test_ctx *t)
{
    /* A unit square of two triangles (CCW from +z) with tilted vertex normals, plus two zero-area
       triangles at the end of the index list (skipped and counted). The shading normal is the
       barycentric interpolation of the vertex normals, not flipped toward the ray. */
    static const float pos[] = { 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 2, 0, 0 };
    float nrm[15];
    static const uint32_t idx[] = { 0, 1, 2, 0, 2, 3, 0, 0, 1, 0, 1, 4 };
    dv3 vn[5] = { { -0.3, -0.3, 1 }, { 0.3, -0.3, 1 }, { 0.3, 0.3, 1 }, { -0.3, 0.3, 1 }, { 0, 0, 1 } };
    pt_scene *s = pt_scene_create();
    pt_scene_info info;
    pt_mesh_desc md;
    int m, id, rc, i, k;
    if (!CHECK(t, s != NULL, "scene")) return;
    for (i = 0; i < 5; i++) {
        dv3 n = dnorm(vn[i]);
        vn[i] = n;
        nrm[3 * i] = (float)n.x; nrm[3 * i + 1] = (float)n.y; nrm[3 * i + 2] = (float)n.z;
    }
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    memset(&md, 0, sizeof md);
    md.positions = pos;
    md.vertex_count = 5;
    md.indices = idx;
    md.triangle_count = 4;
    md.normals = nrm;
    md.material = m;
    id = pt_scene_add_mesh(s, &md);
    rc = id >= 0 ? pt_scene_commit(s) : id;
    if (!CHECK(t, rc == PT_OK, "mesh: %d %s", rc, pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    pt_scene_get_info(s, &info);
    CHECK(t, info.degenerate_triangles_skipped == 2, "degenerate_triangles_skipped = %u, want 2",
          (unsigned)info.degenerate_triangles_skipped);
    CHECK(t, info.primitive_count == 2 && info.mesh_count == 1, "primitive_count %u mesh_count %u",
          (unsigned)info.primitive_count, (unsigned)info.mesh_count);
    CHECK(t, (info.features & PT_FEATURE_MESHES) && (info.features & PT_FEATURE_SHADING_NORMALS),
          "features 0x%x lack MESHES / SHADING_NORMALS", info.features);
    for (k = 0; k < 4; k++) {
        /* points in triangle 0 (y < x) and triangle 1 (y > x), from above and from below */
        double px = k % 2 == 0 ? 0.7 : 0.2, py = k % 2 == 0 ? 0.2 : 0.7, b0, b1, b2;
        int tri = k % 2, below = k >= 2, got;
        const int *vid;
        static const int v0[3] = { 0, 1, 2 }, v1[3] = { 0, 2, 3 };
        dv3 want, o = dv(px + 0.1, py - 0.05, below ? -2 : 2);
        pt_hit h;
        pt_ray r = mkray(o, dsub(dv(px, py, 0), o));
        got = pt_scene_intersect(s, r, INFINITY, &h);
        if (!CHECK(t, got == 1, "ray to (%g, %g) missed the mesh", px, py)) continue;
        /* barycentrics in triangle (v0, v1, v2): p = b0 v0 + b1 v1 + b2 v2 */
        if (tri == 0) { b2 = py; b1 = px - py; b0 = 1 - px; vid = v0; }
        else { b2 = py - px; b1 = px; b0 = 1 - py; vid = v1; }
        want = dnorm(dadd(dadd(dscale(vn[vid[0]], b0), dscale(vn[vid[1]], b1)), dscale(vn[vid[2]], b2)));
        CHECK(t, h.primitive == (uint32_t)(id + tri), "ray %d: primitive %u, want %d", k, (unsigned)h.primitive, id + tri);
        CHECK(t, dlen(dsub(dv_from(h.shading_normal), want)) < 1e-5,
              "ray %d: shading normal (%.6f %.6f %.6f), interpolation gives (%.6f %.6f %.6f)", k, h.shading_normal.x,
              h.shading_normal.y, h.shading_normal.z, want.x, want.y, want.z);
        CHECK(t, dlen(dsub(dv_from(h.geometric_normal), dv(0, 0, 1))) < 1e-6, "ray %d: geometric normal (%g %g %g)", k,
              h.geometric_normal.x, h.geometric_normal.y, h.geometric_normal.z);
        CHECK(t, h.front_face == !below, "ray %d: front_face %d", k, h.front_face);
        CHECK(t, fabs(h.point.x - px) < 1e-6 && fabs(h.point.y - py) < 1e-6 && fabs(h.point.z) < 1e-6 && h.material == m,
              "ray %d: point (%g %g %g) material %d", k, h.point.x, h.point.y, h.point.z, h.material);
    }
    pt_scene_destroy(s);
}

static void scene_errors(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_transform ns = pt_transform_scale(pt_v3(1, 2, 1)), us = pt_transform_scale(pt_v3(2, 2, 2));
    pt_material_desc md;
    pt_mesh_desc mesh;
    static const float pos[] = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
    static const uint32_t bad_idx[] = { 0, 1, 3 };
    pt_render_desc rd;
    pt_image img;
    pt_hit h;
    pt_ray r;
    int m, rc, i;
    const int codes[] = { PT_OK, PT_ERROR_INVALID_ARGUMENT, PT_ERROR_OUT_OF_MEMORY, PT_ERROR_IO, PT_ERROR_INVALID_STATE,
                          PT_ERROR_CANCELLED, PT_ERROR_THREAD, PT_ERROR_UNSUPPORTED };
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    CHECK(t, m >= 0, "material id %d", m);
    CHECK(t, pt_scene_add_sphere(NULL, pt_v3(0, 0, 0), 1, m) == PT_ERROR_INVALID_ARGUMENT, "NULL scene accepted");
    rc = pt_scene_add_sphere(s, pt_v3(NAN, 0, 0), 1, m);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "NaN centre: %d", rc);
    CHECK(t, pt_scene_error_message(s) != NULL && pt_scene_error_message(s)[0] != '\0', "no error message after a failure");
    CHECK(t, pt_scene_add_sphere(s, pt_v3(INFINITY, 0, 0), 1, m) == PT_ERROR_INVALID_ARGUMENT, "infinite centre accepted");
    CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 0, m) == PT_ERROR_INVALID_ARGUMENT, "zero radius accepted");
    CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), -1, m) == PT_ERROR_INVALID_ARGUMENT, "negative radius accepted");
    CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), NAN, m) == PT_ERROR_INVALID_ARGUMENT, "NaN radius accepted");
    CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, -1) == PT_ERROR_INVALID_ARGUMENT, "material -1 accepted");
    CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m + 100) == PT_ERROR_INVALID_ARGUMENT, "unknown material accepted");
    CHECK(t, pt_scene_add_quad(s, pt_v3(0, NAN, 0), pt_v3(1, 0, 0), pt_v3(0, 1, 0), m) == PT_ERROR_INVALID_ARGUMENT, "NaN quad accepted");
    CHECK(t, pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(2, 0, 0), m) == PT_ERROR_INVALID_ARGUMENT,
          "quad with parallel u, v accepted");
    CHECK(t, pt_scene_add_triangle(s, pt_v3(0, 0, 0), pt_v3(1, 0, 0), pt_v3(0, INFINITY, 0), m) == PT_ERROR_INVALID_ARGUMENT,
          "infinite triangle accepted");
    CHECK(t, pt_scene_add_box(s, pt_v3(0, 0, 0), pt_v3(1, NAN, 1), m) == PT_ERROR_INVALID_ARGUMENT, "NaN box accepted");
    CHECK(t, pt_scene_add_material(s, NULL) == PT_ERROR_INVALID_ARGUMENT, "NULL material desc accepted");
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_LAMBERTIAN;
    md.albedo = pt_v3(NAN, 0, 0);
    CHECK(t, pt_scene_add_material(s, &md) == PT_ERROR_INVALID_ARGUMENT, "NaN albedo accepted");
    md.albedo = pt_v3(0.5f, 0.5f, 0.5f);
    md.albedo_texture = 77;
    CHECK(t, pt_scene_add_material(s, &md) == PT_ERROR_INVALID_ARGUMENT, "unknown texture id accepted");
    CHECK(t, pt_scene_add_checker(s, pt_v3(0, 0, 0), pt_v3(1, 1, 1), 0.0f) == PT_ERROR_INVALID_ARGUMENT, "checker scale 0 accepted");
    CHECK(t, pt_scene_add_mesh(s, NULL) == PT_ERROR_INVALID_ARGUMENT, "NULL mesh accepted");
    memset(&mesh, 0, sizeof mesh);
    mesh.positions = pos;
    mesh.vertex_count = 3;
    mesh.indices = bad_idx;
    mesh.triangle_count = 1;
    mesh.material = m;
    CHECK(t, pt_scene_add_mesh(s, &mesh) == PT_ERROR_INVALID_ARGUMENT, "mesh index out of range accepted");
    mesh.indices = NULL;
    CHECK(t, pt_scene_add_mesh(s, &mesh) == PT_ERROR_INVALID_ARGUMENT, "mesh without indices accepted");
    /* spheres need a similarity transform */
    CHECK(t, pt_scene_set_transform(s, &ns) == PT_OK, "setting a non-uniform scale failed");
    rc = pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED, "sphere under non-uniform scale: %d, want PT_ERROR_UNSUPPORTED", rc);
    CHECK(t, pt_scene_add_quad(s, pt_v3(0, 0, 5), pt_v3(1, 0, 0), pt_v3(0, 1, 0), m) >= 0, "quad under non-uniform scale failed");
    CHECK(t, pt_scene_set_transform(s, &us) == PT_OK, "uniform scale failed");
    rc = pt_scene_add_sphere(s, pt_v3(0, 0, -5), 1, m); /* world: centre (0,0,-10), radius 2 */
    CHECK(t, rc >= 0, "sphere under uniform scale: %d", rc);
    {
        pt_transform bad = pt_transform_identity();
        bad.m[1][2] = NAN;
        CHECK(t, pt_scene_set_transform(s, &bad) == PT_ERROR_INVALID_ARGUMENT, "NaN transform accepted");
    }
    pt_scene_set_transform(s, NULL);
    /* uncommitted: queries and rendering fail */
    r = mkray(dv(0, 0, 0), dv(0, 0, -1));
    CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) < 0, "intersect on an uncommitted scene did not fail");
    memset(&rd, 0, sizeof rd);
    rd.width = 4; rd.height = 4; rd.samples_per_pixel = 1; rd.threads = 1;
    rd.camera.look_from = pt_v3(0, 0, 0); rd.camera.look_at = pt_v3(0, 0, -1);
    memset(&img, 0, sizeof img);
    rc = pt_render_image(s, &rd, &img, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_STATE, "rendering an uncommitted scene: %d, want PT_ERROR_INVALID_STATE", rc);
    pt_image_free(&img);
    rc = pt_scene_commit(s);
    CHECK(t, rc == PT_OK, "commit: %d %s", rc, pt_scene_error_message(s));
    CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) == 1 && fabs(h.t - 8) < 1e-5, "uniformly scaled sphere: t %g, want 8", h.t);
    rc = pt_render_image(s, &rd, &img, NULL);
    CHECK(t, rc == PT_OK, "rendering the committed scene: %d", rc);
    pt_image_free(&img);
    pt_scene_add_sphere(s, pt_v3(3, 3, 3), 1, m); /* modified after commit */
    {
        pt_scene_info info;
        pt_scene_get_info(s, &info);
        CHECK(t, info.committed == 0, "info.committed still 1 after a change");
    }
    rc = pt_render_image(s, &rd, &img, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_STATE, "rendering a scene modified after commit: %d, want PT_ERROR_INVALID_STATE", rc);
    pt_image_free(&img);
    rd.width = 0;
    pt_scene_commit(s);
    rc = pt_render_image(s, &rd, &img, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "width 0: %d", rc);
    pt_image_free(&img);
    CHECK(t, pt_render_image(s, NULL, &img, NULL) == PT_ERROR_INVALID_ARGUMENT, "NULL desc accepted");
    pt_scene_destroy(s);
    /* result strings: non-empty and distinct */
    for (i = 0; i < 8; i++) {
        const char *a = pt_result_string(codes[i]);
        int j;
        CHECK(t, a != NULL && a[0] != '\0', "pt_result_string(%d) empty", codes[i]);
        for (j = 0; j < i && a; j++) {
            const char *b = pt_result_string(codes[j]);
            CHECK(t, b == NULL || strcmp(a, b) != 0, "codes %d and %d share the string \"%s\"", codes[i], codes[j], a);
        }
    }
    CHECK(t, pt_result_string(-999) != NULL, "pt_result_string(-999) is NULL");
}

static void scene_info_counts(test_ctx *t)
{
    /* Counts, features and bounds recorded at commit. */
    pt_scene *s = pt_scene_create();
    pt_scene_info info;
    int lam, glass, emit, tex, textured, rc;
    pt_material_desc md;
    if (!CHECK(t, s != NULL, "scene")) return;
    lam = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    glass = pt_scene_add_dielectric(s, 1.5f);
    emit = pt_scene_add_emitter(s, pt_v3(1, 1, 1), 1);
    tex = pt_scene_add_checker(s, pt_v3(0, 0, 0), pt_v3(1, 1, 1), 0.5f);
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_LAMBERTIAN;
    md.albedo_texture = tex;
    textured = pt_scene_add_material(s, &md);
    CHECK(t, tex >= 1, "checker texture id %d, want >= 1", tex);
    rc = pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, lam);
    rc |= pt_scene_add_sphere(s, pt_v3(-3, 1, 0), 0.5f, glass);
    rc |= pt_scene_add_quad(s, pt_v3(-5, -1, -5), pt_v3(10, 0, 0), pt_v3(0, 0, 10), textured);
    rc |= pt_scene_add_triangle(s, pt_v3(0, 4, 0), pt_v3(1, 4, 0), pt_v3(0, 4, 1), emit);
    rc |= pt_scene_commit(s);
    if (!CHECK(t, rc >= 0, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    pt_scene_get_info(s, &info);
    CHECK(t, info.committed == 1, "committed flag not set");
    CHECK(t, info.primitive_count == 4 && info.sphere_count == 2 && info.quad_count == 1 && info.triangle_count == 1,
          "counts: %u prims, %u spheres, %u quads, %u triangles", (unsigned)info.primitive_count, (unsigned)info.sphere_count,
          (unsigned)info.quad_count, (unsigned)info.triangle_count);
    CHECK(t, info.emitter_count == 1 && info.material_count == 4 && info.texture_count == 1,
          "emitters %u materials %u textures %u", (unsigned)info.emitter_count, (unsigned)info.material_count,
          (unsigned)info.texture_count);
    CHECK(t, (info.features & (PT_FEATURE_EMITTERS | PT_FEATURE_SINGLE_EMITTER | PT_FEATURE_TWO_SIDED_EMITTERS |
                               PT_FEATURE_NON_DELTA | PT_FEATURE_DELTA | PT_FEATURE_DIELECTRICS | PT_FEATURE_TEXTURES |
                               PT_FEATURE_SPHERES | PT_FEATURE_QUADS | PT_FEATURE_TRIANGLES)) ==
                 (unsigned)(PT_FEATURE_EMITTERS | PT_FEATURE_SINGLE_EMITTER | PT_FEATURE_TWO_SIDED_EMITTERS |
                            PT_FEATURE_NON_DELTA | PT_FEATURE_DELTA | PT_FEATURE_DIELECTRICS | PT_FEATURE_TEXTURES |
                            PT_FEATURE_SPHERES | PT_FEATURE_QUADS | PT_FEATURE_TRIANGLES),
          "features 0x%x", info.features);
    CHECK(t, !(info.features & (PT_FEATURE_MESHES | PT_FEATURE_TRANSFORMS | PT_FEATURE_SHADING_NORMALS)),
          "features 0x%x claim meshes/transforms/normals", info.features);
    /* power of the two-sided triangle: pi * 1 * 0.5 * 2 */
    CHECK(t, fabs(info.total_emitted_power - TU_PI) < 1e-4 * TU_PI, "total power %.6f, want pi", info.total_emitted_power);
    /* bounds: contain every shape, and not much more */
    CHECK(t, info.bounds_min.x <= -5 && info.bounds_min.y <= -1 && info.bounds_min.z <= -5 && info.bounds_max.x >= 5 &&
                 info.bounds_max.y >= 4 && info.bounds_max.z >= 5,
          "bounds (%g %g %g)-(%g %g %g) do not contain the scene", info.bounds_min.x, info.bounds_min.y,
          info.bounds_min.z, info.bounds_max.x, info.bounds_max.y, info.bounds_max.z);
    CHECK(t, info.bounds_min.x > -5.01 && info.bounds_min.y > -1.01 && info.bounds_max.y < 4.01 && info.bounds_max.x < 5.01,
          "bounds (%g %g %g)-(%g %g %g) are loose", info.bounds_min.x, info.bounds_min.y, info.bounds_min.z,
          info.bounds_max.x, info.bounds_max.y, info.bounds_max.z);
    pt_scene_destroy(s);
}

static void error_message_cleared(test_ctx *t)
{
    /* pt_scene_error_message describes the last call that changes the scene: after a failure, each
       such call that succeeds leaves "" (every one of them is tried); calls that only read the
       scene (info, queries, renders) leave the message as it was. */
    pt_scene *s = pt_scene_create();
    pt_transform tr = pt_transform_translate(pt_v3(0, 0, 1));
    pt_material_desc md;
    pt_mesh_desc mesh;
    pt_scene_info info;
    pt_render_desc rd;
    pt_image img;
    pt_hit h;
    pt_ray r;
    static const float pos[] = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
    static const uint32_t idx[] = { 0, 1, 2 };
    const char *names[13] = { "set_transform", "set_transform(NULL)", "add_lambertian", "add_metal", "add_dielectric",
                              "add_emitter", "add_material", "add_checker", "add_sphere", "add_quad", "add_triangle",
                              "add_box", "add_mesh" };
    int m, k, rc = 0;
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_METAL;
    md.albedo = pt_v3(0.9f, 0.9f, 0.9f);
    memset(&mesh, 0, sizeof mesh);
    mesh.positions = pos;
    mesh.vertex_count = 3;
    mesh.indices = idx;
    mesh.triangle_count = 1;
    mesh.material = m;
    for (k = 0; k < 13; k++) {
        rc = pt_scene_add_sphere(s, pt_v3(0, 0, 0), -1, m); /* fails: negative radius */
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && pt_scene_error_message(s)[0] != '\0', "the failure before %s: %d '%s'",
              names[k], rc, pt_scene_error_message(s));
        switch (k) {
        case 0: rc = pt_scene_set_transform(s, &tr); break;
        case 1: rc = pt_scene_set_transform(s, NULL); break;
        case 2: rc = pt_scene_add_lambertian(s, pt_v3(0.2f, 0.2f, 0.2f)); break;
        case 3: rc = pt_scene_add_metal(s, pt_v3(0.8f, 0.8f, 0.8f), 0.1f); break;
        case 4: rc = pt_scene_add_dielectric(s, 1.5f); break;
        case 5: rc = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0); break;
        case 6: rc = pt_scene_add_material(s, &md); break;
        case 7: rc = pt_scene_add_checker(s, pt_v3(0, 0, 0), pt_v3(1, 1, 1), 1.0f); break;
        case 8: rc = pt_scene_add_sphere(s, pt_v3(0, 0, -5), 1, m); break;
        case 9: rc = pt_scene_add_quad(s, pt_v3(-1, -1, -8), pt_v3(2, 0, 0), pt_v3(0, 2, 0), m); break;
        case 10: rc = pt_scene_add_triangle(s, pt_v3(0, 0, -9), pt_v3(1, 0, -9), pt_v3(0, 1, -9), m); break;
        case 11: rc = pt_scene_add_box(s, pt_v3(3, 3, 3), pt_v3(4, 4, 4), m); break;
        default: rc = pt_scene_add_mesh(s, &mesh); break;
        }
        CHECK(t, rc >= 0 && pt_scene_error_message(s)[0] == '\0', "%s succeeded (%d) but the message is still '%s'",
              names[k], rc, pt_scene_error_message(s));
    }
    rc = pt_scene_set_backend(s, (pt_backend)7);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && pt_scene_error_message(s)[0] != '\0', "backend 7: %d", rc);
    rc = pt_scene_set_backend(s, PT_BACKEND_BUILTIN);
    CHECK(t, rc == PT_OK && pt_scene_error_message(s)[0] == '\0', "set_backend succeeded (%d) but the message is '%s'", rc,
          pt_scene_error_message(s));
    pt_scene_add_sphere(s, pt_v3(0, 0, 0), -1, m);
    rc = pt_scene_commit(s);
    CHECK(t, rc == PT_OK && pt_scene_error_message(s)[0] == '\0', "commit succeeded (%d) but the message is '%s'", rc,
          pt_scene_error_message(s));
    /* read-only calls neither clear nor write it */
    pt_scene_add_sphere(s, pt_v3(0, 0, 0), -1, m);
    r.origin = pt_v3(0, 0, 0);
    r.dir = pt_v3(0, 0, -1);
    memset(&rd, 0, sizeof rd);
    rd.width = 4; rd.height = 4; rd.samples_per_pixel = 1; rd.threads = 1;
    rd.camera.look_from = pt_v3(0, 0, 0); rd.camera.look_at = pt_v3(0, 0, -1);
    memset(&img, 0, sizeof img);
    CHECK(t, pt_scene_get_info(s, &info) == PT_OK && pt_scene_intersect(s, r, INFINITY, &h) == 1 &&
                 pt_render_image(s, &rd, &img, NULL) == PT_OK && strstr(pt_scene_error_message(s), "sphere") != NULL,
          "read-only calls changed the message to '%s'", pt_scene_error_message(s));
    pt_image_free(&img);
    pt_scene_destroy(s);
}

const test_case test_geometry_cases[] = {
    TEST_CASE(intersect_sphere),
    TEST_CASE(intersect_sphere_far_tiny),
    TEST_CASE(intersect_planar),
    TEST_CASE(triangle_fan_watertight),
    TEST_CASE(sliver_triangle_distance),
    TEST_CASE(grazing_edge_hit_on_plane),
    TEST_CASE(offset_ray_origin_scales),
    TEST_CASE(transformed_emitters),
    TEST_CASE(box_helper),
    TEST_CASE(mesh_with_normals),
    TEST_CASE(scene_errors),
    TEST_CASE(error_message_cleared),
    TEST_CASE(scene_info_counts),
    TEST_END
};
