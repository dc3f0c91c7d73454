#define _POSIX_C_SOURCE 200809L
/* custom_pdf.c - a user-defined PDF, used two ways:

   1. Outside rendering: a mixture of the user's cone PDF and the built-in cosine PDF is
      sampled and evaluated like any other pt_pdf. We check that the density returned with
      each sample equals pt_pdf_value of that direction, that the mixture integrates to one,
      and we use it to estimate a solid angle with the estimator f(X)/p(X).

   2. As a render guide (pt_render_desc.guide): at every non-delta surface the renderer
      scatters with p = (1 - g) p_material + g p_guide. Our guide is a cone aimed at a small,
      bright sphere light. With the material-only strategy (no light sampling) such a light
      is found by chance alone, so the image is very noisy; the guide finds it on purpose.
      We render with and without the guide at the same sample count and compare the mean
      (both estimators are unbiased, so the means agree within noise) and the variance.

   usage: custom_pdf [guided.ppm [unguided.ppm]]      (default: custom_pdf.ppm) */
#include <math.h>
#include <stdio.h>
#include <string.h>

#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"

#define PI 3.14159265358979323846

/* ---------------------------------------------------------------------------------------
   The user PDF: directions uniformly distributed in a cone.

   A cone of directions about a unit axis with half-angle theta_max has solid angle
       Omega = int_0^{2 pi} int_0^{theta_max} sin(theta) dtheta dphi = 2 pi (1 - cos theta_max).
   The uniform density on it is p(w) = 1 / Omega inside the cone and 0 outside, so
   int p dw = Omega / Omega = 1: a correct PDF.

   Sampling by inversion: in spherical coordinates about the axis, dw = sin(theta) dtheta dphi
   = d(-cos theta) dphi, so a density constant in w is constant in (cos theta, phi): cos theta
   is uniform on [cos theta_max, 1] and phi is uniform on [0, 2 pi). With u1, u2 uniform on
   [0, 1):  cos theta = 1 - u1 (1 - cos theta_max),  phi = 2 pi u2.

   cos_max = -1 gives the whole sphere (Omega = 4 pi), still a correct PDF.

   Agreement of sample and value: cone_sample returns cone_value(dir) of the very direction
   it returns, so the two agree exactly. Rounding can put a sample a hair (~1e-7 rad) outside
   the cone, where the value is 0; such a sample is refused (return 0), which happens with
   probability ~1e-7 and is allowed by pt_pdf_sample_fn.
   --------------------------------------------------------------------------------------- */

typedef struct cone_pdf {
    pt_onb basis;   /* basis.n is the axis */
    float cos_max;  /* cos(theta_max), in [-1, 1) */
    float density;  /* 1 / (2 pi (1 - cos_max)) */
} cone_pdf;

static void cone_init(cone_pdf *c, pt_vec3 axis, float cos_max)
{
    c->basis = pt_onb_from_normal(pt_normalize(axis));
    c->cos_max = cos_max;
    c->density = (float)(1.0 / (2.0 * PI * (1.0 - (double)cos_max)));
}

static float cone_value(void *user, pt_vec3 dir)
{
    const cone_pdf *c = (const cone_pdf *)user;
    return pt_dot(dir, c->basis.n) >= c->cos_max ? c->density : 0.0f;
}

static int cone_sample(void *user, pt_rng *rng, pt_vec3 *dir, float *pdf)
{
    const cone_pdf *c = (const cone_pdf *)user;
    float cos_t = 1.0f - pt_rng_float(rng) * (1.0f - c->cos_max);
    float sin_t = sqrtf(fmaxf(0.0f, 1.0f - cos_t * cos_t));
    float phi = (float)(2.0 * PI) * pt_rng_float(rng);
    pt_vec3 local = pt_v3(sin_t * cosf(phi), sin_t * sinf(phi), cos_t);
    *dir = pt_normalize(pt_onb_to_world(&c->basis, local));
    *pdf = cone_value(user, *dir);
    return *pdf > 0.0f;
}

