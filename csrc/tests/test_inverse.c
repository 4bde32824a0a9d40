/* Tests of pihyst_compensator_*: exact round trip on reachable trajectories with minor
 * loops (classical, multislope, pwl) and on noise (a reversal nearly every sample:
 * crossings read in operator order, the multislope crossing and kink lists, their
 * sorted fallback for unusual shapes and unordered states), hold on flat stretches,
 * limits and slew limit under any input (NaN, infinities, 1e300), step == run,
 * chunked == whole, any alignment of the state array, validation. */
#include "pihyst.h"
#include "test_util.h"

#include <float.h>
#include <stdint.h>
#include <string.h>

#define N_WALK 4000
#define LEN(a) (sizeof(a) / sizeof *(a))

static const pihyst_shape paper_shape = {150.0, 0.8, 1.2, 0.5};

static unsigned lcg_state = 2024u;
static double uniform(void) /* [0, 1) */
{
    lcg_state = lcg_state * 1103515245u + 12345u;
    return (real)(lcg_state >> 8) / (real)(1u << 24);
}

/* A voltage walk in [lo, hi] with many reversals of every size (minor loops),
 * touching both limits now and then. */
static void voltage_walk(real *u, int n, real lo, real hi)
{
    int i;
    real v = lo, target = hi;
    for (i = 0; i < n; ++i) {
        real step = (hi - lo) * 0.02 * uniform();
        if (uniform() < 0.05) target = lo + (hi - lo) * uniform();
        if (uniform() < 0.01) target = uniform() < 0.5 ? lo : hi;
        v = v < target ? (v + step < target ? v + step : target)
                       : (v - step > target ? v - step : target);
        u[i] = v;
    }
}

/* Desired = the model's output for a voltage walk; compensate from the same start and
 * check predict(compensate(y_d)) == y_d and the limits. Returns the largest
 * |u_comp - u_walk| (the inverse is unique where the model is strictly increasing). */
static real round_trip(pihyst_model *m, real *scratch, size_t scratch_len)
{
    static real u[N_WALK], yd[N_WALK], uc[N_WALK], yc[N_WALK];
    static pihyst_flags flags[N_WALK];
    pihyst_compensator c;
    real du = 0.0, err = 0.0;
    int i;
    voltage_walk(u, N_WALK, m->u_min, m->u_max);
    pihyst_model_reset(m, NULL);
    pihyst_model_run(m, u, yd, N_WALK);
    pihyst_model_reset(m, NULL);
    CHECK(pihyst_compensator_init(&c, m, NAN, NAN, INFINITY, m->u_min, scratch, scratch_len) ==
          PIHYST_OK);
    pihyst_compensator_run(&c, yd, uc, yc, flags, N_WALK);
    for (i = 0; i < N_WALK; ++i) {
        if (fabs(yc[i] - yd[i]) > err) err = fabs(yc[i] - yd[i]);
        if (fabs(uc[i] - u[i]) > du) du = fabs(uc[i] - u[i]);
        CHECK(uc[i] >= m->u_min && uc[i] <= m->u_max);
        /* a flag only where the voltage sits at a limit */
        CHECK(flags[i] == 0 || uc[i] == m->u_min || uc[i] == m->u_max);
    }
    CHECK_NEAR(err, 0.0, TOL(1e-9, 4.0 * c.tol));
    /* the predicted displacement is the model's own output for those voltages, from the
     * start state with the initial voltage applied: bit for bit, but for a ramp model
     * (KP), whose compensator keeps the output as a running sum: within half the
     * equality band of it (pihyst_inverse.c, "saturated ramps") */
    pihyst_model_reset(m, NULL);
    pihyst_model_step(m, m->u_min);
    pihyst_model_run(m, uc, u, N_WALK);
    for (i = 0; i < N_WALK; ++i)
        CHECK((c.in_order & PIHYST_ORDER_RAMPS) ? fabs(u[i] - yc[i]) <= 0.5 * c.tol
                                                : u[i] == yc[i]);
    return du;
}

