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
 *          at u_p contributes from d = 0;
 *        - each envelope kink beyond the crossing changes the slope by
 *          w_k (slope after - slope before).
 *   3. Sort the events by distance, walk them accumulating z and the slope s, and in
 *      the first segment [d_a, d_e] with z(d_e) >= target solve
 *          z(d_a) + s (d - d_a) = target  ->  d = d_a + (target - z(d_a)) / s,
 *      s > 0 there because z rises across the segment. That d is the smallest
 *      solution: the voltage nearest u_p (flat stretches before it are passed over,
 *      never entered). If no segment reaches the target, the window's end is taken
 *      and flagged (limit, or slew limit if that end is the slew bound), unless the
 *      model's output there meets y_d to rounding after all.
 *   4. Apply the voltage to the model, which gives the new state and y_last.
 *
 * The sorted events are kept for the next sample while the direction stays the same:
 * an operator not yet on its envelope keeps its f_k (so its crossing stays where it
 * was), one on its envelope stays on it, and the kinks are fixed. The next sample in
 * the same direction continues the walk from the first event not yet passed, with the
 * slope reached there; only a reversal (or a reset) collects and sorts again, over the
 * whole distance to the voltage limit. A tracking step thus costs O(1 + events passed)
 * plus the model step, a reversal O(K) (O(K log K) for badly unsorted events).
 *
 * Events per family, going up (R_k, crossing c_k = least u >= u_p with R_k(u) >= f_k)
 * and going down (F_k, crossing c_k = greatest u <= u_p with F_k(u) <= f_k):
 *   classical:  up   c_k = f_k + r_k, slope 1;   down  c_k = f_k - r_k, slope 1.
 *               Reachable states satisfy |f_k - f_j| <= |r_k - r_j|, so the crossings
 *               arrive sorted in k and insertion sort is O(K).
 *   multislope: R_k(u) = max(a u + c1_k, b u + c2_k): c_k = min((f_k - c1_k)/a,
 *               (f_k - c2_k)/b); kink at (c1_k - c2_k)/(b - a), slope a -> b.
 *               F_k(u) = min(b u, a u + c3_k): c_k = max(f_k/b, (f_k - c3_k)/a);
 *               kink at c3_k/(b - a), slope (going down) a -> b.
 *               Kinks go in a second list (sorted in k for the paper's shapes),
 *               merged with the sorted crossings into the one list the walk follows.
 *   pwl:        the crossing by binary search on the polyline's values, then every
 *               interior breakpoint beyond it with its slope change, as two events
 *               (+ new slope, - old slope) that the walk sums exactly.
 * Events at or beyond the voltage limit are not collected. The walk keeps its slope as
 * a compensated sum (hi + lo), so that a near-vertical segment joining and leaving
 * (+huge, then -huge) does not wipe out the small slopes around it.
 */
#include "pihyst.h"

#include <float.h>
#include <math.h>

/* ------------------------------------------------------------------ event lists */

/* Events are (distance, slope change) pairs stored interleaved: ev[2i], ev[2i + 1]. */

static void heap_sift(double *ev, size_t root, size_t n)
{
    for (;;) {
        size_t child = 2 * root + 1;
        double d, s;
        if (child >= n) return;
        if (child + 1 < n && ev[2 * (child + 1)] > ev[2 * child]) ++child;
        if (!(ev[2 * child] > ev[2 * root])) return;
        d = ev[2 * root]; s = ev[2 * root + 1];
        ev[2 * root] = ev[2 * child]; ev[2 * root + 1] = ev[2 * child + 1];
        ev[2 * child] = d; ev[2 * child + 1] = s;
        root = child;
    }
}

static void heap_sort(double *ev, size_t n)
{
    size_t i;
    if (n < 2) return;
    for (i = n / 2; i-- > 0;) heap_sift(ev, i, n);
    for (i = n - 1; i > 0; --i) {
        double d = ev[0], s = ev[1];
        ev[0] = ev[2 * i]; ev[1] = ev[2 * i + 1];
        ev[2 * i] = d; ev[2 * i + 1] = s;
        heap_sift(ev, 0, i);
    }
}

/* Sort by distance: insertion sort, O(n) on the nearly sorted lists of reachable
 * states; if it has moved more than 4n + 8 elements the list is far from sorted and
 * heapsort finishes the job, so the worst case stays O(n log n). */
static void sort_events(double *ev, size_t n)
{
    size_t i, moves = 0;
    const size_t budget = 4 * n + 8;
    for (i = 1; i < n; ++i) {
        const double d = ev[2 * i], s = ev[2 * i + 1];
        size_t j = i;
        while (j > 0 && ev[2 * (j - 1)] > d) {
            ev[2 * j] = ev[2 * (j - 1)];
            ev[2 * j + 1] = ev[2 * (j - 1) + 1];
            --j;
            ++moves;
        }
        ev[2 * j] = d;
        ev[2 * j + 1] = s;
        if (moves > budget) {
            heap_sort(ev, n);
            return;
        }
    }
}

/* Walk the sorted cached events ev[*next ..] (distances from the base voltage; q_p is
 * u_p's distance from it, so an event lies d_e = ev - q_p beyond u_p) with slope *slope
 * at u_p and z(0) = 0, up to distance span. Returns 1 and the smallest d with
 * z(d) = target (0 < target) if z(span) >= target, else 0 with d = span. Events passed
 * are consumed: *next and *slope then describe the voltage u_p + d. */
static int walk(const double *ev, size_t n, size_t *next, double slope[2], double q_p,
                double target, double span, double *d_out)
{
    /* the slope is a compensated sum hi + lo (Knuth's TwoSum), so that a steep polyline
     * segment joining and leaving (+huge, then -huge) leaves the small slopes intact */
    double z = 0.0, d0 = 0.0, hi = slope[0], lo = slope[1], s = hi + lo, z_end;
    size_t i;
    int hit = 0;
    for (i = *next; i < n; ++i) {
        double de = ev[2 * i] - q_p, ze, t, bp;
        if (de < d0) de = d0; /* passed already, to rounding */
        if (!(de < span)) break;
        /* z(d_e) = z(d_a) + s (d_e - d_a) */
        ze = z + s * (de - d0);
        if (ze >= target) {
            const double d = d0 + (target - z) / s; /* s > 0: z rose from below target */
            *d_out = d < de ? d : de;
            hit = 1;
            break;
        }
        z = ze;
        d0 = de;
        /* hi + lo += ds */
        t = hi + ev[2 * i + 1];
        bp = t - hi;
        lo += (hi - (t - bp)) + (ev[2 * i + 1] - bp);
        hi = t;
        s = hi + lo;
    }
    if (!hit) {
        z_end = z + s * (span - d0);
        if (z_end >= target) {
            const double d = d0 + (target - z) / s;
            *d_out = d < span ? d : span;
            hit = 1;
        } else {
            *d_out = span;
        }
    }
    *next = i;
    slope[0] = hi;
    slope[1] = lo;
    return hit;
}

/* Merge the sorted lists a (na) and b (nb) into out. */
static void merge_events(const double *a, size_t na, const double *b, size_t nb, double *out)
{
    size_t i = 0, j = 0, n = 0;
    while (i < na || j < nb) {
        if (i < na && (j >= nb || a[2 * i] <= b[2 * j])) {
            out[2 * n] = a[2 * i]; out[2 * n + 1] = a[2 * i + 1]; ++i;
        } else {
            out[2 * n] = b[2 * j]; out[2 * n + 1] = b[2 * j + 1]; ++j;
        }
        ++n;
    }
}

/* ------------------------------------------------------------------ collection */

typedef struct {
    double *a;   /* crossings (and pwl breakpoints) */
    size_t na;
    double *b;   /* multislope kinks */
    size_t nb;
    double s0;   /* slope at distance 0+ */
} events;

static void push(double *ev, size_t *n, double d, double ds)
{
    ev[2 * *n] = d;
    ev[2 * *n + 1] = ds;
    ++*n;
}

/* classical, (3a): c_k = f_k + r_k;  (3b): c_k = f_k - r_k; slope w_k from c_k on */
static void collect_classical(const pihyst_model *m, int up, double u_p, double span,
                              events *e)
{
    const size_t K = m->n_ops;
    const double *restrict w = m->weights, *restrict r = m->coef + K, *restrict f = m->state;
    double *restrict a = e->a;
    double s = 0.0;
    size_t k, n = 0;
    for (k = 0; k < K; ++k) {
        const double d = up ? (f[k] + r[k]) - u_p : u_p - (f[k] - r[k]);
        if (d <= 0.0) {
            s += w[k];
        } else if (d < span) {
            a[2 * n] = d;
            a[2 * n + 1] = w[k];
            ++n;
        }
    }
    e->na = n;
    e->nb = 0;
    e->s0 = s;
}

/* multislope, see the header comment of this file for c_k and the kinks */
static void collect_multislope(const pihyst_model *m, const double *kinks, int up, double u_p,
                               double span, events *e)
{
    const size_t K = m->n_ops;
    const double a_ = m->shape.a, b_ = m->shape.b, ia = 1.0 / a_, ib = 1.0 / b_;
    const double *restrict w = m->weights, *restrict f = m->state, *restrict c = m->coef;
    double s = 0.0;
    size_t k, na = 0, nb = 0;
    if (up) {
        const double *kr = kinks;
        for (k = 0; k < K; ++k) {
            /* R(u) = max(a u + c1, b u + c2) >= f  <=>  u >= min((f - c1)/a, (f - c2)/b) */
            const double x1 = (f[k] - c[k]) * ia, x2 = (f[k] - c[K + k]) * ib;
            const double cross = x1 < x2 ? x1 : x2, d = cross - u_p, dk = kr[k] - u_p;
            if (d <= 0.0) {
                s += w[k] * (u_p < kr[k] ? a_ : b_);
                if (dk > 0.0 && dk < span) push(e->b, &nb, dk, w[k] * (b_ - a_));
            } else if (d < span) {
                push(e->a, &na, d, w[k] * (cross < kr[k] ? a_ : b_));
                if (kr[k] > cross && dk < span) push(e->b, &nb, dk, w[k] * (b_ - a_));
            }
        }
    } else {
        const double *kf = kinks + K;
        for (k = 0; k < K; ++k) {
            /* F(u) = min(b u, a u + c3) <= f  <=>  u <= max(f/b, (f - c3)/a) */
            const double x1 = f[k] * ib, x2 = (f[k] - c[2 * K + k]) * ia;
            const double cross = x1 > x2 ? x1 : x2, d = u_p - cross, dk = u_p - kf[k];
            if (d <= 0.0) {
                s += w[k] * (u_p > kf[k] ? a_ : b_);
                if (dk > 0.0 && dk < span) push(e->b, &nb, dk, w[k] * (b_ - a_));
            } else if (d < span) {
                push(e->a, &na, d, w[k] * (cross > kf[k] ? a_ : b_));
                if (kf[k] < cross && dk < span) push(e->b, &nb, dk, w[k] * (b_ - a_));
            }
        }
    }
    e->na = na;
    e->nb = nb;
    e->s0 = s;
}

/* first index i in [0, n] with v[i] >= x (v non-decreasing) */
static size_t lower_bound(const double *v, size_t n, double x)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (v[mid] < x) lo = mid + 1; else hi = mid;
    }
    return lo;
}

