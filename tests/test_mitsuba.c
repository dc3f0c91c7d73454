/* test_mitsuba.c - pdftrace_scene.h's Mitsuba 3 exporter: the numbers it writes (a quad's
   to_world, a box's faces against pdftrace's own normals, a sphere under a transform, the
   settings and their overrides, the point, spot and directional lights), the binary PLY files
   beside the XML, the environment map resampled for Mitsuba's envmap (and, with Mitsuba, its
   envmap against pdftrace's map in 2000 directions), every refusal with its file:line and nothing left behind, write errors,
   hostile file names, the project's scenes; and, with Mitsuba 3 importable, that Mitsuba loads
   and renders the exports without warnings. */
#define _POSIX_C_SOURCE 200809L
#include "test_util.h"
#include "pdftrace_scene.h"
#include "fuzz/mitsuba_check.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define MTS_HEAD "size 8 6\ncamera look_from 0 0 -5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\nmaterial l emitter 4 4 4\n"

static int mts_exists(const char *path) { return access(path, F_OK) == 0; }

/* Parses text as `name` (meshes relative to dir), exports it to path; the export's code, or 1
   when the parse itself failed (err says why). */
static int mts_export(const char *text, const char *name, const char *dir, const char *path,
                      const pt_mitsuba_options *o, char *err, size_t err_size)
{
    pt_scenefile sf;
    int rc = pt_scenefile_parse(text, strlen(text), name, dir, &sf, err, err_size);
    if (rc != PT_OK) return 1;
    rc = pt_scenefile_export_mitsuba(&sf, path, o, err, err_size);
    pt_scenefile_free(&sf);
    return rc;
}

/* Reads n numbers after the first occurrence of `key` at or after `from` (e.g. `<matrix
   value="`); returns where they end, or NULL. */
static const char *mts_numbers(const char *from, const char *key, double *out, int n)
{
    const char *p = from ? strstr(from, key) : NULL;
    int i;
    if (!p) return NULL;
    p += strlen(key);
    for (i = 0; i < n; ++i) {
        char *end;
        while (*p == ' ' || *p == ',') ++p;
        out[i] = strtod(p, &end);
        if (end == p) return NULL;
        p = end;
    }
    return p;
}

/* The text after the comment naming line `line` of scene `name`. */
static const char *mts_at_line(const char *xml, const char *name, int line)
{
    char key[300];
    snprintf(key, sizeof key, "<!-- %s:%d -->", name, line);
    return strstr(xml, key);
}

/* The exported xml of text (NULL on failure, with a CHECK failure recorded). */
static char *mts_xml_of(test_ctx *t, const char *text, const char *dir, const pt_mitsuba_options *o)
{
    char path[600], err[1024], why[256];
    size_t len = 0;
    char *xml;
    int rc;
    snprintf(path, sizeof path, "%s/x.xml", dir);
    rc = mts_export(text, "t.scene", dir, path, o, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "export: %d '%s'", rc, err)) return NULL;
    xml = tu_read_text(path, &len);
    if (!CHECK(t, xml != NULL, "cannot read %s", path)) return NULL;
    CHECK(t, pt_mitsuba_check_text(xml, len, why, sizeof why), "checker: %s", why);
    return xml;
}

/* Compares the rectangle's 12 numbers with columns u/2, v/2, n, Q + u/2 + v/2. */
static void mts_check_rect(test_ctx *t, const double *m, dv3 q, dv3 u, dv3 v, dv3 n, const char *what)
{
    double want[12];
    dv3 c = dadd(q, dadd(dscale(u, 0.5), dscale(v, 0.5)));
    double wc[4][3];
    int i, j;
    wc[0][0] = u.x / 2; wc[0][1] = u.y / 2; wc[0][2] = u.z / 2;
    wc[1][0] = v.x / 2; wc[1][1] = v.y / 2; wc[1][2] = v.z / 2;
    wc[2][0] = n.x; wc[2][1] = n.y; wc[2][2] = n.z;
    wc[3][0] = c.x; wc[3][1] = c.y; wc[3][2] = c.z;
    for (i = 0; i < 3; ++i)
        for (j = 0; j < 4; ++j) want[4 * i + j] = wc[j][i];
    for (i = 0; i < 12; ++i)
        CHECK(t, fabs(m[i] - want[i]) <= 4e-16 * (fabs(want[i]) + 1e-300), "%s: to_world[%d][%d] = %.17g, want %.17g",
              what, i / 4, i % 4, m[i], want[i]);
}

/* A quad's to_world is exact: columns u/2, v/2, the unit normal u x v, the centre; under a
   mirroring scale the normal stays pdftrace's (u and v swapped, as the builder does). */
static void mitsuba_quad_to_world(test_ctx *t)
{
    char dir[64];
    char *xml;
    double m[12];
    dv3 u = dv(0.5, 0, 0.25), v = dv(0, 3, 0);
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    xml = mts_xml_of(t, MTS_HEAD "quad 1 2 3   0.5 0 0.25   0 3 0   l\nscale -1 1 1\nquad 0 0 0  1 0 0  0 1 0  m\n", dir, NULL);
    if (xml) {
        if (CHECK(t, mts_numbers(mts_at_line(xml, "t.scene", 5), "<matrix value=\"", m, 12) != NULL, "no matrix for line 5"))
            mts_check_rect(t, m, dv(1, 2, 3), u, v, dnorm(dcross(u, v)), "quad");
        if (CHECK(t, mts_numbers(mts_at_line(xml, "t.scene", 7), "<matrix value=\"", m, 12) != NULL, "no matrix for line 7"))
            mts_check_rect(t, m, dv(0, 0, 0), dv(0, 1, 0), dv(-1, 0, 0), dv(0, 0, 1), "mirrored quad");
        CHECK(t, strstr(xml, "<emitter type=\"area\"><rgb name=\"radiance\" value=\"4, 4, 4\"/></emitter>") != NULL,
              "the emitter's area light");
        CHECK(t, strstr(xml, "<bsdf type=\"diffuse\" id=\"mat1\"><rgb name=\"reflectance\" value=\"0, 0, 0\"/></bsdf>") != NULL,
              "the emitter's black bsdf");
        CHECK(t, strstr(xml, "<bsdf type=\"twosided\" id=\"mat0\"><bsdf type=\"diffuse\"><rgb name=\"reflectance\" "
                             "value=\"0.5, 0.5, 0.5\"/></bsdf></bsdf>") != NULL, "the Lambertian bsdf");
    }
    free(xml);
    tu_remove_tree(dir);
}

/* Each exported rectangle of a rotated, mirrored box: pdftrace's own hit at its centre, from
   outside along the exported normal, is a front face with the same normal. */
