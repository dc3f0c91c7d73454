/* test_suite.c - the last section: summaries over the whole run.

   chi2_table prints one row per chi-square case the run made (every call of the PDF checker, in
   the order they ran: case, N draws, dof, chi-square, p, the density's integral over the grid, z of
   E[1/p] against the support's measure), and checks the bookkeeping of the chi-square suite's family
   of comparisons: alpha = 0.01 for the whole suite, Sidak-corrected over TU_SUITE_COMPARISONS, is
   only honest if the run made no more comparisons than that (test_util.h). */
#include "test_util.h"

#include <stdio.h>

static void chi2_table(test_ctx *t)
{
    int i, rows = tu_chi2_row_count(), cases = 0, rejected = 0, issue3 = 0, failed = 0;
    double min_p = 2.0;
    long made = tu_suite_comparisons();
    tu_chi2_print_table();
    for (i = 0; i < rows; i++) {
        const tu_chi2_row *r = tu_chi2_row_at(i);
        if (r->expect_reject) {
            rejected += !r->passed;
            continue;
        }
        cases++;
        issue3 += r->n >= 1000000;
        failed += !r->passed;
        if (r->p < min_p) min_p = r->p;
    }
    CHECK(t, made <= TU_SUITE_COMPARISONS,
          "the run made %ld statistical comparisons in the chi-square suite, more than the %d its Sidak correction assumes",
          made, TU_SUITE_COMPARISONS);
    CHECK(t, failed == 0, "%d chi-square cases failed (see their tests)", failed);
    test_note(t, "%d chi-square cases (%d with 10^6 draws), min p = %.3g; %d deliberately wrong PDFs, %d rejected; %ld comparisons "
                 "at alpha %.3g each (0.01 Sidak over %d)",
              cases, issue3, min_p, rows - cases, rejected, made, tu_suite_alpha(), TU_SUITE_COMPARISONS);
}

const test_case test_suite_cases[] = {
    TEST_CASE(chi2_table),
    TEST_END
};
