/* test_embree.c - the traversal backends (pdftrace.h sections 5 and 5b).

   Always: the backend API's errors (values out of range, a switch that uncommits the scene,
   PT_ERROR_UNSUPPORTED for Embree when it is not compiled in) and pt_scene_info's backend
   fields. With PDFTRACE_EMBREE compiled in:
   - first_hits: 10^6 rays over a scene of spheres, quads, triangles and meshes (boxes of
     quads and of triangles, a heightfield, coincident surfaces), traced by the built-in BVH
     and by Embree. Same primitive and t within 1e-5 of the coordinates' magnitude, or a
     difference that floating-point rounding explains: a tie (both hit, at the same t: a
     shared edge or vertex, or coincident surfaces) or a graze (one backend's hit lies within
     rounding of its primitive's boundary: an edge or a sphere's silhouette). Anything else
     fails. The counts are printed.
   - scenes: every scene of scenes/ (pdftrace_scene.h, pt_scenefile_build) rendered with both
     backends from independent seeds; per-region z-tests of the means, one Sidak family at
     alpha = 0.01 over all regions, channels and scenes.
   - auto / rebuild / ftz: AUTO's threshold, re-commits after a change, and the floating-point
     state (flush-to-zero inside Embree tiles only, the host's state restored).
   - batched: the batched integrator's Embree streams (rtcIntersect1M, rtcOccluded1M) render the
     scalar integrator's film (one rtcIntersect1 / rtcOccluded1 per ray) bit for bit, and are
     the default integrator with Embree 3. */
#define _GNU_SOURCE /* feenableexcept (glibc) for embree_fp_traps */
#include "pdftrace_scene.h"

#include <fenv.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test.h"
#include "test_util.h"

#ifdef PDFTRACE_EMBREE
#if defined(__SSE__) || defined(_M_X64)
#include <xmmintrin.h>
#define TE_HAVE_MXCSR 1
#endif
#endif

/* A small scene (a sphere, a quad, a triangle, a light) for the API tests. */
static pt_scene *te_small_scene(void)
{
    pt_scene *s = pt_scene_create();
    int m, l;
    if (!s) return NULL;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    l = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0);
    if (m < 0 || l < 0 || pt_scene_add_sphere(s, pt_v3(0, 1, 0), 1, m) < 0 ||
        pt_scene_add_quad(s, pt_v3(-5, 0, -5), pt_v3(10, 0, 0), pt_v3(0, 0, 10), m) < 0 ||
        pt_scene_add_triangle(s, pt_v3(-2, 0.5f, 2), pt_v3(2, 0.5f, 2), pt_v3(0, 3, 2), m) < 0 ||
        pt_scene_add_quad(s, pt_v3(-1, 4, -1), pt_v3(2, 0, 0), pt_v3(0, 0, 2), l) < 0) {
        pt_scene_destroy(s);
        return NULL;
    }
    return s;
}

static void embree_backend_errors(test_ctx *t)
{
    pt_scene *s = te_small_scene();
    pt_scene_info info;
    pt_ray r;
    pt_hit h;
    int rc;
    if (!CHECK(t, s != NULL, "scene")) return;
    CHECK(t, pt_scene_set_backend(NULL, PT_BACKEND_BUILTIN) == PT_ERROR_INVALID_ARGUMENT, "NULL scene accepted");
    rc = pt_scene_set_backend(s, (pt_backend)3);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "3 is not a backend"),
          "backend 3: %d '%s'", rc, pt_scene_error_message(s));
    rc = pt_scene_set_backend(s, (pt_backend)-1);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "backend -1: %d", rc);
    /* before any commit the info names the built-in BVH (never AUTO) */
    CHECK(t, pt_scene_get_info(s, &info) == PT_OK && info.backend == PT_BACKEND_BUILTIN,
          "uncommitted scene: backend %d", (int)info.backend);
    /* BUILTIN on a small scene: a build time and its memory (AUTO picks the built-in BVH here
       too, unless a build sets PDFTRACE_EMBREE_SMALL_PRIMS above 4: 3 of the 4 primitives are
       quads and spheres) */
    CHECK(t, pt_scene_set_backend(s, PT_BACKEND_BUILTIN) == PT_OK, "set BUILTIN");
    CHECK(t, pt_scene_commit(s) == PT_OK, "commit: %s", pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    CHECK(t, info.backend == PT_BACKEND_BUILTIN && info.bvh_node_count > 0, "BUILTIN, 4 primitives: backend %d, %u nodes",
          (int)info.backend, (unsigned)info.bvh_node_count);
    CHECK(t, info.build_seconds >= 0.0 && info.build_seconds < 10.0 && info.accel_bytes >= info.bvh_node_count * 16u,
          "built-in: build %g s, %zu bytes for %u nodes", info.build_seconds, info.accel_bytes,
          (unsigned)info.bvh_node_count);
    /* the same backend again leaves the scene committed; another one uncommits it */
    CHECK(t, pt_scene_set_backend(s, PT_BACKEND_BUILTIN) == PT_OK && (pt_scene_get_info(s, &info), info.committed),
          "setting the same backend uncommitted the scene");
    rc = pt_scene_set_backend(s, PT_BACKEND_AUTO);
    pt_scene_get_info(s, &info);
    CHECK(t, rc == PT_OK && !info.committed, "switch to AUTO: %d, committed %d", rc, info.committed);
    CHECK(t, pt_scene_commit(s) == PT_OK, "commit (AUTO): %s", pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
#ifdef PDFTRACE_EMBREE
    CHECK(t, info.backend == (4 < PDFTRACE_EMBREE_SMALL_PRIMS ? PT_BACKEND_EMBREE : PT_BACKEND_BUILTIN),
          "AUTO, 4 primitives, 3 of them quads and spheres: backend %d", (int)info.backend);
#else
    CHECK(t, info.backend == PT_BACKEND_BUILTIN, "AUTO without Embree: backend %d", (int)info.backend);
#endif
    rc = pt_scene_set_backend(s, PT_BACKEND_BUILTIN);
    pt_scene_get_info(s, &info);
    CHECK(t, rc == PT_OK && !info.committed, "switch to BUILTIN: %d, committed %d", rc, info.committed);
    r.origin = pt_v3(0, 1, -5);
    r.dir = pt_v3(0, 0, 1);
    rc = pt_scene_intersect(s, r, INFINITY, &h);
    CHECK(t, rc == PT_ERROR_INVALID_STATE, "query after a switch without a commit: %d", rc);
    CHECK(t, pt_scene_commit(s) == PT_OK && pt_scene_intersect(s, r, INFINITY, &h) == 1 && fabsf(h.t - 4.0f) < 1e-5f,
          "re-committed: no hit at t = 4");
    rc = pt_scene_set_backend(s, PT_BACKEND_EMBREE);
#ifdef PDFTRACE_EMBREE
    CHECK(t, rc == PT_OK, "EMBREE compiled in, but set_backend says %d: %s", rc, pt_scene_error_message(s));
#else
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && strstr(pt_scene_error_message(s), "Embree is not compiled in"),
          "EMBREE without PDFTRACE_EMBREE: %d '%s'", rc, pt_scene_error_message(s));
    CHECK(t, pt_scene_set_embree_config(s, "threads=1") == PT_ERROR_UNSUPPORTED, "set_embree_config without Embree");
    pt_scene_get_info(s, &info);
    CHECK(t, info.committed && info.backend == PT_BACKEND_BUILTIN, "a refused switch changed the scene");
    test_note(t, "Embree not compiled in: set_backend(EMBREE) -> %s", pt_result_string(rc));
#endif
    pt_scene_destroy(s);
}

