/* ptv.c - pdftrace validation tool: renders scene files, exports them to POV-Ray, compares
   pdftrace's images with POV-Ray's and writes the report; `ptv test` is the fast runner used
   by `make test` (malformed scene files, and the fast POV-Ray comparisons when povray is
   installed).

     ptv render SCENE MEAN.pfm VAR.pfm [W H SPP]      mean and variance of the mean per pixel
                                                     (PTV_GUIDING=on|auto|off: path guiding)
     ptv pov SCENE OUT.pov [none|default|medium|high] [W H]
     ptv compare NAME MEAN.pfm VAR.pfm REF.exr OUTDIR BIAS_TOL POV_ERR ACCEPT [NOTE...]
     ptv report OUTDIR NAME...                       OUTDIR/index.html from OUTDIR/NAME.result
     ptv test SCENEDIR WORKDIR [PDFTRACE CORNELL]    the fast runner ("N passed, M failed, K skipped");
                                                     with build/pdftrace and build/cornell, also the
                                                     scene-file renders through the command

   Metrics (compare), over all pixels p and channels c, x = pdftrace, r = POV-Ray:
     bias_c   = sum_p x / sum_p r - 1                (mean relative bias per channel)
     relMSE   = mean (x - r)^2 / (r^2 + 0.01)
     e_p      = mean_c |x - r| / (r + 0.01)           per-pixel relative error, percentiles
     z-test   : |x - r| <= 3.29 sqrt(var_x + (POV_ERR r)^2 + (5e-4 r)^2 + 1e-8) in every
                channel (3.29 = two-sided alpha 0.001; var_x = pdftrace's variance of the pixel
                mean from pt_film_pixel; POV_ERR = POV-Ray's own error, from the recipe's
                tolerance table; 5e-4 = half-float rounding of the EXR).
   A scene passes when every |bias_c| <= BIAS_TOL and the accepted fraction >= ACCEPT
   (ACCEPT 0: the z-test is reported, not required).
   Built with -DPTV_HAVE_EXR (OpenEXR Core C API) and -DPTV_HAVE_PNG (libpng) when present. */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
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

#include "ptv_common.h"

/* ---- comparison ----------------------------------------------------------------------- */

typedef struct metrics {
    double bias[3], relmse, p50, p90, p99, accepted;
    double bias_tol, pov_err, accept_req;
    int pass;
} metrics;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Computes the metrics; writes NAME-err.png (red: pdftrace brighter, blue: darker; full
   colour at 5 % relative difference of the channel mean) into outdir when outdir != NULL. */
PTV_MAYBE_UNUSED static int compare(const pt_image *x, const pt_image *var, const pt_image *r, metrics *m, const char *outdir,
                   const char *name)
{
    size_t n = (size_t)x->width * (size_t)x->height, i;
    double sx[3] = {0, 0, 0}, sr[3] = {0, 0, 0}, mse = 0;
    double *e;
    unsigned char *map;
    size_t acc = 0;
    int c;
    if (x->width != r->width || x->height != r->height || var->width != x->width || var->height != x->height) {
        fprintf(stderr, "ptv: %s: image sizes differ (%dx%d vs %dx%d)\n", name, x->width, x->height, r->width, r->height);
        return 0;
    }
    e = (double *)malloc(n * sizeof *e);
    map = (unsigned char *)malloc(n * 3u);
    if (!e || !map) { free(e); free(map); return 0; }
    for (i = 0; i < n; ++i) {
        double ep = 0, sd = 0, ok = 1;
        for (c = 0; c < 3; ++c) {
            double xv = x->rgb[3 * i + c], rv = r->rgb[3 * i + c], vv = var->rgb[3 * i + c];
            double sigma = sqrt(vv + m->pov_err * m->pov_err * rv * rv + 2.5e-7 * rv * rv + 1e-8);
            sx[c] += xv;
            sr[c] += rv;
            mse += (xv - rv) * (xv - rv) / (rv * rv + 0.01);
            ep += fabs(xv - rv) / (fabs(rv) + 0.01) / 3.0;
            sd += (xv - rv) / 3.0;
            if (!(fabs(xv - rv) <= 3.29 * sigma)) ok = 0;
        }
        e[i] = ep;
        acc += ok ? 1u : 0u;
        {
            double rm = (r->rgb[3 * i] + r->rgb[3 * i + 1] + r->rgb[3 * i + 2]) / 3.0;
            double rel = sd / (rm + 0.01) / 0.05, a = fabs(rel) > 1 ? 1 : fabs(rel);
            unsigned char hi = (unsigned char)(255 * a + 0.5), lo = 0;
            map[3 * i + 0] = rel > 0 ? hi : lo;
            map[3 * i + 1] = lo;
            map[3 * i + 2] = rel < 0 ? hi : lo;
            if (!ok) map[3 * i + 1] = 255; /* rejected by the z-test: green added */
        }
    }
    for (c = 0; c < 3; ++c) m->bias[c] = sr[c] > 1e-9 * (double)n ? sx[c] / sr[c] - 1.0 : 0.0;
    m->relmse = mse / (3.0 * (double)n);
    qsort(e, n, sizeof *e, cmp_double);
    m->p50 = e[(size_t)(0.50 * (double)(n - 1))];
    m->p90 = e[(size_t)(0.90 * (double)(n - 1))];
    m->p99 = e[(size_t)(0.99 * (double)(n - 1))];
    m->accepted = (double)acc / (double)n;
    m->pass = m->accepted >= m->accept_req;
    for (c = 0; c < 3; ++c)
        if (!(fabs(m->bias[c]) <= m->bias_tol)) m->pass = 0;
    if (outdir) {
        char path[2048];
        snprintf(path, sizeof path, "%s/%s-err.png", outdir, name);
        if (!write_png(path, x->width, x->height, map)) m->pass = 0;
    }
    free(e);
    free(map);
    return 1;
}

PTV_MAYBE_UNUSED static void print_metrics(const char *name, const metrics *m)
{
    printf("%s %s: bias %+.3f%% %+.3f%% %+.3f%% (tol %.1f%%), relMSE %.2e, rel.err p50 %.2f%% p90 %.2f%% p99 %.2f%%, "
           "z-test accepted %.2f%% (need %.0f%%)\n",
           m->pass ? "PASS" : "FAIL", name, 100 * m->bias[0], 100 * m->bias[1], 100 * m->bias[2], 100 * m->bias_tol,
           m->relmse, 100 * m->p50, 100 * m->p90, 100 * m->p99, 100 * m->accepted, 100 * m->accept_req);
}

/* ---- comparison with Mitsuba 3 ---------------------------------------------------------- */

/* Per-seed 4 x 4 region means, as validation/mitsuba_render.py and `ptv render ... SEEDS`
   write them: pixel (x, y), y from the top, is in region (4x / w, 4y / h); m[48 k + 3 r + c]
   is seed k's mean of channel c over region r (row-major, top-left first). The file is
   "pt-regions W H K DOF" and K lines of 48 numbers; DOF: the degrees of freedom of the
   variance image written with it (K - 1 from seeds alone, K * spp - 1 from every sample). */
typedef struct seed_regions {
    int w, h, k;
    double dof; /* degrees of freedom of the matching variance image */
    double *m;
} seed_regions;

#define PTV_REGIONS 16

