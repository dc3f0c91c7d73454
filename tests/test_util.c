#define _POSIX_C_SOURCE 200809L /* mkdtemp, rmdir, unlink */
/* test_util.c - statistics, closed forms and the PDF checker shared by the tests (see test_util.h). */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

int tu_verbose(void)
{
    const char *v = getenv("PT_TEST_VERBOSE");
    return v != NULL && v[0] != '\0' && v[0] != '0';
}

/* ------------------------------------------------------------------------------------------ */
/* random numbers                                                                              */

double tu_rand(pt_rng *r)
{
    uint64_t hi = pt_rng_u32(r) >> 5, lo = pt_rng_u32(r) >> 6; /* 27 + 26 = 53 bits */
    return ((double)hi * 67108864.0 + (double)lo) * (1.0 / 9007199254740992.0);
}

dv3 tu_rand_dir(pt_rng *r)
{
    /* Archimedes' hat-box theorem: z uniform in [-1, 1], phi uniform. */
    double z = 1.0 - 2.0 * tu_rand(r);
    double phi = 2.0 * TU_PI * tu_rand(r);
    double s = sqrt(fmax(0.0, 1.0 - z * z));
    return dv(s * cos(phi), s * sin(phi), z);
}

void tu_frame(dv3 axis, dv3 *e1, dv3 *e2)
{
    dv3 a = dnorm(axis);
    dv3 helper = fabs(a.x) < 0.6 ? dv(1, 0, 0) : dv(0, 1, 0);
    *e1 = dnorm(dcross(helper, a));
    *e2 = dcross(a, *e1); /* e1 x e2 = a */
}

dv3 tu_sample_cone(pt_rng *r, dv3 axis, double omc)
{
    dv3 e1, e2;
    double ch = tu_rand(r) * omc;            /* 1 - cos(theta), uniform: equal-area */
    double cos_t = 1.0 - ch;
    double sin_t = sqrt(fmax(0.0, ch * (2.0 - ch)));
    double phi = 2.0 * TU_PI * tu_rand(r);
    tu_frame(axis, &e1, &e2);
    return dnorm(dadd(dadd(dscale(e1, sin_t * cos(phi)), dscale(e2, sin_t * sin(phi))), dscale(dnorm(axis), cos_t)));
}

/* ------------------------------------------------------------------------------------------ */
/* statistics                                                                                  */

double tu_sidak(double alpha, int k)
{
    if (k <= 1) return alpha;
    return 1.0 - pow(1.0 - alpha, 1.0 / (double)k);
}

double tu_z_two_sided(double alpha)
{
    /* P(|Z| > z) = erfc(z / sqrt 2); solve by bisection. */
    double lo = 0.0, hi = 40.0;
    int i;
    for (i = 0; i < 200; i++) {
        double mid = 0.5 * (lo + hi);
        if (erfc(mid / sqrt(2.0)) > alpha) lo = mid; else hi = mid;
    }
    return 0.5 * (lo + hi);
}

/* Regularised lower incomplete gamma P(a, x) by its power series (for x < a + 1). */
static double gamma_p_series(double a, double x)
{
    double term = 1.0 / a, sum = term, ap = a;
    int n;
    for (n = 0; n < 100000; n++) {
        ap += 1.0;
        term *= x / ap;
        sum += term;
        if (fabs(term) < fabs(sum) * 1e-16) break;
    }
    return sum * exp(-x + a * log(x) - lgamma(a));
}

/* Regularised upper incomplete gamma Q(a, x) by its continued fraction (modified Lentz). */
static double gamma_q_fraction(double a, double x)
{
    const double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    int i;
    for (i = 1; i < 100000; i++) {
        double an = -(double)i * ((double)i - a), del;
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1.0 / d;
        del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-16) break;
    }
    return exp(-x + a * log(x) - lgamma(a)) * h;
}

double tu_chi2_sf(double x, double dof)
{
    double a = 0.5 * dof, hx = 0.5 * x;
    if (x <= 0.0) return 1.0;
    if (hx < a + 1.0) return 1.0 - gamma_p_series(a, hx);
    return gamma_q_fraction(a, hx);
}

double tu_z_floor(double mean, double want, double se, double floor)
{
    double d = fabs(mean - want) - floor;
    if (d <= 0.0) return 0.0;
    return se > 0.0 ? d / se : INFINITY;
}

void tu_acc_add(tu_acc *a, double x)
{
    double d;
    a->n += 1.0;
    d = x - a->mean;
    a->mean += d / a->n;
    a->m2 += d * (x - a->mean);
}

double tu_acc_var(const tu_acc *a) { return a->n > 1.0 ? a->m2 / (a->n - 1.0) : 0.0; }
double tu_acc_se(const tu_acc *a) { return a->n > 1.0 ? sqrt(tu_acc_var(a) / a->n) : 0.0; }

/* ------------------------------------------------------------------------------------------ */
/* closed forms                                                                                */

double tu_solid_angle_triangle(dv3 o, dv3 a, dv3 b, dv3 c)
{
    /* tan(Omega / 2) = |r1 . (r2 x r3)| / (l1 l2 l3 + (r1.r2) l3 + (r1.r3) l2 + (r2.r3) l1) */
    dv3 r1 = dsub(a, o), r2 = dsub(b, o), r3 = dsub(c, o);
    double l1 = dlen(r1), l2 = dlen(r2), l3 = dlen(r3);
    double num = fabs(ddot(r1, dcross(r2, r3)));
    double den = l1 * l2 * l3 + ddot(r1, r2) * l3 + ddot(r1, r3) * l2 + ddot(r2, r3) * l1;
    return 2.0 * atan2(num, den);
}

double tu_lambert_polygon(dv3 x, dv3 n, const dv3 *verts, int count)
{
    double sum = 0.0;
    int i;
    for (i = 0; i < count; i++) {
        dv3 ui = dnorm(dsub(verts[i], x));
        dv3 uj = dnorm(dsub(verts[(i + 1) % count], x));
        dv3 cr = dcross(ui, uj);
        double s = dlen(cr);
        double theta = atan2(s, ddot(ui, uj));
        if (s > 0.0) sum += theta * ddot(n, dscale(cr, 1.0 / s));
    }
    return 0.5 * fabs(sum);
}

double tu_fresnel_dielectric(double cos_i, double eta_i, double eta_t)
{
    double sin_i = sqrt(fmax(0.0, 1.0 - cos_i * cos_i));
    double sin_t = eta_i / eta_t * sin_i, cos_t, rs, rp;
    if (sin_t >= 1.0) return 1.0;
    cos_t = sqrt(1.0 - sin_t * sin_t);
    rs = (eta_i * cos_i - eta_t * cos_t) / (eta_i * cos_i + eta_t * cos_t);
    rp = (eta_t * cos_i - eta_i * cos_t) / (eta_t * cos_i + eta_i * cos_t);
    return 0.5 * (rs * rs + rp * rp);
}

/* One minus the cosine of the half-angle of the cone a sphere subtends; the form
   s^2 / (1 + sqrt(1 - s^2)) stays exact for tiny s (docs/accuracy.md). */
static double sphere_omc(double s2) { return s2 / (1.0 + sqrt(fmax(0.0, 1.0 - s2))); }

double tu_light_area(const tu_light *L)
{
    switch (L->kind) {
    case TU_SPHERE: return 4.0 * TU_PI * L->radius * L->radius;
    case TU_QUAD: return dlen(dcross(L->p1, L->p2));
    default: return 0.5 * dlen(dcross(dsub(L->p1, L->p0), dsub(L->p2, L->p0)));
    }
}

/* Planar light: the ray's parameter t, and the (a, b) coordinates of the hit. */
static int planar_hit(const tu_light *L, dv3 o, dv3 w, double *t, double *margin, dv3 *N)
{
    dv3 q, e1, e2, p, rel;
    double nn, denom, a, b;
    if (L->kind == TU_QUAD) { q = L->p0; e1 = L->p1; e2 = L->p2; }
    else { q = L->p0; e1 = dsub(L->p1, L->p0); e2 = dsub(L->p2, L->p0); }
    *N = dcross(e1, e2);
    nn = ddot(*N, *N);
    denom = ddot(w, *N);
    if (denom == 0.0) return 0;
    *t = ddot(dsub(q, o), *N) / denom;
    p = dadd(o, dscale(w, *t));
    rel = dsub(p, q);
    a = ddot(dcross(rel, e2), *N) / nn;
    b = ddot(dcross(e1, rel), *N) / nn;
    if (L->kind == TU_QUAD) {
        *margin = fmin(fmin(a, 1.0 - a), fmin(b, 1.0 - b));
    } else {
        *margin = fmin(fmin(a, b), 1.0 - a - b);
    }
    return 1;
}

