/* pdftrace_scene.h - scene files, Wavefront OBJ meshes, POV-Ray and Mitsuba 3 export for pdftrace.h.
   Part of the pdftrace header family. LICENSE: MIT or public domain, your choice (full text at
   the end of this file).

   ABOUT
   =====
   Reads pdftrace's plain-text scene format (below) and Wavefront OBJ meshes, builds a
   committed pt_scene from them through pdftrace.h's public API, and writes the same scene
   for POV-Ray 3.7 and for Mitsuba 3, the project's reference renderers. Nothing here reaches
   into the core's internals: a parsed scene file (pt_scenefile) is plain data a program may
   inspect, edit or build itself.

   BUILDING
   ========
   In exactly one C or C++ file (it may be the file that implements pdftrace.h, or another):
       #define PDFTRACE_SCENE_IMPLEMENTATION
       #include "pdftrace_scene.h"
   This header includes pdftrace.h; define PDFTRACE_IMPLEMENTATION before it in the same file
   to implement both there. No extra libraries.

   USAGE
   =====
       pt_scenefile sf; pt_scene *scene; pt_render_desc rd; char err[512];
       if (pt_scenefile_load("scenes/cornell.scene", &sf, err, sizeof err) != PT_OK) { puts(err); ... }
       if (pt_scenefile_build(&sf, &scene, &rd, err, sizeof err) != PT_OK) { puts(err); ... }
       ... pt_render_image(scene, &rd, &img, NULL) ...
       pt_scene_destroy(scene); pt_scenefile_free(&sf);
   A mesh in one call, under the scene's current transform:
       int first = pt_scene_add_obj(scene, "bunny.obj", material, err, sizeof err);

   SCENE FILES
   ===========
   A scene file is plain text, one statement per line, `#` starts a comment; tokens are
   separated by blanks. The format, in full:

     size W H                         image size (default 256 256; 1..16384)
     spp N                            samples per pixel (default 64)
     max_depth N                      scattering events per path (default 50; 1 = direct only)
     strategy mis|material|light|mixture
     sampler independent|sobol        where random numbers come from (default sobol:
                                      scrambled Sobol points, pdftrace.h section 2)
     integrator scalar|batched        how paths are traced (batched: a tile's paths a bounce at
                                      a time, the same image; default: pt_integrator)
     indirect_paths N                 paths each camera sample continues as from its first
                                      non-delta vertex (1..8; default 3 with sobol, else 1)
     seed N                           random seed (default 0)
     guiding off|on|auto              path guiding (pdftrace.h, pt_render_desc.guiding): on
                                      learns a guide in the first guiding_budget of the
                                      samples and renders the rest with it; auto renders the
                                      rest guided only if training measured a gain (default off)
     guiding_budget F                 the share of spp training may take, 0 < F < 1 (0.25)
     guiding_alpha F                  the material's share of the guided mixture alpha
                                      p_material + (1 - alpha) p_guide, 0 < F < 1 (0.7)
     guiding_memory MIB               the guide's memory bound in MiB, 1..1048576 (64)
     background R G B                 radiance of rays leaving the scene (default 0 0 0)
     camera look_from X Y Z look_at X Y Z [up X Y Z] [vfov DEGREES]      (required, once)
            [lens_radius R] [focus_distance D]   depth of field: a thin lens of radius R >= 0 (0,
                                      the default: a pinhole) focused at distance D > 0
                                      (default |look_at - look_from|)
     checker NAME R G B R G B SCALE   a texture: the second colour where
                                      floor(x/s)+floor(y/s)+floor(z/s) is odd
     image_texture NAME FILE [raw]    an image looked up at the surface's (u, v) (pdftrace.h,
                                      pt_scene_add_image_texture: bilinear, repeated; pt_hit
                                      has each shape's (u, v)); FILE as a mesh path: PFM or
                                      OpenEXR (linear), or PNG (8-bit sRGB, decoded to linear;
                                      raw: codes / 255 as they are, for non-colour data) when the
                                      loader has a reader for it (pt_scenefile_options.read_png,
                                      read_image); pixels finite and >= 0
     material NAME lambertian R G B | lambertian texture CHECKER_OR_IMAGE
     material NAME metal R G B [fuzz F]
     material NAME roughconductor ALPHA METAL [tint R G B]   GGX rough metal (pdftrace.h,
                                      PT_MATERIAL_ROUGH_CONDUCTOR): ALPHA in [0, 1] (below 1e-3
                                      the smooth Fresnel mirror), METAL one of Au Ag Cu Al
                                      none (F = 1) or `eta R G B k R G B`; tint (default 1 1 1)
                                      multiplies the Fresnel reflectance
     material NAME roughplastic ALPHA R G B | roughplastic ALPHA texture CHECKER
            [ior IOR] [nonlinear]     a diffuse base of albedo R G B (each in [0, 1]) under a
                                      GGX dielectric coat (pdftrace.h, PT_MATERIAL_ROUGH_PLASTIC;
                                      Mitsuba 3's roughplastic): ALPHA in [0, 1] (below 1e-3 the
                                      coat is rendered at 1e-3), IOR > 1 (default 1.5);
                                      nonlinear: the colour shift of internal scattering
     material NAME dielectric IOR
     material NAME roughdielectric ALPHA IOR [ext_ior E]   GGX rough glass (pdftrace.h,
                                      PT_MATERIAL_ROUGH_DIELECTRIC): ALPHA in [0, 1], IOR inside
                                      and E outside (default 1) in [1, 10]; below alpha 1e-3 the
                                      smooth interface
     material NAME emitter R G B [two_sided]
     sphere CX CY CZ RADIUS MATERIAL
     quad QX QY QZ UX UY UZ VX VY VZ MATERIAL      Q + a*u + b*v; normal (emitting side) u x v
     triangle AX AY AZ BX BY BZ CX CY CZ MATERIAL
     box LOX LOY LOZ HIX HIY HIZ MATERIAL
     mesh PATH MATERIAL               Wavefront OBJ (v, vn, vt, f; faces fanned into triangles;
                                      vt read as (u, 1 - v), as Mitsuba 3 reads OBJ),
                                      PATH relative to the scene file's directory and
                                      inside it (below); a file is read once
     point_light X Y Z R G B          a point light of intensity R G B (W/sr)
     spot_light X Y Z TX TY TZ R G B [CUTOFF [BEAM]]   a spot light at X Y Z pointing at the
                                      target TX TY TZ, intensity R G B (W/sr) on its axis,
                                      falling off linearly in the angle from BEAM to CUTOFF
                                      degrees from the axis (Mitsuba 3's spot); CUTOFF in
                                      (0, 90] (default 20), BEAM in (0, CUTOFF] (default 3/4
                                      of CUTOFF; BEAM = CUTOFF: a hard-edged cone)
     directional_light DX DY DZ R G B a light from infinitely far travelling along DX DY DZ
                                      (the sun), irradiance R G B (W/m^2) on a surface facing it
                                      (lights: pdftrace.h, pt_light_desc; they are not seen by
                                      the camera and are reached by shadow rays only)
     environment FILE [SCALE]         an equirectangular environment map of linear RGB
                                      radiance (pdftrace.h, pt_environment_desc), times SCALE
                                      > 0 (default 1), added to the background; FILE as a mesh
                                      path (below), PFM, or OpenEXR when the loader has a
                                      reader for it (pt_scenefile_options.read_image); turned
                                      by the transform in effect, which must be a rotation; once
     translate X Y Z | rotate AX AY AZ DEGREES | scale SX SY SZ | identity
                                      transforms for the shapes and lights that follow (a
                                      light's position as a point, its direction as a
                                      vector; cone angles are kept); each one is
                                      applied after those before it (as in POV-Ray);
                                      identity starts again. Composed in double: a scene
                                      far from the origin is handed to pdftrace relative
                                      to its centre (pt_scene_set_origin)
     pov_light_grid N                 POV-Ray export: N x N spotlights per quad emitter (16)
     pov_radiosity none|default|medium|high       POV-Ray export: indirect light (none)

   Numbers must be finite with magnitude <= 1e7; colours >= 0; names are [A-Za-z_][A-Za-z0-9_-]*
   up to 31 characters and must be defined before use. Every error is reported as
   "file:line: message" and the load fails as a whole (nothing is left allocated). A UTF-8
   byte order mark at the start is skipped. The guiding statements are render settings, not
   scene content: both exporters accept and ignore them.

   UNTRUSTED FILES (pt_scenefile_options; docs/scene-format.md has the details)
   Only regular files are read (opened without blocking, checked with fstat). Mesh and
   environment paths must resolve (realpath) inside the scene's directory or an allowed one,
   else they are refused before being opened; a map file is read whole (at most 256 MB). A file that is not OBJ is named, never quoted; messages write control
   bytes as \xNN. Meshes may take mesh_memory bytes while loading (1 GiB) and `size` is
   refused above image_memory bytes of film and images (4 GiB).

   POV-RAY EXPORT
   ==============
   The POV-Ray 3.7 exporter follows the recipe in docs/povray.md (with its measured tolerances):
   camera `angle` from the vertical FOV with `right -x*W/H` and `sky`;
   fade-trick lights (attenuation 2/(1+(d/fd)^2) so colour = I/(2 pi fd^2)); an N x N
   spotlight grid per quad emitter (tightness 1, radius = falloff = 90 gives the cosine
   profile) a hair in front of it, the visible emitter as `emission 1` plus a black twin; a
   sphere emitter as one point light of intensity L*pi*r^2 (exact for a Lambertian sphere
   above the horizon); glass as rgbf 1 + fresnel reflection + conserve_energy, no_shadow,
   with an opaque twin; mirrors as `reflection`; checker as POV's checker (same parity);
   meshes as mesh2 with normal_vectors; a point light as a fade-trick point light of colour
   I/(2 pi fd^2), a hard-cone spot (beam = cutoff) as the same with `spotlight radius A falloff
   A tightness 0`, a directional light as a `parallel` light of colour E/pi placed outside the
   scene's bounds (POV-Ray does not trace a parallel light's shadow rays to infinity: an
   occluder behind its location casts at most part of its shadow); `assumed_gamma 1.0`,
   `ambient_light 0`, ambient 0. Not exportable (PT_ERROR_UNSUPPORTED with file:line): a
   thin-lens camera (POV-Ray's focal blur stops adaptively after a few aperture samples: no
   exact twin), an environment map (POV-Ray's sky_sphere lights diffuse surfaces only through
   radiosity, which misses a small bright sun), fuzzy metal, a rough conductor (POV-Ray has no
   microfacet reflection nor conductor Fresnel; only metal none below alpha 1e-3, a coloured
   mirror, is exported), a rough plastic (no microfacet reflection nor layered coat in POV-Ray),
   a rough dielectric (no microfacet refraction either), an image texture (POV-Ray's uv_mapping
   and image_map filtering are not pdftrace's), emitting triangles, boxes or meshes, a spot
   light whose beam is
   narrower than its cutoff (POV-Ray's falloff is a smoothstep in the cosine of the angle,
   pdftrace's linear in the angle); and every scene pt_scenefile_build refuses (the exporter
   runs the build first, so it never writes what pdftrace would not render, such as a sphere
   under a non-uniform scale), or one that would need a non-finite number. The scene's file name is
   the only text from input in the output, in comments, escaped by pt_scenefile_escape.

   MITSUBA 3 EXPORT
   ================
   pt_scenefile_export_mitsuba writes an exact twin for Mitsuba 3 (docs/mitsuba.md has the
   mapping, why each piece is exact, and measurements): the `path` integrator with max_depth
   = pdftrace's + 1 (Mitsuba counts the camera segment) and its default Russian roulette; a
   `perspective` sensor (fov_axis y, lookat), a thin lens as `thinlens`; `hdrfilm` float RGB
   with a box filter; the `independent` sampler; quads and box faces as `rectangle` with the
   exact to_world (columns u/2, v/2, unit u x v, centre); spheres; triangles and meshes as
   binary little-endian PLY files "<xml without .xml>.N.ply" beside the XML (vertex normals
   kept, else face_normals); Lambertian as two-sided `diffuse`, a mirror as a two-sided
   `conductor` of material "none", a rough conductor as a two-sided `roughconductor`
   (distribution ggx, sample_visible true, alpha, RGB eta and k or material "none", the tint as
   specular_reflectance; below alpha 1e-3 the smooth `conductor`), a rough plastic as a two-sided
   `roughplastic` (ggx, sample_visible, alpha at least 1e-3, int_ior, ext_ior 1,
   diffuse_reflectance, nonlinear), glass as `dielectric`, a rough dielectric as
   `roughdielectric` (ggx, sample_visible, alpha, int_ior and ext_ior; the smooth `dielectric`
   below pdftrace's delta switch), an emitter as a one-sided `area`
   light on its shape with a black bsdf, an image texture as a `bitmap` (filter_type bilinear,
   wrap_mode repeat; its linear pixels beside the XML as "<xml without .xml>.tex.N.pfm"; mesh
   uvs in the PLY), the background as a `constant` emitter, an
   environment map as an `envmap` emitter (to_world the rotation) of a map resampled to 2H + 1
   rows beside the XML ("<xml without .xml>.env.pfm"), which makes Mitsuba's row interpolation
   pdftrace's exactly, with the background added to it (Mitsuba takes one environment emitter
   per scene), the point, spot and directional lights as Mitsuba's `point`, `spot` (to_world a lookat along the axis)
   and `directional` emitters (the same units and falloff). Refused with
   file:line and the reason (PT_ERROR_UNSUPPORTED, nothing written): fuzzy metal, the 3-D
   checker, two-sided emitters, an albedo (or an image texture's value) above 1, a dielectric of ior 1, and, as for
   POV-Ray, every scene the build refuses and one that needs a non-finite number.
*/
#ifndef PDFTRACE_SCENE_H
#define PDFTRACE_SCENE_H

#if defined(PDFTRACE_SCENE_IMPLEMENTATION) && !defined(_POSIX_C_SOURCE) && !defined(_GNU_SOURCE) && \
    !defined(_WIN32) && !defined(__cplusplus)
#define _POSIX_C_SOURCE 200809L /* open, fstat, realpath; effective only when this header is the first one included */
#endif
#include "pdftrace.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PT_SCENEFILE_NAME_MAX 32

typedef enum pt_scenefile_shape_type {
    PT_SCENEFILE_SPHERE = 0, PT_SCENEFILE_QUAD, PT_SCENEFILE_TRIANGLE, PT_SCENEFILE_BOX, PT_SCENEFILE_MESH
} pt_scenefile_shape_type;

typedef struct pt_scenefile_checker {
    char name[PT_SCENEFILE_NAME_MAX];
    pt_color even, odd;
    float scale;
} pt_scenefile_checker;

/* An `image_texture` statement: the pixels as the build hands them to pt_scene_add_image_texture
   (linear: an 8-bit PNG decoded from sRGB unless raw). */
typedef struct pt_scenefile_image {
    char name[PT_SCENEFILE_NAME_MAX];
    pt_image image;
    int raw;                     /* `raw`: a PNG's codes kept as they are (non-colour data) */
    int line;                    /* line of the statement, for messages */
} pt_scenefile_image;

typedef struct pt_scenefile_material {
    char name[PT_SCENEFILE_NAME_MAX];
    pt_material_type type;
    pt_color albedo;             /* lambertian, metal */
    int checker;                 /* -1, or an index into pt_scenefile.checkers (lambertian) */
    int image;                   /* -1, or an index into pt_scenefile.images (lambertian) */
    float fuzz, ior;
    pt_color emission;           /* emitter */
    int two_sided;
    float roughness;             /* roughconductor: GGX alpha; albedo is its tint */
    pt_conductor conductor;
    pt_color eta, k;             /* PT_CONDUCTOR_CUSTOM */
    int nonlinear;               /* roughplastic (roughness, ior; albedo or checker: the base) */
    float ext_ior;               /* roughdielectric: the index outside (ior is inside's) */
} pt_scenefile_material;

typedef struct pt_obj_mesh {
    float *positions;            /* 3 per vertex, object space */
    float *normals;              /* 3 per vertex, or NULL */
    uint32_t *indices;           /* 3 per triangle */
    float *uvs;                  /* 2 per vertex (pt_mesh_desc.uvs: the file's vt as (u, 1 - v), as
                                    Mitsuba 3 reads OBJ), or NULL */
    uint32_t vertex_count, triangle_count;
} pt_obj_mesh;

typedef struct pt_scenefile_shape {
    pt_scenefile_shape_type type;
    int material;                /* index into pt_scenefile.materials */
    pt_vec3 p[3];                /* sphere: centre; quad: q u v; triangle: a b c; box: lo hi */
    float radius;                /* sphere */
    int mesh;                    /* PT_SCENEFILE_MESH: index into pt_scenefile.meshes */
    pt_transform transform;      /* object to world, in effect when the shape was read */
    double transform_d[3][4];    /* the same composed in double (transform is it rounded) */
    int line;                    /* line of the statement, for messages */
} pt_scenefile_shape;

/* A point_light, spot_light or directional_light statement. desc is the light as written:
   position and direction in the statement's own space (the spot's direction is target -
   position), the spot's cutoff and beam angles with their defaults filled in; the build hands
   it to pt_scene_add_light under the transform. */
typedef struct pt_scenefile_light {
    pt_light_desc desc;
    pt_transform transform;      /* object to world, in effect when the light was read */
    double transform_d[3][4];    /* the same composed in double (transform is it rounded) */
    int line;                    /* line of the statement, for messages */
} pt_scenefile_light;

typedef struct pt_scenefile {
    char file[256];              /* the name used in messages */
    int width, height, samples_per_pixel, max_depth;
    pt_strategy strategy;
    pt_sampler sampler;
    pt_integrator integrator;    /* `integrator`; 0: pt_render_desc's default */
    int indirect_paths;          /* 0: pt_render_desc's default */
    pt_guiding guiding;          /* `guiding`; without one the loader's default (PT_GUIDING_OFF) */
    float guiding_budget;        /* `guiding_budget`, in (0, 1); 0: pt_render_desc's default */
    float guiding_alpha;         /* `guiding_alpha`, in (0, 1); 0: pt_render_desc's default */
    int guiding_memory;          /* `guiding_memory` in MiB (guiding_max_mib); 0: its default */
    uint64_t seed;
    pt_color background;
    pt_camera_desc camera;
    int camera_line;             /* line of the camera statement, for messages */
    int pov_light_grid;          /* N: N x N spotlights per quad emitter */
    int pov_radiosity;           /* 0 none, 1 POV defaults, 2 medium, 3 high (docs/povray.md) */
    pt_scenefile_checker *checkers; int checker_count;
    pt_scenefile_image *images; int image_count;
    pt_scenefile_material *materials; int material_count;
    pt_scenefile_shape *shapes; int shape_count;
    pt_scenefile_light *lights; int light_count; /* in the file's order (their ids in the scene) */
    pt_obj_mesh *meshes; int mesh_count; /* one per distinct OBJ file: mesh statements naming the
                                            same file share it (shapes[i].mesh) */
    uint64_t mesh_bytes;         /* bytes the meshes hold (positions, normals, indices) */
    /* `environment FILE [SCALE]`: the map as read (linear RGB, row 0 the zenith; width 0: no
       statement), its scale, and the transform in effect (the build requires a rotation) */
    pt_image environment;
    float environment_scale;
    pt_transform environment_transform;
    int environment_line;        /* line of the statement, for messages (0: none) */
} pt_scenefile;

/* What the loader may read and allocate. Zero fields take the defaults, so a zeroed struct
   (or a NULL pointer) gives the defaults everywhere. */
#define PT_SCENEFILE_MESH_MEMORY_DEFAULT ((uint64_t)1 << 30)  /* 1 GiB */
#define PT_SCENEFILE_IMAGE_MEMORY_DEFAULT ((uint64_t)4 << 30) /* 4 GiB: about 5000 x 5000 pixels */
typedef struct pt_scenefile_options {
    /* Bytes the loader may use for meshes: the parsed meshes kept, plus the OBJ text and the
       working arrays of the one being parsed. 0: PT_SCENEFILE_MESH_MEMORY_DEFAULT. */
    uint64_t mesh_memory;
    /* The largest pt_scenefile_image_bytes(W, H) a `size` statement may ask for.
       0: PT_SCENEFILE_IMAGE_MEMORY_DEFAULT. */
    uint64_t image_memory;
    /* Mesh paths must resolve (symbolic links and `..` followed) inside the scene file's
       directory or one of these directories; anything else is refused before it is opened. */
    const char *const *allowed_dirs;
    int allowed_dir_count;
    /* Decodes an environment map that is not PFM from the file's bytes (data, size; name for
       messages) into *out, as pt_read_exr_memory of pdftrace_exr.h does (pass it): PT_OK, or an
       error code with a message in err. NULL: only PFM maps are read, and an .exr map is
       refused as needing OpenEXR. */
    int (*read_image)(const void *data, size_t size, const char *name, pt_image *out, char *err, size_t err_size);
    /* Decodes a .png image texture, as pt_read_png_memory of pdftrace_png.h does (pass it):
       channels as their 8-bit codes / 255, which the loader decodes from sRGB unless the
       statement says raw. NULL: a .png texture is refused as needing libpng. */
    int (*read_png)(const void *data, size_t size, const char *name, pt_image *out, char *err, size_t err_size);
} pt_scenefile_options;

/* Loads a scene file. On failure returns an error code, writes "file:line: message" to
   err (err_size bytes, may be 0) and leaves *out empty (nothing to free). Only regular files
   are read (a FIFO or a device is refused without blocking). */
PTDEF int pt_scenefile_load(const char *path, pt_scenefile *out, char *err, size_t err_size);
/* The same with options (NULL: the defaults). */
PTDEF int pt_scenefile_load_ex(const char *path, const pt_scenefile_options *opt, pt_scenefile *out, char *err,
                               size_t err_size);
/* The same from text in memory; `name` is used in messages, meshes are read relative to
   base_dir (NULL: the current directory), which is also the directory they must lie in. */
PTDEF int pt_scenefile_parse(const char *text, size_t length, const char *name, const char *base_dir,
                             pt_scenefile *out, char *err, size_t err_size);
PTDEF int pt_scenefile_parse_ex(const char *text, size_t length, const char *name, const char *base_dir,
                                const pt_scenefile_options *opt, pt_scenefile *out, char *err, size_t err_size);
/* Bytes a render of a width x height image needs for its pt_film (three exact sums of two
   doubles each, 3 channels, and a count per pixel) and two float RGB images (the resolved one and its display copy). */
PTDEF uint64_t pt_scenefile_image_bytes(int width, int height);
PTDEF void pt_scenefile_free(pt_scenefile *desc);
/* Parses a Wavefront OBJ file held in memory (the subset the `mesh` statement reads) into
   *out; `name` is used in messages ("name:line: message"). On failure *out is left empty.
   Free the result with pt_obj_mesh_free. */
PTDEF int pt_obj_parse(const char *text, size_t length, const char *name, pt_obj_mesh *out, char *err,
                       size_t err_size);
PTDEF void pt_obj_mesh_free(pt_obj_mesh *mesh);
/* The pt_mesh_desc that adds a parsed mesh with the given material (the arrays are not copied). */
PTDEF pt_mesh_desc pt_obj_mesh_desc(const pt_obj_mesh *mesh, int material);
/* Reads and parses the OBJ file at path (messages "path:line: message"); only a regular file
   is read. A file whose first statement is not an OBJ keyword is refused as "not an OBJ
   file" without quoting it. */
PTDEF int pt_obj_load(const char *path, pt_obj_mesh *out, char *err, size_t err_size);
/* Loads the OBJ file at path and adds its triangles to the scene with the given material,
   under the scene's current transform (pt_scene_set_transform), as pt_scene_add_mesh does.
   Returns the first primitive's id, or an error code with a message in err. */
PTDEF int pt_scene_add_obj(pt_scene *scene, const char *path, int material, char *err, size_t err_size);
/* Builds a committed scene (the shapes, then the lights in the file's order, so lights[i] is
   the scene's light i, then the environment map) and fills *render (size, spp, depth, strategy, sampler, indirect paths,
   seed, camera, background, guiding and its budget, alpha and memory bound; other fields zero)
   with the public API. On failure *scene is NULL. */
PTDEF int pt_scenefile_build(const pt_scenefile *desc, pt_scene **scene, pt_render_desc *render, char *err,
                             size_t err_size);

typedef struct pt_pov_options {
    int radiosity;               /* -1: the scene's pov_radiosity; else 0..3 as there */
    int light_grid;              /* 0: the scene's pov_light_grid */
    int width, height;           /* 0: the scene's size (used for the camera's aspect ratio) */
} pt_pov_options;
/* How pt_scenefile_escape writes text taken from input into an exporter's output. */
typedef enum pt_scenefile_escape_mode {
    /* Inside a comment of POV-Ray (or C, or any format with line or block comments): keeps
       A-Z a-z 0-9 and " ._-+/:,=@~", writes every other byte as \xNN. No newline, `*`, `#`,
       quote or backslash remains, so the text can neither end a comment nor start one. */
    PT_SCENEFILE_ESCAPE_COMMENT = 0,
    /* XML text or a quoted attribute value: & < > " ' as entities; control bytes, DEL and
       bytes >= 0x80 as '?' (so the result is plain ASCII and well-formed). Not for comments. */
    PT_SCENEFILE_ESCAPE_XML
} pt_scenefile_escape_mode;
/* Writes text (NUL-terminated; NULL: empty) escaped into out, size bytes with the NUL; a
   text too long is cut before the first escape that does not fit. Returns strlen(out). */
PTDEF size_t pt_scenefile_escape(char *out, size_t size, const char *text, pt_scenefile_escape_mode mode);

/* Writes the POV-Ray 3.7 scene (through a temporary file renamed into place). opt may be
   NULL. The first comment lines give the command line that renders it. Refuses (writing
   nothing) every scene pt_scenefile_build refuses, with the build's message, the features
   POV-Ray cannot match, and a scene that would need a non-finite number. Text from the
   scene (its file name) reaches the output only escaped (PT_SCENEFILE_ESCAPE_COMMENT). */
PTDEF int pt_scenefile_write_pov(const pt_scenefile *desc, const char *path, const pt_pov_options *opt, char *err,
                                 size_t err_size);

typedef struct pt_mitsuba_options {
    int width, height;           /* 0: the scene's size */
    int spp;                     /* 0: the scene's samples per pixel */
    int max_depth;               /* pdftrace's scattering events (written as this + 1); 0: the scene's */
} pt_mitsuba_options;
/* Writes the Mitsuba 3 scene (XML, scene format version 3.0.0) to path, its triangles beside
   it as binary little-endian PLY files "<path without .xml>.N.ply", N = 0, 1, ..., and its
   environment map as "<path without .xml>.env.pfm" (all through temporary files renamed into
   place; on failure none is left). opt may be
   NULL. The mapping and what is refused: MITSUBA 3 EXPORT above and docs/mitsuba.md.
   Refuses (writing nothing) every scene pt_scenefile_build refuses, with the build's
   message, the features Mitsuba has no exact twin for (with the statement's file:line), and
   a scene that would need a non-finite number. Text from the scene (its file name) reaches
   the XML only in comments, escaped (PT_SCENEFILE_ESCAPE_COMMENT, '-' as \x2D); the PLY file
   names only in attribute values, escaped (PT_SCENEFILE_ESCAPE_XML), and an output name
   whose file part that escape would alter otherwise (control bytes, bytes >= 0x80, '$', '\')
   is refused when the scene needs PLY files. */
PTDEF int pt_scenefile_export_mitsuba(const pt_scenefile *desc, const char *path, const pt_mitsuba_options *opt,
                                      char *err, size_t err_size);