static void mitsuba_box_faces(test_ctx *t)
{
    static const char text[] = MTS_HEAD "rotate 1 2 3 25\nscale 1 -1 1\ntranslate 0.3 0 0\nbox -1 -0.5 -0.25 1 0.5 0.75 m\n";
    char dir[64], err[1024];
    char *xml;
    const char *p;
    pt_scenefile sf;
    pt_scene *s = NULL;
    pt_render_desc rd;
    int faces = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    xml = mts_xml_of(t, text, dir, NULL);
    if (xml && CHECK(t, pt_scenefile_parse(text, strlen(text), "t.scene", NULL, &sf, err, sizeof err) == PT_OK, "%s", err)) {
        if (CHECK(t, pt_scenefile_build(&sf, &s, &rd, err, sizeof err) == PT_OK, "%s", err)) {
            double m[12];
            for (p = xml; (p = mts_numbers(p, "<matrix value=\"", m, 12)) != NULL; ++faces) {
                dv3 n = dv(m[2], m[6], m[10]), c = dv(m[3], m[7], m[11]);
                pt_ray r;
                pt_hit h;
                r.origin = dv_to(dadd(c, dscale(n, 3.0)));
                r.dir = dv_to(dscale(n, -1.0));
                if (CHECK(t, pt_scene_intersect(s, r, 10.0f, &h) == 1, "face %d: no hit", faces))
                    CHECK(t, h.front_face && ddot(dv_from(h.geometric_normal), n) > 0.999999 &&
                                 dlen(dsub(dv_from(h.point), c)) < 1e-4,
                          "face %d: pdftrace's hit at the centre from outside: normal (%g %g %g) front %d, "
                          "exported (%g %g %g)", faces,
                          (double)h.geometric_normal.x, (double)h.geometric_normal.y, (double)h.geometric_normal.z,
                          h.front_face, n.x, n.y, n.z);
            }
            CHECK(t, faces == 6, "%d rectangles for a box", faces);
        }
        pt_scene_destroy(s);
        pt_scenefile_free(&sf);
    }
    free(xml);
    tu_remove_tree(dir);
}

/* A sphere under rotate, scale 2 and translate: centre moved, radius doubled. */
static void mitsuba_sphere_transform(test_ctx *t)
{
    char dir[64];
    char *xml;
    double c[3] = {0, 0, 0}, r[1] = {0};
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    xml = mts_xml_of(t, MTS_HEAD "rotate 0 0 1 90\nscale 2 2 2\ntranslate 1 0 0\nsphere 1 0 0 0.25 m\n", dir, NULL);
    if (xml) {
        const char *p = mts_at_line(xml, "t.scene", 8);
        CHECK(t, mts_numbers(p, "<point name=\"center\" x=\"", c, 1) && mts_numbers(p, "y=\"", c + 1, 1) &&
                     mts_numbers(p, "z=\"", c + 2, 1) && mts_numbers(p, "<float name=\"radius\" value=\"", r, 1),
              "no sphere for line 8");
        CHECK(t, fabs(c[0] - 1) < 1e-6 && fabs(c[1] - 2) < 1e-6 && fabs(c[2]) < 1e-6 && fabs(r[0] - 0.5) < 1e-12,
              "centre (%g %g %g) radius %.17g, want (1 2 0) 0.5", c[0], c[1], c[2], r[0]);
    }
    free(xml);
    tu_remove_tree(dir);
}

/* Settings: max_depth N + 1, the options' overrides, the thin lens, the background. */
static void mitsuba_settings(test_ctx *t)
{
    char dir[64];
    char *xml;
    double v[2] = {0, 0};
    pt_mitsuba_options o;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    xml = mts_xml_of(t, "size 40 30\nspp 9\nmax_depth 7\nseed 12\nbackground 0.25 0.5 1\n"
                        "camera look_from 0 0 -5 look_at 0 0 1 vfov 33 lens_radius 0.125\n"
                        "material m lambertian 0.5 0.5 0.5\nsphere 0 0 0 1 m\n", dir, NULL);
    if (xml) {
        CHECK(t, strstr(xml, "<integer name=\"max_depth\" value=\"8\"/>") != NULL, "max_depth 7 is not written as 8");
        CHECK(t, strstr(xml, "<integer name=\"width\" value=\"40\"/><integer name=\"height\" value=\"30\"/>") != NULL, "size");
        CHECK(t, strstr(xml, "<integer name=\"sample_count\" value=\"9\"/><integer name=\"seed\" value=\"12\"/>") != NULL, "spp, seed");
        CHECK(t, strstr(xml, "<sensor type=\"thinlens\">") && strstr(xml, "<float name=\"fov\" value=\"33\"/>") &&
                     strstr(xml, "<string name=\"fov_axis\" value=\"y\"/>"), "the thin lens sensor");
        CHECK(t, mts_numbers(xml, "<float name=\"aperture_radius\" value=\"", v, 1) && v[0] == 0.125 &&
                     mts_numbers(xml, "<float name=\"focus_distance\" value=\"", v + 1, 1) && v[1] == 6.0,
              "aperture %g, focus %g (want 0.125, 6: |look_at - look_from|)", v[0], v[1]);
        CHECK(t, strstr(xml, "<rfilter type=\"box\"/>") && strstr(xml, "<string name=\"component_format\" value=\"float32\"/>"),
              "box filter, float film");
        CHECK(t, strstr(xml, "<emitter type=\"constant\"><rgb name=\"radiance\" value=\"0.25, 0.5, 1\"/></emitter>") != NULL,
              "the background");
    }
    free(xml);
    memset(&o, 0, sizeof o);
    o.width = 17;
    o.height = 5;
    o.spp = 3;
    o.max_depth = 1;
    xml = mts_xml_of(t, MTS_HEAD "sphere 0 0 0 1 m\n", dir, &o);
    if (xml) {
        CHECK(t, strstr(xml, "<integer name=\"max_depth\" value=\"2\"/>") != NULL, "max_depth override 1: not 2");
        CHECK(t, strstr(xml, "<integer name=\"width\" value=\"17\"/><integer name=\"height\" value=\"5\"/>") != NULL, "size override");
        CHECK(t, strstr(xml, "<integer name=\"sample_count\" value=\"3\"/>") != NULL, "spp override");
        CHECK(t, strstr(xml, "<sensor type=\"perspective\">") && !strstr(xml, "type=\"constant\""), "pinhole, no background");
    }
    free(xml);
    o.spp = -1;
    {
        char err[256];
        int rc = mts_export(MTS_HEAD "sphere 0 0 0 1 m\n", "t.scene", dir, "/nonexistent/x.xml", &o, err, sizeof err);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(err, "pt_mitsuba_options"), "negative spp: %d '%s'", rc, err);
    }
    tu_remove_tree(dir);
}

