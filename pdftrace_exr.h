/* pdftrace_exr.h - OpenEXR output and input for pdftrace.h images.
   Part of the pdftrace header family. LICENSE: MIT or public domain, your choice (full text at
   the end of this file).

   ABOUT
   =====
   Writes and reads linear HDR images (pt_image) through OpenEXRCore, the C library of
   OpenEXR 3.x. Written files are single-part scanline images with channels B, G, R (the EXR spec stores
   channels sorted by name), data window = display window = (0,0)-(W-1,H-1), increasing-Y
   line order. Reference: the OpenEXR file layout and OpenEXRCore API docs,
   https://openexr.com/en/latest/OpenEXRFileLayout.html and
   https://openexr.com/en/latest/API.html#openexrcore (and the headers openexr_*.h).
   Both functions return PT_OK or a pt_result code (PT_ERROR_INVALID_ARGUMENT,
   PT_ERROR_OUT_OF_MEMORY, PT_ERROR_IO, PT_ERROR_UNSUPPORTED) and, when err is not NULL,
   write a one-line message into err[0 .. err_size-1] (empty on success). No global state:
   safe to call from several threads at once.

   BUILDING
   ========
   In exactly one C or C++ file (it may be the file that implements pdftrace.h, or another):
       #define PDFTRACE_EXR_IMPLEMENTATION
       #include "pdftrace_exr.h"
   This header includes pdftrace.h and <openexr.h>. Compile with -isystem /usr/include/OpenEXR
   -isystem /usr/include/Imath (or the include dirs of `pkg-config --cflags OpenEXR`) and link
   -lOpenEXRCore-3_1 only; the C++ libraries the .pc file lists are not needed. `make OPENEXR=1`
   builds the project's programs this way.

   USAGE
   =====
       char err[512];
       if (pt_write_exr("out.exr", &img, NULL, err, sizeof err) != PT_OK) puts(err);  (half, ZIP)
       pt_image in = {0};
       if (pt_read_exr("in.exr", &in, err, sizeof err) == PT_OK) { ...; pt_image_free(&in); }

   OPTIONS
   =======
   PDFTRACE_EXR_MAX_PIXELS   the readers refuse larger images before allocating (default 2^28)
   PDFTRACE_EXR_MAX_BYTES    ... and images needing more memory than this (default 2^29, 512 MiB)
*/
#ifndef PDFTRACE_EXR_H
#define PDFTRACE_EXR_H

#include "pdftrace.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum pt_exr_pixel_type { PT_EXR_HALF = 0, PT_EXR_FLOAT = 1 } pt_exr_pixel_type;
typedef enum pt_exr_compression {
    PT_EXR_ZIP = 0, /* zlib, 16 scanlines per chunk (lossless) */
    PT_EXR_PIZ = 1, /* wavelet + Huffman, 32 scanlines per chunk (lossless) */
    PT_EXR_NONE = 2
} pt_exr_compression;
typedef struct pt_exr_options {
    pt_exr_pixel_type pixel_type;   /* default (0): half */
    pt_exr_compression compression; /* default (0): ZIP */
} pt_exr_options;

/* Writes img as an RGB EXR through a new temporary beside path (pt_output_open), renamed
   into place: a failed write leaves no file (and no temporary). opt may be NULL (half, ZIP). Half values are rounded to nearest
   even (IEEE 754-2008 binary16); values beyond the half range become +-infinity, NaN stays
   NaN. Float values are stored bit-exactly. */
PTDEF int pt_write_exr(const char *path, const pt_image *img, const pt_exr_options *opt, char *err, size_t err_size);
/* Reads the first part of a scanline EXR with channels R, G and B (any others, e.g. A,
   are ignored; half, float or uint, converted to float) into *out, which is overwritten (not
   freed: pass an empty or freed image). On failure *out is left empty ({0, 0, NULL}). Missing
   file, not an EXR, corrupt or truncated data: PT_ERROR_IO; no R/G/B channel, subsampled
   channels, tiled or deep parts: PT_ERROR_UNSUPPORTED. */
PTDEF int pt_read_exr(const char *path, pt_image *out, char *err, size_t err_size);
/* The same from a whole EXR file held in memory (size bytes at data, read in place, not
   copied); `name` is used in messages (NULL: "<memory>"). */
PTDEF int pt_read_exr_memory(const void *data, size_t size, const char *name, pt_image *out, char *err,
                             size_t err_size);
/* Both readers refuse (PT_ERROR_UNSUPPORTED, with a message saying what the image needs) an
   image of more than PDFTRACE_EXR_MAX_PIXELS pixels, or one whose float image (12 bytes a
   pixel) and decode buffers of one chunk need more than PDFTRACE_EXR_MAX_BYTES, before
   allocating anything for it; a chunk of the file needing more than what is left is refused
   before it is decoded. So a damaged or hostile header cannot make them allocate more than
   about PDFTRACE_EXR_MAX_BYTES. The default, 512 MiB, holds an image of 44 million pixels
   (8192 x 5400); define either macro before including this header to change it. */
