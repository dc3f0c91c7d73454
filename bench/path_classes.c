/* path_classes.c - where a render's variance is, by the kind of path that carries it. The scalar
   integrator, compiled with PDFTRACE_PATH_CLASSES, reports each contribution with its path's
   class (section 7 of pdftrace.h: E D+ L; delta vertices but not between the light and the last
   non-delta vertex; the caustics L S+ D E and L S+ D S+ E, and a caustic's light reaching another
   non-delta vertex directly, L S+ D D ... E, or through delta ones, L S+ D S+ D ... E). This program renders on one thread, sums each class per camera
   sample, and prints per class: its share of the image's mean, its relative variance per sample
   (mean over pixels and channels of Var/(m^2 + 0.01), m the pixel's mean, as the relMSE of
   bench/guide_efficiency.c) and its share of the whole's (the classes' shares need not add up
   to 100 %: their covariances are left out), then the render's CPU time.

   Build and run (from the repository's top level):
     cc -std=c99 -O2 -I. -pthread -o build/path_classes bench/path_classes.c -lm
     build/path_classes scenes/cornell.scene --size 300 --spp 64
     build/path_classes scenes/cornell.scene --size 300 --spp 64 --guiding on
   Options: --size N (square image), --spp N, --guiding off|on, --alpha F (guiding_alpha; 0: the
   default), --sampler independent|sobol (the scene's, else Sobol), --seed N. */
#define PDFTRACE_PATH_CLASSES
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double sample_sum[PT_PATH_CLASS_COUNT][3]; /* the current camera sample's, per class */
static double *pixel_sum, *pixel_sq;              /* per pixel, class and channel */

void pt_path_class_add(int path_class, pt_color e)
{
    sample_sum[path_class][0] += (double)e.x;
    sample_sum[path_class][1] += (double)e.y;
    sample_sum[path_class][2] += (double)e.z;
}

void pt_path_class_sample_done(uint32_t pixel)
{
    double *s = pixel_sum + (size_t)pixel * PT_PATH_CLASS_COUNT * 3u, *q = pixel_sq + (size_t)pixel * PT_PATH_CLASS_COUNT * 3u;
    int c, k;
    for (c = 0; c < PT_PATH_CLASS_COUNT; ++c)
        for (k = 0; k < 3; ++k) {
            s[3 * c + k] += sample_sum[c][k];
            q[3 * c + k] += sample_sum[c][k] * sample_sum[c][k];
        }
    memset(sample_sum, 0, sizeof sample_sum);
}

static void print_table(const pt_film *film, int spp)
{
    static const char *name[PT_PATH_CLASS_COUNT + 1] = {
        "E D+ L (no delta vertex)", "delta vertices, not a caustic", "L S+ D E (caustic seen)",
        "L S+ D S+ E (through glass)", "L S+ D D.. E (next to a D)", "L S+ D S+ D.. E (SDS)", "the image"};
    double mean[PT_PATH_CLASS_COUNT + 1] = {0}, rv[PT_PATH_CLASS_COUNT + 1] = {0};
    size_t n = (size_t)film->width * (size_t)film->height, p;
    int c, k;
    for (p = 0; p < n; ++p)
        for (k = 0; k < 3; ++k) {
            double m = film->sum[3 * p + k] / spp, den = m * m + 0.01;
            mean[PT_PATH_CLASS_COUNT] += m;
            rv[PT_PATH_CLASS_COUNT] += (film->sum_sq[3 * p + k] / spp - m * m) / den;
            for (c = 0; c < PT_PATH_CLASS_COUNT; ++c) {
                size_t i = (p * PT_PATH_CLASS_COUNT + (size_t)c) * 3u + (size_t)k;
                double mc = pixel_sum[i] / spp;
                mean[c] += mc;
                rv[c] += (pixel_sq[i] / spp - mc * mc) / den;
            }
        }
    {   /* every contribution has a class: the classes' means add up to the image's */
        double t = 0.0;
        for (c = 0; c < PT_PATH_CLASS_COUNT; ++c) t += mean[c];
        if (!(fabs(t - mean[PT_PATH_CLASS_COUNT]) <= 1e-5 * mean[PT_PATH_CLASS_COUNT]))
            printf("warning: the classes' means add up to %.6g, the image's is %.6g (a contribution without a class)\n",
                   t / (3.0 * (double)n), mean[PT_PATH_CLASS_COUNT] / (3.0 * (double)n));
    }
    printf("%-32s %10s %12s %18s\n", "class", "mean", "share", "relvar per sample");
    for (c = 0; c <= PT_PATH_CLASS_COUNT; ++c)
        printf("%-32s %10.5f %11.1f%% %10.4f (%5.1f%%)\n", name[c], mean[c] / (3.0 * (double)n),
               100.0 * mean[c] / mean[PT_PATH_CLASS_COUNT], rv[c] / (3.0 * (double)n),
               100.0 * rv[c] / rv[PT_PATH_CLASS_COUNT]);
}

