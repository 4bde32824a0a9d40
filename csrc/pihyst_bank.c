/* pihyst_bank.c - banks of independent models and compensators (see the "Banks" section
 * of pihyst_api.h): one call per sample vector, channel i on its own object. Each
 * channel is advanced by the same function a single model or compensator uses, so a
 * bank gives bit for bit the outputs of N separate calls. The next channel's operator
 * state is prefetched while the current one is stepped (the states of N channels are
 * N separate arrays, typically beyond the first-level cache for N in the thousands). */
#include "pihyst.h"
#include "pihyst_internal.h"

#if defined(__GNUC__)
#define PIHYST_PREFETCH(p) __builtin_prefetch((p), 1, 3)
#else
#define PIHYST_PREFETCH(p) ((void)(p))
#endif

void pihyst_bank_step(pihyst_model *const *models, size_t n, const real *u, real *y)
{
    size_t i;
    for (i = 0; i < n; ++i) {
        if (i + 1 < n) PIHYST_PREFETCH(models[i + 1]->state);
        y[i] = pihyst_model_step(models[i], u[i]);
    }
}

size_t pihyst_bank_compensate(pihyst_compensator *const *comps, size_t n,
                              const real *y_desired, real *u, real *y, pihyst_flags *flags)
{
    size_t i, count = 0;
    for (i = 0; i < n; ++i) {
        pihyst_compensator *c = comps[i];
        pihyst_flags fl;
        if (i + 1 < n) PIHYST_PREFETCH(comps[i + 1]->work_model.state);
        u[i] = pihyst_compensator_step(c, y_desired[i], &fl);
        if (y) y[i] = c->y_last;
        if (flags) flags[i] = fl;
        count += fl != 0;
    }
    return count;
}