#ifndef PDFTRACE_EXR_MAX_PIXELS
#define PDFTRACE_EXR_MAX_PIXELS (1u << 28)
#endif
#ifndef PDFTRACE_EXR_MAX_BYTES
#define PDFTRACE_EXR_MAX_BYTES ((uint64_t)1 << 29)
#endif

#ifdef __cplusplus
}
#endif

#endif /* PDFTRACE_EXR_H */

/* ==========================================================================================
   IMPLEMENTATION
   The OpenEXRCore C API: https://openexr.com/en/latest/API.html#openexrcore and the headers
   openexr_context.h, openexr_part.h, openexr_chunkio.h, openexr_encode.h, openexr_decode.h.
   How: a write context is
   started on "<path>.ptmp"; the header (one scanline part, required attributes, channels)
   is written, then each chunk (16 lines for ZIP, 32 for PIZ: exr_get_scanlines_per_chunk)
   is encoded with an exr_encode_pipeline_t whose channels point at the caller's pixels;
   exr_finish writes the chunk offset table; the file is then renamed into place. Reading
   decodes each chunk with an exr_decode_pipeline_t straight into the float image (the
   library converts half and uint to float). Library messages arrive through the context's
   error_handler_fn and are copied into the caller's buffer (no global state).
   ========================================================================================== */
#ifdef PDFTRACE_EXR_IMPLEMENTATION
#ifndef PDFTRACE_EXR_IMPLEMENTATION_DONE
#define PDFTRACE_EXR_IMPLEMENTATION_DONE

#include <stdio.h>
#include <stdlib.h>
#include <errno.h>
#include <fenv.h>
#include <limits.h>
#include <string.h>
#include <openexr.h>

#if defined(PT_MALLOC) && defined(PT_FREE) && defined(PT_REALLOC)
/* all three given (or defined by pdftrace.h's implementation in this file) */
#elif !defined(PT_MALLOC) && !defined(PT_FREE) && !defined(PT_REALLOC)
#define PT_MALLOC(sz) malloc(sz)
#define PT_REALLOC(p, sz) realloc(p, sz)
#define PT_FREE(p) free(p)
#else
#error "pdftrace_exr.h: define all of PT_MALLOC, PT_REALLOC and PT_FREE, or none"
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* w x h pixels, with room for 64 bytes each in a size_t and at most 2^32 pixels (as pdftrace.h). */
static int pt__exr_pixels(int w, int h, size_t *n)
{
    if (w <= 0 || h <= 0 || (size_t)w > ((size_t)-1) / 64u / (size_t)h || (uint64_t)w * (uint64_t)h > 0xffffffffu)
        return 0;
    *n = (size_t)w * (size_t)h;
    return 1;
}

typedef struct pt__exr_msg {
    char text[256]; /* the library's first message for this context */
} pt__exr_msg;

static void pt__exr_error_cb(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    void *ud = NULL;
    pt__exr_msg *m;
    (void)code;
    if (exr_get_user_data(ctxt, &ud) != EXR_ERR_SUCCESS || !ud || !msg) return;
    m = (pt__exr_msg *)ud;
    if (!m->text[0]) snprintf(m->text, sizeof m->text, "%s", msg);
}

/* Formats "path: what[: detail]" into err and returns code. */
static int pt__exr_fail(char *err, size_t err_size, int code, const char *path, const char *what, const char *detail)
{
    if (err && err_size) {
        if (detail && *detail) snprintf(err, err_size, "%s: %s: %s", path ? path : "(null)", what, detail);
        else snprintf(err, err_size, "%s: %s", path ? path : "(null)", what);
    }
    return code;
}
/* A library failure: the message it reported, else the text for its code. */
static int pt__exr_lib_fail(char *err, size_t err_size, int code, const char *path, const char *what,
                            exr_result_t rv, const pt__exr_msg *m)
{
    if (rv == EXR_ERR_OUT_OF_MEMORY) code = PT_ERROR_OUT_OF_MEMORY;
    else if (rv == EXR_ERR_FEATURE_NOT_IMPLEMENTED) code = PT_ERROR_UNSUPPORTED;
    return pt__exr_fail(err, err_size, code, path, what, m->text[0] ? m->text : exr_get_default_error_message(rv));
}

/* float -> IEEE 754-2008 binary16, round to nearest, ties to even (section 4.3.1). Beyond the
   largest half (65504) values from 65520 (the midpoint to 2^16) on round to infinity; results
   below 2^-14 are half subnormals (steps of 2^-24); NaNs stay NaN (quiet bit set). */