double tu_light_hit(const tu_light *L, dv3 o, dv3 w)
{
    if (L->kind == TU_SPHERE) {
        dv3 l = dsub(L->p0, o);
        double b = ddot(l, w), ww = ddot(w, w);
        /* Haines et al.: discriminant from the perpendicular distance */
        dv3 perp = dsub(l, dscale(w, b / ww));
        double disc = L->radius * L->radius - ddot(perp, perp), s, t0, t1;
        if (disc < 0.0) return -1.0;
        s = sqrt(disc * ww);
        t0 = (b - s) / ww;
        t1 = (b + s) / ww;
        if (t0 > 0.0) return t0;
        if (t1 > 0.0) return t1;
        return -1.0;
    } else {
        double t, margin;
        dv3 N;
        if (!planar_hit(L, o, w, &t, &margin, &N)) return -1.0;
        if (t <= 0.0 || margin < 0.0) return -1.0;
        return t;
    }
}

double tu_light_density(const tu_light *L, dv3 o, dv3 w, int *near)
{
    *near = 0;
    w = dnorm(w);
    if (L->kind == TU_SPHERE) {
        dv3 l = dsub(L->p0, o);
        double d2 = ddot(l, l), r2 = L->radius * L->radius;
        if (fabs(d2 - r2) <= 1e-5 * r2) return -1.0; /* on the surface: model-dependent */
        if (d2 > r2) {
            double omc = sphere_omc(r2 / d2);
            dv3 axis = dscale(l, 1.0 / sqrt(d2));
            dv3 diff = dsub(w, axis);
            double ch = 0.5 * ddot(diff, diff);
            /* float directions resolve angles to ~1e-7 rad; theta ~ sqrt(2 ch) */
            double theta = sqrt(2.0 * ch), theta_max = sqrt(2.0 * omc);
            if (fabs(theta - theta_max) <= 1e-6 + 1e-5 * theta_max) *near = 1;
            return ch <= omc ? 1.0 / (2.0 * TU_PI * omc) : 0.0;
        } else {
            /* inside: uniform area sampling, converted to solid angle */
            double b = ddot(l, w), c = d2 - r2, disc = b * b - c, t, cos_l;
            dv3 x, n;
            if (!L->two_sided) return 0.0;
            t = b + sqrt(fmax(0.0, disc));
            x = dadd(o, dscale(w, t));
            n = dscale(dsub(x, L->p0), 1.0 / L->radius);
            cos_l = fabs(ddot(w, n));
            if (cos_l < 1e-6) *near = 1;
            return t * t / (cos_l * 4.0 * TU_PI * r2);
        }
    } else {
        double t, margin, cos_l, area = tu_light_area(L);
        dv3 N, q = L->p0;
        if (!L->two_sided) {
            dv3 Nl = L->kind == TU_QUAD ? dcross(L->p1, L->p2) : dcross(dsub(L->p1, L->p0), dsub(L->p2, L->p0));
            if (ddot(dsub(o, q), Nl) <= 0.0) return 0.0; /* behind a one-sided light */
        }
        if (!planar_hit(L, o, w, &t, &margin, &N)) return 0.0;
        cos_l = fabs(ddot(w, N)) / dlen(N);
        {
            /* distance of the hit point to the nearest edge (conservatively), against how far a
               direction error of 1e-6 rad moves the hit point: t * 1e-6 / cos */
            double e1 = L->kind == TU_QUAD ? dlen(L->p1) : dlen(dsub(L->p1, L->p0));
            double e2 = L->kind == TU_QUAD ? dlen(L->p2) : dlen(dsub(L->p2, L->p0));
            double e3 = L->kind == TU_QUAD ? 0.0 : dlen(dsub(L->p2, L->p1));
            double dist = fabs(margin) * dlen(N) / fmax(fmax(e1, e2), e3);
            if (dist < fabs(t) * 1e-6 / fmax(cos_l, 1e-12) + 1e-7 * fmax(e1, e2) || cos_l < 1e-6) *near = 1;
        }
        if (t <= 0.0 || margin < 0.0) return 0.0;
        if (tu_planar_spherical(L, o)) return 1.0 / tu_light_solid_angle(L, o);
        return t * t / (cos_l * area);
    }
}

int tu_planar_spherical(const tu_light *L, dv3 o)
{
    dv3 c;
    double d2, size2, omega;
    if (L->kind == TU_QUAD) {
        if (fabs(ddot(L->p1, L->p2)) > 1e-5 * dlen(L->p1) * dlen(L->p2)) return 0; /* not a rectangle */
        c = dsub(dadd(dadd(L->p0, dscale(L->p1, 0.5)), dscale(L->p2, 0.5)), o);
        size2 = 0.25 * (ddot(L->p1, L->p1) + ddot(L->p2, L->p2));
    } else if (L->kind == TU_TRIANGLE) {
        dv3 e0 = dsub(L->p1, L->p0), e1 = dsub(L->p2, L->p1), e2 = dsub(L->p0, L->p2);
        c = dsub(dscale(dadd(dadd(L->p0, L->p1), L->p2), 1.0 / 3.0), o);
        size2 = 0.25 * fmax(ddot(e0, e0), fmax(ddot(e1, e1), ddot(e2, e2)));
    } else {
        return 0;
    }
    d2 = ddot(c, c);
    if (!(size2 >= TU_SPHERICAL_FROM * d2)) return 0;
    omega = tu_light_solid_angle(L, o);
    return omega >= 3e-4 && omega <= 6.22;
}

double tu_light_solid_angle(const tu_light *L, dv3 o)
{
    if (L->kind == TU_SPHERE) {
        dv3 l = dsub(L->p0, o);
        double d2 = ddot(l, l), r2 = L->radius * L->radius;
        if (fabs(d2 - r2) <= 1e-5 * r2) return L->two_sided ? 2.0 * TU_PI : -1.0;
        if (d2 > r2) return 2.0 * TU_PI * sphere_omc(r2 / d2);
        return L->two_sided ? 4.0 * TU_PI : 0.0;
    } else {
        dv3 a, b, c, d, N;
        if (L->kind == TU_QUAD) {
            a = L->p0; b = dadd(a, L->p1); c = dadd(b, L->p2); d = dadd(a, L->p2);
            N = dcross(L->p1, L->p2);
        } else {
            a = L->p0; b = L->p1; c = L->p2; d = a;
            N = dcross(dsub(b, a), dsub(c, a));
        }
        if (!L->two_sided && ddot(dsub(o, a), N) <= 0.0) return 0.0;
        if (L->kind == TU_QUAD) return tu_solid_angle_triangle(o, a, b, c) + tu_solid_angle_triangle(o, a, c, d);
        return tu_solid_angle_triangle(o, a, b, c);
    }
}

void tu_light_cone(const tu_light *L, dv3 o, dv3 *axis, double *omc)
{
    if (L->kind == TU_SPHERE) {
        dv3 l = dsub(L->p0, o);
        double d2 = ddot(l, l), r2 = L->radius * L->radius;
        if (d2 <= r2 * (1.0 + 1e-5)) { *axis = dv(0, 0, 1); *omc = 2.0; return; }
        *axis = dnorm(l);
        *omc = fmin(2.0, sphere_omc(r2 / d2) * 1.05);
    } else {
        dv3 v[4], centroid;
        int n, i;
        double m = 0.0;
        if (L->kind == TU_QUAD) {
            v[0] = L->p0; v[1] = dadd(L->p0, L->p1); v[2] = dadd(v[1], L->p2); v[3] = dadd(L->p0, L->p2);
            n = 4;
        } else {
            v[0] = L->p0; v[1] = L->p1; v[2] = L->p2;
            n = 3;
        }
        centroid = dv(0, 0, 0);
        for (i = 0; i < n; i++) centroid = dadd(centroid, dscale(v[i], 1.0 / n));
        *axis = dnorm(dsub(centroid, o));
        for (i = 0; i < n; i++) {
            dv3 diff = dsub(dnorm(dsub(v[i], o)), *axis);
            m = fmax(m, 0.5 * ddot(diff, diff));
        }
        *omc = fmin(2.0, m * 1.1 + 1e-12);
    }
}

/* ------------------------------------------------------------------------------------------ */
/* domains: equal-area maps of a set of directions to the unit square                          */

typedef struct cone_ctx { dv3 axis, e1, e2; double omc; } cone_ctx;

static int cone_to_unit(const void *ctx, dv3 w, double *x, double *y)
{
    const cone_ctx *c = (const cone_ctx *)ctx;
    dv3 diff = dsub(w, c->axis);
    double ch = 0.5 * ddot(diff, diff), phi;
    /* float directions carry ~6e-8 rad of rounding: 1 - cos(theta) ~ theta^2/2 then errs by
       ~6e-8 * sqrt(2 omc) near the rim; allow that (relative to tiny cones an absolute 1e-7 would
       accept samples far outside) */
    if (ch > c->omc * (1.0 + 1e-4) + 2e-7 * sqrt(c->omc) + 1e-12) return 0;
    *x = fmin(ch / c->omc, 1.0 - 1e-12);
    phi = atan2(ddot(w, c->e2), ddot(w, c->e1));
    if (phi < 0.0) phi += 2.0 * TU_PI;
    *y = fmin(phi / (2.0 * TU_PI), 1.0 - 1e-12);
    return 1;
}

