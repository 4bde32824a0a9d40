/* fuzz_common.h - shared by the libFuzzer harnesses (not part of the core).
 *
 * Each harness body is compiled twice, like the tests: as it is (double API) and with
 * FUZZ_F32 (every public name mapped to its _f32 twin, real = float), and the fuzz entry
 * point runs both on every input. The input bytes are read as a little program:
 * parameters, then operations. Numbers come mostly from 16 bits scaled into a range
 * (so the fuzzer reaches valid models quickly), now and then as NaN, infinities, huge
 * values or raw 8-byte doubles (so it also reaches the validation). */
#ifndef PIHYST_FUZZ_COMMON_H
#define PIHYST_FUZZ_COMMON_H
#include "pihyst.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef FUZZ_F32
#include "pihyst_f32_names.h"
typedef float real;
#define FUZZ_EPS FLT_EPSILON
#define FUZZ_TINY FLT_MIN /* below it a product underflows to a subnormal or 0 */
#define FUZZ_BIG 1e11 /* parameters and inputs below this cannot overflow a float output */
#define FUZZ_NAME(name) name##_f32
#else
typedef double real;
#define FUZZ_EPS DBL_EPSILON
#define FUZZ_TINY DBL_MIN
#define FUZZ_BIG 1e100
#define FUZZ_NAME(name) name##_f64
#endif

