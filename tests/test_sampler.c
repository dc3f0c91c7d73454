/* test_sampler.c - the samplers (pt_render_desc.sampler): PT_SAMPLER_SOBOL's points and renders.

   What is checked, and at which level:
   - sobol_sequence: pt_sobol_u32 against the sequence built here from its definition (van der
     Corput; Sobol's dimensions 1, 2, 3 from the Bratley & Fox recurrence with Joe & Kuo's
     parameters s = 1, a = 0, m = 1; s = 2, a = 1, m = 1, 3; s = 3, a = 1, m = 1, 3, 1), exactly.
   - sobol_definition: pt_sobol_scrambled and pt_sobol_scrambled4 against the scramble built here
     from section 2's comment (SplitMix64 seeds, the nested hash, whole 32-bit reversals), bit for
     bit, over 4096 indices spread below 2^16, around 2^16 and up to 2^32 - 1 (every entry of the
     library's byte tables is used). Exact.
   - sobol_nets: every aligned block of 2^m points of pt_sobol_scrambled (m = 0..12, several
     seeds, blocks at the start, further in and across the 2^16 boundary of the index shuffle) is
     a (0,m,2)-net: each of the 2^m elementary intervals of every shape 2^-a x 2^-(m-a) holds
     exactly one point; so is the unscrambled sequence; values in [0, 1). Exact.
   - sobol_randomised: the scramble is not the identity and depends on the seed (exact), and the
     point of a fixed index over many seeds is uniform on the unit square (Pearson chi-square on a
     16 x 16 grid, 4 indices, in the suite's chi-square family: tu_suite_alpha each).
   - sobol4_nets: pt_sobol_scrambled4 (Sobol's dimensions 0..3, the renderer's pairs of scattered
     directions): its first two coordinates are pt_sobol_scrambled's, and every 2D projection of an
     aligned block of 2^m points (m <= 12, several seeds and blocks) is a (t,m,2)-net with the t of
     the unscrambled sequence's first 2^m points; dims (2, 3) have t <= 2. Exact. Dimensions 2 and
     3 are also checked in sobol_sequence (against the recurrence, Joe & Kuo's d = 3, 4) and
     sobol_randomised (uniform over seeds, 2 more chi-square cases).
   - sobol_variance: on a smooth integrand the variance of the 256-point scrambled-Sobol estimate
     over 64 seeds must be below a tenth of the independent estimator's exact variance, at 99 %
     confidence (the chi-square upper bound of the variance estimate, alpha = 0.01); and the same
     for pt_sobol_scrambled4 on a product of two centred 2D integrands (pure interaction, which two
     separately shuffled 2D sets would estimate at the independent rate; alpha = 0.01).
   - render_unbiased: Sobol renders against analytic images (a plane under a sphere, a quad and a
     triangle light, direct light) and the closed furnace (every pixel 1, long paths: every bounce
     slot and Russian roulette), and against independent renders of a Cornell box with glass
     (MIS, mixture, material and light strategies, and a guide PDF, which draws from the PCG
     stream): 9 comparisons, family-wise alpha 0.01 (Sidak). A Sobol pixel's variance cannot be
     estimated from its own samples (they are not independent), so each test uses the pixels as
     the independent replicates: every pixel has its own random scramble, so the pixel errors
     d_p = x_p - expected_p are independent with mean 0 when the renderer is unbiased; z = mean(d)
     / se(d) over the pixels.
   - render_variance: the per-pixel variance over 12 seeds of direct-light renders of the quad
     plane scene must be lower with Sobol than with independent sampling by a factor 2 (the
     ratio of the summed variances, each a sum of independent pixel estimates; margin: measured
     ~0.1); the check can fail.
   - render_deterministic: same seed, same film (also with 1 and 2 threads and adaptive
     sampling); progressive (1 + 3 + 12 spp in three pt_render calls, or 16 passes) equals one
     pass; another seed or the independent sampler gives another image; bad sampler values are
     rejected; the scene file's `sampler` statement. Exact. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "pdftrace_scene.h" /* the cornell.scene comparison and the `sampler` statement */
#include "test.h"
#include "test_util.h"

/* ---- the sequence from its definition ---- */

/* Direction numbers v_k = m_k / 2^k of a Sobol dimension (Bratley & Fox, "Algorithm 659",
   ACM TOMS 14(1), 1988): m_k = 2 a_1 m_{k-1} ^ ... ^ 2^(s-1) a_(s-1) m_{k-s+1} ^ 2^s m_{k-s} ^ m_{k-s},
   as 32-bit fractions. */
static void sobol_directions(int s, unsigned a, const unsigned *m_init, uint32_t v[32])
{
    uint32_t m[33];
    int k, i;
    for (k = 1; k <= 32; ++k) {
        if (k <= s) m[k] = m_init[k - 1];
        else {
            uint32_t x = m[k - s] ^ (m[k - s] << s);
            for (i = 1; i < s; ++i)
                if ((a >> (s - 1 - i)) & 1u) x ^= m[k - i] << i;
            m[k] = x;
        }
        v[k - 1] = m[k] << (32 - k);
    }
}

static uint32_t sobol_ref(const uint32_t v[32], uint32_t i)
{
    uint32_t x = 0;
    int j;
    for (j = 0; j < 32; ++j)
        if ((i >> j) & 1u) x ^= v[j];
    return x;
}