static dv3 cone_from_unit(const void *ctx, double x, double y, double *jac)
{
    const cone_ctx *c = (const cone_ctx *)ctx;
    double ch = x * c->omc, cos_t = 1.0 - ch, sin_t = sqrt(fmax(0.0, ch * (2.0 - ch))), phi = 2.0 * TU_PI * y;
    *jac = 2.0 * TU_PI * c->omc;
    return dnorm(dadd(dadd(dscale(c->e1, sin_t * cos(phi)), dscale(c->e2, sin_t * sin(phi))), dscale(c->axis, cos_t)));
}

static double cone_propose(const void *ctx, pt_rng *r, dv3 *w)
{
    const cone_ctx *c = (const cone_ctx *)ctx;
    *w = tu_sample_cone(r, c->axis, c->omc);
    return 1.0 / (2.0 * TU_PI * c->omc);
}

/* Planar lights: (a, b) of the parallelogram q + a u + b v, or Duffy's square-to-triangle map
   p = A + x (B - A) + x y (C - B) (barycentrics beta = x (1 - y), gamma = x y). */
static dv3 planar_point(const tu_light *L, double x, double y, double *dA)
{
    if (L->kind == TU_QUAD) {
        *dA = tu_light_area(L);
        return dadd(L->p0, dadd(dscale(L->p1, x), dscale(L->p2, y)));
    }
    *dA = 2.0 * tu_light_area(L) * x;
    return dadd(L->p0, dadd(dscale(dsub(L->p1, L->p0), x), dscale(dsub(L->p2, L->p1), x * y)));
}

static int planar_to_unit(const void *ctx, dv3 w, double *x, double *y)
{
    const tu_planar_ctx *c = (const tu_planar_ctx *)ctx;
    const double eps = 1e-2; /* float directions at grazing angles move the hit point by ~1e-3 */
    dv3 q = c->L.p0, e1, e2, N, p, rel;
    double t, a, b, nn;
    if (c->L.kind == TU_QUAD) { e1 = c->L.p1; e2 = c->L.p2; }
    else { e1 = dsub(c->L.p1, q); e2 = dsub(c->L.p2, q); }
    N = dcross(e1, e2);
    nn = ddot(N, N);
    if (ddot(w, N) == 0.0) return 0;
    t = ddot(dsub(q, c->o), N) / ddot(w, N);
    if (t <= 0.0) return 0;
    p = dadd(c->o, dscale(w, t));
    rel = dsub(p, q);
    a = ddot(dcross(rel, e2), N) / nn;
    b = ddot(dcross(e1, rel), N) / nn;
    if (c->L.kind == TU_QUAD) {
        if (a < -eps || a > 1 + eps || b < -eps || b > 1 + eps) return 0;
        *x = a; *y = b;
    } else {
        double u = a + b;
        if (a < -eps || b < -eps || u > 1 + eps) return 0;
        *x = u;
        *y = u > 0.0 ? b / u : 0.0;
    }
    *x = fmin(fmax(*x, 0.0), 1.0 - 1e-12);
    *y = fmin(fmax(*y, 0.0), 1.0 - 1e-12);
    return 1;
}

static dv3 planar_from_unit(const void *ctx, double x, double y, double *jac)
{
    const tu_planar_ctx *c = (const tu_planar_ctx *)ctx;
    double dA, d2, cosl;
    dv3 p = planar_point(&c->L, x, y, &dA), v = dsub(p, c->o), N, w;
    N = c->L.kind == TU_QUAD ? dcross(c->L.p1, c->L.p2) : dcross(dsub(c->L.p1, c->L.p0), dsub(c->L.p2, c->L.p0));
    d2 = ddot(v, v);
    w = dscale(v, 1.0 / sqrt(d2));
    cosl = fabs(ddot(w, N)) / dlen(N);
    *jac = dA * cosl / d2; /* d omega = cos dA / d^2 */
    return w;
}

static double planar_propose(const void *ctx, pt_rng *r, dv3 *w)
{
    /* uniform area sampling of the light enlarged by 1.25 about its centroid */
    const tu_planar_ctx *c = (const tu_planar_ctx *)ctx;
    tu_light big = c->L;
    double x = tu_rand(r), y = tu_rand(r), dA, d2, cosl, area;
    dv3 p, v, N;
    if (big.kind == TU_QUAD) {
        dv3 centre = dadd(big.p0, dscale(dadd(big.p1, big.p2), 0.5));
        big.p1 = dscale(big.p1, 1.25);
        big.p2 = dscale(big.p2, 1.25);
        big.p0 = dsub(centre, dscale(dadd(big.p1, big.p2), 0.5));
    } else {
        dv3 centre = dscale(dadd(dadd(big.p0, big.p1), big.p2), 1.0 / 3.0);
        big.p0 = dadd(centre, dscale(dsub(big.p0, centre), 1.25));
        big.p1 = dadd(centre, dscale(dsub(big.p1, centre), 1.25));
        big.p2 = dadd(centre, dscale(dsub(big.p2, centre), 1.25));
    }
    if (big.kind == TU_TRIANGLE && x + y > 1.0) { x = 1.0 - x; y = 1.0 - y; }
    area = tu_light_area(&big);
    if (big.kind == TU_QUAD) p = dadd(big.p0, dadd(dscale(big.p1, x), dscale(big.p2, y)));
    else p = dadd(big.p0, dadd(dscale(dsub(big.p1, big.p0), x), dscale(dsub(big.p2, big.p0), y)));
    (void)dA;
    v = dsub(p, c->o);
    d2 = ddot(v, v);
    *w = dscale(v, 1.0 / sqrt(d2));
    N = big.kind == TU_QUAD ? dcross(big.p1, big.p2) : dcross(dsub(big.p1, big.p0), dsub(big.p2, big.p0));
    cosl = fabs(ddot(*w, N)) / dlen(N);
    return d2 / (cosl * area);
}

void tu_planar_domain(tu_domain *d, tu_planar_ctx *ctx, const tu_light *L, dv3 o)
{
    ctx->L = *L;
    ctx->o = o;
    d->to_unit = planar_to_unit;
    d->from_unit = planar_from_unit;
    d->propose = planar_propose;
    d->ctx = ctx;
}

/* ------------------------------------------------------------------------------------------ */
/* the PDF checker                                                                             */

/* Adaptive integration of pt_pdf_value * jacobian over a rectangle of the unit square. Two nested
   midpoint rules (2x2 and 4x4) estimate the error; a rectangle is split in four while they
   disagree by more than 2e-3 relative (plus a small absolute floor, up to depth 5), while `force`
   asks for it (cells beside the support boundary), or -- up to depth mixed_depth -- while it
   contains a discontinuity: a closed 5x5 grid of points (corners and edges included, so that a
   boundary between the outermost midpoints and the edge is seen) holds both zero and non-zero
   values, or values that differ by more than half their mean (the edge of a light's support inside
   a mixture) -- and by more than the absolute floor, so that a smooth lobe's tail, steep in
   relative terms but carrying no mass, is not refined. The support boundary is where the midpoint rule errs most -- systematically so where
   it runs along a grid line (a quad's edge in a plane through the cone axis is a line of constant
   phi), and with 10^6 samples a boundary cell needs its expected count to well under 1 %. */
typedef struct grid_ctx {
    const pt_pdf *pdf;
    const tu_domain *dom;
    double floor;
    long evals, budget;
    int mixed_depth;
} grid_ctx;

static double grid_value(grid_ctx *g, double x, double y)
{
    double jac;
    dv3 w = g->dom->from_unit(g->dom->ctx, x, y, &jac);
    float v = pt_pdf_value(g->pdf, dv_to(w));
    g->evals++;
    return isfinite(v) && v > 0.0f ? (double)v * jac : 0.0;
}

static double rect_integral(grid_ctx *g, double x0, double x1, double y0, double y1, int depth, int force)
{
    double i4 = 0.0, i16 = 0.0, area = (x1 - x0) * (y1 - y0), lo = INFINITY, hi = 0.0, sum = 0.0;
    int a, b, zeros = 0, n = 0, jump;
    for (a = 0; a < 5; a++)
        for (b = 0; b < 5; b++) {
            double v = grid_value(g, x0 + a / 4.0 * (x1 - x0), y0 + b / 4.0 * (y1 - y0));
            if ((a == 1 || a == 3) && (b == 1 || b == 3)) i4 += v; /* the 2x2 midpoints */
            zeros += v == 0.0;
            lo = fmin(lo, v);
            hi = fmax(hi, v);
            sum += v;
            n++;
        }
    for (a = 0; a < 4; a++)
        for (b = 0; b < 4; b++) {
            double v = grid_value(g, x0 + (a + 0.5) / 4 * (x1 - x0), y0 + (b + 0.5) / 4 * (y1 - y0));
            i16 += v;
            zeros += v == 0.0;
            lo = fmin(lo, v);
            hi = fmax(hi, v);
            sum += v;
            n++;
        }
    i4 *= area / 4.0;
    i16 *= area / 16.0;
    /* a jump that can move the cell's integral by more than the absolute floor */
    jump = hi - lo > g->floor && ((zeros > 0 && zeros < n) || hi - lo > 0.5 * sum / n);
    /* a budget keeps a pathological density (spikes everywhere) from taking minutes */
    if (g->evals < g->budget &&
        (force > 0 || (jump && depth < g->mixed_depth) || (depth < 5 && fabs(i16 - i4) > 2e-3 * i16 + g->floor * area))) {
        double xm = 0.5 * (x0 + x1), ym = 0.5 * (y0 + y1);
        return rect_integral(g, x0, xm, y0, ym, depth + 1, force - 1) + rect_integral(g, xm, x1, y0, ym, depth + 1, force - 1) +
               rect_integral(g, x0, xm, ym, y1, depth + 1, force - 1) + rect_integral(g, xm, x1, ym, y1, depth + 1, force - 1);
    }
    return i16;
}

