/* test_pov.c - pdftrace_scene.h's POV-Ray exporter against hostile and extreme scenes: text
   from the scene never reaches the .pov unescaped, every number written is finite, every scene
   the build refuses is refused; and the output checker of the fuzz target (tests/fuzz/pov_check.h)
   rejects bad text; the point, hard-cone spot and directional lights as the recipe has them, and
   the soft spot and an environment map refused. With povray installed, exported scenes are
   rendered at a tiny size. */
#define _POSIX_C_SOURCE 200809L
#include "test_util.h"
#include "pdftrace_scene.h"
#include "fuzz/pov_check.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define POV_HEAD "size 8 8\ncamera look_from 0 0 -5 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\nmaterial l emitter 4 4 4\n"

static int pov_exists(const char *path) { return access(path, F_OK) == 0; }

static int have_povray(void) { return system("povray --version >/dev/null 2>&1") == 0; }

/* Renders pov at W x H in dir (its working directory); 1 when povray succeeded. */
static int pov_render(const char *dir, const char *pov, int w, int h)
{
    char cmd[4096];
    int n = snprintf(cmd, sizeof cmd, "cd '%s' && povray '+I%s' +Oout.png +FN +W%d +H%d -D -V >povray.log 2>&1", dir, pov, w, h);
    return n > 0 && (size_t)n < sizeof cmd && system(cmd) == 0;
}

/* build/test-pov-PID followed by suffix: the runners of make test run side by side, each with its
   own files. Returns a static buffer (one of four, used round robin). */
static const char *pov_path(const char *suffix)
{
    static char buf[4][64];
    static int next;
    char *b = buf[next];
    next = (next + 1) % 4;
    snprintf(b, sizeof buf[0], "build/test-pov-%ld%s", (long)getpid(), suffix);
    return b;
}

/* Parses text as name, exports it to pov_path(".pov"); returns the export's code. */
static int pov_export_text(const char *text, const char *name, char *err, size_t err_size)
{
    pt_scenefile sf;
    int rc = pt_scenefile_parse(text, strlen(text), name, NULL, &sf, err, err_size);
    if (rc != PT_OK) return 1; /* not a PT_ code: the parse itself failed */
    remove(pov_path(".pov"));
    rc = pt_scenefile_write_pov(&sf, pov_path(".pov"), NULL, err, err_size);
    pt_scenefile_free(&sf);
    return rc;
}

/* A newline in the scene path must not end a POV-Ray comment (the path's next line would run as
   POV-Ray code: #fopen ... #write creates a file when the .pov is rendered). */
static void pov_path_injection(test_ctx *t)
{
    static const char payload[] = "x\n#fopen F \"pwned.txt\" write #write(F,\"x\\n\") #fclose F\n";
    char dir[256], sub[512], scene[640], pov[300], run[300], pwned[320], err[1024], why[256];
    pt_scenefile sf;
    FILE *f;
    size_t len = 0;
    char *text;
    int rc;
    snprintf(dir, sizeof dir, "build/test-pov-inject-%ld", (long)getpid());
    snprintf(sub, sizeof sub, "%s/%s", dir, payload);
    snprintf(scene, sizeof scene, "%s/s.scene", sub);
    snprintf(pov, sizeof pov, "%s/out.pov", dir);
    snprintf(run, sizeof run, "%s/run", dir);
    snprintf(pwned, sizeof pwned, "%s/pwned.txt", run);
    mkdir(dir, 0755);
    mkdir(sub, 0755);
    mkdir(run, 0755);
    f = fopen(scene, "w");
    if (!CHECK(t, f != NULL, "cannot create %s", scene)) return;
    fputs(POV_HEAD "sphere 0 0 0 1 m\nquad -1 3 -1 2 0 0 0 0 2 l\n", f);
    fclose(f);
    rc = pt_scenefile_load(scene, &sf, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "load: %s", err)) return;
    rc = pt_scenefile_write_pov(&sf, pov, NULL, err, sizeof err);
    pt_scenefile_free(&sf);
    if (!CHECK(t, rc == PT_OK, "export: %d %s", rc, err)) return;
    text = tu_read_text(pov, &len);
    if (!CHECK(t, text != NULL, "cannot read %s", pov)) return;
    CHECK(t, strstr(text, "\n#fopen") == NULL && strstr(text, "\n#write") == NULL, "the path's #fopen line reached the .pov");
    CHECK(t, strstr(text, "\"pwned.txt\"") == NULL, "a string from the path reached the .pov");
    CHECK(t, strstr(text, "\\x0A\\x23fopen F \\x22pwned.txt\\x22 write") != NULL, "the path is not in the comment, escaped");
    CHECK(t, pt_pov_check_text(text, len, why, sizeof why), "checker: %s", why);
    free(text);
    if (!have_povray()) {
        test_note(t, "povray not installed: render not tried");
    } else {
        char rel[300];
        snprintf(rel, sizeof rel, "../out.pov");
        CHECK(t, pov_render(run, rel, 1, 1), "povray failed on the export (see %s/povray.log)", run);
        if (CHECK(t, !pov_exists(pwned), "rendering the export created %s", pwned))
            test_note(t, "rendered by povray at 1x1; no pwned.txt");
    }
    remove(pwned);
    remove(scene);
}

