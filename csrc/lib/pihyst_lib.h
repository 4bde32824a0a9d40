/* pihyst_lib.h - pihyst as a shared library with a plain C ABI, for tools that call C
 * from outside: LabVIEW (Call Library Function node), MATLAB (loadlibrary/calllib),
 * Simulink (C Caller block), Python (ctypes), ...
 *
 * Only scalars, arrays and an opaque handle cross the boundary: no struct is passed by
 * value, every array is the caller's, its length is the argument next to it, all
 * integers are int32_t and all numbers double. Every function returns a status
 * (0 = PIHYST_OK, negative = error; pihyst_lib_status_text says which) or, for the
 * constructors, the handle (NULL on error, the status in *status).
 *
 * A handle owns one model (its parameters, operator state and, once started, a
 * compensator); it is not thread-safe, different handles are independent. Build:
 * `make -C csrc shared` -> csrc/libpihyst.so (docs/export.md).
 */
#ifndef PIHYST_LIB_H
#define PIHYST_LIB_H
#include <stdint.h>
#ifdef __cplusplus
extern "C" {
#endif

#define PIHYST_LIB_ABI_VERSION 3 /* bump on any change of a signature below
                                    (2: Bouc-Wen models, pihyst_lib_create_boucwen;
                                     3: creep lags, pihyst_lib_set_creep and the flat
                                        file's creep line) */

/* On Windows the DLL exports exactly these functions: the library's build defines
 * PIHYST_LIB_BUILD (make -C csrc shared / dll); a user of the header needs nothing. */
#if defined(_WIN32) && defined(PIHYST_LIB_BUILD)
#define PIHYST_LIB_API __declspec(dllexport)
#else
#define PIHYST_LIB_API
#endif

typedef struct pihyst_lib_model pihyst_lib_model; /* opaque */

/* Library status codes beyond the core's (pihyst.h: 0 ... -13). */
#define PIHYST_LIB_ENOMEM (-100)       /* out of memory */
#define PIHYST_LIB_EFILE (-101)        /* the model file cannot be opened or read */
#define PIHYST_LIB_EFORMAT (-102)      /* the model file is not a pihyst flat model */
#define PIHYST_LIB_ENOCOMPENSATOR (-103) /* pihyst_lib_compensate before _compensator_start */
#define PIHYST_LIB_ELENGTH (-104)      /* a length argument is negative or does not match */
#define PIHYST_LIB_EINPUT (-105)       /* an input sample is NaN or outside the input range */
/* Invalid creep lags: PIHYST_LIB_ECREEP_BASE + the pihyst_creep_status of
 * pihyst_creep.h (-1 ... -6), so -111 ... -116: -114 a time constant not > 0, -115 gains
 * negative or summing to 1 or more, -116 dt negative or not finite, ... */
#define PIHYST_LIB_ECREEP_BASE (-110)

/** PIHYST_LIB_ABI_VERSION of the library actually loaded. */
PIHYST_LIB_API int32_t pihyst_lib_abi_version(void);

/** Text of a status code (static storage; never NULL). */
PIHYST_LIB_API const char *pihyst_lib_status_text(int32_t status);

/** A model from arrays. family: 0 classical, 1 multislope, 2 pwl; n_ops = K.
 *  thresholds: K values (classical, multislope; NULL for pwl). weights: K values.
 *  shape: U, a, b, h (multislope; NULL for the paper's 150, 0.8, 1.2, 0.5).
 *  pwl only (else NULL): rise_len/fall_len K point counts, rise_x/rise_y and
 *  fall_x/fall_y the points of every polyline concatenated (sum of the counts each).
 *  initial_state: K values or NULL for zeros. Copies everything it is given. */
PIHYST_LIB_API pihyst_lib_model *pihyst_lib_create(int32_t family, int32_t n_ops, const double *thresholds,
                                    const double *weights, double offset, double u_min,
                                    double u_max, const double *shape, const int32_t *rise_len,
                                    const double *rise_x, const double *rise_y,
                                    const int32_t *fall_len, const double *fall_x,
                                    const double *fall_y, const double *initial_state,
                                    int32_t *status);

/** A Bouc-Wen model (pihyst_boucwen.h) from its 11 parameters, in this order: beta,
 *  gamma, n, hysteretic, linear, quadratic, offset, u_min, u_max, initial u, initial z.
 *  Its state is (u, z): pihyst_lib_get_state and pihyst_lib_reset take n = 2, and
 *  pihyst_lib_n_operators gives 1. */
PIHYST_LIB_API pihyst_lib_model *pihyst_lib_create_boucwen(const double *params, int32_t *status);

/** A model from a flat model file (`pihyst export MODEL.json --flat -o FILE`); a
 *  Bouc-Wen model's file has family 3. A file with a creep line (`pihyst-flat 2`) gives a
 *  model with creep lags, as pihyst_lib_set_creep. */
PIHYST_LIB_API pihyst_lib_model *pihyst_lib_load(const char *path, int32_t *status);

/** Creep (pihyst_creep.h, docs/theory/creep.md): n first-order lags with time constants
 *  tau (> 0, seconds) and gains gain (>= 0, summing to less than 1) at the fixed sample
 *  interval dt (seconds, >= 0): every sample of pihyst_lib_predict and
 *  pihyst_lib_compensate is dt after the one before. n = 0 removes the lags (tau, gain
 *  may then be NULL). The lags start at rest at the present hysteresis output; the
 *  compensator, if one was started, is stopped. PI and Bouc-Wen models alike (the lags
 *  are driven by the hysteresis output). Invalid lags give PIHYST_LIB_ECREEP_BASE plus
 *  their pihyst_creep_status, and leave the handle as it was. */
PIHYST_LIB_API int32_t pihyst_lib_set_creep(pihyst_lib_model *h, const double *tau, const double *gain,
                             int32_t n, double dt);

/** Number of creep lags (0: none), or a negative status. */
PIHYST_LIB_API int32_t pihyst_lib_n_creep_lags(const pihyst_lib_model *h);

/** Copy the creep lag states z_i into z[0..n-1]; n must be pihyst_lib_n_creep_lags. */
PIHYST_LIB_API int32_t pihyst_lib_get_creep_state(const pihyst_lib_model *h, double *z, int32_t n);

/** Set the creep lag states to z (n values; NULL: at rest at the present hysteresis
 *  output). A running compensator keeps running, from these lag states. */
PIHYST_LIB_API int32_t pihyst_lib_set_creep_state(pihyst_lib_model *h, const double *z, int32_t n);

/** Free a handle (NULL is fine). */
PIHYST_LIB_API void pihyst_lib_free(pihyst_lib_model *h);

/** Number of operators K, or a negative status. */
PIHYST_LIB_API int32_t pihyst_lib_n_operators(const pihyst_lib_model *h);

/** y[t] for u[t], t < n, advancing the operator state and the creep lags (chunks
 *  continue exactly). Returns 0, or PIHYST_LIB_EINPUT (and changes nothing) if an input
 *  is NaN or outside the model's input range. Stops the compensator, if one was
 *  started. */
PIHYST_LIB_API int32_t pihyst_lib_predict(pihyst_lib_model *h, const double *u, double *y, int32_t n);

/** Copy the operator state (K values) into state[0..n-1]; n must be K. */
PIHYST_LIB_API int32_t pihyst_lib_get_state(const pihyst_lib_model *h, double *state, int32_t n);

/** Set the operator state to state (K values; NULL: the model's initial state) and stop
 *  the compensator, if one was started. Creep lags go to rest at the new state's
 *  hysteresis output. */
PIHYST_LIB_API int32_t pihyst_lib_reset(pihyst_lib_model *h, const double *state, int32_t n);

/** Start the feedforward compensator on the current state: voltage limits u_min, u_max
 *  (NaN: the model's input range), slew limit max_step in volts per sample (<= 0 or
 *  infinite: none), u_initial the voltage applied last. Needs every weight >= 0. Creep
 *  lags go to rest at the output at u_initial, as pihyst.compensate starts them
 *  (pihyst_lib_set_creep_state after this continues from other lag states). */
PIHYST_LIB_API int32_t pihyst_lib_compensator_start(pihyst_lib_model *h, double u_min, double u_max,
                                     double max_step, double u_initial);

/** u[t] for the desired outputs y_desired[t], t < n, within the limits whatever the input
 *  (NaN holds the last voltage); flags[t] (may be NULL) receives the pihyst.h
 *  PIHYST_COMP_* bits. With creep each sample's hysteresis target comes from the lags
 *  (pihyst_creep_compensator_step at the fixed interval). Returns the number of flagged
 *  samples or a negative status. */
PIHYST_LIB_API int32_t pihyst_lib_compensate(pihyst_lib_model *h, const double *y_desired, double *u,
                              uint8_t *flags, int32_t n);

#ifdef __cplusplus
}
#endif
#endif /* PIHYST_LIB_H */
