/* The single-precision core (_f32) against the double one, on the same models: every
 * parameter is a float, stored exactly in both, and every input a float, so the two
 * differ by their arithmetic alone.
 *
 * Forward model. Each f_k is a max/min of envelope values and its previous value, and
 * max/min are 1-Lipschitz, so the error of f_k never exceeds the largest error of one
 * envelope evaluation, a u + c (a few roundings of terms up to b|u| + U + r_k), plus
 * that of the constant c computed from r_k, U, a, b, h at init (a few more); the output
 * sum adds (K + 1) roundings of its terms. So
 *
 *     |y_f32 - y_f64| <= (K + 8) FLT_EPSILON E,   E = |offset| + sum_k |w_k| (b u_big + U + r_k)   (T)
 *
 * with u_big = max(|u_min|, |u_max|) (b = 1, U = 0 for classical; PWL: see
 * twin_init_pwl). The measured worst case is printed, as a fraction of T.
 *
 * Compensator. In single precision the output is known to about an ulp of the output
 * scale, so the compensator holds once |y_d - y| <= tol_f32 = 4 (K + 2) FLT_EPSILON S (its
 * own equality band, S the output scale): the voltage it picks puts the f32 model within
 * a few tol_f32 of y_d, and the exact (double) model within that plus T:
 *
 *     |y_f64(u_f32) - y_d| <= 4 tol_f32 + T                                           (C)
 *
 * (about 1e-3 um on 40 um for the paper's models). The voltages themselves agree only
 * where the model is strictly increasing: with slope >= w_0 (classical, r_0 = 0) they
 * differ by at most (C) / w_0. Limits and slew hold exactly in either precision. */
#define PIHYST_TEST_BOTH
#include "test_util.h"

#include <stdio.h>

#define N_TWIN 4000
#define KMAX 64
#define PMAX 5 /* PWL: breakpoints per polyline */

static unsigned lcg = 777u;
static float uniform_f(void) /* [0, 1), a float */
{
    lcg = lcg * 1103515245u + 12345u;
    return (float)(lcg >> 8) / (float)(1u << 24);
}

/* One model in both precisions from float parameters. */
typedef struct {
    pihyst_model m64;
    pihyst_model_f32 m32;
    double r64[KMAX], w64[KMAX], coef64[PIHYST_COEF_LEN(KMAX)], state64[KMAX];
    float r32[KMAX], w32[KMAX], coef32[PIHYST_COEF_LEN(KMAX)], state32[KMAX];
    size_t start[KMAX + 1];                                /* PWL: shared offsets */
    double x64[KMAX * PMAX], rise64[KMAX * PMAX], fall64[KMAX * PMAX];
    float x32[KMAX * PMAX], rise32[KMAX * PMAX], fall32[KMAX * PMAX];
    double E; /* the scale of (T) */
} twin;

static int twin_init(twin *t, pihyst_family family, size_t K, const float *r, const float *w,
                     float offset, float u_min, float u_max, const pihyst_shape_f32 *shape)
{
    pihyst_params p64 = {.family = family, .n_ops = K, .thresholds = t->r64,
                         .weights = t->w64, .offset = offset, .u_min = u_min, .u_max = u_max};
    pihyst_params_f32 p32 = {.family = family, .n_ops = K, .thresholds = t->r32,
                             .weights = t->w32, .offset = offset, .u_min = u_min,
                             .u_max = u_max};
    const double u_big = fabs(u_min) > fabs(u_max) ? fabs(u_min) : fabs(u_max);
    double b = 1.0, U = 0.0;
    size_t k;
    if (shape) {
        p32.shape = *shape;
        p64.shape.U = shape->U;
        p64.shape.a = shape->a;
        p64.shape.b = shape->b;
        p64.shape.h = shape->h;
        b = shape->b;
        U = shape->U;
    }
    t->E = fabs(offset);
    for (k = 0; k < K; ++k) {
        t->r32[k] = r[k];
        t->w32[k] = w[k];
        t->r64[k] = r[k];
        t->w64[k] = w[k];
        t->E += fabs(w[k]) * (b * u_big + U + r[k]);
    }
    return pihyst_model_init(&t->m64, &p64, t->coef64, t->state64) == PIHYST_OK &&
           pihyst_model_init_f32(&t->m32, &p32, t->coef32, t->state32) == PIHYST_OK;
}

