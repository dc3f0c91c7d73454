/* stress_cases.c - the numerical stress cases of issue 7 (see stress.h). Sizes depend on
   c->full; everything else (scenes, bounds, seeds) is the same in make stress and make test. */
#include "pdftrace.h"
#include "../test_util.h"
#include "stress.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------------------------------ */
/* rows and the statistical family                                                             */

void st_init(st_ctx *c, int full, st_row_fn row, void *user)
{
    memset(c, 0, sizeof *c);
    c->full = full;
    c->row = row;
    c->user = user;
    c->max_comparisons = full ? ST_COMPARISONS_FULL : ST_COMPARISONS_FAST;
    c->z_bound = tu_z_two_sided(tu_sidak(ST_ALPHA, c->max_comparisons));
}

#if defined(__GNUC__) || defined(__clang__)
static void st_row(st_ctx *c, int pass, const char *cas, const char *metric, const char *bound, const char *fmt, ...)
    __attribute__((format(printf, 6, 7)));
#endif
static void st_row(st_ctx *c, int pass, const char *cas, const char *metric, const char *bound, const char *fmt, ...)
{
    char result[160];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(result, sizeof result, fmt, ap);
    va_end(ap);
    c->rows++;
    if (!pass) c->failed++;
    if (c->row) c->row(c->user, cas, metric, bound, result, pass);
}

static const char *st_zb(const st_ctx *c)
{
    static char buf[32];
    snprintf(buf, sizeof buf, "<= %.2f", c->z_bound);
    return buf;
}

/* ------------------------------------------------------------------------------------------ */
/* placement: a unit scene scaled by s and moved by off (computed in double, rounded once)     */

typedef struct st_place { double s; dv3 off; const char *name; } st_place;

static pt_vec3 sp_p(const st_place *pl, double x, double y, double z)
{
    return dv_to(dadd(pl->off, dv(x * pl->s, y * pl->s, z * pl->s)));
}
static pt_vec3 sp_v(const st_place *pl, double x, double y, double z) { return dv_to(dv(x * pl->s, y * pl->s, z * pl->s)); }
static dv3 sp_d(const st_place *pl, dv3 u) { return dadd(pl->off, dscale(u, pl->s)); }

/* The sweep: 10^k, k = -6..6, at the origin; 10^k, k = 3..6, moved by (1e6, -1e6, 1e6). Float
   coordinates resolve 2^-24 of their magnitude: a scene 1e6 from the origin must be >= ~1e3 in
   size to be representable at all (the documented limit; see pt_offset_ray_origin). */
#define ST_NPLACES 17
static void st_places(st_place *out)
{
    static char names[ST_NPLACES][40];
    int i, k = 0;
    for (i = -6; i <= 6; i++, k++) {
        out[k].s = pow(10.0, i);
        out[k].off = dv(0, 0, 0);
        snprintf(names[k], sizeof names[k], "x1e%+d", i);
        out[k].name = names[k];
    }
    for (i = 3; i <= 6; i++, k++) {
        out[k].s = pow(10.0, i);
        out[k].off = dv(1e6, -1e6, 1e6);
        snprintf(names[k], sizeof names[k], "x1e%+d at 1e6", i);
        out[k].name = names[k];
    }
}

/* ------------------------------------------------------------------------------------------ */
/* an indexed icosphere (shared vertices: a closed, watertight mesh)                           */

typedef struct st_mesh { double *v; int nv, cap_v; uint32_t *idx; int nt, cap_t; } st_mesh;

static int st_mesh_vertex(st_mesh *m, dv3 p)
{
    int i;
    p = dnorm(p);
    for (i = 0; i < m->nv; i++)
        if (m->v[3 * i] == p.x && m->v[3 * i + 1] == p.y && m->v[3 * i + 2] == p.z) return i;
    if (m->nv == m->cap_v) {
        m->cap_v = m->cap_v ? 2 * m->cap_v : 64;
        m->v = (double *)realloc(m->v, sizeof(double) * 3 * (size_t)m->cap_v);
    }
    m->v[3 * m->nv] = p.x; m->v[3 * m->nv + 1] = p.y; m->v[3 * m->nv + 2] = p.z;
    return m->nv++;
}
static void st_mesh_tri(st_mesh *m, int a, int b, int c)
{
    if (m->nt == m->cap_t) {
        m->cap_t = m->cap_t ? 2 * m->cap_t : 64;
        m->idx = (uint32_t *)realloc(m->idx, sizeof(uint32_t) * 3 * (size_t)m->cap_t);
    }
    m->idx[3 * m->nt] = (uint32_t)a; m->idx[3 * m->nt + 1] = (uint32_t)b; m->idx[3 * m->nt + 2] = (uint32_t)c;
    m->nt++;
}
static dv3 st_mesh_get(const st_mesh *m, int i) { return dv(m->v[3 * i], m->v[3 * i + 1], m->v[3 * i + 2]); }
/* Unit icosphere, outward counter-clockwise faces. Midpoints are normalised in double and looked
   up exactly, so neighbouring triangles share their vertices bit for bit. */
