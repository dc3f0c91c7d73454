/* test_textures.c - surface (u, v) coordinates and image textures (pdftrace.h sections 3 and 4,
   pdftrace_png.h's reader, pdftrace_scene.h's image_texture statement and OBJ vt).

   (u, v) on quads, triangles, mesh triangles with uvs (also under a mirroring transform) and
   spheres against their closed forms, computed here in double; the sphere's and the bilinear
   lookup's values at chosen points against those Mitsuba 3.9 (scalar_rgb) returns there
   (si.uv of a sphere hit; a 2 x 2 bitmap, bilinear, repeat), which the Mitsuba export relies on;
   pt_srgb_decode against IEC 61966-2-1; a textured plane seen head-on under a uniform sky whose
   pixel means equal rho(u, v) at the footprint's centre (E = pi L, so rho E / pi = rho); API and
   scene-file errors. The render test is one comparison of its own family: alpha = 0.01,
   Sidak-corrected over its pixels and channels. */
#include "test_util.h"
#include "pdftrace_scene.h"
#ifdef PDFTRACE_PNG
#include "pdftrace_png.h"
#endif

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int is_zero(pt_color c) { return c.x == 0.0f && c.y == 0.0f && c.z == 0.0f; }

/* The 2 x 2 image of the Mitsuba probe: row 0 (v = 0) red, green; row 1 blue, white. */
static const float probe_rgb[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};

/* Bilinear lookup written out independently: texel centres at (i + 1/2) / n, repeat. */
static double ref_bilinear(const float *rgb, int w, int h, double u, double v, int c)
{
    double x = u * w - 0.5, y = v * h - 0.5, fx = x - floor(x), fy = y - floor(y);
    long x0 = (long)floor(x), y0 = (long)floor(y);
    long xa = ((x0 % w) + w) % w, xb = (xa + 1) % w, ya = ((y0 % h) + h) % h, yb = (ya + 1) % h;
    double a = rgb[3 * (ya * w + xa) + c], b = rgb[3 * (ya * w + xb) + c];
    double cc = rgb[3 * (yb * w + xa) + c], d = rgb[3 * (yb * w + xb) + c];
    return (1 - fy) * ((1 - fx) * a + fx * b) + fy * ((1 - fx) * cc + fx * d);
}

static void bilinear_lookup(test_ctx *t)
{
    /* Mitsuba 3's bitmap (bilinear, repeat) gave these at the probe image */
    static const float probe[][5] = {{0.25f, 0.25f, 1, 0, 0},    {0.75f, 0.25f, 0, 1, 0},  {0.25f, 0.75f, 0, 0, 1},
                                     {0.75f, 0.75f, 1, 1, 1},    {0.0f, 0.0f, 0.5f, 0.5f, 0.5f},
                                     {0.5f, 0.5f, 0.5f, 0.5f, 0.5f}, {0.25f, 0.5f, 0.5f, 0, 0.5f},
                                     {1.1f, 0.25f, 0.7f, 0.3f, 0}, {-0.1f, 0.25f, 0.3f, 0.7f, 0}};
    float big[3 * 5 * 3];
    pt_image img;
    pt_scene *s = pt_scene_create();
    pt_rng rng;
    int tex, tex2, chk, i, c, bad = 0;
    if (!CHECK(t, s != NULL, "scene")) return;
    img.width = 2; img.height = 2; img.rgb = (float *)probe_rgb;
    tex = pt_scene_add_image_texture(s, &img);
    for (i = 0; i < 45; ++i) big[i] = (float)((i * 37) % 11) / 10.0f;
    img.width = 5; img.height = 3; img.rgb = big;
    tex2 = pt_scene_add_image_texture(s, &img);
    chk = pt_scene_add_checker(s, pt_v3(1, 1, 1), pt_v3(0, 0, 0), 1.0f);
    if (!CHECK(t, tex >= 1 && tex2 > tex && chk > tex2, "ids %d %d %d: %s", tex, tex2, chk, pt_scene_error_message(s))) {
        pt_scene_destroy(s);
        return;
    }
    for (i = 0; i < (int)(sizeof probe / sizeof probe[0]); ++i) {
        pt_color got = pt_scene_eval_texture_uv(s, tex, probe[i][0], probe[i][1]);
        CHECK(t, fabsf(got.x - probe[i][2]) < 1e-5f && fabsf(got.y - probe[i][3]) < 1e-5f && fabsf(got.z - probe[i][4]) < 1e-5f,
              "(%g, %g): (%g %g %g), Mitsuba (%g %g %g)", (double)probe[i][0], (double)probe[i][1], (double)got.x,
              (double)got.y, (double)got.z, (double)probe[i][2], (double)probe[i][3], (double)probe[i][4]);
    }
    pt_rng_seed(&rng, 7, 1);
    for (i = 0; i < 2000; ++i) {
        double u = tu_rand(&rng) * 6 - 3, v = tu_rand(&rng) * 6 - 3;
        pt_color got = pt_scene_eval_texture_uv(s, tex2, (float)u, (float)v);
        for (c = 0; c < 3; ++c) {
            double want = ref_bilinear(big, 5, 3, (float)u, (float)v, c), g = c == 0 ? got.x : c == 1 ? got.y : got.z;
            if (fabs(g - want) > 1e-5) bad++;
        }
    }
    CHECK(t, bad == 0, "%d of 6000 lookups of a 5 x 3 image differ from the bilinear formula by > 1e-5", bad);
    /* the other kind gives zero */
    CHECK(t, is_zero(pt_scene_eval_texture_uv(s, chk, 0.3f, 0.3f)) && is_zero(pt_scene_eval_texture(s, tex, pt_v3(0.5f, 0, 0))),
          "a checker looked up by (u, v), or an image by a point, is not zero");
    pt_scene_destroy(s);
}

