/* bench/tput_ab.c - one timed render at the throughput settings (bench/README.md, "Throughput at
   equal depth": max_depth 4, no roulette, no splitting, one path per camera sample, MIS,
   independent numbers), for bench/tput_ab.sh, which builds this file from two revisions of
   pdftrace.h and runs the two binaries in alternating order. Prints the samples per CPU second
   and per wall second (with 1 thread the CPU figure is the one less disturbed by other jobs),
   a hash of the film's sums (equal hashes: equal images) and the image mean.

   tput_ab SCENE WIDTH HEIGHT SPP THREADS INTEGRATOR SEED [MODE]
   (INTEGRATOR: 0 default, 1 scalar, 2 batched; MODE: 0 the throughput settings, the default; 1 the
   same with the Sobol sampler; 2 the scene file's own settings, e.g. a default Sobol render).
   Built with -DPDFTRACE_EMBREE (tput_ab.sh -e) it renders with the Embree backend; with
   -DTPUT_AB_NO_INTEGRATOR it builds against a pdftrace.h from before pt_render_desc.integrator
   (tput_ab.sh passes it for such revisions), whose only integrator is the scalar one. */
#define _POSIX_C_SOURCE 200809L
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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
    char err[1024];
    size_t i, n;
    uint64_t h = 1469598103934665603ULL; /* FNV-1a over the sums' bits */
    double c0, c1, mean = 0.0;
    int integ, mode;
    if (argc != 8 && argc != 9) {
        fprintf(stderr, "usage: tput_ab SCENE WIDTH HEIGHT SPP THREADS INTEGRATOR(0|1|2) SEED [MODE(0|1|2)]\n");
        return 2;
    }
    if (pt_scenefile_load(argv[1], &sd, err, sizeof err) != PT_OK ||
        pt_scenefile_build(&sd, &scene, &d, err, sizeof err) != PT_OK) {
        fprintf(stderr, "tput_ab: %s\n", err);
        return 1;
    }
#ifdef PDFTRACE_EMBREE
    if (pt_scene_set_backend(scene, PT_BACKEND_EMBREE) != PT_OK || pt_scene_commit(scene) != PT_OK) {
        fprintf(stderr, "tput_ab: Embree: %s\n", pt_scene_error_message(scene));
        return 1;
    }
#endif
    mode = argc == 9 ? atoi(argv[8]) : 0;
    d.width = atoi(argv[2]);
    d.height = atoi(argv[3]);
    d.samples_per_pixel = atoi(argv[4]);
    d.samples_per_pass = 0;
    if (mode != 2) { /* 2: the scene file's own settings (the sampler, depth, roulette, splitting) */
        d.strategy = PT_STRATEGY_MIS;
        d.sampler = mode == 1 ? PT_SAMPLER_SOBOL : PT_SAMPLER_INDEPENDENT;
        d.max_depth = 4;
        d.rr_start_depth = -1;
        d.max_splits = -1;
        d.indirect_paths = 1;
        d.guiding = PT_GUIDING_OFF;
    }
    d.adaptive_threshold = 0;
    d.threads = atoi(argv[5]);
    integ = atoi(argv[6]);
#ifndef TPUT_AB_NO_INTEGRATOR
    d.integrator = integ == 1 ? PT_INTEGRATOR_SCALAR : integ == 2 ? PT_INTEGRATOR_BATCHED : PT_INTEGRATOR_DEFAULT;
#else
    (void)integ; /* a revision from before the batched integrator: scalar only */
#endif
    d.seed = (uint64_t)strtoull(argv[7], NULL, 10);
    d.progress = NULL;
    if (pt_film_init(&film, d.width, d.height) != PT_OK) return 1;
    c0 = cpu_seconds();
    if (pt_render(scene, &d, &film, &st) != PT_OK) {
        fprintf(stderr, "tput_ab: %s\n", st.error);
        return 1;
    }
    c1 = cpu_seconds();
    n = 3u * (size_t)d.width * (size_t)d.height;
    for (i = 0; i < n; ++i) {
        uint64_t b;
        memcpy(&b, &film.sum[i], sizeof b);
        h = (h ^ b) * 1099511628211ULL;
        mean += film.sum[i];
    }
    mean /= (double)n * (double)d.samples_per_pixel;
    printf("%.4f %.4f %016llx %.6f\n", 1e-6 * (double)st.samples / (c1 - c0 > 0.0 ? c1 - c0 : 1e-9),
           1e-6 * (double)st.samples / (st.seconds > 0.0 ? st.seconds : 1e-9), (unsigned long long)h, mean);
    pt_film_free(&film);
    pt_scene_destroy(scene);
    pt_scenefile_free(&sd);
    return 0;
}
