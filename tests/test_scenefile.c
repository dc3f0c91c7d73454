/* test_scenefile.c - pdftrace_scene.h: pt_obj_load and pt_scene_add_obj against the two-step path
   they replace (read the file, pt_obj_parse, pt_scene_add_mesh), and the camera statement's
   depth of field. The other statements are tested by validation/ptv.c's runner and the fuzz corpus. */
#include "test_util.h"
#include "pdftrace_scene.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MESH_PATH "scenes/mesh.obj"

/* The whole file at path, NUL-terminated, or NULL. */
static char *read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    char *buf;
    long n;
    if (!f) return NULL;
    if (fseek(f, 0, SEEK_END) != 0 || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) { fclose(f); return NULL; }
    buf = (char *)malloc((size_t)n + 1u);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) { free(buf); buf = NULL; }
    fclose(f);
    if (buf) { buf[n] = '\0'; *len = (size_t)n; }
    return buf;
}

static void obj_load_matches_parse(test_ctx *t)
{
    pt_obj_mesh a, b;
    char err[512];
    size_t len = 0;
    char *text = read_all(MESH_PATH, &len);
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
    const char *tmp = "build/test-scenefile-nofaces.obj";
    FILE *f;
    int mat, rc;
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
    const char *pov = "build/test-scenefile-dof.pov";
    pt_scenefile sf;
    size_t i;
    int rc;
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

const test_case test_scenefile_cases[] = {
    TEST_CASE(obj_load_matches_parse),
    TEST_CASE(add_obj_one_call),
    TEST_CASE(add_obj_errors),
    TEST_CASE(camera_depth_of_field),
    TEST_CASE(camera_depth_of_field_errors),
    TEST_END
};