/* The exporter wrote nan/inf (a light at <-nan, -inf, -nan>, fade_distance inf) for a scene
   the build refuses: it must refuse it, with file:line, and write nothing. */
static void pov_nonfinite_refused(test_ctx *t)
{
    const char *text = POV_HEAD "scale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\n"
                                "scale 1e7 1 1e-6\nsphere 0 0 0 1 l\n";
    char err[1024];
    int rc = pov_export_text(text, "inf.scene", err, sizeof err);
    CHECK(t, rc < 0 && strncmp(err, "inf.scene:10:", 13) == 0, "export: %d '%s'", rc, err);
    CHECK(t, !pov_exists(pov_path(".pov")), "the refused export wrote a file");
    CHECK(t, !pov_exists(pov_path(".pov.ptmp")), "the refused export left its temporary file");
}

/* A sphere under `scale 1 3 1` is refused by the build; the exporter wrote a unit sphere. */
static void pov_ellipsoid_refused(test_ctx *t)
{
    char err[1024];
    int rc = pov_export_text(POV_HEAD "scale 1 3 1\nsphere 0 0 0 1 m\n", "ell.scene", err, sizeof err);
    CHECK(t, rc < 0 && strncmp(err, "ell.scene:6:", 12) == 0, "export: %d '%s'", rc, err);
    CHECK(t, !pov_exists(pov_path(".pov")), "the refused export wrote a file");
    rc = pov_export_text(POV_HEAD "scale 2 2 2\nsphere 0 0 0 1 m\n", "ok.scene", err, sizeof err);
    CHECK(t, rc == PT_OK, "a uniformly scaled sphere: %d '%s'", rc, err);
    remove(pov_path(".pov"));
}

/* A camera the renderer refuses (look_at == look_from, set through the API: the parser refuses
   it) was exported; POV-Ray cannot parse it. */
static void pov_bad_camera_refused(test_ctx *t)
{
    const char *text = "size 8 8\ncamera look_from 1 2 3 look_at 0 0 0\nmaterial m lambertian 0.5 0.5 0.5\nsphere 0 0 0 1 m\n";
    char err[1024];
    pt_scenefile sf;
    int rc;
    if (!CHECK(t, pt_scenefile_parse(text, strlen(text), "cam.scene", NULL, &sf, err, sizeof err) == PT_OK, "%s", err))
        return;
    sf.camera.look_at = sf.camera.look_from;
    remove(pov_path(".pov"));
    rc = pt_scenefile_write_pov(&sf, pov_path(".pov"), NULL, err, sizeof err);
    CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strncmp(err, "cam.scene:2:", 12) == 0, "export: %d '%s'", rc, err);
    CHECK(t, !pov_exists(pov_path(".pov")), "the refused export wrote a file");
    pt_scenefile_free(&sf);
}

