#define _POSIX_C_SOURCE 200809L
/* test_output.c - section 9 of pdftrace.h: film (accumulation, resolve, per-pixel variance), images,
   and the PFM/PPM writers (layout, sRGB encoding, error handling, atomic replacement).
   References: the PFM format (Debevec's Portable Float Map: "PF", width height, negative scale for
   little-endian, rows bottom to top), PPM P6, IEC 61966-2-1 (sRGB transfer function). */
#include "test_util.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#ifdef PDFTRACE_PNG /* built with libpng (make PNG=auto|1): pdftrace_png.h is implemented here */
#define PDFTRACE_PNG_IMPLEMENTATION
#include "pdftrace_png.h"
#include <png.h> /* png_round_trip reads the file back with libpng */
#endif





/* Parses a Netpbm-style header: magic, then `fields` whitespace-separated tokens, then exactly one
   whitespace byte. Returns the offset of the data or -1. */
/* err == before + path + "." + 8 hex digits + ".ptmp" + after: a message naming the temporary. */
static int tmp_message(const char *err, const char *before, const char *path, const char *after)
{
    size_t a = strlen(before), b = strlen(path), i;
    if (strncmp(err, before, a) != 0 || strncmp(err + a, path, b) != 0 || err[a + b] != '.') return 0;
    for (i = 1; i <= 8; ++i)
        if (!strchr("0123456789abcdef", err[a + b + i]) || !err[a + b + i]) return 0;
    return strncmp(err + a + b + 9, ".ptmp", 5) == 0 && strcmp(err + a + b + 14, after) == 0;
}

static long parse_header(const unsigned char *b, long n, const char *magic, char tokens[][32], int fields)
{
    long i = 0;
    int f;
    size_t ml = strlen(magic);
    if (n < (long)ml || memcmp(b, magic, ml) != 0) return -1;
    i = (long)ml;
    for (f = 0; f < fields; f++) {
        int k = 0;
        if (i >= n || !(b[i] == ' ' || b[i] == '\n' || b[i] == '\r' || b[i] == '\t')) return -1;
        while (i < n && (b[i] == ' ' || b[i] == '\n' || b[i] == '\r' || b[i] == '\t')) i++;
        while (i < n && !(b[i] == ' ' || b[i] == '\n' || b[i] == '\r' || b[i] == '\t') && k < 31) tokens[f][k++] = (char)b[i++];
        tokens[f][k] = '\0';
    }
    if (i >= n || !(b[i] == ' ' || b[i] == '\n' || b[i] == '\r' || b[i] == '\t')) return -1;
    return i + 1;
}

static float le_float(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] | ((uint32_t)p[1] << 8) | ((uint32_t)p[2] << 16) | ((uint32_t)p[3] << 24);
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static double srgb_ref(double x)
{
    if (!(x > 0)) return 0;
    if (x >= 1) return 1;
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1 / 2.4) - 0.055;
}

static void pfm_layout(test_ctx *t)
{
    /* 5 x 3 image with distinct values: header "PF" w h -scale (little-endian), then rows from the
       bottom image row to the top, RGB floats, nothing else. */
    char dir[64], path[128], tok[3][32];
    pt_image img;
    unsigned char *b;
    long n, off;
    int x, y, c, rc, bad = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/a.pfm", dir);
    memset(&img, 0, sizeof img);
    if (!CHECK(t, pt_image_init(&img, 5, 3) == PT_OK && img.rgb && img.width == 5 && img.height == 3, "pt_image_init")) {
        tu_remove_tree(dir);
        return;
    }
    for (y = 0; y < 3; y++)
        for (x = 0; x < 5; x++)
            for (c = 0; c < 3; c++) img.rgb[3 * (y * 5 + x) + c] = (float)(x + 10 * y + 100 * c) + 0.25f - (c == 2 ? 1000.0f : 0.0f);
    rc = pt_write_pfm(path, &img);
    CHECK(t, rc == PT_OK, "pt_write_pfm: %d", rc);
    b = tu_read_file(path, &n);
    if (CHECK(t, b != NULL, "cannot read %s", path)) {
        off = parse_header(b, n, "PF", tok, 3);
        if (CHECK(t, off > 0, "PFM header malformed")) {
            CHECK(t, atoi(tok[0]) == 5 && atoi(tok[1]) == 3, "PFM size %s x %s", tok[0], tok[1]);
            CHECK(t, atof(tok[2]) < 0, "PFM scale %s is not negative (little-endian)", tok[2]);
            CHECK(t, n - off == 5 * 3 * 3 * 4, "PFM data is %ld bytes, want %d", n - off, 5 * 3 * 3 * 4);
            if (n - off == 5 * 3 * 3 * 4) {
                for (y = 0; y < 3; y++)        /* file row y is image row 2 - y */
                    for (x = 0; x < 5; x++)
                        for (c = 0; c < 3; c++)
                            if (le_float(b + off + 4 * (3 * (y * 5 + x) + c)) != img.rgb[3 * ((2 - y) * 5 + x) + c]) bad++;
                CHECK(t, bad == 0, "%d PFM values not at their bottom-row-first positions", bad);
            }
        }
        free(b);
    }
    CHECK(t, tu_dir_entries(dir, NULL, 0) == 1, "the writer left extra files in the directory");
    pt_image_free(&img);
    CHECK(t, img.rgb == NULL, "pt_image_free left a dangling pointer");
    tu_remove_tree(dir);
}

/* Writes n bytes to path; 1 on success. */
static int write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    int ok = f && fwrite(data, 1, n, f) == n;
    if (f && fclose(f) != 0) ok = 0;
    return ok;
}

