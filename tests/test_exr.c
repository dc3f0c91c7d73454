#define _POSIX_C_SOURCE 200809L
/* test_exr.c - pdftrace_exr.h: OpenEXR output and input (only with PDFTRACE_OPENEXR;
   built by `make OPENEXR=1`, run alone by `make exr-test`). Without it the section has one test,
   skipped (test_skip), that says the EXR code is not compiled in.
   References: IEEE 754-2008 binary16 (round to nearest, ties to even; subnormals in steps of
   2^-24, largest finite 65504); the OpenEXR file layout and OpenEXRCore API
   (https://openexr.com/en/latest/OpenEXRFileLayout.html, https://openexr.com/en/latest/API.html). */
#include "test_util.h"

#include <stdio.h>
#include <string.h>

#ifndef PDFTRACE_OPENEXR

static void not_compiled(test_ctx *t)
{
    test_skip(t, "OpenEXR support is not compiled in (make OPENEXR=1 or make exr-test)");
}

const test_case test_exr_cases[] = {
    TEST_CASE(not_compiled),
    TEST_END
};

#else /* PDFTRACE_OPENEXR */

#include "pdftrace_exr.h"
#include <openexr.h>
#include <dirent.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

/* ---- files ---- */
static int exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}
static int spit(const char *path, const unsigned char *buf, long n)
{
    FILE *f = fopen(path, "wb");
    int ok;
    if (!f) return 0;
    ok = fwrite(buf, 1, (size_t)n, f) == (size_t)n;
    return (fclose(f) == 0) && ok;
}

/* ---- the reference rounding: binary16 round-to-nearest-even computed in double (own code,
   independent of the library's bit manipulation). Valid for |x| < 65520. */
static double ref_half(double x)
{
    double a = fabs(x), ulp, r;
    int k;
    if (a == 0.0) return x;
    (void)frexp(a, &k); /* a = f 2^k, f in [0.5, 1): exponent e = k - 1 */
    ulp = k - 1 < -14 ? ldexp(1.0, -24) : ldexp(1.0, k - 1 - 10);
    r = a / ulp;
    {   /* ties to even without depending on the FP rounding mode */
        double fl = floor(r), frac = r - fl;
        if (frac > 0.5 || (frac == 0.5 && fmod(fl, 2.0) != 0.0)) fl += 1.0;
        r = fl * ulp;
    }
    return x < 0 ? -r : r;
}

/* 37 x 23: a gradient, HDR values up to 6e4, tiny (half-subnormal) values, zeros, negatives. */
static int make_test_image(pt_image *img, int w, int h)
{
    int x, y, c;
    if (pt_image_init(img, w, h) != PT_OK) return 0;
    for (y = 0; y < h; ++y)
        for (x = 0; x < w; ++x)
            for (c = 0; c < 3; ++c) {
                float *p = &img->rgb[3 * ((size_t)y * (size_t)w + (size_t)x) + (size_t)c];
                double g = (double)(x + 1) / w * (double)(y + 1) / h;
                switch ((x + 3 * y + c) % 7) {
                case 0: *p = (float)g; break;                            /* gradient [0, 1] */
                case 1: *p = (float)(1.0 + 6e4 * g * g); break;          /* HDR, up to 6e4 */
                case 2: *p = (float)(3e-8 * (1 + x) * (1 + c)); break;   /* half subnormals */
                case 3: *p = 0.0f; break;
                case 4: *p = (float)(1e-4 * (y + 1) + 1e-6 * x); break; /* small normals */
                case 5: *p = (float)(-g * 7.25); break;                  /* negative */
                default: *p = (float)(g * 1000.0 + 0.3); break;
                }
            }
    return 1;
}

static int image_empty(const pt_image *img) { return img->width == 0 && img->height == 0 && img->rgb == NULL; }

