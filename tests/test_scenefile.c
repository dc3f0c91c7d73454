/* test_scenefile.c - pdftrace_scene.h: pt_obj_load and pt_scene_add_obj against the two-step path
   they replace (read the file, pt_obj_parse, pt_scene_add_mesh), the camera statement's depth of
   field, the guiding and light statements (lights against the same lights added through the
   API, under transforms and far from the origin), the environment statement (its map against
   the file's pixels, its errors, a decoder given in the options), and what an untrusted scene
   file can do: which files it may read (regular files inside its directory), how much memory
   its meshes and its size may take, what its errors echo. The other statements are tested by
   validation/ptv.c's runner and the fuzz corpus. */
#define _POSIX_C_SOURCE 200809L /* mkfifo, symlink, alarm */
#include "test_util.h"
#include "pdftrace_scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MESH_PATH "scenes/mesh.obj"

static void obj_load_matches_parse(test_ctx *t)
{
    pt_obj_mesh a, b;
    char err[512];
    size_t len = 0;
    char *text = tu_read_text(MESH_PATH, &len);
    int ra, rb;
    if (!CHECK(t, text != NULL, "cannot read %s (run from the repository root)", MESH_PATH)) return;
    ra = pt_obj_load(MESH_PATH, &a, err, sizeof err);
    CHECK(t, ra == PT_OK && err[0] == '\0', "pt_obj_load: %d '%s'", ra, err);
    rb = pt_obj_parse(text, len, MESH_PATH, &b, err, sizeof err);
    CHECK(t, rb == PT_OK, "pt_obj_parse: %d '%s'", rb, err);
    if (ra == PT_OK && rb == PT_OK) {
        CHECK(t, a.vertex_count == b.vertex_count && a.triangle_count == b.triangle_count && a.triangle_count > 0,
              "counts %u/%u vertices, %u/%u triangles", a.vertex_count, b.vertex_count, a.triangle_count, b.triangle_count);
        CHECK(t, a.vertex_count == b.vertex_count && !memcmp(a.positions, b.positions, 12u * a.vertex_count) &&
                     !memcmp(a.indices, b.indices, 12u * a.triangle_count) && (a.normals != NULL) == (b.normals != NULL),
              "the loaded mesh differs from the parsed one");
        test_note(t, "%u vertices, %u triangles", a.vertex_count, a.triangle_count);
    }
    pt_obj_mesh_free(&a);
    pt_obj_mesh_free(&b);
    free(text);
}

/* One scene from pt_scene_add_obj, one from the steps it replaces, both under the same transform. */
static void add_obj_one_call(test_ctx *t)
{
    pt_scene *s1 = pt_scene_create(), *s2 = pt_scene_create();
    pt_transform xf = pt_transform_translate(pt_v3(3.0f, -1.0f, 0.5f));
    pt_obj_mesh m;
    pt_mesh_desc md;
    pt_scene_info i1, i2;
    pt_rng rng;
    char err[512] = "x";
    int m1, m2, id1, id2 = -1, k, differ = 0, hits = 0;
    if (!CHECK(t, s1 && s2, "pt_scene_create failed")) goto done;
    m1 = pt_scene_add_lambertian(s1, pt_v3(0.5f, 0.5f, 0.5f));
    m2 = pt_scene_add_lambertian(s2, pt_v3(0.5f, 0.5f, 0.5f));
    pt_scene_set_transform(s1, &xf);
    pt_scene_set_transform(s2, &xf);
    id1 = pt_scene_add_obj(s1, MESH_PATH, m1, err, sizeof err);
    CHECK(t, id1 == 0 && err[0] == '\0', "pt_scene_add_obj: %d '%s'", id1, err);
    if (CHECK(t, pt_obj_load(MESH_PATH, &m, err, sizeof err) == PT_OK, "pt_obj_load: '%s'", err)) {
        memset(&md, 0, sizeof md); /* fields not named below keep their defaults */
        md.positions = m.positions;
        md.vertex_count = m.vertex_count;
        md.indices = m.indices;
        md.triangle_count = m.triangle_count;
        md.normals = m.normals;
        md.material = m2;
        id2 = pt_scene_add_mesh(s2, &md);
        pt_obj_mesh_free(&m);
    }
    if (!CHECK(t, id2 == 0 && pt_scene_commit(s1) == PT_OK && pt_scene_commit(s2) == PT_OK, "building the scenes failed"))
        goto done;
    pt_scene_get_info(s1, &i1);
    pt_scene_get_info(s2, &i2);
    CHECK(t, i1.primitive_count == i2.primitive_count && i1.primitive_count > 0, "primitives %u and %u",
          i1.primitive_count, i2.primitive_count);
    /* Rays from around the transformed mesh's centre: same hits, same distances. */
    pt_rng_seed(&rng, 15u, 1u);
    for (k = 0; k < 2000; ++k) {
        pt_ray r;
        pt_hit h1, h2;
        int a, b;
        dv3 o = tu_rand_dir(&rng), d = tu_rand_dir(&rng);
        r.origin = pt_v3(3.0f + 10.0f * (float)o.x, -1.0f + 10.0f * (float)o.y, 0.5f + 10.0f * (float)o.z);
        r.dir = pt_normalize(pt_sub(pt_v3(3.0f + 0.5f * (float)d.x, -1.0f + 0.5f * (float)d.y, 0.5f + 0.5f * (float)d.z),
                                    r.origin));
        a = pt_scene_intersect(s1, r, 1e30f, &h1);
        b = pt_scene_intersect(s2, r, 1e30f, &h2);
        if (a != b || (a && (h1.t != h2.t || h1.primitive != h2.primitive))) ++differ;
        hits += a != 0;
    }
    CHECK(t, differ == 0 && hits > 0, "%d of 2000 rays differ, %d hit", differ, hits);
    test_note(t, "%u primitives, %d of 2000 rays hit, all identical", i1.primitive_count, hits);
done:
    pt_scene_destroy(s1);
    pt_scene_destroy(s2);
}

static void add_obj_errors(test_ctx *t)
{
    pt_scene *s = pt_scene_create();
    pt_scene_info info;
    char err[512];
    char tmp[64];
    FILE *f;
    int mat, rc;
    snprintf(tmp, sizeof tmp, "build/test-scenefile-nofaces-%ld.obj", (long)getpid()); /* runners run side by side */
    if (!CHECK(t, s != NULL, "pt_scene_create failed")) return;
    mat = pt_scene_add_lambertian(s, pt_v3(0.5f, 0.5f, 0.5f));
    rc = pt_scene_add_obj(s, "scenes/no-such-mesh.obj", mat, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && strstr(err, "scenes/no-such-mesh.obj") && strstr(err, "No such file"),
          "missing file: %d '%s'", rc, err);
    rc = pt_scene_add_obj(s, NULL, mat, err, sizeof err);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(err, "path"), "NULL path: %d '%s'", rc, err);
    rc = pt_scene_add_obj(NULL, MESH_PATH, mat, err, sizeof err);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(err, "scene"), "NULL scene: %d '%s'", rc, err);
    rc = pt_scene_add_obj(s, MESH_PATH, 999, err, sizeof err);
    CHECK(t, rc < 0 && strstr(err, MESH_PATH) && strlen(err) > strlen(MESH_PATH) + 2, "bad material: %d '%s'", rc, err);
    f = fopen(tmp, "w");
    if (CHECK(t, f != NULL, "cannot write %s", tmp)) {
        fputs("v 0 0 0\nv 1 0 0\n", f);
        fclose(f);
        rc = pt_scene_add_obj(s, tmp, mat, err, sizeof err);
        CHECK(t, rc < 0 && strstr(err, tmp) && strstr(err, "no faces"), "no faces: %d '%s'", rc, err);
        remove(tmp);
    }
    /* Nothing was added by the failed calls. */
    CHECK(t, pt_scene_commit(s) == PT_OK, "commit: '%s'", pt_scene_error_message(s));
    pt_scene_get_info(s, &info);
    CHECK(t, info.primitive_count == 0, "%u primitives after failed calls", info.primitive_count);
    pt_scene_destroy(s);
}

#define DOF_SCENE(lens)                                                                               \
    "size 24 16\nspp 4\nmax_depth 3\n"                                                                \
    "camera look_from 0 1 -6 look_at 0 1 0 vfov 40" lens "\n"                                          \
    "material white lambertian 0.7 0.7 0.7\nmaterial lamp emitter 8 8 8\n"                            \
    "quad -5 0 -5 0 0 10 10 0 0 white\nsphere 0 1 0 1 white\nsphere -2 3 4 0.5 lamp\nsphere 1.5 0.5 -3 0.5 white\n"

