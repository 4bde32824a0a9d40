/* Tests of the dedicated kernels: saturated-ramp polylines (the KP kernels) give the
 * values of the generic polyline path, found by adding a point on a flat part of every
 * polyline (which keeps the function and sends the model down the generic path); the
 * compensator inverts a ramp model exactly, and its ramp search (PIHYST_ORDER_RAMPS)
 * gives the generic event-list walk's voltages, outputs and flags on many random KP
 * models, limits, slew limits, signals and set states; small-K classical and multislope
 * kernels give step == run for every K <= 16 (blocks of any length). */
#include "pihyst.h"
#include "test_util.h"

#include <string.h>

#define LEN_OF(a) (sizeof(a) / sizeof *(a))
#ifdef PIHYST_TEST_F32
#define R_NEXT nextafterf
#else
#define R_NEXT nextafter
#endif

#define KR 24
#define NR 3000
#define KMAX 48
#define NS 400

static unsigned kern_lcg = 4242u;
static real kern_uniform(void)
{
    kern_lcg = kern_lcg * 1103515245u + 12345u;
    return (real)(kern_lcg >> 8) / (real)(1u << 24);
}

/* ramp: 0 (or lo) below c - w/2, rising to hi at c + w/2; as pihyst.identify builds them */
static void ramp(real *x, real *y, real c, real w, real lo, real hi)
{
    x[0] = c - 1.5 * w; x[1] = c - 0.5 * w; x[2] = c + 0.5 * w; x[3] = c + 1.5 * w;
    y[0] = lo; y[1] = lo; y[2] = hi; y[3] = hi;
}

static void test_ramps_equal_generic(void)
{
    static size_t rs4[KR + 1], rs5[KR + 1];
    static real rx4[4 * KR], ry4[4 * KR], fx4[4 * KR], fy4[4 * KR];
    static real rx5[5 * KR], ry5[5 * KR], fx5[5 * KR], fy5[5 * KR];
    static real u[NR], y4[NR], y5[NR], yd[NR], uc[NR], yc[NR];
    static real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(KR, 8 * KR)];
    real w[KR], coef4[PIHYST_COEF_LEN(KR)], coef5[PIHYST_COEF_LEN(KR)], s4[KR], s5[KR];
    const real width = 150.0 / 12.0;
    pihyst_pwl p4, p5;
    pihyst_model m4, m5;
    pihyst_compensator c;
    size_t k, i, t, bad = 0;
    real v = 0.0, err = 0.0;
    for (k = 0; k <= KR; ++k) {
        rs4[k] = 4 * k;
        rs5[k] = 5 * k;
    }
    for (k = 0; k < KR; ++k) {
        const real ci = 150.0 * kern_uniform(), cj = ci + 60.0 * kern_uniform();
        const real hi = k % 3 == 0 ? 1.0 : 0.5 + kern_uniform();
        ramp(rx4 + 4 * k, ry4 + 4 * k, cj, width, 0.0, hi);
        ramp(fx4 + 4 * k, fy4 + 4 * k, ci, width, 0.0, hi);
        w[k] = 0.02 + 0.1 * kern_uniform();
        /* the same polylines with a point inserted on the low flat part */
        for (i = 0; i < 5; ++i) {
            const size_t j = i == 0 ? 0 : i - 1;
            rx5[5 * k + i] = i == 1 ? rx4[4 * k] + 0.25 * width : rx4[4 * k + j];
            ry5[5 * k + i] = ry4[4 * k + j];
            fx5[5 * k + i] = i == 1 ? fx4[4 * k] + 0.25 * width : fx4[4 * k + j];
            fy5[5 * k + i] = fy4[4 * k + j];
        }
    }
    p4.rise_start = rs4; p4.rise_x = rx4; p4.rise_y = ry4;
    p4.fall_start = rs4; p4.fall_x = fx4; p4.fall_y = fy4;
    p5.rise_start = rs5; p5.rise_x = rx5; p5.rise_y = ry5;
    p5.fall_start = rs5; p5.fall_x = fx5; p5.fall_y = fy5;
    CHECK(model_init(&m4, PIHYST_PWL, KR, NULL, w, 0.5, -30.0, 240.0, NULL, &p4, coef4, s4,
                     NULL) == PIHYST_OK);
    CHECK(model_init(&m5, PIHYST_PWL, KR, NULL, w, 0.5, -30.0, 240.0, NULL, &p5, coef5, s5,
                     NULL) == PIHYST_OK);
    CHECK(coef4[0] == 1.0 && coef5[0] == 0.0); /* ramps detected, 5 points not */
    for (t = 0; t < NR; ++t) { /* a walk with minor loops, and jumps now and then */
        v += (real)(8.0 * ((double)kern_uniform() - 0.5));
        if (kern_uniform() < 0.05) v = (real)(270.0 * (double)kern_uniform() - 30.0);
        v = v < -30.0 ? -30.0 : (v > 240.0 ? 240.0 : v);
        u[t] = v;
    }
    pihyst_model_run(&m4, u, y4, NR);
    pihyst_model_run(&m5, u, y5, NR);
    for (t = 0; t < NR; ++t) bad += y4[t] != y5[t];
    for (k = 0; k < KR; ++k) bad += s4[k] != s5[k];
    CHECK(bad == 0);
    /* the compensator inverts the ramp model: its output meets a reachable target */
    pihyst_model_reset(&m4, NULL);
    for (t = 0; t < NR; ++t) u[t] = u[t] < 0.0 ? 0.0 : (u[t] > 150.0 ? 150.0 : u[t]);
    pihyst_model_run(&m4, u, yd, NR);
    pihyst_model_reset(&m4, NULL);
    CHECK(pihyst_compensator_init(&c, &m4, 0.0, 150.0, INFINITY, 0.0, scratch,
                                  sizeof scratch / sizeof *scratch) == PIHYST_OK);
    pihyst_compensator_run(&c, yd, uc, yc, NULL, NR);
    for (t = 0; t < NR; ++t) {
        if (fabs(yc[t] - yd[t]) > err) err = fabs(yc[t] - yd[t]);
        if (!(uc[t] >= 0.0 && uc[t] <= 150.0)) ++bad;
    }
    CHECK(bad == 0);
    CHECK_NEAR(err, 0.0, TOL(1e-11, 2e-4));
}

