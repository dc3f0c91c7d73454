#define _POSIX_C_SOURCE 200809L
/* bench/bvh.c - rays per second of the built-in BVH (pdftrace.h section 5) and of Embree
   (section 5b), side by side in one run, on the Cornell box (scenes/cornell.scene, the scene of
   `make run`) and on a generated terrain of about one million triangles; plus build time and
   memory, the crossover in scene size and what PT_BACKEND_AUTO chooses.

       make bench-bvh            (needs libembree-dev; writes bench/out/bvh.md and bvh.csv)
       build/bench_bvh [--quick] [--crossover] [--reps N] OUTDIR
       build/bench_bvh --levels [--quick] [--reps N] OUTDIR     (make bench-simd)
           --quick      smaller scenes and images (a ~1 min check, not the figures)
           --crossover  only the crossover series
           --levels     only the SIMD levels of the built-in BVH (below; writes simd.md, simd.csv)
           --reps N     repetitions per backend or level (default 7)

   Method. Every scene is built twice from the same description, once per backend
   (pt_scene_set_backend before pt_scene_commit), and both are traced in the same process:
   - trace: one fixed batch of rays, recorded once (with the built-in backend) per scene:
     a camera ray through every pixel centre, and for every camera ray that hits, a
     cosine-distributed bounce ray from the hit point and a shadow ray towards a point on a
     light sampled by pt_pdf_scene_lights (tmax 1 - 1e-4, as the integrator's). Both backends trace exactly this batch through the
     public pt_scene_intersect / pt_scene_occluded, on one thread.
   - render: pt_render_image with the same settings and the same thread count (2) for both;
     rays/s = (camera + bounce + shadow rays) / wall-clock seconds, as pt_render_stats counts
     them. This includes shading, so the ratio is closer to 1 than the trace ratio.
   Repetitions are interleaved (built-in then Embree, then Embree then built-in, ...) and
   the tables give medians; "ratio" is the median over repetitions of the paired ratio
   built-in rays/s / Embree rays/s. Flush-to-zero/denormals-are-zero are set the same for
   both (Embree's recommended MXCSR). Build time and memory come from pt_scene_info
   (build_seconds, accel_bytes); Embree builds with its own threads (TBB), the built-in BVH on
   the calling thread.
   Crossover: terrains of growing size (8 to ~1M triangles) traced the same way (each
   measurement at least 500,000 rays: the batch traced several times); the
   smallest size from which Embree is faster (or within 3 %, a tie at this machine's noise)
   at every larger size is where PDFTRACE_EMBREE_MIN_PRIMS belongs; the report says at how
   many sizes AUTO's choice is the faster backend or ties with it.
   Levels (--levels): the built-in BVH committed once per SIMD level this CPU has (pt_simd_set_cap
   before pt_scene_commit: scalar, sse2 = 4-wide nodes, avx2 = 8-wide, avx512 = 16-wide: this
   program is built with PDFTRACE_AVX512_WIDTH=16, so that avx512/avx2 compares the widths), on the
   Cornell box, every bench/scenes/NAME.scene and the terrain; the batch above split into its
   closest-hit rays (camera and bounce) and its shadow rays, each timed on one thread for every
   level in turn, the order rotated every repetition. Reported: median rays/s per level and the
   median of the paired ratios to sse2 (the 4-wide SSE2 traversal). Every level returns the same
   hits (checked: the hit counts must agree). */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <errno.h>
#include <sys/stat.h>
#include <dirent.h>

#ifndef PDFTRACE_AVX512_WIDTH
#define PDFTRACE_AVX512_WIDTH 16 /* --levels: the avx512 column measures 16-wide nodes (see above) */
#endif
#define PDFTRACE_IMPLEMENTATION
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"

#ifndef PDFTRACE_EMBREE
#error "bench/bvh.c compares the built-in BVH with Embree: build it with make bench-bvh (needs libembree-dev)"
#endif

#if defined(__SSE__) || defined(_M_X64)
#include <xmmintrin.h>
#include <pmmintrin.h>
#define BV_HAVE_MXCSR 1
#endif

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void die(const char *what, int rc, const pt_scene *s)
{
    fprintf(stderr, "bench_bvh: %s failed: %s%s%s\n", what, pt_result_string(rc), s ? ": " : "",
            s ? pt_scene_error_message(s) : "");
    exit(1);
}

/* ---------------------------------------------------------------------------------------
   The generated mesh: a ridged value-noise terrain (Musgrave, "Texturing and Modeling" ch.
   16: octaves of 1 - |2 noise - 1|), n x n vertices over [-100, 100]^2, 2 (n - 1)^2
   triangles, deterministic (integer hash, no RNG state). n = 708: 999,698 triangles.
   --------------------------------------------------------------------------------------- */