int main(int argc, char **argv)
{
    pt_scenefile sd;
    pt_scene *scene = NULL;
    pt_render_desc d;
    pt_render_stats st;
    pt_film film;
    char err[512];
    int size = 300, spp = 64, guiding = 0, sampler = -1, i;
    long seed = 1;
    float alpha = 0.0f;
    clock_t t0;
    if (argc < 2) {
        fprintf(stderr, "usage: path_classes SCENE [--size N] [--spp N] [--guiding off|on] [--sampler S] [--seed N]\n");
        return 2;
    }
    for (i = 2; i < argc; ++i) {
        if (i + 1 < argc && !strcmp(argv[i], "--size")) size = atoi(argv[++i]);
        else if (i + 1 < argc && !strcmp(argv[i], "--spp")) spp = atoi(argv[++i]);
        else if (i + 1 < argc && !strcmp(argv[i], "--guiding")) guiding = !strcmp(argv[++i], "on");
        else if (i + 1 < argc && !strcmp(argv[i], "--sampler")) sampler = !strcmp(argv[++i], "sobol");
        else if (i + 1 < argc && !strcmp(argv[i], "--seed")) seed = atol(argv[++i]);
        else if (i + 1 < argc && !strcmp(argv[i], "--alpha")) alpha = (float)atof(argv[++i]);
        else {
            fprintf(stderr, "path_classes: bad argument '%s'\n", argv[i]);
            return 2;
        }
    }
    if (size < 1 || size > 4096 || spp < 1 || seed < 0) {
        fprintf(stderr, "path_classes: bad --size, --spp or --seed\n");
        return 2;
    }
    if (pt_scenefile_load(argv[1], &sd, err, sizeof err) != PT_OK ||
        pt_scenefile_build(&sd, &scene, &d, err, sizeof err) != PT_OK) {
        fprintf(stderr, "path_classes: %s\n", err);
        return 1;
    }
    d.width = d.height = size;
    d.samples_per_pixel = spp;
    d.threads = 1;                          /* the hooks' sums are not shared between threads */
    d.integrator = PT_INTEGRATOR_SCALAR;    /* the hooks are in the scalar integrator */
    d.strategy = PT_STRATEGY_MIS;
    d.guiding = guiding ? PT_GUIDING_ON : PT_GUIDING_OFF;
    d.seed = (uint64_t)seed;
    d.guiding_alpha = alpha;
    if (sampler >= 0) d.sampler = sampler ? PT_SAMPLER_SOBOL : PT_SAMPLER_INDEPENDENT;
    pixel_sum = (double *)calloc((size_t)size * (size_t)size * PT_PATH_CLASS_COUNT * 3u, sizeof(double));
    pixel_sq = (double *)calloc((size_t)size * (size_t)size * PT_PATH_CLASS_COUNT * 3u, sizeof(double));
    if (!pixel_sum || !pixel_sq || pt_film_init(&film, size, size) != PT_OK) {
        fprintf(stderr, "path_classes: out of memory\n");
        return 1;
    }
    t0 = clock();
    if (pt_render(scene, &d, &film, &st) != PT_OK) {
        fprintf(stderr, "path_classes: %s\n", st.error);
        return 1;
    }
    printf("%s at %dx%d, %d spp, %s sampler, guiding %s, seed %ld: %.2f s CPU, %llu NaN/Inf samples\n", argv[1],
           size, size, spp, d.sampler == PT_SAMPLER_SOBOL ? "sobol" : "independent", guiding ? "on" : "off", seed,
           (double)(clock() - t0) / CLOCKS_PER_SEC, (unsigned long long)st.nonfinite_samples);
    print_table(&film, spp);
    pt_film_free(&film);
    pt_scene_destroy(scene);
    pt_scenefile_free(&sd);
    free(pixel_sum);
    free(pixel_sq);
    return 0;
}
