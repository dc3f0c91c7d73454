#define _POSIX_C_SOURCE 200809L
/* sky.c - ptsky: a procedural HDR sky with a sun, written as a lat-long environment map.

       ptsky OUT.pfm|OUT.exr [--size WxH] [--sun-elevation DEG] [--sun-azimuth DEG]
             [--turbidity T] [--sun-solid-angle SR] [--sun-irradiance E] [--sky-scale S]
             [--ground R G B] [--no-sun]

   The sky dome is the analytic daylight model of A. J. Preetham, P. Shirley and B. Smits, "A
   Practical Analytic Model for Daylight", SIGGRAPH 1999: a Perez distribution of luminance Y
   and chromaticity x, y (Appendix A.2's turbidity-dependent coefficients) scaled by the
   zenith's values, then xyY -> XYZ -> linear sRGB. With --sky-scale 1 a pixel value of 1 is a
   luminance of 1 kcd/m^2 (the model's unit). Below the horizon the ground is a constant grey.
   The sun is a uniform disc whose pixels hold their mean radiance over each pixel's solid
   angle, from the disc's exact overlap with the pixel; its power in the map is checked against
   the disc's before anything is written. Conventions and defaults: docs/sky.md.

   Lat-long map (Mitsuba 3's envmap, as pdftrace's environment light reads it): pixel (x, y) is
   centred at u = (x + 1/2) / W, v = (y + 1/2) / H, direction (sin t sin p, cos t, -sin t cos p)
   with t = pi v, p = 2 pi u; row 0 is the zenith (+y).

   Exit status: 0 written; 2 bad command line (nothing written); 1 failed check or write. The
   same arguments give the same bytes: no randomness, fixed quadratures. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#ifdef PDFTRACE_OPENEXR
#define PDFTRACE_EXR_IMPLEMENTATION
#include "pdftrace_exr.h"
#endif

#define SKY_PI 3.14159265358979323846
#define EXIT_USAGE 2
#define MAX_WIDTH 16384
#define MAX_HEIGHT 8192
#define MAX_PIXELS (1L << 25)           /* 32 Mpixel: about 1 GB of working buffers */
#define SKY_SUBSAMPLES 4                /* per axis, in (phi, cos theta): a pixel's mean radiance */
#define SUN_Z_STEPS 65536               /* midpoint steps in cos theta across the disc's extent */
#define SUN_POWER_TOLERANCE 1e-3        /* map power against the disc's, relative */
#define REAL_SUN_SOLID_ANGLE 6.8e-5     /* a disc of 0.533 degrees across, as the sun's from Earth */
#define DEFAULT_SUN_RATIO 6.0           /* sun (normal) / sky (horizontal) irradiance, clear day */
#define DEFAULT_GROUND_FRACTION 0.1     /* ground = this x the mean luminance along the horizon */
#define HORIZON_STEPS 3600              /* azimuth steps for the horizon's mean luminance */
#define IRRADIANCE_PHI_STEPS 1024       /* the analytic sky irradiance's quadrature, per axis */
#define IRRADIANCE_Z_STEPS 512

/* ---- Preetham, Shirley & Smits 1999 ---- */

/* One Perez distribution: F(theta, gamma) = (1 + A e^(B / cos theta)) (1 + C e^(D gamma) + E cos^2 gamma). */
typedef struct perez {
    double A, B, C, D, E;
} perez;

typedef struct sky_model {
    perez fY, fx, fy;       /* luminance and chromaticity distributions */
    double Yz, xz, yz;      /* zenith luminance (kcd/m^2) and chromaticity */
    double normY, normx, normy; /* F(0, theta_s) of each, the zenith's value */
    double sun[3];          /* unit direction towards the sun */
    double scale;           /* --sky-scale */
} sky_model;

