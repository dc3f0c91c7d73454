/* test_plastic.c - the rough plastic (PT_MATERIAL_ROUGH_PLASTIC, pdftrace.h section 4): a
   Lambertian base under a GGX dielectric coat, Mitsuba 3's roughplastic.

   The model is rebuilt here in double precision from its definition (docs/materials.md): the
   coat's transmittance table T(mu_k) and internal reflectance R_int by the same Gauss-Legendre
   rules over the concentric disk mapped onto the visible normals, with this file's own nodes,
   disk map, visible-normal map, Fresnel (test_util.c) and masking. Against it:
   - chi-square of the material PDF's sampling (the mixture of visible normals and the cosine
     lobe) against pt_pdf_value and the closed-form mixture density at roughness {0.01, 0.1, 0.5,
     1} x incidence {0, 45, 80, 89} degrees, on a half-vector histogram whose polar coordinate is
     the CDF of D cos on its first half (which spreads a narrow coat lobe) and sin^2 of the half
     vector's angle on its second (which spreads the base's cosine lobe); in the chi-square
     suite's Sidak family.
   - the harness rejects the same sampler paired with a density that uses Mitsuba's specular
     weight without the coat's transmittance (the lobe share at the wrong angle).
   - furnace: a convex sphere under a uniform background shows the directional albedo A(theta) =
     spec(theta) + rho / (1 - R_int) T(cos) 2 \int T mu dmu / ior^2, integrated here (spec by a
     midpoint rule on the half-vector square), linear and nonlinear, MIS and MATERIAL; A <= 1 for
     a white base. z-tests at alpha = 0.01, Sidak over the comparisons of that test.
   - API errors, the microfacet feature bit (the scene statement's errors: validation/ptv.c). */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef TU_PI
#define TU_PI 3.14159265358979323846
#endif
#define PL_RES 64

/* ---- the model in double, local frame (z = normal) ---- */
typedef struct pl_model {
    double a, a2, ior, w; /* GGX alpha (the float the material uses), coat index, specular weight */
    double t[PL_RES], rint;
    int nonlinear;
} pl_model;

static double pl_d(dv3 m, double a2)
{
    double s = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
    return m.z > 0.0 ? a2 / (TU_PI * s * s) : 0.0;
}
static double pl_g1(dv3 v, double a2)
{
    double z = fabs(v.z), xy = v.x * v.x + v.y * v.y;
    if (z <= 0.0) return 0.0;
    return 2.0 / (1.0 + sqrt(1.0 + a2 * xy / (z * z)));
}
/* Gauss-Legendre on [0, 1]: the roots of P_n by Newton from Chebyshev guesses */
static void pl_gl(int n, double *x, double *w)
{
    int i, j, it;
    for (i = 0; i < n; i++) {
        double z = cos(TU_PI * (i + 0.75) / (n + 0.5)), d = 1.0;
        for (it = 0; it < 100; it++) {
            double p = 1.0, q = 0.0, step;
            for (j = 1; j <= n; j++) {
                double r = q;
                q = p;
                p = ((2.0 * j - 1.0) * z * q - (j - 1.0) * r) / j;
            }
            d = n * (z * p - q) / (z * z - 1.0);
            step = p / d;
            z -= step;
            if (fabs(step) < 1e-16) break;
        }
        x[i] = 0.5 * (1.0 - z);
        w[i] = 1.0 / ((1.0 - z * z) * d * d);
    }
}
/* Shirley & Chiu's concentric map of the square onto the disk */
static void pl_disk(double u1, double u2, double *px, double *py)
{
    double sx = 2.0 * u1 - 1.0, sy = 2.0 * u2 - 1.0, r, th;
    if (sx == 0.0 && sy == 0.0) { *px = *py = 0.0; return; }
    if (fabs(sx) > fabs(sy)) { r = sx; th = TU_PI / 4.0 * sy / sx; }
    else { r = sy; th = TU_PI / 2.0 - TU_PI / 4.0 * sx / sy; }
    *px = r * cos(th);
    *py = r * sin(th);
}
/* the visible normal of disk point (p1, p2) for v in the xz-plane (Heitz 2018): in the stretched
   frame, p1 along y, p2 toward v's horizontal side, warped by the visible half of the disk */