#ifdef __cplusplus
}
#endif

#endif /* PDFTRACE_SCENE_H */

/* ==========================================================================================
   IMPLEMENTATION
   The parser reads the whole file, then one line at a time into a pt_scenefile
   (pt__sf_statement hands each statement to the reader of its kind); nothing is kept on
   failure. The OBJ reader fans polygons into triangles. The builder and the exporter use only
   the public API and the description.
   ========================================================================================== */
#ifdef PDFTRACE_SCENE_IMPLEMENTATION
#ifndef PDFTRACE_SCENE_IMPLEMENTATION_DONE
#define PDFTRACE_SCENE_IMPLEMENTATION_DONE

#include <errno.h>
#include <float.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* POSIX file access (open without blocking, fstat, realpath) on Unix systems, in every
   dialect: open, fstat and read are declared in all of them; realpath is declared here as
   POSIX.1-2008 has it, since glibc and musl hide it in strict C99 (a compatible redeclaration).
   Elsewhere, or with PDFTRACE_SCENE_NO_POSIX, a fallback on stdio that cannot tell a FIFO from
   a file and confines mesh paths lexically only. */
#if !defined(PDFTRACE_SCENE_NO_POSIX) && (defined(__unix__) || defined(__APPLE__))
#define PT__SF_POSIX 1
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#if !defined(__cplusplus) && !defined(__APPLE__)
extern char *realpath(const char *restrict name, char *restrict resolved);
#endif
#endif

#if defined(PT_MALLOC) && defined(PT_FREE) && defined(PT_REALLOC)
/* all three given (or defined by pdftrace.h's implementation in this file) */
#elif !defined(PT_MALLOC) && !defined(PT_FREE) && !defined(PT_REALLOC)
#define PT_MALLOC(sz) malloc(sz)
#define PT_REALLOC(p, sz) realloc(p, sz)
#define PT_FREE(p) free(p)
#else
#error "pdftrace_scene.h: define all of PT_MALLOC, PT_REALLOC and PT_FREE, or none"
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Finite by bit pattern (immune to -ffast-math), as in pdftrace.h. */
static int pt__sf_isfinite(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return (u & 0x7f800000u) != 0x7f800000u;
}

#define PT__SF_MAX_LINE 4096
#define PT__SF_MAX_TOKENS 40
#define PT__SF_MAX_VALUE 1e7
#define PT__SF_MAX_SHAPES 1000000
#define PT__SF_MAX_LIGHTS 65536
#define PT__SF_MAX_FILE (256u * 1024u * 1024u)
#define PT__SF_MAX_MESH_VERTICES 8000000u

#define PT__SF_MAX_MESHES 1024
#define PT__SF_PATH 4096
#define PT__SF_MAX_ROOTS 17 /* the scene's directory and up to 16 allowed ones */

/* Path guiding of a scene file without a `guiding` statement (pt_scenefile.guiding as loaded,
   and so pt_render_desc.guiding from pt_scenefile_build): a render setting, not scene content. */
#define PT__SF_DEFAULT_GUIDING PT_GUIDING_OFF
/* The sampler of a scene file without a `sampler` statement: Sobol, the most efficient measured
   with MIS on the benchmark scenes (bench/README.md, "Sobol sampler"). */
#define PT__SF_DEFAULT_SAMPLER PT_SAMPLER_SOBOL

typedef struct pt__sf_parser {
    pt_scenefile *d;
    const char *name;    /* file name in messages */
    const char *base_dir;
    int line;
    char *err;
    size_t err_size;
    char *tok[PT__SF_MAX_TOKENS];
    int ntok, pos;
    pt_transform xf;
    double xfd[3][4];    /* xf composed in double */
    int have_camera;
    uint64_t mesh_limit, image_limit;  /* bytes (pt_scenefile_options, defaults applied) */
    const pt_scenefile_options *opt;
    char *roots[PT__SF_MAX_ROOTS];     /* resolved directories mesh paths may lie in, at the first mesh */
    int root_count, roots_done;
    uint64_t file_dev[PT__SF_MAX_MESHES], file_ino[PT__SF_MAX_MESHES]; /* identity of d->meshes[i]'s file */
    int mesh_statements;
} pt__sf_parser;

/* Length of the printable UTF-8 sequence at s (1 for printable ASCII), or 0 for a control
   byte (C0, DEL, C1), a malformed, overlong or surrogate sequence. */
static int pt__sf_utf8_printable(const unsigned char *s)
{
    unsigned c = s[0], cp;
    int n, i;
    if (c >= 0x20u && c < 0x7fu) return 1;
    if (c < 0xc2u || c > 0xf4u) return 0;
    n = c >= 0xf0u ? 4 : c >= 0xe0u ? 3 : 2;
    cp = c & (0x3fu >> (n - 1));
    for (i = 1; i < n; ++i) {
        if ((s[i] & 0xc0u) != 0x80u) return 0; /* also stops at the terminating NUL */
        cp = cp << 6 | (s[i] & 0x3fu);
    }
    if (cp < 0xa0u || (n == 3 && cp < 0x800u) || (n == 4 && (cp < 0x10000u || cp > 0x10ffffu)) ||
        (cp >= 0xd800u && cp <= 0xdfffu))
        return 0;
    return n;
}

/* Rewrites err so that it holds no byte a terminal would act on: control bytes and invalid
   UTF-8 become \xNN (a message quotes tokens of the input, which may hold escape sequences). */
static void pt__sf_escape(char *err, size_t size)
{
    size_t n = strlen(err), i, o = 0;
    char *copy;
    for (i = 0; i < n; ++i)
        if (!pt__sf_utf8_printable((const unsigned char *)err + i)) break;
    if (i == n) return;
    copy = (char *)PT_MALLOC(n + 1u);
    if (!copy) {
        for (; i < n; ++i)
            if (((unsigned char)err[i] & 0x80u) || (unsigned char)err[i] < 0x20u || err[i] == 0x7f) err[i] = '?';
        return;
    }
    memcpy(copy, err, n + 1u);
    for (i = 0; i < n;) {
        int k = pt__sf_utf8_printable((const unsigned char *)copy + i);
        if (k > 0) {
            if (o + (size_t)k >= size) break;
            memcpy(err + o, copy + i, (size_t)k);
            o += (size_t)k;
            i += (size_t)k;
        } else {
            if (o + 4u >= size) break;
            snprintf(err + o, 5, "\\x%02x", (unsigned char)copy[i]);
            o += 4u;
            ++i;
        }
    }
    err[o] = '\0';
    PT_FREE(copy);
}

static void pt__sf_msg(char *err, size_t size, const char *file, int line, const char *fmt, va_list ap)
{
    int n;
    if (!err || size == 0) return;
    if (line > 0) n = snprintf(err, size, "%s:%d: ", file, line);
    else n = snprintf(err, size, "%s: ", file);
    if (n < 0) n = 0;
    if ((size_t)n < size) vsnprintf(err + n, size - (size_t)n, fmt, ap);
    pt__sf_escape(err, size);
}
static int pt__sf_fail(pt__sf_parser *p, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    pt__sf_msg(p->err, p->err_size, p->name, p->line, fmt, ap);
    va_end(ap);
    return code;
}
static int pt__sf_failf(char *err, size_t size, const char *file, int line, int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    pt__sf_msg(err, size, file, line, fmt, ap);
    va_end(ap);
    return code;
}

static int pt__sf_grow(void **arr, int *count_cap, int count, size_t elem)
{
    int cap = *count_cap;
    void *n;
    if (count < cap) return 1;
    cap = cap ? cap * 2 : 16;
    n = PT_REALLOC(*arr, (size_t)cap * elem);
    if (!n) return 0;
    *arr = n;
    *count_cap = cap;
    return 1;
}

PTDEF void pt_scenefile_free(pt_scenefile *d)
{
    int i;
    if (!d) return;
    for (i = 0; i < d->mesh_count; ++i) {
        PT_FREE(d->meshes[i].positions);
        PT_FREE(d->meshes[i].normals);
        PT_FREE(d->meshes[i].uvs);
        PT_FREE(d->meshes[i].indices);
    }
    PT_FREE(d->meshes);
    pt_image_free(&d->environment);
    PT_FREE(d->shapes);
    PT_FREE(d->lights);
    PT_FREE(d->materials);
    PT_FREE(d->checkers);
    if (d->images) {
        int i;
        for (i = 0; i < d->image_count; ++i) pt_image_free(&d->images[i].image);
    }
    PT_FREE(d->images);
    memset(d, 0, sizeof *d);
}

/* ---- Reading files: regular files only, opened without blocking (a FIFO would block in
   open until a writer comes), with the size known before anything is allocated. */
typedef struct pt__sf_in {
#ifdef PT__SF_POSIX
    int fd;
#else
    FILE *f;
#endif
    uint64_t size;               /* bytes, from fstat (0 in the stdio fallback: unknown) */
    uint64_t dev, ino;           /* the file's identity (the fallback: a hash of the path) */
} pt__sf_in;

#ifndef PT__SF_POSIX
/* FNV-1a, 64 bits: the fallback's identity of a normalised path. */
static uint64_t pt__sf_hash(const char *s)
{
    uint64_t h = 14695981039346656037ull;
    while (*s) h = (h ^ (unsigned char)*s++) * 1099511628211ull;
    return h;
}
#endif

/* Opens path for reading if it is a regular file; else returns an error code and *why.
   nofollow: refuse a symbolic link as the last component. */
static int pt__sf_in_open(pt__sf_in *in, const char *path, int nofollow, const char **why)
{
#ifdef PT__SF_POSIX
    struct stat st;
    int flags = O_RDONLY | O_NONBLOCK | O_NOCTTY;
#ifdef O_CLOEXEC
    flags |= O_CLOEXEC;
#endif
#ifdef O_NOFOLLOW
    if (nofollow) flags |= O_NOFOLLOW; /* a link swapped in after the path was resolved */
#else
    (void)nofollow; /* glibc defines O_NOFOLLOW only for POSIX.1-2008 or a GNU dialect */
#endif
    memset(in, 0, sizeof *in);
    in->fd = open(path, flags);
    if (in->fd < 0) { *why = strerror(errno); return PT_ERROR_IO; }
    if (fstat(in->fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        *why = "not a regular file";
        close(in->fd);
        in->fd = -1;
        return PT_ERROR_IO;
    }
    in->size = st.st_size > 0 ? (uint64_t)st.st_size : 0u;
    in->dev = (uint64_t)st.st_dev;
    in->ino = (uint64_t)st.st_ino;
#else
    memset(in, 0, sizeof *in);
    in->f = fopen(path, "rb");
    if (!in->f) { *why = strerror(errno); return PT_ERROR_IO; }
    in->ino = pt__sf_hash(path);
    (void)nofollow;
#endif
    return PT_OK;
}

static void pt__sf_in_close(pt__sf_in *in)
{
#ifdef PT__SF_POSIX
    if (in->fd >= 0) close(in->fd);
    in->fd = -1;
#else
    if (in->f) fclose(in->f);
    in->f = NULL;
#endif
}

/* Reads the whole file (at most max bytes) into a NUL-terminated buffer and closes it. */
static int pt__sf_in_read(pt__sf_in *in, size_t max, char **out, size_t *len, const char **why)
{
    char *buf = NULL, *nb;
    size_t n = 0, cap = 0;
    int rc = PT_OK;
    *out = NULL;
    *len = 0;
    if (in->size > max) { pt__sf_in_close(in); *why = "file too large"; return PT_ERROR_UNSUPPORTED; }
    for (;;) {
        size_t got;
        if (cap - n < 65536u) {
            size_t ncap = cap ? cap * 2u : (size_t)in->size + 65536u;
            if (ncap > max + 65537u) ncap = max + 65537u;
            if (ncap <= cap) { rc = PT_ERROR_UNSUPPORTED; *why = "file too large"; break; }
            nb = (char *)PT_REALLOC(buf, ncap);
            if (!nb) { rc = PT_ERROR_OUT_OF_MEMORY; *why = "out of memory"; break; }
            buf = nb;
            cap = ncap;
        }
#ifdef PT__SF_POSIX
        {
            ssize_t r = read(in->fd, buf + n, cap - n - 1u);
            if (r < 0 && errno == EINTR) continue;
            if (r < 0) { rc = PT_ERROR_IO; *why = strerror(errno); break; }
            got = (size_t)r;
        }
#else
        got = fread(buf + n, 1, cap - n - 1u, in->f);
        if (got == 0 && ferror(in->f)) { rc = PT_ERROR_IO; *why = "read error"; break; }
#endif
        n += got;
        if (n > max) { rc = PT_ERROR_UNSUPPORTED; *why = "file too large"; break; }
        if (got == 0) break;
    }
    pt__sf_in_close(in);
    if (rc != PT_OK) { PT_FREE(buf); return rc; }
    buf[n] = '\0';
    *out = buf;
    *len = n;
    return PT_OK;
}

/* Opens and reads a regular file; on failure *why says why. */
static int pt__sf_read_file(const char *path, char **out, size_t *len, size_t max, const char **why)
{
    pt__sf_in in;
    int rc = pt__sf_in_open(&in, path, 0, why);
    *out = NULL;
    *len = 0;
    if (rc != PT_OK) return rc;
    return pt__sf_in_read(&in, max, out, len, why);
}

/* Splits text[0..len) into lines; calls fn for each with the line number. A line longer than
   PT__SF_MAX_LINE or containing a NUL byte is an error. */
typedef int (*pt__sf_line_fn)(void *ctx, char *line, int number);
static int pt__sf_lines(const char *text, size_t len, void *ctx, pt__sf_line_fn fn, char *err, size_t err_size,
                        const char *file)
{
    char buf[PT__SF_MAX_LINE + 2];
    size_t i = 0;
    int number = 0, rc;
    if (len >= 3 && !memcmp(text, "\xef\xbb\xbf", 3)) i = 3; /* a UTF-8 byte order mark */
    while (i < len) {
        size_t j = i, n;
        while (j < len && text[j] != '\n') {
            if (text[j] == '\0')
                return pt__sf_failf(err, err_size, file, number + 1, PT_ERROR_INVALID_ARGUMENT, "NUL byte in the text");
            ++j;
        }
        ++number;
        n = j - i;
        if (n > PT__SF_MAX_LINE)
            return pt__sf_failf(err, err_size, file, number, PT_ERROR_INVALID_ARGUMENT, "line longer than %d characters",
                                PT__SF_MAX_LINE);
        memcpy(buf, text + i, n);
        buf[n] = '\0';
        if (n > 0 && buf[n - 1] == '\r') buf[n - 1] = '\0';
        rc = fn(ctx, buf, number);
        if (rc != PT_OK) return rc;
        i = j + 1;
    }
    return PT_OK;
}

/* Cuts a comment and splits on blanks. */
static int pt__sf_tokenize(char *line, char **tok, int max)
{
    int n = 0;
    char *c = strchr(line, '#');
    if (c) *c = '\0';
    for (;;) {
        while (*line == ' ' || *line == '\t' || *line == '\v' || *line == '\f' || *line == '\r') ++line;
        if (!*line) break;
        if (n == max) return -1;
        tok[n++] = line;
        while (*line && *line != ' ' && *line != '\t' && *line != '\v' && *line != '\f' && *line != '\r') ++line;
        if (*line) *line++ = '\0';
    }
    return n;
}

static const char *pt__sf_next(pt__sf_parser *p) { return p->pos < p->ntok ? p->tok[p->pos++] : NULL; }

static int pt__sf_parse_double(const char *t, double *v)
{
    char *end;
    if (!t || !*t) return 0;
    *v = strtod(t, &end);
    return *end == '\0';
}

/* Without arithmetic on the value (Inf - Inf would raise FE_INVALID): != and the comparison
   of a non-NaN with DBL_MAX are quiet. */
static int pt__sf_finite(double v) { return v == v && fabs(v) <= DBL_MAX; }

static int pt__sf_num(pt__sf_parser *p, const char *what, float *out)
{
    const char *t = pt__sf_next(p);
    double v;
    if (!t) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: missing number (line ends early)", what);
    if (!pt__sf_parse_double(t, &v)) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: '%s' is not a number", what, t);
    if (!pt__sf_finite(v)) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: '%s' is not finite", what, t);
    if (fabs(v) > PT__SF_MAX_VALUE)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: %s is out of range (magnitude at most 1e7)", what, t);
    *out = (float)v;
    return PT_OK;
}
static int pt__sf_vec(pt__sf_parser *p, const char *what, pt_vec3 *out)
{
    int rc;
    if ((rc = pt__sf_num(p, what, &out->x)) != PT_OK) return rc;
    if ((rc = pt__sf_num(p, what, &out->y)) != PT_OK) return rc;
    return pt__sf_num(p, what, &out->z);
}
static int pt__sf_color(pt__sf_parser *p, const char *what, pt_color *out)
{
    int rc = pt__sf_vec(p, what, out);
    if (rc != PT_OK) return rc;
    if (out->x < 0 || out->y < 0 || out->z < 0)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: colour components must be >= 0", what);
    return PT_OK;
}
static int pt__sf_int(pt__sf_parser *p, const char *what, long lo, long hi, long *out)
{
    const char *t = pt__sf_next(p);
    char *end;
    long v;
    if (!t) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: missing integer (line ends early)", what);
    errno = 0;
    v = strtol(t, &end, 10);
    if (*end != '\0' || errno == ERANGE || v < lo || v > hi)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: expected an integer in [%ld, %ld], got '%s'", what, lo, hi, t);
    *out = v;
    return PT_OK;
}
static int pt__sf_end(pt__sf_parser *p)
{
    if (p->pos < p->ntok)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "unexpected '%s' after the end of the '%s' statement",
                           p->tok[p->pos], p->tok[0]);
    return PT_OK;
}
static int pt__sf_name_ok(const char *s)
{
    size_t i, n = strlen(s);
    if (n == 0 || n >= PT_SCENEFILE_NAME_MAX) return 0;
    for (i = 0; i < n; ++i) {
        char c = s[i];
        int alpha = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
        if (!(alpha || (i > 0 && ((c >= '0' && c <= '9') || c == '-')))) return 0;
    }
    return 1;
}
static int pt__sf_find_material(const pt_scenefile *d, const char *name)
{
    int i;
    for (i = 0; i < d->material_count; ++i)
        if (strcmp(d->materials[i].name, name) == 0) return i;
    return -1;
}
static int pt__sf_find_image(const pt_scenefile *d, const char *name)
{
    int i;
    for (i = 0; i < d->image_count; ++i)
        if (strcmp(d->images[i].name, name) == 0) return i;
    return -1;
}
static int pt__sf_find_checker(const pt_scenefile *d, const char *name)
{
    int i;
    for (i = 0; i < d->checker_count; ++i)
        if (strcmp(d->checkers[i].name, name) == 0) return i;
    return -1;
}
static int pt__sf_new_name(pt__sf_parser *p, const char *kind, const char **out)
{
    const char *t = pt__sf_next(p);
    if (!t) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: missing name", kind);
    if (!pt__sf_name_ok(t))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT,
                           "%s: bad name '%s' (letters, digits, _ and -, at most %d characters, not starting with a digit)",
                           kind, t, PT_SCENEFILE_NAME_MAX - 1);
    if (pt__sf_find_material(p->d, t) >= 0 || pt__sf_find_checker(p->d, t) >= 0 || pt__sf_find_image(p->d, t) >= 0)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: name '%s' is already defined", kind, t);
    *out = t;
    return PT_OK;
}
static int pt__sf_material_ref(pt__sf_parser *p, int *out)
{
    const char *t = pt__sf_next(p);
    if (!t) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: missing material name", p->tok[0]);
    *out = pt__sf_find_material(p->d, t);
    if (*out < 0) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: material '%s' is not defined", p->tok[0], t);
    return PT_OK;
}

/* ---- Wavefront OBJ: v, vn, vt, f (v, v/vt, v//vn, v/vt/vn; negative = relative); o, g, s,
   usemtl, mtllib ignored. Every face corner becomes its own vertex (positions and normals in
   OBJ have separate indices); polygons are fanned from their first corner. */
typedef struct pt__obj {
    float *v; int nv, cv;       /* 3 floats per position */
    float *vn; int nn, cn;
    float *vt; int nt, ct;      /* 3 floats per texture coordinate (u, v, unused) */
    pt_obj_mesh *m;
    uint32_t cap_vert, cap_tri;
    int with_normals;           /* -1 unknown, 0, 1 */
    int with_uvs;               /* -1 unknown, 0, 1 */
    int statements;             /* statements read so far */
    uint64_t limit, used;       /* bytes the arrays may take, and take (their capacities) */
    int over_limit;             /* set when a growth was refused by the limit */
    const char *file;
    char *err; size_t err_size;
} pt__obj;

/* Accounts for an array growing from old_bytes to new_bytes; 0 if that would pass the limit. */
static int pt__obj_charge(pt__obj *o, size_t old_bytes, size_t new_bytes)
{
    if (o->used - old_bytes + new_bytes > o->limit) {
        o->over_limit = 1;
        return 0;
    }
    o->used = o->used - old_bytes + new_bytes;
    return 1;
}
/* Room for one more position or normal (3 floats) in *arr. */
static int pt__obj_grow3(pt__obj *o, float **arr, int *cap, int count)
{
    size_t c = (size_t)*cap, nc = c ? c * 2u : 16u;
    if (count < *cap) return PT_OK;
    if (!pt__obj_charge(o, c * 3u * sizeof(float), nc * 3u * sizeof(float))) return PT_ERROR_OUT_OF_MEMORY;
    if (!pt__sf_grow((void **)arr, cap, count, 3u * sizeof(float))) return PT_ERROR_OUT_OF_MEMORY;
    return PT_OK;
}

/* The statements of the OBJ format (Wavefront, "Object Files (.obj)", Appendix B1 of the
   Advanced Visualizer manual). A file whose first statement is none of them is not OBJ, and
   no message quotes a word that is not one of them: an OBJ error must not reveal another
   file's contents. */
static int pt__obj_keyword(const char *t)
{
    static const char *const words[] = {
        "v", "vt", "vn", "vp", "cstype", "deg", "bmat", "step", "p", "l", "f", "curv", "curv2", "surf", "parm",
        "trim", "hole", "scrv", "sp", "end", "con", "g", "s", "mg", "o", "bevel", "c_interp", "d_interp", "lod",
        "usemtl", "mtllib", "shadow_obj", "trace_obj", "ctech", "stech", "maplib", "usemap", "call", "csh"};
    size_t i;
    for (i = 0; i < sizeof words / sizeof words[0]; ++i)
        if (!strcmp(t, words[i])) return 1;
    return 0;
}

static int pt__obj_fail(pt__obj *o, int line, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    pt__sf_msg(o->err, o->err_size, o->file, line, fmt, ap);
    va_end(ap);
    return PT_ERROR_INVALID_ARGUMENT;
}
static int pt__obj_floats(pt__obj *o, char **tok, int n, int line, float *out)
{
    int i;
    for (i = 0; i < 3; ++i) {
        double v;
        if (i + 1 >= n) return pt__obj_fail(o, line, "'%s' needs 3 numbers", tok[0]);
        if (!pt__sf_parse_double(tok[i + 1], &v) || !pt__sf_finite(v) || fabs(v) > PT__SF_MAX_VALUE)
            return pt__obj_fail(o, line, "'%s' is not a finite number of magnitude <= 1e7", tok[i + 1]);
        out[i] = (float)v;
    }
    return PT_OK;
}
/* Resolves an OBJ index (1-based, or negative from the end) against count; -1 if bad. */
static long pt__obj_index(const char *t, size_t len, int count)
{
    char buf[24];
    char *end;
    long v;
    if (len == 0 || len >= sizeof buf) return -1;
    memcpy(buf, t, len);
    buf[len] = '\0';
    errno = 0;
    v = strtol(buf, &end, 10);
    if (*end != '\0' || errno == ERANGE) return -1;
    if (v > 0 && v <= count) return v - 1;
    if (v < 0 && -v <= count) return count + v;
    return -1;
}
static int pt__obj_push_vertex(pt__obj *o, const float *pos, const float *nrm, const float *uv)
{
    pt_obj_mesh *m = o->m;
    if (m->vertex_count == o->cap_vert) {
        uint32_t nc = o->cap_vert ? o->cap_vert * 2u : 1024u;
        size_t per = 3u * sizeof(float) * (nrm ? 2u : 1u) + (uv ? 2u * sizeof(float) : 0u);
        float *np;
        if (!pt__obj_charge(o, (size_t)o->cap_vert * per, (size_t)nc * per)) return PT_ERROR_OUT_OF_MEMORY;
        np = (float *)PT_REALLOC(m->positions, (size_t)nc * 3u * sizeof(float));
        if (!np) return PT_ERROR_OUT_OF_MEMORY;
        m->positions = np;
        if (nrm) {
            float *nn = (float *)PT_REALLOC(m->normals, (size_t)nc * 3u * sizeof(float));
            if (!nn) return PT_ERROR_OUT_OF_MEMORY;
            m->normals = nn;
        }
        if (uv) {
            float *nu = (float *)PT_REALLOC(m->uvs, (size_t)nc * 2u * sizeof(float));
            if (!nu) return PT_ERROR_OUT_OF_MEMORY;
            m->uvs = nu;
        }
        o->cap_vert = nc;
    }
    memcpy(m->positions + 3u * m->vertex_count, pos, 3u * sizeof(float));
    if (nrm) memcpy(m->normals + 3u * m->vertex_count, nrm, 3u * sizeof(float));
    if (uv) { /* v flipped: OBJ's v runs up the image, pdftrace's (Mitsuba's) down from row 0 */
        m->uvs[2u * m->vertex_count] = uv[0];
        m->uvs[2u * m->vertex_count + 1u] = 1.0f - uv[1];
    }
    m->vertex_count++;
    return PT_OK;
}
static int pt__obj_line(void *ctx, char *line, int number)
{
    pt__obj *o = (pt__obj *)ctx;
    char *tok[260];
    int n = pt__sf_tokenize(line, tok, 260), i;
    if (n < 0) return pt__obj_fail(o, number, "too many items on one line (at most 259 face corners)");
    if (n == 0) return PT_OK;
    if (!pt__obj_keyword(tok[0]))
        return o->statements == 0 ? pt__obj_fail(o, number, "not an OBJ file (its first statement is not an OBJ keyword)")
                                  : pt__obj_fail(o, number, "not an OBJ statement (v, vn, f, vt, o, g, s, usemtl, mtllib)");
    o->statements++;
    if (strcmp(tok[0], "v") == 0 || strcmp(tok[0], "vn") == 0) {
        int is_v = tok[0][1] == '\0';
        float xyz[3];
        int rc = pt__obj_floats(o, tok, n, number, xyz);
        if (rc != PT_OK) return rc;
        if (n > (is_v ? 5 : 4)) return pt__obj_fail(o, number, "'%s' has too many numbers", tok[0]);
        if (is_v) {
            if ((uint32_t)o->nv >= PT__SF_MAX_MESH_VERTICES) return pt__obj_fail(o, number, "too many vertices");
            if ((rc = pt__obj_grow3(o, &o->v, &o->cv, o->nv)) != PT_OK) return rc;
            memcpy(o->v + 3 * o->nv++, xyz, sizeof xyz);
        } else {
            if ((uint32_t)o->nn >= PT__SF_MAX_MESH_VERTICES) return pt__obj_fail(o, number, "too many normals");
            if (!(xyz[0] * xyz[0] + xyz[1] * xyz[1] + xyz[2] * xyz[2] > 1e-20f))
                return pt__obj_fail(o, number, "normal has zero length");
            if ((rc = pt__obj_grow3(o, &o->vn, &o->cn, o->nn)) != PT_OK) return rc;
            memcpy(o->vn + 3 * o->nn++, xyz, sizeof xyz);
        }
        return PT_OK;
    }
    if (strcmp(tok[0], "vt") == 0) { /* vt u [v [w]]: v defaults to 0, w is ignored */
        float uv[3] = {0, 0, 0};
        int rc;
        if (n < 2 || n > 4) return pt__obj_fail(o, number, "'vt' needs 1 to 3 numbers");
        for (i = 1; i < n && i < 3; ++i) {
            double x;
            if (!pt__sf_parse_double(tok[i], &x) || !pt__sf_finite(x) || fabs(x) > PT__SF_MAX_VALUE)
                return pt__obj_fail(o, number, "'%s' is not a finite number of magnitude <= 1e7", tok[i]);
            uv[i - 1] = (float)x;
        }
        if ((uint32_t)o->nt >= PT__SF_MAX_MESH_VERTICES) return pt__obj_fail(o, number, "too many texture coordinates");
        if ((rc = pt__obj_grow3(o, &o->vt, &o->ct, o->nt)) != PT_OK) return rc;
        memcpy(o->vt + 3 * o->nt++, uv, sizeof uv);
        return PT_OK;
    }
    if (strcmp(tok[0], "f") == 0) {
        uint32_t first = o->m->vertex_count, k;
        int corners = n - 1;
        if (corners < 3) return pt__obj_fail(o, number, "a face needs at least 3 vertices, got %d", corners);
        if (o->m->vertex_count + (uint32_t)corners > PT__SF_MAX_MESH_VERTICES) return pt__obj_fail(o, number, "too many face vertices");
        for (i = 1; i < n; ++i) {
            const char *t = tok[i], *s1 = strchr(t, '/'), *s2 = s1 ? strchr(s1 + 1, '/') : NULL;
            long vi = pt__obj_index(t, s1 ? (size_t)(s1 - t) : strlen(t), o->nv), ni = -1, ti = -1;
            int has_n = s2 && s2[1] != '\0';
            int has_t = s1 && s1[1] != '/' && s1[1] != '\0';
            int rc;
            if (vi < 0) return pt__obj_fail(o, number, "face vertex '%s': position index out of range (%d positions so far)", t, o->nv);
            if (s2 && !has_n) return pt__obj_fail(o, number, "face vertex '%s': empty normal index", t);
            if (has_n) {
                ni = pt__obj_index(s2 + 1, strlen(s2 + 1), o->nn);
                if (ni < 0) return pt__obj_fail(o, number, "face vertex '%s': normal index out of range (%d normals so far)", t, o->nn);
            }
            if (o->with_normals < 0) o->with_normals = has_n;
            if (o->with_normals != has_n)
                return pt__obj_fail(o, number, "face vertex '%s': some face vertices have normals and some do not", t);
            if (has_t) {
                ti = pt__obj_index(s1 + 1, s2 ? (size_t)(s2 - s1 - 1) : strlen(s1 + 1), o->nt);
                if (ti < 0)
                    return pt__obj_fail(o, number, "face vertex '%s': texture coordinate index out of range (%d so far)", t, o->nt);
            }
            if (o->with_uvs < 0) o->with_uvs = has_t;
            if (o->with_uvs != has_t)
                return pt__obj_fail(o, number, "face vertex '%s': some face vertices have texture coordinates and some do not", t);
            rc = pt__obj_push_vertex(o, o->v + 3 * vi, has_n ? o->vn + 3 * ni : NULL, has_t ? o->vt + 3 * ti : NULL);
            if (rc != PT_OK) return rc;
        }
        for (k = 1; k + 1 < (uint32_t)corners; ++k) {
            pt_obj_mesh *m = o->m;
            if (m->triangle_count == o->cap_tri) {
                uint32_t nc = o->cap_tri ? o->cap_tri * 2u : 1024u;
                uint32_t *ni2;
                if (!pt__obj_charge(o, (size_t)o->cap_tri * 12u, (size_t)nc * 12u)) return PT_ERROR_OUT_OF_MEMORY;
                ni2 = (uint32_t *)PT_REALLOC(m->indices, (size_t)nc * 3u * sizeof(uint32_t));
                if (!ni2) return PT_ERROR_OUT_OF_MEMORY;
                m->indices = ni2;
                o->cap_tri = nc;
            }
            m->indices[3u * m->triangle_count + 0] = first;
            m->indices[3u * m->triangle_count + 1] = first + k;
            m->indices[3u * m->triangle_count + 2] = first + k + 1u;
            m->triangle_count++;
        }
        return PT_OK;
    }
    if (!strcmp(tok[0], "o") || !strcmp(tok[0], "g") || !strcmp(tok[0], "s") ||
        !strcmp(tok[0], "usemtl") || !strcmp(tok[0], "mtllib"))
        return PT_OK;
    return pt__obj_fail(o, number, "unsupported OBJ statement '%s' (v, vn, f, vt, o, g, s, usemtl, mtllib)", tok[0]);
}
PTDEF void pt_obj_mesh_free(pt_obj_mesh *m)
{
    if (!m) return;
    PT_FREE(m->positions);
    PT_FREE(m->normals);
    PT_FREE(m->uvs);
    PT_FREE(m->indices);
    memset(m, 0, sizeof *m);
}