static perez perez_make(double T, double a0, double a1, double b0, double b1, double c0, double c1, double d0,
                        double d1, double e0, double e1)
{
    perez p;
    p.A = a0 * T + a1;
    p.B = b0 * T + b1;
    p.C = c0 * T + c1;
    p.D = d0 * T + d1;
    p.E = e0 * T + e1;
    return p;
}

/* B < 0 for every turbidity accepted, so the first factor tends to 1 at the horizon. */
static double perez_eval(const perez *p, double cos_theta, double gamma, double cos_gamma)
{
    double horizon = cos_theta > 0 ? 1.0 + p->A * exp(p->B / cos_theta) : 1.0;
    return horizon * (1.0 + p->C * exp(p->D * gamma) + p->E * cos_gamma * cos_gamma);
}

/* Zenith chromaticity: [T^2 T 1] M [ts^3 ts^2 ts 1]^T (the paper's Appendix A.2). */
static double zenith_chroma(const double m[3][4], double T, double ts)
{
    double t[4], r = 0, w[3];
    int i;
    t[0] = ts * ts * ts; t[1] = ts * ts; t[2] = ts; t[3] = 1;
    w[0] = T * T; w[1] = T; w[2] = 1;
    for (i = 0; i < 3; ++i) r += w[i] * (m[i][0] * t[0] + m[i][1] * t[1] + m[i][2] * t[2] + m[i][3] * t[3]);
    return r;
}

static void sky_init(sky_model *m, double T, double theta_s, double phi_s, double scale)
{
    static const double mx[3][4] = { { 0.00166, -0.00375, 0.00209, 0 },
                                     { -0.02903, 0.06377, -0.03202, 0.00394 },
                                     { 0.11693, -0.21196, 0.06052, 0.25886 } };
    static const double my[3][4] = { { 0.00275, -0.00610, 0.00317, 0 },
                                     { -0.04214, 0.08970, -0.04153, 0.00516 },
                                     { 0.15346, -0.26756, 0.06670, 0.26688 } };
    double chi = (4.0 / 9.0 - T / 120.0) * (SKY_PI - 2.0 * theta_s), cs = cos(theta_s);
    m->fY = perez_make(T, 0.1787, -1.4630, -0.3554, 0.4275, -0.0227, 5.3251, 0.1206, -2.5771, -0.0670, 0.3703);
    m->fx = perez_make(T, -0.0193, -0.2592, -0.0665, 0.0008, -0.0004, 0.2125, -0.0641, -0.8989, -0.0033, 0.0452);
    m->fy = perez_make(T, -0.0167, -0.2608, -0.0950, 0.0092, -0.0079, 0.2102, -0.0441, -1.6537, -0.0109, 0.0529);
    m->Yz = (4.0453 * T - 4.9710) * tan(chi) - 0.2155 * T + 2.4192;
    m->xz = zenith_chroma(mx, T, theta_s);
    m->yz = zenith_chroma(my, T, theta_s);
    m->normY = perez_eval(&m->fY, 1.0, theta_s, cs);
    m->normx = perez_eval(&m->fx, 1.0, theta_s, cs);
    m->normy = perez_eval(&m->fy, 1.0, theta_s, cs);
    m->sun[0] = sin(theta_s) * sin(phi_s);
    m->sun[1] = cs;
    m->sun[2] = -sin(theta_s) * cos(phi_s);
    m->scale = scale;
}

/* cos and angle between unit d and the sun. */
static double sun_angle(const sky_model *m, const double d[3], double *cos_gamma)
{
    double c = d[0] * m->sun[0] + d[1] * m->sun[1] + d[2] * m->sun[2];
    c = c > 1 ? 1 : c < -1 ? -1 : c;
    *cos_gamma = c;
    return acos(c);
}

/* The sky's luminance (scaled) along unit d with d[1] >= 0. */
static double sky_luminance(const sky_model *m, const double d[3])
{
    double cg, g = sun_angle(m, d, &cg);
    return m->scale * m->Yz * perez_eval(&m->fY, d[1], g, cg) / m->normY;
}