#ifndef PDFTRACE_EMBREE

const test_case test_embree_cases[] = {
    TEST_CASE(embree_backend_errors),
    TEST_END
};

#else /* PDFTRACE_EMBREE */

/* ---- the first-hit comparison ---- */

/* The test's own record of every primitive, in double, indexed by public primitive id. */
typedef struct te_prim { int kind; dv3 p[3]; double r; } te_prim;
typedef struct te_scene {
    te_prim *prim;
    int count, cap;
    dv3 *aim;     /* points that rays are aimed at: vertices, edge midpoints */
    int aim_count, aim_cap;
} te_scene;

static int te_push(te_scene *ts, int id, int kind, dv3 a, dv3 b, dv3 c, double r)
{
    if (id != ts->count) return 0; /* ids are consecutive: the record must follow the scene */
    if (ts->count == ts->cap) {
        int nc = ts->cap ? 2 * ts->cap : 1024;
        te_prim *np = (te_prim *)realloc(ts->prim, sizeof(te_prim) * (size_t)nc);
        if (!np) return 0;
        ts->prim = np;
        ts->cap = nc;
    }
    ts->prim[ts->count].kind = kind;
    ts->prim[ts->count].p[0] = a;
    ts->prim[ts->count].p[1] = b;
    ts->prim[ts->count].p[2] = c;
    ts->prim[ts->count].r = r;
    ts->count++;
    return 1;
}
static void te_aim(te_scene *ts, dv3 p)
{
    if (ts->aim_count == ts->aim_cap) {
        int nc = ts->aim_cap ? 2 * ts->aim_cap : 1024;
        dv3 *na = (dv3 *)realloc(ts->aim, sizeof(dv3) * (size_t)nc);
        if (!na) return;
        ts->aim = na;
        ts->aim_cap = nc;
    }
    ts->aim[ts->aim_count++] = p;
}
static int te_quad(pt_scene *s, te_scene *ts, dv3 q, dv3 u, dv3 v, int m)
{
    int id = pt_scene_add_quad(s, dv_to(q), dv_to(u), dv_to(v), m);
    if (id < 0) return id;
    te_aim(ts, q);
    te_aim(ts, dadd(q, dscale(u, 0.5)));
    te_aim(ts, dadd(dadd(q, u), v));
    return te_push(ts, id, TU_QUAD, dv_from(dv_to(q)), dv_from(dv_to(u)), dv_from(dv_to(v)), 0) ? id : -100;
}
static int te_tri(pt_scene *s, te_scene *ts, dv3 a, dv3 b, dv3 c, int m)
{
    int id = pt_scene_add_triangle(s, dv_to(a), dv_to(b), dv_to(c), m);
    if (id < 0) return id;
    te_aim(ts, a);
    te_aim(ts, dscale(dadd(a, b), 0.5));
    return te_push(ts, id, TU_TRIANGLE, dv_from(dv_to(a)), dv_from(dv_to(b)), dv_from(dv_to(c)), 0) ? id : -100;
}
static int te_sphere(pt_scene *s, te_scene *ts, dv3 c, double r, int m)
{
    int id = pt_scene_add_sphere(s, dv_to(c), (float)r, m);
    if (id < 0) return id;
    return te_push(ts, id, TU_SPHERE, dv_from(dv_to(c)), c, c, (double)(float)r) ? id : -100;
}
/* A mesh; its triangles are recorded from the same float vertices. */
static int te_mesh(pt_scene *s, te_scene *ts, const float *pos, int nv, const uint32_t *idx, int nt, int m)
{
    pt_mesh_desc md;
    int id, i, k;
    memset(&md, 0, sizeof md);
    md.positions = pos;
    md.vertex_count = (uint32_t)nv;
    md.indices = idx;
    md.triangle_count = (uint32_t)nt;
    md.material = m;
    id = pt_scene_add_mesh(s, &md);
    if (id < 0) return id;
    for (i = 0; i < nt; i++) {
        dv3 v[3];
        for (k = 0; k < 3; k++) {
            const float *p = pos + 3 * idx[3 * i + k];
            v[k] = dv(p[0], p[1], p[2]);
        }
        if (!te_push(ts, id + i, TU_TRIANGLE, v[0], v[1], v[2], 0)) return -100;
    }
    for (i = 0; i < nv; i++) te_aim(ts, dv(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2]));
    return id;
}

/* The comparison scene: built identically into every scene passed (one per backend). */
static int te_build(pt_scene *s, te_scene *ts, int record)
{
    enum { G = 40 };
    static float hpos[3 * (G + 1) * (G + 1)];
    static uint32_t hidx[6 * G * G];
    static const float bpos[24] = { 2, -3, 1, 4, -3, 1, 4, -1, 1, 2, -1, 1, 2, -3, 3, 4, -3, 3, 4, -1, 3, 2, -1, 3 };
    static const uint32_t bidx[36] = { 0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                       3, 6, 2, 3, 7, 6, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5 };
    te_scene dummy;
    pt_rng rng;
    int m, i, j, rc = 0;
    memset(&dummy, 0, sizeof dummy);
    if (!record) ts = &dummy;
    pt_rng_seed(&rng, 5005, 7);
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    if (m < 0) return m;
    /* a smooth heightfield mesh over [-4, 4]^2 at y ~ -2: shared edges and vertices */
    for (j = 0; j <= G; j++)
        for (i = 0; i <= G; i++) {
            float x = -4.0f + 8.0f * (float)i / G, z = -4.0f + 8.0f * (float)j / G;
            float *p = hpos + 3 * (j * (G + 1) + i);
            p[0] = x; p[1] = -2.0f + 0.3f * sinf(1.3f * x) * cosf(0.9f * z); p[2] = z;
        }
    for (j = 0; j < G; j++)
        for (i = 0; i < G; i++) {
            uint32_t a = (uint32_t)(j * (G + 1) + i), b = a + 1, c = a + (G + 1), d = c + 1, *q = hidx + 6 * (j * G + i);
            q[0] = a; q[1] = c; q[2] = b; q[3] = b; q[4] = c; q[5] = d;
        }
    rc = te_mesh(s, ts, hpos, (G + 1) * (G + 1), hidx, 2 * G * G, m);
    /* an axis-aligned box of 12 mesh triangles at integer coordinates (in-plane rays) */
    if (rc >= 0) rc = te_mesh(s, ts, bpos, 8, bidx, 12, m);
    /* axis-aligned boxes of quads at integer coordinates, and one rotated box */
    for (i = 0; i < 6 && rc >= 0; i++) {
        double x = -5 + 2 * i, y = 1 + (i % 3), z = -4 + (i % 2) * 3, sx = 1 + (i % 2), sy = 1, sz = 2;
        dv3 lo = dv(x, y, z), dx = dv(sx, 0, 0), dy = dv(0, sy, 0), dz = dv(0, 0, sz);
        rc = te_quad(s, ts, dadd(lo, dz), dx, dy, m);
        if (rc >= 0) rc = te_quad(s, ts, dadd(lo, dx), dscale(dx, -1), dy, m);
        if (rc >= 0) rc = te_quad(s, ts, dadd(dadd(lo, dx), dz), dscale(dz, -1), dy, m);
        if (rc >= 0) rc = te_quad(s, ts, lo, dz, dy, m);
        if (rc >= 0) rc = te_quad(s, ts, dadd(dadd(lo, dy), dz), dx, dscale(dz, -1), m);
        if (rc >= 0) rc = te_quad(s, ts, lo, dx, dz, m);
    }
    {
        double c = cos(0.6), sn = sin(0.6);
        dv3 ex = dv(c, 0.3, -sn), ey = dv(-0.3 * c, 1, 0.3 * sn), ez = dcross(ex, ey), o = dv(0.5, 0.2, 4);
        if (rc >= 0) rc = te_quad(s, ts, o, ex, ey, m);
        if (rc >= 0) rc = te_quad(s, ts, dadd(o, ez), ey, ex, m);
        if (rc >= 0) rc = te_quad(s, ts, o, ez, ex, m);
    }
    /* random quads, triangles and spheres */
    for (i = 0; i < 120 && rc >= 0; i++) {
        dv3 q = dv(-5 + 10 * tu_rand(&rng), -2 + 6 * tu_rand(&rng), -5 + 10 * tu_rand(&rng));
        rc = te_quad(s, ts, q, dscale(tu_rand_dir(&rng), 0.2 + tu_rand(&rng)), dscale(tu_rand_dir(&rng), 0.2 + tu_rand(&rng)), m);
        if (rc == PT_ERROR_INVALID_ARGUMENT) rc = 0; /* parallel u and v: skipped (rare) */
    }
    for (i = 0; i < 200 && rc >= 0; i++) {
        dv3 a = dv(-5 + 10 * tu_rand(&rng), -2 + 6 * tu_rand(&rng), -5 + 10 * tu_rand(&rng));
        rc = te_tri(s, ts, a, dadd(a, dscale(tu_rand_dir(&rng), 0.3 + tu_rand(&rng))),
                    dadd(a, dscale(tu_rand_dir(&rng), 0.3 + tu_rand(&rng))), m);
        if (rc == PT_ERROR_INVALID_ARGUMENT) rc = 0;
    }
    for (i = 0; i < 120 && rc >= 0; i++) {
        dv3 c = dv(-5 + 10 * tu_rand(&rng), -2 + 6 * tu_rand(&rng), -5 + 10 * tu_rand(&rng));
        rc = te_sphere(s, ts, c, i == 0 ? 1e-3 : (i == 1 ? 3.0 : 0.05 + 0.4 * tu_rand(&rng)), m);
        if (rc >= 0) te_aim(ts, dadd(c, dv(0, ts->prim[rc].r, 0)));
    }
    /* coincident surfaces: a quad and the two triangles that cover it */
    if (rc >= 0) rc = te_quad(s, ts, dv(-1, 5, -1), dv(2, 0, 0), dv(0, 0, 2), m);
    if (rc >= 0) rc = te_tri(s, ts, dv(-1, 5, -1), dv(1, 5, -1), dv(1, 5, 1), m);
    if (rc >= 0) rc = te_tri(s, ts, dv(-1, 5, -1), dv(1, 5, 1), dv(-1, 5, 1), m);
    free(dummy.prim);
    free(dummy.aim);
    return rc < 0 ? rc : PT_OK;
}