/* ---------------------------------------------------------------------------------------
   The guide: a grid of cones, one per cell, each aimed at a sphere region.

   The callback PDF receives no shading point, only its user pointer, so a PDF that depends
   on position needs its parameters stored somewhere that outlives the vertex and is safe to
   read from every render thread. Here: a read-only table with one cone per grid cell,
   computed once before rendering.

   The cone of a cell (centre P, half-diagonal h) is the cone from P around the ball of radius
   R + h about the region's centre C. For any point p in the cell and any point X of the
   region, X - p = (X + P - p) - P, and X + P - p lies within R + h of C; so the cone covers
   the whole region as seen from anywhere in the cell. (Coverage only makes the guide
   useful; correctness never depends on it, because the material PDF is always in the mix.)
   --------------------------------------------------------------------------------------- */

#define GRID 16 /* cells per axis: 4096 cones, ~180 KB */

typedef struct guide_grid {
    pt_vec3 lo;       /* grid corner */
    float cell;       /* cell edge length */
    cone_pdf cones[GRID * GRID * GRID];
} guide_grid;

static void guide_grid_init(guide_grid *g, pt_vec3 lo, float size, pt_vec3 center, float radius)
{
    int x, y, z;
    float h;
    g->lo = lo;
    g->cell = size / GRID;
    h = 0.5f * g->cell * sqrtf(3.0f);
    for (z = 0; z < GRID; z++)
        for (y = 0; y < GRID; y++)
            for (x = 0; x < GRID; x++) {
                pt_vec3 p = pt_add(lo, pt_v3((x + 0.5f) * g->cell, (y + 0.5f) * g->cell, (z + 0.5f) * g->cell));
                pt_vec3 to_c = pt_sub(center, p);
                float d = pt_length(to_c);
                float s = (radius + h) / d;
                cone_pdf *c = &g->cones[(z * GRID + y) * GRID + x];
                if (s < 1.0f) cone_init(c, to_c, sqrtf(1.0f - s * s));
                else cone_init(c, pt_v3(0, 1, 0), -1.0f); /* too close: the whole sphere */
            }
}

/* Grid cell of p, clamped to the grid; NULL for points far outside (or NaN). */
static cone_pdf *guide_cell(guide_grid *g, pt_vec3 p)
{
    float f[3];
    int i[3], k;
    f[0] = (p.x - g->lo.x) / g->cell;
    f[1] = (p.y - g->lo.y) / g->cell;
    f[2] = (p.z - g->lo.z) / g->cell;
    for (k = 0; k < 3; k++) {
        if (!(f[k] > -1.0f && f[k] < GRID + 1.0f)) return NULL;
        i[k] = (int)floorf(f[k]);
        i[k] = i[k] < 0 ? 0 : (i[k] >= GRID ? GRID - 1 : i[k]);
    }
    return &g->cones[(i[2] * GRID + i[1]) * GRID + i[0]];
}

/* pt_guide_fn: called by the renderer at every non-delta shading point, from any thread. */
static int guide_toward_light(void *user, const pt_shading_point *sp, pt_pdf *out)
{
    cone_pdf *c = guide_cell((guide_grid *)user, sp->position);
    /* Skip the guide (return 0) near the light, where the cone is the whole sphere: uniform
       directions would serve worse than the material's own PDF. */
    if (!c || c->cos_max <= -1.0f) return 0;
    /* Skip it where the whole cone lies below the surface: the angle between axis and normal
       is then >= 90 deg + theta_max, i.e. cos <= -sin(theta_max). */
    if (pt_dot(c->basis.n, sp->normal) <= -sqrtf(1.0f - c->cos_max * c->cos_max)) return 0;
    *out = pt_pdf_callback(c, cone_sample, cone_value);
    return 1;
}

/* ---------------------------------------------------------------------------------------
   The scene: a 10 x 10 x 10 room, open at the front, lit by a small bright sphere.
   --------------------------------------------------------------------------------------- */