/* Little-endian float at p. */
static float mts_le_float(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Checks a PLY file: header counts, normals or not, size = header + vertices + faces. Returns
   the file (malloc'd) with *body at the first vertex, or NULL. */
static unsigned char *mts_ply(test_ctx *t, const char *path, long vertices, long faces, int normals, const unsigned char **body)
{
    long size = 0, nv = -1, nf = -1;
    unsigned char *f = tu_read_file(path, &size);
    const char *end;
    if (!CHECK(t, f != NULL, "no PLY file %s", path)) return NULL;
    end = strstr((const char *)f, "end_header\n");
    if (!CHECK(t, end && !strncmp((const char *)f, "ply\nformat binary_little_endian 1.0\n", 36), "%s: not a binary LE PLY", path)) {
        free(f);
        return NULL;
    }
    {
        const char *v = strstr((const char *)f, "element vertex "), *fc = strstr((const char *)f, "element face ");
        if (v) nv = strtol(v + 15, NULL, 10);
        if (fc) nf = strtol(fc + 13, NULL, 10);
    }
    CHECK(t, nv == vertices && nf == faces, "%s: %ld vertices, %ld faces; want %ld, %ld", path, nv, nf, vertices, faces);
    CHECK(t, (strstr((const char *)f, "property float nx\n") != NULL) == normals, "%s: normals %d", path, normals);
    CHECK(t, strstr((const char *)f, "property list uchar uint vertex_indices\n") != NULL, "%s: face list", path);
    *body = (const unsigned char *)end + 11;
    CHECK(t, size == (long)(*body - f) + vertices * (normals ? 24 : 12) + faces * 13, "%s: %ld bytes", path, size);
    return f;
}

/* Meshes and triangles become binary PLY files beside the XML: world-space vertices, normals
   kept (transformed) for a mesh with normals, face_normals otherwise, corners reversed under a
   mirroring transform; an emitting mesh without normals. */
static void mitsuba_ply_files(test_ctx *t)
{
    static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvn 0 0 1\nvn 1 0 0\nf 1//1 2//1 3//1\nf 1//2 3//2 4//2\n";
    char dir[64], path[600], err[1024];
    char *xml = NULL;
    const unsigned char *b;
    unsigned char *f;
    FILE *o;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/m.obj", dir);
    o = fopen(path, "w");
    if (!CHECK(t, o != NULL, "cannot write %s", path)) goto done;
    fputs(obj, o);
    fclose(o);
    xml = mts_xml_of(t, MTS_HEAD "translate 0 0 2\nmesh m.obj m\ntriangle 0 0 0 1 0 0 0 1 0 m\nidentity\n"
                                 "scale -1 1 1\ntriangle 0 0 0 1 0 0 0 1 0 m\nmesh m.obj l\n", dir, NULL);
    if (!xml) goto done;
    snprintf(path, sizeof path, "%s/x.0.ply", dir);
    if ((f = mts_ply(t, path, 6, 2, 1, &b)) != NULL) {
        CHECK(t, mts_le_float(b + 8) == 2.0f && mts_le_float(b + 12) == 0.0f && mts_le_float(b + 20) == 1.0f,
              "first vertex (%g %g %g) normal z %g: want (0 0 2), 1", (double)mts_le_float(b), (double)mts_le_float(b + 4),
              (double)mts_le_float(b + 8), (double)mts_le_float(b + 20));
        CHECK(t, b[6 * 24] == 3 && b[6 * 24 + 5] == 1 && b[6 * 24 + 9] == 2, "first face 0 1 2");
        free(f);
    }
    snprintf(path, sizeof path, "%s/x.1.ply", dir);
    if ((f = mts_ply(t, path, 6, 2, 0, &b)) != NULL) {
        CHECK(t, mts_le_float(b + 12) == 1.0f && mts_le_float(b + 36 + 12) == 0.0f && mts_le_float(b + 36 + 16) == 1.0f,
              "the mirrored triangle's corners a, c, b: second corner (%g %g)", (double)mts_le_float(b + 48),
              (double)mts_le_float(b + 52));
        CHECK(t, mts_le_float(b + 60) == -1.0f, "the mirrored triangle's third corner: x %g, want -1", (double)mts_le_float(b + 60));
        free(f);
    }
    snprintf(path, sizeof path, "%s/x.2.ply", dir);
    if ((f = mts_ply(t, path, 6, 2, 0, &b)) != NULL) {
        CHECK(t, b[6 * 12 + 5] == 2 && b[6 * 12 + 9] == 1, "the mirrored mesh's first face: 0 2 1");
        free(f);
    }
    CHECK(t, strstr(xml, "<shape type=\"ply\"><string name=\"filename\" value=\"x.0.ply\"/><ref id=\"mat0\"/></shape>") != NULL,
          "the mesh with normals");
    CHECK(t, strstr(xml, "value=\"x.1.ply\"/><boolean name=\"face_normals\" value=\"true\"/><ref id=\"mat0\"/>") != NULL,
          "the triangles, with face normals");
    CHECK(t, strstr(xml, "value=\"x.2.ply\"/><boolean name=\"face_normals\" value=\"true\"/><ref id=\"mat1\"/><emitter") != NULL,
          "the emitting mesh, with face normals");
    snprintf(path, sizeof path, "%s/x.3.ply", dir);
    CHECK(t, !mts_exists(path), "one PLY per mesh statement and per material of the triangles: %s", path);
    (void)err;
done:
    free(xml);
    tu_remove_tree(dir);
}

/* What has no exact Mitsuba twin is refused with the statement's file:line and a reason, and
   no file (XML, PLY or temporary) is left. */
static void mitsuba_refusals(test_ctx *t)
{
    static const struct { const char *text; int line; const char *why; } cases[] = {
        {"material f metal 0.9 0.9 0.9 fuzz 0.2\nsphere 0 0 0 1 f\n", 6, "fuzzy metal"},
        {"checker c 1 1 1 0 0 0 0.5\nmaterial k lambertian texture c\ntriangle 0 0 0 1 0 0 0 1 0 m\nsphere 0 0 0 1 k\n", 8,
         "3-D checker"},
        {"material e emitter 1 1 1 two_sided\ntriangle 0 0 0 1 0 0 0 1 0 m\nquad 0 0 0 1 0 0 0 1 0 e\n", 7, "two-sided emitter"},
        {"material w lambertian 1.5 0.5 0.5\nsphere 0 0 0 1 w\n", 6, "albedo above 1"},
        {"material g dielectric 1\nsphere 0 0 0 1 g\n", 6, "ior 1"},
        {"material r roughconductor 0.3 Au tint 1.2 1 1\nsphere 0 0 0 1 r\n", 6, "albedo above 1"},
        {"checker c 0.5 0.5 0.5 0 0 0 0.5\nmaterial p roughplastic 0.2 texture c\ntriangle 0 0 0 1 0 0 0 1 0 m\nsphere 0 0 0 1 p\n",
         8, "3-D checker"},
        {"material g roughdielectric 0.3 1.33 ext_ior 1.33\nsphere 0 0 0 1 g\n", 6, "ior = ext_ior"},
        {"triangle 0 0 0 1 0 0 0 1 0 m\nscale 1 3 1\nsphere 0 0 0 1 m\n", 7, "similarity"},
    };
    char dir[64], path[600], err[1024], list[256];
    size_t i;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/x.xml", dir);
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        char text[1024], want[32];
        int rc;
        snprintf(text, sizeof text, MTS_HEAD "%s", cases[i].text);
        snprintf(want, sizeof want, "r.scene:%d: ", cases[i].line);
        rc = mts_export(text, "r.scene", dir, path, NULL, err, sizeof err);
        CHECK(t, rc < 0 && !strncmp(err, want, strlen(want)) && strstr(err, cases[i].why),
              "case %d: %d '%s' (want '%s...%s')", (int)i, rc, err, want, cases[i].why);
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "case %d left %s", (int)i, list);
    }
    test_note(t, "%d refusals", (int)(sizeof cases / sizeof cases[0]));
    tu_remove_tree(dir);
}

