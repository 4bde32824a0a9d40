/* Tests of pihyst_bw_*: the model against the closed-form solution of the ODE for n = 1
 * (rising, falling, and across the kink at z = 0), step == run, validation; the
 * compensator's exact round trip on a random walk of desired outputs, its limits under
 * any input (NaN, infinities, 1e300), the slew bound, monotone and non-monotone models.
 * Built in both precisions; the single-precision build also compares with the double
 * API. */
#include "test_util.h"

#include "pihyst_boucwen.h"

#include <string.h>

#ifdef PIHYST_TEST_F32
#define BW(name) name##_f32
#else
#define BW(name) name
#endif
typedef BW(pihyst_bw_model) bw_model;
typedef BW(pihyst_bw_params) bw_params;
typedef BW(pihyst_bw_compensator) bw_comp;

#define N_BW 4000

static unsigned bw_lcg = 4242u;
static double bw_uniform(void) /* [0, 1) */
{
    bw_lcg = bw_lcg * 1103515245u + 12345u;
    return (double)(bw_lcg >> 8) / (double)(1u << 24);
}

static bw_params params_of(double beta, double gamma, double n, double a, double c1, double c2)
{
    bw_params p = {(real)beta, (real)gamma, (real)n, (real)a, (real)c1, (real)c2, (real)0.5,
                   (real)0.0, (real)150.0, (real)0.0, (real)0.0};
    return p;
}

static void test_closed_form(void)
{
    /* n = 1, beta = 5, gamma = 1. Rising with z > 0: dz/dx = 1 - 6 z, so from z = 0
     * z(dx) = (1 - exp(-6 dx)) / 6. */
    const bw_params p = params_of(5.0, 1.0, 1.0, -8.0, 40.0, 0.0);
    bw_model m;
    const double tol = TOL(1e-9, 2e-6);
    double z0, c, d, d1, ref;
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_OK);
    CHECK_NEAR(BW(pihyst_bw_advance)(&m, (real)0.0, (real)0.3), (1.0 - exp(-1.8)) / 6.0, tol);
    CHECK_NEAR(m.z_max, 1.0 / 6.0, TOL(1e-15, 1e-7));
    /* falling from z0 = 0.1 by 0.5: first dz/dx = 1 + 4 z (z > 0) down to z = 0 at
     * d1 = -ln(1 + 4 z0) / 4, then dz/dx = 1 + 6 z (z < 0): z = (exp(6 (dx - d1)) - 1) / 6 */
    z0 = 0.1;
    c = 4.0;
    d = 6.0;
    d1 = -log(1.0 + c * z0) / c;
    ref = (exp(d * (-0.5 - d1)) - 1.0) / d;
    CHECK_NEAR(BW(pihyst_bw_advance)(&m, (real)z0, (real)-0.5), ref, tol);
    /* dx = 0 and NaN leave z alone; the state stays within z_max on a long walk */
    CHECK(BW(pihyst_bw_advance)(&m, (real)0.05, (real)0.0) == (real)0.05);
    CHECK(BW(pihyst_bw_advance)(&m, (real)0.05, (real)NAN) == (real)0.05);
}

static void test_step_run_and_state(void)
{
    const bw_params p = params_of(3.0, -1.5, 2.0, 6.0, 20.0, 4.0);
    bw_model a, b;
    static real u[N_BW], y[N_BW];
    int t, bounded = 1, same = 1;
    CHECK(BW(pihyst_bw_init)(&a, &p) == PIHYST_OK);
    b = a;
    for (t = 0; t < N_BW; ++t) u[t] = (real)(150.0 * bw_uniform());
    BW(pihyst_bw_run)(&a, u, y, N_BW);
    for (t = 0; t < N_BW; ++t) {
        same &= BW(pihyst_bw_step)(&b, u[t]) == y[t];
        bounded &= fabs((double)b.z) <= (double)b.z_max * (1.0 + TOL(1e-9, 1e-5));
    }
    CHECK(same);
    CHECK(bounded);
    CHECK(a.u == b.u && a.z == b.z);
    /* out of range inputs are clamped, NaN holds */
    CHECK(BW(pihyst_bw_step)(&b, (real)1e30) == BW(pihyst_bw_step)(&a, (real)150.0));
    CHECK(BW(pihyst_bw_step)(&b, (real)NAN) == BW(pihyst_bw_output)(&b, b.u, b.z));
    CHECK(b.u == (real)150.0);
    /* the rest state: a 0 -> 1 -> 0 cycle from z = 0 ends at z != 0 for n = 2 */
    CHECK(BW(pihyst_bw_rest_z)(&a) != (real)0.0);
}

