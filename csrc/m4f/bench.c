/* bench.c - instructions per sample of every model kind on the Cortex-M4F (make -C csrc
 * bench-m4f, on QEMU's mps2-an386 with -icount shift=0).
 *
 * With -icount shift=0 QEMU advances its virtual clock by 1 ns per instruction executed,
 * and the SysTick counter (processor clock, 25 MHz on this board) counts that clock: one
 * tick is 40 instructions. The program calibrates this on a loop of known length and
 * prints the figures in instructions, not cycles (docs/c-core.md says what that means on
 * a real part).
 *
 * For each model: the model step and the compensator step, in single precision (the
 * model with creep: its _f32 lags too), each
 *   tracking: the mean over a 1 Hz full-range voltage sine sampled at 1 kHz (the
 *             compensator: the model's output for that sine as the desired value);
 *   worst:    the most expensive single sample of a jump to a random value every sample
 *             (a voltage in the input range; a desired value in the output range), to
 *             one SysTick tick (40 instructions).
 * Each line: "m4f: NAME PATH N instructions/sample". */
#include "pihyst.h"
#include "pihyst_boucwen.h"
#include "pihyst_bw_creep.h"
#include "pihyst_creep.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>

#include "kp_p885.h"
#include "kp_smart.h"
#include "kp_p885_creep_flag.h"
#if KP_P885_HAS_CREEP
#include "kp_p885_creep.h"
#endif

#define SYST_CSR (*(volatile uint32_t *)0xE000E010u)
#define SYST_RVR (*(volatile uint32_t *)0xE000E014u)
#define SYST_CVR (*(volatile uint32_t *)0xE000E018u)
#define TICK_MASK 0xFFFFFFu

#define N_TRACK 2000 /* 2 s at 1 kHz: two periods of the sine */
#define N_WORST 400

static double instr_per_tick;
static double read_overhead; /* instructions of one pair of counter reads */

static void systick_start(void)
{
    SYST_RVR = TICK_MASK;
    SYST_CVR = 0;
    SYST_CSR = 5u; /* enabled, processor clock, no interrupt */
}

/* the counter counts down: elapsed ticks from a to b */
static uint32_t elapsed(uint32_t a, uint32_t b) { return (a - b) & TICK_MASK; }

/* 2 n instructions: subs + bne per iteration */
static void __attribute__((noinline)) known_loop(uint32_t n)
{
    __asm__ volatile("1: subs %0, %0, #1\n\tbne 1b" : "+r"(n) : : "cc");
}

static void calibrate(void)
{
    const uint32_t n = 1000000u;
    uint32_t a, b, worst = 0;
    int i;
    a = SYST_CVR;
    known_loop(n);
    b = SYST_CVR;
    instr_per_tick = 2.0 * n / (double)elapsed(a, b);
    /* the pair of reads around an empty sample, averaged over many */
    a = SYST_CVR;
    for (i = 0; i < 100000; ++i) {
        uint32_t x = SYST_CVR, y = SYST_CVR;
        worst += elapsed(x, y);
    }
    b = SYST_CVR;
    (void)worst;
    read_overhead = (double)elapsed(a, b) * instr_per_tick / 100000.0;
    printf("m4f: calibration: %.2f instructions per SysTick tick (expected 40)\n",
           instr_per_tick);
}

static void report(const char *name, const char *path, double instructions)
{
    printf("m4f: %s %s %.0f instructions/sample\n", name, path, instructions);
}

/* the mean of a block of n samples of STMT(t), loop included */
#define TRACK(result, n, STMT)                                                             \
    do {                                                                                   \
        size_t t_;                                                                         \
        uint32_t a_ = SYST_CVR, b_;                                                        \
        for (t_ = 0; t_ < (n); ++t_) { STMT; }                                             \
        b_ = SYST_CVR;                                                                     \
        (result) = (double)elapsed(a_, b_) * instr_per_tick / (double)(n);                \
    } while (0)

/* the most expensive single sample of n */
#define WORST(result, n, STMT)                                                             \
    do {                                                                                   \
        size_t t_;                                                                         \
        uint32_t w_ = 0;                                                                   \
        for (t_ = 0; t_ < (n); ++t_) {                                                     \
            uint32_t a_ = SYST_CVR, b_;                                                    \
            STMT;                                                                          \
            b_ = SYST_CVR;                                                                 \
            if (elapsed(a_, b_) > w_) w_ = elapsed(a_, b_);                                \
        }                                                                                  \
        (result) = (double)w_ * instr_per_tick - read_overhead;                           \
    } while (0)