/* Rough conductors: two-sided roughconductor, ggx, sample_visible, alpha, the metal's eta and k from
   pdftrace's table (pt_conductor_ior) or material none, the tint as specular_reflectance; below
   alpha 1e-3 the smooth conductor pdftrace renders. */
static void mitsuba_rough_conductor(test_ctx *t)
{
    char dir[64];
    char *xml;
    const char *p;
    double v[3] = { 0, 0, 0 };
    pt_color eta, k;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    xml = mts_xml_of(t, MTS_HEAD "material a roughconductor 0.25 Au tint 0.9 0.8 0.7\nmaterial b roughconductor 0.5 none\n"
                                 "material c roughconductor 0.0005 eta 1.5 1 0.5 k 3 2 1\n"
                                 "sphere 0 0 0 1 a\nsphere 3 0 0 1 b\nsphere -3 0 0 1 c\n", dir, NULL);
    if (xml) {
        p = strstr(xml, "<bsdf type=\"twosided\" id=\"mat2\"><bsdf type=\"roughconductor\"><string name=\"distribution\" "
                        "value=\"ggx\"/><boolean name=\"sample_visible\" value=\"true\"/><float name=\"alpha\" value=\"0.25\"/>");
        CHECK(t, p != NULL, "material a: no two-sided ggx roughconductor with sample_visible and alpha 0.25");
        CHECK(t, pt_conductor_ior(PT_CONDUCTOR_AU, &eta, &k) == PT_OK, "pt_conductor_ior(AU)");
        CHECK(t, mts_numbers(p, "name=\"eta\" value=\"", v, 3) && (float)v[0] == eta.x && (float)v[1] == eta.y && (float)v[2] == eta.z,
              "material a: eta %g %g %g, want %g %g %g", v[0], v[1], v[2], eta.x, eta.y, eta.z);
        CHECK(t, mts_numbers(p, "name=\"k\" value=\"", v, 3) && (float)v[0] == k.x && (float)v[1] == k.y && (float)v[2] == k.z,
              "material a: k %g %g %g", v[0], v[1], v[2]);
        CHECK(t, mts_numbers(p, "name=\"specular_reflectance\" value=\"", v, 3) && (float)v[0] == 0.9f && (float)v[2] == 0.7f, "material a: tint");
        p = strstr(xml, "id=\"mat3\"");
        CHECK(t, p && strstr(p, "<string name=\"material\" value=\"none\"/>") && strstr(p, "roughconductor") &&
                     strstr(p, "roughconductor") < strstr(p, "</bsdf></bsdf>"), "material b: %.200s", p ? p : "(missing)");
        p = strstr(xml, "id=\"mat4\"");
        CHECK(t, p && !strncmp(p, "id=\"mat4\"><bsdf type=\"conductor\"><rgb name=\"eta\" value=\"1.5, 1, 0.5\"/>", 60),
              "material c (alpha 5e-4, the smooth conductor): %.120s", p ? p : "(missing)");
        free(xml);
    }
    tu_remove_tree(dir);
}

/* Rough plastics: two-sided roughplastic, ggx, sample_visible, alpha (at least 1e-3: the coat
   pdftrace renders), int_ior, ext_ior 1, diffuse_reflectance, nonlinear; no specular_reflectance. */
static void mitsuba_rough_plastic(test_ctx *t)
{
    char dir[64];
    char *xml;
    const char *p, *e;
    double v[3] = { 0, 0, 0 };
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    xml = mts_xml_of(t, MTS_HEAD "material a roughplastic 0.25 0.9 0.8 0.7 ior 1.7 nonlinear\n"
                                 "material b roughplastic 0.0001 0.1 0.2 0.3\nsphere 0 0 0 1 a\nsphere 3 0 0 1 b\n", dir, NULL);
    if (xml) {
        p = strstr(xml, "<bsdf type=\"twosided\" id=\"mat2\"><bsdf type=\"roughplastic\"><string name=\"distribution\" "
                        "value=\"ggx\"/><boolean name=\"sample_visible\" value=\"true\"/><float name=\"alpha\" value=\"0.25\"/>");
        CHECK(t, p != NULL, "material a: no two-sided ggx roughplastic with sample_visible and alpha 0.25");
        e = p ? strstr(p, "</bsdf></bsdf>") : NULL;
        CHECK(t, p && mts_numbers(p, "name=\"int_ior\" value=\"", v, 1) && (float)v[0] == 1.7f, "material a: int_ior %g", v[0]);
        CHECK(t, p && strstr(p, "<float name=\"ext_ior\" value=\"1\"/>") && strstr(p, "<float name=\"ext_ior\" value=\"1\"/>") < e,
              "material a: ext_ior 1");
        CHECK(t, p && mts_numbers(p, "name=\"diffuse_reflectance\" value=\"", v, 3) && (float)v[0] == 0.9f && (float)v[1] == 0.8f &&
                     (float)v[2] == 0.7f, "material a: diffuse_reflectance %g %g %g", v[0], v[1], v[2]);
        CHECK(t, p && strstr(p, "<boolean name=\"nonlinear\" value=\"true\"/>") && strstr(p, "<boolean name=\"nonlinear\" value=\"true\"/>") < e,
              "material a: nonlinear");
        CHECK(t, p && (!strstr(p, "specular_reflectance") || strstr(p, "specular_reflectance") > e), "material a: a specular_reflectance");
        p = strstr(xml, "id=\"mat3\"");
        CHECK(t, p && mts_numbers(p, "name=\"alpha\" value=\"", v, 1) && (float)v[0] == 1e-3f && strstr(p, "value=\"false\""),
              "material b (alpha 1e-4): alpha %g, want 1e-3 and nonlinear false", v[0]);
        free(xml);
    }
    tu_remove_tree(dir);
}

/* Rough dielectrics: one-sided roughdielectric, ggx, sample_visible, alpha, int_ior and ext_ior
   written out (Mitsuba's ext_ior default is air's, not 1); below pdftrace's delta switch (alpha
   < 1e-3, or alpha |eta - 1| < 1e-3) the smooth dielectric (ior = ext_ior: mitsuba_refusals). */
