/* adaptive_efficiency.c - adaptive sampling's efficiency at equal time against uniform sampling,
   per mode: the median over seeds of 1 / (relMSE x CPU seconds), relMSE = mean over pixels and
   channels of (x - r)^2 / (r^2 + 0.01) against a reference image, minus the reference's own
   noise floor (its .txt file's noise_floor_relmse, given with --floor). One thread, process CPU
   time (clock()), so other load on the machine slows the clock less than wall time.

   Build and run (from the repository's top level):
     cc -std=c99 -O2 -I. -pthread -o build/adaptive_efficiency bench/adaptive_efficiency.c -lm
     build/adaptive_efficiency scenes/cornell.scene bench/ref/cornell.pfm --floor 3.14e-4 \
         --spp 128 --seeds 5 --thresholds 0.07,0.08,0.09
   Prints one line per configuration: uniform at --spp, then each mode (pilot, own-samples) at
   each threshold with a cap of 4 x --spp; the last column is the efficiency over uniform's.
   --min-spp N sets adaptive_min_spp (the pilot's size), --pilot-only skips own-samples. */
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define MAX_SEEDS 64
#define MAX_T 16

/* A PFM file (little-endian "PF" colour, rows bottom first) into rgb, top row first. */
static float *read_pfm(const char *path, int *w, int *h)
{
    FILE *f = fopen(path, "rb");
    char magic[3] = { 0 };
    double scale;
    float *rgb = NULL, *row;
    int y;
    if (!f) return NULL;
    if (fscanf(f, "%2s %d %d %lf", magic, w, h, &scale) != 4 || strcmp(magic, "PF") || scale >= 0 || fgetc(f) == EOF ||
        *w <= 0 || *h <= 0) {
        fclose(f);
        return NULL;
    }
    rgb = (float *)malloc(sizeof(float) * 3 * (size_t)*w * (size_t)*h);
    for (y = *h - 1; rgb && y >= 0; --y) {
        row = rgb + 3 * (size_t)*w * (size_t)y;
        if (fread(row, sizeof(float) * 3, (size_t)*w, f) != (size_t)*w) { free(rgb); rgb = NULL; }
    }
    fclose(f);
    return rgb;
}

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

/* One render: relMSE against ref (minus floor) and CPU seconds. */
static int measure(const pt_scene *s, const pt_render_desc *d, const float *ref, double floor_, double *rel, double *sec,
                   double *samples)
{
    pt_image img;
    pt_render_stats st;
    clock_t c0 = clock();
    size_t i, n = (size_t)d->width * (size_t)d->height * 3u;
    double acc = 0.0;
    memset(&img, 0, sizeof img);
    if (pt_render_image(s, d, &img, &st) != PT_OK) {
        fprintf(stderr, "adaptive_efficiency: %s\n", st.error);
        return 0;
    }
    *sec = (double)(clock() - c0) / CLOCKS_PER_SEC;
    for (i = 0; i < n; ++i) {
        double e = (double)img.rgb[i] - (double)ref[i];
        acc += e * e / ((double)ref[i] * (double)ref[i] + 0.01);
    }
    *rel = acc / (double)n - floor_;
    *samples = (double)st.samples / ((double)d->width * (double)d->height);
    pt_image_free(&img);
    return 1;
}

int main(int argc, char **argv)
{
    const char *path = NULL, *refpath = NULL;
    int spp = 128, seeds = 5, nt = 0, i, k, m, w, h, min_spp = 0, modes = 3;
    double floor_ = 0.0, T[MAX_T], base_eff = 0.0;
    char err[1024];
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc base;
    float *ref;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--spp") && v) spp = atoi(argv[++i]);
        else if (!strcmp(a, "--seeds") && v) seeds = atoi(argv[++i]);
        else if (!strcmp(a, "--floor") && v) floor_ = atof(argv[++i]);
        else if (!strcmp(a, "--min-spp") && v) min_spp = atoi(argv[++i]);
        else if (!strcmp(a, "--pilot-only")) modes = 2;
        else if (!strcmp(a, "--thresholds") && v) {
            char *p = argv[++i];
            while (*p && nt < MAX_T) {
                T[nt++] = strtod(p, &p);
                if (*p == ',') ++p;
            }
        } else if (a[0] != '-' && !path) path = a;
        else if (a[0] != '-' && !refpath) refpath = a;
        else { fprintf(stderr, "adaptive_efficiency: bad argument '%s'\n", a); return 2; }
    }
    if (!path || !refpath || spp <= 0 || seeds < 1 || seeds > MAX_SEEDS || nt == 0) {
        fprintf(stderr, "usage: adaptive_efficiency SCENE REF.pfm --thresholds T1,T2,.. [--spp N --seeds K --floor F]\n");
        return 2;
    }
    if (!(ref = read_pfm(refpath, &w, &h))) { fprintf(stderr, "adaptive_efficiency: cannot read %s\n", refpath); return 1; }
    if (pt_scenefile_load(path, &sf, err, sizeof err) != PT_OK || pt_scenefile_build(&sf, &scene, &base, err, sizeof err) != PT_OK) {
        fprintf(stderr, "adaptive_efficiency: %s\n", err);
        return 1;
    }
    base.width = w;
    base.height = h;
    base.threads = 1;
    printf("%s %dx%d, 1 thread, %d seeds (medians); uniform %d spp, adaptive cap %d spp\n", path, w, h, seeds, spp, 4 * spp);
    printf("| mode | threshold | spp (mean, pilot included) | CPU s | relMSE | efficiency / uniform |\n|---|---:|---:|---:|---:|---:|\n");
    for (m = 0; m < modes; ++m)
        for (k = 0; k < (m ? nt : 1); ++k) {
            double rel[MAX_SEEDS], sec[MAX_SEEDS], eff[MAX_SEEDS], smp[MAX_SEEDS], e;
            char tbuf[32];
            int j;
            for (j = 0; j < seeds; ++j) {
                pt_render_desc d = base;
                d.seed = 101u + (uint64_t)j;
                d.samples_per_pixel = m ? 4 * spp : spp;
                if (m) {
                    d.adaptive_threshold = (float)T[k];
                    d.adaptive_min_spp = min_spp;
                    d.adaptive_mode = m == 1 ? PT_ADAPTIVE_PILOT : PT_ADAPTIVE_OWN_SAMPLES;
                }
                if (!measure(scene, &d, ref, floor_, &rel[j], &sec[j], &smp[j])) return 1;
                eff[j] = 1.0 / (rel[j] * sec[j]);
            }
            e = median(eff, seeds);
            if (!m) base_eff = e;
            if (m) snprintf(tbuf, sizeof tbuf, "%.3g", T[k]);
            else snprintf(tbuf, sizeof tbuf, "-");
            printf("| %s | %s | %.1f | %.3g | %.4g | %.2f |\n", m == 0 ? "uniform" : m == 1 ? "pilot" : "own samples", tbuf,
                   median(smp, seeds), median(sec, seeds), median(rel, seeds), e / base_eff);
            fflush(stdout);
        }
    pt_scene_destroy(scene);
    pt_scenefile_free(&sf);
    free(ref);
    return 0;
}
