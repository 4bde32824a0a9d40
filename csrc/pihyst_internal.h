/* pihyst_internal.h - settings shared by the core's .c files (not public): the
 * precision a file is built for, and compiler settings. Include after pihyst.h. */
#ifndef PIHYST_INTERNAL_H
#define PIHYST_INTERNAL_H

#include <float.h>
#include <limits.h> /* with glibc this defines __GLIBC__, tested below */
#include <math.h>

/* Precision. pihyst_model.c and pihyst_inverse.c are written once, for `real`, with the
 * double API's names; pihyst_*_f32.c define PIHYST_BUILD_F32 and include them, which
 * turns real into float and every public name into its _f32 twin. Constants are written
 * RC(x) so that no operation is promoted to double in the float build (the Makefile
 * checks that with -Wdouble-promotion). */
#ifdef PIHYST_BUILD_F32
#include "pihyst_f32_names.h"
typedef float real;
#define RC(x) ((float)(x))
#define R_FABS fabsf
#define R_NEXTAFTER nextafterf
#define R_EPS FLT_EPSILON
#define R_MIN FLT_MIN
/* relative slack of the validation checks for the rounding of the envelope constants:
 * 32 ulps (the constants take a few roundings each) */
#define R_SLACK (RC(32.0) * FLT_EPSILON)
#else
typedef double real;
#define RC(x) (x)
#define R_FABS fabs
#define R_NEXTAFTER nextafter
#define R_EPS DBL_EPSILON
#define R_MIN DBL_MIN
#define R_SLACK 1e-12
#endif
#define R_INF ((real)INFINITY)

/* Hot loops are compiled for several instruction sets and the best one is picked at
 * load time (function multiversioning, GCC >= 11). That needs ifunc support from the
 * object format and the C library, i.e. ELF and glibc; elsewhere (musl, Windows, macOS,
 * bare metal) the loops are compiled once. */
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11 && defined(__x86_64__) && \
    defined(__ELF__) && defined(__GLIBC__) && !defined(PIHYST_NO_MULTIVERSION)
#define PIHYST_HOT __attribute__((target_clones("default", "arch=x86-64-v3", "arch=x86-64-v4")))
#else
#define PIHYST_HOT
#endif

/* `restrict` (C99) through a macro: MSVC's C dialect spells it __restrict. Every other
 * compiler-specific construct of the core (attributes, builtins, vector extensions,
 * pragmas) sits under #if defined(__GNUC__) or a narrower test, so the sources also
 * compile as plain C11 (make -C csrc portable checks it). */
#if defined(_MSC_VER) && !defined(__clang__)
#define PIHYST_RESTRICT __restrict
#else
#define PIHYST_RESTRICT restrict
#endif

/* Compiler vector extensions (the K <= 16 kernels, the ramp probe, the banks) only where
 * the target has a vector unit: SSE2 on x86, NEON / Advanced SIMD on ARM. Without one
 * (Cortex-M4F: single-precision scalar FPU only) GCC lowers them to scalar code through
 * the stack, several times slower than the portable loops (measured on the M4F, make
 * bench-m4f: a classical K = 4 model step 1015 instructions against 227). */
#if !defined(PIHYST_NO_VECTOR_EXT) && !defined(__SSE2__) && !defined(__ARM_NEON) && \
    !defined(__aarch64__)
#define PIHYST_NO_VECTOR_EXT
#endif

/* A saturated ramp's value, shared by the model and the compensator's ramp step so that
 * both give the same bits: flat at y0 up to x1, from y1 to y2 between x1 and x2, flat
 * beyond:  u < x1: y0;  u >= x2: y2;  else y1 + (y2 - y1)(u - x1)/(x2 - x1). */
#define PIHYST_RAMP_VALUE(x1, x2, y0, y1, y2, u)                                   \
    ((u) < (x1) ? (y0)                                                           \
                : ((u) >= (x2) ? (y2)                                            \
                               : (y1) + ((y2) - (y1)) * ((u) - (x1)) / ((x2) - (x1))))

#ifdef PIHYST_BUILD_F32
#define pihyst_internal_weighted_sum pihyst_internal_weighted_sum_f32
#define pihyst_internal_output_at pihyst_internal_output_at_f32
#endif
/* offset + sum_k w_k f_k exactly as the model step sums it (pihyst_model.c) */
real pihyst_internal_weighted_sum(size_t K, const real *w, const real *f, real offset);
/* the output the model would give for the next sample u, its state left as it is
 * (pihyst_model.c; summed in order, so it may differ from pihyst_model_step's in the last
 * bits) */
real pihyst_internal_output_at(const pihyst_model *m, real u);

#endif /* PIHYST_INTERNAL_H */