/* first index i in [0, n] with v[i] > x (v non-decreasing) */
static size_t upper_bound(const double *v, size_t n, double x)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (v[mid] <= x) lo = mid + 1; else hi = mid;
    }
    return lo;
}

/* slope of segment i, between breakpoints i and i + 1 */
static double seg_slope(const double *x, const double *y, size_t i)
{
    return (y[i + 1] - y[i]) / (x[i + 1] - x[i]);
}

/* pwl going up, (3a), operator with rising polyline (x, y, n >= 2):
 * crossing = least u with R(u) >= f; segment `seg` holds it (extensions included). */
static void collect_pwl_up(const double *x, const double *y, size_t n, double w, double f,
                           double u_p, double span, events *e)
{
    size_t i = lower_bound(y, n, f), seg, q;
    double cross;
    if (i == 0) { /* f <= y[0]: in the left extension, or R >= f everywhere */
        const double s = seg_slope(x, y, 0);
        seg = 0;
        cross = s > 0.0 ? x[0] - (y[0] - f) / s : -INFINITY;
    } else if (i == n) { /* f > y[n-1]: in the right extension, or never */
        const double s = seg_slope(x, y, n - 2);
        seg = n - 2;
        cross = s > 0.0 ? x[n - 1] + (f - y[n - 1]) / s : INFINITY;
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
        const double d = cross - u_p;
        if (!(d < span)) return;
        push(e->a, &e->na, d, w * seg_slope(x, y, seg));
    }
    for (q = seg + 1; q + 1 < n; ++q) { /* interior breakpoints beyond */
        const double d = x[q] - u_p;
        if (!(d < span)) break;
        /* slope change as two events, + new and - old, summed exactly by the walk */
        push(e->a, &e->na, d, w * seg_slope(x, y, q));
        push(e->a, &e->na, d, -w * seg_slope(x, y, q - 1));
    }
}