static void test_round_trip_paper_models(void)
{
    const real rc[4] = {0.0, 10.0, 30.0, 150.0}, wc[4] = {0.008, 0.252, 0.019, 0.582};
    const real rm[4] = {0.0, 20.0, 30.0, 40.0}, wm[4] = {0.196, 0.026, 0.046, 0.028};
    real coef[PIHYST_COEF_LEN(4)], state[4], scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(4, 0)];
    pihyst_model m;
    pihyst_compensator c;
    CHECK(model_init(&m, PIHYST_CLASSICAL, 4, rc, wc, 0.0, 0.0, 150.0, NULL, NULL, coef,
                            state, NULL) == PIHYST_OK);
    /* the inverse is unique (slope >= w_0 > 0), so the voltages agree to the output's
     * error over that slope, 4 tol / w_0: 6e-10 V in double (checked to 1e-9 V), 0.31 V in
     * single precision (measured 0.074 V; w_0 = 0.008 um/V is small) */
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0, scratch, LEN(scratch)) ==
          PIHYST_OK);
    CHECK_NEAR(round_trip(&m, scratch, LEN(scratch)), 0.0, TOL(1e-9, 4.0 * c.tol / wc[0]));
    CHECK(model_init(&m, PIHYST_MULTISLOPE, 4, rm, wm, 1.5, 0.0, 150.0, &paper_shape, NULL,
                            coef, state, NULL) == PIHYST_OK);
    round_trip(&m, scratch, LEN(scratch));
}

static void test_round_trip_many_operators(void)
{
    enum { K = 64 };
    real r[K], w[K], coef[PIHYST_COEF_LEN(K)], state[K];
    real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(K, 0)];
    pihyst_model m;
    int k, fam;
    for (fam = 0; fam < 2; ++fam) {
        for (k = 0; k < K; ++k) {
            r[k] = (fam ? 50.0 : 150.0) * k / K;
            w[k] = k % 7 == 3 ? 0.0 : 0.05 * uniform(); /* zero weights are allowed */
        }
        w[0] = 0.3;
        CHECK(model_init(&m, (pihyst_family)fam, K, r, w, -2.0, fam ? 0.0 : -10.0, 150.0,
                                &paper_shape, NULL, coef, state, NULL) == PIHYST_OK);
        round_trip(&m, scratch, LEN(scratch));
    }
}

/* The classical operators r = 0 and r = 10 as polylines (r = 10 given by one short
 * segment in the middle of the range, continued by its extensions), and a 4-point
 * S-shaped pair. */
static void test_round_trip_pwl(void)
{
    const size_t rs[4] = {0, 2, 4, 8}, fs[4] = {0, 2, 4, 7};
    const real rx[8] = {0, 150, 50, 60, 0, 40, 90, 150};
    const real ry[8] = {0, 150, 40, 50, 0, 5, 60, 80};
    const real fx[7] = {0, 150, 30, 40, 0, 60, 150};
    const real fy[7] = {0, 150, 40, 50, 0, 50, 80};
    const real w[3] = {0.1, 0.2, 0.15}, r[2] = {0.0, 10.0};
    real coef[PIHYST_COEF_LEN(3)], state[3], coef_c[PIHYST_COEF_LEN(2)], state_c[2];
    real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(3, 15)];
    real scratch_c[PIHYST_COMPENSATOR_SCRATCH_LEN(2, 0)];
    real u[200], y[200], u_p[200], u_c[200];
    pihyst_pwl p;
    pihyst_model m, mc;
    pihyst_compensator c, cc;
    int i;
    p.rise_start = rs; p.rise_x = rx; p.rise_y = ry;
    p.fall_start = fs; p.fall_x = fx; p.fall_y = fy;
    CHECK(model_init(&m, PIHYST_PWL, 3, NULL, w, 0.0, 0.0, 150.0, NULL, &p, coef, state,
                            NULL) == PIHYST_OK);
    CHECK(pihyst_compensator_scratch_len(&m) == 7 * 3 + 4 * 8 + 4 + PIHYST_STATE_ALIGN / sizeof(real));
    CHECK(pihyst_compensator_scratch_len(&m) <= PIHYST_COMPENSATOR_SCRATCH_LEN(3, 15));
    round_trip(&m, scratch, LEN(scratch));
    /* two operators: the pwl inverse equals the classical inverse */
    CHECK(model_init(&m, PIHYST_PWL, 2, NULL, w, 0.0, 0.0, 150.0, NULL, &p, coef, state,
                            NULL) == PIHYST_OK);
    CHECK(model_init(&mc, PIHYST_CLASSICAL, 2, r, w, 0.0, 0.0, 150.0, NULL, NULL, coef_c,
                            state_c, NULL) == PIHYST_OK);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0, scratch, LEN(scratch)) == PIHYST_OK);
    CHECK(pihyst_compensator_init(&cc, &mc, NAN, NAN, INFINITY, 0.0, scratch_c, LEN(scratch_c)) == PIHYST_OK);
    for (i = 0; i < 200; ++i) y[i] = 12.0 * sin(0.05 * i) * sin(0.011 * i) + 9.0;
    pihyst_compensator_run(&c, y, u_p, NULL, NULL, 200);
    pihyst_compensator_run(&cc, y, u_c, u, NULL, 200);
    for (i = 0; i < 200; ++i) CHECK_NEAR(u_p[i], u_c[i], TOL(1e-9, F32_ULPS(8, 64)));
}

