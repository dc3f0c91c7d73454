#define _POSIX_C_SOURCE 200809L
/* pdftrace.c - the pdftrace command: renders a scene file (the format of pdftrace_scene.h) and
   writes the image as PNG, OpenEXR, PFM or PPM, chosen by each output's extension.

       pdftrace scenes/cornell.scene -o cornell.png -o cornell.exr --spp 256

   Run with --help for the options. The whole command line, the scene file and the outputs are
   checked before anything renders: a bad option or value, a scene file that does not load or an
   output that cannot be written gives one line on stderr and exit status 2, and no file is
   written. A failure once rendering has started gives exit status 1.
   Built with -DPDFTRACE_PNG (pdftrace_png.h, libpng) and -DPDFTRACE_OPENEXR (pdftrace_exr.h,
   OpenEXRCore) when those libraries are present: the Makefile's PNG and TOOL_EXR.
   Built with -DPDFTRACE_MPI (make MPI=1; pdftrace_mpi.h) it also runs under mpirun: every rank
   loads the scene and renders its share of the samples (pt_render_desc.split_parts), rank 0
   gathers the films in rank order and writes the outputs, which are byte for byte those of a
   one-process render (docs/mpi.md). Until rendering starts every failure is agreed on by all
   ranks: the first failing rank prints its one line ("pdftrace: rank R: ...") and every rank
   exits with its status; a failure once ranks may wait on each other ends the job (MPI_Abort). */
#include <errno.h>
#include <float.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define PDFTRACE_IMPLEMENTATION
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"
#ifdef PDFTRACE_PNG
#define PDFTRACE_PNG_IMPLEMENTATION
#include "pdftrace_png.h"
#endif
#ifdef PDFTRACE_OPENEXR
#define PDFTRACE_EXR_IMPLEMENTATION
#include "pdftrace_exr.h"
#endif
#ifdef PDFTRACE_MPI
#define PDFTRACE_MPI_IMPLEMENTATION
#include "pdftrace_mpi.h"
#endif

#define MAX_OUTPUTS 16
#define MAX_ALLOWED_DIRS 16
#define EXIT_USAGE 2 /* bad command line, scene file or output path: nothing was written */

typedef enum format { FMT_PNG, FMT_EXR, FMT_PFM, FMT_PPM } format;

typedef struct output {
    const char *path;
    format fmt;
} output;

/* The render settings a scene file has; set on the command line, they replace the file's. */
enum { GIVEN_WIDTH = 1, GIVEN_HEIGHT = 2, GIVEN_SPP = 4, GIVEN_STRATEGY = 8, GIVEN_SAMPLER = 16,
       GIVEN_SEED = 32, GIVEN_DEPTH = 64, GIVEN_INDIRECT = 128, GIVEN_GUIDING = 256, GIVEN_GUIDING_BUDGET = 512,
       GIVEN_GUIDING_ALPHA = 1024, GIVEN_GUIDING_MEMORY = 2048, GIVEN_INTEGRATOR = 4096 };

#define GUIDE_IMAGE_HEIGHT 256 /* --guide-at: a 512 x 256 latitude-longitude picture */

typedef struct options {
    const char *scene;
    output outputs[MAX_OUTPUTS];
    int output_count;
    char default_output[4096];   /* SCENE's base name + .png (.ppm without libpng) */
    const char *pov;             /* --export-pov */
    const char *mitsuba;         /* --export-mitsuba */
    output guide_out;            /* --guide-at X Y Z OUT: the picture (path NULL: none) */
    pt_vec3 guide_at;            /* its point, world coordinates */
    pt_render_desc set;          /* the settings given: the scene file's ones only where `given` says */
    unsigned given;              /* GIVEN_* */
    pt_backend backend;
    pt_display_desc display;     /* for the 8-bit outputs */
    double preview_every;        /* seconds; 0: off */
    int quiet;
    const char *allowed_dirs[MAX_ALLOWED_DIRS]; /* --allow-path: more directories meshes and maps may come from */
    pt_scenefile_options load;   /* what the scene file may read and allocate */
} options;

enum { PARSED = 0, PARSED_EXIT = 1, PARSE_FAILED = 2 }; /* PARSED_EXIT: --help or --version printed */

/* ---------------------------------------------------------------------------------------
   Messages and help
   --------------------------------------------------------------------------------------- */

/* One line on stderr, "pdftrace: <message>". Returns PARSE_FAILED so that checks can `return fail(...)`. */
/* Under MPI with several ranks (g_ranks > 1), messages before rendering are held (g_held: the
   first one) until the ranks agree on who failed (mpi_gate); warnings come from rank 0 only. */
static int g_rank = 0, g_ranks = 1, g_hold = 0;
static char g_held[1024];
#ifdef PDFTRACE_MPI
static pt_mpi g_mpi;
#endif

