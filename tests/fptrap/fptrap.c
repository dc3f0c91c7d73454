/* Floating-point trap test (issue 7 item 6): renders every scene file given on the command
   line with each of the four strategies, then a set of built-in scenes that reach the
   numerically hard paths (closed furnace, tiny and huge sphere lights, shading points on and
   inside lights, grazing quads, thin lens, a guide PDF, axis-parallel rays through node
   planes), all at low spp on one thread, with FE_INVALID and FE_DIVBYZERO trapping. Any
   invalid operation (0/0, Inf-Inf, 0*Inf, sqrt(-x), NaN compared ...) or division by zero
   raises SIGFPE: the handler prints the case and the faulting address and exits 1 (rerun the
   case under gdb for the line). Overflow, underflow and inexact are not trapped.
   Needs glibc's feenableexcept; elsewhere it prints SKIP and exits 0. The last line is
   "N passed, M failed, K skipped" (N renders without a trap; K = 1 when traps are unavailable
   and nothing ran). Build with
   -ftrapping-math (make does: FPTRAP_FLAGS; gcc's default): under clang's default FP model
   the compiler may divide in unused SIMD lanes (clang -O3 vectorises the three 1/dir of the
   ray set-up two lanes at a time with 0/0 in the padding lanes) and trap where the source
   does not.
   Usage: fptrap SCENE_FILE...   (make fptrap-test passes every .scene file of scenes/) */
#define _GNU_SOURCE 1
#define PDFTRACE_IMPLEMENTATION
#define PDFTRACE_SCENE_IMPLEMENTATION
#include "pdftrace_scene.h"

#include <fenv.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

static const char *volatile current_case = "(setup)";

#if defined(__GLIBC__) && defined(FE_INVALID) && defined(FE_DIVBYZERO)
#define HAVE_TRAPS 1
static void on_fpe(int sig, siginfo_t *si, void *uc)
{
    char buf[512];
    const char *what = si->si_code == FPE_FLTINV ? "invalid operation" : si->si_code == FPE_FLTDIV ? "division by zero"
                       : si->si_code == FPE_INTDIV ? "integer division by zero" : "floating-point exception";
    int n = snprintf(buf, sizeof buf, "FAIL fptrap: %s in case '%s' at %p (rerun under gdb for the line)\n", what,
                     current_case, si->si_addr);
    (void)sig;
    (void)uc;
    if (!current_case) _exit(1); /* the self-check: quiet */
    if (n > 0) {
        ssize_t w = write(2, buf, (size_t)n < sizeof buf ? (size_t)n : sizeof buf - 1);
        (void)w;
    }
    _exit(1);
}
#else
#define HAVE_TRAPS 0
#endif

static int failures = 0, cases = 0, passes = 0;

/* One render: must succeed with no NaN/Inf sample (the trap catches the operation first). */
static void render_case(const char *name, const pt_scene *s, pt_render_desc r)
{
    pt_image img = {0, 0, NULL};
    pt_render_stats st;
    int rc;
    memset(&st, 0, sizeof st);
    current_case = name;
    r.threads = 1; /* the trap mask is per thread: render on the one that enabled it */
    rc = pt_render_image(s, &r, &img, &st);
    ++cases;
    if (rc != PT_OK || st.nonfinite_samples != 0) {
        printf("FAIL fptrap: %s: %s, %llu non-finite samples\n", name, pt_result_string(rc),
               (unsigned long long)st.nonfinite_samples);
        ++failures;
    } else
        ++passes;
    pt_image_free(&img);
}

static const char *strategy_name(int k)
{
    static const char *const n[4] = {"mis", "material", "light", "mixture"};
    return n[k & 3];
}

static void scene_file(const char *path)
{
    pt_scenefile d;
    pt_scene *s = NULL;
    pt_render_desc r;
    char err[512], name[600];
    int k, rc;
    current_case = path;
    rc = pt_scenefile_load(path, &d, err, sizeof err);
    if (rc == PT_OK) rc = pt_scenefile_build(&d, &s, &r, err, sizeof err);
    if (rc != PT_OK) {
        printf("FAIL fptrap: %s\n", err);
        ++failures;
        pt_scenefile_free(&d);
        return;
    }
    r.width = 32;
    r.height = 32;
    r.samples_per_pixel = 8;
    r.samples_per_pass = 0;
    for (k = 0; k < 4; ++k) {
        r.strategy = (pt_strategy)k;
        snprintf(name, sizeof name, "%s (%s)", path, strategy_name(k));
        render_case(name, s, r);
    }
    pt_scene_destroy(s);
    pt_scenefile_free(&d);
}

static pt_render_desc base_desc(pt_vec3 from, pt_vec3 at)
{
    pt_render_desc r;
    memset(&r, 0, sizeof r);
    r.width = 24;
    r.height = 24;
    r.samples_per_pixel = 8;
    r.camera.look_from = from;
    r.camera.look_at = at;
    r.camera.vfov_degrees = 60;
    return r;
}