/* Many pwl operators listed in random order: the event list arrives unsorted and the
 * sort falls back to heapsort; the result must still be exact. */
static void test_unsorted_pwl(void)
{
    enum { K = 40 };
    size_t rs[K + 1], fs[K + 1];
    real rx[4 * K], ry[4 * K], fx[4 * K], fy[4 * K], w[K];
    real coef[PIHYST_COEF_LEN(K)], state[K], scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(K, 8 * K)];
    pihyst_pwl p;
    pihyst_model m;
    int k, j;
    for (k = 0; k <= K; ++k) rs[k] = fs[k] = 4 * (size_t)k;
    for (k = 0; k < K; ++k) {
        /* ramp-smoothed relay (KP kernel) with random switching voltages s1 <= s2:
         * 0 up to s, then a ramp of the given width, then 1 */
        real s1 = 140.0 * uniform(), s2 = s1 + 10.0 * uniform(), width = 1.0 + 9.0 * uniform();
        const real xs[4] = {-1.0, 0.0, 1.0, 200.0}, ys[4] = {0.0, 0.0, 1.0, 1.0};
        for (j = 0; j < 4; ++j) {
            rx[4 * k + j] = j == 0 || j == 3 ? xs[j] : s2 + width * xs[j];
            fx[4 * k + j] = j == 0 || j == 3 ? xs[j] : s1 + width * xs[j];
            ry[4 * k + j] = fy[4 * k + j] = ys[j];
        }
        w[k] = 0.5 + uniform();
    }
    p.rise_start = rs; p.rise_x = rx; p.rise_y = ry;
    p.fall_start = fs; p.fall_x = fx; p.fall_y = fy;
    CHECK(model_init(&m, PIHYST_PWL, K, NULL, w, 0.0, 0.0, 150.0, NULL, &p, coef, state,
                            NULL) == PIHYST_OK);
    round_trip(&m, scratch, LEN(scratch));
}

/* A near-vertical polyline segment (one ulp wide, slope 4.5e15 in double, 8.4e6 in single) joined and left on the
 * way up: the walk's slope sum must come back to the small slopes exactly. */
static void test_steep_pwl(void)
{
    const size_t start[2] = {0, 6};
    const real x[6] = {0.0, 1.0, 1.0 + TOL(DBL_EPSILON, FLT_EPSILON), 4.0, 5.0, 150.0};
    const real y[6] = {-20.0, -20.0, -19.0, -18.0, -18.0, -18.0};
    const real w[1] = {1.0};
    real coef[PIHYST_COEF_LEN(1)], state[1], scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(1, 12)];
    pihyst_pwl p;
    pihyst_model m;
    pihyst_compensator c;
    p.rise_start = start; p.rise_x = x; p.rise_y = y;
    p.fall_start = start; p.fall_x = x; p.fall_y = y;
    CHECK(model_init(&m, PIHYST_PWL, 1, NULL, w, 0.0, 0.0, 150.0, NULL, &p, coef, state,
                            NULL) == PIHYST_OK);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0, scratch, LEN(scratch)) ==
          PIHYST_OK);
    CHECK_NEAR(pihyst_compensator_step(&c, -18.0 - 1.0 / 3.0, NULL), 3.0, TOL(1e-12, F32_ULPS(8, 32)));
    CHECK_NEAR(c.y_last, -18.0 - 1.0 / 3.0, TOL(1e-12, F32_ULPS(8, 32)));
}

/* Multislope with thresholds > 0 only: after the top at 150 V the output holds while
 * the voltage falls by h r_min = 5 V. A desired output that stays at its maximum must
 * hold the voltage at 150 V, not jump to the other end of the flat stretch. */
