/* pihyst_bank_soa.c - a compensator bank laid out structure-of-arrays, with a fast path
 * for classical channels (the "Compensator banks, structure-of-arrays" section of
 * pihyst_api.h; docs/c-core.md).
 *
 * The fast path. A classical model with thresholds 0 = r_0 < r_1 < ... and weights
 * w_0 > 0, w_k >= 0 is strictly increasing in its input, and its exact inverse is again
 * a classical PI model, in the displacement y~ = y - offset (docs/theory/inverse.md):
 *
 *     z_j <- min(max(z_j, y~ - r'_j), y~ + r'_j)                          (I1)
 *     u    = sum_j w'_j z_j                                                (I2)
 *     r'_j = r'_{j-1} + W_{j-1} (r_j - r_{j-1}),  r'_0 = 0                 (I3)
 *     w'_0 = 1 / W_0,  w'_j = -w_j / (W_j W_{j-1})                        (I4)
 *
 * with W_j = sum_{i<=j} w_i. Its play states are a linear function of the model's
 * operator state f (the state after the last voltage):
 *
 *     z_j = W_j f_j + sum_{i>j} w_i f_i                                   (T)
 *     f_{K-1} = z_{K-1} / W_{K-1},  f_j = f_{j+1} + (z_j - z_{j+1}) / W_j   (T^-1)
 *
 * (z_j - z_{j+1} = W_j (f_j - f_{j+1})). For a state 1-Lipschitz in r,
 * |f_i - f_j| <= r_j - r_i (every reachable state is, see walk_classical in
 * pihyst_inverse.c), |y~ - z_j| = |sum_{i<=j} w_i (f_i - f_j)| <= r'_j, and one step of
 * (I1)-(I2) for a desired y gives the voltage u at which the model reaches y, the z of
 * the model's state after u, and y itself as the output: what the exact compensator
 * finds by its walk, to rounding. It is K clamps and a dot product, without a branch.
 *
 * Layout. Channels are grouped L at a time (L = 64 bytes of reals: 8 doubles, 16
 * floats; one AVX-512 register, two AVX2 ones); a group is a header of PIHYST_SOA_HEADER
 * vectors of L lanes (one lane per channel: offset, u_last, y_last, tol, u_min, u_max,
 * max_step, mode) and then, for each operator k < n_ops, four vectors: r'_k, w'_k and
 * the play states z_k in two buffers.
 * A tick reads one buffer and writes the other (the parity flips every tick), so the
 * state before the tick is still there for a channel that needs the exact path. The
 * groups lie one after the other on a 64-byte boundary. n_ops is the largest K of the
 * fast channels rounded up to 4 (the dot product runs four partial sums); padding
 * operators have r' = 0 and w' = 0.
 *
 * A tick, per group: every lane's y~ (the last output for a hold), (I1)-(I2) for the L
 * lanes at once, then per lane (decided for all lanes at once without a branch, the
 * lanes left for the exact path then taken one by one):
 *   - hold (|y_d - y_last| <= tol, or y_d NaN, as the exact compensator): u_last held,
 *     flag NaN for NaN; (I1) at y_last leaves z as it was, to rounding;
 *   - u inside [u_min, u_max] and |u - u_last| <= max_step (checked in floating point,
 *     as the exact compensator guarantees): u is the voltage, y_d the output, no flag;
 *   - otherwise (y_d out of reach or beyond the slew limit, infinite or huge y_d): the
 *     exact path. f = T^-1 z from the buffer of the tick before is set as the channel's
 *     compensator state at u_last (pihyst_compensator_reset), the compensator steps y_d
 *     (clamp to the window, flags), and z = T f of its new state goes into the buffer
 *     of this tick.
 * Channels without the fast path (other families, r_0 > 0, w_0 = 0 or below 1/1024 of
 * sum w, where the inverse's weights would amplify rounding) run their compensator every
 * tick. A classical channel whose state is not 1-Lipschitz (set by a reset) also does,
 * and joins the fast path as soon as its state is (checked after each of its ticks).
 */
#include "pihyst.h"
#include "pihyst_internal.h"

#include <stdint.h>
#include <string.h>

#if defined(__GNUC__)
#define PIHYST_INLINE __attribute__((always_inline)) inline
#else
#define PIHYST_INLINE
#endif

#define L PIHYST_SOA_LANES_OF(real)
#define ALIGN_BYTES 64

