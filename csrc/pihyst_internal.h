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

#endif /* PIHYST_INTERNAL_H */