static void test_flat_hold(void)
{
    const real r[3] = {10.0, 20.0, 40.0}, w[3] = {0.2, 0.1, 0.05};
    real coef[PIHYST_COEF_LEN(3)], state[3], scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(3, 0)];
    real u[190], yd[190], uc[190], yc[190];
    pihyst_model m;
    pihyst_compensator c;
    int i;
    for (i = 0; i < 190; ++i) u[i] = i <= 150 ? (real)i : 150.0 - 0.125 * (i - 150); /* to 145 */
    CHECK(model_init(&m, PIHYST_MULTISLOPE, 3, r, w, 0.0, 0.0, 150.0, &paper_shape, NULL,
                            coef, state, NULL) == PIHYST_OK);
    pihyst_model_run(&m, u, yd, 190);
    for (i = 151; i < 190; ++i) CHECK(yd[i] == yd[150]); /* the model is flat there */
    pihyst_model_reset(&m, NULL);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0, scratch, LEN(scratch)) == PIHYST_OK);
    pihyst_compensator_run(&c, yd, uc, yc, NULL, 190);
    CHECK_NEAR(uc[150], 150.0, 1e-9);
    for (i = 151; i < 190; ++i) CHECK(uc[i] == uc[150]);
    /* then a small decrease crosses the flat stretch to where the output starts falling */
    CHECK(pihyst_compensator_step(&c, yd[150] - TOL(1e-6, 1e-3), NULL) < 145.0 + 1e-3);
    CHECK(c.u_last > 144.99);
    /* from rest, a desired value equal to the current output holds 0 V */
    CHECK(pihyst_compensator_reset(&c, NULL, 0.0) == PIHYST_OK);
    CHECK(pihyst_compensator_step(&c, 0.0, NULL) == 0.0);
}

static const real garbage[] = {NAN, INFINITY, -INFINITY, 1e300, -1e300, 5.0, NAN, 40.0,
                                 -3.0, 1e-300, 20.0, -INFINITY, 19.0, 21.0, DBL_MAX};

static void test_limits_and_slew(void)
{
    const real r[4] = {0.0, 10.0, 30.0, 150.0}, w[4] = {0.008, 0.252, 0.019, 0.582};
    real coef[PIHYST_COEF_LEN(4)], state[4], scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(4, 0)];
    const int ng = (int)(sizeof garbage / sizeof *garbage);
    pihyst_model m;
    pihyst_compensator c;
    pihyst_flags fl;
    int i, pass;
    CHECK(model_init(&m, PIHYST_CLASSICAL, 4, r, w, 0.0, 0.0, 150.0, NULL, NULL, coef,
                            state, NULL) == PIHYST_OK);
    CHECK(pihyst_compensator_init(&c, &m, 10.0, 120.0, INFINITY, 10.0, scratch, LEN(scratch)) == PIHYST_OK);
    CHECK(pihyst_compensator_step(&c, INFINITY, &fl) == 120.0 && fl == PIHYST_COMP_SAT_HIGH);
    CHECK(pihyst_compensator_step(&c, 1e300, &fl) == 120.0 && fl == PIHYST_COMP_SAT_HIGH);
    CHECK(pihyst_compensator_step(&c, NAN, &fl) == 120.0 && fl == PIHYST_COMP_NAN);
    CHECK(pihyst_compensator_step(&c, -1e300, &fl) == 10.0 && fl == PIHYST_COMP_SAT_LOW);
    CHECK(pihyst_compensator_step(&c, -INFINITY, &fl) == 10.0 && fl == PIHYST_COMP_SAT_LOW);
    /* cut short by the slew limit: out of reach (beyond the voltage limit) is flagged too */
    CHECK(pihyst_compensator_init(&c, &m, 10.0, 120.0, 3.7, 10.0, scratch, LEN(scratch)) ==
          PIHYST_OK);
    CHECK(pihyst_compensator_step(&c, 1e300, &fl) < 14.0 &&
          fl == (PIHYST_COMP_SAT_HIGH | PIHYST_COMP_SLEW));
    CHECK(pihyst_compensator_step(&c, 31.0, &fl) < 18.0 &&
          fl == (PIHYST_COMP_SAT_HIGH | PIHYST_COMP_SLEW));  /* 30.39 um at 120 V */
    CHECK(pihyst_compensator_step(&c, 20.0, &fl) < 22.0 && fl == PIHYST_COMP_SLEW);
    CHECK(pihyst_compensator_step(&c, -1.0, &fl) < 19.0 &&
          fl == (PIHYST_COMP_SAT_LOW | PIHYST_COMP_SLEW));
    for (pass = 0; pass < 2; ++pass) {
        real prev, step = pass ? 0.1 : 3.7;
        CHECK(pihyst_compensator_init(&c, &m, 10.0, 120.0, step, 10.0, scratch, LEN(scratch)) ==
              PIHYST_OK);
        prev = c.u_last;
        for (i = 0; i < 3000; ++i) {
            real yd = i < ng ? garbage[i] : (uniform() < 0.1 ? garbage[i % ng]
                                                                : 60.0 * uniform() - 10.0);
            real u = pihyst_compensator_step(&c, yd, &fl);
            CHECK(u >= 10.0 && u <= 120.0);
            CHECK(fabs(u - prev) <= step);
            if (isnan(yd)) CHECK(u == prev && fl == PIHYST_COMP_NAN);
            if (fl & PIHYST_COMP_SLEW) CHECK(fabs(u - prev) >= step - TOL(1e-12 * step, F32_ULPS(2, 128)));
            prev = u;
        }
    }
}