static void pfm_read(test_ctx *t)
{
    /* pt_read_pfm: what pt_write_pfm wrote comes back bit for bit (NaN, Inf and -0 included); a
       greyscale big-endian "Pf" file written here by hand; and each kind of bad file is refused
       with the file named and the image left empty. */
    char dir[64], path[160], err[256];
    pt_image a, b;
    int i, bad = 0, rc;
    static const unsigned char grey[] = { 'P', 'f', '\n', '2', ' ', '1', '\n', '1', '.', '0', '\n',
                                          0x3f, 0x80, 0x00, 0x00, 0xc0, 0x00, 0x00, 0x00 }; /* 1, -2 */
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    memset(&a, 0, sizeof a);
    memset(&b, 0, sizeof b);
    snprintf(path, sizeof path, "%s/a.pfm", dir);
    if (CHECK(t, pt_image_init(&a, 7, 4) == PT_OK, "pt_image_init")) {
        for (i = 0; i < 7 * 4 * 3; i++) a.rgb[i] = (float)i * 0.37f - 5.0f;
        a.rgb[3] = (float)NAN;
        a.rgb[4] = (float)INFINITY;
        a.rgb[5] = -0.0f;
        CHECK(t, pt_write_pfm(path, &a) == PT_OK, "pt_write_pfm");
        rc = pt_read_pfm(path, &b, err, sizeof err);
        if (CHECK(t, rc == PT_OK && b.width == 7 && b.height == 4, "pt_read_pfm: %d %s (%d x %d)", rc, err, b.width, b.height)) {
            for (i = 0; i < 7 * 4 * 3; i++) bad += memcmp(&a.rgb[i], &b.rgb[i], sizeof(float)) != 0;
            CHECK(t, bad == 0, "%d values differ after the round trip", bad);
            CHECK(t, err[0] == '\0', "message '%s' after success", err);
        }
        pt_image_free(&b);
    }
    snprintf(path, sizeof path, "%s/grey.pfm", dir);
    if (CHECK(t, write_bytes(path, grey, sizeof grey), "writing %s", path)) {
        rc = pt_read_pfm(path, &b, err, sizeof err);
        CHECK(t, rc == PT_OK && b.width == 2 && b.height == 1 && b.rgb[0] == 1.0f && b.rgb[2] == 1.0f &&
                     b.rgb[3] == -2.0f && b.rgb[5] == -2.0f,
              "big-endian greyscale: %d %s", rc, err);
        pt_image_free(&b);
    }
    {
        static const struct { const char *name, *bytes, *want; int code; } cases[] = {
            { "text.pfm", "hello, not a float map\n", "not a PFM file", PT_ERROR_IO },
            { "header.pfm", "PF\n3 x\n-1.0\n", "bad PFM header", PT_ERROR_IO },
            { "zero.pfm", "PF\n3 2\n0\n", "bad PFM header", PT_ERROR_IO },
            { "short.pfm", "PF\n3 2\n-1.0\n0123456789", "truncated", PT_ERROR_IO },
            { "huge.pfm", "PF\n1000000 1000000\n-1.0\n", "PDFTRACE_PFM_MAX_PIXELS", PT_ERROR_UNSUPPORTED },
            { "empty.pfm", "", "not a PFM file", PT_ERROR_IO },
        };
        size_t k;
        for (k = 0; k < sizeof cases / sizeof cases[0]; k++) {
            snprintf(path, sizeof path, "%s/%s", dir, cases[k].name);
            if (!CHECK(t, write_bytes(path, cases[k].bytes, strlen(cases[k].bytes)), "writing %s", path)) continue;
            memset(&b, 0x55, sizeof b); /* (must come back empty) */
            rc = pt_read_pfm(path, &b, err, sizeof err);
            CHECK(t, rc == cases[k].code && strstr(err, cases[k].want) && strstr(err, cases[k].name) && !b.rgb &&
                         b.width == 0 && b.height == 0,
                  "%s: %d '%s'", cases[k].name, rc, err);
        }
    }
    snprintf(path, sizeof path, "%s/missing.pfm", dir);
    rc = pt_read_pfm(path, &b, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && strstr(err, "missing.pfm") && !b.rgb, "missing file: %d '%s'", rc, err);
    CHECK(t, pt_read_pfm(NULL, &b, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT && strstr(err, "path"), "NULL path: '%s'", err);
    CHECK(t, pt_read_pfm(path, NULL, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT && strstr(err, "out"), "NULL out: '%s'", err);
    pt_image_free(&a);
    tu_remove_tree(dir);
}

static void ppm_srgb(test_ctx *t)
{
    /* P6 with maxval 255, top row first; each byte = 255 * sRGB(clamp(x, 0, 1)) to within one unit
       (rounding or truncation), exactly 0 for x <= 0 and 255 for x >= 1. */
    static const float vals[] = { -1.0f, 0.0f, 0.001f, 0.0031308f, 0.01f, 0.05f, 0.18f, 0.2140411f, 0.5f, 0.9f, 0.999f, 1.0f, 1.5f, 100.0f, 0.73f };
    const int w = 5, h = 3;
    char dir[64], path[128], tok[3][32];
    pt_image img;
    unsigned char *b;
    long n, off;
    int i, c, bad = 0, rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/a.ppm", dir);
    memset(&img, 0, sizeof img);
    if (!CHECK(t, pt_image_init(&img, w, h) == PT_OK, "pt_image_init")) { tu_remove_tree(dir); return; }
    for (i = 0; i < w * h; i++)
        for (c = 0; c < 3; c++) img.rgb[3 * i + c] = vals[(i + 5 * c) % 15];
    rc = pt_write_ppm(path, &img);
    CHECK(t, rc == PT_OK, "pt_write_ppm: %d", rc);
    b = tu_read_file(path, &n);
    if (CHECK(t, b != NULL, "cannot read the PPM")) {
        off = parse_header(b, n, "P6", tok, 3);
        if (CHECK(t, off > 0, "PPM header malformed")) {
            CHECK(t, atoi(tok[0]) == w && atoi(tok[1]) == h && atoi(tok[2]) == 255, "PPM header %s %s %s", tok[0], tok[1], tok[2]);
            CHECK(t, n - off == w * h * 3, "PPM data is %ld bytes, want %d", n - off, w * h * 3);
            if (n - off == w * h * 3) {
                for (i = 0; i < w * h * 3; i++) {
                    double x = img.rgb[i], want = 255.0 * srgb_ref(x);
                    int got = b[off + i];
                    if ((x <= 0 && got != 0) || (x >= 1 && got != 255) || fabs(got - want) >= 1.0) {
                        if (bad++ == 0) test_note(t, "value %g -> byte %d, want %.2f", x, got, want);
                    }
                }
                CHECK(t, bad == 0, "%d PPM bytes differ from 255 * sRGB(clamp(x))", bad);
            }
        }
        free(b);
    }
    pt_image_free(&img);
    tu_remove_tree(dir);
}

static void srgb_encode_function(test_ctx *t)
{
    int i, bad = 0, nonmono = 0;
    float prev = -1;
    for (i = 0; i <= 10000; i++) {
        float x = i / 10000.0f, y = pt_srgb_encode(x);
        double want = srgb_ref(x);
        if (fabs(y - want) > 1e-5 * fmax(want, 1e-3)) bad++;
        if (y < prev) nonmono++;
        prev = y;
    }
    CHECK(t, bad == 0, "%d of 10001 values differ from IEC 61966-2-1 (rel 1e-5)", bad);
    CHECK(t, nonmono == 0, "pt_srgb_encode is not monotone");
    CHECK(t, pt_srgb_encode(-0.5f) == 0.0f && pt_srgb_encode(2.0f) == 1.0f && pt_srgb_encode(1e30f) == 1.0f,
          "not clamped: f(-0.5) = %g, f(2) = %g", pt_srgb_encode(-0.5f), pt_srgb_encode(2.0f));
    CHECK(t, fabs(pt_srgb_encode(0.0031308f) - 0.0031308 * 12.92) < 1e-6, "linear segment end");
}

static void write_errors(test_ctx *t)
{
    /* An unwritable target returns PT_ERROR_IO and leaves no file (temporary or final) behind;
       invalid arguments return PT_ERROR_INVALID_ARGUMENT; an existing file is replaced whole. */
    char dir[64], path[160], list[256];
    pt_image img, small;
    int rc, k;
    FILE *f;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    memset(&img, 0, sizeof img);
    memset(&small, 0, sizeof small);
    if (!CHECK(t, pt_image_init(&img, 4, 4) == PT_OK && pt_image_init(&small, 1, 1) == PT_OK, "pt_image_init")) {
        tu_remove_tree(dir);
        return;
    }
    for (k = 0; k < 2; k++) {
        int (*writer)(const char *, const pt_image *) = k == 0 ? pt_write_pfm : pt_write_ppm;
        const char *name = k == 0 ? "pt_write_pfm" : "pt_write_ppm";
        /* a directory that does not exist */
        snprintf(path, sizeof path, "%s/missing/out.img", dir);
        rc = writer(path, &img);
        CHECK(t, rc == PT_ERROR_IO, "%s into a missing directory: %d, want PT_ERROR_IO", name, rc);
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "%s left files behind: %s", name, list);
        /* the target is an existing directory: the temporary file must be removed */
        snprintf(path, sizeof path, "%s/target", dir);
        mkdir(path, 0700);
        rc = writer(path, &img);
        CHECK(t, rc == PT_ERROR_IO, "%s onto a directory: %d, want PT_ERROR_IO", name, rc);
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 1 && tu_dir_entries(path, NULL, 0) == 0,
              "%s onto a directory left files behind: %s", name, list);
        rmdir(path);
        /* a path through a regular file */
        snprintf(path, sizeof path, "%s/file", dir);
        f = fopen(path, "wb");
        if (f) fclose(f);
        snprintf(path, sizeof path, "%s/file/out.img", dir);
        rc = writer(path, &img);
        CHECK(t, rc == PT_ERROR_IO, "%s below a regular file: %d, want PT_ERROR_IO", name, rc);
        snprintf(path, sizeof path, "%s/file", dir);
        unlink(path);
        /* invalid arguments */
        CHECK(t, writer(NULL, &img) == PT_ERROR_INVALID_ARGUMENT, "%s(NULL path) did not fail", name);
        snprintf(path, sizeof path, "%s/x.img", dir);
        CHECK(t, writer(path, NULL) == PT_ERROR_INVALID_ARGUMENT, "%s(NULL image) did not fail", name);
        {
            pt_image empty;
            memset(&empty, 0, sizeof empty);
            empty.width = 4;
            empty.height = 4;
            CHECK(t, writer(path, &empty) == PT_ERROR_INVALID_ARGUMENT, "%s with rgb == NULL did not fail", name);
        }
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "%s: invalid calls left files: %s", name, list);
        /* replacing an existing file: the new content, nothing else in the directory */
        rc = writer(path, &img);
        rc |= writer(path, &small);
        {
            long n1 = 0, n2 = 0;
            unsigned char *b1, *b2;
            char other[160];
            snprintf(other, sizeof other, "%s/y.img", dir);
            writer(other, &small);
            b1 = tu_read_file(path, &n1);
            b2 = tu_read_file(other, &n2);
            CHECK(t, rc == PT_OK && b1 && b2 && n1 == n2 && memcmp(b1, b2, (size_t)n1) == 0,
                  "%s: overwriting a file does not leave exactly the new image", name);
            free(b1);
            free(b2);
            unlink(other);
        }
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 1, "%s: after overwriting, the directory holds: %s", name, list);
        unlink(path);
    }
    pt_image_free(&img);
    pt_image_free(&small);
    tu_remove_tree(dir);
}

