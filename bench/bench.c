/* bench.c - `make bench` / `make bench-quick`: error against time for every strategy and scene,
   POV-Ray and Mitsuba 3 on the same axes, adaptive sampling and the scene-feature skips, the
   headline (`make bench-headline`): the 600 x 600 Cornell box at its own settings against Mitsuba,
   and the throughput (samples/s and rays/s per SIMD level and against Mitsuba 3 at equal depth:
   run_throughput).

     bench run [--quick] [--out DIR] [--budget S] [--seeds N] [--parts LIST] [--scenes LIST]
               [--mitsuba-python PYTHON] [--cache DIR] [--headline-size N]
     bench refs [NAME...]      render the stored references bench/ref/NAME.pfm (+ NAME.txt)
     bench list                the scenes, their files and their references

   Error metric (x = the render, r = the stored reference, over all pixels p and channels c of
   the 128 x 128 image):
     relMSE = mean_{p,c} (x - r)^2 / (r^2 + 0.01)
     bias   = sum_{p,c} x / sum_{p,c} r - 1               (mean relative bias, one number)
   The reference is itself a Monte Carlo render (MIS, many samples); its noise adds its own
   floor = mean_{p,c} var(r) / (r^2 + 0.01) (var = the variance of the pixel mean, from
   pt_film_pixel) to every measured relMSE. We report relMSE - floor (the raw value is in the
   CSV too) and stop a series once the raw relMSE is within 10x the floor.

   Runs: each scene x strategy (material, light, mixture with light weight 0.25/0.5/0.75, MIS,
   MIS with the Sobol sampler) renders progressively at 1, 2, 4, ... samples per pixel into one
   film (each step adds samples with new sample indices, so step k is exactly a render at 2^k
   spp), until the cumulative render time reaches the budget. The guided strategies (MIS with
   path guiding on or auto) render each point afresh instead (see run_series). The first seed fixes the ladder; seeds 2..N render
   the same ladder. Seeds are interleaved (seed-major), so slow phases of a shared machine hit
   every strategy alike; every figure is the median over seeds of that point, except the slope
   of log relMSE against log time, fitted to the mean over seeds (see fit_loglog).

   Output (DIR, default bench/out): series.csv (medians), series-seeds.csv (every seed),
   fits.csv, guiding.csv, pov.csv, mitsuba.csv, adaptive.csv, skips.csv, tput.csv, plot data (*.dat), gnuplot scripts
   (*.gp), PNG plots, summary.md and headline.md. Missing povray, Mitsuba 3 (the venv of `make
   mitsuba-install`) or gnuplot: that part prints SKIP and the rest runs.
   Exit status: 0 when everything ran (acceptance lines may still say FAIL: this is a
   measurement, not a test), 1 on an error, 2 on bad usage. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define PDFTRACE_IMPLEMENTATION
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"
#ifdef PTV_HAVE_EXR
#define PDFTRACE_EXR_IMPLEMENTATION
#include "pdftrace_exr.h"
#endif
#ifdef PTV_HAVE_PNG
#define PDFTRACE_PNG_IMPLEMENTATION
#include "pdftrace_png.h"
#endif

#define PTV_PROG "bench"
#include "validation/ptv_common.h"

/* ---- configuration -------------------------------------------------------------------- */

#define BENCH_SIZE 128         /* every render and reference is BENCH_SIZE x BENCH_SIZE */
#define DOOR_REF_SPP 32768     /* door.scene converges slowly without guiding: 4x the others' samples */
#define MAX_SEEDS 15
#define MAX_LEVELS 20          /* 1 .. 2^19 spp */
#define REF_SEED 0x5eedULL     /* run seeds are 1..N */
#define FLOOR_STOP 10.0        /* stop a series when raw relMSE < FLOOR_STOP x floor */
#define FIT_MIN_SPP 4          /* the slope fit leaves out 1 and 2 spp (fixed per-render costs) */
#define FIT_MIN_RATE 0.9       /* ... and points whose cumulative samples/s is below 0.9 x the last one's */

typedef struct bench_scene {
    const char *name;          /* also bench/ref/NAME.pfm and the output file names */
    const char *file;          /* the scene file (paths relative to the repository root) */
    int ref_spp;               /* samples per pixel of the stored reference */
    int pov_numeric;           /* 1: POV-Ray is a numeric reference here (per the recipe) */
    const char *about;         /* one line for the summary */
    const char *pov_about;     /* why POV-Ray is or is not a numeric reference */
    int rare_paths;            /* 1: some strategy's error is dominated by rare paths (the guiding
                                  scenes; veach-mis's light strategy on its smoothest plate): the
                                  mean of 5 seeds' relMSE is too noisy for the slope line's +-0.1
                                  (caustic, MIS: -0.82; veach-mis, light: -0.80), so it is left out */
} bench_scene;

static const bench_scene scenes[] = {
    {"cornell", "scenes/cornell.scene", 8192, 0,
     "the final Cornell box of The Rest of Your Life (= examples/cornell.c; glass ball), global illumination",
     "loose only: POV-Ray has no caustics without photons (the glass ball's caustic) and radiosity is biased", 0},
    {"tiny-light", "bench/scenes/tiny-light.scene", 8192, 1,
     "a tiny, very bright sphere light plus a large dim window, diffuse, global illumination",
     "numeric, loose (diffuse global illumination: radiosity, the recipe's 'Cornell box' row); the bulb is a point light", 0},
    {"tiny-light-pure", "bench/scenes/tiny-light-pure.scene", 8192, 1,
     "the same room with the tiny sphere light alone (no window)",
     "numeric, loose (as tiny-light)", 0},
    {"metal-glass", "bench/scenes/metal-glass.scene", 8192, 0,
     "chrome, gold and glass balls in a small room under a ceiling light, global illumination",
     "not numeric: caustics (glass and mirrors) need photons, which the exporter does not emit", 0},
    {"many-lights", "bench/scenes/many-lights.scene", 8192, 1,
     "five lights whose powers span four orders of magnitude, diffuse, global illumination",
     "numeric, loose (diffuse global illumination); the sphere lights are point lights", 0},
    {"door", "bench/scenes/door.scene", DOOR_REF_SPP, 0,
     "Veach's door: the camera's room lit only through the gap of a door ajar from a light in the next room "
     "(at least two diffuse bounces, light sampling blocked by the wall), diffuse, global illumination",
     "not numeric (a judgement, not measured): the camera's room is lit only indirectly through a narrow gap, unlike "
     "the directly lit box of the recipe's radiosity row, and radiosity's 35 (default) or 200 (medium) rays per sample "
     "point seldom find the gap", 1},
    {"caustic", "bench/scenes/caustic.scene", 8192, 0,
     "a glass ball on a diffuse floor under a small light: the floor caustic, found only by sampling through the glass",
     "not numeric: caustics need photons, which the exporter does not emit", 1},
    {"lamps", "bench/scenes/lamps.scene", 8192, 1,
     "a room lit only by lights without a shape: the sun through a window, a spot light and a point-light bulb, "
     "diffuse, global illumination",
     "numeric, loose (diffuse global illumination; the spot is hard-edged, its exact POV-Ray twin)", 0},
    {"many-tris", "bench/scenes/many-tris.scene", 8192, 0,
     "a 40-unit hall lit by 1024 small emitting triangles in four brightnesses (the light tree), diffuse, "
     "global illumination",
     "not exported: the POV-Ray exporter makes lights of emitting quads and spheres only (the lamps are triangles)", 0},
    {"sun-sky", "bench/scenes/sun-sky.scene", 8192, 0,
     "objects on a ground plane under an HDR sky with a low sun (a lat-long map): the environment light",
     "not numeric: POV-Ray lights a scene from its sky only through radiosity, and the sun would need a light source "
     "of its own", 0},
    {"close-quad", "bench/scenes/close-quad.scene", 8192, 1,
     "a long ceiling panel 5 cm from the back wall: a large quad light seen from close by (solid-angle sampling), "
     "diffuse, global illumination",
     "numeric, loose (diffuse global illumination: radiosity, the recipe's 'Cornell box' row)", 0},
    {"veach-mis", "bench/scenes/veach-mis.scene", 8192, 0,
     "Veach's MIS scene: four rough metal plates (GGX alpha 0.01 .. 0.25) reflecting four sphere lights of equal "
     "power and radii 0.03 .. 0.9 (MIS against each single strategy)",
     "not exported: POV-Ray has no GGX microfacet model, so the exporter refuses the rough conductor", 1},
    {"rooms", "bench/scenes/rooms.scene", 8192, 1,
     "a closed two-room house of 10 large quads, the camera's room lit through a doorway from a quad light in the "
     "far room, diffuse, global illumination (every ray hits: the throughput scene)",
     "numeric, loose (diffuse global illumination: radiosity, the recipe's 'Cornell box' row)", 0},
};
#define SCENE_COUNT ((int)(sizeof scenes / sizeof scenes[0]))

typedef struct bench_strategy {
    const char *name;
    pt_strategy strategy;
    float light_weight;
    pt_sampler sampler;        /* mis-sobol: PT_SAMPLER_SOBOL (not in the slope acceptance line) */
    pt_guiding guiding;        /* PT_GUIDING_ON / AUTO: path guiding with pt_render's defaults; each
                                  point of such a series is one fresh render (see run_series) */
    int in_quick;              /* 0: not run in quick mode (its series stays empty, levels 0), to keep
                                  make bench-quick within CI's 5 minutes: one guided series there */
} bench_strategy;

static const bench_strategy strategies[] = {
    {"material", PT_STRATEGY_MATERIAL, 0.0f, PT_SAMPLER_INDEPENDENT, PT_GUIDING_OFF, 1},
    {"light", PT_STRATEGY_LIGHT, 0.0f, PT_SAMPLER_INDEPENDENT, PT_GUIDING_OFF, 1},
    {"mix0.25", PT_STRATEGY_MIXTURE, 0.25f, PT_SAMPLER_INDEPENDENT, PT_GUIDING_OFF, 1},
    {"mix0.5", PT_STRATEGY_MIXTURE, 0.5f, PT_SAMPLER_INDEPENDENT, PT_GUIDING_OFF, 1},
    {"mix0.75", PT_STRATEGY_MIXTURE, 0.75f, PT_SAMPLER_INDEPENDENT, PT_GUIDING_OFF, 1},
    {"mis", PT_STRATEGY_MIS, 0.0f, PT_SAMPLER_INDEPENDENT, PT_GUIDING_OFF, 1},
    {"mis-sobol", PT_STRATEGY_MIS, 0.0f, PT_SAMPLER_SOBOL, PT_GUIDING_OFF, 1},
    {"mis-guided", PT_STRATEGY_MIS, 0.0f, PT_SAMPLER_INDEPENDENT, PT_GUIDING_ON, 1},
    {"mis-sobol-guided", PT_STRATEGY_MIS, 0.0f, PT_SAMPLER_SOBOL, PT_GUIDING_ON, 0},
    {"mis-sobol-auto", PT_STRATEGY_MIS, 0.0f, PT_SAMPLER_SOBOL, PT_GUIDING_AUTO, 0},
};
#define STRATEGY_COUNT ((int)(sizeof strategies / sizeof strategies[0]))
#define S_MATERIAL 0
#define S_LIGHT 1
#define S_MIS 5
#define S_MIS_SOBOL 6

enum { PART_SERIES = 1, PART_ADAPTIVE = 2, PART_SKIPS = 4, PART_POV = 8, PART_MITSUBA = 16, PART_HEADLINE = 32,
       PART_TPUT = 64, PART_ALL = 127 };

typedef struct config {
    int quick;
    double budget;             /* seconds of render time per series (first seed) */
    int seeds;
    unsigned parts;
    const char *out;
    const char *ref_dir;
    const char *mitsuba_python; /* the Python of the venv with Mitsuba 3 (make mitsuba-install) */
    const char *cache;          /* the headline's reference image (large: not in bench/ref) */
    int headline_size;          /* 0: the scene file's size; else N x N (for quick checks) */
    int headline_seeds;         /* seeds of the headline (both renderers) */
    int headline_ref_spp;       /* spp of the headline's reference */
    const char *headline_samplers; /* Mitsuba samplers of the headline (comma-separated) */
    int scene_on[SCENE_COUNT];
} config;

/* ---- small utilities ------------------------------------------------------------------ */

static void die_oom(void)
{
    fprintf(stderr, "bench: out of memory\n");
    exit(1);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double median(const double *v, int n)
{
    double t[64];
    int i;
    if (n <= 0) return NAN;
    if (n > 64) n = 64;
    for (i = 0; i < n; ++i) t[i] = v[i];
    qsort(t, (size_t)n, sizeof t[0], cmp_double);
    return n % 2 ? t[n / 2] : 0.5 * (t[n / 2 - 1] + t[n / 2]);
}

static int mkdirs(const char *path)
{
    char buf[2048];
    size_t i, n = strlen(path);
    if (n == 0 || n >= sizeof buf) return 0;
    memcpy(buf, path, n + 1);
    for (i = 1; i <= n; ++i)
        if (buf[i] == '/' || buf[i] == '\0') {
            char c = buf[i];
            buf[i] = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST) {
                fprintf(stderr, "bench: cannot create %s: %s\n", buf, strerror(errno));
                return 0;
            }
            buf[i] = c;
        }
    return 1;
}

static FILE *open_out(const config *cfg, const char *name)
{
    char path[2048];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s", cfg->out, name);
    f = fopen(path, "w");
    if (!f) fprintf(stderr, "bench: cannot write %s: %s\n", path, strerror(errno));
    return f;
}

static int close_out(FILE *f, const char *name)
{
    if (fclose(f) != 0) {
        fprintf(stderr, "bench: error writing %s\n", name);
        return 0;
    }
    return 1;
}

static int have_program(const char *name)
{
    char cmd[256];
    snprintf(cmd, sizeof cmd, "command -v %s >/dev/null 2>&1", name);
    return system(cmd) == 0;
}

/* ---- scenes and references ------------------------------------------------------------ */

/* FNV-1a (64 bit) of a file's bytes: a reference records the hash of the scene file it was
   rendered from, so a changed scene file is caught instead of measured against a stale image. */
static int file_hash(const char *path, uint64_t *hash)
{
    FILE *f = fopen(path, "rb");
    int c;
    uint64_t h = 1469598103934665603ULL;
    if (!f) return 0;
    while ((c = fgetc(f)) != EOF) {
        h ^= (uint64_t)(unsigned char)c;
        h *= 1099511628211ULL;
    }
    fclose(f);
    *hash = h;
    return 1;
}

typedef struct loaded {
    pt_scenefile sd;
    pt_scene *scene;
    pt_render_desc rd;         /* from the scene file, size BENCH_SIZE */
    pt_image ref;              /* the stored reference */
    double floor;              /* its noise floor in relMSE units */
    int ref_spp;
} loaded;

static int load_scene(const bench_scene *bs, loaded *L)
{
    char err[1024];
    memset(L, 0, sizeof *L);
    if (access(bs->file, R_OK) != 0) {
        fprintf(stderr, "bench: scene file %s: %s (run from the repository root, e.g. `make bench`)\n", bs->file,
                strerror(errno));
        return 0;
    }
    if (pt_scenefile_load(bs->file, &L->sd, err, sizeof err) != PT_OK) {
        fprintf(stderr, "bench: %s\n", err);
        return 0;
    }
    if (pt_scenefile_build(&L->sd, &L->scene, &L->rd, err, sizeof err) != PT_OK) {
        fprintf(stderr, "bench: %s\n", err);
        pt_scenefile_free(&L->sd);
        return 0;
    }
    L->rd.width = L->rd.height = BENCH_SIZE;
    return 1;
}

static void free_scene(loaded *L)
{
    pt_scene_destroy(L->scene);
    pt_scenefile_free(&L->sd);
    pt_image_free(&L->ref);
    memset(L, 0, sizeof *L);
}

/* Reads bench/ref/NAME.pfm and the floor and spp from NAME.txt. */
static int load_reference(const config *cfg, const bench_scene *bs, loaded *L)
{
    char path[2048], line[512];
    FILE *f;
    int have_floor = 0, have_hash = 0;
    unsigned long long stored = 0;
    uint64_t hash = 0;
    snprintf(path, sizeof path, "%s/%s.pfm", cfg->ref_dir, bs->name);
    if (access(path, R_OK) != 0) {
        fprintf(stderr, "bench: reference %s is missing: run `make bench-refs` (build/bench refs %s)\n", path, bs->name);
        return 0;
    }
    if (!read_pfm(path, &L->ref)) return 0;
    if (L->ref.width != BENCH_SIZE || L->ref.height != BENCH_SIZE) {
        fprintf(stderr, "bench: %s is %dx%d, expected %dx%d: run `make bench-refs`\n", path, L->ref.width,
                L->ref.height, BENCH_SIZE, BENCH_SIZE);
        return 0;
    }
    snprintf(path, sizeof path, "%s/%s.txt", cfg->ref_dir, bs->name);
    f = fopen(path, "r");
    if (!f) {
        fprintf(stderr, "bench: cannot read %s: %s (run `make bench-refs`)\n", path, strerror(errno));
        return 0;
    }
    while (fgets(line, sizeof line, f)) {
        if (sscanf(line, "noise_floor_relmse %lf", &L->floor) == 1) have_floor = 1;
        if (sscanf(line, "scene_fnv1a %llx", &stored) == 1) have_hash = 1;
        (void)sscanf(line, "spp %d", &L->ref_spp);
    }
    fclose(f);
    if (!have_hash || !file_hash(bs->file, &hash) || hash != (uint64_t)stored) {
        fprintf(stderr, "bench: %s: the reference was rendered from a different %s (scene_fnv1a %s): run `make "
                        "bench-refs` (build/bench refs %s)\n", path, bs->file, have_hash ? "differs" : "missing", bs->name);
        return 0;
    }
    if (!have_floor || !(L->floor >= 0) || !(L->floor < 1)) {
        fprintf(stderr, "bench: %s: no valid 'noise_floor_relmse' line\n", path);
        return 0;
    }
    return 1;
}

/* relMSE and bias of x against r (definitions at the top of the file). */
static void measure(const pt_image *x, const pt_image *r, double *relmse, double *bias)
{
    size_t n = 3u * (size_t)x->width * (size_t)x->height, i;
    double mse = 0, sx = 0, sr = 0;
    for (i = 0; i < n; ++i) {
        double xv = x->rgb[i], rv = r->rgb[i];
        mse += (xv - rv) * (xv - rv) / (rv * rv + 0.01);
        sx += xv;
        sr += rv;
    }
    *relmse = mse / (double)n;
    *bias = sr > 0 ? sx / sr - 1.0 : 0.0;
}

/* ---- bench refs ----------------------------------------------------------------------- */

static int progress_print(void *user, const pt_progress *p)
{
    (void)user;
    fprintf(stderr, "\r  pass %d/%d, %.0f s   ", p->pass, p->pass_count, p->seconds);
    return 0;
}

/* A reference image of L's scene at L->rd's size: MIS, spp samples per pixel, seed REF_SEED; *floor
   = mean over pixels and channels of var(pixel mean) / (r^2 + 0.01), its noise in relMSE units. */
static int render_reference_image(const loaded *L, int spp, pt_image *mean, double *floor, pt_render_stats *st)
{
    pt_film film;
    pt_render_desc d = L->rd; /* L->rd stays the scene's (the headline renders it next) */
    const int w = d.width, h = d.height;
    int x, y, rc, ok = 1;
    double fl = 0;
    d.samples_per_pixel = spp;
    d.samples_per_pass = spp / 64 > 0 ? spp / 64 : 1;
    d.strategy = PT_STRATEGY_MIS;
    d.seed = REF_SEED;
    d.progress = progress_print;
    if (pt_film_init(&film, w, h) != PT_OK) die_oom();
    rc = pt_render(L->scene, &d, &film, st);
    fprintf(stderr, "\n");
    if (rc != PT_OK || pt_film_resolve(&film, mean) != PT_OK) {
        fprintf(stderr, "bench: reference render of %s failed: %s\n", L->sd.file, st->error);
        ok = 0;
    }
    if (ok && st->nonfinite_samples) {
        fprintf(stderr, "bench: reference render of %s caught %llu NaN/Inf samples\n", L->sd.file,
                (unsigned long long)st->nonfinite_samples);
        ok = 0;
    }
    for (y = 0; ok && y < h; ++y)
        for (x = 0; x < w; ++x) {
            pt_color m = pt_v3(0, 0, 0), v = pt_v3(0, 0, 0);
            if (pt_film_pixel(&film, x, y, &m, &v) != PT_OK) ok = 0; /* cannot happen: x, y are in range */
            fl += v.x / ((double)m.x * m.x + 0.01) + v.y / ((double)m.y * m.y + 0.01) + v.z / ((double)m.z * m.z + 0.01);
        }
    *floor = fl / (3.0 * w * h);
    pt_film_free(&film);
    if (!ok) pt_image_free(mean);
    return ok;
}

static int make_reference(const config *cfg, const bench_scene *bs, int spp_override)
{
    const int ref_spp = spp_override > 0 ? spp_override : bs->ref_spp;
    loaded L;
    pt_image mean = {0, 0, NULL};
    pt_render_stats st;
    char path[2048];
    double fl = 0;
    int ok = 1;
    FILE *f;
    uint64_t hash = 0;
    if (!file_hash(bs->file, &hash) || !load_scene(bs, &L)) return 0;
    printf("bench refs: %s (%s), %dx%d, MIS, %d spp, seed %llu\n", bs->name, bs->file, BENCH_SIZE, BENCH_SIZE,
           ref_spp, (unsigned long long)REF_SEED);
    fflush(stdout);
    ok = render_reference_image(&L, ref_spp, &mean, &fl, &st);
    if (ok) {
        snprintf(path, sizeof path, "%s/%s.pfm", cfg->ref_dir, bs->name);
        if (pt_write_pfm(path, &mean) != PT_OK) {
            fprintf(stderr, "bench: cannot write %s\n", path);
            ok = 0;
        }
    }
    if (ok) {
        char tmp[2100];
        snprintf(path, sizeof path, "%s/%s.txt", cfg->ref_dir, bs->name);
        snprintf(tmp, sizeof tmp, "%s.tmp", path);
        f = fopen(tmp, "w");
        if (!f) {
            fprintf(stderr, "bench: cannot write %s: %s\n", tmp, strerror(errno));
            ok = 0;
        } else {
            fprintf(f, "# Reference image %s.pfm for the benchmark scene '%s' (bench/bench.c).\n", bs->name, bs->name);
            fprintf(f, "# Remake it with: make bench-refs   (or: build/bench refs %s, from the repository root)\n", bs->name);
            fprintf(f, "scene %s\nscene_fnv1a %016llx\nsize %d %d\nstrategy mis\nspp %d\nseed %llu\nseconds %.1f\nthreads %d\n",
                    bs->file, (unsigned long long)hash, BENCH_SIZE, BENCH_SIZE, ref_spp, (unsigned long long)REF_SEED,
                    st.seconds, st.threads);
            fprintf(f, "# mean over pixels and channels of var(pixel mean) / (r^2 + 0.01): the relMSE that this\n"
                       "# reference's own noise adds to every error measured against it\n");
            fprintf(f, "noise_floor_relmse %.6e\n", fl);
            if (fclose(f) != 0 || rename(tmp, path) != 0) {
                fprintf(stderr, "bench: cannot write %s\n", path);
                ok = 0;
            }
        }
    }
    if (ok) printf("  wrote %s/%s.pfm (%.1f s, noise floor %.3e)\n", cfg->ref_dir, bs->name, st.seconds, fl);
    pt_image_free(&mean);
    free_scene(&L);
    return ok;
}

/* ---- series: error against time ------------------------------------------------------- */

typedef struct point {
    int spp;
    double time;               /* cumulative render seconds to reach spp (guided series: of the one render) */
    double relmse;             /* raw, against the reference */
    double bias;
    double samples, rays;      /* cumulative (guided series: of the one render, training included) */
    int guided;                /* guided series: pt_render_stats.guiding_used of the render */
    double gain, train_time;   /* guided series: guiding_gain, guiding_seconds */
} point;

typedef struct series {
    int levels;                /* points per seed */
    point seed[MAX_SEEDS][MAX_LEVELS];
    point med[MAX_LEVELS];     /* median over seeds, per field */
    double err[MAX_LEVELS];    /* median relMSE - floor */
    double err_mean[MAX_LEVELS]; /* mean relMSE over seeds - floor: estimates E[relMSE] */
    double slope, slope_lo, slope_hi; /* least-squares slope of log err_mean vs log time (95 % interval) */
    double slope_med;          /* the same fit to the median err (for comparison; see fit_slope) */
    int fit_points;
    uint64_t nonfinite;
    int stopped_by_floor;
} series;

typedef struct results {
    int done[SCENE_COUNT];
    loaded L[SCENE_COUNT];
    series s[SCENE_COUNT][STRATEGY_COUNT];
} results;

/* Renders a progressive series into one film: 1, 2, 4, ... spp. With levels_fixed > 0 renders
   exactly that many levels; otherwise until the cumulative time reaches budget or (when
   *by_floor is 1 on entry) the raw relMSE comes within FLOOR_STOP x floor, and returns the
   count in *levels. On return *by_floor says whether the floor stopped it.
   A guided strategy (bst->guiding not PT_GUIDING_OFF) cannot step progressively: each pt_render
   call trains its own guide from nothing on the first share of that call's samples, so a step of
   2^(k-1) new samples would not be the render of 2^k spp that a user gets. So each of its points
   is one fresh render of N spp (the film cleared), and its time is that render's alone (training
   included), like a Mitsuba point; the series stops once one render takes the budget. */
