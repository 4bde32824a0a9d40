/* portable.c - compiles one source file of the core (PORTABLE_SOURCE) as plain C11 with
 * no compiler extension (make -C csrc portable): the system headers first, then GCC's
 * and clang's identifying macros removed and their extensions poisoned, so that the core
 * compiles as it would on MSVC's C11 dialect, which has none of them: every attribute,
 * builtin, pragma, vector type and bare `restrict` must sit under #if defined(__GNUC__)
 * (or a narrower test) or go through a macro (PIHYST_RESTRICT). */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#undef __GNUC__
#undef __GNUC_MINOR__
#undef __clang__
#undef __x86_64__
#undef __SSE2__
#undef __ELF__
#undef __GLIBC__
#define _MSC_VER 1930 /* as MSVC 2022: PIHYST_RESTRICT is __restrict */
#pragma GCC poison __attribute__ __builtin_prefetch __builtin_assume_aligned
#pragma GCC poison __builtin_cpu_supports __builtin_expect restrict __restrict__
#pragma GCC poison __typeof__ typeof __asm__ asm

#include PORTABLE_SOURCE