/* step == run bit for bit; two chunks == one block; reset restores the start */
static void test_identities(void)
{
    enum { N = 700, K = 9 };
    real r[K], w[K], coef[PIHYST_COEF_LEN(K)], state[K];
    real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(K, 0)];
    real yd[N], u_run[N], y_run[N], u_chunk[N], y_chunk[N];
    pihyst_flags f_run[N], f_chunk[N];
    pihyst_model m;
    pihyst_compensator c;
    int i, k, fam;
    size_t n1, n2, n3;
    for (i = 0; i < N; ++i) yd[i] = 30.0 * sin(0.03 * i) * cos(0.0071 * i) + 15.0;
    yd[100] = NAN;
    yd[200] = 1e300;
    for (fam = 0; fam < 2; ++fam) {
        for (k = 0; k < K; ++k) {
            r[k] = (fam ? 5.0 : 14.0) * k;
            w[k] = 0.04 * (k + 1);
        }
        CHECK(model_init(&m, (pihyst_family)fam, K, r, w, 0.0, 0.0, 150.0, &paper_shape,
                                NULL, coef, state, NULL) == PIHYST_OK);
        CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, 2.5, 0.0, scratch, LEN(scratch)) == PIHYST_OK);
        n1 = pihyst_compensator_run(&c, yd, u_run, y_run, f_run, N);
        CHECK(n1 >= 2);
        CHECK(pihyst_compensator_reset(&c, NULL, 0.0) == PIHYST_OK);
        for (i = 0; i < N; ++i) {
            pihyst_flags fl;
            CHECK(pihyst_compensator_step(&c, yd[i], &fl) == u_run[i]);
            CHECK(c.y_last == y_run[i] && fl == f_run[i]);
        }
        CHECK(pihyst_compensator_reset(&c, NULL, 0.0) == PIHYST_OK);
        n2 = pihyst_compensator_run(&c, yd, u_chunk, y_chunk, f_chunk, 333);
        n3 = pihyst_compensator_run(&c, yd + 333, u_chunk + 333, y_chunk + 333, f_chunk + 333,
                                    N - 333);
        CHECK(n2 + n3 == n1);
        for (i = 0; i < N; ++i)
            CHECK(u_chunk[i] == u_run[i] && y_chunk[i] == y_run[i] && f_chunk[i] == f_run[i]);
        CHECK((f_run[100] & PIHYST_COMP_NAN) && u_run[100] == u_run[99]);
    }
}