static void film_math(test_ctx *t)
{
    /* Synthetic sums: pixel (1, 0) holds samples {1, 2, 3, 6} in red, {0.5} x 4 in green, {-1, 1, -1, 1}
       in blue. Mean = sum/n; variance of the mean = s^2 / n with the unbiased sample variance
       s^2 = (sum_sq - n mean^2) / (n - 1). A pixel without samples has mean 0 (no NaN). */
    pt_film f;
    pt_image img;
    pt_color m, v;
    int rc, i;
    memset(&img, 0, sizeof img);
    rc = pt_film_init(&f, 3, 2);
    if (!CHECK(t, rc == PT_OK && f.sum && f.sum_sq && f.count && f.width == 3 && f.height == 2, "pt_film_init")) return;
    for (i = 0; i < 6; i++)
        CHECK(t, f.count[i] == 0 && f.sum[3 * i] == 0 && f.sum_sq[3 * i + 2] == 0, "fresh film not zeroed at %d", i);
    /* pixel (x = 1, y = 0): index 1 */
    f.count[1] = 4;
    f.sum[3] = 12; f.sum_sq[3] = 1 + 4 + 9 + 36;
    f.sum[4] = 2; f.sum_sq[4] = 1;
    f.sum[5] = 0; f.sum_sq[5] = 4;
    /* pixel (x = 2, y = 1): index 5, one sample (0.25, 0.5, 0.75) */
    f.count[5] = 1;
    f.sum[15] = 0.25; f.sum[16] = 0.5; f.sum[17] = 0.75;
    f.sum_sq[15] = 0.0625; f.sum_sq[16] = 0.25; f.sum_sq[17] = 0.5625;
    rc = pt_film_pixel(&f, 1, 0, &m, &v);
    CHECK(t, rc == PT_OK, "pt_film_pixel: %d", rc);
    CHECK(t, fabs(m.x - 3) < 1e-6 && fabs(m.y - 0.5) < 1e-6 && fabs(m.z) < 1e-6, "mean (%g %g %g), want (3 0.5 0)", m.x, m.y, m.z);
    /* red: s^2 = (50 - 36) / 3 = 14/3, /4 = 7/6; green: 0; blue: s^2 = 4/3, /4 = 1/3 */
    CHECK(t, fabs(v.x - 7.0 / 6.0) < 1e-5 && fabs(v.y) < 1e-6 && fabs(v.z - 1.0 / 3.0) < 1e-5,
          "variance of the mean (%.6f %.6f %.6f), want (%.6f 0 %.6f) = unbiased sample variance / n", v.x, v.y, v.z,
          7.0 / 6.0, 1.0 / 3.0);
    rc = pt_film_pixel(&f, 0, 1, &m, &v);
    CHECK(t, rc == PT_OK && m.x == 0 && m.y == 0 && m.z == 0 && !isnan(v.x) && !isnan(v.y) && !isnan(v.z),
          "empty pixel: mean (%g %g %g), variance (%g %g %g)", m.x, m.y, m.z, v.x, v.y, v.z);
    rc = pt_film_pixel(&f, 2, 1, &m, &v);
    CHECK(t, rc == PT_OK && fabs(m.z - 0.75) < 1e-7 && !isnan(v.x), "one-sample pixel: mean %g, variance %g", m.z, v.x);
    CHECK(t, pt_film_pixel(&f, 3, 0, &m, &v) == PT_ERROR_INVALID_ARGUMENT && pt_film_pixel(&f, 0, -1, &m, &v) == PT_ERROR_INVALID_ARGUMENT,
          "out-of-range pixel accepted");
    rc = pt_film_resolve(&f, &img);
    if (CHECK(t, rc == PT_OK && img.width == 3 && img.height == 2 && img.rgb, "pt_film_resolve: %d", rc)) {
        CHECK(t, fabs(img.rgb[3] - 3) < 1e-6 && fabs(img.rgb[4] - 0.5) < 1e-6 && img.rgb[0] == 0 && fabs(img.rgb[17] - 0.75) < 1e-7,
              "resolved values (%g %g) (%g) (%g)", img.rgb[3], img.rgb[4], img.rgb[0], img.rgb[17]);
        for (i = 0; i < 18; i++) CHECK(t, !isnan(img.rgb[i]), "resolved value %d is NaN", i);
    }
    pt_film_clear(&f);
    for (i = 0; i < 6; i++) CHECK(t, f.count[i] == 0 && f.sum[3 * i] == 0 && f.sum_sq[3 * i] == 0, "pt_film_clear left data at %d", i);
    pt_film_free(&f);
    CHECK(t, f.sum == NULL && f.count == NULL, "pt_film_free left dangling pointers");
    pt_image_free(&img);
    CHECK(t, pt_film_init(&f, 0, 4) == PT_ERROR_INVALID_ARGUMENT, "a 0 x 4 film accepted");
    CHECK(t, pt_image_init(&img, -1, 4) == PT_ERROR_INVALID_ARGUMENT, "a -1 x 4 image accepted");
}