static int fail(const char *fmt, ...)
{
    va_list ap;
    if (g_ranks > 1) {
        char line[1024];
        va_start(ap, fmt);
        vsnprintf(line, sizeof line, fmt, ap);
        va_end(ap);
        if (strncmp(line, "warning:", 8) == 0) {
            if (g_rank == 0) fprintf(stderr, "pdftrace: %s\n", line);
        } else if (g_hold) {
            if (!g_held[0]) memcpy(g_held, line, sizeof line);
        } else {
            fprintf(stderr, "pdftrace: rank %d: %s\n", g_rank, line);
        }
        return PARSE_FAILED;
    }
    fputs("pdftrace: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    return PARSE_FAILED;
}

static int have_png(void)
{
#ifdef PDFTRACE_PNG
    return 1;
#else
    return 0;
#endif
}
static int have_exr(void)
{
#ifdef PDFTRACE_OPENEXR
    return 1;
#else
    return 0;
#endif
}
static int have_embree(void)
{
#ifdef PDFTRACE_EMBREE
    return 1;
#else
    return 0;
#endif
}

static void print_help(void)
{
    printf("usage: pdftrace SCENE [options]\n"
           "Renders a scene file (format: pdftrace_scene.h) and writes the image.\n"
           "\n"
           "  -o, --output FILE      write the image; repeatable; format by extension: .png (8-bit\n"
           "                         sRGB), .exr (half RGB), .pfm (float RGB), .ppm (8-bit sRGB);\n"
           "                         default: SCENE's base name + .png in the current directory\n"
           "Render settings (they override the scene file's):\n"
           "      --width N, --height N, --size WxH   image size in pixels\n"
           "      --spp N            samples per pixel (with --adaptive: the most a pixel gets)\n"
           "      --strategy S       mis | material | light | mixture; --sampler S: independent | sobol\n"
           "      --seed N, --threads N  random seed (>= 0); worker threads, 0 = all cores (0)\n"
           "      --max-depth N      scattering events per path (1: direct light only)\n"
           "      --indirect-paths N paths each camera sample continues as, 1..8\n"
           "      --light-weight W   light PDF weight of the mixture strategy, in (0, 1] (0.5)\n"
           "      --backend B        auto | builtin | embree (auto); --integrator scalar | batched (auto)\n"
           "      --guiding G        off | on | auto: path guiding (auto: only where training pays)\n"
           "      --guiding-budget F, --guiding-alpha F  in (0, 1): training's share of spp (0.25),\n"
           "                         the material's in the guided mixture (0.7); --guiding-memory MIB (64)\n"
           "      --adaptive T       adaptive sampling toward RMS relative error T, e.g. 0.05\n"
           "      --adaptive-mode M  pilot (unbiased) | own-samples | neighbours (biased) (pilot)\n"
           "      --adaptive-min-spp N  the pilot's spp, or the least a pixel gets (max(16, spp/16))\n"
           "      --adaptive-check N    own-samples, neighbours: re-plan every N passes (1)\n"
           "      --adaptive-neighbours-only  the same as --adaptive-mode neighbours\n"
           "      --disable-skips L  force the general path (for benchmarks): all, or a list of\n"
           "                         no-emitters,delta-vertex,facing-away,no-textures,zero-bsdf-shadow,\n"
           "                         solid-angle-quads,light-tree\n"
           "Display, for .png and .ppm:\n"
           "      --exposure EV      multiply by 2^EV (0); --tonemap T: clamp | aces | reinhard (clamp)\n"
           "Other:\n"
           "      --preview-every S  rewrite the outputs every S seconds while rendering\n"
           "      --guide-at X Y Z OUT  render guided, write the guide learned at X Y Z: lat-long map\n"
           "      --export-pov FILE  write the scene for POV-Ray 3.7 (renders too only with -o)\n"
           "      --export-mitsuba FILE.xml  write the scene for Mitsuba 3 (meshes as FILE.N.ply beside it;\n"
           "                         renders too only with -o)\n"
           "      --allow-path DIR   meshes and environment maps may also come from DIR (default: none)\n"
           "      --mesh-memory MB, --image-memory MB  memory limits of the scene (1024, 4096)\n"
           "  -q, --quiet            no progress and no statistics\n"
           "  -h, --help, --version  this help; the version and the formats built in\n"
           "Long options also take --name=value. Exit status: 0 done, 1 rendering or writing\n"
           "failed, 2 bad command line, scene file or output (nothing written).\n");
    if (!have_png() || !have_exr())
        printf("This build has no %s output (rebuild with %s installed).\n",
               !have_png() && !have_exr() ? ".png or .exr" : !have_png() ? ".png" : ".exr",
               !have_png() && !have_exr() ? "libpng-dev and libopenexr-dev" : !have_png() ? "libpng-dev" : "libopenexr-dev");
}

static void print_version(void)
{
#ifdef PDFTRACE_MPI
    const char *mpi = "yes";
#else
    const char *mpi = "no";
#endif
    printf("pdftrace %d.%d.%d (PNG %s, OpenEXR %s, Embree %s, MPI %s)\n", PDFTRACE_VERSION_MAJOR, PDFTRACE_VERSION_MINOR,
           PDFTRACE_VERSION_PATCH, have_png() ? "yes" : "no", have_exr() ? "yes" : "no", have_embree() ? "yes" : "no", mpi);
}

/* ---------------------------------------------------------------------------------------
   Values
   --------------------------------------------------------------------------------------- */

static int parse_long(const char *opt, const char *text, long lo, long hi, long *out)
{
    char *end;
    long v;
    errno = 0;
    v = strtol(text, &end, 10);
    if (text[0] == '\0' || *end != '\0' || errno == ERANGE || v < lo || v > hi)
        return fail("%s: expected an integer in [%ld, %ld], got '%s'", opt, lo, hi, text);
    *out = v;
    return PARSED;
}

static int parse_int(const char *opt, const char *text, int lo, int hi, int *out)
{
    long v = 0;
    if (parse_long(opt, text, lo, hi, &v) != PARSED) return PARSE_FAILED;
    *out = (int)v;
    return PARSED;
}

static int parse_u64(const char *opt, const char *text, uint64_t *out)
{
    char *end;
    unsigned long long v;
    errno = 0;
    v = strtoull(text, &end, 10);
    if (text[0] < '0' || text[0] > '9' || *end != '\0' || errno == ERANGE)
        return fail("%s: expected a non-negative integer, got '%s'", opt, text);
    *out = (uint64_t)v;
    return PARSED;
}

/* A finite number in [lo, hi], or in (lo, hi] when lo_open; `range` describes it in messages. */
static int parse_real(const char *opt, const char *text, double lo, double hi, int lo_open, const char *range,
                      float *out)
{
    char *end;
    double v;
    errno = 0;
    v = strtod(text, &end);
    /* written as !(inside) so that NaN fails too */
    if (text[0] == '\0' || *end != '\0' || errno == ERANGE || !(lo_open ? v > lo : v >= lo) || !(v <= hi))
        return fail("%s: expected %s, got '%s'", opt, range, text);
    *out = (float)v;
    return PARSED;
}

/* A number strictly inside (0, 1), also once stored as a float (0.999999999 would round to 1). */
static int parse_open_unit(const char *opt, const char *text, float *out)
{
    float f = 0.0f;
    if (parse_real(opt, text, 0.0, 1.0, 1, "a number in (0, 1)", &f) != PARSED) return PARSE_FAILED;
    if (!(f > 0.0f && f < 1.0f)) return fail("%s: expected a number in (0, 1), got '%s'", opt, text);
    *out = f;
    return PARSED;
}

/* "WxH", each 1..16384. */
static int parse_size(const char *opt, const char *text, int *w, int *h)
{
    char *end, *end2;
    long a, b;
    errno = 0;
    a = strtol(text, &end, 10);
    if (end == text || (*end != 'x' && *end != 'X')) return fail("%s: expected WxH (e.g. 640x480), got '%s'", opt, text);
    b = strtol(end + 1, &end2, 10);
    if (end2 == end + 1 || *end2 != '\0' || errno == ERANGE || a < 1 || a > 16384 || b < 1 || b > 16384)
        return fail("%s: expected WxH with W and H in [1, 16384], got '%s'", opt, text);
    *w = (int)a;
    *h = (int)b;
    return PARSED;
}

/* text is one of names[0 .. count-1]: *index is its position. */
static int parse_choice(const char *opt, const char *text, const char *const *names, int count, const char *list,
                        int *index)
{
    int i;
    for (i = 0; i < count; i++)
        if (strcmp(text, names[i]) == 0) {
            *index = i;
            return PARSED;
        }
    return fail("%s: expected %s, got '%s'", opt, list, text);
}

static const struct { const char *name; unsigned bit; } skip_names[] = {
    { "no-emitters", PT_SKIP_NO_EMITTERS },   { "delta-vertex", PT_SKIP_DELTA_VERTEX },
    { "facing-away", PT_SKIP_FACING_AWAY },   { "no-textures", PT_SKIP_NO_TEXTURES },
    { "zero-bsdf-shadow", PT_SKIP_ZERO_BSDF_SHADOW }, { "solid-angle-quads", PT_SKIP_SOLID_ANGLE_QUADS },
    { "light-tree", PT_SKIP_LIGHT_TREE }
};

/* "all", a comma-separated list of skip_names, or a number whose bits lie in PT_SKIP_ALL. */
static int parse_skips(const char *opt, const char *text, unsigned *out)
{
    const char *p = text;
    unsigned bits = 0;
    if (strcmp(text, "all") == 0) {
        *out = PT_SKIP_ALL;
        return PARSED;
    }
    if (text[0] >= '0' && text[0] <= '9') {
        char *end;
        unsigned long v = strtoul(text, &end, 0);
        if (*end != '\0' || (v & ~(unsigned long)PT_SKIP_ALL) != 0)
            return fail("%s: '%s' is not a set of PT_SKIP_* bits (mask 0x%x)", opt, text, PT_SKIP_ALL);
        *out = (unsigned)v;
        return PARSED;
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
        if (!found) return fail("%s: unknown skip '%.*s' (see --help)", opt, (int)n, p);
        if (!comma) break;
        p = comma + 1;
    }
    *out = bits;
    return PARSED;
}

/* ---------------------------------------------------------------------------------------
   Options: a table of names, then one function per group of what they set
   --------------------------------------------------------------------------------------- */

typedef enum opt_id {
    O_OUTPUT, O_WIDTH, O_HEIGHT, O_SIZE, O_SPP, O_STRATEGY, O_SAMPLER, O_SEED, O_MAX_DEPTH, O_INDIRECT,
    O_LIGHT_WEIGHT, O_THREADS, O_BACKEND, O_ADAPTIVE, O_ADAPTIVE_MIN, O_ADAPTIVE_CHECK, O_ADAPTIVE_NB, O_ADAPTIVE_MODE,
    O_SKIPS, O_EXPOSURE, O_TONEMAP, O_PREVIEW, O_POV, O_MITSUBA, O_QUIET, O_HELP, O_VERSION, O_ALLOW_PATH,
    O_MESH_MEMORY, O_IMAGE_MEMORY, O_GUIDING, O_GUIDING_BUDGET, O_GUIDING_ALPHA, O_GUIDING_MEMORY, O_GUIDE_AT, O_INTEGRATOR
} opt_id;

static const struct option_def {
    const char *name, *alias; /* alias: the short form, or NULL */
    int takes_value;          /* how many values: 0, 1, or 4 (--guide-at X Y Z OUT) */
    opt_id id;
} option_defs[] = {
    { "--output", "-o", 1, O_OUTPUT },        { "--width", NULL, 1, O_WIDTH },
    { "--height", NULL, 1, O_HEIGHT },        { "--size", NULL, 1, O_SIZE },
    { "--spp", NULL, 1, O_SPP },              { "--strategy", NULL, 1, O_STRATEGY },
    { "--sampler", NULL, 1, O_SAMPLER },      { "--seed", NULL, 1, O_SEED },
    { "--max-depth", NULL, 1, O_MAX_DEPTH },  { "--indirect-paths", NULL, 1, O_INDIRECT },
    { "--light-weight", NULL, 1, O_LIGHT_WEIGHT }, { "--threads", NULL, 1, O_THREADS },
    { "--backend", NULL, 1, O_BACKEND },      { "--adaptive", NULL, 1, O_ADAPTIVE },
    { "--adaptive-min-spp", NULL, 1, O_ADAPTIVE_MIN }, { "--adaptive-check", NULL, 1, O_ADAPTIVE_CHECK },
    { "--adaptive-neighbours-only", NULL, 0, O_ADAPTIVE_NB }, { "--adaptive-mode", NULL, 1, O_ADAPTIVE_MODE },
    { "--disable-skips", NULL, 1, O_SKIPS },
    { "--exposure", NULL, 1, O_EXPOSURE },    { "--tonemap", NULL, 1, O_TONEMAP },
    { "--preview-every", NULL, 1, O_PREVIEW }, { "--export-pov", NULL, 1, O_POV },
    { "--export-mitsuba", NULL, 1, O_MITSUBA },
    { "--quiet", "-q", 0, O_QUIET },          { "--help", "-h", 0, O_HELP },
    { "--version", NULL, 0, O_VERSION },      { "--allow-path", NULL, 1, O_ALLOW_PATH },
    { "--mesh-memory", NULL, 1, O_MESH_MEMORY }, { "--image-memory", NULL, 1, O_IMAGE_MEMORY },
    { "--guiding", NULL, 1, O_GUIDING },      { "--guiding-budget", NULL, 1, O_GUIDING_BUDGET },
    { "--guiding-alpha", NULL, 1, O_GUIDING_ALPHA }, { "--guiding-memory", NULL, 1, O_GUIDING_MEMORY },
    { "--guide-at", NULL, 4, O_GUIDE_AT },    { "--integrator", NULL, 1, O_INTEGRATOR }
};

static const struct option_def *find_option(const char *name)
{
    size_t k;
    for (k = 0; k < sizeof option_defs / sizeof option_defs[0]; k++)
        if (strcmp(name, option_defs[k].name) == 0 || (option_defs[k].alias && strcmp(name, option_defs[k].alias) == 0))
            return &option_defs[k];
    return NULL;
}

/* The settings a scene file has too (GIVEN_* records that they were set here). */
static int set_scene_setting(options *o, opt_id id, const char *name, const char *v)
{
    static const char *const strategies[] = { "mis", "material", "light", "mixture" };
    static const pt_strategy strategy_ids[] = { PT_STRATEGY_MIS, PT_STRATEGY_MATERIAL, PT_STRATEGY_LIGHT,
                                                PT_STRATEGY_MIXTURE };
    static const char *const samplers[] = { "independent", "sobol" };
    static const char *const integrators[] = { "scalar", "batched" };
    static const char *const guidings[] = { "off", "on", "auto" };
    static const pt_guiding guiding_ids[] = { PT_GUIDING_OFF, PT_GUIDING_ON, PT_GUIDING_AUTO };
    pt_render_desc *d = &o->set;
    int k = 0, rc = PARSED;
    switch (id) {
    case O_WIDTH: rc = parse_int(name, v, 1, 16384, &d->width); o->given |= GIVEN_WIDTH; break;
    case O_HEIGHT: rc = parse_int(name, v, 1, 16384, &d->height); o->given |= GIVEN_HEIGHT; break;
    case O_SIZE:
        rc = parse_size(name, v, &d->width, &d->height);
        o->given |= GIVEN_WIDTH | GIVEN_HEIGHT;
        break;
    case O_SPP: rc = parse_int(name, v, 1, 1 << 20, &d->samples_per_pixel); o->given |= GIVEN_SPP; break;
    case O_STRATEGY:
        rc = parse_choice(name, v, strategies, 4, "mis, material, light or mixture", &k);
        d->strategy = strategy_ids[k];
        o->given |= GIVEN_STRATEGY;
        break;
    case O_SAMPLER:
        rc = parse_choice(name, v, samplers, 2, "independent or sobol", &k);
        d->sampler = k ? PT_SAMPLER_SOBOL : PT_SAMPLER_INDEPENDENT;
        o->given |= GIVEN_SAMPLER;
        break;
    case O_INTEGRATOR:
        rc = parse_choice(name, v, integrators, 2, "scalar or batched", &k);
        d->integrator = k ? PT_INTEGRATOR_BATCHED : PT_INTEGRATOR_SCALAR;
        o->given |= GIVEN_INTEGRATOR;
        break;
    case O_SEED: rc = parse_u64(name, v, &d->seed); o->given |= GIVEN_SEED; break;
    case O_MAX_DEPTH: rc = parse_int(name, v, 1, 100000, &d->max_depth); o->given |= GIVEN_DEPTH; break;
    case O_INDIRECT: rc = parse_int(name, v, 1, 8, &d->indirect_paths); o->given |= GIVEN_INDIRECT; break;
    case O_GUIDING:
        rc = parse_choice(name, v, guidings, 3, "off, on or auto", &k);
        d->guiding = guiding_ids[k];
        o->given |= GIVEN_GUIDING;
        break;
    case O_GUIDING_BUDGET: rc = parse_open_unit(name, v, &d->guiding_budget); o->given |= GIVEN_GUIDING_BUDGET; break;
    case O_GUIDING_ALPHA: rc = parse_open_unit(name, v, &d->guiding_alpha); o->given |= GIVEN_GUIDING_ALPHA; break;
    case O_GUIDING_MEMORY:
        rc = parse_int(name, v, 1, 1 << 20, &d->guiding_max_mib); /* MiB, up to 1 TiB as pt_render takes */
        o->given |= GIVEN_GUIDING_MEMORY;
        break;
    default: return fail("internal error: option %s", name);
    }
    return rc;
}

/* The settings only the command line has (the scene file leaves them at their defaults). */
static int set_render_setting(options *o, opt_id id, const char *name, const char *v)
{
    static const char *const backends[] = { "auto", "builtin", "embree" };
    static const pt_backend backend_ids[] = { PT_BACKEND_AUTO, PT_BACKEND_BUILTIN, PT_BACKEND_EMBREE };
    static const char *const modes[] = { "pilot", "own-samples", "neighbours" };
    static const pt_adaptive_mode mode_ids[] = { PT_ADAPTIVE_PILOT, PT_ADAPTIVE_OWN_SAMPLES, PT_ADAPTIVE_NEIGHBOURS };
    pt_render_desc *d = &o->set;
    int k = 0, rc;
    switch (id) {
    case O_LIGHT_WEIGHT: return parse_real(name, v, 0.0, 1.0, 1, "a number in (0, 1]", &d->light_weight);
    case O_THREADS: return parse_int(name, v, 0, 1024, &d->threads);
    case O_BACKEND:
        rc = parse_choice(name, v, backends, 3, "auto, builtin or embree", &k);
        o->backend = backend_ids[k];
        return rc;
    case O_ADAPTIVE: return parse_real(name, v, 0.0, 1e30, 0, "a finite number >= 0", &d->adaptive_threshold);
    case O_ADAPTIVE_MIN: return parse_int(name, v, 2, 1 << 20, &d->adaptive_min_spp);
    case O_ADAPTIVE_CHECK: return parse_int(name, v, 1, 1 << 20, &d->adaptive_check_passes);
    case O_ADAPTIVE_MODE:
        rc = parse_choice(name, v, modes, 3, "pilot, own-samples or neighbours", &k);
        d->adaptive_mode = mode_ids[k];
        return rc;
    case O_SKIPS: return parse_skips(name, v, &d->disable_skips);
    default: return set_scene_setting(o, id, name, v);
    }
}

static int ends_with(const char *s, const char *suffix) /* ASCII case-insensitive */
{
    size_t n = strlen(s), m = strlen(suffix), i;
    if (n <= m) return 0;
    for (i = 0; i < m; i++) {
        char c = s[n - m + i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != suffix[i]) return 0;
    }
    return 1;
}

/* path's directory exists and is writable, and path is not a directory. */
static int check_writable(const char *path)
{
    char dir[4096];
    const char *slash = strrchr(path, '/');
    struct stat st;
    size_t len = !slash ? 1 : slash == path ? 1 : (size_t)(slash - path);
    if (!*path) return fail("empty output path");
    if (len >= sizeof dir) return fail("%s: path too long", path);
    if (!slash) strcpy(dir, ".");
    else {
        memcpy(dir, path, len);
        dir[len] = '\0';
    }
    if (access(dir, W_OK) != 0) return fail("%s: cannot write to directory '%s': %s", path, dir, strerror(errno));
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) return fail("%s: is a directory", path);
    return PARSED;
}

