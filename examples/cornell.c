#define _POSIX_C_SOURCE 200809L
/* cornell.c - the final Cornell box of Shirley's "Ray Tracing: The Rest of Your Life",
   rendered with pdftrace and written as PPM (sRGB, 8 bit) and/or PFM (linear float), or
   EXR (half, ZIP) when built with PDFTRACE_OPENEXR (make OPENEXR=1).

       build/cornell --spp 64 -o out/cornell.ppm -o out/cornell.pfm
       build/cornell --scene scenes/cornell.scene -o out/cornell.pfm   (any scene file)

   Run with --help for the options. Options are checked before anything is rendered, and
   nothing is written unless the whole render succeeded. */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define PDFTRACE_IMPLEMENTATION
#define PDFTRACE_SCENE_IMPLEMENTATION /* --scene: the scene-file loader */
#include "pdftrace_scene.h"
#ifdef PDFTRACE_OPENEXR /* make OPENEXR=1: the EXR header of the family */
#define PDFTRACE_EXR_IMPLEMENTATION
#include "pdftrace_exr.h"
#endif

#define MAX_OUTPUTS 8

typedef struct options {
    int width, height;
    int spp;
    pt_strategy strategy;
    pt_sampler sampler;
    float light_weight;
    int max_depth;
    int threads;
    uint64_t seed;
    int quiet;
    const char *outputs[MAX_OUTPUTS];
    int output_count;
    const char *scene;   /* --scene PATH, or NULL for the built-in Cornell box */
    float adaptive;      /* --adaptive THRESHOLD, 0 = off */
    int adaptive_min_spp, adaptive_check, adaptive_neighbours_only;
    int indirect_paths;  /* --indirect-paths N, 0 = the header's default for the sampler */
    pt_backend backend;  /* --backend: traversal backend (AUTO: the header's rule) */
    unsigned disable_skips; /* PT_SKIP_* bits */
    unsigned given;      /* GIVEN_* bits: options set on the command line win over the scene file */
} options;

enum { GIVEN_W = 1, GIVEN_H = 2, GIVEN_SPP = 4, GIVEN_STRATEGY = 8, GIVEN_DEPTH = 16, GIVEN_SEED = 32,
       GIVEN_SAMPLER = 64, GIVEN_INDIRECT = 128 };

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

static const char *prog = "cornell";

static void usage(FILE *f)
{
    fprintf(f,
        "usage: %s [options]\n"
        "Renders the final Cornell box of \"Ray Tracing: The Rest of Your Life\".\n"
        "\n"
        "  -w, --width N         image width in pixels (default 600)\n"
        "  -h, --height N        image height in pixels (default 600)\n"
        "      --spp N           samples per pixel (default 128)\n"
        "      --strategy S      mis | material | light | mixture (default mis)\n"
        "      --sampler S       independent | sobol: where random numbers come from; sobol =\n"
        "                        scrambled Sobol points, lower error at equal spp (default\n"
        "                        independent)\n"
        "      --indirect-paths N  a camera sample continues from its first non-delta (not\n"
        "                        mirror or glass) vertex as N paths, 1..8 (default 3 with\n"
        "                        sobol, 1 with independent)\n"
        "      --light-weight W  light PDF weight of the mixture strategy, in (0, 1] (default 0.5)\n"
        "      --max-depth N     maximum scattering events per path (default 50)\n"
        "      --threads N       worker threads, 0 = all cores (default 0)\n"
        "      --backend B       auto | builtin | embree: ray traversal (embree needs a build with\n"
        "                        make EMBREE=1; default auto: Embree for large scenes when built in)\n"
        "      --seed N          random seed, a non-negative integer (default 0)\n"
        "  -o, --output PATH     write the image to PATH: PPM if it ends in .ppm, PFM if .pfm,\n"
        "                        EXR (half, ZIP) if .exr (needs a build with make OPENEXR=1);\n"
        "                        may be given up to %d times (default cornell.ppm)\n"
        "      --ppm PATH        same as -o PATH, PATH must end in .ppm\n"
        "      --pfm PATH        same as -o PATH, PATH must end in .pfm\n"
        "  -q, --quiet           no progress line\n"
        "      --scene PATH      render a scene file (format: pdftrace_scene.h) instead of\n"
        "                        the built-in box; its size, spp, depth, strategy, sampler, indirect\n"
        "                        paths and seed are the defaults, options given here override them\n"
        "      --adaptive T      adaptive sampling toward an image RMS relative error T (e.g. 0.05):\n"
        "                        each pixel gets samples in proportion to the square root of the\n"
        "                        noise of its 5x5 neighbourhood and stops when it has its share;\n"
        "                        --spp is then the most a pixel gets (default 0 = off)\n"
        "      --adaptive-min-spp N  samples every pixel gets before it can stop, >= 2\n"
        "                        (default max(16, spp/16))\n"
        "      --adaptive-check N    re-plan the shares every N passes (default 1)\n"
        "      --adaptive-neighbours-only  leave a pixel's own samples out of its noise\n"
        "                        estimate: about a third of the default's bias, more samples for\n"
        "                        the same error (default: counted, which darkens caustics and\n"
        "                        fireflies by ~1 %%, more in places; for a reference image do not\n"
        "                        use --adaptive)\n"
        "      --disable-skips L force the general path for the scene-feature skips in the\n"
        "                        comma-separated list L, or 'all': no-emitters, delta-vertex,\n"
        "                        facing-away, no-textures, zero-bsdf-shadow (for\n"
        "                        benchmarks; the image is the same in\n"
        "                        expectation)\n"
        "      --help            show this help and exit\n"
        "\n"
        "Long options also accept --name=value.\n",
        prog, MAX_OUTPUTS);
}

