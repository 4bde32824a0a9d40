/* Tests of pihyst_creep_*: the step response in closed form, settling, the target (C5)
 * met exactly by (C2)-(C3) for fixed and per-sample intervals, step == run, and the
 * compensator with creep: exact round trip of a model with creep on a voltage walk
 * with holds, limits under any input (NaN, infinities, 1e300), validation. */
#include "test_util.h"

#ifndef PIHYST_TEST_F32 /* the creep lags are double precision only */
#include "pihyst_creep.h"

#include <float.h>

#define N_CREEP 3000

static unsigned creep_lcg = 77u;
static double creep_uniform(void) /* [0, 1) */
{
    creep_lcg = creep_lcg * 1103515245u + 12345u;
    return (double)(creep_lcg >> 8) / (double)(1u << 24);
}

static const double tau3[3] = {0.5, 5.0, 50.0};
static const double gain3[3] = {0.02, 0.03, 0.05};

static void test_step_response(void)
{
    /* from rest at 0, H jumps to 1: y[t] = 1 - sum_i g_i exp(-(t + 1) dt / tau_i) */
    pihyst_creep c;
    double alpha[3], state[3], worst = 0.0;
    int t;
    CHECK(pihyst_creep_init(&c, 3, tau3, gain3, 0.1, alpha, state, NULL) == PIHYST_CREEP_OK);
    for (t = 0; t < 2000; ++t) {
        const double y = pihyst_creep_step(&c, 1.0);
        double ref = 1.0;
        int i;
        for (i = 0; i < 3; ++i) ref -= gain3[i] * exp(-(t + 1) * 0.1 / tau3[i]);
        if (fabs(y - ref) > worst) worst = fabs(y - ref);
    }
    CHECK(worst < 1e-13);
    /* settled: y = h, and a constant h keeps it there */
    pihyst_creep_settle(&c, 3.5);
    CHECK_NEAR(pihyst_creep_step(&c, 3.5), 3.5, 1e-15);
    CHECK_NEAR(pihyst_creep_step_dt(&c, 7.0, 3.5), 3.5, 1e-15);
    /* dt = 0: the lags do not move, y = (1 - sum g) h + sum g z */
    CHECK_NEAR(pihyst_creep_step_dt(&c, 0.0, 4.5), 4.5 - 0.1 * 1.0, 1e-14);
}

static void test_target_exact(void)
{
    pihyst_creep c, d;
    double alpha[3], state[3], alpha2[3], state2[3], y[N_CREEP], h[N_CREEP], dt[N_CREEP];
    double worst = 0.0, worst_dt = 0.0;
    int t;
    CHECK(pihyst_creep_init(&c, 3, tau3, gain3, 0.01, alpha, state, NULL) == PIHYST_CREEP_OK);
    for (t = 0; t < N_CREEP; ++t) {
        const double yd = 10.0 * creep_uniform() - 2.0;
        const double step_dt = creep_uniform() < 0.1 ? 0.0 : 3.0 * creep_uniform();
        double hs = pihyst_creep_target(&c, yd), out = pihyst_creep_step(&c, hs);
        if (fabs(out - yd) > worst) worst = fabs(out - yd);
        hs = pihyst_creep_target_dt(&c, step_dt, yd);
        out = pihyst_creep_step_dt(&c, step_dt, hs);
        if (fabs(out - yd) > worst_dt) worst_dt = fabs(out - yd);
    }
    CHECK(worst < 1e-12);
    CHECK(worst_dt < 1e-12);
    /* run == steps, per-sample intervals and the fixed one */
    CHECK(pihyst_creep_init(&c, 3, tau3, gain3, 0.01, alpha, state, NULL) == PIHYST_CREEP_OK);
    CHECK(pihyst_creep_init(&d, 3, tau3, gain3, 0.01, alpha2, state2, NULL) == PIHYST_CREEP_OK);
    for (t = 0; t < N_CREEP; ++t) {
        h[t] = 5.0 * creep_uniform();
        dt[t] = 0.2 * creep_uniform();
    }
    pihyst_creep_run(&c, h, dt, y, N_CREEP);
    worst = 0.0;
    for (t = 0; t < N_CREEP; ++t) {
        const double s = pihyst_creep_step_dt(&d, dt[t], h[t]);
        if (s != y[t]) worst = 1.0;
    }
    CHECK(worst == 0.0);
    pihyst_creep_run(&c, h, NULL, y, N_CREEP);
    worst = 0.0;
    for (t = 0; t < N_CREEP; ++t)
        if (pihyst_creep_step(&d, h[t]) != y[t]) worst = 1.0;
    CHECK(worst == 0.0);
}