static dv3 pl_vn(dv3 v, double a, double p1, double p2)
{
    dv3 vh = dnorm(dv(a * v.x, a * v.y, v.z)), t1 = dv(0, 1, 0), t2, nh;
    double s = 0.5 * (1.0 + vh.z);
    t2 = dcross(vh, t1);
    p2 = (1.0 - s) * sqrt(fmax(0.0, 1.0 - p1 * p1)) + s * p2;
    nh = dadd(dadd(dscale(t1, p1), dscale(t2, p2)), dscale(vh, sqrt(fmax(0.0, 1.0 - p1 * p1 - p2 * p2))));
    return dnorm(dv(a * nh.x, a * nh.y, fmax(0.0, nh.z)));
}
static double pl_mu(int k) { return fmax(1e-6, (double)(float)((float)k / (float)(PL_RES - 1))); }
/* one mean over the n x n rule: outside (1 - F) G1 of the refracted direction, inside F G1 of the reflected */
static double pl_mean(const pl_model *m, double mu, int inside, int n, const double *x, const double *w)
{
    dv3 v = dv(sqrt(fmax(0.0, 1.0 - mu * mu)), 0.0, mu);
    double sum = 0.0, ei = inside ? m->ior : 1.0, et = inside ? 1.0 : m->ior, eta = ei / et;
    int i, j;
    for (i = 0; i < n; i++)
        for (j = 0; j < n; j++) {
            double p1, p2, c, F;
            dv3 mm;
            pl_disk(x[i], x[j], &p1, &p2);
            mm = pl_vn(v, m->a, p1, p2);
            c = fmin(1.0, fmax(0.0, ddot(v, mm)));
            F = tu_fresnel_dielectric(c, ei, et);
            if (inside) {
                dv3 r = dsub(dscale(mm, 2.0 * c), v);
                if (r.z > 0.0) sum += w[i] * w[j] * F * pl_g1(r, m->a2);
            } else if (F < 1.0) {
                double ct = sqrt(fmax(0.0, 1.0 - eta * eta * (1.0 - c * c)));
                dv3 tt = dadd(dscale(v, -eta), dscale(mm, eta * c - ct));
                if (tt.z < 0.0) sum += w[i] * w[j] * (1.0 - F) * pl_g1(tt, m->a2);
            }
        }
    return sum;
}
static void pl_model_init(pl_model *m, double alpha, double ior, pt_color albedo, int nonlinear)
{
    double x[128], w[128], r = 0.0;
    float fa = (float)fmax(alpha, 1e-3);
    int k;
    m->a = fa;
    m->a2 = (double)(fa * fa);
    m->ior = ior;
    m->nonlinear = nonlinear;
    m->w = 1.0 / (1.0 + ((double)albedo.x + albedo.y + albedo.z) / 3.0);
    pl_gl(32, x, w);
    for (k = 0; k < PL_RES; k++) m->t[k] = pl_mean(m, pl_mu(k), 0, 32, x, w);
    pl_gl(128, x, w);
    for (k = 0; k < PL_RES; k++) r += pl_mu(k) * pl_mean(m, pl_mu(k), 1, 128, x, w);
    m->rint = 2.0 * r / PL_RES;
}
static double pl_t(const pl_model *m, double mu)
{
    double x = fmin(1.0, fmax(0.0, mu)) * (PL_RES - 1);
    int i = (int)x;
    if (i > PL_RES - 2) i = PL_RES - 2;
    return m->t[i] + (x - i) * (m->t[i + 1] - m->t[i]);
}
static double pl_share(const pl_model *m, double mu_o, int wrong)
{
    double t = pl_t(m, mu_o), sp = (1.0 - t) * m->w, df = t * (1.0 - m->w);
    return wrong ? m->w : sp / (sp + df);
}
static double pl_density(const pl_model *m, dv3 o, dv3 i, int wrong)
{
    double ps;
    dv3 h;
    if (o.z <= 0.0 || i.z <= 0.0) return 0.0;
    ps = pl_share(m, o.z, wrong);
    h = dnorm(dadd(o, i));
    return ps * pl_g1(o, m->a2) * pl_d(h, m->a2) / (4.0 * o.z) + (1.0 - ps) * i.z / TU_PI;
}
static double pl_spec_cos(const pl_model *m, dv3 o, dv3 i)
{
    dv3 h;
    if (o.z <= 0.0 || i.z <= 0.0) return 0.0;
    h = dnorm(dadd(o, i));
    return tu_fresnel_dielectric(fmin(1.0, ddot(o, h)), 1.0, m->ior) * pl_d(h, m->a2) * pl_g1(o, m->a2) * pl_g1(i, m->a2) /
           (4.0 * o.z);
}

