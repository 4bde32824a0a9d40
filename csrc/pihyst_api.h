/* pihyst_api.h - the types and functions of one precision; part of pihyst.h.
 *
 * Included twice by pihyst.h (include pihyst.h, not this file): once with
 * PIHYST_REAL = double and PIHYST_NAME(x) = x, once with PIHYST_REAL = float and
 * PIHYST_NAME(x) = x_f32. So pihyst_model_init_f32 takes a pihyst_model_f32 and a
 * pihyst_params_f32 whose numbers are floats, and so on. No include guard on purpose.
 */
#if !defined(PIHYST_REAL) || !defined(PIHYST_NAME)
#error "include pihyst.h, not pihyst_api.h"
#endif

/** Multislope operator shape (paper: U = 150 V, a = 0.8, b = 1.2, h = 0.5). */
typedef struct {
    PIHYST_REAL U; /**< top of the input range the operator is built for, > 0 */
    PIHYST_REAL a; /**< slope near the turning points, 0 < a < b */
    PIHYST_REAL b; /**< slope far from them, b > a */
    PIHYST_REAL h; /**< hold ratio: after a maximum U the output holds for h*r volts,
                        0 <= h <= 1 */
} PIHYST_NAME(pihyst_shape);

/** Piecewise-linear envelopes of K operators, concatenated.
 *  Operator k's rising envelope has the points
 *      (rise_x[i], rise_y[i]),  rise_start[k] <= i < rise_start[k+1],
 *  with rise_x strictly increasing and rise_y non-decreasing; likewise the
 *  falling envelope. rise_start and fall_start have K + 1 entries, start at 0. */
typedef struct {
    const size_t *rise_start;      /**< K + 1 offsets (caller-owned) */
    const PIHYST_REAL *rise_x;     /**< rise_start[K] breakpoints (caller-owned) */
    const PIHYST_REAL *rise_y;     /**< rise_start[K] values (caller-owned) */
    const size_t *fall_start;      /**< K + 1 offsets (caller-owned) */
    const PIHYST_REAL *fall_x;     /**< fall_start[K] breakpoints (caller-owned) */
    const PIHYST_REAL *fall_y;     /**< fall_start[K] values (caller-owned) */
} PIHYST_NAME(pihyst_pwl);

/** Parameters of a model, for pihyst_model_init. Fill it with a designated initializer;
 *  members left out are 0 / NULL:
 *
 *      static const double r[4] = {0, 20, 30, 40}, w[4] = {0.196, 0.026, 0.046, 0.028};
 *      static const pihyst_params params = {
 *          .family = PIHYST_MULTISLOPE, .n_ops = 4, .thresholds = r, .weights = w,
 *          .u_min = 0.0, .u_max = 150.0,
 *          .shape = {.U = 150.0, .a = 0.8, .b = 1.2, .h = 0.5},
 *      };
 *
 *  Every array must outlive the model (the model points into them). */
typedef struct {
    pihyst_family family;
    size_t n_ops;                     /**< K >= 1 */
    const PIHYST_REAL *thresholds;    /**< K values, 0 <= r_0 < r_1 < ...; classical and
                                           multislope (ignored, may be NULL, for PWL) */
    const PIHYST_REAL *weights;       /**< K finite values, any sign */
    PIHYST_REAL offset;               /**< finite output offset */
    PIHYST_REAL u_min, u_max;         /**< input range, u_min < u_max: R <= F is checked on it */
    PIHYST_NAME(pihyst_shape) shape;  /**< multislope only */
    PIHYST_NAME(pihyst_pwl) pwl;      /**< PWL only */
    const PIHYST_REAL *initial_state; /**< K finite values, or NULL for zeros */
} PIHYST_NAME(pihyst_params);

/** A PI-type model. Transparent so firmware can allocate it statically;
 *  fill it with pihyst_model_init, never by hand. */