static void srgb_decode(test_ctx *t)
{
    int k, bad = 0;
    double want = pow((0.5 + 0.055) / 1.055, 2.4);
    CHECK(t, fabs(pt_srgb_decode(0.5f) - want) < 1e-7, "decode(0.5) = %.9g, want %.9g", (double)pt_srgb_decode(0.5f), want);
    CHECK(t, fabs(pt_srgb_decode(0.04f) - 0.04 / 12.92) < 1e-9, "decode(0.04) = %.9g (linear segment)", (double)pt_srgb_decode(0.04f));
    CHECK(t, pt_srgb_decode(0.0f) == 0.0f && pt_srgb_decode(1.0f) == 1.0f && pt_srgb_decode(-1.0f) == 0.0f &&
                 pt_srgb_decode(2.0f) == 1.0f,
          "ends and clamping");
    for (k = 0; k <= 255; ++k) { /* each 8-bit code decodes and re-encodes to itself */
        float lin = pt_srgb_decode((float)k / 255.0f);
        int back = (int)(pt_srgb_encode(lin) * 255.0f + 0.5f);
        if (back != k) bad++;
    }
    CHECK(t, bad == 0, "%d of 256 codes do not survive decode then encode", bad);
}

/* The closed-form (u, v) of each shape at rays through known points. */
static void uv_closed_forms(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_transform mirror;
    pt_mesh_desc md;
    const float pos[9] = {0, 0, 5, 1, 0, 5, 0, 1, 5};
    const float uvs[6] = {0.1f, 0.2f, 0.5f, 0.2f, 0.1f, 0.9f};
    const uint32_t idx[3] = {0, 1, 2};
    pt_rng rng;
    int m, i, bad_q = 0, bad_t = 0, bad_m = 0, bad_s = 0, bad_x = 0;
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    /* quad in z = 0: Q (-1, -2, 0), U (3, 1, 0), V (-1, 2, 0) */
    pt_scene_add_quad(s, pt_v3(-1, -2, 0), pt_v3(3, 1, 0), pt_v3(-1, 2, 0), m);
    /* triangle in z = 2 (no uvs: the barycentric weights of b and c) */
    pt_scene_add_triangle(s, pt_v3(10, 0, 2), pt_v3(13, 0, 2), pt_v3(10, 4, 2), m);
    /* mesh triangle with uvs in z = 5, and its mirror image (x -> -x) in z = 5, x < 0 */
    memset(&md, 0, sizeof md);
    md.positions = pos; md.vertex_count = 3; md.indices = idx; md.triangle_count = 1; md.material = m; md.uvs = uvs;
    i = pt_scene_add_mesh(s, &md);
    CHECK(t, i >= 0, "mesh: %s", pt_scene_error_message(s));
    mirror = pt_transform_identity();
    mirror.m[0][0] = -1.0f;
    mirror.m[0][3] = -20.0f;
    pt_scene_set_transform(s, &mirror);
    CHECK(t, pt_scene_add_mesh(s, &md) >= 0, "mirrored mesh: %s", pt_scene_error_message(s));
    pt_scene_set_transform(s, NULL);
    pt_scene_add_sphere(s, pt_v3(0, 0, 40), 2.0f, m);
    if (!CHECK(t, pt_scene_commit(s) == PT_OK, "commit: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    pt_rng_seed(&rng, 11, 3);
    for (i = 0; i < 500; ++i) {
        double a = 0.01 + 0.98 * tu_rand(&rng), b = 0.01 + 0.98 * tu_rand(&rng), x, y;
        pt_hit h;
        pt_ray r;
        /* quad */
        x = -1 + 3 * a - b; y = -2 + a + 2 * b;
        r.origin = pt_v3((float)x, (float)y, -1); r.dir = pt_v3(0, 0, 1);
        if (pt_scene_intersect(s, r, 1.5f, &h) != 1 || fabs(h.u - a) > 1e-5 || fabs(h.v - b) > 1e-5) bad_q++;
        /* triangle: weights of b and c = (x - 10) / 3, y / 4 */
        if (a + b < 0.98) {
            r.origin = pt_v3((float)(10 + 3 * a), (float)(4 * b), 1); r.dir = pt_v3(0, 0, 1);
            if (pt_scene_intersect(s, r, 3.0f, &h) != 1 || fabs(h.u - a) > 1e-5 || fabs(h.v - b) > 1e-5) bad_t++;
            /* mesh: w0 uv0 + a uv1 + b uv2 at (a, b) */
            r.origin = pt_v3((float)a, (float)b, 4); r.dir = pt_v3(0, 0, 1);
            {
                double wu = (1 - a - b) * uvs[0] + a * uvs[2] + b * uvs[4], wv = (1 - a - b) * uvs[1] + a * uvs[3] + b * uvs[5];
                if (pt_scene_intersect(s, r, 3.0f, &h) != 1 || fabs(h.u - wu) > 1e-5 || fabs(h.v - wv) > 1e-5) bad_m++;
                /* the mirror image at x' = -20 - x carries the same uvs at the same vertex */
                r.origin = pt_v3((float)(-20 - a), (float)b, 4);
                if (pt_scene_intersect(s, r, 3.0f, &h) != 1 || fabs(h.u - wu) > 1e-5 || fabs(h.v - wv) > 1e-5) bad_x++;
            }
        }
        /* sphere: a direction n from the centre; u = atan2(n.y, n.x) / 2 pi in [0, 1), v = acos(n.z) / pi */
        {
            dv3 n = tu_rand_dir(&rng);
            double wu = atan2(n.y, n.x) / (2 * TU_PI), wv = acos(n.z) / TU_PI, du;
            if (wu < 0) wu += 1;
            r.origin = pt_v3((float)(4 * n.x), (float)(4 * n.y), (float)(40 + 4 * n.z));
            r.dir = dv_to(dscale(n, -1));
            if (pt_scene_intersect(s, r, 10.0f, &h) != 1) { bad_s++; continue; }
            du = fabs(h.u - wu);
            if (du > 0.5) du = 1 - du; /* the seam */
            if (du > 1e-4 || fabs(h.v - wv) > 1e-4 || !(h.u >= 0 && h.u < 1)) bad_s++;
        }
    }
    CHECK(t, bad_q == 0, "quad: %d of 500 hits off (a, b)", bad_q);
    CHECK(t, bad_t == 0, "triangle: hits off the barycentric weights of b and c (%d)", bad_t);
    CHECK(t, bad_m == 0, "mesh: hits off the interpolated uvs (%d)", bad_m);
    CHECK(t, bad_x == 0, "mirrored mesh: hits off the interpolated uvs (%d)", bad_x);
    CHECK(t, bad_s == 0, "sphere: %d of 500 hits off atan2(n.y, n.x) / 2 pi, acos(n.z) / pi", bad_s);
    { /* the sphere's values Mitsuba 3 returned at these points (si.uv of a unit sphere) */
        static const float probe[][5] = {{-1, 0, 0, 0.5f, 0.5f}, {0, -1, 0, 0.75f, 0.5f}, {0, 1, 0, 0.25f, 0.5f}, {0, 0, -1, 0, 1}};
        int k;
        for (k = 0; k < 4; ++k) {
            pt_hit h;
            pt_ray r;
            r.origin = pt_v3(5 * probe[k][0], 5 * probe[k][1], 40 + 5 * probe[k][2]);
            r.dir = pt_v3(-probe[k][0], -probe[k][1], -probe[k][2]);
            CHECK(t, pt_scene_intersect(s, r, 10.0f, &h) == 1 && fabsf(h.u - probe[k][3]) < 1e-5f && fabsf(h.v - probe[k][4]) < 1e-5f,
                  "sphere at (%g %g %g): (%g, %g), Mitsuba (%g, %g)", (double)probe[k][0], (double)probe[k][1],
                  (double)probe[k][2], (double)h.u, (double)h.v, (double)probe[k][3], (double)probe[k][4]);
        }
    }
    pt_scene_destroy(s);
}

/* A textured quad seen head-on (a plane parallel to the image: (u, v) affine in the pixel) under
   a uniform sky L = 1, one bounce, MATERIAL: each sample is rho(u, v) at its hit. Where a pixel's
   footprint lies inside one cell between texel centres the bilinear texture is bilinear in the
   pixel, so the pixel's expected mean is rho at the footprint's centre; every such pixel and
   channel must agree within the film's standard error (Student's t, Sidak over them, alpha =
   0.01). */
/* Student's t quantile with nu degrees of freedom from the normal one z (Cornish-Fisher
   expansion, Abramowitz & Stegun 26.7.5; ample for nu >= 100): the film's variance of the mean
   is estimated from spp samples, so a pixel's z-score is t-distributed. */
static double t_quantile(double z, double nu)
{
    double z3 = z * z * z, z5 = z3 * z * z, z7 = z5 * z * z;
    return z + (z3 + z) / (4 * nu) + (5 * z5 + 16 * z3 + 3 * z) / (96 * nu * nu) +
           (3 * z7 + 19 * z5 + 17 * z3 - 15 * z) / (384 * nu * nu * nu);
}

static void textured_plane_render(test_ctx *t)
{
    static const float rgb[3 * 4 * 3] = {0.1f, 0.8f, 0.3f, 0.9f, 0.2f, 0.4f, 0.5f, 0.5f, 0.1f, 0.3f, 0.7f, 0.9f,
                                         0.6f, 0.1f, 0.2f, 0.2f, 0.9f, 0.8f, 0.7f, 0.3f, 0.6f, 0.05f, 0.4f, 0.5f,
                                         0.8f, 0.6f, 0.7f, 0.4f, 0.05f, 0.2f, 0.1f, 0.9f, 0.9f, 0.95f, 0.5f, 0.3f};
    pt_scene *s = pt_scene_create();
    pt_render_desc d = tu_base_desc(48, 48, 128, 2024);
    pt_material_desc md;
    pt_image img;
    pt_film film;
    pt_render_stats st;
    pt_camera cam;
    int tex, m, rc, x, y, c, checked = 0, n_cmp;
    double zmax = 0, zc;
    if (!CHECK(t, s != NULL, "scene")) return;
    img.width = 4; img.height = 3; img.rgb = (float *)rgb;
    tex = pt_scene_add_image_texture(s, &img);
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_LAMBERTIAN;
    md.albedo_texture = tex;
    m = pt_scene_add_material(s, &md);
    /* Q (-1, -1, 0), U (2, 0, 0), V (0, 2, 0): u = (x + 1) / 2, v = (y + 1) / 2 */
    rc = pt_scene_add_quad(s, pt_v3(-1, -1, 0), pt_v3(2, 0, 0), pt_v3(0, 2, 0), m);
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    d.camera.look_from = pt_v3(0, 0, 3);
    d.camera.look_at = pt_v3(0, 0, 0);
    d.camera.vfov_degrees = 30;
    d.max_depth = 1;
    d.background = pt_v3(1, 1, 1);
    d.strategy = PT_STRATEGY_MATERIAL;
    d.threads = 1;
    if (!CHECK(t, pt_film_init(&film, d.width, d.height) == PT_OK, "film")) { pt_scene_destroy(s); return; }
    rc = pt_render(s, &d, &film, &st);
    CHECK(t, rc == PT_OK && st.nonfinite_samples == 0, "render: %d, %llu non-finite", rc, (unsigned long long)st.nonfinite_samples);
    pt_camera_init(&cam, &d.camera, d.width, d.height);
    n_cmp = d.width * d.height * 3;
    zc = t_quantile(tu_z_two_sided(tu_sidak(0.01, n_cmp)), d.samples_per_pixel - 1);
    for (y = 0; y < d.height; ++y)
        for (x = 0; x < d.width; ++x) {
            double us[4], vs[4], uc = 0, vc = 0;
            int k, ok = 1;
            pt_color mean, var;
            for (k = 0; k < 4; ++k) { /* the footprint's corners on z = 0 */
                pt_ray r = pt_camera_ray(&cam, (float)(x + (k & 1)), (float)(y + (k >> 1)), 0.5f, 0.5f);
                double tt = -(double)r.origin.z / r.dir.z, px = r.origin.x + tt * r.dir.x, py = r.origin.y + tt * r.dir.y;
                us[k] = (px + 1) / 2; vs[k] = (py + 1) / 2;
                uc += us[k] / 4; vc += vs[k] / 4;
                if (us[k] <= 0 || us[k] >= 1 || vs[k] <= 0 || vs[k] >= 1) ok = 0;
            }
            for (k = 1; k < 4 && ok; ++k) /* inside one cell between texel centres */
                if (floor(us[k] * 4 - 0.5) != floor(us[0] * 4 - 0.5) || floor(vs[k] * 3 - 0.5) != floor(vs[0] * 3 - 0.5)) ok = 0;
            if (!ok) continue;
            checked++;
            pt_film_pixel(&film, x, y, &mean, &var);
            for (c = 0; c < 3; ++c) {
                double want = ref_bilinear(rgb, 4, 3, uc, vc, c), got = c == 0 ? mean.x : c == 1 ? mean.y : mean.z;
                double se = sqrt(c == 0 ? var.x : c == 1 ? var.y : var.z), z = (fabs(got - want) - 1e-5) / (se > 0 ? se : 1e-30);
                if (z > zmax) zmax = z;
            }
        }
    CHECK(t, checked > 800, "only %d pixels inside single texel cells", checked);
    CHECK(t, zmax <= zc, "a pixel mean is %.2f standard errors from rho at its footprint's centre (limit %.2f)", zmax, zc);
    test_note(t, "%d pixels, worst z %.2f (limit %.2f)", checked, zmax, zc);
    pt_film_free(&film);
    pt_scene_destroy(s);
}

static void api_errors(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_image img;
    float px[6] = {0.5f, 0.5f, 0.5f, 0.5f, 0.5f, 0.5f};
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}, uvs[6] = {0, 0, 1, 0, 0, 1};
    uint32_t idx[3] = {0, 1, 2};
    pt_mesh_desc md;
    int rc, m;
    if (!CHECK(t, s != NULL, "scene")) return;
    rc = pt_scene_add_image_texture(s, NULL);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "image is NULL"), "NULL: %d '%s'", rc,
          pt_scene_error_message(s));
    img.width = 0; img.height = 1; img.rgb = px;
    rc = pt_scene_add_image_texture(s, &img);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "0 x 1"), "0 x 1: %d '%s'", rc,
          pt_scene_error_message(s));
    img.width = 2; img.height = 1; img.rgb = NULL;
    rc = pt_scene_add_image_texture(s, &img);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "rgb NULL"), "no pixels: %d '%s'", rc,
          pt_scene_error_message(s));
    img.rgb = px;
    px[4] = NAN;
    rc = pt_scene_add_image_texture(s, &img);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "pixel (1, 0)"), "NaN: %d '%s'", rc,
          pt_scene_error_message(s));
    px[4] = -0.25f;
    rc = pt_scene_add_image_texture(s, &img);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "pixel (1, 0)"), "negative: %d '%s'", rc,
          pt_scene_error_message(s));
    px[4] = 0.5f;
    rc = pt_scene_add_image_texture(s, &img);
    CHECK(t, rc == 1 && pt_scene_error_message(s)[0] == '\0', "a good image after bad ones: id %d", rc);
    m = pt_scene_add_lambertian(s, pt_v3(1, 1, 1));
    memset(&md, 0, sizeof md);
    md.positions = pos; md.vertex_count = 3; md.indices = idx; md.triangle_count = 1; md.material = m; md.uvs = uvs;
    uvs[3] = INFINITY;
    rc = pt_scene_add_mesh(s, &md);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "uvs of vertex 1"), "mesh uv Inf: %d '%s'", rc,
          pt_scene_error_message(s));
    CHECK(t, is_zero(pt_scene_eval_texture_uv(s, 7, 0, 0)) && is_zero(pt_scene_eval_texture_uv(NULL, 1, 0, 0)),
          "a bad id or scene is not zero");
    pt_scene_destroy(s);
}