static const pt_vec3 light_center = {5.0f, 8.8f, 5.0f};
static const float light_radius = 0.5f;

static int build_room(pt_scene *s)
{
    int rc = PT_OK;
    int white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
    int red = pt_scene_add_lambertian(s, pt_v3(0.65f, 0.05f, 0.05f));
    int green = pt_scene_add_lambertian(s, pt_v3(0.12f, 0.45f, 0.15f));
    int metal = pt_scene_add_metal(s, pt_v3(0.8f, 0.85f, 0.9f), 0.15f);
    int light = pt_scene_add_emitter(s, pt_v3(40, 40, 40), 0); /* a sphere emits outwards */
    pt_transform box;
    if (white < 0) return white;
    if (red < 0) return red;
    if (green < 0) return green;
    if (metal < 0) return metal;
    if (light < 0) return light;
#define ADD(call) do { if (rc >= 0) rc = (call); } while (0)
    ADD(pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(0, 0, 10), pt_v3(10, 0, 0), white));   /* floor */
    ADD(pt_scene_add_quad(s, pt_v3(0, 10, 0), pt_v3(10, 0, 0), pt_v3(0, 0, 10), white));  /* ceiling */
    ADD(pt_scene_add_quad(s, pt_v3(0, 0, 10), pt_v3(10, 0, 0), pt_v3(0, 10, 0), white));  /* back */
    ADD(pt_scene_add_quad(s, pt_v3(10, 0, 0), pt_v3(0, 10, 0), pt_v3(0, 0, 10), green));  /* left (x = 10) */
    ADD(pt_scene_add_quad(s, pt_v3(0, 0, 0), pt_v3(0, 0, 10), pt_v3(0, 10, 0), red));     /* right (x = 0) */
    box = pt_transform_mul(pt_transform_translate(pt_v3(5.5f, 0, 5.5f)), pt_transform_rotate_y(20));
    ADD(pt_scene_set_transform(s, &box));
    ADD(pt_scene_add_box(s, pt_v3(0, 0, 0), pt_v3(3, 5.5f, 3), white));
    ADD(pt_scene_set_transform(s, NULL));
    ADD(pt_scene_add_sphere(s, pt_v3(3.2f, 1.8f, 3.5f), 1.8f, metal));
    ADD(pt_scene_add_sphere(s, light_center, light_radius, light));
#undef ADD
    if (rc >= 0) rc = pt_scene_commit(s);
    return rc < 0 ? rc : PT_OK;
}

/* ---------------------------------------------------------------------------------------
   Part 1: the callback PDF in a mixture, outside rendering.
   --------------------------------------------------------------------------------------- */

