/* bench/env_cells.c - how often an environment light sample's density, taken from the cell it was
   drawn from (pt__env_sample with its radiance wanted), differs from the density evaluated from
   the sampled float direction (pt__env_density, what a ray found by the material's PDF sees), and
   the worst ratio of the two: the samples whose rounding carried them across a cell edge
   (docs/design.md, "Light samples from their cell"). Map samples only (no background share).
   cc -I. -std=c99 -O2 -pthread -o build/env_cells bench/env_cells.c -lm
   build/env_cells SCENE [N]   (N samples, default 10^7; seeded, so the count is reproducible) */
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"
#include <stdio.h>
#include <stdlib.h>
int main(int argc, char **argv)
{
    pt_scenefile sd;
    pt_scene *s;
    pt_render_desc d;
    char err[512];
    pt_rng r;
    long i, n = argc > 2 ? atol(argv[2]) : 10000000L, diff = 0;
    double worst = 1.0;
    if (argc < 2 || pt_scenefile_load(argv[1], &sd, err, sizeof err) != PT_OK ||
        pt_scenefile_build(&sd, &s, &d, err, sizeof err) != PT_OK || !s->env) {
        fprintf(stderr, "usage: env_cells SCENE_WITH_A_MAP [N]%s%s\n", argc < 2 ? "" : ": ", argc < 2 ? "" : err);
        return 2;
    }
    pt_rng_seed(&r, 5, 7);
    for (i = 0; i < n; ++i) {
        pt_vec3 w;
        float p, q, u1 = pt_rng_float(&r), u2 = pt_rng_float(&r);
        pt_color L;
        if (!pt__env_sample(s->env, 0.0f, u1, u2, &w, &p, &L)) continue;
        q = pt__env_density(s->env, 0.0f, w);
        if (p != q) {
            double ratio = p > q ? (double)p / q : (double)q / p;
            diff++;
            if (ratio > worst) worst = ratio;
        }
    }
    printf("%s: %ld of %ld samples' cell density differs from their direction's; worst ratio %.4g\n", argv[1], diff,
           n, worst);
    pt_scene_destroy(s);
    pt_scenefile_free(&sd);
    return 0;
}
