/* pihyst_inverse.c - exact inverse of a PI-type model with non-negative weights, as a
 * streaming compensator with voltage limits and a slew limit. See the "Inverse /
 * compensator" section of pihyst.h for the equations (3), (3a), (3b) and ownership.
 *
 * One sample, from the last voltage u_p with output y_p = y(u_p) and desired y_d:
 *
 *   1. |y_d - y_p| <= tol (or y_d NaN): hold u_p.
 *   2. Otherwise walk away from u_p in the direction of y_d (up if y_d > y_p), inside
 *      the window [max(u_min, u_p - max_step), min(u_max, u_p + max_step)]. In terms of
 *      the distance d >= 0 from u_p, z(d) = |y(u_p +- d) - y_p| is piecewise linear with
 *      non-negative slope; its slope changes at events (d_e, ds_e):
 *        - operator k joins when its envelope reaches f_k (the crossing), adding
 *          w_k times the envelope's slope there; an operator already on its envelope
 *          at u_p joins at d = 0;
 *        - each envelope kink beyond the crossing changes the slope by
 *          w_k (slope after - slope before).
 *   3. Take the events in order of distance, accumulating z and the slope s, and in
 *      the first segment [d_a, d_e] with z(d_e) >= target solve
 *          z(d_a) + s (d - d_a) = target  ->  d = d_a + (target - z(d_a)) / s,
 *      s > 0 there because z rises across the segment (the division is done as a
 *      multiplication by 1/s, which does not wait for the target: rounding only).
 *      That d is the smallest solution: the voltage nearest u_p (flat stretches before
 *      it are passed over, never entered). If no segment reaches the target, the
 *      window's end is taken and flagged (limit, or slew limit if that end is the slew
 *      bound), unless the model's output there meets y_d to rounding after all.
 *   4. Apply the voltage to the model, which gives the new state and y_last.
 *
 * The events of a direction are kept for the next sample while the direction stays the
 * same: an operator not yet on its envelope keeps its f_k (so its crossing stays where
 * it was), one on its envelope stays on it, and the kinks are fixed. The next sample in
 * the same direction continues from the first event not yet passed, with the slope
 * reached there; a reversal (or a reset) starts again from u_p. A tracking step thus
 * costs O(1 + events passed) plus the model step.
 *
 * Events per family, going up (R_k, crossing c_k = least u >= u_p with R_k(u) >= f_k)
 * and going down (F_k, crossing c_k = greatest u <= u_p with F_k(u) <= f_k):
 *   classical:  up   c_k = f_k + r_k, slope 1;   down  c_k = f_k - r_k, slope 1.
 *               For a state 1-Lipschitz in r (reachable states are, see walk_classical)
 *               the crossings come in operator order, so a reversal needs no list: the
 *               walk reads them from the state as it goes, O(1 + events passed).
 *   multislope: R_k(u) = max(a u + c1_k, b u + c2_k): c_k = min((f_k - c1_k)/a,
 *               (f_k - c2_k)/b); kink at (c1_k - c2_k)/(b - a), slope a -> b.
 *               F_k(u) = min(b u, a u + c3_k): c_k = max(f_k/b, (f_k - c3_k)/a);
 *               kink at c3_k/(b - a), slope (going down) a -> b.
 *               Two lists in operator order, crossings and kinks (collect_multislope),
 *               built by vectorized loops without a comparison that picks anything,
 *               and checked to be sorted (they are for reachable states of the paper's
 *               shapes); the walk merges them as it goes. O(K) per reversal.
 *   pwl:        the crossing by binary search on the polyline's values, then every
 *               interior breakpoint beyond it with its slope change, as two events
 *               (+ new slope, - old slope) that the walk sums exactly.
 *   saturated-ramp pwl (every polyline flat, rising, flat: KP kernels): no lists; the
 *               operators sorted by ramp once, and a search and a model step that visit
 *               only those with a ramp where the voltage moves (section "saturated
 *               ramps" below).
 * Lists out of order (a state set by reset, an unusual multislope shape, pwl) are
 * sorted: insertion sort, O(K log K) at worst. For pwl the walk keeps its slope as a
 * compensated sum (hi + lo), so that a near-vertical segment joining and leaving
 * (+huge, then -huge) does not wipe out the small slopes around it; the other families
 * only add slope.
 */
#include "pihyst.h"
#include "pihyst_internal.h"

#include <stdint.h>
#include <string.h>

/* The O(K) loops of a reversal are multiversioned (PIHYST_HOT, pihyst_internal.h). */

/* The per-sample path (step -> solve -> walk) is compiled in one piece, the collection
 * of a reversal out of it. */
#if defined(__GNUC__)
#define PIHYST_INLINE __attribute__((always_inline)) inline
#define PIHYST_NOINLINE __attribute__((noinline))
#else
#define PIHYST_INLINE
#define PIHYST_NOINLINE
#endif

/* ------------------------------------------------------------------ event lists */

/* An event list is two arrays: distances d[i] and slope changes s[i]. */

static void swap_events(real *d, real *s, size_t i, size_t j)
{
    const real td = d[i], ts = s[i];
    d[i] = d[j];
    s[i] = s[j];
    d[j] = td;
    s[j] = ts;
}

static void heap_sift(real *d, real *s, size_t root, size_t n)
{
    for (;;) {
        size_t child = 2 * root + 1;
        if (child >= n) return;
        if (child + 1 < n && d[child + 1] > d[child]) ++child;
        if (!(d[child] > d[root])) return;
        swap_events(d, s, root, child);
        root = child;
    }
}

static void heap_sort(real *d, real *s, size_t n)
{
    size_t i;
    if (n < 2) return;
    for (i = n / 2; i-- > 0;) heap_sift(d, s, i, n);
    for (i = n - 1; i > 0; --i) {
        swap_events(d, s, 0, i);
        heap_sift(d, s, 0, i);
    }
}

/* Sort by distance: insertion sort, O(n) on nearly sorted lists; if it has moved more
 * than 4n + 8 elements the list is far from sorted and heapsort finishes the job, so
 * the worst case stays O(n log n). */
static void sort_events(real *d, real *s, size_t n)
{
    size_t i, moves = 0;
    const size_t budget = 4 * n + 8;
    for (i = 1; i < n; ++i) {
        const real di = d[i], si = s[i];
        size_t j = i;
        while (j > 0 && d[j - 1] > di) {
            d[j] = d[j - 1];
            s[j] = s[j - 1];
            --j;
            ++moves;
        }
        d[j] = di;
        s[j] = si;
        if (moves > budget) {
            heap_sort(d, s, n);
            return;
        }
    }
}

/* 1 if the n distances d are not in non-decreasing order */
static int out_of_order(const real *d, size_t n)
{
    size_t i;
    int bad = 0;
    for (i = 1; i < n; ++i) bad |= d[i] < d[i - 1];
    return bad;
}

/* ------------------------------------------------------------------ walks */

/* End of a walk past its last event: z(d) = z + s (d - d0) up to d = span. Returns 1 and
 * the d with z(d) = target if z(span) >= target, else 0 and d = span. */
static PIHYST_INLINE int walk_last_segment(real z, real s, real d0, real target,
                                           real span, real *d_out)
{
    if (z + s * (span - d0) >= target) {
        const real d = d0 + (target - z) / s;
        *d_out = d < span ? d : span;
        return 1;
    }
    *d_out = span;
    return 0;
}

/* Walk the two sorted event lists a (crossings) and b (kinks), each ended by a +inf
 * sentinel, in merged order (a first on equal distances) from a[next[0]], b[next[1]].
 * Distances are from the base voltage; q_p is u_p's distance from it, so an event lies
 * d_e = ev - q_p beyond u_p. slope is the slope at u_p and z(0) = 0; the walk goes up to
 * distance span. Returns 1 and the smallest d with z(d) = target (0 < target) if
 * z(span) >= target, else 0 with d = span. Events passed are consumed: next and slope
 * then describe the voltage u_p + d. With `compensated` the slope is the sum hi + lo
 * (Knuth's TwoSum), for pwl slope changes that cancel; else slope[0] alone. */
static PIHYST_INLINE int walk(const real *ad, const real *as, const real *bd,
                              const real *bs, size_t next[2], real slope[2], real q_p,
                              real target, real span, int compensated, real *d_out)
{
    real z = RC(0.0), d0 = RC(0.0), hi = slope[0], lo = slope[1], s = hi + lo;
    size_t i = next[0], j = next[1];
    int hit = 0;
    for (;;) {
        real de, ds, ze;
        const int from_b = bd[j] < ad[i];
        if (from_b) {
            de = bd[j] - q_p;
            ds = bs[j];
        } else {
            de = ad[i] - q_p;
            ds = as[i];
        }
        if (de < d0) de = d0; /* passed already, to rounding */
        if (!(de < span)) break;
        ze = z + s * (de - d0); /* z(d_e) = z(d_a) + s (d_e - d_a) */
        if (ze >= target) {
            const real d = d0 + (target - z) * (RC(1.0) / s); /* s > 0: z rose below target */
            *d_out = d < de ? d : de;
            hit = 1;
            break;
        }
        z = ze;
        d0 = de;
        if (compensated) { /* hi + lo += ds */
            const real t = hi + ds, bp = t - hi;
            lo += (hi - (t - bp)) + (ds - bp);
            hi = t;
            s = hi + lo;
        } else {
            hi += ds;
            s = hi;
        }
        if (from_b) ++j; else ++i;
    }
    if (!hit) hit = walk_last_segment(z, s, d0, target, span, d_out);
    next[0] = i;
    next[1] = j;
    slope[0] = hi;
    slope[1] = lo;
    return hit;
}

/* Classical models with an ordered state walk their crossings straight from the state,
 * in operator order, without lists: operator k's crossing lies at c_k = f_k + r_k going
 * up, f_k - r_k going down, at the distance max(+-(c_k - base), 0) from the base. The
 * order holds for every state 1-Lipschitz in r,
 *     |f_k - f_j| <= r_k - r_j     (j < k):
 * then c_k - c_j = (f_k - f_j) +- (r_k - r_j) has the sign of +-1 or is 0. A model step
 * keeps the property: f_k <- max(u - r_k, min(u + r_k, f_k)) is a max and a min of
 * 1-Lipschitz functions of r. In floating point each f_k is the initial value or
 * u - r_k, u + r_k rounded once, so the state stays within an ulp of an exactly
 * Lipschitz one and the crossings in order to a few ulps; a crossing met that much late
 * shifts z by its slope times that much (rounding, below tol). The compensator checks
 * the property whenever its state is set (init, reset) and at the reversals while it
 * fails; until then it collects and sorts, as for the other families. Same contract as
 * walk (slope[0] only); *ahead is the distance of crossing next[0] from the base, kept
 * from the sample before (that operator has not moved since), so that a tracking step
 * does not wait for the state the model has just written. */