/* Bytes a parsed mesh holds once its arrays are trimmed to their counts. */
static uint64_t pt__obj_bytes(const pt_obj_mesh *m)
{
    return (uint64_t)m->vertex_count * (12u * (m->normals ? 2u : 1u) + (m->uvs ? 8u : 0u)) + (uint64_t)m->triangle_count * 12u;
}

/* pt_obj_parse with a limit on the bytes of its arrays; *over_limit tells that the limit, not
   the allocator, refused a growth (then err is left for the caller). The arrays are trimmed. */
static int pt__obj_parse(const char *text, size_t length, const char *name, uint64_t limit, pt_obj_mesh *out,
                         char *err, size_t err_size, int *over_limit)
{
    pt__obj o;
    int rc;
    memset(&o, 0, sizeof o);
    o.m = out;
    o.with_normals = -1;
    o.with_uvs = -1;
    o.limit = limit;
    o.file = name;
    o.err = err;
    o.err_size = err_size;
    rc = pt__sf_lines(text, length, &o, pt__obj_line, err, err_size, name);
    if (rc == PT_OK && out->triangle_count == 0) rc = pt__obj_fail(&o, 0, "no faces");
    if (rc == PT_ERROR_OUT_OF_MEMORY && !o.over_limit) pt__sf_failf(err, err_size, name, 0, rc, "out of memory");
    *over_limit = o.over_limit;
    PT_FREE(o.v);
    PT_FREE(o.vn);
    PT_FREE(o.vt);
    if (rc != PT_OK) {
        pt_obj_mesh_free(out);
        return rc;
    }
    { /* trim; a failed shrink keeps the larger block */
        void *np = PT_REALLOC(out->positions, (size_t)out->vertex_count * 12u), *nn = NULL, *ni;
        if (np) out->positions = (float *)np;
        if (out->normals && (nn = PT_REALLOC(out->normals, (size_t)out->vertex_count * 12u)) != NULL)
            out->normals = (float *)nn;
        if (out->uvs && (nn = PT_REALLOC(out->uvs, (size_t)out->vertex_count * 8u)) != NULL) out->uvs = (float *)nn;
        if ((ni = PT_REALLOC(out->indices, (size_t)out->triangle_count * 12u)) != NULL) out->indices = (uint32_t *)ni;
    }
    return PT_OK;
}

PTDEF int pt_obj_parse(const char *text, size_t length, const char *name, pt_obj_mesh *out, char *err,
                       size_t err_size)
{
    int over = 0;
    if (err && err_size) err[0] = '\0';
    if (!out) return PT_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!name) name = "<obj>";
    if (!text) return pt__sf_failf(err, err_size, name, 0, PT_ERROR_INVALID_ARGUMENT, "no text");
    return pt__obj_parse(text, length, name, ~(uint64_t)0, out, err, err_size, &over);
}

PTDEF pt_mesh_desc pt_obj_mesh_desc(const pt_obj_mesh *m, int material)
{
    pt_mesh_desc md;
    memset(&md, 0, sizeof md);
    md.material = material;
    if (!m) return md;
    md.positions = m->positions;
    md.vertex_count = m->vertex_count;
    md.indices = m->indices;
    md.triangle_count = m->triangle_count;
    md.normals = m->normals;
    md.uvs = m->uvs;
    return md;
}

PTDEF int pt_obj_load(const char *path, pt_obj_mesh *out, char *err, size_t err_size)
{
    char *text = NULL;
    const char *why = "";
    size_t len = 0;
    int rc;
    if (err && err_size) err[0] = '\0';
    if (out) memset(out, 0, sizeof *out);
    if (!path || !*path) return pt__sf_failf(err, err_size, "pt_obj_load", 0, PT_ERROR_INVALID_ARGUMENT, "path is NULL or empty");
    if (!out) return pt__sf_failf(err, err_size, path, 0, PT_ERROR_INVALID_ARGUMENT, "pt_obj_load: out is NULL");
    rc = pt__sf_read_file(path, &text, &len, PT__SF_MAX_FILE, &why);
    if (rc != PT_OK) return pt__sf_failf(err, err_size, path, 0, rc, "cannot read: %s", why);
    rc = pt_obj_parse(text, len, path, out, err, err_size);
    PT_FREE(text);
    return rc;
}

PTDEF int pt_scene_add_obj(pt_scene *scene, const char *path, int material, char *err, size_t err_size)
{
    pt_obj_mesh m;
    pt_mesh_desc md;
    int rc;
    if (!scene) return pt__sf_failf(err, err_size, "pt_scene_add_obj", 0, PT_ERROR_INVALID_ARGUMENT, "scene is NULL");
    rc = pt_obj_load(path, &m, err, err_size);
    if (rc != PT_OK) return rc;
    md = pt_obj_mesh_desc(&m, material);
    rc = pt_scene_add_mesh(scene, &md);
    if (rc < 0) pt__sf_failf(err, err_size, path, 0, rc, "%s", pt_scene_error_message(scene));
    pt_obj_mesh_free(&m);
    return rc;
}

/* ---- Mesh and environment paths: confined to the scene's directory and the allowed ones.
   Messages start with the statement's keyword (p->tok[0]: mesh, environment). */

/* Normalises a path lexically, in place: collapses "//" and "/./" and removes "name/.."
   pairs ("/.." is "/"; a leading ".." of a relative path stays). */
static void pt__sf_normalize(char *path)
{
    char *out = path, *in = path, *base;
    int absolute = path[0] == '/', depth = 0;
    if (absolute) *out++ = '/';
    base = out;
    while (*in) {
        char *c;
        size_t n;
        while (*in == '/') ++in;
        if (!*in) break;
        c = in;
        while (*in && *in != '/') ++in;
        n = (size_t)(in - c);
        if (n == 1 && c[0] == '.') continue;
        if (n == 2 && c[0] == '.' && c[1] == '.') {
            if (depth > 0) { /* drop the last component and its separator */
                while (out > base && out[-1] != '/') --out;
                if (out > base) --out;
                --depth;
                continue;
            }
            if (absolute) continue;
        } else
            ++depth;
        if (out > base) *out++ = '/';
        memmove(out, c, n);
        out += n;
    }
    if (out == path) *out++ = '.';
    *out = '\0';
}

/* path (normalised) is root or lies below it. */
static int pt__sf_inside(const char *path, const char *root)
{
    size_t n = strlen(root);
    if (n == 1 && root[0] == '/') return path[0] == '/';
    return strncmp(path, root, n) == 0 && (path[n] == '/' || path[n] == '\0');
}
static int pt__sf_inside_any(const pt__sf_parser *p, const char *path)
{
    int i;
    for (i = 0; i < p->root_count; ++i)
        if (pt__sf_inside(path, p->roots[i])) return 1;
    return 0;
}

/* The canonical form of path (symbolic links, "." and ".." resolved), or -1 with errno. The
   stdio fallback can only normalise it lexically. */
static int pt__sf_resolve(const char *path, char *out)
{
#ifdef PT__SF_POSIX
    char *r = realpath(path, NULL); /* allocated with malloc: released with free */
    if (!r) return -1;
    if (strlen(r) >= PT__SF_PATH) { free(r); errno = ENAMETOOLONG; return -1; }
    strcpy(out, r);
    free(r);
#else
    if (strlen(path) >= PT__SF_PATH) { errno = ENAMETOOLONG; return -1; }
    strcpy(out, path);
    pt__sf_normalize(out);
#endif
    return 0;
}

/* Resolves, once, the directories input paths may lie in: the scene's, then the allowed ones. */
static int pt__sf_roots(pt__sf_parser *p)
{
    const pt_scenefile_options *o = p->opt;
    int i, count = o && o->allowed_dirs ? o->allowed_dir_count : 0;
    if (p->roots_done) return PT_OK;
    if (count < 0 || count > PT__SF_MAX_ROOTS - 1)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "pt_scenefile_options.allowed_dir_count is %d (0..%d)",
                           count, PT__SF_MAX_ROOTS - 1);
    for (i = 0; i <= count; ++i) {
        const char *dir = i == 0 ? (p->base_dir && *p->base_dir ? p->base_dir : ".") : o->allowed_dirs[i - 1];
        char buf[PT__SF_PATH];
        if (!dir) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "pt_scenefile_options.allowed_dirs[%d] is NULL", i - 1);
        if (pt__sf_resolve(dir, buf) != 0)
            return pt__sf_fail(p, PT_ERROR_IO, "%s: cannot resolve the %s '%s': %s", p->tok[0],
                               i == 0 ? "scene's directory" : "allowed directory", dir, strerror(errno));
        p->roots[i] = (char *)PT_MALLOC(strlen(buf) + 1u);
        if (!p->roots[i]) return pt__sf_fail(p, PT_ERROR_OUT_OF_MEMORY, "out of memory");
        strcpy(p->roots[i], buf);
        p->root_count = i + 1;
    }
    p->roots_done = 1;
    return PT_OK;
}

/* The one answer for every path that does not resolve to something inside the allowed
   directories: missing, dangling, or leading out through "..", an absolute path or a link.
   Whether a file outside exists is not told (nor is a link's target opened to find out). */
static int pt__sf_refuse(pt__sf_parser *p, const char *rel)
{
    return pt__sf_fail(p, PT_ERROR_UNSUPPORTED,
                       "%s: no file '%s' inside the scene's directory%s (it is missing, or it leads out; other "
                       "directories need pt_scenefile_options.allowed_dirs, or pdftrace --allow-path DIR)",
                       p->tok[0], rel, p->root_count > 1 ? " or an allowed one" : "");
}

/* Opens the file `rel` of the statement (a mesh or an environment map) if it resolves inside
   the allowed directories; shown receives the name for the file's messages (rel joined to
   base_dir). */
static int pt__sf_open_input(pt__sf_parser *p, const char *rel, char *shown, size_t shown_size, pt__sf_in *in)
{
    char joined[PT__SF_PATH], real[PT__SF_PATH];
    const char *why = "";
    int rc, n, m;
    if ((rc = pt__sf_roots(p)) != PT_OK) return rc;
    if (rel[0] == '/' || !p->base_dir || !*p->base_dir) n = snprintf(shown, shown_size, "%s", rel);
    else n = snprintf(shown, shown_size, "%s/%s", p->base_dir, rel);
    if (rel[0] == '/') m = snprintf(joined, sizeof joined, "%s", rel);
    else m = snprintf(joined, sizeof joined, "%s/%s", p->roots[0], rel);
    if (n < 0 || (size_t)n >= shown_size || m < 0 || (size_t)m >= sizeof joined)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: path too long", p->tok[0]);
#ifndef PT__SF_POSIX
    if (strchr(rel, '\\') || strchr(rel, ':')) return pt__sf_refuse(p, rel); /* no lexical view of those */
#endif
    pt__sf_normalize(joined);
    if (!pt__sf_inside_any(p, joined)) return pt__sf_refuse(p, rel);
#ifdef PT__SF_POSIX
    if (pt__sf_resolve(joined, real) != 0) return pt__sf_refuse(p, rel);
    if (!pt__sf_inside_any(p, real)) return pt__sf_refuse(p, rel);
#else
    strcpy(real, joined);
#endif
    rc = pt__sf_in_open(in, real, 1, &why);
    if (rc != PT_OK) return pt__sf_fail(p, rc, "%s: cannot read '%s': %s", p->tok[0], rel, why);
    return PT_OK;
}

static int pt__sf_over_budget(pt__sf_parser *p, const char *rel)
{
    return pt__sf_fail(p, PT_ERROR_UNSUPPORTED,
                       "mesh: '%s' does not fit in the mesh memory budget of %llu bytes (the meshes before it hold "
                       "%llu; raise pt_scenefile_options.mesh_memory, or pdftrace --mesh-memory MB)",
                       rel, (unsigned long long)p->mesh_limit, (unsigned long long)p->d->mesh_bytes);
}

/* Reads and parses the opened file `rel` within what is left of the budget, and appends it
   to d->meshes. */
static int pt__sf_new_mesh(pt__sf_parser *p, const char *rel, const char *shown, pt__sf_in *in)
{
    pt_scenefile *d = p->d;
    uint64_t left = p->mesh_limit > d->mesh_bytes ? p->mesh_limit - d->mesh_bytes : 0u;
    uint64_t dev = in->dev, ino = in->ino;
    pt_obj_mesh m, *nm;
    const char *why = "";
    char *text = NULL;
    size_t len = 0;
    int rc, over = 0;
    if (in->size > left) {
        pt__sf_in_close(in);
        return pt__sf_over_budget(p, rel);
    }
    rc = pt__sf_in_read(in, PT__SF_MAX_FILE, &text, &len, &why);
    if (rc != PT_OK) return pt__sf_fail(p, rc, "mesh: cannot read '%s': %s", rel, why);
    if ((uint64_t)len > left) {
        PT_FREE(text);
        return pt__sf_over_budget(p, rel);
    }
    memset(&m, 0, sizeof m);
    rc = pt__obj_parse(text, len, shown, left - len, &m, p->err, p->err_size, &over);
    PT_FREE(text);
    if (over) return pt__sf_over_budget(p, rel);
    if (rc != PT_OK) return rc;
    nm = (pt_obj_mesh *)PT_REALLOC(d->meshes, (size_t)(d->mesh_count + 1) * sizeof *nm);
    if (!nm) {
        pt_obj_mesh_free(&m);
        return pt__sf_fail(p, PT_ERROR_OUT_OF_MEMORY, "out of memory");
    }
    d->meshes = nm;
    p->file_dev[d->mesh_count] = dev;
    p->file_ino[d->mesh_count] = ino;
    d->meshes[d->mesh_count++] = m;
    d->mesh_bytes += pt__obj_bytes(&m);
    return PT_OK;
}

static int pt__sf_add_shape(pt__sf_parser *p, pt_scenefile_shape_type type, pt_scenefile_shape **out)
{
    pt_scenefile *d = p->d;
    int n = d->shape_count;
    pt_scenefile_shape *s;
    if (n >= PT__SF_MAX_SHAPES) return pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "too many shapes (at most %d)", PT__SF_MAX_SHAPES);
    /* Capacity: 16, then doubled whenever the count reaches a power of two >= 16. */
    if (n == 0 || (n >= 16 && (n & (n - 1)) == 0)) {
        size_t ncap = n ? (size_t)n * 2u : 16u;
        pt_scenefile_shape *ns = (pt_scenefile_shape *)PT_REALLOC(d->shapes, ncap * sizeof *ns);
        if (!ns) return pt__sf_fail(p, PT_ERROR_OUT_OF_MEMORY, "out of memory");
        d->shapes = ns;
    }
    s = &d->shapes[d->shape_count++];
    memset(s, 0, sizeof *s);
    s->type = type;
    s->transform = p->xf;
    memcpy(s->transform_d, p->xfd, sizeof s->transform_d);
    s->line = p->line;
    s->mesh = -1;
    *out = s;
    return PT_OK;
}

/* size, spp, max_depth, indirect_paths, seed, pov_light_grid: integers in their ranges. */
static int pt__sf_int_setting(pt__sf_parser *p, const char *kw)
{
    pt_scenefile *d = p->d;
    int rc = PT_OK;
    long v;
    if (!strcmp(kw, "size")) {
        if ((rc = pt__sf_int(p, "size: width", 1, 16384, &v)) != PT_OK) return rc;
        d->width = (int)v;
        if ((rc = pt__sf_int(p, "size: height", 1, 16384, &v)) != PT_OK) return rc;
        d->height = (int)v;
        if (pt_scenefile_image_bytes(d->width, d->height) > p->image_limit)
            return pt__sf_fail(p, PT_ERROR_UNSUPPORTED,
                               "size: a %d x %d render needs %llu bytes for its film and images, more than the "
                               "limit of %llu (raise pt_scenefile_options.image_memory, or pdftrace --image-memory MB)",
                               d->width, d->height, (unsigned long long)pt_scenefile_image_bytes(d->width, d->height),
                               (unsigned long long)p->image_limit);
    } else if (!strcmp(kw, "spp")) {
        if ((rc = pt__sf_int(p, "spp", 1, 1L << 20, &v)) != PT_OK) return rc;
        d->samples_per_pixel = (int)v;
    } else if (!strcmp(kw, "max_depth")) {
        if ((rc = pt__sf_int(p, "max_depth", 1, 100000, &v)) != PT_OK) return rc;
        d->max_depth = (int)v;
    } else if (!strcmp(kw, "indirect_paths")) {
        if ((rc = pt__sf_int(p, "indirect_paths", 1, PT_INDIRECT_PATHS_MAX, &v)) != PT_OK) return rc;
        d->indirect_paths = (int)v;
    } else if (!strcmp(kw, "seed")) {
        if ((rc = pt__sf_int(p, "seed", 0, 2147483647L, &v)) != PT_OK) return rc;
        d->seed = (uint64_t)v;
    } else if (!strcmp(kw, "pov_light_grid")) {
        if ((rc = pt__sf_int(p, "pov_light_grid", 1, 64, &v)) != PT_OK) return rc;
        d->pov_light_grid = (int)v;
    }
    return PT_OK;
}

/* strategy, pov_radiosity, sampler, integrator: one of a few names. */
static int pt__sf_choice(pt__sf_parser *p, const char *kw)
{
    pt_scenefile *d = p->d;
    if (!strcmp(kw, "strategy") || !strcmp(kw, "pov_radiosity")) {
        static const char *const strategies[] = {"mis", "material", "light", "mixture"};
        static const char *const radiosity[] = {"none", "default", "medium", "high"};
        const char *const *names = kw[0] == 's' ? strategies : radiosity;
        const char *t = pt__sf_next(p);
        int i, found = -1;
        for (i = 0; t && i < 4; ++i)
            if (!strcmp(t, names[i])) found = i;
        if (found < 0)
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: expected %s, %s, %s or %s, got '%s'", kw, names[0],
                               names[1], names[2], names[3], t ? t : "nothing");
        if (kw[0] == 's') d->strategy = (pt_strategy)found;
        else d->pov_radiosity = found;
    } else if (!strcmp(kw, "sampler")) {
        const char *t = pt__sf_next(p);
        if (t && !strcmp(t, "independent")) d->sampler = PT_SAMPLER_INDEPENDENT;
        else if (t && !strcmp(t, "sobol")) d->sampler = PT_SAMPLER_SOBOL;
        else
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "sampler: expected independent or sobol, got '%s'",
                               t ? t : "nothing");
    } else if (!strcmp(kw, "integrator")) {
        const char *t = pt__sf_next(p);
        if (t && !strcmp(t, "scalar")) d->integrator = PT_INTEGRATOR_SCALAR;
        else if (t && !strcmp(t, "batched")) d->integrator = PT_INTEGRATOR_BATCHED;
        else
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "integrator: expected scalar or batched, got '%s'",
                               t ? t : "nothing");
    }
    return PT_OK;
}

/* guiding off|on|auto, guiding_budget F, guiding_alpha F (both in (0, 1), checked as the float
   pt_render gets), guiding_memory MIB. */
static int pt__sf_guiding(pt__sf_parser *p, const char *kw)
{
    pt_scenefile *d = p->d;
    int rc;
    long v;
    float f;
    if (!strcmp(kw, "guiding")) {
        static const char *const names[] = {"off", "on", "auto"};
        static const pt_guiding ids[] = {PT_GUIDING_OFF, PT_GUIDING_ON, PT_GUIDING_AUTO};
        const char *t = pt__sf_next(p);
        int i, found = -1;
        for (i = 0; t && i < 3; ++i)
            if (!strcmp(t, names[i])) found = i;
        if (found < 0)
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "guiding: expected off, on or auto, got '%s'",
                               t ? t : "nothing");
        d->guiding = ids[found];
    } else if (!strcmp(kw, "guiding_memory")) {
        if ((rc = pt__sf_int(p, "guiding_memory", 1, 1048576L, &v)) != PT_OK) return rc;
        d->guiding_memory = (int)v;
    } else {
        if ((rc = pt__sf_num(p, kw, &f)) != PT_OK) return rc;
        if (!(f > 0.0f && f < 1.0f))
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: must be in (0, 1), got '%s'", kw, p->tok[p->pos - 1]);
        if (!strcmp(kw, "guiding_budget")) d->guiding_budget = f;
        else d->guiding_alpha = f;
    }
    return PT_OK;
}

/* camera look_from X Y Z look_at X Y Z [up X Y Z] [vfov DEGREES] [lens_radius R]
   [focus_distance D], once. */
static int pt__sf_camera(pt__sf_parser *p)
{
    pt_scenefile *d = p->d;
    int rc = PT_OK;
    int have_from = 0, have_at = 0;
    pt_camera cam;
    if (p->have_camera) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "camera: defined twice");
    while (rc == PT_OK && p->pos < p->ntok) {
        const char *key = pt__sf_next(p);
        if (!strcmp(key, "look_from")) { rc = pt__sf_vec(p, "camera look_from", &d->camera.look_from); have_from = 1; }
        else if (!strcmp(key, "look_at")) { rc = pt__sf_vec(p, "camera look_at", &d->camera.look_at); have_at = 1; }
        else if (!strcmp(key, "up")) rc = pt__sf_vec(p, "camera up", &d->camera.up);
        else if (!strcmp(key, "vfov")) {
            rc = pt__sf_num(p, "camera vfov", &d->camera.vfov_degrees);
            if (rc == PT_OK && !(d->camera.vfov_degrees > 0.0f && d->camera.vfov_degrees < 180.0f))
                rc = pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "camera vfov: must be in (0, 180) degrees");
        } else if (!strcmp(key, "lens_radius")) {
            rc = pt__sf_num(p, "camera lens_radius", &d->camera.lens_radius);
            if (rc == PT_OK && !(d->camera.lens_radius >= 0.0f))
                rc = pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "camera lens_radius: must be >= 0 (0: a pinhole)");
        } else if (!strcmp(key, "focus_distance")) {
            rc = pt__sf_num(p, "camera focus_distance", &d->camera.focus_distance);
            if (rc == PT_OK && !(d->camera.focus_distance > 0.0f))
                rc = pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "camera focus_distance: must be > 0");
        } else
            rc = pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT,
                             "camera: unknown key '%s' (look_from, look_at, up, vfov, lens_radius, focus_distance)", key);
    }
    if (rc != PT_OK) return rc;
    if (!have_from || !have_at) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "camera: needs look_from and look_at");
    if (pt_camera_init(&cam, &d->camera, 1, 1) != PT_OK)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "camera: look_from equals look_at, or up is parallel to the view");
    p->have_camera = p->line;
    d->camera_line = p->line;
    return PT_OK;
}