/* A random KP model of K ramps (F's switching voltage <= R's, equal heights): on a grid
 * of `grid` voltages (coincident breakpoints, as pihyst.identify builds them) or anywhere
 * (grid 0), ramps of mixed widths, some flat (height 0), some weights 0. */
static void random_kp(size_t K, unsigned grid, size_t *starts, real *rx, real *ry, real *fx,
                      real *fy, real *w)
{
    size_t k;
    for (k = 0; k <= K; ++k) starts[k] = 4 * k;
    for (k = 0; k < K; ++k) {
        const real width = grid ? (real)150.0 / (real)grid
                                : (kern_uniform() < (real)0.3 ? (real)0.5 : (real)12.0);
        real a = (real)(170.0 * (double)kern_uniform() - 20.0);
        real b = (real)(170.0 * (double)kern_uniform() - 20.0);
        const real lo = kern_uniform() < (real)0.5 ? (real)0.0 : (real)-0.5;
        const real hi = k % 7 == 3 ? lo : lo + (real)0.1 + (real)2.0 * kern_uniform();
        if (grid) {
            a = (real)(150.0 / grid) * (real)(unsigned)(kern_uniform() * (real)(grid + 1));
            b = (real)(150.0 / grid) * (real)(unsigned)(kern_uniform() * (real)(grid + 1));
        }
        if (a > b) {
            const real t = a;
            a = b;
            b = t;
        }
        ramp(rx + 4 * k, ry + 4 * k, b, width, lo, hi);
        ramp(fx + 4 * k, fy + 4 * k, a, width, lo, hi);
        w[k] = kern_uniform() < (real)0.15 ? (real)0.0 : kern_uniform();
    }
}

/* The steepest slope of a model of K 4-point polylines: sum_k |w_k| max |dy/dx| (a bound on
 * |y(u1) - y(u2)| / |u1 - u2| from one state) */