/* The sky's linear sRGB radiance (scaled) along unit d with d[1] >= 0. */
static void sky_rgb(const sky_model *m, const double d[3], double rgb[3])
{
    double cg, g = sun_angle(m, d, &cg);
    double Y = m->Yz * perez_eval(&m->fY, d[1], g, cg) / m->normY;
    double x = m->xz * perez_eval(&m->fx, d[1], g, cg) / m->normx;
    double y = m->yz * perez_eval(&m->fy, d[1], g, cg) / m->normy;
    double X = x / y * Y, Z = (1.0 - x - y) / y * Y;
    int c;
    /* XYZ -> linear sRGB (IEC 61966-2-1, D65); the sky's chromaticities lie inside the gamut, the clamp is a guard */
    rgb[0] = 3.2406 * X - 1.5372 * Y - 0.4986 * Z;
    rgb[1] = -0.9689 * X + 1.8758 * Y + 0.0415 * Z;
    rgb[2] = 0.0557 * X - 0.2040 * Y + 1.0570 * Z;
    for (c = 0; c < 3; ++c) rgb[c] = rgb[c] > 0 ? m->scale * rgb[c] : 0;
}

/* The direction of (phi, z = cos theta) in the map's convention. */
static void direction(double phi, double z, double d[3])
{
    double r = 1.0 - z * z;
    r = r > 0 ? sqrt(r) : 0;
    d[0] = r * sin(phi);
    d[1] = z;
    d[2] = -r * cos(phi);
}

/* Mean luminance along the horizon (the Perez limit at theta = 90 degrees), over azimuth. */
static double horizon_mean_luminance(const sky_model *m)
{
    double sum = 0, d[3];
    int i;
    for (i = 0; i < HORIZON_STEPS; ++i) {
        direction(2.0 * SKY_PI * (i + 0.5) / HORIZON_STEPS, 0.0, d);
        sum += sky_luminance(m, d);
    }
    return sum / HORIZON_STEPS;
}

/* The analytic sky's luminous irradiance on an upward plane, integral of Y cos theta dw over the
   upper hemisphere (midpoint rule in phi and z = cos theta, where dw = dphi dz): independent of
   the map's size, so the default sun's strength is too. */
static double sky_irradiance_analytic(const sky_model *m)
{
    double sum = 0, d[3];
    int i, j;
    for (j = 0; j < IRRADIANCE_Z_STEPS; ++j) {
        double z = (j + 0.5) / IRRADIANCE_Z_STEPS;
        for (i = 0; i < IRRADIANCE_PHI_STEPS; ++i) {
            direction(2.0 * SKY_PI * (i + 0.5) / IRRADIANCE_PHI_STEPS, z, d);
            sum += sky_luminance(m, d) * z;
        }
    }
    return sum * (2.0 * SKY_PI / IRRADIANCE_PHI_STEPS) * (1.0 / IRRADIANCE_Z_STEPS);
}

/* ---- the map ---- */

/* cos theta at the top edge of row y (y = H: the bottom edge of the last row). */
static double row_z(int y, int H)
{
    return cos(SKY_PI * (double)y / (double)H);
}

/* Every pixel's mean radiance over its solid angle: SKY_SUBSAMPLES^2 midpoints, uniform in
   (phi, cos theta) and so in solid angle; sky above the horizon, the ground below. */
static void render_sky(const sky_model *m, const double ground[3], float *rgb, int W, int H)
{
    const int n = SKY_SUBSAMPLES;
    int x, y, i, j, c;
    for (y = 0; y < H; ++y) {
        double zt = row_z(y, H), zb = row_z(y + 1, H);
        for (x = 0; x < W; ++x) {
            double sum[3] = { 0, 0, 0 }, d[3], v[3];
            for (j = 0; j < n; ++j) {
                double z = zt + (zb - zt) * (j + 0.5) / n;
                for (i = 0; i < n; ++i) {
                    direction(2.0 * SKY_PI * (x + (i + 0.5) / n) / W, z, d);
                    if (z >= 0) sky_rgb(m, d, v);
                    else memcpy(v, ground, sizeof v);
                    for (c = 0; c < 3; ++c) sum[c] += v[c];
                }
            }
            for (c = 0; c < 3; ++c) rgb[3 * ((size_t)y * W + x) + c] = (float)(sum[c] / (n * n));
        }
    }
}