static PIHYST_INLINE int walk_classical(const pihyst_model *m, int up, real base,
                                        size_t next[2], real *ahead, real slope[2],
                                        real q_p, real target, real span, real *d_out)
{
    const size_t K = m->n_ops;
    const real *PIHYST_RESTRICT w = m->weights, *PIHYST_RESTRICT r = m->coef + K, *PIHYST_RESTRICT f = m->state;
    const real sign = up ? RC(1.0) : -RC(1.0), v = sign * base;
    real z = RC(0.0), d0 = RC(0.0), s = slope[0], e = *ahead;
    size_t k = next[0];
    int hit = 0;
    while (k < K) {
        real de = e - q_p, ze;
        if (de < d0) de = d0; /* passed already, to rounding */
        if (!(de < span)) break;
        ze = z + s * (de - d0);
        if (ze >= target) {
            const real d = d0 + (target - z) * (RC(1.0) / s); /* s > 0: z rose below target */
            *d_out = d < de ? d : de;
            hit = 1;
            break;
        }
        z = ze;
        d0 = de;
        s += w[k];
        if (++k < K) {
            /* up: (f + r) - base;  down: base - (f - r) = (r - f) + base */
            const real x = sign * f[k] + r[k] - v;
            e = x > RC(0.0) ? x : RC(0.0);
        } else {
            e = R_INF;
        }
    }
    if (!hit) hit = walk_last_segment(z, s, d0, target, span, d_out);
    next[0] = k;
    *ahead = e;
    slope[0] = s;
    return hit;
}

/* 1 if the classical state is 1-Lipschitz in r (see walk_classical) to a few ulps of
 * the largest |voltage| + r: |f_k - f_{k-1}| <= r_k - r_{k-1} + tol */
static int lipschitz(const pihyst_compensator *c)
{
    const pihyst_model *m = &c->work_model;
    const size_t K = m->n_ops;
    const real *r = m->coef + K, *f = m->state;
    const real u_big = R_FABS(c->u_min) > R_FABS(c->u_max) ? R_FABS(c->u_min) : R_FABS(c->u_max);
    const real tol = RC(8.0) * R_EPS * (u_big + r[K - 1]);
    size_t k;
    int bad = 0;
    for (k = 1; k < K; ++k) bad |= R_FABS(f[k] - f[k - 1]) > (r[k] - r[k - 1]) + tol;
    return !bad;
}

/* ------------------------------------------------------------------ collection */

/* Scratch: kinks (2K, multislope) | crossing list a: distances, slope changes
 * (events_cap + 1 each, the last a +inf sentinel) | kink list b likewise (K + 1 each). */
typedef struct {
    real *ad, *as; /* crossings (and pwl breakpoints) */
    size_t na;
    real *bd, *bs; /* multislope kinks */
    size_t nb;
    real s0;       /* slope at distance 0+ (pwl; the others list it as events at 0) */
} events;

static void lists(const pihyst_compensator *c, events *e)
{
    const size_t K = c->work_model.n_ops, cap = c->events_cap;
    e->ad = c->scratch + 2 * K;
    e->as = e->ad + (cap + 1);
    e->bd = e->as + (cap + 1);
    e->bs = e->bd + (K + 1);
}

static void push(events *e, real d, real ds)
{
    e->ad[e->na] = d;
    e->as[e->na] = ds;
    ++e->na;
}

/* classical, (3a): c_k = f_k + r_k;  (3b): c_k = f_k - r_k; slope w_k from c_k on.
 * Every crossing goes into a in operator order, as its distance from u_p clamped at 0
 * (an operator on its envelope at u_p joins at distance 0). Returns 1 if out of order. */
PIHYST_HOT
static int collect_classical(const pihyst_model *m, int up, real u_p, events *e)
{
    const size_t K = m->n_ops;
    const real *PIHYST_RESTRICT w = m->weights, *PIHYST_RESTRICT r = m->coef + K, *PIHYST_RESTRICT f = m->state;
    real *PIHYST_RESTRICT ad = e->ad, *PIHYST_RESTRICT as = e->as;
    size_t k;
    if (up) {
        for (k = 0; k < K; ++k) {
            const real d = (f[k] + r[k]) - u_p;
            ad[k] = d > RC(0.0) ? d : RC(0.0);
        }
    } else {
        for (k = 0; k < K; ++k) {
            const real d = u_p - (f[k] - r[k]);
            ad[k] = d > RC(0.0) ? d : RC(0.0);
        }
    }
    for (k = 0; k < K; ++k) as[k] = w[k];
    e->na = K;
    e->nb = 0;
    e->s0 = RC(0.0);
    return out_of_order(ad, K);
}

/* multislope, see the header comment of this file for c_k and the kinks. Going up from
 * its crossing c_k (clamped to u_p) operator k contributes
 *     w_k (R_k(u) - f_k) = w_k a (u - c_k) + w_k (b - a) (u - max(kink_k, c_k))+,
 * the kink counting from the crossing on if it lies before it; going down likewise,
 * with min. So the crossing goes into a with slope change w_k a and max(kink_k, c_k)
 * into b with w_k (b - a), both in operator order: b is sorted whenever a is (the kinks
 * are, checked at init, and the max of two non-decreasing sequences is non-decreasing).
 * No comparison picks anything, so the loops vectorize and noise data mispredicts
 * nothing. Returns 1 if the crossings are out of order. */
PIHYST_HOT
static int collect_multislope(const pihyst_model *m, const real *kinks, int up,
                              real u_p, events *e)
{
    const size_t K = m->n_ops;
    const real a_ = m->shape.a, ba = m->shape.b - m->shape.a;
    const real ia = RC(1.0) / a_, ib = RC(1.0) / m->shape.b;
    const real *PIHYST_RESTRICT w = m->weights, *PIHYST_RESTRICT f = m->state, *PIHYST_RESTRICT c = m->coef;
    real *PIHYST_RESTRICT ad = e->ad, *PIHYST_RESTRICT as = e->as, *PIHYST_RESTRICT bd = e->bd,
                     *PIHYST_RESTRICT bs = e->bs;
    size_t k;
    if (up) {
        const real *PIHYST_RESTRICT kr = kinks;
        for (k = 0; k < K; ++k) {
            /* R(u) = max(a u + c1, b u + c2) >= f  <=>  u >= min((f - c1)/a, (f - c2)/b) */
            const real x1 = (f[k] - c[k]) * ia, x2 = (f[k] - c[K + k]) * ib;
            const real x = x1 < x2 ? x1 : x2, xt = x > u_p ? x : u_p;
            ad[k] = xt - u_p;
            bd[k] = (kr[k] > xt ? kr[k] : xt) - u_p;
        }
    } else {
        const real *PIHYST_RESTRICT kf = kinks + K;
        for (k = 0; k < K; ++k) {
            /* F(u) = min(b u, a u + c3) <= f  <=>  u <= max(f/b, (f - c3)/a) */
            const real x1 = f[k] * ib, x2 = (f[k] - c[2 * K + k]) * ia;
            const real x = x1 > x2 ? x1 : x2, xt = x < u_p ? x : u_p;
            ad[k] = u_p - xt;
            bd[k] = u_p - (kf[k] < xt ? kf[k] : xt);
        }
    }
    for (k = 0; k < K; ++k) {
        as[k] = w[k] * a_;
        bs[k] = w[k] * ba;
    }
    e->na = K;
    e->nb = K;
    e->s0 = RC(0.0);
    return out_of_order(ad, K);
}

/* first index i in [0, n] with v[i] >= x (v non-decreasing) */
static size_t lower_bound(const real *v, size_t n, real x)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (v[mid] < x) lo = mid + 1; else hi = mid;
    }
    return lo;
}

/* first index i in [0, n] with v[i] > x (v non-decreasing) */
static size_t upper_bound(const real *v, size_t n, real x)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (v[mid] <= x) lo = mid + 1; else hi = mid;
    }
    return lo;
}

/* slope of segment i, between breakpoints i and i + 1 */
static real seg_slope(const real *x, const real *y, size_t i)
{
    return (y[i + 1] - y[i]) / (x[i + 1] - x[i]);
}

/* pwl going up, (3a), operator with rising polyline (x, y, n >= 2):
 * crossing = least u with R(u) >= f; segment `seg` holds it (extensions included). */
static void collect_pwl_up(const real *x, const real *y, size_t n, real w, real f,
                           real u_p, real span, events *e)
{
    size_t i = lower_bound(y, n, f), seg, q;
    real cross;
    if (i == 0) { /* f <= y[0]: in the left extension, or R >= f everywhere */
        const real s = seg_slope(x, y, 0);
        seg = 0;
        cross = s > RC(0.0) ? x[0] - (y[0] - f) / s : -R_INF;
    } else if (i == n) { /* f > y[n-1]: in the right extension, or never */
        const real s = seg_slope(x, y, n - 2);
        seg = n - 2;
        cross = s > RC(0.0) ? x[n - 1] + (f - y[n - 1]) / s : R_INF;
    } else { /* y[i-1] < f <= y[i] */
        seg = i - 1;
        cross = x[i - 1] + (f - y[i - 1]) * (x[i] - x[i - 1]) / (y[i] - y[i - 1]);
        if (cross > x[i]) cross = x[i];
    }
    if (cross <= u_p) { /* on the envelope at u_p: segment to the right of u_p */
        const size_t j = upper_bound(x, n, u_p);
        seg = j == 0 ? 0 : (j - 1 < n - 2 ? j - 1 : n - 2);
        e->s0 += w * seg_slope(x, y, seg);
    } else {
        const real d = cross - u_p;
        if (!(d < span)) return;
        push(e, d, w * seg_slope(x, y, seg));
    }
    for (q = seg + 1; q + 1 < n; ++q) { /* interior breakpoints beyond */
        const real d = x[q] - u_p;
        if (!(d < span)) break;
        /* slope change as two events, + new and - old, summed exactly by the walk */
        push(e, d, w * seg_slope(x, y, q));
        push(e, d, -w * seg_slope(x, y, q - 1));
    }
}

/* pwl going down, (3b), operator with falling polyline (x, y, n >= 2):
 * crossing = greatest u with F(u) <= f. */
static void collect_pwl_down(const real *x, const real *y, size_t n, real w, real f,
                             real u_p, real span, events *e)
{
    size_t i = upper_bound(y, n, f), seg, q;
    real cross;
    if (i == 0) { /* f < y[0]: in the left extension, or never */
        const real s = seg_slope(x, y, 0);
        seg = 0;
        cross = s > RC(0.0) ? x[0] - (y[0] - f) / s : -R_INF;
    } else if (i == n) { /* f >= y[n-1]: in the right extension, or F <= f everywhere */
        const real s = seg_slope(x, y, n - 2);
        seg = n - 2;
        cross = s > RC(0.0) ? x[n - 1] + (f - y[n - 1]) / s : R_INF;
    } else { /* y[i-1] <= f < y[i] */
        seg = i - 1;
        cross = x[i - 1] + (f - y[i - 1]) * (x[i] - x[i - 1]) / (y[i] - y[i - 1]);
        if (cross < x[i - 1]) cross = x[i - 1];
    }
    if (cross >= u_p) { /* on the envelope at u_p: segment to the left of u_p */
        const size_t j = lower_bound(x, n, u_p);
        seg = j == 0 ? 0 : (j - 1 < n - 2 ? j - 1 : n - 2);
        e->s0 += w * seg_slope(x, y, seg);
    } else {
        const real d = u_p - cross;
        if (!(d < span)) return;
        push(e, d, w * seg_slope(x, y, seg));
    }
    for (q = seg; q >= 1; --q) { /* interior breakpoints below */
        const real d = u_p - x[q];
        if (!(d < span)) break;
        push(e, d, w * seg_slope(x, y, q - 1));
        push(e, d, -w * seg_slope(x, y, q));
    }
}