/* Renders the scene text; returns 1 and fills *img, or records why not. */
static int render_text(test_ctx *t, const char *text, pt_render_desc *rd_out, pt_image *img)
{
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc rd;
    pt_render_stats st;
    char err[512];
    int rc = pt_scenefile_parse(text, strlen(text), "dof.scene", NULL, &sf, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "parse: %s", err)) return 0;
    rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
    pt_scenefile_free(&sf);
    if (!CHECK(t, rc == PT_OK, "build: %s", err)) return 0;
    rd.threads = 1;
    if (rd_out) {
        rd.camera.lens_radius = rd_out->camera.lens_radius;
        rd.camera.focus_distance = rd_out->camera.focus_distance;
    }
    rc = pt_render_image(scene, &rd, img, &st);
    pt_scene_destroy(scene);
    return CHECK(t, rc == PT_OK, "render: %s", st.error);
}

/* The camera statement's lens_radius and focus_distance reach pt_render_desc.camera: the image
   equals one rendered from a pinhole file with the two fields set through the API, and differs
   from the pinhole image. */
static void camera_depth_of_field(test_ctx *t)
{
    pt_scenefile sf;
    pt_render_desc api;
    pt_image lens = {0, 0, NULL}, via_api = {0, 0, NULL}, pinhole = {0, 0, NULL};
    char err[512];
    const char *text = DOF_SCENE(" lens_radius 0.25 focus_distance 4.5");
    int rc = pt_scenefile_parse(text, strlen(text), "dof.scene", NULL, &sf, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "parse: %s", err)) return;
    CHECK(t, sf.camera.lens_radius == 0.25f && sf.camera.focus_distance == 4.5f && sf.camera_line == 4,
          "lens_radius %g, focus_distance %g, line %d", (double)sf.camera.lens_radius,
          (double)sf.camera.focus_distance, sf.camera_line);
    pt_scenefile_free(&sf);
    memset(&api, 0, sizeof api);
    api.camera.lens_radius = 0.25f;
    api.camera.focus_distance = 4.5f;
    if (render_text(t, text, NULL, &lens) && render_text(t, DOF_SCENE(""), &api, &via_api) &&
        render_text(t, DOF_SCENE(""), NULL, &pinhole)) {
        size_t n = 3u * (size_t)lens.width * (size_t)lens.height;
        CHECK(t, !memcmp(lens.rgb, via_api.rgb, n * sizeof(float)), "the file's lens differs from the API's");
        CHECK(t, memcmp(lens.rgb, pinhole.rgb, n * sizeof(float)) != 0, "the lens changed nothing");
    }
    pt_image_free(&lens);
    pt_image_free(&via_api);
    pt_image_free(&pinhole);
}

/* Bad lens values are file:line errors; a thin lens is refused by the POV-Ray export, which then
   writes no file. */
static void camera_depth_of_field_errors(test_ctx *t)
{
    static const struct { const char *lens, *want; } bad[] = {
        {" lens_radius -1", "dof.scene:4: camera lens_radius: must be >= 0"},
        {" focus_distance 0", "dof.scene:4: camera focus_distance: must be > 0"},
        {" focus_distance -2", "dof.scene:4: camera focus_distance: must be > 0"},
        {" lens_radius nan", "dof.scene:4:"},
        {" lens_radius", "dof.scene:4:"},
    };
    char text[1024], err[512];
    char pov[64];
    pt_scenefile sf;
    size_t i;
    int rc;
    snprintf(pov, sizeof pov, "build/test-scenefile-dof-%ld.pov", (long)getpid()); /* runners run side by side */
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(text, sizeof text, "size 24 16\nspp 4\nmax_depth 3\ncamera look_from 0 1 -6 look_at 0 1 0%s\n", bad[i].lens);
        rc = pt_scenefile_parse(text, strlen(text), "dof.scene", NULL, &sf, err, sizeof err);
        CHECK(t, rc != PT_OK && strncmp(err, bad[i].want, strlen(bad[i].want)) == 0, "'%s': %d '%s'", bad[i].lens,
              rc, err);
        if (rc == PT_OK) pt_scenefile_free(&sf);
    }
    rc = pt_scenefile_parse(DOF_SCENE(" lens_radius 0.25"), strlen(DOF_SCENE(" lens_radius 0.25")), "dof.scene", NULL,
                            &sf, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "parse: %s", err)) return;
    remove(pov);
    rc = pt_scenefile_write_pov(&sf, pov, NULL, err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && strstr(err, "dof.scene:4:") && strstr(err, "lens_radius"),
          "POV-Ray export of a thin lens: %d '%s'", rc, err);
    {
        FILE *f = fopen(pov, "r");
        CHECK(t, f == NULL, "the refused export left %s", pov);
        if (f) fclose(f);
    }
    sf.camera.lens_radius = 0.0f;
    rc = pt_scenefile_write_pov(&sf, pov, NULL, err, sizeof err);
    CHECK(t, rc == PT_OK, "POV-Ray export of the pinhole twin: %d '%s'", rc, err);
    remove(pov);
    pt_scenefile_free(&sf);
}

/* Parses text as "t.scene" from base_dir; returns the code, err holds the message. */
static int parse_text(const char *text, const char *base_dir, pt_scenefile *sf, char *err, size_t n)
{
    return pt_scenefile_parse(text, strlen(text), "t.scene", base_dir, sf, err, n);
}
#define T_HEAD "camera look_from 0 0 -5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\n"

/* `integrator scalar|batched` reaches pt_render_desc.integrator through pt_scenefile_build; any
   other word, or none, is a file:line error. */
static void integrator_statement(test_ctx *t)
{
    static const char *const bad[] = {"integrator fast\n", "integrator\n", "integrator batched extra\n"};
    char text[512], err[512];
    pt_scenefile sf;
    pt_scene *s = NULL;
    pt_render_desc rd;
    size_t i;
    int k;
    for (k = 0; k < 2; ++k) {
        snprintf(text, sizeof text, T_HEAD "integrator %s\nsphere 0 0 0 1 m\n", k ? "batched" : "scalar");
        if (!CHECK(t, parse_text(text, NULL, &sf, err, sizeof err) == PT_OK, "parse: %s", err)) continue;
        if (CHECK(t, pt_scenefile_build(&sf, &s, &rd, err, sizeof err) == PT_OK, "build: %s", err)) {
            CHECK(t, rd.integrator == (k ? PT_INTEGRATOR_BATCHED : PT_INTEGRATOR_SCALAR), "integrator %d, want %d",
                  (int)rd.integrator, k ? 2 : 1);
            pt_scene_destroy(s);
        }
        pt_scenefile_free(&sf);
    }
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(text, sizeof text, T_HEAD "%s", bad[i]);
        k = parse_text(text, NULL, &sf, err, sizeof err);
        CHECK(t, k != PT_OK && strncmp(err, "t.scene:3:", 10) == 0 && strstr(err, "integrator"), "'%s': %d '%s'", bad[i],
              k, err);
        if (k == PT_OK) pt_scenefile_free(&sf);
    }
}

/* A bad background is a file:line error at load (its code was overwritten by the end-of-line check). */
static void background_errors_at_load(test_ctx *t)
{
    static const char *const bad[] = {"background 1 1 nan\n", "background -5 -5 -5\n", "background 1 1\n"};
    char text[512], err[512];
    pt_scenefile sf;
    size_t i;
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        int rc;
        snprintf(text, sizeof text, T_HEAD "%ssphere 0 0 0 1 m\n", bad[i]);
        rc = parse_text(text, NULL, &sf, err, sizeof err);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strncmp(err, "t.scene:3: background:", 22) == 0, "'%.*s': %d '%s'",
              (int)strlen(bad[i]) - 1, bad[i], rc, err);
        if (rc == PT_OK) pt_scenefile_free(&sf);
    }
}

/* A UTF-8 byte order mark before the first statement of a scene or an OBJ file is skipped. */
static void byte_order_mark(test_ctx *t)
{
    const char *scene = "\xef\xbb\xbfsize 8 4\n" T_HEAD "sphere 0 0 0 1 m\n";
    const char *obj = "\xef\xbb\xbfv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    char err[512];
    pt_scenefile sf;
    pt_obj_mesh m;
    int rc = parse_text(scene, NULL, &sf, err, sizeof err);
    if (CHECK(t, rc == PT_OK, "scene with a BOM: %d '%s'", rc, err)) {
        CHECK(t, sf.width == 8 && sf.height == 4, "size %d x %d", sf.width, sf.height);
        pt_scenefile_free(&sf);
    }
    rc = pt_obj_parse(obj, strlen(obj), "bom.obj", &m, err, sizeof err);
    CHECK(t, rc == PT_OK && m.triangle_count == 1, "OBJ with a BOM: %d '%s'", rc, err);
    if (rc == PT_OK) pt_obj_mesh_free(&m);
}