/* An image file: a known extension this build can write, in a writable directory. */
static int check_output(output *out, const char *path)
{
    if (ends_with(path, ".png")) out->fmt = FMT_PNG;
    else if (ends_with(path, ".exr")) out->fmt = FMT_EXR;
    else if (ends_with(path, ".pfm")) out->fmt = FMT_PFM;
    else if (ends_with(path, ".ppm")) out->fmt = FMT_PPM;
    else return fail("%s: unknown image format (use .png, .exr, .pfm or .ppm)", path);
    if (out->fmt == FMT_PNG && !have_png())
        return fail("%s: built without PNG support (install libpng-dev and rebuild)", path);
    if (out->fmt == FMT_EXR && !have_exr())
        return fail("%s: built without OpenEXR support (install libopenexr-dev and rebuild)", path);
    if (check_writable(path) != PARSED) return PARSE_FAILED;
    out->path = path;
    return PARSED;
}

static int add_output(options *o, const char *path)
{
    if (o->output_count == MAX_OUTPUTS) return fail("too many outputs (at most %d)", MAX_OUTPUTS);
    if (check_output(&o->outputs[o->output_count], path) != PARSED) return PARSE_FAILED;
    o->output_count++;
    return PARSED;
}

/* --guide-at X Y Z OUT: a finite point and an image file. */
static int set_guide_at(options *o, const char *name, const char *const *v)
{
    static const char *const axes[3] = { "X", "Y", "Z" };
    float c[3] = { 0.0f, 0.0f, 0.0f };
    char what[80];
    int k;
    if (o->guide_out.path) return fail("%s given twice", name);
    for (k = 0; k < 3; k++) {
        snprintf(what, sizeof what, "%s %s", name, axes[k]);
        if (parse_real(what, v[k], -FLT_MAX, FLT_MAX, 0, "a finite number", &c[k]) != PARSED) return PARSE_FAILED;
    }
    o->guide_at = pt_v3(c[0], c[1], c[2]);
    return check_output(&o->guide_out, v[3]);
}