typedef struct {
    pihyst_family family;
    size_t n_ops;                    /**< K, number of operators */
    const PIHYST_REAL *thresholds;   /**< K thresholds r_k (classical, multislope; NULL for PWL) */
    const PIHYST_REAL *weights;      /**< K weights w_k, any sign (caller-owned) */
    PIHYST_REAL offset;              /**< constant added to the output */
    PIHYST_REAL u_min, u_max;        /**< input range on which R <= F is checked */
    PIHYST_NAME(pihyst_shape) shape; /**< multislope only */
    PIHYST_NAME(pihyst_pwl) pwl;     /**< PWL only */
    PIHYST_REAL *coef;               /**< PIHYST_COEF_LEN(K) values, caller-owned, written by
                                          init: per operator the envelope constants (see
                                          pihyst_model.c) */
    PIHYST_REAL *state;              /**< K values f_k[t-1], caller-owned, mutated by
                                          step/run; fastest on a 64-byte boundary */
} PIHYST_NAME(pihyst_model);

/** Validate the parameters once and wire up the model.
 *  @param[out] m      model to fill
 *  @param[in]  params the parameters (the struct itself need not outlive the model, the
 *                     arrays it points to must)
 *  @param[out] coef   PIHYST_COEF_LEN(K) values of scratch
 *  @param[out] state  K values; set to params->initial_state (zeros if it is NULL)
 *  @return PIHYST_OK or the first problem found: PIHYST_ENULL, PIHYST_EFAMILY,
 *          PIHYST_ESIZE, PIHYST_ENONFINITE, PIHYST_ERANGE, PIHYST_ETHRESHOLD,
 *          PIHYST_ESHAPE, PIHYST_EMULTISLOPE_R, PIHYST_EPOLYLINE, PIHYST_EENVELOPE */
pihyst_status PIHYST_NAME(pihyst_model_init)(PIHYST_NAME(pihyst_model) *m,
                                             const PIHYST_NAME(pihyst_params) *params,
                                             PIHYST_REAL *coef, PIHYST_REAL *state);

/** Set the operator state to initial_state (K values), or to zeros if it is NULL. */
void PIHYST_NAME(pihyst_model_reset)(PIHYST_NAME(pihyst_model) *m,
                                     const PIHYST_REAL *initial_state);

/** One sample: update the state by (1) and return y by (2). */
PIHYST_REAL PIHYST_NAME(pihyst_model_step)(PIHYST_NAME(pihyst_model) *m, PIHYST_REAL u);

/** A block: y[t] for u[t], t < n, by (1)-(2). u and y may not overlap. */
void PIHYST_NAME(pihyst_model_run)(PIHYST_NAME(pihyst_model) *m, const PIHYST_REAL *u,
                                   PIHYST_REAL *y, size_t n);

/** Operator matrix: phi[t*K + k] = f_k[t] (row-major, n x K), advancing the state. */
void PIHYST_NAME(pihyst_model_operators)(PIHYST_NAME(pihyst_model) *m, const PIHYST_REAL *u,
                                         PIHYST_REAL *phi, size_t n);

/** Accumulate the normal equations without storing phi, advancing the state:
 *      gram[j*K + k] += sum_t f_j[t] f_k[t]     (K x K, row-major)
 *      rhs[k]        += sum_t f_k[t] d[t]       (K)
 *      sums[k]       += sum_t f_k[t]            (K, may be NULL; for a fitted offset)
 *  Call it on consecutive chunks to build the matrices of a long record. */
void PIHYST_NAME(pihyst_model_gram)(PIHYST_NAME(pihyst_model) *m, const PIHYST_REAL *u,
                                    const PIHYST_REAL *d, size_t n, PIHYST_REAL *gram,
                                    PIHYST_REAL *rhs, PIHYST_REAL *sums);

/** Envelopes of every operator at one input: rise[k] = R_k(u), fall[k] = F_k(u). */
void PIHYST_NAME(pihyst_model_envelopes)(const PIHYST_NAME(pihyst_model) *m, PIHYST_REAL u,
                                         PIHYST_REAL *rise, PIHYST_REAL *fall);

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
 * rounding, not bit for bit.)
 *
 * State and reentrancy: the compensator never writes the model struct. It steps its own
 * copy of the model (c->work_model), whose state is the model's array if that lies on a
 * PIHYST_STATE_ALIGN-byte boundary (or PIHYST_STATE_ALIGN is 0), else an aligned copy in
 * the scratch that is copied to the model's array before each call returns. Either way
 * the model's state array is current between calls.
 *
 * Limits: every output lies in [u_min, u_max] and, with a slew limit, within
 * max_step of the previous output (checked in floating point: |u[t] - u[t-1]| <=
 * max_step exactly). A desired value out of reach saturates at the bound and is
 * flagged; NaN holds the last voltage and is flagged. Differences |y_d - y| below
 * the rounding error of the model output (4 (K + 2) eps times the output scale, eps of
 * the precision) count as equal, so rounding noise cannot push the voltage across a
 * flat region.
 */

