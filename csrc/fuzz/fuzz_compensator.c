/* fuzz_compensator.c - libFuzzer harness of pihyst_compensator_*, in double and single
 * precision.
 *
 * Input: a model (fuzz_common.h, weights mostly >= 0), the compensator's limits, slew
 * limit, initial voltage and scratch length, then operations: step with a desired
 * output (NaN, infinities and huge values included), flush (the same samples through
 * a second compensator's run), reset. Three copies of the model: A, stepped by
 * compensator `ca` one sample at a time; B, whose state array is deliberately off a
 * cache line, run by compensator `cb` in blocks; and a plain model R that is stepped
 * with every voltage `ca` chooses. Invariants:
 *   - init and reset return status codes of pihyst.h; a short scratch is refused;
 *     A and B agree on every status;
 *   - every voltage is finite, inside [u_min, u_max] and within max_step of the last
 *     (the difference computed in the working precision, as pihyst.h promises);
 *   - the flags are PIHYST_COMP_* bits; NaN is flagged exactly when the desired value
 *     is NaN, and holds the voltage; a saturation flag puts the voltage at its limit,
 *     a slew flag moves it by max_step (to an ulp);
 *   - step equals run and the bank: cb's blocks (through run, or sample by sample
 *     through pihyst_bank_compensate) give ca's voltages, outputs and flags bit for bit,
 *     and both return the number of flagged samples;
 *   - y_last equals a separate model: R's output for the chosen voltage (every other
 *     sample through pihyst_bank_step) is ca.y_last bit for bit, and model A's state array equals R's after every call;
 *   - a sample without flags meets the desired value: |y_last - y_d| <= 16 tol plus the
 *     output change of a few ulps of voltage at the steepest slope, plus underflow
 *     (when sane);
 *   - the structure-of-arrays bank (pihyst_compbank, one channel: a fourth copy C of the
 *     model with its compensator, reset with A): the same limits, slew limit and flag
 *     invariants, and a separate model R2 stepped with its voltages meets every unflagged
 *     desired value to 16 tol (sum w / w_0) plus the ulps above (its classical fast path
 *     inverts through 1 / w_0); after pihyst_compbank_sync the compensator holds the
 *     bank's last voltage.
 * Build and run: make -C csrc fuzz (see docs/c-core.md). */
#include "fuzz_common.h"

#define N_MAX 512
#define SCRATCH_MAX PIHYST_COMPENSATOR_SCRATCH_LEN(FUZZ_KMAX, 2 * FUZZ_KMAX * FUZZ_PMAX)

typedef struct {
    real yd[N_MAX], u[N_MAX], y[N_MAX];
    pihyst_flags fl[N_MAX];
    size_t n;
} samples;

/* B runs the samples ca has stepped since the last flush, through run or (bank != 0)
 * through pihyst_bank_compensate one sample at a time; both must agree */
static void flush(pihyst_compensator *cb, samples *ref, int bank)
{
    static real u[N_MAX], y[N_MAX];
    static pihyst_flags fl[N_MAX];
    size_t t, flagged = 0, count = 0;
    if (ref->n == 0) return;
    if (bank) {
        pihyst_compensator *const channels[1] = {cb};
        for (t = 0; t < ref->n; ++t)
            count += pihyst_bank_compensate(channels, 1, &ref->yd[t], &u[t], &y[t], &fl[t]);
    } else {
        count = pihyst_compensator_run(cb, ref->yd, u, y, fl, ref->n);
    }
    for (t = 0; t < ref->n; ++t) flagged += ref->fl[t] != 0;
    REQUIRE(count == flagged);
    REQUIRE(same_bits(u, ref->u, ref->n));
    REQUIRE(same_bits(y, ref->y, ref->n));
    REQUIRE(memcmp(fl, ref->fl, ref->n) == 0);
    ref->n = 0;
}

static real bank_last_u; /* the bank's last voltage */

/* one tick of the one-channel structure-of-arrays bank on compensator cc; mr2 is a
 * separate model stepped with its voltages */