static void sobol_sequence(test_ctx *t)
{
    static const unsigned m1[1] = {1};
    uint32_t v0[32], v1[32], i;
    int j, bad = 0;
    for (j = 0; j < 32; ++j) v0[j] = 1u << (31 - j); /* van der Corput */
    sobol_directions(1, 0, m1, v1);                   /* Joe & Kuo's d = 2: s = 1, a = 0, m = 1 */
    for (i = 0; i < 70000u && bad < 5; ++i) {
        uint32_t a = pt_sobol_u32(i, 0), b = pt_sobol_u32(i, 1);
        if (!CHECK(t, a == sobol_ref(v0, i) && b == sobol_ref(v1, i), "point %u: (%08x, %08x), want (%08x, %08x)", i,
                   a, b, sobol_ref(v0, i), sobol_ref(v1, i)))
            ++bad;
    }
    for (j = 0; j < 32; ++j) { /* single bits up to the top */
        i = 1u << j;
        CHECK(t, pt_sobol_u32(i, 1) == v1[j], "direction number %d: %08x, want %08x", j, pt_sobol_u32(i, 1), v1[j]);
        CHECK(t, pt_sobol_u32(i | 0x5a5au, 1) == sobol_ref(v1, i | 0x5a5au), "point %u", i | 0x5a5au);
    }
    /* the textbook start: 0, 1/2, 3/4, 1/4, 5/8 for dimension 2 */
    CHECK(t, pt_sobol_u32(1, 1) == 0x80000000u && pt_sobol_u32(2, 1) == 0xc0000000u && pt_sobol_u32(3, 1) == 0x40000000u &&
                 pt_sobol_u32(4, 1) == 0xa0000000u,
          "Sobol dimension 2 starts %08x %08x %08x %08x", pt_sobol_u32(1, 1), pt_sobol_u32(2, 1), pt_sobol_u32(3, 1),
          pt_sobol_u32(4, 1));
    /* dimensions 2 and 3: Joe & Kuo's d = 3 (s = 2, a = 1, m = 1, 3) and d = 4 (s = 3, a = 1, m = 1, 3, 1) */
    {
        static const unsigned m2[2] = {1, 3}, m3[3] = {1, 3, 1};
        uint32_t v2[32], v3[32];
        sobol_directions(2, 1, m2, v2);
        sobol_directions(3, 1, m3, v3);
        for (i = 0, bad = 0; i < 70000u && bad < 5; ++i) {
            uint32_t a = pt_sobol_u32(i, 2), b = pt_sobol_u32(i, 3);
            if (!CHECK(t, a == sobol_ref(v2, i) && b == sobol_ref(v3, i), "dims 2, 3, point %u: (%08x, %08x), want (%08x, %08x)",
                       i, a, b, sobol_ref(v2, i), sobol_ref(v3, i)))
                ++bad;
        }
        for (j = 0; j < 32; ++j) {
            i = 1u << j;
            CHECK(t, pt_sobol_u32(i, 2) == v2[j] && pt_sobol_u32(i, 3) == v3[j], "dims 2, 3: direction number %d", j);
            CHECK(t, pt_sobol_u32(i | 0xa5a5u, 3) == sobol_ref(v3, i | 0xa5a5u), "dim 3: point %u", i | 0xa5a5u);
        }
        /* the textbook start of dimensions 3 and 4 (1-based), Gray-code order 1, 3, 2, 6: 1/2, 1/4, 3/4, 5/8 and
           1/2, 1/4, 3/4, 7/8 */
        CHECK(t, pt_sobol_u32(1, 2) == 0x80000000u && pt_sobol_u32(3, 2) == 0x40000000u && pt_sobol_u32(2, 2) == 0xc0000000u &&
                     pt_sobol_u32(6, 2) == 0xa0000000u && pt_sobol_u32(6, 3) == 0xe0000000u,
              "Sobol dimensions 3, 4 start differently: %08x %08x %08x %08x / %08x", pt_sobol_u32(1, 2), pt_sobol_u32(3, 2),
              pt_sobol_u32(2, 2), pt_sobol_u32(6, 2), pt_sobol_u32(6, 3));
    }
    CHECK(t, pt_sobol_u32(5, 4) == 0u && pt_sobol_u32(5, -1) == 0u, "dimensions outside 0..3 give 0");
}

/* ---- the scramble from its definition ---- */

static uint32_t rev32(uint32_t x)
{
    uint32_t r = 0;
    int b;
    for (b = 0; b < 32; ++b) r |= ((x >> b) & 1u) << (31 - b);
    return r;
}
static uint64_t splitmix64(uint64_t z) /* Steele, Lea & Flood 2014's finaliser */
{
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}
static uint32_t lk_hash(uint32_t x, uint32_t add, uint32_t mul) /* section 2's nested hash */
{
    x += add;
    x ^= x * 0xf9b439fcu;
    x *= mul | 1u;
    x ^= x * 0x91d93080u;
    x ^= x * 0x8142c8eau;
    return x;
}
/* Owen scramble of a coordinate (its 32 bits) to the float of the top 24 bits. */
static float owen_ref(uint32_t x, uint32_t add, uint32_t mul)
{
    return (float)(rev32(lk_hash(rev32(x), add, mul)) >> 8) / 16777216.0f;
}
/* pt_sobol_scrambled4 as section 2's comment and pt__sobol_seeds define it, step by step with
   whole 32-bit reversals. */
static void scrambled4_ref(uint32_t index, uint64_t seed, float u[4])
{
    uint64_t h1 = splitmix64(seed), h2 = splitmix64(h1 ^ 0x2545f4914f6cdd1dULL);
    uint64_t h3 = splitmix64(h2 ^ 0x6c62272e07bb0142ULL), h4 = splitmix64(h3 ^ 0x2545f4914f6cdd1dULL);
    uint32_t s = (uint32_t)h1, ir = rev32(index);
    uint32_t k = rev32((lk_hash(ir, s, s >> 15) & 0xffff0000u) | (ir & 0xffffu)); /* 1. shuffle */
    u[0] = owen_ref(pt_sobol_u32(k, 0), (uint32_t)(h1 >> 32), (uint32_t)(h2 >> 48));
    u[1] = owen_ref(pt_sobol_u32(k, 1), (uint32_t)h2, (uint32_t)(h2 >> 32) & 0xffffu);
    u[2] = owen_ref(pt_sobol_u32(k, 2), (uint32_t)h3, (uint32_t)h4);
    u[3] = owen_ref(pt_sobol_u32(k, 3), (uint32_t)(h3 >> 32), (uint32_t)(h4 >> 32));
}

