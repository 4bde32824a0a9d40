/* Tests of pihyst_model_*: the paper's checks (docs/paper.md), validation,
 * and the identities step == run, chunked == whole, gram == operators^T operators. */
#include "pihyst.h"
#include "test_util.h"

#include <string.h>

#define N_CYCLE 301 /* 0 -> 150 -> 0 V in 1 V steps */

static void cycle(real *u)
{
    int i;
    for (i = 0; i < N_CYCLE; ++i) u[i] = i <= 150 ? (real)i : (real)(300 - i);
}

static const pihyst_shape paper_shape = {150.0, 0.8, 1.2, 0.5};

static void test_paper_classical(void)
{
    const real r[4] = {0.0, 10.0, 30.0, 150.0}, w[4] = {0.008, 0.252, 0.019, 0.582};
    real coef[PIHYST_COEF_LEN(4)], state[4], u[N_CYCLE], y[N_CYCLE];
    pihyst_model m;
    CHECK(model_init(&m, PIHYST_CLASSICAL, 4, r, w, 0.0, 0.0, 150.0, NULL, NULL, coef,
                            state, NULL) == PIHYST_OK);
    cycle(u);
    pihyst_model_run(&m, u, y, N_CYCLE);
    CHECK_NEAR(y[150], 38.76, TOL(1e-12, F32_ULPS(8, 64)));
    CHECK_NEAR(y[N_CYCLE - 1], 3.09, TOL(1e-12, F32_ULPS(8, 64)));
    CHECK(state[3] == 0.0); /* r = 150 never leaves 0 on [0, 150] */
}

static void test_paper_multislope(void)
{
    const real r[4] = {0.0, 20.0, 30.0, 40.0}, w[4] = {0.196, 0.026, 0.046, 0.028};
    real coef[PIHYST_COEF_LEN(4)], state[4], u[N_CYCLE], y[N_CYCLE];
    pihyst_model m;
    CHECK(model_init(&m, PIHYST_MULTISLOPE, 4, r, w, 0.0, 0.0, 150.0, &paper_shape, NULL,
                            coef, state, NULL) == PIHYST_OK);
    cycle(u);
    pihyst_model_run(&m, u, y, N_CYCLE);
    CHECK_NEAR(y[150], 41.38, TOL(1e-12, F32_ULPS(8, 64)));
    CHECK(fabs(y[N_CYCLE - 1]) <= TOL(1e-12, F32_ULPS(8, 64)));
}

/* r = 40 (Fig. 5): rising kink at 95 V, hold from 150 V down to 130 V, falling kink at 15 V */
static void test_multislope_r40_kinks(void)
{
    const real r[1] = {40.0}, w[1] = {1.0};
    real coef[PIHYST_COEF_LEN(1)], state[1], rise[1], fall[1];
    pihyst_model m;
    CHECK(model_init(&m, PIHYST_MULTISLOPE, 1, r, w, 0.0, 0.0, 150.0, &paper_shape, NULL,
                            coef, state, NULL) == PIHYST_OK);
    pihyst_model_envelopes(&m, 95.0, rise, fall);
    CHECK_NEAR(rise[0], 0.8 * 55.0, TOL(1e-12, F32_ULPS(8, 128)));
    CHECK_NEAR(rise[0], 1.2 * 95.0 - 70.0, TOL(1e-12, F32_ULPS(8, 128)));
    pihyst_model_envelopes(&m, 15.0, rise, fall);
    CHECK_NEAR(fall[0], 1.2 * 15.0, TOL(1e-12, F32_ULPS(8, 128)));
    CHECK_NEAR(fall[0], 0.8 * 15.0 + 30.0 - 0.6 * 40.0, TOL(1e-12, F32_ULPS(8, 128)));
    /* after the top, the output holds at U - r = 110 until 130 V, then falls */
    CHECK_NEAR(pihyst_model_step(&m, 150.0), 110.0, TOL(1e-12, F32_ULPS(8, 128)));
    CHECK_NEAR(pihyst_model_step(&m, 131.0), 110.0, TOL(1e-12, F32_ULPS(8, 128)));
    CHECK_NEAR(pihyst_model_step(&m, 130.0), 110.0, TOL(1e-12, F32_ULPS(8, 128)));
    CHECK(pihyst_model_step(&m, 129.0) < 110.0 - 0.5);
}