/* ---- the chi-square suite's bookkeeping ---- */

#define TU_MAX_ROWS 512
static tu_chi2_row rows_[TU_MAX_ROWS];
static int row_count_ = 0, rows_dropped_ = 0;
static long suite_comparisons_ = 0;

double tu_suite_alpha(void) { return tu_sidak(TU_SUITE_ALPHA, TU_SUITE_COMPARISONS); }
void tu_suite_count(int comparisons) { suite_comparisons_ += comparisons; }
long tu_suite_comparisons(void) { return suite_comparisons_; }
int tu_chi2_row_count(void) { return row_count_; }
const tu_chi2_row *tu_chi2_row_at(int i) { return i >= 0 && i < row_count_ ? &rows_[i] : NULL; }

static void record_row(const tu_chi2_row *r)
{
    if (row_count_ < TU_MAX_ROWS) rows_[row_count_++] = *r;
    else rows_dropped_++;
}

void tu_chi2_print_table(void)
{
    int i;
    printf("     %-64s %8s %5s %10s %9s %9s %9s %7s  %s\n", "chi-square case", "N", "dof", "chi2", "p", "p marg.", "integral",
           "z 1/p", "result");
    for (i = 0; i < row_count_; i++) {
        const tu_chi2_row *r = &rows_[i];
        char z[16];
        if (r->has_inv_z) snprintf(z, sizeof z, "%7.2f", r->inv_z);
        else snprintf(z, sizeof z, "%7s", "-");
        printf("     %-64.64s %8ld %5d %10.1f %9.3g %9.3g %9.6f %s  %s\n", r->label, r->n, r->dof, r->chi2, r->p, r->p_marginal,
               r->integral, z,
               r->expect_reject ? (r->passed ? "NOT REJECTED (harness too weak)" : "rejected, as it must be")
                                : (r->passed ? "pass" : "FAIL"));
    }
    if (rows_dropped_) printf("     (%d further rows not stored)\n", rows_dropped_);
}