/* What is written, how the 8-bit outputs look, and how the command behaves. */
static int set_output_option(options *o, opt_id id, const char *name, const char *v)
{
    static const char *const tonemaps[] = { "clamp", "reinhard", "aces" };
    static const pt_tonemap tonemap_ids[] = { PT_TONEMAP_CLAMP, PT_TONEMAP_REINHARD, PT_TONEMAP_ACES };
    float seconds = 0.0f;
    int k = 0, rc;
    switch (id) {
    case O_OUTPUT: return add_output(o, v);
    case O_ALLOW_PATH:
        if (o->load.allowed_dir_count == MAX_ALLOWED_DIRS) return fail("%s: at most %d directories", name, MAX_ALLOWED_DIRS);
        o->allowed_dirs[o->load.allowed_dir_count++] = v;
        o->load.allowed_dirs = o->allowed_dirs;
        return PARSED;
    case O_MESH_MEMORY:
    case O_IMAGE_MEMORY: {
        long mb = 0;
        if (parse_long(name, v, 1, 1L << 20, &mb) != PARSED) return PARSE_FAILED; /* MiB, up to 1 TiB */
        *(id == O_MESH_MEMORY ? &o->load.mesh_memory : &o->load.image_memory) = (uint64_t)mb << 20;
        return PARSED;
    }
    case O_POV:
        if (o->pov) return fail("%s given twice", name);
        o->pov = v;
        return check_writable(v);
    case O_MITSUBA:
        if (o->mitsuba) return fail("%s given twice", name);
        o->mitsuba = v;
        return check_writable(v);
    case O_EXPOSURE: return parse_real(name, v, -1e30, 1e30, 0, "a finite number", &o->display.exposure);
    case O_TONEMAP:
        rc = parse_choice(name, v, tonemaps, 3, "clamp, aces or reinhard", &k);
        o->display.tonemap = tonemap_ids[k];
        return rc;
    case O_PREVIEW:
        rc = parse_real(name, v, 0.0, 1e6, 1, "a number of seconds > 0", &seconds);
        o->preview_every = seconds;
        return rc;
    default: return set_render_setting(o, id, name, v);
    }
}

/* Splits "--name=value"; otherwise the value, if the option takes one, is the next argument. */
static int parse_one(options *o, int argc, char **argv, int *i)
{
    const char *arg = argv[*i], *value = NULL, *eq = strchr(arg, '=');
    char name[64];
    const struct option_def *def;
    size_t n = strncmp(arg, "--", 2) == 0 && eq ? (size_t)(eq - arg) : strlen(arg);
    if (n >= sizeof name) return fail("unknown option '%s' (see pdftrace --help)", arg);
    memcpy(name, arg, n);
    name[n] = '\0';
    if (n < strlen(arg)) value = eq + 1;
    def = find_option(name);
    if (!def) return fail("unknown option '%s' (see pdftrace --help)", arg);
    if (!def->takes_value) {
        if (value) return fail("%s takes no value", name);
        switch (def->id) {
        case O_HELP: print_help(); return PARSED_EXIT;
        case O_VERSION: print_version(); return PARSED_EXIT;
        case O_QUIET: o->quiet = 1; return PARSED;
        case O_ADAPTIVE_NB: o->set.adaptive_mode = PT_ADAPTIVE_NEIGHBOURS; return PARSED; /* an alias */
        default: return fail("internal error: option %s", name);
        }
    }
    if (def->takes_value > 1) { /* --guide-at: the values that follow (the first may be after '=') */
        const char *v[4];
        int k;
        for (k = 0; k < def->takes_value && k < 4; k++) {
            if (k == 0 && value) v[0] = value;
            else if (*i + 1 >= argc) return fail("%s needs %d values: X Y Z OUT", name, def->takes_value);
            else v[k] = argv[++*i];
        }
        return set_guide_at(o, name, v);
    }
    if (!value) {
        if (*i + 1 >= argc) return fail("%s needs a value", name);
        value = argv[++*i];
    }
    return set_output_option(o, def->id, name, value);
}