/** Compensator: an exact inverse of a model with w >= 0, with limits.
 *  Transparent for static allocation; fill it with pihyst_compensator_init. The model's
 *  state must change only through the compensator (step, run, reset) while it is in
 *  use: the compensator keeps the breakpoints between samples. */
typedef struct {
    PIHYST_NAME(pihyst_model) *model; /**< initialised model (caller-owned); its state array
                                           is advanced with every voltage chosen */
    PIHYST_NAME(pihyst_model) work_model; /**< the copy that is stepped (internal) */
    PIHYST_REAL u_min, u_max; /**< voltage limits, inside the model's input range */
    PIHYST_REAL max_step;     /**< slew limit: max |u[t] - u[t-1]|, > 0; INFINITY = none */
    PIHYST_REAL u_last;       /**< last voltage (applied to the model state) */
    PIHYST_REAL y_last;       /**< model output at u_last with the current state */
    PIHYST_REAL tol;          /**< equality band of |y_d - y_last| (rounding of the output) */
    PIHYST_REAL *scratch;     /**< caller-owned, scratch_len values: kinks, event lists (or
                                   the ramp constants of a KP model), the aligned working
                                   state */
    size_t scratch_len;       /**< >= pihyst_compensator_scratch_len(model) */
    size_t events_cap;        /**< capacity of the crossing list (events, sentinel excluded) */
    /* breakpoints kept between samples while the direction holds (internal): */
    int dir;                  /**< +1 up, -1 down, 0 none (collect at the next sample) */
    unsigned in_order;        /**< PIHYST_ORDER_* bits */
    PIHYST_REAL base;         /**< voltage the event distances are measured from */
    size_t next[2];           /**< first crossing and first kink not yet passed */
    PIHYST_REAL slope[2];     /**< slope |dy/du| just beyond u_last in direction dir
                                   (hi + lo) */
    PIHYST_REAL ahead;        /**< classical, in order: distance of crossing next[0] from
                                   base */
} PIHYST_NAME(pihyst_compensator);

/** Scratch length (values) that pihyst_compensator_init needs for this model. */
size_t PIHYST_NAME(pihyst_compensator_scratch_len)(const PIHYST_NAME(pihyst_model) *m);

/** Validate and wire up a compensator, then apply u_initial to the model's current
 *  state (a no-op for a state reached by running the model up to u_initial).
 *  @param[out] c          compensator to fill
 *  @param[in,out] m       initialised model; must outlive c; weights must be >= 0
 *  @param[in]  u_min,u_max voltage limits with m->u_min <= u_min < u_max <= m->u_max;
 *                         NAN selects the model's bound
 *  @param[in]  max_step   slew limit (> 0, volts per sample), INFINITY for none
 *  @param[in]  u_initial  voltage before the first sample, in [u_min, u_max]
 *  @param[out] scratch    scratch_len values of caller-owned scratch
 *  @return PIHYST_OK, PIHYST_ENULL, PIHYST_ENEGATIVE_WEIGHT, PIHYST_ELIMITS,
 *          PIHYST_ENONFINITE (u_initial NaN or infinite), PIHYST_ESCRATCH (scratch short) */
pihyst_status PIHYST_NAME(pihyst_compensator_init)(PIHYST_NAME(pihyst_compensator) *c,
                                                   PIHYST_NAME(pihyst_model) *m,
                                                   PIHYST_REAL u_min, PIHYST_REAL u_max,
                                                   PIHYST_REAL max_step, PIHYST_REAL u_initial,
                                                   PIHYST_REAL *scratch, size_t scratch_len);

/** Set the model state to state (K values; NULL = zeros) and the last voltage to
 *  u_last, applying u_last to the state (f_k <- clamp(f_k, R_k(u_last), F_k(u_last))).
 *  On error (state not finite, u_last NaN or outside the limits) nothing changes. */
pihyst_status PIHYST_NAME(pihyst_compensator_reset)(PIHYST_NAME(pihyst_compensator) *c,
                                                    const PIHYST_REAL *state,
                                                    PIHYST_REAL u_last);

