/* fuzz_model.c - libFuzzer harness of pihyst_model_*, in double and single precision.
 *
 * Input: model parameters (fuzz_common.h), then up to 256 input voltages. Invariants:
 *   - init returns a status code of pihyst.h; when it accepts, the parameters satisfy
 *     every documented constraint (require_valid);
 *   - run == step by step == run in two chunks == the structure-of-arrays model bank
 *     (pihyst_modelbank, one channel), bit for bit (NaN inputs included), and the bank's
 *     state after pihyst_modelbank_sync is run's;
 *   - every operator output stays between its envelopes,
 *         R_k(u) <= f_k <= max(R_k(u), F_k(u))      (to rounding; (1) of pihyst.h)
 *   - outputs are finite when parameters and inputs are below FUZZ_BIG (no overflow);
 *   - the operator matrix reproduces the output: offset + sum_k w_k phi[t][k] = y[t];
 *   - the Gram matrix accumulated in two chunks is symmetric and its diagonal is
 *     sum_t phi[t][k]^2.
 * Build and run: make -C csrc fuzz (see docs/c-core.md). */
#include "fuzz_common.h"

#define N_MAX 256

static void check(const uint8_t *data, size_t size)
{
    reader in = {data, size};
    static fuzz_params f;
    static real u[N_MAX], y_run[N_MAX], y_step[N_MAX], y_chunk[N_MAX], phi[N_MAX * FUZZ_KMAX];
    real coef[PIHYST_COEF_LEN(FUZZ_KMAX)], state[FUZZ_KMAX], rise[FUZZ_KMAX], fall[FUZZ_KMAX];
    real gram[FUZZ_KMAX * FUZZ_KMAX], rhs[FUZZ_KMAX], sums[FUZZ_KMAX];
    pihyst_model m;
    pihyst_status s;
    size_t n = 0, t, k, j, K, cut;
    int u_sane = 1; /* every input finite and below FUZZ_BIG: nothing can overflow */

    take_params(&in, &f, 0);
    s = pihyst_model_init(&m, &f.p, coef, state);
    REQUIRE(known_status(s));
    if (s != PIHYST_OK) return;
    require_valid(&f);
    K = m.n_ops;

    while (in.n > 0 && n < N_MAX) {
        u[n] = (real)take_num(&in, (double)f.p.u_min - 20.0, (double)f.p.u_max + 20.0);
        u_sane &= fabs((double)u[n]) <= FUZZ_BIG;
        ++n;
    }
    cut = n ? data[0] % n : 0;

    /* run == step == two chunks */
    pihyst_model_run(&m, u, y_run, n);
    pihyst_model_reset(&m, f.p.initial_state);
    for (t = 0; t < n; ++t) {
        y_step[t] = pihyst_model_step(&m, u[t]);
        if (!sane(&f) || !(fabs((double)u[t]) <= FUZZ_BIG)) continue; /* (overflow) */
        /* f_k between the envelopes at u[t], to the rounding of either evaluation */
        pihyst_model_envelopes(&m, u[t], rise, fall);
        for (k = 0; k < K; ++k) {
            /* (PWL: both sides evaluate the same polyline, bit for bit; only validated
             * parameters enter the slack) */
            const double lo = rise[k], hi = rise[k] > fall[k] ? rise[k] : fall[k];
            const double terms =
                (f.p.family == PIHYST_PWL ? 0.0 : fabs((double)f.r[k])) +
                (f.p.family == PIHYST_MULTISLOPE ? fabs((double)f.p.shape.U) : 0.0);
            const double slack = 64.0 * FUZZ_EPS *
                                 (1.0 + fabs(lo) + fabs(hi) + 4.0 * fabs((double)u[t]) +
                                  4.0 * terms);
            if (!(state[k] >= lo - slack && state[k] <= hi + slack))
                fprintf(stderr, "family %d, t = %zu, k = %zu: u = %.17g, f = %.17g, R = %.17g, "
                        "max(R, F) = %.17g, slack %.3g\n", (int)f.p.family, t, k, (double)u[t],
                        (double)state[k], lo, hi, slack);
            REQUIRE(state[k] >= lo - slack && state[k] <= hi + slack);
        }
    }
    REQUIRE(same_bits(y_run, y_step, n));
    pihyst_model_reset(&m, f.p.initial_state);
    pihyst_model_run(&m, u, y_chunk, cut);
    pihyst_model_run(&m, u + cut, y_chunk + cut, n - cut);
    REQUIRE(same_bits(y_run, y_chunk, n));
    {
        static real work[PIHYST_MODELBANK_WORK_LEN(1)], state_run[FUZZ_KMAX];
        pihyst_model *const channel[1] = {&m};
        pihyst_modelbank b;
        memcpy(state_run, state, K * sizeof(real));
        pihyst_model_reset(&m, f.p.initial_state);
        REQUIRE(pihyst_modelbank_init(&b, channel, 1, work, sizeof work / sizeof(real)) ==
                PIHYST_OK);
        for (t = 0; t < n; ++t) pihyst_modelbank_step(&b, &u[t], &y_chunk[t]);
        REQUIRE(same_bits(y_run, y_chunk, n));
        pihyst_modelbank_sync(&b);
        REQUIRE(same_bits(state, state_run, K));
    }
    if (sane(&f) && u_sane)
        for (t = 0; t < n; ++t) REQUIRE(isfinite(y_run[t]));

    if (!sane(&f) || !u_sane) return;
    /* the operator matrix reproduces the output */
    pihyst_model_reset(&m, f.p.initial_state);
    pihyst_model_operators(&m, u, phi, n);
    for (t = 0; t < n; ++t) {
        double sum = f.p.offset, mag = fabs((double)f.p.offset);
        for (k = 0; k < K; ++k) {
            sum += (double)f.w[k] * phi[t * K + k];
            mag += fabs((double)f.w[k] * phi[t * K + k]);
        }
        REQUIRE(fabs(sum - y_run[t]) <= ((double)K + 2.0) * (4.0 * FUZZ_EPS * mag + FUZZ_TINY));
    }
    /* Gram matrix in two chunks: symmetric, diagonal = sum of squares (when the sums
     * cannot overflow) */
    for (t = 0; t < n * K; ++t)
        if (!(fabs((double)phi[t]) <= FUZZ_BIG)) return;
    memset(gram, 0, sizeof gram);
    memset(rhs, 0, sizeof rhs);
    memset(sums, 0, sizeof sums);
    pihyst_model_reset(&m, f.p.initial_state);
    pihyst_model_gram(&m, u, u, cut, gram, rhs, sums);
    pihyst_model_gram(&m, u + cut, u + cut, n - cut, gram, rhs, sums);
    for (k = 0; k < K; ++k) {
        double sq = 0.0, mag = 0.0;
        for (j = 0; j < K; ++j) REQUIRE(gram[j * K + k] == gram[k * K + j]);
        for (t = 0; t < n; ++t) {
            sq += (double)phi[t * K + k] * phi[t * K + k];
            mag += fabs((double)phi[t * K + k] * phi[t * K + k]);
        }
        REQUIRE(fabs(gram[k * K + k] - sq) <= ((double)n + 2.0) * (4.0 * FUZZ_EPS * mag + FUZZ_TINY));
    }
}

#ifdef FUZZ_F32
void check_model_f32(const uint8_t *data, size_t size);
void check_model_f32(const uint8_t *data, size_t size) { check(data, size); }
#else
void check_model_f32(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    check(data, size);
    check_model_f32(data, size);
    return 0;
}
#endif