static uint32_t lcg = 12345u;
static float uniform(void)
{
    lcg = lcg * 1664525u + 1013904223u;
    return (float)(lcg >> 8) / 16777216.0f;
}

/* each row draws its own numbers (seeded by its name, FNV-1a): a row's figures do not
 * depend on which rows ran before it */
static void seed_row(const char *name)
{
    uint32_t h = 2166136261u;
    for (; *name; ++name) h = (h ^ (uint8_t)*name) * 16777619u;
    lcg = h;
}

/* signals */
static float u_track[N_TRACK], u_jump[N_WORST], y_track[N_TRACK], y_jump[N_WORST];
static volatile float sink;

static void make_voltages(float lo, float hi)
{
    size_t t;
    for (t = 0; t < N_TRACK; ++t)
        u_track[t] = 0.5f * (lo + hi) -
                     0.5f * (hi - lo) * cosf(6.2831853f * (float)t / 1000.0f);
    for (t = 0; t < N_WORST; ++t) u_jump[t] = lo + (hi - lo) * uniform();
}

/* a PI model (single precision): model step and compensator, tracking and worst */
static void bench_pi(const char *name, pihyst_model_f32 *m, float *scratch, size_t scratch_len)
{
    pihyst_compensator_f32 c;
    pihyst_flags fl;
    float y_lo = INFINITY, y_hi = -INFINITY;
    double r;
    size_t t;
    seed_row(name);
    make_voltages(m->u_min, m->u_max);
    pihyst_model_reset_f32(m, NULL);
    TRACK(r, N_TRACK, sink = pihyst_model_step_f32(m, u_track[t_]));
    report(name, "model-tracking", r);
    WORST(r, N_WORST, sink = pihyst_model_step_f32(m, u_jump[t_]));
    report(name, "model-worst", r);
    /* the desired values: the model's outputs for the sine, and random ones in its range */
    pihyst_model_reset_f32(m, NULL);
    for (t = 0; t < N_TRACK; ++t) {
        y_track[t] = pihyst_model_step_f32(m, u_track[t]);
        y_lo = y_track[t] < y_lo ? y_track[t] : y_lo;
        y_hi = y_track[t] > y_hi ? y_track[t] : y_hi;
    }
    for (t = 0; t < N_WORST; ++t) y_jump[t] = y_lo + (y_hi - y_lo) * uniform();
    pihyst_model_reset_f32(m, NULL);
    if (pihyst_compensator_init_f32(&c, m, NAN, NAN, INFINITY, u_track[0], scratch,
                                    scratch_len) != PIHYST_OK) {
        printf("m4f: %s: compensator init failed\n", name);
        return;
    }
    TRACK(r, N_TRACK, sink = pihyst_compensator_step_f32(&c, y_track[t_], &fl));
    report(name, "compensator-tracking", r);
    WORST(r, N_WORST, sink = pihyst_compensator_step_f32(&c, y_jump[t_], &fl));
    report(name, "compensator-worst", r);
}

#define MAXK 64
static float r_buf[MAXK], w_buf[MAXK], coef_buf[PIHYST_COEF_LEN(MAXK)], state_buf[MAXK];
static float scratch_buf[PIHYST_COMPENSATOR_SCRATCH_LEN_F32(MAXK, 16 * 5)];

static void bench_classical(size_t K)
{
    char name[32];
    pihyst_model_f32 m;
    pihyst_params_f32 p = {.family = PIHYST_CLASSICAL, .n_ops = K, .thresholds = r_buf,
                           .weights = w_buf, .u_min = 0.0f, .u_max = 150.0f};
    size_t k;
    snprintf(name, sizeof name, "classical-K%u", (unsigned)K);
    seed_row(name);
    for (k = 0; k < K; ++k) {
        r_buf[k] = 150.0f * (float)k / (float)K;
        w_buf[k] = 0.02f + 0.1f * uniform();
    }
    if (pihyst_model_init_f32(&m, &p, coef_buf, state_buf) != PIHYST_OK) return;
    bench_pi(name, &m, scratch_buf, sizeof scratch_buf / sizeof *scratch_buf);
}

/* the paper's Table 1 multislope model (examples/paper_table1_multislope.json) */
static void bench_multislope(void)
{
    static const float r[4] = {0.0f, 20.0f, 30.0f, 40.0f};
    static const float w[4] = {0.196f, 0.026f, 0.046f, 0.028f};
    pihyst_model_f32 m;
    pihyst_params_f32 p = {.family = PIHYST_MULTISLOPE, .n_ops = 4, .thresholds = r,
                           .weights = w, .u_min = 0.0f, .u_max = 150.0f,
                           .shape = {.U = 150.0f, .a = 0.8f, .b = 1.2f, .h = 0.5f}};
    if (pihyst_model_init_f32(&m, &p, coef_buf, state_buf) != PIHYST_OK) return;
    bench_pi("multislope-K4", &m, scratch_buf, sizeof scratch_buf / sizeof *scratch_buf);
}