/** One sample: the voltage for the desired output y_desired (any value, NaN and
 *  infinities included), applied to the model. *flags (may be NULL) receives the
 *  PIHYST_COMP_* bits; c->y_last then holds the model's output for that voltage (for a
 *  model of saturated ramps, KP, a running sum within tol / 2 of pihyst_model_step's; the
 *  state is pihyst_model_step's bit for bit either way: docs/c-core.md). */
PIHYST_REAL PIHYST_NAME(pihyst_compensator_step)(PIHYST_NAME(pihyst_compensator) *c,
                                                 PIHYST_REAL y_desired, pihyst_flags *flags);

/** A block of n samples: u[t] (and y[t], the model output, if y != NULL; flags[t] if
 *  flags != NULL) for y_desired[t]. Equal to n calls of step. Arrays may not overlap.
 *  @return the number of samples with a flag set (not reached, or NaN). */
size_t PIHYST_NAME(pihyst_compensator_run)(PIHYST_NAME(pihyst_compensator) *c,
                                           const PIHYST_REAL *y_desired, PIHYST_REAL *u,
                                           PIHYST_REAL *y, pihyst_flags *flags, size_t n);

/* ======================================================================
 * Banks: many independent models or compensators per sample vector
 * ======================================================================
 *
 * Deformable mirrors and multi-axis stages drive N actuators per tick, each with its own
 * model (parameters, state) and compensator. A bank call steps channel i with its own
 * object on the i-th value of a sample vector, in one call per tick; the result is
 * bit for bit that of N separate step calls (csrc/pihyst_bank.c). The channels are given
 * as an array of N pointers, so they may be allocated anywhere (one static array of
 * structs: fill the pointer array once). Channels must be distinct objects.
 */

/** y[i] = pihyst_model_step(models[i], u[i]) for i < n. u and y may not overlap. */
void PIHYST_NAME(pihyst_bank_step)(PIHYST_NAME(pihyst_model) *const *models, size_t n,
                                   const PIHYST_REAL *u, PIHYST_REAL *y);

/** u[i] = pihyst_compensator_step(comps[i], y_desired[i], &flags[i]) for i < n;
 *  y[i] (if y != NULL) = comps[i]->y_last, flags (may be NULL) the PIHYST_COMP_* bits.
 *  @return the number of channels with a flag set. */
size_t PIHYST_NAME(pihyst_bank_compensate)(PIHYST_NAME(pihyst_compensator) *const *comps,
                                           size_t n, const PIHYST_REAL *y_desired,
                                           PIHYST_REAL *u, PIHYST_REAL *y,
                                           pihyst_flags *flags);

/* ======================================================================
 * Compensator banks, structure-of-arrays: the fast bank (csrc/pihyst_bank_soa.c)
 * ======================================================================
 *
 * The same channels as pihyst_bank_compensate (N initialised compensators, any
 * families), run from a work array laid out channel-interleaved, L = 64 bytes of reals
 * per group. Classical channels with r_0 = 0 and w_0 > 0 (and w_0 >= sum w / 1024) step
 * the model's exact inverse, itself a classical PI model, vectorized across channels:
 * K branch-free clamps and a dot product per channel. Where that voltage would leave the
 * limits or the slew limit, or y_d is NaN or within tol of the last output, the channel
 * does what its compensator does (the compensator itself takes the ticks that leave the
 * limits, from the state the bank holds for it); every other channel runs its
 * compensator every tick. So every voltage lies inside its channel's limits and slew
 * limit, the flags are the compensator's, and the voltages and outputs are those of the
 * separate compensators to rounding (not bit for bit: the inverse reaches y_d by other
 * operations; docs/c-core.md gives the measured agreement). The output of a fast tick is
 * y_d itself.
 *
 * State: between pihyst_compbank_init and pihyst_compbank_sync the fast channels' state
 * is in the work array, and their compensators (u_last, y_last, model state) are stale.
 * pihyst_compbank_sync brings them up to date (the bank may go on afterwards). A
 * compensator stepped or reset outside the bank needs pihyst_compbank_init again.
 */

/** A structure-of-arrays compensator bank. Transparent for static allocation; fill it
 *  with pihyst_compbank_init. */
