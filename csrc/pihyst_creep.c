/* pihyst_creep.c - creep lags of a PI model and their compensator (pihyst_creep.h,
 * docs/theory/creep.md). Written once for `real`; pihyst_creep_f32.c builds the
 * single-precision lags (PIHYST_BUILD_F32), which keep the deviations from the last
 * hysteresis output instead of the lag states ((C2')-(C5') of pihyst_creep.h: a float
 * lag stepped as (C2) stops short of H): the functions that step or solve the lags have
 * one body per form below, the rest is shared. */
#include "pihyst_creep.h"

#include "pihyst_internal.h"

#ifdef PIHYST_BUILD_F32
#define pihyst_creep pihyst_creep_f32
#define pihyst_creep_init pihyst_creep_init_f32
#define pihyst_creep_settle pihyst_creep_settle_f32
#define pihyst_creep_target pihyst_creep_target_f32
#define pihyst_creep_step pihyst_creep_step_f32
#define pihyst_creep_target_dt pihyst_creep_target_dt_f32
#define pihyst_creep_step_dt pihyst_creep_step_dt_f32
#define pihyst_creep_run pihyst_creep_run_f32
#define pihyst_creep_compensator_step pihyst_creep_compensator_step_f32
#define pihyst_creep_compensator_run pihyst_creep_compensator_run_f32
#define R_EXP expf
#define R_EXPM1 expm1f
#else
#define R_EXP exp
#define R_EXPM1 expm1
#endif

pihyst_creep_status pihyst_creep_init(pihyst_creep *c, size_t n, const real *tau,
                                      const real *gain, real dt, real *alpha, real *state,
                                      const real *initial_state)
{
    size_t i;
    real sum = RC(0.0);
    if (!c || !tau || !gain || !alpha || !state) return PIHYST_CREEP_ENULL;
    if (n == 0) return PIHYST_CREEP_ESIZE;
    for (i = 0; i < n; ++i) {
        if (!isfinite(tau[i]) || !isfinite(gain[i])) return PIHYST_CREEP_ENONFINITE;
        if (!(tau[i] > RC(0.0))) return PIHYST_CREEP_ETAU;
        if (gain[i] < RC(0.0)) return PIHYST_CREEP_EGAIN;
        sum += gain[i];
    }
    if (!(sum < RC(1.0))) return PIHYST_CREEP_EGAIN;
    if (!isfinite(dt) || dt < RC(0.0)) return PIHYST_CREEP_EDT;
    if (initial_state) {
        for (i = 0; i < n; ++i)
            if (!isfinite(initial_state[i])) return PIHYST_CREEP_ENONFINITE;
    }
    c->n = n;
    c->tau = tau;
    c->gain = gain;
    c->dt = dt;
    c->alpha = alpha;
    c->state = state;
    c->beta = RC(0.0);
#ifdef PIHYST_BUILD_F32
    c->h = RC(0.0); /* so that the deviations e_i = z_i - 0 are the initial z_i */
#endif
    for (i = 0; i < n; ++i) {
        /* (C1): alpha = 1 - exp(-dt/tau), without cancellation for dt << tau */
        alpha[i] = -R_EXPM1(-dt / tau[i]);
        c->beta += gain[i] * (RC(1.0) - alpha[i]);            /* (C4) */
        state[i] = initial_state ? initial_state[i] : RC(0.0);
    }
    return PIHYST_CREEP_OK;
}

#ifndef PIHYST_BUILD_F32 /* (C1)-(C5): the state is z_i */

void pihyst_creep_settle(pihyst_creep *c, double h)
{
    size_t i;
    for (i = 0; i < c->n; ++i) c->state[i] = h;
}

/* H* = (y_d - sum_i g_i (1 - alpha_i) z_i) / (1 - beta)                           (C5) */
double pihyst_creep_target(const pihyst_creep *c, double y_desired)
{
    size_t i;
    double carry = 0.0;
    for (i = 0; i < c->n; ++i) carry += c->gain[i] * (1.0 - c->alpha[i]) * c->state[i];
    return (y_desired - carry) / (1.0 - c->beta);
}

/* z_i <- z_i + alpha_i (h - z_i)                                                  (C2)
 * y    = h - sum_i g_i (h - z_i)                                                  (C3) */
double pihyst_creep_step(pihyst_creep *c, double h)
{
    size_t i;
    double lag = 0.0;
    for (i = 0; i < c->n; ++i) {
        c->state[i] += c->alpha[i] * (h - c->state[i]);
        lag += c->gain[i] * (h - c->state[i]);
    }
    return h - lag;
}

double pihyst_creep_target_dt(const pihyst_creep *c, double dt, double y_desired)
{
    size_t i;
    double carry = 0.0, beta = 0.0;
    if (dt == c->dt) return pihyst_creep_target(c, y_desired); /* alpha_i known */
    for (i = 0; i < c->n; ++i) {
        const double keep = c->gain[i] * exp(-dt / c->tau[i]); /* g_i (1 - alpha_i) */
        carry += keep * c->state[i];
        beta += keep;
    }
    return (y_desired - carry) / (1.0 - beta);
}

