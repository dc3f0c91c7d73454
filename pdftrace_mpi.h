/* pdftrace_mpi.h - distributed rendering for pdftrace.h over MPI.
   Part of the pdftrace header family. LICENSE: MIT or public domain, your choice (full text at
   the end of this file).

   ABOUT
   =====
   pdftrace.h splits a render without knowing about MPI: pt_render_desc.split_parts and
   split_part deal the samples out to the parts, and a merge hook (pt_merge_fn) combines what
   the parts hold where the render needs the whole (adaptive sampling's plans, the end). This
   header is that hook over an MPI communicator, plus the two collective steps a driver needs
   around it: agreeing that every rank is ready (or naming the first that is not), and summing
   the render statistics. The combination keeps rank order: rank 0 receives rank 1's buffer,
   adds it, then rank 2's, and so on (MPI_Reduce is not used: its order is unspecified, and
   floating-point addition is not associative; pt_film's sums are exact, so the bytes are those
   of a one-process render either way, but the order is what the core promises). Rank 0 thus
   receives N - 1 films one after the other: fine to about a hundred ranks; past that an
   order-keeping tree (docs/mpi.md) would replace the loop behind the same hook.
   The MPI driver of the pdftrace command (tools/pdftrace.c, make MPI=1) uses it; design and
   measurements: docs/mpi.md.

   BUILDING
   ========
   In exactly one C or C++ file (it may be the file that implements pdftrace.h, or another):
       #define PDFTRACE_MPI_IMPLEMENTATION
       #include "pdftrace_mpi.h"
   This header includes pdftrace.h and <mpi.h>: compile with mpicc (Open MPI or MPICH; Debian:
   apt-get install libopenmpi-dev openmpi-bin), or with `mpicc --showme:compile` and
   `--showme:link`. MPI must be initialised (MPI_Init) before any call.

   USAGE
   =====
       pt_mpi mpi;
       pt_mpi_init(&mpi, MPI_COMM_WORLD);
       int ok = load_my_scene(...);                       (every rank loads the scene)
       int first = pt_mpi_agree(&mpi, ok);                (-1: every rank is ready)
       if (first >= 0) { if (!ok && mpi.rank == first) print_my_error(); exit; }
       pt_mpi_split(&mpi, &desc);                         (split_parts, split_part, merge)
       pt_render(scene, &desc, &film, &stats);            (part 0's film: the whole render)
       pt_mpi_stats_sum(&mpi, &stats);                    (rank 0: the counters of all ranks)
       if (mpi.rank == 0) write the film;
   A rank whose pt_render fails after others may have entered the hook must end the job
   (MPI_Abort): the others would wait for it in the hook for ever.
*/
#ifndef PDFTRACE_MPI_H
#define PDFTRACE_MPI_H

#include "pdftrace.h"
#include <mpi.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct pt_mpi {
    MPI_Comm comm;
    int rank, size;
    size_t bytes_merged;  /* bytes this rank sent or received in the hook so far */
    double seconds;       /* wall clock this rank spent in the hook (waiting for others included) */
} pt_mpi;

/* Fills *mpi for the communicator (its rank and size). PT_OK or PT_ERROR_INVALID_ARGUMENT. */
PTDEF int pt_mpi_init(pt_mpi *mpi, MPI_Comm comm);
/* Collective. Every rank passes whether it is ready; returns -1 when all are, else the lowest
   rank that is not (the same on every rank). -2 if MPI itself failed. */
PTDEF int pt_mpi_agree(pt_mpi *mpi, int ok);
/* Sets desc->split_parts, split_part, merge and merge_user for this rank (a size-1 communicator
   leaves the render whole). */
PTDEF void pt_mpi_split(pt_mpi *mpi, pt_render_desc *desc);
/* The merge hook (pt_merge_fn); user is the pt_mpi. */
PTDEF int pt_mpi_merge(void *user, void *buffer, size_t bytes, int everyone, pt_merge_add_fn add, void *ctx);
/* Collective. On rank 0, *stats becomes the sum over ranks of the counters (samples, rays,
   non-finite samples, splits, guided vertices; threads summed, seconds the largest); the film's
   statistics (min/max spp, pixels converged, estimated error) are rank 0's, which has the
   merged film. Other ranks keep their own. PT_OK, or PT_ERROR_IO if MPI failed. */
PTDEF int pt_mpi_stats_sum(pt_mpi *mpi, pt_render_stats *stats);

#ifdef __cplusplus
}
#endif

#endif /* PDFTRACE_MPI_H */

#ifdef PDFTRACE_MPI_IMPLEMENTATION
#ifndef PDFTRACE_MPI_IMPLEMENTED
#define PDFTRACE_MPI_IMPLEMENTED

#include <stdlib.h>
#include <string.h>

#define PT__MPI_CHUNK ((size_t)1 << 30) /* MPI counts are int: big buffers go in pieces of 1 GiB */