/* Distance from p to the segment ab. */
static double te_seg_dist(dv3 p, dv3 a, dv3 b)
{
    dv3 ab = dsub(b, a);
    double l2 = ddot(ab, ab), u = l2 > 0 ? ddot(dsub(p, a), ab) / l2 : 0;
    if (u < 0) u = 0;
    if (u > 1) u = 1;
    return dlen(dsub(p, dadd(a, dscale(ab, u))));
}
/* How far the ray's hit at t on primitive id is from that primitive's boundary: an edge of a
   triangle or quad, the silhouette of a sphere (|distance from the centre to the line| - r).
   For planar primitives the distance is multiplied by |cos| of the incidence angle: a float
   error e in the ray/plane solution moves the hit along the plane by e / |cos| (at grazing
   incidence the barycentrics of both backends lose that many digits). */
static double te_boundary_dist(const te_scene *ts, int id, pt_ray r, double t)
{
    const te_prim *p = &ts->prim[id];
    dv3 o = dv_from(r.origin), d = dv_from(r.dir), x = dadd(o, dscale(d, t)), n;
    double dist;
    if (p->kind == TU_SPHERE) {
        dv3 f = dsub(p->p[0], o), dn = dnorm(d);
        double along = ddot(f, dn);
        return fabs(dlen(dsub(f, dscale(dn, along))) - p->r);
    }
    if (p->kind == TU_TRIANGLE) {
        double e0 = te_seg_dist(x, p->p[0], p->p[1]), e1 = te_seg_dist(x, p->p[1], p->p[2]), e2 = te_seg_dist(x, p->p[2], p->p[0]);
        dist = fmin(e0, fmin(e1, e2));
        n = dcross(dsub(p->p[1], p->p[0]), dsub(p->p[2], p->p[0]));
    } else {
        dv3 a = p->p[0], b = dadd(a, p->p[1]), c = dadd(b, p->p[2]), e = dadd(a, p->p[2]);
        dist = fmin(fmin(te_seg_dist(x, a, b), te_seg_dist(x, b, c)), fmin(te_seg_dist(x, c, e), te_seg_dist(x, e, a)));
        n = dcross(p->p[1], p->p[2]);
    }
    return dist * fabs(ddot(dnorm(n), dnorm(d)));
}

typedef struct te_counts {
    long uniform_differing; /* ties, crossings and grazes among the uniformly random rays */
    long embree_missed; /* grazes where the built-in hit is the nearer one (Embree found a crack) */
    long rays, hits, same, ties, coincident, grazes, unexplained, t_far, occ_bad;
    double worst_t_rel; /* same primitive: max |t_b - t_e| / (|o| + t |d|) */
    char example[300];
} te_counts;

static void te_compare(const pt_scene *sb, const pt_scene *se, const te_scene *ts, pt_ray r, int check_occ, int uniform,
                       te_counts *c)
{
    pt_hit hb, he;
    int b = pt_scene_intersect(sb, r, INFINITY, &hb), e = pt_scene_intersect(se, r, INFINITY, &he);
    double scale, tol;
    c->rays++;
    if (b == 0 && e == 0) return;
    c->hits++;
    scale = dlen(dv_from(r.origin)) + (double)(b ? hb.t : he.t) * dlen(dv_from(r.dir));
    tol = 1e-5 * scale;
    if (b == 1 && e == 1 && hb.primitive == he.primitive) {
        /* a float error e in the ray/surface solution moves t and the point by ~e / |cos| of the
           incidence angle (amplification capped at 100) */
        double cosi = fabs(ddot(dv_from(hb.geometric_normal), dnorm(dv_from(r.dir))));
        double d = fabs((double)hb.t - (double)he.t) * fmax(cosi, 0.01);
        double dp = dlen(dsub(dv_from(hb.point), dv_from(he.point))) * fmax(cosi, 0.01);
        c->same++;
        if (fmax(d, dp) / scale > c->worst_t_rel) c->worst_t_rel = fmax(d, dp) / scale;
        if (d > tol || dp > tol) {
            c->t_far++;
            if (!c->example[0])
                snprintf(c->example, sizeof c->example,
                         "primitive %u: t %.9g (built-in) vs %.9g (Embree), points (%.7g %.7g %.7g) vs (%.7g %.7g %.7g)",
                         (unsigned)hb.primitive, hb.t, he.t, hb.point.x, hb.point.y, hb.point.z, he.point.x,
                         he.point.y, he.point.z);
        }
        if (check_occ) {
            float t = hb.t < he.t ? hb.t : he.t, t2 = hb.t < he.t ? he.t : hb.t;
            if (pt_scene_occluded(se, r, t * 0.999f) != 0 || pt_scene_occluded(se, r, t2 * 1.001f) != 1) c->occ_bad++;
        }
        return;
    }
    if (b == 1 && e == 1 && fabs((double)hb.t - (double)he.t) <= tol) {
        /* both hit, at the same distance: their surfaces meet there */
        int cb = te_boundary_dist(ts, (int)hb.primitive, r, hb.t) <= tol && te_boundary_dist(ts, (int)he.primitive, r, he.t) <= tol;
        if (cb) c->ties++;
        else c->coincident++;
        c->uniform_differing += uniform && cb;
        return;
    }
    c->uniform_differing += uniform;
    {
        /* the nearer hit must lie on its primitive's boundary: the other backend missed it by rounding */
        int near_is_b = b == 1 && (e == 0 || hb.t < he.t);
        const pt_hit *hn = near_is_b ? &hb : &he;
        double bd = te_boundary_dist(ts, (int)hn->primitive, r, hn->t);
        if (bd <= tol) {
            c->grazes++;
            c->embree_missed += near_is_b;
            return;
        }
        c->unexplained++;
        if (!c->example[0])
            snprintf(c->example, sizeof c->example,
                     "ray (%.7g %.7g %.7g)+t(%.7g %.7g %.7g): built-in %d prim %u t %.7g, Embree %d prim %u t %.7g; "
                     "nearer hit %.3g from its boundary",
                     r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, b, b ? (unsigned)hb.primitive : 0u,
                     b ? hb.t : 0.0f, e, e ? (unsigned)he.primitive : 0u, e ? he.t : 0.0f, bd);
    }
}