static real kp_slope_bound(size_t K, const real *rx, const real *ry, const real *fx,
                           const real *fy, const real *w)
{
    size_t k, i;
    real L = 0.0;
    for (k = 0; k < K; ++k) {
        real s = 0.0;
        for (i = 4 * k; i + 1 < 4 * k + 4; ++i) {
            const real sr = (real)fabs((ry[i + 1] - ry[i]) / (rx[i + 1] - rx[i]));
            const real sf = (real)fabs((fy[i + 1] - fy[i]) / (fx[i + 1] - fx[i]));
            s = sr > s ? sr : s;
            s = sf > s ? sf : s;
        }
        L += (real)fabs(w[k]) * s;
    }
    return L;
}

/* The ramp search against the generic walk on the same model (the compensator told not
 * to use it: PIHYST_ORDER_RAMPS cleared after init). Same flags; outputs and voltages
 * equal to rounding, except that on a flat stretch at the level y_d (to rounding) either
 * end is an exact answer: there both outputs meet y_d. Then the limits.
 * A sample cut short by the slew limit moves the voltage by max_step from the previous
 * one, so it inherits the previous sample's voltage difference (allowed there when both
 * met y_d): its voltages must differ by no more than that (the step adds none), its
 * outputs by no more than the model's slope bound times the voltage difference. (With
 * FMA in one path and not in the other, -O2 on x86-64, a walk's sample met at voltages
 * 7e-5 V apart on a 3.6 um/V slope, then a 40 V slew step gave outputs 2.5e-4 apart.) */