static void collect_pwl(const pihyst_model *m, int up, real u_p, real span, events *e)
{
    const pihyst_pwl *p = &m->pwl;
    size_t k;
    e->na = 0;
    e->nb = 0;
    e->s0 = RC(0.0);
    for (k = 0; k < m->n_ops; ++k) {
        const real w = m->weights[k];
        if (w == RC(0.0)) continue;
        if (up) {
            const size_t s0 = p->rise_start[k], n = p->rise_start[k + 1] - s0;
            if (n >= 2) /* a single point is a constant: never a slope */
                collect_pwl_up(p->rise_x + s0, p->rise_y + s0, n, w, m->state[k], u_p, span, e);
        } else {
            const size_t s0 = p->fall_start[k], n = p->fall_start[k + 1] - s0;
            if (n >= 2)
                collect_pwl_down(p->fall_x + s0, p->fall_y + s0, n, w, m->state[k], u_p, span,
                                 e);
        }
    }
}

/* ------------------------------------------------------------------ saturated ramps */

/* A pwl model whose polylines are all saturated ramps (flat at y1 up to x1, rising to y2
 * at x2, flat beyond: the KP kernels, detected by pihyst_model_init, coef[0] = 1) gets
 * its own search and its own model step, both of which visit only the operators whose
 * ramps lie where the voltage moves, not all K.
 *
 * Sorted ramps. At init the operators are listed twice (ramps_init): by the start x1 of
 * their rising ramp, and by the start -x2 of their falling ramp in the negated voltage
 * p = -u; with each position the greatest ramp end (x2, resp. -x1) up to it, a
 * non-decreasing sequence. The ramps that reach into an interval (a, b) (start < b and
 * end > a) then lie between two binary searches, exactly and for any ramps (unequal
 * widths, coincident or scattered starts): the positions from the first whose greatest
 * end exceeds a to the last whose start is below b. On a grid of centres (what
 * pihyst.identify builds) that is the operators of the one or two centres the interval
 * touches; a ramp much wider than the others lengthens every range after it. The
 * searches start where the list's last search ended (bound_from): tracking moves little.
 *
 * Model step (ramps_step_sparse). f_k <- max(R_k(u), min(F_k(u), f_k)) changes nothing
 * when R_k and F_k both have the same value at u as at the last voltage u_p (both on the
 * same flat part: the ramp formula returns y0 or y2 there, the same bits): with a state
 * the last step left, f = max(R(u_p), min(F(u_p), f')), the update is idempotent. For an
 * operator whose ramps are monotone and ordered (R <= F at every float; ramps_init) it
 * also changes nothing when only its ramp of the other direction moves. So only the
 * operators whose ramp of the direction reaches into (min(u, u_p), max(u, u_p)) are
 * updated, with the few others, by the model step's own expression: the state stays the
 * model step's bit for bit. The output is kept as a running sum: y += w_k (f_new - f_old) for each change,
 * accumulated exactly (TwoSum: hi + lo is the exact sum of the rounded changes), so it
 * drifts from the model step's sum only by the rounding of each change, at most eps
 * times |change|; once the changes since the last exact sum add up to the output scale
 * (the compensator's, |offset| + sum_k w_k max |envelopes|), the sum is taken again over
 * all operators in the model's order (pihyst_internal_weighted_sum, the model step's bits).
 * Between those sums |y_last - model step's y| <= about 2 (K + 2) eps times the scale,
 * below the compensator's equality band tol = 4 (K + 2) eps times the scale (the
 * model step's own sum is within (K + 2) eps of the exact one, and so was the sum the
 * running one started from). When more operators would be visited than K / 2, the full
 * model step runs instead (and gives the exact sum).
 *
 * Search. From u_p with state f, going up, operator k follows R_k from its crossing
 * c_k = x1 + (f_k - y1) dx/dy (R_k(c_k) = f_k) to x2 with the slope s_k = w_k dy/dx, and
 * stays put outside [c_k, x2]. So
 *
 *     y(u) - y_p = z(u) = sum_k s_k (clamp(u, lo_k, hi_k) - lo_k)                   (R1)
 *
 * with lo_k = max(c_k, x1, u_p), hi_k = x2, over the operators that move (f_k < y2,
 * c_k < x2, s_k > 0). Going down, F_k with its crossing and x1 give the same form in
 * p = -u (negation is exact), so both directions solve z(p) = target for p >= q
 * (q = +-u_p), z continuous, non-decreasing, linear between the breakpoints
 * {lo_k, hi_k}. lo_k and hi_k are computed when an operator is visited, from the state
 * of the moment: an operator not reached since the last reversal keeps its f_k (so its
 * crossing stays where it was), one reached lies on its ramp at u_p (its crossing at
 * u_p, to rounding). Every interval starts at or after its ramp's start and ends at its
 * ramp's end, so the sorted list of the direction gives the operators that can add to z
 * in any bracket. The search (solve_ramps):
 *   - tracking: the last answer's segment is kept (slope and right end); an answer
 *     inside it needs no visit at all; else the cell of the last search is probed
 *     again from its kept operators (their intervals do not change while the direction
 *     holds);
 *   - else the sweep (ramps_sweep): from L = q (or the kept cell's end), the operators
 *     of the list read once each in the order of their ramps' starts, z evaluated at
 *     each distinct start beyond L from the operators still open there; the first start
 *     H whose z(H) reaches the target closes the bracket [L, H] (none: the window's end
 *     is taken and flagged, as on the lists), whose operators are kept as the cell;
 *   - in it: probe at a point m inside (the secant point, or the midpoint when the
 *     bracket shrank by less than half); the segment of m then either holds the answer,
 *     solved exactly, or moves L up to its right end or H down to its left end. These
 *     probes (probe_active) visit only the operators with a breakpoint inside the
 *     bracket of the moment, kept in a compact set that shrinks with it.
 * The answer is the least p with z(p) = target, as on the lists: a flat stretch with
 * z = target is passed over to its start (H moves down across it). Cost: the operators
 * whose ramps lie between u_p and the answer (each read once and summed about once) plus
 * a binary search; no O(K) pass at a reversal, no sort (measured in
 * benchmarks/bench_kp.py and make -C csrc bench-m4f). */

enum { RAMP_X1, RAMP_X2, RAMP_Y0, RAMP_Y1, RAMP_Y2, RAMP_N };
/* a sorted list: per position the ramp's start (in p), the greatest end (in p) up to
 * that position, and the operator's index (as a real: exact up to 2^24 operators) */
enum { LIST_KEY, LIST_END_MAX, LIST_INDEX, LIST_N };
/* per position of a sorted list, what the sweep reads (one record of REC_N values, in
 * list order: one pointer walks it): the ramp's start and end in p, the state's limit
 * beyond which the operator cannot move (y2 going up, y1 going down; -+inf for a slope
 * s = 0), y1, dx/dy, the slope s = w dy/dx, the operator's index (a uint32_t in the
 * value's first bytes: no conversion) and the first position whose start is greater
 * (as a real, exact up to 2^24); the state at rest (y1 going up, y2 going down: not yet
 * on the ramp; NaN if the ramp ends beyond the next greater start) and the operator's
 * term of z then, read from P = its start to the next start (see ramps_sweep); then for
 * the model step, the ramp's x1, x2, y0, y2 */
enum {
    REC_KEY, REC_END, REC_LIMIT, REC_Y1, REC_INV, REC_SLOPE, REC_INDEX, REC_NEXT,
    REC_REST, REC_FULL, REC_X1, REC_X2, REC_Y0, REC_Y2, REC_N
};

static size_t rec_index(const real *rec)
{
    uint32_t k;
    memcpy(&k, rec + REC_INDEX, sizeof k);
    return k;
}
/* the running sum of the output: hi + lo, the changes summed since the last exact sum
 * (|change| each) and the scale at which it is taken again; the number of operators not
 * known to be monotone (ramps_init); then, per list, where its
 * last two binary searches ended (the next one starts there: tracking moves little) */
enum { SUM_HI, SUM_LO, SUM_MOVED, SUM_BUDGET, SUM_ODD, SUM_HINTS, SUM_N = SUM_HINTS + 4 };
/* up to this many operators not known to be monotone are updated at every step of the
 * ramp path's own model step; more, and those with a ramp between the two voltages */
#define RAMP_ODD_FEW 8
/* the ramp path keeps operator indices in reals */
#define RAMP_MAX_K ((size_t)1 << 24)

/* Scratch of a ramp model, in blocks of K values: RAMP_N arrays of constants for the
 * rising ramps, the same for the falling ones (by operator), the two sorted lists (LIST_N
 * arrays each), the active set of a search (3 K), the bracket it was taken from (3 K, kept
 * for the next sample; the sweep's two buffers are these two), the operators not known
 * to be monotone (up to K indices), the sweep's records of the two lists (REC_N K each),
 * then the running sum (SUM_N values) */
enum {
    OFF_LISTS = 2 * RAMP_N,
    OFF_ACTIVE = OFF_LISTS + 2 * LIST_N,
    OFF_CELL = OFF_ACTIVE + 3,
    OFF_ODD = OFF_CELL + 3,
    OFF_REC = OFF_ODD + 1,
    OFF_SUM = OFF_REC + 2 * REC_N
};
#define RAMP_SCRATCH(K) ((size_t)OFF_SUM * (K) + SUM_N)

static real *ramp_array(const pihyst_compensator *c, int falling, int which)
{
    return c->scratch + (size_t)(falling * RAMP_N + which) * c->work_model.n_ops;
}

static real *list_array(const pihyst_compensator *c, int down, int which)
{
    return c->scratch + (size_t)(OFF_LISTS + down * LIST_N + which) * c->work_model.n_ops;
}

static real *ramp_block(const pihyst_compensator *c, int offset)
{
    return c->scratch + (size_t)offset * c->work_model.n_ops;
}

static real *ramp_sum(const pihyst_compensator *c) { return ramp_block(c, OFF_SUM); }

/* a model the ramp path takes: every polyline a saturated ramp (pihyst_model_init) */
static int ramp_model(const pihyst_model *m)
{
    return m->family == PIHYST_PWL && m->coef[0] == RC(1.0) && m->n_ops <= RAMP_MAX_K;
}

#ifdef PIHYST_BUILD_F32
#define R_MAX FLT_MAX
#else
#define R_MAX DBL_MAX
#endif