static void film_accumulates_render(test_ctx *t)
{
    /* A render adds exactly samples_per_pixel samples to every pixel, sum/count is what resolve gives,
       and sum_sq >= sum^2 / count (Cauchy-Schwarz) everywhere. */
    pt_scene *s = pt_scene_create();
    pt_render_desc d;
    pt_film f;
    pt_image img;
    pt_render_stats st;
    int m, e, rc, i, c, bad = 0;
    if (!CHECK(t, s != NULL, "scene")) return;
    m = pt_scene_add_lambertian(s, pt_v3(0.6f, 0.5f, 0.4f));
    e = pt_scene_add_emitter(s, pt_v3(3, 3, 3), 0);
    rc = pt_scene_add_sphere(s, pt_v3(0, 0, 0), 1, m);
    rc = rc >= 0 ? pt_scene_add_quad(s, pt_v3(-1, 3, -1), pt_v3(2, 0, 0), pt_v3(0, 0, 2), e) : rc;
    rc = rc >= 0 ? pt_scene_commit(s) : rc;
    if (!CHECK(t, rc == PT_OK, "scene")) { pt_scene_destroy(s); return; }
    memset(&d, 0, sizeof d);
    d.width = 12; d.height = 9; d.samples_per_pixel = 7;
    d.camera.look_from = pt_v3(0, 1, -4); d.camera.look_at = pt_v3(0, 0, 0);
    d.background = pt_v3(0.1f, 0.2f, 0.3f);
    memset(&img, 0, sizeof img);
    pt_film_init(&f, 12, 9);
    rc = pt_render(s, &d, &f, &st);
    CHECK(t, rc == PT_OK && st.nonfinite_samples == 0 && st.samples == 12 * 9 * 7, "render: %d, %llu samples", rc,
          (unsigned long long)st.samples);
    rc = pt_film_resolve(&f, &img);
    for (i = 0; i < 12 * 9 && rc == PT_OK; i++) {
        if (f.count[i] != 7) bad++;
        for (c = 0; c < 3; c++) {
            double mean = f.sum[3 * i + c] / f.count[i];
            if (fabs(img.rgb[3 * i + c] - mean) > 1e-6 * fmax(1, fabs(mean))) bad++;
            if (f.sum_sq[3 * i + c] < f.sum[3 * i + c] * f.sum[3 * i + c] / f.count[i] * (1 - 1e-9)) bad++;
        }
    }
    CHECK(t, rc == PT_OK && bad == 0, "%d film entries inconsistent (count, mean, sum of squares)", bad);
    pt_image_free(&img);
    pt_film_free(&f);
    pt_scene_destroy(s);
}

static void write_error_messages(test_ctx *t)
{
    /* pt_write_pfm_ex and pt_write_ppm_ex describe each failure in err: the path, the step and the
       system's reason (strerror of the errno the failing call set), and leave no file behind; a
       write that succeeds leaves "" there; err may be NULL, and a short err is truncated, not
       overrun. */
    char dir[64], path[160], want[800], list[256], err[1024], tiny[16];
    pt_image img;
    int rc, k, c;
    FILE *f;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    memset(&img, 0, sizeof img);
    if (!CHECK(t, pt_image_init(&img, 3, 2) == PT_OK, "pt_image_init")) { tu_remove_tree(dir); return; }
    for (k = 0; k < 2; k++) {
        int (*writer)(const char *, const pt_image *, char *, size_t) = k == 0 ? pt_write_pfm_ex : pt_write_ppm_ex;
        const char *name = k == 0 ? "pt_write_pfm_ex" : "pt_write_ppm_ex", *what = k == 0 ? "PFM" : "PPM";
        /* cases: a missing directory (ENOENT), a directory as the target (EISDIR, at the rename), a
           path through a regular file (ENOTDIR) */
        for (c = 0; c < 3; c++) {
            const int code[3] = { ENOENT, EISDIR, ENOTDIR };
            if (c == 0) snprintf(path, sizeof path, "%s/missing/out.img", dir);
            if (c == 1) {
                snprintf(path, sizeof path, "%s/target", dir);
                mkdir(path, 0700);
            }
            if (c == 2) {
                snprintf(path, sizeof path, "%s/file", dir);
                f = fopen(path, "wb");
                if (f) fclose(f);
                snprintf(path, sizeof path, "%s/file/out.img", dir);
            }
            err[0] = '\0';
            rc = writer(path, &img, err, sizeof err);
            snprintf(want, sizeof want, "%s: writing %s: cannot %s '", path, what, c == 1 ? "rename" : "create");
            if (c == 1) snprintf(list, sizeof list, "' to '%s': %s", path, strerror(code[c]));
            else snprintf(list, sizeof list, "': %s", strerror(code[c]));
            CHECK(t, rc == PT_ERROR_IO && tmp_message(err, want, path, list), "%s case %d: %d, message '%s', want '%s%s.XXXXXXXX.ptmp%s'",
                  name, c, rc, err, want, path, list);
            if (c == 1) {
                CHECK(t, tu_dir_entries(path, NULL, 0) == 0, "%s onto a directory wrote into it", name);
                rmdir(path);
            }
            if (c == 2) {
                snprintf(path, sizeof path, "%s/file", dir);
                unlink(path);
            }
            CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "%s case %d left files behind: %s", name, c, list);
        }
        /* invalid arguments */
        rc = writer(NULL, &img, err, sizeof err);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(err, "no path") && strstr(err, what), "%s(NULL path): %d '%s'",
              name, rc, err);
        snprintf(path, sizeof path, "%s/x.img", dir);
        rc = writer(path, NULL, err, sizeof err);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && strstr(err, path) && strstr(err, "image is NULL"),
              "%s(NULL image): %d '%s'", name, rc, err);
        /* a short buffer: truncated, terminated, nothing written past err_size */
        memset(tiny, '#', sizeof tiny);
        snprintf(path, sizeof path, "%s/missing/out.img", dir);
        rc = writer(path, &img, tiny, 8);
        CHECK(t, rc == PT_ERROR_IO && strlen(tiny) == 7 && tiny[8] == '#' && tiny[15] == '#', "%s with err_size 8: '%.8s'",
              name, tiny);
        CHECK(t, writer(path, &img, NULL, 0) == PT_ERROR_IO, "%s with err NULL", name);
        /* success clears err */
        snprintf(path, sizeof path, "%s/ok.img", dir);
        memset(err, 'x', sizeof err - 1);
        err[sizeof err - 1] = '\0';
        rc = writer(path, &img, err, sizeof err);
        CHECK(t, rc == PT_OK && err[0] == '\0', "%s success: %d, message '%.40s'", name, rc, err);
        unlink(path);
    }
    pt_image_free(&img);
    tu_remove_tree(dir);
}
/* ---- display transform (pt_image_apply_display) and PNG output ---- */

