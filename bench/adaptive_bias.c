/* adaptive_bias.c - is adaptive sampling's image mean the uniform render's? A measurement, not a
   test: renders SCENE K times with adaptive sampling (seeds 1..K) and K_r times uniformly at a
   high sample count (seeds 1001..1000+K_r), and compares the mean of the whole image and of each
   of 4x4 regions, per channel, with standard errors from the spread over the seeds (Welch's t,
   Welch-Satterthwaite degrees of freedom; Sidak-corrected over the 3 x 17 tests (16 regions and the image), family
   alpha 0.01). Prints one line per failing test and a summary line.

   Build and run (from the repository's top level):
     cc -std=c99 -O2 -I. -pthread -o build/adaptive_bias bench/adaptive_bias.c -lm
     build/adaptive_bias scenes/cornell.scene --size 64x64 --spp 256 --threshold 0.1 --seeds 32
   Options: --size WxH, --spp N (the adaptive cap), --threshold T, --seeds K, --ref-spp N,
   --ref-seeds K, --mode own-samples|neighbours|pilot, --min-spp N, --threads N, --ref-cache FILE
   (the reference's statistics: read if it holds --ref-seeds seeds, else written; the caller keeps
   scene, size and --ref-spp the same). */
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RX 4
#define RY 4
#define MAX_SEEDS 256
#define FAMILY_ALPHA 0.01

/* The regularised incomplete beta function I_x(a, b) by its continued fraction (Abramowitz &
   Stegun 26.5.8), evaluated with the modified Lentz method; x < (a+1)/(a+b+2) directly, else by
   the symmetry I_x(a, b) = 1 - I_{1-x}(b, a). */
static double beta_cf(double a, double b, double x)
{
    const double tiny = 1e-300;
    double c = 1.0, d = 1.0 - (a + b) * x / (a + 1.0), f;
    int m;
    if (fabs(d) < tiny) d = tiny;
    d = 1.0 / d;
    f = d;
    for (m = 1; m < 500; ++m) {
        double num = m * (b - m) * x / ((a + 2.0 * m - 1.0) * (a + 2.0 * m)), delta;
        d = 1.0 + num * d; if (fabs(d) < tiny) d = tiny;
        c = 1.0 + num / c; if (fabs(c) < tiny) c = tiny;
        d = 1.0 / d; f *= d * c;
        num = -(a + m) * (a + b + m) * x / ((a + 2.0 * m) * (a + 2.0 * m + 1.0));
        d = 1.0 + num * d; if (fabs(d) < tiny) d = tiny;
        c = 1.0 + num / c; if (fabs(c) < tiny) c = tiny;
        d = 1.0 / d; delta = d * c; f *= delta;
        if (fabs(delta - 1.0) < 1e-14) break;
    }
    return f;
}
static double beta_inc(double a, double b, double x)
{
    double front;
    if (x <= 0.0) return 0.0;
    if (x >= 1.0) return 1.0;
    front = exp(lgamma(a + b) - lgamma(a) - lgamma(b) + a * log(x) + b * log(1.0 - x));
    if (x < (a + 1.0) / (a + b + 2.0)) return front * beta_cf(a, b, x) / a;
    return 1.0 - front * beta_cf(b, a, 1.0 - x) / b;
}
/* P(|T| > t) for Student's t with df degrees of freedom: I_{df/(df+t^2)}(df/2, 1/2). */
static double t_two_sided(double t, double df) { return beta_inc(0.5 * df, 0.5, df / (df + t * t)); }

typedef struct stats {
    double sum[RX * RY + 1][3], sq[RX * RY + 1][3]; /* region means over the seeds; index RX*RY: the image */
    int n;
} stats;