static void test_validation(void)
{
    bw_model m;
    bw_params p = params_of(5.0, 1.0, 1.0, -8.0, 40.0, 0.0);
    CHECK(BW(pihyst_bw_init)(NULL, &p) == PIHYST_ENULL);
    p.gamma = (real)5.0;
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_ESHAPE);   /* beta > |gamma| */
    p = params_of(5.0, 1.0, 0.5, -8.0, 40.0, 0.0);
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_ESHAPE);   /* n >= 1 */
    p = params_of(900.0, 200.0, 1.0, -8.0, 40.0, 0.0);
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_ESHAPE);   /* beta + |gamma| <= 1000 */
    p = params_of(1e-12, 0.0, 4.0, -8.0, 40.0, 0.0);
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_ESHAPE);   /* beta + gamma >= 1e-9 */
    p = params_of(5.0, 1.0, 1.0, (double)NAN, 40.0, 0.0);
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_ENONFINITE);
    p = params_of(5.0, 1.0, 1.0, -8.0, 40.0, 0.0);
    p.u_max = (real)0.0;
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_ERANGE);
    p = params_of(5.0, 1.0, 1.0, -8.0, 40.0, 0.0);
    p.initial_z = (real)0.2;                               /* beyond z_max = 1/6 */
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_ERANGE);
    p.initial_z = (real)0.0;
    p.initial_u = (real)151.0;
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_ERANGE);
    p.initial_u = (real)10.0;
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_OK);
    CHECK(BW(pihyst_bw_reset)(&m, (real)200.0, (real)0.0) == PIHYST_ERANGE);
    CHECK(BW(pihyst_bw_reset)(&m, (real)20.0, (real)INFINITY) == PIHYST_ENONFINITE);
    CHECK(m.u == (real)10.0);
    /* the texts in Bouc-Wen terms */
    CHECK(strstr(pihyst_bw_status_text(PIHYST_ESHAPE), "beta > |gamma|") != NULL);
    CHECK(strstr(pihyst_bw_status_text(PIHYST_ENEGATIVE_WEIGHT), "monotone") != NULL);
    CHECK(pihyst_bw_status_text(PIHYST_ENULL) == pihyst_status_text(PIHYST_ENULL));
}

/* the compensator of one model on a random walk of desired outputs inside the model's
 * reach, then on hostile input: exact round trip, limits and slew never violated */
static void check_compensator(double beta, double gamma, double n, double a, double c1,
                              double c2)
{
    const bw_params p = params_of(beta, gamma, n, a, c1, c2);
    bw_model m, twin;
    bw_comp c;
    static real yd[N_BW], u[N_BW], y[N_BW];
    static pihyst_flags fl[N_BW];
    const double lo = 0.5 + 0.2 * (c1 + c2), hi = 0.5 + 0.8 * (c1 + c2);
    double worst = 0.0, prev = 30.0;
    int t, in_limits = 1, in_slew = 1, exact_flags = 1, model_agrees = 1;
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_OK);
    CHECK(BW(pihyst_bw_compensator_init)(&c, &m, (real)NAN, (real)NAN, (real)INFINITY,
                                         (real)30.0) == PIHYST_OK);
    twin = m;
    for (t = 0; t < N_BW; ++t) {
        yd[t] = (real)(lo + (hi - lo) * bw_uniform());
        if (t % 7 == 3) yd[t] = yd[t - 1]; /* holds */
    }
    CHECK(BW(pihyst_bw_compensator_run)(&c, yd, u, y, fl, N_BW) == 0);
    for (t = 0; t < N_BW; ++t) {
        const double err = fabs((double)y[t] - (double)yd[t]);
        if (err > worst) worst = err;
        exact_flags &= fl[t] == 0;
        /* the voltages drive a copy of the model to the same outputs */
        model_agrees &= BW(pihyst_bw_step)(&twin, u[t]) == y[t];
    }
    CHECK(exact_flags);
    CHECK(model_agrees);
    CHECK(worst <= TOL(1e-10, 2e-4) * (hi - lo));
    /* hostile input with a slew limit and narrower voltage limits */
    CHECK(BW(pihyst_bw_compensator_reset)(&c, m.u_min, BW(pihyst_bw_rest_z)(&m), (real)30.0) ==
          PIHYST_OK);
    c.u_min = (real)10.0;
    c.u_max = (real)140.0;
    c.max_step = (real)7.5;
    for (t = 0; t < N_BW; ++t) {
        const double r = bw_uniform();
        real v = (real)(lo + (hi - lo) * bw_uniform());
        pihyst_flags f;
        double volts;
        if (r < 0.05) v = (real)NAN;
        else if (r < 0.1) v = (real)INFINITY;
        else if (r < 0.15) v = (real)-INFINITY;
        else if (r < 0.2) v = (real)1e30;
        else if (r < 0.25) v = (real)-1e30;
        volts = (double)BW(pihyst_bw_compensator_step)(&c, v, &f);
        in_limits &= volts >= 10.0 && volts <= 140.0;
        in_slew &= fabs(volts - prev) <= 7.5;
        if (r < 0.05) exact_flags &= f == PIHYST_COMP_NAN && volts == prev;
        else if (r < 0.1) exact_flags &= f == PIHYST_COMP_SAT_HIGH ||
                                          f == (PIHYST_COMP_SAT_HIGH | PIHYST_COMP_SLEW);
        else if (r < 0.15) exact_flags &= f == PIHYST_COMP_SAT_LOW ||
                                           f == (PIHYST_COMP_SAT_LOW | PIHYST_COMP_SLEW);
        else if (f == 0) exact_flags &= fabs((double)c.y_last - (double)v) <=
                                         TOL(1e-10, 2e-4) * (hi - lo);
        prev = volts;
    }
    CHECK(in_limits);
    CHECK(in_slew);
    CHECK(exact_flags);
}

