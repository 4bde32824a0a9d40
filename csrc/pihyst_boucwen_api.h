/* pihyst_boucwen_api.h - the Bouc-Wen types and functions of one precision; part of
 * pihyst_boucwen.h (include that, not this file). Included twice, like pihyst_api.h: with
 * PIHYST_REAL = double and PIHYST_NAME(x) = x, then with float and x_f32. No include guard
 * on purpose. */
#if !defined(PIHYST_REAL) || !defined(PIHYST_NAME)
#error "include pihyst_boucwen.h, not pihyst_boucwen_api.h"
#endif

/** Parameters of a Bouc-Wen model, for pihyst_bw_init (the fields of the JSON model,
 *  docs/interfaces.md). Fill it with a designated initializer. */
typedef struct {
    PIHYST_REAL beta, gamma;   /**< shape on the normalized input: beta > |gamma|,
                                    beta + |gamma| <= PIHYST_BW_MAX_SHAPE,
                                    beta + gamma >= PIHYST_BW_MIN_SPREAD */
    PIHYST_REAL n;             /**< exponent, 1 <= n <= PIHYST_BW_MAX_EXPONENT */
    PIHYST_REAL hysteretic;    /**< a, weight of z (output units) */
    PIHYST_REAL linear;        /**< c_1 */
    PIHYST_REAL quadratic;     /**< c_2 */
    PIHYST_REAL offset;        /**< output at u_min with z = 0 */
    PIHYST_REAL u_min, u_max;  /**< input range, u_min < u_max */
    PIHYST_REAL initial_u;     /**< initial state (u, z): u in [u_min, u_max] ... */
    PIHYST_REAL initial_z;     /**< ... and |z| <= z_max (1 + slack) */
} PIHYST_NAME(pihyst_bw_params);

/** A Bouc-Wen model with its state (u, z). Transparent for static allocation; fill it
 *  with pihyst_bw_init, never by hand. Holds no pointers: it may be copied freely. */
typedef struct {
    PIHYST_REAL beta, gamma, n;
    PIHYST_REAL hysteretic, linear, quadratic, offset;
    PIHYST_REAL u_min, u_max;
    PIHYST_REAL span;   /**< u_max - u_min */
    PIHYST_REAL h;      /**< H = min(1/256, 1/(32 (beta + |gamma|))), the largest substep */
    PIHYST_REAL z_max;  /**< (beta + gamma)^(-1/n) */
    PIHYST_REAL u, z;   /**< state: the last input and the Bouc-Wen variable */
} PIHYST_NAME(pihyst_bw_model);

/** Validate the parameters and set the state to (initial_u, initial_z).
 *  @return PIHYST_OK, PIHYST_ENULL, PIHYST_ENONFINITE (a parameter NaN or infinite),
 *          PIHYST_ESHAPE (beta, gamma or n out of bounds), PIHYST_ERANGE (u_min >= u_max,
 *          or the initial state outside the range or beyond z_max) */
pihyst_status PIHYST_NAME(pihyst_bw_init)(PIHYST_NAME(pihyst_bw_model) *m,
                                          const PIHYST_NAME(pihyst_bw_params) *params);

/** z at rest at u_min after a full u_min -> u_max -> u_min cycle from z = 0 (the Python
 *  model's default initial state). */
PIHYST_REAL PIHYST_NAME(pihyst_bw_rest_z)(const PIHYST_NAME(pihyst_bw_model) *m);

/** Set the state to (u, z); PIHYST_ERANGE (nothing changes) if u is outside the range or
 *  |z| beyond z_max, PIHYST_ENONFINITE if either is NaN or infinite. */
pihyst_status PIHYST_NAME(pihyst_bw_reset)(PIHYST_NAME(pihyst_bw_model) *m, PIHYST_REAL u,
                                           PIHYST_REAL z);

/** z after the monotone input change dx (normalized, clamped to [-1, 1]; NaN: none) from
 *  z: the model's Runge-Kutta arithmetic (docs/theory/bouc-wen.md). The state is not
 *  changed. */
PIHYST_REAL PIHYST_NAME(pihyst_bw_advance)(const PIHYST_NAME(pihyst_bw_model) *m,
                                           PIHYST_REAL z, PIHYST_REAL dx);