static void round_trip_one(test_ctx *t, const char *dir, pt_exr_pixel_type pt, pt_exr_compression cp, const char *label)
{
    pt_image a = { 0, 0, NULL }, b = { 0, 0, NULL };
    pt_exr_options o;
    char path[600], err[512];
    size_t i, n;
    int rc, bad = 0;
    double worst = 0.0;
    o.pixel_type = pt;
    o.compression = cp;
    snprintf(path, sizeof path, "%s/rt-%s.exr", dir, label);
    if (!CHECK(t, make_test_image(&a, 37, 23), "%s: image", label)) return;
    rc = pt_write_exr(path, &a, &o, err, sizeof err);
    if (!CHECK(t, rc == PT_OK && err[0] == '\0', "%s: write rc %d '%s'", label, rc, err)) goto done;
    rc = pt_read_exr(path, &b, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "%s: read rc %d '%s'", label, rc, err)) goto done;
    if (!CHECK(t, b.width == 37 && b.height == 23 && b.rgb, "%s: size %dx%d", label, b.width, b.height)) goto done;
    n = 3u * 37u * 23u;
    if (pt == PT_EXR_FLOAT) {
        CHECK(t, memcmp(a.rgb, b.rgb, n * sizeof(float)) == 0, "%s: float data not bit-exact", label);
    } else {
        for (i = 0; i < n; ++i) {
            double x = a.rgb[i], r = b.rgb[i], want = ref_half(x), tol = fmax(fabs(x) * ldexp(1.0, -11), ldexp(1.0, -25));
            if (r != want || fabs(r - x) > tol) {
                if (bad++ == 0) CHECK(t, 0, "%s: value %zu: %.9g read as %.9g, want %.9g", label, i, x, r, want);
            }
            if (x != 0.0 && fabs(x) >= ldexp(1.0, -14)) worst = fmax(worst, fabs(r - x) / fabs(x));
        }
        CHECK(t, bad == 0, "%s: %d half values off", label, bad);
        CHECK(t, worst <= ldexp(1.0, -11), "%s: worst relative error %.3g > 2^-11", label, worst);
    }
    test_note(t, "%s ok", label);
done:
    pt_image_free(&a);
    pt_image_free(&b);
}

static void round_trip(test_ctx *t)
{
    char dir[64];
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    round_trip_one(t, dir, PT_EXR_HALF, PT_EXR_ZIP, "half-zip");
    round_trip_one(t, dir, PT_EXR_HALF, PT_EXR_PIZ, "half-piz");
    round_trip_one(t, dir, PT_EXR_FLOAT, PT_EXR_ZIP, "float-zip");
    round_trip_one(t, dir, PT_EXR_FLOAT, PT_EXR_PIZ, "float-piz");
    round_trip_one(t, dir, PT_EXR_HALF, PT_EXR_NONE, "half-none");
    round_trip_one(t, dir, PT_EXR_FLOAT, PT_EXR_NONE, "float-none");
    CHECK(t, tu_dir_entries(dir, NULL, 0) == 6, "expected 6 files (no temporaries), found %d", tu_dir_entries(dir, NULL, 0));
    tu_remove_tree(dir);
}

