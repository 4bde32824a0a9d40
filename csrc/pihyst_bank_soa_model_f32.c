/* pihyst_bank_soa_model_f32.c - the single-precision twin of pihyst_bank_soa_model.c
 * (the _f32 API of pihyst.h): the same source, built with real = float. */
#define PIHYST_BUILD_F32
#include "pihyst_bank_soa_model.c"
