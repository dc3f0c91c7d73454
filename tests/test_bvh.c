/* test_bvh.c - section 5 of pdftrace.h: the BVH built by pt_scene_commit.

   On several random scenes (spheres, quads, triangles, meshes, boxes, shapes under transforms, and
   a scene of integer-aligned boxes hit by axis-aligned rays, where slab tests meet 0 * inf),
   pt_scene_intersect must agree with pt_scene_intersect_brute_force on 20000 rays each: the same
   hit/miss, t within 1e-5 relative, the same primitive (distinct primitives only at an exact tie)
   and material; and pt_scene_occluded must agree with both. Deterministic (fixed seeds). */
#define _POSIX_C_SOURCE 200809L /* setenv, unsetenv: PDFTRACE_SIMD */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct bvh_stats { long rays, hits, ties, bad_hit, bad_t, bad_prim, bad_fields, bad_occ, bad_tmax; } bvh_stats;

static void compare_ray(const pt_scene *s, pt_ray r, float tmax, bvh_stats *st, char *example, size_t exsize)
{
    pt_hit hb, hf;
    int b, f, occ;
    memset(&hb, 0, sizeof hb);
    memset(&hf, 0, sizeof hf);
    b = pt_scene_intersect(s, r, tmax, &hb);
    f = pt_scene_intersect_brute_force(s, r, tmax, &hf);
    occ = pt_scene_occluded(s, r, tmax);
    st->rays++;
    if (b != f) {
        if (st->bad_hit++ == 0)
            snprintf(example, exsize, "ray (%.9g %.9g %.9g) + t (%.9g %.9g %.9g): BVH %d, brute force %d (t %.9g)",
                     r.origin.x, r.origin.y, r.origin.z, r.dir.x, r.dir.y, r.dir.z, b, f, f == 1 ? hf.t : hb.t);
        return;
    }
    if (occ != f) st->bad_occ++;
    if (f != 1) return;
    st->hits++;
    if (fabs(hb.t - hf.t) > 1e-5 * hf.t) {
        if (st->bad_t++ == 0 && st->bad_hit == 0)
            snprintf(example, exsize, "t: BVH %.9g, brute force %.9g", hb.t, hf.t);
    }
    if (hb.primitive != hf.primitive) {
        if (fabs(hb.t - hf.t) <= 1e-6 * hf.t) st->ties++;
        else st->bad_prim++;
    } else {
        dv3 p = dadd(dv_from(r.origin), dscale(dv_from(r.dir), hb.t));
        double scale = dlen(dv_from(r.origin)) + hb.t * dlen(dv_from(r.dir));
        if (hb.material != hf.material || dlen(dsub(dv_from(hb.point), p)) > 1e-5 * scale ||
            fabs(dlen(dv_from(hb.geometric_normal)) - 1) > 1e-5 || !(hb.t > 0 && hb.t < tmax))
            st->bad_fields++;
    }
    /* occlusion and closest hit just before / after the hit */
    if (pt_scene_occluded(s, r, hf.t * 0.999f) != 0 || pt_scene_occluded(s, r, hf.t * 1.001f) != 1) st->bad_occ++;
    {
        pt_hit h2;
        if (pt_scene_intersect(s, r, hf.t * 0.999f, &h2) != 0 || pt_scene_intersect(s, r, hf.t * 1.001f, &h2) != 1)
            st->bad_tmax++;
    }
}

/* This section tests the built-in BVH: pin it, whatever AUTO would choose with Embree compiled
   in (section 5b; its own tests are in test_embree.c). */
static int tb_commit_builtin(pt_scene *s)
{
    int rc = pt_scene_set_backend(s, PT_BACKEND_BUILTIN);
    return rc == PT_OK ? pt_scene_commit(s) : rc;
}