/* Control bytes, C1 controls and invalid UTF-8 quoted from a scene line are escaped. */
static void messages_escape_bytes(test_ctx *t)
{
    const char *text = T_HEAD "sph\x1b[2J\x07\xc2\x9b\xff" "ere 0 0 0 1 m \xc3\xa9\n";
    char err[512];
    pt_scenefile sf;
    size_t i;
    int rc = parse_text(text, NULL, &sf, err, sizeof err), raw = 0;
    for (i = 0; err[i]; ++i)
        if ((unsigned char)err[i] < 0x20 || err[i] == 0x7f || (unsigned char)err[i] == 0xff ||
            ((unsigned char)err[i] == 0xc2 && (unsigned char)err[i + 1] == 0x9b))
            raw = 1;
    CHECK(t, rc != PT_OK && !raw && strstr(err, "t.scene:3:") && strstr(err, "sph\\x1b[2J\\x07\\xc2\\x9b\\xffere"),
          "%d, raw bytes %d: '%s'", rc, raw, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
}

/* `size 16384 16384` is refused at its line with the bytes the render would need; a size within
   the limit loads. */
static void size_memory_up_front(test_ctx *t)
{
    char err[512];
    pt_scenefile sf;
    int rc = parse_text("size 16384 16384\n" T_HEAD "sphere 0 0 0 1 m\n", NULL, &sf, err, sizeof err);
    /* 16384^2 pixels x (18 doubles + 1 count + 6 floats) = 46170898432 bytes */
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && strncmp(err, "t.scene:1: size:", 16) == 0 && strstr(err, "46170898432"),
          "%d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
    rc = parse_text("size 4096 4096\n" T_HEAD "sphere 0 0 0 1 m\n", NULL, &sf, err, sizeof err);
    CHECK(t, rc == PT_OK, "4096 x 4096: %d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
}

/* Writes text to dir/name; 1 on success. */
static int write_file(const char *dir, const char *name, const char *text)
{
    char path[512];
    FILE *f;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    f = fopen(path, "w");
    if (!f) return 0;
    fputs(text, f);
    return fclose(f) == 0;
}
#define TRI_OBJ "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"

/* A FIFO as the scene or as a mesh is refused at once (it blocked forever in fopen). An alarm
   ends the runner if a regression blocks again. */
static void fifo_refused(test_ctx *t)
{
    char dir[256], fifo[300], text[512], err[512];
    pt_scenefile sf;
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "no temporary directory")) return;
    snprintf(fifo, sizeof fifo, "%s/pipe", dir);
    if (mkfifo(fifo, 0600) != 0) {
        test_skip(t, "mkfifo failed");
        tu_remove_tree(dir);
        return;
    }
    alarm(20);
    rc = pt_scenefile_load(fifo, &sf, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && strstr(err, fifo) == err && strstr(err, "not a regular file"), "scene FIFO: %d '%s'",
          rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
    snprintf(text, sizeof text, T_HEAD "mesh pipe m\n");
    rc = parse_text(text, dir, &sf, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && strncmp(err, "t.scene:3: mesh:", 16) == 0 && strstr(err, "not a regular file"),
          "mesh FIFO: %d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
    rc = pt_scenefile_load(dir, &sf, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && strstr(err, "not a regular file"), "directory as scene: %d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
    alarm(0);
    tu_remove_tree(dir);
}

/* The message of a mesh statement naming `mesh`, from the scene directory dir. */
static int mesh_message(const char *dir, const char *mesh, char *err, size_t n)
{
    char text[1024];
    pt_scenefile sf;
    int rc;
    snprintf(text, sizeof text, T_HEAD "mesh %s m\n", mesh);
    rc = parse_text(text, dir, &sf, err, n);
    if (rc == PT_OK) pt_scenefile_free(&sf);
    return rc;
}

/* Mesh paths stay inside the scene's directory: `..`, absolute paths and symbolic links that
   lead out are refused before anything is opened, with one message whether the file exists or
   not (the same as for a file missing inside). */
static void mesh_paths_confined(test_ctx *t)
{
    char top[256], dir[300], path[600], err[512], first[512];
    size_t i;
    int rc;
    if (!CHECK(t, tu_make_tmpdir(top, sizeof top), "no temporary directory")) return;
    snprintf(dir, sizeof dir, "%s/scene", top);
    if (!CHECK(t, mkdir(dir, 0700) == 0 && write_file(top, "secret.obj", TRI_OBJ) && write_file(dir, "in.obj", TRI_OBJ),
               "cannot set up %s", top))
        goto done;
    snprintf(path, sizeof path, "%s/secret.obj", top);
    {
        char link[400];
        snprintf(link, sizeof link, "%s/link.obj", dir);
        if (!CHECK(t, symlink(path, link) == 0, "symlink failed")) goto done;
        snprintf(link, sizeof link, "%s/updir", dir);
        if (!CHECK(t, symlink(top, link) == 0, "symlink failed")) goto done;
    }
    rc = mesh_message(dir, "in.obj", err, sizeof err);
    CHECK(t, rc == PT_OK, "in.obj: %d '%s'", rc, err);
    {
        char abs_secret[700], abs_missing[700];
        const char *outside[6];
        snprintf(abs_secret, sizeof abs_secret, "%s/secret.obj", top);
        snprintf(abs_missing, sizeof abs_missing, "%s/missing.obj", top);
        outside[0] = "../secret.obj";
        outside[1] = "../missing.obj";
        outside[2] = abs_secret;
        outside[3] = abs_missing;
        outside[4] = "link.obj";
        outside[5] = "updir/secret.obj";
        for (i = 0; i < 6; ++i) {
            rc = mesh_message(dir, outside[i], err, sizeof err);
            CHECK(t, rc == PT_ERROR_UNSUPPORTED && strncmp(err, "t.scene:3: mesh:", 16) == 0 &&
                         strstr(err, "inside the scene's directory") && strstr(err, outside[i]),
                  "'%s': %d '%s'", outside[i], rc, err);
        }
        rc = mesh_message(dir, "updir/missing.obj", err, sizeof err);
        CHECK(t, rc == PT_ERROR_UNSUPPORTED && strstr(err, "t.scene:3: mesh: no file 'updir/missing.obj' inside"),
              "updir/missing.obj: %d '%s'", rc, err);
        /* the message for an existing file outside equals the one for a missing one, up to the name */
        mesh_message(dir, "../secret.obj", first, sizeof first);
        mesh_message(dir, "../missing.obj", err, sizeof err);
        {
            char *a = strstr(first, "secret"), *b = strstr(err, "missing");
            CHECK(t, a && b && (a - first) == (b - err) && !strcmp(a + 6, b + 7), "'%s' and '%s' differ", first, err);
        }
    }
    rc = mesh_message(dir, "missing.obj", err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && strstr(err, "t.scene:3: mesh: no file 'missing.obj' inside the scene's directory"),
          "missing inside: %d '%s'", rc, err);
    rc = mesh_message(dir, "/etc/shadow", err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && !strstr(err, "root:") && strstr(err, "no file '/etc/shadow' inside"),
          "/etc/shadow: '%s'", err);
done:
    snprintf(path, sizeof path, "%s/updir", dir);
    unlink(path); /* before tu_remove_tree, which follows links to directories */
    tu_remove_tree(top);
}

/* A file that does not start with an OBJ statement is named, never quoted. */
static void obj_contents_not_echoed(test_ctx *t)
{
    const char *shadow = "root:*:19000:0:99999:7:::\ndaemon:*:19000:0:99999:7:::\n";
    const char *later = "v 0 0 0\nsecret-word 1 2 3\n";
    char err[512];
    pt_obj_mesh m;
    int rc = pt_obj_parse(shadow, strlen(shadow), "f.obj", &m, err, sizeof err);
    CHECK(t, rc != PT_OK && strstr(err, "f.obj:1: not an OBJ file") && !strstr(err, "root"), "%d '%s'", rc, err);
    rc = pt_obj_parse(later, strlen(later), "f.obj", &m, err, sizeof err);
    CHECK(t, rc != PT_OK && strstr(err, "f.obj:2:") && !strstr(err, "secret"), "%d '%s'", rc, err);
}

/* Several mesh statements naming one file (under different spellings) parse it once and share it. */
static void mesh_parsed_once(test_ctx *t)
{
    const char *text = T_HEAD "mesh mesh.obj m\ntranslate 1 0 0\nmesh ./mesh.obj m\nmesh mesh.obj m\nmesh ../scenes/mesh.obj m\n";
    char err[512];
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc rd;
    pt_scene_info info;
    int rc = parse_text(text, "scenes", &sf, err, sizeof err), i, same = 1;
    if (!CHECK(t, rc == PT_OK, "%d '%s'", rc, err)) return;
    for (i = 0; i < sf.shape_count; ++i) same &= sf.shapes[i].mesh == 0;
    CHECK(t, sf.mesh_count == 1 && sf.shape_count == 4 && same, "%d meshes parsed for %d mesh statements", sf.mesh_count,
          sf.shape_count);
    rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
    if (CHECK(t, rc == PT_OK, "build: '%s'", err)) {
        pt_scene_get_info(scene, &info);
        CHECK(t, sf.mesh_count == 1 && info.primitive_count == 4u * sf.meshes[0].triangle_count, "%u primitives",
              info.primitive_count);
        test_note(t, "1 parse for 4 statements, %u primitives, %llu mesh bytes", info.primitive_count,
                  (unsigned long long)sf.mesh_bytes);
    }
    pt_scene_destroy(scene);
    pt_scenefile_free(&sf);
}

/* The mesh memory budget: one file shared four times fits where two distinct copies do not;
   the refusal names the statement's file:line and the budget. */
static void mesh_memory_budget(test_ctx *t)
{
    char top[256], err[512], text[1024];
    pt_scenefile_options opt;
    pt_scenefile sf;
    size_t len = 0;
    char *obj = tu_read_text(MESH_PATH, &len);
    int rc;
    if (!CHECK(t, obj != NULL, "cannot read %s", MESH_PATH)) return;
    if (!CHECK(t, tu_make_tmpdir(top, sizeof top) && write_file(top, "a.obj", obj) && write_file(top, "b.obj", obj),
               "cannot write the meshes"))
        goto done;
    memset(&opt, 0, sizeof opt);
    opt.mesh_memory = 500000;
    snprintf(text, sizeof text, T_HEAD "mesh a.obj m\nmesh a.obj m\nmesh a.obj m\nmesh a.obj m\n");
    rc = pt_scenefile_parse_ex(text, strlen(text), "t.scene", top, &opt, &sf, err, sizeof err);
    if (CHECK(t, rc == PT_OK, "one file four times in 500000 bytes: %d '%s'", rc, err)) pt_scenefile_free(&sf);
    snprintf(text, sizeof text, T_HEAD "mesh a.obj m\nmesh b.obj m\n");
    rc = pt_scenefile_parse_ex(text, strlen(text), "t.scene", top, &opt, &sf, err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && strncmp(err, "t.scene:4: mesh: 'b.obj'", 24) == 0 &&
                 strstr(err, "budget of 500000 bytes"), "two files in 500000 bytes: %d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
    opt.mesh_memory = 1000;
    rc = pt_scenefile_parse_ex(text, strlen(text), "t.scene", top, &opt, &sf, err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && strncmp(err, "t.scene:3: mesh: 'a.obj'", 24) == 0 &&
                 strstr(err, "budget of 1000 bytes"), "1000 bytes: %d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
done:
    tu_remove_tree(top);
    free(obj);
}

/* pt_scenefile_options.allowed_dirs lets mesh paths reach another directory, and only that one. */
static void mesh_allowed_dirs(test_ctx *t)
{
    char top[256], dir[300], other[300], err[512];
    const char *allow[1];
    pt_scenefile_options opt;
    pt_scenefile sf;
    const char *text = T_HEAD "mesh ../shared/a.obj m\n";
    const char *text2 = T_HEAD "mesh ../a.obj m\n";
    int rc;
    if (!CHECK(t, tu_make_tmpdir(top, sizeof top), "no temporary directory")) return;
    snprintf(dir, sizeof dir, "%s/scene", top);
    snprintf(other, sizeof other, "%s/shared", top);
    if (!CHECK(t, mkdir(dir, 0700) == 0 && mkdir(other, 0700) == 0 && write_file(other, "a.obj", TRI_OBJ) &&
                      write_file(top, "a.obj", TRI_OBJ), "setup"))
        goto done;
    memset(&opt, 0, sizeof opt);
    rc = pt_scenefile_parse_ex(text, strlen(text), "t.scene", dir, &opt, &sf, err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED, "without allowed_dirs: %d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
    allow[0] = other;
    opt.allowed_dirs = allow;
    opt.allowed_dir_count = 1;
    rc = pt_scenefile_parse_ex(text, strlen(text), "t.scene", dir, &opt, &sf, err, sizeof err);
    if (CHECK(t, rc == PT_OK && sf.mesh_count == 1, "with allowed_dirs: %d '%s'", rc, err)) pt_scenefile_free(&sf);
    rc = pt_scenefile_parse_ex(text2, strlen(text2), "t.scene", dir, &opt, &sf, err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && strstr(err, "or an allowed one"), "a third directory: %d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
done:
    tu_remove_tree(top);
}

/* The sampler a file gets without a `sampler` statement is Sobol (the most efficient measured:
   bench/README.md); the statement still chooses either. */
static void sampler_default(test_ctx *t)
{
    static const struct { const char *line; pt_sampler want; } cases[] = {
        {"", PT_SAMPLER_SOBOL}, {"sampler independent\n", PT_SAMPLER_INDEPENDENT}, {"sampler sobol\n", PT_SAMPLER_SOBOL}};
    char text[512], err[512];
    size_t i;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        pt_scenefile sf;
        pt_scene *scene = NULL;
        pt_render_desc rd;
        int rc;
        snprintf(text, sizeof text, T_HEAD "%ssphere 0 0 0 1 m\n", cases[i].line);
        rc = parse_text(text, NULL, &sf, err, sizeof err);
        if (!CHECK(t, rc == PT_OK, "'%s': %d '%s'", cases[i].line, rc, err)) continue;
        CHECK(t, sf.sampler == cases[i].want, "'%s': read as %d, expected %d", cases[i].line, (int)sf.sampler,
              (int)cases[i].want);
        rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
        if (CHECK(t, rc == PT_OK, "build: %d '%s'", rc, err))
            CHECK(t, rd.sampler == cases[i].want, "'%s': built as %d, expected %d", cases[i].line, (int)rd.sampler,
                  (int)cases[i].want);
        pt_scene_destroy(scene);
        pt_scenefile_free(&sf);
    }
}

/* The guiding statements: read into pt_scenefile and handed to pt_render_desc by the build;
   without them the build's guiding is the file's default (the same as the parsed value, valid);
   bad values are file:line errors naming the statement. */
static void guiding_statements(test_ctx *t)
{
    static const struct { const char *line, *msg; } bad[] = {
        {"guiding sometimes\n", "t.scene:3: guiding: expected off, on or auto, got 'sometimes'"},
        {"guiding\n", "t.scene:3: guiding: expected off, on or auto, got 'nothing'"},
        {"guiding on off\n", "t.scene:3: unexpected 'off' after the end of the 'guiding' statement"},
        {"guiding_budget 1\n", "t.scene:3: guiding_budget: must be in (0, 1), got '1'"},
        {"guiding_budget 0\n", "t.scene:3: guiding_budget: must be in (0, 1), got '0'"},
        {"guiding_budget 0.99999999999\n", "t.scene:3: guiding_budget: must be in (0, 1), got '0.99999999999'"},
        {"guiding_alpha -0.5\n", "t.scene:3: guiding_alpha: must be in (0, 1), got '-0.5'"},
        {"guiding_alpha nan\n", "t.scene:3: guiding_alpha: 'nan' is not finite"},
        {"guiding_memory 0\n", "t.scene:3: guiding_memory: expected an integer in [1, 1048576], got '0'"},
        {"guiding_memory 2.5\n", "t.scene:3: guiding_memory: expected an integer in [1, 1048576], got '2.5'"}};
    char text[512], err[512];
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc rd;
    size_t i;
    int rc = parse_text(T_HEAD "guiding auto\nguiding_budget 0.4\nguiding_alpha 0.3\nguiding_memory 7\nsphere 0 0 0 1 m\n",
                        NULL, &sf, err, sizeof err);
    if (CHECK(t, rc == PT_OK, "the four statements: %d '%s'", rc, err)) {
        CHECK(t, sf.guiding == PT_GUIDING_AUTO && sf.guiding_budget == 0.4f && sf.guiding_alpha == 0.3f &&
                     sf.guiding_memory == 7, "read as %d %g %g %d", (int)sf.guiding, (double)sf.guiding_budget,
              (double)sf.guiding_alpha, sf.guiding_memory);
        rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
        if (CHECK(t, rc == PT_OK, "build: %d '%s'", rc, err))
            CHECK(t, rd.guiding == PT_GUIDING_AUTO && rd.guiding_budget == 0.4f && rd.guiding_alpha == 0.3f &&
                         rd.guiding_max_mib == 7 && rd.guiding_guide == NULL, "built as %d %g %g %d", (int)rd.guiding,
                  (double)rd.guiding_budget, (double)rd.guiding_alpha, rd.guiding_max_mib);
        pt_scene_destroy(scene);
        scene = NULL;
        pt_scenefile_free(&sf);
    }
    rc = parse_text(T_HEAD "sphere 0 0 0 1 m\n", NULL, &sf, err, sizeof err);
    if (CHECK(t, rc == PT_OK, "no guiding statement: %d '%s'", rc, err)) {
        rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
        if (CHECK(t, rc == PT_OK, "build: %d '%s'", rc, err))
            CHECK(t, rd.guiding == sf.guiding && (int)rd.guiding >= (int)PT_GUIDING_OFF &&
                         (int)rd.guiding <= (int)PT_GUIDING_AUTO && rd.guiding_budget == 0.0f &&
                         rd.guiding_alpha == 0.0f && rd.guiding_max_mib == 0,
                  "default: %d (file %d), %g %g %d", (int)rd.guiding, (int)sf.guiding, (double)rd.guiding_budget,
                  (double)rd.guiding_alpha, rd.guiding_max_mib);
        pt_scene_destroy(scene);
        pt_scenefile_free(&sf);
        test_note(t, "without a statement: guiding %d", (int)rd.guiding);
    }
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(text, sizeof text, T_HEAD "%ssphere 0 0 0 1 m\n", bad[i].line);
        rc = parse_text(text, NULL, &sf, err, sizeof err);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strcmp(err, bad[i].msg) == 0, "'%.*s': %d '%s'",
              (int)strlen(bad[i].line) - 1, bad[i].line, rc, err);
        if (rc == PT_OK) pt_scenefile_free(&sf);
    }
}

/* ---- point_light, spot_light, directional_light */

#define L_SCENE_HEAD                                                                                          \
    "size 24 16\nspp 4\nmax_depth 3\ncamera look_from 0 2 -6 look_at 0 0.5 0 vfov 45\n"                        \
    "material white lambertian 0.7 0.7 0.7\nmaterial red lambertian 0.7 0.2 0.2\n"                           \
    "quad -4 0 -4  0 0 8  8 0 0  white\nsphere 0 0.8 0 0.8 red\n"
/* The lights of L_SCENE, line by line (from line 9): a point light, a spot under a translation
   and a rotation, one with the default cone under a scale added to them, a directional light
   under a rotation alone. */
#define L_SCENE                                                                                               \
    L_SCENE_HEAD "point_light 1.5 3 -1  4 5 6\n"                                                               \
    "translate 0.5 0 0\nrotate 0 1 0 30\nspot_light 0 3 0  0 0 1  10 9 8  35 20\n"                             \
    "scale 2 2 2\nspot_light -0.5 1.5 -1  -0.5 0 -1  6 6 6\n"                                                   \
    "identity\nrotate 1 0 0 20\ndirectional_light 0 -1 0  0.5 0.4 0.3\n"

/* Renders a committed scene with the scene file's render settings, one thread. */
static int l_render(test_ctx *t, pt_scene *scene, const pt_render_desc *rd, pt_image *img)
{
    pt_render_desc d = *rd;
    pt_render_stats st;
    int rc;
    d.threads = 1;
    rc = pt_render_image(scene, &d, img, &st);
    return CHECK(t, rc == PT_OK, "render: %s", st.error);
}

/* The three statements read into pt_scenefile (types, lines, the spot's direction target -
   position, its cone with the defaults written out) and built as the same lights added through
   the API under the same transforms: pt_scene_get_light agrees and the images are identical;
   and a light moves with the transform (it is not the untransformed scene's image). */
static void light_statements(test_ctx *t)
{
    pt_scenefile sf;
    pt_scene *file_scene = NULL, *api = NULL;
    pt_render_desc rd;
    pt_image a = {0, 0, NULL}, b = {0, 0, NULL};
    pt_transform x1, x2, x3;
    pt_light_desc l[4], got;
    char err[512];
    int rc, i, white, red;
    rc = parse_text(L_SCENE, NULL, &sf, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "parse: %s", err)) return;
    if (!CHECK(t, sf.light_count == 4 && sf.lights != NULL, "%d lights", sf.light_count)) goto done;
    CHECK(t, sf.lights[0].desc.type == PT_LIGHT_POINT && sf.lights[1].desc.type == PT_LIGHT_SPOT &&
                 sf.lights[2].desc.type == PT_LIGHT_SPOT && sf.lights[3].desc.type == PT_LIGHT_DIRECTIONAL,
          "types %d %d %d %d", (int)sf.lights[0].desc.type, (int)sf.lights[1].desc.type, (int)sf.lights[2].desc.type,
          (int)sf.lights[3].desc.type);
    CHECK(t, sf.lights[0].line == 9 && sf.lights[1].line == 12 && sf.lights[2].line == 14 && sf.lights[3].line == 17,
          "lines %d %d %d %d", sf.lights[0].line, sf.lights[1].line, sf.lights[2].line, sf.lights[3].line);
    CHECK(t, sf.lights[1].desc.direction.x == 0 && sf.lights[1].desc.direction.y == -3 && sf.lights[1].desc.direction.z == 1 &&
                 sf.lights[1].desc.cutoff_angle == 35 && sf.lights[1].desc.beam_width == 20,
          "spot 1: direction (%g %g %g), cone %g %g", (double)sf.lights[1].desc.direction.x,
          (double)sf.lights[1].desc.direction.y, (double)sf.lights[1].desc.direction.z,
          (double)sf.lights[1].desc.cutoff_angle, (double)sf.lights[1].desc.beam_width);
    CHECK(t, sf.lights[2].desc.cutoff_angle == 20 && sf.lights[2].desc.beam_width == 15, "default cone %g %g",
          (double)sf.lights[2].desc.cutoff_angle, (double)sf.lights[2].desc.beam_width);
    CHECK(t, sf.lights[3].desc.intensity.x == 0.5f && sf.lights[3].desc.intensity.z == 0.3f &&
                 sf.lights[3].desc.direction.y == -1, "directional light as read");

    /* the same scene through the API: transforms composed as the parser documents (each one
       applied after those before it) */
    api = pt_scene_create();
    white = pt_scene_add_lambertian(api, pt_v3(0.7f, 0.7f, 0.7f));
    red = pt_scene_add_lambertian(api, pt_v3(0.7f, 0.2f, 0.2f));
    pt_scene_add_quad(api, pt_v3(-4, 0, -4), pt_v3(0, 0, 8), pt_v3(8, 0, 0), white);
    pt_scene_add_sphere(api, pt_v3(0, 0.8f, 0), 0.8f, red);
    memset(l, 0, sizeof l);
    l[0].type = PT_LIGHT_POINT;
    l[0].position = pt_v3(1.5f, 3, -1);
    l[0].intensity = pt_v3(4, 5, 6);
    l[1].type = PT_LIGHT_SPOT;
    l[1].position = pt_v3(0, 3, 0);
    l[1].direction = pt_v3(0, -3, 1);
    l[1].intensity = pt_v3(10, 9, 8);
    l[1].cutoff_angle = 35;
    l[1].beam_width = 20;
    l[2].type = PT_LIGHT_SPOT;
    l[2].position = pt_v3(-0.5f, 1.5f, -1);
    l[2].direction = pt_v3(0, -1.5f, 0);
    l[2].intensity = pt_v3(6, 6, 6);
    l[3].type = PT_LIGHT_DIRECTIONAL;
    l[3].direction = pt_v3(0, -1, 0);
    l[3].intensity = pt_v3(0.5f, 0.4f, 0.3f);
    x1 = pt_transform_mul(pt_transform_rotate(pt_v3(0, 1, 0), 30), pt_transform_translate(pt_v3(0.5f, 0, 0)));
    x2 = pt_transform_mul(pt_transform_scale(pt_v3(2, 2, 2)), x1);
    x3 = pt_transform_rotate(pt_v3(1, 0, 0), 20);
    rc = pt_scene_add_light(api, &l[0]);
    rc = rc >= 0 ? pt_scene_set_transform(api, &x1) : rc;
    rc = rc >= 0 ? pt_scene_add_light(api, &l[1]) : rc;
    rc = rc >= 0 ? pt_scene_set_transform(api, &x2) : rc;
    rc = rc >= 0 ? pt_scene_add_light(api, &l[2]) : rc;
    rc = rc >= 0 ? pt_scene_set_transform(api, &x3) : rc;
    rc = rc >= 0 ? pt_scene_add_light(api, &l[3]) : rc;
    pt_scene_set_transform(api, NULL);
    if (!CHECK(t, rc >= 0 && pt_scene_commit(api) == PT_OK, "API scene: %s", pt_scene_error_message(api))) goto done;
    rc = pt_scenefile_build(&sf, &file_scene, &rd, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "build: %s", err)) goto done;
    for (i = 0; i < 4; ++i) {
        pt_light_desc want;
        if (!CHECK(t, pt_scene_get_light(file_scene, i, &got) == PT_OK && pt_scene_get_light(api, i, &want) == PT_OK,
                   "light %d missing", i))
            continue;
        CHECK(t, !memcmp(&got, &want, sizeof got), "light %d differs from the API's: position (%g %g %g) vs (%g %g %g)",
              i, (double)got.position.x, (double)got.position.y, (double)got.position.z, (double)want.position.x,
              (double)want.position.y, (double)want.position.z);
    }
    /* by hand: translate then rotate 30 degrees about y maps (0, 3, 0) to (0.5 cos 30, 3, -0.5 sin 30)
       (pt_transform_rotate is right-handed: x turns towards -z) */
    if (pt_scene_get_light(file_scene, 1, &got) == PT_OK)
        CHECK(t, fabs(got.position.x - 0.5 * cos(TU_PI / 6)) < 1e-6 && fabs(got.position.y - 3) < 1e-6 &&
                     fabs(got.position.z + 0.5 * sin(TU_PI / 6)) < 1e-6,
              "spot 1 at (%g %g %g)", (double)got.position.x, (double)got.position.y, (double)got.position.z);
    if (pt_scene_get_light(file_scene, 3, &got) == PT_OK) /* (0, -1, 0) turned 20 degrees about x */
        CHECK(t, fabs(got.direction.x) < 1e-6 && fabs(got.direction.y + cos(TU_PI / 9)) < 1e-6 &&
                     fabs(got.direction.z + sin(TU_PI / 9)) < 1e-6,
              "directional light travels along (%g %g %g)", (double)got.direction.x, (double)got.direction.y,
              (double)got.direction.z);
    if (l_render(t, file_scene, &rd, &a) && l_render(t, api, &rd, &b)) {
        size_t n = 3u * (size_t)a.width * (size_t)a.height, k;
        double sum = 0;
        for (k = 0; k < n; ++k) sum += a.rgb[k];
        CHECK(t, !memcmp(a.rgb, b.rgb, n * sizeof(float)), "the file's image differs from the API scene's");
        CHECK(t, sum > 0, "the lights lit nothing");
    }
    pt_image_free(&a);
    pt_image_free(&b);
    pt_scene_destroy(file_scene);
    file_scene = NULL;
    /* without the transforms the lights sit elsewhere: a different image */
    {
        pt_scenefile plain;
        const char *text = L_SCENE_HEAD "point_light 1.5 3 -1  4 5 6\nspot_light 0 3 0  0 0 1  10 9 8  35 20\n"
                                        "spot_light -0.5 1.5 -1  -0.5 0 -1  6 6 6\ndirectional_light 0 -1 0  0.5 0.4 0.3\n";
        rc = parse_text(text, NULL, &plain, err, sizeof err);
        if (CHECK(t, rc == PT_OK, "parse: %s", err)) {
            rc = pt_scenefile_build(&plain, &file_scene, &rd, err, sizeof err);
            if (CHECK(t, rc == PT_OK, "build: %s", err) && l_render(t, file_scene, &rd, &a) && l_render(t, api, &rd, &b))
                CHECK(t, memcmp(a.rgb, b.rgb, 3u * (size_t)a.width * (size_t)a.height * sizeof(float)) != 0,
                      "the transforms changed nothing");
            pt_scenefile_free(&plain);
        }
    }
done:
    pt_image_free(&a);
    pt_image_free(&b);
    pt_scene_destroy(file_scene);
    pt_scene_destroy(api);
    pt_scenefile_free(&sf);
}

/* Every malformed light statement is a file:line error at load naming the statement (and the
   description is left empty); a light the transform carries out of float's range is one at build. */
static void light_statement_errors(test_ctx *t)
{
    static const struct { const char *line, *msg; } bad[] = {
        {"point_light 0 3 0  1 1\n", "t.scene:3: point_light intensity: missing number (line ends early)"},
        {"point_light 0 3\n", "t.scene:3: point_light position: missing number (line ends early)"},
        {"point_light 0 3 0  1 1 1 1\n", "t.scene:3: unexpected '1' after the end of the 'point_light' statement"},
        {"point_light 0 x 0  1 1 1\n", "t.scene:3: point_light position: 'x' is not a number"},
        {"point_light 0 nan 0  1 1 1\n", "t.scene:3: point_light position: 'nan' is not finite"},
        {"point_light 2e7 3 0  1 1 1\n", "t.scene:3: point_light position: 2e7 is out of range (magnitude at most 1e7)"},
        {"point_light 0 3 0  1 -1 1\n", "t.scene:3: point_light intensity: colour components must be >= 0"},
        {"point_light 0 3 0  0 0 0\n", "t.scene:3: point_light intensity: all zero (a light must emit)"},
        {"spot_light 0 3 0  0 0 0\n", "t.scene:3: spot_light intensity: missing number (line ends early)"},
        {"spot_light 0 3 0  0 0\n", "t.scene:3: spot_light target: missing number (line ends early)"},
        {"spot_light 1 2 3  1 2 3  1 1 1\n", "t.scene:3: spot_light: the target equals the position (no direction)"},
        {"spot_light 0 3 0  0 0 0  1 -1 1\n", "t.scene:3: spot_light intensity: colour components must be >= 0"},
        {"spot_light 0 3 0  0 0 0  0 0 0\n", "t.scene:3: spot_light intensity: all zero (a light must emit)"},
        {"spot_light 0 3 0  0 0 0  1 1 1  0\n", "t.scene:3: spot_light cutoff_angle: must be in (0, 90] degrees, got '0'"},
        {"spot_light 0 3 0  0 0 0  1 1 1  -10\n", "t.scene:3: spot_light cutoff_angle: must be in (0, 90] degrees, got '-10'"},
        {"spot_light 0 3 0  0 0 0  1 1 1  90.5\n", "t.scene:3: spot_light cutoff_angle: must be in (0, 90] degrees, got '90.5'"},
        {"spot_light 0 3 0  0 0 0  1 1 1  wide\n", "t.scene:3: spot_light cutoff_angle: 'wide' is not a number"},
        {"spot_light 0 3 0  0 0 0  1 1 1  30 40\n", "t.scene:3: spot_light beam_width: must be in (0, cutoff_angle = 30] degrees, got '40'"},
        {"spot_light 0 3 0  0 0 0  1 1 1  30 0\n", "t.scene:3: spot_light beam_width: must be in (0, cutoff_angle = 30] degrees, got '0'"},
        {"spot_light 0 3 0  0 0 0  1 1 1  30 inf\n", "t.scene:3: spot_light beam_width: 'inf' is not finite"},
        {"spot_light 0 3 0  0 0 0  1 1 1  30 20 5\n", "t.scene:3: unexpected '5' after the end of the 'spot_light' statement"},
        {"directional_light 0 0 0  1 1 1\n", "t.scene:3: directional_light: the direction has zero length"},
        {"directional_light 1e-30 0 0  1 1 1\n", "t.scene:3: directional_light: the direction has zero length"},
        {"directional_light 0 -1 0  1 1\n", "t.scene:3: directional_light irradiance: missing number (line ends early)"},
        {"directional_light 0 -1 0  1 1 -1\n", "t.scene:3: directional_light irradiance: colour components must be >= 0"},
        {"directional_light 0 -1 0  0 0 0\n", "t.scene:3: directional_light irradiance: all zero (a light must emit)"},
        {"directional_light 0 -1 0  1 1 1  1\n", "t.scene:3: unexpected '1' after the end of the 'directional_light' statement"},
        {"directional_light 0 -1\n", "t.scene:3: directional_light direction: missing number (line ends early)"},
        {"point_lights 0 3 0  1 1 1\n", "t.scene:3: unknown statement 'point_lights'"}};
    static const struct { const char *lines, *msg; } build_bad[] = {
        {"scale 1e7 1 1e-6\nscale 1e7 1 1e-6\npoint_light 1e7 0 0  1 1 1\n", "t.scene:6: light: position beyond"},
        {"scale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\n"
         "directional_light 1e7 0 0  1 1 1\n", "t.scene:9: light: direction is zero or overflows"}};
    char text[1024], err[512];
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc rd;
    size_t i;
    int rc;
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        snprintf(text, sizeof text, T_HEAD "%ssphere 0 0 0 1 m\n", bad[i].line);
        memset(&sf, 0x5a, sizeof sf);
        rc = parse_text(text, NULL, &sf, err, sizeof err);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strcmp(err, bad[i].msg) == 0, "'%.*s': %d '%s'",
              (int)strlen(bad[i].line) - 1, bad[i].line, rc, err);
        if (rc == PT_OK) pt_scenefile_free(&sf);
        else CHECK(t, sf.lights == NULL && sf.light_count == 0 && sf.shapes == NULL, "a failed load kept its lights");
    }
    for (i = 0; i < sizeof build_bad / sizeof build_bad[0]; ++i) {
        snprintf(text, sizeof text, T_HEAD "sphere 0 0 0 1 m\n%s", build_bad[i].lines);
        rc = parse_text(text, NULL, &sf, err, sizeof err);
        if (!CHECK(t, rc == PT_OK, "build case %d parse: %s", (int)i, err)) continue;
        rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && scene == NULL && !strncmp(err, build_bad[i].msg, strlen(build_bad[i].msg)),
              "build case %d: %d '%s'", (int)i, rc, err);
        pt_scene_destroy(scene);
        scene = NULL;
        pt_scenefile_free(&sf);
    }
    test_note(t, "%d load errors, %d build errors", (int)(sizeof bad / sizeof bad[0]),
              (int)(sizeof build_bad / sizeof build_bad[0]));
}

