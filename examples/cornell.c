#define _POSIX_C_SOURCE 200809L
/* cornell.c - the final Cornell box of Shirley's "Ray Tracing: The Rest of Your Life", built
   through pdftrace's C API: materials, quads, a transformed box and a sphere, then the camera,
   a render and the image files. `make run` runs it. For scene files and every render setting,
   use the pdftrace command (tools/pdftrace.c); scenes/cornell.scene is this same box.

       build/cornell --spp 64 -o out/cornell.png -o out/cornell.pfm

   Options: --spp N (default 32, Sobol points), -o FILE (repeatable; .ppm, .pfm, and .png when built with
   libpng: make PNG=auto|1), -q, --threads N, --help. Outputs are checked before rendering. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#ifdef PDFTRACE_PNG /* the Makefile's PNG=auto|1: PNG output through libpng */
#define PDFTRACE_PNG_IMPLEMENTATION
#include "pdftrace_png.h"
#define FORMATS ".ppm, .pfm or .png"
#define DEFAULT_OUTPUT "cornell.png"
#else
#define FORMATS ".ppm or .pfm (.png needs libpng)"
#define DEFAULT_OUTPUT "cornell.ppm"
#endif

/* ---------------------------------------------------------------------------------------
   The scene: exactly the book's final Cornell box. A quad is Q + a*u + b*v, a, b in [0,1].
   --------------------------------------------------------------------------------------- */

/* Adds everything to `s` and commits it. Returns PT_OK or the first error code. */
static int build_cornell_box(pt_scene *s)
{
    int rc = PT_OK;
    int red = pt_scene_add_lambertian(s, pt_v3(0.65f, 0.05f, 0.05f));
    int white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
    int green = pt_scene_add_lambertian(s, pt_v3(0.12f, 0.45f, 0.15f));
    int light = pt_scene_add_emitter(s, pt_v3(15, 15, 15), 0); /* one-sided: emits along u x v */
    int glass = pt_scene_add_dielectric(s, 1.5f);
    pt_transform box_to_world;

    if (red < 0) return red;
    if (white < 0) return white;
    if (green < 0) return green;
    if (light < 0) return light;
    if (glass < 0) return glass;

#define ADD(call) do { if (rc >= 0) rc = (call); } while (0)
    /* Walls (Lambertian reflection is two-sided, so their orientation does not matter). */
    ADD(pt_scene_add_quad(s, pt_v3(555, 0, 0), pt_v3(0, 555, 0), pt_v3(0, 0, 555), green));    /* left, seen from the camera */
    ADD(pt_scene_add_quad(s, pt_v3(0, 0, 555), pt_v3(0, 0, -555), pt_v3(0, 555, 0), red));     /* right */
    ADD(pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(555, 0, 0), pt_v3(0, 0, 555), white));      /* floor */
    ADD(pt_scene_add_quad(s, pt_v3(555, 555, 555), pt_v3(-555, 0, 0), pt_v3(0, 0, -555), white)); /* ceiling */
    ADD(pt_scene_add_quad(s, pt_v3(0, 0, 555), pt_v3(555, 0, 0), pt_v3(0, 555, 0), white));    /* back */

    /* The light, 130 x 105 just below the ceiling: u x v = (0, -13650, 0) points down. */
    ADD(pt_scene_add_quad(s, pt_v3(343, 554, 332), pt_v3(-130, 0, 0), pt_v3(0, 0, -105), light));

    /* The tall white box: rotated 15 degrees about +y, then moved to (265, 0, 295). */
    box_to_world = pt_transform_mul(pt_transform_translate(pt_v3(265, 0, 295)), pt_transform_rotate_y(15));
    ADD(pt_scene_set_transform(s, &box_to_world));
    ADD(pt_scene_add_box(s, pt_v3(0, 0, 0), pt_v3(165, 330, 165), white));
    ADD(pt_scene_set_transform(s, NULL));

    /* The glass sphere. */
    ADD(pt_scene_add_sphere(s, pt_v3(190, 90, 190), 90, glass));