/* A PWL model in both precisions: per operator a random polyline R through PMAX float
 * breakpoints, and F = R + gap on the same abscissae. The error of one evaluation,
 * y_i + (y_{i+1} - y_i)(u - x_i)/(x_{i+1} - x_i), is a few roundings of terms up to
 * max|y| + s (u_big + max|x|), s the steepest slope: that replaces b u_big + U + r_k in E. */
static int twin_init_pwl(twin *t, size_t K, const float *w, float offset, float u_min,
                         float u_max)
{
    pihyst_params p64 = {.family = PIHYST_PWL, .n_ops = K, .weights = t->w64,
                         .offset = offset, .u_min = u_min, .u_max = u_max};
    pihyst_params_f32 p32 = {.family = PIHYST_PWL, .n_ops = K, .weights = t->w32,
                             .offset = offset, .u_min = u_min, .u_max = u_max};
    const double u_big = fabs(u_min) > fabs(u_max) ? fabs(u_min) : fabs(u_max);
    size_t k, i;
    t->E = fabs(offset);
    t->start[0] = 0;
    for (k = 0; k < K; ++k) {
        const float gap = 5.0f * uniform_f();
        float x = u_min - 20.0f + 40.0f * uniform_f(), y = -20.0f + 40.0f * uniform_f();
        double slope = 0.0, big_x = 0.0, big_y = 0.0;
        for (i = 0; i < PMAX; ++i) {
            const size_t at = k * PMAX + i;
            if (i) {
                const float dx = 1.0f + 40.0f * uniform_f(), dy = 30.0f * uniform_f();
                x += dx;
                y += dy;
                if (dy / dx > slope) slope = dy / dx;
            }
            t->x32[at] = x;
            t->rise32[at] = y;
            t->fall32[at] = y + gap;
            t->x64[at] = x;
            t->rise64[at] = y;
            t->fall64[at] = (double)t->fall32[at];
            if (fabs(x) > big_x) big_x = fabs(x);
            if (fabs(t->fall32[at]) > big_y) big_y = fabs(t->fall32[at]);
        }
        t->start[k + 1] = (k + 1) * PMAX;
        t->w32[k] = w[k];
        t->w64[k] = w[k];
        t->E += fabs(w[k]) * (big_y + slope * (u_big + big_x));
    }
    p64.pwl.rise_start = p64.pwl.fall_start = t->start;
    p64.pwl.rise_x = p64.pwl.fall_x = t->x64;
    p64.pwl.rise_y = t->rise64;
    p64.pwl.fall_y = t->fall64;
    p32.pwl.rise_start = p32.pwl.fall_start = t->start;
    p32.pwl.rise_x = p32.pwl.fall_x = t->x32;
    p32.pwl.rise_y = t->rise32;
    p32.pwl.fall_y = t->fall32;
    return pihyst_model_init(&t->m64, &p64, t->coef64, t->state64) == PIHYST_OK &&
           pihyst_model_init_f32(&t->m32, &p32, t->coef32, t->state32) == PIHYST_OK;
}

/* a voltage walk in [lo, hi] with minor loops, in floats */
static void walk(float *u, int n, float lo, float hi)
{
    int i;
    float v = lo, target = hi;
    for (i = 0; i < n; ++i) {
        const float step = (hi - lo) * 0.02f * uniform_f();
        if (uniform_f() < 0.05f) target = lo + (hi - lo) * uniform_f();
        v = v < target ? (v + step < target ? v + step : target)
                       : (v - step > target ? v - step : target);
        u[i] = v;
    }
}