/* A scene far from (0, 0, 0) is built relative to its centre (pt_scene_set_origin): its lights
   must move with its shapes. Direct light of a point, a spot and a directional light on a
   floor, moved by 1000 along x (shapes, lights and camera): the image matches the one at the
   origin to float rounding (the same light reaches every pixel; a light left behind would
   leave the floor black or lit from elsewhere). */
static void light_far_origin(test_ctx *t)
{
    static const char near_text[] =
        "size 16 12\nspp 2\nmax_depth 1\ncamera look_from 0 2 -5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\n"
        "quad -3 0 -3  0 0 6  6 0 0  m\npoint_light -1 2 0  4 4 4\nspot_light 1 2 0  1 0 0.5  6 6 6  40 40\n"
        "directional_light 0.3 -1 0.2  0.5 0.5 0.5\n";
    static const char far_text[] =
        "size 16 12\nspp 2\nmax_depth 1\ncamera look_from 1000 2 -5 look_at 1000 0 0\nmaterial m lambertian 0.5 0.5 0.5\n"
        "translate 1000 0 0\nquad -3 0 -3  0 0 6  6 0 0  m\npoint_light -1 2 0  4 4 4\nspot_light 1 2 0  1 0 0.5  6 6 6  40 40\n"
        "directional_light 0.3 -1 0.2  0.5 0.5 0.5\n";
    const char *texts[2] = {near_text, far_text};
    pt_image img[2] = {{0, 0, NULL}, {0, 0, NULL}};
    double worst = 0, total = 0;
    int k;
    for (k = 0; k < 2; ++k) {
        pt_scenefile sf;
        pt_scene *scene = NULL;
        pt_render_desc rd;
        pt_scene_info info;
        char err[512];
        int rc = parse_text(texts[k], NULL, &sf, err, sizeof err);
        if (!CHECK(t, rc == PT_OK, "parse %d: %s", k, err)) goto done;
        rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
        pt_scenefile_free(&sf);
        if (!CHECK(t, rc == PT_OK, "build %d: %s", k, err)) goto done;
        pt_scene_get_info(scene, &info);
        CHECK(t, info.delta_light_count == 3, "scene %d: %u delta lights", k, (unsigned)info.delta_light_count);
        rc = l_render(t, scene, &rd, &img[k]);
        pt_scene_destroy(scene);
        if (!rc) goto done;
    }
    for (k = 0; k < 3 * img[0].width * img[0].height; ++k) {
        double a = img[0].rgb[k], b = img[1].rgb[k];
        total += a;
        if (fabs(a - b) / (a + 1e-3) > worst) worst = fabs(a - b) / (a + 1e-3);
    }
    CHECK(t, total > 0 && worst < 2e-3, "the far scene's image differs by %.2e (relative) from the near one's", worst);
    test_note(t, "largest relative difference %.1e", worst);
done:
    pt_image_free(&img[0]);
    pt_image_free(&img[1]);
}