static int run_series(const loaded *L, const bench_strategy *bst, uint64_t seed, int levels_fixed, double budget,
                      point *pts, int *levels, uint64_t *nonfinite, int *by_floor)
{
    pt_film film;
    pt_image img = {0, 0, NULL};
    pt_render_desc d = L->rd;
    double t = 0, samples = 0, rays = 0;
    int k, spp_done = 0, ok = 1, floor_stop = *by_floor;
    const int fresh = bst->guiding != PT_GUIDING_OFF;
    if (pt_film_init(&film, BENCH_SIZE, BENCH_SIZE) != PT_OK) die_oom();
    d.strategy = bst->strategy;
    d.light_weight = bst->light_weight;
    d.sampler = bst->sampler;
    d.guiding = bst->guiding; /* budget, alpha: pt_render's defaults */
    d.seed = seed;
    d.progress = NULL;
    *by_floor = 0;
    for (k = 0; k < MAX_LEVELS; ++k) {
        pt_render_stats st;
        int target = 1 << k, rc;
        double t0;
        if (fresh) {
            pt_film_clear(&film);
            spp_done = 0;
            t = samples = rays = 0;
        }
        d.samples_per_pixel = target - spp_done;
        d.samples_per_pass = d.samples_per_pixel; /* one pass per step */
        t0 = ptv_now();
        rc = pt_render(L->scene, &d, &film, &st);
        t += ptv_now() - t0;
        if (rc != PT_OK) {
            fprintf(stderr, "bench: %s render at %d spp failed: %s\n", bst->name, target, st.error);
            ok = 0;
            break;
        }
        spp_done = target;
        samples += (double)st.samples;
        rays += (double)(st.camera_rays + st.bounce_rays + st.shadow_rays);
        *nonfinite += st.nonfinite_samples;
        if (pt_film_resolve(&film, &img) != PT_OK) die_oom();
        pts[k].spp = target;
        pts[k].time = t;
        pts[k].samples = samples;
        pts[k].rays = rays;
        pts[k].guided = st.guiding_used;
        pts[k].gain = st.guiding_gain;
        pts[k].train_time = st.guiding_seconds;
        if (st.nonfinite_samples && fresh)
            fprintf(stderr, "bench: %s, %d spp, seed %llu: %llu NaN/Inf samples caught (%s)\n", bst->name, target,
                    (unsigned long long)seed, (unsigned long long)st.nonfinite_samples, st.guiding_note);
        measure(&img, &L->ref, &pts[k].relmse, &pts[k].bias);
        if (levels_fixed > 0) {
            if (k + 1 >= levels_fixed) break;
        } else if (t >= budget) {
            break;
        } else if (floor_stop && pts[k].relmse < FLOOR_STOP * L->floor) {
            *by_floor = 1;
            break;
        }
    }
    if (levels_fixed <= 0) *levels = k < MAX_LEVELS ? k + 1 : MAX_LEVELS;
    pt_image_free(&img);
    pt_film_free(&film);
    return ok;
}

/* Least squares y = a + b x over (log t, log e) of the points with spp >= FIT_MIN_SPP and e > 0,
   t the median time; the 95 % interval from the slope's standard error (two-sided t quantile,
   2.0 beyond 10 degrees of freedom). Returns the slope; lo/hi/points may be NULL.

   Which points: the claim is about error against the time that samples cost, and each
   progressive step pays fixed costs as well (starting the render threads, cold caches: ~1-2 ms
   a step at 128x128). At low spp these are a large part of the cumulative time, so log t there
   is not log N + const, and the fit's slope comes out steeper than the error's true exponent:
   on tiny-light, material, the mean relMSE falls as N^-1.00 from 4 to 1024 spp while time grew
   153x for 256x the samples (cumulative samples/s 4.6 M at 4 spp, 7.6 M at 1024), which made the
   fit against time -1.11. So the fit also leaves out the points whose cumulative samples/s is
   below FIT_MIN_RATE x the series' last point's: there time is proportional to samples.

   Which error: the claim "relMSE falls as 1/N" is about the expected error, E[relMSE] = V/N for
   an unbiased estimator of variance V. The mean over seeds estimates it without bias; the
   median does not when the error is heavy-tailed. Material sampling of a tiny bright light is:
   a few samples hit the light with a huge value, so at low spp most seeds see almost no hits
   (small error) and one sees several (huge error), and the median lies far below the mean
   until hits are common in every seed (measured on tiny-light, material, seeds 1-5 at 4 spp:
   relMSE 0.76 .. 24,600, median 640, mean 6,100; at 1024 spp all within 21.5 .. 25.8). The
   median's slope is then shallower than -1 (-0.76 there) although the mean's is -1. So the
   acceptance fit uses the mean; the median's fit is reported beside it. */
static double fit_loglog(const series *s, const double *e, double *lo, double *hi, int *points)
{
    static const double t975[] = {0, 12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228};
    double sx = 0, sy = 0, sxx = 0, sxy = 0, x[MAX_LEVELS], y[MAX_LEVELS], b, a, rss = 0, se, q, last_rate;
    int n = 0, k;
    if (s->levels < 1 || !(s->med[s->levels - 1].time > 0)) return NAN;
    last_rate = s->med[s->levels - 1].samples / s->med[s->levels - 1].time;
    for (k = 0; k < s->levels; ++k)
        if (s->med[k].spp >= FIT_MIN_SPP && e[k] > 0 && s->med[k].time > 0 &&
            s->med[k].samples / s->med[k].time >= FIT_MIN_RATE * last_rate) {
            x[n] = log(s->med[k].time);
            y[n] = log(e[k]);
            ++n;
        }
    if (points) *points = n;
    if (n < 3) {
        if (lo) *lo = NAN;
        if (hi) *hi = NAN;
        return NAN;
    }
    for (k = 0; k < n; ++k) {
        sx += x[k];
        sy += y[k];
        sxx += x[k] * x[k];
        sxy += x[k] * y[k];
    }
    b = (n * sxy - sx * sy) / (n * sxx - sx * sx);
    a = (sy - b * sx) / n;
    for (k = 0; k < n; ++k) rss += (y[k] - a - b * x[k]) * (y[k] - a - b * x[k]);
    se = sqrt(rss / (n - 2) / (sxx - sx * sx / n));
    q = n - 2 <= 10 ? t975[n - 2] : 2.0;
    if (lo) *lo = b - q * se;
    if (hi) *hi = b + q * se;
    return b;
}

static void fit_slope(series *s)
{
    s->slope = fit_loglog(s, s->err_mean, &s->slope_lo, &s->slope_hi, &s->fit_points);
    s->slope_med = fit_loglog(s, s->err, NULL, NULL, NULL);
}

static void summarize_series(series *s, int seeds, double floor)
{
    int k, j;
    for (k = 0; k < s->levels; ++k) {
        double v[6][MAX_SEEDS];
        for (j = 0; j < seeds; ++j) {
            v[0][j] = s->seed[j][k].time;
            v[1][j] = s->seed[j][k].relmse;
            v[2][j] = s->seed[j][k].bias;
            v[3][j] = s->seed[j][k].samples;
            v[4][j] = s->seed[j][k].rays;
        }
        s->med[k].spp = s->seed[0][k].spp;
        s->med[k].time = median(v[0], seeds);
        s->med[k].relmse = median(v[1], seeds);
        s->med[k].bias = median(v[2], seeds);
        s->med[k].samples = median(v[3], seeds);
        s->med[k].rays = median(v[4], seeds);
        s->err[k] = s->med[k].relmse - floor;
        s->err_mean[k] = -floor;
        for (j = 0; j < seeds; ++j) s->err_mean[k] += v[1][j] / seeds;
    }
    fit_slope(s);
}

/* Time at which a median curve reaches err `target`: log-log interpolation between the two
   points that bracket it. Beyond the last point, extrapolated with slope -1 from it (*extrap
   = 1). Before the first point (the curve starts below target), the first point's time
   (an upper bound, *extrap = -1). */
static double time_to_reach(const series *s, double target, int *extrap)
{
    int k;
    *extrap = 0;
    if (s->levels <= 0 || !(target > 0)) return NAN;
    if (s->err[0] <= target) {
        *extrap = -1;
        return s->med[0].time;
    }
    for (k = 1; k < s->levels; ++k)
        if (s->err[k] <= target && s->err[k] > 0 && s->err[k - 1] > 0) {
            double f = (log(target) - log(s->err[k - 1])) / (log(s->err[k]) - log(s->err[k - 1]));
            return exp(log(s->med[k - 1].time) + f * (log(s->med[k].time) - log(s->med[k - 1].time)));
        }
    *extrap = 1;
    k = s->levels - 1;
    return s->med[k].time * s->err[k] / target;
}

/* Error of a median curve at time t (log-log interpolation; outside the measured range,
   extrapolated with slope -1 from the nearest end and *extrap set). */
PTV_MAYBE_UNUSED static double err_at_time(const series *s, double t, int *extrap)
{
    int k;
    *extrap = 0;
    if (s->levels <= 0 || !(t > 0)) return NAN;
    if (t <= s->med[0].time) {
        *extrap = t < s->med[0].time ? 1 : 0;
        return s->err[0] * s->med[0].time / t;
    }
    for (k = 1; k < s->levels; ++k)
        if (t <= s->med[k].time && s->err[k] > 0 && s->err[k - 1] > 0) {
            double f = (log(t) - log(s->med[k - 1].time)) / (log(s->med[k].time) - log(s->med[k - 1].time));
            return exp(log(s->err[k - 1]) + f * (log(s->err[k]) - log(s->err[k - 1])));
        }
    *extrap = 1;
    k = s->levels - 1;
    return s->err[k] * s->med[k].time / t;
}

static double efficiency(const series *s)
{
    const point *p;
    double e;
    if (s->levels < 1) return NAN; /* not run (quick mode) */
    p = &s->med[s->levels - 1];
    e = s->err[s->levels - 1];
    return e > 0 && p->time > 0 ? 1.0 / (e * p->time) : NAN;
}

static int run_all_series(const config *cfg, results *R)
{
    int i, j, seed;
    for (seed = 0; seed < cfg->seeds; ++seed) {
        for (i = 0; i < SCENE_COUNT; ++i) {
            if (!R->done[i]) continue;
            for (j = 0; j < STRATEGY_COUNT; ++j) {
                series *s = &R->s[i][j];
                int by_floor = 1; /* the runs stop at the reference's noise floor */
                if (cfg->quick && !strategies[j].in_quick) continue;
                if (!run_series(&R->L[i], &strategies[j], (uint64_t)(seed + 1), seed == 0 ? 0 : s->levels, cfg->budget,
                                s->seed[seed], &s->levels, &s->nonfinite, &by_floor))
                    return 0;
                if (seed == 0) s->stopped_by_floor = by_floor;
            }
            printf("  seed %d/%d %-16s done\n", seed + 1, cfg->seeds, scenes[i].name);
            fflush(stdout);
        }
    }
    for (i = 0; i < SCENE_COUNT; ++i)
        if (R->done[i])
            for (j = 0; j < STRATEGY_COUNT; ++j) summarize_series(&R->s[i][j], cfg->seeds, R->L[i].floor);
    return 1;
}

static int write_series_csv(const config *cfg, const results *R)
{
    FILE *f = open_out(cfg, "series.csv"), *g, *h;
    int i, j, k, q;
    if (!f) return 0;
    fprintf(f, "scene,strategy,light_weight,spp,seeds,time_s,relmse,relmse_raw,floor,bias,samples_per_s,rays_per_s\n");
    for (i = 0; i < SCENE_COUNT; ++i)
        if (R->done[i])
            for (j = 0; j < STRATEGY_COUNT; ++j) {
                const series *s = &R->s[i][j];
                for (k = 0; k < s->levels; ++k)
                    fprintf(f, "%s,%s,%.2f,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", scenes[i].name, strategies[j].name,
                            strategies[j].light_weight, s->med[k].spp, cfg->seeds, s->med[k].time, s->err[k],
                            s->med[k].relmse, R->L[i].floor, s->med[k].bias, s->med[k].samples / s->med[k].time,
                            s->med[k].rays / s->med[k].time);
            }
    if (!close_out(f, "series.csv")) return 0;
    g = open_out(cfg, "series-seeds.csv");
    if (!g) return 0;
    /* the last three columns: guided strategies only (guiding_used, guiding_gain, guiding_seconds) */
    fprintf(g, "scene,strategy,seed,spp,time_s,relmse_raw,bias,samples,rays,guided,guiding_gain,guiding_s\n");
    for (i = 0; i < SCENE_COUNT; ++i)
        if (R->done[i])
            for (j = 0; j < STRATEGY_COUNT; ++j)
                for (q = 0; q < cfg->seeds; ++q)
                    for (k = 0; k < R->s[i][j].levels; ++k) {
                        const point *p = &R->s[i][j].seed[q][k];
                        fprintf(g, "%s,%s,%d,%d,%.6g,%.6g,%.6g,%.0f,%.0f,%d,%.4g,%.4g\n", scenes[i].name,
                                strategies[j].name, q + 1, p->spp, p->time, p->relmse, p->bias, p->samples, p->rays,
                                p->guided, p->gain, p->train_time);
                    }
    if (!close_out(g, "series-seeds.csv")) return 0;
    h = open_out(cfg, "fits.csv");
    if (!h) return 0;
    fprintf(h, "scene,strategy,slope_mean,slope_95lo,slope_95hi,slope_median,fit_points,final_spp,final_time_s,final_relmse,efficiency,nonfinite\n");
    for (i = 0; i < SCENE_COUNT; ++i)
        if (R->done[i])
            for (j = 0; j < STRATEGY_COUNT; ++j) {
                const series *s = &R->s[i][j];
                const int l = s->levels - 1;
                if (s->levels < 1) continue; /* not run (quick mode) */
                fprintf(h, "%s,%s,%.4f,%.4f,%.4f,%.4f,%d,%d,%.6g,%.6g,%.6g,%llu\n", scenes[i].name, strategies[j].name,
                        s->slope, s->slope_lo, s->slope_hi, s->slope_med, s->fit_points, s->med[l].spp, s->med[l].time, s->err[l], efficiency(s),
                        (unsigned long long)s->nonfinite);
            }
    return close_out(h, "fits.csv");
}

/* ---- POV-Ray on the same axes ---------------------------------------------------------- */

typedef struct pov_level {
    const char *name;
    int radiosity;             /* 0 none .. 3 high (pt_pov_options) */
    int grid;                  /* spotlights per quad emitter: grid x grid */
    const char *aa;            /* antialiasing options */
    int in_quick;
} pov_level;

/* Quality levels, fastest first. "+A0.0 +AM2 +Rn": adaptive supersampling of every pixel to
   depth n (the recipe's box-filter match is n = 4). */
static const pov_level pov_levels[] = {
    {"no radiosity, 2x2 grid, no AA", 0, 2, "-A", 1},
    {"radiosity default, 4x4 grid, AA R2", 1, 4, "+A0.0 +AM2 +R2", 1},
    {"radiosity medium, 8x8 grid, AA R3", 2, 8, "+A0.0 +AM2 +R3", 0},
};
/* Not run: medium radiosity with a 16x16 grid and AA R4 took 235 s for tiny-light (error
   4.5e-4), and the recipe's high radiosity is slower still (872 s at 256x256): too slow for
   the 25-minute budget of `make bench`. */
#define POV_LEVEL_COUNT ((int)(sizeof pov_levels / sizeof pov_levels[0]))

/* The pdftrace configurations compared with POV-Ray at equal time, by series-strategy name;
   names the strategy table lacks are left out. The acceptance line uses the last one present
   (the configuration pdftrace recommends for quality at a given time: MIS, with the Sobol
   sampler when it is built in); the others are shown beside it. */
static const char *const pov_pt_configs[] = {"mis", "mis-sobol"};
#define POV_PT_CONFIGS ((int)(sizeof pov_pt_configs / sizeof pov_pt_configs[0]))

typedef struct pov_result {
    int ran;
    double time, err, bias;    /* median seconds; relMSE - floor; bias */
    int reps;
    double pt_err[POV_PT_CONFIGS]; /* pdftrace at the same time, per configuration (NAN: not run) */
    int pt_extrap[POV_PT_CONFIGS];
} pov_result;

typedef struct pov_results {
    int available;
    char skip_reason[256];
    int config_strategy[POV_PT_CONFIGS]; /* index into strategies[], -1: not in this build */
    int accept_config;                   /* the configuration the acceptance line uses */
    pov_result r[SCENE_COUNT][POV_LEVEL_COUNT];
    series equal_time[SCENE_COUNT][POV_PT_CONFIGS]; /* numeric scenes: every seed, as long as the slowest level */
} pov_results;

static int strategy_index(const char *name)
{
    int j;
    for (j = 0; j < STRATEGY_COUNT; ++j)
        if (!strcmp(strategies[j].name, name)) return j;
    return -1;
}

static int run_pov(const config *cfg, results *R, pov_results *P)
{
    char dir[2048];
    int i, l, c;
    double tmax;
    memset(P, 0, sizeof *P);
    P->accept_config = 0;
    for (c = 0; c < POV_PT_CONFIGS; ++c) {
        P->config_strategy[c] = strategy_index(pov_pt_configs[c]);
        if (P->config_strategy[c] >= 0) P->accept_config = c;
    }
#ifndef PTV_HAVE_EXR
    snprintf(P->skip_reason, sizeof P->skip_reason, "bench was built without OpenEXR (apt-get install libopenexr-dev), "
                                                    "so POV-Ray's +FE output cannot be read");
    printf("SKIP POV-Ray: %s\n", P->skip_reason);
    (void)cfg; (void)R; (void)i; (void)l; (void)c; (void)dir; (void)tmax;
    return 1;
#else
    if (!have_povray()) {
        snprintf(P->skip_reason, sizeof P->skip_reason, "povray is not installed (apt-get install povray)");
        printf("SKIP POV-Ray: %s\n", P->skip_reason);
        return 1;
    }
    snprintf(dir, sizeof dir, "%s/pov", cfg->out);
    if (!mkdirs(dir)) return 0;
    P->available = 1;
    for (i = 0; i < SCENE_COUNT; ++i) {
        if (!R->done[i]) continue;
        tmax = 0;
        for (l = 0; l < POV_LEVEL_COUNT; ++l) {
            const pov_level *pl = &pov_levels[l];
            pov_result *pr = &P->r[i][l];
            char pov[2300], exr[2300], log[2300], png[2300], err[1024];
            pt_pov_options o;
            pt_image img = {0, 0, NULL};
            double times[5];
            int rep, reps;
            if (cfg->quick && !pl->in_quick) continue;
            snprintf(pov, sizeof pov, "%s/%s-q%d.pov", dir, scenes[i].name, l);
            snprintf(exr, sizeof exr, "%s/%s-q%d.exr", dir, scenes[i].name, l);
            snprintf(log, sizeof log, "%s/%s-q%d.log", dir, scenes[i].name, l);
            snprintf(png, sizeof png, "%s/%s-q%d.png", dir, scenes[i].name, l);
            memset(&o, 0, sizeof o);
            o.radiosity = pl->radiosity;
            o.light_grid = pl->grid;
            o.width = o.height = BENCH_SIZE;
            if (pt_scenefile_write_pov(&R->L[i].sd, pov, &o, err, sizeof err) != PT_OK) {
                /* a scene the exporter refuses (it says why): no POV-Ray rows for it */
                printf("SKIP POV-Ray %s: %s\n", scenes[i].name, err);
                break;
            }
            /* Repeat cheap renders (median of up to 5); a render is deterministic, only its time varies. */
            reps = 1;
            for (rep = 0; rep < reps; ++rep) {
                if (!run_povray(pov, exr, BENCH_SIZE, BENCH_SIZE, pl->aa, log, &times[rep])) {
                    fprintf(stderr, "bench: povray failed on %s (quality %d), see %s\n", scenes[i].name, l, log);
                    return 0;
                }
                if (rep == 0) reps = times[0] < 2.0 ? 5 : times[0] < 10.0 ? 3 : 1;
                if (cfg->quick) reps = 1;
            }
            if (!read_exr(exr, &img)) return 0;
            if (img.width != BENCH_SIZE || img.height != BENCH_SIZE) {
                fprintf(stderr, "bench: %s is %dx%d\n", exr, img.width, img.height);
                pt_image_free(&img);
                return 0;
            }
            measure(&img, &R->L[i].ref, &pr->err, &pr->bias);
            pr->err -= R->L[i].floor;
            pr->time = median(times, reps);
            pr->reps = reps;
            pr->ran = 1;
            for (c = 0; c < POV_PT_CONFIGS; ++c) pr->pt_err[c] = NAN;
            png_tonemapped(png, &img);
            pt_image_free(&img);
            printf("  POV-Ray %-16s q%d %-38s %7.2f s  relMSE %.3e  bias %+.2f%%\n", scenes[i].name, l, pl->name,
                   pr->time, pr->err, 100 * pr->bias);
            fflush(stdout);
            if (pr->time > tmax) tmax = pr->time;
        }
        /* pdftrace at equal time, per configuration. Where POV-Ray is a numeric reference: a series
           per seed (the seeds of the runs, interleaved) rendered until it has used as much time as
           the slowest POV-Ray level (the first seed fixes the ladder, as in the runs), medians
           read off at each level's time (log-log interpolation between the bracketing steps).
           Elsewhere (to keep within the time budget) the series of the runs, extrapolated with
           slope -1 beyond their last point (marked). */
        if (tmax > 0 && !scenes[i].pov_numeric) {
            for (c = 0; c < POV_PT_CONFIGS; ++c) {
                const int j = P->config_strategy[c];
                for (l = 0; l < POV_LEVEL_COUNT; ++l) {
                    pov_result *pr = &P->r[i][l];
                    if (!pr->ran) continue;
                    pr->pt_err[c] = j >= 0 && R->s[i][j].levels > 0 ? err_at_time(&R->s[i][j], pr->time, &pr->pt_extrap[c])
                                                                    : NAN;
                }
            }
        } else if (tmax > 0) {
            int seed;
            for (c = 0; c < POV_PT_CONFIGS; ++c) memset(&P->equal_time[i][c], 0, sizeof P->equal_time[i][c]);
            for (seed = 0; seed < cfg->seeds; ++seed)
                for (c = 0; c < POV_PT_CONFIGS; ++c) {
                    series *e = &P->equal_time[i][c];
                    int by_floor = 0; /* no floor stop: the series must reach the slowest level's time */
                    if (P->config_strategy[c] < 0) continue;
                    if (!run_series(&R->L[i], &strategies[P->config_strategy[c]], (uint64_t)(seed + 1),
                                    seed == 0 ? 0 : e->levels, 1.05 * tmax, e->seed[seed], &e->levels, &e->nonfinite,
                                    &by_floor))
                        return 0;
                }
            for (c = 0; c < POV_PT_CONFIGS; ++c) {
                series *e = &P->equal_time[i][c];
                if (P->config_strategy[c] < 0) continue;
                summarize_series(e, cfg->seeds, R->L[i].floor);
                for (l = 0; l < POV_LEVEL_COUNT; ++l) {
                    pov_result *pr = &P->r[i][l];
                    if (!pr->ran) continue;
                    pr->pt_err[c] = err_at_time(e, pr->time, &pr->pt_extrap[c]);
                }
            }
        }
        for (l = 0; l < POV_LEVEL_COUNT; ++l) {
            const pov_result *pr = &P->r[i][l];
            if (!pr->ran) continue;
            for (c = 0; c < POV_PT_CONFIGS; ++c)
                if (P->config_strategy[c] >= 0)
                    printf("  pdftrace %-9s %-16s at %7.2f s: relMSE %.3e%s (POV-Ray q%d: %.3e): ratio %.3g\n",
                           pov_pt_configs[c], scenes[i].name, pr->time, pr->pt_err[c],
                           pr->pt_extrap[c] ? " (extrapolated)" : "", l, pr->err, pr->pt_err[c] / pr->err);
        }
        fflush(stdout);
    }
    return 1;
#endif
}

static int write_pov_csv(const config *cfg, const results *R, const pov_results *P)
{
    FILE *f;
    int i, l, c;
    if (!P->available) return 1;
    f = open_out(cfg, "pov.csv");
    if (!f) return 0;
    fprintf(f, "scene,level,quality,radiosity,grid,aa,reps,time_s,relmse,bias,pov_numeric,pdftrace_config,"
               "pdftrace_relmse_at_time,extrapolated,pdftrace_over_pov\n");
    for (i = 0; i < SCENE_COUNT; ++i)
        if (R->done[i])
            for (l = 0; l < POV_LEVEL_COUNT; ++l) {
                const pov_result *pr = &P->r[i][l];
                if (!pr->ran) continue;
                for (c = 0; c < POV_PT_CONFIGS; ++c) {
                    if (P->config_strategy[c] < 0) continue;
                    /* RFC 4180: the quality names and AA options contain commas or spaces: quoted */
                    fprintf(f, "%s,%d,\"%s\",%d,%d,\"%s\",%d,%.6g,%.6g,%.6g,%d,%s,%.6g,%d,%.6g\n", scenes[i].name, l,
                            pov_levels[l].name, pov_levels[l].radiosity, pov_levels[l].grid, pov_levels[l].aa, pr->reps,
                            pr->time, pr->err, pr->bias, scenes[i].pov_numeric, pov_pt_configs[c], pr->pt_err[c],
                            pr->pt_extrap[c], pr->pt_err[c] / pr->err);
                }
            }
    return close_out(f, "pov.csv");
}

/* ---- Mitsuba 3 on the same axes -------------------------------------------------------- */

/* bench/mitsuba_series.py renders each scene's Mitsuba twin (pt_scenefile_export_mitsuba) with
   Mitsuba 3's llvm_ad_rgb variant on every core, at 1, 2, 4, ... spp per sampler: the first seed
   until one render takes the series budget (or its raw relMSE comes within FLOOR_STOP x the
   floor), seeds 2..N the same ladder, seed-major. Time = the render alone after one untimed
   warm-up render of that sampler and sample count (Dr.Jit compiles a kernel per configuration on
   first use), the image's evaluation forced inside the timing. Each point is one render of N spp
   (pdftrace's series are progressive, so their time is cumulative: a little more than one render
   of N spp). relMSE and bias: this file's definitions (the script computes them as measure()). */
#define MI_SAMPLERS 2
static const char *const mi_samplers[MI_SAMPLERS] = {"independent", "multijitter"};
#define MI_SCRIPT "bench/mitsuba_series.py"
#define MI_INSTALL "make mitsuba-install"

typedef struct mitsuba_results {
    int available;
    char skip_reason[512];
    int ran[SCENE_COUNT];
    char scene_skip[SCENE_COUNT][512];          /* why a scene has no Mitsuba series */
    series s[SCENE_COUNT][MI_SAMPLERS];
    int spp_used[SCENE_COUNT][MI_SAMPLERS][MAX_LEVELS]; /* multijitter may round a count up */
} mitsuba_results;

/* 'src' quoted for the shell (single quotes; a ' inside becomes '\''). */
static int shell_quote(char *dst, size_t n, const char *src)
{
    size_t k = 0;
    if (n < 3) return 0;
    dst[k++] = '\'';
    for (; *src; ++src) {
        if (*src == '\'') {
            if (k + 5 >= n) return 0;
            memcpy(dst + k, "'\\''", 4);
            k += 4;
        } else {
            if (k + 2 >= n) return 0;
            dst[k++] = *src;
        }
    }
    dst[k++] = '\'';
    dst[k] = '\0';
    return 1;
}