/* Prints "cornell: <message>" and a hint; returns 0 so that parsers can `return fail(...)`. */
static int fail(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s: ", prog);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n%s: try '%s --help'\n", prog, prog);
    return 0;
}

static int parse_long(const char *opt, const char *text, long lo, long hi, long *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(text, &end, 10);
    if (text[0] == '\0' || *end != '\0' || errno == ERANGE || v < lo || v > hi)
        return fail("option %s: expected an integer in [%ld, %ld], got '%s'", opt, lo, hi, text);
    *out = v;
    return 1;
}

static int parse_int(const char *opt, const char *text, int lo, int hi, int *out)
{
    long v = 0;
    if (!parse_long(opt, text, lo, hi, &v)) return 0;
    *out = (int)v;
    return 1;
}

static int parse_u64(const char *opt, const char *text, uint64_t *out)
{
    char *end;
    unsigned long long v;
    errno = 0;
    v = strtoull(text, &end, 10);
    if (text[0] < '0' || text[0] > '9' || *end != '\0' || errno == ERANGE) {
        return fail("option %s: expected a non-negative integer, got '%s'", opt, text);
    }
    *out = (uint64_t)v;
    return 1;
}

static int parse_light_weight(const char *opt, const char *text, float *out)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(text, &end);
    /* !(v > 0 && v <= 1) also rejects NaN. */
    if (text[0] == '\0' || *end != '\0' || errno == ERANGE || !(v > 0.0 && v <= 1.0)) {
        return fail("option %s: expected a number in (0, 1], got '%s'", opt, text);
    }
    *out = (float)v;
    return 1;
}

static int parse_threshold(const char *opt, const char *text, float *out)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(text, &end);
    /* !(v >= 0 && v < 1e30) also rejects NaN and infinity. */
    if (text[0] == '\0' || *end != '\0' || errno == ERANGE || !(v >= 0.0 && v < 1e30)) {
        return fail("option %s: expected a finite number >= 0, got '%s'", opt, text);
    }
    *out = (float)v;
    return 1;
}

static const struct { const char *name; unsigned bit; } skip_names[] = {
    { "no-emitters", PT_SKIP_NO_EMITTERS },   { "delta-vertex", PT_SKIP_DELTA_VERTEX },
    { "facing-away", PT_SKIP_FACING_AWAY },   { "no-textures", PT_SKIP_NO_TEXTURES },
    { "zero-bsdf-shadow", PT_SKIP_ZERO_BSDF_SHADOW }
};

/* "all" or a comma-separated list of the names above. */
static int parse_skips(const char *opt, const char *text, unsigned *out)
{
    const char *p = text;
    unsigned bits = 0;
    if (strcmp(text, "all") == 0) {
        *out = PT_SKIP_ALL;
        return 1;
    }
    for (;;) {
        const char *comma = strchr(p, ',');
        size_t n = comma ? (size_t)(comma - p) : strlen(p), k;
        int found = 0;
        for (k = 0; k < sizeof skip_names / sizeof skip_names[0]; k++)
            if (strlen(skip_names[k].name) == n && strncmp(p, skip_names[k].name, n) == 0) {
                bits |= skip_names[k].bit;
                found = 1;
            }
        if (!found) return fail("option %s: unknown skip '%.*s' (see --help)", opt, (int)n, p);
        if (!comma) break;
        p = comma + 1;
    }
    *out = bits;
    return 1;
}

