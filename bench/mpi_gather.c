/* mpi_gather.c - the time of the film gather of a split render (make bench-mpi; docs/mpi.md).
       mpirun -np N build/bench_mpi_gather [REPEATS]
   For films of growing size, every rank fills a merge buffer laid out as pdftrace.h's (18 doubles
   and a count per pixel: the film's sums, squares, half-buffer sums and their low words), then
   after a barrier pt_mpi_merge gathers them on rank 0 in rank order, adding each with pt_film_add
   (the same work as the core's merge). Rank 0 prints one row per size: pixels, megabytes per
   rank, the median time of REPEATS gathers (default 5), and the rate it received at. */
#define _POSIX_C_SOURCE 200809L
#define PDFTRACE_IMPLEMENTATION
#define PDFTRACE_MPI_IMPLEMENTATION
#include "pdftrace_mpi.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct layout { size_t np; int w, h; } layout;

static void view(const layout *l, unsigned char *buf, pt_film *f)
{
    double *d = (double *)(void *)buf;
    f->width = l->w;
    f->height = l->h;
    f->sum = d;
    f->sum_sq = d + 3u * l->np;
    f->sum_odd = d + 6u * l->np;
    f->low = d + 9u * l->np;
    f->count = (uint32_t *)(void *)(d + 18u * l->np);
}
static void add(void *ctx, void *acc, const void *part)
{
    const layout *l = (const layout *)ctx;
    pt_film a, b;
    view(l, (unsigned char *)acc, &a);
    view(l, (unsigned char *)(uintptr_t)part, &b);
    pt_film_add(&a, &b);
}
static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int main(int argc, char **argv)
{
    static const int sizes[][2] = { { 256, 256 }, { 512, 512 }, { 1024, 1024 }, { 1920, 1080 }, { 2048, 2048 } };
    pt_mpi m;
    int repeats = argc > 1 ? atoi(argv[1]) : 5, k, r;
    MPI_Init(&argc, &argv);
    pt_mpi_init(&m, MPI_COMM_WORLD);
    if (repeats < 1 || repeats > 99) repeats = 5;
    if (m.rank == 0) printf("| ranks | pixels | MB per rank | median gather (s) | received (MB/s) |\n|---|---|---|---|---|\n");
    for (k = 0; k < (int)(sizeof sizes / sizeof sizes[0]); ++k) {
        layout l;
        size_t bytes, i;
        unsigned char *buf;
        double t[99];
        pt_film f;
        l.w = sizes[k][0];
        l.h = sizes[k][1];
        l.np = (size_t)l.w * (size_t)l.h;
        bytes = l.np * (18u * sizeof(double) + sizeof(uint32_t));
        buf = (unsigned char *)malloc(bytes);
        if (!buf) MPI_Abort(MPI_COMM_WORLD, 1);
        for (r = 0; r < repeats; ++r) {
            view(&l, buf, &f);
            for (i = 0; i < 18u * l.np; ++i) f.sum[i] = 0.0; /* (sum .. low are one run of doubles) */
            for (i = 0; i < 3u * l.np; ++i) f.sum[i] = f.sum_sq[i] = f.sum_odd[i] = (double)(i % 97) * 0.01;
            for (i = 0; i < l.np; ++i) f.count[i] = 16u;
            MPI_Barrier(MPI_COMM_WORLD);
            t[r] = MPI_Wtime();
            if (pt_mpi_merge(&m, buf, bytes, 0, add, &l) != 0) MPI_Abort(MPI_COMM_WORLD, 1);
            t[r] = MPI_Wtime() - t[r];
        }
        qsort(t, (size_t)repeats, sizeof t[0], cmp_double);
        if (m.rank == 0)
            printf("| %d | %d x %d | %.1f | %.4f | %.0f |\n", m.size, l.w, l.h, (double)bytes / 1e6, t[repeats / 2],
                   (double)bytes * (double)(m.size - 1) / 1e6 / t[repeats / 2]);
        free(buf);
    }
    MPI_Finalize();
    return 0;
}