static void report(test_ctx *t, const char *name, const bvh_stats *st, const char *example, const pt_scene *s)
{
    pt_scene_info info;
    pt_scene_get_info(s, &info);
    CHECK(t, st->bad_hit == 0, "%s: %ld of %ld rays disagree on hit/miss; %s", name, st->bad_hit, st->rays, example);
    CHECK(t, st->bad_t == 0, "%s: %ld hits with different t (rel 1e-5); %s", name, st->bad_t, example);
    CHECK(t, st->bad_prim == 0, "%s: %ld hits on a different primitive (not a tie)", name, st->bad_prim);
    CHECK(t, st->bad_fields == 0, "%s: %ld hits with wrong material/point/normal/t range", name, st->bad_fields);
    CHECK(t, st->bad_occ == 0, "%s: pt_scene_occluded inconsistent %ld times", name, st->bad_occ);
    CHECK(t, st->bad_tmax == 0, "%s: tmax not respected %ld times", name, st->bad_tmax);
    CHECK(t, info.bvh_node_count >= 1 && info.bvh_max_depth <= 64, "%s: %u BVH nodes, depth %u", name,
          (unsigned)info.bvh_node_count, (unsigned)info.bvh_max_depth);
    CHECK(t, st->hits > st->rays / 10, "%s: only %ld of %ld rays hit anything (test too weak)", name, st->hits, st->rays);
    test_note(t, "%s: %ld/%ld hits, %ld ties, %u prims, depth %u", name, st->hits, st->rays, st->ties,
              (unsigned)info.primitive_count, (unsigned)info.bvh_max_depth);
}

static dv3 rand_in(pt_rng *r, double h) { return dv((2 * tu_rand(r) - 1) * h, (2 * tu_rand(r) - 1) * h, (2 * tu_rand(r) - 1) * h); }

/* Random rays: origins in a box of half-size h, random directions of random length, some axis
   aligned (zero components), some with finite tmax. */
static void random_rays(const pt_scene *s, pt_rng *rng, double h, long n, bvh_stats *st, char *ex, size_t exsize)
{
    long i;
    for (i = 0; i < n; i++) {
        pt_ray r;
        float tmax = INFINITY;
        dv3 d;
        if (i % 5 == 0) {
            int axis = (int)(tu_rand(rng) * 3);
            double sgn = tu_rand(rng) < 0.5 ? -1 : 1;
            d = dv(axis == 0 ? sgn : 0, axis == 1 ? sgn : 0, axis == 2 ? sgn : 0);
        } else {
            d = tu_rand_dir(rng);
        }
        d = dscale(d, 0.1 + 5 * tu_rand(rng));
        r.origin = dv_to(rand_in(rng, h));
        r.dir = dv_to(d);
        if (i % 7 == 0) tmax = (float)(h * tu_rand(rng) / dlen(d));
        compare_ray(s, r, tmax, st, ex, exsize);
    }
}

static int add_heightfield(pt_scene *s, int n, double half, dv3 off, int material)
{
    float *pos = (float *)malloc(sizeof(float) * 3 * (size_t)n * n), *nrm = (float *)malloc(sizeof(float) * 3 * (size_t)n * n);
    uint32_t *idx = (uint32_t *)malloc(sizeof(uint32_t) * 6 * (size_t)(n - 1) * (n - 1));
    pt_mesh_desc md;
    int i, j, k = 0, rc;
    if (!pos || !nrm || !idx) { free(pos); free(nrm); free(idx); return PT_ERROR_OUT_OF_MEMORY; }
    for (j = 0; j < n; j++) {
        for (i = 0; i < n; i++) {
            double x = -half + 2 * half * i / (n - 1), z = -half + 2 * half * j / (n - 1);
            double y = 0.8 * sin(0.9 * x) * cos(0.7 * z);
            dv3 nn = dnorm(dv(-0.8 * 0.9 * cos(0.9 * x) * cos(0.7 * z), 1, 0.8 * 0.7 * sin(0.9 * x) * sin(0.7 * z)));
            float *p = pos + 3 * (j * n + i), *q = nrm + 3 * (j * n + i);
            p[0] = (float)(x + off.x); p[1] = (float)(y + off.y); p[2] = (float)(z + off.z);
            q[0] = (float)nn.x; q[1] = (float)nn.y; q[2] = (float)nn.z;
        }
    }
    for (j = 0; j < n - 1; j++) {
        for (i = 0; i < n - 1; i++) {
            uint32_t a = (uint32_t)(j * n + i), b = a + 1, c = a + (uint32_t)n, d = c + 1;
            idx[k++] = a; idx[k++] = c; idx[k++] = b;
            idx[k++] = b; idx[k++] = c; idx[k++] = d;
        }
    }
    memset(&md, 0, sizeof md);
    md.positions = pos;
    md.vertex_count = (uint32_t)(n * n);
    md.indices = idx;
    md.triangle_count = (uint32_t)(k / 3);
    md.normals = nrm;
    md.material = material;
    rc = pt_scene_add_mesh(s, &md);
    free(pos);
    free(nrm);
    free(idx);
    return rc;
}