PTDEF int pt_mpi_init(pt_mpi *mpi, MPI_Comm comm)
{
    if (!mpi) return PT_ERROR_INVALID_ARGUMENT;
    memset(mpi, 0, sizeof *mpi);
    mpi->comm = comm;
    if (MPI_Comm_rank(comm, &mpi->rank) != MPI_SUCCESS || MPI_Comm_size(comm, &mpi->size) != MPI_SUCCESS)
        return PT_ERROR_INVALID_ARGUMENT;
    return PT_OK;
}

PTDEF int pt_mpi_agree(pt_mpi *mpi, int ok)
{
    int mine = ok ? mpi->size : mpi->rank, first = 0;
    if (MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, mpi->comm) != MPI_SUCCESS) return -2;
    return first < mpi->size ? first : -1;
}

PTDEF void pt_mpi_split(pt_mpi *mpi, pt_render_desc *d)
{
    if (mpi->size <= 1) return;
    d->split_parts = mpi->size;
    d->split_part = mpi->rank;
    d->merge = pt_mpi_merge;
    d->merge_user = mpi;
}

static int pt__mpi_send(pt_mpi *m, const unsigned char *p, size_t n, int to)
{
    while (n > 0) {
        size_t k = n < PT__MPI_CHUNK ? n : PT__MPI_CHUNK;
        if (MPI_Send(p, (int)k, MPI_BYTE, to, 1, m->comm) != MPI_SUCCESS) return 0;
        p += k;
        n -= k;
    }
    return 1;
}
static int pt__mpi_recv(pt_mpi *m, unsigned char *p, size_t n, int from)
{
    while (n > 0) {
        size_t k = n < PT__MPI_CHUNK ? n : PT__MPI_CHUNK;
        if (MPI_Recv(p, (int)k, MPI_BYTE, from, 1, m->comm, MPI_STATUS_IGNORE) != MPI_SUCCESS) return 0;
        p += k;
        n -= k;
    }
    return 1;
}
static int pt__mpi_bcast(pt_mpi *m, unsigned char *p, size_t n)
{
    while (n > 0) {
        size_t k = n < PT__MPI_CHUNK ? n : PT__MPI_CHUNK;
        if (MPI_Bcast(p, (int)k, MPI_BYTE, 0, m->comm) != MPI_SUCCESS) return 0;
        p += k;
        n -= k;
    }
    return 1;
}

/* Rank 0 receives rank 1, 2, ... in turn into one scratch buffer and adds each into its own;
   with everyone, it then broadcasts the result. */
PTDEF int pt_mpi_merge(void *user, void *buffer, size_t bytes, int everyone, pt_merge_add_fn add, void *ctx)
{
    pt_mpi *m = (pt_mpi *)user;
    double t0 = MPI_Wtime();
    int ok = 1, r;
    if (m->rank == 0) {
        unsigned char *tmp = m->size > 1 ? (unsigned char *)malloc(bytes ? bytes : 1u) : NULL;
        if (m->size > 1 && !tmp) return 1;
        for (r = 1; r < m->size && ok; ++r) {
            ok = pt__mpi_recv(m, tmp, bytes, r);
            if (ok) add(ctx, buffer, tmp);
            m->bytes_merged += bytes;
        }
        free(tmp);
    } else {
        ok = pt__mpi_send(m, (const unsigned char *)buffer, bytes, 0);
        m->bytes_merged += bytes;
    }
    if (ok && everyone) {
        ok = pt__mpi_bcast(m, (unsigned char *)buffer, bytes);
        m->bytes_merged += bytes;
    }
    m->seconds += MPI_Wtime() - t0;
    return ok ? 0 : 1;
}

PTDEF int pt_mpi_stats_sum(pt_mpi *m, pt_render_stats *st)
{
    pt_render_stats *all = NULL;
    int r;
    if (m->size <= 1) return PT_OK;
    if (m->rank == 0 && !(all = (pt_render_stats *)malloc(sizeof *st * (size_t)m->size))) return PT_ERROR_OUT_OF_MEMORY;
    /* the same program on every rank: the struct's bytes are the same layout */
    if (MPI_Gather(st, (int)sizeof *st, MPI_BYTE, all, (int)sizeof *st, MPI_BYTE, 0, m->comm) != MPI_SUCCESS) {
        free(all);
        return PT_ERROR_IO;
    }
    if (m->rank == 0) {
        for (r = 1; r < m->size; ++r) {
            const pt_render_stats *o = &all[r];
            st->samples += o->samples;
            st->camera_rays += o->camera_rays;
            st->bounce_rays += o->bounce_rays;
            st->shadow_rays += o->shadow_rays;
            st->nonfinite_samples += o->nonfinite_samples;
            st->split_paths += o->split_paths;
            st->guided_vertices += o->guided_vertices;
            st->threads += o->threads;
            if (o->seconds > st->seconds) st->seconds = o->seconds;
        }
        free(all);
    }
    return PT_OK;
}

#endif /* PDFTRACE_MPI_IMPLEMENTED */
#endif /* PDFTRACE_MPI_IMPLEMENTATION */


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