static void test_validation_and_reset(void)
{
    const real r[3] = {0.0, 10.0, 20.0}, w[3] = {0.5, 0.2, 0.1}, wneg[3] = {0.5, -0.2, 0.1};
    const real bad_state[3] = {0.0, NAN, 0.0}, far_state[3] = {100.0, 100.0, -100.0};
    real coef[PIHYST_COEF_LEN(3)], state[3], scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(3, 0)];
    pihyst_model m;
    pihyst_compensator c;
    CHECK(model_init(&m, PIHYST_CLASSICAL, 3, r, wneg, 0, 0, 150, NULL, NULL, coef, state,
                            NULL) == PIHYST_OK);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0, scratch, LEN(scratch)) ==
          PIHYST_ENEGATIVE_WEIGHT);
    CHECK(model_init(&m, PIHYST_CLASSICAL, 3, r, w, 0, 0, 150, NULL, NULL, coef, state,
                            NULL) == PIHYST_OK);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0, scratch,
                                  pihyst_compensator_scratch_len(&m) - 1) == PIHYST_ESCRATCH);
    CHECK(pihyst_compensator_init(&c, &m, -1, NAN, INFINITY, 0, scratch, LEN(scratch)) == PIHYST_ELIMITS);
    CHECK(pihyst_compensator_init(&c, &m, NAN, 151, INFINITY, 0, scratch, LEN(scratch)) == PIHYST_ELIMITS);
    CHECK(pihyst_compensator_init(&c, &m, 50, 50, INFINITY, 50, scratch, LEN(scratch)) == PIHYST_ELIMITS);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, 0.0, 0, scratch, LEN(scratch)) == PIHYST_ELIMITS);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, NAN, 0, scratch, LEN(scratch)) == PIHYST_ELIMITS);
    CHECK(pihyst_compensator_init(&c, &m, 10, NAN, INFINITY, 0, scratch, LEN(scratch)) == PIHYST_ELIMITS);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, NAN, scratch, LEN(scratch)) ==
          PIHYST_ENONFINITE);
    CHECK(pihyst_compensator_init(NULL, &m, NAN, NAN, INFINITY, 0, scratch, LEN(scratch)) == PIHYST_ENULL);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0, NULL, 18) == PIHYST_ENULL);
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 30, scratch, LEN(scratch)) == PIHYST_OK);
    CHECK(c.u_last == 30.0 && c.u_min == 0.0 && c.u_max == 150.0);
    /* the model state has had 30 V applied: 30, 20, 10 */
    CHECK(state[0] == 30.0 && state[1] == 20.0 && state[2] == 10.0);
    CHECK_NEAR(c.y_last, 0.5 * 30 + 0.2 * 20 + 0.1 * 10, 1e-12);
    CHECK(pihyst_compensator_reset(&c, bad_state, 0.0) == PIHYST_ENONFINITE);
    CHECK(pihyst_compensator_reset(&c, NULL, 151.0) == PIHYST_ELIMITS);
    CHECK(pihyst_compensator_reset(&c, NULL, NAN) == PIHYST_ENONFINITE);
    CHECK(c.u_last == 30.0 && state[0] == 30.0); /* unchanged by the failed resets */
    /* an inconsistent state is brought onto the envelopes of the voltage */
    CHECK(pihyst_compensator_reset(&c, far_state, 50.0) == PIHYST_OK);
    CHECK(state[0] == 50.0 && state[1] == 60.0 && state[2] == 30.0);
    CHECK(strlen(pihyst_status_text(PIHYST_ENEGATIVE_WEIGHT)) > 0);
    CHECK(strlen(pihyst_status_text(PIHYST_ELIMITS)) > 0);
}


/* Desired = the model's output for a random voltage every sample (a reversal nearly
 * every time) from the compensator's start; compensated, predict(u) == y_d to 1e-9 and
 * step == run bit for bit. The model's state is reset to `start` (NULL = zeros) and
 * u_start applied before each run. */
#define N_NOISE 3000
static void noise_round_trip(pihyst_model *m, real *scratch, size_t scratch_len,
                             const real *start, real u_start)
{
    static real u[N_NOISE], yd[N_NOISE], uc[N_NOISE], yc[N_NOISE], us[N_NOISE];
    pihyst_compensator c;
    real err = 0.0;
    int i;
    for (i = 0; i < N_NOISE; ++i) u[i] = m->u_min + (m->u_max - m->u_min) * uniform();
    pihyst_model_reset(m, start);
    pihyst_model_step(m, u_start);
    pihyst_model_run(m, u, yd, N_NOISE);
    pihyst_model_reset(m, start);
    CHECK(pihyst_compensator_init(&c, m, NAN, NAN, INFINITY, u_start, scratch, scratch_len) ==
          PIHYST_OK);
    pihyst_compensator_run(&c, yd, uc, yc, NULL, N_NOISE);
    for (i = 0; i < N_NOISE; ++i) {
        if (fabs(yc[i] - yd[i]) > err) err = fabs(yc[i] - yd[i]);
        CHECK(uc[i] >= m->u_min && uc[i] <= m->u_max);
    }
    CHECK_NEAR(err, 0.0, TOL(1e-9, 4.0 * c.tol));
    /* step by step from the same start: the same bits */
    pihyst_model_reset(m, start);
    CHECK(pihyst_compensator_init(&c, m, NAN, NAN, INFINITY, u_start, scratch, scratch_len) ==
          PIHYST_OK);
    for (i = 0; i < N_NOISE; ++i) us[i] = pihyst_compensator_step(&c, yd[i], NULL);
    for (i = 0; i < N_NOISE && us[i] == uc[i]; ++i) continue;
    CHECK(i == N_NOISE);
}

/* Noise on classical and multislope banks of every size, random thresholds (some close
 * together) and some zero weights. */
