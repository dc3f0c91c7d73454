/* test_microfacet.c - the rough conductor (PT_MATERIAL_ROUGH_CONDUCTOR, pdftrace.h section 4):
   GGX sampled by visible normals.

   - chi-square of the material PDF's sampling against pt_pdf_value at roughness {0.01, 0.1, 0.5, 1}
     and incident angles {0, 45, 80, 89} degrees, each with the closed form G1(wo) D(h) / (4 cos_o)
     computed here in double (the tu_check_pdf checker, test_util.h), on a histogram over the half
     vector: x = tan^2 / (alpha^2 + tan^2) of its angle to the normal (the CDF of D cos, so at
     normal incidence the histogram is flat even for a lobe a few hundredths of a degree wide), y
     its azimuth. These cases belong to the chi-square suite (alpha = 0.01, Sidak-corrected over
     TU_SUITE_COMPARISONS).
   - the harness rejects the visible-normal sampler paired with the density of plain NDF sampling
     D(h) cos_h / (4 wo.h) (the two agree only at normal incidence).
   - white furnace: a convex sphere of the conductor under a uniform background; the radiance along
     a ray meeting it at angle theta is the directional albedo rho(theta) = \int f cos, which this
     file integrates numerically (two independent quadratures that must agree), with F = 1 (the
     single-scattering loss alone) and with gold (Fresnel from the complex formula in double).
     z-tests at alpha = 0.01, Sidak over the comparisons of that test.
   - Fresnel of the named metals against the complex-valued formula; the alpha -> 0 limit (delta
     below 1e-3, continuous through it, no NaN); API errors; MIS against every single strategy. */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef TU_PI
#define TU_PI 3.14159265358979323846
#endif

/* ---- GGX in double, local frame (z = normal) ---- */
static double g_d(dv3 m, double a2)
{
    double s = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
    return m.z > 0.0 ? a2 / (TU_PI * s * s) : 0.0;
}
static double g_g1(dv3 v, double a2)
{
    double t2;
    if (v.z <= 0.0) return 0.0;
    t2 = (v.x * v.x + v.y * v.y) / (v.z * v.z);
    return 2.0 / (1.0 + sqrt(1.0 + a2 * t2));
}
/* Unpolarised Fresnel reflectance of a conductor from the complex amplitude coefficients
   r_s = (cos_i - n cos_t) / (cos_i + n cos_t), r_p = (n cos_i - cos_t) / (n cos_i + cos_t),
   cos_t = sqrt(1 - sin_i^2 / n^2), n = eta + i k (complex arithmetic written out in double). */
typedef struct cx { double re, im; } cx;
static cx cx_mk(double re, double im) { cx z; z.re = re; z.im = im; return z; }
static cx cx_add(cx a, cx b) { return cx_mk(a.re + b.re, a.im + b.im); }
static cx cx_sub(cx a, cx b) { return cx_mk(a.re - b.re, a.im - b.im); }
static cx cx_mul(cx a, cx b) { return cx_mk(a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re); }
static cx cx_div(cx a, cx b)
{
    double d = b.re * b.re + b.im * b.im;
    return cx_mk((a.re * b.re + a.im * b.im) / d, (a.im * b.re - a.re * b.im) / d);
}
static cx cx_sqrt(cx z) /* principal root */
{
    double r = hypot(z.re, z.im), re = sqrt(0.5 * (r + z.re)), im = sqrt(fmax(0.0, 0.5 * (r - z.re)));
    return cx_mk(re, z.im < 0.0 ? -im : im);
}
static double cx_abs2(cx z) { return z.re * z.re + z.im * z.im; }
static double fresnel_complex(double cos_i, double eta, double k)
{
    cx n = cx_mk(eta, k), ci = cx_mk(cos_i, 0.0), one = cx_mk(1.0, 0.0);
    cx ct = cx_sqrt(cx_sub(one, cx_div(cx_mk(1.0 - cos_i * cos_i, 0.0), cx_mul(n, n))));
    cx rs = cx_div(cx_sub(ci, cx_mul(n, ct)), cx_add(ci, cx_mul(n, ct)));
    cx rp = cx_div(cx_sub(cx_mul(n, ci), ct), cx_add(cx_mul(n, ci), ct));
    return 0.5 * (cx_abs2(rs) + cx_abs2(rp));
}

/* The frame of a check: normal n, tangents e1, e2; wo in it. */
typedef struct ggx_ctx {
    dv3 n, e1, e2, wo, wo_l;
    double a, a2;
    int ndf; /* the reference of the WRONG case: NDF-sampling density */
} ggx_ctx;
static dv3 to_l(const ggx_ctx *c, dv3 w) { return dv(ddot(w, c->e1), ddot(w, c->e2), ddot(w, c->n)); }
static dv3 from_l(const ggx_ctx *c, dv3 l)
{
    return dadd(dadd(dscale(c->e1, l.x), dscale(c->e2, l.y)), dscale(c->n, l.z));
}
static double ref_ggx(const void *ctx, dv3 w, int *near)
{
    const ggx_ctx *c = (const ggx_ctx *)ctx;
    dv3 i = to_l(c, w), s = dadd(c->wo_l, i), h;
    /* float rounding: the half vector of two nearly opposite directions (grazing wo and wi) is a
       cancellation, off by ~2.4e-7 / |wo + wi| rad, which moves D by ~2 of that / alpha relative */
    *near = i.z < 1e-4 || 4.8e-7 / (dlen(s) * c->a) > 2e-4;
    if (i.z <= 0.0) return 0.0;
    h = dnorm(s);
    return g_g1(c->wo_l, c->a2) * g_d(h, c->a2) / (4.0 * c->wo_l.z);
}
/* the half-vector domain (see the top of the file) */
static int hv_to_unit(const void *ctx, dv3 w, double *x, double *y)
{
    const ggx_ctx *c = (const ggx_ctx *)ctx;
    dv3 i = to_l(c, w), h;
    double s, phi;
    if (i.z <= -1e-6) return 0;
    h = dnorm(dadd(c->wo_l, i));
    if (h.z <= 0.0) return 0;
    s = h.x * h.x + h.y * h.y;
    *x = fmin(s / (s + c->a2 * h.z * h.z), 1.0 - 1e-12);
    phi = atan2(h.y, h.x);
    if (phi < 0.0) phi += 2.0 * TU_PI;
    *y = fmin(phi / (2.0 * TU_PI), 1.0 - 1e-12);
    return 1;
}
static dv3 hv_from_unit(const void *ctx, double x, double y, double *jac)
{
    const ggx_ctx *c = (const ggx_ctx *)ctx;
    double t = c->a2 * x / (1.0 - x), cos_t = 1.0 / sqrt(1.0 + t), sin_t = sqrt(t / (1.0 + t)), phi = 2.0 * TU_PI * y;
    dv3 h = dv(sin_t * cos(phi), sin_t * sin(phi), cos_t), i;
    double oh = ddot(c->wo_l, h);
    i = dsub(dscale(h, 2.0 * oh), c->wo_l);
    /* d omega_i = 4 |wo.h| d omega_h, d omega_h = pi cos^3 alpha^2 / (1 - x)^2 dx dy */
    *jac = 4.0 * fabs(oh) * TU_PI * cos_t * cos_t * cos_t * c->a2 / ((1.0 - x) * (1.0 - x));
    return dnorm(from_l(c, i));
}
static double hv_propose(const void *ctx, pt_rng *r, dv3 *w)
{
    double jac;
    *w = hv_from_unit(ctx, tu_rand(r), tu_rand(r), &jac);
    return jac > 0.0 ? 1.0 / jac : 1e300;
}
static void ggx_setup(ggx_ctx *c, dv3 n, double theta_deg, double a)
{
    double th = theta_deg * TU_PI / 180.0;
    c->n = dnorm(dv_from(dv_to(n)));
    tu_frame(c->n, &c->e1, &c->e2);
    c->wo = dnorm(dv_from(dv_to(dnorm(dadd(dscale(c->n, cos(th)), dscale(c->e1, sin(th)))))));
    c->a = a;
    c->a2 = (double)((float)a * (float)a); /* the float alpha^2 the material uses */
    c->wo_l = to_l(c, c->wo);
    c->ndf = 0;
}