/* 1 if the ramp's value (PIHYST_RAMP_VALUE) never decreases with u in floating point:
 * each operation of y1 + (y2 - y1)(u - x1)/(x2 - x1) is monotone in u, the value at x1
 * is y1 (= y0), so only the step to y2 at x2 can go down, from the value just below x2 */
static int ramp_monotone(const pihyst_compensator *c, int side, size_t k)
{
    const real x1 = ramp_array(c, side, RAMP_X1)[k], x2 = ramp_array(c, side, RAMP_X2)[k];
    const real y0 = ramp_array(c, side, RAMP_Y0)[k], y1 = ramp_array(c, side, RAMP_Y1)[k];
    const real y2 = ramp_array(c, side, RAMP_Y2)[k], below = R_NEXTAFTER(x2, -R_INF);
    return PIHYST_RAMP_VALUE(x1, x2, y0, y1, y2, below) <= y2;
}

/* 1 if R_k(u) <= F_k(u) at every u in floating point, for monotone ramps: the two are
 * the same ramp, or R rises only after F has risen, from no higher and to no higher
 * (x1 of R >= x2 of F, y0 and y2 of R <= those of F) */
static int ramps_ordered(const pihyst_compensator *c, size_t k)
{
    int which, same = 1;
    for (which = RAMP_X1; which <= RAMP_Y2; ++which)
        same &= ramp_array(c, 0, which)[k] == ramp_array(c, 1, which)[k];
    return same || (ramp_array(c, 0, RAMP_X1)[k] >= ramp_array(c, 1, RAMP_X2)[k] &&
                    ramp_array(c, 0, RAMP_Y0)[k] <= ramp_array(c, 1, RAMP_Y0)[k] &&
                    ramp_array(c, 0, RAMP_Y2)[k] <= ramp_array(c, 1, RAMP_Y2)[k]);
}

/* constants of every ramp, from points 1 and 2 of its polyline: x1, x2, y0 (the value
 * below x1: y1 but for the sign of a zero), y1, y2; then the two sorted lists with their
 * records (dx/dy: 0 for a flat ramp, at most the largest finite value; the slope
 * w dy/dx), and the running sum's budget (the output scale) */
static void ramps_init(pihyst_compensator *c, real scale)
{
    const pihyst_model *m = &c->work_model;
    const size_t K = m->n_ops;
    size_t k;
    int side;
    for (side = 0; side < 2; ++side) {
        const real *x = side ? m->pwl.fall_x : m->pwl.rise_x;
        const real *y = side ? m->pwl.fall_y : m->pwl.rise_y;
        real *x1 = ramp_array(c, side, RAMP_X1), *x2 = ramp_array(c, side, RAMP_X2);
        real *y0 = ramp_array(c, side, RAMP_Y0), *y1 = ramp_array(c, side, RAMP_Y1);
        real *y2 = ramp_array(c, side, RAMP_Y2);
        real *key = list_array(c, side, LIST_KEY), *end_max = list_array(c, side, LIST_END_MAX);
        real *index = list_array(c, side, LIST_INDEX), run = -R_INF;
        for (k = 0; k < K; ++k) {
            x1[k] = x[4 * k + 1];
            x2[k] = x[4 * k + 2];
            y0[k] = y[4 * k];
            y1[k] = y[4 * k + 1];
            y2[k] = y[4 * k + 2];
            /* rising ramps start at x1; falling ones, in p = -u, at -x2 */
            key[k] = side ? -x2[k] : x1[k];
            index[k] = (real)k;
        }
        heap_sort(key, index, K);
        for (k = 0; k < K; ++k) {
            const size_t j = (size_t)index[k];
            const real end = side ? -x1[j] : x2[j];
            const real dx = x2[j] - x1[j], dy = y2[j] - y1[j], s = m->weights[j] * (dy / dx);
            real *rec = ramp_block(c, OFF_REC + side * REC_N) + REC_N * k, inv;
            inv = dy > RC(0.0) ? dx / dy : RC(0.0);
            if (!(inv <= R_MAX)) inv = R_MAX;
            run = end > run ? end : run;
            end_max[k] = run;
            rec[REC_KEY] = key[k];
            rec[REC_END] = end;
            rec[REC_LIMIT] = s > RC(0.0) ? (side ? y1[j] : y2[j]) : (side ? R_INF : -R_INF);
            rec[REC_Y1] = y1[j];
            rec[REC_INV] = inv;
            rec[REC_SLOPE] = s;
            rec[REC_X1] = x1[j];
            rec[REC_X2] = x2[j];
            rec[REC_Y0] = y0[j];
            rec[REC_Y2] = y2[j];
            {
                const uint32_t k32 = (uint32_t)j;
                memcpy(rec + REC_INDEX, &k32, sizeof k32);
            }
        }
        for (k = K; k-- > 0;) { /* the first position with a greater start */
            real *rec = ramp_block(c, OFF_REC + side * REC_N) + REC_N * k, l;
            const size_t next = k + 1 == K               ? K
                                : key[k + 1] > key[k] ? k + 1
                                                      : (size_t)rec[REC_N + REC_NEXT];
            rec[REC_NEXT] = (real)next;
            /* at rest, read at P = key: the sweep's expressions for lo and the term */
            rec[REC_REST] = side ? rec[REC_Y2] : rec[REC_Y1];
            l = side ? rec[REC_END] - (rec[REC_REST] - rec[REC_Y1]) * rec[REC_INV]
                     : rec[REC_KEY] + (rec[REC_REST] - rec[REC_Y1]) * rec[REC_INV];
            l = l > rec[REC_KEY] ? l : rec[REC_KEY];
            rec[REC_FULL] = l < rec[REC_END] ? rec[REC_SLOPE] * (rec[REC_END] - l) : RC(0.0);
            if (!(next < K && rec[REC_END] <= key[next])) rec[REC_REST] = (real)NAN;
        }
    }
    ramp_sum(c)[SUM_BUDGET] = scale;
    ramp_sum(c)[SUM_ODD] = RC(0.0);
    for (k = 0; k < 4; ++k) ramp_sum(c)[SUM_HINTS + k] = RC(0.0);
    for (k = 0; k < K; ++k) /* the operators not known to be monotone, listed */
        if (!(ramp_monotone(c, 0, k) && ramp_monotone(c, 1, k) && ramps_ordered(c, k)))
            ramp_block(c, OFF_ODD)[(size_t)ramp_sum(c)[SUM_ODD]++] = (real)k;
}

/* The first i in [0, n] with v[i] >= x (strict: v[i] > x), v non-decreasing, found from
 * the position *hint of the last search (galloping away from it, then bisecting):
 * O(log |answer - hint|) comparisons. The answer becomes the next hint. */
static size_t bound_from(const real *v, size_t n, real x, int strict, real *hint)
{
#define PIHYST_PAST(i) (strict ? v[i] > x : v[i] >= x)
    size_t g = (size_t)*hint, lo, hi, step = 1;
    if (g > n) g = n;
    if (g == n || PIHYST_PAST(g)) { /* the answer is g or below */
        hi = g;
        while (hi >= step && PIHYST_PAST(hi - step)) {
            hi -= step;
            step *= 2;
        }
        lo = hi >= step ? hi - step + 1 : 0;
    } else { /* above g */
        lo = g + 1;
        hi = n;
        while (lo + step - 1 < n && !PIHYST_PAST(lo + step - 1)) {
            lo += step;
            step *= 2;
        }
        if (lo + step - 1 < n) hi = lo + step - 1;
    }
    while (lo < hi) { /* v[hi] past x, or hi = n */
        const size_t mid = lo + (hi - lo) / 2;
        if (PIHYST_PAST(mid)) hi = mid; else lo = mid + 1;
    }
#undef PIHYST_PAST
    *hint = (real)lo;
    return lo;
}

/* positions [*i0, *i1) of list `down` whose ramps reach into (a, b) in its coordinate
 * (start < b, end > a: a ramp that ends at a or starts at b has the same value at a and
 * b, and adds nothing to z between them); the count */
static size_t ramps_meeting(const pihyst_compensator *c, int down, real a, real b,
                            size_t *i0, size_t *i1)
{
    const size_t K = c->work_model.n_ops;
    real *hints = ramp_sum(c) + SUM_HINTS + 2 * down;
    *i0 = bound_from(list_array(c, down, LIST_END_MAX), K, a, 1, hints);
    *i1 = bound_from(list_array(c, down, LIST_KEY), K, b, 0, hints + 1);
    if (*i1 < *i0) *i1 = *i0;
    return *i1 - *i0;
}

/* The model step's update at u of the operators at positions [i0, i1) of a list, the
 * changes added to hi + lo exactly (TwoSum) and their sizes to moved */
static PIHYST_INLINE void ramps_update_listed(pihyst_compensator *c, const real *index,
                                              size_t i0, size_t i1, real u, real *hi_,
                                              real *lo_, real *moved_)
{
    pihyst_model *m = &c->work_model;
    const real *PIHYST_RESTRICT rx1 = ramp_array(c, 0, RAMP_X1), *PIHYST_RESTRICT rx2 = rx1 + m->n_ops;
    const real *PIHYST_RESTRICT ry0 = ramp_array(c, 0, RAMP_Y0), *PIHYST_RESTRICT ry1 = ry0 + m->n_ops;
    const real *PIHYST_RESTRICT ry2 = ry1 + m->n_ops;
    const real *PIHYST_RESTRICT fx1 = ramp_array(c, 1, RAMP_X1), *PIHYST_RESTRICT fx2 = fx1 + m->n_ops;
    const real *PIHYST_RESTRICT fy0 = ramp_array(c, 1, RAMP_Y0), *PIHYST_RESTRICT fy1 = fy0 + m->n_ops;
    const real *PIHYST_RESTRICT fy2 = fy1 + m->n_ops;
    const real *PIHYST_RESTRICT w = m->weights;
    real *PIHYST_RESTRICT f = m->state;
    real hi = *hi_, lo = *lo_, moved = *moved_;
    size_t i;
    for (i = i0; i < i1; ++i) {
        const size_t k = (size_t)index[i];
        const real old = f[k];
        const real r = PIHYST_RAMP_VALUE(rx1[k], rx2[k], ry0[k], ry1[k], ry2[k], u);
        const real h = PIHYST_RAMP_VALUE(fx1[k], fx2[k], fy0[k], fy1[k], fy2[k], u);
        real v = h < old ? h : old; /* max2(r, min2(h, f)) as the model step */
        v = r > v ? r : v;
        f[k] = v;
        if (v != old) { /* hi + lo += t exactly (Knuth's TwoSum) */
            const real t = w[k] * (v - old), s = hi + t, bp = s - hi;
            lo += (hi - (s - bp)) + (t - bp);
            hi = s;
            moved += R_FABS(t);
        }
    }
    *hi_ = hi;
    *lo_ = lo;
    *moved_ = moved;
}