static void st_icosphere(st_mesh *out, int subdiv)
{
    static const int F[20][3] = { {0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                  {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                  {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1} };
    double g = (1.0 + sqrt(5.0)) / 2.0;
    dv3 P[12];
    st_mesh a, b;
    int i, s;
    P[0] = dv(-1, g, 0); P[1] = dv(1, g, 0); P[2] = dv(-1, -g, 0); P[3] = dv(1, -g, 0);
    P[4] = dv(0, -1, g); P[5] = dv(0, 1, g); P[6] = dv(0, -1, -g); P[7] = dv(0, 1, -g);
    P[8] = dv(g, 0, -1); P[9] = dv(g, 0, 1); P[10] = dv(-g, 0, -1); P[11] = dv(-g, 0, 1);
    memset(&a, 0, sizeof a);
    for (i = 0; i < 12; i++) st_mesh_vertex(&a, P[i]);
    for (i = 0; i < 20; i++) st_mesh_tri(&a, F[i][0], F[i][1], F[i][2]);
    for (s = 0; s < subdiv; s++) {
        memset(&b, 0, sizeof b);
        for (i = 0; i < a.nv; i++) st_mesh_vertex(&b, st_mesh_get(&a, i));
        for (i = 0; i < a.nt; i++) {
            int i0 = (int)a.idx[3 * i], i1 = (int)a.idx[3 * i + 1], i2 = (int)a.idx[3 * i + 2];
            dv3 p0 = st_mesh_get(&a, i0), p1 = st_mesh_get(&a, i1), p2 = st_mesh_get(&a, i2);
            int m01 = st_mesh_vertex(&b, dscale(dadd(p0, p1), 0.5)), m12 = st_mesh_vertex(&b, dscale(dadd(p1, p2), 0.5));
            int m20 = st_mesh_vertex(&b, dscale(dadd(p2, p0), 0.5));
            st_mesh_tri(&b, i0, m01, m20);
            st_mesh_tri(&b, i1, m12, m01);
            st_mesh_tri(&b, i2, m20, m12);
            st_mesh_tri(&b, m01, m12, m20);
        }
        free(a.v); free(a.idx);
        a = b;
    }
    *out = a;
}
static dv3 st_scratch_get(const float *p, int i) { return dv(p[3 * i], p[3 * i + 1], p[3 * i + 2]); }
static void st_mesh_free(st_mesh *m) { free(m->v); free(m->idx); memset(m, 0, sizeof *m); }

/* Adds mesh m (unit sphere) with centre (cx,cy,cz) and radius r in unit-scene coordinates. */
static int st_add_mesh(pt_scene *s, const st_mesh *m, const st_place *pl, double cx, double cy, double cz, double r,
                       int material, float *scratch)
{
    pt_mesh_desc md;
    int i;
    for (i = 0; i < m->nv; i++) {
        pt_vec3 p = sp_p(pl, cx + r * m->v[3 * i], cy + r * m->v[3 * i + 1], cz + r * m->v[3 * i + 2]);
        scratch[3 * i] = p.x; scratch[3 * i + 1] = p.y; scratch[3 * i + 2] = p.z;
    }
    memset(&md, 0, sizeof md);
    md.positions = scratch;
    md.vertex_count = (uint32_t)m->nv;
    md.indices = m->idx;
    md.triangle_count = (uint32_t)m->nt;
    md.material = material;
    return pt_scene_add_mesh(s, &md);
}

/* ------------------------------------------------------------------------------------------ */
/* rendering and region statistics                                                             */

static int st_render(const st_ctx *c, const pt_scene *s, const pt_camera_desc *cam, int w, int h, int spp, int depth,
                     pt_strategy strat, uint64_t seed, pt_film *f, pt_render_stats *st)
{
    pt_render_desc d = tu_base_desc(w, h, spp, seed);
    d.camera = *cam;
    d.max_depth = depth;
    d.strategy = strat;
    d.threads = c->threads;
    if (pt_film_init(f, w, h) != PT_OK) return PT_ERROR_OUT_OF_MEMORY;
    return pt_render(s, &d, f, st);
}

/* Region means of (R+G+B)/3; se is bounded by the mean of the channels' standard errors
   (Minkowski), conservative whatever their correlation. */
static void st_regions(const pt_film *f, int rx, int ry, double *mean, double *se)
{
    tu_region reg[64];
    int i;
    tu_film_regions(f, rx, ry, reg);
    for (i = 0; i < rx * ry; i++) {
        mean[i] = (reg[i].mean[0] + reg[i].mean[1] + reg[i].mean[2]) / 3.0;
        se[i] = (reg[i].se[0] + reg[i].se[1] + reg[i].se[2]) / 3.0;
    }
}
/* Largest |z| of the region means of two independent renders; counts rx*ry comparisons. */
static double st_compare(st_ctx *c, const pt_film *a, const pt_film *b, int rx, int ry, int *worst_region)
{
    double ma[64], sa[64], mb[64], sb[64], worst = 0.0;
    int i;
    st_regions(a, rx, ry, ma, sa);
    st_regions(b, rx, ry, mb, sb);
    for (i = 0; i < rx * ry; i++) {
        double se = sqrt(sa[i] * sa[i] + sb[i] * sb[i]);
        double z = tu_z_floor(ma[i], mb[i], se, TU_FLOAT_FLOOR * fabs(mb[i]));
        if (!(z <= worst)) { worst = z; if (worst_region) *worst_region = i; }
    }
    c->comparisons += rx * ry;
    return worst;
}
/* Largest |z| of the region means against a constant. */
static double st_compare_const(st_ctx *c, const pt_film *a, int rx, int ry, double want)
{
    double ma[64], sa[64], worst = 0.0;
    int i;
    st_regions(a, rx, ry, ma, sa);
    for (i = 0; i < rx * ry; i++) {
        double z = tu_z_floor(ma[i], want, sa[i], TU_FLOAT_FLOOR * fabs(want));
        if (!(z <= worst)) worst = z;
    }
    c->comparisons += rx * ry;
    return worst;
}

/* ------------------------------------------------------------------------------------------ */
/* 1. scale and offset sweep                                                                   */

/* A closed room [0,1]^3 (six quads from pt_scene_add_box, seen from inside) with a quad light
   under the ceiling and a small sphere light; a sphere and an icosphere mesh resting on the
   floor (contact), a standing triangle; outside the room a two-sided quad light over the
   ceiling and a sphere light beside a wall, which must never be seen inside (leaks). */
static pt_scene *st_room(const st_place *pl, int inner_lights, const st_mesh *ico, float *scratch, pt_camera_desc *cam)
{
    pt_scene *s = pt_scene_create();
    int white, red, green, lamp, bulb, outside, rc = 0;
    if (!s) return NULL;
    white = pt_scene_add_lambertian(s, pt_v3(0.7f, 0.7f, 0.7f));
    red = pt_scene_add_lambertian(s, pt_v3(0.7f, 0.2f, 0.2f));
    green = pt_scene_add_lambertian(s, pt_v3(0.2f, 0.7f, 0.3f));
    lamp = pt_scene_add_emitter(s, pt_v3(6, 6, 5), 0);
    bulb = pt_scene_add_emitter(s, pt_v3(30, 25, 20), 0);
    outside = pt_scene_add_emitter(s, pt_v3(50, 50, 50), 1);
    rc |= pt_scene_add_box(s, sp_p(pl, 0, 0, 0), sp_p(pl, 1, 1, 1), white) < 0;
    if (inner_lights) {
        rc |= pt_scene_add_quad(s, sp_p(pl, 0.35, 0.998, 0.35), sp_v(pl, 0.3, 0, 0), sp_v(pl, 0, 0, 0.3), lamp) < 0;
        rc |= pt_scene_add_sphere(s, sp_p(pl, 0.82, 0.75, 0.75), (float)(0.05 * pl->s), bulb) < 0;
    }
    rc |= pt_scene_add_sphere(s, sp_p(pl, 0.3, 0.2, 0.6), (float)(0.2 * pl->s), red) < 0;
    rc |= pt_scene_add_triangle(s, sp_p(pl, 0.55, 0, 0.9), sp_p(pl, 0.95, 0, 0.6), sp_p(pl, 0.8, 0.55, 0.8), green) < 0;
    rc |= st_add_mesh(s, ico, pl, 0.72, 0.15, 0.3, 0.15, white, scratch) < 0;
    rc |= pt_scene_add_quad(s, sp_p(pl, -0.5, 1.2, -0.5), sp_v(pl, 2, 0, 0), sp_v(pl, 0, 0, 2), outside) < 0;
    rc |= pt_scene_add_sphere(s, sp_p(pl, 1.3, 0.5, 0.5), (float)(0.1 * pl->s), outside) < 0;
    if (rc || pt_scene_commit(s) != PT_OK) {
        fprintf(stderr, "stress: room at %s: %s\n", pl->name, pt_scene_error_message(s));
        pt_scene_destroy(s);
        return NULL;
    }
    memset(cam, 0, sizeof *cam);
    cam->look_from = sp_p(pl, 0.5, 0.5, 0.03);
    cam->look_at = sp_p(pl, 0.5, 0.42, 1.0);
    cam->vfov_degrees = 70;
    return s;
}

void st_scale_sweep(st_ctx *c)
{
    st_place pl[ST_NPLACES], unit;
    st_mesh ico;
    float *scratch;
    int W = c->full ? 40 : 24, spp = c->full ? 128 : 24, depth = 4, i, LW = c->full ? 48 : 24;
    pt_film ref;
    pt_camera_desc cam;
    pt_render_stats st;
    pt_scene *s;
    uint64_t nonfinite = 0;
    char cas[64];
    st_places(pl);
    st_icosphere(&ico, 1);
    scratch = (float *)malloc(sizeof(float) * 3 * (size_t)ico.nv);
    unit.s = 1; unit.off = dv(0, 0, 0); unit.name = "unit";
    s = st_room(&unit, 1, &ico, scratch, &cam);
    if (!s || st_render(c, s, &cam, W, W, spp, depth, PT_STRATEGY_MIS, 1, &ref, &st) != PT_OK) {
        st_row(c, 0, "sweep: unit scene", "render", "PT_OK", "failed");
        pt_scene_destroy(s); st_mesh_free(&ico); free(scratch);
        return;
    }
    nonfinite += st.nonfinite_samples;
    pt_scene_destroy(s);
    for (i = 0; i < ST_NPLACES; i++) {
        pt_film f, g;
        double z;
        int worst = -1, rc, p, lit = 0;
        double maxv = 0;
        s = st_room(&pl[i], 1, &ico, scratch, &cam);
        snprintf(cas, sizeof cas, "sweep %s", pl[i].name);
        rc = s ? st_render(c, s, &cam, W, W, spp, depth, PT_STRATEGY_MIS, 100 + (uint64_t)i, &f, &st) : -1;
        pt_scene_destroy(s);
        if (rc != PT_OK) { st_row(c, 0, cas, "render", "PT_OK", "rc %d", rc); continue; }
        nonfinite += st.nonfinite_samples;
        z = st_compare(c, &f, &ref, 4, 4, &worst);
        st_row(c, z <= c->z_bound, cas, "image vs unit: max|z| of 4x4 region means", st_zb(c), "%.2f (region %d)", z,
               worst);
        pt_film_free(&f);
        /* leaks: the same room without its own lights is exactly black inside */
        s = st_room(&pl[i], 0, &ico, scratch, &cam);
        rc = s ? st_render(c, s, &cam, LW, LW, c->full ? 64 : 8, depth, PT_STRATEGY_MIS, 200 + (uint64_t)i, &g, &st) : -1;
        pt_scene_destroy(s);
        if (rc != PT_OK) { st_row(c, 0, cas, "leak render", "PT_OK", "rc %d", rc); continue; }
        nonfinite += st.nonfinite_samples;
        for (p = 0; p < LW * LW * 3; p++) {
            if (g.sum[p] != 0.0) lit++;
            if (g.sum[p] > maxv) maxv = g.sum[p];
        }
        st_row(c, lit == 0, cas, "leak: lit pixels in the closed room lit from outside", "0", "%d (max sum %.3g)",
               lit / 1, maxv);
        pt_film_free(&g);
    }
    pt_film_free(&ref);
    st_row(c, nonfinite == 0, "sweep: all renders", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
    st_mesh_free(&ico);
    free(scratch);
}

/* ------------------------------------------------------------------------------------------ */
/* 1. rays spawned from each shape type                                                        */

/* Shapes of the unit scene, alone in their scene: sphere (centre c, radius 0.5), quad, triangle,
   convex icosphere mesh (radius 0.5, 320 triangles). A primary ray from a random distance
   (log-uniform 1e-2 .. 1e4 scene sizes, both sides of planar shapes) to a random point of the
   shape; from the hit, pt_offset_ray_origin and a direction on the side the ray came from
   (reflection) or the other side (transmission). Reflected rays must hit nothing (the shape is
   alone and convex); transmitted ones: planar shapes nothing, the sphere its far side at the
   chord length, the mesh another of its triangles. */
void st_spawn(st_ctx *c)
{
    st_place pl[ST_NPLACES];
    st_mesh ico;
    float *scratch;
    long N = c->full ? 1000000L : 12000L;
    int i, shape;
    st_places(pl);
    st_icosphere(&ico, 2);
    scratch = (float *)malloc(sizeof(float) * 3 * (size_t)ico.nv);
    for (i = 0; i < ST_NPLACES; i++) {
        long bad[4] = { 0, 0, 0, 0 }, prim_miss[4] = { 0, 0, 0, 0 }, done[4] = { 0, 0, 0, 0 };
        char cas[64], res[160];
        for (shape = 0; shape < 4; shape++) {
            pt_scene *s = pt_scene_create();
            int m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)), rc;
            dv3 C = dv(0.2, -0.1, 0.3);
            dv3 Q = dv(-0.4, 0.1, -0.3), U = dv(0.9, 0.2, 0.1), V = dv(-0.1, 0.3, 0.8);
            dv3 A = dv(-0.3, -0.2, 0.1), B = dv(0.6, 0.1, -0.2), Cc = dv(0.1, 0.7, 0.4);
            pt_rng rng;
            long k;
            if (shape == 0) rc = pt_scene_add_sphere(s, dv_to(sp_d(&pl[i], C)), (float)(0.5 * pl[i].s), m);
            else if (shape == 1) rc = pt_scene_add_quad(s, dv_to(sp_d(&pl[i], Q)), sp_v(&pl[i], U.x, U.y, U.z), sp_v(&pl[i], V.x, V.y, V.z), m);
            else if (shape == 2) rc = pt_scene_add_triangle(s, dv_to(sp_d(&pl[i], A)), dv_to(sp_d(&pl[i], B)), dv_to(sp_d(&pl[i], Cc)), m);
            else rc = st_add_mesh(s, &ico, &pl[i], C.x, C.y, C.z, 0.5, m, scratch);
            if (rc < 0 || pt_scene_commit(s) != PT_OK) { bad[shape] = -1; pt_scene_destroy(s); continue; }
            pt_rng_seed(&rng, 7000 + (uint64_t)(i * 4 + shape), 3);
            for (k = 0; k < N; k++) {
                dv3 target, dir, o, n, w;
                pt_ray r, r2;
                pt_hit h, h2;
                int got, transmit = (k % 4) == 3;
                double dist = pl[i].s * pow(10.0, -2.0 + 6.0 * tu_rand(&rng));
                if (shape == 0) {
                    dv3 u = tu_rand_dir(&rng);
                    target = dadd(C, dscale(u, 0.5));
                    do { dir = tu_rand_dir(&rng); } while (ddot(dir, u) <= 0.05);
                } else if (shape == 3) {
                    /* a point inside a random face, from outside the (convex) mesh */
                    int f = (int)(tu_rand(&rng) * ico.nt);
                    dv3 p0 = st_mesh_get(&ico, (int)ico.idx[3 * f]), p1 = st_mesh_get(&ico, (int)ico.idx[3 * f + 1]);
                    dv3 p2 = st_mesh_get(&ico, (int)ico.idx[3 * f + 2]), fn;
                    double a = 0.001 + 0.998 * tu_rand(&rng), b = 0.001 + 0.998 * tu_rand(&rng);
                    if (a + b > 0.999) { a = 0.999 - a; b = 0.999 - b; if (a < 0.001) a = 0.001; if (b < 0.001) b = 0.001; }
                    dv3 q0 = st_scratch_get(scratch, (int)ico.idx[3 * f]), q1 = st_scratch_get(scratch, (int)ico.idx[3 * f + 1]);
                    dv3 q2 = st_scratch_get(scratch, (int)ico.idx[3 * f + 2]);
                    /* on the float triangle as added (placed), not the exact one */
                    target = dadd(q0, dadd(dscale(dsub(q1, q0), a), dscale(dsub(q2, q0), b)));
                    fn = dnorm(dcross(dsub(p1, p0), dsub(p2, p0)));
                    if (ddot(fn, p0) < 0) fn = dscale(fn, -1); /* outwards */
                    do { dir = tu_rand_dir(&rng); } while (ddot(dir, fn) <= 0.05);
                } else {
                    double a = 0.001 + 0.998 * tu_rand(&rng), b = 0.001 + 0.998 * tu_rand(&rng);
                    /* on the float shape as added (placed), not the exact one */
                    dv3 fq = dv_from(dv_to(sp_d(&pl[i], Q))), fu = dv_from(sp_v(&pl[i], U.x, U.y, U.z));
                    dv3 fv = dv_from(sp_v(&pl[i], V.x, V.y, V.z));
                    dv3 fa = dv_from(dv_to(sp_d(&pl[i], A))), fb = dv_from(dv_to(sp_d(&pl[i], B)));
                    dv3 fc = dv_from(dv_to(sp_d(&pl[i], Cc)));
                    if (shape == 1) target = dadd(fq, dadd(dscale(fu, a), dscale(fv, b)));
                    else {
                        if (a + b > 0.999) { a = 0.999 - a; b = 0.999 - b; if (a < 0.001) a = 0.001; if (b < 0.001) b = 0.001; }
                        target = dadd(fa, dadd(dscale(dsub(fb, fa), a), dscale(dsub(fc, fa), b)));
                    }
                    /* either side, not grazing (a grazing ray from a far float origin lands
                       anywhere on the plane) */
                    {
                        dv3 pn = shape == 1 ? dnorm(dcross(U, V)) : dnorm(dcross(dsub(B, A), dsub(Cc, A)));
                        do { dir = tu_rand_dir(&rng); } while (fabs(ddot(dir, pn)) <= 0.05);
                    }
                }
                if (shape == 0) target = sp_d(&pl[i], target);
                o = dadd(target, dscale(dir, dist));
                r.origin = dv_to(o);
                r.dir = dv_to(dnorm(dsub(target, dv_from(r.origin))));
                if (pt_scene_intersect(s, r, INFINITY, &h) != 1) {
                    /* aimed 1e-3 inside the edges: a miss is a bug unless the far origin's float
                       direction cannot resolve that (2^-24 of the distance, margin 8) */
                    if (dist < 1e-3 * 0.07 * pl[i].s / (8.0 * ldexp(1.0, -24)) && shape != 0) {
                        prim_miss[shape]++;
                    }
                    continue;
                }
                if ((shape == 0 || shape == 3) && ddot(dv_from(h.geometric_normal), dv_from(r.dir)) > 0) {
                    /* the back of a convex shape seen from outside: the ray clipped an edge so
                       closely that entry and exit are within float resolution of t (~2^-24 of
                       a far origin's distance); which one is first is undecidable */
                    continue;
                }
                done[shape]++;
                n = dv_from(h.geometric_normal);
                if (ddot(n, dv_from(r.dir)) > 0) n = dscale(n, -1); /* the side the ray came from */
                do { w = tu_rand_dir(&rng); } while (fabs(ddot(w, n)) < 1e-4);
                if ((ddot(w, n) < 0) != transmit) w = dscale(w, -1);
                r2.origin = pt_offset_ray_origin_scaled(h.point, h.geometric_normal, dv_to(w), h.magnitude);
                r2.dir = dv_to(w);
                got = pt_scene_intersect(s, r2, INFINITY, &h2);
                if (!transmit || shape == 1 || shape == 2) {
                    if (got != 0) {
                        bad[shape]++;
                    }
                } else if (shape == 0) {
                    /* far side of the sphere: chord 2 R |cos| from the surface point */
                    double chord = 2.0 * 0.5 * pl[i].s * fabs(ddot(w, n));
                    if (chord > 1e-3 * pl[i].s && (got != 1 || h2.t < 0.5 * chord)) bad[shape]++;
                } else {
                    if (got != 1 || h2.primitive == h.primitive) {
                        bad[shape]++;
                    }
                }
            }
            pt_scene_destroy(s);
        }
        snprintf(cas, sizeof cas, "spawn %s", pl[i].name);
        snprintf(res, sizeof res, "%ld %ld %ld %ld of %ld %ld %ld %ld", bad[0], bad[1], bad[2], bad[3], done[0], done[1],
                 done[2], done[3]);
        st_row(c, bad[0] == 0 && bad[1] == 0 && bad[2] == 0 && bad[3] == 0, cas,
               "self-hits / lost far sides: sphere quad triangle mesh", "0", "%s", res);
        /* primary rays aimed at interior points: a miss is only possible at a sphere's rim */
        snprintf(res, sizeof res, "%ld %ld %ld", prim_miss[1], prim_miss[2], prim_miss[3]);
        st_row(c, prim_miss[1] == 0 && prim_miss[2] == 0 && prim_miss[3] == 0, cas,
               "primary rays at interior points that missed: quad triangle mesh", "0", "%s", res);
    }
    st_mesh_free(&ico);
    free(scratch);
}

/* ------------------------------------------------------------------------------------------ */
/* 2. a sphere light shrinking to a point at fixed intensity                                   */

/* The cone density of a sphere light averaged over many float shading points, per decade of
   sin^2(theta_max) from 1e-1 down to 1e-9, against 1 / (2 pi (1 - cos)) in double from the same
   floats: a rounding error that is not zero on average (the cancelling 1 - sqrt(1 - s^2) makes
   1 - cos 2^-26 too large on average, +0.07 % of light at the tiny-light bulb; docs/accuracy.md,
   "Tiny sphere lights and Mitsuba") shows in the mean long before it shows at one point.
   Deterministic: mean within 1e-6, worst within 1e-5 (pdftrace's own rounding: ~3e-7). */
static void st_cone_density_mean(st_ctx *c)
{
    const long P = c->full ? 200000L : 20000L;
    int k;
    for (k = 2; k <= 9; k++) {
        pt_rng rng;
        double sum = 0.0, worst = 0.0;
        long i, bad = 0;
        char cas[64];
        pt_rng_seed(&rng, 9500 + (uint64_t)k, 3);
        for (i = 0; i < P; i++) {
            double s2t = pow(10.0, -k + tu_rand(&rng)), h = 0.5 + 4.0 * tu_rand(&rng);
            pt_vec3 of = pt_v3((float)(8.0 * tu_rand(&rng) - 4.0), (float)(2.0 * tu_rand(&rng)),
                               (float)(8.0 * tu_rand(&rng) - 4.0));
            pt_vec3 cf = pt_add(of, dv_to(dscale(tu_rand_dir(&rng), h)));
            dv3 wc = dsub(dv_from(cf), dv_from(of));
            double d2 = ddot(wc, wc);
            float rf = (float)sqrt(s2t * d2);
            double s2 = (double)rf * rf / d2, want = 1.0 / (2.0 * TU_PI * (s2 / (1.0 + sqrt(1.0 - s2)))), rel;
            pt_pdf p = pt_pdf_sphere_light(of, cf, rf, 0);
            pt_vec3 w;
            float pv;
            if (!pt_pdf_sample(&p, &rng, &w, &pv)) { bad++; continue; }
            rel = pv / want - 1.0;
            sum += rel;
            worst = fmax(worst, fabs(rel));
        }
        sum /= (double)P;
        snprintf(cas, sizeof cas, "tiny light cone sin^2 1e-%d..1e-%d", k, k - 1);
        st_row(c, bad == 0 && fabs(sum) <= 1e-6, cas, "density vs 1/(2 pi (1-cos)): mean rel. error", "<= 1e-6", "%+.2e",
               bad ? INFINITY : sum);
        st_row(c, bad == 0 && worst <= 1e-5, cas, "density: worst rel. error", "<= 1e-5", "%.2e", bad ? INFINITY : worst);
    }
}

/* A Lambertian plane y = 0 (albedo rho) under a sphere light of radius R at height 1 with
   radiance L = I / (pi R^2): intensity I = L pi R^2 in every direction. The irradiance at
   horizontal distance x is E = pi L sin^2(alpha) cos(theta) = I cos(theta) / d^2 (d^2 = 1 + x^2),
   exact for every R while theta + alpha <= pi/2 (docs/accuracy.md), i.e. the point-light
   value; the plane's radiance is rho E / pi. Direct light only (max_depth 1), one path per
   sample through pt_trace_path from above the point. */
void st_tiny_light(st_ctx *c)
{
    static const pt_strategy strats[3] = { PT_STRATEGY_LIGHT, PT_STRATEGY_MIXTURE, PT_STRATEGY_MIS };
    static const char *snames[3] = { "LIGHT", "MIXTURE", "MIS" };
    static const double xs[4] = { 0.0, 0.5, 1.0, 2.0 };
    const double rho = 0.5, I = 1.0;
    long N = c->full ? 200000L : 4000L;
    int k, si, pi;
    uint64_t nonfinite = 0;
    double worst_var[3] = { 0, 0, 0 };
    for (k = 1; k <= 6; k++) {
        double R = pow(10.0, -k), L = I / (TU_PI * R * R);
        pt_scene *s = pt_scene_create();
        int white = pt_scene_add_lambertian(s, pt_v3((float)rho, (float)rho, (float)rho));
        int lamp = pt_scene_add_emitter(s, pt_v3((float)L, (float)L, (float)L), 0);
        pt_scene_add_quad(s, pt_v3(-10, 0, -10), pt_v3(0, 0, 20), pt_v3(20, 0, 0), white);
        pt_scene_add_sphere(s, pt_v3(0, 1, 0), (float)R, lamp);
        if (pt_scene_commit(s) != PT_OK) {
            st_row(c, 0, "tiny light", "commit", "PT_OK", "%s", pt_scene_error_message(s));
            pt_scene_destroy(s);
            continue;
        }
        for (si = 0; si < 3; si++) {
            pt_render_desc d = tu_base_desc(1, 1, 1, 0);
            double zmax = 0, rvmax = 0;
            char cas[64];
            d.max_depth = 1;
            d.rr_start_depth = -1;
            d.strategy = strats[si];
            for (pi = 0; pi < 4; pi++) {
                double x = xs[pi], dd = sqrt(1.0 + x * x), want = rho / TU_PI * I * (1.0 / dd) / (dd * dd);
                pt_rng rng;
                pt_ray r;
                pt_path_stats ps;
                tu_acc acc;
                long n;
                double rv;
                memset(&acc, 0, sizeof acc);
                memset(&ps, 0, sizeof ps);
                pt_rng_seed(&rng, 9000 + (uint64_t)(k * 16 + si * 4 + pi), 5);
                r.origin = pt_v3((float)x + 0.2f, 0.4f, 0.3f);
                r.dir = pt_normalize(pt_sub(pt_v3((float)x, 0, 0), r.origin));
                for (n = 0; n < N; n++) {
                    pt_color v = pt_trace_path(s, &d, r, &rng, &ps);
                    tu_acc_add(&acc, v.y);
                }
                nonfinite += ps.nonfinite_samples;
                zmax = fmax(zmax, tu_z_floor(acc.mean, want, tu_acc_se(&acc), TU_FLOAT_FLOOR * want));
                rv = tu_acc_var(&acc) / (want * want);
                rvmax = fmax(rvmax, rv);
            }
            c->comparisons += 4;
            snprintf(cas, sizeof cas, "tiny light R=1e-%d %s", k, snames[si]);
            st_row(c, zmax <= c->z_bound, cas, "mean vs I cos/d^2 (4 points): max|z|", st_zb(c), "%.2f", zmax);
            {
                /* per-sample relative variance: cone sampling of the light makes LIGHT's and MIS's
                   estimate nearly constant; the one-sample mixture (weight w = 0.5) returns ~E/w
                   with probability w, relative variance 1/w - 1 = 1 */
                double bound = strats[si] == PT_STRATEGY_MIXTURE ? 1.05 : 0.05;
                char b[32];
                snprintf(b, sizeof b, "<= %.2f", bound);
                st_row(c, rvmax <= bound, cas, "relative variance Var/E^2 per sample (max of 4)", b, "%.4f", rvmax);
                worst_var[si] = fmax(worst_var[si], rvmax);
            }
        }
        pt_scene_destroy(s);
    }
    st_row(c, nonfinite == 0, "tiny light: all", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
    st_cone_density_mean(c);
}

/* A sphere light shrinking at constant power, r/d = 1e-1 .. 1e-9, must tend to the point light
   (below r/d ~ 1e-7 no float direction lies in its cone). (a) Direct light at Cornell-box scale:
   a Lambertian plane y = 0 (albedo rho) under a one-sided sphere of radius r at height 500 with
   radiance L = I / (pi r^2), against rho/pi I cos / d^2 (exact for every r while the sphere is
   above the horizon, as in st_tiny_light): LIGHT and MIS within 1 % and the family's z, MIXTURE
   (relative variance ~1 per sample) within the family's z.
   (b) The RTRL Cornell box lit by that sphere at the quad light's power (15 x 130 x 105 x pi),
   MIS, full paths, the same seed at every r: each 4x4 region within 1 % of the r/d = 1e-4 image
   (the two differ by O(r^2/d^2) in the light's geometry, and by the rounding of its samples). */
static void st_point_light_plane(st_ctx *c)
{
    static const pt_strategy strats[3] = { PT_STRATEGY_LIGHT, PT_STRATEGY_MIS, PT_STRATEGY_MIXTURE };
    static const double xs[2] = { 0.05, 0.7 };
    const double rho = 0.5, I = 1.0, H = 500.0;
    long N = c->full ? 40000L : 2000L;
    int k, si, pi;
    for (k = 1; k <= 9; k++) {
        float rf = (float)(H * pow(10.0, -k));
        double L = I / (TU_PI * (double)rf * rf), zmax = 0, zmix = 0, relmax = 0;
        pt_vec3 cf = pt_v3(278.0f, (float)H, 278.0f);
        pt_scene *s = pt_scene_create();
        int white = pt_scene_add_lambertian(s, pt_v3((float)rho, (float)rho, (float)rho));
        int lamp = pt_scene_add_emitter(s, pt_v3((float)L, (float)L, (float)L), 0);
        char cas[64];
        pt_scene_add_quad(s, pt_v3(-5000, 0, -5000), pt_v3(0, 0, 10000), pt_v3(10000, 0, 0), white);
        pt_scene_add_sphere(s, cf, rf, lamp);
        snprintf(cas, sizeof cas, "point limit plane r/d=1e-%d", k);
        if (pt_scene_commit(s) != PT_OK) {
            st_row(c, 0, cas, "commit", "PT_OK", "%s", pt_scene_error_message(s));
            pt_scene_destroy(s);
            continue;
        }
        for (si = 0; si < 3; si++) {
            for (pi = 0; pi < 2; pi++) {
                pt_render_desc d = tu_base_desc(1, 1, 1, 0);
                dv3 x = dv(278.0 + xs[pi] * H, 0, 278.0 - 0.1 * H), wc = dsub(dv_from(cf), x);
                double dd = dlen(wc), want = rho / TU_PI * I * (wc.y / dd) / (dd * dd);
                pt_rng rng;
                pt_ray r;
                pt_path_stats ps;
                tu_acc acc;
                long n;
                memset(&acc, 0, sizeof acc);
                memset(&ps, 0, sizeof ps);
                d.max_depth = 1;
                d.rr_start_depth = -1;
                d.strategy = strats[si];
                pt_rng_seed(&rng, 16300 + (uint64_t)(k * 8 + si * 2 + pi), 5);
                r.origin = pt_v3((float)(x.x - 100.0), 200.0f, (float)(x.z - 150.0));
                r.dir = pt_normalize(pt_sub(dv_to(x), r.origin));
                for (n = 0; n < N; n++) tu_acc_add(&acc, pt_trace_path(s, &d, r, &rng, &ps).y);
                if (si == 2) {
                    zmix = fmax(zmix, tu_z_floor(acc.mean, want, tu_acc_se(&acc), TU_FLOAT_FLOOR * want));
                } else {
                    zmax = fmax(zmax, tu_z_floor(acc.mean, want, tu_acc_se(&acc), TU_FLOAT_FLOOR * want));
                    relmax = fmax(relmax, fabs(acc.mean / want - 1.0));
                }
                if (ps.nonfinite_samples) relmax = zmix = INFINITY;
            }
        }
        c->comparisons += 6;
        st_row(c, zmax <= c->z_bound, cas, "LIGHT, MIS mean vs point light rho/pi I cos/d^2 (2 points): max|z|",
               st_zb(c), "%.2f", zmax);
        st_row(c, relmax <= 0.01, cas, "LIGHT, MIS: max relative error vs the point light", "<= 0.01", "%.2e", relmax);
        st_row(c, zmix <= c->z_bound, cas, "MIXTURE mean vs the point light (2 points): max|z|", st_zb(c), "%.2f", zmix);
        pt_scene_destroy(s);
    }
}

/* The RTRL Cornell box (walls, rotated box) lit by a sphere of radius r at (278, 500, 278). */
static pt_scene *st_sphere_cornell(double r)
{
    const double P = 15.0 * 130.0 * 105.0 * TU_PI, L = P / (4.0 * TU_PI * TU_PI * r * r);
    pt_scene *s = pt_scene_create();
    int red = pt_scene_add_lambertian(s, pt_v3(0.65f, 0.05f, 0.05f));
    int white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
    int green = pt_scene_add_lambertian(s, pt_v3(0.12f, 0.45f, 0.15f));
    int lamp = pt_scene_add_emitter(s, pt_v3((float)L, (float)L, (float)L), 0);
    pt_transform x = pt_transform_mul(pt_transform_translate(pt_v3(265, 0, 295)), pt_transform_rotate_y(15));
    pt_scene_add_quad(s, pt_v3(555, 0, 0), pt_v3(0, 555, 0), pt_v3(0, 0, 555), green);
    pt_scene_add_quad(s, pt_v3(0, 0, 555), pt_v3(0, 0, -555), pt_v3(0, 555, 0), red);
    pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(555, 0, 0), pt_v3(0, 0, 555), white);
    pt_scene_add_quad(s, pt_v3(555, 555, 555), pt_v3(-555, 0, 0), pt_v3(0, 0, -555), white);
    pt_scene_add_quad(s, pt_v3(0, 0, 555), pt_v3(555, 0, 0), pt_v3(0, 555, 0), white);
    pt_scene_set_transform(s, &x);
    pt_scene_add_box(s, pt_v3(0, 0, 0), pt_v3(165, 330, 165), white);
    pt_scene_set_transform(s, NULL);
    pt_scene_add_sphere(s, pt_v3(278, 500, 278), (float)r, lamp);
    if (pt_scene_commit(s) != PT_OK) { pt_scene_destroy(s); return NULL; }
    return s;
}

static void st_point_light_cornell(st_ctx *c)
{
    const int W = c->full ? 32 : 16, R = 4;
    const double D = 300.0; /* ~ the light's distance to the walls it lights */
    pt_image ref, im;
    pt_render_desc d = tu_base_desc(W, W, c->full ? 64 : 8, 16400);
    int k, x, y, j;
    memset(&ref, 0, sizeof ref);
    memset(&im, 0, sizeof im);
    d.camera.look_from = pt_v3(278, 278, -800);
    d.camera.look_at = pt_v3(278, 278, 0);
    d.camera.up = pt_v3(0, 1, 0);
    d.camera.vfov_degrees = 40;
    d.threads = c->threads;
    for (k = 4; k <= 9; k++) {
        pt_scene *s = st_sphere_cornell(D * pow(10.0, -k));
        double worst = 0.0;
        char cas[64];
        snprintf(cas, sizeof cas, "point limit cornell r/d=1e-%d", k);
        if (!s || pt_render_image(s, &d, k == 4 ? &ref : &im, NULL) != PT_OK) {
            st_row(c, 0, cas, "commit and render", "PT_OK", "failed");
            pt_scene_destroy(s);
            if (k == 4) return;
            continue;
        }
        pt_scene_destroy(s);
        if (k == 4) continue;
        for (y = 0; y < W; y += R)
            for (x = 0; x < W; x += R) {
                double a = 0, b = 0;
                int i, ii;
                for (i = 0; i < R; i++)
                    for (ii = 0; ii < R; ii++)
                        for (j = 0; j < 3; j++) {
                            a += im.rgb[((size_t)(y + i) * W + x + ii) * 3 + j];
                            b += ref.rgb[((size_t)(y + i) * W + x + ii) * 3 + j];
                        }
                worst = fmax(worst, b > 0 ? fabs(a / b - 1.0) : (a != 0 ? INFINITY : 0.0));
            }
        st_row(c, worst <= 0.01, cas, "MIS, same seed: worst 4x4 region vs the r/d=1e-4 image", "<= 0.01", "%.2e",
               worst);
        pt_image_free(&im);
    }
    pt_image_free(&ref);
}

void st_point_light(st_ctx *c)
{
    st_point_light_plane(c);
    st_point_light_cornell(c);
}

/* ------------------------------------------------------------------------------------------ */
/* 3. watertight: rays from inside closed shapes                                               */

/* Closed shapes at four placements: an icosphere mesh (1280 triangles), a box of six quads
   (pt_scene_add_box) and a sphere. Rays from random interior points: a third in random
   directions, a third at vertices (corners), a third at points on edges. Each must hit. Rays from
   outside through vertices and edges must hit too. */
void st_watertight(st_ctx *c)
{
    static const double ss[4] = { 1.0, 1e-6, 1e6, 1e3 };
    long N = c->full ? 1000000L : 15000L;
    st_mesh ico;
    float *scratch;
    int pi, shape;
    st_icosphere(&ico, 3);
    scratch = (float *)malloc(sizeof(float) * 3 * (size_t)ico.nv);
    for (pi = 0; pi < 4; pi++) {
        st_place pl;
        pl.s = ss[pi];
        pl.off = pi == 3 ? dv(1e6, -1e6, 1e6) : dv(0, 0, 0);
        pl.name = pi == 0 ? "x1" : pi == 1 ? "x1e-6" : pi == 2 ? "x1e+6" : "x1e+3 at 1e6";
        for (shape = 0; shape < 3; shape++) {
            static const char *names[3] = { "icosphere mesh", "box of quads", "sphere" };
            pt_scene *s = pt_scene_create();
            int m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)), rc;
            long k, escaped = 0, missed = 0;
            pt_rng rng;
            char cas[80];
            if (shape == 0) rc = st_add_mesh(s, &ico, &pl, 0, 0, 0, 1, m, scratch);
            else if (shape == 1) rc = pt_scene_add_box(s, sp_p(&pl, -1, -1, -1), sp_p(&pl, 1, 1, 1), m);
            else rc = pt_scene_add_sphere(s, sp_p(&pl, 0, 0, 0), (float)pl.s, m);
            if (rc < 0 || pt_scene_commit(s) != PT_OK) {
                st_row(c, 0, "watertight", names[shape], "built", "%s", pt_scene_error_message(s));
                pt_scene_destroy(s);
                continue;
            }
            pt_rng_seed(&rng, 8000 + (uint64_t)(pi * 3 + shape), 9);
            for (k = 0; k < N; k++) {
                dv3 o, target, dir;
                pt_ray r;
                pt_hit h;
                int kind = (int)(k % 3), outside = (k % 7) == 0 && kind != 0;
                if (shape == 1) o = dv(1.8 * tu_rand(&rng) - 0.9, 1.8 * tu_rand(&rng) - 0.9, 1.8 * tu_rand(&rng) - 0.9);
                else o = dscale(tu_rand_dir(&rng), 0.9 * pow(tu_rand(&rng), 1.0 / 3.0));
                if (kind == 0) target = dadd(o, tu_rand_dir(&rng));
                else if (shape == 0) {
                    int f = (int)(tu_rand(&rng) * ico.nt), e = (int)(tu_rand(&rng) * 3);
                    dv3 p0 = st_mesh_get(&ico, (int)ico.idx[3 * f + e]), p1 = st_mesh_get(&ico, (int)ico.idx[3 * f + (e + 1) % 3]);
                    target = kind == 1 ? p0 : dadd(p0, dscale(dsub(p1, p0), tu_rand(&rng)));
                } else if (shape == 1) {
                    /* a corner, or a point on one of the 12 edges */
                    double sx = tu_rand(&rng) < 0.5 ? -1 : 1, sy = tu_rand(&rng) < 0.5 ? -1 : 1, sz = tu_rand(&rng) < 0.5 ? -1 : 1;
                    int ax = (int)(tu_rand(&rng) * 3);
                    double tpar = 2 * tu_rand(&rng) - 1;
                    target = dv(sx, sy, sz);
                    if (kind == 2) { if (ax == 0) target.x = tpar; else if (ax == 1) target.y = tpar; else target.z = tpar; }
                } else {
                    target = tu_rand_dir(&rng);
                }
                if (outside) {
                    /* from outside, through the vertex or edge point */
                    dv3 away = dnorm(dadd(dnorm(target), dscale(tu_rand_dir(&rng), 0.7)));
                    if (ddot(away, target) <= 0.1) away = dnorm(target);
                    o = dadd(target, dscale(away, 0.5 + 3 * tu_rand(&rng)));
                }
                o = sp_d(&pl, o);
                target = sp_d(&pl, target);
                dir = dsub(target, o);
                r.origin = dv_to(o);
                r.dir = dv_to(dnorm(dsub(target, dv_from(r.origin))));
                (void)dir;
                if (pt_scene_intersect(s, r, INFINITY, &h) != 1) {
                    if (outside) missed++; else escaped++;
                }
            }
            pt_scene_destroy(s);
            snprintf(cas, sizeof cas, "watertight %s %s", names[shape], pl.name);
            st_row(c, escaped == 0 && missed == 0, cas, "rays from inside that escaped + outside through vertex/edge that missed",
                   "0", "%ld + %ld of %ld", escaped, missed, N);
        }
    }
    st_mesh_free(&ico);
    free(scratch);
}