/* The default output: SCENE's base name without its extension, + .png (.ppm without libpng). */
static int add_default_output(options *o)
{
    const char *base = strrchr(o->scene, '/'), *dot;
    size_t n;
    base = base ? base + 1 : o->scene;
    dot = strrchr(base, '.');
    n = dot && dot != base ? (size_t)(dot - base) : strlen(base);
    if (n == 0 || n + 5 > sizeof o->default_output) return fail("%s: no name to derive an output from (use -o)", o->scene);
    memcpy(o->default_output, base, n);
    strcpy(o->default_output + n, have_png() ? ".png" : ".ppm");
    return add_output(o, o->default_output);
}

static int parse_options(int argc, char **argv, options *o)
{
    int i, rc;
    memset(o, 0, sizeof *o);
#ifdef PDFTRACE_OPENEXR
    o->load.read_image = pt_read_exr_memory; /* `environment` maps in OpenEXR besides PFM */
#endif
#ifdef PDFTRACE_PNG
    o->load.read_png = pt_read_png_memory; /* PNG image textures */
#endif
    o->backend = PT_BACKEND_AUTO;
    o->display.tonemap = PT_TONEMAP_CLAMP;
    for (i = 1; i < argc; i++) {
        if (argv[i][0] == '-' && argv[i][1] != '\0') {
            if ((rc = parse_one(o, argc, argv, &i)) != PARSED) return rc;
        } else if (o->scene) {
            return fail("more than one scene file ('%s' and '%s')", o->scene, argv[i]);
        } else {
            o->scene = argv[i];
        }
    }
    if (!o->scene) return fail("no scene file given (usage: pdftrace SCENE [options]; see pdftrace --help)");
    if (o->guide_out.path && (o->given & GIVEN_GUIDING) && o->set.guiding == PT_GUIDING_OFF)
        return fail("--guide-at learns a guide in the render: not with --guiding off");
    if (o->output_count == 0 && !o->pov && !o->mitsuba && !o->guide_out.path) return add_default_output(o);
    return PARSED;
}

/* ---------------------------------------------------------------------------------------
   The scene: loaded, built, the command line's settings applied
   --------------------------------------------------------------------------------------- */

static void apply_settings(const options *o, pt_render_desc *d)
{
    const pt_render_desc *s = &o->set;
    if (o->given & GIVEN_WIDTH) d->width = s->width;
    if (o->given & GIVEN_HEIGHT) d->height = s->height;
    if (o->given & GIVEN_SPP) d->samples_per_pixel = s->samples_per_pixel;
    if (o->given & GIVEN_STRATEGY) d->strategy = s->strategy;
    if (o->given & GIVEN_SAMPLER) d->sampler = s->sampler;
    if (o->given & GIVEN_INTEGRATOR) d->integrator = s->integrator;
    if (o->given & GIVEN_SEED) d->seed = s->seed;
    if (o->given & GIVEN_DEPTH) d->max_depth = s->max_depth;
    if (o->given & GIVEN_INDIRECT) d->indirect_paths = s->indirect_paths;
    if (o->given & GIVEN_GUIDING) d->guiding = s->guiding;
    if (o->given & GIVEN_GUIDING_BUDGET) d->guiding_budget = s->guiding_budget;
    if (o->given & GIVEN_GUIDING_ALPHA) d->guiding_alpha = s->guiding_alpha;
    if (o->given & GIVEN_GUIDING_MEMORY) d->guiding_max_mib = s->guiding_max_mib;
    d->light_weight = s->light_weight;
    d->threads = s->threads;
    d->adaptive_threshold = s->adaptive_threshold;
    d->adaptive_min_spp = s->adaptive_min_spp;
    d->adaptive_check_passes = s->adaptive_check_passes;
    d->adaptive_mode = s->adaptive_mode;
    d->disable_skips = s->disable_skips;
}

/* Loads and builds the scene, writes the POV-Ray and Mitsuba exports if asked; EXIT_SUCCESS or
   an exit status. */
static int load_scene(const options *o, pt_scenefile *sf, pt_scene **scene, pt_render_desc *d)
{
    char err[1024];
    uint64_t limit = o->load.image_memory ? o->load.image_memory : PT_SCENEFILE_IMAGE_MEMORY_DEFAULT;
    int rc = pt_scenefile_load_ex(o->scene, &o->load, sf, err, sizeof err);
    *scene = NULL;
    if (rc == PT_OK) rc = pt_scenefile_build(sf, scene, d, err, sizeof err);
    if (rc != PT_OK) {
        fail("%s", err);
        return rc == PT_ERROR_OUT_OF_MEMORY ? EXIT_FAILURE : EXIT_USAGE;
    }
    apply_settings(o, d);
    if (pt_scenefile_image_bytes(d->width, d->height) > limit) { /* the size given here: said before rendering */
        fail("a %d x %d render needs %llu bytes for its film and images, more than the limit of %llu "
             "(--image-memory MB)", d->width, d->height,
             (unsigned long long)pt_scenefile_image_bytes(d->width, d->height), (unsigned long long)limit);
        return EXIT_USAGE;
    }
    if (o->backend != PT_BACKEND_AUTO) { /* built with AUTO: commit again with the one asked for */
        rc = pt_scene_set_backend(*scene, o->backend);
        if (rc == PT_OK) rc = pt_scene_commit(*scene);
        if (rc != PT_OK) {
            fail("--backend: %s", pt_scene_error_message(*scene));
            return rc == PT_ERROR_OUT_OF_MEMORY ? EXIT_FAILURE : EXIT_USAGE;
        }
    }
    {
        pt_scene_info info; /* the scene renders; say where float cannot resolve it */
        if (pt_scene_get_info(*scene, &info) == PT_OK && info.precision_warnings)
            fail("warning: %s: %u primitive%s too small for float at their coordinates; %s", o->scene,
                 (unsigned)info.precision_warnings, info.precision_warnings == 1 ? "" : "s", info.precision_warning);
    }
    if (o->pov) {
        pt_pov_options po;
        po.radiosity = -1;
        po.light_grid = 0;
        po.width = d->width;
        po.height = d->height;
        rc = pt_scenefile_write_pov(sf, o->pov, &po, err, sizeof err);
        if (rc != PT_OK) {
            fail("%s", err);
            return rc == PT_ERROR_IO || rc == PT_ERROR_OUT_OF_MEMORY ? EXIT_FAILURE : EXIT_USAGE;
        }
        if (!o->quiet) printf("wrote      %s\n", o->pov);
    }
    if (o->mitsuba) {
        pt_mitsuba_options mo;
        mo.width = d->width;
        mo.height = d->height;
        mo.spp = d->samples_per_pixel;
        mo.max_depth = d->max_depth;
        rc = pt_scenefile_export_mitsuba(sf, o->mitsuba, &mo, err, sizeof err);
        if (rc != PT_OK) {
            fail("%s", err);
            return rc == PT_ERROR_IO || rc == PT_ERROR_OUT_OF_MEMORY ? EXIT_FAILURE : EXIT_USAGE;
        }
        if (!o->quiet) printf("wrote      %s\n", o->mitsuba);
    }
    return EXIT_SUCCESS;
}

/* ---------------------------------------------------------------------------------------
   Writing the outputs
   --------------------------------------------------------------------------------------- */

