/* pihyst_boucwen_f32.c - the single-precision twin of pihyst_boucwen.c (the _f32 API of
 * pihyst_boucwen.h): the same source, built with real = float. */
#define PIHYST_BUILD_F32
#include "pihyst_boucwen.c"