/* ------------------------------------------------------------------------------------------ */
/* 3. edges, grazing rays, tangents                                                            */

void st_edges(st_ctx *c)
{
    static const double ss[4] = { 1.0, 1e-6, 1e6, 1e3 };
    long N = c->full ? 200000L : 6000L;
    st_mesh ico;
    float *scratch;
    int pi;
    st_icosphere(&ico, 2);
    scratch = (float *)malloc(sizeof(float) * 3 * (size_t)ico.nv);
    for (pi = 0; pi < 4; pi++) {
        st_place pl;
        pt_scene *s, *sph, *tri;
        int m, rc;
        long k, bad_edge = 0, edge_hits = 0, bad_plane = 0, miss_in = 0, hit_out = 0, bad_tan = 0;
        double eps_tan;
        pt_rng rng;
        char cas[80];
        dv3 TA = dv(-0.3, -0.2, 0.1), TB = dv(0.6, 0.1, -0.2), TC = dv(0.1, 0.7, 0.4);
        pl.s = ss[pi];
        pl.off = pi == 3 ? dv(1e6, -1e6, 1e6) : dv(0, 0, 0);
        pl.name = pi == 0 ? "x1" : pi == 1 ? "x1e-6" : pi == 2 ? "x1e+6" : "x1e+3 at 1e6";
        s = pt_scene_create(); sph = pt_scene_create(); tri = pt_scene_create();
        m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
        pt_scene_add_lambertian(sph, pt_v3(0.5f, 0.5f, 0.5f));
        pt_scene_add_lambertian(tri, pt_v3(0.5f, 0.5f, 0.5f));
        rc = st_add_mesh(s, &ico, &pl, 0, 0, 0, 1, m, scratch);
        rc |= pt_scene_add_sphere(sph, sp_p(&pl, 0, 0, 0), (float)pl.s, 0);
        rc |= pt_scene_add_triangle(tri, dv_to(sp_d(&pl, TA)), dv_to(sp_d(&pl, TB)), dv_to(sp_d(&pl, TC)), 0);
        if (rc < 0 || pt_scene_commit(s) || pt_scene_commit(sph) || pt_scene_commit(tri)) {
            st_row(c, 0, "edges", "scenes", "built", "failed");
            pt_scene_destroy(s); pt_scene_destroy(sph); pt_scene_destroy(tri);
            continue;
        }
        pt_rng_seed(&rng, 6000 + (uint64_t)pi, 11);
        /* the float resolution of a placement: impact parameters closer than this to R are
           undecidable (2^-24 of the coordinates involved, times a margin of 64) */
        eps_tan = fmax(1e-5, 64.0 * ldexp(1.0, -24) * (dlen(pl.off) + 10.0 * pl.s) / pl.s);
        for (k = 0; k < N; k++) {
            /* (a) along a mesh edge, from outside on the edge's line */
            {
                int f = (int)(tu_rand(&rng) * ico.nt), e = (int)(tu_rand(&rng) * 3);
                dv3 a = st_mesh_get(&ico, (int)ico.idx[3 * f + e]), b = st_mesh_get(&ico, (int)ico.idx[3 * f + (e + 1) % 3]);
                double lam = 0.05 + 2 * tu_rand(&rng), len = dlen(dsub(b, a)) * pl.s;
                dv3 o = sp_d(&pl, dadd(a, dscale(dsub(a, b), lam)));
                pt_ray r;
                pt_hit h;
                int got;
                r.origin = dv_to(o);
                r.dir = dv_to(dnorm(dsub(b, a)));
                got = pt_scene_intersect(s, r, INFINITY, &h);
                if (got == 1) {
                    edge_hits++;
                    if (!isfinite(h.t) || h.t < lam * len * (1 - 1e-3) - eps_tan * pl.s ||
                        h.t > (1 + lam) * len * (1 + 1e-3) + eps_tan * pl.s || !(isfinite(h.point.x) && isfinite(h.point.y) && isfinite(h.point.z)))
                        bad_edge++;
                } else if (got != 0) bad_edge++;
            }
            /* (b) in the plane of a triangle, across it: a hit must be finite and on it */
            {
                dv3 n = dnorm(dcross(dsub(TB, TA), dsub(TC, TA))), e1, e2, p, o, dir;
                double a = tu_rand(&rng), b = tu_rand(&rng);
                pt_ray r;
                pt_hit h;
                int got;
                if (a + b > 1) { a = 1 - a; b = 1 - b; }
                p = dadd(TA, dadd(dscale(dsub(TB, TA), a), dscale(dsub(TC, TA), b)));
                tu_frame(n, &e1, &e2);
                {
                    double ang = 2 * TU_PI * tu_rand(&rng);
                    dir = dadd(dscale(e1, cos(ang)), dscale(e2, sin(ang)));
                }
                o = dsub(p, dscale(dir, 2.0));
                r.origin = dv_to(sp_d(&pl, o));
                r.dir = dv_to(dir);
                got = pt_scene_intersect(tri, r, INFINITY, &h);
                if (got == 1) {
                    dv3 hp = dv_from(h.point), lo = sp_d(&pl, dv(-0.3, -0.2, -0.2)), hi = sp_d(&pl, dv(0.6, 0.7, 0.4));
                    double tol = 1e-3 * pl.s + 64.0 * ldexp(1.0, -24) * dlen(pl.off);
                    if (!isfinite(h.t) || h.t <= 0 || hp.x < lo.x - tol || hp.x > hi.x + tol || hp.y < lo.y - tol ||
                        hp.y > hi.y + tol || hp.z < lo.z - tol || hp.z > hi.z + tol)
                        bad_plane++;
                } else if (got != 0) bad_plane++;
            }
            /* (c) tangent to a sphere: impact parameter R (1 + delta), |delta| log-uniform in
               [1e-7, 1e-1]; well inside (delta <= -eps) must hit, well outside must miss */
            {
                dv3 axis = tu_rand_dir(&rng), e1, e2, o, dir, foot;
                double delta = pow(10.0, -7.0 + 6.0 * tu_rand(&rng)) * (tu_rand(&rng) < 0.5 ? -1 : 1);
                double D = 1.5 + 50 * tu_rand(&rng);
                pt_ray r;
                pt_hit h;
                int got;
                tu_frame(axis, &e1, &e2);
                foot = dscale(e1, 1.0 + delta);   /* closest point of the ray to the centre */
                dir = e2;
                o = dsub(foot, dscale(dir, D));
                r.origin = dv_to(sp_d(&pl, o));
                r.dir = dv_to(dir);
                got = pt_scene_intersect(sph, r, INFINITY, &h);
                if (got == 1) {
                    double dist = dlen(dsub(dv_from(h.point), sp_d(&pl, dv(0, 0, 0)))) / pl.s;
                    if (!isfinite(h.t) || fabs(dist - 1.0) > eps_tan) bad_tan++;
                } else if (got != 0) bad_tan++;
                if (delta <= -eps_tan && got != 1) miss_in++;
                if (delta >= eps_tan && got == 1) hit_out++;
            }
        }
        pt_scene_destroy(s); pt_scene_destroy(sph); pt_scene_destroy(tri);
        snprintf(cas, sizeof cas, "edges %s", pl.name);
        st_row(c, bad_edge == 0, cas, "rays along mesh edges: hits off the edge or non-finite", "0", "%ld of %ld (%ld hit)",
               bad_edge, N, edge_hits);
        st_row(c, bad_plane == 0, cas, "rays in a triangle's plane: hits off it or non-finite", "0", "%ld of %ld", bad_plane, N);
        snprintf(cas, sizeof cas, "tangent %s", pl.name);
        {
            char b[48];
            snprintf(b, sizeof b, "0 (|delta| >= %.1e)", eps_tan);
            st_row(c, miss_in == 0 && hit_out == 0 && bad_tan == 0, cas,
                   "sphere: misses inside + hits outside + off-surface hits", b, "%ld + %ld + %ld of %ld", miss_in, hit_out,
                   bad_tan, N);
        }
    }
    st_mesh_free(&ico);
    free(scratch);
}

