/* pihyst_creep.h - creep of a PI model: first-order lags driven by its hysteresis output.
 * C99, no malloc, no globals, no I/O, reentrant; arrays are owned by the caller.
 * Model (docs/theory/creep.md). H[t] is the hysteresis output of a PI model
 * (pihyst.h, equation (2)); n lags with time constants tau_i > 0 and gains g_i >= 0,
 * sum_i g_i < 1, and a sample interval dt[t] >= 0:
 *     alpha_i[t] = 1 - exp(-dt[t] / tau_i)                                  (C1)
 *     z_i[t]     = z_i[t-1] + alpha_i[t] (H[t] - z_i[t-1])                   (C2)
 *     y[t]       = H[t] - sum_i g_i (H[t] - z_i[t])                          (C3)
 * Substituting (C2) into (C3), at each sample the output is affine in H[t]:
 *     y[t] = (1 - beta[t]) H[t] + sum_i g_i (1 - alpha_i[t]) z_i[t-1],
 *     beta[t] = sum_i g_i (1 - alpha_i[t])  in [0, sum_i g_i],                (C4)
 * with slope 1 - beta >= 1 - sum g > 0: y[t] is non-decreasing in the voltage whenever
 * H[t] is, and the desired value y_d is met exactly by the hysteresis target
 *     H*[t] = (y_d - sum_i g_i (1 - alpha_i[t]) z_i[t-1]) / (1 - beta[t]),       (C5)
 * which the exact compensator of pihyst.h then solves for the voltage. At rest the lags
 * settle at z_i = H and y = H: the hysteresis model gives the settled displacement, the
 * lags the approach to it.
 * The state is z_i[t-1] (n doubles). A fixed interval dt (the firmware path) has its
 * alpha_i computed once at init; the _dt functions take the interval per sample. */
#ifndef PIHYST_CREEP_H
#define PIHYST_CREEP_H
#include <stddef.h>

#include "pihyst.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    PIHYST_CREEP_OK = 0,
    PIHYST_CREEP_ENULL = -1,      /* a required pointer is NULL */
    PIHYST_CREEP_ESIZE = -2,      /* n == 0 */
    PIHYST_CREEP_ENONFINITE = -3, /* NaN or infinity in a parameter or the state */
    PIHYST_CREEP_ETAU = -4,       /* a time constant is not > 0 */
    PIHYST_CREEP_EGAIN = -5,      /* a gain is negative, or the gains sum to 1 or more */
    PIHYST_CREEP_EDT = -6         /* the sample interval is negative or not finite */
} pihyst_creep_status;

/** Creep lags. Transparent for static allocation; fill it with pihyst_creep_init. */
typedef struct {
    size_t n;           /**< number of lags */
    const double *tau;  /**< n time constants, > 0 (caller-owned) */
    const double *gain; /**< n gains, >= 0, sum < 1 (caller-owned) */
    double dt;          /**< the fixed sample interval, >= 0 */
    double *alpha;      /**< n doubles (caller-owned), written by init: (C1) for dt */
    double beta;        /**< (C4) for dt */
    double *state;      /**< n doubles z_i[t-1] (caller-owned), mutated by step/run */
} pihyst_creep;

/** Validate and wire up. state is set to initial_state (n values), or to zeros if NULL
 *  (use pihyst_creep_settle to start at rest at a given hysteresis output). */
pihyst_creep_status pihyst_creep_init(pihyst_creep *c, size_t n, const double *tau,
                                      const double *gain, double dt, double *alpha,
                                      double *state, const double *initial_state);

/** At rest: every z_i = h (the lags settled at the hysteresis output h). */
void pihyst_creep_settle(pihyst_creep *c, double h);

/** (C5) for the fixed interval: the hysteresis output that gives y_desired next. */
double pihyst_creep_target(const pihyst_creep *c, double y_desired);

/** (C2)-(C3) for the fixed interval: advance the lags by the hysteresis output h,
 *  return y. */
double pihyst_creep_step(pihyst_creep *c, double h);

/** (C5) and (C2)-(C3) for an interval dt >= 0 given with the sample. */
double pihyst_creep_target_dt(const pihyst_creep *c, double dt, double y_desired);
double pihyst_creep_step_dt(pihyst_creep *c, double dt, double h);

/** A block: y[t] for hysteresis outputs h[t], intervals dt[t] (NULL: the fixed one).
 *  h and y may be the same array. */
void pihyst_creep_run(pihyst_creep *c, const double *h, const double *dt, double *y,
                      size_t n);

/** A compensator for the model with creep, one sample: the hysteresis target (C5) goes
 *  to pihyst_compensator_step (limits, slew, flags as there), the lags advance by the
 *  hysteresis output actually reached. *y (may be NULL) receives the model output.
 *  dt < 0 selects the fixed interval. Returns the voltage. */