/* header vectors of a group */
enum { H_OFFSET, H_U_LAST, H_Y_LAST, H_TOL, H_U_MIN, H_U_MAX, H_MAX_STEP, H_MODE };
/* lane modes (stored as reals in H_MODE) */
#define MODE_NONE RC(0.0)    /* padding lane beyond channel n - 1 */
#define MODE_FAST RC(1.0)    /* (I1)-(I2) */
#define MODE_EXACT RC(2.0)   /* its compensator every tick */
#define MODE_PENDING RC(3.0) /* classical with the fast path, state not yet 1-Lipschitz */

/* per-operator vectors of a group */
enum { OP_R, OP_W, OP_Z0, OP_Z1, OP_VECTORS };

static size_t group_len(size_t n_ops) { return (PIHYST_SOA_HEADER + OP_VECTORS * n_ops) * L; }

static real *group_at(const pihyst_compbank *b, size_t g)
{
    return b->groups + g * group_len(b->n_ops);
}

/* the classical channels whose inverse (I1)-(I4) is used */
static int has_fast_path(const pihyst_compensator *c)
{
    const pihyst_model *m = c->model;
    const size_t K = m->n_ops;
    real W = RC(0.0);
    size_t k;
    if (m->family != PIHYST_CLASSICAL || m->thresholds[0] != RC(0.0)) return 0;
    for (k = 0; k < K; ++k) W += m->weights[k];
    /* w'_0 = 1 / w_0 multiplies the rounding of z (of the order eps (|y| + r'_K)): with
     * w_0 >= W / 1024 the voltage stays within about 1e-11 of the range in double */
    return m->weights[0] > RC(0.0) && m->weights[0] >= W * RC(0.0009765625);
}

/* 1 if the state is 1-Lipschitz in r to a few ulps (as pihyst_inverse.c's lipschitz) */
static int lipschitz(const pihyst_compensator *c)
{
    const pihyst_model *m = c->model;
    const size_t K = m->n_ops;
    const real *r = m->thresholds, *f = m->state;
    const real u_big = R_FABS(c->u_min) > R_FABS(c->u_max) ? R_FABS(c->u_min) : R_FABS(c->u_max);
    const real tol = RC(8.0) * R_EPS * (u_big + r[K - 1]);
    size_t k;
    int bad = 0;
    for (k = 1; k < K; ++k) bad |= R_FABS(f[k] - f[k - 1]) > (r[k] - r[k - 1]) + tol;
    return !bad;
}

/* (T): lane l of the buffer `buf` of group grp from the model state f */
static void to_inverse_state(real *grp, size_t l, int buf, const pihyst_model *m)
{
    const size_t K = m->n_ops;
    const real *w = m->weights, *f = m->state;
    real *ops = grp + PIHYST_SOA_HEADER * L, W = RC(0.0), S = RC(0.0);
    size_t k;
    for (k = 0; k < K; ++k) W += w[k];
    for (k = K; k-- > 0;) { /* W here is W_k: W_{k+1} - w_{k+1} */
        ops[(OP_VECTORS * k + OP_Z0 + buf) * L + l] = W * f[k] + S;
        S += w[k] * f[k];
        W -= w[k];
    }
}

/* (T^-1): the model state from lane l of buffer buf */
static void from_inverse_state(const real *grp, size_t l, int buf, pihyst_model *m)
{
    const size_t K = m->n_ops;
    const real *w = m->weights, *ops = grp + PIHYST_SOA_HEADER * L;
    real *f = m->state, W = RC(0.0), z_next;
    size_t k;
    for (k = 0; k < K; ++k) W += w[k];
    z_next = ops[(OP_VECTORS * (K - 1) + OP_Z0 + buf) * L + l];
    f[K - 1] = z_next / W;
    for (k = K - 1; k-- > 0;) {
        const real z = ops[(OP_VECTORS * k + OP_Z0 + buf) * L + l];
        W -= w[k + 1]; /* W_k */
        f[k] = f[k + 1] + (z - z_next) / W;
        z_next = z;
    }
}

/* lane l of group grp: the channel's inverse (I3)-(I4), limits and the state (T) in
 * buffer buf, from its compensator (fast mode) */
