/* pdftrace.h - a Monte Carlo path tracer built around probability density functions.
   Single-file C99 library. No warranty implied; use at your own risk.

   ABOUT
   =====
   pdftrace renders images by path tracing and is organised around one idea: for an
   integral F = \int f, the estimator f(X)/p(X) with X ~ p is unbiased for any density p
   that is positive wherever f is non-zero, and its variance (\int f^2/p - F^2)/N falls as
   p approaches f/F. At a surface the tracer samples a direction w_i from a PDF p and
   weights the incoming radiance by A * pScatter(w_i) * L_i(w_i) / p(w_i) (A = albedo).
   A weighted average of PDFs (weights summing to one) is again a PDF, so the material's
   PDF can be mixed with a PDF aimed at the lights; the density of such a mixture is
   sum_k w_k p_k(w), never the density of the component that happened to be chosen.

   PDFs are public values (pt_pdf): every PDF the renderer uses can be sampled and
   evaluated by user code, mixed, and replaced by user callbacks.

   BUILDING
   ========
   In exactly one C or C++ file:
       #define PDFTRACE_IMPLEMENTATION
       #include "pdftrace.h"
   Other files include the header without the macro. Link with -lm and -pthread.
   The implementation wants POSIX clocks and threads: if it is the first header the file
   includes, it defines _POSIX_C_SOURCE itself; otherwise compile that file with
   -D_POSIX_C_SOURCE=200809L (or a GNU dialect). Without a monotonic clock, timings fall
   back to clock().

   OPTIONS (define before including the implementation)
   =======
   PDFTRACE_NO_THREADS     build without pthreads; rendering runs on the calling thread
                           unless the host passes its own parallel-for (pt_render_desc).
   PDFTRACE_STATIC         make every public function static to the implementing file.
   PT_MALLOC(sz), PT_REALLOC(p,sz), PT_FREE(p)   override the allocator (all three).
   PT_ASSERT(x)            override assert() (used only for internal invariants; API
                           misuse returns an error code, it never asserts).

   USAGE
   =====
       pt_scene *s = pt_scene_create();
       int white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
       int light = pt_scene_add_emitter(s, pt_v3(15, 15, 15), 0);
       pt_scene_add_quad(s, pt_v3(-5,0,-5), pt_v3(10,0,0), pt_v3(0,0,10), white);   (floor)
       pt_scene_add_quad(s, pt_v3(-1,4,1), pt_v3(2,0,0), pt_v3(0,0,-2), light);    (emits along u x v = -y)
       pt_scene_add_sphere(s, pt_v3(0,1,0), 1, white);
       if (pt_scene_commit(s) != PT_OK) puts(pt_scene_error_message(s));
       pt_render_desc d = {0};                 (zero means "default" for every field)
       d.width = 320; d.height = 240; d.samples_per_pixel = 64;
       d.camera.look_from = pt_v3(0, 2, -8); d.camera.look_at = pt_v3(0, 1, 0);
       pt_image img = {0}; pt_render_stats st;
       pt_render_image(s, &d, &img, &st);
       pt_write_ppm("out.ppm", &img);
       pt_image_free(&img); pt_scene_destroy(s);

   CONVENTIONS
   ===========
   Right-handed world; the camera's screen right is forward x up. Image row 0 is the top.
   A quad is Q + a*u + b*v, a, b in [0,1]; its normal (and emitting side) is u x v.
   A triangle's normal is (b-a) x (c-a). A sphere's normal points outwards.
   Radiance values are linear RGB. Public functions return PT_OK (0) or a negative
   pt_result code; functions that create something return its id (>= 0) or an error code.

   SECTIONS (in the order data flows)
   ========
   1. Math: vectors, rays, transforms, orthonormal basis, random numbers
   2. Sampling and PDFs
   3. Geometry and scenes
   4. Materials and textures
   5. BVH
   6. Camera
   7. Integrator (strategies)
   8. Rendering (tiles, threads, passes, statistics)
   9. Output (framebuffer, PFM and PPM writers)

   SKIPPING WORK A SCENE DOES NOT NEED
   ===================================
   pt_scene_commit records what a scene contains (pt_scene_info.features). The integrator
   then skips work that cannot change the estimate:
   - no emitters: no light selection, no light sampling, no shadow rays; the mixture
     strategy samples the material PDF alone (the light component has no mass).
   - exactly one emitter: no light selection (no random number, no CDF search).
   - a delta (perfectly specular) vertex: no light PDF, no shadow ray; the path follows
     the specular direction and counts emission it hits at full weight.
   - only delta materials in the scene: no light sampling anywhere.
   - one-sided emitters facing away from the shading point (single-emitter scenes):
     the light component is dropped from the mixture for that vertex.
   - no textures: albedo is read directly from the material.
*/
#ifndef PDFTRACE_H
#define PDFTRACE_H