static int parse_strategy(const char *opt, const char *text, pt_strategy *out)
{
    if (strcmp(text, "mis") == 0) *out = PT_STRATEGY_MIS;
    else if (strcmp(text, "material") == 0) *out = PT_STRATEGY_MATERIAL;
    else if (strcmp(text, "light") == 0) *out = PT_STRATEGY_LIGHT;
    else if (strcmp(text, "mixture") == 0) *out = PT_STRATEGY_MIXTURE;
    else return fail("option %s: expected mis, material, light or mixture, got '%s'", opt, text);
    return 1;
}

static int parse_sampler(const char *opt, const char *text, pt_sampler *out)
{
    if (strcmp(text, "independent") == 0) *out = PT_SAMPLER_INDEPENDENT;
    else if (strcmp(text, "sobol") == 0) *out = PT_SAMPLER_SOBOL;
    else return fail("option %s: expected independent or sobol, got '%s'", opt, text);
    return 1;
}

static int parse_backend(const char *opt, const char *text, pt_backend *out)
{
    if (strcmp(text, "auto") == 0) *out = PT_BACKEND_AUTO;
    else if (strcmp(text, "builtin") == 0) *out = PT_BACKEND_BUILTIN;
    else if (strcmp(text, "embree") == 0) *out = PT_BACKEND_EMBREE;
    else return fail("option %s: expected auto, builtin or embree, got '%s'", opt, text);
    return 1;
}

static const char *strategy_name(pt_strategy s)
{
    switch (s) {
    case PT_STRATEGY_MIS: return "mis";
    case PT_STRATEGY_MATERIAL: return "material";
    case PT_STRATEGY_LIGHT: return "light";
    case PT_STRATEGY_MIXTURE: return "mixture";
    }
    return "?";
}

static int ends_with(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n > m && strcmp(s + n - m, suffix) == 0;
}

/* Checks an output path before rendering: a known extension and a writable directory. */
static int check_output(const char *opt, const char *path, const char *required_ext)
{
    char dir[4096];
    const char *slash = strrchr(path, '/');
    size_t len;

    if (required_ext && !ends_with(path, required_ext))
        return fail("option %s: '%s' does not end in %s", opt, path, required_ext);
#ifndef PDFTRACE_OPENEXR
    if (ends_with(path, ".exr"))
        return fail("option %s: '%s': built without OpenEXR support: rebuild with make OPENEXR=1", opt, path);
#endif
    if (!ends_with(path, ".ppm") && !ends_with(path, ".pfm") && !ends_with(path, ".exr"))
        return fail("option %s: '%s' must end in .ppm, .pfm or .exr", opt, path);
    if (!slash) {
        strcpy(dir, ".");
    } else {
        len = slash == path ? 1 : (size_t)(slash - path);
        if (len >= sizeof dir) return fail("option %s: path too long: '%s'", opt, path);
        memcpy(dir, path, len);
        dir[len] = '\0';
    }
    if (access(dir, W_OK) != 0) {
        return fail("option %s: cannot write to directory '%s': %s", opt, dir, strerror(errno));
    }
    return 1;
}