/* pt_sobol_scrambled and pt_sobol_scrambled4 equal the definition above bit for bit (the library
   computes it with byte tables and partial reversals): 4096 indices spread over 0..2^16 - 1 (so
   every entry of those tables is used), around 2^16 and up to 2^32 - 1, several seeds. */
static void sobol_definition(test_ctx *t)
{
    static const uint64_t seeds[] = {0u, 1u, 0x243f6a8885a308d3ULL, 0xffffffffffffffffULL, 0x9e3779b97f4a7c15ULL};
    static const uint32_t extra[] = {65535u, 65536u, 65537u, 0x1234567u, 0x80000000u, 0xfffffffeu, 0xffffffffu};
    int si, bad = 0, n = 0;
    uint32_t j;
    for (si = 0; si < (int)(sizeof seeds / sizeof seeds[0]); ++si)
        for (j = 0; j < 4096u + (uint32_t)(sizeof extra / sizeof extra[0]) && bad < 5; ++j) {
            uint32_t i = j < 4096u ? (j * 0x9e3779b1u) & 0xffffu : extra[j - 4096u];
            float u[4], v[2], w[4];
            pt_sobol_scrambled4(i, seeds[si], u);
            pt_sobol_scrambled(i, seeds[si], v);
            scrambled4_ref(i, seeds[si], w);
            ++n;
            if (!CHECK(t, memcmp(u, w, sizeof u) == 0 && memcmp(v, w, sizeof v) == 0,
                       "seed %d index %u: (%.9g %.9g %.9g %.9g), 2D (%.9g %.9g), want (%.9g %.9g %.9g %.9g)", si, i, u[0],
                       u[1], u[2], u[3], v[0], v[1], w[0], w[1], w[2], w[3]))
                ++bad;
        }
    test_note(t, "%d points equal", n);
}

/* ---- nets ---- */

/* Whether the n = 2^m points (x[i], y[i]) in [0,1) form a (0,m,2)-net in base 2. */
static int is_net(const double *x, const double *y, int m, int *bad_a)
{
    int n = 1 << m, a, i;
    unsigned char *seen = (unsigned char *)malloc((size_t)n);
    if (!seen) return 0;
    for (a = 0; a <= m; ++a) {
        int b = m - a;
        memset(seen, 0, (size_t)n);
        for (i = 0; i < n; ++i) {
            int cx = (int)floor(x[i] * (double)(1 << a)), cy = (int)floor(y[i] * (double)(1 << b));
            int cell = (cx << b) | cy;
            if (cx < 0 || cx >= (1 << a) || cy < 0 || cy >= (1 << b) || seen[cell]) {
                free(seen);
                *bad_a = a;
                return 0;
            }
            seen[cell] = 1;
        }
    }
    free(seen);
    return 1;
}

/* The smallest t for which the n = 2^m points form a (t,m,2)-net in base 2 (every elementary
   interval of area 2^(t-m) holds exactly 2^t points); -1 on a point outside [0,1)^2. */
static int net_t(const double *x, const double *y, int m)
{
    int n = 1 << m, t, a, i;
    int *cnt = (int *)malloc(sizeof(int) * (size_t)n);
    if (!cnt) return -1;
    for (i = 0; i < n; ++i)
        if (!(x[i] >= 0.0 && x[i] < 1.0 && y[i] >= 0.0 && y[i] < 1.0)) {
            free(cnt);
            return -1;
        }
    for (t = 0; t < m; ++t) {
        int ok = 1, k = m - t;
        for (a = 0; a <= k && ok; ++a) {
            int b = k - a;
            memset(cnt, 0, sizeof(int) * ((size_t)1 << k));
            for (i = 0; i < n; ++i) cnt[((int)floor(x[i] * (double)(1 << a)) << b) | (int)floor(y[i] * (double)(1 << b))]++;
            for (i = 0; i < (1 << k) && ok; ++i) ok = cnt[i] == (1 << t);
        }
        if (ok) break;
    }
    free(cnt);
    return t;
}

/* pt_sobol_scrambled4: u[0], u[1] are pt_sobol_scrambled's; each 2D projection of an aligned block of
   2^m points is a (t,m,2)-net with the t of the same projection of the unscrambled sequence's first
   2^m points (an Owen scramble and the nested index shuffle keep elementary intervals whole); the
   projection (2, 3), a scattered direction of its own, has t <= 2 for m <= 12. Exact. */