double pihyst_creep_compensator_step(pihyst_creep *cr, pihyst_compensator *c, double dt,
                                     double y_desired, double *y, pihyst_flags *flags);

/** A block of n samples of pihyst_creep_compensator_step; dt NULL: the fixed interval.
 *  y and flags may be NULL. Returns the number of samples with a flag set. */
size_t pihyst_creep_compensator_run(pihyst_creep *cr, pihyst_compensator *c,
                                    const double *y_desired, const double *dt, double *u,
                                    double *y, pihyst_flags *flags, size_t n);

/** Human-readable text of a status code (static storage). */
const char *pihyst_creep_status_text(pihyst_creep_status status);

/* ---- single precision (_f32): the same lags for a single-precision FPU ----------------
 * A float lag cannot be stepped as (C2) is written: with alpha_i as small as 5e-6 (a
 * 1000 s lag at 200 Hz), z_i + alpha_i (H - z_i) rounds back to z_i whenever
 * alpha_i |H - z_i| is below half an ulp of z_i, i.e. the lag stops anywhere within
 * ulp(z_i) / (2 alpha_i) of H (0.8 um at -120 um). The _f32 lags therefore keep the
 * deviations e_i = z_i - h from the last hysteresis output h, which shrink to zero as
 * the lags settle, and step them with the change of H (the same model as (C2)-(C5)):
 *     x_i = e_i[t-1] - (H[t] - H[t-1]),   e_i[t] = x_i - alpha_i x_i           (C2')
 *     y[t] = H[t] + sum_i g_i e_i[t]                                             (C3')
 *     H*[t] = H[t-1] + (y_d - H[t-1] - sum_i g_i (1 - alpha_i) e_i[t-1]) / (1 - beta) (C5')
 * Rounding is relative to the deviations, not to H. The state is e_i (n floats) and h,
 * h = 0 at init, so initial_state gives z_i as in the double API. */
typedef struct {
    size_t n;          /**< number of lags */
    const float *tau;  /**< n time constants, > 0 (caller-owned) */
    const float *gain; /**< n gains, >= 0, sum < 1 (caller-owned) */
    float dt;          /**< the fixed sample interval, >= 0 */
    float *alpha;      /**< n floats (caller-owned), written by init: (C1) for dt */
    float beta;        /**< (C4) for dt */
    float *state;      /**< n floats e_i = z_i[t-1] - h (caller-owned) */
    float h;           /**< the last hysteresis output H[t-1] */
} pihyst_creep_f32;

/** Validate and wire up (as pihyst_creep_init). state (the deviations) is set so that
 *  z_i = initial_state[i] (n values, h = 0), or to zeros if NULL. */
pihyst_creep_status pihyst_creep_init_f32(pihyst_creep_f32 *c, size_t n, const float *tau,
                                          const float *gain, float dt, float *alpha,
                                          float *state, const float *initial_state);
/** At rest at the hysteresis output h: every z_i = h. */
void pihyst_creep_settle_f32(pihyst_creep_f32 *c, float h);
/** (C5') for the fixed interval. */
float pihyst_creep_target_f32(const pihyst_creep_f32 *c, float y_desired);
/** (C2')-(C3') for the fixed interval: advance the lags by h, return y. */
float pihyst_creep_step_f32(pihyst_creep_f32 *c, float h);
/** (C5') and (C2')-(C3') for an interval dt >= 0 given with the sample. */
float pihyst_creep_target_dt_f32(const pihyst_creep_f32 *c, float dt, float y_desired);
float pihyst_creep_step_dt_f32(pihyst_creep_f32 *c, float dt, float h);
/** A block (dt NULL: the fixed interval); h and y may be the same array. */
void pihyst_creep_run_f32(pihyst_creep_f32 *c, const float *h, const float *dt, float *y,
                          size_t n);
/** pihyst_creep_compensator_step on the _f32 compensator (dt < 0: the fixed interval). */
float pihyst_creep_compensator_step_f32(pihyst_creep_f32 *cr, pihyst_compensator_f32 *c,
                                        float dt, float y_desired, float *y,
                                        pihyst_flags *flags);
/** A block of n samples of pihyst_creep_compensator_step_f32. */
size_t pihyst_creep_compensator_run_f32(pihyst_creep_f32 *cr, pihyst_compensator_f32 *c,
                                        const float *y_desired, const float *dt, float *u,
                                        float *y, pihyst_flags *flags, size_t n);

#ifdef __cplusplus
}
#endif
#endif /* PIHYST_CREEP_H */
