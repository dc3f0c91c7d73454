/* test_rng.c - section 1 of pdftrace.h: the PCG32 generator, pt_rng_float and pt_rng_for_sample.

   Statistical tests use fixed seeds. False-failure rate: alpha = 0.01 for this file, Sidak-corrected
   over its RNG_STAT_TESTS statistical comparisons (1 - 0.99^(1/6) = 0.00167 each). */
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define RNG_STAT_TESTS 6
#define FILE_ALPHA 0.01

static double alpha_each(void) { return tu_sidak(FILE_ALPHA, RNG_STAT_TESTS); }

/* O'Neill's reference seeding (pcg32_srandom_r in the paper's minimal C edition): state 0,
   inc = 2 * seq + 1, step, state += initstate, step. */
static void reference_seed(pt_rng *r, uint64_t initstate, uint64_t seq)
{
    r->state = 0;
    r->inc = (seq << 1) | 1u;
    (void)pt_rng_u32(r);
    r->state += initstate;
    (void)pt_rng_u32(r);
}

static void pcg32_reference_vector(test_ctx *t)
{
    /* The published output of pcg32-demo (pcg-c-basic) for initstate 42, initseq 54. */
    static const uint32_t expected[6] = { 0xa15c02b7u, 0x7b47f409u, 0xba1d3330u, 0x83d2f293u, 0xbfa4784bu, 0xcbed606eu };
    pt_rng r, s;
    int i, same = 1;
    reference_seed(&r, 42u, 54u);
    for (i = 0; i < 6; i++) {
        uint32_t v = pt_rng_u32(&r);
        if (!CHECK(t, v == expected[i], "output %d of PCG32(42, 54) is 0x%08x, want 0x%08x", i, (unsigned)v,
                   (unsigned)expected[i]))
            break;
    }
    /* pt_rng_seed's scheme is not specified; report whether it is the reference one. */
    pt_rng_seed(&s, 42u, 54u);
    reference_seed(&r, 42u, 54u);
    for (i = 0; i < 6; i++) same &= pt_rng_u32(&s) == pt_rng_u32(&r);
    test_note(t, "pt_rng_seed(42, 54) %s the reference seeding", same ? "matches" : "differs from");
}

static void seed_determinism(test_ctx *t)
{
    pt_rng a, b, c, d;
    int i, same_ab = 1, same_ac = 1, same_ad = 1;
    pt_rng_seed(&a, 2024u, 5u);
    pt_rng_seed(&b, 2024u, 5u);
    pt_rng_seed(&c, 2025u, 5u);
    pt_rng_seed(&d, 2024u, 6u);
    CHECK(t, (a.inc & 1u) == 1u && (d.inc & 1u) == 1u, "increment is even: PCG needs an odd increment for full period");
    CHECK(t, a.inc != d.inc, "streams 5 and 6 have the same increment");
    for (i = 0; i < 1000; i++) {
        uint32_t x = pt_rng_u32(&a), y = pt_rng_u32(&b), z = pt_rng_u32(&c), w = pt_rng_u32(&d);
        same_ab &= x == y;
        same_ac &= x == z;
        same_ad &= x == w;
    }
    CHECK(t, same_ab, "the same (seed, stream) gave different sequences");
    CHECK(t, !same_ac, "seeds 2024 and 2025 gave the same sequence");
    CHECK(t, !same_ad, "streams 5 and 6 gave the same sequence");
}

static void float_range(test_ctx *t)
{
    pt_rng r;
    long i, bad = 0;
    float lo = 1.0f, hi = 0.0f;
    uint64_t x = 0;
    int bit;
    pt_rng_seed(&r, 77u, 1u);
    for (i = 0; i < 2000000; i++) {
        float u = pt_rng_float(&r);
        if (!(u >= 0.0f && u < 1.0f)) bad++;
        if (u < lo) lo = u;
        if (u > hi) hi = u;
    }
    CHECK(t, bad == 0, "%ld of 2e6 pt_rng_float values outside [0, 1)", bad);
    /* The largest output: build a state whose XSH-RR output is 0xffffffff (bits 27..58 of
       x ^ (x >> 18) all set, rotation 0) and check that pt_rng_float maps it below 1. */
    for (bit = 58; bit >= 27; bit--) {
        uint64_t hi_bit = bit + 18 <= 63 ? (x >> (bit + 18)) & 1u : 0u;
        x |= (uint64_t)(1u ^ (unsigned)hi_bit) << bit;
    }
    r.state = x;
    r.inc = 1;
    {
        pt_rng copy = r;
        uint32_t u32 = pt_rng_u32(&copy);
        float u = pt_rng_float(&r);
        CHECK(t, u32 == 0xffffffffu, "test construction: output 0x%08x", (unsigned)u32);
        CHECK(t, u < 1.0f && u == 16777215.0f / 16777216.0f, "pt_rng_float of 0xffffffff = %.9g, want 1 - 2^-24", u);
    }
    r.state = 0;
    r.inc = 1;
    CHECK(t, pt_rng_float(&r) == 0.0f, "pt_rng_float of output 0 is not 0");
    test_note(t, "min %.3g max %.9g over 2e6", lo, hi);
}

