/* ptv_common.h - what validation/ptv.c and bench/bench.c share: PFM and EXR readers, PNG
   writers, rendering a scene description into per-pixel means and variances of the mean, and
   running POV-Ray 3.7 on an exported scene. Static functions, included once by each program
   after pdftrace_scene.h. The programs are built with -DPTV_HAVE_EXR (pdftrace_exr.h: reading
   POV-Ray's +FE output) and -DPTV_HAVE_PNG (pdftrace_png.h: the report's images) when those
   libraries are present. */
#ifndef PTV_COMMON_H
#define PTV_COMMON_H

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

/* The name that starts error messages. */
#ifndef PTV_PROG
#define PTV_PROG "ptv"
#endif

#ifdef PTV_HAVE_EXR
#include "pdftrace_exr.h" /* the program defines PDFTRACE_EXR_IMPLEMENTATION */
#endif
/* A program need not use every helper (without OpenEXR nothing compares images). */
#if defined(__GNUC__) || defined(__clang__)
#define PTV_MAYBE_UNUSED __attribute__((unused))
#else
#define PTV_MAYBE_UNUSED
#endif
#ifdef PTV_HAVE_PNG
#include "pdftrace_png.h" /* the program defines PDFTRACE_PNG_IMPLEMENTATION */
#endif

/* ---- images ------------------------------------------------------------------------- */

/* PFM (Portable Float Map): "PF\n<w> <h>\n<scale>\n", scale < 0 little-endian, rows bottom first. */
PTV_MAYBE_UNUSED static int read_pfm(const char *path, pt_image *img)
{
    FILE *f = fopen(path, "rb");
    char magic[3] = {0};
    int w, h, y;
    double scale;
    if (!f) { fprintf(stderr, PTV_PROG ": cannot open %s: %s\n", path, strerror(errno)); return 0; }
    if (fscanf(f, "%2s %d %d %lf", magic, &w, &h, &scale) != 4 || strcmp(magic, "PF") || w <= 0 || h <= 0 ||
        w > 16384 || h > 16384 || !(scale < 0) || fgetc(f) == EOF || pt_image_init(img, w, h) != PT_OK) {
        fprintf(stderr, PTV_PROG ": %s: not a little-endian colour PFM\n", path);
        fclose(f);
        return 0;
    }
    for (y = h - 1; y >= 0; --y) {
        int x, c;
        for (x = 0; x < w; ++x)
            for (c = 0; c < 3; ++c) {
                unsigned char b[4];
                uint32_t u;
                float v;
                if (fread(b, 1, 4, f) != 4) { fprintf(stderr, PTV_PROG ": %s: truncated\n", path); fclose(f); pt_image_free(img); return 0; }
                u = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
                memcpy(&v, &u, 4);
                img->rgb[3 * ((size_t)y * (size_t)w + (size_t)x) + (size_t)c] = v;
            }
    }
    fclose(f);
    return 1;
}

#ifdef PTV_HAVE_EXR
/* An EXR (what POV-Ray's +FE writes) through pdftrace_exr.h, with the reason on stderr. */
PTV_MAYBE_UNUSED static int read_exr(const char *path, pt_image *img)
{
    char err[4096]; /* room for a long path and the library's message */
    if (pt_read_exr(path, img, err, sizeof err) == PT_OK) return 1;
    fprintf(stderr, PTV_PROG ": %s\n", err);
    return 0;
}
#endif

/* An 8-bit RGB image (3 bytes per pixel, top row first) through pdftrace_png.h. */
PTV_MAYBE_UNUSED static int write_png(const char *path, int w, int h, const unsigned char *rgb)
{
#ifdef PTV_HAVE_PNG
    char err[4096];
    if (pt_write_png_rgb8(path, w, h, rgb, err, sizeof err) == PT_OK) return 1;
    fprintf(stderr, PTV_PROG ": %s\n", err);
    return 0;
#else
    (void)path; (void)w; (void)h; (void)rgb;
    return 1; /* no libpng: the report shows no images */
#endif
}

