/* test_origin.c - scenes far from (0, 0, 0): the origin pt_scene_commit chooses, the world
   coordinates of the public queries, and the precision warning (pt_scene_info.precision_*).
   The renders of far scenes are checked by the stress section (tests/stress, "cornell"). */
#include "pdftrace.h"
#include "test.h"
#include "test_util.h"
#include "pdftrace_scene.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A floor 10 x 10 at y = 0, a unit sphere on it at (0, 1, 0) and a quad light at y = 4, all
   moved by off (exact in float for the offsets used here). */
static pt_scene *far_scene(dv3 off)
{
    pt_scene *s = pt_scene_create();
    int w = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)), l = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0), rc;
    rc = pt_scene_add_quad(s, dv_to(dadd(off, dv(-5, 0, -5))), pt_v3(0, 0, 10), pt_v3(10, 0, 0), w);
    rc |= pt_scene_add_sphere(s, dv_to(dadd(off, dv(0, 1, 0))), 1, w);
    rc |= pt_scene_add_quad(s, dv_to(dadd(off, dv(-1, 4, -1))), pt_v3(2, 0, 0), pt_v3(0, 0, 2), l); /* faces down */
    if (rc < 0 || pt_scene_commit(s) != PT_OK) { pt_scene_destroy(s); return NULL; }
    return s;
}

static void far_scene_queries_are_world(test_ctx *t)
{
    /* a scene 1e6..3e6 away is stored relative to its centre; rays, hits, bounds and light
       PDFs stay in world coordinates */
    dv3 off = dv(1e6, -2e6, 3e6);
    pt_scene *s = far_scene(off), *z = far_scene(dv(0, 0, 0));
    pt_scene_info info;
    pt_hit h, hb;
    pt_ray r;
    pt_pdf lp;
    pt_rng rng;
    int i, got, toward = 0;
    if (!CHECK(t, s && z, "scenes did not commit")) goto done;
    pt_scene_get_info(z, &info);
    CHECK(t, info.origin[0] == 0 && info.origin[1] == 0 && info.origin[2] == 0, "a scene at (0, 0, 0) keeps origin 0, got (%g %g %g)",
          info.origin[0], info.origin[1], info.origin[2]);
    pt_scene_get_info(s, &info);
    CHECK(t, fabs(info.origin[0] - 1e6) < 6 && fabs(info.origin[1] + 2e6) < 6 && fabs(info.origin[2] - 3e6) < 6,
          "origin (%.9g %.9g %.9g), want the scene's centre", info.origin[0], info.origin[1], info.origin[2]);
    CHECK(t, info.bounds_min.x <= 1e6 - 5 && info.bounds_max.x >= 1e6 + 5 && info.bounds_min.y <= -2e6 &&
                 info.bounds_max.y >= -2e6 + 4 && info.bounds_max.y < -2e6 + 5.5 && info.bounds_min.z <= 3e6 - 5,
          "bounds (%.9g %.9g %.9g)-(%.9g %.9g %.9g) are not the world's", info.bounds_min.x, info.bounds_min.y,
          info.bounds_min.z, info.bounds_max.x, info.bounds_max.y, info.bounds_max.z);
    /* straight down onto the sphere's top from y = 3 (under the light) */
    r.origin = dv_to(dadd(off, dv(0, 3, 0)));
    r.dir = pt_v3(0, -1, 0);
    got = pt_scene_intersect(s, r, INFINITY, &h);
    if (CHECK(t, got == 1, "no hit on the sphere (%d)", got)) {
        CHECK(t, fabs(h.point.y - (-2e6 + 2)) <= 0.125 && fabs(h.point.x - 1e6) <= 0.07 && fabs(h.point.z - 3e6) <= 0.25,
              "hit (%.9g %.9g %.9g), want the world point (1e6, -1999998, 3e6)", h.point.x, h.point.y, h.point.z);
        CHECK(t, fabsf(h.t - 1.0f) < 1e-3f && h.geometric_normal.y > 0.999f, "t %g normal y %g", h.t, h.geometric_normal.y);
        CHECK(t, h.magnitude >= 1e6f, "magnitude %g does not cover the world point's rounding", h.magnitude);
        CHECK(t, pt_scene_occluded(s, r, h.t * 1.001f) == 1 && pt_scene_occluded(s, r, h.t * 0.999f) == 0,
              "occluded disagrees with the closest hit at t %g", h.t);
        CHECK(t, pt_scene_intersect_brute_force(s, r, INFINITY, &hb) == 1 && hb.primitive == h.primitive &&
                     hb.t == h.t && hb.point.y == h.point.y,
              "brute force: prim %u t %g y %.9g, BVH prim %u t %g y %.9g", hb.primitive, hb.t, hb.point.y, h.primitive, h.t,
              h.point.y);
    }
    /* the light PDF takes a world shading point: its samples point up, at the light */
    lp = pt_pdf_scene_lights(s, dv_to(dadd(off, dv(3, 0.01, 0))));
    pt_rng_seed(&rng, 1, 1);
    for (i = 0; i < 64; i++) {
        pt_vec3 d;
        float p;
        if (pt_pdf_sample(&lp, &rng, &d, &p) && d.y > 0.5f && d.x < 0.0f && p > 0.0f &&
            fabsf(pt_pdf_value(&lp, d) - p) <= 1e-3f * p)
            toward++;
    }
    CHECK(t, toward == 64, "%d of 64 light samples from a world point point at the light", toward);
done:
    pt_scene_destroy(s);
    pt_scene_destroy(z);
}