static uint16_t pt__float_to_half(float f)
{
    uint32_t u, mag, sign, h, rem, halfway;
    memcpy(&u, &f, 4);
    sign = (u >> 16) & 0x8000u;
    mag = u & 0x7fffffffu;
    if (mag >= 0x7f800000u) /* inf or NaN */
        return (uint16_t)(sign | 0x7c00u | (mag > 0x7f800000u ? 0x200u | ((mag >> 13) & 0x3ffu) : 0u));
    if (mag >= 0x477ff000u) return (uint16_t)(sign | 0x7c00u); /* >= 65520 */
    if (mag >= 0x38800000u) {                                  /* normal half: >= 2^-14 */
        uint32_t t = mag - 0x38000000u;                        /* exponent bias 127 -> 15 */
        h = t >> 13;
        rem = t & 0x1fffu;
        if (rem > 0x1000u || (rem == 0x1000u && (h & 1u))) h++; /* a carry moves into the exponent */
        return (uint16_t)(sign | h);
    }
    if (mag <= 0x33000000u) return (uint16_t)sign; /* <= 2^-25: ties to even gives zero */
    {                                              /* subnormal half: mag * 2^24, rounded */
        uint32_t e = mag >> 23, m = (mag & 0x7fffffu) | 0x800000u, shift = 126u - e; /* 14..24 */
        h = m >> shift;
        rem = m & ((1u << shift) - 1u);
        halfway = 1u << (shift - 1u);
        if (rem > halfway || (rem == halfway && (h & 1u))) h++;
        return (uint16_t)(sign | h);
    }
}

static int pt__exr_channel_index(const char *name)
{
    if (!name || !name[0] || name[1]) return -1;
    return name[0] == 'R' ? 0 : name[0] == 'G' ? 1 : name[0] == 'B' ? 2 : -1;
}

/* The stream of a write context: the library writes through pt__exr_file_write into the
   temporary pdftrace.h's pt_output_open created (so it never opens a path itself). The message
   comes first: the error callback reads the context's user data as a pt__exr_msg. */
typedef struct pt__exr_sink {
    pt__exr_msg msg;
    FILE *f;
    int err_no; /* errno of the first failed write, 0 if none */
} pt__exr_sink;
static int64_t pt__exr_file_write(exr_const_context_t ctxt, void *user, const void *buffer, uint64_t sz,
                                  uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    pt__exr_sink *k = (pt__exr_sink *)user;
    (void)ctxt;
    (void)error_cb;
    if (!k || !k->f || !buffer) return -1;
    errno = 0;
    if (offset > (uint64_t)LONG_MAX || sz > (uint64_t)((size_t)-1) || fseek(k->f, (long)offset, SEEK_SET) != 0 ||
        fwrite(buffer, 1, (size_t)sz, k->f) != (size_t)sz) {
        if (!k->err_no) k->err_no = errno ? errno : EIO;
        return -1;
    }
    return (int64_t)sz;
}

/* OpenEXRCore before the fix of its issue 2306 (PR 2307, after release 3.4.7) stores a ZIP
   chunk whose zlib stream is exactly as long as the packed data with that stream in it, and
   readers take a chunk of the unpacked size as uncompressed: the rows read back as garbage.
   The wrapper below stores such chunks uncompressed, as the fixed library does (the file layout
   allows either, whichever is not larger). The pipeline is the first member, so the library's
   pointer to it is a pointer to the wrapper's state. */
typedef struct pt__exr_enc {
    exr_encode_pipeline_t p;
    exr_result_t (*lib_compress)(exr_encode_pipeline_t *);
} pt__exr_enc;
static exr_result_t pt__exr_zip_compress(exr_encode_pipeline_t *p)
{
    pt__exr_enc *e = (pt__exr_enc *)(void *)p;
    exr_result_t rv = e->lib_compress(p);
    if (rv == EXR_ERR_SUCCESS && p->compressed_bytes == p->packed_bytes && p->packed_bytes > 0 &&
        p->compressed_buffer && p->packed_buffer && p->compressed_buffer != p->packed_buffer &&
        p->compressed_alloc_size >= p->packed_bytes)
        memcpy(p->compressed_buffer, p->packed_buffer, (size_t)p->packed_bytes);
    return rv;
}
/* 1 if the library linked at run time needs the wrapper (versions up to 3.4.7). */
static int pt__exr_zip_needs_workaround(void)
{
    int maj = 0, min = 0, pat = 0;
    const char *extra = NULL;
    exr_get_library_version(&maj, &min, &pat, &extra);
    return maj < 3 || (maj == 3 && (min < 4 || (min == 4 && pat <= 7)));
}