/* ------------------------------------------------------------------------------------------ */
/* 3. lights: shading points on lights, the horizon, normals facing away                       */

/* Every strategy against an exact value or against MATERIAL (independent seeds). */
static void st_strategies_vs(st_ctx *c, const char *cas, pt_scene *s, const pt_camera_desc *cam, int W, int spp,
                             int depth, double exact, int rx, uint64_t seed, uint64_t *nonfinite)
{
    static const pt_strategy strats[4] = { PT_STRATEGY_MATERIAL, PT_STRATEGY_LIGHT, PT_STRATEGY_MIXTURE, PT_STRATEGY_MIS };
    static const char *snames[4] = { "MATERIAL", "LIGHT", "MIXTURE", "MIS" };
    pt_film f[4];
    pt_render_stats st;
    int i, ok[4];
    for (i = 0; i < 4; i++) {
        ok[i] = st_render(c, s, cam, W, W, exact >= 0 || i == 0 ? spp : spp / 2, depth, strats[i], seed + (uint64_t)i,
                          &f[i], &st) == PT_OK;
        *nonfinite += st.nonfinite_samples;
    }
    for (i = exact >= 0 ? 0 : 1; i < 4; i++) {
        char name[96], metric[96];
        double z;
        snprintf(name, sizeof name, "%s %s", cas, snames[i]);
        if (!ok[i] || !ok[0]) { st_row(c, 0, name, "render", "PT_OK", "failed"); continue; }
        if (exact >= 0) {
            z = st_compare_const(c, &f[i], rx, rx, exact);
            snprintf(metric, sizeof metric, "%dx%d region means vs exact %.3g: max|z|", rx, rx, exact);
        } else {
            z = st_compare(c, &f[i], &f[0], rx, rx, NULL);
            snprintf(metric, sizeof metric, "%dx%d region means vs MATERIAL: max|z|", rx, rx);
        }
        st_row(c, z <= c->z_bound, name, metric, st_zb(c), "%.2f", z);
    }
    for (i = 0; i < 4; i++) if (ok[i]) pt_film_free(&f[i]);
}

void st_light_geometry(st_ctx *c)
{
    static const double ss[4] = { 1.0, 1e-6, 1e6, 1e3 };
    int W = c->full ? 32 : 16, pi;
    uint64_t nonfinite = 0;
    pt_camera_desc cam;
    /* (a) a closed box of emitting Lambertian quads (albedo 0.5, two-sided emission 0.5): every
       shading point lies on a light, light sampling meets the other walls at grazing angles in
       the corners, and the radiance everywhere inside is Le / (1 - rho) = 1 */
    for (pi = 0; pi < 4; pi++) {
        st_place pl;
        pt_scene *s = pt_scene_create();
        int m;
        char cas[64];
        pl.s = ss[pi];
        pl.off = pi == 3 ? dv(1e6, -1e6, 1e6) : dv(0, 0, 0);
        pl.name = pi == 0 ? "x1" : pi == 1 ? "x1e-6" : pi == 2 ? "x1e+6" : "x1e+3 at 1e6";
        m = tu_add_furnace_material(s);
        if (pt_scene_add_box(s, sp_p(&pl, -1, -1, -1), sp_p(&pl, 1, 1, 1), m) < 0 || pt_scene_commit(s) != PT_OK) {
            st_row(c, 0, "emitting box", "built", "PT_OK", "%s", pt_scene_error_message(s));
            pt_scene_destroy(s);
            continue;
        }
        memset(&cam, 0, sizeof cam);
        cam.look_from = sp_p(&pl, -0.5, -0.3, -0.6);
        cam.look_at = sp_p(&pl, 1, 1, 1);
        cam.vfov_degrees = 100;
        snprintf(cas, sizeof cas, "emitting box %s", pl.name);
        st_strategies_vs(c, cas, s, &cam, W, c->full ? 256 : 64, 0, 1.0, 2, 500 + 10 * (uint64_t)pi, &nonfinite);
        pt_scene_destroy(s);
    }
    /* (a') the same furnace built of 96 one-sided quads facing in (4 x 4 on each side: the light
       tree picks among them, its bounds taken over boxes of every size at these scales); the
       radiance inside is again Le / (1 - rho) = 1 */
    for (pi = 1; pi < 4; pi++) {
        st_place pl;
        pt_scene *s = pt_scene_create();
        pt_material_desc md;
        int m, f, i, j, rc = 0;
        char cas[64];
        pl.s = ss[pi];
        pl.off = pi == 3 ? dv(1e6, -1e6, 1e6) : dv(0, 0, 0);
        pl.name = pi == 1 ? "x1e-6" : pi == 2 ? "x1e+6" : "x1e+3 at 1e6";
        memset(&md, 0, sizeof md);
        md.type = PT_MATERIAL_LAMBERTIAN;
        md.albedo = pt_v3(0.5f, 0.5f, 0.5f);
        md.emission = pt_v3(0.5f, 0.5f, 0.5f);
        m = pt_scene_add_material(s, &md);
        for (f = 0; f < 6; f++) {
            /* side f: axis a at -1 (f even) or +1 (f odd); tiles span the other two axes, u x v
               pointing into the box */
            const int a = f / 2, b = (a + 1) % 3, cc = (a + 2) % 3, sgn = (f % 2) ? 1 : -1;
            for (i = 0; i < 4; i++)
                for (j = 0; j < 4; j++) {
                    double q[3], u[3] = {0, 0, 0}, v[3] = {0, 0, 0};
                    q[a] = sgn;
                    q[b] = -1.0 + 0.5 * i;
                    q[cc] = -1.0 + 0.5 * j;
                    /* e_b x e_c = +e_a: into the box on side -1; swapped on side +1 */
                    if (sgn < 0) { u[b] = 0.5; v[cc] = 0.5; }
                    else { u[cc] = 0.5; v[b] = 0.5; }
                    if (pt_scene_add_quad(s, sp_p(&pl, q[0], q[1], q[2]), sp_v(&pl, u[0], u[1], u[2]),
                                          sp_v(&pl, v[0], v[1], v[2]), m) < 0) rc = -1;
                }
        }
        if (rc < 0 || pt_scene_commit(s) != PT_OK) {
            st_row(c, 0, "emitting tiles", "built", "PT_OK", "%s", pt_scene_error_message(s));
            pt_scene_destroy(s);
            continue;
        }
        memset(&cam, 0, sizeof cam);
        cam.look_from = sp_p(&pl, -0.5, -0.3, -0.6);
        cam.look_at = sp_p(&pl, 1, 1, 1);
        cam.vfov_degrees = 100;
        snprintf(cas, sizeof cas, "96 emitting tiles %s", pl.name);
        st_strategies_vs(c, cas, s, &cam, W, c->full ? 256 : 64, 0, 1.0, 2, 540 + 10 * (uint64_t)pi, &nonfinite);
        pt_scene_destroy(s);
    }
    /* (b) lights at the horizon: a one-sided sphere light centred on the floor (half below it)
       and a quad light standing on the floor, emitting along it; the floor sees both down to
       its horizon */
    {
        pt_scene *s = pt_scene_create();
        int white = pt_scene_add_lambertian(s, pt_v3(0.6f, 0.6f, 0.6f));
        int lamp = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0);
        pt_scene_add_quad(s, pt_v3(-2, 0, -2), pt_v3(0, 0, 4), pt_v3(4, 0, 0), white);
        pt_scene_add_sphere(s, pt_v3(-0.6f, 0, 0), 0.3f, lamp);
        /* u x v = (0.8,0,0) x (0,0.4,0) = +z: emits along the floor towards +z */
        pt_scene_add_quad(s, pt_v3(0.2f, 0, -0.5f), pt_v3(0.8f, 0, 0), pt_v3(0, 0.4f, 0), lamp);
        if (pt_scene_commit(s) == PT_OK) {
            memset(&cam, 0, sizeof cam);
            cam.look_from = pt_v3(0, 3, 0.6f);
            cam.look_at = pt_v3(0, 0, 0);
            cam.vfov_degrees = 60;
            st_strategies_vs(c, "horizon lights", s, &cam, W, c->full ? 1024 : 96, 2, -1, 3, 600, &nonfinite);
        } else st_row(c, 0, "horizon lights", "built", "PT_OK", "%s", pt_scene_error_message(s));
        pt_scene_destroy(s);
    }
    /* (c) normals facing away from the light: a mesh whose shading normals lean 60 degrees away
       from its geometric normals, and a one-sided quad light that faces away from the floor
       (it lights only the ceiling above it) */
    {
        pt_scene *s = pt_scene_create();
        int white = pt_scene_add_lambertian(s, pt_v3(0.6f, 0.6f, 0.6f));
        int lamp = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0);
        static const float pos[12] = { -1, 0.3f, -1, 1, 0.3f, -1, 1, 0.3f, 1, -1, 0.3f, 1 };
        static const uint32_t idx[6] = { 0, 2, 1, 0, 3, 2 };
        float nrm[12];
        pt_mesh_desc md;
        int i;
        for (i = 0; i < 4; i++) { nrm[3 * i] = 0.866f; nrm[3 * i + 1] = 0.5f; nrm[3 * i + 2] = 0; }
        memset(&md, 0, sizeof md);
        md.positions = pos; md.vertex_count = 4; md.indices = idx; md.triangle_count = 2; md.normals = nrm;
        md.material = white;
        pt_scene_add_quad(s, pt_v3(-3, 0, -3), pt_v3(0, 0, 6), pt_v3(6, 0, 0), white);     /* floor, up */
        pt_scene_add_quad(s, pt_v3(-3, 2, -3), pt_v3(6, 0, 0), pt_v3(0, 0, 6), white);     /* ceiling */
        pt_scene_add_mesh(s, &md);
        pt_scene_add_quad(s, pt_v3(-0.4f, 1.2f, -0.4f), pt_v3(0, 0, 0.8f), pt_v3(0.8f, 0, 0), lamp); /* faces up */
        pt_scene_add_sphere(s, pt_v3(1.5f, 1.0f, 0.5f), 0.15f, lamp);
        if (pt_scene_commit(s) == PT_OK) {
            memset(&cam, 0, sizeof cam);
            cam.look_from = pt_v3(0, 1.0f, 2.9f);
            cam.look_at = pt_v3(0, 0.8f, 0);
            cam.vfov_degrees = 90;
            st_strategies_vs(c, "normals away", s, &cam, W, c->full ? 1024 : 96, 3, -1, 3, 700, &nonfinite);
        } else st_row(c, 0, "normals away", "built", "PT_OK", "%s", pt_scene_error_message(s));
        pt_scene_destroy(s);
    }
    st_row(c, nonfinite == 0, "light geometry: all", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
}

/* ------------------------------------------------------------------------------------------ */
/* 4. degenerate input                                                                         */

/* An error code < 0 and a non-empty message that names the shape. */
static int st_err(pt_scene *s, int rc, const char *word)
{
    return rc < 0 && strstr(pt_scene_error_message(s), word) != NULL;
}

static int st_cos_sample(void *user, pt_rng *rng, pt_vec3 *dir, float *pdf)
{
    pt_pdf p = pt_pdf_cosine_hemisphere(*(const pt_vec3 *)user);
    return pt_pdf_sample(&p, rng, dir, pdf);
}
static float st_cos_value(void *user, pt_vec3 dir)
{
    pt_pdf p = pt_pdf_cosine_hemisphere(*(const pt_vec3 *)user);
    return pt_pdf_value(&p, dir);
}