#include <stddef.h>
#include <stdint.h>
#include <math.h>

#define PDFTRACE_VERSION_MAJOR 0
#define PDFTRACE_VERSION_MINOR 1
#define PDFTRACE_VERSION_PATCH 0

#ifndef PTDEF
#ifdef PDFTRACE_STATIC
#define PTDEF static
#else
#define PTDEF extern
#endif
#endif

#if defined(__cplusplus)
#define PT_INLINE static inline
#elif defined(__STDC_VERSION__) && __STDC_VERSION__ >= 199901L
#define PT_INLINE static inline
#else
#define PT_INLINE static
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Return codes. pt_result_string gives a short English description. */
typedef enum pt_result {
    PT_OK = 0,
    PT_ERROR_INVALID_ARGUMENT = -1, /* a NULL pointer, a non-finite value, a bad id ... */
    PT_ERROR_OUT_OF_MEMORY = -2,
    PT_ERROR_IO = -3,               /* a file could not be written */
    PT_ERROR_INVALID_STATE = -4,    /* e.g. rendering a scene that was not committed */
    PT_ERROR_CANCELLED = -5,        /* the render was cancelled; the film holds the passes done */
    PT_ERROR_THREAD = -6,           /* a thread could not be started */
    PT_ERROR_UNSUPPORTED = -7       /* e.g. a sphere under a non-uniform scale */
} pt_result;

PTDEF const char *pt_result_string(int code);

/* ==========================================================================================
   1. MATH: vectors and colours, rays, affine transforms, orthonormal basis, random numbers
   ========================================================================================== */

typedef struct pt_vec3 { float x, y, z; } pt_vec3;
typedef pt_vec3 pt_color; /* linear RGB in x, y, z */

