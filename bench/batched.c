/* bench/batched.c - samples/s of the scalar and the batched integrator (pt_render_desc.integrator),
   measured side by side: for each scene, traversal backend and thread count, R repetitions, each
   a scalar render and a batched render of the same desc in alternating order (ABBA), so load
   changes on a shared machine hit both alike. Reported: the median samples/s of each and the
   median of the per-repetition ratios batched / scalar, with its range. Every batched film is
   compared with its scalar twin byte for byte (a difference is an error, exit 1).

   make bench-batched [BENCH_BATCHED_ARGS="--reps 7 --threads 1,2"]  (-> bench/out/batched.md)
   build/bench_batched [--quick] [--reps N] [--threads LIST] [--embree] [OUTDIR]

   --embree: the Embree backend too (needs a build with -DPDFTRACE_EMBREE; make EMBREE=1 ...).
   PDFTRACE_SIMD=sse2 (etc.) caps the SIMD level as for every pdftrace program. */
#define _POSIX_C_SOURCE 200809L
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct bench_scene {
    const char *name, *path;
    int width, height, spp, quick_spp;
} bench_scene;

static const bench_scene scenes[] = {
    { "cornell (glass ball)", "scenes/cornell.scene", 300, 300, 16, 4 },
    { "cornell-diffuse", "scenes/cornell-diffuse.scene", 300, 300, 16, 4 },
    { "door", "bench/scenes/door.scene", 128, 128, 48, 8 },
    { "closed-room", "bench/scenes/closed-room.scene", 160, 120, 48, 8 },
};

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}
static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static int films_equal(const pt_film *a, const pt_film *b)
{
    size_t n = (size_t)a->width * (size_t)a->height;
    return !memcmp(a->sum, b->sum, 3 * n * sizeof(double)) && !memcmp(a->sum_sq, b->sum_sq, 3 * n * sizeof(double)) &&
           !memcmp(a->sum_odd, b->sum_odd, 3 * n * sizeof(double)) && !memcmp(a->count, b->count, n * sizeof(uint32_t));
}

/* One render into a fresh film: samples/s, or < 0 on failure. */
static double render(const pt_scene *s, const pt_render_desc *d, pt_film *film)
{
    pt_render_stats st;
    if (pt_film_init(film, d->width, d->height) != PT_OK) return -1.0;
    if (pt_render(s, d, film, &st) != PT_OK) {
        fprintf(stderr, "bench_batched: %s\n", st.error);
        return -1.0;
    }
    if ((d->integrator == PT_INTEGRATOR_BATCHED) != (st.batched_samples == st.samples)) {
        fprintf(stderr, "bench_batched: the stats say another integrator ran\n");
        return -1.0;
    }
    return (double)st.samples / (st.seconds > 0.0 ? st.seconds : 1e-9);
}