static void mitsuba_rough_dielectric(test_ctx *t)
{
    char dir[64];
    char *xml;
    const char *p;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    xml = mts_xml_of(t, MTS_HEAD "material a roughdielectric 0.25 1.5\nmaterial b roughdielectric 0.5 1.5 ext_ior 1.33\n"
                                 "material c roughdielectric 0.0005 1.7\nmaterial d roughdielectric 0.5 1.001\n"
                                 "sphere 0 0 0 1 a\nsphere 3 0 0 1 b\nsphere -3 0 0 1 c\nsphere 0 3 0 1 d\n", dir, NULL);
    if (xml) {
        p = strstr(xml, "<bsdf type=\"roughdielectric\" id=\"mat2\"><string name=\"distribution\" value=\"ggx\"/><boolean "
                        "name=\"sample_visible\" value=\"true\"/><float name=\"alpha\" value=\"0.25\"/><float name=\"int_ior\" "
                        "value=\"1.5\"/><float name=\"ext_ior\" value=\"1\"/></bsdf>");
        CHECK(t, p != NULL, "material a: no ggx roughdielectric with sample_visible, alpha 0.25, int_ior 1.5, ext_ior 1");
        p = strstr(xml, "id=\"mat3\"");
        CHECK(t, p && strstr(p, "<float name=\"int_ior\" value=\"1.5\"/><float name=\"ext_ior\" value=\"1.33"),
              "material b: %.200s", p ? p : "(missing)");
        CHECK(t, strstr(xml, "<bsdf type=\"dielectric\" id=\"mat4\"><float name=\"int_ior\" value=\"1.7") != NULL,
              "material c (alpha 5e-4): not the smooth dielectric");
        CHECK(t, strstr(xml, "<bsdf type=\"dielectric\" id=\"mat5\"><float name=\"int_ior\" value=\"1.001") != NULL,
              "material d (alpha 0.5, ior 1.001: delta): not the smooth dielectric");
        CHECK(t, strstr(xml, "twosided\" id=\"mat2") == NULL, "material a exported two-sided");
        free(xml);
    }
    tu_remove_tree(dir);
}

/* Point, spot and directional lights in world space, as Mitsuba 3's point, spot and directional
   emitters: the position under a translation and rotation (composed in double), the spot's lookat
   from the position to a point on the axis with an up not parallel to it, its cone (given, and
   the defaults 20 and 15 written out), the directional light's unit travel direction under a
   non-uniform scale (a vector: the scale applies, then it is normalised), the colours as given. */
static void mitsuba_lights(test_ctx *t)
{
    const char *text = MTS_HEAD "sphere 0 0 0 1 m\n"
                                "point_light 1 4 -2  3 2 1\n"                   /* line 6 */
                                "translate 0 1 0\nrotate 0 0 1 90\n"
                                "spot_light 1 0 0  0 0 0  6 5 4  35 10\n"       /* line 9 */
                                "spot_light 0 0 0  0 0 2  1 1 1\n"              /* line 10 */
                                "identity\nscale 2 1 1\n"
                                "directional_light 1 -2 0.5  0.8 0.7 0.6\n";    /* line 13 */
    char dir[64];
    char *xml;
    double v[9];
    const char *at, *p;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    xml = mts_xml_of(t, text, dir, NULL);
    if (!xml) goto done;
    at = mts_at_line(xml, "t.scene", 6);
    if (CHECK(t, at && mts_numbers(at, "<emitter type=\"point\"><point name=\"position\" x=\"", v, 1) &&
                     mts_numbers(at, "y=\"", v + 1, 1) && mts_numbers(at, "z=\"", v + 2, 1), "no point light at line 6")) {
        CHECK(t, v[0] == 1 && v[1] == 4 && v[2] == -2, "point at (%g %g %g)", v[0], v[1], v[2]);
        p = strstr(at, "<rgb name=\"intensity\" value=\"3, 2, 1\"/></emitter>");
        CHECK(t, p && p < strstr(at, "</emitter>") + 1, "the point light's intensity");
    }
    at = mts_at_line(xml, "t.scene", 9);
    if (CHECK(t, at && strncmp(strstr(at, "<emitter"), "<emitter type=\"spot\"><transform name=\"to_world\"><lookat origin=\"", 60) == 0 &&
                     mts_numbers(at, "origin=\"", v, 3) && mts_numbers(at, "target=\"", v + 3, 3) && mts_numbers(at, "up=\"", v + 6, 3),
              "no spot light at line 9")) {
        /* (1, 0, 0) moved up 1, turned 90 degrees about z: (-1, 1, 0); the axis (-1, 0, 0) -> (0, -1, 0) */
        dv3 o = dv(v[0], v[1], v[2]), a = dnorm(dsub(dv(v[3], v[4], v[5]), o)), up = dv(v[6], v[7], v[8]);
        CHECK(t, fabs(o.x + 1) < 1e-15 && fabs(o.y - 1) < 1e-15 && fabs(o.z) < 1e-15, "origin (%.17g %.17g %.17g)", o.x, o.y, o.z);
        CHECK(t, fabs(a.x) < 1e-15 && fabs(a.y + 1) < 1e-15 && fabs(a.z) < 1e-15, "axis (%.17g %.17g %.17g)", a.x, a.y, a.z);
        CHECK(t, dlen(dcross(up, a)) > 0.5, "up (%g %g %g) nearly parallel to the axis", up.x, up.y, up.z);
        CHECK(t, strstr(at, "<rgb name=\"intensity\" value=\"6, 5, 4\"/><float name=\"cutoff_angle\" value=\"35\"/>"
                            "<float name=\"beam_width\" value=\"10\"/></emitter>") != NULL, "the spot's intensity and cone");
    }
    at = mts_at_line(xml, "t.scene", 10);
    if (CHECK(t, at && mts_numbers(at, "origin=\"", v, 3) && mts_numbers(at, "target=\"", v + 3, 3), "no spot light at line 10")) {
        dv3 a = dnorm(dsub(dv(v[3], v[4], v[5]), dv(v[0], v[1], v[2]))); /* (0, 0, 2) turned about z: still +z */
        CHECK(t, fabs(a.x) < 1e-15 && fabs(a.y) < 1e-15 && fabs(a.z - 1) < 1e-15, "axis (%g %g %g)", a.x, a.y, a.z);
        CHECK(t, strstr(at, "<float name=\"cutoff_angle\" value=\"20\"/><float name=\"beam_width\" value=\"15\"/>") != NULL,
              "the default cone");
    }
    at = mts_at_line(xml, "t.scene", 13);
    if (CHECK(t, at && mts_numbers(at, "<emitter type=\"directional\"><vector name=\"direction\" x=\"", v, 1) &&
                     mts_numbers(at, "y=\"", v + 1, 1) && mts_numbers(at, "z=\"", v + 2, 1), "no directional light at line 13")) {
        dv3 want = dnorm(dv(2, -2, 0.5));
        CHECK(t, fabs(v[0] - want.x) < 1e-15 && fabs(v[1] - want.y) < 1e-15 && fabs(v[2] - want.z) < 1e-15,
              "direction (%.17g %.17g %.17g), want (%.17g %.17g %.17g)", v[0], v[1], v[2], want.x, want.y, want.z);
        CHECK(t, strstr(at, "<rgb name=\"irradiance\" value=\"0.800000012, 0.699999988, 0.600000024\"/></emitter>") != NULL,
              "the irradiance");
    }
done:
    free(xml);
    tu_remove_tree(dir);
}