#undef ADD

    if (rc >= 0) rc = pt_scene_commit(s);
    return rc < 0 ? rc : PT_OK;
}

/* The book's camera: 40 degree vertical field of view, no defocus, black background. */
static void set_cornell_camera(pt_render_desc *d)
{
    d->camera.look_from = pt_v3(278, 278, -800);
    d->camera.look_at = pt_v3(278, 278, 0);
    d->camera.up = pt_v3(0, 1, 0);
    d->camera.vfov_degrees = 40;
    d->camera.lens_radius = 0;
    d->background = pt_v3(0, 0, 0);
}

/* ---------------------------------------------------------------------------------------
   Command line
   --------------------------------------------------------------------------------------- */

#define MAX_OUTPUTS 8

typedef struct options {
    int spp, threads, quiet;
    const char *outputs[MAX_OUTPUTS];
    int output_count;
} options;

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n > m && strcmp(s + n - m, suffix) == 0;
}

/* A known extension this build writes, in a directory we may write to. */
static int check_output(const char *path)
{
    char dir[4096];
    const char *slash;
    size_t len;
    if (!path) {
        fprintf(stderr, "cornell: -o needs a file name\n");
        return 0;
    }
#ifndef PDFTRACE_PNG
    if (ends_with(path, ".png")) {
        fprintf(stderr, "cornell: %s: built without PNG support (install libpng-dev and rebuild)\n", path);
        return 0;
    }
#endif
    if (!ends_with(path, ".ppm") && !ends_with(path, ".pfm") && !ends_with(path, ".png")) {
        fprintf(stderr, "cornell: %s: unknown image format (use " FORMATS ")\n", path);
        return 0;
    }
    slash = strrchr(path, '/');
    len = !slash ? 1 : slash == path ? 1 : (size_t)(slash - path);
    if (len >= sizeof dir) {
        fprintf(stderr, "cornell: %s: path too long\n", path);
        return 0;
    }
    if (!slash) strcpy(dir, ".");
    else {
        memcpy(dir, path, len);
        dir[len] = '\0';
    }
    if (access(dir, W_OK) != 0) {
        fprintf(stderr, "cornell: %s: cannot write to directory '%s': %s\n", path, dir, strerror(errno));
        return 0;
    }
    return 1;
}

/* An integer in [lo, hi]. */
static int parse_int(const char *opt, const char *text, int lo, int hi, int *out)
{
    char *end;
    long v;
    if (!text) {
        fprintf(stderr, "cornell: %s needs a value\n", opt);
        return 0;
    }
    errno = 0;
    v = strtol(text, &end, 10);
    if (!*text || *end || errno == ERANGE || v < lo || v > hi) {
        fprintf(stderr, "cornell: %s: expected an integer in [%d, %d], got '%s'\n", opt, lo, hi, text);
        return 0;
    }
    *out = (int)v;
    return 1;
}

static void usage(void)
{
    printf("usage: cornell [--spp N] [-o FILE]... [--threads N] [-q]\n"
           "Renders the final Cornell box of \"Ray Tracing: The Rest of Your Life\", 600 x 600,\n"
           "built through the C API. --spp: samples per pixel (32, Sobol points); --threads: 0 = all cores;\n"
           "-o: up to %d files, " FORMATS " (default " DEFAULT_OUTPUT "); -q: quiet.\n"
           "For scene files and every render setting, see pdftrace --help.\n", MAX_OUTPUTS);
}