static void ggx_conductor_chi2(test_ctx *t)
{
    static const double rough[4] = { 0.01, 0.1, 0.5, 1.0 }, angle[4] = { 0.0, 45.0, 80.0, 89.0 };
    static char labels[16][96];
    pt_scene *s = pt_scene_create();
    int mats[4], ri, ai, rc = 0;
    double min_p = 2.0;
    if (!CHECK(t, s != NULL, "pt_scene_create failed")) return;
    for (ri = 0; ri < 4; ri++) {
        mats[ri] = pt_scene_add_rough_conductor(s, PT_CONDUCTOR_AU, (float)rough[ri], pt_v3(0.9f, 0.8f, 0.7f));
        rc |= mats[ri] < 0;
    }
    rc |= pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, mats[0]) < 0;
    rc |= pt_scene_commit(s) != PT_OK;
    if (!CHECK(t, rc == 0, "scene setup failed: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (ri = 0; ri < 4; ri++) {
        CHECK(t, pt_material_is_delta(s, mats[ri]) == 0, "roughness %g reported delta", rough[ri]);
        for (ai = 0; ai < 4; ai++) {
            ggx_ctx ctx;
            tu_domain dom;
            tu_pdf_check c;
            tu_pdf_result r;
            pt_pdf p;
            char *label = labels[ri * 4 + ai];
            ggx_setup(&ctx, dnorm(dv(0.2, 1.0, -0.3)), angle[ai], rough[ri]);
            p = pt_pdf_material(s, mats[ri], dv_to(ctx.n), dv_to(ctx.wo));
            snprintf(label, 96, "rough conductor GGX alpha %.2f, %.0f degrees", rough[ri], angle[ai]);
            CHECK(t, pt_pdf_validate(&p) == PT_OK, "%s: pt_pdf_validate failed", label);
            dom.to_unit = hv_to_unit;
            dom.from_unit = hv_from_unit;
            dom.propose = hv_propose;
            dom.ctx = &ctx;
            memset(&c, 0, sizeof c);
            c.label = label;
            c.pdf = &p;
            c.axis = ctx.n;
            c.omc = 1.0 + 1e-6; /* the hemisphere (its rim included) */
            c.domain = &dom;
            c.expected_mass = -1.0; /* below 1: directions reflected below the surface fail */
            c.support = -1.0; /* E[1/p] over the draws that succeed is 2 pi / mass: not a separate check */
            c.ref = ref_ggx;
            c.ref_ctx = &ctx;
            c.n_samples = 1000000;
            c.n_mass = 200000;
            c.ns = 40;
            c.nphi = 81;
            c.seed = 2100 + (uint64_t)(ri * 4 + ai);
            c.alpha = tu_suite_alpha();
            c.inv_z = 0.0;
            TU_CHECK_PDF(t, &c, &r);
            if (r.chi2_p < min_p) min_p = r.chi2_p;
        }
    }
    test_note(t, "16 cases, 10^6 draws each, smallest chi-square p %.3g (alpha per comparison %.2g)", min_p, tu_suite_alpha());
    pt_scene_destroy(s);
}

/* WRONG: the visible-normal sampler's directions reported with the NDF-sampling density. */
typedef struct wrong_user { pt_pdf inner; ggx_ctx *c; } wrong_user;
static float ndf_density(const ggx_ctx *c, pt_vec3 w)
{
    dv3 i = to_l(c, dv_from(w)), h;
    if (i.z <= 0.0) return 0.0f;
    h = dnorm(dadd(c->wo_l, i));
    return (float)(g_d(h, c->a2) * h.z / (4.0 * ddot(c->wo_l, h)));
}
static int wrong_sample(void *user, pt_rng *rng, pt_vec3 *dir, float *pdf)
{
    wrong_user *u = (wrong_user *)user;
    if (!pt_pdf_sample(&u->inner, rng, dir, pdf)) return 0;
    *pdf = ndf_density(u->c, *dir);
    if (!(*pdf > 0.0f)) { *dir = pt_v3(0, 0, 0); *pdf = 0.0f; return 0; }
    return 1;
}
static float wrong_value(void *user, pt_vec3 dir) { return ndf_density(((wrong_user *)user)->c, dir); }