static void embree_first_hits(test_ctx *t)
{
    pt_scene *sb = pt_scene_create(), *se = pt_scene_create();
    te_scene ts;
    te_counts c;
    pt_scene_info ib, ie;
    pt_rng rng;
    long i, n = 1000000;
    int bounds_ok;
    memset(&ts, 0, sizeof ts);
    memset(&c, 0, sizeof c);
    if (!CHECK(t, sb && se, "scenes")) goto done;
    if (!CHECK(t, te_build(sb, &ts, 1) == PT_OK && te_build(se, NULL, 0) == PT_OK, "build: %s %s",
               pt_scene_error_message(sb), pt_scene_error_message(se)))
        goto done;
    CHECK(t, pt_scene_set_backend(sb, PT_BACKEND_BUILTIN) == PT_OK && pt_scene_commit(sb) == PT_OK, "commit built-in");
    CHECK(t, pt_scene_set_backend(se, PT_BACKEND_EMBREE) == PT_OK && pt_scene_commit(se) == PT_OK, "commit Embree: %s",
          pt_scene_error_message(se));
    pt_scene_get_info(sb, &ib);
    pt_scene_get_info(se, &ie);
    if (!CHECK(t, ib.backend == PT_BACKEND_BUILTIN && ie.backend == PT_BACKEND_EMBREE && ie.bvh_node_count == 0,
               "backends %d %d", (int)ib.backend, (int)ie.backend))
        goto done;
    CHECK(t, (int)ib.primitive_count == ts.count && ie.primitive_count == ib.primitive_count, "primitives %u %u (test %d)",
          (unsigned)ib.primitive_count, (unsigned)ie.primitive_count, ts.count);
    CHECK(t, ie.accel_bytes > 0 && ie.build_seconds >= 0.0, "Embree: %zu bytes, %g s", ie.accel_bytes, ie.build_seconds);
    /* the same padded union of the primitives' boxes (to rounding: the built-in takes its root box) */
    {
        double ext = dlen(dsub(dv_from(ib.bounds_max), dv_from(ib.bounds_min)));
        bounds_ok = dlen(dsub(dv_from(ib.bounds_min), dv_from(ie.bounds_min))) <= 1e-5 * ext &&
                    dlen(dsub(dv_from(ib.bounds_max), dv_from(ie.bounds_max))) <= 1e-5 * ext && ext > 10;
    }
    CHECK(t, bounds_ok,
          "bounds differ: (%g %g %g)-(%g %g %g) vs (%g %g %g)-(%g %g %g)", ib.bounds_min.x, ib.bounds_min.y, ib.bounds_min.z,
          ib.bounds_max.x, ib.bounds_max.y, ib.bounds_max.z, ie.bounds_min.x, ie.bounds_min.y, ie.bounds_min.z,
          ie.bounds_max.x, ie.bounds_max.y, ie.bounds_max.z);
    pt_rng_seed(&rng, 8080, 3);
    for (i = 0; i < n; i++) {
        pt_ray r;
        int kind = (int)(i % 20);
        if (kind < 14) { /* uniform: origin in a box around the scene, direction on the sphere */
            r.origin = dv_to(dv(-7 + 14 * tu_rand(&rng), -4 + 11 * tu_rand(&rng), -7 + 14 * tu_rand(&rng)));
            r.dir = dv_to(tu_rand_dir(&rng));
        } else if (kind < 17) { /* aimed at a vertex, an edge midpoint or a sphere's top */
            dv3 o = dv(-7 + 14 * tu_rand(&rng), -4 + 11 * tu_rand(&rng), -7 + 14 * tu_rand(&rng));
            dv3 a = ts.aim[(int)(tu_rand(&rng) * ts.aim_count)];
            r.origin = dv_to(o);
            r.dir = dv_to(dnorm(dsub(a, o)));
        } else { /* axis-aligned from integer and half-integer points (in the planes of faces) */
            int ax = (int)(tu_rand(&rng) * 3), k;
            float p[3], sg = tu_rand(&rng) < 0.5 ? -1.0f : 1.0f;
            for (k = 0; k < 3; k++) p[k] = (float)((int)(tu_rand(&rng) * 14) - 7) + ((i & 1) && k != ax ? 0.5f : 0.0f);
            r.origin = pt_v3(p[0], p[1], p[2]);
            r.dir = pt_v3(ax == 0 ? sg : 0.0f, ax == 1 ? sg : 0.0f, ax == 2 ? sg : 0.0f);
        }
        te_compare(sb, se, &ts, r, i % 10 == 0, kind < 14, &c);
    }
    test_note(t, "%ld rays (70 %% uniform, 15 %% aimed at vertices/edges, 15 %% axis-aligned), %ld hit: %ld same "
                 "primitive (worst |dt| or |dp| x |cos| %.2g of |o|+t|d|); differing %ld: %ld ties on shared edges/vertices, %ld "
                 "coincident or crossing surfaces, %ld edge/silhouette grazes (%ld of them missed by Embree), %ld unexplained (ties and grazes among "
                 "uniform rays: %ld); "
                 "occlusion inconsistent %ld",
              c.rays, c.hits, c.same, c.worst_t_rel, c.ties + c.coincident + c.grazes + c.unexplained, c.ties,
              c.coincident, c.grazes, c.embree_missed, c.unexplained, c.uniform_differing, c.occ_bad);
    CHECK(t, c.unexplained == 0, "%ld differing first hits not explained by rounding; first: %s", c.unexplained, c.example);
    CHECK(t, c.t_far == 0, "%ld hits on the same primitive with t or the point further apart than 1e-5 (|o| + t|d|); "
                           "first: %s",
          c.t_far, c.example);
    CHECK(t, c.occ_bad == 0, "Embree's any-hit query disagrees with its closest hit %ld times", c.occ_bad);
    /* a bound that a systematic error would break: among uniformly random rays (no aim at edges),
       rounding differences are rare */
    CHECK(t, c.uniform_differing <= n / 10000, "%ld of the %ld uniform rays tie or graze (more than 1e-4 of all rays)",
          c.uniform_differing, n * 7 / 10);
    CHECK(t, c.same > n / 4, "only %ld rays hit the same primitive", c.same);
done:
    free(ts.prim);
    free(ts.aim);
    pt_scene_destroy(sb);
    pt_scene_destroy(se);
}