static int write_one(const output *out, const pt_image *linear, const pt_image *shown, char *err, size_t err_size)
{
    err[0] = '\0';
    switch (out->fmt) {
#ifdef PDFTRACE_PNG
    case FMT_PNG: return pt_write_png(out->path, shown, err, err_size);
#endif
#ifdef PDFTRACE_OPENEXR
    case FMT_EXR: return pt_write_exr(out->path, linear, NULL, err, err_size);
#endif
    case FMT_PFM: return pt_write_pfm_ex(out->path, linear, err, err_size);
    case FMT_PPM: return pt_write_ppm_ex(out->path, shown, err, err_size);
    default: return PT_ERROR_UNSUPPORTED; /* refused by add_output */
    }
}

/* Writes img to every output, the 8-bit ones through the display transform. Returns 1 when all
   were written; prints one line per failure (and, if announce, one per file written). */
static int write_outputs(const options *o, const pt_image *img, int announce)
{
    pt_image shown = {0, 0, NULL};
    char err[1024];
    int i, rc, ok = 1;
    for (i = 0; i < o->output_count; i++)
        if (o->outputs[i].fmt == FMT_PNG || o->outputs[i].fmt == FMT_PPM) break;
    if (i < o->output_count && (rc = pt_image_apply_display(img, &o->display, &shown)) != PT_OK) {
        fail("display transform: %s", pt_result_string(rc));
        return 0;
    }
    for (i = 0; i < o->output_count; i++) {
        rc = write_one(&o->outputs[i], img, &shown, err, sizeof err);
        if (rc != PT_OK) {
            if (err[0]) fail("%s", err);
            else fail("%s: writing failed: %s", o->outputs[i].path, pt_result_string(rc));
            ok = 0;
        } else if (announce) {
            printf("wrote      %s\n", o->outputs[i].path);
        }
    }
    pt_image_free(&shown);
    return ok;
}

/* ---------------------------------------------------------------------------------------
   Progress (bar on a terminal, a line now and then otherwise) and previews
   --------------------------------------------------------------------------------------- */

typedef struct progress_state {
    const options *o;
    const pt_film *film;
    pt_image preview;            /* the film resolved for --preview-every */
    int tty;                     /* stderr is a terminal: one bar, redrawn */
    int shown;                   /* something is on the bar's line */
    int last_tenth;              /* plain lines: the 10 % step of the last line printed */
    double last_line, last_preview; /* render seconds */
    int preview_failed;
} progress_state;

/* "12.3 s" under a minute, else "m:ss" or "h:mm:ss". */
static void format_time(double s, char *buf, size_t n)
{
    long t = s > 0 && s < 1e8 ? (long)(s + 0.5) : 0;
    if (s < 59.95) snprintf(buf, n, "%.1f s", s > 0 ? s : 0.0);
    else if (t < 3600) snprintf(buf, n, "%ld:%02ld", t / 60, t % 60);
    else snprintf(buf, n, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
}

/* The bar or a plain line: done of total samples after `seconds`. */
static void show_progress(progress_state *ps, uint64_t done, uint64_t total, double seconds, int final)
{
    double f = total ? (double)done / (double)total : 1.0, rate = seconds > 0 ? (double)done / seconds : 0.0;
    char elapsed[32], eta[32];
    format_time(seconds, elapsed, sizeof elapsed);
    format_time(f > 0 ? seconds * (1.0 - f) / f : 0.0, eta, sizeof eta);
    if (final) f = 1.0;
    if (ps->tty) {
        char bar[31];
        int k, full = (int)(f * 30.0);
        for (k = 0; k < 30; k++) bar[k] = k < full ? '#' : '-';
        bar[30] = '\0';
        fprintf(stderr, "\r[%s] %5.1f%%  %6.2f M samples/s  %s elapsed  %s%s   ", bar, 100.0 * f, rate * 1e-6, elapsed,
                final ? "done" : "ETA ", final ? "    " : eta);
        ps->shown = 1;
    } else {
        fprintf(stderr, "rendering %3.0f%%  %.2f M samples/s  %s elapsed%s%s\n", 100.0 * f, rate * 1e-6, elapsed,
                final ? "" : "  ETA ", final ? "" : eta);
    }
    fflush(stderr);
}

/* Called by pt_render on its own thread between passes: progress, then a preview if due. */
static int on_pass(void *user, const pt_progress *p)
{
    progress_state *ps = (progress_state *)user;
    if (!ps->o->quiet) {
        /* plain lines: at a new 10 % step at most once a second, else every 10 s */
        uint64_t done = p->samples_done * (uint64_t)g_ranks; /* rank 0's share, of about 1/g_ranks */
        int tenth = p->samples_total ? (int)(10 * (done < p->samples_total ? done : p->samples_total) / p->samples_total) : 10;
        double since = p->seconds - ps->last_line;
        if (ps->tty || (tenth > ps->last_tenth && since >= 1.0) || since >= 10.0) {
            if (p->pass < p->pass_count)
                show_progress(ps, done < p->samples_total ? done : p->samples_total, p->samples_total, p->seconds, 0);
            ps->last_tenth = tenth;
            ps->last_line = p->seconds;
        }
    }
    if (ps->o->preview_every > 0 && p->pass < p->pass_count && p->seconds - ps->last_preview >= ps->o->preview_every) {
        ps->last_preview = p->seconds;
        if (pt_film_resolve(ps->film, &ps->preview) != PT_OK || !write_outputs(ps->o, &ps->preview, 0)) {
            ps->preview_failed = 1;
            return 1; /* cancel: the final write would fail the same way */
        }
    }
    return 0;
}

/* ---------------------------------------------------------------------------------------
   Rendering and statistics
   --------------------------------------------------------------------------------------- */

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

static void print_stats(const options *o, const pt_scene *scene, const pt_render_desc *d, const pt_render_stats *st,
                        int guiding_forced)
{
    pt_scene_info info;
    uint64_t rays = st->camera_rays + st->bounce_rays + st->shadow_rays;
    double secs = st->seconds > 0 ? st->seconds : 1e-9, pixels = (double)d->width * (double)d->height;
    printf("scene      %s", o->scene);
    if (pt_scene_get_info(scene, &info) == PT_OK)
        printf(": %u primitives, %s traversal", (unsigned)info.primitive_count,
               info.backend == PT_BACKEND_EMBREE ? "Embree" : "built-in BVH");
    printf("\nimage      %d x %d, %d spp, strategy %s", d->width, d->height, d->samples_per_pixel ? d->samples_per_pixel : 16,
           strategy_name(d->strategy));
    if (d->strategy == PT_STRATEGY_MIXTURE) printf(" (light weight %g)", d->light_weight ? (double)d->light_weight : 0.5);
    if (d->sampler == PT_SAMPLER_SOBOL) printf(", sobol sampler");
    if (d->indirect_paths) printf(", %d indirect path%s", d->indirect_paths, d->indirect_paths == 1 ? "" : "s");
    printf(", max depth %d, seed %llu\n", d->max_depth ? d->max_depth : 50, (unsigned long long)d->seed);
    printf("time       %.3f s on %d thread%s, %d pass%s\n", st->seconds, st->threads, st->threads == 1 ? "" : "s",
           st->passes, st->passes == 1 ? "" : "es");
    if (st->batched_samples == st->samples && st->samples) printf("integrator batched\n");
    else if (st->batched_samples) /* guide training runs scalar (pdftrace.h, pt_integrator) */
        printf("integrator batched (%llu samples), scalar (%llu: guide training)\n",
               (unsigned long long)st->batched_samples, (unsigned long long)(st->samples - st->batched_samples));
    else printf("integrator scalar\n");
    printf("samples    %llu (%.3f M samples/s)\n", (unsigned long long)st->samples, (double)st->samples / secs * 1e-6);
    if (d->adaptive_threshold > 0.0f)
        printf("adaptive   threshold %g: %llu pixels converged early (%.1f%%), %u to %u spp, mean %.1f\n",
               (double)d->adaptive_threshold, (unsigned long long)st->pixels_converged,
               100.0 * (double)st->pixels_converged / pixels, st->min_spp, st->max_spp, (double)st->samples / pixels);
    if (d->guiding != PT_GUIDING_OFF) {
        printf("guiding    %s%s", st->guiding_note, guiding_forced ? " (turned on for --guide-at)" : "");
        if (st->guiding_iterations > 0)
            printf("; training %.3f s, %llu samples; guide %lu KiB, %lu lea%s; %llu guided vertices",
                   st->guiding_seconds, (unsigned long long)st->guiding_samples,
                   (unsigned long)(st->guiding_bytes / 1024u), (unsigned long)st->guiding_leaves,
                   st->guiding_leaves == 1 ? "f" : "ves", (unsigned long long)st->guided_vertices);
        if (st->guiding_photons > 0)
            printf("; %llu caustic photons in %.3f s", (unsigned long long)st->guiding_photons, st->guiding_photon_seconds);
        printf("\n");
    }
    if (st->estimated_error >= 0) printf("error      estimated RMS relative error %.4f\n", st->estimated_error);
    if (d->disable_skips) printf("skips      general path forced for mask 0x%x\n", d->disable_skips);
    printf("rays       %llu camera + %llu bounce + %llu shadow = %llu\n", (unsigned long long)st->camera_rays,
           (unsigned long long)st->bounce_rays, (unsigned long long)st->shadow_rays, (unsigned long long)rays);
    printf("rays/s     %.3f M\n", (double)rays / secs * 1e-6);
    printf("NaN/Inf    %llu samples (caught and zeroed)\n", (unsigned long long)st->nonfinite_samples);
#ifdef PDFTRACE_MPI
    if (g_ranks > 1)
        printf("mpi        %d ranks (counters summed over them); rank 0 received and merged %.1f MB in %.3f s "
               "(waiting included)\n", g_ranks, (double)g_mpi.bytes_merged / 1e6, g_mpi.seconds);
#endif
}

/* --guide-at: the guide's density at the point as a 2N x N latitude-longitude picture (pt_guide_image:
   per steradian, +z up) into out. .pfm and .exr get it as it is; .png and .ppm get it divided by its
   maximum, so that the likeliest direction is white. Returns 1 when it was written. */
static int write_guide_to(const options *o, const output *out, const pt_guide *guide, const pt_render_stats *st)
{
    pt_image img = {0, 0, NULL};
    pt_guide_info info;
    char err[1024];
    int rc;
    if ((rc = pt_guide_image(guide, o->guide_at, 2 * GUIDE_IMAGE_HEIGHT, GUIDE_IMAGE_HEIGHT, &img)) != PT_OK) {
        fail("--guide-at: the guide's picture: %s", pt_result_string(rc));
        return 0;
    }
    if (out->fmt == FMT_PNG || out->fmt == FMT_PPM) {
        size_t i, n = 3u * (size_t)img.width * (size_t)img.height;
        float top = 0.0f;
        for (i = 0; i < n; i++)
            if (img.rgb[i] > top) top = img.rgb[i];
        for (i = 0; i < n && top > 0.0f; i++) img.rgb[i] /= top;
    }
    rc = write_one(out, &img, &img, err, sizeof err);
    pt_image_free(&img);
    if (rc != PT_OK) {
        if (err[0]) fail("%s", err);
        else fail("%s: writing failed: %s", out->path, pt_result_string(rc));
        return 0;
    }
    if (!o->quiet) printf("wrote      %s\n", out->path);
    if (pt_guide_get_info(guide, &info) == PT_OK && info.updates == 0)
        fail("warning: --guide-at: the guide learned nothing (%s); %s shows a uniform density", st->guiding_note,
             out->path);
    return 1;
}

/* --guide-at: the guide's picture, and where the render traced caustic photons their guide's too,
   beside it as OUT's name with "-caustic" before the extension. */
static int write_guide(const options *o, const pt_guide *guide, const pt_render_stats *st)
{
    const pt_guide *caustic = pt_guide_caustic(guide);
    char path[4096];
    output out = o->guide_out;
    const char *dot = strrchr(out.path, '.'), *slash = strrchr(out.path, '/');
    size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - out.path) : strlen(out.path);
    if (!write_guide_to(o, &o->guide_out, guide, st)) return 0;
    if (!caustic) return 1;
    if (snprintf(path, sizeof path, "%.*s-caustic%s", (int)stem, out.path, out.path + stem) >= (int)sizeof path) {
        fail("--guide-at: %s: the name is too long for its -caustic picture", out.path);
        return 0;
    }
    out.path = path;
    return write_guide_to(o, &out, caustic, st);
}