static void load_fast(pihyst_compbank *b, real *grp, size_t l, int buf,
                      const pihyst_compensator *c)
{
    const pihyst_model *m = c->model;
    const size_t K = m->n_ops;
    const real *w = m->weights, *r = m->thresholds;
    real *ops = grp + PIHYST_SOA_HEADER * L, W_prev = w[0], rp = RC(0.0);
    size_t k;
    ops[OP_R * L + l] = RC(0.0);
    ops[OP_W * L + l] = RC(1.0) / w[0];
    for (k = 1; k < K; ++k) {
        const real W = W_prev + w[k];
        rp += W_prev * (r[k] - r[k - 1]);
        ops[(OP_VECTORS * k + OP_R) * L + l] = rp;
        ops[(OP_VECTORS * k + OP_W) * L + l] = -w[k] / (W * W_prev);
        W_prev = W;
    }
    for (k = K; k < b->n_ops; ++k) { /* padding: z = y~, no weight */
        ops[(OP_VECTORS * k + OP_R) * L + l] = RC(0.0);
        ops[(OP_VECTORS * k + OP_W) * L + l] = RC(0.0);
        ops[(OP_VECTORS * k + OP_Z0) * L + l] = RC(0.0);
        ops[(OP_VECTORS * k + OP_Z1) * L + l] = RC(0.0);
    }
    to_inverse_state(grp, l, buf, m);
    grp[H_OFFSET * L + l] = m->offset;
    grp[H_U_LAST * L + l] = c->u_last;
    grp[H_Y_LAST * L + l] = c->y_last;
    grp[H_TOL * L + l] = c->tol;
    grp[H_U_MIN * L + l] = c->u_min;
    grp[H_U_MAX * L + l] = c->u_max;
    grp[H_MAX_STEP * L + l] = c->max_step;
    grp[H_MODE * L + l] = MODE_FAST;
}

/* lane l off the fast path: r' = w' = z = 0, offset = y_last = 0 and tol = inf, so the
 * lane holds at y~ = 0 and its z stay 0 */
static void load_idle(pihyst_compbank *b, real *grp, size_t l, real mode)
{
    size_t k, j;
    real *ops = grp + PIHYST_SOA_HEADER * L;
    for (k = 0; k < b->n_ops; ++k)
        for (j = 0; j < OP_VECTORS; ++j) ops[(OP_VECTORS * k + j) * L + l] = RC(0.0);
    for (j = 0; j < PIHYST_SOA_HEADER; ++j) grp[j * L + l] = RC(0.0);
    grp[H_TOL * L + l] = R_INF;
    grp[H_MODE * L + l] = mode;
}

size_t pihyst_compbank_work_len(pihyst_compensator *const *comps, size_t n)
{
    size_t i, K = 0;
    if (!comps) return 0;
    for (i = 0; i < n; ++i)
        if (comps[i] && has_fast_path(comps[i]) && comps[i]->model->n_ops > K)
            K = comps[i]->model->n_ops;
    K = (K + 3) / 4 * 4;
    return (n + L - 1) / L * group_len(K) + ALIGN_BYTES / sizeof(real);
}

pihyst_status pihyst_compbank_init(pihyst_compbank *b, pihyst_compensator *const *comps,
                                   size_t n, real *work, size_t work_len)
{
    size_t i, K = 0;
    uintptr_t at;
    if (!b || !comps || (!work && n > 0)) return PIHYST_ENULL;
    for (i = 0; i < n; ++i) {
        if (!comps[i]) return PIHYST_ENULL;
        if (has_fast_path(comps[i]) && comps[i]->model->n_ops > K) K = comps[i]->model->n_ops;
    }
    if (n > 0 && work_len < pihyst_compbank_work_len(comps, n)) return PIHYST_ESCRATCH;
    b->comps = comps;
    b->n = n;
    b->n_ops = (K + 3) / 4 * 4;
    b->parity = 0;
    b->n_fast = 0;
    at = (uintptr_t)work;
    at = (at + ALIGN_BYTES - 1) / ALIGN_BYTES * ALIGN_BYTES;
    b->groups = (real *)at;
    for (i = 0; i < (n + L - 1) / L * L; ++i) {
        real *grp = group_at(b, i / L);
        const size_t l = i % L;
        if (i >= n) {
            load_idle(b, grp, l, MODE_NONE);
        } else if (!has_fast_path(comps[i])) {
            load_idle(b, grp, l, MODE_EXACT);
        } else if (!lipschitz(comps[i])) {
            load_idle(b, grp, l, MODE_PENDING);
        } else {
            load_fast(b, grp, l, 0, comps[i]);
            ++b->n_fast;
        }
    }
    return PIHYST_OK;
}

/* ------------------------------------------------------------------ the tick */