/* pwl going down, (3b), operator with falling polyline (x, y, n >= 2):
 * crossing = greatest u with F(u) <= f. */
static void collect_pwl_down(const double *x, const double *y, size_t n, double w, double f,
                             double u_p, double span, events *e)
{
    size_t i = upper_bound(y, n, f), seg, q;
    double cross;
    if (i == 0) { /* f < y[0]: in the left extension, or never */
        const double s = seg_slope(x, y, 0);
        seg = 0;
        cross = s > 0.0 ? x[0] - (y[0] - f) / s : -INFINITY;
    } else if (i == n) { /* f >= y[n-1]: in the right extension, or F <= f everywhere */
        const double s = seg_slope(x, y, n - 2);
        seg = n - 2;
        cross = s > 0.0 ? x[n - 1] + (f - y[n - 1]) / s : INFINITY;
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
        const double d = u_p - cross;
        if (!(d < span)) return;
        push(e->a, &e->na, d, w * seg_slope(x, y, seg));
    }
    for (q = seg; q >= 1; --q) { /* interior breakpoints below */
        const double d = u_p - x[q];
        if (!(d < span)) break;
        push(e->a, &e->na, d, w * seg_slope(x, y, q - 1));
        push(e->a, &e->na, d, -w * seg_slope(x, y, q));
    }
}