/* 1 when the venv's Python imports mitsuba and selects llvm_ad_rgb; else 0 with the reason. */
static int mitsuba_usable(const config *cfg, char *why, size_t why_size)
{
    char q[1100], ql[2200], cmd[3400], log[2100];
    FILE *f;
    if (access(cfg->mitsuba_python, X_OK) != 0) {
        snprintf(why, why_size, "Mitsuba 3 is not installed (no %s): %s, or pass --mitsuba-python PYTHON",
                 cfg->mitsuba_python, MI_INSTALL);
        return 0;
    }
    snprintf(log, sizeof log, "%s/mitsuba-check.log", cfg->out);
    if (!shell_quote(q, sizeof q, cfg->mitsuba_python) || !shell_quote(ql, sizeof ql, log)) {
        snprintf(why, why_size, "the path of the Mitsuba Python or of --out is too long");
        return 0;
    }
    snprintf(cmd, sizeof cmd, "%s %s check >%s 2>&1", q, MI_SCRIPT, ql);
    if (system(cmd) != 0) {
        char line[400] = "";
        f = fopen(log, "r");
        if (f) {
            if (!fgets(line, sizeof line, f)) line[0] = '\0';
            fclose(f);
        }
        line[strcspn(line, "\n")] = '\0';
        snprintf(why, why_size, "%s cannot run Mitsuba 3's llvm_ad_rgb variant (%s): %s", cfg->mitsuba_python,
                 line[0] ? line : "see the log", MI_INSTALL);
        return 0;
    }
    return 1;
}

/* Exports the scene of L as Mitsuba XML at w x h into path; 0 with the exporter's reason. */
static int mitsuba_export(const loaded *L, const char *path, int w, int h, char *why, size_t why_size)
{
    pt_mitsuba_options o;
    memset(&o, 0, sizeof o);
    o.width = w;
    o.height = h;
    return pt_scenefile_export_mitsuba(&L->sd, path, &o, why, why_size) == PT_OK;
}

/* Runs the series script on xml against ref (stop_floor: its floor-stop value; 0 = none) and reads
   its TSV into s[MI_SAMPLERS] (raw relMSE per seed; summarize_series subtracts floor). */
static int mitsuba_series(const config *cfg, const char *xml, const char *ref, const char *samplers, double stop_floor,
                          double budget, int max_spp, int seeds, int pixels, const char *tsv, series *s,
                          int (*used)[MAX_LEVELS])
{
    char qp[1100], qx[2200], qr[2200], qt[2200], cmd[8000], line[512];
    int n[MI_SAMPLERS][MAX_SEEDS], j, q, ok = 1;
    FILE *f;
    if (!shell_quote(qp, sizeof qp, cfg->mitsuba_python) || !shell_quote(qx, sizeof qx, xml) ||
        !shell_quote(qr, sizeof qr, ref) || !shell_quote(qt, sizeof qt, tsv)) {
        fprintf(stderr, "bench: path too long for the Mitsuba command\n");
        return 0;
    }
    snprintf(cmd, sizeof cmd, "%s %s series --xml %s --ref %s --samplers %s --floor %.6e --budget %.6g --max-spp %d "
             "--seeds %d --out %s", qp, MI_SCRIPT, qx, qr, samplers, stop_floor, budget, max_spp, seeds, qt);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench: Mitsuba series failed: %s\n", cmd);
        return 0;
    }
    memset(n, 0, sizeof n);
    for (j = 0; j < MI_SAMPLERS; ++j) memset(&s[j], 0, sizeof s[j]);
    f = fopen(tsv, "r");
    if (!f || !fgets(line, sizeof line, f)) {
        fprintf(stderr, "bench: cannot read %s\n", tsv);
        if (f) fclose(f);
        return 0;
    }
    while (ok && fgets(line, sizeof line, f)) {
        char name[32];
        int seed, spp, spp_used;
        double t, e, b;
        point *p;
        if (sscanf(line, "%31s %d %d %d %lf %lf %lf", name, &seed, &spp, &spp_used, &t, &e, &b) != 7) {
            ok = 0;
            break;
        }
        for (j = 0; j < MI_SAMPLERS && strcmp(name, mi_samplers[j]); ++j) {}
        if (j == MI_SAMPLERS || seed < 1 || seed > seeds || n[j][seed - 1] >= MAX_LEVELS) {
            ok = 0;
            break;
        }
        p = &s[j].seed[seed - 1][n[j][seed - 1]];
        p->spp = spp;
        p->time = t;
        p->relmse = e;
        p->bias = b;
        p->samples = (double)spp_used * pixels;
        p->rays = 0; /* not counted by Mitsuba */
        if (seed == 1) used[j][n[j][0]] = spp_used;
        n[j][seed - 1]++;
    }
    fclose(f);
    for (j = 0; ok && j < MI_SAMPLERS; ++j)
        for (q = 0; q < seeds; ++q)
            if (n[j][q] != n[j][0] || (n[j][0] < 1 && strstr(samplers, mi_samplers[j]))) ok = 0;
    if (!ok) {
        fprintf(stderr, "bench: %s: unexpected content (one line per sampler, seed and spp)\n", tsv);
        return 0;
    }
    for (j = 0; j < MI_SAMPLERS; ++j) s[j].levels = n[j][0];
    return 1;
}

static int run_mitsuba(const config *cfg, results *R, mitsuba_results *M)
{
    char dir[2048];
    int i, j;
    memset(M, 0, sizeof *M);
    if (!mitsuba_usable(cfg, M->skip_reason, sizeof M->skip_reason)) {
        printf("SKIP Mitsuba: %s\n", M->skip_reason);
        return 1;
    }
    snprintf(dir, sizeof dir, "%s/mitsuba", cfg->out);
    if (!mkdirs(dir)) return 0;
    M->available = 1;
    for (i = 0; i < SCENE_COUNT; ++i) {
        char xml[2300], tsv[2300], ref[2300];
        if (!R->done[i]) continue;
        snprintf(xml, sizeof xml, "%s/%s.xml", dir, scenes[i].name);
        snprintf(tsv, sizeof tsv, "%s/%s.tsv", dir, scenes[i].name);
        snprintf(ref, sizeof ref, "%s/%s.pfm", cfg->ref_dir, scenes[i].name);
        if (!mitsuba_export(&R->L[i], xml, BENCH_SIZE, BENCH_SIZE, M->scene_skip[i], sizeof M->scene_skip[i])) {
            printf("SKIP Mitsuba %s: not exported: %s\n", scenes[i].name, M->scene_skip[i]);
            continue;
        }
        if (!mitsuba_series(cfg, xml, ref, "independent,multijitter", R->L[i].floor, cfg->budget, 1 << (MAX_LEVELS - 1), cfg->seeds,
                            BENCH_SIZE * BENCH_SIZE, tsv,
                            M->s[i], M->spp_used[i]))
            return 0;
        for (j = 0; j < MI_SAMPLERS; ++j) {
            const series *s = &M->s[i][j];
            summarize_series(&M->s[i][j], cfg->seeds, R->L[i].floor);
            printf("  Mitsuba %-16s %-12s %5d spp in %.3f s: relMSE %.3e, efficiency %.3g\n", scenes[i].name,
                   mi_samplers[j], M->spp_used[i][j][s->levels - 1], s->med[s->levels - 1].time, s->err[s->levels - 1],
                   efficiency(s));
        }
        M->ran[i] = 1;
        fflush(stdout);
    }
    return 1;
}

static int write_mitsuba_csv(const config *cfg, const results *R, const mitsuba_results *M)
{
    FILE *f;
    int i, j, k;
    if (!M->available) return 1;
    f = open_out(cfg, "mitsuba.csv");
    if (!f) return 0;
    fprintf(f, "scene,sampler,spp,spp_used,seeds,time_s,relmse,relmse_raw,floor,bias,samples_per_s\n");
    for (i = 0; i < SCENE_COUNT; ++i)
        if (M->ran[i])
            for (j = 0; j < MI_SAMPLERS; ++j) {
                const series *s = &M->s[i][j];
                for (k = 0; k < s->levels; ++k)
                    fprintf(f, "%s,%s,%d,%d,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", scenes[i].name, mi_samplers[j],
                            s->med[k].spp, M->spp_used[i][j][k], cfg->seeds, s->med[k].time, s->err[k], s->med[k].relmse,
                            R->L[i].floor, s->med[k].bias, s->med[k].samples / s->med[k].time);
            }
    return close_out(f, "mitsuba.csv");
}

/* pdftrace's best strategy (by efficiency at its last point) against Mitsuba's best sampler: both
   curves read off at the same time t, the earlier of the two last points (log-log interpolation),
   efficiency 1 / (relMSE(t) t); ratio = pdftrace's over Mitsuba's = Mitsuba's error over pdftrace's. */
typedef struct versus {
    int pt_best, mi_best;
    double t, pt_err, mi_err, ratio;
} versus;

static versus versus_mitsuba(const results *R, const mitsuba_results *M, int i)
{
    versus v;
    int j, ex;
    double b = -1;
    memset(&v, 0, sizeof v);
    v.pt_best = v.mi_best = -1;
    for (j = 0; j < STRATEGY_COUNT; ++j)
        if (efficiency(&R->s[i][j]) > b) {
            b = efficiency(&R->s[i][j]);
            v.pt_best = j;
        }
    b = -1;
    for (j = 0; j < MI_SAMPLERS; ++j)
        if (efficiency(&M->s[i][j]) > b) {
            b = efficiency(&M->s[i][j]);
            v.mi_best = j;
        }
    if (v.pt_best < 0 || v.mi_best < 0) {
        v.ratio = NAN;
        return v;
    }
    {
        const series *p = &R->s[i][v.pt_best], *m = &M->s[i][v.mi_best];
        const double tp = p->med[p->levels - 1].time, tm = m->med[m->levels - 1].time;
        v.t = tp < tm ? tp : tm;
        v.pt_err = err_at_time(p, v.t, &ex);
        v.mi_err = err_at_time(m, v.t, &ex);
        v.ratio = v.mi_err / v.pt_err;
    }
    return v;
}

/* ---- headline: the user's default scene at its own size, pdftrace against Mitsuba ------ */

/* The RTRL Cornell box as the user renders it (scenes/cornell.scene: 600 x 600, 128 spp, MIS,
   independent numbers, every core) against Mitsuba 3's samplers on the same scene and size, both
   ways: Mitsuba's error at pdftrace's time (equal time) and the time Mitsuba needs for pdftrace's
   error (equal error), both read off Mitsuba's series (log-log interpolation). The reference is a
   pdftrace MIS render of HEADLINE_REF_SPP spp (seed REF_SEED), kept in the cache directory with
   its noise floor and scene hash and remade when either changes; its floor is subtracted as for
   the 128 x 128 scenes. Mitsuba's series here has no floor stop (it must reach pdftrace's error). */
#define HEADLINE_SCENE "scenes/cornell.scene"
#define HEADLINE_REF_SPP 1024
#define HEADLINE_SEEDS 3

typedef struct headline_results {
    int available;
    char skip_reason[512];
    int width, height, spp, ref_spp, seeds;
    double floor, ref_seconds;
    double pt_time, pt_err, pt_bias;            /* medians over seeds, pdftrace at the scene's settings */
    series mi[MI_SAMPLERS];
    int spp_used[MI_SAMPLERS][MAX_LEVELS];
    double mi_err[MI_SAMPLERS], mi_time[MI_SAMPLERS]; /* at pdftrace's time; to pdftrace's error */
    int mi_err_extrap[MI_SAMPLERS], mi_time_extrap[MI_SAMPLERS];
    int best;                                   /* the sampler with the lower error at pdftrace's time */
} headline_results;

/* The headline reference: reused from cache/cornell-WxH-ref.{pfm,txt} when its hash, size and
   spp match, else rendered and stored there. */
static int headline_reference(const config *cfg, loaded *L, uint64_t hash, headline_results *H)
{
    char pfm[2300], txt[2300], line[512];
    FILE *f;
    unsigned long long stored = 0;
    int w = 0, h = 0, spp = 0, have_floor = 0;
    pt_image mean = {0, 0, NULL};
    pt_render_stats st;
    if (!mkdirs(cfg->cache)) return 0;
    snprintf(pfm, sizeof pfm, "%s/cornell-%dx%d-ref.pfm", cfg->cache, H->width, H->height);
    snprintf(txt, sizeof txt, "%s/cornell-%dx%d-ref.txt", cfg->cache, H->width, H->height);
    f = fopen(txt, "r");
    if (f) {
        while (fgets(line, sizeof line, f)) {
            (void)sscanf(line, "scene_fnv1a %llx", &stored);
            (void)sscanf(line, "size %d %d", &w, &h);
            (void)sscanf(line, "spp %d", &spp);
            (void)sscanf(line, "seconds %lf", &H->ref_seconds);
            if (sscanf(line, "noise_floor_relmse %lf", &H->floor) == 1) have_floor = 1;
        }
        fclose(f);
        if (have_floor && stored == (unsigned long long)hash && w == H->width && h == H->height &&
            spp == H->ref_spp && read_pfm(pfm, &L->ref) && L->ref.width == w && L->ref.height == h) {
            printf("  reference %s (%d spp, noise floor %.3e), kept from an earlier run\n", pfm, spp, H->floor);
            return 1;
        }
        pt_image_free(&L->ref);
    }
    printf("  reference: MIS, %d spp, %dx%d (about %d times the scene's own render)\n", H->ref_spp, H->width,
           H->height, H->ref_spp / (H->spp > 0 ? H->spp : 1));
    fflush(stdout);
    if (!render_reference_image(L, H->ref_spp, &mean, &H->floor, &st)) return 0;
    H->ref_seconds = st.seconds;
    if (pt_write_pfm(pfm, &mean) != PT_OK) {
        fprintf(stderr, "bench: cannot write %s\n", pfm);
        pt_image_free(&mean);
        return 0;
    }
    L->ref = mean;
    f = fopen(txt, "w");
    if (!f) {
        fprintf(stderr, "bench: cannot write %s: %s\n", txt, strerror(errno));
        return 0;
    }
    fprintf(f, "# bench headline reference of %s (bench/bench.c); delete it to remake it\nscene_fnv1a %016llx\n"
               "size %d %d\nspp %d\nseed %llu\nseconds %.1f\nnoise_floor_relmse %.6e\n",
            HEADLINE_SCENE, (unsigned long long)hash, H->width, H->height, H->ref_spp, (unsigned long long)REF_SEED,
            H->ref_seconds, H->floor);
    if (fclose(f) != 0) {
        fprintf(stderr, "bench: error writing %s\n", txt);
        return 0;
    }
    printf("  wrote %s (%.1f s, noise floor %.3e)\n", pfm, H->ref_seconds, H->floor);
    return 1;
}

/* One pdftrace render of the headline at the scene's settings, seed index `seed`: time, relMSE - floor, bias. */
static int headline_pdftrace(const loaded *L, const headline_results *H, int seed, double *t, double *e, double *b)
{
    pt_render_desc d = L->rd;
    pt_render_stats st;
    pt_film film;
    pt_image img = {0, 0, NULL};
    double t0;
    d.seed = (uint64_t)(seed + 1);
    d.progress = NULL;
    if (pt_film_init(&film, H->width, H->height) != PT_OK) die_oom();
    t0 = ptv_now();
    if (pt_render(L->scene, &d, &film, &st) != PT_OK) {
        fprintf(stderr, "bench: headline render failed: %s\n", st.error);
        pt_film_free(&film);
        return 0;
    }
    t[seed] = ptv_now() - t0;
    if (pt_film_resolve(&film, &img) != PT_OK) die_oom();
    measure(&img, &L->ref, &e[seed], &b[seed]);
    e[seed] -= H->floor;
    pt_image_free(&img);
    pt_film_free(&film);
    printf("  pdftrace seed %d: %.2f s, relMSE %.4g\n", seed + 1, t[seed], e[seed]);
    fflush(stdout);
    return 1;
}

static int run_headline(const config *cfg, headline_results *H)
{
    bench_scene bs;
    loaded L;
    uint64_t hash = 0;
    char dir[2048], xml[2300], tsv[2300], ref[2300];
    double t[MAX_SEEDS], e[MAX_SEEDS], b[MAX_SEEDS];
    int seed, j, ok = 1;
    memset(H, 0, sizeof *H);
    if (!mitsuba_usable(cfg, H->skip_reason, sizeof H->skip_reason)) {
        printf("SKIP headline: %s\n", H->skip_reason);
        return 1;
    }
    memset(&bs, 0, sizeof bs);
    bs.name = "cornell";
    bs.file = HEADLINE_SCENE;
    if (!file_hash(bs.file, &hash) || !load_scene(&bs, &L)) return 0;
    /* load_scene sets the benchmark's size: back to the scene file's own */
    L.rd.width = cfg->headline_size ? cfg->headline_size : L.sd.width;
    L.rd.height = cfg->headline_size ? cfg->headline_size : L.sd.height;
    H->width = L.rd.width;
    H->height = L.rd.height;
    H->spp = L.rd.samples_per_pixel;
    H->ref_spp = cfg->headline_ref_spp;
    H->seeds = cfg->headline_seeds;
    printf("headline: %s at %dx%d, %d spp (the scene's settings), %d seeds, against Mitsuba 3\n", HEADLINE_SCENE,
           H->width, H->height, H->spp, H->seeds);
    fflush(stdout);
    if (!headline_reference(cfg, &L, hash, H)) {
        free_scene(&L);
        return 0;
    }
    /* pdftrace's seeds alternate before and after Mitsuba's series (1, 3, ... before; 2, 4, ...
       after), so a change in the shared machine's load between the two does not favour either */
    for (seed = 0; ok && seed < H->seeds; seed += 2) ok = headline_pdftrace(&L, H, seed, t, e, b);
    if (ok) {
        double tb[MAX_SEEDS];
        int nb = 0;
        for (seed = 0; seed < H->seeds; seed += 2) tb[nb++] = t[seed];
        snprintf(dir, sizeof dir, "%s/mitsuba", cfg->out);
        snprintf(xml, sizeof xml, "%s/cornell-%dx%d.xml", dir, H->width, H->height);
        snprintf(tsv, sizeof tsv, "%s/cornell-%dx%d.tsv", dir, H->width, H->height);
        snprintf(ref, sizeof ref, "%s/cornell-%dx%d-ref.pfm", cfg->cache, H->width, H->height);
        ok = mkdirs(dir);
        if (ok && !mitsuba_export(&L, xml, H->width, H->height, H->skip_reason, sizeof H->skip_reason)) {
            fprintf(stderr, "bench: Mitsuba export of %s: %s\n", HEADLINE_SCENE, H->skip_reason);
            ok = 0;
        }
        /* ladder until one render takes pdftrace's time (its seeds so far), so the series reaches it
           (at most 16x pdftrace's spp); an equal error beyond its end is extrapolated (marked) */
        if (ok) ok = mitsuba_series(cfg, xml, ref, cfg->headline_samplers, 0.0, median(tb, nb), 16 * H->spp,
                                    H->seeds, H->width * H->height, tsv, H->mi, H->spp_used);
    }
    for (seed = 1; ok && seed < H->seeds; seed += 2) ok = headline_pdftrace(&L, H, seed, t, e, b);
    if (ok) {
        H->pt_time = median(t, H->seeds);
        H->pt_err = median(e, H->seeds);
        H->pt_bias = median(b, H->seeds);
    }
    H->best = -1;
    for (j = 0; ok && j < MI_SAMPLERS; ++j) {
        if (H->mi[j].levels < 1) continue; /* not asked for (--headline-samplers) */
        summarize_series(&H->mi[j], H->seeds, H->floor);
        H->mi_err[j] = err_at_time(&H->mi[j], H->pt_time, &H->mi_err_extrap[j]);
        H->mi_time[j] = time_to_reach(&H->mi[j], H->pt_err, &H->mi_time_extrap[j]);
        if (H->best < 0 || H->mi_err[j] < H->mi_err[H->best]) H->best = j;
        printf("  Mitsuba %-12s at %.2f s: relMSE %.4g (pdftrace %.4g, ratio %.3g); reaches pdftrace's error in %.2f s "
               "(ratio %.3g)\n", mi_samplers[j], H->pt_time, H->mi_err[j], H->pt_err, H->mi_err[j] / H->pt_err,
               H->mi_time[j], H->mi_time[j] / H->pt_time);
    }
    H->available = ok && H->best >= 0;
    free_scene(&L);
    return ok;
}

/* The headline table (summary.md and headline-600.md). */
static void write_headline_table(FILE *f, const headline_results *H)
{
    int j;
    fprintf(f, "| renderer | spp | time (s) | relMSE | efficiency 1/(relMSE·time) | Mitsuba / pdftrace |\n"
               "|---|---|---|---|---|---|\n");
    fprintf(f, "| pdftrace, the scene's settings (MIS, independent numbers) | %d | %.3g | %.4g | %.3g | - |\n", H->spp,
            H->pt_time, H->pt_err, 1.0 / (H->pt_time * H->pt_err));
    for (j = 0; j < MI_SAMPLERS; ++j)
        if (H->mi[j].levels > 0)
            fprintf(f, "| Mitsuba 3 `%s`%s, equal time | - | %.3g | %.4g%s | %.3g | %srelMSE %.3g×%s |\n", mi_samplers[j],
                j == H->best ? " (best)" : "", H->pt_time, H->mi_err[j], H->mi_err_extrap[j] ? " (extrapolated)" : "",
                1.0 / (H->pt_time * H->mi_err[j]), j == H->best ? "**" : "", H->mi_err[j] / H->pt_err,
                j == H->best ? "**" : "");
    for (j = 0; j < MI_SAMPLERS; ++j)
        if (H->mi[j].levels > 0)
            fprintf(f, "| Mitsuba 3 `%s`%s, equal error | - | %.3g%s | %.4g | %.3g | %stime %.3g×%s |\n", mi_samplers[j],
                j == H->best ? " (best)" : "", H->mi_time[j], H->mi_time_extrap[j] ? " (extrapolated)" : "", H->pt_err,
                1.0 / (H->mi_time[j] * H->pt_err), j == H->best ? "**" : "", H->mi_time[j] / H->pt_time,
                j == H->best ? "**" : "");
    fprintf(f, "\n%dx%d, median of %d seeds; the Mitsuba rows are read off its series (one render per point, "
               "1, 2, 4, … spp) at pdftrace's time and at pdftrace's error. Reference: pdftrace MIS at %d spp, noise "
               "floor %.3g subtracted. Ratios > 1: pdftrace is ahead.\n\n", H->width, H->height, H->seeds, H->ref_spp,
            H->floor);
}

/* ---- throughput: camera samples and rays per second at equal depth ---------------------- */

/* Every scene at 128 x 128, and again at its scene file's own size where that differs (the
   600 x 600 Cornell box, the 160 x 120 rooms), rendered by each configuration in tput_configs:
   pdftrace with the scene committed at each SIMD level this CPU has (pt_simd_set_cap before the
   build), pdftrace with the Sobol sampler, and Mitsuba 3 with each sampler. All at equal depth and
   equal work per camera sample: pdftrace max_depth TPUT_DEPTH with no Russian roulette
   (rr_start_depth < 0), no splitting (max_splits < 0) and one path per camera sample
   (indirect_paths 1); Mitsuba's path integrator at max_depth TPUT_DEPTH + 1 (it counts the camera
   segment: the exporter's mapping) with rr_depth TPUT_MI_RR_DEPTH, beyond it. Each render takes
   about tput_samples camera samples; every core. A repetition renders every configuration once
   (seed = the repetition), the order rotated each repetition, so that a change in the machine's
   load hits the configurations alike; one untimed warm-up render of each Mitsuba sampler first
   (Dr.Jit compiles its kernels on first use, per sample count) and of the baseline. Figures: the
   median samples/s and rays/s (pt_render_stats: closest-hit = camera + bounce rays, occlusion =
   shadow rays; Mitsuba does not count its rays) and, per configuration, the median of the paired
   ratios of its samples/s to the baseline's (pdftrace's default: independent numbers at the
   CPU's level) with a distribution-free interval. Checks: pdftrace's SIMD levels give
   bit-identical images (same seed); each configuration's image mean (all pixels and channels,
   over the repetitions) against the baseline's, with z from the repetitions' spread, so that
   samples/s compares renderers computing the same image. To compare another pdftrace
   configuration (an integrator switch, say), add an entry to tput_configs and set its field in
   tput_desc: the tables and the CSV take every entry. */
static int median_interval(const double *sorted, int n, double *lo, double *hi, double *cover);
static const char *pass_fail(int ok);
#define TPUT_DEPTH 4
#define TPUT_MI_RR_DEPTH 1000
#define TPUT_BEST (-1)         /* tput_config.simd: the level pdftrace chooses by default */
#define TPUT_MAX_REPS 31
#define TPUT_MAX_ROWS (2 * SCENE_COUNT)
#define TPUT_BLOCKS 64         /* the image-mean check's blocks: pixels i (row-major) with i mod 64 = b */

typedef struct tput_config {
    const char *name;          /* the column's name */
    const char *mi_sampler;    /* Mitsuba 3 with this sampler; NULL: pdftrace */
    int simd;                  /* pdftrace: the pt_simd_level the scene is committed at, or TPUT_BEST */
    pt_sampler sampler;        /* pdftrace's sampler */
} tput_config;

static const tput_config tput_configs[] = {
    {"scalar", NULL, PT_SIMD_SCALAR, PT_SAMPLER_INDEPENDENT},
    {"sse2", NULL, PT_SIMD_SSE2, PT_SAMPLER_INDEPENDENT},
    {"avx2", NULL, PT_SIMD_AVX2, PT_SAMPLER_INDEPENDENT},
    {"avx512", NULL, PT_SIMD_AVX512, PT_SAMPLER_INDEPENDENT},
    {"sobol", NULL, TPUT_BEST, PT_SAMPLER_SOBOL},
    {"mitsuba-independent", "independent", 0, PT_SAMPLER_INDEPENDENT},
    {"mitsuba-multijitter", "multijitter", 0, PT_SAMPLER_INDEPENDENT},
};
#define TPUT_CONFIGS ((int)(sizeof tput_configs / sizeof tput_configs[0]))

/* the scenes of quick mode (make bench-quick runs in CI: a minute at most for this part) */
static const char *const tput_quick_scenes[] = {"cornell", "rooms"};

