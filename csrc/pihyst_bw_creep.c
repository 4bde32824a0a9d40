/* pihyst_bw_creep.c - the Bouc-Wen model with creep and its exact compensator
 * (pihyst_bw_creep.h, docs/theory/creep.md). */
#include "pihyst_bw_creep.h"

double pihyst_bw_creep_compensator_step(pihyst_creep *cr, pihyst_bw_compensator *c,
                                        double dt, double y_desired, double *y,
                                        pihyst_flags *flags)
{
    const int fixed = dt < 0.0;
    /* (C5); a NaN desired value gives a NaN target: the compensator holds and flags it */
    const double target = fixed ? pihyst_creep_target(cr, y_desired)
                                : pihyst_creep_target_dt(cr, dt, y_desired);
    const double u = pihyst_bw_compensator_step(c, target, flags);
    /* (C2)-(C3) by the output reached, c->y_last = (B1) at the voltage applied */
    const double out = fixed ? pihyst_creep_step(cr, c->y_last)
                             : pihyst_creep_step_dt(cr, dt, c->y_last);
    if (y) *y = out;
    return u;
}

size_t pihyst_bw_creep_compensator_run(pihyst_creep *cr, pihyst_bw_compensator *c,
                                       const double *y_desired, const double *dt,
                                       double *u, double *y, pihyst_flags *flags,
                                       size_t n)
{
    size_t t, count = 0;
    for (t = 0; t < n; ++t) {
        pihyst_flags fl = 0;
        double out;
        u[t] = pihyst_bw_creep_compensator_step(cr, c, dt ? dt[t] : -1.0, y_desired[t],
                                                &out, &fl);
        if (y) y[t] = out;
        if (flags) flags[t] = fl;
        count += fl != 0;
    }
    return count;
}

void pihyst_bw_creep_run(pihyst_creep *cr, pihyst_bw_model *m, const double *u,
                         const double *dt, double *y, size_t n)
{
    size_t t;
    for (t = 0; t < n; ++t) {
        const double h = pihyst_bw_step(m, u[t]);
        y[t] = dt ? pihyst_creep_step_dt(cr, dt[t], h) : pihyst_creep_step(cr, h);
    }
}