/* The model step's update at u of the monotone, ordered operators (not listed in
 * OFF_ODD) at positions [i0, i1) of the list of the direction, from the last voltage u_p:
 * going up (u > u_p) f_k <- max(R_k(u), f_k), going down f_k <- min(F_k(u), f_k), the
 * changes added to hi + lo exactly and their sizes to moved. This is the model step's
 *     f_k <- max(R_k(u), min(F_k(u), f_k))
 * bit for bit on these operators: after any model step R_k(u_p) <= f_k <= F_k(u_p)
 * (R <= F at every u in floating point), so going up F_k(u) >= F_k(u_p) >= f_k and the
 * min returns f_k; going down R_k(u) <= R_k(u_p) <= f_k and R_k(u) <= F_k(u), so the
 * max returns min(F_k(u), f_k). An operator already at its ramp's top (bottom going
 * down) keeps its state without evaluating the ramp (the ramp never exceeds its top).
 * The other ramp is never evaluated: half the model step's work, no division on the
 * operators the voltage passed over entirely: the positions before the first whose
 * greatest end (LIST_END_MAX) reaches u hold only ramps that end before u (start
 * beyond u, going down), whose value at u is y2 (y0 going down) with no comparison of
 * u. With `resum` the changes are not summed (the caller takes the exact sum
 * afterwards). */
static PIHYST_INLINE void ramps_commit_listed(pihyst_compensator *c, int down, size_t i0,
                                              size_t i1, real u, int resum, real *hi_,
                                              real *lo_, real *moved_)
{
    pihyst_model *m = &c->work_model;
    const real *PIHYST_RESTRICT r = ramp_block(c, OFF_REC + down * REC_N) + REC_N * i0;
    const real *PIHYST_RESTRICT w = m->weights;
    real *PIHYST_RESTRICT f = m->state;
    real hi = *hi_, lo = *lo_, moved = *moved_, hint = (real)i0;
    size_t i = i0, passed;
    /* in p (-u going down), the ramps that end before p = u (before or at, going up:
     * R = y2 from x2 on; strictly before going down: F = y0 below x1) */
    passed = !resum ? i0
                    : bound_from(list_array(c, down, LIST_END_MAX), m->n_ops, down ? -u : u,
                                 !down, &hint);
    if (passed > i1) passed = i1;
    if (resum && down) { /* as below, with the ramp's value y0; two at a time */
        for (; i + 1 < passed; i += 2, r += 2 * REC_N) {
            real *fa = f + rec_index(r), *fb = f + rec_index(r + REC_N);
            if (r[REC_Y0] < *fa) *fa = r[REC_Y0];
            if (r[REC_N + REC_Y0] < *fb) *fb = r[REC_N + REC_Y0];
        }
        if (i < passed) {
            real *fa = f + rec_index(r);
            if (r[REC_Y0] < *fa) *fa = r[REC_Y0];
            ++i;
            r += REC_N;
        }
    } else if (resum) { /* y2 */
        for (; i + 1 < passed; i += 2, r += 2 * REC_N) {
            real *fa = f + rec_index(r), *fb = f + rec_index(r + REC_N);
            if (r[REC_Y2] > *fa) *fa = r[REC_Y2];
            if (r[REC_N + REC_Y2] > *fb) *fb = r[REC_N + REC_Y2];
        }
        if (i < passed) {
            real *fa = f + rec_index(r);
            if (r[REC_Y2] > *fa) *fa = r[REC_Y2];
            ++i;
            r += REC_N;
        }
    }
    for (; i < i1; ++i, r += REC_N) {
        const size_t k = rec_index(r);
        const real old = f[k];
        real v;
        if (down) {
            if (!(old > r[REC_Y1])) continue; /* at its bottom: F_k(u) >= y1 >= f_k */
            v = PIHYST_RAMP_VALUE(r[REC_X1], r[REC_X2], r[REC_Y0], r[REC_Y1], r[REC_Y2], u);
            if (!(v < old)) continue; /* min(F_k(u), f_k) = f_k */
        } else {
            if (!(old < r[REC_Y2])) continue; /* at its top: R_k(u) <= y2 <= f_k */
            /* the value of PIHYST_RAMP_VALUE (x1 < x2), its commonest case first */
            v = u >= r[REC_X2] ? r[REC_Y2]
                               : PIHYST_RAMP_VALUE(r[REC_X1], r[REC_X2], r[REC_Y0], r[REC_Y1],
                                                   r[REC_Y2], u);
            if (!(v > old)) continue; /* max(R_k(u), f_k) = f_k */
        }
        f[k] = v;
        if (!resum) { /* hi + lo += t exactly (Knuth's TwoSum) */
            const real t = w[k] * (v - old), s = hi + t, bp = s - hi;
            lo += (hi - (s - bp)) + (t - bp);
            hi = s;
            moved += R_FABS(t);
        }
    }
    *hi_ = hi;
    *lo_ = lo;
    *moved_ = moved;
}

/* The model step from u_p = c->u_last to u, visiting only the operators with a ramp
 * between them (section comment). Going up, an operator whose ramps are monotone and
 * R <= F (ramps_init) changes only if its rising ramp lies between them: its state lies in
 * [R(u_p), F(u_p)] and F(u) >= F(u_p); going down likewise with the falling ramp. Those
 * are updated through that one ramp (ramps_commit_listed). The other operators (none, on
 * the default fit's models in single precision; 2 of 134 in double, whose ramps touch to
 * an ulp), if they are few (RAMP_ODD_FEW), are all updated in full, through both ramps,
 * after the one-ramp update (which changes nothing the full update would not:
 * max(R, min(F, max(R, f))) = max(R, min(F, f)), min likewise); if more, every operator
 * of either list with a ramp between u_p and u is updated in full. With the AVX2 model
 * step, returns 0, having done nothing, if that would be more than K / 2 visits (the
 * full step is cheaper then). */
static int ramps_step_sparse(pihyst_compensator *c, real u)
{
    pihyst_model *m = &c->work_model;
    const size_t K = m->n_ops;
    const real u_p = c->u_last, a = u < u_p ? u : u_p, b = u < u_p ? u_p : u;
    real *sum = ramp_sum(c);
    const size_t n_odd = (size_t)sum[SUM_ODD];
    const int down = u < u_p, few = n_odd <= RAMP_ODD_FEW;
    int resum;
    real hi = sum[SUM_HI], lo = sum[SUM_LO], moved = sum[SUM_MOVED];
    size_t i0, i1, j0 = 0, j1 = 0;
    /* the ramps of the direction reaching into (a, b) (in p = -u going down) */
    size_t n = down ? ramps_meeting(c, 1, -b, -a, &i0, &i1) : ramps_meeting(c, 0, a, b, &i0, &i1);
    if (few)
        n += n_odd;
    else
        n += down ? ramps_meeting(c, 0, a, b, &j0, &j1) : ramps_meeting(c, 1, -b, -a, &j0, &j1);
#ifdef RAMP_AVX2
    if ((c->in_order & PIHYST_ORDER_RAMPS_AVX2) && 2 * n > K) return 0;
#endif
    /* many changes: the exact sum afterwards (about 4 instructions an operator on an
     * M4F) costs less than a TwoSum for each (about 11) */
    resum = 3 * n > K;
    if (few) {
        ramps_commit_listed(c, down, i0, i1, u, resum, &hi, &lo, &moved);
        ramps_update_listed(c, ramp_block(c, OFF_ODD), 0, n_odd, u, &hi, &lo, &moved);
    } else {
        ramps_update_listed(c, list_array(c, down, LIST_INDEX), i0, i1, u, &hi, &lo, &moved);
        ramps_update_listed(c, list_array(c, !down, LIST_INDEX), j0, j1, u, &hi, &lo, &moved);
    }
    if (resum || moved > sum[SUM_BUDGET]) { /* the exact sum again, in the model's order */
        hi = pihyst_internal_weighted_sum(K, m->weights, m->state, m->offset);
        lo = moved = RC(0.0);
    }
    sum[SUM_HI] = hi;
    sum[SUM_LO] = lo;
    sum[SUM_MOVED] = moved;
    c->y_last = hi + lo;
    return 1;
}

/* What a probe at m finds: z(m) of (R1), the slopes of z just right and left of m, and
 * the nearest breakpoints strictly above and below m (+-inf if none). */
typedef struct {
    real z, right, left, next, prev;
} ramp_probe;

/* The sweep of a search from L (z(L) = zL) towards the window's end: the operators of
 * direction `up` are read once each, in the order of their ramps' starts (the list of the
 * direction), and z is evaluated at each distinct start beyond L, P < kappa:
 *     z(kappa) = z(P) + sum_{open} s_k (min(kappa, hi_k) - max(lo_k, P))^+
 * over the open operators: those read (start <= P) that move (below the ramp's top, going
 * up; above its bottom, going down; a slope) and whose interval (lo_k, hi_k) of (R1)
 * ends beyond P. No operator not yet read adds to z below kappa (lo_k >= its start >=
 * kappa), so z(kappa) is exact to rounding. The operators that start at P are read and
 * summed to kappa at once; one whose interval ends by kappa is closed (its whole rise is
 * in z(kappa)), the others are kept, with lo_k raised to kappa, in the other of two
 * buffers, and summed again at the next kappa. The first kappa with z(kappa) >= target
 * closes the bracket [P, kappa]: its operators (every operator with an interval meeting
 * (P, kappa): those kept from before P, and those that start at P, read again) go to the
 * cell kept for the next sample (cell_set); returns 1 with L = P, zL = z(P), H = kappa
 * and their number in *n_cell. Returns 0 if z at the window's end is below the target.
 * Each operator costs one read (a KP kernel's ramp spans one step of the grid of starts:
 * it closes where it was read), instead of a gather and a probe per cell it meets (the
 * cells this replaced); an operator at rest (its state y1 going up, y2 going down: the
 * ramp not reached) read at its own start, whose ramp ends by the next start, adds the
 * term its record holds, computed at init by the same expressions (REC_REST, REC_FULL):
 * one comparison instead of four, on most operators of a long jump. The read,
 * going up (p = u):
 *     lo_k = max(x1 + (f_k - y1) dx/dy, P),  hi_k = x2,     moves: f_k < y2, s_k > 0
 * (P >= u_p and P >= x1, the ramp's start: the max of section (R1)); going down, in
 * p = -u, lo_k = max(-(x1 + (f_k - y1) dx/dy), P), hi_k = -x1, moves: f_k > y1. */