static void float_uniformity_chi2(test_ctx *t)
{
    /* 64 equal bins, 640000 draws: Pearson chi-square with 63 dof. */
    enum { BINS = 64 };
    long counts[BINS] = { 0 }, i, n = 640000;
    double chi2 = 0, e = (double)n / BINS, p, a = alpha_each();
    pt_rng r;
    pt_rng_seed(&r, 31337u, 9u);
    for (i = 0; i < n; i++) {
        int b = (int)(pt_rng_float(&r) * BINS);
        counts[b < BINS ? b : BINS - 1]++;
    }
    for (i = 0; i < BINS; i++) chi2 += (counts[i] - e) * (counts[i] - e) / e;
    p = tu_chi2_sf(chi2, BINS - 1);
    CHECK(t, p >= a, "chi-square %.1f (63 dof), p = %.3g < %.3g", chi2, p, a);
    test_note(t, "chi2 %.1f/63 dof, p = %.3f, alpha %.2g (0.01 Sidak over %d)", chi2, p, a, RNG_STAT_TESTS);
}

static double correlation(const double *x, const double *y, long n)
{
    double mx = 0, my = 0, sxy = 0, sxx = 0, syy = 0;
    long i;
    for (i = 0; i < n; i++) { mx += x[i]; my += y[i]; }
    mx /= n;
    my /= n;
    for (i = 0; i < n; i++) {
        sxy += (x[i] - mx) * (y[i] - my);
        sxx += (x[i] - mx) * (x[i] - mx);
        syy += (y[i] - my) * (y[i] - my);
    }
    return sxy / sqrt(sxx * syy);
}

static void rng_for_sample_purity(test_ctx *t)
{
    enum { P = 128, S = 64 };
    uint64_t *keys = (uint64_t *)malloc(sizeof(uint64_t) * P * S);
    int p, s, same = 1, differs_seed = 0;
    long dup = 0, i;
    pt_rng a, b, noise;
    if (!CHECK(t, keys != NULL, "out of memory")) return;
    pt_rng_seed(&noise, 5, 5);
    for (p = 0; p < P; p++) {
        for (s = 0; s < S; s++) {
            pt_rng r = pt_rng_for_sample(1234u, (uint32_t)p * 977u, (uint32_t)s);
            uint64_t hi = pt_rng_u32(&r);
            keys[p * S + s] = (hi << 32) | pt_rng_u32(&r);
        }
    }
    /* purity: the same inputs give the same stream later, whatever happened in between */
    for (p = 0; p < P && same; p += 7) {
        for (s = 0; s < S; s += 5) {
            pt_rng r;
            uint64_t hi;
            int k;
            for (k = 0; k < 3; k++) (void)pt_rng_u32(&noise);
            a = pt_rng_for_sample(1234u, (uint32_t)p * 977u, (uint32_t)s);
            r = a;
            hi = pt_rng_u32(&r);
            if (((hi << 32) | pt_rng_u32(&r)) != keys[p * S + s]) same = 0;
            b = pt_rng_for_sample(1235u, (uint32_t)p * 977u, (uint32_t)s);
            if (b.state != a.state || b.inc != a.inc) differs_seed++;
        }
    }
    CHECK(t, same, "pt_rng_for_sample is not a pure function of (seed, pixel, sample)");
    CHECK(t, differs_seed > 0, "pt_rng_for_sample ignores the seed");
    /* distinct (pixel, sample) pairs give distinct streams: the first 64 output bits of 8192 streams
       collide with probability ~8192^2 / 2^65 = 2e-12 if they are independent */
    for (i = 0; i < (long)P * S; i++) {
        long j;
        for (j = i + 1; j < (long)P * S; j++)
            if (keys[i] == keys[j]) dup++;
    }
    CHECK(t, dup == 0, "%ld pairs of (pixel, sample) streams start with the same 64 bits", dup);
    free(keys);
}