/* Exact binary16 cases: rounding at the top of the range, ties, subnormals, inf, NaN. */
static void half_rounding(test_ctx *t)
{
    static const struct { float in, want; } cases[] = {
        { 65504.0f, 65504.0f },               /* largest half */
        { 65519.0f, 65504.0f },               /* below the midpoint */
        { 1.0f + 1.0f / 2048.0f, 1.0f },      /* tie: to even (down) */
        { 1.0f + 3.0f / 2048.0f, 1.0f + 4.0f / 2048.0f }, /* tie: to even (up) */
        { 5.9604645e-8f, 5.9604645e-8f },     /* 2^-24, smallest subnormal */
        { 2.9802322e-8f, 0.0f },              /* 2^-25: tie to zero */
        { 4.4703484e-8f, 5.9604645e-8f },     /* 1.5 * 2^-25: up to 2^-24 */
        { 6.1035156e-5f, 6.1035156e-5f },     /* 2^-14, smallest normal */
        { 6.1020255e-5f, 6.1035156e-5f },     /* just below 2^-14: rounds up to the normal */
        { -2.5f, -2.5f },
        { 1e-30f, 0.0f },
    };
    const int n = (int)(sizeof cases / sizeof cases[0]);
    pt_image a = { 0, 0, NULL }, b = { 0, 0, NULL };
    char dir[64], path[128], err[512];
    int i, rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/h.exr", dir);
    if (!CHECK(t, pt_image_init(&a, n + 3, 1) == PT_OK, "init")) goto done;
    for (i = 0; i < n; ++i) a.rgb[3 * i] = a.rgb[3 * i + 1] = a.rgb[3 * i + 2] = cases[i].in;
    a.rgb[3 * n] = 65520.0f;      /* midpoint to 2^16: to infinity */
    a.rgb[3 * n + 1] = -1e10f;    /* -infinity */
    a.rgb[3 * n + 2] = 0.0f;
    a.rgb[3 * n + 3] = (float)NAN;
    a.rgb[3 * n + 6] = (float)INFINITY;
    rc = pt_write_exr(path, &a, NULL, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "write rc %d %s", rc, err)) goto done;
    rc = pt_read_exr(path, &b, err, sizeof err);
    if (!CHECK(t, rc == PT_OK && b.width == n + 3, "read rc %d %s", rc, err)) goto done;
    for (i = 0; i < n; ++i)
        CHECK(t, b.rgb[3 * i] == cases[i].want && b.rgb[3 * i + 2] == cases[i].want, "%.9g -> %.9g, want %.9g",
              (double)cases[i].in, (double)b.rgb[3 * i], (double)cases[i].want);
    CHECK(t, isinf(b.rgb[3 * n]) && b.rgb[3 * n] > 0, "65520 -> %g, want +inf", (double)b.rgb[3 * n]);
    CHECK(t, isinf(b.rgb[3 * n + 1]) && b.rgb[3 * n + 1] < 0, "-1e10 -> %g, want -inf", (double)b.rgb[3 * n + 1]);
    CHECK(t, isnan(b.rgb[3 * n + 3]), "NaN -> %g", (double)b.rgb[3 * n + 3]);
    CHECK(t, isinf(b.rgb[3 * n + 6]), "inf -> %g", (double)b.rgb[3 * n + 6]);
    test_note(t, "%d exact cases, inf, NaN", n);
done:
    pt_image_free(&a);
    pt_image_free(&b);
    tu_remove_tree(dir);
}

/* A file written with OpenEXRCore directly: channels A (half), B (uint), G (float), R (half),
   data window starting at (5, 7), 16 lines per chunk with ZIP. pdftrace must map by name. */