typedef struct tput_cell {
    int ran;
    char skip[640];            /* why not (a level this CPU lacks, a scene Mitsuba cannot take) */
    int level;                 /* pdftrace: the SIMD level the scene was committed at */
    int spp_used;              /* Mitsuba's multijitter may round the count up */
    double sps[TPUT_MAX_REPS], closest[TPUT_MAX_REPS], occluded[TPUT_MAX_REPS]; /* per second */
    double mean[TPUT_MAX_REPS]; /* image mean over pixels and channels */
    double block[TPUT_MAX_REPS][TPUT_BLOCKS]; /* the same over each block's pixels */
    uint64_t hash[TPUT_MAX_REPS]; /* pdftrace: of the image's floats */
    double med_sps, med_rays, med_closest, med_occluded;
    double ratio, ratio_lo, ratio_hi; /* paired samples/s over the baseline's; lo = hi = NAN: no interval */
    double mean_diff, mean_z;  /* image mean / the baseline's - 1, and its z from the blocks (NAN: identical) */
    int identical;             /* pdftrace: bit-identical to the baseline's image in every repetition */
} tput_cell;

typedef struct tput_row {
    int scene, width, height, spp, threads;
    tput_cell c[TPUT_CONFIGS];
} tput_row;

typedef struct tput_results {
    int available, n, reps, base, mitsuba;
    char skip_reason[512], mi_skip[512];
    double samples_target;
    tput_row row[TPUT_MAX_ROWS];
} tput_results;

/* The render description of configuration c for the row: equal depth, no roulette, no splitting. */
static pt_render_desc tput_desc(const loaded *L, const tput_config *c, const tput_row *row, uint64_t seed)
{
    pt_render_desc d = L->rd;
    d.width = row->width;
    d.height = row->height;
    d.samples_per_pixel = row->spp;
    d.samples_per_pass = 0;
    d.strategy = PT_STRATEGY_MIS;
    d.sampler = c->sampler;
    d.max_depth = TPUT_DEPTH;
    d.rr_start_depth = -1;
    d.max_splits = -1;
    d.indirect_paths = 1;
    d.guiding = PT_GUIDING_OFF;
    d.adaptive_threshold = 0;
    d.threads = 0;
    d.seed = seed;
    d.progress = NULL;
    return d;
}

/* A Mitsuba 3 process serving renders (mitsuba_series.py serve), its stderr into a log file. */
typedef struct tput_mitsuba {
    pid_t pid;
    FILE *to, *from;
} tput_mitsuba;

static int tput_mitsuba_start(const config *cfg, tput_mitsuba *m, const char *log)
{
    int in[2], out[2];
    memset(m, 0, sizeof *m);
    if (pipe(in) != 0) return 0;
    if (pipe(out) != 0) {
        close(in[0]);
        close(in[1]);
        return 0;
    }
    m->pid = fork();
    if (m->pid == 0) {
        int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) dup2(fd, 2);
        dup2(in[0], 0);
        dup2(out[1], 1);
        close(in[0]);
        close(in[1]);
        close(out[0]);
        close(out[1]);
        execl(cfg->mitsuba_python, cfg->mitsuba_python, MI_SCRIPT, "serve", (char *)NULL);
        _exit(127);
    }
    close(in[0]);
    close(out[1]);
    if (m->pid < 0) {
        close(in[1]);
        close(out[0]);
        return 0;
    }
    m->to = fdopen(in[1], "w");
    m->from = fdopen(out[0], "r");
    return m->to && m->from;
}

static void tput_mitsuba_stop(tput_mitsuba *m)
{
    if (m->to) fclose(m->to); /* end of input: the script exits */
    if (m->from) fclose(m->from);
    if (m->pid > 0) waitpid(m->pid, NULL, 0);
    memset(m, 0, sizeof *m);
}

/* Sends one command line and reads the answer into reply; 1 when it begins with "ok". */
static int tput_mitsuba_call(tput_mitsuba *m, char *reply, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vfprintf(m->to, fmt, ap);
    va_end(ap);
    if (fflush(m->to) != 0 || !fgets(reply, (int)n, m->from)) {
        snprintf(reply, n, "error the Mitsuba process ended (its log: mitsuba/tput.log)");
        return 0;
    }
    reply[strcspn(reply, "\n")] = '\0';
    return !strncmp(reply, "ok", 2);
}

/* One pdftrace render of configuration k for repetition rep (rep < 0: a warm-up, not recorded). */
static int tput_render_pdftrace(const loaded *L, pt_scene *scene, tput_row *row, int k, int rep)
{
    tput_cell *c = &row->c[k];
    pt_render_desc d = tput_desc(L, &tput_configs[k], row, rep < 0 ? REF_SEED + 1 : (uint64_t)rep + 1);
    pt_render_stats st;
    pt_film film;
    pt_image img = {0, 0, NULL};
    double t0, t, sum = 0, bsum[TPUT_BLOCKS] = {0};
    size_t i, n = 3u * (size_t)row->width * (size_t)row->height, bn[TPUT_BLOCKS] = {0};
    uint64_t h = 14695981039346656037ULL;
    if (pt_film_init(&film, row->width, row->height) != PT_OK) die_oom();
    t0 = ptv_now();
    if (pt_render(scene, &d, &film, &st) != PT_OK) {
        fprintf(stderr, "bench: throughput render of %s (%s) failed: %s\n", scenes[row->scene].name,
                tput_configs[k].name, st.error);
        pt_film_free(&film);
        return 0;
    }
    t = ptv_now() - t0;
    if (pt_film_resolve(&film, &img) != PT_OK) die_oom();
    pt_film_free(&film);
    if (rep < 0) {
        pt_image_free(&img);
        return 1;
    }
    for (i = 0; i < n; ++i) {
        uint32_t b;
        memcpy(&b, &img.rgb[i], sizeof b);
        h = (h ^ b) * 1099511628211ULL;
        sum += img.rgb[i];
        bsum[i / 3 % TPUT_BLOCKS] += img.rgb[i];
        bn[i / 3 % TPUT_BLOCKS]++;
    }
    pt_image_free(&img);
    for (i = 0; i < TPUT_BLOCKS; ++i) c->block[rep][i] = bn[i] ? bsum[i] / (double)bn[i] : 0;
    c->sps[rep] = (double)st.samples / t;
    c->closest[rep] = (double)(st.camera_rays + st.bounce_rays) / t;
    c->occluded[rep] = (double)st.shadow_rays / t;
    c->mean[rep] = sum / (double)n;
    c->hash[rep] = h;
    row->threads = st.threads;
    return 1;
}

/* One Mitsuba render of configuration k (its scene loaded as "tK"); rep < 0: a warm-up. */
static int tput_render_mitsuba(tput_mitsuba *m, tput_row *row, int k, int rep)
{
    tput_cell *c = &row->c[k];
    char reply[512 + 20 * TPUT_BLOCKS], *p;
    double t = 0, mr = 0, mg = 0, mb = 0;
    int used = 0, w = 0, h = 0, b, ok, len = 0;
    ok = tput_mitsuba_call(m, reply, sizeof reply, "render t%d %d %d %d\n", k, row->spp,
                           rep < 0 ? (int)REF_SEED + 1 : rep + 1, TPUT_BLOCKS) &&
         sscanf(reply, "ok %lf %d %d %d %lf %lf %lf%n", &t, &used, &w, &h, &mr, &mg, &mb, &len) == 7 &&
         w == row->width && h == row->height && t > 0;
    for (b = 0, p = reply + len; ok && b < TPUT_BLOCKS; ++b, p += len)
        ok = sscanf(p, "%lf%n", rep < 0 ? &t : &c->block[rep][b], &len) == 1;
    if (!ok) {
        fprintf(stderr, "bench: Mitsuba throughput render of %s (%s): %s\n", scenes[row->scene].name,
                tput_configs[k].name, reply);
        return 0;
    }
    if (rep < 0) return 1;
    c->spp_used = used;
    c->sps[rep] = (double)used * w * h / t;
    c->closest[rep] = c->occluded[rep] = NAN;
    c->mean[rep] = (mr + mg + mb) / 3.0;
    return 1;
}

/* Commits the row's scene once per SIMD level its pdftrace configurations need (scene_at[level]),
   marking the levels this CPU or build lacks; 0 on a build error. */
static int tput_build_levels(const loaded *L, tput_row *row, int best, pt_scene **scene_at)
{
    char err[1024];
    int k, ok = 1;
    for (k = 0; ok && k < TPUT_CONFIGS; ++k) {
        const tput_config *c = &tput_configs[k];
        pt_render_desc rd;
        pt_scene_info info;
        int level = c->simd == TPUT_BEST ? best : c->simd;
        if (c->mi_sampler) continue;
        row->c[k].level = level;
        if (level > best) {
            snprintf(row->c[k].skip, sizeof row->c[k].skip, "above the default level here, %s (the CPU, the build or "
                     "PDFTRACE_SIMD)",
                     pt_simd_level_name((pt_simd_level)best));
            continue;
        }
        if (scene_at[level]) continue;
        pt_simd_set_cap((pt_simd_level)level);
        if (pt_scenefile_build(&L->sd, &scene_at[level], &rd, err, sizeof err) != PT_OK) {
            fprintf(stderr, "bench: %s\n", err);
            ok = 0;
        } else if (pt_scene_get_info(scene_at[level], &info) != PT_OK || (int)info.simd_level != level) {
            fprintf(stderr, "bench: %s committed at SIMD level %s, asked for %s\n", scenes[row->scene].name,
                    pt_simd_level_name(info.simd_level), pt_simd_level_name((pt_simd_level)level));
            ok = 0;
        }
    }
    pt_simd_set_cap(PT_SIMD_AVX512); /* no cap: the default */
    return ok;
}

/* Exports the row's scene at equal depth and loads it into the Mitsuba process once per sampler
   (as "tK"); a scene or sampler Mitsuba cannot take marks its cells skipped. */
static int tput_mitsuba_load(const config *cfg, const loaded *L, tput_row *row, tput_mitsuba *m)
{
    char xml[2300], why[512], reply[512];
    pt_mitsuba_options o;
    int k, ok = 1;
    snprintf(xml, sizeof xml, "%s/mitsuba/%s-%dx%d-depth%d.xml", cfg->out, scenes[row->scene].name, row->width,
             row->height, TPUT_DEPTH);
    memset(&o, 0, sizeof o);
    o.width = row->width;
    o.height = row->height;
    o.max_depth = TPUT_DEPTH; /* written as TPUT_DEPTH + 1 segments */
    if (strpbrk(xml, " \t\r\n")) {
        snprintf(why, sizeof why, "the path %s has blanks (the commands to Mitsuba split on them)", cfg->out);
        ok = 0;
    } else if (pt_scenefile_export_mitsuba(&L->sd, xml, &o, why, sizeof why) != PT_OK)
        ok = 0;
    for (k = 0; k < TPUT_CONFIGS; ++k) {
        if (!tput_configs[k].mi_sampler) continue;
        if (!ok) {
            snprintf(row->c[k].skip, sizeof row->c[k].skip, "not exported: %s", why);
            continue;
        }
        if (!tput_mitsuba_call(m, reply, sizeof reply, "load t%d %s %s 0 %d\n", k, xml, tput_configs[k].mi_sampler,
                               TPUT_MI_RR_DEPTH))
            snprintf(row->c[k].skip, sizeof row->c[k].skip, "Mitsuba: %s", reply);
    }
    return 1;
}

/* Medians, the paired ratios to the baseline and the image checks of one row. */
static void tput_summarize_row(tput_row *row, int base, int reps)
{
    const tput_cell *b = &row->c[base];
    int k, r;
    for (k = 0; k < TPUT_CONFIGS; ++k) {
        tput_cell *c = &row->c[k];
        double v[TPUT_MAX_REPS], mc = 0, mb = 0, dm = 0, dv = 0, cover, d;
        int n = reps * TPUT_BLOCKS, q;
        if (!c->ran) continue;
        c->med_sps = median(c->sps, reps);
        c->med_closest = median(c->closest, reps);
        c->med_occluded = median(c->occluded, reps);
        for (r = 0; r < reps; ++r) v[r] = c->closest[r] + c->occluded[r];
        c->med_rays = median(v, reps);
        for (r = 0; r < reps; ++r) v[r] = c->sps[r] / b->sps[r];
        qsort(v, (size_t)reps, sizeof v[0], cmp_double);
        c->ratio = median(v, reps);
        if (!median_interval(v, reps, &c->ratio_lo, &c->ratio_hi, &cover)) c->ratio_lo = c->ratio_hi = NAN;
        c->identical = !tput_configs[k].mi_sampler;
        for (r = 0; r < reps; ++r) {
            c->identical &= c->hash[r] == b->hash[r];
            mc += c->mean[r] / reps;
            mb += b->mean[r] / reps;
        }
        /* z: the mean over repetitions and blocks of the block-mean differences over its standard
           error; blocks hold disjoint pixels and repetitions other seeds, so the differences are
           independent, with expectation 0 when both compute the same image */
        for (r = 0; r < reps; ++r)
            for (q = 0; q < TPUT_BLOCKS; ++q) dm += (c->block[r][q] - b->block[r][q]) / n;
        for (r = 0; r < reps; ++r)
            for (q = 0; q < TPUT_BLOCKS; ++q) {
                d = c->block[r][q] - b->block[r][q] - dm;
                dv += d * d / (n - 1.0);
            }
        c->mean_diff = mc / mb - 1.0;
        c->mean_z = c->identical || dv <= 0 ? NAN : dm / sqrt(dv / n);
    }
}

/* Measures one row: every configuration, the repetitions in rotated order. */
static int tput_run_row(const config *cfg, const loaded *L, tput_results *T, tput_row *row, tput_mitsuba *m)
{
    pt_scene *scene_at[PT_SIMD_AVX512 + 1] = {NULL, NULL, NULL, NULL};
    int best = (int)pt_simd_get_level(), k, r, j, ok;
    ok = tput_build_levels(L, row, best, scene_at);
    if (ok && T->mitsuba) ok = tput_mitsuba_load(cfg, L, row, m);
    for (k = 0; k < TPUT_CONFIGS; ++k)
        if (tput_configs[k].mi_sampler && !T->mitsuba) snprintf(row->c[k].skip, sizeof row->c[k].skip, "%s", T->mi_skip);
    for (k = 0; k < TPUT_CONFIGS; ++k) row->c[k].ran = !row->c[k].skip[0];
    /* warm-up: the baseline, and each Mitsuba sampler (its kernels compile for this sample count) */
    if (ok) ok = tput_render_pdftrace(L, scene_at[row->c[T->base].level], row, T->base, -1);
    for (k = 0; ok && k < TPUT_CONFIGS; ++k)
        if (row->c[k].ran && tput_configs[k].mi_sampler) ok = tput_render_mitsuba(m, row, k, -1);
    for (r = 0; ok && r < T->reps; ++r)
        for (j = 0; ok && j < TPUT_CONFIGS; ++j) {
            k = (r + j) % TPUT_CONFIGS;
            if (!row->c[k].ran) continue;
            ok = tput_configs[k].mi_sampler ? tput_render_mitsuba(m, row, k, r)
                                            : tput_render_pdftrace(L, scene_at[row->c[k].level], row, k, r);
        }
    for (k = 0; T->mitsuba && k < TPUT_CONFIGS; ++k) {
        char reply[512];
        if (tput_configs[k].mi_sampler && row->c[k].ran) (void)tput_mitsuba_call(m, reply, sizeof reply, "drop t%d\n", k);
    }
    for (k = 0; k <= PT_SIMD_AVX512; ++k) pt_scene_destroy(scene_at[k]);
    if (ok) tput_summarize_row(row, T->base, T->reps);
    return ok;
}

static int tput_in_quick(const char *name)
{
    size_t i;
    for (i = 0; i < sizeof tput_quick_scenes / sizeof tput_quick_scenes[0]; ++i)
        if (!strcmp(tput_quick_scenes[i], name)) return 1;
    return 0;
}

static int run_throughput(const config *cfg, const results *R, tput_results *T)
{
    tput_mitsuba m;
    char dir[2048], log[2300];
    int i, k, s, ok = 1;
    void (*old_pipe)(int) = signal(SIGPIPE, SIG_IGN); /* a Mitsuba process that died: an error, not a signal */
    memset(T, 0, sizeof *T);
    memset(&m, 0, sizeof m);
    T->reps = cfg->quick ? 3 : 7;
    T->samples_target = cfg->quick ? 131072 : 524288; /* renders of ~0.05 and ~0.2 s at 2.5 M samples/s */
    T->base = -1;
    for (k = 0; k < TPUT_CONFIGS; ++k)
        if (!tput_configs[k].mi_sampler && tput_configs[k].sampler == PT_SAMPLER_INDEPENDENT &&
            tput_configs[k].simd == (int)pt_simd_get_level() && T->base < 0)
            T->base = k;
    if (T->base < 0) {
        fprintf(stderr, "bench: no throughput configuration renders at pdftrace's default SIMD level\n");
        signal(SIGPIPE, old_pipe);
        return 0;
    }
    snprintf(dir, sizeof dir, "%s/mitsuba", cfg->out);
    snprintf(log, sizeof log, "%s/tput.log", dir);
    if (!mitsuba_usable(cfg, T->mi_skip, sizeof T->mi_skip)) printf("SKIP throughput, Mitsuba: %s\n", T->mi_skip);
    else if (!mkdirs(dir) || !tput_mitsuba_start(cfg, &m, log)) {
        snprintf(T->mi_skip, sizeof T->mi_skip, "could not start %s %s serve", cfg->mitsuba_python, MI_SCRIPT);
        printf("SKIP throughput, Mitsuba: %s\n", T->mi_skip);
    } else
        T->mitsuba = 1;
    printf("throughput: %d repetitions, about %.0f camera samples per render, max_depth %d, no roulette\n", T->reps,
           T->samples_target, TPUT_DEPTH);
    fflush(stdout);
    for (i = 0; ok && i < SCENE_COUNT; ++i) {
        const loaded *L = &R->L[i];
        if (!cfg->scene_on[i] || !L->scene || (cfg->quick && !tput_in_quick(scenes[i].name))) continue;
        for (s = 0; ok && s < 2; ++s) {
            tput_row *row = &T->row[T->n];
            int w = s ? L->sd.width : BENCH_SIZE, h = s ? L->sd.height : BENCH_SIZE;
            double spp;
            if (s && w == BENCH_SIZE && h == BENCH_SIZE) continue;
            memset(row, 0, sizeof *row);
            row->scene = i;
            row->width = w;
            row->height = h;
            spp = floor(T->samples_target / ((double)w * h) + 0.5);
            row->spp = spp < 1 ? 1 : (int)spp;
            ok = tput_run_row(cfg, L, T, row, &m);
            if (!ok) break;
            T->n++;
            printf("  %-16s %4dx%-4d %3d spp: pdftrace %.3g M samples/s (%s)", scenes[i].name, w, h, row->spp,
                   row->c[T->base].med_sps * 1e-6, tput_configs[T->base].name);
            for (k = 0; k < TPUT_CONFIGS; ++k)
                if (tput_configs[k].mi_sampler && row->c[k].ran)
                    printf(", %s %.3g M (mean %+.2f%%)", tput_configs[k].name, row->c[k].med_sps * 1e-6,
                           100 * row->c[k].mean_diff);
            printf("\n");
            fflush(stdout);
        }
    }
    if (T->mitsuba) tput_mitsuba_stop(&m);
    signal(SIGPIPE, old_pipe);
    T->available = ok;
    return ok;
}

/* The median over repetitions of a's samples/s over b's (paired), with its interval (NAN: none). */
static double tput_paired(const tput_cell *a, const tput_cell *b, int reps, double *lo, double *hi)
{
    double v[TPUT_MAX_REPS], cover;
    int r;
    for (r = 0; r < reps; ++r) v[r] = a->sps[r] / b->sps[r];
    qsort(v, (size_t)reps, sizeof v[0], cmp_double);
    if (!median_interval(v, reps, lo, hi, &cover)) *lo = *hi = NAN;
    return median(v, reps);
}

/* The fastest configuration of the row that ran, among pdftrace's (mitsuba 0) or Mitsuba's (1); -1: none. */
static int tput_fastest(const tput_row *row, int mitsuba)
{
    int k, b = -1;
    for (k = 0; k < TPUT_CONFIGS; ++k)
        if (row->c[k].ran && !tput_configs[k].mi_sampler == !mitsuba && (b < 0 || row->c[k].med_sps > row->c[b].med_sps))
            b = k;
    return b;
}

static int write_tput_csv(const config *cfg, const tput_results *T)
{
    FILE *f;
    int i, k;
    if (!T->available) return 1;
    f = open_out(cfg, "tput.csv");
    if (!f) return 0;
    fprintf(f, "scene,width,height,config,renderer,simd_level,sampler,spp,spp_used,reps,threads,max_depth,"
               "samples_per_s,rays_per_s,closest_per_s,occluded_per_s,ratio_to_base,ratio_lo,ratio_hi,"
               "mean_vs_base,mean_z,identical_to_base,skip\n");
    for (i = 0; i < T->n; ++i) {
        const tput_row *row = &T->row[i];
        for (k = 0; k < TPUT_CONFIGS; ++k) {
            const tput_config *c = &tput_configs[k];
            const tput_cell *e = &row->c[k];
            fprintf(f, "%s,%d,%d,%s,%s,%s,%s,%d,%d,%d,%d,%d,", scenes[row->scene].name, row->width, row->height, c->name,
                    c->mi_sampler ? "mitsuba3" : "pdftrace", c->mi_sampler ? "" : pt_simd_level_name((pt_simd_level)e->level),
                    c->mi_sampler ? c->mi_sampler : c->sampler == PT_SAMPLER_SOBOL ? "sobol" : "independent", row->spp,
                    c->mi_sampler ? e->spp_used : row->spp, T->reps, row->threads, TPUT_DEPTH);
            if (e->ran)
                fprintf(f, "%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g,%d,\n", e->med_sps, e->med_rays, e->med_closest,
                        e->med_occluded, e->ratio, e->ratio_lo, e->ratio_hi, e->mean_diff, e->mean_z, e->identical);
            else
                fprintf(f, ",,,,,,,,,,\"%s\"\n", e->skip);
        }
    }
    return close_out(f, "tput.csv");
}

/* summary.md's table of every configuration: samples/s, rays/s and the paired ratio to the baseline. */
static void write_tput_levels(FILE *f, const tput_results *T)
{
    int i, k;
    fprintf(f, "| scene | size | spp |");
    for (k = 0; k < TPUT_CONFIGS; ++k) fprintf(f, " %s%s |", tput_configs[k].name, k == T->base ? " (baseline)" : "");
    fprintf(f, " SIMD levels bit-identical |\n|---|---|---|");
    for (k = 0; k <= TPUT_CONFIGS; ++k) fprintf(f, "---|");
    fprintf(f, "\n");
    for (i = 0; i < T->n; ++i) {
        const tput_row *row = &T->row[i];
        int same = 1;
        fprintf(f, "| %s | %dx%d | %d |", scenes[row->scene].name, row->width, row->height, row->spp);
        for (k = 0; k < TPUT_CONFIGS; ++k) {
            const tput_cell *e = &row->c[k];
            if (!e->ran) {
                fprintf(f, " – |");
                continue;
            }
            fprintf(f, " %.3g", e->med_sps * 1e-6);
            if (!tput_configs[k].mi_sampler) fprintf(f, " (%.3g)", e->med_rays * 1e-6);
            if (k != T->base) {
                fprintf(f, " %.3f×", e->ratio);
                if (!isnan(e->ratio_lo)) fprintf(f, " [%.3f, %.3f]", e->ratio_lo, e->ratio_hi);
            }
            fprintf(f, " |");
            if (!tput_configs[k].mi_sampler && tput_configs[k].sampler == tput_configs[T->base].sampler)
                same &= e->identical;
        }
        fprintf(f, " %s |\n", same ? "yes" : "**no**");
    }
    fprintf(f, "\n");
}

/* summary.md's table against Mitsuba 3: the fastest configuration of each renderer, and the check
   that they compute the same image (Mitsuba's image mean against pdftrace's baseline). */
static void write_tput_mitsuba(FILE *f, const tput_results *T)
{
    int i, k;
    fprintf(f, "| scene | size | pdftrace baseline | pdftrace fastest | Mitsuba 3 fastest | pdftrace / Mitsuba (paired) |");
    for (k = 0; k < TPUT_CONFIGS; ++k)
        if (tput_configs[k].mi_sampler) fprintf(f, " image mean, %s / pdftrace − 1 (z) |", tput_configs[k].name);
    fprintf(f, "\n|---|---|---|---|---|---|");
    for (k = 0; k < TPUT_CONFIGS; ++k)
        if (tput_configs[k].mi_sampler) fprintf(f, "---|");
    fprintf(f, "\n");
    for (i = 0; i < T->n; ++i) {
        const tput_row *row = &T->row[i];
        int p = tput_fastest(row, 0), m = tput_fastest(row, 1);
        double lo, hi, r;
        fprintf(f, "| %s | %dx%d | %.3g | %.3g (%s) |", scenes[row->scene].name, row->width, row->height,
                row->c[T->base].med_sps * 1e-6, row->c[p].med_sps * 1e-6, tput_configs[p].name);
        if (m < 0) {
            fprintf(f, " – | – |");
        } else {
            r = tput_paired(&row->c[p], &row->c[m], T->reps, &lo, &hi);
            fprintf(f, " %.3g (%s) | **%.3f**", row->c[m].med_sps * 1e-6, tput_configs[m].mi_sampler, r);
            if (!isnan(lo)) fprintf(f, " [%.3f, %.3f]", lo, hi);
            fprintf(f, " |");
        }
        for (k = 0; k < TPUT_CONFIGS; ++k) {
            const tput_cell *e = &row->c[k];
            if (!tput_configs[k].mi_sampler) continue;
            if (e->ran) fprintf(f, " %+.3f %% (%+.1f) |", 100 * e->mean_diff, e->mean_z);
            else fprintf(f, " %s |", e->skip);
        }
        fprintf(f, "\n");
    }
    fprintf(f, "\n");
}

/* The acceptance lines of issue 19: at equal depth, pdftrace's samples/s at least Mitsuba 3's on the
   Cornell box and on the closed room of large quads, each at its scene file's size. */