static void test_ramp_search_equals_generic(void)
{
    static size_t st[KMAX + 1];
    static real rx[4 * KMAX], ry[4 * KMAX], fx[4 * KMAX], fy[4 * KMAX];
    static real yd[NS], ua[NS], ya[NS], ub[NS], yb[NS], state0[KMAX];
    static real sa[PIHYST_COMPENSATOR_SCRATCH_LEN(KMAX, 8 * KMAX)];
    static real sb[PIHYST_COMPENSATOR_SCRATCH_LEN(KMAX, 8 * KMAX)];
    static pihyst_flags fa[NS], fb[NS];
    static const real limits[4][3] = {
        {0.0, 150.0, INFINITY}, {10.0, 140.0, 15.0}, {0.0, 150.0, 0.7}, {-20.0, 160.0, 40.0}};
    real w[KMAX], coef_a[PIHYST_COEF_LEN(KMAX)], coef_b[PIHYST_COEF_LEN(KMAX)];
    real st_a[KMAX], st_b[KMAX];
    const real du_tol = TOL(1e-9, 2e-3), dy_tol = TOL(1e-9, 2e-4);
    pihyst_pwl p;
    pihyst_model ma, mb;
    pihyst_compensator ca, cb;
    size_t K, k, t, bad_flags = 0, bad_y = 0, bad_u = 0, bad_limits = 0, ramps_used = 0;
    unsigned trial;
    real slope;
    for (trial = 0; trial < 96; ++trial) {
        const real *lim = limits[trial % 4];
        const unsigned grid = trial % 3 == 0 ? 0u : (trial % 3 == 1 ? 15u : 6u);
        real y_lo = INFINITY, y_hi = -INFINITY;
        K = 1 + (size_t)(kern_uniform() * (real)KMAX);
        if (K > KMAX) K = KMAX;
        random_kp(K, grid, st, rx, ry, fx, fy, w);
        p.rise_start = st; p.rise_x = rx; p.rise_y = ry;
        p.fall_start = st; p.fall_x = fx; p.fall_y = fy;
        CHECK(model_init(&ma, PIHYST_PWL, K, NULL, w, 0.3, -20.0, 160.0, NULL, &p, coef_a,
                         st_a, NULL) == PIHYST_OK);
        CHECK(model_init(&mb, PIHYST_PWL, K, NULL, w, 0.3, -20.0, 160.0, NULL, &p, coef_b,
                         st_b, NULL) == PIHYST_OK);
        /* the output range, to draw desired values in and around it */
        for (t = 0; t < 64; ++t) {
            const real y = pihyst_model_step(&ma, (real)(180.0 * (double)t / 63.0 - 20.0));
            y_lo = y < y_lo ? y : y_lo;
            y_hi = y > y_hi ? y : y_hi;
        }
        for (t = 0; t < NS; ++t) {
            const real r = kern_uniform();
            if (trial % 2 == 0) /* a walk: tracking, minor loops */
                yd[t] = t == 0 ? y_lo : yd[t - 1] + (y_hi - y_lo) * (real)0.06 * (r - (real)0.5);
            else /* noise: a jump every sample */
                yd[t] = y_lo - (real)0.05 + (y_hi - y_lo + (real)0.1) * r;
            if (t % 37 == 5) yd[t] = NAN;
            if (t % 53 == 7) yd[t] = t % 2 ? INFINITY : -INFINITY;
            if (t % 61 == 11) yd[t] = (real)1e30;
        }
        /* a set state now and then (crossings anywhere on the ramps) */
        for (k = 0; k < K; ++k) state0[k] = (real)(3.0 * (double)kern_uniform() - 0.7);
        pihyst_model_reset(&ma, trial % 5 == 4 ? state0 : NULL);
        pihyst_model_reset(&mb, trial % 5 == 4 ? state0 : NULL);
        CHECK(pihyst_compensator_init(&ca, &ma, lim[0], lim[1], lim[2], lim[0], sa,
                                      LEN_OF(sa)) == PIHYST_OK);
        CHECK(pihyst_compensator_init(&cb, &mb, lim[0], lim[1], lim[2], lim[0], sb,
                                      LEN_OF(sb)) == PIHYST_OK);
        ramps_used += (ca.in_order & PIHYST_ORDER_RAMPS) != 0;
        cb.in_order &= ~(unsigned)(PIHYST_ORDER_RAMPS | PIHYST_ORDER_RAMPS_AVX2); /* generic */
        pihyst_compensator_run(&ca, yd, ua, ya, fa, NS);
        pihyst_compensator_run(&cb, yd, ub, yb, fb, NS);
        slope = kp_slope_bound(K, rx, ry, fx, fy, w);
        for (t = 0; t < NS; ++t) {
            const int met = fabs(ya[t] - yd[t]) <= ca.tol + dy_tol &&
                            fabs(yb[t] - yd[t]) <= cb.tol + dy_tol;
            const int slewed = t > 0 && (fa[t] & PIHYST_COMP_SLEW) && (fb[t] & PIHYST_COMP_SLEW);
            const real du_prev = t > 0 ? (real)fabs(ua[t - 1] - ub[t - 1]) : (real)0.0;
            const real du = (real)fabs(ua[t] - ub[t]);
            bad_flags += fa[t] != fb[t];
            bad_y += !(fabs(ya[t] - yb[t]) <= dy_tol + (slewed ? slope * du : (real)0.0));
            bad_u += slewed ? !(du <= du_prev + du_tol) : !(du <= du_tol) && !met;
            bad_limits += !(ua[t] >= lim[0] && ua[t] <= lim[1]) ||
                          !(fabs(ua[t] - (t ? ua[t - 1] : lim[0])) <= lim[2]);
        }
        /* the state the compensator leaves is the model's for its voltages */
        for (k = 0; k < K; ++k) bad_y += !(fabs(st_a[k] - st_b[k]) <= dy_tol);
    }
    CHECK(ramps_used == 96);
    CHECK(bad_flags == 0);
    CHECK(bad_y == 0);
    CHECK(bad_u == 0);
    CHECK(bad_limits == 0);
}

/* the ramp search's state is the model's own for its voltages, bit for bit, and its
 * outputs are the model's to half the equality band (the compensator steps only the
 * operators with a ramp where the voltage moves and keeps the output as a running sum);
 * predict(compensate(y_d)) == y_d on a reachable walk of a large KP model */