/* A number the build does not check (set through the API) that is not finite is refused, not written. */
static void mitsuba_nonfinite_refused(test_ctx *t)
{
    const char *text = MTS_HEAD "triangle 0 0 0 1 0 0 0 1 0 m\n";
    char dir[64], path[600], err[1024], list[256];
    pt_scenefile sf;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/x.xml", dir);
    if (CHECK(t, pt_scenefile_parse(text, strlen(text), "n.scene", NULL, &sf, err, sizeof err) == PT_OK, "%s", err)) {
        sf.background.y = (float)nan("");
        CHECK(t, pt_scenefile_export_mitsuba(&sf, path, NULL, err, sizeof err) == PT_ERROR_UNSUPPORTED && strstr(err, "not finite"),
              "a nan background: '%s'", err);
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "left %s", list);
        pt_scenefile_free(&sf);
    }
    tu_remove_tree(dir);
}

/* A path that cannot be written: an error naming it, nothing left; when the XML fails after
   the PLY files were written (its name is a directory), the PLY files are removed. */
static void mitsuba_unwritable(test_ctx *t)
{
    const char *text = MTS_HEAD "triangle 0 0 0 1 0 0 0 1 0 m\n";
    char dir[64], path[600], err[1024], list[256];
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/no/such/dir/x.xml", dir);
    rc = mts_export(text, "u.scene", dir, path, NULL, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && strstr(err, "No such file"), "missing directory: %d '%s'", rc, err);
    CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "left %s", list);
    snprintf(path, sizeof path, "%s/d.xml", dir);
    mkdir(path, 0755);
    rc = mts_export(text, "u.scene", dir, path, NULL, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && strstr(err, "d.xml"), "the XML path is a directory: %d '%s'", rc, err);
    CHECK(t, tu_dir_entries(dir, list, sizeof list) == 1, "left %s (want only d.xml)", list);
    tu_remove_tree(dir);
}

/* Hostile names: the scene's name reaches the XML only in comments, without "--"; the output's
   name reaches it only in the PLY file names, entity-escaped, and one the XML cannot name
   exactly is refused when PLY files are needed. */
static void mitsuba_hostile_names(test_ctx *t)
{
    static const char evil_scene[] = "a-->\n<shape type=\"sphere\"/><!--\x01\xc3\xa9.scene";
    const char *tri = MTS_HEAD "triangle 0 0 0 1 0 0 0 1 0 m\n";
    char dir[64], path[700], ply[700], err[1024], why[256], list[256];
    pt_scenefile sf;
    size_t len = 0;
    char *xml;
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/x.xml", dir);
    if (CHECK(t, pt_scenefile_parse(tri, strlen(tri), evil_scene, NULL, &sf, err, sizeof err) == PT_OK, "%s", err)) {
        rc = pt_scenefile_export_mitsuba(&sf, path, NULL, err, sizeof err);
        pt_scenefile_free(&sf);
        xml = rc == PT_OK ? tu_read_text(path, &len) : NULL;
        if (CHECK(t, xml != NULL, "export %d '%s'", rc, err)) {
            CHECK(t, pt_mitsuba_check_text(xml, len, why, sizeof why), "checker: %s", why);
            CHECK(t, strstr(xml, "<shape type=\"sphere\"/>") == NULL, "the name's markup reached the XML");
            CHECK(t, strstr(xml, "a\\x2D\\x2D\\x3E\\x0A\\x3Cshape") != NULL, "the name is not in a comment, escaped");
        }
        free(xml);
    }
    tu_remove_tree(dir);
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/a&b<c'd\" e.xml", dir);
    rc = mts_export(tri, "h.scene", dir, path, NULL, err, sizeof err);
    xml = rc == PT_OK ? tu_read_text(path, &len) : NULL;
    snprintf(ply, sizeof ply, "%s/a&b<c'd\" e.0.ply", dir);
    if (CHECK(t, xml != NULL, "export %d '%s'", rc, err)) {
        CHECK(t, strstr(xml, "value=\"a&amp;b&lt;c&apos;d&quot; e.0.ply\"") != NULL, "the PLY's name is not escaped");
        CHECK(t, pt_mitsuba_check_text(xml, len, why, sizeof why), "checker: %s", why);
        CHECK(t, mts_exists(ply), "no %s", ply);
    }
    free(xml);
    tu_remove_tree(dir);
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/$HOME\xc3\xa9.xml", dir);
    rc = mts_export(tri, "h.scene", dir, path, NULL, err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && !strncmp(err, "h.scene:5: ", 11) && strstr(err, "PLY"), "%d '%s'", rc, err);
    CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "left %s", list);
    rc = mts_export(MTS_HEAD "sphere 0 0 0 1 m\n", "h.scene", dir, path, NULL, err, sizeof err);
    CHECK(t, rc == PT_OK && mts_exists(path), "no PLY needed: the name is fine: %d '%s'", rc, err);
    tu_remove_tree(dir);
}

/* Every scene of scenes/ and bench/scenes/ exports (and passes the checker) or is refused with
   its file:line and the reason. */
static void mitsuba_project_scenes(test_ctx *t)
{
    static const char *const dirs[] = {"scenes", "bench/scenes"};
    char tmp[64], out[600], path[600], err[1024], why[256];
    int exported = 0, refused = 0;
    size_t k;
    if (!CHECK(t, tu_make_tmpdir(tmp, sizeof tmp), "mkdtemp")) return;
    snprintf(out, sizeof out, "%s/s.xml", tmp);
    for (k = 0; k < 2; ++k) {
        DIR *d = opendir(dirs[k]);
        struct dirent *e;
        if (!CHECK(t, d != NULL, "cannot read %s", dirs[k])) continue;
        while ((e = readdir(d)) != NULL) {
            size_t n = strlen(e->d_name), len = 0;
            pt_scenefile sf;
            int rc;
            if (n < 7 || strcmp(e->d_name + n - 6, ".scene")) continue;
            snprintf(path, sizeof path, "%s/%s", dirs[k], e->d_name);
            if (!CHECK(t, pt_scenefile_load(path, &sf, err, sizeof err) == PT_OK, "%s", err)) continue;
            rc = pt_scenefile_export_mitsuba(&sf, out, NULL, err, sizeof err);
            pt_scenefile_free(&sf);
            if (rc == PT_OK) {
                char *xml = tu_read_text(out, &len);
                CHECK(t, xml && pt_mitsuba_check_text(xml, len, why, sizeof why), "%s: %s", path, xml ? why : "no file");
                free(xml);
                ++exported;
            } else {
                CHECK(t, !strncmp(err, path, strlen(path)) && err[strlen(path)] == ':' && strstr(err, "Mitsuba export: "),
                      "%s: refused without file:line and reason: '%s'", path, err);
                CHECK(t, strcmp(e->d_name, "checker.scene") == 0, "%s refused: %s", path, err);
                ++refused;
            }
        }
        closedir(d);
    }
    CHECK(t, exported >= 12, "only %d scenes exported", exported);
    test_note(t, "%d exported, %d refused", exported, refused);
    tu_remove_tree(tmp);
}