/* checker NAME R G B R G B SCALE */
static int pt__sf_checker(pt__sf_parser *p)
{
    pt_scenefile *d = p->d;
    int rc = PT_OK;
    const char *name = NULL;
    pt_scenefile_checker c;
    if ((rc = pt__sf_new_name(p, "checker", &name)) != PT_OK) return rc;
    memset(&c, 0, sizeof c);
    strcpy(c.name, name);
    if ((rc = pt__sf_color(p, "checker: first colour", &c.even)) != PT_OK) return rc;
    if ((rc = pt__sf_color(p, "checker: second colour", &c.odd)) != PT_OK) return rc;
    if ((rc = pt__sf_num(p, "checker: scale", &c.scale)) != PT_OK) return rc;
    if (!(c.scale >= 1e-6f)) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "checker: scale must be >= 1e-6");
    if (d->checker_count >= 65536) return pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "too many checkers");
    {
        pt_scenefile_checker *nc = (pt_scenefile_checker *)PT_REALLOC(d->checkers, (size_t)(d->checker_count + 1) * sizeof *nc);
        if (!nc) return pt__sf_fail(p, PT_ERROR_OUT_OF_MEMORY, "out of memory");
        d->checkers = nc;
        d->checkers[d->checker_count++] = c;
    }
    return PT_OK;
}

/* roughconductor ALPHA METAL [tint R G B], METAL: Au Ag Cu Al none | eta R G B k R G B */
static int pt__sf_roughconductor(pt__sf_parser *p, pt_scenefile_material *m)
{
    static const char *const names[4] = { "Au", "Ag", "Cu", "Al" };
    const char *metal;
    int rc, i;
    m->type = PT_MATERIAL_ROUGH_CONDUCTOR;
    m->albedo = pt_v3(1.0f, 1.0f, 1.0f);
    if ((rc = pt__sf_num(p, "roughconductor alpha", &m->roughness)) != PT_OK) return rc;
    if (!(m->roughness >= 0.0f && m->roughness <= 1.0f))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughconductor alpha: must be in [0, 1] (GGX alpha)");
    metal = pt__sf_next(p);
    if (!metal) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughconductor: missing metal (Au, Ag, Cu, Al, none, or eta R G B k R G B)");
    m->conductor = PT_CONDUCTOR_NONE;
    for (i = 0; i < 4; ++i)
        if (!strcmp(metal, names[i])) m->conductor = (pt_conductor)((int)PT_CONDUCTOR_AU + i);
    if (!strcmp(metal, "eta")) {
        m->conductor = PT_CONDUCTOR_CUSTOM;
        if ((rc = pt__sf_color(p, "roughconductor eta", &m->eta)) != PT_OK) return rc;
        if (!(m->eta.x > 0.0f && m->eta.y > 0.0f && m->eta.z > 0.0f))
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughconductor eta: must be > 0");
        metal = pt__sf_next(p);
        if (!metal || strcmp(metal, "k")) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughconductor: expected 'k R G B' after eta");
        if ((rc = pt__sf_color(p, "roughconductor k", &m->k)) != PT_OK) return rc;
    } else if (m->conductor == PT_CONDUCTOR_NONE && strcmp(metal, "none"))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughconductor: unknown metal (Au, Ag, Cu, Al, none, or eta R G B k R G B)");
    if (p->pos < p->ntok && !strcmp(p->tok[p->pos], "tint")) {
        p->pos++;
        if ((rc = pt__sf_color(p, "roughconductor tint", &m->albedo)) != PT_OK) return rc;
    }
    return PT_OK;
}

/* roughplastic ALPHA R G B | ALPHA texture CHECKER, then [ior IOR] [nonlinear] in any order */
static int pt__sf_roughplastic(pt__sf_parser *p, pt_scenefile_material *m)
{
    int rc;
    m->type = PT_MATERIAL_ROUGH_PLASTIC;
    if ((rc = pt__sf_num(p, "roughplastic alpha", &m->roughness)) != PT_OK) return rc;
    if (!(m->roughness >= 0.0f && m->roughness <= 1.0f))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughplastic alpha: must be in [0, 1] (GGX alpha)");
    if (p->pos < p->ntok && !strcmp(p->tok[p->pos], "texture")) {
        const char *t;
        p->pos++;
        t = pt__sf_next(p);
        if (!t) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughplastic: missing checker name after 'texture'");
        m->checker = pt__sf_find_checker(p->d, t);
        if (m->checker < 0) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughplastic: checker '%s' is not defined", t);
        if (pt_max_component(p->d->checkers[m->checker].even) > 1.0f || pt_max_component(p->d->checkers[m->checker].odd) > 1.0f)
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughplastic: checker '%s' has a colour above 1 (the base's albedo must be in [0, 1])", t);
        m->albedo = pt_v3(0.5f, 0.5f, 0.5f);
    } else {
        if ((rc = pt__sf_color(p, "roughplastic albedo", &m->albedo)) != PT_OK) return rc;
        if (m->albedo.x > 1.0f || m->albedo.y > 1.0f || m->albedo.z > 1.0f)
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughplastic albedo: must be in [0, 1]");
    }
    m->ior = 1.5f;
    while (p->pos < p->ntok) {
        if (!strcmp(p->tok[p->pos], "ior")) {
            p->pos++;
            if ((rc = pt__sf_num(p, "roughplastic ior", &m->ior)) != PT_OK) return rc;
            if (!(m->ior > 1.0f && m->ior <= 10.0f))
                return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughplastic ior: must be in (1, 10]");
        } else if (!strcmp(p->tok[p->pos], "nonlinear")) {
            p->pos++;
            m->nonlinear = 1;
        } else
            break; /* pt__sf_end reports it */
    }
    return PT_OK;
}

/* roughdielectric ALPHA IOR [ext_ior E] */
static int pt__sf_roughdielectric(pt__sf_parser *p, pt_scenefile_material *m)
{
    int rc;
    m->type = PT_MATERIAL_ROUGH_DIELECTRIC;
    m->ext_ior = 1.0f;
    if ((rc = pt__sf_num(p, "roughdielectric alpha", &m->roughness)) != PT_OK) return rc;
    if (!(m->roughness >= 0.0f && m->roughness <= 1.0f))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughdielectric alpha: must be in [0, 1] (GGX alpha)");
    if ((rc = pt__sf_num(p, "roughdielectric ior", &m->ior)) != PT_OK) return rc;
    if (!(m->ior >= 1.0f && m->ior <= 10.0f))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughdielectric ior: must be in [1, 10]");
    if (p->pos < p->ntok && !strcmp(p->tok[p->pos], "ext_ior")) {
        p->pos++;
        if ((rc = pt__sf_num(p, "roughdielectric ext_ior", &m->ext_ior)) != PT_OK) return rc;
        if (!(m->ext_ior >= 1.0f && m->ext_ior <= 10.0f))
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "roughdielectric ext_ior: must be in [1, 10]");
    }
    return PT_OK;
}

/* material NAME TYPE ...: lambertian, metal, roughconductor, roughplastic, dielectric, roughdielectric or emitter. */
static int pt__sf_material(pt__sf_parser *p)
{
    pt_scenefile *d = p->d;
    int rc = PT_OK;
    const char *name = NULL, *type;
    pt_scenefile_material m;
    if ((rc = pt__sf_new_name(p, "material", &name)) != PT_OK) return rc;
    memset(&m, 0, sizeof m);
    strcpy(m.name, name);
    m.checker = -1;
    m.image = -1;
    type = pt__sf_next(p);
    if (!type) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "material %s: missing type (lambertian, metal, roughconductor, roughplastic, dielectric, roughdielectric, emitter)", name);
    if (!strcmp(type, "lambertian")) {
        m.type = PT_MATERIAL_LAMBERTIAN;
        if (p->pos < p->ntok && !strcmp(p->tok[p->pos], "texture")) {
            const char *t;
            p->pos++;
            t = pt__sf_next(p);
            if (!t) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "material %s: missing texture name after 'texture'", name);
            m.checker = pt__sf_find_checker(d, t);
            m.image = pt__sf_find_image(d, t);
            if (m.checker < 0 && m.image < 0)
                return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "material %s: texture '%s' is not defined (checker or image_texture)",
                                   name, t);
        } else if ((rc = pt__sf_color(p, "lambertian albedo", &m.albedo)) != PT_OK) return rc;
    } else if (!strcmp(type, "metal")) {
        m.type = PT_MATERIAL_METAL;
        if ((rc = pt__sf_color(p, "metal albedo", &m.albedo)) != PT_OK) return rc;
        if (p->pos < p->ntok && !strcmp(p->tok[p->pos], "fuzz")) {
            p->pos++;
            if ((rc = pt__sf_num(p, "metal fuzz", &m.fuzz)) != PT_OK) return rc;
            if (m.fuzz < 0 || m.fuzz > 1) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "metal fuzz: must be in [0, 1]");
        }
    } else if (!strcmp(type, "roughconductor")) {
        if ((rc = pt__sf_roughconductor(p, &m)) != PT_OK) return rc;
    } else if (!strcmp(type, "roughplastic")) {
        if ((rc = pt__sf_roughplastic(p, &m)) != PT_OK) return rc;
    } else if (!strcmp(type, "roughdielectric")) {
        if ((rc = pt__sf_roughdielectric(p, &m)) != PT_OK) return rc;
    } else if (!strcmp(type, "dielectric")) {
        m.type = PT_MATERIAL_DIELECTRIC;
        if ((rc = pt__sf_num(p, "dielectric ior", &m.ior)) != PT_OK) return rc;
        if (!(m.ior >= 1.0f && m.ior <= 10.0f)) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "dielectric ior: must be in [1, 10]");
    } else if (!strcmp(type, "emitter")) {
        m.type = PT_MATERIAL_EMITTER;
        if ((rc = pt__sf_color(p, "emitter radiance", &m.emission)) != PT_OK) return rc;
        if (p->pos < p->ntok && !strcmp(p->tok[p->pos], "two_sided")) { p->pos++; m.two_sided = 1; }
    } else
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "material %s: unknown type '%s' (lambertian, metal, roughconductor, roughplastic, dielectric, roughdielectric, emitter)", name, type);
    if ((rc = pt__sf_end(p)) != PT_OK) return rc;
    if (d->material_count >= 65536) return pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "too many materials");
    {
        pt_scenefile_material *nm = (pt_scenefile_material *)PT_REALLOC(d->materials, (size_t)(d->material_count + 1) * sizeof *nm);
        if (!nm) return pt__sf_fail(p, PT_ERROR_OUT_OF_MEMORY, "out of memory");
        d->materials = nm;
        d->materials[d->material_count++] = m;
    }
    return PT_OK;
}

/* sphere, quad, triangle, box: points, then a radius (sphere) and the material. */
static int pt__sf_shape(pt__sf_parser *p, const char *kw)
{
    int rc = PT_OK;
    pt_scenefile_shape tmp;
    pt_scenefile_shape *s;
    int i, npts = kw[0] == 's' ? 1 : kw[0] == 'b' ? 2 : 3;
    memset(&tmp, 0, sizeof tmp);
    for (i = 0; i < npts; ++i)
        if ((rc = pt__sf_vec(p, kw, &tmp.p[i])) != PT_OK) return rc;
    if (kw[0] == 's') {
        if ((rc = pt__sf_num(p, "sphere radius", &tmp.radius)) != PT_OK) return rc;
        if (!(tmp.radius > 0)) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "sphere: radius must be > 0");
    }
    if ((rc = pt__sf_material_ref(p, &tmp.material)) != PT_OK) return rc;
    if ((rc = pt__sf_end(p)) != PT_OK) return rc;
    if (kw[0] == 'q' && !(pt_length2(pt_cross(tmp.p[1], tmp.p[2])) > 0))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "quad: u and v are parallel or zero (no area)");
    if (kw[0] == 'b' && !(tmp.p[0].x < tmp.p[1].x && tmp.p[0].y < tmp.p[1].y && tmp.p[0].z < tmp.p[1].z))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "box: the first corner must be below the second on every axis");
    if ((rc = pt__sf_add_shape(p, kw[0] == 's' ? PT_SCENEFILE_SPHERE : kw[0] == 'q' ? PT_SCENEFILE_QUAD : kw[0] == 't' ? PT_SCENEFILE_TRIANGLE : PT_SCENEFILE_BOX, &s)) != PT_OK)
        return rc;
    memcpy(s->p, tmp.p, sizeof tmp.p);
    s->radius = tmp.radius;
    s->material = tmp.material;
    return PT_OK;
}

/* mesh PATH MATERIAL: the OBJ file is read now, relative to the scene file; a file already
   read by an earlier mesh statement (the same device and inode) is shared, not read again. */
static int pt__sf_mesh(pt__sf_parser *p)
{
    pt_scenefile *d = p->d;
    int rc = PT_OK, mat, i;
    const char *file = pt__sf_next(p);
    char shown[PT__SF_PATH];
    pt__sf_in in;
    pt_scenefile_shape *s;
    if (!file) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "mesh: missing OBJ file name");
    if ((rc = pt__sf_material_ref(p, &mat)) != PT_OK) return rc;
    if ((rc = pt__sf_end(p)) != PT_OK) return rc;
    if (p->mesh_statements >= PT__SF_MAX_MESHES)
        return pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "too many meshes (at most %d)", PT__SF_MAX_MESHES);
    if ((rc = pt__sf_open_input(p, file, shown, sizeof shown, &in)) != PT_OK) return rc;
    for (i = 0; i < d->mesh_count; ++i)
        if (p->file_dev[i] == in.dev && p->file_ino[i] == in.ino) break;
    if (i < d->mesh_count) pt__sf_in_close(&in);
    else if ((rc = pt__sf_new_mesh(p, file, shown, &in)) != PT_OK) return rc;
    p->mesh_statements++;
    if ((rc = pt__sf_add_shape(p, PT_SCENEFILE_MESH, &s)) != PT_OK) return rc;
    s->mesh = i;
    s->material = mat;
    return PT_OK;
}

/* point_light X Y Z R G B | spot_light X Y Z TX TY TZ R G B [CUTOFF [BEAM]] |
   directional_light DX DY DZ R G B. Checked here as pt_scene_add_light checks them, so that
   a bad light is a file:line error at load; the transform is checked by the build. */
static int pt__sf_light(pt__sf_parser *p, const char *kw)
{
    pt_scenefile *d = p->d;
    pt_scenefile_light l, *nl;
    pt_light_desc *ld = &l.desc;
    char what[48];
    int rc;
    memset(&l, 0, sizeof l);
    ld->type = kw[0] == 'p' ? PT_LIGHT_POINT : kw[0] == 's' ? PT_LIGHT_SPOT : PT_LIGHT_DIRECTIONAL;
    if (ld->type == PT_LIGHT_DIRECTIONAL) {
        snprintf(what, sizeof what, "%s direction", kw);
        if ((rc = pt__sf_vec(p, what, &ld->direction)) != PT_OK) return rc;
        if (!(pt_length2(ld->direction) > 0.0f))
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: the direction has zero length", kw);
    } else {
        snprintf(what, sizeof what, "%s position", kw);
        if ((rc = pt__sf_vec(p, what, &ld->position)) != PT_OK) return rc;
    }
    if (ld->type == PT_LIGHT_SPOT) {
        pt_vec3 target;
        if ((rc = pt__sf_vec(p, "spot_light target", &target)) != PT_OK) return rc;
        ld->direction = pt_sub(target, ld->position);
        if (!(pt_length2(ld->direction) > 0.0f))
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "spot_light: the target equals the position (no direction)");
    }
    snprintf(what, sizeof what, "%s %s", kw, ld->type == PT_LIGHT_DIRECTIONAL ? "irradiance" : "intensity");
    if ((rc = pt__sf_color(p, what, &ld->intensity)) != PT_OK) return rc;
    if (ld->intensity.x == 0.0f && ld->intensity.y == 0.0f && ld->intensity.z == 0.0f)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: all zero (a light must emit)", what);
    if (ld->type == PT_LIGHT_SPOT) {
        ld->cutoff_angle = 20.0f; /* pt_light_desc's defaults, written out for the exporters */
        if (p->pos < p->ntok) {
            if ((rc = pt__sf_num(p, "spot_light cutoff_angle", &ld->cutoff_angle)) != PT_OK) return rc;
            if (!(ld->cutoff_angle > 0.0f && ld->cutoff_angle <= 90.0f))
                return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "spot_light cutoff_angle: must be in (0, 90] degrees, got '%s'",
                                   p->tok[p->pos - 1]);
        }
        ld->beam_width = 0.75f * ld->cutoff_angle;
        if (p->pos < p->ntok) {
            if ((rc = pt__sf_num(p, "spot_light beam_width", &ld->beam_width)) != PT_OK) return rc;
            if (!(ld->beam_width > 0.0f && ld->beam_width <= ld->cutoff_angle))
                return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT,
                                   "spot_light beam_width: must be in (0, cutoff_angle = %g] degrees, got '%s'",
                                   (double)ld->cutoff_angle, p->tok[p->pos - 1]);
        }
    }
    if ((rc = pt__sf_end(p)) != PT_OK) return rc;
    if (d->light_count >= PT__SF_MAX_LIGHTS)
        return pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "too many lights (at most %d)", PT__SF_MAX_LIGHTS);
    l.transform = p->xf;
    memcpy(l.transform_d, p->xfd, sizeof l.transform_d);
    l.line = p->line;
    /* capacity as for shapes: 16, then doubled whenever the count reaches a power of two >= 16 */
    if (d->light_count == 0 || (d->light_count >= 16 && (d->light_count & (d->light_count - 1)) == 0)) {
        size_t ncap = d->light_count ? (size_t)d->light_count * 2u : 16u;
        nl = (pt_scenefile_light *)PT_REALLOC(d->lights, ncap * sizeof *nl);
        if (!nl) return pt__sf_fail(p, PT_ERROR_OUT_OF_MEMORY, "out of memory");
        d->lights = nl;
    }
    d->lights[d->light_count++] = l;
    return PT_OK;
}

/* ---- PFM in memory, for the environment statement (its file comes through the confined
   reader above): "PF" (RGB) or "Pf" (grey), then width, height and scale as text separated by
   whitespace, one whitespace byte, then 4-byte floats row by row from the bottom row up,
   little-endian when the scale is negative. Messages name the file and never quote it. */
#define PT__SF_MAX_ENV_PIXELS (1u << 25) /* 8192 x 4096: 400 MB as float RGB */
static int pt__sf_pfm_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
/* The header token at *pos (printable ASCII, at most n - 1 bytes) and the one whitespace byte
   after it; 0 if there is none. */
static int pt__sf_pfm_token(const char *t, size_t len, size_t *pos, char *tok, size_t n)
{
    size_t k = 0;
    while (*pos < len && pt__sf_pfm_space(t[*pos])) ++*pos;
    while (*pos < len && !pt__sf_pfm_space(t[*pos])) {
        if (k + 1 >= n || t[*pos] < 0x21 || t[*pos] > 0x7e) return 0;
        tok[k++] = t[(*pos)++];
    }
    tok[k] = '\0';
    if (k == 0 || *pos >= len) return 0;
    ++*pos;
    return 1;
}
static int pt__sf_pfm(const char *t, size_t len, const char *name, pt_image *out, char *err, size_t err_size)
{
    char magic[4], ws[12], hs[12], ss[40], *end;
    size_t pos = 0;
    long w = 0, h = 0;
    double scale = 0.0;
    int ch, x, y, c, rc;
    memset(out, 0, sizeof *out);
    if (!pt__sf_pfm_token(t, len, &pos, magic, sizeof magic) || (strcmp(magic, "PF") && strcmp(magic, "Pf")) ||
        !pt__sf_pfm_token(t, len, &pos, ws, sizeof ws) || !pt__sf_pfm_token(t, len, &pos, hs, sizeof hs) ||
        !pt__sf_pfm_token(t, len, &pos, ss, sizeof ss))
        return pt__sf_failf(err, err_size, name, 0, PT_ERROR_INVALID_ARGUMENT,
                            "not a PFM file (no 'PF' or 'Pf' header with width, height and scale)");
    ch = magic[1] == 'F' ? 3 : 1;
    w = strtol(ws, &end, 10);
    if (*end) w = 0;
    h = strtol(hs, &end, 10);
    if (*end) h = 0;
    scale = strtod(ss, &end);
    if (*end || !pt__sf_finite(scale) || scale == 0.0 || w < 1 || h < 1 || w > 65536 || h > 65536)
        return pt__sf_failf(err, err_size, name, 0, PT_ERROR_INVALID_ARGUMENT,
                            "bad PFM header (width and height 1..65536, a finite non-zero scale)");
    if ((uint64_t)w * (uint64_t)h > PT__SF_MAX_ENV_PIXELS)
        return pt__sf_failf(err, err_size, name, 0, PT_ERROR_UNSUPPORTED, "%ld x %ld pixels: an environment map may have %lu",
                            w, h, (unsigned long)PT__SF_MAX_ENV_PIXELS);
    if ((uint64_t)w * (uint64_t)h * (uint64_t)ch * 4u > (uint64_t)(len - pos))
        return pt__sf_failf(err, err_size, name, 0, PT_ERROR_INVALID_ARGUMENT,
                            "truncated PFM: %ld x %ld pixels need %llu bytes of data, the file has %llu", w, h,
                            (unsigned long long)((uint64_t)w * (uint64_t)h * (uint64_t)ch * 4u),
                            (unsigned long long)(len - pos));
    if ((rc = pt_image_init(out, (int)w, (int)h)) != PT_OK)
        return pt__sf_failf(err, err_size, name, 0, rc, "out of memory for %ld x %ld pixels", w, h);
    for (y = (int)h - 1; y >= 0; --y) /* the file's first row is the image's bottom one */
        for (x = 0; x < (int)w; ++x) {
            const unsigned char *px = (const unsigned char *)t + pos;
            for (c = 0; c < 3; ++c) { /* grey: its one value in R, G and B */
                const unsigned char *b = px + 4 * (c < ch ? c : 0);
                uint32_t u = scale < 0.0 ? (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24
                                         : (uint32_t)b[3] | (uint32_t)b[2] << 8 | (uint32_t)b[1] << 16 | (uint32_t)b[0] << 24;
                memcpy(out->rgb + 3u * ((size_t)y * (size_t)w + (size_t)x) + (size_t)c, &u, 4);
            }
            pos += 4u * (size_t)ch;
        }
    return PT_OK;
}

/* 1 if path ends in ext (".pfm", ".exr"), whatever the case of its letters. */
static int pt__sf_has_ext(const char *path, const char *ext)
{
    size_t n = strlen(path), k = strlen(ext), i;
    if (n <= k) return 0;
    for (i = 0; i < k; ++i) {
        char c = path[n - k + i];
        if ((c >= 'A' && c <= 'Z' ? (char)(c - 'A' + 'a') : c) != ext[i]) return 0;
    }
    return 1;
}

/* environment FILE [SCALE], once: the map is read now, from a path confined as a mesh's, and
   decoded as PFM (a .pfm file) or by pt_scenefile_options.read_image (any other); the build
   checks its pixels and that the transform in effect is a rotation (pt_scene_set_environment). */
static int pt__sf_environment(pt__sf_parser *p)
{
    pt_scenefile *d = p->d;
    const char *file = pt__sf_next(p), *why = "";
    char shown[PT__SF_PATH], msg[768];
    float scale = 1.0f;
    pt__sf_in in;
    pt_image img;
    char *data = NULL;
    size_t len = 0;
    int rc, pfm;
    if (!file) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "environment: missing image file name");
    if (p->pos < p->ntok) {
        if ((rc = pt__sf_num(p, "environment scale", &scale)) != PT_OK) return rc;
        if (!(scale > 0.0f))
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "environment scale: must be > 0, got '%s'", p->tok[p->pos - 1]);
    }
    if ((rc = pt__sf_end(p)) != PT_OK) return rc;
    if (d->environment_line)
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "environment: a second map (the first is at line %d; a scene has one)",
                           d->environment_line);
    pfm = pt__sf_has_ext(file, ".pfm");
    if (!pfm && !(p->opt && p->opt->read_image))
        return pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "environment: '%s': %s", file,
                           pt__sf_has_ext(file, ".exr")
                               ? "this program was built without OpenEXR, so it reads PFM maps only "
                                 "(pt_scenefile_options.read_image is NULL)"
                               : "not a .pfm file, and this program reads no other format (an .exr map needs a build "
                                 "with OpenEXR)");
    if ((rc = pt__sf_open_input(p, file, shown, sizeof shown, &in)) != PT_OK) return rc;
    if ((rc = pt__sf_in_read(&in, PT__SF_MAX_FILE, &data, &len, &why)) != PT_OK)
        return pt__sf_fail(p, rc, "environment: cannot read '%s': %s", file, why);
    msg[0] = '\0';
    memset(&img, 0, sizeof img);
    rc = pfm ? pt__sf_pfm(data, len, shown, &img, msg, sizeof msg) : p->opt->read_image(data, len, shown, &img, msg, sizeof msg);
    PT_FREE(data);
    if (rc == PT_OK && (img.width < 1 || img.height < 1 || !img.rgb)) {
        pt_image_free(&img);
        return pt__sf_fail(p, PT_ERROR_IO, "environment: '%s': the image reader returned no pixels", file);
    }
    if (rc == PT_OK && (uint64_t)img.width * (uint64_t)img.height > PT__SF_MAX_ENV_PIXELS) {
        rc = pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "environment: '%s': %d x %d pixels: a map may have %lu", file, img.width,
                         img.height, (unsigned long)PT__SF_MAX_ENV_PIXELS);
        pt_image_free(&img);
        return rc;
    }
    if (rc != PT_OK) {
        pt_image_free(&img);
        return pt__sf_fail(p, rc < 0 ? rc : PT_ERROR_IO, "environment: %s", msg[0] ? msg : "cannot decode the image");
    }
    d->environment = img;
    d->environment_scale = scale;
    d->environment_transform = p->xf;
    d->environment_line = p->line;
    return PT_OK;
}

/* image_texture NAME FILE [raw]: FILE confined as a mesh's path, decoded as PFM (.pfm), PNG
   (.png, by pt_scenefile_options.read_png; 8-bit sRGB codes decoded to linear unless raw) or
   by read_image (any other, OpenEXR); PFM and EXR are linear already. Pixels must be finite
   and >= 0, at most PT__SF_MAX_ENV_PIXELS of them. */
