/* guide_efficiency.c - path guiding against unguided MIS at equal time, per seed: relMSE (mean over
   pixels and channels of (x - r)^2 / (r^2 + 0.01) against a reference image), process CPU seconds
   (one thread) and efficiency 1 / (relMSE x CPU s), with the guided render's stats; then the
   median of guided / unguided efficiency over the seeds. The reference's noise floor is not
   subtracted (the errors compared here are far above it).

   Build and run (from the repository's top level):
     cc -std=c99 -O2 -I. -pthread -o build/guide_efficiency bench/guide_efficiency.c -lm
     build/guide_efficiency bench/scenes/door.scene bench/ref/door.pfm --spp 256 --seeds 3
     build/guide_efficiency scenes/cornell.scene bench/ref/cornell.pfm --spp 128 --seeds 3
   Options: --alpha F, --budget F (pt_render_desc.guiding_alpha, guiding_budget; 0: defaults),
   --auto (PT_GUIDING_AUTO instead of ON), --rr-start N (rr_start_depth of both renders),
   --threads N (default 1; with N > 1 times are wall-clock seconds), --floor F (the reference's own
   relMSE noise floor, subtracted from every relMSE), --spp-unguided N and --sampler-unguided
   independent|sobol (the unguided render's, for equal-time comparisons: choose its spp so that its
   time matches the guided one's; default: the same spp, independent numbers), --sampler-guided
   independent|sobol (the guided render's; default independent),
   --save PREFIX (write the first seed's images as PREFIX-guided.pfm and PREFIX-unguided.pfm),
   --probe X Y Z NX NY NZ TX TY TZ: after the first guided render, the share of the guide's
   density at point X Y Z below the surface of normal N and within 5 and 15 degrees of the
   direction to T (a guide that learned where light comes from puts much of it there). */
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

static double cpu_seconds(void) { return (double)clock() / (double)CLOCKS_PER_SEC; }
static double wall_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double rel_mse(const pt_image *x, const pt_image *r)
{
    size_t n = 3u * (size_t)x->width * (size_t)x->height, i;
    double e = 0.0;
    for (i = 0; i < n; ++i) {
        double d = (double)x->rgb[i] - (double)r->rgb[i];
        e += d * d / ((double)r->rgb[i] * (double)r->rgb[i] + 0.01);
    }
    return e / (double)n;
}