static int demo_mixture(guide_grid *grid)
{
    const pt_vec3 p = pt_v3(5, 0, 5), n = pt_v3(0, 1, 0); /* a point on the floor under the light */
    const int N = 1 << 20;
    pt_pdf parts[2];
    float weights[2] = {0.5f, 0.5f};
    pt_pdf mix, cosine;
    pt_rng rng;
    double max_rel_err = 0, max_len_err = 0, sum, sum2, in_cone = 0;
    double exact, est_cos = 0, se_cos = 0, est_mix = 0, se_mix = 0, mean, se;
    cone_pdf *cone = guide_cell(grid, p);
    int i, rc;

    if (!cone) return PT_ERROR_INVALID_ARGUMENT;
    parts[0] = pt_pdf_callback(cone, cone_sample, cone_value);
    parts[1] = cosine = pt_pdf_cosine_hemisphere(n);
    mix = pt_pdf_mixture(2, parts, weights);
    if ((rc = pt_pdf_validate(&mix)) != PT_OK) return rc;

    printf("Part 1: mixture 0.5 * cone (callback) + 0.5 * cosine hemisphere, at (5, 0, 5)\n");

    /* (a) The density returned with a sample equals pt_pdf_value of that direction. */
    pt_rng_seed(&rng, 1, 0);
    for (i = 0; i < N; i++) {
        pt_vec3 w;
        float pdf;
        double v;
        if (!pt_pdf_sample(&mix, &rng, &w, &pdf)) continue;
        v = pt_pdf_value(&mix, w);
        v = v > 0 ? fabs(pdf - v) / v : 1.0; /* relative difference; a zero value is a failure */
        if (v > max_rel_err) max_rel_err = v;
        if (fabs(pt_length(w) - 1.0) > max_len_err) max_len_err = fabs(pt_length(w) - 1.0);
        in_cone += cone_value(cone, w) > 0;
    }
    printf("  sample vs value: max relative difference %.2g, max | |w| - 1 | %.2g\n", max_rel_err, max_len_err);
    printf("  fraction of samples in the cone: %.4f (at least the cone's weight, 0.5)\n", in_cone / N);

    /* (b) It integrates to one: int p dw = E[p(X) / (1/(4 pi))] for X uniform on the sphere. */
    sum = sum2 = 0;
    for (i = 0; i < N; i++) {
        pt_vec3 w = pt_sample_uniform_sphere(pt_rng_float(&rng), pt_rng_float(&rng));
        double y = pt_pdf_value(&mix, w) * 4.0 * PI;
        sum += y;
        sum2 += y * y;
    }
    mean = sum / N;
    se = sqrt((sum2 / N - mean * mean) / N);
    printf("  integral of the mixture density: %.4f +- %.4f (expected 1)\n", mean, se);

    /* (c) The solid angle of the light seen from p, with f(w) = 1 where w hits the light and
       the estimator f(X)/p(X), for X from the cosine PDF alone and from the mixture. */
    exact = 2.0 * PI * (1.0 - sqrt(1.0 - pow(light_radius / pt_length(pt_sub(light_center, p)), 2.0)));
    for (rc = 0; rc < 2; rc++) {
        const pt_pdf *q = rc == 0 ? &cosine : &mix;
        sum = sum2 = 0;
        for (i = 0; i < N; i++) {
            pt_vec3 w;
            float pdf, t;
            double y = 0;
            pt_ray r;
            r.origin = p;
            if (pt_pdf_sample(q, &rng, &w, &pdf)) {
                r.dir = w;
                if (pt_intersect_sphere(r, light_center, light_radius, 1e30f, &t)) y = 1.0 / pdf;
            }
            sum += y;
            sum2 += y * y;
        }
        mean = sum / N;
        se = sqrt((sum2 / N - mean * mean) / N);
        if (rc == 0) { est_cos = mean; se_cos = se; } else { est_mix = mean; se_mix = se; }
    }
    printf("  solid angle of the light: exact %.6f sr\n", exact);
    printf("    cosine PDF only: %.6f +- %.6f\n", est_cos, se_cos);
    printf("    mixture        : %.6f +- %.6f  (variance %.0fx lower)\n", est_mix, se_mix,
           se_mix > 0 ? (se_cos * se_cos) / (se_mix * se_mix) : 0.0);
    return PT_OK;
}

/* ---------------------------------------------------------------------------------------
   Part 2: the callback PDF as a render guide.
   --------------------------------------------------------------------------------------- */

typedef struct film_summary { double mean, mean_se, mean_variance; } film_summary;

/* The image mean (with its standard error) and the mean per-pixel variance of the mean. */
static int summarize(const pt_film *film, film_summary *out)
{
    double sum = 0, var = 0;
    int x, y, rc, n = film->width * film->height * 3;
    for (y = 0; y < film->height; y++)
        for (x = 0; x < film->width; x++) {
            pt_color m, v;
            if ((rc = pt_film_pixel(film, x, y, &m, &v)) != PT_OK) return rc;
            sum += (double)m.x + m.y + m.z;
            var += (double)v.x + v.y + v.z;
        }
    out->mean = sum / n;
    out->mean_se = sqrt(var) / n;
    out->mean_variance = var / n;
    return PT_OK;
}