static int ramps_sweep(pihyst_compensator *c, int up, real *L_, real *zL_, real *H_,
                       real end, real target, size_t *n_cell)
{
    const size_t K = c->work_model.n_ops;
    const int side = !up;
    const real *PIHYST_RESTRICT rec = ramp_block(c, OFF_REC + side * REC_N);
    const real *PIHYST_RESTRICT f = c->work_model.state;
    real *const cell_set = ramp_block(c, OFF_CELL);
    real *set = cell_set, *other = ramp_block(c, OFF_ACTIVE);
    real P = *L_, zP = *zL_;
    size_t n = 0, j;
    /* the first operator whose ramp ends beyond P, the first starting beyond it */
    size_t i = bound_from(list_array(c, side, LIST_END_MAX), K, P, 1,
                          ramp_sum(c) + SUM_HINTS + 2 * side);
    size_t g = bound_from(list_array(c, side, LIST_KEY), K, P, 1,
                          ramp_sum(c) + SUM_HINTS + 2 * side + 1);
    for (;;) {
        const real kappa =
            g < K && rec[REC_N * g + REC_KEY] < end ? rec[REC_N * g + REC_KEY] : end;
        const size_t i_read = i;
        /* reading the operators that start at P = kappa of the last round, each ending by
         * this kappa (the next start): an operator at rest adds its term of the records */
        const int fast = i_read < g && g < K && kappa == rec[REC_N * g + REC_KEY] &&
                         P == rec[REC_N * i_read + REC_KEY];
        real z = zP;
        size_t kept = 0;
        real *PIHYST_RESTRICT lo = set, *PIHYST_RESTRICT hi = set + K;
        real *PIHYST_RESTRICT w = set + 2 * K, *PIHYST_RESTRICT lo2 = other;
        real *PIHYST_RESTRICT hi2 = other + K, *PIHYST_RESTRICT w2 = other + 2 * K;
        /* the operators open at P: z(kappa), and those still open beyond kappa to the
         * other buffer (lo raised to kappa) */
        for (j = 0; j < n; ++j) {
            const real l = lo[j], h = hi[j], wj = w[j];
            if (h <= kappa) { /* closed: its whole rise */
                z += wj * (h - l);
                continue;
            }
            lo2[kept] = l;
            if (l < kappa) {
                z += wj * (kappa - l);
                lo2[kept] = kappa;
            }
            hi2[kept] = h;
            w2[kept] = wj;
            ++kept;
        }
        /* the operators whose ramps start at or before P, not read yet: read, summed
         * to kappa likewise */
#define PIHYST_SWEEP_READ(L_OF, HI)                                                        \
    for (; i < g; ++i) {                                                                   \
        const real *r = rec + REC_N * i;                                                   \
        const real fk = f[rec_index(r)], h = (HI);                                         \
        real l;                                                                            \
        if (fast && fk == r[REC_REST]) { /* at rest: its term, as computed below */       \
            z += r[REC_FULL];                                                              \
            continue;                                                                      \
        }                                                                                  \
        if (!(up ? fk < r[REC_LIMIT] : fk > r[REC_LIMIT])) continue;                       \
        l = (L_OF);                                                                        \
        l = l > P ? l : P;                                                                 \
        if (!(l < h)) continue;                                                            \
        if (h <= kappa) {                                                                  \
            z += r[REC_SLOPE] * (h - l);                                                   \
            continue;                                                                      \
        }                                                                                  \
        hi2[kept] = h;                                                                     \
        w2[kept] = r[REC_SLOPE];                                                           \
        if (l < kappa) {                                                                   \
            z += r[REC_SLOPE] * (kappa - l);                                               \
            l = kappa;                                                                     \
        }                                                                                  \
        lo2[kept] = l;                                                                     \
        ++kept;                                                                            \
    }
        if (up) { /* x1 + (f - y1) dx/dy; in p = -u: -(x1 + (f - y1) dx/dy) */
            PIHYST_SWEEP_READ(r[REC_KEY] + (fk - r[REC_Y1]) * r[REC_INV], r[REC_END])
        } else {
            PIHYST_SWEEP_READ(r[REC_END] - (fk - r[REC_Y1]) * r[REC_INV], r[REC_END])
        }
#undef PIHYST_SWEEP_READ
        if (z >= target) { /* the bracket [P, kappa]: its operators kept */
            if (set != cell_set) {
                memcpy(cell_set, lo, n * sizeof(real));
                memcpy(cell_set + K, hi, n * sizeof(real));
                memcpy(cell_set + 2 * K, w, n * sizeof(real));
            }
            /* and those just read, again (not clipped to kappa) */
            for (i = i_read; i < g; ++i) {
                const real *r = rec + REC_N * i;
                const real fk = f[rec_index(r)], h = r[REC_END];
                real l;
                if (!(up ? fk < r[REC_LIMIT] : fk > r[REC_LIMIT])) continue;
                l = up ? r[REC_KEY] + (fk - r[REC_Y1]) * r[REC_INV]
                       : r[REC_END] - (fk - r[REC_Y1]) * r[REC_INV];
                l = l > P ? l : P;
                if (!(l < h)) continue;
                cell_set[n] = l;
                cell_set[K + n] = h;
                cell_set[2 * K + n] = r[REC_SLOPE];
                ++n;
            }
            *L_ = P;
            *zL_ = zP;
            *H_ = kappa;
            *n_cell = n;
            return 1;
        }
        if (!(kappa < end)) return 0;
        P = kappa;
        zP = z;
        n = kept;
        g = (size_t)rec[REC_N * g + REC_NEXT]; /* the operators starting at kappa */
        {
            real *const t = set; /* swap the buffers */
            set = other;
            other = t;
        }
    }
}

/* A jump's probes on the operators that still matter. Inside the bracket [L, H],
 *     z(p) = zL + lin (p - L) + sum_{k in A} s_k (clamp(p, a_k, b_k) - a_k)
 * where A holds the operators with a breakpoint strictly inside (L, H), clipped to it
 * (a_k = max(lo_k, L), b_k = min(hi_k, H)): an operator whose clipped interval covers
 * [L, H] adds its slope to lin, one with nothing inside (L, H) adds nothing beyond zL.
 * Each probe first clips the set to the current bracket, folding or dropping operators,
 * and writes what is left compactly to (a, b, w) (from lo, hi, s: the first probe reads
 * every operator, later ones the set in place); then it finds at m z(m), the slopes just
 * right and left of m and the nearest breakpoints above and below m (bounded by H and
 * L), and with zH, z(H). The bracket shrinks with every probe, so the set does too: a
 * jump costs about one pass over the operators plus passes over ever fewer, instead of a
 * pass over all of them per probe. */
static PIHYST_INLINE void probe_active(size_t *n, const real *lo, const real *hi,
                                       const real *s, real *a, real *b, real *w, real L,
                                       real H, real zL, real *lin, real m, real *zH,
                                       ramp_probe *r)
{
    size_t i, j = 0;
    real z = RC(0.0), zh = RC(0.0), sr = RC(0.0), sl = RC(0.0), nx = H, pv = L, lin_ = *lin;
    for (i = 0; i < *n; ++i) {
        const real l = lo[i] > L ? lo[i] : L, h = hi[i] < H ? hi[i] : H, wi = s[i];
        /* nothing inside (L, H) */
        if (!(l < h)) continue;
        if (l <= L && h >= H) { /* covers the bracket: linear in it */
            lin_ += wi;
            continue;
        }
        a[j] = l;
        b[j] = h;
        w[j] = wi;
        ++j;
        if (zH) zh += wi * (h - l);
        /* its term at m: nothing but its start above m, its whole rise and its end
         * below m, or m on it (branches: a scalar FPU has no min/max) */
        if (l > m) {
            nx = l < nx ? l : nx;
        } else if (h < m) {
            z += wi * (h - l);
            pv = h > pv ? h : pv;
        } else {
            z += wi * (m - l);
            if (m < h) {
                sr += wi;
                nx = h < nx ? h : nx;
            }
            if (l < m) {
                sl += wi;
                pv = l > pv ? l : pv;
            }
        }
    }
    *n = j;
    *lin = lin_;
    if (zH) *zH = zL + lin_ * (H - L) + zh;
    r->z = zL + lin_ * (m - L) + z;
    r->right = lin_ + sr;
    r->left = lin_ + sl;
    r->next = nx;
    r->prev = pv;
}

/* The model step of a ramp model, with AVX2 on x86-64 (double precision; the f32 core is
 * for FPUs without it): the state update of pihyst_model_step bit for bit,
 *     f_k <- max(R_k(u), min(F_k(u), f_k)),   R, F by PIHYST_RAMP_VALUE,
 * then the model's own sum. The ramp constants lie one array per quantity (whole-vector
 * loads: the model reads its 4-point polylines operator by operator, ~16 scalar
 * instructions each), and a block of 4 operators none of whose ramps has u on its rising
 * part (u < x1 or u >= x2: most blocks) skips the division. The same operations in the
 * same order as the scalar expression, lane by lane: (y2 - y1) * (u - x1), / (x2 - x1),
 * + y1 (nothing to contract into an FMA), and min/max that return their second operand
 * on equality as `h < f ? h : f` and `r > v ? r : v` do. Picked at init when the CPU has
 * AVX2 (PIHYST_ORDER_RAMPS_AVX2); the compiler cannot be brought to vectorize the
 * portable form (it scalarizes the selects around the per-block division). */
#if defined(__GNUC__) && defined(__x86_64__) && !defined(PIHYST_BUILD_F32) && \
    !defined(PIHYST_NO_VECTOR_EXT)
#define RAMP_AVX2 1
#include <immintrin.h>

/* one ramp side of a block: the values at u, the division only where u is on a ramp */
#define RAMP_AVX2_SIDE(out, a, k)                                                          \
    do {                                                                                   \
        const __m256d x1_ = _mm256_loadu_pd((a)[RAMP_X1] + (k));                           \
        const __m256d x2_ = _mm256_loadu_pd((a)[RAMP_X2] + (k));                           \
        const __m256d y0_ = _mm256_loadu_pd((a)[RAMP_Y0] + (k));                           \
        const __m256d y2_ = _mm256_loadu_pd((a)[RAMP_Y2] + (k));                           \
        const __m256d below_ = _mm256_cmp_pd(uv, x1_, _CMP_LT_OQ); /* u < x1 */           \
        const __m256d above_ = _mm256_cmp_pd(uv, x2_, _CMP_GE_OQ); /* u >= x2 */           \
        (out) = _mm256_blendv_pd(y2_, y0_, below_);                                        \
        if (_mm256_movemask_pd(_mm256_or_pd(below_, above_)) != 15) {                      \
            const __m256d y1_ = _mm256_loadu_pd((a)[RAMP_Y1] + (k));                       \
            const __m256d t_ = _mm256_add_pd(                                              \
                y1_, _mm256_div_pd(_mm256_mul_pd(_mm256_sub_pd(y2_, y1_),                  \
                                                 _mm256_sub_pd(uv, x1_)),                  \
                                   _mm256_sub_pd(x2_, x1_)));                              \
            (out) = _mm256_blendv_pd(t_, (out), _mm256_or_pd(below_, above_));             \
        }                                                                                  \
    } while (0)

