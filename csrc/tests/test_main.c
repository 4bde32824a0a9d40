/* Tiny test runner: every test_*.c registers its cases in TEST_CASES below.
 * Prints one line per failure and "N passed, N failed" at the end. */
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

int main(void)
{
    run_model_tests();
    run_inverse_tests();
    run_creep_tests();
    printf("%d passed, %d failed\n", test_passed, test_failed);
    return test_failed == 0 ? 0 : 1;
}
