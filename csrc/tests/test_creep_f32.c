/* Tests of the single-precision creep lags (pihyst_creep_*_f32, the deviation form
 * (C2')-(C5') of pihyst_creep.h) against the double lags (pihyst_creep.c) on the same
 * parameters and hysteresis outputs (floats, so both see the same numbers): random lag
 * sets from 10 ms to 1000 s at 200 Hz and 1 kHz, jumps, walks and holds; the slow lag
 * that a float lag stepped as (C2) would stall on; the target met through the f32
 * compensator (a KP-like ramp model and a classical one); settling; validation. Built in
 * the single-precision suite only. */
#include "test_util.h"

#ifdef PIHYST_TEST_F32
#include "pihyst_creep.h"

#include <stdio.h>

#define MAX_LAGS 9

static unsigned cf_lcg = 4242u;
static float cf_uniform(void) /* [0, 1), a float */
{
    cf_lcg = cf_lcg * 1103515245u + 12345u;
    return (float)(cf_lcg >> 8) / 16777216.0f;
}

typedef struct {
    size_t n;
    float tau[MAX_LAGS], gain[MAX_LAGS], alpha[MAX_LAGS], state[MAX_LAGS];
    double tau_d[MAX_LAGS], gain_d[MAX_LAGS], alpha_d[MAX_LAGS], state_d[MAX_LAGS];
    pihyst_creep_f32 f;
    pihyst_creep d;
} creep_twin;

/* n lags, tau log-uniform in [10 ms, 1000 s], gains summing to at most 0.3 */
static int twin_creep(creep_twin *t, size_t n, float dt)
{
    size_t i;
    t->n = n;
    for (i = 0; i < n; ++i) {
        t->tau[i] = 0.01f * powf(10.0f, 5.0f * cf_uniform());
        t->gain[i] = 0.3f / (float)n * cf_uniform();
        t->tau_d[i] = t->tau[i];
        t->gain_d[i] = t->gain[i];
    }
    return pihyst_creep_init_f32(&t->f, n, t->tau, t->gain, dt, t->alpha, t->state, NULL) ==
               PIHYST_CREEP_OK &&
           pihyst_creep_init(&t->d, n, t->tau_d, t->gain_d, (double)dt, t->alpha_d, t->state_d,
                             NULL) == PIHYST_CREEP_OK;
}

static double worst_fraction = 0.0;

/* |y_f32 - y_f64| <= (n + 4) eps (|h| + sum g |e|) + sum_i g_i B_i: the output's sum, and
 * each lag's error B_i, which takes at most 4 eps (|e_i| + |dH|) per step (x, alpha x with
 * the rounding of alpha itself, the difference) and decays by (1 - alpha_i) per step:
 * B_i <- (1 - alpha_i) B_i + 4 eps (|e_i| + |dH|). */
static void compare(creep_twin *t, const float *h, const float *dt, size_t T)
{
    size_t s, i;
    double b[MAX_LAGS] = {0.0}, h_last = 0.0;
    int ok = 1;
    for (s = 0; s < T; ++s) {
        const float y = dt ? pihyst_creep_step_dt_f32(&t->f, dt[s], h[s])
                           : pihyst_creep_step_f32(&t->f, h[s]);
        double e_before[MAX_LAGS], yd, bound = 0.0, sum_ge = 0.0;
        for (i = 0; i < t->n; ++i) e_before[i] = t->state_d[i] - h_last;
        yd = dt ? pihyst_creep_step_dt(&t->d, dt[s], h[s]) : pihyst_creep_step(&t->d, h[s]);
        for (i = 0; i < t->n; ++i) {
            const double alpha = dt ? -expm1(-(double)dt[s] / t->tau_d[i]) : t->alpha_d[i];
            b[i] = (1.0 - alpha) * b[i] +
                   4.0 * FLT_EPSILON * (fabs(e_before[i]) + fabs(h[s] - h_last));
            sum_ge += t->gain_d[i] * fabs(t->state_d[i] - h[s]);
            bound += t->gain_d[i] * b[i];
        }
        bound += ((double)t->n + 4.0) * FLT_EPSILON * (fabs(h[s]) + sum_ge);
        if (!(fabs(y - yd) <= bound)) ok = 0;
        if (bound > 0.0 && fabs(y - yd) / bound > worst_fraction)
            worst_fraction = fabs(y - yd) / bound;
        h_last = h[s];
    }
    CHECK(ok);
}