double pihyst_creep_step_dt(pihyst_creep *c, double dt, double h)
{
    size_t i;
    double lag = 0.0;
    if (dt == c->dt) return pihyst_creep_step(c, h); /* alpha_i known: no exp */
    for (i = 0; i < c->n; ++i) {
        c->state[i] += -expm1(-dt / c->tau[i]) * (h - c->state[i]);
        lag += c->gain[i] * (h - c->state[i]);
    }
    return h - lag;
}

#else /* (C2')-(C5'): the state is e_i = z_i - c->h */

void pihyst_creep_settle(pihyst_creep *c, float h)
{
    size_t i;
    for (i = 0; i < c->n; ++i) c->state[i] = 0.0f;
    c->h = h;
}

/* H* = H[t-1] + (y_d - H[t-1] - sum_i g_i (1 - alpha_i) e_i) / (1 - beta)          (C5') */
float pihyst_creep_target(const pihyst_creep *c, float y_desired)
{
    size_t i;
    float carry = 0.0f;
    for (i = 0; i < c->n; ++i) carry += c->gain[i] * (1.0f - c->alpha[i]) * c->state[i];
    return c->h + ((y_desired - c->h) - carry) / (1.0f - c->beta);
}

/* x_i = e_i - (h - H[t-1]),  e_i <- x_i - alpha_i x_i                               (C2')
 * y   = h + sum_i g_i e_i                                                            (C3') */
float pihyst_creep_step(pihyst_creep *c, float h)
{
    size_t i;
    const float dh = h - c->h;
    float lag = 0.0f;
    for (i = 0; i < c->n; ++i) {
        const float x = c->state[i] - dh;
        c->state[i] = x - c->alpha[i] * x;
        lag += c->gain[i] * c->state[i];
    }
    c->h = h;
    return h + lag;
}

float pihyst_creep_target_dt(const pihyst_creep *c, float dt, float y_desired)
{
    size_t i;
    float carry = 0.0f, beta = 0.0f;
    if (dt == c->dt) return pihyst_creep_target(c, y_desired); /* alpha_i known */
    for (i = 0; i < c->n; ++i) {
        const float keep = c->gain[i] * expf(-dt / c->tau[i]); /* g_i (1 - alpha_i) */
        carry += keep * c->state[i];
        beta += keep;
    }
    return c->h + ((y_desired - c->h) - carry) / (1.0f - beta);
}

float pihyst_creep_step_dt(pihyst_creep *c, float dt, float h)
{
    size_t i;
    const float dh = h - c->h;
    float lag = 0.0f;
    if (dt == c->dt) return pihyst_creep_step(c, h); /* alpha_i known: no exp */
    for (i = 0; i < c->n; ++i) {
        const float x = c->state[i] - dh;
        c->state[i] = x + expm1f(-dt / c->tau[i]) * x; /* x - alpha_i x */
        lag += c->gain[i] * c->state[i];
    }
    c->h = h;
    return h + lag;
}

#endif

void pihyst_creep_run(pihyst_creep *c, const real *h, const real *dt, real *y, size_t n)
{
    size_t t;
    if (dt) {
        for (t = 0; t < n; ++t) y[t] = pihyst_creep_step_dt(c, dt[t], h[t]);
    } else {
        for (t = 0; t < n; ++t) y[t] = pihyst_creep_step(c, h[t]);
    }
}

real pihyst_creep_compensator_step(pihyst_creep *cr, pihyst_compensator *c, real dt,
                                   real y_desired, real *y, pihyst_flags *flags)
{
    const int fixed = dt < RC(0.0);
    /* a NaN desired value gives a NaN target: the compensator holds and flags it */
    const real target = fixed ? pihyst_creep_target(cr, y_desired)
                              : pihyst_creep_target_dt(cr, dt, y_desired);
    const real u = pihyst_compensator_step(c, target, flags);
    const real out = fixed ? pihyst_creep_step(cr, c->y_last)
                           : pihyst_creep_step_dt(cr, dt, c->y_last);
    if (y) *y = out;
    return u;
}

size_t pihyst_creep_compensator_run(pihyst_creep *cr, pihyst_compensator *c,
                                    const real *y_desired, const real *dt, real *u, real *y,
                                    pihyst_flags *flags, size_t n)
{
    size_t t, count = 0;
    for (t = 0; t < n; ++t) {
        pihyst_flags fl = 0;
        real out;
        u[t] = pihyst_creep_compensator_step(cr, c, dt ? dt[t] : RC(-1.0), y_desired[t], &out,
                                             &fl);
        if (y) y[t] = out;
        if (flags) flags[t] = fl;
        count += fl != 0;
    }
    return count;
}

#ifndef PIHYST_BUILD_F32 /* one copy, shared by both precisions */
const char *pihyst_creep_status_text(pihyst_creep_status status)
{
    switch (status) {
    case PIHYST_CREEP_OK: return "ok";
    case PIHYST_CREEP_ENULL: return "a required pointer is NULL";
    case PIHYST_CREEP_ESIZE: return "creep needs at least one lag";
    case PIHYST_CREEP_ENONFINITE: return "creep parameter or state is NaN or infinite";
    case PIHYST_CREEP_ETAU: return "creep time constants must be > 0";
    case PIHYST_CREEP_EGAIN: return "creep gains must be >= 0 and sum to less than 1";
    case PIHYST_CREEP_EDT: return "creep sample interval must be finite and >= 0";
    }
    return "unknown status";
}
#endif