/* The operators in double precision, written from their sources (Reinhard et al. 2002 eq. 3;
   Narkowicz 2016), with the clamp to [0, 1] and 0 for negative values and NaN. */
static double display_ref(double x, pt_tonemap op)
{
    double v;
    if (!(x > 0)) return 0;
    if (isinf(x)) return 1;
    v = op == PT_TONEMAP_REINHARD ? x / (1 + x)
        : op == PT_TONEMAP_ACES   ? (x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)
                                  : x;
    return v < 1 ? v : 1;
}

/* One pixel per value, run through d; returns the number of channels more than 1 float ulp
   from display_ref(x * 2^exposure), noting the first. */
static int display_mismatches(test_ctx *t, const float *vals, int n, const pt_display_desc *d, const char *what)
{
    pt_image src, dst;
    int i, bad = 0, rc;
    memset(&src, 0, sizeof src);
    memset(&dst, 0, sizeof dst);
    if (!CHECK(t, pt_image_init(&src, n, 1) == PT_OK, "pt_image_init")) return 1;
    for (i = 0; i < 3 * n; i++) src.rgb[i] = vals[i / 3];
    rc = pt_image_apply_display(&src, d, &dst);
    if (CHECK(t, rc == PT_OK && dst.rgb && dst.width == n && dst.height == 1, "%s: pt_image_apply_display: %d", what, rc))
        for (i = 0; i < 3 * n; i++) {
            double want = display_ref((double)src.rgb[i] * pow(2.0, d->exposure), d->tonemap);
            if (!(fabs(dst.rgb[i] - want) <= 1.2e-7 * fmax(want, 1e-30))) {
                if (bad++ == 0) test_note(t, "%s: %g -> %.9g, want %.9g", what, src.rgb[i], dst.rgb[i], want);
            }
        }
    else
        bad++;
    pt_image_free(&src);
    pt_image_free(&dst);
    return bad;
}

static void display_operators(test_ctx *t)
{
    /* Each operator against its formula over a range of values (to float rounding), and values
       known exactly: clamp keeps [0, 1] unchanged; Reinhard 1 -> 1/2, 3 -> 3/4; ACES 0 -> 0,
       1 -> 2.54 / 3.16, and 1 from x = 7.24 on (the root of 0.08 x^2 - 0.56 x - 0.14). */
    static const float vals[] = { -2.0f, 0.0f, 1e-6f, 0.01f, 0.18f, 0.5f, 1.0f, 3.0f, 7.0f, 7.5f, 100.0f, 1e30f };
    static const pt_tonemap ops[3] = { PT_TONEMAP_CLAMP, PT_TONEMAP_REINHARD, PT_TONEMAP_ACES };
    static const char *const names[3] = { "clamp", "reinhard", "aces" };
    const int n = (int)(sizeof vals / sizeof vals[0]);
    pt_display_desc d;
    pt_image img;
    int k, i;
    for (k = 0; k < 3; k++) {
        d.exposure = 0.0f;
        d.tonemap = ops[k];
        CHECK(t, display_mismatches(t, vals, n, &d, names[k]) == 0, "%s differs from its formula", names[k]);
    }
    memset(&img, 0, sizeof img);
    if (!CHECK(t, pt_image_init(&img, 4, 1) == PT_OK, "pt_image_init")) return;
    for (i = 0; i < 12; i++) img.rgb[i] = (float)i / 11.0f;
    d.exposure = 0.0f;
    d.tonemap = PT_TONEMAP_CLAMP;
    {
        pt_image out;
        memset(&out, 0, sizeof out);
        if (CHECK(t, pt_image_apply_display(&img, &d, &out) == PT_OK, "clamp")) {
            CHECK(t, memcmp(out.rgb, img.rgb, 12 * sizeof(float)) == 0, "clamp changed values inside [0, 1]");
            CHECK(t, pt_image_apply_display(&img, NULL, &out) == PT_OK && memcmp(out.rgb, img.rgb, 12 * sizeof(float)) == 0,
                  "d = NULL is not exposure 0, clamp");
        }
        pt_image_free(&out);
    }
    img.rgb[0] = 1.0f; img.rgb[1] = 3.0f; img.rgb[2] = -1.0f;
    img.rgb[3] = 0.0f; img.rgb[4] = 1.0f; img.rgb[5] = 8.0f;
    img.rgb[6] = (float)NAN; img.rgb[7] = (float)INFINITY; img.rgb[8] = 1e-3f;
    d.tonemap = PT_TONEMAP_REINHARD;
    if (CHECK(t, pt_image_apply_display(&img, &d, &img) == PT_OK, "reinhard in place"))
        CHECK(t, img.rgb[0] == 0.5f && img.rgb[1] == 0.75f && img.rgb[2] == 0.0f && img.rgb[6] == 0.0f && img.rgb[7] == 1.0f,
              "reinhard: 1 -> %g, 3 -> %g, -1 -> %g, NaN -> %g, inf -> %g (want 0.5 0.75 0 0 1)", img.rgb[0], img.rgb[1],
              img.rgb[2], img.rgb[6], img.rgb[7]);
    img.rgb[3] = 0.0f; img.rgb[4] = 1.0f; img.rgb[5] = 8.0f;
    d.tonemap = PT_TONEMAP_ACES;
    if (CHECK(t, pt_image_apply_display(&img, &d, &img) == PT_OK, "aces in place"))
        CHECK(t, img.rgb[3] == 0.0f && img.rgb[4] == (float)(2.54 / 3.16) && img.rgb[5] == 1.0f,
              "aces: 0 -> %g, 1 -> %.9g (want %.9g), 8 -> %g (want 1)", img.rgb[3], img.rgb[4], (float)(2.54 / 3.16),
              img.rgb[5]);
    pt_image_free(&img);
}