#define T_LONG 60000

static void test_twin_lags(void)
{
    static float h[T_LONG], dt[T_LONG];
    int rep;
    for (rep = 0; rep < 12; ++rep) {
        creep_twin t;
        const size_t n = 1 + (size_t)rep % MAX_LAGS;
        const float step_dt = rep % 2 ? 0.005f : 0.001f;
        size_t s;
        float v = 0.0f;
        CHECK(twin_creep(&t, n, step_dt));
        for (s = 0; s < T_LONG; ++s) { /* jumps, walks and holds in [-150, 150] um */
            const float r = cf_uniform();
            if (r < 0.002f) v = 300.0f * cf_uniform() - 150.0f;
            else if (r < 0.6f) v += 0.5f * (cf_uniform() - 0.5f);
            h[s] = v;
            dt[s] = cf_uniform() < 0.1f ? 0.0f : 3.0f * step_dt * cf_uniform();
        }
        compare(&t, h, rep % 3 == 2 ? dt : NULL, T_LONG);
    }
}

/* The case the deviation form is for: P-885's slowest lag (tau = 1000 s) at 200 Hz,
 * alpha = 5e-6, after a step to -120 um: the lag must keep approaching H. Stepped as
 * (C2) in floats it would stop within ulp(120)/(2 alpha) = 0.8 um of H. */
static void test_slow_lag(void)
{
    static const float tau[1] = {1000.0f}, gain[1] = {0.2f};
    float alpha[1], state[1], y = 0.0f;
    pihyst_creep_f32 c;
    long s;
    double z_exact;
    CHECK(pihyst_creep_init_f32(&c, 1, tau, gain, 0.005f, alpha, state, NULL) ==
          PIHYST_CREEP_OK);
    for (s = 0; s < 400000; ++s) y = pihyst_creep_step_f32(&c, -120.0f); /* 2000 s */
    /* z = -120 (1 - (1 - alpha)^T), y = -120 + 0.2 (z + 120) */
    z_exact = -120.0 * (1.0 - pow(1.0 + expm1(-0.005 / 1000.0), 400000.0));
    /* measured: 6.3e-5 of the deviation e = z + 120 = 16.24 um after 2000 s (the
     * roundings of 400000 steps); the (C2) form in floats would be off by up to 0.8 um */
    CHECK_NEAR(c.state[0], z_exact + 120.0, 1e-4 * (z_exact + 120.0));
    CHECK_NEAR(y, -120.0 + 0.2 * (z_exact + 120.0), 0.2 * 1e-4 * (z_exact + 120.0) + 1e-5);
}