static void test_noise(void)
{
    enum { KMAX = 64 };
    static const int sizes[] = {1, 2, 4, 16, 64};
    real r[KMAX], w[KMAX], coef[PIHYST_COEF_LEN(KMAX)], state[KMAX];
    real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(KMAX, 0)];
    pihyst_model m;
    int fam, i, k;
    for (fam = 0; fam < 2; ++fam) {
        for (i = 0; i < (int)LEN(sizes); ++i) {
            const int K = sizes[i];
            for (k = 0; k < K; ++k) {
                r[k] = (fam ? 46.0 : 150.0) * (k + (k % 3 == 1 ? 0.999 * uniform() : 0.0)) / K;
                w[k] = k % 5 == 2 ? 0.0 : 0.02 + 0.1 * uniform();
            }
            CHECK(model_init(&m, (pihyst_family)fam, (size_t)K, r, w, 0.5, 0.0, 150.0,
                                    &paper_shape, NULL, coef, state, NULL) == PIHYST_OK);
            noise_round_trip(&m, scratch, LEN(scratch), NULL, 0.0);
        }
    }
}

/* Multislope shapes other than the paper's: random (a, b, h), whose crossings now and
 * then arrive out of operator order (sorted then), and one with a close to b and h = 1. */
static void test_noise_multislope_shapes(void)
{
    enum { K = 12 };
    real r[K], w[K], coef[PIHYST_COEF_LEN(K)], state[K];
    real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(K, 0)];
    pihyst_model m;
    pihyst_shape shape = {150.0, 0.95, 1.05, 1.0};
    int trial, k;
    for (trial = 0; trial < 12; ++trial) {
        real r_max;
        if (trial > 0) {
            shape.a = 0.5 + 0.45 * uniform();
            shape.b = 1.05 + 0.55 * uniform();
            shape.h = uniform();
        }
        r_max = (1.0 - shape.a) * shape.U / (1.0 - shape.a * shape.h);
        for (k = 0; k < K; ++k) {
            r[k] = r_max * (k + 0.9 * uniform()) / K;
            w[k] = 0.02 + 0.1 * uniform();
        }
        CHECK(model_init(&m, PIHYST_MULTISLOPE, K, r, w, 0.0, 0.0, 150.0, &shape, NULL,
                                coef, state, NULL) == PIHYST_OK);
        noise_round_trip(&m, scratch, LEN(scratch), NULL, 0.0);
    }
}

/* A classical state that is not 1-Lipschitz in r (set by reset, not reachable from
 * rest): its crossings are out of operator order, so they are collected and sorted,
 * and exact; a large excursion wipes the memory out and the crossings are read in
 * order again. */
static void test_classical_unordered_state(void)
{
    enum { K = 6 };
    const real r[K] = {0.0, 5.0, 50.0, 60.0, 61.0, 90.0};
    const real w[K] = {0.3, 0.1, 0.2, 0.05, 0.15, 0.1};
    const real start[K] = {75.0, 75.0, 110.0, 20.0, 130.0, 0.0}; /* 110 vs 20: |df| > dr */
    real coef[PIHYST_COEF_LEN(K)], state[K], scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(K, 0)];
    real yd[3];
    pihyst_model m;
    pihyst_compensator c;
    int i;
    CHECK(model_init(&m, PIHYST_CLASSICAL, K, r, w, 0.0, 0.0, 150.0, NULL, NULL, coef,
                            state, NULL) == PIHYST_OK);
    noise_round_trip(&m, scratch, LEN(scratch), start, 75.0);
    /* from that state, up to 150 and down to 0: every operator on an envelope of those */
    CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0, scratch, LEN(scratch)) ==
          PIHYST_OK);
    CHECK(pihyst_compensator_reset(&c, start, 75.0) == PIHYST_OK);
    CHECK(state[2] == 110.0 && state[3] == 20.0);
    pihyst_model_reset(&m, start);
    pihyst_model_step(&m, 75.0);
    yd[0] = pihyst_model_step(&m, 150.0);
    yd[1] = pihyst_model_step(&m, 0.0);
    yd[2] = pihyst_model_step(&m, 40.0);
    pihyst_model_reset(&m, start);
    pihyst_model_step(&m, 75.0);
    CHECK(pihyst_compensator_reset(&c, start, 75.0) == PIHYST_OK);
    CHECK(!(c.in_order & PIHYST_ORDER_CLASSICAL)); /* out of order: lists */
    for (i = 0; i < 3; ++i) {
        pihyst_compensator_step(&c, yd[i], NULL);
        CHECK_NEAR(c.y_last, yd[i], TOL(1e-9, 4.0 * c.tol));
    }
    CHECK(c.in_order & PIHYST_ORDER_CLASSICAL); /* ordered again: read from the state */
}