/* Errors from Embree itself: a device configuration it refuses ("threads=abc": rtcNewDevice
   fails) becomes a pdftrace error with Embree's message for EMBREE, and a fallback for AUTO. */
static void embree_device_errors(test_ctx *t)
{
    pt_scene *s = te_small_scene();
    pt_scene_info info;
    pt_ray r;
    pt_hit h;
    char longer[200];
    int rc, k;
    if (!CHECK(t, s != NULL, "scene")) return;
    memset(longer, 'x', sizeof longer - 1);
    longer[sizeof longer - 1] = '\0';
    CHECK(t, pt_scene_set_embree_config(s, longer) == PT_ERROR_INVALID_ARGUMENT, "a 199-character configuration");
    CHECK(t, pt_scene_set_embree_config(s, "threads=abc") == PT_OK && pt_scene_set_backend(s, PT_BACKEND_EMBREE) == PT_OK,
          "set");
    rc = pt_scene_commit(s);
    CHECK(t, rc < 0 && strstr(pt_scene_error_message(s), "Embree could not create a device") &&
             strstr(pt_scene_error_message(s), "threads=abc"),
          "EMBREE with a bad configuration: %d '%s'", rc, pt_scene_error_message(s));
    test_note(t, "bad configuration -> %s: %s", pt_result_string(rc), pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    r.origin = pt_v3(0, 1, -10);
    r.dir = pt_v3(0, 0, 1);
    CHECK(t, !info.committed && pt_scene_intersect(s, r, INFINITY, &h) == PT_ERROR_INVALID_STATE,
          "a failed commit left the scene usable");
    /* AUTO falls back to the built-in BVH (the small scene is below the threshold: force the
       decision with a scene above it) */
    pt_scene_destroy(s);
    s = pt_scene_create();
    k = s ? pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)) : -1;
    for (rc = k; rc >= 0 && s && (int)(pt_scene_get_info(s, &info), info.primitive_count) < PDFTRACE_EMBREE_MIN_PRIMS;)
        rc = pt_scene_add_sphere(s, pt_v3((float)(info.primitive_count % 100), (float)(info.primitive_count / 100), 0),
                                 0.25f, k);
    if (rc >= 0) rc = pt_scene_set_embree_config(s, "threads=abc");
    if (rc >= 0) rc = pt_scene_commit(s);
    if (s) pt_scene_get_info(s, &info);
    CHECK(t, rc == PT_OK && info.backend == PT_BACKEND_BUILTIN && pt_scene_error_message(s)[0] == '\0',
          "AUTO with a bad configuration: %d, backend %d '%s'", rc, (int)info.backend, s ? pt_scene_error_message(s) : "");
    /* a good configuration again: Embree */
    if (s) {
        CHECK(t, pt_scene_set_embree_config(s, "threads=1") == PT_OK && pt_scene_set_backend(s, PT_BACKEND_EMBREE) == PT_OK &&
                     pt_scene_commit(s) == PT_OK && (pt_scene_get_info(s, &info), info.backend == PT_BACKEND_EMBREE),
              "threads=1: %s", pt_scene_error_message(s));
        CHECK(t, pt_scene_set_embree_config(s, NULL) == PT_OK, "NULL configuration");
    }
    pt_scene_destroy(s);
}

static void embree_auto_and_rebuild(test_ctx *t)
{
    /* AUTO: Embree from PDFTRACE_EMBREE_MIN_PRIMS primitives on and the built-in BVH below */
    int n[2], k;
    n[0] = PDFTRACE_EMBREE_MIN_PRIMS - 1;
    n[1] = PDFTRACE_EMBREE_MIN_PRIMS;
    for (k = PDFTRACE_EMBREE_MIN_PRIMS > 0 ? 0 : 1; k < 2; k++) {
        pt_scene *s = pt_scene_create();
        pt_scene_info info;
        int m = s ? pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)) : -1, i, rc = m;
        for (i = 0; i < n[k] && rc >= 0; i++) { /* a triangle of the same extent as a 0.25 sphere */
            float cx = (float)(i % 100), cy = (float)(i / 100);
            rc = pt_scene_add_triangle(s, pt_v3(cx - 0.25f, cy - 0.25f, -0.25f), pt_v3(cx + 0.25f, cy - 0.25f, -0.25f),
                                       pt_v3(cx, cy + 0.25f, -0.25f), m);
        }
        if (rc >= 0) rc = pt_scene_commit(s);
        if (CHECK(t, rc >= 0, "scene of %d triangles: %d", n[k], rc)) {
            pt_ray r;
            pt_hit h;
            pt_scene_get_info(s, &info);
            CHECK(t, info.backend == (k ? PT_BACKEND_EMBREE : PT_BACKEND_BUILTIN), "AUTO with %d primitives chose %d",
                  n[k], (int)info.backend);
            r.origin = pt_v3(7, 3, -10);
            r.dir = pt_v3(0, 0, 1);
            if (n[k] > 307)
                CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) == 1 && h.primitive == 307 && fabsf(h.t - 9.75f) < 1e-5f,
                      "AUTO, %d primitives: wrong hit", n[k]);
            test_note(t, "AUTO, %d primitives: %s, build %.3f s, %zu bytes", n[k], k ? "Embree" : "built-in",
                      info.build_seconds, info.accel_bytes);
        }
        pt_scene_destroy(s);
    }
    /* scenes mostly of spheres: the built-in BVH at any size below PDFTRACE_EMBREE_MIN_PRIMS
       (since one primitive per leaf, it is the faster one on small scenes: bench/out/bvh.md),
       unless a build sets PDFTRACE_EMBREE_SMALL_PRIMS: then Embree below it */
    for (k = 0; k < 2; k++) {
        int count = PDFTRACE_EMBREE_SMALL_PRIMS > 1 ? PDFTRACE_EMBREE_SMALL_PRIMS - 1 + k : 3 + 28 * k, i, rc;
        pt_scene *s = pt_scene_create();
        pt_scene_info info;
        int m = s ? pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)) : -1;
        for (i = 0, rc = m; i < count && rc >= 0; i++) rc = pt_scene_add_sphere(s, pt_v3((float)i, 0, 0), 0.25f, m);
        if (rc >= 0) rc = pt_scene_commit(s);
        if (CHECK(t, rc >= 0, "scene of %d spheres: %d", count, rc)) {
            pt_scene_get_info(s, &info);
            CHECK(t, info.backend == (count < PDFTRACE_EMBREE_SMALL_PRIMS ? PT_BACKEND_EMBREE : PT_BACKEND_BUILTIN),
                  "AUTO with %d spheres chose %d", count, (int)info.backend);
        }
        pt_scene_destroy(s);
    }
    /* a change after an Embree commit: commit again rebuilds, the new shape is hit */
    {
        pt_scene *s = te_small_scene();
        pt_ray r;
        pt_hit h;
        int m, rc;
        if (!CHECK(t, s != NULL, "scene")) return;
        m = pt_scene_add_lambertian(s, pt_v3(0.2f, 0.2f, 0.2f));
        rc = pt_scene_set_backend(s, PT_BACKEND_EMBREE);
        if (rc == PT_OK) rc = pt_scene_commit(s);
        r.origin = pt_v3(0, 1, -10);
        r.dir = pt_v3(0, 0, 1);
        CHECK(t, rc == PT_OK && pt_scene_intersect(s, r, INFINITY, &h) == 1 && h.primitive == 0 && fabsf(h.t - 9) < 1e-5f,
              "Embree: the sphere was not hit at t = 9");
        rc = pt_scene_add_quad(s, pt_v3(-1, 0, -6), pt_v3(2, 0, 0), pt_v3(0, 2, 0), m);
        CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) == PT_ERROR_INVALID_STATE, "changed scene still answers");
        CHECK(t, rc >= 0 && pt_scene_commit(s) == PT_OK && pt_scene_intersect(s, r, INFINITY, &h) == 1 &&
                     (int)h.primitive == rc && fabsf(h.t - 4) < 1e-5f,
              "after the re-commit the new quad is not hit at t = 4");
        CHECK(t, pt_scene_occluded(s, r, 3.9f) == 0 && pt_scene_occluded(s, r, 4.1f) == 1, "occlusion around the new quad");
        /* switching back to the built-in BVH and again to Embree */
        CHECK(t, pt_scene_set_backend(s, PT_BACKEND_BUILTIN) == PT_OK && pt_scene_commit(s) == PT_OK &&
                     pt_scene_intersect(s, r, INFINITY, &h) == 1 && (int)h.primitive == rc,
              "switch to the built-in BVH");
        CHECK(t, pt_scene_set_backend(s, PT_BACKEND_EMBREE) == PT_OK && pt_scene_commit(s) == PT_OK &&
                     pt_scene_intersect(s, r, INFINITY, &h) == 1 && (int)h.primitive == rc,
              "switch back to Embree");
        pt_scene_destroy(s);
    }
    /* an empty scene with Embree: commits, nothing is hit */
    {
        pt_scene *s = pt_scene_create();
        pt_ray r;
        pt_hit h;
        pt_scene_info info;
        r.origin = pt_v3(0, 0, 0);
        r.dir = pt_v3(0, 0, 1);
        CHECK(t, s && pt_scene_set_backend(s, PT_BACKEND_EMBREE) == PT_OK && pt_scene_commit(s) == PT_OK &&
                     pt_scene_intersect(s, r, INFINITY, &h) == 0 && pt_scene_occluded(s, r, INFINITY) == 0,
              "empty Embree scene");
        if (s) {
            pt_scene_get_info(s, &info);
            CHECK(t, info.backend == PT_BACKEND_EMBREE, "empty scene: backend %d", (int)info.backend);
        }
        pt_scene_destroy(s);
    }
}