static void sobol4_nets(test_ctx *t)
{
    static const uint64_t seeds[] = {3u, 0x243f6a8885a308d3ULL, 0xffffffffffffffffULL};
    static const uint32_t starts[] = {0u, 3u, 65535u};
    enum { MMAX = 12 };
    double *c[4], *r[4];
    int m, si, bi, d0, d1, k, blocks = 0, worst23 = 0;
    uint32_t i;
    for (k = 0; k < 4; ++k) {
        c[k] = (double *)malloc(sizeof(double) << MMAX);
        r[k] = (double *)malloc(sizeof(double) << MMAX);
        if (!CHECK(t, c[k] && r[k], "out of memory")) goto done;
    }
    for (m = 1; m <= MMAX; ++m) {
        int n = 1 << m, tref[4][4];
        for (i = 0; i < (uint32_t)n; ++i)
            for (k = 0; k < 4; ++k) r[k][i] = pt_sobol_u32(i, k) / 4294967296.0;
        for (d0 = 0; d0 < 4; ++d0)
            for (d1 = d0 + 1; d1 < 4; ++d1) tref[d0][d1] = net_t(r[d0], r[d1], m);
        CHECK(t, tref[0][1] == 0 && tref[2][3] >= 0 && tref[2][3] <= 2, "unscrambled, m = %d: t(0,1) = %d, t(2,3) = %d", m,
              tref[0][1], tref[2][3]);
        if (tref[2][3] > worst23) worst23 = tref[2][3];
        for (si = 0; si < 3; ++si)
            for (bi = 0; bi < 3; ++bi) {
                uint32_t base = (starts[bi] << m) & ~((uint32_t)n - 1u);
                for (i = 0; i < (uint32_t)n; ++i) {
                    float u[4], w[2];
                    pt_sobol_scrambled4(base + i, seeds[si], u);
                    pt_sobol_scrambled(base + i, seeds[si], w);
                    if (!CHECK(t, u[0] == w[0] && u[1] == w[1], "point %u: scrambled4 (%g, %g) != scrambled (%g, %g)", base + i,
                               u[0], u[1], w[0], w[1]))
                        goto done;
                    for (k = 0; k < 4; ++k) c[k][i] = u[k];
                }
                for (d0 = 0; d0 < 4; ++d0)
                    for (d1 = d0 + 1; d1 < 4; ++d1) {
                        int tt = net_t(c[d0], c[d1], m);
                        if (!CHECK(t, tt == tref[d0][d1], "m = %d, seed %d, block at %u: dims (%d, %d) t = %d, unscrambled %d", m,
                                   si, base, d0, d1, tt, tref[d0][d1]))
                            goto done;
                    }
                ++blocks;
            }
    }
    test_note(t, "%d scrambled 4D blocks, m <= %d; t of dims (2, 3) up to %d", blocks, MMAX, worst23);
done:
    for (k = 0; k < 4; ++k) {
        free(c[k]);
        free(r[k]);
    }
}

static void sobol_nets(test_ctx *t)
{
    static const uint64_t seeds[] = {0u, 1u, 0x243f6a8885a308d3ULL, 0xffffffffffffffffULL, 12345u};
    static const uint32_t starts[] = {0u, 1u, 5u, 65535u}; /* block index j: points j 2^m ... */
    enum { MMAX = 12 };
    double *x = (double *)malloc(sizeof(double) << MMAX), *y = (double *)malloc(sizeof(double) << MMAX);
    int m, si, bi, nets = 0, bad_a = -1;
    uint32_t i;
    if (!CHECK(t, x && y, "out of memory")) goto done;
    for (m = 0; m <= MMAX; ++m) {
        int n = 1 << m;
        /* unscrambled */
        for (i = 0; i < (uint32_t)n; ++i) {
            x[i] = pt_sobol_u32(i, 0) / 4294967296.0;
            y[i] = pt_sobol_u32(i, 1) / 4294967296.0;
        }
        CHECK(t, is_net(x, y, m, &bad_a), "unscrambled: the first 2^%d points are not a (0,%d,2)-net (shape a=%d)", m, m,
              bad_a);
        for (si = 0; si < (int)(sizeof seeds / sizeof seeds[0]); ++si)
            for (bi = 0; bi < (int)(sizeof starts / sizeof starts[0]); ++bi) {
                uint32_t base = (starts[bi] << m) & ~((uint32_t)n - 1u);
                if (m == MMAX && bi == 3) base = 0xfff000u; /* across 2^16: aligned blocks higher up */
                for (i = 0; i < (uint32_t)n; ++i) {
                    float u[2] = {-1.0f, -1.0f};
                    pt_sobol_scrambled(base + i, seeds[si], u);
                    if (!CHECK(t, u[0] >= 0.0f && u[0] < 1.0f && u[1] >= 0.0f && u[1] < 1.0f,
                               "point %u seed %d: (%g, %g) outside [0,1)", base + i, si, u[0], u[1]))
                        goto done;
                    x[i] = u[0];
                    y[i] = u[1];
                }
                if (CHECK(t, is_net(x, y, m, &bad_a),
                          "seed %d: points %u..%u are not a (0,%d,2)-net (shape 2^-%d x 2^-%d has an empty cell)", si, base,
                          base + (uint32_t)n - 1u, m, bad_a, m - bad_a))
                    ++nets;
            }
    }
    test_note(t, "%d scrambled blocks checked, m <= %d", nets, MMAX);
done:
    free(x);
    free(y);
}

/* ---- randomisation ---- */

/* Chi-square p-value of point `index` of pt_sobol_scrambled (four = 0) or of dimensions 2 and 3 of
   pt_sobol_scrambled4 (four = 1) over 25,600 random seeds, on a 16 x 16 grid (255 dof). */
static double seeds_chi2_p(uint32_t index, uint64_t rng_seed, int four)
{
    enum { G = 16, N = 25600 };
    static int count[G * G];
    double chi2 = 0.0, e = (double)N / (G * G);
    pt_rng r;
    int c;
    memset(count, 0, sizeof count);
    pt_rng_seed(&r, rng_seed, 5u);
    for (c = 0; c < N; ++c) {
        float u[4];
        uint64_t seed = ((uint64_t)pt_rng_u32(&r) << 32) | pt_rng_u32(&r);
        if (four) {
            pt_sobol_scrambled4(index, seed, u);
            u[0] = u[2];
            u[1] = u[3];
        } else
            pt_sobol_scrambled(index, seed, u);
        count[(int)(u[0] * G) * G + (int)(u[1] * G)]++;
    }
    for (c = 0; c < G * G; ++c) chi2 += (count[c] - e) * (count[c] - e) / e;
    return tu_chi2_sf(chi2, G * G - 1);
}

