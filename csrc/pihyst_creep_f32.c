/* pihyst_creep_f32.c - the creep lags of pihyst_creep.h in single precision, in the
 * deviation form (C2')-(C5') of that header, for a single-precision FPU (Cortex-M4F):
 * float operations only (make -C csrc m4f checks that no software double routine is
 * called). The double lags (pihyst_creep.c) are their reference in the tests
 * (csrc/tests/test_creep_f32.c). */
#include "pihyst_creep.h"

#include <math.h>

pihyst_creep_status pihyst_creep_init_f32(pihyst_creep_f32 *c, size_t n, const float *tau,
                                          const float *gain, float dt, float *alpha,
                                          float *state, const float *initial_state)
{
    size_t i;
    float sum = 0.0f;
    if (!c || !tau || !gain || !alpha || !state) return PIHYST_CREEP_ENULL;
    if (n == 0) return PIHYST_CREEP_ESIZE;
    for (i = 0; i < n; ++i) {
        if (!isfinite(tau[i]) || !isfinite(gain[i])) return PIHYST_CREEP_ENONFINITE;
        if (!(tau[i] > 0.0f)) return PIHYST_CREEP_ETAU;
        if (gain[i] < 0.0f) return PIHYST_CREEP_EGAIN;
        sum += gain[i];
    }
    if (!(sum < 1.0f)) return PIHYST_CREEP_EGAIN;
    if (!isfinite(dt) || dt < 0.0f) return PIHYST_CREEP_EDT;
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
    c->h = 0.0f;
    c->beta = 0.0f;
    for (i = 0; i < n; ++i) {
        alpha[i] = -expm1f(-dt / tau[i]);      /* (C1), no cancellation for dt << tau */
        c->beta += gain[i] * (1.0f - alpha[i]); /* (C4) */
        state[i] = initial_state ? initial_state[i] : 0.0f; /* e_i = z_i - 0 */
    }
    return PIHYST_CREEP_OK;
}

void pihyst_creep_settle_f32(pihyst_creep_f32 *c, float h)
{
    size_t i;
    for (i = 0; i < c->n; ++i) c->state[i] = 0.0f;
    c->h = h;
}

/* H* = H[t-1] + (y_d - H[t-1] - sum_i g_i (1 - alpha_i) e_i) / (1 - beta)          (C5') */
float pihyst_creep_target_f32(const pihyst_creep_f32 *c, float y_desired)
{
    size_t i;
    float carry = 0.0f;
    for (i = 0; i < c->n; ++i) carry += c->gain[i] * (1.0f - c->alpha[i]) * c->state[i];
    return c->h + ((y_desired - c->h) - carry) / (1.0f - c->beta);
}

/* x_i = e_i - (h - H[t-1]),  e_i <- x_i - alpha_i x_i                               (C2')
 * y   = h + sum_i g_i e_i                                                            (C3') */
float pihyst_creep_step_f32(pihyst_creep_f32 *c, float h)
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

float pihyst_creep_target_dt_f32(const pihyst_creep_f32 *c, float dt, float y_desired)
{
    size_t i;
    float carry = 0.0f, beta = 0.0f;
    if (dt == c->dt) return pihyst_creep_target_f32(c, y_desired); /* alpha_i known */
    for (i = 0; i < c->n; ++i) {
        const float keep = c->gain[i] * expf(-dt / c->tau[i]); /* g_i (1 - alpha_i) */
        carry += keep * c->state[i];
        beta += keep;
    }
    return c->h + ((y_desired - c->h) - carry) / (1.0f - beta);
}

float pihyst_creep_step_dt_f32(pihyst_creep_f32 *c, float dt, float h)
{
    size_t i;
    const float dh = h - c->h;
    float lag = 0.0f;
    if (dt == c->dt) return pihyst_creep_step_f32(c, h); /* alpha_i known: no exp */
    for (i = 0; i < c->n; ++i) {
        const float x = c->state[i] - dh;
        c->state[i] = x + expm1f(-dt / c->tau[i]) * x; /* x - alpha_i x */
        lag += c->gain[i] * c->state[i];
    }
    c->h = h;
    return h + lag;
}

void pihyst_creep_run_f32(pihyst_creep_f32 *c, const float *h, const float *dt, float *y,
                          size_t n)
{
    size_t t;
    if (dt) {
        for (t = 0; t < n; ++t) y[t] = pihyst_creep_step_dt_f32(c, dt[t], h[t]);
    } else {
        for (t = 0; t < n; ++t) y[t] = pihyst_creep_step_f32(c, h[t]);
    }
}

float pihyst_creep_compensator_step_f32(pihyst_creep_f32 *cr, pihyst_compensator_f32 *c,
                                        float dt, float y_desired, float *y,
                                        pihyst_flags *flags)
{
    const int fixed = dt < 0.0f;
    /* a NaN desired value gives a NaN target: the compensator holds and flags it */
    const float target = fixed ? pihyst_creep_target_f32(cr, y_desired)
                               : pihyst_creep_target_dt_f32(cr, dt, y_desired);
    const float u = pihyst_compensator_step_f32(c, target, flags);
    const float out = fixed ? pihyst_creep_step_f32(cr, c->y_last)
                            : pihyst_creep_step_dt_f32(cr, dt, c->y_last);
    if (y) *y = out;
    return u;
}

size_t pihyst_creep_compensator_run_f32(pihyst_creep_f32 *cr, pihyst_compensator_f32 *c,
                                        const float *y_desired, const float *dt, float *u,
                                        float *y, pihyst_flags *flags, size_t n)
{
    size_t t, count = 0;
    for (t = 0; t < n; ++t) {
        pihyst_flags fl = 0;
        float out;
        u[t] = pihyst_creep_compensator_step_f32(cr, c, dt ? dt[t] : -1.0f, y_desired[t],
                                                 &out, &fl);
        if (y) y[t] = out;
        if (flags) flags[t] = fl;
        count += fl != 0;
    }
    return count;
}