int main(int argc, char **argv)
{
    int reps = 5, quick = 0, embree = 0, threads[4] = { 1, 2, 0, 0 }, nthreads = 2, i, sc, bk, th, r;
    const char *outdir = "bench/out";
    char path[1024];
    FILE *md;
    for (i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--quick")) { quick = 1; reps = 3; }
        else if (!strcmp(argv[i], "--embree")) embree = 1;
        else if (!strcmp(argv[i], "--reps") && i + 1 < argc) reps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) {
            char *p = argv[++i];
            for (nthreads = 0; *p && nthreads < 4; ++nthreads) {
                threads[nthreads] = (int)strtol(p, &p, 10);
                if (*p == ',') ++p;
            }
        } else if (argv[i][0] != '-') outdir = argv[i];
        else {
            fprintf(stderr, "usage: bench_batched [--quick] [--reps N] [--threads LIST] [--embree] [OUTDIR]\n");
            return 2;
        }
    }
    if (reps < 1 || reps > 101 || nthreads < 1) {
        fprintf(stderr, "bench_batched: --reps must be 1..101 and --threads a list like 1,2\n");
        return 2;
    }
    snprintf(path, sizeof path, "%s/batched.md", outdir);
    md = fopen(path, "w");
    if (!md) {
        fprintf(stderr, "bench_batched: cannot write %s\n", path);
        return 1;
    }
    fprintf(md, "# Scalar and batched integrator, samples/s (bench/batched.c)\n\n"
                "SIMD level %d (0 scalar, 1 SSE2, 2 AVX2, 3 AVX-512); %d repetitions, ABBA order; the films are "
                "identical byte for byte.\n\n"
                "| scene | backend | threads | scalar M samples/s | batched M samples/s | batched / scalar (median, range) |\n"
                "|---|---|---|---|---|---|\n",
            (int)pt_simd_get_level(), reps);
    printf("%-22s %-8s %3s %12s %12s %s\n", "scene", "backend", "thr", "scalar M/s", "batched M/s", "ratio (min, max)");
    for (sc = 0; sc < (int)(sizeof scenes / sizeof scenes[0]); ++sc) {
        pt_scenefile sf;
        pt_scene *s = NULL;
        pt_render_desc base;
        char err[512];
        snprintf(path, sizeof path, "%s", scenes[sc].path);
        if (pt_scenefile_load(path, &sf, err, sizeof err) != PT_OK || pt_scenefile_build(&sf, &s, &base, err, sizeof err) != PT_OK) {
            fprintf(stderr, "bench_batched: %s (run from the repository's top directory)\n", err);
            return 1;
        }
        pt_scenefile_free(&sf);
        base.width = scenes[sc].width;
        base.height = scenes[sc].height;
        base.samples_per_pixel = quick ? scenes[sc].quick_spp : scenes[sc].spp;
        for (bk = 0; bk < 1 + embree; ++bk) {
            if (pt_scene_set_backend(s, bk ? PT_BACKEND_EMBREE : PT_BACKEND_BUILTIN) != PT_OK || pt_scene_commit(s) != PT_OK) {
                fprintf(stderr, "bench_batched: backend %s unavailable in this build\n", bk ? "embree" : "builtin");
                return 1;
            }
            for (th = 0; th < nthreads; ++th) {
                double a[101], b[101], q[101];
                for (r = 0; r < reps; ++r) {
                    pt_render_desc d = base;
                    pt_film fa, fb;
                    d.threads = threads[th];
                    d.seed = (uint64_t)r;
                    d.integrator = PT_INTEGRATOR_SCALAR;
                    if (r % 2 == 0) a[r] = render(s, &d, &fa);
                    d.integrator = PT_INTEGRATOR_BATCHED;
                    b[r] = render(s, &d, &fb);
                    d.integrator = PT_INTEGRATOR_SCALAR;
                    if (r % 2 == 1) a[r] = render(s, &d, &fa);
                    if (a[r] < 0.0 || b[r] < 0.0) return 1;
                    if (!films_equal(&fa, &fb)) {
                        fprintf(stderr, "bench_batched: %s: the batched film differs from the scalar one\n", scenes[sc].name);
                        return 1;
                    }
                    pt_film_free(&fa);
                    pt_film_free(&fb);
                    q[r] = b[r] / a[r];
                }
                {
                    double lo = q[0], hi = q[0], ma, mb, mq;
                    for (r = 1; r < reps; ++r) {
                        lo = q[r] < lo ? q[r] : lo;
                        hi = q[r] > hi ? q[r] : hi;
                    }
                    ma = median(a, reps);
                    mb = median(b, reps);
                    mq = median(q, reps);
                    printf("%-22s %-8s %3d %12.3f %12.3f %.3f (%.3f, %.3f)\n", scenes[sc].name, bk ? "embree" : "builtin",
                           threads[th], ma * 1e-6, mb * 1e-6, mq, lo, hi);
                    fprintf(md, "| %s | %s | %d | %.3f | %.3f | %.3f (%.3f - %.3f) |\n", scenes[sc].name,
                            bk ? "embree" : "builtin", threads[th], ma * 1e-6, mb * 1e-6, mq, lo, hi);
                    fflush(stdout);
                }
            }
        }
        pt_scene_destroy(s);
    }
    fclose(md);
    return 0;
}
