/* pihyst_creep_f32.c - the single-precision lags of pihyst_creep.h (the _f32 API, in the
 * deviation form (C2')-(C5') of that header): the source of pihyst_creep.c built with
 * real = float, float operations only (make -C csrc m4f checks that no software double
 * routine is called). The double lags are their reference in the tests
 * (csrc/tests/test_creep_f32.c). */
#define PIHYST_BUILD_F32
#include "pihyst_creep.c"