static void recommit_moves_the_origin(test_ctx *t)
{
    /* shapes added after a commit are world shapes too; the next commit moves the origin */
    dv3 off = dv(1e6, 1e6, 1e6);
    pt_scene *s = far_scene(off);
    pt_scene_info a, b;
    pt_hit h;
    pt_ray r;
    int m;
    if (!CHECK(t, s != NULL, "scene did not commit")) return;
    pt_scene_get_info(s, &a);
    m = pt_scene_add_lambertian(s, pt_v3(0.2f, 0.2f, 0.2f));
    CHECK(t, pt_scene_add_sphere(s, pt_v3(1e6f, 1e6f + 1.0f, 1e6f + 20.0f), 2, m) >= 0, "second sphere");
    CHECK(t, pt_scene_commit(s) == PT_OK, "second commit: %s", pt_scene_error_message(s));
    pt_scene_get_info(s, &b);
    CHECK(t, b.origin[2] > a.origin[2] + 4, "origin z %.9g -> %.9g: the bounds grew to z + 22", a.origin[2], b.origin[2]);
    r.origin = dv_to(dadd(off, dv(0, 1, -10)));
    r.dir = pt_v3(0, 0, 1);
    CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) == 1 && h.primitive == 1 && fabs(h.point.z - (1e6 - 1)) <= 0.07,
          "the first sphere: prim %u at z %.9g, want 1 at 999999", h.primitive, h.point.z);
    r.origin = dv_to(dadd(off, dv(0, 1, 10)));
    CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) == 1 && h.primitive == 3 && fabs(h.point.z - (1e6 + 18)) <= 0.07,
          "the added sphere: prim %u at z %.9g, want 3 at 1000018", h.primitive, h.point.z);
    /* a floor through (0, 0, 0) makes the scene its own size from there: origin 0 again */
    CHECK(t, pt_scene_add_quad(s, pt_v3(-2e6f, 0, -2e6f), pt_v3(0, 0, 4e6f), pt_v3(4e6f, 0, 0), m) >= 0, "floor");
    CHECK(t, pt_scene_commit(s) == PT_OK, "third commit: %s", pt_scene_error_message(s));
    pt_scene_get_info(s, &b);
    CHECK(t, b.origin[0] == 0 && b.origin[1] == 0 && b.origin[2] == 0, "origin (%g %g %g), want 0", b.origin[0],
          b.origin[1], b.origin[2]);
    r.origin = dv_to(dadd(off, dv(0, 1, -10)));
    CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) == 1 && h.primitive == 1 && fabs(h.point.z - (1e6 - 1)) <= 0.07,
          "after moving back: prim %u at z %.9g, want 1 at 999999", h.primitive, h.point.z);
    pt_scene_destroy(s);
}

/* The guide sees world shading points: the largest distance of one from the far scene's centre. */
static int record_guide(void *user, const pt_shading_point *sp, pt_pdf *out)
{
    double *far = (double *)user, d;
    dv3 p = dsub(dv_from(sp->position), dv(1e6, -2e6, 3e6));
    (void)out;
    d = dlen(p);
    if (!(d <= far[0])) far[0] = d;
    return 0;
}
static void far_render_guide_is_world(test_ctx *t)
{
    /* pt_render traces a far scene relative to its origin; the guide still gets world points */
    dv3 off = dv(1e6, -2e6, 3e6);
    pt_scene *s = far_scene(off);
    pt_render_desc d = tu_base_desc(8, 8, 2, 1);
    pt_render_stats st;
    pt_image img;
    double far = 0.0;
    if (!CHECK(t, s != NULL, "scene did not commit")) return;
    d.camera.look_from = dv_to(dadd(off, dv(0, 2, -12)));
    d.camera.look_at = dv_to(dadd(off, dv(0, 1, 0)));
    d.guide = record_guide;
    d.guide_user = &far;
    d.threads = 1;
    memset(&img, 0, sizeof img);
    CHECK(t, pt_render_image(s, &d, &img, &st) == PT_OK, "render: %s", st.error);
    CHECK(t, far > 0.5 && far < 8.0, "guide points up to %g from the scene (want world points within the floor)", far);
    pt_image_free(&img);
    pt_scene_destroy(s);
}