int tu_check_pdf_(test_ctx *t, const tu_pdf_check *c, tu_pdf_result *res, const char *file, int line)
{
    const double cone_sa = 2.0 * TU_PI * c->omc;
    const double z = tu_z_two_sided(c->alpha);
    /* float densities carry absolute rounding error: allow 1e-6 of the density of a uniform cone */
    const double abs_tol = 1e-6 / cone_sa;
    const int ns = c->ns, nphi = c->nphi;
    long *hist = NULL;
    long i, succ = 0, fails = 0, bad_rc = 0, bad_fail_out = 0, nonfinite = 0, nonpositive = 0, nonunit = 0;
    long mismatch = 0, ref_mismatch = 0, outside = 0, binned = 0, value_bad = 0, value_ref_mismatch = 0;
    char example[200] = "", ref_example[200] = "", value_example[200] = "", out_example[200] = "";
    double worst_rel = 0.0;
    tu_acc inv, mass;
    cone_ctx cone;
    tu_domain cone_dom;
    const tu_domain *dom = c->domain;
    pt_rng rng, rng2;
    int ok = 1, comparisons = 0;
    double F;
    tu_chi2_row row;

    memset(&row, 0, sizeof row);
    snprintf(row.label, sizeof row.label, "%s", c->label);
    row.n = c->n_samples;
    row.dof = -1;
    row.p = 2.0;
    row.p_marginal = 2.0;
    row.expect_reject = c->expect_reject;
    memset(&inv, 0, sizeof inv);
    memset(&mass, 0, sizeof mass);
    cone.axis = dnorm(c->axis);
    cone.omc = c->omc;
    tu_frame(cone.axis, &cone.e1, &cone.e2);
    cone_dom.to_unit = cone_to_unit;
    cone_dom.from_unit = cone_from_unit;
    cone_dom.propose = cone_propose;
    cone_dom.ctx = &cone;
    if (!dom) dom = &cone_dom;
    if (res) {
        memset(res, 0, sizeof *res);
        res->chi2_p = 2.0;
        res->marginal_p = 2.0;
        res->dof = -1;
        res->inv_z = NAN;
        res->integral = NAN;
    }
    if (ns > 0) {
        hist = (long *)calloc((size_t)ns * (size_t)nphi, sizeof *hist);
        if (!CHECK_AT(t, file, line, hist != NULL, "%s: out of memory", c->label)) return 0;
    }
    pt_rng_seed(&rng, c->seed, 11);
    pt_rng_seed(&rng2, c->seed, 12);

    /* (a) the samples */
    for (i = 0; i < c->n_samples; i++) {
        pt_vec3 d = pt_v3(-7.0f, -7.0f, -7.0f);
        float pv = -7.0f, v;
        int rc = pt_pdf_sample(c->pdf, &rng, &d, &pv), near = 0;
        double r = -1.0, len, x, y;
        dv3 w;
        if (rc != 0 && rc != 1) { bad_rc++; continue; }
        if (rc == 0) {
            fails++;
            if (d.x != 0.0f || d.y != 0.0f || d.z != 0.0f || pv != 0.0f) bad_fail_out++;
            continue;
        }
        succ++;
        if (!isfinite(d.x) || !isfinite(d.y) || !isfinite(d.z) || !isfinite(pv)) { nonfinite++; continue; }
        if (!(pv > 0.0f)) { nonpositive++; continue; }
        len = dlen(dv_from(d));
        if (fabs(len - 1.0) > 1e-5) nonunit++;
        w = dnorm(dv_from(d));
        v = pt_pdf_value(c->pdf, d);
        if (c->ref) r = c->ref(c->ref_ctx, w, &near);
        if (!isfinite(v)) nonfinite++;
        else if (!near) {
            double rel = fabs((double)v - (double)pv) / fmax(v, pv);
            if (rel > worst_rel) worst_rel = rel;
            if (rel > TU_SAMPLE_VALUE_REL && mismatch++ == 0)
                snprintf(example, sizeof example, "sample (%.9g, %.9g, %.9g) pdf %.9g, pt_pdf_value %.9g", d.x, d.y,
                         d.z, pv, v);
        }
        if (r >= 0.0 && !near && fabs(pv - r) > 1e-3 * r + abs_tol) {
            if (ref_mismatch++ == 0)
                snprintf(ref_example, sizeof ref_example, "sample (%.9g, %.9g, %.9g) pdf %.9g, closed form %.9g",
                         d.x, d.y, d.z, pv, r);
        }
        if (!cone_to_unit(&cone, w, &x, &y) || !dom->to_unit(dom->ctx, w, &x, &y)) {
            if (outside++ == 0)
                snprintf(out_example, sizeof out_example, "(%.9g, %.9g, %.9g) pdf %.9g", d.x, d.y, d.z, pv);
            continue;
        }
        tu_acc_add(&inv, 1.0 / pv);
        if (hist) {
            int si = (int)(x * ns), pj = (int)(y * nphi);
            if (si >= ns) si = ns - 1;
            if (pj >= nphi) pj = nphi - 1;
            hist[(long)si * nphi + pj]++;
            binned++;
        }
    }

    /* pt_pdf_value at directions from the proposal: finite, >= 0, equal to the closed form; and
       the mass \int p = E[p(W) / q(W)] for W drawn from the proposal q, which covers the support */
    for (i = 0; i < c->n_mass; i++) {
        dv3 w0;
        double q = dom->propose(dom->ctx, &rng2, &w0), r;
        dv3 w = dnorm(dv_from(dv_to(w0)));
        float v = pt_pdf_value(c->pdf, dv_to(w));
        int near = 0;
        if (!isfinite(v) || v < 0.0f) {
            if (value_bad++ == 0)
                snprintf(value_example, sizeof value_example, "pt_pdf_value(%.9g, %.9g, %.9g) = %g", w.x, w.y, w.z, v);
            continue;
        }
        tu_acc_add(&mass, (double)v / q);
        if (c->ref) {
            r = c->ref(c->ref_ctx, w, &near);
            if (r >= 0.0 && !near && (r == 0.0 ? v != 0.0f : fabs(v - r) > 1e-3 * r + abs_tol)) {
                if (value_ref_mismatch++ == 0)
                    snprintf(value_example, sizeof value_example,
                             "pt_pdf_value(%.9g, %.9g, %.9g) = %.9g, closed form %.9g", w.x, w.y, w.z, v, r);
            }
        }
    }

    /* hard failures (docs/accuracy.md): no sample outside the domain, no negative or
       non-finite density, ... (the two grid-based ones follow with the chi-square) */
    ok &= CHECK_AT(t, file, line, bad_rc == 0, "%s: pt_pdf_sample returned neither 0 nor 1 (%ld times)", c->label, bad_rc);
    ok &= CHECK_AT(t, file, line, bad_fail_out == 0, "%s: a failed draw left non-zero dir/pdf (%ld times)", c->label,
                   bad_fail_out);
    ok &= CHECK_AT(t, file, line, nonfinite == 0, "%s: %ld non-finite samples or densities", c->label, nonfinite);
    ok &= CHECK_AT(t, file, line, nonpositive == 0, "%s: %ld successful samples with density <= 0", c->label, nonpositive);
    ok &= CHECK_AT(t, file, line, nonunit == 0, "%s: %ld sampled directions not unit length (1e-5)", c->label, nonunit);
    ok &= CHECK_AT(t, file, line, mismatch == 0,
                   "%s: %ld of %ld sample densities differ from pt_pdf_value (rel %.0e; worst %.2e), e.g. %s", c->label,
                   mismatch, succ, TU_SAMPLE_VALUE_REL, worst_rel, example);
    ok &= CHECK_AT(t, file, line, ref_mismatch == 0,
                   "%s: %ld of %ld sample densities differ from the closed form (rel 1e-3), e.g. %s", c->label,
                   ref_mismatch, succ, ref_example);
    ok &= CHECK_AT(t, file, line, outside == 0, "%s: %ld samples outside the support, e.g. %s", c->label, outside,
                   out_example);
    ok &= CHECK_AT(t, file, line, value_bad == 0, "%s: %ld pt_pdf_value results negative or non-finite, e.g. %s",
                   c->label, value_bad, value_example);
    ok &= CHECK_AT(t, file, line, value_ref_mismatch == 0,
                   "%s: pt_pdf_value differs from the closed form at %ld of %ld directions (rel 1e-3), e.g. %s",
                   c->label, value_ref_mismatch, c->n_mass, value_example);

    /* (b) mass */
    F = c->n_samples > 0 ? (double)succ / (double)c->n_samples : 0.0;
    if (res) {
        res->success_fraction = F;
        res->mass = mass.mean;
        res->inv_pdf_mean = inv.mean;
        res->worst_sample_value_rel = worst_rel;
    }
    if (c->expected_mass >= 0.0) {
        double M = c->expected_mass, se = sqrt(M * (1.0 - M) / (double)c->n_samples);
        /* 1e-4: allowance for draws rejected for numerical reasons (a bias below 1e-4) */
        ok &= CHECK_AT(t, file, line, fabs(F - M) <= z * se + 1e-4,
                       "%s: %ld of %ld draws succeeded (%.6f), expected mass %.6f (z limit %.2f)", c->label, succ,
                       c->n_samples, F, M, z);
        if (se > 0 && res) res->max_abs_z = fmax(res->max_abs_z, fabs(F - M) / se);
        comparisons++;
        if (c->n_mass > 0) {
            double sem = tu_acc_se(&mass);
            ok &= CHECK_AT(t, file, line, fabs(mass.mean - M) <= z * sem + 1e-5 * M,
                           "%s: integral of pt_pdf_value over the sphere %.6f +- %.6f, expected %.6f (z limit %.2f)",
                           c->label, mass.mean, sem, M, z);
            if (sem > 0 && res) res->max_abs_z = fmax(res->max_abs_z, fabs(mass.mean - M) / sem);
            comparisons++;
        }
    }
    if (c->n_mass > 0 && c->n_samples > 0) {
        double se = sqrt(tu_acc_var(&mass) / mass.n + F * (1.0 - F) / (double)c->n_samples);
        ok &= CHECK_AT(t, file, line, fabs(mass.mean - F) <= z * se + 1e-4,
                       "%s: integral of pt_pdf_value %.6f but fraction of successful draws %.6f (se %.2g)", c->label,
                       mass.mean, F, se);
        if (se > 0 && res) res->max_abs_z = fmax(res->max_abs_z, fabs(mass.mean - F) / se);
        comparisons++;
    }
    if (c->support > 0.0 && inv.n > 1) {
        /* E[1/p] over samples = the measure of the support (docs/accuracy.md: within 3 sigma
           when inv_z = 3; else at the suite's level alpha) */
        double se = tu_acc_se(&inv), lim = c->inv_z > 0.0 ? c->inv_z : z;
        ok &= CHECK_AT(t, file, line, fabs(inv.mean - c->support) <= lim * se + 1e-5 * c->support,
                       "%s: mean of 1/pdf %.9g +- %.3g, expected the support's solid angle %.9g (z limit %.2f)",
                       c->label, inv.mean, se, c->support, lim);
        row.has_inv_z = 1;
        row.inv_z = se > 0 ? (inv.mean - c->support) / se : 0.0;
        if (res) {
            res->inv_z = row.inv_z;
            if (se > 0) res->max_abs_z = fmax(res->max_abs_z, fabs(row.inv_z));
        }
        if (!(c->inv_z > 0.0)) comparisons++;
    }

    /* (c) chi-square: expected count of a cell = N * (integral of pt_pdf_value over the cell), N the
       number of draws (Mitsuba 3's ChiSquareTest); cells expecting fewer than 5 pooled */
    if (hist && binned > 0) {
        double *I = (double *)malloc((size_t)ns * (size_t)nphi * sizeof *I);
        char *flag = (char *)calloc((size_t)ns * (size_t)nphi, 1);
        double total = 0.0, chi2 = 0.0, pool_e = 0.0, pool_o = 0.0, p, N = (double)c->n_samples;
        int cells = 0, si, pj, refined = 0;
        long zero_cell_samples = 0;
        grid_ctx grid;
        if (!CHECK_AT(t, file, line, I != NULL && flag != NULL, "%s: out of memory", c->label)) {
            free(I); free(flag); free(hist); return 0;
        }
        grid.pdf = c->pdf;
        grid.dom = dom;
        grid.floor = 1e-4 * (c->expected_mass > 0 ? c->expected_mass : 1.0);
        grid.evals = 0;
        grid.budget = c->n_samples >= 500000 ? 40000000L : 4000000L;
        grid.mixed_depth = c->n_samples >= 500000 ? 7 : 5;
        for (si = 0; si < ns; si++)
            for (pj = 0; pj < nphi; pj++)
                I[si * nphi + pj] = rect_integral(&grid, (double)si / ns, (double)(si + 1) / ns, (double)pj / nphi,
                                                  (double)(pj + 1) / nphi, 0, 0);
        /* cells on either side of the support boundary: integrate again with forced refinement */
        for (si = 0; si < ns; si++) {
            for (pj = 0; pj < nphi; pj++) {
                int di, dj, boundary = 0;
                for (di = -1; di <= 1; di++)
                    for (dj = -1; dj <= 1; dj++) {
                        int ni = si + di, nj = pj + dj;
                        if (dom == &cone_dom) nj = (nj + nphi) % nphi; /* phi wraps around */
                        if (ni < 0 || ni >= ns || nj < 0 || nj >= nphi) continue;
                        if ((I[ni * nphi + nj] > 0.0) != (I[si * nphi + pj] > 0.0)) boundary = 1;
                    }
                if (boundary) { flag[si * nphi + pj] = 1; refined++; }
            }
        }
        for (si = 0; si < ns; si++)
            for (pj = 0; pj < nphi; pj++)
                if (flag[si * nphi + pj])
                    I[si * nphi + pj] = rect_integral(&grid, (double)si / ns, (double)(si + 1) / ns, (double)pj / nphi,
                                                      (double)(pj + 1) / nphi, 0, 3);
        /* hard failure: a sample in a cell whose integrated density is zero. Before declaring it,
           integrate that cell once more on a 4^6 finer grid (a sliver of support thinner than the
           quadrature's points is not an error of the PDF). */
        for (si = 0; si < ns * nphi; si++) {
            if (hist[si] > 0 && I[si] == 0.0) {
                long budget = grid.budget;
                grid.budget = grid.evals + 200000;
                I[si] = rect_integral(&grid, (double)(si / nphi) / ns, (double)(si / nphi + 1) / ns,
                                      (double)(si % nphi) / nphi, (double)(si % nphi + 1) / nphi, 0, 6);
                grid.budget = budget;
                if (I[si] == 0.0) zero_cell_samples += hist[si];
            }
        }
        for (si = 0; si < ns * nphi; si++) total += I[si];
        row.integral = total;
        if (res) res->integral = total;
        ok &= CHECK_AT(t, file, line, total > 0.0, "%s: pt_pdf_value integrates to zero over the domain", c->label);
        ok &= CHECK_AT(t, file, line, zero_cell_samples == 0,
                       "%s: hard failure: %ld samples in cells where pt_pdf_value integrates to zero", c->label,
                       zero_cell_samples);
        ok &= CHECK_AT(t, file, line, total <= 1.0 + TU_MASS_TOL,
                       "%s: hard failure: pt_pdf_value integrates to %.6f > 1 over the domain", c->label, total);
        if (total > 0.0) {
            for (si = 0; si < ns * nphi; si++) {
                double e = N * I[si], o = (double)hist[si];
                if (e >= 5.0) {
                    chi2 += (o - e) * (o - e) / e;
                    cells++;
                    if (getenv("PT_TEST_DEBUG") && (o - e) * (o - e) / e > 9)
                        printf("      cell %d,%d expected %.1f observed %.0f\n", si / nphi, si % nphi, e, o);
                } else {
                    pool_e += e;
                    pool_o += o;
                }
            }
            if (pool_e >= 5.0) { chi2 += (pool_o - pool_e) * (pool_o - pool_e) / pool_e; cells++; }
            else {
                ok &= CHECK_AT(t, file, line, pool_o <= pool_e + 5.0 * sqrt(pool_e) + 5.0,
                               "%s: %.0f samples in cells where the density integrates to %.3g expected samples",
                               c->label, pool_o, pool_e);
            }
            p = cells > 1 ? tu_chi2_sf(chi2, cells - 1) : 1.0;
            row.chi2 = chi2;
            row.dof = cells - 1;
            row.p = p;
            if (res) { res->chi2_p = p; res->chi2 = chi2; res->dof = cells - 1; }
            ok &= CHECK_AT(t, file, line, p >= c->alpha,
                           "%s: chi-square %.1f with %d dof, p = %.3g < alpha %.3g (samples do not follow pt_pdf_value)",
                           c->label, chi2, cells - 1, p, c->alpha);
            comparisons++;
            {
                /* The two marginals (rows: 1 - cos or a; columns: phi or b), each its own chi-square
                   from the same histogram and cell integrals: a smooth deviation along one axis (a
                   warp off by a few per cent) spreads over thousands of 2D cells, where its chi-square
                   excess N * int (df)^2 / f is lost in the noise of the many degrees of freedom, but
                   stands out in 40 marginal bins. */
                double pm[2];
                int axis;
                for (axis = 0; axis < 2; axis++) {
                    int nb = axis == 0 ? ns : nphi, b, mcells = 0;
                    double mchi2 = 0.0, pe = 0.0, po = 0.0;
                    for (b = 0; b < nb; b++) {
                        double e = 0.0, o = 0.0;
                        int j;
                        for (j = 0; j < (axis == 0 ? nphi : ns); j++) {
                            int cell = axis == 0 ? b * nphi + j : j * nphi + b;
                            e += N * I[cell];
                            o += (double)hist[cell];
                        }
                        if (e >= 5.0) { mchi2 += (o - e) * (o - e) / e; mcells++; }
                        else { pe += e; po += o; }
                    }
                    if (pe >= 5.0) { mchi2 += (po - pe) * (po - pe) / pe; mcells++; }
                    pm[axis] = mcells > 1 ? tu_chi2_sf(mchi2, mcells - 1) : 1.0;
                    ok &= CHECK_AT(t, file, line, pm[axis] >= c->alpha,
                                   "%s: chi-square of the %s marginal %.1f with %d dof, p = %.3g < alpha %.3g", c->label,
                                   axis == 0 ? "first (1 - cos, or a)" : "second (phi, or b)", mchi2, mcells - 1, pm[axis], c->alpha);
                    if (mcells > 1) comparisons++;
                }
                row.p_marginal = fmin(pm[0], pm[1]);
                if (res) res->marginal_p = row.p_marginal;
            }
            if (tu_verbose())
                printf("    %s: chi2 %.1f dof %d p %.4f, marginals p >= %.4f (%d boundary cells, %ld evaluations, integral %.6f)\n",
                       c->label, chi2, cells - 1, p, row.p_marginal, refined, grid.evals, total);
        }
        free(I);
        free(flag);
    }
    if (tu_verbose())
        printf("    %s: success %.6f, mass %.6f +- %.6f (exp %.6f), E[1/p] %.6g +- %.3g (exp %.6g), worst sample/value rel %.2e\n",
               c->label, F, mass.mean, tu_acc_se(&mass), c->expected_mass, inv.mean, tu_acc_se(&inv), c->support, worst_rel);
    free(hist);
    row.passed = ok;
    if (!c->expect_reject) tu_suite_count(comparisons);
    if (row.dof >= 0) record_row(&row);
    return ok;
}