/* a generic piecewise-linear model: 16 operators, polylines of 5 points (not saturated
 * ramps, so the generic paths): R_k(u) = P(u - r_k), F_k(u) = P(u + r_k), P convex */
static void bench_pwl(void)
{
    enum { K = 16, NP = 5 };
    static const float px[NP] = {-200.0f, 0.0f, 50.0f, 100.0f, 350.0f};
    static const float py[NP] = {-100.0f, 0.0f, 30.0f, 80.0f, 380.0f};
    static size_t st[K + 1];
    static float rx[K * NP], ry[K * NP], fx[K * NP], fy[K * NP];
    pihyst_model_f32 m;
    pihyst_params_f32 p = {.family = PIHYST_PWL, .n_ops = K, .weights = w_buf,
                           .u_min = 0.0f, .u_max = 150.0f};
    size_t k, i;
    seed_row("pwl-K16");
    for (k = 0; k <= K; ++k) st[k] = NP * k;
    for (k = 0; k < K; ++k) {
        const float rk = 75.0f * (float)k / (float)K;
        for (i = 0; i < NP; ++i) {
            rx[NP * k + i] = px[i] + rk;
            fx[NP * k + i] = px[i] - rk;
            ry[NP * k + i] = fy[NP * k + i] = py[i] / 150.0f;
        }
        w_buf[k] = 0.02f + 0.1f * uniform();
    }
    p.pwl.rise_start = st; p.pwl.rise_x = rx; p.pwl.rise_y = ry;
    p.pwl.fall_start = st; p.pwl.fall_x = fx; p.pwl.fall_y = fy;
    if (pihyst_model_init_f32(&m, &p, coef_buf, state_buf) != PIHYST_OK) {
        printf("m4f: pwl: init failed\n");
        return;
    }
    bench_pi("pwl-K16", &m, scratch_buf, sizeof scratch_buf / sizeof *scratch_buf);
}

static void bench_kp(void)
{
    static pihyst_model_f32 m;
    char name[48];
    if (kp_p885_init(&m) != PIHYST_OK) return;
    snprintf(name, sizeof name, "kp-P885-K%u", (unsigned)KP_P885_N_OPS);
    bench_pi(name, &m, kp_p885_scratch, sizeof kp_p885_scratch / sizeof *kp_p885_scratch);
    if (kp_smart_init(&m) != PIHYST_OK) return;
    snprintf(name, sizeof name, "kp-SmartHysteresis-K%u", (unsigned)KP_SMART_N_OPS);
    bench_pi(name, &m, kp_smart_scratch, sizeof kp_smart_scratch / sizeof *kp_smart_scratch);
}

/* the Bouc-Wen model of examples/firmware/boucwen_loop.c (n = 1), single precision; and
 * one with n = 1.5 (every slope evaluation a powf) */
static const pihyst_bw_params_f32 bw_loop_params = {
    .beta = 5.0f, .gamma = 1.0f, .n = 1.0f, .hysteretic = -8.0f, .linear = 40.0f,
    .offset = 0.3f, .u_min = 0.0f, .u_max = 150.0f};
static const pihyst_bw_params_f32 bw_n15_params = {
    .beta = 4.0f, .gamma = -2.0f, .n = 1.5f, .hysteretic = 5.0f, .linear = 10.0f,
    .quadratic = 3.0f, .offset = 0.5f, .u_min = 0.0f, .u_max = 150.0f};

