/* Tests of the dedicated kernels: saturated-ramp polylines (the KP kernels) give the
 * values of the generic polyline path, found by adding a point on a flat part of every
 * polyline (which keeps the function and sends the model down the generic path); the
 * compensator inverts a ramp model exactly; small-K classical and multislope kernels
 * give step == run for every K <= 16 (blocks of any length). */
#include "pihyst.h"
#include "test_util.h"

#include <string.h>

#define KR 24
#define NR 3000

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
    test_small_kernels_step_equals_run();
}