static void harness_rejects_vndf_with_ndf_density(test_ctx *t)
{
    /* At 60 degrees and alpha 0.5 the visible-normal density G1(wo) D / (4 cos_o) and the NDF
       density D cos_h / (4 wo.h) differ; sample and value agree (both report the NDF one), so the
       chi-square and the mass comparisons must see it. Passes only when the checker rejects it. */
    pt_scene *s = pt_scene_create();
    int m;
    ggx_ctx ctx;
    tu_domain dom;
    tu_pdf_check c;
    tu_pdf_result r;
    wrong_user u;
    pt_pdf p;
    char reason[768];
    int failures;
    if (!CHECK(t, s != NULL, "pt_scene_create failed")) return;
    m = pt_scene_add_rough_conductor(s, PT_CONDUCTOR_NONE, 0.5f, pt_v3(1, 1, 1));
    if (!CHECK(t, m >= 0 && pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m) >= 0 && pt_scene_commit(s) == PT_OK, "scene: %s",
               pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    ggx_setup(&ctx, dv(0, 0, 1), 60.0, 0.5);
    u.inner = pt_pdf_material(s, m, dv_to(ctx.n), dv_to(ctx.wo));
    u.c = &ctx;
    p = pt_pdf_callback(&u, wrong_sample, wrong_value);
    dom.to_unit = hv_to_unit;
    dom.from_unit = hv_from_unit;
    dom.propose = hv_propose;
    dom.ctx = &ctx;
    memset(&c, 0, sizeof c);
    c.label = "WRONG: GGX visible-normal samples, NDF density";
    c.pdf = &p;
    c.axis = ctx.n;
    c.omc = 1.0 + 1e-6;
    c.domain = &dom;
    c.expected_mass = -1.0;
    c.support = -1.0;
    c.n_samples = 1000000;
    c.n_mass = 200000;
    c.ns = 40;
    c.nphi = 81;
    c.seed = 2190;
    c.alpha = tu_suite_alpha();
    failures = tu_check_pdf_rejects(&c, &r, reason, sizeof reason);
    CHECK(t, failures > 0, "the NDF density with visible-normal samples was not rejected (chi2 p = %.3g)", r.chi2_p);
    CHECK(t, r.chi2_p < c.alpha, "chi-square p = %.3g not below alpha %.3g", r.chi2_p, c.alpha);
    test_note(t, "rejected by %d check(s); chi2 %.0f, %d dof, p = %.3g; first: %.120s", failures, r.chi2, r.dof, r.chi2_p,
              reason);
    pt_scene_destroy(s);
}

/* Directional albedo rho(theta) = \int f cos d omega_i of the conductor (F from fresnel_complex,
   or 1 when eta <= 0), two ways: (1) the midpoint rule on the half-vector square (n x n), (2) the
   midpoint rule in (cos theta_i, phi_i) on the hemisphere, refined near the mirror direction by
   splitting the polar range at the lobe. They must agree before either is trusted. */
static double f_cos(const ggx_ctx *c, dv3 i, double eta, double k)
{
    dv3 h;
    double F;
    if (i.z <= 0.0) return 0.0;
    h = dnorm(dadd(c->wo_l, i));
    F = eta > 0.0 ? fresnel_complex(ddot(c->wo_l, h), eta, k) : 1.0;
    return F * g_d(h, c->a2) * g_g1(c->wo_l, c->a2) * g_g1(i, c->a2) / (4.0 * c->wo_l.z);
}
static double albedo_halfvector(const ggx_ctx *c, double eta, double k, int n)
{
    /* x = 1 - (1 - v)^4: the integrand on the square grows like (1 - x)^(-1/2) toward grazing half
       vectors (wo.h / cos_h), which this substitution makes vanish instead */
    double sum = 0.0;
    int a, b;
    for (a = 0; a < n; a++) {
        double v = (a + 0.5) / n, x = 1.0 - pow(1.0 - v, 4.0), dx = 4.0 * pow(1.0 - v, 3.0);
        for (b = 0; b < n; b++) {
            double jac;
            dv3 w = hv_from_unit(c, x, (b + 0.5) / n, &jac);
            sum += f_cos(c, to_l(c, w), eta, k) * jac * dx;
        }
    }
    return sum / ((double)n * n);
}
static double albedo_spherical(const ggx_ctx *c, double eta, double k, int n)
{
    /* substitution u in [0,1] -> cos_i^2 weighted toward the mirror direction: the product of the
       midpoint rule in u = (1 - cos)^(1/4) and phi about the MIRROR direction r (lobe-centred
       polar coordinates), points below the surface contributing zero */
    dv3 r = dv(-c->wo_l.x, -c->wo_l.y, c->wo_l.z), e1, e2;
    double sum = 0.0;
    int a, b;
    tu_frame(r, &e1, &e2);
    for (a = 0; a < n; a++) {
        double u = (a + 0.5) / n, omc = 2.0 * u * u * u * u, du = 8.0 * u * u * u / n; /* d(1 - cos) */
        double ct = 1.0 - omc, st = sqrt(fmax(0.0, 1.0 - ct * ct));
        for (b = 0; b < 2 * n; b++) {
            double phi = 2.0 * TU_PI * (b + 0.5) / (2 * n);
            dv3 i = dadd(dadd(dscale(e1, st * cos(phi)), dscale(e2, st * sin(phi))), dscale(r, ct));
            sum += f_cos(c, i, eta, k) * du * (2.0 * TU_PI / (2 * n));
        }
    }
    return sum;
}

static void ggx_white_furnace(test_ctx *t)
{
    /* rays along -z at x = sin(theta) meet the unit sphere at angle theta; the sphere is convex, so
       the pixel is rho(theta) x 1. MIS (the default) and MATERIAL strategies. */
    static const double rough[4] = { 0.01, 0.1, 0.5, 1.0 }, angle[4] = { 0.0, 45.0, 80.0, 89.0 };
    const int n_paths = 40000, comparisons = 2 * 4 * 4 * 2;
    double zlim = tu_z_two_sided(1.0 - pow(0.99, 1.0 / comparisons)), worst = 0.0, worst_q = 0.0, loss1 = 0.0;
    int mi, ri, ai, strat;
    for (mi = 0; mi < 2; mi++) {
        const double eta = mi == 0 ? 0.0 : 0.1431189557, kk = mi == 0 ? 0.0 : 3.9831604247; /* gold's red channel */
        for (ri = 0; ri < 4; ri++) {
            pt_scene *s = pt_scene_create();
            pt_material_desc md;
            int m, rc;
            memset(&md, 0, sizeof md);
            md.type = PT_MATERIAL_ROUGH_CONDUCTOR;
            md.albedo = pt_v3(1, 1, 1);
            md.roughness = (float)rough[ri];
            md.conductor = mi == 0 ? PT_CONDUCTOR_NONE : PT_CONDUCTOR_AU;
            if (!CHECK(t, s != NULL, "scene")) return;
            m = pt_scene_add_material(s, &md);
            rc = m >= 0 && pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m) >= 0 && pt_scene_commit(s) == PT_OK;
            if (!CHECK(t, rc, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
            for (ai = 0; ai < 4; ai++) {
                double th = angle[ai] * TU_PI / 180.0, q1, q2;
                ggx_ctx c;
                ggx_setup(&c, dv(0, 0, 1), angle[ai], rough[ri]);
                q1 = albedo_halfvector(&c, eta, kk, 600);
                q2 = albedo_spherical(&c, eta, kk, 600);
                worst_q = fmax(worst_q, fabs(q1 - q2));
                CHECK(t, fabs(q1 - q2) < 1e-4, "quadratures disagree: alpha %g, %g degrees: %.6f vs %.6f", rough[ri], angle[ai],
                      q1, q2);
                if (mi == 0 && ri == 3 && ai == 0) {
                    /* closed form: at alpha 1, D cos d omega_h is uniform in sin^2 theta_h = x, wi
                       leaves at 2 theta_h and G1(wi) = 2 cos / (1 + cos), so rho = \int_0^1/2
                       (1 - 2x) / (1 - x) dx = 1 - ln 2 */
                    loss1 = 1.0 - q1;
                    CHECK(t, fabs(q1 - (1.0 - log(2.0))) < 2e-5, "F = 1, alpha 1, normal incidence: quadrature %.6f, 1 - ln 2 = %.6f",
                          q1, 1.0 - log(2.0));
                }
                for (strat = 0; strat < 2; strat++) {
                    pt_render_desc d = tu_base_desc(1, 1, 1, 0);
                    pt_path_stats st;
                    pt_rng rng;
                    pt_ray ray;
                    tu_acc acc;
                    double z;
                    int i;
                    memset(&st, 0, sizeof st);
                    memset(&acc, 0, sizeof acc);
                    d.background = pt_v3(1, 1, 1);
                    d.strategy = strat == 0 ? PT_STRATEGY_MIS : PT_STRATEGY_MATERIAL;
                    pt_rng_seed(&rng, 2200 + (uint64_t)(mi * 100 + ri * 10 + ai), (uint64_t)strat);
                    ray.origin = pt_v3((float)sin(th), 0.0f, 10.0f);
                    ray.dir = pt_v3(0, 0, -1);
                    for (i = 0; i < n_paths; i++) {
                        pt_color L = pt_trace_path(s, &d, ray, &rng, &st);
                        tu_acc_add(&acc, L.x);
                    }
                    CHECK(t, st.nonfinite_samples == 0, "alpha %g, %g degrees: %llu non-finite samples", rough[ri], angle[ai],
                          (unsigned long long)st.nonfinite_samples);
                    /* the ray's rounded hit is not exactly at theta: at 89 degrees the angle moves by
                       ~1e-5 rad, rho by < 1e-4 relative; the float floor covers it */
                    z = tu_z_floor(acc.mean, q1, tu_acc_se(&acc), 1e-3 * q1 + 1e-6);
                    worst = fmax(worst, z);
                    CHECK(t, z <= zlim, "%s alpha %g, %g degrees, %s: rho %.5f +- %.2g, quadrature %.5f (z %.2f > %.2f)",
                          mi ? "gold" : "F = 1", rough[ri], angle[ai], strat ? "MATERIAL" : "MIS", acc.mean,
                          tu_acc_se(&acc), q1, z, zlim);
                }
            }
            pt_scene_destroy(s);
        }
    }
    test_note(t, "%d comparisons, worst z %.2f (limit %.2f); quadratures agree to %.1e; F = 1, alpha 1 at normal incidence loses %.5f (ln 2)",
              comparisons, worst, zlim, worst_q, loss1);
}

static void ggx_fresnel(test_ctx *t)
{
    /* pt_material_conductor_fresnel of each named metal and a custom one against the complex
       formula; at normal incidence ((n-1)^2 + k^2) / ((n+1)^2 + k^2) */
    static const pt_conductor cs[5] = { PT_CONDUCTOR_AU, PT_CONDUCTOR_AG, PT_CONDUCTOR_CU, PT_CONDUCTOR_AL, PT_CONDUCTOR_CUSTOM };
    static const double tab[5][6] = {
        { 0.1431189557, 0.3749570432, 1.4424785571, 3.9831604247, 2.3857207478, 1.6032152899 },
        { 0.1552646489, 0.1167232965, 0.1383806959, 4.8283433224, 3.1222459278, 2.1469504455 },
        { 0.2004376970, 0.9240334304, 1.1022119527, 3.9129485033, 2.4528477015, 2.1421879552 },
        { 1.6574599595, 0.8803689579, 0.5212287346, 9.2238691996, 6.2695232477, 4.8370012281 },
        { 1.5, 2.0, 0.3, 0.0, 0.5, 7.0 } };
    pt_scene *s = pt_scene_create();
    int i, j, ch, bad = 0, m[6];
    double worst = 0.0;
    if (!CHECK(t, s != NULL, "scene")) return;
    for (i = 0; i < 5; i++) {
        pt_material_desc d;
        memset(&d, 0, sizeof d);
        d.type = PT_MATERIAL_ROUGH_CONDUCTOR;
        d.albedo = pt_v3(1, 1, 1);
        d.roughness = 0.3f;
        d.conductor = cs[i];
        d.eta = pt_v3((float)tab[4][0], (float)tab[4][1], (float)tab[4][2]);
        d.k = pt_v3((float)tab[4][3], (float)tab[4][4], (float)tab[4][5]);
        m[i] = pt_scene_add_material(s, &d);
        CHECK(t, m[i] >= 0, "conductor %d: %s", (int)cs[i], pt_scene_error_message(s));
    }
    m[5] = pt_scene_add_rough_conductor(s, PT_CONDUCTOR_NONE, 0.3f, pt_v3(1, 1, 1));
    for (i = 0; i < 5; i++) {
        for (j = 0; j <= 100; j++) {
            double c = j / 100.0;
            pt_color F = pt_material_conductor_fresnel(s, m[i], (float)c);
            for (ch = 0; ch < 3; ch++) {
                double want = fresnel_complex(c, (double)(float)tab[i][ch], (double)(float)tab[i][3 + ch]);
                double got = ch == 0 ? F.x : ch == 1 ? F.y : F.z, e = fabs(got - want) / fmax(want, 1e-3);
                worst = fmax(worst, e);
                if (e > 2e-4 && bad++ == 0)
                    CHECK(t, 0, "conductor %d channel %d cos %.2f: %.7f, complex formula %.7f", (int)cs[i], ch, c, got, want);
            }
            if (j == 100) {
                double n = (double)(float)tab[i][0], k = (double)(float)tab[i][3];
                double want = ((n - 1) * (n - 1) + k * k) / ((n + 1) * (n + 1) + k * k);
                CHECK(t, fabs(F.x - want) < 1e-5, "conductor %d at normal incidence: %.7f, closed form %.7f", (int)cs[i], F.x, want);
            }
        }
    }
    {
        pt_color one = pt_material_conductor_fresnel(s, m[5], 0.3f), none = pt_material_conductor_fresnel(s, 99, 0.5f);
        CHECK(t, one.x == 1.0f && one.y == 1.0f && one.z == 1.0f, "PT_CONDUCTOR_NONE: F = %g, not 1", one.x);
        CHECK(t, none.x == 0.0f, "a bad material id gave F = %g, not 0", none.x);
    }
    test_note(t, "5 conductors x 101 angles x 3 channels, worst relative difference %.2e (limit 2e-4)", worst);
    pt_scene_destroy(s);
}

static void ggx_mirror_limit(test_ctx *t)
{
    /* Below roughness 1e-3 the material is the Fresnel mirror (delta); at and above it a GGX lobe.
       Both sides of the switch give the furnace value of the smooth mirror F(cos) within the blur
       of the lobe; no NaN/Inf for roughness 0 .. 1e-2 at 0 .. 89.9 degrees. */
    static const float rough[7] = { 0.0f, 1e-4f, 9.99e-4f, 1e-3f, 1.01e-3f, 3e-3f, 1e-2f };
    static const double angle[4] = { 0.0, 45.0, 89.0, 89.9 };
    int ri, ai;
    double worst = 0.0;
    for (ri = 0; ri < 7; ri++) {
        pt_scene *s = pt_scene_create();
        int m, rc;
        if (!CHECK(t, s != NULL, "scene")) return;
        m = pt_scene_add_rough_conductor(s, PT_CONDUCTOR_CU, rough[ri], pt_v3(1, 1, 1));
        rc = m >= 0 && pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m) >= 0 && pt_scene_commit(s) == PT_OK;
        if (!CHECK(t, rc, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        CHECK(t, pt_material_is_delta(s, m) == (rough[ri] < 1e-3f), "roughness %g: delta %d", rough[ri],
              pt_material_is_delta(s, m));
        for (ai = 0; ai < 4; ai++) {
            double th = angle[ai] * TU_PI / 180.0, sum = 0.0;
            pt_render_desc d = tu_base_desc(1, 1, 1, 0);
            pt_path_stats st;
            pt_rng rng;
            pt_ray ray;
            pt_color F;
            int i, n = 4000;
            memset(&st, 0, sizeof st);
            d.background = pt_v3(1, 1, 1);
            pt_rng_seed(&rng, 2300 + (uint64_t)ri, (uint64_t)ai);
            ray.origin = pt_v3((float)sin(th), 0.0f, 10.0f);
            ray.dir = pt_v3(0, 0, -1);
            for (i = 0; i < n; i++) sum += pt_trace_path(s, &d, ray, &rng, &st).y;
            sum /= n;
            CHECK(t, st.nonfinite_samples == 0, "roughness %g, %g degrees: %llu non-finite samples", rough[ri], angle[ai],
                  (unsigned long long)st.nonfinite_samples);
            if (ai < 2) { /* away from grazing the lobe's blur and masking change rho by < 1e-3 */
                float ct;
                pt_hit h;
                pt_scene_intersect(s, ray, 1e30f, &h);
                ct = pt_dot(h.geometric_normal, pt_v3(0, 0, 1));
                F = pt_material_conductor_fresnel(s, m, ct);
                worst = fmax(worst, fabs(sum - F.y));
                CHECK(t, fabs(sum - F.y) < 2e-3 + (rough[ri] >= 1e-2f ? 3e-3 : 0.0),
                      "roughness %g, %g degrees: furnace %.6f, mirror F %.6f", rough[ri], angle[ai], sum, F.y);
            }
        }
        pt_scene_destroy(s);
    }
    test_note(t, "roughness 0 .. 1e-2 through the delta switch at 1e-3: furnace within %.1e of the mirror's F; no NaN/Inf", worst);
}

static void ggx_api_errors(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_material_desc d;
    int rc;
    if (!CHECK(t, s != NULL, "scene")) return;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_ROUGH_CONDUCTOR;
    d.albedo = pt_v3(1, 1, 1);
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc >= 0 && pt_material_is_delta(s, rc) == 1, "zero-initialised rough conductor: %d (want a delta mirror)", rc);
    d.roughness = -0.1f;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "roughness"), "roughness -0.1: %d '%s'", rc,
          pt_scene_error_message(s));
    d.roughness = 1.5f;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "roughness"), "roughness 1.5: %d", rc);
    d.roughness = NAN;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "roughness"), "roughness NaN: %d", rc);
    d.roughness = 0.2f;
    d.conductor = (pt_conductor)77;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "conductor"), "conductor 77: %d", rc);
    d.conductor = PT_CONDUCTOR_CUSTOM;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "eta"), "custom with eta 0: %d '%s'", rc,
          pt_scene_error_message(s));
    d.eta = pt_v3(1, 1, 1);
    d.k = pt_v3(1, -1, 1);
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), " k "), "custom with k < 0: %d '%s'", rc,
          pt_scene_error_message(s));
    d.k = pt_v3(1, 0, 1);
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc >= 0, "custom conductor eta 1, k (1, 0, 1) refused: %s", pt_scene_error_message(s));
    {
        pt_scene_info info;
        int m2 = pt_scene_add_rough_conductor(s, PT_CONDUCTOR_AG, 0.2f, pt_v3(1, 1, 1));
        CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m2) >= 0 && pt_scene_commit(s) == PT_OK, "commit");
        pt_scene_get_info(s, &info);
        CHECK(t, (info.features & PT_FEATURE_MICROFACET) != 0, "PT_FEATURE_MICROFACET not set");
    }
    pt_scene_destroy(s);
    s = pt_scene_create();
    if (s) {
        pt_scene_info info;
        int m3 = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f)), m4 = pt_scene_add_rough_conductor(s, PT_CONDUCTOR_AU, 0, pt_v3(1, 1, 1));
        CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m3) >= 0 && pt_scene_add_sphere(s, pt_v3(3, 0, 0), 1, m4) >= 0 &&
                     pt_scene_commit(s) == PT_OK, "commit 2");
        pt_scene_get_info(s, &info);
        CHECK(t, (info.features & PT_FEATURE_MICROFACET) == 0, "PT_FEATURE_MICROFACET set without a rough (non-delta) conductor");
        pt_scene_destroy(s);
    }
}