PT_INLINE pt_vec3 pt_v3(float x, float y, float z) { pt_vec3 r; r.x = x; r.y = y; r.z = z; return r; }
PT_INLINE pt_vec3 pt_add(pt_vec3 a, pt_vec3 b) { return pt_v3(a.x + b.x, a.y + b.y, a.z + b.z); }
PT_INLINE pt_vec3 pt_sub(pt_vec3 a, pt_vec3 b) { return pt_v3(a.x - b.x, a.y - b.y, a.z - b.z); }
PT_INLINE pt_vec3 pt_mul(pt_vec3 a, pt_vec3 b) { return pt_v3(a.x * b.x, a.y * b.y, a.z * b.z); }
PT_INLINE pt_vec3 pt_scale(pt_vec3 a, float s) { return pt_v3(a.x * s, a.y * s, a.z * s); }
PT_INLINE pt_vec3 pt_neg(pt_vec3 a) { return pt_v3(-a.x, -a.y, -a.z); }
PT_INLINE pt_vec3 pt_madd(pt_vec3 a, pt_vec3 b, float s) { return pt_v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s); }
PT_INLINE float pt_dot(pt_vec3 a, pt_vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
PT_INLINE pt_vec3 pt_cross(pt_vec3 a, pt_vec3 b)
{
    return pt_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
PT_INLINE float pt_length2(pt_vec3 a) { return pt_dot(a, a); }
PT_INLINE float pt_length(pt_vec3 a) { return sqrtf(pt_dot(a, a)); }
/* Returns the zero vector for a zero-length input (never NaN from a finite input). */
PT_INLINE pt_vec3 pt_normalize(pt_vec3 a)
{
    float l2 = pt_dot(a, a);
    return l2 > 0.0f ? pt_scale(a, 1.0f / sqrtf(l2)) : pt_v3(0.0f, 0.0f, 0.0f);
}
PT_INLINE float pt_max_component(pt_vec3 a)
{
    float m = a.x > a.y ? a.x : a.y;
    return m > a.z ? m : a.z;
}

typedef struct pt_ray {
    pt_vec3 origin;
    pt_vec3 dir;       /* need not be unit length for intersection queries; t is in units of dir */
} pt_ray;

PT_INLINE pt_vec3 pt_ray_at(pt_ray r, float t) { return pt_madd(r.origin, r.dir, t); }

/* Offsets a surface point p along the geometric normal n, to the side of w, far enough that a
   ray leaving from the result cannot hit the surface it left, yet close enough not to skip
   nearby geometry (Waechter & Binder, "A Fast and Robust Method for Avoiding
   Self-Intersection", Ray Tracing Gems ch. 6, 2019). */
PTDEF pt_vec3 pt_offset_ray_origin(pt_vec3 p, pt_vec3 n, pt_vec3 w);

/* Affine transform: a 3x4 row-major matrix m, p' = M p + t (t = column 3). */
typedef struct pt_transform { float m[3][4]; } pt_transform;

PTDEF pt_transform pt_transform_identity(void);
PTDEF pt_transform pt_transform_translate(pt_vec3 t);
PTDEF pt_transform pt_transform_scale(pt_vec3 s);
PTDEF pt_transform pt_transform_rotate(pt_vec3 axis, float degrees); /* right-handed, about axis through 0 */
PTDEF pt_transform pt_transform_rotate_y(float degrees);
PTDEF pt_transform pt_transform_mul(pt_transform a, pt_transform b); /* a * b: applies b, then a */
PTDEF pt_vec3 pt_transform_point(const pt_transform *t, pt_vec3 p);
PTDEF pt_vec3 pt_transform_vector(const pt_transform *t, pt_vec3 v);
/* Normals transform by the inverse transpose; returns PT_ERROR_INVALID_ARGUMENT if singular. */
PTDEF int pt_transform_normal(const pt_transform *t, pt_vec3 n, pt_vec3 *out);

/* Orthonormal basis (s, t, n), right-handed, built branch-free from a unit normal
   (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 6(1), 2017). */
typedef struct pt_onb { pt_vec3 s, t, n; } pt_onb;

PTDEF pt_onb pt_onb_from_normal(pt_vec3 n);
PT_INLINE pt_vec3 pt_onb_to_world(const pt_onb *b, pt_vec3 l)
{
    return pt_v3(b->s.x * l.x + b->t.x * l.y + b->n.x * l.z,
                 b->s.y * l.x + b->t.y * l.y + b->n.y * l.z,
                 b->s.z * l.x + b->t.z * l.y + b->n.z * l.z);
}
PT_INLINE pt_vec3 pt_onb_to_local(const pt_onb *b, pt_vec3 w)
{
    return pt_v3(pt_dot(w, b->s), pt_dot(w, b->t), pt_dot(w, b->n));
}

/* PCG32 random number generator (O'Neill, "PCG: A Family of Simple Fast Space-Efficient
   Statistically Good Algorithms for Random Number Generation", 2014): 64-bit LCG state,
   XSH-RR output, 2^63 selectable streams. */
typedef struct pt_rng { uint64_t state, inc; } pt_rng;

PT_INLINE uint32_t pt_rng_u32(pt_rng *r)
{
    uint64_t old = r->state;
    uint32_t xorshifted, rot;
    r->state = old * 6364136223846793005ULL + r->inc;
    xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((0u - rot) & 31u));
}
/* Uniform float in [0, 1): the top 24 bits, so 1.0 is never returned. */
PT_INLINE float pt_rng_float(pt_rng *r) { return (float)(pt_rng_u32(r) >> 8) * (1.0f / 16777216.0f); }
PTDEF void pt_rng_seed(pt_rng *r, uint64_t seed, uint64_t stream);
/* The stream of one camera sample: a pure function of (seed, pixel index, sample index), so
   an image is bit-identical whatever the thread count or tile order. */
PTDEF pt_rng pt_rng_for_sample(uint64_t seed, uint32_t pixel, uint32_t sample);

/* ==========================================================================================
   2. SAMPLING AND PDFs
   A pt_pdf is a density over directions (solid angle, sr^-1) at a point. Build one with the
   constructors below, then draw from it with pt_pdf_sample and evaluate it with
   pt_pdf_value; the two agree (the density returned with a sample equals pt_pdf_value of
   that direction). Mixtures and the scene's light PDF keep pointers: the components, the
   weights and the scene must outlive the pt_pdf.
   ========================================================================================== */

typedef enum pt_pdf_type {
    PT_PDF_NONE = 0,
    PT_PDF_UNIFORM_SPHERE,     /* 1/(4 pi) everywhere */
    PT_PDF_COSINE_HEMISPHERE,  /* cos(theta)/pi about a normal */
    PT_PDF_SPHERE_LIGHT,       /* towards a sphere, by solid angle (cone); by area from inside */
    PT_PDF_QUAD_LIGHT,         /* towards a parallelogram, area sampling converted to solid angle */
    PT_PDF_TRIANGLE_LIGHT,     /* towards a triangle, area sampling converted to solid angle */
    PT_PDF_SCENE_LIGHTS,       /* all emitters of a committed scene, each picked by power */
    PT_PDF_MATERIAL,           /* a non-delta material's scattering PDF */
    PT_PDF_MIXTURE,            /* sum_k w_k p_k */
    PT_PDF_CALLBACK            /* user-defined */
} pt_pdf_type;

struct pt_pdf;
struct pt_scene;

/* User-defined PDF. sample: write a direction (unit length) and its density, return 1; return
   0 when no sample can be drawn. value: the density of a unit direction (0 where none). */
typedef int (*pt_pdf_sample_fn)(void *user, pt_rng *rng, pt_vec3 *dir, float *pdf);
typedef float (*pt_pdf_value_fn)(void *user, pt_vec3 dir);

typedef struct pt_pdf {
    pt_pdf_type type;
    pt_vec3 origin;        /* the shading point (light PDFs) */
    union {
        struct { pt_onb basis; } cosine;
        struct { pt_vec3 center; float radius; int two_sided; } sphere;
        struct { pt_vec3 q, u, v; int two_sided; } quad;
        struct { pt_vec3 a, b, c; int two_sided; } triangle;
        struct { const struct pt_scene *scene; } lights;
        struct { const struct pt_scene *scene; int material; pt_vec3 normal, wo; } material;
        struct { int count; const struct pt_pdf *components; const float *weights; } mixture;
        struct { void *user; pt_pdf_sample_fn sample; pt_pdf_value_fn value; } callback;
    } as;
} pt_pdf;

PTDEF pt_pdf pt_pdf_uniform_sphere(void);
PTDEF pt_pdf pt_pdf_cosine_hemisphere(pt_vec3 unit_normal);
/* A sphere light seen from origin. One-sided spheres emit outwards only, so their density is
   zero from inside; two-sided ones are sampled by area from inside or on the surface. */
PTDEF pt_pdf pt_pdf_sphere_light(pt_vec3 origin, pt_vec3 center, float radius, int two_sided);
/* One-sided quads and triangles emit on the side of their normal; seen from behind, their
   density is zero everywhere and sampling fails (returns 0). */
PTDEF pt_pdf pt_pdf_quad_light(pt_vec3 origin, pt_vec3 q, pt_vec3 u, pt_vec3 v, int two_sided);
PTDEF pt_pdf pt_pdf_triangle_light(pt_vec3 origin, pt_vec3 a, pt_vec3 b, pt_vec3 c, int two_sided);
/* All emitters of a committed scene: light i is picked with probability P_i proportional to
   its power (mean radiance x area x pi, x2 if two-sided); value = sum_i P_i p_i(dir). Lights
   facing away from origin have no density, so the PDF may integrate to less than one there;
   sampling them fails (returns 0), which keeps every estimator that uses it unbiased. */
PTDEF pt_pdf pt_pdf_scene_lights(const struct pt_scene *scene, pt_vec3 origin);
/* The scattering PDF of material `material` at a surface with unit normal `normal` (facing the
   viewer is not required), for outgoing direction wo (unit, pointing away from the surface).
   Delta materials have no PDF: sampling returns 0 and value is 0. */
PTDEF pt_pdf pt_pdf_material(const struct pt_scene *scene, int material, pt_vec3 normal, pt_vec3 wo);
/* Weights must be >= 0 and sum to 1 (within 1e-4); pt_pdf_validate checks it. */
PTDEF pt_pdf pt_pdf_mixture(int count, const pt_pdf *components, const float *weights);
PTDEF pt_pdf pt_pdf_callback(void *user, pt_pdf_sample_fn sample, pt_pdf_value_fn value);

/* PT_OK, or PT_ERROR_INVALID_ARGUMENT for a malformed PDF (bad weights, NULL callbacks,
   non-finite parameters, an uncommitted scene ...). */
PTDEF int pt_pdf_validate(const pt_pdf *pdf);
/* Draws a unit direction; *pdf receives pt_pdf_value of it (for a mixture: sum_k w_k p_k).
   Returns 1 on success, 0 when no direction could be drawn (then *dir and *pdf are zero). */
PTDEF int pt_pdf_sample(const pt_pdf *pdf, pt_rng *rng, pt_vec3 *dir, float *pdf_value);
/* The density of unit direction dir, in sr^-1. */
PTDEF float pt_pdf_value(const pt_pdf *pdf, pt_vec3 dir);

/* Warping functions from [0,1)^2, each with the density it produces. */
PTDEF pt_vec3 pt_sample_uniform_sphere(float u1, float u2);                  /* 1/(4 pi) */
PTDEF pt_vec3 pt_sample_cosine_hemisphere(float u1, float u2);               /* z/pi, z up */
PTDEF void pt_sample_concentric_disk(float u1, float u2, float *x, float *y); /* Shirley & Chiu 1997 */

/* ==========================================================================================
   3. GEOMETRY AND SCENES
   A scene owns materials, textures and shapes. Shapes are added under the scene's current
   transform (pt_scene_set_transform), which is applied to their geometry when they are
   added: an instanced emitter is an emitter in world space and is sampled exactly. Add
   everything, then pt_scene_commit (builds the BVH and the light table); change the scene
   and it must be committed again before it is rendered.
   ========================================================================================== */

typedef struct pt_scene pt_scene;

/* Scene features recorded at commit (pt_scene_info.features). */
enum {
    PT_FEATURE_EMITTERS        = 1 << 0,  /* at least one emitting shape */
    PT_FEATURE_SINGLE_EMITTER  = 1 << 1,  /* exactly one */
    PT_FEATURE_TWO_SIDED_EMITTERS = 1 << 2,
    PT_FEATURE_NON_DELTA       = 1 << 3,  /* some material has a scattering PDF */
    PT_FEATURE_DELTA           = 1 << 4,  /* some material is perfectly specular */
    PT_FEATURE_DIELECTRICS     = 1 << 5,
    PT_FEATURE_TEXTURES        = 1 << 6,
    PT_FEATURE_SPHERES         = 1 << 7,
    PT_FEATURE_QUADS           = 1 << 8,
    PT_FEATURE_TRIANGLES       = 1 << 9,
    PT_FEATURE_MESHES          = 1 << 10,
    PT_FEATURE_SHADING_NORMALS = 1 << 11, /* some mesh has per-vertex normals */
    PT_FEATURE_TRANSFORMS      = 1 << 12  /* some shape was added under a non-identity transform */
};

typedef struct pt_scene_info {
    unsigned features;            /* PT_FEATURE_* */
    int committed;                /* 1 when committed and unchanged since */
    uint32_t primitive_count;     /* spheres + quads + triangles (mesh triangles included) */
    uint32_t sphere_count, quad_count, triangle_count, mesh_count;
    uint32_t emitter_count;       /* emitting primitives: each is one light */
    uint32_t material_count, texture_count;
    uint32_t degenerate_triangles_skipped; /* zero-area mesh triangles left out */
    uint32_t bvh_node_count, bvh_max_depth;
    double total_emitted_power;   /* sum of light powers (W, in radiance x area x sr units) */
    pt_vec3 bounds_min, bounds_max;
} pt_scene_info;

PTDEF pt_scene *pt_scene_create(void);      /* NULL when out of memory */
PTDEF void pt_scene_destroy(pt_scene *scene);
/* The last error a scene function reported, with detail ("quad 3: u and v are parallel").
   Never NULL; "" when there was none. */
PTDEF const char *pt_scene_error_message(const pt_scene *scene);

/* Applies to every shape added afterwards; NULL resets to the identity. Spheres need a
   similarity transform (rotation, translation, uniform scale): a sphere added under any
   other transform fails with PT_ERROR_UNSUPPORTED. */
PTDEF int pt_scene_set_transform(pt_scene *scene, const pt_transform *transform);

/* Shapes. Each returns the index of its first primitive (>= 0) or an error code. */
PTDEF int pt_scene_add_sphere(pt_scene *scene, pt_vec3 center, float radius, int material);
PTDEF int pt_scene_add_quad(pt_scene *scene, pt_vec3 q, pt_vec3 u, pt_vec3 v, int material);
PTDEF int pt_scene_add_triangle(pt_scene *scene, pt_vec3 a, pt_vec3 b, pt_vec3 c, int material);
/* Axis-aligned box [lo, hi] as six outward-facing quads (then the current transform). */
PTDEF int pt_scene_add_box(pt_scene *scene, pt_vec3 lo, pt_vec3 hi, int material);

typedef struct pt_mesh_desc {
    const float *positions;      /* 3 floats per vertex */
    uint32_t vertex_count;
    const uint32_t *indices;     /* 3 per triangle, counter-clockwise seen from the front */
    uint32_t triangle_count;
    const float *normals;        /* optional: 3 floats per vertex, interpolated for shading */
    int material;
} pt_mesh_desc;
/* Copies the data. Zero-area triangles are skipped (counted in pt_scene_info). */
PTDEF int pt_scene_add_mesh(pt_scene *scene, const pt_mesh_desc *mesh);

PTDEF int pt_scene_commit(pt_scene *scene);
PTDEF int pt_scene_get_info(const pt_scene *scene, pt_scene_info *info);

/* A ray-surface intersection. */
typedef struct pt_hit {
    float t;                  /* ray parameter of the hit */
    pt_vec3 point;
    pt_vec3 geometric_normal; /* unit, the shape's own orientation (not flipped to the ray) */
    pt_vec3 shading_normal;   /* unit, interpolated for meshes with normals, else geometric */
    int front_face;           /* 1 when the ray arrives on the side the geometric normal points to */
    uint32_t primitive;       /* index as returned by pt_scene_add_* (+ triangle index in a mesh) */
    int material;
} pt_hit;

/* Closest hit with 0 < t < tmax. Returns 1 on a hit, 0 on a miss, an error code on misuse
   (NULL pointers, uncommitted scene). */
PTDEF int pt_scene_intersect(const pt_scene *scene, pt_ray ray, float tmax, pt_hit *hit);
/* 1 when anything is hit with 0 < t < tmax (any hit, early exit). */
PTDEF int pt_scene_occluded(const pt_scene *scene, pt_ray ray, float tmax);
/* Reference closest hit that tests every primitive; for tests and debugging. */
PTDEF int pt_scene_intersect_brute_force(const pt_scene *scene, pt_ray ray, float tmax, pt_hit *hit);

/* Single-primitive intersections: the smallest t in (0, tmax), or return 0.
   Ray/sphere after Haines et al., "Precision Improvements for Ray/Sphere Intersection",
   Ray Tracing Gems ch. 7; ray/triangle is watertight (Woop, Benthin & Wald, JCGT 2(1), 2013). */
PTDEF int pt_intersect_sphere(pt_ray ray, pt_vec3 center, float radius, float tmax, float *t);
PTDEF int pt_intersect_quad(pt_ray ray, pt_vec3 q, pt_vec3 u, pt_vec3 v, float tmax, float *t);
PTDEF int pt_intersect_triangle(pt_ray ray, pt_vec3 a, pt_vec3 b, pt_vec3 c, float tmax, float *t);

/* ==========================================================================================
   4. MATERIALS AND TEXTURES
   Every material may also emit (emission > 0). Lambertian reflection is two-sided (a wall is
   lit and seen from both sides); emission is one-sided (on the side of the geometric normal)
   unless two_sided_emission is set.
   ========================================================================================== */

typedef enum pt_material_type {
    PT_MATERIAL_LAMBERTIAN = 0, /* pScatter = cos/pi, sampled by the cosine PDF */
    PT_MATERIAL_METAL,          /* mirror direction plus fuzz (a ball of radius fuzz around it);
                                   fuzz = 0 is a delta mirror */
    PT_MATERIAL_DIELECTRIC,     /* clear glass: exact unpolarised Fresnel, total internal reflection; delta */
    PT_MATERIAL_EMITTER         /* emits `emission`, reflects nothing */
} pt_material_type;

typedef struct pt_material_desc {
    pt_material_type type;
    pt_color albedo;            /* Lambertian, metal (ignored by dielectric, which is clear) */
    int albedo_texture;         /* 0: use albedo; else an id from pt_scene_add_checker */
    float fuzz;                 /* metal, clamped to [0, 1] */
    float ior;                  /* dielectric index of refraction; 0 means 1.5 */
    pt_color emission;          /* emitted radiance */
    int two_sided_emission;
} pt_material_desc;

PTDEF int pt_scene_add_material(pt_scene *scene, const pt_material_desc *desc); /* id >= 0 */
PTDEF int pt_scene_add_lambertian(pt_scene *scene, pt_color albedo);
PTDEF int pt_scene_add_metal(pt_scene *scene, pt_color albedo, float fuzz);
PTDEF int pt_scene_add_dielectric(pt_scene *scene, float ior);
PTDEF int pt_scene_add_emitter(pt_scene *scene, pt_color radiance, int two_sided);
/* A 3D checker: colour `odd` where floor(x/s)+floor(y/s)+floor(z/s) is odd, `even` elsewhere
   (world space, s = scale > 0). Returns a texture id >= 1. */
PTDEF int pt_scene_add_checker(pt_scene *scene, pt_color even, pt_color odd, float scale);
PTDEF pt_color pt_scene_eval_texture(const pt_scene *scene, int texture, pt_vec3 p);
/* 1 when the material scatters only into delta directions (mirror, glass) or not at all. */
PTDEF int pt_material_is_delta(const pt_scene *scene, int material);

/* Shading point passed to a user guide PDF (see pt_render_desc.guide). */
typedef struct pt_shading_point {
    pt_vec3 position;
    pt_vec3 normal;      /* shading normal, flipped to the side of wo */
    pt_vec3 wo;          /* unit, towards the previous vertex */
    int material;
    int depth;           /* 0 at the first surface seen from the camera */
} pt_shading_point;

/* ==========================================================================================
   5. BVH: built by pt_scene_commit (binned SAH; see the implementation for details).
   ========================================================================================== */

/* ==========================================================================================
   6. CAMERA
   ========================================================================================== */

typedef struct pt_camera_desc {
    pt_vec3 look_from, look_at;
    pt_vec3 up;                 /* zero: (0,1,0) */
    float vfov_degrees;         /* vertical field of view; 0: 40 */
    float lens_radius;          /* 0: pinhole; > 0: thin lens */
    float focus_distance;       /* thin lens; 0: |look_at - look_from| */
} pt_camera_desc;

typedef struct pt_camera {
    pt_vec3 origin, forward, right, up; /* right = forward x up (right-handed) */
    pt_vec3 pixel00, pixel_du, pixel_dv; /* on the focus plane */
    float lens_radius;
    int width, height;
} pt_camera;

PTDEF int pt_camera_init(pt_camera *cam, const pt_camera_desc *desc, int width, int height);
/* The ray through image position (x, y) in pixels (0,0 = top-left corner of the image), with
   lens sample (u1, u2). The direction is unit length. */
PTDEF pt_ray pt_camera_ray(const pt_camera *cam, float x, float y, float u1, float u2);

/* ==========================================================================================
   7. INTEGRATOR: direction-sampling strategies
   ========================================================================================== */

typedef enum pt_strategy {
    /* Next-event estimation plus material sampling, combined by multiple importance sampling
       with the power heuristic (Veach & Guibas 1995). The default. */
    PT_STRATEGY_MIS = 0,
    /* Material PDF only: emission is counted where a scattered ray hits it. */
    PT_STRATEGY_MATERIAL,
    /* Light PDF only for direct light (a shadow ray to a sampled light point, emission hit by
       scattered rays not counted). A light PDF has no density where there is no light, so the
       path continues (indirect light) by the material PDF. At max_depth 1 this is pure light
       sampling. */
    PT_STRATEGY_LIGHT,
    /* One-sample mixture: the direction comes from light_weight * p_lights + (1 - light_weight)
       * p_material, weighted by A * pScatter / (sum of both densities), and is also the path's
       continuation (Shirley, "Ray Tracing: The Rest of Your Life"). */
    PT_STRATEGY_MIXTURE
} pt_strategy;

/* A user guide PDF: fills *out for a shading point and returns 1, or returns 0 to skip the
   guide there. The PDF is mixed into the material side of every strategy with
   pt_render_desc.guide_weight: p_scatter = (1 - g) p_material + g p_guide. */
typedef int (*pt_guide_fn)(void *user, const pt_shading_point *sp, pt_pdf *out);

/* Counters for one or more paths. */
typedef struct pt_path_stats {
    uint64_t camera_rays, bounce_rays, shadow_rays;
    uint64_t nonfinite_samples;   /* samples that were NaN/Inf, counted and replaced by zero */
} pt_path_stats;

/* ==========================================================================================
   8. RENDERING: tiles, threads, progressive passes, statistics
   ========================================================================================== */

typedef struct pt_progress {
    int pass, pass_count;         /* passes done so far, passes planned */
    uint64_t samples_done, samples_total;
    double seconds;
} pt_progress;
/* Called on the rendering thread after each pass. Return non-zero to cancel. */
typedef int (*pt_progress_fn)(void *user, const pt_progress *progress);

/* Host parallel-for: must call job(job_data, i) once for every i in [0, count), from any
   threads, and return when all calls have returned. */
typedef void (*pt_job_fn)(void *job_data, int index);
typedef void (*pt_parallel_for_fn)(void *user, int count, pt_job_fn job, void *job_data);

typedef struct pt_render_desc {
    int width, height;           /* required, > 0 */
    int samples_per_pixel;       /* 0: 16 */
    int samples_per_pass;        /* 0: samples_per_pixel / 16, at least 1 */
    pt_camera_desc camera;
    pt_strategy strategy;        /* 0: PT_STRATEGY_MIS */
    float light_weight;          /* PT_STRATEGY_MIXTURE, in (0, 1]; 0: 0.5 */
    int max_depth;               /* maximum scattering events; 1 = direct light only; 0: 50 */
    int rr_start_depth;          /* Russian roulette from this depth on; 0: 3; < 0: never */
    int threads;                 /* 0: all cores */
    int tile_size;               /* 0: 16 */
    uint64_t seed;
    pt_color background;         /* radiance of rays that leave the scene */
    pt_progress_fn progress;
    void *progress_user;
    const volatile int *cancel;  /* optional: set *cancel non-zero to stop between tiles */
    pt_parallel_for_fn parallel_for; /* optional: the host's own parallel-for */
    void *parallel_for_user;
    pt_guide_fn guide;           /* optional user PDF, see pt_guide_fn */
    void *guide_user;
    float guide_weight;          /* in [0, 1); 0 with a guide: 0.5 */
} pt_render_desc;

typedef struct pt_render_stats {
    uint64_t samples;            /* camera samples taken */
    uint64_t camera_rays, bounce_rays, shadow_rays;
    uint64_t nonfinite_samples;  /* NaN/Inf samples caught, zeroed and counted */
    double seconds;              /* wall clock */
    int passes, threads;
} pt_render_stats;

/* ==========================================================================================
   9. OUTPUT: framebuffer (film), images, writers
   The film accumulates per pixel, in double precision, the sum and the sum of squares of the
   samples and their count. Rendering into a film that already holds samples continues with
   new sample indices, so renders can be resumed and refined.
   ========================================================================================== */

typedef struct pt_film {
    int width, height;
    double *sum;      /* 3 per pixel, row 0 at the top */
    double *sum_sq;   /* 3 per pixel */
    uint32_t *count;  /* samples per pixel */
} pt_film;

typedef struct pt_image {
    int width, height;
    float *rgb;       /* 3 floats per pixel, row 0 at the top, linear radiance */
} pt_image;

PTDEF int pt_film_init(pt_film *film, int width, int height);
PTDEF void pt_film_free(pt_film *film);
PTDEF void pt_film_clear(pt_film *film);
/* Per-pixel mean into *image (allocated or reallocated to the film's size). */
PTDEF int pt_film_resolve(const pt_film *film, pt_image *image);
/* Mean of pixel (x, y) and the variance of that mean (sample variance / count). */
PTDEF int pt_film_pixel(const pt_film *film, int x, int y, pt_color *mean, pt_color *variance_of_mean);

PTDEF int pt_image_init(pt_image *image, int width, int height);
PTDEF void pt_image_free(pt_image *image);

/* Renders desc->samples_per_pixel more samples into every pixel of the film (initialised to
   the desc's size). Returns PT_OK, PT_ERROR_CANCELLED (the film holds what was done) or an
   error. stats may be NULL. */
PTDEF int pt_render(const pt_scene *scene, const pt_render_desc *desc, pt_film *film, pt_render_stats *stats);
/* Convenience: a fresh film, rendered and resolved into *image. */
PTDEF int pt_render_image(const pt_scene *scene, const pt_render_desc *desc, pt_image *image, pt_render_stats *stats);
/* Radiance along one camera ray: one path-traced sample, with the desc's strategy and depth.
   The desc's width, height and camera are not used. stats may be NULL. Non-finite results
   are counted in stats and returned as zero. */
PTDEF pt_color pt_trace_path(const pt_scene *scene, const pt_render_desc *desc, pt_ray ray, pt_rng *rng,
                             pt_path_stats *stats);

/* Writers. Each writes to a temporary file beside the target and renames it into place, so
   a failed write leaves no partial file. PFM: linear float RGB (little-endian, bottom row
   first as the format requires). PPM: binary P6, sRGB-encoded, clamped to [0, 1]. */
PTDEF int pt_write_pfm(const char *path, const pt_image *image);
PTDEF int pt_write_ppm(const char *path, const pt_image *image);
PTDEF float pt_srgb_encode(float linear); /* IEC 61966-2-1 transfer function, clamped */

#ifdef __cplusplus
}
#endif

#endif /* PDFTRACE_H */