/** y = offset + c_1 x + c_2 x^2 + a z at input u. */
PIHYST_REAL PIHYST_NAME(pihyst_bw_output)(const PIHYST_NAME(pihyst_bw_model) *m,
                                          PIHYST_REAL u, PIHYST_REAL z);

/** One sample: advance the state by the input u, return y. u is clamped to the input
 *  range; NaN holds the last input. */
PIHYST_REAL PIHYST_NAME(pihyst_bw_step)(PIHYST_NAME(pihyst_bw_model) *m, PIHYST_REAL u);

/** A block: y[t] for u[t], t < n (n calls of step). u and y may not overlap. */
void PIHYST_NAME(pihyst_bw_run)(PIHYST_NAME(pihyst_bw_model) *m, const PIHYST_REAL *u,
                                PIHYST_REAL *y, size_t n);

/** Exact compensator of a monotone Bouc-Wen model (pihyst_boucwen.h). Transparent for
 *  static allocation; fill it with pihyst_bw_compensator_init. */
typedef struct {
    PIHYST_NAME(pihyst_bw_model) *model; /**< caller-owned; its state is advanced by every
                                              voltage chosen */
    PIHYST_REAL u_min, u_max; /**< voltage limits, inside the model's input range */
    PIHYST_REAL max_step;     /**< slew limit: max |u[t] - u[t-1]|, > 0; INFINITY = none */
    PIHYST_REAL y_last;       /**< model output at the last voltage (model->u) */
    PIHYST_REAL scale;        /**< |offset| + |c_1| + |c_2| + |a| z_max: the output scale of
                                   the tolerance */
} PIHYST_NAME(pihyst_bw_compensator);

/** Validate and wire up; then apply u_initial to the model's current state.
 *  @param u_min,u_max voltage limits, m->u_min <= u_min < u_max <= m->u_max; NAN selects
 *                     the model's bound
 *  @param max_step    slew limit (> 0, volts per sample), INFINITY for none
 *  @param u_initial   voltage before the first sample, in [u_min, u_max]
 *  @return PIHYST_OK, PIHYST_ENULL, PIHYST_ENEGATIVE_WEIGHT (the model is not monotone:
 *          min(c_1, c_1 + 2 c_2) + min(a, 0) 2 beta / (beta + gamma) < 0),
 *          PIHYST_ELIMITS, PIHYST_ENONFINITE (u_initial NaN or infinite) */
pihyst_status PIHYST_NAME(pihyst_bw_compensator_init)(PIHYST_NAME(pihyst_bw_compensator) *c,
                                                      PIHYST_NAME(pihyst_bw_model) *m,
                                                      PIHYST_REAL u_min, PIHYST_REAL u_max,
                                                      PIHYST_REAL max_step,
                                                      PIHYST_REAL u_initial);

/** Set the model state to (u, z), then apply the voltage u_last (in the limits). On error
 *  nothing changes: PIHYST_ENONFINITE, PIHYST_ERANGE (state outside the model's range or
 *  beyond z_max), PIHYST_ELIMITS (u_last outside the limits). */
pihyst_status PIHYST_NAME(pihyst_bw_compensator_reset)(PIHYST_NAME(pihyst_bw_compensator) *c,
                                                       PIHYST_REAL u, PIHYST_REAL z,
                                                       PIHYST_REAL u_last);

/** One sample: the voltage for y_desired (any value, NaN and infinities included),
 *  applied to the model; *flags (may be NULL) receives the PIHYST_COMP_* bits and
 *  c->y_last the model's output. */
PIHYST_REAL PIHYST_NAME(pihyst_bw_compensator_step)(PIHYST_NAME(pihyst_bw_compensator) *c,
                                                    PIHYST_REAL y_desired,
                                                    pihyst_flags *flags);

/** A block of n samples of step: u[t], y[t] (may be NULL) and flags[t] (may be NULL).
 *  Arrays may not overlap. Returns the number of samples with a flag set. */
size_t PIHYST_NAME(pihyst_bw_compensator_run)(PIHYST_NAME(pihyst_bw_compensator) *c,
                                              const PIHYST_REAL *y_desired, PIHYST_REAL *u,
                                              PIHYST_REAL *y, pihyst_flags *flags, size_t n);