static int write_rgba_direct(const char *path, int w, int h, uint16_t *hr, float *fg, uint32_t *ub, uint16_t *ha)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    exr_attr_box2i_t dw;
    int part = 0, y, c, ready = 0;
    int32_t spc = 0;
    exr_result_t rv;
    init.error_handler_fn = NULL;
    rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS) rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    if (rv == EXR_ERR_SUCCESS) rv = exr_initialize_required_attr_simple(ctx, part, w, h, EXR_COMPRESSION_ZIP);
    dw.min.x = 5; dw.min.y = 7; dw.max.x = 5 + w - 1; dw.max.y = 7 + h - 1;
    if (rv == EXR_ERR_SUCCESS) rv = exr_set_data_window(ctx, part, &dw);
    if (rv == EXR_ERR_SUCCESS) rv = exr_add_channel(ctx, part, "R", EXR_PIXEL_HALF, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    if (rv == EXR_ERR_SUCCESS) rv = exr_add_channel(ctx, part, "G", EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    if (rv == EXR_ERR_SUCCESS) rv = exr_add_channel(ctx, part, "B", EXR_PIXEL_UINT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
    if (rv == EXR_ERR_SUCCESS) rv = exr_add_channel(ctx, part, "A", EXR_PIXEL_HALF, EXR_PERCEPTUALLY_LINEAR, 1, 1);
    if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctx);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_scanlines_per_chunk(ctx, part, &spc);
    for (y = dw.min.y; rv == EXR_ERR_SUCCESS && y <= dw.max.y; y += spc) {
        exr_chunk_info_t ci;
        size_t row;
        rv = exr_write_scanline_chunk_info(ctx, part, y, &ci);
        if (rv != EXR_ERR_SUCCESS) break;
        row = (size_t)(ci.start_y - dw.min.y) * (size_t)w;
        rv = ready ? exr_encoding_update(ctx, part, &ci, &enc) : exr_encoding_initialize(ctx, part, &ci, &enc);
        if (rv != EXR_ERR_SUCCESS) break;
        for (c = 0; c < enc.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            char nm = ch->channel_name[0];
            ch->user_pixel_stride = nm == 'R' || nm == 'A' ? 2 : 4;
            ch->user_bytes_per_element = (int16_t)ch->user_pixel_stride;
            ch->user_line_stride = ch->user_pixel_stride * w;
            ch->user_data_type = ch->data_type;
            ch->encode_from_ptr = nm == 'R' ? (const uint8_t *)(hr + row) : nm == 'G' ? (const uint8_t *)(fg + row)
                                  : nm == 'B' ? (const uint8_t *)(ub + row) : (const uint8_t *)(ha + row);
        }
        if (!ready) rv = exr_encoding_choose_default_routines(ctx, part, &enc);
        ready = 1;
        if (rv == EXR_ERR_SUCCESS) rv = exr_encoding_run(ctx, part, &enc);
    }
    if (ready) exr_encoding_destroy(ctx, &enc);
    if (ctx) { exr_result_t fr = exr_finish(&ctx); if (rv == EXR_ERR_SUCCESS) rv = fr; }
    return rv == EXR_ERR_SUCCESS;
}

static void rgba_written_by_library(test_ctx *t)
{
    enum { W = 29, H = 41 };
    static uint16_t hr[W * H], ha[W * H];
    static float fg[W * H];
    static uint32_t ub[W * H];
    pt_image b = { 0, 0, NULL };
    char dir[64], path[128], err[512];
    int i, rc, bad = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(path, sizeof path, "%s/rgba.exr", dir);
    for (i = 0; i < W * H; ++i) {
        hr[i] = (uint16_t)(0x3c00u + (unsigned)i % 1024u); /* 1 + (i mod 1024)/1024 as half */
        fg[i] = (float)i * 0.001f + 1e-7f;
        ub[i] = (uint32_t)(i * 37);
        ha[i] = 0x3800u; /* 0.5 */
    }
    if (!CHECK(t, write_rgba_direct(path, W, H, hr, fg, ub, ha), "writing the RGBA file with OpenEXRCore failed")) goto done;
    rc = pt_read_exr(path, &b, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "read rc %d '%s'", rc, err)) goto done;
    if (!CHECK(t, b.width == W && b.height == H, "size %dx%d, want %dx%d", b.width, b.height, W, H)) goto done;
    for (i = 0; i < W * H; ++i) {
        float r = 1.0f + (float)(i % 1024) / 1024.0f;
        if (b.rgb[3 * i] != r || b.rgb[3 * i + 1] != fg[i] || b.rgb[3 * i + 2] != (float)ub[i]) {
            if (bad++ == 0)
                CHECK(t, 0, "pixel %d: (%g %g %g), want (%g %g %g)", i, (double)b.rgb[3 * i], (double)b.rgb[3 * i + 1],
                      (double)b.rgb[3 * i + 2], (double)r, (double)fg[i], (double)ub[i]);
        }
    }
    CHECK(t, bad == 0, "%d pixels wrong", bad);
    test_note(t, "A/B/G/R = half/uint/float/half, data window at (5, 7)");
done:
    pt_image_free(&b);
    tu_remove_tree(dir);
}

static void expect_read_error(test_ctx *t, const char *path, const char *what)
{
    pt_image b;
    char err[512];
    int rc;
    b.width = 3; b.height = 4; b.rgb = NULL; /* must come back empty */
    err[0] = '\0';
    rc = pt_read_exr(path, &b, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO, "%s: rc %d (%s), want PT_ERROR_IO", what, rc, pt_result_string(rc));
    CHECK(t, image_empty(&b), "%s: image not left empty (%dx%d)", what, b.width, b.height);
    CHECK(t, err[0] != '\0' && strstr(err, path) != NULL, "%s: message '%s' does not name the file", what, err);
    if (rc == PT_OK) pt_image_free(&b);
}