/* Scene files: OBJ vt as (u, 1 - v) into the hits; image_texture from PFM; the errors with
   file:line. */
static void scene_file_textures(test_ctx *t)
{
    char dir[256], path[512], err[1024];
    pt_scenefile sf;
    pt_scene *s = NULL;
    pt_render_desc rd;
    pt_image img;
    float px[6] = {0.25f, 0.5f, 0.75f, 1.0f, 0.0f, 0.125f};
    FILE *f;
    int rc;
    struct { const char *text, *want; } bad[] = {
        {"image_texture t nothere.pfm\n", "x.scene:1: image_texture: no file 'nothere.pfm' inside the scene's directory"},
        {"image_texture t tex.pfm bogus\n", "x.scene:1:"},
        {"image_texture t tex.pfm\nimage_texture t tex.pfm\n", "x.scene:2: image_texture: name 't' is already defined"},
        {"material q lambertian texture nope\n", "x.scene:1: material q: texture 'nope' is not defined"},
        {"image_texture t zero.pfm\n", "x.scene:1: image_texture t:"},
        {"image_texture t tex.bmp\n", "x.scene:1: image_texture t: 'tex.bmp': not a .pfm or .png file"},
        {"image_texture t tex.png\n", "x.scene:1: image_texture t: 'tex.png': this program was built without libpng"},
        {"mesh badvt.obj m\n", "badvt.obj:3: face vertex '1/7': texture coordinate index out of range"},
        {"mesh mixvt.obj m\n", "mixvt.obj:4: face vertex '2': some face vertices have texture coordinates and some do not"},
    };
    size_t i;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "tmpdir")) return;
    img.width = 2; img.height = 1; img.rgb = px;
    snprintf(path, sizeof path, "%s/tex.pfm", dir);
    CHECK(t, pt_write_pfm(path, &img) == PT_OK, "write %s", path);
    snprintf(path, sizeof path, "%s/zero.pfm", dir);
    if ((f = fopen(path, "wb")) != NULL) { fputs("PF\n0 1\n-1\n", f); fclose(f); }
    snprintf(path, sizeof path, "%s/badvt.obj", dir);
    if ((f = fopen(path, "w")) != NULL) { fputs("v 0 0 0\nv 1 0 0\nf 1/7 2/1 1/1\n", f); fclose(f); }
    snprintf(path, sizeof path, "%s/mixvt.obj", dir);
    if ((f = fopen(path, "w")) != NULL) { fputs("v 0 0 0\nv 1 0 0\nvt 0 0\nf 1/1 2 1\n", f); fclose(f); }
    snprintf(path, sizeof path, "%s/tri.obj", dir);
    if ((f = fopen(path, "w")) != NULL) {
        fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.1 0.2\nvt 0.5 0.2\nvt 0.1 0.9\nf 1/1 2/2 3/3\n", f);
        fclose(f);
    }
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        char text[600];
        snprintf(text, sizeof text, "camera look_from 0 0 5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\n%s", bad[i].text);
        /* two lines of prelude: shift the expected line numbers of x.scene by 2 */
        rc = pt_scenefile_parse(text, strlen(text), "x.scene", dir, &sf, err, sizeof err);
        if (rc == PT_OK) {
            pt_scenefile_free(&sf);
            CHECK(t, 0, "'%s' loaded", bad[i].text);
            continue;
        }
        {
            char want[300];
            const char *w = bad[i].want;
            int line;
            if (sscanf(w, "x.scene:%d:", &line) == 1) {
                const char *rest = strchr(w + 8, ':');
                snprintf(want, sizeof want, "x.scene:%d:%s", line + 2, rest + 1);
            } else {
                snprintf(want, sizeof want, "%s", w);
            }
            CHECK(t, strstr(err, want) != NULL, "'%s': got '%s', want '%s'", bad[i].text, err, want);
        }
    }
    {
        const char *text = "camera look_from 0 0 5 look_at 0 0 0\nimage_texture t tex.pfm\nmaterial m lambertian texture t\n"
                           "mesh tri.obj m\n";
        rc = pt_scenefile_parse(text, strlen(text), "ok.scene", dir, &sf, err, sizeof err);
        if (CHECK(t, rc == PT_OK, "load: %s", err)) {
            CHECK(t, sf.image_count == 1 && sf.images[0].image.width == 2 && sf.images[0].image.rgb[3] == 1.0f &&
                         sf.meshes[0].uvs && fabsf(sf.meshes[0].uvs[1] - 0.8f) < 1e-6f,
                  "texture read as linear PFM; OBJ vt (0.1, 0.2) read as (0.1, 0.8)");
            rc = pt_scenefile_build(&sf, &s, &rd, err, sizeof err);
            if (CHECK(t, rc == PT_OK, "build: %s", err)) {
                pt_hit h;
                pt_ray r;
                r.origin = pt_v3(0.0005f, 0.0005f, 1); r.dir = pt_v3(0, 0, -1);
                CHECK(t, pt_scene_intersect(s, r, 5, &h) == 1 && fabsf(h.u - 0.1f) < 1e-3f && fabsf(h.v - 0.8f) < 1e-3f,
                      "hit by the first corner: (%g, %g), want (0.1, 0.8) as Mitsuba 3 reads the OBJ", (double)h.u, (double)h.v);
            }
            pt_scene_destroy(s);
            pt_scenefile_free(&sf);
        }
    }
