/* pihyst_bw_creep_f32.c - the single-precision twin of pihyst_bw_creep.c (the _f32 API of
 * pihyst_bw_creep.h): the same source, built with real = float. */
#define PIHYST_BUILD_F32
#include "pihyst_bw_creep.c"