void st_degenerate(st_ctx *c)
{
    pt_scene *s = pt_scene_create();
    int m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)), ok, rc;
    float nanf_ = (float)NAN, inff = (float)INFINITY;
    /* zero-area shapes */
    ok = st_err(s, pt_scene_add_triangle(s, pt_v3(0, 0, 0), pt_v3(1, 1, 1), pt_v3(2, 2, 2), m), "triangle") &&
         st_err(s, pt_scene_add_triangle(s, pt_v3(1, 2, 3), pt_v3(1, 2, 3), pt_v3(0, 0, 1), m), "triangle") &&
         st_err(s, pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(0, 0, 0), pt_v3(0, 1, 0), m), "quad") &&
         st_err(s, pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(1, 2, 3), pt_v3(-2, -4, -6), m), "quad") &&
         st_err(s, pt_scene_add_box(s, pt_v3(0, 0, 0), pt_v3(1, 0, 1), m), "box");
    st_row(c, ok, "degenerate: zero area", "collinear/coincident triangle, zero/parallel quad edges, flat box",
           "error + message", "%s", ok ? "errors" : pt_scene_error_message(s));
    {
        static const float pos[9] = { 0, 0, 0, 1, 1, 1, 2, 2, 2 };
        static const float pos2[12] = { 0, 0, 0, 1, 1, 1, 2, 2, 2, 0, 1, 0 };
        static const uint32_t idx[3] = { 0, 1, 2 }, idx2[6] = { 0, 1, 2, 0, 1, 3 };
        pt_mesh_desc md;
        pt_scene_info info;
        memset(&md, 0, sizeof md);
        md.positions = pos; md.vertex_count = 3; md.indices = idx; md.triangle_count = 1; md.material = m;
        ok = st_err(s, pt_scene_add_mesh(s, &md), "mesh");
        md.positions = pos2; md.vertex_count = 4; md.indices = idx2; md.triangle_count = 2;
        rc = pt_scene_add_mesh(s, &md);
        pt_scene_get_info(s, &info);
        ok = ok && rc >= 0 && info.degenerate_triangles_skipped == 1;
        st_row(c, ok, "degenerate: zero-area mesh triangles", "all degenerate / one of two", "error / skipped and counted",
               "%s", ok ? "error / 1 skipped" : "wrong");
    }
    /* radii */
    ok = st_err(s, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 0.0f, m), "sphere") &&
         st_err(s, pt_scene_add_sphere(s, pt_v3(0, 0, 0), -1.0f, m), "sphere") &&
         st_err(s, pt_scene_add_sphere(s, pt_v3(0, 0, 0), -0.0f, m), "sphere") &&
         st_err(s, pt_scene_add_sphere(s, pt_v3(0, 0, 0), nanf_, m), "sphere") &&
         st_err(s, pt_scene_add_sphere(s, pt_v3(0, 0, 0), inff, m), "sphere");
    st_row(c, ok, "degenerate: sphere radius", "0, -0, -1, NaN, Inf", "error + message", "%s", ok ? "errors" : "accepted");
    /* NaN / Inf coordinates */
    {
        static const float posn[9] = { 0, 0, 0, 1, 0, 0, 0, (float)NAN, 0 };
        static const uint32_t idx[3] = { 0, 1, 2 };
        pt_mesh_desc md;
        pt_transform xf = pt_transform_identity();
        memset(&md, 0, sizeof md);
        md.positions = posn; md.vertex_count = 3; md.indices = idx; md.triangle_count = 1; md.material = m;
        xf.m[0][3] = inff;
        ok = st_err(s, pt_scene_add_sphere(s, pt_v3(nanf_, 0, 0), 1, m), "sphere") &&
             st_err(s, pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(inff, 0, 0), pt_v3(0, 1, 0), m), "quad") &&
             st_err(s, pt_scene_add_triangle(s, pt_v3(0, 0, -inff), pt_v3(1, 0, 0), pt_v3(0, 1, 0), m), "triangle") &&
             st_err(s, pt_scene_add_box(s, pt_v3(0, nanf_, 0), pt_v3(1, 1, 1), m), "box") &&
             st_err(s, pt_scene_add_mesh(s, &md), "mesh") && st_err(s, pt_scene_set_transform(s, &xf), "transform");
        st_row(c, ok, "degenerate: NaN/Inf coordinates", "sphere, quad, triangle, box, mesh, transform", "error + message",
               "%s", ok ? "errors" : "accepted");
    }
    /* finite but enormous: products of two coordinates overflow float */
    {
        pt_scene *h = pt_scene_create();
        int hm = pt_scene_add_lambertian(h, pt_v3(0.5f, 0.5f, 0.5f));
        ok = st_err(h, pt_scene_add_sphere(h, pt_v3(0, 0, 0), 3e19f, hm), "sphere") &&
             st_err(h, pt_scene_add_sphere(h, pt_v3(0, 0, 2e18f), 1.0f, hm), "sphere") &&
             st_err(h, pt_scene_add_quad(h, pt_v3(-1e30f, -1, -1e30f), pt_v3(2e30f, 0, 0), pt_v3(0, 0, 2e30f), hm), "quad") &&
             st_err(h, pt_scene_add_quad(h, pt_v3(2e18f, 0, 0), pt_v3(1, 0, 0), pt_v3(0, 0, 1), hm), "quad") &&
             st_err(h, pt_scene_add_triangle(h, pt_v3(1e25f, 0, 0), pt_v3(0, 1e25f, 0), pt_v3(0, 0, 1e25f), hm), "triangle") &&
             st_err(h, pt_scene_add_triangle(h, pt_v3(3e18f, 0, 0), pt_v3(3e18f, 1, 0), pt_v3(3e18f, 0, 1), hm), "triangle") &&
             st_err(h, pt_scene_add_triangle(h, pt_v3(0, 0, 0), pt_v3(1e-23f, 0, 0), pt_v3(0, 1e-23f, 0), hm), "triangle");
        st_row(c, ok, "degenerate: huge coordinates", "r 3e19, centre/corners 2e18..1e30; area underflow (1e-23 edges)", "error + message",
               "%s", ok ? "errors" : "accepted");
        pt_scene_destroy(h);
    }
    /* mixture weights that are zero, negative or do not sum to one */
    {
        pt_vec3 up = pt_v3(0, 1, 0), down = pt_v3(0, -1, 0);
        pt_pdf comp[3], mix;
        float w1[2] = { 0.1f, 0.3f }, w2[3] = { 0.5f, -1.0f, 0.5f }, w0[2] = { 0.0f, 0.0f };
        pt_rng rng;
        int i, n = c->full ? 200000 : 20000, upc = 0, bad = 0, fails = 0;
        pt_vec3 d;
        float p;
        double z;
        comp[0] = pt_pdf_callback(&up, st_cos_sample, st_cos_value);
        comp[1] = pt_pdf_callback(&down, st_cos_sample, st_cos_value);
        comp[2] = pt_pdf_uniform_sphere();
        mix = pt_pdf_mixture(2, comp, w1);
        pt_rng_seed(&rng, 4242, 1);
        for (i = 0; i < n; i++) {
            if (!pt_pdf_sample(&mix, &rng, &d, &p)) { fails++; continue; }
            if (d.y > 0) upc++;
            if (fabs(p - pt_pdf_value(&mix, d)) > 1e-5 * p) bad++;
        }
        /* weights 0.1 and 0.3 act as 0.25 and 0.75: the upper hemisphere gets a quarter */
        z = fabs(upc - 0.25 * n) / sqrt(n * 0.25 * 0.75);
        c->comparisons += 1;
        st_row(c, pt_pdf_validate(&mix) != PT_OK && bad == 0 && fails == 0 && z <= c->z_bound,
               "degenerate: mixture weights 0.1+0.3", "validate rejects; draws follow w/sum w (z); sample pdf == value",
               st_zb(c), "z %.2f, %d mismatches", z, bad);
        mix = pt_pdf_mixture(3, comp, w2);
        bad = 0; fails = 0;
        for (i = 0; i < 2000; i++) {
            if (!pt_pdf_sample(&mix, &rng, &d, &p)) { fails++; continue; }
            if (fabs(p - pt_pdf_value(&mix, d)) > 1e-5 * p) bad++;
        }
        st_row(c, pt_pdf_validate(&mix) != PT_OK && bad == 0 && fails == 0, "degenerate: mixture weight -1",
               "validate rejects; negative weight ignored, sample pdf == value", "0 mismatches", "%d", bad);
        mix = pt_pdf_mixture(2, comp, w0);
        ok = pt_pdf_validate(&mix) != PT_OK && pt_pdf_sample(&mix, &rng, &d, &p) == 0 && p == 0.0f &&
             pt_pdf_value(&mix, up) == 0.0f;
        st_row(c, ok, "degenerate: mixture weights all 0", "validate rejects; no sample, density 0", "as stated", "%s",
               ok ? "as stated" : "different");
    }
    pt_scene_destroy(s);
    /* zero-power lights and the empty scene: no lights, the background only */
    {
        pt_scene *e = pt_scene_create();
        pt_scene *z = pt_scene_create();
        pt_render_desc d = tu_base_desc(8, 8, 4, 1);
        pt_image img;
        pt_scene_info info;
        pt_hit h;
        pt_ray r;
        int i, all_bg = 1, rc1, rc2, black = 1;
        int zl = pt_scene_add_emitter(z, pt_v3(0, 0, 0), 0);
        int zw = pt_scene_add_lambertian(z, pt_v3(0.5f, 0.5f, 0.5f));
        pt_scene_add_sphere(z, pt_v3(0, 0, 0), 1, zl);
        pt_scene_add_quad(z, pt_v3(-5, -1, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), zw);
        d.camera.look_from = pt_v3(0, 0, 5);
        d.camera.look_at = pt_v3(0, 0, 0);
        d.background = pt_v3(0.2f, 0.3f, 0.4f);
        d.threads = c->threads;
        rc1 = pt_scene_commit(e);
        memset(&img, 0, sizeof img);
        rc2 = rc1 == PT_OK ? pt_render_image(e, &d, &img, NULL) : rc1;
        for (i = 0; rc2 == PT_OK && i < 64; i++)
            all_bg &= img.rgb[3 * i] == 0.2f && img.rgb[3 * i + 1] == 0.3f && img.rgb[3 * i + 2] == 0.4f;
        r.origin = pt_v3(0, 0, 0); r.dir = pt_v3(0, 0, 1);
        ok = rc2 == PT_OK && all_bg && pt_scene_intersect(e, r, INFINITY, &h) == 0 && pt_scene_occluded(e, r, INFINITY) == 0;
        st_row(c, ok, "degenerate: empty scene", "commit, render, intersect", "background, no hit", "%s",
               ok ? "background, no hit" : "different");
        pt_image_free(&img);
        d.background = pt_v3(0, 0, 0);
        rc1 = pt_scene_commit(z);
        pt_scene_get_info(z, &info);
        rc2 = rc1 == PT_OK ? pt_render_image(z, &d, &img, NULL) : rc1;
        for (i = 0; rc2 == PT_OK && i < 64 * 3; i++) black &= img.rgb[i] == 0.0f;
        ok = rc2 == PT_OK && info.emitter_count == 0 && black;
        st_row(c, ok, "degenerate: zero-power light", "emitter of radiance 0", "no light, black image", "%s",
               ok ? "no light, black" : "different");
        pt_image_free(&img);
        pt_scene_destroy(e);
        pt_scene_destroy(z);
    }
    /* the camera: inside geometry, zero-length and parallel vectors */
    {
        pt_scene *g = pt_scene_create();
        int w = pt_scene_add_lambertian(g, pt_v3(0.5f, 0.5f, 0.5f));
        int l2 = pt_scene_add_emitter(g, pt_v3(2, 2, 2), 1);
        int l1 = pt_scene_add_emitter(g, pt_v3(5, 5, 5), 0);
        pt_render_desc d = tu_base_desc(8, 8, 16, 3);
        pt_render_stats st;
        pt_image img;
        int i, black = 1, finite = 1, rc1, rc2, rc3, rc4;
        pt_scene_add_sphere(g, pt_v3(0, 0, 0), 1, w);          /* closed, lit only from outside */
        pt_scene_add_sphere(g, pt_v3(5, 0, 0), 1, l2);         /* a two-sided light to stand in */
        pt_scene_add_sphere(g, pt_v3(0, 3, 0), 0.5f, l1);
        pt_scene_commit(g);
        d.threads = c->threads;
        d.camera.look_from = pt_v3(0.2f, 0.1f, 0);
        d.camera.look_at = pt_v3(1, 0, 0);
        memset(&img, 0, sizeof img);
        rc1 = pt_render_image(g, &d, &img, &st);
        for (i = 0; rc1 == PT_OK && i < 64 * 3; i++) black &= img.rgb[i] == 0.0f;
        pt_image_free(&img);
        d.camera.look_from = pt_v3(5.3f, 0, 0);
        d.camera.look_at = pt_v3(6, 0, 0);
        rc2 = pt_render_image(g, &d, &img, &st);
        for (i = 0; rc2 == PT_OK && i < 64 * 3; i++) finite &= isfinite(img.rgb[i]) && img.rgb[i] > 0.0f;
        pt_image_free(&img);
        ok = rc1 == PT_OK && black && rc2 == PT_OK && finite && st.nonfinite_samples == 0;
        st_row(c, ok, "degenerate: camera inside geometry", "inside a closed sphere / a two-sided sphere light",
               "black / finite > 0", "%s", ok ? "black / finite" : "different");
        d.camera.look_at = d.camera.look_from;
        rc1 = pt_render_image(g, &d, &img, &st);
        pt_image_free(&img);
        ok = rc1 == PT_ERROR_INVALID_ARGUMENT && strstr(st.error, "camera") != NULL;
        d.camera.look_at = pt_v3(6, 0, 0);
        d.camera.up = pt_v3(0, 0, 0);
        rc2 = pt_render_image(g, &d, &img, NULL);   /* documented: zero up means (0,1,0) */
        pt_image_free(&img);
        d.camera.up = pt_v3(2, 0, 0);               /* parallel to the view */
        rc3 = pt_render_image(g, &d, &img, NULL);
        pt_image_free(&img);
        d.camera.up = pt_v3(0, 1, 0);
        d.camera.look_from = pt_v3(nanf_, 0, 0);
        rc4 = pt_render_image(g, &d, &img, NULL);
        pt_image_free(&img);
        ok = ok && rc2 == PT_OK && rc3 == PT_ERROR_INVALID_ARGUMENT && rc4 == PT_ERROR_INVALID_ARGUMENT;
        st_row(c, ok, "degenerate: camera vectors", "look_at == look_from / up 0 / up parallel / NaN",
               "error / default up / error / error", "%d / %d / %d / %d", rc1, rc2, rc3, rc4);
        pt_scene_destroy(g);
    }
}

/* The exact distance along r to the plane of the float triangle a, b, c, in double. */
static double st_plane_t(pt_ray r, pt_vec3 a, pt_vec3 b, pt_vec3 c)
{
    dv3 A = dv_from(a), n = dcross(dsub(dv_from(b), A), dsub(dv_from(c), A));
    return ddot(n, dsub(A, dv_from(r.origin))) / ddot(n, dv_from(r.dir));
}