static void sobol_randomised(test_ctx *t)
{
    static const uint32_t idx[] = {0u, 1u, 77u, 40000u};
    double alpha = tu_suite_alpha(), worst_p = 1.0;
    int k, differ = 0, seed_differ = 0;
    uint32_t i;
    /* not the identity, and a function of the seed */
    for (i = 0; i < 64; ++i) {
        float u[2], w[2];
        pt_sobol_scrambled(i, 7u, u);
        pt_sobol_scrambled(i, 8u, w);
        differ += fabs(u[0] - pt_sobol_u32(i, 0) / 4294967296.0) > 1e-6 || fabs(u[1] - pt_sobol_u32(i, 1) / 4294967296.0) > 1e-6;
        seed_differ += u[0] != w[0] || u[1] != w[1];
    }
    CHECK(t, differ >= 60, "only %d of 64 scrambled points differ from the unscrambled ones", differ);
    CHECK(t, seed_differ >= 60, "only %d of 64 points differ between seeds 7 and 8", seed_differ);
    /* the point of one index over random seeds is uniform on the square; pt_sobol_scrambled4's
       dimensions 2 and 3 likewise */
    for (k = 0; k < (int)(sizeof idx / sizeof idx[0]) + 2; ++k) {
        int four = k >= (int)(sizeof idx / sizeof idx[0]);
        uint32_t index = four ? idx[2 * (k - 4) + 1] : idx[k];
        double p = seeds_chi2_p(index, four ? 199u + (uint64_t)(k - 4) : 99u + (uint64_t)k, four);
        tu_suite_count(1);
        if (p < worst_p) worst_p = p;
        CHECK(t, p >= alpha, "%sindex %u over seeds: chi-square p = %.3g < %.3g", four ? "dims 2, 3, " : "", index, p, alpha);
    }
    test_note(t, "uniform over seeds: smallest p %.3g (level %.2g each)", worst_p, alpha);
}

/* ---- variance on a smooth integrand ---- */

/* f(x, y) = exp(x) cos(y) + x y: integral (e - 1) sin 1 + 1/4, second moment in closed form. */
static double smooth_f(double x, double y) { return exp(x) * cos(y) + x * y; }

static void sobol_variance(test_ctx *t)
{
    enum { N = 256, R = 64 };
    const double e = exp(1.0), s1 = sin(1.0), c1 = cos(1.0);
    /* E[f] and E[f^2]: int e^2x cos^2 y = (e^2 - 1)/2 * (1/2 + sin 2 / 4); int 2 x y e^x cos y =
       2 * [x e^x - e^x]_0^1 * [y sin y + cos y]_0^1 = 2 * 1 * (s1 + c1 - 1); int x^2 y^2 = 1/9 */
    double mean = (e - 1.0) * s1 + 0.25;
    double m2 = (e * e - 1.0) / 2.0 * (0.5 + sin(2.0) / 4.0) + 2.0 * (s1 + c1 - 1.0) + 1.0 / 9.0;
    double var_indep = (m2 - mean * mean) / N, ss = 0.0, sum = 0.0, var_q, upper, chi2_lo;
    int r;
    uint32_t i;
    for (r = 0; r < R; ++r) {
        double est = 0.0;
        for (i = 0; i < N; ++i) {
            float u[2];
            pt_sobol_scrambled(i, 0x9e3779b97f4a7c15ULL * (uint64_t)(r + 1), u);
            est += smooth_f(u[0], u[1]);
        }
        est /= N;
        sum += est;
        ss += (est - mean) * (est - mean); /* the mean is known: R degrees of freedom */
    }
    var_q = ss / R;
    /* chi-square(R) lower 1 % quantile by Wilson-Hilferty: R (1 - 2/(9R) - z sqrt(2/(9R)))^3 */
    chi2_lo = R * pow(1.0 - 2.0 / (9.0 * R) - tu_z_two_sided(0.02) * sqrt(2.0 / (9.0 * R)), 3.0);
    upper = ss / chi2_lo;
    CHECK(t, fabs(sum / R - mean) < 6.0 * sqrt(var_indep / R), "mean of the estimates %.6f, integral %.6f", sum / R, mean);
    CHECK(t, upper < 0.1 * var_indep,
          "scrambled Sobol variance %.3g (99 %% upper bound %.3g) is not below a tenth of independent sampling's %.3g",
          var_q, upper, var_indep);
    test_note(t, "%d points: variance %.3g vs independent %.3g (ratio %.2g, 99%% bound %.2g)", N, var_q, var_indep,
              var_q / var_indep, upper / var_indep);
    /* pt_sobol_scrambled4 stratifies the four dimensions jointly: h = (f(u0, u1) - mean) (f(u2, u3) - mean) has
       mean 0 and no main effects, so two separately shuffled 2D sets (padding) estimate it no better than
       independent points (variance var_f^2 / N); the 4D point must do ten times better (99 % upper bound) */
    {
        double var_f = m2 - mean * mean, var_h_indep = var_f * var_f / N, ss4 = 0.0, sum4 = 0.0, upper4;
        for (r = 0; r < R; ++r) {
            double est = 0.0;
            for (i = 0; i < N; ++i) {
                float u[4];
                pt_sobol_scrambled4(i, 0x2545f4914f6cdd1dULL * (uint64_t)(r + 1), u);
                est += (smooth_f(u[0], u[1]) - mean) * (smooth_f(u[2], u[3]) - mean);
            }
            est /= N;
            sum4 += est;
            ss4 += est * est;
        }
        upper4 = ss4 / chi2_lo;
        CHECK(t, fabs(sum4 / R) < 6.0 * sqrt(var_h_indep / R), "4D: mean of the estimates %.3g, integral 0", sum4 / R);
        CHECK(t, upper4 < 0.1 * var_h_indep,
              "4D: variance %.3g (99 %% upper bound %.3g) of the interaction is not below a tenth of independent points' %.3g",
              ss4 / R, upper4, var_h_indep);
        test_note(t, "4D interaction: ratio %.2g (99%% bound %.2g)", ss4 / R / var_h_indep, upper4 / var_h_indep);
    }
}