/* Every scene the build refuses, the export refuses; and a number the build does not check (a
   description edited through the API) that is not finite is refused, not written. */
static void pov_refuses_what_build_refuses(test_ctx *t)
{
    static const char *const bad[] = {
        "scale 1 3 1\nsphere 0 0 0 1 l\n",
        "scale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nbox 0 0 0 1 1 1 m\n",
        "scale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\ntriangle 0 0 0 1 0 0 0 1 1 m\n",
        "scale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nscale 1e7 1 1e-6\nquad 0 0 0 1 0 0 0 1 1 l\n",
        "rotate 1 0 0 30\nscale 1 1 2\nsphere 0 0 0 1 m\n",
    };
    char text[1024], err[1024];
    size_t i;
    pt_scenefile sf;
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        pt_scene *s = NULL;
        pt_render_desc rd;
        int brc, rc;
        snprintf(text, sizeof text, POV_HEAD "%s", bad[i]);
        if (!CHECK(t, pt_scenefile_parse(text, strlen(text), "b.scene", NULL, &sf, err, sizeof err) == PT_OK,
                   "case %d parse: %s", (int)i, err))
            continue;
        brc = pt_scenefile_build(&sf, &s, &rd, err, sizeof err);
        pt_scene_destroy(s);
        remove(pov_path(".pov"));
        rc = pt_scenefile_write_pov(&sf, pov_path(".pov"), NULL, err, sizeof err);
        test_note(t, "case %d: build %s", (int)i, brc == PT_OK ? "accepts" : "refuses");
        CHECK(t, brc == PT_OK || (rc < 0 && strncmp(err, "b.scene:", 8) == 0 && !pov_exists(pov_path(".pov"))),
              "case %d: build %d, export %d '%s'", (int)i, brc, rc, err);
        pt_scenefile_free(&sf);
    }
    snprintf(text, sizeof text, POV_HEAD "sphere 0 0 0 1 m\n");
    if (CHECK(t, pt_scenefile_parse(text, strlen(text), "nan.scene", NULL, &sf, err, sizeof err) == PT_OK, "%s", err)) {
        sf.background.y = (float)nan("");
        remove(pov_path(".pov"));
        CHECK(t, pt_scenefile_write_pov(&sf, pov_path(".pov"), NULL, err, sizeof err) == PT_ERROR_UNSUPPORTED &&
                     strstr(err, "not finite") && !pov_exists(pov_path(".pov")),
              "a nan background: '%s'", err);
        sf.background.y = 0;
        sf.camera.look_from.x = (float)HUGE_VAL;
        CHECK(t, pt_scenefile_write_pov(&sf, pov_path(".pov"), NULL, err, sizeof err) < 0 &&
                     strncmp(err, "nan.scene:2:", 12) == 0 && !pov_exists(pov_path(".pov")),
              "an infinite camera: '%s'", err);
        pt_scenefile_free(&sf);
    }
}

/* The checker of the fuzz target fails on each kind of bad text, and passes real exports. */
static void pov_checker_catches_bad_text(test_ctx *t)
{
    static const char *const bad[] = {
        "sphere { <0, 0, nan>, 1 }\n", "sphere { <0, 0, -inf>, 1 }\n", "// a.scene\n#fopen F \"x\" write\n",
        "#include \"colors.inc\"\n", "sphere { <0, 0, 0>, 1 \n", "sphere { <0, 0, 0>, 1 } }\n", "// a\rsphere\n",
        "/* a */\n", "// a.scene */ sphere\n", "sphere { <0, 0, 0>, 1 } // tail\n", "pwned { }\n",
        "// a\x0c#declare\n", "sphere { <0, 0, 0>, 1 }", "background { rgb <1e, 0, 0> }\n", "// \xc3\xa9\n",
    };
    static const char *const scenes[] = {"scenes/cornell.scene", "scenes/checker.scene", "scenes/mesh.scene",
                                         "scenes/glass.scene", "scenes/direct-sphere.scene", "scenes/lights-direct.scene"};
    char why[256], err[1024];
    size_t i, len = 0;
    for (i = 0; i < sizeof bad / sizeof bad[0]; ++i)
        CHECK(t, !pt_pov_check_text(bad[i], strlen(bad[i]), why, sizeof why), "accepted bad text %d", (int)i);
    for (i = 0; i < sizeof scenes / sizeof scenes[0]; ++i) {
        pt_scenefile sf;
        char *text;
        if (!CHECK(t, pt_scenefile_load(scenes[i], &sf, err, sizeof err) == PT_OK, "%s", err)) continue;
        CHECK(t, pt_scenefile_write_pov(&sf, pov_path(".pov"), NULL, err, sizeof err) == PT_OK, "%s", err);
        pt_scenefile_free(&sf);
        text = tu_read_text(pov_path(".pov"), &len);
        CHECK(t, text && pt_pov_check_text(text, len, why, sizeof why), "%s: %s", scenes[i], text ? why : "no file");
        free(text);
    }
    remove(pov_path(".pov"));
}

