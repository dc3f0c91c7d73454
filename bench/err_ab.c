/* bench/err_ab.c - one render's relMSE and bias against a stored reference (bench.c's measure())
   and its CPU seconds, for comparing what two revisions of pdftrace.h estimate at equal samples
   (e.g. two light trees): build it against each revision like bench/tput_ab.sh does and run the
   two for the same seeds. The scene file's own settings, 128 x 128 (the references' size), one
   thread.

   err_ab SCENE REF.pfm SPP SEED
   prints: relMSE bias cpu_seconds */
#define _POSIX_C_SOURCE 200809L
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>

static double cpu_seconds(void)
{
    struct rusage u;
    getrusage(RUSAGE_SELF, &u);
    return (double)u.ru_utime.tv_sec + 1e-6 * (double)u.ru_utime.tv_usec + (double)u.ru_stime.tv_sec +
           1e-6 * (double)u.ru_stime.tv_usec;
}

int main(int argc, char **argv)
{
    pt_scenefile sd;
    pt_scene *scene;
    pt_render_desc d;
    pt_film film;
    pt_render_stats st;
    pt_image ref, img;
    char err[1024];
    double c0, c1, mse = 0.0, sx = 0.0, sr = 0.0;
    size_t i, n;
    if (argc != 5) {
        fprintf(stderr, "usage: err_ab SCENE REF.pfm SPP SEED\n");
        return 2;
    }
    if (pt_scenefile_load(argv[1], &sd, err, sizeof err) != PT_OK ||
        pt_scenefile_build(&sd, &scene, &d, err, sizeof err) != PT_OK || pt_read_pfm(argv[2], &ref, err, sizeof err) != PT_OK) {
        fprintf(stderr, "err_ab: %s\n", err);
        return 1;
    }
    d.width = ref.width;
    d.height = ref.height;
    d.samples_per_pixel = atoi(argv[3]);
    d.seed = (uint64_t)strtoull(argv[4], NULL, 10);
    d.threads = 1;
    d.progress = NULL;
    img.rgb = NULL;
    if (pt_film_init(&film, d.width, d.height) != PT_OK) return 1;
    c0 = cpu_seconds();
    if (pt_render(scene, &d, &film, &st) != PT_OK) {
        fprintf(stderr, "err_ab: %s\n", st.error);
        return 1;
    }
    c1 = cpu_seconds();
    if (pt_image_init(&img, d.width, d.height) != PT_OK || pt_film_resolve(&film, &img) != PT_OK) return 1;
    n = 3u * (size_t)d.width * (size_t)d.height;
    for (i = 0; i < n; ++i) { /* bench.c's relMSE and bias */
        double x = img.rgb[i], r = ref.rgb[i];
        mse += (x - r) * (x - r) / (r * r + 0.01);
        sx += x;
        sr += r;
    }
    printf("%.6f %+.5f %.4f\n", mse / (double)n, sr > 0.0 ? sx / sr - 1.0 : 0.0, c1 - c0);
    pt_image_free(&img);
    pt_image_free(&ref);
    pt_film_free(&film);
    pt_scene_destroy(scene);
    pt_scenefile_free(&sd);
    return 0;
}