static void step_bank(pihyst_compbank *bank, pihyst_compensator *cc, pihyst_model *mr2,
                      const fuzz_params *f, real yd, double sum_w, size_t steps)
{
    const real u_p = bank_last_u;
    real u, y;
    pihyst_flags fl = 0xff;
    const size_t count = pihyst_compbank_compensate(bank, &yd, &u, &y, &fl);
    const real y_r = pihyst_model_step(mr2, u);
    bank_last_u = u;
    REQUIRE(count == (fl != 0));
    REQUIRE(isfinite(u) && u >= cc->u_min && u <= cc->u_max);
    REQUIRE(fabs((double)(real)(u - u_p)) <= (double)cc->max_step);
    REQUIRE((fl & ~(PIHYST_COMP_SAT_LOW | PIHYST_COMP_SAT_HIGH | PIHYST_COMP_NAN |
                    PIHYST_COMP_SLEW)) == 0);
    REQUIRE(!(fl & PIHYST_COMP_NAN) == !isnan(yd));
    if (isnan(yd)) REQUIRE(fl == PIHYST_COMP_NAN && u == u_p);
    /* out of reach: at the limit, or on the way there when the slew limit cut it short */
    if (fl & PIHYST_COMP_SAT_LOW) REQUIRE(u == cc->u_min || (fl & PIHYST_COMP_SLEW));
    if (fl & PIHYST_COMP_SAT_HIGH) REQUIRE(u == cc->u_max || (fl & PIHYST_COMP_SLEW));
    if (fl == 0 && sane(f) && f->w[0] > 0.0) {
        const double ulp_y =
            8.0 * FUZZ_EPS * (fabs((double)u) + fabs((double)u_p) + 1.0) * f->max_slope * sum_w +
            ((double)f->p.n_ops + 2.0) * FUZZ_TINY;
        const double amp = bank->n_fast ? sum_w / (double)f->w[0] : 1.0;
        REQUIRE(fabs((double)y_r - (double)yd) <= 16.0 * (double)cc->tol * amp + ulp_y);
    }
    if (steps % 64 == 0) {
        pihyst_compbank_sync(bank);
        REQUIRE(cc->u_last == u);
    }
}