/* The two-sided standard normal quantile: z with erfc(z / sqrt 2) = alpha, by bisection. */
static double normal_quantile2(double alpha)
{
    double lo = 0, hi = 40;
    int i;
    for (i = 0; i < 200; ++i) {
        double mid = 0.5 * (lo + hi);
        if (erfc(mid / sqrt(2.0)) > alpha) lo = mid;
        else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* The two-sided Student t quantile for nu degrees of freedom from the normal one, by the
   asymptotic expansion of Abramowitz & Stegun 26.7.5 (good to ~1e-3 for nu >= 7 at the tails
   used here). */
static double t_quantile2(double z, double nu)
{
    double z2 = z * z, z3 = z2 * z, z5 = z3 * z2, z7 = z5 * z2, z9 = z7 * z2;
    double g1 = (z3 + z) / 4, g2 = (5 * z5 + 16 * z3 + 3 * z) / 96;
    double g3 = (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / 384;
    double g4 = (79 * z9 + 776 * z7 + 1482 * z5 - 1920 * z3 - 945 * z) / 92160;
    if (!(nu < 1e12)) return z;
    return z + g1 / nu + g2 / (nu * nu) + g3 / (nu * nu * nu) + g4 / (nu * nu * nu * nu);
}

/* Welch-Satterthwaite degrees of freedom of a + b, variances with na and nb degrees of freedom. */
static double welch_dof(double a, double na, double b, double nb)
{
    double d = a * a / na + b * b / nb;
    return d > 0 ? (a + b) * (a + b) / d : 1e30;
}

typedef struct mi_metrics {
    double bias[3], se[3];       /* channel mean bias (x / r - 1) and its standard error, from the seeds */
    double relmse, p50, p90, p99; /* as for POV-Ray (compare) */
    double accepted;             /* fraction of pixels the per-pixel test accepts in every channel */
    double region_worst;         /* largest |t| / critical value over the 48 region tests */
    int region_rejected;         /* region tests that reject */
    int use_region;              /* 1: the region test decides, 0: the per-pixel test (>= 99 %) */
    int bias_ok, pixel_ok, region_ok, pass;
} mi_metrics;

/* Seed k's mean of channel c over the whole image, from its region means (weighted by the
   number of pixels in each region). */
static double seed_image_mean(const seed_regions *s, int k, int c)
{
    double sum = 0;
    int r;
    for (r = 0; r < PTV_REGIONS; ++r) {
        int rx = r % 4, ry = r / 4;
        /* region rx holds the x with 4x / w == rx: x in [ceil(rx w / 4), ceil((rx + 1) w / 4)) */
        double nx = (double)(((rx + 1) * s->w + 3) / 4 - (rx * s->w + 3) / 4);
        double ny = (double)(((ry + 1) * s->h + 3) / 4 - (ry * s->h + 3) / 4);
        sum += nx * ny * s->m[48 * k + 3 * r + c];
    }
    return sum / ((double)s->w * (double)s->h);
}

/* Mean and variance of that mean over the seeds of a per-seed quantity q[k]. */
static void seeds_mean_var(const double *q, int k, double *mean, double *var)
{
    double s = 0, ss = 0;
    int i;
    for (i = 0; i < k; ++i) s += q[i];
    *mean = s / k;
    for (i = 0; i < k; ++i) ss += (q[i] - *mean) * (q[i] - *mean);
    *var = ss / (k - 1) / k;
}

/* Per channel: bias = mean_x / mean_r - 1 with the standard error of the ratio (first-order),
   each mean's variance from its seeds. Pass iff |bias| <= 3 SE and <= 0.5 %. */
static void mi_bias(const seed_regions *x, const seed_regions *r, mi_metrics *m)
{
    double qx[256], qr[256];
    int c, k;
    m->bias_ok = 1;
    for (c = 0; c < 3; ++c) {
        double mx, vx, mr, vr;
        for (k = 0; k < x->k; ++k) qx[k] = seed_image_mean(x, k, c);
        for (k = 0; k < r->k; ++k) qr[k] = seed_image_mean(r, k, c);
        seeds_mean_var(qx, x->k, &mx, &vx);
        seeds_mean_var(qr, r->k, &mr, &vr);
        if (mr > 1e-9) {
            m->bias[c] = mx / mr - 1;
            m->se[c] = sqrt(vx / (mr * mr) + mx * mx * vr / (mr * mr * mr * mr));
        } else {
            m->bias[c] = mx - mr; /* a black channel: the absolute difference */
            m->se[c] = sqrt(vx + vr);
        }
        if (!(fabs(m->bias[c]) <= 3 * m->se[c] + 1e-7 && fabs(m->bias[c]) <= 0.005)) m->bias_ok = 0;
    }
}

/* The region test: per region and channel, Welch's t on the seeds' region means, two-sided,
   Sidak-corrected to a family-wise alpha of 0.01 over the 48 tests. */
static void mi_regions(const seed_regions *x, const seed_regions *r, mi_metrics *m)
{
    double qx[256], qr[256], a1 = 1 - pow(1 - 0.01, 1.0 / (3 * PTV_REGIONS)), z = normal_quantile2(a1);
    int i, k;
    m->region_worst = 0;
    m->region_rejected = 0;
    for (i = 0; i < 3 * PTV_REGIONS; ++i) {
        double mx, vx, mr, vr, ratio;
        for (k = 0; k < x->k; ++k) qx[k] = x->m[48 * k + i];
        for (k = 0; k < r->k; ++k) qr[k] = r->m[48 * k + i];
        seeds_mean_var(qx, x->k, &mx, &vx);
        seeds_mean_var(qr, r->k, &mr, &vr);
        /* (1e-5 r)^2 + 1e-12: float rounding, so noiseless regions (a uniform background seen
           directly) compare to rounding (Mitsuba stores an RGB 0.7 as 0.6999983) */
        ratio = fabs(mx - mr) / sqrt(vx + vr + 1e-10 * mr * mr + 1e-12) /
                (vx + vr > 0 ? t_quantile2(z, welch_dof(vx, x->k - 1, vr, r->k - 1)) : z);
        if (!(ratio <= 1)) ++m->region_rejected;
        if (!(ratio <= m->region_worst)) m->region_worst = ratio;
    }
    m->region_ok = m->region_rejected == 0;
}

/* The per-pixel test with both renderers' noise: in every channel
   |x - r| <= t * sqrt(var_x + var_r + (1e-5 r)^2 + 1e-12), t the two-sided alpha = 0.001
   quantile of Student's t at the Welch-Satterthwaite degrees of freedom (1e-5 r: float
   rounding of two sums). Writes the error map (as compare's) to map when map != NULL. */
static void mi_pixels(const pt_image *x, const pt_image *vx, double nx, const pt_image *r, const pt_image *vr, double nr,
                      mi_metrics *m, unsigned char *map)
{
    size_t n = (size_t)x->width * (size_t)x->height, i, acc = 0;
    double z = normal_quantile2(0.001);
    for (i = 0; i < n; ++i) {
        int c, ok = 1;
        double sd = 0, rm = 0;
        for (c = 0; c < 3; ++c) {
            size_t j = 3 * i + (size_t)c;
            double d = (double)x->rgb[j] - (double)r->rgb[j], a = vx->rgb[j], b = vr->rgb[j], rv = r->rgb[j];
            double sigma = sqrt(a + b + 1e-10 * rv * rv + 1e-12);
            double t = a + b > 0 ? t_quantile2(z, welch_dof(a, nx, b, nr)) : z;
            if (!(fabs(d) <= t * sigma)) ok = 0;
            sd += d / 3;
            rm += rv / 3;
        }
        acc += ok ? 1u : 0u;
        if (map) {
            double rel = sd / (rm + 0.01) / 0.05, a = fabs(rel) > 1 ? 1 : fabs(rel);
            unsigned char hi = (unsigned char)(255 * a + 0.5);
            map[3 * i + 0] = rel > 0 ? hi : 0;
            map[3 * i + 1] = ok ? 0 : 255; /* rejected: green added */
            map[3 * i + 2] = rel < 0 ? hi : 0;
        }
    }
    m->accepted = (double)acc / (double)n;
    m->pixel_ok = m->accepted >= 0.99;
}

/* Every test of a Mitsuba comparison; the scene passes on the bias test and on the per-pixel
   test (use_region 0) or the region test (use_region 1). Returns 0 when the inputs disagree
   in size. */
static int compare_mitsuba(const pt_image *x, const pt_image *vx, const seed_regions *sx, const pt_image *r,
                           const pt_image *vr, const seed_regions *sr, int use_region, mi_metrics *m, unsigned char *map)
{
    metrics pm;
    int same = x->width == r->width && x->height == r->height;
    same = same && vx->width == x->width && vx->height == x->height && vr->width == x->width && vr->height == x->height;
    same = same && sx->w == x->width && sx->h == x->height && sr->w == x->width && sr->h == x->height;
    if (!same || sx->k < 2 || sr->k < 2) return 0;
    memset(m, 0, sizeof *m);
    memset(&pm, 0, sizeof pm); /* compare's relMSE and error percentiles (its z-test is POV-Ray's) */
    if (!compare(x, vx, r, &pm, NULL, "mitsuba")) return 0;
    m->relmse = pm.relmse;
    m->p50 = pm.p50;
    m->p90 = pm.p90;
    m->p99 = pm.p99;
    m->use_region = use_region;
    mi_bias(sx, sr, m);
    mi_regions(sx, sr, m);
    mi_pixels(x, vx, sx->dof, r, vr, sr->dof, m, map);
    m->pass = m->bias_ok && (use_region ? m->region_ok : m->pixel_ok);
    return 1;
}

/* Reads a regions file (see seed_regions); 0 with a message when it is malformed. */
static int read_regions(const char *path, seed_regions *s)
{
    FILE *f = fopen(path, "r");
    char magic[16] = "";
    size_t i, n;
    s->m = NULL;
    if (!f) { fprintf(stderr, "ptv: cannot open %s: %s\n", path, strerror(errno)); return 0; }
    if (fscanf(f, "%15s %d %d %d %lf", magic, &s->w, &s->h, &s->k, &s->dof) != 5 || strcmp(magic, "pt-regions") ||
        s->w < 4 || s->h < 4 || s->w > 16384 || s->h > 16384 || s->k < 2 || s->k > 256 || !(s->dof >= 1)) {
        fprintf(stderr, "ptv: %s: not a regions file (pt-regions W H K DOF; W, H >= 4; 2 <= K <= 256)\n", path);
        fclose(f);
        return 0;
    }
    n = (size_t)s->k * 48u;
    s->m = (double *)malloc(n * sizeof *s->m);
    for (i = 0; s->m && i < n; ++i)
        if (fscanf(f, "%lf", &s->m[i]) != 1 || !isfinite(s->m[i])) break;
    fclose(f);
    if (!s->m || i != n) {
        fprintf(stderr, "ptv: %s: expected %d lines of 48 finite numbers\n", path, s->k);
        free(s->m);
        s->m = NULL;
        return 0;
    }
    return 1;
}

/* Writes a regions file from k images of w x h (top row first), with the given DOF. */
static int write_regions(const char *path, const pt_image *imgs, int k, double dof)
{
    char tmp[2100];
    FILE *f;
    int s, ok;
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    f = fopen(tmp, "w");
    if (!f) { fprintf(stderr, "ptv: cannot write %s\n", tmp); return 0; }
    fprintf(f, "pt-regions %d %d %d %.17g\n", imgs[0].width, imgs[0].height, k, dof);
    for (s = 0; s < k; ++s) {
        double sum[48] = {0};
        int cnt[PTV_REGIONS] = {0}, x, y, i;
        const pt_image *im = &imgs[s];
        for (y = 0; y < im->height; ++y)
            for (x = 0; x < im->width; ++x) {
                int reg = 4 * (4 * y / im->height) + 4 * x / im->width, c;
                ++cnt[reg];
                for (c = 0; c < 3; ++c) sum[3 * reg + c] += im->rgb[3 * ((size_t)y * (size_t)im->width + (size_t)x) + (size_t)c];
            }
        for (i = 0; i < 48; ++i) fprintf(f, "%s%.9g", i ? " " : "", cnt[i / 3] ? sum[i] / cnt[i / 3] : 0.0);
        fprintf(f, "\n");
    }
    ok = fclose(f) == 0 && rename(tmp, path) == 0;
    if (!ok) { remove(tmp); fprintf(stderr, "ptv: writing %s failed\n", path); }
    return ok;
}

PTV_MAYBE_UNUSED static void print_mi_metrics(const char *name, const mi_metrics *m)
{
    printf("%s %s (Mitsuba, %s test): bias %+.3f%%±%.3f %+.3f%%±%.3f %+.3f%%±%.3f (need <= 3 SE and 0.5%%), relMSE %.2e, "
           "rel.err p50 %.2f%% p90 %.2f%% p99 %.2f%%, pixels accepted %.2f%% (%s 99%%), regions rejected %d of 48 "
           "(worst |t|/crit %.2f%s)\n",
           m->pass ? "PASS" : "FAIL", name, m->use_region ? "region" : "pixel", 100 * m->bias[0], 100 * m->se[0],
           100 * m->bias[1], 100 * m->se[1], 100 * m->bias[2], 100 * m->se[2], m->relmse, 100 * m->p50, 100 * m->p90,
           100 * m->p99, 100 * m->accepted, m->use_region ? "reported; pixel test needs" : "need", m->region_rejected,
           m->region_worst, m->use_region ? "" : "; reported");
}

/* Renders sd K times with seeds seed, seed + 1, ... (W x H, SPP; 0: the scene's) into K images
   (*seeds, allocated here), their mean and the variance of that mean (the seeds' pt_film_pixel
   variances summed over K^2: every camera sample counted, K * spp - 1 degrees of freedom). */
static int render_seeds(const pt_scenefile *sd, int w, int h, int spp, int k, pt_image *mean, pt_image *var,
                        pt_image **seeds, int *spp_used)
{
    pt_scene *scene = NULL;
    pt_render_desc rd;
    pt_film film;
    pt_render_stats st;
    char err[1024];
    int rc = pt_scenefile_build(sd, &scene, &rd, err, sizeof err), s, ok = 1;
    size_t n;
    *seeds = NULL;
    if (rc != PT_OK) { fprintf(stderr, "ptv: %s\n", err); return 0; }
    if (w > 0) { rd.width = w; rd.height = h; }
    if (spp > 0) rd.samples_per_pixel = spp;
    *spp_used = rd.samples_per_pixel;
    n = 3 * (size_t)rd.width * (size_t)rd.height;
    *seeds = (pt_image *)calloc((size_t)k, sizeof **seeds);
    if (!*seeds || pt_film_init(&film, rd.width, rd.height) != PT_OK || pt_image_init(mean, rd.width, rd.height) != PT_OK ||
        pt_image_init(var, rd.width, rd.height) != PT_OK) {
        pt_scene_destroy(scene);
        fprintf(stderr, "ptv: out of memory\n");
        return 0;
    }
    memset(mean->rgb, 0, n * sizeof *mean->rgb);
    memset(var->rgb, 0, n * sizeof *var->rgb);
    for (s = 0; s < k && ok; ++s) {
        uint64_t seed0 = rd.seed;
        int x, y;
        rd.seed = seed0 + (uint64_t)s;
        pt_film_clear(&film);
        ok = pt_render(scene, &rd, &film, &st) == PT_OK && pt_image_init(&(*seeds)[s], rd.width, rd.height) == PT_OK;
        rd.seed = seed0;
        if (!ok) { fprintf(stderr, "ptv: render failed: %s\n", st.error); break; }
        for (y = 0; y < rd.height; ++y)
            for (x = 0; x < rd.width; ++x) {
                pt_color mc, vc;
                size_t j = 3 * ((size_t)y * (size_t)rd.width + (size_t)x);
                float *o = &(*seeds)[s].rgb[j];
                pt_film_pixel(&film, x, y, &mc, &vc);
                o[0] = mc.x; o[1] = mc.y; o[2] = mc.z;
                mean->rgb[j] += mc.x / (float)k; mean->rgb[j + 1] += mc.y / (float)k; mean->rgb[j + 2] += mc.z / (float)k;
                var->rgb[j] += vc.x / ((float)k * (float)k);
                var->rgb[j + 1] += vc.y / ((float)k * (float)k);
                var->rgb[j + 2] += vc.z / ((float)k * (float)k);
            }
    }
    pt_film_free(&film);
    pt_scene_destroy(scene);
    return ok;
}

/* ---- commands ------------------------------------------------------------------------- */

static int load(const char *path, pt_scenefile *sd)
{
    char err[1024];
    pt_scenefile_options opt;
    memset(&opt, 0, sizeof opt);
#ifdef PTV_HAVE_EXR
    opt.read_image = pt_read_exr_memory; /* `environment` maps in OpenEXR besides PFM */
#endif
#ifdef PTV_HAVE_PNG
    opt.read_png = pt_read_png_memory; /* PNG image textures */
#endif
    if (pt_scenefile_load_ex(path, &opt, sd, err, sizeof err) != PT_OK) { fprintf(stderr, "ptv: %s\n", err); return 0; }
    return 1;
}

static void free_images(pt_image *imgs, int k)
{
    int i;
    for (i = 0; imgs && i < k; ++i) pt_image_free(&imgs[i]);
    free(imgs);
}

/* render SCENE MEAN.pfm VAR.pfm [W H SPP [SEEDS REGIONS.txt]]: with SEEDS, SEEDS independent
   renders (render_seeds) and their per-seed region means, for compare-mitsuba. */
static int cmd_render(int argc, char **argv)
{
    pt_scenefile sd;
    pt_image mean = {0, 0, NULL}, var = {0, 0, NULL}, *seeds = NULL;
    int ok, w = 0, h = 0, spp = 0, k = 0, spp_used = 0;
    if (argc != 5 && argc != 8 && argc != 10) {
        fprintf(stderr, "usage: ptv render SCENE MEAN.pfm VAR.pfm [W H SPP [SEEDS REGIONS.txt]]\n");
        return 2;
    }
    if (argc >= 8) { w = atoi(argv[5]); h = atoi(argv[6]); spp = atoi(argv[7]); }
    if (argc == 10 && ((k = atoi(argv[8])) < 2 || k > 256 || w < 4 || h < 4)) {
        fprintf(stderr, "ptv: render: SEEDS must be in [2, 256] and W, H >= 4\n");
        return 2;
    }
    if (!load(argv[2], &sd)) return 1;
    if (getenv("PTV_GUIDING")) { /* validate.sh's *-guided rows: the scene rendered with path guiding */
        const char *g = getenv("PTV_GUIDING");
        sd.guiding = !strcmp(g, "on") ? PT_GUIDING_ON : !strcmp(g, "auto") ? PT_GUIDING_AUTO : PT_GUIDING_OFF;
    }
    ok = k ? render_seeds(&sd, w, h, spp, k, &mean, &var, &seeds, &spp_used) : render_desc(&sd, w, h, spp, &mean, &var);
    pt_scenefile_free(&sd);
    if (ok && k) ok = write_regions(argv[9], seeds, k, (double)k * spp_used - 1);
    if (ok) ok = pt_write_pfm(argv[3], &mean) == PT_OK && pt_write_pfm(argv[4], &var) == PT_OK;
    free_images(seeds, k);
    pt_image_free(&mean);
    pt_image_free(&var);
    if (!ok) fprintf(stderr, "ptv: render %s failed\n", argv[2]);
    return ok ? 0 : 1;
}

static int radiosity_level(const char *s)
{
    return !strcmp(s, "none") ? 0 : !strcmp(s, "default") ? 1 : !strcmp(s, "medium") ? 2 : !strcmp(s, "high") ? 3 : -1;
}

static int cmd_pov(int argc, char **argv)
{
    pt_scenefile sd;
    pt_pov_options o;
    char err[1024];
    int rc;
    if (argc != 4 && argc != 5 && argc != 7) { fprintf(stderr, "usage: ptv pov SCENE OUT.pov [none|default|medium|high] [W H]\n"); return 2; }
    memset(&o, 0, sizeof o);
    o.radiosity = argc >= 5 ? radiosity_level(argv[4]) : -1;
    if (argc >= 5 && o.radiosity < 0) { fprintf(stderr, "ptv: bad radiosity level '%s'\n", argv[4]); return 2; }
    if (argc == 7) { o.width = atoi(argv[5]); o.height = atoi(argv[6]); }
    if (!load(argv[2], &sd)) return 1;
    rc = pt_scenefile_write_pov(&sd, argv[3], &o, err, sizeof err);
    pt_scenefile_free(&sd);
    if (rc != PT_OK) { fprintf(stderr, "ptv: %s\n", err); return 1; }
    return 0;
}

static int cmd_compare(int argc, char **argv)
{
#ifdef PTV_HAVE_EXR
    pt_image x = {0, 0, NULL}, v = {0, 0, NULL}, r = {0, 0, NULL};
    metrics m;
    char path[2048];
    FILE *f;
    int ok, i;
    if (argc < 10) { fprintf(stderr, "usage: ptv compare NAME MEAN.pfm VAR.pfm REF.exr OUTDIR BIAS_TOL POV_ERR ACCEPT [NOTE...]\n"); return 2; }
    memset(&m, 0, sizeof m);
    m.bias_tol = atof(argv[7]);
    m.pov_err = atof(argv[8]);
    m.accept_req = atof(argv[9]);
    ok = read_pfm(argv[3], &x) && read_pfm(argv[4], &v) && read_exr(argv[5], &r) && compare(&x, &v, &r, &m, argv[6], argv[2]);
    if (ok) {
        snprintf(path, sizeof path, "%s/%s-pt.png", argv[6], argv[2]);
        ok = png_tonemapped(path, &x);
        snprintf(path, sizeof path, "%s/%s-pov.png", argv[6], argv[2]);
        ok = ok && png_tonemapped(path, &r);
    }
    if (ok) {
        print_metrics(argv[2], &m);
        snprintf(path, sizeof path, "%s/%s.result", argv[6], argv[2]);
        f = fopen(path, "w");
        if (!f) ok = 0;
        else {
            fprintf(f, "%d %d %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %d", x.width, x.height, m.bias[0],
                    m.bias[1], m.bias[2], m.relmse, m.p50, m.p90, m.p99, m.accepted, m.bias_tol, m.pov_err, m.accept_req, m.pass);
            for (i = 10; i < argc; ++i) fprintf(f, " %s", argv[i]);
            fprintf(f, "\n");
            ok = fclose(f) == 0;
        }
    }
    pt_image_free(&x);
    pt_image_free(&v);
    pt_image_free(&r);
    if (!ok) { fprintf(stderr, "ptv: compare %s failed\n", argv[2]); return 1; }
    return m.pass ? 0 : 3;
#else
    (void)argc; (void)argv;
    fprintf(stderr, "ptv: built without OpenEXR (install libopenexr-dev and rebuild): cannot compare\n");
    return 1;
#endif
}

/* Reads PREFIX.pfm, PREFIX-var.pfm and PREFIX-regions.txt. */
static int read_run(const char *prefix, pt_image *mean, pt_image *var, seed_regions *s)
{
    char path[2048];
    snprintf(path, sizeof path, "%s.pfm", prefix);
    if (!read_pfm(path, mean)) return 0;
    snprintf(path, sizeof path, "%s-var.pfm", prefix);
    if (!read_pfm(path, var)) return 0;
    snprintf(path, sizeof path, "%s-regions.txt", prefix);
    return read_regions(path, s);
}

/* Writes OUTDIR/NAME-mitsuba.result: one line of the numbers `report` reads, then the note. */
static int write_mi_result(const char *outdir, const char *name, const pt_image *x, const seed_regions *sx,
                           const seed_regions *sr, const mi_metrics *m, int argc, char **argv, int first_note)
{
    char path[2048];
    FILE *f;
    int i;
    snprintf(path, sizeof path, "%s/%s-mitsuba.result", outdir, name);
    f = fopen(path, "w");
    if (!f) { fprintf(stderr, "ptv: cannot write %s\n", path); return 0; }
    fprintf(f, "%d %d %d %d %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %.6g %d %d %d", x->width, x->height,
            sx->k, sr->k, m->bias[0], m->bias[1], m->bias[2], m->se[0], m->se[1], m->se[2], m->relmse, m->p50, m->p90,
            m->p99, m->accepted, m->region_worst, m->region_rejected, m->use_region, m->pass);
    for (i = first_note; i < argc; ++i) fprintf(f, " %s", argv[i]);
    fprintf(f, "\n");
    return fclose(f) == 0;
}

/* compare-mitsuba NAME PT_PREFIX MI_PREFIX OUTDIR pixel|region [NOTE...] */
static int cmd_compare_mitsuba(int argc, char **argv)
{
    pt_image x = {0, 0, NULL}, vx = {0, 0, NULL}, r = {0, 0, NULL}, vr = {0, 0, NULL};
    seed_regions sx = {0, 0, 0, 0, NULL}, sr = {0, 0, 0, 0, NULL};
    mi_metrics m;
    unsigned char *map = NULL;
    char path[2048];
    int ok, use_region;
    if (argc < 7 || (strcmp(argv[6], "pixel") && strcmp(argv[6], "region"))) {
        fprintf(stderr, "usage: ptv compare-mitsuba NAME PT_PREFIX MI_PREFIX OUTDIR pixel|region [NOTE...]\n");
        return 2;
    }
    use_region = !strcmp(argv[6], "region");
    ok = read_run(argv[3], &x, &vx, &sx) && read_run(argv[4], &r, &vr, &sr);
    if (ok) ok = (map = (unsigned char *)malloc(3 * (size_t)x.width * (size_t)x.height)) != NULL;
    if (ok && !compare_mitsuba(&x, &vx, &sx, &r, &vr, &sr, use_region, &m, map)) {
        fprintf(stderr, "ptv: %s: the pdftrace and Mitsuba images, variances and regions differ in size\n", argv[2]);
        ok = 0;
    }
    if (ok) {
        snprintf(path, sizeof path, "%s/%s-ptm.png", argv[5], argv[2]);
        ok = png_tonemapped(path, &x);
        snprintf(path, sizeof path, "%s/%s-mi.png", argv[5], argv[2]);
        ok = ok && png_tonemapped(path, &r);
        snprintf(path, sizeof path, "%s/%s-mierr.png", argv[5], argv[2]);
        ok = ok && write_png(path, x.width, x.height, map);
        ok = ok && write_mi_result(argv[5], argv[2], &x, &sx, &sr, &m, argc, argv, 7);
    }
    if (ok) print_mi_metrics(argv[2], &m);
    free(map);
    free(sx.m);
    free(sr.m);
    pt_image_free(&x);
    pt_image_free(&vx);
    pt_image_free(&r);
    pt_image_free(&vr);
    if (!ok) { fprintf(stderr, "ptv: compare-mitsuba %s failed\n", argv[2]); return 1; }
    return m.pass ? 0 : 3;
}

static void html_escape(FILE *f, const char *s)
{
    for (; *s; ++s) {
        if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else if (*s == '&') fputs("&amp;", f);
        else fputc(*s, f);
    }
}

/* The POV-Ray table of the report, one row per name; returns 1 when every row passed. */
static int report_pov(FILE *f, const char *outdir, char **names, int count)
{
    char path[2048], line[4096];
    int i, all = 1;
    fprintf(f, "<h2>pdftrace vs POV-Ray 3.7</h2>\n<p>bias<sub>c</sub> = &Sigma;x/&Sigma;r &minus; 1 per channel; relMSE = "
               "mean (x&minus;r)&sup2;/(r&sup2;+0.01); per-pixel error e = mean<sub>c</sub> |x&minus;r|/(r+0.01); z-test: "
               "|x&minus;r| &le; 3.29&middot;&radic;(var<sub>pdftrace</sub> + (pov_err&middot;r)&sup2; + (5e-4&middot;r)&sup2;) "
               "in every channel (two-sided &alpha; = 0.001 per channel). Error map: red = pdftrace brighter, blue = darker, "
               "full colour at 5 %%; green = pixel rejected by the z-test. Images sRGB-encoded, clipped at 1.</p>\n"
               "<table><tr><th>scene</th><th>size</th><th>bias R</th><th>bias G</th><th>bias B</th><th>bias tol</th>"
               "<th>relMSE</th><th>e p50</th><th>e p90</th><th>e p99</th><th>z-test accepted</th><th>required</th>"
               "<th>POV err</th><th>result</th><th>reference</th></tr>\n");
    for (i = 0; i < count; ++i) {
        FILE *r;
        int w = 0, h = 0, pass = 0, n = 0;
        double v[11];
        char *note = NULL;
        snprintf(path, sizeof path, "%s/%s.result", outdir, names[i]);
        r = fopen(path, "r");
        if (r && fgets(line, sizeof line, r)) {
            n = sscanf(line, "%d %d %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %d", &w, &h, &v[0], &v[1], &v[2], &v[3],
                       &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10], &pass);
            note = line;
            { int k; for (k = 0; k < 14 && note; ++k) { note = strchr(note, ' '); if (note) ++note; } }
            if (note) note[strcspn(note, "\n")] = '\0';
        }
        if (r) fclose(r);
        fprintf(f, "<tr><td><a href=\"#%s\">%s</a></td>", names[i], names[i]);
        if (n != 14) {
            fprintf(f, "<td colspan=\"14\" class=\"fail\">no result (render or comparison failed)</td></tr>\n");
            all = 0;
            continue;
        }
        all = all && pass;
        fprintf(f, "<td>%dx%d</td><td>%+.3f%%</td><td>%+.3f%%</td><td>%+.3f%%</td><td>&plusmn;%.1f%%</td><td>%.2e</td>"
                   "<td>%.2f%%</td><td>%.2f%%</td><td>%.2f%%</td><td>%.2f%%</td><td>%.0f%%</td><td>%.1f%%</td>"
                   "<td class=\"%s\">%s</td><td style=\"text-align:left\">",
                w, h, 100 * v[0], 100 * v[1], 100 * v[2], 100 * v[8], v[3], 100 * v[4], 100 * v[5], 100 * v[6],
                100 * v[7], 100 * v[10], 100 * v[9], pass ? "pass" : "fail", pass ? "PASS" : "FAIL");
        html_escape(f, note ? note : "");
        fprintf(f, "</td></tr>\n");
    }
    fprintf(f, "</table>\n");
    return all;
}

/* A row of a scene whose Mitsuba render is known to be wrong (validate.sh appends a line "known
   REASON" to its result) is KNOWN instead of FAIL only if the disagreement is the known one:
   pdftrace darker than Mitsuba in every channel, by at most 0.5 %. */
static int mi_known_fault(const double *bias)
{
    return bias[0] < 0 && bias[1] < 0 && bias[2] < 0 && bias[0] >= -0.005 && bias[1] >= -0.005 && bias[2] >= -0.005;
}

/* One row of the Mitsuba table from NAME-mitsuba.result: the numbers of write_mi_result, or a
   line "skip REASON" / "refused REASON" (neither passes nor fails), then optionally a line
   "known REASON". Returns 1 on a pass, 0 on a failure, 2 when skipped or not exported, 3 for
   the known disagreement of a known row. */
static int report_mi_row(FILE *f, const char *outdir, const char *name)
{
    char path[2048], line[4096], known[1024] = "", *note = NULL;
    FILE *r;
    int w = 0, h = 0, kx = 0, kr = 0, rej = 0, use_region = 0, pass = 0, n = 0, k, is_known = 0;
    double v[12];
    snprintf(path, sizeof path, "%s/%s-mitsuba.result", outdir, name);
    r = fopen(path, "r");
    if (r && fgets(line, sizeof line, r)) {
        line[strcspn(line, "\n")] = '\0';
        n = sscanf(line, "%d %d %d %d %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %d %d %d", &w, &h, &kx, &kr, &v[0],
                   &v[1], &v[2], &v[3], &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10], &v[11], &rej, &use_region, &pass);
        for (note = line, k = 0; k < 19 && note; ++k) { note = strchr(note, ' '); if (note) ++note; }
        if (fgets(known, sizeof known, r) && !strncmp(known, "known ", 6)) {
            known[strcspn(known, "\n")] = '\0';
            is_known = 1;
        }
    }
    if (r) fclose(r);
    fprintf(f, "<tr><td><a href=\"#%s\">%s</a></td>", name, name);
    if (n != 19) {
        int skipped = r && (!strncmp(line, "skip ", 5) || !strncmp(line, "refused ", 8));
        fprintf(f, "<td colspan=\"14\" class=\"%s\" style=\"text-align:left\">", skipped ? "" : "fail");
        if (skipped) html_escape(f, !strncmp(line, "skip ", 5) ? "SKIP: " : "not exported: ");
        html_escape(f, skipped ? strchr(line, ' ') + 1 : "no result (export, render or comparison failed)");
        fprintf(f, "</td></tr>\n");
        return skipped ? 2 : 0;
    }
    fprintf(f, "<td>%dx%d</td><td>%d / %d</td>", w, h, kx, kr);
    for (k = 0; k < 3; ++k) fprintf(f, "<td>%+.3f%% &plusmn; %.3f</td>", 100 * v[k], 100 * v[3 + k]);
    fprintf(f, "<td>%.2e</td><td>%.2f%% / %.2f%% / %.2f%%</td><td>%s%.2f%%</td><td>%s%d (%.2f)</td><td>%s</td>"
               "<td class=\"%s\">%s</td><td style=\"text-align:left\">",
            v[6], 100 * v[7], 100 * v[8], 100 * v[9], use_region ? "" : "<b>", 100 * v[10], use_region ? "<b>" : "", rej,
            v[11], use_region ? "region" : "pixel", pass ? "pass" : is_known && mi_known_fault(v) ? "known" : "fail",
            pass ? "PASS" : is_known && mi_known_fault(v) ? "KNOWN (Mitsuba at fault)" : "FAIL");
    if (is_known) {
        html_escape(f, pass ? "the known Mitsuba fault did not show (re-check it): " : known + 6);
        fputs("; ", f);
    }
    html_escape(f, note ? note : "");
    fprintf(f, "</td></tr>\n");
    if (is_known) printf("%s (Mitsuba): %s\n", name, pass ? "PASS, but the known Mitsuba fault did not show: re-check it"
                                                           : mi_known_fault(v) ? "KNOWN: Mitsuba is at fault (see the note)"
                                                                               : "FAIL: not the known Mitsuba fault");
    return pass ? 1 : is_known && mi_known_fault(v) ? 3 : 0;
}

/* The Mitsuba table of the report; returns 1 when no row failed; *skipped: rows skipped or
   not exported; *known: rows with the known disagreement of a renderer known to be wrong. */
static int report_mitsuba(FILE *f, const char *outdir, char **names, int count, int *skipped, int *known)
{
    int i, all = 1;
    fprintf(f, "<h2>pdftrace vs Mitsuba 3</h2>\n<p>Both renderers render the scene with K independent seeds. "
               "bias<sub>c</sub> = mean<sub>x</sub>/mean<sub>r</sub> &minus; 1 &plusmn; its standard error from the seeds; "
               "passes at |bias| &le; 3 SE and &le; 0.5 %% in every channel. The scene's test (bold) must pass too: "
               "<i>pixel</i>: &ge; 99 %% of pixels with |x&minus;r| &le; t&middot;&radic;(var<sub>x</sub> + var<sub>r</sub>) "
               "in every channel (Welch t, two-sided &alpha; = 0.001; pdftrace's variance from every sample, Mitsuba's "
               "from its seeds); <i>region</i>: 4&times;4 region means of the seeds, Welch t per region and channel, "
               "&Scaron;id&aacute;k-corrected to &alpha; = 0.01 over the 48 tests, none may reject (for scenes whose "
               "caustics make per-pixel variances unreliable). Error map as above.</p>\n"
               "<table><tr><th>scene</th><th>size</th><th>seeds pt / mi</th><th>bias R</th><th>bias G</th><th>bias B</th>"
               "<th>relMSE</th><th>e p50 / p90 / p99</th><th>pixels accepted</th><th>regions rejected (worst |t|/crit)</th>"
               "<th>test</th><th>result</th><th>note</th></tr>\n");
    for (i = 0; i < count; ++i) {
        int rc = report_mi_row(f, outdir, names[i]);
        if (rc == 0) all = 0;
        if (rc == 2) ++*skipped;
        if (rc == 3) ++*known;
    }
    fprintf(f, "</table>\n");
    return all;
}

/* 1 when name is one of names[0 .. count). */
static int listed(const char *name, char **names, int count)
{
    int i;
    for (i = 0; i < count; ++i)
        if (!strcmp(name, names[i])) return 1;
    return 0;
}

/* The images of one scene: the POV-Ray comparison's and/or the Mitsuba comparison's (when it
   wrote them: not for a skipped or refused row). */
static void report_images(FILE *f, const char *outdir, const char *name, int pov, int mi)
{
    char path[2048];
    snprintf(path, sizeof path, "%s/%s-mi.png", outdir, name);
    mi = mi && access(path, F_OK) == 0;
    if (!pov && !mi) return;
    fprintf(f, "<div class=\"scene\" id=\"%s\"><h2>%s</h2><table>", name, name);
    if (pov)
        fprintf(f, "<tr><td><img src=\"%s-pt.png\" alt=\"pdftrace\"><br>pdftrace</td><td><img src=\"%s-pov.png\" "
                   "alt=\"POV-Ray\"><br>POV-Ray</td><td><img src=\"%s-err.png\" alt=\"error map\"><br>error map</td></tr>",
                name, name, name);
    if (mi)
        fprintf(f, "<tr><td><img src=\"%s-ptm.png\" alt=\"pdftrace\"><br>pdftrace (Mitsuba run)</td><td><img "
                   "src=\"%s-mi.png\" alt=\"Mitsuba\"><br>Mitsuba 3</td><td><img src=\"%s-mierr.png\" alt=\"error map\"><br>"
                   "error map vs Mitsuba</td></tr>", name, name, name);
    fprintf(f, "</table></div>\n");
}

/* report OUTDIR [NAME...] [--mitsuba NAME...]: the POV-Ray rows, then the Mitsuba rows. */
static int cmd_report(int argc, char **argv)
{
    char index[2048], tmp[2100];
    FILE *f;
    int i, all = 1, npov, nmi = 0, skipped = 0, known = 0;
    char **pov = argv + 3, **mi = NULL, verdict[512];
    if (argc < 4) { fprintf(stderr, "usage: ptv report OUTDIR [NAME...] [--mitsuba NAME...]\n"); return 2; }
    for (npov = 0; 3 + npov < argc && strcmp(pov[npov], "--mitsuba"); ++npov) {}
    if (3 + npov < argc) { mi = pov + npov + 1; nmi = argc - 4 - npov; }
    snprintf(index, sizeof index, "%s/index.html", argv[2]);
    snprintf(tmp, sizeof tmp, "%s.tmp", index);
    f = fopen(tmp, "w");
    if (!f) { fprintf(stderr, "ptv: cannot write %s\n", tmp); return 1; }
    fprintf(f, "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>pdftrace validation</title>\n<style>\n"
               "body{font-family:sans-serif;margin:20px;background:#fafafa}table{border-collapse:collapse}"
               "td,th{border:1px solid #bbb;padding:4px 8px;text-align:right}th{background:#eee}"
               ".pass{color:#070;font-weight:bold}.fail{color:#b00;font-weight:bold}.known{color:#a60;font-weight:bold}"
               "img{width:256px;height:256px;image-rendering:pixelated;border:1px solid #888}"
               ".scene{margin:18px 0}.scene td{text-align:center;border:none}</style></head><body>\n"
               "<h1>pdftrace validation: POV-Ray 3.7 and Mitsuba 3</h1>\n");
    if (npov) all = report_pov(f, argv[2], pov, npov);
    if (nmi) all = report_mitsuba(f, argv[2], mi, nmi, &skipped, &known) && all;
    for (i = 0; i < npov; ++i) report_images(f, argv[2], pov[i], 1, listed(pov[i], mi, nmi));
    for (i = 0; i < nmi; ++i)
        if (!listed(mi[i], pov, npov)) report_images(f, argv[2], mi[i], 0, 1);
    snprintf(verdict, sizeof verdict, "%s%s", all ? "all compared scenes pass" : "some scenes FAIL",
             skipped ? "; Mitsuba rows skipped or not exported: " : "");
    if (skipped) snprintf(verdict + strlen(verdict), sizeof verdict - strlen(verdict), "%d", skipped);
    if (known)
        snprintf(verdict + strlen(verdict), sizeof verdict - strlen(verdict),
                 "; %d Mitsuba row(s) KNOWN: Mitsuba is at fault there (the row's note says why)", known);
    fprintf(f, "<p>Overall: <span class=\"%s\">%s</span></p></body></html>\n", all ? "pass" : "fail", verdict);
    if (fclose(f) != 0 || rename(tmp, index) != 0) { remove(tmp); fprintf(stderr, "ptv: writing %s failed\n", index); return 1; }
    printf("wrote %s: %s\n", index, verdict);
    return all ? 0 : 3;
}

/* ---- the fast runner ------------------------------------------------------------------ */

static int passed, failed, skipped;

static void result(int ok, const char *what, const char *detail)
{
    printf("%s %s%s%s\n", ok ? "PASS" : "FAIL", what, detail && *detail ? ": " : "", detail ? detail : "");
    if (ok) ++passed;
    else ++failed;
}

/* A test that cannot run here (a tool or library missing): counted as skipped, not passed. */
static void skip(const char *what, const char *reason)
{
    printf("SKIP %s: %s\n", what, reason);
    ++skipped;
}

typedef struct bad_case {
    const char *what, *text, *expect; /* expect: a substring of the message */
} bad_case;

static const char *const good_header = "camera look_from 0 1 -5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\n";

static const bad_case bad_cases[] = {
    {"unknown statement", "camera look_from 0 1 -5 look_at 0 0 0\nmaterial m lambertian .5 .5 .5\nspheer 0 0 0 1 m\n", "bad.scene:3: unknown statement 'spheer'"},
    {"missing field (truncated line)", "%Hsphere 0 0 0\n", "bad.scene:3: sphere radius: missing number"},
    {"not a number", "%Hsphere 0 0 zero 1 m\n", "bad.scene:3: sphere: 'zero' is not a number"},
    {"NaN", "%Hsphere 0 nan 0 1 m\n", "bad.scene:3: sphere: 'nan' is not finite"},
    {"infinity", "%Hquad 0 0 0 inf 0 0 0 1 0 m\n", "not finite"},
    {"huge number", "%Hsphere 1e300 0 0 1 m\n", "bad.scene:3: sphere: 1e300 is out of range"},
    {"huge but finite", "%Hsphere 2e7 0 0 1 m\n", "out of range"},
    {"negative radius", "%Hsphere 0 0 0 -1 m\n", "radius must be > 0"},
    {"undefined material", "%Hsphere 0 0 0 1 steel\n", "bad.scene:3: sphere: material 'steel' is not defined"},
    {"extra tokens", "%Hsphere 0 0 0 1 m m\n", "unexpected 'm' after the end of the 'sphere' statement"},
    {"degenerate quad", "%Hquad 0 0 0 1 0 0 2 0 0 m\n", "quad: u and v are parallel"},
    {"inverted box", "%Hbox 1 1 1 0 0 0 m\n", "box: the first corner must be below"},
    {"no camera", "material m lambertian 1 1 1\nsphere 0 0 0 1 m\n", "bad.scene: no 'camera' statement"},
    {"camera twice", "%Hcamera look_from 0 0 1 look_at 0 0 0\n", "bad.scene:3: camera: defined twice"},
    {"camera up parallel", "camera look_from 0 5 0 look_at 0 0 0 up 0 1 0\n", "bad.scene:1: camera: look_from equals look_at, or up is parallel"},
    {"camera bad vfov", "camera look_from 0 0 -1 look_at 0 0 0 vfov 180\n", "camera vfov: must be in (0, 180)"},
    {"camera unknown key", "camera look_from 0 0 -1 look_at 0 0 0 fov 40\n", "camera: unknown key 'fov'"},
    {"no shapes", "%H", "bad.scene: no shapes"},
    {"negative colour", "%Hmaterial n lambertian 0.5 -0.1 0.5\n", "colour components must be >= 0"},
    {"duplicate name", "%Hmaterial m metal 1 1 1\n", "name 'm' is already defined"},
    {"roughconductor alpha above 1", "%Hmaterial r roughconductor 1.5 Au\n", "bad.scene:3: roughconductor alpha: must be in [0, 1]"},
    {"roughconductor unknown metal", "%Hmaterial r roughconductor 0.2 Pt\n", "bad.scene:3: roughconductor: unknown metal"},
    {"roughconductor no metal", "%Hmaterial r roughconductor 0.2\n", "bad.scene:3: roughconductor: missing metal"},
    {"roughconductor eta 0", "%Hmaterial r roughconductor 0.2 eta 0 1 1 k 1 1 1\n", "bad.scene:3: roughconductor eta: must be > 0"},
    {"roughconductor eta without k", "%Hmaterial r roughconductor 0.2 eta 1 1 1 1 1 1\n", "bad.scene:3: roughconductor: expected 'k R G B'"},
    {"roughconductor negative k", "%Hmaterial r roughconductor 0.2 eta 1 1 1 k 1 -1 1\n", "bad.scene:3: roughconductor k"},
    {"roughconductor negative tint", "%Hmaterial r roughconductor 0.2 Cu tint 1 -1 1\n", "bad.scene:3: roughconductor tint"},
    {"roughplastic alpha above 1", "%Hmaterial p roughplastic 1.5 0.5 0.5 0.5\n", "bad.scene:3: roughplastic alpha: must be in [0, 1]"},
    {"roughplastic albedo above 1", "%Hmaterial p roughplastic 0.2 0.5 1.5 0.5\n", "bad.scene:3: roughplastic albedo: must be in [0, 1]"},
    {"roughplastic ior 1", "%Hmaterial p roughplastic 0.2 0.5 0.5 0.5 ior 1\n", "bad.scene:3: roughplastic ior: must be in (1, 10]"},
    {"roughplastic unknown option", "%Hmaterial p roughplastic 0.2 0.5 0.5 0.5 shiny\n", "bad.scene:3: unexpected 'shiny'"},
    {"roughplastic no albedo", "%Hmaterial p roughplastic 0.2\n", "bad.scene:3: roughplastic albedo"},
    {"roughplastic unknown checker", "%Hmaterial p roughplastic 0.2 texture nope\n", "bad.scene:3: roughplastic: checker 'nope' is not defined"},
    {"roughplastic checker above 1", "%Hchecker c 0.1 0.1 0.1 1.2 1 1 1\nmaterial p roughplastic 0.2 texture c\n", "bad.scene:4: roughplastic: checker 'c' has a colour above 1"},
    {"roughdielectric alpha above 1", "%Hmaterial r roughdielectric 2 1.5\n", "bad.scene:3: roughdielectric alpha: must be in [0, 1]"},
    {"roughdielectric no ior", "%Hmaterial r roughdielectric 0.2\n", "bad.scene:3: roughdielectric ior"},
    {"roughdielectric ior below 1", "%Hmaterial r roughdielectric 0.2 0.5\n", "bad.scene:3: roughdielectric ior: must be in [1, 10]"},
    {"roughdielectric ext_ior missing", "%Hmaterial r roughdielectric 0.2 1.5 ext_ior\n", "bad.scene:3: roughdielectric ext_ior"},
    {"roughdielectric ext_ior above 10", "%Hmaterial r roughdielectric 0.2 1.5 ext_ior 11\n", "bad.scene:3: roughdielectric ext_ior: must be in [1, 10]"},
    {"roughdielectric trailing", "%Hmaterial r roughdielectric 0.2 1.5 1.33\n", "bad.scene:3:"},
    {"bad name", "%Hmaterial 9lives lambertian 1 1 1\n", "bad name '9lives'"},
    {"unknown material type", "%Hmaterial n plastic 1 1 1\n", "unknown type 'plastic'"},
    {"undefined checker", "%Hmaterial n lambertian texture nope\n", "texture 'nope' is not defined"},
    {"checker scale 0", "%Hchecker c 1 1 1 0 0 0 0\n", "checker: scale must be >= 1e-6"},
    {"size 0", "%Hsize 0 100\n", "size: width: expected an integer in [1, 16384], got '0'"},
    {"size huge", "%Hsize 100000000000000000000 10\n", "expected an integer"},
    {"spp text", "%Hspp many\n", "spp: expected an integer"},
    {"bad strategy", "%Hstrategy best\n", "strategy: expected mis, material, light or mixture, got 'best'"},
    {"bad sampler", "%Hsampler halton\n", "bad.scene:3: sampler: expected independent or sobol, got 'halton'"},
    {"indirect_paths 9", "%Hindirect_paths 9\n", "bad.scene:3: indirect_paths: expected an integer in [1, 8], got '9'"},
    {"bad guiding", "%Hguiding sometimes\n", "bad.scene:3: guiding: expected off, on or auto, got 'sometimes'"},
    {"guiding_budget 1", "%Hguiding_budget 1\n", "bad.scene:3: guiding_budget"},
    {"point_light short", "%Hpoint_light 0 3 0 1 1\n", "bad.scene:3: point_light intensity: missing number (line ends early)"},
    {"point_light negative", "%Hpoint_light 0 3 0 1 -1 1\n", "bad.scene:3: point_light intensity: colour components must be >= 0"},
    {"point_light dark", "%Hpoint_light 0 3 0 0 0 0\n", "bad.scene:3: point_light intensity: all zero"},
    {"spot_light aimed at itself", "%Hspot_light 1 2 3 1 2 3 1 1 1\n", "bad.scene:3: spot_light: the target equals the position"},
    {"spot_light cutoff 95", "%Hspot_light 0 3 0 0 0 0 1 1 1 95\n", "bad.scene:3: spot_light cutoff_angle: must be in (0, 90] degrees, got '95'"},
    {"spot_light beam > cutoff", "%Hspot_light 0 3 0 0 0 0 1 1 1 30 40\n", "bad.scene:3: spot_light beam_width: must be in (0, cutoff_angle = 30] degrees"},
    {"spot_light extra", "%Hspot_light 0 3 0 0 0 0 1 1 1 30 20 10\n", "bad.scene:3: unexpected '10' after the end of the 'spot_light' statement"},
    {"directional_light zero", "%Hdirectional_light 0 0 0 1 1 1\n", "bad.scene:3: directional_light: the direction has zero length"},
    {"directional_light text", "%Hdirectional_light 0 down 0 1 1 1\n", "bad.scene:3: directional_light direction: 'down' is not a number"},
    {"singular scale", "%Hscale 1 0 1\n", "scale: every factor must have magnitude >= 1e-6"},
    {"rotate zero axis", "%Hrotate 0 0 0 45\n", "rotate: the axis has zero length"},
    {"overflowing transform", "%Hscale 1e7 1e7 1e7\nscale 1e7 1e7 1e7\nscale 1e7 1e7 1e7\nscale 1e7 1e7 1e7\nscale 1e7 1e7 1e7\nscale 1e7 1e7 1e7\n",
     "the combined transform is singular or not finite"},
    {"include (not supported)", "%Hinclude other.scene\n", "unknown statement 'include'"},
    {"too many tokens", "%Hsphere 0 0 0 1 m 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30 31 32 33 34 35 36 37 38 39 40\n",
     "too many items on one line"},
    {"missing mesh file", "%Hmesh no-such.obj m\n", "bad.scene:3: mesh: no file 'no-such.obj' inside"},
    {"OBJ index out of range", "%Hmesh bad-index.obj m\n", "bad-index.obj:4: face vertex '7': position index out of range"},
    {"OBJ index zero", "%Hmesh bad-zero.obj m\n", "bad-zero.obj:4: face vertex '0'"},
    {"OBJ normal index", "%Hmesh bad-normal.obj m\n", "bad-normal.obj:5: face vertex '3//2': normal index out of range"},
    {"OBJ NaN vertex", "%Hmesh bad-nan.obj m\n", "bad-nan.obj:2: 'nan' is not a finite number"},
    {"OBJ no faces", "%Hmesh bad-empty.obj m\n", "bad-empty.obj: no faces"},
    {"OBJ two-vertex face", "%Hmesh bad-short.obj m\n", "bad-short.obj:4: a face needs at least 3 vertices, got 2"},
    {"OBJ unknown statement", "%Hmesh bad-curve.obj m\n", "bad-curve.obj:1: unsupported OBJ statement 'curv'"},
};

static void expand(char *out, size_t size, const char *text)
{
    /* %H: a camera and a material m on lines 1-2, so the case's own statement is on line 3. */
    if (!strncmp(text, "%H", 2)) snprintf(out, size, "%s%s", good_header, text + 2);
    else snprintf(out, size, "%s", text);
}

static int write_text(const char *dir, const char *name, const char *text)
{
    char path[2048];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    f = fopen(path, "w");
    if (!f) return 0;
    fputs(text, f);
    return fclose(f) == 0;
}

static void test_malformed(const char *work)
{
    size_t i;
    char text[8192], err[1024], line[1400];
    pt_scenefile sd;
    write_text(work, "bad-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n");
    write_text(work, "bad-zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
    write_text(work, "bad-normal.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//1 2//1 3//2\n");
    write_text(work, "bad-nan.obj", "v 0 0 0\nv nan 0 0\n");
    write_text(work, "bad-empty.obj", "# nothing\nv 0 0 0\n");
    write_text(work, "bad-short.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n");
    write_text(work, "bad-curve.obj", "curv 0 1 1 2\n");
    for (i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; ++i) {
        const bad_case *b = &bad_cases[i];
        int rc;
        expand(text, sizeof text, b->text);
        memset(&sd, 0x5a, sizeof sd);
        rc = pt_scenefile_parse(text, strlen(text), "bad.scene", work, &sd, err, sizeof err);
        snprintf(line, sizeof line, "%s -> %s", b->what, err);
        result(rc != PT_OK && strstr(err, b->expect) != NULL && sd.shapes == NULL && sd.shape_count == 0,
               "malformed scene", line);
        if (rc == PT_OK) pt_scenefile_free(&sd);
    }
    /* Inputs that cannot be written as a short string. */
    {
        static const char nul_text[] = "camera look_from 0 1 -5 look_at 0 0 0\nsph\0ere 0 0 0 1 m\n";
        int rc = pt_scenefile_parse(nul_text, sizeof nul_text - 1, "bad.scene", work, &sd, err, sizeof err);
        snprintf(line, sizeof line, "NUL byte -> %s", err);
        result(rc != PT_OK && strstr(err, "bad.scene:2: NUL byte") != NULL, "malformed scene", line);
    }
    {
        static char longline[PT__SF_MAX_LINE + 100];
        int rc;
        memset(longline, ' ', sizeof longline - 1);
        memcpy(longline, "sphere", 6);
        longline[sizeof longline - 1] = '\0';
        rc = pt_scenefile_parse(longline, strlen(longline), "bad.scene", work, &sd, err, sizeof err);
        snprintf(line, sizeof line, "line of %d characters -> %s", (int)strlen(longline), err);
        result(rc != PT_OK && strstr(err, "bad.scene:1: line longer than") != NULL, "malformed scene", line);
    }
    {
        char path[2048];
        int rc;
        snprintf(path, sizeof path, "%s/no-such.scene", work);
        rc = pt_scenefile_load(path, &sd, err, sizeof err);
        snprintf(line, sizeof line, "missing scene file -> %s", err);
        result(rc == PT_ERROR_IO && strstr(err, "cannot read the scene") != NULL, "malformed scene", line);
        /* a directory: fopen works on Linux, reading fails */
        rc = pt_scenefile_load(work, &sd, err, sizeof err);
        snprintf(line, sizeof line, "a directory as scene file -> %s", err);
        result(rc != PT_OK && strstr(err, work) == err, "malformed scene", line);
    }
    /* Parsed, but refused when built: a sphere under a non-uniform scale. */
    {
        pt_scene *s = (pt_scene *)&sd;
        pt_render_desc rd;
        int rc;
        expand(text, sizeof text, "%Hscale 1 2 1\nsphere 0 0 0 1 m\n");
        rc = pt_scenefile_parse(text, strlen(text), "bad.scene", work, &sd, err, sizeof err);
        if (rc == PT_OK) {
            rc = pt_scenefile_build(&sd, &s, &rd, err, sizeof err);
            pt_scenefile_free(&sd);
        }
        snprintf(line, sizeof line, "sphere under non-uniform scale (build) -> %s", err);
        result(rc == PT_ERROR_UNSUPPORTED && s == NULL && strstr(err, "bad.scene:4:") != NULL, "malformed scene", line);
    }
    /* Parsed, but refused by the POV-Ray exporter, which writes nothing. */
    {
        char pov[2048];
        int rc;
        snprintf(pov, sizeof pov, "%s/fuzzy.pov", work);
        remove(pov);
        expand(text, sizeof text, "%Hmaterial f metal 1 1 1 fuzz 0.3\nsphere 0 0 0 1 f\n");
        rc = pt_scenefile_parse(text, strlen(text), "bad.scene", work, &sd, err, sizeof err);
        if (rc == PT_OK) {
            rc = pt_scenefile_write_pov(&sd, pov, NULL, err, sizeof err);
            pt_scenefile_free(&sd);
        }
        snprintf(line, sizeof line, "fuzzy metal (POV export) -> %s", err);
        result(rc == PT_ERROR_UNSUPPORTED && access(pov, F_OK) != 0 && strstr(err, "bad.scene:4:") != NULL,
               "malformed scene", line);
    }
    {
        char pov[2048];
        int rc;
        snprintf(pov, sizeof pov, "%s/roughglass.pov", work);
        remove(pov);
        expand(text, sizeof text, "%Hmaterial g roughdielectric 0.2 1.5\nsphere 0 0 0 1 g\n");
        rc = pt_scenefile_parse(text, strlen(text), "bad.scene", work, &sd, err, sizeof err);
        if (rc == PT_OK) {
            rc = pt_scenefile_write_pov(&sd, pov, NULL, err, sizeof err);
            pt_scenefile_free(&sd);
        }
        snprintf(line, sizeof line, "rough dielectric (POV export) -> %s", err);
        result(rc == PT_ERROR_UNSUPPORTED && access(pov, F_OK) != 0 && strstr(err, "bad.scene:4:") != NULL &&
                   strstr(err, "rough dielectric") != NULL,
               "malformed scene", line);
    }
}

static void test_scenes_load(const char *dir)
{
    static const char *const names[] = {"cornell", "cornell-diffuse", "direct-quad", "direct-sphere", "mirror", "glass", "checker", "mesh",
                                        "lights", "lights-direct", "env", "rough-metal", "rough-glass",
                                        "rough-plastic", "textured"};
    size_t i;
    for (i = 0; i < sizeof names / sizeof names[0]; ++i) {
        char path[2048], err[1024] = "";
        pt_scenefile sd;
        pt_scene *s = NULL;
        pt_render_desc rd;
        int rc;
        snprintf(path, sizeof path, "%s/%s.scene", dir, names[i]);
        rc = pt_scenefile_load(path, &sd, err, sizeof err);
        if (rc == PT_OK) {
            rc = pt_scenefile_build(&sd, &s, &rd, err, sizeof err);
            pt_scene_destroy(s);
            pt_scenefile_free(&sd);
        }
        result(rc == PT_OK, "scene loads and builds", rc == PT_OK ? path : err);
    }
}

#ifdef PTV_HAVE_EXR
static void test_compare(const char *dir, const char *work, const char *name, int size, int spp, int grid, double pov_err)
{
    char path[2048], pov[2048], exr[2048], log[2048], err[1024], what[256];
    pt_scenefile sd;
    pt_pov_options o;
    pt_image x = {0, 0, NULL}, v = {0, 0, NULL}, r = {0, 0, NULL};
    metrics m;
    int ok;
    if (grid > 0) snprintf(what, sizeof what, "POV-Ray comparison %s (%dx%d, %d spp, %dx%d light grid)", name, size, size, spp, grid, grid);
    else snprintf(what, sizeof what, "POV-Ray comparison %s (%dx%d, %d spp)", name, size, size, spp);
    snprintf(path, sizeof path, "%s/%s.scene", dir, name);
    snprintf(pov, sizeof pov, "%s/%s.pov", work, name);
    snprintf(exr, sizeof exr, "%s/%s.exr", work, name);
    if (pt_scenefile_load(path, &sd, err, sizeof err) != PT_OK) { result(0, what, err); return; }
    memset(&o, 0, sizeof o);
    o.radiosity = -1;
    o.light_grid = grid;
    o.width = o.height = size;
    ok = pt_scenefile_write_pov(&sd, pov, &o, err, sizeof err) == PT_OK;
    if (!ok) { pt_scenefile_free(&sd); result(0, what, err); return; }
    snprintf(log, sizeof log, "%s/%s.log", work, name);
    if (!run_povray(pov, exr, size, size, NULL, log, NULL)) {
        pt_scenefile_free(&sd);
        snprintf(err, sizeof err, "povray failed: see %s/%s.log", work, name);
        result(0, what, err);
        return;
    }
    ok = render_desc(&sd, size, size, spp, &x, &v);
    pt_scenefile_free(&sd);
    memset(&m, 0, sizeof m);
    m.bias_tol = 0.01;
    m.pov_err = pov_err;
    m.accept_req = 0.99;
    ok = ok && read_exr(exr, &r) && compare(&x, &v, &r, &m, NULL, name);
    if (ok) {
        snprintf(err, sizeof err, "bias %+.3f%% %+.3f%% %+.3f%% (tol 1%%), z-test accepted %.2f%% (need 99%%)",
                 100 * m.bias[0], 100 * m.bias[1], 100 * m.bias[2], 100 * m.accepted);
        result(m.pass, what, err);
    } else
        result(0, what, "render or EXR read failed");
    pt_image_free(&x);
    pt_image_free(&v);
    pt_image_free(&r);
}
#endif

/* Fuzz: every scene file, mutated at random (deterministic) - lines cut short, tokens replaced by
   huge, NaN, negative or junk values, characters deleted or duplicated, lines swapped. Each
   result must be a clean success (then it must build or fail cleanly, and export or fail
   cleanly) or an error whose message starts with the file name. Run under ASan for memory. */
static uint64_t fuzz_state = 0x9E3779B97F4A7C15ull;
static uint32_t fuzz_rand(uint32_t n)
{
    fuzz_state ^= fuzz_state << 13;
    fuzz_state ^= fuzz_state >> 7;
    fuzz_state ^= fuzz_state << 17;
    return (uint32_t)(fuzz_state >> 11) % n;
}
static void test_fuzz(const char *dir, const char *work, int rounds)
{
    static const char *const names[] = {"cornell", "direct-quad", "direct-sphere", "mirror", "checker", "mesh", "lights"};
    static const char *const junk[] = {"1e300", "-1e300", "nan", "inf", "-0", "0", "-1", "1e7", "1e-40", "x", "#", "",
                                       "99999999999999999999", "0x10", "mesh.obj", "white", "lamp", "sphere", "-5e6"};
    char *text = NULL, *buf = NULL, err[1024], pov[2048], detail[1200];
    int r, bad = 0, ok_count = 0, err_count = 0;
    size_t cap = 0;
    snprintf(pov, sizeof pov, "%s/fuzz.pov", work);
    for (r = 0; r < rounds && !bad; ++r) {
        char path[2048];
        FILE *f;
        size_t len = 0, n, i;
        int m, muts = 1 + (int)fuzz_rand(4), rc;
        pt_scenefile sd;
        snprintf(path, sizeof path, "%s/%s.scene", dir, names[r % (int)(sizeof names / sizeof names[0])]);
        f = fopen(path, "rb");
        if (!f) { bad = 1; break; }
        if (cap < 1u << 20) { free(text); free(buf); cap = 1u << 20; text = (char *)malloc(cap); buf = (char *)malloc(cap); }
        if (!text || !buf) { fclose(f); bad = 1; break; }
        len = fread(text, 1, cap / 4, f);
        fclose(f);
        for (m = 0; m < muts; ++m) {
            size_t pos = len ? fuzz_rand((uint32_t)len) : 0, k = 0;
            int kind = (int)fuzz_rand(5);
            if (kind == 0) { /* cut the line short at pos */
                size_t e = pos;
                while (e < len && text[e] != '\n') ++e;
                memmove(text + pos, text + e, len - e);
                len -= e - pos;
            } else if (kind == 1) { /* replace the token at pos */
                const char *j = junk[fuzz_rand((uint32_t)(sizeof junk / sizeof junk[0]))];
                size_t s0 = pos, e = pos, jl = strlen(j);
                while (s0 > 0 && text[s0 - 1] != ' ' && text[s0 - 1] != '\n') --s0;
                while (e < len && text[e] != ' ' && text[e] != '\n') ++e;
                if (len - (e - s0) + jl >= cap / 2) continue;
                memmove(text + s0 + jl, text + e, len - e);
                memcpy(text + s0, j, jl);
                len = len - (e - s0) + jl;
            } else if (kind == 2 && len) { /* delete a character */
                memmove(text + pos, text + pos + 1, len - pos - 1);
                --len;
            } else if (kind == 3 && len + 1 < cap / 2) { /* duplicate a character */
                memmove(text + pos + 1, text + pos, len - pos);
                ++len;
            } else { /* append a copy of a random line */
                size_t s0 = pos, e = pos;
                while (s0 > 0 && text[s0 - 1] != '\n') --s0;
                while (e < len && text[e] != '\n') ++e;
                if (len + (e - s0) + 1 >= cap / 2) continue;
                memcpy(buf, text + s0, e - s0);
                k = e - s0;
                text[len++] = '\n';
                memcpy(text + len, buf, k);
                len += k;
            }
        }
        n = len;
        rc = pt_scenefile_parse(text, n, "fuzz.scene", dir, &sd, err, sizeof err);
        if (rc != PT_OK) {
            ++err_count;
            if (strncmp(err, "fuzz.scene", 10) != 0 && strstr(err, ".obj") == NULL) bad = 1;
            for (i = 0; i < sizeof sd && !bad; ++i)
                if (((const unsigned char *)&sd)[i] != 0) bad = 1; /* *out left empty */
        } else {
            pt_scene *s = NULL;
            pt_render_desc rd;
            ++ok_count;
            rc = pt_scenefile_build(&sd, &s, &rd, err, sizeof err);
            if (rc == PT_OK) {
                pt_hit hit;
                pt_ray ray;
                ray.origin = rd.camera.look_from;
                ray.dir = pt_sub(rd.camera.look_at, rd.camera.look_from);
                if (pt_scene_intersect(s, ray, 1e30f, &hit) < 0) bad = 1;
                pt_scene_destroy(s);
            } else if (s != NULL || strncmp(err, "fuzz.scene", 10) != 0)
                bad = 1;
            rc = pt_scenefile_write_pov(&sd, pov, NULL, err, sizeof err);
            if (rc != PT_OK && strncmp(err, "fuzz.scene", 10) != 0 && strstr(err, "fuzz.pov") == NULL) bad = 1;
            pt_scenefile_free(&sd);
        }
        if (bad) snprintf(detail, sizeof detail, "round %d: unexpected result, message '%s'", r, err);
    }
    if (!bad)
        snprintf(detail, sizeof detail, "%d mutated scene files: %d loaded (then built/exported or refused cleanly), %d refused with file:line",
                 rounds, ok_count, err_count);
    remove(pov);
    free(text);
    free(buf);
    result(!bad, "fuzz", detail);
}

/* ---- compare-mitsuba on synthetic images --------------------------------------------------- */

/* One synthetic renderer: k seed images of a 64 x 64 gradient, each pixel with independent
   Gaussian noise of 5 % (Box-Muller), scaled by gain, and by region_gain inside region 5
   (second row, second column); then the mean, its variance (from the seeds) and the regions. */
static int synth_run(const char *work, uint64_t seed, int k, double gain, double region_gain, pt_image *mean, pt_image *var, seed_regions *sr)
{
    const int w = 64, h = 64;
    char path[2048];
    pt_image *imgs = (pt_image *)calloc((size_t)k, sizeof *imgs);
    pt_rng rng;
    int s, x, y, c, ok = imgs != NULL && pt_image_init(mean, w, h) == PT_OK && pt_image_init(var, w, h) == PT_OK;
    pt_rng_seed(&rng, seed, 7);
    for (s = 0; ok && s < k; ++s) {
        ok = pt_image_init(&imgs[s], w, h) == PT_OK;
        for (y = 0; ok && y < h; ++y)
            for (x = 0; x < w; ++x)
                for (c = 0; c < 3; ++c) {
                    double u1 = 1.0 - pt_rng_float(&rng), u2 = pt_rng_float(&rng); /* u1 in (0, 1] */
                    double g = sqrt(-2 * log(u1)) * cos(6.283185307179586 * u2);
                    double truth = (0.2 + 0.6 * (x + y) / (double)(w + h)) * (1.0 - 0.2 * c) * gain;
                    if (4 * (4 * y / h) + 4 * x / w == 5) truth *= region_gain;
                    imgs[s].rgb[3 * (y * w + x) + c] = (float)(truth * (1 + 0.05 * g));
                }
    }
    for (y = 0; ok && y < h; ++y)
        for (x = 0; x < w; ++x)
            for (c = 0; c < 3; ++c) {
                size_t j = 3 * ((size_t)y * (size_t)w + (size_t)x) + (size_t)c;
                double s1 = 0, s2 = 0, m;
                for (s = 0; s < k; ++s) { s1 += imgs[s].rgb[j]; s2 += (double)imgs[s].rgb[j] * imgs[s].rgb[j]; }
                m = s1 / k;
                mean->rgb[j] = (float)m;
                var->rgb[j] = (float)((s2 - s1 * m) / (k - 1) / k);
            }
    snprintf(path, sizeof path, "%s/synth-regions.txt", work);
    ok = ok && write_regions(path, imgs, k, k - 1) && read_regions(path, sr);
    remove(path);
    free_images(imgs, k);
    return ok;
}

/* compare-mitsuba's tests on synthetic renders with known truth (fixed seeds): the same mean
   passes every test; a 1 % offset fails the bias test; +2 % in one region fails the region
   test. And the t quantiles against tables (t_{0.995} at 10 and 30 degrees of freedom). */
static void test_compare_mitsuba(const char *work)
{
    static const struct { const char *what; double gain, region_gain; int use_region, expect_pass; } cases[] = {
        {"identical mean passes (pixel test)", 1.0, 1.0, 0, 1},
        {"identical mean passes (region test)", 1.0, 1.0, 1, 1},
        {"1 % offset fails", 1.01, 1.0, 0, 0},
        {"+2 % in one region fails the region test", 1.0, 1.02, 1, 0},
    };
    char detail[512];
    double z01 = normal_quantile2(0.01), t10 = t_quantile2(z01, 10), t30 = t_quantile2(z01, 30), z = normal_quantile2(0.001);
    size_t i;
    snprintf(detail, sizeof detail, "z(0.001) %.4f (3.2905), t(0.01; 10) %.4f (3.1693), t(0.01; 30) %.4f (2.7500)", z, t10, t30);
    result(fabs(z - 3.2905) < 1e-3 && fabs(t10 - 3.1693) < 5e-3 && fabs(t30 - 2.75) < 2e-3, "compare-mitsuba: quantiles", detail);
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        pt_image x = {0, 0, NULL}, vx = {0, 0, NULL}, r = {0, 0, NULL}, vr = {0, 0, NULL};
        seed_regions sx = {0, 0, 0, 0, NULL}, sr = {0, 0, 0, 0, NULL};
        mi_metrics m;
        int ok = synth_run(work, 11 + i, 16, cases[i].gain, cases[i].region_gain, &x, &vx, &sx) &&
                 synth_run(work, 101 + i, 16, 1.0, 1.0, &r, &vr, &sr) &&
                 compare_mitsuba(&x, &vx, &sx, &r, &vr, &sr, cases[i].use_region, &m, NULL);
        char what[160];
        snprintf(what, sizeof what, "compare-mitsuba: %s", cases[i].what);
        if (ok) {
            snprintf(detail, sizeof detail, "bias %+.3f%%±%.3f %+.3f%%±%.3f %+.3f%%±%.3f, pixels accepted %.2f%%, "
                     "regions rejected %d (worst %.2f)", 100 * m.bias[0], 100 * m.se[0], 100 * m.bias[1], 100 * m.se[1],
                     100 * m.bias[2], 100 * m.se[2], 100 * m.accepted, m.region_rejected, m.region_worst);
            /* the region case must fail by the region test itself, whatever the bias test says */
            ok = cases[i].expect_pass ? m.pass && m.bias_ok && m.pixel_ok && m.region_ok
                 : cases[i].use_region ? !m.region_ok && !m.pass : !m.bias_ok && !m.pass;
        } else
            snprintf(detail, sizeof detail, "could not build the synthetic renders");
        result(ok, what, detail);
        free(sx.m);
        free(sr.m);
        pt_image_free(&x);
        pt_image_free(&vx);
        pt_image_free(&r);
        pt_image_free(&vr);
    }
}

/* 1 when the files at paths a and b both open and hold the same bytes. */
static int same_bytes(const char *a, const char *b)
{
    FILE *fa, *fb;
    int same = 0, ca, cb;
    if ((fa = fopen(a, "rb")) != NULL) {
        if ((fb = fopen(b, "rb")) != NULL) {
            do { ca = fgetc(fa); cb = fgetc(fb); } while (ca == cb && ca != EOF);
            same = ca == cb;
            fclose(fb);
        }
        fclose(fa);
    }
    return same;
}

/* scenes/cornell.scene through the pdftrace command must be exactly the built-in box of
   examples/cornell.c (build/cornell, 600 x 600): same image bytes. */
static void test_cornell_identical(const char *pdftrace, const char *cornell, const char *dir, const char *work)
{
    char cmd[8192], a[2048], b[2048];
    int same = 0;
    snprintf(a, sizeof a, "%s/builtin.pfm", work);
    snprintf(b, sizeof b, "%s/from-file.pfm", work);
    remove(a);
    remove(b);
    snprintf(cmd, sizeof cmd, "'%s' -q --spp 2 -o '%s' >/dev/null && '%s' '%s/cornell.scene' -q --spp 2 --size 600x600 "
             "--max-depth 50 -o '%s' >/dev/null", cornell, a, pdftrace, dir, b);
    if (system(cmd) == 0) same = same_bytes(a, b);
    result(same, "pdftrace scenes/cornell.scene renders bit-identical to build/cornell's built-in box", "600x600, 2 spp");
}

/* pdftrace takes a scene file's sampler and indirect_paths as its defaults, and the command
   line overrides them: cornell.scene plus "sampler sobol" and "indirect_paths 2" renders as
   cornell.scene with --sampler sobol --indirect-paths 2 (same bytes), and with
   --indirect-paths 1 as --indirect-paths 1 (and not as 2). */
static void test_scene_settings(const char *pdftrace, const char *dir, const char *work)
{
    char cmd[24576], scene[2048], from_file[2048], given[2048], over[2048], one[2048], src[2048];
    const char *common = "-q --spp 4 --size 32x32";
    int ok, n, same2 = 0, same1 = 0, differs = 0;
    snprintf(src, sizeof src, "%s/cornell.scene", dir);
    snprintf(scene, sizeof scene, "%s/cornell-sobol2.scene", work);
    snprintf(from_file, sizeof from_file, "%s/sobol2-file.pfm", work);
    snprintf(given, sizeof given, "%s/sobol2-given.pfm", work);
    snprintf(over, sizeof over, "%s/sobol2-over1.pfm", work);
    snprintf(one, sizeof one, "%s/sobol1-given.pfm", work);
    remove(from_file);
    remove(given);
    remove(over);
    remove(one);
    n = snprintf(cmd, sizeof cmd,
             "cat '%s' > '%s' && printf '\\nsampler sobol\\nindirect_paths 2\\n' >> '%s' && "
             "'%s' '%s' %s -o '%s' >/dev/null && '%s' '%s' %s --sampler sobol --indirect-paths 2 -o '%s' "
             ">/dev/null && '%s' '%s' %s --indirect-paths 1 -o '%s' >/dev/null && '%s' '%s' %s "
             "--sampler sobol --indirect-paths 1 -o '%s' >/dev/null",
             src, scene, scene, pdftrace, scene, common, from_file, pdftrace, src, common, given, pdftrace, scene, common,
             over, pdftrace, src, common, one);
    ok = n > 0 && (size_t)n < sizeof cmd && system(cmd) == 0; /* (a truncated command is a failure) */
    if (ok) {
        same2 = same_bytes(from_file, given);
        same1 = same_bytes(over, one);
        differs = !same_bytes(from_file, one);
    }
    result(ok && same2 && same1 && differs,
           "pdftrace: the file's sampler and indirect_paths are defaults, --indirect-paths overrides",
           !ok ? "a render failed (or the paths are too long)" : !same2 ? "file's indirect_paths 2 != --indirect-paths 2"
           : !same1 ? "--indirect-paths 1 over the file != --indirect-paths 1" : !differs ? "indirect_paths 1 and 2 gave "
           "the same image" : "32x32, 4 spp, sobol");
}

/* The four POV-Ray comparisons of cmd_test, each counted as skipped. */
static void skip_compare(const char *reason)
{
    static const char *const names[] = {"direct-quad", "checker", "mirror", "glass"};
    char what[128];
    size_t i;
    for (i = 0; i < sizeof names / sizeof names[0]; ++i) {
        snprintf(what, sizeof what, "POV-Ray comparison %s", names[i]);
        skip(what, reason);
    }
}

static int cmd_test(int argc, char **argv)
{
    if (argc != 4 && argc != 6) {
        fprintf(stderr, "usage: ptv test SCENEDIR WORKDIR [build/pdftrace build/cornell]\n");
        return 2;
    }
    test_malformed(argv[3]);
    test_scenes_load(argv[2]);
    test_fuzz(argv[2], argv[3], 3000);
    test_compare_mitsuba(argv[3]);
    if (argc == 6) {
        test_cornell_identical(argv[4], argv[5], argv[2], argv[3]);
        test_scene_settings(argv[4], argv[2], argv[3]);
    }
#ifdef PTV_HAVE_EXR
    if (have_povray()) {
        test_compare(argv[2], argv[3], "direct-quad", 64, 256, 8, 0.01);
        test_compare(argv[2], argv[3], "checker", 64, 256, 8, 0.01);
        test_compare(argv[2], argv[3], "mirror", 96, 256, 8, 0.01); /* at 64x64 its edge pixels make +0.6 % */
        test_compare(argv[2], argv[3], "glass", 64, 256, 0, 0.01); /* 0: the scene's grid (1: the tiles light nothing) */
        test_compare(argv[2], argv[3], "lights-direct", 64, 256, 0, 0.01); /* point, hard spot, directional light */
    } else
        skip_compare("povray is not installed (apt-get install povray)");
#else
    skip_compare("built without OpenEXR (apt-get install libopenexr-dev)");
#endif
    if (argc != 6) {
        skip("pdftrace scenes/cornell.scene renders bit-identical to build/cornell's built-in box",
             "no build/pdftrace and build/cornell arguments");
        skip("pdftrace: the file's sampler and indirect_paths are defaults, --indirect-paths overrides",
             "no build/pdftrace and build/cornell arguments");
    }
    printf("%d passed, %d failed, %d skipped\n", passed, failed, skipped);
    return failed ? 1 : 0;
}

int main(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "render")) return cmd_render(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "pov")) return cmd_pov(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "compare")) return cmd_compare(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "compare-mitsuba")) return cmd_compare_mitsuba(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "report")) return cmd_report(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "test")) return cmd_test(argc, argv);
    fprintf(stderr, "usage: ptv render|pov|compare|compare-mitsuba|report|test ... (see validation/ptv.c)\n");
    return 2;
}