/* A guide that aims at a fixed quad (as the runner's guide test does). */
static int quad_guide(void *user, const pt_shading_point *sp, pt_pdf *out)
{
    const pt_vec3 *q = (const pt_vec3 *)user;
    *out = pt_pdf_quad_light(sp->position, q[0], q[1], q[2], 0);
    return 1;
}

static void all_strategies(const char *name, const pt_scene *s, pt_render_desc r)
{
    char buf[256];
    int k;
    for (k = 0; k < 4; ++k) {
        r.strategy = (pt_strategy)k;
        snprintf(buf, sizeof buf, "built-in %s (%s)", name, strategy_name(k));
        render_case(buf, s, r);
    }
}

static void builtin_scenes(void)
{
    static pt_vec3 guide_quad[3];
    pt_scene *s;
    pt_render_desc r;
    int white, lamp, mirror, glass, rough, i;
    float radii[4] = {1e-1f, 1e-3f, 1e-6f, 1e3f};

    /* Closed furnace: camera inside an emitting diffuse sphere (every path hits it). */
    s = pt_scene_create();
    {
        pt_material_desc md;
        memset(&md, 0, sizeof md);
        md.type = PT_MATERIAL_LAMBERTIAN;
        md.albedo = pt_v3(0.5f, 0.5f, 0.5f);
        md.emission = pt_v3(0.5f, 0.5f, 0.5f);
        md.two_sided_emission = 1;
        white = pt_scene_add_material(s, &md);
        pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, white);
    }
    current_case = "built-in furnace (commit)";
    if (pt_scene_commit(s) == PT_OK) all_strategies("closed furnace", s, base_desc(pt_v3(0, 0, 0.2f), pt_v3(0, 0, -1)));
    pt_scene_destroy(s);

    /* Sphere lights from 1e-1 to 1e-6 of the scene size (and one huge) over a plane, seen
       from above, from inside the light and from its surface. */
    for (i = 0; i < 4; ++i) {
        char name[64];
        float rad = radii[i], L = 1.0f / (rad * rad);
        s = pt_scene_create();
        white = pt_scene_add_lambertian(s, pt_v3(0.7f, 0.7f, 0.7f));
        lamp = pt_scene_add_emitter(s, pt_v3(L, L, L), 0);
        pt_scene_add_quad(s, pt_v3(-5, 0, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), white);
        pt_scene_add_sphere(s, pt_v3(0, 1, 0), rad, lamp);
        current_case = "built-in sphere light (commit)";
        if (pt_scene_commit(s) == PT_OK) {
            snprintf(name, sizeof name, "sphere light r=%g", (double)rad);
            all_strategies(name, s, base_desc(pt_v3(0, 3, -3), pt_v3(0, 0, 0)));
            r = base_desc(pt_v3(0, 1, 0), pt_v3(0, 0, 0));
            r.camera.up = pt_v3(0, 0, 1); /* looking straight down */
            snprintf(name, sizeof name, "sphere light r=%g, camera at its centre", (double)rad);
            all_strategies(name, s, r);
            r.camera.look_from = pt_v3(0, 1 - rad, 0);
            snprintf(name, sizeof name, "sphere light r=%g, camera on its surface", (double)rad);
            all_strategies(name, s, r);
        }
        pt_scene_destroy(s);
    }

    /* Box of materials: mirror, glass, fuzzy metal, grazing quad light, triangle light, a
       checker, axis-aligned camera rays exactly in the box's planes, a thin lens, a guide. */
    s = pt_scene_create();
    white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
    lamp = pt_scene_add_emitter(s, pt_v3(15, 15, 15), 1);
    mirror = pt_scene_add_metal(s, pt_v3(0.9f, 0.9f, 0.9f), 0);
    rough = pt_scene_add_metal(s, pt_v3(0.8f, 0.6f, 0.2f), 0.7f);
    glass = pt_scene_add_dielectric(s, 1.5f);
    {
        int tex = pt_scene_add_checker(s, pt_v3(1, 1, 1), pt_v3(0.1f, 0.1f, 0.1f), 0.5f);
        pt_material_desc md;
        memset(&md, 0, sizeof md);
        md.type = PT_MATERIAL_LAMBERTIAN;
        md.albedo_texture = tex;
        pt_scene_add_quad(s, pt_v3(-2, 0, -2), pt_v3(0, 0, 4), pt_v3(4, 0, 0), pt_scene_add_material(s, &md));
    }
    pt_scene_add_quad(s, pt_v3(-2, 0, 2), pt_v3(4, 0, 0), pt_v3(0, 4, 0), white);    /* back wall */
    pt_scene_add_quad(s, pt_v3(-2, 4, -2), pt_v3(4, 0, 0), pt_v3(0, 0, 4), white);   /* ceiling */
    guide_quad[0] = pt_v3(-0.5f, 3.99f, -0.5f);
    guide_quad[1] = pt_v3(1, 0, 0);
    guide_quad[2] = pt_v3(0, 0, 1);
    pt_scene_add_quad(s, guide_quad[0], guide_quad[1], guide_quad[2], lamp);          /* faces down */
    pt_scene_add_quad(s, pt_v3(1.99f, 0.5f, -1), pt_v3(0, 0, 1), pt_v3(0, 1e-4f, 0), lamp); /* grazing sliver */
    pt_scene_add_triangle(s, pt_v3(-1.9f, 0.5f, 0), pt_v3(-1.9f, 1.5f, 0), pt_v3(-1.9f, 1, 1), lamp);
    pt_scene_add_sphere(s, pt_v3(-0.8f, 0.5f, 0.5f), 0.5f, mirror);
    pt_scene_add_sphere(s, pt_v3(0.8f, 0.5f, 0.0f), 0.5f, glass);
    pt_scene_add_box(s, pt_v3(-0.3f, 0, -1.2f), pt_v3(0.3f, 1, -0.6f), rough);
    current_case = "built-in box (commit)";
    if (pt_scene_commit(s) == PT_OK) {
        r = base_desc(pt_v3(0, 1, -6), pt_v3(0, 1, 0));
        all_strategies("box", s, r);
        /* camera on the box's face planes, looking straight down an axis (rays in node planes) */
        r = base_desc(pt_v3(0.3f, 1, -6), pt_v3(0.3f, 1, 0));
        r.camera.vfov_degrees = 1e-3f;
        all_strategies("box, axis-parallel rays in a bounding plane", s, r);
        r = base_desc(pt_v3(0, 1, -6), pt_v3(0, 1, 0));
        r.camera.lens_radius = 0.2f;
        all_strategies("box, thin lens", s, r);
        r = base_desc(pt_v3(0, 1, -6), pt_v3(0, 1, 0));
        r.guide = quad_guide;
        r.guide_user = guide_quad;
        r.guide_weight = 0.5f;
        all_strategies("box, guide PDF", s, r);
        r = base_desc(pt_v3(0, 1, -6), pt_v3(0, 1, 0));
        r.background = pt_v3(0.2f, 0.3f, 0.4f);
        r.rr_start_depth = 1;
        r.max_depth = 200;
        all_strategies("box, background, early roulette, deep paths", s, r);
    }
    pt_scene_destroy(s);

    /* No emitters at all, and only delta materials. */
    s = pt_scene_create();
    mirror = pt_scene_add_metal(s, pt_v3(1, 1, 1), 0);
    pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, mirror);
    pt_scene_add_quad(s, pt_v3(-3, -1, -3), pt_v3(0, 0, 6), pt_v3(6, 0, 0), mirror);
    current_case = "built-in delta only (commit)";
    if (pt_scene_commit(s) == PT_OK) {
        r = base_desc(pt_v3(0, 0.5f, -4), pt_v3(0, 0, 0));
        r.background = pt_v3(1, 1, 1);
        all_strategies("delta only, no emitters", s, r);
    }
    pt_scene_destroy(s);
}