static void test_ramp_search_round_trip(void)
{
    static size_t st[KMAX + 1];
    static real rx[4 * KMAX], ry[4 * KMAX], fx[4 * KMAX], fy[4 * KMAX];
    static real u[NR], yd[NR], uc[NR], yc[NR], yp[NR];
    static real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(KMAX, 8 * KMAX)];
    real w[KMAX], coef[PIHYST_COEF_LEN(KMAX)], state[KMAX], state_c[KMAX], v = 0.0, err = 0.0;
    pihyst_pwl p;
    pihyst_model m;
    pihyst_compensator c;
    size_t t, bad = 0;
    random_kp(KMAX, 15u, st, rx, ry, fx, fy, w);
    p.rise_start = st; p.rise_x = rx; p.rise_y = ry;
    p.fall_start = st; p.fall_x = fx; p.fall_y = fy;
    CHECK(model_init(&m, PIHYST_PWL, KMAX, NULL, w, 0.0, 0.0, 150.0, NULL, &p, coef, state,
                     NULL) == PIHYST_OK);
    for (t = 0; t < NR; ++t) {
        v += (real)(6.0 * ((double)kern_uniform() - 0.5));
        if (kern_uniform() < 0.05) v = (real)(150.0 * (double)kern_uniform());
        v = v < 0.0 ? 0.0 : (v > 150.0 ? 150.0 : v);
        u[t] = v;
    }
    pihyst_model_run(&m, u, yd, NR);
    pihyst_model_reset(&m, NULL);
    CHECK(pihyst_compensator_init(&c, &m, 0.0, 150.0, INFINITY, 0.0, scratch, LEN_OF(scratch)) ==
          PIHYST_OK);
    CHECK((c.in_order & PIHYST_ORDER_RAMPS) != 0);
    pihyst_compensator_run(&c, yd, uc, yc, NULL, NR);
    for (t = 0; t < NR; ++t)
        if (fabs(yc[t] - yd[t]) > err) err = fabs(yc[t] - yd[t]);
    CHECK_NEAR(err, 0.0, TOL(1e-11, 4.0 * c.tol));
    memcpy(state_c, state, KMAX * sizeof *state);
    pihyst_model_reset(&m, NULL);
    pihyst_model_step(&m, 0.0);
    pihyst_model_run(&m, uc, yp, NR);
    for (t = 0; t < NR; ++t) bad += !(fabs(yp[t] - yc[t]) <= 0.5 * c.tol);
    CHECK(bad == 0);
    CHECK(memcmp(state_c, state, KMAX * sizeof *state) == 0);
}

/* The compensator's own model step on a ramp model (AVX2 where the CPU has it) gives the
 * model step's state and output bit for bit: reset(state, u) applies u, for random
 * states and voltages on the breakpoints, an ulp off them, and anywhere; ramps with
 * signed zeros (y0 = -0, y1 = +0). */