static int pt__sf_image_texture(pt__sf_parser *p)
{
    pt_scenefile *d = p->d;
    const char *name = NULL, *file, *why = "";
    char shown[PT__SF_PATH], msg[768];
    pt__sf_in in;
    pt_scenefile_image t;
    pt_scenefile_image *nt;
    char *data = NULL;
    size_t len = 0, i, n;
    int rc, pfm, png;
    int (*reader)(const void *, size_t, const char *, pt_image *, char *, size_t);
    if ((rc = pt__sf_new_name(p, "image_texture", &name)) != PT_OK) return rc;
    memset(&t, 0, sizeof t);
    strcpy(t.name, name);
    t.line = p->line;
    file = pt__sf_next(p);
    if (!file) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "image_texture %s: missing image file name", name);
    if (p->pos < p->ntok && !strcmp(p->tok[p->pos], "raw")) { p->pos++; t.raw = 1; }
    if ((rc = pt__sf_end(p)) != PT_OK) return rc;
    pfm = pt__sf_has_ext(file, ".pfm");
    png = pt__sf_has_ext(file, ".png");
    reader = png ? (p->opt ? p->opt->read_png : NULL) : (p->opt ? p->opt->read_image : NULL);
    if (!pfm && !reader)
        return pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "image_texture %s: '%s': %s", name, file,
                           png ? "this program was built without libpng, so it reads no PNG textures "
                                 "(pt_scenefile_options.read_png is NULL)"
                               : "not a .pfm or .png file, and this program reads no other format (an .exr texture "
                                 "needs a build with OpenEXR)");
    if (d->image_count >= 4096) return pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "image_texture: too many textures (4096)");
    if ((rc = pt__sf_open_input(p, file, shown, sizeof shown, &in)) != PT_OK) return rc;
    if ((rc = pt__sf_in_read(&in, PT__SF_MAX_FILE, &data, &len, &why)) != PT_OK)
        return pt__sf_fail(p, rc, "image_texture %s: cannot read '%s': %s", name, file, why);
    msg[0] = '\0';
    rc = pfm ? pt__sf_pfm(data, len, shown, &t.image, msg, sizeof msg) : reader(data, len, shown, &t.image, msg, sizeof msg);
    PT_FREE(data);
    if (rc != PT_OK) {
        pt_image_free(&t.image);
        return pt__sf_fail(p, rc < 0 ? rc : PT_ERROR_IO, "image_texture %s: %s", name, msg[0] ? msg : "cannot decode the image");
    }
    if (t.image.width < 1 || t.image.height < 1 || !t.image.rgb ||
        (uint64_t)t.image.width * (uint64_t)t.image.height > PT__SF_MAX_ENV_PIXELS) {
        rc = pt__sf_fail(p, PT_ERROR_UNSUPPORTED, "image_texture %s: '%s': %d x %d pixels: a texture has 1 to %lu", name, file,
                         t.image.width, t.image.height, (unsigned long)PT__SF_MAX_ENV_PIXELS);
        pt_image_free(&t.image);
        return rc;
    }
    n = 3u * (size_t)t.image.width * (size_t)t.image.height;
    for (i = 0; i < n; ++i) {
        float v = t.image.rgb[i];
        if (!pt__sf_isfinite(v) || v < 0.0f) {
            rc = pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "image_texture %s: '%s': pixel (%d, %d) is not finite and >= 0",
                             name, file, (int)((i / 3u) % (size_t)t.image.width), (int)((i / 3u) / (size_t)t.image.width));
            pt_image_free(&t.image);
            return rc;
        }
        if (png && !t.raw) t.image.rgb[i] = pt_srgb_decode(v);
    }
    nt = (pt_scenefile_image *)PT_REALLOC(d->images, (size_t)(d->image_count + 1) * sizeof *nt);
    if (!nt) {
        pt_image_free(&t.image);
        return pt__sf_fail(p, PT_ERROR_OUT_OF_MEMORY, "out of memory");
    }
    d->images = nt;
    d->images[d->image_count++] = t;
    return PT_OK;
}

/* xfd = t xfd in double: a translation of 1e7 after a rotation keeps the object's small
   coordinates exact, where the float product rounds them to 1 unit. */
static void pt__sf_xfd_identity(double x[3][4])
{
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 4; ++j) x[i][j] = i == j ? 1.0 : 0.0;
}
static void pt__sf_xfd_mul(double x[3][4], const pt_transform *t)
{
    double r[3][4];
    int i, j;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 4; ++j)
            r[i][j] = (double)t->m[i][0] * x[0][j] + (double)t->m[i][1] * x[1][j] + (double)t->m[i][2] * x[2][j] +
                      (j == 3 ? (double)t->m[i][3] : 0.0);
    memcpy(x, r, sizeof r);
}

/* translate, scale, rotate: composed after the transform in effect (identity resets it). */
static int pt__sf_transform(pt__sf_parser *p, const char *kw)
{
    int rc = PT_OK;
    pt_vec3 a;
    pt_transform t;
    float det;
    if ((rc = pt__sf_vec(p, kw, &a)) != PT_OK) return rc;
    if (kw[0] == 'r') {
        float deg;
        if ((rc = pt__sf_num(p, "rotate angle", &deg)) != PT_OK) return rc;
        if (!(pt_length2(a) > 1e-20f)) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "rotate: the axis has zero length");
        t = pt_transform_rotate(pt_normalize(a), deg);
    } else if (kw[0] == 's') {
        if (!(fabsf(a.x) >= 1e-6f && fabsf(a.y) >= 1e-6f && fabsf(a.z) >= 1e-6f))
            return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "scale: every factor must have magnitude >= 1e-6");
        t = pt_transform_scale(a);
    } else
        t = pt_transform_translate(a);
    p->xf = pt_transform_mul(t, p->xf); /* applied after the transforms before it */
    pt__sf_xfd_mul(p->xfd, &t);
    det = p->xf.m[0][0] * (p->xf.m[1][1] * p->xf.m[2][2] - p->xf.m[1][2] * p->xf.m[2][1]) -
          p->xf.m[0][1] * (p->xf.m[1][0] * p->xf.m[2][2] - p->xf.m[1][2] * p->xf.m[2][0]) +
          p->xf.m[0][2] * (p->xf.m[1][0] * p->xf.m[2][1] - p->xf.m[1][1] * p->xf.m[2][0]);
    if (!(fabsf(det) > 1e-30f) || !pt__sf_isfinite(det) || !pt__sf_isfinite(p->xf.m[0][3]) ||
        !pt__sf_isfinite(p->xf.m[1][3]) || !pt__sf_isfinite(p->xf.m[2][3]))
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "%s: the combined transform is singular or not finite", kw);
    return PT_OK;
}

/* One statement (p->tok, at least one token): the handlers above read its arguments; each
   statement must use all of its tokens (pt__sf_end). */
static int pt__sf_statement(pt__sf_parser *p)
{
    pt_scenefile *d = p->d;
    const char *kw = p->tok[0];
    int rc = PT_OK;
    p->pos = 1;
    if (!strcmp(kw, "size") || !strcmp(kw, "spp") || !strcmp(kw, "max_depth") || !strcmp(kw, "indirect_paths") ||
        !strcmp(kw, "seed") || !strcmp(kw, "pov_light_grid")) {
        if ((rc = pt__sf_int_setting(p, kw)) != PT_OK) return rc;
    } else if (!strcmp(kw, "strategy") || !strcmp(kw, "pov_radiosity") || !strcmp(kw, "sampler") ||
               !strcmp(kw, "integrator")) {
        if ((rc = pt__sf_choice(p, kw)) != PT_OK) return rc;
    } else if (!strcmp(kw, "guiding") || !strcmp(kw, "guiding_budget") || !strcmp(kw, "guiding_alpha") ||
               !strcmp(kw, "guiding_memory")) {
        if ((rc = pt__sf_guiding(p, kw)) != PT_OK) return rc;
    } else if (!strcmp(kw, "background")) {
        if ((rc = pt__sf_color(p, "background", &d->background)) != PT_OK) return rc;
    } else if (!strcmp(kw, "camera")) {
        if ((rc = pt__sf_camera(p)) != PT_OK) return rc;
    } else if (!strcmp(kw, "checker")) {
        if ((rc = pt__sf_checker(p)) != PT_OK) return rc;
    } else if (!strcmp(kw, "material")) {
        if ((rc = pt__sf_material(p)) != PT_OK) return rc;
    } else if (!strcmp(kw, "sphere") || !strcmp(kw, "quad") || !strcmp(kw, "triangle") || !strcmp(kw, "box")) {
        if ((rc = pt__sf_shape(p, kw)) != PT_OK) return rc;
    } else if (!strcmp(kw, "mesh")) {
        if ((rc = pt__sf_mesh(p)) != PT_OK) return rc;
    } else if (!strcmp(kw, "point_light") || !strcmp(kw, "spot_light") || !strcmp(kw, "directional_light")) {
        if ((rc = pt__sf_light(p, kw)) != PT_OK) return rc;
    } else if (!strcmp(kw, "environment")) {
        if ((rc = pt__sf_environment(p)) != PT_OK) return rc;
    } else if (!strcmp(kw, "image_texture")) {
        if ((rc = pt__sf_image_texture(p)) != PT_OK) return rc;
    } else if (!strcmp(kw, "identity")) {
        p->xf = pt_transform_identity();
        pt__sf_xfd_identity(p->xfd);
    } else if (!strcmp(kw, "translate") || !strcmp(kw, "scale") || !strcmp(kw, "rotate")) {
        if ((rc = pt__sf_transform(p, kw)) != PT_OK) return rc;
    } else {
        return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "unknown statement '%s'", kw);
    }
    return pt__sf_end(p);
}

static int pt__sf_line(void *ctx, char *line, int number)
{
    pt__sf_parser *p = (pt__sf_parser *)ctx;
    p->line = number;
    p->ntok = pt__sf_tokenize(line, p->tok, PT__SF_MAX_TOKENS);
    if (p->ntok < 0) return pt__sf_fail(p, PT_ERROR_INVALID_ARGUMENT, "too many items on one line (at most %d)", PT__SF_MAX_TOKENS);
    if (p->ntok == 0) return PT_OK;
    return pt__sf_statement(p);
}

PTDEF uint64_t pt_scenefile_image_bytes(int width, int height)
{
    uint64_t n = width > 0 && height > 0 ? (uint64_t)width * (uint64_t)height : 0u;
    return n * (18u * sizeof(double) + sizeof(uint32_t) + 6u * sizeof(float));
}

PTDEF int pt_scenefile_parse(const char *text, size_t length, const char *name, const char *base_dir,
                             pt_scenefile *out, char *err, size_t err_size)
{
    return pt_scenefile_parse_ex(text, length, name, base_dir, NULL, out, err, err_size);
}

PTDEF int pt_scenefile_parse_ex(const char *text, size_t length, const char *name, const char *base_dir,
                                const pt_scenefile_options *opt, pt_scenefile *out, char *err, size_t err_size)
{
    pt__sf_parser p;
    int rc, i;
    if (err && err_size) err[0] = '\0';
    if (!out) return PT_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!name) name = "<scene>";
    if (!text) return pt__sf_failf(err, err_size, name, 0, PT_ERROR_INVALID_ARGUMENT, "no text");
    memset(&p, 0, sizeof p);
    p.d = out;
    p.name = name;
    p.base_dir = base_dir;
    p.err = err;
    p.err_size = err_size;
    p.xf = pt_transform_identity();
    p.opt = opt;
    p.mesh_limit = opt && opt->mesh_memory ? opt->mesh_memory : PT_SCENEFILE_MESH_MEMORY_DEFAULT;
    p.image_limit = opt && opt->image_memory ? opt->image_memory : PT_SCENEFILE_IMAGE_MEMORY_DEFAULT;
    pt__sf_xfd_identity(p.xfd);
    snprintf(out->file, sizeof out->file, "%s", name);
    out->width = 256;
    out->height = 256;
    out->samples_per_pixel = 64;
    out->max_depth = 50;
    out->pov_light_grid = 16;
    out->guiding = PT__SF_DEFAULT_GUIDING;
    out->sampler = PT__SF_DEFAULT_SAMPLER;
    rc = pt__sf_lines(text, length, &p, pt__sf_line, err, err_size, name);
    if (rc == PT_OK && !p.have_camera)
        rc = pt__sf_failf(err, err_size, name, 0, PT_ERROR_INVALID_ARGUMENT, "no 'camera' statement");
    if (rc == PT_OK && out->shape_count == 0)
        rc = pt__sf_failf(err, err_size, name, 0, PT_ERROR_INVALID_ARGUMENT, "no shapes");
    for (i = 0; i < p.root_count; ++i) PT_FREE(p.roots[i]);
    if (rc != PT_OK) pt_scenefile_free(out);
    return rc;
}

PTDEF int pt_scenefile_load(const char *path, pt_scenefile *out, char *err, size_t err_size)
{
    return pt_scenefile_load_ex(path, NULL, out, err, err_size);
}

PTDEF int pt_scenefile_load_ex(const char *path, const pt_scenefile_options *opt, pt_scenefile *out, char *err,
                               size_t err_size)
{
    char *text = NULL, dir[PT__SF_PATH];
    const char *slash, *why = "";
    size_t len = 0;
    int rc;
    if (err && err_size) err[0] = '\0';
    if (!out) return PT_ERROR_INVALID_ARGUMENT;
    memset(out, 0, sizeof *out);
    if (!path) return PT_ERROR_INVALID_ARGUMENT;
    rc = pt__sf_read_file(path, &text, &len, 64u * 1024u * 1024u, &why);
    if (rc != PT_OK) return pt__sf_failf(err, err_size, path, 0, rc, "cannot read the scene: %s", why);
    slash = strrchr(path, '/');
    if (slash && (size_t)(slash - path) < sizeof dir) {
        memcpy(dir, path, (size_t)(slash - path));
        dir[slash - path] = '\0';
        if (slash == path) strcpy(dir, "/");
    } else
        strcpy(dir, ".");
    rc = pt_scenefile_parse_ex(text, len, path, dir, opt, out, err, err_size);
    PT_FREE(text);
    return rc;
}

/* A shape's or light's transform in double: transform_d when it rounds to transform (as the
   parser makes them), else transform itself (a pt_scenefile filled in by hand). */
static void pt__sf_xfd(const pt_transform *t, const double td[3][4], double x[3][4])
{
    int i, j, same = 1;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 4; ++j) same &= (float)td[i][j] == t->m[i][j];
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 4; ++j) x[i][j] = same ? td[i][j] : (double)t->m[i][j];
}
static void pt__sf_shape_xfd(const pt_scenefile_shape *sh, double x[3][4])
{
    pt__sf_xfd(&sh->transform, sh->transform_d, x);
}
static void pt__sf_dbounds(double x[3][4], pt_vec3 p, double pad, double lo[3], double hi[3])
{
    int i;
    for (i = 0; i < 3; ++i) {
        double v = x[i][0] * p.x + x[i][1] * p.y + x[i][2] * p.z + x[i][3];
        if (v - pad < lo[i]) lo[i] = v - pad;
        if (v + pad > hi[i]) hi[i] = v + pad;
    }
}
/* The origin for pt_scene_set_origin: the centre of the shapes' world bounds (in double, then
   rounded to float so that untransformed float shapes move exactly) when they lie farther from
   (0, 0, 0) than 8 times their size, pt_scene_commit's rule. Returns 0 for a scene near the
   origin: the build then hands over the parser's float transforms unchanged. */
static int pt__sf_origin(const pt_scenefile *d, double c[3])
{
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, x[3][4], size = 0, far = 0;
    int i, k;
    uint32_t v;
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *sh = &d->shapes[i];
        const pt_vec3 *p = sh->p;
        pt__sf_shape_xfd(sh, x);
        if (sh->type == PT_SCENEFILE_SPHERE) {
            /* the radius scaled in double: in float, a huge scale overflows to inf (and inf - inf below) */
            double sx = sqrt(x[0][0] * x[0][0] + x[1][0] * x[1][0] + x[2][0] * x[2][0]);
            pt__sf_dbounds(x, p[0], (double)sh->radius * sx, lo, hi);
        } else if (sh->type == PT_SCENEFILE_QUAD) {
            pt__sf_dbounds(x, p[0], 0, lo, hi);
            pt__sf_dbounds(x, pt_add(p[0], p[1]), 0, lo, hi);
            pt__sf_dbounds(x, pt_add(p[0], p[2]), 0, lo, hi);
            pt__sf_dbounds(x, pt_add(pt_add(p[0], p[1]), p[2]), 0, lo, hi);
        } else if (sh->type == PT_SCENEFILE_TRIANGLE) {
            for (k = 0; k < 3; ++k) pt__sf_dbounds(x, p[k], 0, lo, hi);
        } else if (sh->type == PT_SCENEFILE_BOX) {
            for (k = 0; k < 8; ++k)
                pt__sf_dbounds(x, pt_v3((k & 1) ? p[1].x : p[0].x, (k & 2) ? p[1].y : p[0].y, (k & 4) ? p[1].z : p[0].z), 0,
                               lo, hi);
        } else {
            const pt_obj_mesh *m = &d->meshes[sh->mesh];
            for (v = 0; v < m->vertex_count; ++v)
                pt__sf_dbounds(x, pt_v3(m->positions[3 * v], m->positions[3 * v + 1], m->positions[3 * v + 2]), 0, lo, hi);
        }
    }
    for (k = 0; k < 3 && d->shape_count; ++k) {
        if (!(fabs(lo[k]) < 1e300 && fabs(hi[k]) < 1e300)) return 0; /* unbounded: the build refuses it */
        c[k] = 0.5 * lo[k] + 0.5 * hi[k];
        if (hi[k] - lo[k] > size) size = hi[k] - lo[k];
        if (fabs(c[k]) > far) far = fabs(c[k]);
    }
    if (!(far > 8.0 * size) || !(far < 1e30)) return 0;
    for (k = 0; k < 3; ++k) c[k] = (double)(float)c[k];
    return 1;
}
/* The float transform (t, td) relative to origin c: the double translation minus c, rounded once. */
static pt_transform pt__sf_local_xf(const pt_transform *tf, const double td[3][4], const double c[3])
{
    double x[3][4];
    pt_transform t;
    int i, j;
    pt__sf_xfd(tf, td, x);
    for (i = 0; i < 3; ++i) {
        for (j = 0; j < 3; ++j) t.m[i][j] = (float)x[i][j];
        t.m[i][3] = (float)(x[i][3] - c[i]);
    }
    return t;
}

/* The environment statement's map, under its transform without the translation (a map is
   only turned; pt_scene_set_environment refuses anything but a rotation), with its message
   at the statement's file:line. */
static int pt__sf_build_environment(const pt_scenefile *d, pt_scene *s, char *err, size_t err_size)
{
    pt_transform t = d->environment_transform;
    pt_environment_desc e;
    int rc;
    t.m[0][3] = t.m[1][3] = t.m[2][3] = 0.0f;
    memset(&e, 0, sizeof e);
    e.map = &d->environment;
    e.scale = d->environment_scale;
    if ((rc = pt_scene_set_transform(s, &t)) == PT_OK) rc = pt_scene_set_environment(s, &e);
    if (rc != PT_OK) return pt__sf_failf(err, err_size, d->file, d->environment_line, rc, "%s", pt_scene_error_message(s));
    return PT_OK;
}

PTDEF int pt_scenefile_build(const pt_scenefile *d, pt_scene **scene, pt_render_desc *r, char *err, size_t err_size)
{
    double origin[3] = {0, 0, 0};
    int far;
    pt_scene *s;
    int *tex = NULL, *mat = NULL, i, rc = PT_OK;
    if (err && err_size) err[0] = '\0';
    if (scene) *scene = NULL;
    if (!d || !scene || !r) return PT_ERROR_INVALID_ARGUMENT;
    s = pt_scene_create();
    tex = (int *)PT_MALLOC(((size_t)d->checker_count + (size_t)d->image_count + 1u) * sizeof(int));
    mat = (int *)PT_MALLOC(((size_t)d->material_count + 1u) * sizeof(int));
    if (!s || !tex || !mat) {
        rc = pt__sf_failf(err, err_size, d->file, 0, PT_ERROR_OUT_OF_MEMORY, "out of memory");
        goto done;
    }
    for (i = 0; i < d->checker_count && rc == PT_OK; ++i) {
        const pt_scenefile_checker *c = &d->checkers[i];
        tex[i] = pt_scene_add_checker(s, c->even, c->odd, c->scale);
        if (tex[i] < 0) rc = pt__sf_failf(err, err_size, d->file, 0, tex[i], "checker %s: %s", c->name, pt_scene_error_message(s));
    }
    for (i = 0; i < d->image_count && rc == PT_OK; ++i) { /* after the checkers in tex[] */
        const pt_scenefile_image *im = &d->images[i];
        int id = pt_scene_add_image_texture(s, &im->image);
        tex[d->checker_count + i] = id;
        if (id < 0)
            rc = pt__sf_failf(err, err_size, d->file, im->line, id, "image_texture %s: %s", im->name, pt_scene_error_message(s));
    }
    for (i = 0; i < d->material_count && rc == PT_OK; ++i) {
        const pt_scenefile_material *m = &d->materials[i];
        pt_material_desc md;
        memset(&md, 0, sizeof md);
        md.type = m->type;
        md.albedo = m->albedo;
        md.albedo_texture = m->checker >= 0 ? tex[m->checker] : m->image >= 0 ? tex[d->checker_count + m->image] : 0;
        md.fuzz = m->fuzz;
        md.ior = m->ior;
        md.emission = m->emission;
        md.two_sided_emission = m->two_sided;
        md.roughness = m->roughness;
        md.conductor = m->conductor;
        md.eta = m->eta;
        md.k = m->k;
        md.nonlinear = m->nonlinear;
        md.ext_ior = m->ext_ior;
        mat[i] = pt_scene_add_material(s, &md);
        if (mat[i] < 0) rc = pt__sf_failf(err, err_size, d->file, 0, mat[i], "material %s: %s", m->name, pt_scene_error_message(s));
    }
    far = rc == PT_OK && pt__sf_origin(d, origin);
    if (far && (rc = pt_scene_set_origin(s, origin[0], origin[1], origin[2])) != PT_OK)
        rc = pt__sf_failf(err, err_size, d->file, 0, rc, "%s", pt_scene_error_message(s));
    for (i = 0; i < d->shape_count && rc == PT_OK; ++i) {
        const pt_scenefile_shape *sh = &d->shapes[i];
        int m = mat[sh->material], id;
        pt_transform local;
        if (far) local = pt__sf_local_xf(&sh->transform, sh->transform_d, origin);
        if ((rc = pt_scene_set_transform(s, far ? &local : &sh->transform)) != PT_OK) {
            rc = pt__sf_failf(err, err_size, d->file, sh->line, rc, "%s", pt_scene_error_message(s));
            break;
        }
        switch (sh->type) {
        case PT_SCENEFILE_SPHERE: id = pt_scene_add_sphere(s, sh->p[0], sh->radius, m); break;
        case PT_SCENEFILE_QUAD: id = pt_scene_add_quad(s, sh->p[0], sh->p[1], sh->p[2], m); break;
        case PT_SCENEFILE_TRIANGLE: id = pt_scene_add_triangle(s, sh->p[0], sh->p[1], sh->p[2], m); break;
        case PT_SCENEFILE_BOX: id = pt_scene_add_box(s, sh->p[0], sh->p[1], m); break;
        default: {
            pt_mesh_desc md = pt_obj_mesh_desc(&d->meshes[sh->mesh], m);
            id = pt_scene_add_mesh(s, &md);
        }
        }
        if (id < 0) rc = pt__sf_failf(err, err_size, d->file, sh->line, id, "%s", pt_scene_error_message(s));
    }
    for (i = 0; i < d->light_count && rc == PT_OK; ++i) { /* placed as the shapes are */
        const pt_scenefile_light *l = &d->lights[i];
        pt_transform local;
        int id;
        if (far) local = pt__sf_local_xf(&l->transform, l->transform_d, origin);
        if ((rc = pt_scene_set_transform(s, far ? &local : &l->transform)) != PT_OK) {
            rc = pt__sf_failf(err, err_size, d->file, l->line, rc, "%s", pt_scene_error_message(s));
            break;
        }
        id = pt_scene_add_light(s, &l->desc);
        if (id < 0) rc = pt__sf_failf(err, err_size, d->file, l->line, id, "%s", pt_scene_error_message(s));
    }
    if (rc == PT_OK && d->environment.width > 0) rc = pt__sf_build_environment(d, s, err, err_size);
    if (rc == PT_OK) pt_scene_set_transform(s, NULL);
    if (rc == PT_OK && (rc = pt_scene_commit(s)) != PT_OK)
        rc = pt__sf_failf(err, err_size, d->file, 0, rc, "%s", pt_scene_error_message(s));
done:
    PT_FREE(tex);
    PT_FREE(mat);
    if (rc != PT_OK) {
        pt_scene_destroy(s);
        return rc;
    }
    memset(r, 0, sizeof *r);
    r->width = d->width;
    r->height = d->height;
    r->samples_per_pixel = d->samples_per_pixel;
    r->max_depth = d->max_depth;
    r->strategy = d->strategy;
    r->sampler = d->sampler;
    r->integrator = d->integrator;
    r->indirect_paths = d->indirect_paths;
    r->guiding = d->guiding;
    r->guiding_budget = d->guiding_budget;
    r->guiding_alpha = d->guiding_alpha;
    r->guiding_max_mib = d->guiding_memory;
    r->seed = d->seed;
    r->background = d->background;
    r->camera = d->camera;
    *scene = s;
    return PT_OK;
}

/* ---- Escaping text taken from input (scene names, paths) for the exporters' output. */
PTDEF size_t pt_scenefile_escape(char *out, size_t size, const char *text, pt_scenefile_escape_mode mode)
{
    static const char hex[] = "0123456789ABCDEF";
    size_t n = 0;
    if (!out || size == 0) return 0;
    for (; text && *text; ++text) {
        unsigned char c = (unsigned char)*text;
        char rep[8];
        size_t k;
        if (mode == PT_SCENEFILE_ESCAPE_XML) {
            const char *e = c == '&' ? "&amp;" : c == '<' ? "&lt;" : c == '>' ? "&gt;" : c == '"' ? "&quot;"
                          : c == '\'' ? "&apos;" : NULL;
            if (e) strcpy(rep, e);
            else { rep[0] = (c >= 0x20 && c < 0x7f) ? (char)c : '?'; rep[1] = '\0'; }
        } else if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || (c && strchr(" ._-+/:,=@~", c))) {
            rep[0] = (char)c; rep[1] = '\0';
        } else {
            rep[0] = '\\'; rep[1] = 'x'; rep[2] = hex[c >> 4]; rep[3] = hex[c & 15]; rep[4] = '\0';
        }
        k = strlen(rep);
        if (n + k >= size) break; /* never half an escape */
        memcpy(out + n, rep, k);
        n += k;
    }
    out[n] = '\0';
    return n;
}

/* ---- POV-Ray 3.7 export (the recipe: docs/povray.md). Everything is written through
   pt__pov_put (fixed text, integers), pt__pov_g (numbers, checked finite) and the escaped
   scene name. The exporter runs twice: a first pass with f == NULL writes nothing and only
   finds a non-finite number, so a file is written only when every number is finite. */
typedef struct pt__pov {
    FILE *f;                  /* NULL: the checking pass */
    const pt_scenefile *d;
    double fd, hair;          /* fade distance, light offset */
    double centre[3], diag;   /* the shapes' bounds: centre and diagonal */
    int grid;
    int line;                 /* the statement being written (0: none), for messages */
    int bad_line, bad;        /* the first non-finite number: where */
    char name[4 * sizeof(((pt_scenefile *)0)->file) + 1]; /* d->file, escaped for comments */
} pt__pov;

static void pt__pov_put(pt__pov *w, const char *fmt, ...)
{
    va_list ap;
    if (!w->f) return;
    va_start(ap, fmt);
    vfprintf(w->f, fmt, ap);
    va_end(ap);
}
static void pt__pov_g(pt__pov *w, double x)
{
    if (!pt__sf_finite(x)) {
        if (!w->bad) w->bad_line = w->line;
        w->bad = 1;
        x = 0;
    }
    if (w->f) fprintf(w->f, "%.9g", x);
}
static void pt__pov_v(pt__pov *w, pt_vec3 v)
{
    pt__pov_put(w, "<");
    pt__pov_g(w, (double)v.x);
    pt__pov_put(w, ", ");
    pt__pov_g(w, (double)v.y);
    pt__pov_put(w, ", ");
    pt__pov_g(w, (double)v.z);
    pt__pov_put(w, ">");
}
/* rgb <r, g, b> scaled by k (in double). */
static void pt__pov_rgb(pt__pov *w, pt_color c, double k)
{
    pt__pov_put(w, "rgb <");
    pt__pov_g(w, (double)c.x * k);
    pt__pov_put(w, ", ");
    pt__pov_g(w, (double)c.y * k);
    pt__pov_put(w, ", ");
    pt__pov_g(w, (double)c.z * k);
    pt__pov_put(w, ">");
}