/* The Python to try for Mitsuba 3: $PDFTRACE_MITSUBA_PYTHON, else make mitsuba-install's venv
   (build/mitsuba-venv), else python3. */
static const char *mts_python(void)
{
    const char *p = getenv("PDFTRACE_MITSUBA_PYTHON");
    if (p && *p) return p;
    return access("build/mitsuba-venv/bin/python", X_OK) == 0 ? "build/mitsuba-venv/bin/python" : "python3";
}

/* Mitsuba loads and renders exported scenes (scalar_rgb, 1 spp) without a warning or an error. */
static void mitsuba_renders_exports(test_ctx *t)
{
    static const char *const scenes[] = {"scenes/cornell.scene", "scenes/mesh.scene", "scenes/glass.scene",
                                         "bench/scenes/metal-glass.scene", "bench/scenes/sky.scene", "scenes/lights.scene"};
    char dir[64], cmd[2048], out[600], log[600], err[1024];
    size_t i, len = 0;
    if (strchr(mts_python(), '\'')) { test_skip(t, "PDFTRACE_MITSUBA_PYTHON holds a quote"); return; }
    snprintf(cmd, sizeof cmd, "'%s' -c 'import mitsuba' >/dev/null 2>&1", mts_python());
    if (system(cmd) != 0) {
        test_skip(t, "Mitsuba 3 is not importable by %s (make mitsuba-install, or set PDFTRACE_MITSUBA_PYTHON)", mts_python());
        return;
    }
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    for (i = 0; i < sizeof scenes / sizeof scenes[0]; ++i) {
        pt_scenefile sf;
        pt_mitsuba_options o;
        char *text;
        int rc;
        memset(&o, 0, sizeof o);
        o.width = o.height = 8;
        o.spp = 1;
        snprintf(out, sizeof out, "%s/s%d.xml", dir, (int)i);
        snprintf(log, sizeof log, "%s/s%d.log", dir, (int)i);
        if (!CHECK(t, pt_scenefile_load(scenes[i], &sf, err, sizeof err) == PT_OK, "%s", err)) continue;
        rc = pt_scenefile_export_mitsuba(&sf, out, &o, err, sizeof err);
        pt_scenefile_free(&sf);
        if (!CHECK(t, rc == PT_OK, "%s: %s", scenes[i], err)) continue;
        snprintf(cmd, sizeof cmd,
                 "'%s' -c 'import mitsuba as mi, sys; mi.set_variant(\"scalar_rgb\"); "
                 "mi.render(mi.load_file(sys.argv[1]), spp=1)' '%s' >'%s' 2>&1", mts_python(), out, log);
        rc = system(cmd);
        text = tu_read_text(log, &len);
        CHECK(t, rc == 0 && text && !strstr(text, "WARN") && !strstr(text, "rror"), "%s: Mitsuba said: %s", scenes[i],
              text ? text : "(no log)");
        free(text);
    }
    test_note(t, "%d exports rendered by Mitsuba (8x8, 1 spp), no warnings", (int)(sizeof scenes / sizeof scenes[0]));
    tu_remove_tree(dir);
}

/* The map of mitsuba_environment: pixel (x, y) = ((1 + x + 3 y), (2 + x), (7 - y)) / 4. */
static int mts_env_map(const char *dir, int w, int h)
{
    char path[600];
    pt_image img = {0, 0, NULL};
    int x, y, rc;
    if (pt_image_init(&img, w, h) != PT_OK) return 0;
    for (y = 0; y < h; ++y)
        for (x = 0; x < w; ++x) {
            float *p = img.rgb + 3 * (y * w + x);
            p[0] = (float)(1 + x + 3 * y) / 4.0f;
            p[1] = (float)(2 + x) / 4.0f;
            p[2] = (float)(7 - y) / 4.0f;
        }
    snprintf(path, sizeof path, "%s/map.pfm", dir);
    rc = pt_write_pfm(path, &img);
    pt_image_free(&img);
    return rc == PT_OK;
}

/* With Mitsuba importable: its envmap of the export xml, evaluated in 2000 random directions,
   against pdftrace's background + map of the scene text; returns the largest relative
   difference (-1: not run, -2: failed, with why). */
static double mts_env_compare(const char *dir, const char *xml, const char *text, char *why, size_t n)
{
    char path[600], cmd[2048], *out;
    pt_scenefile sf;
    pt_scene *scene = NULL;
    pt_render_desc rd;
    pt_rng rng;
    FILE *f;
    size_t len = 0;
    double worst = -2;
    int k;
    if (strchr(mts_python(), '\'')) return -1;
    snprintf(cmd, sizeof cmd, "'%s' -c 'import mitsuba' >/dev/null 2>&1", mts_python());
    if (system(cmd) != 0) return -1;
    if (pt_scenefile_parse(text, strlen(text), "e.scene", dir, &sf, why, n) != PT_OK) return -2;
    k = pt_scenefile_build(&sf, &scene, &rd, why, n);
    pt_scenefile_free(&sf);
    if (k != PT_OK) return -2;
    snprintf(path, sizeof path, "%s/dirs.txt", dir);
    f = fopen(path, "w");
    pt_rng_seed(&rng, 7u, 1u);
    for (k = 0; f && k < 2000; ++k) {
        dv3 d = tu_rand_dir(&rng);
        pt_color c = pt_scene_environment_radiance(scene, pt_v3((float)d.x, (float)d.y, (float)d.z));
        fprintf(f, "%.9g %.9g %.9g %.9g %.9g %.9g\n", (double)(float)d.x, (double)(float)d.y, (double)(float)d.z,
                (double)(c.x + rd.background.x), (double)(c.y + rd.background.y), (double)(c.z + rd.background.z));
    }
    pt_scene_destroy(scene);
    if (!f || fclose(f) != 0) { snprintf(why, n, "cannot write %.400s", path); return -2; }
    snprintf(path, sizeof path, "%s/cmp.py", dir);
    f = fopen(path, "w");
    if (!f) { snprintf(why, n, "cannot write %.400s", path); return -2; }
    fputs("import sys, mitsuba as mi\nmi.set_variant('scalar_rgb')\n"
          "em = [e for e in mi.load_file(sys.argv[1]).emitters()][0]\nworst = 0.0\n"
          "for line in open(sys.argv[2]):\n    v = [float(x) for x in line.split()]\n"
          "    si = mi.SurfaceInteraction3f()\n    si.wi = mi.Vector3f(-v[0], -v[1], -v[2])\n    c = em.eval(si)\n"
          "    for k in range(3):\n        worst = max(worst, abs(c[k] - v[3 + k]) / v[3 + k])\n"
          "print('worst %.9g' % worst)\n", f);
    fclose(f);
    snprintf(cmd, sizeof cmd, "'%s' '%s/cmp.py' '%s' '%s/dirs.txt' >'%s/cmp.txt' 2>&1", mts_python(), dir, xml, dir, dir);
    k = system(cmd);
    snprintf(path, sizeof path, "%s/cmp.txt", dir);
    out = tu_read_text(path, &len);
    if (k != 0 || !out || !strstr(out, "worst ")) snprintf(why, n, "Mitsuba said: %s", out ? out : "(nothing)");
    else worst = atof(strstr(out, "worst ") + 6);
    free(out);
    return worst;
}

