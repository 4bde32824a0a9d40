/* pihyst_model.c - operator banks and PI-type models: init, reset, step, run,
 * operator matrix, Gram matrix. See pihyst.h for the equations and ownership. */
#include "pihyst.h"
#include "pihyst_internal.h"

#include <stdint.h>
#include <string.h>

#if defined(__GNUC__)
#define PIHYST_INLINE __attribute__((always_inline)) inline
#else
#define PIHYST_INLINE
#endif


/* Operators are processed in lanes of PIHYST_LANES partial sums, which lets the
 * compiler vectorize the weighted sum without reassociating it (no fast-math). */
#define PIHYST_LANES 8
/* The lane loops unrolled, so that the partial sums stay in registers (GCC and clang
 * unroll and vectorise them on their own where there is a vector unit; on a scalar FPU,
 * Cortex-M4F, GCC -O2 otherwise keeps them in memory: 3 extra loads and stores per
 * operator). Only the code changes, not the order of the sums. */
#if defined(__clang__)
#define PIHYST_UNROLL_LANES _Pragma("clang loop unroll(full)")
#elif defined(__GNUC__) && __GNUC__ >= 8
#define PIHYST_UNROLL_LANES _Pragma("GCC unroll 8")
#else
#define PIHYST_UNROLL_LANES
#endif

/* Layout of m->coef (4K reals), by family:
 *   classical:  coef[k]      = -r_k                       R_k(u) = u + coef[k]
 *               coef[K + k]  = +r_k                       F_k(u) = u + coef[K + k]
 *   multislope: coef[k]      = -a r_k                     R_k(u) = max(a u + coef[k],
 *               coef[K + k]  = -r_k - (b - 1)U                          b u + coef[K + k])
 *               coef[2K + k] = (1 - a)U - (1 - a h) r_k   F_k(u) = min(b u, a u + coef[2K + k])
 *   pwl:        coef[0] = 1 if every polyline is a saturated ramp (below), else 0;
 *               the rest unused.
 *
 * Saturated ramps: a polyline of 4 points with y[0] == y[1] and y[2] == y[3] (flat, a
 * rising segment, flat: the Krasnosel'skii-Pokrovskii kernels of pihyst.identify). A
 * model whose polylines all have that shape is detected at init; its operators are then
 * updated by a branch-free loop over the operators (update_ramps) instead of a binary
 * search per polyline, with the same value: y[0] below x[1], y[2] from x[2] on, and
 * between them the generic formula y1 + (y2 - y1)(u - x1)/(x2 - x1) of that segment. */

static real max2(real x, real y) { return x > y ? x : y; }
static real min2(real x, real y) { return x < y ? x : y; }

/* Polyline through (x[i], y[i]), i < n, continued beyond its ends with the end
 * segments' slopes; a single point is a constant. */
static real polyline_eval(const real *x, const real *y, size_t n, real u)
{
    size_t lo = 0, hi;
    if (n == 1) return y[0];
    if (u <= x[0]) {
        lo = 0;
    } else if (u >= x[n - 1]) {
        lo = n - 2;
    } else {
        /* binary search for x[lo] <= u < x[lo + 1] */
        hi = n - 1;
        while (hi - lo > 1) {
            size_t mid = lo + (hi - lo) / 2;
            if (x[mid] <= u) lo = mid; else hi = mid;
        }
    }
    return y[lo] + (y[lo + 1] - y[lo]) * (u - x[lo]) / (x[lo + 1] - x[lo]);
}

static real rise_pwl(const pihyst_pwl *p, size_t k, real u)
{
    size_t s = p->rise_start[k];
    return polyline_eval(p->rise_x + s, p->rise_y + s, p->rise_start[k + 1] - s, u);
}

static real fall_pwl(const pihyst_pwl *p, size_t k, real u)
{
    size_t s = p->fall_start[k];
    return polyline_eval(p->fall_x + s, p->fall_y + s, p->fall_start[k + 1] - s, u);
}

