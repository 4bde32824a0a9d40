/* pihyst_boucwen.c - the Bouc-Wen model and its exact compensator (pihyst_boucwen.h,
 * docs/theory/bouc-wen.md). Written once for `real`; pihyst_boucwen_f32.c builds the
 * single-precision twin. Every expression keeps the operation order of the Python model
 * (src/pihyst/model/_boucwen.py, src/pihyst/inverse/_boucwen.py), its twin: without FMA
 * contraction the two agree bit for bit. */
#include "pihyst_boucwen.h"

#include "pihyst_internal.h"

#ifdef PIHYST_BUILD_F32
#define pihyst_bw_params pihyst_bw_params_f32
#define pihyst_bw_model pihyst_bw_model_f32
#define pihyst_bw_init pihyst_bw_init_f32
#define pihyst_bw_rest_z pihyst_bw_rest_z_f32
#define pihyst_bw_reset pihyst_bw_reset_f32
#define pihyst_bw_advance pihyst_bw_advance_f32
#define pihyst_bw_output pihyst_bw_output_f32
#define pihyst_bw_step pihyst_bw_step_f32
#define pihyst_bw_run pihyst_bw_run_f32
#define pihyst_bw_compensator pihyst_bw_compensator_f32
#define pihyst_bw_compensator_init pihyst_bw_compensator_init_f32
#define pihyst_bw_compensator_reset pihyst_bw_compensator_reset_f32
#define pihyst_bw_compensator_step pihyst_bw_compensator_step_f32
#define pihyst_bw_compensator_run pihyst_bw_compensator_run_f32
#define R_POW powf
#define R_CEIL ceilf
#define R_COPYSIGN copysignf
/* initial |z| may exceed z_max by the rounding of z_max and of the stored state */
#define BW_Z_SLACK (RC(32.0) * FLT_EPSILON)
#else
#define R_POW pow
#define R_CEIL ceil
#define R_COPYSIGN copysign
#define BW_Z_SLACK 1e-9
#endif

/* 8-point Gauss-Legendre nodes and weights on [-1, 1] (numpy.polynomial.legendre.leggauss(8)
 * to 17 digits; the Python model holds the same literals) */
static const real gl_nodes[8] = {
    RC(-0.9602898564975362), RC(-0.7966664774136267), RC(-0.525532409916329),
    RC(-0.18343464249564978), RC(0.18343464249564978), RC(0.525532409916329),
    RC(0.7966664774136267), RC(0.9602898564975362)};
static const real gl_weights[8] = {
    RC(0.10122853629037706), RC(0.22238103445337443), RC(0.3137066458778869),
    RC(0.36268378337836166), RC(0.36268378337836166), RC(0.3137066458778869),
    RC(0.22238103445337443), RC(0.10122853629037706)};

static int is_finite(real x) { return isfinite(x) != 0; }

/* g_s(z) = 1 - |z|^n (s beta sign(z) + gamma)                                      (B2)
 * (pow(x, 1) is x exactly, so the n = 1 shortcut changes no bit) */
static real slope(const pihyst_bw_model *m, real z, real s)
{
    const real az = R_FABS(z);
    const real p = m->n == RC(1.0) ? az : R_POW(az, m->n);
    return RC(1.0) - p * (s * m->beta * R_COPYSIGN(RC(1.0), z) + m->gamma);
}

/* one classical Runge-Kutta substep: z + k (g1 + 2 g2 + 2 g3 + g4) / 6 */
static real rk4(const pihyst_bw_model *m, real z, real k, real s)
{
    const real g1 = slope(m, z, s);
    const real g2 = slope(m, z + RC(0.5) * k * g1, s);
    const real g3 = slope(m, z + RC(0.5) * k * g2, s);
    const real g4 = slope(m, z + k * g3, s);
    return z + k * (g1 + RC(2.0) * g2 + RC(2.0) * g3 + g4) / RC(6.0);
}

/* the input change that brings z to 0: dx_c = integral from z to 0 of dzeta / g_s(zeta),
 * by Gauss-Legendre (g_s is smooth on one side of 0) */
static real to_zero(const pihyst_bw_model *m, real z, real s)
{
    const real half = RC(-0.5) * z;
    real sum = RC(0.0);
    int i;
    for (i = 0; i < 8; ++i) sum += gl_weights[i] / slope(m, z + half * (RC(1.0) + gl_nodes[i]), s);
    return half * sum;
}