static void precision_warning(test_ctx *t)
{
    /* a floor 2e7 wide cannot be moved nearer: a box 10 wide 9e6 from its centre is under the
       spawn offset there (~3e-5 x 9e6 = 275) and is counted; the same box with no floor is not */
    pt_scene *s = pt_scene_create(), *u = pt_scene_create(), *e = pt_scene_create();
    pt_scene_info info;
    int m, mu, le;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    mu = pt_scene_add_lambertian(u, pt_v3(0.5f, 0.5f, 0.5f));
    CHECK(t, pt_scene_add_quad(s, pt_v3(-1e7f, 0, -1e7f), pt_v3(0, 0, 2e7f), pt_v3(2e7f, 0, 0), m) >= 0, "floor");
    CHECK(t, pt_scene_add_box(s, pt_v3(9e6f, 0, 9e6f), pt_v3(9e6f + 10, 10, 9e6f + 10), m) >= 0, "box");
    CHECK(t, pt_scene_add_box(u, pt_v3(9e6f, 0, 9e6f), pt_v3(9e6f + 10, 10, 9e6f + 10), mu) >= 0, "box alone");
    CHECK(t, pt_scene_commit(s) == PT_OK && pt_scene_commit(u) == PT_OK, "commit");
    pt_scene_get_info(s, &info);
    CHECK(t, info.precision_warnings == 6 && strstr(info.precision_warning, "primitive") != NULL &&
                 strstr(info.precision_warning, "spawn offset") != NULL,
          "floor + far box: %u warnings, '%s' (want the box's 6 quads)", (unsigned)info.precision_warnings,
          info.precision_warning);
    pt_scene_get_info(u, &info);
    CHECK(t, info.precision_warnings == 0 && info.precision_warning[0] == '\0', "the box alone: %u warnings, '%s'",
          (unsigned)info.precision_warnings, info.precision_warning);
    /* an emitter is never spawned from, but a sphere light 1e-8 wide at x = 1 is below 8 ulps there */
    le = pt_scene_add_emitter(e, pt_v3(1, 1, 1), 0);
    CHECK(t, pt_scene_add_sphere(e, pt_v3(1, 0, 0), 1e-8f, le) >= 0, "tiny light");
    CHECK(t, pt_scene_add_sphere(e, pt_v3(-1, 0, 0), 1e-3f, le) >= 0, "small light");
    CHECK(t, pt_scene_commit(e) == PT_OK, "commit");
    pt_scene_get_info(e, &info);
    CHECK(t, info.precision_warnings == 1 && strstr(info.precision_warning, "primitive 0 ") != NULL,
          "tiny light: %u warnings, '%s' (want primitive 0 only)", (unsigned)info.precision_warnings,
          info.precision_warning);
    pt_scene_destroy(s);
    pt_scene_destroy(u);
    pt_scene_destroy(e);
}

/* A scene file: the Cornell box's floor and its tall rotated box, moved by `off` with a
   translate statement composed after the box's rotation. */