int tu_check_pdf_rejects(tu_pdf_check *c, tu_pdf_result *res, char *reason, size_t size)
{
    test_ctx scratch;
    memset(&scratch, 0, sizeof scratch);
    c->expect_reject = 1;
    tu_check_pdf_(&scratch, c, res, __FILE__, __LINE__);
    snprintf(reason, size, "%s", scratch.failures ? scratch.reason : "(nothing failed)");
    return scratch.failures;
}

/* ------------------------------------------------------------------------------------------ */
/* films                                                                                       */

int tu_film_regions(const pt_film *f, int rx, int ry, tu_region *out)
{
    int i, j, x, y, k;
    for (j = 0; j < ry; j++) {
        for (i = 0; i < rx; i++) {
            tu_region *r = &out[j * rx + i];
            double var[3] = { 0, 0, 0 };
            int x0 = i * f->width / rx, x1 = (i + 1) * f->width / rx;
            int y0 = j * f->height / ry, y1 = (j + 1) * f->height / ry;
            memset(r, 0, sizeof *r);
            for (y = y0; y < y1; y++) {
                for (x = x0; x < x1; x++) {
                    pt_color m, v;
                    if (pt_film_pixel(f, x, y, &m, &v) != PT_OK) return 0;
                    r->mean[0] += m.x; r->mean[1] += m.y; r->mean[2] += m.z;
                    var[0] += v.x; var[1] += v.y; var[2] += v.z;
                    r->pixels++;
                }
            }
            for (k = 0; k < 3; k++) {
                r->mean[k] /= r->pixels;
                r->se[k] = sqrt(var[k]) / r->pixels;
            }
        }
    }
    return 1;
}

int tu_render_into(test_ctx *t, const pt_scene *s, const pt_render_desc *d, pt_film *film, pt_render_stats *st,
                   const char *what)
{
    int rc;
    pt_render_stats local;
    if (!st) st = &local;
    if (!CHECK(t, pt_film_init(film, d->width, d->height) == PT_OK, "%s: film", what)) return 0;
    rc = pt_render(s, d, film, st);
    CHECK(t, rc == PT_OK, "%s: pt_render returned %d (%s: %s)", what, rc, pt_result_string(rc), st->error);
    CHECK(t, st->nonfinite_samples == 0, "%s: %llu non-finite samples", what, (unsigned long long)st->nonfinite_samples);
    return rc == PT_OK;
}

int tu_film_equal(const pt_film *a, const pt_film *b)
{
    size_t n;
    if (a->width != b->width || a->height != b->height) return 0;
    n = (size_t)a->width * (size_t)a->height;
    return memcmp(a->sum, b->sum, n * 3 * sizeof(double)) == 0 &&
           memcmp(a->sum_sq, b->sum_sq, n * 3 * sizeof(double)) == 0 &&
           memcmp(a->count, b->count, n * sizeof(uint32_t)) == 0 &&
           memcmp(a->sum_odd, b->sum_odd, n * 3 * sizeof(double)) == 0 &&
           (!a->low || !b->low || memcmp(a->low, b->low, n * 9 * sizeof(double)) == 0);
}

/* ------------------------------------------------------------------------------------------ */
/* analytic images                                                                             */

/* Irradiance at a point x of the plane y = 0 (normal +y) from the light, radiance Le. */
double tu_plane_irradiance(const tu_light *L, double Le, dv3 x)
{
    if (L->kind == TU_POINT || L->kind == TU_SPOT) {
        /* E = I falloff cos(theta) / d^2 (Mitsuba 3's spot falloff: linear in the angle) */
        dv3 l = dsub(L->p0, x);
        double d2 = ddot(l, l), d = sqrt(d2), fall = 1.0;
        if (l.y <= 0.0) return 0.0;
        if (L->kind == TU_SPOT) {
            double a = acos(fmin(1.0, fmax(-1.0, -ddot(L->p1, l) / d))) * (180.0 / TU_PI);
            fall = a <= L->beam ? 1.0 : a >= L->cutoff ? 0.0 : (L->cutoff - a) / (L->cutoff - L->beam);
        }
        return Le * fall * (l.y / d) / d2;
    }
    if (L->kind == TU_DIRECTIONAL) return Le * fmax(0.0, -L->p1.y);
    if (L->kind == TU_SPHERE) {
        /* E = pi L sin^2(alpha) cos(theta), sin alpha = R / d, cos theta = (c - x).n / d */
        dv3 l = dsub(L->p0, x);
        double d2 = ddot(l, l);
        return TU_PI * Le * (L->radius * L->radius / d2) * (l.y / sqrt(d2));
    } else {
        dv3 v[4];
        int n;
        if (L->kind == TU_QUAD) {
            v[0] = L->p0; v[1] = dadd(L->p0, L->p1); v[2] = dadd(v[1], L->p2); v[3] = dadd(L->p0, L->p2);
            n = 4;
        } else {
            v[0] = L->p0; v[1] = L->p1; v[2] = L->p2;
            n = 3;
        }
        return Le * tu_lambert_polygon(x, dv(0, 1, 0), v, n);
    }
}