#ifdef PDFTRACE_PNG
    { /* a PNG texture through pt_read_png_memory: codes / 255, then sRGB-decoded unless raw */
        unsigned char code[6] = {0, 64, 128, 200, 255, 17};
        pt_scenefile_options opt;
        const char *text = "camera look_from 0 0 5 look_at 0 0 0\nimage_texture c tex8.png\nimage_texture r tex8.png raw\n"
                           "material m lambertian texture c\nsphere 0 0 0 1 m\n";
        int k, bad_c = 0;
        snprintf(path, sizeof path, "%s/tex8.png", dir);
        CHECK(t, pt_write_png_rgb8(path, 2, 1, code, err, sizeof err) == PT_OK, "write png: %s", err);
        memset(&opt, 0, sizeof opt);
        opt.read_png = pt_read_png_memory;
        rc = pt_scenefile_parse_ex(text, strlen(text), "png.scene", dir, &opt, &sf, err, sizeof err);
        if (CHECK(t, rc == PT_OK, "load: %s", err)) {
            for (k = 0; k < 6; ++k) {
                if (sf.images[0].image.rgb[k] != pt_srgb_decode((float)code[k] / 255.0f)) bad_c++;
                if (sf.images[1].image.rgb[k] != (float)code[k] / 255.0f) bad_c++;
            }
            CHECK(t, bad_c == 0, "%d texels not decoded as sRGB (colour) or kept (raw)", bad_c);
            pt_scenefile_free(&sf);
        }
        rc = pt_read_png_memory("not a png", 9, "junk.png", &img, err, sizeof err);
        CHECK(t, rc == PT_ERROR_IO && strstr(err, "junk.png: reading PNG:") && img.rgb == NULL, "junk: %d '%s'", rc, err);
    }
#else
    test_note(t, "PNG textures not tested: built without libpng");
#endif
    tu_remove_tree(dir);
}

const test_case test_textures_cases[] = {
    TEST_CASE(bilinear_lookup),
    TEST_CASE(srgb_decode),
    TEST_CASE(uv_closed_forms),
    TEST_CASE(textured_plane_render),
    TEST_CASE(api_errors),
    TEST_CASE(scene_file_textures),
    TEST_END
};