static void test_settle_target(void)
{
    static const float tau[3] = {0.5f, 5.0f, 50.0f}, gain[3] = {0.02f, 0.03f, 0.05f};
    static const float bad_tau[3] = {0.5f, 0.0f, 3.0f}, big[3] = {0.5f, 0.3f, 0.2f};
    static const float bad_state[3] = {0.0f, NAN, 0.0f}, z0[3] = {1.0f, 2.0f, 3.0f};
    float alpha[3], state[3], worst = 0.0f, worst_dt = 0.0f;
    pihyst_creep_f32 c;
    pihyst_creep d;
    double alpha_d[3], state_d[3];
    static const double tau_d[3] = {0.5, 5.0, 50.0}, gain_d[3] = {0.02, 0.03, 0.05};
    int s;
    CHECK(pihyst_creep_init_f32(&c, 3, tau, gain, 0.01f, alpha, state, NULL) ==
          PIHYST_CREEP_OK);
    pihyst_creep_settle_f32(&c, 3.5f);
    CHECK(pihyst_creep_step_f32(&c, 3.5f) == 3.5f); /* settled: y = h exactly */
    CHECK(pihyst_creep_step_dt_f32(&c, 7.0f, 3.5f) == 3.5f);
    /* the target (C5') is met by the step (C2')-(C3'), fixed and per-sample intervals */
    for (s = 0; s < 3000; ++s) {
        const float yd = 10.0f * cf_uniform() - 2.0f;
        const float step_dt = cf_uniform() < 0.1f ? 0.0f : 3.0f * cf_uniform();
        float hs = pihyst_creep_target_f32(&c, yd), out = pihyst_creep_step_f32(&c, hs);
        if (fabsf(out - yd) > worst) worst = fabsf(out - yd);
        hs = pihyst_creep_target_dt_f32(&c, step_dt, yd);
        out = pihyst_creep_step_dt_f32(&c, step_dt, hs);
        if (fabsf(out - yd) > worst_dt) worst_dt = fabsf(out - yd);
    }
    CHECK(worst <= 16.0f * FLT_EPSILON * 10.0f);
    CHECK(worst_dt <= 16.0f * FLT_EPSILON * 10.0f);
    /* initial_state gives z_i as in the double API */
    CHECK(pihyst_creep_init_f32(&c, 3, tau, gain, 0.01f, alpha, state, z0) == PIHYST_CREEP_OK);
    CHECK(pihyst_creep_init(&d, 3, tau_d, gain_d, 0.01, alpha_d, state_d,
                            (const double[3]){1.0, 2.0, 3.0}) == PIHYST_CREEP_OK);
    CHECK_NEAR(pihyst_creep_step_f32(&c, 4.0f), pihyst_creep_step(&d, 4.0), 1e-5);
    CHECK_NEAR(pihyst_creep_target_f32(&c, 5.0f), pihyst_creep_target(&d, 5.0), 1e-5);
    /* validation: the double API's codes */
    CHECK(pihyst_creep_init_f32(NULL, 3, tau, gain, 0.1f, alpha, state, NULL) ==
          PIHYST_CREEP_ENULL);
    CHECK(pihyst_creep_init_f32(&c, 0, tau, gain, 0.1f, alpha, state, NULL) ==
          PIHYST_CREEP_ESIZE);
    CHECK(pihyst_creep_init_f32(&c, 3, bad_tau, gain, 0.1f, alpha, state, NULL) ==
          PIHYST_CREEP_ETAU);
    CHECK(pihyst_creep_init_f32(&c, 3, tau, big, 0.1f, alpha, state, NULL) ==
          PIHYST_CREEP_EGAIN);
    CHECK(pihyst_creep_init_f32(&c, 3, tau, gain, -0.1f, alpha, state, NULL) ==
          PIHYST_CREEP_EDT);
    CHECK(pihyst_creep_init_f32(&c, 3, tau, gain, 0.1f, alpha, state, bad_state) ==
          PIHYST_CREEP_ENONFINITE);
}

/* A model with creep compensated in single precision: the desired output is the model's
 * (f32, with its f32 lags) for a voltage walk with holds; the compensator with the lags
 * meets it to the compensator's tolerance plus the lags' rounding, unflagged, and keeps
 * every voltage in the limits under any input. A classical model (r_0 = 0: strictly
 * increasing) and a KP-like ramp model (the compensator's ramp path). */
#define N_CF 4000
static void round_trip(pihyst_model *m, const float *tau, const float *gain, size_t n_lags,
                       float *scratch, size_t scratch_len)
{
    static float yd[N_CF], uc[N_CF], yc[N_CF];
    static pihyst_flags flags[N_CF];
    static const float wild[6] = {NAN, INFINITY, -INFINITY, 1e30f, -1e30f, 20.0f};
    float alpha[MAX_LAGS], state[MAX_LAGS], err = 0.0f, scale = 0.0f, v = 0.0f, target = 100.0f;
    pihyst_creep_f32 cr;
    pihyst_compensator c;
    int t, bad = 0;
    CHECK(pihyst_creep_init_f32(&cr, n_lags, tau, gain, 0.005f, alpha, state, NULL) ==
          PIHYST_CREEP_OK);
    pihyst_model_reset(m, NULL);
    pihyst_creep_settle_f32(&cr, pihyst_model_step(m, 0.0f));
    for (t = 0; t < N_CF; ++t) {
        if (cf_uniform() < 0.01f) target = 150.0f * cf_uniform();
        if (cf_uniform() < 0.5f)
            v = v < target ? fminf(v + 2.0f * cf_uniform(), target)
                           : fmaxf(v - 2.0f * cf_uniform(), target);
        yd[t] = pihyst_creep_step_f32(&cr, pihyst_model_step(m, v));
        if (fabsf(yd[t]) > scale) scale = fabsf(yd[t]);
    }
    pihyst_model_reset(m, NULL);
    CHECK(pihyst_creep_init_f32(&cr, n_lags, tau, gain, 0.005f, alpha, state, NULL) ==
          PIHYST_CREEP_OK);
    pihyst_creep_settle_f32(&cr, pihyst_model_step(m, 0.0f));
    CHECK(pihyst_compensator_init(&c, m, NAN, NAN, INFINITY, 0.0f, scratch, scratch_len) ==
          PIHYST_OK);
    CHECK(pihyst_creep_compensator_run_f32(&cr, &c, yd, NULL, uc, yc, flags, N_CF) == 0);
    for (t = 0; t < N_CF; ++t)
        if (fabsf(yc[t] - yd[t]) > err) err = fabsf(yc[t] - yd[t]);
    /* the compensator's band c.tol on the hysteresis target, plus the rounding of the
     * target and of the lags' output (a few ulps of the output scale) */
    CHECK(err <= c.tol + 16.0f * FLT_EPSILON * scale);
    for (t = 0; t < 3 * N_CF; ++t) {
        pihyst_flags fl;
        float y;
        const float uu = pihyst_creep_compensator_step_f32(&cr, &c, 0.005f * (float)(t % 3) - 0.001f,
                                                           wild[t % 6], &y, &fl);
        if (!(uu >= 0.0f && uu <= 150.0f) || !isfinite(y)) bad = 1;
        if (t % 6 == 0 && !(fl & PIHYST_COMP_NAN)) bad = 1;
    }
    CHECK(!bad);
}

