/* Tests of pihyst_bank_*: a bank of channels of every family (with their own limits,
 * slew limits and states) gives bit for bit the outputs of the same channels stepped
 * one by one, on tracking signals, noise, NaN, infinities and values out of reach; the
 * limits hold on every channel; NULL y/flags are allowed; an empty bank does nothing. */
#include "pihyst.h"
#include "test_util.h"

#include <string.h>

#define N_CH 6
#define N_TICKS 3000
#define MAX_K 16

static unsigned bank_lcg = 77u;
static real bank_uniform(void) /* [0, 1) */
{
    bank_lcg = bank_lcg * 1103515245u + 12345u;
    return (real)(bank_lcg >> 8) / (real)(1u << 24);
}

typedef struct {
    pihyst_model m[N_CH];
    pihyst_compensator c[N_CH];
    real coef[N_CH][PIHYST_COEF_LEN(MAX_K)];
    real state[N_CH][MAX_K];
    real scratch[N_CH][PIHYST_COMPENSATOR_SCRATCH_LEN(MAX_K, 15) + 64];
} channels;

static const size_t rs[4] = {0, 2, 4, 8}, fs[4] = {0, 2, 4, 7};
static const real rx[8] = {0, 150, 50, 60, 0, 40, 90, 150};
static const real ry[8] = {0, 150, 40, 50, 0, 5, 60, 80};
static const real fx[7] = {0, 150, 30, 40, 0, 60, 150};
static const real fy[7] = {0, 150, 40, 50, 0, 50, 80};
static const pihyst_shape shape = {150.0, 0.8, 1.2, 0.5};
static real r16[MAX_K], w16[MAX_K];
static const real r4[4] = {0, 20, 30, 40}, w4[4] = {0.196, 0.026, 0.046, 0.028};
static const real r3[3] = {0, 5, 30}, w3[3] = {0.5, 0.2, 0.1};

/* channel i: family, limits and slew limit of its own */
static void channels_init(channels *ch)
{
    pihyst_pwl p;
    size_t i;
    const real slew[N_CH] = {INFINITY, 3.0, INFINITY, 0.5, 10.0, INFINITY};
    const real lo[N_CH] = {0.0, 10.0, 0.0, 0.0, 20.0, 0.0};
    const real hi[N_CH] = {150.0, 120.0, 150.0, 150.0, 100.0, 150.0};
    for (i = 0; i < MAX_K; ++i) {
        r16[i] = (real)(9.0 * (double)i);
        w16[i] = (real)(0.05 + 0.01 * (double)(i % 5));
    }
    p.rise_start = rs; p.rise_x = rx; p.rise_y = ry;
    p.fall_start = fs; p.fall_x = fx; p.fall_y = fy;
    CHECK(model_init(&ch->m[0], PIHYST_CLASSICAL, MAX_K, r16, w16, 0.0, 0.0, 150.0, NULL, NULL,
                     ch->coef[0], ch->state[0], NULL) == PIHYST_OK);
    CHECK(model_init(&ch->m[1], PIHYST_CLASSICAL, 3, r3, w3, 1.5, 0.0, 150.0, NULL, NULL,
                     ch->coef[1], ch->state[1], NULL) == PIHYST_OK);
    CHECK(model_init(&ch->m[2], PIHYST_MULTISLOPE, 4, r4, w4, 0.0, 0.0, 150.0, &shape, NULL,
                     ch->coef[2], ch->state[2], NULL) == PIHYST_OK);
    CHECK(model_init(&ch->m[3], PIHYST_PWL, 3, NULL, w3, 0.0, 0.0, 150.0, NULL, &p,
                     ch->coef[3], ch->state[3], NULL) == PIHYST_OK);
    CHECK(model_init(&ch->m[4], PIHYST_MULTISLOPE, 4, r4, w4, -2.0, 0.0, 150.0, &shape, NULL,
                     ch->coef[4], ch->state[4], NULL) == PIHYST_OK);
    CHECK(model_init(&ch->m[5], PIHYST_CLASSICAL, 5, r16, w16, 0.0, 0.0, 150.0, NULL, NULL,
                     ch->coef[5], ch->state[5], NULL) == PIHYST_OK);
    for (i = 0; i < N_CH; ++i)
        CHECK(pihyst_compensator_init(&ch->c[i], &ch->m[i], lo[i], hi[i], slew[i], lo[i],
                                      ch->scratch[i], sizeof ch->scratch[i] / sizeof(real)) ==
              PIHYST_OK);
}