/* ---- the check's frame and its half-vector domain ---- */
typedef struct pl_ctx {
    dv3 n, e1, e2, wo, o;
    const pl_model *m;
    int wrong;
} pl_ctx;
static dv3 pl_local(const pl_ctx *c, dv3 w) { return dv(ddot(w, c->e1), ddot(w, c->e2), ddot(w, c->n)); }
static dv3 pl_world(const pl_ctx *c, dv3 l) { return dadd(dadd(dscale(c->e1, l.x), dscale(c->e2, l.y)), dscale(c->n, l.z)); }
/* The polar coordinate of a half vector at angle th, in two closed-form pieces: up to th*, where
   the CDF of D cos reaches PL_SPLIT, x = CDF / PL_SPLIT / 2 (spreads the coat's lobe); beyond,
   x = 1/2 + (sin^2 th - sin^2 th*) / (1 - sin^2 th*) / 2 (spreads the base's cosine lobe). */
#define PL_SPLIT 0.9
static double pl_s2star(const pl_ctx *c) { double t2 = c->m->a2 * PL_SPLIT / (1.0 - PL_SPLIT); return t2 / (1.0 + t2); }
static double pl_x_of(const pl_ctx *c, double th)
{
    double s = sin(th), co = cos(th), s2 = s * s, ss = pl_s2star(c);
    if (s2 <= ss) return 0.5 * (s2 / (s2 + c->m->a2 * co * co)) / PL_SPLIT;
    return 0.5 + 0.5 * (s2 - ss) / (1.0 - ss);
}
static int pl_to_unit(const void *ctx, dv3 w, double *x, double *y)
{
    const pl_ctx *c = (const pl_ctx *)ctx;
    dv3 i = pl_local(c, w), h;
    double phi;
    if (i.z <= -1e-6) return 0;
    h = dnorm(dadd(c->o, i));
    if (h.z <= 0.0) return 0;
    *x = fmin(pl_x_of(c, atan2(sqrt(h.x * h.x + h.y * h.y), h.z)), 1.0 - 1e-12);
    phi = atan2(h.y, h.x);
    if (phi < 0.0) phi += 2.0 * TU_PI;
    *y = fmin(phi / (2.0 * TU_PI), 1.0 - 1e-12);
    return 1;
}
static dv3 pl_from_unit(const void *ctx, double x, double y, double *jac)
{
    const pl_ctx *c = (const pl_ctx *)ctx;
    double ss = pl_s2star(c), a2 = c->m->a2, s2, s, co, oh, dh, phi = 2.0 * TU_PI * y;
    dv3 h, i;
    if (x < 0.5) { /* tan^2 = a^2 X / (1 - X), X = 2 x PL_SPLIT */
        double X = 2.0 * x * PL_SPLIT, t2 = a2 * X / (1.0 - X), q;
        s2 = t2 / (1.0 + t2);
        co = sqrt(1.0 / (1.0 + t2));
        q = s2 + a2 * co * co;
        /* d omega_h = sin dth dphi; dx/dth = sin cos a^2 / (q^2 PL_SPLIT) */
        dh = 2.0 * TU_PI * PL_SPLIT * q * q / (co * a2);
    } else {
        s2 = ss + (2.0 * x - 1.0) * (1.0 - ss);
        co = sqrt(fmax(0.0, 1.0 - s2));
        dh = 2.0 * TU_PI * (1.0 - ss) / co; /* dx/dth = sin cos / (1 - sin^2 th*) */
    }
    s = sqrt(s2);
    h = dv(s * cos(phi), s * sin(phi), co);
    oh = ddot(c->o, h);
    i = dsub(dscale(h, 2.0 * oh), c->o);
    *jac = 4.0 * fabs(oh) * dh; /* d omega_i = 4 |wo.h| d omega_h */
    return dnorm(pl_world(c, i));
}
static double pl_propose(const void *ctx, pt_rng *r, dv3 *w)
{
    double jac;
    *w = pl_from_unit(ctx, tu_rand(r), tu_rand(r), &jac);
    return jac > 0.0 ? 1.0 / jac : 1e300;
}
static double pl_ref(const void *ctx, dv3 w, int *near)
{
    const pl_ctx *c = (const pl_ctx *)ctx;
    dv3 i = pl_local(c, w), s = dadd(c->o, i);
    /* float rounding of the half vector (pt__ggx_d): as test_microfacet.c's ref_ggx */
    *near = i.z < 1e-4 || 4.8e-7 / (dlen(s) * c->m->a) > 2e-4;
    return pl_density(c->m, c->o, i, c->wrong);
}
static void pl_setup(pl_ctx *c, const pl_model *m, dv3 n, double theta_deg)
{
    double th = theta_deg * TU_PI / 180.0;
    c->n = dnorm(dv_from(dv_to(n)));
    tu_frame(c->n, &c->e1, &c->e2);
    c->wo = dnorm(dv_from(dv_to(dnorm(dadd(dscale(c->n, cos(th)), dscale(c->e1, sin(th)))))));
    c->o = pl_local(c, c->wo);
    c->m = m;
    c->wrong = 0;
}
static void pl_check_init(tu_pdf_check *c, tu_domain *dom, pl_ctx *ctx, const pt_pdf *p, const char *label)
{
    dom->to_unit = pl_to_unit;
    dom->from_unit = pl_from_unit;
    dom->propose = pl_propose;
    dom->ctx = ctx;
    memset(c, 0, sizeof *c);
    c->label = label;
    c->pdf = p;
    c->axis = ctx->n;
    c->omc = 1.0 + 1e-6;
    c->domain = dom;
    c->expected_mass = -1.0; /* below 1: coat directions reflected below the surface fail */
    c->support = -1.0;
    c->ref = pl_ref;
    c->ref_ctx = ctx;
    c->n_samples = 40000;
    c->n_mass = 10000;
    c->ns = 32;
    c->nphi = 24;
    c->alpha = tu_suite_alpha();
}