static void write_tput_acceptance(FILE *f, const tput_results *T)
{
    int i;
    for (i = 0; T->available && i < T->n; ++i) {
        const tput_row *row = &T->row[i];
        int p = tput_fastest(row, 0), m = tput_fastest(row, 1);
        double lo, hi, r;
        if (m < 0 || p < 0 || (strcmp(scenes[row->scene].name, "cornell") && strcmp(scenes[row->scene].name, "rooms")) ||
            (row->width == BENCH_SIZE && row->height == BENCH_SIZE))
            continue;
        r = tput_paired(&row->c[p], &row->c[m], T->reps, &lo, &hi);
        fprintf(f, "| %s %dx%d: at equal depth (%d, no roulette) pdftrace's camera samples/s ≥ Mitsuba 3's | pdftrace %s "
                   "%.3g M/s, Mitsuba %s %.3g M/s: **ratio %.3f** (paired median) | %s |\n",
                scenes[row->scene].name, row->width, row->height, TPUT_DEPTH, tput_configs[p].name,
                row->c[p].med_sps * 1e-6, tput_configs[m].mi_sampler, row->c[m].med_sps * 1e-6, r, pass_fail(r >= 1));
    }
}

static void write_tput_summary(FILE *f, const tput_results *T)
{
    fprintf(f, "## Throughput at equal depth\n\n");
    if (!T->available) {
        fprintf(f, "SKIP: %s\n\n", T->skip_reason);
        return;
    }
    fprintf(f, "Every configuration renders each scene at max_depth %d (pdftrace's scattering events; Mitsuba 3's path "
               "integrator at max_depth %d, as it counts the camera segment) without Russian roulette (pdftrace "
               "rr_start_depth < 0; Mitsuba rr_depth %d), pdftrace without splitting (max_splits < 0, indirect_paths 1): "
               "one path per camera sample in both. About %.0f camera samples per render, every core (%d threads), "
               "%d repetitions whose order of configurations rotates; after an untimed warm-up render. Figures are "
               "medians; **M camera samples/s (M rays/s)**, rays = closest-hit (camera and bounce) + occlusion (shadow) "
               "rays from pt_render_stats (Mitsuba does not count its rays), then the median of the paired ratios of "
               "samples/s to the baseline (pdftrace's default: independent numbers at this CPU's SIMD level) with its "
               "distribution-free 95 %% interval where the repetitions allow one. A pdftrace level column is the scene "
               "committed at that level (pt_simd_set_cap); *sobol* is the Sobol sampler at the default level. "
               "tput.csv has every figure, closest-hit and occlusion rays apart.\n\n",
            TPUT_DEPTH, TPUT_DEPTH + 1, TPUT_MI_RR_DEPTH, T->samples_target, T->n ? T->row[0].threads : 0, T->reps);
    write_tput_levels(f, T);
    fprintf(f, "### Against Mitsuba 3 at equal depth\n\n");
    if (!T->mitsuba) fprintf(f, "Mitsuba: SKIP (%s).\n\n", T->mi_skip);
    fprintf(f, "M camera samples/s; the ratio is the median of the paired ratios of the two fastest configurations (> 1: "
               "pdftrace is ahead). The image-mean columns check that both compute the same image at this depth: "
               "Mitsuba's image mean (all pixels and channels, over the repetitions) against pdftrace's baseline, and z "
               "= the mean difference of the %d pixel blocks' means (pixel i in block i mod %d) over its standard error "
               "across blocks and repetitions (independent differences: |z| beyond 3 is unlikely by chance; Mitsuba's "
               "max_depth one lower, 4 segments, moves the rooms' mean by −9 %%).\n\n", TPUT_BLOCKS, TPUT_BLOCKS);
    write_tput_mitsuba(f, T);
}

/* ---- adaptive sampling and the scene-feature skips ------------------------------------ */

#define ADAPTIVE_MAX 12
#define ADAPTIVE_CAP 4 /* adaptive renders may give a pixel up to 4x the uniform render's spp */
typedef struct adaptive_results {
    int available;
    char skip_reason[256];
    int n_uniform, n_adaptive;
    point uniform[MAX_LEVELS];         /* medians over seeds */
    double uniform_err[MAX_LEVELS];
    point adaptive[ADAPTIVE_MAX];
    double adaptive_err[ADAPTIVE_MAX];
    double threshold[ADAPTIVE_MAX];
    double converged[ADAPTIVE_MAX];    /* fraction of pixels that stopped early */
    double target_err, uniform_time, adaptive_time, ratio;
    double series_time, ratio_series;  /* the series' own time for N spp, and the ratio against it */
    double ratio_samples;              /* samples adaptive needs for the uniform error / uniform samples */
    double uniform_check_err;          /* median relMSE of the uniform renders timed beside (= E) */
    int ratio_extrap;
    int end_spp;                       /* the uniform render's spp that is compared */
    int neighbours_only;               /* pt_render_desc.adaptive_neighbours_only of the adaptive renders */
    char image_uniform[256], image_adaptive[256], image_map[256];
} adaptive_results;

#define SKIP_MAX 16
#define SKIP_REPS_MAX 64
/* How the general path of a skip relates to the specialised one, which decides the ratio that
   says whether the skip pays (see run_skips). */
typedef enum skip_kind {
    SKIP_EXACT,     /* the same image bit for bit: the time ratio */
    SKIP_SAME_DIST, /* the same estimator, other random numbers (the general path draws numbers it
                       then multiplies by zero): same variance, so the time ratio */
    SKIP_ESTIMATOR  /* another estimator (other variance): the time ratio at equal error */
} skip_kind;
typedef struct skip_result {
    const char *name, *scene, *what;
    char strategy[32];
    unsigned bit;
    skip_kind kind;
    int reps, spp;
    double t_on, t_off;                /* medians of the CPU times: specialised, general forced */
    double ratio, ratio_lo, ratio_hi;  /* median of the paired ratios t_on / t_off and its
                                          distribution-free interval (binomial order statistics) */
    double ratio_cover;                /* the interval's exact coverage (>= 0.95) */
    double v_on, v_off;                /* mean relMSE of one render (from the pixels' sample variance) */
    double eq, eq_lo, eq_hi;           /* time ratio at equal error (t_on v_on) / (t_off v_off), 95 %
                                          bootstrap interval over repetitions */
    double relmse_between;             /* relMSE of one image against the other, same seed (0: bit-identical) */
    double dec, dec_lo, dec_hi;        /* the deciding ratio (ratio or eq, by kind) and its interval */
    int pays;                          /* dec_hi < 1 */
} skip_result;
typedef struct skip_results {
    int available, n;
    char skip_reason[256];
    skip_result r[SKIP_MAX];
} skip_results;

/* Writes a PNG (libpng) of img, sRGB-encoded; without libpng a PPM beside it. */
static void save_image(const config *cfg, const char *name, const pt_image *img, char *shown, size_t shown_size)
{
    char path[2300];
#ifdef PTV_HAVE_PNG
    snprintf(path, sizeof path, "%s/%s.png", cfg->out, name);
    if (png_tonemapped(path, img)) snprintf(shown, shown_size, "%s.png", name);
#else
    snprintf(path, sizeof path, "%s/%s.ppm", cfg->out, name);
    if (pt_write_ppm(path, img) == PT_OK) snprintf(shown, shown_size, "%s.ppm", name);
#endif
}

/* Adaptive sampling against uniform sampling on the Cornell box, MIS. Uniform: the MIS series
   ends at N spp with error E (median over the seeds). Adaptive: one render per threshold T (the
   image's target RMS relative error, so T^2 targets relMSE), T from 1.26 sqrt(E) down to
   0.56 sqrt(E) in steps of 2^(1/6) (quick: 1.19 down to 0.59 sqrt(E), steps of 2^(1/4)), so the
   two thresholds that bracket E are about 1.5x apart in error (with steps of sqrt(2), ~2.4x,
   the log-log chord overstated the cost: at 128 spp, 6 seeds, 0.686x the uniform samples from
   thresholds 1, 0.8 x sqrt(E) against 0.650x from 0.85, 0.72 x sqrt(E)),
   samples_per_pixel capped at ADAPTIVE_CAP x N, everything else at the header's defaults (pass
   size, minimum spp, check interval); time and relMSE are medians over the seeds.
   The time adaptive needs to reach E is interpolated (log-log) between the two thresholds that
   bracket it. It is compared with the time of a uniform render of N spp (header defaults: N/16
   spp per pass) timed here, side by side: the renders run seed-major (seed s: the uniform
   render, then every threshold), so a slow phase of the shared machine hits both alike; the
   series' own time for N spp (measured minutes earlier, progressive in 1, 1, 2, 4, ... spp
   steps) is reported beside it. */
/* end_spp 0: compare at the uniform series' last point (images saved unless neighbours_only);
   otherwise at its point of end_spp samples per pixel (the Cornell scene file's own 128), if the
   series has it before its last point. The adaptive renders use PT_ADAPTIVE_OWN_SAMPLES, or with
   neighbours_only PT_ADAPTIVE_NEIGHBOURS (a pixel's own samples left out of its noise estimate;
   the control for own samples: section 8 of pdftrace.h). */
static int run_adaptive(const config *cfg, results *R, adaptive_results *A, int end_spp, int neighbours_only)
{
    const int sc = 0; /* cornell */
    const series *u = &R->s[sc][S_MIS];
    loaded *L = &R->L[sc];
    int k, seed, n, nu, end = u->levels - 1, save = end_spp == 0 && !neighbours_only;
    double base, kept_err = 1;
    double t[ADAPTIVE_MAX][MAX_SEEDS], e[ADAPTIVE_MAX][MAX_SEEDS], b[ADAPTIVE_MAX][MAX_SEEDS];
    double smp[ADAPTIVE_MAX][MAX_SEEDS], cv[ADAPTIVE_MAX][MAX_SEEDS], tu[MAX_SEEDS], eu[MAX_SEEDS];
    pt_image keep = {0, 0, NULL};
    memset(A, 0, sizeof *A);
    if (!R->done[sc] || u->levels < 2) {
        snprintf(A->skip_reason, sizeof A->skip_reason, "needs the cornell MIS series (--parts series,adaptive)");
        printf("SKIP adaptive: %s\n", A->skip_reason);
        return 1;
    }
    if (end_spp > 0) {
        for (end = 0; end < u->levels - 1 && u->med[end].spp != end_spp; ++end) {}
        if (end >= u->levels - 1) {
            snprintf(A->skip_reason, sizeof A->skip_reason, "the uniform series has no %d-spp point before its end",
                     end_spp);
            printf("SKIP adaptive at %d spp: %s\n", end_spp, A->skip_reason);
            return 1;
        }
    }
    A->available = 1;
    A->neighbours_only = neighbours_only;
    A->n_uniform = u->levels;
    for (k = 0; k < u->levels; ++k) {
        A->uniform[k] = u->med[k];
        A->uniform_err[k] = u->err[k];
    }
    nu = u->med[end].spp;
    A->end_spp = nu;
    A->target_err = u->err[end];
    A->series_time = u->med[end].time;
    base = sqrt(A->target_err);
    n = cfg->quick ? 5 : 8;
    A->n_adaptive = n;
    printf("adaptive%s: cornell, MIS, uniform series at %d spp: relMSE %.3e in %.3f s; %d thresholds x %d seeds\n",
           neighbours_only ? " (neighbours only)" : "", nu, A->target_err, A->series_time, n, cfg->seeds);
    for (k = 0; k < n; ++k) /* 2^(1/3) .. 2^(-5/6) x sqrt(E); quick: 2^(1/4) .. 2^(-3/4) x sqrt(E) */
        A->threshold[k] = base * (cfg->quick ? pow(2.0, 0.25 - 0.25 * k) : pow(2.0, (2.0 - k) / 6.0));
    for (seed = 0; seed < cfg->seeds; ++seed) {
        for (k = -1; k < n; ++k) {
            pt_render_desc d = L->rd;
            pt_render_stats st;
            pt_film film;
            pt_image img = {0, 0, NULL};
            double t0, tt, ee, bb;
            d.strategy = PT_STRATEGY_MIS;
            d.seed = (uint64_t)(seed + 1);
            d.samples_per_pixel = k < 0 ? nu : ADAPTIVE_CAP * nu;
            d.samples_per_pass = 0;   /* the header's defaults: spp/16 per pass uniform, cap/64 adaptive, */
            d.adaptive_min_spp = 0;   /* min spp max(16, cap/16), */
            d.adaptive_check_passes = 0; /* a check after every pass */
            d.adaptive_threshold = k < 0 ? 0.0f : (float)A->threshold[k];
            /* the re-planning schemes this part describes (the pilot default is measured in docs/design.md) */
            d.adaptive_mode = neighbours_only ? PT_ADAPTIVE_NEIGHBOURS : PT_ADAPTIVE_OWN_SAMPLES;
            d.adaptive_neighbours_only = 0;
            if (pt_film_init(&film, BENCH_SIZE, BENCH_SIZE) != PT_OK) die_oom();
            t0 = ptv_now();
            if (pt_render(L->scene, &d, &film, &st) != PT_OK) {
                fprintf(stderr, "bench: adaptive render failed: %s\n", st.error);
                pt_film_free(&film);
                pt_image_free(&keep);
                return 0;
            }
            tt = ptv_now() - t0;
            if (pt_film_resolve(&film, &img) != PT_OK) die_oom();
            measure(&img, &L->ref, &ee, &bb);
            ee -= L->floor;
            if (k < 0) {
                tu[seed] = tt;
                eu[seed] = ee;
                if (seed == 0 && save)
                    save_image(cfg, "adaptive-uniform", &img, A->image_uniform, sizeof A->image_uniform);
                pt_image_free(&img);
                pt_film_free(&film);
                continue;
            }
            t[k][seed] = tt;
            e[k][seed] = ee;
            b[k][seed] = bb;
            smp[k][seed] = (double)st.samples;
            cv[k][seed] = (double)st.pixels_converged / (BENCH_SIZE * BENCH_SIZE);
            /* keep seed 1's image nearest the target, and its samples-per-pixel map */
            if (save && seed == 0 &&
                (k == 0 || fabs(log(ee / A->target_err)) < fabs(log(kept_err / A->target_err)))) {
                pt_image map = {0, 0, NULL};
                int i;
                uint32_t maxc = 1;
                kept_err = ee;
                pt_image_free(&keep);
                keep = img;
                img.rgb = NULL;
                if (pt_image_init(&map, BENCH_SIZE, BENCH_SIZE) != PT_OK) die_oom();
                for (i = 0; i < BENCH_SIZE * BENCH_SIZE; ++i)
                    if (film.count[i] > maxc) maxc = film.count[i];
                for (i = 0; i < BENCH_SIZE * BENCH_SIZE; ++i) {
                    /* grey level: log2 of the samples, scaled so the cap is white (then sRGB-decoded,
                       so the PNG shows the grey level itself) */
                    float g = (float)(log((double)film.count[i] + 1.0) / log((double)maxc + 1.0));
                    float lin = g <= 0.04045f ? g / 12.92f : (float)pow((g + 0.055) / 1.055, 2.4);
                    map.rgb[3 * i] = map.rgb[3 * i + 1] = map.rgb[3 * i + 2] = lin;
                }
                save_image(cfg, "adaptive-spp", &map, A->image_map, sizeof A->image_map);
                pt_image_free(&map);
            }
            pt_image_free(&img);
            pt_film_free(&film);
        }
        printf("  seed %d/%d done\n", seed + 1, cfg->seeds);
        fflush(stdout);
    }
    A->uniform_time = median(tu, cfg->seeds);
    A->uniform_check_err = median(eu, cfg->seeds);
    printf("  uniform %d spp, timed beside: %.3f s, relMSE %.3e\n", nu, A->uniform_time, A->uniform_check_err);
    for (k = 0; k < n; ++k) {
        A->adaptive[k].spp = ADAPTIVE_CAP * nu;
        A->adaptive[k].time = median(t[k], cfg->seeds);
        A->adaptive_err[k] = median(e[k], cfg->seeds);
        A->adaptive[k].bias = median(b[k], cfg->seeds);
        A->adaptive[k].samples = median(smp[k], cfg->seeds);
        A->converged[k] = median(cv[k], cfg->seeds);
        printf("  threshold %.4f: %.3f s, relMSE %.3e, %.1f%% of pixels stopped early, %.2g samples\n", A->threshold[k],
               A->adaptive[k].time, A->adaptive_err[k], 100 * A->converged[k], A->adaptive[k].samples);
    }
    if (keep.rgb) save_image(cfg, "adaptive-image", &keep, A->image_adaptive, sizeof A->image_adaptive);
    pt_image_free(&keep);
    /* time and samples to the uniform error: the adaptive points ordered by threshold (decreasing error) */
    {
        series tmp;
        int ex;
        memset(&tmp, 0, sizeof tmp);
        tmp.levels = n;
        for (k = 0; k < n; ++k) {
            tmp.med[k] = A->adaptive[k];
            tmp.err[k] = A->adaptive_err[k];
        }
        A->adaptive_time = time_to_reach(&tmp, A->target_err, &A->ratio_extrap);
        A->ratio = A->adaptive_time / A->uniform_time;
        A->ratio_series = A->adaptive_time / A->series_time;
        for (k = 0; k < n; ++k) tmp.med[k].time = A->adaptive[k].samples;
        A->ratio_samples = time_to_reach(&tmp, A->target_err, &ex) / ((double)nu * BENCH_SIZE * BENCH_SIZE);
    }
    printf("  adaptive reaches the uniform error %.3e in %.3f s vs %.3f s: ratio %.2f%s (%.2f against the series' "
           "time, %.2f in samples)\n", A->target_err, A->adaptive_time, A->uniform_time, A->ratio,
           A->ratio_extrap ? " (extrapolated)" : "", A->ratio_series, A->ratio_samples);
    return 1;
}

/* One scene-feature skip: its bit, the scene and strategy where it does its work. */
typedef struct skip_case {
    const char *name;
    unsigned bit;
    const char *scene_file, *scene_name;
    pt_strategy strategy;
    float light_weight;
    skip_kind kind;
    const char *what;
} skip_case;

/* (PT_SKIP_LIGHT_SELECTION and PT_SKIP_NO_TRIANGLES were measured here and removed from
   pdftrace.h: no gain shown; see its top comment.) */
static const skip_case skip_cases[] = {
    /* no emitters under the mixture: the general path keeps the light component, whose samples
       fail and end the path (an estimator with more variance per sample, paths are shorter).
       The lamps room has delta lights only: no emitting shape and no environment */
    {"NO_EMITTERS", PT_SKIP_NO_EMITTERS, "bench/scenes/lamps.scene", "lamps", PT_STRATEGY_MIXTURE, 0.5f, SKIP_ESTIMATOR,
     "no light component or light sampling in a scene without emitters"},
    /* the general path samples a light at the delta vertex and evaluates the material toward
       it, which is zero: the same estimate, three more random numbers drawn */
    {"DELTA_VERTEX", PT_SKIP_DELTA_VERTEX, "bench/scenes/metal-glass.scene", "metal-glass", PT_STRATEGY_MIS, 0.0f,
     SKIP_SAME_DIST, "no light sample at mirror/glass vertices"},
    /* the general path keeps the light component at vertices behind the light (the Cornell
       box's ceiling): its samples fail and end the path. The box with the glass ball made
       diffuse: the ball's caustic noise, common to both paths, swamps the ratio at low spp
       (with it: 0.97 [0.92, 1.02] quick, 0.85 [0.80, 0.92] full, 0.78 at 128 spp x 31) */
    {"FACING_AWAY", PT_SKIP_FACING_AWAY, "scenes/cornell-diffuse.scene", "cornell-diffuse", PT_STRATEGY_MIXTURE, 0.5f,
     SKIP_ESTIMATOR, "mixture drops the light of a one-sided emitter facing away"},
    {"NO_TEXTURES", PT_SKIP_NO_TEXTURES, "scenes/cornell.scene", "cornell", PT_STRATEGY_MIS, 0.0f, SKIP_EXACT,
     "albedo read directly, no texture lookup"},
    /* light samples fall below the surface on the half of each ball that faces away */
    {"ZERO_BSDF_SHADOW", PT_SKIP_ZERO_BSDF_SHADOW, "bench/scenes/balls.scene", "balls", PT_STRATEGY_MIS, 0.0f,
     SKIP_EXACT, "no shadow ray to a light below the surface"},
    /* solid-angle sampling of large rectangular lights; the general path samples them by area. The
       close panel, where it is meant to pay, and Veach's door, whose lamp is large next to the
       walls around it (elsewhere no shading point qualifies and the images are the same bit for
       bit: bench/README.md) */
    {"SOLID_ANGLE_QUADS", PT_SKIP_SOLID_ANGLE_QUADS, "bench/scenes/close-quad.scene", "close-quad", PT_STRATEGY_MIS, 0.0f,
     SKIP_ESTIMATOR, "large rectangular lights sampled in solid angle, not by area"},
    {"SOLID_ANGLE_QUADS", PT_SKIP_SOLID_ANGLE_QUADS, "bench/scenes/door.scene", "door", PT_STRATEGY_MIS, 0.0f,
     SKIP_ESTIMATOR, "the same on Veach's door"},
    /* the light tree against picking by power, on the hall of 1024 lamps */
    {"LIGHT_TREE", PT_SKIP_LIGHT_TREE, "bench/scenes/many-tris.scene", "many-tris", PT_STRATEGY_MIS, 0.0f,
     SKIP_ESTIMATOR, "a light picked by the light tree, not by power alone"},
};
#define SKIP_CASE_COUNT ((int)(sizeof skip_cases / sizeof skip_cases[0]))

/* CPU time of the process (all its threads), seconds: unlike wall time it does not count the
   time other programs on this shared machine hold the core. */
static double cpu_now(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) return ptv_now();
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* P(X <= k) for X ~ Binomial(n, 1/2). */
static double binom_half_cdf(int n, int k)
{
    double p = 0, c = 1; /* c = C(n, i) */
    int i;
    for (i = 0; i <= k && i <= n; ++i) {
        p += c;
        c = c * (double)(n - i) / (double)(i + 1);
    }
    return p * pow(0.5, n);
}

/* Distribution-free confidence interval for the median of n independent values (sorted in
   v): [v_(k), v_(n+1-k)] with the largest k such that P(Binomial(n, 1/2) <= k - 1) <= 2.5 %,
   the interval that inverts the sign test (Conover, "Practical Nonparametric Statistics", 3rd
   ed., 1999, sec. 3.2). *cover is its exact coverage 1 - 2 P(B <= k - 1). Needs n >= 6. */
static int median_interval(const double *sorted, int n, double *lo, double *hi, double *cover)
{
    int k = 0;
    while (k + 1 <= n / 2 && binom_half_cdf(n, k) <= 0.025) ++k; /* k: P(B <= k - 1) <= 0.025 */
    if (k == 0) return 0;
    *lo = sorted[k - 1];
    *hi = sorted[n - k];
    *cover = 1.0 - 2.0 * binom_half_cdf(n, k - 1);
    return 1;
}

