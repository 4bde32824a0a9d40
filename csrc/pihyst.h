/* pihyst.h - Prandtl-Ishlinskii hysteresis core.
 *
 * C99, no malloc, no globals, no I/O, reentrant. Every array is owned by the
 * caller; its length is written next to it. A firmware project copies the .c and .h
 * files of csrc (this header, pihyst_internal.h, pihyst_*.c) as they are.
 *
 * Model (docs/theory/operators.md-3): a bank of K generalized play operators
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
#define PIHYST_ABI_VERSION 2 /* bump on any struct layout or signature change */

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
    PIHYST_ERANGE = -9,      /* input range empty (u_min >= u_max) */
    PIHYST_ENEGATIVE_WEIGHT = -10, /* compensator: a weight is negative (model not monotone) */
    PIHYST_ELIMITS = -11     /* compensator: voltage limits, slew limit or voltage invalid */
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

/* ======================================================================
 * Inverse / compensator (docs/theory/inverse.md): desired displacement -> voltage.
 * ======================================================================
 *
 * For a fixed operator state f (the state after the last voltage u_p was applied,
 * so R_k(u_p) <= f_k <= F_k(u_p)), the model output as a function of the next
 * voltage u is
 *
 *     y(u) = offset + sum_k w_k max(R_k(u), min(F_k(u), f_k))                (3)
 *          = offset + sum_k w_k max(f_k, R_k(u))     for u >= u_p            (3a)
 *          = offset + sum_k w_k min(f_k, F_k(u))     for u <= u_p            (3b)
 *
 * which is continuous, piecewise linear and, when every w_k >= 0, non-decreasing.
 * Each sample solves y(u) = y_d exactly: the breakpoints of (3a) or (3b) beyond u_p
 * (where an envelope crosses its f_k, and the envelopes' own kinks) are walked in
 * order of distance from u_p, accumulating value and slope, and the linear equation
 * of the segment that brackets y_d is solved. No iteration, no tolerance. Where y is
 * flat the voltage nearest u_p is chosen (hold, don't jump). The breakpoints are kept
 * while the direction of motion holds, so a tracking step costs O(1 + the breakpoints
 * it passes) plus one model step. At a reversal the breakpoints of reachable states
 * come in operator order: a classical compensator reads them from the state as it
 * walks (O(1 + breakpoints passed), no list), a multislope one lists crossings and
 * kinks in one vectorized pass and checks the order (O(K)); anything out of order is
 * sorted. (A compensator reset to another's (state, u_last) therefore continues it to
 * rounding, not bit for bit.) The compensator works on a cache-line-aligned copy of
 * the operator state, so the alignment of the caller's array does not matter: during
 * a call the model points at that copy, between calls at the caller's array, current.
 *
 * Limits: every output lies in [u_min, u_max] and, with a slew limit, within
 * max_step of the previous output (checked in floating point: |u[t] - u[t-1]| <=
 * max_step exactly). A desired value out of reach saturates at the bound and is
 * flagged; NaN holds the last voltage and is flagged. Differences |y_d - y| below
 * the rounding error of the model output (4 (K + 2) eps times the output scale)
 * count as equal, so rounding noise cannot push the voltage across a flat region.
 */

/** Per-sample flags of pihyst_compensator_step / _run (bits, 0 = desired reached). */
enum {
    PIHYST_COMP_SAT_LOW = 1,  /**< out of reach below: voltage at u_min */
    PIHYST_COMP_SAT_HIGH = 2, /**< out of reach above: voltage at u_max */
    PIHYST_COMP_NAN = 4,      /**< desired value NaN: last voltage held */
    PIHYST_COMP_SLEW = 8      /**< not reached within the slew limit: voltage moved by max_step */
};

/** Scratch a compensator needs at most, in doubles, for K = n_ops operators and a model
 *  with n_points polyline breakpoints in total (rising plus falling; 0 for classical and
 *  multislope). pihyst_compensator_scratch_len gives the exact figure for a model. */
#define PIHYST_COMPENSATOR_SCRATCH_LEN(n_ops, n_points) (10 * (n_ops) + 8 * (n_points) + 12)