real pihyst_bw_advance(const pihyst_bw_model *m, real z, real dx)
{
    real steps, k, s;
    long i, count;
    if (dx == RC(0.0) || dx != dx) return z;
    if (dx > RC(1.0)) dx = RC(1.0);  /* the input range's width: no longer step exists */
    if (dx < RC(-1.0)) dx = RC(-1.0);
    /* m = max(1, ceil(|dx| / H)), the 1e-9 absorbing the rounding of |dx| / H */
    steps = R_CEIL(R_FABS(dx) / m->h - RC(1e-9));
    count = steps < RC(1.0) ? 1 : (long)steps;
    s = dx > RC(0.0) ? RC(1.0) : RC(-1.0);
    k = dx / (real)count;
    for (i = 0; i < count; ++i) {
        real z_new = rk4(m, z, k, s);
        if (z * s < RC(0.0) && RC(0.0) < z_new * s) { /* across the kink at z = 0 */
            const real dx_c = to_zero(m, z, s);
            if (R_FABS(dx_c) < R_FABS(k)) z_new = rk4(m, RC(0.0), k - dx_c, s);
        }
        z = z_new;
    }
    return z;
}

static real normalized(const pihyst_bw_model *m, real u) { return (u - m->u_min) / (m->u_max - m->u_min); }

/* y = offset + c_1 x + c_2 x^2 + a z                                                 (B1) */
real pihyst_bw_output(const pihyst_bw_model *m, real u, real z)
{
    const real x = normalized(m, u);
    return m->offset + m->linear * x + m->quadratic * x * x + m->hysteretic * z;
}

real pihyst_bw_rest_z(const pihyst_bw_model *m)
{
    return pihyst_bw_advance(m, pihyst_bw_advance(m, RC(0.0), RC(1.0)), RC(-1.0));
}

static pihyst_status state_ok(const pihyst_bw_model *m, real u, real z)
{
    if (!is_finite(u) || !is_finite(z)) return PIHYST_ENONFINITE;
    if (!(m->u_min <= u && u <= m->u_max)) return PIHYST_ERANGE;
    if (R_FABS(z) > m->z_max * (RC(1.0) + BW_Z_SLACK)) return PIHYST_ERANGE;
    return PIHYST_OK;
}

pihyst_status pihyst_bw_init(pihyst_bw_model *m, const pihyst_bw_params *p)
{
    pihyst_bw_model w;
    pihyst_status status;
    real spread, h;
    if (!m || !p) return PIHYST_ENULL;
    if (!is_finite(p->beta) || !is_finite(p->gamma) || !is_finite(p->n) || !is_finite(p->hysteretic) ||
        !is_finite(p->linear) || !is_finite(p->quadratic) || !is_finite(p->offset) ||
        !is_finite(p->u_min) || !is_finite(p->u_max))
        return PIHYST_ENONFINITE;
    spread = p->beta + R_FABS(p->gamma);
    if (!(p->beta > R_FABS(p->gamma)) || !(spread <= RC(PIHYST_BW_MAX_SHAPE)) ||
        !(p->beta + p->gamma >= RC(PIHYST_BW_MIN_SPREAD)) ||
        !(RC(1.0) <= p->n && p->n <= RC(PIHYST_BW_MAX_EXPONENT)))
        return PIHYST_ESHAPE;
    if (!(p->u_min < p->u_max)) return PIHYST_ERANGE;
    w.beta = p->beta;
    w.gamma = p->gamma;
    w.n = p->n;
    w.hysteretic = p->hysteretic;
    w.linear = p->linear;
    w.quadratic = p->quadratic;
    w.offset = p->offset;
    w.u_min = p->u_min;
    w.u_max = p->u_max;
    w.span = p->u_max - p->u_min;
    if (!is_finite(w.span)) return PIHYST_ERANGE;
    /* H = min(1/256, 1/(32 (beta + |gamma|))) */
    h = RC(1.0) / (RC(32.0) * spread);
    w.h = RC(1.0) / RC(256.0) < h ? RC(1.0) / RC(256.0) : h;
    /* z_max = (beta + gamma)^(-1/n) */
    w.z_max = R_POW(p->beta + p->gamma, RC(-1.0) / p->n);
    status = state_ok(&w, p->initial_u, p->initial_z);
    if (status != PIHYST_OK) return status;
    w.u = p->initial_u;
    w.z = p->initial_z;
    *m = w;
    return PIHYST_OK;
}