static uint64_t splitmix64(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* The time ratio at equal error over the repetitions idx[0..n): the median paired time ratio
   times the ratio of the mean relMSEs (relMSE falls as 1/samples and time grows with them, so
   time x relMSE is the time to a fixed error, up to a constant). */
static double equal_error_ratio(const double *pr, const double *v_on, const double *v_off, const int *idx, int n)
{
    double t[SKIP_REPS_MAX], a = 0, b = 0;
    int i;
    for (i = 0; i < n; ++i) {
        t[i] = pr[idx[i]];
        a += v_on[idx[i]];
        b += v_off[idx[i]];
    }
    return median(t, n) * a / b;
}

/* For each skip: renders with every skip on (specialised) and with that skip's general path
   forced, one thread, same seed and spp, back to back in pairs whose order alternates; the
   time of a render is CPU time. Per repetition r the paired ratio t_on / t_off; the figure is
   their median with a sign-test interval. For each render its relMSE is estimated from the
   pixels' sample variance (pt_film_pixel: the variance of the pixel mean) over (r^2 + 0.01),
   r the mean of every render of that case (both paths): the estimators are unbiased, so this
   is their expected relMSE, with no reference image and no reference noise. A skip pays when
   the upper end of the 95 % interval of its deciding ratio is below 1. The spp is calibrated
   so that one render takes about a target time; skips that change the estimator render
   longer (more samples per pair): their error ratio rests on rare high-weight paths (a path
   the general path kept at weight 1 / (1 - light_weight)), which few samples miss, so their
   equal-error ratio drifts toward 1 at low spp (FACING_AWAY on the Cornell box: 0.96 at 8
   spp x 17 pairs, 0.85 at 16 x 31, 0.78 at 128 x 31). */
static int find_scene(const char *name);
static int run_skips(const config *cfg, results *R, skip_results *S)
{
    const double t_exact = cfg->quick ? 0.06 : 0.2, t_est = cfg->quick ? 0.18 : 0.5;
    const int reps_exact = cfg->quick ? 17 : 31, reps_est = cfg->quick ? 11 : 31, boot = 2000;
    const int reps_max = reps_exact > reps_est ? reps_exact : reps_est;
    const size_t npix = (size_t)BENCH_SIZE * BENCH_SIZE;
    float *var = (float *)malloc(sizeof(float) * 3u * npix * 2u * (size_t)reps_max);
    double *mean = (double *)malloc(sizeof(double) * 3u * npix);
    int c;
    (void)R;
    memset(S, 0, sizeof *S);
    if (!var || !mean) die_oom();
    S->available = 1;
    printf("skips: %d cases, %d paired repetitions of ~%.2f s each (%d of ~%.2f s for skips that change the "
           "estimator; CPU time, 1 thread)\n", SKIP_CASE_COUNT, reps_exact, t_exact, reps_est, t_est);
    for (c = 0; c < SKIP_CASE_COUNT && c < SKIP_MAX; ++c) {
        const skip_case *sk = &skip_cases[c];
        const double target = sk->kind == SKIP_ESTIMATOR ? t_est : t_exact;
        const int reps = sk->kind == SKIP_ESTIMATOR ? reps_est : reps_exact;
        skip_result *o = &S->r[S->n];
        bench_scene bs;
        loaded L;
        pt_render_desc d;
        pt_render_stats fst;
        pt_film film;
        pt_image first = {0, 0, NULL}, img = {0, 0, NULL};
        double t_on[SKIP_REPS_MAX], t_off[SKIP_REPS_MAX], pr[SKIP_REPS_MAX], v_on[SKIP_REPS_MAX],
            v_off[SKIP_REPS_MAX], eqb[4096], sorted[SKIP_REPS_MAX], bias;
        int spp = 2, r, i, b, n_mean = 0, idx[SKIP_REPS_MAX]; /* 2: a pixel's variance needs two samples */
        uint64_t rs = 0x5c1b5ULL + (uint64_t)c;
        size_t p;
        if (find_scene(sk->scene_name) >= 0 && !cfg->scene_on[find_scene(sk->scene_name)]) continue; /* --scenes */
        memset(&bs, 0, sizeof bs);
        memset(&fst, 0, sizeof fst);
        bs.name = sk->scene_name;
        bs.file = sk->scene_file;
        if (!load_scene(&bs, &L)) return 0;
        if (pt_film_init(&film, BENCH_SIZE, BENCH_SIZE) != PT_OK) die_oom();
        d = L.rd;
        d.strategy = sk->strategy;
        d.light_weight = sk->light_weight;
        d.threads = 1;
        d.seed = 1;
        memset(mean, 0, sizeof(double) * 3u * npix);
        /* calibrate: double spp (from 2) until one render takes at least target / 2 */
        for (;;) {
            double t0 = cpu_now();
            d.samples_per_pixel = spp;
            d.samples_per_pass = spp;
            pt_film_clear(&film);
            if (pt_render(L.scene, &d, &film, &fst) != PT_OK) goto fail;
            if (cpu_now() - t0 >= target / 2 || spp >= 1 << 16) break;
            spp *= 2;
        }
        for (r = 0; r < reps; ++r) {
            int half;
            d.seed = (uint64_t)(r + 1);
            for (half = 0; half < 2; ++half) {
                const int general = (r + half) % 2; /* alternate which of the two goes first */
                float *vm = var + 3u * npix * (2u * (size_t)r + (size_t)general);
                double t0;
                d.disable_skips = general ? sk->bit : 0u;
                pt_film_clear(&film);
                t0 = cpu_now();
                if (pt_render(L.scene, &d, &film, &fst) != PT_OK) goto fail;
                (general ? t_off : t_on)[r] = cpu_now() - t0;
                for (p = 0; p < npix; ++p) {
                    pt_color m, v;
                    pt_film_pixel(&film, (int)(p % BENCH_SIZE), (int)(p / BENCH_SIZE), &m, &v);
                    mean[3 * p] += m.x;
                    mean[3 * p + 1] += m.y;
                    mean[3 * p + 2] += m.z;
                    vm[3 * p] = v.x;
                    vm[3 * p + 1] = v.y;
                    vm[3 * p + 2] = v.z;
                }
                n_mean++;
                /* the first pair (same seed): how far apart the two images are */
                if (r == 0) {
                    if (pt_film_resolve(&film, half == 0 ? &first : &img) != PT_OK) goto fail;
                    if (half == 1) measure(&first, &img, &o->relmse_between, &bias);
                }
            }
            pr[r] = t_on[r] / t_off[r];
        }
        /* relMSE of each render: its variance of the pixel mean over (mean^2 + 0.01) */
        for (i = 0; i < 3 * (int)npix; ++i) mean[i] /= n_mean;
        for (r = 0; r < 2 * reps; ++r) {
            const float *vm = var + 3u * npix * (size_t)r;
            double s = 0;
            for (i = 0; i < 3 * (int)npix; ++i) s += vm[i] / (mean[i] * mean[i] + 0.01);
            (r % 2 ? v_off : v_on)[r / 2] = s / (3.0 * (double)npix);
        }
        o->name = sk->name;
        o->bit = sk->bit;
        o->scene = sk->scene_name;
        if (sk->strategy == PT_STRATEGY_MIXTURE) snprintf(o->strategy, sizeof o->strategy, "mixture %.2g", sk->light_weight);
        else snprintf(o->strategy, sizeof o->strategy, "%s", sk->strategy == PT_STRATEGY_MIS ? "MIS" : "other");
        o->what = sk->what;
        o->kind = sk->kind;
        o->reps = reps;
        o->spp = spp;
        o->t_on = median(t_on, reps);
        o->t_off = median(t_off, reps);
        for (r = 0; r < reps; ++r) sorted[r] = pr[r];
        qsort(sorted, (size_t)reps, sizeof sorted[0], cmp_double);
        o->ratio = median(pr, reps);
        if (!median_interval(sorted, reps, &o->ratio_lo, &o->ratio_hi, &o->ratio_cover)) {
            o->ratio_lo = 0;
            o->ratio_hi = INFINITY;
            o->ratio_cover = 1;
        }
        o->v_on = o->v_off = 0;
        for (r = 0; r < reps; ++r) {
            o->v_on += v_on[r] / reps;
            o->v_off += v_off[r] / reps;
            idx[r] = r;
        }
        o->eq = equal_error_ratio(pr, v_on, v_off, idx, reps);
        /* percentile bootstrap over repetitions (Efron & Tibshirani, "An Introduction to the
           Bootstrap", 1993, ch. 13), fixed seed */
        for (b = 0; b < boot; ++b) {
            for (r = 0; r < reps; ++r) idx[r] = (int)(splitmix64(&rs) % (uint64_t)reps);
            eqb[b] = equal_error_ratio(pr, v_on, v_off, idx, reps);
        }
        qsort(eqb, (size_t)boot, sizeof eqb[0], cmp_double);
        o->eq_lo = eqb[(int)(0.025 * boot)];
        o->eq_hi = eqb[(int)(0.975 * boot) - 1];
        if (sk->kind == SKIP_ESTIMATOR) {
            o->dec = o->eq;
            o->dec_lo = o->eq_lo;
            o->dec_hi = o->eq_hi;
        } else {
            o->dec = o->ratio;
            o->dec_lo = o->ratio_lo;
            o->dec_hi = o->ratio_hi;
        }
        o->pays = o->dec_hi < 1.0;
        printf("  %-17s %-15s %-11s %5d spp: CPU %.4f / %.4f s, time ratio %.3f [%.3f, %.3f], equal-error ratio %.3f "
               "[%.3f, %.3f], images differ by %.2e: %s\n", sk->name, sk->scene_name, o->strategy, spp, o->t_on,
               o->t_off, o->ratio, o->ratio_lo, o->ratio_hi, o->eq, o->eq_lo, o->eq_hi, o->relmse_between,
               o->pays ? "pays" : "gain not shown");
        fflush(stdout);
        S->n++;
        pt_image_free(&first);
        pt_image_free(&img);
        pt_film_free(&film);
        free_scene(&L);
        continue;
    fail:
        fprintf(stderr, "bench: render failed: %s\n", fst.error);
        pt_image_free(&first);
        pt_image_free(&img);
        pt_film_free(&film);
        free_scene(&L);
        free(var);
        free(mean);
        return 0;
    }
    free(var);
    free(mean);
    return 1;
}

/* adaptive.csv: the uniform MIS series, then each available adaptive run's renders (mode
   "adaptive" counts a pixel's own samples, "adaptive-neighbours" does not; end_spp: the uniform
   render it is compared with). */
static int write_adaptive_csv(const config *cfg, const adaptive_results *const *runs, int count)
{
    FILE *f;
    int k, r;
    const adaptive_results *A = runs[0];
    if (!A->available) return 1;
    f = open_out(cfg, "adaptive.csv");
    if (!f) return 0;
    fprintf(f, "mode,end_spp,threshold,spp_max,time_s,relmse,bias,samples,converged_fraction\n");
    for (k = 0; k < A->n_uniform; ++k)
        fprintf(f, "uniform,0,0,%d,%.6g,%.6g,%.6g,%.0f,0\n", A->uniform[k].spp, A->uniform[k].time, A->uniform_err[k],
                A->uniform[k].bias, A->uniform[k].samples);
    for (r = 0; r < count; ++r) {
        const adaptive_results *B = runs[r];
        if (!B->available) continue;
        for (k = 0; k < B->n_adaptive; ++k)
            fprintf(f, "%s,%d,%.4g,%d,%.6g,%.6g,%.6g,%.0f,%.4f\n", B->neighbours_only ? "adaptive-neighbours" : "adaptive",
                    B->end_spp, B->threshold[k], B->adaptive[k].spp, B->adaptive[k].time, B->adaptive_err[k],
                    B->adaptive[k].bias, B->adaptive[k].samples, B->converged[k]);
    }
    return close_out(f, "adaptive.csv");
}

static const char *skip_kind_name(skip_kind k)
{
    return k == SKIP_EXACT ? "exact" : k == SKIP_SAME_DIST ? "same-estimator" : "estimator";
}

static int write_skips_csv(const config *cfg, const skip_results *S)
{
    FILE *f;
    int k;
    if (!S->available) return 1;
    f = open_out(cfg, "skips.csv");
    if (!f) return 0;
    fprintf(f, "skip,bit,scene,strategy,kind,spp,reps,cpu_specialised_s,cpu_general_s,time_ratio,time_ratio_lo,"
               "time_ratio_hi,time_ratio_coverage,relmse_specialised,relmse_general,equal_error_ratio,equal_error_lo,"
               "equal_error_hi,deciding_ratio,deciding_lo,deciding_hi,pays,relmse_between_images\n");
    for (k = 0; k < S->n; ++k) {
        const skip_result *o = &S->r[k];
        fprintf(f, "%s,%u,%s,%s,%s,%d,%d,%.6g,%.6g,%.4f,%.4f,%.4f,%.4f,%.6g,%.6g,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d,%.6g\n",
                o->name, o->bit, o->scene, o->strategy, skip_kind_name(o->kind), o->spp, o->reps, o->t_on, o->t_off,
                o->ratio, o->ratio_lo, o->ratio_hi, o->ratio_cover, o->v_on, o->v_off, o->eq, o->eq_lo, o->eq_hi,
                o->dec, o->dec_lo, o->dec_hi, o->pays, o->relmse_between);
    }
    return close_out(f, "skips.csv");
}

/* ---- plots (gnuplot) ------------------------------------------------------------------- */

static const char *const strategy_style[STRATEGY_COUNT] = {
    "lc rgb '#d62728' pt 5", "lc rgb '#1f77b4' pt 7", "lc rgb '#ff7f0e' pt 9 dt 2", "lc rgb '#9467bd' pt 11 dt 2",
    "lc rgb '#8c564b' pt 13 dt 2", "lc rgb '#2ca02c' pt 4 lw 2", "lc rgb '#17becf' pt 6 lw 2",
    "lc rgb '#e377c2' pt 8 lw 2 dt 4", "lc rgb '#bcbd22' pt 10 lw 2 dt 4", "lc rgb '#ff9896' pt 12 lw 1 dt 5"};

/* SCENE.dat: one block per strategy (time, relMSE - floor), then the POV-Ray points. */
static int write_plot_data(const config *cfg, const results *R, const pov_results *P, const mitsuba_results *M, int i)
{
    char name[256];
    FILE *f;
    int j, k, l;
    snprintf(name, sizeof name, "%s.dat", scenes[i].name);
    f = open_out(cfg, name);
    if (!f) return 0;
    for (j = 0; j < STRATEGY_COUNT; ++j) {
        const series *s = &R->s[i][j];
        fprintf(f, "# %s: time_s relmse spp\n", strategies[j].name);
        for (k = 0, l = 0; k < s->levels; ++k)
            if (s->err[k] > 0) {
                fprintf(f, "%.6g %.6g %d\n", s->med[k].time, s->err[k], s->med[k].spp);
                ++l;
            }
        if (!l) fprintf(f, "nan nan 0\n"); /* no point (not run in quick mode): keeps the index (below) */
        fprintf(f, "\n\n");
    }
    fprintf(f, "# POV-Ray: time_s relmse level\n");
    for (l = 0, k = 0; l < POV_LEVEL_COUNT; ++l)
        if (P->available && P->r[i][l].ran && P->r[i][l].err > 0) {
            fprintf(f, "%.6g %.6g %d\n", P->r[i][l].time, P->r[i][l].err, l);
            ++k;
        }
    /* a block of only a comment is not counted by gnuplot's index: without POV-Ray points the
       Mitsuba curves would be read one block late */
    if (!k) fprintf(f, "nan nan 0\n");
    fprintf(f, "\n\n");
    for (j = 0; j < MI_SAMPLERS; ++j) { /* index STRATEGY_COUNT + 1 + j */
        const series *s = &M->s[i][j];
        fprintf(f, "# Mitsuba 3 %s: time_s relmse spp\n", mi_samplers[j]);
        for (k = 0; M->ran[i] && k < s->levels; ++k)
            if (s->err[k] > 0) fprintf(f, "%.6g %.6g %d\n", s->med[k].time, s->err[k], M->spp_used[i][j][k]);
        if (!M->ran[i]) fprintf(f, "nan nan 0\n"); /* keeps the index for gnuplot */
        fprintf(f, "\n\n");
    }
    return close_out(f, name);
}

static const char *const mitsuba_style[MI_SAMPLERS] = {"lc rgb '#000000' pt 2 dt 3 lw 2", "lc rgb '#7f7f7f' pt 1 dt 3 lw 2"};

static void plot_commands(FILE *g, const results *R, const pov_results *P, const mitsuba_results *M, int i, int small)
{
    int j, l, any_pov = 0, first = 1;
    for (l = 0; l < POV_LEVEL_COUNT; ++l)
        if (P->available && P->r[i][l].ran && P->r[i][l].err > 0) any_pov = 1;
    fprintf(g, "set title '%s (%dx%d, median of seeds)'\n", scenes[i].name, BENCH_SIZE, BENCH_SIZE);
    fprintf(g, "set logscale xy\nset format x '10^{%%L}'\nset format y '10^{%%L}'\n");
    fprintf(g, "set xlabel 'render time (s)'\nset ylabel 'relMSE'\nset grid\n");
    fprintf(g, "set key %s\n", small ? "bottom left font ',8' spacing 0.8" : "outside right");
    fprintf(g, "plot ");
    for (j = 0; j < STRATEGY_COUNT; ++j) {
        if (R->s[i][j].levels < 1) continue; /* not run (quick mode); its block in the .dat is empty */
        fprintf(g, "%s'%s.dat' index %d using 1:2 with linespoints %s title '%s'", first ? "" : ", \\\n     ",
                scenes[i].name, j, strategy_style[j], strategies[j].name);
        first = 0;
    }
    if (any_pov)
        fprintf(g, ", \\\n     '%s.dat' index %d using 1:2:(sprintf('q%%d', $3)) with labels point pt 3 ps 1.5 lc rgb 'black' "
                   "offset 0.8,0.6 font ',8' title 'POV-Ray'", scenes[i].name, STRATEGY_COUNT);
    if (M->ran[i])
        for (j = 0; j < MI_SAMPLERS; ++j)
            fprintf(g, ", \\\n     '%s.dat' index %d using 1:2 with linespoints %s title 'Mitsuba %s'", scenes[i].name,
                    STRATEGY_COUNT + 1 + j, mitsuba_style[j], mi_samplers[j]);
    fprintf(g, "\n");
}

/* One adaptive run's points for adaptive.dat: time_s relmse threshold. */
static void write_adaptive_points(FILE *f, const adaptive_results *A)
{
    int k;
    for (k = 0; k < A->n_adaptive; ++k)
        if (A->adaptive_err[k] > 0) fprintf(f, "%.6g %.6g %.3g\n", A->adaptive[k].time, A->adaptive_err[k], A->threshold[k]);
}

static int make_plots(const config *cfg, const results *R, const pov_results *P, const mitsuba_results *M,
                      const adaptive_results *A,
                      const adaptive_results *A3, char *status, size_t status_size)
{
    FILE *g;
    int i, n = 0, panels = A->available, rows;
    char cmd[4096];
    for (i = 0; i < SCENE_COUNT; ++i)
        if (R->done[i] && !write_plot_data(cfg, R, P, M, i)) return 0;
    for (i = 0; i < SCENE_COUNT; ++i) panels += R->done[i];
    rows = panels > 6 ? (panels + 2) / 3 : 2; /* three panels a row */
    if (A->available) {
        FILE *f = open_out(cfg, "adaptive.dat");
        int k;
        if (!f) return 0;
        fprintf(f, "# uniform MIS: time_s relmse\n");
        for (k = 0; k < A->n_uniform; ++k)
            if (A->uniform_err[k] > 0) fprintf(f, "%.6g %.6g\n", A->uniform[k].time, A->uniform_err[k]);
        fprintf(f, "\n\n# adaptive MIS: time_s relmse threshold\n");
        write_adaptive_points(f, A);
        fprintf(f, "\n\n# adaptive MIS, neighbours only: time_s relmse threshold\n");
        if (A3->available) write_adaptive_points(f, A3);
        else fprintf(f, "nan nan nan\n"); /* keeps index 2 for gnuplot */
        fprintf(f, "\n\n");
        if (!close_out(f, "adaptive.dat")) return 0;
    }
    g = open_out(cfg, "plots.gp");
    if (!g) return 0;
    fprintf(g, "# gnuplot script written by bench/bench.c; run in %s: gnuplot plots.gp\n", cfg->out);
    fprintf(g, "set terminal pngcairo size 900,560 font 'sans,11'\n");
    for (i = 0; i < SCENE_COUNT; ++i) {
        if (!R->done[i]) continue;
        fprintf(g, "set output '%s.png'\n", scenes[i].name);
        plot_commands(g, R, P, M, i, 0);
        fprintf(g, "reset\n");
    }
    if (A->available) {
        fprintf(g, "set output 'adaptive.png'\nset title 'cornell: adaptive vs uniform sampling (MIS)'\n"
                   "set logscale xy\nset format x '10^{%%L}'\nset format y '10^{%%L}'\nset grid\n"
                   "set xlabel 'render time (s)'\nset ylabel 'relMSE'\n"
                   "plot 'adaptive.dat' index 0 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'uniform', \\\n"
                   "     'adaptive.dat' index 1 using 1:2 with linespoints lc rgb '#e377c2' pt 6 lw 2 title 'adaptive', \\\n"
                   "     'adaptive.dat' index 2 using 1:2 with linespoints lc rgb '#7f7f7f' pt 8 lw 1 dt 2 "
                   "title 'adaptive, neighbours only'\nreset\n");
    }
    /* The headline: every scene on one page. */
    fprintf(g, "set terminal pngcairo size 1500,%d font 'sans,10'\nset output 'headline.png'\n"
               "set multiplot layout %d,3 title 'pdftrace: relMSE against render time, %dx%d, 2 cores (make bench)'\n",
            450 * rows, rows, BENCH_SIZE, BENCH_SIZE);
    for (i = 0; i < SCENE_COUNT; ++i) {
        if (!R->done[i]) continue;
        plot_commands(g, R, P, M, i, 1);
        ++n;
    }
    if (A->available && n < 3 * rows)
        fprintf(g, "set title 'cornell: adaptive vs uniform (MIS)'\n"
                   "plot 'adaptive.dat' index 0 using 1:2 with linespoints lc rgb '#2ca02c' pt 4 lw 2 title 'uniform', \\\n"
                   "     'adaptive.dat' index 1 using 1:2 with linespoints lc rgb '#e377c2' pt 6 lw 2 title 'adaptive', \\\n"
                   "     'adaptive.dat' index 2 using 1:2 with linespoints lc rgb '#7f7f7f' pt 8 lw 1 dt 2 "
                   "title 'neighbours only'\n");
    fprintf(g, "unset multiplot\n");
    if (!close_out(g, "plots.gp")) return 0;
    if (!have_program("gnuplot")) {
        snprintf(status, status_size, "SKIP plots: gnuplot is not installed (apt-get install gnuplot-nox); the data and "
                                      "%s/plots.gp are written", cfg->out);
        printf("%s\n", status);
        return 1;
    }
    snprintf(cmd, sizeof cmd, "cd '%s' && gnuplot plots.gp 2>gnuplot.log", cfg->out);
    if (system(cmd) != 0) {
        snprintf(status, status_size, "gnuplot failed: see %s/gnuplot.log", cfg->out);
        fprintf(stderr, "bench: %s\n", status);
        return 0;
    }
    snprintf(status, status_size, "plots written by gnuplot");
    return 1;
}

/* ---- summary.md ------------------------------------------------------------------------ */

/* MIS against the best single strategy (material or light; `all` = also the mixtures): the time
   MIS needs to reach that strategy's final error, over that strategy's time. */
typedef struct mis_ratio {
    int best;                  /* strategy index */
    double target, t_best, t_mis, ratio;
    int extrap;
} mis_ratio;

static mis_ratio mis_vs_best(const results *R, int i, int all)
{
    mis_ratio m;
    int j;
    double best_eff = -1;
    memset(&m, 0, sizeof m);
    m.best = -1;
    for (j = 0; j < STRATEGY_COUNT; ++j) {
        double e;
        if (strategies[j].strategy == PT_STRATEGY_MIS || (!all && j != S_MATERIAL && j != S_LIGHT)) continue;
        e = efficiency(&R->s[i][j]);
        if (e > best_eff) {
            best_eff = e;
            m.best = j;
        }
    }
    if (m.best < 0) {
        m.ratio = NAN;
        return m;
    }
    {
        const series *b = &R->s[i][m.best];
        m.target = b->err[b->levels - 1];
        m.t_best = b->med[b->levels - 1].time;
        m.t_mis = time_to_reach(&R->s[i][S_MIS], m.target, &m.extrap);
        m.ratio = m.t_mis / m.t_best;
    }
    return m;
}

static void fmt_g(char *buf, size_t n, double v)
{
    if (v != v) snprintf(buf, n, "-");
    else snprintf(buf, n, "%.3g", v);
}

/* ---- path guiding at equal time -------------------------------------------------------- */

/* A scene's guided strategies (PT_GUIDING_ON or AUTO) against its best unguided strategy, by
   efficiency at the series' last points (every series ends near the same time, the budget;
   a guided render's time includes its training). */
typedef struct guiding_cmp {
    int best_unguided;         /* strategy index; -1: none */
    int best_on;               /* the most efficient PT_GUIDING_ON strategy; -1: none */
    int autos;                 /* the PT_GUIDING_AUTO strategy; -1: none */
} guiding_cmp;

static guiding_cmp guiding_compare(const results *R, int i)
{
    guiding_cmp g;
    int j;
    g.best_unguided = g.best_on = g.autos = -1;
    for (j = 0; j < STRATEGY_COUNT; ++j) {
        const double e = efficiency(&R->s[i][j]);
        if (R->s[i][j].levels < 1) continue; /* not run (quick mode) */
        if (strategies[j].guiding == PT_GUIDING_OFF) {
            if (g.best_unguided < 0 || e > efficiency(&R->s[i][g.best_unguided])) g.best_unguided = j;
        } else if (strategies[j].guiding == PT_GUIDING_ON) {
            if (g.best_on < 0 || e > efficiency(&R->s[i][g.best_on])) g.best_on = j;
        } else if (g.autos < 0)
            g.autos = j;
    }
    return g;
}

/* The bias at a series' last point: the mean over seeds and its standard error (the seeds'
   renders are independent; the reference's own offset is common to every strategy). */
static void last_bias(const series *s, int seeds, double *mean, double *se)
{
    const int l = s->levels - 1;
    double m = 0, v = 0;
    int q;
    for (q = 0; q < seeds; ++q) m += s->seed[q][l].bias / seeds;
    for (q = 0; q < seeds; ++q) v += (s->seed[q][l].bias - m) * (s->seed[q][l].bias - m);
    *mean = m;
    *se = seeds > 1 ? sqrt(v / (seeds - 1) / seeds) : NAN;
}

/* Of a series' last point over the seeds: how many renders were guided, the median measured gain
   and the median training time of those renders. */
static int last_guided(const series *s, int seeds, double *gain, double *train)
{
    const int l = s->levels - 1;
    double g[MAX_SEEDS], t[MAX_SEEDS];
    int q, n = 0;
    for (q = 0; q < seeds; ++q) {
        g[q] = s->seed[q][l].gain;
        t[q] = s->seed[q][l].train_time;
        n += s->seed[q][l].guided;
    }
    *gain = median(g, seeds);
    *train = median(t, seeds);
    return n;
}

static void fmt_bias(char *buf, size_t n, const series *s, int seeds)
{
    double m, se;
    last_bias(s, seeds, &m, &se);
    snprintf(buf, n, "%+.2f%% ± %.2f%%%s", 100 * m, 100 * se, fabs(m) > 3 * se ? " (> 3 SE)" : "");
}

static void write_guiding_summary(FILE *f, const config *cfg, const results *R)
{
    int i, j, any = 0;
    char b[96];
    for (i = 0; i < SCENE_COUNT; ++i) any |= R->done[i];
    if (!any) return;
    fprintf(f, "## Path guiding at equal time\n\n"
               "Guided strategies (`pt_render_desc.guiding`, with pt_render's defaults: up to a quarter of the "
               "samples train the guide in iterations of 1, 2, 4, … spp, the rest are rendered with the final "
               "guide, every sample counts in the image; material share alpha 0.7):");
    for (j = 0; j < STRATEGY_COUNT; ++j)
        if (strategies[j].guiding != PT_GUIDING_OFF)
            fprintf(f, " `%s` (MIS, %s numbers, %s)", strategies[j].name,
                    strategies[j].sampler == PT_SAMPLER_SOBOL ? "Sobol" : "independent",
                    strategies[j].guiding == PT_GUIDING_ON ? "PT_GUIDING_ON"
                                                          : "PT_GUIDING_AUTO: goes on guided only if training "
                                                            "measures a gain");
    fprintf(f, ". A guide is trained per render, so each point of a guided series is one fresh render of N spp "
               "(its time = pt_render's wall clock, training included), not a progressive step; a render of fewer "
               "than 16 spp is too short to train and is not guided. Efficiency = 1/(relMSE · time) at each series' "
               "last point (every series ends near the same time, the budget), against the scene's most efficient "
               "unguided strategy; ratio > 1: guiding ahead. Bias = Σx/Σr − 1 at the last point, mean over the %d "
               "seeds ± its standard error (the reference's own offset is common to every column: the unguided one "
               "is the control).\n\n| scene | best unguided | efficiency |", cfg->seeds);
    for (j = 0; j < STRATEGY_COUNT; ++j)
        if (strategies[j].guiding != PT_GUIDING_OFF) fprintf(f, " %s |", strategies[j].name);
    fprintf(f, " **guided / unguided** | **auto / unguided** | auto: guided at its last point |"
               " bias: best unguided |");
    for (j = 0; j < STRATEGY_COUNT; ++j)
        if (strategies[j].guiding != PT_GUIDING_OFF) fprintf(f, " bias: %s |", strategies[j].name);
    fprintf(f, "\n|---|---|---|");
    for (j = 0; j < STRATEGY_COUNT; ++j)
        if (strategies[j].guiding != PT_GUIDING_OFF) fprintf(f, "---|---|");
    fprintf(f, "---|---|---|---|\n");
    for (i = 0; i < SCENE_COUNT; ++i) {
        guiding_cmp g;
        double eu, gain, train;
        if (!R->done[i]) continue;
        g = guiding_compare(R, i);
        if (g.best_unguided < 0) continue;
        eu = efficiency(&R->s[i][g.best_unguided]);
        fmt_g(b, sizeof b, eu);
        fprintf(f, "| %s | %s (%d spp) | %s |", scenes[i].name, strategies[g.best_unguided].name,
                R->s[i][g.best_unguided].med[R->s[i][g.best_unguided].levels - 1].spp, b);
        for (j = 0; j < STRATEGY_COUNT; ++j) {
            const series *s = &R->s[i][j];
            if (strategies[j].guiding == PT_GUIDING_OFF) continue;
            if (s->levels < 1) {
                fprintf(f, " not run (quick mode) |");
                continue;
            }
            fmt_g(b, sizeof b, efficiency(s));
            fprintf(f, " %s (%d spp) |", b, s->med[s->levels - 1].spp);
        }
        if (g.best_on >= 0) fprintf(f, " **%.2f** (%s) |", efficiency(&R->s[i][g.best_on]) / eu, strategies[g.best_on].name);
        else fprintf(f, " - |");
        if (g.autos >= 0) {
            const int n = last_guided(&R->s[i][g.autos], cfg->seeds, &gain, &train);
            fprintf(f, " **%.2f** | %d of %d seeds (median gain %.2f) |", efficiency(&R->s[i][g.autos]) / eu, n,
                    cfg->seeds, gain);
        } else
            fprintf(f, " - | - |");
        fmt_bias(b, sizeof b, &R->s[i][g.best_unguided], cfg->seeds);
        fprintf(f, " %s |", b);
        for (j = 0; j < STRATEGY_COUNT; ++j)
            if (strategies[j].guiding != PT_GUIDING_OFF) {
                if (R->s[i][j].levels < 1) snprintf(b, sizeof b, "-");
                else fmt_bias(b, sizeof b, &R->s[i][j], cfg->seeds);
                fprintf(f, " %s |", b);
            }
        fprintf(f, "\n");
    }
    fprintf(f, "\nPer render (series-seeds.csv, guiding.csv): whether it was guided, training's measured gain "
               "(pt_render_stats.guiding_gain) and its time.\n\n");
}

/* guiding.csv: one row per scene and guided strategy (the table "Path guiding at equal time"). */
static int write_guiding_csv(const config *cfg, const results *R)
{
    FILE *f = open_out(cfg, "guiding.csv");
    int i, j;
    if (!f) return 0;
    fprintf(f, "scene,strategy,guiding,last_spp,time_s,relmse,efficiency,best_unguided,best_unguided_efficiency,"
               "efficiency_ratio,guided_seeds,seeds,median_gain,median_training_s,bias_mean,bias_se,"
               "best_unguided_bias_mean,best_unguided_bias_se,nonfinite\n");
    for (i = 0; i < SCENE_COUNT; ++i) {
        guiding_cmp g;
        if (!R->done[i]) continue;
        g = guiding_compare(R, i);
        for (j = 0; g.best_unguided >= 0 && j < STRATEGY_COUNT; ++j) {
            const series *s = &R->s[i][j], *u = &R->s[i][g.best_unguided];
            const int l = s->levels - 1;
            double gain, train, bm, bse, um, use;
            int n;
            if (strategies[j].guiding == PT_GUIDING_OFF || s->levels < 1) continue;
            n = last_guided(s, cfg->seeds, &gain, &train);
            last_bias(s, cfg->seeds, &bm, &bse);
            last_bias(u, cfg->seeds, &um, &use);
            fprintf(f, "%s,%s,%s,%d,%.6g,%.6g,%.6g,%s,%.6g,%.6g,%d,%d,%.4g,%.4g,%.6g,%.6g,%.6g,%.6g,%llu\n",
                    scenes[i].name, strategies[j].name, strategies[j].guiding == PT_GUIDING_ON ? "on" : "auto",
                    s->med[l].spp, s->med[l].time, s->err[l], efficiency(s), strategies[g.best_unguided].name,
                    efficiency(u), efficiency(s) / efficiency(u), n, cfg->seeds, gain, train, bm, bse, um, use,
                    (unsigned long long)s->nonfinite);
        }
    }
    return close_out(f, "guiding.csv");
}

static const char *pass_fail(int ok) { return ok ? "**PASS**" : "**FAIL**"; }

/* One adaptive run's renders as a Markdown table (threshold, time, relMSE, bias, pixels stopped). */
static void write_adaptive_table(FILE *f, const adaptive_results *A)
{
    int k;
    fprintf(f, "| threshold | time (s) | relMSE | bias | pixels stopped early |\n|---|---|---|---|---|\n");
    for (k = 0; k < A->n_adaptive; ++k)
        fprintf(f, "| %.3g | %.3g | %.3g | %+.2f%% | %.1f%% |\n", A->threshold[k], A->adaptive[k].time, A->adaptive_err[k],
                100 * A->adaptive[k].bias, 100 * A->converged[k]);
    fprintf(f, "\n");
}

/* The adaptive render whose error came nearest the uniform target (log distance), or -1. */
static int nearest_threshold(const adaptive_results *A)
{
    int k, best = -1;
    for (k = 0; k < A->n_adaptive; ++k)
        if (A->adaptive_err[k] > 0 && (best < 0 || fabs(log(A->adaptive_err[k] / A->target_err)) <
                                                       fabs(log(A->adaptive_err[best] / A->target_err))))
            best = k;
    return best;
}

/* The adaptive image mean against the uniform one at the compared spp (both measured against the
   reference: (1 + adaptive bias) / (1 + uniform bias) - 1), at the threshold nearest the target;
   NaN when there is none. */
static double adaptive_bias_vs_uniform(const adaptive_results *A)
{
    int k = nearest_threshold(A), u;
    for (u = 0; u < A->n_uniform && A->uniform[u].spp != A->end_spp; ++u) {}
    if (k < 0 || u >= A->n_uniform) return 0.0 * HUGE_VAL;
    return (1.0 + A->adaptive[k].bias) / (1.0 + A->uniform[u].bias) - 1.0;
}

/* summary.md: Mitsuba 3 against pdftrace per scene, and the headline. */
static void write_mitsuba_summary(FILE *f, const config *cfg, const results *R, const mitsuba_results *M,
                                  const headline_results *H)
{
    int i;
    fprintf(f, "## Mitsuba 3 on the same axes\n\n");
    if (!M->available)
        fprintf(f, "SKIP: %s\n\n", M->skip_reason);
    else {
        fprintf(f, "Mitsuba 3 (`llvm_ad_rgb`, every core) renders each scene's export (`pt_scenefile_export_mitsuba`, "
                   "in `%s/mitsuba/`) with its `independent` and `multijitter` samplers at 1, 2, 4, … spp, one render "
                   "per point (pdftrace's points are cumulative progressive steps), render time only (after a warm-up "
                   "render of each configuration; bench/mitsuba_series.py), median of %d seeds, the same reference and "
                   "relMSE.\n\n"
                   "### pdftrace's best strategy / Mitsuba's best sampler: efficiency at equal time\n\n"
                   "Best = highest efficiency at the series' last point; both curves read off at the same time t (the "
                   "earlier of the two last points). Ratio > 1: pdftrace reaches a lower error in the same time.\n\n"
                   "| scene | pdftrace best | Mitsuba best | t (s) | pdftrace relMSE at t | Mitsuba relMSE at t | "
                   "pdftrace efficiency | Mitsuba efficiency | **ratio** |\n|---|---|---|---|---|---|---|---|---|\n",
                cfg->out, cfg->seeds);
        for (i = 0; i < SCENE_COUNT; ++i) {
            versus v;
            if (!R->done[i]) continue;
            if (!M->ran[i]) {
                fprintf(f, "| %s | SKIP: %s |||||||\n", scenes[i].name, M->scene_skip[i]);
                continue;
            }
            v = versus_mitsuba(R, M, i);
            fprintf(f, "| %s | %s | %s | %.3g | %.3g | %.3g | %.3g | %.3g | **%.2f** |\n", scenes[i].name,
                    strategies[v.pt_best].name, mi_samplers[v.mi_best], v.t, v.pt_err, v.mi_err, 1.0 / (v.pt_err * v.t),
                    1.0 / (v.mi_err * v.t), v.ratio);
        }
        if (H->available)
            fprintf(f, "| **cornell %dx%d** (headline: pdftrace at the scene's settings) | mis (%d spp) | %s | %.3g | "
                       "%.4g | %.4g | %.3g | %.3g | **%.2f** |\n", H->width, H->height, H->spp, mi_samplers[H->best],
                    H->pt_time, H->pt_err, H->mi_err[H->best], 1.0 / (H->pt_err * H->pt_time),
                    1.0 / (H->mi_err[H->best] * H->pt_time), H->mi_err[H->best] / H->pt_err);
        fprintf(f, "\n");
    }
    fprintf(f, "## Headline: the RTRL Cornell box as the user renders it, against Mitsuba 3\n\n");
    if (!H->available)
        fprintf(f, "SKIP: %s\n\n", H->skip_reason);
    else
        write_headline_table(f, H);
}

static int write_summary(const config *cfg, const results *R, const pov_results *P, const mitsuba_results *M,
                         const headline_results *H, const adaptive_results *A,
                         const adaptive_results *A2, const adaptive_results *A3, const adaptive_results *A4,
                         const skip_results *S, const tput_results *T, const char *plot_status, double total_seconds)
{
    FILE *f = open_out(cfg, "summary.md"), *h;
    int i, j, l, k, c, in_range = 0, n_series = 0;
    time_t now = time(NULL);
    char date[64], b1[64];
    struct utsname un;
    if (!f) return 0;
    strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", gmtime(&now));
    if (uname(&un) != 0) strcpy(un.machine, "?");
    fprintf(f, "# pdftrace benchmark: error against time\n\n");
    fprintf(f, "Written by `build/bench run%s` (bench/bench.c) on %s, %s %s, %ld cores online; %s mode, %.2f s of render "
               "time per series, median of %d seeds, %dx%d images, whole run %.0f s. Remake: `make bench` (full) or "
               "`make bench-quick`.\n\n",
            cfg->quick ? " --quick" : "", date, un.sysname, un.machine, sysconf(_SC_NPROCESSORS_ONLN),
            cfg->quick ? "quick" : "full", cfg->budget, cfg->seeds, BENCH_SIZE, BENCH_SIZE, total_seconds);
    fprintf(f, "**Metric.** relMSE = mean over pixels and channels of (x − r)² / (r² + 0.01), x the render, r the "
               "stored reference (bench/ref, MIS at many samples), **minus the reference's own noise floor** "
               "(mean var(r)/(r² + 0.01), in bench/ref/NAME.txt); a series stops when the raw relMSE comes within "
               "%.0f× that floor. Bias = Σx/Σr − 1 over all pixels and channels. Time = wall-clock render time "
               "(cumulative over the progressive steps 1, 2, 4, … spp; scene build excluded), 2 threads. "
               "Efficiency = 1/(relMSE · time) at a series' last point. Every figure is the median over seeds, except the "
               "slope: it is fitted to the mean relMSE over seeds (the estimate of E[relMSE], which independent "
               "sampling makes fall as 1/N; the median of a heavy-tailed error lies below it at low sample counts, so "
               "its slope, shown beside, is shallower until rare hits are common in every seed).\n\n",
            FLOOR_STOP);

    /* acceptance */
    fprintf(f, "## Acceptance\n\n| line | figure (this run) | result |\n|---|---|---|\n");
    for (i = 0; i < SCENE_COUNT; ++i) {
        mis_ratio m;
        if (!R->done[i] || strncmp(scenes[i].name, "tiny-light", 10) != 0) continue;
        m = mis_vs_best(R, i, 0);
        if (m.best < 0) continue;
        fprintf(f, "| %s: MIS reaches the best single strategy's final error in at most half its time | best single = %s "
                   "(relMSE %.3g in %.3g s); MIS reaches it in %.3g s%s: **ratio %.2f** | %s |\n",
                scenes[i].name, strategies[m.best].name, m.target, m.t_best, m.t_mis,
                m.extrap > 0 ? " (extrapolated)" : m.extrap < 0 ? " (at its first point already)" : "", m.ratio,
                !strcmp(scenes[i].name, "tiny-light") ? pass_fail(m.ratio <= 0.5) : "control (not an acceptance line)");
    }
    write_tput_acceptance(f, T);
    for (i = 0; i < SCENE_COUNT; ++i) { /* Veach's scene: MIS against each single strategy (issue 21) */
        double em, el, ex;
        if (!R->done[i] || strcmp(scenes[i].name, "veach-mis") != 0) continue;
        ex = efficiency(&R->s[i][S_MIS]);
        em = efficiency(&R->s[i][S_MATERIAL]);
        el = efficiency(&R->s[i][S_LIGHT]);
        fprintf(f, "| %s: MIS efficiency ≥ 1.5× each single strategy's at equal time | MIS %.3g, material %.3g, light %.3g: "
                   "**%.2f× material, %.2f× light** | %s |\n",
                scenes[i].name, ex, em, el, ex / em, ex / el, pass_fail(ex >= 1.5 * em && ex >= 1.5 * el));
    }
    for (i = 0; i < SCENE_COUNT; ++i)
        if (R->done[i])
            for (j = 0; j < STRATEGY_COUNT; ++j) {
                const series *s = &R->s[i][j];
                /* QMC converges faster; a guided render's guide improves with its samples */
                if (strategies[j].sampler != PT_SAMPLER_INDEPENDENT || strategies[j].guiding != PT_GUIDING_OFF ||
                    scenes[i].rare_paths)
                    continue;
                if (s->slope == s->slope) {
                    ++n_series;
                    if (fabs(s->slope + 1.0) <= 0.1) ++in_range;
                }
            }
    {
        int first = 1;
        fprintf(f, "| slope of log relMSE vs log time, independent sampling (unguided): −1 ± 0.1 | %d of %d fitted series (scenes × "
                   "strategies, ≥ 3 points with ≥ %d spp and cumulative samples/s ≥ %.1f× the last point's; log of the "
                   "mean relMSE over seeds, which estimates E[relMSE]) within ±0.1", in_range, n_series, FIT_MIN_SPP,
                FIT_MIN_RATE);
        for (i = 0; i < SCENE_COUNT; ++i)
            if (R->done[i] && !scenes[i].rare_paths)
                for (j = 0; j < STRATEGY_COUNT; ++j) {
                    const series *s = &R->s[i][j];
                    if (strategies[j].sampler != PT_SAMPLER_INDEPENDENT || strategies[j].guiding != PT_GUIDING_OFF) continue;
                    if (s->slope == s->slope && !(fabs(s->slope + 1.0) <= 0.1)) {
                        fprintf(f, "%s%s %s %.2f", first ? "; outside: " : ", ", scenes[i].name, strategies[j].name, s->slope);
                        first = 0;
                    }
                }
        if (R->done[0]) {
            fmt_g(b1, sizeof b1, R->s[0][S_MIS].slope);
            fprintf(f, "; cornell MIS %s", b1);
        }
        first = 1;
        for (i = 0; i < SCENE_COUNT; ++i)
            if (R->done[i] && scenes[i].rare_paths) {
                fmt_g(b1, sizeof b1, R->s[i][S_MIS].slope);
                fprintf(f, "%s%s (MIS %s)", first ? ". Left out, some strategy's error dominated by rare paths (the "
                                                    "guiding scenes; veach-mis's light strategy on its smoothest plate), "
                                                    "so 5 seeds' mean relMSE is too noisy for ±0.1; slopes in their "
                                                    "tables: " : ", ", scenes[i].name, b1);
                first = 0;
            }
        fprintf(f, " | %s |\n", pass_fail(in_range == n_series && n_series > 0));
    }
    if (A->available) {
        fprintf(f, "| adaptive reaches the uniform render's error in ≤ 0.7× the time (cornell) | at the series' end, "
                   "%d spp: uniform MIS relMSE %.3g in %.3g s (timed beside; the series: %.3g s); adaptive reaches it "
                   "in %.3g s%s: **ratio %.2f** (%.2f against the series' time; %.2f in samples)",
                A->end_spp, A->target_err, A->uniform_time, A->series_time, A->adaptive_time,
                A->ratio_extrap ? " (extrapolated)" : "", A->ratio, A->ratio_series, A->ratio_samples);
        if (A2->available)
            fprintf(f, ". At %d spp (the Cornell scene file's own count): relMSE %.3g in %.3g s; adaptive %.3g s%s: "
                       "**ratio %.2f** (%.2f in samples)", A2->end_spp, A2->target_err, A2->uniform_time,
                    A2->adaptive_time, A2->ratio_extrap ? " (extrapolated)" : "", A2->ratio, A2->ratio_samples);
        fprintf(f, ". The adaptive image mean against the uniform one (a pixel's own samples count: stopping "
                   "bias, section 8; threshold nearest the target): %+.2f%% at %d spp",
                100 * adaptive_bias_vs_uniform(A), A->end_spp);
        if (A2->available) fprintf(f, ", %+.2f%% at %d spp", 100 * adaptive_bias_vs_uniform(A2), A2->end_spp);
        if (A3->available || A4->available) {
            fprintf(f, ". Control, `adaptive_neighbours_only` (a pixel planned from its neighbours only: smaller "
                       "bias, more samples):");
            if (A3->available)
                fprintf(f, " %d spp ratio %.2f (%.2f in samples; mean %+.2f%%)", A3->end_spp, A3->ratio,
                        A3->ratio_samples, 100 * adaptive_bias_vs_uniform(A3));
            if (A4->available)
                fprintf(f, "%s %d spp ratio %.2f (%.2f in samples; mean %+.2f%%)", A3->available ? ";" : "", A4->end_spp,
                        A4->ratio, A4->ratio_samples, 100 * adaptive_bias_vs_uniform(A4));
        }
        fprintf(f, " | %s (every end shown must be ≤ 0.7; seams: see the images) |\n",
                pass_fail(A->ratio <= 0.7 && (!A2->available || A2->ratio <= 0.7)));
    } else
        fprintf(f, "| adaptive sampling | SKIP: %s | - |\n", A->skip_reason);
    if (S->available) {
        int all = 1;
        fprintf(f, "| each scene-feature skip pays (95 %% interval of its ratio below 1; time ratio for exact and "
                   "same-estimator skips, time ratio at equal error for the others) | ");
        for (k = 0; k < S->n; ++k) {
            const skip_result *o = &S->r[k];
            fprintf(f, "%s%s %s %.3f [%.3f, %.3f]: %s", k ? "; " : "", o->name,
                    o->kind == SKIP_ESTIMATOR ? "equal-error ratio" : "time ratio", o->dec, o->dec_lo, o->dec_hi,
                    o->pays ? "pays" : "gain not shown");
            if (!o->pays) all = 0;
        }
        fprintf(f, " | %s |\n", pass_fail(all));
    } else
        fprintf(f, "| scene-feature skips | SKIP: %s | - |\n", S->skip_reason);
    if (P->available) {
        int all = 1, any = 0;
        const int ac = P->accept_config;
        fprintf(f, "| pdftrace (%s; median of %d seeds) below POV-Ray's error at equal time on every scene where POV-Ray "
                   "is numeric | ", pov_pt_configs[ac], cfg->seeds);
        for (i = 0; i < SCENE_COUNT; ++i) {
            double worst = 0;
            int n = 0;
            if (!R->done[i] || !scenes[i].pov_numeric) continue;
            for (l = 0; l < POV_LEVEL_COUNT; ++l)
                if (P->r[i][l].ran) {
                    double q = P->r[i][l].pt_err[ac] / P->r[i][l].err;
                    if (!(P->r[i][l].err > 0)) q = INFINITY;
                    if (q > worst || q != q) worst = q;
                    ++n;
                }
            if (!n) continue;
            fprintf(f, "%s%s: worst pdftrace/POV-Ray error ratio %.3g over %d levels", any ? "; " : "", scenes[i].name, worst, n);
            any = 1;
            if (!(worst < 1)) all = 0;
        }
        fprintf(f, " | %s |\n", any ? pass_fail(all) : "-");
    } else
        fprintf(f, "| POV-Ray | SKIP: %s | - |\n", P->skip_reason);
    fprintf(f, "\n![relMSE against time](headline.png)\n\n");

    /* efficiency table */
    fprintf(f, "## Efficiency 1/(relMSE · time) at the last point (higher is better; best per scene in bold)\n\n| scene |");
    for (j = 0; j < STRATEGY_COUNT; ++j) fprintf(f, " %s |", strategies[j].name);
    for (j = 0; j < MI_SAMPLERS; ++j) fprintf(f, " Mitsuba %s |", mi_samplers[j]);
    fprintf(f, " MIS time ratio* |\n|---|");
    for (j = 0; j <= STRATEGY_COUNT + MI_SAMPLERS; ++j) fprintf(f, "---|");
    fprintf(f, "\n");
    for (i = 0; i < SCENE_COUNT; ++i) {
        double best = -1;
        mis_ratio m;
        if (!R->done[i]) continue;
        for (j = 0; j < STRATEGY_COUNT; ++j)
            if (efficiency(&R->s[i][j]) > best) best = efficiency(&R->s[i][j]);
        for (j = 0; M->ran[i] && j < MI_SAMPLERS; ++j)
            if (efficiency(&M->s[i][j]) > best) best = efficiency(&M->s[i][j]);
        fprintf(f, "| %s |", scenes[i].name);
        for (j = 0; j < STRATEGY_COUNT + MI_SAMPLERS; ++j) {
            double e = j < STRATEGY_COUNT ? efficiency(&R->s[i][j])
                       : M->ran[i]        ? efficiency(&M->s[i][j - STRATEGY_COUNT]) : NAN;
            fmt_g(b1, sizeof b1, e);
            fprintf(f, e == best ? " **%s** |" : " %s |", b1);
        }
        m = mis_vs_best(R, i, 0);
        fprintf(f, " %.2f (vs %s) |\n", m.ratio, m.best >= 0 ? strategies[m.best].name : "-");
    }
    fprintf(f, "\n\\* time MIS needs to reach the final error of the best single strategy (material or light, by "
               "efficiency), divided by that strategy's time.\n\n");
    write_mitsuba_summary(f, cfg, R, M, H);
    write_tput_summary(f, T);
    /* the Sobol sampler against independent sampling, both MIS */
    fprintf(f, "## Sobol sampler (mis-sobol) against independent sampling (mis)\n\n"
               "relMSE of MIS with PT_SAMPLER_SOBOL divided by MIS with independent sampling (< 1: Sobol lower), "
               "medians over seeds: at equal spp (the last spp both series reached) and at equal time (mis-sobol's "
               "curve interpolated log-log at mis's last time; extrapolated with slope −1 beyond its ends). "
               "Both with pdftrace's defaults, so a mis-sobol camera sample continues as 3 paths from its first "
               "diffuse vertex (pt_render_desc.indirect_paths: 3 with Sobol, 1 with independent numbers): the "
               "equal-spp ratio is per camera sample, not per unit of work; equal time is the fair comparison.\n\n"
               "| scene | spp | relMSE ratio at equal spp | time (s) | relMSE ratio at equal time |\n|---|---|---|---|---|\n");
    for (i = 0; i < SCENE_COUNT; ++i) {
        const series *a = &R->s[i][S_MIS], *b = &R->s[i][S_MIS_SOBOL];
        int n, ex = 0;
        double te, eb;
        if (!R->done[i] || a->levels <= 0 || b->levels <= 0) continue;
        n = a->levels < b->levels ? a->levels : b->levels;
        te = a->med[a->levels - 1].time;
        eb = err_at_time(b, te, &ex);
        fprintf(f, "| %s | %d | %.3g | %.3g | %.3g%s |\n", scenes[i].name, a->med[n - 1].spp,
                b->err[n - 1] / a->err[n - 1], te, eb / a->err[a->levels - 1], ex ? " (extrapolated)" : "");
    }
    fprintf(f, "\n");
    write_guiding_summary(f, cfg, R);
    /* the same table for the README */
    h = open_out(cfg, "headline.md");
    if (h) {
        fprintf(h, "| scene | material | light | mixture 0.5 | MIS | MIS time to the best single strategy's error | "
                   "Mitsuba 3 best | pdftrace best / Mitsuba best at equal time |\n|---|---|---|---|---|---|---|---|\n");
        for (i = 0; i < SCENE_COUNT; ++i) {
            mis_ratio m;
            if (!R->done[i]) continue;
            m = mis_vs_best(R, i, 0);
            fprintf(h, "| %s | %.3g | %.3g | %.3g | %.3g | %.2f× (vs %s) |", scenes[i].name, efficiency(&R->s[i][0]),
                    efficiency(&R->s[i][1]), efficiency(&R->s[i][3]), efficiency(&R->s[i][S_MIS]), m.ratio,
                    m.best >= 0 ? strategies[m.best].name : "-");
            if (M->ran[i]) {
                const versus v = versus_mitsuba(R, M, i);
                fprintf(h, " %.3g (%s) | %.2f× (%s) |\n", 1.0 / (v.mi_err * v.t), mi_samplers[v.mi_best], v.ratio,
                        strategies[v.pt_best].name);
            } else
                fprintf(h, " - | - |\n");
        }
        if (H->available) {
            fprintf(h, "\n");
            write_headline_table(h, H);
        }
        close_out(h, "headline.md");
    }

    /* per scene */
    fprintf(f, "## Scenes\n\n");
    for (i = 0; i < SCENE_COUNT; ++i) {
        mis_ratio m, ma;
        if (!R->done[i]) continue;
        fprintf(f, "### %s\n\n%s (`%s`). Reference: %d spp MIS, noise floor %.3g. POV-Ray: %s.\n\n![%s](%s.png)\n\n",
                scenes[i].name, scenes[i].about, scenes[i].file, R->L[i].ref_spp, R->L[i].floor, scenes[i].pov_about,
                scenes[i].name, scenes[i].name);
        fprintf(f, "| strategy | last spp | time (s) | relMSE | bias | samples/s | rays/s | slope [95 %%] | slope (median) | efficiency |\n"
                   "|---|---|---|---|---|---|---|---|---|---|\n");
        for (j = 0; j < STRATEGY_COUNT; ++j) {
            const series *s = &R->s[i][j];
            const point *p = &s->med[s->levels - 1];
            char slope[96], slope_med[32];
            if (s->levels < 1) { /* not run (quick mode) */
                fprintf(f, "| %s | not run (quick mode) |||||||||\n", strategies[j].name);
                continue;
            }
            if (s->slope == s->slope)
                snprintf(slope, sizeof slope, "%.3f [%.3f, %.3f]", s->slope, s->slope_lo, s->slope_hi);
            else
                snprintf(slope, sizeof slope, "- (%d points with >= %d spp)", s->fit_points, FIT_MIN_SPP);
            if (s->slope_med == s->slope_med) snprintf(slope_med, sizeof slope_med, "%.3f", s->slope_med);
            else snprintf(slope_med, sizeof slope_med, "-");
            fprintf(f, "| %s | %d | %.3g | %.3g | %+.2f%% | %.3g M | %.3g M | %s | %s | %.3g |\n", strategies[j].name,
                    p->spp, p->time, s->err[s->levels - 1], 100 * p->bias, p->samples / p->time / 1e6,
                    p->rays / p->time / 1e6, slope, slope_med, efficiency(s));
        }
        for (j = 0; M->ran[i] && j < MI_SAMPLERS; ++j) {
            const series *s = &M->s[i][j];
            const point *p = &s->med[s->levels - 1];
            char slope[96], slope_med[32];
            fmt_g(slope_med, sizeof slope_med, s->slope_med);
            if (s->slope == s->slope) snprintf(slope, sizeof slope, "%.3f [%.3f, %.3f]", s->slope, s->slope_lo, s->slope_hi);
            else snprintf(slope, sizeof slope, "- (%d points with >= %d spp)", s->fit_points, FIT_MIN_SPP);
            fprintf(f, "| Mitsuba 3 %s (one render per point) | %d | %.3g | %.3g | %+.2f%% | %.3g M | - | %s | %s | %.3g |\n",
                    mi_samplers[j], M->spp_used[i][j][s->levels - 1], p->time, s->err[s->levels - 1], 100 * p->bias,
                    p->samples / p->time / 1e6, slope, slope_med, efficiency(s));
        }
        if (!M->ran[i] && M->available) fprintf(f, "| Mitsuba 3 | SKIP: %s |||||||||\n", M->scene_skip[i]);
        m = mis_vs_best(R, i, 0);
        ma = mis_vs_best(R, i, 1);
        fprintf(f, "\nMIS reaches the final error of %s (the best single strategy) in %.2f× its time%s; of %s (the best "
                   "non-MIS strategy, mixtures included) in %.2f× its time%s.",
                m.best >= 0 ? strategies[m.best].name : "-", m.ratio, m.extrap > 0 ? " (extrapolated)" : "",
                ma.best >= 0 ? strategies[ma.best].name : "-", ma.ratio, ma.extrap > 0 ? " (extrapolated)" : "");
        for (j = 0; j < STRATEGY_COUNT; ++j)
            if (R->s[i][j].stopped_by_floor) fprintf(f, " %s stopped at the reference's noise floor.", strategies[j].name);
        for (j = 0; j < STRATEGY_COUNT; ++j)
            if (R->s[i][j].nonfinite) fprintf(f, " %s: %llu NaN/Inf samples caught.", strategies[j].name,
                                              (unsigned long long)R->s[i][j].nonfinite);
        for (j = 0; j < STRATEGY_COUNT; ++j)
            if (strategies[j].guiding != PT_GUIDING_OFF && R->s[i][j].levels > 0) {
                const series *s = &R->s[i][j];
                double gain, train;
                const int n = last_guided(s, cfg->seeds, &gain, &train);
                fprintf(f, " %s (one render per point): at %d spp guided in %d of %d seeds, training %.3g s of %.3g s "
                           "(medians), measured gain %.2f.", strategies[j].name, s->med[s->levels - 1].spp, n,
                        cfg->seeds, train, s->med[s->levels - 1].time, gain);
            }
        fprintf(f, "\n\n");
        if (P->available) {
            int any = 0;
            for (l = 0; l < POV_LEVEL_COUNT; ++l) any |= P->r[i][l].ran;
            if (any) {
                fprintf(f, "pdftrace at each POV-Ray level's time: %s. Ratio < 1: pdftrace's error is lower.\n\n"
                           "| POV-Ray quality | time (s) | relMSE | bias |",
                        scenes[i].pov_numeric ? "the median over seeds of series rendered as long as the slowest level"
                                              : "the median series of the runs (extrapolated with slope -1 past their end)");
                for (c = 0; c < POV_PT_CONFIGS; ++c)
                    if (P->config_strategy[c] >= 0) fprintf(f, " pdftrace %s relMSE | pdftrace %s / POV-Ray |", pov_pt_configs[c],
                                                            pov_pt_configs[c]);
                fprintf(f, "\n|---|---|---|---|");
                for (c = 0; c < POV_PT_CONFIGS; ++c)
                    if (P->config_strategy[c] >= 0) fprintf(f, "---|---|");
                fprintf(f, "\n");
                for (l = 0; l < POV_LEVEL_COUNT; ++l) {
                    const pov_result *pr = &P->r[i][l];
                    if (!pr->ran) continue;
                    fprintf(f, "| q%d: %s | %.3g | %.3g | %+.2f%% |", l, pov_levels[l].name, pr->time, pr->err, 100 * pr->bias);
                    for (c = 0; c < POV_PT_CONFIGS; ++c)
                        if (P->config_strategy[c] >= 0)
                            fprintf(f, " %.3g%s | %s%.3g%s |", pr->pt_err[c], pr->pt_extrap[c] ? " (extrapolated)" : "",
                                    c == P->accept_config ? "**" : "", pr->pt_err[c] / pr->err,
                                    c == P->accept_config ? "**" : "");
                    fprintf(f, "\n");
                }
                fprintf(f, "\n");
            }
        }
    }

    /* adaptive */
    fprintf(f, "## Adaptive sampling (cornell, MIS)\n\n");
    if (!A->available)
        fprintf(f, "SKIP: %s\n\n", A->skip_reason);
    else {
        fprintf(f, "![adaptive](adaptive.png)\n\n| mode | threshold | spp (max) | time (s) | relMSE | bias | pixels stopped early |\n"
                   "|---|---|---|---|---|---|---|\n");
        for (k = 0; k < A->n_uniform; ++k)
            fprintf(f, "| uniform | - | %d | %.3g | %.3g | %+.2f%% | - |\n", A->uniform[k].spp, A->uniform[k].time,
                    A->uniform_err[k], 100 * A->uniform[k].bias);
        for (k = 0; k < A->n_adaptive; ++k)
            fprintf(f, "| adaptive | %.3g | %d | %.3g | %.3g | %+.2f%% | %.1f%% |\n", A->threshold[k], A->adaptive[k].spp,
                    A->adaptive[k].time, A->adaptive_err[k], 100 * A->adaptive[k].bias, 100 * A->converged[k]);
        fprintf(f, "\nUniform reaches relMSE %.3g in %.3g s (a uniform render of the series' last spp, timed beside the "
                   "adaptive renders, seed-major; the series took %.3g s); adaptive in %.3g s: ratio %.2f%s (%.2f against "
                   "the series' time; %.2f in samples). Images for the seam check: `%s`, `%s`, samples per pixel `%s`.\n\n",
                A->target_err, A->uniform_time, A->series_time, A->adaptive_time, A->ratio,
                A->ratio_extrap ? " (extrapolated)" : "", A->ratio_series, A->ratio_samples, A->image_uniform,
                A->image_adaptive, A->image_map);
        if (A2->available) {
            fprintf(f, "The same at the uniform series' %d-spp point (the Cornell scene file's own sample count): "
                       "uniform relMSE %.3g in %.3g s (timed beside); adaptive in %.3g s%s: ratio %.2f (%.2f in samples).\n\n",
                    A2->end_spp, A2->target_err, A2->uniform_time, A2->adaptive_time,
                    A2->ratio_extrap ? " (extrapolated)" : "", A2->ratio, A2->ratio_samples);
            write_adaptive_table(f, A2);
        } else
            fprintf(f, "At the Cornell scene's own 128 spp: SKIP (%s).\n\n", A2->skip_reason);
        {   /* the control: a pixel's own samples left out of its noise estimate */
            const adaptive_results *C[2];
            int r;
            C[0] = A3;
            C[1] = A4;
            fprintf(f, "Control: the same with `adaptive_neighbours_only` = 1 (a pixel's noise estimated from the 24 "
                       "other pixels of its 5x5 neighbourhood only: its stopping does not depend on its own samples "
                       "directly, so the bias is smaller, but a pixel that drew a firefly does not sample on to dilute "
                       "it).\n\n");
            for (r = 0; r < 2; ++r) {
                if (!C[r]->available) {
                    fprintf(f, "Neighbours only, %s: SKIP (%s).\n\n", r ? "128 spp" : "the series' end", C[r]->skip_reason);
                    continue;
                }
                fprintf(f, "Neighbours only, %d spp: uniform relMSE %.3g in %.3g s (timed beside); adaptive in %.3g s%s: "
                           "ratio %.2f (%.2f in samples).\n\n", C[r]->end_spp, C[r]->target_err, C[r]->uniform_time,
                        C[r]->adaptive_time, C[r]->ratio_extrap ? " (extrapolated)" : "", C[r]->ratio, C[r]->ratio_samples);
                write_adaptive_table(f, C[r]);
            }
        }
    }

    /* skips */
    fprintf(f, "## Scene-feature skips\n\n");
    if (!S->available)
        fprintf(f, "SKIP: %s\n\n", S->skip_reason);
    else {
        fprintf(f, "Each skip on the scene and strategy where it does its work: a render with every skip on "
                   "(specialised) against the same render with that skip's general path forced "
                   "(pt_render_desc.disable_skips), one thread, same seed and spp, back to back in pairs whose order "
                   "alternates; time = CPU time of the render (not counting time other programs hold the core). "
                   "**Time ratio**: median of the paired ratios t_specialised / t_general, with its distribution-free "
                   "interval (sign test: binomial order statistics, coverage ≥ 95 %%, exact value in skips.csv). "
                   "**Equal-error ratio**: (t_spec · relMSE_spec) / (t_gen · relMSE_gen), the ratio of the times the two "
                   "need to reach the same error (relMSE falls as 1/time); relMSE of a render = mean over pixels and "
                   "channels of its pixel-mean variance (the film's sample variance) / (r² + 0.01), r the mean of "
                   "every render of the case, averaged over repetitions; 95 %% percentile-bootstrap interval over "
                   "repetitions; these cases render longer (more samples), since their error ratio rests on rare "
                   "high-weight paths that few samples miss. **Which ratio decides**: *exact* skips give the same image bit for bit, and "
                   "*same-estimator* skips the same estimate from other random numbers (the general path draws numbers "
                   "whose contribution is multiplied by zero), so their error per sample is the same and the time ratio "
                   "decides; *estimator* skips change how the path is sampled (the general path keeps a mixture "
                   "component whose samples fail and end the path: shorter paths, more variance), so the time at equal "
                   "error decides. (For the other skips the equal-error column is only a check: with the same estimator "
                   "its relMSE ratio is noise around 1, and on scenes with caustics, whose rare bright paths make relMSE "
                   "heavy-tailed, the bootstrap interval is optimistic.) A skip **pays** when the upper end of its deciding ratio's interval is below 1.\n\n"
                   "| skip | scene | strategy | kind | what it skips | spp | reps | CPU s specialised / general | time ratio "
                   "[95 %%] | equal-error ratio [95 %%] | verdict | images differ by |\n"
                   "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
        for (k = 0; k < S->n; ++k) {
            const skip_result *o = &S->r[k];
            fprintf(f, "| %s | %s | %s | %s | %s | %d | %d | %.4g / %.4g | %s%.3f [%.3f, %.3f]%s | %s%.3f [%.3f, %.3f]%s "
                       "| %s | %.2g |\n", o->name, o->scene, o->strategy, skip_kind_name(o->kind), o->what, o->spp,
                    o->reps, o->t_on, o->t_off, o->kind == SKIP_ESTIMATOR ? "" : "**", o->ratio, o->ratio_lo,
                    o->ratio_hi, o->kind == SKIP_ESTIMATOR ? "" : "**", o->kind == SKIP_ESTIMATOR ? "**" : "", o->eq,
                    o->eq_lo, o->eq_hi, o->kind == SKIP_ESTIMATOR ? "**" : "", o->pays ? "pays" : "gain not shown",
                    o->relmse_between);
        }
        fprintf(f, "\n");
    }
    fprintf(f, "## Files\n\nseries.csv (medians per spp), series-seeds.csv (every seed), fits.csv (slopes, efficiency), "
               "guiding.csv (the guided strategies against the best unguided one), pov.csv, adaptive.csv, skips.csv, tput.csv; SCENE.png and headline.png (%s), from plots.gp and the .dat files.\n",
            plot_status);
    return close_out(f, "summary.md");
}

/* ---- main ------------------------------------------------------------------------------ */

static int usage(void)
{
    fprintf(stderr,
            "usage: bench run [--quick] [--out DIR] [--budget SECONDS] [--seeds N] [--parts LIST] [--scenes LIST]\n"
            "                 [--mitsuba-python PYTHON] [--cache DIR]\n"
            "       bench refs [--spp N] [NAME...]   (--spp: override the table, for experiments)\n"
            "       bench list\n"
            "  --parts: comma-separated series,adaptive,skips,pov,mitsuba,headline,throughput (default all;\n"
            "           pov and mitsuba need series; headline, the 600x600 Cornell box against Mitsuba, is left\n"
            "           out of --quick unless named; throughput: samples/s and rays/s per SIMD level and\n"
            "           against Mitsuba at equal depth, quick: the cornell and rooms scenes only)\n"
            "  --mitsuba-python: the Python of a venv with Mitsuba 3 (default $MITSUBA_PYTHON, else\n"
            "           build/mitsuba-venv/bin/python; make mitsuba-install creates it)\n"
            "  --cache: where the headline keeps its reference image (default build/bench-cache)\n"
            "  --headline-size N: the headline at N x N instead of the scene's size (quick checks)\n"
            "  --headline-seeds N, --headline-ref-spp N (3, 1024), --headline-samplers independent,multijitter\n"
            "           (or one of them): a cheaper headline on a busy machine\n"
            "  --scenes: comma-separated scene names (default all; see bench list)\n"
            "Run from the repository root (make bench / make bench-quick / make bench-refs).\n");
    return 2;
}

static int find_scene(const char *name)
{
    int i;
    for (i = 0; i < SCENE_COUNT; ++i)
        if (!strcmp(scenes[i].name, name)) return i;
    return -1;
}

/* Parses a comma-separated list; calls fn for each item; returns 0 on an unknown item. */
static int parse_list(const char *list, int (*fn)(config *, const char *), config *cfg)
{
    char buf[512], *tok, *save = NULL;
    if (strlen(list) >= sizeof buf) return 0;
    strcpy(buf, list);
    for (tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save))
        if (!fn(cfg, tok)) return 0;
    return 1;
}
static int add_part(config *cfg, const char *p)
{
    if (!strcmp(p, "series")) cfg->parts |= PART_SERIES;
    else if (!strcmp(p, "adaptive")) cfg->parts |= PART_ADAPTIVE;
    else if (!strcmp(p, "skips")) cfg->parts |= PART_SKIPS;
    else if (!strcmp(p, "pov")) cfg->parts |= PART_POV;
    else if (!strcmp(p, "mitsuba")) cfg->parts |= PART_MITSUBA;
    else if (!strcmp(p, "headline")) cfg->parts |= PART_HEADLINE;
    else if (!strcmp(p, "throughput")) cfg->parts |= PART_TPUT;
    else {
        fprintf(stderr, "bench: unknown part '%s' (series, adaptive, skips, pov, mitsuba, headline, throughput)\n", p);
        return 0;
    }
    return 1;
}
static int add_scene(config *cfg, const char *name)
{
    int i = find_scene(name);
    if (i < 0) {
        fprintf(stderr, "bench: unknown scene '%s' (bench list)\n", name);
        return 0;
    }
    cfg->scene_on[i] = 1;
    return 1;
}

static int parse_positive(const char *opt, const char *v, double lo, double hi, double *out)
{
    char *end;
    double x;
    errno = 0;
    x = strtod(v, &end);
    if (errno || end == v || *end || !(x >= lo && x <= hi)) {
        fprintf(stderr, "bench: %s needs a number in [%g, %g], got '%s'\n", opt, lo, hi, v);
        return 0;
    }
    *out = x;
    return 1;
}

static int cmd_run(int argc, char **argv)
{
    config cfg;
    static results R;
    static pov_results P;
    static adaptive_results A, A2, A3, A4; /* own samples at the end / 128 spp; neighbours only, the same */
    static skip_results S;
    static mitsuba_results M;
    static headline_results H;
    static tput_results T;
    char plot_status[512] = "not made";
    int i, any_scene = 0, ok = 1, budget_set = 0;
    double t0 = ptv_now(), v;
    memset(&cfg, 0, sizeof cfg);
    cfg.out = "bench/out";
    cfg.ref_dir = "bench/ref";
    cfg.seeds = 5;
    cfg.mitsuba_python = getenv("MITSUBA_PYTHON") && *getenv("MITSUBA_PYTHON") ? getenv("MITSUBA_PYTHON")
                                                                               : "build/mitsuba-venv/bin/python";
    cfg.cache = "build/bench-cache";
    cfg.headline_seeds = HEADLINE_SEEDS;
    cfg.headline_ref_spp = HEADLINE_REF_SPP;
    cfg.headline_samplers = "independent,multijitter";
    for (i = 2; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "--quick")) cfg.quick = 1;
        else if (!strcmp(a, "--out") && i + 1 < argc) cfg.out = argv[++i];
        else if (!strcmp(a, "--mitsuba-python") && i + 1 < argc) cfg.mitsuba_python = argv[++i];
        else if (!strcmp(a, "--cache") && i + 1 < argc) cfg.cache = argv[++i];
        else if (!strcmp(a, "--headline-samplers") && i + 1 < argc) {
            cfg.headline_samplers = argv[++i];
            if (strcmp(cfg.headline_samplers, "independent") && strcmp(cfg.headline_samplers, "multijitter") &&
                strcmp(cfg.headline_samplers, "independent,multijitter")) {
                fprintf(stderr, "bench: --headline-samplers: independent, multijitter or independent,multijitter\n");
                return 2;
            }
        } else if (!strcmp(a, "--headline-seeds") && i + 1 < argc) {
            if (!parse_positive(a, argv[++i], 1, MAX_SEEDS, &v)) return 2;
            cfg.headline_seeds = (int)v;
        } else if (!strcmp(a, "--headline-ref-spp") && i + 1 < argc) {
            if (!parse_positive(a, argv[++i], 16, 1 << 20, &v)) return 2;
            cfg.headline_ref_spp = (int)v;
        } else if (!strcmp(a, "--headline-size") && i + 1 < argc) {
            if (!parse_positive(a, argv[++i], 8, 4096, &v)) return 2;
            cfg.headline_size = (int)v;
        }
        else if (!strcmp(a, "--budget") && i + 1 < argc) {
            if (!parse_positive(a, argv[++i], 0.001, 3600, &cfg.budget)) return 2;
            budget_set = 1;
        } else if (!strcmp(a, "--seeds") && i + 1 < argc) {
            if (!parse_positive(a, argv[++i], 5, MAX_SEEDS, &v)) return 2;
            cfg.seeds = (int)v;
        } else if (!strcmp(a, "--parts") && i + 1 < argc) {
            if (!parse_list(argv[++i], add_part, &cfg)) return 2;
        } else if (!strcmp(a, "--scenes") && i + 1 < argc) {
            if (!parse_list(argv[++i], add_scene, &cfg)) return 2;
        } else {
            fprintf(stderr, "bench: unknown or incomplete option '%s'\n", a);
            return usage();
        }
    }
    if (!budget_set) cfg.budget = cfg.quick ? 0.12 : 2.0;
    if (!cfg.parts) cfg.parts = cfg.quick ? PART_ALL & ~PART_HEADLINE : PART_ALL;
    for (i = 0; i < SCENE_COUNT; ++i) any_scene |= cfg.scene_on[i];
    if (!any_scene)
        for (i = 0; i < SCENE_COUNT; ++i) cfg.scene_on[i] = 1;
    if ((cfg.parts & PART_MITSUBA) && !(cfg.parts & PART_SERIES)) {
        fprintf(stderr, "bench: --parts mitsuba needs series (Mitsuba is compared with pdftrace's series)\n");
        return 2;
    }
    if ((cfg.parts & PART_POV) && !(cfg.parts & PART_SERIES)) {
        fprintf(stderr, "bench: --parts pov needs series (POV-Ray is compared with the MIS series at equal time)\n");
        return 2;
    }
    if (!mkdirs(cfg.out)) return 1;
    printf("bench: %s mode, %.2f s per series, %d seeds, %dx%d, output in %s\n", cfg.quick ? "quick" : "full", cfg.budget,
           cfg.seeds, BENCH_SIZE, BENCH_SIZE, cfg.out);
    fflush(stdout);
    /* Check every input before measuring anything. */
    for (i = 0; i < SCENE_COUNT; ++i) {
        if (!cfg.scene_on[i]) continue;
        if (!load_scene(&scenes[i], &R.L[i]) || !load_reference(&cfg, &scenes[i], &R.L[i])) {
            int k;
            for (k = 0; k <= i; ++k) free_scene(&R.L[k]);
            return 1;
        }
        R.done[i] = 1;
    }
    if (cfg.parts & PART_SERIES) {
        printf("series: %d scenes x %d strategies x %d seeds\n", SCENE_COUNT, STRATEGY_COUNT, cfg.seeds);
        ok = run_all_series(&cfg, &R) && write_series_csv(&cfg, &R) && write_guiding_csv(&cfg, &R);
    } else
        for (i = 0; i < SCENE_COUNT; ++i) R.done[i] = 0; /* nothing to report per scene */
    if (ok && (cfg.parts & PART_ADAPTIVE)) ok = run_adaptive(&cfg, &R, &A, 0, 0);
    if (ok && (cfg.parts & PART_ADAPTIVE) && !cfg.quick) ok = run_adaptive(&cfg, &R, &A2, 128, 0);
    if (ok && (cfg.parts & PART_ADAPTIVE) && !cfg.quick) ok = run_adaptive(&cfg, &R, &A3, 0, 1);
    if (ok && (cfg.parts & PART_ADAPTIVE) && !cfg.quick) ok = run_adaptive(&cfg, &R, &A4, 128, 1);
    if (ok && (cfg.parts & PART_ADAPTIVE)) {
        const adaptive_results *runs[4];
        runs[0] = &A;
        runs[1] = &A2;
        runs[2] = &A3;
        runs[3] = &A4;
        ok = write_adaptive_csv(&cfg, runs, 4);
    }
    if (ok && (cfg.parts & PART_SKIPS)) ok = run_skips(&cfg, &R, &S) && write_skips_csv(&cfg, &S);
    if (ok && (cfg.parts & PART_POV)) ok = run_pov(&cfg, &R, &P) && write_pov_csv(&cfg, &R, &P);
    if (ok && (cfg.parts & PART_MITSUBA)) ok = run_mitsuba(&cfg, &R, &M) && write_mitsuba_csv(&cfg, &R, &M);
    if (ok && (cfg.parts & PART_HEADLINE)) ok = run_headline(&cfg, &H);
    if (ok && (cfg.parts & PART_TPUT)) ok = run_throughput(&cfg, &R, &T) && write_tput_csv(&cfg, &T);
    if (!(cfg.parts & PART_TPUT)) snprintf(T.skip_reason, sizeof T.skip_reason, "not run (--parts)");
    if (!(cfg.parts & PART_MITSUBA)) snprintf(M.skip_reason, sizeof M.skip_reason, "not run (--parts)");
    if (!(cfg.parts & PART_HEADLINE))
        snprintf(H.skip_reason, sizeof H.skip_reason, cfg.quick ? "quick mode (make bench-headline runs it)"
                                                                : "not run (--parts)");
    if (!(cfg.parts & PART_ADAPTIVE)) snprintf(A.skip_reason, sizeof A.skip_reason, "not run (--parts)");
    {   /* the full mode's runs, when not run: why */
        adaptive_results *full_only[3];
        full_only[0] = &A2;
        full_only[1] = &A3;
        full_only[2] = &A4;
        for (i = 0; i < 3; ++i)
            if (!full_only[i]->available && !full_only[i]->skip_reason[0])
                snprintf(full_only[i]->skip_reason, sizeof full_only[i]->skip_reason, cfg.quick ? "quick mode" : "not run (--parts)");
    }
    if (!(cfg.parts & PART_SKIPS)) snprintf(S.skip_reason, sizeof S.skip_reason, "not run (--parts)");
    if (!(cfg.parts & PART_POV)) snprintf(P.skip_reason, sizeof P.skip_reason, "not run (--parts)");
    if (ok && (cfg.parts & PART_SERIES)) ok = make_plots(&cfg, &R, &P, &M, &A, &A3, plot_status, sizeof plot_status);
    if (ok) ok = write_summary(&cfg, &R, &P, &M, &H, &A, &A2, &A3, &A4, &S, &T, plot_status, ptv_now() - t0);
    for (i = 0; i < SCENE_COUNT; ++i) free_scene(&R.L[i]);
    if (!ok) {
        fprintf(stderr, "bench: failed\n");
        return 1;
    }
    printf("bench: wrote %s/summary.md (%.0f s)\n", cfg.out, ptv_now() - t0);
    return 0;
}