/* Encodes the chunks of img (half: converted into a buffer of spc lines). */
static exr_result_t pt__exr_write_chunks(exr_context_t ctx, int part, const pt_image *img, exr_pixel_type_t ptype,
                                         int32_t spc, int zip_fix)
{
    pt__exr_enc enc; /* enc.p zeroed, as EXR_ENCODE_PIPELINE_INITIALIZER ({0}) does */
    uint16_t *half = NULL;
    exr_result_t rv = EXR_ERR_SUCCESS;
    int enc_ready = 0, c;
    int64_t y;
    memset(&enc, 0, sizeof enc);
    if (ptype == EXR_PIXEL_HALF) {
        half = (uint16_t *)PT_MALLOC(sizeof(uint16_t) * 3u * (size_t)img->width * (size_t)spc);
        if (!half) return EXR_ERR_OUT_OF_MEMORY;
    }
    for (y = 0; rv == EXR_ERR_SUCCESS && y < img->height; y += spc) {
        exr_chunk_info_t ci;
        const float *src;
        size_t i, count;
        rv = exr_write_scanline_chunk_info(ctx, part, (int)y, &ci);
        if (rv != EXR_ERR_SUCCESS) break;
        if (ci.start_y < 0 || ci.height < 1 || (int64_t)ci.start_y + ci.height > img->height) { rv = EXR_ERR_INCORRECT_CHUNK; break; }
        src = img->rgb + 3u * (size_t)ci.start_y * (size_t)img->width;
        count = 3u * (size_t)ci.height * (size_t)img->width;
        if (half)
            for (i = 0; i < count; ++i) half[i] = pt__float_to_half(src[i]);
        rv = enc_ready ? exr_encoding_update(ctx, part, &ci, &enc.p) : exr_encoding_initialize(ctx, part, &ci, &enc.p);
        if (rv != EXR_ERR_SUCCESS) break;
        enc_ready = 1;
        for (c = 0; c < enc.p.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &enc.p.channels[c];
            int k = pt__exr_channel_index(ch->channel_name);
            if (k < 0) { rv = EXR_ERR_INVALID_ARGUMENT; break; }
            ch->encode_from_ptr = half ? (const uint8_t *)(half + k) : (const uint8_t *)(src + k);
            ch->user_bytes_per_element = half ? 2 : 4;
            ch->user_pixel_stride = 3 * ch->user_bytes_per_element;
            ch->user_line_stride = ch->user_pixel_stride * img->width;
            ch->user_data_type = half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
        }
        if (rv == EXR_ERR_SUCCESS && y == 0) rv = exr_encoding_choose_default_routines(ctx, part, &enc.p);
        if (rv == EXR_ERR_SUCCESS && zip_fix && enc.p.compress_fn && enc.p.compress_fn != pt__exr_zip_compress) {
            enc.lib_compress = enc.p.compress_fn; /* checked each chunk, in case update resets it */
            enc.p.compress_fn = pt__exr_zip_compress;
        }
        if (rv == EXR_ERR_SUCCESS) rv = exr_encoding_run(ctx, part, &enc.p);
    }
    if (enc_ready) exr_encoding_destroy(ctx, &enc.p);
    PT_FREE(half);
    return rv;
}

static int pt__exr_verify(const char *tmp, const pt_image *img, int half, char *detail, size_t detail_size);