pihyst_status pihyst_bw_reset(pihyst_bw_model *m, real u, real z)
{
    const pihyst_status status = state_ok(m, u, z);
    if (status != PIHYST_OK) return status;
    m->u = u;
    m->z = z;
    return PIHYST_OK;
}

real pihyst_bw_step(pihyst_bw_model *m, real u)
{
    if (u != u) u = m->u;
    if (u < m->u_min) u = m->u_min;
    if (u > m->u_max) u = m->u_max;
    m->z = pihyst_bw_advance(m, m->z, normalized(m, u) - normalized(m, m->u));
    m->u = u;
    return pihyst_bw_output(m, u, m->z);
}

void pihyst_bw_run(pihyst_bw_model *m, const real *u, real *y, size_t n)
{
    size_t t;
    for (t = 0; t < n; ++t) y[t] = pihyst_bw_step(m, u[t]);
}

/* ---------------------------------------------------------------- compensator */

/* lower bound of dy/dx: min(c_1, c_1 + 2 c_2) + min(a, 0) 2 beta / (beta + gamma) */
static real min_slope(const pihyst_bw_model *m)
{
    const real d = RC(2.0) * m->beta / (m->beta + m->gamma);
    const real c = m->linear + RC(2.0) * m->quadratic;
    return (m->linear < c ? m->linear : c) + (m->hysteretic < RC(0.0) ? m->hysteretic : RC(0.0)) * d;
}

/* apply the voltage u to the model's state */
static void apply(pihyst_bw_compensator *c, real u)
{
    pihyst_bw_model *m = c->model;
    m->z = pihyst_bw_advance(m, m->z, normalized(m, u) - normalized(m, m->u));
    m->u = u;
    c->y_last = pihyst_bw_output(m, u, m->z);
}

pihyst_status pihyst_bw_compensator_init(pihyst_bw_compensator *c, pihyst_bw_model *m,
                                         real u_min, real u_max, real max_step, real u_initial)
{
    if (!c || !m) return PIHYST_ENULL;
    if (!(min_slope(m) >= RC(0.0))) return PIHYST_ENEGATIVE_WEIGHT;
    if (u_min != u_min) u_min = m->u_min;
    if (u_max != u_max) u_max = m->u_max;
    if (!(m->u_min <= u_min && u_min < u_max && u_max <= m->u_max)) return PIHYST_ELIMITS;
    if (!(max_step > RC(0.0))) return PIHYST_ELIMITS;
    if (!is_finite(u_initial)) return PIHYST_ENONFINITE;
    if (!(u_min <= u_initial && u_initial <= u_max)) return PIHYST_ELIMITS;
    c->model = m;
    c->u_min = u_min;
    c->u_max = u_max;
    c->max_step = max_step;
    c->scale = R_FABS(m->offset) + R_FABS(m->linear) + R_FABS(m->quadratic) +
               R_FABS(m->hysteretic) * m->z_max;
    apply(c, u_initial);
    return PIHYST_OK;
}

pihyst_status pihyst_bw_compensator_reset(pihyst_bw_compensator *c, real u, real z, real u_last)
{
    pihyst_status status = state_ok(c->model, u, z);
    if (status != PIHYST_OK) return status;
    if (!is_finite(u_last)) return PIHYST_ENONFINITE;
    if (!(c->u_min <= u_last && u_last <= c->u_max)) return PIHYST_ELIMITS;
    c->model->u = u;
    c->model->z = z;
    apply(c, u_last);
    return PIHYST_OK;
}

/* Y(u) from the state (u_p, z_p) = (m->u, m->z); *z_out receives Z(u) */
static real output_after(const pihyst_bw_model *m, real u, real *z_out)
{
    *z_out = pihyst_bw_advance(m, m->z, normalized(m, u) - normalized(m, m->u));
    return pihyst_bw_output(m, u, *z_out);
}

/* a Newton step from u (state z there, residual err): u - err / (dY/du); NaN where the
 * slope is not positive (the caller then bisects) */