/* pt_scenefile_escape: every byte 1..255 through both modes. */
static void pov_escape_modes(test_ctx *t)
{
    char in[256], out[1100], small[8];
    size_t i, n;
    for (i = 0; i < 255; ++i) in[i] = (char)(i + 1);
    in[255] = '\0';
    n = pt_scenefile_escape(out, sizeof out, in, PT_SCENEFILE_ESCAPE_COMMENT);
    CHECK(t, n == strlen(out), "length %d", (int)n);
    for (i = 0; i < n; ++i)
        CHECK(t, strchr("\n\r*#\"%", out[i]) == NULL && out[i] >= 0x20 && out[i] < 0x7f, "byte 0x%02x kept", out[i] & 255);
    CHECK(t, strstr(out, "\\x0A") && strstr(out, "\\x2A") && strstr(out, "\\x5C") && strstr(out, "\\xFF") && strstr(out, "abc"),
          "escapes missing");
    n = pt_scenefile_escape(out, sizeof out, in, PT_SCENEFILE_ESCAPE_XML);
    for (i = 0; i < n; ++i) CHECK(t, strchr("<>\"'", out[i]) == NULL && out[i] >= 0x20 && out[i] < 0x7f, "byte 0x%02x kept", out[i] & 255);
    CHECK(t, strstr(out, "&amp;") && strstr(out, "&lt;") && strstr(out, "&gt;") && strstr(out, "&quot;") && strstr(out, "&apos;"),
          "entities missing: %s", out);
    n = pt_scenefile_escape(small, sizeof small, "ab\n\ncd", PT_SCENEFILE_ESCAPE_COMMENT);
    CHECK(t, n == 6 && strcmp(small, "ab\\x0A") == 0, "cut before an escape that does not fit: '%s'", small);
    n = pt_scenefile_escape(small, sizeof small, "abc&d", PT_SCENEFILE_ESCAPE_XML);
    CHECK(t, n == 3 && strcmp(small, "abc") == 0, "'%s'", small);
    CHECK(t, pt_scenefile_escape(small, sizeof small, NULL, PT_SCENEFILE_ESCAPE_XML) == 0 && small[0] == '\0', "NULL text");
}

/* Exported project scenes parse in POV-Ray (rendered at 4x4). */
static void pov_exports_render(test_ctx *t)
{
    static const char *const scenes[] = {"cornell", "checker", "mesh", "glass", "direct-sphere", "mirror", "lights-direct"};
    char dir[256], pov[320], path[320], err[1024];
    size_t i;
    if (!have_povray()) {
        test_skip(t, "povray is not installed (apt-get install povray)");
        return;
    }
    snprintf(dir, sizeof dir, "build/test-pov-render-%ld", (long)getpid());
    mkdir(dir, 0755);
    for (i = 0; i < sizeof scenes / sizeof scenes[0]; ++i) {
        pt_scenefile sf;
        pt_pov_options o;
        snprintf(path, sizeof path, "scenes/%s.scene", scenes[i]);
        snprintf(pov, sizeof pov, "%s/%s.pov", dir, scenes[i]);
        if (!CHECK(t, pt_scenefile_load(path, &sf, err, sizeof err) == PT_OK, "%s", err)) continue;
        memset(&o, 0, sizeof o);
        o.radiosity = 0;
        o.light_grid = 2;
        CHECK(t, pt_scenefile_write_pov(&sf, pov, &o, err, sizeof err) == PT_OK, "%s", err);
        pt_scenefile_free(&sf);
        snprintf(path, sizeof path, "%s.pov", scenes[i]);
        CHECK(t, pov_render(dir, path, 4, 4), "povray failed on %s (see %s/povray.log)", pov, dir);
    }
    test_note(t, "%d exported scenes rendered at 4x4", (int)(sizeof scenes / sizeof scenes[0]));
}

