/* stress.h - numerical stress cases for pdftrace (issue 7: scales, tiny lights, grazing rays,
   degenerate input). One implementation (stress_cases.c) serves two programs:
   - `make stress` (tests/stress/stress_main.c): full sizes, prints the table
     case | metric | bound | result and exits non-zero on any failing row;
   - the test runner's section `stress` (tests/test_stress.c): the same cases at small sizes.

   Every statistical row belongs to one family per run: alpha = 0.01 family-wise, Sidak-corrected
   over at most ST_COMPARISONS_FULL (make stress) or ST_COMPARISONS_FAST (make test) comparisons;
   each comparison is a two-sided z-test at 1 - 0.99^(1/K). The last row checks the bound. */
#ifndef PDFTRACE_STRESS_H
#define PDFTRACE_STRESS_H

#define ST_ALPHA 0.01
#define ST_COMPARISONS_FULL 800 /* make stress makes 707 */
#define ST_COMPARISONS_FAST 750 /* the fast run makes 656 */

typedef void (*st_row_fn)(void *user, const char *case_name, const char *metric, const char *bound,
                          const char *result, int pass);

typedef struct st_ctx {
    int full;              /* 1: make stress sizes; 0: the fast sizes of make test */
    int threads;           /* render threads (0: all cores) */
    int max_comparisons;   /* K of the Sidak family */
    double z_bound;        /* per-comparison two-sided z at 1 - (1 - ST_ALPHA)^(1/K) */
    long comparisons;      /* made so far */
    int rows, failed;
    st_row_fn row;
    void *user;
} st_ctx;

void st_init(st_ctx *c, int full, st_row_fn row, void *user);

/* The cases. Each adds rows through c->row. */
void st_scale_sweep(st_ctx *c);      /* 1: images at 10^k, k = -6..6, and at a 1e6 offset; leaks */
void st_spawn(st_ctx *c);            /* 1: rays spawned from sphere/quad/triangle/mesh never re-hit */
void st_tiny_light(st_ctx *c);       /* 2: sphere light 1e-1 .. 1e-6 at fixed intensity */
void st_point_light(st_ctx *c);      /* 2: sphere light r/d 1e-1 .. 1e-9 at constant power: the point light */
void st_watertight(st_ctx *c);       /* 3: rays from inside closed shapes never escape */
void st_edges(st_ctx *c);            /* 3: rays along edges, through vertices, tangent to spheres */
void st_light_geometry(st_ctx *c);   /* 3: shading points on lights, horizon, normals facing away */
void st_guiding(st_ctx *c);         /* path guiding at every scale, memory bound, emission 1e-6 .. 1e6 */
void st_delta_lights(st_ctx *c);     /* point/spot/directional lights at every scale, 0.01-degree cones,
                                        close and grazing */
void st_environment(st_ctx *c);     /* environment maps: 1e6:1 contrast, zeros, suns of 1e-2 .. 1e-4 sr */
void st_microfacet(st_ctx *c);       /* rough conductors: alpha 1e-4 .. 1, 0 .. 90 degrees; bounded weights, no NaN */
void st_plastic(st_ctx *c);          /* rough plastics: alpha 1e-4 .. 1, ior 1.0001 .. 3, 0 .. 90 degrees; albedo <= 1, no NaN */
void st_rough_dielectric(st_ctx *c); /* rough dielectrics: alpha 1e-4 .. 1, ior 1.001 .. 1.5, 0 .. 90 degrees both sides */
void st_degenerate(st_ctx *c);       /* 4: degenerate input: errors or documented finite behaviour */
void st_slivers(st_ctx *c);          /* fuzzed sliver triangles: intersect, brute force, occluded agree; t */
void st_cornell_offset(st_ctx *c); /* 5: the Cornell box moved by 1e5 .. 1e7 renders as at the origin */
void st_family(st_ctx *c);           /* the family-size row (last) */

#endif