static pt_scene *far_scenefile(const char *off, pt_render_desc *d, char *err, size_t n)
{
    char text[512];
    pt_scenefile f;
    pt_scene *s = NULL;
    snprintf(text, sizeof text,
             "camera look_from 0 0 -1 look_at 0 0 0\nmaterial white lambertian 0.73 0.73 0.73\n"
             "translate %s\nquad 0 0 0 555 0 0 0 0 555 white\nquad 0 555 0 0 0 555 555 0 0 white\nidentity\n"
             "rotate 0 1 0 15\ntranslate 265 0 295\ntranslate %s\nbox 0 0 0 165 330 165 white\n", off, off);
    if (pt_scenefile_parse(text, strlen(text), "far.scene", ".", &f, err, n) != PT_OK) return NULL;
    if (pt_scenefile_build(&f, &s, d, err, n) != PT_OK) s = NULL;
    pt_scenefile_free(&f);
    return s;
}
static void scenefile_far_transforms_in_double(test_ctx *t)
{
    /* the scene-file build composes transforms in double and hands the core small coordinates
       relative to the scene's centre: the rotated box moved by 1e7 is hit at the distances of the
       box at the origin (in float at 1e7 its corners round to 1 unit) */
    char err[256] = "";
    pt_render_desc d;
    pt_scene *z = far_scenefile("0 0 0", &d, err, sizeof err), *s = far_scenefile("10000000 10000000 10000000", &d, err, sizeof err);
    pt_scene_info info;
    double worst = 0.0;
    int i, hits = 0;
    if (!CHECK(t, z && s, "build: %s", err)) goto done;
    pt_scene_get_info(s, &info);
    CHECK(t, fabs(info.origin[0] - 1e7) < 600 && info.precision_warnings == 0, "origin x %.9g, %u warnings",
          info.origin[0], (unsigned)info.precision_warnings);
    for (i = 0; i < 64; i++) {
        /* from the camera's place, at 64 points of the box's two faces it sees; and from the side */
        dv3 o = i < 48 ? dv(278, 278, -800) : dv(900, 100 + 3 * i, 380), target = dv(265 + 2.6 * (i % 8) * 8, 20 + 38 * (i / 8), 280);
        pt_ray r0, r1;
        pt_hit h0, h1;
        if (i >= 48) target = dv(300, 100 + 3 * i, 300 + 8 * (i - 48));
        r0.origin = dv_to(o);
        r0.dir = dv_to(dnorm(dsub(target, o)));
        r1.origin = dv_to(dadd(o, dv(1e7, 1e7, 1e7)));
        r1.dir = r0.dir;
        if (pt_scene_intersect(z, r0, INFINITY, &h0) != 1) continue;
        if (!CHECK(t, pt_scene_intersect(s, r1, INFINITY, &h1) == 1 && h1.primitive == h0.primitive,
                   "ray %d: the far scene misses primitive %u", i, h0.primitive))
            continue;
        hits++;
        if (!(fabs((double)h1.t - h0.t) <= worst)) worst = fabs((double)h1.t - h0.t);
    }
    CHECK(t, hits >= 48 && worst <= 0.01, "%d hits; largest |t(far) - t(origin)| = %.4g (want <= 0.01)", hits, worst);
    test_note(t, "%d hits, largest t difference %.3g", hits, worst);
done:
    pt_scene_destroy(z);
    pt_scene_destroy(s);
}

static void set_origin_api(test_ctx *t)
{
    /* shapes given relative to a fixed origin; queries in world coordinates; misuse is refused */
    pt_scene *s = pt_scene_create();
    pt_scene_info info;
    pt_hit h;
    pt_ray r;
    int m, rc;
    CHECK(t, pt_scene_set_origin(NULL, 0, 0, 0) == PT_ERROR_INVALID_ARGUMENT, "NULL scene accepted");
    rc = pt_scene_set_origin(s, 1e7, NAN, 0);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "set_origin") != NULL,
          "NaN origin: %d '%s'", rc, pt_scene_error_message(s));
    CHECK(t, pt_scene_set_origin(s, 12345678.25, -1e7, 0.5) == PT_OK, "set_origin: %s", pt_scene_error_message(s));
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 0.25f, m) >= 0, "sphere");
    rc = pt_scene_set_origin(s, 0, 0, 0);
    CHECK(t, rc == PT_ERROR_INVALID_STATE && strstr(pt_scene_error_message(s), "set_origin") != NULL,
          "set_origin after a shape: %d '%s'", rc, pt_scene_error_message(s));
    CHECK(t, pt_scene_commit(s) == PT_OK, "commit: %s", pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    CHECK(t, info.origin[0] == 12345678.25 && info.origin[1] == -1e7 && info.origin[2] == 0.5,
          "commit changed the fixed origin to (%.17g %.17g %.17g)", info.origin[0], info.origin[1], info.origin[2]);
    /* a sphere 0.25 wide 1.2e7 from (0, 0, 0): float world rays still find it (t is exact) */
    r.origin = pt_v3(12345678.0f, -1e7f, 10.0f);
    r.dir = pt_normalize(pt_v3(0.25f, 0, -9.5f));
    CHECK(t, pt_scene_intersect(s, r, INFINITY, &h) == 1 && fabsf(h.t - (sqrtf(0.0625f + 90.25f) - 0.25f)) < 1e-4f,
          "hit t %g, want %g", h.t, sqrtf(0.0625f + 90.25f) - 0.25f);
    pt_scene_destroy(s);
}

const test_case test_origin_cases[] = {
    TEST_CASE(set_origin_api),
    TEST_CASE(scenefile_far_transforms_in_double),
    TEST_CASE(far_scene_queries_are_world),
    TEST_CASE(recommit_moves_the_origin),
    TEST_CASE(far_render_guide_is_world),
    TEST_CASE(precision_warning),
    TEST_END
};