/* ---- the environment statement */

/* Writes a W x H PFM (little-endian, bottom row first) whose pixel (x, y), row 0 at the top,
   is (1 + x + 10 y, 2 + x, 3 + y) / 8; 1 on success. */
static int env_write_pfm(const char *dir, const char *name, int w, int h)
{
    char path[512];
    FILE *f;
    int x, y, ok;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    f = fopen(path, "wb");
    if (!f) return 0;
    ok = fprintf(f, "PF\n%d %d\n-1.0\n", w, h) > 0;
    for (y = h - 1; y >= 0 && ok; --y)
        for (x = 0; x < w && ok; ++x) {
            float v[3];
            unsigned char b[12];
            int c, k;
            v[0] = (float)(1 + x + 10 * y) / 8.0f;
            v[1] = (float)(2 + x) / 8.0f;
            v[2] = (float)(3 + y) / 8.0f;
            for (c = 0; c < 3; ++c) {
                uint32_t u;
                memcpy(&u, &v[c], 4);
                for (k = 0; k < 4; ++k) b[4 * c + k] = (unsigned char)(u >> (8 * k));
            }
            ok = fwrite(b, 1, 12, f) == 12;
        }
    return fclose(f) == 0 && ok;
}

/* The direction, in the map's own frame, of the centre of pixel (x, y) of a W x H map. */
static pt_vec3 env_pixel_dir(int x, int y, int w, int h)
{
    double u = (x + 0.5) / w, v = (y + 0.5) / h, th = 3.14159265358979323846 * v, ph = 2.0 * 3.14159265358979323846 * u;
    return pt_v3((float)(sin(th) * sin(ph)), (float)cos(th), (float)(-sin(th) * cos(ph)));
}

