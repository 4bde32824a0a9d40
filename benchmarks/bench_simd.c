/* Timing harness for the forward model against the best hand-vectorized C kernel,
 * compiled and run by bench_simd.py (gcc -O3 -march=native when it has AVX2 + FMA).
 * Not part of the library.
 *
 *   bench_simd FAMILY N REPEATS     FAMILY: 0 classical, 1 multislope; K = 16
 *
 * Both kernels run the same random walk with minor loops (N samples, best of REPEATS):
 *   core: pihyst_model_run (the library, multiversioned);
 *   hand: AVX2 + FMA intrinsics written for K = 16: the 16 operator states, envelope
 *         constants and weights live in registers for the whole block, the weighted sum
 *         is a tree. Exactly what a specialist would write for a fixed K.
 * Prints: <ns/sample core> <ns/sample hand> <max |y_core - y_hand|> */
#include "pihyst.h"

#include <immintrin.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define K 16

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double hsum(__m256d s)
{
    __m128d lo = _mm256_castpd256_pd128(s), hi = _mm256_extractf128_pd(s, 1);
    lo = _mm_add_pd(lo, hi);
    return _mm_cvtsd_f64(_mm_add_sd(lo, _mm_unpackhi_pd(lo, lo)));
}

static void hand_classical(const double *r, const double *w, double *f, double offset,
                           const double *u, double *y, size_t n)
{
    __m256d fv[4], lo[4], hi[4], wv[4];
    size_t t;
    int j;
    for (j = 0; j < 4; ++j) {
        fv[j] = _mm256_loadu_pd(f + 4 * j);
        hi[j] = _mm256_loadu_pd(r + 4 * j);
        lo[j] = _mm256_sub_pd(_mm256_setzero_pd(), hi[j]);
        wv[j] = _mm256_loadu_pd(w + 4 * j);
    }
    for (t = 0; t < n; ++t) {
        const __m256d ub = _mm256_set1_pd(u[t]);
        __m256d acc[4];
        for (j = 0; j < 4; ++j) {
            __m256d v = _mm256_min_pd(fv[j], _mm256_add_pd(ub, hi[j]));
            fv[j] = _mm256_max_pd(v, _mm256_add_pd(ub, lo[j]));
            acc[j] = _mm256_mul_pd(wv[j], fv[j]);
        }
        y[t] = offset + hsum(_mm256_add_pd(_mm256_add_pd(acc[0], acc[1]),
                                           _mm256_add_pd(acc[2], acc[3])));
    }
    for (j = 0; j < 4; ++j) _mm256_storeu_pd(f + 4 * j, fv[j]);
}

static void hand_multislope(const double *r, const double *w, double *f, double offset,
                            double U, double a, double b, double h, const double *u,
                            double *y, size_t n)
{
    __m256d fv[4], c1[4], c2[4], c3[4], wv[4];
    const __m256d av = _mm256_set1_pd(a), bv = _mm256_set1_pd(b);
    size_t t;
    int j;
    for (j = 0; j < 4; ++j) {
        const __m256d rv = _mm256_loadu_pd(r + 4 * j);
        fv[j] = _mm256_loadu_pd(f + 4 * j);
        c1[j] = _mm256_mul_pd(_mm256_set1_pd(-a), rv);
        c2[j] = _mm256_sub_pd(_mm256_set1_pd(-(b - 1.0) * U), rv);
        c3[j] = _mm256_fnmadd_pd(_mm256_set1_pd(1.0 - a * h), rv,
                                 _mm256_set1_pd((1.0 - a) * U));
        wv[j] = _mm256_loadu_pd(w + 4 * j);
    }
    for (t = 0; t < n; ++t) {
        const __m256d ut = _mm256_set1_pd(u[t]);
        const __m256d au = _mm256_mul_pd(av, ut), bu = _mm256_mul_pd(bv, ut);
        __m256d acc[4];
        for (j = 0; j < 4; ++j) {
            __m256d lo = _mm256_max_pd(_mm256_add_pd(au, c1[j]), _mm256_add_pd(bu, c2[j]));
            __m256d hi = _mm256_min_pd(bu, _mm256_add_pd(au, c3[j]));
            fv[j] = _mm256_max_pd(_mm256_min_pd(fv[j], hi), lo);
            acc[j] = _mm256_mul_pd(wv[j], fv[j]);
        }
        y[t] = offset + hsum(_mm256_add_pd(_mm256_add_pd(acc[0], acc[1]),
                                           _mm256_add_pd(acc[2], acc[3])));
    }
    for (j = 0; j < 4; ++j) _mm256_storeu_pd(f + 4 * j, fv[j]);
}

int main(int argc, char **argv)
{
    int family = argc > 1 ? atoi(argv[1]) : 0;
    size_t n = argc > 2 ? (size_t)atol(argv[2]) : 1000000, t;
    int repeats = argc > 3 ? atoi(argv[3]) : 5, rep;
    double *u = malloc(n * sizeof *u), *y1 = malloc(n * sizeof *y1),
           *y2 = malloc(n * sizeof *y2);
    double r[K], w[K], coef[PIHYST_COEF_LEN(K)], f_hand[K], err = 0.0;
    double best_core = 1e30, best_hand = 1e30, v = 0.0;
    double *state = aligned_alloc(64, 64 * ((K * sizeof(double) + 63) / 64));
    unsigned s = 12345u;
    pihyst_model m;
    pihyst_params p;
    int k;
    for (t = 0; t < n; ++t) { /* reflected random walk in [0, 150] */
        s = s * 1103515245u + 12345u;
        v += 4.0 * ((double)(s >> 8) / 16777216.0 - 0.5);
        if (v < 0) v = -v;
        if (v > 150) v = 300 - v;
        u[t] = v;
    }
    for (k = 0; k < K; ++k) {
        r[k] = family == 0 ? 150.0 * k / K : 50.0 * k / K;
        w[k] = 0.01 + 0.005 * (k % 7);
    }
    memset(&p, 0, sizeof p);
    p.family = family == 0 ? PIHYST_CLASSICAL : PIHYST_MULTISLOPE;
    p.n_ops = K;
    p.thresholds = r;
    p.weights = w;
    p.u_min = 0.0;
    p.u_max = 150.0;
    p.shape.U = 150.0; p.shape.a = 0.8; p.shape.b = 1.2; p.shape.h = 0.5;
    if (pihyst_model_init(&m, &p, coef, state) != PIHYST_OK) return 1;
    for (rep = 0; rep < repeats; ++rep) {
        double t0 = now();
        pihyst_model_reset(&m, NULL);
        pihyst_model_run(&m, u, y1, n);
        t0 = now() - t0;
        if (t0 < best_core) best_core = t0;
        memset(f_hand, 0, sizeof f_hand);
        t0 = now();
        if (family == 0)
            hand_classical(r, w, f_hand, 0.0, u, y2, n);
        else
            hand_multislope(r, w, f_hand, 0.0, 150.0, 0.8, 1.2, 0.5, u, y2, n);
        t0 = now() - t0;
        if (t0 < best_hand) best_hand = t0;
    }
    for (t = 0; t < n; ++t)
        if (fabs(y1[t] - y2[t]) > err) err = fabs(y1[t] - y2[t]);
    printf("%.3f %.3f %.3g\n", 1e9 * best_core / (double)n, 1e9 * best_hand / (double)n, err);
    free(u); free(y1); free(y2); free(state);
    return 0;
}