static const double pl_rough[4] = { 0.01, 0.1, 0.5, 1.0 }, pl_angle[4] = { 0.0, 45.0, 80.0, 89.0 };

static void plastic_chi2(test_ctx *t)
{
    static char labels[16][96];
    static pl_model models[4];
    pt_scene *s = pt_scene_create();
    pt_color rho = pt_v3(0.8f, 0.3f, 0.1f);
    int mats[4], ri, ai, rc = 0;
    double min_p = 2.0;
    if (!CHECK(t, s != NULL, "pt_scene_create failed")) return;
    for (ri = 0; ri < 4; ri++) {
        mats[ri] = pt_scene_add_rough_plastic(s, rho, (float)pl_rough[ri], 1.5f);
        rc |= mats[ri] < 0;
        pl_model_init(&models[ri], (float)pl_rough[ri], 1.5, rho, 0);
    }
    rc |= pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, mats[0]) < 0;
    rc |= pt_scene_commit(s) != PT_OK;
    if (!CHECK(t, rc == 0, "scene setup failed: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    for (ri = 0; ri < 4; ri++) {
        CHECK(t, pt_material_is_delta(s, mats[ri]) == 0, "roughness %g reported delta", pl_rough[ri]);
        for (ai = 0; ai < 4; ai++) {
            pl_ctx ctx;
            tu_domain dom;
            tu_pdf_check c;
            tu_pdf_result r;
            pt_pdf p;
            char *label = labels[ri * 4 + ai];
            pl_setup(&ctx, &models[ri], dnorm(dv(0.2, 1.0, -0.3)), pl_angle[ai]);
            p = pt_pdf_material(s, mats[ri], dv_to(ctx.n), dv_to(ctx.wo));
            snprintf(label, 96, "rough plastic alpha %.2f, %.0f degrees", pl_rough[ri], pl_angle[ai]);
            CHECK(t, pt_pdf_validate(&p) == PT_OK, "%s: pt_pdf_validate failed", label);
            pl_check_init(&c, &dom, &ctx, &p, label);
            c.seed = 2500 + (uint64_t)(ri * 4 + ai);
            TU_CHECK_PDF(t, &c, &r);
            if (r.chi2_p < min_p) min_p = r.chi2_p;
        }
    }
    test_note(t, "16 cases, %d draws each, smallest chi-square p %.3g (alpha per comparison %.2g)", 40000, min_p,
              tu_suite_alpha());
    pt_scene_destroy(s);
}