static void test_validation(void)
{
    const real w[3] = {1.0, 1.0, 1.0};
    const real unsorted[3] = {0.0, 20.0, 10.0}, negative[3] = {-1.0, 0.0, 1.0};
    const real too_big[3] = {0.0, 20.0, 51.0}, ok[3] = {0.0, 20.0, 50.0};
    const real nan_r[3] = {0.0, NAN, 30.0};
    real coef[PIHYST_COEF_LEN(3)], state[3];
    pihyst_shape bad_shape = {150.0, 1.3, 1.2, 0.5};
    pihyst_model m;
    CHECK(model_init(&m, PIHYST_CLASSICAL, 3, unsorted, w, 0, 0, 150, NULL, NULL, coef,
                            state, NULL) == PIHYST_ETHRESHOLD);
    CHECK(model_init(&m, PIHYST_CLASSICAL, 3, negative, w, 0, 0, 150, NULL, NULL, coef,
                            state, NULL) == PIHYST_ETHRESHOLD);
    CHECK(model_init(&m, PIHYST_CLASSICAL, 3, nan_r, w, 0, 0, 150, NULL, NULL, coef,
                            state, NULL) == PIHYST_ENONFINITE);
    CHECK(model_init(&m, PIHYST_CLASSICAL, 0, ok, w, 0, 0, 150, NULL, NULL, coef, state,
                            NULL) == PIHYST_ESIZE);
    CHECK(model_init(&m, PIHYST_CLASSICAL, 3, ok, NULL, 0, 0, 150, NULL, NULL, coef,
                            state, NULL) == PIHYST_ENULL);
    CHECK(model_init(&m, PIHYST_CLASSICAL, 3, ok, w, 0, 150, 0, NULL, NULL, coef, state,
                            NULL) == PIHYST_ERANGE);
    CHECK(model_init(&m, PIHYST_MULTISLOPE, 3, too_big, w, 0, 0, 150, &paper_shape, NULL,
                            coef, state, NULL) == PIHYST_EMULTISLOPE_R);
    CHECK(model_init(&m, PIHYST_MULTISLOPE, 3, ok, w, 0, 0, 150, &paper_shape, NULL, coef,
                            state, NULL) == PIHYST_OK);
    CHECK(model_init(&m, PIHYST_MULTISLOPE, 3, ok, w, 0, 0, 150, &bad_shape, NULL, coef,
                            state, NULL) == PIHYST_ESHAPE);
    CHECK(strlen(pihyst_status_text(PIHYST_EENVELOPE)) > 0);
}