__attribute__((target("avx2"))) static void ramps_update_avx2(size_t K,
                                                               const real *const *rc,
                                                               const real *const *fc,
                                                               real *f, real u)
{
    const __m256d uv = _mm256_set1_pd(u);
    size_t k = 0;
    for (; k + 4 <= K; k += 4) {
        __m256d r, h;
        RAMP_AVX2_SIDE(r, rc, k);
        RAMP_AVX2_SIDE(h, fc, k);
        /* max(r, min(h, f)): minpd(h, f) = h < f ? h : f, maxpd(r, v) = r > v ? r : v */
        _mm256_storeu_pd(f + k, _mm256_max_pd(r, _mm256_min_pd(h, _mm256_loadu_pd(f + k))));
    }
    for (; k < K; ++k) {
        const real r = PIHYST_RAMP_VALUE(rc[RAMP_X1][k], rc[RAMP_X2][k], rc[RAMP_Y0][k],
                                         rc[RAMP_Y1][k], rc[RAMP_Y2][k], u);
        const real h = PIHYST_RAMP_VALUE(fc[RAMP_X1][k], fc[RAMP_X2][k], fc[RAMP_Y0][k],
                                         fc[RAMP_Y1][k], fc[RAMP_Y2][k], u);
        const real v = h < f[k] ? h : f[k];
        f[k] = r > v ? r : v;
    }
}
#undef RAMP_AVX2_SIDE

/* pihyst_model_step's value and state on a ramp model, through ramps_update_avx2 */
static real ramps_step_avx2(pihyst_compensator *c, real u)
{
    pihyst_model *m = &c->work_model;
    const real *rc[RAMP_N], *fc[RAMP_N];
    int i;
    for (i = 0; i < RAMP_N; ++i) {
        rc[i] = ramp_array(c, 0, i);
        fc[i] = ramp_array(c, 1, i);
    }
    ramps_update_avx2(m->n_ops, rc, fc, m->state, u);
    return pihyst_internal_weighted_sum(m->n_ops, m->weights, m->state, m->offset);
}
#endif

/* the p in [a, b] on the line through (a, za), (b, zb) with z = target (za < target <=
 * zb) */
static real ramp_interpolate(real a, real za, real b, real zb, real target)
{
    const real p = a + (target - za) * ((b - a) / (zb - za));
    return p < a ? a : (p > b ? b : p);
}

/* The least p in (q, q + span] with z(p) = target (> 0), as the distance d = p - q:
 * returns 1, or 0 with d = span if z(q + span) < target. Same contract as solve. */
static int solve_ramps(pihyst_compensator *c, int up, real u_p, real span, real target,
                       real *d)
{
    const size_t K = c->work_model.n_ops;
    const real q = up ? u_p : -u_p, end = q + span;
    real L = q, zL = RC(0.0), H = end, zH = RC(0.0), p = end, width, lin = RC(0.0);
    real *act = ramp_block(c, OFF_ACTIVE), *cell_set = ramp_block(c, OFF_CELL);
    size_t n_active;
    ramp_probe r;
    int i, halve = 0, found = 0;
    if (c->dir != (up ? 1 : -1)) { /* a reversal: nothing kept */
        c->dir = up ? 1 : -1;
        c->next[0] = c->next[1] = 0;
    }
    /* The segment of the last answer, kept (next[0] = 1) with its slope (slope[0]) and
     * right end (ahead): z is linear from q up to there, so while the answer stays
     * inside it needs no probe (a tracking step mostly does). */
    if (c->next[0]) {
        const real nb = c->ahead < end ? c->ahead : end, sigma = c->slope[0];
        if (nb > q && sigma * (nb - q) >= target) {
            p = q + target / sigma; /* sigma > 0: z rose by target within the segment */
            *d = (p < nb ? p : nb) - q;
            return 1;
        }
        c->next[0] = 0;
    }
    /* The cell of the last search (next[1] = its operators + 1, base = its end): its
     * operators' intervals stay as they were while the direction holds, so while q lies
     * inside it a probe of its kept set replaces a gather. */
    if (c->next[1] && q < c->base) {
        H = c->base < end ? c->base : end;
        n_active = c->next[1] - 1;
        p = L + RC(0.5) * (H - L);
        if (!(p > L && p < H)) p = H;
        probe_active(&n_active, cell_set, cell_set + K, cell_set + 2 * K, act, act + K,
                     act + 2 * K, L, H, zL, &lin, p, &zH, &r);
        if (zH >= target) {
            found = 1;
        } else if (!(H < end)) { /* the window ends below the target */
            *d = span;
            return 0;
        } else {
            L = H;
            zL = zH;
        }
    }
    /* the sweep from L: the bracket [L, H] whose z(H) reaches the target and its
     * operators (kept for the next sample), probed once at its midpoint (H if L and H
     * are adjacent numbers), which also gives z(H) */
    if (!found) {
        size_t n_cell;
        if (!ramps_sweep(c, up, &L, &zL, &H, end, target, &n_cell)) {
            c->next[1] = 0;
            *d = span; /* the window ends below the target */
            return 0;
        }
        c->base = H;
        c->next[1] = n_cell + 1;
        n_active = n_cell;
        lin = RC(0.0);
        p = L + RC(0.5) * (H - L);
        if (!(p > L && p < H)) p = H;
        probe_active(&n_active, cell_set, cell_set + K, cell_set + 2 * K, act, act + K,
                     act + 2 * K, L, H, zL, &lin, p, &zH, &r);
    }
    width = H - L;
    for (i = 0; i < 100; ++i) {
        /* the secant point, or the midpoint if the bracket shrank by less than half */
        real m = p;
        if (i > 0) {
            m = halve ? L + RC(0.5) * (H - L) : ramp_interpolate(L, zL, H, zH, target);
            if (!(m > L && m < H)) m = L + RC(0.5) * (H - L);
            if (!(m > L && m < H)) break; /* L, H adjacent numbers */
            probe_active(&n_active, act, act + K, act + 2 * K, act, act + K, act + 2 * K, L, H,
                         zL, &lin, m, NULL, &r);
        } else if (!(m < H)) {
            break;
        }
        if (r.z < target) { /* the answer lies right of m */
            const real nb = r.next < H ? r.next : H;
            const real zn = r.z + r.right * (nb - m);
            if (!(nb < H)) { /* no breakpoint in (m, H): linear up to H */
                *d = ramp_interpolate(m, r.z, H, zH, target) - q;
                return 1;
            }
            if (zn >= target) {
                p = m + (target - r.z) / r.right;
                *d = (p < nb ? p : nb) - q;
                c->next[0] = 1; /* keep the segment [m, r.next] */
                c->slope[0] = r.right;
                c->ahead = r.next;
                return 1;
            }
            L = nb;
            zL = zn;
        } else { /* z(m) >= target: the least such p lies at or left of m */
            const real pb = r.prev > L ? r.prev : L;
            const real zp = r.z - r.left * (m - pb);
            if (!(pb > L)) { /* no breakpoint in (L, m): linear from L */
                *d = ramp_interpolate(L, zL, m, r.z, target) - q;
                return 1;
            }
            if (zp < target) {
                p = pb + (target - zp) / r.left;
                *d = (p < m ? p : m) - q;
                c->next[0] = 1; /* keep the segment [pb, m] */
                c->slope[0] = r.left;
                c->ahead = m;
                return 1;
            }
            H = pb;
            zH = zp;
        }
        halve = !(H - L <= RC(0.5) * width);
        width = H - L;
    }
    *d = ramp_interpolate(L, zL, H, zH, target) - q;
    return 1;
}

/* ------------------------------------------------------------------ reversal */

/* A reversal (or the first sample) on the lists: collect the events of direction `up`
 * from u_p into a and b, sorted by distance, to be walked from u_p and kept for the
 * following samples. Classical and multislope lists arrive sorted for reachable states
 * (checked, in O(K)); others are sorted. */
static PIHYST_NOINLINE void reverse(pihyst_compensator *c, int up, real u_p)
{
    const pihyst_model *m = &c->work_model;
    events e;
    int sorted = 0;
    lists(c, &e);
    switch (m->family) {
    case PIHYST_CLASSICAL:
        sorted = !collect_classical(m, up, u_p, &e);
        break;
    case PIHYST_MULTISLOPE:
        sorted = !collect_multislope(m, c->scratch, up, u_p, &e) &&
                 (c->in_order & (up ? PIHYST_ORDER_RISING_KINKS : PIHYST_ORDER_FALLING_KINKS));
        break;
    default:
        collect_pwl(m, up, u_p, up ? c->u_max - u_p : u_p - c->u_min, &e);
        break;
    }
    if (!sorted) {
        sort_events(e.ad, e.as, e.na);
        sort_events(e.bd, e.bs, e.nb);
    }
    e.ad[e.na] = e.bd[e.nb] = R_INF; /* sentinels */
    e.as[e.na] = e.bs[e.nb] = RC(0.0);
    c->next[0] = c->next[1] = 0;
    c->slope[0] = e.s0;
    c->slope[1] = RC(0.0);
}

/* The distance d in (0, span] at which |y - y_p| first reaches target (returns 1), or
 * d = span if the window ends first (returns 0). */
static PIHYST_INLINE int solve(pihyst_compensator *c, int up, real u_p, real span,
                               real target, real *d)
{
    const pihyst_model *m = &c->work_model;
    events e;
    if (c->in_order & PIHYST_ORDER_RAMPS) return solve_ramps(c, up, u_p, span, target, d);
    if (c->dir != (up ? 1 : -1)) { /* a reversal: start again from u_p */
        c->dir = up ? 1 : -1;
        c->base = u_p;
        if (m->family == PIHYST_CLASSICAL && !(c->in_order & PIHYST_ORDER_CLASSICAL) && lipschitz(c))
            c->in_order |= PIHYST_ORDER_CLASSICAL;
        if (c->in_order & PIHYST_ORDER_CLASSICAL) {
            const real x = up ? (m->state[0] + m->coef[m->n_ops]) - u_p
                                : u_p - (m->state[0] - m->coef[m->n_ops]);
            c->next[0] = c->next[1] = 0;
            c->slope[0] = c->slope[1] = RC(0.0);
            c->ahead = x > RC(0.0) ? x : RC(0.0);
        } else {
            reverse(c, up, u_p);
        }
    }
    if (c->in_order & PIHYST_ORDER_CLASSICAL)
        return walk_classical(m, up, c->base, c->next, &c->ahead, c->slope,
                              up ? u_p - c->base : c->base - u_p, target, span, d);
    lists(c, &e);
    return walk(e.ad, e.as, e.bd, e.bs, c->next, c->slope, up ? u_p - c->base : c->base - u_p,
                target, span, m->family == PIHYST_PWL, d);
}

/* ------------------------------------------------------------------ public API */

static size_t pwl_points(const pihyst_model *m)
{
    size_t nr, nf;
    if (m->family != PIHYST_PWL) return 0;
    nr = m->pwl.rise_start[m->n_ops];
    nf = m->pwl.fall_start[m->n_ops];
    return nr > nf ? nr : nf;
}

size_t pihyst_compensator_scratch_len(const pihyst_model *m)
{
    /* kinks 2K | crossing list 2 (K + 2 points + 1) | kink list 2 (K + 1), or for a ramp
     * model what the ramp path keeps (RAMP_SCRATCH) if that is more | working state K on
     * a PIHYST_STATE_ALIGN boundary (+ the padding that takes) */
    const size_t K = m->n_ops;
    size_t n = 6 * K + 4 * pwl_points(m) + 4;
    if (ramp_model(m) && RAMP_SCRATCH(K) > n) n = RAMP_SCRATCH(K);
    return n + K + PIHYST_STATE_ALIGN / sizeof(real);
}