#ifdef TE_HAVE_MXCSR
/* The floating-point state seen on the render threads: a guide callback runs there. */
typedef struct te_fp { volatile unsigned seen_or, seen_and; } te_fp;
static int te_guide(void *user, const pt_shading_point *sp, pt_pdf *out)
{
    te_fp *f = (te_fp *)user;
    unsigned csr = _mm_getcsr() & 0x8040u;
    (void)sp;
    (void)out;
    f->seen_or |= csr;   /* racy between threads, but every thread writes the same bits */
    f->seen_and &= csr;
    return 0;
}
static void te_serial_for(void *user, int count, pt_job_fn job, void *data)
{
    int i;
    (void)user;
    for (i = 0; i < count; i++) job(data, i);
}
#endif

static void embree_fp_state(test_ctx *t)
{
#ifdef TE_HAVE_MXCSR
    int be, mode;
    unsigned before = _mm_getcsr();
    for (be = PT_BACKEND_BUILTIN; be <= PT_BACKEND_EMBREE; be++) {
        pt_scene *s = te_small_scene();
        if (!CHECK(t, s && pt_scene_set_backend(s, (pt_backend)be) == PT_OK && pt_scene_commit(s) == PT_OK, "scene"))
            continue;
        for (mode = 0; mode < 3; mode++) { /* threads, one thread, the host's parallel_for */
            te_fp f;
            pt_image img;
            pt_render_desc d = tu_base_desc(16, 16, 2, 1);
            int rc;
            d.camera.look_from = pt_v3(0, 2, -8);
            d.camera.look_at = pt_v3(0, 1, 0);
            d.guide = te_guide;
            d.guide_user = &f;
            d.threads = mode == 0 ? 2 : 1;
            if (mode == 2) d.parallel_for = te_serial_for;
            f.seen_or = 0u;
            f.seen_and = 0x8040u;
            memset(&img, 0, sizeof img);
            rc = pt_render_image(s, &d, &img, NULL);
            CHECK(t, rc == PT_OK, "render: %d", rc);
            if (be == PT_BACKEND_EMBREE)
                CHECK(t, f.seen_and == 0x8040u, "Embree, mode %d: FTZ/DAZ not set on a render thread (%#x)", mode, f.seen_or);
            else
                CHECK(t, f.seen_or == 0u, "built-in, mode %d: FTZ/DAZ set on a render thread (%#x)", mode, f.seen_or);
            /* the control bits (DAZ, exception masks, rounding, FTZ), not the sticky flags 0-5 that
               any float code raises */
            CHECK(t, (_mm_getcsr() & 0xffc0u) == (before & 0xffc0u),
                  "backend %d, mode %d: the caller's MXCSR controls changed (%#x -> %#x)", be, mode, before, _mm_getcsr());
            pt_image_free(&img);
        }
        pt_scene_destroy(s);
    }
    test_note(t, "FTZ/DAZ on in Embree tiles only (threads, one thread, host parallel_for); caller's MXCSR %#x kept",
              before);
#else
    test_skip(t, "no SSE control register on this target");
#endif
}

/* A host that traps FE_INVALID and FE_DIVBYZERO: Embree's own code produces inf and NaN on
   purpose (1/0 for zero direction components, 0 * inf in slab tests) and raised SIGFPE inside
   rtcIntersect1 before pdftrace masked exceptions around its Embree calls. A regression kills
   the runner with SIGFPE (which fails make test). */
static void embree_fp_traps(test_ctx *t)
{
#if defined(__GLIBC__) && defined(FE_INVALID) && defined(FE_DIVBYZERO)
    pt_scene *s = te_small_scene();
    pt_rng rng;
    pt_image img;
    pt_render_desc d = tu_base_desc(24, 24, 4, 3);
    long hits = 0, i;
    int rc, old;
    if (!CHECK(t, s != NULL, "scene")) return;
    rc = pt_scene_add_box(s, pt_v3(-3, -1, -3), pt_v3(3, 5, 3), pt_scene_add_lambertian(s, pt_v3(0.3f, 0.3f, 0.3f)));
    old = feenableexcept(FE_INVALID | FE_DIVBYZERO);
    if (!CHECK(t, old != -1, "feenableexcept failed")) { pt_scene_destroy(s); return; }
    if (rc >= 0) rc = pt_scene_set_backend(s, PT_BACKEND_EMBREE);
    if (rc >= 0) rc = pt_scene_commit(s); /* the build, on this thread too */
    pt_rng_seed(&rng, 77, 1);
    for (i = 0; i < 20000 && rc >= 0; i++) {
        pt_ray r;
        pt_hit h;
        int ax = (int)(i % 3);
        r.origin = pt_v3((float)((int)(pt_rng_float(&rng) * 6) - 3), (float)((int)(pt_rng_float(&rng) * 6) - 1),
                         (float)((int)(pt_rng_float(&rng) * 6) - 3));
        r.dir = (i & 1) ? pt_v3(ax == 0 ? 1.0f : 0.0f, ax == 1 ? -1.0f : 0.0f, ax == 2 ? 1.0f : 0.0f)
                        : pt_v3(pt_rng_float(&rng) - 0.5f, pt_rng_float(&rng) - 0.5f, pt_rng_float(&rng) - 0.5f);
        hits += pt_scene_intersect(s, r, INFINITY, &h) == 1;
        hits += pt_scene_occluded(s, r, 2.0f) == 1;
    }
    d.camera.look_from = pt_v3(0, 2, -2.5f);
    d.camera.look_at = pt_v3(0, 1, 0);
    d.threads = 1; /* this thread, with the traps */
    memset(&img, 0, sizeof img);
    if (rc >= 0) rc = pt_render_image(s, &d, &img, NULL);
    fedisableexcept(FE_INVALID | FE_DIVBYZERO);
    if (old > 0) feenableexcept(old);
    CHECK(t, rc == PT_OK && hits > 20000, "traps on: %d, %ld hits", rc, hits);
    test_note(t, "FE_INVALID|FE_DIVBYZERO trapping: Embree build, 40000 queries (half axis-aligned) and a render ran");
    pt_image_free(&img);
    pt_scene_destroy(s);
#else
    test_skip(t, "no feenableexcept (not glibc)");
#endif
}