static void pt__sf_bounds_add(pt_vec3 *lo, pt_vec3 *hi, pt_vec3 p)
{
    if (p.x < lo->x) lo->x = p.x;
    if (p.y < lo->y) lo->y = p.y;
    if (p.z < lo->z) lo->z = p.z;
    if (p.x > hi->x) hi->x = p.x;
    if (p.y > hi->y) hi->y = p.y;
    if (p.z > hi->z) hi->z = p.z;
}
/* Uniform scale of a similarity transform (length of the image of a unit x vector). */
static float pt__sf_xf_scale(const pt_transform *t) { return pt_length(pt_transform_vector(t, pt_v3(1, 0, 0))); }

static void pt__pov_texture(pt__pov *w, int material)
{
    const pt_scenefile_material *m = &w->d->materials[material];
    switch (m->type) {
    case PT_MATERIAL_LAMBERTIAN:
        if (m->checker >= 0) {
            const pt_scenefile_checker *c = &w->d->checkers[m->checker];
            /* Both renderers: second colour where floor(x/s)+floor(y/s)+floor(z/s) is odd. */
            pt__pov_put(w, "texture { pigment { checker ");
            pt__pov_rgb(w, c->even, 1.0);
            pt__pov_put(w, ", ");
            pt__pov_rgb(w, c->odd, 1.0);
            pt__pov_put(w, " scale ");
            pt__pov_g(w, (double)c->scale);
            pt__pov_put(w, " } finish { diffuse 1 } }");
        } else {
            pt__pov_put(w, "texture { pigment { ");
            pt__pov_rgb(w, m->albedo, 1.0);
            pt__pov_put(w, " } finish { diffuse 1 } }");
        }
        break;
    case PT_MATERIAL_METAL:
    case PT_MATERIAL_ROUGH_CONDUCTOR: /* only the coloured mirror (alpha < 1e-3, metal none) gets here */
        pt__pov_put(w, "texture { pigment { rgb 0 } finish { diffuse 0 reflection { ");
        pt__pov_rgb(w, m->albedo, 1.0);
        pt__pov_put(w, " } } }");
        break;
    case PT_MATERIAL_DIELECTRIC:
        pt__pov_put(w, "texture { pigment { rgbf 1 } finish { diffuse 0 reflection { 0, 1 fresnel on } conserve_energy } } "
                       "interior { ior ");
        pt__pov_g(w, (double)(m->ior > 0 ? m->ior : 1.5f));
        pt__pov_put(w, " }");
        break;
    default: /* emitter: the visible surface, pixel = pigment x emission */
        pt__pov_put(w, "texture { pigment { ");
        pt__pov_rgb(w, m->emission, 1.0);
        pt__pov_put(w, " } finish { emission 1 diffuse 0 } }");
        break;
    }
}

static void pt__pov_mesh2(pt__pov *w, const pt_obj_mesh *m, const pt_transform *t)
{
    uint32_t i;
    pt__pov_put(w, "mesh2 {\n  vertex_vectors { %u", (unsigned)m->vertex_count);
    for (i = 0; i < m->vertex_count; ++i) {
        pt__pov_put(w, ",\n    ");
        pt__pov_v(w, pt_transform_point(t, pt_v3(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2])));
    }
    pt__pov_put(w, " }\n");
    if (m->normals) {
        pt__pov_put(w, "  normal_vectors { %u", (unsigned)m->vertex_count);
        for (i = 0; i < m->vertex_count; ++i) {
            pt_vec3 n;
            if (pt_transform_normal(t, pt_v3(m->normals[3 * i], m->normals[3 * i + 1], m->normals[3 * i + 2]), &n) != PT_OK)
                n = pt_v3(0, 1, 0);
            pt__pov_put(w, ",\n    ");
            pt__pov_v(w, pt_normalize(n));
        }
        pt__pov_put(w, " }\n");
    }
    pt__pov_put(w, "  face_indices { %u", (unsigned)m->triangle_count);
    for (i = 0; i < m->triangle_count; ++i)
        pt__pov_put(w, ",\n    <%u, %u, %u>", (unsigned)m->indices[3 * i], (unsigned)m->indices[3 * i + 1],
                    (unsigned)m->indices[3 * i + 2]);
    pt__pov_put(w, " }\n  ");
}

/* The geometry of a shape in world space, without its closing brace. */
static void pt__pov_geometry(pt__pov *w, const pt_scenefile_shape *s)
{
    const pt_transform *t = &s->transform;
    int i, j;
    switch (s->type) {
    case PT_SCENEFILE_SPHERE:
        pt__pov_put(w, "sphere { ");
        pt__pov_v(w, pt_transform_point(t, s->p[0]));
        pt__pov_put(w, ", ");
        pt__pov_g(w, (double)s->radius * (double)pt__sf_xf_scale(t));
        pt__pov_put(w, " ");
        break;
    case PT_SCENEFILE_QUAD: {
        pt_vec3 q = pt_transform_point(t, s->p[0]), u = pt_transform_vector(t, s->p[1]), v = pt_transform_vector(t, s->p[2]);
        pt__pov_put(w, "mesh { triangle { ");
        pt__pov_v(w, q); pt__pov_put(w, ", "); pt__pov_v(w, pt_add(q, u)); pt__pov_put(w, ", "); pt__pov_v(w, pt_add(pt_add(q, u), v));
        pt__pov_put(w, " } triangle { ");
        pt__pov_v(w, q); pt__pov_put(w, ", "); pt__pov_v(w, pt_add(pt_add(q, u), v)); pt__pov_put(w, ", "); pt__pov_v(w, pt_add(q, v));
        pt__pov_put(w, " } ");
        break;
    }
    case PT_SCENEFILE_TRIANGLE:
        pt__pov_put(w, "triangle { ");
        pt__pov_v(w, pt_transform_point(t, s->p[0])); pt__pov_put(w, ", ");
        pt__pov_v(w, pt_transform_point(t, s->p[1])); pt__pov_put(w, ", ");
        pt__pov_v(w, pt_transform_point(t, s->p[2])); pt__pov_put(w, " ");
        break;
    case PT_SCENEFILE_BOX:
        /* POV's matrix: p' = p * M with rows x, y, z, translation, i.e. the transpose of ours. */
        pt__pov_put(w, "box { ");
        pt__pov_v(w, s->p[0]); pt__pov_put(w, ", "); pt__pov_v(w, s->p[1]);
        pt__pov_put(w, " matrix <");
        for (j = 0; j < 4; ++j)
            for (i = 0; i < 3; ++i) {
                pt__pov_g(w, (double)t->m[i][j]);
                pt__pov_put(w, j == 3 && i == 2 ? "> " : ", ");
            }
        break;
    case PT_SCENEFILE_MESH:
        pt__pov_mesh2(w, &w->d->meshes[s->mesh], t);
        break;
    }
}

static void pt__pov_quad_lights(pt__pov *w, pt_vec3 q, pt_vec3 u, pt_vec3 v, pt_vec3 n, pt_color le)
{
    /* N x N spotlights at the cell centres, a hair in front; colour Le*A/(N^2*2*pi*fd^2). */
    int i, j, N = w->grid;
    double area = (double)pt_length(pt_cross(u, v));
    double k = area / ((double)N * N * 2.0 * 3.14159265358979323846 * w->fd * w->fd);
    pt_vec3 c = pt_madd(q, n, (float)w->hair);
    for (i = 0; i < N; ++i)
        for (j = 0; j < N; ++j) {
            pt_vec3 pos = pt_add(pt_madd(c, u, (float)((i + 0.5) / N)), pt_scale(v, (float)((j + 0.5) / N)));
            pt__pov_put(w, "light_source { ");
            pt__pov_v(w, pos);
            pt__pov_put(w, ", ");
            pt__pov_rgb(w, le, k);
            pt__pov_put(w, " spotlight point_at ");
            pt__pov_v(w, pt_add(pos, n));
            pt__pov_put(w, " radius 90 falloff 90 tightness 1 fade_distance ");
            pt__pov_g(w, w->fd);
            pt__pov_put(w, " fade_power 2 }\n");
        }
}

/* The file's header: comments, global settings, background and camera. */
static void pt__pov_header(pt__pov *w, const pt_pov_options *o, int width, int height)
{
    const pt_scenefile *d = w->d;
    int radiosity = o && o->radiosity >= 0 ? o->radiosity : d->pov_radiosity;
    double vfov = d->camera.vfov_degrees > 0 ? (double)d->camera.vfov_degrees : 40.0;
    double aspect = (double)width / (double)height;
    double angle = 2.0 * atan(aspect * tan(vfov * 3.14159265358979323846 / 360.0)) * 180.0 / 3.14159265358979323846;
    pt_vec3 up = pt_length2(d->camera.up) > 0 ? d->camera.up : pt_v3(0, 1, 0);

    pt__pov_put(w, "// POV-Ray 3.7 scene written by pdftrace %d.%d.%d from %s\n", PDFTRACE_VERSION_MAJOR,
                PDFTRACE_VERSION_MINOR, PDFTRACE_VERSION_PATCH, w->name);
    pt__pov_put(w, "// render: povray +I<this file> +O<out>.exr +FE +W%d +H%d +A0.0 +AM2 +R4 -D\n", width, height);
    pt__pov_put(w, "// (+FE: linear half-float OpenEXR; +A0.0 +AM2 +R4 approximates pdftrace's box-filtered pixels)\n");
    pt__pov_put(w, "#version 3.7;\n#default { finish { ambient 0 emission 0 diffuse 1 } }\n");
    pt__pov_put(w, "global_settings {\n  assumed_gamma 1.0\n  ambient_light 0\n  max_trace_level 64\n  adc_bailout 1e-6\n");
    if (radiosity == 1) pt__pov_put(w, "  radiosity { brightness 1 gray_threshold 0 }\n");
    if (radiosity == 2)
        pt__pov_put(w, "  radiosity { count 200 error_bound 0.5 recursion_limit 4 nearest_count 10 brightness 1 gray_threshold 0 }\n");
    if (radiosity == 3)
        pt__pov_put(w, "  radiosity { count 800,1600 error_bound 0.15 recursion_limit 8 nearest_count 20 pretrace_start 0.08\n"
                       "    pretrace_end 0.005 minimum_reuse 0.005 maximum_reuse 0.1 low_error_factor 0.5 adc_bailout 0.001\n"
                       "    brightness 1 gray_threshold 0 }\n");
    pt__pov_put(w, "}\nbackground { ");
    w->line = 0;
    pt__pov_rgb(w, d->background, 1.0);
    pt__pov_put(w, " }\n// right-handed pinhole: angle is the horizontal field of view\n");
    w->line = d->camera_line;
    pt__pov_put(w, "camera { perspective location ");
    pt__pov_v(w, d->camera.look_from);
    pt__pov_put(w, " right -x*");
    pt__pov_g(w, aspect);
    pt__pov_put(w, " up y direction z angle ");
    pt__pov_g(w, angle);
    pt__pov_put(w, " sky ");
    pt__pov_v(w, up);
    pt__pov_put(w, " look_at ");
    pt__pov_v(w, d->camera.look_at);
    pt__pov_put(w, " }\n\n");
}

/* The cone angles of a spot as pdftrace resolves them (0: the defaults of pt_light_desc). */
static void pt__sf_spot_angles(const pt_light_desc *l, float *cutoff, float *beam)
{
    *cutoff = l->cutoff_angle == 0.0f ? 20.0f : l->cutoff_angle;
    *beam = l->beam_width == 0.0f ? 0.75f * *cutoff : l->beam_width;
}

/* A point, hard-cone spot or directional light (pt__pov_refuse has refused the others). A
   point of intensity I is the fade trick's point light, colour I/(2 pi fd^2) (docs/povray.md);
   a spot adds a cone of constant intensity out to its cutoff (tightness 0: no cos^n factor;
   radius = falloff: no smoothstep ramp), aimed along the axis from a point_at far enough away
   for its printed digits to keep the direction. A directional light of irradiance E is a
   parallel light of colour E/pi (POV's diffuse has no 1/pi: the recipe folds it into the
   lights); POV-Ray does not trace its shadow rays to infinity (an occluder behind the location
   cast only part of its shadow, measured), so the location is put at least two bounds
   diagonals behind the scene's centre, with every shape between it and any surface. */
static void pt__pov_light(pt__pov *w, const pt_scenefile_light *l)
{
    const double inv_pi = 0.31830988618379067154;
    const pt_light_desc *ld = &l->desc;
    pt_vec3 pos = pt_transform_point(&l->transform, ld->position);
    pt_vec3 dir = pt_transform_vector(&l->transform, ld->direction);
    double len = sqrt((double)dir.x * dir.x + (double)dir.y * dir.y + (double)dir.z * dir.z), a[3] = {0, 0, 0}, far;
    if (ld->type != PT_LIGHT_POINT) { /* the build refused a zero or overflowing direction */
        a[0] = (double)dir.x / len;
        a[1] = (double)dir.y / len;
        a[2] = (double)dir.z / len;
    }
    w->line = l->line;
    pt__pov_put(w, "// %s:%d\nlight_source { ", w->name, l->line);
    if (ld->type == PT_LIGHT_DIRECTIONAL) {
        far = 2.0 * w->diag + fabs(w->centre[0]) + fabs(w->centre[1]) + fabs(w->centre[2]); /* digits, as for a spot */
        pt__pov_put(w, "<");
        pt__pov_g(w, w->centre[0] - far * a[0]);
        pt__pov_put(w, ", ");
        pt__pov_g(w, w->centre[1] - far * a[1]);
        pt__pov_put(w, ", ");
        pt__pov_g(w, w->centre[2] - far * a[2]);
        pt__pov_put(w, ">, ");
        pt__pov_rgb(w, ld->intensity, inv_pi);
        pt__pov_put(w, " parallel point_at <");
        pt__pov_g(w, w->centre[0]);
        pt__pov_put(w, ", ");
        pt__pov_g(w, w->centre[1]);
        pt__pov_put(w, ", ");
        pt__pov_g(w, w->centre[2]);
        pt__pov_put(w, "> }\n");
        return;
    }
    pt__pov_v(w, pos);
    pt__pov_put(w, ", ");
    pt__pov_rgb(w, ld->intensity, 0.5 * inv_pi / (w->fd * w->fd));
    if (ld->type == PT_LIGHT_SPOT) {
        float cutoff, beam;
        double m = fabs((double)pos.x) > fabs((double)pos.y) ? fabs((double)pos.x) : fabs((double)pos.y);
        if (fabs((double)pos.z) > m) m = fabs((double)pos.z);
        far = w->diag + m; /* the target's 9 digits keep the axis to ~1e-8 */
        pt__sf_spot_angles(ld, &cutoff, &beam);
        pt__pov_put(w, " spotlight point_at <");
        pt__pov_g(w, (double)pos.x + far * a[0]);
        pt__pov_put(w, ", ");
        pt__pov_g(w, (double)pos.y + far * a[1]);
        pt__pov_put(w, ", ");
        pt__pov_g(w, (double)pos.z + far * a[2]);
        pt__pov_put(w, "> radius ");
        pt__pov_g(w, (double)cutoff);
        pt__pov_put(w, " falloff ");
        pt__pov_g(w, (double)cutoff);
        pt__pov_put(w, " tightness 0");
    }
    pt__pov_put(w, " fade_distance ");
    pt__pov_g(w, w->fd);
    pt__pov_put(w, " fade_power 2 }\n");
}

static void pt__pov_body(pt__pov *w, const pt_pov_options *o, int width, int height)
{
    const pt_scenefile *d = w->d;
    int i;
    pt__pov_header(w, o, width, height);
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *s = &d->shapes[i];
        const pt_scenefile_material *m = &d->materials[s->material];
        w->line = s->line;
        pt__pov_put(w, "// %s:%d\n", w->name, s->line);
        if (m->type == PT_MATERIAL_EMITTER) {
            if (s->type == PT_SCENEFILE_QUAD) {
                const pt_transform *t = &s->transform;
                pt_vec3 q = pt_transform_point(t, s->p[0]), u = pt_transform_vector(t, s->p[1]), v = pt_transform_vector(t, s->p[2]);
                pt_vec3 n = pt_normalize(pt_cross(u, v));
                pt__pov_quad_lights(w, q, u, v, n, m->emission);
                if (m->two_sided) pt__pov_quad_lights(w, q, u, v, pt_neg(n), m->emission);
            } else if (s->type == PT_SCENEFILE_SPHERE) {
                /* A Lambertian sphere of radiance L has intensity L*pi*r^2 in every direction;
                   colour I/(2*pi*fd^2) = L*r^2/(2*fd^2). */
                double r = (double)s->radius * (double)pt__sf_xf_scale(&s->transform);
                pt__pov_put(w, "light_source { ");
                pt__pov_v(w, pt_transform_point(&s->transform, s->p[0]));
                pt__pov_put(w, ", ");
                pt__pov_rgb(w, m->emission, r * r / (2.0 * w->fd * w->fd));
                pt__pov_put(w, " fade_distance ");
                pt__pov_g(w, w->fd);
                pt__pov_put(w, " fade_power 2 }\n");
            }
            pt__pov_geometry(w, s);
            pt__pov_texture(w, s->material);
            pt__pov_put(w, " no_shadow no_radiosity }\n");
            pt__pov_geometry(w, s);
            pt__pov_put(w, "texture { pigment { rgb 0 } finish { diffuse 0 } } no_image no_reflection no_shadow }\n");
        } else {
            pt__pov_geometry(w, s);
            pt__pov_texture(w, s->material);
            if (m->type == PT_MATERIAL_DIELECTRIC) {
                pt__pov_put(w, " no_shadow }\n");
                pt__pov_geometry(w, s); /* the opaque twin casts the shadow */
                pt__pov_put(w, "texture { pigment { rgb 0 } finish { diffuse 0 } } no_image no_reflection no_radiosity }\n");
            } else
                pt__pov_put(w, " }\n");
        }
    }
    for (i = 0; i < d->light_count; ++i) pt__pov_light(w, &d->lights[i]);
}

/* What the export refuses, before anything is written: every scene the build refuses (the
   same validation: pt_scenefile_build itself), then what POV-Ray cannot match. POV-Ray's
   focal blur draws a few aperture samples per pixel and stops adaptively (blur_samples,
   confidence, variance) rather than integrating over the lens disk, so a thin lens has no
   exact twin. A camera the renderer refuses (pt_camera_init) is refused too. */
static int pt__pov_refuse(const pt_scenefile *d, int width, int height, char *err, size_t err_size)
{
    pt_scene *scene = NULL;
    pt_render_desc rd;
    pt_camera cam;
    int i, rc = pt_scenefile_build(d, &scene, &rd, err, err_size);
    pt_scene_destroy(scene);
    if (rc != PT_OK) return rc;
    if (pt_camera_init(&cam, &d->camera, width, height) != PT_OK) /* the renderer's own check */
        return pt__sf_failf(err, err_size, d->file, d->camera_line, PT_ERROR_INVALID_ARGUMENT,
                            "POV-Ray export: pdftrace cannot render this camera (a non-finite vector, look_at "
                            "equal to look_from, up parallel to the view, or vfov outside (0, 180))");
    if (d->camera.lens_radius > 0.0f)
        return pt__sf_failf(err, err_size, d->file, d->camera_line, PT_ERROR_UNSUPPORTED,
                            "POV-Ray export: a thin-lens camera (lens_radius %g) has no exact POV-Ray equivalent; "
                            "export with lens_radius 0", (double)d->camera.lens_radius);
    if (d->environment.width > 0) /* measured: docs/povray.md, "Environment maps" */
        return pt__sf_failf(err, err_size, d->file, d->environment_line, PT_ERROR_UNSUPPORTED,
                            "POV-Ray export: an environment map has no POV-Ray equivalent as a light: POV-Ray's "
                            "sky_sphere lights diffuse surfaces only through radiosity, a cached estimate from a "
                            "few hundred rays per sample point that misses a small bright sun in the map");
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *s = &d->shapes[i];
        const pt_scenefile_material *m = &d->materials[s->material];
        if (m->type == PT_MATERIAL_METAL && m->fuzz > 0)
            return pt__sf_failf(err, err_size, d->file, s->line, PT_ERROR_UNSUPPORTED,
                                "POV-Ray export: fuzzy metal (material %s) has no POV-Ray equivalent", m->name);
        if (m->type == PT_MATERIAL_ROUGH_CONDUCTOR && (m->roughness >= 1e-3f || m->conductor != PT_CONDUCTOR_NONE))
            return pt__sf_failf(err, err_size, d->file, s->line, PT_ERROR_UNSUPPORTED,
                                "POV-Ray export: a rough conductor (material %s) has no POV-Ray equivalent: POV-Ray has no "
                                "microfacet reflection (no GGX distribution or masking) and no conductor Fresnel term; "
                                "only alpha < 1e-3 with metal none (a coloured mirror) is exported", m->name);
        if (m->type == PT_MATERIAL_ROUGH_PLASTIC)
            return pt__sf_failf(err, err_size, d->file, s->line, PT_ERROR_UNSUPPORTED,
                                "POV-Ray export: a rough plastic (material %s) has no POV-Ray equivalent: POV-Ray has no "
                                "microfacet reflection and no layered coat (its phong and specular highlights have no Fresnel "
                                "term and take no energy from the diffuse base), so no setting is a numeric twin", m->name);
        if (m->type == PT_MATERIAL_ROUGH_DIELECTRIC)
            return pt__sf_failf(err, err_size, d->file, s->line, PT_ERROR_UNSUPPORTED,
                                "POV-Ray export: a rough dielectric (material %s) has no POV-Ray equivalent: POV-Ray has "
                                "no microfacet reflection or refraction (its glass is a smooth interface, and its "
                                "normal-perturbing `micronormals` are not a GGX distribution with masking), and its "
                                "interiors assume an exterior of index 1; use dielectric for smooth glass", m->name);
        if (m->type == PT_MATERIAL_EMITTER && s->type != PT_SCENEFILE_QUAD && s->type != PT_SCENEFILE_SPHERE)
            return pt__sf_failf(err, err_size, d->file, s->line, PT_ERROR_UNSUPPORTED,
                                "POV-Ray export: only quads and spheres can emit (material %s)", m->name);
        if (m->image >= 0)
            return pt__sf_failf(err, err_size, d->file, s->line, PT_ERROR_UNSUPPORTED,
                                "POV-Ray export: an image texture (material %s) has no exact POV-Ray twin: POV-Ray's "
                                "uv_mapping parameterises spheres about +y (pdftrace, as Mitsuba, about +z) and its "
                                "image_map filtering is not pdftrace's bilinear lookup between texel centres; not "
                                "approximated", m->name);
    }
    for (i = 0; i < d->light_count; ++i) {
        const pt_scenefile_light *l = &d->lights[i];
        float cutoff, beam;
        pt__sf_spot_angles(&l->desc, &cutoff, &beam);
        if (l->desc.type == PT_LIGHT_SPOT && beam < cutoff)
            return pt__sf_failf(err, err_size, d->file, l->line, PT_ERROR_UNSUPPORTED,
                                "POV-Ray export: a spot light with a beam of %g degrees inside a cutoff of %g has no "
                                "exact POV-Ray equivalent (POV-Ray's falloff is a smoothstep in the cosine of the angle, "
                                "pdftrace's linear in the angle, as Mitsuba 3's); give it beam = cutoff (a hard-edged "
                                "cone, exported exactly)", (double)beam, (double)cutoff);
    }
    return PT_OK;
}

/* The scene's bounds set the fade distance and the light offset; the grid and the name. */
static void pt__pov_setup(pt__pov *w, const pt_scenefile *d, const pt_pov_options *o)
{
    pt_vec3 lo = pt_v3(FLT_MAX, FLT_MAX, FLT_MAX), hi = pt_v3(-FLT_MAX, -FLT_MAX, -FLT_MAX);
    char file[sizeof d->file];
    double diag;
    int i;
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *s = &d->shapes[i];
        const pt_transform *t = &s->transform;
        uint32_t k;
        switch (s->type) {
        case PT_SCENEFILE_SPHERE: {
            pt_vec3 c = pt_transform_point(t, s->p[0]);
            float r = s->radius * pt__sf_xf_scale(t);
            pt__sf_bounds_add(&lo, &hi, pt_sub(c, pt_v3(r, r, r)));
            pt__sf_bounds_add(&lo, &hi, pt_add(c, pt_v3(r, r, r)));
            break;
        }
        case PT_SCENEFILE_MESH: {
            const pt_obj_mesh *m2 = &d->meshes[s->mesh];
            for (k = 0; k < m2->vertex_count; ++k)
                pt__sf_bounds_add(&lo, &hi, pt_transform_point(t, pt_v3(m2->positions[3 * k], m2->positions[3 * k + 1], m2->positions[3 * k + 2])));
            break;
        }
        case PT_SCENEFILE_BOX:
            for (k = 0; k < 8; ++k)
                pt__sf_bounds_add(&lo, &hi, pt_transform_point(t, pt_v3((k & 1) ? s->p[1].x : s->p[0].x,
                                                                       (k & 2) ? s->p[1].y : s->p[0].y,
                                                                       (k & 4) ? s->p[1].z : s->p[0].z)));
            break;
        case PT_SCENEFILE_QUAD:
            pt__sf_bounds_add(&lo, &hi, pt_transform_point(t, s->p[0]));
            pt__sf_bounds_add(&lo, &hi, pt_transform_point(t, pt_add(s->p[0], pt_add(s->p[1], s->p[2]))));
            pt__sf_bounds_add(&lo, &hi, pt_transform_point(t, pt_add(s->p[0], s->p[1])));
            pt__sf_bounds_add(&lo, &hi, pt_transform_point(t, pt_add(s->p[0], s->p[2])));
            break;
        default:
            for (k = 0; k < 3; ++k) pt__sf_bounds_add(&lo, &hi, pt_transform_point(t, s->p[k]));
        }
    }
    diag = d->shape_count ? (double)pt_length(pt_sub(hi, lo)) : 1.0;
    if (!(diag > 0) || !pt__sf_finite(diag)) diag = 1.0;
    memset(w, 0, sizeof *w);
    w->d = d;
    w->diag = diag;
    w->centre[0] = d->shape_count ? 0.5 * (double)lo.x + 0.5 * (double)hi.x : 0.0;
    w->centre[1] = d->shape_count ? 0.5 * (double)lo.y + 0.5 * (double)hi.y : 0.0;
    w->centre[2] = d->shape_count ? 0.5 * (double)lo.z + 0.5 * (double)hi.z : 0.0;
    w->grid = o && o->light_grid > 0 ? o->light_grid : d->pov_light_grid > 0 ? d->pov_light_grid : 16;
    if (w->grid > 64) w->grid = 64;
    w->fd = 1e-4 * diag;   /* relative error (fd/d)^2 */
    w->hair = 1e-5 * diag; /* the grid sits this far in front of its emitter (emitter and twin are no_shadow) */
    memcpy(file, d->file, sizeof file); /* d->file is input: only safe bytes reach a comment */
    file[sizeof file - 1] = '\0';
    pt_scenefile_escape(w->name, sizeof w->name, file, PT_SCENEFILE_ESCAPE_COMMENT);
}

