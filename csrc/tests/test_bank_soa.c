/* Tests of pihyst_compbank_* (the structure-of-arrays bank with the classical fast
 * path): on random classical channels (their own K, offsets, limits, slew limits, zero
 * weights) mixed with channels that take the exact path (multislope, pwl, w_0 = 0,
 * r_0 > 0, a state that is not 1-Lipschitz), on tracking signals, noise, NaN,
 * infinities and values out of reach, the bank gives the voltages and outputs of the
 * same channels run as separate compensators to rounding (1e-9 of the range in double),
 * the same flags and counts, bit for bit on the exact-path channels; every voltage lies
 * within its limits and slew limit; sync brings the compensators up to date; a short
 * work array and NULL are refused; an empty bank does nothing. */
#include "pihyst.h"
#include "test_util.h"

#include <stdio.h>
#include <string.h>

#define SOA_N 41 /* not a multiple of the lanes: a partial last group */
#define SOA_KMAX 20
#define SOA_TICKS 4000

static unsigned soa_lcg = 2024u;
static real soa_uniform(void) /* [0, 1) */
{
    soa_lcg = soa_lcg * 1103515245u + 12345u;
    return (real)(soa_lcg >> 8) / (real)(1u << 24);
}

typedef struct {
    pihyst_model m[SOA_N];
    pihyst_compensator c[SOA_N];
    real coef[SOA_N][PIHYST_COEF_LEN(SOA_KMAX)];
    real state[SOA_N][SOA_KMAX];
    real scratch[SOA_N][PIHYST_COMPENSATOR_SCRATCH_LEN(SOA_KMAX, 15) + 64];
} soa_channels;

/* parameters shared by both copies of a channel (the models point into them) */
static real soa_r[SOA_N][SOA_KMAX], soa_w[SOA_N][SOA_KMAX], soa_f0[SOA_N][SOA_KMAX];
static size_t soa_K[SOA_N];
static real soa_lo[SOA_N], soa_hi[SOA_N], soa_slew[SOA_N], soa_off[SOA_N];
static int soa_kind[SOA_N]; /* 0 classical fast, 1 multislope, 2 pwl, 3 w_0 = 0, 4 r_0 > 0,
                               5 classical with a state that is not 1-Lipschitz */

static const size_t soa_rs[3] = {0, 2, 6}, soa_fs[3] = {0, 2, 5};
static const real soa_rx[6] = {0, 150, 0, 40, 90, 150}, soa_ry[6] = {0, 150, 0, 5, 60, 80};
static const real soa_fx[5] = {0, 150, 0, 60, 150}, soa_fy[5] = {0, 150, 0, 50, 80};
static const real soa_r4[4] = {0, 20, 30, 40}, soa_w4[4] = {0.196, 0.026, 0.046, 0.028};
static const pihyst_shape soa_shape = {150.0, 0.8, 1.2, 0.5};

static void soa_params(void)
{
    size_t i, k;
    for (i = 0; i < SOA_N; ++i) {
        const size_t K = 1 + (size_t)(soa_uniform() * SOA_KMAX);
        real r = (real)0.0;
        soa_kind[i] = i % 9 == 4 ? 1 : i % 9 == 7 ? 2 : i == 10 ? 3 : i == 19 ? 4 : i == 23 ? 5 : 0;
        soa_K[i] = soa_kind[i] == 1 ? 4 : soa_kind[i] == 2 ? 2 : K;
        for (k = 0; k < soa_K[i]; ++k) {
            soa_r[i][k] = r;
            r += (real)(0.5 + 150.0 / (double)K * 2.0 * (double)soa_uniform());
            soa_w[i][k] = soa_uniform() < 0.15 ? (real)0.0 : (real)(0.1 * (double)soa_uniform());
            soa_f0[i][k] = (real)(40.0 * (double)soa_uniform() - 10.0);
        }
        soa_w[i][0] = (real)(0.1 + 0.3 * (double)soa_uniform());
        if (soa_kind[i] == 3) soa_w[i][0] = (real)0.0;
        if (soa_kind[i] == 4) soa_r[i][0] = (real)2.0;
        if (soa_kind[i] == 5) { /* not 1-Lipschitz until the voltage goes below ~100 */
            for (k = 0; k < soa_K[i]; ++k) soa_f0[i][k] = (real)0.0;
            soa_f0[i][soa_K[i] > 1] = (real)100.0;
        }
        soa_off[i] = (real)(4.0 * (double)soa_uniform() - 2.0);
        soa_lo[i] = i % 3 == 0 ? (real)0.0 : (real)(20.0 * (double)soa_uniform());
        soa_hi[i] = i % 4 == 0 ? (real)150.0 : (real)(120.0 + 30.0 * (double)soa_uniform());
        soa_slew[i] = i % 5 == 1 ? (real)(0.2 + 5.0 * (double)soa_uniform()) : (real)INFINITY;
    }
}