/* The parameter struct filled with designated initializers; distinct status codes. */
static void test_params(void)
{
    static const real r[4] = {0.0, 20.0, 30.0, 40.0}, w[4] = {0.196, 0.026, 0.046, 0.028};
    static const real start[4] = {1.0, 2.0, 3.0, 4.0};
    real coef[PIHYST_COEF_LEN(4)], state[4];
    pihyst_model m;
    pihyst_params p = {
        .family = PIHYST_MULTISLOPE, .n_ops = 4, .thresholds = r, .weights = w,
        .u_max = 150.0, .shape = {.U = 150.0, .a = 0.8, .b = 1.2, .h = 0.5},
    };
    CHECK(pihyst_model_init(&m, &p, coef, state) == PIHYST_OK);
    CHECK(m.u_min == 0.0 && m.u_max == 150.0 && m.offset == 0.0 && m.thresholds == r);
    CHECK(m.shape.h == (real)0.5 && state[0] == 0.0 && state[3] == 0.0);
    p.initial_state = start;
    CHECK(pihyst_model_init(&m, &p, coef, state) == PIHYST_OK);
    CHECK(state[0] == 1.0 && state[3] == 4.0);
    CHECK(pihyst_model_init(&m, NULL, coef, state) == PIHYST_ENULL);
    CHECK(pihyst_model_init(&m, &p, NULL, state) == PIHYST_ENULL);
    p.family = (pihyst_family)3; /* an unknown family is not a shape error */
    CHECK(pihyst_model_init(&m, &p, coef, state) == PIHYST_EFAMILY);
    p.family = PIHYST_MULTISLOPE;
    p.shape.U = 0.0; /* left out */
    CHECK(pihyst_model_init(&m, &p, coef, state) == PIHYST_ESHAPE);
    p.family = PIHYST_PWL; /* no polylines given */
    CHECK(pihyst_model_init(&m, &p, coef, state) == PIHYST_ENULL);
    p.family = PIHYST_CLASSICAL;
    p.u_max = 0.0;
    CHECK(pihyst_model_init(&m, &p, coef, state) == PIHYST_ERANGE);
    CHECK(strcmp(pihyst_status_text(PIHYST_EFAMILY), pihyst_status_text(PIHYST_ESHAPE)) != 0);
    CHECK(strcmp(pihyst_status_text(PIHYST_ESCRATCH), pihyst_status_text(PIHYST_ESIZE)) != 0);
    CHECK(strcmp(pihyst_status_text((pihyst_status)-99), "unknown status") == 0);
}

static void test_pwl(void)
{
    /* operator 0: classical r = 10 as polylines; operator 1: R above F -> rejected */
    const size_t start[3] = {0, 2, 4};
    const real rx[4] = {0, 150, 0, 150}, ry[4] = {-10, 140, 0, 150};
    const real fx[4] = {0, 150, 0, 150}, fy[4] = {10, 160, -5, 145};
    const real r[1] = {10.0}, w[2] = {0.5, 0.0};
    real coef[PIHYST_COEF_LEN(2)], state[2], coef_c[PIHYST_COEF_LEN(1)], state_c[1];
    real u[N_CYCLE], y[N_CYCLE], y_c[N_CYCLE];
    pihyst_pwl p;
    pihyst_model m, mc;
    int i;
    p.rise_start = start; p.rise_x = rx; p.rise_y = ry;
    p.fall_start = start; p.fall_x = fx; p.fall_y = fy;
    CHECK(model_init(&m, PIHYST_PWL, 2, NULL, w, 0, 0, 150, NULL, &p, coef, state, NULL) ==
          PIHYST_EENVELOPE);
    CHECK(model_init(&m, PIHYST_PWL, 1, NULL, w, 0, 0, 150, NULL, &p, coef, state, NULL) ==
          PIHYST_OK);
    {   /* found by fuzzing: breakpoints a subnormal apart (the envelope became a
         * staircase, or infinite), and a slope that overflows */
        const real sx[2] = {0.0, TOL(5e-324, 1e-45)}, sy[2] = {0.0, TOL(5e-324, 1e-45)};
        const real vx[2] = {0.0, TOL(1e-300, 1e-30)}, vy[2] = {0.0, TOL(1e300, 1e30)};
        const size_t one[2] = {0, 2};
        pihyst_pwl subnormal = {one, sx, sy, one, sx, sy}, steep = {one, vx, vy, one, vx, vy};
        pihyst_model bad;
        real bad_coef[PIHYST_COEF_LEN(1)], bad_state[1];
        CHECK(model_init(&bad, PIHYST_PWL, 1, NULL, w, 0, 0, 150, NULL, &subnormal, bad_coef,
                         bad_state, NULL) == PIHYST_EPOLYLINE);
        CHECK(model_init(&bad, PIHYST_PWL, 1, NULL, w, 0, 0, 150, NULL, &steep, bad_coef,
                         bad_state, NULL) == PIHYST_EPOLYLINE);
    }
    CHECK(model_init(&mc, PIHYST_CLASSICAL, 1, r, w, 0, 0, 150, NULL, NULL, coef_c, state_c,
                            NULL) == PIHYST_OK);
    cycle(u);
    pihyst_model_run(&m, u, y, N_CYCLE);
    pihyst_model_run(&mc, u, y_c, N_CYCLE);
    for (i = 0; i < N_CYCLE; ++i) CHECK_NEAR(y[i], y_c[i], TOL(1e-12, F32_ULPS(8, 128)));
}