static int same_bits(const void *a, const void *b, size_t n) { return memcmp(a, b, n) == 0; }

/* desired value for channel i at tick t: tracking most of the time, jumps, noise,
 * NaN, infinities and values far out of reach now and then */
static real desired(size_t i, size_t t)
{
    real x = bank_uniform();
    if (x < 0.01) return NAN;
    if (x < 0.02) return x < 0.015 ? INFINITY : -INFINITY;
    if (x < 0.03) return (real)(x < 0.025 ? 1e30 : -1e30);
    if (x < 0.15) return (real)(40.0 * bank_uniform() - 5.0);
    return (real)(15.0 + 12.0 * sin(0.01 * (double)t + (double)i) * cos(0.003 * (double)t));
}

static void test_bank_compensate_equals_channels(void)
{
    static channels a, b;
    pihyst_compensator *ca[N_CH];
    real yd[N_CH], u_bank[N_CH], y_bank[N_CH], u_one[N_CH], y_one[N_CH];
    pihyst_flags f_bank[N_CH], f_one[N_CH];
    size_t i, t, count, count_one, bad = 0, bad_limits = 0;
    channels_init(&a);
    channels_init(&b);
    for (i = 0; i < N_CH; ++i) ca[i] = &a.c[i];
    for (t = 0; t < N_TICKS; ++t) {
        for (i = 0; i < N_CH; ++i) yd[i] = desired(i, t);
        count = pihyst_bank_compensate(ca, N_CH, yd, u_bank, y_bank, f_bank);
        count_one = 0;
        for (i = 0; i < N_CH; ++i) {
            const real u_prev = b.c[i].u_last;
            u_one[i] = pihyst_compensator_step(&b.c[i], yd[i], &f_one[i]);
            y_one[i] = b.c[i].y_last;
            count_one += f_one[i] != 0;
            if (!(u_one[i] >= b.c[i].u_min && u_one[i] <= b.c[i].u_max &&
                  fabs(u_one[i] - u_prev) <= b.c[i].max_step))
                ++bad_limits;
        }
        if (!same_bits(u_bank, u_one, sizeof u_bank) || !same_bits(y_bank, y_one, sizeof y_bank) ||
            !same_bits(f_bank, f_one, sizeof f_bank) || count != count_one)
            ++bad;
    }
    CHECK(bad == 0);
    CHECK(bad_limits == 0);
    for (i = 0; i < N_CH; ++i)
        CHECK(same_bits(a.state[i], b.state[i], a.m[i].n_ops * sizeof(real)));
    /* y and flags may be NULL */
    for (i = 0; i < N_CH; ++i) yd[i] = (real)(3.0 + (double)i);
    pihyst_bank_compensate(ca, N_CH, yd, u_bank, NULL, NULL);
    for (i = 0; i < N_CH; ++i) u_one[i] = pihyst_compensator_step(&b.c[i], yd[i], NULL);
    CHECK(same_bits(u_bank, u_one, sizeof u_bank));
    /* an empty bank touches nothing */
    CHECK(pihyst_bank_compensate(ca, 0, yd, NULL, NULL, NULL) == 0);
}

static void test_bank_step_equals_models(void)
{
    static channels a, b;
    pihyst_model *ma[N_CH];
    real u[N_CH], y_bank[N_CH], y_one[N_CH];
    size_t i, t, bad = 0;
    channels_init(&a);
    channels_init(&b);
    for (i = 0; i < N_CH; ++i) ma[i] = &a.m[i];
    for (t = 0; t < N_TICKS; ++t) {
        for (i = 0; i < N_CH; ++i)
            u[i] = (real)(150.0 * (0.5 + 0.45 * sin(0.02 * (double)t + (double)i)) *
                          (bank_uniform() < 0.2 ? bank_uniform() : 1.0));
        pihyst_bank_step(ma, N_CH, u, y_bank);
        for (i = 0; i < N_CH; ++i) y_one[i] = pihyst_model_step(&b.m[i], u[i]);
        if (!same_bits(y_bank, y_one, sizeof y_bank)) ++bad;
    }
    CHECK(bad == 0);
    for (i = 0; i < N_CH; ++i)
        CHECK(same_bits(a.state[i], b.state[i], a.m[i].n_ops * sizeof(real)));
    pihyst_bank_step(ma, 0, u, NULL);
}

void run_bank_tests(void)
{
    test_bank_compensate_equals_channels();
    test_bank_step_equals_models();
}