static void ggx_strategies_agree(test_ctx *t)
{
    /* A rough copper plane under a quad light (a glossy highlight): MIS, MATERIAL, LIGHT and
       MIXTURE estimate the same radiance along each of 4 camera rays (z-tests between MIS and each
       other strategy, alpha = 0.01, Sidak over 12 comparisons). Direct light only (max_depth 1). */
    pt_scene *s = pt_scene_create();
    int cu, light, k, st_i, rc;
    double zlim = tu_z_two_sided(1.0 - pow(0.99, 1.0 / 12.0)), worst = 0.0;
    if (!CHECK(t, s != NULL, "scene")) return;
    cu = pt_scene_add_rough_conductor(s, PT_CONDUCTOR_CU, 0.2f, pt_v3(1, 1, 1));
    light = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0);
    rc = pt_scene_add_quad(s, pt_v3(-5, 0, -5), pt_v3(0, 0, 10), pt_v3(10, 0, 0), cu) >= 0;
    rc &= pt_scene_add_quad(s, pt_v3(-0.5f, 2, -0.5f), pt_v3(1, 0, 0), pt_v3(0, 0, 1), light) >= 0;
    rc &= pt_scene_commit(s) == PT_OK;
    if (!CHECK(t, rc, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (k = 0; k < 4; k++) {
        pt_ray ray;
        tu_acc acc[4];
        ray.origin = pt_v3(-2.0f - 0.5f * k, 1.5f, 0.1f * k);
        ray.dir = pt_normalize(pt_sub(pt_v3(0.3f * k - 0.2f, 0, 0.05f), ray.origin));
        for (st_i = 0; st_i < 4; st_i++) {
            pt_render_desc d = tu_base_desc(1, 1, 1, 0);
            pt_path_stats ps;
            pt_rng rng;
            int i;
            memset(&ps, 0, sizeof ps);
            memset(&acc[st_i], 0, sizeof acc[st_i]);
            d.strategy = (pt_strategy)st_i;
            d.max_depth = 1;
            pt_rng_seed(&rng, 2400 + (uint64_t)k, (uint64_t)st_i);
            for (i = 0; i < 100000; i++) tu_acc_add(&acc[st_i], pt_trace_path(s, &d, ray, &rng, &ps).x);
            CHECK(t, ps.nonfinite_samples == 0, "ray %d strategy %d: non-finite samples", k, st_i);
        }
        for (st_i = 1; st_i < 4; st_i++) {
            double se = sqrt(tu_acc_se(&acc[0]) * tu_acc_se(&acc[0]) + tu_acc_se(&acc[st_i]) * tu_acc_se(&acc[st_i]));
            double z = se > 0 ? fabs(acc[0].mean - acc[st_i].mean) / se : 0.0;
            worst = fmax(worst, z);
            CHECK(t, z <= zlim, "ray %d: MIS %.5f, strategy %d %.5f (z %.2f > %.2f)", k, acc[0].mean, st_i, acc[st_i].mean, z, zlim);
        }
        CHECK(t, acc[0].mean > 0.01, "ray %d sees no highlight (%.4g): the test would be vacuous", k, acc[0].mean);
    }
    test_note(t, "4 rays x 3 strategy pairs, worst z %.2f (limit %.2f)", worst, zlim);
    pt_scene_destroy(s);
}


/* ==== the rough dielectric (PT_MATERIAL_ROUGH_DIELECTRIC) ====
   The frame's normal n is on wo's side; eta = n_far / n_near (1.5 from outside, 1/1.5 from
   inside, the public PDF told which by the outward normal it is given). The chi-square domain is
   the microfacet normal: the unit square's left half is reflection (the half vector), its right half
   transmission (the generalised half vector m ~ o + eta i), each in the coordinates of the
   conductor's histogram (x = tan^2 / (alpha^2 + tan^2), azimuth). */
typedef struct rd_ctx {
    ggx_ctx g;
    double eta;
} rd_ctx;
static double rd_fresnel(double c, double r) /* dielectric, n_i / n_t = r, cos_i = c > 0 */
{
    double s2 = r * r * (1.0 - c * c), ct, rs, rp;
    if (s2 >= 1.0) return 1.0;
    ct = sqrt(1.0 - s2);
    rs = (r * c - ct) / (r * c + ct);
    rp = (c - r * ct) / (c + r * ct);
    return 0.5 * (rs * rs + rp * rp);
}
/* the generalised half vector of a transmission, on the normal's side; 0 if o.m > 0 > i.m fails */
static int rd_half_t(const rd_ctx *c, dv3 i, dv3 *m)
{
    dv3 h = dadd(c->g.wo_l, dscale(i, c->eta));
    if (dlen(h) <= 0.0) return 0;
    h = dnorm(h);
    if (h.z < 0.0) h = dscale(h, -1.0);
    *m = h;
    return ddot(c->g.wo_l, h) > 0.0 && ddot(i, h) < 0.0;
}
/* A pScatter (want_f) or the sampling density, in double */
static double rd_eval(const rd_ctx *c, dv3 i, int want_f)
{
    const dv3 o = c->g.wo_l;
    const double a2 = c->g.a2;
    dv3 h;
    double F, om, im, den, t;
    if (i.z > 0.0) {
        h = dnorm(dadd(o, i));
        F = rd_fresnel(ddot(o, h), 1.0 / c->eta);
        t = F * g_d(h, a2) * g_g1(o, a2) / (4.0 * o.z);
        return want_f ? t * g_g1(i, a2) : t;
    }
    if (i.z == 0.0 || !rd_half_t(c, i, &h)) return 0.0;
    om = ddot(o, h);
    im = ddot(i, h);
    F = rd_fresnel(om, 1.0 / c->eta);
    den = om + c->eta * im;
    t = (1.0 - F) * g_d(h, a2) * g_g1(o, a2) * om * -im / (o.z * den * den);
    return want_f ? t * g_g1(dv(i.x, i.y, -i.z), a2) : t * c->eta * c->eta;
}
static double ref_rd(const void *ctx, dv3 w, int *near)
{
    const rd_ctx *c = (const rd_ctx *)ctx;
    dv3 i = to_l(&c->g, w), s = i.z > 0.0 ? dadd(c->g.wo_l, i) : dadd(c->g.wo_l, dscale(i, c->eta));
    /* float rounding: near the surface, and the (generalised) half vector of a cancellation */
    *near = fabs(i.z) < 2e-2 || 4.8e-7 * fmax(1.0, c->eta) / (dlen(s) * c->g.a) > 2e-4;
    if (i.z > 0.0) { /* reflection near the critical angle: F's slope is infinite there */
        double om = ddot(c->g.wo_l, dnorm(s));
        if (fabs((1.0 - om * om) / (c->eta * c->eta) - 1.0) < 0.05) *near = 1;
    }
    if (i.z < 0.0 && dlen(s) > 0.0) {
        /* a microfacet seen edge-on (o.m -> 0: 1 - F and o.m carry o.m's rounding, relative), one
           near total internal reflection (1 - F ~ cos_t, a cancellation), or one at m_z = 0 (where
           the sign of o + eta i, and D, jump) */
        dv3 m = dnorm(s);
        double om = fabs(ddot(c->g.wo_l, m));
        if (om < 2e-3 || (1.0 - om * om) / (c->eta * c->eta) > 0.95 || fabs(m.z) < 1e-3) *near = 1;
    }
    return rd_eval(c, i, 0);
}
static int rd_to_unit(const void *ctx, dv3 w, double *x, double *y)
{
    const rd_ctx *c = (const rd_ctx *)ctx;
    dv3 i = to_l(&c->g, w), h;
    double s, phi;
    int t = i.z < 0.0;
    if (i.z == 0.0) return 0;
    if (!t) {
        h = dnorm(dadd(c->g.wo_l, i));
        if (h.z <= 0.0) return 0;
    } else {
        h = dadd(c->g.wo_l, dscale(i, c->eta));
        if (dlen(h) <= 0.0) return 0;
        h = dnorm(h);
        if (h.z < 0.0) h = dscale(h, -1.0);
    }
    s = h.x * h.x + h.y * h.y;
    /* X' = 1 - (1 - X)^(1/4): the tilted microfacets that still refract near total internal
       reflection (a sliver X > 1 - 1e-4 at alpha 0.01) get a visible share of the cell */
    *x = 0.5 * (t + fmin(1.0 - pow(1.0 - s / (s + c->g.a2 * h.z * h.z), 0.25), 1.0 - 1e-12));
    phi = atan2(h.y, h.x);
    if (phi < 0.0) phi += 2.0 * TU_PI;
    *y = fmin(phi / (2.0 * TU_PI), 1.0 - 1e-12);
    return 1;
}
static dv3 rd_from_unit(const void *ctx, double x, double y, double *jac)
{
    const rd_ctx *c = (const rd_ctx *)ctx;
    const dv3 o = c->g.wo_l;
    int t = x >= 0.5;
    double Xp = 2.0 * x - t, X = 1.0 - pow(1.0 - Xp, 4.0), tt = c->g.a2 * X / (1.0 - X);
    double cos_t = 1.0 / sqrt(1.0 + tt), sin_t = sqrt(tt / (1.0 + tt)), phi = 2.0 * TU_PI * y, oh;
    /* d omega_m / dx dy: 2 (the half square) x 4 (1 - X')^3 x pi cos^3 alpha^2 / (1 - X)^2 */
    double dm = 2.0 * 4.0 * pow(1.0 - Xp, 3.0) * TU_PI * cos_t * cos_t * cos_t * c->g.a2 / ((1.0 - X) * (1.0 - X));
    dv3 h = dv(sin_t * cos(phi), sin_t * sin(phi), cos_t), i;
    oh = ddot(o, h);
    *jac = 0.0;
    if (!t) {
        i = dsub(dscale(h, 2.0 * oh), o);
        if (i.z > 0.0 && oh > 0.0) *jac = 4.0 * oh * dm;
    } else {
        double r = 1.0 / c->eta, s2 = r * r * (1.0 - oh * oh), ct, im, den;
        if (oh <= 0.0 || s2 >= 1.0) return dnorm(from_l(&c->g, dv(0.0, 0.0, -1.0))); /* no refraction: jac 0 */
        ct = sqrt(1.0 - s2);
        i = dadd(dscale(o, -r), dscale(h, r * oh - ct));
        im = ddot(i, h);
        den = oh + c->eta * im;
        if (i.z < 0.0) *jac = den * den / (c->eta * c->eta * fabs(im)) * dm;
    }
    return dnorm(from_l(&c->g, i));
}
static double rd_propose(const void *ctx, pt_rng *r, dv3 *w)
{
    double jac;
    *w = rd_from_unit(ctx, tu_rand(r), tu_rand(r), &jac);
    return jac > 0.0 ? 1.0 / jac : 1e300;
}
/* n on wo's side; inside: wo is inside the glass (eta = 1 / ior) */
static void rd_setup(rd_ctx *c, dv3 n, double theta_deg, double a, double ior, int inside)
{
    ggx_setup(&c->g, n, theta_deg, a);
    c->eta = inside ? 1.0 / (double)(float)ior : (double)(float)ior;
    if (inside) c->eta = 1.0 / (double)(float)ior;
}
static void rd_domain(tu_domain *dom, rd_ctx *c)
{
    dom->to_unit = rd_to_unit;
    dom->from_unit = rd_from_unit;
    dom->propose = rd_propose;
    dom->ctx = c;
}

static void rough_dielectric_chi2(test_ctx *t)
{
    /* 4 roughnesses x 4 angles x {outside, inside}; each histogram holds both lobes */
    static const double rough[4] = { 0.01, 0.1, 0.5, 1.0 }, angle[4] = { 0.0, 45.0, 80.0, 89.0 };
    static char labels[32][96];
    pt_scene *s = pt_scene_create();
    int mats[4], ri, ai, side, rc = 0;
    double min_p = 2.0;
    if (!CHECK(t, s != NULL, "pt_scene_create failed")) return;
    for (ri = 0; ri < 4; ri++) {
        mats[ri] = pt_scene_add_rough_dielectric(s, 1.5f, (float)rough[ri]);
        rc |= mats[ri] < 0;
    }
    rc |= pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, mats[0]) < 0;
    rc |= pt_scene_commit(s) != PT_OK;
    if (!CHECK(t, rc == 0, "scene setup failed: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (ri = 0; ri < 4; ri++) {
        CHECK(t, pt_material_is_delta(s, mats[ri]) == 0, "roughness %g reported delta", rough[ri]);
        for (ai = 0; ai < 4; ai++)
            for (side = 0; side < 2; side++) {
                rd_ctx ctx;
                tu_domain dom;
                tu_pdf_check c;
                tu_pdf_result r;
                pt_pdf p;
                char *label = labels[(ri * 4 + ai) * 2 + side];
                rd_setup(&ctx, dnorm(dv(0.2, 1.0, -0.3)), angle[ai], rough[ri], 1.5, side);
                /* the public PDF takes the outward normal: from inside it points away from wo */
                p = pt_pdf_material(s, mats[ri], side ? dv_to(dscale(ctx.g.n, -1.0)) : dv_to(ctx.g.n), dv_to(ctx.g.wo));
                snprintf(label, 96, "rough dielectric alpha %.2f, %.0f degrees, from %s", rough[ri], angle[ai],
                         side ? "inside" : "outside");
                rd_domain(&dom, &ctx);
                memset(&c, 0, sizeof c);
                c.label = label;
                c.pdf = &p;
                c.axis = ctx.g.n;
                c.omc = 2.0;
                c.domain = &dom;
                c.expected_mass = -1.0; /* below 1: directions a microfacet sends to the wrong side fail */
                c.support = -1.0;
                c.ref = ref_rd;
                c.ref_ctx = &ctx;
                c.n_samples = 60000;
                c.n_mass = 12000;
                c.ns = 16;
                c.nphi = 12;
                c.seed = 2500 + (uint64_t)((ri * 4 + ai) * 2 + side);
                c.alpha = tu_suite_alpha();
                c.inv_z = 0.0;
                TU_CHECK_PDF(t, &c, &r);
                if (r.chi2_p < min_p) min_p = r.chi2_p;
            }
    }
    test_note(t, "32 cases, 6 x 10^4 draws each, smallest chi-square p %.3g (alpha per comparison %.2g)", min_p,
              tu_suite_alpha());
    pt_scene_destroy(s);
}

/* WRONG: the rough dielectric's visible-normal samples reported with the plain NDF density
   D(m) cos_m (F or 1 - F) |dm/di| */
typedef struct rd_wrong { pt_pdf inner; rd_ctx *c; } rd_wrong;
static float rd_ndf_density(const rd_ctx *c, pt_vec3 w)
{
    dv3 i = to_l(&c->g, dv_from(w)), h;
    double F, om, im, den;
    if (i.z > 0.0) {
        h = dnorm(dadd(c->g.wo_l, i));
        F = rd_fresnel(ddot(c->g.wo_l, h), 1.0 / c->eta);
        return (float)(F * g_d(h, c->g.a2) * h.z / (4.0 * ddot(c->g.wo_l, h)));
    }
    if (i.z == 0.0 || !rd_half_t(c, i, &h)) return 0.0f;
    om = ddot(c->g.wo_l, h);
    im = ddot(i, h);
    den = om + c->eta * im;
    F = rd_fresnel(om, 1.0 / c->eta);
    return (float)((1.0 - F) * g_d(h, c->g.a2) * h.z * c->eta * c->eta * -im / (den * den));
}
static int rd_wrong_sample(void *user, pt_rng *rng, pt_vec3 *dir, float *pdf)
{
    rd_wrong *u = (rd_wrong *)user;
    if (!pt_pdf_sample(&u->inner, rng, dir, pdf)) return 0;
    *pdf = rd_ndf_density(u->c, *dir);
    if (!(*pdf > 0.0f)) { *dir = pt_v3(0, 0, 0); *pdf = 0.0f; return 0; }
    return 1;
}
static float rd_wrong_value(void *user, pt_vec3 dir) { return rd_ndf_density(((rd_wrong *)user)->c, dir); }
static void harness_rejects_rough_dielectric_ndf_density(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    int m, failures;
    rd_ctx ctx;
    tu_domain dom;
    tu_pdf_check c;
    tu_pdf_result r;
    rd_wrong u;
    pt_pdf p;
    char reason[768];
    if (!CHECK(t, s != NULL, "pt_scene_create failed")) return;
    m = pt_scene_add_rough_dielectric(s, 1.5f, 0.5f);
    if (!CHECK(t, m >= 0 && pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m) >= 0 && pt_scene_commit(s) == PT_OK, "scene: %s",
               pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    rd_setup(&ctx, dv(0, 0, 1), 60.0, 0.5, 1.5, 0);
    u.inner = pt_pdf_material(s, m, dv_to(ctx.g.n), dv_to(ctx.g.wo));
    u.c = &ctx;
    p = pt_pdf_callback(&u, rd_wrong_sample, rd_wrong_value);
    rd_domain(&dom, &ctx);
    memset(&c, 0, sizeof c);
    c.label = "WRONG: rough dielectric visible-normal samples, NDF density";
    c.pdf = &p;
    c.axis = ctx.g.n;
    c.omc = 2.0;
    c.domain = &dom;
    c.expected_mass = -1.0;
    c.support = -1.0;
    c.n_samples = 200000;
    c.n_mass = 40000;
    c.ns = 24;
    c.nphi = 24;
    c.seed = 2590;
    c.alpha = tu_suite_alpha();
    failures = tu_check_pdf_rejects(&c, &r, reason, sizeof reason);
    CHECK(t, failures > 0, "the NDF density with visible-normal samples was not rejected (chi2 p = %.3g)", r.chi2_p);
    CHECK(t, r.chi2_p < c.alpha, "chi-square p = %.3g not below alpha %.3g", r.chi2_p, c.alpha);
    test_note(t, "rejected by %d check(s); chi2 %.0f, %d dof, p = %.3g; first: %.120s", failures, r.chi2, r.dof, r.chi2_p,
              reason);
    pt_scene_destroy(s);
}

/* \int A pScatter over the sphere, reflection (*R) and transmission (*T, as rendered: with the
   1 / eta^2 of radiance), by the midpoint rule on the microfacet square of rd_from_unit (n x n per
   half, x = 1 - (1 - v)^2 in each half, which with rd_from_unit's own substitution makes the
   integrand vanish toward grazing microfacets as albedo_halfvector's does) */
static void rd_albedo(const rd_ctx *c, int n, double *R, double *T)
{
    int half, a, b;
    *R = *T = 0.0;
    for (half = 0; half < 2; half++)
        for (a = 0; a < n; a++) {
            double v = (a + 0.5) / n, X = 1.0 - pow(1.0 - v, 2.0), dx = 2.0 * (1.0 - v), sum = 0.0;
            for (b = 0; b < n; b++) {
                double jac;
                dv3 w = rd_from_unit(c, 0.5 * (X + half), (b + 0.5) / n, &jac);
                if (jac > 0.0) sum += rd_eval(c, to_l(&c->g, w), 1) * jac * 0.5 * dx;
            }
            if (half) *T += sum / ((double)n * n);
            else *R += sum / ((double)n * n);
        }
}

static void rough_dielectric_furnace(test_ctx *t)
{
    /* A 2000 x 2000 quad of rough glass (the plane z = 0, outward normal +z) under a uniform
       background 1: a ray meeting it at angle theta from above (outside) or below (inside) scatters
       once and leaves, so its radiance is the albedo R + T of the model (T with 1 / eta^2). The
       albedo is integrated numerically (two resolutions that must agree); z-tests at alpha 0.01,
       Sidak over the comparisons. The energy R + eta^2 T must not exceed 1 and, at alpha 0.01,
       must lose under 1e-3 (the single-scattering loss of a nearly smooth interface). */
    static const double rough[4] = { 0.01, 0.1, 0.5, 1.0 }, angle[4] = { 0.0, 45.0, 80.0, 89.0 };
    const int n_paths = 6000, comparisons = 2 * 4 * 4;
    double zlim = tu_z_two_sided(1.0 - pow(0.99, 1.0 / comparisons)), worst = 0.0, worst_q = 0.0, min_e = 2.0, max_e = 0.0;
    int ri, ai, side;
    for (ri = 0; ri < 4; ri++) {
        pt_scene *s = pt_scene_create();
        int m, rc;
        if (!CHECK(t, s != NULL, "scene")) return;
        m = pt_scene_add_rough_dielectric(s, 1.5f, (float)rough[ri]);
        rc = m >= 0 && pt_scene_add_quad(s, pt_v3(-1000, -1000, 0), pt_v3(2000, 0, 0), pt_v3(0, 2000, 0), m) >= 0 &&
             pt_scene_commit(s) == PT_OK;
        if (!CHECK(t, rc, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        for (ai = 0; ai < 4; ai++)
            for (side = 0; side < 2; side++) {
                double th = angle[ai] * TU_PI / 180.0, R1, T1, R2, T2, q, e, z;
                rd_ctx c;
                pt_render_desc d = tu_base_desc(1, 1, 1, 0);
                pt_path_stats st;
                pt_rng rng;
                pt_ray ray;
                tu_acc acc;
                int i;
                rd_setup(&c, dv(0, 0, side ? -1.0 : 1.0), angle[ai], rough[ri], 1.5, side);
                /* from inside the total-internal-reflection edge is a jump of the integrand across the
                   grid: the midpoint rule converges as 1/n there, so the two resolutions' difference
                   is the quadrature's error bound and widens the z-test's floor */
                rd_albedo(&c, 150, &R1, &T1);
                rd_albedo(&c, 300, &R2, &T2);
                q = R2 + T2;
                worst_q = fmax(worst_q, fabs(q - (R1 + T1)));
                CHECK(t, fabs(q - (R1 + T1)) < 1e-2 * q, "quadratures disagree: alpha %g, %g degrees, side %d: %.6f vs %.6f",
                      rough[ri], angle[ai], side, R1 + T1, q);
                e = R2 + T2 * c.eta * c.eta;
                min_e = fmin(min_e, e);
                max_e = fmax(max_e, e);
                CHECK(t, e <= 1.0 + 1e-3 + fabs(q - (R1 + T1)) * c.eta * c.eta, "alpha %g, %g degrees, side %d: energy R + eta^2 T = %.5f > 1", rough[ri], angle[ai],
                      side, e);
                if (ri == 0 && ai < 2)
                    CHECK(t, e > 0.999, "alpha 0.01, %g degrees, side %d: energy %.5f loses more than 1e-3", angle[ai], side, e);
                memset(&st, 0, sizeof st);
                memset(&acc, 0, sizeof acc);
                d.background = pt_v3(1, 1, 1);
                pt_rng_seed(&rng, 2600 + (uint64_t)(ri * 10 + ai), (uint64_t)side);
                /* the ray meets the plane at the origin at angle theta, in the frame's (n, e1) plane */
                ray.dir = dv_to(dscale(dadd(dscale(c.g.n, cos(th)), dscale(c.g.e1, sin(th))), -1.0));
                ray.origin = pt_scale(ray.dir, -10.0f);
                for (i = 0; i < n_paths; i++) tu_acc_add(&acc, pt_trace_path(s, &d, ray, &rng, &st).y);
                CHECK(t, st.nonfinite_samples == 0, "alpha %g, %g degrees, side %d: %llu non-finite samples", rough[ri],
                      angle[ai], side, (unsigned long long)st.nonfinite_samples);
                z = tu_z_floor(acc.mean, q, tu_acc_se(&acc), 2e-3 * q + fabs(q - (R1 + T1)) + 1e-6);
                worst = fmax(worst, z);
                CHECK(t, z <= zlim, "alpha %g, %g degrees, from %s: albedo %.5f +- %.2g, quadrature %.5f (z %.2f > %.2f)",
                      rough[ri], angle[ai], side ? "inside" : "outside", acc.mean, tu_acc_se(&acc), q, z, zlim);
            }
        pt_scene_destroy(s);
    }
    test_note(t, "%d comparisons, worst z %.2f (limit %.2f); quadratures agree to %.1e; energy R + eta^2 T in [%.4f, %.4f]",
              comparisons, worst, zlim, worst_q, min_e, max_e);
}

static void rough_dielectric_smooth_limit(test_ctx *t)
{
    /* Through the delta switch (alpha 1e-3) the rough dielectric's furnace (the plane above, from
       outside and inside at 0 and 45 degrees) stays at the smooth interface's R + T / eta^2 within
       the lobe's blur; roughness 0 .. 1e-2, and ior near 1 (1.0005: delta by alpha |eta - 1|), no
       NaN/Inf. */
    static const float rough[6] = { 0.0f, 1e-4f, 9.99e-4f, 1e-3f, 3e-3f, 1e-2f };
    static const double angle[2] = { 0.0, 30.0 }; /* (from inside, 30 is below the critical 41.8) */
    int ri, ai, side;
    double worst = 0.0;
    for (ri = 0; ri < 7; ri++) {
        pt_scene *s = pt_scene_create();
        float ior = ri < 6 ? 1.5f : 1.0005f, a = ri < 6 ? rough[ri] : 0.5f;
        int m, rc;
        if (!CHECK(t, s != NULL, "scene")) return;
        m = pt_scene_add_rough_dielectric(s, ior, a);
        rc = m >= 0 && pt_scene_add_quad(s, pt_v3(-1000, -1000, 0), pt_v3(2000, 0, 0), pt_v3(0, 2000, 0), m) >= 0 &&
             pt_scene_commit(s) == PT_OK;
        if (!CHECK(t, rc, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        CHECK(t, pt_material_is_delta(s, m) == (a < 1e-3f || a * fabsf(ior - 1.0f) < 1e-3f), "roughness %g ior %g: delta %d", a, ior,
              pt_material_is_delta(s, m));
        for (ai = 0; ai < 2; ai++)
            for (side = 0; side < 2; side++) {
                double th = angle[ai] * TU_PI / 180.0, eta = side ? 1.0 / ior : ior, c = cos(th), F, want, sum = 0.0;
                pt_render_desc d = tu_base_desc(1, 1, 1, 0);
                pt_path_stats st;
                pt_rng rng;
                pt_ray ray;
                int i, n = 4000;
                F = rd_fresnel(c, 1.0 / eta);
                want = F + (1.0 - F) / (eta * eta);
                memset(&st, 0, sizeof st);
                d.background = pt_v3(1, 1, 1);
                pt_rng_seed(&rng, 2700 + (uint64_t)ri, (uint64_t)(ai * 2 + side));
                ray.dir = pt_normalize(pt_v3((float)sin(th), 0.0f, side ? (float)c : -(float)c));
                ray.origin = pt_scale(ray.dir, -10.0f);
                for (i = 0; i < n; i++) sum += pt_trace_path(s, &d, ray, &rng, &st).y;
                sum /= n;
                CHECK(t, st.nonfinite_samples == 0, "roughness %g, %g degrees: %llu non-finite samples", a, angle[ai],
                      (unsigned long long)st.nonfinite_samples);
                worst = fmax(worst, fabs(sum - want) / want);
                /* the sampled choice R/T is the noise: sd sqrt(F (1 - F)) |1 - 1/eta^2| / sqrt(n); 4.5 of
                   it, plus the lobe's blur */
                CHECK(t, fabs(sum - want) < 4.5 * sqrt(F * (1.0 - F) / n) * fabs(1.0 - 1.0 / (eta * eta)) + 2e-3 * want,
                      "roughness %g ior %g, %g degrees, side %d: furnace %.6f, smooth %.6f", a, ior, angle[ai], side, sum, want);
            }
        pt_scene_destroy(s);
    }
    test_note(t, "roughness 0 .. 1e-2 through the delta switch, and ior 1.0005: within %.1e (relative) of the smooth "
                 "interface; no NaN/Inf", worst);
}

static void rough_dielectric_api_errors(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_material_desc d;
    pt_scene_info info;
    int rc;
    if (!CHECK(t, s != NULL, "scene")) return;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_ROUGH_DIELECTRIC;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc >= 0 && pt_material_is_delta(s, rc) == 1, "zero-initialised rough dielectric: %d (want smooth glass)", rc);
    d.roughness = 1.5f;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "roughness"), "roughness 1.5: %d", rc);
    d.roughness = 0.2f;
    d.ext_ior = -1.0f;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "ext_ior"), "ext_ior -1: %d '%s'", rc,
          pt_scene_error_message(s));
    d.ext_ior = 1.33f;
    d.ior = 1e-3f;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc >= 0, "ior 1e-3 under water refused: %s", pt_scene_error_message(s));
    d.ior = NAN;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "ior"), "ior NaN: %d", rc);
    rc = pt_scene_add_rough_dielectric(s, 1.5f, 0.3f);
    CHECK(t, rc >= 0 && pt_material_is_delta(s, rc) == 0, "pt_scene_add_rough_dielectric: %d", rc);
    CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, rc) >= 0 && pt_scene_commit(s) == PT_OK, "commit");
    pt_scene_get_info(s, &info);
    CHECK(t, (info.features & PT_FEATURE_MICROFACET) != 0, "PT_FEATURE_MICROFACET not set for a rough dielectric");
    pt_scene_destroy(s);
}

