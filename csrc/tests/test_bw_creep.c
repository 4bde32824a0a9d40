/* Tests of pihyst_bw_creep_*: the Bouc-Wen compensator with creep meets the desired
 * outputs of a random staircase-and-ramp walk exactly (the model with creep replayed on
 * its voltages gives them back, fixed interval and per-sample intervals), the lag state
 * follows the output reached when the target is out of reach, and no input (NaN,
 * infinities, 1e300) moves a voltage outside the limits or beyond the slew bound.
 * Built in both precisions (the _f32 build on the _f32 lags, pihyst_bw_creep_f32.c); the
 * single-precision build also compares with the double functions. */
#include "test_util.h"

#include "pihyst_bw_creep.h"

#ifdef PIHYST_TEST_F32
#define BWC(name) name##_f32
#define BWC_EPS ((double)FLT_EPSILON)
#else
#define BWC(name) name
#define BWC_EPS DBL_EPSILON
#endif
typedef BWC(pihyst_bw_model) bwc_model;
typedef BWC(pihyst_bw_params) bwc_params;
typedef BWC(pihyst_bw_compensator) bwc_comp;
typedef BWC(pihyst_creep) bwc_creep;

#define N_BWC 3000

static unsigned bwc_lcg = 999u;
static double bwc_uniform(void) /* [0, 1) */
{
    bwc_lcg = bwc_lcg * 1103515245u + 12345u;
    return (double)(bwc_lcg >> 8) / (double)(1u << 24);
}

static const real bwc_tau[4] = {(real)0.2, (real)2.0, (real)20.0, (real)200.0};
static const real bwc_gain[4] = {(real)0.01, (real)0.015, (real)0.02, (real)0.025};
static const bwc_params bwc_p = {(real)5.0, (real)1.0, (real)1.3, (real)-6.0, (real)40.0,
                                 (real)2.0, (real)0.5, (real)0.0, (real)150.0, (real)0.0,
                                 (real)0.0};

/* a remanent monotone model (a < 0), at rest at 0 V after a full cycle, with its lags
 * settled at its output there */
static void bwc_setup(bwc_model *m, bwc_creep *cr, real dt, real *alpha, real *z)
{
    CHECK(BWC(pihyst_bw_init)(m, &bwc_p) == PIHYST_OK);
    CHECK(BWC(pihyst_bw_reset)(m, (real)0.0, BWC(pihyst_bw_rest_z)(m)) == PIHYST_OK);
    CHECK(BWC(pihyst_creep_init)(cr, 4, bwc_tau, bwc_gain, dt, alpha, z, NULL) ==
          PIHYST_CREEP_OK);
    BWC(pihyst_creep_settle)(cr, BWC(pihyst_bw_output)(m, m->u, m->z));
}

/* a walk of voltages: staircase targets, ramps of up to 3 V per sample, half the samples
 * holding; intervals of 5-25 ms */
static void bwc_walk(real *u, real *dt, int n)
{
    double v = 0.0, target = 100.0;
    int t;
    for (t = 0; t < n; ++t) {
        if (bwc_uniform() < 0.01) target = 150.0 * bwc_uniform();
        if (bwc_uniform() < 0.5) /* holds: half the samples do not move */
            v = v < target ? fmin(v + 3.0 * bwc_uniform(), target)
                           : fmax(v - 3.0 * bwc_uniform(), target);
        u[t] = (real)v;
        dt[t] = (real)(0.005 + 0.02 * bwc_uniform());
    }
}

