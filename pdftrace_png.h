/* pdftrace_png.h - PNG output for pdftrace.h images, through libpng.
   Part of the pdftrace header family. LICENSE: MIT or public domain, your choice (full text at
   the end of this file).

   ABOUT
   =====
   Writes 8-bit RGB PNG files through libpng's simplified API (png_image_write_to_stdio,
   libpng 1.6 or later; the libpng manual, http://www.libpng.org/pub/png/libpng-manual.txt,
   section V, "Simplified API"). pt_write_png encodes every channel as pt_write_ppm does:
   clamped to [0, 1], the sRGB transfer function (pt_srgb_encode), times 255, plus 0.5,
   truncated; for exposure and tone mapping apply pt_image_apply_display first. libpng marks
   8-bit files as sRGB (an sRGB chunk, perceptual intent). pt_write_png_rgb8 writes bytes the
   caller has already encoded (3 per pixel, row 0 at the top).
   pt_read_png_memory reads a PNG held in memory (image textures: pdftrace_scene.h passes it as
   pt_scenefile_options.read_png) through the same simplified API as 8-bit RGB (grey and
   palette expanded, alpha dropped, 16-bit rounded to 8, a gAMA other than sRGB's converted to
   sRGB by libpng) and returns each channel as its stored code k / 255, still sRGB-encoded:
   the caller decodes colour with pt_srgb_decode and keeps non-colour data (roughness) as it is.
   Both write to a new temporary beside the target (pdftrace.h's pt_output_open) and rename it
   into place: a failed write leaves no file (and no temporary). They return PT_OK or a pt_result
   code (PT_ERROR_INVALID_ARGUMENT, PT_ERROR_OUT_OF_MEMORY, PT_ERROR_IO) and, when err is not
   NULL, write a one-line message into err[0 .. err_size-1] (empty on success): "PATH: writing
   PNG: cannot create 'PATH.XXXXXXXX.ptmp': REASON", "... cannot write 'TMP': REASON", "...
   cannot rename 'TMP' to 'PATH': REASON" (the system's strerror) or libpng's own message. Safe
   to call from several threads at once.

   BUILDING
   ========
   In exactly one C or C++ file (it may be the file that implements pdftrace.h, or another):
       #define PDFTRACE_PNG_IMPLEMENTATION
       #include "pdftrace_png.h"
   This header includes pdftrace.h and <png.h>. Compile with `pkg-config --cflags libpng` and
   link `pkg-config --libs libpng` (-lpng16). The Makefile's PNG=auto|0|1 builds the project's
   programs this way when libpng is found (Debian: apt-get install libpng-dev).

   USAGE
   =====
       char err[512];
       if (pt_write_png("out.png", &img, err, sizeof err) != PT_OK) puts(err);
       pt_display_desc d = {1.0f, PT_TONEMAP_ACES};     (one stop brighter, filmic curve)
       pt_image shown = {0};
       if (pt_image_apply_display(&img, &d, &shown) == PT_OK)
           pt_write_png("shown.png", &shown, err, sizeof err);
       pt_image_free(&shown);
*/
#ifndef PDFTRACE_PNG_H
#define PDFTRACE_PNG_H

#include "pdftrace.h"

#ifdef __cplusplus
extern "C" {
#endif

/* img as an 8-bit sRGB PNG (see above). */
PTDEF int pt_write_png(const char *path, const pt_image *img, char *err, size_t err_size);
/* A PNG file's bytes (data, size; name for messages) into *out (row 0 at the top): each channel
   as its 8-bit code / 255, not decoded (see above). PT_OK; PT_ERROR_IO (not a PNG, corrupt,
   truncated) or PT_ERROR_OUT_OF_MEMORY with "NAME: reading PNG: reason" in err; *out is left
   empty on failure. Images over 2^28 pixels are refused before their pixels are allocated. */
PTDEF int pt_read_png_memory(const void *data, size_t size, const char *name, pt_image *out, char *err,
                             size_t err_size);
/* width x height pixels of 3 bytes (R, G, B) each, rows top first, written as they are. */
PTDEF int pt_write_png_rgb8(const char *path, int width, int height, const unsigned char *rgb, char *err,
                            size_t err_size);

#ifdef __cplusplus
}
#endif