static double worst_forward = 0.0, worst_compensator = 0.0; /* fractions of (T), (C) */

/* forward: run both on the same float inputs (a walk, then noise), compare by (T) */
static void compare_forward(twin *t)
{
    static float u32[N_TWIN], y32[N_TWIN];
    static double u64[N_TWIN], y64[N_TWIN];
    const size_t K = t->m64.n_ops;
    const double bound = ((double)K + 8.0) * FLT_EPSILON * t->E;
    double err = 0.0;
    int i;
    walk(u32, N_TWIN / 2, t->m32.u_min, t->m32.u_max);
    for (i = N_TWIN / 2; i < N_TWIN; ++i)
        u32[i] = t->m32.u_min + (t->m32.u_max - t->m32.u_min) * uniform_f();
    for (i = 0; i < N_TWIN; ++i) u64[i] = u32[i];
    pihyst_model_reset(&t->m64, NULL);
    pihyst_model_reset_f32(&t->m32, NULL);
    pihyst_model_run(&t->m64, u64, y64, N_TWIN);
    pihyst_model_run_f32(&t->m32, u32, y32, N_TWIN);
    for (i = 0; i < N_TWIN; ++i)
        if (fabs(y32[i] - y64[i]) > err) err = fabs(y32[i] - y64[i]);
    CHECK_NEAR(err, 0.0, bound);
    if (err / bound > worst_forward) worst_forward = err / bound;
}

/* compensator: desired = the double model's output for a float voltage walk; both
 * compensators (slew limit max_step) follow it; the f32 voltages, applied to the double
 * model, must meet it by (C), within the limits */
static void compare_compensator(twin *t, float max_step, int unique)
{
    static float u_walk[N_TWIN], yd32[N_TWIN], u32[N_TWIN], y32[N_TWIN];
    static double yd64[N_TWIN], u64[N_TWIN], y64[N_TWIN], y_check[N_TWIN], u_in[N_TWIN];
    static pihyst_flags f32[N_TWIN], f64[N_TWIN];
    const size_t K = t->m64.n_ops;
    static double scratch64[PIHYST_COMPENSATOR_SCRATCH_LEN(KMAX, 2 * KMAX * PMAX)];
    static float scratch32[PIHYST_COMPENSATOR_SCRATCH_LEN_F32(KMAX, 2 * KMAX * PMAX)];
    pihyst_compensator c64;
    pihyst_compensator_f32 c32;
    const float lo = t->m32.u_min, hi = t->m32.u_max;
    double bound, err = 0.0, du = 0.0;
    int i, in_limits = 1;
    walk(u_walk, N_TWIN, lo, hi);
    for (i = 0; i < N_TWIN; ++i) u_in[i] = u_walk[i];
    pihyst_model_reset(&t->m64, NULL);
    pihyst_model_step(&t->m64, lo);
    pihyst_model_run(&t->m64, u_in, yd64, N_TWIN);
    yd64[N_TWIN / 3] = NAN; /* held in both */
    for (i = 0; i < N_TWIN; ++i) yd32[i] = (float)yd64[i];
    pihyst_model_reset(&t->m64, NULL);
    pihyst_model_reset_f32(&t->m32, NULL);
    CHECK(pihyst_compensator_init(&c64, &t->m64, NAN, NAN, max_step, lo, scratch64,
                                  sizeof scratch64 / sizeof *scratch64) == PIHYST_OK);
    CHECK(pihyst_compensator_init_f32(&c32, &t->m32, NAN, NAN, max_step, lo, scratch32,
                                      sizeof scratch32 / sizeof *scratch32) == PIHYST_OK);
    pihyst_compensator_run(&c64, yd64, u64, y64, f64, N_TWIN);
    pihyst_compensator_run_f32(&c32, yd32, u32, y32, f32, N_TWIN);
    /* the exact model driven by the single-precision voltages */
    for (i = 0; i < N_TWIN; ++i) u_in[i] = u32[i];
    pihyst_model_reset(&t->m64, NULL);
    pihyst_model_step(&t->m64, lo);
    pihyst_model_run(&t->m64, u_in, y_check, N_TWIN);
    bound = 4.0 * c32.tol + ((double)K + 8.0) * FLT_EPSILON * t->E;
    for (i = 0; i < N_TWIN; ++i) {
        const float prev = i ? u32[i - 1] : lo;
        in_limits &= u32[i] >= lo && u32[i] <= hi && fabsf(u32[i] - prev) <= max_step;
        CHECK((f32[i] & PIHYST_COMP_NAN) == (f64[i] & PIHYST_COMP_NAN));
        if (f32[i] || f64[i]) continue; /* slew-limited: both behind, by different amounts */
        if (fabs(y_check[i] - yd64[i]) > err) err = fabs(y_check[i] - yd64[i]);
        if (fabs(u32[i] - u64[i]) > du) du = fabs(u32[i] - u64[i]);
    }
    CHECK(in_limits);
    CHECK_NEAR(err, 0.0, bound);
    if (unique) CHECK_NEAR(du, 0.0, (bound + 4.0 * c64.tol) / t->w64[0]);
    if (err / bound > worst_compensator) worst_compensator = err / bound;
}

