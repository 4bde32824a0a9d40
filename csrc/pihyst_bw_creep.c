/* pihyst_bw_creep.c - the Bouc-Wen model with creep and its exact compensator
 * (pihyst_bw_creep.h, docs/theory/creep.md). Written once for `real`;
 * pihyst_bw_creep_f32.c builds the single-precision twin on the _f32 lags and the _f32
 * Bouc-Wen compensator. */
#include "pihyst_bw_creep.h"

#include "pihyst_internal.h"

#ifdef PIHYST_BUILD_F32
#define pihyst_creep pihyst_creep_f32
#define pihyst_creep_target pihyst_creep_target_f32
#define pihyst_creep_target_dt pihyst_creep_target_dt_f32
#define pihyst_creep_step pihyst_creep_step_f32
#define pihyst_creep_step_dt pihyst_creep_step_dt_f32
#define pihyst_bw_model pihyst_bw_model_f32
#define pihyst_bw_step pihyst_bw_step_f32
#define pihyst_bw_compensator pihyst_bw_compensator_f32
#define pihyst_bw_compensator_step pihyst_bw_compensator_step_f32
#define pihyst_bw_creep_compensator_step pihyst_bw_creep_compensator_step_f32
#define pihyst_bw_creep_compensator_run pihyst_bw_creep_compensator_run_f32
#define pihyst_bw_creep_run pihyst_bw_creep_run_f32
#endif

real pihyst_bw_creep_compensator_step(pihyst_creep *cr, pihyst_bw_compensator *c, real dt,
                                      real y_desired, real *y, pihyst_flags *flags)
{
    const int fixed = dt < RC(0.0);
    /* (C5); a NaN desired value gives a NaN target: the compensator holds and flags it */
    const real target = fixed ? pihyst_creep_target(cr, y_desired)
                              : pihyst_creep_target_dt(cr, dt, y_desired);
    const real u = pihyst_bw_compensator_step(c, target, flags);
    /* (C2)-(C3) by the output reached, c->y_last = (B1) at the voltage applied */
    const real out = fixed ? pihyst_creep_step(cr, c->y_last)
                           : pihyst_creep_step_dt(cr, dt, c->y_last);
    if (y) *y = out;
    return u;
}

size_t pihyst_bw_creep_compensator_run(pihyst_creep *cr, pihyst_bw_compensator *c,
                                       const real *y_desired, const real *dt, real *u,
                                       real *y, pihyst_flags *flags, size_t n)
{
    size_t t, count = 0;
    for (t = 0; t < n; ++t) {
        pihyst_flags fl = 0;
        real out;
        u[t] = pihyst_bw_creep_compensator_step(cr, c, dt ? dt[t] : RC(-1.0), y_desired[t],
                                                &out, &fl);
        if (y) y[t] = out;
        if (flags) flags[t] = fl;
        count += fl != 0;
    }
    return count;
}

void pihyst_bw_creep_run(pihyst_creep *cr, pihyst_bw_model *m, const real *u, const real *dt,
                         real *y, size_t n)
{
    size_t t;
    for (t = 0; t < n; ++t) {
        const real h = pihyst_bw_step(m, u[t]);
        y[t] = dt ? pihyst_creep_step_dt(cr, dt[t], h) : pihyst_creep_step(cr, h);
    }
}