/** Compensator: an exact inverse of a model with w >= 0, with limits.
 *  Transparent for static allocation; fill it with pihyst_compensator_init. The model's
 *  state must change only through the compensator (step, run, reset) while it is in
 *  use: the compensator keeps the breakpoints and a working copy of the state between
 *  samples. */
typedef struct {
    pihyst_model *model; /**< initialised model (caller-owned); its state is advanced
                              with every voltage the compensator chooses */
    double u_min, u_max; /**< voltage limits, inside the model's input range */
    double max_step;     /**< slew limit: max |u[t] - u[t-1]|, > 0; INFINITY = none */
    double u_last;       /**< last voltage (applied to the model state) */
    double y_last;       /**< model output at u_last with the current state */
    double tol;          /**< equality band of |y_d - y_last| (rounding of the output) */
    double *scratch;     /**< caller-owned, scratch_len doubles: kinks, event lists, the
                              aligned working state */
    size_t scratch_len;  /**< >= pihyst_compensator_scratch_len(model) */
    size_t events_cap;   /**< capacity of the crossing list (events, sentinel excluded) */
    /* breakpoints kept between samples while the direction holds (internal): */
    int dir;             /**< +1 up, -1 down, 0 none (collect at the next sample) */
    unsigned in_order;   /**< bits 0, 1: rising, falling kinks sorted by distance (multislope);
                              bit 2: classical state 1-Lipschitz in r (crossings in order) */
    double base;         /**< voltage the event distances are measured from */
    size_t next[2];      /**< first crossing and first kink not yet passed */
    double slope[2];     /**< slope |dy/du| just beyond u_last in direction dir (hi + lo) */
    double ahead;        /**< classical, in order: distance of crossing next[0] from base */
    double *work;        /**< the state worked on: the model's array if it is aligned to a
                              cache line, else an aligned copy in scratch */
} pihyst_compensator;

/** Scratch length (doubles) that pihyst_compensator_init needs for this model. */
size_t pihyst_compensator_scratch_len(const pihyst_model *m);

/** Validate and wire up a compensator, then apply u_initial to the model's current
 *  state (a no-op for a state reached by running the model up to u_initial).
 *  @param[out] c          compensator to fill
 *  @param[in,out] m       initialised model; must outlive c; weights must be >= 0
 *  @param[in]  u_min,u_max voltage limits with m->u_min <= u_min < u_max <= m->u_max;
 *                         NAN selects the model's bound
 *  @param[in]  max_step   slew limit (> 0, volts per sample), INFINITY for none
 *  @param[in]  u_initial  voltage before the first sample, in [u_min, u_max]
 *  @param[out] scratch    scratch_len doubles of caller-owned scratch
 *  @return PIHYST_OK, PIHYST_ENULL, PIHYST_ENEGATIVE_WEIGHT, PIHYST_ELIMITS,
 *          PIHYST_ENONFINITE (u_initial NaN or infinite), PIHYST_ESIZE (scratch short) */
pihyst_status pihyst_compensator_init(pihyst_compensator *c, pihyst_model *m, double u_min,
                                      double u_max, double max_step, double u_initial,
                                      double *scratch, size_t scratch_len);

/** Set the model state to state (K values; NULL = zeros) and the last voltage to
 *  u_last, applying u_last to the state (f_k <- clamp(f_k, R_k(u_last), F_k(u_last))).
 *  On error (state not finite, u_last NaN or outside the limits) nothing changes. */
pihyst_status pihyst_compensator_reset(pihyst_compensator *c, const double *state,
                                       double u_last);

/** One sample: the voltage for the desired output y_desired (any double, NaN and
 *  infinities included), applied to the model. *flags (may be NULL) receives the
 *  PIHYST_COMP_* bits; c->y_last then holds the model's output for that voltage. */
double pihyst_compensator_step(pihyst_compensator *c, double y_desired, unsigned *flags);

/** A block of n samples: u[t] (and y[t], the model output, if y != NULL; flags[t] if
 *  flags != NULL) for y_desired[t]. Equal to n calls of step. Arrays may not overlap.
 *  @return the number of samples with a flag set (not reached, or NaN). */
size_t pihyst_compensator_run(pihyst_compensator *c, const double *y_desired, double *u,
                              double *y, unsigned char *flags, size_t n);

#ifdef __cplusplus
}
#endif
#endif /* PIHYST_H */