static int pt__exr_write(const char *path, const pt_image *img, const pt_exr_options *opt, char *err, size_t err_size)
{
    static const char *const names[3] = { "R", "G", "B" };
    pt_exr_options o;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    exr_compression_t ctype;
    exr_pixel_type_t ptype;
    pt__exr_sink sink;
    pt_output_file out;
    const char *what = "starting the file";
    char detail[320];
    size_t n;
    int part = 0, c, rc;
    int32_t spc = 0;
    exr_result_t rv;

    if (err && err_size) err[0] = '\0';
    memset(&sink, 0, sizeof sink);
    if (!path || !*path || !img || !img->rgb || !pt__exr_pixels(img->width, img->height, &n))
        return pt__exr_fail(err, err_size, PT_ERROR_INVALID_ARGUMENT, path, "writing EXR", "no path or an empty image");
    if (img->width > INT32_MAX / 12) /* the library's line strides are int32 */
        return pt__exr_fail(err, err_size, PT_ERROR_UNSUPPORTED, path, "writing EXR", "image too wide");
    o.pixel_type = PT_EXR_HALF;
    o.compression = PT_EXR_ZIP;
    if (opt) o = *opt;
    if ((o.pixel_type != PT_EXR_HALF && o.pixel_type != PT_EXR_FLOAT) ||
        (o.compression != PT_EXR_ZIP && o.compression != PT_EXR_PIZ && o.compression != PT_EXR_NONE))
        return pt__exr_fail(err, err_size, PT_ERROR_INVALID_ARGUMENT, path, "writing EXR", "unknown pixel type or compression");
    ctype = o.compression == PT_EXR_ZIP ? EXR_COMPRESSION_ZIP : o.compression == PT_EXR_PIZ ? EXR_COMPRESSION_PIZ : EXR_COMPRESSION_NONE;
    ptype = o.pixel_type == PT_EXR_HALF ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;

    if ((rc = pt_output_open(&out, path, 0, "EXR", err, err_size)) != PT_OK) return rc;
    sink.f = out.file;
    init.error_handler_fn = pt__exr_error_cb;
    init.user_data = &sink;
    init.write_fn = pt__exr_file_write;
    rv = exr_start_write(&ctx, out.tmp_path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS) { what = "adding the part"; rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part); }
    if (rv == EXR_ERR_SUCCESS) {
        what = "setting the header";
        rv = exr_initialize_required_attr_simple(ctx, part, img->width, img->height, ctype);
    }
    for (c = 0; c < 3 && rv == EXR_ERR_SUCCESS; ++c)
        rv = exr_add_channel(ctx, part, names[c], ptype, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    if (rv == EXR_ERR_SUCCESS) { what = "writing the header"; rv = exr_write_header(ctx); }
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_scanlines_per_chunk(ctx, part, &spc);
    if (rv == EXR_ERR_SUCCESS && spc < 1) rv = EXR_ERR_INVALID_ARGUMENT;
    if (rv == EXR_ERR_SUCCESS) {
        what = "writing pixels";
        rv = pt__exr_write_chunks(ctx, part, img, ptype, spc, ctype == EXR_COMPRESSION_ZIP && pt__exr_zip_needs_workaround());
    }
    if (ctx) {
        exr_result_t fr = exr_finish(&ctx); /* writes the chunk offset table */
        if (rv == EXR_ERR_SUCCESS && fr != EXR_ERR_SUCCESS) { rv = fr; what = "finishing the file"; }
    }
    if (rv != EXR_ERR_SUCCESS) {
        int code = (rv == EXR_ERR_INVALID_ARGUMENT || rv == EXR_ERR_ARGUMENT_OUT_OF_RANGE) &&
                           strcmp(what, "setting the header") == 0
                       ? PT_ERROR_INVALID_ARGUMENT
                       : PT_ERROR_IO;
        if (sink.err_no && err && err_size) /* a failed write: the temporary and the system's reason */
            snprintf(err, err_size, "%s: writing EXR (%s): cannot write '%s': %s", path, what, out.tmp_path,
                     strerror(sink.err_no));
        else pt__exr_lib_fail(err, err_size, code, path, what, rv, &sink.msg);
        (void)pt_output_close(&out, 0, "EXR", err, err_size);
        return rv == EXR_ERR_OUT_OF_MEMORY ? PT_ERROR_OUT_OF_MEMORY : code;
    }
    /* Flushed and closed by pt_output_close only after the check: flush here, then read back. */
    if (fflush(out.file) != 0 || ferror(out.file)) return pt_output_close(&out, 0, "EXR", err, err_size);
    if (!pt__exr_verify(out.tmp_path, img, ptype == EXR_PIXEL_HALF, detail, sizeof detail)) {
        pt__exr_fail(err, err_size, PT_ERROR_IO, path, "the file read back differs from the image (not written)", detail);
        pt_output_close(&out, 0, "EXR", err, err_size);
        return PT_ERROR_IO;
    }
    return pt_output_close(&out, 1, "EXR", err, err_size);
}

/* The source of pt_read_exr_memory. The message comes first: the error callback reads the
   context's user data as a pt__exr_msg. */
typedef struct pt__exr_src {
    pt__exr_msg msg;
    const unsigned char *data; /* NULL: read the file named path */
    size_t size;
} pt__exr_src;

/* pread semantics on the memory buffer: a short count at the end, 0 past it. */
static int64_t pt__exr_mem_read(exr_const_context_t ctxt, void *user, void *buffer, uint64_t sz, uint64_t offset,
                                exr_stream_error_func_ptr_t error_cb)
{
    const pt__exr_src *src = (const pt__exr_src *)user;
    uint64_t avail;
    (void)ctxt;
    (void)error_cb;
    if (!src || !buffer) return -1;
    if (offset >= (uint64_t)src->size) return 0;
    avail = (uint64_t)src->size - offset;
    if (sz > avail) sz = avail;
    if (sz > (uint64_t)INT64_MAX) sz = (uint64_t)INT64_MAX;
    memcpy(buffer, src->data + offset, (size_t)sz);
    return (int64_t)sz;
}
static int64_t pt__exr_mem_size(exr_const_context_t ctxt, void *user)
{
    const pt__exr_src *src = (const pt__exr_src *)user;
    (void)ctxt;
    return src && (uint64_t)src->size <= (uint64_t)INT64_MAX ? (int64_t)src->size : -1;
}