/* Renders into a film of our own (so that previews can resolve it between passes) and writes
   the outputs, and with --guide-at trains a guide of our own (guiding turned on if it is off)
   and writes its picture. Returns the exit status. */
static int render(const options *o, const pt_scene *scene, pt_render_desc *d)
{
    progress_state ps;
    pt_film film;
    pt_image img = {0, 0, NULL};
    pt_render_stats st;
    pt_guide *guide = NULL;
    int rc, ok, forced = 0;
    memset(&ps, 0, sizeof ps);
    ps.o = o;
    ps.film = &film;
    ps.tty = isatty(STDERR_FILENO);
    ps.last_tenth = 0;
    if ((rc = pt_film_init(&film, d->width, d->height)) != PT_OK) {
        fail("%d x %d film: %s", d->width, d->height, pt_result_string(rc));
        return EXIT_FAILURE;
    }
    if (o->guide_out.path) {
        pt_guide_desc gd;
        memset(&gd, 0, sizeof gd);
        gd.max_bytes = d->guiding_max_mib > 0 ? (size_t)d->guiding_max_mib << 20 : 0u; /* 0: its default */
        if ((rc = pt_guide_create_for_scene(scene, &gd, &guide)) != PT_OK) {
            fail("--guide-at: creating the guide: %s", pt_result_string(rc));
            pt_film_free(&film);
            return EXIT_FAILURE;
        }
        forced = d->guiding == PT_GUIDING_OFF;
        if (forced) d->guiding = PT_GUIDING_ON;
        d->guiding_guide = guide;
    }
    d->progress = on_pass;
    d->progress_user = &ps;
#ifdef PDFTRACE_MPI
    pt_mpi_split(&g_mpi, d);
#endif
    rc = pt_render(scene, d, &film, &st);
#ifdef PDFTRACE_MPI
    if (rc == PT_OK && pt_mpi_stats_sum(&g_mpi, &st) != PT_OK) rc = PT_ERROR_IO;
#endif
    if (!o->quiet && rc == PT_OK) show_progress(&ps, st.samples, st.samples, st.seconds, 1);
    if (ps.shown) fputc('\n', stderr);
    pt_image_free(&ps.preview);
    if (rc != PT_OK) {
        if (!ps.preview_failed)
            fail("rendering failed (%d x %d): %s", d->width, d->height, st.error[0] ? st.error : pt_result_string(rc));
#ifdef PDFTRACE_MPI
        if (g_ranks > 1) MPI_Abort(MPI_COMM_WORLD, EXIT_FAILURE); /* the other ranks may wait in the merge */
#endif
        pt_film_free(&film);
        pt_guide_destroy(guide);
        return EXIT_FAILURE;
    }
    if (g_rank != 0) { /* its share is in rank 0's film */
        pt_film_free(&film);
        return EXIT_SUCCESS;
    }
    rc = pt_film_resolve(&film, &img);
    pt_film_free(&film);
    if (rc != PT_OK) {
        fail("resolving the %d x %d film: %s", d->width, d->height, pt_result_string(rc));
        pt_guide_destroy(guide);
        return EXIT_FAILURE;
    }
    if (!o->quiet) print_stats(o, scene, d, &st, forced);
    ok = write_outputs(o, &img, !o->quiet);
    pt_image_free(&img);
    if (guide && !write_guide(o, guide, &st)) ok = 0;
    pt_guide_destroy(guide);
    return ok ? EXIT_SUCCESS : EXIT_FAILURE;
}