/* Adds one film's region means (of the pixel means) to s. */
static void add_film(stats *s, const pt_film *f)
{
    double acc[RX * RY + 1][3];
    int cnt[RX * RY + 1], x, y, c, r;
    memset(acc, 0, sizeof acc);
    memset(cnt, 0, sizeof cnt);
    for (y = 0; y < f->height; ++y)
        for (x = 0; x < f->width; ++x) {
            size_t i = (size_t)y * (size_t)f->width + (size_t)x;
            int reg = (y * RY / f->height) * RX + x * RX / f->width;
            for (c = 0; c < 3; ++c) {
                double m = f->sum[3 * i + c] / (double)f->count[i];
                acc[reg][c] += m;
                acc[RX * RY][c] += m;
            }
            cnt[reg]++;
            cnt[RX * RY]++;
        }
    for (r = 0; r <= RX * RY; ++r)
        for (c = 0; c < 3; ++c) {
            double m = acc[r][c] / cnt[r];
            s->sum[r][c] += m;
            s->sq[r][c] += m * m;
        }
    s->n++;
}
static void mean_var(const stats *s, int r, int c, double *m, double *v)
{
    *m = s->sum[r][c] / s->n;
    *v = (s->sq[r][c] - s->n * *m * *m) / (s->n - 1);
    if (*v < 0) *v = 0;
}