int main(int argc, char **argv)
{
    int i;
#if HAVE_TRAPS
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_fpe;
    sa.sa_flags = SA_SIGINFO;
    sigaction(SIGFPE, &sa, NULL);
    feclearexcept(FE_ALL_EXCEPT);
    if (feenableexcept(FE_INVALID | FE_DIVBYZERO) == -1) {
        printf("SKIP fptrap: feenableexcept failed\n");
        printf("0 passed, 0 failed, 1 skipped\n");
        return 0;
    }
    /* The trap must work, or the test proves nothing: a child computing 0/0 must die by it. */
    {
        pid_t pid = fork();
        int status = 0;
        if (pid == 0) {
            volatile double z = 0.0, q;
            current_case = NULL;
            q = z / z;
            (void)q;
            _exit(0); /* not trapped */
        }
        if (pid < 0 || waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 1) {
            printf("FAIL fptrap: 0/0 did not trap (the test build cannot see FP exceptions)\n");
            printf("0 passed, 1 failed, 0 skipped\n");
            return 1;
        }
    }
#else
    printf("SKIP fptrap: no feenableexcept (not glibc)\n");
    printf("0 passed, 0 failed, 1 skipped\n");
    return 0;
#endif
    for (i = 1; i < argc; ++i) scene_file(argv[i]);
    builtin_scenes();
    printf("%s fptrap: %d renders (%d scene files x 4 strategies + built-in scenes) without an FP trap, %d failures\n",
           failures ? "FAIL" : "PASS", cases, argc - 1, failures);
    printf("%d passed, %d failed, 0 skipped\n", passes, failures);
    return failures ? 1 : 0;
}