/* Bytes the library holds while decoding one chunk of w x spc pixels: the packed and unpacked
   chunk and a scratch buffer of the same size (ZIP, PIZ), estimated from the channel list. */
static uint64_t pt__exr_chunk_bytes(const exr_attr_chlist_t *chl, int64_t w, int32_t spc)
{
    uint64_t per_pixel = 0;
    int c;
    for (c = 0; chl && c < chl->num_channels; ++c) per_pixel += chl->entries[c].pixel_type == EXR_PIXEL_HALF ? 2u : 4u;
    return 3u * per_pixel * (uint64_t)w * (uint64_t)(spc > 0 ? spc : 1);
}

/* Decodes the chunk holding line y as float RGB. image: dst is the whole data window's image
   (the chunk goes to its rows); else dst holds the chunk from its first line. A chunk whose
   packed plus twice its unpacked size exceeds room is refused (EXR_ERR_OUT_OF_MEMORY) before
   the library allocates for it. The chunk's lines are returned in *first and *count. */
static exr_result_t pt__exr_decode_chunk(exr_context_t ctx, int y, const exr_attr_box2i_t *dw, uint64_t room, float *dst,
                                         int image, int32_t *first, int32_t *count)
{
    exr_chunk_info_t ci;
    exr_decode_pipeline_t dec; /* zeroed, as EXR_DECODE_PIPELINE_INITIALIZER ({0}) does */
    int64_t w = (int64_t)dw->max.x - (int64_t)dw->min.x + 1;
    exr_result_t rv;
    int c;
    memset(&dec, 0, sizeof dec);
    rv = exr_read_scanline_chunk_info(ctx, 0, y, &ci);
    if (rv != EXR_ERR_SUCCESS) return rv;
    if (ci.start_y < dw->min.y || ci.height < 1 || (int64_t)ci.start_y + ci.height - 1 > dw->max.y)
        return EXR_ERR_CORRUPT_CHUNK;
    if (ci.packed_size > room || ci.unpacked_size > (room - ci.packed_size) / 2u) return EXR_ERR_OUT_OF_MEMORY;
    if (first) *first = ci.start_y;
    if (count) *count = ci.height;
    rv = exr_decoding_initialize(ctx, 0, &ci, &dec);
    if (rv == EXR_ERR_SUCCESS) {
        float *row = image ? dst + 3u * (size_t)((int64_t)ci.start_y - dw->min.y) * (size_t)w : dst;
        for (c = 0; c < dec.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &dec.channels[c];
            int k = pt__exr_channel_index(ch->channel_name);
            if (k < 0) { ch->decode_to_ptr = NULL; continue; } /* NULL: the decoder skips it */
            ch->decode_to_ptr = (uint8_t *)(row + k);
            ch->user_pixel_stride = 12;
            ch->user_line_stride = (int32_t)(12 * w);
            ch->user_bytes_per_element = 4;
            ch->user_data_type = EXR_PIXEL_FLOAT;
        }
        rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
        if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(ctx, 0, &dec);
    }
    exr_decoding_destroy(ctx, &dec);
    return rv;
}

/* Reads the written file tmp back one chunk at a time and compares it with img: floats bit for
   bit, halves as the binary16 values written (NaN matches NaN). On a difference or a read
   failure detail says where. */