static real newton(const pihyst_bw_model *m, real u, real z, real err, real s)
{
    const real x = normalized(m, u);
    const real dy = (m->linear + RC(2.0) * m->quadratic * x + m->hysteretic * slope(m, z, s)) /
                    m->span;
    return dy > RC(0.0) ? u - err / dy : (real)NAN;
}

static real larger(real a, real b) { return a > b ? a : b; }

/* Is y_d out of reach at the voltage limit? Asked when the slew window ends short of it
 * at `end`, where the model gives y_end with z_end, y_d lying beyond y_end in the
 * direction s. On the sweep from there to the limit z moves from z_end towards s z_max
 * (g_s > 0 below z_max), so Y(limit) = p(x) + a z(limit), p(x) = offset + c_1 x + c_2 x^2,
 * lies between p(x) + a z_end and p(x) + a s z_max; and Y moves by at least min_slope per
 * unit of x in direction s (a monotone model). A y_d clearly short of those bounds
 * (reachable) or past them (out of reach) is decided without the model's evaluation at
 * the limit, which takes up to 1/H substeps. "Clearly" is by 10^-3 of the output scale,
 * beyond the integration error of the model (below 1e-8 of |a| z_max,
 * docs/theory/bouc-wen.md) and its rounding in either precision; a y_d nearer a bound
 * evaluates Y(limit). */
static int beyond_limit(const pihyst_bw_compensator *c, real end, real y_end, real z_end,
                        real limit, real yd, real s)
{
    const pihyst_bw_model *m = c->model;
    const real margin = RC(1e-3) * c->scale;
    const real x_limit = normalized(m, limit);
    const real p = m->offset + m->linear * x_limit + m->quadratic * x_limit * x_limit;
    const real y_from = p + m->hysteretic * z_end, y_to = p + m->hysteretic * (s * m->z_max);
    const real reach = y_end + s * min_slope(m) * R_FABS(x_limit - normalized(m, end));
    real nearest = (y_from - y_to) * s < RC(0.0) ? y_from : y_to;
    const real farthest = (y_from - y_to) * s < RC(0.0) ? y_to : y_from;
    real z_limit;
    if ((reach - nearest) * s > RC(0.0)) nearest = reach;
    if ((yd - nearest) * s < -margin) return 0;
    if ((yd - farthest) * s > margin) return 1;
    return (output_after(m, limit, &z_limit) - yd) * s < RC(0.0);
}

#define BW_MAX_ITERATIONS 200
#define BW_NEWTON_FIRST 8 /* Newton steps from u_p before the reachable end must be evaluated */

/* Solve Y(u) = y_d from a = u_p (Y(a) before y_d) towards the reachable end in direction s:
 * Newton steps from u_p; the end is evaluated only when a step would reach or pass it (or
 * after BW_NEWTON_FIRST steps without a bracket). Out of reach there: the voltage stops at
 * the end, *flags says why. Else [a, b] brackets y_d while Newton or bisection steps shrink
 * it: Newton where its step stays in the bracket and is at most half the step before last,
 * else bisection. *z_out receives Z(u). */