static void bench_boucwen(const char *name, const pihyst_bw_params_f32 *params)
{
    char slewed[48];
    pihyst_bw_model_f32 m;
    pihyst_bw_compensator_f32 c;
    pihyst_flags fl;
    float y_lo = INFINITY, y_hi = -INFINITY;
    double r;
    size_t t;
    if (pihyst_bw_init_f32(&m, params) != PIHYST_OK) return;
    seed_row(name);
    make_voltages(0.0f, 150.0f);
    TRACK(r, N_TRACK, sink = pihyst_bw_step_f32(&m, u_track[t_]));
    report(name, "model-tracking", r);
    WORST(r, N_WORST, sink = pihyst_bw_step_f32(&m, u_jump[t_]));
    report(name, "model-worst", r);
    pihyst_bw_reset_f32(&m, 0.0f, 0.0f);
    for (t = 0; t < N_TRACK; ++t) {
        y_track[t] = pihyst_bw_step_f32(&m, u_track[t]);
        y_lo = y_track[t] < y_lo ? y_track[t] : y_lo;
        y_hi = y_track[t] > y_hi ? y_track[t] : y_hi;
    }
    for (t = 0; t < N_WORST; ++t) y_jump[t] = y_lo + (y_hi - y_lo) * uniform();
    pihyst_bw_reset_f32(&m, 0.0f, 0.0f);
    if (pihyst_bw_compensator_init_f32(&c, &m, NAN, NAN, INFINITY, 0.0f) != PIHYST_OK) return;
    TRACK(r, N_TRACK, sink = pihyst_bw_compensator_step_f32(&c, y_track[t_], &fl));
    report(name, "compensator-tracking", r);
    WORST(r, N_WORST, sink = pihyst_bw_compensator_step_f32(&c, y_jump[t_], &fl));
    report(name, "compensator-worst", r);
    /* with a slew limit of 0.5 V per sample: a sample moves at most 0.5 V, one substep */
    snprintf(slewed, sizeof slewed, "%s-slew-0.5V", name);
    pihyst_bw_reset_f32(&m, 0.0f, 0.0f);
    if (pihyst_bw_compensator_init_f32(&c, &m, NAN, NAN, 0.5f, 0.0f) != PIHYST_OK) return;
    TRACK(r, N_TRACK, sink = pihyst_bw_compensator_step_f32(&c, y_track[t_], &fl));
    report(slewed, "compensator-tracking", r);
    WORST(r, N_WORST, sink = pihyst_bw_compensator_step_f32(&c, y_jump[t_], &fl));
    report(slewed, "compensator-worst", r);
    /* steps between 10 % and 90 % of the output range every 500 samples, slewed: most
     * samples ramp towards a target beyond the slew window */
    for (t = 0; t < N_TRACK; ++t)
        y_track[t] = y_lo + (y_hi - y_lo) * ((t / 500) % 2 ? 0.9f : 0.1f);
    TRACK(r, N_TRACK, sink = pihyst_bw_compensator_step_f32(&c, y_track[t_], &fl));
    report(slewed, "compensator-steps", r);
}

/* the same Bouc-Wen model with three creep lags (0.3, 3, 30 s at 1 kHz), single
 * precision: the _f32 lags and pihyst_bw_creep_compensator_step_f32 (pihyst_bw_creep_f32.c) */
static void bench_bw_creep(void)
{
    static const float tau[3] = {0.3f, 3.0f, 30.0f}, gain[3] = {0.02f, 0.035f, 0.015f};
    float alpha[3], state[3], h0;
    pihyst_bw_model_f32 m;
    pihyst_bw_compensator_f32 c;
    pihyst_creep_f32 cr;
    pihyst_flags fl;
    float y_lo = INFINITY, y_hi = -INFINITY;
    double r;
    size_t t;
    if (pihyst_bw_init_f32(&m, &bw_loop_params) != PIHYST_OK ||
        pihyst_creep_init_f32(&cr, 3, tau, gain, 0.001f, alpha, state, NULL) != PIHYST_CREEP_OK) {
        printf("m4f: bouc-wen-creep: init failed\n");
        return;
    }
    seed_row("bouc-wen-creep");
    make_voltages(0.0f, 150.0f);
    h0 = pihyst_bw_output_f32(&m, m.u, m.z);
    pihyst_creep_settle_f32(&cr, h0);
    TRACK(r, N_TRACK, sink = pihyst_creep_step_f32(&cr, pihyst_bw_step_f32(&m, u_track[t_])));
    report("bouc-wen-creep", "model-tracking", r);
    WORST(r, N_WORST, sink = pihyst_creep_step_f32(&cr, pihyst_bw_step_f32(&m, u_jump[t_])));
    report("bouc-wen-creep", "model-worst", r);
    pihyst_bw_reset_f32(&m, 0.0f, 0.0f);
    pihyst_creep_settle_f32(&cr, h0);
    for (t = 0; t < N_TRACK; ++t) {
        y_track[t] = pihyst_creep_step_f32(&cr, pihyst_bw_step_f32(&m, u_track[t]));
        y_lo = y_track[t] < y_lo ? y_track[t] : y_lo;
        y_hi = y_track[t] > y_hi ? y_track[t] : y_hi;
    }
    for (t = 0; t < N_WORST; ++t) y_jump[t] = y_lo + (y_hi - y_lo) * uniform();
    pihyst_bw_reset_f32(&m, 0.0f, 0.0f);
    if (pihyst_bw_compensator_init_f32(&c, &m, NAN, NAN, INFINITY, 0.0f) != PIHYST_OK) return;
    pihyst_creep_settle_f32(&cr, c.y_last);
    TRACK(r, N_TRACK,
          sink = pihyst_bw_creep_compensator_step_f32(&cr, &c, -1.0f, y_track[t_], NULL, &fl));
    report("bouc-wen-creep", "compensator-tracking", r);
    WORST(r, N_WORST,
          sink = pihyst_bw_creep_compensator_step_f32(&cr, &c, -1.0f, y_jump[t_], NULL, &fl));
    report("bouc-wen-creep", "compensator-worst", r);
}