static void test_compensator(void)
{
    check_compensator(5.0, 1.0, 1.0, -8.0, 40.0, 0.0);  /* remanent, min slope 26.7 */
    check_compensator(4.0, -2.0, 1.5, 5.0, 10.0, 3.0);  /* gamma < 0 */
    check_compensator(2.0, 0.5, 3.0, 4.0, 30.0, -10.0); /* concave reversible part */
}

/* slew-limited samples: SAT is set exactly when the model at the voltage limit, from the
 * state before the sample, misses y_d (the compensator decides most of them by bounds,
 * beyond_limit); targets anywhere around the output range and near its ends */
static void check_slew_flags(double beta, double gamma, double n, double a, double c1,
                             double c2)
{
    const bw_params p = params_of(beta, gamma, n, a, c1, c2);
    bw_model m, before;
    bw_comp c;
    double y_lo, y_hi;
    int t, wrong = 0, slewed = 0, saturated = 0;
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_OK);
    y_lo = (double)BW(pihyst_bw_output)(&m, (real)0.0, -m.z_max);
    y_hi = (double)BW(pihyst_bw_output)(&m, (real)150.0, m.z_max);
    CHECK(BW(pihyst_bw_compensator_init)(&c, &m, (real)10.0, (real)140.0, (real)2.5,
                                         (real)75.0) == PIHYST_OK);
    for (t = 0; t < N_BW / 4; ++t) {
        const double r = bw_uniform();
        /* a quarter of the targets within 1 % of the output range of an end */
        const double yd = t % 4 == 0 ? (r < 0.5 ? y_lo : y_hi) + 0.02 * (r - 0.25) * (y_hi - y_lo)
                                     : y_lo + (1.2 * r - 0.1) * (y_hi - y_lo);
        pihyst_flags fl;
        before = m;
        BW(pihyst_bw_compensator_step)(&c, (real)yd, &fl);
        if (fl & PIHYST_COMP_SLEW) {
            const real s = (real)yd > BW(pihyst_bw_output)(&before, before.u, before.z)
                               ? (real)1.0 : (real)-1.0;
            const real limit = s > (real)0.0 ? c.u_max : c.u_min;
            const real z = BW(pihyst_bw_advance)(&before, before.z,
                                                 (limit - before.u) / before.span);
            const int out = (BW(pihyst_bw_output)(&before, limit, z) - (real)yd) * s <
                            (real)0.0;
            const int sat = (fl & (PIHYST_COMP_SAT_HIGH | PIHYST_COMP_SAT_LOW)) != 0;
            wrong += out != sat;
            ++slewed;
            saturated += sat;
        }
    }
    CHECK(wrong == 0);
    CHECK(slewed > 100 && saturated > 10 && saturated < slewed);
}

static void test_slew_flags(void)
{
    check_slew_flags(5.0, 1.0, 1.0, -8.0, 40.0, 0.0);  /* remanent (a < 0) */
    check_slew_flags(4.0, -2.0, 1.5, 5.0, 10.0, 3.0);
    check_slew_flags(30.0, -10.0, 2.5, 2.0, 1.0, 0.0); /* min_slope = 1 */
}