/* Reads n numbers after `key` (the first at or after from); the end, or NULL. */
static const char *pov_numbers(const char *from, const char *key, double *out, int n)
{
    const char *p = from ? strstr(from, key) : NULL;
    int i;
    if (!p) return NULL;
    p += strlen(key);
    for (i = 0; i < n; ++i) {
        char *end;
        while (*p && !((*p >= '0' && *p <= '9') || *p == '-' || *p == '+' || *p == '.')) ++p; /* words, <, > */
        out[i] = strtod(p, &end);
        if (end == p) return NULL;
        p = end;
    }
    return p;
}

/* The light_source of the statement on `line`, up to its end of line (a static copy), or NULL. */
static const char *pov_light_at(const char *text, int line)
{
    static char buf[1024];
    char key[64];
    const char *p, *e;
    snprintf(key, sizeof key, "// l.scene:%d\nlight_source { ", line);
    p = strstr(text, key);
    if (!p) return NULL;
    p += strlen(key) - strlen("light_source { ");
    e = strchr(p, '\n');
    if (!e || (size_t)(e - p) >= sizeof buf) return NULL;
    memcpy(buf, p, (size_t)(e - p));
    buf[e - p] = '\0';
    return buf;
}

/* Point, hard-cone spot and directional lights as the recipe has them (docs/povray.md): the
   fade trick's colour I/(2 pi fd^2) at the transformed position; the spot's cone of constant
   intensity (radius = falloff = cutoff, tightness 0) along the transformed axis; the parallel
   light of colour E/pi travelling along the transformed direction from a location whose plane
   (normal to the light) leaves every corner of the scene's bounds in front of it. The text
   passes the fuzz checker, and POV-Ray renders it. */