void st_slivers(st_ctx *c)
{
    /* Fuzzed sliver triangles (length L up to 1e7, width 1e-5 L .. 1e-2 L, at offsets up to 1e7;
       every other one in an axis-aligned plane, as in x = const), each alone in a scene, hit from close by at a point well inside (barycentrics >= 0.1): the
       closest hit, brute force and the shadow ray must agree (occluded just beyond t, not just
       before), and t must match the double-precision plane distance. */
    const int n = c->full ? 20000 : 1500;
    int i, disagree = 0, missed = 0, hits = 0;
    double worst = 0.0;
    char ex[160] = "";
    pt_rng rng;
    pt_rng_seed(&rng, 0x511e4ull, 5u);
    for (i = 0; i < n; i++) {
        double M = pow(10.0, 7.0 * tu_rand(&rng)), L = M * (0.5 + 0.5 * tu_rand(&rng));
        double w = L * pow(10.0, -5.0 + 3.0 * tu_rand(&rng)), u = 0.1 + 0.8 * tu_rand(&rng), v, wc;
        dv3 off = dscale(tu_rand_dir(&rng), M * tu_rand(&rng)), e1 = tu_rand_dir(&rng), e2, nrm, p, dir;
        pt_vec3 a, b, cc;
        pt_scene *s = pt_scene_create();
        pt_ray r;
        pt_hit h, hb;
        int m, hi, bf, occ_after, occ_before;
        double tref, dist;
        if (i % 2) { /* in an axis-aligned plane: a flat bounding box, which a wrong t misses */
            int ax = (i / 2) % 3;
            double ang = 2.0 * TU_PI * tu_rand(&rng);
            dv3 x = dv(ax == 1, ax == 2, ax == 0), y = dv(ax == 2, ax == 0, ax == 1);
            e1 = dadd(dscale(x, cos(ang)), dscale(y, sin(ang)));
        }
        tu_frame(e1, &e2, &nrm);
        if (i % 2) {
            int ax = (i / 2) % 3;
            nrm = dv(ax == 0, ax == 1, ax == 2);
            e2 = dcross(nrm, e1);
        }
        a = dv_to(dadd(off, dscale(e1, -0.5 * L)));
        b = dv_to(dadd(off, dscale(e1, 0.5 * L)));
        cc = dv_to(dadd(dadd(off, dscale(e1, (tu_rand(&rng) - 0.5) * L)), dscale(e2, w)));
        /* a point with barycentrics (u', v', wc) all >= 0.1 (wc on the apex c) */
        wc = 0.1 + 0.8 * tu_rand(&rng) * (1.0 - u);
        v = 1.0 - u - wc;
        if (v < 0.1) { v = 0.1; u = 1.0 - v - wc; }
        p = dadd(dadd(dscale(dv_from(a), u), dscale(dv_from(b), v)), dscale(dv_from(cc), wc));
        dir = dnorm(dadd(dscale(nrm, tu_rand(&rng) < 0.5 ? -1.0 : 1.0), dscale(tu_rand_dir(&rng), 0.9)));
        dist = w * pow(10.0, 6.0 * tu_rand(&rng) - 3.0);
        r.origin = dv_to(dsub(p, dscale(dir, dist)));
        r.dir = dv_to(dir);
        if (!s) continue;
        m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
        if (pt_scene_add_triangle(s, a, b, cc, m) < 0 || pt_scene_set_backend(s, PT_BACKEND_BUILTIN) != PT_OK ||
            pt_scene_commit(s) != PT_OK) {
            pt_scene_destroy(s);
            continue; /* no area in float: refused */
        }
        tref = st_plane_t(r, a, b, cc);
        hi = pt_scene_intersect(s, r, INFINITY, &h);
        bf = pt_scene_intersect_brute_force(s, r, INFINITY, &hb);
        occ_after = hi == 1 ? pt_scene_occluded(s, r, (float)(h.t * 1.0001)) : 0;
        occ_before = hi == 1 ? pt_scene_occluded(s, r, (float)(h.t * 0.9999)) : 0;
        if (hi != 1 && tref > 0.0) missed++;
        if (hi != bf || (hi == 1 && (hb.t != h.t || occ_after != 1 || occ_before != 0))) {
            if (disagree++ == 0)
                snprintf(ex, sizeof ex, "L %.3g w %.3g: intersect %d t %.9g, brute %d t %.9g, occluded %d/%d", L, w,
                         hi, h.t, bf, hb.t, occ_before, occ_after);
        }
        if (hi == 1 && tref > 0.0) {
            double e = fabs(h.t - tref) / tref;
            hits++;
            if (e > worst) worst = e;
        }
        pt_scene_destroy(s);
    }
    st_row(c, disagree == 0, "slivers: intersect / occluded", "closest hit = brute force; occluded at t(1 +- 1e-4)",
           "0 disagreements", "%d of %d%s%s", disagree, n, disagree ? "; " : "", ex);
    st_row(c, missed == 0 && hits > n / 2, "slivers: hits", "rays at barycentrics >= 0.1 that miss", "0",
           "%d missed, %d hit", missed, hits);
    st_row(c, worst <= 1e-5, "slivers: distance", "max |t - t_double| / t_double", "<= 1e-5", "%.3g", worst);
}

/* ------------------------------------------------------------------------------------------ */
/* 5. the Cornell box far from the origin                                                      */

/* The final Cornell box of Shirley's "Ray Tracing: The Rest of Your Life" (examples/cornell.c)
   moved by (d, d, d), every point handed to pdftrace in float as a C API user would: the sum
   in double, rounded once; the rotated box under a float pt_transform. */
static pt_scene *st_cornell(double d, pt_camera_desc *cam)
{
    static const double Q[6][9] = { { 555, 0, 0, 0, 555, 0, 0, 0, 555 },       { 0, 0, 555, 0, 0, -555, 0, 555, 0 },
                                    { 0, 0, 0, 555, 0, 0, 0, 0, 555 },         { 555, 555, 555, -555, 0, 0, 0, 0, -555 },
                                    { 0, 0, 555, 555, 0, 0, 0, 555, 0 },       { 343, 554, 332, -130, 0, 0, 0, 0, -105 } };
    pt_scene *s = pt_scene_create();
    int m[6], rc = 0, i;
    pt_transform xf;
    dv3 o = dv(d, d, d);
    if (!s) return NULL;
    m[1] = pt_scene_add_lambertian(s, pt_v3(0.65f, 0.05f, 0.05f));
    m[2] = m[3] = m[4] = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
    m[0] = pt_scene_add_lambertian(s, pt_v3(0.12f, 0.45f, 0.15f));
    m[5] = pt_scene_add_emitter(s, pt_v3(15, 15, 15), 0);
    for (i = 0; i < 6; i++)
        rc |= pt_scene_add_quad(s, dv_to(dadd(o, dv(Q[i][0], Q[i][1], Q[i][2]))), pt_v3((float)Q[i][3], (float)Q[i][4], (float)Q[i][5]),
                                pt_v3((float)Q[i][6], (float)Q[i][7], (float)Q[i][8]), m[i]) < 0;
    xf = pt_transform_mul(pt_transform_translate(dv_to(dadd(o, dv(265, 0, 295)))), pt_transform_rotate_y(15));
    rc |= pt_scene_set_transform(s, &xf) != PT_OK;
    rc |= pt_scene_add_box(s, pt_v3(0, 0, 0), pt_v3(165, 330, 165), m[2]) < 0;
    rc |= pt_scene_set_transform(s, NULL) != PT_OK;
    rc |= pt_scene_add_sphere(s, dv_to(dadd(o, dv(190, 90, 190))), 90, pt_scene_add_dielectric(s, 1.5f)) < 0;
    if (rc || pt_scene_commit(s) != PT_OK) {
        fprintf(stderr, "stress: Cornell box at %g: %s\n", d, pt_scene_error_message(s));
        pt_scene_destroy(s);
        return NULL;
    }
    memset(cam, 0, sizeof *cam);
    cam->look_from = dv_to(dadd(o, dv(278, 278, -800)));
    cam->look_at = dv_to(dadd(o, dv(278, 278, 0)));
    cam->vfov_degrees = 40;
    return s;
}

/* The box moved by 1e5 .. 1e7 against the box at the origin, with the same seed: the renders
   trace the same paths up to rounding, so the region means differ by what the offset changes,
   not by noise; each 4x4 region's mean within 1 % (deterministic: fixed seeds). */