static void display_exposure(test_ctx *t)
{
    /* 2^EV multiplies before the operator: EV +1 doubles, EV -2 quarters (exact in float), so
       Reinhard at EV +1 maps 0.5 to 1/2 and 1.5 to 3/4; a fractional EV follows 2^EV too. A dst of
       another size is reallocated to src's. */
    static const float vals[] = { 0.0f, 0.05f, 0.25f, 0.5f, 1.0f, 1.5f, 4.0f, 300.0f };
    static const float evs[] = { 1.0f, -2.0f, 0.5f, -7.25f, 3.0f };
    const int n = (int)(sizeof vals / sizeof vals[0]);
    pt_display_desc d;
    pt_image src, dst;
    int k, op;
    for (op = 0; op < 3; op++)
        for (k = 0; k < (int)(sizeof evs / sizeof evs[0]); k++) {
            char what[64];
            d.exposure = evs[k];
            d.tonemap = (pt_tonemap)op;
            snprintf(what, sizeof what, "operator %d, EV %g", op, (double)evs[k]);
            CHECK(t, display_mismatches(t, vals, n, &d, what) == 0, "%s differs from x * 2^EV then the operator", what);
        }
    memset(&src, 0, sizeof src);
    memset(&dst, 0, sizeof dst);
    if (!CHECK(t, pt_image_init(&src, 2, 1) == PT_OK && pt_image_init(&dst, 5, 7) == PT_OK, "pt_image_init")) {
        pt_image_free(&src);
        return;
    }
    src.rgb[0] = 0.25f; src.rgb[1] = 0.5f; src.rgb[2] = 0.75f;
    src.rgb[3] = 0.5f; src.rgb[4] = 1.5f; src.rgb[5] = 0.125f;
    d.exposure = 1.0f;
    d.tonemap = PT_TONEMAP_CLAMP;
    if (CHECK(t, pt_image_apply_display(&src, &d, &dst) == PT_OK && dst.width == 2 && dst.height == 1, "EV +1 clamp"))
        CHECK(t, dst.rgb[0] == 0.5f && dst.rgb[1] == 1.0f && dst.rgb[2] == 1.0f && dst.rgb[5] == 0.25f,
              "EV +1: 0.25 -> %g, 0.5 -> %g, 0.75 -> %g, 0.125 -> %g", dst.rgb[0], dst.rgb[1], dst.rgb[2], dst.rgb[5]);
    d.exposure = -2.0f;
    if (CHECK(t, pt_image_apply_display(&src, &d, &dst) == PT_OK, "EV -2 clamp"))
        CHECK(t, dst.rgb[0] == 0.0625f && dst.rgb[4] == 0.375f, "EV -2: 0.25 -> %g, 1.5 -> %g", dst.rgb[0], dst.rgb[4]);
    d.exposure = 1.0f;
    d.tonemap = PT_TONEMAP_REINHARD;
    if (CHECK(t, pt_image_apply_display(&src, &d, &dst) == PT_OK, "EV +1 reinhard"))
        CHECK(t, dst.rgb[1] == 0.5f && dst.rgb[4] == 0.75f, "EV +1 reinhard: 0.5 -> %g, 1.5 -> %g", dst.rgb[1], dst.rgb[4]);
    pt_image_free(&src);
    pt_image_free(&dst);
}

static void display_bad_arguments(test_ctx *t)
{
    /* Non-finite exposure, an unknown tonemap, NULL or empty images: PT_ERROR_INVALID_ARGUMENT,
       and dst keeps its size and values. */
    pt_display_desc d;
    pt_image src, dst, empty;
    int k;
    memset(&src, 0, sizeof src);
    memset(&dst, 0, sizeof dst);
    memset(&empty, 0, sizeof empty);
    if (!CHECK(t, pt_image_init(&src, 2, 2) == PT_OK && pt_image_init(&dst, 2, 2) == PT_OK, "pt_image_init")) {
        pt_image_free(&src);
        return;
    }
    for (k = 0; k < 12; k++) {
        src.rgb[k] = 0.5f;
        dst.rgb[k] = 0.25f;
    }
    d.tonemap = PT_TONEMAP_CLAMP;
    d.exposure = (float)NAN;
    CHECK(t, pt_image_apply_display(&src, &d, &dst) == PT_ERROR_INVALID_ARGUMENT, "NaN exposure accepted");
    d.exposure = (float)INFINITY;
    CHECK(t, pt_image_apply_display(&src, &d, &dst) == PT_ERROR_INVALID_ARGUMENT, "+inf exposure accepted");
    d.exposure = -(float)INFINITY;
    CHECK(t, pt_image_apply_display(&src, &d, &dst) == PT_ERROR_INVALID_ARGUMENT, "-inf exposure accepted");
    d.exposure = 0.0f;
    d.tonemap = (pt_tonemap)3;
    CHECK(t, pt_image_apply_display(&src, &d, &dst) == PT_ERROR_INVALID_ARGUMENT, "tonemap 3 accepted");
    d.tonemap = (pt_tonemap)-1;
    CHECK(t, pt_image_apply_display(&src, &d, &dst) == PT_ERROR_INVALID_ARGUMENT, "tonemap -1 accepted");
    d.tonemap = PT_TONEMAP_ACES;
    CHECK(t, pt_image_apply_display(NULL, &d, &dst) == PT_ERROR_INVALID_ARGUMENT, "src NULL accepted");
    CHECK(t, pt_image_apply_display(&src, &d, NULL) == PT_ERROR_INVALID_ARGUMENT, "dst NULL accepted");
    CHECK(t, pt_image_apply_display(&empty, &d, &dst) == PT_ERROR_INVALID_ARGUMENT, "an empty src accepted");
    empty.width = 2;
    empty.height = 2;
    CHECK(t, pt_image_apply_display(&empty, &d, &dst) == PT_ERROR_INVALID_ARGUMENT, "src with rgb NULL accepted");
    for (k = 0; k < 12; k++)
        if (dst.rgb[k] != 0.25f) break;
    CHECK(t, k == 12 && dst.width == 2 && dst.height == 2, "a refused call changed dst (value %d)", k);
    pt_image_free(&src);
    pt_image_free(&dst);
}