/* Adds w x the length of [a, b] (0 <= a <= b <= 2 pi) inside each pixel's phi range to row[]. */
static void add_span(double *row, int W, double a, double b, double w)
{
    double px = 2.0 * SKY_PI / W;
    int x0 = (int)floor(a / px), x1 = (int)floor(b / px), x;
    if (x0 < 0) x0 = 0;
    if (x1 > W - 1) x1 = W - 1;
    for (x = x0; x <= x1; ++x) {
        double lo = x * px > a ? x * px : a, hi = (x + 1) * px < b ? (x + 1) * px : b;
        if (hi > lo) row[x] += (hi - lo) * w;
    }
}

/* The solid angle of each pixel inside the cap {d : d.sun >= cos alpha}, into area[] (zeroed).
   On the sphere dw = dphi dz, so a pixel's share is the integral over z of the length in phi of
   the cap's circle of latitude z that falls in the pixel's phi range; the circle is exact, the
   z integral a midpoint rule of SUN_Z_STEPS steps over the cap's z extent (its error falls as
   steps^-1.5 at the square-root ends). */
static void sun_areas(double *area, int W, int H, double theta_s, double phi_s, double alpha)
{
    double cos_alpha = cos(alpha), zs = cos(theta_s), rs = sin(theta_s);
    double t_lo = theta_s - alpha > 0 ? theta_s - alpha : 0;
    double t_hi = theta_s + alpha < SKY_PI ? theta_s + alpha : SKY_PI;
    double z_hi = cos(t_lo), z_lo = cos(t_hi), two_pi = 2.0 * SKY_PI;
    int y0 = (int)floor(t_lo / SKY_PI * H), y1 = (int)floor(t_hi / SKY_PI * H), y, i, x;
    if (y1 > H - 1) y1 = H - 1;
    for (y = y0; y <= y1; ++y) {
        double zt = row_z(y, H), zb = row_z(y + 1, H), full = 0, dz;
        double a = zb > z_lo ? zb : z_lo, b = zt < z_hi ? zt : z_hi;
        int n;
        if (!(b > a)) continue;
        n = (int)ceil(SUN_Z_STEPS * (b - a) / (z_hi - z_lo));
        if (n < 16) n = 16;
        dz = (b - a) / n;
        for (i = 0; i < n; ++i) {
            double z = a + (i + 0.5) * dz, r = sqrt(1.0 - z * z > 0 ? 1.0 - z * z : 0), c, half, lo, hi, k;
            if (r * rs < 1e-300) { /* a pole, or the sun at the zenith: the whole circle or none of it */
                if (z * zs >= cos_alpha) full += dz;
                continue;
            }
            c = (cos_alpha - z * zs) / (r * rs);
            if (c >= 1) continue;
            if (c <= -1) { full += dz; continue; }
            half = acos(c);
            k = floor((phi_s - half) / two_pi);
            lo = phi_s - half - k * two_pi;
            hi = phi_s + half - k * two_pi;
            add_span(area + (size_t)y * W, W, lo, hi < two_pi ? hi : two_pi, dz);
            if (hi > two_pi) add_span(area + (size_t)y * W, W, 0, hi - two_pi, dz);
        }
        if (full > 0)
            for (x = 0; x < W; ++x) area[(size_t)y * W + x] += full * two_pi / W;
    }
}

/* ---- command line ---- */