PTDEF int pt_scenefile_write_pov(const pt_scenefile *d, const char *path, const pt_pov_options *o, char *err,
                                  size_t err_size)
{
    pt__pov w;
    int width, height, rc;
    pt_output_file out;
    if (err && err_size) err[0] = '\0';
    if (!d || !path || !*path) return PT_ERROR_INVALID_ARGUMENT;
    width = o && o->width > 0 ? o->width : d->width;
    height = o && o->height > 0 ? o->height : d->height;
    if ((rc = pt__pov_refuse(d, width, height, err, err_size)) != PT_OK) return rc;
    pt__pov_setup(&w, d, o);
    pt__pov_body(&w, o, width, height); /* w.f == NULL: only checks the numbers */
    if (w.bad)
        return pt__sf_failf(err, err_size, d->file, w.bad_line, PT_ERROR_UNSUPPORTED,
                            "POV-Ray export: a number to be written is not finite (nan or inf); POV-Ray cannot read it");

    rc = pt_output_open(&out, path, 1, "POV-Ray scene", err, err_size); /* exclusive temporary, renamed into place */
    if (rc != PT_OK) return rc;
    w.f = out.file;
    pt__pov_body(&w, o, width, height);
    return pt_output_close(&out, !ferror(w.f), "POV-Ray scene", err, err_size);
}

/* ---- Mitsuba 3 export (the mapping and its measurements: docs/mitsuba.md). As for POV-Ray,
   every number goes through pt__mts_g (checked finite) and everything runs twice: a first
   pass with no file open only looks for a non-finite number, so files are written only when
   every number is finite. Triangles go to binary little-endian PLY files beside the XML: one
   per mesh statement, and one per material for the triangle statements. */
typedef struct pt__mts_ply {
    int shape;                /* a mesh statement's shape, or -1: every triangle statement of `material` */
    int material;
    int line;                 /* the statement (the first triangle's) */
} pt__mts_ply;

typedef struct pt__mts {
    FILE *f;                  /* the XML, or a PLY; NULL: the checking pass */
    const pt_scenefile *d;
    int width, height, spp, depth; /* depth: pdftrace's scattering events */
    int line, bad, bad_line;  /* the statement being written; the first non-finite number */
    double near_clip, far_clip;
    unsigned char *used;      /* per material: some shape uses it (only those are written) */
    pt__mts_ply *ply;         /* the PLY files, in the order the XML names them */
    int ply_count;
    char name[4 * sizeof(((pt_scenefile *)0)->file) * 4 + 1]; /* d->file, escaped for a comment */
    char base[6 * PT__SF_PATH + 1];  /* the side files' common part (the XML's stem, no directory), XML-escaped */
    pt_image env;             /* the environment map resampled for Mitsuba (pt__mts_env_map; width 0: none) */
} pt__mts;

static void pt__mts_put(pt__mts *w, const char *fmt, ...)
{
    va_list ap;
    if (!w->f) return;
    va_start(ap, fmt);
    vfprintf(w->f, fmt, ap);
    va_end(ap);
}
/* A number; %.17g so that a double read back is the same double (a float: the same float). */
static void pt__mts_g(pt__mts *w, double x)
{
    if (!pt__sf_finite(x)) {
        if (!w->bad) w->bad_line = w->line;
        w->bad = 1;
        x = 0;
    }
    if (x == 0) x = 0; /* no "-0" */
    if (w->f) fprintf(w->f, "%.17g", x);
}
/* A float of the scene as it is (%.9g reads back as the same float). */
static void pt__mts_f(pt__mts *w, float x)
{
    if (!pt__sf_isfinite(x)) {
        pt__mts_g(w, (double)x);
        return;
    }
    if (x == 0) x = 0;
    if (w->f) fprintf(w->f, "%.9g", (double)x);
}
/* <point name=".." x=".." y=".." z=".."/> */
static void pt__mts_point_el(pt__mts *w, const char *name, double x, double y, double z)
{
    pt__mts_put(w, "<point name=\"%s\" x=\"", name);
    pt__mts_g(w, x);
    pt__mts_put(w, "\" y=\"");
    pt__mts_g(w, y);
    pt__mts_put(w, "\" z=\"");
    pt__mts_g(w, z);
    pt__mts_put(w, "\"/>");
}
static void pt__mts_rgb(pt__mts *w, const char *name, pt_color c)
{
    pt__mts_put(w, "<rgb name=\"%s\" value=\"", name);
    pt__mts_f(w, c.x);
    pt__mts_put(w, ", ");
    pt__mts_f(w, c.y);
    pt__mts_put(w, ", ");
    pt__mts_f(w, c.z);
    pt__mts_put(w, "\"/>");
}

/* Text from input for an XML comment: the comment escape, with '-' as \x2D too (an XML
   comment may not hold "--" nor end in '-'). */
static void pt__mts_comment_text(char *out, size_t size, const char *text)
{
    char tmp[4 * sizeof(((pt_scenefile *)0)->file) + 1];
    size_t i, n = 0;
    pt_scenefile_escape(tmp, sizeof tmp, text, PT_SCENEFILE_ESCAPE_COMMENT);
    for (i = 0; tmp[i] && n + 5u < size; ++i) {
        if (tmp[i] == '-') { memcpy(out + n, "\\x2D", 4); n += 4; }
        else out[n++] = tmp[i];
    }
    out[n] = '\0';
}

/* A rough conductor: two-sided (pdftrace's materials are) `roughconductor` with distribution ggx,
   sample_visible true, alpha, eta and k as RGB (the named metals too: pdftrace's own table, not
   Mitsuba's spectral data) or material "none", and the tint as specular_reflectance; below alpha
   1e-3, where pdftrace renders the smooth Fresnel mirror, the smooth `conductor`. */
static void pt__mts_conductor(pt__mts *w, const pt_scenefile_material *m, int i)
{
    int smooth = m->roughness < 1e-3f;
    pt__mts_put(w, "  <bsdf type=\"twosided\" id=\"mat%d\"><bsdf type=\"%s\">", i, smooth ? "conductor" : "roughconductor");
    if (!smooth) {
        pt__mts_put(w, "<string name=\"distribution\" value=\"ggx\"/><boolean name=\"sample_visible\" value=\"true\"/>"
                       "<float name=\"alpha\" value=\"");
        pt__mts_f(w, m->roughness);
        pt__mts_put(w, "\"/>");
    }
    if (m->conductor == PT_CONDUCTOR_NONE) {
        pt__mts_put(w, "<string name=\"material\" value=\"none\"/>");
    } else {
        pt_color eta = m->eta, k = m->k;
        if (m->conductor != PT_CONDUCTOR_CUSTOM) pt_conductor_ior(m->conductor, &eta, &k);
        pt__mts_rgb(w, "eta", eta);
        pt__mts_rgb(w, "k", k);
    }
    pt__mts_rgb(w, "specular_reflectance", m->albedo);
    pt__mts_put(w, "</bsdf></bsdf>\n");
}

/* A rough plastic: two-sided `roughplastic` with distribution ggx, sample_visible true, alpha (at
   least 1e-3, the coat pdftrace renders), int_ior, ext_ior 1, diffuse_reflectance and nonlinear;
   Mitsuba's specular_reflectance stays at its default, 1 (pdftrace's coat has no tint). */
static void pt__mts_plastic(pt__mts *w, const pt_scenefile_material *m, int i)
{
    pt__mts_put(w, "  <bsdf type=\"twosided\" id=\"mat%d\"><bsdf type=\"roughplastic\"><string name=\"distribution\" "
                   "value=\"ggx\"/><boolean name=\"sample_visible\" value=\"true\"/><float name=\"alpha\" value=\"", i);
    pt__mts_f(w, m->roughness > 1e-3f ? m->roughness : 1e-3f);
    pt__mts_put(w, "\"/><float name=\"int_ior\" value=\"");
    pt__mts_f(w, m->ior > 0.0f ? m->ior : 1.5f);
    pt__mts_put(w, "\"/><float name=\"ext_ior\" value=\"1\"/>");
    pt__mts_rgb(w, "diffuse_reflectance", m->albedo);
    pt__mts_put(w, "<boolean name=\"nonlinear\" value=\"%s\"/></bsdf></bsdf>\n", m->nonlinear ? "true" : "false");
}

/* A rough dielectric: `roughdielectric` with distribution ggx, sample_visible true, alpha, int_ior
   and ext_ior written out (Mitsuba's ext_ior defaults to air's 1.000277). Its transmission scales
   radiance by 1/eta^2 in radiance mode as pdftrace's does, so the twin is exact. Below pdftrace's
   delta switch (alpha < 1e-3, or alpha |eta - 1| < 1e-3) the smooth `dielectric`, which scales
   alike. Not two-sided: the inside is the side the normal points away from, in both. */
static void pt__mts_rough_dielectric(pt__mts *w, const pt_scenefile_material *m, int i)
{
    float e = m->ext_ior > 0.0f ? m->ext_ior : 1.0f, n = m->ior > 0.0f ? m->ior : 1.5f;
    int smooth = m->roughness < 1e-3f || m->roughness * fabsf(n / e - 1.0f) < 1e-3f;
    pt__mts_put(w, "  <bsdf type=\"%s\" id=\"mat%d\">", smooth ? "dielectric" : "roughdielectric", i);
    if (!smooth) {
        pt__mts_put(w, "<string name=\"distribution\" value=\"ggx\"/><boolean name=\"sample_visible\" value=\"true\"/>"
                       "<float name=\"alpha\" value=\"");
        pt__mts_f(w, m->roughness);
        pt__mts_put(w, "\"/>");
    }
    pt__mts_put(w, "<float name=\"int_ior\" value=\"");
    pt__mts_f(w, n);
    pt__mts_put(w, "\"/><float name=\"ext_ior\" value=\"");
    pt__mts_f(w, e);
    pt__mts_put(w, "\"/></bsdf>\n");
}

/* Image texture `image` as Mitsuba 3's bitmap: the linear pixels pdftrace uses, written beside
   the XML ("<stem>.tex.<image>.pfm", so Mitsuba decodes nothing), bilinear between texel
   centres, repeated (pt_scene_add_image_texture: the same lookup); raw for non-colour data. */
static void pt__mts_bitmap(pt__mts *w, const char *name, int image, int raw)
{
    pt__mts_put(w, "<texture type=\"bitmap\" name=\"%s\"><string name=\"filename\" value=\"%s.tex.%d.pfm\"/>"
                   "<string name=\"filter_type\" value=\"bilinear\"/><string name=\"wrap_mode\" value=\"repeat\"/>"
                   "<boolean name=\"raw\" value=\"%s\"/></texture>", name, w->base, image, raw ? "true" : "false");
}

/* The bsdf of material i, with id "mat<i>": Lambertian as two-sided diffuse (an image texture as
   a bitmap), a mirror as a
   two-sided conductor without Fresnel (material "none": reflectance = specular_reflectance),
   glass as a smooth dielectric in vacuum, an emitter as black diffuse (it reflects nothing). */
static void pt__mts_bsdf(pt__mts *w, int i)
{
    const pt_scenefile_material *m = &w->d->materials[i];
    char name[16 * PT_SCENEFILE_NAME_MAX + 1], raw[PT_SCENEFILE_NAME_MAX];
    memcpy(raw, m->name, sizeof raw);
    raw[sizeof raw - 1] = '\0';
    pt__mts_comment_text(name, sizeof name, raw);
    pt__mts_put(w, "  <!-- material %s -->\n", name);
    switch (m->type) {
    case PT_MATERIAL_LAMBERTIAN:
        pt__mts_put(w, "  <bsdf type=\"twosided\" id=\"mat%d\"><bsdf type=\"diffuse\">", i);
        if (m->image >= 0) pt__mts_bitmap(w, "reflectance", m->image, 0);
        else pt__mts_rgb(w, "reflectance", m->albedo);
        pt__mts_put(w, "</bsdf></bsdf>\n");
        break;
    case PT_MATERIAL_METAL:
        pt__mts_put(w, "  <bsdf type=\"twosided\" id=\"mat%d\"><bsdf type=\"conductor\"><string name=\"material\" "
                       "value=\"none\"/>", i);
        pt__mts_rgb(w, "specular_reflectance", m->albedo);
        pt__mts_put(w, "</bsdf></bsdf>\n");
        break;
    case PT_MATERIAL_ROUGH_CONDUCTOR:
        pt__mts_conductor(w, m, i);
        break;
    case PT_MATERIAL_ROUGH_PLASTIC:
        pt__mts_plastic(w, m, i);
        break;
    case PT_MATERIAL_ROUGH_DIELECTRIC:
        pt__mts_rough_dielectric(w, m, i);
        break;
    case PT_MATERIAL_DIELECTRIC:
        pt__mts_put(w, "  <bsdf type=\"dielectric\" id=\"mat%d\"><float name=\"int_ior\" value=\"", i);
        pt__mts_f(w, m->ior > 0.0f ? m->ior : 1.5f); /* 0 means 1.5, as in pt_material_desc */
        pt__mts_put(w, "\"/><float name=\"ext_ior\" value=\"1\"/></bsdf>\n");
        break;
    default:
        pt__mts_put(w, "  <bsdf type=\"diffuse\" id=\"mat%d\"><rgb name=\"reflectance\" value=\"0, 0, 0\"/></bsdf>\n", i);
    }
}

/* The end of a shape element: its bsdf and, for an emitter, a one-sided area light. */
static void pt__mts_shape_end(pt__mts *w, int material)
{
    const pt_scenefile_material *m = &w->d->materials[material];
    pt__mts_put(w, "<ref id=\"mat%d\"/>", material);
    if (m->type == PT_MATERIAL_EMITTER) {
        pt__mts_put(w, "<emitter type=\"area\">");
        pt__mts_rgb(w, "radiance", m->emission);
        pt__mts_put(w, "</emitter>");
    }
    pt__mts_put(w, "</shape>\n");
}

static double pt__mts_det(double x[3][4])
{
    return x[0][0] * (x[1][1] * x[2][2] - x[1][2] * x[2][1]) - x[0][1] * (x[1][0] * x[2][2] - x[1][2] * x[2][0]) +
           x[0][2] * (x[1][0] * x[2][1] - x[1][1] * x[2][0]);
}
static void pt__mts_point(double x[3][4], pt_vec3 p, double out[3])
{
    int i;
    for (i = 0; i < 3; ++i) out[i] = x[i][0] * p.x + x[i][1] * p.y + x[i][2] * p.z + x[i][3];
}
static void pt__mts_vector(double x[3][4], pt_vec3 p, double out[3])
{
    int i;
    for (i = 0; i < 3; ++i) out[i] = x[i][0] * p.x + x[i][1] * p.y + x[i][2] * p.z;
}

/* Q + a u + b v (a, b in [0, 1]) as Mitsuba's rectangle, [-1, 1]^2 in z = 0 with normal +z:
   to_world has the columns u/2, v/2, n = (u x v)/|u x v| and the centre Q + u/2 + v/2, so
   the normal is pdftrace's u x v (n is orthogonal to u and v: Mitsuba's normal transform
   M^-T maps +z onto it). Under a mirroring transform u and v are swapped first, as
   pdftrace's builder does, which keeps the emitting side on the transformed normal. */
static void pt__mts_rectangle(pt__mts *w, double x[3][4], pt_vec3 q0, pt_vec3 u0, pt_vec3 v0, int material)
{
    double q[3], u[3], v[3], n[3], len, m[3][4];
    int i, j;
    pt__mts_point(x, q0, q);
    pt__mts_vector(x, u0, u);
    pt__mts_vector(x, v0, v);
    if (pt__mts_det(x) < 0) {
        double t[3];
        memcpy(t, u, sizeof t); memcpy(u, v, sizeof t); memcpy(v, t, sizeof t);
    }
    n[0] = u[1] * v[2] - u[2] * v[1];
    n[1] = u[2] * v[0] - u[0] * v[2];
    n[2] = u[0] * v[1] - u[1] * v[0];
    len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    for (i = 0; i < 3; ++i) {
        m[i][0] = 0.5 * u[i];
        m[i][1] = 0.5 * v[i];
        m[i][2] = n[i] / len; /* len == 0 gives NaN: caught by pt__mts_g */
        m[i][3] = q[i] + 0.5 * u[i] + 0.5 * v[i];
    }
    pt__mts_put(w, "  <shape type=\"rectangle\"><transform name=\"to_world\"><matrix value=\"");
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 4; ++j) {
            pt__mts_g(w, m[i][j]);
            pt__mts_put(w, " ");
        }
    pt__mts_put(w, "0 0 0 1\"/></transform>");
    pt__mts_shape_end(w, material);
}

/* A box: the six faces pdftrace's pt_scene_add_box makes (u x v out of the box), each a rectangle. */
static void pt__mts_box(pt__mts *w, double x[3][4], pt_vec3 lo, pt_vec3 hi, int material)
{
    pt_vec3 q[6], u[6], v[6];
    pt_vec3 dx = pt_v3(hi.x - lo.x, 0, 0), dy = pt_v3(0, hi.y - lo.y, 0), dz = pt_v3(0, 0, hi.z - lo.z);
    int i;
    q[0] = pt_v3(lo.x, lo.y, hi.z); u[0] = dx; v[0] = dy;
    q[1] = pt_v3(hi.x, lo.y, lo.z); u[1] = pt_neg(dx); v[1] = dy;
    q[2] = pt_v3(hi.x, lo.y, hi.z); u[2] = pt_neg(dz); v[2] = dy;
    q[3] = pt_v3(lo.x, lo.y, lo.z); u[3] = dz; v[3] = dy;
    q[4] = pt_v3(lo.x, hi.y, hi.z); u[4] = dx; v[4] = pt_neg(dz);
    q[5] = pt_v3(lo.x, lo.y, lo.z); u[5] = dx; v[5] = dz;
    for (i = 0; i < 6; ++i) pt__mts_rectangle(w, x, q[i], u[i], v[i], material);
}

/* A sphere under a similarity (the build refuses any other): the centre moved, the radius
   scaled by the transform's scale (the length of its first column). */
static void pt__mts_sphere(pt__mts *w, double x[3][4], pt_vec3 c0, float radius, int material)
{
    double c[3], s = sqrt(x[0][0] * x[0][0] + x[1][0] * x[1][0] + x[2][0] * x[2][0]);
    pt__mts_point(x, c0, c);
    pt__mts_put(w, "  <shape type=\"sphere\">");
    pt__mts_point_el(w, "center", c[0], c[1], c[2]);
    pt__mts_put(w, "<float name=\"radius\" value=\"");
    pt__mts_g(w, (double)radius * s);
    pt__mts_put(w, "\"/>");
    pt__mts_shape_end(w, material);
}

/* ---- PLY (Turk, "The PLY Polygon File Format", 1994): a text header, then little-endian
   float32 vertices (x y z [nx ny nz]) and faces (uint8 count 3, three uint32 indices). */
static void pt__mts_le32(FILE *f, uint32_t u)
{
    unsigned char b[4];
    b[0] = (unsigned char)(u & 0xffu);
    b[1] = (unsigned char)((u >> 8) & 0xffu);
    b[2] = (unsigned char)((u >> 16) & 0xffu);
    b[3] = (unsigned char)(u >> 24);
    fwrite(b, 1, 4, f);
}
/* A float: checked finite in both passes (a PLY float is not written as text). */
static void pt__mts_ply_float(pt__mts *w, double x)
{
    float f = (float)x;
    uint32_t u;
    if (!pt__sf_isfinite(f) || !pt__sf_finite(x)) {
        if (!w->bad) w->bad_line = w->line;
        w->bad = 1;
        f = 0.0f;
    }
    memcpy(&u, &f, sizeof u);
    if (w->f) pt__mts_le32(w->f, u);
}
static void pt__mts_ply_header(pt__mts *w, uint32_t vertices, uint32_t faces, int normals, int uvs)
{
    pt__mts_put(w, "ply\nformat binary_little_endian 1.0\ncomment written by pdftrace %d.%d.%d\n", PDFTRACE_VERSION_MAJOR,
                PDFTRACE_VERSION_MINOR, PDFTRACE_VERSION_PATCH);
    pt__mts_put(w, "element vertex %lu\nproperty float x\nproperty float y\nproperty float z\n", (unsigned long)vertices);
    if (normals) pt__mts_put(w, "property float nx\nproperty float ny\nproperty float nz\n");
    if (uvs) pt__mts_put(w, "property float u\nproperty float v\n"); /* Mitsuba's PLY reads them unflipped */
    pt__mts_put(w, "element face %lu\nproperty list uchar uint vertex_indices\nend_header\n", (unsigned long)faces);
}
static void pt__mts_ply_face(pt__mts *w, uint32_t a, uint32_t b, uint32_t c)
{
    if (!w->f) return;
    fputc(3, w->f);
    pt__mts_le32(w->f, a);
    pt__mts_le32(w->f, b);
    pt__mts_le32(w->f, c);
}

/* A mesh statement: its vertices in world space (the transform in double, rounded once), the
   normals by the inverse transpose and normalised (as pdftrace's builder does; dropped for an
   emitter, which reflects nothing and emits on the geometric side), the corners' order
   reversed under a mirroring transform. Triangles with no area in float are skipped, as the
   builder skips them. */
static void pt__mts_ply_mesh(pt__mts *w, const pt_scenefile_shape *s)
{
    const pt_obj_mesh *m = &w->d->meshes[s->mesh];
    int normals = m->normals && w->d->materials[s->material].type != PT_MATERIAL_EMITTER;
    double x[3][4], it[3][3], det;
    uint32_t k, faces = 0, pass;
    int i, j;
    pt__sf_shape_xfd(s, x);
    det = pt__mts_det(x);
    for (i = 0; i < 3; ++i) /* inverse transpose = cofactors / det */
        for (j = 0; j < 3; ++j)
            it[i][j] = (x[(i + 1) % 3][(j + 1) % 3] * x[(i + 2) % 3][(j + 2) % 3] -
                        x[(i + 1) % 3][(j + 2) % 3] * x[(i + 2) % 3][(j + 1) % 3]) / det;
    for (pass = 0; pass < 2; ++pass) {
        for (k = 0; k < m->triangle_count; ++k) {
            pt_vec3 p[3];
            uint32_t c, *ix = m->indices + 3u * k;
            double q[3];
            for (c = 0; c < 3; ++c) {
                pt__mts_point(x, pt_v3(m->positions[3 * ix[c]], m->positions[3 * ix[c] + 1], m->positions[3 * ix[c] + 2]), q);
                p[c] = pt_v3((float)q[0], (float)q[1], (float)q[2]);
            }
            if (!(pt_length2(pt_cross(pt_sub(p[1], p[0]), pt_sub(p[2], p[0]))) > 0.0f)) continue;
            if (pass == 0) ++faces;
            else if (det < 0) pt__mts_ply_face(w, ix[0], ix[2], ix[1]);
            else pt__mts_ply_face(w, ix[0], ix[1], ix[2]);
        }
        if (pass == 1) break;
        if (faces == 0) { /* nothing Mitsuba could load: as the build, refuse it */
            if (!w->bad) w->bad_line = s->line;
            w->bad = 1;
        }
        pt__mts_ply_header(w, m->vertex_count, faces, normals, m->uvs != NULL);
        for (k = 0; k < m->vertex_count; ++k) {
            double q[3];
            const float *pp = m->positions + 3u * k;
            pt__mts_point(x, pt_v3(pp[0], pp[1], pp[2]), q);
            for (i = 0; i < 3; ++i) pt__mts_ply_float(w, q[i]);
            if (normals) {
                const float *nn = m->normals + 3u * k;
                double n[3], len;
                for (i = 0; i < 3; ++i) n[i] = it[i][0] * nn[0] + it[i][1] * nn[1] + it[i][2] * nn[2];
                len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
                for (i = 0; i < 3; ++i) pt__mts_ply_float(w, n[i] / len);
            }
            if (m->uvs) {
                pt__mts_ply_float(w, m->uvs[2u * k]);
                pt__mts_ply_float(w, m->uvs[2u * k + 1u]);
            }
        }
    }
}

/* The triangle statements of one material: three vertices each, in world space, reversed
   under a mirroring transform (as pt_scene_add_triangle does). */
static void pt__mts_ply_triangles(pt__mts *w, int material)
{
    const pt_scenefile *d = w->d;
    uint32_t n = 0, k;
    int i, c, j;
    for (i = 0; i < d->shape_count; ++i)
        n += d->shapes[i].type == PT_SCENEFILE_TRIANGLE && d->shapes[i].material == material;
    pt__mts_ply_header(w, 3u * n, n, 0, 0);
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *s = &d->shapes[i];
        double x[3][4], q[3];
        int mirror;
        if (s->type != PT_SCENEFILE_TRIANGLE || s->material != material) continue;
        w->line = s->line;
        pt__sf_shape_xfd(s, x);
        mirror = pt__mts_det(x) < 0;
        for (c = 0; c < 3; ++c) {
            pt__mts_point(x, s->p[mirror && c ? 3 - c : c], q);
            for (j = 0; j < 3; ++j) pt__mts_ply_float(w, q[j]);
        }
    }
    for (k = 0; k < n; ++k) pt__mts_ply_face(w, 3u * k, 3u * k + 1u, 3u * k + 2u);
}

static void pt__mts_ply_body(pt__mts *w, int job)
{
    const pt__mts_ply *p = &w->ply[job];
    w->line = p->line;
    if (p->shape >= 0) pt__mts_ply_mesh(w, &w->d->shapes[p->shape]);
    else pt__mts_ply_triangles(w, p->material);
}

/* The XML's shape for PLY file `job`. Without normals in the file, face_normals keeps
   Mitsuba from computing smooth ones. */
static void pt__mts_ply_shape(pt__mts *w, int job)
{
    const pt__mts_ply *p = &w->ply[job];
    const pt_scenefile_shape *s = p->shape >= 0 ? &w->d->shapes[p->shape] : NULL;
    int normals = s && w->d->meshes[s->mesh].normals && w->d->materials[p->material].type != PT_MATERIAL_EMITTER;
    pt__mts_put(w, "  <shape type=\"ply\"><string name=\"filename\" value=\"%s.%d.ply\"/>", w->base, job);
    if (!normals) pt__mts_put(w, "<boolean name=\"face_normals\" value=\"true\"/>");
    pt__mts_shape_end(w, p->material);
}

/* The map's scale as the build resolves it (pt_environment_desc: 0 means 1). */
static float pt__mts_env_scale(const pt_scenefile *d) { return d->environment_scale == 0.0f ? 1.0f : d->environment_scale; }

/* The environment map as Mitsuba 3's envmap needs it. Both renderers put column x at
   u = (x + 1/2) / W, interpolate bilinearly and wrap in u; but pdftrace's row y is the cell
   centred at v = (y + 1/2) / H (held constant above the first centre and below the last),
   where Mitsuba's rows are point samples from the zenith to the nadir, row k at v = k / (H' - 1)
   (src/emitters/envmap.cpp, eval_spectrum). With H' = 2H + 1 rows, row 2y + 1 is pdftrace's
   row y (at v = (y + 1/2) / H), row 2y for 0 < y < H the mean of its rows y - 1 and y (at v =
   y / H, halfway between their centres), and rows 0 and 2H copies of its first and last: then
   Mitsuba's interpolant, linear between its rows, equals pdftrace's, which is linear between
   row centres, everywhere. A background is added to every pixel, divided by the scale that
   Mitsuba applies: Mitsuba 3 takes one environment emitter per scene, so it cannot be a
   `constant` emitter beside the map. Returns 0 when out of memory; a pixel that is not finite
   marks the export bad (at the statement's line). */