static void pov_lights(test_ctx *t)
{
    const char *text = POV_HEAD "quad -3 0 -3  0 0 6  6 0 0  m\nsphere 0 1 0 1 m\n"
                                "point_light 1 4 -2  3 2 1\n"                        /* line 7 */
                                "translate 0 1 0\nrotate 0 0 1 90\n"
                                "spot_light 1 0 0  0 0 0  6 5 4  25 25\n"            /* line 10 */
                                "identity\nscale 2 1 1\n"
                                "directional_light 1 -2 0.5  0.8 0.7 0.6\n";         /* line 13 */
    const double two_pi = 2.0 * TU_PI;
    char err[1024], why[256];
    double v[9], fd = 0, lo_hi[2][3] = {{-3, 0, -3}, {3, 2, 3}};
    const char *l;
    char *out;
    size_t len = 0;
    int rc = pov_export_text(text, "l.scene", err, sizeof err), i;
    if (!CHECK(t, rc == PT_OK, "export: %d '%s'", rc, err)) return;
    out = tu_read_text(pov_path(".pov"), &len);
    if (!CHECK(t, out != NULL, "no file")) return;
    CHECK(t, pt_pov_check_text(out, len, why, sizeof why), "checker: %s", why);
    l = pov_light_at(out, 7);
    if (CHECK(t, l && pov_numbers(l, "light_source {", v, 6) && pov_numbers(l, "fade_distance", &fd, 1), "point: '%s'", l ? l : "none")) {
        CHECK(t, v[0] == 1 && v[1] == 4 && v[2] == -2, "point at <%g %g %g>", v[0], v[1], v[2]);
        CHECK(t, fabs(v[3] * two_pi * fd * fd / 3 - 1) < 1e-7 && fabs(v[4] * two_pi * fd * fd / 2 - 1) < 1e-7 &&
                     fabs(v[5] * two_pi * fd * fd / 1 - 1) < 1e-7,
              "point colour %g %g %g with fade_distance %g: not I/(2 pi fd^2)", v[3], v[4], v[5], fd);
        CHECK(t, strstr(l, "fade_power 2 }") && !strstr(l, "spotlight"), "point: '%s'", l);
    }
    l = pov_light_at(out, 10);
    if (CHECK(t, l && pov_numbers(l, "light_source {", v, 6) && pov_numbers(l, "point_at", v + 6, 3), "spot: '%s'", l ? l : "none")) {
        /* (1, 0, 0) moved up 1, then turned 90 degrees about z: (1, 1, 0) -> (-1, 1, 0); the
           axis (-1, 0, 0) -> (0, -1, 0) */
        dv3 axis = dnorm(dv(v[6] - v[0], v[7] - v[1], v[8] - v[2]));
        CHECK(t, fabs(v[0] + 1) < 1e-6 && fabs(v[1] - 1) < 1e-6 && fabs(v[2]) < 1e-6, "spot at <%g %g %g>", v[0], v[1], v[2]);
        CHECK(t, fabs(axis.x) < 1e-6 && fabs(axis.y + 1) < 1e-9 && fabs(axis.z) < 1e-6, "spot axis (%g %g %g)", axis.x,
              axis.y, axis.z);
        CHECK(t, fabs(v[3] * two_pi * fd * fd / 6 - 1) < 1e-7 && fabs(v[5] * two_pi * fd * fd / 4 - 1) < 1e-7,
              "spot colour %g %g %g", v[3], v[4], v[5]);
        CHECK(t, strstr(l, " radius 25 falloff 25 tightness 0 fade_distance ") != NULL, "spot cone: '%s'", l);
    }
    l = pov_light_at(out, 13);
    if (CHECK(t, l && pov_numbers(l, "light_source {", v, 6) && pov_numbers(l, "point_at", v + 6, 3), "directional: '%s'", l ? l : "none")) {
        dv3 loc = dv(v[0], v[1], v[2]), d = dnorm(dsub(dv(v[6], v[7], v[8]), loc)), want = dnorm(dv(2, -2, 0.5));
        int k;
        CHECK(t, dlen(dsub(d, want)) < 1e-7, "travels along (%g %g %g), want (%g %g %g)", d.x, d.y, d.z, want.x, want.y, want.z);
        CHECK(t, fabs(v[3] * TU_PI / 0.8 - 1) < 1e-7 && fabs(v[5] * TU_PI / 0.6 - 1) < 1e-7, "colour %g %g %g: not E/pi",
              v[3], v[4], v[5]);
        CHECK(t, strstr(l, " parallel point_at ") && !strstr(l, "fade"), "directional: '%s'", l);
        for (k = 0; k < 8; ++k) {
            dv3 c = dv(lo_hi[k & 1][0], lo_hi[(k >> 1) & 1][1], lo_hi[k >> 2][2]);
            CHECK(t, ddot(dsub(c, loc), d) > 1.0, "corner %d lies behind the parallel light's plane", k);
        }
    }
    for (i = 0; i < 3; ++i) /* no other light_source than the three */
        l = strstr(i ? l + 1 : out, "light_source");
    CHECK(t, l && !strstr(l + 1, "light_source"), "more than three light sources");
    free(out);
    if (have_povray()) {
        char dir[256], rel[64];
        snprintf(dir, sizeof dir, "build/test-pov-lights-%ld", (long)getpid());
        snprintf(rel, sizeof rel, "../test-pov-%ld-lights.pov", (long)getpid()); /* pov_path("-lights.pov") from dir */
        mkdir(dir, 0755);
        CHECK(t, rename(pov_path(".pov"), pov_path("-lights.pov")) == 0, "rename");
        CHECK(t, pov_render(dir, rel, 4, 4), "povray failed on the lights (see %s/povray.log)", dir);
        remove(pov_path("-lights.pov"));
    } else
        test_note(t, "povray not installed: render not tried");
    remove(pov_path(".pov"));
}