/* step == run, chunked == whole, gram == sum of outer products of the operator rows */
static void test_identities(void)
{
    enum { N = 500, K = 11 };
    real r[K], w[K], coef[PIHYST_COEF_LEN(K)], state[K], u[N], y_run[N], y_step[N];
    real y_chunks[N], phi[N * K], gram[K * K], rhs[K], sums[K], d[N];
    pihyst_model m;
    unsigned lcg = 12345u;
    int fam, i, j, k;
    for (i = 0; i < N; ++i) {
        lcg = lcg * 1103515245u + 12345u;
        u[i] = 150.0 * (real)(lcg >> 8) / (real)(1u << 24);
        d[i] = 0.1 * u[i];
    }
    for (fam = 0; fam < 2; ++fam) {
        for (k = 0; k < K; ++k) {
            r[k] = (fam ? 4.5 : 13.0) * k;
            w[k] = 0.01 * (k + 1);
        }
        CHECK(model_init(&m, (pihyst_family)fam, K, r, w, 0.5, 0, 150, &paper_shape, NULL,
                                coef, state, NULL) == PIHYST_OK);
        pihyst_model_run(&m, u, y_run, N);
        pihyst_model_reset(&m, NULL);
        for (i = 0; i < N; ++i) y_step[i] = pihyst_model_step(&m, u[i]);
        pihyst_model_reset(&m, NULL);
        pihyst_model_run(&m, u, y_chunks, 123);
        pihyst_model_run(&m, u + 123, y_chunks + 123, N - 123);
        for (i = 0; i < N; ++i) {
            CHECK(y_run[i] == y_step[i]);
            CHECK(y_run[i] == y_chunks[i]);
        }
        pihyst_model_reset(&m, NULL);
        pihyst_model_operators(&m, u, phi, N);
        for (i = 0; i < N; ++i) {
            real s = 0.5;
            for (k = 0; k < K; ++k) s += w[k] * phi[i * K + k];
            CHECK_NEAR(s, y_run[i], TOL(1e-10, F32_ULPS(2 * (K + 2), 64)));
        }
        memset(gram, 0, sizeof gram);
        memset(rhs, 0, sizeof rhs);
        memset(sums, 0, sizeof sums);
        pihyst_model_reset(&m, NULL);
        pihyst_model_gram(&m, u, d, 200, gram, rhs, sums);
        pihyst_model_gram(&m, u + 200, d + 200, N - 200, gram, rhs, sums);
        for (j = 0; j < K; ++j) {
            real sr = 0.0, ss = 0.0;
            for (i = 0; i < N; ++i) {
                sr += phi[i * K + j] * d[i];
                ss += phi[i * K + j];
            }
            CHECK_NEAR(rhs[j], sr, TOL(1e-8, 1e-4) * (1.0 + fabs(sr)));
            CHECK_NEAR(sums[j], ss, TOL(1e-8, 1e-4) * (1.0 + fabs(ss)));
            for (k = 0; k < K; ++k) {
                real g = 0.0;
                for (i = 0; i < N; ++i) g += phi[i * K + j] * phi[i * K + k];
                CHECK_NEAR(gram[j * K + k], g, TOL(1e-8, 1e-4) * (1.0 + fabs(g)));
            }
        }
    }
}

void run_model_tests(void)
{
    test_paper_classical();
    test_paper_multislope();
    test_multislope_r40_kinks();
    test_validation();
    test_params();
    test_pwl();
    test_identities();
}