/* The state array at any alignment (steps of one element across a cache line): the same
 * voltages bit for bit, the caller's array current after every call, and the model
 * pointing at it between calls. buf is only as aligned as a real (4 bytes for a float on
 * a Cortex-M4): rounding it up to 64 bytes may skip 64 / sizeof(real) - 1 elements. */
static void test_state_alignment(void)
{
    enum { K = 16, N = 600, PAD = 8 };
    static real buf[K + PAD + 64 / sizeof(real)], yd[N], u0[N], u1[N];
    real r[K], w[K], coef[PIHYST_COEF_LEN(K)], ref_state[K];
    real scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(K, 0)];
    real *base = (real *)(((uintptr_t)buf + 63) / 64 * 64);
    pihyst_model m;
    pihyst_compensator c;
    int fam, off, i, k;
    for (fam = 0; fam < 2; ++fam) {
        for (k = 0; k < K; ++k) {
            r[k] = (fam ? 46.0 : 150.0) * k / K;
            w[k] = 0.05 + 0.05 * uniform();
        }
        for (off = 0; off < PAD; ++off) {
            real *state = base + off;
            CHECK(model_init(&m, (pihyst_family)fam, K, r, w, 0.0, 0.0, 150.0,
                                    &paper_shape, NULL, coef, state, NULL) == PIHYST_OK);
            if (off == 0) {
                real u[N];
                for (i = 0; i < N; ++i) u[i] = 150.0 * uniform();
                pihyst_model_run(&m, u, yd, N);
                pihyst_model_reset(&m, NULL);
            }
            CHECK(pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0, scratch,
                                          LEN(scratch)) == PIHYST_OK);
            CHECK(m.state == state);
            for (i = 0; i < N; ++i) {
                (off == 0 ? u0 : u1)[i] = pihyst_compensator_step(&c, yd[i], NULL);
                CHECK(m.state == state);
                CHECK_NEAR(c.y_last, yd[i], TOL(1e-9, 4.0 * c.tol));
            }
            if (off == 0) {
                memcpy(ref_state, state, sizeof ref_state);
            } else {
                CHECK(memcmp(u0, u1, sizeof u0) == 0);
                CHECK(memcmp(ref_state, state, sizeof ref_state) == 0);
            }
            /* the block run leaves the same state in the caller's array */
            CHECK(pihyst_compensator_reset(&c, NULL, 0.0) == PIHYST_OK);
            pihyst_compensator_run(&c, yd, u1, NULL, NULL, N);
            CHECK(memcmp(u0, u1, sizeof u0) == 0);
            CHECK(memcmp(ref_state, state, sizeof ref_state) == 0);
        }
    }
}

/* pihyst_compensator_scratch_len never exceeds the macro */
static void test_scratch_len(void)
{
    const size_t start[3] = {0, 5, 9};
    const real x[9] = {0, 1, 2, 3, 4, 0, 1, 2, 3}, y[9] = {0, 1, 2, 3, 4, 0, 1, 2, 3};
    real r[64], w[64], coef[PIHYST_COEF_LEN(64)], state[64];
    pihyst_pwl p;
    pihyst_model m;
    size_t k;
    for (k = 0; k < 64; ++k) {
        r[k] = (real)k;
        w[k] = 1.0;
        CHECK(model_init(&m, PIHYST_CLASSICAL, k + 1, r, w, 0.0, 0.0, 150.0, NULL, NULL,
                                coef, state, NULL) == PIHYST_OK);
        CHECK(pihyst_compensator_scratch_len(&m) <= PIHYST_COMPENSATOR_SCRATCH_LEN(k + 1, 0));
    }
    p.rise_start = start; p.rise_x = x; p.rise_y = y;
    p.fall_start = start; p.fall_x = x; p.fall_y = y;
    k = model_init(&m, PIHYST_PWL, 2, NULL, w, 0.0, 0.0, 3.0, NULL, &p, coef, state,
                          NULL) == PIHYST_OK;
    CHECK(k);
    if (k) CHECK(pihyst_compensator_scratch_len(&m) <= PIHYST_COMPENSATOR_SCRATCH_LEN(2, 18));
}

void run_inverse_tests(void)
{
    test_round_trip_paper_models();
    test_round_trip_many_operators();
    test_round_trip_pwl();
    test_unsorted_pwl();
    test_steep_pwl();
    test_flat_hold();
    test_limits_and_slew();
    test_identities();
    test_validation_and_reset();
    test_noise();
    test_noise_multislope_shapes();
    test_classical_unordered_state();
    test_state_alignment();
    test_scratch_len();
}
