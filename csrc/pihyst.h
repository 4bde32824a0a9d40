/* pihyst.h - Prandtl-Ishlinskii hysteresis core.
 *
 * C99, no malloc, no globals, no I/O, reentrant. Every array is owned by the
 * caller; its length is written next to it. A firmware project copies the csrc .c files
 * and this header as they are.
 *
 * Model (DESIGN.md sections 2-3): a bank of K generalized play operators
 *
 *     f_k[t] = max(R_k(u[t]), min(F_k(u[t]), f_k[t-1]))          (1)
 *     y[t]   = offset + sum_k w_k f_k[t]                           (2)
 *
 * with rising envelope R_k <= falling envelope F_k, both continuous and
 * non-decreasing on the input range [u_min, u_max]. Families:
 *
 *   PIHYST_CLASSICAL   R_k(u) = u - r_k,  F_k(u) = u + r_k
 *   PIHYST_MULTISLOPE  R_k(u) = max(a(u - r_k), b u - r_k - (b - 1)U)
 *                      F_k(u) = min(b u, a u + (1 - a)U - (1 - a h) r_k)
 *   PIHYST_PWL         R_k, F_k polylines given by breakpoints; beyond its first
 *                      and last breakpoint a polyline continues with the slope of
 *                      its first and last segment (a single point is a constant).
 *
 * The operator state (f_k[t-1], K doubles) is explicit: read it, set it, save it;
 * a signal run in chunks gives exactly the output of one run.
 */