static void test_ramp_step_equals_model_step(void)
{
    static size_t st[KMAX + 1];
    static real rx[4 * KMAX], ry[4 * KMAX], fx[4 * KMAX], fy[4 * KMAX];
    static real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(KMAX, 8 * KMAX)];
    real w[KMAX], coef_a[PIHYST_COEF_LEN(KMAX)], coef_b[PIHYST_COEF_LEN(KMAX)];
    real st_a[KMAX], st_b[KMAX], state0[KMAX];
    pihyst_pwl p;
    pihyst_model ma, mb;
    pihyst_compensator c;
    size_t K, k, i, bad = 0;
    unsigned trial;
    for (trial = 0; trial < 40; ++trial) {
        K = 1 + (size_t)(kern_uniform() * (real)KMAX);
        if (K > KMAX) K = KMAX;
        random_kp(K, trial % 2 ? 15u : 0u, st, rx, ry, fx, fy, w);
        for (k = 0; k < K; k += 5) { /* -0 below, +0 on: the same polyline */
            if (ry[4 * k + 1] == (real)0.0) ry[4 * k] = (real)-0.0;
            if (fy[4 * k + 1] == (real)0.0) fy[4 * k] = (real)-0.0;
        }
        p.rise_start = st; p.rise_x = rx; p.rise_y = ry;
        p.fall_start = st; p.fall_x = fx; p.fall_y = fy;
        CHECK(model_init(&ma, PIHYST_PWL, K, NULL, w, 0.3, -20.0, 160.0, NULL, &p, coef_a,
                         st_a, NULL) == PIHYST_OK);
        CHECK(model_init(&mb, PIHYST_PWL, K, NULL, w, 0.3, -20.0, 160.0, NULL, &p, coef_b,
                         st_b, NULL) == PIHYST_OK);
        CHECK(pihyst_compensator_init(&c, &ma, NAN, NAN, INFINITY, 0.0, scratch,
                                      LEN_OF(scratch)) == PIHYST_OK);
        for (i = 0; i < 200; ++i) {
            const size_t j = (size_t)(kern_uniform() * (real)(4 * K)) % (4 * K);
            const real x = kern_uniform() < (real)0.5 ? rx[j] : fx[j];
            const real pick = kern_uniform();
            real u = pick < (real)0.3 ? x
                     : pick < (real)0.5 ? R_NEXT(x, (real)-INFINITY)
                     : pick < (real)0.7 ? R_NEXT(x, (real)INFINITY)
                                        : (real)(180.0 * (double)kern_uniform() - 20.0);
            real y;
            u = u < (real)-20.0 ? (real)-20.0 : (u > (real)160.0 ? (real)160.0 : u);
            for (k = 0; k < K; ++k) state0[k] = (real)(3.0 * (double)kern_uniform() - 0.7);
            CHECK(pihyst_compensator_reset(&c, state0, u) == PIHYST_OK);
            pihyst_model_reset(&mb, state0);
            y = pihyst_model_step(&mb, u);
            bad += memcmp(&y, &c.y_last, sizeof y) != 0;
            bad += memcmp(st_a, st_b, K * sizeof *st_a) != 0;
        }
    }
    CHECK(bad == 0);
}

/* The compensator's own model step on a ramp model, sample by sample, against the model
 * step on the same voltages: it visits only the operators with a ramp between the last
 * voltage and the new one, so its state must be the model step's bit for bit after every
 * sample, and its output (a running sum, taken exactly again now and then) within half the
 * equality band of the model step's; walks (tracking, reversals), jumps and slew-limited
 * runs, long enough that the running sum is taken again many times. */
static void test_ramp_sparse_step_equals_model_step(void)
{
    static size_t st[KMAX + 1];
    static real rx[4 * KMAX], ry[4 * KMAX], fx[4 * KMAX], fy[4 * KMAX];
    static real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(KMAX, 8 * KMAX)];
    real w[KMAX], coef_a[PIHYST_COEF_LEN(KMAX)], coef_b[PIHYST_COEF_LEN(KMAX)];
    real st_a[KMAX], st_b[KMAX], y_lo = INFINITY, y_hi = -INFINITY, yd = 0.0;
    pihyst_pwl p;
    pihyst_model ma, mb;
    pihyst_compensator c;
    size_t K, t, bad_state = 0, bad_y = 0;
    unsigned trial;
    for (trial = 0; trial < 24; ++trial) {
        const real step = trial % 3 == 2 ? (real)2.0 : (real)INFINITY;
        K = trial % 4 == 0 ? KMAX : 1 + (size_t)(kern_uniform() * (real)KMAX);
        if (K > KMAX) K = KMAX;
        random_kp(K, trial % 2 ? 15u : 0u, st, rx, ry, fx, fy, w);
        p.rise_start = st; p.rise_x = rx; p.rise_y = ry;
        p.fall_start = st; p.fall_x = fx; p.fall_y = fy;
        CHECK(model_init(&ma, PIHYST_PWL, K, NULL, w, 0.3, -20.0, 160.0, NULL, &p, coef_a,
                         st_a, NULL) == PIHYST_OK);
        CHECK(model_init(&mb, PIHYST_PWL, K, NULL, w, 0.3, -20.0, 160.0, NULL, &p, coef_b,
                         st_b, NULL) == PIHYST_OK);
        y_lo = INFINITY;
        y_hi = -INFINITY;
        for (t = 0; t < 64; ++t) {
            const real y = pihyst_model_step(&mb, (real)(180.0 * (double)t / 63.0 - 20.0));
            y_lo = y < y_lo ? y : y_lo;
            y_hi = y > y_hi ? y : y_hi;
        }
        pihyst_model_reset(&mb, NULL);
        pihyst_model_step(&mb, 0.0);
        CHECK(pihyst_compensator_init(&c, &ma, 0.0, 150.0, step, 0.0, scratch,
                                      LEN_OF(scratch)) == PIHYST_OK);
        CHECK((c.in_order & PIHYST_ORDER_RAMPS) != 0);
        yd = y_lo;
        for (t = 0; t < 3000; ++t) {
            const real r = kern_uniform();
            real y;
            if (trial % 2 == 0 && t % 500 > 50) /* a walk: tracking, minor loops */
                yd += (y_hi - y_lo) * (real)0.02 * (r - (real)0.5);
            else /* a jump */
                yd = y_lo + (y_hi - y_lo) * r;
            pihyst_compensator_step(&c, yd, NULL);
            y = pihyst_model_step(&mb, c.u_last);
            bad_state += memcmp(st_a, st_b, K * sizeof *st_a) != 0;
            bad_y += !(fabs(y - c.y_last) <= 0.5 * c.tol);
        }
    }
    CHECK(bad_state == 0);
    CHECK(bad_y == 0);
}

