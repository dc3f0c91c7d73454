/* pdftrace.h - a Monte Carlo path tracer built around probability density functions.
   Single-file C99 library. LICENSE: MIT or public domain, your choice (full text at the end of
   this file). No warranty implied; use at your own risk.

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
   back to clock(). Dialects and -march settings give the same images: the header keeps FMA
   contraction out of its implementation. -ffast-math does not keep images bit-identical
   between the integrators and SIMD levels (NaN and Inf are still caught).

   THE HEADER FAMILY
   =================
   Optional parts live in their own single-file headers, each including this one and each
   with its own implementation macro (define it in one file, which may be the same file):
       pdftrace_scene.h   PDFTRACE_SCENE_IMPLEMENTATION   scene files, OBJ meshes, POV-Ray and Mitsuba export
       pdftrace_exr.h     PDFTRACE_EXR_IMPLEMENTATION     OpenEXR output and input (OpenEXRCore)
       pdftrace_png.h     PDFTRACE_PNG_IMPLEMENTATION     PNG output (libpng)
       pdftrace_mpi.h     PDFTRACE_MPI_IMPLEMENTATION     a render split over MPI ranks (section 8's merge hook)

   OPTIONS (define before including the implementation)
   =======
   PDFTRACE_NO_THREADS     build without pthreads; rendering runs on the calling thread
                           unless the host passes its own parallel-for (pt_render_desc).
   PDFTRACE_STATIC         make every public function static to the implementing file.
   PDFTRACE_NO_SIMD        scalar BVH traversal only, even where SSE2 is available (same results;
                           the SSE2 code is compiled on x86-64 and wherever __SSE2__ is defined).
   PDFTRACE_SIMD (environment variable, read at each pt_scene_commit): scalar, sse2, avx2 or
                           avx512 caps the built-in BVH's SIMD level, chosen at run time from what
                           the CPU has (pt_simd_level; pt_simd_set_cap is the same cap in the API).
                           Every level gives the same hits and images bit for bit.
   PDFTRACE_AVX512_WIDTH   children per BVH node at the AVX-512 level: 8 (default, as AVX2) or 16.
   PDFTRACE_NO_WIDE_BVH    no AVX2/AVX-512 code (gcc and clang on x86 compile it by default with
                           per-function target attributes; other compilers never do).
   PDFTRACE_EMBREE         trace rays with Embree 3 (section 5b; include path embree3/,
                           link -lembree3); PDFTRACE_EMBREE4 selects Embree 4 (untested).
                           PDFTRACE_EMBREE_MIN_PRIMS, PDFTRACE_EMBREE_SMALL_PRIMS: AUTO's
                           rule (see pt_scene_set_backend).
   PT_MALLOC(sz), PT_REALLOC(p,sz), PT_FREE(p)   override the allocator (all three).
   PT_ASSERT(x)            override assert() (used only for internal invariants; API
                           misuse returns an error code, it never asserts).

   USAGE
   =====
       pt_scene *s = pt_scene_create();
       int white = pt_scene_add_lambertian(s, pt_v3(0.73f, 0.73f, 0.73f));
       int light = pt_scene_add_emitter(s, pt_v3(15, 15, 15), 0);
       pt_scene_add_quad(s, pt_v3(-5,0,-5), pt_v3(10,0,0), pt_v3(0,0,10), white);   (floor)
       pt_scene_add_quad(s, pt_v3(-1,4,-1), pt_v3(2,0,0), pt_v3(0,0,2), light);    (emits along u x v = -y)
       pt_scene_add_sphere(s, pt_v3(0,1,0), 1, white);
       pt_light_desc sun = {0};                (optional: lights without a shape, section 4)
       sun.type = PT_LIGHT_DIRECTIONAL; sun.direction = pt_v3(1,-3,1); sun.intensity = pt_v3(2,2,2);
       pt_scene_add_light(s, &sun);
       pt_image sky = {0};                     (optional: an HDR sky, section 4; row 0 the zenith)
       if (pt_read_pfm("sky.pfm", &sky, NULL, 0) == PT_OK) {
           pt_environment_desc env = {0}; env.map = &sky;
           pt_scene_set_environment(s, &env); pt_image_free(&sky);   (the scene keeps a copy)
       }
       if (pt_scene_commit(s) != PT_OK) puts(pt_scene_error_message(s));
       pt_render_desc d = {0};                 (zero means "default" for every field)
       d.width = 320; d.height = 240; d.samples_per_pixel = 64;
       d.camera.look_from = pt_v3(0, 2, -8); d.camera.look_at = pt_v3(0, 1, 0);
       d.sampler = PT_SAMPLER_SOBOL;           (optional: scrambled Sobol points, lower error per
                                               sample than the default independent numbers; section 2)
       pt_image img = {0}; pt_render_stats st;
       if (pt_render_image(s, &d, &img, &st) != PT_OK) puts(st.error);
       pt_write_ppm("out.ppm", &img);
       pt_image_free(&img); pt_scene_destroy(s);

   CONVENTIONS
   ===========
   Right-handed world; the camera's screen right is forward x up. Image row 0 is the top.
   A quad is Q + a*u + b*v, a, b in [0,1]; its normal (and emitting side) is u x v.
   A triangle's normal is (b-a) x (c-a). A sphere's normal points outwards.
   Radiance values are linear RGB. Public functions return PT_OK (0) or a negative
   pt_result code; functions that create something return its id (>= 0) or an error code.
   A failure's one-line message goes where the call's own data is: into the scene for calls
   that build it (pt_scene_error_message), into pt_render_stats.error for a render, into the
   caller's err[err_size] for the file writers and readers (pt_write_*_ex here; the loaders
   and writers of pdftrace_scene.h, pdftrace_exr.h and pdftrace_png.h).
   There is no global or per-thread error state.

   SECTIONS (in the order data flows)
   ========
   The declarations and the implementation below share these numbers and this order; each
   section opens with what it does and why.
   0. Internal types: the scene's private representation (implementation only)
   1. Math: vectors, rays, transforms, orthonormal basis, random numbers
   2. Sampling and PDFs: samplers (independent, Sobol), warps, light and material densities, the
      learned guide (pt_guide)
   3. Geometry and scenes: primitives, intersections, building a scene
   4. Materials and textures
   5. BVH (the built-in traversal)
   5b. Embree traversal (optional: define PDFTRACE_EMBREE; links embree3)
   5c. Commit and ray queries (implementation only; declared in section 3)
   6. Camera
   7. Integrator (strategies, Russian roulette, splitting)
   8. Rendering (tiles, threads, passes, adaptive sampling, guiding's training, splitting a render
      over processes, statistics; the film and images)
   9. Output (sRGB, PFM and PPM writers)
   The measurements behind the implementation's tuned choices: docs/internals.md.

   SKIPPING WORK A SCENE DOES NOT NEED
   ===================================
   pt_scene_commit records what a scene contains (pt_scene_info.features). The integrator
   then skips work that cannot change the estimate. Each skip has a bit in
   pt_render_desc.disable_skips that forces the general path instead (for benchmarks; the
   image keeps its expectation, and "exact" skips give it bit for bit). A skip stays only while
   `make bench` shows that it pays: the 95 % interval of its time ratio (for a skip that changes
   the estimator, of its time ratio at equal error) lies below 1 (bench/README.md, "Skips"; the
   figures: docs/internals.md, "Scene-feature skips"):
   - no emitters: no light selection, no light sampling, no shadow rays; the mixture
     strategy samples the material PDF alone (the light component has no mass).
     PT_SKIP_NO_EMITTERS.
   - a delta (perfectly specular) vertex: no light PDF, no shadow ray; the path follows
     the specular direction and counts emission it hits at full weight.
     PT_SKIP_DELTA_VERTEX. With only delta materials in the scene this skips light
     sampling everywhere (the same bit: there is no separate scene-level test).
   - one-sided emitters facing away from the shading point (single-emitter scenes):
     the light component is dropped from the mixture for that vertex. PT_SKIP_FACING_AWAY.
   - no texture on a material: albedo is read directly from it. PT_SKIP_NO_TEXTURES, exact.
     A hit's (u, v) is computed only at a material with an image texture (pt_hit.u, .v).
   - a light sample the material does not reflect (below the surface): no shadow ray.
     PT_SKIP_ZERO_BSDF_SHADOW, exact.
   - a rectangular light that is large next to its distance: sampled uniformly in solid angle
     (spherical rectangles, section 2) instead of by area. PT_SKIP_SOLID_ANGLE_QUADS (a better
     estimator rather than less work, measured the same way).
   - many emitting shapes (16 or more): the light for next-event estimation is picked by a light
     tree (power, distance, the lights' orientation and the receiver's; section 2) rather than
     by power alone.
     PT_SKIP_LIGHT_TREE.
   - no point, spot or directional light: no delta-light estimate (one test per vertex; not a
     switchable skip, since the general path would add nothing).
   - no environment map and a black background: no environment light (one test per light
     sample and escaped ray; not switchable either, for the same reason).
   - no rough conductor, rough dielectric or rough plastic (PT_FEATURE_MICROFACET): no microfacet
     code runs; the material functions dispatch Lambertian first and the rough materials last,
     and the transmitting vertex's other side (its spawn point below ng for transmitted rays and
     shadow rays) is one flag test (not switchable: there is no general path to force).
   Bits 1u << 1 and 1u << 5 belonged to two skips that did not pay (PT_SKIP_LIGHT_SELECTION,
   PT_SKIP_NO_TRIANGLES) and are rejected. Rays in scenes without triangles still skip the
   watertight-triangle set-up, as the only path.
   Adaptive sampling (pt_render_desc.adaptive_threshold) gives noisy pixels more samples than
   quiet ones: see section 8. The default (PT_ADAPTIVE_PILOT) plans every pixel's samples once,
   from a separate pilot render whose samples are then discarded, so the image keeps the uniform
   render's expectation. PT_ADAPTIVE_OWN_SAMPLES re-plans between passes from the image's own
   samples: a lower error for the time, but biased dark (pixels that have not yet drawn a rare
   bright sample stop sooner: caustics and fireflies come out up to a few % dark in some
   regions); PT_ADAPTIVE_NEIGHBOURS (adaptive_neighbours_only = 1) leaves a pixel's own samples
   out of its estimate, with a smaller bias. Measured: docs/internals.md, "Adaptive sampling".

   PATH GUIDING
   ============
   The light PDFs aim only at emitters a vertex can see; light that arrives off other surfaces,
   through glass or through a gap is found by the material's PDF alone. pt_render_desc.guiding
   learns where it comes from while rendering: a pt_guide (section 2; Mueller, Gross & Novak 2017)
   records the radiance the paths of training iterations of 1, 2, 4, ... samples per pixel bring
   back, and the material side of every strategy becomes alpha p_material + (1 - alpha) p_guide
   at non-delta vertices, its density used everywhere (MIS weights included); the guide is folded
   onto the surface's side (pt_pdf_guide_hemisphere), and Russian roulette follows the radiance
   each of its leaves learned, so that paths carrying indirect light live on. In scenes with
   mirrors or glass and shaped lights, photons traced from the lights through those surfaces
   train a second guide first (pt_guide_caustic: the caustics next-event estimation cannot
   sample, and, one diffuse bounce on, where they are seen through the glass), which takes half
   of the guide's share where they landed. Every sample stays
   in the image with equal weight, so the image is unbiased and bit-identical at any thread count.
   PT_GUIDING_AUTO measures, in the last training iteration, whether the guide pays and goes on
   unguided if not; scenes where guiding cannot help (no non-delta material, no light) skip it.
   What it gains where: docs/design.md, "Path guiding".
*/
#ifndef PDFTRACE_H
#define PDFTRACE_H

#if defined(PDFTRACE_IMPLEMENTATION) && !defined(_POSIX_C_SOURCE) && !defined(_GNU_SOURCE) && !defined(_WIN32) && \
    !defined(__cplusplus)
#define _POSIX_C_SOURCE 200809L /* effective only when this header is the first one included */
#endif
#include <stddef.h>
#include <stdint.h>
#include <stdio.h> /* FILE, for pt_output_file */
#include <math.h>
/* No contraction of a * b + c into a fused multiply-add in pdftrace's code: the vector code
   repeats the scalar code's roundings lane by lane, which a contracted scalar expression (GCC's
   default in GNU modes, clang's anywhere, once the target has FMA) would not match. GCC's pragma
   is used only where the target has FMA (it changes code generation) and over the inline algebra
   below only in the implementation's file (where a copy GCC keeps out of line must not contract);
   clang contracts as it parses, so its pragma covers that algebra always. -ffast-math overrides
   both. PT__CONTRACT_OFF ... PT__CONTRACT_RESTORE bracket code (the tests' internals section too). */
#if defined(__clang__)
#define PT__NO_CONTRACT 1
#define PT__CONTRACT_OFF _Pragma("STDC FP_CONTRACT OFF")
#define PT__CONTRACT_RESTORE _Pragma("STDC FP_CONTRACT DEFAULT")
#elif defined(__GNUC__) && !defined(__INTEL_COMPILER) && (defined(__FP_FAST_FMAF) || defined(__FP_FAST_FMA))
#define PT__NO_CONTRACT 1
#define PT__CONTRACT_OFF _Pragma("GCC push_options") _Pragma("GCC optimize(\"fp-contract=off\")")
#define PT__CONTRACT_RESTORE _Pragma("GCC pop_options")
#else
#define PT__CONTRACT_OFF
#define PT__CONTRACT_RESTORE
#endif
#if defined(__clang__) || defined(PDFTRACE_IMPLEMENTATION)
#define PT__CONTRACT_PUBLIC
PT__CONTRACT_OFF
#endif

#define PDFTRACE_VERSION_MAJOR 0
#define PDFTRACE_VERSION_MINOR 1
#define PDFTRACE_VERSION_PATCH 0

#ifndef PTDEF
#ifdef PDFTRACE_STATIC
#if defined(__GNUC__) || defined(__clang__)
#define PTDEF static __attribute__((unused)) /* a file need not call every function */
#else
#define PTDEF static
#endif
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
   Small value types passed by value, with inline functions for the vector algebra a caller
   needs; the random numbers are PCG32 streams, one per camera sample.
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
   Self-Intersection", Ray Tracing Gems ch. 6, 2019): each coordinate moves by 256 ulps, or by
   magnitude/65536 where it is below magnitude/32. `magnitude` is the size of the coordinates
   that computed p, along n (pt_hit.magnitude; 0 for an axis-aligned plane through 0, whose
   points are exact; |p| is used when larger); the original method's constants assume 1, and fail for scenes far smaller (an offset of 1.5e-5
   leaves a 1e-6 scene altogether) or far larger (a coordinate near 0 of a point computed from
   coordinates near 1e6 has an error far above 1.5e-5). The offset is ~3e-5 magnitude: geometry
   closer than that to a surface is skipped, and float coordinates resolve 2^-24 of their
   magnitude, so geometry d away from the origin needs features >= ~1e-3 d (e.g. >= 1e3 at 1e6);
   the renderer measures d from the scene's own origin (pt_scene_commit), not from (0, 0, 0). */
PTDEF pt_vec3 pt_offset_ray_origin_scaled(pt_vec3 p, pt_vec3 n, pt_vec3 w, float magnitude);
/* The same with magnitude 1 (Waechter & Binder's constants: scenes of unit scale). */
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
/* The library's own double acos on [-1, 1] and sin and cos on [-pi/4, 9 pi/4], within 4 ulps of a
   correctly rounded libm: quad lights' solid-angle sampling uses them, so that its vector version
   computes the same bits as the scalar one on every CPU. Outside those ranges: libm's answer. */
PTDEF double pt_acos(double c);
PTDEF void pt_sincos(double x, double *sn, double *cs);
/* The library's own float atan2, within 3 ulps of the exact value (libm's where y or x is 0, a
   NaN, an infinity or tiny): the environment map's (u, v) use it, and it is several times faster. */
PTDEF float pt_atan2f(float y, float x);

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
    PT_PDF_CALLBACK,           /* user-defined */
    PT_PDF_GUIDE,              /* a learned guide's leaf (pt_pdf_guide, pt_pdf_guide_hemisphere) */
    PT_PDF_ENVIRONMENT         /* a scene's environment light (pt_pdf_environment) */
} pt_pdf_type;

struct pt_pdf;
struct pt_scene;
struct pt_guide;
struct pt_image;

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
        struct { const struct pt_scene *scene; pt_vec3 normal; } lights; /* normal: unit, or 0 */
        struct { const struct pt_scene *scene; int material; pt_vec3 normal, wo; } material;
        struct { int count; const struct pt_pdf *components; const float *weights; } mixture;
        struct { void *user; pt_pdf_sample_fn sample; pt_pdf_value_fn value; } callback;
        struct { const struct pt_guide *guide; uint32_t leaf; pt_vec3 fold; } guide; /* fold: 0 or the
                                                                                   hemisphere's normal */
        struct { const struct pt_scene *scene; pt_color background; } environment;
    } as;
} pt_pdf;

PTDEF pt_pdf pt_pdf_uniform_sphere(void);
PTDEF pt_pdf pt_pdf_cosine_hemisphere(pt_vec3 unit_normal);
/* A sphere light seen from origin. One-sided spheres emit outwards only, so their density is
   zero from inside; two-sided ones are sampled by area from inside or on the surface. A sphere
   narrower than float's angular resolution (r below ~1e-7 of its distance) may hold no float
   direction: pt_pdf_sample then returns the rounding of a direction in its cone with the cone's
   density, whose pt_pdf_value is 0 (inside a mixture such a draw fails instead). */
PTDEF pt_pdf pt_pdf_sphere_light(pt_vec3 origin, pt_vec3 center, float radius, int two_sided);
/* One-sided quads and triangles emit on the side of their normal; seen from behind, their
   density is zero everywhere and sampling fails (returns 0). */
PTDEF pt_pdf pt_pdf_quad_light(pt_vec3 origin, pt_vec3 q, pt_vec3 u, pt_vec3 v, int two_sided);
PTDEF pt_pdf pt_pdf_triangle_light(pt_vec3 origin, pt_vec3 a, pt_vec3 b, pt_vec3 c, int two_sided);
/* All emitters of a committed scene: light i is picked with probability P_i proportional to
   its power (mean radiance x area x pi, x2 if two-sided); value = sum_i P_i p_i(dir). Lights
   facing away from origin have no density, so the PDF may integrate to less than one there;
   sampling them fails (returns 0), which keeps every estimator that uses it unbiased. Emitting
   shapes only: the environment light's density is pt_pdf_environment. */
PTDEF pt_pdf pt_pdf_scene_lights(const struct pt_scene *scene, pt_vec3 origin);
/* The same at a point of a surface that reflects only on the side of `normal` (world, any
   length; the zero vector: none, as pt_pdf_scene_lights): no light is picked for its part
   below that plane, which sharpens the light tree's choice (a render does this at every
   vertex of a reflecting material). */
PTDEF pt_pdf pt_pdf_scene_lights_at(const struct pt_scene *scene, pt_vec3 origin, pt_vec3 normal);
/* The directional density with which a render samples the environment light of a committed
   scene (pt_scene_set_environment) under a constant background radiance `background`
   (pt_render_desc.background): the map's piecewise-constant density mixed with the uniform
   sphere in proportion to their powers. No map and a black background: no density (sampling
   fails, value 0). */
PTDEF pt_pdf pt_pdf_environment(const struct pt_scene *scene, pt_color background);
/* The scattering PDF of material `material` at a surface with unit normal `normal` (facing the
   viewer is not required), for outgoing direction wo (unit, pointing away from the surface).
   Delta materials have no PDF: sampling returns 0 and value is 0. */
PTDEF pt_pdf pt_pdf_material(const struct pt_scene *scene, int material, pt_vec3 normal, pt_vec3 wo);
/* Weights must be >= 0 and sum to 1 (within 1e-4); pt_pdf_validate checks it. Unvalidated
   weights behave as documented, finite: weights that are not > 0 (zero, negative, NaN) are
   ignored and the others are divided by their sum, so sampling and pt_pdf_value always agree
   (a mixture of 0.1 p1 + 0.3 p2 is 0.25 p1 + 0.75 p2); with no positive weight it has no
   density (sampling fails, value 0). */
PTDEF pt_pdf pt_pdf_mixture(int count, const pt_pdf *components, const float *weights);
PTDEF pt_pdf pt_pdf_callback(void *user, pt_pdf_sample_fn sample, pt_pdf_value_fn value);

/* A learned PDF: the guide (path guiding). A pt_guide is a spatial binary tree over a box whose
   leaves each hold a quadtree over the directions (an SD-tree: Mueller, Gross & Novak, "Practical
   Path Guiding for Efficient Light-Transport Simulation", EGSR 2017). Directions map to the unit
   square by the cylindrical equal-area map x = (cos(theta) + 1) / 2, y = phi / (2 pi), so a
   density q over the square is q / (4 pi) per steradian. Records (a point, a direction and a
   value >= 0, e.g. incident radiance over the density it was sampled with) are added into the
   guide's "building" tree, each spread over the directional cells a square the size of its own
   cell overlaps; pt_guide_update turns them into the sampling tree (each quadtree
   quadrant's probability in proportion to the values recorded in it) and refines both trees
   where the values concentrate: a spatial leaf splits in two once it held more than
   spatial_threshold x sqrt(2^k) records in update k, a directional cell splits in four when it
   holds more than directional_threshold of its leaf's value. pt_render trains one itself
   (pt_render_desc.guiding); this API builds, inspects and samples one outside a render.
   Records from several threads at once are safe and their order does not matter: values are
   summed in fixed point (integers), so a guide is bit-identical however its records were
   scheduled. Sampling and pt_pdf_value of pt_pdf_guide agree exactly; a leaf with no data yet
   is uniform over the sphere. A spatial leaf's quadtree covers the whole sphere: at a surface,
   the part of it below the surface is wasted (mix it with the material's PDF). */
typedef struct pt_guide pt_guide;
typedef struct pt_guide_desc {
    pt_vec3 bounds_min, bounds_max; /* the box it learns over (pt_guide_create); points outside are
                                       clamped into it */
    size_t max_bytes;               /* memory bound of both trees, >= 4096; 0: 64 MiB. Refinement
                                       stops at it */
    float spatial_threshold;        /* c above; 0: 12000 */
    float directional_threshold;    /* rho above, in (0, 1); 0: 0.01 */
    int max_directional_depth;      /* deepest quadtree level, 1..16 (a level-16 cell is ~1e-4 rad
                                       wide, ~1000 float roundings of a direction); 0: 16 */
    float value_resolution;         /* the fixed-point unit of the sums; 0: 2^-24. A record's
                                       value is clamped to 2^40 units */
} pt_guide_desc;
typedef struct pt_guide_info {
    int updates;                    /* pt_guide_update calls so far */
    uint32_t spatial_leaves, spatial_depth;
    uint64_t directional_nodes;     /* quadtree nodes, sampling and building trees */
    size_t bytes;                   /* memory held */
    size_t max_bytes;               /* the bound (resolved) */
    int at_memory_bound;            /* 1 when the last update stopped refining at max_bytes */
    uint64_t records;               /* records since the last update */
} pt_guide_info;
/* Creates an empty guide (every leaf uniform). desc NULL or a bad field: PT_ERROR_INVALID_ARGUMENT
   with *out NULL; also PT_ERROR_OUT_OF_MEMORY. */
PTDEF int pt_guide_create(const pt_guide_desc *desc, pt_guide **out);
/* A guide over a committed scene's bounds (desc may be NULL: every default; its bounds are not
   used), in world coordinates like every other point of the API. pt_render_desc.guiding_guide
   takes only such a guide. */
PTDEF int pt_guide_create_for_scene(const struct pt_scene *scene, const pt_guide_desc *desc, pt_guide **out);
PTDEF void pt_guide_destroy(pt_guide *guide);
/* Adds value (finite, >= 0) for unit direction dir at point. PT_ERROR_INVALID_ARGUMENT otherwise. */
PTDEF int pt_guide_record(pt_guide *guide, pt_vec3 point, pt_vec3 dir, float value);
/* Makes the records the sampling distribution, refines, and clears the records (see above).
   Not concurrently with pt_guide_record or with sampling from the guide. */
PTDEF int pt_guide_update(pt_guide *guide);
PTDEF int pt_guide_get_info(const pt_guide *guide, pt_guide_info *info);
/* The guide's density at point (the leaf holding it): PT_PDF_GUIDE. The guide must outlive it and
   not be updated while it is used. A NULL guide gives a PDF with no density. */
PTDEF pt_pdf pt_pdf_guide(const pt_guide *guide, pt_vec3 point);
/* The guide at point folded onto the hemisphere of unit_normal: a direction below it is mirrored
   through the tangent plane, so the density of w above is p(w) + p(w - 2 (w.n) n) and zero below.
   Every draw then leaves on the side of the normal (for a surface that only reflects, no sample is
   wasted below it), at the cost of a second look-up per evaluation. PT_PDF_GUIDE. */
PTDEF pt_pdf pt_pdf_guide_hemisphere(const pt_guide *guide, pt_vec3 point, pt_vec3 unit_normal);
/* The guide's density at point as a latitude-longitude picture (column: phi from 0 to 2 pi about
   +z, starting at +x; row: theta from 0 at +z at the top to pi), each pixel's value in all three
   channels: the density of the direction at its centre, per steradian. *image is allocated or
   reallocated as by pt_film_resolve. */
PTDEF int pt_guide_image(const pt_guide *guide, pt_vec3 point, int width, int height, struct pt_image *image);
/* The caustic photons' guide a guided render attached to guide (pt_render_desc.guiding_guide;
   section 8, "Guiding": a second pt_guide, learned from photons traced from the lights through
   the delta surfaces, owned by guide), or NULL when the render traced none (no delta surface or
   no shaped light). Valid until guide is destroyed or guides another render. */
PTDEF const pt_guide *pt_guide_caustic(const pt_guide *guide);

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

/* Samplers: where the renderer's random numbers come from (pt_render_desc.sampler).
   INDEPENDENT: every number of a camera sample comes from its own PCG stream
   (pt_rng_for_sample). SOBOL: randomised quasi-Monte Carlo. Each group of numbers the
   integrator draws together (the pixel position, the lens position, and at every bounce the
   light choice, the point on the light, the scattered direction, Russian roulette, ...) is
   one fixed "set" of one or two dimensions (the scattered directions of depths 2i and 2i + 1
   together: one of four); a set's value for a pixel's k-th sample is point k of Sobol's
   two-dimensional (0,2)-sequence (four-dimensional: Sobol's first four dimensions) after a
   nested uniform shuffle of k and an Owen scramble of each coordinate, keyed by a hash of
   (seed, pixel, set) (Burley, "Practical Hash-based Owen Scrambling", JCGT 9(4), 2020; sets
   padded as in Pharr, Jakob & Humphreys, "Physically Based Rendering", 4th ed., ch. 8). Every
   point is uniformly distributed, so the estimate stays unbiased, while any 2^m consecutive
   samples of a pixel (from an aligned start, e.g. the first 2^m) are stratified in every set:
   one point in each elementary interval of area 2^-m (the odd depth's direction of a
   four-dimensional set: 2^t points in each of area 2^(t-m), t <= 2). Error falls faster than with independent numbers where the
   integrand is smooth (direct light, anti-aliasing). The k-th sample is a pure function of
   (seed, pixel, k), as with INDEPENDENT, so progressive passes and resumed renders give the
   same image as one pass. A pixel's samples are not independent, so the film's per-pixel
   variance (adaptive sampling) and the half-buffer error estimate (pt_film_error) assume what
   is not true: they overestimate a SOBOL image's error (by how much: docs/internals.md, "The
   error estimate under the Sobol sampler"), which makes adaptive sampling conservative, not
   wrong. Use independent seeds to measure a SOBOL render's error. */
typedef enum pt_sampler {
    PT_SAMPLER_INDEPENDENT = 0,
    PT_SAMPLER_SOBOL = 1
} pt_sampler;

/* Sobol's sequence, unscrambled: coordinate dim of point `index` (0: van der Corput; 1, 2, 3:
   Sobol's dimensions with Joe & Kuo's parameters, primitive polynomials x + 1, x^2 + x + 1 and
   x^3 + x + 1), as a 32-bit binary fraction (the value is result / 2^32). Returns 0 for a dim
   outside 0..3. */
PTDEF uint32_t pt_sobol_u32(uint32_t index, int dim);
/* The point PT_SAMPLER_SOBOL uses: point `index` of the 2D Sobol sequence with the index
   shuffled (nested uniform scramble of its low 16 bits) and both coordinates Owen-scrambled,
   all keyed by `seed`; u[0], u[1] in [0, 1). For a uniformly random seed, each point is
   uniform on [0, 1)^2; for any fixed seed, points j 2^m ... (j + 1) 2^m - 1 form a (0,m,2)-net
   (m <= 16). The renderer's one-dimensional sets use u[0]. */
PTDEF void pt_sobol_scrambled(uint32_t index, uint64_t seed, float u[2]);
/* The same point with Sobol's dimensions 2 and 3 as well (one shuffle of the index, each
   coordinate Owen-scrambled with its own seeds): u[0], u[1] are pt_sobol_scrambled's; the
   renderer's four-dimensional sets (two successive scattered directions) use it. Each point is
   uniform on [0, 1)^4 for a uniformly random seed; (u[2], u[3]) alone form (1,m,2)-nets. */
PTDEF void pt_sobol_scrambled4(uint32_t index, uint64_t seed, float u[4]);

/* ==========================================================================================
   3. GEOMETRY AND SCENES
   A scene owns materials, textures and shapes. Shapes are added under the scene's current
   transform (pt_scene_set_transform), which is applied to their geometry when they are
   added: an instanced emitter is an emitter in world space and is sampled exactly. Add
   everything, then pt_scene_commit (builds the acceleration structure, section 5 or 5b, and
   the light table; implemented in section 5c); change the scene and it must be committed
   again before it is rendered.
   Threads: a committed scene may be rendered from several threads at once (pt_render,
   pt_render_image, pt_trace_path; also pt_scene_intersect, pt_scene_occluded, the light and
   material PDFs): those calls only read it and write no message into it. Adding to, changing
   or committing a scene while another call uses it is not allowed.
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
    PT_FEATURE_TRANSFORMS      = 1 << 12, /* some shape was added under a non-identity transform */
    PT_FEATURE_DELTA_LIGHTS    = 1 << 13, /* some point, spot or directional light (pt_scene_add_light) */
    PT_FEATURE_ENVIRONMENT     = 1 << 14, /* an environment map (pt_scene_set_environment) */
    PT_FEATURE_MICROFACET      = 1 << 15  /* some rough conductor or dielectric that is not delta, or rough plastic */
};

/* SIMD levels of the built-in BVH's traversal (section 5), chosen at run time at each commit:
   the highest the CPU supports, capped by pt_simd_set_cap and by the environment variable
   PDFTRACE_SIMD (scalar, sse2, avx2 or avx512). Every level finds the same hits bit for bit, so
   renders are identical at every level; only the speed differs. */
typedef enum pt_simd_level {
    PT_SIMD_SCALAR = 0,           /* portable C (the only level with PDFTRACE_NO_SIMD) */
    PT_SIMD_SSE2 = 1,             /* 4-wide nodes and leaf blocks (x86-64's baseline) */
    PT_SIMD_AVX2 = 2,             /* 8-wide nodes (gcc or clang on x86; leaf blocks as SSE2) */
    PT_SIMD_AVX512 = 3            /* AVX-512F: 8-wide nodes, or 16 with PDFTRACE_AVX512_WIDTH=16 */
} pt_simd_level;

/* Traversal backends (pt_scene_set_backend, section 5b). */
typedef enum pt_backend {
    PT_BACKEND_AUTO = 0,          /* Embree for large scenes when compiled in, else built-in */
    PT_BACKEND_BUILTIN = 1,       /* pdftrace's own BVH (section 5) */
    PT_BACKEND_EMBREE = 2         /* Embree (section 5b; needs PDFTRACE_EMBREE) */
} pt_backend;

typedef struct pt_scene_info {
    unsigned features;            /* PT_FEATURE_* */
    int committed;                /* 1 when committed and unchanged since */
    uint32_t primitive_count;     /* spheres + quads + triangles (mesh triangles included) */
    uint32_t sphere_count, quad_count, triangle_count, mesh_count;
    uint32_t emitter_count;       /* emitting primitives: each is one light */
    uint32_t material_count, texture_count;
    uint32_t degenerate_triangles_skipped; /* zero-area mesh triangles left out */
    uint32_t bvh_node_count, bvh_max_depth; /* built-in BVH (0 when Embree traces the scene) */
    double total_emitted_power;   /* sum of light powers (W, in radiance x area x sr units) */
    pt_vec3 bounds_min, bounds_max;
    pt_backend backend;           /* the backend the last commit chose (never AUTO) */
    double build_seconds;         /* acceleration-structure build time at the last commit (wall) */
    size_t accel_bytes;           /* memory the backend allocated for traversal: built-in, the BVH
                                     nodes and leaf blocks (a copy of the triangle and quad
                                     data, laid out for 4-wide tests); Embree, everything its
                                     device allocated (its BVH, the triangle index buffer; the
                                     vertices are shared with the primitive array) plus
                                     pdftrace's primitive id maps. The scene's own primitive
                                     array, which shading uses with either backend, is not
                                     counted. */
    double origin[3];             /* the centre the committed scene is stored and traced relative
                                     to (see pt_scene_commit); (0, 0, 0) for most scenes */
    uint32_t precision_warnings;  /* primitives smaller than float resolves at their coordinates,
                                     or than the spawn offset there (see pt_scene_commit) */
    char precision_warning[200];  /* "" when precision_warnings is 0, else what and where */
    uint32_t delta_light_count;   /* point, spot and directional lights (pt_scene_add_light) */
    int environment_width, environment_height; /* the environment map's size (0 x 0: none) */
    pt_simd_level simd_level;     /* the level the last commit chose (pt_simd_get_level) */
    unsigned bvh_width;           /* children per node the built-in traversal uses: 4, 8 or 16 */
} pt_scene_info;

PTDEF pt_scene *pt_scene_create(void);      /* NULL when out of memory */
PTDEF void pt_scene_destroy(pt_scene *scene);
/* Why the last call that changes the scene (pt_scene_set_*, pt_scene_add_*, pt_scene_commit)
   failed, with detail ("quad: no area in float ..."); such a call that succeeds clears it: ""
   then. Never NULL. Calls that only read the scene (pt_scene_get_info, the queries, pt_render and
   pt_render_image, whose message is in pt_render_stats.error) leave it unchanged. */
PTDEF const char *pt_scene_error_message(const pt_scene *scene);

/* Applies to every shape added afterwards; NULL resets to the identity. Spheres need a
   similarity transform (rotation, translation, uniform scale): a sphere added under any
   other transform fails with PT_ERROR_UNSUPPORTED. */
PTDEF int pt_scene_set_transform(pt_scene *scene, const pt_transform *transform);

/* Shapes. Each returns the index of its first primitive (>= 0) or an error code (with
   pt_scene_error_message): non-finite input, zero radius or area, coordinates beyond 1e18 in
   magnitude (products of two must stay finite in float), and shapes whose area underflows in
   float (edges below ~1e-9 of the scene's units: keep scenes within ~1e-9 .. 1e9). */
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
    const float *uvs;            /* optional: 2 floats (u, v) per vertex, finite, interpolated into
                                    pt_hit.u, .v for image textures; NULL: (u, v) = the hit's
                                    barycentric weights of the 2nd and 3rd corner (Mitsuba's) */
} pt_mesh_desc;
/* Copies the data. Zero-area triangles are skipped (counted in pt_scene_info); the others get
   consecutive primitive indices, starting at the returned one, in the order given. */
PTDEF int pt_scene_add_mesh(pt_scene *scene, const pt_mesh_desc *mesh);

/* Commit chooses the scene's origin (unless pt_scene_set_origin fixed it): (0, 0, 0), or, for
   a scene farther from (0, 0, 0) than 8 times its size, the centre of its bounds (rounded to
   float). Geometry is stored, and
   pt_render traces camera rays, relative to it (the difference taken in double), so spawn
   offsets and intersections keep the precision of a scene at the origin. Everything public
   stays in world coordinates: pt_scene_intersect, pt_scene_occluded and pt_trace_path take
   world rays and return world hits, pt_pdf_scene_lights a world origin, guides world points,
   textures are evaluated at world points, pt_scene_info.bounds are world. Input is float, so
   a scene 1e7 away has its vertices rounded to 1 unit before this (build such scenes in
   double relative to a centre you choose, as pdftrace_scene.h does).
   Commit also counts the primitives float cannot represent well (pt_scene_info.precision_*):
   a feature (sphere radius, smallest height of a quad or triangle) under 8 ulps of its world
   coordinates, or, for a scattering material, under 16 spawn offsets (pt_offset_ray_origin:
   ~3e-5 of the coordinates relative to the origin). Such a scene commits; the renders are
   unreliable there. */
PTDEF int pt_scene_commit(pt_scene *scene);
PTDEF int pt_scene_get_info(const pt_scene *scene, pt_scene_info *info);
/* Fixes the origin instead of letting commit choose it: the shapes' coordinates (after the
   scene's transform) are then relative to (x, y, z), i.e. world = given + origin, so a caller
   that computes a far scene in double can hand pdftrace small floats. Everything else stays in
   world coordinates, as above (rays, hits, bounds, camera). Only on a scene with no shapes yet
   (PT_ERROR_INVALID_STATE otherwise); (x, y, z) must be finite. */
PTDEF int pt_scene_set_origin(pt_scene *scene, double x, double y, double z);

/* A ray-surface intersection. */
typedef struct pt_hit {
    float t;                  /* ray parameter of the hit */
    pt_vec3 point;
    pt_vec3 geometric_normal; /* unit, the shape's own orientation (not flipped to the ray) */
    pt_vec3 shading_normal;   /* unit, interpolated for meshes with normals, else geometric */
    int front_face;           /* 1 when the ray arrives on the side the geometric normal points to */
    uint32_t primitive;       /* index as returned by pt_scene_add_* (+ triangle index in a mesh) */
    int material;
    float magnitude;          /* the scale of point's rounding error along the normal (the
                                 primitive's coordinates weighted by |normal|), for
                                 pt_offset_ray_origin_scaled */
    float u, v;               /* surface coordinates, where image textures are looked up (those of
                                 Mitsuba 3's shapes, so an exported scene maps alike). Quad
                                 Q + a U + b V: (a, b). Triangle a, b, c hit at barycentric weights
                                 (w0, w1, w2): (w1, w2), or, in a mesh with uvs, w0 uv_a + w1 uv_b
                                 + w2 uv_c. Sphere, n the unit normal in world axes:
                                 u = atan2(n.y, n.x) / (2 pi) wrapped to [0, 1), v = acos(n.z) / pi.
                                 Set by pt_scene_intersect*; the renderer computes them only at
                                 materials with an image texture */
} pt_hit;

/* Closest hit with 0 < t < tmax. Returns 1 on a hit, 0 on a miss, an error code on misuse
   (PT_ERROR_INVALID_ARGUMENT: NULL pointers, a non-finite ray; PT_ERROR_INVALID_STATE: an
   uncommitted scene), with no message (queries never write the scene). */
PTDEF int pt_scene_intersect(const pt_scene *scene, pt_ray ray, float tmax, pt_hit *hit);
/* 1 when anything is hit with 0 < t < tmax (any hit, early exit). */
PTDEF int pt_scene_occluded(const pt_scene *scene, pt_ray ray, float tmax);
/* Reference closest hit that tests every primitive; for tests and debugging. */
PTDEF int pt_scene_intersect_brute_force(const pt_scene *scene, pt_ray ray, float tmax, pt_hit *hit);

/* Single-primitive intersections: the smallest t in (0, tmax), or return 0. Edges count as
   part of a quad or triangle (a ray through an edge hits).
   Ray/sphere after Haines et al., "Precision Improvements for Ray/Sphere Intersection",
   Ray Tracing Gems ch. 7; ray/triangle is watertight (Woop, Benthin & Wald, JCGT 2(1), 2013). */
PTDEF int pt_intersect_sphere(pt_ray ray, pt_vec3 center, float radius, float tmax, float *t);
PTDEF int pt_intersect_quad(pt_ray ray, pt_vec3 q, pt_vec3 u, pt_vec3 v, float tmax, float *t);
PTDEF int pt_intersect_triangle(pt_ray ray, pt_vec3 a, pt_vec3 b, pt_vec3 c, float tmax, float *t);

/* ==========================================================================================
   4. MATERIALS AND TEXTURES
   Every material may also emit (emission > 0). Lambertian reflection is two-sided (a wall is
   lit and seen from both sides), as are the metals; emission is one-sided (on the side of the
   geometric normal) unless two_sided_emission is set. The rough conductor is a GGX microfacet
   BRDF sampled by its visible normals, a density that mixes with the light PDFs like
   Lambertian's; the rough dielectric is its glass twin, the only non-delta material that
   scatters below the geometric surface; the rough plastic is a Lambertian base under a GGX
   dielectric coat (Mitsuba 3's roughplastic), sampled by a mixture of the two (docs/materials.md).
   A material's albedo may come from a texture: the 3-D checker at the world point, or an image
   at the hit's surface coordinates (pt_hit.u, .v; docs/textures.md).
   ========================================================================================== */

typedef enum pt_material_type {
    PT_MATERIAL_LAMBERTIAN = 0, /* pScatter = cos/pi, sampled by the cosine PDF */
    PT_MATERIAL_METAL,          /* mirror direction plus fuzz (a ball of radius fuzz around it);
                                   fuzz = 0 is a delta mirror. The lobe of "Ray Tracing in One
                                   Weekend", kept for its scenes: it has a closed-form density
                                   (so it mixes with light PDFs) but is not a physical BRDF (no
                                   Fresnel, no masking, not reciprocal) and has no exact twin in
                                   Mitsuba or POV-Ray; PT_MATERIAL_ROUGH_CONDUCTOR is the
                                   physical rough metal */
    PT_MATERIAL_DIELECTRIC,     /* clear glass: exact unpolarised Fresnel, total internal reflection; delta */
    PT_MATERIAL_EMITTER,        /* emits `emission`, reflects nothing */
    PT_MATERIAL_ROUGH_CONDUCTOR, /* GGX microfacet metal (below): roughness, conductor, albedo tints it */
    PT_MATERIAL_ROUGH_PLASTIC,  /* a Lambertian base (albedo) under a GGX dielectric coat (below):
                                   roughness, ior, nonlinear; Mitsuba 3's `roughplastic` */
    PT_MATERIAL_ROUGH_DIELECTRIC /* GGX microfacet glass (below): roughness, ior inside, ext_ior outside */
} pt_material_type;

/* The complex index of refraction eta + i k of a rough conductor, per RGB channel (relative to
   the outside, a vacuum). NONE: Fresnel reflectance 1 at every angle (Mitsuba's material
   "none"). The named metals are linear-sRGB reductions of measured spectra (the RGB values
   renderers commonly tabulate from Mitsuba 0.5's spectral data; docs/materials.md):
     Au  eta (0.1431, 0.3750, 1.4425)  k (3.9832, 2.3857, 1.6032)
     Ag  eta (0.1553, 0.1167, 0.1384)  k (4.8283, 3.1222, 2.1470)
     Cu  eta (0.2004, 0.9240, 1.1022)  k (3.9129, 2.4528, 2.1422)
     Al  eta (1.6575, 0.8804, 0.5212)  k (9.2239, 6.2695, 4.8370) */
typedef enum pt_conductor {
    PT_CONDUCTOR_NONE = 0,
    PT_CONDUCTOR_CUSTOM,        /* pt_material_desc.eta and .k */
    PT_CONDUCTOR_AU,
    PT_CONDUCTOR_AG,
    PT_CONDUCTOR_CU,
    PT_CONDUCTOR_AL
} pt_conductor;

typedef struct pt_material_desc {
    pt_material_type type;
    pt_color albedo;            /* Lambertian, metal (ignored by dielectric, which is clear) */
    int albedo_texture;         /* 0: use albedo; else an id from pt_scene_add_checker or
                                   pt_scene_add_image_texture (it replaces albedo) */
    float fuzz;                 /* metal, clamped to [0, 1] */
    float ior;                  /* dielectric (and rough plastic coat) index of refraction; 0 means
                                   1.5; else finite, >= 0.001 (the coat's > 1) */
    pt_color emission;          /* emitted radiance */
    int two_sided_emission;
    /* Rough conductor: BRDF f = albedo F(wo.h) D(h) G1(wo) G1(wi) / (4 cos_o cos_i), h the half
       vector, D the isotropic GGX distribution (Trowbridge-Reitz; Walter et al. 2007), G1 Smith's
       masking for it, F the exact unpolarised Fresnel reflectance of the conductor (Mitsuba 3's
       `roughconductor` with distribution ggx, term for term). Sampled by the visible normals
       (Heitz 2018) with density G1(wo) D(h) / (4 cos_o); directions the sampled microfacet
       reflects below the surface fail, which is the model's single-scattering energy loss. */
    float roughness;            /* GGX alpha (not a "perceptual" roughness), finite, in [0, 1]. Below
                                   1e-3 (a lobe under 0.06 degrees) the material is the smooth
                                   Fresnel mirror, a delta material; the switch changes images
                                   only by that blur. 0: the mirror */
    pt_conductor conductor;     /* 0: PT_CONDUCTOR_NONE */
    pt_color eta, k;            /* PT_CONDUCTOR_CUSTOM: eta finite > 0, k finite >= 0 */
    /* Rough plastic: Mitsuba 3's `roughplastic` (distribution ggx, visible normals), term for
       term: f cos_i = F(wo.h) D(h) G1(wo) G1(wi) / (4 cos_o)
                     + rho / (1 - R_int) T(cos_o) T(cos_i) cos_i / (pi ior^2),
       rho the albedo (in [0, 1]; rho R_int in the denominator when `nonlinear`), T the coat's
       transmittance into the layer and R_int its diffuse internal reflectance, both integrated
       at commit as Mitsuba does (docs/materials.md). roughness: the coat's GGX alpha in [0, 1]
       (below 1e-3 the coat is rendered at alpha 1e-3, a lobe under 0.06 degrees: the smooth coat
       up to that blur); ior: the coat's index (0 means 1.5; else finite, > 1). Reflects on the
       side of wo only; sampled by a mixture of the visible normals and the cosine lobe. */
    int nonlinear;              /* rough plastic: the base's colour shifted by internal scattering */
    /* Rough dielectric: the interface between ior (inside, the side the geometric normal points
       away from) and ext_ior (outside), clear like PT_MATERIAL_DIELECTRIC (albedo ignored). With
       eta = n_far / n_near seen from wo and m the microfacet normal (Walter et al. 2007, GGX, the
       Smith G = G1(wo) G1(wi), F the exact dielectric Fresnel at wo.m):
         reflection   A pScatter = F D(h) G / (4 cos_o)
         transmission A pScatter = (1 - F) D(m) G |wo.m| |wi.m| / (cos_o (wo.m + eta wi.m)^2)
       which is Walter's BTDF times cos_i times 1 / eta^2: transmitted radiance is scaled by
       (n_near / n_far)^2 across the interface (the solid angle's compression), exactly as Mitsuba
       3's `roughdielectric` and `dielectric` do in radiance mode, so a path that enters and leaves
       an object carries no net factor. Sampled by the visible normals of wo (Heitz 2018), then
       reflection with probability F(wo.m) else refraction; directions the microfacet sends to the
       wrong side fail (the single-scattering loss). Below roughness 1e-3, or when roughness x
       |eta - 1| < 1e-3 (the transmitted lobe narrower than 0.06 degrees), it is the smooth
       interface: a delta material with the same 1 / eta^2 on transmission (docs/materials.md). */
    float ext_ior;              /* rough dielectric: index outside; 0 means 1; else finite >= 0.001 */
} pt_material_desc;

PTDEF int pt_scene_add_material(pt_scene *scene, const pt_material_desc *desc); /* id >= 0 */
/* Shorthands for pt_scene_add_material with the other fields zero: the same checks and
   defaults (pt_scene_add_dielectric(s, 0) is glass of ior 1.5). */
PTDEF int pt_scene_add_lambertian(pt_scene *scene, pt_color albedo);
PTDEF int pt_scene_add_metal(pt_scene *scene, pt_color albedo, float fuzz);
PTDEF int pt_scene_add_dielectric(pt_scene *scene, float ior);
PTDEF int pt_scene_add_emitter(pt_scene *scene, pt_color radiance, int two_sided);
/* A rough conductor (tint: pt_material_desc.albedo; eta, k zero: not for PT_CONDUCTOR_CUSTOM). */
PTDEF int pt_scene_add_rough_conductor(pt_scene *scene, pt_conductor conductor, float roughness, pt_color tint);
/* A rough plastic (Mitsuba's roughplastic, linear colours): albedo in [0, 1], GGX roughness, coat ior (0: 1.5). */
PTDEF int pt_scene_add_rough_plastic(pt_scene *scene, pt_color albedo, float roughness, float ior);
/* A rough dielectric of index ior inside (0: 1.5) under a vacuum (ext_ior 1). */
PTDEF int pt_scene_add_rough_dielectric(pt_scene *scene, float ior, float roughness);
/* The Fresnel reflectance per channel of a conductor at cos(theta) (clamped to [0, 1]) of
   material `material` (PT_MATERIAL_ROUGH_CONDUCTOR; zero for other types or a bad id). */
PTDEF pt_color pt_material_conductor_fresnel(const pt_scene *scene, int material, float cos_theta);
/* The table's eta and k of a named metal (PT_CONDUCTOR_AU .. _AL): PT_OK; else
   PT_ERROR_INVALID_ARGUMENT (NONE and CUSTOM have no table entry; NULL outputs). */
PTDEF int pt_conductor_ior(pt_conductor conductor, pt_color *eta, pt_color *k);
/* A 3D checker: colour `odd` where floor(x/s)+floor(y/s)+floor(z/s) is odd, `even` elsewhere
   (world space, s = scale > 0). Returns a texture id >= 1. */
PTDEF int pt_scene_add_checker(pt_scene *scene, pt_color even, pt_color odd, float scale);
/* An image texture looked up at the hit's (u, v) (pt_hit): linear RGB pixels (finite, >= 0; at
   least 1 x 1; copied), row 0 at v = 0 and column 0 at u = 0, pixel (x, y) centred at
   ((x + 1/2) / W, (y + 1/2) / H), filtered bilinearly between pixel centres and repeated in u
   and v (Mitsuba 3's `bitmap` with filter_type bilinear and wrap_mode repeat). The pixels are
   used as given: decoding sRGB (8-bit colour) is the reader's job (pdftrace_png.h,
   pt_srgb_decode). As albedo_texture it colours Lambertian, metal and the rough conductor's
   tint. Returns a texture id >= 1, or an error code (PT_ERROR_INVALID_ARGUMENT naming the bad
   argument, PT_ERROR_OUT_OF_MEMORY). */
PTDEF int pt_scene_add_image_texture(pt_scene *scene, const struct pt_image *image);
/* A 3-D texture (checker) at world point p; (0, 0, 0) for an image texture or a bad id. */
PTDEF pt_color pt_scene_eval_texture(const pt_scene *scene, int texture, pt_vec3 p);
/* An image texture at (u, v); (0, 0, 0) for a 3-D texture or a bad id. */
PTDEF pt_color pt_scene_eval_texture_uv(const pt_scene *scene, int texture, float u, float v);
/* 1 when the material scatters only into delta directions (mirror, glass) or not at all. */
PTDEF int pt_material_is_delta(const pt_scene *scene, int material);

/* Lights without a shape: point, spot and directional lights (delta lights). A ray cannot hit
   one, so they are reached only by next-event estimation: at every vertex with a scattering
   density, under every strategy (PT_STRATEGY_MATERIAL and _MIXTURE included), one delta light
   is picked in proportion to what it would give that point unshadowed (by power when there are
   more than 16) and a shadow ray is traced to it, with MIS weight 1 (no other technique can find
   it). Shaped emitters keep their own light table and strategy. Delta
   lights are not seen by the camera, have no density in pt_pdf_scene_lights and are not in
   pt_scene_info.emitter_count (pt_scene_info.delta_light_count). They are added under the
   scene's current transform (the position as a point, the direction as a vector, normalised).
   Units, per RGB channel:
   - POINT: radiant intensity I (W/sr): a surface at distance d facing it at angle theta
     receives E = I cos(theta) / d^2.
   - SPOT: I along its axis; at angle a from the axis, I x falloff(a): 1 for a <= beam_width,
     (cutoff_angle - a) / (cutoff_angle - beam_width) up to cutoff_angle (linear in the angle),
     0 beyond (Mitsuba 3's `spot`).
   - DIRECTIONAL: irradiance E (W/m^2) on a surface facing the light: E cos(theta) elsewhere; its
     light arrives from -direction everywhere (the sun). */
typedef enum pt_light_type {
    PT_LIGHT_POINT = 1,
    PT_LIGHT_SPOT = 2,
    PT_LIGHT_DIRECTIONAL = 3
} pt_light_type;

typedef struct pt_light_desc {
    pt_light_type type;
    pt_vec3 position;            /* POINT, SPOT */
    pt_vec3 direction;           /* SPOT: the axis the cone opens along; DIRECTIONAL: the direction
                                    its light travels; any non-zero length */
    pt_color intensity;          /* POINT, SPOT: I (W/sr); DIRECTIONAL: E (W/m^2); finite, >= 0,
                                    not all zero */
    float cutoff_angle;          /* SPOT: degrees in (0, 90]; 0: 20 */
    float beam_width;            /* SPOT: degrees in (0, cutoff_angle]; 0: 3/4 of cutoff_angle */
} pt_light_desc;

/* Returns the light's id (>= 0, counting delta lights from 0) or an error code with
   pt_scene_error_message naming the bad field. */
PTDEF int pt_scene_add_light(pt_scene *scene, const pt_light_desc *light);
/* The light as added (the transform applied, defaults resolved): PT_OK, or
   PT_ERROR_INVALID_ARGUMENT for a bad id or NULL. */
PTDEF int pt_scene_get_light(const pt_scene *scene, int id, pt_light_desc *light);

/* The environment light: radiance arriving from infinitely far away, L(w) = background +
   scale x map(w), where background is pt_render_desc.background (a constant) and map an
   equirectangular ("lat-long") image of linear RGB radiance. Seen from a direction w in the
   map's own frame, u = atan2(w.x, -w.z) / (2 pi) (wrapped to [0, 1)) and v = acos(w.y) / pi,
   so row 0 is the zenith (+y) and the map's centre column looks along +z (Mitsuba 3's `envmap`
   convention); pixel (x, y) is centred at u = (x + 1/2) / W, v = (y + 1/2) / H and the map is
   interpolated bilinearly between pixel centres, periodically in u and held constant beyond
   the first and last rows' centres. The map is set under the scene's current transform, which
   must be a rotation (a translation part is ignored): it turns the map's frame into the world.
   Rays that leave the scene see L(w); next-event estimation samples it under every strategy
   that samples lights (MIS, LIGHT, MIXTURE): the map by a piecewise-constant density over its
   pixels, proportional to each pixel's mean luminance (the bilinear interpolant's exact mean
   over the pixel) and uniform in solid angle within the pixel, so it has no sin(theta)
   singularity at the poles; the constant background by uniform sphere sampling; the two
   mixed in proportion to their powers. A scene with neither pays nothing for it. The
   details and measurements: docs/design.md, "The environment light". */
typedef struct pt_environment_desc {
    const struct pt_image *map;  /* linear RGB, finite, >= 0, at least 2 x 2 pixels; copied. NULL:
                                    no map (the environment is the background alone) */
    float scale;                 /* multiplies the map; 0: 1; finite and > 0 otherwise */
} pt_environment_desc;
/* Sets (or, with desc NULL or desc->map NULL, removes) the scene's environment map. PT_OK, or
   an error code with pt_scene_error_message naming the bad field. */
PTDEF int pt_scene_set_environment(pt_scene *scene, const pt_environment_desc *desc);
/* What a ray leaving the scene along unit world direction dir sees of the map, scale x map(dir)
   (the background not included); (0, 0, 0) without a map or for a bad scene or direction. */
PTDEF pt_color pt_scene_environment_radiance(const pt_scene *scene, pt_vec3 dir);

/* Shading point passed to a user guide PDF (see pt_render_desc.guide). */
typedef struct pt_shading_point {
    pt_vec3 position;
    pt_vec3 normal;      /* shading normal, flipped to the side of wo */
    pt_vec3 wo;          /* unit, towards the previous vertex */
    int material;
    int depth;           /* 0 at the first surface seen from the camera */
} pt_shading_point;

/* ==========================================================================================
   5. BVH: built by pt_scene_commit (binned SAH; see the implementation for details). It has no
   API of its own: pt_scene_intersect and pt_scene_occluded (section 3) query it.
   ========================================================================================== */

/* ==========================================================================================
   5b. EMBREE TRAVERSAL (optional: define PDFTRACE_EMBREE)
   With PDFTRACE_EMBREE defined in the implementing file (include path with embree3/rtcore.h,
   link -lembree3; `make EMBREE=1`), pt_scene_commit can hand the scene to Intel Embree 3
   instead of building the built-in BVH. Everything else (materials, lights, the integrator,
   the image) is the same; only the closest-hit and any-hit queries change. Without the
   macro the header never includes an Embree header and PT_BACKEND_EMBREE is refused.
   - Every primitive is traced by Embree: triangles (single ones and mesh triangles) as
     Embree triangles; quads and spheres as Embree user geometry whose callbacks run
     pdftrace's own exact tests (section 3), so their hits are the built-in ones bit for bit.
   - pdftrace bakes transforms into primitives when they are added (it has no instance
     objects), so "instances" reach Embree flattened: one copy per placement. (Embree's
     instancing would share the memory of repeated objects; pdftrace does not use it.)
   - Embree's BVH build runs on its own (TBB) threads; rays are traced on pdftrace's render
     threads (or the host's parallel_for). Those set flush-to-zero and denormals-are-zero
     for the duration of each tile, as Embree asks, and restore the previous state, so the
     host's floating-point state is unchanged afterwards. pt_scene_intersect and
     pt_scene_occluded leave the caller's state alone (correct, maybe slower on denormals).
   - The batched integrator (pt_render_desc.integrator; with Embree 3 the default from
     PDFTRACE_EMBREE_MIN_PRIMS primitives, where AUTO chooses Embree) hands Embree
     its batch's rays as one stream (rtcIntersect1M, rtcOccluded1M) rather than one call per
     ray; the hits are the same (PDFTRACE_EMBREE_STREAM=0: per ray). Ties (two primitives at
     the same t) go to a triangle, else to the lowest primitive type and index, whatever order
     Embree visits them in; two triangles at the same t are Embree's to order.
   - Embree errors become pdftrace error codes with Embree's message in
     pt_scene_error_message; the library never aborts. Embree's own code computes with
     inf and NaN on purpose, so every call into it masks SSE floating-point exceptions
     for its duration: a host that traps FE_INVALID or FE_DIVBYZERO keeps working.
   PDFTRACE_EMBREE4: include embree4/rtcore.h and use Embree 4's query arguments (written to
   Embree 4's documentation, not compiled here: untested).
   ========================================================================================== */

/* Chooses the traversal backend that the next pt_scene_commit builds. A different choice on a
   committed scene uncommits it (like adding a shape): commit again before rendering or
   querying (until then they fail with PT_ERROR_INVALID_STATE). So a scene built by
   pt_scenefile_build can be switched and re-committed. PT_BACKEND_EMBREE without
   PDFTRACE_EMBREE compiled in: PT_ERROR_UNSUPPORTED. AUTO (the default) uses Embree, when
   compiled in, for scenes of at least PDFTRACE_EMBREE_MIN_PRIMS primitives (and, if a build
   sets PDFTRACE_EMBREE_SMALL_PRIMS, for tiny scenes made mostly of quads and spheres), and
   falls back to the built-in BVH if Embree fails; an explicit EMBREE reports the failure instead.
   pt_scene_info.backend says which one the commit chose. */
PTDEF int pt_scene_set_backend(pt_scene *scene, pt_backend backend);
/* The configuration string handed to rtcNewDevice at the next commit with Embree (see
   Embree's rtcNewDevice documentation; e.g. "threads=2" caps the threads of its BVH build).
   NULL or "": Embree's defaults (or PDFTRACE_EMBREE_CONFIG). Copied; at most 127 characters.
   A configuration Embree refuses makes an EMBREE commit fail with Embree's error (AUTO falls
   back to the built-in BVH). Without PDFTRACE_EMBREE: PT_ERROR_UNSUPPORTED. */
PTDEF int pt_scene_set_embree_config(pt_scene *scene, const char *config);

/* Run-time SIMD dispatch of the built-in BVH (pt_simd_level). pt_simd_cpu_level: the highest
   level this CPU and build support. pt_simd_set_cap: the highest level later commits may use
   (process-wide; default PT_SIMD_AVX512, i.e. no cap); PT_ERROR_INVALID_ARGUMENT for a value
   out of range. Set it before committing scenes on other threads. pt_simd_get_level: the level
   the next commit chooses, the least of the CPU's, the cap and PDFTRACE_SIMD (an unknown
   PDFTRACE_SIMD makes pt_scene_commit fail with a message naming it). A committed scene keeps
   its level (pt_scene_info.simd_level). pt_simd_level_name: "scalar", "sse2", "avx2",
   "avx512" (NULL out of range). */
PTDEF pt_simd_level pt_simd_cpu_level(void);
PTDEF int pt_simd_set_cap(pt_simd_level cap);
PTDEF pt_simd_level pt_simd_get_level(void);
PTDEF const char *pt_simd_level_name(pt_simd_level level);

/* AUTO uses Embree (when compiled in) for scenes with at least PDFTRACE_EMBREE_MIN_PRIMS
   primitives, and the built-in BVH below. PDFTRACE_EMBREE_SMALL_PRIMS (default 0: off) also
   sends scenes of fewer primitives than it, made mostly of quads and spheres (triangles less
   than half the primitives), to Embree.
   The threshold sits above the largest triangle scene on which the built-in BVH was faster in
   every run of make bench-bvh; from there on Embree is about as fast or faster, and the further
   the larger the scene. On small scenes of quads and spheres the built-in BVH is faster (one
   primitive per leaf, section 5), so the small-scene rule is off. The figures:
   docs/internals.md, "Embree or the built-in BVH". */
#ifndef PDFTRACE_EMBREE_SMALL_PRIMS
#define PDFTRACE_EMBREE_SMALL_PRIMS 0
#endif
#ifndef PDFTRACE_EMBREE_MIN_PRIMS
#define PDFTRACE_EMBREE_MIN_PRIMS 5000
#endif

/* ==========================================================================================
   6. CAMERA: a pinhole or thin-lens camera from look-at parameters. pt_render builds one from
   pt_render_desc.camera; pt_camera_ray gives the same rays to a caller.
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
   How a path chooses its directions (pt_strategy), an optional user PDF mixed into it (a
   guide), the counters of a path, and the scene-feature skips that can be switched off.
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
   pt_render_desc.guide_weight: p_scatter = (1 - g) p_material + g p_guide.
   Called from every render thread at once: `user` must be safe to read concurrently. The
   pt_shading_point is valid only during the call; the pt_pdf written to *out is used while
   that vertex is shaded, which, where the path splits (section 7), goes on after the split
   copies' own calls to the guide at later vertices. So anything it points to (mixture
   components and weights, callback data, a scene) must outlive the call and must not be
   overwritten by later calls: point into `user` or other data that stays unchanged until
   pt_render returns, never into the callback's own stack frame or a per-call scratch buffer. */
typedef int (*pt_guide_fn)(void *user, const pt_shading_point *sp, pt_pdf *out);

/* Counters for one or more paths. */
typedef struct pt_path_stats {
    uint64_t camera_rays, bounce_rays, shadow_rays;
    uint64_t nonfinite_samples;   /* samples that were NaN/Inf, counted and replaced by zero */
    uint64_t split_paths;         /* extra paths started by splitting (section 7, "Splitting") */
    uint64_t guided_vertices;     /* vertices that sampled from a learned guide (path guiding) */
} pt_path_stats;

/* Scene-feature skips (see "SKIPPING WORK A SCENE DOES NOT NEED" at the top). Each skip is on by
   default; a bit set in pt_render_desc.disable_skips makes the integrator take the general path
   for that feature instead (for benchmarks and tests: the image has the same expectation either
   way; "exact" skips give the same image bit for bit, the others consume random numbers
   differently and agree within noise). */
#define PT_SKIP_NO_EMITTERS      (1u << 0) /* no emitters: no light sampling at all. General: light
                                              sampling is attempted (and finds nothing); the mixture
                                              keeps its light component (which ends the path) */
#define PT_SKIP_DELTA_VERTEX     (1u << 2) /* at a delta vertex (mirror, glass): no light sample, no
                                              material evaluation toward it. General: a light is sampled
                                              and the material evaluated (it reflects nothing there). In
                                              a scene with only delta materials this skips light
                                              sampling everywhere */
#define PT_SKIP_FACING_AWAY      (1u << 3) /* mixture, single one-sided emitter facing away from the
                                              vertex: the light component is dropped from the mixture.
                                              General: it stays (its samples fail and end the path) */
#define PT_SKIP_NO_TEXTURES      (1u << 4) /* untextured material: albedo read directly. General: it is
                                              looked up as a constant texture. Exact */
#define PT_SKIP_ZERO_BSDF_SHADOW (1u << 6) /* no shadow ray toward a light sample the material does not
                                              reflect (light below the surface). General: the shadow ray
                                              is traced and its result multiplied by zero. Exact (only
                                              the shadow-ray count differs) */
#define PT_SKIP_SOLID_ANGLE_QUADS (1u << 7) /* a rectangular light that is large next to its distance
                                              is sampled uniformly in solid angle (section 2, spherical
                                              rectangles). General: every quad and triangle light by area
                                              (the same expectation, more variance near large lights) */
#define PT_SKIP_LIGHT_TREE       (1u << 8) /* a scene with PT__LIGHT_TREE_MIN (16) or more emitting shapes
                                              picks the light for next-event estimation by its light
                                              tree (distance and orientation; section 2). General: by
                                              power alone (the same expectation) */
/* bits 1u << 1 and 1u << 5 were PT_SKIP_LIGHT_SELECTION and PT_SKIP_NO_TRIANGLES (removed) */
#define PT_SKIP_ALL              (PT_SKIP_NO_EMITTERS | PT_SKIP_DELTA_VERTEX | PT_SKIP_FACING_AWAY | \
                                  PT_SKIP_NO_TEXTURES | PT_SKIP_ZERO_BSDF_SHADOW | PT_SKIP_SOLID_ANGLE_QUADS | \
                                  PT_SKIP_LIGHT_TREE)

/* The integrator that traces a render's paths (pt_render_desc.integrator). SCALAR traces one
   path at a time, vertex by vertex (the reference). BATCHED advances the paths of a tile's
   samples together in batches, stage by stage (closest hits, emission and light samples, the
   batch's shadow rays, continuation): the same functions in the same order per path, so the
   same image bit for bit. With Embree 3 (section 5b) the batch's closest hits and shadow rays
   go to Embree as streams (rtcIntersect1M, rtcOccluded1M). Path guiding's training iterations
   run batched too, recording the same records; pt_render_stats.batched_samples counts the
   samples the batched integrator took. With the Sobol sampler a split's copies (indirect_paths) are paths of the
   batch too; with independent numbers they run depth first as in SCALAR
   (pt_render_stats.batched_split_paths). */
typedef enum pt_integrator {
    PT_INTEGRATOR_DEFAULT = 0,  /* the faster one as measured (bench/README.md, "make bench-batched" and
                                   "Two revisions side by side"): BATCHED for scenes on the built-in BVH
                                   with AVX2 or better (its stages then run 8 paths at a time; scenes of at
                                   most 64 quads and spheres also trace 8-ray packets) and for scenes of at
                                   least PDFTRACE_EMBREE_MIN_PRIMS primitives traced by Embree 3 (its
                                   batches then go to Embree as streams), else SCALAR */
    PT_INTEGRATOR_SCALAR = 1,
    PT_INTEGRATOR_BATCHED = 2
} pt_integrator;

/* ==========================================================================================
   8. RENDERING: tiles, threads, progressive passes, adaptive sampling, statistics
   A render is described by a pt_render_desc (zero means "default" for every field but the
   image size) and adds samples to a film, which is resolved into an image; pt_render_image
   does all three.
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

/* How adaptive sampling plans (pt_render_desc.adaptive_mode; section 8 of the implementation). */
typedef enum pt_adaptive_mode {
    PT_ADAPTIVE_PILOT = 0,        /* unbiased: adaptive_min_spp pilot samples per pixel, rendered
                                     apart and discarded, fix each pixel's count in the image once */
    PT_ADAPTIVE_OWN_SAMPLES = 1,  /* biased dark: re-planned between passes from the image's samples,
                                     a pixel's own included (1 of the 25 of its 5x5 neighbourhood) */
    PT_ADAPTIVE_NEIGHBOURS = 2    /* biased, less: re-planned, a pixel's own samples left out */
} pt_adaptive_mode;

/* Path guiding (pt_render_desc.guiding; section 8 of the implementation, "Guiding"). */
typedef enum pt_guiding {
    PT_GUIDING_OFF = 0,   /* the material's PDF (and a user guide, if any) alone */
    PT_GUIDING_ON = 1,    /* train a guide (pt_guide) in the first guiding_budget of the samples,
                             then render with p = alpha p_material + (1 - alpha) p_guide */
    PT_GUIDING_AUTO = 2   /* train as ON within a quarter of the budget, whose last iteration
                             measures the efficiency (1 / (error x cost)) with and without the
                             guide (its second half guided at a quarter of the pixels); go on as
                             ON only if the guide pays, else render the rest unguided */
} pt_guiding;

/* Splitting a render (pt_render_desc.split_parts; section 8, "Splitting a render"). A merge hook
   combines a buffer that every part of a split render holds at the same point of the render (the
   same size on every part) in part order: it must leave in `buffer` of part 0, and of every part
   when `everyone` is 1, the result of
       acc = part 0's buffer; for p = 1 .. N-1: add(ctx, acc, part p's buffer)
   (add combines exactly, so any grouping of those calls that keeps the order, e.g. a tree, gives
   the same bytes). It returns 0, or non-zero when it failed (the render then fails on this part; a
   distributed driver should end the job, since the other parts wait in the hook). */
typedef void (*pt_merge_add_fn)(void *ctx, void *acc, const void *part);
typedef int (*pt_merge_fn)(void *user, void *buffer, size_t bytes, int everyone, pt_merge_add_fn add, void *ctx);

/* The most copies pt_render_desc.indirect_paths may ask for. */
#define PT_INDIRECT_PATHS_MAX 8

typedef struct pt_render_desc {
    int width, height;           /* required, > 0 */
    int samples_per_pixel;       /* 0: 16 */
    int samples_per_pass;        /* 0: samples_per_pixel / 16, at least 1 */
    pt_camera_desc camera;
    pt_strategy strategy;        /* 0: PT_STRATEGY_MIS */
    float light_weight;          /* PT_STRATEGY_MIXTURE, in (0, 1]; 0: 0.5 */
    int max_depth;               /* maximum scattering events; 1 = direct light only; 0: 50 */
    int rr_start_depth;          /* Russian roulette from this depth on; 0: 3; < 0: never (its
                                    survival probability depends on the sampler: section 7) */
    int max_splits;              /* splitting: at most this many extra paths per camera sample where
                                    a path's throughput exceeds 2, and indirect_paths' (section 7);
                                    0: 64; < 0: never;
                                    at most 65536 */
    int indirect_paths;          /* each camera sample's path continues from its first non-delta
                                    vertex as this many independent copies (its direct light is
                                    estimated once; they count towards max_splits; section 7);
                                    0: 3 with PT_SAMPLER_SOBOL, 1 (no split) with INDEPENDENT;
                                    at most 8 */
    int threads;                 /* 0: all cores */
    int tile_size;               /* 0: 8 when samples_per_pass >= 8, else 16 */
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
    /* Adaptive sampling (see section 8 of the implementation): each pixel's noise is estimated
       from the sample variances of the pixels of its 5x5 neighbourhood; samples go to the pixels
       in proportion to the square root of their noise per unit of cost (the allocation that
       minimises the image's mean relative squared error for the time spent). By default
       (adaptive_mode PT_ADAPTIVE_PILOT) the noise comes from a pilot render that is discarded,
       so the image is unbiased; the other modes plan from the image's own samples (biased).
       samples_per_pixel is the most any pixel gets (the pilot's samples included); the default
       samples_per_pass becomes samples_per_pixel / 64 (more for each pixel once few pixels
       still sample). */
    float adaptive_threshold;    /* 0: off (every pixel gets samples_per_pixel). Otherwise a finite
                                    value > 0: the RMS relative error sqrt(mean((x-r)^2/(r^2+0.01)))
                                    the image should reach; e.g. 0.05 */
    int adaptive_min_spp;        /* PT_ADAPTIVE_PILOT: the pilot's samples per pixel (the image then
                                    gets 2 to samples_per_pixel - this per pixel; with fewer than
                                    this + 2 samples_per_pixel the render is uniform); other modes:
                                    samples every pixel gets before it can stop. >= 2; 0: a default
                                    of max(16, samples_per_pixel / 16) */
    int adaptive_check_passes;   /* re-planning modes: the shares are re-planned every this many
                                    passes, >= 1; 0: 1 (PT_ADAPTIVE_PILOT plans once) */
    int adaptive_neighbours_only; /* 1: the same as adaptive_mode = PT_ADAPTIVE_NEIGHBOURS (kept for
                                    existing callers; adaptive_mode must then be 0 or that) */
    pt_adaptive_mode adaptive_mode; /* 0: PT_ADAPTIVE_PILOT, unbiased. PT_ADAPTIVE_OWN_SAMPLES: a
                                    pixel that drew a firefly samples on and dilutes it: the lowest
                                    error, but biased dark (pixels that drew none stop sooner; less
                                    as samples grow). PT_ADAPTIVE_NEIGHBOURS: only the 24 other
                                    pixels, a smaller bias (all measured: docs/internals.md,
                                    "Adaptive sampling") */
    unsigned disable_skips;      /* PT_SKIP_* bits: force the general path; 0: every skip on; bits
                                    outside PT_SKIP_ALL: PT_ERROR_INVALID_ARGUMENT */
    pt_sampler sampler;          /* 0: PT_SAMPLER_INDEPENDENT; PT_SAMPLER_SOBOL: randomised
                                    quasi-Monte Carlo (section 2), lower error at equal samples */
    pt_integrator integrator;    /* 0: PT_INTEGRATOR_DEFAULT (see there); SCALAR or BATCHED (the same image) */
    /* Path guiding: a guide (section 2, pt_guide) learned in training iterations of 1, 2, 4, ...
       samples per pixel, each rendered with the guide of the ones before; then the rest of the
       samples with the final guide. Every sample counts in the image with equal weight and each
       is unbiased, so the image is (section 8, "Guiding"). Not with a user guide
       (pt_render_desc.guide); each pt_render call trains afresh (unless guiding_guide). */
    pt_guiding guiding;          /* 0: PT_GUIDING_OFF */
    float guiding_budget;        /* the share of samples_per_pixel training may take, in (0, 1); 0:
                                    0.25. Iterations 1, 2, ..., 2^(T-1) spp: the most T with
                                    2^T - 1 <= budget x samples_per_pixel; T < 2: no guiding */
    float guiding_alpha;         /* the material's share of the guided mixture, in (0, 1); 0: 0.7 */
    int guiding_max_mib;         /* the guide's memory bound in MiB, >= 1; 0: 64 */
    pt_guide *guiding_guide;     /* optional: a guide from pt_guide_create_for_scene(scene) that the
                                    render trains (on from what it holds) and leaves trained, to be
                                    inspected or reused (one never updated takes the render's
                                    fixed-point unit); NULL: the render makes its own */
    /* Splitting a render over processes or machines (section 8, "Splitting a render"; the MPI
       driver in tools/pdftrace.c): with split_parts = N > 1 the call renders part split_part of
       the render, the samples k of pixel i with (i + k) mod N = split_part (the same sample
       indices, hence the same random numbers and Sobol points, as the whole render). Every part
       must get the same scene, desc (but split_part) and film contents. Adding the parts' samples
       to the film in part order (pt_film_add) gives the whole render's film bit for bit, for every
       sampler, strategy and splitting setting. Adaptive sampling needs merge: its decisions are
       made from the merged film, the same on every part. With merge, part 0's film ends holding
       the whole render; without, on the other parts, and after a cancel, each film gets its own
       part's samples (a cancel on one part leaves the others waiting in the hook).
       Not with guiding (PT_ERROR_UNSUPPORTED: section 8 says why). */
    int split_parts;             /* 0 or 1: the whole render; at most 65536 */
    int split_part;              /* 0 .. split_parts - 1 */
    pt_merge_fn merge;           /* optional: the hook that combines the parts (see pt_merge_fn) */
    void *merge_user;
} pt_render_desc;

typedef struct pt_render_stats {
    uint64_t samples;            /* camera samples taken (an adaptive pilot's included) */
    uint64_t camera_rays, bounce_rays, shadow_rays;
    uint64_t nonfinite_samples;  /* NaN/Inf samples caught, zeroed and counted */
    uint64_t split_paths;        /* extra paths started by splitting (section 7) */
    uint64_t guided_vertices;    /* vertices that sampled from a learned guide (path guiding) */
    uint64_t batched_samples;    /* camera samples the batched integrator took (the rest: scalar) */
    uint64_t batched_split_paths; /* of split_paths, those the batched integrator ran as paths of its
                                    batch (the rest ran depth first in the scalar integrator) */
    double seconds;              /* wall clock */
    int passes, threads;
    uint64_t pixels_converged;   /* adaptive: pixels that stopped before samples_per_pixel (the
                                    pilot's samples counted) */
    uint32_t min_spp, max_spp;   /* fewest and most samples this render added to a pixel (to the
                                    film: without the pilot's) */
    double estimated_error;      /* the film's estimated RMS relative error at the end, the square
                                    root of pt_film_error over the whole image; -1 if unknown (a
                                    pixel with fewer than 2 samples) */
    int guiding_used;            /* 1 when the image was rendered with a learned guide */
    int guiding_iterations;      /* training iterations run */
    uint64_t guiding_samples;    /* camera samples of the training iterations (in the image too) */
    double guiding_seconds;      /* wall clock of the training (counted in seconds) */
    double guiding_gain;         /* AUTO: the efficiency the last training iteration measured with
                                    the guide over without (> 1: the guide pays); 0 when not measured */
    size_t guiding_bytes;        /* memory of the guide at the end */
    uint32_t guiding_leaves;     /* its spatial leaves */
    uint64_t guiding_photons;    /* caustic photons traced for the guide (section 8, "Guiding"; 0 in
                                    scenes without a delta surface or a shaped light) */
    double guiding_photon_seconds; /* their wall clock (counted in guiding_seconds) */
    char guiding_note[128];      /* "" without guiding; else what was decided and why */
    char error[256];             /* "" on success; else why the call failed or stopped, naming the one
                                    argument or pt_render_desc field at fault with its value, e.g.
                                    "pt_render_desc.width = 0: must be > 0" */
} pt_render_stats;

/* The film accumulates per pixel the sum and the sum of squares of the samples and their count,
   and the sum of the odd-numbered samples alone (the "B" half-buffer; the even-numbered "A" half
   is sum - sum_odd): 148 bytes per pixel. Each sum is kept as two doubles, sum + low, added with
   error-free transformations (TwoSum, Knuth TAOCP vol. 2, 4.2.2), so it is the exact sum of the
   samples (float values, squared exactly in double) and sum is that exact sum rounded once: the
   film does not depend on the order or grouping in which samples and films are added, which is
   what lets a render be split (section 8, "Splitting a render"). Exact while a pixel's smallest
   non-zero sample is above 2^-80 of its sum (squares: 2^-56 of the sum of squares); below that
   the low word rounds, and the grouping could change sum's last bit with odds of about 2^-50.
   Rendering into a film that already holds samples continues with new sample indices, so renders
   can be resumed and refined. */
typedef struct pt_film {
    int width, height;
    double *sum;      /* 3 per pixel, row 0 at the top: the sums rounded to double */
    double *sum_sq;   /* 3 per pixel */
    uint32_t *count;  /* samples per pixel */
    double *sum_odd;  /* 3 per pixel: the samples with an odd sample index k */
    double *low;      /* 9 per pixel: what sum, sum_sq and sum_odd (3 each, in that order) leave out
                         of the exact sums; a film made by hand may leave it 0 */
} pt_film;

/* An image: linear RGB, as pt_film_resolve makes it and the writers (section 9) take it. */
typedef struct pt_image {
    int width, height;
    float *rgb;       /* 3 floats per pixel, row 0 at the top, linear radiance */
} pt_image;

PTDEF int pt_film_init(pt_film *film, int width, int height);
PTDEF void pt_film_free(pt_film *film);
PTDEF void pt_film_clear(pt_film *film);
/* dst += src, pixel by pixel (exactly: see pt_film; the films must be the same size). The merge of
   a split render's parts, in part order. PT_ERROR_INVALID_ARGUMENT if a pixel's count would pass
   4294967295 (dst is then unchanged). */
PTDEF int pt_film_add(pt_film *dst, const pt_film *src);
/* Adds one sample of value v with sample index k to pixel (x, y), as pt_render does. */
PTDEF int pt_film_add_sample(pt_film *film, int x, int y, uint32_t k, pt_color v);
/* Per-pixel mean into *image (allocated or reallocated to the film's size). */
PTDEF int pt_film_resolve(const pt_film *film, pt_image *image);
/* Mean of pixel (x, y) and the variance of that mean (sample variance / count). */
PTDEF int pt_film_pixel(const pt_film *film, int x, int y, pt_color *mean, pt_color *variance_of_mean);
/* The half-buffer error estimate for the pixels x0 <= x < x1, y0 <= y < y1: the mean over
   pixels and channels of (A - B)^2 nA nB / n^2 / (I^2 + 0.01), where A and B are the means of
   the even- and odd-numbered samples (nA, nB of them), I the pixel mean and n = nA + nB.
   (A - B)^2 nA nB / n^2 is an unbiased estimate of the variance of I, so *rel_mse estimates
   the region's relMSE mean((I - r)^2 / (r^2 + 0.01)). Pixels with fewer than 2 samples count
   as unknown: *rel_mse is then +Inf. pt_render reports its square root over the whole image as
   pt_render_stats.estimated_error; adaptive sampling does not use it (it plans from each
   pixel's sample variance, section 8). */
PTDEF int pt_film_error(const pt_film *film, int x0, int y0, int x1, int y1, double *rel_mse);

PTDEF int pt_image_init(pt_image *image, int width, int height);
PTDEF void pt_image_free(pt_image *image);

/* Renders desc->samples_per_pixel more samples into every pixel of the film (with adaptive
   sampling at most that many), which the caller initialised with pt_film_init(film,
   desc->width, desc->height). Returns PT_OK, PT_ERROR_CANCELLED (the film holds what was done)
   or an error. stats may be NULL; if not, stats->error says why a call failed (the scene's
   message is not written: see section 3 on threads). */
PTDEF int pt_render(const pt_scene *scene, const pt_render_desc *desc, pt_film *film, pt_render_stats *stats);
/* Convenience: a fresh film, rendered and resolved into *image. */
PTDEF int pt_render_image(const pt_scene *scene, const pt_render_desc *desc, pt_image *image, pt_render_stats *stats);
/* Radiance along one camera ray: one path-traced sample, with the desc's strategy, depth and
   splitting (indirect_paths, whose default follows desc->sampler, as roulette's q does:
   section 7). The desc's width, height and camera are not used, nor its sampler otherwise (every number comes from *rng, which advances). stats may be NULL. Non-finite results
   are counted in stats and returned as zero. The direction is normalised unless it is already
   unit length to float precision (then it is used as given, so a pt_camera_ray sample traced
   here equals the one pt_render takes). */
PTDEF pt_color pt_trace_path(const pt_scene *scene, const pt_render_desc *desc, pt_ray ray, pt_rng *rng,
                             pt_path_stats *stats);

/* ==========================================================================================
   9. OUTPUT: image writers (OpenEXR: pdftrace_exr.h)
   ========================================================================================== */

/* Writers. Each writes to a new temporary file beside the target (pt_output_open) and renames it
   into place, so a failed write leaves no partial file (and no temporary). PFM: linear float RGB
   (little-endian, bottom row first as the format requires). PPM: binary P6, sRGB-encoded,
   clamped to [0, 1]. They return PT_OK, PT_ERROR_INVALID_ARGUMENT (no path, an empty image),
   PT_ERROR_OUT_OF_MEMORY or PT_ERROR_IO. The _ex forms also write a one-line message into
   err[0 .. err_size-1] when err is not NULL ("" on success), as pt_write_exr does
   (pdftrace_exr.h): "dir/x.ppm: writing PPM: cannot create 'dir/x.ppm.1a2b3c4d.ptmp': No such
   file or directory" (the path and the system's reason). Safe to call from several threads at
   once (the only shared state is the registry of temporaries, behind a mutex). */
PTDEF int pt_write_pfm(const char *path, const pt_image *image);
PTDEF int pt_write_ppm(const char *path, const pt_image *image);
PTDEF int pt_write_pfm_ex(const char *path, const pt_image *image, char *err, size_t err_size);
/* Reads a PFM file (colour "PF" or greyscale "Pf", either byte order, rows stored bottom first)
   into *out (overwritten, not freed: pass an empty or freed image; left empty on failure), row
   0 at the top. Images over PDFTRACE_PFM_MAX_PIXELS (default 2^28) are refused before anything
   is allocated for them. PT_OK, PT_ERROR_IO (missing, unreadable, not a PFM, truncated),
   PT_ERROR_UNSUPPORTED (too large) or PT_ERROR_OUT_OF_MEMORY, with a one-line message naming
   the file in err when it is not NULL. Values are returned as stored (NaN and Inf included). */
PTDEF int pt_read_pfm(const char *path, pt_image *out, char *err, size_t err_size);
PTDEF int pt_write_ppm_ex(const char *path, const pt_image *image, char *err, size_t err_size);
PTDEF float pt_srgb_encode(float linear); /* IEC 61966-2-1 transfer function, clamped */
PTDEF float pt_srgb_decode(float encoded); /* its inverse, linear from encoded in [0, 1] (clamped) */

/* The temporary file every writer of the family (this header, pdftrace_exr.h, pdftrace_png.h,
   pdftrace_scene.h) writes through; for writers of other formats too. pt_output_open creates
   "<path>.XXXXXXXX.ptmp" in the target's directory exclusively (POSIX: O_CREAT | O_EXCL |
   O_NOFOLLOW, so a file or symlink planted there is never followed or reused; permissions 0666
   less the umask, as fopen's), opens it as t->file ("wb", or "w" when text) and registers its name
   for pt_output_remove_temporaries. pt_output_close flushes and closes it and, when ok is nonzero,
   renames it onto path; on any failure, or when ok is 0, the temporary is removed. Both return
   PT_OK, PT_ERROR_INVALID_ARGUMENT, PT_ERROR_OUT_OF_MEMORY or PT_ERROR_IO and write
   "path: writing <what>: <step> '<temporary>': <reason>" into err (reason: the system's strerror,
   e.g. "No space left on device"). pt_output_close must follow every successful pt_output_open.
   Without POSIX (no <fcntl.h>) the exclusive creation is a check then fopen, which a concurrent
   process can race. */
typedef struct pt_output_file {
    FILE *file;     /* the open temporary */
    char *tmp_path; /* its name (owned) */
    const char *path; /* the target, as given (not copied) */
    int slot;       /* the registry's slot, -1 if not registered */
} pt_output_file;
PTDEF int pt_output_open(pt_output_file *t, const char *path, int text, const char *what, char *err, size_t err_size);
PTDEF int pt_output_close(pt_output_file *t, int ok, const char *what, char *err, size_t err_size);
/* Removes every temporary an output writer of this process has open (at most 16 are tracked at
   once; more still work, untracked). Async-signal-safe: call it from a SIGINT/SIGTERM handler,
   which then re-raises the signal; nothing else in this header is safe there. */
PTDEF void pt_output_remove_temporaries(void);

/* Display transform for the 8-bit outputs: each channel is multiplied by 2^exposure and mapped
   to display-linear [0, 1], which pt_write_ppm (and pdftrace_png.h's pt_write_png) then
   sRGB-encode. The operators, on each channel x >= 0 (negative values and NaN become 0):
     CLAMP     min(x, 1).
     REINHARD  x / (1 + x): the global operator, eq. 3 of Reinhard, Stark, Shirley, Ferwerda,
               "Photographic Tone Reproduction for Digital Images", SIGGRAPH 2002. The paper
               applies it to luminance; here it maps each channel, so that every channel stays
               below 1 without a second clip (very bright saturated colours go toward white).
     ACES      x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14), clamped to 1: K. Narkowicz's fit of
               the ACES RRT + ODT, "ACES Filmic Tone Mapping Curve" (2016),
               https://knarkowicz.wordpress.com/2016/01/06/aces-filmic-tone-mapping-curve/ (per
               channel, as there; its input is pre-exposed: 1 maps to 0.80). */
typedef enum pt_tonemap { PT_TONEMAP_CLAMP = 0, PT_TONEMAP_REINHARD, PT_TONEMAP_ACES } pt_tonemap;
typedef struct pt_display_desc {
    float exposure;              /* EV: multiply by 2^exposure; 0: none. Must be finite */
    pt_tonemap tonemap;          /* 0: PT_TONEMAP_CLAMP */
} pt_display_desc;
/* Writes the display transform of src into *dst, which is allocated or reallocated to src's
   size as by pt_film_resolve; dst may be src (in place). d may be NULL (exposure 0, clamp).
   A non-finite exposure or an unknown tonemap: PT_ERROR_INVALID_ARGUMENT, dst unchanged. */
PTDEF int pt_image_apply_display(const pt_image *src, const pt_display_desc *d, pt_image *dst);

#ifdef __cplusplus
}
#endif

#ifdef PT__CONTRACT_PUBLIC
PT__CONTRACT_RESTORE
#endif
#endif /* PDFTRACE_H */

/* ==========================================================================================
   IMPLEMENTATION
   ========================================================================================== */
#ifdef PDFTRACE_IMPLEMENTATION
#ifndef PDFTRACE_IMPLEMENTATION_DONE
#define PDFTRACE_IMPLEMENTATION_DONE

PT__CONTRACT_OFF /* no FMA contraction (defined with the public part) */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdarg.h>
#include <float.h>
#include <limits.h>
#include <time.h>
#include <errno.h>
#ifndef PDFTRACE_NO_THREADS
#include <pthread.h>
#include <unistd.h>
#endif
#ifdef PDFTRACE_EMBREE
#ifdef PDFTRACE_EMBREE4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif
#if defined(__SSE__) || defined(_M_X64) || (defined(_M_IX86_FP) && _M_IX86_FP >= 1)
#include <xmmintrin.h> /* _mm_getcsr/_mm_setcsr: flush-to-zero and denormals-are-zero */
#define PT__HAVE_MXCSR 1
#endif
#endif

#if defined(PT_MALLOC) && defined(PT_FREE) && defined(PT_REALLOC)
/* all three given */
#elif !defined(PT_MALLOC) && !defined(PT_FREE) && !defined(PT_REALLOC)
#define PT_MALLOC(sz) malloc(sz)
#define PT_REALLOC(p, sz) realloc(p, sz)
#define PT_FREE(p) free(p)
#else
#error "pdftrace: define all of PT_MALLOC, PT_REALLOC and PT_FREE, or none"
#endif

/* SSE2 (baseline on x86-64) for the BVH's 4-wide box and triangle tests; scalar code elsewhere. */
#if !defined(PDFTRACE_NO_SIMD) && (defined(__SSE2__) || defined(_M_X64) || (defined(_M_IX86_FP) && _M_IX86_FP >= 2))
#include <emmintrin.h>
#define PT__SSE 1
#endif
/* Wider BVH nodes, chosen at run time (pt_simd_level): 8 children with AVX2 and AVX-512F (16
   with PDFTRACE_AVX512_WIDTH=16).
   Only gcc and clang on x86 compile them (per-function target attributes and
   __builtin_cpu_supports); other compilers and architectures get the SSE2 or scalar code. */
#if defined(PT__SSE) && !defined(PDFTRACE_NO_WIDE_BVH) && (defined(__GNUC__) || defined(__clang__)) && \
    (defined(__x86_64__) || defined(__i386__))
#include <immintrin.h>
#define PT__WIDE 1
#define PT__TARGET_AVX2 __attribute__((target("avx2")))
#define PT__TARGET_AVX512 __attribute__((target("avx512f")))
#endif

#ifndef PT_ASSERT
#include <assert.h>
#define PT_ASSERT(x) assert(x)
#endif

#define PT__PI 3.14159265358979323846f
#define PT__INV_PI 0.31830988618379067154f
#define PT__INV_4PI 0.07957747154594766788f
#define PT__INF FLT_MAX
/* Largest coordinate magnitude accepted for shapes: products of two coordinates (dot and cross
   products, squared radii) stay finite in float. */
#define PT__MAX_COORD 1e18f
#if defined(__GNUC__) || defined(__clang__)
#define PT__HOT inline __attribute__((always_inline))
#define PT__NOINLINE __attribute__((noinline)) /* rarely run: kept out of the hot caller's code */
#define PT__UNLIKELY(x) __builtin_expect(!!(x), 0)
#else
#define PT__HOT inline
#define PT__NOINLINE
#define PT__UNLIKELY(x) (x)
#endif

#ifdef __cplusplus
extern "C" {
#endif

PTDEF const char *pt_result_string(int code)
{
    switch (code) {
    case PT_OK: return "ok";
    case PT_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case PT_ERROR_OUT_OF_MEMORY: return "out of memory";
    case PT_ERROR_IO: return "input/output error";
    case PT_ERROR_INVALID_STATE: return "invalid state";
    case PT_ERROR_CANCELLED: return "cancelled";
    case PT_ERROR_THREAD: return "thread error";
    case PT_ERROR_UNSUPPORTED: return "unsupported";
    default: return "unknown error";
    }
}

/* ------------------------------------------------------------------------------------------
   0. Internal types: the private representation of a scene, shared by every section below.
   Shapes become pt__prim records (one per sphere, quad or triangle, geometry baked into world
   space when added); materials, textures and lights are flat arrays indexed by id. The BVH's
   node and leaf layouts (section 5) and the Embree handles (section 5b) are declared here too,
   because struct pt_scene holds them. Types used inside one section only are declared there.
   pt__fail records a scene function's error message (pt_scene_error_message).
   ------------------------------------------------------------------------------------------ */

enum { PT__PRIM_SPHERE = 0, PT__PRIM_QUAD = 1, PT__PRIM_TRIANGLE = 2 };

typedef struct pt__prim {
    pt_vec3 p0;       /* sphere: centre | quad: Q | triangle: a */
    pt_vec3 p1;       /* sphere: (radius, 0, 0) | quad: u | triangle: b */
    pt_vec3 p2;       /* quad: v | triangle: c */
    pt_vec3 n;        /* quad, triangle: unit geometric normal */
    pt_vec3 w;        /* quad: v x w0 and ... */
    pt_vec3 w2;       /* ... w0 x u, with w0 = n'/(n'.n'), n' = u x v: a = h.w, b = h.w2 */
    pt_vec3 mag;      /* set at commit (pt__prim_cache): per-axis magnitude (pt__prim_magnitude) */
    float inset[2];   /* set at commit, quad: how far inside [0, 1] pt__fill_hit keeps a and b */
    uint32_t id;      /* public primitive index */
    int32_t material;
    int32_t light;    /* index into scene->lights, or -1 */
    int32_t normals;  /* first of 3 shading normals in scene->normals, or -1 */
    int32_t type;     /* PT__PRIM_* */
    int32_t uvs;      /* mesh triangle: first of 6 floats (u, v per corner) in scene->uvs, or -1 */
} pt__prim;

/* Per-ray data computed once per traversal. */
typedef struct pt__rayctx {
    pt_vec3 o, d;
    int kx, ky, kz;       /* watertight triangle test: axis permutation */
    float sx, sy, sz;     /* and shear */
    int triangles;        /* whether the permutation and shear were set up */
} pt__rayctx;

typedef struct pt__material {
    pt_material_type type;
    pt_color albedo;
    int texture;      /* 0 or texture id */
    float fuzz, ior;
    pt_color emission;
    int two_sided, emits, delta, scatters;
    float alpha, alpha2;  /* rough conductor and dielectric: GGX alpha and alpha^2 */
    int transmits;        /* a non-delta rough dielectric: scattered directions go below ng too */
    int fresnel;          /* rough conductor: 0 for F = 1, else eta + i k */
    pt_color eta, k;
    /* rough plastic (section 4, "coated plastic"): the coat's index, 1/ior^2, its diffuse internal
       reflectance, the specular share of the sampling mixture, nonlinear, and the coat's
       transmittance at cos = k / (PT__COAT_RES - 1) */
    float coat_ior, coat_inv_ior2, coat_rint, coat_wspec;
    int nonlinear;
    float coat_t[64];
} pt__material;

/* A texture: the 3-D checker (rgb NULL) or an image (w x h linear RGB, row 0 at v = 0). */
typedef struct pt__texture {
    pt_color even, odd; float inv_scale;
    int w, h;
    float *rgb;
} pt__texture;

typedef struct pt__light {
    uint32_t prim;    /* index into scene->prims (after BVH ordering) */
    double power;     /* in double: radiance near FLT_MAX or near denormal still has a power */
    float select_pdf, cdf;
    float area;
} pt__light;

/* A node of the light tree (section 2, "light tree"): the bounds, power and normal cone of the
   lights below it. */
typedef struct pt__lnode {
    pt_vec3 lo, hi;      /* the lights' bounds */
    pt_vec3 centre;      /* of the bounds, and the square of their half diagonal (the distance */
    float r2;            /* term is clamped to it: a point among the lights is not infinitely near) */
    pt_vec3 axis;        /* the normals' cone: its axis (unit), */
    float cos_o, sin_o;  /* the cosine and sine of its half-angle (cos -1: every direction), */
    float cos_e;         /* the cosine of the emission's angle beyond the normals (0: pi/2), */
    float pmin;          /* and the least of axis . x over the bounds */
    float power;
    uint32_t a, b;       /* children; a leaf: a = the light's index, b = PT__LNODE_LEAF */
} pt__lnode;
#define PT__LNODE_LEAF 0xffffffffu
/* The light tree as the sampler walks it: each node holds up to eight children side by side (the
   binary tree's nodes three levels down), so one AVX2 pass, or two SSE passes, bound all eight
   (section 2, "light tree"). */
#define PT__LTREE_W 8
#define PT__LTREE_BITS 3 /* log2 PT__LTREE_W: a child's lane in a light's trail */
typedef struct pt__lnodew {
    float lo[3][PT__LTREE_W], hi[3][PT__LTREE_W];         /* per axis, per child: as in pt__lnode */
    float centre[3][PT__LTREE_W], axis[3][PT__LTREE_W];
    float r2[PT__LTREE_W], cos_o[PT__LTREE_W], sin_o[PT__LTREE_W], cos_e[PT__LTREE_W], pmin[PT__LTREE_W];
    float power[PT__LTREE_W]; /* an empty child has power 0 */
    uint32_t child[PT__LTREE_W]; /* a node's index, or PT__LCHILD_LIGHT | a light's index */
} pt__lnodew;
#define PT__LCHILD_LIGHT 0x80000000u

/* A delta light (pt_scene_add_light). */
typedef struct pt__dlight {
    pt_light_desc desc;  /* as added, transformed, defaults resolved; position in the caller's
                            coordinates (relative to a fixed origin, if any) */
    pt_vec3 pos;         /* relative to the scene's origin (commit) */
    pt_vec3 axis;        /* unit: the spot's axis, the directional light's direction of travel */
    float cutoff, beam, inv_transition; /* SPOT (radians) */
    float tan_in, tan_out; /* SPOT: the falloff's shortcuts (pt__spot_bounds) */
    float mean;          /* the intensity's mean (commit) */
    double power;        /* picks it (commit) */
    float select_pdf, cdf;
} pt__dlight;
/* Up to this many delta lights are picked by what each gives the vertex (pt__delta_prepare). */
#define PT__DELTA_PICK_MAX 16u

/* The environment map (pt_scene_set_environment) and its sampling tables: a pixel's cell is
   the rectangle [x, x+1) / W by [y, y+1) / H of (u, v); its probability is row_pmf x the
   conditional, stored as cell_density = P(cell) / (cell's solid angle). */
typedef struct pt__env {
    int w, h;
    float *rgb;           /* w x h x 3, the scale applied */
    float *row_cdf;       /* h + 1: the marginal over rows (0 .. 1) */
    float *col_cdf;       /* h x (w + 1): each row's conditional over its columns */
    float *cell_density;  /* w x h: solid-angle density of the map's sampling in each cell */
    int *row_guide;       /* h + 1, and h x (w + 1): guide tables of the cdfs (pt__cdf_find) */
    int *col_guide;
    double *cos_edge;     /* h + 1: cos(theta) at each row edge, cos(pi y / H) */
    float rot[3][3];      /* the map's frame into the world (a rotation) */
    double mean;          /* the mean over the sphere of the channel-mean radiance */
    float scale;          /* as given (pt_environment_desc.scale, resolved) */
} pt__env;
static void pt__env_free(pt__env *e);

#ifdef PDFTRACE_EMBREE
/* The user data of an Embree user geometry: the scene and its primID -> prims index map. */
typedef struct pt__rtc_geom { const pt_scene *scene; const uint32_t *map; float pad; } pt__rtc_geom;
/* The Embree side of a committed scene (section 5b). Geometry ids are the primitive types
   (PT__PRIM_*): one Embree geometry per type present. */
typedef struct pt__rtc {
    RTCDevice device;
    RTCScene scene;
    uint32_t *map[3];          /* per geometry: Embree primID -> index into scene->prims */
    uint32_t count[3];
    pt__rtc_geom user[3];
    long long device_bytes;    /* the device's memory, from its memory monitor */
    int error_code;            /* first RTCError reported by the error callback (0: none) */
    char error_text[160];
} pt__rtc;
#endif

/* The BVH (section 5): 4-wide nodes; leaves in a pool of 16-byte units, each a header (block
   counts) followed by blocks of four triangles, of four quads and of four other primitives. */
typedef struct pt__node4 {
    float box[6][4];  /* lo x, hi x, lo y, hi y, lo z, hi z of the four children (empty: lo > hi) */
    uint32_t child[4];/* node index, or PT__BVH_LEAF | offset of the leaf in the pool */
    uint32_t pad[4];  /* 128 bytes: two cache lines */
} pt__node4;
/* Wider nodes over the same leaves (pt_simd_level): 8 and 16 children, rows as in pt__node4. */
typedef struct pt__node8 {
    float box[6][8];
    uint32_t child[8];
} pt__node8;
typedef struct pt__node16 {
    float box[6][16];
    uint32_t child[16];
} pt__node16;
typedef struct pt__leaf16 {
    uint32_t u[4];    /* leaf header: triangle, quad, sphere blocks, 0 */
} pt__leaf16;
typedef struct pt__tri4 {
    float v[9][4];    /* v[3 * vertex + axis][lane] */
    uint32_t prim[4]; /* index into scene->prims */
} pt__tri4;
typedef struct pt__quad4 {
    float v[14][4];   /* Q, unit normal, w, w2 (pt__prim fields), by axis, then lane; then the
                         largest a and b margins pt__hit_quad can accept (pt__quad_edge_caps) */
    uint32_t prim[4];
} pt__quad4;
typedef struct pt__sphere4 {
    float v[4][4];    /* centre x, y, z, radius, then lane */
    uint32_t prim[4];
} pt__sphere4;

struct pt_scene {
    pt__prim *prims;
    uint32_t prim_count, prim_cap;
    pt__material *mats;
    uint32_t mat_count, mat_cap;
    pt__texture *texs;
    uint32_t tex_count, tex_cap;
    pt_vec3 *normals;
    uint32_t normal_count, normal_cap;
    float *uvs;                /* mesh uvs: 6 floats per triangle that has them (pt__prim.uvs) */
    uint32_t uv_count, uv_cap;
    void *bvh_mem;    /* one allocation: nodes then the leaf pool, aligned to 64 bytes */
    pt__node4 *nodes;
    pt__leaf16 *pool;
    uint32_t node_count, bvh_depth;
    size_t bvh_bytes;
    int simd;                  /* pt_simd_level chosen at the last commit */
    unsigned bvh_width;        /* 4, or 8 / 16: the wide nodes (over the same leaves) traversal uses */
    void *wide_mem, *wide;     /* the wide nodes' allocation, and the nodes in it (aligned to 64) */
    uint32_t wide_count;
    pt__light *lights;
    uint32_t light_count;
    double total_power;
    pt__lnodew *ltree;         /* the light tree (commit; NULL: fewer than PT__LIGHT_TREE_MIN lights) */
    uint64_t *ltrail;          /* per light: its path from the root, three bits (the child) per level */
    uint32_t ltree_count;
    pt__dlight *dlights;       /* delta lights, in the order added */
    uint32_t dlight_count, dlight_cap;
    pt__env *env;              /* the environment map (NULL: none) */
    pt_transform xf;
    int xf_identity;
    int committed;
    unsigned features;
    uint32_t sphere_count, quad_count, triangle_count, mesh_count, degenerate_skipped;
    pt_vec3 lo, hi;
    int backend_request;       /* pt_backend from pt_scene_set_backend */
    char embree_config[128];   /* pt_scene_set_embree_config */
    int backend;               /* what the last commit built: PT_BACKEND_BUILTIN or _EMBREE */
    double build_seconds;
    size_t accel_bytes;
#ifdef PDFTRACE_EMBREE
    pt__rtc rtc;
#endif
    double origin[3];          /* the scene's centre: prims [0, placed) are stored relative to it */
    int has_origin;            /* origin is not (0, 0, 0) */
    int fixed_origin;          /* pt_scene_set_origin: commit keeps it, every shape is relative to it */
    uint32_t placed;
    uint32_t fine_prims;       /* pt_scene_info.precision_warnings */
    char warning[200];         /* pt_scene_info.precision_warning */
    char error[256];
};

/* A world point (the public API's) into the scene's stored coordinates and back, in double:
   the exact difference of two nearby floats, then rounded once. */
static pt_vec3 pt__to_local(const pt_scene *s, pt_vec3 p)
{
    if (!s->has_origin) return p;
    return pt_v3((float)((double)p.x - s->origin[0]), (float)((double)p.y - s->origin[1]),
                 (float)((double)p.z - s->origin[2]));
}
static pt_vec3 pt__to_world(const pt_scene *s, pt_vec3 p)
{
    if (!s->has_origin) return p;
    return pt_v3((float)((double)p.x + s->origin[0]), (float)((double)p.y + s->origin[1]),
                 (float)((double)p.z + s->origin[2]));
}

/* A failed call that changes the scene records why. Not const: calls that only read a scene
   (queries, renders) cannot write it, so they may run on several threads at once. */
static int pt__fail(pt_scene *scene, int code, const char *fmt, ...)
{
    if (scene) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(scene->error, sizeof scene->error, fmt, ap);
        va_end(ap);
    }
    return code;
}
/* Every public call that changes a scene starts here, so its message describes that call alone
   ("" once it succeeds). Returns scene (NULL: the caller fails with PT_ERROR_INVALID_ARGUMENT). */
static pt_scene *pt__enter(pt_scene *scene)
{
    if (scene) scene->error[0] = '\0';
    return scene;
}
/* A per-call message (no shared state): formats into err[0 .. size-1] when err is not NULL. */
static int pt__msg(char *err, size_t size, int code, const char *fmt, ...)
{
    if (err && size) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, size, fmt, ap);
        va_end(ap);
    }
    return code;
}

/* ------------------------------------------------------------------------------------------
   1. Math: what the inline vector functions of the header do not cover. Finite tests on the bit
   pattern (so that -ffast-math builds still catch NaN and Inf); the offset of a ray origin off
   a surface (Waechter & Binder, Ray Tracing Gems ch. 6, 2019, scaled to the scene, below);
   affine transforms (Rodrigues' rotation) and normals by the cofactor matrix; the orthonormal
   basis of Duff et al. (JCGT 6(1), 2017); PCG32 seeding (O'Neill 2014) and the per-sample
   streams, hashed with SplitMix64 (Steele, Lea & Flood 2014) so that a sample's numbers depend
   only on (seed, pixel, sample index).
   ------------------------------------------------------------------------------------------ */

/* isfinite on the bit pattern, so that -ffast-math builds still catch NaN and Inf. */
static int pt__isfinite(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return (u & 0x7f800000u) != 0x7f800000u;
}
static int pt__vfinite(pt_vec3 v) { return pt__isfinite(v.x) && pt__isfinite(v.y) && pt__isfinite(v.z); }
static float pt__minf(float a, float b) { return a < b ? a : b; }
static double pt__mind(double a, double b) { return a < b ? a : b; }
static double pt__maxd(double a, double b) { return a > b ? a : b; }
static float pt__maxf(float a, float b) { return a > b ? a : b; }
static float pt__safe_sqrt(float x) { return sqrtf(x > 0.0f ? x : 0.0f); }
static pt_vec3 pt__vmin(pt_vec3 a, pt_vec3 b) { return pt_v3(pt__minf(a.x, b.x), pt__minf(a.y, b.y), pt__minf(a.z, b.z)); }
static pt_vec3 pt__vmax(pt_vec3 a, pt_vec3 b) { return pt_v3(pt__maxf(a.x, b.x), pt__maxf(a.y, b.y), pt__maxf(a.z, b.z)); }
static float pt__vmaxabs(pt_vec3 v) { return pt__maxf(fabsf(v.x), pt__maxf(fabsf(v.y), fabsf(v.z))); }
static float pt__vget(pt_vec3 v, int axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }
static int pt__is_black(pt_vec3 c) { return c.x <= 0.0f && c.y <= 0.0f && c.z <= 0.0f; }
static int pt__color_ok(pt_color c) { return pt__vfinite(c) && c.x >= 0.0f && c.y >= 0.0f && c.z >= 0.0f; }

/* Waechter & Binder, Ray Tracing Gems ch. 6: move each coordinate by int(256 n_i) ulps in
   the direction of the normal (integer arithmetic on the float bits), or by n_i/65536 near
   the origin where ulps are too small to matter. */
#ifndef PT__SSE
static float pt__int_as_float(int32_t i) { float f; memcpy(&f, &i, sizeof f); return f; }
static int32_t pt__float_as_int(float f) { int32_t i; memcpy(&i, &f, sizeof i); return i; }
static float pt__offset_coord(float p, float n, float magnitude)
{
    const float origin = magnitude * (1.0f / 32.0f), float_scale = magnitude * (1.0f / 65536.0f), int_scale = 256.0f;
    int32_t of_i = (int32_t)(int_scale * n);
    float p_i = pt__int_as_float(pt__float_as_int(p) + ((p < 0.0f) ? -of_i : of_i));
    return fabsf(p) < origin ? p + float_scale * n : p_i;
}
#endif
static PT__HOT pt_vec3 pt__offset_origin(pt_vec3 p, pt_vec3 n, pt_vec3 w, float magnitude)
{
    if (pt_dot(n, w) < 0.0f) n = pt_neg(n);
    if (!(magnitude >= 0.0f) || !pt__isfinite(magnitude)) magnitude = 1.0f;
    /* never below p's own size, and never 0: the ulp step is only valid away from 0 (from
       p_i = 0 towards -n_i it would build a NaN), so a coordinate at 0 must take the additive path */
    magnitude = pt__maxf(magnitude, pt__vmaxabs(p));
    if (!(magnitude > 0.0f)) magnitude = FLT_MIN;
#ifdef PT__SSE
    {
        /* pt__offset_coord's operations on the three coordinates at once (the same results) */
        const __m128 p4 = _mm_set_ps(0.0f, p.z, p.y, p.x), n4 = _mm_set_ps(0.0f, n.z, n.y, n.x);
        const __m128 m4 = _mm_set1_ps(magnitude);
        __m128i of = _mm_cvttps_epi32(_mm_mul_ps(_mm_set1_ps(256.0f), n4));
        const __m128i neg = _mm_castps_si128(_mm_cmplt_ps(p4, _mm_setzero_ps()));
        __m128 p_i, p_f, near;
        float out[4];
        of = _mm_sub_epi32(_mm_xor_si128(of, neg), neg); /* -of_i where p < 0 */
        p_i = _mm_castsi128_ps(_mm_add_epi32(_mm_castps_si128(p4), of));
        p_f = _mm_add_ps(p4, _mm_mul_ps(_mm_mul_ps(m4, _mm_set1_ps(1.0f / 65536.0f)), n4));
        near = _mm_cmplt_ps(_mm_andnot_ps(_mm_set1_ps(-0.0f), p4), _mm_mul_ps(m4, _mm_set1_ps(1.0f / 32.0f)));
        _mm_storeu_ps(out, _mm_or_ps(_mm_and_ps(near, p_f), _mm_andnot_ps(near, p_i)));
        return pt_v3(out[0], out[1], out[2]);
    }
#else
    return pt_v3(pt__offset_coord(p.x, n.x, magnitude), pt__offset_coord(p.y, n.y, magnitude),
                 pt__offset_coord(p.z, n.z, magnitude));
#endif
}
PTDEF pt_vec3 pt_offset_ray_origin_scaled(pt_vec3 p, pt_vec3 n, pt_vec3 w, float magnitude)
{
    return pt__offset_origin(p, n, w, magnitude);
}
PTDEF pt_vec3 pt_offset_ray_origin(pt_vec3 p, pt_vec3 n, pt_vec3 w) { return pt__offset_origin(p, n, w, 1.0f); }

PTDEF pt_transform pt_transform_identity(void)
{
    pt_transform t;
    memset(&t, 0, sizeof t);
    t.m[0][0] = t.m[1][1] = t.m[2][2] = 1.0f;
    return t;
}
PTDEF pt_transform pt_transform_translate(pt_vec3 v)
{
    pt_transform t = pt_transform_identity();
    t.m[0][3] = v.x; t.m[1][3] = v.y; t.m[2][3] = v.z;
    return t;
}
PTDEF pt_transform pt_transform_scale(pt_vec3 s)
{
    pt_transform t = pt_transform_identity();
    t.m[0][0] = s.x; t.m[1][1] = s.y; t.m[2][2] = s.z;
    return t;
}
/* Rodrigues' rotation formula, in matrix form. */
PTDEF pt_transform pt_transform_rotate(pt_vec3 axis, float degrees)
{
    pt_transform t = pt_transform_identity();
    pt_vec3 a = pt_normalize(axis);
    double th = (double)degrees * 3.14159265358979323846 / 180.0;
    float c = (float)cos(th), s = (float)sin(th), k = 1.0f - c;
    if (pt_length2(a) == 0.0f) return t;
    t.m[0][0] = a.x * a.x * k + c;       t.m[0][1] = a.x * a.y * k - a.z * s; t.m[0][2] = a.x * a.z * k + a.y * s;
    t.m[1][0] = a.y * a.x * k + a.z * s; t.m[1][1] = a.y * a.y * k + c;       t.m[1][2] = a.y * a.z * k - a.x * s;
    t.m[2][0] = a.z * a.x * k - a.y * s; t.m[2][1] = a.z * a.y * k + a.x * s; t.m[2][2] = a.z * a.z * k + c;
    return t;
}
PTDEF pt_transform pt_transform_rotate_y(float degrees) { return pt_transform_rotate(pt_v3(0, 1, 0), degrees); }
PTDEF pt_transform pt_transform_mul(pt_transform a, pt_transform b)
{
    pt_transform r;
    int i, j;
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 4; ++j) {
            r.m[i][j] = a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j] + a.m[i][2] * b.m[2][j];
        }
        r.m[i][3] += a.m[i][3];
    }
    return r;
}
PTDEF pt_vec3 pt_transform_point(const pt_transform *t, pt_vec3 p)
{
    return pt_v3(t->m[0][0] * p.x + t->m[0][1] * p.y + t->m[0][2] * p.z + t->m[0][3],
                 t->m[1][0] * p.x + t->m[1][1] * p.y + t->m[1][2] * p.z + t->m[1][3],
                 t->m[2][0] * p.x + t->m[2][1] * p.y + t->m[2][2] * p.z + t->m[2][3]);
}
PTDEF pt_vec3 pt_transform_vector(const pt_transform *t, pt_vec3 v)
{
    return pt_v3(t->m[0][0] * v.x + t->m[0][1] * v.y + t->m[0][2] * v.z,
                 t->m[1][0] * v.x + t->m[1][1] * v.y + t->m[1][2] * v.z,
                 t->m[2][0] * v.x + t->m[2][1] * v.y + t->m[2][2] * v.z);
}
/* n' = (M^-1)^T n, computed as the cofactor matrix of M times n (the determinant only scales). */
PTDEF int pt_transform_normal(const pt_transform *t, pt_vec3 n, pt_vec3 *out)
{
    pt_vec3 c0 = pt_v3(t->m[0][0], t->m[1][0], t->m[2][0]);
    pt_vec3 c1 = pt_v3(t->m[0][1], t->m[1][1], t->m[2][1]);
    pt_vec3 c2 = pt_v3(t->m[0][2], t->m[1][2], t->m[2][2]);
    pt_vec3 r0 = pt_cross(c1, c2), r1 = pt_cross(c2, c0), r2 = pt_cross(c0, c1);
    float det = pt_dot(c0, r0);
    pt_vec3 m;
    if (!out) return PT_ERROR_INVALID_ARGUMENT;
    if (det == 0.0f || !pt__isfinite(det)) { *out = pt_v3(0, 0, 0); return PT_ERROR_INVALID_ARGUMENT; }
    m = pt_v3(r0.x * n.x + r1.x * n.y + r2.x * n.z,
              r0.y * n.x + r1.y * n.y + r2.y * n.z,
              r0.z * n.x + r1.z * n.y + r2.z * n.z);
    if (det < 0.0f) m = pt_neg(m);
    *out = pt_normalize(m);
    return PT_OK;
}
static float pt__transform_det(const pt_transform *t)
{
    pt_vec3 c0 = pt_v3(t->m[0][0], t->m[1][0], t->m[2][0]);
    pt_vec3 c1 = pt_v3(t->m[0][1], t->m[1][1], t->m[2][1]);
    pt_vec3 c2 = pt_v3(t->m[0][2], t->m[1][2], t->m[2][2]);
    return pt_dot(c0, pt_cross(c1, c2));
}

/* Duff, Burgess, Christensen, Hery, Kensler, Liani & Villemin, "Building an Orthonormal
   Basis, Revisited", JCGT 6(1), 2017: branch-free, exact at n.z = -1 thanks to copysign. */
static PT__HOT pt_onb pt__onb(pt_vec3 n)
{
    pt_onb b;
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float c = n.x * n.y * a;
    b.s = pt_v3(1.0f + sign * n.x * n.x * a, sign * c, -sign * n.x);
    b.t = pt_v3(c, sign + n.y * n.y * a, -n.y);
    b.n = n;
    return b;
}
PTDEF pt_onb pt_onb_from_normal(pt_vec3 n) { return pt__onb(n); }

/* PCG32 seeding as in O'Neill's reference: state = 0, inc = 2*stream+1, step, add seed, step. */
PTDEF void pt_rng_seed(pt_rng *r, uint64_t seed, uint64_t stream)
{
    if (!r) return;
    r->state = 0u;
    r->inc = (stream << 1u) | 1u;
    (void)pt_rng_u32(r);
    r->state += seed;
    (void)pt_rng_u32(r);
}
/* SplitMix64 finaliser (Steele, Lea & Flood, "Fast Splittable Pseudorandom Number
   Generators", OOPSLA 2014) hashes (seed, pixel, sample) into a PCG state and stream. */
static uint64_t pt__mix64(uint64_t z)
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}
PTDEF pt_rng pt_rng_for_sample(uint64_t seed, uint32_t pixel, uint32_t sample)
{
    pt_rng r;
    uint64_t key = ((uint64_t)pixel << 32) | (uint64_t)sample;
    uint64_t h1 = pt__mix64(seed + 0x9e3779b97f4a7c15ULL);
    uint64_t h2 = pt__mix64(key ^ h1);
    uint64_t h3 = pt__mix64(h2 + 0x9e3779b97f4a7c15ULL);
    pt_rng_seed(&r, h2, h3);
    return r;
}

/* ------------------------------------------------------------------------------------------
   2. Sampling and PDFs: where the integrator's random numbers come from, and the densities it
   samples. The integrator draws through a pt__sampler: in INDEPENDENT mode every draw is the
   next number of the sample's PCG stream, in the order the integrator asks; in SOBOL mode a
   draw names its set (PT__SET_*: pixel, lens, and per bounce light choice, light point, scatter
   direction, ...), whose value is a function of (seed, pixel, sample index, set) alone, so a
   set keeps its dimensions whatever branches a path took before it (Burley, "Practical
   Hash-based Owen Scrambling", JCGT 9(4), 2020). Then the warps from the unit square (Shirley &
   Chiu's concentric disk, Malley's method), the light densities (a sphere's cone, area sampling
   of quads and triangles, the scene's lights picked by power), the fuzzy metal lobe, and the
   public pt_pdf, whose sampling and density agree by construction: a mixture's density is
   sum_k w_k p_k, never the density of the component that was chosen.
   ------------------------------------------------------------------------------------------ */

/* ---- Samplers (pt_sampler). A set's point (pt_sobol_scrambled), for sample index k and a
   64-bit set seed:
   1. Shuffle: k' = a nested uniform scramble of k's low 16 bits (a random permutation in which
      bit b of k' depends only on bits >= b of k, so each aligned block of 2^m indices maps onto
      an aligned block of 2^m: the first 2^m samples are still a whole block of the sequence;
      Burley 2020, sec. 4). Independent shuffles decorrelate sets that share the sequence
      ("padding", Kollig & Keller, "Efficient Multidimensional Sampling", EG 2002; pbrt-v4's
      PaddedSobolSampler).
   2. Sobol's (0,2)-sequence at k': x0 = van der Corput (the bits of k' reversed), x1 = the
      generator matrix of Sobol's second dimension (Sobol 1967; Joe & Kuo, "Constructing Sobol
      sequences with better two-dimensional projections", SIAM J. Sci. Comput. 30(5), 2008:
      primitive polynomial x + 1, m_1 = 1, so m_k = m_{k-1} xor 2 m_{k-1}).
   3. Owen scramble of each coordinate (Owen, "Randomly permuted (t,m,s)-nets and
      (t,s)-sequences", 1995): a random nested permutation of the binary digits, made by
      reversing the bits and applying a hash in which each output bit depends only on the seed
      and the bits below it (Laine & Karras, "Stratified sampling for stochastic transparency",
      EGSR 2011; Burley 2020, sec. 3), then reversing back.
   Step 3 starts by adding a uniform 32-bit seed, and the rest is a bijection fixed by seeds
   independent of it, so every coordinate is exactly uniform over the 2^32 binary fractions
   whatever k is: each sample is uniform on the unit square and the estimator unbiased. Seeds
   come from SplitMix64 (pt__mix64) of (seed, pixel, set). */

/* The bits of x in reverse order: bits within bytes swapped in three steps, then the bytes. */
static uint32_t pt__reverse_bits(uint32_t x)
{
    x = ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_bswap32(x);
#else
    x = ((x >> 8) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8);
    return (x >> 16) | (x << 16);
#endif
}
/* A random permutation of 32-bit words in which output bit b is input bit b xor a function of the
   seeds and input bits 0..b-1: adding, multiplying by an odd number and x ^= x * (an even number)
   each have that form, and so has their composition (Laine & Karras 2011). Applied to reversed
   bits it is a nested uniform (Owen) scramble of the binary fraction. The multiplier is a second,
   independent seed (a seed-dependent multiply mixes better: Vegdahl, "Building a Better LK Hash",
   2021); the even constants are ours. For a uniform `add` the result is exactly uniform whatever
   x and `mul_odd` are: x + add is uniform and the rest is a bijection fixed by `mul_odd`. The
   multiplier comes odd (pt__sobol_seeds stores it so). */
static uint32_t pt__nested_hash(uint32_t x, uint32_t add, uint32_t mul_odd)
{
    x += add;
    x ^= x * 0xf9b439fcu;
    x *= mul_odd;
    x ^= x * 0x91d93080u;
    x ^= x * 0x8142c8eau;
    return x;
}
/* Sobol's second coordinate of point i, bit-reversed. Its direction numbers are v_j = m_{j+1} /
   2^{j+1} with m_k = m_{k-1} xor 2 m_{k-1}, m_1 = 1: m_{j+1} = (1 + x)^j over GF(2), row j of
   Pascal's triangle mod 2, a palindrome, so reversed v_j has bit b set iff C(j, b) is odd, iff b's
   bits are a subset of j's (Lucas). Bit b of the result is then the parity of i's set bits j that
   are supersets of b: the GF(2) superset-sum transform of i's bit vector, five butterfly steps. */
static uint32_t pt__sobol1_reversed(uint32_t i)
{
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    return i ^ (i >> 16);
}
/* Sobol's dimensions 2 and 3, bit-reversed, from the same superset/subset idea as a table: the
   direction numbers v_j (j = 0..31) of Joe & Kuo's d = 3 (s = 2, a = 1, m = 1, 3) and d = 4
   (s = 3, a = 1, m = 1, 3, 1), each reversed, dimension 2 in the low word and 3 in the high word
   (Bratley & Fox, "Algorithm 659", ACM TOMS 14(1), 1988: m_k = 2 a_1 m_{k-1} ^ ... ^ 2^s m_{k-s}
   ^ m_{k-s}, v_j = m_{j+1} / 2^{j+1}; tests/test_sampler.c rebuilds them from the recurrence). */
static const uint64_t pt__sobol23_rdir[32] = {
    0x0000000100000001ULL, 0x0000000300000003ULL, 0x0000000400000006ULL, 0x0000000a00000009ULL,
    0x0000001f00000017ULL, 0x0000002e0000003aULL, 0x0000004500000071ULL, 0x000000c9000000a3ULL,
    0x0000011b00000116ULL, 0x000002a400000339ULL, 0x0000079a00000677ULL, 0x00000b67000009aaULL,
    0x0000101e00001601ULL, 0x0000302d00003903ULL, 0x0000404100007706ULL, 0x0000a0c30000aa09ULL,
    0x0001f10400010117ULL, 0x0002e28a0003033aULL, 0x000457df00060671ULL, 0x000c9bae000909a3ULL,
    0x0011a10500171616ULL, 0x002a7289003a3939ULL, 0x0079e7db00717777ULL, 0x00b6dba400a3aaaaULL,
    0x0100011a01170001ULL, 0x030002a7033a0003ULL, 0x0400079e06710006ULL, 0x0a000b6d09a30009ULL,
    0x1f00100116160017ULL, 0x2e0030033939003aULL, 0x4500400477770071ULL, 0xc900a00aaaaa00a3ULL};
/* Sobol's coordinates 2 (low word) and 3 (high word) of point i, bit-reversed: the xor of the
   reversed direction numbers of i's set bits. */
static uint64_t pt__sobol23_reversed(uint32_t i)
{
    uint64_t x = 0u;
#if defined(__GNUC__) || defined(__clang__)
    for (; i; i &= i - 1u) x ^= pt__sobol23_rdir[__builtin_ctz(i)];
#else
    int j;
    for (j = 0; i; ++j, i >>= 1)
        if (i & 1u) x ^= pt__sobol23_rdir[j];
#endif
    return x;
}
/* The same for the low 16 bits of i, by nibbles: row j, entry n is the xor of the reversed
   direction numbers of n's bits placed at 4j .. 4j + 3 (made from pt__sobol23_rdir). */
static const uint64_t pt__sobol23_rnibble[4][16] = {
    {0x0000000000000000ULL, 0x0000000100000001ULL, 0x0000000300000003ULL, 0x0000000200000002ULL,
     0x0000000400000006ULL, 0x0000000500000007ULL, 0x0000000700000005ULL, 0x0000000600000004ULL,
     0x0000000a00000009ULL, 0x0000000b00000008ULL, 0x000000090000000aULL, 0x000000080000000bULL,
     0x0000000e0000000fULL, 0x0000000f0000000eULL, 0x0000000d0000000cULL, 0x0000000c0000000dULL},
    {0x0000000000000000ULL, 0x0000001f00000017ULL, 0x0000002e0000003aULL, 0x000000310000002dULL,
     0x0000004500000071ULL, 0x0000005a00000066ULL, 0x0000006b0000004bULL, 0x000000740000005cULL,
     0x000000c9000000a3ULL, 0x000000d6000000b4ULL, 0x000000e700000099ULL, 0x000000f80000008eULL,
     0x0000008c000000d2ULL, 0x00000093000000c5ULL, 0x000000a2000000e8ULL, 0x000000bd000000ffULL},
    {0x0000000000000000ULL, 0x0000011b00000116ULL, 0x000002a400000339ULL, 0x000003bf0000022fULL,
     0x0000079a00000677ULL, 0x0000068100000761ULL, 0x0000053e0000054eULL, 0x0000042500000458ULL,
     0x00000b67000009aaULL, 0x00000a7c000008bcULL, 0x000009c300000a93ULL, 0x000008d800000b85ULL,
     0x00000cfd00000fddULL, 0x00000de600000ecbULL, 0x00000e5900000ce4ULL, 0x00000f4200000df2ULL},
    {0x0000000000000000ULL, 0x0000101e00001601ULL, 0x0000302d00003903ULL, 0x0000203300002f02ULL,
     0x0000404100007706ULL, 0x0000505f00006107ULL, 0x0000706c00004e05ULL, 0x0000607200005804ULL,
     0x0000a0c30000aa09ULL, 0x0000b0dd0000bc08ULL, 0x000090ee0000930aULL, 0x000080f00000850bULL,
     0x0000e0820000dd0fULL, 0x0000f09c0000cb0eULL, 0x0000d0af0000e40cULL, 0x0000c0b10000f20dULL}};
static uint64_t pt__sobol23_reversed16(uint32_t i)
{
    return pt__sobol23_rnibble[0][i & 15u] ^ pt__sobol23_rnibble[1][(i >> 4) & 15u] ^
           pt__sobol23_rnibble[2][(i >> 8) & 15u] ^ pt__sobol23_rnibble[3][(i >> 12) & 15u];
}
PTDEF uint32_t pt_sobol_u32(uint32_t index, int dim)
{
    if (dim == 0) return pt__reverse_bits(index);
    if (dim == 1) return pt__reverse_bits(pt__sobol1_reversed(index));
    if (dim == 2) return pt__reverse_bits((uint32_t)pt__sobol23_reversed(index));
    if (dim == 3) return pt__reverse_bits((uint32_t)(pt__sobol23_reversed(index) >> 32));
    return 0u;
}
/* The bits of a byte in reverse order (tests/test_sampler.c checks every entry). */
static const unsigned char pt__reverse_byte[256] = {
    0x00, 0x80, 0x40, 0xc0, 0x20, 0xa0, 0x60, 0xe0, 0x10, 0x90, 0x50, 0xd0, 0x30, 0xb0, 0x70, 0xf0,
    0x08, 0x88, 0x48, 0xc8, 0x28, 0xa8, 0x68, 0xe8, 0x18, 0x98, 0x58, 0xd8, 0x38, 0xb8, 0x78, 0xf8,
    0x04, 0x84, 0x44, 0xc4, 0x24, 0xa4, 0x64, 0xe4, 0x14, 0x94, 0x54, 0xd4, 0x34, 0xb4, 0x74, 0xf4,
    0x0c, 0x8c, 0x4c, 0xcc, 0x2c, 0xac, 0x6c, 0xec, 0x1c, 0x9c, 0x5c, 0xdc, 0x3c, 0xbc, 0x7c, 0xfc,
    0x02, 0x82, 0x42, 0xc2, 0x22, 0xa2, 0x62, 0xe2, 0x12, 0x92, 0x52, 0xd2, 0x32, 0xb2, 0x72, 0xf2,
    0x0a, 0x8a, 0x4a, 0xca, 0x2a, 0xaa, 0x6a, 0xea, 0x1a, 0x9a, 0x5a, 0xda, 0x3a, 0xba, 0x7a, 0xfa,
    0x06, 0x86, 0x46, 0xc6, 0x26, 0xa6, 0x66, 0xe6, 0x16, 0x96, 0x56, 0xd6, 0x36, 0xb6, 0x76, 0xf6,
    0x0e, 0x8e, 0x4e, 0xce, 0x2e, 0xae, 0x6e, 0xee, 0x1e, 0x9e, 0x5e, 0xde, 0x3e, 0xbe, 0x7e, 0xfe,
    0x01, 0x81, 0x41, 0xc1, 0x21, 0xa1, 0x61, 0xe1, 0x11, 0x91, 0x51, 0xd1, 0x31, 0xb1, 0x71, 0xf1,
    0x09, 0x89, 0x49, 0xc9, 0x29, 0xa9, 0x69, 0xe9, 0x19, 0x99, 0x59, 0xd9, 0x39, 0xb9, 0x79, 0xf9,
    0x05, 0x85, 0x45, 0xc5, 0x25, 0xa5, 0x65, 0xe5, 0x15, 0x95, 0x55, 0xd5, 0x35, 0xb5, 0x75, 0xf5,
    0x0d, 0x8d, 0x4d, 0xcd, 0x2d, 0xad, 0x6d, 0xed, 0x1d, 0x9d, 0x5d, 0xdd, 0x3d, 0xbd, 0x7d, 0xfd,
    0x03, 0x83, 0x43, 0xc3, 0x23, 0xa3, 0x63, 0xe3, 0x13, 0x93, 0x53, 0xd3, 0x33, 0xb3, 0x73, 0xf3,
    0x0b, 0x8b, 0x4b, 0xcb, 0x2b, 0xab, 0x6b, 0xeb, 0x1b, 0x9b, 0x5b, 0xdb, 0x3b, 0xbb, 0x7b, 0xfb,
    0x07, 0x87, 0x47, 0xc7, 0x27, 0xa7, 0x67, 0xe7, 0x17, 0x97, 0x57, 0xd7, 0x37, 0xb7, 0x77, 0xf7,
    0x0f, 0x8f, 0x4f, 0xcf, 0x2f, 0xaf, 0x6f, 0xef, 0x1f, 0x9f, 0x5f, 0xdf, 0x3f, 0xbf, 0x7f, 0xff};
/* Step 3's last part for one coordinate: h is the scrambled value bit-reversed; the float is the
   top 24 bits of reverse(h) over 2^24 (as pt_rng_float takes a word's top 24 bits), i.e. h's low
   24 bits reversed: three byte look-ups instead of a whole 32-bit reversal. */
static float pt__reversed_fraction_float(uint32_t h)
{
    uint32_t f = ((uint32_t)pt__reverse_byte[h & 0xffu] << 16) | ((uint32_t)pt__reverse_byte[(h >> 8) & 0xffu] << 8) |
                 (uint32_t)pt__reverse_byte[(h >> 16) & 0xffu];
    return (float)(int32_t)f * (1.0f / 16777216.0f);
}
/* Step 3 for one coordinate given bit-reversed: the Owen-scrambled value as a float. */
static float pt__owen_float(uint32_t x_reversed, uint32_t add, uint32_t mul_odd)
{
    return pt__reversed_fraction_float(pt__nested_hash(x_reversed, add, mul_odd));
}
/* A set's seeds for steps 1 and 3, all from its 64-bit seed by SplitMix64 (pt__mix64):
   h1 = mix64(seed) and h2 = mix64(h1 ^ c1) give the shuffle's (addend h1's low word, multiplier
   that word shifted down 15) and coordinates 0 and 1's (addends h1's high word and h2's low word;
   multipliers h2's top 16 bits and its bits 32..47); h3 = mix64(h2 ^ c2) and h4 = mix64(h3 ^ c1)
   give coordinates 2 and 3's (addends h3's low and high words, multipliers h4's), made only for
   the sets that draw them (mul[2] = 0 until then). Multipliers are stored odd (pt__nested_hash). */
typedef struct pt__sobol_seeds {
    uint64_t seed;  /* the set seed they come from */
    uint32_t shuffle_add, shuffle_mul;
    uint32_t add[4], mul[4];
} pt__sobol_seeds;
static PT__NOINLINE void pt__sobol_seeds_make(pt__sobol_seeds *e, uint64_t seed)
{
    uint64_t h1 = pt__mix64(seed), h2 = pt__mix64(h1 ^ 0x2545f4914f6cdd1dULL);
    e->seed = seed;
    e->shuffle_add = (uint32_t)h1;
    e->shuffle_mul = ((uint32_t)h1 >> 15) | 1u;
    e->add[0] = (uint32_t)(h1 >> 32);
    e->mul[0] = (uint32_t)(h2 >> 48) | 1u;
    e->add[1] = (uint32_t)h2;
    e->mul[1] = ((uint32_t)(h2 >> 32) & 0xffffu) | 1u;
    e->add[2] = e->add[3] = e->mul[2] = e->mul[3] = 0u;
}
static PT__NOINLINE void pt__sobol_seeds_make23(pt__sobol_seeds *e)
{
    uint64_t h2 = pt__mix64(pt__mix64(e->seed) ^ 0x2545f4914f6cdd1dULL);
    uint64_t h3 = pt__mix64(h2 ^ 0x6c62272e07bb0142ULL), h4 = pt__mix64(h3 ^ 0x2545f4914f6cdd1dULL);
    e->add[2] = (uint32_t)h3;
    e->mul[2] = (uint32_t)h4 | 1u;
    e->add[3] = (uint32_t)(h3 >> 32);
    e->mul[3] = (uint32_t)(h4 >> 32) | 1u;
}
/* Step 1's last part by look-ups: entry b of row 0 is (reverse(b) | Sobol dimension 1's reversed
   coordinate of index reverse(b) << 16), of row 1 the same for reverse(b) << 8 (each coordinate
   of a 16-bit index fits 16 bits). */
static const uint32_t pt__sobol_shuffle_bytes[2][256] = {
    {0x00000000, 0x00ff0080, 0x00550040, 0x00aa00c0, 0x00330020, 0x00cc00a0, 0x00660060, 0x009900e0,
     0x00110010, 0x00ee0090, 0x00440050, 0x00bb00d0, 0x00220030, 0x00dd00b0, 0x00770070, 0x008800f0,
     0x000f0008, 0x00f00088, 0x005a0048, 0x00a500c8, 0x003c0028, 0x00c300a8, 0x00690068, 0x009600e8,
     0x001e0018, 0x00e10098, 0x004b0058, 0x00b400d8, 0x002d0038, 0x00d200b8, 0x00780078, 0x008700f8,
     0x00050004, 0x00fa0084, 0x00500044, 0x00af00c4, 0x00360024, 0x00c900a4, 0x00630064, 0x009c00e4,
     0x00140014, 0x00eb0094, 0x00410054, 0x00be00d4, 0x00270034, 0x00d800b4, 0x00720074, 0x008d00f4,
     0x000a000c, 0x00f5008c, 0x005f004c, 0x00a000cc, 0x0039002c, 0x00c600ac, 0x006c006c, 0x009300ec,
     0x001b001c, 0x00e4009c, 0x004e005c, 0x00b100dc, 0x0028003c, 0x00d700bc, 0x007d007c, 0x008200fc,
     0x00030002, 0x00fc0082, 0x00560042, 0x00a900c2, 0x00300022, 0x00cf00a2, 0x00650062, 0x009a00e2,
     0x00120012, 0x00ed0092, 0x00470052, 0x00b800d2, 0x00210032, 0x00de00b2, 0x00740072, 0x008b00f2,
     0x000c000a, 0x00f3008a, 0x0059004a, 0x00a600ca, 0x003f002a, 0x00c000aa, 0x006a006a, 0x009500ea,
     0x001d001a, 0x00e2009a, 0x0048005a, 0x00b700da, 0x002e003a, 0x00d100ba, 0x007b007a, 0x008400fa,
     0x00060006, 0x00f90086, 0x00530046, 0x00ac00c6, 0x00350026, 0x00ca00a6, 0x00600066, 0x009f00e6,
     0x00170016, 0x00e80096, 0x00420056, 0x00bd00d6, 0x00240036, 0x00db00b6, 0x00710076, 0x008e00f6,
     0x0009000e, 0x00f6008e, 0x005c004e, 0x00a300ce, 0x003a002e, 0x00c500ae, 0x006f006e, 0x009000ee,
     0x0018001e, 0x00e7009e, 0x004d005e, 0x00b200de, 0x002b003e, 0x00d400be, 0x007e007e, 0x008100fe,
     0x00010001, 0x00fe0081, 0x00540041, 0x00ab00c1, 0x00320021, 0x00cd00a1, 0x00670061, 0x009800e1,
     0x00100011, 0x00ef0091, 0x00450051, 0x00ba00d1, 0x00230031, 0x00dc00b1, 0x00760071, 0x008900f1,
     0x000e0009, 0x00f10089, 0x005b0049, 0x00a400c9, 0x003d0029, 0x00c200a9, 0x00680069, 0x009700e9,
     0x001f0019, 0x00e00099, 0x004a0059, 0x00b500d9, 0x002c0039, 0x00d300b9, 0x00790079, 0x008600f9,
     0x00040005, 0x00fb0085, 0x00510045, 0x00ae00c5, 0x00370025, 0x00c800a5, 0x00620065, 0x009d00e5,
     0x00150015, 0x00ea0095, 0x00400055, 0x00bf00d5, 0x00260035, 0x00d900b5, 0x00730075, 0x008c00f5,
     0x000b000d, 0x00f4008d, 0x005e004d, 0x00a100cd, 0x0038002d, 0x00c700ad, 0x006d006d, 0x009200ed,
     0x001a001d, 0x00e5009d, 0x004f005d, 0x00b000dd, 0x0029003d, 0x00d600bd, 0x007c007d, 0x008300fd,
     0x00020003, 0x00fd0083, 0x00570043, 0x00a800c3, 0x00310023, 0x00ce00a3, 0x00640063, 0x009b00e3,
     0x00130013, 0x00ec0093, 0x00460053, 0x00b900d3, 0x00200033, 0x00df00b3, 0x00750073, 0x008a00f3,
     0x000d000b, 0x00f2008b, 0x0058004b, 0x00a700cb, 0x003e002b, 0x00c100ab, 0x006b006b, 0x009400eb,
     0x001c001b, 0x00e3009b, 0x0049005b, 0x00b600db, 0x002f003b, 0x00d000bb, 0x007a007b, 0x008500fb,
     0x00070007, 0x00f80087, 0x00520047, 0x00ad00c7, 0x00340027, 0x00cb00a7, 0x00610067, 0x009e00e7,
     0x00160017, 0x00e90097, 0x00430057, 0x00bc00d7, 0x00250037, 0x00da00b7, 0x00700077, 0x008f00f7,
     0x0008000f, 0x00f7008f, 0x005d004f, 0x00a200cf, 0x003b002f, 0x00c400af, 0x006e006f, 0x009100ef,
     0x0019001f, 0x00e6009f, 0x004c005f, 0x00b300df, 0x002a003f, 0x00d500bf, 0x007f007f, 0x008000ff},
    {0x00000000, 0xffff8000, 0x55554000, 0xaaaac000, 0x33332000, 0xcccca000, 0x66666000, 0x9999e000,
     0x11111000, 0xeeee9000, 0x44445000, 0xbbbbd000, 0x22223000, 0xddddb000, 0x77777000, 0x8888f000,
     0x0f0f0800, 0xf0f08800, 0x5a5a4800, 0xa5a5c800, 0x3c3c2800, 0xc3c3a800, 0x69696800, 0x9696e800,
     0x1e1e1800, 0xe1e19800, 0x4b4b5800, 0xb4b4d800, 0x2d2d3800, 0xd2d2b800, 0x78787800, 0x8787f800,
     0x05050400, 0xfafa8400, 0x50504400, 0xafafc400, 0x36362400, 0xc9c9a400, 0x63636400, 0x9c9ce400,
     0x14141400, 0xebeb9400, 0x41415400, 0xbebed400, 0x27273400, 0xd8d8b400, 0x72727400, 0x8d8df400,
     0x0a0a0c00, 0xf5f58c00, 0x5f5f4c00, 0xa0a0cc00, 0x39392c00, 0xc6c6ac00, 0x6c6c6c00, 0x9393ec00,
     0x1b1b1c00, 0xe4e49c00, 0x4e4e5c00, 0xb1b1dc00, 0x28283c00, 0xd7d7bc00, 0x7d7d7c00, 0x8282fc00,
     0x03030200, 0xfcfc8200, 0x56564200, 0xa9a9c200, 0x30302200, 0xcfcfa200, 0x65656200, 0x9a9ae200,
     0x12121200, 0xeded9200, 0x47475200, 0xb8b8d200, 0x21213200, 0xdedeb200, 0x74747200, 0x8b8bf200,
     0x0c0c0a00, 0xf3f38a00, 0x59594a00, 0xa6a6ca00, 0x3f3f2a00, 0xc0c0aa00, 0x6a6a6a00, 0x9595ea00,
     0x1d1d1a00, 0xe2e29a00, 0x48485a00, 0xb7b7da00, 0x2e2e3a00, 0xd1d1ba00, 0x7b7b7a00, 0x8484fa00,
     0x06060600, 0xf9f98600, 0x53534600, 0xacacc600, 0x35352600, 0xcacaa600, 0x60606600, 0x9f9fe600,
     0x17171600, 0xe8e89600, 0x42425600, 0xbdbdd600, 0x24243600, 0xdbdbb600, 0x71717600, 0x8e8ef600,
     0x09090e00, 0xf6f68e00, 0x5c5c4e00, 0xa3a3ce00, 0x3a3a2e00, 0xc5c5ae00, 0x6f6f6e00, 0x9090ee00,
     0x18181e00, 0xe7e79e00, 0x4d4d5e00, 0xb2b2de00, 0x2b2b3e00, 0xd4d4be00, 0x7e7e7e00, 0x8181fe00,
     0x01010100, 0xfefe8100, 0x54544100, 0xababc100, 0x32322100, 0xcdcda100, 0x67676100, 0x9898e100,
     0x10101100, 0xefef9100, 0x45455100, 0xbabad100, 0x23233100, 0xdcdcb100, 0x76767100, 0x8989f100,
     0x0e0e0900, 0xf1f18900, 0x5b5b4900, 0xa4a4c900, 0x3d3d2900, 0xc2c2a900, 0x68686900, 0x9797e900,
     0x1f1f1900, 0xe0e09900, 0x4a4a5900, 0xb5b5d900, 0x2c2c3900, 0xd3d3b900, 0x79797900, 0x8686f900,
     0x04040500, 0xfbfb8500, 0x51514500, 0xaeaec500, 0x37372500, 0xc8c8a500, 0x62626500, 0x9d9de500,
     0x15151500, 0xeaea9500, 0x40405500, 0xbfbfd500, 0x26263500, 0xd9d9b500, 0x73737500, 0x8c8cf500,
     0x0b0b0d00, 0xf4f48d00, 0x5e5e4d00, 0xa1a1cd00, 0x38382d00, 0xc7c7ad00, 0x6d6d6d00, 0x9292ed00,
     0x1a1a1d00, 0xe5e59d00, 0x4f4f5d00, 0xb0b0dd00, 0x29293d00, 0xd6d6bd00, 0x7c7c7d00, 0x8383fd00,
     0x02020300, 0xfdfd8300, 0x57574300, 0xa8a8c300, 0x31312300, 0xcecea300, 0x64646300, 0x9b9be300,
     0x13131300, 0xecec9300, 0x46465300, 0xb9b9d300, 0x20203300, 0xdfdfb300, 0x75757300, 0x8a8af300,
     0x0d0d0b00, 0xf2f28b00, 0x58584b00, 0xa7a7cb00, 0x3e3e2b00, 0xc1c1ab00, 0x6b6b6b00, 0x9494eb00,
     0x1c1c1b00, 0xe3e39b00, 0x49495b00, 0xb6b6db00, 0x2f2f3b00, 0xd0d0bb00, 0x7a7a7b00, 0x8585fb00,
     0x07070700, 0xf8f88700, 0x52524700, 0xadadc700, 0x34342700, 0xcbcba700, 0x61616700, 0x9e9ee700,
     0x16161700, 0xe9e99700, 0x43435700, 0xbcbcd700, 0x25253700, 0xdadab700, 0x70707700, 0x8f8ff700,
     0x08080f00, 0xf7f78f00, 0x5d5d4f00, 0xa2a2cf00, 0x3b3b2f00, 0xc4c4af00, 0x6e6e6f00, 0x9191ef00,
     0x19191f00, 0xe6e69f00, 0x4c4c5f00, 0xb3b3df00, 0x2a2a3f00, 0xd5d5bf00, 0x7f7f7f00, 0x8080ff00}};
/* Step 1: the shuffled index k of the sample whose index is reverse(index_reversed) and whose
   index's high 16 bits are index_high (= index & 0xffff0000), and *k1 = pt__sobol1_reversed(k)
   given index_high1 = pt__sobol1_reversed(index_high). The shuffle scrambles the index's low 16
   bits (the top 16 of index_reversed) and keeps its high ones: k = reverse(r) with r = the hash's
   top 16 bits over index_reversed's low 16, so k = index_high | the hash's top 16 bits reversed
   (two byte look-ups, which also give dimension 1, a linear function of k over GF(2)). */
static uint32_t pt__sobol_shuffle(const pt__sobol_seeds *e, uint32_t index_reversed, uint32_t index_high,
                                  uint32_t index_high1, uint32_t *k1)
{
    uint32_t h = pt__nested_hash(index_reversed, e->shuffle_add, e->shuffle_mul);
    uint32_t v = pt__sobol_shuffle_bytes[1][(h >> 16) & 0xffu] ^ pt__sobol_shuffle_bytes[0][h >> 24];
    *k1 = index_high1 ^ (v >> 16);
    return index_high | (v & 0xffffu);
}
/* Steps 2 and 3: dims (1 or 2) coordinates 0 and 1 of the point with shuffled index k (van der
   Corput's fraction is reverse(k), so its reversal is k itself). */
static void pt__sobol_point01(const pt__sobol_seeds *e, uint32_t k, uint32_t k1, float *u)
{
    u[0] = pt__owen_float(k, e->add[0], e->mul[0]);
    u[1] = pt__owen_float(k1, e->add[1], e->mul[1]);
}
/* Coordinates 2 and 3 of the point. */
static void pt__sobol_point23(pt__sobol_seeds *e, uint32_t k, float *u)
{
    uint64_t x = pt__sobol23_reversed16(k) ^ pt__sobol23_reversed(k & 0xffff0000u);
    if (!e->mul[2]) pt__sobol_seeds_make23(e);
    u[0] = pt__owen_float((uint32_t)x, e->add[2], e->mul[2]);
    u[1] = pt__owen_float((uint32_t)(x >> 32), e->add[3], e->mul[3]);
}
/* The public functions' point: dimensions 0 and 1 of set `seed` at sample `index` into u, the
   set's seeds into *e; returns the shuffled index (for dimensions 2 and 3). */
static uint32_t pt__sobol_point_at(pt__sobol_seeds *e, uint32_t index, uint64_t seed, float *u)
{
    uint32_t k, k1;
    pt__sobol_seeds_make(e, seed);
    k = pt__sobol_shuffle(e, pt__reverse_bits(index), index & 0xffff0000u, pt__sobol1_reversed(index & 0xffff0000u), &k1);
    pt__sobol_point01(e, k, k1, u);
    return k;
}
PTDEF void pt_sobol_scrambled(uint32_t index, uint64_t seed, float u[2])
{
    pt__sobol_seeds e;
    if (u) (void)pt__sobol_point_at(&e, index, seed, u);
}
PTDEF void pt_sobol_scrambled4(uint32_t index, uint64_t seed, float u[4])
{
    pt__sobol_seeds e;
    if (u) pt__sobol_point23(&e, pt__sobol_point_at(&e, index, seed, u), u + 2);
}
/* The seeds of the sets drawn lately, each tagged with the set seed it was made from: a set's seed
   depends on (render seed, pixel, set, split copy) and not on the sample, so a pixel's samples,
   drawn one after another by one tile job, share them and the SplitMix64 chain runs once per
   pixel and set instead of once per draw. Set s of a sampler is kept in entry (s + its
   cache_lane) modulo PT__SOBOL_CACHE_SIZE: a camera sample's path has lane 0, and a split copy
   the lane PT__SOBOL_CACHE_LANE x copy further on than its parent's, so the copies a path splits
   into (indirect_paths: every camera sample) keep their sets apart (8 bounces per lane) instead
   of evicting each other's. An entry is used only when its tag equals the set seed wanted (else
   it is remade), so the values drawn never depend on the cache. Entries start as the seeds of
   set seed 0. */
#define PT__SOBOL_CACHE_SIZE 256u
#define PT__SOBOL_CACHE_LANE 64u
typedef struct pt__sobol_cache {
    pt__sobol_seeds e[PT__SOBOL_CACHE_SIZE];
} pt__sobol_cache;
static void pt__sobol_cache_init(pt__sobol_cache *c)
{
    uint32_t i;
    pt__sobol_seeds_make(&c->e[0], 0u);
    for (i = 1; i < PT__SOBOL_CACHE_SIZE; ++i) c->e[i] = c->e[0];
}

/* The integrator's source of random numbers for one camera sample (see above). */
typedef struct pt__sampler {
    pt_rng rng;            /* INDEPENDENT: every draw. SOBOL: only user PDFs (a guide's pt_pdf_sample),
                              seeded on first use (pt__sampler_rng) */
    int sobol;
    int rng_seeded;        /* SOBOL: whether rng is seeded yet */
    uint32_t index_reversed; /* SOBOL: the sample's index within its pixel, bits reversed */
    uint32_t index_high;   /* SOBOL: the index's high 16 bits (index & 0xffff0000) */
    uint32_t index_high1;  /* SOBOL: pt__sobol1_reversed(index_high) */
    uint64_t key;          /* SOBOL: a hash of (seed, pixel) (pt__sobol_pixel_key) */
    uint64_t seed;         /* SOBOL: the render's seed, pixel and sample index, to seed rng */
    uint32_t pixel, sample;
    pt__sobol_cache *cache; /* SOBOL: set seeds, shared by the samples of one tile job */
    uint32_t cache_lane;   /* SOBOL: where its sets go in the cache (pt__sobol_cache) */
    /* SOBOL: draws made ahead (pt__sobol_draw_ahead), each tagged with its set's seed (and a
       scattered direction with its depth's parity): [0] a light point, [1] a scattered direction;
       bit i of ahead_ok: entry i is set */
    uint64_t ahead_seed[2];
    float ahead_u[2][2];
    uint32_t ahead_odd, ahead_ok;
} pt__sampler;

/* Sets: the pixel and lens positions, then PT__SLOTS per bounce (depth d's slot s is set
   PT__SET_BOUNCE(d, s)). Two-dimensional: PIXEL, LENS, LIGHT_POINT, SCATTER_DIR; SCATTER_DIR of
   an even depth d is four-dimensional: its dimensions 2 and 3 are depth d + 1's scattered
   direction (pt__draw_scatter; that depth's own SCATTER_DIR set is unused). */
#define PT__SET_PIXEL 0u
#define PT__SET_LENS 1u
enum {
    PT__SLOT_LIGHT_PICK = 0,  /* which light (pt__lights_sample's u0) */
    PT__SLOT_LIGHT_POINT,     /* the point on it (u1, u2) */
    PT__SLOT_SCATTER_DIR,     /* the material's direction (u1, u2) */
    PT__SLOT_SCATTER_EXTRA,   /* the material's third number (fuzz radius) */
    PT__SLOT_GUIDE,           /* guide or material */
    PT__SLOT_MIXTURE,         /* mixture strategy: light or scatter */
    PT__SLOT_FRESNEL,         /* glass: reflect or refract */
    PT__SLOT_RR,              /* Russian roulette */
    PT__SLOTS
};
#define PT__SET_BOUNCE(depth, slot) (2u + (uint32_t)PT__SLOTS * (uint32_t)(depth) + (uint32_t)(slot))
/* The pick among delta lights at depth d (a set of its own, apart from the bounce sets above, so
   that scenes without delta lights draw exactly what they drew before delta lights existed). */
#define PT__SET_DELTA_PICK(depth) (0x80000000u + (uint32_t)(depth))

/* SOBOL: the key of a pixel's sets (the same for all its samples). */
static uint64_t pt__sobol_pixel_key(uint64_t seed, uint32_t pixel)
{
    return pt__mix64(pt__mix64(seed ^ 0x6a09e667f3bcc909ULL) + (uint64_t)pixel);
}
/* `pixel_key` (pt__sobol_pixel_key(seed, pixel)) and `cache` (initialised) are used by SOBOL only. */
static void pt__sampler_init(pt__sampler *smp, pt_sampler kind, uint64_t seed, uint32_t pixel, uint32_t sample,
                             uint64_t pixel_key, pt__sobol_cache *cache)
{
    smp->sobol = kind == PT_SAMPLER_SOBOL;
    smp->rng_seeded = !smp->sobol;
    if (!smp->sobol) smp->rng = pt_rng_for_sample(seed, pixel, sample);
    smp->seed = seed;
    smp->pixel = pixel;
    smp->sample = sample;
    smp->index_reversed = 0u;
    smp->index_high = smp->index_high1 = 0u;
    smp->key = 0u;
    smp->cache = NULL;
    smp->cache_lane = 0u;
    smp->ahead_ok = 0u;
    if (smp->sobol) {
        smp->index_reversed = pt__reverse_bits(sample);
        smp->index_high = sample & 0xffff0000u;
        smp->index_high1 = pt__sobol1_reversed(smp->index_high);
        smp->key = pixel_key;
        smp->cache = cache;
    }
}
/* The sample's PCG stream (pt_rng_for_sample; a guide PDF draws from it in either mode). */
static pt_rng *pt__sampler_rng(pt__sampler *smp)
{
    if (smp->sobol && !smp->rng_seeded) {
        smp->rng = pt_rng_for_sample(smp->seed, smp->pixel, smp->sample);
        smp->rng_seeded = 1;
    }
    return &smp->rng;
}
static uint64_t pt__set_seed(const pt__sampler *smp, uint32_t set)
{
    return smp->key + 0x9e3779b97f4a7c15ULL * (uint64_t)(set + 1u);
}
/* SOBOL: the seeds of set `set` (whose set seed is `seed`) of this sample's pixel (from the
   cache, or made). */
static pt__sobol_seeds *pt__sobol_set_seeds(const pt__sampler *smp, uint32_t set, uint64_t seed)
{
    pt__sobol_seeds *e = &smp->cache->e[(set + smp->cache_lane) & (PT__SOBOL_CACHE_SIZE - 1u)];
    if (e->seed != seed) pt__sobol_seeds_make(e, seed);
    return e;
}
/* The SOBOL halves of the draws below (the independent halves are inlined into the integrator). */
static float pt__draw1_sobol(const pt__sampler *smp, uint32_t set)
{
    const pt__sobol_seeds *e = pt__sobol_set_seeds(smp, set, pt__set_seed(smp, set));
    uint32_t k1;
    return pt__owen_float(pt__sobol_shuffle(e, smp->index_reversed, smp->index_high, smp->index_high1, &k1), e->add[0],
                          e->mul[0]);
}
static void pt__draw2_sobol_make(const pt__sampler *smp, uint32_t set, uint64_t seed, float *u)
{
    const pt__sobol_seeds *e = pt__sobol_set_seeds(smp, set, seed);
    uint32_t k1, k = pt__sobol_shuffle(e, smp->index_reversed, smp->index_high, smp->index_high1, &k1);
    pt__sobol_point01(e, k, k1, u);
}
static void pt__draw2_sobol(const pt__sampler *smp, uint32_t set, float *a, float *b)
{
    const uint64_t seed = pt__set_seed(smp, set);
    float u[2];
    if ((smp->ahead_ok & 1u) && smp->ahead_seed[0] == seed) {
        *a = smp->ahead_u[0][0];
        *b = smp->ahead_u[0][1];
        return;
    }
    pt__draw2_sobol_make(smp, set, seed, u);
    *a = u[0];
    *b = u[1];
}
static void pt__draw_scatter_sobol_make(const pt__sampler *smp, uint32_t set, uint64_t seed, uint32_t odd, float *u)
{
    pt__sobol_seeds *e = pt__sobol_set_seeds(smp, set, seed);
    uint32_t k1, k = pt__sobol_shuffle(e, smp->index_reversed, smp->index_high, smp->index_high1, &k1);
    if (odd) pt__sobol_point23(e, k, u);
    else pt__sobol_point01(e, k, k1, u);
}
static void pt__draw_scatter_sobol(const pt__sampler *smp, int depth, float *a, float *b)
{
    const uint32_t set = PT__SET_BOUNCE(depth & ~1, PT__SLOT_SCATTER_DIR), odd = (uint32_t)depth & 1u;
    const uint64_t seed = pt__set_seed(smp, set);
    float u[2];
    if ((smp->ahead_ok & 2u) && smp->ahead_seed[1] == seed && smp->ahead_odd == odd) {
        *a = smp->ahead_u[1][0];
        *b = smp->ahead_u[1][1];
        return;
    }
    pt__draw_scatter_sobol_make(smp, set, seed, odd, u);
    *a = u[0];
    *b = u[1];
}
/* SOBOL: makes depth `depth`'s light point (if `light`) and scattered direction (if `scatter`)
   ahead of their draws, which then find them (the same function of (seed, pixel, sample, set):
   the same numbers). The batched integrator draws a whole batch's ahead in one loop, whose
   paths' independent hash chains overlap, where each draw in its place would wait on its own. */
static void pt__sobol_draw_ahead(pt__sampler *smp, int depth, int light, int scatter)
{
    smp->ahead_ok = 0u;
    if (light) {
        const uint32_t set = PT__SET_BOUNCE(depth, PT__SLOT_LIGHT_POINT);
        smp->ahead_seed[0] = pt__set_seed(smp, set);
        pt__draw2_sobol_make(smp, set, smp->ahead_seed[0], smp->ahead_u[0]);
        smp->ahead_ok = 1u;
    }
    if (scatter) {
        const uint32_t set = PT__SET_BOUNCE(depth & ~1, PT__SLOT_SCATTER_DIR);
        smp->ahead_seed[1] = pt__set_seed(smp, set);
        smp->ahead_odd = (uint32_t)depth & 1u;
        pt__draw_scatter_sobol_make(smp, set, smp->ahead_seed[1], smp->ahead_odd, smp->ahead_u[1]);
        smp->ahead_ok |= 2u;
    }
}
#ifdef PT__WIDE
/* The same with AVX2 for up to 8 draws at a time (the batched integrator's stage 1b), each one's
   set seeds (pt__sobol_seeds) gathered by pt__sobol_ahead_add: exactly the scalar draws' integer
   steps (the byte look-ups of pt__sobol_shuffle and pt__reversed_fraction_float as bit
   reversals, Sobol's dimensions 2 and 3 as the xor of the direction numbers of k's set bits)
   and the same exact conversion to float, so the same numbers. */
typedef struct pt__sobol_ahead8 {
    uint32_t ir[8], ih[8], ih1[8], sadd[8], smul[8], add0[8], mul0[8], add1[8], mul1[8], odd[8];
    float *out[8];
    int n;
} pt__sobol_ahead8;
PT__TARGET_AVX2 static __m256i pt__nested_hash8(__m256i x, __m256i add, __m256i mul_odd)
{
    x = _mm256_add_epi32(x, add);
    x = _mm256_xor_si256(x, _mm256_mullo_epi32(x, _mm256_set1_epi32((int)0xf9b439fcu)));
    x = _mm256_mullo_epi32(x, mul_odd);
    x = _mm256_xor_si256(x, _mm256_mullo_epi32(x, _mm256_set1_epi32((int)0x91d93080u)));
    return _mm256_xor_si256(x, _mm256_mullo_epi32(x, _mm256_set1_epi32((int)0x8142c8eau)));
}
/* Each 32-bit lane's bits reversed: the nibbles of each byte by a table, then the bytes. */
PT__TARGET_AVX2 static __m256i pt__reverse_bits8(__m256i x)
{
    const __m256i lut = _mm256_setr_epi8(0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15,
                                         0, 8, 4, 12, 2, 10, 6, 14, 1, 9, 5, 13, 3, 11, 7, 15);
    const __m256i bytes = _mm256_setr_epi8(3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12,
                                           3, 2, 1, 0, 7, 6, 5, 4, 11, 10, 9, 8, 15, 14, 13, 12);
    const __m256i nib = _mm256_set1_epi8(0x0f);
    __m256i lo = _mm256_shuffle_epi8(lut, _mm256_and_si256(x, nib));
    __m256i hi = _mm256_shuffle_epi8(lut, _mm256_and_si256(_mm256_srli_epi16(x, 4), nib));
    return _mm256_shuffle_epi8(_mm256_or_si256(_mm256_slli_epi16(lo, 4), hi), bytes);
}
PT__TARGET_AVX2 static __m256i pt__sobol1_reversed8(__m256i i)
{
    i = _mm256_xor_si256(i, _mm256_and_si256(_mm256_srli_epi32(i, 1), _mm256_set1_epi32(0x55555555)));
    i = _mm256_xor_si256(i, _mm256_and_si256(_mm256_srli_epi32(i, 2), _mm256_set1_epi32(0x33333333)));
    i = _mm256_xor_si256(i, _mm256_and_si256(_mm256_srli_epi32(i, 4), _mm256_set1_epi32(0x0f0f0f0f)));
    i = _mm256_xor_si256(i, _mm256_and_si256(_mm256_srli_epi32(i, 8), _mm256_set1_epi32(0x00ff00ff)));
    return _mm256_xor_si256(i, _mm256_srli_epi32(i, 16));
}
/* pt__owen_float of each lane. */
PT__TARGET_AVX2 static __m256 pt__owen_float8(__m256i x_reversed, __m256i add, __m256i mul_odd)
{
    __m256i f = _mm256_srli_epi32(pt__reverse_bits8(pt__nested_hash8(x_reversed, add, mul_odd)), 8);
    return _mm256_mul_ps(_mm256_cvtepi32_ps(f), _mm256_set1_ps(1.0f / 16777216.0f));
}
#define PT__LOAD8(a) _mm256_loadu_si256((const __m256i *)(const void *)(a))
PT__TARGET_AVX2 static void pt__sobol_ahead8_run(pt__sobol_ahead8 *a)
{
    __m256i h, r, k, k1, odd;
    float u0[8], u1[8];
    int i;
    for (i = a->n; i < 8; ++i) { /* unused lanes: copies of the first */
        a->ir[i] = a->ir[0]; a->ih[i] = a->ih[0]; a->ih1[i] = a->ih1[0]; a->sadd[i] = a->sadd[0];
        a->smul[i] = a->smul[0]; a->add0[i] = a->add0[0]; a->mul0[i] = a->mul0[0]; a->add1[i] = a->add1[0];
        a->mul1[i] = a->mul1[0]; a->odd[i] = a->odd[0];
    }
    /* step 1 (pt__sobol_shuffle): r = the hash's top 16 bits reversed */
    h = pt__nested_hash8(PT__LOAD8(a->ir), PT__LOAD8(a->sadd), PT__LOAD8(a->smul));
    r = _mm256_and_si256(pt__reverse_bits8(h), _mm256_set1_epi32(0xffff));
    k = _mm256_or_si256(PT__LOAD8(a->ih), r);
    k1 = _mm256_xor_si256(PT__LOAD8(a->ih1), pt__sobol1_reversed8(r));
    odd = _mm256_cmpgt_epi32(PT__LOAD8(a->odd), _mm256_setzero_si256());
    if (_mm256_movemask_epi8(odd)) { /* dimensions 2 and 3 (pt__sobol_point23) where odd */
        __m256i x2 = _mm256_setzero_si256(), x3 = _mm256_setzero_si256(), kk = k;
        uint32_t high = 0u;
        int j, bits;
        for (i = 0; i < 8; ++i) high |= a->ih[i];
        bits = high ? 32 : 16; /* k = ih | r, r < 2^16 */
        for (j = 0; j < bits; ++j) {
            __m256i m = _mm256_srai_epi32(_mm256_slli_epi32(kk, 31), 31);
            x2 = _mm256_xor_si256(x2, _mm256_and_si256(m, _mm256_set1_epi32((int)(uint32_t)pt__sobol23_rdir[j])));
            x3 = _mm256_xor_si256(x3, _mm256_and_si256(m, _mm256_set1_epi32((int)(uint32_t)(pt__sobol23_rdir[j] >> 32))));
            kk = _mm256_srli_epi32(kk, 1);
        }
        k1 = _mm256_blendv_epi8(k1, x3, odd);
        k = _mm256_blendv_epi8(k, x2, odd);
    }
    _mm256_storeu_ps(u0, pt__owen_float8(k, PT__LOAD8(a->add0), PT__LOAD8(a->mul0)));
    _mm256_storeu_ps(u1, pt__owen_float8(k1, PT__LOAD8(a->add1), PT__LOAD8(a->mul1)));
    for (i = 0; i < a->n; ++i) {
        a->out[i][0] = u0[i];
        a->out[i][1] = u1[i];
    }
    a->n = 0;
}
#undef PT__LOAD8
/* Adds sampler smp's draw of the set whose seeds are e (its dimensions 2 and 3 if odd) into out. */
static void pt__sobol_ahead_add(pt__sobol_ahead8 *a, const pt__sampler *smp, pt__sobol_seeds *e, uint32_t odd, float *out)
{
    const int i = a->n, d = odd ? 2 : 0;
    if (odd && !e->mul[2]) pt__sobol_seeds_make23(e);
    a->ir[i] = smp->index_reversed;
    a->ih[i] = smp->index_high;
    a->ih1[i] = smp->index_high1;
    a->sadd[i] = e->shuffle_add;
    a->smul[i] = e->shuffle_mul;
    a->add0[i] = e->add[d];
    a->mul0[i] = e->mul[d];
    a->add1[i] = e->add[d + 1];
    a->mul1[i] = e->mul[d + 1];
    a->odd[i] = odd;
    a->out[i] = out;
    if (++a->n == 8) pt__sobol_ahead8_run(a);
}
/* pt__sobol_draw_ahead's draws into a (run when 8 are in; the caller runs the rest). */
static void pt__sobol_draw_ahead8(pt__sobol_ahead8 *a, pt__sampler *smp, int depth, int light, int scatter)
{
    smp->ahead_ok = 0u;
    if (light) {
        const uint32_t set = PT__SET_BOUNCE(depth, PT__SLOT_LIGHT_POINT);
        smp->ahead_seed[0] = pt__set_seed(smp, set);
        pt__sobol_ahead_add(a, smp, pt__sobol_set_seeds(smp, set, smp->ahead_seed[0]), 0u, smp->ahead_u[0]);
        smp->ahead_ok = 1u;
    }
    if (scatter) {
        const uint32_t set = PT__SET_BOUNCE(depth & ~1, PT__SLOT_SCATTER_DIR);
        smp->ahead_seed[1] = pt__set_seed(smp, set);
        smp->ahead_odd = (uint32_t)depth & 1u;
        pt__sobol_ahead_add(a, smp, pt__sobol_set_seeds(smp, set, smp->ahead_seed[1]), smp->ahead_odd, smp->ahead_u[1]);
        smp->ahead_ok |= 2u;
    }
}
#endif
/* One number of set `set`. */
static PT__HOT float pt__draw1(pt__sampler *smp, uint32_t set)
{
    if (!smp->sobol) return pt_rng_float(&smp->rng);
    return pt__draw1_sobol(smp, set);
}
/* The same for a number the caller may not use: independent mode draws it anyway (to keep the
   stream's order); SOBOL skips the work when `used` is 0 (the value is then 0.5, never read). */
static PT__HOT float pt__draw1_if(pt__sampler *smp, uint32_t set, int used)
{
    if (smp->sobol && !used) return 0.5f;
    return pt__draw1(smp, set);
}
/* Two numbers of set `set` (independent: *a, then *b). */
static PT__HOT void pt__draw2(pt__sampler *smp, uint32_t set, float *a, float *b)
{
    if (!smp->sobol) {
        *a = pt_rng_float(&smp->rng);
        *b = pt_rng_float(&smp->rng);
        return;
    }
    pt__draw2_sobol(smp, set, a, b);
}
/* The scattered direction's two numbers at `depth` (independent: *a, then *b, as pt__draw2).
   SOBOL: the directions of depths 2i and 2i + 1 are one four-dimensional point (dimensions 0, 1
   and 2, 3 of set PT__SET_BOUNCE(2i, PT__SLOT_SCATTER_DIR)), so the two-bounce integral of a
   path's first indirect bounces is stratified jointly, not only in each direction (Burley 2020,
   sec. 5, pads with sets of four dimensions; it lowers the variance against two separately
   shuffled 2D sets: docs/internals.md, "Four-dimensional sets for two bounces"). Both depths
   use the set's one shuffled index, whichever of them drew. */
static PT__HOT void pt__draw_scatter(pt__sampler *smp, int depth, float *a, float *b)
{
    if (!smp->sobol) {
        *a = pt_rng_float(&smp->rng);
        *b = pt_rng_float(&smp->rng);
        return;
    }
    pt__draw_scatter_sobol(smp, depth, a, b);
}

/* sin and cos of x in [-pi/4, pi/4] by their Taylor polynomials to degree 9 and 10 (truncation
   error below 2e-9, under float's rounding), in float: the same operations on every CPU and in
   every build, where a libm's sinf/cosf differ, and a fraction of their cost. */
static PT__HOT void pt__sincos_quarter(float x, float *sn, float *cs)
{
    const float x2 = x * x;
    *sn = x + x * x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f + x2 * (1.0f / 362880.0f))));
    *cs = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f + x2 * (-1.0f / 3628800.0f)))));
}
/* sin and cos of 2 pi u for u in [0, 1]: u less its nearest quarter turn k/4 (exact: k/4 is a
   multiple of u's ulp and |u - k/4| <= 1/8), pt__sincos_quarter of 2 pi times that, turned by k
   quarter turns. k is counted by comparisons (a NaN gives k = 0 and NaNs out, no undefined
   conversion), so pt__sincos_turn8 does these operations lane by lane. */
static PT__HOT void pt__sincos_turn(float u, float *sn, float *cs)
{
    const float q = 4.0f * u + 0.5f;
    const int k = (q >= 1.0f) + (q >= 2.0f) + (q >= 3.0f) + (q >= 4.0f);
    float s, c;
    pt__sincos_quarter((2.0f * PT__PI) * (u - 0.25f * (float)k), &s, &c);
    switch (k & 3) {
    case 0: *sn = s; *cs = c; break;
    case 1: *sn = c; *cs = -s; break;
    case 2: *sn = -s; *cs = -c; break;
    default: *sn = -c; *cs = s; break;
    }
}
/* Double-precision acos, sin and cos for the solid-angle sampling of quad lights (pt__sphrect_init,
   pt__sphrect_point): the same operations on every CPU and in every build, where libm's differ,
   and written so that a vector version does exactly these operations per lane (no table, no
   branch that the lanes cannot take as a select). Within a few ulps of a correctly rounded libm
   (the math tests check 4). */
#define PT__PIO2_HI 1.5707963267948966     /* pi/2 rounded to double ... */
#define PT__PIO2_LO 6.123233995736766e-17  /* ... and the rest of pi/2 */
/* (asin(x) - x)/x^3 as a polynomial in t = x^2 on [0, 1/4], degree 12: Chebyshev interpolation
   (near minimax; Trefethen, "Approximation Theory and Approximation Practice", ch. 16), made with
   mpmath: chebyfit(lambda t: (asin(sqrt(t)) - sqrt(t))/t**1.5, [0, 0.25], 13); its error, 1.5e-17,
   is 0.03 ulp of asin. */
static const double pt__asin_c[13] = { 0.16666666666666669, 0.07499999999998433, 0.04464285714635543,
    0.030381944138531247, 0.02237217294214989, 0.017352392720869973, 0.013971212973552933, 0.011479177415184906,
    0.01032281435018578, 0.005457506718640358, 0.01740087944269402, -0.014851887071247204, 0.028757851367421566 };
static PT__HOT double pt__asin_poly(double t)
{
    double p = pt__asin_c[12];
    int i;
    for (i = 11; i >= 0; --i) p = pt__asin_c[i] + t * p; /* (Horner) */
    return p;
}
/* acos(c) for c in [-1, 1]: pi/2 - asin(c) where |c| <= 1/2; else with s = sqrt((1 - |c|)/2),
   2 asin(s) for c > 0 and pi - 2 asin(s) for c < 0 (the half-angle reduction of Cody & Waite,
   "Software Manual for the Elementary Functions", 1980, ch. 10), so asin's argument is at most 1/2. */
static PT__HOT double pt__acos_d(double c)
{
    const double ac = fabs(c);
    const int small = ac <= 0.5;
    const double t = small ? c * c : 0.5 * (1.0 - ac), s = small ? c : sqrt(t);
    const double a = s + s * (t * pt__asin_poly(t)), r = PT__PIO2_HI - (a - PT__PIO2_LO);
    PT_ASSERT(!(c < -1.0 || c > 1.0)); /* (NaN passes, to NaN, as libm's) */
    return small ? r : (c < 0.0 ? 2.0 * r : 2.0 * a);
}
/* sin and cos of x for x in [-pi/4, 2 pi + pi/4]: x less the nearest multiple n pi/2, by pi/2 in
   three parts (Cody & Waite, ch. 8: the first two of 33 and 31 bits, so n times them is exact and
   x - n p1 is exact), then the Taylor polynomials of sin and cos to degree 17 and 16 on
   [-pi/4, pi/4] (truncation error below 1e-19), swapped and negated by n mod 4. */
#define PT__PIO2_1 1.5707963267341256
#define PT__PIO2_2 6.077100506303966e-11
#define PT__PIO2_3 2.0222662487959506e-21
static const double pt__sin_c[8] = { -1.0 / 6.0, 1.0 / 120.0, -1.0 / 5040.0, 1.0 / 362880.0, -1.0 / 39916800.0,
    1.0 / 6227020800.0, -1.0 / 1307674368000.0, 1.0 / 355687428096000.0 };
static const double pt__cos_c[8] = { -0.5, 1.0 / 24.0, -1.0 / 720.0, 1.0 / 40320.0, -1.0 / 3628800.0, 1.0 / 479001600.0,
    -1.0 / 87178291200.0, 1.0 / 20922789888000.0 };
static PT__HOT void pt__sincos_d(double x, double *sn, double *cs)
{
    const int n = (int)(x * 0.6366197723675814 + 0.5);
    const double dn = (double)n, r = ((x - dn * PT__PIO2_1) - dn * PT__PIO2_2) - dn * PT__PIO2_3, r2 = r * r;
    double ps = pt__sin_c[7], pc = pt__cos_c[7], s, c;
    int i;
    for (i = 6; i >= 0; --i) {
        ps = pt__sin_c[i] + r2 * ps;
        pc = pt__cos_c[i] + r2 * pc;
    }
    s = r + r * (r2 * ps);
    c = 1.0 + r2 * pc;
    PT_ASSERT(x >= -0.7854 && x <= 7.0686);
    switch (n & 3) {
    case 0: *sn = s; *cs = c; break;
    case 1: *sn = c; *cs = -s; break;
    case 2: *sn = -s; *cs = -c; break;
    default: *sn = -c; *cs = s; break;
    }
}
/* Outside their ranges the public forms answer as libm does (NaN; libm's sin and cos), where the
   internal ones assert: a caller's argument must not abort the host program. */
PTDEF double pt_acos(double c) { return c < -1.0 || c > 1.0 ? acos(c) : pt__acos_d(c); }
PTDEF void pt_sincos(double x, double *sn, double *cs)
{
    if (x >= -0.7854 && x <= 7.0686) {
        pt__sincos_d(x, sn, cs);
    } else {
        *sn = sin(x);
        *cs = cos(x);
    }
}
/* (atan(a) - a)/a^3 as a cubic in t = a^2 on [0, (2 - sqrt3)^2]: Chebyshev interpolation at the
   interval's 4 Chebyshev nodes (near minimax; Trefethen, "Approximation Theory and Approximation
   Practice", ch. 16) of the series sum_k (-1)^k t^(k-1) / (2k + 1); the fit's own error is 1.1e-9
   of atan(a), the float evaluation's about 1 ulp. */
static const float pt__atan_c[4] = { -0.333333316571899f, 0.19999251524457345f, -0.14233056633154942f,
                                     0.09907260477202492f };
/* The octants' offsets (float nearest) and signs, by (x < 0) 4 + (|y| > |x|) 2 + (the pi/6
   reduction): |atan2| is the offset plus the sign times atan(a'). */
static const float pt__atan_off[8] = { 0.0f, 0.52359879f, 1.57079637f, 1.04719758f, 3.14159274f, 2.61799383f,
                                       1.57079637f, 2.09439516f };
static const float pt__atan_sgn[8] = { 1.0f, 1.0f, -1.0f, -1.0f, -1.0f, -1.0f, 1.0f, 1.0f };
static const float pt__atan_red[2][2] = { { 1.0f, 0.0f }, { 1.73205081f, 1.0f } }; /* (sqrt3, 1) reduces */
/* atan2 in float: the octant's argument a = lo/hi in (0, 1], reduced to |a'| <= tan(pi/12) by
   atan(a) = pi/6 + atan((a sqrt3 - 1) / (a + sqrt3)) (Cody & Waite, "Software Manual for the
   Elementary Functions", 1980, ch. 11), one division, the cubic above, then the octant's offset
   plus or minus that. Tables and selects, not branches, on the common path (directions come in no
   order a predictor could learn; on random arguments it takes a quarter of glibc 2.36's atan2f's
   time). Zeros, infinities, NaNs and arguments beyond 1e-30 .. 1e30 (where the reduction's
   products could leave float's normal range) go to libm, so signs of zero, inf/inf and NaN come
   out as its. */
static PT__HOT float pt__atan2f(float y, float x)
{
    const float ab[2] = { fabsf(x), fabsf(y) };
    const int swap = ab[1] > ab[0];
    const float hi = ab[swap], lo = ab[!swap];
    int big, k;
    float a, t, r;
    if (!(lo > 0.0f && hi > 1e-30f && hi < 1e30f)) return atan2f(y, x);
    big = lo > 0.26794919f * hi;
    /* (lo sqrt3 - hi) / (lo + hi sqrt3) or lo / hi, by table rather than branch: lo 1 - hi 0 is lo */
    a = (lo * pt__atan_red[big][0] - hi * pt__atan_red[big][1]) /
        (lo * pt__atan_red[big][1] + hi * pt__atan_red[big][0]);
    t = a * a;
    r = a + a * (t * (pt__atan_c[0] + t * (pt__atan_c[1] + t * (pt__atan_c[2] + t * pt__atan_c[3]))));
    k = (x < 0.0f) * 4 + swap * 2 + big;
    return copysignf(pt__atan_off[k] + pt__atan_sgn[k] * r, y); /* (one rounding; y is not 0) */
}
PTDEF float pt_atan2f(float y, float x) { return pt__atan2f(y, x); }
/* Concentric map of the square to the disk (Shirley & Chiu, "A Low Distortion Map Between
   Disk and Square", JGT 2(3), 1997). In the sectors where |sy| >= |sx| the angle is
   pi/2 - (pi/4) sx/sy, whose cosine and sine are the sine and cosine of (pi/4) sx/sy. */
static PT__HOT void pt__concentric_disk(float u1, float u2, float *x, float *y)
{
    float sx = 2.0f * u1 - 1.0f, sy = 2.0f * u2 - 1.0f, sn, cs;
    if (sx == 0.0f && sy == 0.0f) { *x = 0.0f; *y = 0.0f; return; }
    if (fabsf(sx) > fabsf(sy)) {
        pt__sincos_quarter((PT__PI / 4.0f) * (sy / sx), &sn, &cs);
        *x = sx * cs;
        *y = sx * sn;
    } else {
        pt__sincos_quarter((PT__PI / 4.0f) * (sx / sy), &sn, &cs);
        *x = sy * sn;
        *y = sy * cs;
    }
}
PTDEF void pt_sample_concentric_disk(float u1, float u2, float *x, float *y) { pt__concentric_disk(u1, u2, x, y); }
/* Malley's method: project the uniform disk up to the hemisphere; density cos(theta)/pi. */
static PT__HOT pt_vec3 pt__cosine_hemisphere(float u1, float u2)
{
    float x, y;
    pt__concentric_disk(u1, u2, &x, &y);
    return pt_v3(x, y, pt__safe_sqrt(1.0f - x * x - y * y));
}
PTDEF pt_vec3 pt_sample_cosine_hemisphere(float u1, float u2) { return pt__cosine_hemisphere(u1, u2); }
#ifdef PT__WIDE
/* pt__sincos_quarter for 8 lanes (AVX2): its operations in its order, so the same bits. */
PT__TARGET_AVX2 static inline void pt__sincos_quarter8(__m256 a, __m256 *sn, __m256 *cs)
{
    const __m256 a2 = _mm256_mul_ps(a, a);
    __m256 s, c;
    s = _mm256_add_ps(_mm256_set1_ps(1.0f / 120.0f),
                      _mm256_mul_ps(a2, _mm256_add_ps(_mm256_set1_ps(-1.0f / 5040.0f),
                                                      _mm256_mul_ps(a2, _mm256_set1_ps(1.0f / 362880.0f)))));
    *sn = _mm256_add_ps(a, _mm256_mul_ps(_mm256_mul_ps(a, a2), _mm256_add_ps(_mm256_set1_ps(-1.0f / 6.0f), _mm256_mul_ps(a2, s))));
    c = _mm256_add_ps(_mm256_set1_ps(1.0f / 40320.0f), _mm256_mul_ps(a2, _mm256_set1_ps(-1.0f / 3628800.0f)));
    c = _mm256_add_ps(_mm256_set1_ps(1.0f / 24.0f),
                      _mm256_mul_ps(a2, _mm256_add_ps(_mm256_set1_ps(-1.0f / 720.0f), _mm256_mul_ps(a2, c))));
    *cs = _mm256_add_ps(_mm256_set1_ps(1.0f), _mm256_mul_ps(a2, _mm256_add_ps(_mm256_set1_ps(-0.5f), _mm256_mul_ps(a2, c))));
}
/* pt__sincos_turn for 8 lanes: k's comparisons as masks, the quarter turns as selects and sign flips. */
PT__TARGET_AVX2 static inline void pt__sincos_turn8(__m256 u, __m256 *sn, __m256 *cs)
{
    const __m256 one = _mm256_set1_ps(1.0f), signbit = _mm256_set1_ps(-0.0f);
    const __m256 q = _mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(4.0f), u), _mm256_set1_ps(0.5f));
    const __m256 ge1 = _mm256_cmp_ps(q, one, _CMP_GE_OQ), ge2 = _mm256_cmp_ps(q, _mm256_set1_ps(2.0f), _CMP_GE_OQ);
    const __m256 ge3 = _mm256_cmp_ps(q, _mm256_set1_ps(3.0f), _CMP_GE_OQ), ge4 = _mm256_cmp_ps(q, _mm256_set1_ps(4.0f), _CMP_GE_OQ);
    const __m256 k = _mm256_add_ps(_mm256_add_ps(_mm256_and_ps(ge1, one), _mm256_and_ps(ge2, one)),
                                   _mm256_add_ps(_mm256_and_ps(ge3, one), _mm256_and_ps(ge4, one)));
    const __m256 odd = _mm256_xor_ps(_mm256_xor_ps(ge1, ge2), _mm256_xor_ps(ge3, ge4)); /* k = 1 or 3 */
    const __m256 sneg = _mm256_andnot_ps(ge4, ge2);                                      /* k = 2 or 3 */
    const __m256 cneg = _mm256_andnot_ps(ge3, ge1);                                      /* k = 1 or 2 */
    __m256 s, c;
    pt__sincos_quarter8(_mm256_mul_ps(_mm256_set1_ps(2.0f * PT__PI), _mm256_sub_ps(u, _mm256_mul_ps(_mm256_set1_ps(0.25f), k))),
                        &s, &c);
    *sn = _mm256_xor_ps(_mm256_blendv_ps(s, c, odd), _mm256_and_ps(sneg, signbit));
    *cs = _mm256_xor_ps(_mm256_blendv_ps(c, s, odd), _mm256_and_ps(cneg, signbit));
}
/* pt_onb_to_world(pt__onb(n), l) for 8 lanes (Duff et al. 2017), in the scalar code's order. */
PT__TARGET_AVX2 static inline void pt__onb_to_world8(const __m256 *n, const __m256 *l, __m256 *w)
{
    const __m256 one = _mm256_set1_ps(1.0f), signbit = _mm256_set1_ps(-0.0f);
    const __m256 sign = _mm256_or_ps(_mm256_and_ps(signbit, n[2]), one);
    const __m256 inv = _mm256_div_ps(_mm256_set1_ps(-1.0f), _mm256_add_ps(sign, n[2]));
    const __m256 c = _mm256_mul_ps(_mm256_mul_ps(n[0], n[1]), inv);
    w[0] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_add_ps(one, _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(sign, n[0]), n[0]), inv)), l[0]),
                                       _mm256_mul_ps(c, l[1])),
                         _mm256_mul_ps(n[0], l[2]));
    w[1] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(sign, c), l[0]),
                                       _mm256_mul_ps(_mm256_add_ps(sign, _mm256_mul_ps(_mm256_mul_ps(n[1], n[1]), inv)), l[1])),
                         _mm256_mul_ps(n[1], l[2]));
    w[2] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_xor_ps(signbit, sign), n[0]), l[0]),
                                       _mm256_mul_ps(_mm256_xor_ps(signbit, n[1]), l[1])),
                         _mm256_mul_ps(n[2], l[2]));
}
/* A Lambertian vertex's scattered direction and density (pt__material_sample_dir: the disk map
   with pt__sincos_quarter, Malley's lift, pt__onb's basis at the shading normal n, the cosine
   density) for 8 lanes at a time with AVX2, each lane doing the scalar code's float operations
   in the scalar code's order (no FMA), so the same bits. In: n and the draws u1, u2; out: w, pdf. */
PT__TARGET_AVX2 static void pt__lambert_dir8(const float *nx, const float *ny, const float *nz, const float *u1,
                                             const float *u2, float *wx, float *wy, float *wz, float *pdf)
{
    const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps(), signbit = _mm256_set1_ps(-0.0f);
    const __m256 sx = _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(2.0f), _mm256_loadu_ps(u1)), one);
    const __m256 sy = _mm256_sub_ps(_mm256_mul_ps(_mm256_set1_ps(2.0f), _mm256_loadu_ps(u2)), one);
    const __m256 xbig = _mm256_cmp_ps(_mm256_andnot_ps(signbit, sx), _mm256_andnot_ps(signbit, sy), _CMP_GT_OQ);
    const __m256 at0 = _mm256_and_ps(_mm256_cmp_ps(sx, zero, _CMP_EQ_OQ), _mm256_cmp_ps(sy, zero, _CMP_EQ_OQ));
    const __m256 den = _mm256_blendv_ps(sy, sx, xbig), num = _mm256_blendv_ps(sx, sy, xbig);
    __m256 sn, cs, l[3], n[3], w[3], d;
    pt__sincos_quarter8(_mm256_mul_ps(_mm256_set1_ps(PT__PI / 4.0f), _mm256_div_ps(num, den)), &sn, &cs);
    /* pt__concentric_disk (0 at the centre, where 0/0 made a NaN) and Malley's lift */
    l[0] = _mm256_andnot_ps(at0, _mm256_mul_ps(den, _mm256_blendv_ps(sn, cs, xbig)));
    l[1] = _mm256_andnot_ps(at0, _mm256_mul_ps(den, _mm256_blendv_ps(cs, sn, xbig)));
    l[2] = _mm256_sub_ps(_mm256_sub_ps(one, _mm256_mul_ps(l[0], l[0])), _mm256_mul_ps(l[1], l[1]));
    l[2] = _mm256_sqrt_ps(_mm256_and_ps(_mm256_cmp_ps(l[2], zero, _CMP_GT_OQ), l[2]));
    n[0] = _mm256_loadu_ps(nx);
    n[1] = _mm256_loadu_ps(ny);
    n[2] = _mm256_loadu_ps(nz);
    pt__onb_to_world8(n, l, w);
    /* the density max(0, n . w) / pi (max_ps(0, d) is 0 > d ? 0 : d, as pt__maxf) */
    d = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(n[0], w[0]), _mm256_mul_ps(n[1], w[1])), _mm256_mul_ps(n[2], w[2]));
    _mm256_storeu_ps(wx, w[0]);
    _mm256_storeu_ps(wy, w[1]);
    _mm256_storeu_ps(wz, w[2]);
    _mm256_storeu_ps(pdf, _mm256_mul_ps(_mm256_max_ps(zero, d), _mm256_set1_ps(PT__INV_PI)));
}
#endif
/* Archimedes: z is uniform on [-1, 1] for uniform directions; density 1/(4 pi). */
PTDEF pt_vec3 pt_sample_uniform_sphere(float u1, float u2)
{
    float z = 1.0f - 2.0f * u1, r = pt__safe_sqrt(1.0f - z * z), phi = 2.0f * PT__PI * u2;
    return pt_v3(r * cosf(phi), r * sinf(phi), z);
}

/* A point sampled on a light, seen from a shading point. */
typedef struct pt__light_sample {
    pt_vec3 dir;      /* unit, from the shading point to the light point */
    float dist;       /* distance to the light point */
    float pdf;        /* solid-angle density of dir for this light alone */
    pt_vec3 point, normal;
    pt_color radiance; /* an environment sample's (background + map); unset for other lights */
    int rounded;      /* 1: dir is only the float rounding of a direction that meets the light
                         (a sphere narrower than float's angular resolution): a segment to
                         point is valid, a ray along dir misses and has density 0 */
    const void *sph_prim; /* a planar light sampled with solid-angle sampling allowed: its primitive,
                             and in sph_S the solid angle sampled by (0: sampled by area); a
                             caller that wants them sets sph_prim to NULL first */
    double sph_S;
} pt__light_sample;

/* --- sphere light. Outside: uniform in the cone of directions that meet the sphere, with
   1 - cos(theta_max) = s^2 / (1 + cos(theta_max)), s = sin(theta_max), which stays exact for
   tiny and distant spheres where 1 - sqrt(1 - s^2) rounds to zero (docs/accuracy.md, "Robust
   numerics"; Shirley RTRL sec. 12 for the cone; pbrt-v4 sec. 6.2.4). Inside or on the
   sphere (two-sided only; a one-sided sphere emits outwards and cannot light its inside):
   uniform area sampling converted to solid angle, density dist^2 / (|cos| * area). */
/* Inside or on the surface. A point on a sphere rounds to either side of it; within 1e-5
   (relative, in squared distance) it counts as on it, where area sampling is exact and a
   cone from "just outside" would put the sampled point behind the origin. */
static int pt__sphere_inside(pt_vec3 o, pt_vec3 c, float r)
{
    pt_vec3 wc = pt_sub(c, o);
    return pt_length2(wc) <= r * r * (1.0f + 1e-5f);
}
/* Whether the float direction w from o lies in the cone of directions that meet the sphere
   (c, r): sin^2 of the angle from the cross product, in double, with c - o exact in double,
   so the test is exact for the given floats and stays accurate for tiny angles (no tolerance
   band: a band would add mass to the density of tiny, distant spheres). pt__hit_sphere decides
   tiny spheres by the same formula, so a direction in the cone is a ray that hits. */
static int pt__in_cone(pt_vec3 w, pt_vec3 o, pt_vec3 c, float r)
{
    double wx = w.x, wy = w.y, wz = w.z;
    double cx = (double)c.x - o.x, cy = (double)c.y - o.y, cz = (double)c.z - o.z;
    double xx = wy * cz - wz * cy, yy = wz * cx - wx * cz, zz = wx * cy - wy * cx;
    double ww = wx * wx + wy * wy + wz * wz;
    if (wx * cx + wy * cy + wz * cz <= 0.0) return 0;
    /* |w x wc|^2 / (|w|^2 |wc|^2) <= r^2 / |wc|^2 */
    return xx * xx + yy * yy + zz * zz <= (double)r * (double)r * ww;
}
static float pt__cone_one_minus_cos(float s2)
{
    float cosmax = pt__safe_sqrt(1.0f - s2);
    return s2 / (1.0f + cosmax);
}
/* A cone narrower than float's angular resolution (half-angle below ~1e-7: a float unit vector
   near the axis is ~2^-24 off in each component) may hold no float direction at all. Such a
   sample keeps the sampled point and density with the rounded direction (pt__light_sample's
   `rounded`): a shadow segment to the point lights like the exact sphere, which tends to the
   point light as r/d -> 0. The normal at the sampled point then comes from the angles, not from
   point - c (whose float error exceeds r): cos(alpha) = sin^2/sin_max + cos sqrt(1 -
   sin^2/sin_max^2), alpha measured at the centre from the direction towards o (pbrt-v4 sec.
   6.2.4, "Sampling a sphere"). */
static pt_vec3 pt__cone_normal(const pt_onb *b, float s2, float sin2_t, float cos_t, float sin_phi, float cos_phi)
{
    float smax = sqrtf(s2), q = sin2_t / s2;
    float cos_a = pt__minf(1.0f, sin2_t / smax + cos_t * pt__safe_sqrt(1.0f - q));
    float sin_a = pt__safe_sqrt(1.0f - cos_a * cos_a);
    return pt_normalize(pt_onb_to_world(b, pt_v3(sin_a * cos_phi, sin_a * sin_phi, -cos_a)));
}
static float pt__sphere_light_value(pt_vec3 o, pt_vec3 c, float r, int two_sided, pt_vec3 w);
static PT__HOT int pt__sphere_light_sample(pt_vec3 o, pt_vec3 c, float r, int two_sided, float u1, float u2,
                                   pt__light_sample *ls)
{
    pt_vec3 wc = pt_sub(c, o);
    float d2 = pt_length2(wc);
    if (!pt__sphere_inside(o, c, r)) {
        float d = sqrtf(d2), s2 = (r * r) / d2;
        float omc = pt__cone_one_minus_cos(s2);           /* 1 - cos(theta_max) */
        float uc = u1 * omc;
        float cos_t = 1.0f - uc, sin2_t = uc * (2.0f - uc), sin_t = pt__safe_sqrt(sin2_t);
        float sin_phi, cos_phi, t;
        pt_onb b = pt__onb(pt_scale(wc, 1.0f / d));
        pt_vec3 w0;
        if (!(omc > 0.0f)) return 0;
        pt__sincos_turn(u2, &sin_phi, &cos_phi); /* phi = 2 pi u2 */
        w0 = ls->dir = pt_normalize(pt_onb_to_world(&b, pt_v3(sin_t * cos_phi, sin_t * sin_phi, cos_t)));
        ls->rounded = 0;
        {
            /* a sample at the rim can round to just outside the cone; nudge it towards the axis
               (by a fraction of the cone's angle far below float resolution elsewhere) so that
               sample and value agree wherever float directions resolve the cone */
            int k;
            float step = 1e-4f;
            for (k = 0; k < 24 && !pt__in_cone(ls->dir, o, c, r); ++k, step *= 2.0f)
                ls->dir = pt_normalize(pt_add(ls->dir, pt_scale(pt_sub(b.n, ls->dir), step)));
            if (!pt__in_cone(ls->dir, o, c, r)) {
                ls->rounded = 1; /* below float resolution (see pt__cone_normal) */
                ls->dir = w0;
            }
        }
        ls->pdf = 1.0f / (2.0f * PT__PI * omc);
        /* distance to the near intersection: d (cos - sqrt(s^2 - sin^2)) */
        t = d * (cos_t - pt__safe_sqrt(s2 - sin2_t));
        ls->dist = t > 0.0f ? t : 0.0f;
        ls->point = pt_madd(o, ls->dir, ls->dist);
        if (ls->rounded) ls->normal = pt__cone_normal(&b, s2, sin2_t, cos_t, sin_phi, cos_phi);
        else ls->normal = pt_normalize(pt_sub(ls->point, c));
        return pt__isfinite(ls->pdf) && ls->dist > 0.0f;
    }
    if (!two_sided) return 0;
    {
        pt_vec3 n = pt_sample_uniform_sphere(u1, u2), p = pt_madd(c, n, r), v = pt_sub(p, o);
        float dist2 = pt_length2(v), dist;
        if (!(dist2 > 0.0f)) return 0;
        dist = sqrtf(dist2);
        ls->dir = pt_scale(v, 1.0f / dist);
        /* the density of a uniform area sample, dist^2 / (|cos| A), in the closed form that
           pt__sphere_light_value uses, so that sample and value agree */
        ls->pdf = pt__sphere_light_value(o, c, r, 1, ls->dir);
        if (!(ls->pdf > 0.0f)) return 0;
        ls->dist = dist;
        ls->point = p;
        ls->normal = n;
        ls->rounded = 0;
        return pt__isfinite(ls->pdf);
    }
}
/* Density of unit direction w. */
static float pt__sphere_light_value(pt_vec3 o, pt_vec3 c, float r, int two_sided, pt_vec3 w)
{
    pt_vec3 wc = pt_sub(c, o);
    float d2 = pt_length2(wc);
    if (!pt__sphere_inside(o, c, r)) {
        float s2 = (r * r) / d2;
        if (!pt__in_cone(w, o, c, r)) return 0.0f;
        return 1.0f / (2.0f * PT__PI * pt__cone_one_minus_cos(s2));
    }
    if (!two_sided) return 0.0f;
    {
        /* From inside or on the sphere (unit w, b = w.(c - o)): the far root of
           |o + t w - c|^2 = r^2 is t = b + sqrt(D), D = r^2 - |c - o|^2 + b^2, and the cosine
           at the light point is (p - c).w / r = sqrt(D) / r. Both in double and in closed form:
           from a point on the surface D = b^2 exactly, where the float discriminant of a
           ray-sphere test cancels to zero at grazing angles and the density would explode. */
        double b = (double)w.x * wc.x + (double)w.y * wc.y + (double)w.z * wc.z;
        double dd = (double)wc.x * wc.x + (double)wc.y * wc.y + (double)wc.z * wc.z;
        double D = (double)r * r - dd + b * b, sD, t;
        if (!(D > 0.0)) return 0.0f;
        sD = sqrt(D);
        t = b + sD;
        if (!(t > 0.0)) return 0.0f;
        return (float)((t * t) / (4.0 * 3.14159265358979323846 * (double)r * sD));
    }
}

/* --- planar lights (parallelogram, triangle): area sampling converted to solid angle,
   p(w) = dist^2 / (|cos theta_l| A) (pbrt-v4 sec. 4.2.3, change of variables). A one-sided
   light seen from behind its plane has no density at all. */
static int pt__planar_faces(pt_vec3 o, pt_vec3 q, pt_vec3 n, int two_sided)
{
    float side = pt_dot(n, pt_sub(o, q));
    return two_sided ? side != 0.0f : side > 0.0f;
}
/* dist^2 / (|cos theta_l| A) for a light point at distance t along unit w. */
static float pt__planar_density(pt_vec3 n, float area, float t, pt_vec3 w)
{
    float cosl = fabsf(pt_dot(n, w));
    return cosl > 0.0f ? (t * t) / (cosl * area) : 0.0f;
}
/* The geometry section's primitive set-up and intersection, used here so that the public
   light PDFs and the scene's light table share one sampler and one density. */
static void pt__set_quad(pt__prim *p, pt_vec3 q, pt_vec3 u, pt_vec3 v);
static void pt__set_triangle(pt__prim *p, pt_vec3 a, pt_vec3 b, pt_vec3 c);
static float pt__prim_area(const pt__prim *p);
static void pt__rayctx_init2(pt__rayctx *rc, pt_ray r, int need_triangles);
static int pt__hit_prim(const pt__rayctx *rc, const pt__prim *p, float tmax, float *t, float *bary);

/* A uniform point on a quad, or on a triangle with b0 = 1 - sqrt(u1), b1 = u2 sqrt(u1)
   (Osada, Funkhouser, Chazelle & Dobkin, "Shape Distributions", ACM TOG 21(4), 2002, eq. 1). */
static pt_vec3 pt__planar_point(const pt__prim *p, float u1, float u2)
{
    float su, b0, b1;
    if (p->type == PT__PRIM_QUAD) return pt_madd(pt_madd(p->p0, p->p1, u1), p->p2, u2);
    su = sqrtf(u1);
    b0 = 1.0f - su;
    b1 = u2 * su;
    return pt_add(pt_add(pt_scale(p->p0, b0), pt_scale(p->p1, b1)), pt_scale(p->p2, 1.0f - b0 - b1));
}
/* Solid-angle sampling of a rectangular quad: the area-preserving map of its spherical rectangle
   (Urena, Fajardo & King, "An Area-Preserving Parametrization for Spherical Rectangles", EGSR
   2013), in double: density 1/S over the directions that meet the quad, S its solid angle. Where S
   is outside [PT__SPHERICAL_MIN, PT__SPHERICAL_MAX] (pbrt-v4's limits: below, S = (sum of the four
   angles) - 2 pi has lost its digits and area sampling is already close to 1/S; near a whole
   hemisphere the map degenerates), and for quads that are not rectangles, the light is sampled by
   area. Solid-angle sampling costs four arccosines per look-up and pays only where area sampling's
   density varies much over the light, that is where the light is large next to its distance
   (whatever its orientation: a point beside a ceiling light, near its plane, sees distances from
   ~0 to its width): so it is used only where (half the quad's diagonal / the distance to its
   centre)^2 is at least PT__SPHERICAL_FROM (bench/README.md, "Solid-angle sampling of quads"). The
   choice depends only on the light and the shading point, so sample and value agree. */
#define PT__SPHERICAL_MIN 3e-4
#define PT__SPHERICAL_MAX 6.22
#ifndef PT__SPHERICAL_FROM
#define PT__SPHERICAL_FROM 0.3
#endif
typedef struct pt__sphrect {
    double o[3], ex[3], ey[3], ez[3];
    double x0, y0, z0, x1, y1, b0, b1, k, S;
} pt__sphrect;
static double pt__d3dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static void pt__d3cross(double *out, const double *a, const double *b);
static double pt__acos_clamped(double c) { return pt__acos_d(c < -1.0 ? -1.0 : (c > 1.0 ? 1.0 : c)); }
/* 1 when quad p seen from o is a rectangle whose solid angle is in range (r then set up). The
   normals of the planes through o and each edge, (0, z0, -y0), (-z0, 0, x1), (0, -z0, y1) and
   (z0, 0, -x0) over their lengths l0 .. l3, are never formed: the cosines of the inner angles
   between neighbours are the closed forms below, so the set-up costs four square roots and no
   unit vectors but the frame's. */
/* Is quad p large next to its distance from o? (float: only a threshold) */
static PT__HOT int pt__sphrect_wanted(const pt__prim *p, pt_vec3 o)
{
    pt_vec3 cc = pt_sub(pt_madd(pt_madd(p->p0, p->p1, 0.5f), p->p2, 0.5f), o);
    return 0.25f * (pt_length2(p->p1) + pt_length2(p->p2)) >= (float)PT__SPHERICAL_FROM * pt_length2(cc);
}
static int pt__sphrect_setup(pt__sphrect *r, const pt__prim *p, pt_vec3 o)
{
    double u[3], v[3], d[3], lu, lv, iu, iv, zz, l0, l1, l2, l3, g0, g1, g2, g3, c[3], ic;
    int i;
    u[0] = p->p1.x; u[1] = p->p1.y; u[2] = p->p1.z;
    v[0] = p->p2.x; v[1] = p->p2.y; v[2] = p->p2.z;
    lu = sqrt(pt__d3dot(u, u));
    lv = sqrt(pt__d3dot(v, v));
    if (!(lu > 0.0 && lv > 0.0) || fabs(pt__d3dot(u, v)) > 1e-5 * lu * lv) return 0; /* not a rectangle */
    iu = 1.0 / lu;
    iv = 1.0 / lv;
    for (i = 0; i < 3; ++i) {
        r->ex[i] = u[i] * iu;
        r->ey[i] = v[i] * iv;
    }
    pt__d3cross(c, r->ex, r->ey);
    ic = 1.0 / sqrt(pt__d3dot(c, c));
    for (i = 0; i < 3; ++i) r->ez[i] = c[i] * ic;
    r->o[0] = o.x; r->o[1] = o.y; r->o[2] = o.z;
    d[0] = (double)p->p0.x - o.x; d[1] = (double)p->p0.y - o.y; d[2] = (double)p->p0.z - o.z;
    r->x0 = pt__d3dot(d, r->ex);
    r->y0 = pt__d3dot(d, r->ey);
    r->z0 = pt__d3dot(d, r->ez);
    if (r->z0 > 0.0) { /* the rectangle's plane below o in its own frame */
        for (i = 0; i < 3; ++i) r->ez[i] = -r->ez[i];
        r->z0 = -r->z0;
    }
    if (!(r->z0 < 0.0)) return 0;
    r->x1 = r->x0 + lu;
    r->y1 = r->y0 + lv;
    zz = r->z0 * r->z0;
    l0 = sqrt(zz + r->y0 * r->y0);
    l1 = sqrt(zz + r->x1 * r->x1);
    l2 = sqrt(zz + r->y1 * r->y1);
    l3 = sqrt(zz + r->x0 * r->x0);
    /* the inner angles: acos of minus the dot products of neighbouring normals */
    g0 = pt__acos_clamped(r->y0 * r->x1 / (l0 * l1));
    g1 = pt__acos_clamped(-(r->x1 * r->y1) / (l1 * l2));
    g2 = pt__acos_clamped(r->x0 * r->y1 / (l2 * l3));
    g3 = pt__acos_clamped(-(r->x0 * r->y0) / (l3 * l0));
    r->S = g0 + g1 + g2 + g3 - 2.0 * 3.14159265358979323846;
    if (!(r->S >= PT__SPHERICAL_MIN && r->S <= PT__SPHERICAL_MAX)) return 0;
    r->b0 = -r->y0 / l0;
    r->b1 = r->y1 / l2;
    r->k = 2.0 * 3.14159265358979323846 - g2 - g3;
    return 1;
}
static int pt__sphrect_init(pt__sphrect *r, const pt__prim *p, pt_vec3 o)
{
    return pt__sphrect_wanted(p, o) && pt__sphrect_setup(r, p, o);
}
/* The point of the rectangle that (u1, u2) maps to (Urena et al. 2013, sec. 3-4). */
static pt_vec3 pt__sphrect_point(const pt__sphrect *r, double u1, double u2)
{
    double au = u1 * r->S + r->k, sa, ca, fu, cu, xu, dd, h0, h1, hv, yv;
    pt__sincos_d(au, &sa, &ca); /* au is in [0, 2 pi]: k = 2 pi - g2 - g3 >= 0, k + S = g0 + g1 <= 2 pi */
    fu = sa != 0.0 ? (ca * r->b0 - r->b1) / sa : 0.0;
    if (!(fu == fu)) fu = 0.0;
    cu = (fu > 0.0 ? 1.0 : -1.0) / sqrt(fu * fu + r->b0 * r->b0);
    cu = cu < -1.0 ? -1.0 : (cu > 1.0 ? 1.0 : cu);
    xu = 1.0 - cu * cu > 0.0 ? -(cu * r->z0) / sqrt(1.0 - cu * cu) : (cu > 0.0 ? r->x1 : r->x0);
    xu = xu < r->x0 ? r->x0 : (xu > r->x1 ? r->x1 : xu);
    dd = sqrt(xu * xu + r->z0 * r->z0);
    h0 = r->y0 / sqrt(dd * dd + r->y0 * r->y0);
    h1 = r->y1 / sqrt(dd * dd + r->y1 * r->y1);
    hv = h0 + u2 * (h1 - h0);
    yv = hv * hv < 1.0 - 1e-12 ? hv * dd / sqrt(1.0 - hv * hv) : r->y1;
    yv = yv < r->y0 ? r->y0 : (yv > r->y1 ? r->y1 : yv);
    return pt_v3((float)(r->o[0] + xu * r->ex[0] + yv * r->ey[0] + r->z0 * r->ez[0]),
                 (float)(r->o[1] + xu * r->ex[1] + yv * r->ey[1] + r->z0 * r->ez[1]),
                 (float)(r->o[2] + xu * r->ex[2] + yv * r->ey[2] + r->z0 * r->ez[2]));
}

/* The spherical rectangle's set-up and point for 4 shading points at once (4 lanes of double with
   AVX2; pt__batch_lights): lane by lane the operations of pt__sphrect_setup and pt__sphrect_point
   with pt__acos_d and pt__sincos_d, in the same order and without FMA, so the bits are the
   scalar code's. Where the scalar code branches, both sides are computed and selected; a
   division or square root the scalar code would skip gets a harmless operand instead, so no lane
   raises an exception (FE_INVALID, FE_DIVBYZERO) that the scalar code would not. */
#ifdef PT__WIDE
PT__TARGET_AVX2 static inline __m256d pt__v4sel(__m256d m, __m256d a, __m256d b) { return _mm256_blendv_pd(b, a, m); }
PT__TARGET_AVX2 static inline __m256d pt__v4neg(__m256d a) { return _mm256_xor_pd(a, _mm256_set1_pd(-0.0)); }
PT__TARGET_AVX2 static inline __m256d pt__v4dot(const __m256d *a, const __m256d *b)
{
    return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(a[0], b[0]), _mm256_mul_pd(a[1], b[1])), _mm256_mul_pd(a[2], b[2]));
}
/* lo if x < lo, hi if x > hi, else x (NaN stays): the scalar code's ternaries as max(lo, min(hi, x)) */
PT__TARGET_AVX2 static inline __m256d pt__v4clamp(__m256d x, __m256d lo, __m256d hi)
{
    return _mm256_max_pd(lo, _mm256_min_pd(hi, x));
}
PT__TARGET_AVX2 static __m256d pt__acos4(__m256d c)
{
    const __m256d one = _mm256_set1_pd(1.0), ac = _mm256_andnot_pd(_mm256_set1_pd(-0.0), c);
    const __m256d small = _mm256_cmp_pd(ac, _mm256_set1_pd(0.5), _CMP_LE_OQ);
    const __m256d t = pt__v4sel(small, _mm256_mul_pd(c, c), _mm256_mul_pd(_mm256_set1_pd(0.5), _mm256_sub_pd(one, ac)));
    const __m256d s = pt__v4sel(small, c, _mm256_sqrt_pd(t));
    __m256d p = _mm256_set1_pd(pt__asin_c[12]), a, r;
    int i;
    for (i = 11; i >= 0; --i) p = _mm256_add_pd(_mm256_set1_pd(pt__asin_c[i]), _mm256_mul_pd(t, p));
    a = _mm256_add_pd(s, _mm256_mul_pd(s, _mm256_mul_pd(t, p)));
    r = _mm256_sub_pd(_mm256_set1_pd(PT__PIO2_HI), _mm256_sub_pd(a, _mm256_set1_pd(PT__PIO2_LO)));
    return pt__v4sel(small, r, pt__v4sel(_mm256_cmp_pd(c, _mm256_setzero_pd(), _CMP_LT_OQ), _mm256_mul_pd(_mm256_set1_pd(2.0), r),
                                         _mm256_mul_pd(_mm256_set1_pd(2.0), a)));
}
PT__TARGET_AVX2 static void pt__sincos4(__m256d x, __m256d *sn, __m256d *cs)
{
    const __m128i n = _mm256_cvttpd_epi32(_mm256_add_pd(_mm256_mul_pd(x, _mm256_set1_pd(0.6366197723675814)), _mm256_set1_pd(0.5)));
    const __m256d dn = _mm256_cvtepi32_pd(n);
    const __m256d r = _mm256_sub_pd(_mm256_sub_pd(_mm256_sub_pd(x, _mm256_mul_pd(dn, _mm256_set1_pd(PT__PIO2_1))),
                                                  _mm256_mul_pd(dn, _mm256_set1_pd(PT__PIO2_2))),
                                    _mm256_mul_pd(dn, _mm256_set1_pd(PT__PIO2_3)));
    const __m256d r2 = _mm256_mul_pd(r, r), sign = _mm256_set1_pd(-0.0);
    const __m256i n64 = _mm256_cvtepi32_epi64(n), b1 = _mm256_set1_epi64x(1), b2 = _mm256_set1_epi64x(2);
    const __m256d odd = _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(n64, b1), b1));
    const __m256d sneg = _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(n64, b2), b2));
    const __m256d cneg = _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(_mm256_add_epi64(n64, b1), b2), b2));
    __m256d ps = _mm256_set1_pd(pt__sin_c[7]), pc = _mm256_set1_pd(pt__cos_c[7]), s, c;
    int i;
    for (i = 6; i >= 0; --i) {
        ps = _mm256_add_pd(_mm256_set1_pd(pt__sin_c[i]), _mm256_mul_pd(r2, ps));
        pc = _mm256_add_pd(_mm256_set1_pd(pt__cos_c[i]), _mm256_mul_pd(r2, pc));
    }
    s = _mm256_add_pd(r, _mm256_mul_pd(r, _mm256_mul_pd(r2, ps)));
    c = _mm256_add_pd(_mm256_set1_pd(1.0), _mm256_mul_pd(r2, pc));
    *sn = _mm256_xor_pd(pt__v4sel(odd, c, s), _mm256_and_pd(sneg, sign));
    *cs = _mm256_xor_pd(pt__v4sel(odd, s, c), _mm256_and_pd(cneg, sign));
}
/* pt__sphrect in 4 lanes */
typedef struct pt__sphrect4 {
    __m256d o[3], ex[3], ey[3], ez[3];
    __m256d x0, y0, z0, x1, y1, b0, b1, k, S;
} pt__sphrect4;
/* a lane's value where m is set, else lane j's */
PT__TARGET_AVX2 static inline __m256d pt__v4fill(__m256d m, __m256d a, int j)
{
    double t[4];
    _mm256_storeu_pd(t, a);
    return pt__v4sel(m, a, _mm256_set1_pd(t[j]));
}
/* pt__sphrect_setup's lanes (the mask of those it returns 1 for): a lane that is not a rectangle
   goes on with the unit square's frame, one with o in its plane with z0 = -1. */
PT__TARGET_AVX2 static __m256d pt__sphrect_setup4(pt__sphrect4 *r, const pt__prim *const *p, const pt_vec3 *o)
{
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), twopi = _mm256_set1_pd(2.0 * 3.14159265358979323846);
    __m256d u[3], v[3], d[3], c[3], lu, lv, ok, flip, zz, l0, l1, l2, l3, g0, g1, g2, g3, iu, iv, ic;
    int i;
    for (i = 0; i < 3; ++i) {
        double a[4], b[4], q[4], w[4];
        int j;
        for (j = 0; j < 4; ++j) {
            a[j] = i == 0 ? p[j]->p1.x : i == 1 ? p[j]->p1.y : p[j]->p1.z;
            b[j] = i == 0 ? p[j]->p2.x : i == 1 ? p[j]->p2.y : p[j]->p2.z;
            q[j] = i == 0 ? p[j]->p0.x : i == 1 ? p[j]->p0.y : p[j]->p0.z;
            w[j] = i == 0 ? o[j].x : i == 1 ? o[j].y : o[j].z;
        }
        u[i] = _mm256_loadu_pd(a);
        v[i] = _mm256_loadu_pd(b);
        r->o[i] = _mm256_loadu_pd(w);
        d[i] = _mm256_sub_pd(_mm256_loadu_pd(q), r->o[i]);
    }
    lu = _mm256_sqrt_pd(pt__v4dot(u, u));
    lv = _mm256_sqrt_pd(pt__v4dot(v, v));
    ok = _mm256_and_pd(_mm256_and_pd(_mm256_cmp_pd(lu, zero, _CMP_GT_OQ), _mm256_cmp_pd(lv, zero, _CMP_GT_OQ)),
                       _mm256_cmp_pd(_mm256_andnot_pd(_mm256_set1_pd(-0.0), pt__v4dot(u, v)),
                                     _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(1e-5), lu), lv), _CMP_NGT_UQ));
    for (i = 0; i < 3; ++i) {
        u[i] = pt__v4sel(ok, u[i], i == 0 ? one : zero);
        v[i] = pt__v4sel(ok, v[i], i == 1 ? one : zero);
    }
    lu = pt__v4sel(ok, lu, one);
    lv = pt__v4sel(ok, lv, one);
    iu = _mm256_div_pd(one, lu);
    iv = _mm256_div_pd(one, lv);
    for (i = 0; i < 3; ++i) {
        r->ex[i] = _mm256_mul_pd(u[i], iu);
        r->ey[i] = _mm256_mul_pd(v[i], iv);
    }
    c[0] = _mm256_sub_pd(_mm256_mul_pd(r->ex[1], r->ey[2]), _mm256_mul_pd(r->ex[2], r->ey[1]));
    c[1] = _mm256_sub_pd(_mm256_mul_pd(r->ex[2], r->ey[0]), _mm256_mul_pd(r->ex[0], r->ey[2]));
    c[2] = _mm256_sub_pd(_mm256_mul_pd(r->ex[0], r->ey[1]), _mm256_mul_pd(r->ex[1], r->ey[0]));
    ic = _mm256_div_pd(one, _mm256_sqrt_pd(pt__v4dot(c, c)));
    for (i = 0; i < 3; ++i) r->ez[i] = _mm256_mul_pd(c[i], ic);
    r->x0 = pt__v4dot(d, r->ex);
    r->y0 = pt__v4dot(d, r->ey);
    r->z0 = pt__v4dot(d, r->ez);
    flip = _mm256_cmp_pd(r->z0, zero, _CMP_GT_OQ);
    for (i = 0; i < 3; ++i) r->ez[i] = pt__v4sel(flip, pt__v4neg(r->ez[i]), r->ez[i]);
    r->z0 = pt__v4sel(flip, pt__v4neg(r->z0), r->z0);
    flip = _mm256_cmp_pd(r->z0, zero, _CMP_LT_OQ);
    ok = _mm256_and_pd(ok, flip);
    r->z0 = pt__v4sel(flip, r->z0, _mm256_set1_pd(-1.0));
    r->x1 = _mm256_add_pd(r->x0, lu);
    r->y1 = _mm256_add_pd(r->y0, lv);
    zz = _mm256_mul_pd(r->z0, r->z0);
    l0 = _mm256_sqrt_pd(_mm256_add_pd(zz, _mm256_mul_pd(r->y0, r->y0)));
    l1 = _mm256_sqrt_pd(_mm256_add_pd(zz, _mm256_mul_pd(r->x1, r->x1)));
    l2 = _mm256_sqrt_pd(_mm256_add_pd(zz, _mm256_mul_pd(r->y1, r->y1)));
    l3 = _mm256_sqrt_pd(_mm256_add_pd(zz, _mm256_mul_pd(r->x0, r->x0)));
    {
        const __m256d m1 = _mm256_set1_pd(-1.0);
        g0 = pt__acos4(pt__v4clamp(_mm256_div_pd(_mm256_mul_pd(r->y0, r->x1), _mm256_mul_pd(l0, l1)), m1, one));
        g1 = pt__acos4(pt__v4clamp(_mm256_div_pd(pt__v4neg(_mm256_mul_pd(r->x1, r->y1)), _mm256_mul_pd(l1, l2)), m1, one));
        g2 = pt__acos4(pt__v4clamp(_mm256_div_pd(_mm256_mul_pd(r->x0, r->y1), _mm256_mul_pd(l2, l3)), m1, one));
        g3 = pt__acos4(pt__v4clamp(_mm256_div_pd(pt__v4neg(_mm256_mul_pd(r->x0, r->y0)), _mm256_mul_pd(l3, l0)), m1, one));
    }
    r->S = _mm256_sub_pd(_mm256_add_pd(_mm256_add_pd(_mm256_add_pd(g0, g1), g2), g3), twopi);
    ok = _mm256_and_pd(ok, _mm256_and_pd(_mm256_cmp_pd(r->S, _mm256_set1_pd(PT__SPHERICAL_MIN), _CMP_GE_OQ),
                                         _mm256_cmp_pd(r->S, _mm256_set1_pd(PT__SPHERICAL_MAX), _CMP_LE_OQ)));
    r->b0 = _mm256_div_pd(pt__v4neg(r->y0), l0);
    r->b1 = _mm256_div_pd(r->y1, l2);
    r->k = _mm256_sub_pd(_mm256_sub_pd(twopi, g2), g3);
    return ok;
}
/* pt__sphrect_point's lanes, into q (rounded to float as there) */
PT__TARGET_AVX2 static void pt__sphrect_point4(const pt__sphrect4 *r, __m256d u1, __m256d u2, float q[3][4])
{
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0);
    const __m256d au = _mm256_add_pd(_mm256_mul_pd(u1, r->S), r->k);
    __m256d sa, ca, nz, fu, cu, w, pos, xu, dd, h0, h1, hv, lt;
    int i;
    pt__sincos4(au, &sa, &ca);
    nz = _mm256_cmp_pd(sa, zero, _CMP_NEQ_UQ);
    fu = pt__v4sel(nz, _mm256_div_pd(_mm256_sub_pd(_mm256_mul_pd(ca, r->b0), r->b1), pt__v4sel(nz, sa, one)), zero);
    fu = pt__v4sel(_mm256_cmp_pd(fu, fu, _CMP_ORD_Q), fu, zero);
    cu = _mm256_div_pd(pt__v4sel(_mm256_cmp_pd(fu, zero, _CMP_GT_OQ), one, _mm256_set1_pd(-1.0)),
                       _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(fu, fu), _mm256_mul_pd(r->b0, r->b0))));
    cu = pt__v4clamp(cu, _mm256_set1_pd(-1.0), one);
    w = _mm256_sub_pd(one, _mm256_mul_pd(cu, cu));
    pos = _mm256_cmp_pd(w, zero, _CMP_GT_OQ);
    xu = pt__v4sel(pos, _mm256_div_pd(pt__v4neg(_mm256_mul_pd(cu, r->z0)), _mm256_sqrt_pd(pt__v4sel(pos, w, one))),
                   pt__v4sel(_mm256_cmp_pd(cu, zero, _CMP_GT_OQ), r->x1, r->x0));
    xu = pt__v4clamp(xu, r->x0, r->x1);
    dd = _mm256_sqrt_pd(_mm256_add_pd(_mm256_mul_pd(xu, xu), _mm256_mul_pd(r->z0, r->z0)));
    w = _mm256_mul_pd(dd, dd);
    h0 = _mm256_div_pd(r->y0, _mm256_sqrt_pd(_mm256_add_pd(w, _mm256_mul_pd(r->y0, r->y0))));
    h1 = _mm256_div_pd(r->y1, _mm256_sqrt_pd(_mm256_add_pd(w, _mm256_mul_pd(r->y1, r->y1))));
    hv = _mm256_add_pd(h0, _mm256_mul_pd(u2, _mm256_sub_pd(h1, h0)));
    w = _mm256_mul_pd(hv, hv);
    lt = _mm256_cmp_pd(w, _mm256_set1_pd(1.0 - 1e-12), _CMP_LT_OQ);
    w = pt__v4sel(lt, _mm256_div_pd(_mm256_mul_pd(hv, dd), _mm256_sqrt_pd(pt__v4sel(lt, _mm256_sub_pd(one, w), one))), r->y1);
    w = pt__v4clamp(w, r->y0, r->y1);
    for (i = 0; i < 3; ++i)
        _mm_storeu_ps(q[i], _mm256_cvtpd_ps(_mm256_add_pd(_mm256_add_pd(_mm256_add_pd(r->o[i], _mm256_mul_pd(xu, r->ex[i])),
                                                                        _mm256_mul_pd(w, r->ey[i])),
                                                          _mm256_mul_pd(r->z0, r->ez[i]))));
}
/* Quads p[j] sampled by solid angle from o[j] at (u1[j], u2[j]), j < 4, whose pt__sphrect_wanted
   holds: ok[j] = pt__sphrect_setup's answer; where 1, the point and the solid angle. */
PT__TARGET_AVX2 static void pt__sphrect_sample4(const pt__prim *const *p, const pt_vec3 *o, const float *u1,
                                                const float *u2, int *ok, pt_vec3 *q, double *S)
{
    pt__sphrect4 r;
    float qq[3][4];
    double a[4], b[4];
    const __m256d m = pt__sphrect_setup4(&r, p, o);
    const int bits = _mm256_movemask_pd(m);
    int j, i;
    for (j = 0; j < 4; ++j) ok[j] = (bits >> j) & 1;
    if (!bits) return;
    j = bits & 1 ? 0 : bits & 2 ? 1 : bits & 4 ? 2 : 3; /* the lanes that failed take lane j's values */
    for (i = 0; i < 3; ++i) {
        r.o[i] = pt__v4fill(m, r.o[i], j);
        r.ex[i] = pt__v4fill(m, r.ex[i], j);
        r.ey[i] = pt__v4fill(m, r.ey[i], j);
        r.ez[i] = pt__v4fill(m, r.ez[i], j);
    }
    r.x0 = pt__v4fill(m, r.x0, j); r.y0 = pt__v4fill(m, r.y0, j); r.z0 = pt__v4fill(m, r.z0, j);
    r.x1 = pt__v4fill(m, r.x1, j); r.y1 = pt__v4fill(m, r.y1, j);
    r.b0 = pt__v4fill(m, r.b0, j); r.b1 = pt__v4fill(m, r.b1, j);
    r.k = pt__v4fill(m, r.k, j); r.S = pt__v4fill(m, r.S, j);
    for (i = 0; i < 4; ++i) {
        a[i] = u1[i];
        b[i] = u2[i];
    }
    pt__sphrect_point4(&r, _mm256_loadu_pd(a), _mm256_loadu_pd(b), qq);
    _mm256_storeu_pd(S, r.S);
    for (j = 0; j < 4; ++j) q[j] = pt_v3(qq[0][j], qq[1][j], qq[2][j]);
}
#endif

/* Solid-angle sampling of a triangle light (Arvo, "Stratified Sampling of Spherical Triangles",
   SIGGRAPH 1995), in double, under the rule of rectangles above: where (half its longest edge /
   the distance to its centroid)^2 is at least PT__SPHERICAL_FROM and its solid angle S is in
   [PT__SPHERICAL_MIN, PT__SPHERICAL_MAX]; density 1/S. */
typedef struct pt__sphtri {
    double o[3], A[3], B[3], C[3], alpha, cos_c, S;
} pt__sphtri;
static int pt__d3unit_or0(double *a, const double *v)
{
    double l = sqrt(pt__d3dot(v, v));
    if (!(l > 0.0) || !(l < HUGE_VAL)) return 0;
    a[0] = v[0] / l;
    a[1] = v[1] / l;
    a[2] = v[2] / l;
    return 1;
}
static void pt__d3cross(double *out, const double *a, const double *b)
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}
static int pt__sphtri_init(pt__sphtri *r, const pt__prim *p, pt_vec3 o)
{
    double v[3], nab[3], nbc[3], nca[3], beta, gamma;
    const pt_vec3 *P[3];
    int i;
    {   /* is it large next to its distance? (float: only a threshold) */
        pt_vec3 c = pt_sub(pt_scale(pt_add(pt_add(p->p0, p->p1), p->p2), 1.0f / 3.0f), o);
        float e = pt__maxf(pt_length2(pt_sub(p->p1, p->p0)),
                           pt__maxf(pt_length2(pt_sub(p->p2, p->p1)), pt_length2(pt_sub(p->p0, p->p2))));
        if (!(0.25f * e >= (float)PT__SPHERICAL_FROM * pt_length2(c))) return 0;
    }
    P[0] = &p->p0; P[1] = &p->p1; P[2] = &p->p2;
    r->o[0] = o.x; r->o[1] = o.y; r->o[2] = o.z;
    for (i = 0; i < 3; ++i) {
        double *d = i == 0 ? r->A : i == 1 ? r->B : r->C;
        v[0] = (double)P[i]->x - o.x; v[1] = (double)P[i]->y - o.y; v[2] = (double)P[i]->z - o.z;
        if (!pt__d3unit_or0(d, v)) return 0;
    }
    /* the angles at the vertices, between the planes through o and each edge */
    pt__d3cross(v, r->A, r->B);
    if (!pt__d3unit_or0(nab, v)) return 0;
    pt__d3cross(v, r->B, r->C);
    if (!pt__d3unit_or0(nbc, v)) return 0;
    pt__d3cross(v, r->C, r->A);
    if (!pt__d3unit_or0(nca, v)) return 0;
    r->alpha = pt__acos_clamped(-pt__d3dot(nab, nca));
    beta = pt__acos_clamped(-pt__d3dot(nbc, nab));
    gamma = pt__acos_clamped(-pt__d3dot(nca, nbc));
    r->S = r->alpha + beta + gamma - 3.14159265358979323846;
    r->cos_c = pt__d3dot(r->A, r->B);
    return r->S >= PT__SPHERICAL_MIN && r->S <= PT__SPHERICAL_MAX;
}
/* The point of triangle p that (u1, u2) maps to: a direction by Arvo's two steps (the sub-triangle
   of area u1 S fixes the point C' on the arc AC; then z uniform in cos along the arc BC'), then its
   hit with the triangle's plane. */
static pt_vec3 pt__sphtri_point(const pt__sphtri *r, const pt__prim *p, double u1, double u2)
{
    double ap = u1 * r->S, s = sin(ap - r->alpha), t = cos(ap - r->alpha), ca = cos(r->alpha), sa = sin(r->alpha);
    double u = t - ca, v = s + sa * r->cos_c, den = (v * s + u * t) * sa, q, w[3], ch[3], dir[3], z, k, n[3], hit;
    int i;
    q = den != 0.0 ? ((v * t - u * s) * ca - v) / den : 1.0;
    q = q < -1.0 ? -1.0 : (q > 1.0 ? 1.0 : q);
    k = pt__d3dot(r->C, r->A);
    for (i = 0; i < 3; ++i) w[i] = r->C[i] - k * r->A[i];
    if (!pt__d3unit_or0(w, w)) { w[0] = w[1] = w[2] = 0.0; }
    for (i = 0; i < 3; ++i) ch[i] = q * r->A[i] + sqrt(1.0 - q * q) * w[i];
    z = 1.0 - u2 * (1.0 - pt__d3dot(ch, r->B));
    z = z < -1.0 ? -1.0 : (z > 1.0 ? 1.0 : z);
    k = pt__d3dot(ch, r->B);
    for (i = 0; i < 3; ++i) w[i] = ch[i] - k * r->B[i];
    if (!pt__d3unit_or0(w, w)) { w[0] = w[1] = w[2] = 0.0; }
    for (i = 0; i < 3; ++i) dir[i] = z * r->B[i] + sqrt(1.0 - z * z) * w[i];
    n[0] = p->n.x; n[1] = p->n.y; n[2] = p->n.z;
    w[0] = (double)p->p0.x - r->o[0]; w[1] = (double)p->p0.y - r->o[1]; w[2] = (double)p->p0.z - r->o[2];
    k = pt__d3dot(n, dir);
    hit = k != 0.0 ? pt__d3dot(n, w) / k : 0.0;
    return pt_v3((float)(r->o[0] + hit * dir[0]), (float)(r->o[1] + hit * dir[1]), (float)(r->o[2] + hit * dir[2]));
}

/* The solid-angle density of a direction that meets quad or triangle p at distance t from o. */
static float pt__planar_density_from(const pt__prim *p, float area, pt_vec3 o, float t, pt_vec3 w, int sph)
{
    if (sph) {
        pt__sphrect r;
        pt__sphtri tr;
        if (p->type == PT__PRIM_QUAD && pt__sphrect_init(&r, p, o)) return (float)(1.0 / r.S);
        if (p->type == PT__PRIM_TRIANGLE && pt__sphtri_init(&tr, p, o)) return (float)(1.0 / tr.S);
    }
    return pt__planar_density(p->n, area, t, w);
}

static PT__HOT int pt__planar_light_at(const pt__prim *p, float area, pt_vec3 o, pt_vec3 q, double S, pt__light_sample *ls);
/* Samples quad or triangle primitive p (of area `area`) from o. */
static int pt__planar_light_sample(const pt__prim *p, float area, int two_sided, pt_vec3 o, float u1, float u2,
                                   pt__light_sample *ls, int sph)
{
    pt_vec3 q;
    double S = 0.0;
    pt__sphrect r;
    pt__sphtri tr;
    if (!pt__planar_faces(o, p->p0, p->n, two_sided)) return 0;
    if (sph && p->type == PT__PRIM_QUAD) {
        ls->sph_prim = p;
        ls->sph_S = 0.0;
    }
    if (sph && p->type == PT__PRIM_QUAD && pt__sphrect_init(&r, p, o)) {
        q = pt__sphrect_point(&r, u1, u2);
        S = ls->sph_S = r.S;
    } else if (sph && p->type == PT__PRIM_TRIANGLE && pt__sphtri_init(&tr, p, o)) {
        q = pt__sphtri_point(&tr, p, u1, u2);
        S = tr.S;
    } else {
        q = pt__planar_point(p, u1, u2);
    }
    return pt__planar_light_at(p, area, o, q, S, ls);
}
/* The rest of a sample of quad or triangle p once its point q is chosen (by solid angle S, or by
   area where S is 0). */
static PT__HOT int pt__planar_light_at(const pt__prim *p, float area, pt_vec3 o, pt_vec3 q, double S, pt__light_sample *ls)
{
    pt_vec3 v;
    float dist2, dist;
    v = pt_sub(q, o);
    dist2 = pt_length2(v);
    if (!(dist2 > 0.0f)) return 0;
    dist = sqrtf(dist2);
    ls->dir = pt_scale(v, 1.0f / dist);
    ls->pdf = S > 0.0 ? (float)(1.0 / S) : pt__planar_density(p->n, area, dist, ls->dir);
    ls->dist = dist;
    ls->point = q;
    ls->normal = p->n;
    ls->rounded = 0;
    return ls->pdf > 0.0f && pt__isfinite(ls->pdf);
}
/* The density of unit direction w towards quad or triangle primitive p from o. */
static float pt__planar_light_value(const pt__prim *p, float area, int two_sided, pt_vec3 o, pt_vec3 w, int sph)
{
    pt__rayctx rc;
    pt_ray r;
    float t, bary[3];
    if (!pt__planar_faces(o, p->p0, p->n, two_sided)) return 0.0f;
    r.origin = o;
    r.dir = w;
    pt__rayctx_init2(&rc, r, p->type == PT__PRIM_TRIANGLE);
    if (!pt__hit_prim(&rc, p, PT__INF, &t, bary)) return 0.0f;
    return pt__planar_density_from(p, area, o, t, w, sph);
}
/* A temporary primitive for the public quad and triangle PDFs (0 when it has no area). */
static int pt__planar_make(pt__prim *p, int type, pt_vec3 a, pt_vec3 b, pt_vec3 c, float *area)
{
    memset(p, 0, sizeof *p);
    p->type = type;
    if (type == PT__PRIM_QUAD) {
        if (!(pt_length2(pt_cross(b, c)) > 0.0f)) return 0;
        pt__set_quad(p, a, b, c);
    } else {
        if (!(pt_length2(pt_cross(pt_sub(b, a), pt_sub(c, a))) > 0.0f)) return 0;
        pt__set_triangle(p, a, b, c);
    }
    *area = pt__prim_area(p);
    return *area > 0.0f;
}
/* The primitive of a PT_PDF_QUAD_LIGHT or PT_PDF_TRIANGLE_LIGHT pdf. */
static int pt__pdf_planar(const pt_pdf *pdf, pt__prim *p, float *area, int *two_sided)
{
    if (pdf->type == PT_PDF_QUAD_LIGHT) {
        *two_sided = pdf->as.quad.two_sided;
        return pt__planar_make(p, PT__PRIM_QUAD, pdf->as.quad.q, pdf->as.quad.u, pdf->as.quad.v, area);
    }
    *two_sided = pdf->as.triangle.two_sided;
    return pt__planar_make(p, PT__PRIM_TRIANGLE, pdf->as.triangle.a, pdf->as.triangle.b, pdf->as.triangle.c, area);
}

/* --- lights of a scene (used by the integrator and by pt_pdf_scene_lights) --- */
static PT__HOT int pt__light_prim_sample(const pt_scene *s, const pt__prim *p, pt_vec3 o, float u1, float u2,
                                 pt__light_sample *ls, int sph)
{
    int two = s->mats[p->material].two_sided;
    if (p->type == PT__PRIM_SPHERE) return pt__sphere_light_sample(o, p->p0, p->p1.x, two, u1, u2, ls);
    return pt__planar_light_sample(p, s->lights[p->light].area, two, o, u1, u2, ls, sph);
}
static float pt__light_prim_value(const pt_scene *s, const pt__prim *p, pt_vec3 o, pt_vec3 w, int sph)
{
    int two = s->mats[p->material].two_sided;
    if (p->type == PT__PRIM_SPHERE) return pt__sphere_light_value(o, p->p0, p->p1.x, two, w);
    return pt__planar_light_value(p, s->lights[p->light].area, two, o, w, sph);
}
/* Density of w for one light that a ray from o along w reaches at distance t (no ray cast). */
static float pt__light_prim_value_at(const pt_scene *s, const pt__prim *p, pt_vec3 o, pt_vec3 w, float t, int sph)
{
    int two = s->mats[p->material].two_sided;
    if (p->type == PT__PRIM_SPHERE) return pt__sphere_light_value(o, p->p0, p->p1.x, two, w);
    if (!pt__planar_faces(o, p->p0, p->n, two)) return 0.0f;
    return pt__planar_density_from(p, s->lights[p->light].area, o, t, w, sph);
}
static uint32_t pt__pick_light(const pt_scene *s, float u)
{
    uint32_t lo = 0, hi = s->light_count - 1u;
    while (lo < hi) { /* first light whose cdf exceeds u */
        uint32_t mid = (lo + hi) / 2u;
        if (s->lights[mid].cdf > u) hi = mid;
        else lo = mid + 1u;
    }
    return lo;
}

/* --- light tree: a light is picked by descending a tree over the lights (eight children per
   node), choosing each child in proportion to a conservative estimate of what its lights can send
   to the shading point (power, distance and orientation: Conty Estevez & Kulla, "Importance Sampling of Many Lights
   with Adaptive Tree Splitting", 2018, as in pbrt-v4's light BVH). The orientation bounds are
   taken over the node's box rather than its bounding sphere, which keeps them tight for rows and
   planes of lights, and include the receiver's normal where the caller knows it (the same normal
   must be given to the sample and to the PMF). The probability of a light is the product of the
   choices on its path (the scene's ltrail), so it can be evaluated for MIS. Scenes with fewer
   than PT__LIGHT_TREE_MIN lights pick by power (bench/README.md, "Light tree"). */
#ifndef PT__LIGHT_TREE_MIN
#define PT__LIGHT_TREE_MIN 16u
#endif
#define PT__LIGHTS_SPHERICAL 1u /* mode bits of the functions below: solid-angle sampling of planar */
#define PT__LIGHTS_TREE 2u      /* lights; the light tree (where the scene has one) */
/* What each of node n's children can send to p, up to a common factor, into imp[8]; 0 only
   where nothing can light p. nr: the receiver's normal, which nothing below its plane reaches
   (has_nr 0: no receiver bound, for a point alone or a material that transmits). Cosines are
   bounded over each child's box: the projection of a direction between p and the box on a
   normal is at most the largest projection of their offset over their least distance. The AVX2
   version (8 children), the SSE version (4 children from lane h) and the scalar one do the same
   float operations in the same order, so they agree to the bit (no division by zero in any lane:
   fptrap). One body for both vector widths: V the vector type, the rest its intrinsics. */
#define PT__LNODE_IMPORTANCE(NAME, TARGET, V, SET1, LOADU, ADD, SUB, MUL, DIV, SQRT, MAX, MIN, AND, OR,         \
                             ANDNOT, GT, LT, LE)                                                                          \
    TARGET static V NAME(const pt__lnodew *n, int h, pt_vec3 p, pt_vec3 nr, int has_nr)                                \
    {                                                                                                                  \
        const V zero = SET1(0.0f), one = SET1(1.0f), none = SET1(-1.0f);                                               \
        const V px = SET1(p.x), py = SET1(p.y), pz = SET1(p.z);                                                        \
        const V lx = LOADU(n->lo[0] + h), ly = LOADU(n->lo[1] + h), lz = LOADU(n->lo[2] + h);                          \
        const V hx = LOADU(n->hi[0] + h), hy = LOADU(n->hi[1] + h), hz = LOADU(n->hi[2] + h);                          \
        const V cos_o = LOADU(n->cos_o + h);                                                                           \
        V dx = SUB(px, MAX(lx, MIN(px, hx)));                                                                          \
        V dy = SUB(py, MAX(ly, MIN(py, hy)));                                                                          \
        V dz = SUB(pz, MAX(lz, MIN(pz, hz)));                                                                          \
        V dmin2 = ADD(ADD(MUL(dx, dx), MUL(dy, dy)), MUL(dz, dz));                                                     \
        V apart = GT(dmin2, zero);                                                                                     \
        V inv = AND(apart, DIV(one, SQRT(OR(AND(apart, dmin2), ANDNOT(apart, one)))));                                 \
        V num, side, tilted, cone, cos_p, cos_r = one, dead, rd2;                                                      \
        /* 1 / the distance to the centre, clamped to the child's size (a point among its lights is   \
           not infinitely near) */                                                                                     \
        dx = SUB(px, LOADU(n->centre[0] + h));                                                                         \
        dy = SUB(py, LOADU(n->centre[1] + h));                                                                         \
        dz = SUB(pz, LOADU(n->centre[2] + h));                                                                         \
        rd2 = ADD(ADD(MUL(dx, dx), MUL(dy, dy)), MUL(dz, dz));                                                         \
        rd2 = DIV(one, MAX(MAX(rd2, LOADU(n->r2 + h)), SET1(FLT_MIN)));                                                \
        /* the emitters: cos theta' = cos max(0, theta_w - theta_o), theta_w the least angle between  \
           the cone's axis and a direction from the box to p; with cos theta_w = num / dmin, the      \
           sine is sqrt(dmin^2 - num^2) / dmin */                                                                      \
        num = SUB(ADD(ADD(MUL(LOADU(n->axis[0] + h), px), MUL(LOADU(n->axis[1] + h), py)), MUL(LOADU(n->axis[2] + h), pz)), \
                  LOADU(n->pmin + h));                                                                                 \
        num = MAX(num, zero);                                                                                          \
        side = SQRT(MAX(SUB(dmin2, MUL(num, num)), zero));                                                             \
        tilted = MUL(ADD(MUL(num, cos_o), MUL(side, LOADU(n->sin_o + h))), inv);                                       \
        cone = AND(AND(GT(cos_o, none), apart), LT(MUL(num, inv), cos_o));                                             \
        cos_p = OR(AND(cone, tilted), ANDNOT(cone, one));                                                              \
        dead = AND(GT(cos_o, none), LE(cos_p, LOADU(n->cos_e + h)));                                                   \
        if (has_nr) { /* the receiver: nothing on or below its plane */                                                \
            V r = SUB(ADD(ADD(MUL(SET1(nr.x), nr.x > 0.0f ? hx : lx), MUL(SET1(nr.y), nr.y > 0.0f ? hy : ly)),         \
                          MUL(SET1(nr.z), nr.z > 0.0f ? hz : lz)),                                                     \
                      SET1(pt_dot(nr, p)));                                                                            \
            dead = OR(dead, LE(r, zero));                                                                              \
            cos_r = OR(AND(apart, MIN(one, MUL(r, inv))), ANDNOT(apart, one));                                         \
        }                                                                                                              \
        return ANDNOT(dead, MUL(MUL(MUL(LOADU(n->power + h), cos_p), cos_r), rd2));                                    \
    }
#ifdef PT__SSE
PT__LNODE_IMPORTANCE(pt__lnode_importance_sse, PT__HOT, __m128, _mm_set1_ps, _mm_loadu_ps, _mm_add_ps,
                     _mm_sub_ps, _mm_mul_ps, _mm_div_ps, _mm_sqrt_ps, _mm_max_ps, _mm_min_ps, _mm_and_ps, _mm_or_ps,
                     _mm_andnot_ps, _mm_cmpgt_ps, _mm_cmplt_ps, _mm_cmple_ps)
#endif
#ifdef PT__WIDE
/* the signalling predicates of SSE's cmpgt, cmplt and cmple (the same flags on a NaN) */
#define PT__LGT8(a, b) _mm256_cmp_ps(a, b, _CMP_GT_OS)
#define PT__LLT8(a, b) _mm256_cmp_ps(a, b, _CMP_LT_OS)
#define PT__LLE8(a, b) _mm256_cmp_ps(a, b, _CMP_LE_OS)
PT__LNODE_IMPORTANCE(pt__lnode_importance_avx2, PT__TARGET_AVX2 inline, __m256, _mm256_set1_ps, _mm256_loadu_ps,
                     _mm256_add_ps, _mm256_sub_ps, _mm256_mul_ps, _mm256_div_ps, _mm256_sqrt_ps,
                     _mm256_max_ps, _mm256_min_ps, _mm256_and_ps, _mm256_or_ps, _mm256_andnot_ps, PT__LGT8, PT__LLT8,
                     PT__LLE8)
#endif
#ifndef PT__SSE
static void pt__lnode_importance_scalar(const pt__lnodew *n, pt_vec3 p, pt_vec3 nr, int has_nr, float *imp)
{
    int k;
    for (k = 0; k < PT__LTREE_W; ++k) {
        pt_vec3 d;
        float dx = p.x - pt__maxf(n->lo[0][k], pt__minf(p.x, n->hi[0][k]));
        float dy = p.y - pt__maxf(n->lo[1][k], pt__minf(p.y, n->hi[1][k]));
        float dz = p.z - pt__maxf(n->lo[2][k], pt__minf(p.z, n->hi[2][k]));
        float dmin2 = dx * dx + dy * dy + dz * dz, inv = dmin2 > 0.0f ? 1.0f / sqrtf(dmin2) : 0.0f;
        float cos_p = 1.0f, cos_r = 1.0f, rd2;
        d = pt_sub(p, pt_v3(n->centre[0][k], n->centre[1][k], n->centre[2][k]));
        rd2 = 1.0f / pt__maxf(pt__maxf(pt_length2(d), n->r2[k]), FLT_MIN);
        imp[k] = 0.0f;
        if (n->cos_o[k] > -1.0f) {
            float num = pt__maxf(n->axis[0][k] * p.x + n->axis[1][k] * p.y + n->axis[2][k] * p.z - n->pmin[k], 0.0f);
            if (dmin2 > 0.0f && num * inv < n->cos_o[k])
                cos_p = (num * n->cos_o[k] + pt__safe_sqrt(dmin2 - num * num) * n->sin_o[k]) * inv;
            if (cos_p <= n->cos_e[k]) continue;
        }
        if (has_nr) {
            float r = nr.x * (nr.x > 0.0f ? n->hi[0][k] : n->lo[0][k]) + nr.y * (nr.y > 0.0f ? n->hi[1][k] : n->lo[1][k]) +
                      nr.z * (nr.z > 0.0f ? n->hi[2][k] : n->lo[2][k]) - pt_dot(nr, p);
            if (r <= 0.0f) continue;
            cos_r = dmin2 > 0.0f ? pt__minf(1.0f, r * inv) : 1.0f;
        }
        imp[k] = n->power[k] * cos_p * cos_r * rd2;
    }
}
#endif
/* The running sums c of the children's importances, in the order of a three-step parallel scan
   (each sum adds the one 1, then 2, then 4 lanes down, or 0 below lane 0), which the AVX2 level
   does in three vector additions; every level computes them so. */
static void pt__lnodew_scan(const float *imp, float *c)
{
    float a[8];
    int k, step, j;
    for (k = 0; k < PT__LTREE_W; ++k) c[k] = imp[k];
    for (j = 0; j < PT__LTREE_W; j += 8) {
        float *cj = c + j;
        for (step = 1; step < 8; step *= 2) {
            for (k = 0; k < 8; ++k) a[k] = cj[k] + (k >= step ? cj[k - step] : 0.0f);
            for (k = 0; k < 8; ++k) cj[k] = a[k];
        }
        if (j) for (k = 0; k < 8; ++k) cj[k] = cj[k] + cj[-1];
    }
}
/* How many running sums are at most t (the child a descent with threshold t takes). */
static int pt__lnodew_count(const float *c, float t)
{
    int k = 0, j;
    for (j = 0; j < PT__LTREE_W; ++j) k += c[j] <= t;
    return k;
}
#ifdef PT__WIDE
/* The running sums of 8 importances in three vector additions (pt__lnodew_scan's order). */
PT__TARGET_AVX2 static inline __m256 pt__scan8_avx2(__m256 x)
{
    const __m256 zero = _mm256_setzero_ps();
    __m256 y = _mm256_blend_ps(_mm256_permutevar8x32_ps(x, _mm256_setr_epi32(0, 0, 1, 2, 3, 4, 5, 6)), zero, 0x01);
    x = _mm256_add_ps(x, y);
    y = _mm256_blend_ps(_mm256_permutevar8x32_ps(x, _mm256_setr_epi32(0, 0, 0, 1, 2, 3, 4, 5)), zero, 0x03);
    x = _mm256_add_ps(x, y);
    return _mm256_add_ps(x, _mm256_permute2f128_ps(x, x, 0x08)); /* the low half added into the high half */
}
/* pt__lnodew_level with AVX2, 8 children a pass: the importances, their scan and the count at
   u x total. */
PT__TARGET_AVX2 static inline int pt__lnodew_level_avx2(const pt__lnodew *n, pt_vec3 p, pt_vec3 nr, int has_nr, float u,
                                                        float *imp, float *c, int *k)
{
    __m256 x[PT__LTREE_W / 8], carry = _mm256_setzero_ps(), t;
    float total;
    int j, m = 0;
    for (j = 0; j < PT__LTREE_W / 8; ++j) {
        x[j] = pt__lnode_importance_avx2(n, 8 * j, p, nr, has_nr);
        _mm256_storeu_ps(imp + 8 * j, x[j]);
        x[j] = pt__scan8_avx2(x[j]);
    }
    for (j = 0; j < PT__LTREE_W / 8; ++j) {
        if (j) x[j] = _mm256_add_ps(x[j], carry);
        carry = _mm256_permutevar8x32_ps(x[j], _mm256_set1_epi32(7));
        _mm256_storeu_ps(c + 8 * j, x[j]);
    }
    total = _mm_cvtss_f32(_mm256_castps256_ps128(carry));
    if (!(total > 0.0f && pt__isfinite(total))) return 0;
    t = _mm256_set1_ps(u * total);
    for (j = 0; j < PT__LTREE_W / 8; ++j) m += __builtin_popcount((unsigned)_mm256_movemask_ps(_mm256_cmp_ps(x[j], t, _CMP_LE_OS)));
    *k = m;
    return 1;
}
#endif
static int pt__has_normal(pt_vec3 nr) { return nr.x != 0.0f || nr.y != 0.0f || nr.z != 0.0f; }
/* One step of pt__tree_pick's descent after node n's level (importances imp, running sums c, k
   the number of sums at most u x total): the first child whose running sum exceeds u x total (a
   child that cannot light p adds nothing, so it is passed over); where rounding puts u x total
   at or past the total, the last child that can light p. Multiplies the choice's probability
   into *prob, rescales *u for the next level and returns the child (n->child). Every descent
   (one pick, or several interleaved) steps with this, so they agree to the bit. */
static PT__HOT uint32_t pt__tree_step(const pt__lnodew *n, const float *imp, const float *c, int k, float *u, float *prob)
{
    const float total = c[PT__LTREE_W - 1], t = *u * total;
    float below;
    if (PT__UNLIKELY(k > PT__LTREE_W - 1)) for (k = PT__LTREE_W - 1; !(imp[k] > 0.0f); --k) {}
    below = k ? c[k - 1] : 0.0f;
    *prob *= imp[k] / total;
    *u = pt__minf((t - below) / imp[k], 0.99999994f);
    return n->child[k];
}
/* The descent of pt__tree_pick from node n, one body for every level function LEVEL. */
#define PT__TREE_DESCENT(LEVEL)                                                                                    \
    for (;;) {                                                                                                     \
        int k;                                                                                                     \
        uint32_t child;                                                                                            \
        if (!LEVEL(n, p, nr, has_nr, u, imp, c, &k)) return 0;                                                     \
        child = pt__tree_step(n, imp, c, k, &u, &prob);                                                            \
        if (child & PT__LCHILD_LIGHT) {                                                                            \
            *light = child & ~PT__LCHILD_LIGHT;                                                                    \
            *pmf = prob;                                                                                           \
            return prob > 0.0f;                                                                                    \
        }                                                                                                          \
        n = &s->ltree[child];                                                                                      \
    }
#ifdef PT__WIDE
/* pt__lnodew_level_avx2 for callers outside AVX2 code. */
PT__TARGET_AVX2 PT__NOINLINE static int pt__lnodew_level_avx2_call(const pt__lnodew *n, pt_vec3 p, pt_vec3 nr, int has_nr,
                                                                   float u, float *imp, float *c, int *k)
{
    return pt__lnodew_level_avx2(n, p, nr, has_nr, u, imp, c, k);
}
/* pt__tree_pick's descent compiled for AVX2 (the scalar steps are the same float operations). */
PT__TARGET_AVX2 PT__NOINLINE static int pt__tree_pick_avx2(const pt_scene *s, pt_vec3 p, pt_vec3 nr, int has_nr, float u,
                                                           uint32_t *light, float *pmf)
{
    const pt__lnodew *n = &s->ltree[0];
    float prob = 1.0f, imp[PT__LTREE_W], c[PT__LTREE_W];
    PT__TREE_DESCENT(pt__lnodew_level_avx2)
}
#endif
/* A pick of pt__tree_picks_avx2: in, the point, the receiver normal (0: none) and the number u
   of pt__tree_pick; out, what it gives (ok its return, light and pmf set where ok). */
typedef struct pt__tree_query {
    pt_vec3 p, nr;
    float u, pmf;
    uint32_t light;
    int ok;
} pt__tree_query;
#ifdef PT__WIDE
#ifndef PT__TREE_SLOTS
#define PT__TREE_SLOTS 4 /* the picks descending side by side */
#endif
/* The state of pt__tree_picks_avx2's slots: each slot's query (at; -1: idle), node, number u,
   probability so far, receiver-normal flag, and its level's importances, sums, count and whether
   any child lights the point (lit); next: the next query to take, live: the slots busy. */
typedef struct pt__tree_slots {
    const pt__lnodew *node[PT__TREE_SLOTS];
    float u[PT__TREE_SLOTS], prob[PT__TREE_SLOTS], imp[PT__TREE_SLOTS][PT__LTREE_W], c[PT__TREE_SLOTS][PT__LTREE_W];
    int has_nr[PT__TREE_SLOTS], at[PT__TREE_SLOTS], k[PT__TREE_SLOTS], lit[PT__TREE_SLOTS];
    int next, live;
} pt__tree_slots;
/* Slot g takes the next of the n queries q at the root, or goes idle. */
static PT__HOT void pt__tree_slot_take(const pt_scene *s, pt__tree_slots *z, const pt__tree_query *q, int n, int g)
{
    z->node[g] = &s->ltree[0];
    if (z->next >= n) {
        if (z->at[g] >= 0) --z->live;
        z->at[g] = -1;
        return;
    }
    if (z->at[g] < 0) ++z->live;
    z->at[g] = z->next++;
    z->has_nr[g] = pt__has_normal(q[z->at[g]].nr);
    z->u[g] = q[z->at[g]].u;
    z->prob[g] = 1.0f;
}
static void pt__tree_slots_start(const pt_scene *s, pt__tree_slots *z, const pt__tree_query *q, int n)
{
    int g;
    z->next = z->live = 0;
    for (g = 0; g < PT__TREE_SLOTS; ++g) {
        z->at[g] = -1;
        z->u[g] = 0.0f;
        z->has_nr[g] = z->k[g] = z->lit[g] = 0;
        pt__tree_slot_take(s, z, q, n, g);
    }
}
/* Every busy slot's step after its level (pt__tree_step): down to the child, or its query's
   result and the next query. */
static PT__HOT void pt__tree_slots_step(const pt_scene *s, pt__tree_slots *z, pt__tree_query *q, int n)
{
    int g;
    for (g = 0; g < PT__TREE_SLOTS; ++g) {
        pt__tree_query *x;
        uint32_t child;
        if (z->at[g] < 0) continue;
        x = &q[z->at[g]];
        x->ok = 0;
        if (z->lit[g]) {
            child = pt__tree_step(z->node[g], z->imp[g], z->c[g], z->k[g], &z->u[g], &z->prob[g]);
            if (!(child & PT__LCHILD_LIGHT)) {
                z->node[g] = &s->ltree[child];
                continue;
            }
            x->light = child & ~PT__LCHILD_LIGHT;
            x->pmf = z->prob[g];
            x->ok = z->prob[g] > 0.0f;
        }
        pt__tree_slot_take(s, z, q, n, g); /* the pick ended: the slot takes the next */
    }
}
/* pt__tree_pick (AVX2) for n points at once. A descent is a chain of dependent steps (a node's
   load, its children's importances, their sums, the child), so one pick leaves the core mostly
   waiting; here PT__TREE_SLOTS picks descend together, each one level a round, so their chains
   overlap, and a slot whose pick ends takes the next query. Each pick does pt__tree_pick's float
   operations (pt__lnodew_level_avx2, pt__tree_step), so the results are the same to the bit. */
PT__TARGET_AVX2 PT__NOINLINE static void pt__tree_picks_avx2(const pt_scene *s, pt__tree_query *q, int n)
{
    pt__tree_slots z;
    int g;
    pt__tree_slots_start(s, &z, q, n);
    while (z.live) {
        for (g = 0; g < PT__TREE_SLOTS; ++g)
            if (z.at[g] >= 0) {
                const pt__tree_query *x = &q[z.at[g]];
                z.lit[g] = pt__lnodew_level_avx2(z.node[g], x->p, x->nr, z.has_nr[g], z.u[g], z.imp[g], z.c[g], &z.k[g]);
            }
        pt__tree_slots_step(s, &z, q, n);
    }
}
/* Two 8-float rows as one 16-float vector (a's in lanes 0-7, b's in 8-15); and two numbers
   broadcast to the halves. (The zero-masked insert under a full mask: g++ warns about the plain
   one's undefined pass-through.) */
PT__TARGET_AVX512 static inline __m512 pt__join8(__m256 a, __m256 b)
{
    return _mm512_castpd_ps(_mm512_maskz_insertf64x4((__mmask8)0xff, _mm512_castpd256_pd512(_mm256_castps_pd(a)),
                                                     _mm256_castps_pd(b), 1));
}
#define PT__LOAD2(F) pt__join8(_mm256_loadu_ps(na->F), _mm256_loadu_ps(nb->F))
#define PT__SET2(x, y) pt__join8(_mm256_set1_ps(x), _mm256_set1_ps(y))
#define PT__SEL16(m, yes, no) _mm512_mask_blend_ps(m, no, yes)
/* pt__lnode_importance_avx2 of node na from point pa (normal ra; ha: has one) in lanes 0-7 and of
   nb from pb in lanes 8-15, in one AVX-512 pass: the same float operations in the same order
   per lane; a lane mask selects where the AVX2 code ands with a lane mask. The receiver's bound
   is computed for both halves and applied where its half has a normal. */
PT__TARGET_AVX512 static inline __m512 pt__lnode_importance2_avx512(const pt__lnodew *na, const pt__lnodew *nb, pt_vec3 pa,
                                                                  pt_vec3 pb, pt_vec3 ra, pt_vec3 rb, int ha, int hb)
{
    const __mmask16 all = 0xffff, hmask = (__mmask16)((ha ? 0x00ffu : 0u) | (hb ? 0xff00u : 0u));
    const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f), none = _mm512_set1_ps(-1.0f);
    const __m512 px = PT__SET2(pa.x, pb.x), py = PT__SET2(pa.y, pb.y), pz = PT__SET2(pa.z, pb.z);
    const __m512 lx = PT__LOAD2(lo[0]), ly = PT__LOAD2(lo[1]), lz = PT__LOAD2(lo[2]);
    const __m512 hx = PT__LOAD2(hi[0]), hy = PT__LOAD2(hi[1]), hz = PT__LOAD2(hi[2]);
    const __m512 cos_o = PT__LOAD2(cos_o);
    __m512 dx = _mm512_sub_ps(px, _mm512_maskz_max_ps(all, lx, _mm512_maskz_min_ps(all, px, hx)));
    __m512 dy = _mm512_sub_ps(py, _mm512_maskz_max_ps(all, ly, _mm512_maskz_min_ps(all, py, hy)));
    __m512 dz = _mm512_sub_ps(pz, _mm512_maskz_max_ps(all, lz, _mm512_maskz_min_ps(all, pz, hz)));
    __m512 dmin2 = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz));
    __mmask16 apart = _mm512_cmp_ps_mask(dmin2, zero, _CMP_GT_OS), cone, dead, lit;
    __m512 inv = _mm512_maskz_mov_ps(apart, _mm512_div_ps(one, _mm512_maskz_sqrt_ps(all, PT__SEL16(apart, dmin2, one))));
    __m512 num, side, tilted, cos_p, cos_r = one, rd2, r;
    dx = _mm512_sub_ps(px, PT__LOAD2(centre[0]));
    dy = _mm512_sub_ps(py, PT__LOAD2(centre[1]));
    dz = _mm512_sub_ps(pz, PT__LOAD2(centre[2]));
    rd2 = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dx), _mm512_mul_ps(dy, dy)), _mm512_mul_ps(dz, dz));
    rd2 = _mm512_div_ps(one, _mm512_maskz_max_ps(all, _mm512_maskz_max_ps(all, rd2, PT__LOAD2(r2)), _mm512_set1_ps(FLT_MIN)));
    num = _mm512_sub_ps(_mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(PT__LOAD2(axis[0]), px), _mm512_mul_ps(PT__LOAD2(axis[1]), py)),
                                      _mm512_mul_ps(PT__LOAD2(axis[2]), pz)),
                        PT__LOAD2(pmin));
    num = _mm512_maskz_max_ps(all, num, zero);
    side = _mm512_maskz_sqrt_ps(all, _mm512_maskz_max_ps(all, _mm512_sub_ps(dmin2, _mm512_mul_ps(num, num)), zero));
    tilted = _mm512_mul_ps(_mm512_add_ps(_mm512_mul_ps(num, cos_o), _mm512_mul_ps(side, PT__LOAD2(sin_o))), inv);
    lit = _mm512_cmp_ps_mask(cos_o, none, _CMP_GT_OS);
    cone = lit & apart & _mm512_cmp_ps_mask(_mm512_mul_ps(num, inv), cos_o, _CMP_LT_OS);
    cos_p = PT__SEL16(cone, tilted, one);
    dead = lit & _mm512_cmp_ps_mask(cos_p, PT__LOAD2(cos_e), _CMP_LE_OS);
    if (hmask) { /* the receiver: nothing on or below its plane (masked to the halves with a normal) */
        const __mmask16 sx = (__mmask16)((ra.x > 0.0f ? 0x00ffu : 0u) | (rb.x > 0.0f ? 0xff00u : 0u));
        const __mmask16 sy = (__mmask16)((ra.y > 0.0f ? 0x00ffu : 0u) | (rb.y > 0.0f ? 0xff00u : 0u));
        const __mmask16 sz = (__mmask16)((ra.z > 0.0f ? 0x00ffu : 0u) | (rb.z > 0.0f ? 0xff00u : 0u));
        r = _mm512_maskz_add_ps(hmask, _mm512_maskz_mul_ps(hmask, PT__SET2(ra.x, rb.x), PT__SEL16(sx, hx, lx)),
                                _mm512_maskz_mul_ps(hmask, PT__SET2(ra.y, rb.y), PT__SEL16(sy, hy, ly)));
        r = _mm512_maskz_add_ps(hmask, r, _mm512_maskz_mul_ps(hmask, PT__SET2(ra.z, rb.z), PT__SEL16(sz, hz, lz)));
        r = _mm512_maskz_sub_ps(hmask, r, PT__SET2(pt_dot(ra, pa), pt_dot(rb, pb)));
        dead |= _mm512_mask_cmp_ps_mask(hmask, r, zero, _CMP_LE_OS);
        cos_r = PT__SEL16(hmask & apart, _mm512_maskz_min_ps(hmask, one, _mm512_maskz_mul_ps(hmask, r, inv)), one);
    }
    return _mm512_maskz_mov_ps((__mmask16)~dead, _mm512_mul_ps(_mm512_mul_ps(_mm512_mul_ps(PT__LOAD2(power), cos_p), cos_r), rd2));
}
#undef PT__LOAD2
#undef PT__SEL16
/* pt__lnodew_level_avx2 for slots g and g + 1 of z at once (lanes 0-7 and 8-15): the importances,
   their running sums (pt__scan8_avx2's three additions within each half), each slot's total and
   count at u x total (z->lit, z->k); xa, xb: the slots' queries. */
PT__TARGET_AVX512 static inline void pt__lnodew_level2_avx512(pt__tree_slots *z, int g, const pt__tree_query *xa,
                                                              const pt__tree_query *xb)
{
    const __m512i i1 = _mm512_setr_epi32(0, 0, 1, 2, 3, 4, 5, 6, 8, 8, 9, 10, 11, 12, 13, 14);
    const __m512i i2 = _mm512_setr_epi32(0, 0, 0, 1, 2, 3, 4, 5, 8, 8, 8, 9, 10, 11, 12, 13);
    const __m512i i4 = _mm512_setr_epi32(0, 0, 0, 0, 0, 1, 2, 3, 8, 8, 8, 8, 8, 9, 10, 11);
    __m512 x = pt__lnode_importance2_avx512(z->node[g], z->node[g + 1], xa->p, xb->p, xa->nr, xb->nr, z->has_nr[g],
                                            z->has_nr[g + 1]);
    float t[2];
    unsigned go = 0u, le;
    int j;
    _mm512_storeu_ps(z->imp[g], x); /* (slots g and g + 1's rows are one after the other) */
    x = _mm512_add_ps(x, _mm512_maskz_permutexvar_ps((__mmask16)0xfefe, i1, x));
    x = _mm512_add_ps(x, _mm512_maskz_permutexvar_ps((__mmask16)0xfcfc, i2, x));
    x = _mm512_add_ps(x, _mm512_maskz_permutexvar_ps((__mmask16)0xf0f0, i4, x));
    _mm512_storeu_ps(z->c[g], x);
    for (j = 0; j < 2; ++j) {
        const float total = z->c[g + j][PT__LTREE_W - 1];
        z->lit[g + j] = total > 0.0f && pt__isfinite(total);
        t[j] = z->lit[g + j] ? z->u[g + j] * total : 0.0f;
        if (z->lit[g + j]) go |= j ? 0xff00u : 0x00ffu;
    }
    le = (unsigned)_mm512_mask_cmp_ps_mask((__mmask16)go, x, PT__SET2(t[0], t[1]), _CMP_LE_OS);
    z->k[g] = __builtin_popcount(le & 0xffu);
    z->k[g + 1] = __builtin_popcount(le >> 8);
}
#undef PT__SET2
#if PT__TREE_SLOTS % 2
#error "PT__TREE_SLOTS must be even (pt__tree_picks_avx512 pairs them)"
#endif
/* pt__tree_picks_avx2 with two slots a pass of AVX-512 (pt__lnodew_level2_avx512): the same
   results to the bit. An idle slot beside a busy one computes from its partner's query, unread. */
PT__TARGET_AVX512 PT__NOINLINE static void pt__tree_picks_avx512(const pt_scene *s, pt__tree_query *q, int n)
{
    pt__tree_slots z;
    int g;
    pt__tree_slots_start(s, &z, q, n);
    while (z.live) {
        for (g = 0; g < PT__TREE_SLOTS; g += 2) {
            const int a = z.at[g] >= 0 ? z.at[g] : z.at[g + 1], b = z.at[g + 1] >= 0 ? z.at[g + 1] : z.at[g];
            if (a >= 0) pt__lnodew_level2_avx512(&z, g, &q[a], &q[b]);
        }
        pt__tree_slots_step(s, &z, q, n);
    }
}
#endif
/* pt__lnodew_level without the AVX2 pass (arguments as pt__lnodew_level_avx2's). */
static PT__HOT int pt__lnodew_level_narrow(const pt__lnodew *n, pt_vec3 p, pt_vec3 nr, int has_nr, float u, float *imp,
                                          float *c, int *k)
{
    float total;
#ifdef PT__SSE
    int j;
    for (j = 0; j < PT__LTREE_W; j += 4) _mm_storeu_ps(imp + j, pt__lnode_importance_sse(n, j, p, nr, has_nr));
#else
    pt__lnode_importance_scalar(n, p, nr, has_nr, imp);
#endif
    pt__lnodew_scan(imp, c);
    total = c[PT__LTREE_W - 1];
    if (!(total > 0.0f && pt__isfinite(total))) return 0;
    *k = pt__lnodew_count(c, u * total);
    return 1;
}
/* One level of the descent from node n: the children's importances imp, their running sums c
   (c[7] the total), and *k the number of sums at most u x total; 0 when no child can light p.
   One AVX2 pass where the scene's level has it, else two SSE passes (or the scalar loop). */
static PT__HOT int pt__lnodew_level(const pt_scene *s, const pt__lnodew *n, pt_vec3 p, pt_vec3 nr, int has_nr,
                                    float u, float *imp, float *c, int *k)
{
#ifdef PT__WIDE
    if (s->simd >= PT_SIMD_AVX2) return pt__lnodew_level_avx2_call(n, p, nr, has_nr, u, imp, c, k);
#endif
    (void)s;
    return pt__lnodew_level_narrow(n, p, nr, has_nr, u, imp, c, k);
}
static PT__HOT int pt__tree_pick(const pt_scene *s, pt_vec3 p, pt_vec3 nr, float u, uint32_t *light, float *pmf)
{
    const pt__lnodew *n = &s->ltree[0];
    const int has_nr = pt__has_normal(nr);
    float prob = 1.0f, imp[PT__LTREE_W], c[PT__LTREE_W];
#ifdef PT__WIDE
    if (s->simd >= PT_SIMD_AVX2) return pt__tree_pick_avx2(s, p, nr, has_nr, u, light, pmf);
#endif
    PT__TREE_DESCENT(pt__lnodew_level_narrow)
}
/* The probability that light li is picked from p with receiver normal nr (mode: PT__LIGHTS_*). */
static float pt__light_pmf(const pt_scene *s, pt_vec3 p, pt_vec3 nr, uint32_t li, unsigned mode)
{
    const pt__lnodew *n;
    const int has_nr = pt__has_normal(nr);
    uint64_t trail;
    float prob = 1.0f, imp[PT__LTREE_W], c[PT__LTREE_W];
    if (!s->ltree || !(mode & PT__LIGHTS_TREE)) return s->lights[li].select_pdf;
    n = &s->ltree[0];
    trail = s->ltrail[li];
    for (;;) {
        uint32_t k = (uint32_t)(trail & (PT__LTREE_W - 1u)), child;
        int ignored;
        if (!pt__lnodew_level(s, n, p, nr, has_nr, 0.0f, imp, c, &ignored)) return 0.0f;
        prob *= imp[k] / c[PT__LTREE_W - 1];
        child = n->child[k];
        if (child & PT__LCHILD_LIGHT) return prob;
        n = &s->ltree[child];
        trail >>= PT__LTREE_BITS;
    }
}

/* Picks a light (by the tree, or by power) and samples it: ls->pdf is P_i * p_i(dir). */
/* Its two halves: the pick (light *li with probability *pick), then ls->pdf times the pick's. */
static PT__HOT int pt__lights_pick(const pt_scene *s, pt_vec3 o, pt_vec3 nr, float u0, uint32_t *li, float *pick,
                                   unsigned mode)
{
    if (!s->light_count) return 0;
    if (s->ltree && (mode & PT__LIGHTS_TREE)) return pt__tree_pick(s, o, nr, u0, li, pick);
    *li = pt__pick_light(s, u0);
    *pick = s->lights[*li].select_pdf;
    return 1;
}
static PT__HOT int pt__lights_picked(pt__light_sample *ls, float pick, uint32_t li, uint32_t *light_index)
{
    ls->pdf *= pick;
    *light_index = li;
    return ls->pdf > 0.0f && pt__isfinite(ls->pdf);
}
static PT__HOT int pt__lights_sample(const pt_scene *s, pt_vec3 o, pt_vec3 nr, float u0, float u1, float u2,
                                     pt__light_sample *ls, uint32_t *light_index, unsigned mode)
{
    uint32_t li;
    float pick;
    if (!pt__lights_pick(s, o, nr, u0, &li, &pick, mode)) return 0;
    if (!pt__light_prim_sample(s, &s->prims[s->lights[li].prim], o, u1, u2, ls, (mode & PT__LIGHTS_SPHERICAL) != 0))
        return 0;
    return pt__lights_picked(ls, pick, li, light_index);
}
static float pt__lights_value(const pt_scene *s, pt_vec3 o, pt_vec3 nr, pt_vec3 w, unsigned mode)
{
    uint32_t i;
    float v = 0.0f;
    for (i = 0; i < s->light_count; ++i) {
        float pv = pt__light_prim_value(s, &s->prims[s->lights[i].prim], o, w, (mode & PT__LIGHTS_SPHERICAL) != 0);
        if (pv > 0.0f) v += pt__light_pmf(s, o, nr, i, mode) * pv;
    }
    return v;
}

/* --- environment light (pt_scene_set_environment): L(w) = background + map(w). The map is
   sampled by a piecewise-constant density over its pixels' cells (the rectangles
   [x, x+1)/W x [y, y+1)/H of (u, v)), each cell's probability proportional to the mean
   luminance of the bilinear interpolant over it, and uniform in solid angle within the cell
   (phi uniform, cos(theta) uniform): the density of a cell is P(cell) / (its solid angle), with
   no 1/sin(theta) to blow up at the poles (the piecewise-constant 2-D distribution of pbrt,
   Pharr, Jakob & Humphreys, 4th ed., sec. A.5, with the exact solid angle of each cell in place
   of the sin(theta) at its centre). The background is sampled uniformly over the sphere; the
   two are mixed in proportion to their powers. */
#define PT__ENV_LIGHT 0xffffffffu /* the light index of an environment sample */
static double pt__env_luminance(const float *c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }
/* The map's (u, v) in [0, 1) x [0, 1] of world direction w (unit). theta by atan2: exact near the poles. */
static void pt__env_uv(const pt__env *e, pt_vec3 w, float *u, float *v)
{
    float x = e->rot[0][0] * w.x + e->rot[1][0] * w.y + e->rot[2][0] * w.z;
    float y = e->rot[0][1] * w.x + e->rot[1][1] * w.y + e->rot[2][1] * w.z;
    float z = e->rot[0][2] * w.x + e->rot[1][2] * w.y + e->rot[2][2] * w.z;
    float uu = pt__atan2f(x, -z) * (0.5f * PT__INV_PI);
    if (uu < 0.0f) uu += 1.0f;
    *u = uu < 1.0f ? uu : 0.0f;
    *v = pt__atan2f(sqrtf(x * x + z * z), y) * PT__INV_PI;
}
/* The map (scale applied) at (u, v): bilinear between pixel centres, periodic in u. */
static pt_color pt__env_lookup(const pt__env *e, float u, float v)
{
    float fx = u * (float)e->w - 0.5f, fy = v * (float)e->h - 0.5f, x0f = floorf(fx), y0f = floorf(fy);
    float tx = fx - x0f, ty = fy - y0f;
    int x0 = (int)x0f, y0 = (int)y0f, x1, y1;
    const float *a, *b, *c, *d;
    if (x0 < 0) x0 += e->w;
    if (x0 >= e->w) x0 -= e->w;
    x1 = x0 + 1 < e->w ? x0 + 1 : 0;
    y1 = y0 + 1;
    if (y0 < 0) y0 = 0;
    if (y0 > e->h - 1) y0 = e->h - 1;
    if (y1 > e->h - 1) y1 = e->h - 1;
    a = e->rgb + 3 * ((size_t)y0 * (size_t)e->w + (size_t)x0);
    b = e->rgb + 3 * ((size_t)y0 * (size_t)e->w + (size_t)x1);
    c = e->rgb + 3 * ((size_t)y1 * (size_t)e->w + (size_t)x0);
    d = e->rgb + 3 * ((size_t)y1 * (size_t)e->w + (size_t)x1);
    return pt_v3((1.0f - ty) * ((1.0f - tx) * a[0] + tx * b[0]) + ty * ((1.0f - tx) * c[0] + tx * d[0]),
                 (1.0f - ty) * ((1.0f - tx) * a[1] + tx * b[1]) + ty * ((1.0f - tx) * c[1] + tx * d[1]),
                 (1.0f - ty) * ((1.0f - tx) * a[2] + tx * b[2]) + ty * ((1.0f - tx) * c[2] + tx * d[2]));
}
/* The map's radiance along world direction w (unit) and, in *density, its sampling density
   there (per sr), from one (u, v). */
static pt_color pt__env_eval(const pt__env *e, pt_vec3 w, float *density)
{
    float u, v;
    int x, y;
    pt__env_uv(e, w, &u, &v);
    x = (int)(u * (float)e->w);
    y = (int)(v * (float)e->h);
    if (x > e->w - 1) x = e->w - 1;
    if (y > e->h - 1) y = e->h - 1;
    *density = e->cell_density[(size_t)y * (size_t)e->w + (size_t)x];
    return pt__env_lookup(e, u, v);
}
static pt_color pt__env_map_radiance(const pt__env *e, pt_vec3 w)
{
    float u, v;
    pt__env_uv(e, w, &u, &v);
    return pt__env_lookup(e, u, v);
}
/* The index i of [cdf[i], cdf[i+1]) holding u (cdf: n + 1 entries from 0 to 1), never an empty
   interval, and u's place in it, in [0, 1). guide[k] (n + 1 entries) is the answer for
   u = k / n, so the search starts in a bracket of a few intervals (the guide table of Chen &
   Asau 1974); the bracket is widened where float rounding of u n put it off by one. */
static int pt__cdf_find(const float *cdf, const int *guide, int n, float u, double *frac)
{
    int k = (int)(u * (float)n), lo, hi;
    if (k > n - 1) k = n - 1;
    if (k < 0) k = 0;
    lo = guide[k];
    hi = guide[k + 1];
    while (lo > 0 && cdf[lo] > u) --lo;
    while (hi < n - 1 && !(cdf[hi + 1] > u)) ++hi;
    while (lo < hi) { /* the first i with cdf[i + 1] > u */
        int mid = (lo + hi) / 2;
        if (cdf[mid + 1] > u) hi = mid;
        else lo = mid + 1;
    }
    while (lo > 0 && !(cdf[lo + 1] > cdf[lo])) --lo; /* (u = 1 rounded: the last non-empty one) */
    *frac = cdf[lo + 1] > cdf[lo] ? ((double)u - cdf[lo]) / ((double)cdf[lo + 1] - cdf[lo]) : 0.5;
    if (*frac < 0.0) *frac = 0.0;
    if (*frac >= 1.0) *frac = 0.99999999999999989;
    return lo;
}
/* A direction *w of the map's density, and the (u, v) and cell index it was drawn at. */
static int pt__env_map_sample(const pt__env *e, float u1, float u2, pt_vec3 *w, float *u, float *v, size_t *cell)
{
    double fy, fx, c0, c1, cos_t, sin_t, phi, sin_p, cos_p, lx, ly, lz;
    int y = pt__cdf_find(e->row_cdf, e->row_guide, e->h, u1, &fy), x;
    const float *cc = e->col_cdf + (size_t)y * (size_t)(e->w + 1);
    if (!(cc[e->w] > 0.0f)) return 0;
    x = pt__cdf_find(cc, e->col_guide + (size_t)y * (size_t)(e->w + 1), e->w, u2, &fx);
    c0 = e->cos_edge[y];
    c1 = e->cos_edge[y + 1];
    cos_t = c0 - fy * (c0 - c1);
    sin_t = sqrt(pt__maxd(0.0, (1.0 - cos_t) * (1.0 + cos_t)));
    phi = 2.0 * 3.14159265358979323846 * ((double)x + fx) / (double)e->w;
    pt__sincos_d(phi, &sin_p, &cos_p); /* (phi in [0, 2 pi); pt__env_sample8 does the same in 4 lanes) */
    lx = sin_t * sin_p;
    ly = cos_t;
    lz = -sin_t * cos_p;
    *w = pt_normalize(pt_v3((float)(e->rot[0][0] * lx + e->rot[0][1] * ly + e->rot[0][2] * lz),
                            (float)(e->rot[1][0] * lx + e->rot[1][1] * ly + e->rot[1][2] * lz),
                            (float)(e->rot[2][0] * lx + e->rot[2][1] * ly + e->rot[2][2] * lz)));
    *u = (float)(((double)x + fx) / (double)e->w);
    *v = pt__atan2f((float)sin_t, (float)cos_t) * PT__INV_PI;
    *cell = (size_t)y * (size_t)e->w + (size_t)x;
    return 1;
}
/* The environment light along w: the map's radiance (0 without one) and, in *density, the
   light's density c_uniform / (4 pi) + (1 - c_uniform) p_map(w). */
static pt_color pt__env_light_eval(const pt__env *e, float c_uniform, pt_vec3 w, float *density)
{
    float pm = 0.0f;
    pt_color L = e ? pt__env_eval(e, w, &pm) : pt_v3(0, 0, 0);
    *density = c_uniform * PT__INV_4PI + (1.0f - c_uniform) * pm;
    return L;
}
static float pt__env_density(const pt__env *e, float c_uniform, pt_vec3 w)
{
    float p;
    (void)pt__env_light_eval(e, c_uniform, w, &p);
    return p;
}
/* Samples the environment light: direction *w and its density *pdf, and with Lmap the map's
   radiance along it. With Lmap (light sampling) a map sample takes both from the point and cell it
   was drawn at, without the two atan2 of the direction: the density is the cell's own, where the
   direction's float rounding could put it in a neighbour (docs/design.md, "Environment samples
   from their cell"). Without (a pt_pdf's sample) both come from the direction, so that the
   sample's density is pt_pdf_value's to the bit. */
static int pt__env_sample(const pt__env *e, float c_uniform, float u1, float u2, pt_vec3 *w, float *pdf, pt_color *Lmap)
{
    pt_color L;
    float u, v;
    size_t cell;
    if (u1 < c_uniform || !e) {
        *w = pt_sample_uniform_sphere(pt__minf(u1 / c_uniform, 0.99999994f), u2);
    } else if (!pt__env_map_sample(e, pt__minf((u1 - c_uniform) / (1.0f - c_uniform), 0.99999994f), u2, w, &u, &v,
                                   &cell)) {
        return 0;
    } else if (Lmap) {
        *Lmap = pt__env_lookup(e, u, v);
        *pdf = c_uniform * PT__INV_4PI + (1.0f - c_uniform) * e->cell_density[cell];
        return *pdf > 0.0f && pt__isfinite(*pdf);
    }
    L = pt__env_light_eval(e, c_uniform, *w, pdf);
    if (Lmap) *Lmap = L;
    return *pdf > 0.0f && pt__isfinite(*pdf);
}
/* The share of the uniform sphere in the environment light's density under background bg. */
static float pt__env_uniform_share(const pt__env *e, pt_color bg)
{
    double b = ((double)bg.x + (double)bg.y + (double)bg.z) / 3.0, m = e ? e->mean : 0.0;
    if (!(b > 0.0)) return 0.0f;
    return m > 0.0 ? (float)(b / (b + m)) : 1.0f;
}
#ifdef PT__WIDE
/* The environment 8 lanes at a time (stages 1e and 2e of the batched integrator, AVX2): each lane
   does the float and double operations of pt__atan2f, pt__env_eval, pt__cdf_find and
   pt__env_map_sample in their order, without FMA, so the same bits. A lane the scalar code would
   answer differently from the common path (pt__atan2f's arguments that go to libm, an empty
   CDF interval, a uniform-sphere sample) is left out of the returned bits for the scalar code to
   redo; it computes with harmless operands, so no lane raises an exception the scalar code would
   not. The map's indices are 32-bit: pt__env_wide says whether the map is small enough. */
enum { PT__EO_L = 0, PT__EO_PM = 3, PT__EO_DIR = 4, PT__EO_OUT = 7 };
static int pt__env_wide(const pt__env *e)
{
    return e && (double)e->h * (double)(e->w + 1) < 2147483647.0 && 3.0 * (double)e->w * (double)e->h < 2147483647.0;
}
/* pt__atan2f for 8 lanes; *bad: the lanes pt__atan2f gives to libm (a zero, an infinity, a NaN,
   arguments beyond 1e-30 .. 1e30), whose results here are meaningless. */
PT__TARGET_AVX2 static inline __m256 pt__atan2f8(__m256 y, __m256 x, __m256 *bad)
{
    const __m256 signbit = _mm256_set1_ps(-0.0f), one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
    const __m256 ax = _mm256_andnot_ps(signbit, x), ay = _mm256_andnot_ps(signbit, y);
    const __m256 swap = _mm256_cmp_ps(ay, ax, _CMP_GT_OQ);
    __m256 hi = _mm256_blendv_ps(ax, ay, swap), lo = _mm256_blendv_ps(ay, ax, swap), ok, big, r0, r1, a, t, r;
    __m256i k;
    ok = _mm256_and_ps(_mm256_cmp_ps(lo, zero, _CMP_GT_OQ),
                       _mm256_and_ps(_mm256_cmp_ps(hi, _mm256_set1_ps(1e-30f), _CMP_GT_OQ),
                                     _mm256_cmp_ps(hi, _mm256_set1_ps(1e30f), _CMP_LT_OQ)));
    *bad = _mm256_andnot_ps(ok, _mm256_castsi256_ps(_mm256_set1_epi32(-1)));
    hi = _mm256_blendv_ps(one, hi, ok);
    lo = _mm256_blendv_ps(one, lo, ok);
    big = _mm256_cmp_ps(lo, _mm256_mul_ps(_mm256_set1_ps(0.26794919f), hi), _CMP_GT_OQ);
    r0 = _mm256_blendv_ps(_mm256_set1_ps(pt__atan_red[0][0]), _mm256_set1_ps(pt__atan_red[1][0]), big);
    r1 = _mm256_blendv_ps(_mm256_set1_ps(pt__atan_red[0][1]), _mm256_set1_ps(pt__atan_red[1][1]), big);
    a = _mm256_div_ps(_mm256_sub_ps(_mm256_mul_ps(lo, r0), _mm256_mul_ps(hi, r1)),
                      _mm256_add_ps(_mm256_mul_ps(lo, r1), _mm256_mul_ps(hi, r0)));
    t = _mm256_mul_ps(a, a);
    r = _mm256_add_ps(_mm256_set1_ps(pt__atan_c[2]), _mm256_mul_ps(t, _mm256_set1_ps(pt__atan_c[3])));
    r = _mm256_add_ps(_mm256_set1_ps(pt__atan_c[0]), _mm256_mul_ps(t, _mm256_add_ps(_mm256_set1_ps(pt__atan_c[1]), _mm256_mul_ps(t, r))));
    r = _mm256_add_ps(a, _mm256_mul_ps(a, _mm256_mul_ps(t, r)));
    k = _mm256_or_si256(_mm256_and_si256(_mm256_castps_si256(_mm256_cmp_ps(x, zero, _CMP_LT_OQ)), _mm256_set1_epi32(4)),
                        _mm256_or_si256(_mm256_and_si256(_mm256_castps_si256(swap), _mm256_set1_epi32(2)),
                                        _mm256_and_si256(_mm256_castps_si256(big), _mm256_set1_epi32(1))));
    r = _mm256_add_ps(_mm256_permutevar8x32_ps(_mm256_loadu_ps(pt__atan_off), k),
                      _mm256_mul_ps(_mm256_permutevar8x32_ps(_mm256_loadu_ps(pt__atan_sgn), k), r));
    return _mm256_or_ps(_mm256_andnot_ps(signbit, r), _mm256_and_ps(signbit, y));
}
/* pt__env_lookup for 8 lanes: the four pixels' channels gathered (indices below 2^31: pt__env_wide). */
PT__TARGET_AVX2 static inline void pt__env_lookup8(const pt__env *e, __m256 u, __m256 v, __m256 *L)
{
    const __m256 one = _mm256_set1_ps(1.0f), half = _mm256_set1_ps(0.5f);
    const __m256i W = _mm256_set1_epi32(e->w), h1 = _mm256_set1_epi32(e->h - 1), i1 = _mm256_set1_epi32(1);
    const __m256 fx = _mm256_sub_ps(_mm256_mul_ps(u, _mm256_set1_ps((float)e->w)), half);
    const __m256 fy = _mm256_sub_ps(_mm256_mul_ps(v, _mm256_set1_ps((float)e->h)), half);
    const __m256 x0f = _mm256_floor_ps(fx), y0f = _mm256_floor_ps(fy);
    const __m256 tx = _mm256_sub_ps(fx, x0f), ty = _mm256_sub_ps(fy, y0f);
    const __m256 sx = _mm256_sub_ps(one, tx), sy = _mm256_sub_ps(one, ty);
    __m256i x0 = _mm256_cvttps_epi32(x0f), y0 = _mm256_cvttps_epi32(y0f), x1, y1, ia, ib, ic, id;
    int c;
    x0 = _mm256_add_epi32(x0, _mm256_and_si256(_mm256_cmpgt_epi32(_mm256_setzero_si256(), x0), W)); /* x0 < 0 */
    x0 = _mm256_sub_epi32(x0, _mm256_andnot_si256(_mm256_cmpgt_epi32(W, x0), W));                    /* x0 >= w */
    x1 = _mm256_add_epi32(x0, i1);
    x1 = _mm256_and_si256(x1, _mm256_cmpgt_epi32(W, x1));
    y1 = _mm256_min_epi32(_mm256_add_epi32(y0, i1), h1);
    y0 = _mm256_min_epi32(_mm256_max_epi32(y0, _mm256_setzero_si256()), h1);
    y0 = _mm256_mullo_epi32(y0, W);
    y1 = _mm256_mullo_epi32(y1, W);
    ia = _mm256_mullo_epi32(_mm256_add_epi32(y0, x0), _mm256_set1_epi32(3));
    ib = _mm256_mullo_epi32(_mm256_add_epi32(y0, x1), _mm256_set1_epi32(3));
    ic = _mm256_mullo_epi32(_mm256_add_epi32(y1, x0), _mm256_set1_epi32(3));
    id = _mm256_mullo_epi32(_mm256_add_epi32(y1, x1), _mm256_set1_epi32(3));
    for (c = 0; c < 3; ++c) {
        const float *base = e->rgb + c;
        const __m256 a = _mm256_i32gather_ps(base, ia, 4), b = _mm256_i32gather_ps(base, ib, 4);
        const __m256 cc = _mm256_i32gather_ps(base, ic, 4), d = _mm256_i32gather_ps(base, id, 4);
        L[c] = _mm256_add_ps(_mm256_mul_ps(sy, _mm256_add_ps(_mm256_mul_ps(sx, a), _mm256_mul_ps(tx, b))),
                             _mm256_mul_ps(ty, _mm256_add_ps(_mm256_mul_ps(sx, cc), _mm256_mul_ps(tx, d))));
    }
}
/* pt__env_eval for 8 lanes: w (unit, world) in in[0..2]; the map's radiance to out[PT__EO_L ..]
   and the cell's density to out[PT__EO_PM]. Returns the lanes taken. */
PT__TARGET_AVX2 static int pt__env_eval8(const pt__env *e, float (*in)[8], float (*out)[8])
{
    const __m256 wx = _mm256_loadu_ps(in[0]), wy = _mm256_loadu_ps(in[1]), wz = _mm256_loadu_ps(in[2]);
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    __m256 c[3], uu, u, v, bad1, bad2, L[3];
    __m256i xi, yi;
    int k;
    for (k = 0; k < 3; ++k)
        c[k] = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(_mm256_set1_ps(e->rot[0][k]), wx), _mm256_mul_ps(_mm256_set1_ps(e->rot[1][k]), wy)),
                             _mm256_mul_ps(_mm256_set1_ps(e->rot[2][k]), wz));
    uu = _mm256_mul_ps(pt__atan2f8(c[0], _mm256_xor_ps(_mm256_set1_ps(-0.0f), c[2]), &bad1), _mm256_set1_ps(0.5f * PT__INV_PI));
    uu = _mm256_blendv_ps(uu, _mm256_add_ps(uu, one), _mm256_cmp_ps(uu, zero, _CMP_LT_OQ));
    u = _mm256_and_ps(uu, _mm256_cmp_ps(uu, one, _CMP_LT_OQ));
    v = _mm256_mul_ps(pt__atan2f8(_mm256_sqrt_ps(_mm256_add_ps(_mm256_mul_ps(c[0], c[0]), _mm256_mul_ps(c[2], c[2]))), c[1], &bad2),
                      _mm256_set1_ps(PT__INV_PI));
    xi = _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(u, _mm256_set1_ps((float)e->w))), _mm256_set1_epi32(e->w - 1));
    yi = _mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(v, _mm256_set1_ps((float)e->h))), _mm256_set1_epi32(e->h - 1));
    _mm256_storeu_ps(out[PT__EO_PM],
                     _mm256_i32gather_ps(e->cell_density, _mm256_add_epi32(_mm256_mullo_epi32(yi, _mm256_set1_epi32(e->w)), xi), 4));
    pt__env_lookup8(e, u, v, L);
    for (k = 0; k < 3; ++k) _mm256_storeu_ps(out[PT__EO_L + k], L[k]);
    return ~_mm256_movemask_ps(_mm256_or_ps(bad1, bad2)) & 0xff;
}
/* 4 doubles base[i] (the masked form: gcc 12's unmasked one reads an undefined source, which g++ warns of) */
PT__TARGET_AVX2 static inline __m256d pt__gather4d(const double *base, __m128i i)
{
    return _mm256_mask_i32gather_pd(_mm256_setzero_pd(), base, i, _mm256_castsi256_pd(_mm256_set1_epi64x(-1)), 8);
}
/* The first i in [start, bound] of each lane with cdf[i + 1] > u, or bound, by halving steps of
   at most wmax in all (the number of i from start on with cdf[i + 1] <= u: cdf is non-decreasing). */
PT__TARGET_AVX2 static inline __m256i pt__cdf_count8(const float *cdf, __m256i base, __m256i start, __m256i bound, int wmax,
                                                     __m256 u)
{
    const __m256i b1 = _mm256_add_epi32(bound, _mm256_set1_epi32(1));
    __m256i i = start;
    int step = 1;
    while (2 * step <= wmax) step *= 2;
    for (; step >= 1 && wmax > 0; step /= 2) {
        const __m256i cand = _mm256_add_epi32(i, _mm256_set1_epi32(step));
        const __m256 c = _mm256_i32gather_ps(cdf, _mm256_add_epi32(base, _mm256_min_epi32(cand, bound)), 4);
        const __m256 adv = _mm256_andnot_ps(_mm256_cmp_ps(c, u, _CMP_GT_OQ), _mm256_castsi256_ps(_mm256_cmpgt_epi32(b1, cand)));
        i = _mm256_add_epi32(i, _mm256_and_si256(_mm256_castps_si256(adv), _mm256_set1_epi32(step)));
    }
    return i;
}
/* pt__cdf_find for 8 lanes, the cdf of lane j at cdf + base[j] (n + 1 entries) and its guide at
   guide + base[j]: the first i with cdf[i + 1] > u (at most n - 1), searched between the guide's
   entries as the scalar code starts, and checked (cdf[i] <= u < cdf[i + 1] at the ends' exceptions)
   to be the first one; where the guide's bracket missed it (float rounding of u n), the group
   searches all n intervals. That is the scalar search's answer wherever its interval is not
   empty. u's place in it in two halves of 4 doubles. Returns the lanes whose interval is empty
   (the scalar code's u = 1 case), for it to redo. */
PT__TARGET_AVX2 static inline __m256 pt__cdf_find8(const float *cdf, const int *guide, __m256i base, int n, __m256 u,
                                                   __m256i *idx, __m256d *frac)
{
    const __m256i zero = _mm256_setzero_si256(), n1 = _mm256_set1_epi32(n - 1);
    const __m256i k = _mm256_max_epi32(_mm256_min_epi32(_mm256_cvttps_epi32(_mm256_mul_ps(u, _mm256_set1_ps((float)n))), n1), zero);
    const __m256i lo = _mm256_i32gather_epi32(guide, _mm256_add_epi32(base, k), 4);
    const __m256i hi = _mm256_i32gather_epi32(guide, _mm256_add_epi32(base, _mm256_add_epi32(k, _mm256_set1_epi32(1))), 4);
    int wd[8], wmax = 0, j, h;
    __m256i i;
    __m256 c0, c1, empty, miss;
    _mm256_storeu_si256((__m256i *)wd, _mm256_sub_epi32(hi, lo));
    for (j = 0; j < 8; ++j) wmax = wd[j] > wmax ? wd[j] : wmax;
    i = pt__cdf_count8(cdf, base, lo, hi, wmax, u);
    c0 = _mm256_i32gather_ps(cdf, _mm256_add_epi32(base, i), 4);
    c1 = _mm256_i32gather_ps(cdf, _mm256_add_epi32(base, _mm256_add_epi32(i, _mm256_set1_epi32(1))), 4);
    miss = _mm256_or_ps(_mm256_andnot_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(i, n1)), _mm256_cmp_ps(c1, u, _CMP_NGT_UQ)),
                        _mm256_andnot_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(i, zero)), _mm256_cmp_ps(c0, u, _CMP_GT_OQ)));
    if (PT__UNLIKELY(_mm256_movemask_ps(miss))) {
        i = _mm256_min_epi32(pt__cdf_count8(cdf, base, zero, _mm256_set1_epi32(n), n - 1, u), n1);
        c0 = _mm256_i32gather_ps(cdf, _mm256_add_epi32(base, i), 4);
        c1 = _mm256_i32gather_ps(cdf, _mm256_add_epi32(base, _mm256_add_epi32(i, _mm256_set1_epi32(1))), 4);
    }
    empty = _mm256_cmp_ps(c1, c0, _CMP_NGT_UQ);
    c1 = _mm256_blendv_ps(c1, _mm256_add_ps(c0, _mm256_set1_ps(1.0f)), empty);
    for (h = 0; h < 2; ++h) {
        const __m256d ud = _mm256_cvtps_pd(h ? _mm256_extractf128_ps(u, 1) : _mm256_castps256_ps128(u));
        const __m256d d0 = _mm256_cvtps_pd(h ? _mm256_extractf128_ps(c0, 1) : _mm256_castps256_ps128(c0));
        const __m256d d1 = _mm256_cvtps_pd(h ? _mm256_extractf128_ps(c1, 1) : _mm256_castps256_ps128(c1));
        __m256d f = _mm256_div_pd(_mm256_sub_pd(ud, d0), _mm256_sub_pd(d1, d0));
        f = _mm256_blendv_pd(f, _mm256_setzero_pd(), _mm256_cmp_pd(f, _mm256_setzero_pd(), _CMP_LT_OQ));
        frac[h] = _mm256_blendv_pd(f, _mm256_set1_pd(0.99999999999999989), _mm256_cmp_pd(f, _mm256_set1_pd(1.0), _CMP_GE_OQ));
    }
    *idx = i;
    return empty;
}
/* pt__env_sample with its radiance wanted (light sampling) for 8 lanes of draws u1, u2 and the
   uniform share c: the direction to out[PT__EO_DIR ..], the map's radiance at the point drawn
   to out[PT__EO_L ..] and the density c / (4 pi) + (1 - c) p_cell to out[PT__EO_PM] (the
   caller tests it > 0 and finite, as pt__env_sample does). Returns the lanes taken: not those
   with u1 < c (a uniform-sphere sample), an empty interval, or sin theta, cos theta that
   pt__atan2f gives to libm (the poles). */
PT__TARGET_AVX2 static int pt__env_sample8(const pt__env *e, float c, const float *u1, const float *u2, float (*out)[8])
{
    const __m256 cv = _mm256_set1_ps(c), one = _mm256_set1_ps(1.0f);
    const __m256 a1 = _mm256_loadu_ps(u1);
    const __m256 bad0 = _mm256_cmp_ps(a1, cv, _CMP_LT_OQ);
    const __m256 v1 = _mm256_min_ps(_mm256_div_ps(_mm256_sub_ps(a1, cv), _mm256_sub_ps(one, cv)), _mm256_set1_ps(0.99999994f));
    const __m256d tau = _mm256_set1_pd(2.0 * 3.14159265358979323846), W = _mm256_set1_pd((double)e->w);
    __m256d fy[2], fx[2];
    __m256i y, x;
    __m256 bad1, bad2, bad3, w[3], st[2], ct[2], uf[2], sn8, cs8, u, v, l2, ok, L[3], inv;
    int h, k;
    bad1 = pt__cdf_find8(e->row_cdf, e->row_guide, _mm256_setzero_si256(), e->h, v1, &y, fy);
    bad2 = pt__cdf_find8(e->col_cdf, e->col_guide, _mm256_mullo_epi32(y, _mm256_set1_epi32(e->w + 1)), e->w,
                         _mm256_loadu_ps(u2), &x, fx);
    for (h = 0; h < 2; ++h) {
        const __m128i yh = h ? _mm256_extracti128_si256(y, 1) : _mm256_castsi256_si128(y);
        const __m128i xh = h ? _mm256_extracti128_si256(x, 1) : _mm256_castsi256_si128(x);
        const __m256d c0 = pt__gather4d(e->cos_edge, yh), c1 = pt__gather4d(e->cos_edge, _mm_add_epi32(yh, _mm_set1_epi32(1)));
        const __m256d cos_t = _mm256_sub_pd(c0, _mm256_mul_pd(fy[h], _mm256_sub_pd(c0, c1)));
        const __m256d one_d = _mm256_set1_pd(1.0);
        const __m256d sin_t = _mm256_sqrt_pd(_mm256_max_pd(_mm256_setzero_pd(), _mm256_mul_pd(_mm256_sub_pd(one_d, cos_t),
                                                                                               _mm256_add_pd(one_d, cos_t))));
        const __m256d xf = _mm256_add_pd(_mm256_cvtepi32_pd(xh), fx[h]);
        __m256d sn, cs, l[3];
        pt__sincos4(_mm256_div_pd(_mm256_mul_pd(tau, xf), W), &sn, &cs);
        l[0] = _mm256_mul_pd(sin_t, sn);
        l[1] = cos_t;
        l[2] = _mm256_mul_pd(_mm256_xor_pd(_mm256_set1_pd(-0.0), sin_t), cs);
        for (k = 0; k < 3; ++k) {
            const __m256d d = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(_mm256_set1_pd((double)e->rot[k][0]), l[0]),
                                                          _mm256_mul_pd(_mm256_set1_pd((double)e->rot[k][1]), l[1])),
                                            _mm256_mul_pd(_mm256_set1_pd((double)e->rot[k][2]), l[2]));
            const __m128 f = _mm256_cvtpd_ps(d);
            w[k] = h ? _mm256_insertf128_ps(w[k], f, 1) : _mm256_castps128_ps256(f);
        }
        uf[h] = _mm256_castps128_ps256(_mm256_cvtpd_ps(_mm256_div_pd(xf, W)));
        st[h] = _mm256_castps128_ps256(_mm256_cvtpd_ps(sin_t));
        ct[h] = _mm256_castps128_ps256(_mm256_cvtpd_ps(cos_t));
    }
    u = _mm256_insertf128_ps(uf[0], _mm256_castps256_ps128(uf[1]), 1);
    sn8 = _mm256_insertf128_ps(st[0], _mm256_castps256_ps128(st[1]), 1);
    cs8 = _mm256_insertf128_ps(ct[0], _mm256_castps256_ps128(ct[1]), 1);
    /* pt_normalize */
    l2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(w[0], w[0]), _mm256_mul_ps(w[1], w[1])), _mm256_mul_ps(w[2], w[2]));
    ok = _mm256_cmp_ps(l2, _mm256_setzero_ps(), _CMP_GT_OQ);
    inv = _mm256_div_ps(one, _mm256_sqrt_ps(_mm256_blendv_ps(one, l2, ok)));
    for (k = 0; k < 3; ++k) _mm256_storeu_ps(out[PT__EO_DIR + k], _mm256_and_ps(ok, _mm256_mul_ps(w[k], inv)));
    v = _mm256_mul_ps(pt__atan2f8(sn8, cs8, &bad3), _mm256_set1_ps(PT__INV_PI));
    pt__env_lookup8(e, u, v, L);
    for (k = 0; k < 3; ++k) _mm256_storeu_ps(out[PT__EO_L + k], L[k]);
    _mm256_storeu_ps(out[PT__EO_PM],
                     _mm256_add_ps(_mm256_mul_ps(cv, _mm256_set1_ps(PT__INV_4PI)),
                                   _mm256_mul_ps(_mm256_sub_ps(one, cv),
                                                 _mm256_i32gather_ps(e->cell_density,
                                                                     _mm256_add_epi32(_mm256_mullo_epi32(y, _mm256_set1_epi32(e->w)), x), 4))));
    return ~_mm256_movemask_ps(_mm256_or_ps(_mm256_or_ps(bad0, bad1), _mm256_or_ps(bad2, bad3))) & 0xff;
}
#endif

/* --- fuzzy metal lobe: the direction of r + f s, with r the unit mirror direction and s
   uniform in the unit ball (Shirley, "Ray Tracing in One Weekend" v3, sec. 10.6). Its
   density follows in closed form: along direction w at angle theta from r the ball covers
   t in [t1, t2], roots of t^2 - 2 t cos(theta) + 1 - f^2 = 0, and
   p(w) = (t2^3 - t1^3) / (3 V), V = 4/3 pi f^3. With h = sqrt(f^2 - sin^2 theta),
   t2 - t1 = 2h and t2^3 - t1^3 = 2h (4 cos^2 theta - 1 + f^2) (no cancellation);
   for f <= 1 the ball never contains the origin, so t1 >= 0 wherever cos(theta) >= 0. */
static float pt__fuzz_value(pt_vec3 r, float f, pt_vec3 w)
{
    float cos_t = pt_dot(w, r), sin2 = pt_length2(pt_cross(w, r)), f2 = f * f, h;
    if (cos_t <= 0.0f || sin2 >= f2) return 0.0f;
    h = sqrtf(f2 - sin2);
    return h * (4.0f * cos_t * cos_t - 1.0f + f2) / (2.0f * PT__PI * f2 * f);
}
static pt_vec3 pt__fuzz_sample(pt_vec3 r, float f, float u1, float u2, float u3)
{
    pt_vec3 s = pt_scale(pt_sample_uniform_sphere(u1, u2), f * cbrtf(u3));
    return pt_normalize(pt_add(r, s));
}
static pt_vec3 pt__reflect(pt_vec3 wo, pt_vec3 n) { return pt_sub(pt_scale(n, 2.0f * pt_dot(wo, n)), wo); }

/* --- GGX (Trowbridge-Reitz) microfacets of isotropic roughness a, in a local frame with the
   normal along +z (Walter, Marschner, Li & Torrance, "Microfacet Models for Refraction through
   Rough Surfaces", EGSR 2007; Heitz, "Understanding the Masking-Shadowing Function in
   Microfacet-Based BRDFs", JCGT 3(2), 2014). For unit m, D(m) = a^2 / (pi (m_x^2 + m_y^2 +
   a^2 m_z^2)^2), the usual 1 / (pi a^2 cos^4 (1 + tan^2 / a^2)^2) without tangents, so grazing
   m and tiny a need no division by cos. Smith's G1(v) = 2 / (1 + sqrt(1 + a^2 tan^2)), written
   2 v_z / (v_z + sqrt(v_z^2 + a^2 (v_x^2 + v_y^2))). */
static float pt__ggx_d(pt_vec3 m, float a2)
{
    float s = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
    if (!(m.z > 0.0f) || !(s > 0.0f)) return 0.0f;
    return a2 / (PT__PI * s * s);
}
static float pt__ggx_g1(pt_vec3 v, float a2)
{
    float z2 = v.z * v.z, d;
    if (!(v.z > 0.0f)) return 0.0f;
    d = v.z + sqrtf(z2 + a2 * (v.x * v.x + v.y * v.y));
    return d > 0.0f ? 2.0f * v.z / d : 0.0f;
}
/* A microfacet normal drawn from the distribution of normals visible from v (v_z > 0):
   D_v(m) = G1(v) max(0, v.m) D(m) / v_z (Heitz, "Sampling the GGX Distribution of Visible
   Normals", JCGT 7(4), 2018: stretch v to the hemisphere configuration, sample the projected
   disk, unstretch). pt__ggx_vn_disk: the normal of a point (p1, p2) of the unit disk, p1 across
   the plane of v and the normal; pt__ggx_sample_vn: the disk point from polar coordinates. */
static pt_vec3 pt__ggx_vn_disk(pt_vec3 v, float a, float p1, float p2)
{
    pt_vec3 vh = pt_normalize(pt_v3(a * v.x, a * v.y, v.z)), t1, t2, nh;
    float l2 = vh.x * vh.x + vh.y * vh.y, s = 0.5f * (1.0f + vh.z);
    t1 = l2 > 0.0f ? pt_scale(pt_v3(-vh.y, vh.x, 0.0f), 1.0f / sqrtf(l2)) : pt_v3(1.0f, 0.0f, 0.0f);
    t2 = pt_cross(vh, t1);
    p2 = (1.0f - s) * pt__safe_sqrt(1.0f - p1 * p1) + s * p2;
    nh = pt_add(pt_add(pt_scale(t1, p1), pt_scale(t2, p2)), pt_scale(vh, pt__safe_sqrt(1.0f - p1 * p1 - p2 * p2)));
    return pt_normalize(pt_v3(a * nh.x, a * nh.y, pt__maxf(0.0f, nh.z)));
}
static pt_vec3 pt__ggx_sample_vn(pt_vec3 v, float a, float u1, float u2)
{
    float r = sqrtf(u1), phi = 2.0f * PT__PI * u2;
    return pt__ggx_vn_disk(v, a, r * cosf(phi), r * sinf(phi));
}
/* The density of reflected directions wi = reflect(wo, m) for m ~ D_v(wo): D_v(m) / (4 wo.m)
   = G1(wo) D(m) / (4 wo_z), m the half vector of wo and wi (both above the surface). */
static float pt__ggx_reflect_density(pt_vec3 wo, pt_vec3 wi, float a2)
{
    pt_vec3 m;
    if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return 0.0f;
    m = pt_normalize(pt_add(wo, wi));
    return pt__ggx_g1(wo, a2) * pt__ggx_d(m, a2) / (4.0f * wo.z);
}

/* Forward declarations of the material functions (section 4) used by the public PDFs. */
static int pt__material_pdf_sample(const pt_scene *s, int material, pt_vec3 n, pt_vec3 wo, float u1, float u2,
                                   float u3, pt_vec3 *dir, float *pdf);
static float pt__material_pdf_value(const pt_scene *s, int material, pt_vec3 n, pt_vec3 wo, pt_vec3 w);

static pt_pdf pt__pdf_blank(pt_pdf_type type)
{
    pt_pdf p;
    memset(&p, 0, sizeof p);
    p.type = type;
    return p;
}
PTDEF pt_pdf pt_pdf_uniform_sphere(void) { return pt__pdf_blank(PT_PDF_UNIFORM_SPHERE); }
PTDEF pt_pdf pt_pdf_cosine_hemisphere(pt_vec3 unit_normal)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_COSINE_HEMISPHERE);
    p.as.cosine.basis = pt_onb_from_normal(pt_normalize(unit_normal));
    return p;
}
PTDEF pt_pdf pt_pdf_sphere_light(pt_vec3 origin, pt_vec3 center, float radius, int two_sided)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_SPHERE_LIGHT);
    p.origin = origin;
    p.as.sphere.center = center;
    p.as.sphere.radius = radius;
    p.as.sphere.two_sided = two_sided;
    return p;
}
PTDEF pt_pdf pt_pdf_quad_light(pt_vec3 origin, pt_vec3 q, pt_vec3 u, pt_vec3 v, int two_sided)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_QUAD_LIGHT);
    p.origin = origin;
    p.as.quad.q = q; p.as.quad.u = u; p.as.quad.v = v;
    p.as.quad.two_sided = two_sided;
    return p;
}
PTDEF pt_pdf pt_pdf_triangle_light(pt_vec3 origin, pt_vec3 a, pt_vec3 b, pt_vec3 c, int two_sided)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_TRIANGLE_LIGHT);
    p.origin = origin;
    p.as.triangle.a = a; p.as.triangle.b = b; p.as.triangle.c = c;
    p.as.triangle.two_sided = two_sided;
    return p;
}
PTDEF pt_pdf pt_pdf_scene_lights(const pt_scene *scene, pt_vec3 origin)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_SCENE_LIGHTS);
    p.origin = origin;
    p.as.lights.scene = scene;
    p.as.lights.normal = pt_v3(0.0f, 0.0f, 0.0f);
    return p;
}
PTDEF pt_pdf pt_pdf_scene_lights_at(const pt_scene *scene, pt_vec3 origin, pt_vec3 normal)
{
    pt_pdf p = pt_pdf_scene_lights(scene, origin);
    float l2 = pt_length2(normal);
    if (l2 > 0.0f && pt__isfinite(l2)) p.as.lights.normal = pt_scale(normal, 1.0f / sqrtf(l2));
    return p;
}
PTDEF pt_pdf pt_pdf_environment(const pt_scene *scene, pt_color background)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_ENVIRONMENT);
    p.as.environment.scene = scene;
    p.as.environment.background = background;
    return p;
}
/* The environment light of pdf (PT_PDF_ENVIRONMENT): its map and uniform share; 0 if it has none. */
static int pt__pdf_env(const pt_pdf *pdf, const pt__env **e, float *c_uniform)
{
    const pt_scene *s = pdf->as.environment.scene;
    if (!s || !s->committed || !pt__color_ok(pdf->as.environment.background)) return 0;
    *e = s->env;
    *c_uniform = pt__env_uniform_share(s->env, pdf->as.environment.background);
    return s->env ? s->env->mean > 0.0 || *c_uniform > 0.0f : *c_uniform > 0.0f;
}
PTDEF pt_pdf pt_pdf_material(const pt_scene *scene, int material, pt_vec3 normal, pt_vec3 wo)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_MATERIAL);
    p.as.material.scene = scene;
    p.as.material.material = material;
    p.as.material.normal = pt_normalize(normal);
    p.as.material.wo = pt_normalize(wo);
    return p;
}
PTDEF pt_pdf pt_pdf_mixture(int count, const pt_pdf *components, const float *weights)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_MIXTURE);
    p.as.mixture.count = count;
    p.as.mixture.components = components;
    p.as.mixture.weights = weights;
    return p;
}
PTDEF pt_pdf pt_pdf_callback(void *user, pt_pdf_sample_fn sample, pt_pdf_value_fn value)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_CALLBACK);
    p.as.callback.user = user;
    p.as.callback.sample = sample;
    p.as.callback.value = value;
    return p;
}

/* --- the learned guide (pt_guide): an SD-tree after Mueller, Gross & Novak, "Practical Path
   Guiding for Efficient Light-Transport Simulation" (EGSR 2017). A spatial binary tree (split
   at the middle, axes x, y, z in turn) whose leaves hold two quadtrees over the equal-area square
   of directions: the sampling tree (each node's four quadrant probabilities) and the building
   tree (each node's four fixed-point sums of the records), whose topology is fixed between
   updates so that records need no lock. --- */
#define PT__GUIDE_MAX_DEPTH 16          /* quadtree levels: a float direction resolves ~1e-7 rad, a
                                           level-16 cell is 1e-4 rad wide (deeper cells would be a
                                           few roundings wide: sample and value would disagree) */
#define PT__GUIDE_SPATIAL_MAX_DEPTH 48  /* spatial levels (16 halvings per axis) */
#define PT__GUIDE_CLAMP_UNITS ((uint64_t)1 << 40)

/* a sampling tree's node: its quadrants' probabilities and children side by side, so a level of
   a descent reads one 32-byte node */
typedef struct pt__dnode {
    float prob[4];      /* P(quadrant | node), summing to 1 */
    uint32_t child[4];  /* the quadrant's child node, 0: the quadrant is a leaf */
} pt__dnode;
typedef struct pt__dtree {
    uint32_t nodes, cap;
    pt__dnode *node;   /* sampling tree */
    uint32_t *child;   /* building tree: 4 per node, the quadrant's child node (0: a leaf) */
    uint64_t *energy;  /* building tree: 4 per node, sums of the records in fixed point */
} pt__dtree;

typedef struct pt__guide_leaf {
    pt__dtree sampling, building;
    uint64_t records;  /* records since the last update (added atomically) */
    int trained;       /* the sampling tree holds learned data (else it is uniform) */
    float flux;        /* the last update's mean record: an estimate of the integral of L_i over the
                          sphere at the leaf (Russian roulette's expected contribution) */
} pt__guide_leaf;

typedef struct pt__guide_node {
    int axis;          /* 0, 1, 2: split at the middle of that axis; -1: a leaf */
    int depth;         /* the root's is 0; a leaf at depth d splits along axis d mod 3 */
    uint32_t child[2]; /* children (lower, upper half), or child[0] = the leaf's index */
} pt__guide_node;

struct pt_guide {
    pt_guide_desc desc;               /* resolved */
    pt_vec3 lo, hi, inv_extent;       /* the box, in the coordinates records are made in */
    const pt_scene *scene;            /* pt_guide_create_for_scene: points are converted to local */
    pt__guide_node *nodes;
    uint32_t *jump;                   /* 2^jump_bits entries: the node a point's first jump_bits
                                         levels lead to (pt__guide_leaf_at) */
    int jump_bits;                    /* PT__GUIDE_JUMP_BITS, or 0 under a memory bound below 1 MiB */
    pt__guide_leaf *leaves;
    uint32_t node_count, node_cap, leaf_count, leaf_cap;
    uint64_t max_nodes;               /* directional nodes max_bytes allows */
    double unit;                      /* the value of one fixed-point unit */
    int updates, at_bound;
    struct pt_guide *caustic;         /* a render's caustic photons (section 8), owned; or NULL */
#if !defined(PDFTRACE_NO_THREADS) && !defined(__GNUC__) && !defined(__clang__)
    pthread_mutex_t lock;             /* no atomics: the sums are added under a lock */
#endif
};

/* an integer sum does not depend on the order of its terms: the guide is the same whatever the
   threads' schedule */
static void pt__guide_add(pt_guide *g, uint64_t *p, uint64_t v)
{
#if defined(PDFTRACE_NO_THREADS)
    (void)g;
    *p += v;
#elif defined(__GNUC__) || defined(__clang__)
    (void)g;
    (void)__atomic_fetch_add(p, v, __ATOMIC_RELAXED);
#else
    pthread_mutex_lock(&g->lock);
    *p += v;
    pthread_mutex_unlock(&g->lock);
#endif
}

/* atan2 to 3e-9, faster than libm's (it was most of a guide look-up): the octant's
   argument a = lo/hi in [0, 1], reduced to |a'| <= tan(pi/12) by atan(a) = pi/6 + atan((a sqrt3
   - 1) / (a + sqrt3)), taken as one division (lo sqrt3 - hi) / (lo + hi sqrt3), then the odd
   Taylor series to a^11 (remainder below a^13 / 13 < 3e-9). Selects, not branches: directions
   come in no order a predictor could learn. */
static double pt__atan2d(double y, double x)
{
    const double ax = fabs(x), ay = fabs(y), hi = ax > ay ? ax : ay, lo = ax > ay ? ay : ax;
    const int big = lo > 0.2679491924311227 * hi;
    const double num = big ? lo * 1.7320508075688772 - hi : lo, den = big ? lo + hi * 1.7320508075688772 : hi;
    double a, a2, r;
    if (!(hi > 0.0)) return 0.0;
    a = num / den;
    a2 = a * a;
    r = (big ? 0.5235987755982988 : 0.0) +
        a * (1.0 + a2 * (-1.0 / 3.0 + a2 * (0.2 + a2 * (-1.0 / 7.0 + a2 * (1.0 / 9.0 + a2 * (-1.0 / 11.0))))));
    r = ay > ax ? 1.5707963267948966 - r : r;
    r = x < 0.0 ? 3.141592653589793 - r : r;
    return y < 0.0 ? -r : r;
}

/* The cylindrical equal-area map: (x, y) in [0,1)^2, d(omega) = 4 pi dx dy. */
static void pt__guide_dir_to_square(pt_vec3 w, float *x, float *y)
{
    /* in double: a deep cell (2^-20 wide) is a few float roundings of a direction wide */
    double z = w.z < -1.0f ? -1.0 : (w.z > 1.0f ? 1.0 : (double)w.z), phi = pt__atan2d((double)w.y, (double)w.x);
    if (phi < 0.0) phi += 6.283185307179586;
    *x = (float)((z + 1.0) * 0.5);
    *y = (float)(phi * 0.15915494309189535);
    if (!(*x < 1.0f)) *x = 0.99999994f;
    if (!(*y < 1.0f)) *y = 0.99999994f;
    if (!(*x >= 0.0f)) *x = 0.0f;
    if (!(*y >= 0.0f)) *y = 0.0f;
}
static pt_vec3 pt__guide_square_to_dir(double x, double y)
{
    double z = 2.0 * x - 1.0, r = sqrt(1.0 - z * z > 0.0 ? 1.0 - z * z : 0.0), phi = 6.283185307179586 * y;
    return pt_v3((float)(r * cos(phi)), (float)(r * sin(phi)), (float)z);
}

/* One level down the quadtree: the quadrant of (x, y) and (x, y) rescaled into it. */
static int pt__guide_quadrant(float *x, float *y)
{
    int bx = *x >= 0.5f, by = *y >= 0.5f;
    *x = 2.0f * *x - (float)bx;
    *y = 2.0f * *y - (float)by;
    return bx + 2 * by;
}

/* The sampling tree's density over the square at (x, y) (1: uniform). */
static float pt__dtree_density(const pt__dtree *t, float x, float y)
{
    float d = 1.0f;
    uint32_t n = 0;
    int level;
    if (!t->nodes) return 1.0f;
    for (level = 0; level < PT__GUIDE_MAX_DEPTH; ++level) {
        const pt__dnode *nd = t->node + n;
        int q = pt__guide_quadrant(&x, &y);
        d *= 4.0f * nd->prob[q];
        n = nd->child[q];
        if (!n || !(d > 0.0f)) break;
    }
    return d > 0.0f ? d : 0.0f;
}
/* The densities at two points of the square (a direction and its mirror), the two descents
   interleaved so that each hides the other's memory latency; each as pt__dtree_density's. */
static void pt__dtree_density2(const pt__dtree *t, float x0, float y0, float x1, float y1, float *d0, float *d1)
{
    float a = 1.0f, b = 1.0f;
    uint32_t n = 0, m = 0;
    int level, go_a = 1, go_b = 1;
    if (!t->nodes) { *d0 = *d1 = 1.0f; return; }
    for (level = 0; level < PT__GUIDE_MAX_DEPTH && (go_a || go_b); ++level) {
        if (go_a) {
            const pt__dnode *nd = t->node + n;
            int q = pt__guide_quadrant(&x0, &y0);
            a *= 4.0f * nd->prob[q];
            n = nd->child[q];
            go_a = n && a > 0.0f;
        }
        if (go_b) {
            const pt__dnode *nd = t->node + m;
            int q = pt__guide_quadrant(&x1, &y1);
            b *= 4.0f * nd->prob[q];
            m = nd->child[q];
            go_b = m && b > 0.0f;
        }
    }
    *d0 = a > 0.0f ? a : 0.0f;
    *d1 = b > 0.0f ? b : 0.0f;
}

/* The densities of two trees (a, b) at two points each (a direction and its mirror): the four
   descents interleaved, as pt__dtree_density2's two. */
static void pt__dtree_density4(const pt__dtree *a, const pt__dtree *b, float x0, float y0, float x1, float y1,
                               float d[4])
{
    const pt__dtree *t[4];
    float x[4], y[4], p[4] = {1.0f, 1.0f, 1.0f, 1.0f};
    uint32_t n[4] = {0, 0, 0, 0};
    int level, k, go[4], live;
    t[0] = t[1] = a;
    t[2] = t[3] = b;
    x[0] = x[2] = x0;
    y[0] = y[2] = y0;
    x[1] = x[3] = x1;
    y[1] = y[3] = y1;
    go[0] = go[1] = a->nodes != 0;
    go[2] = go[3] = b->nodes != 0;
    live = go[0] || go[2];
    for (level = 0; level < PT__GUIDE_MAX_DEPTH && live; ++level) {
        live = 0;
        for (k = 0; k < 4; ++k) {
            if (go[k]) {
                const pt__dnode *nd = t[k]->node + n[k];
                int q = pt__guide_quadrant(&x[k], &y[k]);
                p[k] *= 4.0f * nd->prob[q];
                n[k] = nd->child[q];
                go[k] = n[k] && p[k] > 0.0f;
                live |= go[k];
            }
        }
    }
    for (k = 0; k < 4; ++k) d[k] = p[k] > 0.0f ? p[k] : 0.0f;
}

/* Draws (x, y) from the sampling tree by warping (ux, uy) level by level (a column by its
   marginal, then the quadrant in it), so each level takes one bit of each number. */
static float pt__dtree_sample(const pt__dtree *t, float ux, float uy, double *x, double *y, double *cell)
{
    double ox = 0.0, oy = 0.0, size = 1.0;
    float d = 1.0f;
    uint32_t n = 0;
    int level;
    for (level = 0; t->nodes && level < PT__GUIDE_MAX_DEPTH; ++level) {
        const float *p = t->node[n].prob;
        float left = p[0] + p[2], right = p[1] + p[3], top, bottom;
        int bx, by;
        if (!(left + right > 0.0f)) break;
        bx = ux * (left + right) >= left;
        ux = bx ? (ux * (left + right) - left) / right : ux * (left + right) / left;
        top = p[bx];
        bottom = p[bx + 2];
        by = uy * (top + bottom) >= top;
        uy = by ? (uy * (top + bottom) - top) / bottom : uy * (top + bottom) / top;
        ux = pt__minf(pt__maxf(ux, 0.0f), 0.99999994f);
        uy = pt__minf(pt__maxf(uy, 0.0f), 0.99999994f);
        size *= 0.5;
        ox += (double)bx * size;
        oy += (double)by * size;
        d *= 4.0f * p[bx + 2 * by];
        n = t->node[n].child[bx + 2 * by];
        if (!n) break;
    }
    *x = ox + (double)ux * size;
    *y = oy + (double)uy * size;
    cell[0] = ox + 0.5 * size; /* its centre and size */
    cell[1] = oy + 0.5 * size;
    cell[2] = size;
    return d; /* the density over the square of the cell drawn */
}

static void pt__dtree_free(pt__dtree *t)
{
    PT_FREE(t->node);
    PT_FREE(t->child);
    PT_FREE(t->energy);
    memset(t, 0, sizeof *t);
}
/* Appends a node to a building tree (its quadrants leaves with zero sums) as *index; 0 when out
   of memory. */
static int pt__dtree_push(pt__dtree *t, uint32_t *index)
{
    uint32_t n;
    int q;
    if (t->nodes == t->cap) {
        uint32_t cap = t->cap ? 2u * t->cap : 4u;
        uint32_t *c = (uint32_t *)PT_REALLOC(t->child, sizeof(uint32_t) * 4u * cap);
        uint64_t *e;
        if (!c) return 0;
        t->child = c;
        e = (uint64_t *)PT_REALLOC(t->energy, sizeof(uint64_t) * 4u * cap);
        if (!e) return 0;
        t->energy = e;
        t->cap = cap;
    }
    n = t->nodes++;
    for (q = 0; q < 4; ++q) {
        t->child[4u * n + (uint32_t)q] = 0;
        t->energy[4u * n + (uint32_t)q] = 0;
    }
    *index = n;
    return 1;
}
/* A copy of a sampling tree. */
static int pt__dtree_copy(pt__dtree *dst, const pt__dtree *src)
{
    memset(dst, 0, sizeof *dst);
    if (!src->nodes) return 1;
    dst->node = (pt__dnode *)PT_MALLOC(sizeof(pt__dnode) * src->nodes);
    if (!dst->node) return 0;
    memcpy(dst->node, src->node, sizeof(pt__dnode) * src->nodes);
    dst->nodes = dst->cap = src->nodes;
    return 1;
}
static size_t pt__dtree_bytes(const pt__dtree *t)
{
    return (size_t)t->cap * (t->node ? sizeof(pt__dnode) : 0u) +
           (size_t)t->cap * 4u * ((t->child ? sizeof(uint32_t) : 0u) + (t->energy ? sizeof(uint64_t) : 0u));
}

/* The spatial leaf holding p (coordinates of the guide's box; outside: clamped into it). A node
   at depth d halves axis d mod 3 for the (d/3 + 1)-th time, so its side is bit 15 - d/3 of that
   axis's 16-bit cell index: p becomes a 48-bit Morton code (x, y, z bits interleaved) once, and
   the descent reads bit 47 - d, without a branch on the side. floor(c 2^16) keeps exactly the
   bits that halving c in float would compare (x 2 and 2c - 1 are exact). */
#define PT__GUIDE_JUMP_BITS 12
static uint64_t pt__guide_spread16(uint32_t v)
{
    uint64_t x = (uint64_t)(v & 0xffffu);
    x = (x | (x << 16)) & 0x0000ff0000ffULL;
    x = (x | (x << 8)) & 0x00f00f00f00fULL;
    x = (x | (x << 4)) & 0x0c30c30c30c3ULL;
    x = (x | (x << 2)) & 0x249249249249ULL;
    return x;
}
static uint32_t pt__guide_cell16(float c)
{
    if (!(c < 1.0f)) return 0xffffu; /* (NaN too: the float descent took the upper half) */
    return c > 0.0f ? (uint32_t)(c * 65536.0f) : 0u;
}
static uint32_t pt__guide_leaf_at(const pt_guide *g, pt_vec3 p)
{
    const uint64_t code = (pt__guide_spread16(pt__guide_cell16((p.x - g->lo.x) * g->inv_extent.x)) << 2) |
                          (pt__guide_spread16(pt__guide_cell16((p.y - g->lo.y) * g->inv_extent.y)) << 1) |
                          pt__guide_spread16(pt__guide_cell16((p.z - g->lo.z) * g->inv_extent.z));
    const pt__guide_node *nd = g->nodes + g->jump[code >> (48 - g->jump_bits)];
    while (nd->axis >= 0) nd = g->nodes + nd->child[(code >> (47 - nd->depth)) & 1u];
    return nd->child[0];
}
/* The jump table of the first jump_bits levels (a node at depth d splits on bit 47 - d of the
   code, so those levels read only its top bits): one load instead of a chain of them; remade
   whenever the spatial tree changes. */
static void pt__guide_jump_build(pt_guide *g)
{
    uint32_t i;
    for (i = 0; i < (1u << g->jump_bits); ++i) {
        const uint64_t code = (uint64_t)i << (48 - g->jump_bits);
        uint32_t n = 0;
        while (g->nodes[n].axis >= 0 && g->nodes[n].depth < g->jump_bits)
            n = g->nodes[n].child[(code >> (47 - g->nodes[n].depth)) & 1u];
        g->jump[i] = n;
    }
}
static pt_vec3 pt__guide_local(const pt_guide *g, pt_vec3 p) { return g->scene ? pt__to_local(g->scene, p) : p; }

static float pt__guide_value(const pt_guide *g, uint32_t leaf, pt_vec3 w)
{
    float x, y;
    if (!g || leaf >= g->leaf_count) return 0.0f;
    pt__guide_dir_to_square(w, &x, &y);
    return pt__dtree_density(&g->leaves[leaf].sampling, x, y) * PT__INV_4PI;
}
/* exact = 1: *p is pt_pdf_value of the direction as rounded, so that sample and value agree
   exactly (pt_pdf_sample); 0: the density of the cell it was drawn in, which differs only where
   rounding carries a direction across a cell's edge (the integrator's cheaper choice) */
static int pt__guide_sample(const pt_guide *g, uint32_t leaf, float u1, float u2, pt_vec3 *w, float *p, int exact)
{
    double x, y, cell[3];
    float d;
    int k;
    if (!g || leaf >= g->leaf_count) return 0;
    d = pt__dtree_sample(&g->leaves[leaf].sampling, u1, u2, &x, &y, cell);
    *w = pt__guide_square_to_dir(x, y); /* (unit to float precision) */
    if (!exact) {
        *p = d * PT__INV_4PI;
        return *p > 0.0f;
    }
    /* a point within a float rounding of its cell's edge can round into the neighbour, which may
       have no density: such a point moves a little toward its cell's centre (a change of the
       density within the cell far below what a chi-square can see) */
    for (k = 0; k < 4 && !((*p = pt__guide_value(g, leaf, *w)) > 0.0f); ++k) {
        x = cell[0] + 0.75 * (x - cell[0]);
        y = cell[1] + 0.75 * (y - cell[1]);
        *w = pt__guide_square_to_dir(x, y);
    }
    return *p > 0.0f;
}

/* The folded guide (pt_pdf_guide_hemisphere): fold n = 0 is the whole sphere. */
static pt_vec3 pt__guide_mirror(pt_vec3 w, pt_vec3 n) { return pt_sub(w, pt_scale(n, 2.0f * pt_dot(w, n))); }
/* The mirror of the square's point (x, y) through the plane of n, for an axis normal (z flips x;
   x and y turn phi), without a second atan2; 0 for another n. */
static int pt__guide_mirror_square(pt_vec3 n, float x, float y, float *mx, float *my)
{
    float m;
    if (n.x == 0.0f && n.y == 0.0f) {
        *mx = pt__minf(1.0f - x, 0.99999994f);
        *my = y;
        return 1;
    }
    if (!((n.y == 0.0f && n.z == 0.0f) || (n.x == 0.0f && n.z == 0.0f))) return 0;
    m = (n.x != 0.0f ? 0.5f : 1.0f) - y;
    *mx = x;
    *my = m < 0.0f ? m + 1.0f : (m >= 1.0f ? 0.0f : m);
    return 1;
}
/* The density over the square at (x, y) plus that at its mirror through the plane of n (w: the
   direction of (x, y), for a normal off the axes). */
static float pt__guide_fold_density(const pt__dtree *t, pt_vec3 n, pt_vec3 w, float x, float y)
{
    float mx, my, d, dm;
    if (!pt__guide_mirror_square(n, x, y, &mx, &my)) pt__guide_dir_to_square(pt__guide_mirror(w, n), &mx, &my);
    pt__dtree_density2(t, x, y, mx, my, &d, &dm);
    return d + dm;
}
static float pt__guide_value_fold(const pt_guide *g, uint32_t leaf, pt_vec3 n, pt_vec3 w)
{
    float c = pt_dot(w, n), x, y;
    if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) return pt__guide_value(g, leaf, w);
    if (!(c > 0.0f) || !g || leaf >= g->leaf_count) return 0.0f;
    pt__guide_dir_to_square(w, &x, &y);
    return pt__guide_fold_density(&g->leaves[leaf].sampling, n, w, x, y) * PT__INV_4PI;
}
/* A draw of the guide, mirrored above n if it fell below; *p: the folded density of the direction
   returned (exact: as pt__guide_sample's, the draw moved off a cell's edge first). */
static int pt__guide_sample_fold(const pt_guide *g, uint32_t leaf, pt_vec3 n, float u1, float u2, pt_vec3 *w, float *p,
                                 int exact)
{
    float c, d, mx, my;
    double x, y, cell[3];
    if (exact || (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f)) {
        if (!pt__guide_sample(g, leaf, u1, u2, w, p, exact)) return 0;
        if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) return 1;
        c = pt_dot(*w, n);
        if (c == 0.0f) return 0;
        if (c < 0.0f) *w = pt__guide_mirror(*w, n);
        *p = pt__guide_value_fold(g, leaf, n, *w);
        return *p > 0.0f;
    }
    /* the integrator's: the drawn cell's density plus its mirror's, from the square's point */
    if (!g || leaf >= g->leaf_count) return 0;
    d = pt__dtree_sample(&g->leaves[leaf].sampling, u1, u2, &x, &y, cell);
    *w = pt__guide_square_to_dir(x, y);
    c = pt_dot(*w, n);
    if (c == 0.0f) return 0;
    if (!pt__guide_mirror_square(n, (float)x, (float)y, &mx, &my)) pt__guide_dir_to_square(pt__guide_mirror(*w, n), &mx, &my);
    *p = (d + pt__dtree_density(&g->leaves[leaf].sampling, mx, my)) * PT__INV_4PI;
    if (c < 0.0f) *w = pt__guide_mirror(*w, n);
    return *p > 0.0f;
}

/* A record is spread over the directional cells that a square the size of its own cell overlaps,
   in proportion to the overlap (the directional box filter of Mueller, "Practical Path Guiding in
   Production", SIGGRAPH 2019 course notes), so that one record informs its neighbours too and a
   guide learned from few records is less spiky. (Its spatial filter, over the leaves a box the
   size of the record's leaf overlaps, cost more training time than it gained: docs/design.md.) */
static double pt__overlap(double a0, double a1, double b0, double b1)
{
    double lo = a0 > b0 ? a0 : b0, hi = a1 < b1 ? a1 : b1;
    return hi > lo ? hi - lo : 0.0;
}
/* Adds `density` units per unit area (of node n's square) over the box [x0,x1) x [y0,y1) of n's
   square, to the leaf quadrants below n it overlaps. */
static void pt__dtree_splat_box(pt_guide *g, pt__dtree *t, uint32_t n, double x0, double x1, double y0, double y1,
                                double density, int level)
{
    int q;
    for (q = 0; q < 4; ++q) {
        double qx = 0.5 * (double)(q & 1), qy = 0.5 * (double)(q >> 1);
        double a = pt__overlap(x0, x1, qx, qx + 0.5) * pt__overlap(y0, y1, qy, qy + 0.5) * density;
        uint32_t c = t->child[4u * n + (uint32_t)q];
        if (!(a >= 0.5)) continue; /* (below resolution) */
        if (c && level + 1 < PT__GUIDE_MAX_DEPTH)
            pt__dtree_splat_box(g, t, c, 2.0 * (x0 - qx), 2.0 * (x1 - qx), 2.0 * (y0 - qy), 2.0 * (y1 - qy),
                                density * 0.25, level + 1);
        else /* only leaf quadrants are added to (one contended add, not one per level); the inner
                sums are made at the update (pt__dtree_sum_up) */
            pt__guide_add(g, &t->energy[4u * n + (uint32_t)q], a >= (double)PT__GUIDE_CLAMP_UNITS ? PT__GUIDE_CLAMP_UNITS
                                                                                              : (uint64_t)(a + 0.5));
    }
}
/* units along w into one leaf's building tree, spread over a square the size of w's cell. */
static void pt__dtree_splat(pt_guide *g, pt__dtree *t, pt_vec3 w, double units)
{
    {
    float x, y, cx, cy;
    double s = 1.0, x0, x1, y0, y1, area;
    uint32_t n = 0;
    int level;
    pt__guide_dir_to_square(w, &x, &y);
    cx = x;
    cy = y;
    for (level = 0; level < PT__GUIDE_MAX_DEPTH; ++level) { /* the size of w's cell */
        int q = pt__guide_quadrant(&cx, &cy);
        s *= 0.5;
        n = t->child[4u * n + (uint32_t)q];
        if (!n) break;
    }
    x0 = (double)x - 0.5 * s;
    x1 = (double)x + 0.5 * s;
    if (x0 < 0.0) x0 = 0.0; /* (cos(theta) does not wrap) */
    if (x1 > 1.0) x1 = 1.0;
    y0 = (double)y - 0.5 * s;
    y1 = (double)y + 0.5 * s;
    area = (x1 - x0) * (y1 - y0);
    if (!(area > 0.0)) return;
    if (y0 < 0.0) { /* phi wraps around */
        pt__dtree_splat_box(g, t, 0, x0, x1, y0 + 1.0, 1.0, units / area, 0);
        y0 = 0.0;
    } else if (y1 > 1.0) {
        pt__dtree_splat_box(g, t, 0, x0, x1, 0.0, y1 - 1.0, units / area, 0);
        y1 = 1.0;
    }
    pt__dtree_splat_box(g, t, 0, x0, x1, y0, y1, units / area, 0);
    }
}
/* Adds `value` (>= 0) along w at p (local coordinates): into the leaf holding p, filtered over
   directions as above. */
static void pt__guide_splat(pt_guide *g, pt_vec3 p, pt_vec3 w, double value)
{
    pt__guide_leaf *l = &g->leaves[pt__guide_leaf_at(g, p)];
    double u = value / g->unit;
    pt__guide_add(g, &l->records, 1u);
    if (!(u >= 0.5)) return; /* zero, below resolution, or NaN */
    pt__dtree_splat(g, &l->building, w, u > (double)PT__GUIDE_CLAMP_UNITS ? (double)PT__GUIDE_CLAMP_UNITS : u);
}

/* The sampling tree of a building tree: the same topology, each node's sums normalised (a node
   whose sums are all zero is never reached by sampling: its parent's quadrant has none). */
static int pt__dtree_to_sampling(const pt__dtree *b, pt__dtree *out)
{
    uint32_t n;
    memset(out, 0, sizeof *out);
    out->node = (pt__dnode *)PT_MALLOC(sizeof(pt__dnode) * b->nodes);
    if (!out->node) return 0;
    for (n = 0; n < b->nodes; ++n) {
        const uint64_t *e = b->energy + 4u * n;
        double sum = (double)e[0] + (double)e[1] + (double)e[2] + (double)e[3];
        int q;
        for (q = 0; q < 4; ++q) {
            out->node[n].prob[q] = sum > 0.0 ? (float)((double)e[q] / sum) : 0.25f;
            out->node[n].child[q] = b->child[4u * n + (uint32_t)q];
        }
    }
    out->nodes = out->cap = b->nodes;
    return 1;
}

/* A fresh building tree for the next records: a quadrant is subdivided where the sampling tree
   gives it more than rho of the leaf's probability (a leaf quadrant's share is spread evenly over
   its four children), to max_directional_depth levels and while *budget (nodes) lasts. Mueller et
   al. 2017, section 3.3. */
typedef struct pt__refine_item { uint32_t s, b; int has_s, depth; float f; } pt__refine_item;
static int pt__dtree_refine(const pt_guide *g, const pt__dtree *s, pt__dtree *b, uint64_t *budget, int *at_bound)
{
    pt__refine_item stack[4 * PT__GUIDE_MAX_DEPTH + 4];
    int top = 0;
    uint32_t root;
    memset(b, 0, sizeof *b);
    if (!pt__dtree_push(b, &root)) return 0;
    stack[top].s = 0;
    stack[top].has_s = s->nodes > 0;
    stack[top].b = root;
    stack[top].depth = 1;
    stack[top].f = 1.0f;
    ++top;
    while (top > 0) {
        pt__refine_item it = stack[--top];
        int q;
        for (q = 0; q < 4; ++q) {
            float fq = it.f * (it.has_s ? s->node[it.s].prob[q] : 0.25f);
            uint32_t c;
            if (!(fq > g->desc.directional_threshold) || it.depth >= g->desc.max_directional_depth) continue;
            if (*budget == 0) { *at_bound = 1; continue; }
            if (!pt__dtree_push(b, &c)) return 0;
            --*budget;
            b->child[4u * it.b + (uint32_t)q] = c;
            stack[top].has_s = it.has_s && s->node[it.s].child[q] != 0;
            stack[top].s = stack[top].has_s ? s->node[it.s].child[q] : 0;
            stack[top].b = c;
            stack[top].depth = it.depth + 1;
            stack[top].f = fq;
            ++top;
        }
    }
    return 1;
}


/* Splits spatial node i (a leaf) in two at the middle of axis depth mod 3: both halves start
   from the leaf's sampling tree, each with half its records. 0 when out of memory. */
static int pt__guide_split(pt_guide *g, uint32_t i)
{
    uint32_t old = g->nodes[i].child[0], fresh = g->leaf_count;
    pt__guide_leaf *l;
    if (g->node_count + 2u > g->node_cap) {
        uint32_t cap = 2u * g->node_cap;
        pt__guide_node *nn = (pt__guide_node *)PT_REALLOC(g->nodes, sizeof *nn * cap);
        if (!nn) return 0;
        g->nodes = nn;
        g->node_cap = cap;
    }
    if (g->leaf_count + 1u > g->leaf_cap) {
        uint32_t cap = 2u * g->leaf_cap;
        pt__guide_leaf *nl = (pt__guide_leaf *)PT_REALLOC(g->leaves, sizeof *nl * cap);
        if (!nl) return 0;
        g->leaves = nl;
        g->leaf_cap = cap;
    }
    l = &g->leaves[fresh];
    memset(l, 0, sizeof *l);
    if (!pt__dtree_copy(&l->sampling, &g->leaves[old].sampling)) return 0;
    l->trained = g->leaves[old].trained;
    l->flux = g->leaves[old].flux;
    g->leaves[old].records /= 2u;
    l->records = g->leaves[old].records;
    g->leaf_count++;
    g->nodes[g->node_count].axis = -1;
    g->nodes[g->node_count].depth = g->nodes[i].depth + 1;
    g->nodes[g->node_count].child[0] = old;
    g->nodes[g->node_count].child[1] = 0;
    g->nodes[g->node_count + 1u] = g->nodes[g->node_count];
    g->nodes[g->node_count + 1u].child[0] = fresh;
    g->nodes[i].axis = g->nodes[i].depth % 3;
    g->nodes[i].child[0] = g->node_count;
    g->nodes[i].child[1] = g->node_count + 1u;
    g->node_count += 2u;
    return 1;
}

static uint64_t pt__guide_sampling_nodes(const pt_guide *g)
{
    uint64_t n = 0;
    uint32_t i;
    for (i = 0; i < g->leaf_count; ++i) n += g->leaves[i].sampling.nodes;
    return n;
}

/* The update (Mueller et al. 2017, section 3.4): every leaf's records become its sampling tree,
   leaves with many records split (spatial_threshold x sqrt(2^updates), recursively, halving the
   count each time), then every leaf gets a fresh building tree refined from its sampling tree.
   Sequential, in node order: the result depends only on the sums. */
/* An inner quadrant's sum is its child's four (children come after their parents). */
static void pt__dtree_sum_up(pt__dtree *t)
{
    uint32_t n = 4u * t->nodes;
    while (n-- > 0) {
        uint32_t c = t->child[n];
        if (c) t->energy[n] = t->energy[4u * c] + t->energy[4u * c + 1u] + t->energy[4u * c + 2u] + t->energy[4u * c + 3u];
    }
}

static int pt__guide_update(pt_guide *g)
{
    uint32_t i;
    uint64_t budget;
    double threshold = (double)g->desc.spatial_threshold * sqrt(pow(2.0, (double)g->updates));
    g->at_bound = 0;
    for (i = 0; i < g->leaf_count; ++i) {
        pt__guide_leaf *l = &g->leaves[i];
        const uint64_t *e = l->building.energy;
        if (l->building.nodes) pt__dtree_sum_up(&l->building);
        if (l->building.nodes && e[0] + e[1] + e[2] + e[3] > 0u) {
            pt__dtree s;
            if (!pt__dtree_to_sampling(&l->building, &s)) return PT_ERROR_OUT_OF_MEMORY;
            pt__dtree_free(&l->sampling);
            l->sampling = s;
            l->trained = 1;
        }
        if (l->records) l->flux = (float)((double)(e[0] + e[1] + e[2] + e[3]) * g->unit / (double)l->records);
    }
    for (i = 0; i < g->node_count; ++i) { /* (nodes appended by a split are visited too) */
        uint32_t leaf;
        if (g->nodes[i].axis >= 0) continue;
        leaf = g->nodes[i].child[0];
        if (!((double)g->leaves[leaf].records > threshold) || g->nodes[i].depth >= PT__GUIDE_SPATIAL_MAX_DEPTH)
            continue;
        if (2u * (pt__guide_sampling_nodes(g) + g->leaves[leaf].sampling.nodes + 1u) > g->max_nodes) {
            g->at_bound = 1;
            continue;
        }
        if (!pt__guide_split(g, i)) return PT_ERROR_OUT_OF_MEMORY;
    }
    {
        uint64_t used = pt__guide_sampling_nodes(g);
        budget = g->max_nodes > used + g->leaf_count ? g->max_nodes - used - g->leaf_count : 0u;
    }
    for (i = 0; i < g->leaf_count; ++i) {
        pt__guide_leaf *l = &g->leaves[i];
        pt__dtree_free(&l->building);
        if (!pt__dtree_refine(g, &l->sampling, &l->building, &budget, &g->at_bound)) return PT_ERROR_OUT_OF_MEMORY;
        l->records = 0;
    }
    pt__guide_jump_build(g);
    g->updates++;
    return PT_OK;
}

static int pt__guide_make(const pt_guide_desc *d, pt_vec3 lo, pt_vec3 hi, const pt_scene *scene, pt_guide **out)
{
    pt_guide *g;
    pt_guide_desc r;
    uint64_t budget;
    int at = 0;
    memset(&r, 0, sizeof r);
    if (d) r = *d;
    if (!r.max_bytes) r.max_bytes = (size_t)64 << 20;
    if (r.spatial_threshold == 0.0f) r.spatial_threshold = 12000.0f;
    if (r.directional_threshold == 0.0f) r.directional_threshold = 0.01f;
    if (!r.max_directional_depth) r.max_directional_depth = PT__GUIDE_MAX_DEPTH;
    if (r.value_resolution == 0.0f) r.value_resolution = 1.0f / 16777216.0f;
    if (r.max_bytes < 4096u || !pt__isfinite(r.spatial_threshold) || !(r.spatial_threshold >= 1.0f) ||
        !(r.directional_threshold > 0.0f && r.directional_threshold < 1.0f) || r.max_directional_depth < 1 ||
        r.max_directional_depth > PT__GUIDE_MAX_DEPTH || !pt__isfinite(r.value_resolution) ||
        !(r.value_resolution > 0.0f))
        return PT_ERROR_INVALID_ARGUMENT;
    g = (pt_guide *)PT_MALLOC(sizeof *g);
    if (!g) return PT_ERROR_OUT_OF_MEMORY;
    memset(g, 0, sizeof *g);
    g->desc = r;
    g->lo = lo;
    g->hi = hi;
    g->inv_extent = pt_v3(1.0f / (hi.x - lo.x), 1.0f / (hi.y - lo.y), 1.0f / (hi.z - lo.z));
    g->scene = scene;
    g->unit = (double)r.value_resolution;
    /* a directional node costs 4 child indices and 4 probabilities (sampling) or 4 sums (building) */
    g->max_nodes = (uint64_t)(r.max_bytes / (4u * (2u * sizeof(uint32_t) + sizeof(float) + sizeof(uint64_t))));
    g->node_cap = g->leaf_cap = 16;
    g->nodes = (pt__guide_node *)PT_MALLOC(sizeof(pt__guide_node) * g->node_cap);
    g->leaves = (pt__guide_leaf *)PT_MALLOC(sizeof(pt__guide_leaf) * g->leaf_cap);
    if (!g->nodes || !g->leaves) { pt_guide_destroy(g); return PT_ERROR_OUT_OF_MEMORY; }
    g->node_count = g->leaf_count = 1;
    g->nodes[0].axis = -1;
    g->nodes[0].depth = 0;
    g->nodes[0].child[0] = g->nodes[0].child[1] = 0;
    g->jump_bits = r.max_bytes >= ((size_t)1 << 20) ? PT__GUIDE_JUMP_BITS : 0; /* (16 KiB) */
    g->jump = (uint32_t *)PT_MALLOC(sizeof(uint32_t) << g->jump_bits);
    if (!g->jump) { pt_guide_destroy(g); return PT_ERROR_OUT_OF_MEMORY; }
    pt__guide_jump_build(g);
    memset(&g->leaves[0], 0, sizeof g->leaves[0]);
#if !defined(PDFTRACE_NO_THREADS) && !defined(__GNUC__) && !defined(__clang__)
    pthread_mutex_init(&g->lock, NULL);
#endif
    budget = g->max_nodes;
    if (!pt__dtree_refine(g, &g->leaves[0].sampling, &g->leaves[0].building, &budget, &at)) {
        pt_guide_destroy(g);
        return PT_ERROR_OUT_OF_MEMORY;
    }
    *out = g;
    return PT_OK;
}

PTDEF int pt_guide_create(const pt_guide_desc *d, pt_guide **out)
{
    if (out) *out = NULL;
    if (!d || !out || !pt__vfinite(d->bounds_min) || !pt__vfinite(d->bounds_max) ||
        !(d->bounds_max.x > d->bounds_min.x && d->bounds_max.y > d->bounds_min.y && d->bounds_max.z > d->bounds_min.z))
        return PT_ERROR_INVALID_ARGUMENT;
    return pt__guide_make(d, d->bounds_min, d->bounds_max, NULL, out);
}

PTDEF int pt_guide_create_for_scene(const pt_scene *s, const pt_guide_desc *d, pt_guide **out)
{
    pt_vec3 lo, hi, pad;
    if (out) *out = NULL;
    if (!s || !out || !s->committed) return !s || !out ? PT_ERROR_INVALID_ARGUMENT : PT_ERROR_INVALID_STATE;
    lo = s->lo;
    hi = s->hi;
    if (!pt__vfinite(lo) || !pt__vfinite(hi) || !(hi.x >= lo.x && hi.y >= lo.y && hi.z >= lo.z)) {
        lo = pt_v3(-1, -1, -1); /* no shapes */
        hi = pt_v3(1, 1, 1);
    }
    /* a flat scene still gets a box: each side at least 1e-3 of the largest */
    pad = pt_scale(pt_v3(1, 1, 1), 1e-3f * pt__maxf(1e-3f, pt_max_component(pt_sub(hi, lo))));
    lo = pt_sub(lo, pad);
    hi = pt_add(hi, pad);
    return pt__guide_make(d, lo, hi, s, out);
}

PTDEF void pt_guide_destroy(pt_guide *g)
{
    uint32_t i;
    if (!g) return;
    pt_guide_destroy(g->caustic);
    for (i = 0; g->leaves && i < g->leaf_count; ++i) {
        pt__dtree_free(&g->leaves[i].sampling);
        pt__dtree_free(&g->leaves[i].building);
    }
#if !defined(PDFTRACE_NO_THREADS) && !defined(__GNUC__) && !defined(__clang__)
    pthread_mutex_destroy(&g->lock);
#endif
    PT_FREE(g->nodes);
    PT_FREE(g->jump);
    PT_FREE(g->leaves);
    PT_FREE(g);
}

PTDEF const pt_guide *pt_guide_caustic(const pt_guide *g) { return g ? g->caustic : NULL; }

PTDEF int pt_guide_record(pt_guide *g, pt_vec3 point, pt_vec3 dir, float value)
{
    if (!g || !pt__vfinite(point) || !pt__vfinite(dir) || !(fabsf(pt_length2(dir) - 1.0f) <= 1e-3f) ||
        !pt__isfinite(value) || value < 0.0f)
        return PT_ERROR_INVALID_ARGUMENT;
    pt__guide_splat(g, pt__guide_local(g, point), dir, (double)value);
    return PT_OK;
}

PTDEF int pt_guide_update(pt_guide *g)
{
    return g ? pt__guide_update(g) : PT_ERROR_INVALID_ARGUMENT;
}

PTDEF int pt_guide_get_info(const pt_guide *g, pt_guide_info *info)
{
    uint32_t i;
    if (!g || !info) return PT_ERROR_INVALID_ARGUMENT;
    memset(info, 0, sizeof *info);
    info->updates = g->updates;
    info->spatial_leaves = g->leaf_count;
    info->max_bytes = g->desc.max_bytes;
    info->at_memory_bound = g->at_bound;
    info->bytes = sizeof *g + sizeof(pt__guide_node) * g->node_cap + sizeof(pt__guide_leaf) * g->leaf_cap +
                  (sizeof(uint32_t) << g->jump_bits);
    for (i = 0; i < g->node_count; ++i)
        if ((uint32_t)g->nodes[i].depth > info->spatial_depth) info->spatial_depth = (uint32_t)g->nodes[i].depth;
    for (i = 0; i < g->leaf_count; ++i) {
        const pt__guide_leaf *l = &g->leaves[i];
        info->directional_nodes += l->sampling.nodes + l->building.nodes;
        info->bytes += pt__dtree_bytes(&l->sampling) + pt__dtree_bytes(&l->building);
        info->records += l->records;
    }
    return PT_OK;
}

PTDEF pt_pdf pt_pdf_guide(const pt_guide *g, pt_vec3 point)
{
    pt_pdf p = pt__pdf_blank(PT_PDF_GUIDE);
    p.origin = point;
    p.as.guide.guide = g;
    p.as.guide.leaf = g && pt__vfinite(point) ? pt__guide_leaf_at(g, pt__guide_local(g, point)) : 0u;
    p.as.guide.fold = pt_v3(0, 0, 0);
    return p;
}
PTDEF pt_pdf pt_pdf_guide_hemisphere(const pt_guide *g, pt_vec3 point, pt_vec3 n)
{
    pt_pdf p = pt_pdf_guide(g, point);
    if (!pt__vfinite(n) || !(pt_length2(n) > 0.0f)) p.as.guide.guide = NULL; /* (no density) */
    else p.as.guide.fold = pt_normalize(n);
    return p;
}

PTDEF int pt_guide_image(const pt_guide *g, pt_vec3 point, int width, int height, pt_image *image)
{
    int x, y, rc;
    uint32_t leaf;
    if (!g || !image || !pt__vfinite(point) || width <= 0 || height <= 0) return PT_ERROR_INVALID_ARGUMENT;
    if (!image->rgb || image->width != width || image->height != height) {
        pt_image_free(image);
        if ((rc = pt_image_init(image, width, height)) != PT_OK) return rc;
    }
    leaf = pt__guide_leaf_at(g, pt__guide_local(g, point));
    for (y = 0; y < height; ++y)
        for (x = 0; x < width; ++x) {
            float theta = PT__PI * ((float)y + 0.5f) / (float)height, phi = 2.0f * PT__PI * ((float)x + 0.5f) / (float)width;
            pt_vec3 w = pt_v3(sinf(theta) * cosf(phi), sinf(theta) * sinf(phi), cosf(theta));
            float v = pt__guide_value(g, leaf, w);
            float *px = image->rgb + 3u * ((size_t)y * (size_t)width + (size_t)x);
            px[0] = px[1] = px[2] = v;
        }
    return PT_OK;
}

static int pt__pdf_validate_depth(const pt_pdf *pdf, int depth)
{
    if (!pdf || depth > 32) return PT_ERROR_INVALID_ARGUMENT;
    switch (pdf->type) {
    case PT_PDF_UNIFORM_SPHERE: return PT_OK;
    case PT_PDF_COSINE_HEMISPHERE:
        return pt__vfinite(pdf->as.cosine.basis.n) && pt_length2(pdf->as.cosine.basis.n) > 0.5f ? PT_OK
                                                                                                 : PT_ERROR_INVALID_ARGUMENT;
    case PT_PDF_SPHERE_LIGHT:
        return pt__vfinite(pdf->origin) && pt__vfinite(pdf->as.sphere.center) && pt__isfinite(pdf->as.sphere.radius) &&
                       pdf->as.sphere.radius > 0.0f
                   ? PT_OK
                   : PT_ERROR_INVALID_ARGUMENT;
    case PT_PDF_QUAD_LIGHT:
        return pt__vfinite(pdf->origin) && pt__vfinite(pdf->as.quad.q) && pt__vfinite(pdf->as.quad.u) &&
                       pt__vfinite(pdf->as.quad.v) && pt_length2(pt_cross(pdf->as.quad.u, pdf->as.quad.v)) > 0.0f
                   ? PT_OK
                   : PT_ERROR_INVALID_ARGUMENT;
    case PT_PDF_TRIANGLE_LIGHT:
        return pt__vfinite(pdf->origin) && pt__vfinite(pdf->as.triangle.a) && pt__vfinite(pdf->as.triangle.b) &&
                       pt__vfinite(pdf->as.triangle.c) &&
                       pt_length2(pt_cross(pt_sub(pdf->as.triangle.b, pdf->as.triangle.a),
                                           pt_sub(pdf->as.triangle.c, pdf->as.triangle.a))) > 0.0f
                   ? PT_OK
                   : PT_ERROR_INVALID_ARGUMENT;
    case PT_PDF_SCENE_LIGHTS:
        return pdf->as.lights.scene && pdf->as.lights.scene->committed && pt__vfinite(pdf->origin)
                   ? PT_OK
                   : PT_ERROR_INVALID_ARGUMENT;
    case PT_PDF_MATERIAL: {
        const pt_scene *s = pdf->as.material.scene;
        if (!s || pdf->as.material.material < 0 || (uint32_t)pdf->as.material.material >= s->mat_count)
            return PT_ERROR_INVALID_ARGUMENT;
        return pt__vfinite(pdf->as.material.normal) && pt__vfinite(pdf->as.material.wo) ? PT_OK
                                                                                        : PT_ERROR_INVALID_ARGUMENT;
    }
    case PT_PDF_MIXTURE: {
        int k;
        double sum = 0.0;
        if (pdf->as.mixture.count <= 0 || !pdf->as.mixture.components || !pdf->as.mixture.weights)
            return PT_ERROR_INVALID_ARGUMENT;
        for (k = 0; k < pdf->as.mixture.count; ++k) {
            float w = pdf->as.mixture.weights[k];
            if (!pt__isfinite(w) || w < 0.0f) return PT_ERROR_INVALID_ARGUMENT;
            sum += w;
            if (pt__pdf_validate_depth(&pdf->as.mixture.components[k], depth + 1) != PT_OK)
                return PT_ERROR_INVALID_ARGUMENT;
        }
        return fabs(sum - 1.0) <= 1e-4 ? PT_OK : PT_ERROR_INVALID_ARGUMENT;
    }
    case PT_PDF_CALLBACK:
        return pdf->as.callback.sample && pdf->as.callback.value ? PT_OK : PT_ERROR_INVALID_ARGUMENT;
    case PT_PDF_GUIDE:
        return pdf->as.guide.guide && pdf->as.guide.leaf < pdf->as.guide.guide->leaf_count ? PT_OK
                                                                                            : PT_ERROR_INVALID_ARGUMENT;
    case PT_PDF_ENVIRONMENT:
        return pdf->as.environment.scene && pdf->as.environment.scene->committed &&
                       pt__color_ok(pdf->as.environment.background)
                   ? PT_OK
                   : PT_ERROR_INVALID_ARGUMENT;
    default: return PT_ERROR_INVALID_ARGUMENT;
    }
}
PTDEF int pt_pdf_validate(const pt_pdf *pdf) { return pt__pdf_validate_depth(pdf, 0); }

/* Mixtures nest; a cyclic or absurdly deep one (misuse) yields no density instead of
   unbounded recursion. */
#define PT__PDF_MAX_DEPTH 32
static float pt__pdf_value_depth(const pt_pdf *pdf, pt_vec3 w, int depth);
static int pt__pdf_sample_depth(const pt_pdf *pdf, pt_rng *rng, pt_vec3 *dir, float *pdf_value, int depth, int exact);
PTDEF float pt_pdf_value(const pt_pdf *pdf, pt_vec3 w) { return pt__pdf_value_depth(pdf, w, 0); }
PTDEF int pt_pdf_sample(const pt_pdf *pdf, pt_rng *rng, pt_vec3 *dir, float *pdf_value)
{
    return pt__pdf_sample_depth(pdf, rng, dir, pdf_value, 0, 0);
}
static float pt__pdf_value_depth(const pt_pdf *pdf, pt_vec3 w, int depth)
{
    float v = 0.0f;
    if (!pdf || depth > PT__PDF_MAX_DEPTH) return 0.0f;
    switch (pdf->type) {
    case PT_PDF_UNIFORM_SPHERE: v = PT__INV_4PI; break;
    case PT_PDF_COSINE_HEMISPHERE: v = pt__maxf(0.0f, pt_dot(w, pdf->as.cosine.basis.n)) * PT__INV_PI; break;
    case PT_PDF_SPHERE_LIGHT:
        v = pt__sphere_light_value(pdf->origin, pdf->as.sphere.center, pdf->as.sphere.radius, pdf->as.sphere.two_sided,
                                   w);
        break;
    case PT_PDF_QUAD_LIGHT:
    case PT_PDF_TRIANGLE_LIGHT: {
        pt__prim prim;
        float area;
        int two;
        if (pt__pdf_planar(pdf, &prim, &area, &two)) v = pt__planar_light_value(&prim, area, two, pdf->origin, w, 1);
        break;
    }
    case PT_PDF_SCENE_LIGHTS:
        if (pdf->as.lights.scene && pdf->as.lights.scene->committed)
            v = pt__lights_value(pdf->as.lights.scene, pt__to_local(pdf->as.lights.scene, pdf->origin),
                                 pdf->as.lights.normal, w, PT__LIGHTS_SPHERICAL | PT__LIGHTS_TREE);
        break;
    case PT_PDF_MATERIAL:
        if (pdf->as.material.scene && pdf->as.material.material >= 0 &&
            (uint32_t)pdf->as.material.material < pdf->as.material.scene->mat_count)
            v = pt__material_pdf_value(pdf->as.material.scene, pdf->as.material.material, pdf->as.material.normal,
                                       pdf->as.material.wo, w);
        break;
    case PT_PDF_MIXTURE: {
        int k;
        float wsum = 0.0f;
        if (!pdf->as.mixture.components || !pdf->as.mixture.weights) break;
        for (k = 0; k < pdf->as.mixture.count; ++k)
            if (pdf->as.mixture.weights[k] > 0.0f) {
                wsum += pdf->as.mixture.weights[k];
                v += pdf->as.mixture.weights[k] * pt__pdf_value_depth(&pdf->as.mixture.components[k], w, depth + 1);
            }
        v = wsum > 0.0f ? v / wsum : 0.0f; /* unnormalised weights (see pt_pdf_mixture) */
        break;
    }
    case PT_PDF_CALLBACK:
        if (pdf->as.callback.value) v = pdf->as.callback.value(pdf->as.callback.user, w);
        break;
    case PT_PDF_GUIDE: v = pt__guide_value_fold(pdf->as.guide.guide, pdf->as.guide.leaf, pdf->as.guide.fold, w); break;
    case PT_PDF_ENVIRONMENT: {
        const pt__env *e;
        float c;
        if (pt__pdf_env(pdf, &e, &c)) v = pt__env_density(e, c, w);
        break;
    }
    default: break;
    }
    return pt__isfinite(v) && v > 0.0f ? v : 0.0f;
}

/* exact = 1: only directions whose pt_pdf_value is the returned density (see PT_PDF_SPHERE_LIGHT) */
static int pt__pdf_sample_depth(const pt_pdf *pdf, pt_rng *rng, pt_vec3 *dir, float *pdf_value, int depth, int exact)
{
    pt_vec3 w = pt_v3(0, 0, 0);
    float p = 0.0f;
    int ok = 0;
    pt__light_sample ls;
    if (dir) *dir = w;
    if (pdf_value) *pdf_value = 0.0f;
    if (!pdf || !rng || !dir || !pdf_value || depth > PT__PDF_MAX_DEPTH) return 0;
    switch (pdf->type) {
    case PT_PDF_UNIFORM_SPHERE: {
        float u1 = pt_rng_float(rng), u2 = pt_rng_float(rng);
        w = pt_sample_uniform_sphere(u1, u2);
        p = PT__INV_4PI;
        ok = 1;
        break;
    }
    case PT_PDF_COSINE_HEMISPHERE: {
        float u1 = pt_rng_float(rng), u2 = pt_rng_float(rng);
        pt_vec3 l = pt_sample_cosine_hemisphere(u1, u2);
        w = pt_normalize(pt_onb_to_world(&pdf->as.cosine.basis, l));
        p = pt__maxf(0.0f, pt_dot(w, pdf->as.cosine.basis.n)) * PT__INV_PI;
        ok = p > 0.0f;
        break;
    }
    case PT_PDF_SPHERE_LIGHT: {
        float u1 = pt_rng_float(rng), u2 = pt_rng_float(rng);
        ok = pt__sphere_light_sample(pdf->origin, pdf->as.sphere.center, pdf->as.sphere.radius,
                                     pdf->as.sphere.two_sided, u1, u2, &ls);
        /* a rounded direction (a sphere below float's angular resolution) has density 0 for
           pt_pdf_value: returned alone, refused inside a mixture, whose density must be the
           sum of its components' values */
        if (ok && ls.rounded && exact) ok = 0;
        w = ls.dir; p = ls.pdf;
        break;
    }
    case PT_PDF_QUAD_LIGHT:
    case PT_PDF_TRIANGLE_LIGHT: {
        float u1 = pt_rng_float(rng), u2 = pt_rng_float(rng), area;
        pt__prim prim;
        int two;
        ok = pt__pdf_planar(pdf, &prim, &area, &two) && pt__planar_light_sample(&prim, area, two, pdf->origin, u1, u2, &ls, 1);
        w = ls.dir; p = ls.pdf;
        break;
    }
    case PT_PDF_SCENE_LIGHTS: {
        float u0 = pt_rng_float(rng), u1 = pt_rng_float(rng), u2 = pt_rng_float(rng);
        uint32_t li;
        pt_vec3 o;
        if (!pdf->as.lights.scene || !pdf->as.lights.scene->committed) break;
        o = pt__to_local(pdf->as.lights.scene, pdf->origin);
        ok = pt__lights_sample(pdf->as.lights.scene, o, pdf->as.lights.normal, u0, u1, u2, &ls, &li,
                               PT__LIGHTS_SPHERICAL | PT__LIGHTS_TREE);
        if (ok) {
            w = ls.dir;
            /* the density of the direction over all lights, not the picked one's alone */
            p = pt__lights_value(pdf->as.lights.scene, o, pdf->as.lights.normal, w, PT__LIGHTS_SPHERICAL | PT__LIGHTS_TREE);
            ok = p > 0.0f;
        }
        break;
    }
    case PT_PDF_ENVIRONMENT: {
        float u1 = pt_rng_float(rng), u2 = pt_rng_float(rng), c;
        const pt__env *e;
        ok = pt__pdf_env(pdf, &e, &c) && pt__env_sample(e, c, u1, u2, &w, &p, NULL);
        break;
    }
    case PT_PDF_MATERIAL: {
        float u1 = pt_rng_float(rng), u2 = pt_rng_float(rng), u3 = pt_rng_float(rng);
        const pt_scene *s = pdf->as.material.scene;
        if (!s || pdf->as.material.material < 0 || (uint32_t)pdf->as.material.material >= s->mat_count) break;
        ok = pt__material_pdf_sample(s, pdf->as.material.material, pdf->as.material.normal, pdf->as.material.wo, u1,
                                     u2, u3, &w, &p);
        break;
    }
    case PT_PDF_MIXTURE: {
        int k, n = pdf->as.mixture.count, chosen = -1;
        float u = pt_rng_float(rng), acc = 0.0f, pk = 0.0f, wsum = 0.0f;
        if (n <= 0 || !pdf->as.mixture.components || !pdf->as.mixture.weights) break;
        for (k = 0; k < n; ++k)
            if (pdf->as.mixture.weights[k] > 0.0f) wsum += pdf->as.mixture.weights[k];
        if (!(wsum > 0.0f) || !pt__isfinite(wsum)) break;
        u *= wsum; /* select in proportion to the positive weights, whatever their sum */
        for (k = 0; k < n; ++k) {
            float wk = pdf->as.mixture.weights[k];
            if (!(wk > 0.0f)) continue;
            chosen = k;          /* the last positive-weight component absorbs rounding */
            acc += wk;
            if (u < acc) break;
        }
        if (chosen < 0) break;
        if (!pt__pdf_sample_depth(&pdf->as.mixture.components[chosen], rng, &w, &pk, depth + 1, 1)) break;
        /* density of the mixture: sum over every component, the chosen one included */
        p = 0.0f;
        for (k = 0; k < n; ++k) {
            float wk = pdf->as.mixture.weights[k];
            if (!(wk > 0.0f)) continue;
            p += wk * (k == chosen ? pk : pt__pdf_value_depth(&pdf->as.mixture.components[k], w, depth + 1));
        }
        p /= wsum;
        ok = p > 0.0f;
        break;
    }
    case PT_PDF_CALLBACK:
        if (pdf->as.callback.sample) ok = pdf->as.callback.sample(pdf->as.callback.user, rng, &w, &p) ? 1 : 0;
        break;
    case PT_PDF_GUIDE: {
        float u1 = pt_rng_float(rng), u2 = pt_rng_float(rng);
        ok = pt__guide_sample_fold(pdf->as.guide.guide, pdf->as.guide.leaf, pdf->as.guide.fold, u1, u2, &w, &p, 1);
        break;
    }
    default: break;
    }
    if (!ok || !pt__vfinite(w) || !pt__isfinite(p) || !(p > 0.0f)) return 0;
    *dir = w;
    *pdf_value = p;
    return 1;
}

/* ------------------------------------------------------------------------------------------
   3. Geometry and scenes: ray/primitive intersections, hit records and building a scene.
   Spheres after Haines et al. (Ray Tracing Gems ch. 7, 2019), with a double-precision path for
   tiny or distant ones; parallelograms by their plane coordinates (Shirley, "Ray Tracing: The
   Next Week") with a rounding margin at the edges so that boxes stay closed; triangles by the
   watertight test of Woop, Benthin & Wald (JCGT 2(1), 2013). A hit point is re-computed on the
   primitive (not o + t d, whose error grows with the distance) and carries the magnitude of its
   rounding error for the ray offset of section 1. Shapes are added under the scene's current
   transform, baked into their world-space coordinates, and validated so that every later
   product of coordinates stays finite.
   ------------------------------------------------------------------------------------------ */

/* need_triangles = 0 skips the shear set-up in scenes without triangles. */
static PT__HOT void pt__rayctx_init2(pt__rayctx *rc, pt_ray r, int need_triangles)
{
    float ax, ay, az, dk;
    rc->o = r.origin;
    rc->d = r.dir;
    rc->triangles = need_triangles;
    if (!need_triangles) { rc->kx = 0; rc->ky = 1; rc->kz = 2; rc->sx = rc->sy = rc->sz = 0.0f; return; }
    ax = fabsf(r.dir.x); ay = fabsf(r.dir.y); az = fabsf(r.dir.z);
    /* Woop, Benthin & Wald 2013: kz = dominant axis, kx/ky follow cyclically (swapped to keep
       the winding when dir[kz] < 0). Chosen by selects and indexing rather than branches, which a
       random direction would mispredict: kz = (ax > ay) ? (ax > az ? 0 : 2) : (ay > az ? 1 : 2). */
    {
        static const int next[3] = {1, 2, 0};
        const float dv[3] = {r.dir.x, r.dir.y, r.dir.z};
        const int xy = ax > ay, big = (xy ? ax : ay) > az, kz = 2 - big * (1 + xy);
        const int kx = next[kz], ky = next[kx], swap = -(int)(dv[kz] < 0.0f);
        rc->kz = kz;
        rc->kx = kx ^ ((kx ^ ky) & swap);
        rc->ky = ky ^ ((kx ^ ky) & swap);
        dk = dv[kz];
        if (dk == 0.0f) dk = FLT_MIN; /* zero direction: nothing is hit, but stay finite */
        rc->sx = dv[rc->kx] / dk;
        rc->sy = dv[rc->ky] / dk;
    }
    rc->sz = 1.0f / dk;
}
static void pt__rayctx_init(pt__rayctx *rc, pt_ray r) { pt__rayctx_init2(rc, r, 1); }

/* Haines, Guenther & Akenine-Moeller, "Precision Improvements for Ray/Sphere Intersection",
   Ray Tracing Gems ch. 7: the discriminant from (r - |l|)(r + |l|) with l the part of
   f = o - c perpendicular to the ray, and the stable root pair q/a, c/q. */
static PT__HOT int pt__hit_sphere(const pt__rayctx *rc, pt_vec3 c, float r, float tmax, float *t_out)
{
    pt_vec3 f = pt_sub(rc->o, c);
    float a = pt_dot(rc->d, rc->d), bp = -pt_dot(f, rc->d), cc, disc, q, t0, t1, ll;
    pt_vec3 l;
    if (!(a > 0.0f)) return 0;
    if (r * r < 1e-6f * pt_dot(f, f)) {
        /* Tiny or distant (r < 1e-3 |o - c|): the float o - c alone is off by 2^-24 |o - c|,
           6% of a sphere 1e-6 away as far, enough for rays aimed at a tiny sphere light to
           miss it (docs/internals.md, "Tiny and distant spheres"). In double, from the exact
           o - c, with the perpendicular distance by the cross product as in pt__in_cone. */
        double fx = (double)rc->o.x - c.x, fy = (double)rc->o.y - c.y, fz = (double)rc->o.z - c.z;
        double dx = rc->d.x, dy = rc->d.y, dz = rc->d.z, dd = dx * dx + dy * dy + dz * dz;
        double xx = dy * fz - dz * fy, yy = dz * fx - dx * fz, zz = dx * fy - dy * fx;
        double b = -(fx * dx + fy * dy + fz * dz), h2 = (double)r * r * dd - (xx * xx + yy * yy + zz * zz);
        double tm;
        if (h2 < 0.0 || b <= 0.0) return 0; /* missed, or the sphere is behind (o is outside it) */
        /* the near root (b - sqrt(h2)) / dd as (|f|^2 - r^2) / (b + sqrt(h2)): no cancellation */
        tm = (fx * fx + fy * fy + fz * fz - (double)r * r) / (b + sqrt(h2));
        if (!(tm > 0.0 && tm < (double)tmax)) return 0;
        *t_out = (float)tm;
        return *t_out > 0.0f;
    }
    l = pt_add(f, pt_scale(rc->d, bp / a));
    ll = pt_length(l);
    disc = a * (r - ll) * (r + ll);
    if (disc < 0.0f) return 0;
    cc = pt_dot(f, f) - r * r;
    q = bp + copysignf(sqrtf(disc), bp);
    if (q == 0.0f) return 0;
    t0 = cc / q;
    t1 = q / a;
    if (t0 > t1) { float tmp = t0; t0 = t1; t1 = tmp; }
    if (t0 > 0.0f && t0 < tmax) { *t_out = t0; return 1; }
    if (t1 > 0.0f && t1 < tmax) { *t_out = t1; return 1; }
    return 0;
}

/* How far beyond its edges (in space) pt__hit_quad may accept a point: 2^-20 of the quad's
   coordinates. The a, b margin below is capped by it (a sliver quad's a, b are so
   ill-conditioned that its rounding bound would cover its whole plane), and pt__prim_bounds
   pads quads by twice it, so the BVH never culls what the test accepts. */
static float pt__quad_margin(const pt__prim *p)
{
    return 9.5367431640625e-7f * (pt__vmaxabs(p->p0) + pt__vmaxabs(p->p1) + pt__vmaxabs(p->p2));
}
/* The caps of pt__hit_quad's a and b margins (its ta, tb are never larger): a point with a or b
   beyond them is a miss whatever the ray. Stored per quad in the BVH's quad blocks, so that
   the SIMD test sends only lanes within them to the scalar test. */
static void pt__quad_edge_caps(const pt__prim *p, float *ta, float *tb)
{
    *ta = pt__quad_margin(p) * 0.57735f / pt__vmaxabs(p->p1);
    *tb = pt__quad_margin(p) * 0.57735f / pt__vmaxabs(p->p2);
}

/* Parallelogram Q + a u + b v: plane hit, then plane coordinates a = w.(h x v), b = w.(u x h)
   with w = n'/(n'.n'), h = hit - Q (Shirley, "Ray Tracing: The Next Week", sec. 6), as
   a = h.(v x w), b = h.(w x u) with both vectors precomputed. */
static PT__HOT int pt__hit_quad(const pt__rayctx *rc, const pt__prim *p, float tmax, float *t_out)
{
    float denom = pt_dot(p->n, rc->d), t, a, b;
    pt_vec3 h;
    if (denom == 0.0f) return 0;
    t = pt_dot(p->n, pt_sub(p->p0, rc->o)) / denom;
    if (!(t > 0.0f && t < tmax)) return 0;
    h = pt_sub(pt_madd(rc->o, rc->d, t), p->p0);
    a = pt_dot(h, p->w);
    b = pt_dot(h, p->w2);
    if (a < 0.0f || a > 1.0f || b < 0.0f || b > 1.0f) {
        /* Quads that share an edge (a box) compute it each from their own Q, u, v: without a
           margin a ray exactly at the edge can fail both (rays escaped closed boxes). Accept
           points within the rounding error of a and b: h = (o + t d) - Q is off by ~u |o + t d|
           from the sum and ~u t |d| from the product, plus t's own relative error (a few u)
           times |d| (u = FLT_EPSILON / 2; Higham, "Accuracy and Stability of Numerical
           Algorithms", sec. 3.1), and a = h.w by that times the sum of |w|. */
        float e = FLT_EPSILON * (pt__vmaxabs(pt_add(h, p->p0)) + 2.0f * t * pt__vmaxabs(rc->d));
        float cap = pt__quad_margin(p) * 0.57735f; /* |u| <= sqrt(3) max|u_i| */
        float ta = pt__minf(e * (fabsf(p->w.x) + fabsf(p->w.y) + fabsf(p->w.z)), cap / pt__vmaxabs(p->p1));
        float tb = pt__minf(e * (fabsf(p->w2.x) + fabsf(p->w2.y) + fabsf(p->w2.z)), cap / pt__vmaxabs(p->p2));
        if (a < -ta || a > 1.0f + ta || b < -tb || b > 1.0f + tb) return 0;
    }
    *t_out = t;
    return 1;
}

/* Float leaves t with a relative error of about 6e-8 times the condition of U, V, W (the sum
   of the products' magnitudes over |det|) plus that of T (the sum of its terms' magnitudes over
   |T|: vertices far from the hit along the ray, in float rounded by more than t itself). When
   either exceeds this (a sliver, a huge triangle hit close by), the distance and barycentrics
   are recomputed in double (pt__hit_triangle_precise); below it t is within ~1e-5. */
#ifndef PT__TRI_COND
#define PT__TRI_COND 16.0f
#endif

/* For a hit pt__hit_triangle's float edge functions accepted (their signs decide it, so that
   triangles sharing an edge decide it alike), t and the barycentrics in double: returns 1 with
   *t_out and bary when 0 < t < tmax, 0 if not, -1 for a ray within 1e-3 radians of the plane
   (along an edge, in the plane), which the float test decides as before: the plane's t is then
   the far crossing of a ray its rounding tilted. t is the distance to the plane through a,
   n.(a - o) / n.d with n = (b - a) x (c - a): differences of floats and their products are exact
   in double (for coordinates within 2^29 of each other's exponent), so only the last sums
   round; the watertight test's T / det, even in double, multiplies the rounding of U, V, W by
   the vertices' distance along the ray. The barycentrics are U, V, W / det in double (Woop et
   al. 2013). */
static int pt__hit_triangle_precise(const pt__rayctx *rc, pt_vec3 a, pt_vec3 b, pt_vec3 c, float tmax, float *t_out,
                                    float *bary)
{
    const int kx = rc->kx, ky = rc->ky, kz = rc->kz;
    const double o[3] = { rc->o.x, rc->o.y, rc->o.z }, sx = rc->sx, sy = rc->sy, sz = rc->sz;
    const double pa[3] = { a.x, a.y, a.z }, pb[3] = { b.x, b.y, b.z }, pc[3] = { c.x, c.y, c.z };
    double Akz = pa[kz] - o[kz], Bkz = pb[kz] - o[kz], Ckz = pc[kz] - o[kz];
    double Ax = (pa[kx] - o[kx]) - sx * Akz, Ay = (pa[ky] - o[ky]) - sy * Akz;
    double Bx = (pb[kx] - o[kx]) - sx * Bkz, By = (pb[ky] - o[ky]) - sy * Bkz;
    double Cx = (pc[kx] - o[kx]) - sx * Ckz, Cy = (pc[ky] - o[ky]) - sy * Ckz;
    double U = Cx * By - Cy * Bx, V = Ax * Cy - Ay * Cx, W = Bx * Ay - By * Ax, det = U + V + W, t, nd;
    double e1[3], e2[3], n[3];
    int i;
    for (i = 0; i < 3; ++i) { e1[i] = pb[i] - pa[i]; e2[i] = pc[i] - pa[i]; }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    nd = n[0] * rc->d.x + n[1] * rc->d.y + n[2] * rc->d.z;
    (void)sz;
    if (!(nd * nd > 1e-6 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) *
                        ((double)rc->d.x * rc->d.x + (double)rc->d.y * rc->d.y + (double)rc->d.z * rc->d.z)))
        return -1;
    if (det == 0.0) return 0;
    t = (n[0] * (pa[0] - o[0]) + n[1] * (pa[1] - o[1]) + n[2] * (pa[2] - o[2])) / nd;
    if (!(t > 0.0 && t < (double)tmax) || !((float)t > 0.0f)) return 0;
    *t_out = (float)t;
    if (!(*t_out < tmax)) return 0;
    if (bary) {
        /* The double signs may differ from the float ones near an edge (the float test said
           inside): clamp to >= 0 and divide by the new sum, so that the point stays on the
           triangle's plane (a bare clamp leaves their sum above 1 and the point off the plane by
           that excess times the vertices' size, where a spawned ray re-hits the triangle). */
        double u = U / det > 0.0 ? U / det : 0.0, v = V / det > 0.0 ? V / det : 0.0;
        double w = W / det > 0.0 ? W / det : 0.0, sum = u + v + w;
        if (!(sum > 0.0)) { u = v = w = 1.0; sum = 3.0; }
        bary[0] = (float)(u / sum);
        bary[1] = (float)(v / sum);
        bary[2] = (float)(w / sum);
    }
    return 1;
}

/* Watertight ray/triangle intersection (Woop, Benthin & Wald, "Watertight Ray/Triangle
   Intersection", JCGT 2(1), 2013): vertices translated to the ray origin, sheared so the ray
   is +z, 2D edge functions; an edge function that is exactly zero is recomputed in double, and
   an ill-conditioned hit's distance too (PT__TRI_COND). */
static PT__HOT int pt__hit_triangle(const pt__rayctx *rc, pt_vec3 a, pt_vec3 b, pt_vec3 c, float tmax, float *t_out,
                            float *bary)
{
    pt_vec3 A = pt_sub(a, rc->o), B = pt_sub(b, rc->o), C = pt_sub(c, rc->o);
    float Akz = pt__vget(A, rc->kz), Bkz = pt__vget(B, rc->kz), Ckz = pt__vget(C, rc->kz);
    float Ax = pt__vget(A, rc->kx) - rc->sx * Akz, Ay = pt__vget(A, rc->ky) - rc->sy * Akz;
    float Bx = pt__vget(B, rc->kx) - rc->sx * Bkz, By = pt__vget(B, rc->ky) - rc->sy * Bkz;
    float Cx = pt__vget(C, rc->kx) - rc->sx * Ckz, Cy = pt__vget(C, rc->ky) - rc->sy * Ckz;
    float CxBy = Cx * By, CyBx = Cy * Bx, AxCy = Ax * Cy, AyCx = Ay * Cx, BxAy = Bx * Ay, ByAx = By * Ax;
    float U = CxBy - CyBx, V = AxCy - AyCx, W = BxAy - ByAx, det, T, inv, P;
    /* the same sum in the same order as pt__tri4_hit's, so both route the same lanes */
    P = fabsf(CxBy) + fabsf(CyBx) + fabsf(AxCy) + fabsf(AyCx) + fabsf(BxAy) + fabsf(ByAx);
    if (U == 0.0f || V == 0.0f || W == 0.0f) {
        U = (float)((double)Cx * (double)By - (double)Cy * (double)Bx);
        V = (float)((double)Ax * (double)Cy - (double)Ay * (double)Cx);
        W = (float)((double)Bx * (double)Ay - (double)By * (double)Ax);
    }
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return 0;
    det = U + V + W;
    if (det == 0.0f) return 0;
    {
        float Ta = U * (rc->sz * Akz), Tb = V * (rc->sz * Bkz), Tc = W * (rc->sz * Ckz);
        T = Ta + Tb + Tc;
        if (P > PT__TRI_COND * fabsf(det) || fabsf(Ta) + fabsf(Tb) + fabsf(Tc) > PT__TRI_COND * fabsf(T)) {
            int hit = pt__hit_triangle_precise(rc, a, b, c, tmax, t_out, bary);
            if (hit >= 0) return hit;
        }
    }
    if (det < 0.0f ? (T >= 0.0f || T <= tmax * det) : (T <= 0.0f || T >= tmax * det)) return 0;
    inv = 1.0f / det;
    *t_out = T * inv;
    if (!(*t_out > 0.0f && *t_out < tmax)) return 0;
    if (bary) { bary[0] = U * inv; bary[1] = V * inv; bary[2] = W * inv; }
    return 1;
}

PTDEF int pt_intersect_sphere(pt_ray ray, pt_vec3 center, float radius, float tmax, float *t)
{
    pt__rayctx rc;
    float tt;
    if (!t || !(radius > 0.0f)) return 0;
    pt__rayctx_init(&rc, ray);
    if (!pt__hit_sphere(&rc, center, radius, tmax, &tt)) return 0;
    *t = tt;
    return 1;
}
static void pt__quad_setup(pt__prim *p)
{
    pt_vec3 nn = pt_cross(p->p1, p->p2), w0 = pt_scale(nn, 1.0f / pt_dot(nn, nn));
    p->n = pt_normalize(nn);
    /* w0.(h x v) = h.(v x w0) and w0.(u x h) = h.(w0 x u): precomputed once */
    p->w = pt_cross(p->p2, w0);
    p->w2 = pt_cross(w0, p->p1);
}
PTDEF int pt_intersect_quad(pt_ray ray, pt_vec3 q, pt_vec3 u, pt_vec3 v, float tmax, float *t)
{
    pt__rayctx rc;
    pt__prim p;
    float tt;
    if (!t || !(pt_length2(pt_cross(u, v)) > 0.0f)) return 0;
    memset(&p, 0, sizeof p);
    p.p0 = q; p.p1 = u; p.p2 = v;
    pt__quad_setup(&p);
    pt__rayctx_init(&rc, ray);
    if (!pt__hit_quad(&rc, &p, tmax, &tt)) return 0;
    *t = tt;
    return 1;
}
PTDEF int pt_intersect_triangle(pt_ray ray, pt_vec3 a, pt_vec3 b, pt_vec3 c, float tmax, float *t)
{
    pt__rayctx rc;
    float tt;
    if (!t) return 0;
    pt__rayctx_init(&rc, ray);
    if (!pt__hit_triangle(&rc, a, b, c, tmax, &tt, NULL)) return 0;
    *t = tt;
    return 1;
}

/* Intersects one primitive; bary receives triangle barycentrics. */
static PT__HOT int pt__hit_prim(const pt__rayctx *rc, const pt__prim *p, float tmax, float *t, float *bary)
{
    switch (p->type) {
    case PT__PRIM_SPHERE: return pt__hit_sphere(rc, p->p0, p->p1.x, tmax, t);
    case PT__PRIM_QUAD: return pt__hit_quad(rc, p, tmax, t);
    default: return pt__hit_triangle(rc, p->p0, p->p1, p->p2, tmax, t, bary);
    }
}

/* The scale of the rounding error, along unit normal n, of a point computed on p and of a
   re-intersection of p from near it: sum_i |n_i| m_i, m_i the largest |coordinate i| that
   enters (sphere: |c_i| + r; quad: |Q_i| + |u_i| + |v_i|; triangle: the vertices'). Products
   with exact zeros are exact, so an axis-aligned plane through 0 has magnitude 0 and its points
   leave it by a few ulps, where a fixed 1/65536 would lift them 1e-3 above a floor 50 wide or
   leave a 1e-6 scene altogether (pt_offset_ray_origin_scaled). */
static float pt__prim_magnitude(const pt__prim *p, pt_vec3 n)
{
    return fabsf(n.x) * p->mag.x + fabsf(n.y) * p->mag.y + fabsf(n.z) * p->mag.z;
}
/* What pt__fill_hit needs per primitive, computed once at commit: m_i of pt__prim_magnitude
   and a quad's insets (see pt__fill_hit). */
static void pt__prim_cache(pt__prim *p)
{
    pt_vec3 m;
    if (p->type == PT__PRIM_SPHERE) {
        float r = p->p1.x;
        m = pt_v3(fabsf(p->p0.x) + r, fabsf(p->p0.y) + r, fabsf(p->p0.z) + r);
    } else if (p->type == PT__PRIM_QUAD) {
        m = pt_v3(fabsf(p->p0.x) + fabsf(p->p1.x) + fabsf(p->p2.x), fabsf(p->p0.y) + fabsf(p->p1.y) + fabsf(p->p2.y),
                  fabsf(p->p0.z) + fabsf(p->p1.z) + fabsf(p->p2.z));
    } else {
        m = pt_v3(pt__maxf(fabsf(p->p0.x), pt__maxf(fabsf(p->p1.x), fabsf(p->p2.x))),
                  pt__maxf(fabsf(p->p0.y), pt__maxf(fabsf(p->p1.y), fabsf(p->p2.y))),
                  pt__maxf(fabsf(p->p0.z), pt__maxf(fabsf(p->p1.z), fabsf(p->p2.z))));
    }
    p->mag = m;
    p->inset[0] = p->inset[1] = 0.0f;
    if (p->type == PT__PRIM_QUAD) {
        float mq = pt__vmaxabs(p->p0), mu = pt__vmaxabs(p->p1), mv = pt__vmaxabs(p->p2);
        p->inset[0] = pt__minf(0.5f, 4.0f * FLT_EPSILON * (mq + mu) / mu);
        p->inset[1] = pt__minf(0.5f, 4.0f * FLT_EPSILON * (mq + mv) / mv);
    }
}

/* Surface area (light powers, area sampling). */
static float pt__prim_area(const pt__prim *p)
{
    if (p->type == PT__PRIM_SPHERE) return 4.0f * PT__PI * p->p1.x * p->p1.x;
    if (p->type == PT__PRIM_QUAD) return pt_length(pt_cross(p->p1, p->p2));
    return 0.5f * pt_length(pt_cross(pt_sub(p->p1, p->p0), pt_sub(p->p2, p->p0)));
}

/* Fills a public hit record for primitive p hit at t. */
static PT__HOT void pt__fill_hit(const pt_scene *s, const pt__prim *p, pt_ray ray, float t, const float *bary, pt_hit *h)
{
    h->t = t;
    h->primitive = p->id;
    h->material = p->material;
    if (p->type == PT__PRIM_SPHERE) {
        /* re-project onto the sphere to remove the error of o + t d (pbrt-v4 sec. 6.8.5); the
           direction from the centre in double, from the exact o - c: in float it is off by
           2^-24 |o - c|, which turns the normals of tiny far spheres (a light 1e-6 wide seen
           from 1 away) by degrees and makes rim hits back faces */
        double ex = (double)ray.origin.x - p->p0.x + (double)t * ray.dir.x;
        double ey = (double)ray.origin.y - p->p0.y + (double)t * ray.dir.y;
        double ez = (double)ray.origin.z - p->p0.z + (double)t * ray.dir.z;
        double el = sqrt(ex * ex + ey * ey + ez * ez);
        pt_vec3 n = el > 0.0 ? pt_v3((float)(ex / el), (float)(ey / el), (float)(ez / el)) : pt_v3(0, 0, 1);
        h->point = pt_madd(p->p0, n, p->p1.x);
        h->geometric_normal = n;
        h->shading_normal = n;
    } else if (p->type == PT__PRIM_QUAD) {
        /* on the plane: Q + a u + b v, not o + t d, whose error grows with the distance the ray
           travelled (a far camera put points below a floor: acne and light leaks); a and b a
           few ulps inside [0, 1]: a point on an edge shared with another face (a room's
           corner) lies in that face's plane, where a ray leaving into it finds t = 0, no hit,
           and leaves the room */
        pt_vec3 hq = pt_sub(pt_ray_at(ray, t), p->p0);
        float ea = p->inset[0], eb = p->inset[1]; /* min(0.5, 4 eps (max|Q_i| + max|u_i|) / max|u_i|), v alike */
        float a = pt__minf(1.0f - ea, pt__maxf(ea, pt_dot(hq, p->w)));
        float b = pt__minf(1.0f - eb, pt__maxf(eb, pt_dot(hq, p->w2)));
        h->point = pt_madd(pt_madd(p->p0, p->p1, a), p->p2, b);
        h->geometric_normal = p->n;
        h->shading_normal = p->n;
    } else {
        /* barycentric point on the triangle is more accurate than o + t d */
        h->point = pt_add(pt_add(pt_scale(p->p0, bary[0]), pt_scale(p->p1, bary[1])), pt_scale(p->p2, bary[2]));
        h->geometric_normal = p->n;
        h->shading_normal = p->n;
        if (p->normals >= 0) {
            const pt_vec3 *nv = s->normals + p->normals;
            pt_vec3 ns = pt_normalize(pt_add(pt_add(pt_scale(nv[0], bary[0]), pt_scale(nv[1], bary[1])),
                                             pt_scale(nv[2], bary[2])));
            if (pt_length2(ns) > 0.0f) h->shading_normal = ns;
        }
    }
    h->front_face = pt_dot(ray.dir, h->geometric_normal) < 0.0f;
    if (p->type == PT__PRIM_SPHERE) {
        /* a ray from outside meets the outside: decided by the exact origin, not by a normal
           that is a few degrees off at the rim of a tiny far sphere (where rays aimed at a light
           1e-6 wide would hit its "back" and find no emission) */
        double ox = (double)ray.origin.x - p->p0.x, oy = (double)ray.origin.y - p->p0.y;
        double oz = (double)ray.origin.z - p->p0.z, d2 = ox * ox + oy * oy + oz * oz, r2 = (double)p->p1.x * p->p1.x;
        if (d2 != r2) h->front_face = d2 > r2;
    }
    h->magnitude = pt__prim_magnitude(p, h->geometric_normal);
}

/* The hit's surface coordinates (pt_hit.u, .v; Mitsuba 3's parameterisations), from a filled
   hit h on p and the triangle's barycentric weights. Only where something needs them: the
   renderer calls it at materials with an image texture, so other scenes never pay for it. */
static void pt__hit_uv(const pt_scene *s, const pt__prim *p, const float *bary, const pt_hit *h, float *u, float *v)
{
    if (p->type == PT__PRIM_SPHERE) {
        pt_vec3 n = h->geometric_normal; /* world axes (a sphere keeps no rotation) */
        float a = atan2f(n.y, n.x) * (0.5f / PT__PI);
        *u = a < 0.0f ? a + 1.0f : a;
        if (*u >= 1.0f) *u = 0.0f;
        *v = acosf(pt__minf(1.0f, pt__maxf(-1.0f, n.z))) * (1.0f / PT__PI);
    } else if (p->type == PT__PRIM_QUAD) {
        pt_vec3 hq = pt_sub(h->point, p->p0); /* both in the scene's stored coordinates */
        *u = pt_dot(hq, p->w);
        *v = pt_dot(hq, p->w2);
    } else if (p->uvs >= 0) {
        const float *t = s->uvs + p->uvs;
        *u = bary[0] * t[0] + bary[1] * t[2] + bary[2] * t[4];
        *v = bary[0] * t[1] + bary[1] * t[3] + bary[2] * t[5];
    } else {
        *u = bary[1];
        *v = bary[2];
    }
}

PTDEF pt_scene *pt_scene_create(void)
{
    pt_scene *s = (pt_scene *)PT_MALLOC(sizeof(pt_scene));
    if (!s) return NULL;
    memset(s, 0, sizeof *s);
    s->xf = pt_transform_identity();
    s->xf_identity = 1;
    s->backend = PT_BACKEND_BUILTIN;
    return s;
}
#ifdef PDFTRACE_EMBREE
static void pt__rtc_release(pt_scene *s);
#endif
PTDEF void pt_scene_destroy(pt_scene *s)
{
    if (!s) return;
#ifdef PDFTRACE_EMBREE
    pt__rtc_release(s);
#endif
    PT_FREE(s->prims);
    PT_FREE(s->mats);
    if (s->texs) {
        uint32_t i;
        for (i = 0; i < s->tex_count; ++i) PT_FREE(s->texs[i].rgb);
    }
    PT_FREE(s->texs);
    PT_FREE(s->normals);
    PT_FREE(s->uvs);
    PT_FREE(s->bvh_mem);
    PT_FREE(s->wide_mem);
    PT_FREE(s->lights);
    PT_FREE(s->ltree);
    PT_FREE(s->ltrail);
    PT_FREE(s->dlights);
    pt__env_free(s->env);
    PT_FREE(s);
}
PTDEF const char *pt_scene_error_message(const pt_scene *s) { return s ? s->error : "scene is NULL"; }

/* Grows an array to hold `need` elements; returns 0 when out of memory or on overflow. */
static int pt__grow(void **arr, uint32_t *cap, uint32_t need, size_t elem)
{
    uint32_t nc;
    void *p;
    if (need <= *cap) return 1;
    if (need > 0x7fffffffu / 2u) return 0;
    nc = *cap ? *cap : 16u;
    while (nc < need) nc *= 2u;
    if ((size_t)nc > ((size_t)-1) / elem) return 0;
    p = PT_REALLOC(*arr, (size_t)nc * elem);
    if (!p) return 0;
    *arr = p;
    *cap = nc;
    return 1;
}

PTDEF int pt_scene_set_transform(pt_scene *s, const pt_transform *t)
{
    int i, j;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if (!t) {
        s->xf = pt_transform_identity();
        s->xf_identity = 1;
        return PT_OK;
    }
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 4; ++j)
            if (!pt__isfinite(t->m[i][j]))
                return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "transform: element [%d][%d] is not finite", i, j);
    {
        float det = pt__transform_det(t);
        if (!(fabsf(det) > 0.0f) || !pt__isfinite(det))
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "transform: matrix is singular");
    }
    {
        pt_transform id = pt_transform_identity();
        s->xf = *t;
        s->xf_identity = memcmp(t, &id, sizeof *t) == 0;
    }
    return PT_OK;
}

static int pt__check_material(pt_scene *s, int material, const char *what)
{
    if (material < 0 || (uint32_t)material >= s->mat_count)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "%s: material %d does not exist (the scene has %u)", what,
                        material, (unsigned)s->mat_count);
    return PT_OK;
}
static pt__prim *pt__new_prim(pt_scene *s, int type, int material)
{
    pt__prim *p;
    if (!pt__grow((void **)&s->prims, &s->prim_cap, s->prim_count + 1u, sizeof(pt__prim))) return NULL;
    p = &s->prims[s->prim_count];
    memset(p, 0, sizeof *p);
    p->type = type;
    p->material = material;
    p->light = -1;
    p->normals = -1;
    p->uvs = -1;
    p->id = s->prim_count++;
    s->committed = 0;
    if (!s->xf_identity) s->features |= PT_FEATURE_TRANSFORMS;
    return p;
}

PTDEF int pt_scene_add_sphere(pt_scene *s, pt_vec3 center, float radius, int material)
{
    pt__prim *p;
    float r = radius;
    int rc;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if ((rc = pt__check_material(s, material, "sphere")) != PT_OK) return rc;
    if (!pt__vfinite(center) || !pt__isfinite(radius) || !(radius > 0.0f))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "sphere: centre must be finite and radius > 0 (radius %g)",
                        (double)radius);
    if (pt__vmaxabs(center) > PT__MAX_COORD || radius > PT__MAX_COORD)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                        "sphere: centre and radius must have magnitude <= %g (radius %g): products of two "
                        "coordinates must stay finite in float", (double)PT__MAX_COORD, (double)radius);
    if (!s->xf_identity) {
        /* a similarity transform has M^T M = k^2 I */
        pt_vec3 c0 = pt_v3(s->xf.m[0][0], s->xf.m[1][0], s->xf.m[2][0]);
        pt_vec3 c1 = pt_v3(s->xf.m[0][1], s->xf.m[1][1], s->xf.m[2][1]);
        pt_vec3 c2 = pt_v3(s->xf.m[0][2], s->xf.m[1][2], s->xf.m[2][2]);
        float k2 = pt_length2(c0), tol = 1e-4f * k2;
        if (fabsf(pt_length2(c1) - k2) > tol || fabsf(pt_length2(c2) - k2) > tol || fabsf(pt_dot(c0, c1)) > tol ||
            fabsf(pt_dot(c0, c2)) > tol || fabsf(pt_dot(c1, c2)) > tol)
            return pt__fail(s, PT_ERROR_UNSUPPORTED,
                            "sphere: the current transform is not a similarity (rotation, translation, uniform "
                            "scale); a sphere would become an ellipsoid");
        center = pt_transform_point(&s->xf, center);
        r = radius * sqrtf(k2);
        if (!pt__vfinite(center) || !pt__isfinite(r) || !(r > 0.0f) || pt__vmaxabs(center) > PT__MAX_COORD ||
            r > PT__MAX_COORD)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "sphere: transformed sphere is not finite");
    }
    p = pt__new_prim(s, PT__PRIM_SPHERE, material);
    if (!p) return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "sphere: out of memory");
    p->p0 = center;
    p->p1 = pt_v3(r, 0.0f, 0.0f);
    s->sphere_count++;
    s->features |= PT_FEATURE_SPHERES;
    return (int)p->id;
}

/* Transforms a parallelogram; a mirroring transform swaps u and v so that the emitting side
   stays on the geometrically transformed side. */
static int pt__xf_quad(const pt_scene *s, pt_vec3 *q, pt_vec3 *u, pt_vec3 *v)
{
    if (!s->xf_identity) {
        *q = pt_transform_point(&s->xf, *q);
        *u = pt_transform_vector(&s->xf, *u);
        *v = pt_transform_vector(&s->xf, *v);
        if (pt__transform_det(&s->xf) < 0.0f) { pt_vec3 t = *u; *u = *v; *v = t; }
    }
    return pt__vfinite(*q) && pt__vfinite(*u) && pt__vfinite(*v) && pt_length2(pt_cross(*u, *v)) > 0.0f &&
           pt__isfinite(pt_length2(pt_cross(*u, *v))) &&
           pt__vmaxabs(*q) + pt__vmaxabs(*u) + pt__vmaxabs(*v) <= PT__MAX_COORD;
}
static void pt__set_quad(pt__prim *p, pt_vec3 q, pt_vec3 u, pt_vec3 v)
{
    p->p0 = q; p->p1 = u; p->p2 = v;
    pt__quad_setup(p);
}
PTDEF int pt_scene_add_quad(pt_scene *s, pt_vec3 q, pt_vec3 u, pt_vec3 v, int material)
{
    pt__prim *p;
    int rc;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if ((rc = pt__check_material(s, material, "quad")) != PT_OK) return rc;
    if (!pt__vfinite(q) || !pt__vfinite(u) || !pt__vfinite(v))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "quad: Q, u and v must be finite");
    if (!pt__xf_quad(s, &q, &u, &v))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                        "quad: no area in float (u and v parallel or zero, |u x v|^2 under- or overflows, or a "
                        "corner beyond %g)", (double)PT__MAX_COORD);
    p = pt__new_prim(s, PT__PRIM_QUAD, material);
    if (!p) return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "quad: out of memory");
    pt__set_quad(p, q, u, v);
    s->quad_count++;
    s->features |= PT_FEATURE_QUADS;
    return (int)p->id;
}

static void pt__set_triangle(pt__prim *p, pt_vec3 a, pt_vec3 b, pt_vec3 c)
{
    p->p0 = a; p->p1 = b; p->p2 = c;
    p->n = pt_normalize(pt_cross(pt_sub(b, a), pt_sub(c, a)));
}
static int pt__tri_ok(pt_vec3 a, pt_vec3 b, pt_vec3 c)
{
    float a2 = pt_length2(pt_cross(pt_sub(b, a), pt_sub(c, a)));
    return pt__vfinite(a) && pt__vfinite(b) && pt__vfinite(c) && a2 > 0.0f && pt__isfinite(a2) &&
           pt__vmaxabs(a) <= PT__MAX_COORD && pt__vmaxabs(b) <= PT__MAX_COORD && pt__vmaxabs(c) <= PT__MAX_COORD;
}
PTDEF int pt_scene_add_triangle(pt_scene *s, pt_vec3 a, pt_vec3 b, pt_vec3 c, int material)
{
    pt__prim *p;
    int rc;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if ((rc = pt__check_material(s, material, "triangle")) != PT_OK) return rc;
    if (!pt__vfinite(a) || !pt__vfinite(b) || !pt__vfinite(c))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "triangle: vertices must be finite");
    if (!s->xf_identity) {
        a = pt_transform_point(&s->xf, a);
        b = pt_transform_point(&s->xf, b);
        c = pt_transform_point(&s->xf, c);
        if (pt__transform_det(&s->xf) < 0.0f) { pt_vec3 t = b; b = c; c = t; }
    }
    if (!pt__tri_ok(a, b, c))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                        "triangle: no area in float (collinear or coincident vertices, |(b-a) x (c-a)|^2 under- or "
                        "overflows, or a vertex beyond %g)", (double)PT__MAX_COORD);
    p = pt__new_prim(s, PT__PRIM_TRIANGLE, material);
    if (!p) return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "triangle: out of memory");
    pt__set_triangle(p, a, b, c);
    s->triangle_count++;
    s->features |= PT_FEATURE_TRIANGLES;
    return (int)p->id;
}

PTDEF int pt_scene_add_box(pt_scene *s, pt_vec3 lo, pt_vec3 hi, int material)
{
    pt_vec3 q[6], u[6], v[6];
    pt_vec3 dx, dy, dz;
    int i, rc, first = -1;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if ((rc = pt__check_material(s, material, "box")) != PT_OK) return rc;
    if (!pt__vfinite(lo) || !pt__vfinite(hi) || !(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "box: corners must be finite with max > min on every axis");
    dx = pt_v3(hi.x - lo.x, 0, 0); dy = pt_v3(0, hi.y - lo.y, 0); dz = pt_v3(0, 0, hi.z - lo.z);
    /* six faces, each with u x v pointing out of the box */
    q[0] = pt_v3(lo.x, lo.y, hi.z); u[0] = dx; v[0] = dy;            /* +z */
    q[1] = pt_v3(hi.x, lo.y, lo.z); u[1] = pt_neg(dx); v[1] = dy;    /* -z */
    q[2] = pt_v3(hi.x, lo.y, hi.z); u[2] = pt_neg(dz); v[2] = dy;    /* +x */
    q[3] = pt_v3(lo.x, lo.y, lo.z); u[3] = dz; v[3] = dy;            /* -x */
    q[4] = pt_v3(lo.x, hi.y, hi.z); u[4] = dx; v[4] = pt_neg(dz);    /* +y */
    q[5] = pt_v3(lo.x, lo.y, lo.z); u[5] = dx; v[5] = dz;            /* -y */
    for (i = 0; i < 6; ++i)
        if (!pt__xf_quad(s, &q[i], &u[i], &v[i]))
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "box: face %d is degenerate after the transform", i);
    if (!pt__grow((void **)&s->prims, &s->prim_cap, s->prim_count + 6u, sizeof(pt__prim)))
        return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "box: out of memory");
    for (i = 0; i < 6; ++i) {
        pt__prim *p = pt__new_prim(s, PT__PRIM_QUAD, material);
        pt__set_quad(p, q[i], u[i], v[i]);
        if (first < 0) first = (int)p->id;
    }
    s->quad_count += 6;
    s->features |= PT_FEATURE_QUADS;
    return first;
}

PTDEF int pt_scene_add_mesh(pt_scene *s, const pt_mesh_desc *m)
{
    uint32_t i, good = 0, first = 0;
    int rc, have_first = 0;
    float det;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if (!m) return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "mesh: desc is NULL");
    if ((rc = pt__check_material(s, m->material, "mesh")) != PT_OK) return rc;
    if (!m->positions || !m->indices || m->vertex_count == 0 || m->triangle_count == 0)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "mesh: positions, indices and counts are required");
    if (m->triangle_count > 0x3fffffffu / 3u)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "mesh: too many triangles (%u)", (unsigned)m->triangle_count);
    for (i = 0; i < m->vertex_count; ++i) {
        pt_vec3 p = pt_v3(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]);
        if (!pt__vfinite(p) || pt__vmaxabs(p) > PT__MAX_COORD)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "mesh: vertex %u is not finite or beyond %g", (unsigned)i,
                            (double)PT__MAX_COORD);
        if (m->normals &&
            !pt__vfinite(pt_v3(m->normals[3 * i], m->normals[3 * i + 1], m->normals[3 * i + 2])))
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "mesh: normal %u is not finite", (unsigned)i);
        if (m->uvs && !(pt__isfinite(m->uvs[2 * i]) && pt__isfinite(m->uvs[2 * i + 1])))
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "mesh: uvs of vertex %u are not finite", (unsigned)i);
    }
    for (i = 0; i < 3u * m->triangle_count; ++i)
        if (m->indices[i] >= m->vertex_count)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "mesh: triangle %u uses vertex %u, but there are %u",
                            (unsigned)(i / 3u), (unsigned)m->indices[i], (unsigned)m->vertex_count);
    if (!pt__grow((void **)&s->prims, &s->prim_cap, s->prim_count + m->triangle_count, sizeof(pt__prim)) ||
        (m->normals &&
         !pt__grow((void **)&s->normals, &s->normal_cap, s->normal_count + 3u * m->triangle_count, sizeof(pt_vec3))) ||
        (m->uvs && (m->triangle_count > 0x7fffffffu / 6u - s->uv_count / 6u ||
                    !pt__grow((void **)&s->uvs, &s->uv_cap, s->uv_count + 6u * m->triangle_count, sizeof(float)))))
        return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "mesh: out of memory (%u triangles)", (unsigned)m->triangle_count);
    det = s->xf_identity ? 1.0f : pt__transform_det(&s->xf);
    for (i = 0; i < m->triangle_count; ++i) {
        pt_vec3 v[3], n[3];
        float uv[6] = {0, 0, 0, 0, 0, 0};
        int k;
        pt__prim *p;
        n[0] = n[1] = n[2] = pt_v3(0, 0, 0);
        for (k = 0; k < 3; ++k) {
            uint32_t vi = m->indices[3 * i + (uint32_t)k];
            if (m->uvs) { uv[2 * k] = m->uvs[2 * vi]; uv[2 * k + 1] = m->uvs[2 * vi + 1]; }
            v[k] = pt_v3(m->positions[3 * vi], m->positions[3 * vi + 1], m->positions[3 * vi + 2]);
            if (!s->xf_identity) v[k] = pt_transform_point(&s->xf, v[k]);
            if (m->normals) {
                n[k] = pt_v3(m->normals[3 * vi], m->normals[3 * vi + 1], m->normals[3 * vi + 2]);
                if (!s->xf_identity) (void)pt_transform_normal(&s->xf, n[k], &n[k]);
                n[k] = pt_normalize(n[k]);
            }
        }
        if (det < 0.0f) {
            pt_vec3 t = v[1]; v[1] = v[2]; v[2] = t;
            t = n[1]; n[1] = n[2]; n[2] = t;
            { float a = uv[2], b = uv[3]; uv[2] = uv[4]; uv[3] = uv[5]; uv[4] = a; uv[5] = b; }
        }
        if (!pt__tri_ok(v[0], v[1], v[2])) continue; /* counted below, once the mesh is added */
        p = pt__new_prim(s, PT__PRIM_TRIANGLE, m->material);
        pt__set_triangle(p, v[0], v[1], v[2]);
        if (m->normals) {
            p->normals = (int32_t)s->normal_count;
            s->normals[s->normal_count++] = n[0];
            s->normals[s->normal_count++] = n[1];
            s->normals[s->normal_count++] = n[2];
        }
        if (m->uvs) {
            p->uvs = (int32_t)s->uv_count;
            memcpy(s->uvs + s->uv_count, uv, sizeof uv);
            s->uv_count += 6u;
        }
        if (!have_first) { first = p->id; have_first = 1; }
        good++;
    }
    if (!good) return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "mesh: every triangle has zero area");
    s->degenerate_skipped += m->triangle_count - good;
    s->triangle_count += good;
    s->mesh_count++;
    s->features |= PT_FEATURE_TRIANGLES | PT_FEATURE_MESHES | (m->normals ? (unsigned)PT_FEATURE_SHADING_NORMALS : 0u);
    return (int)first;
}

/* ------------------------------------------------------------------------------------------
   4. Materials and textures: the material table (Lambertian, metal with an optional fuzz lobe,
   clear dielectric, emitter, rough conductor, rough plastic with its coat tables), the 3D checker
   and image textures (bilinear between texel centres, repeated; looked up at the hit's (u, v)),
   and what the integrator asks of a material: its
   A * pScatter for a direction (BRDF times cosine), the density with which it samples a
   direction, a sampled direction, and the exact unpolarised Fresnel reflectance of a dielectric
   interface. Delta materials (mirror, glass) have no density and are followed by the integrator.
   ------------------------------------------------------------------------------------------ */


/* Rough conductor: below this GGX alpha the material is the smooth Fresnel mirror (delta). The
   half vector of two float directions is off by ~1e-7 rad (more near grazing), which moves D by
   about twice that over alpha, relative: 1e-4 here, past 1e-2 near alpha 1e-5 (docs/materials.md). */
#define PT__GGX_MIN_ALPHA 1e-3f
/* Named conductors: eta then k, per channel (pt_conductor's table). */
static const float pt__conductor_table[4][6] = {
    { 0.1431189557f, 0.3749570432f, 1.4424785571f, 3.9831604247f, 2.3857207478f, 1.6032152899f }, /* Au */
    { 0.1552646489f, 0.1167232965f, 0.1383806959f, 4.8283433224f, 3.1222459278f, 2.1469504455f }, /* Ag */
    { 0.2004376970f, 0.9240334304f, 1.1022119527f, 3.9129485033f, 2.4528477015f, 2.1421879552f }, /* Cu */
    { 1.6574599595f, 0.8803689579f, 0.5212287346f, 9.2238691996f, 6.2695232477f, 4.8370012281f }  /* Al */
};
PTDEF int pt_conductor_ior(pt_conductor c, pt_color *eta, pt_color *k)
{
    const float *t;
    if (!eta || !k || (int)c < (int)PT_CONDUCTOR_AU || (int)c > (int)PT_CONDUCTOR_AL) return PT_ERROR_INVALID_ARGUMENT;
    t = pt__conductor_table[(int)c - (int)PT_CONDUCTOR_AU];
    *eta = pt_v3(t[0], t[1], t[2]);
    *k = pt_v3(t[3], t[4], t[5]);
    return PT_OK;
}
static int pt__conductor_resolve(pt_scene *s, const pt_material_desc *d, pt__material *m)
{
    if (!pt__isfinite(d->roughness) || d->roughness < 0.0f || d->roughness > 1.0f)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: roughness = %g: must be finite and in [0, 1]",
                        (double)d->roughness);
    if ((int)d->conductor < (int)PT_CONDUCTOR_NONE || (int)d->conductor > (int)PT_CONDUCTOR_AL)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: unknown conductor %d", (int)d->conductor);
    m->alpha = d->roughness;
    m->alpha2 = d->roughness * d->roughness;
    m->fresnel = d->conductor != PT_CONDUCTOR_NONE;
    if (d->conductor == PT_CONDUCTOR_CUSTOM) {
        if (!pt__vfinite(d->eta) || !(d->eta.x > 0.0f) || !(d->eta.y > 0.0f) || !(d->eta.z > 0.0f))
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: conductor eta = (%g, %g, %g): must be finite and > 0",
                            (double)d->eta.x, (double)d->eta.y, (double)d->eta.z);
        if (!pt__color_ok(d->k))
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: conductor k = (%g, %g, %g): must be finite and >= 0",
                            (double)d->k.x, (double)d->k.y, (double)d->k.z);
        m->eta = d->eta;
        m->k = d->k;
    } else if (d->conductor != PT_CONDUCTOR_NONE) {
        pt_conductor_ior(d->conductor, &m->eta, &m->k);
    }
    return PT_OK;
}

/* --- coated plastic: a Lambertian base under a GGX dielectric coat, the model of Mitsuba 3's
   `roughplastic` (its src/bsdfs/roughplastic.cpp, and eval_transmittance and eval_reflectance
   of include/mitsuba/render/microfacet.h, read for the model and its constants; Weidlich &
   Wilkie, "Arbitrarily Layered Micro-Facet Surfaces", GRAPHITE 2007, for the layering).
   T(mu), the coat's transmittance into the layer from a direction of cosine mu: the mean over
   normals m visible from it (Heitz 2018) of (1 - F(w.m)) G1(t, m), t the refracted direction,
   counted only below the surface. Tabulated at mu_k = max(1e-6, k / 63), k = 0 .. 63, read by
   linear interpolation in mu. R_int, the layer's diffuse internal reflectance: 2/64 sum_k mu_k
   R(mu_k), R(mu) the mean of F G1(r, m) from inside (relative index 1/ior), r the reflected
   direction, counted only above: Mitsuba's own discrete mean, kept so that the model is the
   same term for term. Both means are Gauss-Legendre rules over the visible-normal sampler's unit
   square mapped onto the visible normals through the concentric disk (Shirley & Chiu 1997), as
   Mitsuba's sampler maps it: n x n nodes, n = 32 for T and 128 for R (whose integrand has the
   kink of total internal reflection). The rule's own error (up to 4e-4 in T at normal incidence) is
   part of the model, so both renderers' tables agree to float rounding (docs/materials.md). */
#define PT__COAT_RES 64
static float pt__fresnel_dielectric(float cos_i, float eta, float *cos_t);
/* Gauss-Legendre nodes and weights of order n on [0, 1] (Newton's method on P_n). */
static void pt__gauss_legendre(int n, double *x, double *w)
{
    int i, j, it;
    for (i = 0; i < n; ++i) {
        double z = cos(3.14159265358979323846 * ((double)i + 0.75) / ((double)n + 0.5)), dp = 1.0;
        for (it = 0; it < 64; ++it) {
            double p1 = 1.0, p0 = 0.0, dz;
            for (j = 1; j <= n; ++j) {
                double pm = p0;
                p0 = p1;
                p1 = ((2.0 * j - 1.0) * z * p0 - (j - 1.0) * pm) / j;
            }
            dp = n * (z * p1 - p0) / (z * z - 1.0);
            dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-15) break;
        }
        x[i] = 0.5 * (1.0 - z);
        w[i] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
}
/* The coat seen from each direction of the table, mu_k = max(1e-6, k / 63): from outside
   (inside = 0) the mean of (1 - F) G1 of the refracted direction, from inside the mean of F G1 of
   the reflected one, by the n x n rule (n even, at most 128). The rule is symmetric and u1 -> 1 - u1
   mirrors the disk point, and so the normal, across the plane of v and the normal, where the
   integrand is even: half the rows, counted twice. */
static void pt__coat_means(const pt__material *mat, int inside, int n, double *out)
{
    double x[128], w[128];
    float a = mat->alpha, a2 = mat->alpha2, eta = inside ? mat->coat_ior : 1.0f / mat->coat_ior;
    pt_vec3 v[PT__COAT_RES];
    int i, j, k;
    pt__gauss_legendre(n, x, w);
    for (k = 0; k < PT__COAT_RES; ++k) {
        float mu = pt__maxf(1e-6f, (float)k / (float)(PT__COAT_RES - 1));
        v[k] = pt_v3(pt__safe_sqrt(1.0f - mu * mu), 0.0f, mu);
        out[k] = 0.0;
    }
    for (i = 0; i < n / 2; ++i)
        for (j = 0; j < n; ++j) {
            float p1, p2;
            double wt = 2.0 * w[i] * w[j];
            pt__concentric_disk((float)x[i], (float)x[j], &p1, &p2);
            for (k = 0; k < PT__COAT_RES; ++k) {
                pt_vec3 m = pt__ggx_vn_disk(v[k], a, p1, p2), t;
                float c = pt__minf(1.0f, pt__maxf(0.0f, pt_dot(v[k], m))), ct = 0.0f;
                float F = pt__fresnel_dielectric(c, eta, &ct);
                if (inside) {
                    t = pt__reflect(v[k], m);
                    if (t.z > 0.0f) out[k] += wt * F * pt__ggx_g1(t, a2);
                } else if (F < 1.0f) {
                    t = pt_add(pt_scale(v[k], -eta), pt_scale(m, eta * c - ct));
                    if (t.z < 0.0f) out[k] += wt * (1.0f - F) * pt__ggx_g1(pt_v3(t.x, t.y, -t.z), a2);
                }
            }
        }
}
static void pt__coat_tables(pt__material *m)
{
    double t[PT__COAT_RES], r[PT__COAT_RES], rint = 0.0;
    int k;
    pt__coat_means(m, 0, 32, t);
    pt__coat_means(m, 1, 128, r);
    for (k = 0; k < PT__COAT_RES; ++k) {
        m->coat_t[k] = (float)t[k];
        rint += (double)pt__maxf(1e-6f, (float)k / (float)(PT__COAT_RES - 1)) * r[k];
    }
    m->coat_rint = (float)(2.0 * rint / PT__COAT_RES);
}
static int pt__plastic_resolve(pt_scene *s, const pt_material_desc *d, pt__material *m)
{
    pt_color lo = d->albedo, hi = d->albedo;
    if (!pt__isfinite(d->roughness) || d->roughness < 0.0f || d->roughness > 1.0f)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: roughness = %g: must be finite and in [0, 1]",
                        (double)d->roughness);
    if (d->ior != 0.0f && !(d->ior > 1.0f))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: rough plastic ior = %g: must be > 1 (0 means 1.5)",
                        (double)d->ior);
    if (d->albedo_texture) {
        lo = s->texs[d->albedo_texture - 1].even;
        hi = s->texs[d->albedo_texture - 1].odd;
    }
    if (pt_max_component(lo) > 1.0f || pt_max_component(hi) > 1.0f)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: rough plastic albedo above 1: the base reflects at most "
                                                      "what reaches it (and 1 - albedo R_int must stay > 0)");
    m->alpha = pt__maxf(d->roughness, PT__GGX_MIN_ALPHA);
    m->alpha2 = m->alpha * m->alpha;
    m->coat_ior = d->ior > 0.0f ? d->ior : 1.5f;
    m->coat_inv_ior2 = 1.0f / (m->coat_ior * m->coat_ior);
    m->nonlinear = d->nonlinear != 0;
    /* Mitsuba's specular sampling weight s / (d + s): s = 1 (no specular tint), d the mean albedo */
    m->coat_wspec = 1.0f / (1.0f + (lo.x + lo.y + lo.z + hi.x + hi.y + hi.z) / 6.0f);
    pt__coat_tables(m);
    return PT_OK;
}

/* Rough dielectric: roughness as the conductor's; ext_ior 0 (1) or like ior; the relative index
   ior / ext_ior must be finite and positive. */
static int pt__rough_dielectric_resolve(pt_scene *s, const pt_material_desc *d, pt__material *m)
{
    float ratio;
    if (!pt__isfinite(d->roughness) || d->roughness < 0.0f || d->roughness > 1.0f)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: roughness = %g: must be finite and in [0, 1]",
                        (double)d->roughness);
    if (!pt__isfinite(d->ext_ior) || d->ext_ior < 0.0f || (d->ext_ior > 0.0f && d->ext_ior < 1e-3f))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                        "material: ext_ior = %g: must be 0 (meaning 1) or finite and >= 0.001", (double)d->ext_ior);
    ratio = (d->ior > 0.0f ? d->ior : 1.5f) / (d->ext_ior > 0.0f ? d->ext_ior : 1.0f);
    if (!pt__isfinite(ratio) || !(ratio > 0.0f))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: ior / ext_ior = %g: must be finite and > 0",
                        (double)ratio);
    m->alpha = d->roughness;
    m->alpha2 = d->roughness * d->roughness;
    return PT_OK;
}

PTDEF int pt_scene_add_material(pt_scene *s, const pt_material_desc *d)
{
    pt__material m;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if (!d) return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: desc is NULL");
    memset(&m, 0, sizeof m);
    if ((int)d->type < (int)PT_MATERIAL_LAMBERTIAN || (int)d->type > (int)PT_MATERIAL_ROUGH_DIELECTRIC)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: unknown type %d", (int)d->type);
    if (!pt__color_ok(d->albedo))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: albedo must be finite and >= 0");
    if (!pt__color_ok(d->emission))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: emission must be finite and >= 0");
    if (d->albedo_texture < 0 || (uint32_t)d->albedo_texture > s->tex_count)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: texture %d does not exist", d->albedo_texture);
    if (!pt__isfinite(d->fuzz) || d->fuzz < 0.0f)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "material: fuzz must be finite and >= 0");
    if (!pt__isfinite(d->ior) || d->ior < 0.0f || (d->ior > 0.0f && d->ior < 1e-3f))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                        "material: ior = %g: must be 0 (meaning 1.5) or finite and >= 0.001", (double)d->ior);
    if (d->type == PT_MATERIAL_ROUGH_CONDUCTOR) {
        int rc = pt__conductor_resolve(s, d, &m);
        if (rc != PT_OK) return rc;
    }
    if (d->type == PT_MATERIAL_ROUGH_PLASTIC) {
        int rc = pt__plastic_resolve(s, d, &m);
        if (rc != PT_OK) return rc;
    }
    if (d->type == PT_MATERIAL_ROUGH_DIELECTRIC) {
        int rc = pt__rough_dielectric_resolve(s, d, &m);
        if (rc != PT_OK) return rc;
    }
    m.type = d->type;
    m.albedo = d->albedo;
    m.texture = d->albedo_texture;
    m.fuzz = pt__minf(d->fuzz, 1.0f);
    m.ior = d->ior > 0.0f ? d->ior : 1.5f;
    if (d->type == PT_MATERIAL_ROUGH_DIELECTRIC) m.ior /= d->ext_ior > 0.0f ? d->ext_ior : 1.0f; /* relative */
    m.emission = d->emission;
    m.two_sided = d->two_sided_emission != 0;
    m.emits = !pt__is_black(d->emission);
    m.scatters = d->type != PT_MATERIAL_EMITTER;
    m.delta = d->type == PT_MATERIAL_DIELECTRIC || (d->type == PT_MATERIAL_METAL && m.fuzz == 0.0f) ||
              (d->type == PT_MATERIAL_ROUGH_CONDUCTOR && m.alpha < PT__GGX_MIN_ALPHA) ||
              (d->type == PT_MATERIAL_ROUGH_DIELECTRIC &&
               (m.alpha < PT__GGX_MIN_ALPHA || m.alpha * fabsf(m.ior - 1.0f) < PT__GGX_MIN_ALPHA));
    m.transmits = d->type == PT_MATERIAL_ROUGH_DIELECTRIC && !m.delta;
    if (!pt__grow((void **)&s->mats, &s->mat_cap, s->mat_count + 1u, sizeof(pt__material)))
        return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "material: out of memory");
    s->mats[s->mat_count] = m;
    s->committed = 0;
    return (int)s->mat_count++;
}
PTDEF int pt_scene_add_lambertian(pt_scene *s, pt_color albedo)
{
    pt_material_desc d;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_LAMBERTIAN;
    d.albedo = albedo;
    return pt_scene_add_material(s, &d);
}
PTDEF int pt_scene_add_metal(pt_scene *s, pt_color albedo, float fuzz)
{
    pt_material_desc d;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_METAL;
    d.albedo = albedo;
    d.fuzz = fuzz;
    return pt_scene_add_material(s, &d);
}
PTDEF int pt_scene_add_dielectric(pt_scene *s, float ior)
{
    pt_material_desc d;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_DIELECTRIC;
    d.ior = ior; /* pt_scene_add_material checks it: 0 means 1.5, as in pt_material_desc */
    return pt_scene_add_material(s, &d);
}
PTDEF int pt_scene_add_emitter(pt_scene *s, pt_color radiance, int two_sided)
{
    pt_material_desc d;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_EMITTER;
    d.emission = radiance;
    d.two_sided_emission = two_sided;
    return pt_scene_add_material(s, &d);
}
PTDEF int pt_scene_add_rough_conductor(pt_scene *s, pt_conductor conductor, float roughness, pt_color tint)
{
    pt_material_desc d;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_ROUGH_CONDUCTOR;
    d.albedo = tint;
    d.conductor = conductor;
    d.roughness = roughness;
    return pt_scene_add_material(s, &d);
}
PTDEF int pt_scene_add_rough_plastic(pt_scene *s, pt_color albedo, float roughness, float ior)
{
    pt_material_desc d;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_ROUGH_PLASTIC;
    d.albedo = albedo;
    d.roughness = roughness;
    d.ior = ior;
    return pt_scene_add_material(s, &d);
}
PTDEF int pt_scene_add_rough_dielectric(pt_scene *s, float ior, float roughness)
{
    pt_material_desc d;
    memset(&d, 0, sizeof d);
    d.type = PT_MATERIAL_ROUGH_DIELECTRIC;
    d.ior = ior;
    d.roughness = roughness;
    return pt_scene_add_material(s, &d);
}
PTDEF int pt_scene_add_checker(pt_scene *s, pt_color even, pt_color odd, float scale)
{
    pt__texture t;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    memset(&t, 0, sizeof t);
    if (!pt__color_ok(even) || !pt__color_ok(odd) || !pt__isfinite(scale) || !(scale > 0.0f))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "checker: colours must be finite and >= 0, scale > 0");
    t.even = even;
    t.odd = odd;
    t.inv_scale = 1.0f / scale;
    if (!pt__grow((void **)&s->texs, &s->tex_cap, s->tex_count + 1u, sizeof(pt__texture)))
        return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "checker: out of memory");
    s->texs[s->tex_count++] = t;
    s->committed = 0;
    return (int)s->tex_count; /* ids start at 1; 0 means "no texture" */
}
/* Parity of floor(x/s) + floor(y/s) + floor(z/s), one term at a time so that large
   coordinates do not overflow an integer. */
static pt_color pt__checker(const pt__texture *t, pt_vec3 p)
{
    double fx = floor((double)p.x * t->inv_scale), fy = floor((double)p.y * t->inv_scale);
    double fz = floor((double)p.z * t->inv_scale);
    int parity = ((int)fmod(fabs(fx), 2.0) + (int)fmod(fabs(fy), 2.0) + (int)fmod(fabs(fz), 2.0)) & 1;
    return parity ? t->odd : t->even;
}
PTDEF int pt_scene_add_image_texture(pt_scene *s, const pt_image *img)
{
    pt__texture t;
    size_t i, n;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if (!img) return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "image texture: image is NULL");
    if (img->width < 1 || img->height < 1 || !img->rgb)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "image texture: image is %d x %d%s: needs at least 1 x 1 pixels",
                        img->width, img->height, img->rgb ? "" : " with no pixels (rgb NULL)");
    if ((uint64_t)img->width * (uint64_t)img->height > ((uint64_t)1 << 28))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "image texture: image is %d x %d: more than 2^28 pixels",
                        img->width, img->height);
    n = 3u * (size_t)img->width * (size_t)img->height;
    for (i = 0; i < n; ++i)
        if (!pt__isfinite(img->rgb[i]) || img->rgb[i] < 0.0f)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "image texture: image pixel (%d, %d) is not finite and >= 0",
                            (int)((i / 3u) % (size_t)img->width), (int)((i / 3u) / (size_t)img->width));
    memset(&t, 0, sizeof t);
    t.w = img->width;
    t.h = img->height;
    t.rgb = (float *)PT_MALLOC(n * sizeof(float));
    if (!t.rgb || !pt__grow((void **)&s->texs, &s->tex_cap, s->tex_count + 1u, sizeof(pt__texture))) {
        PT_FREE(t.rgb);
        return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "image texture: out of memory (%d x %d pixels)", img->width, img->height);
    }
    memcpy(t.rgb, img->rgb, n * sizeof(float));
    s->texs[s->tex_count++] = t;
    s->committed = 0;
    return (int)s->tex_count;
}
/* Texel index of coordinate x (pixel units, any real) wrapped into [0, n) (repeat). */
static int pt__wrap(double x, int n)
{
    double r = x - (double)n * floor(x / (double)n);
    int i = (int)r;
    return i < 0 ? 0 : i >= n ? n - 1 : i;
}
/* Bilinear lookup between pixel centres, repeated in u and v (Mitsuba 3's bitmap with
   filter_type bilinear and wrap_mode repeat: x = u W - 1/2, weights from its fraction). */
static pt_color pt__image_lookup(const pt__texture *t, float u, float v)
{
    double x = (double)u * t->w - 0.5, y = (double)v * t->h - 0.5, fx0, fy0;
    float fx, fy;
    int x0, x1, y0, y1;
    const float *a, *b, *c, *d;
    if (!(x == x) || !(y == y) || fabs(x) > 1e15 || fabs(y) > 1e15) return pt_v3(0, 0, 0);
    fx0 = floor(x);
    fy0 = floor(y);
    fx = (float)(x - fx0);
    fy = (float)(y - fy0);
    x0 = pt__wrap(fx0, t->w);
    x1 = x0 + 1 == t->w ? 0 : x0 + 1;
    y0 = pt__wrap(fy0, t->h);
    y1 = y0 + 1 == t->h ? 0 : y0 + 1;
    a = t->rgb + 3u * ((size_t)y0 * (size_t)t->w + (size_t)x0);
    b = t->rgb + 3u * ((size_t)y0 * (size_t)t->w + (size_t)x1);
    c = t->rgb + 3u * ((size_t)y1 * (size_t)t->w + (size_t)x0);
    d = t->rgb + 3u * ((size_t)y1 * (size_t)t->w + (size_t)x1);
    return pt_v3((1.0f - fy) * ((1.0f - fx) * a[0] + fx * b[0]) + fy * ((1.0f - fx) * c[0] + fx * d[0]),
                 (1.0f - fy) * ((1.0f - fx) * a[1] + fx * b[1]) + fy * ((1.0f - fx) * c[1] + fx * d[1]),
                 (1.0f - fy) * ((1.0f - fx) * a[2] + fx * b[2]) + fy * ((1.0f - fx) * c[2] + fx * d[2]));
}
PTDEF pt_color pt_scene_eval_texture(const pt_scene *s, int texture, pt_vec3 p)
{
    if (!s || texture < 1 || (uint32_t)texture > s->tex_count || s->texs[texture - 1].rgb) return pt_v3(0, 0, 0);
    return pt__checker(&s->texs[texture - 1], p);
}
PTDEF pt_color pt_scene_eval_texture_uv(const pt_scene *s, int texture, float u, float v)
{
    if (!s || texture < 1 || (uint32_t)texture > s->tex_count || !s->texs[texture - 1].rgb) return pt_v3(0, 0, 0);
    return pt__image_lookup(&s->texs[texture - 1], u, v);
}
PTDEF int pt_material_is_delta(const pt_scene *s, int material)
{
    if (!s || material < 0 || (uint32_t)material >= s->mat_count) return 0;
    return s->mats[material].delta || !s->mats[material].scatters;
}
/* --- delta lights (pt_scene_add_light) --- */
/* The spot's shortcuts for pt__spot_falloff: an angle whose tangent (sin over a positive cos) is
   below tan_in is inside the beam, one whose tangent is above tan_out is outside the cone. Each
   bound is 1e-4 of the angle inside its edge, far beyond the few float ulps of atan2f's error
   and the float products' and bounds' rounding, so atan2f would compare alike; tan_in 0 and
   tan_out infinite turn them off (a beam too narrow for a relative margin, a cone near 90
   degrees). */
static void pt__spot_bounds(pt__dlight *l)
{
    double in = (double)l->beam * (1.0 - 1e-4), out = (double)l->cutoff * (1.0 + 1e-4);
    l->tan_in = l->beam >= 1e-6f ? (float)tan(in) : 0.0f;
    l->tan_out = out < 1.5 ? (float)tan(out) : (float)HUGE_VAL;
}
PTDEF int pt_scene_add_light(pt_scene *s, const pt_light_desc *d)
{
    pt__dlight l;
    const float deg = 0.017453292519943295f;
    int positioned, directed;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if (!d) return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "light: the pt_light_desc is NULL");
    if (d->type != PT_LIGHT_POINT && d->type != PT_LIGHT_SPOT && d->type != PT_LIGHT_DIRECTIONAL)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "light: type = %d: must be PT_LIGHT_POINT, _SPOT or _DIRECTIONAL",
                        (int)d->type);
    if (!pt__color_ok(d->intensity) || pt__is_black(d->intensity))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "light: intensity must be finite, >= 0 and not all zero");
    memset(&l, 0, sizeof l);
    l.desc = *d;
    positioned = d->type != PT_LIGHT_DIRECTIONAL;
    directed = d->type != PT_LIGHT_POINT;
    if (positioned) {
        if (!pt__vfinite(d->position) || pt__vmaxabs(d->position) > PT__MAX_COORD)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "light: position must be finite, within %g",
                            (double)PT__MAX_COORD);
        l.desc.position = s->xf_identity ? d->position : pt_transform_point(&s->xf, d->position);
        if (!pt__vfinite(l.desc.position) || pt__vmaxabs(l.desc.position) > PT__MAX_COORD)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "light: position beyond %g after the scene's transform",
                            (double)PT__MAX_COORD);
    } else {
        l.desc.position = pt_v3(0, 0, 0);
    }
    if (directed) {
        pt_vec3 a = d->direction;
        float len;
        if (!pt__vfinite(a) || !(pt_length2(a) > 0.0f))
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "light: direction must be finite and non-zero");
        if (!s->xf_identity) a = pt_transform_vector(&s->xf, a);
        len = pt_length(a);
        if (!(len > 0.0f) || !pt__isfinite(len))
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "light: direction is zero or overflows after the transform");
        l.axis = pt_scale(a, 1.0f / len);
        l.desc.direction = l.axis;
    } else {
        l.desc.direction = pt_v3(0, 0, 0);
    }
    if (d->type == PT_LIGHT_SPOT) {
        float c = d->cutoff_angle == 0.0f ? 20.0f : d->cutoff_angle, b;
        if (!pt__isfinite(c) || !(c > 0.0f) || c > 90.0f)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "light: cutoff_angle = %g: must be in (0, 90] degrees (0: 20)",
                            (double)d->cutoff_angle);
        b = d->beam_width == 0.0f ? 0.75f * c : d->beam_width;
        if (!pt__isfinite(b) || !(b > 0.0f) || b > c)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                            "light: beam_width = %g: must be in (0, cutoff_angle = %g] degrees (0: 3/4 of it)",
                            (double)d->beam_width, (double)c);
        l.desc.cutoff_angle = c;
        l.desc.beam_width = b;
        l.cutoff = c * deg;
        l.beam = b * deg;
        l.inv_transition = b < c ? 1.0f / (l.cutoff - l.beam) : 0.0f;
        pt__spot_bounds(&l);
    } else {
        l.desc.cutoff_angle = l.desc.beam_width = 0.0f;
    }
    if (!pt__grow((void **)&s->dlights, &s->dlight_cap, s->dlight_count + 1u, sizeof(pt__dlight)))
        return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "light: out of memory");
    s->dlights[s->dlight_count] = l;
    s->committed = 0;
    return (int)s->dlight_count++;
}
PTDEF int pt_scene_get_light(const pt_scene *s, int id, pt_light_desc *light)
{
    if (!s || !light || id < 0 || (uint32_t)id >= s->dlight_count) return PT_ERROR_INVALID_ARGUMENT;
    *light = s->dlights[id].desc;
    return PT_OK;
}
static void pt__env_free(pt__env *e)
{
    if (!e) return;
    PT_FREE(e->rgb);
    PT_FREE(e->row_cdf);
    PT_FREE(e->col_cdf);
    PT_FREE(e->cell_density);
    PT_FREE(e->row_guide);
    PT_FREE(e->col_guide);
    PT_FREE(e->cos_edge);
    PT_FREE(e);
}
/* guide[k] = the first i in [0, n) with cdf[i + 1] > k / n (n - 1 if none), k = 0 .. n. */
static void pt__cdf_guide(const float *cdf, int n, int *guide)
{
    int k, i = 0;
    for (k = 0; k <= n; ++k) {
        float u = (float)k / (float)n;
        while (i < n - 1 && !(cdf[i + 1] > u)) ++i;
        guide[k] = i;
    }
}
/* The sampling tables of e (pixels set): each cell's weight is the mean luminance over it of
   the bilinear interpolant, the pixel's luminance filtered by [1/8, 3/4, 1/8] in x (periodic)
   and in y (held at the first and last rows); positive wherever the radiance is. */
static void pt__env_tables(pt__env *e, double *lum, double *row_w)
{
    const int w = e->w, h = e->h;
    const double k[3] = { 0.125, 0.75, 0.125 }, pi = 3.14159265358979323846;
    double total = 0.0, acc, sum = 0.0;
    int x, y, i, j;
    for (y = 0; y < h; ++y)
        for (x = 0; x < w; ++x) {
            const float *c = e->rgb + 3 * ((size_t)y * (size_t)w + (size_t)x);
            sum += ((double)c[0] + (double)c[1] + (double)c[2]) / 3.0 *
                   (cos(pi * y / h) - cos(pi * (y + 1) / h)); /* (x 2 pi / w, below) */
        }
    e->mean = sum * (2.0 * pi / w) / (4.0 * pi);
    for (y = 0; y <= h; ++y) e->cos_edge[y] = cos(pi * y / h);
    for (y = 0; y < h; ++y) {
        double rw = 0.0;
        float *cc = e->col_cdf + (size_t)y * (size_t)(w + 1);
        for (x = 0; x < w; ++x) {
            double f = 0.0;
            for (j = -1; j <= 1; ++j) {
                int yy = y + j < 0 ? 0 : (y + j > h - 1 ? h - 1 : y + j);
                for (i = -1; i <= 1; ++i) {
                    int xx = (x + i + w) % w;
                    f += k[j + 1] * k[i + 1] * pt__env_luminance(e->rgb + 3 * ((size_t)yy * (size_t)w + (size_t)xx));
                }
            }
            lum[x] = f;
            rw += f;
        }
        acc = 0.0;
        cc[0] = 0.0f;
        for (x = 0; x < w; ++x) {
            acc += lum[x];
            cc[x + 1] = rw > 0.0 ? (float)(acc / rw) : 0.0f;
        }
        if (rw > 0.0) cc[w] = 1.0f;
        row_w[y] = rw * (e->cos_edge[y] - e->cos_edge[y + 1]);
        total += row_w[y];
    }
    acc = 0.0;
    e->row_cdf[0] = 0.0f;
    for (y = 0; y < h; ++y) {
        acc += row_w[y];
        e->row_cdf[y + 1] = total > 0.0 ? (float)(acc / total) : 0.0f;
    }
    if (total > 0.0) e->row_cdf[h] = 1.0f;
    pt__cdf_guide(e->row_cdf, h, e->row_guide);
    for (y = 0; y < h; ++y)
        pt__cdf_guide(e->col_cdf + (size_t)y * (size_t)(w + 1), w, e->col_guide + (size_t)y * (size_t)(w + 1));
    /* each cell's density from the stored (float) tables, so that it is exactly what sampling does */
    for (y = 0; y < h; ++y) {
        const float *cc = e->col_cdf + (size_t)y * (size_t)(w + 1);
        double omega = (2.0 * pi / w) * (e->cos_edge[y] - e->cos_edge[y + 1]);
        double pr = (double)e->row_cdf[y + 1] - (double)e->row_cdf[y];
        for (x = 0; x < w; ++x) {
            double p = pr * ((double)cc[x + 1] - (double)cc[x]) / omega;
            e->cell_density[(size_t)y * (size_t)w + (size_t)x] = p > 0.0 && p < 3.4e38 ? (float)p : 0.0f;
        }
    }
}
/* The rotation part of t, if it is one (orthonormal rows within 1e-4, determinant > 0). */
static int pt__rotation_of(const pt_transform *t, float r[3][3])
{
    int i, j, k;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) r[i][j] = t->m[i][j];
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 3; ++j) {
            double d = 0.0;
            for (k = 0; k < 3; ++k) d += (double)r[k][i] * r[k][j];
            if (!(fabs(d - (i == j ? 1.0 : 0.0)) <= 1e-4)) return 0;
        }
    return pt__transform_det(t) > 0.0f;
}
PTDEF int pt_scene_set_environment(pt_scene *s, const pt_environment_desc *d)
{
    pt__env *e;
    const pt_image *img;
    size_t n, i;
    double *tmp;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if (!d || !d->map) {
        pt__env_free(s->env);
        s->env = NULL;
        s->committed = 0;
        return PT_OK;
    }
    img = d->map;
    if (img->width < 2 || img->height < 2 || img->width > (1 << 16) || img->height > (1 << 16) || !img->rgb)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                        "environment: map is %d x %d%s: it needs 2 .. 65536 pixels on each side, and pixels",
                        img->width, img->height, img->rgb ? "" : " without pixels (rgb NULL)");
    if (!pt__isfinite(d->scale) || d->scale < 0.0f)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "environment: scale = %g: must be finite and > 0 (0: 1)",
                        (double)d->scale);
    n = (size_t)img->width * (size_t)img->height;
    for (i = 0; i < 3 * n; ++i)
        if (!pt__isfinite(img->rgb[i]) || img->rgb[i] < 0.0f)
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                            "environment: map pixel (%d, %d) channel %d = %g: must be finite and >= 0",
                            (int)(i / 3 % (size_t)img->width), (int)(i / 3 / (size_t)img->width), (int)(i % 3),
                            (double)img->rgb[i]);
    e = (pt__env *)PT_MALLOC(sizeof *e);
    if (!e) return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "environment: out of memory");
    memset(e, 0, sizeof *e);
    if (!pt__rotation_of(&s->xf, e->rot)) {
        PT_FREE(e);
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT,
                        "environment: the scene's current transform is not a rotation (an environment can only be turned)");
    }
    e->w = img->width;
    e->h = img->height;
    e->scale = d->scale == 0.0f ? 1.0f : d->scale;
    e->rgb = (float *)PT_MALLOC(3 * n * sizeof(float));
    e->row_cdf = (float *)PT_MALLOC((size_t)(e->h + 1) * sizeof(float));
    e->col_cdf = (float *)PT_MALLOC((size_t)e->h * (size_t)(e->w + 1) * sizeof(float));
    e->cell_density = (float *)PT_MALLOC(n * sizeof(float));
    e->cos_edge = (double *)PT_MALLOC((size_t)(e->h + 1) * sizeof(double));
    e->row_guide = (int *)PT_MALLOC((size_t)(e->h + 1) * sizeof(int));
    e->col_guide = (int *)PT_MALLOC((size_t)e->h * (size_t)(e->w + 1) * sizeof(int));
    tmp = (double *)PT_MALLOC((size_t)(e->w + e->h) * sizeof(double));
    if (!e->rgb || !e->row_cdf || !e->col_cdf || !e->cell_density || !e->cos_edge || !e->row_guide || !e->col_guide ||
        !tmp) {
        PT_FREE(tmp);
        pt__env_free(e);
        return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "environment: out of memory (%d x %d map)", img->width, img->height);
    }
    for (i = 0; i < 3 * n; ++i) {
        e->rgb[i] = img->rgb[i] * e->scale;
        if (!pt__isfinite(e->rgb[i])) {
            PT_FREE(tmp);
            pt__env_free(e);
            return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "environment: scale = %g overflows the map's pixel %d",
                            (double)d->scale, (int)(i / 3));
        }
    }
    pt__env_tables(e, tmp, tmp + e->w);
    PT_FREE(tmp);
    pt__env_free(s->env);
    s->env = e;
    s->committed = 0;
    return PT_OK;
}
PTDEF pt_color pt_scene_environment_radiance(const pt_scene *s, pt_vec3 dir)
{
    float len2 = pt_length2(dir);
    if (!s || !s->env || !pt__vfinite(dir) || !(len2 > 0.0f)) return pt_v3(0, 0, 0);
    return pt__env_map_radiance(s->env, pt_scale(dir, 1.0f / sqrtf(len2)));
}
/* A spot's falloff toward unit w (from the light): Mitsuba 3's `spot`, linear in the angle. The
   angle is atan2(|axis x w|, axis . w), exact for small angles too, where acos of a dot product is
   not (cos 0.01 degrees rounds to 1 in float). */
static float pt__spot_falloff(const pt__dlight *l, pt_vec3 w)
{
    float sn = pt_length(pt_cross(l->axis, w)), cs = pt_dot(l->axis, w), a;
    /* the angle atan2f(sn, cs) is well inside the beam or well outside the cone: the comparisons
       below give what they would give on atan2f's result, without it */
    if (cs > 0.0f && sn >= 0.0f && sn <= FLT_MAX) {
        if (sn < cs * l->tan_in) return 1.0f;
        if (sn > cs * l->tan_out) return 0.0f;
    } else if (cs <= 0.0f && l->tan_out <= FLT_MAX) {
        return 0.0f; /* 90 degrees or more (atan2f's few ulps under pi/2 included), the cone narrower */
    }
    a = atan2f(sn, cs);
    if (a <= l->beam) return 1.0f;
    if (!(a < l->cutoff)) return 0.0f;
    return pt__minf(1.0f, (l->cutoff - a) * l->inv_transition);
}
/* Radiant power, to pick among more than PT__DELTA_PICK_MAX delta lights: 4 pi I for a point, I
   times the solid angle of the cone to the middle of the falloff for a spot, and E times the
   cross-section of the scene's bounding sphere (radius r) for a directional light. */
static double pt__dlight_power(const pt__dlight *l, double r)
{
    double i = ((double)l->desc.intensity.x + (double)l->desc.intensity.y + (double)l->desc.intensity.z) / 3.0;
    if (l->desc.type == PT_LIGHT_POINT) return 4.0 * 3.14159265358979323846 * i;
    if (l->desc.type == PT_LIGHT_SPOT)
        return 2.0 * 3.14159265358979323846 * i *
               (1.0 - cos(0.5 * ((double)l->desc.cutoff_angle + (double)l->desc.beam_width) * 0.017453292519943295));
    return 3.14159265358979323846 * r * r * i;
}

/* The albedo at hit h of primitive p (bary: a triangle's weights): a checker at the world
   point, an image at the hit's (u, v), computed here only. */
static pt_color pt__albedo(const pt_scene *s, const pt__material *m, const pt__prim *p, const float *bary, const pt_hit *h)
{
    const pt__texture *t;
    float u, v;
    if (!m->texture) return m->albedo;
    t = &s->texs[m->texture - 1];
    if (!t->rgb) return pt__checker(t, pt__to_world(s, h->point));
    pt__hit_uv(s, p, bary, h, &u, &v);
    return pt__image_lookup(t, u, v);
}

/* Exact unpolarised Fresnel reflectance of a conductor of relative index eta + i k at cos_i in
   [0, 1], in the real form with a^2 + b^2 = |eta^2 - sin^2|  (Pharr, Jakob & Humphreys, PBR 3rd
   ed., sec. 8.2.1): no complex arithmetic, and exact for k = 0 too. */
static float pt__fresnel_conductor(float cos_i, float eta, float k)
{
    float c2 = cos_i * cos_i, s2 = 1.0f - c2, t = eta * eta - k * k - s2;
    float ab2 = sqrtf(t * t + 4.0f * eta * eta * k * k), a = pt__safe_sqrt(0.5f * (ab2 + t));
    float t1 = ab2 + c2, t2 = 2.0f * a * cos_i, rs = (t1 - t2) / (t1 + t2);
    float t3 = ab2 * c2 + s2 * s2, t4 = t2 * s2, rp = rs * (t3 - t4) / (t3 + t4);
    return 0.5f * (rs + rp);
}
static pt_color pt__conductor_fresnel_rgb(const pt__material *m, float cos_i)
{
    cos_i = pt__minf(1.0f, pt__maxf(0.0f, cos_i));
    if (!m->fresnel) return pt_v3(1.0f, 1.0f, 1.0f);
    return pt_v3(pt__fresnel_conductor(cos_i, m->eta.x, m->k.x), pt__fresnel_conductor(cos_i, m->eta.y, m->k.y),
                 pt__fresnel_conductor(cos_i, m->eta.z, m->k.z));
}
PTDEF pt_color pt_material_conductor_fresnel(const pt_scene *s, int material, float cos_theta)
{
    if (!s || material < 0 || (uint32_t)material >= s->mat_count || !pt__isfinite(cos_theta) ||
        s->mats[material].type != PT_MATERIAL_ROUGH_CONDUCTOR)
        return pt_v3(0, 0, 0);
    return pt__conductor_fresnel_rgb(&s->mats[material], cos_theta);
}
static pt_vec3 pt__onb_local(const pt_onb *b, pt_vec3 w) { return pt_v3(pt_dot(w, b->s), pt_dot(w, b->t), pt_dot(w, b->n)); }
/* The rough conductor's A * pScatter = albedo F D G1(wo) G1(wi) / (4 cos_o) (pt_material_desc). */
static pt_color pt__conductor_eval(const pt__material *m, pt_color tint, pt_vec3 ns, pt_vec3 wo, pt_vec3 wi)
{
    pt_onb b = pt__onb(ns);
    pt_vec3 o = pt__onb_local(&b, wo), i = pt__onb_local(&b, wi), h;
    float g;
    if (!(o.z > 0.0f) || !(i.z > 0.0f)) return pt_v3(0, 0, 0);
    h = pt_normalize(pt_add(o, i));
    g = pt__ggx_d(h, m->alpha2) * pt__ggx_g1(o, m->alpha2) * pt__ggx_g1(i, m->alpha2) / (4.0f * o.z);
    return pt_scale(pt_mul(tint, pt__conductor_fresnel_rgb(m, pt_dot(o, h))), g);
}
/* The coat's transmittance at cosine mu (the table, linear in mu) and the specular share of the
   sampling mixture seen from a direction of transmittance t: Mitsuba's weight w moved by the
   coat's reflectance there, (1 - t) w / ((1 - t) w + t (1 - w)). */
static float pt__coat_t(const pt__material *m, float mu)
{
    float x = pt__minf(1.0f, pt__maxf(0.0f, mu)) * (float)(PT__COAT_RES - 1);
    int i = (int)x;
    if (i > PT__COAT_RES - 2) i = PT__COAT_RES - 2;
    return m->coat_t[i] + (x - (float)i) * (m->coat_t[i + 1] - m->coat_t[i]);
}
static float pt__coat_spec_share(const pt__material *m, float mu_o)
{
    float t = pt__coat_t(m, mu_o), sp = (1.0f - t) * m->coat_wspec, df = t * (1.0f - m->coat_wspec);
    return sp + df > 0.0f ? sp / (sp + df) : 1.0f;
}
/* The rough plastic's A * pScatter (pt_material_desc): the coat's GGX reflection plus the base
   seen through it. */
static pt_color pt__plastic_eval(const pt__material *m, pt_color rho, pt_vec3 ns, pt_vec3 wo, pt_vec3 wi)
{
    pt_onb b = pt__onb(ns);
    pt_vec3 o = pt__onb_local(&b, wo), i = pt__onb_local(&b, wi), h;
    float ct = 0.0f, F, spec, k;
    pt_color diff;
    if (!(o.z > 0.0f) || !(i.z > 0.0f)) return pt_v3(0, 0, 0);
    h = pt_normalize(pt_add(o, i));
    F = pt__fresnel_dielectric(pt__minf(1.0f, pt__maxf(0.0f, pt_dot(o, h))), 1.0f / m->coat_ior, &ct);
    spec = F * pt__ggx_d(h, m->alpha2) * pt__ggx_g1(o, m->alpha2) * pt__ggx_g1(i, m->alpha2) / (4.0f * o.z);
    k = pt__coat_t(m, o.z) * pt__coat_t(m, i.z) * i.z * m->coat_inv_ior2 * PT__INV_PI;
    if (m->nonlinear)
        diff = pt_v3(rho.x / (1.0f - rho.x * m->coat_rint), rho.y / (1.0f - rho.y * m->coat_rint),
                     rho.z / (1.0f - rho.z * m->coat_rint));
    else
        diff = pt_scale(rho, 1.0f / (1.0f - m->coat_rint));
    return pt_add(pt_scale(diff, k), pt_v3(spec, spec, spec));
}
/* The mixture's density: the visible normals with the specular share, the cosine lobe otherwise. */
static float pt__plastic_density(const pt__material *m, pt_vec3 ns, pt_vec3 wo, pt_vec3 wi)
{
    pt_onb b = pt__onb(ns);
    pt_vec3 o = pt__onb_local(&b, wo), i = pt__onb_local(&b, wi);
    float ps;
    if (!(o.z > 0.0f) || !(i.z > 0.0f)) return 0.0f;
    ps = pt__coat_spec_share(m, o.z);
    return ps * pt__ggx_reflect_density(o, i, m->alpha2) + (1.0f - ps) * i.z * PT__INV_PI;
}
/* One draw of the mixture: u1 picks the lobe and is stretched back onto [0, 1) for it. */
static int pt__plastic_sample(const pt__material *m, pt_vec3 ns, pt_vec3 wo, float u1, float u2, pt_vec3 *wi, float *pdf)
{
    pt_onb b = pt__onb(ns);
    pt_vec3 o = pt__onb_local(&b, wo), i;
    float ps;
    if (!(o.z > 0.0f)) return 0;
    ps = pt__coat_spec_share(m, o.z);
    if (u1 < ps) {
        i = pt__reflect(o, pt__ggx_sample_vn(o, m->alpha, pt__minf(u1 / ps, 0.99999994f), u2));
    } else {
        i = pt__cosine_hemisphere(pt__minf((u1 - ps) / (1.0f - ps), 0.99999994f), u2);
    }
    if (!(i.z > 0.0f)) return 0;
    *wi = pt_normalize(pt_onb_to_world(&b, i));
    *pdf = pt__plastic_density(m, ns, wo, *wi);
    return *pdf > 0.0f;
}

static float pt__fresnel_dielectric(float cos_i, float eta, float *cos_t);
/* The rough dielectric in the local frame of the shading normal on wo's side (o.z > 0), eta =
   n_far / n_near (pt_material_desc). A transmission's microfacet normal is the generalised half
   vector m = +-(o + eta i) / |o + eta i| on the normal's side (Walter et al. 2007, eq. 16); it is
   valid when o.m > 0 > i.m (each direction on its own side of the microfacet, as Smith's G1 of
   Mitsuba 3 requires). Returns 0 when it is not (or o + eta i vanishes: eta 1 along -o). */
static int pt__ggx_refract_half(pt_vec3 o, pt_vec3 i, float eta, pt_vec3 *m)
{
    pt_vec3 h = pt_add(o, pt_scale(i, eta));
    float l2 = pt_length2(h);
    if (!(l2 > 0.0f)) return 0;
    h = pt_scale(h, 1.0f / sqrtf(l2));
    if (h.z < 0.0f) h = pt_neg(h);
    *m = h;
    return pt_dot(o, h) > 0.0f && pt_dot(i, h) < 0.0f;
}
/* A pScatter (the BSDF times cos_i, 1 / eta^2 on transmission: pt_material_desc) and the density
   of the visible-normal sampler (D_v(m) times F or 1 - F, times the Jacobian of m -> i: 1 / (4 o.m)
   for reflection, eta^2 |i.m| / (o.m + eta i.m)^2 for refraction). *pdf may be NULL. */
static float pt__rough_dielectric_local(const pt__material *m, float eta, pt_vec3 o, pt_vec3 i, float *pdf)
{
    pt_vec3 h, ib;
    float F, ct = 0.0f, om, im, den, g1o;
    if (pdf) *pdf = 0.0f;
    if (!(o.z > 0.0f) || i.z == 0.0f || !(i.z == i.z)) return 0.0f;
    g1o = pt__ggx_g1(o, m->alpha2);
    if (i.z > 0.0f) {
        float d;
        h = pt_normalize(pt_add(o, i));
        om = pt_dot(o, h);
        F = pt__fresnel_dielectric(om, 1.0f / eta, &ct);
        d = pt__ggx_d(h, m->alpha2) * g1o / (4.0f * o.z);
        if (pdf) *pdf = F * d;
        return F * d * pt__ggx_g1(i, m->alpha2);
    }
    if (!pt__ggx_refract_half(o, i, eta, &h)) return 0.0f;
    om = pt_dot(o, h);
    im = pt_dot(i, h);
    F = pt__fresnel_dielectric(om, 1.0f / eta, &ct);
    den = om + eta * im;
    if (!(den * den > 0.0f)) return 0.0f;
    ib = pt_v3(i.x, i.y, -i.z); /* G1 depends on the angle to the normal alone */
    {
        float t = (1.0f - F) * pt__ggx_d(h, m->alpha2) * g1o * om * -im / (o.z * den * den);
        if (pdf) *pdf = t * eta * eta;
        return t * pt__ggx_g1(ib, m->alpha2);
    }
}
/* A visible normal of o, then reflection with probability F(o.m), else refraction through it.
   Returns 0 when the direction leaves on the wrong side. */
static int pt__rough_dielectric_sample_local(const pt__material *m, float eta, pt_vec3 o, float u1, float u2,
                                             float u3, pt_vec3 *i)
{
    pt_vec3 mn = pt__ggx_sample_vn(o, m->alpha, u1, u2);
    float c = pt_dot(o, mn), ct = 0.0f, F, r = 1.0f / eta;
    if (!(c > 0.0f)) return 0;
    F = pt__fresnel_dielectric(pt__minf(c, 1.0f), r, &ct);
    if (u3 < F) {
        *i = pt__reflect(o, mn);
        return i->z > 0.0f;
    }
    *i = pt_add(pt_scale(o, -r), pt_scale(mn, r * c - ct));
    return i->z < 0.0f;
}
/* What a delta material's reflection multiplies the throughput by: the albedo, times the Fresnel
   reflectance at cos_i for the rough conductor below PT__GGX_MIN_ALPHA. */
static pt_color pt__delta_reflectance(const pt__material *m, pt_color albedo, float cos_i)
{
    if (m->type == PT_MATERIAL_ROUGH_CONDUCTOR) return pt_mul(albedo, pt__conductor_fresnel_rgb(m, cos_i));
    return albedo;
}

/* A * pScatter(wi) = BRDF * cos for a non-delta material, with ns and ng the shading and
   geometric normals already flipped to the side of wo. Directions below the geometric
   surface carry nothing. */
static PT__HOT pt_color pt__material_eval(const pt__material *m, pt_color albedo, pt_vec3 ns, pt_vec3 ng, pt_vec3 wo,
                                  pt_vec3 wi, float eta)
{
    if (PT__UNLIKELY(m->transmits)) {
        /* below ng only by transmission, and on the same side of ns as of ng (no light leaks
           between the shading and the geometric surface) */
        pt_onb b = pt__onb(ns);
        float cg = pt_dot(ng, wi), cs;
        pt_vec3 i = pt__onb_local(&b, wi);
        cs = i.z;
        if (!(cg * cs > 0.0f)) return pt_v3(0, 0, 0);
        return pt_scale(pt_v3(1, 1, 1), pt__rough_dielectric_local(m, eta, pt__onb_local(&b, wo), i, NULL));
    }
    if (pt_dot(ng, wi) <= 0.0f) return pt_v3(0, 0, 0);
    if (m->type == PT_MATERIAL_LAMBERTIAN) {
        float c = pt_dot(ns, wi);
        return c > 0.0f ? pt_scale(albedo, c * PT__INV_PI) : pt_v3(0, 0, 0);
    }
    if (m->type == PT_MATERIAL_METAL && m->fuzz > 0.0f)
        return pt_scale(albedo, pt__fuzz_value(pt__reflect(wo, ns), m->fuzz, wi));
    if (m->type == PT_MATERIAL_ROUGH_CONDUCTOR && !m->delta) return pt__conductor_eval(m, albedo, ns, wo, wi);
    if (m->type == PT_MATERIAL_ROUGH_PLASTIC) return pt__plastic_eval(m, albedo, ns, wo, wi);
    return pt_v3(0, 0, 0);
}
/* The density with which the material samples wi (ns flipped to the side of wo). */
static float pt__material_density(const pt__material *m, pt_vec3 ns, pt_vec3 wo, pt_vec3 wi, float eta)
{
    if (m->type == PT_MATERIAL_LAMBERTIAN) return pt__maxf(0.0f, pt_dot(ns, wi)) * PT__INV_PI;
    if (m->type == PT_MATERIAL_METAL && m->fuzz > 0.0f) return pt__fuzz_value(pt__reflect(wo, ns), m->fuzz, wi);
    if (m->type == PT_MATERIAL_ROUGH_CONDUCTOR && !m->delta) {
        pt_onb b = pt__onb(ns);
        return pt__ggx_reflect_density(pt__onb_local(&b, wo), pt__onb_local(&b, wi), m->alpha2);
    }
    if (m->type == PT_MATERIAL_ROUGH_PLASTIC) return pt__plastic_density(m, ns, wo, wi);
    if (m->transmits) {
        pt_onb b = pt__onb(ns);
        float p;
        pt__rough_dielectric_local(m, eta, pt__onb_local(&b, wo), pt__onb_local(&b, wi), &p);
        return p;
    }
    return 0.0f;
}
static PT__HOT int pt__material_sample_dir(const pt__material *m, pt_vec3 ns, pt_vec3 wo, float eta, float u1, float u2,
                                           float u3, pt_vec3 *wi, float *pdf)
{
    if (m->type == PT_MATERIAL_LAMBERTIAN) {
        /* not normalized again: the point is on the unit hemisphere and the basis orthonormal to a
           few ulps, so |wi| = 1 within 4e-7 (3 ulps, the most seen over 2e7 normals and draws),
           and the square root and division sat on every path's critical chain
           (bench/README.md, "Per-vertex work") */
        pt_onb b = pt__onb(ns);
        *wi = pt_onb_to_world(&b, pt__cosine_hemisphere(u1, u2));
        *pdf = pt__maxf(0.0f, pt_dot(ns, *wi)) * PT__INV_PI;
        return *pdf > 0.0f;
    }
    if (m->type == PT_MATERIAL_METAL && m->fuzz > 0.0f) {
        pt_vec3 r = pt__reflect(wo, ns);
        *wi = pt__fuzz_sample(r, m->fuzz, u1, u2, u3);
        *pdf = pt__fuzz_value(r, m->fuzz, *wi);
        return *pdf > 0.0f;
    }
    if (m->type == PT_MATERIAL_ROUGH_CONDUCTOR && !m->delta) {
        /* a visible normal, reflected; below the surface the draw fails (the energy the
           single-scattering model loses). The density is evaluated from the returned direction,
           so it equals pt__material_density exactly. */
        pt_onb b = pt__onb(ns);
        pt_vec3 o = pt__onb_local(&b, wo), mn, i;
        if (!(o.z > 0.0f)) return 0;
        mn = pt__ggx_sample_vn(o, m->alpha, u1, u2);
        i = pt__reflect(o, mn);
        if (!(i.z > 0.0f)) return 0;
        *wi = pt_normalize(pt_onb_to_world(&b, i));
        *pdf = pt__material_density(m, ns, wo, *wi, eta);
        return *pdf > 0.0f;
    }
    if (m->transmits) {
        pt_onb b = pt__onb(ns);
        pt_vec3 o = pt__onb_local(&b, wo), i;
        if (!(o.z > 0.0f) || !pt__rough_dielectric_sample_local(m, eta, o, u1, u2, u3, &i)) return 0;
        *wi = pt_normalize(pt_onb_to_world(&b, i));
        *pdf = pt__material_density(m, ns, wo, *wi, eta);
        return *pdf > 0.0f;
    }
    if (m->type == PT_MATERIAL_ROUGH_PLASTIC) return pt__plastic_sample(m, ns, wo, u1, u2, wi, pdf);
    return 0;
}
/* The public material PDF: n is the surface's outward normal (a rough dielectric's inside is
   behind it), turned to wo's side here. */
static int pt__material_pdf_sample(const pt_scene *s, int material, pt_vec3 n, pt_vec3 wo, float u1, float u2,
                                   float u3, pt_vec3 *dir, float *pdf)
{
    const pt__material *m = &s->mats[material];
    float eta = m->ior;
    if (pt_dot(n, wo) < 0.0f) { n = pt_neg(n); eta = 1.0f / eta; }
    if (m->delta || !m->scatters) return 0;
    return pt__material_sample_dir(m, n, wo, eta, u1, u2, u3, dir, pdf);
}
static float pt__material_pdf_value(const pt_scene *s, int material, pt_vec3 n, pt_vec3 wo, pt_vec3 w)
{
    const pt__material *m = &s->mats[material];
    float eta = m->ior;
    if (pt_dot(n, wo) < 0.0f) { n = pt_neg(n); eta = 1.0f / eta; }
    if (m->delta || !m->scatters) return 0.0f;
    return pt__material_density(m, n, wo, w, eta);
}

/* Exact Fresnel reflectance of a dielectric interface for unpolarised light; eta = n_i/n_t.
   Returns 1 under total internal reflection and then leaves *cos_t untouched. */
static float pt__fresnel_dielectric(float cos_i, float eta, float *cos_t)
{
    float sin2_t = eta * eta * (1.0f - cos_i * cos_i), ct, rs, rp;
    if (sin2_t >= 1.0f) return 1.0f;
    ct = pt__safe_sqrt(1.0f - sin2_t);
    rs = (eta * cos_i - ct) / (eta * cos_i + ct);
    rp = (cos_i - eta * ct) / (cos_i + eta * ct);
    *cos_t = ct;
    return 0.5f * (rs * rs + rp * rp);
}

/* ------------------------------------------------------------------------------------------
   5. BVH: a 4-wide BVH collapsed from a binary one built with the binned surface area
   heuristic (Wald, "On fast Construction of SAH-based Bounding Volume Hierarchies", IEEE RT
   2007): centroids binned into 16 bins per axis, the split of least SAH cost taken. The
   intersection cost is counted per block of four triangles, the unit a leaf tests at once.
   The binary tree is then collapsed into nodes of up to four children, always opening the
   child of largest surface area (Wald, Benthin & Boulos, "Getting Rid of Packets", IEEE RT
   2008; Dammertz, Hanika & Keller, "Shallow Bounding Volume Hierarchies for Fast SIMD Ray
   Tracing of Incoherent Rays", EGSR 2008). A node holds its children's boxes side by side,
   so that one SSE slab test (Kay & Kajiya 1986) tests all four; a leaf holds its triangles
   in blocks of four, intersected together with the watertight test of Woop, Benthin & Wald
   (JCGT 2(1), 2013) and giving bit for bit the scalar test's result (lanes whose edge
   function is exactly zero go to the scalar test, which redoes it in double); quads likewise
   in blocks of four with the scalar quad test's operations (lanes within the edge margin go
   to the scalar test), and spheres in blocks of four with the scalar sphere test's (lanes of
   tiny or distant spheres go to its double-precision path; a block of one sphere is tested
   by the scalar test alone).
   Traversal (single rays) visits the hit children nearest first and keeps the others on a
   stack with their entry distances; the near plane of each slab is chosen once per ray from
   the sign of the direction. Box tests widen the exit distance by 1 + 2 gamma(3) (Ize,
   "Robust BVH Ray Traversal", JCGT 2(2), 2013) and node boxes are padded outwards, so rays
   lying in a bounding plane are not culled. Everything is deterministic: the tree depends
   only on the scene, the traversal only on the ray. Without SSE2 (or at PT_SIMD_SCALAR) the
   same layout is traversed by scalar code, with AVX2 by 8-wide nodes, with the same results.
   ------------------------------------------------------------------------------------------ */

#ifndef PT__BVH_BINS
#define PT__BVH_BINS 16
#endif
#ifndef PT__BVH_MAX_LEAF
#define PT__BVH_MAX_LEAF 8
#endif        /* primitives per leaf: at most 2 blocks of each kind */
/* Scenes of at most this many primitives get one primitive per leaf. The SAH keeps the few
   large quads of a room (floor, walls, box faces) together in leaves of up to four, whose
   boxes span the room, so every ray tests a whole block of four; one primitive per leaf
   gives each quad its own (flat) box in the 4-wide node, where a box test, much cheaper than
   a block test, culls the quads a ray does not cross. That pays on small scenes of large quads
   and spheres and costs on larger ones (many coplanar tiles, meshes), hence the limit
   (docs/internals.md, "One primitive per leaf in small scenes"). */
#ifndef PT__BVH_SMALL_SCENE
#define PT__BVH_SMALL_SCENE 32
#endif
#define PT__BVH_SAH_DEPTH 40      /* below this depth splits are by median: depth stays bounded */
#define PT__BVH_STACK 256         /* > 3 x the deepest tree (40 SAH + 32 median levels) */
#define PT__BVH_MAX_DEPTH 73      /* levels of any collapsed tree: at most the binary tree's */
#define PT__BVH_LEAF 0x80000000u  /* child reference: PT__BVH_LEAF | offset of the leaf in the pool (16-byte units) */
#define PT__BVH_OFFSET_MASK 0x7fffffffu
/* SAH costs relative to one block test (four triangles): a node visit costs about half a
   block test in instructions, so 0.5 (docs/internals.md, "SAH costs"). */
#ifndef PT__BVH_COST_NODE
#define PT__BVH_COST_NODE 0.5f
#endif
#ifndef PT__BVH_COST_BLOCK
#define PT__BVH_COST_BLOCK 1.0f
#endif

/* Binary build node (temporary). */
typedef struct pt__bnode {
    float lo[3];
    uint32_t index;   /* leaf: first primitive; inner: second child (first child is next) */
    float hi[3];
    uint32_t count;   /* leaf: number of primitives (> 0); inner: 0 */
} pt__bnode;

typedef struct pt__bvh_build {
    pt_vec3 *lo, *hi, *c;
    uint32_t *idx;
    pt__bnode *nodes;
    uint32_t node_count, max_depth;
    uint32_t max_leaf;          /* PT__BVH_MAX_LEAF, or 1 in small scenes (PT__BVH_SMALL_SCENE) */
    /* collapse */
    const pt__prim *prims;
    pt__node4 *n4;
    pt__leaf16 *pool;
    uint32_t n4_count, depth4;
    size_t pool_used;
    uint32_t *leaf_ref;         /* per binary leaf: its child reference (the wide nodes share the leaves) */
} pt__bvh_build;

static void pt__prim_bounds(const pt__prim *p, pt_vec3 *lo, pt_vec3 *hi)
{
    if (p->type == PT__PRIM_SPHERE) {
        pt_vec3 r = pt_v3(p->p1.x, p->p1.x, p->p1.x);
        *lo = pt_sub(p->p0, r);
        *hi = pt_add(p->p0, r);
    } else if (p->type == PT__PRIM_QUAD) {
        pt_vec3 a = p->p0, b = pt_add(p->p0, p->p1), c = pt_add(p->p0, p->p2), d = pt_add(b, p->p2);
        float m = 2.0f * pt__quad_margin(p); /* pt__hit_quad accepts points this close to the edges */
        *lo = pt_sub(pt__vmin(pt__vmin(a, b), pt__vmin(c, d)), pt_v3(m, m, m));
        *hi = pt_add(pt__vmax(pt__vmax(a, b), pt__vmax(c, d)), pt_v3(m, m, m));
    } else {
        *lo = pt__vmin(pt__vmin(p->p0, p->p1), p->p2);
        *hi = pt__vmax(pt__vmax(p->p0, p->p1), p->p2);
    }
}
static float pt__half_area(pt_vec3 lo, pt_vec3 hi)
{
    pt_vec3 d = pt__vmax(pt_sub(hi, lo), pt_v3(0, 0, 0));
    return d.x * d.y + d.y * d.z + d.z * d.x;
}
/* Blocks a leaf of n primitives costs (rounded up to whole blocks of four). */
static float pt__blocks(uint32_t n) { return (float)((n + 3u) / 4u); }

/* Relative 2^-22 plus 1e-30 absolute (a normal float whose product with 1/0 -> FLT_MAX is
   still larger than any distance in a scene). */
static float pt__pad_down(float x) { return x - (fabsf(x) * 2.384185791e-7f + 1e-30f); }
static float pt__pad_up(float x) { return x + (fabsf(x) * 2.384185791e-7f + 1e-30f); }

/* The bin of centroid coordinate c on an axis whose centroids start at cmin, scale = bins per unit
   (finite, > 0). Clamped in float before the conversion: a float-to-int conversion of a value
   out of int's range (or of NaN) is undefined behaviour (C99 6.3.1.4). */
static int pt__bvh_bin(float c, float cmin, float scale)
{
    float f = (c - cmin) * scale;
    if (!(f > 0.0f)) return 0;
    if (f >= (float)(PT__BVH_BINS - 1)) return PT__BVH_BINS - 1;
    return (int)f;
}
/* Bins per unit length on an axis whose centroids span ext, or 0 when the axis is flat for
   binning: no extent, or one so small (denormal) that PT__BVH_BINS / ext overflows. */
static float pt__bvh_bin_scale(float ext)
{
    float scale;
    if (!(ext > 0.0f)) return 0.0f;
    scale = (float)PT__BVH_BINS / ext;
    return scale <= FLT_MAX ? scale : 0.0f;
}

static uint32_t pt__bvh_build_range(pt__bvh_build *b, uint32_t begin, uint32_t end, uint32_t depth)
{
    uint32_t ni = b->node_count++, n = end - begin, i, mid = begin;
    pt_vec3 lo = pt_v3(FLT_MAX, FLT_MAX, FLT_MAX), hi = pt_neg(lo), clo = lo, chi = hi;
    pt__bnode *node = &b->nodes[ni];
    int best_axis = -1, best_bin = -1, axis, k;
    float best_cost = FLT_MAX;
    if (depth > b->max_depth) b->max_depth = depth;
    for (i = begin; i < end; ++i) {
        uint32_t p = b->idx[i];
        lo = pt__vmin(lo, b->lo[p]);
        hi = pt__vmax(hi, b->hi[p]);
        clo = pt__vmin(clo, b->c[p]);
        chi = pt__vmax(chi, b->c[p]);
    }
    /* padded outwards: a ray running exactly in a bounding plane (an axis-aligned ray along a
       box face) would otherwise get 0 * 1/0 for that slab and be culled */
    node->lo[0] = pt__pad_down(lo.x); node->lo[1] = pt__pad_down(lo.y); node->lo[2] = pt__pad_down(lo.z);
    node->hi[0] = pt__pad_up(hi.x); node->hi[1] = pt__pad_up(hi.y); node->hi[2] = pt__pad_up(hi.z);
    node->count = 0;
    node->index = begin;
    if (n <= 1) { node->count = n; return ni; }
    if (depth < PT__BVH_SAH_DEPTH) {
        for (axis = 0; axis < 3; ++axis) {
            float cmin = pt__vget(clo, axis), ext = pt__vget(chi, axis) - cmin, scale;
            uint32_t cnt[PT__BVH_BINS];
            pt_vec3 blo[PT__BVH_BINS], bhi[PT__BVH_BINS];
            float right_area[PT__BVH_BINS];
            uint32_t right_cnt[PT__BVH_BINS];
            pt_vec3 alo, ahi;
            uint32_t acc;
            if (!((scale = pt__bvh_bin_scale(ext)) > 0.0f)) continue;
            for (k = 0; k < PT__BVH_BINS; ++k) { cnt[k] = 0; blo[k] = pt_v3(FLT_MAX, FLT_MAX, FLT_MAX); bhi[k] = pt_neg(blo[k]); }
            for (i = begin; i < end; ++i) {
                uint32_t p = b->idx[i];
                int bin = pt__bvh_bin(pt__vget(b->c[p], axis), cmin, scale);
                cnt[bin]++;
                blo[bin] = pt__vmin(blo[bin], b->lo[p]);
                bhi[bin] = pt__vmax(bhi[bin], b->hi[p]);
            }
            alo = pt_v3(FLT_MAX, FLT_MAX, FLT_MAX); ahi = pt_neg(alo); acc = 0;
            for (k = PT__BVH_BINS - 1; k > 0; --k) {
                alo = pt__vmin(alo, blo[k]); ahi = pt__vmax(ahi, bhi[k]); acc += cnt[k];
                right_area[k] = acc ? pt__half_area(alo, ahi) : 0.0f;
                right_cnt[k] = acc;
            }
            alo = pt_v3(FLT_MAX, FLT_MAX, FLT_MAX); ahi = pt_neg(alo); acc = 0;
            for (k = 0; k < PT__BVH_BINS - 1; ++k) {
                float cost;
                alo = pt__vmin(alo, blo[k]); ahi = pt__vmax(ahi, bhi[k]); acc += cnt[k];
                if (acc == 0 || right_cnt[k + 1] == 0) continue;
                cost = pt__half_area(alo, ahi) * pt__blocks(acc) + right_area[k + 1] * pt__blocks(right_cnt[k + 1]);
                if (cost < best_cost) { best_cost = cost; best_axis = axis; best_bin = k; }
            }
        }
    }
    if (best_axis >= 0) {
        float parent = pt__half_area(lo, hi);
        float split_cost = PT__BVH_COST_NODE + PT__BVH_COST_BLOCK * (parent > 0.0f ? best_cost / parent : (float)n);
        if (split_cost >= PT__BVH_COST_BLOCK * pt__blocks(n) && n <= b->max_leaf) { node->count = n; return ni; }
        {
            float cmin = pt__vget(clo, best_axis), scale = pt__bvh_bin_scale(pt__vget(chi, best_axis) - cmin);
            uint32_t lo_i = begin, hi_i = end;
            while (lo_i < hi_i) {
                uint32_t p = b->idx[lo_i];
                if (pt__bvh_bin(pt__vget(b->c[p], best_axis), cmin, scale) <= best_bin) lo_i++;
                else { b->idx[lo_i] = b->idx[--hi_i]; b->idx[hi_i] = p; }
            }
            mid = lo_i;
        }
    }
    if (mid <= begin || mid >= end) {
        /* no useful SAH split (coincident centroids or too deep): a leaf if small enough,
           otherwise halve the range so that the depth stays logarithmic */
        if (n <= b->max_leaf) { node->count = n; return ni; }
        mid = begin + n / 2u;
    }
    pt__bvh_build_range(b, begin, mid, depth + 1u);
    {
        uint32_t right = pt__bvh_build_range(b, mid, end, depth + 1u);
        b->nodes[ni].index = right;
    }
    return ni;
}

/* Counts the primitives of a binary leaf by kind. */
static void pt__leaf_kinds(const pt__bvh_build *b, const pt__bnode *leaf, uint32_t *tri, uint32_t *quad, uint32_t *other)
{
    uint32_t i;
    *tri = *quad = *other = 0;
    for (i = leaf->index; i < leaf->index + leaf->count; ++i) {
        int type = b->prims[b->idx[i]].type;
        if (type == PT__PRIM_TRIANGLE) ++*tri;
        else if (type == PT__PRIM_QUAD) ++*quad;
        else ++*other;
    }
}
/* Size of a leaf in the pool, in 16-byte units: a header, then triangle blocks (10 units),
   quad blocks (15) and sphere blocks (5; spheres are the only other kind). */
static size_t pt__leaf_units(uint32_t tri, uint32_t quad, uint32_t other)
{
    return 1u + 10u * (size_t)((tri + 3u) / 4u) + 15u * (size_t)((quad + 3u) / 4u) + 5u * (size_t)((other + 3u) / 4u);
}

static int pt__leaf_kind(int type) { return type == PT__PRIM_TRIANGLE ? 0 : type == PT__PRIM_QUAD ? 1 : 2; }

/* Writes a binary leaf into the pool (its primitives reordered: triangles, quads, others) and
   returns the child reference. Blocks are padded with copies of their lane 0. */
static uint32_t pt__emit_leaf(pt__bvh_build *b, const pt__bnode *leaf)
{
    uint32_t tmp[PT__BVH_MAX_LEAF], i, n = 0, nt, nq, no, j, lane, kind;
    uint32_t begin = leaf->index, end = leaf->index + leaf->count;
    size_t off = b->pool_used;
    pt__leaf16 *h = &b->pool[off];
    char *blk;
    for (kind = 0; kind < 3; ++kind) /* stable: triangles, quads, others */
        for (i = begin; i < end; ++i) {
            int type = b->prims[b->idx[i]].type;
            if ((kind == 0 && type == PT__PRIM_TRIANGLE) || (kind == 1 && type == PT__PRIM_QUAD) ||
                (kind == 2 && type != PT__PRIM_TRIANGLE && type != PT__PRIM_QUAD))
                tmp[n++] = b->idx[i];
        }
    for (i = 1; i < n; ++i) { /* each kind by public id: a block's lowest lane at a tie is the shape added first */
        uint32_t v = tmp[i];
        int kv = pt__leaf_kind(b->prims[v].type);
        for (j = i; j > 0 && pt__leaf_kind(b->prims[tmp[j - 1]].type) == kv && b->prims[tmp[j - 1]].id > b->prims[v].id; --j)
            tmp[j] = tmp[j - 1];
        tmp[j] = v;
    }
    for (i = 0; i < n; ++i) b->idx[begin + i] = tmp[i];
    pt__leaf_kinds(b, leaf, &nt, &nq, &no);
    h->u[0] = (nt + 3u) / 4u; h->u[1] = (nq + 3u) / 4u; h->u[2] = (no + 3u) / 4u; h->u[3] = 0;
    blk = (char *)(h + 1);
    for (j = 0; j < h->u[0]; ++j, blk += sizeof(pt__tri4)) {
        pt__tri4 *q = (pt__tri4 *)(void *)blk;
        for (lane = 0; lane < 4; ++lane) {
            uint32_t k = 4u * j + (4u * j + lane < nt ? lane : 0u);
            const pt__prim *p = &b->prims[b->idx[begin + k]];
            q->v[0][lane] = p->p0.x; q->v[1][lane] = p->p0.y; q->v[2][lane] = p->p0.z;
            q->v[3][lane] = p->p1.x; q->v[4][lane] = p->p1.y; q->v[5][lane] = p->p1.z;
            q->v[6][lane] = p->p2.x; q->v[7][lane] = p->p2.y; q->v[8][lane] = p->p2.z;
            q->prim[lane] = begin + k;
        }
    }
    for (j = 0; j < h->u[1]; ++j, blk += sizeof(pt__quad4)) {
        pt__quad4 *q = (pt__quad4 *)(void *)blk;
        for (lane = 0; lane < 4; ++lane) {
            uint32_t k = nt + 4u * j + (4u * j + lane < nq ? lane : 0u);
            const pt__prim *p = &b->prims[b->idx[begin + k]];
            q->v[0][lane] = p->p0.x; q->v[1][lane] = p->p0.y; q->v[2][lane] = p->p0.z;
            q->v[3][lane] = p->n.x; q->v[4][lane] = p->n.y; q->v[5][lane] = p->n.z;
            q->v[6][lane] = p->w.x; q->v[7][lane] = p->w.y; q->v[8][lane] = p->w.z;
            q->v[9][lane] = p->w2.x; q->v[10][lane] = p->w2.y; q->v[11][lane] = p->w2.z;
            pt__quad_edge_caps(p, &q->v[12][lane], &q->v[13][lane]);
            q->prim[lane] = begin + k;
        }
    }
    for (j = 0; j < h->u[2]; ++j, blk += sizeof(pt__sphere4)) {
        pt__sphere4 *q = (pt__sphere4 *)(void *)blk;
        for (lane = 0; lane < 4; ++lane) {
            uint32_t k = nt + nq + 4u * j + (4u * j + lane < no ? lane : 0u);
            const pt__prim *p = &b->prims[b->idx[begin + k]];
            PT_ASSERT(p->type == PT__PRIM_SPHERE);
            q->v[0][lane] = p->p0.x; q->v[1][lane] = p->p0.y; q->v[2][lane] = p->p0.z; q->v[3][lane] = p->p1.x;
            q->prim[lane] = begin + k;
        }
    }
    b->pool_used += pt__leaf_units(nt, nq, no);
    PT_ASSERT((size_t)(blk - (char *)h) == 16u * pt__leaf_units(nt, nq, no));
    return PT__BVH_LEAF | (uint32_t)off;
}

/* Collapses the binary subtree at `bi` into a 4-wide node (and its descendants, depth first). */
static uint32_t pt__bvh_collapse(pt__bvh_build *b, uint32_t bi, uint32_t depth)
{
    uint32_t kids[4], nk = 0, ni = b->n4_count++, i;
    pt__node4 *node = &b->n4[ni];
    if (depth > b->depth4) b->depth4 = depth;
    if (b->nodes[bi].count) kids[nk++] = bi;
    else { kids[nk++] = bi + 1u; kids[nk++] = b->nodes[bi].index; }
    while (nk < 4) { /* open the inner child of largest surface area */
        int best = -1;
        float best_area = -1.0f;
        for (i = 0; i < nk; ++i) {
            const pt__bnode *c = &b->nodes[kids[i]];
            float a;
            if (c->count) continue;
            a = pt__half_area(pt_v3(c->lo[0], c->lo[1], c->lo[2]), pt_v3(c->hi[0], c->hi[1], c->hi[2]));
            if (a > best_area) { best_area = a; best = (int)i; }
        }
        if (best < 0) break;
        {
            uint32_t c = kids[best];
            kids[best] = c + 1u;
            kids[nk++] = b->nodes[c].index;
        }
    }
    for (i = 0; i < 4; ++i) {
        int a;
        if (i < nk) {
            const pt__bnode *c = &b->nodes[kids[i]];
            for (a = 0; a < 3; ++a) { node->box[2 * a][i] = c->lo[a]; node->box[2 * a + 1][i] = c->hi[a]; }
        } else { /* empty slot: an inverted box no ray enters, and an empty leaf */
            for (a = 0; a < 3; ++a) { node->box[2 * a][i] = HUGE_VALF; node->box[2 * a + 1][i] = -HUGE_VALF; }
            node->child[i] = PT__BVH_LEAF; /* the empty leaf at offset 0 */
        }
        node->pad[i] = 0;
    }
    for (i = 0; i < nk; ++i) {
        uint32_t ref = b->nodes[kids[i]].count ? pt__emit_leaf(b, &b->nodes[kids[i]]) : pt__bvh_collapse(b, kids[i], depth + 1u);
        if (b->nodes[kids[i]].count) b->leaf_ref[kids[i]] = ref;
        b->n4[ni].child[i] = ref; /* b->n4 does not move: allocated for the worst case */
    }
    return ni;
}

/* Run-time SIMD dispatch (pt_simd_level): the CPU's level from __builtin_cpu_supports (which
   also checks that the OS saves the wider registers), capped by pt_simd_set_cap and PDFTRACE_SIMD
   at each commit. Without gcc or clang on x86 the SSE2 level (or the scalar one) is all.
   With AVX2 the same binary tree is also collapsed into 8-wide nodes (16-wide with
   PDFTRACE_AVX512_WIDTH=16 at the AVX-512 level) over the same leaves; only the box tests are
   wider. Each width visits leaves in its own order, so the closest hit is defined without it:
   every leaf block is tested against the ray's own tmax, and hits are ordered by t, then by
   public primitive id (leaves hold each kind in id order): every level returns the same
   primitive, t and barycentrics bit for bit. */
#ifndef PDFTRACE_AVX512_WIDTH
#define PDFTRACE_AVX512_WIDTH 8 /* 16-wide nodes did not pay (bench/README.md, "SIMD levels") */
#endif
#if defined(__GNUC__) || defined(__clang__)
static int pt__simd_cap = PT_SIMD_AVX512;
#define PT__SIMD_CAP_LOAD() __atomic_load_n(&pt__simd_cap, __ATOMIC_RELAXED)
#define PT__SIMD_CAP_STORE(v) __atomic_store_n(&pt__simd_cap, (v), __ATOMIC_RELAXED)
#else
static volatile int pt__simd_cap = PT_SIMD_AVX512;
#define PT__SIMD_CAP_LOAD() pt__simd_cap
#define PT__SIMD_CAP_STORE(v) (pt__simd_cap = (v))
#endif
static const char *const pt__simd_names[4] = { "scalar", "sse2", "avx2", "avx512" };

PTDEF pt_simd_level pt_simd_cpu_level(void)
{
#if defined(PT__WIDE)
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f")) return PT_SIMD_AVX512;
    if (__builtin_cpu_supports("avx2")) return PT_SIMD_AVX2;
    return PT_SIMD_SSE2;
#elif defined(PT__SSE)
    return PT_SIMD_SSE2;
#else
    return PT_SIMD_SCALAR;
#endif
}
PTDEF int pt_simd_set_cap(pt_simd_level cap)
{
    if ((int)cap < PT_SIMD_SCALAR || (int)cap > PT_SIMD_AVX512) return PT_ERROR_INVALID_ARGUMENT;
    PT__SIMD_CAP_STORE((int)cap);
    return PT_OK;
}
PTDEF const char *pt_simd_level_name(pt_simd_level level)
{
    return (int)level >= PT_SIMD_SCALAR && (int)level <= PT_SIMD_AVX512 ? pt__simd_names[level] : NULL;
}
/* PDFTRACE_SIMD as a level: PT_SIMD_AVX512 (no cap) when unset or empty, -1 when unknown. */
static int pt__simd_env(void)
{
    const char *v = getenv("PDFTRACE_SIMD");
    int k;
    if (!v || !*v) return PT_SIMD_AVX512;
    for (k = 0; k < 4; ++k)
        if (!strcmp(v, pt__simd_names[k])) return k;
    return -1;
}
PTDEF pt_simd_level pt_simd_get_level(void)
{
    int level = (int)pt_simd_cpu_level(), cap = PT__SIMD_CAP_LOAD(), env = pt__simd_env();
    if (cap < level) level = cap;
    if (env >= 0 && env < level) level = env;
    return (pt_simd_level)level;
}
/* The level of a commit (s->simd); an unknown PDFTRACE_SIMD is an error. */
static int pt__simd_choose(pt_scene *s)
{
    if (pt__simd_env() < 0)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "commit: PDFTRACE_SIMD=\"%.40s\" is not a SIMD level (scalar, sse2, avx2 or avx512)",
                        getenv("PDFTRACE_SIMD"));
    s->simd = (int)pt_simd_get_level();
    return PT_OK;
}

/* Collapses the binary subtree at `bi` into a node of up to w (8 or 16) children, as
   pt__bvh_collapse does into four, over the leaves it emitted (b->leaf_ref). The node's rows are
   box[6][w] then child[w], at `stride` bytes per node from `nodes`. */
static uint32_t pt__bvh_collapse_wide(pt__bvh_build *b, uint32_t bi, unsigned w, char *nodes, size_t stride,
                                      uint32_t *count)
{
    uint32_t kids[16], nk = 0, ni = (*count)++, i;
    float *box = (float *)(void *)(nodes + stride * ni);
    uint32_t *child = (uint32_t *)(void *)(box + 6u * w);
    if (b->nodes[bi].count) kids[nk++] = bi;
    else { kids[nk++] = bi + 1u; kids[nk++] = b->nodes[bi].index; }
    while (nk < w) { /* open the inner child of largest surface area */
        int best = -1;
        float best_area = -1.0f;
        for (i = 0; i < nk; ++i) {
            const pt__bnode *c = &b->nodes[kids[i]];
            float a;
            if (c->count) continue;
            a = pt__half_area(pt_v3(c->lo[0], c->lo[1], c->lo[2]), pt_v3(c->hi[0], c->hi[1], c->hi[2]));
            if (a > best_area) { best_area = a; best = (int)i; }
        }
        if (best < 0) break;
        {
            uint32_t c = kids[best];
            kids[best] = c + 1u;
            kids[nk++] = b->nodes[c].index;
        }
    }
    for (i = 0; i < w; ++i) {
        unsigned a;
        for (a = 0; a < 3; ++a) { /* an empty slot: an inverted box no ray enters, the empty leaf */
            box[2u * a * w + i] = i < nk ? b->nodes[kids[i]].lo[a] : HUGE_VALF;
            box[(2u * a + 1u) * w + i] = i < nk ? b->nodes[kids[i]].hi[a] : -HUGE_VALF;
        }
        child[i] = PT__BVH_LEAF;
    }
    for (i = 0; i < nk; ++i) {
        uint32_t ref = b->nodes[kids[i]].count ? b->leaf_ref[kids[i]] : pt__bvh_collapse_wide(b, kids[i], w, nodes, stride, count);
        child = (uint32_t *)(void *)(nodes + stride * ni + 6u * w * sizeof(float));
        child[i] = ref;
    }
    return ni;
}

/* Releases the built-in BVH (also when Embree traces the scene instead). */
static void pt__bvh_free(pt_scene *s)
{
    PT_FREE(s->wide_mem);
    s->wide_mem = s->wide = NULL;
    s->wide_count = 0;
    s->bvh_width = 4;
    PT_FREE(s->bvh_mem);
    s->bvh_mem = NULL;
    s->nodes = NULL;
    s->pool = NULL;
    s->node_count = 0;
    s->bvh_depth = 0;
    s->bvh_bytes = 0;
}

/* The wide nodes for the scene's SIMD level (none below AVX2), derived from the same binary
   tree and leaves as the 4-wide ones. */
static int pt__bvh_build_wide(pt_scene *s, pt__bvh_build *b, uint32_t inner)
{
    unsigned w = s->simd >= PT_SIMD_AVX512 && PDFTRACE_AVX512_WIDTH == 16 ? 16u : s->simd >= PT_SIMD_AVX2 ? 8u : 4u;
    size_t stride = w == 16u ? sizeof(pt__node16) : sizeof(pt__node8);
    s->bvh_width = 4;
    if (w == 4u) return PT_OK;
    s->wide_mem = PT_MALLOC(64u + stride * ((size_t)inner + 1u));
    if (!s->wide_mem) return PT_ERROR_OUT_OF_MEMORY;
    s->wide = (char *)s->wide_mem + (64u - (size_t)((uintptr_t)s->wide_mem & 63u)) % 64u;
    s->wide_count = 0;
    pt__bvh_collapse_wide(b, 0, w, (char *)s->wide, stride, &s->wide_count);
    s->bvh_width = w;
    return PT_OK;
}

static int pt__bvh_build_scene(pt_scene *s)
{
    pt__bvh_build b;
    uint32_t n = s->prim_count, i, inner = 0;
    size_t units = 1u; /* offset 0: an empty leaf for empty child slots */
    pt__prim *sorted = NULL;
    size_t node_bytes, bytes;
    char *mem;
    pt__bvh_free(s);
    s->lo = s->hi = pt_v3(0, 0, 0);
    if (n == 0) return PT_OK;
    memset(&b, 0, sizeof b);
    b.lo = (pt_vec3 *)PT_MALLOC(sizeof(pt_vec3) * n);
    b.hi = (pt_vec3 *)PT_MALLOC(sizeof(pt_vec3) * n);
    b.c = (pt_vec3 *)PT_MALLOC(sizeof(pt_vec3) * n);
    b.idx = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * n);
    b.max_leaf = n <= PT__BVH_SMALL_SCENE ? 1u : PT__BVH_MAX_LEAF;
    b.nodes = (pt__bnode *)PT_MALLOC(sizeof(pt__bnode) * (2u * (size_t)n));
    b.leaf_ref = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * (2u * (size_t)n));
    if (!b.lo || !b.hi || !b.c || !b.idx || !b.nodes || !b.leaf_ref) goto oom;
    for (i = 0; i < n; ++i) {
        pt__prim_bounds(&s->prims[i], &b.lo[i], &b.hi[i]);
        b.c[i] = pt_scale(pt_add(b.lo[i], b.hi[i]), 0.5f);
        b.idx[i] = i;
    }
    pt__bvh_build_range(&b, 0, n, 0);
    PT_FREE(b.lo); PT_FREE(b.hi); PT_FREE(b.c);
    b.lo = b.hi = b.c = NULL;
    /* sizes of the 4-wide tree: at most one node per binary inner node (plus a root) */
    b.prims = s->prims;
    for (i = 0; i < b.node_count; ++i) {
        if (b.nodes[i].count) {
            uint32_t t, q, o;
            pt__leaf_kinds(&b, &b.nodes[i], &t, &q, &o);
            units += pt__leaf_units(t, q, o);
        } else {
            inner++;
        }
    }
    if (units > PT__BVH_OFFSET_MASK)
        return pt__fail(s, PT_ERROR_UNSUPPORTED, "commit: %u primitives are more than the BVH can index", (unsigned)n);
    node_bytes = sizeof(pt__node4) * ((size_t)inner + 1u);
    bytes = 64u + node_bytes + 16u * units;
    s->bvh_mem = PT_MALLOC(bytes);
    sorted = (pt__prim *)PT_MALLOC(sizeof(pt__prim) * n);
    if (!s->bvh_mem || !sorted) goto oom;
    mem = (char *)s->bvh_mem + (64u - (size_t)((uintptr_t)s->bvh_mem & 63u)) % 64u;
    b.n4 = (pt__node4 *)(void *)mem;
    b.pool = (pt__leaf16 *)(void *)(mem + node_bytes);
    memset(b.pool, 0, sizeof(pt__leaf16));
    b.pool_used = 1u;
    pt__bvh_collapse(&b, 0, 0);
    PT_ASSERT(b.n4_count <= inner + 1u && b.pool_used == units);
    if (pt__bvh_build_wide(s, &b, inner) != PT_OK) goto oom;
    bytes += s->wide_mem ? (size_t)s->wide_count * (s->bvh_width == 16 ? sizeof(pt__node16) : sizeof(pt__node8)) : 0u;
    s->lo = pt_v3(b.nodes[0].lo[0], b.nodes[0].lo[1], b.nodes[0].lo[2]);
    s->hi = pt_v3(b.nodes[0].hi[0], b.nodes[0].hi[1], b.nodes[0].hi[2]);
    for (i = 0; i < n; ++i) sorted[i] = s->prims[b.idx[i]];
    memcpy(s->prims, sorted, sizeof(pt__prim) * n);
    s->nodes = b.n4;
    s->pool = b.pool;
    s->node_count = b.n4_count;
    s->bvh_depth = b.depth4;
    s->bvh_bytes = bytes;
    PT_FREE(b.idx); PT_FREE(b.nodes); PT_FREE(b.leaf_ref); PT_FREE(sorted);
    return PT_OK;
oom:
    PT_FREE(b.lo); PT_FREE(b.hi); PT_FREE(b.c); PT_FREE(b.idx); PT_FREE(b.nodes); PT_FREE(b.leaf_ref); PT_FREE(sorted);
    pt__bvh_free(s);
    return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "commit: out of memory building the BVH (%u primitives)", (unsigned)n);
}

/* Per-ray traversal data. The inverse direction (FLT_MAX for a zero component) is clamped to
   +-FLT_MAX, so that no slab product is 0 * inf; near[a] is the row of node->box holding the
   entry plane of axis a. */
typedef struct pt__trav {
    const pt__rayctx *rc;
    int near_row[3];      /* the far plane is in row near_row ^ 1 */
    int kx, ky, kz;
    int sse;              /* the SSE2 code (PT_SIMD_SSE2 and up), or the scalar code (PT_SIMD_SCALAR) */
#ifdef PT__SSE
    __m128 o4[3], inv4[3], d4[3];
    __m128 ok4[3], s4[3]; /* watertight test: origin and shear in the permuted axes */
#endif
    float o[3], inv[3];   /* the scalar code's (and the wide box tests') */
} pt__trav;

static PT__HOT void pt__trav_init(pt__trav *tv, const pt__rayctx *rc, int simd)
{
    tv->rc = rc;
    tv->kx = rc->kx; tv->ky = rc->ky; tv->kz = rc->kz;
    tv->sse = simd >= PT_SIMD_SSE2;
    {
        int a;
        const float d[3] = { rc->d.x, rc->d.y, rc->d.z };
        tv->o[0] = rc->o.x; tv->o[1] = rc->o.y; tv->o[2] = rc->o.z;
        for (a = 0; a < 3; ++a) {
            tv->inv[a] = d[a] != 0.0f ? 1.0f / d[a] : FLT_MAX;
            if (!(fabsf(tv->inv[a]) <= FLT_MAX)) tv->inv[a] = copysignf(FLT_MAX, tv->inv[a]);
            tv->near_row[a] = 2 * a + (tv->inv[a] < 0.0f);
        }
    }
#ifdef PT__SSE
    if (!tv->sse) return;
    {
        int a;
        const float d[3] = { rc->d.x, rc->d.y, rc->d.z };
        for (a = 0; a < 3; ++a) { /* the scalar values, broadcast */
            tv->o4[a] = _mm_set1_ps(tv->o[a]);
            tv->inv4[a] = _mm_set1_ps(tv->inv[a]);
            tv->d4[a] = _mm_set1_ps(d[a]);
        }
    }
    if (rc->triangles) {
        const float *o = &rc->o.x;
        tv->ok4[0] = _mm_set1_ps(o[rc->kx]);
        tv->ok4[1] = _mm_set1_ps(o[rc->ky]);
        tv->ok4[2] = _mm_set1_ps(o[rc->kz]);
        tv->s4[0] = _mm_set1_ps(rc->sx);
        tv->s4[1] = _mm_set1_ps(rc->sy);
        tv->s4[2] = _mm_set1_ps(rc->sz);
    } else { /* no triangle blocks in the scene */
        tv->ok4[0] = tv->ok4[1] = tv->ok4[2] = tv->s4[0] = tv->s4[1] = tv->s4[2] = _mm_setzero_ps();
    }
#endif
}

/* Slab test of the four children: bit i of the result is set when the ray enters child i
   before tmax; tnear[i] receives its entry distance. */
#ifdef PT__SSE
static PT__HOT unsigned pt__box4_sse(const pt__node4 *n, const pt__trav *tv, float tmax, float *tnear)
{
    __m128 nx = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->box[tv->near_row[0]]), tv->o4[0]), tv->inv4[0]);
    __m128 ny = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->box[tv->near_row[1]]), tv->o4[1]), tv->inv4[1]);
    __m128 nz = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->box[tv->near_row[2]]), tv->o4[2]), tv->inv4[2]);
    __m128 fx = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->box[(tv->near_row[0] ^ 1)]), tv->o4[0]), tv->inv4[0]);
    __m128 fy = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->box[(tv->near_row[1] ^ 1)]), tv->o4[1]), tv->inv4[1]);
    __m128 fz = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->box[(tv->near_row[2] ^ 1)]), tv->o4[2]), tv->inv4[2]);
    __m128 t0 = _mm_max_ps(_mm_max_ps(nx, ny), _mm_max_ps(nz, _mm_setzero_ps()));
    __m128 t1 = _mm_mul_ps(_mm_min_ps(_mm_min_ps(fx, fy), fz), _mm_set1_ps(1.00000036f));
    t1 = _mm_min_ps(t1, _mm_set1_ps(tmax));
    _mm_storeu_ps(tnear, t0);
    return (unsigned)_mm_movemask_ps(_mm_cmple_ps(t0, t1));
}
#endif
static PT__HOT unsigned pt__box4_scalar(const pt__node4 *n, const pt__trav *tv, float tmax, float *tnear)
{
    unsigned mask = 0, i;
    for (i = 0; i < 4; ++i) {
        float nx = (n->box[tv->near_row[0]][i] - tv->o[0]) * tv->inv[0];
        float ny = (n->box[tv->near_row[1]][i] - tv->o[1]) * tv->inv[1];
        float nz = (n->box[tv->near_row[2]][i] - tv->o[2]) * tv->inv[2];
        float fx = (n->box[(tv->near_row[0] ^ 1)][i] - tv->o[0]) * tv->inv[0];
        float fy = (n->box[(tv->near_row[1] ^ 1)][i] - tv->o[1]) * tv->inv[1];
        float fz = (n->box[(tv->near_row[2] ^ 1)][i] - tv->o[2]) * tv->inv[2];
        float t0 = pt__maxf(pt__maxf(nx, ny), pt__maxf(nz, 0.0f));
        float t1 = pt__minf(pt__minf(pt__minf(fx, fy), fz) * 1.00000036f, tmax);
        tnear[i] = t0;
        if (t0 <= t1) mask |= 1u << i;
    }
    return mask;
}
static PT__HOT unsigned pt__box4(const pt__node4 *n, const pt__trav *tv, float tmax, float *tnear)
{
#ifdef PT__SSE
    if (tv->sse) return pt__box4_sse(n, tv, tmax, tnear);
#endif
    return pt__box4_scalar(n, tv, tmax, tnear);
}

/* Index of the lowest set bit of a 4-bit mask (portable count-trailing-zeros). */
static const unsigned char pt__lowest_bit[16] = { 0, 0, 1, 0, 2, 0, 1, 0, 3, 0, 1, 0, 2, 0, 1, 0 };

/* Lane `lane` of a triangle block through the scalar watertight test. */
static PT__HOT int pt__tri4_lane(const pt__trav *tv, const pt__tri4 *q, int lane, float tmax, float *t, float *bary)
{
    return pt__hit_triangle(tv->rc, pt_v3(q->v[0][lane], q->v[1][lane], q->v[2][lane]),
                            pt_v3(q->v[3][lane], q->v[4][lane], q->v[5][lane]),
                            pt_v3(q->v[6][lane], q->v[7][lane], q->v[8][lane]), tmax, t, bary);
}

/* The four triangles of a block against the ray: returns the lane of the nearest hit with
   0 < t < tmax (the lowest lane at a tie), or -1; fills *t and bary. Every lane is tested
   against the same tmax, so the result depends on the block and tmax alone (the traversal
   relies on it: every width finds the same hit). any != 0: returns the first lane found. */
#ifdef PT__SSE
static PT__HOT int pt__tri4_hit_sse(const pt__trav *tv, const pt__tri4 *q, float tmax, float *t_out, float *bary, int any)
{
    /* the scalar test's operations in the same order, four lanes at a time */
    const int kx = tv->kx, ky = tv->ky, kz = tv->kz;
    __m128 zero = _mm_setzero_ps(), tmax4 = _mm_set1_ps(tmax);
    __m128 Akz = _mm_sub_ps(_mm_loadu_ps(q->v[kz]), tv->ok4[2]);
    __m128 Bkz = _mm_sub_ps(_mm_loadu_ps(q->v[3 + kz]), tv->ok4[2]);
    __m128 Ckz = _mm_sub_ps(_mm_loadu_ps(q->v[6 + kz]), tv->ok4[2]);
    __m128 Ax = _mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(q->v[kx]), tv->ok4[0]), _mm_mul_ps(tv->s4[0], Akz));
    __m128 Ay = _mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(q->v[ky]), tv->ok4[1]), _mm_mul_ps(tv->s4[1], Akz));
    __m128 Bx = _mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(q->v[3 + kx]), tv->ok4[0]), _mm_mul_ps(tv->s4[0], Bkz));
    __m128 By = _mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(q->v[3 + ky]), tv->ok4[1]), _mm_mul_ps(tv->s4[1], Bkz));
    __m128 Cx = _mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(q->v[6 + kx]), tv->ok4[0]), _mm_mul_ps(tv->s4[0], Ckz));
    __m128 Cy = _mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(q->v[6 + ky]), tv->ok4[1]), _mm_mul_ps(tv->s4[1], Ckz));
    __m128 CxBy = _mm_mul_ps(Cx, By), CyBx = _mm_mul_ps(Cy, Bx), AxCy = _mm_mul_ps(Ax, Cy);
    __m128 AyCx = _mm_mul_ps(Ay, Cx), BxAy = _mm_mul_ps(Bx, Ay), ByAx = _mm_mul_ps(By, Ax);
    __m128 U = _mm_sub_ps(CxBy, CyBx), V = _mm_sub_ps(AxCy, AyCx), W = _mm_sub_ps(BxAy, ByAx);
    __m128 zmask = _mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, zero), _mm_cmpeq_ps(V, zero)), _mm_cmpeq_ps(W, zero));
    __m128 neg = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(U, zero), _mm_cmplt_ps(V, zero)), _mm_cmplt_ps(W, zero));
    __m128 pos = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(U, zero), _mm_cmpgt_ps(V, zero)), _mm_cmpgt_ps(W, zero));
    __m128 det, T, tdet, dneg, rej, ok, inv, t;
    int zbits = _mm_movemask_ps(zmask), okbits, lane, best = -1;
    float ts[4], us[4], vs[4], ws[4], is[4], best_t = tmax;
    ok = _mm_andnot_ps(_mm_or_ps(zmask, _mm_and_ps(neg, pos)), _mm_castsi128_ps(_mm_set1_epi32(-1)));
    if (!_mm_movemask_ps(ok) && !zbits) return -1;
    det = _mm_add_ps(_mm_add_ps(U, V), W);
    {
        /* ill-conditioned lanes (PT__TRI_COND) go to the scalar test, which redoes them in double */
        const __m128 sign = _mm_set1_ps(-0.0f), cond = _mm_set1_ps(PT__TRI_COND);
        __m128 Ta = _mm_mul_ps(U, _mm_mul_ps(tv->s4[2], Akz)), Tb = _mm_mul_ps(V, _mm_mul_ps(tv->s4[2], Bkz));
        __m128 Tc = _mm_mul_ps(W, _mm_mul_ps(tv->s4[2], Ckz)), P, Q, ill;
        P = _mm_add_ps(_mm_add_ps(_mm_andnot_ps(sign, CxBy), _mm_andnot_ps(sign, CyBx)), _mm_andnot_ps(sign, AxCy));
        P = _mm_add_ps(_mm_add_ps(_mm_add_ps(P, _mm_andnot_ps(sign, AyCx)), _mm_andnot_ps(sign, BxAy)), _mm_andnot_ps(sign, ByAx));
        T = _mm_add_ps(_mm_add_ps(Ta, Tb), Tc);
        Q = _mm_add_ps(_mm_add_ps(_mm_andnot_ps(sign, Ta), _mm_andnot_ps(sign, Tb)), _mm_andnot_ps(sign, Tc));
        ill = _mm_or_ps(_mm_cmpgt_ps(P, _mm_mul_ps(cond, _mm_andnot_ps(sign, det))),
                        _mm_cmpgt_ps(Q, _mm_mul_ps(cond, _mm_andnot_ps(sign, T))));
        ill = _mm_and_ps(ok, _mm_andnot_ps(_mm_cmpeq_ps(det, zero), ill)); /* det == 0: a miss either way */
        zbits |= _mm_movemask_ps(ill);
        ok = _mm_andnot_ps(ill, ok);
    }
    /* tmax * det only where det != 0: inf * 0 would raise FE_INVALID (FP-trap builds) */
    tdet = _mm_cmpneq_ps(det, zero);
    tdet = _mm_mul_ps(tmax4, _mm_or_ps(_mm_and_ps(tdet, det), _mm_andnot_ps(tdet, _mm_set1_ps(1.0f))));
    dneg = _mm_cmplt_ps(det, zero);
    rej = _mm_or_ps(_mm_and_ps(dneg, _mm_or_ps(_mm_cmpge_ps(T, zero), _mm_cmple_ps(T, tdet))),
                    _mm_andnot_ps(dneg, _mm_or_ps(_mm_cmple_ps(T, zero), _mm_cmpge_ps(T, tdet))));
    ok = _mm_andnot_ps(_mm_or_ps(rej, _mm_cmpeq_ps(det, zero)), ok);
    okbits = _mm_movemask_ps(ok);
    if (okbits) {
        /* divide only in lanes that passed (others by 1: no division by zero) */
        inv = _mm_div_ps(_mm_set1_ps(1.0f), _mm_or_ps(_mm_and_ps(ok, det), _mm_andnot_ps(ok, _mm_set1_ps(1.0f))));
        t = _mm_mul_ps(T, inv);
        okbits &= _mm_movemask_ps(_mm_and_ps(_mm_cmpgt_ps(t, zero), _mm_cmplt_ps(t, tmax4)));
        _mm_storeu_ps(ts, t);
        _mm_storeu_ps(is, inv);
    }
    if (!okbits && !zbits) return -1;
    if (any && okbits) return 0;
    for (lane = 0; lane < 4; ++lane) {
        if (okbits & (1 << lane)) {
            if (ts[lane] < best_t) { best_t = ts[lane]; best = lane; }
        } else if (zbits & (1 << lane)) {
            float tz, bz[3];
            if (pt__tri4_lane(tv, q, lane, tmax, &tz, bz)) {
                if (any) return lane;
                if (tz < best_t) { best_t = tz; best = lane; }
            }
        }
    }
    if (best < 0) return -1;
    *t_out = best_t;
    if (okbits & (1 << best)) {
        _mm_storeu_ps(us, U);
        _mm_storeu_ps(vs, V);
        _mm_storeu_ps(ws, W);
        bary[0] = us[best] * is[best]; bary[1] = vs[best] * is[best]; bary[2] = ws[best] * is[best];
    } else {
        float tz;
        pt__tri4_lane(tv, q, best, tmax, &tz, bary);
    }
    return best;
}
#endif
static PT__HOT int pt__tri4_hit_scalar(const pt__trav *tv, const pt__tri4 *q, float tmax, float *t_out, float *bary, int any)
{
    int lane, best = -1;
    float best_t = tmax, bb[3];
    for (lane = 0; lane < 4; ++lane) {
        float t;
        /* every lane against the block's tmax, as the SSE code: the triangle test's
           rejection T >= tmax det rounds, so a smaller tmax could reject a nearer hit */
        if (pt__tri4_lane(tv, q, lane, tmax, &t, bb) && (best < 0 || t < best_t)) {
            if (any) return lane;
            best_t = t; best = lane;
            bary[0] = bb[0]; bary[1] = bb[1]; bary[2] = bb[2];
        }
    }
    if (best >= 0) *t_out = best_t;
    return best;
}
static PT__HOT int pt__tri4_hit(const pt__trav *tv, const pt__tri4 *q, float tmax, float *t_out, float *bary, int any)
{
#ifdef PT__SSE
    if (tv->sse) return pt__tri4_hit_sse(tv, q, tmax, t_out, bary, any);
#endif
    return pt__tri4_hit_scalar(tv, q, tmax, t_out, bary, any);
}

/* The four quads of a block (pt__hit_quad's operations, four lanes at a time): returns the
   lane of the nearest hit with 0 < t < tmax (lowest lane at a tie), or -1. */
#ifdef PT__SSE
static PT__HOT int pt__quad4_hit_sse(const pt__trav *tv, const pt_scene *s, const pt__quad4 *q, float tmax, float *t_out,
                                 int any)
{
    __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    __m128 dx = tv->d4[0], dy = tv->d4[1], dz = tv->d4[2];
    __m128 nx = _mm_loadu_ps(q->v[3]), ny = _mm_loadu_ps(q->v[4]), nz = _mm_loadu_ps(q->v[5]);
    __m128 denom = _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, dx), _mm_mul_ps(ny, dy)), _mm_mul_ps(nz, dz));
    __m128 ok = _mm_cmpneq_ps(denom, zero), t, hx, hy, hz, a, bb, out;
    __m128 px = _mm_loadu_ps(q->v[0]), py = _mm_loadu_ps(q->v[1]), pz = _mm_loadu_ps(q->v[2]);
    float ts[4], best_t = tmax;
    int bits, lane, best = -1;
    if (!_mm_movemask_ps(ok)) return -1;
    t = _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, _mm_sub_ps(px, tv->o4[0])), _mm_mul_ps(ny, _mm_sub_ps(py, tv->o4[1]))),
                   _mm_mul_ps(nz, _mm_sub_ps(pz, tv->o4[2])));
    t = _mm_div_ps(t, _mm_or_ps(_mm_and_ps(ok, denom), _mm_andnot_ps(ok, one)));
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(t, zero), _mm_cmplt_ps(t, _mm_set1_ps(tmax))));
    if (!_mm_movemask_ps(ok)) return -1;
    t = _mm_and_ps(ok, t); /* lanes out of range: t = 0, so that no o + d t overflows into inf * 0 */
    hx = _mm_sub_ps(_mm_add_ps(tv->o4[0], _mm_mul_ps(dx, t)), px);
    hy = _mm_sub_ps(_mm_add_ps(tv->o4[1], _mm_mul_ps(dy, t)), py);
    hz = _mm_sub_ps(_mm_add_ps(tv->o4[2], _mm_mul_ps(dz, t)), pz);
    a = _mm_add_ps(_mm_add_ps(_mm_mul_ps(hx, _mm_loadu_ps(q->v[6])), _mm_mul_ps(hy, _mm_loadu_ps(q->v[7]))),
                   _mm_mul_ps(hz, _mm_loadu_ps(q->v[8])));
    bb = _mm_add_ps(_mm_add_ps(_mm_mul_ps(hx, _mm_loadu_ps(q->v[9])), _mm_mul_ps(hy, _mm_loadu_ps(q->v[10]))),
                    _mm_mul_ps(hz, _mm_loadu_ps(q->v[11])));
    out = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(a, zero), _mm_cmpgt_ps(a, one)),
                    _mm_or_ps(_mm_cmplt_ps(bb, zero), _mm_cmpgt_ps(bb, one)));
    bits = _mm_movemask_ps(_mm_andnot_ps(out, ok));
    _mm_storeu_ps(ts, t);
    {
        /* lanes that hit the plane just outside [0,1]^2: pt__hit_quad's rounding margin decides
           (a ray through the edge two quads share must hit one of them; stress, watertight box) */
        int edge = _mm_movemask_ps(_mm_and_ps(out, ok));
        if (edge) {
            /* only lanes within the caps of the margin (pt__quad_edge_caps) can be hits */
            __m128 ta = _mm_loadu_ps(q->v[12]), tb = _mm_loadu_ps(q->v[13]);
            __m128 far_out = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(a, _mm_sub_ps(zero, ta)), _mm_cmpgt_ps(a, _mm_add_ps(one, ta))),
                                       _mm_or_ps(_mm_cmplt_ps(bb, _mm_sub_ps(zero, tb)), _mm_cmpgt_ps(bb, _mm_add_ps(one, tb))));
            edge &= ~_mm_movemask_ps(far_out);
            for (lane = 0; edge && lane < 4; ++lane) {
                float tq;
                if (!(edge & (1 << lane))) continue;
                if (pt__hit_quad(tv->rc, &s->prims[q->prim[lane]], tmax, &tq)) { bits |= 1 << lane; ts[lane] = tq; }
            }
        }
    }
    if (!bits) return -1;
    if (any) return pt__lowest_bit[bits];
    for (lane = 0; lane < 4; ++lane)
        if ((bits & (1 << lane)) && ts[lane] < best_t) { best_t = ts[lane]; best = lane; }
    (void)s;
    if (best >= 0) *t_out = best_t;
    return best;
}
#endif
static PT__HOT int pt__quad4_hit_scalar(const pt__trav *tv, const pt_scene *s, const pt__quad4 *q, float tmax, float *t_out,
                                 int any)
{
    int lane, best = -1;
    float best_t = tmax;
    for (lane = 0; lane < 4; ++lane) {
        float t;
        if (pt__hit_quad(tv->rc, &s->prims[q->prim[lane]], best_t, &t)) {
            if (any) return lane;
            best_t = t; best = lane;
        }
    }
    if (best >= 0) *t_out = best_t;
    return best;
}
static PT__HOT int pt__quad4_hit(const pt__trav *tv, const pt_scene *s, const pt__quad4 *q, float tmax, float *t_out,
                                 int any)
{
#ifdef PT__SSE
    if (tv->sse) return pt__quad4_hit_sse(tv, s, q, tmax, t_out, any);
#endif
    return pt__quad4_hit_scalar(tv, s, q, tmax, t_out, any);
}

/* The spheres of a block (pt__hit_sphere's operations, four lanes at a time; lanes of tiny or
   distant spheres, which pt__hit_sphere decides in double, go to it): returns the lane of the
   nearest hit with 0 < t < tmax (lowest lane at a tie), or -1. Blocks are padded with copies of
   lane 0. */
#ifdef PT__SSE
static PT__HOT int pt__sphere4_hit_sse(const pt__trav *tv, const pt__sphere4 *q, float tmax, float *t_out, int any)
{
    const pt__rayctx *rc = tv->rc;
    int lane, best = -1;
    float best_t = tmax;
    float a = pt_dot(rc->d, rc->d), ts[4];
    __m128 zero = _mm_setzero_ps(), sign = _mm_set1_ps(-0.0f), a4, cx, cy, cz, r, fx, fy, fz, bp, ff, rr, k, lx, ly, lz;
    __m128 ll, disc, ok, cc, sq, qq, qd, t0, t1, sw, lo, hi, h0, h1, t;
    int bits, tiny;
    if (q->prim[1] == q->prim[0]) { /* a single sphere: the scalar test is cheaper */
        if (!pt__hit_sphere(rc, pt_v3(q->v[0][0], q->v[1][0], q->v[2][0]), q->v[3][0], tmax, t_out)) return -1;
        return 0;
    }
    if (!(a > 0.0f)) return -1; /* as every lane's scalar test */
    a4 = _mm_set1_ps(a);
    cx = _mm_loadu_ps(q->v[0]); cy = _mm_loadu_ps(q->v[1]); cz = _mm_loadu_ps(q->v[2]); r = _mm_loadu_ps(q->v[3]);
    fx = _mm_sub_ps(tv->o4[0], cx); fy = _mm_sub_ps(tv->o4[1], cy); fz = _mm_sub_ps(tv->o4[2], cz);
    bp = _mm_xor_ps(sign, _mm_add_ps(_mm_add_ps(_mm_mul_ps(fx, tv->d4[0]), _mm_mul_ps(fy, tv->d4[1])),
                                     _mm_mul_ps(fz, tv->d4[2])));
    ff = _mm_add_ps(_mm_add_ps(_mm_mul_ps(fx, fx), _mm_mul_ps(fy, fy)), _mm_mul_ps(fz, fz));
    rr = _mm_mul_ps(r, r);
    tiny = _mm_movemask_ps(_mm_cmplt_ps(rr, _mm_mul_ps(_mm_set1_ps(1e-6f), ff)));
    k = _mm_div_ps(bp, a4);
    lx = _mm_add_ps(fx, _mm_mul_ps(tv->d4[0], k));
    ly = _mm_add_ps(fy, _mm_mul_ps(tv->d4[1], k));
    lz = _mm_add_ps(fz, _mm_mul_ps(tv->d4[2], k));
    ll = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(lx, lx), _mm_mul_ps(ly, ly)), _mm_mul_ps(lz, lz)));
    disc = _mm_mul_ps(_mm_mul_ps(a4, _mm_sub_ps(r, ll)), _mm_add_ps(r, ll));
    ok = _mm_andnot_ps(_mm_cmplt_ps(disc, zero), _mm_castsi128_ps(_mm_set1_epi32(-1)));
    cc = _mm_sub_ps(ff, rr);
    sq = _mm_sqrt_ps(_mm_and_ps(ok, disc)); /* no square root of a negative: FE_INVALID traps */
    qq = _mm_add_ps(bp, _mm_or_ps(_mm_andnot_ps(sign, sq), _mm_and_ps(sign, bp)));
    ok = _mm_andnot_ps(_mm_cmpeq_ps(qq, zero), ok);
    qd = _mm_or_ps(_mm_and_ps(ok, qq), _mm_andnot_ps(ok, _mm_set1_ps(1.0f)));
    t0 = _mm_div_ps(cc, qd);
    t1 = _mm_div_ps(qq, a4);
    sw = _mm_cmpgt_ps(t0, t1); /* if (t0 > t1) swap */
    lo = _mm_or_ps(_mm_and_ps(sw, t1), _mm_andnot_ps(sw, t0));
    hi = _mm_or_ps(_mm_and_ps(sw, t0), _mm_andnot_ps(sw, t1));
    h0 = _mm_and_ps(_mm_cmpgt_ps(lo, zero), _mm_cmplt_ps(lo, _mm_set1_ps(tmax)));
    h1 = _mm_and_ps(_mm_cmpgt_ps(hi, zero), _mm_cmplt_ps(hi, _mm_set1_ps(tmax)));
    t = _mm_or_ps(_mm_and_ps(h0, lo), _mm_andnot_ps(h0, hi));
    bits = _mm_movemask_ps(_mm_and_ps(ok, _mm_or_ps(h0, h1))) & ~tiny;
    if (!bits && !tiny) return -1;
    if (any && bits) return pt__lowest_bit[bits];
    _mm_storeu_ps(ts, t);
    for (lane = 0; lane < 4 && (lane == 0 || q->prim[lane] != q->prim[0]); ++lane) { /* to the padding */
        if (tiny & (1 << lane)) {
            float tz;
            if (pt__hit_sphere(rc, pt_v3(q->v[0][lane], q->v[1][lane], q->v[2][lane]), q->v[3][lane], best_t, &tz)) {
                if (any) return lane;
                best_t = tz; best = lane;
            }
        } else if ((bits & (1 << lane)) && ts[lane] < best_t) {
            best_t = ts[lane]; best = lane;
        }
    }
    if (best >= 0) *t_out = best_t;
    return best;
}
#endif
static PT__HOT int pt__sphere4_hit_scalar(const pt__trav *tv, const pt__sphere4 *q, float tmax, float *t_out, int any)
{
    const pt__rayctx *rc = tv->rc;
    int lane, best = -1;
    float best_t = tmax;
    for (lane = 0; lane < 4 && (lane == 0 || q->prim[lane] != q->prim[0]); ++lane) { /* to the padding */
        float t;
        if (pt__hit_sphere(rc, pt_v3(q->v[0][lane], q->v[1][lane], q->v[2][lane]), q->v[3][lane], best_t, &t)) {
            if (any) return lane;
            best_t = t; best = lane;
        }
    }
    if (best >= 0) *t_out = best_t;
    return best;
}
static PT__HOT int pt__sphere4_hit(const pt__trav *tv, const pt__sphere4 *q, float tmax, float *t_out, int any)
{
#ifdef PT__SSE
    if (tv->sse) return pt__sphere4_hit_sse(tv, q, tmax, t_out, any);
#endif
    return pt__sphere4_hit_scalar(tv, q, tmax, t_out, any);
}


/* The nearest hit found so far. Hits are ordered by t, then by public primitive id (at an exact
   tie, e.g. a ray through the edge two faces share, the shape added first), so that the result
   does not depend on the order leaves are visited in: each node width visits them in its own. */
typedef struct pt__best {
    float t;
    uint32_t prim;
    int found;
    float bary[3];
} pt__best;

static PT__HOT void pt__best_offer(const pt_scene *s, pt__best *b, float t, uint32_t prim, const float *bary)
{
    if (b->found && (t > b->t || (t == b->t && s->prims[prim].id >= s->prims[b->prim].id))) return;
    b->t = t; b->prim = prim; b->found = 1;
    b->bary[0] = bary[0]; b->bary[1] = bary[1]; b->bary[2] = bary[2];
}

/* The blocks of a leaf against the ray. Every block is tested against the ray's own tmax0, not
   the nearest hit so far: a block's result then depends on the block alone (the triangle test
   rounds its tmax comparison), and the (t, primitive) order picks the same hit in any width. */
static PT__HOT void pt__leaf_closest(const pt_scene *s, const pt__trav *tv, uint32_t ref, float tmax0, pt__best *b)
{
    static const float no_bary[3] = { 0.0f, 0.0f, 0.0f };
    const pt__leaf16 *h = &s->pool[ref & PT__BVH_OFFSET_MASK];
    const char *blk = (const char *)(h + 1);
    uint32_t j;
    for (j = 0; j < h->u[0]; ++j, blk += sizeof(pt__tri4)) {
        const pt__tri4 *q = (const pt__tri4 *)(const void *)blk;
        float t = 0.0f, bb[3] = { 0.0f, 0.0f, 0.0f };
        int l = pt__tri4_hit(tv, q, tmax0, &t, bb, 0); /* bb is written only on a hit */
        if (l >= 0) pt__best_offer(s, b, t, q->prim[l], bb);
    }
    for (j = 0; j < h->u[1]; ++j, blk += sizeof(pt__quad4)) {
        const pt__quad4 *q = (const pt__quad4 *)(const void *)blk;
        float t;
        int l = pt__quad4_hit(tv, s, q, tmax0, &t, 0);
        if (l >= 0) pt__best_offer(s, b, t, q->prim[l], no_bary);
    }
    for (j = 0; j < h->u[2]; ++j, blk += sizeof(pt__sphere4)) {
        const pt__sphere4 *q = (const pt__sphere4 *)(const void *)blk;
        float t;
        int l = pt__sphere4_hit(tv, q, tmax0, &t, 0);
        if (l >= 0) pt__best_offer(s, b, t, q->prim[l], no_bary);
    }
}

/* Any hit in a leaf with 0 < t < tmax. Quad and sphere blocks that hold only primitive `skip`
   (one-primitive leaves, PT__BVH_SMALL_SCENE) are not tested (see pt__bvh_any). */
static PT__HOT int pt__leaf_any(const pt_scene *s, const pt__trav *tv, uint32_t ref, float tmax, uint32_t skip)
{
    const pt__leaf16 *h = &s->pool[ref & PT__BVH_OFFSET_MASK];
    const char *blk = (const char *)(h + 1);
    uint32_t j;
    for (j = 0; j < h->u[0]; ++j, blk += sizeof(pt__tri4)) {
        float t, bb[3];
        if (pt__tri4_hit(tv, (const pt__tri4 *)(const void *)blk, tmax, &t, bb, 1) >= 0) return 1;
    }
    for (j = 0; j < h->u[1]; ++j, blk += sizeof(pt__quad4)) {
        const pt__quad4 *q = (const pt__quad4 *)(const void *)blk;
        float t;
        if (q->prim[0] == skip && q->prim[1] == skip) continue; /* a block of the skipped primitive alone */
        if (pt__quad4_hit(tv, s, q, tmax, &t, 1) >= 0) return 1;
    }
    for (j = 0; j < h->u[2]; ++j, blk += sizeof(pt__sphere4)) {
        const pt__sphere4 *q = (const pt__sphere4 *)(const void *)blk;
        float t;
        if (q->prim[0] == skip && q->prim[1] == skip) continue;
        if (pt__sphere4_hit(tv, q, tmax, &t, 1) >= 0) return 1;
    }
    return 0;
}

/* Closest hit through the 4-wide nodes (scalar or SSE2 box tests). */
static void pt__bvh_closest4(const pt_scene *s, const pt__trav *tv, float tmax0, pt__best *b)
{
    uint32_t stack_ref[PT__BVH_STACK];
    float stack_t[PT__BVH_STACK], tmax = tmax0;
    int sp = 0;
    uint32_t ref = 0;
    for (;;) {
        if (!(ref & PT__BVH_LEAF)) {
            const pt__node4 *n = &s->nodes[ref];
            float tn[4];
            unsigned mask = pt__box4(n, tv, tmax, tn);
            if (mask) {
                /* one child hit (the common case): go there; two: the nearer now, the farther
                   on the stack; more: all on the stack, sorted so the nearest is on top */
                unsigned i0 = pt__lowest_bit[mask], i1;
                mask &= mask - 1u;
                if (!mask) { ref = n->child[i0]; continue; }
                i1 = pt__lowest_bit[mask];
                mask &= mask - 1u;
                if (!mask) {
                    PT_ASSERT(sp < PT__BVH_STACK);
                    if (tn[i0] <= tn[i1]) { stack_ref[sp] = n->child[i1]; stack_t[sp] = tn[i1]; ref = n->child[i0]; }
                    else { stack_ref[sp] = n->child[i0]; stack_t[sp] = tn[i0]; ref = n->child[i1]; }
                    sp++;
                    continue;
                }
                {
                    int base = sp, i, j;
                    PT_ASSERT(sp + 4 <= PT__BVH_STACK);
                    stack_ref[sp] = n->child[i0]; stack_t[sp] = tn[i0]; sp++;
                    stack_ref[sp] = n->child[i1]; stack_t[sp] = tn[i1]; sp++;
                    while (mask) {
                        unsigned ik = pt__lowest_bit[mask];
                        mask &= mask - 1u;
                        stack_ref[sp] = n->child[ik]; stack_t[sp] = tn[ik]; sp++;
                    }
                    for (i = base + 1; i < sp; ++i) { /* insertion sort, farthest at the bottom */
                        uint32_t rr = stack_ref[i];
                        float dd = stack_t[i];
                        for (j = i; j > base && stack_t[j - 1] < dd; --j) { stack_ref[j] = stack_ref[j - 1]; stack_t[j] = stack_t[j - 1]; }
                        stack_ref[j] = rr; stack_t[j] = dd;
                    }
                    ref = stack_ref[--sp];
                    continue;
                }
            }
        } else {
            pt__leaf_closest(s, tv, ref, tmax0, b);
            if (b->found) tmax = b->t;
        }
        /* next: the nearest stacked node not behind the closest hit (a node at its distance
           may hold a primitive of lower index at the same t) */
        for (;;) {
            if (sp == 0) return;
            --sp;
            if (stack_t[sp] <= tmax) break;
        }
        ref = stack_ref[sp];
    }
}

/* Any hit through the 4-wide nodes. */
static int pt__bvh_any4(const pt_scene *s, const pt__trav *tv, float tmax, uint32_t skip)
{
    uint32_t stack_ref[PT__BVH_STACK];
    int sp = 0;
    uint32_t ref = 0;
    for (;;) {
        if (!(ref & PT__BVH_LEAF)) {
            const pt__node4 *n = &s->nodes[ref];
            float tn[4];
            unsigned mask = pt__box4(n, tv, tmax, tn);
            if (mask) {
                ref = n->child[pt__lowest_bit[mask]];
                mask &= mask - 1u;
                while (mask) {
                    PT_ASSERT(sp < PT__BVH_STACK);
                    stack_ref[sp++] = n->child[pt__lowest_bit[mask]];
                    mask &= mask - 1u;
                }
                continue;
            }
        } else if (pt__leaf_any(s, tv, ref, tmax, skip)) {
            return 1;
        }
        if (sp == 0) return 0;
        ref = stack_ref[--sp];
    }
}

#ifdef PT__WIDE
/* The wide traversals (8 children with AVX2, 16 with AVX-512F) are compiled for their
   instruction set alone; the leaf tests they call stay SSE2 code outside them (not inlined: no
   FMA contraction or other code generation can change a hit's bits). */
static PT__NOINLINE void pt__leaf_closest_call(const pt_scene *s, const pt__trav *tv, uint32_t ref, float tmax0,
                                               pt__best *b)
{
    pt__leaf_closest(s, tv, ref, tmax0, b);
}
static PT__NOINLINE int pt__leaf_any_call(const pt_scene *s, const pt__trav *tv, uint32_t ref, float tmax, uint32_t skip)
{
    return pt__leaf_any(s, tv, ref, tmax, skip);
}

/* Stacks the hit children of a wide node (mask: bit i for child i; tn: entry distances) and
   returns the next node: the nearest child; with more than one, the others go on the stack
   sorted farthest at the bottom (closest hit: sort = 1) or unsorted (any hit: sort = 0). */
static PT__HOT uint32_t pt__wide_push(const uint32_t *child, unsigned mask, const float *tn, uint32_t *stack_ref,
                                      float *stack_t, int *sp, int sort)
{
    int base = *sp, i, j;
    unsigned i0 = (unsigned)__builtin_ctz(mask);
    mask &= mask - 1u;
    if (!mask) return child[i0];
    if (!sort) {
        while (mask) { stack_ref[(*sp)++] = child[__builtin_ctz(mask)]; mask &= mask - 1u; }
        return child[i0];
    }
    stack_ref[*sp] = child[i0]; stack_t[*sp] = tn[i0]; (*sp)++;
    while (mask) {
        unsigned ik = (unsigned)__builtin_ctz(mask);
        mask &= mask - 1u;
        stack_ref[*sp] = child[ik]; stack_t[*sp] = tn[ik]; (*sp)++;
    }
    for (i = base + 1; i < *sp; ++i) { /* insertion sort, farthest at the bottom */
        uint32_t rr = stack_ref[i];
        float dd = stack_t[i];
        for (j = i; j > base && stack_t[j - 1] < dd; --j) { stack_ref[j] = stack_ref[j - 1]; stack_t[j] = stack_t[j - 1]; }
        stack_ref[j] = rr; stack_t[j] = dd;
    }
    return stack_ref[--(*sp)];
}

/* One traversal body per width: W children, vector type V, the box test's intrinsics. The slab
   test is pt__box4's, W lanes at a time. closest != 0: nearest hit into *b (returns 0); else
   any hit (returns 1 or 0). */
#define PT__WIDE_TRAVERSAL(NAME, TARGET, W, NODE, V, SET1, LOADU, SUB, MUL, MAX, MIN, STOREU, LEMASK)                  \
    TARGET static int NAME(const pt_scene *s, const pt__trav *tv, float tmax0, pt__best *b, uint32_t skip, int closest) \
    {                                                                                                              \
        uint32_t stack_ref[(W - 1) * PT__BVH_MAX_DEPTH + W];                                                       \
        float stack_t[(W - 1) * PT__BVH_MAX_DEPTH + W], tn[W], tmax = tmax0;                                       \
        const V ox = SET1(tv->o[0]), oy = SET1(tv->o[1]), oz = SET1(tv->o[2]);                                     \
        const V ix = SET1(tv->inv[0]), iy = SET1(tv->inv[1]), iz = SET1(tv->inv[2]);                               \
        const V zero = SET1(0.0f), widen = SET1(1.00000036f);                                                      \
        const int r0 = tv->near_row[0], r1 = tv->near_row[1], r2 = tv->near_row[2];                                \
        const NODE *nodes = (const NODE *)s->wide;                                                                 \
        int sp = 0;                                                                                                \
        uint32_t ref = 0;                                                                                          \
        for (;;) {                                                                                                 \
            if (!(ref & PT__BVH_LEAF)) {                                                                           \
                const NODE *n = &nodes[ref];                                                                       \
                V nx = MUL(SUB(LOADU(n->box[r0]), ox), ix), ny = MUL(SUB(LOADU(n->box[r1]), oy), iy);              \
                V nz = MUL(SUB(LOADU(n->box[r2]), oz), iz), fx = MUL(SUB(LOADU(n->box[r0 ^ 1]), ox), ix);          \
                V fy = MUL(SUB(LOADU(n->box[r1 ^ 1]), oy), iy), fz = MUL(SUB(LOADU(n->box[r2 ^ 1]), oz), iz);      \
                V t0 = MAX(MAX(nx, ny), MAX(nz, zero));                                                            \
                V t1 = MIN(MUL(MIN(MIN(fx, fy), fz), widen), SET1(tmax));                                          \
                unsigned mask = (unsigned)LEMASK(t0, t1);                                                          \
                if (mask) {                                                                                        \
                    STOREU(tn, t0);                                                                                \
                    PT_ASSERT(sp + W <= (W - 1) * PT__BVH_MAX_DEPTH + W);                                          \
                    ref = pt__wide_push(n->child, mask, tn, stack_ref, stack_t, &sp, closest);                     \
                    continue;                                                                                      \
                }                                                                                                  \
            } else if (closest) {                                                                                  \
                pt__leaf_closest_call(s, tv, ref, tmax0, b);                                                       \
                if (b->found) tmax = b->t;                                                                         \
            } else if (pt__leaf_any_call(s, tv, ref, tmax, skip)) {                                                \
                return 1;                                                                                          \
            }                                                                                                      \
            for (;;) {                                                                                             \
                if (sp == 0) return 0;                                                                             \
                --sp;                                                                                              \
                if (!closest || stack_t[sp] <= tmax) break;                                                        \
            }                                                                                                      \
            ref = stack_ref[sp];                                                                                   \
        }                                                                                                          \
    }

#define PT__LE8(a, b) _mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ))
PT__WIDE_TRAVERSAL(pt__bvh_trace8, PT__TARGET_AVX2, 8, pt__node8, __m256, _mm256_set1_ps, _mm256_loadu_ps,
                   _mm256_sub_ps, _mm256_mul_ps, _mm256_max_ps, _mm256_min_ps, _mm256_storeu_ps, PT__LE8)
#define PT__LE16(a, b) _mm512_cmp_ps_mask(a, b, _CMP_LE_OQ)
/* the zero-masked forms under a full mask: g++ 12 warns about the plain ones' undefined pass-through */
#define PT__MAX16(a, b) _mm512_maskz_max_ps((__mmask16)0xffff, a, b)
#define PT__MIN16(a, b) _mm512_maskz_min_ps((__mmask16)0xffff, a, b)
PT__WIDE_TRAVERSAL(pt__bvh_trace16, PT__TARGET_AVX512, 16, pt__node16, __m512, _mm512_set1_ps, _mm512_loadu_ps,
                   _mm512_sub_ps, _mm512_mul_ps, PT__MAX16, PT__MIN16, _mm512_storeu_ps, PT__LE16)
#endif

/* Closest hit: returns 1 and the primitive index (into s->prims), t and barycentrics. The node
   width is the one the scene was committed with (pt_simd_level); every width finds the same hit. */
static int pt__bvh_closest(const pt_scene *s, const pt__rayctx *rc, float tmax, uint32_t *prim, float *t_out,
                           float *bary)
{
    pt__trav tv;
    pt__best b;
    if (!s->node_count) return 0;
    pt__trav_init(&tv, rc, s->simd);
    b.found = 0; b.t = tmax; b.prim = 0;
#ifdef PT__WIDE
    if (s->bvh_width == 16) pt__bvh_trace16(s, &tv, tmax, &b, 0, 1);
    else if (s->bvh_width == 8) pt__bvh_trace8(s, &tv, tmax, &b, 0, 1);
    else
#endif
        pt__bvh_closest4(s, &tv, tmax, &b);
    if (!b.found) return 0;
    *prim = b.prim; *t_out = b.t;
    bary[0] = b.bary[0]; bary[1] = b.bary[1]; bary[2] = b.bary[2];
    return 1;
}

/* Any hit with 0 < t < tmax (shadow rays): stops at the first primitive found. Quad and sphere
   blocks that hold only primitive `skip` (one-primitive leaves, PT__BVH_SMALL_SCENE) are not
   tested: the shadow ray towards a point sampled on a light passes its own light (0xffffffff:
   none). */
static int pt__bvh_any(const pt_scene *s, const pt__rayctx *rc, float tmax, uint32_t skip)
{
    pt__trav tv;
    if (!s->node_count) return 0;
    pt__trav_init(&tv, rc, s->simd);
#ifdef PT__WIDE
    if (s->bvh_width == 16) return pt__bvh_trace16(s, &tv, tmax, NULL, skip, 0);
    if (s->bvh_width == 8) return pt__bvh_trace8(s, &tv, tmax, NULL, skip, 0);
#endif
    return pt__bvh_any4(s, &tv, tmax, skip);
}

/* --- Packets for small scenes (the batched integrator, section 7). A scene of at most
   PT__PACKET_MAX quads and spheres (no triangles) is small enough that testing a ray against
   every primitive costs less than a BVH descent; the batched integrator's closest hits then test
   four rays at once (SSE2 lanes = rays) against each primitive in turn, with each lane doing
   exactly the float operations of pt__hit_quad and pt__hit_sphere (as the leaf blocks' SIMD tests
   above do with lanes = primitives; the lanes their margins or the tiny-sphere case send to the
   scalar tests go there too). The BVH never culls what these tests accept (pt__quad_margin), and
   the hit kept is the one of least (t, public id), as pt__best_offer keeps, so a ray's hit is the
   BVH's bit for bit. (The door scene's 38 primitives run 1.19x the BVH's speed this way:
   bench/README.md, "Two revisions side by side".) */
#define PT__PACKET_MAX 64
typedef struct pt__packet_scene {
    int n;                          /* primitives, in public id order; 0: not a small scene */
    uint32_t prim[PT__PACKET_MAX];  /* index into s->prims */
    int sphere[PT__PACKET_MAX];
    float v[PT__PACKET_MAX][14];    /* a quad's pt__quad4 fields, a sphere's centre and radius */
    int chunks;                     /* runs of primitives (in that order) under one box: */
    int chunk_end[PT__PACKET_MAX];  /* run c ends before primitive chunk_end[c] */
    float box[PT__PACKET_MAX][6];   /* its bounds as the BVH's nodes pad them (lo xyz, hi xyz) */
} pt__packet_scene;

#ifdef PT__SSE
/* Whether scene s is small in that sense (and traced by the built-in BVH with SIMD). */
static int pt__packet_small(const pt_scene *s)
{
    uint32_t i;
    if (s->backend != PT_BACKEND_BUILTIN || s->simd == PT_SIMD_SCALAR || s->prim_count > PT__PACKET_MAX ||
        s->prim_count == 0)
        return 0;
    for (i = 0; i < s->prim_count; ++i)
        if (s->prims[i].type == PT__PRIM_TRIANGLE) return 0;
    return 1;
}
#endif
#ifdef PT__SSE
/* The packets' runs of primitives under one box (the 16-ray packets test a run's box before its
   primitives, as the BVH tests a node's): from each primitive, the longest run of at most 6 whose
   box's half area is at most the sum of its primitives', as the faces of a box (a scene file's
   `box`) or of a room. */
static void pt__packet_chunks(const pt_scene *s, pt__packet_scene *ps)
{
    int i = 0, c = 0;
    while (i < ps->n) {
        pt_vec3 lo, hi, plo, phi, blo, bhi;
        float sum;
        int k, best = 1;
        pt__prim_bounds(&s->prims[ps->prim[i]], &lo, &hi);
        blo = lo; bhi = hi;
        sum = pt__half_area(lo, hi);
        for (k = 2; k <= 6 && i + k <= ps->n; ++k) {
            pt__prim_bounds(&s->prims[ps->prim[i + k - 1]], &plo, &phi);
            lo = pt__vmin(lo, plo); hi = pt__vmax(hi, phi);
            sum += pt__half_area(plo, phi);
            if (pt__half_area(lo, hi) <= sum) { best = k; blo = lo; bhi = hi; }
        }
        i += best;
        ps->chunk_end[c] = i;
        ps->box[c][0] = pt__pad_down(blo.x); ps->box[c][1] = pt__pad_down(blo.y); ps->box[c][2] = pt__pad_down(blo.z);
        ps->box[c][3] = pt__pad_up(bhi.x); ps->box[c][4] = pt__pad_up(bhi.y); ps->box[c][5] = pt__pad_up(bhi.z);
        ++c;
    }
    ps->chunks = c;
}
#endif
/* Sets up the packets of scene s, or ps->n = 0 when it is not small. */
static void pt__packet_init(const pt_scene *s, pt__packet_scene *ps)
{
    uint32_t i, j;
    ps->n = 0;
#ifdef PT__SSE
    if (!pt__packet_small(s)) return;
    for (i = 0; i < s->prim_count; ++i) { /* by public id (insertion) */
        for (j = (uint32_t)ps->n; j > 0 && s->prims[ps->prim[j - 1]].id > s->prims[i].id; --j) ps->prim[j] = ps->prim[j - 1];
        ps->prim[j] = i;
        ps->n++;
    }
    for (i = 0; i < (uint32_t)ps->n; ++i) {
        const pt__prim *p = &s->prims[ps->prim[i]];
        float *v = ps->v[i];
        ps->sphere[i] = p->type == PT__PRIM_SPHERE;
        memset(v, 0, sizeof ps->v[i]);
        if (ps->sphere[i]) {
            v[0] = p->p0.x; v[1] = p->p0.y; v[2] = p->p0.z; v[3] = p->p1.x;
        } else {
            v[0] = p->p0.x; v[1] = p->p0.y; v[2] = p->p0.z;
            v[3] = p->n.x; v[4] = p->n.y; v[5] = p->n.z;
            v[6] = p->w.x; v[7] = p->w.y; v[8] = p->w.z;
            v[9] = p->w2.x; v[10] = p->w2.y; v[11] = p->w2.z;
            pt__quad_edge_caps(p, &v[12], &v[13]);
        }
    }
    pt__packet_chunks(s, ps);
#else
    (void)s; (void)i; (void)j;
#endif
}

#ifdef PT__SSE
/* Quad i of ps against 4 rays (o, d by axis): the lanes hit with 0 < t (mask) and their t. */
static PT__HOT int pt__packet_quad(const pt_scene *s, const pt__packet_scene *ps, int i, const __m128 *o, const __m128 *d,
                                   const pt__rayctx *const *rc, __m128 *t_out)
{
    const float *v = ps->v[i];
    __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    __m128 nx = _mm_set1_ps(v[3]), ny = _mm_set1_ps(v[4]), nz = _mm_set1_ps(v[5]);
    __m128 px = _mm_set1_ps(v[0]), py = _mm_set1_ps(v[1]), pz = _mm_set1_ps(v[2]);
    __m128 denom = _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, d[0]), _mm_mul_ps(ny, d[1])), _mm_mul_ps(nz, d[2]));
    __m128 ok = _mm_cmpneq_ps(denom, zero), t, hx, hy, hz, a, bb, out;
    float ts[4];
    int bits, edge, lane;
    if (!_mm_movemask_ps(ok)) return 0;
    t = _mm_add_ps(_mm_add_ps(_mm_mul_ps(nx, _mm_sub_ps(px, o[0])), _mm_mul_ps(ny, _mm_sub_ps(py, o[1]))),
                   _mm_mul_ps(nz, _mm_sub_ps(pz, o[2])));
    t = _mm_div_ps(t, _mm_or_ps(_mm_and_ps(ok, denom), _mm_andnot_ps(ok, one)));
    ok = _mm_and_ps(ok, _mm_and_ps(_mm_cmpgt_ps(t, zero), _mm_cmplt_ps(t, _mm_set1_ps(PT__INF))));
    if (!_mm_movemask_ps(ok)) return 0;
    t = _mm_and_ps(ok, t); /* (as pt__quad4_hit_sse) */
    hx = _mm_sub_ps(_mm_add_ps(o[0], _mm_mul_ps(d[0], t)), px);
    hy = _mm_sub_ps(_mm_add_ps(o[1], _mm_mul_ps(d[1], t)), py);
    hz = _mm_sub_ps(_mm_add_ps(o[2], _mm_mul_ps(d[2], t)), pz);
    a = _mm_add_ps(_mm_add_ps(_mm_mul_ps(hx, _mm_set1_ps(v[6])), _mm_mul_ps(hy, _mm_set1_ps(v[7]))),
                   _mm_mul_ps(hz, _mm_set1_ps(v[8])));
    bb = _mm_add_ps(_mm_add_ps(_mm_mul_ps(hx, _mm_set1_ps(v[9])), _mm_mul_ps(hy, _mm_set1_ps(v[10]))),
                    _mm_mul_ps(hz, _mm_set1_ps(v[11])));
    out = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(a, zero), _mm_cmpgt_ps(a, one)),
                    _mm_or_ps(_mm_cmplt_ps(bb, zero), _mm_cmpgt_ps(bb, one)));
    bits = _mm_movemask_ps(_mm_andnot_ps(out, ok));
    edge = _mm_movemask_ps(_mm_and_ps(out, ok));
    if (edge) { /* pt__hit_quad's margin decides the lanes within the caps */
        __m128 ta = _mm_set1_ps(v[12]), tb = _mm_set1_ps(v[13]);
        __m128 far_out = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(a, _mm_sub_ps(zero, ta)), _mm_cmpgt_ps(a, _mm_add_ps(one, ta))),
                                   _mm_or_ps(_mm_cmplt_ps(bb, _mm_sub_ps(zero, tb)), _mm_cmpgt_ps(bb, _mm_add_ps(one, tb))));
        edge &= ~_mm_movemask_ps(far_out);
        if (edge) {
            _mm_storeu_ps(ts, t);
            for (lane = 0; lane < 4; ++lane) {
                float tq;
                if ((edge & (1 << lane)) && pt__hit_quad(rc[lane], &s->prims[ps->prim[i]], PT__INF, &tq)) {
                    bits |= 1 << lane;
                    ts[lane] = tq;
                }
            }
            t = _mm_loadu_ps(ts);
        }
    }
    *t_out = t;
    return bits;
}

/* Sphere i of ps against 4 rays (pt__sphere4_hit_sse with lanes = rays; aa = d.d by lane). */
static PT__HOT int pt__packet_sphere(const pt__packet_scene *ps, int i, const __m128 *o, const __m128 *d, __m128 aa,
                                     const pt__rayctx *const *rc, __m128 *t_out)
{
    const float *v = ps->v[i];
    __m128 zero = _mm_setzero_ps(), sign = _mm_set1_ps(-0.0f), r = _mm_set1_ps(v[3]), fx, fy, fz, bp, ff, rr, k;
    __m128 lx, ly, lz, ll, disc, ok, cc, sq, qq, qd, t0, t1, sw, lo, hi, h0, h1, t, inf = _mm_set1_ps(PT__INF);
    int bits, tiny, lane;
    fx = _mm_sub_ps(o[0], _mm_set1_ps(v[0]));
    fy = _mm_sub_ps(o[1], _mm_set1_ps(v[1]));
    fz = _mm_sub_ps(o[2], _mm_set1_ps(v[2]));
    bp = _mm_xor_ps(sign, _mm_add_ps(_mm_add_ps(_mm_mul_ps(fx, d[0]), _mm_mul_ps(fy, d[1])), _mm_mul_ps(fz, d[2])));
    ff = _mm_add_ps(_mm_add_ps(_mm_mul_ps(fx, fx), _mm_mul_ps(fy, fy)), _mm_mul_ps(fz, fz));
    rr = _mm_mul_ps(r, r);
    tiny = _mm_movemask_ps(_mm_cmplt_ps(rr, _mm_mul_ps(_mm_set1_ps(1e-6f), ff)));
    k = _mm_div_ps(bp, aa);
    lx = _mm_add_ps(fx, _mm_mul_ps(d[0], k));
    ly = _mm_add_ps(fy, _mm_mul_ps(d[1], k));
    lz = _mm_add_ps(fz, _mm_mul_ps(d[2], k));
    ll = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(lx, lx), _mm_mul_ps(ly, ly)), _mm_mul_ps(lz, lz)));
    disc = _mm_mul_ps(_mm_mul_ps(aa, _mm_sub_ps(r, ll)), _mm_add_ps(r, ll));
    ok = _mm_andnot_ps(_mm_cmplt_ps(disc, zero), _mm_castsi128_ps(_mm_set1_epi32(-1)));
    cc = _mm_sub_ps(ff, rr);
    sq = _mm_sqrt_ps(_mm_and_ps(ok, disc)); /* no square root of a negative: FE_INVALID traps */
    qq = _mm_add_ps(bp, _mm_or_ps(_mm_andnot_ps(sign, sq), _mm_and_ps(sign, bp)));
    ok = _mm_andnot_ps(_mm_cmpeq_ps(qq, zero), ok);
    qd = _mm_or_ps(_mm_and_ps(ok, qq), _mm_andnot_ps(ok, _mm_set1_ps(1.0f)));
    t0 = _mm_div_ps(cc, qd);
    t1 = _mm_div_ps(qq, aa);
    sw = _mm_cmpgt_ps(t0, t1);
    lo = _mm_or_ps(_mm_and_ps(sw, t1), _mm_andnot_ps(sw, t0));
    hi = _mm_or_ps(_mm_and_ps(sw, t0), _mm_andnot_ps(sw, t1));
    h0 = _mm_and_ps(_mm_cmpgt_ps(lo, zero), _mm_cmplt_ps(lo, inf));
    h1 = _mm_and_ps(_mm_cmpgt_ps(hi, zero), _mm_cmplt_ps(hi, inf));
    t = _mm_or_ps(_mm_and_ps(h0, lo), _mm_andnot_ps(h0, hi));
    bits = _mm_movemask_ps(_mm_and_ps(ok, _mm_or_ps(h0, h1))) & ~tiny;
    if (tiny) { /* tiny or distant: pt__hit_sphere's double-precision case */
        float ts[4];
        _mm_storeu_ps(ts, t);
        for (lane = 0; lane < 4; ++lane) {
            float tz;
            if ((tiny & (1 << lane)) &&
                pt__hit_sphere(rc[lane], pt_v3(v[0], v[1], v[2]), v[3], PT__INF, &tz)) {
                bits |= 1 << lane;
                ts[lane] = tz;
            }
        }
        t = _mm_loadu_ps(ts);
    }
    *t_out = t;
    return bits;
}

/* The closest hits of n <= 4 rays (pt__scene_closest's results, tmax infinite). */
static PT__HOT void pt__packet_closest4(const pt_scene *s, const pt__packet_scene *ps, const pt__rayctx *const *rc4, int n,
                                        int *found, uint32_t *prim, float *t_out)
{
    const pt__rayctx *rc[4];
    float buf[6][4];
    __m128 o[3], d[3], aa, best = _mm_set1_ps(PT__INF);
    int lane, i, any = 0;
    uint32_t bp[4] = { 0, 0, 0, 0 };
    for (lane = 0; lane < 4; ++lane) {
        rc[lane] = rc4[lane < n ? lane : 0]; /* (the padding repeats ray 0; its results are dropped) */
        buf[0][lane] = rc[lane]->o.x; buf[1][lane] = rc[lane]->o.y; buf[2][lane] = rc[lane]->o.z;
        buf[3][lane] = rc[lane]->d.x; buf[4][lane] = rc[lane]->d.y; buf[5][lane] = rc[lane]->d.z;
    }
    for (i = 0; i < 3; ++i) {
        o[i] = _mm_loadu_ps(buf[i]);
        d[i] = _mm_loadu_ps(buf[3 + i]);
    }
    aa = _mm_add_ps(_mm_add_ps(_mm_mul_ps(d[0], d[0]), _mm_mul_ps(d[1], d[1])), _mm_mul_ps(d[2], d[2]));
    for (i = 0; i < ps->n; ++i) {
        __m128 t, closer;
        int bits = ps->sphere[i] ? pt__packet_sphere(ps, i, o, d, aa, rc, &t) : pt__packet_quad(s, ps, i, o, d, rc, &t);
        if (!bits) continue; /* no lane hit it (t is then not set) */
        /* strictly closer: at a tie the primitive of lower id (visited first) stays */
        closer = _mm_cmplt_ps(t, best);
        bits &= _mm_movemask_ps(closer);
        if (!bits) continue;
        for (lane = 0; lane < 4; ++lane)
            if (bits & (1 << lane)) bp[lane] = ps->prim[i];
        { /* best = t in the lanes of bits */
            __m128i sel = _mm_set_epi32(8, 4, 2, 1);
            __m128 m = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(_mm_set1_epi32(bits), sel), sel));
            best = _mm_or_ps(_mm_and_ps(m, t), _mm_andnot_ps(m, best));
        }
        any |= bits;
    }
    {
        float bt[4];
        _mm_storeu_ps(bt, best);
        for (lane = 0; lane < n; ++lane) {
            found[lane] = (any >> lane) & 1;
            prim[lane] = bp[lane];
            t_out[lane] = bt[lane];
        }
    }
}
#endif
#ifdef PT__WIDE
#define PT__LT8(a, b) _mm256_cmp_ps((a), (b), _CMP_LT_OS) /* (cmpltps's predicate) */
#define PT__GT8(a, b) _mm256_cmp_ps((b), (a), _CMP_LT_OS)
#define PT__EQ8(a, b) _mm256_cmp_ps((a), (b), _CMP_EQ_OQ)
/* The same three with AVX2, 8 rays at a time (pt_simd_level AVX2 and up). */
PT__TARGET_AVX2 static PT__HOT int pt__packet_quad8(const pt_scene *s, const pt__packet_scene *ps, int i, const __m256 *o, const __m256 *d,
                                   const pt__rayctx *const *rc, __m256 best, __m256 *t_out)
{
    const float *v = ps->v[i];
    __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
    __m256 nx = _mm256_set1_ps(v[3]), ny = _mm256_set1_ps(v[4]), nz = _mm256_set1_ps(v[5]);
    __m256 px = _mm256_set1_ps(v[0]), py = _mm256_set1_ps(v[1]), pz = _mm256_set1_ps(v[2]);
    __m256 denom = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, d[0]), _mm256_mul_ps(ny, d[1])), _mm256_mul_ps(nz, d[2]));
    __m256 ok = _mm256_cmp_ps(denom, zero, _CMP_NEQ_UQ), t, hx, hy, hz, a, bb, out;
    float ts[8];
    int bits, edge, lane;
    if (!_mm256_movemask_ps(ok)) return 0;
    t = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, _mm256_sub_ps(px, o[0])), _mm256_mul_ps(ny, _mm256_sub_ps(py, o[1]))),
                   _mm256_mul_ps(nz, _mm256_sub_ps(pz, o[2])));
    t = _mm256_div_ps(t, _mm256_or_ps(_mm256_and_ps(ok, denom), _mm256_andnot_ps(ok, one)));
    /* t < best (<= inf): a lane whose nearest hit so far is not farther cannot take this quad
       (the caller keeps the strictly closer), so it skips the rest, the edge test included
       (whose t is this t: pt__hit_quad's operations) */
    ok = _mm256_and_ps(ok, _mm256_and_ps(PT__GT8(t, zero), PT__LT8(t, best)));
    if (!_mm256_movemask_ps(ok)) return 0;
    t = _mm256_and_ps(ok, t); /* (as pt__quad4_hit_sse) */
    hx = _mm256_sub_ps(_mm256_add_ps(o[0], _mm256_mul_ps(d[0], t)), px);
    hy = _mm256_sub_ps(_mm256_add_ps(o[1], _mm256_mul_ps(d[1], t)), py);
    hz = _mm256_sub_ps(_mm256_add_ps(o[2], _mm256_mul_ps(d[2], t)), pz);
    a = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(hx, _mm256_set1_ps(v[6])), _mm256_mul_ps(hy, _mm256_set1_ps(v[7]))),
                   _mm256_mul_ps(hz, _mm256_set1_ps(v[8])));
    bb = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(hx, _mm256_set1_ps(v[9])), _mm256_mul_ps(hy, _mm256_set1_ps(v[10]))),
                    _mm256_mul_ps(hz, _mm256_set1_ps(v[11])));
    out = _mm256_or_ps(_mm256_or_ps(PT__LT8(a, zero), PT__GT8(a, one)),
                    _mm256_or_ps(PT__LT8(bb, zero), PT__GT8(bb, one)));
    bits = _mm256_movemask_ps(_mm256_andnot_ps(out, ok));
    edge = _mm256_movemask_ps(_mm256_and_ps(out, ok));
    if (edge) { /* pt__hit_quad's margin decides the lanes within the caps */
        __m256 ta = _mm256_set1_ps(v[12]), tb = _mm256_set1_ps(v[13]);
        __m256 far_out = _mm256_or_ps(_mm256_or_ps(PT__LT8(a, _mm256_sub_ps(zero, ta)), PT__GT8(a, _mm256_add_ps(one, ta))),
                                   _mm256_or_ps(PT__LT8(bb, _mm256_sub_ps(zero, tb)), PT__GT8(bb, _mm256_add_ps(one, tb))));
        edge &= ~_mm256_movemask_ps(far_out);
        if (edge) {
            _mm256_storeu_ps(ts, t);
            for (lane = 0; lane < 8; ++lane) {
                float tq;
                if ((edge & (1 << lane)) && pt__hit_quad(rc[lane], &s->prims[ps->prim[i]], PT__INF, &tq)) {
                    bits |= 1 << lane;
                    ts[lane] = tq;
                }
            }
            t = _mm256_loadu_ps(ts);
        }
    }
    *t_out = t;
    return bits;
}

/* (lim: each lane's tmax, pt__hit_sphere's; 0 for a lane not to test) */
PT__TARGET_AVX2 static PT__HOT int pt__packet_sphere8(const pt__packet_scene *ps, int i, const __m256 *o, const __m256 *d, __m256 aa,
                                     const pt__rayctx *const *rc, __m256 lim, __m256 *t_out)
{
    const float *v = ps->v[i];
    __m256 zero = _mm256_setzero_ps(), sign = _mm256_set1_ps(-0.0f), r = _mm256_set1_ps(v[3]), fx, fy, fz, bp, ff, rr, k;
    __m256 lx, ly, lz, ll, disc, ok, cc, sq, qq, qd, t0, t1, sw, lo, hi, h0, h1, t;
    int bits, tiny, lane;
    fx = _mm256_sub_ps(o[0], _mm256_set1_ps(v[0]));
    fy = _mm256_sub_ps(o[1], _mm256_set1_ps(v[1]));
    fz = _mm256_sub_ps(o[2], _mm256_set1_ps(v[2]));
    bp = _mm256_xor_ps(sign, _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(fx, d[0]), _mm256_mul_ps(fy, d[1])), _mm256_mul_ps(fz, d[2])));
    ff = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(fx, fx), _mm256_mul_ps(fy, fy)), _mm256_mul_ps(fz, fz));
    rr = _mm256_mul_ps(r, r);
    tiny = _mm256_movemask_ps(_mm256_and_ps(PT__LT8(rr, _mm256_mul_ps(_mm256_set1_ps(1e-6f), ff)), PT__GT8(lim, zero)));
    k = _mm256_div_ps(bp, aa);
    lx = _mm256_add_ps(fx, _mm256_mul_ps(d[0], k));
    ly = _mm256_add_ps(fy, _mm256_mul_ps(d[1], k));
    lz = _mm256_add_ps(fz, _mm256_mul_ps(d[2], k));
    ll = _mm256_sqrt_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(lx, lx), _mm256_mul_ps(ly, ly)), _mm256_mul_ps(lz, lz)));
    disc = _mm256_mul_ps(_mm256_mul_ps(aa, _mm256_sub_ps(r, ll)), _mm256_add_ps(r, ll));
    ok = _mm256_andnot_ps(PT__LT8(disc, zero), _mm256_castsi256_ps(_mm256_set1_epi32(-1)));
    cc = _mm256_sub_ps(ff, rr);
    sq = _mm256_sqrt_ps(_mm256_and_ps(ok, disc)); /* no square root of a negative: FE_INVALID traps */
    qq = _mm256_add_ps(bp, _mm256_or_ps(_mm256_andnot_ps(sign, sq), _mm256_and_ps(sign, bp)));
    ok = _mm256_andnot_ps(PT__EQ8(qq, zero), ok);
    qd = _mm256_or_ps(_mm256_and_ps(ok, qq), _mm256_andnot_ps(ok, _mm256_set1_ps(1.0f)));
    t0 = _mm256_div_ps(cc, qd);
    t1 = _mm256_div_ps(qq, aa);
    sw = PT__GT8(t0, t1);
    lo = _mm256_or_ps(_mm256_and_ps(sw, t1), _mm256_andnot_ps(sw, t0));
    hi = _mm256_or_ps(_mm256_and_ps(sw, t0), _mm256_andnot_ps(sw, t1));
    h0 = _mm256_and_ps(PT__GT8(lo, zero), PT__LT8(lo, lim));
    h1 = _mm256_and_ps(PT__GT8(hi, zero), PT__LT8(hi, lim));
    t = _mm256_or_ps(_mm256_and_ps(h0, lo), _mm256_andnot_ps(h0, hi));
    bits = _mm256_movemask_ps(_mm256_and_ps(ok, _mm256_or_ps(h0, h1))) & ~tiny;
    if (tiny) { /* tiny or distant: pt__hit_sphere's double-precision case */
        float ts[8], lims[8];
        _mm256_storeu_ps(ts, t);
        _mm256_storeu_ps(lims, lim);
        for (lane = 0; lane < 8; ++lane) {
            float tz;
            if ((tiny & (1 << lane)) &&
                pt__hit_sphere(rc[lane], pt_v3(v[0], v[1], v[2]), v[3], lims[lane], &tz)) {
                bits |= 1 << lane;
                ts[lane] = tz;
            }
        }
        t = _mm256_loadu_ps(ts);
    }
    *t_out = t;
    return bits;
}

PT__TARGET_AVX2 static void pt__packet_closest8(const pt_scene *s, const pt__packet_scene *ps, const pt__rayctx *const *rc4, int n,
                                        int *found, uint32_t *prim, float *t_out)
{
    const pt__rayctx *rc[8];
    float buf[6][8];
    __m256 o[3], d[3], aa, inf = _mm256_set1_ps(PT__INF), best = inf;
    __m256i bpv = _mm256_setzero_si256();
    int lane, i, any = 0;
    uint32_t bp[8];
    for (lane = 0; lane < 8; ++lane) {
        rc[lane] = rc4[lane < n ? lane : 0]; /* (the padding repeats ray 0; its results are dropped) */
        buf[0][lane] = rc[lane]->o.x; buf[1][lane] = rc[lane]->o.y; buf[2][lane] = rc[lane]->o.z;
        buf[3][lane] = rc[lane]->d.x; buf[4][lane] = rc[lane]->d.y; buf[5][lane] = rc[lane]->d.z;
    }
    for (i = 0; i < 3; ++i) {
        o[i] = _mm256_loadu_ps(buf[i]);
        d[i] = _mm256_loadu_ps(buf[3 + i]);
    }
    aa = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(d[0], d[0]), _mm256_mul_ps(d[1], d[1])), _mm256_mul_ps(d[2], d[2]));
    for (i = 0; i < ps->n; ++i) {
        __m256 t, closer;
        int bits = ps->sphere[i] ? pt__packet_sphere8(ps, i, o, d, aa, rc, inf, &t) : pt__packet_quad8(s, ps, i, o, d, rc, best, &t);
        if (!bits) continue; /* no lane hit it (t is then not set) */
        /* strictly closer: at a tie the primitive of lower id (visited first) stays */
        closer = PT__LT8(t, best);
        bits &= _mm256_movemask_ps(closer);
        if (!bits) continue;
        { /* best = t and the primitive = this one in the lanes of bits */
            __m256i sel = _mm256_set_epi32(128, 64, 32, 16, 8, 4, 2, 1);
            __m256i mi = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(bits), sel), sel);
            __m256 m = _mm256_castsi256_ps(mi);
            best = _mm256_or_ps(_mm256_and_ps(m, t), _mm256_andnot_ps(m, best));
            bpv = _mm256_or_si256(_mm256_and_si256(mi, _mm256_set1_epi32((int)ps->prim[i])), _mm256_andnot_si256(mi, bpv));
        }
        any |= bits;
    }
    {
        float bt[8];
        _mm256_storeu_ps(bt, best);
        _mm256_storeu_si256((__m256i *)(void *)bp, bpv);
        for (lane = 0; lane < n; ++lane) {
            found[lane] = (any >> lane) & 1;
            prim[lane] = bp[lane];
            t_out[lane] = bt[lane];
        }
    }
}

/* Any hits of n <= 8 shadow rays in a scene of at most PT__BVH_SMALL_SCENE primitives
   (pt__scene_any's answers): each ray with its own tmax and skipped primitive (0xffffffff:
   none), which in such a scene, one primitive per leaf block, the BVH skips wherever it is
   (pt__leaf_any). Returns bit `lane` set for an occluded ray. Each lane does the float
   operations of the BVH's leaf tests (pt__quad4_hit_sse's, pt__hit_sphere's for a block of one
   sphere); a lane stops testing once occluded (its bound set to 0: nothing lies at 0 < t < 0),
   and the packet when every lane is. */
PT__TARGET_AVX2 static int pt__packet_any8(const pt_scene *s, const pt__packet_scene *ps, const pt__rayctx *const *rc8,
                                           const float *tmax, const uint32_t *skip, int n)
{
    const pt__rayctx *rc[8];
    float buf[7][8];
    uint32_t sk[8];
    const int all = (1 << n) - 1;
    __m256 o[3], d[3], aa, lim;
    __m256i skv;
    const __m256i sel = _mm256_set_epi32(128, 64, 32, 16, 8, 4, 2, 1);
    int lane, i, hit = 0;
    for (lane = 0; lane < 8; ++lane) {
        const int j = lane < n ? lane : 0; /* (the padding repeats ray 0 with tmax 0: never a hit) */
        rc[lane] = rc8[j];
        buf[0][lane] = rc[lane]->o.x; buf[1][lane] = rc[lane]->o.y; buf[2][lane] = rc[lane]->o.z;
        buf[3][lane] = rc[lane]->d.x; buf[4][lane] = rc[lane]->d.y; buf[5][lane] = rc[lane]->d.z;
        buf[6][lane] = lane < n ? tmax[j] : 0.0f;
        sk[lane] = skip[j];
    }
    for (i = 0; i < 3; ++i) {
        o[i] = _mm256_loadu_ps(buf[i]);
        d[i] = _mm256_loadu_ps(buf[3 + i]);
    }
    lim = _mm256_loadu_ps(buf[6]);
    skv = _mm256_loadu_si256((const __m256i *)(const void *)sk);
    aa = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(d[0], d[0]), _mm256_mul_ps(d[1], d[1])), _mm256_mul_ps(d[2], d[2]));
    for (i = 0; i < ps->n; ++i) {
        /* the lanes that skip this primitive test it against 0 */
        __m256 skipped = _mm256_castsi256_ps(_mm256_cmpeq_epi32(skv, _mm256_set1_epi32((int)ps->prim[i])));
        __m256 bound = _mm256_andnot_ps(skipped, lim), t;
        int bits = ps->sphere[i] ? pt__packet_sphere8(ps, i, o, d, aa, rc, bound, &t)
                                 : pt__packet_quad8(s, ps, i, o, d, rc, bound, &t);
        if (!bits) continue;
        hit |= bits;
        if ((hit & all) == all) break;
        lim = _mm256_andnot_ps(_mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(bits), sel), sel)), lim);
    }
    return hit & all;
}

/* The same four with AVX-512F, 16 rays at a time (pt_simd_level AVX512): each lane does the float
   operations of its 8-wide counterpart, with the lanes' masks in mask registers. */
#define PT__LT16(a, b) _mm512_cmp_ps_mask((a), (b), _CMP_LT_OS)
#define PT__GT16(a, b) _mm512_cmp_ps_mask((b), (a), _CMP_LT_OS)
#define PT__OR16(a, b) _mm512_castsi512_ps(_mm512_or_si512(_mm512_castps_si512(a), _mm512_castps_si512(b)))
#define PT__AND16(a, b) _mm512_castsi512_ps(_mm512_and_si512(_mm512_castps_si512(a), _mm512_castps_si512(b)))
/* (the zero-masked forms under a full mask, as PT__MAX16) */
#define PT__ANDNOT16(a, b) \
    _mm512_castsi512_ps(_mm512_maskz_andnot_epi32((__mmask16)0xffff, _mm512_castps_si512(a), _mm512_castps_si512(b)))
#define PT__SQRT16(a) _mm512_maskz_sqrt_ps((__mmask16)0xffff, a)
#define PT__DOT16(ax, ay, az, bx, by, bz) \
    _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(ax, bx), _mm512_mul_ps(ay, by)), _mm512_mul_ps(az, bz))
PT__TARGET_AVX512 static PT__HOT int pt__packet_quad16(const pt_scene *s, const pt__packet_scene *ps, int i, const __m512 *o,
                                                       const __m512 *d, const pt__rayctx *const *rc, __m512 best, __m512 *t_out)
{
    const float *v = ps->v[i];
    __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
    __m512 nx = _mm512_set1_ps(v[3]), ny = _mm512_set1_ps(v[4]), nz = _mm512_set1_ps(v[5]);
    __m512 px = _mm512_set1_ps(v[0]), py = _mm512_set1_ps(v[1]), pz = _mm512_set1_ps(v[2]);
    __m512 denom = PT__DOT16(nx, ny, nz, d[0], d[1], d[2]), t, hx, hy, hz, a, bb;
    int ok = (int)_mm512_cmp_ps_mask(denom, zero, _CMP_NEQ_UQ), out, bits, edge, lane;
    if (!ok) return 0;
    t = PT__DOT16(nx, ny, nz, _mm512_sub_ps(px, o[0]), _mm512_sub_ps(py, o[1]), _mm512_sub_ps(pz, o[2]));
    t = _mm512_div_ps(t, _mm512_mask_blend_ps((__mmask16)ok, one, denom));
    /* t < best: as in pt__packet_quad8 */
    ok &= (int)(PT__GT16(t, zero) & PT__LT16(t, best));
    if (!ok) return 0;
    t = _mm512_maskz_mov_ps((__mmask16)ok, t);
    hx = _mm512_sub_ps(_mm512_add_ps(o[0], _mm512_mul_ps(d[0], t)), px);
    hy = _mm512_sub_ps(_mm512_add_ps(o[1], _mm512_mul_ps(d[1], t)), py);
    hz = _mm512_sub_ps(_mm512_add_ps(o[2], _mm512_mul_ps(d[2], t)), pz);
    a = PT__DOT16(hx, hy, hz, _mm512_set1_ps(v[6]), _mm512_set1_ps(v[7]), _mm512_set1_ps(v[8]));
    bb = PT__DOT16(hx, hy, hz, _mm512_set1_ps(v[9]), _mm512_set1_ps(v[10]), _mm512_set1_ps(v[11]));
    out = (int)(PT__LT16(a, zero) | PT__GT16(a, one) | PT__LT16(bb, zero) | PT__GT16(bb, one));
    bits = ok & ~out;
    edge = ok & out;
    if (edge) { /* pt__hit_quad's margin decides the lanes within the caps */
        __m512 ta = _mm512_set1_ps(v[12]), tb = _mm512_set1_ps(v[13]);
        edge &= ~(int)(PT__LT16(a, _mm512_sub_ps(zero, ta)) | PT__GT16(a, _mm512_add_ps(one, ta)) |
                       PT__LT16(bb, _mm512_sub_ps(zero, tb)) | PT__GT16(bb, _mm512_add_ps(one, tb)));
        if (edge) {
            float ts[16];
            _mm512_storeu_ps(ts, t);
            for (lane = 0; lane < 16; ++lane) {
                float tq;
                if ((edge & (1 << lane)) && pt__hit_quad(rc[lane], &s->prims[ps->prim[i]], PT__INF, &tq)) {
                    bits |= 1 << lane;
                    ts[lane] = tq;
                }
            }
            t = _mm512_loadu_ps(ts);
        }
    }
    *t_out = t;
    return bits;
}

/* (lim: each lane's tmax, pt__hit_sphere's; 0 for a lane not to test) */
PT__TARGET_AVX512 static PT__HOT int pt__packet_sphere16(const pt__packet_scene *ps, int i, const __m512 *o, const __m512 *d,
                                                         __m512 aa, const pt__rayctx *const *rc, __m512 lim, __m512 *t_out)
{
    const float *v = ps->v[i];
    __m512 zero = _mm512_setzero_ps(), sign = _mm512_set1_ps(-0.0f), r = _mm512_set1_ps(v[3]), fx, fy, fz, bp, ff, rr, k;
    __m512 lx, ly, lz, ll, disc, cc, sq, qq, qd, t0, t1, lo, hi, t;
    int bits, tiny, lane, ok, sw, h0, h1;
    fx = _mm512_sub_ps(o[0], _mm512_set1_ps(v[0]));
    fy = _mm512_sub_ps(o[1], _mm512_set1_ps(v[1]));
    fz = _mm512_sub_ps(o[2], _mm512_set1_ps(v[2]));
    bp = _mm512_castsi512_ps(_mm512_xor_si512(_mm512_castps_si512(sign), _mm512_castps_si512(PT__DOT16(fx, fy, fz, d[0], d[1], d[2]))));
    ff = PT__DOT16(fx, fy, fz, fx, fy, fz);
    rr = _mm512_mul_ps(r, r);
    tiny = (int)(PT__LT16(rr, _mm512_mul_ps(_mm512_set1_ps(1e-6f), ff)) & PT__GT16(lim, zero));
    k = _mm512_div_ps(bp, aa);
    lx = _mm512_add_ps(fx, _mm512_mul_ps(d[0], k));
    ly = _mm512_add_ps(fy, _mm512_mul_ps(d[1], k));
    lz = _mm512_add_ps(fz, _mm512_mul_ps(d[2], k));
    ll = PT__SQRT16(PT__DOT16(lx, ly, lz, lx, ly, lz));
    disc = _mm512_mul_ps(_mm512_mul_ps(aa, _mm512_sub_ps(r, ll)), _mm512_add_ps(r, ll));
    ok = 0xffff & ~(int)PT__LT16(disc, zero);
    cc = _mm512_sub_ps(ff, rr);
    sq = PT__SQRT16(_mm512_maskz_mov_ps((__mmask16)ok, disc)); /* no square root of a negative: FE_INVALID traps */
    qq = _mm512_add_ps(bp, PT__OR16(PT__ANDNOT16(sign, sq), PT__AND16(sign, bp)));
    ok &= ~(int)_mm512_cmp_ps_mask(qq, zero, _CMP_EQ_OQ);
    qd = _mm512_mask_blend_ps((__mmask16)ok, _mm512_set1_ps(1.0f), qq);
    t0 = _mm512_div_ps(cc, qd);
    t1 = _mm512_div_ps(qq, aa);
    sw = (int)PT__GT16(t0, t1);
    lo = _mm512_mask_blend_ps((__mmask16)sw, t0, t1);
    hi = _mm512_mask_blend_ps((__mmask16)sw, t1, t0);
    h0 = (int)(PT__GT16(lo, zero) & PT__LT16(lo, lim));
    h1 = (int)(PT__GT16(hi, zero) & PT__LT16(hi, lim));
    t = _mm512_mask_blend_ps((__mmask16)h0, hi, lo);
    bits = ok & (h0 | h1) & ~tiny;
    if (tiny) { /* tiny or distant: pt__hit_sphere's double-precision case */
        float ts[16], lims[16];
        _mm512_storeu_ps(ts, t);
        _mm512_storeu_ps(lims, lim);
        for (lane = 0; lane < 16; ++lane) {
            float tz;
            if ((tiny & (1 << lane)) &&
                pt__hit_sphere(rc[lane], pt_v3(v[0], v[1], v[2]), v[3], lims[lane], &tz)) {
                bits |= 1 << lane;
                ts[lane] = tz;
            }
        }
        t = _mm512_loadu_ps(ts);
    }
    *t_out = t;
    return bits;
}

/* Loads 16 rays (padding repeats ray 0) by axis into o, d, their directions' d.d into *aa and
   their inverses (pt__trav_init's: 1/0 and overflows as FLT_MAX of the sign) into inv. */
PT__TARGET_AVX512 static PT__HOT void pt__packet_load16(const pt__rayctx *const *rcn, int n, const pt__rayctx **rc, __m512 *o,
                                                        __m512 *d, __m512 *aa, __m512 *inv)
{
    float buf[6][16];
    int lane, i;
    for (lane = 0; lane < 16; ++lane) {
        rc[lane] = rcn[lane < n ? lane : 0];
        buf[0][lane] = rc[lane]->o.x; buf[1][lane] = rc[lane]->o.y; buf[2][lane] = rc[lane]->o.z;
        buf[3][lane] = rc[lane]->d.x; buf[4][lane] = rc[lane]->d.y; buf[5][lane] = rc[lane]->d.z;
    }
    for (i = 0; i < 3; ++i) {
        o[i] = _mm512_loadu_ps(buf[i]);
        d[i] = _mm512_loadu_ps(buf[3 + i]);
    }
    *aa = PT__DOT16(d[0], d[1], d[2], d[0], d[1], d[2]);
    for (i = 0; i < 3; ++i) {
        const __m512 big = _mm512_set1_ps(FLT_MAX), sign = _mm512_set1_ps(-0.0f);
        const __mmask16 nz = _mm512_cmp_ps_mask(d[i], _mm512_setzero_ps(), _CMP_NEQ_UQ);
        __m512 r = _mm512_div_ps(_mm512_set1_ps(1.0f), _mm512_mask_blend_ps(nz, _mm512_set1_ps(1.0f), d[i]));
        r = _mm512_mask_blend_ps(nz, big, r);
        inv[i] = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(PT__ANDNOT16(sign, r), big, _CMP_LE_OQ),
                                      PT__OR16(big, PT__AND16(sign, r)), r);
    }
}

/* Whether any of 16 rays meets box b (a run's, pt__packet_chunks) at some t <= its lim: the
   BVH's slab test (PT__WIDE_TRAVERSAL's, lanes = rays), so it never culls a primitive that the
   BVH would have tested. */
PT__TARGET_AVX512 static PT__HOT int pt__packet_box16(const float *b, const __m512 *o, const __m512 *inv, __m512 lim)
{
    const __m512 lx = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(b[0]), o[0]), inv[0]);
    const __m512 ly = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(b[1]), o[1]), inv[1]);
    const __m512 lz = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(b[2]), o[2]), inv[2]);
    const __m512 hx = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(b[3]), o[0]), inv[0]);
    const __m512 hy = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(b[4]), o[1]), inv[1]);
    const __m512 hz = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(b[5]), o[2]), inv[2]);
    const __m512 t0 = PT__MAX16(PT__MAX16(PT__MIN16(lx, hx), PT__MIN16(ly, hy)), PT__MAX16(PT__MIN16(lz, hz), _mm512_setzero_ps()));
    const __m512 t1 = PT__MIN16(PT__MIN16(PT__MAX16(lx, hx), PT__MAX16(ly, hy)), PT__MAX16(lz, hz));
    const __m512 far = PT__MIN16(_mm512_mul_ps(t1, _mm512_set1_ps(1.00000036f)), lim);
    return _mm512_cmp_ps_mask(t0, far, _CMP_LE_OQ) != 0;
}

/* pt__packet_closest8 for n <= 16 rays. */
PT__TARGET_AVX512 static void pt__packet_closest16(const pt_scene *s, const pt__packet_scene *ps, const pt__rayctx *const *rcn,
                                                   int n, int *found, uint32_t *prim, float *t_out)
{
    const pt__rayctx *rc[16];
    __m512 o[3], d[3], inv[3], aa, inf = _mm512_set1_ps(PT__INF), best = inf;
    __m512i bpv = _mm512_setzero_si512();
    int lane, i, c, any = 0;
    uint32_t bp[16];
    float bt[16];
    pt__packet_load16(rcn, n, rc, o, d, &aa, inv);
    for (i = 0, c = 0; i < ps->n; ++i) {
        __m512 t;
        int bits;
        if (i == (c ? ps->chunk_end[c - 1] : 0)) { /* a run's first primitive: its box first */
            const int end = ps->chunk_end[c++];
            if (end - i > 1 && !pt__packet_box16(ps->box[c - 1], o, inv, best)) {
                i = end - 1;
                continue;
            }
        }
        bits = ps->sphere[i] ? pt__packet_sphere16(ps, i, o, d, aa, rc, inf, &t) : pt__packet_quad16(s, ps, i, o, d, rc, best, &t);
        if (!bits) continue; /* no lane hit it (t is then not set) */
        /* strictly closer: at a tie the primitive of lower id (visited first) stays */
        bits &= (int)PT__LT16(t, best);
        if (!bits) continue;
        best = _mm512_mask_blend_ps((__mmask16)bits, best, t);
        bpv = _mm512_mask_blend_epi32((__mmask16)bits, bpv, _mm512_set1_epi32((int)ps->prim[i]));
        any |= bits;
    }
    _mm512_storeu_ps(bt, best);
    _mm512_storeu_si512((void *)bp, bpv);
    for (lane = 0; lane < n; ++lane) {
        found[lane] = (any >> lane) & 1;
        prim[lane] = bp[lane];
        t_out[lane] = bt[lane];
    }
}

/* pt__packet_any8 for n <= 16 rays. */
PT__TARGET_AVX512 static int pt__packet_any16(const pt_scene *s, const pt__packet_scene *ps, const pt__rayctx *const *rcn,
                                              const float *tmax, const uint32_t *skip, int n)
{
    const pt__rayctx *rc[16];
    float tm[16];
    uint32_t sk[16];
    const int all = (1 << n) - 1;
    __m512 o[3], d[3], inv[3], aa, lim;
    __m512i skv;
    int lane, i, c, hit = 0;
    pt__packet_load16(rcn, n, rc, o, d, &aa, inv);
    for (lane = 0; lane < 16; ++lane) {
        tm[lane] = lane < n ? tmax[lane] : 0.0f; /* (the padding: tmax 0, never a hit) */
        sk[lane] = skip[lane < n ? lane : 0];
    }
    lim = _mm512_loadu_ps(tm);
    skv = _mm512_loadu_si512((const void *)sk);
    for (i = 0, c = 0; i < ps->n; ++i) {
        /* the lanes that skip this primitive test it against 0 */
        __mmask16 skipped = _mm512_cmpeq_epi32_mask(skv, _mm512_set1_epi32((int)ps->prim[i]));
        __m512 bound = _mm512_maskz_mov_ps((__mmask16)~skipped, lim), t;
        int bits;
        if (i == (c ? ps->chunk_end[c - 1] : 0)) { /* a run's first primitive: its box first */
            const int end = ps->chunk_end[c++];
            if (end - i > 1 && !pt__packet_box16(ps->box[c - 1], o, inv, lim)) {
                i = end - 1;
                continue;
            }
        }
        bits = ps->sphere[i] ? pt__packet_sphere16(ps, i, o, d, aa, rc, bound, &t)
                                 : pt__packet_quad16(s, ps, i, o, d, rc, bound, &t);
        if (!bits) continue;
        hit |= bits;
        if ((hit & all) == all) break;
        lim = _mm512_maskz_mov_ps((__mmask16)~bits, lim);
    }
    return hit & all;
}
#endif

/* ------------------------------------------------------------------------------------------
   5b. Embree traversal (PDFTRACE_EMBREE). One Embree device and scene per pt_scene, made at
   commit. Geometry id = primitive type (PT__PRIM_*), one geometry per type present:
   - triangles: RTC_GEOMETRY_TYPE_TRIANGLE over the vertices stored in the primitives
     (pdftrace keeps no shared mesh vertices after pt_scene_add_mesh), shared with Embree
     rather than copied (see pt__rtc_build). Embree's hit (u, v) weights vertices
     1 and 2: pdftrace's barycentrics (weights of a, b, c) are (1 - u - v, u, v). Embree's
     triangle test differs from the built-in watertight test (Woop et al. 2013) only by
     rounding; RTC_SCENE_FLAG_ROBUST asks for its watertight variant (no cracks on shared
     edges; see PDFTRACE_EMBREE_SCENE_FLAGS).
   - quads and spheres: RTC_GEOMETRY_TYPE_USER calling pt__hit_quad and pt__hit_sphere.
     Embree's native quads would be two triangles, with t and edge decisions of their own,
     and its native spheres (RTC_GEOMETRY_TYPE_SPHERE_POINT) solve the plain quadratic, which
     loses the digits that the Haines et al. form keeps for small or distant spheres: the
     light code relies on those hits (points within 1e-5 of a sphere light count as on it).
     User geometry keeps every quad and sphere hit identical to the built-in one, at the
     price of a callback per candidate; scenes large enough for Embree to pay are meshes.
   Rays are traced from pdftrace's offset origins (no epsilon of Embree's own) with
   tnear = FLT_MIN and tfar just below tmax: the built-in accepts 0 < t < tmax, Embree
   tnear <= t <= tfar. The callbacks find pdftrace's per-ray data (pt__rayctx) in an extended
   intersect context (Embree 3 docs, rtcInitIntersectContext: "the context can be extended by
   the application").
   ------------------------------------------------------------------------------------------ */
#ifdef PDFTRACE_EMBREE

/* Scene flags and build quality (overridable): ROBUST for Embree's watertight triangle test
   (the embree test section compares 10^6 first hits with the built-in BVH's); MEDIUM, Embree's
   default quality for a static scene. */
#ifndef PDFTRACE_EMBREE_SCENE_FLAGS
#define PDFTRACE_EMBREE_SCENE_FLAGS RTC_SCENE_FLAG_ROBUST
#endif
#ifndef PDFTRACE_EMBREE_BUILD_QUALITY
#define PDFTRACE_EMBREE_BUILD_QUALITY RTC_BUILD_QUALITY_MEDIUM
#endif
/* 1: the batched integrator traces its batch's closest hits and shadow rays as Embree 3 streams
   (rtcIntersect1M, rtcOccluded1M); 0: one rtcIntersect1 / rtcOccluded1 call per ray. Embree 4
   has no stream calls: always per ray there. */
#ifndef PDFTRACE_EMBREE_STREAM
#define PDFTRACE_EMBREE_STREAM 1
#endif
/* Device configuration string passed to rtcNewDevice (NULL: Embree's defaults). */
#ifndef PDFTRACE_EMBREE_CONFIG
#define PDFTRACE_EMBREE_CONFIG NULL
#endif

typedef struct pt__rtc_ctx {
#if RTC_VERSION_MAJOR >= 4
    struct RTCRayQueryContext base; /* first member: the callbacks cast the context back */
#else
    struct RTCIntersectContext base;
#endif
    const pt__rayctx *const *rc; /* by Embree ray id: one ray (id 0, `one`) or a stream's */
    const pt__rayctx *one;
} pt__rtc_ctx;

static void pt__rtc_ctx_init(pt__rtc_ctx *c, const pt__rayctx *rc)
{
#if RTC_VERSION_MAJOR >= 4
    rtcInitRayQueryContext(&c->base);
#else
    rtcInitIntersectContext(&c->base);
#endif
    c->one = rc;
    c->rc = &c->one;
}

static const char *pt__rtc_error_name(int code)
{
    switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    default: return "unknown error";
    }
}
static int pt__rtc_result(int code)
{
    switch (code) {
    case RTC_ERROR_INVALID_ARGUMENT: return PT_ERROR_INVALID_ARGUMENT;
    case RTC_ERROR_OUT_OF_MEMORY: return PT_ERROR_OUT_OF_MEMORY;
    case RTC_ERROR_UNSUPPORTED_CPU: return PT_ERROR_UNSUPPORTED;
    case RTC_ERROR_CANCELLED: return PT_ERROR_CANCELLED;
    default: return PT_ERROR_INVALID_STATE;
    }
}

/* Device callbacks. Embree may call them from its build threads: the first error wins (a
   later one may race with it, but only ever to replace one message by another). */
static void pt__rtc_on_error(void *user, enum RTCError code, const char *str)
{
    pt_scene *s = (pt_scene *)user;
    if (!s || code == RTC_ERROR_NONE || s->rtc.error_code) return;
    s->rtc.error_code = (int)code;
    snprintf(s->rtc.error_text, sizeof s->rtc.error_text, "%s", str ? str : "");
}
static bool pt__rtc_on_memory(void *user, ssize_t bytes, bool post)
{
    pt_scene *s = (pt_scene *)user;
    (void)post; /* allocations are reported before (post = false), frees after, negative */
#if defined(__GNUC__) || defined(__clang__)
    __atomic_fetch_add(&s->rtc.device_bytes, (long long)bytes, __ATOMIC_RELAXED);
#else
    s->rtc.device_bytes += (long long)bytes; /* no atomics: a racy but harmless statistic */
#endif
    return true;
}

static void pt__rtc_release(pt_scene *s)
{
    int k;
    if (s->rtc.scene) rtcReleaseScene(s->rtc.scene);
    if (s->rtc.device) rtcReleaseDevice(s->rtc.device);
    for (k = 0; k < 3; ++k) PT_FREE(s->rtc.map[k]);
    memset(&s->rtc, 0, sizeof s->rtc);
}

/* User geometry callbacks (quads and spheres). geometryUserPtr is the geometry's pt__rtc_geom.
   Single-ray queries hand them N == 1; a stream (pt__rtc_closest_n, pt__rtc_any_n) is traced by
   Embree as packets, so N rays in SOA layout with a valid mask, each found by its id. The SOA
   fields (Embree 3 docs, RTCRayN and RTCHitN; rtcore_ray.h's accessors are C++ only): field f of
   ray i is float or unsigned [f * N + i]; the ray's tfar is field 8 and its id field 10, the hit
   (after the ray's 12 fields) has Ng x, y, z, u, v, primID, geomID, instID[0]. */
#define PT__RTCN_F(base, f, n, i) (((float *)(base))[(f) * (n) + (i)])
#define PT__RTCN_U(base, f, n, i) (((unsigned *)(void *)(base))[(f) * (n) + (i)])
#define PT__RTCN_TFAR 8u
#define PT__RTCN_ID 10u
static const pt__prim *pt__rtc_user_prim(void *user, unsigned prim_id)
{
    const pt__rtc_geom *g = (const pt__rtc_geom *)user;
    return &g->scene->prims[g->map[prim_id]];
}
static void pt__rtc_bounds(const struct RTCBoundsFunctionArguments *a)
{
    const pt__prim *p = pt__rtc_user_prim(a->geometryUserPtr, a->primID);
    pt_vec3 lo, hi;
    float e = ((const pt__rtc_geom *)a->geometryUserPtr)->pad;
    pt__prim_bounds(p, &lo, &hi);
    /* Padded like the built-in nodes, plus 2^-24 of the scene's extent: with less padding at
       coordinate 0 Embree culls some rays that run exactly in the plane of an axis-aligned quad
       (docs/internals.md, "Embree user-geometry bounds"). */
    a->bounds_o->lower_x = pt__pad_down(lo.x) - e; a->bounds_o->lower_y = pt__pad_down(lo.y) - e;
    a->bounds_o->lower_z = pt__pad_down(lo.z) - e;
    a->bounds_o->upper_x = pt__pad_up(hi.x) + e; a->bounds_o->upper_y = pt__pad_up(hi.y) + e;
    a->bounds_o->upper_z = pt__pad_up(hi.z) + e;
}
static int pt__rtc_user_hit(const pt__prim *p, const pt__rayctx *rc, float tfar, float *t)
{
    /* Embree keeps hits with t <= tfar; the built-in tests keep t < tmax */
    float tmax = nextafterf(tfar, FLT_MAX);
    return p->type == PT__PRIM_SPHERE ? pt__hit_sphere(rc, p->p0, p->p1.x, tmax, t) : pt__hit_quad(rc, p, tmax, t);
}
static void pt__rtc_intersect(const struct RTCIntersectFunctionNArguments *a)
{
    const pt__rtc_ctx *c = (const pt__rtc_ctx *)(const void *)a->context;
    float *ray = (float *)(void *)a->rayhit, *hit = ray + 12u * a->N; /* RTCRayN, then RTCHitN */
    const pt__prim *p = pt__rtc_user_prim(a->geometryUserPtr, a->primID);
    unsigned i, n = a->N;
    float t;
    for (i = 0; i < n; ++i) {
        float tfar = PT__RTCN_F(ray, PT__RTCN_TFAR, n, i);
        unsigned g = PT__RTCN_U(hit, 6, n, i);
        if (!a->valid[i] || !pt__rtc_user_hit(p, c->rc[PT__RTCN_U(ray, PT__RTCN_ID, n, i)], tfar, &t)) continue;
        /* A tie (t = the hit so far) goes to a triangle, else to the least (geomID, primID), not
           to the primitive Embree happens to visit last: a stream's packets and a single ray
           visit in different orders, and their hits must be the same. */
        if (t == tfar && g != RTC_INVALID_GEOMETRY_ID &&
            (g == PT__PRIM_TRIANGLE || g < a->geomID || (g == a->geomID && PT__RTCN_U(hit, 5, n, i) < a->primID)))
            continue;
        PT__RTCN_F(ray, PT__RTCN_TFAR, n, i) = t;
        PT__RTCN_F(hit, 0, n, i) = p->n.x; /* Ng, unused by pdftrace */
        PT__RTCN_F(hit, 1, n, i) = p->n.y;
        PT__RTCN_F(hit, 2, n, i) = p->n.z;
        PT__RTCN_F(hit, 3, n, i) = 0.0f; /* u, v */
        PT__RTCN_F(hit, 4, n, i) = 0.0f;
        PT__RTCN_U(hit, 5, n, i) = a->primID;
        PT__RTCN_U(hit, 6, n, i) = a->geomID;
        PT__RTCN_U(hit, 7, n, i) = RTC_INVALID_GEOMETRY_ID; /* instID[0] */
    }
}
static void pt__rtc_occluded(const struct RTCOccludedFunctionNArguments *a)
{
    const pt__rtc_ctx *c = (const pt__rtc_ctx *)(const void *)a->context;
    const pt__prim *p = pt__rtc_user_prim(a->geometryUserPtr, a->primID);
    float *ray = (float *)(void *)a->ray, t;
    unsigned i, n = a->N;
    for (i = 0; i < n; ++i)
        if (a->valid[i] && pt__rtc_user_hit(p, c->rc[PT__RTCN_U(ray, PT__RTCN_ID, n, i)], PT__RTCN_F(ray, PT__RTCN_TFAR, n, i), &t))
            PT__RTCN_F(ray, PT__RTCN_TFAR, n, i) = -INFINITY; /* Embree's "occluded" mark */
}

static int pt__rtc_fail(pt_scene *s, int fallback_code, const char *what)
{
    int code = s->rtc.error_code;
    if (!code && s->rtc.device) code = (int)rtcGetDeviceError(s->rtc.device);
    if (!code) code = fallback_code;
    pt__fail(s, pt__rtc_result(code), "commit: Embree %s: %s%s%s", what, pt__rtc_error_name(code),
             s->rtc.error_text[0] ? ": " : "", s->rtc.error_text);
    pt__rtc_release(s);
    return pt__rtc_result(code);
}

/* Builds the Embree scene for s->prims (in their current order). */
static int pt__rtc_build(pt_scene *s)
{
    uint32_t i, n[3] = {0, 0, 0};
    int k, code;
    float extent = 0.0f;
    pt__rtc_release(s);
    for (i = 0; i < s->prim_count; ++i) n[s->prims[i].type]++;
    for (k = 0; k < 3; ++k) {
        if (!n[k]) continue;
        s->rtc.map[k] = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * n[k]);
        if (!s->rtc.map[k]) {
            pt__rtc_release(s);
            return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "commit: out of memory for Embree (%u primitives)",
                            (unsigned)s->prim_count);
        }
    }
    for (i = 0; i < s->prim_count; ++i) {
        int t = s->prims[i].type;
        pt_vec3 lo, hi;
        s->rtc.map[t][s->rtc.count[t]++] = i;
        pt__prim_bounds(&s->prims[i], &lo, &hi);
        extent = pt__maxf(extent, pt__maxf(pt_max_component(pt_neg(lo)), pt_max_component(hi)));
    }
    for (k = 0; k < 3; ++k) {
        s->rtc.user[k].scene = s;
        s->rtc.user[k].map = s->rtc.map[k];
        s->rtc.user[k].pad = extent * 5.9604645e-8f + 1e-30f; /* 2^-24 of the largest coordinate */
    }
    s->rtc.device = rtcNewDevice(s->embree_config[0] ? s->embree_config : PDFTRACE_EMBREE_CONFIG);
    if (!s->rtc.device) {
        code = (int)rtcGetDeviceError(NULL);
        snprintf(s->rtc.error_text, sizeof s->rtc.error_text, "configuration \"%s\"",
                 s->embree_config[0] ? s->embree_config : "(default)");
        return pt__rtc_fail(s, code ? code : RTC_ERROR_UNKNOWN, "could not create a device");
    }
    rtcSetDeviceErrorFunction(s->rtc.device, pt__rtc_on_error, s);
    rtcSetDeviceMemoryMonitorFunction(s->rtc.device, pt__rtc_on_memory, s);
    s->rtc.scene = rtcNewScene(s->rtc.device);
    if (!s->rtc.scene) return pt__rtc_fail(s, RTC_ERROR_UNKNOWN, "could not create a scene");
    rtcSetSceneFlags(s->rtc.scene, (enum RTCSceneFlags)(PDFTRACE_EMBREE_SCENE_FLAGS));
    rtcSetSceneBuildQuality(s->rtc.scene, PDFTRACE_EMBREE_BUILD_QUALITY);
    for (k = 0; k < 3; ++k) {
        RTCGeometry g;
        if (!n[k]) continue;
        g = rtcNewGeometry(s->rtc.device, k == PT__PRIM_TRIANGLE ? RTC_GEOMETRY_TYPE_TRIANGLE : RTC_GEOMETRY_TYPE_USER);
        if (!g) return pt__rtc_fail(s, RTC_ERROR_UNKNOWN, "could not create a geometry");
        if (k == PT__PRIM_TRIANGLE) {
            /* Zero copy where the indices fit in 32 bits: the vertex buffer is s->prims itself,
               read as floats (byte stride 4), a triangle's vertices being the floats at its
               p0, p1 and p2; only the index buffer (12 bytes a triangle) is Embree's. The last
               element ends 16 bytes before the array does (Embree loads vertices 16 bytes at a
               time). The array stays put until the next commit (a shape added in between
               uncommits the scene, and no query runs on an uncommitted scene). */
            size_t bytes = sizeof(pt__prim) * (size_t)s->prim_count, nvert = (bytes - 16u) / 4u + 1u;
            int shared = bytes >= 16u && nvert <= 0xffffffffu;
            float *v = shared ? NULL
                              : (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                 3 * sizeof(float), 3u * (size_t)n[k]);
            unsigned *ix = (unsigned *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                               3 * sizeof(unsigned), (size_t)n[k]);
            if (shared && ix) {
                rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, s->prims, 0, 4u, nvert);
                for (i = 0; i < n[k]; ++i) {
                    size_t base = sizeof(pt__prim) * (size_t)s->rtc.map[k][i];
                    ix[3u * (size_t)i] = (unsigned)((base + offsetof(pt__prim, p0)) / 4u);
                    ix[3u * (size_t)i + 1u] = (unsigned)((base + offsetof(pt__prim, p1)) / 4u);
                    ix[3u * (size_t)i + 2u] = (unsigned)((base + offsetof(pt__prim, p2)) / 4u);
                }
            } else if (!v || !ix) {
                rtcReleaseGeometry(g);
                return pt__rtc_fail(s, RTC_ERROR_OUT_OF_MEMORY, "could not allocate the triangle buffers");
            }
            if (!shared) for (i = 0; i < n[k]; ++i) {
                const pt__prim *p = &s->prims[s->rtc.map[k][i]];
                float *w = v + 9u * (size_t)i;
                w[0] = p->p0.x; w[1] = p->p0.y; w[2] = p->p0.z;
                w[3] = p->p1.x; w[4] = p->p1.y; w[5] = p->p1.z;
                w[6] = p->p2.x; w[7] = p->p2.y; w[8] = p->p2.z;
                ix[3u * (size_t)i] = 3u * i; ix[3u * (size_t)i + 1u] = 3u * i + 1u; ix[3u * (size_t)i + 2u] = 3u * i + 2u;
            }
        } else {
            rtcSetGeometryUserPrimitiveCount(g, n[k]);
            rtcSetGeometryUserData(g, &s->rtc.user[k]);
            rtcSetGeometryBoundsFunction(g, pt__rtc_bounds, &s->rtc.user[k]);
            rtcSetGeometryIntersectFunction(g, pt__rtc_intersect);
            rtcSetGeometryOccludedFunction(g, pt__rtc_occluded);
        }
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(s->rtc.scene, g, (unsigned)k);
        rtcReleaseGeometry(g); /* the scene holds it */
    }
    rtcCommitScene(s->rtc.scene);
    code = (int)rtcGetDeviceError(s->rtc.device);
    if (code != RTC_ERROR_NONE || s->rtc.error_code) return pt__rtc_fail(s, code, "failed to build the scene");
    return PT_OK;
}

static size_t pt__rtc_bytes(const pt_scene *s)
{
    size_t b = s->rtc.device_bytes > 0 ? (size_t)s->rtc.device_bytes : 0u;
    int k;
    for (k = 0; k < 3; ++k) b += sizeof(uint32_t) * s->rtc.count[k];
    return b;
}

static PT__HOT void pt__rtc_ray(struct RTCRay *r, const pt__rayctx *rc, float tmax)
{
    r->org_x = rc->o.x; r->org_y = rc->o.y; r->org_z = rc->o.z;
    r->dir_x = rc->d.x; r->dir_y = rc->d.y; r->dir_z = rc->d.z;
    r->tnear = FLT_MIN; /* 0 < t, as the built-in: Embree keeps t >= tnear and returned t = -0 for
                           an origin on a triangle with tnear = 0 (a denormal would be flushed) */
    r->tfar = nextafterf(tmax, 0.0f); /* t < tmax, as the built-in */
    r->time = 0.0f;
    r->mask = 0xffffffffu;
    r->id = 0u;
    r->flags = 0u;
}
static int pt__rtc_ray_ok(const pt__rayctx *rc, float tmax)
{
    return tmax > 0.0f && (rc->d.x != 0.0f || rc->d.y != 0.0f || rc->d.z != 0.0f);
}

/* Embree's SIMD code relies on IEEE defaults (a zero direction component gives 1/0 = inf, and
   0 * inf = NaN in its slab tests): with a host that unmasked floating-point exceptions
   (feenableexcept(FE_INVALID | FE_DIVBYZERO)) it would raise SIGFPE. Every call into Embree
   masks all SSE exceptions (MXCSR bits 7-12) for its duration when any is unmasked and
   restores the caller's MXCSR after it (flags raised inside Embree are dropped with it);
   pdftrace's own code keeps running under the host's traps. */
#ifdef PT__HAVE_MXCSR
#define PT__RTC_GUARD_BEGIN unsigned pt__csr_ = _mm_getcsr(); if ((pt__csr_ & 0x1f80u) != 0x1f80u) _mm_setcsr(pt__csr_ | 0x1f80u)
#define PT__RTC_GUARD_END if ((pt__csr_ & 0x1f80u) != 0x1f80u) _mm_setcsr(pt__csr_)
#else
#define PT__RTC_GUARD_BEGIN (void)0
#define PT__RTC_GUARD_END (void)0
#endif

static int pt__rtc_closest(const pt_scene *s, const pt__rayctx *rc, float tmax, uint32_t *prim, float *t_out,
                           float *bary)
{
    pt__rtc_ctx c;
    struct RTCRayHit rh;
    unsigned g;
    if (!pt__rtc_ray_ok(rc, tmax)) return 0;
    pt__rtc_ctx_init(&c, rc);
    pt__rtc_ray(&rh.ray, rc, tmax);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    {
        PT__RTC_GUARD_BEGIN;
#if RTC_VERSION_MAJOR >= 4
        struct RTCIntersectArguments args;
        rtcInitIntersectArguments(&args);
        args.context = &c.base;
        rtcIntersect1(s->rtc.scene, &rh, &args);
#else
        rtcIntersect1(s->rtc.scene, &c.base, &rh);
#endif
        PT__RTC_GUARD_END;
    }
    g = rh.hit.geomID;
    if (g >= 3u || rh.hit.primID >= s->rtc.count[g]) return 0;
    *prim = s->rtc.map[g][rh.hit.primID];
    *t_out = rh.ray.tfar;
    if (g == PT__PRIM_TRIANGLE) {
        bary[0] = 1.0f - rh.hit.u - rh.hit.v;
        bary[1] = rh.hit.u;
        bary[2] = rh.hit.v;
    } else {
        bary[0] = bary[1] = bary[2] = 0.0f;
    }
    return 1;
}
static int pt__rtc_any(const pt_scene *s, const pt__rayctx *rc, float tmax)
{
    pt__rtc_ctx c;
    struct RTCRay r;
    if (!pt__rtc_ray_ok(rc, tmax)) return 0;
    pt__rtc_ctx_init(&c, rc);
    pt__rtc_ray(&r, rc, tmax);
    {
        PT__RTC_GUARD_BEGIN;
#if RTC_VERSION_MAJOR >= 4
        struct RTCOccludedArguments args;
        rtcInitOccludedArguments(&args);
        args.context = &c.base;
        rtcOccluded1(s->rtc.scene, &r, &args);
#else
        rtcOccluded1(s->rtc.scene, &c.base, &r);
#endif
        PT__RTC_GUARD_END;
    }
    return r.tfar < 0.0f;
}

#if RTC_VERSION_MAJOR < 4 && PDFTRACE_EMBREE_STREAM
#define PT__RTC_STREAM 64 /* the most rays of one stream call (a batch's camera samples) */
/* The closest hits of n <= PT__RTC_STREAM rays (0 < t < inf) in one rtcIntersect1M call: what
   n calls of pt__rtc_closest return (the callbacks run the same tests; Embree's triangle test is
   the same per lane), into found[i], prim[i], t[i] and bary[3 i .. 3 i + 2]. */
static void pt__rtc_closest_n(const pt_scene *s, const pt__rayctx *const *rc, int n, int *found, uint32_t *prim,
                              float *t, float *bary)
{
    struct RTCRayHit rh[PT__RTC_STREAM];
    const pt__rayctx *rcs[PT__RTC_STREAM];
    int idx[PT__RTC_STREAM], i, m = 0;
    pt__rtc_ctx c;
    for (i = 0; i < n; ++i) {
        found[i] = 0;
        if (!pt__rtc_ray_ok(rc[i], PT__INF)) continue;
        pt__rtc_ray(&rh[m].ray, rc[i], PT__INF);
        rh[m].ray.id = (unsigned)m;
        rh[m].hit.geomID = rh[m].hit.primID = rh[m].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rcs[m] = rc[i];
        idx[m++] = i;
    }
    if (!m) return;
    pt__rtc_ctx_init(&c, NULL);
    c.rc = rcs;
    {
        PT__RTC_GUARD_BEGIN;
        rtcIntersect1M(s->rtc.scene, &c.base, rh, (unsigned)m, sizeof rh[0]);
        PT__RTC_GUARD_END;
    }
    for (i = 0; i < m; ++i) {
        unsigned g = rh[i].hit.geomID;
        int j = idx[i];
        if (g >= 3u || rh[i].hit.primID >= s->rtc.count[g]) continue;
        found[j] = 1;
        prim[j] = s->rtc.map[g][rh[i].hit.primID];
        t[j] = rh[i].ray.tfar;
        bary[3 * j] = g == PT__PRIM_TRIANGLE ? 1.0f - rh[i].hit.u - rh[i].hit.v : 0.0f;
        bary[3 * j + 1] = g == PT__PRIM_TRIANGLE ? rh[i].hit.u : 0.0f;
        bary[3 * j + 2] = g == PT__PRIM_TRIANGLE ? rh[i].hit.v : 0.0f;
    }
}
/* Any hits of n <= PT__RTC_STREAM rays (0 < t < tmax[i]) in one rtcOccluded1M call: hit[i] as
   pt__rtc_any returns it. */
static void pt__rtc_any_n(const pt_scene *s, const pt__rayctx *const *rc, const float *tmax, int n, int *hit)
{
    struct RTCRay r[PT__RTC_STREAM];
    const pt__rayctx *rcs[PT__RTC_STREAM];
    int idx[PT__RTC_STREAM], i, m = 0;
    pt__rtc_ctx c;
    for (i = 0; i < n; ++i) {
        hit[i] = 0;
        if (!pt__rtc_ray_ok(rc[i], tmax[i])) continue;
        pt__rtc_ray(&r[m], rc[i], tmax[i]);
        r[m].id = (unsigned)m;
        rcs[m] = rc[i];
        idx[m++] = i;
    }
    if (!m) return;
    pt__rtc_ctx_init(&c, NULL);
    c.rc = rcs;
    {
        PT__RTC_GUARD_BEGIN;
        rtcOccluded1M(s->rtc.scene, &c.base, r, (unsigned)m, sizeof r[0]);
        PT__RTC_GUARD_END;
    }
    for (i = 0; i < m; ++i) hit[idx[i]] = r[i].tfar < 0.0f;
}
#endif

/* Flush-to-zero and denormals-are-zero (MXCSR bits 15 and 6) for Embree's traversal; the
   previous state is returned for pt__ftz_end. A no-op without SSE (e.g. on ARM). */
static unsigned pt__ftz_begin(void)
{
#ifdef PT__HAVE_MXCSR
    unsigned old = _mm_getcsr();
    _mm_setcsr(old | 0x8040u);
    return old;
#else
    return 0u;
#endif
}
static void pt__ftz_end(unsigned old)
{
#ifdef PT__HAVE_MXCSR
    _mm_setcsr(old);
#else
    (void)old;
#endif
}
#endif /* PDFTRACE_EMBREE */

/* ------------------------------------------------------------------------------------------
   5c. Commit and ray queries. pt_scene_commit turns the shapes added so far into something that
   can be rendered: it builds the acceleration structure of the chosen backend (the built-in BVH
   of section 5, or Embree, section 5b), the light table (every emitting primitive is a light,
   picked with probability proportional to its power; sampled in section 2) and the scene's
   feature bits (the skips at the top of this file). Every closest-hit and any-hit query, the
   integrator's and the public ones, goes through one dispatch to the backend the commit chose.
   ------------------------------------------------------------------------------------------ */

PTDEF int pt_scene_set_backend(pt_scene *s, pt_backend backend)
{
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if ((int)backend < (int)PT_BACKEND_AUTO || (int)backend > (int)PT_BACKEND_EMBREE)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "set_backend: %d is not a backend (0 auto, 1 built-in, 2 Embree)",
                        (int)backend);
#ifndef PDFTRACE_EMBREE
    if (backend == PT_BACKEND_EMBREE)
        return pt__fail(s, PT_ERROR_UNSUPPORTED,
                        "set_backend: Embree is not compiled in (define PDFTRACE_EMBREE, link -lembree3: make EMBREE=1)");
#endif
    if (backend != (pt_backend)s->backend_request) s->committed = 0; /* commit again to switch */
    s->backend_request = (int)backend;
    return PT_OK;
}

PTDEF int pt_scene_set_embree_config(pt_scene *s, const char *config)
{
    size_t n = config ? strlen(config) : 0u;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
#ifndef PDFTRACE_EMBREE
    (void)n;
    return pt__fail(s, PT_ERROR_UNSUPPORTED, "set_embree_config: Embree is not compiled in (define PDFTRACE_EMBREE)");
#else
    if (n >= sizeof s->embree_config)
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "set_embree_config: %u characters (at most %u)", (unsigned)n,
                        (unsigned)(sizeof s->embree_config - 1u));
    if (n) memcpy(s->embree_config, config, n);
    s->embree_config[n] = '\0';
    return PT_OK;
#endif
}

static double pt__now(void);

/* Builds the acceleration structure of the backend chosen for s (commit's first step). */
static int pt__accel_build(pt_scene *s)
{
    double t0 = pt__now();
    int rc;
    if ((rc = pt__simd_choose(s)) != PT_OK) return rc;
#ifdef PDFTRACE_EMBREE
    int want = s->backend_request;
    if (want == PT_BACKEND_AUTO) { /* the rule of section 5b (PDFTRACE_EMBREE_MIN_PRIMS) */
        want = s->prim_count >= (uint32_t)(PDFTRACE_EMBREE_MIN_PRIMS) ? PT_BACKEND_EMBREE : PT_BACKEND_BUILTIN;
#if PDFTRACE_EMBREE_SMALL_PRIMS > 0
        if (2u * (uint64_t)s->triangle_count < s->prim_count && s->prim_count < (uint32_t)(PDFTRACE_EMBREE_SMALL_PRIMS))
            want = PT_BACKEND_EMBREE;
#endif
    }
    pt__rtc_release(s);
    if (want == PT_BACKEND_EMBREE) {
        {
            PT__RTC_GUARD_BEGIN; /* the calling thread takes part in Embree's build */
            rc = pt__rtc_build(s);
            PT__RTC_GUARD_END;
        }
        if (rc == PT_OK) {
            pt__bvh_free(s);
            s->backend = PT_BACKEND_EMBREE;
            s->build_seconds = pt__now() - t0;
            s->accel_bytes = pt__rtc_bytes(s);
            return PT_OK;
        }
        if (s->backend_request == PT_BACKEND_EMBREE) return rc;
        s->error[0] = '\0'; /* AUTO: the built-in BVH instead */
        t0 = pt__now();
    }
#endif
    s->backend = PT_BACKEND_BUILTIN;
    if ((rc = pt__bvh_build_scene(s)) != PT_OK) return rc;
    s->build_seconds = pt__now() - t0;
    s->accel_bytes = s->bvh_bytes;
    return PT_OK;
}

/* The scene's origin (pt_scene_commit): the world bounds in double (prims [0, placed) are
   relative to the previous origin), then every primitive moved to the new one. */
static void pt__place(pt_scene *s)
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, c[3] = {0, 0, 0};
    double size = 0.0, far = 0.0;
    uint32_t i;
    int k;
    if (s->fixed_origin) {
        s->placed = s->prim_count;
        return;
    }
    for (i = 0; i < s->prim_count; ++i) {
        pt_vec3 a, b;
        double o[3] = {0, 0, 0};
        if (i < s->placed) memcpy(o, s->origin, sizeof o);
        pt__prim_bounds(&s->prims[i], &a, &b);
        lo[0] = pt__mind(lo[0], a.x + o[0]); lo[1] = pt__mind(lo[1], a.y + o[1]); lo[2] = pt__mind(lo[2], a.z + o[2]);
        hi[0] = pt__maxd(hi[0], b.x + o[0]); hi[1] = pt__maxd(hi[1], b.y + o[1]); hi[2] = pt__maxd(hi[2], b.z + o[2]);
    }
    for (k = 0; k < 3 && s->prim_count; ++k) {
        c[k] = 0.5 * lo[k] + 0.5 * hi[k];
        size = pt__maxd(size, hi[k] - lo[k]);
        far = pt__maxd(far, fabs(c[k]));
    }
    for (k = 0; k < 3; ++k) c[k] = far > 8.0 * size ? (double)(float)c[k] : 0.0;
    for (i = 0; i < s->prim_count; ++i) {
        pt__prim *p = &s->prims[i];
        double d[3];
        for (k = 0; k < 3; ++k) d[k] = c[k] - (i < s->placed ? s->origin[k] : 0.0);
        if (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0) continue;
        p->p0 = pt_v3((float)(p->p0.x - d[0]), (float)(p->p0.y - d[1]), (float)(p->p0.z - d[2]));
        if (p->type != PT__PRIM_TRIANGLE) continue; /* a sphere's radius, a quad's u and v stay */
        p->p1 = pt_v3((float)(p->p1.x - d[0]), (float)(p->p1.y - d[1]), (float)(p->p1.z - d[2]));
        p->p2 = pt_v3((float)(p->p2.x - d[0]), (float)(p->p2.y - d[1]), (float)(p->p2.z - d[2]));
    }
    memcpy(s->origin, c, sizeof c);
    s->has_origin = c[0] != 0.0 || c[1] != 0.0 || c[2] != 0.0;
    s->placed = s->prim_count;
}

/* The smallest extent of a primitive: a sphere's radius, a quad's or triangle's smallest height. */
static float pt__prim_feature(const pt__prim *p)
{
    float a = pt__prim_area(p), e;
    if (p->type == PT__PRIM_SPHERE) return p->p1.x;
    if (p->type == PT__PRIM_QUAD) return a / pt__maxf(pt_length(p->p1), pt_length(p->p2));
    e = pt__maxf(pt_length(pt_sub(p->p1, p->p0)), pt__maxf(pt_length(pt_sub(p->p2, p->p1)), pt_length(pt_sub(p->p0, p->p2))));
    return 2.0f * a / e;
}
/* Counts the primitives float cannot represent well (pt_scene_commit) and describes the worst. */
static void pt__precision_check(pt_scene *s)
{
    double worst = 1.0, far = pt__maxd(fabs(s->origin[0]), pt__maxd(fabs(s->origin[1]), fabs(s->origin[2])));
    uint32_t i;
    s->fine_prims = 0;
    s->warning[0] = '\0';
    for (i = 0; i < s->prim_count; ++i) {
        const pt__prim *p = &s->prims[i];
        double m = pt__vmaxabs(p->mag), f = pt__prim_feature(p), world = m + far;
        double ulps = f / (FLT_EPSILON * world), offsets = f / (256.0 * FLT_EPSILON * m);
        double r = ulps / 8.0;
        if (s->mats[p->material].scatters) r = pt__mind(r, offsets / 16.0);
        if (!(r < 1.0)) continue;
        s->fine_prims++;
        if (r >= worst) continue;
        worst = r;
        snprintf(s->warning, sizeof s->warning,
                 "primitive %u is %.3g across at coordinates of %.3g: %.3g float ulps there, %.3g spawn offsets "
                 "(move the scene nearer the origin or scale it up)",
                 (unsigned)p->id, f, world, ulps, offsets);
    }
}

/* --- the light tree (section 2): built top-down over the light table. Each node's lights are
   split where the surface area orientation heuristic is least (Conty Estevez & Kulla 2018; pbrt-v4's
   SAOH): the sum over the two halves of power x the solid-angle measure of their normal cones x
   the area of their bounds, tried at PT__LTREE_BUCKETS - 1 planes along each axis. This keeps
   lights that face different ways apart, which the orientation bound needs. Where no plane
   separates the centres, or the tree grows deep enough that a light's path might not fit the
   64 bits of its trail, the node splits at the median instead (depth ceil(log2 n) from there). */
#define PT__LTREE_BUCKETS 12
typedef struct pt__lkey { float key; uint32_t light; } pt__lkey;
static int pt__lkey_cmp(const void *a, const void *b)
{
    const pt__lkey *x = (const pt__lkey *)a, *y = (const pt__lkey *)b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return x->light < y->light ? -1 : (x->light > y->light ? 1 : 0); /* deterministic */
}
/* The smallest cone holding cones a and b (pbrt-v4's DirectionCone union, in closed form; for
   opposite axes, which pbrt-v4 bounds by the whole sphere, any axis at right angles will do). */
static void pt__cone_union(pt__lnode *out, const pt__lnode *a, const pt__lnode *b)
{
    float ta, tb, td, to, tr;
    pt_vec3 w;
    out->cos_e = pt__minf(a->cos_e, b->cos_e); /* the wider of the two emission angles */
    if (a->cos_o <= -1.0f || b->cos_o <= -1.0f) { out->axis = a->axis; out->cos_o = -1.0f; return; }
    ta = acosf(pt__minf(1.0f, a->cos_o));
    tb = acosf(pt__minf(1.0f, b->cos_o));
    td = acosf(pt__minf(1.0f, pt__maxf(-1.0f, pt_dot(a->axis, b->axis))));
    if (pt__minf(td + tb, PT__PI) <= ta) { out->axis = a->axis; out->cos_o = a->cos_o; return; }
    if (pt__minf(td + ta, PT__PI) <= tb) { out->axis = b->axis; out->cos_o = b->cos_o; return; }
    to = 0.5f * (ta + td + tb);
    if (to >= PT__PI) { out->axis = a->axis; out->cos_o = -1.0f; return; }
    /* rotate a's axis toward b's by tr = to - ta, about their common normal (Rodrigues) */
    tr = to - ta;
    w = pt_cross(a->axis, b->axis);
    if (!(pt_length2(w) > 1e-12f)) w = pt_cross(a->axis, fabsf(a->axis.x) < 0.9f ? pt_v3(1, 0, 0) : pt_v3(0, 1, 0));
    w = pt_normalize(w);
    out->axis = pt_normalize(pt_add(pt_scale(a->axis, cosf(tr)), pt_scale(pt_cross(w, a->axis), sinf(tr))));
    out->cos_o = cosf(to);
}
/* A light's own node: its bounds, power and normal cone. */
static void pt__lnode_of_light(const pt_scene *s, uint32_t li, pt__lnode *node)
{
    const pt__light *l = &s->lights[li];
    const pt__prim *p = &s->prims[l->prim];
    pt__prim_bounds(p, &node->lo, &node->hi);
    node->power = (float)l->power;
    node->axis = p->type == PT__PRIM_SPHERE ? pt_v3(0, 0, 1) : p->n;
    node->cos_o = p->type == PT__PRIM_SPHERE || s->mats[p->material].two_sided ? -1.0f : 1.0f;
    node->cos_e = 0.0f; /* Lambertian emission: to 90 degrees from the normal */
    node->a = li;
    node->b = PT__LNODE_LEAF;
}
/* Adds node x (a light or a group) to the group g (g->a: how many lights g holds, 0: empty). */
static void pt__lnode_grow(pt__lnode *g, const pt__lnode *x, uint32_t count)
{
    if (!g->a) {
        *g = *x;
        g->a = 0u;
    } else {
        pt__lnode u;
        pt__cone_union(&u, g, x);
        g->axis = u.axis;
        g->cos_o = u.cos_o;
        g->cos_e = u.cos_e;
        g->lo = pt__vmin(g->lo, x->lo);
        g->hi = pt__vmax(g->hi, x->hi);
        g->power += x->power;
    }
    g->a += count;
}
/* The SAOH cost of a group: power x the normal cone's measure x the bounds' area (pbrt-v4,
   LightBounds and EvaluateCost; the measure is Conty Estevez & Kulla's M_omega). */
static double pt__lnode_cost(const pt__lnode *g)
{
    const double pi = 3.14159265358979323846;
    double to = g->cos_o <= -1.0f ? pi : acos((double)pt__minf(1.0f, g->cos_o));
    double te = acos((double)pt__maxf(-1.0f, pt__minf(1.0f, g->cos_e))), tw = to + te < pi ? to + te : pi;
    double m = 2.0 * pi * (1.0 - cos(to)) +
               pi / 2.0 * (2.0 * tw * sin(to) - cos(to - 2.0 * tw) - 2.0 * to * sin(to) + cos(to));
    pt_vec3 e = pt_sub(g->hi, g->lo);
    double area = 2.0 * ((double)e.x * e.y + (double)e.y * e.z + (double)e.z * e.x);
    return (double)g->power * m * area;
}
static float pt__vcomp(pt_vec3 v, int axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }
static int pt__ltree_bucket(float centre2, float lo, float width)
{
    int k = (int)((float)PT__LTREE_BUCKETS * (0.5f * centre2 - lo) / width);
    return k < 0 ? 0 : (k > PT__LTREE_BUCKETS - 1 ? PT__LTREE_BUCKETS - 1 : k);
}
/* Where to split keys[begin, end) (sorted on return along the chosen axis): the first index of
   the second half. */
static uint32_t pt__ltree_split(const pt__lnode *info, pt__lkey *keys, uint32_t begin, uint32_t end, uint32_t depth)
{
    pt_vec3 clo = pt_v3(FLT_MAX, FLT_MAX, FLT_MAX), chi = pt_neg(clo), blo = clo, bhi = chi;
    uint32_t i, n = end - begin, lg = 0;
    int axis, k, best_axis = -1, best_k = 0;
    double best = 0.0;
    float emax;
    while (lg < 32u && ((uint64_t)1 << lg) < n) lg++;
    for (i = begin; i < end; ++i) {
        const pt__lnode *x = &info[keys[i].light];
        pt_vec3 c = pt_scale(pt_add(x->lo, x->hi), 0.5f);
        clo = pt__vmin(clo, c);
        chi = pt__vmax(chi, c);
        blo = pt__vmin(blo, x->lo);
        bhi = pt__vmax(bhi, x->hi);
    }
    emax = pt__vmaxabs(pt_sub(bhi, blo));
    for (axis = 0; axis < 3 && depth + lg < 60u; ++axis) {
        pt__lnode bucket[PT__LTREE_BUCKETS], below[PT__LTREE_BUCKETS], above;
        float lo = pt__vcomp(clo, axis), width = pt__vcomp(chi, axis) - lo;
        float extent = pt__vcomp(bhi, axis) - pt__vcomp(blo, axis);
        if (!(width > 0.0f)) continue;
        memset(bucket, 0, sizeof bucket);
        for (i = begin; i < end; ++i) {
            const pt__lnode *x = &info[keys[i].light];
            pt__lnode_grow(&bucket[pt__ltree_bucket(pt__vcomp(x->lo, axis) + pt__vcomp(x->hi, axis), lo, width)], x, 1u);
        }
        memset(below, 0, sizeof below);
        for (k = 0; k < PT__LTREE_BUCKETS; ++k) {
            if (k) below[k] = below[k - 1];
            if (bucket[k].a) pt__lnode_grow(&below[k], &bucket[k], bucket[k].a);
        }
        memset(&above, 0, sizeof above);
        for (k = PT__LTREE_BUCKETS - 1; k >= 1; --k) {
            double c;
            if (bucket[k].a) pt__lnode_grow(&above, &bucket[k], bucket[k].a);
            if (!above.a || !below[k - 1].a) continue;
            /* (pbrt-v4's regularisation: splits across thin axes cost more) */
            c = (pt__lnode_cost(&below[k - 1]) + pt__lnode_cost(&above)) * (double)(emax / pt__maxf(extent, emax * 1e-6f));
            if (best_axis < 0 || c <= best) { best = c; best_axis = axis; best_k = k; }
        }
    }
    axis = best_axis;
    if (axis < 0) { /* the median along the widest spread of the centres */
        pt_vec3 e = pt_sub(chi, clo);
        axis = e.x >= e.y && e.x >= e.z ? 0 : (e.y >= e.z ? 1 : 2);
    }
    for (i = begin; i < end; ++i)
        keys[i].key = pt__vcomp(info[keys[i].light].lo, axis) + pt__vcomp(info[keys[i].light].hi, axis);
    qsort(keys + begin, n, sizeof *keys, pt__lkey_cmp);
    if (best_axis >= 0) {
        float lo = pt__vcomp(clo, axis), width = pt__vcomp(chi, axis) - lo;
        for (i = begin; i < end && pt__ltree_bucket(keys[i].key, lo, width) < best_k; ++i) {}
        if (i > begin && i < end) return i;
    }
    return begin + n / 2u;
}
/* Builds the binary tree over keys[begin, end) into bin; returns the node's index. */
static uint32_t pt__ltree_node(pt__lnode *bin, uint32_t *count, const pt__lnode *info, pt__lkey *keys, uint32_t begin,
                               uint32_t end, uint32_t depth)
{
    uint32_t n = (*count)++, mid, a, b;
    pt__lnode *node = &bin[n];
    if (end - begin == 1) {
        *node = info[keys[begin].light];
    } else {
        mid = pt__ltree_split(info, keys, begin, end, depth);
        a = pt__ltree_node(bin, count, info, keys, begin, mid, depth + 1u);
        b = pt__ltree_node(bin, count, info, keys, mid, end, depth + 1u);
        node = &bin[n];
        node->lo = pt__vmin(bin[a].lo, bin[b].lo);
        node->hi = pt__vmax(bin[a].hi, bin[b].hi);
        node->power = bin[a].power + bin[b].power;
        pt__cone_union(node, &bin[a], &bin[b]);
        node->a = a;
        node->b = b;
    }
    node->centre = pt_scale(pt_add(node->lo, node->hi), 0.5f);
    node->r2 = 0.25f * pt_length2(pt_sub(node->hi, node->lo));
    node->sin_o = pt__safe_sqrt(1.0f - node->cos_o * node->cos_o);
    node->pmin = node->axis.x * (node->axis.x > 0.0f ? node->lo.x : node->hi.x) +
                 node->axis.y * (node->axis.y > 0.0f ? node->lo.y : node->hi.y) +
                 node->axis.z * (node->axis.z > 0.0f ? node->lo.z : node->hi.z);
    return n;
}
/* The nodes below binary node x, `levels` binary levels down (or a light above that), appended
   to list. */
static void pt__ltree_gather(const pt__lnode *bin, uint32_t x, int levels, uint32_t *list, int *n)
{
    if (levels == 0 || bin[x].b == PT__LNODE_LEAF) {
        list[(*n)++] = x;
        return;
    }
    pt__ltree_gather(bin, bin[x].a, levels - 1, list, n);
    pt__ltree_gather(bin, bin[x].b, levels - 1, list, n);
}
/* The children of the 8-wide node made from binary node b (not a light): b's descendants three
   levels down, or a light above that. */
static int pt__ltree_kids(const pt__lnode *bin, uint32_t b, uint32_t *list)
{
    int n = 0;
    pt__ltree_gather(bin, b, PT__LTREE_BITS, list, &n);
    return n;
}
static uint32_t pt__ltree_kids_count(const pt__lnode *bin, uint32_t b)
{
    uint32_t list[PT__LTREE_W], total = 1;
    int i, n = pt__ltree_kids(bin, b, list);
    for (i = 0; i < n; ++i)
        if (bin[list[i]].b != PT__LNODE_LEAF) total += pt__ltree_kids_count(bin, list[i]);
    return total;
}
/* Makes s->ltree's node for binary node b at 8-wide depth `depth`; a light's trail gets its
   child's lane in bits 3 depth to 3 depth + 2 (depth < 21: the binary tree is at most 62 deep). */
static uint32_t pt__ltree_collapse(pt_scene *s, const pt__lnode *bin, uint32_t b, uint32_t depth, uint64_t trail)
{
    uint32_t m = s->ltree_count++, list[PT__LTREE_W];
    int k, n = pt__ltree_kids(bin, b, list);
    pt__lnodew *node = &s->ltree[m];
    memset(node, 0, sizeof *node);
    for (k = 0; k < PT__LTREE_W; ++k) { /* empty children: no power, no cone */
        node->r2[k] = 1.0f;
        node->cos_o[k] = -1.0f;
        node->child[k] = PT__LCHILD_LIGHT;
    }
    for (k = 0; k < n; ++k) {
        const pt__lnode *x = &bin[list[k]];
        uint64_t t = trail | ((uint64_t)k << (PT__LTREE_BITS * depth));
        node->lo[0][k] = x->lo.x;
        node->lo[1][k] = x->lo.y;
        node->lo[2][k] = x->lo.z;
        node->hi[0][k] = x->hi.x;
        node->hi[1][k] = x->hi.y;
        node->hi[2][k] = x->hi.z;
        node->centre[0][k] = x->centre.x;
        node->centre[1][k] = x->centre.y;
        node->centre[2][k] = x->centre.z;
        node->axis[0][k] = x->axis.x;
        node->axis[1][k] = x->axis.y;
        node->axis[2][k] = x->axis.z;
        node->r2[k] = x->r2;
        node->cos_o[k] = x->cos_o;
        node->sin_o[k] = x->sin_o;
        node->cos_e[k] = x->cos_e;
        node->pmin[k] = x->pmin;
        node->power[k] = x->power;
        if (x->b == PT__LNODE_LEAF) {
            node->child[k] = PT__LCHILD_LIGHT | x->a;
            s->ltrail[x->a] = t;
        } else {
            uint32_t c = pt__ltree_collapse(s, bin, list[k], depth + 1u, t);
            s->ltree[m].child[k] = c; /* (s->ltree does not move: allocated whole) */
        }
    }
    return m;
}
static int pt__ltree_build(pt_scene *s)
{
    pt__lkey *keys;
    pt__lnode *info, *bin;
    uint32_t i, count = 0;
    PT_FREE(s->ltree);
    PT_FREE(s->ltrail);
    s->ltree = NULL;
    s->ltrail = NULL;
    s->ltree_count = 0;
    if (s->light_count < PT__LIGHT_TREE_MIN) return PT_OK;
    s->ltrail = (uint64_t *)PT_MALLOC(sizeof(uint64_t) * s->light_count);
    keys = (pt__lkey *)PT_MALLOC(sizeof(pt__lkey) * s->light_count);
    info = (pt__lnode *)PT_MALLOC(sizeof(pt__lnode) * s->light_count);
    bin = (pt__lnode *)PT_MALLOC(sizeof(pt__lnode) * (2u * (size_t)s->light_count - 1u));
    if (s->ltrail && keys && info && bin) {
        for (i = 0; i < s->light_count; ++i) {
            keys[i].light = i;
            keys[i].key = 0.0f;
            pt__lnode_of_light(s, i, &info[i]);
        }
        pt__ltree_node(bin, &count, info, keys, 0, s->light_count, 0);
        s->ltree = (pt__lnodew *)PT_MALLOC(sizeof(pt__lnodew) * pt__ltree_kids_count(bin, 0));
        if (s->ltree) pt__ltree_collapse(s, bin, 0, 0, 0);
    }
    PT_FREE(keys);
    PT_FREE(info);
    PT_FREE(bin);
    if (!s->ltree) {
        PT_FREE(s->ltrail);
        s->ltrail = NULL;
        return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "commit: out of memory (light tree of %u lights)", (unsigned)s->light_count);
    }
    return PT_OK;
}

PTDEF int pt_scene_commit(pt_scene *s)
{
    uint32_t i, nl = 0;
    int rc;
    double total = 0.0, acc = 0.0;
    unsigned f;
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    pt__place(s);
    if ((rc = pt__accel_build(s)) != PT_OK) return rc;
    /* light table: every emitting primitive is a light, picked in proportion to its power */
    PT_FREE(s->lights);
    s->lights = NULL;
    s->light_count = 0;
    for (i = 0; i < s->prim_count; ++i) {
        pt__prim_cache(&s->prims[i]);
        s->prims[i].light = -1;
        if (s->mats[s->prims[i].material].emits) nl++;
    }
    pt__precision_check(s);
    if (nl) {
        /* lights in the order the primitives were added (their ids), not in the BVH's order of
           s->prims: which light a number picks, and so the image, does not depend on the tree or
           the backend */
        uint32_t *by_id = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * s->prim_count), k;
        s->lights = (pt__light *)PT_MALLOC(sizeof(pt__light) * nl);
        if (!s->lights || !by_id) {
            PT_FREE(by_id);
            return pt__fail(s, PT_ERROR_OUT_OF_MEMORY, "commit: out of memory (%u lights)", (unsigned)nl);
        }
        for (i = 0; i < s->prim_count; ++i) by_id[s->prims[i].id] = i; /* ids are 0 .. prim_count - 1 (pt__new_prim) */
        for (k = 0; k < s->prim_count; ++k) {
            const pt__material *m;
            pt__light *l;
            i = by_id[k];
            m = &s->mats[s->prims[i].material];
            if (!m->emits) continue;
            l = &s->lights[s->light_count];
            l->prim = i;
            l->area = pt__prim_area(&s->prims[i]);
            l->power = ((double)m->emission.x + (double)m->emission.y + (double)m->emission.z) / 3.0 *
                       (double)l->area * 3.14159265358979323846 * (m->two_sided ? 2.0 : 1.0);
            if (!(l->power > 0.0) || !(l->power < 1e300)) {
                PT_FREE(by_id);
                return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "commit: emitter (primitive %u) has power %g",
                                (unsigned)s->prims[i].id, (double)l->power);
            }
            total += l->power;
            s->prims[i].light = (int32_t)s->light_count++;
        }
        PT_FREE(by_id);
        for (i = 0; i < s->light_count; ++i) {
            s->lights[i].select_pdf = (float)(s->lights[i].power / total);
            acc += s->lights[i].power;
            s->lights[i].cdf = (float)(acc / total);
        }
        s->lights[s->light_count - 1].cdf = 1.0f;
    }
    s->total_power = total;
    if ((rc = pt__ltree_build(s)) != PT_OK) return rc;
    /* features */
    f = s->features & (PT_FEATURE_SPHERES | PT_FEATURE_QUADS | PT_FEATURE_TRIANGLES | PT_FEATURE_MESHES |
                       PT_FEATURE_SHADING_NORMALS | PT_FEATURE_TRANSFORMS);
    if (s->light_count) f |= PT_FEATURE_EMITTERS;
    if (s->light_count == 1) f |= PT_FEATURE_SINGLE_EMITTER;
    if (s->backend != PT_BACKEND_BUILTIN) s->lo = s->hi = pt_v3(0, 0, 0); /* the built-in build set them */
    if (s->backend != PT_BACKEND_BUILTIN && s->prim_count) { /* Embree: the same padded union of the bounds */
        pt_vec3 lo = pt_v3(FLT_MAX, FLT_MAX, FLT_MAX), hi = pt_neg(lo), a, b;
        for (i = 0; i < s->prim_count; ++i) {
            pt__prim_bounds(&s->prims[i], &a, &b);
            lo = pt__vmin(lo, a);
            hi = pt__vmax(hi, b);
        }
        s->lo = pt_v3(pt__pad_down(lo.x), pt__pad_down(lo.y), pt__pad_down(lo.z));
        s->hi = pt_v3(pt__pad_up(hi.x), pt__pad_up(hi.y), pt__pad_up(hi.z));
    }
    for (i = 0; i < s->prim_count; ++i) {
        const pt__material *m = &s->mats[s->prims[i].material];
        if (m->emits && m->two_sided) f |= PT_FEATURE_TWO_SIDED_EMITTERS;
        if (m->scatters && !m->delta) f |= PT_FEATURE_NON_DELTA;
        if (m->delta) f |= PT_FEATURE_DELTA;
        if (m->type == PT_MATERIAL_DIELECTRIC || m->type == PT_MATERIAL_ROUGH_DIELECTRIC) f |= PT_FEATURE_DIELECTRICS;
        if (((m->type == PT_MATERIAL_ROUGH_CONDUCTOR || m->type == PT_MATERIAL_ROUGH_DIELECTRIC) && !m->delta) ||
            m->type == PT_MATERIAL_ROUGH_PLASTIC)
            f |= PT_FEATURE_MICROFACET;
        if (m->texture) f |= PT_FEATURE_TEXTURES;
    }
    if (s->dlight_count) {
        /* delta lights: positions relative to the origin, and their pick table by power */
        pt_vec3 ext = pt_sub(s->hi, s->lo);
        double r = s->prim_count ? 0.5 * sqrt((double)ext.x * ext.x + (double)ext.y * ext.y + (double)ext.z * ext.z) : 1.0,
               tot = 0.0, acc = 0.0;
        if (!(r > 0.0) || !(r < 1e300)) r = 1.0;
        for (i = 0; i < s->dlight_count; ++i) {
            pt__dlight *l = &s->dlights[i];
            l->pos = s->fixed_origin ? l->desc.position : pt__to_local(s, l->desc.position);
            l->mean = (l->desc.intensity.x + l->desc.intensity.y + l->desc.intensity.z) * (1.0f / 3.0f);
            l->power = pt__dlight_power(l, r);
            if (!(l->power > 0.0) || !(l->power < 1e300))
                return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "commit: light %u has power %g", (unsigned)i, l->power);
            tot += l->power;
        }
        for (i = 0; i < s->dlight_count; ++i) {
            s->dlights[i].select_pdf = (float)(s->dlights[i].power / tot);
            acc += s->dlights[i].power;
            s->dlights[i].cdf = (float)(acc / tot);
        }
        s->dlights[s->dlight_count - 1u].cdf = 1.0f;
        f |= PT_FEATURE_DELTA_LIGHTS;
    }
    if (s->env) f |= PT_FEATURE_ENVIRONMENT;
    s->features = f;
    s->committed = 1;
    return PT_OK;
}

PTDEF int pt_scene_set_origin(pt_scene *s, double x, double y, double z)
{
    if (!pt__enter(s)) return PT_ERROR_INVALID_ARGUMENT;
    if (!(fabs(x) <= DBL_MAX && fabs(y) <= DBL_MAX && fabs(z) <= DBL_MAX))
        return pt__fail(s, PT_ERROR_INVALID_ARGUMENT, "set_origin: (%g, %g, %g) is not finite", x, y, z);
    if (s->prim_count)
        return pt__fail(s, PT_ERROR_INVALID_STATE, "set_origin: %u primitives were added before it (set the origin first)",
                        (unsigned)s->prim_count);
    s->origin[0] = x;
    s->origin[1] = y;
    s->origin[2] = z;
    s->has_origin = x != 0.0 || y != 0.0 || z != 0.0;
    s->fixed_origin = 1;
    s->committed = 0;
    return PT_OK;
}

PTDEF int pt_scene_get_info(const pt_scene *s, pt_scene_info *info)
{
    if (!s || !info) return PT_ERROR_INVALID_ARGUMENT;
    memset(info, 0, sizeof *info);
    info->features = s->features;
    info->committed = s->committed;
    info->primitive_count = s->prim_count;
    info->sphere_count = s->sphere_count;
    info->quad_count = s->quad_count;
    info->triangle_count = s->triangle_count;
    info->mesh_count = s->mesh_count;
    info->emitter_count = s->committed ? s->light_count : 0u;
    info->delta_light_count = s->dlight_count;
    info->environment_width = s->env ? s->env->w : 0;
    info->environment_height = s->env ? s->env->h : 0;
    info->material_count = s->mat_count;
    info->texture_count = s->tex_count;
    info->degenerate_triangles_skipped = s->degenerate_skipped;
    info->bvh_node_count = s->node_count;
    info->bvh_max_depth = s->bvh_depth;
    info->simd_level = (pt_simd_level)s->simd;
    info->bvh_width = s->node_count ? s->bvh_width : 0u;
    info->total_emitted_power = s->total_power;
    info->bounds_min = s->lo;
    info->bounds_max = s->hi;
    if (s->has_origin) { /* world bounds, still padded outwards */
        pt_vec3 lo = pt__to_world(s, s->lo), hi = pt__to_world(s, s->hi);
        info->bounds_min = pt_v3(pt__pad_down(lo.x), pt__pad_down(lo.y), pt__pad_down(lo.z));
        info->bounds_max = pt_v3(pt__pad_up(hi.x), pt__pad_up(hi.y), pt__pad_up(hi.z));
    }
    memcpy(info->origin, s->origin, sizeof info->origin);
    info->precision_warnings = s->fine_prims;
    memcpy(info->precision_warning, s->warning, sizeof info->precision_warning);
    info->backend = (pt_backend)s->backend;
    info->build_seconds = s->build_seconds;
    info->accel_bytes = s->accel_bytes;
    return PT_OK;
}

/* --- the traversal dispatch: every closest-hit and any-hit query goes through these --- */
static PT__HOT int pt__scene_closest(const pt_scene *s, const pt__rayctx *rc, float tmax, uint32_t *prim, float *t_out,
                                     float *bary)
{
#ifdef PDFTRACE_EMBREE
    if (s->backend == PT_BACKEND_EMBREE) return pt__rtc_closest(s, rc, tmax, prim, t_out, bary);
#endif
    return pt__bvh_closest(s, rc, tmax, prim, t_out, bary);
}
static PT__HOT int pt__scene_any(const pt_scene *s, const pt__rayctx *rc, float tmax, uint32_t skip)
{
#ifdef PDFTRACE_EMBREE
    if (s->backend == PT_BACKEND_EMBREE) return pt__rtc_any(s, rc, tmax); /* tests `skip` too */
#endif
    return pt__bvh_any(s, rc, tmax, skip);
}

/* --- public queries --- */
/* A public hit is in world coordinates; its magnitude then includes the origin's. */
static void pt__hit_to_world(const pt_scene *s, pt_hit *h)
{
    pt_vec3 n = h->geometric_normal;
    if (!s->has_origin) return;
    h->point = pt__to_world(s, h->point);
    h->magnitude += (float)(fabsf(n.x) * fabs(s->origin[0]) + fabsf(n.y) * fabs(s->origin[1]) +
                            fabsf(n.z) * fabs(s->origin[2]));
}
static int pt__query_ok(const pt_scene *s, pt_ray ray, float tmax)
{
    if (!s) return PT_ERROR_INVALID_ARGUMENT;
    if (!s->committed) return PT_ERROR_INVALID_STATE; /* no message: queries never write the scene */
    if (!pt__vfinite(ray.origin) || !pt__vfinite(ray.dir) || tmax != tmax) return PT_ERROR_INVALID_ARGUMENT;
    return PT_OK;
}
PTDEF int pt_scene_intersect(const pt_scene *s, pt_ray ray, float tmax, pt_hit *hit)
{
    pt__rayctx rc;
    uint32_t prim;
    float t, bary[3];
    int e = pt__query_ok(s, ray, tmax);
    if (e != PT_OK) return e;
    if (!hit) return PT_ERROR_INVALID_ARGUMENT;
    ray.origin = pt__to_local(s, ray.origin);
    pt__rayctx_init(&rc, ray);
    if (!pt__scene_closest(s, &rc, tmax, &prim, &t, bary)) return 0;
    pt__fill_hit(s, &s->prims[prim], ray, t, bary, hit);
    pt__hit_uv(s, &s->prims[prim], bary, hit, &hit->u, &hit->v);
    pt__hit_to_world(s, hit);
    return 1;
}
PTDEF int pt_scene_occluded(const pt_scene *s, pt_ray ray, float tmax)
{
    pt__rayctx rc;
    int e = pt__query_ok(s, ray, tmax);
    if (e != PT_OK) return e;
    ray.origin = pt__to_local(s, ray.origin);
    pt__rayctx_init(&rc, ray);
    return pt__scene_any(s, &rc, tmax, 0xffffffffu);
}
PTDEF int pt_scene_intersect_brute_force(const pt_scene *s, pt_ray ray, float tmax, pt_hit *hit)
{
    pt__rayctx rc;
    uint32_t i, best = 0;
    float bary[3] = {0, 0, 0}, best_bary[3] = {0, 0, 0}, t;
    int found = 0, e = pt__query_ok(s, ray, tmax);
    if (e != PT_OK) return e;
    if (!hit) return PT_ERROR_INVALID_ARGUMENT;
    ray.origin = pt__to_local(s, ray.origin);
    pt__rayctx_init(&rc, ray);
    for (i = 0; i < s->prim_count; ++i) {
        if (pt__hit_prim(&rc, &s->prims[i], tmax, &t, bary)) {
            tmax = t;
            best = i;
            memcpy(best_bary, bary, sizeof bary);
            found = 1;
        }
    }
    if (!found) return 0;
    pt__fill_hit(s, &s->prims[best], ray, tmax, best_bary, hit);
    pt__hit_uv(s, &s->prims[best], best_bary, hit, &hit->u, &hit->v);
    pt__hit_to_world(s, hit);
    return 1;
}

/* ------------------------------------------------------------------------------------------
   6. Camera: pinhole or thin lens from look-at parameters; screen right = forward x up
   (right-handed). The image plane lies at the focus distance, so a thin lens (a point on the
   lens from the concentric disk map, section 2) keeps that plane sharp (Shirley, "Ray Tracing
   in One Weekend", defocus blur).
   ------------------------------------------------------------------------------------------ */

/* pt_camera_init, naming the pt_render_desc.camera field at fault in err (may be NULL). */
static int pt__camera_init(pt_camera *cam, const pt_camera_desc *d, int width, int height, char *err, size_t n)
{
    const int bad = PT_ERROR_INVALID_ARGUMENT;
    pt_vec3 fwd, up, right, tup;
    float vfov, focus, h, vh, vw;
    if (!cam || !d || width <= 0 || height <= 0) return pt__msg(err, n, bad, "camera: NULL or an empty image");
    if (!pt__vfinite(d->look_from))
        return pt__msg(err, n, bad, "pt_render_desc.camera.look_from = (%g, %g, %g): must be finite",
                       (double)d->look_from.x, (double)d->look_from.y, (double)d->look_from.z);
    if (!pt__vfinite(d->look_at))
        return pt__msg(err, n, bad, "pt_render_desc.camera.look_at = (%g, %g, %g): must be finite",
                       (double)d->look_at.x, (double)d->look_at.y, (double)d->look_at.z);
    if (!pt__vfinite(d->up))
        return pt__msg(err, n, bad, "pt_render_desc.camera.up = (%g, %g, %g): must be finite", (double)d->up.x,
                       (double)d->up.y, (double)d->up.z);
    vfov = d->vfov_degrees == 0.0f ? 40.0f : d->vfov_degrees;
    if (!pt__isfinite(vfov) || !(vfov > 0.0f && vfov < 180.0f))
        return pt__msg(err, n, bad, "pt_render_desc.camera.vfov_degrees = %g: must be in (0, 180) (0: 40)",
                       (double)d->vfov_degrees);
    if (!pt__isfinite(d->lens_radius) || d->lens_radius < 0.0f)
        return pt__msg(err, n, bad, "pt_render_desc.camera.lens_radius = %g: must be finite and >= 0",
                       (double)d->lens_radius);
    if (!pt__isfinite(d->focus_distance) || d->focus_distance < 0.0f)
        return pt__msg(err, n, bad, "pt_render_desc.camera.focus_distance = %g: must be finite and >= 0",
                       (double)d->focus_distance);
    fwd = pt_sub(d->look_at, d->look_from);
    if (!(pt_length2(fwd) > 0.0f))
        return pt__msg(err, n, bad,
                       "pt_render_desc.camera.look_at = (%g, %g, %g): equals look_from (no view direction)",
                       (double)d->look_at.x, (double)d->look_at.y, (double)d->look_at.z);
    fwd = pt_normalize(fwd);
    up = pt_length2(d->up) > 0.0f ? pt_normalize(d->up) : pt_v3(0, 1, 0);
    right = pt_cross(fwd, up);
    if (!(pt_length2(right) > 1e-12f))
        return pt__msg(err, n, bad, "pt_render_desc.camera.up = (%g, %g, %g)%s: parallel to look_at - look_from",
                       (double)d->up.x, (double)d->up.y, (double)d->up.z,
                       pt_length2(d->up) > 0.0f ? "" : " (the default (0, 1, 0))");
    right = pt_normalize(right);
    tup = pt_cross(right, fwd);
    focus = d->focus_distance > 0.0f ? d->focus_distance : pt_length(pt_sub(d->look_at, d->look_from));
    h = (float)tan((double)vfov * 3.14159265358979323846 / 360.0);
    vh = 2.0f * h * focus;
    vw = vh * (float)width / (float)height;
    cam->origin = d->look_from;
    cam->forward = fwd;
    cam->right = right;
    cam->up = tup;
    cam->pixel_du = pt_scale(right, vw / (float)width);
    cam->pixel_dv = pt_scale(tup, -vh / (float)height);
    cam->pixel00 = pt_add(pt_add(pt_madd(d->look_from, fwd, focus), pt_scale(right, -0.5f * vw)), pt_scale(tup, 0.5f * vh));
    cam->lens_radius = d->lens_radius;
    cam->width = width;
    cam->height = height;
    return PT_OK;
}
PTDEF int pt_camera_init(pt_camera *cam, const pt_camera_desc *d, int width, int height)
{
    return pt__camera_init(cam, d, width, height, NULL, 0);
}
static PT__HOT pt_ray pt__camera_ray(const pt_camera *cam, float x, float y, float u1, float u2)
{
    pt_ray r;
    pt_vec3 target = pt_add(pt_add(cam->pixel00, pt_scale(cam->pixel_du, x)), pt_scale(cam->pixel_dv, y));
    r.origin = cam->origin;
    if (cam->lens_radius > 0.0f) {
        float lx, ly;
        pt__concentric_disk(u1, u2, &lx, &ly);
        r.origin = pt_add(r.origin, pt_add(pt_scale(cam->right, lx * cam->lens_radius),
                                           pt_scale(cam->up, ly * cam->lens_radius)));
    }
    r.dir = pt_normalize(pt_sub(target, r.origin));
    return r;
}
PTDEF pt_ray pt_camera_ray(const pt_camera *cam, float x, float y, float u1, float u2)
{
    return pt__camera_ray(cam, x, y, u1, u2);
}

/* ------------------------------------------------------------------------------------------
   7. Integrator: one path per camera sample, its vertices shaded by one of four strategies.
   At every non-delta vertex the "scatter" density is the material's PDF, mixed with the
   user's guide PDF when there is one: p_s = (1 - g) p_material + g p_guide. The strategies:
   - MATERIAL: w_i ~ p_s; weight A pScatter / p_s; emission counted where rays land.
   - LIGHT: direct light by a shadow ray to a point sampled from the light PDF (picked by
     power), weight A pScatter Le / p_light; emission that scattered rays land on is not
     counted (it is the light strategy's), except after a delta vertex or from the camera.
     The path continues by p_s for indirect light.
   - MIXTURE: w_i ~ w p_lights + (1 - w) p_s and weight A pScatter / (w p_lights(w_i) +
     (1 - w) p_s(w_i)), where p_lights(w_i) sums over all lights; emission counted where rays
     land. A light sample that fails (a one-sided light seen from behind) ends the path: the
     estimator stays unbiased because that mass is simply absent from the density.
   - MIS: both of LIGHT's and MATERIAL's estimates of direct light, weighted by the power
     heuristic w_a = p_a^2 / (p_a^2 + p_b^2) (Veach & Guibas, "Optimally Combining Sampling
     Techniques for Monte Carlo Rendering", SIGGRAPH 1995).
   Paths end by Russian roulette and, where their throughput grows, split (both below).
   Depth counts scattering events: max_depth 1 is direct light only.
   ------------------------------------------------------------------------------------------ */

/* Russian roulette (Arvo & Kirk 1990) from rr_start_depth continues with probability
   q = min(0.95, sqrt(g max(beta_in))) and divides beta by q, where beta_in is the throughput
   that reached this vertex, before its scatter weight f/p, and g = 1 (2 with the Sobol sampler).
   Why the square root: roulette trades the variance it adds, b^2 E[Y^2] (1/q - 1) for a
   continuation b Y, against the time (1 - q) C it saves; the q that minimises variance x time
   is proportional to b (so q = b/b_ref), with b_ref set by the rest of the pixel's variance and
   cost, which a path does not know. q = b (b_ref = 1, pbrt's choice) cuts paths too early;
   q = sqrt(b) keeps more paths of throughput 0.1-1. b_ref grows with the square root of the
   rest of the pixel's variance per sample, which Sobol's stratification makes smaller, so
   roulette cuts later there: b_ref = 1/2, q = min(0.95, sqrt(2 b)). Any q chosen before the
   coin is flipped keeps the estimator unbiased; taking it from the throughput after the scatter
   weight (the textbook choice) turns a well-sampled direction into a firefly: when f/p is tiny
   because p is large (a light-sampled direction towards a small bright light under MIXTURE),
   the path survives with q ~ f/p and is rescaled by 1/q, so the light it then hits counts at
   full strength in a few rare paths instead of at weight f/p in all of them. The measurements
   behind each of these choices: docs/internals.md, "Russian roulette". */
#define PT__RR_GAIN_SOBOL 2.0f /* b_ref = 1/2 with the Sobol sampler (above) */

typedef struct pt__settings {
    pt_strategy strategy;
    float light_weight;
    int max_depth, rr_start, max_splits;
    int indirect_paths; /* k of the first non-delta vertex's split, 1..PT__SPLIT_MAX_COPIES */
    float rr_gain;      /* Russian roulette's q = min(0.95, sqrt(rr_gain max(beta_in))): 1 / b_ref */
    pt_color background;
    pt_guide_fn guide;
    void *guide_user;
    float guide_weight;
    unsigned general;  /* PT_SKIP_* bits whose general path is forced (pt_render_desc.disable_skips) */
    pt_sampler sampler;
    const pt_guide *learned;  /* path guiding (section 8): the guide sampled at non-delta vertices */
    pt_guide *recording;      /* the guide the paths' radiance is recorded into (training) */
    float learned_weight;     /* 1 - alpha: the guide's share of the scatter density */
    /* the environment light (background and map; pt__settings_for_scene) */
    const pt__env *env;       /* the scene's map, NULL: none */
    int env_on;               /* some environment radiance: the environment is a light */
    float env_pick;           /* the probability that light sampling picks the environment (0: off) */
    float env_uniform;        /* the uniform sphere's share of the environment's density */
    float lights_share;       /* 1 - env_pick: the shaped lights' share (exactly 1 when off) */
    int batched;              /* pt_render_desc.integrator resolved (pt__settings_for_scene): 1 BATCHED, 0 SCALAR */
} pt__settings;

/* Whether the skip `bit` is taken (not disabled by pt_render_desc.disable_skips). */
#define PT__SKIP(cfg, bit) (((cfg)->general & (bit)) == 0u)
/* The light-sampling mode (PT__LIGHTS_*) the skips allow. */
static unsigned pt__lights_mode(const pt__settings *cfg)
{
    return (PT__SKIP(cfg, PT_SKIP_SOLID_ANGLE_QUADS) ? PT__LIGHTS_SPHERICAL : 0u) |
           (PT__SKIP(cfg, PT_SKIP_LIGHT_TREE) ? PT__LIGHTS_TREE : 0u);
}

#define PT__MAX_SPLITS_LIMIT 65536 /* pt_render_desc.max_splits above this: invalid */
#define PT__INDIRECT_PATHS_LIMIT PT_INDIRECT_PATHS_MAX /* above this: invalid (= PT__SPLIT_MAX_COPIES) */
#define PT__INDIRECT_PATHS_SOBOL 3 /* its default with PT_SAMPLER_SOBOL (1 with INDEPENDENT) */

/* Each rejection names the one pt_render_desc field at fault, with its value, in err (may be NULL). */
static int pt__settings_from_desc(const pt_render_desc *d, pt__settings *c, char *err, size_t n)
{
    const int bad = PT_ERROR_INVALID_ARGUMENT;
    memset(c, 0, sizeof *c);
    if ((int)d->strategy < (int)PT_STRATEGY_MIS || (int)d->strategy > (int)PT_STRATEGY_MIXTURE)
        return pt__msg(err, n, bad,
                       "pt_render_desc.strategy = %d: must be PT_STRATEGY_MIS (0) .. PT_STRATEGY_MIXTURE (3)",
                       (int)d->strategy);
    c->strategy = d->strategy;
    c->light_weight = d->light_weight == 0.0f ? 0.5f : d->light_weight;
    if (!pt__isfinite(c->light_weight) || !(c->light_weight > 0.0f && c->light_weight <= 1.0f))
        return pt__msg(err, n, bad, "pt_render_desc.light_weight = %g: must be in (0, 1] (0: 0.5)",
                       (double)d->light_weight);
    if (d->max_depth < 0)
        return pt__msg(err, n, bad, "pt_render_desc.max_depth = %d: must be >= 0 (0: 50)", d->max_depth);
    c->max_depth = d->max_depth == 0 ? 50 : d->max_depth;
    c->rr_start = d->rr_start_depth == 0 ? 3 : (d->rr_start_depth < 0 ? 0x7fffffff : d->rr_start_depth);
    if (d->max_splits > PT__MAX_SPLITS_LIMIT)
        return pt__msg(err, n, bad, "pt_render_desc.max_splits = %d: must be at most %d (0: 64; < 0: no splitting)",
                       d->max_splits, PT__MAX_SPLITS_LIMIT);
    c->max_splits = d->max_splits == 0 ? 64 : (d->max_splits < 0 ? 0 : d->max_splits);
    if (d->indirect_paths < 0 || d->indirect_paths > PT__INDIRECT_PATHS_LIMIT)
        return pt__msg(err, n, bad, "pt_render_desc.indirect_paths = %d: must be in 0 .. %d (0: the sampler's default)",
                       d->indirect_paths, PT__INDIRECT_PATHS_LIMIT);
    if (!pt__color_ok(d->background))
        return pt__msg(err, n, bad, "pt_render_desc.background = (%g, %g, %g): must be finite and >= 0",
                       (double)d->background.x, (double)d->background.y, (double)d->background.z);
    c->background = d->background;
    c->guide = d->guide;
    c->guide_user = d->guide_user;
    c->guide_weight = d->guide ? (d->guide_weight == 0.0f ? 0.5f : d->guide_weight) : 0.0f;
    if (!pt__isfinite(c->guide_weight) || c->guide_weight < 0.0f || c->guide_weight >= 1.0f)
        return pt__msg(err, n, bad, "pt_render_desc.guide_weight = %g: must be in [0, 1) (0 with a guide: 0.5)",
                       (double)d->guide_weight);
    if (d->disable_skips & ~PT_SKIP_ALL)
        return pt__msg(err, n, bad,
                       "pt_render_desc.disable_skips = 0x%x: bits 0x%x are not PT_SKIP_* bits (PT_SKIP_ALL = 0x%x)",
                       d->disable_skips, d->disable_skips & ~PT_SKIP_ALL, PT_SKIP_ALL);
    c->general = d->disable_skips;
    if ((int)d->sampler < (int)PT_SAMPLER_INDEPENDENT || (int)d->sampler > (int)PT_SAMPLER_SOBOL)
        return pt__msg(err, n, bad,
                       "pt_render_desc.sampler = %d: must be PT_SAMPLER_INDEPENDENT (0) or PT_SAMPLER_SOBOL (1)",
                       (int)d->sampler);
    c->sampler = d->sampler;
    if ((int)d->integrator < (int)PT_INTEGRATOR_DEFAULT || (int)d->integrator > (int)PT_INTEGRATOR_BATCHED)
        return pt__msg(err, n, bad,
                       "pt_render_desc.integrator = %d: must be PT_INTEGRATOR_DEFAULT (0), _SCALAR (1) or _BATCHED (2)",
                       (int)d->integrator);
    c->batched = (int)d->integrator; /* (PT_INTEGRATOR_DEFAULT: resolved by pt__settings_for_scene) */
    c->rr_gain = c->sampler == PT_SAMPLER_SOBOL ? PT__RR_GAIN_SOBOL : 1.0f;
    c->indirect_paths = d->indirect_paths != 0 ? d->indirect_paths
                                               : c->sampler == PT_SAMPLER_SOBOL ? PT__INDIRECT_PATHS_SOBOL : 1;
    if (c->indirect_paths > c->max_splits + 1) c->indirect_paths = c->max_splits + 1; /* (max_splits < 0: 1) */
    return PT_OK;
}

/* The environment light's part of cfg for scene s: it is picked among the shaped lights in
   proportion to power, its power taken as that of a uniform radiance (the mean) falling on the
   scene's bounding sphere of radius R, 4 pi^2 R^2 L (the convention of pbrt-v4's infinite
   lights), kept within [0.001, 0.999] so neither is starved when both are present. */
static void pt__settings_for_scene(pt__settings *c, const pt_scene *s)
{
    double bg = ((double)c->background.x + (double)c->background.y + (double)c->background.z) / 3.0;
    double m = s->env ? s->env->mean : 0.0, phi, r;
    pt_vec3 ext = pt_sub(s->hi, s->lo);
    /* the default integrator: BATCHED where its stages run 8 wide (the built-in BVH with AVX2) or
       Embree 3 traces its batches as streams in a scene large enough for AUTO to choose Embree
       (the cases where it is measured faster: bench/README.md, "make bench-batched", "Embree
       streams" and "Two revisions side by side"), SCALAR elsewhere */
    if (c->batched == (int)PT_INTEGRATOR_DEFAULT) {
        c->batched = s->backend == PT_BACKEND_BUILTIN && s->simd >= PT_SIMD_AVX2;
#ifdef PT__RTC_STREAM
        c->batched |= s->backend == PT_BACKEND_EMBREE && s->prim_count >= (uint32_t)(PDFTRACE_EMBREE_MIN_PRIMS);
#endif
    }
    else c->batched = c->batched == (int)PT_INTEGRATOR_BATCHED;
    c->env = s->env;
    c->env_on = bg + m > 0.0;
    c->env_pick = 0.0f;
    c->lights_share = 1.0f;
    c->env_uniform = 0.0f;
    if (!c->env_on) return;
    c->env_uniform = pt__env_uniform_share(s->env, c->background);
    if (!s->light_count) {
        c->env_pick = 1.0f;
        c->lights_share = 0.0f;
        return;
    }
    r = s->prim_count ? 0.5 * sqrt((double)ext.x * ext.x + (double)ext.y * ext.y + (double)ext.z * ext.z) : 1.0;
    if (!(r > 0.0) || !(r < 1e150)) r = 1.0;
    phi = 4.0 * 9.8696044010893586 * r * r * (bg + m);
    c->env_pick = (float)pt__mind(0.999, pt__maxd(0.001, phi / (phi + s->total_power)));
    c->lights_share = 1.0f - c->env_pick;
}

static float pt__power_heuristic(float a, float b)
{
    float a2 = a * a, b2 = b * b;
    if (!pt__isfinite(a2)) return 1.0f; /* a dominates (only in extreme cases) */
    return a2 + b2 > 0.0f ? a2 / (a2 + b2) : 0.0f;
}
/* The power heuristic over a (a > 0), a / (a^2 + b^2): the weight of a sample of density a
   divided by that density, in one division where the weight and the quotient take two one after
   the other on next-event estimation's chain */
static float pt__power_heuristic_over(float a, float b)
{
    float a2 = a * a, b2 = b * b;
    if (!pt__isfinite(a2)) return 1.0f / a;
    return a2 + b2 > 0.0f ? a / (a2 + b2) : 0.0f;
}

/* Per-vertex state of the scatter density (material PDF mixed with an optional guide). */
typedef struct pt__vertex {
    const pt__material *m;
    pt_vec3 p, o, ng, ns, wo; /* o: the spawn point on the side of ng, the origin of every ray and
                                 of every light computation at this vertex */
    pt_vec3 ob;               /* m->transmits: the spawn point below ng, for transmitted and shadow
                                 rays that leave below (pt__vertex_origin) */
    float eta;                /* a rough dielectric's n_far / n_near seen from wo (else unused) */
    pt_color albedo;
    int has_guide;
    float g;
    pt_pdf guide;
    float cshare;             /* the caustic photons' share of the guide's (0: none) and their leaf */
    uint32_t cleaf;
    float rr_e, rr_ref; /* guided roulette: the expected contribution of going on per unit throughput
                           (0: unknown) and the path's reference (pt__trace_from) */
    int surface;          /* non-delta vertices before this one on its path (this one non-delta) */
    const void *sph_prim; /* the light sample at o: a quad light's primitive and the solid angle it */
    double sph_S;         /* was sampled by (pt__light_sample; NULL: none), which the emission a
                             scattered ray finds on that light reuses (pt__emission_weight) */
    int scat_ok;          /* 1: scat_wi and scat_pdf are this vertex's Lambertian direction and density
                             for the draws scat_u (the batch's stage 3b, pt__batch_scatter_ahead); 0
                             from pt__vertex_at on */
    float scat_u[2], scat_pdf;
    pt_vec3 scat_wi;
} pt__vertex;

/* The guide's density at vertex v: the learned guide's, mixed with the caustic photons' where
   they landed (pt__vertex_learned). */
static float pt__vertex_guide_density(const pt__vertex *v, pt_vec3 wi)
{
    const pt_guide *g = v->guide.as.guide.guide;
    const pt_vec3 n = v->guide.as.guide.fold;
    const float c = v->cshare;
    float x, y, mx, my, d0, d1, p;
    if (!(c > 0.0f)) return pt_pdf_value(&v->guide, wi);
    if (n.x == 0.0f && n.y == 0.0f && n.z == 0.0f) /* (a transmitting material: unfolded) */
        return c * pt__guide_value(g->caustic, v->cleaf, wi) +
               (c < 1.0f ? (1.0f - c) * pt__guide_value(g, v->guide.as.guide.leaf, wi) : 0.0f);
    if (!(pt_dot(wi, n) > 0.0f)) return 0.0f;
    /* the square's point and its mirror once, for both trees */
    pt__guide_dir_to_square(wi, &x, &y);
    if (!pt__guide_mirror_square(n, x, y, &mx, &my)) pt__guide_dir_to_square(pt__guide_mirror(wi, n), &mx, &my);
    if (c < 1.0f) { /* both trees, their four descents interleaved */
        float d[4];
        pt__dtree_density4(&g->caustic->leaves[v->cleaf].sampling, &g->leaves[v->guide.as.guide.leaf].sampling, x, y,
                           mx, my, d);
        return (c * (d[0] + d[1]) + (1.0f - c) * (d[2] + d[3])) * PT__INV_4PI;
    }
    pt__dtree_density2(&g->caustic->leaves[v->cleaf].sampling, x, y, mx, my, &d0, &d1);
    p = c * (d0 + d1);
    return p * PT__INV_4PI;
}
/* pg: the guide's density of wi when it is known (a guide sample's own), else < 0 */
static PT__HOT float pt__scatter_density_pg(const pt__vertex *v, pt_vec3 wi, float pg)
{
    float pm = v->m->type == PT_MATERIAL_LAMBERTIAN ? pt__maxf(0.0f, pt_dot(v->ns, wi)) * PT__INV_PI /* (inline) */
                                                    : pt__material_density(v->m, v->ns, v->wo, wi, v->eta);
    if (!v->has_guide) return pm;
    return (1.0f - v->g) * pm + v->g * (pg >= 0.0f ? pg : pt__vertex_guide_density(v, wi));
}
static PT__HOT float pt__scatter_density(const pt__vertex *v, pt_vec3 wi) { return pt__scatter_density_pg(v, wi, -1.0f); }
/* *pg receives the guide's density of *wi when the guide drew it, else -1 */
static PT__HOT int pt__scatter_sample(const pt__vertex *v, pt__sampler *smp, int depth, pt_vec3 *wi, float *pg)
{
    float u0 = v->has_guide ? pt__draw1(smp, PT__SET_BOUNCE(depth, PT__SLOT_GUIDE)) : 1.0f;
    *pg = -1.0f;
    if (v->has_guide && u0 < v->g) {
        /* (a one-sample mixture: only directions of the guide's own density) */
        if (v->guide.type == PT_PDF_GUIDE) { /* the learned guide, from the scattering numbers */
            float u1, u2;
            const pt_guide *g = v->guide.as.guide.guide;
            pt__draw_scatter(smp, depth, &u1, &u2);
            if (!(v->cshare > 0.0f))
                return pt__guide_sample_fold(g, v->guide.as.guide.leaf, v->guide.as.guide.fold, u1, u2, wi, pg, 0);
            /* the caustic photons' guide or the learned one, by u0 rescaled to [0, 1) */
            if (u0 < v->g * v->cshare) {
                if (!pt__guide_sample_fold(g->caustic, v->cleaf, v->guide.as.guide.fold, u1, u2, wi, pg, 0)) return 0;
            } else if (!pt__guide_sample_fold(g, v->guide.as.guide.leaf, v->guide.as.guide.fold, u1, u2, wi, pg, 0)) {
                return 0;
            }
            *pg = pt__vertex_guide_density(v, *wi);
            return *pg > 0.0f;
        }
        return pt__pdf_sample_depth(&v->guide, pt__sampler_rng(smp), wi, pg, 0, 1);
    } else {
        float u1, u2, u3, pm;
        pt__draw_scatter(smp, depth, &u1, &u2);
        u3 = pt__draw1_if(smp, PT__SET_BOUNCE(depth, PT__SLOT_SCATTER_EXTRA),
                          v->m->type == PT_MATERIAL_METAL || v->m->transmits);
        return pt__material_sample_dir(v->m, v->ns, v->wo, v->eta, u1, u2, u3, wi, &pm);
    }
}

/* The receiver normal of the light tree's choice at vertex v (pt__lnodew_importance): none of
   these materials reflects light from below ng (pt__material_eval); any other material gets none
   (the rough dielectric transmits light from below: no bound). */
static pt_vec3 pt__receiver_normal(const pt__vertex *v)
{
    if (v->m->type == PT_MATERIAL_LAMBERTIAN || v->m->type == PT_MATERIAL_METAL ||
        v->m->type == PT_MATERIAL_ROUGH_CONDUCTOR || v->m->type == PT_MATERIAL_ROUGH_PLASTIC)
        return v->ng;
    return pt_v3(0.0f, 0.0f, 0.0f);
}

/* Where a ray along w leaves vertex v: the spawn point on w's side of ng (below it only for a
   transmitting material, whose non-delta directions and shadow rays may go there). */
static PT__HOT pt_vec3 pt__vertex_origin(const pt__vertex *v, pt_vec3 w)
{
    return PT__UNLIKELY(v->m->transmits) && pt_dot(w, v->ng) < 0.0f ? v->ob : v->o;
}

/* The environment's light sample ls whose direction and density (pt__env_sample's, > 0 and finite)
   are set, with the map's radiance Lmap there: the rest of it, and its pick's probability. */
static PT__HOT int pt__env_light_finish(const pt__settings *cfg, pt_color Lmap, pt__light_sample *ls, uint32_t *light_index)
{
    ls->radiance = pt_add(cfg->background, Lmap);
    ls->pdf *= cfg->env_pick;
    ls->dist = PT__INF;
    ls->point = ls->normal = pt_v3(0, 0, 0);
    ls->rounded = 0;
    *light_index = PT__ENV_LIGHT;
    return ls->pdf > 0.0f;
}
/* A light sample of the environment, picked (pt__lights_sample_all). */
static PT__HOT int pt__env_light_sample(const pt__settings *cfg, float u1, float u2, pt__light_sample *ls,
                                        uint32_t *light_index)
{
    pt_color Lmap;
    if (!pt__env_sample(cfg->env, cfg->env_uniform, u1, u2, &ls->dir, &ls->pdf, &Lmap)) return 0;
    return pt__env_light_finish(cfg, Lmap, ls, light_index);
}
/* Light sampling with the environment: it is picked with probability cfg->env_pick, the shaped
   lights (pt__lights_sample) otherwise; ls->pdf is the pick's probability times the light's
   density, and *light_index is PT__ENV_LIGHT for the environment. */
static PT__HOT int pt__lights_sample_all(const pt_scene *s, const pt__settings *cfg, pt_vec3 o, pt_vec3 nr, float u0,
                                         float u1, float u2, pt__light_sample *ls, uint32_t *light_index)
{
    if (PT__UNLIKELY(cfg->env_pick > 0.0f)) {
        if (u0 < cfg->env_pick) return pt__env_light_sample(cfg, u1, u2, ls, light_index);
        u0 = pt__minf((u0 - cfg->env_pick) / cfg->lights_share, 0.99999994f);
        if (!pt__lights_sample(s, o, nr, u0, u1, u2, ls, light_index, pt__lights_mode(cfg))) return 0;
        ls->pdf *= cfg->lights_share;
        return ls->pdf > 0.0f;
    }
    return pt__lights_sample(s, o, nr, u0, u1, u2, ls, light_index, pt__lights_mode(cfg));
}
/* The density of pt__lights_sample_all: env_pick p_env + (1 - env_pick) sum_i P_i p_i. */
static float pt__lights_value_all(const pt_scene *s, const pt__settings *cfg, pt_vec3 o, pt_vec3 nr, pt_vec3 w)
{
    float v = s->light_count ? pt__lights_value(s, o, nr, w, pt__lights_mode(cfg)) : 0.0f;
    if (PT__UNLIKELY(cfg->env_pick > 0.0f))
        v = cfg->env_pick * pt__env_density(cfg->env, cfg->env_uniform, w) + cfg->lights_share * v;
    return v;
}

/* Whether any light can be sampled from p at all; exact (and cheap) for one light. Called only
   with at least one light (PT_SKIP_NO_EMITTERS is the caller's). */
static int pt__lights_reachable(const pt_scene *s, pt_vec3 p)
{
    const pt__prim *lp;
    int two;
    if (s->light_count != 1) return 1;
    lp = &s->prims[s->lights[0].prim];
    two = s->mats[lp->material].two_sided;
    if (lp->type == PT__PRIM_SPHERE) return two || !pt__sphere_inside(p, lp->p0, lp->p1.x);
    return pt__planar_faces(p, lp->p0, lp->n, two);
}

/* The shadow ray from v's spawn point to the light sample ls of light li: the segment, which
   ends at t = 1 short of the light's offset point (target: that point, pt__light_target). */
static PT__HOT void pt__light_shadow_ray_to(const pt__vertex *v, const pt__light_sample *ls, pt_vec3 target, int tri,
                                            pt__rayctx *src)
{
    pt_ray sr;
    sr.origin = pt__vertex_origin(v, ls->dir);
    sr.dir = pt_sub(target, sr.origin);
    pt__rayctx_init2(src, sr, tri);
}
static PT__HOT pt_vec3 pt__light_target(const pt_scene *s, const pt__light_sample *ls, uint32_t li)
{
    return pt__offset_origin(ls->point, ls->normal, pt_neg(ls->dir),
                             pt__prim_magnitude(&s->prims[s->lights[li].prim], ls->normal));
}
static PT__HOT void pt__light_shadow_ray(const pt_scene *s, const pt__vertex *v, const pt__light_sample *ls, uint32_t li,
                                         int tri, pt__rayctx *src)
{
    pt__light_shadow_ray_to(v, ls, pt__light_target(s, ls, li), tri, src);
}

/* Whether the segment from v's spawn point to the light sample ls of light li is unoccluded
   (one shadow ray). */
static PT__HOT int pt__light_visible(const pt_scene *s, const pt__vertex *v, const pt__light_sample *ls, uint32_t li,
                                     int tri, pt_path_stats *st)
{
    pt__rayctx src;
    pt__light_shadow_ray(s, v, ls, li, tri, &src);
    st->shadow_rays++;
    /* the light itself is skipped: a segment to a point sampled on a sphere (the near side seen
       from outside, any point from inside) or on a planar light meets that light only at the
       point, which the segment stops short of */
    return !pt__scene_any(s, &src, 1.0f - 1e-4f, s->lights[li].prim);
}

/* Next-event estimation at vertex v for the light sample ls (LIGHT and MIS) in two halves around
   its one shadow ray, so that the batched integrator (below) can trace a batch's shadow rays
   together: pt__nee_prepare evaluates f and sets up the shadow ray (0: nothing to add, no ray),
   pt__nee_finish gives the contribution beta f Le w / p_light of an unoccluded one. The MIS
   weight comes after the shadow ray: a guided density costs a tree descent, wasted on an
   occluded light. */
typedef struct pt__nee_ray {
    pt__rayctx rc;
    float tmax;
    uint32_t skip; /* the light's primitive, which the ray ignores (0xffffffff: none) */
    pt_color f;
} pt__nee_ray;
/* (target: the shadow ray's end, pt__light_target, where the caller has it already; else NULL) */
static PT__HOT int pt__nee_prepare_to(const pt_scene *s, const pt__settings *cfg, const pt__vertex *v,
                                      const pt__light_sample *ls, uint32_t li, int tri, pt__nee_ray *nr, pt_path_stats *st,
                                      const pt_vec3 *target)
{
    nr->f = pt__material_eval(v->m, v->albedo, v->ns, v->ng, v->wo, ls->dir, v->eta);
    if (pt__is_black(nr->f) && PT__SKIP(cfg, PT_SKIP_ZERO_BSDF_SHADOW)) return 0;
    if (li == PT__ENV_LIGHT) { /* the environment: a shadow ray to infinity */
        pt_ray sr;
        if (pt__is_black(ls->radiance)) return 0;
        sr.origin = pt__vertex_origin(v, ls->dir);
        sr.dir = ls->dir;
        pt__rayctx_init2(&nr->rc, sr, tri);
        nr->tmax = PT__INF;
        nr->skip = 0xffffffffu;
    } else { /* (pt__light_visible's segment) */
        if (target) pt__light_shadow_ray_to(v, ls, *target, tri, &nr->rc);
        else pt__light_shadow_ray(s, v, ls, li, tri, &nr->rc);
        nr->tmax = 1.0f - 1e-4f;
        nr->skip = s->lights[li].prim;
    }
    st->shadow_rays++;
    return 1;
}
static PT__HOT int pt__nee_prepare(const pt_scene *s, const pt__settings *cfg, const pt__vertex *v,
                                   const pt__light_sample *ls, uint32_t li, int tri, pt__nee_ray *nr, pt_path_stats *st)
{
    return pt__nee_prepare_to(s, cfg, v, ls, li, tri, nr, st, NULL);
}
static PT__HOT pt_color pt__nee_finish(const pt_scene *s, const pt__settings *cfg, const pt__vertex *v,
                                       const pt__light_sample *ls, uint32_t li, pt_color beta, pt_color f)
{
    float w_over_p;
    pt_color Le = li == PT__ENV_LIGHT ? ls->radiance : s->mats[s->prims[s->lights[li].prim].material].emission;
    if (cfg->strategy == PT_STRATEGY_MIS && !v->m->delta) w_over_p = pt__power_heuristic_over(ls->pdf, pt__scatter_density(v, ls->dir));
    else w_over_p = 1.0f / ls->pdf;
    return pt_mul(beta, pt_scale(pt_mul(f, Le), w_over_p));
}
/* Both halves with the shadow ray between them (the scalar integrator). */
static PT__HOT pt_color pt__nee_contribution(const pt_scene *s, const pt__settings *cfg, const pt__vertex *v,
                                     const pt__light_sample *ls, uint32_t li, pt_color beta, int tri,
                                     pt_path_stats *st)
{
    pt__nee_ray nr;
    if (!pt__nee_prepare(s, cfg, v, ls, li, tri, &nr, st) || pt__scene_any(s, &nr.rc, nr.tmax, nr.skip))
        return pt_v3(0, 0, 0);
    return pt__nee_finish(s, cfg, v, ls, li, beta, nr.f);
}

/* Next-event estimation of the delta lights (pt_scene_add_light) at non-delta vertex v, under
   every strategy, since no scattered ray can reach them: one light and one shadow ray; the
   contribution beta f L / P, with L = I falloff / d^2 (point, spot) or E (directional), has MIS
   weight 1. With up to PT__DELTA_PICK_MAX delta lights the light is picked with probability P
   proportional to what it would give v unshadowed, L cos(theta) at v's geometric normal (0 where
   the material can reflect none of it, so leaving those out is exact): distance, orientation and
   the spot's cone count, which picking by power cannot see (a sun whose power is taken over the
   scene's cross-section takes most picks in a room it lights only through a window:
   docs/design.md, "Lights without a shape"). With more, by power. A point light at the shading
   point itself (d = 0, an integrand with no finite value) adds nothing. */
/* The weight of light l at v, and in *fall the spot's falloff toward v (1 for other lights;
   unset where the weight is 0 before it). */
static float pt__delta_weight(const pt__vertex *v, const pt__dlight *l, float *fall)
{
    float c, i = l->mean;
    pt_vec3 d;
    float d2, inv, sg = 1.0f;
    *fall = 1.0f;
    if (PT__UNLIKELY(v->m->transmits)) sg = 0.0f; /* |cos|: a transmitting vertex sees lights below ng too */
    if (l->desc.type == PT_LIGHT_DIRECTIONAL) {
        c = -pt_dot(v->ng, l->axis);
        return i * pt__maxf(0.0f, c) + (1.0f - sg) * i * pt__maxf(0.0f, -c);
    }
    d = pt_sub(l->pos, v->p);
    d2 = pt_length2(d);
    if (!(d2 > 0.0f)) return 0.0f;
    inv = 1.0f / sqrtf(d2);
    c = pt_dot(v->ng, d) * inv;
    if (sg == 0.0f) c = fabsf(c);
    if (!(c > 0.0f)) return 0.0f;
    if (l->desc.type == PT_LIGHT_SPOT) i *= (*fall = pt__spot_falloff(l, pt_scale(d, -inv)));
    return i * c / d2;
}
/* pt__delta_prepare's pick among n weights w with running sums against us = u x their sum: the
   last light with weight up to the first whose running sum exceeds us, without branches (a
   weight of 0 leaves the sum as it is, so adding it changes nothing). */
static uint32_t pt__delta_pick_select(const float *w, uint32_t n, float us)
{
    float acc = 0.0f;
    uint32_t i, k = 0;
    int done = 0;
    for (i = 0; i < n; ++i) {
        const int take = !done & (w[i] > 0.0f);
        acc += w[i];
        k = take ? i : k;
        done |= take & (us < acc);
    }
    return k;
}
/* The delta lights at vertex v (a scene with any), in two halves around the shadow ray, as
   next-event estimation's (the batched integrator traces it with the batch's): pt__delta_prepare
   picks one light, evaluates f and sets up the shadow ray in nr (0: nothing to add, no ray), and
   in *Li_over_pick the light's radiance at v over the pick's probability; an unoccluded ray adds
   beta f Li / pick (pt__delta_finish). w_in and fall_in: the lights' weights and falloffs at v
   (pt__delta_weight's bits, from stage 2d: pt__batch_delta) for 2 .. PT__DELTA_PICK_MAX lights,
   or NULL to compute them here. */
static int pt__delta_prepare(const pt_scene *s, const pt__settings *cfg, const pt__vertex *v, int depth, pt__sampler *smp,
                             int tri, pt__nee_ray *nr, pt_color *Li, float *pick_out, pt_path_stats *st,
                             const float *w_in, const float *fall_in)
{
    const pt__dlight *l = &s->dlights[0];
    pt_vec3 wi;
    pt_color f;
    pt_ray sr;
    float tmax, pick = 1.0f, fall_k = -1.0f; /* the picked light's falloff, if its weight has it */
    if (s->dlight_count > 1) {
        float u = pt__draw1(smp, PT__SET_DELTA_PICK(depth));
        if (s->dlight_count <= PT__DELTA_PICK_MAX) {
            float wl[PT__DELTA_PICK_MAX], fl[PT__DELTA_PICK_MAX], sum = 0.0f, acc = 0.0f;
            const float *w = w_in ? w_in : wl, *fall = w_in ? fall_in : fl;
            uint32_t i, k = 0;
            if (w_in)
                for (i = 0; i < s->dlight_count; ++i) sum += w[i];
            else
                for (i = 0; i < s->dlight_count; ++i) sum += (wl[i] = pt__delta_weight(v, &s->dlights[i], &fl[i]));
            if (!(sum > 0.0f) || !pt__isfinite(sum)) return 0;
            if (w_in) /* (weights ready: the same pick without branches, which a random pick mispredicts) */
                k = pt__delta_pick_select(w, s->dlight_count, u * sum);
            else
                for (i = 0; i < s->dlight_count; ++i) /* the last light with weight whose range holds u */
                    if (w[i] > 0.0f) {
                        k = i;
                        acc += w[i];
                        if (u * sum < acc) break;
                    }
            l = &s->dlights[k];
            pick = w[k] / sum;
            fall_k = fall[k]; /* (w[k] > 0: the weight got as far as the falloff) */
        } else {
            uint32_t lo = 0, hi = s->dlight_count - 1u;
            while (lo < hi) { /* first light whose cdf exceeds u */
                uint32_t mid = (lo + hi) / 2u;
                if (s->dlights[mid].cdf > u) hi = mid;
                else lo = mid + 1u;
            }
            l = &s->dlights[lo];
            pick = l->select_pdf;
        }
    }
    if (l->desc.type == PT_LIGHT_DIRECTIONAL) {
        sr.origin = pt__vertex_origin(v, pt_neg(l->axis));
        sr.dir = wi = pt_neg(l->axis);
        *Li = l->desc.intensity;
        tmax = PT__INF;
    } else {
        /* distance and direction from the surface point itself, not from the spawn point above it,
           whose offset would be a visible part of d for a light close to the surface */
        pt_vec3 d = pt_sub(l->pos, v->p);
        float d2 = pt_length2(d), fall = 1.0f;
        if (!(d2 > 0.0f)) return 0;
        if (l->desc.type == PT_LIGHT_SPOT &&
            !((fall = fall_k >= 0.0f ? fall_k : pt__spot_falloff(l, pt_scale(d, -1.0f / sqrtf(d2)))) > 0.0f))
            return 0;
        *Li = pt_scale(l->desc.intensity, fall / d2);
        wi = pt_scale(d, 1.0f / sqrtf(d2));
        sr.origin = pt__vertex_origin(v, wi);
        sr.dir = pt_sub(l->pos, sr.origin); /* the segment to the light, short of it (a light on a surface is
                                          not hidden by that surface) */
        tmax = 1.0f - 1e-4f;
    }
    f = pt__material_eval(v->m, v->albedo, v->ns, v->ng, v->wo, wi, v->eta);
    if (pt__is_black(f) && PT__SKIP(cfg, PT_SKIP_ZERO_BSDF_SHADOW)) return 0;
    pt__rayctx_init2(&nr->rc, sr, tri);
    nr->tmax = tmax;
    nr->skip = 0xffffffffu;
    nr->f = f;
    *pick_out = pick;
    st->shadow_rays++;
    return 1;
}
static pt_color pt__delta_finish(pt_color beta, const pt__nee_ray *nr, pt_color Li, float pick)
{
    return pt_mul(beta, pt_scale(pt_mul(nr->f, Li), 1.0f / pick));
}
/* Both halves with the shadow ray between them (the scalar integrator). */
static pt_color pt__delta_nee(const pt_scene *s, const pt__settings *cfg, const pt__vertex *v, pt_color beta,
                              int depth, pt__sampler *smp, int tri, pt_path_stats *st)
{
    pt__nee_ray nr;
    pt_color Li;
    float pick;
    if (!pt__delta_prepare(s, cfg, v, depth, smp, tri, &nr, &Li, &pick, st, NULL, NULL) ||
        pt__scene_any(s, &nr.rc, nr.tmax, nr.skip))
        return pt_v3(0, 0, 0);
    return pt__delta_finish(beta, &nr, Li, pick);
}

/* The scene-feature skips (PT_SKIP_*) appear below as PT__SKIP(cfg, bit) tests; with the bit
   in cfg->general the general path runs instead. */
/* Splitting (a weight window: Arvo & Kirk 1990, "Particle Transport and Image Synthesis", who
   brought Russian roulette and splitting to rendering; Vorba & Krivanek 2016, "Adjoint-Driven
   Russian Roulette and Splitting in Light Transport Simulation"). Russian roulette keeps a path's
   throughput from falling far below 1; splitting keeps it from growing far above. A throughput
   above 1 comes from scatter weights f/p > 1, that is from densities smaller than the material's
   own: MIXTURE gives every direction that misses the lights the weight f / ((1 - w) p_s), and
   with light_weight 0.75 over white walls (albedo 0.73) that is 4 x 0.73 per bounce. Such a path
   has probability 0.25^d of reaching depth d and weight 2.9^d there, so its second moment grows
   as 0.25 x 2.9^2 = 2.1 per bounce and the variance is dominated by paths too rare to be seen.
   So where a non-delta vertex is reached with max(beta_in) >= 2, the path continues as
   k = min(8, floor(max(beta_in))) independent copies, each with beta_in / k, each sampling its
   own direction (and its own roulette): the expectation is unchanged, every copy's throughput
   stays below 2, and the second moment a bounce multiplies in becomes (E[w^2] + (k - 1) E[w]^2)
   / k instead of E[w^2], w = f/p (E[w] <= albedo < 1), so it no longer grows without bound.
   The extra copies run after the path that split, depth first, on the same sampler stream
   (INDEPENDENT) or on Sobol sets scrambled with their own key (SOBOL); at most max_splits extra
   copies per camera sample (default 64), after which paths go on unsplit. The next-event
   estimate of the vertex is taken once, before the split. With MATERIAL, LIGHT and MIS and the
   built-in materials, throughputs stay near or below 1 (cosine-sampled Lambertian: f/p = albedo;
   glass: 1), so paths split only after a dozen or more bounces through glass and mirrors, whose
   weight 1 roulette divides by 0.95 each time; with a guide, or MIXTURE, they split often. What
   it does to the error: docs/internals.md, "Splitting (the weight window)". */
#define PT__SPLIT_BETA 2.0f
#define PT__GUIDE_RR_WINDOW 10.0f /* guided roulette: q >= min(0.95, 10 b e / ref) (bench/README.md) */
#define PT__SPLIT_MAX_COPIES 8

/* indirect_paths (pt_render_desc): a camera sample's path also splits at its first non-delta
   vertex, into k copies that continue independently after that vertex's one next-event
   estimate. A camera sample's error is the sum of what it estimates once (where in the pixel,
   the first vertex's emission and direct light: variance V_c, cost C_c) and what the
   continuation estimates (V_i, C_i per copy); with k copies, variance x cost is
   (V_c + V_i / k)(C_c + k C_i), least at k* = sqrt(V_i C_c / (V_c C_i)) -- the trade-off of
   splitting (Arvo & Kirk 1990), as in production renderers' "indirect samples per camera
   sample". The Sobol sampler stratifies the first vertex's dimensions over a pixel's samples, so
   V_c is small and k* large; with independent numbers V_c holds e.g. the choice among many
   lights. So the default is 3 with Sobol, and 1 (no split) with independent numbers (the
   measurements: docs/internals.md, "Indirect paths"). The path starts with throughput k and its
   sum is divided by k, so each copy carries throughput ~1 like an unsplit path, and roulette and
   the weight window treat it so. */

/* A camera sample's splitting budget: `left` extra copies may still start (max_splits), and
   `first` is the split of the first non-delta vertex still to come (indirect_paths; 1 once it
   has been reached). */
/* Path classes (a diagnostic, compiled only with PDFTRACE_PATH_CLASSES: bench/path_classes.c).
   The scalar integrator hands each contribution to pt_path_class_add, which the including file
   defines, with the class of the path that made it, from the sequence of its vertices: D a
   non-delta vertex, S a delta one, read from the camera (E) to the light (L). */
#ifdef PDFTRACE_PATH_CLASSES
enum {
    PT_PATH_CLASS_NO_DELTA,        /* E D+ L: no delta vertex */
    PT_PATH_CLASS_DELTA,           /* delta vertices, none between the light and the last D */
    PT_PATH_CLASS_CAUSTIC_SEEN,    /* L S+ D E: a caustic the camera sees */
    PT_PATH_CLASS_CAUSTIC_THROUGH, /* L S+ D S+ E: a caustic seen through delta surfaces */
    PT_PATH_CLASS_CAUSTIC_BOUNCE,  /* L S+ D D ... E: a caustic's light, one more D next to it */
    PT_PATH_CLASS_CAUSTIC_SDS,     /* L S+ D S+ D ... E: a caustic's light seen through delta
                                      surfaces from a D (no unbiased local sampling technique
                                      connects these: only a scattered direction finds them) */
    PT_PATH_CLASS_COUNT
};
void pt_path_class_add(int path_class, pt_color contribution);
void pt_path_class_sample_done(uint32_t pixel); /* after each camera sample of pt_render (scalar) */
typedef struct pt__pclass {
    int d, s_first, s_last, s_any; /* D count; S before the first D, since the last D, anywhere */
    int s_before;         /* an S between the last D and the D before it */
} pt__pclass;
static void pt__pclass_vertex(pt__pclass *c, int delta)
{
    if (!delta) c->s_before = c->s_last && c->d > 0;
    if (delta) {
        c->s_first |= c->d == 0;
        c->s_last = c->s_any = 1;
    } else {
        c->d++;
        c->s_last = 0;
    }
}
/* the class of light reached by a ray from the last vertex (next-event estimation's is
   pt__pclass_nee's) */
static int pt__pclass_found(const pt__pclass *c)
{
    if (!c->s_last || c->d == 0) return c->s_any ? PT_PATH_CLASS_DELTA : PT_PATH_CLASS_NO_DELTA;
    if (c->d == 1) return c->s_first ? PT_PATH_CLASS_CAUSTIC_THROUGH : PT_PATH_CLASS_CAUSTIC_SEEN;
    return c->s_before ? PT_PATH_CLASS_CAUSTIC_SDS : PT_PATH_CLASS_CAUSTIC_BOUNCE;
}
static int pt__pclass_nee(const pt__pclass *c) { return c->s_any ? PT_PATH_CLASS_DELTA : PT_PATH_CLASS_NO_DELTA; }
#define PT__PCLASS(...) __VA_ARGS__
#else
#define PT__PCLASS(...)
#endif

typedef struct pt__splits {
    int left, first;
    float rr_ref; /* guided roulette: the path's expected value at its first guided vertex (0: none yet) */
    PT__PCLASS(pt__pclass pc;) /* the path's class at the vertex that splits (split copies start from it) */
} pt__splits;

/* How many copies the path continues as from a non-delta vertex reached with throughput beta_in:
   the first such vertex of a camera sample splits into indirect_paths, any vertex into
   min(8, floor(max(beta_in))) once that is 2 or more (the larger of the two), within the
   budget. */
static int pt__split_count(pt_color beta_in, pt__splits *sp)
{
    const float b = pt_max_component(beta_in);
    int k = sp->first;
    sp->first = 1;
    if (b >= PT__SPLIT_BETA) {
        const int kw = b >= (float)PT__SPLIT_MAX_COPIES ? PT__SPLIT_MAX_COPIES : (int)b;
        if (kw > k) k = kw;
    }
    if (k - 1 > sp->left) k = sp->left + 1;
    sp->left -= k - 1;
    return k;
}

/* A split copy's sampler: SOBOL re-keys the scrambling (the copy's sets are Owen-scrambled
   Sobol sets of their own, stratified over the pixel's samples); INDEPENDENT draws on from the
   parent's stream, which the copy runs before the parent goes on. */
static pt__sampler *pt__split_sampler(pt__sampler *parent, pt__sampler *child, int depth, int copy)
{
    if (!parent->sobol) return parent;
    *child = *parent;
    child->key = pt__mix64(parent->key ^ (0x94d049bb133111ebULL * (uint64_t)(depth * PT__SPLIT_MAX_COPIES + copy + 1)));
    pt_rng_seed(&child->rng, child->key, (uint64_t)copy);
    child->rng_seeded = 1;  /* (else a guide's first draw would reseed it with the parent's stream) */
    child->cache_lane = parent->cache_lane + PT__SOBOL_CACHE_LANE * (uint32_t)copy;
    return child;
}

/* The direction a delta material at vertex v scatters into, and the throughput's factor: a clear
   dielectric reflects when u < F, else refracts (weight F/F or (1-F)/(1-F) = 1); a mirror or
   smooth metal reflects with its reflectance. 0: nothing leaves on the side of ng. Paths and
   caustic photons (section 8, "Guiding") both take it. */
static PT__HOT int pt__delta_scatter(const pt__vertex *v, int front_face, float u, pt_vec3 *wi, pt_color *beta)
{
    const pt__material *m = v->m;
    if (m->type == PT_MATERIAL_DIELECTRIC || m->type == PT_MATERIAL_ROUGH_DIELECTRIC) {
        float eta = front_face ? 1.0f / m->ior : m->ior, cos_t = 0.0f;
        float cos_i = pt__minf(1.0f, pt_dot(v->wo, v->ns));
        float F = pt__fresnel_dielectric(cos_i, eta, &cos_t);
        if (u < F) *wi = pt__reflect(v->wo, v->ns);
        else {
            *wi = pt_normalize(pt_add(pt_scale(v->wo, -eta), pt_scale(v->ns, eta * cos_i - cos_t)));
            /* the smooth limit of the rough dielectric scales transmitted radiance by
               (n_near / n_far)^2 as the rough one does (pt_material_desc) */
            if (m->type == PT_MATERIAL_ROUGH_DIELECTRIC) *beta = pt_scale(*beta, eta * eta);
        }
        return 1;
    }
    *wi = pt__reflect(v->wo, v->ns);
    if (pt_dot(*wi, v->ng) <= 0.0f) return 0;
    *beta = pt_mul(*beta, pt__delta_reflectance(m, v->albedo, pt_dot(v->wo, v->ns)));
    return 1;
}

/* The continuation at vertex v (depth `depth`, throughput beta_in reaching it): the scattered
   direction and its weight, the spawned ray, then Russian roulette. Returns 0 if the path ends.
   *L_out (zero on entry) receives emission found without a ray (see the rounded case below). */
static PT__HOT int pt__continue(const pt_scene *s, const pt__settings *cfg, const pt__vertex *v, const pt_hit *h, int depth,
                        pt_color beta_in, pt__sampler *smp, int any_lights, int pick, pt_ray *ray, pt_color *beta,
                        float *prev_pdf, int *prev_delta, pt_color *L_out, pt_path_stats *st)
{
    const pt__material *m = v->m;
    pt_vec3 wi;
    *beta = beta_in;
    if (m->delta) {
        /* perfectly specular: follow the delta direction; no light PDF here */
        float u = m->type == PT_MATERIAL_DIELECTRIC || m->type == PT_MATERIAL_ROUGH_DIELECTRIC
                      ? pt__draw1(smp, PT__SET_BOUNCE(depth, PT__SLOT_FRESNEL))
                      : 0.0f;
        if (!pt__delta_scatter(v, h->front_face, u, &wi, beta)) return 0;
        *prev_delta = 1;
    } else {
        float p_total, u, pg = -1.0f;
        pt_color f;
        int use_light = 0;
        pt__light_sample ls;
        uint32_t li = 0;
        int weighed = 0; /* 1: *beta already carries f / p_total */
        ls.rounded = 0;
        if (cfg->strategy == PT_STRATEGY_MIXTURE && any_lights &&
            (!s->light_count || cfg->env_on || !PT__SKIP(cfg, PT_SKIP_FACING_AWAY) || pt__lights_reachable(s, v->o))) {
            u = pt__draw1(smp, PT__SET_BOUNCE(depth, PT__SLOT_MIXTURE));
            use_light = u < cfg->light_weight;
            if (use_light) {
                float u0 = pt__draw1_if(smp, PT__SET_BOUNCE(depth, PT__SLOT_LIGHT_PICK), pick), u1, u2;
                pt__draw2(smp, PT__SET_BOUNCE(depth, PT__SLOT_LIGHT_POINT), &u1, &u2);
                if (!pt__lights_sample_all(s, cfg, v->o, pt__receiver_normal(v), u0, u1, u2, &ls, &li)) return 0;
                wi = ls.dir;
            } else if (!pt__scatter_sample(v, smp, depth, &wi, &pg)) return 0;
            /* a rounded direction has no density for its own light: that light's share is the
               sample's own (ls.pdf, the pick probability included) */
            p_total = cfg->light_weight *
                          (pt__lights_value_all(s, cfg, v->o, pt__receiver_normal(v), wi) + (ls.rounded ? ls.pdf : 0.0f)) +
                      (1.0f - cfg->light_weight) * pt__scatter_density_pg(v, wi, pg);
        } else if (!v->has_guide && m->type == PT_MATERIAL_LAMBERTIAN) {
            /* pt__scatter_sample's draws for a Lambertian vertex without a guide, whose sampling
               density is the material's: not evaluated a second time */
            float u1, u2, u3;
            pt__draw_scatter(smp, depth, &u1, &u2);
            u3 = pt__draw1_if(smp, PT__SET_BOUNCE(depth, PT__SLOT_SCATTER_EXTRA), 0);
            if (v->scat_ok && v->scat_u[0] == u1 && v->scat_u[1] == u2) { /* made ahead for these draws */
                wi = v->scat_wi;
                p_total = v->scat_pdf;
                if (!(p_total > 0.0f)) return 0;
            } else if (!pt__material_sample_dir(m, v->ns, v->wo, v->eta, u1, u2, u3, &wi, &p_total)) return 0;
            /* f / p_total = albedo (cos/pi over the same cos/pi, which the draw made > 0), where
               pt__material_eval gives f; no division on the path's chain */
            if (!(pt_dot(v->ng, wi) > 0.0f) || pt__is_black(v->albedo)) return 0;
            *beta = pt_mul(*beta, v->albedo);
            weighed = 1;
        } else {
            if (!pt__scatter_sample(v, smp, depth, &wi, &pg)) return 0;
            p_total = pt__scatter_density_pg(v, wi, pg);
        }
        if (!weighed) {
            f = pt__material_eval(m, v->albedo, v->ns, v->ng, v->wo, wi, v->eta);
            if (pt__is_black(f) || !(p_total > 0.0f)) return 0;
            *beta = pt_mul(*beta, pt_scale(f, 1.0f / p_total));
        }
        *prev_pdf = p_total;
        *prev_delta = 0;
        if (ls.rounded) {
            /* a sphere light narrower than float's angular resolution, which a ray along the
               rounded direction misses: the ray's hit is the light when the segment to the
               sampled point is unoccluded, and the path ends there (what such a light reflects
               is O(r^2/d^2)); else the ray goes on to the occluder */
            if (pt__light_visible(s, v, &ls, li, (s->features & PT_FEATURE_TRIANGLES) != 0, st)) {
                *L_out = pt_mul(*beta, s->mats[s->prims[s->lights[li].prim].material].emission);
                return 0;
            }
        }
    }
    /* non-delta directions leave on the side of ng (pt__material_eval) except a rough
       dielectric's transmitted ones: the spawn point on wi's side, the one light sampling used */
    ray->origin = *prev_delta ? pt__offset_origin(v->p, v->ng, wi, h->magnitude) : pt__vertex_origin(v, wi);
    ray->dir = wi;
    if (depth + 1 >= cfg->rr_start) {
        float b = pt_max_component(beta_in), q = pt__minf(0.95f, sqrtf(cfg->rr_gain * b));
        /* with a learned guide, q also follows the expected contribution b e of going on against
           the path's reference (adjoint-driven roulette, Vorba & Krivanek 2016, without its
           splitting): only ever raised, so a poor estimate costs rays, not fireflies */
        if (v->rr_e > 0.0f && v->rr_ref > 0.0f) q = pt__maxf(q, pt__minf(0.95f, PT__GUIDE_RR_WINDOW * b * v->rr_e / v->rr_ref));
        if (!(q > 0.0f) || pt__draw1(smp, PT__SET_BOUNCE(depth, PT__SLOT_RR)) >= q) return 0;
        *beta = pt_scale(*beta, 1.0f / q);
    }
    return 1;
}

static pt_color pt__trace_from(const pt_scene *s, const pt__settings *cfg, pt_ray ray, pt_color beta, int depth0,
                               int surfaces0, int prev_delta, float prev_pdf, pt_vec3 prev_p, pt_vec3 prev_n,
                               pt__sampler *smp, pt_path_stats *st, pt__splits *sp);

/* Training a guide (section 8, "Guiding"): a non-delta vertex that continued along w with
   density pdf and throughput beta (after the scatter weight and roulette) when the path had
   gathered L0; what the path gathers after it, divided by beta, estimates the radiance L_i
   arriving along w, and L_i / pdf is recorded (Mueller et al. 2017: the records' sum over a
   directional cell estimates the integral of L_i over it). The first PT__GUIDE_PATH_RECORDS
   vertices of a path (and of each split copy) are recorded. With next-event estimation (MIS,
   LIGHT) the emission a recorded vertex's own ray finds is left out: direct light is NEE's to
   sample, and the guide spends its share on the light NEE cannot see. */
#define PT__GUIDE_PATH_RECORDS 12
typedef struct pt__guide_rec {
    pt_vec3 p, w;
    float pdf;
    pt_color beta, L0;
} pt__guide_rec;
static void pt__guide_record_path(pt_guide *g, const pt__guide_rec *r, int n, pt_color L)
{
    int i;
    if (!pt__vfinite(L)) return;
    for (i = 0; i < n; ++i) {
        const float *b = &r[i].beta.x, *l = &L.x, *l0 = &r[i].L0.x;
        double sum = 0.0;
        int c, used = 0;
        for (c = 0; c < 3; ++c)
            if (b[c] > 0.0f) { sum += ((double)l[c] - (double)l0[c]) / (double)b[c]; ++used; }
        pt__guide_splat(g, r[i].p, r[i].w, used ? sum / (double)used / (double)r[i].pdf : 0.0);
    }
}

/* Copies 1 .. k-1 of a split at vertex v, each with throughput beta_share (copy 0 is the path
   that split, which goes on in pt__trace_from). Kept out of line: it runs rarely, and inlined
   it slows the unsplit path (docs/internals.md, "Splitting (the weight window)"). */
#if defined(__GNUC__)
__attribute__((noinline))
#endif
static pt_color pt__split_copies(const pt_scene *s, const pt__settings *cfg, const pt__vertex *v, const pt_hit *h,
                                 int depth, int k, pt_color beta_share, pt__sampler *smp, int any_lights, int pick,
                                 int prev_delta, float prev_pdf, pt_path_stats *st, pt__splits *sp)
{
    pt_color L = pt_v3(0, 0, 0);
    int copy;
    PT__PCLASS(const pt__pclass pc = sp->pc;) /* (a copy's own splits overwrite sp->pc) */
    for (copy = 1; copy < k; ++copy) {
        pt__sampler child;
        pt__sampler *cs = pt__split_sampler(smp, &child, depth, copy);
        pt_ray r2;
        pt_color b2;
        float pp2 = prev_pdf;
        int pd2 = prev_delta;
        st->split_paths++;
        PT__PCLASS(sp->pc = pc;)
        pt_color Lc = pt_v3(0, 0, 0);
        if (pt__continue(s, cfg, v, h, depth, beta_share, cs, any_lights, pick, &r2, &b2, &pp2, &pd2, &Lc, st)) {
            pt_color Li = pt__trace_from(s, cfg, r2, b2, depth + 1, v->surface + 1, pd2, pp2, v->o, pt__receiver_normal(v),
                                         cs, st, sp);
            st->bounce_rays++;
            L = pt_add(L, Li);
            if (PT__UNLIKELY(cfg->recording != NULL) && !pd2) {
                pt__guide_rec one;
                one.p = v->p;
                one.w = r2.dir;
                one.pdf = pp2;
                one.beta = b2;
                one.L0 = pt_v3(0, 0, 0);
                pt__guide_record_path(cfg->recording, &one, 1, Li);
            }
        }
        L = pt_add(L, Lc);
        PT__PCLASS(pt_path_class_add(pt__pclass_found(&pc), pt_scale(Lc, 1.0f / (float)cfg->indirect_paths));)
    }
    return L;
}

/* Path guiding at non-delta vertex v: guided roulette's estimate of what going on adds per unit
   throughput, from the learned guide's leaf once it has data, and, at the first
   PT__GUIDE_SAMPLE_SURFACES non-delta vertices of a path (v->surface counts those before v), the
   leaf's guide folded about the geometric normal (non-delta materials reflect only:
   pt__continue; a transmitting one keeps the whole sphere, fold 0). Later vertices sample the
   material alone: each guided vertex pays two quadtree descents and an atan2, and the light the
   guide finds matters most where the path's throughput is still high (bench/README.md, "Path
   guiding, step by step"). Delta bounces are not counted: the caustic under a glass ball, seen
   through it from a wall, is reached at bounce 3 and found from there by its guide. */
#define PT__GUIDE_SAMPLE_SURFACES 2
#define PT__CAUSTIC_SHARE 0.5f /* the caustic photons' share of the guide's, where they landed */
static void pt__vertex_learned(const pt__settings *cfg, pt__vertex *v, pt_path_stats *st)
{
    uint32_t leaf = pt__guide_leaf_at(cfg->learned, v->p);
    const pt_guide *cg = cfg->learned->caustic;
    int trained = cfg->learned->leaves[leaf].trained;
    if (trained) v->rr_e = cfg->learned->leaves[leaf].flux * pt_max_component(v->albedo) * (0.5f / PT__PI);
    if (v->surface >= PT__GUIDE_SAMPLE_SURFACES) return;
    if (cg) {
        v->cleaf = pt__guide_leaf_at(cg, v->p);
        if (cg->leaves[v->cleaf].trained) v->cshare = trained ? PT__CAUSTIC_SHARE : 1.0f;
    }
    if (!trained && !(v->cshare > 0.0f)) return;
    v->guide.type = PT_PDF_GUIDE; /* (the fields it reads; a whole blank costs a memset a vertex) */
    v->guide.as.guide.guide = cfg->learned;
    v->guide.as.guide.leaf = leaf;
    v->guide.as.guide.fold = PT__UNLIKELY(v->m->transmits) ? pt_v3(0.0f, 0.0f, 0.0f) : v->ng;
    v->g = cfg->learned_weight;
    v->has_guide = 1;
    st->guided_vertices++;
}

/* What a ray along w that leaves the scene with throughput beta gathers from the environment
   light, weighted as emission found by a ray is (the strategies at the top of this section). */
/* pt__env_escape given the map's radiance Lmap along w and the density pm of its cell (0 and 0
   without a map), pt__env_light_eval's operations in its order. */
static pt_color pt__env_escape_map(const pt__settings *cfg, pt_color Lmap, float pm, pt_color beta, int prev_delta,
                                   float prev_pdf)
{
    const float p = cfg->env_uniform * PT__INV_4PI + (1.0f - cfg->env_uniform) * pm;
    const pt_color L = pt_add(cfg->background, Lmap);
    float wt = 1.0f;
    if (!prev_delta && cfg->strategy == PT_STRATEGY_MIS) wt = pt__power_heuristic(prev_pdf, cfg->env_pick * p);
    return pt_scale(pt_mul(beta, L), wt);
}
static pt_color pt__env_escape(const pt__settings *cfg, pt_vec3 w, pt_color beta, int prev_delta, float prev_pdf)
{
    float pm = 0.0f;
    pt_color Lmap;
    if (!prev_delta && cfg->strategy == PT_STRATEGY_LIGHT) return pt_v3(0, 0, 0);
    Lmap = cfg->env ? pt__env_eval(cfg->env, w, &pm) : pt_v3(0, 0, 0);
    return pt__env_escape_map(cfg, Lmap, pm, beta, prev_delta, prev_pdf);
}

/* Vertex v's spawn point on the side of ng and, for a transmitting material, the one below it
   and the relative index seen from wo (pt__vertex). */
static PT__HOT void pt__vertex_spawn(pt__vertex *v, const pt_hit *h)
{
    v->o = pt__offset_origin(v->p, v->ng, v->ng, h->magnitude);
    v->eta = 1.0f;
    if (PT__UNLIKELY(v->m->transmits)) {
        v->ob = pt__offset_origin(v->p, v->ng, pt_neg(v->ng), h->magnitude);
        v->eta = h->front_face ? v->m->ior : 1.0f / v->m->ior;
    }
}

/* The scattering vertex at hit h of primitive prim (material m) that a ray along dir found:
   its frame, wo, albedo and spawn points (the guide's fields are the caller's). */
static PT__HOT void pt__vertex_at(const pt_scene *s, const pt__settings *cfg, pt__vertex *v, const pt__prim *prim,
                                  const pt__material *m, const pt_hit *h, pt_vec3 dir, const float *bary)
{
    v->m = m;
    v->p = h->point;
    v->sph_prim = NULL;
    v->scat_ok = 0;
    v->wo = pt_neg(dir);
    v->ng = h->front_face ? h->geometric_normal : pt_neg(h->geometric_normal);
    v->ns = pt_dot(h->shading_normal, v->wo) < 0.0f ? pt_neg(h->shading_normal) : h->shading_normal;
    if (m->texture || PT__SKIP(cfg, PT_SKIP_NO_TEXTURES)) {
        v->albedo = pt__albedo(s, m, prim, bary, h);
    } else { /* general path: an untextured material looked up as a constant texture */
        pt__texture ct;
        memset(&ct, 0, sizeof ct);
        ct.even = ct.odd = m->albedo;
        ct.inv_scale = 1.0f;
        v->albedo = pt__checker(&ct, h->point);
    }
    pt__vertex_spawn(v, h);
}

/* The weight of emission that a ray scattered at a non-delta vertex (prev_p, receiver normal
   prev_n, density prev_pdf) finds on the emitting primitive prim at distance t along dir: the
   strategies at the top of this section. */
static PT__HOT float pt__emission_weight(const pt_scene *s, const pt__settings *cfg, const pt__prim *prim, float prev_pdf,
                                         pt_vec3 prev_p, pt_vec3 prev_n, pt_vec3 dir, float t, const pt__vertex *pv)
{
    float pl, d;
    if (cfg->strategy == PT_STRATEGY_LIGHT) return 0.0f;
    if (cfg->strategy != PT_STRATEGY_MIS) return 1.0f;
    if (pv && pv->sph_prim == (const void *)prim) /* the previous vertex's light sample set this quad up */
        d = pv->sph_S > 0.0 ? (float)(1.0 / pv->sph_S) : pt__planar_density(prim->n, s->lights[prim->light].area, t, dir);
    else
        d = pt__light_prim_value_at(s, prim, prev_p, dir, t, PT__SKIP(cfg, PT_SKIP_SOLID_ANGLE_QUADS));
    pl = cfg->lights_share * pt__light_pmf(s, prev_p, prev_n, (uint32_t)prim->light, pt__lights_mode(cfg)) * d;
    return pt__power_heuristic(prev_pdf, pl);
}

/* The path from `ray` on, which has throughput beta and has scattered `depth0` times, at
   `surfaces0` non-delta vertices (see pt__trace). */
static pt_color pt__trace_from(const pt_scene *s, const pt__settings *cfg, pt_ray ray, pt_color beta, int depth0,
                               int surfaces0, int prev_delta, float prev_pdf, pt_vec3 prev_p, pt_vec3 prev_n,
                               pt__sampler *smp, pt_path_stats *st, pt__splits *sp)
{
    pt_color L = pt_v3(0, 0, 0), beta_in;
    int depth, surfaces = surfaces0;
    const int any_lights = s->light_count > 0 || cfg->env_on || !PT__SKIP(cfg, PT_SKIP_NO_EMITTERS);
    const int tri = (s->features & PT_FEATURE_TRIANGLES) != 0; /* else rays skip the triangle set-up */
    const int nee = any_lights && (cfg->strategy == PT_STRATEGY_MIS || cfg->strategy == PT_STRATEGY_LIGHT);
    const int pick = s->light_count != 1 || cfg->env_pick > 0.0f; /* the light choice's number is used */
    pt__vertex v;
    pt__guide_rec recs[PT__GUIDE_PATH_RECORDS]; /* training: this call's non-delta vertices */
    int nrec = 0, rec_last = -1;
    v.has_guide = 0; /* (every other field is set at each vertex before it is read; v.guide only
                        when has_guide is) */
    v.g = 0.0f;
    v.rr_e = v.rr_ref = 0.0f;
    v.sph_prim = NULL; /* (the caller's vertex is not this one's: no light sample to reuse) */
    PT__PCLASS(pt__pclass pc = sp->pc; const float pc_k = 1.0f / (float)cfg->indirect_paths;)
    for (depth = depth0;; ++depth) {
        pt__rayctx rc;
        uint32_t pi;
        float t, bary[3];
        const pt__prim *prim;
        const pt__material *m;
        pt_hit h;
        int k;
        pt__rayctx_init2(&rc, ray, tri);
        if (!pt__scene_closest(s, &rc, PT__INF, &pi, &t, bary)) {
            if (PT__UNLIKELY(cfg->env_on)) {
                pt_color e = pt__env_escape(cfg, ray.dir, beta, prev_delta, prev_pdf);
                L = pt_add(L, e);
                PT__PCLASS(pt_path_class_add(pt__pclass_found(&pc), pt_scale(e, pc_k));)
                if (rec_last >= 0 && nee) recs[rec_last].L0 = pt_add(recs[rec_last].L0, e);
            } else {
                L = pt_add(L, pt_mul(beta, cfg->background)); /* (black: the scene has no environment) */
            }
            break;
        }
        prim = &s->prims[pi];
        m = &s->mats[prim->material];
        pt__fill_hit(s, prim, ray, t, bary, &h);
        /* emission reached by the ray */
        if (m->emits && (m->two_sided || h.front_face)) {
            float w = 1.0f;
            if (!prev_delta) {
                w = pt__emission_weight(s, cfg, prim, prev_pdf, prev_p, prev_n, ray.dir, t, &v);
            }
            if (w > 0.0f) {
                pt_color e = pt_scale(pt_mul(beta, m->emission), w);
                L = pt_add(L, e);
                PT__PCLASS(pt_path_class_add(pt__pclass_found(&pc), pt_scale(e, pc_k));)
                /* training with next-event estimation: direct light is NEE's, the guide learns the rest */
                if (rec_last >= 0 && nee) recs[rec_last].L0 = pt_add(recs[rec_last].L0, e);
            }
        }
        rec_last = -1;
        if (depth >= cfg->max_depth || !m->scatters) break;

        beta_in = beta;
        PT__PCLASS(pt__pclass_vertex(&pc, m->delta);)
        pt__vertex_at(s, cfg, &v, prim, m, &h, ray.dir, bary);
        if (m->delta && nee && !PT__SKIP(cfg, PT_SKIP_DELTA_VERTEX)) {
            /* general path: next-event estimation as at any vertex; a delta material reflects
               nothing toward the sampled point (pt__material_eval is zero), so this adds nothing */
            pt__light_sample ls;
            uint32_t li;
            float u0 = pt__draw1_if(smp, PT__SET_BOUNCE(depth, PT__SLOT_LIGHT_PICK), pick), u1, u2;
            pt__draw2(smp, PT__SET_BOUNCE(depth, PT__SLOT_LIGHT_POINT), &u1, &u2);
            if (pt__lights_sample_all(s, cfg, v.o, pt_v3(0.0f, 0.0f, 0.0f), u0, u1, u2, &ls, &li))
                L = pt_add(L, pt__nee_contribution(s, cfg, &v, &ls, li, beta, tri, st));
        }
        if (!m->delta) {
            v.surface = surfaces++;
            v.has_guide = 0;
            v.cshare = 0.0f;
            v.rr_e = 0.0f; /* (set at a guided vertex; delta vertices keep the last one's: the light
                              through glass is what the vertex before it learned) */
            if (cfg->guide) {
                pt_shading_point sp;
                sp.position = pt__to_world(s, v.p);
                sp.normal = v.ns;
                sp.wo = v.wo;
                sp.material = prim->material;
                sp.depth = depth;
                v.g = cfg->guide_weight;
                v.has_guide = cfg->guide(cfg->guide_user, &sp, &v.guide) ? 1 : 0;
            } else if (cfg->learned) {
                pt__vertex_learned(cfg, &v, st);
            }
            /* next-event estimation (LIGHT and MIS) */
            if (nee) {
                pt__light_sample ls;
                uint32_t li;
                float u0 = pt__draw1_if(smp, PT__SET_BOUNCE(depth, PT__SLOT_LIGHT_PICK), pick), u1, u2;
                pt__draw2(smp, PT__SET_BOUNCE(depth, PT__SLOT_LIGHT_POINT), &u1, &u2);
                ls.sph_prim = NULL;
                ls.sph_S = 0.0;
                if (pt__lights_sample_all(s, cfg, v.o, pt__receiver_normal(&v), u0, u1, u2, &ls, &li)) {
                    pt_color e = pt__nee_contribution(s, cfg, &v, &ls, li, beta, tri, st);
                    L = pt_add(L, e);
                    PT__PCLASS(pt_path_class_add(pt__pclass_nee(&pc), pt_scale(e, pc_k));)
                }
                v.sph_prim = ls.sph_prim;
                v.sph_S = ls.sph_S;
            }
            /* the delta lights, under every strategy (a scene without them skips this) */
            if (PT__UNLIKELY(s->dlight_count != 0)) {
                pt_color e = pt__delta_nee(s, cfg, &v, beta, depth, smp, tri, st);
                L = pt_add(L, e);
                PT__PCLASS(pt_path_class_add(pt__pclass_nee(&pc), pt_scale(e, pc_k));)
            }
            if (v.rr_e > 0.0f && !(sp->rr_ref > 0.0f)) /* the first guided vertex: what the path has so far
                                                          and what going on should add */
                sp->rr_ref = pt_max_component(L) + pt_max_component(beta) * v.rr_e;
            v.rr_ref = sp->rr_ref;
        }
        /* the continuation: split copies first (each ends before the next starts), then this path */
        if (!m->delta &&
            (sp->first > 1 ||
             PT__UNLIKELY(beta_in.x >= PT__SPLIT_BETA || beta_in.y >= PT__SPLIT_BETA || beta_in.z >= PT__SPLIT_BETA)) &&
            (k = pt__split_count(beta_in, sp)) > 1) {
            beta_in = pt_scale(beta_in, 1.0f / (float)k);
            PT__PCLASS(sp->pc = pc;)
            L = pt_add(L, pt__split_copies(s, cfg, &v, &h, depth, k, beta_in, smp, any_lights, pick, prev_delta, prev_pdf,
                                           st, sp));
        }
        {
            pt_color Lc = pt_v3(0, 0, 0);
            int go = pt__continue(s, cfg, &v, &h, depth, beta_in, smp, any_lights, pick, &ray, &beta, &prev_pdf,
                                  &prev_delta, &Lc, st);
            L = pt_add(L, Lc);
            PT__PCLASS(pt_path_class_add(pt__pclass_found(&pc), pt_scale(Lc, pc_k));)
            if (!go) break;
            if (PT__UNLIKELY(cfg->recording != NULL) && !prev_delta && nrec < PT__GUIDE_PATH_RECORDS) {
                recs[nrec].p = v.p; /* what arrives along ray.dir is what L gains from here on */
                recs[nrec].w = ray.dir;
                recs[nrec].pdf = prev_pdf;
                recs[nrec].beta = beta;
                recs[nrec].L0 = L;
                rec_last = nrec++;
            }
        }
        prev_p = v.o;
        prev_n = pt__receiver_normal(&v);
        st->bounce_rays++;
    }
    if (nrec) pt__guide_record_path(cfg->recording, recs, nrec, L);
    return L;
}

/* One path from the camera ray `ray`: throughput 1, no scattering yet. */
static pt_color pt__trace(const pt_scene *s, const pt__settings *cfg, pt_ray ray, pt__sampler *smp, pt_path_stats *st)
{
    /* indirect_paths k: the path starts with throughput k and the sum is divided by k, so each of
       the k copies the first non-delta vertex splits into has throughput ~1, as an unsplit path
       would: roulette (q from the throughput) and the weight window treat a copy as they treat
       a whole path. (With throughput 1/k, q = sqrt(1/k) would kill the copies early:
       docs/internals.md, "Indirect paths".) k = 1 is exact: throughput 1, and x * 1.0f == x. */
    const float k = (float)cfg->indirect_paths;
    pt__splits sp;
    sp.left = cfg->max_splits;
    sp.first = cfg->indirect_paths;
    sp.rr_ref = 0.0f;
    PT__PCLASS(memset(&sp.pc, 0, sizeof sp.pc);)
    st->camera_rays++;
    return pt_scale(pt__trace_from(s, cfg, ray, pt_v3(k, k, k), 0, 0, 1, 0.0f, ray.origin, pt_v3(0.0f, 0.0f, 0.0f), smp, st, &sp),
                    1.0f / k);
}

/* One camera sample with the per-sample NaN/Inf guard. */
static pt_color pt__sample(const pt_scene *s, const pt__settings *cfg, pt_ray ray, pt__sampler *smp,
                          pt_path_stats *st)
{
    pt_color L = pt__trace(s, cfg, ray, smp, st);
    if (!pt__vfinite(L)) {
        st->nonfinite_samples++;
        return pt_v3(0, 0, 0);
    }
    return L;
}

PTDEF pt_color pt_trace_path(const pt_scene *s, const pt_render_desc *d, pt_ray ray, pt_rng *rng, pt_path_stats *stats)
{
    pt__settings cfg;
    pt_path_stats local;
    pt__sampler smp;
    pt_color L;
    if (!s || !d || !rng || !s->committed || pt__settings_from_desc(d, &cfg, NULL, 0) != PT_OK ||
        !pt__vfinite(ray.origin) || !pt__vfinite(ray.dir) || !(pt_length2(ray.dir) > 0.0f))
        return pt_v3(0, 0, 0);
    pt__settings_for_scene(&cfg, s);
    if (!(fabsf(pt_length2(ray.dir) - 1.0f) <= 1e-6f)) ray.dir = pt_normalize(ray.dir); /* unit: as given */
    ray.origin = pt__to_local(s, ray.origin);
    memset(&local, 0, sizeof local);
    memset(&smp, 0, sizeof smp);
    smp.rng = *rng; /* independent: one path from the caller's stream, which advances as it draws */
    L = pt__sample(s, &cfg, ray, &smp, &local);
    *rng = smp.rng;
    if (stats) {
        stats->camera_rays += local.camera_rays;
        stats->bounce_rays += local.bounce_rays;
        stats->shadow_rays += local.shadow_rays;
        stats->nonfinite_samples += local.nonfinite_samples;
        stats->split_paths += local.split_paths;
        stats->guided_vertices += local.guided_vertices;
    }
    return L;
}

/* --- The batched integrator (pt_render_desc.integrator = PT_INTEGRATOR_BATCHED). The paths of up
   to PT__BATCH camera samples of a tile advance together, a bounce at a time, in stages over the
   batch: (1) the closest hits of every live path's ray; (2) for each path the emission its ray
   found, its next vertex and, with next-event estimation, the light sample and its shadow ray;
   (3) the batch's shadow rays; (4) for each path its light sample's contribution, the delta
   lights, splitting and the continuation (scattered direction, roulette); paths that ended leave
   the live list. Each stage calls what pt__trace_from calls, in the same order for each path,
   and a path keeps its own sampler, so every path draws the same numbers, does the same float
   operations and adds up its radiance in the same order as the scalar integrator: the image is
   the same bit for bit (tests/test_render.c, "batched"). A guide's training iterations
   (cfg->recording) keep each path's records in its lane (pt__lane_recs). Stage 2 leaves light
   samples of quads to stage 2c (by area, 8 at a time), which leaves those by solid angle to 2b
   (4 at a time), of spheres to 2s (8 at a time), light-tree picks to 2t (pt__lane_light). Split
   copies (indirect_paths: every camera sample of a default render). With the Sobol sampler a copy draws from sets of its own (pt__split_sampler), so copies 1 .. k-1 of a split
   take free lanes and run beside the path that split (copy 0), as the camera sample's family.
   What the scalar integrator does in its depth-first order is kept: (a) sums: a copy's lane sums
   its own path from 0; the parent logs what it gathers while its copies run (pt__lane_add) and,
   once they have all ended, adds their sum as pt__split_copies makes it, then its log
   (pt__lane_fold); (b) the camera sample's shared splitting state (pt__splits: the split budget,
   guided roulette's reference) is read and changed only by the family's first path in the scalar
   order (a list kept per family: a split's copies go before the path that split), which is
   where the scalar integrator would be; another path that needs it waits (pt__lane_shared);
   (c) rays and NaN counts go to the camera sample's. With independent numbers the copies draw
   from the parent's stream and run depth first in stage 4 (pt__split_copies), as they do when
   no lanes are free; pt_render_stats.batched_split_paths counts the copies that ran as lanes. */
#define PT__BATCH 64
#define PT__BATCH_LANES (4 * PT__BATCH) /* a batch's camera samples and the split copies' lanes */
#define PT__LANE_LOG 32     /* a lane's log; a bounce adds at most PT__LANE_LOG_BOUNCE to it (5 sums: */
#define PT__LANE_LOG_BOUNCE 6 /* emission, a delta vertex's light, the light sample, delta lights, Lc) */
enum { PT__WAIT_NONE, PT__WAIT_HEAD, PT__WAIT_LOG, PT__WAIT_ENDED };

typedef struct pt__lane {
    pt__sampler smp;
    pt__splits sp;
    pt__vertex v;
    pt_path_stats st;
    pt_ray ray;
    pt__rayctx rc; /* the ray's, for its closest hit */
    pt_color beta, beta_in, L;
    pt_vec3 prev_p, prev_n;
    float prev_pdf, k; /* k: indirect_paths, the throughput the path starts with (pt__trace) */
    int depth, surfaces, prev_delta, found, shadow; /* surfaces: non-delta vertices so far */
    int defer;         /* its light sample left to stage 2b (1), 2c (2), 2s (3) or 2e (4), or its pick to 2t (5) */
    float dpick, du0, du1, du2; /* (pt__lane_light) with the pick's probability, its number (2t), the point's */
    uint32_t pi, li, pix, index_k;
    float t, bary[3];
    pt_hit h;
    pt__light_sample ls;
    pt__nee_ray nr;
    pt__nee_ray dnr;  /* the delta lights' shadow ray (dshadow as shadow; pt__delta_prepare), with: */
    pt_color dLi;
    float dpick_delta;
    int dshadow;
    int esc;          /* stage 1e evaluated the environment map where the ray left the scene: */
    pt_color esc_L;   /* its radiance */
    float esc_pm;     /* and its cell's density (pt__env_eval) */
    int ddefer;       /* its delta lights left to stage 2d (pt__batch_delta) */
    /* split copies as lanes (below): the camera sample's lane is its family's root */
    int self, root, parent, copy; /* copy: which of the parent's copies (1 .. k-1) */
    int prev, next, head;         /* the family's scalar order (head: the root's, its first) */
    int pending, nkids, nlog, wait; /* pending: copies still running; wait: PT__WAIT_* */
    struct pt__lane_kids *kids;   /* (its own: kept apart, as only a split touches it) */
    struct pt__lane_recs *recs;   /* training (cfg->recording): its path's records; else NULL */
} pt__lane;

/* A lane's split copies' sums and its log (pt__lane_add). */
typedef struct pt__lane_kids {
    pt_color L[PT__SPLIT_MAX_COPIES], Lc[PT__SPLIT_MAX_COPIES]; /* each copy's path's sum, its continuation's */
    unsigned char go[PT__SPLIT_MAX_COPIES];                     /* whether the copy went on */
    pt_color log[PT__LANE_LOG]; /* what the path gathered while its copies ran, in order */
} pt__lane_kids;

/* Training a guide in the batched integrator (cfg->recording): a lane's records as
   pt__trace_from keeps them (a split copy's first is its continuation from the parent's vertex,
   as pt__split_copies records it), splatted when the path has ended (pt__lane_recs_flush; the
   splats are integer sums, so their order changes nothing). A record made while the lane's copies
   run has mark >= 0: its L0 is the lane's sum once pt__lane_fold has added the copies' and `mark`
   entries of the log, where the scalar integrator's sum stood. e: the emission the record's own
   ray found, which L0 leaves out (pt__trace_from adds it to L0 when found; added here at the end,
   the same float addition). */
typedef struct pt__lane_recs {
    pt__guide_rec r[PT__GUIDE_PATH_RECORDS + 1];
    pt_color e[PT__GUIDE_PATH_RECORDS + 1];
    signed char mark[PT__GUIDE_PATH_RECORDS + 1];
    int n, cap, last; /* records, how many it may hold, the last one's (-1: none to find emission) */
} pt__lane_recs;

/* A path's records at its start: none yet, up to PT__GUIDE_PATH_RECORDS of its own vertices. */
static void pt__lane_recs_start(pt__lane_recs *r)
{
    r->n = 0;
    r->last = -1;
    r->cap = PT__GUIDE_PATH_RECORDS;
}

/* Lane l's non-delta vertex continued along l->ray (pt__trace_from's record after pt__continue). */
static PT__NOINLINE void pt__lane_record(pt__lane *l, const int copies)
{
    pt__lane_recs *r = l->recs;
    const int i = r->n;
    if (i >= r->cap) return;
    r->r[i].p = l->v.p;
    r->r[i].w = l->ray.dir;
    r->r[i].pdf = l->prev_pdf;
    r->r[i].beta = l->beta;
    r->r[i].L0 = l->L;
    r->e[i] = pt_v3(0.0f, 0.0f, 0.0f);
    r->mark[i] = (signed char)(copies && l->pending ? l->nlog : -1);
    r->last = r->n++;
}

/* The records of lane l whose sum stood at l->L after `mark` entries of its log (pt__lane_fold). */
static void pt__lane_recs_resolve(pt__lane_recs *r, int mark, pt_color L)
{
    int i;
    for (i = 0; i < r->n; ++i)
        if (r->mark[i] == mark) {
            r->r[i].L0 = L;
            r->mark[i] = -1;
        }
}

/* A path's records into the guide once its sum L is final. */
static PT__NOINLINE void pt__lane_recs_flush(pt_guide *g, pt__lane_recs *r, pt_color L)
{
    int i;
    for (i = 0; i < r->n; ++i) r->r[i].L0 = pt_add(r->r[i].L0, r->e[i]);
    if (r->n) pt__guide_record_path(g, r->r, r->n, L);
    r->n = 0;
}

/* The lanes split copies take (free: not in use; spawn: copies started in this stage 4; parked:
   lanes that wait, pt__lane_continue). */
typedef struct pt__batch_pool {
    pt__lane_kids *kids;
    pt_guide *recording; /* cfg->recording */
    int nfree, nspawn, nparked;
    uint64_t lane_copies; /* split copies that ran as lanes */
    int free[PT__BATCH_LANES], spawn[PT__BATCH_LANES], parked[PT__BATCH_LANES];
} pt__batch_pool;
/* What every stage of a batch needs: pt__trace_from's per-path constants, and whether copies
   run as lanes (copies; pool). */
typedef struct pt__batch_ctx {
    const pt_scene *s;
    const pt__settings *cfg;
    int tri, any_lights, nee, pick, copies;
    int area;        /* quads' light samples left to stage 2c, and 2b (pt__lane_light) */
    int env8;        /* the environment map evaluated (stage 1e) and sampled (stage 2e) 8 lanes at a time */
    int picks;       /* the light tree's picks left to stage 2t (pt__lane_light) */
    int sph;         /* solid-angle sampling of quads allowed (PT__LIGHTS_SPHERICAL) */
    int dvec;        /* the delta lights' weights left to stage 2d (pt__batch_delta) */
    unsigned lmode;  /* pt__lights_mode */
    pt__lane *lanes;
    pt__batch_pool *pool; /* (copies only) */
} pt__batch_ctx;

static void pt__stats_sum(pt_path_stats *t, const pt_path_stats *a)
{
    t->camera_rays += a->camera_rays;
    t->bounce_rays += a->bounce_rays;
    t->shadow_rays += a->shadow_rays;
    t->nonfinite_samples += a->nonfinite_samples;
    t->split_paths += a->split_paths;
    t->guided_vertices += a->guided_vertices;
}

/* Lane l gathers x: into its sum, or, while copies it split into are still running (whose sum
   the scalar integrator adds first), into its log, which pt__lane_fold adds after theirs. A zero
   is left out of the log: a sum that starts at +0 is never -0, so adding a zero leaves it as is. */
static PT__HOT void pt__lane_add(pt__lane *l, pt_color x, const int copies)
{
    if (!copies || !l->pending) l->L = pt_add(l->L, x);
    else if (x.x != 0.0f || x.y != 0.0f || x.z != 0.0f) l->kids->log[l->nlog++] = x;
}

/* Once lane l's copies have all ended: their sum as pt__split_copies makes it (copy by copy, the
   path's sum, then what its continuation found), added to l's, then l's log in order. */
static PT__NOINLINE void pt__lane_fold(pt__lane *l)
{
    const pt__lane_kids *kx = l->kids;
    pt_color S = pt_v3(0, 0, 0);
    int c;
    for (c = 1; c <= l->nkids; ++c) {
        if (kx->go[c]) S = pt_add(S, kx->L[c]);
        S = pt_add(S, kx->Lc[c]);
    }
    l->L = pt_add(l->L, S);
    if (PT__UNLIKELY(l->recs != NULL)) pt__lane_recs_resolve(l->recs, 0, l->L);
    for (c = 0; c < l->nlog; ++c) {
        l->L = pt_add(l->L, kx->log[c]);
        if (PT__UNLIKELY(l->recs != NULL)) pt__lane_recs_resolve(l->recs, c + 1, l->L);
    }
    l->nlog = 0;
}

/* Lane idx's path has ended: once its copies have too, it leaves its family's order, its sum
   goes to its parent (its rays to the camera sample's count) and its lane is free again; the
   parent, if that was its last copy, folds and may end in turn. */
static PT__NOINLINE void pt__lane_end(pt__lane *lanes, pt__batch_pool *pool, int idx)
{
    pt__lane *l = &lanes[idx];
    l->wait = PT__WAIT_ENDED;
    while (l->wait == PT__WAIT_ENDED && !l->pending) {
        pt__lane *p;
        if (PT__UNLIKELY(l->recs != NULL)) pt__lane_recs_flush(pool->recording, l->recs, l->L);
        if (l->prev >= 0) lanes[l->prev].next = l->next;
        else lanes[l->root].head = l->next;
        if (l->next >= 0) lanes[l->next].prev = l->prev;
        if (l->parent < 0) return;
        p = &lanes[l->parent];
        p->kids->L[l->copy] = l->L;
        pt__stats_sum(&lanes[l->root].st, &l->st);
        pool->free[pool->nfree++] = l->self;
        if (--p->pending == 0) pt__lane_fold(p);
        l = p;
    }
}

/* A camera sample's path at its start (pt__trace): throughput k = indirect_paths, no scattering. */
static void pt__lane_start(pt__lane *l, const pt__settings *cfg, pt_ray ray)
{
    const float k = (float)cfg->indirect_paths;
    l->sp.left = cfg->max_splits;
    l->sp.first = cfg->indirect_paths;
    l->sp.rr_ref = 0.0f;
    PT__PCLASS(memset(&l->sp.pc, 0, sizeof l->sp.pc);)
    memset(&l->st, 0, sizeof l->st);
    l->st.camera_rays++;
    l->ray = ray;
    l->k = k;
    l->beta = pt_v3(k, k, k);
    l->L = pt_v3(0, 0, 0);
    l->depth = 0;
    l->surfaces = 0;
    l->prev_delta = 1;
    l->prev_pdf = 0.0f;
    l->prev_p = ray.origin;
    l->prev_n = pt_v3(0.0f, 0.0f, 0.0f);
    l->v.has_guide = 0;
    l->v.cshare = 0.0f;
    l->v.g = 0.0f;
    l->v.rr_e = l->v.rr_ref = 0.0f;
    l->v.sph_prim = NULL;
    if (PT__UNLIKELY(l->recs != NULL)) pt__lane_recs_start(l->recs);
}

/* pt__lights_pick at vertex v. A pick by power reads neither the vertex's point nor its normal,
   which are left alone (the point, just stored, would be read back before the stores are done). */
static PT__HOT int pt__lane_pick(const pt__batch_ctx *b, const pt__vertex *v, float u0, uint32_t *li, float *pick)
{
    if (!(b->s->ltree && (b->lmode & PT__LIGHTS_TREE)))
        return pt__lights_pick(b->s, pt_v3(0.0f, 0.0f, 0.0f), pt_v3(0.0f, 0.0f, 0.0f), u0, li, pick, 0u);
    return pt__lights_pick(b->s, v->o, pt__receiver_normal(v), u0, li, pick, b->lmode);
}
/* pt__lights_picked for a shaped light's sample at a lane, and with an environment the shaped
   lights' share pt__lights_sample_all multiplies in after it (in that order: the same bits). */
static PT__HOT int pt__lane_picked(const pt__batch_ctx *b, pt__light_sample *ls, float pick, uint32_t li,
                                   uint32_t *light_index)
{
    if (!pt__lights_picked(ls, pick, li, light_index)) return 0;
    if (PT__UNLIKELY(b->cfg->env_pick > 0.0f)) {
        ls->pdf *= b->cfg->lights_share;
        return ls->pdf > 0.0f;
    }
    return 1;
}
/* The rest of pt__lane_light at lane l once its pick chose shaped light li with probability pick
   (stage 2, or 2t): a quad's or a sphere's sample left to stages 2c and 2s (l->defer 2 or 3), any
   other light's sample and its shadow ray. */
static PT__HOT void pt__lane_light_picked(const pt__batch_ctx *b, pt__lane *l, uint32_t li, float pick)
{
    const pt_scene *s = b->s;
    pt__vertex *v = &l->v;
    const pt__prim *p = &s->prims[s->lights[li].prim];
    if (p->type == PT__PRIM_QUAD || p->type == PT__PRIM_SPHERE) {
        l->defer = p->type == PT__PRIM_QUAD ? 2 : 3;
        l->li = li;
        l->dpick = pick;
        return;
    }
    l->shadow = pt__light_prim_sample(s, p, v->o, l->du1, l->du2, &l->ls, b->sph) &&
                pt__lane_picked(b, &l->ls, pick, li, &l->li) &&
                pt__nee_prepare(s, b->cfg, v, &l->ls, l->li, b->tri, &l->nr, &l->st);
    v->sph_prim = l->ls.sph_prim;
    v->sph_S = l->ls.sph_S;
}
/* Stage 2's light sample at lane l's vertex (the numbers u0, u1, u2 of pt__lights_sample_all) and
   its shadow ray. Where the light tree picks (b->picks), the pick is left to stage 2t (l->defer =
   5; pt__batch_picks), which makes the batch's picks several at a time. Where the light picked is
   a quad, the rest is left to stage 2c (l->defer = 2; pt__batch_area_lights), which makes the
   batch's area samples of quads 8 at a time and leaves those to be sampled by solid angle
   (pt__sphrect_wanted) to stage 2b (pt__batch_lights), which sets up their spherical rectangles 4
   at a time; a sphere's to stage 2s (l->defer = 3; pt__batch_sphere_lights), 8 cones at a time;
   the environment's to stage 2e (l->defer = 4; pt__batch_env_lights), 8 at a time. b->area and
   b->env8 are 0 without AVX2: then it is all done here. With an environment a shaped light is
   picked with pt__lights_sample_all's u0 rescaled, and its density carries the lights' share
   (pt__lane_picked). Either way each path does what pt__lights_sample_all and pt__nee_prepare do. */
static PT__HOT void pt__lane_light(const pt__batch_ctx *b, pt__lane *l, float u0, float u1, float u2)
{
    const pt_scene *s = b->s;
    const pt__settings *cfg = b->cfg;
    pt__vertex *v = &l->v;
    uint32_t li = 0;  /* set by pt__lights_pick (gcc -Og cannot see it) */
    float pick = 0.0f;
    l->ls.sph_prim = NULL;
    l->ls.sph_S = 0.0;
    l->du1 = u1;
    l->du2 = u2;
    if (b->env8 && u0 < cfg->env_pick) {
        l->defer = 4;
        return;
    }
    if (!b->area || (PT__UNLIKELY(cfg->env_pick > 0.0f) && u0 < cfg->env_pick)) {
        l->shadow = pt__lights_sample_all(s, cfg, v->o, pt__receiver_normal(v), u0, u1, u2, &l->ls, &l->li) &&
                    pt__nee_prepare(s, cfg, v, &l->ls, l->li, b->tri, &l->nr, &l->st);
    } else {
        if (PT__UNLIKELY(cfg->env_pick > 0.0f)) u0 = pt__minf((u0 - cfg->env_pick) / cfg->lights_share, 0.99999994f);
        if (b->picks) {
            l->defer = 5;
            l->du0 = u0;
            return;
        }
        if (pt__lane_pick(b, v, u0, &li, &pick)) {
            pt__lane_light_picked(b, l, li, pick);
            return;
        }
        l->shadow = 0;
    }
    v->sph_prim = l->ls.sph_prim;
    v->sph_S = l->ls.sph_S;
}
/* Stage 2t: the light tree's picks stage 2 left (pick: n lanes), PT__TREE_SLOTS side by side
   (pt__tree_picks_avx2), then the rest of each lane's light sample (pt__lane_light_picked), whose
   quads and spheres are appended to area (*narea) and sph (*nsph) for stages 2c and 2s. */
static void pt__batch_picks(const pt__batch_ctx *b, pt__lane *lanes, const int *pick, int n, int *area, int *narea,
                            int *sph, int *nsph)
{
#ifdef PT__WIDE
    pt__tree_query q[PT__BATCH];
    int i, j, m;
    for (i = 0; i < n; i += m) {
        m = n - i < PT__BATCH ? n - i : PT__BATCH;
        for (j = 0; j < m; ++j) {
            const pt__vertex *v = &lanes[pick[i + j]].v;
            q[j].p = v->o;
            q[j].nr = pt__receiver_normal(v);
            q[j].u = lanes[pick[i + j]].du0;
        }
        if (b->s->simd >= PT_SIMD_AVX512) pt__tree_picks_avx512(b->s, q, m);
        else pt__tree_picks_avx2(b->s, q, m);
        for (j = 0; j < m; ++j) {
            pt__lane *l = &lanes[pick[i + j]];
            l->defer = 0;
            if (q[j].ok) {
                pt__lane_light_picked(b, l, q[j].light, q[j].pmf);
                if (l->defer == 3) sph[(*nsph)++] = pick[i + j];
                else if (l->defer) area[(*narea)++] = pick[i + j];
                continue;
            }
            l->shadow = 0;
            l->v.sph_prim = NULL; /* (l->ls's, as pt__lane_light leaves it) */
            l->v.sph_S = 0.0;
        }
    }
#else
    (void)b; (void)lanes; (void)pick; (void)n; (void)area; (void)narea; (void)sph; (void)nsph; /* (b->picks is 0) */
#endif
}
/* Stage 2b for lane l, whose quad p's spherical rectangle was set up (ok; then q, S: its point and
   solid angle): the rest of pt__planar_light_sample, the pick, and the shadow ray. */
static PT__HOT void pt__lane_light_finish(const pt__batch_ctx *b, pt__lane *l, const pt__prim *p, int ok, pt_vec3 q, double S)
{
    const pt_scene *s = b->s;
    pt__vertex *v = &l->v;
    l->defer = 0;
    l->ls.sph_prim = p;
    l->ls.sph_S = ok ? S : 0.0;
    if (!ok) {
        q = pt__planar_point(p, l->du1, l->du2);
        S = 0.0;
    }
    l->shadow = pt__planar_light_at(p, s->lights[p->light].area, v->o, q, S, &l->ls) &&
                pt__lane_picked(b, &l->ls, l->dpick, l->li, &l->li) &&
                pt__nee_prepare(s, b->cfg, v, &l->ls, l->li, b->tri, &l->nr, &l->st);
    v->sph_prim = l->ls.sph_prim;
    v->sph_S = l->ls.sph_S;
}
/* Stage 2b: the light samples stage 2 left (defer: n lanes), 4 at a time (pt__sphrect_sample4; a
   last group of fewer repeats its last lane). */
static void pt__batch_lights(const pt__batch_ctx *b, pt__lane *lanes, const int *defer, int n)
{
#ifdef PT__WIDE
    int i, j;
    for (i = 0; i < n; i += 4) {
        const pt__prim *p[4];
        pt_vec3 o[4], q[4];
        float u1[4], u2[4];
        double S[4];
        int ok[4];
        for (j = 0; j < 4; ++j) {
            const pt__lane *l = &lanes[defer[i + j < n ? i + j : n - 1]];
            p[j] = &b->s->prims[b->s->lights[l->li].prim];
            o[j] = l->v.o;
            u1[j] = l->du1;
            u2[j] = l->du2;
        }
        pt__sphrect_sample4(p, o, u1, u2, ok, q, S);
        for (j = 0; j < 4 && i + j < n; ++j) pt__lane_light_finish(b, &lanes[defer[i + j]], p[j], ok[j], q[j], S[j]);
    }
#else
    (void)b; (void)lanes; (void)defer; (void)n; /* (b->area is 0) */
#endif
}

#ifdef PT__WIDE
/* Stage 2c's numbers. A light's (pt__qa_light_of): the quad's corner p0, edges e1, e2 and normal
   n, its area, the shadow ray offset's magnitude (pt__prim_magnitude, made valid as
   pt__offset_origin does) and its two-sidedness (1 or 0). A lane's, one row per quantity and a
   column per lane: in, the vertex's point o and the point's numbers u1, u2; out, the light point
   q, the unit direction, the distance, the density and the shadow ray's end (pt__light_target). */
enum { PT__QL_P0 = 0, PT__QL_E1 = 3, PT__QL_E2 = 6, PT__QL_N = 9, PT__QL_AREA = 12, PT__QL_MAG, PT__QL_TWO, PT__QL_SIZE };
enum { PT__QA_O = 0, PT__QA_U1 = 3, PT__QA_U2, PT__QA_IN };
enum { PT__QA_Q = 0, PT__QA_DIR = 3, PT__QA_DIST = 6, PT__QA_PDF, PT__QA_TARGET, PT__QA_OUT = PT__QA_TARGET + 3 };
typedef float pt__qa_row[PT__BATCH_LANES + 8];
typedef struct pt__qa_light { float v[PT__QL_SIZE]; } pt__qa_light;
static void pt__qa_light_of(const pt_scene *s, const pt__prim *p, pt__qa_light *r)
{
    const float mag = pt__prim_magnitude(p, p->n);
    r->v[PT__QL_P0] = p->p0.x; r->v[PT__QL_P0 + 1] = p->p0.y; r->v[PT__QL_P0 + 2] = p->p0.z;
    r->v[PT__QL_E1] = p->p1.x; r->v[PT__QL_E1 + 1] = p->p1.y; r->v[PT__QL_E1 + 2] = p->p1.z;
    r->v[PT__QL_E2] = p->p2.x; r->v[PT__QL_E2 + 1] = p->p2.y; r->v[PT__QL_E2 + 2] = p->p2.z;
    r->v[PT__QL_N] = p->n.x; r->v[PT__QL_N + 1] = p->n.y; r->v[PT__QL_N + 2] = p->n.z;
    r->v[PT__QL_AREA] = s->lights[p->light].area;
    r->v[PT__QL_MAG] = !(mag >= 0.0f) || !pt__isfinite(mag) ? 1.0f : mag;
    r->v[PT__QL_TWO] = s->mats[p->material].two_sided ? 1.0f : 0.0f;
}
/* Quantity k of the 8 lanes' lights L[0..7] (all L[0] where same). */
PT__TARGET_AVX2 static inline __m256 pt__qa_lights8(const pt__qa_light *const *L, int k, int same)
{
    if (same) return _mm256_set1_ps(L[0]->v[k]);
    return _mm256_setr_ps(L[0]->v[k], L[1]->v[k], L[2]->v[k], L[3]->v[k], L[4]->v[k], L[5]->v[k], L[6]->v[k], L[7]->v[k]);
}
PT__TARGET_AVX2 static inline __m256 pt__v8dot(const __m256 *a, const __m256 *b)
{
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(a[0], b[0]), _mm256_mul_ps(a[1], b[1])), _mm256_mul_ps(a[2], b[2]));
}
/* pt__offset_origin(p, n, w, magnitude) for 8 lanes: the magnitude made valid, the normal turned
   to w's side, and each coordinate moved as the SSE2 code moves it (ulp steps as integer adds). */
PT__TARGET_AVX2 static inline void pt__offset_origin8(const __m256 *p, const __m256 *n, const __m256 *w, __m256 magnitude,
                                                      __m256 *out)
{
    const __m256 zero = _mm256_setzero_ps(), signbit = _mm256_set1_ps(-0.0f);
    const __m256 flip = _mm256_and_ps(signbit, _mm256_cmp_ps(pt__v8dot(n, w), zero, _CMP_LT_OQ));
    const __m256 valid = _mm256_and_ps(_mm256_cmp_ps(magnitude, zero, _CMP_GE_OQ),
                                       _mm256_cmp_ps(magnitude, _mm256_castsi256_ps(_mm256_set1_epi32(0x7f800000)), _CMP_LT_OQ));
    __m256 m = _mm256_max_ps(_mm256_andnot_ps(signbit, p[0]), _mm256_max_ps(_mm256_andnot_ps(signbit, p[1]), _mm256_andnot_ps(signbit, p[2])));
    int k;
    m = _mm256_max_ps(_mm256_blendv_ps(_mm256_set1_ps(1.0f), magnitude, valid), m);
    m = _mm256_blendv_ps(_mm256_set1_ps(FLT_MIN), m, _mm256_cmp_ps(m, zero, _CMP_GT_OQ));
    for (k = 0; k < 3; ++k) {
        const __m256 nk = _mm256_xor_ps(n[k], flip);
        const __m256i neg = _mm256_castps_si256(_mm256_cmp_ps(p[k], zero, _CMP_LT_OQ));
        __m256i of = _mm256_cvttps_epi32(_mm256_mul_ps(_mm256_set1_ps(256.0f), nk));
        __m256 p_i, p_f, near;
        of = _mm256_sub_epi32(_mm256_xor_si256(of, neg), neg); /* -of_i where p < 0 */
        p_i = _mm256_castsi256_ps(_mm256_add_epi32(_mm256_castps_si256(p[k]), of));
        p_f = _mm256_add_ps(p[k], _mm256_mul_ps(_mm256_mul_ps(m, _mm256_set1_ps(1.0f / 65536.0f)), nk));
        near = _mm256_cmp_ps(_mm256_andnot_ps(signbit, p[k]), _mm256_mul_ps(m, _mm256_set1_ps(1.0f / 32.0f)), _CMP_LT_OQ);
        out[k] = _mm256_blendv_ps(p_i, p_f, near);
    }
}
/* Area samples of quads for the 8 lanes from column i (their lights L; same: all L[0]), each lane
   doing the float operations of pt__planar_faces, pt__sphrect_wanted (sph: solid-angle sampling
   allowed), pt__planar_point, pt__planar_light_at (the density of pt__planar_density) and
   pt__light_target (pt__offset_origin with the SSE2 code's integer steps) in the scalar code's
   order, without FMA, so the same bits. A lane whose quad faces away or goes to solid-angle
   sampling, whose point is at o, or whose cosine is 0 takes 1 for the square root's and the
   quotient's operand, so no lane raises an exception (FE_INVALID, FE_DIVBYZERO) that the scalar
   code would not. Returns the lanes' bits: facing (bit k), wanted (bit 8 + k), a point away from
   o (bit 16 + k). */
PT__TARGET_AVX2 static int pt__quad_area8(pt__qa_row *in, const pt__qa_light *const *L, int same, pt__qa_row *out, int i,
                                          int sph)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), signbit = _mm256_set1_ps(-0.0f);
    const __m256 u1 = _mm256_loadu_ps(in[PT__QA_U1] + i), u2 = _mm256_loadu_ps(in[PT__QA_U2] + i);
    __m256 o[3], p0[3], e1[3], e2[3], n[3], d[3], q[3], dir[3], w[3], t[3];
    __m256 faces, wanted = zero, live, dist2, dist, inv, cosl, cpos, pdf;
    int k;
    for (k = 0; k < 3; ++k) {
        o[k] = _mm256_loadu_ps(in[PT__QA_O + k] + i);
        p0[k] = pt__qa_lights8(L, PT__QL_P0 + k, same);
        e1[k] = pt__qa_lights8(L, PT__QL_E1 + k, same);
        e2[k] = pt__qa_lights8(L, PT__QL_E2 + k, same);
        n[k] = pt__qa_lights8(L, PT__QL_N + k, same);
        d[k] = _mm256_sub_ps(o[k], p0[k]);
    }
    { /* pt__planar_faces: n . (o - p0) != 0 for a two-sided quad, > 0 for a one-sided one */
        const __m256 side = pt__v8dot(n, d);
        faces = _mm256_blendv_ps(_mm256_cmp_ps(side, zero, _CMP_GT_OQ), _mm256_cmp_ps(side, zero, _CMP_NEQ_UQ),
                                 _mm256_cmp_ps(pt__qa_lights8(L, PT__QL_TWO, same), zero, _CMP_NEQ_UQ));
    }
    if (sph) { /* pt__sphrect_wanted */
        const __m256 half = _mm256_set1_ps(0.5f);
        __m256 cc[3];
        for (k = 0; k < 3; ++k)
            cc[k] = _mm256_sub_ps(_mm256_add_ps(_mm256_add_ps(p0[k], _mm256_mul_ps(e1[k], half)), _mm256_mul_ps(e2[k], half)),
                                  o[k]);
        wanted = _mm256_cmp_ps(_mm256_mul_ps(_mm256_set1_ps(0.25f), _mm256_add_ps(pt__v8dot(e1, e1), pt__v8dot(e2, e2))),
                               _mm256_mul_ps(_mm256_set1_ps((float)PT__SPHERICAL_FROM), pt__v8dot(cc, cc)), _CMP_GE_OQ);
    }
    /* pt__planar_point, pt__planar_light_at, pt__planar_density */
    for (k = 0; k < 3; ++k) {
        q[k] = _mm256_add_ps(_mm256_add_ps(p0[k], _mm256_mul_ps(e1[k], u1)), _mm256_mul_ps(e2[k], u2));
        d[k] = _mm256_sub_ps(q[k], o[k]);
    }
    dist2 = pt__v8dot(d, d);
    live = _mm256_and_ps(_mm256_andnot_ps(wanted, faces), _mm256_cmp_ps(dist2, zero, _CMP_GT_OQ));
    dist = _mm256_sqrt_ps(_mm256_blendv_ps(one, dist2, live));
    inv = _mm256_div_ps(one, dist);
    for (k = 0; k < 3; ++k) dir[k] = _mm256_mul_ps(d[k], inv);
    cosl = _mm256_andnot_ps(signbit, pt__v8dot(n, dir));
    cpos = _mm256_cmp_ps(cosl, zero, _CMP_GT_OQ);
    pdf = _mm256_div_ps(_mm256_mul_ps(dist, dist), _mm256_blendv_ps(one, _mm256_mul_ps(cosl, pt__qa_lights8(L, PT__QL_AREA, same)),
                                                                    _mm256_and_ps(cpos, live)));
    pdf = _mm256_and_ps(cpos, pdf);
    /* pt__light_target: pt__offset_origin(q, n, -dir, magnitude) */
    for (k = 0; k < 3; ++k) w[k] = _mm256_xor_ps(signbit, dir[k]);
    pt__offset_origin8(q, n, w, pt__qa_lights8(L, PT__QL_MAG, same), t);
    for (k = 0; k < 3; ++k) {
        _mm256_storeu_ps(out[PT__QA_TARGET + k] + i, t[k]);
        _mm256_storeu_ps(out[PT__QA_Q + k] + i, q[k]);
        _mm256_storeu_ps(out[PT__QA_DIR + k] + i, dir[k]);
    }
    _mm256_storeu_ps(out[PT__QA_DIST] + i, dist);
    _mm256_storeu_ps(out[PT__QA_PDF] + i, pdf);
    return _mm256_movemask_ps(faces) | _mm256_movemask_ps(wanted) << 8 | _mm256_movemask_ps(live) << 16;
}
/* Stage 2c for lane l, whose quad p faces its vertex and is sampled by area (bits: pt__quad_area8's
   for this lane; column j of out): the rest of pt__planar_light_sample, the pick, and
   pt__nee_prepare with the shadow ray's end made. */
static PT__HOT void pt__lane_area_finish(const pt__batch_ctx *b, pt__lane *l, const pt__prim *p, pt__qa_row *out, int j,
                                         int bits)
{
    pt__vertex *v = &l->v;
    pt_vec3 target;
    int ok = 0;
    if (b->sph) l->ls.sph_prim = p;
    if (bits & (1 << 16)) {
        l->ls.dir = pt_v3(out[PT__QA_DIR][j], out[PT__QA_DIR + 1][j], out[PT__QA_DIR + 2][j]);
        l->ls.pdf = out[PT__QA_PDF][j];
        l->ls.dist = out[PT__QA_DIST][j];
        l->ls.point = pt_v3(out[PT__QA_Q][j], out[PT__QA_Q + 1][j], out[PT__QA_Q + 2][j]);
        l->ls.normal = p->n;
        l->ls.rounded = 0;
        ok = l->ls.pdf > 0.0f && pt__isfinite(l->ls.pdf);
    }
    target = pt_v3(out[PT__QA_TARGET][j], out[PT__QA_TARGET + 1][j], out[PT__QA_TARGET + 2][j]);
    l->shadow = ok && pt__lane_picked(b, &l->ls, l->dpick, l->li, &l->li) &&
                pt__nee_prepare_to(b->s, b->cfg, v, &l->ls, l->li, b->tri, &l->nr, &l->st, &target);
    v->sph_prim = l->ls.sph_prim;
    v->sph_S = l->ls.sph_S;
}
/* Stage 2s's numbers, one row per quantity and a column per lane of a group of 8: in, the vertex's
   point o, the point's numbers u1, u2, the sphere's centre c, radius r and pt__prim_magnitude's
   m; out, the light sample's direction, point, normal, distance, density and the shadow ray's end. */
enum { PT__SS_O = 0, PT__SS_U1 = 3, PT__SS_U2, PT__SS_C, PT__SS_R = PT__SS_C + 3, PT__SS_MAG, PT__SS_IN = PT__SS_MAG + 3 };
enum { PT__SO_DIR = 0, PT__SO_POINT = 3, PT__SO_NORMAL = 6, PT__SO_TARGET = 9, PT__SO_DIST = 12, PT__SO_PDF, PT__SO_OUT };
/* pt__in_cone for the 8 lanes, in double as it is (two halves of 4): the lanes' bits. */
PT__TARGET_AVX2 static inline int pt__in_cone8(const __m256 *w, const __m256 *o, const __m256 *c, __m256 r)
{
    int h, bits = 0;
    for (h = 0; h < 2; ++h) {
        __m256d wd[3], cd[3], x, y, z, ww, dot, rd;
        int k;
        for (k = 0; k < 3; ++k) {
            wd[k] = _mm256_cvtps_pd(h ? _mm256_extractf128_ps(w[k], 1) : _mm256_castps256_ps128(w[k]));
            cd[k] = _mm256_sub_pd(_mm256_cvtps_pd(h ? _mm256_extractf128_ps(c[k], 1) : _mm256_castps256_ps128(c[k])),
                                  _mm256_cvtps_pd(h ? _mm256_extractf128_ps(o[k], 1) : _mm256_castps256_ps128(o[k])));
        }
        rd = _mm256_cvtps_pd(h ? _mm256_extractf128_ps(r, 1) : _mm256_castps256_ps128(r));
        x = _mm256_sub_pd(_mm256_mul_pd(wd[1], cd[2]), _mm256_mul_pd(wd[2], cd[1]));
        y = _mm256_sub_pd(_mm256_mul_pd(wd[2], cd[0]), _mm256_mul_pd(wd[0], cd[2]));
        z = _mm256_sub_pd(_mm256_mul_pd(wd[0], cd[1]), _mm256_mul_pd(wd[1], cd[0]));
        ww = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(wd[0], wd[0]), _mm256_mul_pd(wd[1], wd[1])), _mm256_mul_pd(wd[2], wd[2]));
        dot = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(wd[0], cd[0]), _mm256_mul_pd(wd[1], cd[1])), _mm256_mul_pd(wd[2], cd[2]));
        x = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x, x), _mm256_mul_pd(y, y)), _mm256_mul_pd(z, z));
        bits |= _mm256_movemask_pd(_mm256_and_pd(_mm256_cmp_pd(dot, _mm256_setzero_pd(), _CMP_GT_OQ),
                                                 _mm256_cmp_pd(x, _mm256_mul_pd(_mm256_mul_pd(rd, rd), ww), _CMP_LE_OQ))) << (4 * h);
    }
    return bits;
}
/* Cone samples of sphere lights seen from outside for 8 lanes, each lane doing the float operations
   of pt__sphere_light_sample (pt__cone_one_minus_cos, pt__sincos_turn, pt__onb, pt_normalize,
   pt__in_cone, the near intersection, the normal) and of pt__light_target in the scalar code's
   order, without FMA, so the same bits. A lane whose point is inside or on its sphere, whose
   direction rounded out of the cone (the nudge) or whose sample the scalar code rejects is left
   out of the returned bits, for the scalar code to redo; such lanes take 1 as the operand of the
   square roots and divisions, so no lane raises an exception the scalar code would not. */
PT__TARGET_AVX2 static int pt__sphere_sample8(float (*in)[8], float (*out)[8])
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), signbit = _mm256_set1_ps(-0.0f);
    const __m256 r = _mm256_loadu_ps(in[PT__SS_R]), u1 = _mm256_loadu_ps(in[PT__SS_U1]);
    __m256 o[3], c[3], wc[3], n[3], l[3], w[3], q[3], pn[3], nrm[3], t[3], mg = zero;
    __m256 d2, rr, live, d, s2, x, omc, uc, cos_t, sin2_t, sin_t, sn, cs, inv, l2, ok, pdf, dist;
    int k;
    for (k = 0; k < 3; ++k) {
        o[k] = _mm256_loadu_ps(in[PT__SS_O + k]);
        c[k] = _mm256_loadu_ps(in[PT__SS_C + k]);
        wc[k] = _mm256_sub_ps(c[k], o[k]);
    }
    /* outside (not pt__sphere_inside), the cone's 1 - cos(theta_max) (pt__cone_one_minus_cos) */
    d2 = pt__v8dot(wc, wc);
    rr = _mm256_mul_ps(r, r);
    live = _mm256_cmp_ps(d2, _mm256_mul_ps(rr, _mm256_set1_ps(1.0f + 1e-5f)), _CMP_GT_OQ);
    d2 = _mm256_blendv_ps(one, d2, live);
    d = _mm256_sqrt_ps(d2);
    s2 = _mm256_div_ps(rr, d2);
    x = _mm256_sub_ps(one, s2);
    omc = _mm256_div_ps(s2, _mm256_add_ps(one, _mm256_sqrt_ps(_mm256_and_ps(_mm256_cmp_ps(x, zero, _CMP_GT_OQ), x))));
    live = _mm256_and_ps(live, _mm256_cmp_ps(omc, zero, _CMP_GT_OQ));
    /* the direction: uniform in the cone about wc / d */
    uc = _mm256_mul_ps(u1, omc);
    cos_t = _mm256_sub_ps(one, uc);
    sin2_t = _mm256_mul_ps(uc, _mm256_sub_ps(_mm256_set1_ps(2.0f), uc));
    sin_t = _mm256_sqrt_ps(_mm256_and_ps(_mm256_cmp_ps(sin2_t, zero, _CMP_GT_OQ), sin2_t));
    pt__sincos_turn8(_mm256_loadu_ps(in[PT__SS_U2]), &sn, &cs);
    inv = _mm256_div_ps(one, d);
    for (k = 0; k < 3; ++k) n[k] = _mm256_mul_ps(wc[k], inv);
    l[0] = _mm256_mul_ps(sin_t, cs);
    l[1] = _mm256_mul_ps(sin_t, sn);
    l[2] = cos_t;
    pt__onb_to_world8(n, l, w);
    l2 = pt__v8dot(w, w);
    ok = _mm256_cmp_ps(l2, zero, _CMP_GT_OQ);
    live = _mm256_and_ps(live, ok);
    inv = _mm256_div_ps(one, _mm256_sqrt_ps(_mm256_blendv_ps(one, l2, ok)));
    for (k = 0; k < 3; ++k) w[k] = _mm256_mul_ps(w[k], inv);
    /* the density, and the distance to the near intersection d (cos - sqrt(s^2 - sin^2)) */
    pdf = _mm256_div_ps(one, _mm256_mul_ps(_mm256_set1_ps(2.0f * PT__PI), _mm256_blendv_ps(one, omc, live)));
    x = _mm256_sub_ps(s2, sin2_t);
    dist = _mm256_mul_ps(d, _mm256_sub_ps(cos_t, _mm256_sqrt_ps(_mm256_and_ps(_mm256_cmp_ps(x, zero, _CMP_GT_OQ), x))));
    dist = _mm256_and_ps(_mm256_cmp_ps(dist, zero, _CMP_GT_OQ), dist);
    live = _mm256_and_ps(live, _mm256_cmp_ps(dist, zero, _CMP_GT_OQ));
    live = _mm256_and_ps(live, _mm256_cmp_ps(pdf, _mm256_castsi256_ps(_mm256_set1_epi32(0x7f800000)), _CMP_LT_OQ));
    /* the point, its normal (pt_normalize: 0 for a point at c) and the shadow ray's end */
    for (k = 0; k < 3; ++k) {
        q[k] = _mm256_add_ps(o[k], _mm256_mul_ps(w[k], dist));
        pn[k] = _mm256_sub_ps(q[k], c[k]);
    }
    l2 = pt__v8dot(pn, pn);
    ok = _mm256_cmp_ps(l2, zero, _CMP_GT_OQ);
    inv = _mm256_div_ps(one, _mm256_sqrt_ps(_mm256_blendv_ps(one, l2, ok)));
    for (k = 0; k < 3; ++k) {
        nrm[k] = _mm256_and_ps(ok, _mm256_mul_ps(pn[k], inv));
        mg = _mm256_add_ps(mg, _mm256_mul_ps(_mm256_andnot_ps(signbit, nrm[k]), _mm256_loadu_ps(in[PT__SS_MAG + k])));
        l[k] = _mm256_xor_ps(signbit, w[k]);
    }
    pt__offset_origin8(q, nrm, l, mg, t);
    for (k = 0; k < 3; ++k) {
        _mm256_storeu_ps(out[PT__SO_DIR + k], w[k]);
        _mm256_storeu_ps(out[PT__SO_POINT + k], q[k]);
        _mm256_storeu_ps(out[PT__SO_NORMAL + k], nrm[k]);
        _mm256_storeu_ps(out[PT__SO_TARGET + k], t[k]);
    }
    _mm256_storeu_ps(out[PT__SO_DIST], dist);
    _mm256_storeu_ps(out[PT__SO_PDF], pdf);
    return _mm256_movemask_ps(live) & pt__in_cone8(w, o, c, r);
}
#endif
/* Stage 2c: the quads' light samples stage 2 left (area: n lanes), 8 at a time (pt__quad_area8;
   the last group's unused lanes copy the first): those facing away end there, those to be sampled
   by solid angle are appended to defer (stage 2b; returns their new count), the rest finish. */
static int pt__batch_area_lights(const pt__batch_ctx *b, pt__lane *lanes, const int *area, int n, int *defer, int ndefer)
{
#ifdef PT__WIDE
    const pt_scene *s = b->s;
    pt__qa_row in[PT__QA_IN], out[PT__QA_OUT];
    const pt__prim *prim[PT__BATCH_LANES + 8];
    pt__qa_light rec[8], last = {{0.0f}}; /* (set before its first use; gcc -Og cannot see it) */
    const pt__qa_light *L[8];
    const pt__prim *lastp = NULL;
    int i, k;
    for (i = 0; i < n; ++i) {
        const pt__lane *l = &lanes[area[i]];
        prim[i] = &s->prims[s->lights[l->li].prim];
        in[PT__QA_O][i] = l->v.o.x;
        in[PT__QA_O + 1][i] = l->v.o.y;
        in[PT__QA_O + 2][i] = l->v.o.z;
        in[PT__QA_U1][i] = l->du1;
        in[PT__QA_U2][i] = l->du2;
    }
    for (i = n; i % 8; ++i) {
        prim[i] = prim[0];
        for (k = 0; k < PT__QA_IN; ++k) in[k][i] = in[k][0];
    }
    for (i = 0; i < n; i += 8) {
        int same = 1, bits;
        for (k = 1; k < 8; ++k) same &= prim[i + k] == prim[i];
        if (same) { /* (the common case: one light for all 8, its numbers kept from the last group) */
            if (prim[i] != lastp) pt__qa_light_of(s, lastp = prim[i], &last);
            L[0] = &last;
        } else {
            for (k = 0; k < 8; ++k) {
                pt__qa_light_of(s, prim[i + k], &rec[k]);
                L[k] = &rec[k];
            }
        }
        bits = pt__quad_area8(in, L, same, out, i, b->sph);
        for (k = 0; k < 8 && i + k < n; ++k) {
            pt__lane *l = &lanes[area[i + k]];
            if (!((bits >> k) & 1)) { /* facing away: no sample (pt__planar_faces) */
                l->defer = 0;
                l->shadow = 0;
                l->v.sph_prim = NULL;
                l->v.sph_S = 0.0;
            } else if ((bits >> (8 + k)) & 1) { /* by solid angle (pt__sphrect_wanted) */
                l->defer = 1;
                defer[ndefer++] = area[i + k];
            } else {
                l->defer = 0;
                pt__lane_area_finish(b, l, prim[i + k], out, i + k, bits >> k);
            }
        }
    }
#else
    (void)b; (void)lanes; (void)area; (void)n; (void)defer; /* (b->area is 0) */
#endif
    return ndefer;
}

/* Stage 2s: the sphere lights' samples stage 2 left (sph: n lanes), 8 at a time
   (pt__sphere_sample8; a last group's unused lanes copy its first); a lane the vector code left
   out does what stage 2 would have done. Then the pick and the shadow ray (pt__nee_prepare_to
   with the shadow ray's end made). */
static void pt__batch_sphere_lights(const pt__batch_ctx *b, pt__lane *lanes, const int *sph, int n)
{
#ifdef PT__WIDE
    const pt_scene *s = b->s;
    float in[PT__SS_IN][8], out[PT__SO_OUT][8];
    int i, j, bits;
    for (i = 0; i < n; i += 8) {
        for (j = 0; j < 8; ++j) {
            const pt__lane *l = &lanes[sph[i + j < n ? i + j : i]];
            const pt__prim *p = &s->prims[s->lights[l->li].prim];
            in[PT__SS_O][j] = l->v.o.x;
            in[PT__SS_O + 1][j] = l->v.o.y;
            in[PT__SS_O + 2][j] = l->v.o.z;
            in[PT__SS_U1][j] = l->du1;
            in[PT__SS_U2][j] = l->du2;
            in[PT__SS_C][j] = p->p0.x;
            in[PT__SS_C + 1][j] = p->p0.y;
            in[PT__SS_C + 2][j] = p->p0.z;
            in[PT__SS_R][j] = p->p1.x;
            in[PT__SS_MAG][j] = p->mag.x;
            in[PT__SS_MAG + 1][j] = p->mag.y;
            in[PT__SS_MAG + 2][j] = p->mag.z;
        }
        bits = pt__sphere_sample8(in, out);
        for (j = 0; j < 8 && i + j < n; ++j) {
            pt__lane *l = &lanes[sph[i + j]];
            pt__vertex *v = &l->v;
            const pt__prim *p = &s->prims[s->lights[l->li].prim];
            l->defer = 0;
            if ((bits >> j) & 1) {
                pt_vec3 target = pt_v3(out[PT__SO_TARGET][j], out[PT__SO_TARGET + 1][j], out[PT__SO_TARGET + 2][j]);
                l->ls.dir = pt_v3(out[PT__SO_DIR][j], out[PT__SO_DIR + 1][j], out[PT__SO_DIR + 2][j]);
                l->ls.point = pt_v3(out[PT__SO_POINT][j], out[PT__SO_POINT + 1][j], out[PT__SO_POINT + 2][j]);
                l->ls.normal = pt_v3(out[PT__SO_NORMAL][j], out[PT__SO_NORMAL + 1][j], out[PT__SO_NORMAL + 2][j]);
                l->ls.dist = out[PT__SO_DIST][j];
                l->ls.pdf = out[PT__SO_PDF][j];
                l->ls.rounded = 0;
                l->shadow = pt__lane_picked(b, &l->ls, l->dpick, l->li, &l->li) &&
                            pt__nee_prepare_to(s, b->cfg, v, &l->ls, l->li, b->tri, &l->nr, &l->st, &target);
            } else {
                l->shadow = pt__light_prim_sample(s, p, v->o, l->du1, l->du2, &l->ls, b->sph) &&
                            pt__lane_picked(b, &l->ls, l->dpick, l->li, &l->li) &&
                            pt__nee_prepare(s, b->cfg, v, &l->ls, l->li, b->tri, &l->nr, &l->st);
            }
            v->sph_prim = l->ls.sph_prim;
            v->sph_S = l->ls.sph_S;
        }
    }
#else
    (void)b; (void)lanes; (void)sph; (void)n; /* (b->area is 0) */
#endif
}

/* Stage 1e: the environment map along the rays of the live paths (live: n lanes) that left the
   scene, 8 at a time (pt__env_eval8; a last group's unused lanes copy its first), for stage 2 to
   weigh (pt__env_escape_map). A lane the vector code left out, or one whose path gathers nothing
   there (light sampling only, after a non-delta vertex), is left to stage 2 (l->esc = 0). */
static void pt__batch_escapes(const pt__batch_ctx *b, pt__lane *lanes, const int *live, int n)
{
#ifdef PT__WIDE
    const pt__settings *cfg = b->cfg;
    const int light_only = cfg->strategy == PT_STRATEGY_LIGHT;
    float in[3][8], out[PT__EO_OUT][8];
    int idx[8], i, j, m = 0, bits;
    for (i = 0; i <= n; ++i) {
        if (i < n) {
            pt__lane *l = &lanes[live[i]];
            if (l->found) continue;
            l->esc = 0;
            if (light_only && !l->prev_delta) continue;
            idx[m++] = live[i];
            if (m < 8) continue;
        }
        if (!m) break;
        for (j = 0; j < 8; ++j) {
            const pt__lane *l = &lanes[idx[j < m ? j : 0]];
            in[0][j] = l->ray.dir.x;
            in[1][j] = l->ray.dir.y;
            in[2][j] = l->ray.dir.z;
        }
        bits = pt__env_eval8(cfg->env, in, out);
        for (j = 0; j < m; ++j) {
            pt__lane *l = &lanes[idx[j]];
            l->esc = (bits >> j) & 1;
            l->esc_L = pt_v3(out[PT__EO_L][j], out[PT__EO_L + 1][j], out[PT__EO_L + 2][j]);
            l->esc_pm = out[PT__EO_PM][j];
        }
        m = 0;
    }
#else
    (void)b; (void)lanes; (void)live; (void)n; /* (b->env8 is 0) */
#endif
}

/* Stage 2e: the environment's light samples stage 2 left (env: n lanes), 8 at a time
   (pt__env_sample8; a last group's unused lanes copy its first); a lane the vector code left out
   does what stage 2 would have done. Then the pick and the shadow ray (pt__nee_prepare). */
static void pt__batch_env_lights(const pt__batch_ctx *b, pt__lane *lanes, const int *env, int n)
{
#ifdef PT__WIDE
    const pt__settings *cfg = b->cfg;
    float u1[8], u2[8], out[PT__EO_OUT][8];
    int i, j, bits;
    for (i = 0; i < n; i += 8) {
        for (j = 0; j < 8; ++j) {
            const pt__lane *l = &lanes[env[i + j < n ? i + j : i]];
            u1[j] = l->du1;
            u2[j] = l->du2;
        }
        bits = pt__env_sample8(cfg->env, cfg->env_uniform, u1, u2, out);
        for (j = 0; j < 8 && i + j < n; ++j) {
            pt__lane *l = &lanes[env[i + j]];
            pt__vertex *v = &l->v;
            l->defer = 0;
            if ((bits >> j) & 1) {
                l->ls.dir = pt_v3(out[PT__EO_DIR][j], out[PT__EO_DIR + 1][j], out[PT__EO_DIR + 2][j]);
                l->ls.pdf = out[PT__EO_PM][j];
                l->shadow = l->ls.pdf > 0.0f && pt__isfinite(l->ls.pdf) &&
                            pt__env_light_finish(cfg, pt_v3(out[PT__EO_L][j], out[PT__EO_L + 1][j], out[PT__EO_L + 2][j]),
                                                 &l->ls, &l->li);
            } else {
                l->shadow = pt__env_light_sample(cfg, l->du1, l->du2, &l->ls, &l->li);
            }
            l->shadow = l->shadow && pt__nee_prepare(b->s, cfg, v, &l->ls, l->li, b->tri, &l->nr, &l->st);
            v->sph_prim = l->ls.sph_prim;
            v->sph_S = l->ls.sph_S;
        }
    }
#else
    (void)b; (void)lanes; (void)env; (void)n; /* (b->env8 is 0) */
#endif
}

/* Stage 2 for one path whose closest hit is known: returns 0 if the path ends here. */
static PT__HOT int pt__lane_shade(const pt__batch_ctx *b, pt__lane *l, const int copies)
{
    const pt_scene *s = b->s;
    const pt__settings *cfg = b->cfg;
    const pt__prim *prim;
    const pt__material *m;
    pt__vertex *v = &l->v;
    l->shadow = l->dshadow = l->ddefer = 0;
    l->defer = 0;
    if (!l->found) {
        if (PT__UNLIKELY(cfg->env_on)) {
            pt_color e = b->env8 && l->esc ? pt__env_escape_map(cfg, l->esc_L, l->esc_pm, l->beta, l->prev_delta, l->prev_pdf)
                                           : pt__env_escape(cfg, l->ray.dir, l->beta, l->prev_delta, l->prev_pdf);
            pt__lane_add(l, e, copies);
            if (PT__UNLIKELY(l->recs != NULL) && l->recs->last >= 0 && b->nee) l->recs->e[l->recs->last] = e;
        } else {
            pt__lane_add(l, pt_mul(l->beta, cfg->background), copies);
        }
        return 0;
    }
    prim = &s->prims[l->pi];
    m = &s->mats[prim->material];
    pt__fill_hit(s, prim, l->ray, l->t, l->bary, &l->h);
    if (m->emits && (m->two_sided || l->h.front_face)) {
        float w = l->prev_delta ? 1.0f
                                : pt__emission_weight(s, cfg, prim, l->prev_pdf, l->prev_p, l->prev_n, l->ray.dir, l->t, v);
        if (w > 0.0f) {
            pt_color e = pt_scale(pt_mul(l->beta, m->emission), w);
            pt__lane_add(l, e, copies);
            /* training with next-event estimation: direct light is NEE's (pt__trace_from) */
            if (PT__UNLIKELY(l->recs != NULL) && l->recs->last >= 0 && b->nee) l->recs->e[l->recs->last] = e;
        }
    }
    if (PT__UNLIKELY(l->recs != NULL)) l->recs->last = -1;
    if (l->depth >= cfg->max_depth || !m->scatters) return 0;
    l->beta_in = l->beta;
    pt__vertex_at(s, cfg, v, prim, m, &l->h, l->ray.dir, l->bary);
    if (m->delta && b->nee && !PT__SKIP(cfg, PT_SKIP_DELTA_VERTEX)) { /* (the general path of pt__trace_from) */
        pt__light_sample ls;
        uint32_t li;
        float u0 = pt__draw1_if(&l->smp, PT__SET_BOUNCE(l->depth, PT__SLOT_LIGHT_PICK), b->pick), u1, u2;
        pt__draw2(&l->smp, PT__SET_BOUNCE(l->depth, PT__SLOT_LIGHT_POINT), &u1, &u2);
        if (pt__lights_sample_all(s, cfg, v->o, pt_v3(0.0f, 0.0f, 0.0f), u0, u1, u2, &ls, &li))
            pt__lane_add(l, pt__nee_contribution(s, cfg, v, &ls, li, l->beta, b->tri, &l->st), copies);
    }
    if (!m->delta) {
        v->surface = l->surfaces++;
        v->has_guide = 0;
        v->cshare = 0.0f;
        v->rr_e = 0.0f;
        if (cfg->guide) {
            pt_shading_point sp;
            sp.position = pt__to_world(s, v->p);
            sp.normal = v->ns;
            sp.wo = v->wo;
            sp.material = prim->material;
            sp.depth = l->depth;
            v->g = cfg->guide_weight;
            v->has_guide = cfg->guide(cfg->guide_user, &sp, &v->guide) ? 1 : 0;
        } else if (cfg->learned) {
            pt__vertex_learned(cfg, v, &l->st);
        }
        if (b->nee) {
            float u0 = pt__draw1_if(&l->smp, PT__SET_BOUNCE(l->depth, PT__SLOT_LIGHT_PICK), b->pick), u1, u2;
            pt__draw2(&l->smp, PT__SET_BOUNCE(l->depth, PT__SLOT_LIGHT_POINT), &u1, &u2);
            pt__lane_light(b, l, u0, u1, u2);
        }
        /* the delta lights (pt__trace_from's order: after the light sample's draws) */
        l->ddefer = b->dvec;
        if (PT__UNLIKELY(s->dlight_count != 0) && !b->dvec)
            l->dshadow = pt__delta_prepare(s, cfg, v, l->depth, &l->smp, b->tri, &l->dnr, &l->dLi, &l->dpick_delta, &l->st,
                                           NULL, NULL);
    }
    return 1;
}

#ifdef PT__WIDE
/* Inputs of pt__delta_weight8, one row of 8 lanes each: the vertices' p and ng, and sg (1, or 0
   where the material transmits). */
enum { PT__DW_P = 0, PT__DW_N = 3, PT__DW_SG = 6, PT__DW_IN = 7 };
/* pt__delta_weight of light l at 8 vertices at a time with AVX2, each lane doing the scalar
   code's float operations in its order (no FMA), so the same bits, into w and fall; a lane whose
   value the scalar code does not compute (it returns 0 first) is computed on safe operands (no
   0/0, x/0 or 0 x inf to trap on) and masked. Returns the lanes (bits) of a spot whose
   shortcuts could not decide the falloff (it needs atan2f): their w and fall are the scalar
   code's to fill. */
PT__TARGET_AVX2 static int pt__delta_weight8(const pt__dlight *l, float (*in)[8], float *w, float *fall)
{
    const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f), sign = _mm256_set1_ps(-0.0f);
    const __m256 nx = _mm256_loadu_ps(in[PT__DW_N]), ny = _mm256_loadu_ps(in[PT__DW_N + 1]);
    const __m256 nz = _mm256_loadu_ps(in[PT__DW_N + 2]), sg = _mm256_loadu_ps(in[PT__DW_SG]);
    const __m256 mean = _mm256_set1_ps(l->mean), transmits = _mm256_cmp_ps(sg, zero, _CMP_EQ_OQ);
    __m256 dx, dy, dz, d2, ok, inv, c, i = mean, f = one;
    int undecided = 0;
    if (l->desc.type == PT_LIGHT_DIRECTIONAL) { /* i max(0, c) + (1 - sg) i max(0, -c), c = -(ng . axis) */
        c = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, _mm256_set1_ps(l->axis.x)), _mm256_mul_ps(ny, _mm256_set1_ps(l->axis.y))),
                          _mm256_mul_ps(nz, _mm256_set1_ps(l->axis.z)));
        c = _mm256_xor_ps(sign, c);
        _mm256_storeu_ps(w, _mm256_add_ps(_mm256_mul_ps(mean, _mm256_max_ps(zero, c)),
                                          _mm256_mul_ps(_mm256_mul_ps(_mm256_sub_ps(one, sg), mean),
                                                        _mm256_max_ps(zero, _mm256_xor_ps(sign, c)))));
        _mm256_storeu_ps(fall, one);
        return 0;
    }
    dx = _mm256_sub_ps(_mm256_set1_ps(l->pos.x), _mm256_loadu_ps(in[PT__DW_P]));
    dy = _mm256_sub_ps(_mm256_set1_ps(l->pos.y), _mm256_loadu_ps(in[PT__DW_P + 1]));
    dz = _mm256_sub_ps(_mm256_set1_ps(l->pos.z), _mm256_loadu_ps(in[PT__DW_P + 2]));
    d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)), _mm256_mul_ps(dz, dz));
    ok = _mm256_cmp_ps(d2, zero, _CMP_GT_OQ);
    d2 = _mm256_blendv_ps(one, d2, ok);
    inv = _mm256_div_ps(one, _mm256_sqrt_ps(d2));
    c = _mm256_mul_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, dx), _mm256_mul_ps(ny, dy)), _mm256_mul_ps(nz, dz)), inv);
    c = _mm256_blendv_ps(c, _mm256_andnot_ps(sign, c), transmits); /* (|c| where the vertex transmits) */
    ok = _mm256_and_ps(ok, _mm256_cmp_ps(c, zero, _CMP_GT_OQ));
    if (l->desc.type == PT_LIGHT_SPOT) { /* pt__spot_falloff toward -d / |d| */
        const __m256 ax = _mm256_set1_ps(l->axis.x), ay = _mm256_set1_ps(l->axis.y), az = _mm256_set1_ps(l->axis.z);
        const __m256 ninv = _mm256_xor_ps(sign, inv);
        const __m256 wx = _mm256_mul_ps(dx, ninv), wy = _mm256_mul_ps(dy, ninv), wz = _mm256_mul_ps(dz, ninv);
        const __m256 cx = _mm256_sub_ps(_mm256_mul_ps(ay, wz), _mm256_mul_ps(az, wy));
        const __m256 cy = _mm256_sub_ps(_mm256_mul_ps(az, wx), _mm256_mul_ps(ax, wz));
        const __m256 cz = _mm256_sub_ps(_mm256_mul_ps(ax, wy), _mm256_mul_ps(ay, wx));
        const __m256 sn = _mm256_sqrt_ps(
            _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(cx, cx), _mm256_mul_ps(cy, cy)), _mm256_mul_ps(cz, cz)));
        const __m256 cs = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, wx), _mm256_mul_ps(ay, wy)), _mm256_mul_ps(az, wz));
        const __m256 front = _mm256_and_ps(_mm256_cmp_ps(cs, zero, _CMP_GT_OQ),
                                           _mm256_and_ps(_mm256_cmp_ps(sn, zero, _CMP_GE_OQ),
                                                         _mm256_cmp_ps(sn, _mm256_set1_ps(FLT_MAX), _CMP_LE_OQ)));
        const __m256 inside = _mm256_and_ps(front, _mm256_cmp_ps(sn, _mm256_mul_ps(cs, _mm256_set1_ps(l->tan_in)), _CMP_LT_OQ));
        __m256 outside = zero;
        if (l->tan_out <= FLT_MAX) /* (else: no shortcut outside, and no 0 x inf) */
            outside = _mm256_or_ps(_mm256_and_ps(front, _mm256_cmp_ps(sn, _mm256_mul_ps(cs, _mm256_set1_ps(l->tan_out)),
                                                                      _CMP_GT_OQ)),
                                   _mm256_cmp_ps(cs, zero, _CMP_LE_OQ));
        f = _mm256_and_ps(inside, one);
        i = _mm256_mul_ps(mean, f);
        undecided = _mm256_movemask_ps(_mm256_andnot_ps(_mm256_or_ps(inside, outside), ok));
    }
    _mm256_storeu_ps(w, _mm256_and_ps(ok, _mm256_div_ps(_mm256_mul_ps(i, c), d2)));
    _mm256_storeu_ps(fall, f);
    return undecided;
}
/* Stage 2d: the delta lights' weights at the vertices stage 2 left to it (l->ddefer), 8 vertices
   a light at a time (pt__delta_weight8; a last group's unused lanes copy its first), then each
   vertex's pick and shadow ray (pt__delta_prepare with those weights). Its draw is the lane's
   next after stage 2's (pt__lane_shade leaves nothing else to draw in between), so the numbers
   are the scalar integrator's. */
static void pt__batch_delta(const pt__batch_ctx *b, pt__lane *lanes, const int *shade, int nshade)
{
    const pt_scene *s = b->s;
    const uint32_t nl = s->dlight_count;
    float in[PT__DW_IN][8], w[PT__DELTA_PICK_MAX][8], fall[PT__DELTA_PICK_MAX][8];
    pt__lane *ls[8];
    int i = 0;
    while (i < nshade) {
        int n = 0, j, k;
        uint32_t q;
        for (; i < nshade && n < 8; ++i) {
            pt__lane *l = &lanes[shade[i]];
            const pt__vertex *v = &l->v;
            if (!l->ddefer) continue;
            in[PT__DW_P][n] = v->p.x;
            in[PT__DW_P + 1][n] = v->p.y;
            in[PT__DW_P + 2][n] = v->p.z;
            in[PT__DW_N][n] = v->ng.x;
            in[PT__DW_N + 1][n] = v->ng.y;
            in[PT__DW_N + 2][n] = v->ng.z;
            in[PT__DW_SG][n] = v->m->transmits ? 0.0f : 1.0f;
            ls[n++] = l;
        }
        if (!n) break;
        for (j = n; j < 8; ++j)
            for (k = 0; k < PT__DW_IN; ++k) in[k][j] = in[k][0];
        for (q = 0; q < nl; ++q) {
            int bits = pt__delta_weight8(&s->dlights[q], in, w[q], fall[q]);
            for (j = 0; bits; ++j, bits >>= 1)
                if ((bits & 1) && j < n) w[q][j] = pt__delta_weight(&ls[j]->v, &s->dlights[q], &fall[q][j]);
        }
        for (j = 0; j < n; ++j) {
            pt__lane *l = ls[j];
            float wj[PT__DELTA_PICK_MAX], fj[PT__DELTA_PICK_MAX];
            for (q = 0; q < nl; ++q) {
                wj[q] = w[q][j];
                fj[q] = fall[q][j];
            }
            l->dshadow = pt__delta_prepare(s, b->cfg, &l->v, l->depth, &l->smp, b->tri, &l->dnr, &l->dLi, &l->dpick_delta,
                                           &l->st, wj, fj);
        }
    }
}
#else
static void pt__batch_delta(const pt__batch_ctx *b, pt__lane *lanes, const int *shade, int nshade)
{
    (void)b; (void)lanes; (void)shade; (void)nshade;
}
#endif

/* Stage 4's splits with the Sobol sampler: copies 1 .. k-1 of lane l's split into k take free
   lanes of their own, each after its continuation from l's vertex (pt__split_copies's order:
   the copies draw from sets of their own, so the order they run in changes no number), and go
   before l in the family's scalar order; l goes on as copy 0, its gains logged until they end. */
static PT__NOINLINE void pt__lane_split(pt__batch_ctx *b, pt__lane *l, int k)
{
    const pt__vertex *v = &l->v;
    pt__lane_kids *kx = l->kids;
    int c;
    l->nkids = k - 1;
    b->pool->lane_copies += (uint64_t)(k - 1);
    for (c = 1; c < k; ++c) {
        const int idx = b->pool->free[b->pool->nfree - 1];
        pt__lane *cl = &b->lanes[idx];
        float pp2 = l->prev_pdf;
        int pd2 = l->prev_delta;
        pt_color Lc = pt_v3(0, 0, 0);
        l->st.split_paths++;
        (void)pt__split_sampler(&l->smp, &cl->smp, l->depth, c);
        kx->go[c] = (unsigned char)pt__continue(b->s, b->cfg, v, &l->h, l->depth, l->beta_in, &cl->smp, b->any_lights,
                                                b->pick, &cl->ray, &cl->beta, &pp2, &pd2, &Lc, &l->st);
        kx->Lc[c] = Lc;
        kx->L[c] = pt_v3(0, 0, 0);
        if (!kx->go[c]) continue;
        b->pool->nfree--;
        l->st.bounce_rays++;
        memset(&cl->st, 0, sizeof cl->st);
        cl->L = pt_v3(0, 0, 0);
        cl->prev_pdf = pp2;
        cl->prev_delta = pd2;
        cl->prev_p = v->o;
        cl->prev_n = pt__receiver_normal(v);
        cl->depth = l->depth + 1;
        cl->surfaces = v->surface + 1;
        cl->v.has_guide = 0; /* (pt__trace_from's start) */
        cl->v.cshare = 0.0f;
        cl->v.g = 0.0f;
        cl->v.rr_e = cl->v.rr_ref = 0.0f;
        cl->v.sph_prim = NULL;
        cl->self = idx;
        cl->root = l->root;
        cl->parent = l->self;
        cl->copy = c;
        cl->pending = cl->nkids = cl->nlog = 0;
        cl->wait = PT__WAIT_NONE;
        if (PT__UNLIKELY(cl->recs != NULL)) { /* its continuation's record first (pt__split_copies) */
            pt__lane_recs_start(cl->recs);
            if (!pd2) {
                pt__lane_recs *r = cl->recs;
                r->r[0].p = v->p;
                r->r[0].w = cl->ray.dir;
                r->r[0].pdf = pp2;
                r->r[0].beta = cl->beta;
                r->r[0].L0 = r->e[0] = pt_v3(0.0f, 0.0f, 0.0f);
                r->mark[0] = -1;
                r->n = 1;
                r->cap = 1 + PT__GUIDE_PATH_RECORDS;
            }
        }
        cl->next = l->self; /* (before l, after the copies before it) */
        cl->prev = l->prev;
        if (l->prev >= 0) b->lanes[l->prev].next = idx;
        else b->lanes[l->root].head = idx;
        l->prev = idx;
        l->pending++;
        b->pool->spawn[b->pool->nspawn++] = idx;
    }
    if (!l->pending) pt__lane_fold(l);
}

/* Stage 4's use of the camera sample's shared splitting state sp (pt__splits: the budget, guided
   roulette's reference), at non-delta vertex l->v where the path may split or set the reference:
   what it does there depends on what the paths before it in the scalar integrator's order did,
   so a copy goes on only as its family's first (returns 0 if it is not: it waits). */
static PT__NOINLINE int pt__lane_shared(pt__batch_ctx bc, pt__lane *l, pt__splits *sp, int split)
{
    pt__batch_ctx *b = &bc;
    pt__vertex *v = &l->v;
    int k;
    if (b->lanes[l->root].head != l->self) return 0;
    if (v->rr_e > 0.0f && !(sp->rr_ref > 0.0f)) sp->rr_ref = pt_max_component(l->L) + pt_max_component(l->beta) * v->rr_e;
    v->rr_ref = sp->rr_ref; /* (before the copies' continuations, which read it) */
    if (split && (k = pt__split_count(l->beta_in, sp)) > 1) {
        l->beta_in = pt_scale(l->beta_in, 1.0f / (float)k);
        if (b->copies && b->pool->nfree >= k - 1) pt__lane_split(b, l, k);
        else
            l->L = pt_add(l->L, pt__split_copies(b->s, b->cfg, v, &l->h, l->depth, k, l->beta_in, &l->smp, b->any_lights,
                                                 b->pick, l->prev_delta, l->prev_pdf, &l->st, sp));
    }
    return 1;
}

/* Stage 4 for one path after its shadow ray (l->shadow: 2 if occluded): returns 0 if it ends, 1
   if it goes on, 2 if it waits (l->wait): PT__WAIT_HEAD, for pt__lane_shared (the lane then
   resumes there), or PT__WAIT_LOG, a path whose log could fill, for its copies to end. */
static PT__HOT int pt__lane_continue(pt__batch_ctx *b, pt__lane *l, const int copies)
{
    const pt_scene *s = b->s;
    const pt__settings *cfg = b->cfg;
    pt__vertex *v = &l->v;
    pt_color Lc = pt_v3(0, 0, 0);
    int go;
    if (!v->m->delta) {
        pt__splits *sp = copies ? &b->lanes[l->root].sp : &l->sp; /* (the camera sample's) */
        int split;
        if (!copies || l->wait != PT__WAIT_HEAD) {
            if (l->shadow == 1) pt__lane_add(l, pt__nee_finish(s, cfg, v, &l->ls, l->li, l->beta, l->nr.f), copies);
            if (PT__UNLIKELY(s->dlight_count != 0)) /* (pt__delta_nee's zero where it adds nothing) */
                pt__lane_add(l, l->dshadow == 1 ? pt__delta_finish(l->beta, &l->dnr, l->dLi, l->dpick_delta) : pt_v3(0, 0, 0),
                             copies);
        }
        split = sp->first > 1 || PT__UNLIKELY(l->beta_in.x >= PT__SPLIT_BETA || l->beta_in.y >= PT__SPLIT_BETA ||
                                               l->beta_in.z >= PT__SPLIT_BETA);
        if (!copies) { /* (the path is its camera sample's only one: pt__trace_from's order) */
            int k;
            if (v->rr_e > 0.0f && !(sp->rr_ref > 0.0f))
                sp->rr_ref = pt_max_component(l->L) + pt_max_component(l->beta) * v->rr_e;
            v->rr_ref = sp->rr_ref;
            if (split && (k = pt__split_count(l->beta_in, sp)) > 1) {
                l->beta_in = pt_scale(l->beta_in, 1.0f / (float)k);
                l->L = pt_add(l->L, pt__split_copies(s, cfg, v, &l->h, l->depth, k, l->beta_in, &l->smp, b->any_lights,
                                                     b->pick, l->prev_delta, l->prev_pdf, &l->st, sp));
            }
        } else if (PT__UNLIKELY(split || (v->rr_e > 0.0f && !(sp->rr_ref > 0.0f))) && !pt__lane_shared(*b, l, sp, split)) {
            l->wait = PT__WAIT_HEAD;
            return 2;
        } else {
            l->wait = PT__WAIT_NONE;
            v->rr_ref = sp->rr_ref;
        }
    }
    go = pt__continue(s, cfg, v, &l->h, l->depth, l->beta_in, &l->smp, b->any_lights, b->pick, &l->ray, &l->beta,
                      &l->prev_pdf, &l->prev_delta, &Lc, &l->st);
    pt__lane_add(l, Lc, copies);
    if (!go) return 0;
    if (PT__UNLIKELY(l->recs != NULL) && !l->prev_delta) pt__lane_record(l, copies);
    l->prev_p = v->o;
    l->prev_n = pt__receiver_normal(v);
    l->st.bounce_rays++;
    l->depth++;
    if (copies && PT__UNLIKELY(l->nlog > PT__LANE_LOG - PT__LANE_LOG_BOUNCE)) {
        l->wait = PT__WAIT_LOG;
        return 2;
    }
    return 1;
}

#ifdef PT__RTC_STREAM
/* Stage 1 with Embree 3: the live paths' closest hits as streams (pt__rtc_closest_n), at most
   PT__RTC_STREAM rays each (split copies as lanes can make a batch of more live paths). */
static void pt__batch_closest_rtc(const pt_scene *s, pt__lane *lanes, const int *live, int nlive)
{
    const pt__rayctx *rc[PT__BATCH_LANES];
    int found[PT__BATCH_LANES], i;
    uint32_t prim[PT__BATCH_LANES];
    float t[PT__BATCH_LANES], bary[3 * PT__BATCH_LANES];
    for (i = 0; i < nlive; ++i) rc[i] = &lanes[live[i]].rc;
    for (i = 0; i < nlive; i += PT__RTC_STREAM) /* (streams of at most PT__RTC_STREAM rays) */
        pt__rtc_closest_n(s, rc + i, nlive - i < PT__RTC_STREAM ? nlive - i : PT__RTC_STREAM, found + i, prim + i, t + i,
                          bary + 3 * i);
    for (i = 0; i < nlive; ++i) {
        pt__lane *l = &lanes[live[i]];
        l->found = found[i];
        if (!found[i]) continue;
        l->pi = prim[i];
        l->t = t[i];
        l->bary[0] = bary[3 * i]; l->bary[1] = bary[3 * i + 1]; l->bary[2] = bary[3 * i + 2];
    }
}
#endif

/* Stage 1: the closest hits of the live paths' rays, in a small scene 8 at a time with AVX2 or 4
   with SSE2 (pt__packet_closest8/4, the level pt_simd_level chose), with Embree 3 as streams
   (pt__batch_closest_rtc), else one at a time. */
static PT__HOT void pt__batch_closest(const pt_scene *s, const pt__packet_scene *pk, pt__lane *lanes, const int *live,
                                      int nlive, int tri)
{
    int i, j;
    for (i = 0; i < nlive; ++i) pt__rayctx_init2(&lanes[live[i]].rc, lanes[live[i]].ray, tri);
#ifdef PT__RTC_STREAM
    if (s->backend == PT_BACKEND_EMBREE) {
        pt__batch_closest_rtc(s, lanes, live, nlive);
        return;
    }
#endif
#ifdef PT__SSE
    if (pk->n > 0) {
        int w = 4;
#ifdef PT__WIDE
        if (s->simd >= PT_SIMD_AVX2) w = s->simd >= PT_SIMD_AVX512 ? 16 : 8;
#endif
        for (i = 0; i < nlive; i += w) {
            const pt__rayctx *rc[16];
            int m = nlive - i < w ? nlive - i : w, found[16];
            uint32_t prim[16];
            float t[16];
            for (j = 0; j < m; ++j) rc[j] = &lanes[live[i + j]].rc;
#ifdef PT__WIDE
            if (m > 8) pt__packet_closest16(s, pk, rc, m, found, prim, t);
            else if (w >= 8) pt__packet_closest8(s, pk, rc, m, found, prim, t);
            else
#endif
                pt__packet_closest4(s, pk, rc, m, found, prim, t);
            for (j = 0; j < m; ++j) {
                pt__lane *l = &lanes[live[i + j]];
                l->found = found[j];
                l->pi = prim[j];
                l->t = t[j];
                l->bary[0] = l->bary[1] = l->bary[2] = 0.0f;
            }
        }
        return;
    }
#else
    (void)pk; (void)j;
#endif
    for (i = 0; i < nlive; ++i) {
        pt__lane *l = &lanes[live[i]];
        l->found = pt__scene_closest(s, &l->rc, PT__INF, &l->pi, &l->t, l->bary);
    }
}

/* Stage 1b (SOBOL): each live path's light point and scattered direction of this bounce drawn
   ahead (pt__sobol_draw_ahead) where its vertex will draw them: a non-delta scattering material
   before the last depth (a guided vertex may draw its direction from the guide instead: that
   draw is then only wasted). */
static void pt__batch_draw_ahead(const pt__batch_ctx bc, pt__lane *lanes, const int *live, int nlive)
{
    const pt__batch_ctx *b = &bc;
    const int scatter = b->cfg->strategy != PT_STRATEGY_MIXTURE;
    int i;
#ifdef PT__WIDE
    if (b->s->simd >= PT_SIMD_AVX2) {
        pt__sobol_ahead8 a;
        a.n = 0;
        for (i = 0; i < nlive; ++i) {
            pt__lane *l = &lanes[live[i]];
            const pt__material *m;
            if (!l->found || l->depth >= b->cfg->max_depth) continue;
            m = &b->s->mats[b->s->prims[l->pi].material];
            if (m->scatters && !m->delta) pt__sobol_draw_ahead8(&a, &l->smp, l->depth, b->nee, scatter);
        }
        if (a.n) pt__sobol_ahead8_run(&a);
        return;
    }
#endif
    for (i = 0; i < nlive; ++i) {
        pt__lane *l = &lanes[live[i]];
        const pt__material *m;
        if (!l->found || l->depth >= b->cfg->max_depth) continue;
        m = &b->s->mats[b->s->prims[l->pi].material];
        if (m->scatters && !m->delta) pt__sobol_draw_ahead(&l->smp, l->depth, b->nee, scatter);
    }
}

/* Stage 3: the shadow rays of the paths that have one (l->shadow = 2 where occluded) and of their
   delta lights (l->dshadow), in a small scene of at most PT__BVH_SMALL_SCENE primitives 8 at a time
   with AVX2 (pt__packet_any8; in larger packet scenes the BVH measured as fast: docs/design.md,
   "Packets for shadow rays"), with Embree 3 as streams of at most PT__RTC_STREAM rays
   (pt__rtc_any_n), else one at a time. */
static void pt__batch_shadow(const pt_scene *s, const pt__packet_scene *pk, pt__lane *lanes, const int *shade, int nshade)
{
    const pt__nee_ray *ray[2 * PT__BATCH_LANES];
    int *flag[2 * PT__BATCH_LANES];
    int i, m = 0;
    for (i = 0; i < nshade; ++i) { /* (the rays, gathered first) */
        pt__lane *l = &lanes[shade[i]];
        if (l->shadow) {
            ray[m] = &l->nr;
            flag[m++] = &l->shadow;
        }
        if (PT__UNLIKELY(l->dshadow)) {
            ray[m] = &l->dnr;
            flag[m++] = &l->dshadow;
        }
    }
#ifdef PT__WIDE
    if (pk->n > 0 && s->prim_count <= PT__BVH_SMALL_SCENE && s->simd >= PT_SIMD_AVX2) {
        const pt__rayctx *rc[16];
        float tmax[16];
        uint32_t skip[16];
        const int w = s->simd >= PT_SIMD_AVX512 ? 16 : 8;
        int o, j;
        for (o = 0; o < m; o += w) {
            const int k = m - o < w ? m - o : w;
            int hit;
            for (j = 0; j < k; ++j) {
                rc[j] = &ray[o + j]->rc;
                tmax[j] = ray[o + j]->tmax;
                skip[j] = ray[o + j]->skip;
            }
            hit = k > 8 ? pt__packet_any16(s, pk, rc, tmax, skip, k) : pt__packet_any8(s, pk, rc, tmax, skip, k);
            for (j = 0; j < k; ++j)
                if (hit & (1 << j)) *flag[o + j] = 2;
        }
        return;
    }
#else
    (void)pk;
#endif
#ifdef PT__RTC_STREAM
    if (s->backend == PT_BACKEND_EMBREE) {
        const pt__rayctx *rc[2 * PT__BATCH_LANES];
        float tmax[2 * PT__BATCH_LANES];
        int hit[2 * PT__BATCH_LANES], o;
        for (i = 0; i < m; ++i) {
            rc[i] = &ray[i]->rc;
            tmax[i] = ray[i]->tmax;
        }
        for (o = 0; o < m; o += PT__RTC_STREAM) /* (streams of at most PT__RTC_STREAM rays) */
            pt__rtc_any_n(s, rc + o, tmax + o, m - o < PT__RTC_STREAM ? m - o : PT__RTC_STREAM, hit + o);
        for (i = 0; i < m; ++i)
            if (hit[i]) *flag[i] = 2;
        return;
    }
#endif
    for (i = 0; i < m; ++i)
        if (pt__scene_any(s, &ray[i]->rc, ray[i]->tmax, ray[i]->skip)) *flag[i] = 2;
}

#ifdef PT__WIDE
/* The two numbers sampler smp's continuation at `depth` draws first for its direction
   (pt__draw_scatter), without drawing them: SOBOL's are a function of the set (the draw made
   ahead in stage 1b where there is one), the independent ones the next two of its stream. */
static void pt__scatter_peek(const pt__sampler *smp, int depth, float *u1, float *u2)
{
    if (smp->sobol) {
        pt__draw_scatter_sobol(smp, depth, u1, u2);
    } else {
        pt_rng r = smp->rng;
        *u1 = pt_rng_float(&r);
        *u2 = pt_rng_float(&r);
    }
}
#endif
/* Stage 3b (AVX2): the scattered direction and density of each path whose vertex is Lambertian
   and unguided (pt__continue's branch for such a vertex, outside the mixture strategy), made 8 at
   a time (pt__lambert_dir8) from the numbers its continuation will draw (pt__scatter_peek; with
   independent numbers the stream's next two: the delta lights' pick was drawn in stage 2) and
   kept in the vertex tagged with those numbers (pt__vertex.scat_*), which pt__continue takes
   when its draws match (a split's copies, which draw first from the stream with independent
   numbers, leave them unused). A path's chain of divisions, square root and polynomials becomes
   a vector's share of one. */
static void pt__batch_scatter_ahead(const pt__batch_ctx bc, pt__lane *lanes, const int *shade, int nshade)
{
#ifdef PT__WIDE
    const pt__batch_ctx *b = &bc;
    /* the vertices' normals and draws gathered first, so that the vector loads find them stored */
    float in[5][PT__BATCH_LANES + 8], out[4][PT__BATCH_LANES + 8]; /* n.x, n.y, n.z, u1, u2; w, pdf */
    pt__vertex *vs[PT__BATCH_LANES];
    int i, k, n = 0;
    if (b->s->simd < PT_SIMD_AVX2 || b->cfg->strategy == PT_STRATEGY_MIXTURE) return;
    for (i = 0; i < nshade; ++i) {
        pt__lane *l = &lanes[shade[i]];
        pt__vertex *v = &l->v;
        if (v->m->type != PT_MATERIAL_LAMBERTIAN || v->m->delta || v->has_guide) continue;
        pt__scatter_peek(&l->smp, l->depth, &in[3][n], &in[4][n]);
        in[0][n] = v->ns.x;
        in[1][n] = v->ns.y;
        in[2][n] = v->ns.z;
        vs[n++] = v;
    }
    if (!n) return;
    for (i = n; i % 8; ++i) /* (the last block's unused lanes: copies of the first) */
        for (k = 0; k < 5; ++k) in[k][i] = in[k][0];
    for (i = 0; i < n; i += 8)
        pt__lambert_dir8(in[0] + i, in[1] + i, in[2] + i, in[3] + i, in[4] + i, out[0] + i, out[1] + i, out[2] + i,
                         out[3] + i);
    for (i = 0; i < n; ++i) {
        pt__vertex *v = vs[i];
        v->scat_u[0] = in[3][i];
        v->scat_u[1] = in[4][i];
        v->scat_wi = pt_v3(out[0][i], out[1][i], out[2][i]);
        v->scat_pdf = out[3][i];
        v->scat_ok = 1;
    }
#else
    (void)bc; (void)lanes; (void)shade; (void)nshade;
#endif
}

/* Lanes that waited (pt__lane_continue) and may now go on: back into live[] from nlive on;
   returns the new nlive. A lane resumed at its family's head may split, end or wait again, which
   may let others go on: the scan repeats until nothing changes. */
static PT__NOINLINE int pt__batch_resume(pt__batch_ctx bc, int *live, int nlive)
{
    pt__batch_ctx *b = &bc;
    int i, changed = 1;
    while (changed && b->pool->nparked > 0) {
        changed = 0;
        for (i = 0; i < b->pool->nparked;) {
            const int idx = b->pool->parked[i];
            pt__lane *l = &b->lanes[idx];
            int r = 1;
            if (l->wait == PT__WAIT_HEAD ? b->lanes[l->root].head != idx : l->pending != 0) {
                ++i;
                continue;
            }
            b->pool->parked[i] = b->pool->parked[--b->pool->nparked];
            changed = 1;
            if (l->wait == PT__WAIT_HEAD) r = pt__lane_continue(b, l, 1);
            else l->wait = PT__WAIT_NONE;
            if (r == 1) live[nlive++] = idx;
            else if (r == 2) b->pool->parked[b->pool->nparked++] = idx;
            else pt__lane_end(b->lanes, b->pool, idx);
        }
    }
    return nlive;
}

/* Runs the paths of lanes[0 .. n-1] to their ends; each lane's L is then its sample's value (the
   NaN/Inf guard of pt__sample applied). pk: the scene's packets (pt__packet_init). With kids
   (PT__BATCH_LANES of them; the Sobol sampler), lanes holds PT__BATCH_LANES lanes, those from n on
   for split copies; without, PT__BATCH, and the copies run in pt__split_copies. Returns the split
   copies that ran as lanes. */
static PT__HOT uint64_t pt__batch_run_with(const pt_scene *s, const pt__settings *cfg, const pt__packet_scene *pk,
                                           pt__lane *lanes, pt__lane_kids *kids, int n, const int copies)
{
    int live[PT__BATCH_LANES], shade[PT__BATCH_LANES], defer[PT__BATCH_LANES], area[PT__BATCH_LANES], sph[PT__BATCH_LANES];
    int env[PT__BATCH_LANES], pick[PT__BATCH_LANES];
    int nlive = n, nshade, ndefer, narea, nsph, nenv, npick, i;
    pt__batch_ctx bc, *b = &bc;
    pt__batch_pool pool;
    b->pool = &pool;
    b->s = s;
    b->cfg = cfg;
    b->tri = (s->features & PT_FEATURE_TRIANGLES) != 0;
    b->any_lights = s->light_count > 0 || cfg->env_on || !PT__SKIP(cfg, PT_SKIP_NO_EMITTERS);
    b->nee = b->any_lights && (cfg->strategy == PT_STRATEGY_MIS || cfg->strategy == PT_STRATEGY_LIGHT);
    b->pick = s->light_count != 1 || cfg->env_pick > 0.0f;
    b->copies = copies;
    b->lmode = pt__lights_mode(cfg);
    b->sph = (b->lmode & PT__LIGHTS_SPHERICAL) != 0;
    b->area = s->simd >= PT_SIMD_AVX2;
    b->dvec = b->area && s->dlight_count > 1u && s->dlight_count <= PT__DELTA_PICK_MAX;
#ifndef PT__WIDE
    b->area = b->dvec = 0;
#endif
    b->env8 = 0;
#ifdef PT__WIDE
    b->env8 = b->area && cfg->env_on && pt__env_wide(cfg->env) && cfg->env_uniform < 1.0f;
#endif
    b->picks = b->area && s->ltree && (b->lmode & PT__LIGHTS_TREE);
    b->lanes = lanes;
    b->pool->kids = kids;
    b->pool->recording = cfg->recording;
    b->pool->nfree = b->pool->nspawn = b->pool->nparked = 0;
    b->pool->lane_copies = 0;
    if (kids)
        for (i = PT__BATCH_LANES - 1; i >= 0; --i) {
            lanes[i].kids = &kids[i];
            if (i >= n) b->pool->free[b->pool->nfree++] = i;
        }
    for (i = 0; i < n; ++i) {
        pt__lane *l = &lanes[i];
        live[i] = i;
        l->self = l->root = l->head = i;
        l->parent = l->prev = l->next = -1;
        l->pending = l->nkids = l->nlog = 0;
        l->wait = PT__WAIT_NONE;
    }
    while (nlive > 0) {
        pt__batch_closest(s, pk, lanes, live, nlive, b->tri); /* (1) closest hits */
        if (cfg->sampler == PT_SAMPLER_SOBOL) pt__batch_draw_ahead(*b, lanes, live, nlive); /* (1b) */
        if (b->env8) pt__batch_escapes(b, lanes, live, nlive); /* (1e) the environment where rays left */
        for (i = 0, nshade = 0, ndefer = 0, narea = 0, nsph = 0, nenv = 0, npick = 0; i < nlive; ++i) /* (2) emission, vertices, light samples */
            if (pt__lane_shade(b, &lanes[live[i]], copies)) {
                if (lanes[live[i]].defer == 5) pick[npick++] = live[i];
                else if (lanes[live[i]].defer == 4) env[nenv++] = live[i];
                else if (lanes[live[i]].defer == 3) sph[nsph++] = live[i];
                else if (lanes[live[i]].defer) area[narea++] = live[i];
                shade[nshade++] = live[i];
            } else if (copies) pt__lane_end(lanes, b->pool, live[i]);
        if (npick) pt__batch_picks(b, lanes, pick, npick, area, &narea, sph, &nsph); /* (2t) the light tree's picks */
        if (nenv) pt__batch_env_lights(b, lanes, env, nenv); /* (2e) the environment's samples */
        if (b->dvec) pt__batch_delta(b, lanes, shade, nshade); /* (2d) the delta lights */
        if (nsph) pt__batch_sphere_lights(b, lanes, sph, nsph); /* (2s) spheres' samples */
        if (narea) ndefer = pt__batch_area_lights(b, lanes, area, narea, defer, 0); /* (2c) quads' samples */
        if (ndefer) pt__batch_lights(b, lanes, defer, ndefer); /* (2b) quads' solid-angle samples */
        pt__batch_shadow(s, pk, lanes, shade, nshade); /* (3) shadow rays */
        pt__batch_scatter_ahead(*b, lanes, shade, nshade); /* (3b) Lambertian directions */
        for (i = 0, nlive = 0; i < nshade; ++i) { /* (4) contributions, splits, continuation */
            const int r = pt__lane_continue(b, &lanes[shade[i]], copies);
            if (r == 1) live[nlive++] = shade[i];
            else if (copies && r == 2) b->pool->parked[b->pool->nparked++] = shade[i];
            else if (copies) pt__lane_end(lanes, b->pool, shade[i]);
        }
        if (copies) {
            for (i = 0; i < b->pool->nspawn; ++i) live[nlive++] = b->pool->spawn[i]; /* (the new copies) */
            b->pool->nspawn = 0;
            nlive = pt__batch_resume(*b, live, nlive);
            for (i = 0; i < b->pool->nspawn; ++i) live[nlive++] = b->pool->spawn[i];
            b->pool->nspawn = 0;
        }
    }
    for (i = 0; i < n; ++i) {
        pt__lane *l = &lanes[i];
        if (!copies && PT__UNLIKELY(l->recs != NULL)) pt__lane_recs_flush(cfg->recording, l->recs, l->L);
        l->L = pt_scale(l->L, 1.0f / l->k);
        if (!pt__vfinite(l->L)) {
            l->st.nonfinite_samples++;
            l->L = pt_v3(0, 0, 0);
        }
    }
    return b->pool->lane_copies;
}
/* (two functions: with copies as lanes, and without, which keeps none of their bookkeeping) */
static PT__NOINLINE uint64_t pt__batch_run_lanes(const pt_scene *s, const pt__settings *cfg, const pt__packet_scene *pk,
                                                 pt__lane *lanes, pt__lane_kids *kids, int n)
{
    return pt__batch_run_with(s, cfg, pk, lanes, kids, n, 1);
}
static PT__NOINLINE uint64_t pt__batch_run_plain(const pt_scene *s, const pt__settings *cfg, const pt__packet_scene *pk,
                                                 pt__lane *lanes, int n)
{
    return pt__batch_run_with(s, cfg, pk, lanes, NULL, n, 0);
}
static uint64_t pt__batch_run(const pt_scene *s, const pt__settings *cfg, const pt__packet_scene *pk, pt__lane *lanes,
                              pt__lane_kids *kids, int n)
{
    return kids ? pt__batch_run_lanes(s, cfg, pk, lanes, kids, n) : pt__batch_run_plain(s, cfg, pk, lanes, n);
}

/* ------------------------------------------------------------------------------------------
   8. Rendering: the image is cut into tiles; each pass adds samples_per_pass samples to every
   pixel of every tile. Tiles are handed out by a pthreads pool (or the host's parallel-for).
   A pixel's k-th sample draws from the stream pt_rng_for_sample(seed, pixel, k) (with
   PT_SAMPLER_SOBOL: from the scrambled Sobol sets keyed by (seed, pixel, k), section 2) and is
   added to the pixel in sample order by the one job that owns the tile, so the image does not
   depend on the thread count or the order in which tiles run. Even-numbered samples also go to
   half-buffer A, odd-numbered ones to B (the film keeps sum and sum_odd; A = sum - sum_odd).
   With adaptive sampling (adaptive_threshold > 0) the samples each pixel takes are planned
   between passes (Neyman's allocation, below): once from a discarded pilot render by default,
   or re-planned from the film itself; a planned pass's jobs are chunks of pixels of about equal
   work instead of tiles. pt_render validates the
   desc, sets the render up, runs the passes and sums up their statistics; the film's own
   functions (init, resolve, error estimate) close the section.
   ------------------------------------------------------------------------------------------ */

static double pt__now(void)
{
#if defined(CLOCK_MONOTONIC)
    struct timespec ts;
    if (clock_gettime(CLOCK_MONOTONIC, &ts) == 0) return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
#endif
    return (double)clock() / (double)CLOCKS_PER_SEC;
}

static int pt__cpu_count(void)
{
#if !defined(PDFTRACE_NO_THREADS) && defined(_SC_NPROCESSORS_ONLN)
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    if (n > 0 && n < 4096) return (int)n;
#endif
    return 1;
}

/* Exact sums: a sum is kept as hi + lo, hi the exact sum rounded to double (pt_film). TwoSum
   (Knuth, TAOCP vol. 2, 4.2.2; Moller 1965) gives s = fl(a + b) and the exact error e with
   a + b = s + e in round-to-nearest, whatever the magnitudes; adding x (or another hi + lo) is a
   TwoSum, an addition of the small parts (exact while they fit one double: see pt_film), and a
   TwoSum that rounds the total once more into hi and keeps the rest in lo. */
static void pt__two_sum(double a, double b, double *s, double *e)
{
    double t = a + b, bv = t - a;
    *e = (a - (t - bv)) + (b - bv);
    *s = t;
}
static void pt__dd_add(double *hi, double *lo, double x)
{
    double s, e;
    pt__two_sum(*hi, x, &s, &e);
    pt__two_sum(s, e + *lo, hi, lo);
}
static void pt__dd_add_dd(double *hi, double *lo, double x_hi, double x_lo)
{
    double s, e;
    pt__two_sum(*hi, x_hi, &s, &e);
    pt__two_sum(s, e + (*lo + x_lo), hi, lo);
}
/* Sample L with index k into one pixel's sums (sum, sum_sq, sum_odd: 3 each; lo: their 9 low words). */
static void pt__film_sample(double *sum, double *sq, double *odd, double *lo, uint32_t k, pt_color L)
{
    const double v[3] = { L.x, L.y, L.z };
    int c;
    for (c = 0; c < 3; ++c) {
        pt__dd_add(&sum[c], &lo[c], v[c]);
        pt__dd_add(&sq[c], &lo[3 + c], v[c] * v[c]); /* exact: a float's square fits a double */
        if (k & 1u) pt__dd_add(&odd[c], &lo[6 + c], v[c]);
    }
}

#ifdef PT__WIDE
/* pt__film_sample with the three channels in one AVX2 vector per sum (the fourth lane unused):
   the same IEEE additions and subtractions per channel, so the same sums to the bit. */
PT__TARGET_AVX2 static void pt__film_sample_avx2(double *sum, double *sq, double *odd, double *lo, uint32_t k, pt_color L)
{
    const __m256d v = _mm256_set_pd(0.0, (double)L.z, (double)L.y, (double)L.x);
    double *hi[3], *lw[3];
    __m256d x[3];
    int j, nq = (k & 1u) ? 3 : 2;
    hi[0] = sum; hi[1] = sq; hi[2] = odd;
    lw[0] = lo; lw[1] = lo + 3; lw[2] = lo + 6;
    x[0] = v; x[1] = _mm256_mul_pd(v, v); x[2] = v; /* a float's square is exact in a double */
    for (j = 0; j < nq; ++j) { /* pt__dd_add: two of pt__two_sum */
        __m256d h = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(hi[j])), _mm_load_sd(hi[j] + 2), 1);
        __m256d l = _mm256_insertf128_pd(_mm256_castpd128_pd256(_mm_loadu_pd(lw[j])), _mm_load_sd(lw[j] + 2), 1);
        __m256d t = _mm256_add_pd(h, x[j]), bv = _mm256_sub_pd(t, h);
        __m256d e = _mm256_add_pd(_mm256_sub_pd(h, _mm256_sub_pd(t, bv)), _mm256_sub_pd(x[j], bv));
        __m256d b = _mm256_add_pd(e, l), t2 = _mm256_add_pd(t, b), bv2 = _mm256_sub_pd(t2, t);
        __m256d e2 = _mm256_add_pd(_mm256_sub_pd(t, _mm256_sub_pd(t2, bv2)), _mm256_sub_pd(b, bv2));
        _mm_storeu_pd(hi[j], _mm256_castpd256_pd128(t2));
        _mm_store_sd(hi[j] + 2, _mm256_extractf128_pd(t2, 1));
        _mm_storeu_pd(lw[j], _mm256_castpd256_pd128(e2));
        _mm_store_sd(lw[j] + 2, _mm256_extractf128_pd(e2, 1));
    }
}
#endif

/* dst += src over np pixels (either may be a view into a merge buffer; a NULL low counts as 0). */
static void pt__film_add_raw(pt_film *dst, const pt_film *src, size_t np)
{
    size_t i;
    int c;
    for (i = 0; i < np; ++i) {
        double *lo = dst->low + 9u * i;
        const double *sl = src->low ? src->low + 9u * i : NULL;
        for (c = 0; c < 3; ++c) {
            size_t j = 3u * i + (size_t)c;
            pt__dd_add_dd(&dst->sum[j], &lo[c], src->sum[j], sl ? sl[c] : 0.0);
            pt__dd_add_dd(&dst->sum_sq[j], &lo[3 + c], src->sum_sq[j], sl ? sl[3 + c] : 0.0);
            pt__dd_add_dd(&dst->sum_odd[j], &lo[6 + c], src->sum_odd[j], sl ? sl[6 + c] : 0.0);
        }
        dst->count[i] += src->count[i];
    }
}
typedef struct pt__pass {
    const pt_scene *scene;
    const pt__settings *cfg;
    const pt_camera *cam;
    pt_film *film;
    uint64_t seed;
    int tile_size, tiles_x, spp;
    const volatile int *cancel;
    const int *jobs;            /* job i renders tile jobs[i] */
    const uint32_t *pixel_spp;  /* adaptive: samples each pixel takes in this pass; NULL: spp each */
    const uint32_t *chunk_first; /* adaptive: job i renders the pixels (raster order) chunk_first[i] to
                                   chunk_first[i + 1] - 1 instead of tile i; NULL: tiles */
    double *pixel_rays;         /* adaptive: rays each pixel traced in this render; NULL: not counted */
    uint32_t *whole;            /* split render: per pixel the whole render's sample count so far, the
                                   next sample index (film holds this part's samples only); NULL: the
                                   film's own count */
    uint32_t parts, part;       /* split render: this part's samples are k with (pixel + k) % parts == part */
    int batched;                /* the batched integrator runs the jobs (pt__render_job_batched) */
    pt_path_stats *tile_stats;  /* one per tile */
    uint64_t *tile_samples;     /* one per tile */
    uint64_t *tile_copies;      /* one per tile: split copies the batched integrator ran as lanes */
    unsigned char *tile_done;   /* one per tile */
#ifndef PDFTRACE_NO_THREADS
    pthread_mutex_t lock;
    int next, count;
#endif
} pt__pass;

/* The pixels of job `index`: rows y0 .. y1 - 1 of columns x0 .. x1 - 1, the first row from xa and
   the last up to xb (a tile: xa = x0, xb = x1; an adaptive chunk: a run of pixels in raster order). */
typedef struct pt__job_pixels {
    int x0, y0, x1, y1, xa, xb;
} pt__job_pixels;
static void pt__job_range(const pt__pass *ps, int index, pt__job_pixels *r)
{
    const pt_film *film = ps->film;
    int tx = index % ps->tiles_x, ty = index / ps->tiles_x;
    r->x0 = tx * ps->tile_size;
    r->y0 = ty * ps->tile_size;
    /* x0 < width and y0 < height: the tile's far edge without int overflow */
    r->x1 = ps->tile_size < film->width - r->x0 ? r->x0 + ps->tile_size : film->width;
    r->y1 = ps->tile_size < film->height - r->y0 ? r->y0 + ps->tile_size : film->height;
    if (ps->chunk_first) { /* adaptive: job = the pixels chunk_first[index] .. chunk_first[index + 1] - 1 */
        uint32_t p0 = ps->chunk_first[index], p1 = ps->chunk_first[index + 1], w = (uint32_t)film->width;
        r->y0 = (int)(p0 / w);
        r->y1 = p1 > p0 ? (int)((p1 - 1u) / w) + 1 : r->y0;
        r->xa = (int)(p0 % w);
        r->xb = p1 > p0 ? (int)((p1 - 1u) % w) + 1 : r->xa;
        r->x0 = 0;
        r->x1 = film->width;
    } else {
        r->xa = r->x0;
        r->xb = r->x1;
    }
}

/* Sample index_k of pixel (x, y): its sampler and camera ray. */
static pt_ray pt__camera_sample(const pt__pass *ps, pt__sampler *smp, int x, int y, uint32_t pix, uint32_t index_k,
                                uint64_t pixel_key, pt__sobol_cache *cache)
{
    float jx, jy, l1, l2;
    pt__sampler_init(smp, ps->cfg->sampler, ps->seed, pix, index_k, pixel_key, cache);
    pt__draw2(smp, PT__SET_PIXEL, &jx, &jy);
    if (smp->sobol && !(ps->cam->lens_radius > 0.0f)) l1 = l2 = 0.5f; /* pinhole: unused */
    else pt__draw2(smp, PT__SET_LENS, &l1, &l2);
    return pt__camera_ray(ps->cam, (float)x + jx, (float)y + jy, l1, l2);
}

/* A finished lane's sample into its pixel's sums, its rays into the pixel's count, its stats into *st. */
static void pt__lane_to_film(const pt__pass *ps, const pt__lane *d, pt_path_stats *st)
{
    pt_film *film = ps->film;
    uint32_t p = d->pix;
#ifdef PT__WIDE
    if (ps->scene->simd >= PT_SIMD_AVX2)
        pt__film_sample_avx2(film->sum + 3u * p, film->sum_sq + 3u * p, film->sum_odd + 3u * p, film->low + 9u * p,
                             d->index_k, d->L);
    else
#endif
        pt__film_sample(film->sum + 3u * p, film->sum_sq + 3u * p, film->sum_odd + 3u * p, film->low + 9u * p,
                        d->index_k, d->L);
    if (ps->pixel_rays) ps->pixel_rays[p] += (double)(d->st.camera_rays + d->st.bounce_rays + d->st.shadow_rays);
    pt__stats_sum(st, &d->st);
}

/* The batched integrator's job: the job's samples, in the scalar job's order, PT__BATCH at a
   time through pt__batch_run; each sample then goes to its pixel (the film's sums do not depend
   on the order they are added in) and its rays to the pixel's count. Returns 0 (nothing done)
   when the lanes cannot be allocated: the caller then runs the job scalar. */
static int pt__render_job_batched(pt__pass *ps, int index)
{
    pt_film *film = ps->film;
    pt__job_pixels r;
    /* split copies as lanes: with Sobol sets of their own (independent numbers: the parent's
       stream, so depth first in pt__split_copies), and not for the path classes' diagnostic */
    const int copies_as_lanes = ps->cfg->sampler == PT_SAMPLER_SOBOL && ps->cfg->max_splits > 0 PT__PCLASS(&& 0);
    const size_t nl = copies_as_lanes ? PT__BATCH_LANES : PT__BATCH; /* (one block: lanes, then the kids) */
    pt__lane *lanes = (pt__lane *)PT_MALLOC(sizeof(pt__lane) * nl + (copies_as_lanes ? sizeof(pt__lane_kids) * nl : 0u));
    pt__lane_kids *kids = copies_as_lanes && lanes ? (pt__lane_kids *)(void *)(lanes + nl) : NULL;
    pt__lane_recs *recs = ps->cfg->recording ? (pt__lane_recs *)PT_MALLOC(sizeof(pt__lane_recs) * nl) : NULL;
    pt__sobol_cache *cache = (pt__sobol_cache *)PT_MALLOC(sizeof(pt__sobol_cache));
    pt__packet_scene *pk = (pt__packet_scene *)PT_MALLOC(sizeof(pt__packet_scene));
    pt_path_stats st;
    uint64_t taken = 0, copies = 0;
    int x, y, k, n = 0, i;
    const int sobol = ps->cfg->sampler == PT_SAMPLER_SOBOL;
    if (!lanes || !cache || !pk || (ps->cfg->recording && !recs)) {
        PT_FREE(lanes);
        PT_FREE(recs);
        PT_FREE(cache);
        PT_FREE(pk);
        return 0;
    }
    for (i = 0; i < (int)nl; ++i) lanes[i].recs = recs ? &recs[i] : NULL;
    pt__packet_init(ps->scene, pk);
    memset(&st, 0, sizeof st);
    if (sobol) pt__sobol_cache_init(cache);
    pt__job_range(ps, index, &r);
    for (y = r.y0; y < r.y1; ++y) {
        for (x = y == r.y0 ? r.xa : r.x0; x < (y == r.y1 - 1 ? r.xb : r.x1); ++x) {
            uint32_t pix = (uint32_t)y * (uint32_t)film->width + (uint32_t)x;
            uint32_t base = ps->whole ? ps->whole[pix] : film->count[pix];
            uint32_t count = ps->pixel_spp ? ps->pixel_spp[pix] : (uint32_t)ps->spp, mine = 0;
            uint64_t pixel_key;
            if (count == 0) continue;
            pixel_key = sobol ? pt__sobol_pixel_key(ps->seed, pix) : 0u;
            for (k = 0; k < (int)count; ++k) {
                uint32_t index_k = base + (uint32_t)k;
                pt__lane *l = &lanes[n];
                if (ps->parts > 1u && ((uint64_t)pix + index_k) % ps->parts != ps->part) continue;
                mine++;
                l->pix = pix;
                l->index_k = index_k;
                pt__lane_start(l, ps->cfg, pt__camera_sample(ps, &l->smp, x, y, pix, index_k, pixel_key, cache));
                if (++n < PT__BATCH) continue;
                copies += pt__batch_run(ps->scene, ps->cfg, pk, lanes, kids, n);
                for (i = 0; i < n; ++i) pt__lane_to_film(ps, &lanes[i], &st);
                n = 0;
            }
            film->count[pix] += mine; /* (read by no path: the samples in flight keep their index_k) */
            if (ps->whole) ps->whole[pix] = base + count;
            taken += mine;
        }
    }
    copies += pt__batch_run(ps->scene, ps->cfg, pk, lanes, kids, n);
    for (i = 0; i < n; ++i) pt__lane_to_film(ps, &lanes[i], &st);
    PT_FREE(lanes);
    PT_FREE(recs);
    PT_FREE(cache);
    PT_FREE(pk);
    ps->tile_stats[index] = st;
    ps->tile_samples[index] = taken;
    ps->tile_copies[index] = copies;
    ps->tile_done[index] = 2; /* (2: done by the batched integrator) */
    return 1;
}

static void pt__render_tile(void *data, int job)
{
    pt__pass *ps = (pt__pass *)data;
    pt_film *film = ps->film;
    int index = ps->jobs[job];
    int x, y, k;
    pt__job_pixels r;
    uint64_t taken = 0;
    pt_path_stats st;
    pt__sobol_cache cache;
    int sobol = ps->cfg->sampler == PT_SAMPLER_SOBOL;
    if (ps->cancel && *ps->cancel) return;
    if (ps->batched && pt__render_job_batched(ps, index)) return;
    memset(&st, 0, sizeof st);
    if (sobol) pt__sobol_cache_init(&cache);
    pt__job_range(ps, index, &r);
    for (y = r.y0; y < r.y1; ++y) {
        for (x = y == r.y0 ? r.xa : r.x0; x < (y == r.y1 - 1 ? r.xb : r.x1); ++x) {
            uint32_t pix = (uint32_t)y * (uint32_t)film->width + (uint32_t)x;
            uint32_t base = ps->whole ? ps->whole[pix] : film->count[pix];
            uint32_t n = ps->pixel_spp ? ps->pixel_spp[pix] : (uint32_t)ps->spp, mine = 0;
            uint64_t rays0 = st.camera_rays + st.bounce_rays + st.shadow_rays;
            double *sum = film->sum + 3u * pix, *sq = film->sum_sq + 3u * pix, *odd = film->sum_odd + 3u * pix;
            double *lo = film->low + 9u * pix;
            uint64_t pixel_key;
            if (n == 0) continue;
            pixel_key = sobol ? pt__sobol_pixel_key(ps->seed, pix) : 0u;
            for (k = 0; k < (int)n; ++k) {
                uint32_t index_k = base + (uint32_t)k;
                pt__sampler smp;
                pt_ray ray;
                pt_color L;
                if (ps->parts > 1u && ((uint64_t)pix + index_k) % ps->parts != ps->part) continue;
                mine++;
                ray = pt__camera_sample(ps, &smp, x, y, pix, index_k, pixel_key, &cache);
                L = pt__sample(ps->scene, ps->cfg, ray, &smp, &st);
                PT__PCLASS(pt_path_class_sample_done(pix);)
                pt__film_sample(sum, sq, odd, lo, index_k, L);
            }
            film->count[pix] += mine;
            if (ps->whole) ps->whole[pix] = base + n;
            taken += mine;
            if (ps->pixel_rays)
                ps->pixel_rays[pix] += (double)(st.camera_rays + st.bounce_rays + st.shadow_rays - rays0);
        }
    }
    ps->tile_stats[index] = st;
    ps->tile_samples[index] = taken;
    ps->tile_done[index] = 1;
}

#ifdef PDFTRACE_EMBREE
/* A tile with flush-to-zero and denormals-are-zero on (Embree's requirement for speed), and the
   thread's previous state restored: the host's threads (parallel_for, the calling thread) keep
   their floating-point state. */
static void pt__render_tile_ftz(void *data, int index)
{
    unsigned old = pt__ftz_begin();
    pt__render_tile(data, index);
    pt__ftz_end(old);
}
#endif
static pt_job_fn pt__tile_job(const pt_scene *s)
{
#ifdef PDFTRACE_EMBREE
    if (s->backend == PT_BACKEND_EMBREE) return pt__render_tile_ftz;
#else
    (void)s;
#endif
    return pt__render_tile;
}

#ifndef PDFTRACE_NO_THREADS
static void *pt__worker(void *data)
{
    pt__pass *ps = (pt__pass *)data;
    pt_job_fn job = pt__tile_job(ps->scene);
    for (;;) {
        int i;
        pthread_mutex_lock(&ps->lock);
        i = ps->next++;
        pthread_mutex_unlock(&ps->lock);
        if (i >= ps->count) break;
        job(ps, i);
    }
    return NULL;
}
#endif

/* Runs `jobs` tiles (ps->jobs) of a pass; returns the number of threads used. The workers are
   created per pass: creating and joining them costs far less than a pass's work, so a
   persistent pool would not pay (docs/internals.md, "Tiles, chunks and threads"). */
static int pt__run_pass(pt__pass *ps, int jobs, int threads, const pt_render_desc *d)
{
    int i;
    pt_job_fn job = pt__tile_job(ps->scene);
    if (d->parallel_for) {
        d->parallel_for(d->parallel_for_user, jobs, job, ps);
        return threads;
    }
#ifndef PDFTRACE_NO_THREADS
    if (threads > 1 && jobs > 1) {
        pthread_t tid[256];
        int started = 0, n = threads > jobs ? jobs : threads;
        if (n > 256) n = 256;
        ps->next = 0;
        ps->count = jobs;
        for (i = 0; i < n - 1; ++i) {
            if (pthread_create(&tid[i], NULL, pt__worker, ps) != 0) break; /* fewer threads: still correct */
            started++;
        }
        (void)pt__worker(ps); /* the calling thread works too */
        for (i = 0; i < started; ++i) pthread_join(tid[i], NULL);
        return started + 1;
    }
#endif
    for (i = 0; i < jobs; ++i) job(ps, i);
    return 1;
}

/* Adaptive sampling (adaptive_threshold = T > 0), planned per pixel.
   Goal: the image's relMSE, mean_i v_i / n_i over pixels i with v_i = Var(one sample) / (r_i^2 +
   0.01) averaged over the channels (the regularised relative error of rendering benchmarks; r_i
   the pixel's true value) and n_i its samples, should reach T^2 for the least time. With c_i the
   cost of one of its samples that is n_i = L sqrt(v_i / c_i) (Lagrange; Neyman's allocation for
   stratified sampling, "On the Two Different Aspects of the Representative Method", 1934, with
   costs as in Cochran, "Sampling Techniques", 3rd ed., 1977, sec. 5.5), L fixed by the target.
   (Stopping each pixel at error T^2 instead, n_i proportional to v_i, costs as many samples as
   uniform sampling for the same mean error.) How well v_i can be known bounds the gain: where
   rare bright samples (caustics) make most of the variance, a pixel's own variance is mostly
   noise even after thousands of samples, so v_i is averaged over a neighbourhood.
   Estimates, from the pilot (PT_ADAPTIVE_PILOT, below), else from the film every
   adaptive_check_passes passes once this render has given every pixel adaptive_min_spp
   samples (default max(16, samples_per_pixel / 16)): s_i^2, the sample
   variance of pixel i per channel (sum_sq, n - 1 degrees of freedom), divided by m^2 + 0.01
   with m the 3x3 mean of the pixel means (the pixel's own mean is a poor stand-in for r: a
   pixel that caught a firefly would divide it away); c_i = the rays pixel i traced per sample
   in this render (a count, never a clock, so the image does not depend on timing). v_i used
   for pixel i is the mean over the 25 pixels of its 5x5 neighbourhood, the pixel itself
   included (adaptive_neighbours_only = 1: the other 24 only); c_i the mean over the other 24.
   The neighbourhood also spreads noise a little beyond where it was seen: a zero-variance pixel
   near noisy ones keeps sampling, so there is no seam where the noise starts. Why 5x5, and the
   variants that did no better: docs/internals.md, "Adaptive sampling". */
/* The neighbourhood v_i and c_i are averaged over: (2 R + 1)^2 pixels, R = 2. */
#define PT__ADAPTIVE_R 2
#define PT__ADAPTIVE_BOX ((2 * PT__ADAPTIVE_R + 1) * (2 * PT__ADAPTIVE_R + 1))

/* The pilot (PT_ADAPTIVE_PILOT, the default). A pixel's estimate is the plain mean of the film's
   samples, so it is unbiased only if the number of them, n_i, does not depend on their values:
   planned from the film itself, n_i is a stopping time and E[mean] != the pixel's value (below).
   So the pilot's adaptive_min_spp samples per pixel go to a film of their own, drawn with a
   seed hashed from the render's (independent of the film's samples with either sampler); the
   plan (n_i, clamped to [2, samples_per_pixel - pilot]) is made once from the pilot alone and
   the pilot is then discarded. The film's samples are then drawn after, and independently of,
   everything n_i depends on, so E[film mean_i | n_i] = the pixel's value for every n_i >= 1, and
   unconditionally too (the tower rule): the image is unbiased, at the cost of the pilot's
   samples. The film's k-th sample is the uniform render's k-th (same seed, same index). Kept in
   the estimate, the pilot would bias it: a pilot that drew a firefly plans more samples that
   dilute it, one that drew none plans fewer (the stopping bias again). Re-planning from the film
   is not allowed here for the same reason. Measured gain and bias: docs/design.md. */
#define PT__ADAPTIVE_FLOOR 2 /* film samples every pixel gets in pilot mode: its variance stays defined */

/* Own samples or not. The allocation above minimises the expected error; the error of the one
   image rendered is what is judged, and with rare bright samples they differ: a pixel that drew
   a firefly has a large error now, and more samples there dilute it. With its own variance in
   its estimate (1/25 of it, so a firefly raises the pixel's share, and its neighbours', by
   1/25 of its size), that pixel samples on; a pixel that drew none stops at its share. That is
   the classic stopping bias of adaptive sampling (Kirk & Arvo, "Unbiased sampling techniques
   for image synthesis", SIGGRAPH 1991): pixels that stop early are the ones that missed the
   rare bright samples, so the image is biased dark, and the bias shrinks as the samples grow
   (each draw moves a pixel's mean by less). Leaving the pixel out (adaptive_neighbours_only)
   makes the bias smaller but not zero: a pixel's own samples still enter L and its neighbours'
   normalisation m. PT_ADAPTIVE_OWN_SAMPLES counts the own samples, for the lowest error with
   the bias included. The measured bias and gain of the modes: docs/internals.md, "Adaptive
   sampling".
   Every decision is taken between passes on the calling thread from the film and the rays
   counted per pixel, so the image stays independent of the thread count and job order.
   Memory: 124 bytes per pixel during an adaptive render, besides the film (272 with the
   pilot's film). */
/* Adaptive sampling state of one pt_render call. */
typedef struct pt__adaptive {
    double target;             /* threshold^2: the relMSE the image should reach */
    int min_spp, check_passes, per_pass, cap, width, height;
    int self;                  /* 1: a pixel's own noise is in its 5x5 mean; 0: only the neighbours' */
    int pilot;                 /* PT_ADAPTIVE_PILOT: the pilot's samples per pixel; 0: re-planning */
    pt_film pilot_film;        /* the pilot's samples (pilot > 0), planned from, never resolved */
    pt_film *film;             /* the caller's film, which the passes after the pilot render into */
    uint32_t *start;           /* per pixel: the film's count when this render began */
    uint32_t *want;            /* per pixel: samples it should still take, from the last check */
    uint32_t *step;            /* per pixel: samples it takes in the next pass (0: none) */
    double *rays;              /* per pixel: rays it traced in this render (the cost proxy) */
    double *noise, *cost;      /* per pixel: v_i from its own samples; rays per sample */
    double *var, *cpp;         /* per pixel: the neighbour means of noise and cost, used to plan */
    double *lo, *hi;           /* per pixel: the fewest and most samples it can end with */
    double *mean, *mbox;       /* 3 per pixel (channel-major): the pixel means and their 3x3 means */
    double *tmp;               /* per pixel: scratch */
    uint32_t *chunk_first;     /* chunks + 1: the jobs of the next pass (see pt__adaptive_plan) */
    int chunks;                /* the most jobs a pass is cut into */
} pt__adaptive;

/* out_i = the mean of v over the (2R+1)x(2R+1) neighbourhood of pixel i (clipped at the image
   border), with pixel i itself when self is 1, without it when self is 0; tmp: scratch for the
   separable row sums. */
static void pt__box_mean(const double *v, double *out, double *tmp, int w, int h, int R, int self)
{
    int x, y, k;
    for (y = 0; y < h; ++y)
        for (x = 0; x < w; ++x) {
            const double *r = v + (size_t)y * (size_t)w;
            double acc = 0.0;
            for (k = x - R; k <= x + R; ++k)
                if (k >= 0 && k < w) acc += r[k];
            tmp[(size_t)y * (size_t)w + (size_t)x] = acc;
        }
    for (y = 0; y < h; ++y)
        for (x = 0; x < w; ++x) {
            size_t i = (size_t)y * (size_t)w + (size_t)x;
            double box = 0.0;
            int nx = (x + R < w ? x + R : w - 1) - (x - R > 0 ? x - R : 0) + 1;
            int ny = (y + R < h ? y + R : h - 1) - (y - R > 0 ? y - R : 0) + 1, n = nx * ny - !self;
            for (k = y - R; k <= y + R; ++k)
                if (k >= 0 && k < h) box += tmp[(size_t)k * (size_t)w + (size_t)x];
            out[i] = n > 0 ? (self ? box : box - v[i]) / n : v[i];
        }
}

/* Re-plans the samples (see the comments above pt__adaptive): per pixel i, v_i from the film's
   sample variance averaged over its 5x5 neighbourhood (itself as 1 of 25 when a->self, else the
   other pixels only), c_i = rays per sample averaged over the other pixels of that
   neighbourhood; then the Lagrange multiplier L with mean_i v_i / n_i(L) = threshold^2,
   n_i(L) = clamp(L sqrt(v_i / c_i), count_i, start_i + cap) (the samples already taken stay),
   found by Newton's method safeguarded by bisection (the mean is convex and decreasing in L);
   L = 0 (every pixel stops) when the target is already reached, and every pixel with v_i > 0
   samples to its cap when the target is out of reach. want_i = round(n_i - count_i), the
   samples pixel i should still take (pt__adaptive_plan hands them out). With the pilot
   (a->pilot > 0) the variances and costs come from the pilot's film, count_i is the film's
   (which the pilot did not touch), n_i >= count_i + 2 and the cap is lower by the pilot's
   samples. */
static void pt__adaptive_check(pt__adaptive *a, const pt_film *film)
{
    size_t i, np = (size_t)a->width * (size_t)a->height;
    double f_lo = 0.0, f_hi = 0.0, target_sum, lam, lam_lo = HUGE_VAL, lam_hi = 0.0;
    const pt_film *src = a->pilot ? &a->pilot_film : film; /* the samples the plan is made from */
    const double least = a->pilot ? (double)PT__ADAPTIVE_FLOOR : 0.0, cap = (double)(a->cap - a->pilot);
    int iter, all_cap = 0;
    int c;
    for (i = 0; i < np && !all_cap; ++i) {
        if (src->count[i] < 2) { all_cap = 1; break; } /* no variance yet (a resumed film's edge case) */
        for (c = 0; c < 3; ++c) a->mean[c * np + i] = src->sum[3 * i + c] / (double)src->count[i];
    }
    for (c = 0; c < 3 && !all_cap; ++c) pt__box_mean(a->mean + c * np, a->mbox + c * np, a->tmp, a->width, a->height, 1, 1);
    for (i = 0; i < np && !all_cap; ++i) {
        double n = (double)src->count[i], v = 0.0;
        double added = a->pilot ? n : (double)(film->count[i] - a->start[i]); /* the samples a->rays counts */
        for (c = 0; c < 3; ++c) {
            double m = a->mean[c * np + i], r = a->mbox[c * np + i];
            double s2 = (src->sum_sq[3 * i + c] - src->sum[3 * i + c] * m) / (n - 1.0);
            v += (s2 > 0.0 ? s2 : 0.0) / (r * r + 0.01);
        }
        a->noise[i] = v / 3.0;
        a->cost[i] = added > 0.0 && a->rays[i] > 0.0 ? a->rays[i] / added : 1.0;
        if (!(a->noise[i] < HUGE_VAL)) all_cap = 1;
    }
    if (!all_cap) {
        pt__box_mean(a->noise, a->var, a->tmp, a->width, a->height, PT__ADAPTIVE_R, 0);
        if (a->self) /* the pixel itself as 1 of 25, at the image border too (where a clipped box
                        mean would weigh it 1/15 or 1/9, and darken the border more) */
            for (i = 0; i < np; ++i)
                a->var[i] = (a->noise[i] + (double)(PT__ADAPTIVE_BOX - 1) * a->var[i]) / (double)PT__ADAPTIVE_BOX;
        pt__box_mean(a->cost, a->cpp, a->tmp, a->width, a->height, PT__ADAPTIVE_R, 0);
        /* r_i = sqrt(v_i / c_i) into tmp; the bracket of L: below lam_lo every n_i sits at its
           count, above lam_hi at its cap */
        for (i = 0; i < np; ++i) {
            double r = sqrt(a->var[i] / a->cpp[i]), lo = (double)film->count[i] + least;
            double hi = (double)a->start[i] + cap;
            a->tmp[i] = r;
            a->lo[i] = lo;
            a->hi[i] = hi > lo ? hi : lo;
            f_lo += a->var[i] / lo;
            f_hi += a->var[i] / (hi > lo ? hi : lo);
            if (r > 0.0) {
                if (lo / r < lam_lo) lam_lo = lo / r;
                if (hi / r > lam_hi) lam_hi = hi / r;
            }
        }
        target_sum = a->target * (double)np;
        if (!(f_lo < HUGE_VAL) || !(f_hi < HUGE_VAL)) all_cap = 1;
        else if (f_lo <= target_sum || !(lam_hi > 0.0)) lam = 0.0;  /* reached: every pixel stops */
        else if (f_hi >= target_sum) lam = HUGE_VAL;              /* out of reach: every noisy pixel to its cap */
        else {
            lam = sqrt(lam_lo * lam_hi);
            for (iter = 0; iter < 100; ++iter) {
                double f = 0.0, slope = 0.0, next;
                for (i = 0; i < np; ++i) { /* branch-free, so that it vectorises */
                    double lo = a->lo[i], hi = a->hi[i], n = lam * a->tmp[i], q;
                    int inside = n > lo && n < hi;
                    n = n < lo ? lo : n;
                    n = n > hi ? hi : n;
                    q = a->var[i] / n;
                    f += q;
                    slope += inside ? q : 0.0;
                }
                if (fabs(f - target_sum) <= 1e-6 * target_sum) break;
                if (f > target_sum) lam_lo = lam; else lam_hi = lam;
                /* Newton: f(L) = const + slope L0 / L near L0, so df/dL = -slope / L0 */
                next = slope > 0.0 ? lam + (f - target_sum) * lam / slope : 0.0;
                if (!(next > lam_lo && next < lam_hi)) next = sqrt(lam_lo * lam_hi);
                if (!(lam_hi > lam_lo * (1.0 + 1e-12))) break;
                lam = next;
            }
        }
        if (!all_cap)
            for (i = 0; i < np; ++i) {
                double room = (double)a->start[i] + cap - (double)film->count[i];
                double want = a->tmp[i] > 0.0 ? floor(lam * a->tmp[i] - (double)film->count[i] + 0.5) : 0.0;
                if (want < least) want = least;
                if (want > room) want = room;
                a->want[i] = want > 0.0 ? (uint32_t)want : 0u;
            }
    }
    if (all_cap)  /* an unknown or overflowing estimate: every pixel samples on to its cap */
        for (i = 0; i < np; ++i) {
            a->want[i] = a->start[i] + (uint32_t)(a->cap - a->pilot) - film->count[i];
            a->cpp[i] = 1.0;
        }
}

/* The next pass: pixel i takes min(want_i, step) samples, step = per_pass x (pixels / pixels
   that still sample), at most the cap, so that the last passes are not a long tail of nearly
   empty ones. The jobs are chunks of pixels in raster order, cut so that each holds about the
   same work (samples x smoothed rays per sample): a few pixels far apart that still sample split
   evenly over the threads, which tiles would not do. Returns the number of jobs (at most
   a->chunks). */
static int pt__adaptive_plan(pt__adaptive *a, pt__pass *ps, int *job_list)
{
    size_t i, np = (size_t)a->width * (size_t)a->height;
    double total = 0.0, acc = 0.0;
    int jobs = 0;
    size_t active = 0;
    uint32_t most;
    for (i = 0; i < np; ++i) active += a->want[i] > 0u;
    /* per_pass samples per pixel, more when few pixels still sample, so that a pass holds about
       as many samples as a pass over every pixel: fewer passes, each long enough for the threads */
    most = active > 0 && np / active > 1 ? (np / active < (size_t)a->cap ? (uint32_t)(np / active) : (uint32_t)a->cap) : 1u;
    most = most > (uint32_t)a->cap / (uint32_t)a->per_pass ? (uint32_t)a->cap : most * (uint32_t)a->per_pass;
    for (i = 0; i < np; ++i) {
        uint32_t n = a->want[i] < most ? a->want[i] : most;
        a->step[i] = n;
        a->want[i] -= n;
        total += (double)n * a->cpp[i];
    }
    a->chunk_first[0] = 0;
    if (total > 0.0)
        for (i = 0; i < np; ++i) {
            if (!a->step[i]) continue;
            if (acc >= total * (double)jobs / (double)a->chunks && jobs < a->chunks) {
                a->chunk_first[jobs] = (uint32_t)i; /* job jobs - 1 ends before the pixel that starts this one */
                jobs++;
            }
            acc += (double)a->step[i] * a->cpp[i];
        }
    a->chunk_first[jobs] = (uint32_t)np;
    for (i = 0; i < (size_t)jobs; ++i) job_list[i] = (int)i;
    ps->pixel_spp = a->step;
    ps->chunk_first = a->chunk_first;
    return jobs;
}

/* Everything pt_render checks before it renders, in order, each rejection naming the one argument
   or pt_render_desc field at fault with its value (err may be NULL). film NULL: not checked
   (pt_render_image makes its own). Fills *cfg and *cam. */
static int pt__render_check(const pt_scene *s, const pt_render_desc *d, const pt_film *film, int need_film,
                            pt__settings *cfg, pt_camera *cam, char *err, size_t n)
{
    const int bad = PT_ERROR_INVALID_ARGUMENT;
    int rc;
    if (!s) return pt__msg(err, n, bad, "pt_render: scene is NULL");
    if (!d) return pt__msg(err, n, bad, "pt_render: desc is NULL");
    if (need_film && !film) return pt__msg(err, n, bad, "pt_render: film is NULL");
    if (!s->committed)
        return pt__msg(err, n, PT_ERROR_INVALID_STATE, "pt_render: the scene is not committed (or changed since)");
    if (d->width <= 0) return pt__msg(err, n, bad, "pt_render_desc.width = %d: must be > 0", d->width);
    if (d->height <= 0) return pt__msg(err, n, bad, "pt_render_desc.height = %d: must be > 0", d->height);
    if (d->samples_per_pixel < 0)
        return pt__msg(err, n, bad, "pt_render_desc.samples_per_pixel = %d: must be >= 0 (0: 16)",
                       d->samples_per_pixel);
    if (d->samples_per_pass < 0)
        return pt__msg(err, n, bad, "pt_render_desc.samples_per_pass = %d: must be >= 0 (0: a default)",
                       d->samples_per_pass);
    if (d->threads < 0)
        return pt__msg(err, n, bad, "pt_render_desc.threads = %d: must be >= 0 (0: all cores)", d->threads);
    if (d->tile_size < 0)
        return pt__msg(err, n, bad, "pt_render_desc.tile_size = %d: must be >= 0 (0: a default)", d->tile_size);
    if (film && (!film->sum || !film->sum_sq || !film->count || !film->sum_odd || !film->low))
        return pt__msg(err, n, bad, "pt_render: the film is not initialised (pt_film_init)");
    if (film && (film->width != d->width || film->height != d->height))
        return pt__msg(err, n, bad, "pt_render_desc.width x height = %d x %d: the film is %d x %d", d->width, d->height,
                       film->width, film->height);
    if (film) { /* a pixel's count and sample index are 32-bit: refuse a render that would wrap them */
        size_t i, np = (size_t)film->width * (size_t)film->height;
        uint32_t most = 0, spp = d->samples_per_pixel ? (uint32_t)d->samples_per_pixel : 16u;
        for (i = 0; i < np; ++i)
            if (film->count[i] > most) most = film->count[i];
        if (most > 0xffffffffu - spp)
            return pt__msg(err, n, bad,
                           "pt_render_desc.samples_per_pixel = %d: the film holds %lu samples in a pixel already, "
                           "and a pixel can count at most 4294967295", d->samples_per_pixel, (unsigned long)most);
    }
    if ((rc = pt__settings_from_desc(d, cfg, err, n)) != PT_OK) return rc;
    pt__settings_for_scene(cfg, s);
    if (!pt__isfinite(d->adaptive_threshold) || d->adaptive_threshold < 0.0f)
        return pt__msg(err, n, bad, "pt_render_desc.adaptive_threshold = %g: must be finite and >= 0 (0: off)",
                       (double)d->adaptive_threshold);
    if (d->adaptive_min_spp < 0 || d->adaptive_min_spp == 1)
        return pt__msg(err, n, bad, "pt_render_desc.adaptive_min_spp = %d: must be 0 (a default) or >= 2",
                       d->adaptive_min_spp);
    if (d->adaptive_check_passes < 0)
        return pt__msg(err, n, bad, "pt_render_desc.adaptive_check_passes = %d: must be >= 0 (0: 1)",
                       d->adaptive_check_passes);
    if (d->adaptive_neighbours_only != 0 && d->adaptive_neighbours_only != 1)
        return pt__msg(err, n, bad, "pt_render_desc.adaptive_neighbours_only = %d: must be 0 or 1",
                       d->adaptive_neighbours_only);
    if ((int)d->adaptive_mode < 0 || (int)d->adaptive_mode > (int)PT_ADAPTIVE_NEIGHBOURS)
        return pt__msg(err, n, bad, "pt_render_desc.adaptive_mode = %d: must be PT_ADAPTIVE_PILOT (0), "
                       "PT_ADAPTIVE_OWN_SAMPLES (1) or PT_ADAPTIVE_NEIGHBOURS (2)", (int)d->adaptive_mode);
    if (d->adaptive_neighbours_only && d->adaptive_mode == PT_ADAPTIVE_OWN_SAMPLES)
        return pt__msg(err, n, bad, "pt_render_desc.adaptive_mode = PT_ADAPTIVE_OWN_SAMPLES: "
                       "adaptive_neighbours_only = 1 asks for PT_ADAPTIVE_NEIGHBOURS");
    if (d->split_parts < 0 || d->split_parts > 65536)
        return pt__msg(err, n, bad, "pt_render_desc.split_parts = %d: must be in 0 .. 65536 (0 or 1: not split)",
                       d->split_parts);
    if (d->split_part < 0 || d->split_part >= (d->split_parts > 1 ? d->split_parts : 1))
        return pt__msg(err, n, bad, "pt_render_desc.split_part = %d: must be in 0 .. %d (split_parts - 1)",
                       d->split_part, (d->split_parts > 1 ? d->split_parts : 1) - 1);
    if (d->split_parts > 1 && d->adaptive_threshold != 0.0f && !d->merge)
        return pt__msg(err, n, bad, "pt_render_desc.merge = NULL: a split render with adaptive sampling "
                       "(split_parts = %d) needs the merge hook to plan from the merged film", d->split_parts);
    if (s->has_origin && pt__vfinite(d->camera.look_from) && pt__vfinite(d->camera.look_at)) {
        pt_camera_desc local = d->camera; /* traced relative to the scene's origin (pt_scene_commit) */
        local.look_from = pt__to_local(s, local.look_from);
        local.look_at = pt__to_local(s, local.look_at);
        if (pt_length2(pt_sub(local.look_at, local.look_from)) > 0.0f)
            return pt__camera_init(cam, &local, d->width, d->height, err, n);
    }
    return pt__camera_init(cam, &d->camera, d->width, d->height, err, n);
}

/* The schedule and running totals of one pt_render call: set by pt__render_setup, advanced by
   pt__render_passes, summed up by pt__render_end_stats. */
typedef struct pt__render_run {
    int spp, per_pass, passes;  /* samples per pixel and per pass (the last pass takes the rest) */
    int adaptive;               /* adaptive_threshold != 0 */
    int threads, used;          /* threads asked for; threads the last pass ran on */
    int jobs, *job_list;        /* the next pass's jobs: tiles, or the adaptive plan's chunks */
    uint64_t done;              /* camera samples taken */
    uint32_t added;             /* samples every pixel has been given by the passes so far */
    double t0;                  /* pt__now() when pt_render began */
    pt_render_stats total;
    struct pt__split *split;    /* a split render's state (split_parts > 1); NULL: the whole render */
    int merge_failed;           /* the merge hook returned non-zero */
} pt__render_run;

/* --- Splitting a render (pt_render_desc.split_parts = N > 1). Part p renders the samples k of
   pixel i with (i + k) mod N = p: the whole render's sample indices, so the same random numbers
   (and Sobol points: the sequence is dealt out, not re-scrambled), and every pass of the whole
   render is the same pass on every part with about 1/N of its samples in each pixel (dealing by
   i + k rather than by ranges of k balances even the passes of one sample per pixel that adaptive
   sampling's small steps make). The part renders into a film of its own (`part`); the sample
   index of pixel i is the whole render's count (`whole`), which every part knows, since which
   samples a pass takes is decided the same way on every part. Because the film's sums are exact
   (pt_film), the parts' films added in order equal the whole render's film bit for bit.
   Decisions: adaptive sampling plans from the merged film (the pilot's, or the film's so far)
   and the merged ray counts: the merge hook combines the parts' films (everyone = 1) at every
   check, so every part makes the same plan as the whole render; at the end the parts' films are
   combined into part 0's (everyone = 0). What cannot be split: guiding (PT_GUIDING_ON and AUTO).
   Its training records are integer sums and would merge exactly, but its tree refinement,
   AUTO's decision and the guided render would need the guide merged after every iteration, and
   the hook for that is not written: pt_render refuses it rather than train per part (a guide per
   part would make the image depend on the number of parts). --- */
typedef struct pt__split {
    pt_film part;               /* this part's samples of the film (the pilot's: ad->pilot_film) */
    uint32_t *whole;            /* per pixel: the whole render's count in the film */
    uint32_t *pilot_whole;      /* per pixel: the whole render's count in the pilot's film */
    pt_film merged;             /* re-planning checks: the caller's film plus every part's samples */
    const pt_film *film;        /* the caller's film (its contents when the render began) */
    double *rays;               /* the merged ray counts per pixel (views into buf) */
    unsigned char *buf;         /* the merge buffer: a film's arrays, then rays if any, then counts */
    size_t np;
} pt__split;

typedef struct pt__merge_ctx { size_t np; int rays; } pt__merge_ctx;
/* A film's arrays and (with rays) a ray count per pixel as views into a merge buffer. */
static void pt__merge_view(const pt__merge_ctx *c, unsigned char *buf, pt_film *f, double **rays)
{
    double *dbl = (double *)(void *)buf;
    size_t np = c->np;
    f->sum = dbl;
    f->sum_sq = dbl + 3u * np;
    f->sum_odd = dbl + 6u * np;
    f->low = dbl + 9u * np;
    *rays = c->rays ? dbl + 18u * np : NULL;
    f->count = (uint32_t *)(void *)(dbl + (c->rays ? 19u : 18u) * np);
}
static size_t pt__merge_bytes(const pt__merge_ctx *c)
{
    return c->np * ((c->rays ? 19u : 18u) * sizeof(double) + sizeof(uint32_t));
}
static void pt__merge_add(void *ctx, void *acc, const void *part)
{
    const pt__merge_ctx *c = (const pt__merge_ctx *)ctx;
    pt_film a, b;
    double *ra, *rb;
    size_t i;
    pt__merge_view(c, (unsigned char *)acc, &a, &ra);
    pt__merge_view(c, (unsigned char *)(uintptr_t)part, &b, &rb);
    pt__film_add_raw(&a, &b, c->np);
    if (ra)
        for (i = 0; i < c->np; ++i) ra[i] += rb[i]; /* integer counts: exact in double */
}
/* Packs film f (and rays, if not NULL) into the buffer, has the hook combine it over the parts and
   leaves views of the result in *out and *rays_out. Returns 0 if the hook failed. */
static int pt__split_merge(pt__split *sp, const pt_render_desc *d, const pt_film *f, const double *rays,
                           int everyone, pt_film *out, double **rays_out)
{
    pt__merge_ctx c;
    pt_film v;
    double *rv;
    size_t np = sp->np;
    c.np = np;
    c.rays = rays != NULL;
    pt__merge_view(&c, sp->buf, &v, &rv);
    memcpy(v.sum, f->sum, sizeof(double) * 3u * np);
    memcpy(v.sum_sq, f->sum_sq, sizeof(double) * 3u * np);
    memcpy(v.sum_odd, f->sum_odd, sizeof(double) * 3u * np);
    memcpy(v.low, f->low, sizeof(double) * 9u * np);
    memcpy(v.count, f->count, sizeof(uint32_t) * np);
    if (rays) memcpy(rv, rays, sizeof(double) * np);
    if (d->merge(d->merge_user, sp->buf, pt__merge_bytes(&c), everyone, pt__merge_add, &c) != 0) return 0;
    v.width = f->width;
    v.height = f->height;
    *out = v;
    if (rays_out) *rays_out = rv;
    return 1;
}
static void pt__split_free(pt__split *sp)
{
    pt_film_free(&sp->part);
    pt_film_free(&sp->merged);
    PT_FREE(sp->whole);
    PT_FREE(sp->pilot_whole);
    PT_FREE(sp->buf);
}
/* Sets a split render up after pt__render_setup: the part's film and the whole render's counts
   take the place of the film in the pass (of the pilot's film: its counts start at 0). */
static int pt__split_init(pt__split *sp, const pt_render_desc *d, pt_film *film, pt__pass *ps, pt__adaptive *ad)
{
    pt__merge_ctx c;
    size_t np = (size_t)d->width * (size_t)d->height;
    memset(sp, 0, sizeof *sp);
    sp->np = c.np = np;
    c.rays = 1;
    if (pt_film_init(&sp->part, d->width, d->height) != PT_OK) return 0;
    sp->whole = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * np);
    sp->pilot_whole = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * np);
    sp->buf = d->merge ? (unsigned char *)PT_MALLOC(pt__merge_bytes(&c)) : NULL;
    if (!sp->whole || !sp->pilot_whole || (d->merge && !sp->buf)) return 0;
    if (d->merge && d->adaptive_threshold != 0.0f && pt_film_init(&sp->merged, d->width, d->height) != PT_OK) return 0;
    sp->film = film;
    memcpy(sp->whole, film->count, sizeof(uint32_t) * np);
    memset(sp->pilot_whole, 0, sizeof(uint32_t) * np);
    ps->parts = (uint32_t)d->split_parts;
    ps->part = (uint32_t)d->split_part;
    if (ad->pilot) {
        ad->film = &sp->part;
        ps->whole = sp->pilot_whole;
    } else {
        ps->film = &sp->part;
        ps->whole = sp->whole;
    }
    return 1;
}
/* An adaptive check of a split render: from the merged pilot (merged into the pilot's film, which
   takes no more samples) or from the caller's film plus every part's samples so far, with the
   merged ray counts. Returns 0 if the hook failed. */
static int pt__split_check(pt__split *sp, pt__adaptive *ad, const pt_render_desc *d, int pilot)
{
    const pt_film *film = sp->film;
    pt_film m, counts;
    double *rays, *own = ad->rays;
    if (pilot) {
        if (!pt__split_merge(sp, d, &ad->pilot_film, ad->rays, 1, &m, &rays)) return 0;
        memcpy(ad->pilot_film.sum, m.sum, sizeof(double) * 3u * sp->np);
        memcpy(ad->pilot_film.sum_sq, m.sum_sq, sizeof(double) * 3u * sp->np);
        memcpy(ad->pilot_film.sum_odd, m.sum_odd, sizeof(double) * 3u * sp->np);
        memcpy(ad->pilot_film.low, m.low, sizeof(double) * 9u * sp->np);
        memcpy(ad->pilot_film.count, m.count, sizeof(uint32_t) * sp->np);
        memcpy(ad->rays, rays, sizeof(double) * sp->np);
        counts = sp->part; /* the film's counts: the whole render's */
        counts.count = sp->whole;
        pt__adaptive_check(ad, &counts);
        return 1;
    }
    if (!pt__split_merge(sp, d, &sp->part, ad->rays, 1, &m, &rays)) return 0;
    memcpy(sp->merged.sum, film->sum, sizeof(double) * 3u * sp->np);
    memcpy(sp->merged.sum_sq, film->sum_sq, sizeof(double) * 3u * sp->np);
    memcpy(sp->merged.sum_odd, film->sum_odd, sizeof(double) * 3u * sp->np);
    memcpy(sp->merged.low, film->low, sizeof(double) * 9u * sp->np);
    memcpy(sp->merged.count, film->count, sizeof(uint32_t) * sp->np);
    pt__film_add_raw(&sp->merged, &m, sp->np);
    ad->rays = rays;
    pt__adaptive_check(ad, &sp->merged);
    ad->rays = own;
    return 1;
}
/* The end of a split render: part 0's film += every part's samples (with the hook), else each
   film += its own part's. Returns 0 if the hook failed. */
static int pt__split_finish(pt__split *sp, const pt_render_desc *d, pt_film *film)
{
    pt_film m;
    if (!d->merge) {
        pt__film_add_raw(film, &sp->part, sp->np);
        return 1;
    }
    if (!pt__split_merge(sp, d, &sp->part, NULL, 0, &m, NULL)) return 0;
    pt__film_add_raw(film, d->split_part == 0 ? &m : &sp->part, sp->np);
    return 1;
}

/* Adaptive sampling's state for one render: its settings with their defaults, and its
   per-pixel arrays (the film's counts at the start copied). Returns 0 when out of memory
   (pt__adaptive_free releases what was allocated). */
static int pt__adaptive_init(pt__adaptive *ad, const pt_render_desc *d, const pt_film *film, int spp, int per_pass)
{
    size_t np = (size_t)d->width * (size_t)d->height;
    pt_adaptive_mode mode = d->adaptive_neighbours_only ? PT_ADAPTIVE_NEIGHBOURS : d->adaptive_mode;
    ad->target = (double)d->adaptive_threshold * (double)d->adaptive_threshold;
    ad->min_spp = d->adaptive_min_spp ? d->adaptive_min_spp : (spp / 16 > 16 ? spp / 16 : 16);
    ad->check_passes = d->adaptive_check_passes ? d->adaptive_check_passes : 1;
    ad->self = mode != PT_ADAPTIVE_NEIGHBOURS;
    if (mode == PT_ADAPTIVE_PILOT) { /* no room beside the pilot: uniform (no check is ever reached) */
        if (ad->min_spp + PT__ADAPTIVE_FLOOR <= spp) ad->pilot = ad->min_spp;
        else ad->min_spp = spp;
        if (ad->pilot && pt_film_init(&ad->pilot_film, d->width, d->height) != PT_OK) return 0;
    }
    ad->per_pass = per_pass;
    ad->cap = spp;
    ad->width = d->width;
    ad->height = d->height;
    ad->start = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * np);
    ad->want = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * np);
    ad->step = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * np);
    ad->rays = (double *)PT_MALLOC(sizeof(double) * np);
    ad->noise = (double *)PT_MALLOC(sizeof(double) * np);
    ad->cost = (double *)PT_MALLOC(sizeof(double) * np);
    ad->var = (double *)PT_MALLOC(sizeof(double) * np);
    ad->lo = (double *)PT_MALLOC(sizeof(double) * np);
    ad->hi = (double *)PT_MALLOC(sizeof(double) * np);
    ad->mean = (double *)PT_MALLOC(sizeof(double) * 3 * np);
    ad->mbox = (double *)PT_MALLOC(sizeof(double) * 3 * np);
    ad->cpp = (double *)PT_MALLOC(sizeof(double) * np);
    ad->tmp = (double *)PT_MALLOC(sizeof(double) * np);
    ad->chunk_first = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * (size_t)(ad->chunks + 1));
    if (ad->start) memcpy(ad->start, film->count, sizeof(uint32_t) * np);
    if (ad->rays) memset(ad->rays, 0, sizeof(double) * np);
    return ad->start && ad->want && ad->step && ad->rays && ad->noise && ad->cost && ad->var && ad->lo && ad->hi &&
           ad->cpp && ad->mean && ad->mbox && ad->tmp && ad->chunk_first;
}
static void pt__adaptive_free(pt__adaptive *ad)
{
    pt_film_free(&ad->pilot_film);
    PT_FREE(ad->start);
    PT_FREE(ad->want);
    PT_FREE(ad->step);
    PT_FREE(ad->rays);
    PT_FREE(ad->noise);
    PT_FREE(ad->cost);
    PT_FREE(ad->var);
    PT_FREE(ad->lo);
    PT_FREE(ad->hi);
    PT_FREE(ad->mean);
    PT_FREE(ad->mbox);
    PT_FREE(ad->cpp);
    PT_FREE(ad->tmp);
    PT_FREE(ad->chunk_first);
}

/* The set-up of a validated render: the pass schedule, the tiles and the thread count, the
   per-job counters, adaptive sampling's state, the job list of the first pass and the pass's
   lock. On failure err (per call) says why; what was allocated is freed by the caller. */
static int pt__render_setup(const pt_scene *s, const pt_render_desc *d, pt_film *film, const pt__settings *cfg,
                            const pt_camera *cam, pt__pass *ps, pt__adaptive *ad, pt__render_run *r, char *err,
                            size_t en)
{
    int tiles, tiles_x, tiles_y, tile, slots, adaptive_ok, most;
    r->spp = d->samples_per_pixel ? d->samples_per_pixel : 16;
    r->per_pass = d->samples_per_pass ? d->samples_per_pass
                                      : (r->spp / (r->adaptive ? 64 : 16) > 0 ? r->spp / (r->adaptive ? 64 : 16) : 1);
    if (r->per_pass > r->spp) r->per_pass = r->spp;
    /* rounded up without spp + per_pass - 1, which overflows int near INT_MAX */
    r->passes = r->spp / r->per_pass + (r->spp % r->per_pass != 0);
    memset(ps, 0, sizeof *ps);
    /* default tiles: 8 x 8 pixels once a pass takes >= 8 samples per pixel (a job then holds >= 512
       samples), else 16 x 16: the smaller the jobs, the closer together the threads finish a pass
       (docs/internals.md, "Tiles, chunks and threads"). A tile larger than the image is the whole
       image (the image does not depend on the tiles), so the size is capped at the larger side. */
    ps->tile_size = d->tile_size ? d->tile_size : (r->per_pass >= 8 ? 8 : 16);
    most = d->width > d->height ? d->width : d->height;
    if (ps->tile_size > most) ps->tile_size = most;
    tiles_x = d->width / ps->tile_size + (d->width % ps->tile_size != 0);
    tiles_y = d->height / ps->tile_size + (d->height % ps->tile_size != 0);
    if ((uint64_t)tiles_x * (uint64_t)tiles_y > (uint64_t)INT_MAX)
        return pt__msg(err, en, PT_ERROR_INVALID_ARGUMENT,
                       "pt_render_desc.tile_size = %d: %d x %d pixels make more than %d tiles", d->tile_size,
                       d->width, d->height, INT_MAX);
    tiles = tiles_x * tiles_y;
    r->threads = d->threads ? d->threads : pt__cpu_count();
#ifdef PDFTRACE_NO_THREADS
    if (!d->parallel_for) r->threads = 1;
#endif
    ps->scene = s;
    ps->cfg = cfg;
    ps->batched = cfg->batched;
    ps->cam = cam;
    ps->film = film;
    ps->seed = d->seed;
    ps->tiles_x = tiles_x;
    ps->cancel = d->cancel;
    /* jobs: tiles, or in adaptive passes up to ad.chunks chunks of pixels: 32 per thread, since at
       the end of a pass a thread waits for at most the other threads' last job (fewer chunks
       left threads idle: docs/internals.md, "Tiles, chunks and threads"; uniform passes have 64
       tiles at 128 x 128) */
    ad->chunks = 32 * r->threads < 4096 ? 32 * r->threads : 4096;
    slots = r->adaptive && ad->chunks > tiles ? ad->chunks : tiles;
    ps->tile_stats = (pt_path_stats *)PT_MALLOC(sizeof(pt_path_stats) * (size_t)slots);
    ps->tile_samples = (uint64_t *)PT_MALLOC(sizeof(uint64_t) * (size_t)slots);
    ps->tile_copies = (uint64_t *)PT_MALLOC(sizeof(uint64_t) * (size_t)slots);
    ps->tile_done = (unsigned char *)PT_MALLOC((size_t)slots);
    r->job_list = (int *)PT_MALLOC(sizeof(int) * (size_t)slots);
    adaptive_ok = !r->adaptive || pt__adaptive_init(ad, d, film, r->spp, r->per_pass);
    ps->pixel_rays = ad->rays;
    if (!ps->tile_stats || !ps->tile_samples || !ps->tile_copies || !ps->tile_done || !r->job_list || !adaptive_ok)
        return pt__msg(err, en, PT_ERROR_OUT_OF_MEMORY, "pt_render: out of memory (%d x %d pixels)", d->width,
                       d->height);
    if (ad->pilot) { /* the pilot's passes first, into its own film with its own seed (section 8) */
        ad->film = film;
        ps->film = &ad->pilot_film;
        ps->seed = pt__mix64(d->seed ^ 0x3c6ef372fe94f82bULL);
        r->passes = ad->pilot / r->per_pass + (ad->pilot % r->per_pass != 0) + (r->spp - ad->pilot) / r->per_pass +
                    ((r->spp - ad->pilot) % r->per_pass != 0);
    }
    for (tile = 0; tile < tiles; ++tile) r->job_list[tile] = tile;
    r->jobs = tiles;
    ps->jobs = r->job_list;
#ifndef PDFTRACE_NO_THREADS
    if (pthread_mutex_init(&ps->lock, NULL) != 0)
        return pt__msg(err, en, PT_ERROR_THREAD, "pt_render: pthread_mutex_init failed");
#endif
    return PT_OK;
}

/* The passes: each renders its jobs (every tile, or the adaptive plan's chunks), adds their
   counters to the totals and reports progress; with adaptive sampling the next pass is planned
   from the film. Returns PT_OK, or PT_ERROR_CANCELLED (the film holds the passes done). */
static int pt__render_passes(pt__pass *ps, pt__adaptive *ad, const pt_render_desc *d, pt__render_run *r)
{
    int pass;
    for (pass = 0; pass < r->passes && r->jobs > 0; ++pass) {
        int all_done = 1, j;
        ps->spp = (pass == r->passes - 1) ? r->spp - r->per_pass * (r->passes - 1) : r->per_pass;
        if (ad->pilot) /* the pilot's passes end at exactly its count; the planned ones ignore ps->spp */
            ps->spp = r->added < (uint32_t)ad->pilot && ad->pilot - (int)r->added < r->per_pass ? ad->pilot - (int)r->added
                                                                                                : r->per_pass;
        for (j = 0; j < r->jobs; ++j) ps->tile_done[r->job_list[j]] = 0;
        r->used = pt__run_pass(ps, r->jobs, r->threads, d);
        for (j = 0; j < r->jobs; ++j) {
            const pt_path_stats *ts = &ps->tile_stats[r->job_list[j]];
            if (!ps->tile_done[r->job_list[j]]) { all_done = 0; continue; }
            r->total.camera_rays += ts->camera_rays;
            r->total.bounce_rays += ts->bounce_rays;
            r->total.shadow_rays += ts->shadow_rays;
            r->total.nonfinite_samples += ts->nonfinite_samples;
            r->total.split_paths += ts->split_paths;
            r->total.guided_vertices += ts->guided_vertices;
            r->done += ps->tile_samples[r->job_list[j]];
            if (ps->tile_done[r->job_list[j]] == 2) {
                r->total.batched_samples += ps->tile_samples[r->job_list[j]];
                r->total.batched_split_paths += ps->tile_copies[r->job_list[j]];
            }
        }
        r->added += (uint32_t)ps->spp;
        r->total.passes = pass + 1;
        if (!all_done || (d->cancel && *d->cancel)) return PT_ERROR_CANCELLED;
        if (d->progress) {
            pt_progress pr;
            pr.pass = pass + 1;
            pr.pass_count = r->passes;
            pr.samples_done = r->done;
            pr.samples_total = (uint64_t)d->width * (uint64_t)d->height * (uint64_t)r->spp;
            pr.seconds = pt__now() - r->t0;
            if (d->progress(d->progress_user, &pr)) return PT_ERROR_CANCELLED;
        }
        if (r->adaptive && pass + 1 < r->passes && r->added >= (uint32_t)ad->min_spp) {
            if (!ps->pixel_spp && ad->pilot) { /* the pilot is done: plan once from it, then render the film */
                ps->film = ad->film;
                ps->seed = d->seed;
                if (!r->split) pt__adaptive_check(ad, ps->film);
                else if ((ps->whole = r->split->whole), !pt__split_check(r->split, ad, d, 1)) r->merge_failed = 1;
            } else if (!ps->pixel_spp || (!ad->pilot && (pass + 1) % ad->check_passes == 0)) {
                if (!r->split) pt__adaptive_check(ad, ps->film);
                else if (!pt__split_check(r->split, ad, d, 0)) r->merge_failed = 1;
            }
            if (r->merge_failed) return PT_ERROR_IO;
            r->jobs = pt__adaptive_plan(ad, ps, r->job_list);
        }
    }
    return PT_OK;
}

/* The film's statistics after the passes: the fewest and most samples this render gave a pixel,
   the pixels adaptive sampling stopped early, and the estimated RMS relative error. */
static void pt__render_end_stats(const pt__adaptive *ad, const pt_render_desc *d, const pt_film *film,
                                 pt__render_run *r)
{
    r->total.min_spp = r->total.max_spp = r->added;
    {
        double e = HUGE_VAL;
        (void)pt_film_error(film, 0, 0, film->width, film->height, &e);
        r->total.estimated_error = e < HUGE_VAL ? sqrt(e) : -1.0;
    }
    if (r->adaptive) {
        size_t i, np = (size_t)d->width * (size_t)d->height;
        r->total.min_spp = (uint32_t)r->spp;
        r->total.max_spp = 0;
        for (i = 0; i < np; ++i) {
            uint32_t n = film->count[i] - ad->start[i];
            if (n + (ad->pilot ? ad->pilot_film.count[i] : 0u) < (uint32_t)r->spp) r->total.pixels_converged++;
            if (n < r->total.min_spp) r->total.min_spp = n;
            if (n > r->total.max_spp) r->total.max_spp = n;
        }
    }
}

/* One render of the desc's samples into the film (what pt_render does without guiding); with
   learned/recording set, its paths sample from and record into a guide (section 8, "Guiding");
   with pixel_spp (not adaptive, one pass), pixel i takes pixel_spp[i] samples instead. */
static int pt__render_once(const pt_scene *s, const pt_render_desc *d, pt_film *film, pt_render_stats *stats,
                           const pt_guide *learned, pt_guide *recording, float learned_weight,
                           const uint32_t *pixel_spp)
{
    pt__settings cfg;
    pt_camera cam;
    pt__pass ps;
    pt__adaptive ad;
    pt__render_run run;
    pt__split split;
    int rc, result;
    char *err = stats ? stats->error : NULL; /* per call: several threads may render one scene */
    size_t en = stats ? sizeof stats->error : 0u;
    memset(&run, 0, sizeof run);
    memset(&split, 0, sizeof split);
    run.t0 = pt__now();
    run.used = 1;
    run.adaptive = d ? d->adaptive_threshold != 0.0f : 0;
    memset(&ad, 0, sizeof ad);
    if (stats) memset(stats, 0, sizeof *stats);
    if ((rc = pt__render_check(s, d, film, 1, &cfg, &cam, err, en)) != PT_OK) return rc;
    cfg.learned = learned;
    cfg.recording = recording;
    cfg.learned_weight = learned_weight;
    result = pt__render_setup(s, d, film, &cfg, &cam, &ps, &ad, &run, err, en);
    if (pixel_spp) ps.pixel_spp = pixel_spp;
    if (result == PT_OK && d->split_parts > 1 && !pt__split_init(&split, d, film, &ps, &ad))
        result = pt__msg(err, en, PT_ERROR_OUT_OF_MEMORY, "pt_render: out of memory for a split render (%d x %d pixels)",
                         d->width, d->height);
    else if (result == PT_OK && d->split_parts > 1)
        run.split = &split;
    if (result == PT_OK) {
        result = pt__render_passes(&ps, &ad, d, &run);
        if (run.split && result == PT_OK && !pt__split_finish(&split, d, film)) run.merge_failed = 1;
        if (run.split && result == PT_ERROR_CANCELLED) /* its own samples only: the other parts are elsewhere */
            pt__film_add_raw(film, &split.part, split.np);
        if (run.merge_failed) result = pt__msg(err, en, PT_ERROR_IO, "pt_render: the merge hook of a split render failed");
        pt__render_end_stats(&ad, d, film, &run);
#ifndef PDFTRACE_NO_THREADS
        pthread_mutex_destroy(&ps.lock);
#endif
    }
    PT_FREE(ps.tile_stats);
    PT_FREE(ps.tile_samples);
    PT_FREE(ps.tile_copies);
    PT_FREE(ps.tile_done);
    PT_FREE(run.job_list);
    pt__adaptive_free(&ad);
    pt__split_free(&split);
    if (result != PT_OK && result != PT_ERROR_CANCELLED) return result;
    run.total.samples = run.done;
    run.total.seconds = pt__now() - run.t0;
    run.total.threads = run.used;
    if (stats) *stats = run.total;
    if (result == PT_ERROR_CANCELLED) pt__msg(err, en, result, "pt_render: cancelled after %d passes", run.total.passes);
    return result;
}

/* --- Caustic photons (section 8, "Guiding"). Light that reaches a non-delta surface through
   glass or off a mirror (L S+ D paths) is what next-event estimation cannot sample and what the
   path guide, learning from the few camera paths that happen upon it, learns last: most of the
   Cornell box's noise. Photons traced from the lights through the delta surfaces to the first
   non-delta one find it directly (importance-driven path tracing with photons: Jensen, "Importance
   Driven Path Tracing using the Photon Map", EGWR 1995). Each records, where it lands, its flux
   along the direction it came from into a second guide (pt_guide.caustic: its own spatial tree,
   refined over rounds of 1, 2, 4, 8 parts of the photons), so a leaf's directional density is
   proportional to the caustic irradiance arriving from each direction (L_i cos, the product with
   the diffuse lobe's cosine for free). Guided vertices whose leaf holds caustic photons mix it
   into the guide's share (pt__vertex_learned); the photons only shape a PDF, so the image stays
   unbiased whatever they learn. Photons leave every light by area and towards the bounding sphere
   of the delta primitives (Jensen's projection maps, one cone), so nearly every photon is a
   caustic one; delta lights and the environment emit none yet. --- */
#define PT__PHOTON_ROUNDS 4        /* refinement rounds of 1, 2, 4, 8 fifteenths of the photons */
#define PT__PHOTON_CHUNK 4096      /* photons per job */
#define PT__PHOTON_MAX_DELTA 12    /* delta bounces a photon follows */
#define PT__PHOTON_SPATIAL 1000.0f /* the caustic guide's spatial threshold (records per leaf) */

typedef struct pt__photon_run {
    const pt_scene *s;
    pt_guide *g;
    pt_vec3 c;           /* the delta primitives' bounding sphere */
    float r;
    uint64_t seed, first; /* photon indices first .. first + count - 1 of this round */
    uint64_t count;
    int jobs;
    int next;
#ifndef PDFTRACE_NO_THREADS
    pthread_mutex_t lock;
#endif
} pt__photon_run;

/* A sphere around the delta primitives (centre, radius): about their box's centre, wide enough
   for each one's own sphere (exact for a single sphere); 0 when there is none. */
static void pt__prim_sphere(const pt__prim *p, pt_vec3 *c, float *r)
{
    pt_vec3 lo, hi;
    if (p->type == PT__PRIM_SPHERE) {
        *c = p->p0;
        *r = p->p1.x;
        return;
    }
    pt__prim_bounds(p, &lo, &hi);
    *c = pt_scale(pt_add(lo, hi), 0.5f);
    *r = 0.5f * pt_length(pt_sub(hi, lo));
}
static int pt__delta_bounds(const pt_scene *s, pt_vec3 *c, float *r)
{
    pt_vec3 lo = pt_v3(FLT_MAX, FLT_MAX, FLT_MAX), hi = pt_scale(lo, -1.0f), pc;
    uint32_t i;
    float pr, R = 0.0f;
    int any = 0;
    for (i = 0; i < s->prim_count; ++i) {
        if (!s->mats[s->prims[i].material].delta) continue;
        pt__prim_sphere(&s->prims[i], &pc, &pr);
        lo = pt__vmin(lo, pt_sub(pc, pt_v3(pr, pr, pr)));
        hi = pt__vmax(hi, pt_add(pc, pt_v3(pr, pr, pr)));
        any = 1;
    }
    if (!any) return 0;
    *c = pt_scale(pt_add(lo, hi), 0.5f);
    for (i = 0; i < s->prim_count; ++i) {
        if (!s->mats[s->prims[i].material].delta) continue;
        pt__prim_sphere(&s->prims[i], &pc, &pr);
        R = pt__maxf(R, pt_length(pt_sub(pc, *c)) + pr);
    }
    *r = R * 1.0001f + 1e-6f * pt__vmaxabs(*c);
    return pt__vfinite(*c) && pt__isfinite(*r);
}

/* Follows a photon along ray through at most PT__PHOTON_MAX_DELTA delta bounces (beta its
   throughput, updated) to the first non-delta surface: returns 1 with the hit there and the
   direction the photon arrived along, 0 if it left the scene or ended. *deltas: the delta
   bounces taken. */
static int pt__photon_deltas(const pt_scene *s, pt_ray ray, pt_rng *rng, pt_color *beta, const pt__prim **prim,
                             pt_hit *h, float bary[3], pt_vec3 *arrival, int *deltas)
{
    const int tri = (s->features & PT_FEATURE_TRIANGLES) != 0;
    for (*deltas = 0; *deltas <= PT__PHOTON_MAX_DELTA; ++*deltas) {
        pt__rayctx rc;
        uint32_t pi;
        float t;
        pt__vertex v;
        pt_vec3 wi;
        pt__rayctx_init2(&rc, ray, tri);
        if (!pt__scene_closest(s, &rc, PT__INF, &pi, &t, bary)) return 0;
        *prim = &s->prims[pi];
        v.m = &s->mats[(*prim)->material];
        if (!v.m->scatters) return 0;
        pt__fill_hit(s, *prim, ray, t, bary, h);
        *arrival = ray.dir;
        if (!v.m->delta) return 1;
        v.p = h->point;
        v.wo = pt_neg(ray.dir);
        v.ng = h->front_face ? h->geometric_normal : pt_neg(h->geometric_normal);
        v.ns = pt_dot(h->shading_normal, v.wo) < 0.0f ? pt_neg(h->shading_normal) : h->shading_normal;
        v.albedo = v.m->texture ? pt__albedo(s, v.m, *prim, bary, h) : v.m->albedo;
        if (!pt__delta_scatter(&v, h->front_face, pt_rng_float(rng), &wi, beta)) return 0;
        ray.origin = pt__offset_origin(v.p, v.ng, wi, h->magnitude);
        ray.dir = wi;
    }
    return 0;
}

/* A landed caustic photon goes on: one bounce cosine-weighted about the lit side's normal (its
   throughput times the albedo, exact for a Lambertian surface; it only shapes a PDF), then
   delta bounces; if it passed a delta surface it is recorded at the next non-delta one. These
   are the ways a diffuse point sees a caustic through glass (S D S paths), which no shadow ray
   can join: the point's photon leaf then points into the glass where the caustic shows. */
static void pt__photon_onward(const pt__photon_run *run, pt_rng *rng, const pt__prim *prim, const pt_hit *h,
                              const float bary[3], pt_color beta, double flux)
{
    const pt_scene *s = run->s;
    const pt__material *m = &s->mats[prim->material];
    pt_vec3 ng = h->front_face ? h->geometric_normal : pt_neg(h->geometric_normal);
    pt_onb b = pt__onb(ng);
    pt_ray ray;
    pt_hit h2;
    const pt__prim *p2;
    pt_vec3 arrival;
    float bary2[3];
    int deltas;
    ray.dir = pt_onb_to_world(&b, pt__cosine_hemisphere(pt_rng_float(rng), pt_rng_float(rng)));
    ray.origin = pt__offset_origin(h->point, ng, ray.dir, h->magnitude);
    beta = pt_mul(beta, m->texture ? pt__albedo(s, m, prim, bary, h) : m->albedo);
    if (pt__photon_deltas(s, ray, rng, &beta, &p2, &h2, bary2, &arrival, &deltas) && deltas > 0)
        pt__guide_splat(run->g, h2.point, pt_neg(arrival), flux * ((double)beta.x + (double)beta.y + (double)beta.z) / 3.0);
}

/* Photon i: a point on a light picked by power, a direction towards the delta bounds (uniform in
   their cone; cosine-weighted where the point is inside them), then delta bounces to the first
   non-delta surface, where its flux is recorded along the way it came; then it goes on
   (pt__photon_onward). */
static void pt__photon_trace(const pt__photon_run *run, uint64_t i)
{
    const pt_scene *s = run->s;
    pt_rng rng;
    const pt__light *l;
    const pt__prim *lp;
    const pt__material *lm;
    pt_vec3 y, n, w, dc;
    pt_color beta;
    double d2, pw, flux;
    float cos_y, bary[3];
    int bounces;
    pt_ray ray;
    const pt__prim *prim;
    pt_hit h;
    pt_vec3 arrival;
    pt_rng_seed(&rng, run->seed, i);
    l = &s->lights[pt__pick_light(s, pt_rng_float(&rng))];
    lp = &s->prims[l->prim];
    lm = &s->mats[lp->material];
    if (lp->type == PT__PRIM_SPHERE) {
        float u1 = pt_rng_float(&rng), u2 = pt_rng_float(&rng), z = 1.0f - 2.0f * u1, sr = pt__safe_sqrt(1.0f - z * z);
        n = pt_v3(sr * cosf(2.0f * PT__PI * u2), sr * sinf(2.0f * PT__PI * u2), z);
        y = pt_madd(lp->p0, n, lp->p1.x);
    } else {
        float u1 = pt_rng_float(&rng), u2 = pt_rng_float(&rng);
        y = pt__planar_point(lp, u1, u2);
        n = lp->n;
    }
    dc = pt_sub(run->c, y);
    d2 = (double)pt_length2(dc);
    if (d2 > (double)run->r * (double)run->r * 1.0001) { /* uniform in the bounds' cone */
        double s2 = (double)run->r * run->r / d2, omc = s2 / (1.0 + sqrt(1.0 - s2)); /* 1 - cos(max) */
        double ct = 1.0 - pt_rng_float(&rng) * omc, st = sqrt(pt__maxd(0.0, 1.0 - ct * ct));
        float phi = 2.0f * PT__PI * pt_rng_float(&rng);
        pt_onb b = pt__onb(pt_scale(dc, 1.0f / sqrtf((float)d2)));
        w = pt_normalize(pt_onb_to_world(&b, pt_v3((float)st * cosf(phi), (float)st * sinf(phi), (float)ct)));
        pw = 1.0 / (2.0 * 3.141592653589793 * omc);
    } else { /* inside the bounds: cosine-weighted about the light's normal */
        pt_onb b = pt__onb(n);
        w = pt_onb_to_world(&b, pt__cosine_hemisphere(pt_rng_float(&rng), pt_rng_float(&rng)));
        pw = (double)pt_dot(w, n) / 3.141592653589793;
    }
    cos_y = pt_dot(w, n);
    if (lm->two_sided) cos_y = fabsf(cos_y);
    if (!(cos_y > 0.0f) || !(pw > 0.0)) return;
    /* the photon's flux times the number of photons: L_e cos / (p_area p_dir), p_area = pick / area
       (only a leaf's relative sums matter: its directional density) */
    flux = (double)cos_y * (double)l->area / ((double)l->select_pdf * pw);
    beta = lm->emission;
    ray.origin = pt__offset_origin(y, n, w, pt__prim_magnitude(lp, n));
    ray.dir = w;
    if (!pt__photon_deltas(s, ray, &rng, &beta, &prim, &h, bary, &arrival, &bounces) || bounces == 0)
        return; /* (a photon that lands without a delta bounce is next-event estimation's light) */
    pt__guide_splat(run->g, h.point, pt_neg(arrival), flux * ((double)beta.x + (double)beta.y + (double)beta.z) / 3.0);
    pt__photon_onward(run, &rng, prim, &h, bary, beta, flux);
}

static void pt__photon_job(void *data, int job)
{
    const pt__photon_run *run = (const pt__photon_run *)data;
    uint64_t i = run->first + (uint64_t)job * PT__PHOTON_CHUNK, end = run->first + run->count;
    uint64_t stop = i + PT__PHOTON_CHUNK < end ? i + PT__PHOTON_CHUNK : end;
    for (; i < stop; ++i) pt__photon_trace(run, i);
}

#ifndef PDFTRACE_NO_THREADS
static void *pt__photon_worker(void *data)
{
    pt__photon_run *run = (pt__photon_run *)data;
    for (;;) {
        int i;
        pthread_mutex_lock(&run->lock);
        i = run->next++;
        pthread_mutex_unlock(&run->lock);
        if (i >= run->jobs) break;
        pt__photon_job(run, i);
    }
    return NULL;
}
#endif

/* One round's photons on the render's threads (or the host's parallel-for): the records are
   integer sums, so the guide does not depend on which thread traced which photon. */
static void pt__photon_round(pt__photon_run *run, int threads, const pt_render_desc *d)
{
    int i;
    (void)threads;
    run->jobs = (int)((run->count + PT__PHOTON_CHUNK - 1) / PT__PHOTON_CHUNK);
    run->next = 0;
    if (d->parallel_for) {
        d->parallel_for(d->parallel_for_user, run->jobs, pt__photon_job, run);
        return;
    }
#ifndef PDFTRACE_NO_THREADS
    if (threads > 1 && run->jobs > 1) {
        pthread_t tid[256];
        int started = 0, n = threads > run->jobs ? run->jobs : threads;
        if (n > 256) n = 256;
        pthread_mutex_init(&run->lock, NULL);
        for (i = 0; i < n - 1; ++i) {
            if (pthread_create(&tid[i], NULL, pt__photon_worker, run) != 0) break;
            started++;
        }
        (void)pt__photon_worker(run);
        for (i = 0; i < started; ++i) pthread_join(tid[i], NULL);
        pthread_mutex_destroy(&run->lock);
        return;
    }
#endif
    for (i = 0; i < run->jobs; ++i) pt__photon_job(run, i);
}

/* The caustic guide of a guided render (NULL when the scene has no delta surface or no shaped
   light): `photons` photons in PT__PHOTON_ROUNDS rounds, the guide updated after each. */
static int pt__caustic_guide(const pt_scene *s, const pt_render_desc *d, uint64_t photons, size_t max_bytes,
                             pt_guide **out)
{
    pt__photon_run run;
    pt_guide_desc gd;
    uint64_t done = 0, parts = (1u << PT__PHOTON_ROUNDS) - 1u;
    int k, rc, threads = d->threads > 0 ? d->threads : pt__cpu_count();
    *out = NULL;
    memset(&run, 0, sizeof run);
    if (!s->light_count || !(s->features & PT_FEATURE_DELTA) || !pt__delta_bounds(s, &run.c, &run.r)) return PT_OK;
    memset(&gd, 0, sizeof gd);
    gd.max_bytes = max_bytes;
    gd.spatial_threshold = PT__PHOTON_SPATIAL;
    /* a photon's flux x N is at most about 2 x the lights' power: 2^-24 of that is the unit */
    gd.value_resolution = (float)pt__maxd(2.0 * s->total_power / 16777216.0, 1e-30);
    if ((rc = pt_guide_create_for_scene(s, &gd, &run.g)) != PT_OK) return rc;
    run.s = s;
    run.seed = pt__mix64(d->seed ^ 0x70686f746f6e73ULL); /* ("photons": a stream apart from the pixels') */
    for (k = 0; k < PT__PHOTON_ROUNDS; ++k) {
        run.first = done;
        run.count = k + 1 < PT__PHOTON_ROUNDS ? photons * ((uint64_t)1 << k) / parts : photons - done;
        pt__photon_round(&run, threads, d);
        done += run.count;
        if ((rc = pt__guide_update(run.g)) != PT_OK) {
            pt_guide_destroy(run.g);
            return rc;
        }
    }
    *out = run.g;
    return PT_OK;
}

/* --- Guiding: pt_render with pt_render_desc.guiding. Training iterations of 1, 2, 4, ...,
   2^(T-1) samples per pixel (the most T with 2^T - 1 <= guiding_budget x spp; Mueller et al.
   2017, section 4), each guided by what the iterations before it recorded and recording its own
   paths' radiance for the next; then the rest of the spp with the final guide. Every sample goes
   into the film with the same weight, fixed before any is drawn, and each is unbiased given the
   guide it used (which only earlier samples shaped), so the image is unbiased; a render has the
   same sample indices with and without guiding. Splats are summed as integers and the guide is
   updated between iterations on one thread, so the image does not depend on the thread count.
   AUTO trains within a quarter of the budget, renders the last of those iterations' first half
   unguided and its second half guided at a quarter of the pixels and compares their efficiencies 1 / (relMSE per sample x
   cost per sample), relMSE estimated against the film's mean and the cost counted in rays and
   guide look-ups (counts, not clocks: the decision is deterministic); only if the guide pays does
   training go on, and the rest is guided. --- */
#define PT__GUIDING_BUDGET 0.25f
#define PT__GUIDING_ALPHA 0.7f
#define PT__GUIDING_MIB 64
#define PT__GUIDING_MAX_ITERATIONS 16
#define PT__GUIDING_AUTO_GAIN 1.0 /* AUTO guides above this measured gain (docs/design.md, "AUTO") */
#define PT__GUIDING_AUTO_SHARE 0.25 /* ... measured within this share of the training budget */
#define PT__GUIDING_LOOKUP_COST 2.0 /* AUTO's cost model: a guided vertex costs 2 rays (the door 1.6,
                                       the Cornell box 2.1, training included: docs/design.md) */

static int pt__guiding_check(const pt_render_desc *d, char *err, size_t n)
{
    const int bad = PT_ERROR_INVALID_ARGUMENT;
    if ((int)d->guiding < (int)PT_GUIDING_OFF || (int)d->guiding > (int)PT_GUIDING_AUTO)
        return pt__msg(err, n, bad, "pt_render_desc.guiding = %d: must be PT_GUIDING_OFF (0), PT_GUIDING_ON (1) or "
                       "PT_GUIDING_AUTO (2)", (int)d->guiding);
    if (!pt__isfinite(d->guiding_budget) || !(d->guiding_budget >= 0.0f && d->guiding_budget < 1.0f))
        return pt__msg(err, n, bad, "pt_render_desc.guiding_budget = %g: must be in (0, 1) (0: %g)",
                       (double)d->guiding_budget, (double)PT__GUIDING_BUDGET);
    if (!pt__isfinite(d->guiding_alpha) || !(d->guiding_alpha >= 0.0f && d->guiding_alpha < 1.0f))
        return pt__msg(err, n, bad, "pt_render_desc.guiding_alpha = %g: must be in (0, 1) (0: %g)",
                       (double)d->guiding_alpha, (double)PT__GUIDING_ALPHA);
    if (d->guiding_max_mib < 0 || d->guiding_max_mib > 1048576)
        return pt__msg(err, n, bad, "pt_render_desc.guiding_max_mib = %d: must be in 1 .. 1048576 (0: %d)",
                       d->guiding_max_mib, PT__GUIDING_MIB);
    if (d->guiding != PT_GUIDING_OFF && d->split_parts > 1)
        return pt__msg(err, n, PT_ERROR_UNSUPPORTED, "pt_render_desc.guiding = %d: a split render (split_parts = %d) "
                       "cannot guide yet (section 8, \"Splitting a render\")", (int)d->guiding, d->split_parts);
    if (d->guiding != PT_GUIDING_OFF && d->guide)
        return pt__msg(err, n, bad, "pt_render_desc.guiding = %d: not with a user guide (pt_render_desc.guide)",
                       (int)d->guiding);
    return PT_OK;
}

static const char *pt__guiding_pointless(const pt_scene *s, const pt_render_desc *d)
{
    uint32_t i;
    int non_delta = 0;
    for (i = 0; i < s->mat_count; ++i)
        if (s->mats[i].scatters && !s->mats[i].delta) non_delta = 1;
    if (!non_delta) return "no material with a scattering density: nothing to guide";
    if (!s->light_count && !s->dlight_count && pt__is_black(d->background) && !(s->env && s->env->mean > 0.0))
        return "no emitter, environment or background: no light to learn";
    return NULL;
}

/* The fixed-point unit of a render's guide: 2^-24 of the brightest emission, background or
   environment map pixel. */
static float pt__guiding_unit(const pt_scene *s, const pt_render_desc *d)
{
    float top = (d->background.x + d->background.y + d->background.z) / 3.0f;
    uint32_t i;
    if (s->env) {
        size_t k, n = (size_t)s->env->w * (size_t)s->env->h;
        for (k = 0; k < n; ++k)
            top = pt__maxf(top, (s->env->rgb[3 * k] + s->env->rgb[3 * k + 1] + s->env->rgb[3 * k + 2]) / 3.0f);
    }
    for (i = 0; i < s->mat_count; ++i)
        if (s->mats[i].emits)
            top = pt__maxf(top, (s->mats[i].emission.x + s->mats[i].emission.y + s->mats[i].emission.z) / 3.0f);
    for (i = 0; i < s->dlight_count; ++i) /* (intensity or irradiance: the radiance it gives at unit scale) */
        top = pt__maxf(top, (s->dlights[i].desc.intensity.x + s->dlights[i].desc.intensity.y +
                             s->dlights[i].desc.intensity.z) / 3.0f);
    top = top > 0.0f && pt__isfinite(top) ? top : 1.0f;
    return pt__maxf(top * (1.0f / 16777216.0f), 1e-30f);
}

static void pt__stats_add(pt_render_stats *t, const pt_render_stats *a)
{
    t->samples += a->samples;
    t->camera_rays += a->camera_rays;
    t->bounce_rays += a->bounce_rays;
    t->shadow_rays += a->shadow_rays;
    t->nonfinite_samples += a->nonfinite_samples;
    t->split_paths += a->split_paths;
    t->guided_vertices += a->guided_vertices;
    t->batched_samples += a->batched_samples;
    t->batched_split_paths += a->batched_split_paths;
}

/* The per-pixel sums of the samples one training iteration added to the film: the film after it
   minus `before` (a copy of sum and sum_sq taken before it; counts likewise). */
typedef struct pt__film_snap {
    double *sum, *sum_sq;
    uint32_t *count;
} pt__film_snap;
static void pt__snap_free(pt__film_snap *sn)
{
    PT_FREE(sn->sum);
    PT_FREE(sn->sum_sq);
    PT_FREE(sn->count);
}
static int pt__snap_take(pt__film_snap *sn, const pt_film *f)
{
    size_t np = (size_t)f->width * (size_t)f->height;
    if (!sn->sum) {
        sn->sum = (double *)PT_MALLOC(sizeof(double) * 3u * np);
        sn->sum_sq = (double *)PT_MALLOC(sizeof(double) * 3u * np);
        sn->count = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * np);
        if (!sn->sum || !sn->sum_sq || !sn->count) return 0;
    }
    memcpy(sn->sum, f->sum, sizeof(double) * 3u * np);
    memcpy(sn->sum_sq, f->sum_sq, sizeof(double) * 3u * np);
    memcpy(sn->count, f->count, sizeof(uint32_t) * np);
    return 1;
}
/* The squared relative errors of the samples `after` holds and `before` does not at the pixels i
   with only[i] > 0, against the film's mean (all its samples), added to *err, and their count
   (pixels x channels x samples) to *n: *err / *n is their relMSE per sample. */
static void pt__guiding_rel_err(const pt_film *f, const pt__film_snap *after, const pt__film_snap *before,
                                const uint32_t *only, double *err, double *n)
{
    size_t i, np = (size_t)f->width * (size_t)f->height;
    for (i = 0; i < 3u * np; ++i) {
        double m = (double)(after->count[i / 3u] - before->count[i / 3u]), r, s1, s2;
        if (!(m > 0.0) || (only && !only[i / 3u])) continue;
        r = f->sum[i] / (double)f->count[i / 3u];
        s1 = after->sum[i] - before->sum[i];
        s2 = after->sum_sq[i] - before->sum_sq[i];
        *err += (s2 - 2.0 * r * s1 + m * r * r) / (r * r + 0.01);
        *n += m;
    }
}

/* One training render into the film, sampling from `learned` (NULL: unguided) and recording into
   g (NULL: not recording), spp samples per pixel or pixel_spp[i] at pixel i; its cost (rays and
   guide look-ups) is added to *cost and its samples to *samples. */
static int pt__guiding_step(const pt_scene *s, const pt_render_desc *d, pt_film *film, int spp,
                            const uint32_t *pixel_spp, const pt_guide *learned, pt_guide *g, float weight,
                            pt_render_stats *acc, double *cost, double *samples, char *err, size_t en)
{
    pt_render_desc sub = *d;
    pt_render_stats st;
    int rc;
    sub.guiding = PT_GUIDING_OFF;
    sub.guiding_guide = NULL;
    sub.samples_per_pixel = sub.samples_per_pass = spp;
    sub.adaptive_threshold = 0.0f;
    sub.progress = NULL;
    rc = pt__render_once(s, &sub, film, &st, learned, g, weight, pixel_spp);
    if (rc != PT_OK) return pt__msg(err, en, rc, "%s", st.error);
    pt__stats_add(acc, &st);
    *cost += (double)(st.camera_rays + st.bounce_rays + st.shadow_rays) +
             PT__GUIDING_LOOKUP_COST * (double)st.guided_vertices;
    *samples += (double)st.samples;
    return PT_OK;
}

/* AUTO's decision, in training iteration `it` (n = 2^it samples per pixel): n/2 unguided samples
   everywhere, recording; then the other n - n/2 guided (and recording) at a quarter of the
   pixels (even x, even y) and unguided, not recording, at the others. *gain is the guided samples'
   efficiency 1 / (relMSE per sample x cost per sample) over the unguided ones'; both are measured
   on samples of the same iteration (a rare bright path the unguided samples miss would make an
   unguided iteration of its own look better than it is), and guiding a quarter of the pixels
   halves what a scene the guide does not help pays for finding out (docs/design.md, "AUTO"). */
static int pt__guiding_decide(const pt_scene *s, const pt_render_desc *d, pt_film *film, pt_guide *g, int n,
                              float weight, pt_render_stats *acc, double *gain, char *err, size_t en)
{
    size_t np = (size_t)d->width * (size_t)d->height, i;
    pt__film_snap a, b, c, now;
    uint32_t *guided = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * np), *plain = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * np);
    double cu = 0.0, nu = 0.0, cg = 0.0, ng = 0.0, eu = 0.0, mu = 0.0, eg = 0.0, mg = 0.0;
    int rc = PT_ERROR_OUT_OF_MEMORY;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    memset(&c, 0, sizeof c);
    now.sum = film->sum; /* (the film itself, read as a snapshot) */
    now.sum_sq = film->sum_sq;
    now.count = film->count;
    if (guided && plain) {
        for (i = 0; i < np; ++i) {
            int on = (int)(((i % (size_t)d->width) | (i / (size_t)d->width)) & 1u) == 0;
            guided[i] = on ? (uint32_t)(n - n / 2) : 0u;
            plain[i] = on ? 0u : (uint32_t)(n - n / 2);
        }
        if (pt__snap_take(&a, film) &&
            (rc = pt__guiding_step(s, d, film, n / 2, NULL, NULL, g, weight, acc, &cu, &nu, err, en)) == PT_OK &&
            (rc = PT_ERROR_OUT_OF_MEMORY, pt__snap_take(&b, film)) &&
            (rc = pt__guiding_step(s, d, film, n - n / 2, guided, g, g, weight, acc, &cg, &ng, err, en)) == PT_OK &&
            (rc = PT_ERROR_OUT_OF_MEMORY, pt__snap_take(&c, film)) &&
            (rc = pt__guiding_step(s, d, film, n - n / 2, plain, NULL, NULL, weight, acc, &cu, &nu, err, en)) == PT_OK) {
            /* all against the mean of every sample so far */
            pt__guiding_rel_err(film, &b, &a, NULL, &eu, &mu);
            pt__guiding_rel_err(film, &c, &b, NULL, &eg, &mg);
            pt__guiding_rel_err(film, &now, &c, NULL, &eu, &mu);
            eu = mu > 0.0 && nu > 0.0 ? eu / mu * (cu / nu) : 0.0;
            eg = mg > 0.0 && ng > 0.0 ? eg / mg * (cg / ng) : 0.0;
            *gain = eg > 0.0 ? eu / eg : (eu > 0.0 ? HUGE_VAL : 1.0);
        }
    }
    if (rc == PT_ERROR_OUT_OF_MEMORY) pt__msg(err, en, rc, "pt_render: out of memory for guiding's error estimate");
    PT_FREE(guided);
    PT_FREE(plain);
    pt__snap_free(&a);
    pt__snap_free(&b);
    pt__snap_free(&c);
    return rc;
}

/* The caustic photons of guided render d into g->caustic (replacing a previous render's): one
   photon per 4 camera samples of the render, at least 2^16 and at most 2^22 (photons cost about as
   much as a camera sample each: docs/design.md, "Caustic photons"). */
#define PT__PHOTONS_PER_SAMPLE 0.25
static int pt__guiding_photons(const pt_scene *s, const pt_render_desc *d, pt_guide *g, size_t max_bytes,
                               pt_render_stats *acc)
{
    double t0 = pt__now(), n = PT__PHOTONS_PER_SAMPLE * (double)d->width * (double)d->height *
                                   (double)(d->samples_per_pixel ? d->samples_per_pixel : 16);
    uint64_t photons = (uint64_t)pt__mind(4194304.0, pt__maxd(65536.0, n));
    int rc;
    pt_guide_destroy(g->caustic);
    g->caustic = NULL;
    rc = pt__caustic_guide(s, d, photons, max_bytes / 4u, &g->caustic);
    if (rc == PT_OK && g->caustic) {
        pt_guide_info gi;
        pt_guide_get_info(g->caustic, &gi);
        acc->guiding_photons = photons;
        acc->guiding_bytes += gi.bytes;
    }
    acc->guiding_photon_seconds = pt__now() - t0;
    return rc;
}

/* The training iterations (see above), into the caller's film. With AUTO the last one decides
   (pt__guiding_decide): *gain, then *use. */
static int pt__guiding_train(const pt_scene *s, const pt_render_desc *d, pt_film *film, pt_guide *g, int T, int Td,
                             float weight, size_t max_bytes, int *use, pt_render_stats *acc, double *gain, char *err,
                             size_t en)
{
    int it, rc = PT_OK;
    *use = 1;
    for (it = 0; it < T && rc == PT_OK; ++it) {
        double cost = 0.0, samples = 0.0;
        int n = 1 << it;
        if (d->guiding == PT_GUIDING_AUTO && it == Td - 1) {
            if ((rc = pt__guiding_decide(s, d, film, g, n, weight, acc, gain, err, en)) != PT_OK) break;
            *use = *gain > PT__GUIDING_AUTO_GAIN;
            /* the caustic photons only once guiding is decided on: a scene it does not help pays
               nothing for them */
            if (*use && (rc = pt__guiding_photons(s, d, g, max_bytes, acc)) != PT_OK) {
                pt__msg(err, en, rc, "pt_render: out of memory for the caustic photons' guide");
                break;
            }
        } else if ((rc = pt__guiding_step(s, d, film, n, NULL, it > 0 ? g : NULL, g, weight, acc, &cost, &samples, err,
                                          en)) != PT_OK)
            break;
        acc->guiding_iterations = it + 1;
        if (!*use) break; /* (AUTO: the rest unguided, untrained) */
        if ((rc = pt__guide_update(g)) != PT_OK) pt__msg(err, en, rc, "pt_render: out of memory for the guide");
    }
    return rc;
}

static int pt__render_guided(const pt_scene *s, const pt_render_desc *d, pt_film *film, pt_render_stats *stats)
{
    char *err = stats ? stats->error : NULL;
    size_t en = stats ? sizeof stats->error : 0u;
    pt_render_stats acc, fin;
    pt_render_desc last = *d;
    pt_guide *g = d->guiding_guide;
    const char *why = pt__guiding_pointless(s, d);
    int spp = d->samples_per_pixel ? d->samples_per_pixel : 16, T = 0, Td = 0, rc = PT_OK, use = 0, own = !g;
    float budget = d->guiding_budget > 0.0f ? d->guiding_budget : PT__GUIDING_BUDGET;
    float weight = 1.0f - (d->guiding_alpha > 0.0f ? d->guiding_alpha : PT__GUIDING_ALPHA);
    double t0 = pt__now(), gain = 0.0;
    memset(&acc, 0, sizeof acc);
    memset(&fin, 0, sizeof fin);
    if (g && g->scene != s)
        return pt__msg(err, en, PT_ERROR_INVALID_ARGUMENT,
                       "pt_render_desc.guiding_guide: not made for this scene (pt_guide_create_for_scene)");
    while (T < PT__GUIDING_MAX_ITERATIONS && (double)((1u << (T + 1)) - 1u) <= (double)budget * (double)spp) ++T;
    /* AUTO decides within a quarter of the budget (at least iterations 0 and 1), so that a scene
       the guide does not help pays little for finding out */
    while (Td < T && (Td < 2 || (double)((1u << (Td + 1)) - 1u) <= PT__GUIDING_AUTO_SHARE * (double)budget * (double)spp)) ++Td;
    if (!why && T < 2) why = "too few samples to train (fewer than 3 in the budget)";
    if (!why) {
        pt_guide_desc gd;
        memset(&gd, 0, sizeof gd);
        gd.max_bytes = (size_t)(d->guiding_max_mib ? d->guiding_max_mib : PT__GUIDING_MIB) << 20;
        gd.value_resolution = pt__guiding_unit(s, d);
        if (own && (rc = pt_guide_create_for_scene(s, &gd, &g)) != PT_OK)
            return pt__msg(err, en, rc, "pt_render: out of memory for the guide");
        if (!own && !g->updates) g->unit = (double)gd.value_resolution;
        pt_guide_destroy(g->caustic); /* (a caller's guide: the last render's photons) */
        g->caustic = NULL;
        if (d->guiding == PT_GUIDING_ON && (rc = pt__guiding_photons(s, d, g, gd.max_bytes, &acc)) != PT_OK)
            pt__msg(err, en, rc, "pt_render: out of memory for the caustic photons' guide");
        else
            rc = pt__guiding_train(s, d, film, g, T, Td, weight, gd.max_bytes, &use, &acc, &gain, err, en);
        acc.guiding_seconds = pt__now() - t0;
        acc.guiding_samples = acc.samples;
        if (rc == PT_OK) {
            pt_guide_info gi;
            pt_guide_get_info(g, &gi);
            acc.guiding_bytes += gi.bytes;
            acc.guiding_leaves = gi.spatial_leaves;
            acc.guiding_gain = gain;
            if (d->guiding == PT_GUIDING_ON)
                pt__msg(acc.guiding_note, sizeof acc.guiding_note, 0, "guided: %d training iterations (guiding on)",
                        acc.guiding_iterations);
            else
                pt__msg(acc.guiding_note, sizeof acc.guiding_note, 0,
                        "%s: %d training iterations, measured gain %.2f (auto: %s %.2f)", use ? "guided" : "not guided",
                        acc.guiding_iterations, gain, use ? "above" : "not above", PT__GUIDING_AUTO_GAIN);
            last.samples_per_pixel = spp - (int)(acc.guiding_samples / ((uint64_t)d->width * (uint64_t)d->height));
            if (last.samples_per_pixel > 0)
                rc = pt__render_once(s, &last, film, &fin, use ? g : NULL, NULL, weight, NULL);
        }
        if (own) pt_guide_destroy(g);
    } else {
        pt__msg(acc.guiding_note, sizeof acc.guiding_note, 0, "not guided: %s", why);
        rc = pt__render_once(s, &last, film, &fin, NULL, NULL, 0.0f, NULL);
    }
    pt__stats_add(&fin, &acc);
    fin.guiding_used = use;
    fin.guiding_iterations = acc.guiding_iterations;
    fin.guiding_samples = acc.guiding_samples;
    fin.guiding_seconds = acc.guiding_seconds;
    fin.guiding_gain = acc.guiding_gain;
    fin.guiding_bytes = acc.guiding_bytes;
    fin.guiding_leaves = acc.guiding_leaves;
    fin.guiding_photons = acc.guiding_photons;
    fin.guiding_photon_seconds = acc.guiding_photon_seconds;
    memcpy(fin.guiding_note, acc.guiding_note, sizeof fin.guiding_note);
    fin.seconds = pt__now() - t0;
    if (stats) {
        if (rc != PT_OK && err && err[0]) memcpy(fin.error, err, sizeof fin.error);
        *stats = fin;
    }
    return rc;
}

PTDEF int pt_render(const pt_scene *s, const pt_render_desc *d, pt_film *film, pt_render_stats *stats)
{
    char *err = stats ? stats->error : NULL;
    size_t en = stats ? sizeof stats->error : 0u;
    int rc;
    if (stats) memset(stats, 0, sizeof *stats);
    if (d && (rc = pt__guiding_check(d, err, en)) != PT_OK) return rc;
    if (!d || d->guiding == PT_GUIDING_OFF) return pt__render_once(s, d, film, stats, NULL, NULL, 0.0f, NULL);
    {   /* the desc, scene and film first: a guide is built only for a render that can run */
        pt__settings cfg;
        pt_camera cam;
        if ((rc = pt__render_check(s, d, film, 1, &cfg, &cam, err, en)) != PT_OK) return rc;
    }
    return pt__render_guided(s, d, film, stats);
}

PTDEF int pt_render_image(const pt_scene *s, const pt_render_desc *d, pt_image *image, pt_render_stats *stats)
{
    pt_film film;
    pt__settings cfg;
    pt_camera cam;
    char *err = stats ? stats->error : NULL;
    size_t en = stats ? sizeof stats->error : 0u;
    int rc, rr;
    if (stats) memset(stats, 0, sizeof *stats);
    if (!image) return pt__msg(err, en, PT_ERROR_INVALID_ARGUMENT, "pt_render_image: image is NULL");
    /* the desc first, so that a bad width is named as such rather than as a failed film */
    if ((rc = pt__render_check(s, d, NULL, 0, &cfg, &cam, err, en)) != PT_OK) return rc;
    memset(&film, 0, sizeof film);
    if ((rc = pt_film_init(&film, d->width, d->height)) != PT_OK)
        return rc == PT_ERROR_OUT_OF_MEMORY
                   ? pt__msg(err, en, rc, "pt_render_image: out of memory for a film of %d x %d pixels", d->width,
                             d->height)
                   : pt__msg(err, en, rc, "pt_render_desc.width x height = %d x %d: too many pixels", d->width,
                             d->height);
    rc = pt_render(s, d, &film, stats);
    if (rc == PT_OK || rc == PT_ERROR_CANCELLED) {
        rr = pt_film_resolve(&film, image);
        if (rr != PT_OK)
            rc = pt__msg(err, en, rr, "pt_render_image: out of memory for an image of %d x %d pixels", d->width,
                         d->height);
    }
    pt_film_free(&film);
    return rc;
}

/* --- the film (sums per pixel), its resolve into an image, its error estimate --- */
static int pt__pixels(int w, int h, size_t *n)
{
    if (w <= 0 || h <= 0 || (size_t)w > ((size_t)-1) / 64u / (size_t)h || (uint64_t)w * (uint64_t)h > 0xffffffffu)
        return 0;
    *n = (size_t)w * (size_t)h;
    return 1;
}
PTDEF int pt_film_init(pt_film *f, int w, int h)
{
    size_t n;
    if (!f) return PT_ERROR_INVALID_ARGUMENT;
    memset(f, 0, sizeof *f);
    if (!pt__pixels(w, h, &n)) return PT_ERROR_INVALID_ARGUMENT;
    f->sum = (double *)PT_MALLOC(sizeof(double) * 3u * n);
    f->sum_sq = (double *)PT_MALLOC(sizeof(double) * 3u * n);
    f->count = (uint32_t *)PT_MALLOC(sizeof(uint32_t) * n);
    f->sum_odd = (double *)PT_MALLOC(sizeof(double) * 3u * n);
    f->low = (double *)PT_MALLOC(sizeof(double) * 9u * n);
    if (!f->sum || !f->sum_sq || !f->count || !f->sum_odd || !f->low) {
        pt_film_free(f);
        return PT_ERROR_OUT_OF_MEMORY;
    }
    f->width = w;
    f->height = h;
    pt_film_clear(f);
    return PT_OK;
}
PTDEF void pt_film_free(pt_film *f)
{
    if (!f) return;
    PT_FREE(f->sum);
    PT_FREE(f->sum_sq);
    PT_FREE(f->count);
    PT_FREE(f->sum_odd);
    PT_FREE(f->low);
    memset(f, 0, sizeof *f);
}
PTDEF void pt_film_clear(pt_film *f)
{
    size_t n;
    if (!f || !f->sum || !f->sum_sq || !f->count || !f->sum_odd || !pt__pixels(f->width, f->height, &n)) return;
    memset(f->sum, 0, sizeof(double) * 3u * n);
    memset(f->sum_sq, 0, sizeof(double) * 3u * n);
    memset(f->count, 0, sizeof(uint32_t) * n);
    memset(f->sum_odd, 0, sizeof(double) * 3u * n);
    if (f->low) memset(f->low, 0, sizeof(double) * 9u * n);
}
static int pt__film_ok(const pt_film *f, size_t *n)
{
    return f && f->sum && f->sum_sq && f->count && f->sum_odd && f->low && pt__pixels(f->width, f->height, n);
}
PTDEF int pt_film_add(pt_film *dst, const pt_film *src)
{
    size_t n, m, i;
    if (!pt__film_ok(dst, &n) || !src || !src->sum || !src->sum_sq || !src->count || !src->sum_odd ||
        !pt__pixels(src->width, src->height, &m) || src->width != dst->width || src->height != dst->height)
        return PT_ERROR_INVALID_ARGUMENT;
    for (i = 0; i < n; ++i)
        if (src->count[i] > 0xffffffffu - dst->count[i]) return PT_ERROR_INVALID_ARGUMENT;
    pt__film_add_raw(dst, src, n);
    return PT_OK;
}
PTDEF int pt_film_add_sample(pt_film *f, int x, int y, uint32_t k, pt_color v)
{
    size_t n, i;
    if (!pt__film_ok(f, &n) || x < 0 || y < 0 || x >= f->width || y >= f->height) return PT_ERROR_INVALID_ARGUMENT;
    i = (size_t)y * (size_t)f->width + (size_t)x;
    if (f->count[i] == 0xffffffffu) return PT_ERROR_INVALID_ARGUMENT;
    pt__film_sample(f->sum + 3u * i, f->sum_sq + 3u * i, f->sum_odd + 3u * i, f->low + 9u * i, k, v);
    f->count[i]++;
    return PT_OK;
}
PTDEF int pt_image_init(pt_image *img, int w, int h)
{
    size_t n;
    if (!img) return PT_ERROR_INVALID_ARGUMENT;
    memset(img, 0, sizeof *img);
    if (!pt__pixels(w, h, &n)) return PT_ERROR_INVALID_ARGUMENT;
    img->rgb = (float *)PT_MALLOC(sizeof(float) * 3u * n);
    if (!img->rgb) return PT_ERROR_OUT_OF_MEMORY;
    memset(img->rgb, 0, sizeof(float) * 3u * n);
    img->width = w;
    img->height = h;
    return PT_OK;
}
PTDEF void pt_image_free(pt_image *img)
{
    if (!img) return;
    PT_FREE(img->rgb);
    memset(img, 0, sizeof *img);
}
PTDEF int pt_film_resolve(const pt_film *f, pt_image *img)
{
    size_t n, i;
    int c;
    if (!f || !img || !f->sum || !f->count || !pt__pixels(f->width, f->height, &n)) return PT_ERROR_INVALID_ARGUMENT;
    if (!img->rgb || img->width != f->width || img->height != f->height) {
        int rc;
        pt_image_free(img);
        if ((rc = pt_image_init(img, f->width, f->height)) != PT_OK) return rc;
    }
    for (i = 0; i < n; ++i)
        for (c = 0; c < 3; ++c)
            img->rgb[3u * i + (size_t)c] = f->count[i] ? (float)(f->sum[3u * i + (size_t)c] / (double)f->count[i]) : 0.0f;
    return PT_OK;
}
PTDEF int pt_film_pixel(const pt_film *f, int x, int y, pt_color *mean, pt_color *var_of_mean)
{
    size_t i;
    double m[3], v[3], n;
    int c;
    if (!f || !f->sum || x < 0 || y < 0 || x >= f->width || y >= f->height) return PT_ERROR_INVALID_ARGUMENT;
    i = (size_t)y * (size_t)f->width + (size_t)x;
    n = (double)f->count[i];
    for (c = 0; c < 3; ++c) {
        m[c] = n > 0.0 ? f->sum[3u * i + (size_t)c] / n : 0.0;
        /* unbiased sample variance, divided by n for the variance of the mean */
        v[c] = n > 1.0 ? (f->sum_sq[3u * i + (size_t)c] - n * m[c] * m[c]) / (n - 1.0) / n : 0.0;
        if (v[c] < 0.0) v[c] = 0.0;
    }
    if (mean) *mean = pt_v3((float)m[0], (float)m[1], (float)m[2]);
    if (var_of_mean) *var_of_mean = pt_v3((float)v[0], (float)v[1], (float)v[2]);
    return PT_OK;
}

PTDEF int pt_film_error(const pt_film *f, int x0, int y0, int x1, int y1, double *rel_mse)
{
    int x, y, c;
    double acc = 0.0;
    if (rel_mse) *rel_mse = 0.0;
    if (!f || !f->sum || !f->count || !f->sum_odd || !rel_mse) return PT_ERROR_INVALID_ARGUMENT;
    if (x0 < 0) x0 = 0;
    if (y0 < 0) y0 = 0;
    if (x1 > f->width) x1 = f->width;
    if (y1 > f->height) y1 = f->height;
    if (x0 >= x1 || y0 >= y1) return PT_ERROR_INVALID_ARGUMENT;
    for (y = y0; y < y1; ++y)
        for (x = x0; x < x1; ++x) {
            size_t i = (size_t)y * (size_t)f->width + (size_t)x;
            uint32_t n = f->count[i], nb = n / 2u, na = n - nb; /* sample indices 0..n-1: nb odd ones */
            double dn = (double)n, scale;
            if (n < 2u) {
                *rel_mse = HUGE_VAL;
                return PT_OK;
            }
            scale = (double)na * (double)nb / (dn * dn);
            for (c = 0; c < 3; ++c) {
                double sb = f->sum_odd[3u * i + (size_t)c], sum = f->sum[3u * i + (size_t)c];
                double a = (sum - sb) / (double)na, b = sb / (double)nb, m = sum / dn;
                acc += (a - b) * (a - b) * scale / (m * m + 0.01);
            }
        }
    *rel_mse = acc / (3.0 * (double)(x1 - x0) * (double)(y1 - y0));
    if (!(*rel_mse < HUGE_VAL)) *rel_mse = HUGE_VAL; /* NaN from overflowing sums counts as unknown */
    return PT_OK;
}

/* ------------------------------------------------------------------------------------------
   9. Output: the sRGB transfer function (IEC 61966-2-1) and the PFM (linear float, bottom row
   first) and PPM (8-bit sRGB) writers. Each writer writes a temporary file beside the target
   and renames it into place, so that a failed write never leaves a partial image.
   ------------------------------------------------------------------------------------------ */

PTDEF float pt_srgb_encode(float x)
{
    if (!(x > 0.0f)) return 0.0f; /* also maps NaN to 0 */
    if (x >= 1.0f) return 1.0f;
    return x <= 0.0031308f ? 12.92f * x : 1.055f * powf(x, 1.0f / 2.4f) - 0.055f;
}
/* The inverse transfer function (IEC 61966-2-1), in double and rounded once: an 8-bit texel
   k / 255 decodes to the float nearest its exact linear value. */
PTDEF float pt_srgb_decode(float x)
{
    double e = x;
    if (!(x > 0.0f)) return 0.0f;
    if (x >= 1.0f) return 1.0f;
    return (float)(e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4));
}

/* Output temporaries. The registry lets a signal handler remove the temporaries in progress: a
   slot holds a name while its writer has the file open (live = 1). Slots are taken round-robin and
   a released name is freed only when its slot is taken again, so a handler running on another
   thread while a slot is released still reads a whole, unfreed name. */
#if (defined(__unix__) || defined(__unix) || defined(__APPLE__)) && \
    (defined(_POSIX_C_SOURCE) || defined(_XOPEN_SOURCE) || defined(_GNU_SOURCE))
#include <fcntl.h>
#include <unistd.h>
#define PT__POSIX_IO 1
#endif
#include <signal.h> /* sig_atomic_t */
#define PT__TMP_SLOTS 16
static char *volatile pt__tmp_name[PT__TMP_SLOTS];
static volatile sig_atomic_t pt__tmp_live[PT__TMP_SLOTS];
static unsigned pt__tmp_next, pt__tmp_counter;
#ifndef PDFTRACE_NO_THREADS
static pthread_mutex_t pt__tmp_lock = PTHREAD_MUTEX_INITIALIZER;
#define PT__TMP_LOCK() pthread_mutex_lock(&pt__tmp_lock)
#define PT__TMP_UNLOCK() pthread_mutex_unlock(&pt__tmp_lock)
#else
#define PT__TMP_LOCK() ((void)0)
#define PT__TMP_UNLOCK() ((void)0)
#endif

/* Takes a slot for name (-1: all busy); the old name of the slot is returned to be freed. */
static int pt__tmp_register(char *name, char **old)
{
    int k, slot = -1;
    PT__TMP_LOCK();
    for (k = 0; k < PT__TMP_SLOTS && slot < 0; ++k) {
        int i = (int)((pt__tmp_next + (unsigned)k) % PT__TMP_SLOTS);
        if (!pt__tmp_live[i]) slot = i;
    }
    *old = NULL;
    if (slot >= 0) {
        *old = pt__tmp_name[slot];
        pt__tmp_name[slot] = name;
        pt__tmp_live[slot] = 1;
        pt__tmp_next = (unsigned)slot + 1u;
    }
    PT__TMP_UNLOCK();
    return slot;
}
static void pt__tmp_release(int slot)
{
    if (slot < 0 || slot >= PT__TMP_SLOTS) return;
    PT__TMP_LOCK();
    pt__tmp_live[slot] = 0;
    PT__TMP_UNLOCK();
}
PTDEF void pt_output_remove_temporaries(void)
{
    int i;
    for (i = 0; i < PT__TMP_SLOTS; ++i) {
        char *name = pt__tmp_name[i];
        if (pt__tmp_live[i] && name) {
#ifdef PT__POSIX_IO
            unlink(name); /* async-signal-safe (POSIX.1-2008 2.4.3); remove() is not listed */
#else
            remove(name);
#endif
        }
    }
}

/* A name for the temporary: path + "." + 8 hex digits + ".ptmp"; the digits mix the process id,
   the clock, a per-process counter and the attempt, so concurrent writers rarely collide. */
static void pt__tmp_name_for(char *tmp, size_t len, const char *path, unsigned attempt)
{
    uint32_t h = 2166136261u, v[4];
    int k;
    PT__TMP_LOCK();
    v[0] = pt__tmp_counter++;
    PT__TMP_UNLOCK();
#ifdef PT__POSIX_IO
    v[1] = (uint32_t)getpid();
#else
    v[1] = (uint32_t)(uintptr_t)&h;
#endif
    v[2] = (uint32_t)time(NULL) ^ (uint32_t)clock();
    v[3] = attempt;
    for (k = 0; k < 16; ++k) h = (h ^ ((v[k / 4] >> (8 * (k % 4))) & 0xffu)) * 16777619u; /* FNV-1a */
    memcpy(tmp, path, len);
    snprintf(tmp + len, 15, ".%08lx.ptmp", (unsigned long)h);
}

/* Creates tmp exclusively; NULL with errno set on failure (EEXIST: the name is taken). */
static FILE *pt__tmp_create(const char *tmp, int text)
{
#ifdef PT__POSIX_IO
    int flags = O_WRONLY | O_CREAT | O_EXCL, fd;
    FILE *f;
#ifdef O_NOFOLLOW
    flags |= O_NOFOLLOW;
#endif
#ifdef O_CLOEXEC
    flags |= O_CLOEXEC;
#endif
    fd = open(tmp, flags, 0666); /* the umask applies, as for fopen */
    if (fd < 0) return NULL;
    f = fdopen(fd, text ? "w" : "wb");
    if (!f) {
        int e = errno;
        close(fd);
        unlink(tmp);
        errno = e;
    }
    return f;
#else
    FILE *f = fopen(tmp, "rb"); /* without POSIX: a check, then create (racy, see the declaration) */
    if (f) {
        fclose(f);
        errno = EEXIST;
        return NULL;
    }
    return fopen(tmp, text ? "w" : "wb");
#endif
}

PTDEF int pt_output_open(pt_output_file *t, const char *path, int text, const char *what, char *err, size_t err_size)
{
    size_t len;
    char *old = NULL;
    unsigned attempt;
    int e = 0;
    if (err && err_size) err[0] = '\0';
    if (!what) what = "output";
    if (!t) return pt__msg(err, err_size, PT_ERROR_INVALID_ARGUMENT, "%s: writing %s: no pt_output_file", path ? path : "(null)", what);
    memset(t, 0, sizeof *t);
    t->slot = -1;
    if (!path || !*path) return pt__msg(err, err_size, PT_ERROR_INVALID_ARGUMENT, "writing %s: no path", what);
    len = strlen(path);
    if (len > ((size_t)-1) - 16u || !(t->tmp_path = (char *)PT_MALLOC(len + 16u)))
        return pt__msg(err, err_size, PT_ERROR_OUT_OF_MEMORY, "%s: writing %s: out of memory", path, what);
    t->path = path;
    for (attempt = 0; attempt < 64u; ++attempt) {
        pt__tmp_name_for(t->tmp_path, len, path, attempt);
        errno = 0;
        if ((t->file = pt__tmp_create(t->tmp_path, text)) != NULL) break;
        e = errno;
        if (e != EEXIST) break;
    }
    if (!t->file) {
        int rc = pt__msg(err, err_size, PT_ERROR_IO, "%s: writing %s: cannot create '%s': %s", path, what, t->tmp_path,
                         e ? strerror(e) : "cannot create the file");
        PT_FREE(t->tmp_path);
        t->tmp_path = NULL;
        return rc;
    }
    t->slot = pt__tmp_register(t->tmp_path, &old);
    PT_FREE(old);
    errno = 0;
    return PT_OK;
}

/* A failure of pt_output_close's step: the message, then the temporary is removed. */
static int pt__output_fail(pt_output_file *t, int e, const char *step, const char *what, char *err, size_t err_size)
{
    int ren = strcmp(step, "cannot rename") == 0, rc;
    rc = pt__msg(err, err_size, PT_ERROR_IO, "%s: writing %s: %s '%s'%s%s%s: %s", t->path, what, step, t->tmp_path,
                 ren ? " to '" : "", ren ? t->path : "", ren ? "'" : "", e ? strerror(e) : "write error");
    remove(t->tmp_path);
    return rc;
}

PTDEF int pt_output_close(pt_output_file *t, int ok, const char *what, char *err, size_t err_size)
{
    int e = ok ? 0 : errno, rc = PT_OK;
    if (!what) what = "output";
    if (!t || !t->tmp_path) return PT_ERROR_INVALID_ARGUMENT;
    if (t->file) {
        errno = 0;
        if (fflush(t->file) != 0 || ferror(t->file)) {
            if (ok) e = errno;
            ok = 0;
        }
        errno = 0;
        if (fclose(t->file) != 0 && ok) {
            e = errno;
            ok = 0;
        }
        t->file = NULL;
    }
    if (!ok) {
        if (err && err_size && !err[0]) rc = pt__output_fail(t, e, "cannot write", what, err, err_size);
        else {
            remove(t->tmp_path);
            rc = PT_ERROR_IO;
        }
    } else {
#ifdef _WIN32
        remove(t->path); /* rename does not replace an existing file there */
#endif
        errno = 0;
        if (rename(t->tmp_path, t->path) != 0) rc = pt__output_fail(t, errno, "cannot rename", what, err, err_size);
    }
    pt__tmp_release(t->slot); /* the name stays allocated in the registry until its slot is reused */
    if (t->slot < 0) PT_FREE(t->tmp_path);
    t->tmp_path = NULL;
    t->slot = -1;
    return rc;
}

/* PFM and PPM through pt_output_open/close. errno is read right after the step that failed. */
typedef int (*pt__writer_fn)(FILE *f, const pt_image *img);
static int pt__write_atomic(const char *path, const pt_image *img, pt__writer_fn fn, const char *what, char *err,
                            size_t err_size)
{
    pt_output_file t;
    size_t n;
    int ok, rc;
    if (err && err_size) err[0] = '\0';
    if (!path || !*path) return pt__msg(err, err_size, PT_ERROR_INVALID_ARGUMENT, "writing %s: no path", what);
    if (!img) return pt__msg(err, err_size, PT_ERROR_INVALID_ARGUMENT, "%s: writing %s: image is NULL", path, what);
    if (!img->rgb || !pt__pixels(img->width, img->height, &n))
        return pt__msg(err, err_size, PT_ERROR_INVALID_ARGUMENT, "%s: writing %s: the image has no pixels (%d x %d%s)",
                       path, what, img->width, img->height, img->rgb ? "" : ", rgb NULL");
    if ((rc = pt_output_open(&t, path, 0, what, err, err_size)) != PT_OK) return rc;
    ok = fn(t.file, img);
    return pt_output_close(&t, ok, what, err, err_size);
}
static int pt__pfm_body(FILE *f, const pt_image *img)
{
    int x, y, c;
    unsigned char buf[12];
    if (fprintf(f, "PF\n%d %d\n-1.0\n", img->width, img->height) < 0) return 0;
    for (y = img->height - 1; y >= 0; --y) { /* PFM stores the bottom row first */
        for (x = 0; x < img->width; ++x) {
            for (c = 0; c < 3; ++c) {
                uint32_t u;
                float v = img->rgb[3u * ((size_t)y * (size_t)img->width + (size_t)x) + (size_t)c];
                memcpy(&u, &v, 4);
                buf[4 * c + 0] = (unsigned char)(u & 0xffu);
                buf[4 * c + 1] = (unsigned char)((u >> 8) & 0xffu);
                buf[4 * c + 2] = (unsigned char)((u >> 16) & 0xffu);
                buf[4 * c + 3] = (unsigned char)((u >> 24) & 0xffu);
            }
            if (fwrite(buf, 1, 12, f) != 12) return 0;
        }
    }
    return 1;
}
#ifndef PDFTRACE_PFM_MAX_PIXELS
#define PDFTRACE_PFM_MAX_PIXELS (1u << 28)
#endif
/* One header token of a PFM (whitespace-separated); 0 at end of file or if it is too long. */
static int pt__pfm_token(FILE *f, char *tok, size_t n)
{
    size_t k = 0;
    int c;
    do c = fgetc(f);
    while (c == ' ' || c == '\t' || c == '\n' || c == '\r');
    while (c != EOF && c != ' ' && c != '\t' && c != '\n' && c != '\r') {
        if (k + 1 >= n) return 0;
        tok[k++] = (char)c;
        c = fgetc(f);
    }
    tok[k] = '\0';
    return k > 0 && c != EOF; /* (one whitespace byte ends the last token, before the data) */
}
PTDEF int pt_read_pfm(const char *path, pt_image *out, char *err, size_t err_size)
{
    char magic[8], ws[16], hs[16], ss[64], *end;
    long w, h;
    double scale;
    int channels, little, x, y, c, rc;
    FILE *f;
    unsigned char buf[12];
    if (out) memset(out, 0, sizeof *out);
    if (!path || !out) return pt__msg(err, err_size, PT_ERROR_INVALID_ARGUMENT, "pt_read_pfm: %s is NULL", path ? "out" : "path");
    f = fopen(path, "rb");
    if (!f) return pt__msg(err, err_size, PT_ERROR_IO, "%s: cannot open: %s", path, strerror(errno));
    if (!pt__pfm_token(f, magic, sizeof magic) || (strcmp(magic, "PF") && strcmp(magic, "Pf")) ||
        !pt__pfm_token(f, ws, sizeof ws) || !pt__pfm_token(f, hs, sizeof hs) || !pt__pfm_token(f, ss, sizeof ss)) {
        fclose(f);
        return pt__msg(err, err_size, PT_ERROR_IO, "%s: not a PFM file (no 'PF'/'Pf' header with width, height and scale)", path);
    }
    channels = magic[1] == 'F' ? 3 : 1;
    w = strtol(ws, &end, 10);
    if (*end || w <= 0 || w > 1000000) w = -1;
    h = strtol(hs, &end, 10);
    if (*end || h <= 0 || h > 1000000) h = -1;
    scale = strtod(ss, &end);
    if (w < 0 || h < 0 || *end || !(scale == scale) || scale == 0.0) {
        fclose(f);
        return pt__msg(err, err_size, PT_ERROR_IO, "%s: bad PFM header (width and height 1 .. 1000000, a finite non-zero scale)",
                       path); /* (the file's bytes are not quoted: it may be anyone's) */
    }
    if ((unsigned long)w * (unsigned long)h > (unsigned long)PDFTRACE_PFM_MAX_PIXELS) {
        fclose(f);
        return pt__msg(err, err_size, PT_ERROR_UNSUPPORTED, "%s: %ld x %ld pixels: more than PDFTRACE_PFM_MAX_PIXELS (%lu)", path,
                       w, h, (unsigned long)PDFTRACE_PFM_MAX_PIXELS);
    }
    little = scale < 0.0;
    if ((rc = pt_image_init(out, (int)w, (int)h)) != PT_OK) {
        fclose(f);
        return pt__msg(err, err_size, rc, "%s: out of memory for %ld x %ld pixels", path, w, h);
    }
    for (y = (int)h - 1; y >= 0; --y) /* the bottom row first */
        for (x = 0; x < (int)w; ++x) {
            float *px = out->rgb + 3u * ((size_t)y * (size_t)w + (size_t)x);
            if (fread(buf, 4, (size_t)channels, f) != (size_t)channels) {
                fclose(f);
                pt_image_free(out);
                return pt__msg(err, err_size, PT_ERROR_IO, "%s: truncated: the data ends in row %d of %ld (from the bottom)", path,
                               (int)h - 1 - y, h);
            }
            for (c = 0; c < channels; ++c) {
                const unsigned char *b = buf + 4 * c;
                uint32_t u = little ? (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24
                                    : (uint32_t)b[3] | (uint32_t)b[2] << 8 | (uint32_t)b[1] << 16 | (uint32_t)b[0] << 24;
                memcpy(&px[c], &u, 4);
            }
            if (channels == 1) px[1] = px[2] = px[0];
        }
    fclose(f);
    if (err && err_size) err[0] = '\0';
    return PT_OK;
}
static int pt__ppm_body(FILE *f, const pt_image *img)
{
    int x, y, c;
    unsigned char px[3];
    if (fprintf(f, "P6\n%d %d\n255\n", img->width, img->height) < 0) return 0;
    for (y = 0; y < img->height; ++y) {
        for (x = 0; x < img->width; ++x) {
            for (c = 0; c < 3; ++c) {
                float v = img->rgb[3u * ((size_t)y * (size_t)img->width + (size_t)x) + (size_t)c];
                px[c] = (unsigned char)(pt_srgb_encode(v) * 255.0f + 0.5f);
            }
            if (fwrite(px, 1, 3, f) != 3) return 0;
        }
    }
    return 1;
}
PTDEF int pt_write_pfm_ex(const char *path, const pt_image *img, char *err, size_t err_size)
{
    return pt__write_atomic(path, img, pt__pfm_body, "PFM", err, err_size);
}
PTDEF int pt_write_ppm_ex(const char *path, const pt_image *img, char *err, size_t err_size)
{
    return pt__write_atomic(path, img, pt__ppm_body, "PPM", err, err_size);
}
PTDEF int pt_write_pfm(const char *path, const pt_image *img) { return pt_write_pfm_ex(path, img, NULL, 0); }
PTDEF int pt_write_ppm(const char *path, const pt_image *img) { return pt_write_ppm_ex(path, img, NULL, 0); }

/* Display transform (formulas and sources at the declaration of pt_image_apply_display). */
static float pt__display_channel(double v, pt_tonemap op)
{
    if (!(v > 0.0)) return 0.0f; /* negative values and NaN */
    if (v > 1e100) return 1.0f;  /* every operator gives 1 in float here (and ACES's products would overflow) */
    if (op == PT_TONEMAP_REINHARD) v = v / (1.0 + v);
    else if (op == PT_TONEMAP_ACES) v = v * (2.51 * v + 0.03) / (v * (2.43 * v + 0.59) + 0.14);
    return v < 1.0 ? (float)v : 1.0f;
}
PTDEF int pt_image_apply_display(const pt_image *src, const pt_display_desc *d, pt_image *dst)
{
    pt_display_desc dd;
    size_t n, i;
    double scale;
    dd.exposure = 0.0f;
    dd.tonemap = PT_TONEMAP_CLAMP;
    if (d) dd = *d;
    if (!src || !dst || !src->rgb || !pt__pixels(src->width, src->height, &n)) return PT_ERROR_INVALID_ARGUMENT;
    if (!pt__isfinite(dd.exposure) ||
        (dd.tonemap != PT_TONEMAP_CLAMP && dd.tonemap != PT_TONEMAP_REINHARD && dd.tonemap != PT_TONEMAP_ACES))
        return PT_ERROR_INVALID_ARGUMENT;
    if (dst != src && (!dst->rgb || dst->width != src->width || dst->height != src->height)) {
        int rc;
        pt_image_free(dst);
        if ((rc = pt_image_init(dst, src->width, src->height)) != PT_OK) return rc;
    }
    scale = pow(2.0, (double)dd.exposure); /* exact for whole EVs; 0: 1, so CLAMP alone is min(max(x, 0), 1) */
    for (i = 0; i < 3u * n; ++i) dst->rgb[i] = pt__display_channel((double)src->rgb[i] * scale, dd.tonemap);
    return PT_OK;
}

#ifdef __cplusplus
}
#endif

PT__CONTRACT_RESTORE

/* PDFTRACE_IMPLEMENTATION_COMPLETE */
#endif /* PDFTRACE_IMPLEMENTATION_DONE */
#endif /* PDFTRACE_IMPLEMENTATION */

/*
This software is available under 2 licenses -- choose whichever you prefer.
------------------------------------------------------------------------------
ALTERNATIVE A - MIT License
Copyright (c) 2026 the pdftrace authors
Permission is hereby granted, free of charge, to any person obtaining a copy of
this software and associated documentation files (the "Software"), to deal in
the Software without restriction, including without limitation the rights to
use, copy, modify, merge, publish, distribute, sublicense, and/or sell copies
of the Software, and to permit persons to whom the Software is furnished to do
so, subject to the following conditions:
The above copyright notice and this permission notice shall be included in all
copies or substantial portions of the Software.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS OR COPYRIGHT HOLDERS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER
LIABILITY, WHETHER IN AN ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM,
OUT OF OR IN CONNECTION WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE
SOFTWARE.
------------------------------------------------------------------------------
ALTERNATIVE B - Public Domain (www.unlicense.org)
This is free and unencumbered software released into the public domain.
Anyone is free to copy, modify, publish, use, compile, sell, or distribute this
software, either in source code form or as a compiled binary, for any purpose,
commercial or non-commercial, and by any means.
In jurisdictions that recognize copyright laws, the author or authors of this
software dedicate any and all copyright interest in the software to the public
domain. We make this dedication for the benefit of the public at large and to
the detriment of our heirs and successors. We intend this dedication to be an
overt act of relinquishment in perpetuity of all present and future rights to
this software under copyright law.
THE SOFTWARE IS PROVIDED "AS IS", WITHOUT WARRANTY OF ANY KIND, EXPRESS OR
IMPLIED, INCLUDING BUT NOT LIMITED TO THE WARRANTIES OF MERCHANTABILITY,
FITNESS FOR A PARTICULAR PURPOSE AND NONINFRINGEMENT. IN NO EVENT SHALL THE
AUTHORS BE LIABLE FOR ANY CLAIM, DAMAGES OR OTHER LIABILITY, WHETHER IN AN
ACTION OF CONTRACT, TORT OR OTHERWISE, ARISING FROM, OUT OF OR IN CONNECTION
WITH THE SOFTWARE OR THE USE OR OTHER DEALINGS IN THE SOFTWARE.
------------------------------------------------------------------------------
*/