static void soa_init(soa_channels *ch)
{
    pihyst_pwl p;
    size_t i;
    p.rise_start = soa_rs; p.rise_x = soa_rx; p.rise_y = soa_ry;
    p.fall_start = soa_fs; p.fall_x = soa_fx; p.fall_y = soa_fy;
    for (i = 0; i < SOA_N; ++i) {
        pihyst_status s;
        switch (soa_kind[i]) {
        case 1:
            s = model_init(&ch->m[i], PIHYST_MULTISLOPE, 4, soa_r4, soa_w4, soa_off[i], 0.0, 150.0,
                           &soa_shape, NULL, ch->coef[i], ch->state[i], NULL);
            break;
        case 2:
            s = model_init(&ch->m[i], PIHYST_PWL, 2, NULL, soa_w[i], soa_off[i], 0.0, 150.0, NULL,
                           &p, ch->coef[i], ch->state[i], NULL);
            break;
        default:
            s = model_init(&ch->m[i], PIHYST_CLASSICAL, soa_K[i], soa_r[i], soa_w[i], soa_off[i],
                           0.0, 150.0, NULL, NULL, ch->coef[i], ch->state[i],
                           soa_kind[i] == 5 ? soa_f0[i] : NULL);
            break;
        }
        CHECK(s == PIHYST_OK);
        CHECK(pihyst_compensator_init(&ch->c[i], &ch->m[i], soa_lo[i], soa_hi[i], soa_slew[i],
                                      soa_lo[i] + (real)1.0, ch->scratch[i],
                                      sizeof ch->scratch[i] / sizeof(real)) == PIHYST_OK);
    }
}

/* desired value for channel i at tick t: tracking in stretches, noise, jumps, NaN,
 * infinities and values out of reach */
static real soa_desired(size_t i, size_t t, int noise)
{
    const real x = soa_uniform();
    if (x < 0.01) return NAN;
    if (x < 0.02) return x < 0.015 ? INFINITY : -INFINITY;
    if (x < 0.03) return (real)(x < 0.025 ? 1e30 : -1e30);
    if (x < 0.06) return (real)(80.0 * (double)soa_uniform() - 20.0); /* often out of reach */
    if (noise) return (real)(30.0 * (double)soa_uniform());
    if (x < 0.07) return soa_desired(i, t - 1, 0); /* the same value again: a hold */
    return (real)(12.0 + 10.0 * sin(0.013 * (double)t + (double)i) * cos(0.0031 * (double)t));
}

static real soa_work[PIHYST_COMPBANK_WORK_LEN(SOA_N, SOA_KMAX)];