/* The environment statement as Mitsuba's envmap: the XML names "<stem>.env.pfm" with the
   scale and the statement's rotation as to_world, and writes no constant emitter (Mitsuba takes
   one environment emitter: the background goes into the map, divided by the scale); the map
   has 2H + 1 rows, row 2y + 1 pdftrace's row y, row 2y the mean of its rows y - 1 and y, rows 0
   and 2H its first and last (with a background and a rotation, then without). With Mitsuba
   importable, its envmap in 2000 directions equals pdftrace's background + map (to float
   rounding). */
static void mitsuba_environment(test_ctx *t)
{
    char dir[64], xml[600], path[600], text[1024], err[1024], why[512];
    const char *rotated = MTS_HEAD "background 0.1 0.2 0.3\nrotate 1 2 3 40\nenvironment map.pfm 1.5\nsphere 0 0 0 1 m\n";
    pt_transform rot = pt_transform_rotate(pt_normalize(pt_v3(1, 2, 3)), 40.0f);
    pt_image e = {0, 0, NULL};
    double m[12], worst = -2;
    char *x = NULL;
    size_t len = 0;
    int pass, rc, k, y, off = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir) && mts_env_map(dir, 5, 3), "cannot write the map")) return;
    snprintf(xml, sizeof xml, "%s/e.xml", dir);
    snprintf(path, sizeof path, "%s/e.env.pfm", dir);
    for (pass = 0; pass < 2; ++pass) { /* with a background, then without */
        const float add[3] = {pass ? 0.0f : 0.1f / 1.5f, pass ? 0.0f : 0.2f / 1.5f, pass ? 0.0f : 0.3f / 1.5f};
        snprintf(text, sizeof text, "%s", pass ? MTS_HEAD "environment map.pfm\nsphere 0 0 0 1 m\n" : rotated);
        rc = mts_export(text, "e.scene", dir, xml, NULL, err, sizeof err);
        if (!CHECK(t, rc == PT_OK, "export %d: %d '%s'", pass, rc, err)) break;
        x = tu_read_text(xml, &len);
        CHECK(t, x && strstr(x, "<emitter type=\"envmap\"><string name=\"filename\" value=\"e.env.pfm\"/>") &&
                     strstr(x, pass ? "<float name=\"scale\" value=\"1\"/>" : "<float name=\"scale\" value=\"1.5\"/>") &&
                     !strstr(x, "type=\"constant\"") && pt_mitsuba_check_text(x, len, why, sizeof why),
              "pass %d: the envmap element: %s", pass, x ? x : "no XML");
        if (pass == 0 && CHECK(t, x && mts_numbers(strstr(x, "type=\"envmap\""), "<matrix value=\"", m, 12), "no matrix"))
            for (k = 0; k < 12; ++k) /* the scene's floats, written to read back as the same floats */
                off += (float)m[k] != (k % 4 == 3 ? 0.0f : rot.m[k / 4][k % 4]);
        CHECK(t, off == 0, "to_world is not the rotation");
        free(x);
        x = NULL;
        if (!CHECK(t, pt_read_pfm(path, &e, err, sizeof err) == PT_OK && e.width == 5 && e.height == 7, "the map: %s %d x %d",
                   err, e.width, e.height))
            break;
        for (y = 0; y < 7; ++y) /* pdftrace's rows a and b at Mitsuba's row y, then its pixel (3, y) */
            for (k = 0; k < 3; ++k) {
                int a = y % 2 ? (y - 1) / 2 : y / 2 - 1, b = y % 2 ? a : y / 2;
                double va, vb, want, got = e.rgb[3 * (y * 5 + 3) + k];
                a = a < 0 ? 0 : a;
                b = b > 2 ? 2 : b;
                va = k == 0 ? (1 + 3 + 3 * a) / 4.0 : k == 1 ? (2 + 3) / 4.0 : (7 - a) / 4.0;
                vb = k == 0 ? (1 + 3 + 3 * b) / 4.0 : k == 1 ? (2 + 3) / 4.0 : (7 - b) / 4.0;
                want = 0.5 * (va + vb) + add[k];
                if (fabs(got - want) > 1e-6 * want) {
                    CHECK(t, 0, "pass %d: row %d channel %d is %.9g, want %.9g", pass, y, k, got, want);
                    ++off;
                }
            }
        pt_image_free(&e);
        if (pass == 0) worst = off == 0 ? mts_env_compare(dir, xml, rotated, why, sizeof why) : -2;
    }
    if (worst == -1) test_note(t, "rows and XML checked; Mitsuba not importable, its envmap not evaluated");
    else if (CHECK(t, worst >= 0 && worst < 1e-4, "Mitsuba's envmap differs from pdftrace's by %.3g (%s)", worst,
                   worst == -2 ? why : "relative"))
        test_note(t, "Mitsuba's envmap in 2000 directions: largest relative difference %.2g", worst);
    pt_image_free(&e);
    free(x);
    tu_remove_tree(dir);
}

const test_case test_mitsuba_cases[] = {
    TEST_CASE(mitsuba_quad_to_world),
    TEST_CASE(mitsuba_box_faces),
    TEST_CASE(mitsuba_sphere_transform),
    TEST_CASE(mitsuba_settings),
    TEST_CASE(mitsuba_ply_files),
    TEST_CASE(mitsuba_lights),
    TEST_CASE(mitsuba_refusals),
    TEST_CASE(mitsuba_rough_conductor),
    TEST_CASE(mitsuba_rough_plastic),
    TEST_CASE(mitsuba_rough_dielectric),
    TEST_CASE(mitsuba_nonfinite_refused),
    TEST_CASE(mitsuba_unwritable),
    TEST_CASE(mitsuba_hostile_names),
    TEST_CASE(mitsuba_project_scenes),
    TEST_CASE(mitsuba_renders_exports),
    TEST_CASE(mitsuba_environment),
    TEST_END
};