static void rough_dielectric_lights_below(test_ctx *t)
{
    /* The integrator's other side: a rough glass plane (z = 0) seen from above, lit from below it
       by a quad light and a point light through transmission (and by a background of 0.2 from both
       sides). MIS, MATERIAL, LIGHT and MIXTURE must agree (z-tests between MIS and each other,
       alpha 0.01, Sidak over 9), and the light below must come through. Direct light only. */
    pt_scene *s = pt_scene_create();
    int g, light, k, st_i, rc;
    double zlim = tu_z_two_sided(1.0 - pow(0.99, 1.0 / 9.0)), worst = 0.0;
    if (!CHECK(t, s != NULL, "scene")) return;
    g = pt_scene_add_rough_dielectric(s, 1.5f, 0.3f);
    light = pt_scene_add_emitter(s, pt_v3(4, 4, 4), 0);
    rc = pt_scene_add_quad(s, pt_v3(-5, -5, 0), pt_v3(10, 0, 0), pt_v3(0, 10, 0), g) >= 0;
    rc &= pt_scene_add_quad(s, pt_v3(-0.5f, -0.5f, -2), pt_v3(1, 0, 0), pt_v3(0, 1, 0), light) >= 0; /* u x v = +z: faces the glass */
    {
        pt_light_desc ld;
        memset(&ld, 0, sizeof ld);
        ld.type = PT_LIGHT_POINT;
        ld.position = pt_v3(1.0f, 0.5f, -1.0f);
        ld.intensity = pt_v3(2, 2, 2);
        rc &= pt_scene_add_light(s, &ld) >= 0;
    }
    rc &= pt_scene_commit(s) == PT_OK;
    if (!CHECK(t, rc, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (k = 0; k < 3; k++) {
        pt_ray ray;
        tu_acc acc[4];
        ray.origin = pt_v3(0.3f * k, -0.2f, 2.0f);
        ray.dir = pt_normalize(pt_sub(pt_v3(0.2f * k - 0.1f, 0.1f, 0), ray.origin));
        for (st_i = 0; st_i < 4; st_i++) {
            pt_render_desc d = tu_base_desc(1, 1, 1, 0);
            pt_path_stats ps;
            pt_rng rng;
            int i;
            memset(&ps, 0, sizeof ps);
            memset(&acc[st_i], 0, sizeof acc[st_i]);
            d.strategy = (pt_strategy)st_i;
            d.max_depth = 1;
            d.background = pt_v3(0.2f, 0.2f, 0.2f);
            pt_rng_seed(&rng, 2800 + (uint64_t)k, (uint64_t)st_i);
            for (i = 0; i < 40000; i++) tu_acc_add(&acc[st_i], pt_trace_path(s, &d, ray, &rng, &ps).x);
            CHECK(t, ps.nonfinite_samples == 0, "ray %d strategy %d: non-finite samples", k, st_i);
        }
        for (st_i = 1; st_i < 4; st_i++) {
            double se = sqrt(tu_acc_se(&acc[0]) * tu_acc_se(&acc[0]) + tu_acc_se(&acc[st_i]) * tu_acc_se(&acc[st_i]));
            double z = se > 0 ? fabs(acc[0].mean - acc[st_i].mean) / se : 0.0;
            worst = fmax(worst, z);
            CHECK(t, z <= zlim, "ray %d: MIS %.5f, strategy %d %.5f (z %.2f > %.2f)", k, acc[0].mean, st_i, acc[st_i].mean, z,
                  zlim);
        }
        /* above the plane only the background's reflection (< 0.2 x 0.2) could arrive without transmission */
        CHECK(t, acc[0].mean > 0.1, "ray %d: %.4g: the light below does not come through", k, acc[0].mean);
    }
    test_note(t, "3 rays x 3 strategy pairs, worst z %.2f (limit %.2f)", worst, zlim);
    pt_scene_destroy(s);
}

const test_case test_microfacet_cases[] = {
    TEST_CASE(ggx_conductor_chi2),
    TEST_CASE(harness_rejects_vndf_with_ndf_density),
    TEST_CASE(ggx_white_furnace),
    TEST_CASE(ggx_fresnel),
    TEST_CASE(ggx_mirror_limit),
    TEST_CASE(ggx_api_errors),
    TEST_CASE(ggx_strategies_agree),
    TEST_CASE(rough_dielectric_chi2),
    TEST_CASE(harness_rejects_rough_dielectric_ndf_density),
    TEST_CASE(rough_dielectric_furnace),
    TEST_CASE(rough_dielectric_smooth_limit),
    TEST_CASE(rough_dielectric_api_errors),
    TEST_CASE(rough_dielectric_lights_below),
    TEST_END
};
