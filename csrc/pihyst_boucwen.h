/* pihyst_boucwen.h - the Bouc-Wen hysteresis model and its exact compensator.
 *
 * C99, no malloc, no globals, no I/O, reentrant; the model struct holds its state (u, z)
 * and no pointers. Two precisions with the same API, like pihyst.h: double
 * (pihyst_bw_model, pihyst_bw_init, ...) and single (pihyst_bw_model_f32, ...).
 * Status codes and compensator flags are those of pihyst.h.
 *
 * Model (docs/theory/bouc-wen.md). On the normalized input x = (u - u_min) / (u_max -
 * u_min), with s = sign(dx),
 *
 *     y = offset + c_1 x + c_2 x^2 + a z,                                       (B1)
 *     dz/dx = g_s(z) = 1 - |z|^n (s beta sign(z) + gamma),                     (B2)
 *
 * integrated between two samples by m = ceil(|dx| / H) classical Runge-Kutta substeps of
 * dx / m, H = min(1/256, 1/(32 (beta + |gamma|))); a substep that takes z across 0 is
 * split at the input change that brings z to 0 (8-point Gauss-Legendre quadrature of
 * dz / g_s). This arithmetic is the model's definition: it is that of the Python model
 * (src/pihyst/model/_boucwen.py), operation for operation.
 *
 * Compensator: from the state (u_p, z_p), Y(u) = (B1) after the step u_p -> u is
 * non-decreasing on both sides of u_p when the model is monotone, min(c_1, c_1 + 2 c_2) +
 * min(a, 0) 2 beta / (beta + gamma) >= 0 (others are refused). Each sample solves
 * Y(u) = y_d between u_p and the reachable end [max(u_min, u_p - max_step), min(u_max,
 * u_p + max_step)] by Newton steps from u_p; the end is evaluated only when a step would
 * reach or pass it (or after 8 steps without a bracket). Once y_d is bracketed, a Newton
 * step is taken if it stays in the bracket and is at most half the step before last,
 * else the bracket is bisected. It stops at |Y(u) - y_d| <= 4 eps (|y_d| + |offset| +
 * |c_1| + |c_2| + |a| z_max) or when the bracket is two adjacent numbers; eps is that of
 * the precision. Out of reach: the voltage stops at the bracket's end, flagged
 * PIHYST_COMP_SAT_LOW/HIGH at a limit or PIHYST_COMP_SLEW at the slew bound (with
 * PIHYST_COMP_SAT_LOW/HIGH too if the limit itself would miss y_d); NaN holds
 * the last voltage (PIHYST_COMP_NAN). Every voltage lies in [u_min, u_max] and within
 * max_step of the previous one, whatever y_d is.
 */
#ifndef PIHYST_BOUCWEN_H
#define PIHYST_BOUCWEN_H
#include <stddef.h>

#include "pihyst.h"

#ifdef __cplusplus
extern "C" {
#endif

#define PIHYST_BW_MAX_SHAPE 1000.0   /* beta + |gamma| above this: a step, not a model */
#define PIHYST_BW_MAX_EXPONENT 10.0
#define PIHYST_BW_MIN_SPREAD 1e-9    /* beta + gamma below this: z_max beyond use, |z|^n overflows */

/** Text of a status code as the pihyst_bw_* functions mean it (static storage): the shape,
 *  range and monotonicity codes in Bouc-Wen terms, the others as pihyst_status_text. */
const char *pihyst_bw_status_text(pihyst_status status);

#define PIHYST_REAL double
#define PIHYST_NAME(name) name
#include "pihyst_boucwen_api.h"
#undef PIHYST_REAL
#undef PIHYST_NAME

#define PIHYST_REAL float
#define PIHYST_NAME(name) name##_f32
#include "pihyst_boucwen_api.h"
#undef PIHYST_REAL
#undef PIHYST_NAME

#ifdef __cplusplus
}
#endif
#endif /* PIHYST_BOUCWEN_H */