/* ---- renders ---- */

/* Pixel replicates: accumulates d_p = x_p - want_p (green channel), normalised by want's scale. */
typedef struct pix_diff {
    tu_acc acc;
} pix_diff;

static double pix_z(const pix_diff *d)
{
    double se = tu_acc_se(&d->acc);
    return se > 0.0 ? d->acc.mean / se : (d->acc.mean == 0.0 ? 0.0 : INFINITY);
}

#define UNBIASED_COMPARISONS 9

/* A guide PDF for the tests: the pt_pdf `user` points to, everywhere. */
static int fixed_guide(void *user, const pt_shading_point *sp, pt_pdf *out)
{
    (void)sp;
    *out = *(const pt_pdf *)user;
    return 1;
}

static void render_unbiased(test_ctx *t)
{
    const double zc = tu_z_two_sided(tu_sidak(0.01, UNBIASED_COMPARISONS));
    int kind, seed, x, y, n = 0;
    char summary[512] = "";
    size_t len = 0;
    /* 1-3: analytic planes, direct light */
    for (kind = TU_SPHERE; kind <= TU_TRIANGLE; ++kind) {
        tu_plane_scene ps;
        pix_diff d;
        memset(&d, 0, sizeof d);
        if (!CHECK(t, tu_plane_scene_create(&ps, kind, 24, 24), "plane scene %d", kind)) return;
        for (seed = 1; seed <= 3; ++seed) {
            pt_render_desc rd = tu_base_desc(24, 24, 16, (uint64_t)seed);
            pt_film f;
            memset(&f, 0, sizeof f);
            rd.camera = ps.camera;
            rd.max_depth = 1;
            rd.sampler = PT_SAMPLER_SOBOL;
            if (!tu_render_into(t, ps.scene, &rd, &f, NULL, "plane")) {
                pt_film_free(&f);
                break;
            }
            for (y = 0; y < 24; ++y)
                for (x = 0; x < 24; ++x) {
                    pt_color m, v;
                    double want = ps.ref[y * 24 + x];
                    pt_film_pixel(&f, x, y, &m, &v);
                    if (want > 0.0) tu_acc_add(&d.acc, (m.y - want) / want);
                }
            pt_film_free(&f);
        }
        CHECK(t, fabs(pix_z(&d)) <= zc, "plane, light kind %d: mean relative pixel error %.3g, z = %.2f (limit %.2f)", kind,
              d.acc.mean, pix_z(&d), zc);
        len += (size_t)snprintf(summary + len, sizeof summary - len, "plane%d z %.2f; ", kind, pix_z(&d));
        ++n;
        tu_plane_scene_destroy(&ps);
    }
    /* 4: the closed furnace (every pixel 1), long paths */
    {
        pt_scene *s = pt_scene_create();
        pt_render_desc rd = tu_base_desc(24, 24, 8, 5u);
        pt_film f;
        pix_diff d;
        memset(&f, 0, sizeof f);
        memset(&d, 0, sizeof d);
        if (!CHECK(t, s && tu_add_closed_furnace(s) == PT_OK, "furnace")) return;
        rd.camera.look_from = pt_v3(0, 0, 0);
        rd.camera.look_at = pt_v3(0, 0, 1);
        rd.camera.vfov_degrees = 90;
        rd.sampler = PT_SAMPLER_SOBOL;
        rd.rr_start_depth = 2;
        if (tu_render_into(t, s, &rd, &f, NULL, "furnace"))
            for (y = 0; y < 24; ++y)
                for (x = 0; x < 24; ++x) {
                    pt_color m, v;
                    pt_film_pixel(&f, x, y, &m, &v);
                    tu_acc_add(&d.acc, m.y - 1.0);
                }
        pt_film_free(&f);
        pt_scene_destroy(s);
        CHECK(t, fabs(pix_z(&d)) <= zc, "closed furnace: mean pixel %.5f (want 1), z = %.2f (limit %.2f)", 1.0 + d.acc.mean,
              pix_z(&d), zc);
        len += (size_t)snprintf(summary + len, sizeof summary - len, "furnace z %.2f; ", pix_z(&d));
        ++n;
    }
    /* 5-9: Sobol against independent renders of scenes/cornell.scene (glass: the Fresnel slot) */
    {
        static const char *const names[] = {"mis", "mixture", "material", "light", "mis+guide"};
        pt_scenefile sd;
        pt_scene *s = NULL;
        pt_render_desc base;
        char err[512];
        int k;
        if (!CHECK(t, pt_scenefile_load("scenes/cornell.scene", &sd, err, sizeof err) == PT_OK, "cornell.scene: %s", err))
            return;
        if (!CHECK(t, pt_scenefile_build(&sd, &s, &base, err, sizeof err) == PT_OK, "cornell.scene: %s", err)) {
            pt_scenefile_free(&sd);
            return;
        }
        pt_scenefile_free(&sd);
        for (k = 0; k < 5; ++k) {
            pt_render_desc a = base, b;
            pt_film fa, fb;
            pix_diff d;
            memset(&fa, 0, sizeof fa);
            memset(&fb, 0, sizeof fb);
            pt_pdf guide_pdf = pt_pdf_uniform_sphere();
            memset(&d, 0, sizeof d);
            a.width = a.height = 32;
            a.samples_per_pixel = 32;
            a.samples_per_pass = 32;
            a.strategy = k == 1 ? PT_STRATEGY_MIXTURE : k == 2 ? PT_STRATEGY_MATERIAL : k == 3 ? PT_STRATEGY_LIGHT
                                                                                              : PT_STRATEGY_MIS;
            a.max_depth = 6;
            if (k == 4) {
                a.guide = fixed_guide;
                a.guide_user = &guide_pdf;
                a.guide_weight = 0.3f;
            }
            a.seed = 11u + (uint64_t)k;
            b = a;
            b.seed = 1011u + (uint64_t)k;
            b.sampler = PT_SAMPLER_SOBOL;
            if (tu_render_into(t, s, &a, &fa, NULL, names[k]) && tu_render_into(t, s, &b, &fb, NULL, names[k]))
                for (y = 0; y < 32; ++y)
                    for (x = 0; x < 32; ++x) {
                        pt_color ma, mb, v;
                        pt_film_pixel(&fa, x, y, &ma, &v);
                        pt_film_pixel(&fb, x, y, &mb, &v);
                        tu_acc_add(&d.acc, (double)mb.y - (double)ma.y);
                    }
            pt_film_free(&fa);
            pt_film_free(&fb);
            CHECK(t, fabs(pix_z(&d)) <= zc, "cornell %s: Sobol - independent mean pixel difference %.4g, z = %.2f (limit %.2f)",
                  names[k], d.acc.mean, pix_z(&d), zc);
            len += (size_t)snprintf(summary + len, sizeof summary - len, "cornell %s z %.2f; ", names[k], pix_z(&d));
            ++n;
        }
        pt_scene_destroy(s);
    }
    CHECK(t, n == UNBIASED_COMPARISONS, "%d comparisons made, %d planned", n, UNBIASED_COMPARISONS);
    test_note(t, "%s|z| limit %.2f (family alpha 0.01 over %d)", summary, zc, UNBIASED_COMPARISONS);
}