static void test_round_trip(int per_sample)
{
    static real u[N_BWC], dt[N_BWC], yd[N_BWC], uc[N_BWC], yc[N_BWC], yr[N_BWC];
    static pihyst_flags flags[N_BWC];
    real alpha[4], z[4], z_comp[4];
    double err = 0.0, tol = 0.0;
    bwc_model m;
    bwc_creep cr;
    bwc_comp c;
    int t, i, same = 1;
    /* desired values: the model's own output for a walk of voltages (reachable) */
    bwc_setup(&m, &cr, (real)0.01, alpha, z);
    bwc_walk(u, dt, N_BWC);
    BWC(pihyst_bw_creep_run)(&cr, &m, u, per_sample ? dt : NULL, yd, N_BWC);
    /* compensate them from the same start */
    bwc_setup(&m, &cr, (real)0.01, alpha, z);
    CHECK(BWC(pihyst_bw_compensator_init)(&c, &m, (real)NAN, (real)NAN, (real)INFINITY,
                                          (real)0.0) == PIHYST_OK);
    CHECK(BWC(pihyst_bw_creep_compensator_run)(&cr, &c, yd, per_sample ? dt : NULL, uc, yc,
                                               flags, N_BWC) == 0);
    for (i = 0; i < 4; ++i) z_comp[i] = z[i];
    /* met to the compensator's tolerance, 4 eps (|y_d| + scale), carried through (C5)
     * and (C3) (a factor 1 / (1 - beta) < 1.1 and their own roundings): 16 eps */
    for (t = 0; t < N_BWC; ++t) {
        const double e = fabs((double)yc[t] - (double)yd[t]);
        const double bound = 16.0 * BWC_EPS * (fabs((double)yd[t]) + (double)c.scale);
        if (e > err) err = e;
        if (e > bound) tol = e / bound > tol ? e / bound : tol;
    }
    CHECK(tol == 0.0);
    CHECK(err < TOL(1e-9, 1e-3));
    /* the model with creep replayed on the compensator's voltages gives the same outputs,
     * bit for bit, and ends in the same lag state */
    bwc_setup(&m, &cr, (real)0.01, alpha, z);
    BWC(pihyst_bw_creep_run)(&cr, &m, uc, per_sample ? dt : NULL, yr, N_BWC);
    for (t = 0; t < N_BWC; ++t) same &= yr[t] == yc[t];
    CHECK(same);
    for (i = 0; i < 4; ++i) CHECK(z[i] == z_comp[i]);
}

static void test_out_of_reach(void)
{
    /* 1000 um is out of reach: the voltage stops at the limit, flagged, and the lags
     * advance by the output at the limit, as a model run on those voltages does */
    real alpha[4], z[4], z_comp[4], y = (real)0.0, yr = (real)0.0;
    bwc_model m;
    bwc_creep cr;
    bwc_comp c;
    pihyst_flags fl;
    int t, i;
    bwc_setup(&m, &cr, (real)0.01, alpha, z);
    CHECK(BWC(pihyst_bw_compensator_init)(&c, &m, (real)0.0, (real)120.0, (real)INFINITY,
                                          (real)0.0) == PIHYST_OK);
    for (t = 0; t < 50; ++t) {
        const real u = BWC(pihyst_bw_creep_compensator_step)(&cr, &c, (real)-1.0,
                                                             (real)1000.0, &y, &fl);
        CHECK(u == (real)120.0);
        CHECK(fl == PIHYST_COMP_SAT_HIGH);
    }
    for (i = 0; i < 4; ++i) z_comp[i] = z[i];
    bwc_setup(&m, &cr, (real)0.01, alpha, z);
    for (t = 0; t < 50; ++t)
        yr = BWC(pihyst_creep_step)(&cr, BWC(pihyst_bw_step)(&m, (real)120.0));
    CHECK(y == yr);
    for (i = 0; i < 4; ++i) CHECK(z[i] == z_comp[i]);
}

static void test_any_input(void)
{
    static const double wild[7] = {NAN, INFINITY, -INFINITY, 1e300, -1e300, 20.0, 1e-300};
    real alpha[4], z[4], y, last;
    bwc_model m;
    bwc_creep cr;
    bwc_comp c;
    int t, bad = 0;
    bwc_setup(&m, &cr, (real)0.01, alpha, z);
    CHECK(BWC(pihyst_bw_compensator_init)(&c, &m, (real)10.0, (real)140.0, (real)7.5,
                                          (real)10.0) == PIHYST_OK);
    last = (real)10.0;
    for (t = 0; t < 700; ++t) {
        pihyst_flags fl;
        const real u = BWC(pihyst_bw_creep_compensator_step)(
            &cr, &c, (real)(0.01 * (t % 3) - 0.005), (real)wild[t % 7], &y, &fl);
        if (!(u >= (real)10.0 && u <= (real)140.0) || fabs((double)(u - last)) > 7.5 ||
            !isfinite(y))
            bad = 1;
        if (t % 7 == 0 && !(fl & PIHYST_COMP_NAN)) bad = 1;
        if (t % 7 == 0 && u != last) bad = 1;
        last = u;
    }
    CHECK(!bad);
}