static void test_compensator(void)
{
    /* a classical model with creep; desired = its output for a staircase-and-ramp walk */
    static const double thr[4] = {0.0, 10.0, 25.0, 45.0};
    static const double w[4] = {0.2, 0.1, 0.05, 0.04};
    static double u[N_CREEP], yd[N_CREEP], uc[N_CREEP], yc[N_CREEP];
    static pihyst_flags flags[N_CREEP];
    static double scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(4, 0)];
    static const double wild[6] = {NAN, INFINITY, -INFINITY, 1e300, -1e300, 20.0};
    double coef[PIHYST_COEF_LEN(4)], fstate[4], alpha[3], zstate[3], err = 0.0;
    pihyst_model m;
    pihyst_creep cr;
    pihyst_compensator c;
    double v = 0.0, target = 100.0;
    int t, bad = 0;
    size_t n_flagged;
    pihyst_params params = {0};
    params.family = PIHYST_CLASSICAL;
    params.n_ops = 4;
    params.thresholds = thr;
    params.weights = w;
    params.offset = 1.0;
    params.u_min = 0.0;
    params.u_max = 150.0;
    CHECK(pihyst_model_init(&m, &params, coef, fstate) == PIHYST_OK);
    CHECK(pihyst_creep_init(&cr, 3, tau3, gain3, 0.05, alpha, zstate, NULL) ==
          PIHYST_CREEP_OK);
    pihyst_creep_settle(&cr, pihyst_model_step(&m, 0.0));
    for (t = 0; t < N_CREEP; ++t) {
        if (creep_uniform() < 0.01) target = 150.0 * creep_uniform();
        if (creep_uniform() < 0.5) /* holds: half the samples do not move */
            v = v < target ? fmin(v + 2.0 * creep_uniform(), target)
                           : fmax(v - 2.0 * creep_uniform(), target);
        u[t] = v;
        yd[t] = pihyst_creep_step(&cr, pihyst_model_step(&m, v));
    }
    pihyst_model_reset(&m, NULL);
    CHECK(pihyst_creep_init(&cr, 3, tau3, gain3, 0.05, alpha, zstate, NULL) ==
          PIHYST_CREEP_OK);
    pihyst_creep_settle(&cr, pihyst_model_step(&m, 0.0));
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0, scratch,
                                  sizeof scratch / sizeof *scratch) == PIHYST_OK);
    n_flagged = pihyst_creep_compensator_run(&cr, &c, yd, NULL, uc, yc, flags, N_CREEP);
    CHECK(n_flagged == 0);
    for (t = 0; t < N_CREEP; ++t)
        if (fabs(yc[t] - yd[t]) > err) err = fabs(yc[t] - yd[t]);
    CHECK(err < 1e-9);
    /* the r = 0 operator makes the model strictly increasing: the voltage is unique */
    err = 0.0;
    for (t = 0; t < N_CREEP; ++t)
        if (fabs(uc[t] - u[t]) > err) err = fabs(uc[t] - u[t]);
    CHECK(err < 1e-7);
    /* any input: the voltage stays inside the limits */
    for (t = 0; t < N_CREEP; ++t) {
        pihyst_flags fl;
        double y;
        const double uu = pihyst_creep_compensator_step(&cr, &c, 0.05 * (t % 3),
                                                        wild[t % 6], &y, &fl);
        if (!(uu >= 0.0 && uu <= 150.0) || !isfinite(y)) bad = 1;
        if (t % 6 == 0 && !(fl & PIHYST_COMP_NAN)) bad = 1;
    }
    CHECK(!bad);
}

static void test_validation(void)
{
    pihyst_creep c;
    double alpha[3], state[3];
    const double neg_tau[3] = {0.5, 0.0, 3.0};
    const double big[3] = {0.5, 0.3, 0.2};
    const double neg[3] = {0.1, -0.01, 0.1};
    const double bad_state[3] = {0.0, NAN, 0.0};
    CHECK(pihyst_creep_init(NULL, 3, tau3, gain3, 0.1, alpha, state, NULL) ==
          PIHYST_CREEP_ENULL);
    CHECK(pihyst_creep_init(&c, 0, tau3, gain3, 0.1, alpha, state, NULL) ==
          PIHYST_CREEP_ESIZE);
    CHECK(pihyst_creep_init(&c, 3, neg_tau, gain3, 0.1, alpha, state, NULL) ==
          PIHYST_CREEP_ETAU);
    CHECK(pihyst_creep_init(&c, 3, tau3, big, 0.1, alpha, state, NULL) == PIHYST_CREEP_EGAIN);
    CHECK(pihyst_creep_init(&c, 3, tau3, neg, 0.1, alpha, state, NULL) == PIHYST_CREEP_EGAIN);
    CHECK(pihyst_creep_init(&c, 3, tau3, gain3, -0.1, alpha, state, NULL) ==
          PIHYST_CREEP_EDT);
    CHECK(pihyst_creep_init(&c, 3, tau3, gain3, INFINITY, alpha, state, NULL) ==
          PIHYST_CREEP_EDT);
    CHECK(pihyst_creep_init(&c, 3, tau3, gain3, 0.1, alpha, state, bad_state) ==
          PIHYST_CREEP_ENONFINITE);
    CHECK(pihyst_creep_status_text(PIHYST_CREEP_EGAIN)[0] != '\0');
}

void run_creep_tests(void)
{
    test_step_response();
    test_target_exact();
    test_compensator();
    test_validation();
}
#endif /* PIHYST_TEST_F32 */