static int render(const pt_scene *scene, guide_grid *grid, const char *path, film_summary *sum, double *seconds)
{
    pt_render_desc d = {0};
    pt_render_stats st;
    pt_film film;
    pt_image img = {0};
    int rc;
    d.width = d.height = 200;
    d.samples_per_pixel = 64;
    d.strategy = PT_STRATEGY_MATERIAL; /* no light sampling: only scattering finds the light */
    d.camera.look_from = pt_v3(5, 5, -14);
    d.camera.look_at = pt_v3(5, 5, 0);
    d.camera.vfov_degrees = 40;
    d.seed = 7;
    if (grid) {
        d.guide = guide_toward_light;
        d.guide_user = grid;
        d.guide_weight = 0.5f;
    }
    if ((rc = pt_film_init(&film, d.width, d.height)) != PT_OK) return rc;
    rc = pt_render(scene, &d, &film, &st);
    if (rc == PT_OK) rc = summarize(&film, sum);
    if (rc == PT_OK) rc = pt_film_resolve(&film, &img);
    *seconds = st.seconds;
    if (rc == PT_OK && path) rc = pt_write_ppm(path, &img);
    pt_image_free(&img);
    pt_film_free(&film);
    return rc;
}

int main(int argc, char **argv)
{
    static guide_grid grid; /* ~20 KB: static rather than on the stack */
    const char *guided_path = argc > 1 ? argv[1] : "custom_pdf.ppm";
    const char *unguided_path = argc > 2 ? argv[2] : NULL;
    film_summary a, b;
    double ta = 0, tb = 0;
    pt_scene *scene;
    int rc;

    if (argc > 3 || (argc > 1 && argv[1][0] == '-')) {
        fprintf(stderr, "usage: %s [guided.ppm [unguided.ppm]]\n", argv[0]);
        return argc > 1 && strcmp(argv[1], "--help") == 0 ? 0 : 2;
    }

    guide_grid_init(&grid, pt_v3(0, 0, 0), 10.0f, light_center, light_radius);
    if ((rc = demo_mixture(&grid)) != PT_OK) {
        fprintf(stderr, "custom_pdf: mixture demo failed: %s\n", pt_result_string(rc));
        return 1;
    }

    if (!(scene = pt_scene_create())) {
        fprintf(stderr, "custom_pdf: out of memory\n");
        return 1;
    }
    if ((rc = build_room(scene)) != PT_OK) {
        fprintf(stderr, "custom_pdf: scene: %s (%s)\n", pt_result_string(rc), pt_scene_error_message(scene));
        pt_scene_destroy(scene);
        return 1;
    }
    printf("\nPart 2: material-only strategy, 200 x 200, 64 spp, without and with the guide (weight 0.5)\n");
    rc = render(scene, NULL, unguided_path, &a, &ta);
    if (rc == PT_OK) rc = render(scene, &grid, guided_path, &b, &tb);
    pt_scene_destroy(scene);
    if (rc != PT_OK) {
        fprintf(stderr, "custom_pdf: rendering failed: %s\n", pt_result_string(rc));
        return 1;
    }
    printf("  unguided: image mean %.4f +- %.4f, mean pixel variance %.3g, %.2f s\n", a.mean, a.mean_se,
           a.mean_variance, ta);
    printf("  guided  : image mean %.4f +- %.4f, mean pixel variance %.3g, %.2f s\n", b.mean, b.mean_se,
           b.mean_variance, tb);
    printf("  the means differ by %.1f standard errors (both unbiased); variance unguided / guided = %.2f\n",
           fabs(a.mean - b.mean) / sqrt(a.mean_se * a.mean_se + b.mean_se * b.mean_se),
           b.mean_variance > 0 ? a.mean_variance / b.mean_variance : 0.0);
    printf("wrote %s", guided_path);
    if (unguided_path) printf(" and %s", unguided_path);
    printf("\n");
    return 0;
}