/* A spot whose beam is narrower than its cutoff (given, or the default 3/4) has no exact POV-Ray
   twin: refused with its file:line and why, and nothing written. */
static void pov_soft_spot_refused(test_ctx *t)
{
    static const struct { const char *light; int line; } cases[] = {
        {"spot_light 0 3 0  0 0 0  5 5 5  30 15\n", 6},
        {"spot_light 0 3 0  0 0 0  5 5 5\n", 6},
        {"spot_light 0 3 0  0 0 0  5 5 5  40\n", 6},
        {"point_light 0 3 0  1 1 1\nrotate 1 0 0 10\nspot_light 0 3 0  0 0 0  5 5 5  30 29.9\n", 8}};
    char text[1024], err[1024], want[32];
    size_t i;
    for (i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        int rc;
        snprintf(text, sizeof text, POV_HEAD "sphere 0 0 0 1 m\n%s", cases[i].light);
        snprintf(want, sizeof want, "s.scene:%d: ", cases[i].line);
        rc = pov_export_text(text, "s.scene", err, sizeof err);
        CHECK(t, rc == PT_ERROR_UNSUPPORTED && !strncmp(err, want, strlen(want)) && strstr(err, "smoothstep") &&
                     strstr(err, "beam"),
              "case %d: %d '%s'", (int)i, rc, err);
        CHECK(t, !pov_exists(pov_path(".pov")) && !pov_exists(pov_path(".pov.ptmp")), "case %d wrote a file", (int)i);
    }
    snprintf(text, sizeof text, POV_HEAD "sphere 0 0 0 1 m\nspot_light 0 3 0  0 0 0  5 5 5  40 40\n");
    CHECK(t, pov_export_text(text, "s.scene", err, sizeof err) == PT_OK, "a hard cone: '%s'", err);
    remove(pov_path(".pov"));
}

/* An environment map is refused (POV-Ray's sky_sphere lights diffuse surfaces only through
   radiosity: docs/povray.md, "Environment maps") at the statement's file:line; nothing written. */
static void pov_environment_refused(test_ctx *t)
{
    const char *text = POV_HEAD "sphere 0 0 0 1 m\nrotate 0 1 0 30\nenvironment sky.pfm 0.5\n";
    char err[1024];
    pt_scenefile sf;
    int rc;
    if (!CHECK(t, pt_scenefile_parse(text, strlen(text), "env.scene", "scenes", &sf, err, sizeof err) == PT_OK, "%s", err))
        return;
    remove(pov_path(".pov"));
    rc = pt_scenefile_write_pov(&sf, pov_path(".pov"), NULL, err, sizeof err);
    CHECK(t, rc == PT_ERROR_UNSUPPORTED && strncmp(err, "env.scene:7: POV-Ray export: an environment map", 47) == 0 &&
                 strstr(err, "radiosity"), "export: %d '%s'", rc, err);
    CHECK(t, !pov_exists(pov_path(".pov")) && !pov_exists(pov_path(".pov.ptmp")), "the refused export wrote a file");
    pt_scenefile_free(&sf);
}

const test_case test_pov_cases[] = {
    TEST_CASE(pov_path_injection),
    TEST_CASE(pov_nonfinite_refused),
    TEST_CASE(pov_ellipsoid_refused),
    TEST_CASE(pov_refuses_what_build_refuses),
    TEST_CASE(pov_bad_camera_refused),
    TEST_CASE(pov_checker_catches_bad_text),
    TEST_CASE(pov_escape_modes),
    TEST_CASE(pov_exports_render),
    TEST_CASE(pov_lights),
    TEST_CASE(pov_soft_spot_refused),
    TEST_CASE(pov_environment_refused),
    TEST_END
};