#ifndef PIHYST_H
#define PIHYST_H
#include <stddef.h>
#ifdef __cplusplus
extern "C" {
#endif

#define PIHYST_VERSION_MAJOR 0
#define PIHYST_VERSION_MINOR 1
#define PIHYST_ABI_VERSION 1 /* bump on any struct layout or signature change */

typedef enum {
    PIHYST_OK = 0,
    PIHYST_ENULL = -1,       /* a required pointer is NULL */
    PIHYST_ESIZE = -2,       /* n_ops == 0, or a polyline without points */
    PIHYST_ENONFINITE = -3,  /* NaN or infinity in a parameter or state */
    PIHYST_ETHRESHOLD = -4,  /* thresholds negative or not strictly increasing */
    PIHYST_ESHAPE = -5,      /* multislope shape invalid: needs 0 < a < b, 0 <= h <= 1, U > 0 */
    PIHYST_EMULTISLOPE_R = -6, /* multislope threshold above (1 - a)U / (1 - a h) */
    PIHYST_EPOLYLINE = -7,   /* breakpoints not strictly increasing, or envelope decreasing */
    PIHYST_EENVELOPE = -8,   /* R > F somewhere on the input range */
    PIHYST_ERANGE = -9       /* input range empty (u_min >= u_max) */
} pihyst_status;

typedef enum {
    PIHYST_CLASSICAL = 0,
    PIHYST_MULTISLOPE = 1,
    PIHYST_PWL = 2
} pihyst_family;

/** Multislope operator shape (paper: U = 150 V, a = 0.8, b = 1.2, h = 0.5). */
typedef struct {
    double U; /**< top of the input range the operator is built for, > 0 */
    double a; /**< slope near the turning points, 0 < a < b */
    double b; /**< slope far from them, b > a */
    double h; /**< hold ratio: after a maximum U the output holds for h*r volts, 0 <= h <= 1 */
} pihyst_shape;

/** Piecewise-linear envelopes of K operators, concatenated.
 *  Operator k's rising envelope has the points
 *      (rise_x[i], rise_y[i]),  rise_start[k] <= i < rise_start[k+1],
 *  with rise_x strictly increasing and rise_y non-decreasing; likewise the
 *  falling envelope. rise_start and fall_start have K + 1 entries, start at 0. */
typedef struct {
    const size_t *rise_start; /**< K + 1 offsets (caller-owned) */
    const double *rise_x;     /**< rise_start[K] breakpoints (caller-owned) */
    const double *rise_y;     /**< rise_start[K] values (caller-owned) */
    const size_t *fall_start; /**< K + 1 offsets (caller-owned) */
    const double *fall_x;     /**< fall_start[K] breakpoints (caller-owned) */
    const double *fall_y;     /**< fall_start[K] values (caller-owned) */
} pihyst_pwl;

/** Length of the coefficient scratch a model needs, in doubles. */
#define PIHYST_COEF_LEN(n_ops) (4 * (n_ops))

/** A PI-type model. Transparent so firmware can allocate it statically;
 *  fill it with pihyst_model_init, never by hand. */
typedef struct {
    pihyst_family family;
    size_t n_ops;              /**< K, number of operators */
    const double *thresholds;  /**< K thresholds r_k (classical, multislope; NULL for PWL) */
    const double *weights;     /**< K weights w_k, any sign (caller-owned) */
    double offset;             /**< constant added to the output */
    double u_min, u_max;       /**< input range on which R <= F is checked */
    pihyst_shape shape;        /**< multislope only */
    pihyst_pwl pwl;            /**< PWL only */
    double *coef;              /**< PIHYST_COEF_LEN(K) doubles, caller-owned, written by init:
                                    per operator the envelope constants (see pihyst_model.c) */
    double *state;             /**< K doubles f_k[t-1], caller-owned, mutated by step/run */
} pihyst_model;

/** Validate the parameters once and wire up the model.
 *  @param[out] m          model to fill
 *  @param[in]  family     operator family
 *  @param[in]  n_ops      K >= 1
 *  @param[in]  thresholds K values, 0 <= r_0 < r_1 < ...; ignored (may be NULL) for PWL
 *  @param[in]  weights    K finite values
 *  @param[in]  offset     finite output offset
 *  @param[in]  u_min,u_max input range, u_min < u_max
 *  @param[in]  shape      multislope shape (ignored, may be NULL, for other families)
 *  @param[in]  pwl        envelopes (ignored, may be NULL, for other families)
 *  @param[out] coef       PIHYST_COEF_LEN(K) doubles of scratch
 *  @param[in,out] state   K doubles; set to initial_state (or zeros if it is NULL)
 *  @param[in]  initial_state K finite values or NULL
 *  All pointed-to arrays must outlive the model. */
pihyst_status pihyst_model_init(pihyst_model *m, pihyst_family family, size_t n_ops,
                                const double *thresholds, const double *weights, double offset,
                                double u_min, double u_max, const pihyst_shape *shape,
                                const pihyst_pwl *pwl, double *coef, double *state,
                                const double *initial_state);

/** Set the operator state to initial_state (K values), or to zeros if it is NULL. */
void pihyst_model_reset(pihyst_model *m, const double *initial_state);

/** One sample: update the state by (1) and return y by (2). */
double pihyst_model_step(pihyst_model *m, double u);

/** A block: y[t] for u[t], t < n, by (1)-(2). u and y may not overlap. */
void pihyst_model_run(pihyst_model *m, const double *u, double *y, size_t n);

/** Operator matrix: phi[t*K + k] = f_k[t] (row-major, n x K), advancing the state. */
void pihyst_model_operators(pihyst_model *m, const double *u, double *phi, size_t n);

/** Accumulate the normal equations without storing phi, advancing the state:
 *      gram[j*K + k] += sum_t f_j[t] f_k[t]     (K x K, row-major)
 *      rhs[k]        += sum_t f_k[t] d[t]       (K)
 *      sums[k]       += sum_t f_k[t]            (K, may be NULL; for a fitted offset)
 *  Call it on consecutive chunks to build the matrices of a long record. */
void pihyst_model_gram(pihyst_model *m, const double *u, const double *d, size_t n,
                       double *gram, double *rhs, double *sums);

/** Envelopes of every operator at one input: rise[k] = R_k(u), fall[k] = F_k(u). */
void pihyst_model_envelopes(const pihyst_model *m, double u, double *rise, double *fall);

/** Human-readable text of a status code (static storage). */
const char *pihyst_status_text(pihyst_status status);

#ifdef __cplusplus
}
#endif
#endif /* PIHYST_H */