/* The sparse step's skips against ramps that rounding (or the envelope check's slack)
 * leaves out of order: n_slack operators whose rising ramp ends above their falling
 * envelope by delta, within the slack pihyst_model_init allows (R <= F + slack), so going
 * down across their rising ramp their state drops to F although their falling ramp does
 * not move; one operator whose ramps are the same ramp; one KP kernel; 12 kernels far
 * off (so that the step stays sparse). With 1 such operator the compensator visits it at
 * every step, with 10 (more than RAMP_ODD_FEW) through the other list. The compensator's
 * state must be the model step's bit for bit after every sample. */
static void out_of_order_case(size_t n_slack)
{
    enum { KX = 24 };
    static size_t st[KX + 1];
    static real rx[4 * KX], ry[4 * KX], fx[4 * KX], fy[4 * KX];
    static real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(KX, 8 * KX)];
    const real delta = TOL(1e-13, 1e-6);
    /* x1, x2, y0 (= y1), y2 of the rising and falling ramp of each kind of operator */
    static const real kinds[4][8] = {{10, 20, 0, 1, 80, 90, 1, 2},  /* R above F by delta */
                                     {50, 60, 0, 1, 50, 60, 0, 1},  /* the same ramp */
                                     {40, 50, 0, 2, 10, 20, 0, 2},  /* KP */
                                     {95, 97, 0, 1, 92, 94, 0, 1}}; /* far off */
    real w[KX], coef_a[PIHYST_COEF_LEN(KX)], coef_b[PIHYST_COEF_LEN(KX)];
    real coef_c[PIHYST_COEF_LEN(KX)], st_a[KX], st_b[KX], st_c[KX], u;
    const size_t K = n_slack + 14;
    pihyst_pwl p;
    pihyst_model ma, mb, mc;
    pihyst_compensator c;
    size_t t, k, bad = 0, dropped = 0;
    for (k = 0; k <= K; ++k) st[k] = 4 * k;
    for (k = 0; k < K; ++k) {
        const real *d = kinds[k < n_slack ? 0 : k == n_slack ? 1 : k == n_slack + 1 ? 2 : 3];
        const real top = k < n_slack ? d[3] + delta : d[3];
        rx[4 * k] = d[0] - 5; rx[4 * k + 1] = d[0]; rx[4 * k + 2] = d[1]; rx[4 * k + 3] = d[1] + 5;
        ry[4 * k] = ry[4 * k + 1] = d[2];
        ry[4 * k + 2] = ry[4 * k + 3] = top;
        fx[4 * k] = d[4] - 5; fx[4 * k + 1] = d[4]; fx[4 * k + 2] = d[5]; fx[4 * k + 3] = d[5] + 5;
        fy[4 * k] = fy[4 * k + 1] = d[6];
        fy[4 * k + 2] = fy[4 * k + 3] = d[7];
        w[k] = k < n_slack ? (real)1.0 / (real)(k + 1) : k < n_slack + 2 ? (real)0.5 : (real)0.01;
    }
    p.rise_start = st; p.rise_x = rx; p.rise_y = ry;
    p.fall_start = st; p.fall_x = fx; p.fall_y = fy;
    CHECK(model_init(&ma, PIHYST_PWL, K, NULL, w, 0.0, 0.0, 100.0, NULL, &p, coef_a, st_a,
                     NULL) == PIHYST_OK);
    CHECK(model_init(&mb, PIHYST_PWL, K, NULL, w, 0.0, 0.0, 100.0, NULL, &p, coef_b, st_b,
                     NULL) == PIHYST_OK);
    CHECK(model_init(&mc, PIHYST_PWL, K, NULL, w, 0.0, 0.0, 100.0, NULL, &p, coef_c, st_c,
                     NULL) == PIHYST_OK);
    CHECK(pihyst_compensator_init(&c, &ma, NAN, NAN, INFINITY, 0.0, scratch, LEN_OF(scratch)) ==
          PIHYST_OK);
    CHECK((c.in_order & PIHYST_ORDER_RAMPS) != 0);
    pihyst_model_step(&mb, 0.0);
    for (t = 0; t < 4000; ++t) {
        /* desired: the model's output for voltages that put the first operators at their
         * tops (60 V), then leave them there (25 V), then step down to 15-16 V, across
         * the rising ramps of the first n_slack and the KP kernel's falling ramp only,
         * then anywhere */
        const real before = st_a[0];
        u = t % 4 == 0   ? (real)60.0
            : t % 4 == 1 ? (real)25.0
            : t % 4 == 2 ? (real)(15.0 + (double)kern_uniform())
                         : (real)(100.0 * (double)kern_uniform());
        pihyst_compensator_step(&c, pihyst_model_step(&mc, u), NULL);
        pihyst_model_step(&mb, c.u_last);
        bad += memcmp(st_a, st_b, K * sizeof *st_a) != 0;
        dropped += st_a[0] < before && c.u_last < (real)20.0 && c.u_last > (real)10.0;
    }
    CHECK(bad == 0);
    CHECK(dropped > 0); /* the case happened */
}