typedef struct options {
    const char *out;
    int exr;
    int width, height;
    double elevation, azimuth, turbidity, solid_angle, irradiance, scale, ground[3];
    int no_sun, have_solid_angle, have_irradiance, have_ground;
} options;

static void usage(FILE *f)
{
    fprintf(f,
            "usage: ptsky OUT.pfm|OUT.exr [options]\n"
            "  a Preetham et al. 1999 daylight sky with a sun disc as a lat-long map (row 0 the zenith,\n"
            "  u = atan2(d.x, -d.z) / (2 pi), v = acos(d.y) / pi); linear RGB, 1 = 1 kcd/m^2 at --sky-scale 1\n"
            "  --size WxH             map size, 2..%d x 2..%d (default 512x256)\n"
            "  --sun-elevation DEG    sun's angle above the horizon, 0..90 (default 38)\n"
            "  --sun-azimuth DEG      sun's phi in degrees: the sun is at u = DEG / 360; 0 = -z, 90 = +x,\n"
            "                         180 = +z, 270 = -x (default 45)\n"
            "  --turbidity T          haze, 2..10, the model's fitted range (default 3)\n"
            "  --sun-solid-angle SR   the disc's solid angle, 1e-8..2 pi exclusive (default 6.8e-5, the sun's)\n"
            "  --sun-irradiance E     irradiance from the disc on a surface facing it, > 0, in map units, equal\n"
            "                         in R, G and B (default %g x the sky's horizontal irradiance)\n"
            "  --sky-scale S          multiplies the sky and the default ground and sun, > 0 (default 1)\n"
            "  --ground R G B         radiance below the horizon, >= 0 (default grey, %g x the sky's mean\n"
            "                         luminance along the horizon)\n"
            "  --no-sun               the sky alone (the sun's position still shapes the sky)\n"
            ".exr needs a build with OpenEXR (32-bit float, ZIP); .pfm always works.\n",
            MAX_WIDTH, MAX_HEIGHT, DEFAULT_SUN_RATIO, DEFAULT_GROUND_FRACTION);
}

/* One line on stderr, exit status 2. */
static void fail_usage(const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "ptsky: ");
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, " (ptsky --help for usage)\n");
    exit(EXIT_USAGE);
}

/* A finite number in [lo, hi] (either end open when its flag says so), or exit. */
static double parse_real(const char *opt, const char *s, double lo, int lo_open, double hi, int hi_open,
                         const char *range)
{
    char *end;
    double v;
    if (!*s || *s == ' ' || *s == '\t') fail_usage("%s: '%s' is not a number", opt, s);
    v = strtod(s, &end);
    if (*end || !isfinite(v)) fail_usage("%s: '%s' is not a finite number", opt, s);
    if (v < lo || (lo_open && v == lo) || v > hi || (hi_open && v == hi))
        fail_usage("%s: %s is out of range (%s)", opt, s, range);
    return v;
}

static int parse_dim(const char *s, const char **end)
{
    long v = 0;
    if (*s < '0' || *s > '9') return -1;
    while (*s >= '0' && *s <= '9') {
        v = v * 10 + (*s++ - '0');
        if (v > 1000000) return -1;
    }
    *end = s;
    return (int)v;
}

static void parse_size(const char *s, int *w, int *h)
{
    const char *p;
    int W = parse_dim(s, &p), H;
    if (W < 0 || *p != 'x') fail_usage("--size: '%s' is not WxH (e.g. 512x256)", s);
    H = parse_dim(p + 1, &p);
    if (H < 0 || *p) fail_usage("--size: '%s' is not WxH (e.g. 512x256)", s);
    if (W < 2 || W > MAX_WIDTH || H < 2 || H > MAX_HEIGHT || (long)W * H > MAX_PIXELS)
        fail_usage("--size: %s is out of range (width 2..%d, height 2..%d, at most %ld pixels)", s, MAX_WIDTH,
                   MAX_HEIGHT, MAX_PIXELS);
    *w = W;
    *h = H;
}

