/* Tests of pihyst_bw_creep_*: the Bouc-Wen compensator with creep meets the desired
 * outputs of a random staircase-and-ramp walk exactly (the model with creep replayed on
 * its voltages gives them back, fixed interval and per-sample intervals), the lag state
 * follows the output reached when the target is out of reach, and no input (NaN,
 * infinities, 1e300) moves a voltage outside the limits or beyond the slew bound.
 * Double precision only, like the lags. */
#include "test_util.h"

#ifndef PIHYST_TEST_F32 /* the creep lags are double precision only */
#include "pihyst_bw_creep.h"

#define N_BWC 3000

static unsigned bwc_lcg = 999u;
static double bwc_uniform(void) /* [0, 1) */
{
    bwc_lcg = bwc_lcg * 1103515245u + 12345u;
    return (double)(bwc_lcg >> 8) / (double)(1u << 24);
}

static const double bwc_tau[4] = {0.2, 2.0, 20.0, 200.0};
static const double bwc_gain[4] = {0.01, 0.015, 0.02, 0.025};

/* a remanent monotone model (a < 0), at rest at 0 V after a full cycle, with its lags
 * settled at its output there */
static void bwc_setup(pihyst_bw_model *m, pihyst_creep *cr, double dt, double *alpha,
                      double *z)
{
    pihyst_bw_params p = {5.0, 1.0, 1.3, -6.0, 40.0, 2.0, 0.5, 0.0, 150.0, 0.0, 0.0};
    CHECK(pihyst_bw_init(m, &p) == PIHYST_OK);
    CHECK(pihyst_bw_reset(m, 0.0, pihyst_bw_rest_z(m)) == PIHYST_OK);
    CHECK(pihyst_creep_init(cr, 4, bwc_tau, bwc_gain, dt, alpha, z, NULL) ==
          PIHYST_CREEP_OK);
    pihyst_creep_settle(cr, pihyst_bw_output(m, m->u, m->z));
}

static void test_round_trip(int per_sample)
{
    static double u[N_BWC], dt[N_BWC], yd[N_BWC], uc[N_BWC], yc[N_BWC], yr[N_BWC];
    static pihyst_flags flags[N_BWC];
    double alpha[4], z[4], z_comp[4], err = 0.0, v = 0.0, target = 100.0;
    pihyst_bw_model m;
    pihyst_creep cr;
    pihyst_bw_compensator c;
    int t, i;
    /* desired values: the model's own output for a walk of voltages (reachable) */
    bwc_setup(&m, &cr, 0.01, alpha, z);
    for (t = 0; t < N_BWC; ++t) {
        if (bwc_uniform() < 0.01) target = 150.0 * bwc_uniform();
        if (bwc_uniform() < 0.5) /* holds: half the samples do not move */
            v = v < target ? fmin(v + 3.0 * bwc_uniform(), target)
                           : fmax(v - 3.0 * bwc_uniform(), target);
        u[t] = v;
        dt[t] = 0.005 + 0.02 * bwc_uniform();
    }
    pihyst_bw_creep_run(&cr, &m, u, per_sample ? dt : NULL, yd, N_BWC);
    /* compensate them from the same start */
    bwc_setup(&m, &cr, 0.01, alpha, z);
    CHECK(pihyst_bw_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0) == PIHYST_OK);
    CHECK(pihyst_bw_creep_compensator_run(&cr, &c, yd, per_sample ? dt : NULL, uc, yc, flags,
                                          N_BWC) == 0);
    for (i = 0; i < 4; ++i) z_comp[i] = z[i];
    for (t = 0; t < N_BWC; ++t)
        if (fabs(yc[t] - yd[t]) > err) err = fabs(yc[t] - yd[t]);
    CHECK(err < 1e-9);
    /* the model with creep replayed on the compensator's voltages gives the same outputs
     * and ends in the same lag state */
    bwc_setup(&m, &cr, 0.01, alpha, z);
    pihyst_bw_creep_run(&cr, &m, uc, per_sample ? dt : NULL, yr, N_BWC);
    err = 0.0;
    for (t = 0; t < N_BWC; ++t)
        if (fabs(yr[t] - yd[t]) > err) err = fabs(yr[t] - yd[t]);
    CHECK(err < 1e-9);
    for (i = 0; i < 4; ++i) CHECK_NEAR(z[i], z_comp[i], 1e-9);
}

static void test_out_of_reach(void)
{
    /* 1000 um is out of reach: the voltage stops at the limit, flagged, and the lags
     * advance by the output at the limit, as a model run on those voltages does */
    double alpha[4], z[4], z_comp[4], y, yr = 0.0;
    pihyst_bw_model m;
    pihyst_creep cr;
    pihyst_bw_compensator c;
    pihyst_flags fl;
    int t, i;
    bwc_setup(&m, &cr, 0.01, alpha, z);
    CHECK(pihyst_bw_compensator_init(&c, &m, 0.0, 120.0, INFINITY, 0.0) == PIHYST_OK);
    for (t = 0; t < 50; ++t) {
        const double u = pihyst_bw_creep_compensator_step(&cr, &c, -1.0, 1000.0, &y, &fl);
        CHECK(u == 120.0);
        CHECK(fl == PIHYST_COMP_SAT_HIGH);
    }
    for (i = 0; i < 4; ++i) z_comp[i] = z[i];
    bwc_setup(&m, &cr, 0.01, alpha, z);
    for (t = 0; t < 50; ++t) yr = pihyst_creep_step(&cr, pihyst_bw_step(&m, 120.0));
    CHECK_NEAR(y, yr, 1e-12);
    for (i = 0; i < 4; ++i) CHECK_NEAR(z[i], z_comp[i], 1e-12);
}

static void test_any_input(void)
{
    static const double wild[7] = {NAN, INFINITY, -INFINITY, 1e300, -1e300, 20.0, 1e-300};
    double alpha[4], z[4], y, last = 0.0;
    pihyst_bw_model m;
    pihyst_creep cr;
    pihyst_bw_compensator c;
    int t, bad = 0;
    bwc_setup(&m, &cr, 0.01, alpha, z);
    CHECK(pihyst_bw_compensator_init(&c, &m, 10.0, 140.0, 7.5, 10.0) == PIHYST_OK);
    last = 10.0;
    for (t = 0; t < 700; ++t) {
        pihyst_flags fl;
        const double u = pihyst_bw_creep_compensator_step(&cr, &c, 0.01 * (t % 3) - 0.005,
                                                          wild[t % 7], &y, &fl);
        if (!(u >= 10.0 && u <= 140.0) || fabs(u - last) > 7.5 || !isfinite(y)) bad = 1;
        if (t % 7 == 0 && !(fl & PIHYST_COMP_NAN)) bad = 1;
        if (t % 7 == 0 && u != last) bad = 1;
        last = u;
    }
    CHECK(!bad);
}

void run_bw_creep_tests(void)
{
    test_round_trip(0);
    test_round_trip(1);
    test_out_of_reach();
    test_any_input();
}
#endif /* PIHYST_TEST_F32 */
