/* test_util.h - statistics, double-precision geometry and the PDF checker shared by the tests.
   Everything here is independent of the library's own math (the library is only called to
   draw samples and evaluate densities), so the tests compare against separate code. */
#ifndef PDFTRACE_TEST_UTIL_H
#define PDFTRACE_TEST_UTIL_H

#include <stdint.h>
#include <math.h>
#include "pdftrace.h"
#include "test.h"

#define TU_PI 3.14159265358979323846

/* ---- double-precision vectors ---- */
typedef struct dv3 { double x, y, z; } dv3;
static inline dv3 dv(double x, double y, double z) { dv3 r; r.x = x; r.y = y; r.z = z; return r; }
static inline dv3 dv_from(pt_vec3 v) { return dv(v.x, v.y, v.z); }
static inline pt_vec3 dv_to(dv3 v) { return pt_v3((float)v.x, (float)v.y, (float)v.z); }
static inline dv3 dadd(dv3 a, dv3 b) { return dv(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline dv3 dsub(dv3 a, dv3 b) { return dv(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline dv3 dscale(dv3 a, double s) { return dv(a.x * s, a.y * s, a.z * s); }
static inline double ddot(dv3 a, dv3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline dv3 dcross(dv3 a, dv3 b)
{
    return dv(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline double dlen(dv3 a) { return sqrt(ddot(a, a)); }
static inline dv3 dnorm(dv3 a) { double l = dlen(a); return l > 0 ? dscale(a, 1.0 / l) : a; }

/* ---- random numbers for the tests (PCG32 from the header; its quality is tested in test_rng.c) ---- */
double tu_rand(pt_rng *r);                 /* uniform double in [0, 1), 53 bits */
dv3 tu_rand_dir(pt_rng *r);                /* uniform on the unit sphere (Archimedes: z uniform) */
void tu_frame(dv3 axis, dv3 *e1, dv3 *e2); /* right-handed (e1, e2, axis), own construction */
/* Uniform direction in the cone 1 - cos(theta) <= omc about axis (omc = 2: whole sphere). */
dv3 tu_sample_cone(pt_rng *r, dv3 axis, double omc);

/* ---- statistics ---- */
/* The closed furnace (pbrt-v4's test): adds to s a sphere of radius 1 at the origin, Lambertian albedo
   0.5 with two-sided emission 0.5, so every point inside sees Le/(1 - rho) = 1, and commits. */
/* The furnace material: Lambertian, albedo 0.5, two-sided emission 0.5 (inside a closed shape of
   it the radiance is Le / (1 - albedo) = 1 everywhere). Returns its index or a negative pt_result. */
int tu_add_furnace_material(pt_scene *s);
int tu_add_closed_furnace(pt_scene *s);
/* Temporary directories for the writer tests: create one under /tmp (1 on success), count its
   entries (names into list if given; -1 if it cannot be read), remove it with its contents. */
int tu_make_tmpdir(char *buf, size_t n);
int tu_dir_entries(const char *dir, char *list, size_t n);
void tu_remove_tree(const char *dir);
unsigned char *tu_read_file(const char *path, long *size); /* malloc'd, NUL-terminated; NULL on failure */
char *tu_read_text(const char *path, size_t *len);          /* the same as text */
/* A render desc with every field zero (defaults) but size, samples per pixel and seed. */
pt_render_desc tu_base_desc(int w, int h, int spp, uint64_t seed);
double tu_sidak(double alpha, int k);      /* per-test level for family-wise alpha over k tests */
double tu_z_two_sided(double alpha);       /* z with P(|Z| > z) = alpha, Z standard normal */
double tu_chi2_sf(double x, double dof);   /* P(X > x) for X ~ chi-square(dof) */

/* z-score of a mean against an exact reference, after allowing a systematic error of `floor`:
   (|mean - want| - floor) / se, or 0 inside the floor; infinite if se == 0 and outside it. The
   render tests use floor = TU_FLOAT_FLOOR * |want|: a float32 renderer starts secondary rays from
   origins offset by ~256 ulps (Waechter & Binder) and so estimates quantities ~1e-5 (relative)
   away from the surface point; near-zero-variance estimators would turn that into huge z. The
   floor is far below every bias these tests exist to catch (>= 1e-3). */
#define TU_FLOAT_FLOOR 1e-4
double tu_z_floor(double mean, double want, double se, double floor);

typedef struct tu_acc { double n, mean, m2; } tu_acc; /* Welford running mean and variance */
void tu_acc_add(tu_acc *a, double x);
double tu_acc_var(const tu_acc *a);        /* unbiased sample variance */
double tu_acc_se(const tu_acc *a);         /* standard error of the mean */

/* ---- closed forms ---- */
/* Solid angle of triangle abc seen from o (Van Oosterom & Strackee, IEEE TBME 30(2), 1983). */
double tu_solid_angle_triangle(dv3 o, dv3 a, dv3 b, dv3 c);
/* Irradiance at x (normal n) from a uniform Lambertian polygon of unit radiance, Lambert's polygon
   formula E = 1/2 sum_i Theta_i (n . g_i), Theta_i = atan2(|u_i x u_i+1|, u_i . u_i+1). The polygon
   must lie above the tangent plane. */
double tu_lambert_polygon(dv3 x, dv3 n, const dv3 *verts, int count);
/* Unpolarised Fresnel reflectance for a dielectric interface (exact, from Snell's law). */
double tu_fresnel_dielectric(double cos_i, double eta_i, double eta_t);

/* Lights as seen by a light-sampling PDF (area or cone sampling converted to solid angle). */
enum { TU_SPHERE, TU_QUAD, TU_TRIANGLE, TU_POINT, TU_SPOT, TU_DIRECTIONAL };
typedef struct tu_light {
    int kind;
    dv3 p0, p1, p2;  /* sphere: center; quad: q, u, v; triangle: a, b, c; point, spot: position (p0),
                        spot: unit axis (p1); directional: unit direction of travel (p1) */
    double radius;
    int two_sided;
    double cutoff, beam; /* spot: degrees */
} tu_light;
/* Density in sr^-1 of the light's sampling PDF at unit direction w from o. *near is set when w is
   within float precision of the support boundary. Returns -1 when the reference is undefined
   (a shading point on the surface of a sphere light, where either model is valid). */
double tu_light_density(const tu_light *L, dv3 o, dv3 w, int *near);
double tu_light_solid_angle(const tu_light *L, dv3 o); /* measure of {density > 0} */
/* 1 when pdftrace samples planar light L from o uniformly in solid angle (pt__sphrect_init,
   pt__sphtri_init): a rectangle with (half its diagonal / the distance to its centre)^2, or a
   triangle with (half its longest edge / the distance to its centroid)^2, at least
   TU_SPHERICAL_FROM (pdftrace.h's PT__SPHERICAL_FROM), and a solid angle in [3e-4, 6.22]. */
#define TU_SPHERICAL_FROM 0.3
int tu_planar_spherical(const tu_light *L, dv3 o);
void tu_light_cone(const tu_light *L, dv3 o, dv3 *axis, double *omc); /* a cone containing it */
double tu_light_area(const tu_light *L);
/* Where the ray o + t w first hits the light (t > 0), or -1. */
double tu_light_hit(const tu_light *L, dv3 o, dv3 w);

/* ---- the PDF checker ----
   For one pt_pdf it checks
   (a) every sample: return value 0/1, unit direction, finite density > 0 equal to pt_pdf_value of
       the direction (relative 1e-4) and to the closed form (relative 1e-3); failed draws give zero
       outputs; no sample outside the cone that contains the support;
   (b) mass: the fraction of successful draws, an importance-sampled Monte Carlo estimate of \int p
       (mean of p/q over directions from a proposal q that covers the support: uniform in the cone,
       or area sampling of an enlarged planar light) and the expected mass agree; the mean of 1/pdf
       over the samples equals the measure of the support;
   (c) shape: a Pearson chi-square test of the sample histogram on a grid over the domain's unit
       square against N * \int_cell p (adaptive midpoint rule, refined at the support boundary);
   and pt_pdf_value against the closed form at the proposal's directions.
   Each case makes TU_PDF_COMPARISONS statistical comparisons at level alpha each. */
typedef double (*tu_density_fn)(const void *ctx, dv3 w, int *near);

/* The set of directions a check works on, as an equal-measure map to the unit square (for the
   histogram), with a proposal density covering it (for the mass estimate). The default is the cone
   (axis, omc) with coordinates ((1 - cos theta)/omc, phi/2pi) and uniform cone sampling. */
typedef struct tu_domain {
    int (*to_unit)(const void *ctx, dv3 w, double *x, double *y);      /* 0: w is outside */
    dv3 (*from_unit)(const void *ctx, double x, double y, double *jac); /* jac = d omega / dx dy */
    double (*propose)(const void *ctx, pt_rng *r, dv3 *w);             /* returns q(w) in sr^-1 */
    const void *ctx;
} tu_domain;
/* A planar light's own parametrisation: (a, b) of a parallelogram, Duffy's map for a triangle; the
   proposal is uniform area sampling of the light enlarged 1.25x about its centroid. Robust for the
   thin slivers that grazing views produce, where a cone histogram has no resolution. */
typedef struct tu_planar_ctx { tu_light L; dv3 o; } tu_planar_ctx;
void tu_planar_domain(tu_domain *d, tu_planar_ctx *ctx, const tu_light *L, dv3 o);

typedef struct tu_pdf_check {
    const char *label;
    const pt_pdf *pdf;
    dv3 axis;
    double omc;              /* cone 1 - cos(theta) <= omc containing the support; 2 = whole sphere */
    const tu_domain *domain; /* NULL: the cone */
    double expected_mass;    /* \int p over the sphere; < 0: unknown */
    double support;          /* solid angle of {p > 0}; <= 0: skip E[1/p] (e.g. infinite variance) */
    tu_density_fn ref;       /* closed form, or NULL */
    const void *ref_ctx;
    long n_samples, n_mass;
    int ns, nphi;            /* chi-square grid; ns = 0 skips the chi-square test */
    uint64_t seed;
    double alpha;            /* per comparison */
    double inv_z;            /* > 0: E[1/p] must lie within inv_z standard errors (3 for the cases of
                                issue 3); 0: at the level alpha like the other comparisons */
    int expect_reject;       /* a deliberately wrong PDF (harness demonstration): recorded as such and
                                not counted in the suite's family of comparisons */
} tu_pdf_check;

/* The most statistical comparisons one checker call makes at level alpha: chi-square, its two
   marginals, success fraction vs mass, Monte Carlo mass vs expected mass, Monte Carlo mass vs
   success fraction, E[1/p]. */
#define TU_PDF_COMPARISONS 7
/* Relative agreement required between the density returned with a sample and pt_pdf_value of the
   sampled direction (docs/accuracy.md: 1e-5 or better). */
#define TU_SAMPLE_VALUE_REL 1e-5
/* Hard failure when pt_pdf_value integrates over the histogram's domain to more than 1 + this (the
   adaptive quadrature is accurate to ~1e-4 on every case of the suite). */
#define TU_MASS_TOL 2e-3

typedef struct tu_pdf_result {
    double chi2_p;           /* 2 when not run */
    double marginal_p;       /* the smaller p of the two marginal chi-squares (2 when not run) */
    double chi2;
    int dof;                 /* -1 when not run */
    double integral;         /* pt_pdf_value integrated over the histogram's domain (NAN: not run) */
    double max_abs_z;        /* over the z comparisons */
    double inv_z;            /* (E[1/p] - support) / se, NAN when not checked */
    double worst_sample_value_rel; /* max relative difference of sample density and pt_pdf_value */
    double success_fraction, mass, inv_pdf_mean;
} tu_pdf_result;

/* ---- the chi-square suite ----
   Every statistical comparison made by a PDF check (tu_check_pdf and the other chi-square tests of
   sampling) belongs to one family: alpha = 0.01 for the whole suite, Sidak-corrected over at most
   TU_SUITE_COMPARISONS comparisons, i.e. each is made at 1 - 0.99^(1/TU_SUITE_COMPARISONS). The
   checker counts the comparisons it makes (tests count their others with tu_suite_count); the
   suite.chi2_table test fails if an unfiltered run made more than the bound, and prints one row
   per chi-square case. */
#define TU_SUITE_ALPHA 0.01
/* 1080: an unfiltered run made 545 before the environment light's 9 cases (62 more: 607), the
   rough conductor's 16 (64 more: 671), the rough plastic's 16 (at most 112 more: 783) and the
   rough dielectric's 32 (at most 7 each: 224 more, 1007); the margin keeps a case or two from
   breaking the bound */
#define TU_SUITE_COMPARISONS 1081
double tu_suite_alpha(void);
void tu_suite_count(int comparisons);
long tu_suite_comparisons(void);

typedef struct tu_chi2_row {
    char label[96];
    long n;                  /* draws */
    int dof;
    double chi2, p, p_marginal, integral, inv_z; /* p_marginal: the smaller of the two marginals' p */
    int has_inv_z, expect_reject, passed;
} tu_chi2_row;
int tu_chi2_row_count(void);
const tu_chi2_row *tu_chi2_row_at(int i);
void tu_chi2_print_table(void);

int tu_check_pdf_(test_ctx *t, const tu_pdf_check *c, tu_pdf_result *res, const char *file, int line);
#define TU_CHECK_PDF(t, c, res) tu_check_pdf_((t), (c), (res), __FILE__, __LINE__)
/* Runs the checker on a deliberately wrong PDF (c->expect_reject is set) into a scratch context:
   returns how many checks failed and copies the first failure's reason into reason[size]. */
int tu_check_pdf_rejects(tu_pdf_check *c, tu_pdf_result *res, char *reason, size_t size);

/* ---- films ---- */
typedef struct tu_region { double mean[3], se[3]; int pixels; } tu_region;
/* Splits the film into rx * ry regions (row-major, region 0 top-left) and computes each region's
   mean and its standard error from pt_film_pixel's per-pixel variance of the mean. */
int tu_film_regions(const pt_film *f, int rx, int ry, tu_region *out);
int tu_film_equal(const pt_film *a, const pt_film *b); /* bit-identical sums, squares, counts, half-buffers, low words */
/* pt_film_init + pt_render, checking PT_OK and zero NaN/Inf samples (st may be NULL). Returns 1 on
   PT_OK; the caller frees the film, as the tests did with their own copies. */
int tu_render_into(test_ctx *t, const pt_scene *s, const pt_render_desc *d, pt_film *film, pt_render_stats *st,
                   const char *what);

/* ---- analytic images: a Lambertian plane lit by one light, direct light only ----
   The plane y = 0 (albedo rho) under one emitter of radiance L (a sphere, a quad or a triangle, all
   wholly above the plane and facing it), seen by a pinhole camera looking straight down from below
   the emitter (so no camera ray meets it). With max_depth 1 the exact outgoing radiance at a plane
   point is rho E / pi (Lambertian receiver), E from Lambert's polygon formula (planar lights) or
   E = pi L sin^2(alpha) cos(theta) (a sphere wholly above the tangent plane, so theta + alpha <= pi/2
   holds everywhere: docs/accuracy.md). A pixel's expectation is the mean of rho E / pi over its
   footprint (the renderer jitters the camera ray uniformly over the pixel): computed by the midpoint
   rule on 8 x 8 camera rays per pixel, hit with the plane in double precision; its error is
   estimated by Richardson's rule from the 4 x 4 rule, |I_8 - I_4| / 3 (midpoint error ~ h^2). */
#define TU_PLANE_MAX_LIGHTS 32
typedef struct tu_plane_scene {
    pt_scene *scene;
    int light_count;
    tu_light light[TU_PLANE_MAX_LIGHTS]; /* the emitters, in double; E adds up (none may shadow another) */
    double radiance[TU_PLANE_MAX_LIGHTS];
    double rho;
    pt_camera_desc camera;
    int width, height;
    double *ref, *qerr;      /* per pixel: the footprint mean of rho E / pi and its quadrature error */
} tu_plane_scene;
/* The standard scenes: one light of radiance 1 over the plane (rho 0.5); kind: TU_SPHERE, TU_QUAD or
   TU_TRIANGLE; two_sided and flip (emit upwards, away from the plane) for planar lights.
   Returns 1 on success. */
int tu_plane_scene_create(tu_plane_scene *ps, int kind, int width, int height);
int tu_plane_scene_create_ex(tu_plane_scene *ps, int kind, int two_sided, int flip, int width, int height);
/* For a scene built by the caller (ps->scene committed, holding the plane y = 0 of albedo ps->rho and
   the ps->light_count lights listed, all above the plane and facing it): sets the camera and
   computes the references. */
int tu_plane_scene_finish(tu_plane_scene *ps, int width, int height);
void tu_plane_scene_destroy(tu_plane_scene *ps);
/* Irradiance at x on the plane y = 0 (normal +y) from a light of radiance Le facing it (for the
   delta lights, Le is the intensity I, W/sr, or the directional light's irradiance E). */
double tu_plane_irradiance(const tu_light *L, double Le, dv3 x);

typedef struct tu_image_stats {
    int pixels, accepted;    /* pixels whose z (beyond the float floor) is within z_pixel */
    double mean_rel;         /* mean over pixels of (mean - ref) / ref */
    double mean_z;           /* mean signed z over pixels */
    double max_abs_z;
    double image_mean, image_ref, image_se, image_z; /* the image's mean pixel value */
    double worst_qerr_over_se; /* reference quadrature error / pixel standard error, worst pixel */
    uint64_t nonfinite;
    double seconds;
    int rc;                  /* pt_render's result */
} tu_image_stats;
/* Renders the scene with d (its width, height, camera and max_depth are set here) into a fresh film
   and compares every pixel (green channel) with its reference: z = (|mean - ref| - floor) / se with
   se from pt_film_pixel's variance of the mean and floor = TU_FLOAT_FLOOR * ref. */
void tu_plane_render_compare(const tu_plane_scene *ps, pt_render_desc *d, double z_pixel, tu_image_stats *out);

/* ---- environment maps (pt_scene_set_environment) ----
   The map's frame: u = atan2(x, -z) / 2pi in [0, 1), v = acos(y) / pi, row 0 at the zenith (+y),
   pixel (x, y) centred on ((x + 1/2) / W, (y + 1/2) / H); world = R map (R a rotation). */
/* The rotation by deg degrees about axis (right-handed, Rodrigues' formula) in double, row-major,
   into R[9], and rounded to float into *xf if xf is not NULL. */
void tu_rotation(dv3 axis, double deg, double *R, pt_transform *xf);
dv3 tu_env_dir(double u, double v);        /* the unit map-frame direction of (u, v) */
void tu_env_uv(dv3 d, double *u, double *v); /* (u, v) of a unit map-frame direction */
/* A procedural sky, w x h linear RGB into img (rgb malloc'd; free with free()): a gradient from a
   blue zenith to a pale horizon (smooth in v), a dim ground below it, and a sun: pixels whose
   centre lies within sun_radius (radians) of the unit map-frame direction sun get sun_radiance
   (x (1, 0.9, 0.7)) added. Returns 1 on success. */
int tu_env_sky(pt_image *img, int w, int h, dv3 sun, double sun_radius, double sun_radiance);
/* The irradiance E = \int L(w) max(0, n . w) dw at a surface of unit world normal n under the
   environment map of committed scene s (w x h pixels, set under the rotation R, map frame to world,
   row-major; NULL: the identity), L the channel (0, 1, 2) of pt_scene_environment_radiance, so the
   reference follows the library's own lookup. Integrated over the map's (u, v) in the patches
   between pixel centres, where the bilinear radiance is smooth (and in the polar caps beyond the
   first and last rows' centres; in parts of at most 1/32 turn for small maps), by k x k
   Gauss-Legendre with k = 5, the v interval at each u split at the horizon (n . w = 0), so that
   every piece is smooth; patches whose four corner pixels are black are skipped. *err (if not
   NULL) = |E_5 - E_3|, the quadrature's error bound. */
double tu_env_irradiance(const pt_scene *s, int w, int h, const double *R, dv3 n, int channel, double *err);

int tu_verbose(void); /* PT_TEST_VERBOSE set: print per-case details */

#endif