static int pt__exr_verify(const char *tmp, const pt_image *img, int half, char *detail, size_t detail_size)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    exr_attr_box2i_t dw;
    pt__exr_msg m;
    int32_t spc = 0, first = 0, count = 0;
    float *buf = NULL;
    int ok = 0, y;
    exr_result_t rv;
    memset(&m, 0, sizeof m);
    init.error_handler_fn = pt__exr_error_cb;
    init.user_data = &m;
    snprintf(detail, detail_size, "cannot read it back");
    rv = exr_start_read(&ctx, tmp, &init);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_data_window(ctx, 0, &dw);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_scanlines_per_chunk(ctx, 0, &spc);
    if (rv == EXR_ERR_SUCCESS && (dw.min.x != 0 || dw.min.y != 0 || dw.max.x != img->width - 1 ||
                                  dw.max.y != img->height - 1 || spc < 1))
        rv = EXR_ERR_CORRUPT_CHUNK;
    if (rv == EXR_ERR_SUCCESS && !(buf = (float *)PT_MALLOC(12u * (size_t)img->width * (size_t)spc))) rv = EXR_ERR_OUT_OF_MEMORY;
    for (y = 0; rv == EXR_ERR_SUCCESS && y < img->height; y += spc) {
        size_t i, cnt;
        const float *src;
        rv = pt__exr_decode_chunk(ctx, y, &dw, (uint64_t)-1, buf, 0, &first, &count);
        if (rv != EXR_ERR_SUCCESS) break;
        if (first != y || count < 1 || (int64_t)first + count > img->height) { rv = EXR_ERR_CORRUPT_CHUNK; break; }
        src = img->rgb + 3u * (size_t)first * (size_t)img->width;
        cnt = 3u * (size_t)count * (size_t)img->width;
        for (i = 0; i < cnt; ++i) {
            uint32_t a, b;
            if (half) {
                a = pt__float_to_half(src[i]);
                b = pt__float_to_half(buf[i]);
            } else {
                memcpy(&a, &src[i], 4);
                memcpy(&b, &buf[i], 4);
            }
            if (a != b && !(src[i] != src[i] && buf[i] != buf[i])) break;
        }
        if (i < cnt) {
            snprintf(detail, detail_size, "line %d, pixel %d: wrote %.9g, read %.9g", first + (int)(i / 3u / (size_t)img->width),
                     (int)(i / 3u % (size_t)img->width), (double)src[i], (double)buf[i]);
            break;
        }
    }
    ok = rv == EXR_ERR_SUCCESS && y >= img->height;
    if (rv != EXR_ERR_SUCCESS)
        snprintf(detail, detail_size, "cannot read it back: %s", m.text[0] ? m.text : exr_get_default_error_message(rv));
    PT_FREE(buf);
    if (ctx) exr_finish(&ctx);
    return ok;
}

PTDEF int pt_write_exr(const char *path, const pt_image *img, const pt_exr_options *opt, char *err, size_t err_size)
{
    fenv_t env; /* as pt__exr_read: the library runs in non-stop floating-point mode */
    int held = feholdexcept(&env) == 0, rc = pt__exr_write(path, img, opt, err, err_size);
    if (held) fesetenv(&env);
    return rc;
}