/* An invariant: on violation, say which and abort (libFuzzer saves the input). */
#define REQUIRE(cond)                                                                    \
    do {                                                                                 \
        if (!(cond)) {                                                                   \
            fprintf(stderr, "invariant violated (%s): %s at %s:%d\n",                    \
                    sizeof(real) == 4 ? "f32" : "f64", #cond, __FILE__, __LINE__);       \
            abort();                                                                     \
        }                                                                                \
    } while (0)

typedef struct {
    const uint8_t *p;
    size_t n;
} reader;

static inline unsigned take_u8(reader *r)
{
    if (r->n == 0) return 0;
    --r->n;
    return *r->p++;
}

static inline unsigned take_u16(reader *r)
{
    const unsigned hi = take_u8(r);
    return hi << 8 | take_u8(r);
}

/* A number in [lo, hi] mostly; 1 in 16 a special value or raw bytes. */
static inline double take_num(reader *r, double lo, double hi)
{
    const unsigned sel = take_u8(r);
    double raw = 0.0;
    if (sel < 240) return lo + (hi - lo) * (double)take_u16(r) / 65535.0;
    switch (sel) {
    case 240: return NAN;
    case 241: return INFINITY;
    case 242: return -INFINITY;
    case 243: return 0.0;
    case 244: return -0.0;
    case 245: return lo;
    case 246: return hi;
    case 247: return 1e300;
    case 248: return -1e300;
    case 249: return 5e-324;
    default:
        if (r->n >= sizeof raw) {
            memcpy(&raw, r->p, sizeof raw);
            r->p += sizeof raw;
            r->n -= sizeof raw;
        }
        return raw;
    }
}

/* every code pihyst.h defines, and a text for it */
static inline int known_status(pihyst_status s)
{
    return s <= PIHYST_OK && s >= PIHYST_ESCRATCH &&
           strcmp(pihyst_status_text(s), "unknown status") != 0;
}

/* bitwise equality of two arrays (NaN == NaN, -0 != +0) */
static inline int same_bits(const real *x, const real *y, size_t n)
{
    return n == 0 || memcmp(x, y, n * sizeof *x) == 0;
}

#define FUZZ_KMAX 12
#define FUZZ_PMAX 6 /* polyline points per envelope */

/* Model parameters read from the input, with the arrays they point to. */
typedef struct {
    pihyst_params p;
    real r[FUZZ_KMAX], w[FUZZ_KMAX], init[FUZZ_KMAX];
    size_t rs[FUZZ_KMAX + 1], fs[FUZZ_KMAX + 1];
    real rx[FUZZ_KMAX * FUZZ_PMAX], ry[FUZZ_KMAX * FUZZ_PMAX];
    real fx[FUZZ_KMAX * FUZZ_PMAX], fy[FUZZ_KMAX * FUZZ_PMAX];
    double big;      /* largest |parameter| or polyline slope */
    double max_slope; /* largest envelope slope, for error bounds */
} fuzz_params;

static inline void track(fuzz_params *f, double v)
{
    if (isnan(f->big)) return; /* NaN stays NaN: a later number must not clear it */
    if (!(fabs(v) <= f->big)) f->big = fabs(v); /* NaN makes it NaN: not sane */
}

/* Read a model. With `monotone`, weights are >= 0 unless the input insists (raw). */
static inline void take_params(reader *r, fuzz_params *f, int monotone)
{
    size_t k, i, K;
    double x, y;
    memset(f, 0, sizeof *f);
    f->p.family = (pihyst_family)(take_u8(r) % (monotone ? 3 : 4)); /* 3: unknown */
    K = 1 + take_u8(r) % FUZZ_KMAX;
    f->p.n_ops = take_u8(r) == 255 ? 0 : K;
    f->p.u_min = (real)take_num(r, -200.0, 100.0);
    f->p.u_max = f->p.u_min + (real)take_num(r, 0.0, 300.0);
    f->p.offset = (real)take_num(r, -10.0, 10.0);
    f->p.shape.U = (real)take_num(r, 0.0, 300.0);
    f->p.shape.a = (real)take_num(r, 0.0, 1.2);
    f->p.shape.b = f->p.shape.a + (real)take_num(r, 0.0, 1.0);
    f->p.shape.h = (real)take_num(r, 0.0, 1.0);
    track(f, f->p.u_min);
    track(f, f->p.u_max);
    track(f, f->p.offset);
    if (f->p.family == PIHYST_MULTISLOPE) {
        track(f, f->p.shape.U);
        track(f, f->p.shape.a);
        track(f, f->p.shape.b);
    }
    f->max_slope = f->p.family == PIHYST_MULTISLOPE ? fabs((double)f->p.shape.b) : 1.0;
    for (k = 0; k < K; ++k) {
        f->r[k] = (k ? f->r[k - 1] : (real)0.0) + (real)take_num(r, 0.0, k ? 30.0 : 10.0);
        f->w[k] = (real)take_num(r, monotone ? 0.0 : -1.0, 1.0);
        track(f, f->r[k]);
        track(f, f->w[k]);
    }
    f->p.thresholds = take_u8(r) == 255 ? NULL : f->r;
    f->p.weights = f->w;
    if (take_u8(r) & 1) {
        for (k = 0; k < K; ++k) f->init[k] = (real)take_num(r, -300.0, 300.0);
        f->p.initial_state = f->init;
    }
    if (f->p.family == PIHYST_PWL) {
        /* per operator a rising polyline and a falling one: the same abscissae shifted
         * left (so F >= R where the values are alike), values with a gap above */
        f->rs[0] = f->fs[0] = 0;
        for (k = 0; k < K; ++k) {
            const size_t n = 1 + take_u8(r) % FUZZ_PMAX, at = f->rs[k];
            const double shift = take_num(r, 0.0, 40.0), gap = take_num(r, 0.0, 20.0);
            x = take_num(r, -250.0, 250.0);
            y = take_num(r, -100.0, 100.0);
            for (i = 0; i < n; ++i) {
                const double dx = take_num(r, 0.0, 100.0), dy = take_num(r, 0.0, 60.0);
                if (i) {
                    x += dx;
                    y += dy;
                    if (dx > 0.0 && dy / dx > f->max_slope) f->max_slope = dy / dx;
                    if (dx > 0.0) track(f, dy / dx);
                }
                f->rx[at + i] = (real)x;
                f->ry[at + i] = (real)y;
                f->fx[at + i] = (real)(x - shift);
                f->fy[at + i] = (real)(y + gap);
                track(f, x);
                track(f, y + gap);
            }
            f->rs[k + 1] = f->fs[k + 1] = at + n;
        }
        /* single-precision rounding can make a steep segment steeper */
        if (f->max_slope > 1.0) f->max_slope *= 2.0;
        f->p.pwl.rise_start = f->rs;
        f->p.pwl.rise_x = f->rx;
        f->p.pwl.rise_y = f->ry;
        f->p.pwl.fall_start = f->fs;
        f->p.pwl.fall_x = f->fx;
        f->p.pwl.fall_y = f->fy;
    }
}

/* What pihyst_model_init promises of parameters it accepts, checked independently. */
static inline void require_valid(const fuzz_params *f)
{
    const pihyst_params *p = &f->p;
    size_t k, i;
    REQUIRE(p->n_ops >= 1 && p->weights != NULL);
    REQUIRE(p->family == PIHYST_CLASSICAL || p->family == PIHYST_MULTISLOPE ||
            p->family == PIHYST_PWL);
    REQUIRE(isfinite(p->offset) && isfinite(p->u_min) && isfinite(p->u_max));
    REQUIRE(p->u_min < p->u_max);
    for (k = 0; k < p->n_ops; ++k) {
        REQUIRE(isfinite(p->weights[k]));
        if (p->initial_state) REQUIRE(isfinite(p->initial_state[k]));
        if (p->family != PIHYST_PWL) {
            REQUIRE(p->thresholds != NULL);
            REQUIRE(isfinite(p->thresholds[k]) && p->thresholds[k] >= 0);
            if (k) REQUIRE(p->thresholds[k] > p->thresholds[k - 1]);
        } else {
            for (i = f->rs[k] + 1; i < f->rs[k + 1]; ++i)
                REQUIRE(f->rx[i] > f->rx[i - 1] && f->ry[i] >= f->ry[i - 1]);
            for (i = f->fs[k] + 1; i < f->fs[k + 1]; ++i)
                REQUIRE(f->fx[i] > f->fx[i - 1] && f->fy[i] >= f->fy[i - 1]);
        }
    }
    if (p->family == PIHYST_MULTISLOPE) {
        const pihyst_shape *s = &p->shape;
        REQUIRE(isfinite(s->U) && isfinite(s->a) && isfinite(s->b) && isfinite(s->h));
        REQUIRE(s->U > 0 && s->a > 0 && s->b > s->a && s->h >= 0 && s->h <= 1);
    }
}

/* parameters small enough that no output can overflow */
static inline int sane(const fuzz_params *f)
{
    return f->big <= FUZZ_BIG;
}

#endif /* PIHYST_FUZZ_COMMON_H */