/* `environment FILE SCALE` under a rotation: the map is read (its pixels as written, row 0 the
   zenith), the scale and the line are kept, and the built scene's map, at each pixel centre
   turned by the rotation, is the pixel times the scale; a grey `Pf` file and big-endian data
   (positive scale) read the same; the background stays the render's. */
static void environment_statement(test_ctx *t)
{
    char dir[256], err[512];
    const char *text = T_HEAD "background 0.1 0.2 0.3\nrotate 1 2 3 40\nenvironment map.pfm 1.5\nsphere 0 0 0 1 m\n";
    pt_transform rot = pt_transform_rotate(pt_normalize(pt_v3(1, 2, 3)), 40.0f);
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc rd;
    pt_scene_info info;
    int rc, x, y, off = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir) && env_write_pfm(dir, "map.pfm", 6, 3), "cannot write the map")) return;
    rc = parse_text(text, dir, &sf, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "parse: %d '%s'", rc, err)) goto done;
    CHECK(t, sf.environment.width == 6 && sf.environment.height == 3 && sf.environment_scale == 1.5f &&
                 sf.environment_line == 5, "map %d x %d, scale %g, line %d", sf.environment.width, sf.environment.height,
          (double)sf.environment_scale, sf.environment_line);
    CHECK(t, sf.environment.rgb && sf.environment.rgb[0] == 1.0f / 8 && sf.environment.rgb[3 * (2 * 6 + 5) + 1] == 7.0f / 8,
          "pixels (0, 0) R %g and (5, 2) G %g", sf.environment.rgb ? (double)sf.environment.rgb[0] : -1.0,
          sf.environment.rgb ? (double)sf.environment.rgb[3 * (2 * 6 + 5) + 1] : -1.0);
    rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
    pt_scenefile_free(&sf);
    if (!CHECK(t, rc == PT_OK, "build: %d '%s'", rc, err)) goto done;
    pt_scene_get_info(scene, &info);
    CHECK(t, info.environment_width == 6 && info.environment_height == 3 && (info.features & PT_FEATURE_ENVIRONMENT),
          "the scene's map is %d x %d", info.environment_width, info.environment_height);
    CHECK(t, rd.background.x == 0.1f && rd.background.z == 0.3f, "background %g %g %g", (double)rd.background.x,
          (double)rd.background.y, (double)rd.background.z);
    for (y = 0; y < 3; ++y)
        for (x = 0; x < 6; ++x) {
            pt_color c = pt_scene_environment_radiance(scene, pt_transform_vector(&rot, env_pixel_dir(x, y, 6, 3)));
            double want[3];
            want[0] = 1.5 * (1 + x + 10 * y) / 8.0;
            want[1] = 1.5 * (2 + x) / 8.0;
            want[2] = 1.5 * (3 + y) / 8.0;
            off += fabs(c.x - want[0]) > 1e-4 * want[0] || fabs(c.y - want[1]) > 1e-4 * want[1] ||
                   fabs(c.z - want[2]) > 1e-4 * want[2];
        }
    CHECK(t, off == 0, "%d of 18 pixel centres differ from scale x pixel", off);
    test_note(t, "6 x 3 map under a rotation: 18 pixel centres = 1.5 x pixel");