static uint32_t tr_hash(int x, int y, uint32_t seed)
{
    uint32_t h = (uint32_t)x * 0x8da6b343u ^ (uint32_t)y * 0xd8163841u ^ seed * 0xcb1ab31fu;
    h ^= h >> 15; h *= 0x2c1b3c6du; h ^= h >> 12; h *= 0x297a2d39u; h ^= h >> 15;
    return h;
}
static double tr_lattice(int x, int y, uint32_t seed) { return (double)(tr_hash(x, y, seed) >> 8) / 16777216.0; }
static double tr_noise(double x, double y, uint32_t seed) /* value noise, smoothstep-interpolated */
{
    int xi = (int)floor(x), yi = (int)floor(y);
    double fx = x - xi, fy = y - yi, a, b, c, d, top, bot;
    fx = fx * fx * (3 - 2 * fx);
    fy = fy * fy * (3 - 2 * fy);
    a = tr_lattice(xi, yi, seed); b = tr_lattice(xi + 1, yi, seed);
    c = tr_lattice(xi, yi + 1, seed); d = tr_lattice(xi + 1, yi + 1, seed);
    bot = a + (b - a) * fx;
    top = c + (d - c) * fx;
    return bot + (top - bot) * fy;
}
static double tr_height(double x, double z)
{
    double h = 0, amp = 1, f = 1.0 / 40.0;
    int o;
    for (o = 0; o < 7; o++) {
        h += amp * (1 - fabs(2 * tr_noise(x * f, z * f, 17u + (uint32_t)o) - 1));
        amp *= 0.5;
        f *= 2.03;
    }
    return 28.0 * h - 20.0;
}

typedef struct terrain { float *pos; uint32_t *idx; uint32_t nv, nt; } terrain;

static void terrain_make(int n, terrain *t)
{
    int i, j;
    size_t k = 0;
    t->pos = (float *)malloc(sizeof(float) * 3 * (size_t)n * (size_t)n);
    t->idx = (uint32_t *)malloc(sizeof(uint32_t) * 6 * (size_t)(n - 1) * (size_t)(n - 1));
    if (!t->pos || !t->idx) { fprintf(stderr, "bench_bvh: out of memory (terrain %d)\n", n); exit(1); }
    for (j = 0; j < n; j++)
        for (i = 0; i < n; i++) {
            double x = -100 + 200.0 * i / (n - 1), z = -100 + 200.0 * j / (n - 1);
            float *p = t->pos + 3 * ((size_t)j * n + i);
            p[0] = (float)x; p[1] = (float)tr_height(x, z); p[2] = (float)z;
        }
    for (j = 0; j < n - 1; j++)
        for (i = 0; i < n - 1; i++) {
            uint32_t a = (uint32_t)(j * n + i), b = a + 1, c = a + (uint32_t)n, d = c + 1;
            t->idx[k++] = a; t->idx[k++] = c; t->idx[k++] = b;
            t->idx[k++] = b; t->idx[k++] = c; t->idx[k++] = d;
        }
    t->nv = (uint32_t)(n * n);
    t->nt = (uint32_t)(k / 3);
}
static void terrain_free(terrain *t) { free(t->pos); free(t->idx); }

/* The terrain lit by a sphere light above it; camera looking down over it. */
static pt_scene *terrain_scene(const terrain *t, pt_backend backend, pt_render_desc *rd)
{
    pt_scene *s = pt_scene_create();
    pt_mesh_desc md;
    int rock, light, rc;
    if (!s) die("pt_scene_create", PT_ERROR_OUT_OF_MEMORY, NULL);
    rock = pt_scene_add_lambertian(s, pt_v3(0.55f, 0.5f, 0.45f));
    light = pt_scene_add_emitter(s, pt_v3(30, 30, 30), 0);
    memset(&md, 0, sizeof md);
    md.positions = t->pos;
    md.vertex_count = t->nv;
    md.indices = t->idx;
    md.triangle_count = t->nt;
    md.material = rock;
    if ((rc = pt_scene_add_mesh(s, &md)) < 0) die("pt_scene_add_mesh", rc, s);
    if ((rc = pt_scene_add_sphere(s, pt_v3(40, 90, 30), 12, light)) < 0) die("pt_scene_add_sphere", rc, s);
    if ((rc = pt_scene_set_backend(s, backend)) != PT_OK) die("pt_scene_set_backend", rc, s);
    if ((rc = pt_scene_commit(s)) != PT_OK) die("pt_scene_commit (terrain)", rc, s);
    memset(rd, 0, sizeof *rd);
    rd->width = 320;
    rd->height = 240;
    rd->samples_per_pixel = 2;
    rd->camera.look_from = pt_v3(0, 45, -125);
    rd->camera.look_at = pt_v3(0, -5, 0);
    rd->camera.up = pt_v3(0, 1, 0);
    rd->camera.vfov_degrees = 45;
    rd->background = pt_v3(0.05f, 0.06f, 0.08f);
    return s;
}

/* A scene file (scenes/cornell.scene is the scene of `make run`), committed with the given backend. */
static pt_scene *file_scene(const char *path, pt_backend backend, pt_render_desc *rd)
{
    pt_scenefile sd;
    pt_scene *s = NULL;
    char err[1024];
    int rc = pt_scenefile_load(path, &sd, err, sizeof err);
    if (rc == PT_OK) {
        rc = pt_scenefile_build(&sd, &s, rd, err, sizeof err);
        pt_scenefile_free(&sd);
    }
    if (rc != PT_OK) { fprintf(stderr, "bench_bvh: %s: %s\n", path, err); exit(1); }
    /* the loader commits with the default backend: choose ours and commit again */
    if ((rc = pt_scene_set_backend(s, backend)) != PT_OK) die("pt_scene_set_backend", rc, s);
    if ((rc = pt_scene_commit(s)) != PT_OK) die("pt_scene_commit (scene file)", rc, s);
    return s;
}
static pt_scene *cornell_scene(pt_backend backend, pt_render_desc *rd) { return file_scene("scenes/cornell.scene", backend, rd); }