typedef struct {
    PIHYST_NAME(pihyst_compensator) *const *comps; /**< N channels (caller-owned) */
    size_t n;              /**< N */
    size_t n_ops;          /**< operators per group: the largest fast K, rounded up to 4 */
    size_t n_fast;         /**< channels on the fast path */
    PIHYST_REAL *groups;   /**< the groups, in the caller's work array (64-byte aligned) */
    unsigned parity;       /**< which play-state buffer holds the state (internal) */
} PIHYST_NAME(pihyst_compbank);

/** Work length (values) that pihyst_compbank_init needs for these channels. */
size_t PIHYST_NAME(pihyst_compbank_work_len)(PIHYST_NAME(pihyst_compensator) *const *comps,
                                             size_t n);

/** Lay out N initialised, distinct compensators (their current state and last voltage)
 *  in the work array. comps and the compensators must outlive the bank.
 *  @return PIHYST_OK, PIHYST_ENULL, PIHYST_ESCRATCH (work shorter than
 *          pihyst_compbank_work_len) */
pihyst_status PIHYST_NAME(pihyst_compbank_init)(PIHYST_NAME(pihyst_compbank) *b,
                                                PIHYST_NAME(pihyst_compensator) *const *comps,
                                                size_t n, PIHYST_REAL *work, size_t work_len);

/** One tick: u[i] for y_desired[i] (any values), y[i] the model output (y_d on a fast
 *  tick; may be NULL), flags[i] the PIHYST_COMP_* bits (may be NULL). Arrays may not
 *  overlap. @return the number of channels with a flag set. */
size_t PIHYST_NAME(pihyst_compbank_compensate)(PIHYST_NAME(pihyst_compbank) *b,
                                               const PIHYST_REAL *y_desired, PIHYST_REAL *u,
                                               PIHYST_REAL *y, pihyst_flags *flags);

/** Write the fast channels' state back to their compensators (model state, u_last,
 *  y_last), by pihyst_compensator_reset at the last voltage. */
void PIHYST_NAME(pihyst_compbank_sync)(PIHYST_NAME(pihyst_compbank) *b);

/* ======================================================================
 * Model banks, structure-of-arrays (csrc/pihyst_bank_soa_model.c)
 * ======================================================================
 *
 * The same channels as pihyst_bank_step (N initialised models, any families), run from
 * a work array laid out channel-interleaved: classical channels with K <= 16 are stepped
 * 64 bytes of reals at a time with the operations of the single model's K <= 16 kernel,
 * in the same order, so every output is bit for bit pihyst_model_step's; other channels
 * (and all of them in a build without compiler vector extensions) are stepped by
 * pihyst_model_step in the same call. Between pihyst_modelbank_init and
 * pihyst_modelbank_sync the fast channels' states are in the work array (their models'
 * state arrays are stale); a model stepped or reset outside the bank needs init again.
 */

/** A structure-of-arrays model bank. Fill it with pihyst_modelbank_init. */
typedef struct {
    PIHYST_NAME(pihyst_model) *const *models; /**< N channels (caller-owned) */
    size_t n;              /**< N */
    size_t n_fast;         /**< channels stepped in the groups */
    PIHYST_REAL *groups;   /**< the groups, in the caller's work array (64-byte aligned) */
} PIHYST_NAME(pihyst_modelbank);

/** Work length (values) that pihyst_modelbank_init needs for n channels. */
size_t PIHYST_NAME(pihyst_modelbank_work_len)(PIHYST_NAME(pihyst_model) *const *models,
                                              size_t n);

/** Lay out N initialised, distinct models (their current states) in the work array.
 *  @return PIHYST_OK, PIHYST_ENULL, PIHYST_ESCRATCH (work too short) */
pihyst_status PIHYST_NAME(pihyst_modelbank_init)(PIHYST_NAME(pihyst_modelbank) *b,
                                                 PIHYST_NAME(pihyst_model) *const *models,
                                                 size_t n, PIHYST_REAL *work, size_t work_len);

/** One tick: y[i] = the output of channel i for u[i] (as pihyst_model_step). */
void PIHYST_NAME(pihyst_modelbank_step)(PIHYST_NAME(pihyst_modelbank) *b,
                                        const PIHYST_REAL *u, PIHYST_REAL *y);

/** Copy the fast channels' states back to their models' state arrays. */
void PIHYST_NAME(pihyst_modelbank_sync)(PIHYST_NAME(pihyst_modelbank) *b);