static void bad_files(test_ctx *t)
{
    pt_image a = { 0, 0, NULL };
    pt_exr_options o;
    unsigned char *buf = NULL;
    char dir[64], good[128], path[128], err[512];
    long size = 0, i;
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    snprintf(good, sizeof good, "%s/good.exr", dir);
    if (!CHECK(t, make_test_image(&a, 64, 48), "image")) goto done;
    o.pixel_type = PT_EXR_HALF;
    o.compression = PT_EXR_ZIP;
    rc = pt_write_exr(good, &a, &o, err, sizeof err);
    if (!CHECK(t, rc == PT_OK, "write rc %d %s", rc, err)) goto done;
    buf = tu_read_file(good, &size);
    if (!CHECK(t, buf && size > 400, "reading back %s", good)) goto done;

    /* corrupt: 64 bytes inverted in the middle of the pixel data */
    snprintf(path, sizeof path, "%s/corrupt.exr", dir);
    for (i = size / 2; i < size / 2 + 64 && i < size; ++i) buf[i] ^= 0xffu;
    CHECK(t, spit(path, buf, size), "writing %s", path);
    expect_read_error(t, path, "corrupt");
    for (i = size / 2; i < size / 2 + 64 && i < size; ++i) buf[i] ^= 0xffu;

    /* truncated at half */
    snprintf(path, sizeof path, "%s/truncated.exr", dir);
    CHECK(t, spit(path, buf, size / 2), "writing %s", path);
    expect_read_error(t, path, "truncated");
    /* only the header's first bytes */
    snprintf(path, sizeof path, "%s/stub.exr", dir);
    CHECK(t, spit(path, buf, 10), "writing %s", path);
    expect_read_error(t, path, "10-byte stub");
    /* not an EXR */
    snprintf(path, sizeof path, "%s/not.exr", dir);
    CHECK(t, spit(path, (const unsigned char *)"PF\n2 2\n-1.0\n................", 28), "writing %s", path);
    expect_read_error(t, path, "not an EXR");
    /* empty and missing */
    snprintf(path, sizeof path, "%s/empty.exr", dir);
    CHECK(t, spit(path, buf, 0), "writing %s", path);
    expect_read_error(t, path, "empty");
    snprintf(path, sizeof path, "%s/missing.exr", dir);
    expect_read_error(t, path, "missing");
    {
        pt_image b = { 0, 0, NULL };
        rc = pt_read_exr(NULL, &b, err, sizeof err);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT && image_empty(&b), "NULL path: rc %d", rc);
        rc = pt_read_exr(good, NULL, NULL, 0);
        CHECK(t, rc == PT_ERROR_INVALID_ARGUMENT, "NULL image: rc %d", rc);
        rc = pt_read_exr(good, &b, NULL, 0); /* no message buffer: fine */
        CHECK(t, rc == PT_OK && b.width == 64, "good file without err buffer: rc %d", rc);
        pt_image_free(&b);
    }
    test_note(t, "corrupt, truncated, stub, non-EXR, empty, missing: PT_ERROR_IO with a message");
done:
    free(buf);
    pt_image_free(&a);
    tu_remove_tree(dir);
}