/* ---------------------------------------------------------------------------------------
   The ray batch
   --------------------------------------------------------------------------------------- */

typedef struct bray { pt_ray r; float tmax; int shadow; } bray;
typedef struct batch { bray *rays; size_t n, shadow; } batch;

static float rnd(uint64_t *st) /* splitmix64 -> [0,1) */
{
    uint64_t z = (*st += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (float)(z >> 40) * (1.0f / 16777216.0f);
}

/* The ray batch of a scene: camera rays, a cosine bounce from every hit, and a shadow ray
   towards a point on a light (a direction from pt_pdf_scene_lights, the light's
   distance found by a closest-hit query; tmax 1 - 1e-4 of it, as the integrator's). */
static void make_batch(const pt_scene *s, const pt_render_desc *rd, int w, int h, batch *b)
{
    pt_camera cam;
    pt_rng rng;
    uint64_t st = 12345;
    int x, y, rc;
    b->rays = (bray *)malloc(sizeof(bray) * 3 * (size_t)w * (size_t)h);
    b->n = b->shadow = 0;
    if (!b->rays) { fprintf(stderr, "bench_bvh: out of memory (rays)\n"); exit(1); }
    if ((rc = pt_camera_init(&cam, &rd->camera, w, h)) != PT_OK) die("pt_camera_init", rc, NULL);
    pt_rng_seed(&rng, 7, 11);
    for (y = 0; y < h; y++)
        for (x = 0; x < w; x++) {
            pt_ray r = pt_camera_ray(&cam, (float)x + 0.5f, (float)y + 0.5f, 0.5f, 0.5f);
            pt_hit hit, lh;
            b->rays[b->n].r = r; b->rays[b->n].tmax = INFINITY; b->rays[b->n].shadow = 0; b->n++;
            if (pt_scene_intersect(s, r, INFINITY, &hit) == 1) {
                pt_vec3 n = hit.geometric_normal, d, o, ld;
                pt_onb basis;
                pt_pdf lp;
                float u1 = rnd(&st), u2 = rnd(&st), rr = sqrtf(u1), ph = 6.2831853f * u2, pv;
                if (pt_dot(n, r.dir) > 0) n = pt_neg(n);
                basis = pt_onb_from_normal(n);
                d = pt_onb_to_world(&basis, pt_v3(rr * cosf(ph), rr * sinf(ph), sqrtf(1 - u1)));
                o = pt_offset_ray_origin(hit.point, n, d);
                b->rays[b->n].r.origin = o; b->rays[b->n].r.dir = d; b->rays[b->n].tmax = INFINITY;
                b->rays[b->n].shadow = 0; b->n++;
                o = pt_offset_ray_origin(hit.point, n, n);
                lp = pt_pdf_scene_lights(s, o);
                if (pt_pdf_sample(&lp, &rng, &ld, &pv)) {
                    pt_ray lr;
                    lr.origin = o; lr.dir = ld;
                    if (pt_scene_intersect(s, lr, INFINITY, &lh) == 1) {
                        b->rays[b->n].r.origin = o; b->rays[b->n].r.dir = pt_scale(ld, lh.t);
                        b->rays[b->n].tmax = 1.0f - 1e-4f; b->rays[b->n].shadow = 1; b->n++;
                        b->shadow++;
                    }
                }
            }
        }
}

/* Traces the batch `passes` times; returns seconds, counts the hits of one pass. */
static double trace_batch(const pt_scene *s, const batch *b, int passes, long *hits)
{
    size_t i;
    long h = 0;
    double t0 = now_s();
    for (i = 0; i < b->n * (size_t)passes; i++) {
        const bray *r = &b->rays[i % b->n];
        if (r->shadow) h += pt_scene_occluded(s, r->r, r->tmax) == 1;
        else {
            pt_hit hit;
            h += pt_scene_intersect(s, r->r, r->tmax, &hit) == 1;
        }
    }
    *hits = h / passes;
    return now_s() - t0;
}

/* ---------------------------------------------------------------------------------------
   Statistics and output
   --------------------------------------------------------------------------------------- */

static int cmp_name(const void *a, const void *b) { return strcmp((const char *)a, (const char *)b); }
static int cmp_d(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}
static double median(const double *v, int n)
{
    double tmp[64];
    int i;
    for (i = 0; i < n; i++) tmp[i] = v[i];
    qsort(tmp, (size_t)n, sizeof(double), cmp_d);
    return n % 2 ? tmp[n / 2] : 0.5 * (tmp[n / 2 - 1] + tmp[n / 2]);
}

#define MAX_REPS 64
static const char *backend_name(pt_backend b) { return b == PT_BACKEND_EMBREE ? "embree" : b == PT_BACKEND_BUILTIN ? "builtin" : "auto"; }

typedef struct result {
    const char *scene;
    uint32_t prims;
    double build[2];            /* seconds: builtin, embree */
    size_t bytes[2];
    double trace[2][MAX_REPS];  /* rays/s */
    double render[2][MAX_REPS];
    double trace_ratio[MAX_REPS], render_ratio[MAX_REPS];
    long hits[2];
    size_t rays;
    int reps, rendered;
    pt_backend autob;
    uint32_t kinds[3];          /* spheres, quads, triangles */
} result;

static FILE *csv;

/* The trace (and render) comparison of one scene pair. Each trace measurement traces the
   batch often enough for at least min_rays rays (short timings are noise on a shared machine). */
static void compare(result *res, pt_scene *sc[2], const batch *b, const pt_render_desc *rd, int reps, int render,
                    size_t min_rays)
{
    int rep, k, passes = (int)((min_rays + b->n - 1) / b->n);
    pt_scene_info info;
    res->reps = reps;
    res->rays = b->n;
    if (passes < 1) passes = 1;
    res->rendered = render;
    for (k = 0; k < 2; k++) {
        pt_scene_get_info(sc[k], &info);
        res->build[k] = info.build_seconds;
        res->bytes[k] = info.accel_bytes;
        res->prims = info.primitive_count;
        res->kinds[0] = info.sphere_count; res->kinds[1] = info.quad_count; res->kinds[2] = info.triangle_count;
        if (info.backend != (k ? PT_BACKEND_EMBREE : PT_BACKEND_BUILTIN)) {
            fprintf(stderr, "bench_bvh: %s: scene %d reports backend %d\n", res->scene, k, (int)info.backend);
            exit(1);
        }
    }
    for (rep = 0; rep < reps; rep++) {
        int order;
        for (order = 0; order < 2; order++) {
            int kb = (rep + order) % 2; /* alternate which backend goes first */
            double sec = trace_batch(sc[kb], b, passes, &res->hits[kb]);
            res->trace[kb][rep] = (double)b->n * passes / sec;
            fprintf(csv, "%s,%u,%s,trace,%d,%zu,%.6f,%.1f\n", res->scene, res->prims, kb ? "embree" : "builtin", rep,
                    b->n * (size_t)passes, sec, res->trace[kb][rep]);
        }
        res->trace_ratio[rep] = res->trace[0][rep] / res->trace[1][rep];
        if (render) {
            for (order = 0; order < 2; order++) {
                int kb = (rep + order) % 2, rc;
                pt_image img = {0};
                pt_render_stats st;
                double nr;
                pt_render_desc d = *rd;
                d.threads = 2;
                d.seed = (uint64_t)rep;
                if ((rc = pt_render_image(sc[kb], &d, &img, &st)) != PT_OK) die("pt_render_image", rc, sc[kb]);
                nr = (double)(st.camera_rays + st.bounce_rays + st.shadow_rays);
                res->render[kb][rep] = nr / st.seconds;
                fprintf(csv, "%s,%u,%s,render,%d,%.0f,%.6f,%.1f\n", res->scene, res->prims, kb ? "embree" : "builtin", rep,
                        nr, st.seconds, res->render[kb][rep]);
                pt_image_free(&img);
            }
            res->render_ratio[rep] = res->render[0][rep] / res->render[1][rep];
        }
    }
    fflush(csv);
}

static pt_backend auto_choice_for(pt_scene *s)
{
    pt_scene_info info;
    int rc;
    if ((rc = pt_scene_set_backend(s, PT_BACKEND_AUTO)) != PT_OK) die("pt_scene_set_backend(AUTO)", rc, s);
    if ((rc = pt_scene_commit(s)) != PT_OK) die("pt_scene_commit (auto)", rc, s);
    pt_scene_get_info(s, &info);
    return info.backend;
}

static void print_result(FILE *f, const result *r)
{
    double tb = median(r->trace[0], r->reps), te = median(r->trace[1], r->reps), ratio = median(r->trace_ratio, r->reps);
    int faster_e = ratio < 1.0;
    fprintf(f, "| %s | %u | %.4f / %.4f | %.3f / %.3f | %.3f | %.3f | **%.2f** |", r->scene, r->prims, r->build[0], r->build[1],
            (double)r->bytes[0] / 1048576.0, (double)r->bytes[1] / 1048576.0, tb * 1e-6, te * 1e-6, ratio);
    if (r->rendered)
        fprintf(f, " %.3f | %.3f | %.2f |", median(r->render[0], r->reps) * 1e-6, median(r->render[1], r->reps) * 1e-6,
                median(r->render_ratio, r->reps));
    else
        fprintf(f, " - | - | - |");
    fprintf(f, " %s | %s (%s) |\n", faster_e ? "embree" : "builtin", backend_name(r->autob),
            (r->autob == PT_BACKEND_EMBREE) == faster_e ? "pays" : "the slower one");
}

/* ---------------------------------------------------------------------------------------
   SIMD levels of the built-in BVH (--levels)
   --------------------------------------------------------------------------------------- */

#define NLEV 4
typedef struct lev_result {
    char scene[64];
    uint32_t prims;
    int nlev;
    size_t rays[2];                     /* closest, shadow */
    double rps[2][NLEV][MAX_REPS];      /* rays/s: [closest, shadow][level][rep] */
    double ratio[2][NLEV][MAX_REPS];    /* paired level / sse2 */
    double wide[2][MAX_REPS];           /* paired avx512 / avx2 (16-wide / 8-wide nodes) */
} lev_result;

/* Traces the rays of the batch of one kind (shadow or not) `passes` times; returns seconds. */
static double trace_kind(const pt_scene *s, const batch *b, int shadow, int passes, long *hits)
{
    size_t i;
    int p;
    long h = 0;
    double t0 = now_s();
    for (p = 0; p < passes; p++)
        for (i = 0; i < b->n; i++) {
            const bray *r = &b->rays[i];
            if (r->shadow != shadow) continue;
            if (shadow) h += pt_scene_occluded(s, r->r, r->tmax) == 1;
            else {
                pt_hit hit;
                h += pt_scene_intersect(s, r->r, r->tmax, &hit) == 1;
            }
        }
    *hits = h;
    return now_s() - t0;
}

static void levels_scene(lev_result *res, pt_scene **sc, int nlev, const batch *b, int reps, size_t min_rays)
{
    int rep, k, kind;
    pt_scene_info info;
    res->nlev = nlev;
    res->rays[0] = b->n - b->shadow;
    res->rays[1] = b->shadow;
    pt_scene_get_info(sc[0], &info);
    res->prims = info.primitive_count;
    for (rep = 0; rep < reps; rep++)
        for (kind = 0; kind < 2; kind++) {
            size_t n = res->rays[kind];
            int passes = n ? (int)((min_rays + n - 1) / n) : 0;
            long hits[NLEV];
            if (!n) continue;
            for (k = 0; k < nlev; k++) {
                int lv = (rep + k) % nlev; /* rotate which level goes first */
                double sec = trace_kind(sc[lv], b, kind, passes, &hits[lv]);
                res->rps[kind][lv][rep] = (double)n * passes / sec;
                fprintf(csv, "%s,%u,%s,%s,%d,%zu,%.6f,%.1f\n", res->scene, res->prims, pt_simd_level_name((pt_simd_level)lv),
                        kind ? "occluded" : "closest", rep, n * (size_t)passes, sec, res->rps[kind][lv][rep]);
            }
            for (k = 0; k < nlev; k++) {
                if (hits[k] != hits[0]) {
                    fprintf(stderr, "bench_bvh: %s: level %s found %ld hits, scalar %ld\n", res->scene,
                            pt_simd_level_name((pt_simd_level)k), hits[k], hits[0]);
                    exit(1);
                }
                res->ratio[kind][k][rep] = nlev > 1 ? res->rps[kind][k][rep] / res->rps[kind][1][rep] : 1.0;
            }
            res->wide[kind][rep] = nlev > 3 ? res->rps[kind][3][rep] / res->rps[kind][2][rep] : 1.0;
        }
    fflush(csv);
}

/* The scene committed once per level (pt_simd_set_cap); sc[k] is level k's. */
static void levels_commit(pt_scene **sc, int nlev, pt_scene *(*make)(const void *, pt_render_desc *), const void *arg,
                          pt_render_desc *rd)
{
    int k, rc;
    for (k = 0; k < nlev; k++) {
        pt_scene_info info;
        pt_simd_set_cap((pt_simd_level)k);
        sc[k] = make(arg, rd);
        if ((rc = pt_scene_set_backend(sc[k], PT_BACKEND_BUILTIN)) != PT_OK || (rc = pt_scene_commit(sc[k])) != PT_OK)
            die("pt_scene_commit (levels)", rc, sc[k]);
        pt_scene_get_info(sc[k], &info);
        if ((int)info.simd_level != k) { fprintf(stderr, "bench_bvh: cap %d gave level %d\n", k, (int)info.simd_level); exit(1); }
    }
    pt_simd_set_cap(PT_SIMD_AVX512);
}
static pt_scene *make_file(const void *path, pt_render_desc *rd) { return file_scene((const char *)path, PT_BACKEND_BUILTIN, rd); }
static pt_scene *make_terrain(const void *t, pt_render_desc *rd) { return terrain_scene((const terrain *)t, PT_BACKEND_BUILTIN, rd); }

static void levels_print(FILE *md, const lev_result *r)
{
    int kind, k;
    for (kind = 0; kind < 2; kind++) {
        int reps = 0;
        while (reps < MAX_REPS && r->rps[kind][0][reps] > 0) reps++;
        if (!r->rays[kind] || !reps) continue;
        fprintf(md, "| %s | %u | %s |", r->scene, r->prims, kind ? "occluded" : "closest");
        for (k = 0; k < NLEV; k++) {
            if (k < r->nlev) fprintf(md, " %.2f |", median(r->rps[kind][k], reps) * 1e-6);
            else fprintf(md, " - |");
        }
        for (k = 0; k < NLEV; k++) {
            if (k == 1) continue;
            if (k < r->nlev) fprintf(md, " %.3f |", median(r->ratio[kind][k], reps));
            else fprintf(md, " - |");
        }
        if (r->nlev > 3) fprintf(md, " %.3f |\n", median(r->wide[kind], reps));
        else fprintf(md, " - |\n");
    }
}

static int levels_main(const char *outdir, int quick, int reps)
{
    static lev_result res[24];
    int nres = 0, nlev = (int)pt_simd_cpu_level() + 1, i;
    char path[1024], names[24][256];
    int nnames = 0;
    double t_start = now_s();
    size_t min_rays = quick ? 100000 : 400000;
    FILE *md;
    DIR *dir;
    struct dirent *e;
    snprintf(path, sizeof path, "%s/simd.csv", outdir);
    if (!(csv = fopen(path, "w"))) { fprintf(stderr, "bench_bvh: cannot write %s\n", path); return 1; }
    fprintf(csv, "scene,prims,level,kind,rep,rays,seconds,rays_per_s\n");
    snprintf(names[nnames++], sizeof names[0], "scenes/cornell.scene");
    if ((dir = opendir("bench/scenes")) != NULL) {
        while ((e = readdir(dir)) != NULL && nnames < 20) {
            size_t len = strlen(e->d_name);
            if (len < 7 || strcmp(e->d_name + len - 6, ".scene") != 0) continue;
            snprintf(names[nnames++], sizeof names[0], "bench/scenes/%s", e->d_name);
        }
        closedir(dir);
    }
    qsort(names + 1, (size_t)(nnames - 1), sizeof names[0], cmp_name);
    for (i = 0; i <= nnames; i++) {
        pt_scene *sc[NLEV];
        pt_render_desc rd;
        batch b;
        terrain t;
        lev_result *r = &res[nres++];
        int k;
        memset(r, 0, sizeof *r);
        if (i < nnames) {
            snprintf(r->scene, sizeof r->scene, "%s", names[i]);
            levels_commit(sc, nlev, make_file, names[i], &rd);
            make_batch(sc[0], &rd, quick ? 80 : 160, quick ? 60 : 120, &b);
        } else {
            terrain_make(quick ? 272 : 708, &t);
            snprintf(r->scene, sizeof r->scene, "terrain-%u", t.nt);
            levels_commit(sc, nlev, make_terrain, &t, &rd);
            make_batch(sc[0], &rd, quick ? 160 : 320, quick ? 120 : 240, &b);
        }
        levels_scene(r, sc, nlev, &b, reps, min_rays);
        fprintf(stderr, "levels: %s, %u prims: closest avx2/sse2 %.3f, occluded %.3f\n", r->scene, r->prims,
                nlev > 2 ? median(r->ratio[0][2], reps) : 1.0, nlev > 2 ? median(r->ratio[1][2], reps) : 1.0);
        for (k = 0; k < nlev; k++) pt_scene_destroy(sc[k]);
        free(b.rays);
        if (i == nnames) terrain_free(&t);
    }
    fclose(csv);
    snprintf(path, sizeof path, "%s/simd.md", outdir);
    if (!(md = fopen(path, "w"))) { fprintf(stderr, "bench_bvh: cannot write %s\n", path); return 1; }
    fprintf(md, "# Built-in BVH per SIMD level (`make bench-simd`)\n\n");
    fprintf(md, "Produced by bench/bvh.c --levels in %.0f s%s; method in its top comment. One thread, %d repetitions, "
                "the levels' order rotated each repetition; medians of rays/s (M) and of the paired ratios to sse2 "
                "(the 4-wide SSE2 traversal). closest: camera and bounce rays (pt_scene_intersect); occluded: shadow "
                "rays (pt_scene_occluded). Levels this CPU has: scalar..%s.\n\n",
            now_s() - t_start, quick ? " (--quick)" : "", reps, pt_simd_level_name((pt_simd_level)(nlev - 1)));
    fprintf(md, "| scene | primitives | rays | scalar | sse2 | avx2 (8-wide) | avx512 (%d-wide) | scalar/sse2 | "
                "avx2/sse2 | avx512/sse2 | avx512/avx2 |\n|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
            (int)PDFTRACE_AVX512_WIDTH);
    for (i = 0; i < nres; i++) levels_print(md, &res[i]);
    fclose(md);
    fprintf(stderr, "wrote %s/simd.md and %s/simd.csv (%.0f s)\n", outdir, outdir, now_s() - t_start);
    return 0;
}

int main(int argc, char **argv)
{
    const char *outdir = NULL;
    int quick = 0, reps = 7, i, rc, cross_only = 0, levels = 0;
    char path[1024];
    FILE *md;
    result res_cornell, res_mesh, cross[24], suite[32];
    static char suite_names[32][256];
    int nsuite = 0;
    const double tie = 0.03; /* paired ratios within 3 % of 1 count as a tie (the noise of this machine) */
    int ncross = 0;
    static const int cross_n[] = { 3, 5, 8, 12, 17, 24, 34, 41, 48, 58, 68, 80, 96, 113, 136, 192, 272, 384, 543, 708 };
    int ncross_sizes = (int)(sizeof cross_n / sizeof cross_n[0]);
    double t_start = now_s();

    for (i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick")) quick = 1;
        else if (!strcmp(argv[i], "--crossover")) cross_only = 1;
        else if (!strcmp(argv[i], "--levels")) levels = 1;
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
        else if (argv[i][0] == '-') { fprintf(stderr, "usage: bench_bvh [--quick] [--crossover | --levels] [--reps N] OUTDIR\n"); return 2; }
        else outdir = argv[i];
    }
    if (!outdir || reps < 1 || reps > MAX_REPS) { fprintf(stderr, "usage: bench_bvh [--quick] [--reps N (1..%d)] OUTDIR\n", MAX_REPS); return 2; }
    if (mkdir(outdir, 0777) != 0 && errno != EEXIST) { fprintf(stderr, "bench_bvh: cannot create %s\n", outdir); return 1; }
#ifdef BV_HAVE_MXCSR
    _MM_SET_FLUSH_ZERO_MODE(_MM_FLUSH_ZERO_ON);
    _MM_SET_DENORMALS_ZERO_MODE(_MM_DENORMALS_ZERO_ON);
#endif
    if (levels) return levels_main(outdir, quick, reps);
    snprintf(path, sizeof path, "%s/bvh.csv", outdir);
    csv = fopen(path, "w");
    if (!csv) { fprintf(stderr, "bench_bvh: cannot write %s\n", path); return 1; }
    fprintf(csv, "scene,prims,backend,kind,rep,rays,seconds,rays_per_s\n");

    memset(&res_cornell, 0, sizeof res_cornell);
    memset(&res_mesh, 0, sizeof res_mesh);
    /* 1. Cornell box */
    if (!cross_only) {
        pt_scene *sc[2];
        pt_render_desc rd;
        batch b;
        res_cornell.scene = "cornell";
        sc[0] = cornell_scene(PT_BACKEND_BUILTIN, &rd);
        sc[1] = cornell_scene(PT_BACKEND_EMBREE, &rd);
        rd.samples_per_pixel = quick ? 1 : 4;
        if (quick) { rd.width = 200; rd.height = 200; }
        make_batch(sc[0], &rd, rd.width, rd.height, &b);
        fprintf(stderr, "cornell: %zu rays per batch\n", b.n);
        compare(&res_cornell, sc, &b, &rd, reps, 1, 1);
        res_cornell.autob = auto_choice_for(sc[0]);
        pt_scene_destroy(sc[0]);
        pt_scene_destroy(sc[1]);
        free(b.rays);
    }
    /* 2. the ~1M-triangle terrain */
    if (!cross_only) {
        terrain t;
        pt_scene *sc[2];
        pt_render_desc rd;
        batch b;
        int n = quick ? 272 : 708;
        res_mesh.scene = quick ? "terrain-147k" : "terrain-1M";
        terrain_make(n, &t);
        sc[0] = terrain_scene(&t, PT_BACKEND_BUILTIN, &rd);
        sc[1] = terrain_scene(&t, PT_BACKEND_EMBREE, &rd);
        if (quick) { rd.width = 160; rd.height = 120; rd.samples_per_pixel = 1; }
        make_batch(sc[0], &rd, 2 * rd.width, 2 * rd.height, &b);
        fprintf(stderr, "terrain: %u triangles, %zu rays per batch\n", t.nt, b.n);
        compare(&res_mesh, sc, &b, &rd, reps, 1, 1);
        res_mesh.autob = auto_choice_for(sc[0]);
        pt_scene_destroy(sc[0]);
        pt_scene_destroy(sc[1]);
        free(b.rays);
        terrain_free(&t);
    }
    /* 3. the scene suite (every scenes/NAME.scene, sorted by name), trace only: small scenes of every
       primitive kind, for AUTO's rule below MIN_PRIMS */
    if (!cross_only) {
        DIR *dir = opendir("scenes");
        struct dirent *e;
        if (!dir) { fprintf(stderr, "bench_bvh: cannot open scenes/\n"); return 1; }
        while ((e = readdir(dir)) != NULL && nsuite < 32) {
            size_t len = strlen(e->d_name);
            if (len < 7 || strcmp(e->d_name + len - 6, ".scene") != 0) continue;
            snprintf(suite_names[nsuite], sizeof suite_names[nsuite], "scenes/%s", e->d_name);
            nsuite++;
        }
        closedir(dir);
        qsort(suite_names, (size_t)nsuite, sizeof suite_names[0], cmp_name);
        for (i = 0; i < nsuite; i++) {
            pt_scene *sc[2];
            pt_render_desc rd;
            batch b;
            result *r = &suite[i];
            memset(r, 0, sizeof *r);
            r->scene = suite_names[i];
            sc[0] = file_scene(suite_names[i], PT_BACKEND_BUILTIN, &rd);
            sc[1] = file_scene(suite_names[i], PT_BACKEND_EMBREE, &rd);
            make_batch(sc[0], &rd, 160, 120, &b);
            compare(r, sc, &b, &rd, reps, 0, quick ? 100000 : 500000);
            r->autob = auto_choice_for(sc[0]);
            fprintf(stderr, "suite: %s, %u prims, built-in/Embree %.2f\n", r->scene, r->prims, median(r->trace_ratio, reps));
            pt_scene_destroy(sc[0]);
            pt_scene_destroy(sc[1]);
            free(b.rays);
        }
    }
    /* 4. crossover: terrains of growing size, trace only */
    for (i = 0; i < ncross_sizes && ncross < 24; i++) {
        terrain t;
        pt_scene *sc[2];
        pt_render_desc rd;
        batch b;
        result *r = &cross[ncross];
        static char names[24][32];
        if (quick && cross_n[i] > 272) break;
        memset(r, 0, sizeof *r);
        terrain_make(cross_n[i], &t);
        snprintf(names[ncross], sizeof names[ncross], "terrain-%u", t.nt);
        r->scene = names[ncross];
        sc[0] = terrain_scene(&t, PT_BACKEND_BUILTIN, &rd);
        sc[1] = terrain_scene(&t, PT_BACKEND_EMBREE, &rd);
        make_batch(sc[0], &rd, 160, 120, &b);
        compare(r, sc, &b, &rd, reps, 0, quick ? 100000 : 500000);
        r->autob = auto_choice_for(sc[0]);
        fprintf(stderr, "crossover: %u prims, built-in/Embree %.2f\n", r->prims, median(r->trace_ratio, reps));
        pt_scene_destroy(sc[0]);
        pt_scene_destroy(sc[1]);
        free(b.rays);
        terrain_free(&t);
        ncross++;
    }
    fclose(csv);

    /* report */
    snprintf(path, sizeof path, "%s/bvh.md", outdir);
    md = fopen(path, "w");
    if (!md) { fprintf(stderr, "bench_bvh: cannot write %s\n", path); return 1; }
    fprintf(md, "# Built-in BVH vs Embree (`make bench-bvh`)\n\n");
    fprintf(md, "Produced by bench/bvh.c in %.0f s%s; method in its top comment. %d interleaved repetitions per backend, "
                "medians. Trace: one fixed batch of rays (camera, diffuse bounce, shadow) through pt_scene_intersect / "
                "pt_scene_occluded on one thread. Render: pt_render_image on 2 threads (includes shading). "
                "Ratio: median of the paired built-in/Embree rays/s. Build: pt_scene_info.build_seconds (Embree on its own "
                "TBB threads, built-in on one). Memory: pt_scene_info.accel_bytes.\n\n",
            now_s() - t_start, quick ? " (--quick)" : "", reps);
    fprintf(md, "| scene | primitives | build s (built-in / Embree) | memory MiB (built-in / Embree) | trace Mrays/s built-in | "
                "trace Mrays/s Embree | trace ratio | render Mrays/s built-in | render Mrays/s Embree | render ratio | faster | "
                "AUTO uses |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|\n");
    if (!cross_only) {
        print_result(md, &res_cornell);
        print_result(md, &res_mesh);
    }
    fprintf(md, "\nRays per trace batch: Cornell %zu, terrain %zu. Hits in the batch (built-in / Embree): Cornell %ld / %ld, "
                "terrain %ld / %ld (they may differ by a few rays that graze an edge).\n",
            res_cornell.rays, res_mesh.rays, res_cornell.hits[0], res_cornell.hits[1], res_mesh.hits[0], res_mesh.hits[1]);
    if (nsuite) {
        int bad = 0;
        fprintf(md, "\n## Scene suite (scenes/*.scene, trace only)\n\n| scene | spheres / quads / triangles | "
                    "trace Mrays/s built-in | trace Mrays/s Embree | ratio | faster | AUTO uses |\n"
                    "|---|---:|---:|---:|---:|---|---|\n");
        for (i = 0; i < nsuite; i++) {
            const result *r = &suite[i];
            double ratio = median(r->trace_ratio, r->reps);
            int slower = (r->autob == PT_BACKEND_EMBREE && ratio > 1.0 + tie) || (r->autob == PT_BACKEND_BUILTIN && ratio < 1.0 - tie);
            bad += slower;
            fprintf(md, "| %s | %u / %u / %u | %.3f | %.3f | %.2f | %s | %s%s |\n", r->scene, r->kinds[0], r->kinds[1],
                    r->kinds[2], median(r->trace[0], r->reps) * 1e-6, median(r->trace[1], r->reps) * 1e-6, ratio,
                    ratio < 1 ? "embree" : "builtin", backend_name(r->autob), slower ? " (the slower one)" : "");
        }
        fprintf(md, "\nAUTO's choice is the faster backend, or within %.0f %% of it, on %d of %d suite scenes.\n", 100 * tie,
                nsuite - bad, nsuite);
    }
    fprintf(md, "\n## Crossover (terrains of growing size, trace only)\n\n| primitives | build s (built-in / Embree) | "
                "trace Mrays/s built-in | trace Mrays/s Embree | ratio | faster | AUTO uses |\n|---:|---:|---:|---:|---:|---|---|\n");
    {
        int first_e = -1;
        for (i = 0; i < ncross; i++) {
            const result *r = &cross[i];
            double ratio = median(r->trace_ratio, r->reps);
            fprintf(md, "| %u | %.4f / %.4f | %.3f | %.3f | %.2f | %s | %s |\n", r->prims, r->build[0], r->build[1],
                    median(r->trace[0], r->reps) * 1e-6, median(r->trace[1], r->reps) * 1e-6, ratio,
                    ratio < 1 ? "embree" : "builtin", backend_name(r->autob));
        }
        /* the smallest size from which Embree is faster (beyond a tie) at every larger size */
        for (i = ncross - 1; i >= 0 && median(cross[i].trace_ratio, cross[i].reps) < 1.0 + tie; i--) first_e = i;
        fprintf(md, "\nPDFTRACE_EMBREE_MIN_PRIMS compiled in: %lu. ", (unsigned long)PDFTRACE_EMBREE_MIN_PRIMS);
        if (first_e < 0)
            fprintf(md, "Measured: the built-in BVH was faster at the largest size measured.\n");
        else if (first_e == 0)
            fprintf(md, "Measured: Embree was as fast or faster at every size measured (from %u primitives).\n", cross[0].prims);
        else
            fprintf(md, "Measured: the built-in BVH is faster up to %u primitives; from %u on, Embree is as fast (within "
                        "%.0f %%) or faster at every size.\n",
                    cross[first_e - 1].prims, cross[first_e].prims, 100 * tie);
        {
            int bad = 0;
            for (i = 0; i < ncross; i++) {
                double ratio = median(cross[i].trace_ratio, cross[i].reps);
                if ((cross[i].autob == PT_BACKEND_EMBREE && ratio > 1.0 + tie) ||
                    (cross[i].autob == PT_BACKEND_BUILTIN && ratio < 1.0 - tie))
                    bad++;
            }
            fprintf(md, "AUTO's choice is the faster backend, or within %.0f %% of it, at %d of %d sizes%s.\n", 100 * tie,
                    ncross - bad, ncross, bad ? " - the compiled threshold does NOT fit this run" : "");
        }
    }
    fclose(md);
    fprintf(stderr, "wrote %s/bvh.md and %s/bvh.csv (%.0f s)\n", outdir, outdir, now_s() - t_start);
    (void)rc;
    return 0;
}