/* Returns 1 on success, 0 after printing an error, 2 when --help was printed. */
static int parse_options(int argc, char **argv, options *o)
{
    int i;
    o->width = 600;
    o->height = 600;
    o->spp = 128;
    o->strategy = PT_STRATEGY_MIS;
    o->sampler = PT_SAMPLER_INDEPENDENT;
    o->light_weight = 0.5f;
    o->max_depth = 50;
    o->threads = 0;
    o->seed = 0;
    o->quiet = 0;
    o->output_count = 0;
    o->scene = NULL;
    o->given = 0;
    o->adaptive = 0.0f;
    o->adaptive_min_spp = 0;
    o->adaptive_check = 0;
    o->adaptive_neighbours_only = 0;
    o->indirect_paths = 0;
    o->backend = PT_BACKEND_AUTO;
    o->disable_skips = 0;

    for (i = 1; i < argc; i++) {
        const char *arg = argv[i];
        char name[64];
        const char *value = NULL;
        const char *eq = strchr(arg, '=');

        /* "--name=value" or "--name value" or "-x value". */
        if (strncmp(arg, "--", 2) == 0 && eq) {
            size_t n = (size_t)(eq - arg);
            if (n >= sizeof name) return fail("unknown option '%s'", arg);
            memcpy(name, arg, n);
            name[n] = '\0';
            value = eq + 1;
        } else {
            if (strlen(arg) >= sizeof name) return fail("unknown option '%s'", arg);
            strcpy(name, arg);
        }

        if (strcmp(name, "--help") == 0) {
            usage(stdout);
            return 2;
        }
        if (strcmp(name, "-q") == 0 || strcmp(name, "--quiet") == 0) {
            if (value) return fail("option %s takes no value", name);
            o->quiet = 1;
            continue;
        }
        if (strcmp(name, "--adaptive-neighbours-only") == 0) {
            if (value) return fail("option %s takes no value", name);
            o->adaptive_neighbours_only = 1;
            continue;
        }

        /* Every other option takes a value. */
        if (strcmp(name, "-w") && strcmp(name, "--width") && strcmp(name, "-h") && strcmp(name, "--height") &&
            strcmp(name, "--spp") && strcmp(name, "--strategy") && strcmp(name, "--sampler") &&
            strcmp(name, "--indirect-paths") && strcmp(name, "--backend") &&
            strcmp(name, "--light-weight") &&
            strcmp(name, "--max-depth") && strcmp(name, "--threads") && strcmp(name, "--seed") &&
            strcmp(name, "-o") && strcmp(name, "--output") && strcmp(name, "--ppm") && strcmp(name, "--pfm") &&
            strcmp(name, "--scene") && strcmp(name, "--adaptive") && strcmp(name, "--adaptive-min-spp") &&
            strcmp(name, "--adaptive-check") && strcmp(name, "--disable-skips")) {
            return fail("unknown option '%s'", arg);
        }
        if (!value) {
            if (i + 1 >= argc) return fail("option %s needs a value", name);
            value = argv[++i];
        }

        if (!strcmp(name, "-w") || !strcmp(name, "--width")) {
            if (!parse_int(name, value, 1, 16384, &o->width)) return 0;
            o->given |= GIVEN_W;
        } else if (!strcmp(name, "-h") || !strcmp(name, "--height")) {
            if (!parse_int(name, value, 1, 16384, &o->height)) return 0;
            o->given |= GIVEN_H;
        } else if (!strcmp(name, "--spp")) {
            if (!parse_int(name, value, 1, 1 << 20, &o->spp)) return 0;
            o->given |= GIVEN_SPP;
        } else if (!strcmp(name, "--strategy")) {
            if (!parse_strategy(name, value, &o->strategy)) return 0;
            o->given |= GIVEN_STRATEGY;
        } else if (!strcmp(name, "--sampler")) {
            if (!parse_sampler(name, value, &o->sampler)) return 0;
            o->given |= GIVEN_SAMPLER;
        } else if (!strcmp(name, "--indirect-paths")) {
            if (!parse_int(name, value, 1, 8, &o->indirect_paths)) return 0;
            o->given |= GIVEN_INDIRECT;
        } else if (!strcmp(name, "--backend")) {
            if (!parse_backend(name, value, &o->backend)) return 0;
        } else if (!strcmp(name, "--light-weight")) {
            if (!parse_light_weight(name, value, &o->light_weight)) return 0;
        } else if (!strcmp(name, "--max-depth")) {
            if (!parse_int(name, value, 1, 100000, &o->max_depth)) return 0;
            o->given |= GIVEN_DEPTH;
        } else if (!strcmp(name, "--threads")) {
            if (!parse_int(name, value, 0, 1024, &o->threads)) return 0;
        } else if (!strcmp(name, "--seed")) {
            if (!parse_u64(name, value, &o->seed)) return 0;
            o->given |= GIVEN_SEED;
        } else if (!strcmp(name, "--adaptive")) {
            if (!parse_threshold(name, value, &o->adaptive)) return 0;
        } else if (!strcmp(name, "--adaptive-min-spp")) {
            if (!parse_int(name, value, 2, 1 << 20, &o->adaptive_min_spp)) return 0;
        } else if (!strcmp(name, "--adaptive-check")) {
            if (!parse_int(name, value, 1, 1 << 20, &o->adaptive_check)) return 0;
        } else if (!strcmp(name, "--disable-skips")) {
            if (!parse_skips(name, value, &o->disable_skips)) return 0;
        } else if (!strcmp(name, "--scene")) {
            if (o->scene) return fail("option %s given twice", name);
            if (!*value) return fail("option %s: empty path", name);
            o->scene = value;
        } else { /* -o, --output, --ppm, --pfm */
            const char *ext = !strcmp(name, "--ppm") ? ".ppm" : !strcmp(name, "--pfm") ? ".pfm" : NULL;
            if (o->output_count == MAX_OUTPUTS) return fail("too many outputs (at most %d)", MAX_OUTPUTS);
            if (!check_output(name, value, ext)) return 0;
            o->outputs[o->output_count++] = value;
        }
    }
    if (o->output_count == 0) {
        if (!check_output("-o", "cornell.ppm", NULL)) return 0;
        o->outputs[o->output_count++] = "cornell.ppm";
    }
    return 1;
}