static void stream_correlation(test_ctx *t)
{
    /* Pearson correlation r of independent uniform sequences: sqrt(n) r ~ N(0, 1). Four
       comparisons: two pt_rng_seed streams; adjacent pixels and adjacent sample indices of
       pt_rng_for_sample; lag 1 within a stream. Plus a 16x16 chi-square of pixel-pair values. */
    enum { N = 200000 };
    double *x = (double *)malloc(sizeof(double) * (N + 1)), *y = (double *)malloc(sizeof(double) * (N + 1));
    double z = tu_z_two_sided(alpha_each()), r, worst = 0, a = alpha_each();
    pt_rng s1, s2;
    long i;
    long cells[256] = { 0 };
    double chi2 = 0, p;
    if (!CHECK(t, x && y, "out of memory")) { free(x); free(y); return; }
    pt_rng_seed(&s1, 99u, 1u);
    pt_rng_seed(&s2, 99u, 2u);
    for (i = 0; i < N; i++) { x[i] = pt_rng_float(&s1); y[i] = pt_rng_float(&s2); }
    r = correlation(x, y, N);
    worst = fmax(worst, fabs(r) * sqrt((double)N));
    CHECK(t, fabs(r) * sqrt((double)N) <= z, "streams 1 and 2: correlation %.4g (z = %.2f > %.2f)", r, r * sqrt((double)N), z);
    for (i = 0; i <= N; i++) {
        pt_rng q = pt_rng_for_sample(7u, (uint32_t)i, 0u);
        x[i] = pt_rng_float(&q);
    }
    r = correlation(x, x + 1, N);
    worst = fmax(worst, fabs(r) * sqrt((double)N));
    CHECK(t, fabs(r) * sqrt((double)N) <= z, "pixel p vs p+1: correlation %.4g (z = %.2f > %.2f)", r, r * sqrt((double)N), z);
    for (i = 0; i < N; i++) {
        pt_rng q = pt_rng_for_sample(7u, 4242u, (uint32_t)i);
        pt_rng q2 = pt_rng_for_sample(7u, 4242u, (uint32_t)i + 1u);
        x[i] = pt_rng_float(&q);
        y[i] = pt_rng_float(&q2);
    }
    r = correlation(x, y, N);
    worst = fmax(worst, fabs(r) * sqrt((double)N));
    CHECK(t, fabs(r) * sqrt((double)N) <= z, "sample s vs s+1: correlation %.4g (z = %.2f > %.2f)", r, r * sqrt((double)N), z);
    for (i = 0; i <= N; i++) x[i] = pt_rng_float(&s1);
    r = correlation(x, x + 1, N);
    worst = fmax(worst, fabs(r) * sqrt((double)N));
    CHECK(t, fabs(r) * sqrt((double)N) <= z, "lag-1 autocorrelation %.4g (z = %.2f > %.2f)", r, r * sqrt((double)N), z);
    /* joint uniformity of (first value of pixel p, first value of pixel p + 1) */
    for (i = 0; i <= N; i++) {
        pt_rng q = pt_rng_for_sample(8u, (uint32_t)i, 3u);
        x[i] = pt_rng_float(&q);
    }
    for (i = 0; i < N; i++) cells[(int)(x[i] * 16) * 16 + (int)(x[i + 1] * 16)]++;
    for (i = 0; i < 256; i++) chi2 += (cells[i] - N / 256.0) * (cells[i] - N / 256.0) / (N / 256.0);
    p = tu_chi2_sf(chi2, 255);
    CHECK(t, p >= a, "pairs of adjacent pixels: chi-square %.1f (255 dof), p = %.3g", chi2, p);
    test_note(t, "max |z| %.2f (limit %.2f), pair chi2 p = %.3f, alpha %.2g each", worst, z, p, a);
    free(x);
    free(y);
}

const test_case test_rng_cases[] = {
    TEST_CASE(pcg32_reference_vector),
    TEST_CASE(seed_determinism),
    TEST_CASE(float_range),
    TEST_CASE(float_uniformity_chi2),
    TEST_CASE(rng_for_sample_purity),
    TEST_CASE(stream_correlation),
    TEST_END
};