void pihyst_model_envelopes(const pihyst_model *m, real u, real *rise, real *fall)
{
    size_t k, n = m->n_ops;
    const real *c = m->coef;
    for (k = 0; k < n; ++k) {
        switch (m->family) {
        case PIHYST_CLASSICAL:
            rise[k] = u + c[k];
            fall[k] = u + c[n + k];
            break;
        case PIHYST_MULTISLOPE:
            rise[k] = max2(m->shape.a * u + c[k], m->shape.b * u + c[n + k]);
            fall[k] = min2(m->shape.b * u, m->shape.a * u + c[2 * n + k]);
            break;
        default:
            rise[k] = rise_pwl(&m->pwl, k, u);
            fall[k] = fall_pwl(&m->pwl, k, u);
            break;
        }
    }
}

/* ---------------------------------------------------------------- validation */

static int all_finite(const real *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

static pihyst_status check_polyline(const real *x, const real *y, size_t n)
{
    size_t i;
    if (n == 0) return PIHYST_ESIZE;
    if (!all_finite(x, n) || !all_finite(y, n)) return PIHYST_ENONFINITE;
    for (i = 1; i < n; ++i) {
        if (!(x[i] > x[i - 1]) || y[i] < y[i - 1]) return PIHYST_EPOLYLINE;
        /* Breakpoints closer than the smallest normal number: dy (u - x) / dx would
         * amplify the underflow of the product into a staircase, not a line. A slope
         * that overflows would turn the envelope into +-inf and NaN. */
        if (!(x[i] - x[i - 1] >= R_MIN) || !isfinite((y[i] - y[i - 1]) / (x[i] - x[i - 1])))
            return PIHYST_EPOLYLINE;
    }
    return PIHYST_OK;
}

static pihyst_status check_pwl(const pihyst_pwl *p, size_t n_ops)
{
    size_t k;
    pihyst_status s;
    if (!p || !p->rise_start || !p->rise_x || !p->rise_y || !p->fall_start || !p->fall_x ||
        !p->fall_y)
        return PIHYST_ENULL;
    if (p->rise_start[0] != 0 || p->fall_start[0] != 0) return PIHYST_ESIZE;
    for (k = 0; k < n_ops; ++k) {
        size_t rs = p->rise_start[k], re = p->rise_start[k + 1];
        size_t fs = p->fall_start[k], fe = p->fall_start[k + 1];
        if (re <= rs || fe <= fs) return PIHYST_ESIZE;
        s = check_polyline(p->rise_x + rs, p->rise_y + rs, re - rs);
        if (s != PIHYST_OK) return s;
        s = check_polyline(p->fall_x + fs, p->fall_y + fs, fe - fs);
        if (s != PIHYST_OK) return s;
    }
    return PIHYST_OK;
}

/* every polyline a saturated ramp (see the coef layout): operator k's points at 4k */
static int all_ramps(const pihyst_pwl *p, size_t K)
{
    size_t k;
    for (k = 0; k < K; ++k) {
        const real *ry = p->rise_y + 4 * k, *fy = p->fall_y + 4 * k;
        if (p->rise_start[k + 1] != 4 * (k + 1) || p->fall_start[k + 1] != 4 * (k + 1))
            return 0;
        if (!(ry[0] == ry[1] && ry[2] == ry[3] && fy[0] == fy[1] && fy[2] == fy[3]))
            return 0;
    }
    return 1;
}

/* R_k <= F_k on [u_min, u_max]: both are piecewise linear, so it suffices to check
 * the ends of the range and every breakpoint of either envelope inside it. */
static int envelope_ok_at(const pihyst_model *m, size_t k, real u)
{
    real r, f;
    switch (m->family) {
    case PIHYST_CLASSICAL:
        r = u + m->coef[k];
        f = u + m->coef[m->n_ops + k];
        break;
    case PIHYST_MULTISLOPE:
        r = max2(m->shape.a * u + m->coef[k], m->shape.b * u + m->coef[m->n_ops + k]);
        f = min2(m->shape.b * u, m->shape.a * u + m->coef[2 * m->n_ops + k]);
        break;
    default:
        r = rise_pwl(&m->pwl, k, u);
        f = fall_pwl(&m->pwl, k, u);
        break;
    }
    /* relative slack for the rounding of the envelope constants */
    return r <= f + R_SLACK * (RC(1.0) + R_FABS(f));
}

static int envelopes_ordered(const pihyst_model *m)
{
    size_t k, i;
    for (k = 0; k < m->n_ops; ++k) {
        if (!envelope_ok_at(m, k, m->u_min) || !envelope_ok_at(m, k, m->u_max)) return 0;
        if (m->family == PIHYST_MULTISLOPE) {
            const pihyst_shape *s = &m->shape;
            real r = m->thresholds[k];
            real kink_r = (r + (s->b - RC(1.0)) * s->U - s->a * r) / (s->b - s->a);
            real kink_f = ((RC(1.0) - s->a) * s->U - (RC(1.0) - s->a * s->h) * r) / (s->b - s->a);
            if (kink_r > m->u_min && kink_r < m->u_max && !envelope_ok_at(m, k, kink_r)) return 0;
            if (kink_f > m->u_min && kink_f < m->u_max && !envelope_ok_at(m, k, kink_f)) return 0;
        } else if (m->family == PIHYST_PWL) {
            const pihyst_pwl *p = &m->pwl;
            for (i = p->rise_start[k]; i < p->rise_start[k + 1]; ++i)
                if (p->rise_x[i] > m->u_min && p->rise_x[i] < m->u_max &&
                    !envelope_ok_at(m, k, p->rise_x[i]))
                    return 0;
            for (i = p->fall_start[k]; i < p->fall_start[k + 1]; ++i)
                if (p->fall_x[i] > m->u_min && p->fall_x[i] < m->u_max &&
                    !envelope_ok_at(m, k, p->fall_x[i]))
                    return 0;
        }
    }
    return 1;
}

pihyst_status pihyst_model_init(pihyst_model *m, const pihyst_params *params, real *coef,
                                real *state)
{
    size_t k, n_ops;
    const real *thresholds, *weights;
    pihyst_status s;
    if (!m || !params || !params->weights || !coef || !state) return PIHYST_ENULL;
    if (params->family != PIHYST_CLASSICAL && params->family != PIHYST_MULTISLOPE &&
        params->family != PIHYST_PWL)
        return PIHYST_EFAMILY;
    n_ops = params->n_ops;
    thresholds = params->thresholds;
    weights = params->weights;
    if (n_ops == 0) return PIHYST_ESIZE;
    if (!all_finite(weights, n_ops) || !isfinite(params->offset) || !isfinite(params->u_min) ||
        !isfinite(params->u_max))
        return PIHYST_ENONFINITE;
    if (!(params->u_min < params->u_max)) return PIHYST_ERANGE;
    if (params->initial_state && !all_finite(params->initial_state, n_ops))
        return PIHYST_ENONFINITE;

    memset(m, 0, sizeof *m);
    m->family = params->family;
    m->n_ops = n_ops;
    m->weights = weights;
    m->offset = params->offset;
    m->u_min = params->u_min;
    m->u_max = params->u_max;
    m->coef = coef;
    m->state = state;

    if (m->family != PIHYST_PWL) {
        if (!thresholds) return PIHYST_ENULL;
        if (!all_finite(thresholds, n_ops)) return PIHYST_ENONFINITE;
        for (k = 0; k < n_ops; ++k)
            if (thresholds[k] < RC(0.0) || (k > 0 && !(thresholds[k] > thresholds[k - 1])))
                return PIHYST_ETHRESHOLD;
        m->thresholds = thresholds;
    }
    switch (m->family) {
    case PIHYST_CLASSICAL:
        for (k = 0; k < n_ops; ++k) {
            coef[k] = -thresholds[k];
            coef[n_ops + k] = thresholds[k];
        }
        break;
    case PIHYST_MULTISLOPE: {
        const pihyst_shape *shape = &params->shape;
        const real U = shape->U, a = shape->a, b = shape->b, h = shape->h;
        if (!isfinite(U) || !isfinite(a) || !isfinite(b) || !isfinite(h)) return PIHYST_ENONFINITE;
        if (!(U > RC(0.0)) || !(a > RC(0.0)) || !(b > a) || !(h >= RC(0.0)) || !(h <= RC(1.0)))
            return PIHYST_ESHAPE;
        /* F's kink u = ((1 - a)U - (1 - a h) r) / (b - a) must not fall below 0 */
        if (thresholds[n_ops - 1] >
            (RC(1.0) - a) * U / (RC(1.0) - a * h) * (RC(1.0) + R_SLACK))
            return PIHYST_EMULTISLOPE_R;
        m->shape = *shape;
        for (k = 0; k < n_ops; ++k) {
            const real r = thresholds[k];
            coef[k] = -a * r;
            coef[n_ops + k] = -r - (b - RC(1.0)) * U;
            coef[2 * n_ops + k] = (RC(1.0) - a) * U - (RC(1.0) - a * h) * r;
            coef[3 * n_ops + k] = RC(0.0);
        }
        break;
    }
    default: /* PIHYST_PWL */
        s = check_pwl(&params->pwl, n_ops);
        if (s != PIHYST_OK) return s;
        m->pwl = params->pwl;
        for (k = 0; k < PIHYST_COEF_LEN(n_ops); ++k) coef[k] = RC(0.0);
        coef[0] = all_ramps(&m->pwl, n_ops) ? RC(1.0) : RC(0.0);
        break;
    }
    if (!envelopes_ordered(m)) return PIHYST_EENVELOPE;
    pihyst_model_reset(m, params->initial_state);
    return PIHYST_OK;
}

void pihyst_model_reset(pihyst_model *m, const real *initial_state)
{
    size_t k;
    for (k = 0; k < m->n_ops; ++k) m->state[k] = initial_state ? initial_state[k] : RC(0.0);
}

/* ---------------------------------------------------------------- hot loops */

/* Each kernel advances the state over n samples. With y != NULL it writes the model
 * output (2); with phi != NULL the operator matrix; with gram != NULL it accumulates
 * the normal equations. Time is the outer loop, operators the inner one. */

/* classical: f_k = max(u - r_k, min(u + r_k, f_k)),  y = offset + sum_k w_k f_k */
PIHYST_HOT
static void run_classical(size_t K, const real *PIHYST_RESTRICT w, const real *PIHYST_RESTRICT c,
                          real *PIHYST_RESTRICT f, real offset, const real *PIHYST_RESTRICT u,
                          real *PIHYST_RESTRICT y, size_t n)
{
    size_t t, k, j;
    const size_t K_lanes = K - K % PIHYST_LANES;
    for (t = 0; t < n; ++t) {
        const real ut = u[t];
        real acc[PIHYST_LANES] = {RC(0.0)};
        real sum = offset;
        for (k = 0; k < K_lanes; k += PIHYST_LANES) {
            PIHYST_UNROLL_LANES
            for (j = 0; j < PIHYST_LANES; ++j) {
                real v = f[k + j], hi = ut + c[K + k + j], lo = ut + c[k + j];
                v = v < hi ? v : hi;
                v = v > lo ? v : lo;
                f[k + j] = v;
                acc[j] += w[k + j] * v;
            }
        }
        for (k = K_lanes; k < K; ++k) {
            real v = f[k], hi = ut + c[K + k], lo = ut + c[k];
            v = v < hi ? v : hi;
            v = v > lo ? v : lo;
            f[k] = v;
            sum += w[k] * v;
        }
        PIHYST_UNROLL_LANES
        for (j = 0; j < PIHYST_LANES; ++j) sum += acc[j];
        y[t] = sum;
    }
}

/* Small banks, K <= PIHYST_SMALL = 16 (GCC and clang): the operators are padded to 16
 * (padding: envelope constants 0 and weight 0, so a padded operator follows u and adds a
 * zero) and held for the whole block in four vector variables of four lanes each
 * (compiler vector extensions), which the compiler keeps in registers: no state store
 * and reload between samples. min and max are the scalar loops' v < h ? v : h per lane
 * (NaN included), which compiles to one vector min/max. The weighted sum is a fixed tree,
 * ((a0 + a1) + (a2 + a3)) over the vectors then (s0 + s2) + (s1 + s3) over the lanes:
 * a short dependency chain whose order depends on neither n nor the data, so step and
 * run still give the same bits. The vectors are 4 x real (32 bytes in double, 16 in
 * single): one AVX2 register, or two SSE2 ones in the default clone of PIHYST_HOT.
 * Other compilers use the generic loops below. */
#define PIHYST_SMALL 16
#if defined(__GNUC__) && !defined(PIHYST_NO_VECTOR_EXT)
#define PIHYST_HAVE_SMALL 1
typedef real vreal __attribute__((vector_size(4 * sizeof(real))));

/* Lane updates as macros on named vectors (no vector passed by value: that would depend
 * on the ABI of the clone). The per-lane selects v < h ? v : h are those of the scalar
 * loops (NaN included) and compile to one vector min/max each. */
#define PIHYST_CLAMP_LANES(fj, hj, lj)                                \
    do {                                                              \
        int i_;                                                       \
        for (i_ = 0; i_ < 4; ++i_) {                                  \
            real v_ = (fj)[i_];                                       \
            v_ = v_ < (hj)[i_] ? v_ : (hj)[i_];                       \
            (fj)[i_] = v_ > (lj)[i_] ? v_ : (lj)[i_];                 \
        }                                                             \
    } while (0)
#define PIHYST_MAX_LANES(r, x, z)                                     \
    do {                                                              \
        int i_;                                                       \
        for (i_ = 0; i_ < 4; ++i_) (r)[i_] = (x)[i_] > (z)[i_] ? (x)[i_] : (z)[i_]; \
    } while (0)
#define PIHYST_MIN_LANES(r, x, z)                                     \
    do {                                                              \
        int i_;                                                       \
        for (i_ = 0; i_ < 4; ++i_) (r)[i_] = (x)[i_] < (z)[i_] ? (x)[i_] : (z)[i_]; \
    } while (0)
/* the fixed tree of the weighted sum */
#define PIHYST_TREE_SUM(s, a0, a1, a2, a3) \
    ((s) = ((a0) + (a1)) + ((a2) + (a3)), ((s)[0] + (s)[2]) + ((s)[1] + (s)[3]))

/* 16 values (K of x, then zeros) into four vectors; K = 16 is a plain copy of constant
 * size (four vector loads: a single-sample call, as the compensator makes, stays cheap) */
static PIHYST_INLINE void load_padded(vreal *v, const real *x, size_t K)
{
    if (K == PIHYST_SMALL) {
        memcpy(v, x, PIHYST_SMALL * sizeof *x);
    } else {
        real tmp[PIHYST_SMALL] = {RC(0.0)};
        memcpy(tmp, x, K * sizeof *x);
        memcpy(v, tmp, sizeof tmp);
    }
}

static PIHYST_INLINE void store_state(real *f, const vreal *v, size_t K)
{
    if (K == PIHYST_SMALL) {
        memcpy(f, v, PIHYST_SMALL * sizeof *f);
    } else {
        real tmp[PIHYST_SMALL];
        memcpy(tmp, v, sizeof tmp);
        memcpy(f, tmp, K * sizeof *f);
    }
}

PIHYST_HOT
static void run_classical_small(size_t K, const real *PIHYST_RESTRICT w, const real *PIHYST_RESTRICT c,
                                real *PIHYST_RESTRICT f, real offset, const real *PIHYST_RESTRICT u,
                                real *PIHYST_RESTRICT y, size_t n)
{
    vreal fv[4], lo[4], hi[4], wv[4];
    vreal f0, f1, f2, f3;
    size_t t;
    load_padded(fv, f, K);
    load_padded(lo, c, K);
    load_padded(hi, c + K, K);
    load_padded(wv, w, K);
    f0 = fv[0]; f1 = fv[1]; f2 = fv[2]; f3 = fv[3];
    for (t = 0; t < n; ++t) {
        const vreal ut = {u[t], u[t], u[t], u[t]};
        vreal h0 = ut + hi[0], h1 = ut + hi[1], h2 = ut + hi[2], h3 = ut + hi[3];
        vreal l0 = ut + lo[0], l1 = ut + lo[1], l2 = ut + lo[2], l3 = ut + lo[3], s;
        PIHYST_CLAMP_LANES(f0, h0, l0);
        PIHYST_CLAMP_LANES(f1, h1, l1);
        PIHYST_CLAMP_LANES(f2, h2, l2);
        PIHYST_CLAMP_LANES(f3, h3, l3);
        y[t] = offset + PIHYST_TREE_SUM(s, wv[0] * f0, wv[1] * f1, wv[2] * f2, wv[3] * f3);
    }
    fv[0] = f0; fv[1] = f1; fv[2] = f2; fv[3] = f3;
    store_state(f, fv, K);
}

PIHYST_HOT
static void run_multislope_small(size_t K, real a, real b, const real *PIHYST_RESTRICT w,
                                 const real *PIHYST_RESTRICT c, real *PIHYST_RESTRICT f, real offset,
                                 const real *PIHYST_RESTRICT u, real *PIHYST_RESTRICT y, size_t n)
{
    vreal fv[4], c1[4], c2[4], c3[4], wv[4];
    vreal f0, f1, f2, f3;
    size_t t;
    load_padded(fv, f, K);
    load_padded(c1, c, K);
    load_padded(c2, c + K, K);
    load_padded(c3, c + 2 * K, K);
    load_padded(wv, w, K);
    f0 = fv[0]; f1 = fv[1]; f2 = fv[2]; f3 = fv[3];
    for (t = 0; t < n; ++t) {
        const real aus = a * u[t], bus = b * u[t];
        const vreal au = {aus, aus, aus, aus}, bu = {bus, bus, bus, bus};
        vreal s;
#define PIHYST_MS_LANE(fj, j)                                 \
    do {                                                      \
        vreal r1 = au + c1[j], r2 = bu + c2[j], f2_ = au + c3[j], l_, h_; \
        PIHYST_MAX_LANES(l_, r1, r2);                         \
        PIHYST_MIN_LANES(h_, bu, f2_);                        \
        PIHYST_CLAMP_LANES(fj, h_, l_);                       \
    } while (0)
        PIHYST_MS_LANE(f0, 0);
        PIHYST_MS_LANE(f1, 1);
        PIHYST_MS_LANE(f2, 2);
        PIHYST_MS_LANE(f3, 3);
#undef PIHYST_MS_LANE
        y[t] = offset + PIHYST_TREE_SUM(s, wv[0] * f0, wv[1] * f1, wv[2] * f2, wv[3] * f3);
    }
    fv[0] = f0; fv[1] = f1; fv[2] = f2; fv[3] = f3;
    store_state(f, fv, K);
}
#endif

/* multislope: f_k = max(max(a u - a r_k, b u - r_k - (b-1)U),
 *                       min(min(b u, a u + (1-a)U - (1-ah) r_k), f_k)) */
PIHYST_HOT
static void run_multislope(size_t K, real a, real b, const real *PIHYST_RESTRICT w,
                           const real *PIHYST_RESTRICT c, real *PIHYST_RESTRICT f, real offset,
                           const real *PIHYST_RESTRICT u, real *PIHYST_RESTRICT y, size_t n)
{
    size_t t, k, j;
    const size_t K_lanes = K - K % PIHYST_LANES;
    for (t = 0; t < n; ++t) {
        const real au = a * u[t], bu = b * u[t];
        real acc[PIHYST_LANES] = {RC(0.0)};
        real sum = offset;
        for (k = 0; k < K_lanes; k += PIHYST_LANES) {
            PIHYST_UNROLL_LANES
            for (j = 0; j < PIHYST_LANES; ++j) {
                real r1 = au + c[k + j], r2 = bu + c[K + k + j], f2 = au + c[2 * K + k + j];
                real lo = r1 > r2 ? r1 : r2;
                real hi = bu < f2 ? bu : f2;
                real v = f[k + j];
                v = v < hi ? v : hi;
                v = v > lo ? v : lo;
                f[k + j] = v;
                acc[j] += w[k + j] * v;
            }
        }
        for (k = K_lanes; k < K; ++k) {
            real r1 = au + c[k], r2 = bu + c[K + k], f2 = au + c[2 * K + k];
            real lo = r1 > r2 ? r1 : r2;
            real hi = bu < f2 ? bu : f2;
            real v = f[k];
            v = v < hi ? v : hi;
            v = v > lo ? v : lo;
            f[k] = v;
            sum += w[k] * v;
        }
        PIHYST_UNROLL_LANES
        for (j = 0; j < PIHYST_LANES; ++j) sum += acc[j];
        y[t] = sum;
    }
}

/* Saturated-ramp polylines (see the coef layout): every polyline has 4 points, so
 * operator k's are at 4k. The value (PIHYST_RAMP_VALUE, pihyst_internal.h, which the
 * compensator's ramp step shares) equals polyline_eval's (up to the sign of a zero). */
#define PIHYST_RAMP(x, y, u) PIHYST_RAMP_VALUE((x)[1], (x)[2], (y)[0], (y)[1], (y)[2], u)

PIHYST_HOT
static void update_ramps(size_t K, const real *PIHYST_RESTRICT rx, const real *PIHYST_RESTRICT ry,
                         const real *PIHYST_RESTRICT fx, const real *PIHYST_RESTRICT fy, real *PIHYST_RESTRICT f,
                         real u)
{
    size_t k;
    for (k = 0; k < K; ++k) {
        const real r = PIHYST_RAMP(rx + 4 * k, ry + 4 * k, u);
        const real h = PIHYST_RAMP(fx + 4 * k, fy + 4 * k, u);
        const real v = h < f[k] ? h : f[k]; /* max2(r, min2(h, f)) as the generic loop */
        f[k] = r > v ? r : v;
    }
}

/* One sample of (1) for every operator, any family (used by the slow paths). */
static void update_operators(pihyst_model *m, real u)
{
    size_t k, K = m->n_ops;
    const real *c = m->coef;
    real *f = m->state;
    switch (m->family) {
    case PIHYST_CLASSICAL:
        for (k = 0; k < K; ++k) f[k] = max2(u + c[k], min2(u + c[K + k], f[k]));
        break;
    case PIHYST_MULTISLOPE: {
        real au = m->shape.a * u, bu = m->shape.b * u;
        for (k = 0; k < K; ++k)
            f[k] = max2(max2(au + c[k], bu + c[K + k]), min2(min2(bu, au + c[2 * K + k]), f[k]));
        break;
    }
    default:
        if (c[0] == RC(1.0)) {
            update_ramps(K, m->pwl.rise_x, m->pwl.rise_y, m->pwl.fall_x, m->pwl.fall_y, f, u);
            break;
        }
        for (k = 0; k < K; ++k)
            f[k] = max2(rise_pwl(&m->pwl, k, u), min2(fall_pwl(&m->pwl, k, u), f[k]));
        break;
    }
}

/* y = offset + sum_k w_k f_k in PIHYST_LANES partial sums (as run_classical): a chain of
 * K dependent additions would cost K times the adder's latency per sample */
PIHYST_HOT
static real weighted_sum(size_t K, const real *PIHYST_RESTRICT w, const real *PIHYST_RESTRICT f, real offset)
{
    size_t k, j;
    const size_t K_lanes = K - K % PIHYST_LANES;
    real acc[PIHYST_LANES] = {RC(0.0)};
    real sum = offset;
    for (k = 0; k < K_lanes; k += PIHYST_LANES)
        PIHYST_UNROLL_LANES
        for (j = 0; j < PIHYST_LANES; ++j) acc[j] += w[k + j] * f[k + j];
    for (k = K_lanes; k < K; ++k) sum += w[k] * f[k];
    PIHYST_UNROLL_LANES
    for (j = 0; j < PIHYST_LANES; ++j) sum += acc[j];
    return sum;
}

/* the model's sum for the compensator's ramp step (pihyst_internal.h), bit for bit */
real pihyst_internal_weighted_sum(size_t K, const real *w, const real *f, real offset)
{
    return weighted_sum(K, w, f, offset);
}

real pihyst_internal_output_at(const pihyst_model *m, real u)
{
    size_t k, K = m->n_ops;
    const real *c = m->coef, *f = m->state;
    real y = m->offset;
    for (k = 0; k < K; ++k) {
        real rise, fall;
        switch (m->family) {
        case PIHYST_CLASSICAL:
            rise = u + c[k];
            fall = u + c[K + k];
            break;
        case PIHYST_MULTISLOPE:
            rise = max2(m->shape.a * u + c[k], m->shape.b * u + c[K + k]);
            fall = min2(m->shape.b * u, m->shape.a * u + c[2 * K + k]);
            break;
        default:
            rise = rise_pwl(&m->pwl, k, u);
            fall = fall_pwl(&m->pwl, k, u);
            break;
        }
        y += m->weights[k] * max2(rise, min2(fall, f[k]));
    }
    return y;
}

static void run_pwl(pihyst_model *m, const real *u, real *y, size_t n)
{
    size_t t;
    for (t = 0; t < n; ++t) {
        update_operators(m, u[t]);
        y[t] = weighted_sum(m->n_ops, m->weights, m->state, m->offset);
    }
}

/* The loops store the operator state and load it back a sample later: a state on a
 * 64-byte boundary runs up to twice as fast on x86-64 (no vector store straddles two
 * cache lines, so store-to-load forwarding works). The compensator sees to that itself
 * (PIHYST_STATE_ALIGN); direct callers align their state array. */
void pihyst_model_run(pihyst_model *m, const real *u, real *y, size_t n)
{
    switch (m->family) {
    case PIHYST_CLASSICAL:
#ifdef PIHYST_HAVE_SMALL
        if (m->n_ops <= PIHYST_SMALL) {
            run_classical_small(m->n_ops, m->weights, m->coef, m->state, m->offset, u, y, n);
            break;
        }
#endif
        run_classical(m->n_ops, m->weights, m->coef, m->state, m->offset, u, y, n);
        break;
    case PIHYST_MULTISLOPE:
#ifdef PIHYST_HAVE_SMALL
        if (m->n_ops <= PIHYST_SMALL) {
            run_multislope_small(m->n_ops, m->shape.a, m->shape.b, m->weights, m->coef,
                                 m->state, m->offset, u, y, n);
            break;
        }
#endif
        run_multislope(m->n_ops, m->shape.a, m->shape.b, m->weights, m->coef, m->state,
                       m->offset, u, y, n);
        break;
    default:
        run_pwl(m, u, y, n);
        break;
    }
}

/* step is run on one sample, so that step-by-step and block give the same bits */
real pihyst_model_step(pihyst_model *m, real u)
{
    real y;
    pihyst_model_run(m, &u, &y, 1);
    return y;
}

void pihyst_model_operators(pihyst_model *m, const real *u, real *phi, size_t n)
{
    size_t t, K = m->n_ops;
    for (t = 0; t < n; ++t) {
        update_operators(m, u[t]);
        memcpy(phi + t * K, m->state, K * sizeof *phi);
    }
}

/* gram += f f^T, rhs += f d, sums += f, accumulated over t; the upper triangle is
 * summed and mirrored so the matrix is exactly symmetric. */
void pihyst_model_gram(pihyst_model *m, const real *u, const real *d, size_t n,
                       real *gram, real *rhs, real *sums)
{
    size_t t, j, k, K = m->n_ops;
    const real *f = m->state;
    for (t = 0; t < n; ++t) {
        update_operators(m, u[t]);
        for (j = 0; j < K; ++j) {
            const real fj = f[j];
            rhs[j] += fj * d[t];
            if (sums) sums[j] += fj;
            for (k = j; k < K; ++k) gram[j * K + k] += fj * f[k];
        }
    }
    for (j = 0; j < K; ++j)
        for (k = 0; k < j; ++k) gram[j * K + k] = gram[k * K + j];
}

#ifndef PIHYST_BUILD_F32 /* one definition, in the double build */
const char *pihyst_status_text(pihyst_status status)
{
    switch (status) {
    case PIHYST_OK: return "ok";
    case PIHYST_ENULL: return "a required array is missing (NULL)";
    case PIHYST_ESIZE: return "empty operator bank or empty polyline";
    case PIHYST_ENONFINITE: return "a parameter or state value is NaN or infinite";
    case PIHYST_ETHRESHOLD: return "thresholds must be >= 0 and strictly increasing";
    case PIHYST_ESHAPE: return "multislope shape must have U > 0, 0 < a < b and 0 <= h <= 1";
    case PIHYST_EMULTISLOPE_R:
        return "multislope threshold above (1 - a)U / (1 - a h): the falling envelope "
               "would not return to the origin";
    case PIHYST_EPOLYLINE:
        return "polyline breakpoints must be strictly increasing (by more than the smallest "
               "normal number), values non-decreasing and slopes finite";
    case PIHYST_EENVELOPE: return "rising envelope above falling envelope on the input range";
    case PIHYST_ERANGE: return "input range must have u_min < u_max";
    case PIHYST_ENEGATIVE_WEIGHT:
        return "compensation needs non-negative weights (the model must be monotone)";
    case PIHYST_ELIMITS:
        return "voltage limits must lie in the model's input range with u_min < u_max, the "
               "slew limit must be > 0, and the voltage must lie within the limits";
    case PIHYST_EFAMILY: return "unknown model family";
    case PIHYST_ESCRATCH: return "compensator scratch shorter than pihyst_compensator_scratch_len";
    }
    return "unknown status";
}
#endif