/* ---------------------------------------------------------------------------------------
   Progress and statistics
   --------------------------------------------------------------------------------------- */

/* One line, rewritten in place with \r on a terminal; one line per pass in a log file. */
static int show_progress(void *user, const pt_progress *p)
{
    int tty = *(const int *)user;
    double percent = p->samples_total ? 100.0 * (double)p->samples_done / (double)p->samples_total : 100.0;
    double rate = p->seconds > 0 ? (double)p->samples_done / p->seconds : 0.0;
    fprintf(stderr, "%spass %d/%d  %5.1f%%  %7.2f s  %.2f M samples/s%s", tty ? "\r" : "", p->pass, p->pass_count,
            percent, p->seconds, rate * 1e-6, tty ? "   " : "\n");
    fflush(stderr);
    return 0; /* never cancel */
}

static void print_stats(const options *o, const pt_scene *scene, const pt_render_stats *st)
{
    pt_scene_info info;
    uint64_t rays = st->camera_rays + st->bounce_rays + st->shadow_rays;
    double secs = st->seconds > 0 ? st->seconds : 1e-9;
    printf("image      %d x %d, %d spp, strategy %s", o->width, o->height, o->spp, strategy_name(o->strategy));
    if (o->strategy == PT_STRATEGY_MIXTURE) printf(" (light weight %g)", (double)o->light_weight);
    if (o->sampler == PT_SAMPLER_SOBOL) printf(", sobol sampler");
    if (o->indirect_paths) printf(", %d indirect path%s", o->indirect_paths, o->indirect_paths == 1 ? "" : "s");
    printf(", max depth %d, seed %llu\n", o->max_depth, (unsigned long long)o->seed);
    if (pt_scene_get_info(scene, &info) == PT_OK)
        printf("scene      %u primitives, %s traversal\n", (unsigned)info.primitive_count,
               info.backend == PT_BACKEND_EMBREE ? "Embree" : "built-in BVH");
    printf("time       %.3f s on %d thread%s, %d pass%s\n", st->seconds, st->threads, st->threads == 1 ? "" : "s",
           st->passes, st->passes == 1 ? "" : "es");
    printf("samples    %llu (%.3f M samples/s)\n", (unsigned long long)st->samples, (double)st->samples / secs * 1e-6);
    if (o->adaptive > 0.0f)
        printf("adaptive   threshold %g: %llu of %llu pixels converged early (%.1f%%), %u to %u spp, mean %.1f\n",
               (double)o->adaptive, (unsigned long long)st->pixels_converged,
               (unsigned long long)o->width * (unsigned long long)o->height,
               100.0 * (double)st->pixels_converged / ((double)o->width * (double)o->height), st->min_spp,
               st->max_spp, (double)st->samples / ((double)o->width * (double)o->height));
    if (st->estimated_error >= 0)
        printf("error      estimated RMS relative error %.4f (half-buffer estimate)\n", st->estimated_error);
    if (o->disable_skips) printf("skips      general path forced for mask 0x%x\n", o->disable_skips);
    printf("rays       %llu camera + %llu bounce + %llu shadow = %llu\n", (unsigned long long)st->camera_rays,
           (unsigned long long)st->bounce_rays, (unsigned long long)st->shadow_rays, (unsigned long long)rays);
    printf("rays/s     %.3f M\n", (double)rays / secs * 1e-6);
    printf("NaN/Inf    %llu samples\n", (unsigned long long)st->nonfinite_samples);
}

/* ---------------------------------------------------------------------------------------
   main
   --------------------------------------------------------------------------------------- */