void st_cornell_offset(st_ctx *c)
{
    static const double D[] = { 1e5, 1e6, 9.99e6, 1e7 };
    int W = c->full ? 64 : 32, spp = c->full ? 256 : 16, depth = 8, i, k;
    pt_film ref;
    pt_render_stats st;
    pt_camera_desc cam;
    pt_scene_info info;
    pt_scene *s = st_cornell(0.0, &cam);
    double mr[16], sr[16];
    uint64_t nonfinite = 0;
    if (!s || st_render(c, s, &cam, W, W, spp, depth, PT_STRATEGY_MIS, 5, &ref, &st) != PT_OK) {
        st_row(c, 0, "cornell at the origin", "render", "PT_OK", "failed");
        pt_scene_destroy(s);
        return;
    }
    nonfinite += st.nonfinite_samples;
    pt_scene_get_info(s, &info);
    st_row(c, info.precision_warnings == 0, "cornell at the origin", "precision warnings at commit", "0", "%u",
           (unsigned)info.precision_warnings);
    pt_scene_destroy(s);
    st_regions(&ref, 4, 4, mr, sr);
    for (i = 0; i < (int)(sizeof D / sizeof D[0]); i++) {
        pt_film f;
        double mf[16], sf[16], worst = 0.0, sum_f = 0.0, sum_r = 0.0;
        int at = -1, rc;
        char cas[48];
        snprintf(cas, sizeof cas, "cornell moved by %g", D[i]);
        s = st_cornell(D[i], &cam);
        rc = s ? st_render(c, s, &cam, W, W, spp, depth, PT_STRATEGY_MIS, 5, &f, &st) : -1;
        if (s) pt_scene_get_info(s, &info);
        pt_scene_destroy(s);
        if (rc != PT_OK) { st_row(c, 0, cas, "render", "PT_OK", "rc %d", rc); continue; }
        nonfinite += st.nonfinite_samples;
        st_regions(&f, 4, 4, mf, sf);
        for (k = 0; k < 16; k++) {
            double rel = fabs(mf[k] / mr[k] - 1.0);
            if (!(rel <= worst)) { worst = rel; at = k; }
            sum_f += mf[k];
            sum_r += mr[k];
        }
        st_row(c, worst <= 0.01, cas, "4x4 region means vs the origin's, same seed: max rel. diff", "<= 1 %",
               "%.3f %% (region %d; image %+.3f %%)", 100.0 * worst, at, 100.0 * (sum_f / sum_r - 1.0));
        st_row(c, info.precision_warnings == 0, cas, "precision warnings at commit", "0", "%u",
               (unsigned)info.precision_warnings);
        pt_film_free(&f);
    }
    pt_film_free(&ref);
    st_row(c, nonfinite == 0, "cornell: all renders", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
}

/* ------------------------------------------------------------------------------------------ */
/* 4. path guiding under the same stress                                                       */

/* The scale-sweep room rendered with path guiding on at every place (scales 1e-6 .. 1e6 and far
   offsets): the guided image against the unguided unit room; a guide held to its smallest memory
   bound (it must stop refining, still unbiased); and emission scaled by 1e-6 and 1e6 (the
   fixed-point sums follow the brightest emitter), guided image / scale against unit emission. */
static void st_guiding_place(st_ctx *c, const st_place *pl, const st_mesh *ico, float *scratch, const pt_film *ref,
                             int W, int spp, uint64_t seed, uint64_t *nonfinite)
{
    pt_camera_desc cam;
    pt_scene *s = st_room(pl, 1, ico, scratch, &cam);
    pt_render_desc d = tu_base_desc(W, W, spp, seed);
    pt_render_stats st;
    pt_film f;
    char cas[64];
    int rc, worst = -1;
    double z;
    snprintf(cas, sizeof cas, "guiding %s", pl->name);
    if (!s) { st_row(c, 0, cas, "scene", "built", "failed"); return; }
    d.camera = cam;
    d.max_depth = 4;
    d.threads = c->threads;
    d.guiding = PT_GUIDING_ON;
    rc = pt_film_init(&f, W, W) == PT_OK ? pt_render(s, &d, &f, &st) : PT_ERROR_OUT_OF_MEMORY;
    pt_scene_destroy(s);
    if (rc != PT_OK) { st_row(c, 0, cas, "render", "PT_OK", "rc %d", rc); pt_film_free(&f); return; }
    *nonfinite += st.nonfinite_samples;
    z = st_compare(c, &f, ref, 2, 2, &worst);
    st_row(c, z <= c->z_bound && st.guiding_used == 1, cas, "guided image vs unguided unit: max|z| 2x2 regions",
           st_zb(c), "%.2f (region %d), %u leaves", z, worst, st.guiding_leaves);
    pt_film_free(&f);
}

/* The far-reflector scene (a floor lit by a small two-sided lamp and by a reflector above it)
   with emission x k, rendered guided; its film divided by k. */
static int st_reflector(const st_ctx *c, float k, int W, int spp, uint64_t seed, int guided, pt_film *f,
                        pt_render_stats *st)
{
    pt_scene *s = pt_scene_create();
    pt_render_desc d = tu_base_desc(W, W, spp, seed);
    int white, lamp, rc = 0;
    size_t i;
    if (!s) return PT_ERROR_OUT_OF_MEMORY;
    white = pt_scene_add_lambertian(s, pt_v3(0.7f, 0.7f, 0.7f));
    lamp = pt_scene_add_emitter(s, pt_v3(10 * k, 10 * k, 10 * k), 1);
    rc |= pt_scene_add_quad(s, pt_v3(-5, 0, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), white) < 0;
    rc |= pt_scene_add_quad(s, pt_v3(-2, 20, -2), pt_v3(4, 0, 0), pt_v3(0, 0, 4), white) < 0;
    rc |= pt_scene_add_quad(s, pt_v3(-0.5f, 19.5f, -0.5f), pt_v3(1, 0, 0), pt_v3(0, 0, 1), lamp) < 0;
    if (rc || pt_scene_commit(s) != PT_OK) { pt_scene_destroy(s); return PT_ERROR_INVALID_ARGUMENT; }
    d.camera.look_from = pt_v3(0, 3, -3);
    d.camera.look_at = pt_v3(0, 0, 0);
    d.camera.vfov_degrees = 40;
    d.max_depth = 4;
    d.threads = c->threads;
    d.guiding = guided ? PT_GUIDING_ON : PT_GUIDING_OFF;
    rc = pt_film_init(f, W, W) == PT_OK ? pt_render(s, &d, f, st) : PT_ERROR_OUT_OF_MEMORY;
    pt_scene_destroy(s);
    for (i = 0; rc == PT_OK && i < 3u * (size_t)W * (size_t)W; i++) {
        f->sum[i] /= (double)k;
        f->sum_odd[i] /= (double)k;
        f->sum_sq[i] /= (double)k * (double)k;
    }
    return rc;
}

void st_guiding(st_ctx *c)
{
    st_place pl[ST_NPLACES], unit;
    st_mesh ico;
    float *scratch;
    int W = c->full ? 40 : 20, spp = c->full ? 128 : 16, RW = c->full ? 48 : 24, rspp = c->full ? 256 : 32, i;
    static const float ks[] = {1e-6f, 1e6f};
    pt_film ref, rref;
    pt_camera_desc cam;
    pt_render_stats st;
    pt_scene *s;
    uint64_t nonfinite = 0;
    st_places(pl);
    st_icosphere(&ico, 1);
    scratch = (float *)malloc(sizeof(float) * 3 * (size_t)ico.nv);
    unit.s = 1; unit.off = dv(0, 0, 0); unit.name = "unit";
    s = st_room(&unit, 1, &ico, scratch, &cam);
    if (!s || st_render(c, s, &cam, W, W, spp, 4, PT_STRATEGY_MIS, 7, &ref, &st) != PT_OK) {
        st_row(c, 0, "guiding: unit scene", "render", "PT_OK", "failed");
        pt_scene_destroy(s); st_mesh_free(&ico); free(scratch);
        return;
    }
    pt_scene_destroy(s);
    for (i = 0; i < ST_NPLACES; i += c->full ? 1 : 4)
        st_guiding_place(c, &pl[i], &ico, scratch, &ref, W, spp, 400 + (uint64_t)i, &nonfinite);
    {   /* the smallest memory bound: refinement stops there, the image stays unbiased */
        pt_guide_desc gd;
        pt_guide *g = NULL;
        pt_guide_info gi;
        pt_render_desc d = tu_base_desc(W, W, spp, 77);
        pt_film f;
        double z;
        int rc;
        memset(&gd, 0, sizeof gd);
        gd.max_bytes = 4096;
        s = st_room(&unit, 1, &ico, scratch, &cam);
        rc = s ? pt_guide_create_for_scene(s, &gd, &g) : PT_ERROR_OUT_OF_MEMORY;
        d.camera = cam;
        d.max_depth = 4;
        d.threads = c->threads;
        d.guiding = PT_GUIDING_ON;
        d.guiding_guide = g;
        if (rc == PT_OK) rc = pt_film_init(&f, W, W) == PT_OK ? pt_render(s, &d, &f, &st) : PT_ERROR_OUT_OF_MEMORY;
        if (rc == PT_OK && pt_guide_get_info(g, &gi) == PT_OK) {
            nonfinite += st.nonfinite_samples;
            z = st_compare(c, &f, &ref, 4, 4, NULL);
            st_row(c, z <= c->z_bound && gi.at_memory_bound == 1 && gi.bytes <= 2 * gd.max_bytes + 4096,
                   "guiding: 4 KiB memory bound", "at the bound; image vs unguided max|z|", st_zb(c),
                   "at bound %d, %lu bytes held; %.2f", gi.at_memory_bound, (unsigned long)gi.bytes, z);
            pt_film_free(&f);
        } else {
            st_row(c, 0, "guiding: 4 KiB memory bound", "render", "PT_OK", "rc %d", rc);
        }
        pt_guide_destroy(g);
        pt_scene_destroy(s);
    }
    if (st_reflector(c, 1.0f, RW, rspp, 5, 0, &rref, &st) != PT_OK) {
        st_row(c, 0, "guiding: reflector", "render", "PT_OK", "failed");
    } else {
        for (i = 0; i < (int)(sizeof ks / sizeof ks[0]); i++) {
            pt_film f;
            char cas[64];
            double z;
            snprintf(cas, sizeof cas, "guiding: emission x %g", (double)ks[i]);
            if (st_reflector(c, ks[i], RW, rspp, 50 + (uint64_t)i, 1, &f, &st) != PT_OK) {
                st_row(c, 0, cas, "render", "PT_OK", "failed");
                continue;
            }
            nonfinite += st.nonfinite_samples;
            z = st_compare(c, &f, &rref, 4, 4, NULL);
            st_row(c, z <= c->z_bound && st.guiding_used == 1, cas, "guided / scale vs unguided x 1: max|z| 4x4",
                   st_zb(c), "%.2f", z);
            pt_film_free(&f);
        }
        pt_film_free(&rref);
    }
    {   /* the RTRL box (its glass ball: caustic photons) at the origin and moved by 1e6: guided
           against unguided at the same place */
        static const double D[] = { 0.0, 1e6 };
        int CW = c->full ? 32 : 16, cspp = c->full ? 256 : 32, k;
        for (k = 0; k < 2; k++) {
            pt_scene *cs = st_cornell(D[k], &cam);
            pt_film u, f;
            pt_render_desc d = tu_base_desc(CW, CW, cspp, 61 + (uint64_t)k);
            char cas[64];
            double z;
            int rc;
            snprintf(cas, sizeof cas, "guiding: cornell (glass) at %g", D[k]);
            if (!cs || st_render(c, cs, &cam, CW, CW, cspp, 8, PT_STRATEGY_MIS, 71 + (uint64_t)k, &u, &st) != PT_OK) {
                st_row(c, 0, cas, "unguided render", "PT_OK", "failed");
                pt_scene_destroy(cs);
                continue;
            }
            nonfinite += st.nonfinite_samples;
            d.camera = cam;
            d.max_depth = 8;
            d.threads = c->threads;
            d.guiding = PT_GUIDING_ON;
            rc = pt_film_init(&f, CW, CW) == PT_OK ? pt_render(cs, &d, &f, &st) : PT_ERROR_OUT_OF_MEMORY;
            if (rc == PT_OK) {
                nonfinite += st.nonfinite_samples;
                z = st_compare(c, &f, &u, 2, 2, NULL);
                st_row(c, z <= c->z_bound && st.guiding_used == 1 && st.guiding_photons > 0, cas,
                       "guided (caustic photons) vs unguided: max|z| 2x2", st_zb(c), "%.2f, %llu photons", z,
                       (unsigned long long)st.guiding_photons);
                pt_film_free(&f);
            } else {
                st_row(c, 0, cas, "guided render", "PT_OK", "rc %d", rc);
            }
            pt_film_free(&u);
            pt_scene_destroy(cs);
        }
    }
    pt_film_free(&ref);
    st_row(c, nonfinite == 0, "guiding: all renders", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
    st_mesh_free(&ico);
    free(scratch);
}

/* ------------------------------------------------------------------------------------------ */
/* delta lights: point, spot and directional lights at every scale, tiny cones, close, grazing  */

/* The radiance (green) of one direct-light path (max_depth 1) from `from` to the plane point `to`:
   a delta light's estimate there has no variance, so it equals rho E / pi up to rounding. */
static double st_delta_probe(const pt_scene *s, pt_vec3 from, pt_vec3 to, uint64_t *nonfinite)
{
    pt_render_desc d = tu_base_desc(1, 1, 1, 1);
    pt_ray r;
    pt_rng rng;
    pt_path_stats ps;
    pt_color L;
    d.max_depth = 1;
    r.origin = from;
    r.dir = pt_normalize(pt_sub(to, from));
    pt_rng_seed(&rng, 1, 1);
    memset(&ps, 0, sizeof ps);
    L = pt_trace_path(s, &d, r, &rng, &ps);
    *nonfinite += ps.nonfinite_samples;
    return (double)L.y;
}
static double st_rel(double got, double want) { return want != 0.0 ? fabs(got - want) / fabs(want) : fabs(got); }

/* A Lambertian plane y = 0 (rho 0.5, 2 x 2 units, scaled and moved by pl) with one delta light. */
static pt_scene *st_delta_plane(const st_place *pl, const pt_light_desc *light)
{
    pt_scene *s = pt_scene_create();
    int m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    pt_light_desc d = *light;
    d.position = sp_p(pl, light->position.x, light->position.y, light->position.z);
    d.intensity = pt_scale(light->intensity, (float)(pl->s * pl->s)); /* E stays the same at every scale */
    if (light->type == PT_LIGHT_DIRECTIONAL) d.intensity = light->intensity;
    if (pt_scene_add_quad(s, sp_p(pl, -1, 0, -1), sp_v(pl, 0, 0, 2), sp_v(pl, 2, 0, 0), m) < 0 ||
        pt_scene_add_light(s, &d) < 0 || pt_scene_commit(s) != PT_OK) {
        fprintf(stderr, "stress: delta plane at %s: %s\n", pl->name, pt_scene_error_message(s));
        pt_scene_destroy(s);
        return NULL;
    }
    return s;
}

/* E at plane point (x, 0, z) of the unit scene, in double: I f cos / d^2, or E0 cos. */
static double st_delta_E(const pt_light_desc *l, double x, double z)
{
    dv3 p = dv(x, 0, z), lp = dv(l->position.x, l->position.y, l->position.z), w, ax;
    double d2, d, f = 1.0, ang;
    if (l->type == PT_LIGHT_DIRECTIONAL) {
        ax = dnorm(dv(l->direction.x, l->direction.y, l->direction.z));
        return l->intensity.y * fmax(0.0, -ax.y);
    }
    w = dsub(lp, p);
    d2 = ddot(w, w);
    d = sqrt(d2);
    if (l->type == PT_LIGHT_SPOT) {
        ax = dnorm(dv(l->direction.x, l->direction.y, l->direction.z));
        ang = atan2(dlen(dcross(ax, dscale(w, -1.0 / d))), -ddot(ax, w) / d) * (180.0 / TU_PI);
        f = ang <= l->beam_width ? 1.0 : ang >= l->cutoff_angle ? 0.0 : (l->cutoff_angle - ang) / (l->cutoff_angle - l->beam_width);
    }
    return l->intensity.y * f * fmax(0.0, w.y / d) / d2;
}

/* At every scale and offset of the sweep, a point, a spot and a directional light over the plane
   give the unit scene's irradiance (intensities scaled by s^2) at three probe points each. */
static void st_delta_sweep(st_ctx *c)
{
    st_place pl[ST_NPLACES];
    pt_light_desc L[3];
    static const double px[3] = {0.0, 0.31, -0.47}, pz[3] = {0.0, -0.22, 0.38};
    int i, k, j;
    st_places(pl);
    memset(L, 0, sizeof L);
    L[0].type = PT_LIGHT_POINT; L[0].position = pt_v3(0.1f, 0.6f, -0.05f); L[0].intensity = pt_v3(1, 1, 1);
    L[1].type = PT_LIGHT_SPOT; L[1].position = pt_v3(-0.1f, 0.8f, 0.1f); L[1].direction = pt_v3(0.1f, -1, -0.05f);
    L[1].intensity = pt_v3(2, 2, 2); L[1].cutoff_angle = 40; L[1].beam_width = 15;
    L[2].type = PT_LIGHT_DIRECTIONAL; L[2].direction = pt_v3(0.3f, -1, 0.2f); L[2].intensity = pt_v3(1.5f, 1.5f, 1.5f);
    for (i = 0; i < ST_NPLACES; i++) {
        double worst = 0.0;
        uint64_t nf = 0;
        int ok = 1;
        for (k = 0; k < 3 && ok; k++) {
            pt_scene *s = st_delta_plane(&pl[i], &L[k]);
            if (!s) { ok = 0; break; }
            for (j = 0; j < 3; j++) {
                double want = 0.5 / TU_PI * st_delta_E(&L[k], px[j], pz[j]);
                double got = st_delta_probe(s, sp_p(&pl[i], px[j] + 0.01, 0.3, pz[j]), sp_p(&pl[i], px[j], 0, pz[j]), &nf);
                worst = fmax(worst, st_rel(got, want));
            }
            pt_scene_destroy(s);
        }
        st_row(c, ok && nf == 0 && worst <= 1e-5, "delta lights sweep", pl[i].name,
               "rel err <= 1e-5", "%s%.1e (9 probes), %llu NaN/Inf", ok ? "" : "setup failed; ", worst, (unsigned long long)nf);
    }
}

/* Spot cones from 10 down to 0.01 degrees (beam half the cutoff): the axis, the beam's middle, the
   falloff's middle (f = 1/2) and just outside; the angle is the light's own float arithmetic on
   positions 1 unit away, so a cone of 0.01 degrees (1.7e-4 rad) resolves to ~1e-7 / 1.7e-4. */
static void st_delta_tiny_cones(st_ctx *c)
{
    static const double cones[4] = {10.0, 1.0, 0.1, 0.01};
    static const double at[4] = {0.0, 0.25, 0.75, 1.05}; /* fractions of the cutoff */
    st_place unit;
    int i, j;
    unit.s = 1.0;
    unit.off = dv(0, 0, 0);
    unit.name = "x1";
    for (i = 0; i < 4; i++) {
        pt_light_desc l;
        pt_scene *s;
        double worst = 0.0;
        uint64_t nf = 0;
        char name[48];
        memset(&l, 0, sizeof l);
        l.type = PT_LIGHT_SPOT;
        l.position = pt_v3(0, 1, 0);
        l.direction = pt_v3(0, -1, 0);
        l.intensity = pt_v3(1, 1, 1);
        l.cutoff_angle = (float)cones[i];
        l.beam_width = (float)(cones[i] / 2);
        snprintf(name, sizeof name, "cutoff %g deg, beam %g deg", cones[i], cones[i] / 2);
        s = st_delta_plane(&unit, &l);
        if (!s) { st_row(c, 0, "delta spot cones", name, "set up", "failed"); continue; }
        for (j = 0; j < 4; j++) {
            double x = tan(at[j] * cones[i] * TU_PI / 180.0), want = 0.5 / TU_PI * st_delta_E(&l, x, 0.0);
            double got = st_delta_probe(s, pt_v3((float)x, 0.5f, 0.0f), pt_v3((float)x, 0, 0), &nf);
            /* outside the cone: exactly 0; inside: relative; at the falloff's middle absolute in f */
            worst = fmax(worst, want == 0.0 ? (got != 0.0 ? 1.0 : 0.0) : st_rel(got, want));
        }
        pt_scene_destroy(s);
        st_row(c, nf == 0 && worst <= 1e-3, "delta spot cones", name, "rel err <= 1e-3", "%.1e (4 probes), %llu NaN/Inf", worst,
               (unsigned long long)nf);
    }
}

/* A point light close to the plane (height h, intensity h^2: E = 1 at its foot) and a directional
   light at grazing elevation (E = E0 sin e): accurate down to h = 1e-5 (the light's distance is
   taken from the surface point, not from the spawn point ~3e-5 above it) and e = 0.01 degrees; at
   h = 1e-7, a few float roundings of the plane's coordinates, only finiteness is required. */
static void st_delta_close_grazing(st_ctx *c)
{
    static const double hs[4] = {1e-1, 1e-3, 1e-5, 1e-7};
    static const double es[3] = {10.0, 1.0, 0.01};
    st_place unit;
    int i;
    unit.s = 1.0;
    unit.off = dv(0, 0, 0);
    unit.name = "x1";
    for (i = 0; i < 4; i++) {
        pt_light_desc l;
        pt_scene *s;
        uint64_t nf = 0;
        double got, want = 0.5 / TU_PI, err;
        char name[48];
        int accurate = hs[i] >= 1e-5;
        memset(&l, 0, sizeof l);
        l.type = PT_LIGHT_POINT;
        l.position = pt_v3(0.2f, (float)hs[i], 0.1f);
        l.intensity = pt_v3((float)(hs[i] * hs[i]), (float)(hs[i] * hs[i]), (float)(hs[i] * hs[i]));
        snprintf(name, sizeof name, "point light at height %g", hs[i]);
        s = st_delta_plane(&unit, &l);
        if (!s) { st_row(c, 0, "delta close and grazing", name, "set up", "failed"); continue; }
        got = st_delta_probe(s, pt_v3(0.2f, 0.5f, 0.1f), pt_v3(0.2f, 0, 0.1f), &nf);
        err = st_rel(got, want);
        pt_scene_destroy(s);
        st_row(c, nf == 0 && got == got && (!accurate || err <= 1e-4), "delta close and grazing", name,
               accurate ? "rel err <= 1e-4" : "finite", "%.1e, %llu NaN/Inf", err, (unsigned long long)nf);
    }
    for (i = 0; i < 3; i++) {
        pt_light_desc l;
        pt_scene *s;
        uint64_t nf = 0;
        double e = es[i] * TU_PI / 180.0, got, want, err;
        char name[48];
        memset(&l, 0, sizeof l);
        l.type = PT_LIGHT_DIRECTIONAL;
        l.direction = pt_v3((float)cos(e), (float)-sin(e), 0.0f);
        l.intensity = pt_v3(1, 1, 1);
        snprintf(name, sizeof name, "directional at elevation %g deg", es[i]);
        s = st_delta_plane(&unit, &l);
        if (!s) { st_row(c, 0, "delta close and grazing", name, "set up", "failed"); continue; }
        want = 0.5 / TU_PI * st_delta_E(&l, 0.0, 0.0);
        got = st_delta_probe(s, pt_v3(0, 0.5f, 0.01f), pt_v3(0, 0, 0), &nf);
        err = st_rel(got, want);
        pt_scene_destroy(s);
        st_row(c, nf == 0 && err <= 1e-5, "delta close and grazing", name, "rel err <= 1e-5", "%.1e, %llu NaN/Inf", err,
               (unsigned long long)nf);
    }
}

void st_delta_lights(st_ctx *c)
{
    st_delta_sweep(c);
    st_delta_tiny_cones(c);
    st_delta_close_grazing(c);
}

/* ------------------------------------------------------------------------------------------ */
/* the environment light: contrasts, zeros and small suns                                      */

/* A w x h map of grey value v (rgb malloc'd), or NULL. */
static float *st_env_flat(pt_image *img, int w, int h, float v)
{
    size_t i, n = 3 * (size_t)w * (size_t)h;
    img->width = w;
    img->height = h;
    img->rgb = (float *)malloc(sizeof(float) * n);
    if (img->rgb)
        for (i = 0; i < n; i++) img->rgb[i] = v;
    return img->rgb;
}
static void st_env_pixel(pt_image *img, int x, int y, float v)
{
    float *p = img->rgb + 3 * ((size_t)y * (size_t)img->width + (size_t)x);
    p[0] = p[1] = p[2] = v;
}

/* One environment case: a Lambertian plane y = 0 (rho 0.5) under the map (and a grey background
   bg), radiance at a plane point from N paths of pt_trace_path (direct light only) under LIGHT,
   MIS and MIXTURE against rho E / pi, E = pi bg + the map's irradiance integrated from
   pt_scene_environment_radiance (tu_env_irradiance); z beyond the float floor, one comparison
   per strategy. Also the per-sample relative variance Var / E^2 of LIGHT and MIS, which the map's
   importance sampling keeps small: uniform sampling of the sphere would give ~4 pi / Omega for
   a light of solid angle Omega (1e5 for the 1e-4 sr sun); the bound is 20. */
static void st_env_case(st_ctx *c, const char *cas, const pt_image *map, double bg, uint64_t seed, uint64_t *nonfinite)
{
    static const pt_strategy strats[3] = { PT_STRATEGY_LIGHT, PT_STRATEGY_MIS, PT_STRATEGY_MIXTURE };
    const double rho = 0.5;
    const long N = c->full ? 200000L : 4000L;
    pt_scene *s = pt_scene_create();
    pt_environment_desc d;
    int white = pt_scene_add_lambertian(s, pt_v3((float)rho, (float)rho, (float)rho)), si, rc;
    double E, qerr = 0.0, want, zmax = 0.0, rv = 0.0;
    rc = pt_scene_add_quad(s, pt_v3(-10, 0, -10), pt_v3(0, 0, 20), pt_v3(20, 0, 0), white);
    d.map = map;
    d.scale = 0.0f;
    rc = rc >= 0 ? pt_scene_set_environment(s, &d) : rc;
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (rc != PT_OK) {
        st_row(c, 0, cas, "set up", "PT_OK", "%s", pt_scene_error_message(s));
        pt_scene_destroy(s);
        return;
    }
    E = TU_PI * bg + tu_env_irradiance(s, map->width, map->height, NULL, dv(0, 1, 0), 1, &qerr);
    want = rho * E / TU_PI;
    for (si = 0; si < 3; si++) {
        pt_render_desc rd = tu_base_desc(1, 1, 1, 0);
        pt_rng rng;
        pt_ray r;
        pt_path_stats ps;
        tu_acc acc;
        long n;
        memset(&acc, 0, sizeof acc);
        memset(&ps, 0, sizeof ps);
        rd.max_depth = 1;
        rd.rr_start_depth = -1;
        rd.strategy = strats[si];
        rd.light_weight = 0.5f;
        rd.background = pt_v3((float)bg, (float)bg, (float)bg);
        pt_rng_seed(&rng, seed + (uint64_t)si, 9);
        r.origin = pt_v3(0.3f, 0.4f, 0.2f);
        r.dir = pt_normalize(pt_sub(pt_v3(0.1f, 0, 0.05f), r.origin));
        for (n = 0; n < N; n++) tu_acc_add(&acc, pt_trace_path(s, &rd, r, &rng, &ps).y);
        *nonfinite += ps.nonfinite_samples;
        zmax = fmax(zmax, tu_z_floor(acc.mean, want, tu_acc_se(&acc), TU_FLOAT_FLOOR * want + qerr * rho / TU_PI));
        if (strats[si] != PT_STRATEGY_MIXTURE) rv = fmax(rv, tu_acc_var(&acc) / (want * want));
    }
    c->comparisons += 3;
    st_row(c, zmax <= c->z_bound, cas, "plane radiance vs rho E/pi, LIGHT/MIS/MIXTURE: max|z|", st_zb(c), "%.2f (E = %.6g)",
           zmax, E);
    st_row(c, rv <= 20.0, cas, "relative variance Var/E^2 per sample, LIGHT and MIS", "<= 20", "%.3g", rv);
    pt_scene_destroy(s);
}

/* Maps of 1e6:1 contrast and with zeros: one pixel of 1e6 in a field of 1 (64 x 32); black but for
   one row, in the middle and at the zenith; suns (discs of pixels of radiance 1 / Omega, so that
   their irradiance at normal incidence is ~1) of solid angle Omega = 1e-2, 1e-3 and (make stress)
   1e-4 sr, 40 degrees from the zenith, on a black map of at least ~10 pixels per sun, under a
   grey background sky of 0.2 (sampled uniformly, mixed with the map by power). The delta-light
   case covers spot cones down to 0.01 degrees. */
void st_environment(st_ctx *c)
{
    pt_image m;
    uint64_t nonfinite = 0;
    int k, x, y;
    if (st_env_flat(&m, 64, 32, 1.0f)) {
        st_env_pixel(&m, 20, 9, 1e6f);
        st_env_case(c, "env: hot pixel 1e6 in a field of 1", &m, 0.0, 12000, &nonfinite);
        free(m.rgb);
    }
    for (k = 0; k < 2; k++) {
        if (!st_env_flat(&m, 64, 32, 0.0f)) break;
        for (x = 0; x < 64; x++) st_env_pixel(&m, x, k == 0 ? 10 : 0, 1.0f);
        st_env_case(c, k == 0 ? "env: one row lit (10 of 32)" : "env: one row lit (the top)", &m, 0.0, 12010 + 10 * (uint64_t)k,
                    &nonfinite);
        free(m.rgb);
    }
    for (k = 2; k <= (c->full ? 4 : 3); k++) {
        double omega = pow(10.0, -k), r = acos(1.0 - omega / (2.0 * TU_PI));
        int h = k == 4 ? 1024 : 256, count = 0;
        dv3 sun = tu_env_dir(0.3, 40.0 / 180.0);
        char cas[64];
        if (!st_env_flat(&m, 2 * h, h, 0.0f)) break;
        for (y = 0; y < h; y++)
            for (x = 0; x < 2 * h; x++)
                if (ddot(tu_env_dir((x + 0.5) / (2 * h), (y + 0.5) / h), sun) >= cos(r)) {
                    st_env_pixel(&m, x, y, (float)(1.0 / omega));
                    count++;
                }
        snprintf(cas, sizeof cas, "env: sun 1e-%d sr (%d pixels)", k, count);
        st_env_case(c, cas, &m, 0.2, 12040 + 10 * (uint64_t)k, &nonfinite);
        free(m.rgb);
    }
    st_row(c, nonfinite == 0, "env: all", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
}

/* Rough conductors from roughness 1e-4 (the delta mirror below 1e-3) to 1, incidence from 0 to
   89.99 degrees. A white (F = 1, tint 1) conductor sphere under a uniform background of 1, one ray
   meeting it at angle theta: under MATERIAL every sample is F G1(wi) <= 1 (the visible-normal
   sampler's weight); MIS as well, for NaN/Inf. The material PDF at those angles
   (and exactly tangent, cos 0): every draw finite with a positive density equal to pt_pdf_value. */
void st_microfacet(st_ctx *c)
{
    static const float rough[7] = { 1e-4f, 9.9e-4f, 1e-3f, 1e-2f, 0.1f, 0.5f, 1.0f };
    static const double angle[7] = { 0.0, 45.0, 80.0, 89.0, 89.9, 89.99, 90.0 };
    const int n = c->full ? 20000 : 2000;
    uint64_t nonfinite = 0;
    int ri, ai, i;
    for (ri = 0; ri < 7; ri++) {
        pt_scene *s = pt_scene_create();
        int m = s ? pt_scene_add_rough_conductor(s, PT_CONDUCTOR_NONE, rough[ri], pt_v3(1, 1, 1)) : -1;
        double worst_max = 0.0;
        long bad_draws = 0, draws = 0;
        char cas[64];
        snprintf(cas, sizeof cas, "microfacet: alpha %g", (double)rough[ri]);
        if (m < 0 || pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m) < 0 || pt_scene_commit(s) != PT_OK) {
            st_row(c, 0, cas, "scene", "builds", "%s", s ? pt_scene_error_message(s) : "out of memory");
            pt_scene_destroy(s);
            continue;
        }
        for (ai = 0; ai < 7; ai++) {
            double th = angle[ai] * TU_PI / 180.0;
            pt_vec3 nrm = pt_v3(0, 0, 1), wo = dv_to(dnorm(dv(sin(th), 0.0, cos(th))));
            pt_pdf p = pt_pdf_material(s, m, nrm, wo);
            pt_rng rng;
            int strat;
            pt_rng_seed(&rng, 13000 + (uint64_t)(ri * 10 + ai), 1);
            for (i = 0; i < n; i++) {
                pt_vec3 d;
                float pv, v;
                if (!pt_pdf_sample(&p, &rng, &d, &pv)) continue;
                draws++;
                v = pt_pdf_value(&p, d);
                if (!(pv > 0.0f) || !isfinite(pv) || v != pv || !isfinite(d.x + d.y + d.z)) bad_draws++;
            }
            if (ai == 6) continue; /* a ray cannot meet the sphere at exactly 90 degrees */
            for (strat = 0; strat < 2; strat++) {
                pt_render_desc d = tu_base_desc(1, 1, 1, 0);
                pt_path_stats st;
                pt_ray ray;
                double sum = 0.0, mx = 0.0;
                memset(&st, 0, sizeof st);
                d.background = pt_v3(1, 1, 1);
                d.strategy = strat == 0 ? PT_STRATEGY_MATERIAL : PT_STRATEGY_MIS;
                d.rr_start_depth = -1;
                ray.origin = pt_v3((float)sin(th), 0.0f, 10.0f);
                ray.dir = pt_v3(0, 0, -1);
                for (i = 0; i < n; i++) {
                    pt_color L = pt_trace_path(s, &d, ray, &rng, &st);
                    sum += L.x;
                    mx = fmax(mx, fmax(L.x, fmax(L.y, L.z)));
                }
                nonfinite += st.nonfinite_samples;
                if (strat == 0) worst_max = fmax(worst_max, mx);
                if (strat == 0 && sum / n > 1.0 + 1e-5) worst_max = fmax(worst_max, sum / n);
            }
        }
        st_row(c, worst_max <= 1.0 + 1e-5, cas, "largest MATERIAL sample, 0 .. 89.99 degrees", "<= 1", "%.6f", worst_max);
        st_row(c, bad_draws == 0, cas, "PDF draws (0 .. 90 degrees) non-finite or != pt_pdf_value", "0", "%ld of %ld", bad_draws,
               draws);
        pt_scene_destroy(s);
    }
    st_row(c, nonfinite == 0, "microfacet: all", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
}

/* Rough plastics from roughness 1e-4 (rendered at 1e-3) to 1 and coat indices from 1.0001 to 3,
   incidence from 0 to 89.99 degrees (and exactly tangent for the PDF). The material PDF: every
   draw finite with a positive density equal to pt_pdf_value. A white base (albedo 1) on a sphere
   under a uniform background of 1, one ray at angle theta, MATERIAL and MIS: no NaN/Inf, and the
   mean over the angles (each the directional albedo, <= 1 for this model: test_plastic.c) not
   above 1 (one-sided z). The mixture's weight f cos / p has no bound of 1 (a coat facet can
   reflect more than the coat's mean share predicts); the largest is reported. */
void st_plastic(st_ctx *c)
{
    static const float rough[8] = { 1e-4f, 1e-3f, 1e-2f, 0.1f, 0.5f, 1.0f, 0.1f, 1e-4f };
    static const float iors[8] = { 1.5f, 1.5f, 1.5f, 1.5f, 1.5f, 1.5f, 1.0001f, 3.0f };
    static const double angle[7] = { 0.0, 45.0, 80.0, 89.0, 89.9, 89.99, 90.0 };
    const int n = c->full ? 20000 : 1000;
    uint64_t nonfinite = 0;
    int ri, ai, i;
    for (ri = 0; ri < 8; ri++) {
        pt_scene *s = pt_scene_create();
        int m = s ? pt_scene_add_rough_plastic(s, pt_v3(1, 1, 1), rough[ri], iors[ri]) : -1;
        double worst_max = 0.0, sum = 0.0, sum2 = 0.0, mean, se, z;
        long bad_draws = 0, draws = 0, paths = 0;
        char cas[64];
        snprintf(cas, sizeof cas, "plastic: alpha %g, ior %g", (double)rough[ri], (double)iors[ri]);
        if (m < 0 || pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m) < 0 || pt_scene_commit(s) != PT_OK) {
            st_row(c, 0, cas, "scene", "builds", "%s", s ? pt_scene_error_message(s) : "out of memory");
            pt_scene_destroy(s);
            continue;
        }
        for (ai = 0; ai < 7; ai++) {
            double th = angle[ai] * TU_PI / 180.0;
            pt_vec3 nrm = pt_v3(0, 0, 1), wo = dv_to(dnorm(dv(sin(th), 0.0, cos(th))));
            pt_pdf p = pt_pdf_material(s, m, nrm, wo);
            pt_rng rng;
            int strat;
            pt_rng_seed(&rng, 14000 + (uint64_t)(ri * 10 + ai), 1);
            for (i = 0; i < n; i++) {
                pt_vec3 d;
                float pv, v;
                if (!pt_pdf_sample(&p, &rng, &d, &pv)) continue;
                draws++;
                v = pt_pdf_value(&p, d);
                if (!(pv > 0.0f) || !isfinite(pv) || v != pv || !isfinite(d.x + d.y + d.z)) bad_draws++;
            }
            if (ai == 6) continue; /* a ray cannot meet the sphere at exactly 90 degrees */
            for (strat = 0; strat < 2; strat++) {
                pt_render_desc d = tu_base_desc(1, 1, 1, 0);
                pt_path_stats st;
                pt_ray ray;
                memset(&st, 0, sizeof st);
                d.background = pt_v3(1, 1, 1);
                d.strategy = strat == 0 ? PT_STRATEGY_MATERIAL : PT_STRATEGY_MIS;
                d.rr_start_depth = -1;
                ray.origin = pt_v3((float)sin(th), 0.0f, 10.0f);
                ray.dir = pt_v3(0, 0, -1);
                for (i = 0; i < n; i++) {
                    pt_color L = pt_trace_path(s, &d, ray, &rng, &st);
                    if (strat == 0) {
                        sum += L.x;
                        sum2 += (double)L.x * L.x;
                        paths++;
                        worst_max = fmax(worst_max, fmax(L.x, fmax(L.y, L.z)));
                    }
                }
                nonfinite += st.nonfinite_samples;
            }
        }
        mean = sum / (double)paths;
        se = sqrt(fmax(0.0, sum2 / (double)paths - mean * mean) / (double)(paths - 1));
        z = se > 0.0 ? (mean - 1.0) / se : (mean > 1.0 ? 1e30 : 0.0);
        c->comparisons += 1;
        st_row(c, z <= c->z_bound, cas, "white base, MATERIAL mean albedo over 0 .. 89.99 degrees: z above 1", st_zb(c),
               "%.4f (z %.2f; largest sample %.3g)", mean, z, worst_max);
        st_row(c, bad_draws == 0, cas, "PDF draws (0 .. 90 degrees) non-finite or != pt_pdf_value", "0", "%ld of %ld", bad_draws,
               draws);
        pt_scene_destroy(s);
    }
    st_row(c, nonfinite == 0, "plastic: all", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
}

/* Rough dielectrics from roughness 1e-4 (the smooth interface below 1e-3) to 1, incidence 0 to
   89.99 degrees from outside and inside, ior 1.5 and ior near 1 (1.001, 1.01: the transmitted lobe
   alpha |eta - 1| wide, delta below 1e-3). A glass plane under a uniform background of 1, one ray
   meeting it at angle theta: under MATERIAL a sample is G1(wi) (reflection) or G1(wi) / eta^2
   (transmission), so at most max(1, 1 / eta^2); MIS as well, for NaN/Inf. The material PDF at those
   angles (and exactly tangent): every draw finite with a positive density equal to pt_pdf_value. */
void st_rough_dielectric(st_ctx *c)
{
    static const float rough[7] = { 1e-4f, 9.9e-4f, 1e-3f, 1e-2f, 0.1f, 0.5f, 1.0f };
    static const float iors[3] = { 1.5f, 1.01f, 1.001f };
    static const double angle[7] = { 0.0, 45.0, 80.0, 89.0, 89.9, 89.99, 90.0 };
    const int n = c->full ? 10000 : 1000;
    uint64_t nonfinite = 0;
    int ri, ii, ai, side, i;
    for (ii = 0; ii < 3; ii++)
        for (ri = 0; ri < 7; ri++) {
            pt_scene *s = pt_scene_create();
            int m = s ? pt_scene_add_rough_dielectric(s, iors[ii], rough[ri]) : -1;
            double worst = 0.0, bound = (double)iors[ii] * (double)iors[ii] * (1.0 + 1e-5);
            long bad_draws = 0, draws = 0;
            char cas[64];
            snprintf(cas, sizeof cas, "rough glass: ior %g alpha %g", (double)iors[ii], (double)rough[ri]);
            if (m < 0 || pt_scene_add_quad(s, pt_v3(-1e3f, -1e3f, 0), pt_v3(2e3f, 0, 0), pt_v3(0, 2e3f, 0), m) < 0 ||
                pt_scene_commit(s) != PT_OK) {
                st_row(c, 0, cas, "scene", "builds", "%s", s ? pt_scene_error_message(s) : "out of memory");
                pt_scene_destroy(s);
                continue;
            }
            for (ai = 0; ai < 7; ai++)
                for (side = 0; side < 2; side++) {
                    double th = angle[ai] * TU_PI / 180.0, sg = side ? -1.0 : 1.0;
                    pt_vec3 wo = dv_to(dnorm(dv(sin(th), 0.0, sg * cos(th))));
                    pt_pdf p = pt_pdf_material(s, m, pt_v3(0, 0, 1), wo);
                    pt_rng rng;
                    int strat;
                    pt_rng_seed(&rng, 14000 + (uint64_t)((ii * 10 + ri) * 10 + ai), (uint64_t)side);
                    for (i = 0; i < n; i++) {
                        pt_vec3 d;
                        float pv, v;
                        if (!pt_pdf_sample(&p, &rng, &d, &pv)) continue;
                        draws++;
                        v = pt_pdf_value(&p, d);
                        if (!(pv > 0.0f) || !isfinite(pv) || v != pv || !isfinite(d.x + d.y + d.z)) bad_draws++;
                    }
                    if (ai == 6) continue; /* a ray cannot meet the plane at exactly 90 degrees */
                    for (strat = 0; strat < 2; strat++) {
                        pt_render_desc d = tu_base_desc(1, 1, 1, 0);
                        pt_path_stats st;
                        pt_ray ray;
                        double mx = 0.0;
                        memset(&st, 0, sizeof st);
                        d.background = pt_v3(1, 1, 1);
                        d.strategy = strat == 0 ? PT_STRATEGY_MATERIAL : PT_STRATEGY_MIS;
                        d.rr_start_depth = -1;
                        ray.dir = pt_neg(wo);
                        ray.origin = pt_scale(wo, 10.0f);
                        for (i = 0; i < n; i++) {
                            pt_color L = pt_trace_path(s, &d, ray, &rng, &st);
                            mx = fmax(mx, fmax(L.x, fmax(L.y, L.z)));
                        }
                        nonfinite += st.nonfinite_samples;
                        if (strat == 0) worst = fmax(worst, mx);
                    }
                }
            st_row(c, worst <= bound, cas, "largest MATERIAL sample, 0 .. 89.99 degrees, both sides", "<= ior^2", "%.6f", worst);
            st_row(c, bad_draws == 0, cas, "PDF draws (0 .. 90 degrees) non-finite or != pt_pdf_value", "0", "%ld of %ld",
                   bad_draws, draws);
            pt_scene_destroy(s);
        }
    st_row(c, nonfinite == 0, "rough glass: all", "NaN/Inf samples", "0", "%llu", (unsigned long long)nonfinite);
}

void st_family(st_ctx *c)
{
    char b[48];
    snprintf(b, sizeof b, "<= %d", c->max_comparisons);
    st_row(c, c->comparisons <= c->max_comparisons, "family",
           "z-comparisons made (Sidak family, alpha 0.01 for the whole run)", b, "%ld (each at |z| %s)", c->comparisons,
           st_zb(c));
}
