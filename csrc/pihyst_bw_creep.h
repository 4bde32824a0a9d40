/* pihyst_bw_creep.h - the exact compensator of a Bouc-Wen model with creep: the creep
 * lags of pihyst_creep.h driven by the output of the Bouc-Wen model of pihyst_boucwen.h.
 * C99, no malloc, no globals, no I/O, reentrant; double precision, and single precision
 * (_f32: the _f32 lags of pihyst_creep.h, in their deviation form (C2')-(C5'), and the
 * _f32 Bouc-Wen compensator; pihyst_bw_creep_f32.c).
 *
 * Model (docs/theory/creep.md). The Bouc-Wen output (B1) is the settled displacement
 * H[t]; the lags give y[t] = H[t] - sum_i g_i (H[t] - z_i[t]) ((C1)-(C3) of
 * pihyst_creep.h). At each sample y is affine in H with slope 1 - beta > 0 (C4), so a
 * desired value y_d is met exactly by the hysteresis target H* of (C5), which the exact
 * Bouc-Wen compensator solves for the voltage (limits, slew and flags as there: no
 * voltage leaves the limits, whatever y_d is); the lags then advance by the output H the
 * Bouc-Wen model actually reached (H*, or the end of reach), so the lag state always
 * matches the voltage applied. */
#ifndef PIHYST_BW_CREEP_H
#define PIHYST_BW_CREEP_H
#include <stddef.h>

#include "pihyst_boucwen.h"
#include "pihyst_creep.h"

#ifdef __cplusplus
extern "C" {
#endif

/** One sample: the target (C5) for y_desired (any value; NaN holds the voltage, +-inf
 *  saturates) goes to pihyst_bw_compensator_step, then the lags advance by the reached
 *  output c->y_last. dt < 0 selects the lags' fixed interval. *y (may be NULL) receives
 *  the model output with creep, *flags (may be NULL) the PIHYST_COMP_* bits. Returns the
 *  voltage. */
double pihyst_bw_creep_compensator_step(pihyst_creep *cr, pihyst_bw_compensator *c,
                                        double dt, double y_desired, double *y,
                                        pihyst_flags *flags);

/** A block of n samples of pihyst_bw_creep_compensator_step; dt NULL: the fixed
 *  interval. y and flags may be NULL; arrays may not overlap. Returns the number of
 *  samples with a flag set. */
size_t pihyst_bw_creep_compensator_run(pihyst_creep *cr, pihyst_bw_compensator *c,
                                       const double *y_desired, const double *dt,
                                       double *u, double *y, pihyst_flags *flags,
                                       size_t n);

/** The model forward: y[t] for the inputs u[t] (Bouc-Wen step, then the lags with
 *  intervals dt[t], NULL: the fixed one). u and y may not overlap. */
void pihyst_bw_creep_run(pihyst_creep *cr, pihyst_bw_model *m, const double *u,
                         const double *dt, double *y, size_t n);

/* ---- single precision (_f32): the same functions on floats ---------------------------- */
float pihyst_bw_creep_compensator_step_f32(pihyst_creep_f32 *cr, pihyst_bw_compensator_f32 *c,
                                           float dt, float y_desired, float *y,
                                           pihyst_flags *flags);
size_t pihyst_bw_creep_compensator_run_f32(pihyst_creep_f32 *cr, pihyst_bw_compensator_f32 *c,
                                           const float *y_desired, const float *dt,
                                           float *u, float *y, pihyst_flags *flags,
                                           size_t n);
void pihyst_bw_creep_run_f32(pihyst_creep_f32 *cr, pihyst_bw_model_f32 *m, const float *u,
                             const float *dt, float *y, size_t n);

#ifdef __cplusplus
}
#endif
#endif /* PIHYST_BW_CREEP_H */