/* WRONG: the mixture's draws reported with Mitsuba's weight as the specular share, without the
   coat's transmittance at wo (sample and value agree, so only the harness can see it). */
typedef struct pl_wrong { pt_pdf inner; pl_ctx *c; } pl_wrong;
static float pl_wrong_density(const pl_ctx *c, pt_vec3 w) { return (float)pl_density(c->m, c->o, pl_local(c, dv_from(w)), 1); }
static int pl_wrong_sample(void *user, pt_rng *rng, pt_vec3 *dir, float *pdf)
{
    pl_wrong *u = (pl_wrong *)user;
    if (!pt_pdf_sample(&u->inner, rng, dir, pdf)) return 0;
    *pdf = pl_wrong_density(u->c, *dir);
    if (!(*pdf > 0.0f)) { *dir = pt_v3(0, 0, 0); *pdf = 0.0f; return 0; }
    return 1;
}
static float pl_wrong_value(void *user, pt_vec3 dir) { return pl_wrong_density(((pl_wrong *)user)->c, dir); }

static void harness_rejects_plastic_fixed_share(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pl_model m;
    pl_ctx ctx;
    tu_domain dom;
    tu_pdf_check c;
    tu_pdf_result r;
    pl_wrong u;
    pt_pdf p;
    char reason[768];
    int mat, failures;
    if (!CHECK(t, s != NULL, "pt_scene_create failed")) return;
    mat = pt_scene_add_rough_plastic(s, pt_v3(0.5f, 0.5f, 0.5f), 0.3f, 1.5f);
    if (!CHECK(t, mat >= 0 && pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, mat) >= 0 && pt_scene_commit(s) == PT_OK, "scene: %s",
               pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
    pl_model_init(&m, 0.3, 1.5, pt_v3(0.5f, 0.5f, 0.5f), 0);
    pl_setup(&ctx, &m, dv(0, 0, 1), 30.0);
    ctx.wrong = 1;
    u.inner = pt_pdf_material(s, mat, dv_to(ctx.n), dv_to(ctx.wo));
    u.c = &ctx;
    p = pt_pdf_callback(&u, pl_wrong_sample, pl_wrong_value);
    pl_check_init(&c, &dom, &ctx, &p, "WRONG: rough plastic draws, fixed specular share");
    c.seed = 2590;
    failures = tu_check_pdf_rejects(&c, &r, reason, sizeof reason);
    CHECK(t, failures > 0, "the fixed-share density was not rejected (chi2 p = %.3g)", r.chi2_p);
    CHECK(t, r.chi2_p < c.alpha, "chi-square p = %.3g not below alpha %.3g", r.chi2_p, c.alpha);
    test_note(t, "rejected by %d check(s); chi2 %.0f, %d dof, p = %.3g; first: %.120s", failures, r.chi2, r.dof, r.chi2_p,
              reason);
    pt_scene_destroy(s);
}

/* The coat's specular albedo \int f_spec cos: the midpoint rule on the half-vector square (x the
   CDF of D cos, substituted x = 1 - (1 - v)^4 so the integrand's growth toward grazing half
   vectors vanishes), as test_microfacet.c's albedo_halfvector. */
static double pl_spec_albedo(const pl_model *m, dv3 o, int n)
{
    double sum = 0.0;
    int a, b;
    for (a = 0; a < n; a++) {
        double v = (a + 0.5) / n, x = 1.0 - pow(1.0 - v, 4.0), dx = 4.0 * pow(1.0 - v, 3.0);
        double tt = m->a2 * x / (1.0 - x), ct = 1.0 / sqrt(1.0 + tt), st = sqrt(tt / (1.0 + tt));
        for (b = 0; b < n; b++) {
            double phi = 2.0 * TU_PI * (b + 0.5) / n, oh, jac;
            dv3 h = dv(st * cos(phi), st * sin(phi), ct), i;
            oh = ddot(o, h);
            i = dsub(dscale(h, 2.0 * oh), o);
            jac = 4.0 * fabs(oh) * TU_PI * ct * ct * ct * m->a2 / ((1.0 - x) * (1.0 - x));
            sum += pl_spec_cos(m, o, i) * jac * dx;
        }
    }
    return sum / ((double)n * n);
}
/* 2 \int_0^1 T(mu) mu dmu of the piecewise-linear table, exactly (Simpson on each segment) */
static double pl_t_moment(const pl_model *m)
{
    double sum = 0.0;
    int k;
    for (k = 0; k < PL_RES - 1; k++) {
        double a = (double)k / (PL_RES - 1), b = (double)(k + 1) / (PL_RES - 1), c = 0.5 * (a + b);
        sum += (b - a) / 6.0 * (pl_t(m, a) * a + 4.0 * pl_t(m, c) * c + pl_t(m, b) * b);
    }
    return 2.0 * sum;
}
static double pl_albedo(const pl_model *m, double theta, double rho, double spec, double moment)
{
    double mu = cos(theta), base = m->nonlinear ? rho / (1.0 - rho * m->rint) : rho / (1.0 - m->rint);
    return spec + base * pl_t(m, mu) * moment / (m->ior * m->ior);
}

static void plastic_furnace(test_ctx *t)
{
    /* rays along -z at x = sin(theta) meet the unit sphere at angle theta; the sphere is convex, so
       the pixel is A(theta) x 1. Base (1, 0.5, 0): white, grey, and the coat alone. */
    const int n_paths = 16000, comparisons = 4 * 4 * 3;
    const pt_color rho = pt_v3(1.0f, 0.5f, 0.0f);
    double zlim = tu_z_two_sided(1.0 - pow(0.99, 1.0 / comparisons)), worst = 0.0, amax = 0.0;
    int ri, ai;
    for (ri = 0; ri < 4; ri++) {
        pt_scene *s = pt_scene_create();
        pt_material_desc md;
        pl_model m;
        double moment;
        int mat, ok;
        if (!CHECK(t, s != NULL, "scene")) return;
        memset(&md, 0, sizeof md);
        md.type = PT_MATERIAL_ROUGH_PLASTIC;
        md.albedo = rho;
        md.roughness = (float)pl_rough[ri];
        md.ior = ri == 2 ? 2.0f : 1.5f;
        md.nonlinear = ri & 1;
        mat = pt_scene_add_material(s, &md);
        ok = mat >= 0 && pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, mat) >= 0 && pt_scene_commit(s) == PT_OK;
        if (!CHECK(t, ok, "scene: %s", pt_scene_error_message(s))) { pt_scene_destroy(s); return; }
        pl_model_init(&m, md.roughness, md.ior, rho, md.nonlinear);
        moment = pl_t_moment(&m);
        for (ai = 0; ai < 4; ai++) {
            double th = pl_angle[ai] * TU_PI / 180.0, spec, want[3];
            pt_render_desc d = tu_base_desc(1, 1, 1, 0);
            pt_path_stats st;
            pt_rng rng;
            pt_ray ray;
            tu_acc acc[3];
            int i, ch;
            spec = pl_spec_albedo(&m, dv(sin(th), 0.0, cos(th)), 300);
            for (ch = 0; ch < 3; ch++) want[ch] = pl_albedo(&m, th, (&rho.x)[ch], spec, moment);
            amax = fmax(amax, want[0]);
            CHECK(t, want[0] <= 1.0, "alpha %g, %g degrees: a white base's albedo %.6f above 1", pl_rough[ri], pl_angle[ai],
                  want[0]);
            memset(&st, 0, sizeof st);
            memset(acc, 0, sizeof acc);
            d.background = pt_v3(1, 1, 1);
            d.strategy = (ai & 1) ? PT_STRATEGY_MATERIAL : PT_STRATEGY_MIS;
            pt_rng_seed(&rng, 2600 + (uint64_t)(ri * 10 + ai), 0);
            ray.origin = pt_v3((float)sin(th), 0.0f, 10.0f);
            ray.dir = pt_v3(0, 0, -1);
            for (i = 0; i < n_paths; i++) {
                pt_color L = pt_trace_path(s, &d, ray, &rng, &st);
                tu_acc_add(&acc[0], L.x);
                tu_acc_add(&acc[1], L.y);
                tu_acc_add(&acc[2], L.z);
            }
            CHECK(t, st.nonfinite_samples == 0, "alpha %g, %g degrees: %llu non-finite samples", pl_rough[ri], pl_angle[ai],
                  (unsigned long long)st.nonfinite_samples);
            for (ch = 0; ch < 3; ch++) {
                /* the ray's rounded hit angle and the quadrature: a relative floor of 1e-3 */
                double z = tu_z_floor(acc[ch].mean, want[ch], tu_acc_se(&acc[ch]), 1e-3 * want[ch] + 1e-6);
                worst = fmax(worst, z);
                CHECK(t, z <= zlim, "alpha %g, %g degrees, %s, channel %d: A %.5f +- %.2g, integrated %.5f (z %.2f > %.2f)",
                      pl_rough[ri], pl_angle[ai], (ai & 1) ? "MATERIAL" : "MIS", ch, acc[ch].mean, tu_acc_se(&acc[ch]),
                      want[ch], z, zlim);
            }
        }
        pt_scene_destroy(s);
    }
    test_note(t, "%d comparisons, worst z %.2f (limit %.2f); largest white-base albedo %.4f", comparisons, worst, zlim, amax);
}

