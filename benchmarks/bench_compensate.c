/* Timing harness for the C compensator, compiled and run by bench_compensate.py
 * (gcc -O3 with the core's sources). Not part of the library.
 *
 *   bench_compensate FAMILY K N REPEATS [TRAJECTORY [STATE_OFFSET]]
 *       FAMILY: 0 classical, 1 multislope
 *       TRAJECTORY: 0 (default) a walk of random steps up to 0.5 V with reversals at
 *                   random levels; 1 ramps between random levels at 0.25 V per sample;
 *                   2 a random voltage every sample (a reversal two samples in three,
 *                   each far from the last voltage: the worst case)
 *       STATE_OFFSET: -1 (default) the operator state in its own malloc block, as a
 *                   user allocates it (16-byte aligned here, not on a cache line);
 *                   0..7: that many doubles past a 64-byte boundary
 *
 * Desired trajectory: the model's own output for that voltage signal with minor loops
 * (so every sample is reachable). Prints one line:
 *   <ns/sample exact step> <ns/sample bisection> <max |y - y_d| exact> <max |y - y_d| bisection>
 *
 * Bisection baseline: for the fixed state, the least u in the window [u_min, u_max] with
 *   y(u) = offset + sum_k w_k max(R_k(u), min(F_k(u), f_k)) >= y_d
 * halving the bracket until it is 1e-12 V wide, then the model is stepped with it. */
#include "pihyst.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static unsigned long long rng = 88172645463325252ULL;
static double uniform(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) / 9007199254740992.0;
}

/* y(u) for the model's current state, without changing it */
static double output_at(const pihyst_model *m, double u)
{
    const size_t K = m->n_ops;
    const double *c = m->coef, *f = m->state, *w = m->weights;
    double y = m->offset;
    size_t k;
    if (m->family == PIHYST_CLASSICAL) {
        for (k = 0; k < K; ++k) {
            double v = f[k], lo = u + c[k], hi = u + c[K + k];
            v = v < hi ? v : hi;
            v = v > lo ? v : lo;
            y += w[k] * v;
        }
    } else {
        const double au = m->shape.a * u, bu = m->shape.b * u;
        for (k = 0; k < K; ++k) {
            double r1 = au + c[k], r2 = bu + c[K + k], f2 = au + c[2 * K + k];
            double lo = r1 > r2 ? r1 : r2, hi = bu < f2 ? bu : f2, v = f[k];
            v = v < hi ? v : hi;
            v = v > lo ? v : lo;
            y += w[k] * v;
        }
    }
    return y;
}

static void bisection_run(pihyst_model *m, const double *yd, double *u, double *y, size_t n)
{
    size_t t;
    for (t = 0; t < n; ++t) {
        double lo = m->u_min, hi = m->u_max;
        if (output_at(m, hi) < yd[t]) {
            lo = hi;
        } else if (output_at(m, lo) >= yd[t]) {
            hi = lo;
        } else {
            while (hi - lo > 1e-12) {
                double mid = 0.5 * (lo + hi);
                if (output_at(m, mid) >= yd[t]) hi = mid; else lo = mid;
            }
        }
        u[t] = hi;
        y[t] = pihyst_model_step(m, hi);
    }
}