done:
    pt_scene_destroy(scene);
    tu_remove_tree(dir);
}

/* Grey ("Pf") and big-endian (positive scale) PFM maps read as the RGB little-endian one would. */
static void environment_pfm_forms(test_ctx *t)
{
    static const unsigned char grey_be[] = {'P', 'f', '\n', '2', ' ', '2', '\n', '1', '.', '0', '\n',
                                            0x3f, 0x80, 0, 0, 0x40, 0, 0, 0, 0x40, 0x40, 0, 0, 0x40, 0x80, 0, 0};
    char dir[256], path[400], err[512];
    pt_scenefile sf;
    FILE *f;
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "no temporary directory")) return;
    snprintf(path, sizeof path, "%s/g.pfm", dir);
    f = fopen(path, "wb");
    if (!CHECK(t, f && fwrite(grey_be, 1, sizeof grey_be, f) == sizeof grey_be && fclose(f) == 0, "cannot write %s", path))
        goto done;
    rc = parse_text(T_HEAD "environment g.pfm\nsphere 0 0 0 1 m\n", dir, &sf, err, sizeof err);
    if (CHECK(t, rc == PT_OK, "%d '%s'", rc, err)) {
        const float *p = sf.environment.rgb; /* the file's first row (1, 2) is the bottom one */
        CHECK(t, sf.environment.width == 2 && sf.environment.height == 2 && p[0] == 3 && p[1] == 3 && p[2] == 3 &&
                     p[3] == 4 && p[6] == 1 && p[9] == 2 && sf.environment_scale == 1.0f,
              "read %g %g / %g %g, scale %g", (double)p[0], (double)p[3], (double)p[6], (double)p[9],
              (double)sf.environment_scale);
        pt_scenefile_free(&sf);
    }