#ifdef PIHYST_TEST_F32
/* the single-precision compensator with creep follows the double one on the same floats:
 * the outputs with creep to 1e-5 of the output range (the _f32 model's tolerance against
 * double, docs/c-core.md), the voltages to 1e-3 V (that of the compensator without creep) */
static void test_bw_creep_twin(void)
{
    static float u[N_BWC], dt[N_BWC], yd[N_BWC];
    static const double tau_d[4] = {0.2f, 2.0f, 20.0f, 200.0f};
    static const double gain_d[4] = {0.01f, 0.015f, 0.02f, 0.025f};
    const pihyst_bw_params pd = {5.0, 1.0, 1.3f, -6.0, 40.0, 2.0, 0.5, 0.0, 150.0, 0.0, 0.0};
    double alpha_d[4], z_d[4], worst_y = 0.0, worst_u = 0.0, y_lo = INFINITY, y_hi = -INFINITY;
    float alpha_f[4], z_f[4];
    pihyst_bw_model md;
    pihyst_creep crd;
    pihyst_bw_compensator cd;
    pihyst_bw_model_f32 mf;
    pihyst_creep_f32 crf;
    pihyst_bw_compensator_f32 cf;
    int t;
    bwc_setup(&mf, &crf, 0.01f, alpha_f, z_f);
    bwc_walk(u, dt, N_BWC);
    pihyst_bw_creep_run_f32(&crf, &mf, u, NULL, yd, N_BWC);
    for (t = 0; t < N_BWC; ++t) {
        y_lo = fmin(y_lo, (double)yd[t]);
        y_hi = fmax(y_hi, (double)yd[t]);
    }
    /* the same walk forward in both precisions */
    CHECK(pihyst_bw_init(&md, &pd) == PIHYST_OK);
    CHECK(pihyst_bw_reset(&md, 0.0, pihyst_bw_rest_z(&md)) == PIHYST_OK);
    CHECK(pihyst_creep_init(&crd, 4, tau_d, gain_d, 0.01f, alpha_d, z_d, NULL) ==
          PIHYST_CREEP_OK);
    pihyst_creep_settle(&crd, pihyst_bw_output(&md, md.u, md.z));
    bwc_setup(&mf, &crf, 0.01f, alpha_f, z_f);
    for (t = 0; t < N_BWC; ++t) {
        const double e = fabs(pihyst_creep_step_dt(&crd, (double)dt[t],
                                                   pihyst_bw_step(&md, (double)u[t])) -
                              (double)pihyst_creep_step_dt_f32(&crf, dt[t],
                                                               pihyst_bw_step_f32(&mf, u[t])));
        if (e > worst_y) worst_y = e;
    }
    CHECK(worst_y <= 1e-5 * (y_hi - y_lo));
    /* the compensator on the float desired values, per-sample intervals */
    CHECK(pihyst_bw_reset(&md, 0.0, pihyst_bw_rest_z(&md)) == PIHYST_OK);
    pihyst_creep_settle(&crd, pihyst_bw_output(&md, md.u, md.z));
    bwc_setup(&mf, &crf, 0.01f, alpha_f, z_f);
    CHECK(pihyst_bw_compensator_init(&cd, &md, NAN, NAN, INFINITY, 0.0) == PIHYST_OK);
    CHECK(pihyst_bw_compensator_init_f32(&cf, &mf, NAN, NAN, INFINITY, 0.0f) == PIHYST_OK);
    pihyst_creep_settle(&crd, cd.y_last);
    pihyst_creep_settle_f32(&crf, cf.y_last);
    for (t = 0; t < N_BWC; ++t) {
        double yd_d, e;
        float yd_f;
        const double ud = pihyst_bw_creep_compensator_step(&crd, &cd, (double)dt[t],
                                                           (double)yd[t], &yd_d, NULL);
        const float uf = pihyst_bw_creep_compensator_step_f32(&crf, &cf, dt[t], yd[t], &yd_f,
                                                              NULL);
        e = fabs(ud - (double)uf);
        if (e > worst_u) worst_u = e;
        e = fabs(yd_d - (double)yd_f);
        if (e > worst_y) worst_y = e;
    }
    CHECK(worst_u <= 1e-3);
    CHECK(worst_y <= 1e-5 * (y_hi - y_lo));
}
#endif

void run_bw_creep_tests(void)
{
    test_round_trip(0);
    test_round_trip(1);
    test_out_of_reach();
    test_any_input();
#ifdef PIHYST_TEST_F32
    test_bw_creep_twin();
#endif
}