static int add_uv_sphere(pt_scene *s, dv3 c, double R, int rings, int segs, int material)
{
    int nv = 2 + (rings - 1) * segs, nt = 2 * segs * (rings - 1), i, j, k = 0, rc;
    float *pos = (float *)malloc(sizeof(float) * 3 * (size_t)nv);
    uint32_t *idx = (uint32_t *)malloc(sizeof(uint32_t) * 3 * (size_t)nt);
    pt_mesh_desc md;
    if (!pos || !idx) { free(pos); free(idx); return PT_ERROR_OUT_OF_MEMORY; }
    pos[0] = (float)c.x; pos[1] = (float)(c.y + R); pos[2] = (float)c.z;
    pos[3] = (float)c.x; pos[4] = (float)(c.y - R); pos[5] = (float)c.z;
    for (i = 1; i < rings; i++) {
        double th = TU_PI * i / rings;
        for (j = 0; j < segs; j++) {
            double ph = 2 * TU_PI * j / segs;
            float *p = pos + 3 * (2 + (i - 1) * segs + j);
            p[0] = (float)(c.x + R * sin(th) * cos(ph)); p[1] = (float)(c.y + R * cos(th)); p[2] = (float)(c.z + R * sin(th) * sin(ph));
        }
    }
    for (j = 0; j < segs; j++) {
        uint32_t a = (uint32_t)(2 + j), b = (uint32_t)(2 + (j + 1) % segs);
        idx[k++] = 0; idx[k++] = b; idx[k++] = a;
        a = (uint32_t)(2 + (rings - 2) * segs + j); b = (uint32_t)(2 + (rings - 2) * segs + (j + 1) % segs);
        idx[k++] = 1; idx[k++] = a; idx[k++] = b;
    }
    for (i = 1; i < rings - 1; i++) {
        for (j = 0; j < segs; j++) {
            uint32_t a = (uint32_t)(2 + (i - 1) * segs + j), b = (uint32_t)(2 + (i - 1) * segs + (j + 1) % segs);
            uint32_t c2 = a + (uint32_t)segs, d = b + (uint32_t)segs;
            idx[k++] = a; idx[k++] = b; idx[k++] = c2;
            idx[k++] = b; idx[k++] = d; idx[k++] = c2;
        }
    }
    memset(&md, 0, sizeof md);
    md.positions = pos;
    md.vertex_count = (uint32_t)nv;
    md.indices = idx;
    md.triangle_count = (uint32_t)(k / 3);
    md.material = material;
    rc = pt_scene_add_mesh(s, &md);
    free(pos);
    free(idx);
    return rc;
}