#if KP_P885_HAS_CREEP
/* the P-885 model with its creep lags, as the default fit gives it, in single precision:
 * the hysteresis model of kp_p885.h and the lags of kp_p885_creep.h (the same model
 * exported with --float: its kp_p885_creep_creep_init wires up the _f32 lags,
 * pihyst_creep_f32.c) */
static void bench_creep(void)
{
    static pihyst_model_f32 m;
    static pihyst_compensator_f32 c;
    pihyst_creep_f32 cr;
    char name[48], lags[48];
    pihyst_flags fl;
    float y_lo = INFINITY, y_hi = -INFINITY, h0;
    double r;
    size_t t;
    if (kp_p885_init(&m) != PIHYST_OK ||
        kp_p885_creep_creep_init(&cr, 0.0f) != PIHYST_CREEP_OK) {
        printf("m4f: creep: init failed\n");
        return;
    }
    snprintf(name, sizeof name, "kp-P885-K%u-creep", (unsigned)KP_P885_N_OPS);
    snprintf(lags, sizeof lags, "creep-lags-%u", (unsigned)KP_P885_CREEP_CREEP_LAGS);
    seed_row(name);
    make_voltages(m.u_min, m.u_max);
    h0 = pihyst_model_step_f32(&m, u_track[0]);
    pihyst_model_reset_f32(&m, kp_p885_initial_state);
    pihyst_creep_settle_f32(&cr, h0);
    TRACK(r, N_TRACK, sink = pihyst_creep_step_f32(&cr, pihyst_model_step_f32(&m, u_track[t_])));
    report(name, "model-tracking", r);
    WORST(r, N_WORST, sink = pihyst_creep_step_f32(&cr, pihyst_model_step_f32(&m, u_jump[t_])));
    report(name, "model-worst", r);
    pihyst_model_reset_f32(&m, kp_p885_initial_state);
    pihyst_creep_settle_f32(&cr, h0);
    for (t = 0; t < N_TRACK; ++t) {
        y_track[t] = pihyst_creep_step_f32(&cr, pihyst_model_step_f32(&m, u_track[t]));
        y_lo = y_track[t] < y_lo ? y_track[t] : y_lo;
        y_hi = y_track[t] > y_hi ? y_track[t] : y_hi;
    }
    for (t = 0; t < N_WORST; ++t) y_jump[t] = y_lo + (y_hi - y_lo) * uniform();
    pihyst_model_reset_f32(&m, kp_p885_initial_state);
    if (pihyst_compensator_init_f32(&c, &m, NAN, NAN, INFINITY, u_track[0], kp_p885_scratch,
                                    sizeof kp_p885_scratch / sizeof *kp_p885_scratch) !=
        PIHYST_OK)
        return;
    pihyst_creep_settle_f32(&cr, c.y_last);
    TRACK(r, N_TRACK,
          sink = pihyst_creep_compensator_step_f32(&cr, &c, -1.0f, y_track[t_], NULL, &fl));
    report(name, "compensator-tracking", r);
    WORST(r, N_WORST,
          sink = pihyst_creep_compensator_step_f32(&cr, &c, -1.0f, y_jump[t_], NULL, &fl));
    report(name, "compensator-worst", r);
    /* the lags alone (what the creep adds to the hysteresis model) */
    TRACK(r, N_TRACK, sink = pihyst_creep_step_f32(&cr, y_track[t_]));
    report(lags, "model-tracking", r);
    TRACK(r, N_TRACK, sink = pihyst_creep_target_f32(&cr, y_track[t_]));
    report(lags, "compensator-target", r);
}
#endif

int main(void)
{
    systick_start();
    calibrate();
    bench_classical(4);
    bench_classical(16);
    bench_classical(64);
    bench_multislope();
    bench_pwl();
    bench_kp();
    bench_boucwen("bouc-wen", &bw_loop_params);
    bench_boucwen("bouc-wen-n1.5", &bw_n15_params);
    bench_bw_creep();
#if KP_P885_HAS_CREEP
    bench_creep();
#endif
    return 0;
}