/* The batched integrator with the Embree backend (its closest hits and shadow rays as Embree
   streams, section 5b) renders the scalar integrator's film bit for bit: quads and spheres (user
   geometry, whose callbacks then take packets of rays), glass, triangles (a mesh), delta and many
   lights, under MIS and light sampling, independent and Sobol numbers. */
static void embree_batched_bit_identical(test_ctx *t)
{
#ifdef PDFTRACE_EMBREE
    static const char *const scenes[] = { "scenes/cornell.scene", "scenes/mesh.scene", "scenes/lights.scene" };
    const int ns = (int)(sizeof scenes / sizeof scenes[0]);
    int i, c, renders = 0;
    char err[512];
    for (i = 0; i < ns; ++i) {
        pt_scenefile sf;
        pt_scene *s = NULL;
        pt_render_desc base;
        if (!CHECK(t, pt_scenefile_load(scenes[i], &sf, err, sizeof err) == PT_OK, "%s: %s", scenes[i], err)) continue;
        if (!CHECK(t, pt_scenefile_build(&sf, &s, &base, err, sizeof err) == PT_OK, "%s: %s", scenes[i], err)) {
            pt_scenefile_free(&sf);
            continue;
        }
        pt_scenefile_free(&sf);
        if (!CHECK(t, pt_scene_set_backend(s, PT_BACKEND_EMBREE) == PT_OK && pt_scene_commit(s) == PT_OK, "%s: Embree: %s",
                   scenes[i], pt_scene_error_message(s))) {
            pt_scene_destroy(s);
            continue;
        }
        base.width = 24;
        base.height = 18;
        base.samples_per_pixel = 8;
        base.seed = 91;
        base.max_depth = base.max_depth > 8 ? 8 : base.max_depth;
        for (c = 0; c < 2; ++c) {
            pt_render_desc d = base, e;
            pt_film a, b;
            pt_render_stats sa, sb;
            d.strategy = c ? PT_STRATEGY_LIGHT : PT_STRATEGY_MIS;
            d.sampler = c ? PT_SAMPLER_SOBOL : PT_SAMPLER_INDEPENDENT;
            d.integrator = PT_INTEGRATOR_SCALAR;
            d.threads = 2;
            e = d;
            e.integrator = PT_INTEGRATOR_BATCHED;
            e.threads = 1;
            memset(&a, 0, sizeof a);
            memset(&b, 0, sizeof b);
            if (tu_render_into(t, s, &d, &a, &sa, "scalar") && tu_render_into(t, s, &e, &b, &sb, "batched")) {
                CHECK(t, tu_film_equal(&a, &b), "%s, %s: Embree, the batched film differs from the scalar one", scenes[i],
                      c ? "light sobol" : "MIS");
                CHECK(t, sb.batched_samples == sb.samples && sb.shadow_rays == sa.shadow_rays && sb.shadow_rays > 0,
                      "%s: batched samples %llu of %llu, shadow rays %llu and %llu", scenes[i],
                      (unsigned long long)sb.batched_samples, (unsigned long long)sb.samples,
                      (unsigned long long)sa.shadow_rays, (unsigned long long)sb.shadow_rays);
                renders += 2;
            }
#ifndef PDFTRACE_EMBREE4
            if (c == 0) { /* below PDFTRACE_EMBREE_MIN_PRIMS the default stays SCALAR */
                pt_film f;
                pt_render_stats sd;
                d.integrator = PT_INTEGRATOR_DEFAULT;
                memset(&f, 0, sizeof f);
                if (tu_render_into(t, s, &d, &f, &sd, "default"))
                    CHECK(t, tu_film_equal(&a, &f) && sd.batched_samples == 0, "%s: Embree, default: %s, %llu of %llu batched",
                          scenes[i], tu_film_equal(&a, &f) ? "same film" : "the film differs",
                          (unsigned long long)sd.batched_samples, (unsigned long long)sd.samples);
                pt_film_free(&f);
                renders++;
            }
#endif
            pt_film_free(&a);
            pt_film_free(&b);
        }
        pt_scene_destroy(s);
    }
    {   /* coincident surfaces: every ray on the overlap is a tie (two quads, a triangle on a quad) */
        pt_scene *s = te_small_scene();
        pt_scene_info info;
        pt_render_desc d = tu_base_desc(24, 24, 4, 1), e;
        pt_film a, b;
        int red = s ? pt_scene_add_lambertian(s, pt_v3(0.7f, 0.1f, 0.1f)) : -1;
        int green = s ? pt_scene_add_lambertian(s, pt_v3(0.1f, 0.7f, 0.1f)) : -1;
        if (CHECK(t, s && red >= 0 && green >= 0 && pt_scene_add_quad(s, pt_v3(-3, 0, -3), pt_v3(6, 0, 0), pt_v3(0, 0, 6), red) >= 0 &&
                         pt_scene_add_quad(s, pt_v3(-4, 0, -2), pt_v3(5, 0, 0), pt_v3(0, 0, 5), green) >= 0 &&
                         pt_scene_add_triangle(s, pt_v3(-2, 0, -2), pt_v3(-2, 0, 2), pt_v3(2, 0, 0), green) >= 0,
                  "coincident scene")) {
            int k;
            pt_render_stats sd;
            /* 5000 small triangles behind the camera: a scene where AUTO picks Embree, and the
               default integrator (with Embree 3) is BATCHED */
            for (k = 0; k < 5000; ++k)
                pt_scene_add_triangle(s, pt_v3((float)(k % 100) * 0.1f, 9, 8 + (float)(k / 100) * 0.1f),
                                      pt_v3((float)(k % 100) * 0.1f + 0.05f, 9, 8 + (float)(k / 100) * 0.1f),
                                      pt_v3((float)(k % 100) * 0.1f, 9.05f, 8 + (float)(k / 100) * 0.1f), red);
            d.camera.look_from = pt_v3(0.3f, 6, -4);
            d.camera.look_at = pt_v3(0, 0, 0);
            d.integrator = PT_INTEGRATOR_SCALAR;
            e = d;
            e.integrator = PT_INTEGRATOR_DEFAULT;
            memset(&a, 0, sizeof a);
            memset(&b, 0, sizeof b);
            if (CHECK(t, pt_scene_set_backend(s, PT_BACKEND_AUTO) == PT_OK && pt_scene_commit(s) == PT_OK &&
                             pt_scene_get_info(s, &info) == PT_OK && info.backend == PT_BACKEND_EMBREE,
                      "coincident scene: AUTO did not choose Embree") &&
                tu_render_into(t, s, &d, &a, NULL, "scalar") && tu_render_into(t, s, &e, &b, &sd, "default")) {
                CHECK(t, tu_film_equal(&a, &b), "coincident surfaces: Embree, the batched film differs from the scalar one");
#ifndef PDFTRACE_EMBREE4
                CHECK(t, sd.batched_samples == sd.samples, "AUTO with Embree: the default integrator took %llu of %llu samples batched",
                      (unsigned long long)sd.batched_samples, (unsigned long long)sd.samples);
#endif
            }
            renders += 2;
            pt_film_free(&a);
            pt_film_free(&b);
        }
        pt_scene_destroy(s);
    }
    test_note(t, "%d Embree renders of %d scenes and coincident surfaces: batched (streams) = scalar (per ray) bit for bit",
              renders, ns);
#else
    test_skip(t, "Embree not compiled in (make EMBREE=1)");
#endif
}