static void write_errors(test_ctx *t)
{
    pt_image a = { 0, 0, NULL }, none = { 0, 0, NULL };
    pt_exr_options o;
    char dir[64], path[160], tmp[200], err[512];
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    if (!CHECK(t, make_test_image(&a, 8, 5), "image")) goto done;
    snprintf(path, sizeof path, "%s/no/such/dir/x.exr", dir);
    rc = pt_write_exr(path, &a, NULL, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && err[0], "unwritable path: rc %d '%s'", rc, err);
    CHECK(t, !exists(path), "unwritable path: file exists");
    /* the target is a directory: the temporary file is written, the rename fails, and it is removed */
    snprintf(path, sizeof path, "%s/sub", dir);
    CHECK(t, mkdir(path, 0700) == 0, "mkdir");
    snprintf(tmp, sizeof tmp, "%s.ptmp", path);
    rc = pt_write_exr(path, &a, NULL, err, sizeof err);
    CHECK(t, rc == PT_ERROR_IO && err[0], "directory as target: rc %d '%s'", rc, err);
    CHECK(t, !exists(tmp), "directory as target: %s left behind", tmp);
    rmdir(path);
    CHECK(t, tu_dir_entries(dir, NULL, 0) == 0, "%d files left in %s", tu_dir_entries(dir, NULL, 0), dir);
    /* bad arguments */
    snprintf(path, sizeof path, "%s/ok.exr", dir);
    CHECK(t, pt_write_exr(path, &none, NULL, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT, "empty image accepted");
    CHECK(t, pt_write_exr(NULL, &a, NULL, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT, "NULL path accepted");
    CHECK(t, pt_write_exr("", &a, NULL, NULL, 0) == PT_ERROR_INVALID_ARGUMENT, "empty path accepted");
    o.pixel_type = (pt_exr_pixel_type)7;
    o.compression = PT_EXR_ZIP;
    CHECK(t, pt_write_exr(path, &a, &o, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT, "bad pixel type accepted");
    o.pixel_type = PT_EXR_FLOAT;
    o.compression = (pt_exr_compression)9;
    CHECK(t, pt_write_exr(path, &a, &o, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT, "bad compression accepted");
    CHECK(t, !exists(path), "a rejected write left %s", path);
    /* replacing an existing file works */
    CHECK(t, pt_write_exr(path, &a, NULL, err, sizeof err) == PT_OK, "write: %s", err);
    CHECK(t, pt_write_exr(path, &a, NULL, err, sizeof err) == PT_OK, "rewrite: %s", err);
    CHECK(t, tu_dir_entries(dir, NULL, 0) == 1, "%d files after rewriting", tu_dir_entries(dir, NULL, 0));
done:
    pt_image_free(&a);
    tu_remove_tree(dir);
}

/* pt_read_exr_memory: the same pixels as pt_read_exr from the file's bytes (float and half),
   every truncation of a small file fails cleanly, a header asking for more than
   PDFTRACE_EXR_MAX_PIXELS is refused before allocating, bad arguments. */
static void memory_reader(test_ctx *t)
{
    pt_image a = { 0, 0, NULL }, f = { 0, 0, NULL }, m = { 0, 0, NULL };
    pt_exr_options o;
    unsigned char *buf = NULL;
    char dir[64], path[128], err[512];
    long size = 0, cut;
    int rc, k, bad = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    if (!CHECK(t, make_test_image(&a, 13, 37), "image")) goto done;
    for (k = 0; k < 2; ++k) {
        o.pixel_type = k ? PT_EXR_HALF : PT_EXR_FLOAT;
        o.compression = k ? PT_EXR_PIZ : PT_EXR_ZIP;
        snprintf(path, sizeof path, "%s/m%d.exr", dir, k);
        rc = pt_write_exr(path, &a, &o, err, sizeof err);
        if (!CHECK(t, rc == PT_OK, "write rc %d %s", rc, err)) goto done;
        free(buf);
        buf = tu_read_file(path, &size);
        if (!CHECK(t, buf && size > 100, "reading back %s", path)) goto done;
        rc = pt_read_exr(path, &f, err, sizeof err);
        if (!CHECK(t, rc == PT_OK, "file read rc %d %s", rc, err)) goto done;
        rc = pt_read_exr_memory(buf, (size_t)size, "mem.exr", &m, err, sizeof err);
        if (!CHECK(t, rc == PT_OK && err[0] == '\0', "memory read rc %d '%s'", rc, err)) goto done;
        CHECK(t, m.width == 13 && m.height == 37 && memcmp(f.rgb, m.rgb, sizeof(float) * 3u * 13u * 37u) == 0,
              "%s: memory read differs from the file read", k ? "half/PIZ" : "float/ZIP");
        if (k == 0) CHECK(t, memcmp(a.rgb, m.rgb, sizeof(float) * 3u * 13u * 37u) == 0, "float data not bit-exact");
        pt_image_free(&f);
        pt_image_free(&m);
    }
    /* every prefix of the half/PIZ file fails with PT_ERROR_IO, an empty image and a message */
    for (cut = 0; cut < size; ++cut) {
        m.width = 5; m.height = 5; m.rgb = NULL;
        rc = pt_read_exr_memory(buf, (size_t)cut, "cut.exr", &m, err, sizeof err);
        if (rc != PT_ERROR_IO || !image_empty(&m) || strncmp(err, "cut.exr: ", 9) != 0) {
            if (bad++ == 0) CHECK(t, 0, "prefix of %ld bytes: rc %d '%s'", cut, rc, err);
            if (rc == PT_OK) pt_image_free(&m);
        }
    }
    CHECK(t, bad == 0, "%d of %ld prefixes not rejected cleanly", bad, size);
    /* the dataWindow attribute patched to 2^14 x 2^15 pixels > PDFTRACE_EXR_MAX_PIXELS: refused
       from the header, before allocating (layout: name, type "box2i", size 16, 4 int32 LE) */
    {
        static const char key[] = "dataWindow\0box2i\0";
        long at = -1, j;
        for (j = 0; j + (long)sizeof key + 20 <= size && at < 0; ++j)
            if (memcmp(buf + j, key, sizeof key - 1) == 0) at = j + (long)sizeof key - 1 + 4;
        if (CHECK(t, at > 0, "no dataWindow attribute found")) {
            unsigned char save[16];
            static const unsigned char big[16] = { 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0x3f, 0, 0, 0xff, 0x7f, 0, 0 };
            memcpy(save, buf + at, 16);
            memcpy(buf + at, big, 16);
            m.width = 1; m.height = 1; m.rgb = NULL;
            rc = pt_read_exr_memory(buf, (size_t)size, "huge.exr", &m, err, sizeof err);
            CHECK(t, rc == PT_ERROR_UNSUPPORTED && image_empty(&m) && strstr(err, "PDFTRACE_EXR_MAX_PIXELS"),
                  "2^29-pixel data window: rc %d '%s' (want PT_ERROR_UNSUPPORTED)", rc, err);
            if (rc == PT_OK) pt_image_free(&m);
            /* under the pixel cap but 768 MiB of floats: refused by the byte budget before allocating
               (a hostile header used to make the reader allocate it) */
            {
                static const unsigned char b8k[16] = { 0, 0, 0, 0, 0, 0, 0, 0, 0xff, 0x1f, 0, 0, 0xff, 0x1f, 0, 0 };
                memcpy(buf + at, b8k, 16);
                m.width = 1; m.height = 1; m.rgb = NULL;
                rc = pt_read_exr_memory(buf, (size_t)size, "8k.exr", &m, err, sizeof err);
                CHECK(t, rc == PT_ERROR_UNSUPPORTED && image_empty(&m) && strstr(err, "PDFTRACE_EXR_MAX_BYTES") &&
                             strstr(err, "8192 x 8192"),
                      "8192 x 8192 data window: rc %d '%s' (want PT_ERROR_UNSUPPORTED naming PDFTRACE_EXR_MAX_BYTES)", rc, err);
                if (rc == PT_OK) pt_image_free(&m);
            }
            memcpy(buf + at, save, 16);
        }
    }
    CHECK(t, pt_read_exr_memory(NULL, 10, "x", &m, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT && image_empty(&m),
          "NULL data accepted");
    CHECK(t, pt_read_exr_memory(buf, (size_t)size, NULL, NULL, NULL, 0) == PT_ERROR_INVALID_ARGUMENT, "NULL image accepted");
    rc = pt_read_exr_memory(buf, (size_t)size, NULL, &m, NULL, 0);
    CHECK(t, rc == PT_OK && m.width == 13, "no name, no err buffer: rc %d", rc);
    pt_image_free(&m);
    test_note(t, "file = memory (float/ZIP, half/PIZ); %ld prefixes rejected; 2^29-pixel header refused", size);
done:
    free(buf);
    pt_image_free(&a);
    pt_image_free(&f);
    pt_image_free(&m);
    tu_remove_tree(dir);
}

/* A 2 x 40 float image whose last ZIP chunk (lines 32-39) deflates to exactly its packed size:
   OpenEXRCore up to 3.4.7 stores the zlib bytes as if uncompressed, and the rows read back as
   garbage, while the write reports success. The values: 26 of 64 random, the rest 0.5. */
static void zip_chunk_exactly_packed_size(test_ctx *t)
{
    pt_image a = { 0, 0, NULL }, b = { 0, 0, NULL };
    pt_exr_options o;
    char dir[64], path[160], err[512];
    uint32_t x = 1567u * 2654435761u;
    size_t i;
    int rc, bad = 0;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) return;
    if (!CHECK(t, pt_image_init(&a, 2, 40) == PT_OK, "image")) goto done;
    for (i = 0; i < 240; ++i) {
        x = x * 1664525u + 1013904223u;
        a.rgb[i] = (x >> 26) < 26u ? (float)((x >> 8) & 0xffffu) / 65536.0f : 0.5f;
    }
    o.pixel_type = PT_EXR_FLOAT;
    o.compression = PT_EXR_ZIP;
    snprintf(path, sizeof path, "%s/z.exr", dir);
    rc = pt_write_exr(path, &a, &o, err, sizeof err);
    CHECK(t, rc == PT_OK, "write: %d '%s'", rc, err);
    rc = pt_read_exr(path, &b, err, sizeof err);
    if (CHECK(t, rc == PT_OK && b.width == 2 && b.height == 40, "read back: %d '%s'", rc, err))
        for (i = 0; i < 240; ++i) bad += memcmp(&a.rgb[i], &b.rgb[i], 4) != 0;
    CHECK(t, bad == 0, "%d of 240 values differ after the round trip", bad);
    test_note(t, "2 x 40 float ZIP, %d values differ", bad);
done:
    pt_image_free(&a);
    pt_image_free(&b);
    tu_remove_tree(dir);
}

/* A file or symlink planted at the old temporary name "<path>.ptmp" is neither followed nor
   overwritten; the written file has the usual permissions (0666 less the umask). */
static void temporary_not_followed(test_ctx *t)
{
    pt_image a = { 0, 0, NULL };
    char dir[64], path[160], link[200], victim[160], err[512], list[256];
    unsigned char *v;
    long n = 0;
    struct stat st;
    mode_t old = umask(022);
    int rc;
    if (!CHECK(t, tu_make_tmpdir(dir, sizeof dir), "mkdtemp")) { umask(old); return; }
    if (!CHECK(t, make_test_image(&a, 8, 5), "image")) goto done;
    snprintf(victim, sizeof victim, "%s/victim", dir);
    snprintf(path, sizeof path, "%s/out.exr", dir);
    snprintf(link, sizeof link, "%s.ptmp", path);
    CHECK(t, spit(victim, (const unsigned char *)"keep", 4), "victim");
    CHECK(t, symlink(victim, link) == 0, "symlink");
    rc = pt_write_exr(path, &a, NULL, err, sizeof err);
    CHECK(t, rc == PT_OK, "write: %d '%s'", rc, err);
    v = tu_read_file(victim, &n);
    CHECK(t, v && n == 4 && memcmp(v, "keep", 4) == 0, "the symlink's target was overwritten (%ld bytes)", n);
    free(v);
    CHECK(t, lstat(link, &st) == 0 && S_ISLNK(st.st_mode), "the planted symlink was removed or replaced");
    CHECK(t, stat(path, &st) == 0 && (st.st_mode & 0777) == 0644, "mode %o, want 644 under umask 022", (unsigned)(st.st_mode & 0777));
    CHECK(t, tu_dir_entries(dir, list, sizeof list) == 3, "want out.exr, out.exr.ptmp, victim: %s", list);
done:
    umask(old);
    pt_image_free(&a);
    tu_remove_tree(dir);
}

const test_case test_exr_cases[] = {
    TEST_CASE(round_trip),
    TEST_CASE(half_rounding),
    TEST_CASE(rgba_written_by_library),
    TEST_CASE(bad_files),
    TEST_CASE(write_errors),
    TEST_CASE(memory_reader),
    TEST_CASE(zip_chunk_exactly_packed_size),
    TEST_CASE(temporary_not_followed),
    TEST_END
};

#endif /* PDFTRACE_OPENEXR */
