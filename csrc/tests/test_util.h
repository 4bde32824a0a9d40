#ifndef PIHYST_TEST_UTIL_H
#define PIHYST_TEST_UTIL_H
/* The tests are written once, for the double API with `real` numbers, and built twice:
 * as they are, and with PIHYST_TEST_F32, which maps every public name to its _f32 twin
 * and real to float. TOL(d, f) is a tolerance: d in double, f in single precision.
 * Files that use both APIs side by side (test_twin.c) define PIHYST_TEST_BOTH first. */
#include "pihyst.h"

#include <float.h>
#include <math.h>

#ifndef PIHYST_TEST_BOTH
#ifdef PIHYST_TEST_F32
#include "pihyst_f32_names.h"
typedef float real;
#define TOL(d, f) (f)
#else
typedef double real;
#define TOL(d, f) (d)
#endif
/* n units in the last place of single precision at magnitude v */
#define F32_ULPS(n, v) ((n) * (double)FLT_EPSILON * (v))

/* pihyst_model_init with the parameters in a row (shape and pwl may be NULL) */
pihyst_status model_init(pihyst_model *m, pihyst_family family, size_t n_ops,
                         const real *thresholds, const real *weights, real offset, real u_min,
                         real u_max, const pihyst_shape *shape, const pihyst_pwl *pwl,
                         real *coef, real *state, const real *initial_state);
#endif

extern int test_passed;
extern int test_failed;
void test_check(int ok, const char *what, const char *file, int line);
void test_check_near(double x, double y, double tol, const char *what, const char *file,
                     int line);

#define CHECK(cond) test_check((cond) != 0, #cond, __FILE__, __LINE__)
#define CHECK_NEAR(x, y, tol) test_check_near((x), (y), (tol), #x " ~ " #y, __FILE__, __LINE__)

void run_model_tests(void);
void run_boucwen_tests(void);
void run_inverse_tests(void);
void run_bank_tests(void);
void run_bank_soa_tests(void);
void run_kernel_tests(void);
void run_twin_tests(void);
void run_creep_tests(void);
void run_creep_f32_tests(void);
void run_bw_creep_tests(void);
#endif
