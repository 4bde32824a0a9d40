/* pihyst_internal.h - compiler settings shared by the core's .c files (not public). */
#ifndef PIHYST_INTERNAL_H
#define PIHYST_INTERNAL_H

/* Hot loops are compiled for several instruction sets and the best one is picked at
 * load time (function multiversioning), so a distributed build stays portable without
 * -march=native. */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(__clang__) && \
    !defined(PIHYST_NO_MULTIVERSION)
#define PIHYST_HOT __attribute__((target_clones("default", "arch=x86-64-v3", "arch=x86-64-v4")))
#else
#define PIHYST_HOT
#endif

/* The loops store the operator state and load it back a sample later; when the state is
 * not on a cache line its vector stores straddle two lines, store-to-load forwarding
 * fails and the loop runs twice as slowly (measured). Working states are aligned to: */
#define PIHYST_ALIGN 64

#endif /* PIHYST_INTERNAL_H */