static int pt__mts_env_map(pt__mts *w)
{
    const pt_scenefile *d = w->d;
    const pt_image *m = &d->environment;
    int x, k, c, W = m->width, H = m->height;
    float add[3], scale = pt__mts_env_scale(d);
    if (pt_image_init(&w->env, W, 2 * H + 1) != PT_OK) return 0;
    add[0] = d->background.x / scale;
    add[1] = d->background.y / scale;
    add[2] = d->background.z / scale;
    for (k = 0; k <= 2 * H; ++k) {
        int a = k % 2 ? (k - 1) / 2 : k / 2 - 1, b = k % 2 ? a : k / 2; /* the rows it takes */
        if (a < 0) a = 0;
        if (b > H - 1) b = H - 1;
        for (x = 0; x < W; ++x)
            for (c = 0; c < 3; ++c) {
                float va = m->rgb[3u * ((size_t)a * (size_t)W + (size_t)x) + (size_t)c];
                float vb = m->rgb[3u * ((size_t)b * (size_t)W + (size_t)x) + (size_t)c];
                float v = (a == b ? va : 0.5f * va + 0.5f * vb) + add[c];
                if (!pt__sf_isfinite(v)) {
                    if (!w->bad) w->bad_line = d->environment_line;
                    w->bad = 1;
                    v = 0.0f;
                }
                w->env.rgb[3u * ((size_t)k * (size_t)W + (size_t)x) + (size_t)c] = v;
            }
    }
    return 1;
}

/* The envmap emitter: the resampled map beside the XML ("<stem>.env.pfm"), its scale, and the
   statement's rotation as to_world (the map's frame into the world, as pdftrace's; Mitsuba
   looks a direction up through the inverse). */
static void pt__mts_envmap(pt__mts *w)
{
    const pt_scenefile *d = w->d;
    int i, j;
    w->line = d->environment_line;
    pt__mts_put(w, "  <!-- %s:%d -->\n", w->name, d->environment_line);
    pt__mts_put(w, "  <emitter type=\"envmap\"><string name=\"filename\" value=\"%s.env.pfm\"/><float name=\"scale\" value=\"",
                w->base);
    pt__mts_f(w, pt__mts_env_scale(d));
    pt__mts_put(w, "\"/><transform name=\"to_world\"><matrix value=\"");
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 4; ++j) {
            pt__mts_f(w, j < 3 ? d->environment_transform.m[i][j] : 0.0f);
            pt__mts_put(w, " ");
        }
    pt__mts_put(w, "0 0 0 1\"/></transform></emitter>\n");
    w->line = 0;
}

/* The XML's head: the integrator, the sensor (with its sampler and film), the bsdfs of the
   materials in use and the background (or the environment map, with the background in it). */
static void pt__mts_header(pt__mts *w)
{
    const pt_scenefile *d = w->d;
    const pt_camera_desc *c = &d->camera;
    double vfov = c->vfov_degrees > 0 ? (double)c->vfov_degrees : 40.0;
    pt_vec3 up = pt_length2(c->up) > 0 ? c->up : pt_v3(0, 1, 0);
    int i;
    w->line = 0;
    pt__mts_put(w, "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n");
    pt__mts_put(w, "<!-- Mitsuba 3 scene written by pdftrace %d.%d.%d from %s -->\n", PDFTRACE_VERSION_MAJOR,
                PDFTRACE_VERSION_MINOR, PDFTRACE_VERSION_PATCH, w->name);
    pt__mts_put(w, "<!-- render: mitsuba -m scalar_rgb -o OUT.exr THIS.xml (or -m llvm_ad_rgb) -->\n");
    pt__mts_put(w, "<scene version=\"3.0.0\">\n");
    /* Mitsuba's max_depth counts the camera segment too: N scattering events are N + 1 segments. */
    pt__mts_put(w, "  <integrator type=\"path\"><integer name=\"max_depth\" value=\"%ld\"/>"
                   "<boolean name=\"hide_emitters\" value=\"false\"/></integrator>\n", (long)w->depth + 1L);
    w->line = d->camera_line;
    pt__mts_put(w, "  <sensor type=\"%s\">\n    <string name=\"fov_axis\" value=\"y\"/><float name=\"fov\" value=\"",
                c->lens_radius > 0 ? "thinlens" : "perspective");
    pt__mts_g(w, vfov);
    pt__mts_put(w, "\"/>\n");
    if (c->lens_radius > 0) {
        /* pdftrace's thin lens: a uniform disk of lens_radius, sharp at focus_distance (default
           |look_at - look_from|) on a plane normal to the view, as Mitsuba's thinlens */
        double focus = c->focus_distance > 0 ? (double)c->focus_distance : (double)pt_length(pt_sub(c->look_at, c->look_from));
        pt__mts_put(w, "    <float name=\"aperture_radius\" value=\"");
        pt__mts_f(w, c->lens_radius);
        pt__mts_put(w, "\"/><float name=\"focus_distance\" value=\"");
        pt__mts_g(w, focus);
        pt__mts_put(w, "\"/>\n");
    }
    /* the clipping planes enclose the whole scene (Mitsuba's default far_clip is 1e4) */
    pt__mts_put(w, "    <float name=\"near_clip\" value=\"");
    pt__mts_g(w, w->near_clip);
    pt__mts_put(w, "\"/><float name=\"far_clip\" value=\"");
    pt__mts_g(w, w->far_clip);
    pt__mts_put(w, "\"/>\n    <transform name=\"to_world\"><lookat origin=\"");
    pt__mts_f(w, c->look_from.x); pt__mts_put(w, ", ");
    pt__mts_f(w, c->look_from.y); pt__mts_put(w, ", ");
    pt__mts_f(w, c->look_from.z);
    pt__mts_put(w, "\" target=\"");
    pt__mts_f(w, c->look_at.x); pt__mts_put(w, ", ");
    pt__mts_f(w, c->look_at.y); pt__mts_put(w, ", ");
    pt__mts_f(w, c->look_at.z);
    pt__mts_put(w, "\" up=\"");
    pt__mts_f(w, up.x); pt__mts_put(w, ", ");
    pt__mts_f(w, up.y); pt__mts_put(w, ", ");
    pt__mts_f(w, up.z);
    pt__mts_put(w, "\"/></transform>\n");
    pt__mts_put(w, "    <sampler type=\"independent\"><integer name=\"sample_count\" value=\"%d\"/>"
                   "<integer name=\"seed\" value=\"%lu\"/></sampler>\n", w->spp, (unsigned long)(d->seed & 0x7fffffffu));
    /* box filter: each sample counts for its own pixel only, as in pdftrace's film */
    pt__mts_put(w, "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"%d\"/><integer name=\"height\" value=\"%d\"/>"
                   "<string name=\"pixel_format\" value=\"rgb\"/><string name=\"component_format\" value=\"float32\"/>"
                   "<rfilter type=\"box\"/></film>\n  </sensor>\n", w->width, w->height);
    w->line = 0;
    for (i = 0; i < d->material_count; ++i)
        if (w->used[i]) pt__mts_bsdf(w, i);
    if (w->env.width > 0) pt__mts_envmap(w);
    else if (!(d->background.x == 0 && d->background.y == 0 && d->background.z == 0)) { /* (a nan is written: refused) */
        pt__mts_put(w, "  <emitter type=\"constant\">");
        pt__mts_rgb(w, "radiance", d->background);
        pt__mts_put(w, "</emitter>\n");
    }
}

/* A point, spot or directional light, in world space (the transform in double): Mitsuba 3's
   `point` (intensity in W/sr), `spot` (its cone along +z of to_world, aimed by a lookat from
   the position to a point on its axis; the same linear falloff in the angle from beam_width to
   cutoff_angle, in degrees) and `directional` (`direction` the way the light travels,
   irradiance in W/m^2): the same units and profiles as pdftrace's (docs/mitsuba.md). */
static void pt__mts_light(pt__mts *w, const pt_scenefile_light *l)
{
    const pt_light_desc *ld = &l->desc;
    double x[3][4], p[3], a[3], len;
    int i;
    pt__sf_xfd(&l->transform, l->transform_d, x);
    pt__mts_point(x, ld->position, p);
    pt__mts_vector(x, ld->direction, a);
    len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (ld->type != PT_LIGHT_POINT) /* the build refused a zero direction; an overflow gives nan: refused */
        for (i = 0; i < 3; ++i) a[i] /= len;
    w->line = l->line;
    pt__mts_put(w, "  <!-- %s:%d -->\n", w->name, l->line);
    if (ld->type == PT_LIGHT_POINT) {
        pt__mts_put(w, "  <emitter type=\"point\">");
        pt__mts_point_el(w, "position", p[0], p[1], p[2]);
        pt__mts_rgb(w, "intensity", ld->intensity);
    } else if (ld->type == PT_LIGHT_SPOT) {
        float cutoff, beam;
        /* up: the world axis least aligned with the cone's (lookat needs one not parallel to
           it; the cone is round, so which one does not matter) */
        int k = fabs(a[0]) <= fabs(a[1]) && fabs(a[0]) <= fabs(a[2]) ? 0 : fabs(a[1]) <= fabs(a[2]) ? 1 : 2;
        pt__sf_spot_angles(ld, &cutoff, &beam);
        pt__mts_put(w, "  <emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"");
        for (i = 0; i < 3; ++i) {
            pt__mts_g(w, p[i]);
            pt__mts_put(w, i < 2 ? ", " : "\" target=\"");
        }
        for (i = 0; i < 3; ++i) { /* the target as far off as the position is large: Mitsuba's
                                     scalar variants read it in float, which keeps the axis then */
            pt__mts_g(w, p[i] + a[i] * (1.0 + fabs(p[0]) + fabs(p[1]) + fabs(p[2])));
            pt__mts_put(w, i < 2 ? ", " : "\" up=\"");
        }
        pt__mts_put(w, "%s\"/></transform>", k == 0 ? "1, 0, 0" : k == 1 ? "0, 1, 0" : "0, 0, 1");
        pt__mts_rgb(w, "intensity", ld->intensity);
        pt__mts_put(w, "<float name=\"cutoff_angle\" value=\"");
        pt__mts_f(w, cutoff);
        pt__mts_put(w, "\"/><float name=\"beam_width\" value=\"");
        pt__mts_f(w, beam);
        pt__mts_put(w, "\"/>");
    } else {
        pt__mts_put(w, "  <emitter type=\"directional\"><vector name=\"direction\" x=\"");
        pt__mts_g(w, a[0]);
        pt__mts_put(w, "\" y=\"");
        pt__mts_g(w, a[1]);
        pt__mts_put(w, "\" z=\"");
        pt__mts_g(w, a[2]);
        pt__mts_put(w, "\"/>");
        pt__mts_rgb(w, "irradiance", ld->intensity);
    }
    pt__mts_put(w, "</emitter>\n");
}

static void pt__mts_body(pt__mts *w)
{
    const pt_scenefile *d = w->d;
    int i, job = 0;
    for (i = 0; i < d->material_count; ++i) w->used[i] &= 1u;
    pt__mts_header(w);
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *s = &d->shapes[i];
        double x[3][4];
        w->line = s->line;
        pt__sf_shape_xfd(s, x);
        if (s->type == PT_SCENEFILE_TRIANGLE) {
            if (w->used[s->material] & 2u) continue; /* written with the first triangle of its material */
            w->used[s->material] |= 2u;
        }
        pt__mts_put(w, "  <!-- %s:%d -->\n", w->name, s->line);
        switch (s->type) {
        case PT_SCENEFILE_SPHERE: pt__mts_sphere(w, x, s->p[0], s->radius, s->material); break;
        case PT_SCENEFILE_QUAD: pt__mts_rectangle(w, x, s->p[0], s->p[1], s->p[2], s->material); break;
        case PT_SCENEFILE_BOX: pt__mts_box(w, x, s->p[0], s->p[1], s->material); break;
        default: pt__mts_ply_shape(w, job++);
        }
    }
    for (i = 0; i < d->light_count; ++i) pt__mts_light(w, &d->lights[i]);
    pt__mts_put(w, "</scene>\n");
}

/* What the export refuses, before anything is written: every scene the build refuses (the
   build itself runs), a camera the renderer refuses, then what Mitsuba has no exact twin for
   (docs/mitsuba.md, with the measurements behind each). */
/* The largest channel value of an image. */
static float pt__mts_image_max(const pt_image *im)
{
    size_t i, n = 3u * (size_t)im->width * (size_t)im->height;
    float m = 0.0f;
    for (i = 0; i < n; ++i) m = im->rgb[i] > m ? im->rgb[i] : m;
    return m;
}
static int pt__mts_refuse(const pt_scenefile *d, int width, int height, char *err, size_t err_size)
{
    pt_scene *scene = NULL;
    pt_render_desc rd;
    pt_camera cam;
    int i, rc = pt_scenefile_build(d, &scene, &rd, err, err_size);
    pt_scene_destroy(scene);
    if (rc != PT_OK) return rc;
    if (pt_camera_init(&cam, &d->camera, width, height) != PT_OK)
        return pt__sf_failf(err, err_size, d->file, d->camera_line, PT_ERROR_INVALID_ARGUMENT,
                            "Mitsuba export: pdftrace cannot render this camera (a non-finite vector, look_at "
                            "equal to look_from, up parallel to the view, or vfov outside (0, 180))");
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *s = &d->shapes[i];
        const pt_scenefile_material *m = &d->materials[s->material];
        const char *why = NULL;
        if (m->type == PT_MATERIAL_METAL && m->fuzz > 0)
            why = "fuzzy metal (material %s) has no exact Mitsuba equivalent (its rough conductors are microfacet "
                  "models, not pdftrace's mirror direction jittered in a ball)";
        else if ((m->type == PT_MATERIAL_LAMBERTIAN || m->type == PT_MATERIAL_ROUGH_PLASTIC) && m->checker >= 0)
            why = "the 3-D checker texture (material %s) has no exact Mitsuba equivalent (Mitsuba's checkerboard "
                  "is a 2-D texture over a shape's (u, v) coordinates)";
        else if (m->image >= 0 && pt__mts_image_max(&d->images[m->image].image) > 1.0f)
            why = "an image texture with a value above 1 (material %s): Mitsuba accepts RGB reflectances in [0, 1] only";
        else if ((m->type == PT_MATERIAL_LAMBERTIAN || m->type == PT_MATERIAL_METAL ||
                  m->type == PT_MATERIAL_ROUGH_CONDUCTOR) &&
                 (m->albedo.x > 1 || m->albedo.y > 1 || m->albedo.z > 1))
            why = "an albedo above 1 (material %s): Mitsuba accepts RGB reflectances in [0, 1] only";
        else if (m->type == PT_MATERIAL_DIELECTRIC && m->ior == 1.0f)
            why = "a dielectric of ior 1 (material %s): Mitsuba's dielectric needs an interior index that differs "
                  "from the exterior one (1)";
        else if (m->type == PT_MATERIAL_ROUGH_DIELECTRIC && m->ior == m->ext_ior)
            why = "a rough dielectric with ior = ext_ior (material %s): Mitsuba's dielectrics need an interior "
                  "index that differs from the exterior one";
        else if (m->type == PT_MATERIAL_EMITTER && m->two_sided)
            why = "a two-sided emitter (material %s): Mitsuba's area lights emit on one side only, and a pair of "
                  "coincident back-to-back shapes is not exact (each ray hits either one)";
        if (why) {
            char msg[320];
            snprintf(msg, sizeof msg, why, m->name);
            return pt__sf_failf(err, err_size, d->file, s->line, PT_ERROR_UNSUPPORTED, "Mitsuba export: %s", msg);
        }
    }
    return PT_OK;
}

/* The clipping planes: far beyond the farthest point of the scene's bounds from the camera,
   near at a millionth of that (Mitsuba's sensors clip; pdftrace's camera does not). */
static void pt__mts_clip(pt__mts *w)
{
    const pt_scenefile *d = w->d;
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, x[3][4], far2 = 0;
    pt_vec3 e = d->camera.look_from;
    int i, k;
    uint32_t v;
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *s = &d->shapes[i];
        const pt_vec3 *p = s->p;
        pt__sf_shape_xfd(s, x);
        if (s->type == PT_SCENEFILE_SPHERE) {
            double sx = sqrt(x[0][0] * x[0][0] + x[1][0] * x[1][0] + x[2][0] * x[2][0]);
            pt__sf_dbounds(x, p[0], (double)s->radius * sx, lo, hi);
        } else if (s->type == PT_SCENEFILE_MESH) {
            const pt_obj_mesh *m = &d->meshes[s->mesh];
            for (v = 0; v < m->vertex_count; ++v)
                pt__sf_dbounds(x, pt_v3(m->positions[3 * v], m->positions[3 * v + 1], m->positions[3 * v + 2]), 0, lo, hi);
        } else if (s->type == PT_SCENEFILE_BOX) {
            for (k = 0; k < 8; ++k)
                pt__sf_dbounds(x, pt_v3((k & 1) ? p[1].x : p[0].x, (k & 2) ? p[1].y : p[0].y, (k & 4) ? p[1].z : p[0].z), 0,
                               lo, hi);
        } else if (s->type == PT_SCENEFILE_QUAD) {
            pt__sf_dbounds(x, p[0], 0, lo, hi);
            pt__sf_dbounds(x, pt_add(p[0], p[1]), 0, lo, hi);
            pt__sf_dbounds(x, pt_add(p[0], p[2]), 0, lo, hi);
            pt__sf_dbounds(x, pt_add(pt_add(p[0], p[1]), p[2]), 0, lo, hi);
        } else
            for (k = 0; k < 3; ++k) pt__sf_dbounds(x, p[k], 0, lo, hi);
    }
    for (k = 0; k < 8 && d->shape_count; ++k) {
        double dx = ((k & 1) ? hi[0] : lo[0]) - (double)e.x, dy = ((k & 2) ? hi[1] : lo[1]) - (double)e.y,
               dz = ((k & 4) ? hi[2] : lo[2]) - (double)e.z;
        if (dx * dx + dy * dy + dz * dz > far2) far2 = dx * dx + dy * dy + dz * dz;
    }
    w->far_clip = 2.0 * sqrt(far2) + 1.0;
    w->near_clip = 1e-6 * w->far_clip;
}

/* Which materials are used, and the PLY files: one per mesh statement, one per material of
   the triangle statements (at its first triangle). Returns 0 when out of memory. */
static int pt__mts_plan(pt__mts *w)
{
    const pt_scenefile *d = w->d;
    int i;
    w->used = (unsigned char *)PT_MALLOC((size_t)d->material_count + 1u);
    w->ply = (pt__mts_ply *)PT_MALLOC(((size_t)d->shape_count + 1u) * sizeof *w->ply);
    if (!w->used || !w->ply) return 0;
    memset(w->used, 0, (size_t)d->material_count + 1u);
    for (i = 0; i < d->shape_count; ++i) {
        const pt_scenefile_shape *s = &d->shapes[i];
        if (s->type == PT_SCENEFILE_MESH || (s->type == PT_SCENEFILE_TRIANGLE && !(w->used[s->material] & 2u))) {
            w->ply[w->ply_count].shape = s->type == PT_SCENEFILE_MESH ? i : -1;
            w->ply[w->ply_count].material = s->material;
            w->ply[w->ply_count].line = s->line;
            w->ply_count++;
            if (s->type == PT_SCENEFILE_TRIANGLE) w->used[s->material] |= 2u;
        }
        w->used[s->material] |= 1u;
    }
    return 1;
}

/* "<path without .xml>.<job>.ply" into out (size bytes), or with job < 0 the environment map's
   "<path without .xml>.env.pfm", with job <= -2 image texture -2 - job's "<...>.tex.N.pfm"; 0 if
   it does not fit. */
static int pt__mts_ply_path(const char *path, int job, char *out, size_t size)
{
    size_t n = strlen(path);
    int k;
    if (n > 4 && !strcmp(path + n - 4, ".xml")) n -= 4;
    if (job <= -2) k = snprintf(out, size, "%.*s.tex.%d.pfm", (int)n, path, -2 - job);
    else if (job < 0) k = snprintf(out, size, "%.*s.env.pfm", (int)n, path);
    else k = snprintf(out, size, "%.*s.%d.ply", (int)n, path, job);
    return k > 0 && (size_t)k < size;
}

/* The side files' common part as the XML names them: the file part of the stem, XML-escaped.
   A byte the escape would alter (not just spell as an entity), or '$' (Mitsuba substitutes
   $name in attribute values), or '\' (a separator on Windows), would name another file:
   refused. */
static int pt__mts_base(pt__mts *w, const char *path, char *err, size_t err_size)
{
    char stem[PT__SF_PATH];
    const char *b, *c;
    size_t n = strlen(path);
    if (n > 4 && !strcmp(path + n - 4, ".xml")) n -= 4;
    if (n >= sizeof stem)
        return pt__sf_failf(err, err_size, path, 0, PT_ERROR_INVALID_ARGUMENT, "Mitsuba export: the path is too long");
    memcpy(stem, path, n);
    stem[n] = '\0';
    b = strrchr(stem, '/');
    b = b ? b + 1 : stem;
    for (c = b; *c; ++c)
        if ((unsigned char)*c < 0x20u || (unsigned char)*c >= 0x7fu || *c == '$' || *c == '\\')
            return pt__sf_failf(err, err_size, w->d->file, w->ply_count ? w->ply[0].line : w->d->environment_line,
                                PT_ERROR_UNSUPPORTED,
                                "Mitsuba export: the scene needs files named after the output (PLY meshes, the "
                                "environment map, image textures), and its file name holds a byte the XML cannot name them with (a "
                                "control byte, a byte >= 0x80, '$' or '\\'); choose another name");
    pt_scenefile_escape(w->base, sizeof w->base, b, PT_SCENEFILE_ESCAPE_XML);
    return PT_OK;
}

/* Writes PLY file `job` to its place (through a temporary renamed into place). */
static int pt__mts_write_ply(pt__mts *w, const char *path, int job, char *err, size_t err_size)
{
    char ply_path[PT__SF_PATH + 32];
    pt_output_file out;
    int rc;
    if (!pt__mts_ply_path(path, job, ply_path, sizeof ply_path))
        return pt__sf_failf(err, err_size, path, 0, PT_ERROR_INVALID_ARGUMENT, "Mitsuba export: the path is too long");
    rc = pt_output_open(&out, ply_path, 0, "PLY mesh", err, err_size);
    if (rc != PT_OK) return rc;
    w->f = out.file;
    pt__mts_ply_body(w, job);
    w->f = NULL;
    return pt_output_close(&out, !ferror(out.file), "PLY mesh", err, err_size);
}

/* The files: the environment map and the PLY files first, then the XML; when one fails, the
   ones written are removed. */
static int pt__mts_write(pt__mts *w, const char *path, char *err, size_t err_size)
{
    char ply_path[PT__SF_PATH + 32];
    pt_output_file out;
    int i, done = 0, env = 0, tex = 0, rc = PT_OK;
    if (w->env.width > 0) {
        if (!pt__mts_ply_path(path, -1, ply_path, sizeof ply_path))
            return pt__sf_failf(err, err_size, path, 0, PT_ERROR_INVALID_ARGUMENT, "Mitsuba export: the path is too long");
        if ((rc = pt_write_pfm_ex(ply_path, &w->env, err, err_size)) != PT_OK) return rc;
        env = 1;
    }
    for (i = 0; i < w->d->image_count && rc == PT_OK; ++i) {
        if (!pt__mts_ply_path(path, -2 - i, ply_path, sizeof ply_path))
            rc = pt__sf_failf(err, err_size, path, 0, PT_ERROR_INVALID_ARGUMENT, "Mitsuba export: the path is too long");
        else if ((rc = pt_write_pfm_ex(ply_path, &w->d->images[i].image, err, err_size)) == PT_OK)
            tex = i + 1;
    }
    for (i = 0; i < w->ply_count && rc == PT_OK; ++i)
        if ((rc = pt__mts_write_ply(w, path, i, err, err_size)) == PT_OK) done = i + 1;
    if (rc == PT_OK && (rc = pt_output_open(&out, path, 1, "Mitsuba scene", err, err_size)) == PT_OK) {
        w->f = out.file;
        pt__mts_body(w);
        w->f = NULL;
        rc = pt_output_close(&out, !ferror(out.file), "Mitsuba scene", err, err_size);
    }
    for (i = env ? -1 : 0; rc != PT_OK && i < done; ++i)
        if (pt__mts_ply_path(path, i, ply_path, sizeof ply_path)) remove(ply_path);
    for (i = 0; rc != PT_OK && i < tex; ++i)
        if (pt__mts_ply_path(path, -2 - i, ply_path, sizeof ply_path)) remove(ply_path);
    return rc;
}

PTDEF int pt_scenefile_export_mitsuba(const pt_scenefile *d, const char *path, const pt_mitsuba_options *o, char *err,
                                      size_t err_size)
{
    pt__mts w;
    char file[sizeof d->file];
    int rc, i;
    if (err && err_size) err[0] = '\0';
    if (!d || !path || !*path)
        return pt__sf_failf(err, err_size, "pt_scenefile_export_mitsuba", 0, PT_ERROR_INVALID_ARGUMENT,
                            "the scene is NULL, or the path is NULL or empty");
    if (o && (o->width < 0 || o->height < 0 || o->spp < 0 || o->max_depth < 0 || o->max_depth > 1000000))
        return pt__sf_failf(err, err_size, "pt_scenefile_export_mitsuba", 0, PT_ERROR_INVALID_ARGUMENT,
                            "pt_mitsuba_options: width, height, spp and max_depth must be >= 0 (0: the scene's), "
                            "max_depth at most 1000000");
    memset(&w, 0, sizeof w);
    w.d = d;
    w.width = o && o->width > 0 ? o->width : d->width;
    w.height = o && o->height > 0 ? o->height : d->height;
    w.spp = o && o->spp > 0 ? o->spp : d->samples_per_pixel > 0 ? d->samples_per_pixel : 16;
    w.depth = o && o->max_depth > 0 ? o->max_depth : d->max_depth > 0 ? d->max_depth : 50;
    if (w.width <= 0 || w.height <= 0)
        return pt__sf_failf(err, err_size, d->file, 0, PT_ERROR_INVALID_ARGUMENT, "Mitsuba export: the image size is %d x %d",
                            w.width, w.height);
    if ((rc = pt__mts_refuse(d, w.width, w.height, err, err_size)) != PT_OK) return rc;
    if (!pt__mts_plan(&w)) {
        rc = pt__sf_failf(err, err_size, d->file, 0, PT_ERROR_OUT_OF_MEMORY, "Mitsuba export: out of memory");
        goto done;
    }
    if ((w.ply_count || d->environment.width > 0 || d->image_count > 0) &&
        (rc = pt__mts_base(&w, path, err, err_size)) != PT_OK)
        goto done;
    if (d->environment.width > 0 && !pt__mts_env_map(&w)) {
        rc = pt__sf_failf(err, err_size, d->file, d->environment_line, PT_ERROR_OUT_OF_MEMORY, "Mitsuba export: out of memory");
        goto done;
    }
    memcpy(file, d->file, sizeof file); /* d->file is input: only safe bytes reach a comment */
    file[sizeof file - 1] = '\0';
    pt__mts_comment_text(w.name, sizeof w.name, file);
    pt__mts_clip(&w);
    pt__mts_body(&w); /* w.f == NULL: only checks the numbers */
    for (i = 0; i < w.ply_count; ++i) pt__mts_ply_body(&w, i);
    if (w.bad) {
        rc = pt__sf_failf(err, err_size, d->file, w.bad_line, PT_ERROR_UNSUPPORTED,
                          "Mitsuba export: a number to be written is not finite (nan or inf), or a mesh has no "
                          "triangle with an area in float, or an environment pixel plus the background over its "
                          "scale is not finite");
        goto done;
    }
    rc = pt__mts_write(&w, path, err, err_size);
done:
    PT_FREE(w.used);
    PT_FREE(w.ply);
    pt_image_free(&w.env);
    return rc;
}

#ifdef __cplusplus
}
#endif

#endif /* PDFTRACE_SCENE_IMPLEMENTATION_DONE */
#endif /* PDFTRACE_SCENE_IMPLEMENTATION */

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
