#define _POSIX_C_SOURCE 200809L
/* stress_main.c - `make stress`: the numerical stress cases of issue 7 at full size.

   Usage: stress [--fast] [case-filter]   (--fast: the sizes of the runner's stress section)
   Prints the table  case | metric | bound | result  (one row per check, PASS or FAIL), the
   time per case, and exits with status 1 if any row failed. Statistical rows form one Sidak
   family with alpha = 0.01 for the whole run (see stress.h). */
#define PDFTRACE_IMPLEMENTATION
#include "pdftrace.h"
#include "stress.h"
#include "../test.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

/* test_util.c's PDF checker reports through the runner's check function; the stress cases do
   not use it, but the symbols must exist. */
int test_check_(test_ctx *t, int ok, const char *file, int line, const char *fmt, ...)
{
    (void)file; (void)line; (void)fmt;
    t->checks++;
    if (!ok) t->failures++;
    return ok;
}
void test_note(test_ctx *t, const char *fmt, ...) { (void)t; (void)fmt; }

static void print_row(void *user, const char *cas, const char *metric, const char *bound, const char *result, int pass)
{
    (void)user;
    printf("| %-32s | %-62s | %-18s | %-34s | %s |\n", cas, metric, bound, result, pass ? "PASS" : "FAIL");
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    static const struct { const char *name; void (*fn)(st_ctx *); } cases[] = {
        { "sweep", st_scale_sweep }, { "spawn", st_spawn }, { "tiny", st_tiny_light },
        { "point", st_point_light },
        { "watertight", st_watertight }, { "edges", st_edges }, { "lights", st_light_geometry },
        { "degenerate", st_degenerate }, { "slivers", st_slivers }, { "cornell", st_cornell_offset },
        { "guiding", st_guiding }, { "delta", st_delta_lights }, { "environment", st_environment },
        { "microfacet", st_microfacet }, { "plastic", st_plastic },
        { "roughglass", st_rough_dielectric },
    };
    const char *filter = NULL;
    int full = 1, a;
    st_ctx c;
    size_t i;
    double t0 = now();
    for (a = 1; a < argc; a++) {
        if (strcmp(argv[a], "--fast") == 0) full = 0;
        else filter = argv[a];
    }
    setvbuf(stdout, NULL, _IOLBF, 0);
    st_init(&c, full, print_row, NULL);
    printf("| %-32s | %-62s | %-18s | %-34s | %s |\n", "case", "metric", "bound", "result", "    ");
    printf("|%s|%s|%s|%s|------|\n", "----------------------------------",
           "----------------------------------------------------------------", "--------------------",
           "------------------------------------");
    for (i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double t1 = now();
        if (filter && !strstr(cases[i].name, filter)) continue;
        cases[i].fn(&c);
        fprintf(stderr, "stress: %s took %.1f s\n", cases[i].name, now() - t1);
    }
    st_family(&c);
    printf("\nstress: %d rows, %d failed, %.1f s (family: %ld z-comparisons, each at |z| <= %.2f, alpha 0.01 "
           "Sidak-corrected over %d)\n",
           c.rows, c.failed, now() - t0, c.comparisons, c.z_bound, c.max_comparisons);
    return c.failed ? 1 : 0;
}