int main(int argc, char **argv)
{
    int family, K, k, rep, reps, kind, offset;
    size_t n, t;
    double *r, *w, *coef, *state, *state_block, *scratch, *u, *yd, *uc, *yc;
    double v = 0.0, target = 150.0, best_exact = 1e30, best_bisect = 1e30;
    double err_exact = 0.0, err_bisect = 0.0;
    const pihyst_shape shape = {150.0, 0.8, 1.2, 0.5};
    pihyst_model m;
    pihyst_compensator c;
    size_t scratch_len;
    if (argc < 5 || argc > 7) {
        fprintf(stderr, "usage: %s FAMILY K N REPEATS [TRAJECTORY [STATE_OFFSET]]\n", argv[0]);
        return 2;
    }
    kind = argc >= 6 ? atoi(argv[5]) : 0;
    offset = argc == 7 ? atoi(argv[6]) : -1;
    family = atoi(argv[1]);
    K = atoi(argv[2]);
    n = (size_t)atol(argv[3]);
    reps = atoi(argv[4]);
    r = malloc(K * sizeof *r);
    w = malloc(K * sizeof *w);
    coef = malloc(PIHYST_COEF_LEN(K) * sizeof *coef);
    state_block = malloc((K + 16) * sizeof *state_block);
    state = offset < 0 ? state_block
                       : (double *)(((uintptr_t)state_block + 63) / 64 * 64) + (offset & 7);
    scratch = malloc(PIHYST_COMPENSATOR_SCRATCH_LEN(K, 0) * sizeof *scratch);
    u = malloc(n * sizeof *u);
    yd = malloc(n * sizeof *yd);
    uc = malloc(n * sizeof *uc);
    yc = malloc(n * sizeof *yc);
    if (!r || !w || !coef || !state_block || !scratch || !u || !yd || !uc || !yc) return 1;
    for (k = 0; k < K; ++k) {
        r[k] = (family ? 50.0 : 150.0) * k / K;
        w[k] = (k == 0 ? 0.2 : 0.0) + 0.1 * uniform();
    }
    {
        const pihyst_params params = {.family = family ? PIHYST_MULTISLOPE : PIHYST_CLASSICAL,
                                      .n_ops = (size_t)K, .thresholds = r, .weights = w,
                                      .u_min = 0.0, .u_max = 150.0, .shape = shape};
        if (pihyst_model_init(&m, &params, coef, state) != PIHYST_OK) return 1;
    }
    /* voltage walk: steps up to 0.5 V per sample, reversals at random levels; or ramps
     * at 0.25 V per sample between random levels */
    for (t = 0; t < n; ++t) {
        double step = kind ? 0.25 : 0.5 * uniform();
        if (kind ? v == target : uniform() < 0.01) target = 150.0 * uniform();
        v = v < target ? (v + step < target ? v + step : target)
                       : (v - step > target ? v - step : target);
        u[t] = kind == 2 ? 150.0 * uniform() : v;
    }
    pihyst_model_run(&m, u, yd, n);
    scratch_len = pihyst_compensator_scratch_len(&m);
    for (rep = 0; rep < reps; ++rep) {
        double t0, t1;
        pihyst_model_reset(&m, NULL);
        if (pihyst_compensator_init(&c, &m, NAN, NAN, INFINITY, 0.0, scratch, scratch_len) !=
            PIHYST_OK)
            return 1;
        t0 = now();
        for (t = 0; t < n; ++t) uc[t] = pihyst_compensator_step(&c, yd[t], NULL);
        t1 = now();
        if (t1 - t0 < best_exact) best_exact = t1 - t0;
        yc[0] = 0.0;
    }
    pihyst_model_reset(&m, NULL);
    pihyst_model_run(&m, uc, yc, n);
    for (t = 0; t < n; ++t)
        if (fabs(yc[t] - yd[t]) > err_exact) err_exact = fabs(yc[t] - yd[t]);
    for (rep = 0; rep < reps; ++rep) {
        double t0, t1;
        size_t nb = n / 10 > 0 ? n / 10 : n; /* bisection is slow: a tenth of the samples */
        pihyst_model_reset(&m, NULL);
        t0 = now();
        bisection_run(&m, yd, uc, yc, nb);
        t1 = now();
        if ((t1 - t0) / (double)nb * (double)n < best_bisect)
            best_bisect = (t1 - t0) / (double)nb * (double)n;
        if (rep == 0)
            for (t = 0; t < nb; ++t)
                if (fabs(yc[t] - yd[t]) > err_bisect) err_bisect = fabs(yc[t] - yd[t]);
    }
    printf("%.3f %.3f %.3g %.3g\n", 1e9 * best_exact / (double)n, 1e9 * best_bisect / (double)n,
           err_exact, err_bisect);
    free(r); free(w); free(coef); free(state_block); free(scratch);
    free(u); free(yd); free(uc); free(yc);
    return 0;
}