/* Midpoint rule over the pixel footprint with k x k camera rays. */
static double footprint_mean(const tu_plane_scene *ps, const pt_camera *cam, int x, int y, int k)
{
    double sum = 0.0;
    int a, b, i;
    for (a = 0; a < k; a++) {
        for (b = 0; b < k; b++) {
            pt_ray r = pt_camera_ray(cam, (float)(x + (a + 0.5) / k), (float)(y + (b + 0.5) / k), 0.5f, 0.5f);
            double tt = -(double)r.origin.y / (double)r.dir.y;
            dv3 p = dadd(dv_from(r.origin), dscale(dv_from(r.dir), tt));
            for (i = 0; i < ps->light_count; i++) sum += ps->rho / TU_PI * tu_plane_irradiance(&ps->light[i], ps->radiance[i], p);
        }
    }
    return sum / (k * k);
}

int tu_plane_scene_finish(tu_plane_scene *ps, int width, int height)
{
    pt_camera cam;
    int x, y;
    ps->width = width;
    ps->height = height;
    ps->camera.look_from = pt_v3(0, 1, 0);
    ps->camera.look_at = pt_v3(0, 0, 0);
    ps->camera.up = pt_v3(0, 0, -1);
    ps->camera.vfov_degrees = 70;
    if (pt_camera_init(&cam, &ps->camera, width, height) != PT_OK) return 0;
    ps->ref = (double *)malloc(sizeof(double) * (size_t)width * (size_t)height);
    ps->qerr = (double *)malloc(sizeof(double) * (size_t)width * (size_t)height);
    if (!ps->ref || !ps->qerr) return 0;
    for (y = 0; y < height; y++) {
        for (x = 0; x < width; x++) {
            double i8 = footprint_mean(ps, &cam, x, y, 8), i4 = footprint_mean(ps, &cam, x, y, 4);
            ps->ref[y * width + x] = i8;
            ps->qerr[y * width + x] = fabs(i8 - i4) / 3.0;
        }
    }
    return 1;
}

int tu_plane_scene_create(tu_plane_scene *ps, int kind, int width, int height)
{
    return tu_plane_scene_create_ex(ps, kind, 0, 0, width, height);
}

int tu_plane_scene_create_ex(tu_plane_scene *ps, int kind, int two_sided, int flip, int width, int height)
{
    int floor_m, light_m, rc;
    tu_light *L = &ps->light[0];
    memset(ps, 0, sizeof *ps);
    ps->rho = 0.5;
    ps->light_count = 1;
    ps->radiance[0] = 1.0;
    L->kind = kind;
    L->two_sided = two_sided;
    if (kind == TU_SPHERE) {
        /* sin^2(alpha) = 1/4.84 below the centre; the sphere (y in [1.2, 3.2]) is above the camera */
        L->p0 = dv(0.3, 2.2, 0.1);
        L->radius = 1.0;
    } else if (kind == TU_QUAD) {
        L->p0 = dv(-1.0, 1.5, -1.0); /* u x v = (0, -4, 0): faces the plane */
        L->p1 = dv(2.0, 0.0, 0.0);
        L->p2 = dv(0.0, 0.0, 2.0);
        if (flip) { L->p1 = dv(0.0, 0.0, 2.0); L->p2 = dv(2.0, 0.0, 0.0); } /* the same quad facing up */
    } else {
        L->p0 = dv(-1.2, 1.5, -1.0); /* (b - a) x (c - a) points down */
        L->p1 = dv(1.5, 1.5, -0.9);
        L->p2 = dv(-0.9, 1.5, 1.4);
        if (flip) { dv3 tmp = L->p1; L->p1 = L->p2; L->p2 = tmp; }
    }
    ps->scene = pt_scene_create();
    if (!ps->scene) return 0;
    floor_m = pt_scene_add_lambertian(ps->scene, pt_v3((float)ps->rho, (float)ps->rho, (float)ps->rho));
    light_m = pt_scene_add_emitter(ps->scene, pt_v3(1, 1, 1), two_sided);
    rc = pt_scene_add_quad(ps->scene, pt_v3(-20, 0, -20), pt_v3(0, 0, 40), pt_v3(40, 0, 0), floor_m);
    if (rc >= 0) {
        if (kind == TU_SPHERE) rc = pt_scene_add_sphere(ps->scene, dv_to(L->p0), (float)L->radius, light_m);
        else if (kind == TU_QUAD) rc = pt_scene_add_quad(ps->scene, dv_to(L->p0), dv_to(L->p1), dv_to(L->p2), light_m);
        else rc = pt_scene_add_triangle(ps->scene, dv_to(L->p0), dv_to(L->p1), dv_to(L->p2), light_m);
    }
    if (rc < 0 || pt_scene_commit(ps->scene) != PT_OK) return 0;
    if (flip && !two_sided) ps->radiance[0] = 0.0; /* a one-sided light facing away lights nothing */
    return tu_plane_scene_finish(ps, width, height);
}

void tu_plane_scene_destroy(tu_plane_scene *ps)
{
    if (ps->scene) pt_scene_destroy(ps->scene);
    free(ps->ref);
    free(ps->qerr);
    memset(ps, 0, sizeof *ps);
}

void tu_plane_render_compare(const tu_plane_scene *ps, pt_render_desc *d, double z_pixel, tu_image_stats *out)
{
    pt_film f;
    pt_render_stats st;
    int x, y;
    double var_sum = 0.0;
    memset(out, 0, sizeof *out);
    d->width = ps->width;
    d->height = ps->height;
    d->camera = ps->camera;
    d->max_depth = 1;
    out->rc = pt_film_init(&f, d->width, d->height);
    if (out->rc != PT_OK) return;
    out->rc = pt_render(ps->scene, d, &f, &st);
    out->nonfinite = st.nonfinite_samples;
    out->seconds = st.seconds;
    if (out->rc == PT_OK) {
        for (y = 0; y < d->height; y++) {
            for (x = 0; x < d->width; x++) {
                pt_color m, v;
                double want = ps->ref[y * d->width + x], se, z, zs;
                pt_film_pixel(&f, x, y, &m, &v);
                se = sqrt((double)v.y);
                z = tu_z_floor(m.y, want, se, TU_FLOAT_FLOOR * want);
                zs = m.y >= want ? z : -z;
                out->pixels++;
                out->accepted += z <= z_pixel;
                if (want > 0.0) out->mean_rel += (m.y - want) / want;
                out->mean_z += zs;
                out->max_abs_z = fmax(out->max_abs_z, z);
                out->image_mean += m.y;
                out->image_ref += want;
                var_sum += v.y;
                if (se > 0.0) out->worst_qerr_over_se = fmax(out->worst_qerr_over_se, ps->qerr[y * d->width + x] / se);
                else if (ps->qerr[y * d->width + x] > 0.0) out->worst_qerr_over_se = INFINITY;
            }
        }
        out->mean_rel /= out->pixels;
        out->mean_z /= out->pixels;
        out->image_mean /= out->pixels;
        out->image_ref /= out->pixels;
        out->image_se = sqrt(var_sum) / out->pixels;
        out->image_z = tu_z_floor(out->image_mean, out->image_ref, out->image_se, TU_FLOAT_FLOOR * out->image_ref);
        if (out->image_mean < out->image_ref) out->image_z = -out->image_z;
    }
    pt_film_free(&f);
}

int tu_add_furnace_material(pt_scene *s)
{
    pt_material_desc md;
    memset(&md, 0, sizeof md);
    md.type = PT_MATERIAL_LAMBERTIAN;
    md.albedo = pt_v3(0.5f, 0.5f, 0.5f);
    md.emission = pt_v3(0.5f, 0.5f, 0.5f);
    md.two_sided_emission = 1;
    return pt_scene_add_material(s, &md);
}

int tu_add_closed_furnace(pt_scene *s)
{
    int m = tu_add_furnace_material(s), rc;
    if (m < 0) return m;
    rc = pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m);
    return rc >= 0 ? pt_scene_commit(s) : rc;
}

/* ---- temporary directories (output and EXR writer tests) ---- */
int tu_make_tmpdir(char *buf, size_t n)
{
    snprintf(buf, n, "/tmp/pdftrace-test-XXXXXX");
    return mkdtemp(buf) != NULL;
}

/* Number of entries in dir (excluding . and ..); names into list if given. */
int tu_dir_entries(const char *dir, char *list, size_t n)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    int count = 0;
    if (list && n) list[0] = '\0';
    if (!d) return -1;
    while ((e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        count++;
        if (list && strlen(list) + strlen(e->d_name) + 2 < n) {
            strcat(list, e->d_name);
            strcat(list, " ");
        }
    }
    closedir(d);
    return count;
}

void tu_remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    struct dirent *e;
    char path[512];
    if (!d) return;
    while ((e = readdir(d)) != NULL) {
        struct stat st;
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) tu_remove_tree(path);
        else unlink(path);
    }
    closedir(d);
    rmdir(dir);
}