int main(int argc, char **argv)
{
    const char *path = NULL, *mode = "default", *cache = NULL;
    int w = 64, h = 64, spp = 256, seeds = 32, ref_spp = 2048, ref_seeds = 16, min_spp = 0, threads = 0, i, k, c, r;
    double threshold = 0.1, samples = 0.0, uniform_samples;
    char err[1024];
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc base;
    stats A, R;
    int fails = 0, tests = 0;
    double alpha, worst_p = 1.0;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--size") && v && sscanf(v, "%dx%d", &w, &h) == 2) ++i;
        else if (!strcmp(a, "--spp") && v) spp = atoi(argv[++i]);
        else if (!strcmp(a, "--threshold") && v) threshold = atof(argv[++i]);
        else if (!strcmp(a, "--seeds") && v) seeds = atoi(argv[++i]);
        else if (!strcmp(a, "--ref-spp") && v) ref_spp = atoi(argv[++i]);
        else if (!strcmp(a, "--ref-seeds") && v) ref_seeds = atoi(argv[++i]);
        else if (!strcmp(a, "--min-spp") && v) min_spp = atoi(argv[++i]);
        else if (!strcmp(a, "--threads") && v) threads = atoi(argv[++i]);
        else if (!strcmp(a, "--mode") && v) mode = argv[++i];
        else if (!strcmp(a, "--ref-cache") && v) cache = argv[++i];
        else if (a[0] != '-' && !path) path = a;
        else { fprintf(stderr, "adaptive_bias: bad argument '%s' (see the comment at the top of the source)\n", a); return 2; }
    }
    if (!path || w <= 0 || h <= 0 || spp <= 0 || seeds < 2 || seeds > MAX_SEEDS || ref_seeds < 2 || ref_spp <= 0) {
        fprintf(stderr, "usage: adaptive_bias SCENE [--size WxH --spp N --threshold T --seeds K --ref-spp N "
                        "--ref-seeds K --mode M --min-spp N --threads N]\n");
        return 2;
    }
    if (pt_scenefile_load(path, &sf, err, sizeof err) != PT_OK || pt_scenefile_build(&sf, &scene, &base, err, sizeof err) != PT_OK) {
        fprintf(stderr, "adaptive_bias: %s\n", err);
        return 1;
    }
    base.width = w;
    base.height = h;
    base.threads = threads;
    memset(&A, 0, sizeof A);
    memset(&R, 0, sizeof R);
    if (cache) { /* the reference's statistics from an earlier run with the same scene, size and reference */
        FILE *cf = fopen(cache, "rb");
        if (cf) {
            if (fread(&R, sizeof R, 1, cf) != 1 || R.n != ref_seeds) memset(&R, 0, sizeof R);
            fclose(cf);
        }
    }
    for (k = R.n ? ref_seeds : 0; k < ref_seeds + seeds; ++k) {
        int ref = k < ref_seeds;
        pt_render_desc d = base;
        pt_film f;
        pt_render_stats st;
        d.seed = ref ? 1001u + (uint64_t)k : 1u + (uint64_t)(k - ref_seeds);
        d.samples_per_pixel = ref ? ref_spp : spp;
        if (!ref) {
            d.adaptive_threshold = (float)threshold;
            d.adaptive_min_spp = min_spp;
            if (!strcmp(mode, "neighbours")) d.adaptive_neighbours_only = 1;
            else if (!strcmp(mode, "own-samples")) d.adaptive_mode = PT_ADAPTIVE_OWN_SAMPLES;
            else if (!strcmp(mode, "pilot")) d.adaptive_mode = PT_ADAPTIVE_PILOT;
            else if (strcmp(mode, "default")) { fprintf(stderr, "adaptive_bias: unknown mode '%s'\n", mode); return 2; }
        }
        if (pt_film_init(&f, w, h) != PT_OK || pt_render(scene, &d, &f, &st) != PT_OK) {
            fprintf(stderr, "adaptive_bias: render failed: %s\n", st.error);
            return 1;
        }
        if (!ref) samples += (double)st.samples;
        add_film(ref ? &R : &A, &f);
        pt_film_free(&f);
        if (ref && k == ref_seeds - 1 && cache) {
            FILE *cf = fopen(cache, "wb");
            if (!cf || fwrite(&R, sizeof R, 1, cf) != 1) fprintf(stderr, "adaptive_bias: cannot write %s\n", cache);
            if (cf) fclose(cf);
        }
    }
    uniform_samples = (double)seeds * w * h * spp;
    alpha = 1.0 - pow(1.0 - FAMILY_ALPHA, 1.0 / (3.0 * (RX * RY + 1)));
    printf("%s %dx%d, adaptive (%s) T %g, cap %d spp, %d seeds: %.1f %% of the cap's samples; reference %d x %d spp\n",
           path, w, h, mode, threshold, spp, seeds, 100.0 * samples / uniform_samples, ref_seeds, ref_spp);
    for (r = 0; r <= RX * RY; ++r)
        for (c = 0; c < 3; ++c) {
            double ma, va, mr, vr, sa, sr, se, t, df, p;
            mean_var(&A, r, c, &ma, &va);
            mean_var(&R, r, c, &mr, &vr);
            sa = va / A.n;
            sr = vr / R.n;
            se = sqrt(sa + sr);
            t = se > 0 ? (ma - mr) / se : 0.0;
            df = (sa + sr) * (sa + sr) / (sa * sa / (A.n - 1) + sr * sr / (R.n - 1) + 1e-300);
            p = t_two_sided(fabs(t), df);
            if (r == RX * RY)
                printf("image %c: adaptive %.5f, reference %.5f: %+.3f %% (t %+.2f, %.3f %% s.e.)\n", "RGB"[c], ma, mr,
                       100.0 * (ma / mr - 1.0), t, 100.0 * se / mr);
            tests++;
            if (p < worst_p) worst_p = p;
            if (p < alpha) {
                fails++;
                printf("FAIL %s (%d, %d) %c: adaptive %.5f, reference %.5f: %+.3f %% (t %+.2f, df %.0f, p %.2g)\n",
                       r == RX * RY ? "image" : "region", r % RX,
                       r / RX, "RGB"[c], ma, mr, 100.0 * (ma / mr - 1.0), t, df, p);
            }
        }
    {   /* the regions' relative differences, channel G, as a 4x4 table */
        int y;
        printf("region mean / reference - 1, channel G (%%):\n");
        for (y = 0; y < RY; ++y) {
            int x;
            for (x = 0; x < RX; ++x) {
                double ma, va, mr, vr;
                mean_var(&A, y * RX + x, 1, &ma, &va);
                mean_var(&R, y * RX + x, 1, &mr, &vr);
                printf(" %+7.3f", 100.0 * (ma / mr - 1.0));
            }
            printf("\n");
        }
    }
    printf("%s: %d of %d tests fail (per-test alpha %.3g: Sidak over %d at %.2f); smallest p %.3g\n",
           fails ? "FAIL" : "PASS", fails, tests, alpha, tests, FAMILY_ALPHA, worst_p);
    pt_scene_destroy(scene);
    pt_scenefile_free(&sf);
    return fails ? 3 : 0;
}