/* (I1)-(I2) for the L lanes of a group: z of buffer `cur` clamped at yt, written to
 * buffer 1 - cur, and u = sum_k w'_k z_k in four partial sums (k mod 4), added as
 * (s0 + s1) + (s2 + s3). n_ops is a multiple of 4. */
#if defined(__GNUC__) && !defined(PIHYST_NO_VECTOR_EXT)
typedef real vlane __attribute__((vector_size(L * sizeof(real))));

#define PIHYST_SOA_CLAMP(z, hi, lo)                          \
    do {                                                     \
        size_t i_;                                           \
        for (i_ = 0; i_ < L; ++i_) {                         \
            real v_ = (z)[i_];                               \
            v_ = v_ < (hi)[i_] ? v_ : (hi)[i_];              \
            (z)[i_] = v_ > (lo)[i_] ? v_ : (lo)[i_];         \
        }                                                    \
    } while (0)

static PIHYST_INLINE void inverse_lanes(size_t n_ops, real *PIHYST_RESTRICT ops, int cur,
                                        const real *PIHYST_RESTRICT yt_in,
                          real *PIHYST_RESTRICT u_out)
{
    vlane yt, s0 = {RC(0.0)}, s1 = {RC(0.0)}, s2 = {RC(0.0)}, s3 = {RC(0.0)}, u;
    vlane *v = (vlane *)__builtin_assume_aligned(ops, 64);
    size_t k;
    memcpy(&yt, yt_in, sizeof yt);
#define PIHYST_SOA_OP(q, s)                                                      \
    do {                                                                         \
        vlane *o_ = v + OP_VECTORS * (k + (q));                                  \
        vlane z_ = o_[OP_Z0 + cur], hi_ = yt + o_[OP_R], lo_ = yt - o_[OP_R];    \
        PIHYST_SOA_CLAMP(z_, hi_, lo_);                                          \
        o_[OP_Z1 - cur] = z_;                                                    \
        s += o_[OP_W] * z_;                                                      \
    } while (0)
    for (k = 0; k < n_ops; k += 4) {
        PIHYST_SOA_OP(0, s0);
        PIHYST_SOA_OP(1, s1);
        PIHYST_SOA_OP(2, s2);
        PIHYST_SOA_OP(3, s3);
    }
#undef PIHYST_SOA_OP
    u = (s0 + s1) + (s2 + s3);
    memcpy(u_out, &u, sizeof u);
}
#else
static PIHYST_INLINE void inverse_lanes(size_t n_ops, real *PIHYST_RESTRICT ops, int cur,
                                        const real *PIHYST_RESTRICT yt,
                          real *PIHYST_RESTRICT u_out)
{
    real s[4][L];
    size_t k, l, q;
    memset(s, 0, sizeof s);
    for (k = 0; k < n_ops; k += 4)
        for (q = 0; q < 4; ++q) {
            real *o = ops + OP_VECTORS * (k + q) * L;
            for (l = 0; l < L; ++l) {
                real z = o[(OP_Z0 + cur) * L + l];
                const real hi = yt[l] + o[OP_R * L + l], lo = yt[l] - o[OP_R * L + l];
                z = z < hi ? z : hi;
                z = z > lo ? z : lo;
                o[(OP_Z1 - cur) * L + l] = z;
                s[q][l] += o[OP_W * L + l] * z;
            }
        }
    for (l = 0; l < L; ++l) u_out[l] = (s[0][l] + s[1][l]) + (s[2][l] + s[3][l]);
}
#endif

/* the exact path for channel i (lane l of grp): its compensator steps y_d from its
 * state; for a fast lane that state is first set from z of buffer cur (T^-1), and the
 * new state goes to buffer 1 - cur (T) */
static pihyst_flags exact_step(pihyst_compbank *b, real *grp, size_t i, size_t l, int cur,
                               real yd, real *u)
{
    pihyst_compensator *c = b->comps[i];
    const real mode = grp[H_MODE * L + l];
    pihyst_flags fl;
    if (mode == MODE_FAST) {
        from_inverse_state(grp, l, cur, c->model);
        (void)pihyst_compensator_reset(c, c->model->state, grp[H_U_LAST * L + l]);
    }
    *u = pihyst_compensator_step(c, yd, &fl);
    if (mode == MODE_FAST) {
        to_inverse_state(grp, l, 1 - cur, c->model);
        grp[H_U_LAST * L + l] = c->u_last;
        grp[H_Y_LAST * L + l] = c->y_last;
    } else if (mode == MODE_PENDING && lipschitz(c)) {
        load_fast(b, grp, l, 1 - cur, c);
        ++b->n_fast;
    }
    return fl;
}