#endif /* PDFTRACE_PNG_H */

/* ==========================================================================================
   IMPLEMENTATION
   The simplified API writes a whole image from one buffer: a png_image names its size and
   format (PNG_FORMAT_RGB), png_image_write_to_stdio writes it to the open temporary and reports
   failure in png_image.message; pt_output_close flushes, closes and renames it into place.
   ========================================================================================== */
#ifdef PDFTRACE_PNG_IMPLEMENTATION
#ifndef PDFTRACE_PNG_IMPLEMENTATION_DONE
#define PDFTRACE_PNG_IMPLEMENTATION_DONE

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <png.h>

#if defined(PT_MALLOC) && defined(PT_FREE) && defined(PT_REALLOC)
/* all three given (or defined by pdftrace.h's implementation in this file) */
#elif !defined(PT_MALLOC) && !defined(PT_FREE) && !defined(PT_REALLOC)
#define PT_MALLOC(sz) malloc(sz)
#define PT_REALLOC(p, sz) realloc(p, sz)
#define PT_FREE(p) free(p)
#else
#error "pdftrace_png.h: define all of PT_MALLOC, PT_REALLOC and PT_FREE, or none"
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* Formats "path: writing PNG: <fmt ...>" into err and returns code. */
static int pt__png_fail(char *err, size_t err_size, int code, const char *path, const char *fmt, ...)
{
    va_list ap;
    int n;
    if (!err || !err_size) return code;
    n = snprintf(err, err_size, "%s: writing PNG: ", path ? path : "(null)");
    if (n < 0) n = 0;
    if ((size_t)n < err_size) {
        va_start(ap, fmt);
        vsnprintf(err + n, err_size - (size_t)n, fmt, ap);
        va_end(ap);
    }
    return code;
}

/* w x h pixels of 3 bytes, with at most 2^32 pixels and a size that fits a size_t (as pdftrace.h). */
static int pt__png_pixels(int w, int h, size_t *n)
{
    if (w <= 0 || h <= 0 || (size_t)w > ((size_t)-1) / 64u / (size_t)h || (uint64_t)w * (uint64_t)h > 0xffffffffu)
        return 0;
    *n = (size_t)w * (size_t)h;
    return 1;
}

/* Writes the open temporary t->file; on failure the message is libpng's, or the system's reason
   when a write failed (libpng's own text for that is only "Write Error"). */
static int pt__png_write_file(pt_output_file *t, int w, int h, const unsigned char *rgb, char *err, size_t err_size)
{
    png_image im;
    int ok, e;
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    im.width = (png_uint_32)w;
    im.height = (png_uint_32)h;
    im.format = PNG_FORMAT_RGB;
    errno = 0;
    ok = png_image_write_to_stdio(&im, t->file, 0, rgb, 0, NULL) != 0;
    e = errno;
    if (!ok && !(ferror(t->file) && e))
        pt__png_fail(err, err_size, PT_ERROR_IO, t->path, "%s", im.message[0] ? im.message : "libpng failed");
    errno = e;
    return ok;
}

PTDEF int pt_write_png_rgb8(const char *path, int width, int height, const unsigned char *rgb, char *err,
                            size_t err_size)
{
    pt_output_file t;
    size_t n;
    int rc;
    if (err && err_size) err[0] = '\0';
    if (!path || !*path || !rgb || !pt__png_pixels(width, height, &n))
        return pt__png_fail(err, err_size, PT_ERROR_INVALID_ARGUMENT, path, "no path or an empty image");
    if ((rc = pt_output_open(&t, path, 0, "PNG", err, err_size)) != PT_OK) return rc;
    return pt_output_close(&t, pt__png_write_file(&t, width, height, rgb, err, err_size), "PNG", err, err_size);
}