static void test_ramp_sparse_step_out_of_order(void)
{
    out_of_order_case(1);
    out_of_order_case(10);
}

/* the small-K kernels: a block equals the same samples stepped one at a time, any K */
static void test_small_kernels_step_equals_run(void)
{
    static const pihyst_shape shape = {150.0, 0.8, 1.2, 0.5};
    real r[17], w[17], coef[PIHYST_COEF_LEN(17)], st[17], u[500], y_run[500], state_run[17];
    pihyst_model m;
    size_t K, t, fam, bad = 0;
    for (K = 0; K < 17; ++K) {
        r[K] = (real)(2.9 * (double)K);
        w[K] = (real)(0.01 + 0.01 * (double)(K % 4));
    }
    for (t = 0; t < 500; ++t) u[t] = (real)(150.0 * (double)kern_uniform());
    for (fam = 0; fam < 2; ++fam) {
        for (K = 1; K <= 17; ++K) {
            const pihyst_family family = fam ? PIHYST_MULTISLOPE : PIHYST_CLASSICAL;
            CHECK(model_init(&m, family, K, r, w, 0.1, 0.0, 150.0, &shape, NULL, coef, st,
                             NULL) == PIHYST_OK);
            pihyst_model_run(&m, u, y_run, 500);
            memcpy(state_run, st, K * sizeof *st);
            pihyst_model_reset(&m, NULL);
            for (t = 0; t < 500; ++t) bad += memcmp(&y_run[t], &(real){pihyst_model_step(&m, u[t])},
                                                    sizeof(real)) != 0;
            bad += memcmp(state_run, st, K * sizeof *st) != 0;
        }
    }
    CHECK(bad == 0);
}

void run_kernel_tests(void)
{
    test_ramps_equal_generic();
    test_ramp_search_equals_generic();
    test_ramp_search_round_trip();
    test_ramp_step_equals_model_step();
    test_ramp_sparse_step_equals_model_step();
    test_ramp_sparse_step_out_of_order();
    test_small_kernels_step_equals_run();
}