static void test_compensator_refuses(void)
{
    bw_params p = params_of(5.0, 1.0, 1.0, -8.0, 10.0, 0.0);  /* 10 - 8 * 10/6 < 0 */
    bw_model m;
    bw_comp c;
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_OK);
    CHECK(BW(pihyst_bw_compensator_init)(&c, &m, (real)NAN, (real)NAN, (real)INFINITY,
                                         (real)0.0) == PIHYST_ENEGATIVE_WEIGHT);
    p = params_of(5.0, 1.0, 1.0, -8.0, 40.0, 0.0);
    CHECK(BW(pihyst_bw_init)(&m, &p) == PIHYST_OK);
    CHECK(BW(pihyst_bw_compensator_init)(NULL, &m, (real)NAN, (real)NAN, (real)INFINITY,
                                         (real)0.0) == PIHYST_ENULL);
    CHECK(BW(pihyst_bw_compensator_init)(&c, &m, (real)-1.0, (real)NAN, (real)INFINITY,
                                         (real)0.0) == PIHYST_ELIMITS);
    CHECK(BW(pihyst_bw_compensator_init)(&c, &m, (real)NAN, (real)NAN, (real)0.0,
                                         (real)0.0) == PIHYST_ELIMITS);
    CHECK(BW(pihyst_bw_compensator_init)(&c, &m, (real)NAN, (real)NAN, (real)INFINITY,
                                         (real)NAN) == PIHYST_ENONFINITE);
    CHECK(BW(pihyst_bw_compensator_init)(&c, &m, (real)20.0, (real)100.0, (real)INFINITY,
                                         (real)10.0) == PIHYST_ELIMITS);
    CHECK(BW(pihyst_bw_compensator_init)(&c, &m, (real)20.0, (real)100.0, (real)INFINITY,
                                         (real)20.0) == PIHYST_OK);
    CHECK(BW(pihyst_bw_compensator_reset)(&c, (real)0.0, (real)0.0, (real)150.0) ==
          PIHYST_ELIMITS);
    CHECK(m.u == (real)20.0);
}

#ifdef PIHYST_TEST_F32
/* the single-precision model and compensator follow the double ones */
static void test_twin_precisions(void)
{
    const pihyst_bw_params pd = {4.0, -2.0, 1.5, 5.0, 10.0, 3.0, 0.5, 0.0, 150.0, 0.0, 0.0};
    const pihyst_bw_params_f32 pf = {4.0f, -2.0f, 1.5f, 5.0f, 10.0f, 3.0f, 0.5f, 0.0f, 150.0f,
                                     0.0f, 0.0f};
    pihyst_bw_model md;
    pihyst_bw_model_f32 mf;
    pihyst_bw_compensator cd;
    pihyst_bw_compensator_f32 cf;
    double worst = 0.0, worst_u = 0.0;
    int t;
    CHECK(pihyst_bw_init(&md, &pd) == PIHYST_OK);
    CHECK(pihyst_bw_init_f32(&mf, &pf) == PIHYST_OK);
    for (t = 0; t < N_BW; ++t) {
        const float u = (float)(150.0 * bw_uniform());
        const double e = fabs(pihyst_bw_step(&md, (double)u) - (double)pihyst_bw_step_f32(&mf, u));
        if (e > worst) worst = e;
    }
    CHECK(worst <= 1e-5 * 18.5); /* of the output range */
    CHECK(pihyst_bw_compensator_init(&cd, &md, NAN, NAN, INFINITY, 30.0) == PIHYST_OK);
    CHECK(pihyst_bw_compensator_init_f32(&cf, &mf, NAN, NAN, INFINITY, 30.0f) == PIHYST_OK);
    for (t = 0; t < N_BW; ++t) {
        const float yd = (float)(4.0 + 11.0 * bw_uniform());
        const double e = fabs(pihyst_bw_compensator_step(&cd, (double)yd, NULL) -
                              (double)pihyst_bw_compensator_step_f32(&cf, yd, NULL));
        if (e > worst_u) worst_u = e;
    }
    CHECK(worst_u <= 1e-3); /* volts, of 150 */
}
#endif

void run_boucwen_tests(void)
{
    test_closed_form();
    test_step_run_and_state();
    test_validation();
    test_compensator();
    test_slew_flags();
    test_compensator_refuses();
#ifdef PIHYST_TEST_F32
    test_twin_precisions();
#endif
}
