/* ptv.c - pdftrace validation tool: renders scene files, exports them to POV-Ray, compares
   pdftrace's images with POV-Ray's and writes the report; `ptv test` is the fast runner used
   by `make test` (malformed scene files, and the fast POV-Ray comparisons when povray is
   installed).

     ptv render SCENE MEAN.pfm VAR.pfm [W H SPP]      mean and variance of the mean per pixel
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

/* ---- commands ------------------------------------------------------------------------- */

static int load(const char *path, pt_scenefile *sd)
{
    char err[1024];
    if (pt_scenefile_load(path, sd, err, sizeof err) != PT_OK) { fprintf(stderr, "ptv: %s\n", err); return 0; }
    return 1;
}

static int cmd_render(int argc, char **argv)
{
    pt_scenefile sd;
    pt_image mean = {0, 0, NULL}, var = {0, 0, NULL};
    int ok, w = 0, h = 0, spp = 0;
    if (argc != 5 && argc != 8) { fprintf(stderr, "usage: ptv render SCENE MEAN.pfm VAR.pfm [W H SPP]\n"); return 2; }
    if (argc == 8) { w = atoi(argv[5]); h = atoi(argv[6]); spp = atoi(argv[7]); }
    if (!load(argv[2], &sd)) return 1;
    ok = render_desc(&sd, w, h, spp, &mean, &var);
    pt_scenefile_free(&sd);
    if (ok) ok = pt_write_pfm(argv[3], &mean) == PT_OK && pt_write_pfm(argv[4], &var) == PT_OK;
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

static void html_escape(FILE *f, const char *s)
{
    for (; *s; ++s) {
        if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else if (*s == '&') fputs("&amp;", f);
        else fputc(*s, f);
    }
}

static int cmd_report(int argc, char **argv)
{
    char path[2048], index[2048], tmp[2100], line[4096];
    FILE *f;
    int i, all = 1;
    if (argc < 4) { fprintf(stderr, "usage: ptv report OUTDIR NAME...\n"); return 2; }
    snprintf(index, sizeof index, "%s/index.html", argv[2]);
    snprintf(tmp, sizeof tmp, "%s.tmp", index);
    f = fopen(tmp, "w");
    if (!f) { fprintf(stderr, "ptv: cannot write %s\n", tmp); return 1; }
    fprintf(f, "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>pdftrace vs POV-Ray</title>\n<style>\n"
               "body{font-family:sans-serif;margin:20px;background:#fafafa}table{border-collapse:collapse}"
               "td,th{border:1px solid #bbb;padding:4px 8px;text-align:right}th{background:#eee}"
               ".pass{color:#070;font-weight:bold}.fail{color:#b00;font-weight:bold}"
               "img{width:256px;height:256px;image-rendering:pixelated;border:1px solid #888}"
               ".scene{margin:18px 0}.scene td{text-align:center;border:none}</style></head><body>\n"
               "<h1>pdftrace vs POV-Ray 3.7</h1>\n<p>bias<sub>c</sub> = &Sigma;x/&Sigma;r &minus; 1 per channel; relMSE = "
               "mean (x&minus;r)&sup2;/(r&sup2;+0.01); per-pixel error e = mean<sub>c</sub> |x&minus;r|/(r+0.01); z-test: "
               "|x&minus;r| &le; 3.29&middot;&radic;(var<sub>pdftrace</sub> + (pov_err&middot;r)&sup2; + (5e-4&middot;r)&sup2;) "
               "in every channel (two-sided &alpha; = 0.001 per channel). Error map: red = pdftrace brighter, blue = darker, "
               "full colour at 5 %%; green = pixel rejected by the z-test. Images sRGB-encoded, clipped at 1.</p>\n"
               "<table><tr><th>scene</th><th>size</th><th>bias R</th><th>bias G</th><th>bias B</th><th>bias tol</th>"
               "<th>relMSE</th><th>e p50</th><th>e p90</th><th>e p99</th><th>z-test accepted</th><th>required</th>"
               "<th>POV err</th><th>result</th><th>reference</th></tr>\n");
    for (i = 3; i < argc; ++i) {
        FILE *r;
        int w = 0, h = 0, pass = 0, n = 0;
        double v[11];
        char *note = NULL;
        snprintf(path, sizeof path, "%s/%s.result", argv[2], argv[i]);
        r = fopen(path, "r");
        if (r && fgets(line, sizeof line, r)) {
            n = sscanf(line, "%d %d %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %lf %d", &w, &h, &v[0], &v[1], &v[2], &v[3],
                       &v[4], &v[5], &v[6], &v[7], &v[8], &v[9], &v[10], &pass);
            note = line;
            { int k; for (k = 0; k < 14 && note; ++k) { note = strchr(note, ' '); if (note) ++note; } }
            if (note) note[strcspn(note, "\n")] = '\0';
        }
        if (r) fclose(r);
        fprintf(f, "<tr><td><a href=\"#%s\">%s</a></td>", argv[i], argv[i]);
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
    for (i = 3; i < argc; ++i)
        fprintf(f, "<div class=\"scene\" id=\"%s\"><h2>%s</h2><table><tr><td><img src=\"%s-pt.png\" alt=\"pdftrace\"><br>pdftrace</td>"
                   "<td><img src=\"%s-pov.png\" alt=\"POV-Ray\"><br>POV-Ray</td><td><img src=\"%s-err.png\" alt=\"error map\"><br>"
                   "error map</td></tr></table></div>\n", argv[i], argv[i], argv[i], argv[i], argv[i]);
    fprintf(f, "<p>Overall: <span class=\"%s\">%s</span></p></body></html>\n", all ? "pass" : "fail", all ? "all scenes pass" : "some scenes FAIL");
    if (fclose(f) != 0 || rename(tmp, index) != 0) { remove(tmp); fprintf(stderr, "ptv: writing %s failed\n", index); return 1; }
    printf("wrote %s: %s\n", index, all ? "all scenes pass" : "some scenes FAIL");
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
    {"bad name", "%Hmaterial 9lives lambertian 1 1 1\n", "bad name '9lives'"},
    {"unknown material type", "%Hmaterial n plastic 1 1 1\n", "unknown type 'plastic'"},
    {"undefined checker", "%Hmaterial n lambertian texture nope\n", "checker 'nope' is not defined"},
    {"checker scale 0", "%Hchecker c 1 1 1 0 0 0 0\n", "checker: scale must be >= 1e-6"},
    {"size 0", "%Hsize 0 100\n", "size: width: expected an integer in [1, 16384], got '0'"},
    {"size huge", "%Hsize 100000000000000000000 10\n", "expected an integer"},
    {"spp text", "%Hspp many\n", "spp: expected an integer"},
    {"bad strategy", "%Hstrategy best\n", "strategy: expected mis, material, light or mixture, got 'best'"},
    {"bad sampler", "%Hsampler halton\n", "bad.scene:3: sampler: expected independent or sobol, got 'halton'"},
    {"indirect_paths 9", "%Hindirect_paths 9\n", "bad.scene:3: indirect_paths: expected an integer in [1, 8], got '9'"},
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
}

static void test_scenes_load(const char *dir)
{
    static const char *const names[] = {"cornell", "cornell-diffuse", "direct-quad", "direct-sphere", "mirror", "glass", "checker", "mesh"};
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
    static const char *const names[] = {"cornell", "direct-quad", "direct-sphere", "mirror", "checker", "mesh"};
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
    if (argc >= 2 && !strcmp(argv[1], "report")) return cmd_report(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "test")) return cmd_test(argc, argv);
    fprintf(stderr, "usage: ptv render|pov|compare|report|test ... (see validation/ptv.c)\n");
    return 2;
}