int main(int argc, char **argv)
{
    options opt;
    pt_scene *scene;
    pt_render_desc desc = {0};
    pt_render_stats stats;
    pt_image image = {0};
    int rc, i, status = 0;
    int stderr_is_tty = isatty(STDERR_FILENO);

    rc = parse_options(argc, argv, &opt);
    if (rc == 2) return 0;
    if (rc == 0) return 2;

    if (opt.scene) {
        /* A scene file: its settings are the defaults; options given on the command line win. */
        pt_scenefile sd;
        pt_render_desc from_file;
        char err[1024];
        rc = pt_scenefile_load(opt.scene, &sd, err, sizeof err);
        if (rc == PT_OK) {
            rc = pt_scenefile_build(&sd, &scene, &from_file, err, sizeof err);
            pt_scenefile_free(&sd);
        }
        if (rc != PT_OK) {
            fprintf(stderr, "%s: %s\n", prog, err);
            return 1;
        }
        if (!(opt.given & GIVEN_W)) opt.width = from_file.width;
        if (!(opt.given & GIVEN_H)) opt.height = from_file.height;
        if (!(opt.given & GIVEN_SPP)) opt.spp = from_file.samples_per_pixel;
        if (!(opt.given & GIVEN_STRATEGY)) opt.strategy = from_file.strategy;
        if (!(opt.given & GIVEN_SAMPLER)) opt.sampler = from_file.sampler;
        if (!(opt.given & GIVEN_DEPTH)) opt.max_depth = from_file.max_depth;
        if (!(opt.given & GIVEN_SEED)) opt.seed = from_file.seed;
        if (!(opt.given & GIVEN_INDIRECT)) opt.indirect_paths = from_file.indirect_paths;
        desc.camera = from_file.camera;
        desc.background = from_file.background;
    } else {
        scene = pt_scene_create();
        if (!scene) {
            fprintf(stderr, "%s: out of memory\n", prog);
            return 1;
        }
        rc = build_cornell_box(scene);
        if (rc != PT_OK) {
            fprintf(stderr, "%s: building the scene failed: %s (%s)\n", prog, pt_result_string(rc),
                    pt_scene_error_message(scene));
            pt_scene_destroy(scene);
            return 1;
        }
        set_cornell_camera(&desc);
    }
    if (opt.backend != PT_BACKEND_AUTO) { /* the scene was committed with AUTO: commit again */
        rc = pt_scene_set_backend(scene, opt.backend);
        if (rc == PT_OK) rc = pt_scene_commit(scene);
        if (rc != PT_OK) {
            fprintf(stderr, "%s: --backend: %s (%s)\n", prog, pt_result_string(rc), pt_scene_error_message(scene));
            pt_scene_destroy(scene);
            return 1;
        }
    }

    desc.width = opt.width;
    desc.height = opt.height;
    desc.samples_per_pixel = opt.spp;
    desc.strategy = opt.strategy;
    desc.sampler = opt.sampler;
    desc.indirect_paths = opt.indirect_paths;
    desc.light_weight = opt.light_weight;
    desc.max_depth = opt.max_depth;
    desc.threads = opt.threads;
    desc.seed = opt.seed;
    desc.adaptive_threshold = opt.adaptive;
    desc.adaptive_min_spp = opt.adaptive_min_spp;
    desc.adaptive_check_passes = opt.adaptive_check;
    desc.adaptive_neighbours_only = opt.adaptive_neighbours_only;
    desc.disable_skips = opt.disable_skips;
    if (!opt.quiet) {
        desc.progress = show_progress;
        desc.progress_user = &stderr_is_tty;
    }

    rc = pt_render_image(scene, &desc, &image, &stats);
    if (!opt.quiet && stderr_is_tty) fputc('\n', stderr);
    if (rc != PT_OK) {
        fprintf(stderr, "%s: rendering failed: %s\n", prog, pt_result_string(rc));
        status = 1;
    } else {
        print_stats(&opt, scene, &stats);
        for (i = 0; i < opt.output_count; i++) {
            const char *path = opt.outputs[i];
            char err[512] = "";
#ifdef PDFTRACE_OPENEXR
            if (ends_with(path, ".exr")) rc = pt_write_exr(path, &image, NULL, err, sizeof err);
            else
#endif
            rc = ends_with(path, ".pfm") ? pt_write_pfm(path, &image) : pt_write_ppm(path, &image);
            if (rc != PT_OK) {
                fprintf(stderr, "%s: writing %s failed: %s%s%s\n", prog, path, pt_result_string(rc), err[0] ? ": " : "", err);
                status = 1;
            } else {
                printf("wrote      %s\n", path);
            }
        }
    }
    pt_image_free(&image);
    pt_scene_destroy(scene);
    return status;
}