static int cmd_refs(int argc, char **argv)
{
    config cfg;
    int i, k, ok = 1, first = 2, spp = 0, names = 0;
    double v;
    memset(&cfg, 0, sizeof cfg);
    cfg.ref_dir = "bench/ref";
    if (argc >= 4 && !strcmp(argv[2], "--spp")) {
        if (!parse_positive("--spp", argv[3], 1, 1 << 24, &v)) return 2;
        spp = (int)v;
        first = 4;
    }
    for (k = first; k < argc; ++k) {
        if (find_scene(argv[k]) < 0) {
            fprintf(stderr, "bench: unknown scene '%s' (bench list)\n", argv[k]);
            return 2;
        }
        ++names;
    }
    if (!mkdirs(cfg.ref_dir)) return 1;
    for (i = 0; i < SCENE_COUNT && ok; ++i) {
        int want = names == 0;
        for (k = first; k < argc; ++k) want |= !strcmp(argv[k], scenes[i].name);
        if (want) ok = make_reference(&cfg, &scenes[i], spp);
    }
    return ok ? 0 : 1;
}

static int cmd_list(void)
{
    int i;
    for (i = 0; i < SCENE_COUNT; ++i)
        printf("%-16s %-36s ref %5d spp  POV-Ray %s\n    %s\n", scenes[i].name, scenes[i].file, scenes[i].ref_spp,
               scenes[i].pov_numeric ? "numeric" : "not numeric", scenes[i].about);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "run")) return cmd_run(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "refs")) return cmd_refs(argc, argv);
    if (argc == 2 && !strcmp(argv[1], "list")) return cmd_list();
    return usage();
}