/* Returns 1 to render, 0 after an error, 2 after --help. */
static int parse_options(int argc, char **argv, options *o)
{
    int i;
    memset(o, 0, sizeof *o);
    o->spp = 32;
    for (i = 1; i < argc; i++) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage();
            return 2;
        } else if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
            o->quiet = 1;
        } else if (!strcmp(a, "--spp")) {
            if (!parse_int(a, v, 1, 1 << 20, &o->spp)) return 0;
            i++;
        } else if (!strcmp(a, "--threads")) {
            if (!parse_int(a, v, 0, 1024, &o->threads)) return 0;
            i++;
        } else if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (o->output_count == MAX_OUTPUTS) {
                fprintf(stderr, "cornell: at most %d outputs\n", MAX_OUTPUTS);
                return 0;
            }
            if (!check_output(v)) return 0;
            o->outputs[o->output_count++] = v;
            i++;
        } else {
            fprintf(stderr, "cornell: unknown option '%s' (see cornell --help)\n", a);
            return 0;
        }
    }
    if (o->output_count == 0) o->outputs[o->output_count++] = DEFAULT_OUTPUT;
    return 1;
}

/* ---------------------------------------------------------------------------------------
   Render and write
   --------------------------------------------------------------------------------------- */

/* A percentage, rewritten in place on a terminal (pt_render calls it after every pass). */
static int show_progress(void *user, const pt_progress *p)
{
    (void)user;
    fprintf(stderr, "\rrendering %3d%%", (int)(100 * p->samples_done / (p->samples_total ? p->samples_total : 1)));
    fflush(stderr);
    return 0; /* never cancel */
}

static int write_image(const char *path, const pt_image *img)
{
    char err[1024] = "";
    int rc;
#ifdef PDFTRACE_PNG
    if (ends_with(path, ".png")) rc = pt_write_png(path, img, err, sizeof err);
    else
#endif
    rc = ends_with(path, ".pfm") ? pt_write_pfm_ex(path, img, err, sizeof err) : pt_write_ppm_ex(path, img, err, sizeof err);
    if (rc != PT_OK) {
        if (err[0]) fprintf(stderr, "cornell: %s\n", err);
        else fprintf(stderr, "cornell: %s: writing failed: %s\n", path, pt_result_string(rc));
    }
    return rc == PT_OK;
}

int main(int argc, char **argv)
{
    options opt;
    pt_scene *scene;
    pt_render_desc desc = {0}; /* zero means "default" for every field */
    pt_render_stats stats;
    pt_image image = {0};
    int rc, i, status = 0;

    rc = parse_options(argc, argv, &opt);
    if (rc != 1) return rc == 2 ? 0 : 2;

    scene = pt_scene_create();
    if (!scene) {
        fprintf(stderr, "cornell: out of memory\n");
        return 1;
    }
    rc = build_cornell_box(scene);
    if (rc != PT_OK) {
        fprintf(stderr, "cornell: building the scene failed: %s\n", pt_scene_error_message(scene));
        pt_scene_destroy(scene);
        return 1;
    }
    set_cornell_camera(&desc);
    desc.width = 600;
    desc.height = 600;
    desc.samples_per_pixel = opt.spp;
    desc.sampler = PT_SAMPLER_SOBOL; /* as a scene file's default: the most efficient measured */
    desc.threads = opt.threads;
    if (!opt.quiet && isatty(STDERR_FILENO)) desc.progress = show_progress;

    rc = pt_render_image(scene, &desc, &image, &stats);
    if (desc.progress) fputc('\n', stderr);
    if (rc != PT_OK) {
        fprintf(stderr, "cornell: rendering failed: %s\n", stats.error[0] ? stats.error : pt_result_string(rc));
        status = 1;
    } else {
        if (!opt.quiet)
            printf("rendered   600 x 600, %d spp in %.2f s on %d thread%s (%.2f M samples/s)\n", opt.spp, stats.seconds,
                   stats.threads, stats.threads == 1 ? "" : "s", (double)stats.samples / (stats.seconds > 0 ? stats.seconds : 1e-9) * 1e-6);
        for (i = 0; i < opt.output_count; i++) {
            if (!write_image(opt.outputs[i], &image)) status = 1;
            else if (!opt.quiet) printf("wrote      %s\n", opt.outputs[i]);
        }
    }
    pt_image_free(&image);
    pt_scene_destroy(scene);
    return status;
}