static void plastic_api_errors(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_material_desc d;
    pt_scene_info info;
    int rc, chk;
    if (!CHECK(t, s != NULL, "scene")) return;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_ROUGH_PLASTIC;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc >= 0 && pt_material_is_delta(s, rc) == 0, "zero-initialised rough plastic: %d (want a non-delta material)", rc);
    d.roughness = -0.1f;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "roughness"), "roughness -0.1: %d", rc);
    d.roughness = NAN;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "roughness"), "roughness NaN: %d", rc);
    d.roughness = 0.2f;
    d.ior = 1.0f;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "ior"), "ior 1: %d '%s'", rc,
          pt_scene_error_message(s));
    d.ior = 0.5f;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "ior"), "ior 0.5: %d", rc);
    d.ior = 1.5f;
    d.albedo = pt_v3(0.5f, 1.2f, 0.5f);
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "albedo"), "albedo 1.2: %d '%s'", rc,
          pt_scene_error_message(s));
    chk = pt_scene_add_checker(s, pt_v3(0.2f, 0.2f, 0.2f), pt_v3(1.5f, 0.2f, 0.2f), 1.0f);
    d.albedo = pt_v3(0.5f, 0.5f, 0.5f);
    d.albedo_texture = chk;
    rc = pt_scene_add_material(s, &d);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(pt_scene_error_message(s), "albedo"), "checker with 1.5: %d", rc);
    d.albedo_texture = 0;
    rc = pt_scene_add_rough_plastic(s, pt_v3(0.5f, 0.5f, 0.5f), 0.0f, 0.0f);
    CHECK(t, rc >= 0, "alpha 0, ior 0 (1.5) refused: %s", pt_scene_error_message(s));
    CHECK(t, pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, rc) >= 0 && pt_scene_commit(s) == PT_OK, "commit");
    pt_scene_get_info(s, &info);
    CHECK(t, (info.features & PT_FEATURE_MICROFACET) != 0, "PT_FEATURE_MICROFACET not set by a rough plastic");
    pt_scene_destroy(s);
}

const test_case test_plastic_cases[] = {
    TEST_CASE(plastic_chi2),
    TEST_CASE(harness_rejects_plastic_fixed_share),
    TEST_CASE(plastic_furnace),
    TEST_CASE(plastic_api_errors),
    TEST_END
};