void run_twin_tests(void)
{
    static const float rc[4] = {0.0f, 10.0f, 30.0f, 150.0f}, wc[4] = {0.008f, 0.252f, 0.019f, 0.582f};
    static const float rm[4] = {0.0f, 20.0f, 30.0f, 40.0f}, wm[4] = {0.196f, 0.026f, 0.046f, 0.028f};
    static const pihyst_shape_f32 paper = {150.0f, 0.8f, 1.2f, 0.5f};
    static const size_t sizes[] = {1, 4, 16, 64};
    static twin t;
    float r[KMAX], w[KMAX];
    size_t i, k;
    int fam;
    /* the paper's models (Table 1) */
    CHECK(twin_init(&t, PIHYST_CLASSICAL, 4, rc, wc, 0.0f, 0.0f, 150.0f, NULL));
    compare_forward(&t);
    compare_compensator(&t, INFINITY, 1);
    compare_compensator(&t, 0.5f, 0);
    CHECK(twin_init(&t, PIHYST_MULTISLOPE, 4, rm, wm, 1.5f, 0.0f, 150.0f, &paper));
    compare_forward(&t);
    compare_compensator(&t, INFINITY, 0);
    compare_compensator(&t, 0.5f, 0);
    /* random banks of every size, classical with r_0 = 0 (a unique inverse) */
    for (fam = 0; fam < 2; ++fam) {
        for (i = 0; i < sizeof sizes / sizeof *sizes; ++i) {
            const size_t K = sizes[i];
            for (k = 0; k < K; ++k) {
                r[k] = (fam ? 46.0f : 150.0f) * ((float)k + 0.9f * uniform_f()) / (float)K;
                w[k] = 0.01f + 0.1f * uniform_f();
            }
            r[0] = 0.0f;
            CHECK(twin_init(&t, (pihyst_family)fam, K, r, w, -2.0f, fam ? 0.0f : -10.0f,
                            150.0f, fam ? &paper : NULL));
            compare_forward(&t);
            compare_compensator(&t, INFINITY, fam == 0);
        }
    }
    /* PWL banks */
    for (i = 0; i < sizeof sizes / sizeof *sizes; ++i) {
        const size_t K = sizes[i];
        for (k = 0; k < K; ++k) w[k] = 0.01f + 0.1f * uniform_f();
        CHECK(twin_init_pwl(&t, K, w, 0.5f, 0.0f, 150.0f));
        compare_forward(&t);
        compare_compensator(&t, INFINITY, 0);
    }
    printf("single vs double precision: worst |y_f32 - y_f64| %.2f of bound (T), worst "
           "|y_f64(u_f32) - y_d| %.2f of bound (C)\n", worst_forward, worst_compensator);
}