#ifdef PDFTRACE_PNG
/* Reads an 8-bit RGB PNG with libpng's simplified API into a malloc'd buffer. */
static unsigned char *read_png_rgb(const char *path, int *w, int *h)
{
    png_image im;
    unsigned char *buf;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&im, path)) return NULL;
    im.format = PNG_FORMAT_RGB;
    buf = (unsigned char *)malloc(PNG_IMAGE_SIZE(im));
    if (!buf || !png_image_finish_read(&im, NULL, buf, 0, NULL)) {
        png_image_free(&im);
        free(buf);
        return NULL;
    }
    *w = (int)im.width;
    *h = (int)im.height;
    return buf;
}

static void png_round_trip(test_ctx *t)
{
    /* pt_write_png then libpng's reader: the size, and every byte equal to what pt_write_ppm
       writes, (unsigned char)(255 pt_srgb_encode(x) + 0.5); the PNG signature and an sRGB chunk;
       pt_write_png_rgb8 keeps bytes as given; no temporary file is left; a missing directory and a
       directory as the target are PT_ERROR_IO with the path, the step and strerror in the message. */
    static const float vals[] = { -1.0f, 0.0f, 0.001f, 0.0031308f, 0.01f, 0.05f, 0.18f, 0.2140411f, 0.5f, 0.9f, 0.999f, 1.0f, 1.5f, 100.0f, 0.73f };
    static const unsigned char sig[8] = { 137, 80, 78, 71, 13, 10, 26, 10 };
    const int w = 5, h = 3;
    char dir[64], path[128], err[512], list[256];
    pt_image img;
    unsigned char *px, *file, raw[6] = { 0, 1, 127, 128, 254, 255 };
    long n = 0;
    int i, rw = 0, rh = 0, bad = 0, rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/a.png", dir);
    memset(&img, 0, sizeof img);
    if (!CHECK(t, pt_image_init(&img, w, h) == PT_OK, "pt_image_init")) { tu_remove_tree(dir); return; }
    for (i = 0; i < 3 * w * h; i++) img.rgb[i] = vals[(i % 3 * 5 + i / 3) % 15];
    rc = pt_write_png(path, &img, err, sizeof err);
    CHECK(t, rc == PT_OK && err[0] == '\0', "pt_write_png: %d '%s'", rc, err);
    px = read_png_rgb(path, &rw, &rh);
    if (CHECK(t, px != NULL && rw == w && rh == h, "read back: %s, %d x %d", px ? "ok" : "failed", rw, rh)) {
        for (i = 0; i < 3 * w * h; i++)
            if (px[i] != (unsigned char)(pt_srgb_encode(img.rgb[i]) * 255.0f + 0.5f)) {
                if (bad++ == 0) test_note(t, "value %g -> byte %d", img.rgb[i], px[i]);
            }
        CHECK(t, bad == 0, "%d bytes differ from 255 pt_srgb_encode(x) + 0.5", bad);
    }
    free(px);
    file = tu_read_file(path, &n);
    CHECK(t, file && n > 41 && memcmp(file, sig, 8) == 0 && memcmp(file + 12, "IHDR", 4) == 0 && memcmp(file + 37, "sRGB", 4) == 0,
          "no PNG signature, IHDR and sRGB chunk at the start of the file");
    free(file);
    rc = pt_write_png_rgb8(path, 2, 1, raw, err, sizeof err);
    px = read_png_rgb(path, &rw, &rh);
    CHECK(t, rc == PT_OK && px && rw == 2 && rh == 1 && memcmp(px, raw, 6) == 0, "pt_write_png_rgb8 did not keep its bytes");
    free(px);
    CHECK(t, tu_dir_entries(dir, list, sizeof list) == 1, "the writer left extra files: %s", list);
    snprintf(path, sizeof path, "%s/missing/b.png", dir);
    rc = pt_write_png(path, &img, err, sizeof err);
    {
        char want[512];
        char after[256];
        snprintf(want, sizeof want, "%s: writing PNG: cannot create '", path);
        snprintf(after, sizeof after, "': %s", strerror(ENOENT));
        CHECK(t, rc == PT_ERROR_IO && tmp_message(err, want, path, after), "missing directory: %d '%s'", rc, err);
    }
    snprintf(path, sizeof path, "%s/target.png", dir);
    mkdir(path, 0700);
    rc = pt_write_png(path, &img, err, sizeof err);
    {
        char want[512];
        char after[256];
        snprintf(want, sizeof want, "%s: writing PNG: cannot rename '", path);
        snprintf(after, sizeof after, "' to '%s': %s", path, strerror(EISDIR));
        CHECK(t, rc == PT_ERROR_IO && tmp_message(err, want, path, after), "a directory as the target: %d '%s'", rc, err);
    }
    rmdir(path);
    CHECK(t, pt_write_png(path, NULL, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT && err[0], "NULL image accepted");
    CHECK(t, tu_dir_entries(dir, list, sizeof list) == 1, "failed writes left files: %s", list);
    pt_image_free(&img);
    tu_remove_tree(dir);
}
#else
static void png_round_trip(test_ctx *t)
{
    test_skip(t, "built without libpng (pdftrace_png.h needs PNG=1 or libpng-dev with PNG=auto)");
}
#endif

typedef int (*tu_writer)(const char *, const pt_image *, char *, size_t);
static int write_png_or_skip(const char *path, const pt_image *img, char *err, size_t n)
{
#ifdef PDFTRACE_PNG
    return pt_write_png(path, img, err, n);
#else
    (void)path; (void)img; (void)err; (void)n;
    return -1000;
#endif
}

/* A symlink planted at the old temporary name "<path>.ptmp" is not followed: its target keeps its
   bytes (each writer used to overwrite it), and the written file has mode 0666 less the umask. */
static void temporary_symlink_not_followed(test_ctx *t)
{
    static const tu_writer writers[3] = { pt_write_pfm_ex, pt_write_ppm_ex, write_png_or_skip };
    static const char *const names[3] = { "out.pfm", "out.ppm", "out.png" };
    char dir[64], path[160], link[200], victim[160], err[1024], list[256];
    pt_image img;
    mode_t old = umask(022);
    int k, ran = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) { umask(old); return; }
    memset(&img, 0, sizeof img);
    CHECK(t, pt_image_init(&img, 4, 3) == PT_OK, "pt_image_init");
    for (k = 0; k < 3 && img.rgb; ++k) {
        unsigned char *v;
        long n = 0;
        struct stat st;
        FILE *f;
        int rc;
        snprintf(victim, sizeof victim, "%s/victim", dir);
        snprintf(path, sizeof path, "%s/%s", dir, names[k]);
        snprintf(link, sizeof link, "%s.ptmp", path);
        f = fopen(victim, "wb");
        if (f) { fputs("keep", f); fclose(f); }
        CHECK(t, symlink(victim, link) == 0, "symlink %s", link);
        rc = writers[k](path, &img, err, sizeof err);
        if (rc != -1000) {
            ran++;
            CHECK(t, rc == PT_OK, "%s: %d '%s'", names[k], rc, err);
            v = tu_read_file(victim, &n);
            CHECK(t, v && n == 4 && memcmp(v, "keep", 4) == 0, "%s: the symlink's target was overwritten (%ld bytes)",
                  names[k], n);
            free(v);
            CHECK(t, lstat(link, &st) == 0 && S_ISLNK(st.st_mode), "%s: the planted symlink was replaced", names[k]);
            CHECK(t, stat(path, &st) == 0 && (st.st_mode & 0777) == 0644, "%s: mode %o, want 644 under umask 022",
                  names[k], (unsigned)(st.st_mode & 0777));
        }
        unlink(link);
        unlink(path);
        unlink(victim);
    }
    CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "files left: %s", list);
    test_note(t, "%d writers (PNG %s)", ran, ran == 3 ? "included" : "not built");
    umask(old);
    pt_image_free(&img);
    tu_remove_tree(dir);
}