pt_render_desc tu_base_desc(int w, int h, int spp, uint64_t seed)
{
    pt_render_desc d;
    memset(&d, 0, sizeof d);
    d.width = w;
    d.height = h;
    d.samples_per_pixel = spp;
    d.seed = seed;
    return d;
}

/* The whole file at path (size into *size), NUL-terminated, or NULL. */
unsigned char *tu_read_file(const char *path, long *size)
{
    FILE *f = fopen(path, "rb");
    unsigned char *buf;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) != 0 || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
        fclose(f);
        return NULL;
    }
    buf = (unsigned char *)malloc((size_t)n + 1u);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) { free(buf); buf = NULL; }
    fclose(f);
    if (buf) buf[n] = '\0';
    *size = n;
    return buf;
}

/* tu_read_file as text: the length into *len. */
char *tu_read_text(const char *path, size_t *len)
{
    long n = 0;
    char *text = (char *)tu_read_file(path, &n);
    if (text) *len = (size_t)n;
    return text;
}

/* ------------------------------------------------------------------------------------------ */
/* environment maps                                                                            */

void tu_rotation(dv3 axis, double deg, double *R, pt_transform *xf)
{
    dv3 a = dnorm(axis);
    double th = deg * TU_PI / 180.0, c = cos(th), s = sin(th), k = 1.0 - c;
    int i, j;
    R[0] = a.x * a.x * k + c;       R[1] = a.x * a.y * k - a.z * s; R[2] = a.x * a.z * k + a.y * s;
    R[3] = a.y * a.x * k + a.z * s; R[4] = a.y * a.y * k + c;       R[5] = a.y * a.z * k - a.x * s;
    R[6] = a.z * a.x * k - a.y * s; R[7] = a.z * a.y * k + a.x * s; R[8] = a.z * a.z * k + c;
    if (xf) {
        *xf = pt_transform_identity();
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) xf->m[i][j] = (float)R[3 * i + j];
    }
}

dv3 tu_env_dir(double u, double v)
{
    double phi = 2.0 * TU_PI * u, th = TU_PI * v;
    return dv(sin(th) * sin(phi), cos(th), -sin(th) * cos(phi));
}

void tu_env_uv(dv3 d, double *u, double *v)
{
    double uu = atan2(d.x, -d.z) / (2.0 * TU_PI);
    if (uu < 0.0) uu += 1.0;
    *u = uu < 1.0 ? uu : 0.0;
    *v = atan2(sqrt(d.x * d.x + d.z * d.z), d.y) / TU_PI;
}

int tu_env_sky(pt_image *img, int w, int h, dv3 sun, double sun_radius, double sun_radiance)
{
    static const double zenith[3] = { 0.15, 0.3, 0.8 }, horizon[3] = { 0.7, 0.8, 0.9 }, ground[3] = { 0.12, 0.1, 0.08 };
    static const double tint[3] = { 1.0, 0.9, 0.7 };
    double cos_r = cos(sun_radius);
    int x, y, c;
    img->width = w;
    img->height = h;
    img->rgb = (float *)malloc(sizeof(float) * 3 * (size_t)w * (size_t)h);
    if (!img->rgb) return 0;
    sun = dnorm(sun);
    for (y = 0; y < h; y++) {
        double v = (y + 0.5) / h, t = fmin(1.0, 2.0 * v);
        for (x = 0; x < w; x++) {
            dv3 d = tu_env_dir((x + 0.5) / w, v);
            float *px = img->rgb + 3 * ((size_t)y * (size_t)w + (size_t)x);
            for (c = 0; c < 3; c++) {
                /* smooth: t^2 (3 - 2t) from zenith to horizon; the ground blends in below */
                double s = t * t * (3.0 - 2.0 * t), L = zenith[c] + (horizon[c] - zenith[c]) * s;
                if (v > 0.5) L = ground[c] + (horizon[c] - ground[c]) * exp(-40.0 * (v - 0.5));
                if (ddot(d, sun) >= cos_r) L += sun_radiance * tint[c];
                px[c] = (float)L;
            }
        }
    }
    return 1;
}

/* Gauss-Legendre nodes and weights on [0, 1] for 3 and 5 points. */
static const double gl3_x[3] = { 0.11270166537925831, 0.5, 0.88729833462074169 };
static const double gl3_w[3] = { 0.27777777777777778, 0.44444444444444444, 0.27777777777777778 };
static const double gl5_x[5] = { 0.046910077030668004, 0.23076534494715845, 0.5, 0.76923465505284155, 0.95308992296933200 };
static const double gl5_w[5] = { 0.11846344252809454, 0.23931433524968324, 0.28444444444444444, 0.23931433524968324,
                                 0.11846344252809454 };

static double env_channel(const pt_scene *s, const double *R, dv3 d, int channel)
{
    dv3 w = R ? dv(R[0] * d.x + R[1] * d.y + R[2] * d.z, R[3] * d.x + R[4] * d.y + R[5] * d.z,
                   R[6] * d.x + R[7] * d.y + R[8] * d.z)
              : d;
    pt_color c = pt_scene_environment_radiance(s, dv_to(w));
    return channel == 0 ? c.x : channel == 1 ? c.y : c.z;
}

double tu_env_irradiance(const pt_scene *s, int w, int h, const double *R, dv3 n, int channel, double *err)
{
    double e3 = 0.0, e5 = 0.0;
    dv3 nm = R ? dv(R[0] * n.x + R[3] * n.y + R[6] * n.z, R[1] * n.x + R[4] * n.y + R[7] * n.z,
                    R[2] * n.x + R[5] * n.y + R[8] * n.z)
               : n; /* the normal in the map's frame, R^T n */
    /* large patches (small maps) in su x sv parts, so that no part spans more than 1/32 of a turn */
    const int su = (32 + w - 1) / w, sv = (16 + h - 1) / h;
    int x, yi, a, b, k, piece;
    /* which pixels are black (each pixel centre's radiance looked up once) */
    char *lit = (char *)malloc((size_t)w * (size_t)h);
    if (!lit) {
        if (err) *err = INFINITY;
        return NAN;
    }
    for (yi = 0; yi < h; yi++)
        for (x = 0; x < w; x++) lit[yi * w + x] = env_channel(s, R, tu_env_dir((x + 0.5) / w, (yi + 0.5) / h), channel) != 0.0;
    /* v segments: the cap [0, 1/2H], between row centres, the cap [1 - 1/2H, 1]; rows at their ends */
    for (yi = 0; yi <= h; yi++) {
        double v0 = yi == 0 ? 0.0 : (yi - 0.5) / h, v1 = yi == h ? 1.0 : (yi + 0.5) / h;
        int r0 = yi == 0 ? 0 : yi - 1, r1 = yi == h ? h - 1 : yi;
        for (x = 0; x < w; x++) {
            double u0 = (x + 0.5) / w, u1 = (x + 1.5) / w;
            /* the patch's four corner pixels all black: nothing to add */
            if (!lit[r0 * w + x] && !lit[r0 * w + (x + 1) % w] && !lit[r1 * w + x] && !lit[r1 * w + (x + 1) % w]) continue;
            for (k = 0; k < 2; k++) {
                int m = k == 0 ? 3 : 5;
                const double *gx = k == 0 ? gl3_x : gl5_x, *gw = k == 0 ? gl3_w : gl5_w;
                double sum = 0.0;
                for (a = 0; a < m * su; a++) {
                    /* at this u the horizon n . d = 0 lies at theta = atan2(-n.y, n.x sin(phi) - n.z cos(phi))
                       (mod pi): the v interval is split there, so that each piece is smooth */
                    double u = u0 + (a / m + gx[a % m]) * (u1 - u0) / su, phi = 2.0 * TU_PI * u;
                    double th = atan2(-nm.y, nm.x * sin(phi) - nm.z * cos(phi)), vh, cut[3];
                    if (th < 0.0) th += TU_PI;
                    vh = th / TU_PI;
                    cut[0] = v0;
                    cut[1] = vh > v0 && vh < v1 ? vh : v1;
                    cut[2] = v1;
                    for (piece = 0; piece < 2; piece++) {
                        double p0 = cut[piece], p1 = cut[piece + 1], part = 0.0;
                        if (!(p1 > p0)) continue;
                        for (b = 0; b < m * sv; b++) {
                            double v = p0 + (b / m + gx[b % m]) * (p1 - p0) / sv;
                            dv3 d = tu_env_dir(u, v);
                            double c = ddot(d, nm);
                            /* d omega = 2 pi^2 sin(pi v) du dv */
                            if (c > 0.0) part += gw[b % m] * env_channel(s, R, d, channel) * c * sin(TU_PI * v);
                        }
                        sum += gw[a % m] * part * (p1 - p0) / sv;
                    }
                }
                sum *= 2.0 * TU_PI * TU_PI * (u1 - u0) / su;
                if (k == 0) e3 += sum;
                else e5 += sum;
            }
        }
    }
    free(lit);
    if (err) *err = fabs(e5 - e3);
    return e5;
}