static real solve(const pihyst_bw_compensator *c, real a, real end, real yd, real s,
                  real *z_out, pihyst_flags *flags)
{
    const pihyst_bw_model *m = c->model;
    const real tol = RC(4.0) * R_EPS * (R_FABS(yd) + c->scale);
    real u = newton(m, a, m->z, pihyst_bw_output(m, a, m->z) - yd, s);
    real dx = R_FABS(end - a), dx_old = dx, b = end, z_b = RC(0.0), z;
    int have_b = 0, i;
    *flags = 0;
    for (i = 0; i < BW_MAX_ITERATIONS; ++i) {
        real y, err, step;
        if (!have_b) {
            const real lo_e = a < end ? a : end, hi_e = a < end ? end : a;
            if (!(lo_e < u && u < hi_e) || i >= BW_NEWTON_FIRST) {
                real z_end;
                const real y_end = output_after(m, end, &z_end);
                if ((y_end - yd) * s <= RC(0.0)) { /* out of reach (or just reached) */
                    if (y_end != yd) {
                        const real limit = s > RC(0.0) ? c->u_max : c->u_min;
                        const pihyst_flags sat =
                            s > RC(0.0) ? PIHYST_COMP_SAT_HIGH : PIHYST_COMP_SAT_LOW;
                        /* cut short by the slew limit, and out of reach too if the voltage
                         * limit itself misses yd (out of reach does not depend on the slew) */
                        *flags = end == limit ? sat
                                 : beyond_limit(c, end, y_end, z_end, limit, yd, s)
                                     ? (pihyst_flags)(sat | PIHYST_COMP_SLEW)
                                     : PIHYST_COMP_SLEW;
                    }
                    *z_out = z_end;
                    return end;
                }
                b = end;
                z_b = z_end;
                have_b = 1;
            }
        }
        if (have_b) {
            const real lo = a < b ? a : b, hi = a < b ? b : a;
            if (!(lo < u && u < hi)) u = RC(0.5) * (a + b);
        }
        y = output_after(m, u, &z);
        err = y - yd;
        if (R_FABS(err) <= tol) {
            *z_out = z;
            return u;
        }
        if (err * s < RC(0.0)) {
            a = u;
        } else {
            b = u;
            z_b = z;
            have_b = 1;
        }
        if (!have_b) {
            u = newton(m, u, z, err, s);
            continue;
        }
        if (R_FABS(b - a) <= RC(2.0) * R_EPS * larger(larger(R_FABS(a), R_FABS(b)), R_MIN))
            break;
        step = newton(m, u, z, err, s);
        dx_old = dx;
        if ((a < b ? a < step && step < b : b < step && step < a) &&
            R_FABS(step - u) <= RC(0.5) * dx_old) {
            dx = R_FABS(step - u);
            u = step;
        } else {
            u = RC(0.5) * (a + b);
            dx = RC(0.5) * R_FABS(b - a);
        }
    }
    *z_out = z_b;
    return b;
}

real pihyst_bw_compensator_step(pihyst_bw_compensator *c, real yd, pihyst_flags *flags)
{
    pihyst_bw_model *m = c->model;
    const real up = m->u;
    real yp, s, end, u, z;
    pihyst_flags fl = 0;
    yp = pihyst_bw_output(m, up, m->z);
    c->y_last = yp;
    if (yd != yd) {
        if (flags) *flags = PIHYST_COMP_NAN;
        return up;
    }
    if (yd == yp) {
        if (flags) *flags = 0;
        return up;
    }
    s = yd > yp ? RC(1.0) : RC(-1.0);
    if (s > RC(0.0)) {
        end = up + c->max_step;
        if (!(end < c->u_max)) end = c->u_max;
    } else {
        end = up - c->max_step;
        if (!(end > c->u_min)) end = c->u_min;
    }
    while (R_FABS(end - up) > c->max_step) end = R_NEXTAFTER(end, up); /* rounding of u_p +- slew */
    u = solve(c, up, end, yd, s, &z, &fl);
    m->u = u;
    m->z = z;
    c->y_last = pihyst_bw_output(m, u, z);
    if (flags) *flags = fl;
    return u;
}

#ifndef PIHYST_BUILD_F32 /* one copy, shared by both precisions */
const char *pihyst_bw_status_text(pihyst_status status)
{
    switch (status) {
    case PIHYST_ESHAPE:
        return "Bouc-Wen shape must have beta > |gamma|, beta + |gamma| <= 1000, "
               "beta + gamma >= 1e-9 and 1 <= n <= 10";
    case PIHYST_ERANGE:
        return "Bouc-Wen input range must have u_min < u_max, and the state u inside it with "
               "|z| <= z_max";
    case PIHYST_ENEGATIVE_WEIGHT:
        return "compensation needs a monotone Bouc-Wen model: min(c_1, c_1 + 2 c_2) + "
               "min(a, 0) 2 beta / (beta + gamma) >= 0";
    default: return pihyst_status_text(status);
    }
}
#endif

size_t pihyst_bw_compensator_run(pihyst_bw_compensator *c, const real *y_desired, real *u,
                                 real *y, pihyst_flags *flags, size_t n)
{
    size_t t, flagged = 0;
    for (t = 0; t < n; ++t) {
        pihyst_flags fl;
        u[t] = pihyst_bw_compensator_step(c, y_desired[t], &fl);
        if (y) y[t] = c->y_last;
        if (flags) flags[t] = fl;
        flagged += fl != 0;
    }
    return flagged;
}