PTDEF int pt_write_png(const char *path, const pt_image *img, char *err, size_t err_size)
{
    unsigned char *rgb;
    size_t n, i;
    int rc;
    if (err && err_size) err[0] = '\0';
    if (!path || !*path || !img || !img->rgb || !pt__png_pixels(img->width, img->height, &n))
        return pt__png_fail(err, err_size, PT_ERROR_INVALID_ARGUMENT, path, "no path or an empty image");
    rgb = (unsigned char *)PT_MALLOC(3u * n);
    if (!rgb) return pt__png_fail(err, err_size, PT_ERROR_OUT_OF_MEMORY, path, "out of memory");
    for (i = 0; i < 3u * n; ++i) rgb[i] = (unsigned char)(pt_srgb_encode(img->rgb[i]) * 255.0f + 0.5f); /* as pt_write_ppm */
    rc = pt_write_png_rgb8(path, img->width, img->height, rgb, err, err_size);
    PT_FREE(rgb);
    return rc;
}

/* Formats "name: reading PNG: <fmt ...>" into err and returns code. */
static int pt__png_rfail(char *err, size_t err_size, int code, const char *name, const char *fmt, ...)
{
    va_list ap;
    int n;
    if (!err || !err_size) return code;
    n = snprintf(err, err_size, "%s: reading PNG: ", name);
    if (n < 0) n = 0;
    if ((size_t)n < err_size) {
        va_start(ap, fmt);
        vsnprintf(err + n, err_size - (size_t)n, fmt, ap);
        va_end(ap);
    }
    return code;
}

PTDEF int pt_read_png_memory(const void *data, size_t size, const char *name, pt_image *out, char *err,
                             size_t err_size)
{
    png_image im;
    unsigned char *rgb;
    size_t n, i;
    int rc;
    if (err && err_size) err[0] = '\0';
    if (!name) name = "(memory)";
    if (!out || !data || size == 0)
        return pt__png_rfail(err, err_size, PT_ERROR_INVALID_ARGUMENT, name, "no data or no output image");
    memset(out, 0, sizeof *out);
    memset(&im, 0, sizeof im);
    im.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&im, data, size))
        return pt__png_rfail(err, err_size, PT_ERROR_IO, name, "%s", im.message[0] ? im.message : "not a PNG file");
    if (im.width > 65536u || im.height > 65536u || (uint64_t)im.width * im.height > ((uint64_t)1 << 28) ||
        !pt__png_pixels((int)im.width, (int)im.height, &n)) {
        png_image_free(&im);
        return pt__png_rfail(err, err_size, PT_ERROR_IO, name, "%lu x %lu pixels: at most 2^28 are read",
                            (unsigned long)im.width, (unsigned long)im.height);
    }
    im.format = PNG_FORMAT_RGB;
    rgb = (unsigned char *)PT_MALLOC(3u * n);
    if (!rgb || (rc = pt_image_init(out, (int)im.width, (int)im.height)) != PT_OK) {
        PT_FREE(rgb);
        png_image_free(&im);
        return pt__png_rfail(err, err_size, PT_ERROR_OUT_OF_MEMORY, name, "out of memory");
    }
    if (!png_image_finish_read(&im, NULL, rgb, 0, NULL)) {
        rc = pt__png_rfail(err, err_size, PT_ERROR_IO, name, "%s", im.message[0] ? im.message : "corrupt file");
        PT_FREE(rgb);
        pt_image_free(out);
        png_image_free(&im);
        return rc;
    }
    for (i = 0; i < 3u * n; ++i) out->rgb[i] = (float)rgb[i] / 255.0f;
    PT_FREE(rgb);
    return PT_OK;
}

#ifdef __cplusplus
}
#endif

#endif /* PDFTRACE_PNG_IMPLEMENTATION_DONE */
#endif /* PDFTRACE_PNG_IMPLEMENTATION */

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