static void test_compbank_equals_compensators(int noise)
{
    static soa_channels a, b;
    pihyst_compensator *ca[SOA_N];
    pihyst_compbank bank;
    real yd[SOA_N], u_bank[SOA_N], y_bank[SOA_N], u_prev[SOA_N];
    pihyst_flags f_bank[SOA_N];
    const real tol_u = TOL(1e-9, 2e-4) * (real)150.0, tol_y = TOL(1e-9, 2e-4) * (real)40.0;
    real worst_u = (real)0.0, worst_y = (real)0.0;
    size_t i, t, bad_flags = 0, bad_count = 0, bad_limits = 0, bad_exact = 0, n_fast = 0;
    soa_init(&a);
    soa_init(&b);
    for (i = 0; i < SOA_N; ++i) {
        ca[i] = &a.c[i];
        u_prev[i] = a.c[i].u_last;
        n_fast += soa_kind[i] == 0;
    }
    CHECK(pihyst_compbank_work_len(ca, SOA_N) <= sizeof soa_work / sizeof(real));
    CHECK(pihyst_compbank_init(&bank, ca, SOA_N, soa_work, sizeof soa_work / sizeof(real)) ==
          PIHYST_OK);
    CHECK(bank.n_fast == n_fast); /* the non-Lipschitz channel joins later */
    for (t = 0; t < SOA_TICKS; ++t) {
        size_t count, count_one = 0;
        for (i = 0; i < SOA_N; ++i) yd[i] = soa_desired(i, t, noise && t % 500 > 100);
        count = pihyst_compbank_compensate(&bank, yd, u_bank, y_bank, f_bank);
        for (i = 0; i < SOA_N; ++i) {
            pihyst_flags fl;
            const real u1 = pihyst_compensator_step(&b.c[i], yd[i], &fl), y1 = b.c[i].y_last;
            const real du = fabs(u_bank[i] - u1), dy = fabs(y_bank[i] - y1);
            count_one += fl != 0;
            bad_flags += fl != f_bank[i];
            if (du > worst_u) worst_u = du;
            if (dy > worst_y) worst_y = dy;
            if (soa_kind[i] >= 1 && soa_kind[i] <= 4 && (u_bank[i] != u1 || y_bank[i] != y1))
                ++bad_exact;
            if (!(u_bank[i] >= b.c[i].u_min && u_bank[i] <= b.c[i].u_max &&
                  fabs(u_bank[i] - u_prev[i]) <= b.c[i].max_step))
                ++bad_limits;
            u_prev[i] = u_bank[i];
        }
        bad_count += count != count_one;
    }
    CHECK(bad_flags == 0);
    CHECK(bad_count == 0);
    CHECK(bad_limits == 0);
    CHECK(bad_exact == 0);
    CHECK(worst_u <= tol_u);
    CHECK(worst_y <= tol_y);
    CHECK(bank.n_fast == n_fast + 1); /* the non-Lipschitz channel has joined */
    printf("compbank (%s): largest |du| %.3g, |dy| %.3g\n", noise ? "noise" : "tracking",
           (double)worst_u, (double)worst_y);
    /* sync: the compensators hold the bank's state; the bank goes on afterwards */
    pihyst_compbank_sync(&bank);
    for (i = 0; i < SOA_N; ++i) {
        size_t k;
        CHECK(a.c[i].u_last == u_prev[i]);
        for (k = 0; k < a.m[i].n_ops; ++k)
            CHECK_NEAR(a.state[i][k], b.state[i][k], TOL(1e-9, 2e-4) * 150.0);
    }
    for (i = 0; i < SOA_N; ++i) yd[i] = (real)(5.0 + 0.1 * (double)i);
    pihyst_compbank_compensate(&bank, yd, u_bank, NULL, NULL);
    for (i = 0; i < SOA_N; ++i)
        CHECK_NEAR(u_bank[i], pihyst_compensator_step(&b.c[i], yd[i], NULL), tol_u);
}

static void test_compbank_checks(void)
{
    static soa_channels a;
    pihyst_compensator *ca[SOA_N];
    pihyst_compbank bank;
    size_t i;
    real y0 = (real)1.0, u0 = (real)0.0;
    soa_init(&a);
    for (i = 0; i < SOA_N; ++i) ca[i] = &a.c[i];
    CHECK(pihyst_compbank_init(NULL, ca, SOA_N, soa_work, 100000) == PIHYST_ENULL);
    CHECK(pihyst_compbank_init(&bank, NULL, SOA_N, soa_work, 100000) == PIHYST_ENULL);
    CHECK(pihyst_compbank_init(&bank, ca, SOA_N, soa_work,
                               pihyst_compbank_work_len(ca, SOA_N) - 1) == PIHYST_ESCRATCH);
    /* an empty bank touches nothing */
    CHECK(pihyst_compbank_init(&bank, ca, 0, NULL, 0) == PIHYST_OK);
    CHECK(pihyst_compbank_compensate(&bank, &y0, &u0, NULL, NULL) == 0);
    CHECK(u0 == (real)0.0);
    pihyst_compbank_sync(&bank);
}

/* the structure-of-arrays model bank: bit for bit pihyst_model_step on every channel
 * (classical K <= 16 in the groups, the others by the single model), states after sync */