static void check(const uint8_t *data, size_t size)
{
    reader in = {data, size};
    static fuzz_params f;
    static real scratch_a[SCRATCH_MAX], scratch_b[SCRATCH_MAX], reset_state[FUZZ_KMAX];
    static real state_b_buf[FUZZ_KMAX + 32];
    static samples ref;
    real coef_a[PIHYST_COEF_LEN(FUZZ_KMAX)], coef_b[PIHYST_COEF_LEN(FUZZ_KMAX)];
    real coef_r[PIHYST_COEF_LEN(FUZZ_KMAX)], state_a[FUZZ_KMAX], state_r[FUZZ_KMAX];
    /* off a 64-byte boundary by 1 to 7 values */
    real *state_b = (real *)(((uintptr_t)state_b_buf + 63) / 64 * 64) + 1 + take_u8(&in) % 7;
    static real scratch_c[SCRATCH_MAX], bank_work[PIHYST_COMPBANK_WORK_LEN(1, FUZZ_KMAX)];
    real coef_c[PIHYST_COEF_LEN(FUZZ_KMAX)], coef_r2[PIHYST_COEF_LEN(FUZZ_KMAX)];
    real state_c[FUZZ_KMAX], state_r2[FUZZ_KMAX];
    pihyst_model ma, mb, mr, mc, mr2;
    pihyst_compensator ca, cb, cc;
    pihyst_compensator *const bank_ch[1] = {&cc};
    pihyst_compbank bank;
    pihyst_status sa, sb;
    size_t need, scratch_len, K, k, steps = 0;
    real lo, hi, max_step, u_init;
    double sum_w = 0.0, y_scale;

    take_params(&in, &f, 1);
    if (pihyst_model_init(&ma, &f.p, coef_a, state_a) != PIHYST_OK) return;
    REQUIRE(pihyst_model_init(&mb, &f.p, coef_b, state_b) == PIHYST_OK);
    REQUIRE(pihyst_model_init(&mr, &f.p, coef_r, state_r) == PIHYST_OK);
    REQUIRE(pihyst_model_init(&mc, &f.p, coef_c, state_c) == PIHYST_OK);
    REQUIRE(pihyst_model_init(&mr2, &f.p, coef_r2, state_r2) == PIHYST_OK);
    K = ma.n_ops;

    /* limits: NaN (the model's bound) half the time */
    lo = take_u8(&in) & 1 ? (real)NAN : (real)take_num(&in, f.p.u_min - 10.0, f.p.u_max);
    hi = take_u8(&in) & 1 ? (real)NAN : (real)take_num(&in, f.p.u_min, f.p.u_max + 10.0);
    max_step = take_u8(&in) & 1 ? (real)INFINITY : (real)take_num(&in, 0.0, 20.0);
    u_init = (real)take_num(&in, isnan(lo) ? f.p.u_min : lo, isnan(hi) ? f.p.u_max : hi);
    need = pihyst_compensator_scratch_len(&ma);
    REQUIRE(need <= SCRATCH_MAX);
    scratch_len = need - (take_u8(&in) == 7); /* now and then one short */

    sa = pihyst_compensator_init(&ca, &ma, lo, hi, max_step, u_init, scratch_a, scratch_len);
    sb = pihyst_compensator_init(&cb, &mb, lo, hi, max_step, u_init, scratch_b, scratch_len);
    REQUIRE(known_status(sa) && sa == sb);
    if (scratch_len < need) REQUIRE(sa != PIHYST_OK);
    if (sa != PIHYST_OK) return;
    REQUIRE(pihyst_compensator_init(&cc, &mc, lo, hi, max_step, u_init, scratch_c,
                                    scratch_len) == PIHYST_OK);
    REQUIRE(pihyst_compbank_work_len(bank_ch, 1) <= sizeof bank_work / sizeof(real));
    REQUIRE(pihyst_compbank_init(&bank, bank_ch, 1, bank_work,
                                 sizeof bank_work / sizeof(real)) == PIHYST_OK);
    pihyst_model_step(&mr2, u_init);
    bank_last_u = u_init;
    REQUIRE(ca.u_last == u_init && ma.state == state_a && mb.state == state_b);
    pihyst_model_step(&mr, u_init);
    REQUIRE(same_bits(state_a, state_r, K) && same_bits(state_b, state_r, K));
    for (k = 0; k < K; ++k) sum_w += f.w[k];
    y_scale = 1.0 + sum_w * ((double)ca.u_max - (double)ca.u_min);
    ref.n = 0;

    while (in.n > 0 && steps < 4 * N_MAX) {
        const unsigned op = take_u8(&in) % 16;
        if (op < 13) { /* a step */
            const real u_p = ca.u_last;
            const real yd = (real)take_num(&in, ca.y_last - y_scale, ca.y_last + y_scale);
            pihyst_flags fl = 0xff;
            const real u = pihyst_compensator_step(&ca, yd, &fl);
            pihyst_model *const plain[1] = {&mr};
            real y_r;
            if (steps & 1) /* every other sample through the model bank */
                pihyst_bank_step(plain, 1, &u, &y_r);
            else
                y_r = pihyst_model_step(&mr, u);
            ++steps;
            REQUIRE(u == ca.u_last && ma.state == state_a);
            REQUIRE(isfinite(u) && u >= ca.u_min && u <= ca.u_max);
            /* the slew limit holds for the difference in the working precision (pihyst.h) */
            REQUIRE(fabs((double)(real)(u - u_p)) <= (double)ca.max_step);
            REQUIRE((fl & ~(PIHYST_COMP_SAT_LOW | PIHYST_COMP_SAT_HIGH | PIHYST_COMP_NAN |
                            PIHYST_COMP_SLEW)) == 0);
            REQUIRE(!(fl & PIHYST_COMP_NAN) == !isnan(yd));
            if (isnan(yd)) REQUIRE(fl == PIHYST_COMP_NAN && u == u_p);
            /* out of reach: at the limit, or on the way there when the slew limit cut it
             * short (then with PIHYST_COMP_SLEW) */
            if (fl == PIHYST_COMP_SAT_LOW) REQUIRE(u == ca.u_min);
            if (fl == PIHYST_COMP_SAT_HIGH) REQUIRE(u == ca.u_max);
            if (fl & PIHYST_COMP_SLEW)
                REQUIRE(fl != (PIHYST_COMP_SLEW | PIHYST_COMP_SAT_LOW | PIHYST_COMP_SAT_HIGH) &&
                        !(fl & PIHYST_COMP_NAN) &&
                        fabs((double)u - (double)u_p) >=
                            (double)ca.max_step - 4.0 * FUZZ_EPS * (fabs((double)u) + 1.0));
            /* y_last is the model's output for u: a separate model says the same */
            REQUIRE(y_r == ca.y_last);
            REQUIRE(same_bits(state_a, state_r, K));
            if (sane(&f)) REQUIRE(isfinite(ca.y_last));
            if (fl == 0 && sane(&f)) {
                /* a few ulps of voltage at the steepest slope, and underflow (subnormal
                 * weights or values) in each term of the output */
                const double ulp_y =
                    8.0 * FUZZ_EPS * (fabs((double)u) + fabs((double)u_p) + 1.0) * f.max_slope *
                        sum_w +
                    ((double)K + 2.0) * FUZZ_TINY;
                if (!(fabs((double)ca.y_last - (double)yd) <= 16.0 * (double)ca.tol + ulp_y))
                    fprintf(stderr, "family %d, K = %zu, step %zu: u_p = %.17g, u = %.17g, "
                            "y_d = %.17g, y_last = %.17g, tol = %.3g, ulp_y = %.3g\n",
                            (int)f.p.family, K, steps, (double)u_p, (double)u, (double)yd,
                            (double)ca.y_last, (double)ca.tol, ulp_y);
                REQUIRE(fabs((double)ca.y_last - (double)yd) <= 16.0 * (double)ca.tol + ulp_y);
            }
            step_bank(&bank, &cc, &mr2, &f, yd, sum_w, steps);
            if (ref.n == N_MAX) flush(&cb, &ref, 0);
            ref.yd[ref.n] = yd;
            ref.u[ref.n] = u;
            ref.y[ref.n] = ca.y_last;
            ref.fl[ref.n] = fl;
            ++ref.n;
        } else if (op < 15) { /* flush: B catches up through run, or the bank */
            flush(&cb, &ref, op == 14);
            REQUIRE(same_bits(state_b, state_a, K) && cb.u_last == ca.u_last);
        } else { /* reset both (B after catching up) and R */
            const int with_state = take_u8(&in) & 1;
            const real u_last = (real)take_num(&in, ca.u_min, ca.u_max);
            for (k = 0; k < K; ++k) reset_state[k] = (real)take_num(&in, -300.0, 300.0);
            flush(&cb, &ref, 0);
            sa = pihyst_compensator_reset(&ca, with_state ? reset_state : NULL, u_last);
            sb = pihyst_compensator_reset(&cb, with_state ? reset_state : NULL, u_last);
            REQUIRE(known_status(sa) && sa == sb);
            if (sa == PIHYST_OK) {
                REQUIRE(ca.u_last == u_last);
                pihyst_model_reset(&mr, with_state ? reset_state : NULL);
                pihyst_model_step(&mr, u_last);
                REQUIRE(pihyst_compensator_reset(&cc, with_state ? reset_state : NULL,
                                                 u_last) == PIHYST_OK);
                REQUIRE(pihyst_compbank_init(&bank, bank_ch, 1, bank_work,
                                             sizeof bank_work / sizeof(real)) == PIHYST_OK);
                pihyst_model_reset(&mr2, with_state ? reset_state : NULL);
                pihyst_model_step(&mr2, u_last);
                bank_last_u = u_last;
            } else {
                REQUIRE(!isfinite(u_last) || u_last < ca.u_min || u_last > ca.u_max ||
                        with_state);
            }
            REQUIRE(same_bits(state_a, state_r, K) && same_bits(state_b, state_r, K));
        }
    }
    flush(&cb, &ref, 0);
    REQUIRE(same_bits(state_b, state_a, K));
}

#ifdef FUZZ_F32
void check_compensator_f32(const uint8_t *data, size_t size);
void check_compensator_f32(const uint8_t *data, size_t size) { check(data, size); }
#else
void check_compensator_f32(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    check(data, size);
    check_compensator_f32(data, size);
    return 0;
}
#endif
