/* Tiny test runner: every test_*.c registers its cases in main below. Built twice
 * (double, and single precision with PIHYST_TEST_F32, which adds the comparison of the
 * two precisions). Prints one line per failure and "N passed, N failed" at the end. */
#include "test_util.h"

#include <stdio.h>

int test_passed = 0;
int test_failed = 0;

void test_check(int ok, const char *what, const char *file, int line)
{
    if (ok) {
        ++test_passed;
    } else {
        ++test_failed;
        printf("FAIL %s:%d: %s\n", file, line, what);
    }
}

void test_check_near(double x, double y, double tol, const char *what, const char *file,
                     int line)
{
    test_check(fabs(x - y) <= tol, what, file, line);
    if (!(fabs(x - y) <= tol)) printf("     |%.17g - %.17g| = %.3g > %.3g\n", x, y, fabs(x - y), tol);
}

pihyst_status model_init(pihyst_model *m, pihyst_family family, size_t n_ops,
                         const real *thresholds, const real *weights, real offset, real u_min,
                         real u_max, const pihyst_shape *shape, const pihyst_pwl *pwl,
                         real *coef, real *state, const real *initial_state)
{
    pihyst_params p = {.family = family, .n_ops = n_ops, .thresholds = thresholds,
                       .weights = weights, .offset = offset, .u_min = u_min, .u_max = u_max,
                       .initial_state = initial_state};
    if (shape) p.shape = *shape;
    if (pwl) p.pwl = *pwl;
    return pihyst_model_init(m, &p, coef, state);
}

int main(void)
{
    run_model_tests();
    run_inverse_tests();
    run_bank_tests();
    run_bank_soa_tests();
    run_kernel_tests();
    run_boucwen_tests();
#ifndef PIHYST_TEST_F32
    run_creep_tests(); /* the _f32 lags have their own tests (test_creep_f32.c) */
#endif
    run_bw_creep_tests();
#ifdef PIHYST_TEST_F32
    run_twin_tests();
    run_creep_f32_tests();
#if PIHYST_STATE_ALIGN == 0
    printf("single precision, PIHYST_STATE_ALIGN=0: %d passed, %d failed\n", test_passed,
           test_failed);
#else
    printf("single precision: %d passed, %d failed\n", test_passed, test_failed);
#endif
#elif PIHYST_STATE_ALIGN == 0
    printf("double precision, PIHYST_STATE_ALIGN=0: %d passed, %d failed\n", test_passed,
           test_failed);
#else
    printf("double precision: %d passed, %d failed\n", test_passed, test_failed);
#endif
    return test_failed == 0 ? 0 : 1;
}