static void test_modelbank_equals_models(void)
{
    static soa_channels a, b;
    static real work[PIHYST_MODELBANK_WORK_LEN(SOA_N)];
    pihyst_model *ma[SOA_N];
    pihyst_modelbank bank;
    real u[SOA_N], y_bank[SOA_N], y_one[SOA_N], y0 = (real)1.0;
    size_t i, t, bad = 0, n_fast = 0;
    soa_init(&a);
    soa_init(&b);
    for (i = 0; i < SOA_N; ++i) {
        ma[i] = &a.m[i];
        n_fast += a.m[i].family == PIHYST_CLASSICAL && a.m[i].n_ops <= 16;
    }
    CHECK(pihyst_modelbank_work_len(ma, SOA_N) <= sizeof work / sizeof(real));
    CHECK(pihyst_modelbank_init(&bank, ma, SOA_N, work, sizeof work / sizeof(real)) ==
          PIHYST_OK);
    /* the groups need compiler vector extensions, which the core uses only where there
     * is a vector unit (pihyst_internal.h) */
#if defined(__GNUC__) && !defined(PIHYST_NO_VECTOR_EXT) && \
    (defined(__SSE2__) || defined(__ARM_NEON) || defined(__aarch64__))
    CHECK(bank.n_fast == n_fast && n_fast > 20);
#else
    CHECK(bank.n_fast == 0);
#endif
    for (t = 0; t < SOA_TICKS; ++t) {
        for (i = 0; i < SOA_N; ++i)
            u[i] = (real)(150.0 * (0.5 + 0.45 * sin(0.02 * (double)t + (double)i)) *
                          (soa_uniform() < 0.3 ? (double)soa_uniform() : 1.0));
        pihyst_modelbank_step(&bank, u, y_bank);
        for (i = 0; i < SOA_N; ++i) y_one[i] = pihyst_model_step(&b.m[i], u[i]);
        bad += memcmp(y_bank, y_one, sizeof y_bank) != 0;
    }
    CHECK(bad == 0);
    pihyst_modelbank_sync(&bank);
    for (i = 0; i < SOA_N; ++i)
        CHECK(memcmp(a.state[i], b.state[i], a.m[i].n_ops * sizeof(real)) == 0);
    CHECK(pihyst_modelbank_init(&bank, ma, SOA_N, work, pihyst_modelbank_work_len(ma, SOA_N) - 1)
          == PIHYST_ESCRATCH);
    CHECK(pihyst_modelbank_init(&bank, NULL, SOA_N, work, 100) == PIHYST_ENULL);
    CHECK(pihyst_modelbank_init(&bank, ma, 0, NULL, 0) == PIHYST_OK);
    pihyst_modelbank_step(&bank, &y0, NULL);
    pihyst_modelbank_sync(&bank);
}

/* signed zeros: a lane's padded operators must give what the single model's padding
 * gives (u = -0, offset -0 and weight -0 made the bank answer -0 where the model answers
 * +0; fuzz/corpus/model/regress-001) */
static void test_modelbank_signed_zero(void)
{
    static real work[PIHYST_MODELBANK_WORK_LEN(1)];
    const real zeros[2] = {(real)-0.0, (real)0.0};
    real r[1] = {(real)9.25}, w[1], coef[PIHYST_COEF_LEN(1)], state[1], y_bank, y_one;
    pihyst_model m;
    pihyst_model *ch[1] = {&m};
    pihyst_modelbank bank;
    pihyst_params p;
    size_t a, b, c;
    for (a = 0; a < 2; ++a)         /* weight */
        for (b = 0; b < 2; ++b)     /* offset */
            for (c = 0; c < 2; ++c) { /* input */
                memset(&p, 0, sizeof p);
                w[0] = zeros[a];
                p.family = PIHYST_CLASSICAL;
                p.n_ops = 1;
                p.thresholds = r;
                p.weights = w;
                p.offset = zeros[b];
                p.u_min = (real)-10.0;
                p.u_max = (real)10.0;
                CHECK(pihyst_model_init(&m, &p, coef, state) == PIHYST_OK);
                y_one = pihyst_model_step(&m, zeros[c]);
                pihyst_model_reset(&m, NULL);
                CHECK(pihyst_modelbank_init(&bank, ch, 1, work, sizeof work / sizeof(real)) ==
                      PIHYST_OK);
                pihyst_modelbank_step(&bank, &zeros[c], &y_bank);
                CHECK(memcmp(&y_bank, &y_one, sizeof y_one) == 0);
            }
}

void run_bank_soa_tests(void)
{
    test_modelbank_signed_zero();
    soa_params();
    test_modelbank_equals_models();
    test_compbank_equals_compensators(0);
    test_compbank_equals_compensators(1);
    test_compbank_checks();
}