static int ends_with_ci(const char *s, const char *suffix)
{
    size_t n = strlen(s), k = strlen(suffix), i;
    if (n <= k) return 0;
    for (i = 0; i < k; ++i) {
        char c = s[n - k + i];
        if (c >= 'A' && c <= 'Z') c = (char)(c - 'A' + 'a');
        if (c != suffix[i]) return 0;
    }
    return s[n - k - 1] != '/';
}

enum { OPT_SIZE, OPT_ELEVATION, OPT_AZIMUTH, OPT_TURBIDITY, OPT_SOLID_ANGLE, OPT_IRRADIANCE, OPT_SCALE, OPT_GROUND,
       OPT_NO_SUN, OPT_COUNT };

static void parse_args(int argc, char **argv, options *o)
{
    static const char *names[OPT_COUNT] = { "--size", "--sun-elevation", "--sun-azimuth", "--turbidity",
                                            "--sun-solid-angle", "--sun-irradiance", "--sky-scale", "--ground",
                                            "--no-sun" };
    static const int values[OPT_COUNT] = { 1, 1, 1, 1, 1, 1, 1, 3, 0 };
    int seen[OPT_COUNT] = { 0 };
    int i, k, c;
    memset(o, 0, sizeof *o);
    o->width = 512;
    o->height = 256;
    o->elevation = 38;
    o->azimuth = 45;
    o->turbidity = 3;
    o->solid_angle = REAL_SUN_SOLID_ANGLE;
    o->scale = 1;
    for (i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            exit(0);
        }
        if (a[0] != '-') {
            if (o->out) fail_usage("more than one output path ('%s' and '%s')", o->out, a);
            o->out = a;
            continue;
        }
        for (k = 0; k < OPT_COUNT && strcmp(a, names[k]); ++k) {}
        if (k == OPT_COUNT) fail_usage("unknown option '%s'", a);
        if (seen[k]++) fail_usage("%s given twice", a);
        if (i + values[k] >= argc) fail_usage(values[k] == 1 ? "%s needs a value" : "%s needs three values, R G B", a);
        switch (k) {
        case OPT_SIZE: parse_size(argv[++i], &o->width, &o->height); break;
        case OPT_ELEVATION: o->elevation = parse_real(a, argv[++i], 0, 0, 90, 0, "0..90 degrees"); break;
        case OPT_AZIMUTH: o->azimuth = parse_real(a, argv[++i], -1e6, 0, 1e6, 0, "-1e6..1e6 degrees"); break;
        case OPT_TURBIDITY:
            o->turbidity = parse_real(a, argv[++i], 2, 0, 10, 0, "2..10, the range the model was fitted to");
            break;
        case OPT_SOLID_ANGLE:
            o->solid_angle = parse_real(a, argv[++i], 1e-8, 0, 2.0 * SKY_PI, 1, "1e-8 sr up to 2 pi sr exclusive");
            o->have_solid_angle = 1;
            break;
        case OPT_IRRADIANCE:
            o->irradiance = parse_real(a, argv[++i], 0, 1, 1e30, 0, "> 0 and at most 1e30");
            o->have_irradiance = 1;
            break;
        case OPT_SCALE: o->scale = parse_real(a, argv[++i], 0, 1, 1e30, 0, "> 0 and at most 1e30"); break;
        case OPT_GROUND:
            for (c = 0; c < 3; ++c) o->ground[c] = parse_real(a, argv[++i], 0, 0, 1e30, 0, ">= 0 and at most 1e30");
            o->have_ground = 1;
            break;
        default: o->no_sun = 1; break;
        }
    }
    if (!o->out) fail_usage("no output path (OUT.pfm or OUT.exr)");
    if (o->no_sun && (o->have_solid_angle || o->have_irradiance))
        fail_usage("--no-sun with %s: there is no sun to size or light",
                   o->have_solid_angle ? "--sun-solid-angle" : "--sun-irradiance");
    if (ends_with_ci(o->out, ".exr")) o->exr = 1;
    else if (!ends_with_ci(o->out, ".pfm"))
        fail_usage("%s: unknown output format (the name must end in .pfm or .exr)", o->out);