/* Forget the kept events (the state was set): the next sample collects afresh, and a
 * classical state is checked for order again (walk_classical). */
static void forget_events(pihyst_compensator *c)
{
    c->dir = 0;
    c->in_order &= ~PIHYST_ORDER_CLASSICAL;
    c->next[0] = c->next[1] = 0;
    c->slope[0] = c->slope[1] = c->base = c->ahead = RC(0.0);
}

/* The compensator steps its own copy of the model, c->work_model, and never writes the
 * caller's model struct. The copy's state is the caller's array if that lies on a
 * PIHYST_STATE_ALIGN boundary, else an aligned array at the end of the scratch (the
 * model loops run up to twice as fast on an aligned state, see pihyst_model_run); then
 * publish() copies it to the caller's array before a call returns, so that array is
 * current between calls. */
static real *working_state(pihyst_model *m, real *scratch)
{
#if PIHYST_STATE_ALIGN > 0
    const size_t K = m->n_ops;
    uintptr_t at;
    if ((uintptr_t)m->state % PIHYST_STATE_ALIGN == 0) return m->state;
    at = (uintptr_t)(scratch + pihyst_compensator_scratch_len(m) - K -
                     PIHYST_STATE_ALIGN / sizeof(real));
    at = (at + PIHYST_STATE_ALIGN - 1) / PIHYST_STATE_ALIGN * PIHYST_STATE_ALIGN;
    return (real *)at;
#else
    (void)scratch;
    return m->state;
#endif
}

static void publish(pihyst_compensator *c)
{
    if (c->work_model.state != c->model->state)
        memcpy(c->model->state, c->work_model.state, c->model->n_ops * sizeof(real));
}

/* apply u to the working state, every operator (any state: init, reset); a ramp
 * model's running sum starts again from the model step's exact sum */
static void apply_full(pihyst_compensator *c, real u)
{
#ifdef RAMP_AVX2
    if (c->in_order & PIHYST_ORDER_RAMPS_AVX2)
        c->y_last = ramps_step_avx2(c, u);
    else
#endif
        c->y_last = pihyst_model_step(&c->work_model, u);
    c->u_last = u;
    if (c->in_order & PIHYST_ORDER_RAMPS) {
        real *sum = ramp_sum(c);
        sum[SUM_HI] = c->y_last;
        sum[SUM_LO] = sum[SUM_MOVED] = RC(0.0);
    }
}

/* apply u to the working state after the last voltage: a ramp model visits only the
 * operators with a ramp between the two (ramps_step_sparse) */
static void apply(pihyst_compensator *c, real u)
{
    if ((c->in_order & PIHYST_ORDER_RAMPS) && ramps_step_sparse(c, u)) {
        c->u_last = u;
        return;
    }
    apply_full(c, u);
}

pihyst_status pihyst_compensator_init(pihyst_compensator *c, pihyst_model *m, real u_min,
                                      real u_max, real max_step, real u_initial,
                                      real *scratch, size_t scratch_len)
{
    size_t k, K;
    real scale, *rise, *fall;
    if (!c || !m || !scratch) return PIHYST_ENULL;
    K = m->n_ops;
    for (k = 0; k < K; ++k)
        if (m->weights[k] < RC(0.0)) return PIHYST_ENEGATIVE_WEIGHT;
    if (isnan(u_min)) u_min = m->u_min;
    if (isnan(u_max)) u_max = m->u_max;
    if (!(m->u_min <= u_min && u_min < u_max && u_max <= m->u_max)) return PIHYST_ELIMITS;
    if (!(max_step > RC(0.0))) return PIHYST_ELIMITS; /* also NaN */
    if (scratch_len < pihyst_compensator_scratch_len(m)) return PIHYST_ESCRATCH;
    if (!isfinite(u_initial)) return PIHYST_ENONFINITE;
    if (!(u_min <= u_initial && u_initial <= u_max)) return PIHYST_ELIMITS;

    c->model = m;
    c->work_model = *m;
    c->u_min = u_min;
    c->u_max = u_max;
    c->max_step = max_step;
    c->scratch = scratch;
    c->scratch_len = scratch_len;
    c->events_cap = K + 2 * pwl_points(m); /* pwl: two events per breakpoint */

    /* Output scale |offset| + sum_k w_k max|envelopes at the limits| bounds the terms
     * of (2) for every state consistent with a voltage in the limits; the rounding of
     * a K-term sum is below (K + 2) eps times it. */
    rise = scratch + 2 * K;
    fall = scratch + 3 * K;
    scale = R_FABS(m->offset);
    pihyst_model_envelopes(m, u_min, rise, fall);
    for (k = 0; k < K; ++k) {
        real v = R_FABS(rise[k]) > R_FABS(fall[k]) ? R_FABS(rise[k]) : R_FABS(fall[k]);
        scratch[4 * K + k] = v;
    }
    pihyst_model_envelopes(m, u_max, rise, fall);
    for (k = 0; k < K; ++k) {
        real v = scratch[4 * K + k];
        if (R_FABS(rise[k]) > v) v = R_FABS(rise[k]);
        if (R_FABS(fall[k]) > v) v = R_FABS(fall[k]);
        scale += m->weights[k] * v;
    }
    c->tol = RC(4.0) * ((real)K + RC(2.0)) * R_EPS * scale;

    if (m->family == PIHYST_MULTISLOPE) {
        /* rising kink: a u + c1 = b u + c2;  falling kink: b u = a u + c3 */
        const real ba = m->shape.b - m->shape.a;
        for (k = 0; k < K; ++k) {
            scratch[k] = (m->coef[k] - m->coef[K + k]) / ba;
            scratch[K + k] = m->coef[2 * K + k] / ba;
        }
    }
    /* kinks in operator order by distance: rising ones increasing, falling ones
     * decreasing (a < 1 for both, and a h < 1 for the falling ones) */
    c->in_order = PIHYST_ORDER_RISING_KINKS | PIHYST_ORDER_FALLING_KINKS;
    for (k = 1; k < K && m->family == PIHYST_MULTISLOPE; ++k) {
        if (scratch[k] < scratch[k - 1]) c->in_order &= ~PIHYST_ORDER_RISING_KINKS;
        if (scratch[K + k] > scratch[K + k - 1]) c->in_order &= ~PIHYST_ORDER_FALLING_KINKS;
    }
    if (ramp_model(m)) { /* saturated ramps */
        c->in_order |= PIHYST_ORDER_RAMPS;
        ramps_init(c, scale);
#ifdef RAMP_AVX2
        if (__builtin_cpu_supports("avx2")) c->in_order |= PIHYST_ORDER_RAMPS_AVX2;
#endif
    }
    c->work_model.state = working_state(m, scratch);
    if (c->work_model.state != m->state) memcpy(c->work_model.state, m->state, K * sizeof(real));
    forget_events(c);
    apply_full(c, u_initial);
    publish(c);
    return PIHYST_OK;
}

pihyst_status pihyst_compensator_reset(pihyst_compensator *c, const real *state,
                                       real u_last)
{
    size_t k;
    if (!c) return PIHYST_ENULL;
    if (!isfinite(u_last)) return PIHYST_ENONFINITE;
    if (!(c->u_min <= u_last && u_last <= c->u_max)) return PIHYST_ELIMITS;
    if (state)
        for (k = 0; k < c->work_model.n_ops; ++k)
            if (!isfinite(state[k])) return PIHYST_ENONFINITE;
    pihyst_model_reset(&c->work_model, state);
    forget_events(c);
    apply_full(c, u_last);
    publish(c);
    return PIHYST_OK;
}

/* Window end above u_p: min(u_max, u_p + max_step), with u_p + max_step lowered by
 * ulps until (end - u_p) <= max_step holds in floating point. */
static real window_hi(const pihyst_compensator *c, real u_p, int *slew)
{
    real h = u_p + c->max_step;
    while (h - u_p > c->max_step) h = R_NEXTAFTER(h, u_p);
    *slew = h < c->u_max;
    return *slew ? h : c->u_max;
}

static real window_lo(const pihyst_compensator *c, real u_p, int *slew)
{
    real l = u_p - c->max_step;
    while (u_p - l > c->max_step) l = R_NEXTAFTER(l, u_p);
    *slew = l > c->u_min;
    return *slew ? l : c->u_min;
}

/* One sample on the working state. Returns the flags. */
static PIHYST_INLINE pihyst_flags step(pihyst_compensator *c, real y_desired)
{
    const real u_p = c->u_last, y_p = c->y_last;
    pihyst_flags fl = 0;
    if (isnan(y_desired)) {
        fl = PIHYST_COMP_NAN;
    } else if (!(R_FABS(y_desired - y_p) <= c->tol)) {
        const int up = y_desired > y_p;
        int slew;
        real u, d;
        const real end = up ? window_hi(c, u_p, &slew) : window_lo(c, u_p, &slew);
        const real span = up ? end - u_p : u_p - end;
        const real target = up ? y_desired - y_p : y_p - y_desired;
        if (span > RC(0.0) && solve(c, up, u_p, span, target, &d)) {
            /* u_p +- d, kept inside [u_p, end] against rounding */
            if (up) {
                u = u_p + d;
                u = u > end ? end : (u < u_p ? u_p : u);
            } else {
                u = u_p - d;
                u = u < end ? end : (u > u_p ? u_p : u);
            }
        } else {
            u = end;
            fl = up ? PIHYST_COMP_SAT_HIGH : PIHYST_COMP_SAT_LOW;
            if (slew) {
                /* cut short by the slew limit; out of reach too if the voltage limit
                 * itself misses y_desired (out of reach does not depend on the slew) */
                const real y_limit =
                    pihyst_internal_output_at(&c->work_model, up ? c->u_max : c->u_min);
                const real short_by = up ? y_desired - y_limit : y_limit - y_desired;
                fl = short_by > c->tol ? (pihyst_flags)(fl | PIHYST_COMP_SLEW)
                                       : PIHYST_COMP_SLEW;
            }
        }
        if (u != u_p) apply(c, u);
        /* at the window's end the model may meet y_d after all, to rounding: not a miss */
        if (fl && R_FABS(y_desired - c->y_last) <= c->tol) fl = 0;
    }
    return fl;
}

real pihyst_compensator_step(pihyst_compensator *c, real y_desired, pihyst_flags *flags)
{
    const real u_p = c->u_last;
    const pihyst_flags fl = step(c, y_desired);
    if (c->u_last != u_p) publish(c);
    if (flags) *flags = fl;
    return c->u_last;
}

size_t pihyst_compensator_run(pihyst_compensator *c, const real *y_desired, real *u,
                              real *y, pihyst_flags *flags, size_t n)
{
    size_t t, count = 0;
    for (t = 0; t < n; ++t) {
        const pihyst_flags fl = step(c, y_desired[t]);
        u[t] = c->u_last;
        if (y) y[t] = c->y_last;
        if (flags) flags[t] = fl;
        count += fl != 0;
    }
    if (n > 0) publish(c);
    return count;
}
