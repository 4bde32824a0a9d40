#ifndef PIHYST_TEST_UTIL_H
#define PIHYST_TEST_UTIL_H
#include <math.h>

extern int test_passed;
extern int test_failed;
void test_check(int ok, const char *what, const char *file, int line);

#define CHECK(cond) test_check((cond) != 0, #cond, __FILE__, __LINE__)
#define CHECK_NEAR(x, y, tol) test_check(fabs((x) - (y)) <= (tol), #x " ~ " #y, __FILE__, __LINE__)

void run_model_tests(void);
void run_inverse_tests(void);
void run_creep_tests(void);
#endif