static void collect_pwl(const pihyst_model *m, int up, double u_p, double span, events *e)
{
    const pihyst_pwl *p = &m->pwl;
    size_t k;
    e->na = 0;
    e->nb = 0;
    e->s0 = 0.0;
    for (k = 0; k < m->n_ops; ++k) {
        const double w = m->weights[k];
        if (w == 0.0) continue;
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

/* Collect and sort the events of direction `up` from u_p over the whole distance to
 * the voltage limit, and keep them (with the slope at u_p) for the following samples. */
static void rebuild(pihyst_compensator *c, int up, double u_p)
{
    const size_t K = c->model->n_ops;
    const double span = up ? c->u_max - u_p : u_p - c->u_min;
    double *merged;
    events e;
    e.a = c->scratch + 2 * K;
    e.b = e.a + 2 * c->events_cap;
    merged = e.b + 2 * K;
    switch (c->model->family) {
    case PIHYST_CLASSICAL:
        collect_classical(c->model, up, u_p, span, &e);
        break;
    case PIHYST_MULTISLOPE:
        collect_multislope(c->model, c->scratch, up, u_p, span, &e);
        break;
    default:
        collect_pwl(c->model, up, u_p, span, &e);
        break;
    }
    sort_events(e.a, e.na);
    sort_events(e.b, e.nb);
    if (e.nb) {
        merge_events(e.a, e.na, e.b, e.nb, merged);
        c->events = merged;
    } else {
        c->events = e.a;
    }
    c->dir = up ? 1 : -1;
    c->base = u_p;
    c->next = 0;
    c->count = e.na + e.nb;
    c->slope[0] = e.s0;
    c->slope[1] = 0.0;
}

/* The distance d in (0, span] at which |y - y_p| first reaches target (returns 1), or
 * d = span if the window ends first (returns 0). */
static int solve(pihyst_compensator *c, int up, double u_p, double span, double target,
                 double *d)
{
    if (c->dir != (up ? 1 : -1)) rebuild(c, up, u_p);
    return walk(c->events, c->count, &c->next, c->slope,
                up ? u_p - c->base : c->base - u_p, target, span, d);
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
    /* kinks 2K | first list (K + 2 points) pairs | second list K pairs |
     * merged list (2K + 2 points) pairs */
    return 10 * m->n_ops + 8 * pwl_points(m);
}

static void forget_events(pihyst_compensator *c)
{
    c->dir = 0;
    c->events = c->scratch;
    c->count = c->next = 0;
    c->slope[0] = c->slope[1] = c->base = 0.0;
}

static void apply(pihyst_compensator *c, double u)
{
    c->y_last = pihyst_model_step(c->model, u);
    c->u_last = u;
}

pihyst_status pihyst_compensator_init(pihyst_compensator *c, pihyst_model *m, double u_min,
                                      double u_max, double max_step, double u_initial,
                                      double *scratch, size_t scratch_len)
{
    size_t k, K;
    double scale, *rise, *fall;
    if (!c || !m || !scratch) return PIHYST_ENULL;
    K = m->n_ops;
    for (k = 0; k < K; ++k)
        if (m->weights[k] < 0.0) return PIHYST_ENEGATIVE_WEIGHT;
    if (isnan(u_min)) u_min = m->u_min;
    if (isnan(u_max)) u_max = m->u_max;
    if (!(m->u_min <= u_min && u_min < u_max && u_max <= m->u_max)) return PIHYST_ELIMITS;
    if (!(max_step > 0.0)) return PIHYST_ELIMITS; /* also NaN */
    if (scratch_len < pihyst_compensator_scratch_len(m)) return PIHYST_ESIZE;
    if (!isfinite(u_initial)) return PIHYST_ENONFINITE;
    if (!(u_min <= u_initial && u_initial <= u_max)) return PIHYST_ELIMITS;

    c->model = m;
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
    scale = fabs(m->offset);
    pihyst_model_envelopes(m, u_min, rise, fall);
    for (k = 0; k < K; ++k) {
        double v = fabs(rise[k]) > fabs(fall[k]) ? fabs(rise[k]) : fabs(fall[k]);
        scratch[4 * K + k] = v;
    }
    pihyst_model_envelopes(m, u_max, rise, fall);
    for (k = 0; k < K; ++k) {
        double v = scratch[4 * K + k];
        if (fabs(rise[k]) > v) v = fabs(rise[k]);
        if (fabs(fall[k]) > v) v = fabs(fall[k]);
        scale += m->weights[k] * v;
    }
    c->tol = 4.0 * ((double)K + 2.0) * DBL_EPSILON * scale;

    if (m->family == PIHYST_MULTISLOPE) {
        /* rising kink: a u + c1 = b u + c2;  falling kink: b u = a u + c3 */
        const double ba = m->shape.b - m->shape.a;
        for (k = 0; k < K; ++k) {
            scratch[k] = (m->coef[k] - m->coef[K + k]) / ba;
            scratch[K + k] = m->coef[2 * K + k] / ba;
        }
    }
    forget_events(c);
    apply(c, u_initial);
    return PIHYST_OK;
}

pihyst_status pihyst_compensator_reset(pihyst_compensator *c, const double *state,
                                       double u_last)
{
    size_t k;
    if (!c) return PIHYST_ENULL;
    if (!isfinite(u_last)) return PIHYST_ENONFINITE;
    if (!(c->u_min <= u_last && u_last <= c->u_max)) return PIHYST_ELIMITS;
    if (state)
        for (k = 0; k < c->model->n_ops; ++k)
            if (!isfinite(state[k])) return PIHYST_ENONFINITE;
    pihyst_model_reset(c->model, state);
    forget_events(c);
    apply(c, u_last);
    return PIHYST_OK;
}

/* Window end above u_p: min(u_max, u_p + max_step), with u_p + max_step lowered by
 * ulps until (end - u_p) <= max_step holds in floating point. */
static double window_hi(const pihyst_compensator *c, double u_p, int *slew)
{
    double h = u_p + c->max_step;
    while (h - u_p > c->max_step) h = nextafter(h, u_p);
    *slew = h < c->u_max;
    return *slew ? h : c->u_max;
}

static double window_lo(const pihyst_compensator *c, double u_p, int *slew)
{
    double l = u_p - c->max_step;
    while (u_p - l > c->max_step) l = nextafter(l, u_p);
    *slew = l > c->u_min;
    return *slew ? l : c->u_min;
}

double pihyst_compensator_step(pihyst_compensator *c, double y_desired, unsigned *flags)
{
    const double u_p = c->u_last, y_p = c->y_last;
    unsigned fl = 0;
    if (isnan(y_desired)) {
        fl = PIHYST_COMP_NAN;
    } else if (!(fabs(y_desired - y_p) <= c->tol)) {
        const int up = y_desired > y_p;
        int slew;
        double u, d;
        const double end = up ? window_hi(c, u_p, &slew) : window_lo(c, u_p, &slew);
        const double span = up ? end - u_p : u_p - end;
        const double target = up ? y_desired - y_p : y_p - y_desired;
        if (span > 0.0 && solve(c, up, u_p, span, target, &d)) {
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
            fl = slew ? PIHYST_COMP_SLEW : (up ? PIHYST_COMP_SAT_HIGH : PIHYST_COMP_SAT_LOW);
        }
        if (u != u_p) apply(c, u);
        /* at the window's end the model may meet y_d after all, to rounding: not a miss */
        if (fl && fabs(y_desired - c->y_last) <= c->tol) fl = 0;
    }
    if (flags) *flags = fl;
    return c->u_last;
}

size_t pihyst_compensator_run(pihyst_compensator *c, const double *y_desired, double *u,
                              double *y, unsigned char *flags, size_t n)
{
    size_t t, count = 0;
    for (t = 0; t < n; ++t) {
        unsigned fl;
        u[t] = pihyst_compensator_step(c, y_desired[t], &fl);
        if (y) y[t] = c->y_last;
        if (flags) flags[t] = (unsigned char)fl;
        count += fl != 0;
    }
    return count;
}