static void bvh_random_scenes(test_ctx *t)
{
    const char *names[4] = { "300 spheres", "300 quads", "400 triangles", "mixed + meshes + transforms" };
    int k;
    for (k = 0; k < 4; k++) {
        pt_scene *s = pt_scene_create();
        pt_rng rng;
        bvh_stats st;
        char ex[256] = "";
        int m[3], i, rc = 0;
        if (!CHECK(t, s != NULL, "scene")) return;
        pt_rng_seed(&rng, 3000 + k, 1);
        m[0] = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
        m[1] = pt_scene_add_metal(s, pt_v3(0.5f, 0.5f, 0.5f), 0.2f);
        m[2] = pt_scene_add_dielectric(s, 1.5f);
        for (i = 0; i < (k == 3 ? 100 : k == 2 ? 400 : 300) && rc >= 0; i++) {
            int kind = k == 3 ? i % 3 : k, mat = m[i % 3];
            dv3 p = rand_in(&rng, 10);
            if (k == 3 && i % 10 == 0) {
                pt_transform xf = pt_transform_mul(pt_transform_translate(dv_to(rand_in(&rng, 3))),
                                                   pt_transform_mul(pt_transform_rotate(pt_normalize(dv_to(tu_rand_dir(&rng))), (float)(360 * tu_rand(&rng))),
                                                                    pt_transform_scale(pt_v3(1.5f, 1.5f, 1.5f))));
                pt_scene_set_transform(s, &xf);
            }
            if (kind == 0) rc = pt_scene_add_sphere(s, dv_to(p), (float)(0.05 + 1.2 * tu_rand(&rng)), mat);
            else if (kind == 1)
                rc = pt_scene_add_quad(s, dv_to(p), dv_to(dscale(tu_rand_dir(&rng), 0.2 + 2.5 * tu_rand(&rng))),
                                       dv_to(dscale(tu_rand_dir(&rng), 0.2 + 2.5 * tu_rand(&rng))), mat);
            else
                rc = pt_scene_add_triangle(s, dv_to(p), dv_to(dadd(p, dscale(tu_rand_dir(&rng), 0.2 + 2.5 * tu_rand(&rng)))),
                                           dv_to(dadd(p, dscale(tu_rand_dir(&rng), 0.2 + 2.5 * tu_rand(&rng)))), mat);
            pt_scene_set_transform(s, NULL);
        }
        if (k == 3) {
            if (rc >= 0) rc = add_heightfield(s, 40, 9, dv(0, -6, 0), m[0]);
            if (rc >= 0) rc = add_uv_sphere(s, dv(4, 3, -2), 2.5, 16, 24, m[1]);
            if (rc >= 0) rc = pt_scene_add_box(s, pt_v3(-6, -2, 3), pt_v3(-3, 4, 7), m[2]);
        }
        rc = rc >= 0 ? tb_commit_builtin(s) : rc;
        if (!CHECK(t, rc == PT_OK, "%s: %d %s", names[k], rc, pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        memset(&st, 0, sizeof st);
        random_rays(s, &rng, 12, 20000, &st, ex, sizeof ex);
        report(t, names[k], &st, ex, s);
        pt_scene_destroy(s);
    }
}

static void bvh_axis_aligned(test_ctx *t)
{
    /* Integer-aligned boxes and axis-aligned rays from integer and half-integer points: direction
       components of exactly 0 (1/0 = inf in slab tests; 0 * inf = NaN when the origin lies on a slab
       plane), rays in the planes of faces, hits on edges and corners. */
    pt_scene *s = pt_scene_create();
    pt_rng rng;
    bvh_stats st;
    char ex[256] = "";
    int m, i, rc = 0;
    if (!CHECK(t, s != NULL, "scene")) return;
    pt_rng_seed(&rng, 3100, 1);
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    for (i = 0; i < 60 && rc >= 0; i++) {
        int x = (int)(tu_rand(&rng) * 12) - 6, y = (int)(tu_rand(&rng) * 12) - 6, z = (int)(tu_rand(&rng) * 12) - 6;
        int sx = 1 + (int)(tu_rand(&rng) * 3), sy = 1 + (int)(tu_rand(&rng) * 3), sz = 1 + (int)(tu_rand(&rng) * 3);
        rc = pt_scene_add_box(s, pt_v3((float)x, (float)y, (float)z), pt_v3((float)(x + sx), (float)(y + sy), (float)(z + sz)), m);
    }
    rc = rc >= 0 ? tb_commit_builtin(s) : rc;
    if (!CHECK(t, rc == PT_OK, "boxes: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    memset(&st, 0, sizeof st);
    for (i = 0; i < 20000; i++) {
        pt_ray r;
        int axis = (int)(tu_rand(&rng) * 3), half = i % 2;
        float sgn = tu_rand(&rng) < 0.5f ? -1.0f : 1.0f;
        float c[3];
        int j;
        for (j = 0; j < 3; j++) c[j] = (float)((int)(tu_rand(&rng) * 16) - 8) + (half && j != axis ? 0.5f : 0.0f);
        r.origin = pt_v3(c[0], c[1], c[2]);
        if (i % 4 == 3) r.dir = pt_v3(sgn, axis == 0 ? 0.0f : sgn, axis == 2 ? 1.0f : 0.0f); /* diagonals in a plane */
        else r.dir = pt_v3(axis == 0 ? sgn : 0.0f, axis == 1 ? sgn : 0.0f, axis == 2 ? sgn : 0.0f);
        compare_ray(s, r, INFINITY, &st, ex, sizeof ex);
    }
    report(t, "integer boxes, axis-aligned rays", &st, ex, s);
    pt_scene_destroy(s);
}

static void bvh_ray_along_max_bound(test_ctx *t)
{
    /* Minimal case of the above: one quad x in [-3,-1], y in [-7,-5] at z = 3; rays along +z through
       its 3x3 grid of corner/edge/centre lines (x in {-3,-2,-1}, y in {-7,-6,-5}). Brute force counts
       the edges (watertight, inclusive); the BVH must return the same answer for all nine. */
    pt_scene *s = pt_scene_create();
    const float xs[3] = { -3, -2, -1 }, ys[3] = { -7, -6, -5 };
    int m, rc, i, j, differ = 0;
    char first[128] = "";
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    rc = pt_scene_add_quad(s, pt_v3(-3, -7, 3), pt_v3(2, 0, 0), pt_v3(0, 2, 0), m);
    rc = rc >= 0 ? tb_commit_builtin(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene")) { pt_scene_destroy(s); return; }
    for (i = 0; i < 3; i++) {
        for (j = 0; j < 3; j++) {
            pt_ray r;
            pt_hit h, hb;
            int a, b;
            r.origin = pt_v3(xs[i], ys[j], -5);
            r.dir = pt_v3(0, 0, 1);
            a = pt_scene_intersect(s, r, INFINITY, &h);
            b = pt_scene_intersect_brute_force(s, r, INFINITY, &hb);
            CHECK(t, b == 1, "brute force missed the quad at (%g, %g)", xs[i], ys[j]);
            if (a != b && differ++ == 0) snprintf(first, sizeof first, "(%g, %g): BVH %d, brute force %d", xs[i], ys[j], a, b);
        }
    }
    CHECK(t, differ == 0, "%d of 9 rays along the quad's edge/centre lines: BVH and brute force differ, first %s", differ, first);
    pt_scene_destroy(s);
}

static void bvh_rebuild_after_change(test_ctx *t)
{
    /* A shape added after commit is found after the next commit (the BVH is rebuilt). */
    pt_scene *s = pt_scene_create();
    int m, rc, id;
    pt_ray r;
    pt_hit h;
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    rc = pt_scene_add_sphere(s, pt_v3(0, 0, -10), 1, m);
    rc = rc >= 0 ? tb_commit_builtin(s) : rc;
    id = pt_scene_add_sphere(s, pt_v3(0, 0, -5), 1, m);
    rc = rc >= 0 && id >= 0 ? tb_commit_builtin(s) : -1;
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    r.origin = pt_v3(0, 0, 0);
    r.dir = pt_v3(0, 0, -1);
    CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) == 1 && h.primitive == (uint32_t)id && fabs(h.t - 4) < 1e-5,
          "after re-commit the new sphere is not the closest hit (primitive %u, t %g)", (unsigned)h.primitive, h.t);
    pt_scene_destroy(s);
}

static void bvh_denormal_extent(test_ctx *t)
{
    /* Two triangles at z = 0 and z = 1e-40: the centroids' z extent is denormal, so 16 / extent is
       inf and the binning computed 0 * inf and converted the NaN to int (undefined behaviour: the
       sanitizer runners stop here). Also 40 triangles with z steps of a few denormals (the SAH
       build, leaves of up to 8) and a pair 1e-38 apart (a normal extent whose bin scale is near
       FLT_MAX). Each must commit and agree with brute force on rays down -z and random rays. */
    static const float dz[3] = { 1e-40f, 1e-44f, 1e-38f };
    static const int count[3] = { 2, 40, 2 };
    int c;
    for (c = 0; c < 3; c++) {
        pt_scene *s = pt_scene_create();
        pt_rng rng;
        bvh_stats st;
        char ex[256] = "", name[64];
        int m, rc = PT_OK, k;
        if (!CHECK(t, s != NULL, "scene")) return;
        pt_rng_seed(&rng, 7100u + (uint64_t)c, 3u);
        m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
        for (k = 0; k < count[c] && rc >= 0; k++) {
            float z = dz[c] * (float)k;
            rc = pt_scene_add_triangle(s, pt_v3(0, 0, z), pt_v3(1, 0, z), pt_v3(0, 1, z), m);
        }
        rc = rc >= 0 ? tb_commit_builtin(s) : rc;
        snprintf(name, sizeof name, "%d triangles %g apart in z", count[c], (double)dz[c]);
        if (!CHECK(t, rc == PT_OK, "%s: commit %d %s", name, rc, pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        memset(&st, 0, sizeof st);
        for (k = 0; k < 2000; k++) {
            pt_ray r;
            r.origin = pt_v3((float)tu_rand(&rng), (float)tu_rand(&rng), 1.0f);
            r.dir = pt_v3((float)(0.2 * tu_rand(&rng) - 0.1), (float)(0.2 * tu_rand(&rng) - 0.1), -1.0f);
            compare_ray(s, r, INFINITY, &st, ex, sizeof ex);
        }
        random_rays(s, &rng, 2.0, 2000, &st, ex, sizeof ex);
        report(t, name, &st, ex, s);
        pt_scene_destroy(s);
    }
}


/* ---- run-time SIMD levels (pt_simd_level) ----
   Every level this CPU has, forced through PDFTRACE_SIMD, must give bit-identical hits (the whole
   pt_hit), the same occlusion answers and bit-identical films to the scalar level: on the mixed
   scene above with a light, on integer boxes hit along the axes, and on overlapping coplanar
   quads (most of their hits are exact ties in t, often across leaves: the hit is the quad added
   first at any width).
   Also the API cap, a bad cap and a bad PDFTRACE_SIMD (a commit error naming it). */
#define SL_RAYS 6000
static float sl_rect[120][4]; /* the coplanar quads of scene 2: x0, y0, x1, y1 (primitive id = index) */
static pt_scene *sl_scene(int kind)
{
    pt_scene *s = pt_scene_create();
    pt_rng rng;
    int m, i, rc = 0;
    if (!s) return NULL;
    pt_rng_seed(&rng, 3300u + (uint64_t)kind, 1u);
    m = pt_scene_add_lambertian(s, pt_v3(0.6f, 0.5f, 0.4f));
    for (i = 0; i < 120 && rc >= 0; i++) {
        dv3 p = rand_in(&rng, 8);
        if (kind == 0 && i % 3 == 0) rc = pt_scene_add_sphere(s, dv_to(p), (float)(0.05 + tu_rand(&rng)), m);
        else if (kind == 0 && i % 3 == 1)
            rc = pt_scene_add_triangle(s, dv_to(p), dv_to(dadd(p, dscale(tu_rand_dir(&rng), 0.5 + 2 * tu_rand(&rng)))),
                                       dv_to(dadd(p, dscale(tu_rand_dir(&rng), 0.5 + 2 * tu_rand(&rng)))), m);
        else if (kind == 0)
            rc = pt_scene_add_quad(s, dv_to(p), dv_to(dscale(tu_rand_dir(&rng), 0.5 + 2 * tu_rand(&rng))),
                                   dv_to(dscale(tu_rand_dir(&rng), 0.5 + 2 * tu_rand(&rng))), m);
        else if (kind == 1 && i < 60) {
            float x = (float)((int)(tu_rand(&rng) * 12) - 6), y = (float)((int)(tu_rand(&rng) * 12) - 6);
            float z = (float)((int)(tu_rand(&rng) * 12) - 6);
            rc = pt_scene_add_box(s, pt_v3(x, y, z), pt_v3(x + 1 + (float)(int)(3 * tu_rand(&rng)), y + 2, z + 1), m);
        } else if (kind == 2) { /* quads in the plane z = 0, overlapping: equal t for every one a ray crosses */
            float *q = sl_rect[i];
            q[0] = (float)(int)(tu_rand(&rng) * 16) - 8; q[1] = (float)(int)(tu_rand(&rng) * 16) - 8;
            /* sides 1, 2 or 4: the normal is exactly (0, 0, 1), so every quad's t is the same float */
            q[2] = q[0] + (float)(1 << (int)(3 * tu_rand(&rng))); q[3] = q[1] + (float)(1 << (int)(3 * tu_rand(&rng)));
            rc = pt_scene_add_quad(s, pt_v3(q[0], q[1], 0), pt_v3(q[2] - q[0], 0, 0), pt_v3(0, q[3] - q[1], 0), m);
        }
    }
    if (kind == 0 && rc >= 0) rc = add_heightfield(s, 24, 9, dv(0, -7, 0), m);
    if (kind == 0 && rc >= 0) rc = add_uv_sphere(s, dv(3, 2, -2), 2.0, 12, 16, m);
    if (rc >= 0) rc = pt_scene_add_sphere(s, pt_v3(0, 12, 0), 2, pt_scene_add_emitter(s, pt_v3(20, 20, 20), 0));
    if (rc < 0 || tb_commit_builtin(s) != PT_OK) { pt_scene_destroy(s); return NULL; }
    return s;
}

/* Traces the fixed rays of scene `kind` into hits[] and occ[] (pt_hit zeroed first: compared whole). */
static void sl_trace(const pt_scene *s, int kind, pt_hit *hits, int *occ)
{
    pt_rng rng;
    int i;
    pt_rng_seed(&rng, 3400u + (uint64_t)kind, 2u);
    for (i = 0; i < SL_RAYS; i++) {
        pt_ray r;
        float tmax = i % 7 == 0 ? (float)(12 * tu_rand(&rng)) : INFINITY;
        int axis = (int)(tu_rand(&rng) * 3);
        r.origin = kind == 1 ? pt_v3((float)(int)(tu_rand(&rng) * 16) - 8, (float)(int)(tu_rand(&rng) * 16) - 7.5f, 9.5f)
                             : dv_to(rand_in(&rng, 10));
        if (kind == 2) r.origin.z = 5.0f;
        {   /* towards a random point of the scene (axis-aligned for half the rays at the boxes) */
            dv3 to = rand_in(&rng, 6);
            if (kind == 2) to.z = 0;
            r.dir = kind == 1 && i % 2 ? pt_v3(axis == 0 ? 1.0f : 0.0f, axis == 1 ? -1.0f : 0.0f, axis == 2 ? -1.0f : 0.0f)
                                       : dv_to(dsub(to, dv_from(r.origin)));
        }
        memset(&hits[i], 0, sizeof hits[i]);
        if (pt_scene_intersect(s, r, tmax, &hits[i]) != 1) memset(&hits[i], 0, sizeof hits[i]);
        occ[i] = pt_scene_occluded(s, r, tmax);
    }
}

static int sl_setenv(const char *v) { return v ? setenv("PDFTRACE_SIMD", v, 1) : unsetenv("PDFTRACE_SIMD"); }

static void sl_render(test_ctx *t, const pt_scene *s, pt_film *f, const char *what)
{
    pt_render_desc d = tu_base_desc(24, 16, 2, 77);
    d.camera.look_from = pt_v3(0, 4, 16);
    d.camera.look_at = pt_v3(0, 0, 0);
    d.max_depth = 6;
    tu_render_into(t, s, &d, f, NULL, what);
}

static void bvh_simd_levels(test_ctx *t)
{
    static const unsigned width[4] = { 4, 4, 8, 16 };
    const char *saved = getenv("PDFTRACE_SIMD");
    char keep[64] = "";
    int cpu = (int)pt_simd_cpu_level(), kind, level, hits = 0, ties = 0, overlaps = 0;
    pt_hit *ref = (pt_hit *)malloc(sizeof(pt_hit) * SL_RAYS), *h = (pt_hit *)malloc(sizeof(pt_hit) * SL_RAYS);
    int *ref_occ = (int *)malloc(sizeof(int) * SL_RAYS), *occ = (int *)malloc(sizeof(int) * SL_RAYS);
    if (saved) snprintf(keep, sizeof keep, "%s", saved);
    if (!CHECK(t, ref && h && ref_occ && occ, "out of memory")) goto done;
    for (kind = 0; kind < 3; kind++) {
        pt_film ref_film, film;
        memset(&ref_film, 0, sizeof ref_film);
        for (level = PT_SIMD_SCALAR; level <= cpu; level++) {
            pt_scene *s;
            pt_scene_info info;
            int i, bad_hit = 0, bad_occ = 0, first = -1;
            sl_setenv(pt_simd_level_name((pt_simd_level)level));
            s = sl_scene(kind);
            if (!CHECK(t, s != NULL, "scene %d at %s", kind, pt_simd_level_name((pt_simd_level)level))) continue;
            pt_scene_get_info(s, &info);
            CHECK(t, (int)info.simd_level == level && (info.bvh_width == width[level] || (level == PT_SIMD_AVX512 && info.bvh_width == 8)),
                  "scene %d: PDFTRACE_SIMD=%s gave level %d, width %u", kind, pt_simd_level_name((pt_simd_level)level),
                  (int)info.simd_level, info.bvh_width);
            sl_trace(s, kind, level == PT_SIMD_SCALAR ? ref : h, level == PT_SIMD_SCALAR ? ref_occ : occ);
            if (level == PT_SIMD_SCALAR) {
                for (i = 0; i < SL_RAYS; i++) hits += ref[i].t > 0;
                for (i = 0; kind == 2 && i < SL_RAYS; i++) { /* an exact tie goes to the quad added first */
                    int q, first_q = -1, edge = 0;
                    if (!(ref[i].t > 0) || ref[i].primitive >= 120) continue;
                    for (q = 0; q < 120 && first_q < 0; q++) {
                        float x = ref[i].point.x, y = ref[i].point.y, *r = sl_rect[q];
                        if (fabsf(x - r[0]) < 1e-3f || fabsf(x - r[2]) < 1e-3f || fabsf(y - r[1]) < 1e-3f || fabsf(y - r[3]) < 1e-3f) edge = 1;
                        else if (x > r[0] && x < r[2] && y > r[1] && y < r[3]) first_q = q;
                    }
                    if (!edge) {
                        ties += first_q != (int)ref[i].primitive;
                        overlaps++;
                    }
                }
                sl_render(t, s, &ref_film, "scalar");
            } else {
                for (i = 0; i < SL_RAYS; i++) {
                    if (memcmp(&ref[i], &h[i], sizeof h[i]) != 0 && bad_hit++ == 0) first = i;
                    if (ref_occ[i] != occ[i]) bad_occ++;
                }
                CHECK(t, bad_hit == 0, "scene %d, %s: %d of %d closest hits differ from the scalar level's (first: ray %d, t %.9g prim %u against t %.9g prim %u)",
                      kind, pt_simd_level_name((pt_simd_level)level), bad_hit, SL_RAYS, first, first >= 0 ? h[first].t : 0.0,
                      first >= 0 ? (unsigned)h[first].primitive : 0u, first >= 0 ? ref[first].t : 0.0, first >= 0 ? (unsigned)ref[first].primitive : 0u);
                CHECK(t, bad_occ == 0, "scene %d, %s: %d occlusion answers differ from the scalar level's", kind,
                      pt_simd_level_name((pt_simd_level)level), bad_occ);
                sl_render(t, s, &film, pt_simd_level_name((pt_simd_level)level));
                CHECK(t, tu_film_equal(&ref_film, &film), "scene %d, %s: film differs from the scalar level's", kind,
                      pt_simd_level_name((pt_simd_level)level));
                pt_film_free(&film);
            }
            pt_scene_destroy(s);
        }
        pt_film_free(&ref_film);
    }
    CHECK(t, ties == 0 && overlaps > SL_RAYS / 4, "coplanar quads: %d of %d hits are not on the quad added first", ties, overlaps);
    CHECK(t, hits > 3 * SL_RAYS / 2, "only %d of %d rays hit (test too weak)", hits, 3 * SL_RAYS);
    /* the API cap and the errors */
    sl_setenv(NULL);
    CHECK(t, pt_simd_set_cap(PT_SIMD_SCALAR) == PT_OK && pt_simd_get_level() == PT_SIMD_SCALAR, "cap scalar: level %d",
          (int)pt_simd_get_level());
    CHECK(t, pt_simd_set_cap((pt_simd_level)4) == PT_ERROR_INVALID_ARGUMENT && pt_simd_get_level() == PT_SIMD_SCALAR,
          "cap 4 accepted");
    CHECK(t, pt_simd_set_cap(PT_SIMD_AVX512) == PT_OK && (int)pt_simd_get_level() == cpu, "no cap: level %d, cpu %d",
          (int)pt_simd_get_level(), cpu);
    CHECK(t, pt_simd_level_name((pt_simd_level)-1) == NULL, "name of level -1");
    sl_setenv("avx3");
    {
        pt_scene *s = pt_scene_create();
        int m = s ? pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)) : -1, rc;
        if (CHECK(t, s != NULL && m >= 0, "scene")) {
            pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m);
            rc = pt_scene_commit(s);
            CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "PDFTRACE_SIMD=\"avx3\"") != NULL,
                  "PDFTRACE_SIMD=avx3: commit %d, \"%s\"", rc, pt_scene_error_message(s));
        }
        pt_scene_destroy(s);
    }
    test_note(t, "levels scalar..%s, %d hits of %d rays", pt_simd_level_name((pt_simd_level)cpu), hits, 3 * SL_RAYS);
done:
    sl_setenv(saved ? keep : NULL);
    free(ref); free(h); free(ref_occ); free(occ);
}

const test_case test_bvh_cases[] = {
    TEST_CASE(bvh_random_scenes),
    TEST_CASE(bvh_axis_aligned),
    TEST_CASE(bvh_ray_along_max_bound),
    TEST_CASE(bvh_rebuild_after_change),
    TEST_CASE(bvh_denormal_extent),
    TEST_CASE(bvh_simd_levels),
    TEST_END
};