#ifndef PDFTRACE_OPENEXR
    if (o->exr) fail_usage("%s: this ptsky was built without OpenEXR; write .pfm (or rebuild with OpenEXR)", o->out);
#endif
}

int main(int argc, char **argv)
{
    options o;
    sky_model m;
    pt_image img;
    float *sky;
    double *area = NULL, ground[3], theta_s, phi_s, alpha = 0, sun_L = 0, sun_E = 0, e_sky[3] = { 0, 0, 0 };
    double e_sky_Y, horizon_Y, map_power[3] = { 0, 0, 0 }, disc_power = 0, rel = 0;
    size_t npix, i;
    int x, y, c, rc;
    char err[1024];

    parse_args(argc, argv, &o);
    theta_s = (90.0 - o.elevation) * SKY_PI / 180.0;
    phi_s = fmod(o.azimuth, 360.0);
    if (phi_s < 0) phi_s += 360.0;
    phi_s *= SKY_PI / 180.0;
    sky_init(&m, o.turbidity, theta_s, phi_s, o.scale);
    horizon_Y = horizon_mean_luminance(&m);
    if (o.have_ground) memcpy(ground, o.ground, sizeof ground);
    else ground[0] = ground[1] = ground[2] = DEFAULT_GROUND_FRACTION * horizon_Y;
    if (!o.no_sun) {
        /* Omega = 2 pi (1 - cos alpha) = 4 pi sin^2(alpha / 2); a uniform disc of radiance L gives
           E = L pi sin^2 alpha = L Omega (1 - Omega / (4 pi)) on a surface facing it */
        alpha = 2.0 * asin(sqrt(o.solid_angle / (4.0 * SKY_PI)));
        sun_E = o.have_irradiance ? o.irradiance : DEFAULT_SUN_RATIO * sky_irradiance_analytic(&m);
        sun_L = sun_E / (o.solid_angle * (1.0 - o.solid_angle / (4.0 * SKY_PI)));
        disc_power = sun_L * o.solid_angle;
    }

    npix = (size_t)o.width * (size_t)o.height;
    memset(&img, 0, sizeof img);
    img.width = o.width;
    img.height = o.height;
    img.rgb = (float *)malloc(3 * npix * sizeof(float));
    sky = (float *)malloc(3 * npix * sizeof(float));
    if (!o.no_sun) area = (double *)calloc(npix, sizeof(double));
    if (!img.rgb || !sky || (!o.no_sun && !area)) {
        fprintf(stderr, "ptsky: out of memory for a %dx%d map\n", o.width, o.height);
        return 1;
    }
    render_sky(&m, ground, sky, o.width, o.height);
    memcpy(img.rgb, sky, 3 * npix * sizeof(float));

    /* the sun: each pixel's mean radiance over its solid angle, L x overlap / pixel solid angle; a disc
       reaching below the horizon is drawn whole (the ground is a backdrop, not an occluder) */
    if (!o.no_sun) {
        sun_areas(area, o.width, o.height, theta_s, phi_s, alpha);
        for (y = 0; y < o.height; ++y) {
            double pix_sa = 2.0 * SKY_PI / o.width * (row_z(y, o.height) - row_z(y + 1, o.height));
            for (x = 0; x < o.width; ++x) {
                size_t p = (size_t)y * o.width + x;
                if (area[p] > 0)
                    for (c = 0; c < 3; ++c) img.rgb[3 * p + c] = (float)(sky[3 * p + c] + sun_L * area[p] / pix_sa);
            }
        }
    }
    for (i = 0; i < 3 * npix; ++i)
        if (!isfinite(img.rgb[i])) {
            fprintf(stderr, "ptsky: a pixel overflows a float (sun radiance %g); lower --sun-irradiance, "
                            "--sky-scale or --ground\n", sun_L);
            return EXIT_USAGE;
        }

    /* from the stored floats: the sky's irradiance on an upward plane (integral of L cos theta dw
       over each pixel's part above the horizon) and the sun's power (sum of (map - sky) x pixel solid angle) */
    for (y = 0; y < o.height; ++y) {
        double zt = row_z(y, o.height), zb = row_z(y + 1, o.height);
        double pix_sa = 2.0 * SKY_PI / o.width * (zt - zb);
        double at = zt > 0 ? zt : 0, ab = zb > 0 ? zb : 0;
        double cos_w = 2.0 * SKY_PI / o.width * 0.5 * (at * at - ab * ab);
        for (x = 0; x < o.width; ++x) {
            size_t p = (size_t)y * o.width + x;
            for (c = 0; c < 3; ++c) {
                e_sky[c] += sky[3 * p + c] * cos_w;
                map_power[c] += ((double)img.rgb[3 * p + c] - (double)sky[3 * p + c]) * pix_sa;
            }
        }
    }
    e_sky_Y = 0.2126 * e_sky[0] + 0.7152 * e_sky[1] + 0.0722 * e_sky[2];
    if (!o.no_sun) {
        int worst = 0; /* the sun is white: every channel holds the disc's power */
        for (c = 0; c < 3; ++c)
            if (fabs(map_power[c] / disc_power - 1.0) > fabs(map_power[worst] / disc_power - 1.0)) worst = c;
        rel = fabs(map_power[worst] / disc_power - 1.0);
        printf("sun power check: map %.9g, disc %.9g (radiance %.9g x %.6g sr), relative error %.2e (bound %.0e): %s\n",
               map_power[worst], disc_power, sun_L, o.solid_angle, rel, SUN_POWER_TOLERANCE,
               rel < SUN_POWER_TOLERANCE ? "ok" : "FAILED");
        if (!(rel < SUN_POWER_TOLERANCE)) {
            fprintf(stderr, "ptsky: the sun's power in the map is off by %.2e relative; nothing written\n", rel);
            return 1;
        }
    }

    if (o.exr) {
#ifdef PDFTRACE_OPENEXR
        pt_exr_options eo;
        eo.pixel_type = PT_EXR_FLOAT; /* half's largest value, 65504, would clip the sun */
        eo.compression = PT_EXR_ZIP;
        rc = pt_write_exr(o.out, &img, &eo, err, sizeof err);
#else
        rc = PT_ERROR_UNSUPPORTED;
        snprintf(err, sizeof err, "%s: built without OpenEXR", o.out);
#endif
    } else {
        rc = pt_write_pfm_ex(o.out, &img, err, sizeof err);
    }
    if (rc != PT_OK) {
        fprintf(stderr, "ptsky: %s\n", err);
        return 1;
    }
    printf("ptsky: %s %dx%d, turbidity %g, sun direction (%.6f, %.6f, %.6f) (elevation %g, azimuth %g), ", o.out,
           o.width, o.height, o.turbidity, m.sun[0], m.sun[1], m.sun[2], o.elevation, o.azimuth);
    if (o.no_sun) printf("no sun");
    else printf("sun irradiance %.6g (facing it)", sun_E);
    printf(", sky irradiance %.6g (horizontal plane, luminance; RGB %.6g %.6g %.6g)", e_sky_Y, e_sky[0], e_sky[1],
           e_sky[2]);
    if (!o.no_sun) printf(", ratio %.4g", e_sky_Y > 0 ? sun_E / e_sky_Y : 0.0);
    printf(", ground %.6g %.6g %.6g\n", ground[0], ground[1], ground[2]);
    free(area);
    free(sky);
    free(img.rgb);
    return 0;
}