/* ---- the scene suite: same image within noise ---- */
#ifndef TE_SCENE_DIR
#define TE_SCENE_DIR "scenes"
#endif
#define TE_RX 4
#define TE_RY 4

static void embree_scene_images(test_ctx *t)
{
    static const char *names[] = { "cornell", "cornell-diffuse", "direct-quad", "direct-sphere", "mirror", "glass",
                                   "checker", "mesh", "lights-direct", "lights", "env", "rough-metal", "rough-glass",
                                   "rough-plastic", "textured" };
    const int ns = (int)(sizeof names / sizeof names[0]);
    char listing[4096], summary[600] = "";
    int k, listed = tu_dir_entries(TE_SCENE_DIR, listing, sizeof listing), nscene_files = 0;
    int comparisons = ns * TE_RX * TE_RY * 3;
    double alpha = tu_sidak(0.01, comparisons), zc = tu_z_two_sided(alpha), zmax_all = 0;
    /* every scene file of the suite is in the list above (a new one must be added) */
    if (CHECK(t, listed > 0, "cannot list %s/ (run from the repository root)", TE_SCENE_DIR)) {
        char *p = listing;
        while (*p) {
            char *end = strchr(p, ' '), name[256];
            size_t len = end ? (size_t)(end - p) : strlen(p);
            if (len < sizeof name) {
                memcpy(name, p, len);
                name[len] = '\0';
                if (len > 6 && strcmp(name + len - 6, ".scene") == 0) {
                    int found = 0;
                    name[len - 6] = '\0';
                    for (k = 0; k < ns; k++) found |= strcmp(names[k], name) == 0;
                    CHECK(t, found, "scenes/%s.scene is not in this test's list", name);
                    nscene_files++;
                }
            }
            if (!end) break;
            p = end + 1;
        }
        CHECK(t, nscene_files == ns, "%d scene files, the test lists %d", nscene_files, ns);
    }
    for (k = 0; k < ns; k++) {
        char path[512], err[512];
        pt_scenefile desc;
        pt_scene *s = NULL;
        pt_render_desc rd;
        pt_film film[2];
        tu_region reg[2][TE_RX * TE_RY];
        int be, rc, w, h, i, ch, fails = 0;
        double zmax = 0;
        pt_scene_info info;
        memset(film, 0, sizeof film);
        snprintf(path, sizeof path, "%s/%s.scene", TE_SCENE_DIR, names[k]);
        rc = pt_scenefile_load(path, &desc, err, sizeof err);
        if (!CHECK(t, rc == PT_OK, "%s: %s", path, err)) continue;
        rc = pt_scenefile_build(&desc, &s, &rd, err, sizeof err);
        pt_scenefile_free(&desc);
        if (!CHECK(t, rc == PT_OK, "%s: build: %s", path, err)) continue;
        /* small and quick: 48 pixels on the long side, 24 samples per pixel */
        w = rd.width >= rd.height ? 48 : (48 * rd.width + rd.height / 2) / rd.height;
        h = rd.width >= rd.height ? (48 * rd.height + rd.width / 2) / rd.width : 48;
        rd.width = w < 8 ? 8 : w;
        rd.height = h < 8 ? 8 : h;
        rd.samples_per_pixel = 24;
        rd.samples_per_pass = 24;
        for (be = 0; be < 2 && rc == PT_OK; be++) {
            pt_render_stats st;
            rc = pt_scene_set_backend(s, be ? PT_BACKEND_EMBREE : PT_BACKEND_BUILTIN);
            if (rc == PT_OK) rc = pt_scene_commit(s);
            if (!CHECK(t, rc == PT_OK, "%s: backend %d: %s", names[k], be, pt_scene_error_message(s))) break;
            pt_scene_get_info(s, &info);
            CHECK(t, (int)info.backend == (be ? PT_BACKEND_EMBREE : PT_BACKEND_BUILTIN), "%s: backend %d", names[k],
                  (int)info.backend);
            rd.seed = 1000u + 17u * (uint64_t)k + (uint64_t)be; /* independent images */
            rc = pt_film_init(&film[be], rd.width, rd.height);
            if (rc == PT_OK) rc = pt_render(s, &rd, &film[be], &st);
            if (!CHECK(t, rc == PT_OK, "%s: render %d: %d", names[k], be, rc)) break;
            CHECK(t, st.nonfinite_samples == 0, "%s: %llu NaN/Inf samples", names[k],
                  (unsigned long long)st.nonfinite_samples);
            if (!CHECK(t, tu_film_regions(&film[be], TE_RX, TE_RY, reg[be]), "%s: regions", names[k])) rc = -1;
        }
        if (rc == PT_OK) {
            for (i = 0; i < TE_RX * TE_RY; i++)
                for (ch = 0; ch < 3; ch++) {
                    double a = reg[0][i].mean[ch], b = reg[1][i].mean[ch];
                    double se = sqrt(reg[0][i].se[ch] * reg[0][i].se[ch] + reg[1][i].se[ch] * reg[1][i].se[ch]);
                    double z = tu_z_floor(a, b, se, TU_FLOAT_FLOOR * fmax(fabs(a), fabs(b)));
                    if (z > zmax) zmax = z;
                    if (z > zc) {
                        fails++;
                        CHECK(t, 0, "%s: region %d channel %d: built-in %.6g +- %.2g, Embree %.6g +- %.2g, z %.2f > %.2f",
                              names[k], i, ch, a, reg[0][i].se[ch], b, reg[1][i].se[ch], z, zc);
                    }
                }
            if (zmax > zmax_all) zmax_all = zmax;
            {
                size_t len = strlen(summary);
                snprintf(summary + len, sizeof summary - len, "%s%s z %.2f", len ? ", " : "", names[k], zmax);
            }
        }
        (void)fails;
        pt_film_free(&film[0]);
        pt_film_free(&film[1]);
        pt_scene_destroy(s);
    }
    test_note(t, "%d scenes x %d regions x 3 channels, Sidak alpha 0.01 -> |z| <= %.2f; max z %.2f (%s)", ns,
              TE_RX * TE_RY, zc, zmax_all, summary);
}

const test_case test_embree_cases[] = {
    TEST_CASE(embree_backend_errors),
    TEST_CASE(embree_device_errors),
    TEST_CASE(embree_auto_and_rebuild),
    TEST_CASE(embree_fp_state),
    TEST_CASE(embree_fp_traps),
    TEST_CASE(embree_first_hits),
    TEST_CASE(embree_scene_images),
    TEST_CASE(embree_batched_bit_identical),
    TEST_END
};

#endif /* PDFTRACE_EMBREE */