/* A linear image, sRGB-encoded as pt_write_ppm does. */
PTV_MAYBE_UNUSED static int png_tonemapped(const char *path, const pt_image *img)
{
#ifdef PTV_HAVE_PNG
    char err[4096];
    if (pt_write_png(path, img, err, sizeof err) == PT_OK) return 1;
    fprintf(stderr, PTV_PROG ": %s\n", err);
    return 0;
#else
    (void)path; (void)img;
    return 1;
#endif
}

/* ---- rendering ------------------------------------------------------------------------ */

PTV_MAYBE_UNUSED static int render_desc(const pt_scenefile *sd, int w, int h, int spp, pt_image *mean, pt_image *var)
{
    pt_scene *scene = NULL;
    pt_render_desc rd;
    pt_film film;
    char err[1024];
    pt_render_stats st;
    int rc = pt_scenefile_build(sd, &scene, &rd, err, sizeof err), x, y;
    if (rc != PT_OK) { fprintf(stderr, PTV_PROG ": %s\n", err); return 0; }
    if (w > 0) { rd.width = w; rd.height = h; }
    if (spp > 0) rd.samples_per_pixel = spp;
    if (pt_film_init(&film, rd.width, rd.height) != PT_OK) { pt_scene_destroy(scene); return 0; }
    rc = pt_render(scene, &rd, &film, &st);
    pt_scene_destroy(scene);
    if (rc != PT_OK || pt_image_init(mean, rd.width, rd.height) != PT_OK || pt_image_init(var, rd.width, rd.height) != PT_OK) {
        fprintf(stderr, PTV_PROG ": render failed: %s\n", rc != PT_OK ? st.error : "out of memory");
        pt_film_free(&film);
        return 0;
    }
    for (y = 0; y < rd.height; ++y)
        for (x = 0; x < rd.width; ++x) {
            pt_color m = pt_v3(0, 0, 0), v = pt_v3(0, 0, 0);
            size_t i = 3 * ((size_t)y * (size_t)rd.width + (size_t)x);
            if (pt_film_pixel(&film, x, y, &m, &v) != PT_OK) m = v = pt_v3(-1, -1, -1); /* cannot happen */
            mean->rgb[i] = m.x; mean->rgb[i + 1] = m.y; mean->rgb[i + 2] = m.z;
            var->rgb[i] = v.x; var->rgb[i + 1] = v.y; var->rgb[i + 2] = v.z;
        }
    pt_film_free(&film);
    return 1;
}

/* ---- POV-Ray --------------------------------------------------------------------------- */

/* Seconds on a monotonic clock. */
PTV_MAYBE_UNUSED static double ptv_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* 1 when `povray` is on the PATH. */
PTV_MAYBE_UNUSED static int have_povray(void) { return system("command -v povray >/dev/null 2>&1") == 0; }

/* Renders POV (an exported scene) into EXR (+FE: linear half float) at W x H with the
   antialiasing options AA (NULL: the recipe's "+A0.0 +AM2 +R4", closest to a box-filtered
   pixel average); POV-Ray's output goes to LOG. Returns 1 when povray succeeded and wrote the
   file, and the wall time of the run (process start to exit) in *seconds (may be NULL). */
PTV_MAYBE_UNUSED static int run_povray(const char *pov, const char *exr, int w, int h, const char *aa, const char *log,
                                       double *seconds)
{
    char cmd[8192];
    double t0;
    int rc;
    remove(exr);
    snprintf(cmd, sizeof cmd, "povray +I'%s' +O'%s' +FE +W%d +H%d %s -D -V -GA >'%s' 2>&1", pov, exr, w, h,
             aa ? aa : "+A0.0 +AM2 +R4", log);
    t0 = ptv_now();
    rc = system(cmd);
    if (seconds) *seconds = ptv_now() - t0;
    return rc == 0 && access(exr, F_OK) == 0;
}

#endif /* PTV_COMMON_H */