done:
    tu_remove_tree(dir);
}

/* The statement's errors, each "t.scene:LINE: ..." (at load, or for a transform that is not a
   rotation and a bad pixel at build), and a map path confined as a mesh's. */
static void environment_errors(test_ctx *t)
{
    static const struct { const char *text, *want; int build; } bad[] = {
        {"environment missing.pfm\n", "t.scene:3: environment: no file 'missing.pfm' inside the scene's directory", 0},
        {"environment text.pfm\n", "t.scene:3: environment: ", 0},
        {"environment short.pfm\n", "t.scene:3: environment: ", 0},
        {"environment map.pfm 0\n", "t.scene:3: environment scale: must be > 0, got '0'", 0},
        {"environment map.pfm -1\n", "t.scene:3: environment scale: must be > 0, got '-1'", 0},
        {"environment map.pfm nan\n", "t.scene:3: environment scale: 'nan' is not finite", 0},
        {"environment map.pfm 1 2\n", "t.scene:3: unexpected '2' after the end of the 'environment' statement", 0},
        {"environment\n", "t.scene:3: environment: missing image file name", 0},
        {"environment map.pfm\nenvironment map.pfm\n", "t.scene:4: environment: a second map (the first is at line 3", 0},
        {"environment map.exr\n", "t.scene:3: environment: 'map.exr': this program was built without OpenEXR", 0},
        {"environment map.hdr\n", "t.scene:3: environment: 'map.hdr': not a .pfm file", 0},
        {"environment ../map.pfm\n", "t.scene:3: environment: no file '../map.pfm' inside the scene's directory", 0},
        {"environment /etc/passwd\n", "t.scene:3: environment: '/etc/passwd': not a .pfm file", 0},
        {"scale 1 2 1\nenvironment map.pfm\n", "t.scene:4: environment: the scene's current transform is not a rotation", 1},
        {"scale -1 1 1\nenvironment map.pfm\n", "t.scene:4: environment: the scene's current transform is not a rotation", 1},
        {"environment neg.pfm\n", "t.scene:3: environment: map pixel (", 1},
    };
    static const unsigned char neg[] = {'P', 'f', '\n', '2', ' ', '2', '\n', '-', '1', '\n',
                                        0, 0, 0x80, 0x3f, 0, 0, 0x80, 0xbf, 0, 0, 0x80, 0x3f, 0, 0, 0x80, 0x3f};
    char top[256], dir[300], text[1024], err[512], path[400];
    size_t i;
    FILE *f;
    if (!CHECK(t, tu_make_tmpdir(top, sizeof top), "no temporary directory")) return;
    snprintf(dir, sizeof dir, "%s/scene", top);
    snprintf(path, sizeof path, "%s/neg.pfm", dir);
    if (!CHECK(t, mkdir(dir, 0700) == 0 && env_write_pfm(dir, "map.pfm", 4, 2) && env_write_pfm(top, "map.pfm", 4, 2) &&
                      write_file(dir, "text.pfm", "secret text\n") && write_file(dir, "short.pfm", "PF\n4 2\n-1\nxyz"),
               "setup"))
        goto done;
    f = fopen(path, "wb");
    if (!CHECK(t, f && fwrite(neg, 1, sizeof neg, f) == sizeof neg && fclose(f) == 0, "cannot write %s", path)) goto done;
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        pt_scenefile sf;
        pt_scene *scene = NULL;
        pt_render_desc rd;
        int rc;
        snprintf(text, sizeof text, T_HEAD "%sidentity\nsphere 0 0 0 1 m\n", bad[i].text);
        rc = parse_text(text, dir, &sf, err, sizeof err);
        if (bad[i].build && CHECK(t, rc == PT_OK, "'%s' should load: '%s'", bad[i].text, err)) {
            rc = pt_scenefile_build(&sf, &scene, &rd, err, sizeof err);
            CHECK(t, scene == NULL, "a refused build left a scene");
            pt_scenefile_free(&sf);
        } else if (rc == PT_OK)
            pt_scenefile_free(&sf);
        CHECK(t, rc < 0 && strncmp(err, bad[i].want, strlen(bad[i].want)) == 0 && !strstr(err, "secret"),
              "'%.*s': %d '%s'", (int)strlen(bad[i].text) - 1, bad[i].text, rc, err);
    }
    test_note(t, "%d bad statements, each with its file:line", (int)(sizeof bad / sizeof bad[0]));
done:
    tu_remove_tree(top);
}

/* A decoder (pt_scenefile_options.read_image) reads every map that is not .pfm: it gets the
   file's bytes and its name, and its message is reported at the statement's file:line. */
static int env_fake_calls;
static int env_fake_reader(const void *data, size_t size, const char *name, pt_image *out, char *err, size_t err_size)
{
    ++env_fake_calls;
    if (size >= 4 && !memcmp(data, "good", 4) && strstr(name, "/a.exr") && pt_image_init(out, 4, 2) == PT_OK) {
        size_t k;
        for (k = 0; k < 24; ++k) out->rgb[k] = 0.25f;
        return PT_OK;
    }
    snprintf(err, err_size, "%s: not an image the fake reader knows", name);
    return PT_ERROR_IO;
}
static void environment_reader_hook(test_ctx *t)
{
    char dir[256], err[512];
    pt_scenefile_options opt;
    pt_scenefile sf;
    const char *good = T_HEAD "environment a.exr 2\nsphere 0 0 0 1 m\n", *bad = T_HEAD "environment b.exr\nsphere 0 0 0 1 m\n";
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir) && write_file(dir, "a.exr", "good bytes") && write_file(dir, "b.exr", "bad"),
               "setup"))
        return;
    memset(&opt, 0, sizeof opt);
    opt.read_image = env_fake_reader;
    env_fake_calls = 0;
    rc = pt_scenefile_parse_ex(good, strlen(good), "t.scene", dir, &opt, &sf, err, sizeof err);
    if (CHECK(t, rc == PT_OK && env_fake_calls == 1, "%d calls: %d '%s'", env_fake_calls, rc, err)) {
        CHECK(t, sf.environment.width == 4 && sf.environment.rgb[23] == 0.25f && sf.environment_scale == 2.0f,
              "the reader's image was not kept");
        pt_scenefile_free(&sf);
    }
    rc = pt_scenefile_parse_ex(bad, strlen(bad), "t.scene", dir, &opt, &sf, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && !strncmp(err, "t.scene:3: environment: ", 24) && strstr(err, "not an image the fake reader"),
          "%d '%s'", rc, err);
    if (rc == PT_OK) pt_scenefile_free(&sf);
    tu_remove_tree(dir);
}

const test_case test_scenefile_cases[] = {
    TEST_CASE(obj_load_matches_parse),
    TEST_CASE(add_obj_one_call),
    TEST_CASE(add_obj_errors),
    TEST_CASE(camera_depth_of_field),
    TEST_CASE(camera_depth_of_field_errors),
    TEST_CASE(integrator_statement),
    TEST_CASE(background_errors_at_load),
    TEST_CASE(byte_order_mark),
    TEST_CASE(messages_escape_bytes),
    TEST_CASE(size_memory_up_front),
    TEST_CASE(fifo_refused),
    TEST_CASE(mesh_paths_confined),
    TEST_CASE(obj_contents_not_echoed),
    TEST_CASE(mesh_parsed_once),
    TEST_CASE(mesh_memory_budget),
    TEST_CASE(mesh_allowed_dirs),
    TEST_CASE(guiding_statements),
    TEST_CASE(sampler_default),
    TEST_CASE(light_statements),
    TEST_CASE(light_statement_errors),
    TEST_CASE(light_far_origin),
    TEST_CASE(environment_statement),
    TEST_CASE(environment_pfm_forms),
    TEST_CASE(environment_errors),
    TEST_CASE(environment_reader_hook),
    TEST_END
};