static void render_variance(test_ctx *t)
{
    enum { W = 16, SEEDS = 12 };
    tu_plane_scene ps;
    double var[2] = {0.0, 0.0}, ratio;
    int smp, seed, p;
    double *sum = NULL, *sq = NULL;
    if (!CHECK(t, tu_plane_scene_create(&ps, TU_QUAD, W, W), "plane scene")) return;
    sum = (double *)calloc(W * W, sizeof(double));
    sq = (double *)calloc(W * W, sizeof(double));
    if (!CHECK(t, sum && sq, "out of memory")) goto done;
    for (smp = 0; smp < 2; ++smp) {
        memset(sum, 0, W * W * sizeof(double));
        memset(sq, 0, W * W * sizeof(double));
        for (seed = 0; seed < SEEDS; ++seed) {
            pt_render_desc rd = tu_base_desc(W, W, 64, 100u + (uint64_t)seed);
            pt_film f;
            memset(&f, 0, sizeof f);
            rd.camera = ps.camera;
            rd.max_depth = 1;
            rd.sampler = smp ? PT_SAMPLER_SOBOL : PT_SAMPLER_INDEPENDENT;
            if (tu_render_into(t, ps.scene, &rd, &f, NULL, "plane"))
                for (p = 0; p < W * W; ++p) {
                    pt_color m, v;
                    pt_film_pixel(&f, p % W, p / W, &m, &v);
                    sum[p] += m.y;
                    sq[p] += (double)m.y * m.y;
                }
            pt_film_free(&f);
        }
        for (p = 0; p < W * W; ++p) var[smp] += (sq[p] - sum[p] * sum[p] / SEEDS) / (SEEDS - 1);
    }
    ratio = var[1] / var[0];
    CHECK(t, ratio < 0.5, "Sobol's variance over seeds is %.3g of independent sampling's (must be < 0.5)", ratio);
    test_note(t, "quad light, direct, 64 spp: summed pixel variance over %d seeds, Sobol / independent = %.3g", SEEDS, ratio);
done:
    free(sum);
    free(sq);
    tu_plane_scene_destroy(&ps);
}