/* pt_output_remove_temporaries (the command's SIGINT/SIGTERM handler calls it) removes the
   temporaries that are open; pt_output_close then reports the failed rename and writes nothing. */
static void temporaries_removed_by_hook(test_ctx *t)
{
    pt_output_file a, b;
    char dir[64], pa[160], pb[160], err[1024], list[256];
    struct stat st;
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(pa, sizeof pa, "%s/a.pfm", dir);
    snprintf(pb, sizeof pb, "%s/b.pfm", dir);
    rc = pt_output_open(&a, pa, 0, "test", err, sizeof err);
    CHECK(t, rc == PT_OK && a.file && a.tmp_path, "open a: %d '%s'", rc, err);
    rc = pt_output_open(&b, pb, 1, "test", err, sizeof err);
    CHECK(t, rc == PT_OK && b.file && b.tmp_path, "open b: %d '%s'", rc, err);
    if (rc == PT_OK && a.tmp_path) {
        fputs("x", a.file);
        CHECK(t, stat(a.tmp_path, &st) == 0 && tu_dir_entries(dir, NULL, 0) == 2, "the temporaries do not exist");
        pt_output_remove_temporaries();
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "left after the hook: %s", list);
        rc = pt_output_close(&a, 1, "test", err, sizeof err);
        CHECK(t, rc == PT_ERROR_IO && strstr(err, "cannot rename") && strstr(err, strerror(ENOENT)), "close a: %d '%s'", rc, err);
        rc = pt_output_close(&b, 1, "test", err, sizeof err);
        CHECK(t, rc == PT_ERROR_IO, "close b: %d", rc);
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "files after closing: %s", list);
    }
    /* a closed output is no longer removed by the hook */
    rc = pt_output_open(&a, pa, 0, "test", err, sizeof err);
    if (CHECK(t, rc == PT_OK, "open: '%s'", err)) {
        rc = pt_output_close(&a, 1, "test", err, sizeof err);
        pt_output_remove_temporaries();
        CHECK(t, rc == PT_OK && stat(pa, &st) == 0, "a closed output was removed: %d '%s'", rc, err);
    }
    tu_remove_tree(dir);
}

/* A write that fails for lack of room names the path, the temporary and the system's reason. The
   writers never write in place (a temporary, then rename), so /dev/full cannot be their target:
   a child process with RLIMIT_FSIZE of 1000 bytes (SIGXFSZ ignored: write fails with EFBIG)
   stands for a full disk. */
static void write_error_disk_full(test_ctx *t)
{
    static const tu_writer writers[3] = { pt_write_pfm_ex, pt_write_ppm_ex, write_png_or_skip };
    static const char *const names[3] = { "PFM", "PPM", "PNG" };
    char dir[64], path[160], err[1024], list[256];
    pt_image img;
    int k, ran = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    memset(&img, 0, sizeof img);
    CHECK(t, pt_image_init(&img, 200, 200) == PT_OK, "pt_image_init");
    for (k = 0; k < 40000 * 3 && img.rgb; ++k) img.rgb[k] = (float)((k * 7919) % 1000) / 999.0f; /* little to compress */
    for (k = 0; k < 3 && img.rgb; ++k) {
        int fds[2], status = 0, rc;
        ssize_t got;
        pid_t pid;
        snprintf(path, sizeof path, "%s/out.img", dir);
        if (!CHECK(t, pipe(fds) == 0, "pipe")) break;
        pid = fork();
        if (pid == 0) {
            struct rlimit rl;
            close(fds[0]);
            signal(SIGXFSZ, SIG_IGN);
            rl.rlim_cur = rl.rlim_max = 1000;
            setrlimit(RLIMIT_FSIZE, &rl);
            err[0] = '\0';
            rc = writers[k](path, &img, err, sizeof err);
            if (write(fds[1], &rc, sizeof rc) < 0 || write(fds[1], err, strlen(err) + 1) < 0) _exit(2);
            _exit(0);
        }
        close(fds[1]);
        rc = 0;
        memset(err, 0, sizeof err);
        got = read(fds[0], &rc, sizeof rc);
        if (got == (ssize_t)sizeof rc) {
            ssize_t m = read(fds[0], err, sizeof err - 1);
            if (m < 0) err[0] = '\0';
        }
        close(fds[0]);
        waitpid(pid, &status, 0);
        if (rc == -1000) continue;
        ran++;
        CHECK(t, got == (ssize_t)sizeof rc && rc == PT_ERROR_IO && strncmp(err, path, strlen(path)) == 0 &&
                     strstr(err, names[k]) && strstr(err, ".ptmp'") && strstr(err, strerror(EFBIG)),
              "%s: %d '%s' (want the path, the temporary and '%s')", names[k], rc, err, strerror(EFBIG));
        CHECK(t, tu_dir_entries(dir, list, sizeof list) == 0, "%s: files left: %s", names[k], list);
    }
    test_note(t, "%d writers; e.g. '%s'", ran, err);
    pt_image_free(&img);
    tu_remove_tree(dir);
}

const test_case test_output_cases[] = {
    TEST_CASE(pfm_layout),
    TEST_CASE(pfm_read),
    TEST_CASE(ppm_srgb),
    TEST_CASE(srgb_encode_function),
    TEST_CASE(write_errors),
    TEST_CASE(write_error_messages),
    TEST_CASE(film_math),
    TEST_CASE(film_accumulates_render),
    TEST_CASE(display_operators),
    TEST_CASE(display_exposure),
    TEST_CASE(display_bad_arguments),
    TEST_CASE(png_round_trip),
    TEST_CASE(temporary_symlink_not_followed),
    TEST_CASE(temporaries_removed_by_hook),
    TEST_CASE(write_error_disk_full),
    TEST_END
};
