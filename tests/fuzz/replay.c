/* Corpus replay (make test): feeds every file of tests/fuzz/corpus/<target>/ to the harness
   entry point of that target (tests/fuzz/harness.c), the same code the libFuzzer targets
   run. A failing harness check or a sanitizer report aborts with the input's name; otherwise
   the last two lines are "fuzz replay: N inputs (...)" and "N passed, 0 failed, K skipped"
   (K: the exr inputs when the build has no OpenEXR). Inputs named accept-* must load, reject-*
   must be refused (with a message); others may do either.
   Usage: fuzz_replay CORPUS_DIR   (the directory holding scene/, obj/, pov/ and exr/)
   PT_FUZZ_VERBOSE=1: one line per input. PT_FUZZ_FPTRAP=1 (glibc): FE_INVALID and
   FE_DIVBYZERO trap (SIGFPE) while the inputs run, e.g. to replay a fuzzer's own corpus. */
#define _GNU_SOURCE 1
#include <dirent.h>
#include <fenv.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "harness.h"

static int trap_mode = 0;

/* SIGFPE in trap mode: name the input (async-signal-safe writes only) and exit 1. */
static void on_fpe(int sig)
{
    static const char msg[] = "fuzz replay: floating-point trap (FE_INVALID or FE_DIVBYZERO) in input ";
    const char *name = pt_fuzz_input_name ? pt_fuzz_input_name : "?";
    ssize_t w;
    (void)sig;
    w = write(2, msg, sizeof msg - 1);
    w = write(2, name, strlen(name));
    w = write(2, "\n", 1);
    (void)w;
    _exit(1);
}

typedef int (*entry_fn)(const uint8_t *, size_t);

static int cmp_names(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* Runs every regular file of dir/sub through fn, in name order; returns the count or -1. */
static long replay_dir(const char *dir, const char *sub, entry_fn fn)
{
    char path[4096];
    DIR *dp;
    struct dirent *de;
    char **names = NULL;
    size_t n = 0, cap = 0, i;
    long done = 0;
    snprintf(path, sizeof path, "%s/%s", dir, sub);
    dp = opendir(path);
    if (!dp) {
        fprintf(stderr, "fuzz replay: cannot open %s\n", path);
        return -1;
    }
    while ((de = readdir(dp)) != NULL) {
        if (de->d_name[0] == '.') continue;
        if (n == cap) {
            char **nn;
            cap = cap ? cap * 2 : 64;
            nn = (char **)realloc(names, cap * sizeof *names);
            if (!nn) { closedir(dp); return -1; }
            names = nn;
        }
        names[n] = (char *)malloc(strlen(de->d_name) + 1);
        if (!names[n]) { closedir(dp); return -1; }
        strcpy(names[n++], de->d_name);
    }
    closedir(dp);
    if (n) qsort(names, n, sizeof *names, cmp_names);
    for (i = 0; i < n; ++i) {
        FILE *f;
        unsigned char *buf = NULL;
        long len;
        snprintf(path, sizeof path, "%s/%s/%s", dir, sub, names[i]);
        f = fopen(path, "rb");
        if (!f || fseek(f, 0, SEEK_END) != 0 || (len = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
            fprintf(stderr, "fuzz replay: cannot read %s\n", path);
            if (f) fclose(f);
            return -1;
        }
        buf = (unsigned char *)malloc((size_t)len + 1);
        if (!buf || fread(buf, 1, (size_t)len, f) != (size_t)len) {
            fprintf(stderr, "fuzz replay: cannot read %s\n", path);
            fclose(f);
            free(buf);
            return -1;
        }
        fclose(f);
        pt_fuzz_input_name = path;
        pt_fuzz_expect = !strncmp(names[i], "accept-", 7) ? 1 : !strncmp(names[i], "reject-", 7) ? -1 : 0;
        fn(buf, (size_t)len); /* exactly len bytes: no terminator is promised to the harness */
        pt_fuzz_input_name = NULL;
        free(buf);
        free(names[i]);
        ++done;
    }
    free(names);
    return done;
}

#ifndef PDFTRACE_OPENEXR
/* The inputs of dir/sub that this build cannot replay (0 if there is no such directory). */
static long count_dir(const char *dir, const char *sub)
{
    char path[4096];
    DIR *dp;
    struct dirent *de;
    long n = 0;
    snprintf(path, sizeof path, "%s/%s", dir, sub);
    dp = opendir(path);
    if (!dp) return 0;
    while ((de = readdir(dp)) != NULL)
        if (de->d_name[0] != '.') ++n;
    closedir(dp);
    return n;
}
#endif

int main(int argc, char **argv)
{
    long ns, no, np, ne = 0, skipped = 0;
    if (argc != 2) {
        fprintf(stderr, "usage: %s CORPUS_DIR\n", argv[0]);
        return 2;
    }
    pt_fuzz_verbose = getenv("PT_FUZZ_VERBOSE") != NULL && getenv("PT_FUZZ_VERBOSE")[0] == '1';
    if (getenv("PT_FUZZ_FPTRAP") != NULL && getenv("PT_FUZZ_FPTRAP")[0] == '1') {
#if defined(__GLIBC__) && defined(FE_INVALID) && defined(FE_DIVBYZERO)
        feenableexcept(FE_INVALID | FE_DIVBYZERO);
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_fpe;
        sigaction(SIGFPE, &sa, NULL);
        trap_mode = 1;
#else
        fprintf(stderr, "fuzz replay: PT_FUZZ_FPTRAP ignored (needs glibc's feenableexcept)\n");
#endif
    }
    ns = replay_dir(argv[1], "scene", pt_fuzz_scene);
    no = replay_dir(argv[1], "obj", pt_fuzz_obj);
    np = replay_dir(argv[1], "pov", pt_fuzz_pov);
#ifdef PDFTRACE_OPENEXR
    ne = replay_dir(argv[1], "exr", pt_fuzz_exr);
#endif
    if (ns < 0 || no < 0 || np < 0 || ne < 0) return 1;
    if (trap_mode) printf("fuzz replay: FE_INVALID and FE_DIVBYZERO trapped\n");
    if (ns == 0 || no == 0 || np == 0) {
        fprintf(stderr, "fuzz replay: empty corpus (scene %ld, obj %ld, pov %ld)\n", ns, no, np);
        return 1;
    }
#ifdef PDFTRACE_OPENEXR
    printf("fuzz replay: %ld inputs (scene %ld, obj %ld, pov %ld, exr %ld)\n", ns + no + np + ne, ns, no, np, ne);
#else
    skipped = count_dir(argv[1], "exr");
    printf("fuzz replay: %ld inputs (scene %ld, obj %ld, pov %ld); %ld exr inputs skipped: OpenEXR not compiled in\n",
           ns + no + np, ns, no, np, skipped);
#endif
    printf("%ld passed, 0 failed, %ld skipped\n", ns + no + np + ne, skipped);
    return 0;
}