static int pt__exr_read_body(const char *path, pt__exr_src *src, pt_image *out, char *err, size_t err_size)
{
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    exr_context_t ctx = NULL;
    const exr_attr_chlist_t *chl = NULL;
    exr_attr_box2i_t dw;
    exr_storage_t storage;
    pt__exr_msg *mp = &src->msg;
    pt_image img;
    int32_t spc = 0;
    int64_t w, h, y;
    size_t n;
    int found[3] = { 0, 0, 0 }, c, rc;
    uint64_t budget = (uint64_t)(PDFTRACE_EXR_MAX_BYTES), image_bytes, chunk_bytes;
    exr_result_t rv;

    memset(&img, 0, sizeof img);
    init.error_handler_fn = pt__exr_error_cb;
    init.user_data = src;
    if (src->data) {
        init.read_fn = pt__exr_mem_read;
        init.size_fn = pt__exr_mem_size;
    }
    /* The header is parsed here: a missing file, a non-EXR file or a damaged header fail. */
    rv = exr_start_read(&ctx, path, &init);
    if (rv != EXR_ERR_SUCCESS) {
        if (ctx) exr_finish(&ctx);
        return pt__exr_lib_fail(err, err_size, PT_ERROR_IO, path, "cannot read as EXR", rv, mp);
    }
    rv = exr_get_storage(ctx, 0, &storage);
    if (rv == EXR_ERR_SUCCESS && storage != EXR_STORAGE_SCANLINE) {
        exr_finish(&ctx);
        return pt__exr_fail(err, err_size, PT_ERROR_UNSUPPORTED, path, "reading EXR",
                            "only scanline images are supported (tiled or deep part)");
    }
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_data_window(ctx, 0, &dw);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_channels(ctx, 0, &chl);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_scanlines_per_chunk(ctx, 0, &spc);
    if (rv != EXR_ERR_SUCCESS) {
        exr_finish(&ctx);
        return pt__exr_lib_fail(err, err_size, PT_ERROR_IO, path, "reading the header", rv, mp);
    }
    for (c = 0; chl && c < chl->num_channels; ++c) {
        int k = pt__exr_channel_index(chl->entries[c].name.str);
        if (k < 0) continue; /* A, Z, layers ...: ignored */
        if (chl->entries[c].x_sampling != 1 || chl->entries[c].y_sampling != 1) {
            exr_finish(&ctx);
            return pt__exr_fail(err, err_size, PT_ERROR_UNSUPPORTED, path, "reading EXR", "subsampled R, G or B channel");
        }
        found[k] = 1;
    }
    if (!found[0] || !found[1] || !found[2]) {
        exr_finish(&ctx);
        return pt__exr_fail(err, err_size, PT_ERROR_UNSUPPORTED, path, "reading EXR", "the image has no R, G and B channels");
    }
    w = (int64_t)dw.max.x - (int64_t)dw.min.x + 1;
    h = (int64_t)dw.max.y - (int64_t)dw.min.y + 1;
    if (w < 1 || h < 1 || w > INT32_MAX / 12 || h > INT32_MAX || spc < 1 || !pt__exr_pixels((int)w, (int)h, &n)) {
        exr_finish(&ctx);
        return pt__exr_fail(err, err_size, PT_ERROR_IO, path, "reading EXR", "bad data window");
    }
    if ((uint64_t)n > (uint64_t)(PDFTRACE_EXR_MAX_PIXELS)) {
        exr_finish(&ctx);
        return pt__exr_fail(err, err_size, PT_ERROR_UNSUPPORTED, path, "reading EXR",
                            "image larger than PDFTRACE_EXR_MAX_PIXELS pixels");
    }
    image_bytes = (uint64_t)n * 12u;
    chunk_bytes = pt__exr_chunk_bytes(chl, w, spc);
    if (image_bytes + chunk_bytes > budget) {
        char why[160];
        exr_finish(&ctx);
        snprintf(why, sizeof why, "a %lld x %lld image needs %llu MiB, more than PDFTRACE_EXR_MAX_BYTES (%llu MiB)",
                 (long long)w, (long long)h, (unsigned long long)((image_bytes + chunk_bytes) >> 20),
                 (unsigned long long)(budget >> 20));
        return pt__exr_fail(err, err_size, PT_ERROR_UNSUPPORTED, path, "reading EXR", why);
    }
    rc = pt_image_init(&img, (int)w, (int)h);
    if (rc != PT_OK) {
        exr_finish(&ctx);
        return pt__exr_fail(err, err_size, rc, path, "reading EXR", "cannot allocate the image");
    }
    for (y = dw.min.y; rv == EXR_ERR_SUCCESS && y <= dw.max.y; y += spc)
        rv = pt__exr_decode_chunk(ctx, (int)y, &dw, budget - image_bytes, img.rgb, 1, NULL, NULL);
    exr_finish(&ctx);
    if (rv != EXR_ERR_SUCCESS) {
        pt_image_free(&img);
        if (rv == EXR_ERR_OUT_OF_MEMORY && !mp->text[0])
            return pt__exr_fail(err, err_size, PT_ERROR_UNSUPPORTED, path, "reading EXR",
                                "a chunk needs more memory than PDFTRACE_EXR_MAX_BYTES allows");
        return pt__exr_lib_fail(err, err_size, PT_ERROR_IO, path, "reading pixels (corrupt or truncated file)", rv, mp);
    }
    *out = img;
    return PT_OK;
}

/* OpenEXRCore's own floating-point arithmetic (e.g. a NaN screenWindowWidth in a hostile header)
   runs in non-stop mode: a host that traps FE_INVALID must not die inside the library, and its
   exception flags and traps are restored afterwards (C99 feholdexcept / fesetenv). */
static int pt__exr_read(const char *path, pt__exr_src *src, pt_image *out, char *err, size_t err_size)
{
    fenv_t env;
    int held = feholdexcept(&env) == 0, rc = pt__exr_read_body(path, src, out, err, err_size);
    if (held) fesetenv(&env);
    return rc;
}

PTDEF int pt_read_exr(const char *path, pt_image *out, char *err, size_t err_size)
{
    pt__exr_src src;
    if (err && err_size) err[0] = '\0';
    if (out) memset(out, 0, sizeof *out);
    if (!path || !*path || !out)
        return pt__exr_fail(err, err_size, PT_ERROR_INVALID_ARGUMENT, path, "reading EXR", "no path or no output image");
    memset(&src, 0, sizeof src);
    return pt__exr_read(path, &src, out, err, err_size);
}

PTDEF int pt_read_exr_memory(const void *data, size_t size, const char *name, pt_image *out, char *err,
                             size_t err_size)
{
    pt__exr_src src;
    if (err && err_size) err[0] = '\0';
    if (!name || !*name) name = "<memory>";
    if (out) memset(out, 0, sizeof *out);
    if (!data || !out)
        return pt__exr_fail(err, err_size, PT_ERROR_INVALID_ARGUMENT, name, "reading EXR", "no data or no output image");
    memset(&src, 0, sizeof src);
    src.data = (const unsigned char *)data;
    src.size = size;
    return pt__exr_read(name, &src, out, err, err_size);
}

#ifdef __cplusplus
}
#endif

#endif /* PDFTRACE_EXR_IMPLEMENTATION_DONE */
#endif /* PDFTRACE_EXR_IMPLEMENTATION */

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