/* The fast lanes of a group for one tick, without a branch: y~ per lane (the last output
 * for a hold), (I1)-(I2), then per lane the voltage and output (held, or the inverse's u
 * and y_d) and whether the lane is done: a fast lane that holds or whose u is inside its
 * limits and slew limit; its u_last and y_last are updated. exact[l] = 1 marks the lanes
 * left for the exact path (exact-mode and padding lanes, and fast lanes out of bounds). */
PIHYST_HOT
static void group_tick(size_t n_ops, real *PIHYST_RESTRICT grp, int cur, const real *PIHYST_RESTRICT yd,
                       real *PIHYST_RESTRICT uo, real *PIHYST_RESTRICT yo, real *PIHYST_RESTRICT exact)
{
    real yt[L], ug[L];
    size_t l;
    for (l = 0; l < L; ++l) {
        const real yp = grp[H_Y_LAST * L + l];
        const int hold = !(R_FABS(yd[l] - yp) > grp[H_TOL * L + l]);
        yt[l] = (hold ? yp : yd[l]) - grp[H_OFFSET * L + l];
    }
    inverse_lanes(n_ops, grp + PIHYST_SOA_HEADER * L, cur, yt, ug);
    for (l = 0; l < L; ++l) {
        const real up = grp[H_U_LAST * L + l], yp = grp[H_Y_LAST * L + l], ul = ug[l];
        const int hold = !(R_FABS(yd[l] - yp) > grp[H_TOL * L + l]);
        /* & and |, not && and ||: no branch, so that the loop vectorizes */
        const int inside = (ul >= grp[H_U_MIN * L + l]) & (ul <= grp[H_U_MAX * L + l]) &
                           (R_FABS(ul - up) <= grp[H_MAX_STEP * L + l]);
        const int done = (grp[H_MODE * L + l] == MODE_FAST) & (hold | inside);
        const real un = hold ? up : ul, yn = hold ? yp : yd[l];
        uo[l] = un;
        yo[l] = yn;
        grp[H_U_LAST * L + l] = done ? un : up;
        grp[H_Y_LAST * L + l] = done ? yn : yp;
        exact[l] = done ? RC(0.0) : RC(1.0);
    }
}

size_t pihyst_compbank_compensate(pihyst_compbank *b, const real *y_desired, real *u,
                                  real *y, pihyst_flags *flags)
{
    const size_t n = b->n, n_groups = (n + L - 1) / L;
    const int cur = (int)b->parity;
    size_t g, l, count = 0;
    for (g = 0; g < n_groups; ++g) {
        real *grp = group_at(b, g);
        real yd_pad[L], uo[L], yo[L], exact[L];
        const size_t i0 = g * L, lanes = n - i0 < L ? n - i0 : L;
        const real *yd = y_desired + i0;
        if (lanes < L) { /* the last group: padding lanes desire 0 (they hold) */
            for (l = 0; l < L; ++l) yd_pad[l] = l < lanes ? yd[l] : RC(0.0);
            yd = yd_pad;
        }
        group_tick(b->n_ops, grp, cur, yd, uo, yo, exact);
        for (l = 0; l < lanes; ++l) {
            const size_t i = i0 + l;
            pihyst_flags fl = isnan(yd[l]) ? PIHYST_COMP_NAN : 0; /* a done NaN lane held */
            real ui = uo[l], yi = yo[l];
            if (exact[l] != RC(0.0)) {
                fl = exact_step(b, grp, i, l, cur, yd[l], &ui);
                yi = b->comps[i]->y_last;
            }
            u[i] = ui;
            if (y) y[i] = yi;
            if (flags) flags[i] = fl;
            count += fl != 0;
        }
    }
    b->parity = 1u - b->parity;
    return count;
}

void pihyst_compbank_sync(pihyst_compbank *b)
{
    size_t i;
    for (i = 0; i < b->n; ++i) {
        real *grp = group_at(b, i / L);
        const size_t l = i % L;
        pihyst_compensator *c = b->comps[i];
        if (grp[H_MODE * L + l] != MODE_FAST) continue;
        from_inverse_state(grp, l, (int)b->parity, c->model);
        (void)pihyst_compensator_reset(c, c->model->state, grp[H_U_LAST * L + l]);
    }
}