static void probe(const pt_guide *g, const float *v)
{
    pt_vec3 p = pt_v3(v[0], v[1], v[2]), n = pt_normalize(pt_v3(v[3], v[4], v[5]));
    pt_vec3 to = pt_normalize(pt_sub(pt_v3(v[6], v[7], v[8]), p));
    pt_pdf pdf = pt_pdf_guide(g, p);
    double tot = 0.0, below = 0.0, in5 = 0.0, in15 = 0.0;
    int a, b;
    for (a = 0; a < 256; ++a)
        for (b = 0; b < 512; ++b) { /* cells of equal solid angle: z and phi uniform */
            double z = -1.0 + 2.0 * (a + 0.5) / 256.0, phi = 2.0 * 3.14159265358979 * (b + 0.5) / 512.0, r = sqrt(1.0 - z * z);
            pt_vec3 w = pt_v3((float)(r * cos(phi)), (float)(r * sin(phi)), (float)z);
            double m = (double)pt_pdf_value(&pdf, w);
            tot += m;
            if (pt_dot(w, n) < 0.0f) below += m;
            if (pt_dot(w, to) > cos(5.0 * 3.14159265358979 / 180.0)) in5 += m;
            if (pt_dot(w, to) > cos(15.0 * 3.14159265358979 / 180.0)) in15 += m;
        }
    printf("probe (%g %g %g): below the surface %.3f, within 5 deg %.4f (uniform 0.0019), within 15 deg %.4f (uniform 0.0170)\n",
           v[0], v[1], v[2], below / tot, in5 / tot, in15 / tot);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int main(int argc, char **argv)
{
    pt_scenefile sd;
    pt_scene *scene = NULL;
    pt_render_desc base;
    pt_image ref, img;
    char err[1024];
    int spp = 128, seeds = 3, i, k, rr = 0, have_probe = 0, guiding = PT_GUIDING_ON, threads = 1, spp_u = 0;
    pt_sampler sampler_u = PT_SAMPLER_INDEPENDENT, sampler_g = PT_SAMPLER_INDEPENDENT;
    float alpha = 0.0f, budget = 0.0f, pv[9];
    double floor_relmse = 0.0;
    const char *save = NULL;
    double ratio[MAX_SEEDS];
    if (argc < 3) {
        fprintf(stderr, "usage: guide_efficiency SCENE REF.pfm [--spp N] [--seeds N] [--alpha F] [--budget F] [--auto]\n"
                        "       [--rr-start N] [--probe X Y Z NX NY NZ TX TY TZ]\n");
        return 2;
    }
    for (i = 3; i < argc; ++i) {
        if (!strcmp(argv[i], "--spp") && i + 1 < argc) spp = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--seeds") && i + 1 < argc) seeds = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--alpha") && i + 1 < argc) alpha = (float)atof(argv[++i]);
        else if (!strcmp(argv[i], "--budget") && i + 1 < argc) budget = (float)atof(argv[++i]);
        else if (!strcmp(argv[i], "--auto")) guiding = PT_GUIDING_AUTO;
        else if (!strcmp(argv[i], "--save") && i + 1 < argc) save = argv[++i];
        else if (!strcmp(argv[i], "--threads") && i + 1 < argc) threads = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--floor") && i + 1 < argc) floor_relmse = atof(argv[++i]);
        else if (!strcmp(argv[i], "--spp-unguided") && i + 1 < argc) spp_u = atoi(argv[++i]);
        else if ((!strcmp(argv[i], "--sampler-unguided") || !strcmp(argv[i], "--sampler-guided")) && i + 1 < argc) {
            pt_sampler *which = !strcmp(argv[i], "--sampler-guided") ? &sampler_g : &sampler_u;
            ++i;
            if (!strcmp(argv[i], "sobol")) *which = PT_SAMPLER_SOBOL;
            else if (strcmp(argv[i], "independent")) { fprintf(stderr, "guide_efficiency: bad sampler '%s'\n", argv[i]); return 2; }
        }
        else if (!strcmp(argv[i], "--rr-start") && i + 1 < argc) rr = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--probe") && i + 9 < argc) {
            for (k = 0; k < 9; ++k) pv[k] = (float)atof(argv[++i]);
            have_probe = 1;
        } else {
            fprintf(stderr, "guide_efficiency: bad argument '%s'\n", argv[i]);
            return 2;
        }
    }
    if (spp_u == 0) spp_u = spp;
    if (spp < 1 || spp_u < 1 || threads < 1 || seeds < 1 || seeds > MAX_SEEDS) { fprintf(stderr, "guide_efficiency: bad --spp or --seeds\n"); return 2; }
    memset(&ref, 0, sizeof ref);
    memset(&img, 0, sizeof img);
    if (pt_scenefile_load(argv[1], &sd, err, sizeof err) != PT_OK || pt_scenefile_build(&sd, &scene, &base, err, sizeof err) != PT_OK ||
        pt_read_pfm(argv[2], &ref, err, sizeof err) != PT_OK) {
        fprintf(stderr, "guide_efficiency: %s\n", err);
        return 1;
    }
    base.width = ref.width;
    base.height = ref.height;
    base.samples_per_pixel = spp;
    base.threads = threads;
    base.strategy = PT_STRATEGY_MIS;
    base.rr_start_depth = rr;
    base.guiding_alpha = alpha;
    base.guiding_budget = budget;
    printf("%s at %dx%d, guided %d spp (%s), unguided %d spp (%s), %d thread(s), %s time, noise floor %.3g subtracted\n",
           argv[1], ref.width, ref.height, spp, sampler_g == PT_SAMPLER_SOBOL ? "sobol" : "independent", spp_u,
           sampler_u == PT_SAMPLER_SOBOL ? "sobol" : "independent", threads,
           threads > 1 ? "wall" : "CPU", floor_relmse);
    for (k = 0; k < seeds; ++k) {
        double eff[2];
        int g;
        for (g = 0; g < 2; ++g) {
            pt_render_desc d = base;
            pt_film film;
            pt_render_stats st;
            pt_guide *guide = NULL;
            double t0, t, e;
            d.seed = (uint64_t)(101 + k);
            d.guiding = g ? (pt_guiding)guiding : PT_GUIDING_OFF;
            d.sampler = g ? sampler_g : sampler_u;
            if (!g) d.samples_per_pixel = spp_u;
            if (g && have_probe && k == 0 && pt_guide_create_for_scene(scene, NULL, &guide) == PT_OK) d.guiding_guide = guide;
            if (pt_film_init(&film, d.width, d.height) != PT_OK) return 1;
            t0 = threads > 1 ? wall_seconds() : cpu_seconds();
            if (pt_render(scene, &d, &film, &st) != PT_OK) { fprintf(stderr, "guide_efficiency: %s\n", st.error); return 1; }
            t = (threads > 1 ? wall_seconds() : cpu_seconds()) - t0;
            pt_film_resolve(&film, &img);
            e = rel_mse(&img, &ref) - floor_relmse;
            if (save && k == 0) {
                char path[1024];
                snprintf(path, sizeof path, "%s-%s.pfm", save, g ? "guided" : "unguided");
                if (pt_write_pfm(path, &img) != PT_OK) fprintf(stderr, "guide_efficiency: cannot write %s\n", path);
            }
            eff[g] = 1.0 / (e * t);
            printf("seed %d %-8s relMSE %.5g  cpu %6.2f s  efficiency %.4g  rays/sample %.2f  guided vertices/sample %.2f  leaves %u  "
                   "NaN/Inf %llu  photons %llu (%.2f s)  %s\n",
                   101 + k, g ? "guided" : "unguided", e, t, eff[g],
                   (double)(st.camera_rays + st.bounce_rays + st.shadow_rays) / (double)st.samples,
                   (double)st.guided_vertices / (double)st.samples, (unsigned)st.guiding_leaves,
                   (unsigned long long)st.nonfinite_samples, (unsigned long long)st.guiding_photons, st.guiding_photon_seconds,
                   st.guiding_note);
            if (guide) probe(guide, pv);
            pt_guide_destroy(guide);
            pt_film_free(&film);
        }
        ratio[k] = eff[1] / eff[0];
    }
    qsort(ratio, (size_t)seeds, sizeof ratio[0], cmp_double);
    printf("median efficiency guided / unguided: %.3f\n", ratio[seeds / 2]);
    pt_image_free(&img);
    pt_image_free(&ref);
    pt_scene_destroy(scene);
    pt_scenefile_free(&sd);
    return 0;
}