/* SIGINT and SIGTERM remove the temporaries of the outputs being written, then end the process
   as the signal would have (SA_RESETHAND restores the default action; the raised signal is
   delivered when the handler returns). A signal ignored when the command starts (SIGINT of a
   shell's background job) stays ignored. */
static void on_signal(int sig)
{
    pt_output_remove_temporaries();
    raise(sig);
}
static void install_signal_handlers(void)
{
    static const int sigs[2] = { SIGINT, SIGTERM };
    struct sigaction sa;
    int i;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sa.sa_flags = SA_RESETHAND;
    sigemptyset(&sa.sa_mask);
    for (i = 0; i < 2; i++) {
        struct sigaction old;
        if (sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler != SIG_IGN) sigaction(sigs[i], &sa, NULL);
    }
}

/* An output that is the scene file itself (the same device and inode, so also through a link)
   would replace the input: refused before anything is read or written. */
static int check_outputs_not_input(const options *o)
{
    struct stat in, st;
    int i;
    if (stat(o->scene, &in) != 0) return PARSED; /* reported when the scene is loaded */
    for (i = 0; i <= o->output_count + 2; i++) {
        const char *path = i < o->output_count ? o->outputs[i].path : i == o->output_count ? o->pov
                         : i == o->output_count + 1 ? o->mitsuba : o->guide_out.path;
        if (path && stat(path, &st) == 0 && st.st_dev == in.st_dev && st.st_ino == in.st_ino)
            return fail("%s: is the scene file %s; an output must not replace an input", path, o->scene);
    }
    return PARSED;
}

/* ---------------------------------------------------------------------------------------
   MPI: agreeing on failures before rendering, and that every rank renders the same thing
   --------------------------------------------------------------------------------------- */

/* Collective under MPI: every rank passes its status; the lowest failing rank prints its held
   message; returns the largest status of all ranks (the same everywhere). */
static int mpi_gate(int status)
{
#ifdef PDFTRACE_MPI
    if (g_ranks > 1) {
        int first = pt_mpi_agree(&g_mpi, status == EXIT_SUCCESS), worst = status;
        if (first == g_rank) fprintf(stderr, "pdftrace: rank %d: %s\n", g_rank, g_held[0] ? g_held : "failed");
        if (first == -2 || MPI_Allreduce(&status, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD) != MPI_SUCCESS)
            MPI_Abort(MPI_COMM_WORLD, EXIT_FAILURE);
        g_held[0] = '\0';
        return worst;
    }
#endif
    return status;
}

#ifdef PDFTRACE_MPI
static uint64_t fnv1a(uint64_t h, const void *data, size_t n)
{
    const unsigned char *p = (const unsigned char *)data;
    while (n--) h = (h ^ *p++) * 1099511628211ULL;
    return h;
}
/* The scene file's bytes and the settings that decide the image. */
static uint64_t render_fingerprint(const options *o, const pt_render_desc *d)
{
    uint64_t h = 14695981039346656037ULL;
    const int ints[] = { d->width, d->height, d->samples_per_pixel, d->samples_per_pass, (int)d->strategy, d->max_depth,
                         d->rr_start_depth, d->max_splits, d->indirect_paths, d->adaptive_min_spp, d->adaptive_check_passes,
                         d->adaptive_neighbours_only, (int)d->adaptive_mode, (int)d->disable_skips, (int)d->sampler,
                         d->tile_size };
    const float floats[] = { d->light_weight, d->adaptive_threshold };
    FILE *f = fopen(o->scene, "rb");
    if (f) {
        unsigned char buf[65536];
        size_t n;
        while ((n = fread(buf, 1, sizeof buf, f)) > 0) h = fnv1a(h, buf, n);
        fclose(f);
    }
    h = fnv1a(h, ints, sizeof ints);
    h = fnv1a(h, floats, sizeof floats);
    return fnv1a(h, &d->seed, sizeof d->seed);
}
#endif

/* Several ranks: what cannot be split is refused, and every rank must render rank 0's scene with
   rank 0's settings (collective: every rank calls it). Returns the status. */
static int mpi_check_render(const options *o, const pt_render_desc *d, int status)
{
#ifdef PDFTRACE_MPI
    uint64_t mine = status == EXIT_SUCCESS ? render_fingerprint(o, d) : 0u, first = mine;
    if (g_ranks <= 1) return status;
    if (MPI_Bcast(&first, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD) != MPI_SUCCESS) MPI_Abort(MPI_COMM_WORLD, EXIT_FAILURE);
    if (status != EXIT_SUCCESS) return status;
    if (d->guiding != PT_GUIDING_OFF || o->guide_out.path) {
        fail("%s: guiding cannot be split over MPI ranks yet (docs/mpi.md): run one rank, or --guiding off",
             o->guide_out.path ? "--guide-at" : (o->given & GIVEN_GUIDING) ? "--guiding" : "the scene file's guiding");
        return EXIT_USAGE;
    }
    if (o->preview_every > 0) {
        fail("--preview-every: not under MPI with %d ranks (the film is gathered only at the end)", g_ranks);
        return EXIT_USAGE;
    }
    if (mine != first) {
        fail("%s: the scene file or the settings differ from rank 0's (every rank must render the same scene)", o->scene);
        return EXIT_USAGE;
    }
#else
    (void)o;
    (void)d;
#endif
    return status;
}

static int run(int argc, char **argv)
{
    options o;
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc d;
    int rc = parse_options(argc, argv, &o), status;
    status = rc == PARSED || rc == PARSED_EXIT ? EXIT_SUCCESS : EXIT_USAGE;
    if (rc == PARSED && check_outputs_not_input(&o) != PARSED) status = EXIT_USAGE;
    if ((status = mpi_gate(status)) != EXIT_SUCCESS || rc == PARSED_EXIT) return status;
    if (g_rank != 0) { /* rank 0 writes the exports and the outputs, and reports */
        o.pov = o.mitsuba = NULL;
        o.quiet = 1;
    }
    install_signal_handlers();
    memset(&sf, 0, sizeof sf);
    memset(&d, 0, sizeof d);
    status = load_scene(&o, &sf, &scene, &d);
    status = mpi_gate(mpi_check_render(&o, &d, status));
    g_hold = 0;
    if (status == EXIT_SUCCESS && (o.output_count > 0 || o.guide_out.path)) status = render(&o, scene, &d);
    pt_scene_destroy(scene);
    pt_scenefile_free(&sf);
    return status;
}

int main(int argc, char **argv)
{
    int status;
#ifdef PDFTRACE_MPI
    int provided = 0; /* pt_render's threads never call MPI: the calling thread does, between passes */
    if (MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) {
        fputs("pdftrace: MPI_Init_thread failed\n", stderr);
        return EXIT_FAILURE;
    }
    pt_mpi_init(&g_mpi, MPI_COMM_WORLD);
    g_rank = g_mpi.rank;
    g_ranks = g_mpi.size;
    g_hold = 1;
    if (g_rank != 0 && !freopen("/dev/null", "w", stdout)) /* rank 0 alone prints */
        fprintf(stderr, "pdftrace: rank %d: cannot silence stdout\n", g_rank);
#endif
    status = run(argc, argv);
#ifdef PDFTRACE_MPI
    MPI_Finalize();
#endif
    return status;
}