static void test_round_trip(void)
{
    static const float tau[4] = {0.02f, 0.3f, 6.0f, 200.0f};
    static const float gain[4] = {0.01f, 0.02f, 0.04f, 0.05f};
    static const float thr[4] = {0.0f, 10.0f, 25.0f, 45.0f}, w[4] = {0.2f, 0.1f, 0.05f, 0.04f};
    enum { K = 24 };
    static float coef[PIHYST_COEF_LEN(K)], f[K], wk[K];
    static float rx[4 * K], ry[4 * K], fx[4 * K], fy[4 * K];
    static size_t st[K + 1];
    static float scratch[PIHYST_COMPENSATOR_SCRATCH_LEN_F32(K, 8 * K)]; /* 4 K rising, 4 K falling */
    pihyst_model m;
    pihyst_pwl pwl;
    size_t k;
    CHECK(model_init(&m, PIHYST_CLASSICAL, 4, thr, w, 1.0f, 0.0f, 150.0f, NULL, NULL, coef, f,
                     NULL) == PIHYST_OK);
    round_trip(&m, tau, gain, 4, scratch, sizeof scratch / sizeof *scratch);
    /* KP kernels: ramps of width 12 V, the falling one 6-30 V left of the rising one */
    for (k = 0; k <= K; ++k) st[k] = 4 * k;
    for (k = 0; k < K; ++k) {
        const float c = 150.0f * (float)(k % 6) / 5.0f, shift = 6.0f + 4.0f * (float)(k / 6);
        const float xr[4] = {c - 100.0f, c, c + 12.0f, c + 300.0f};
        size_t i;
        for (i = 0; i < 4; ++i) {
            rx[4 * k + i] = xr[i];
            fx[4 * k + i] = xr[i] - shift;
            ry[4 * k + i] = fy[4 * k + i] = i < 2 ? 0.0f : 1.0f;
        }
        wk[k] = 0.5f + cf_uniform();
    }
    pwl.rise_start = st; pwl.rise_x = rx; pwl.rise_y = ry;
    pwl.fall_start = st; pwl.fall_x = fx; pwl.fall_y = fy;
    CHECK(model_init(&m, PIHYST_PWL, K, NULL, wk, 0.0f, 0.0f, 150.0f, NULL, &pwl, coef, f,
                     NULL) == PIHYST_OK);
    CHECK(m.coef[0] == 1.0f); /* the ramp path */
    round_trip(&m, tau, gain, 4, scratch, sizeof scratch / sizeof *scratch);
}

void run_creep_f32_tests(void)
{
    test_twin_lags();
    test_slow_lag();
    test_settle_target();
    test_round_trip();
    /* the measured worst case, as a fraction of the bound (deterministic: same output on
     * the host and the target) */
    printf("creep f32: worst |y_f32 - y_f64| = %.3g of the bound\n", worst_fraction);
}
#else
void run_creep_f32_tests(void) {}
#endif