static void render_deterministic(test_ctx *t)
{
    tu_plane_scene ps;
    pt_render_desc d;
    pt_film one, again, prog, passes, other, indep, thr;
    int rc;
    memset(&one, 0, sizeof one);
    memset(&again, 0, sizeof again);
    memset(&prog, 0, sizeof prog);
    memset(&passes, 0, sizeof passes);
    memset(&other, 0, sizeof other);
    memset(&indep, 0, sizeof indep);
    memset(&thr, 0, sizeof thr);
    if (!CHECK(t, tu_plane_scene_create(&ps, TU_SPHERE, 16, 12), "plane scene")) return;
    d = tu_base_desc(16, 12, 16, 42u);
    d.camera = ps.camera;
    d.max_depth = 3;
    d.sampler = PT_SAMPLER_SOBOL;
    d.samples_per_pass = 16;
    d.threads = 2;
    tu_render_into(t, ps.scene, &d, &one, NULL, "one pass");
    tu_render_into(t, ps.scene, &d, &again, NULL, "again");
    CHECK(t, tu_film_equal(&one, &again), "the same seed gave another film");
    d.threads = 1;
    tu_render_into(t, ps.scene, &d, &thr, NULL, "one thread");
    CHECK(t, tu_film_equal(&one, &thr), "1 and 2 threads gave different films");
    d.threads = 2;
    /* progressive: 1 + 3 + 12 samples in three calls */
    if (CHECK(t, pt_film_init(&prog, 16, 12) == PT_OK, "film")) {
        static const int steps[3] = {1, 3, 12};
        int i;
        for (i = 0; i < 3; ++i) {
            d.samples_per_pixel = steps[i];
            d.samples_per_pass = steps[i];
            rc = pt_render(ps.scene, &d, &prog, NULL);
            CHECK(t, rc == PT_OK, "progressive step %d: %d", i, rc);
        }
        CHECK(t, tu_film_equal(&one, &prog), "1 + 3 + 12 spp in three renders differs from 16 spp in one");
    }
    d.samples_per_pixel = 16;
    d.samples_per_pass = 1;
    tu_render_into(t, ps.scene, &d, &passes, NULL, "16 passes");
    CHECK(t, tu_film_equal(&one, &passes), "16 passes of 1 spp differ from one pass of 16");
    d.samples_per_pass = 16;
    d.seed = 43u;
    tu_render_into(t, ps.scene, &d, &other, NULL, "seed 43");
    CHECK(t, !tu_film_equal(&one, &other), "seeds 42 and 43 gave the same film");
    d.seed = 42u;
    d.sampler = PT_SAMPLER_INDEPENDENT;
    tu_render_into(t, ps.scene, &d, &indep, NULL, "independent");
    CHECK(t, !tu_film_equal(&one, &indep), "the Sobol and the independent sampler gave the same film");
    /* adaptive sampling runs with Sobol and stays independent of the thread count */
    {
        pt_film a1, a2;
        pt_render_stats s1, s2;
        memset(&a1, 0, sizeof a1);
        memset(&a2, 0, sizeof a2);
        d.sampler = PT_SAMPLER_SOBOL;
        d.samples_per_pixel = 256;
        d.samples_per_pass = 0;
        d.adaptive_threshold = 0.05f;
        d.adaptive_min_spp = 16;
        d.threads = 1;
        tu_render_into(t, ps.scene, &d, &a1, &s1, "adaptive, 1 thread");
        d.threads = 2;
        tu_render_into(t, ps.scene, &d, &a2, &s2, "adaptive, 2 threads");
        CHECK(t, tu_film_equal(&a1, &a2), "adaptive Sobol: 1 and 2 threads gave different films");
        CHECK(t, s1.pixels_converged > 0 && s1.min_spp < 256, "adaptive Sobol stopped no pixel (%llu, min spp %u)",
              (unsigned long long)s1.pixels_converged, s1.min_spp);
        pt_film_free(&a1);
        pt_film_free(&a2);
        d.adaptive_threshold = 0.0f;
    }
    /* invalid values */
    {
        pt_film f;
        if (CHECK(t, pt_film_init(&f, 16, 12) == PT_OK, "film")) {
            d.sampler = (pt_sampler)2;
            CHECK(t, pt_render(ps.scene, &d, &f, NULL) == PT_ERROR_INVALID_ARGUMENT, "sampler 2 accepted");
            d.sampler = (pt_sampler)-1;
            CHECK(t, pt_render(ps.scene, &d, &f, NULL) == PT_ERROR_INVALID_ARGUMENT, "sampler -1 accepted");
            CHECK(t, f.count[0] == 0, "a rejected render added samples");
            pt_film_free(&f);
        }
    }
    /* the scene file statement */
    {
        static const char text[] = "size 8 8\nsampler sobol\nindirect_paths 2\ncamera look_from 0 0 -3 look_at 0 0 0\n"
                                   "material w lambertian 0.5 0.5 0.5\nsphere 0 0 0 1 w\n";
        static const char bad[] = "size 8 8\nsampler halton\n";
        pt_scenefile sd;
        pt_scene *s = NULL;
        pt_render_desc rd;
        char err[256];
        if (CHECK(t, pt_scenefile_parse(text, sizeof text - 1, "t.scene", NULL, &sd, err, sizeof err) == PT_OK, "%s", err)) {
            CHECK(t, sd.sampler == PT_SAMPLER_SOBOL, "sampler sobol read as %d", (int)sd.sampler);
            CHECK(t, sd.indirect_paths == 2, "indirect_paths 2 read as %d", sd.indirect_paths);
            if (CHECK(t, pt_scenefile_build(&sd, &s, &rd, err, sizeof err) == PT_OK, "%s", err)) {
                CHECK(t, rd.sampler == PT_SAMPLER_SOBOL && rd.indirect_paths == 2, "build: sampler %d, indirect_paths %d",
                      (int)rd.sampler, rd.indirect_paths);
                pt_scene_destroy(s);
            }
            pt_scenefile_free(&sd);
        }
        err[0] = '\0';
        CHECK(t, pt_scenefile_parse(bad, sizeof bad - 1, "t.scene", NULL, &sd, err, sizeof err) == PT_ERROR_INVALID_ARGUMENT,
              "sampler halton accepted");
        CHECK(t, strstr(err, "t.scene:2:") && strstr(err, "independent or sobol"), "message: '%s'", err);
    }
    pt_film_free(&one);
    pt_film_free(&again);
    pt_film_free(&thr);
    pt_film_free(&prog);
    pt_film_free(&passes);
    pt_film_free(&other);
    pt_film_free(&indep);
    tu_plane_scene_destroy(&ps);
}

const test_case test_sampler_cases[] = {
    TEST_CASE(sobol_sequence),
    TEST_CASE(sobol_definition),
    TEST_CASE(sobol_nets),
    TEST_CASE(sobol4_nets),
    TEST_CASE(sobol_randomised),
    TEST_CASE(sobol_variance),
    TEST_CASE(render_unbiased),
    TEST_CASE(render_variance),
    TEST_CASE(render_deterministic),
    TEST_END
};
