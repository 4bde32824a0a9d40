/* pihyst.h - Prandtl-Ishlinskii hysteresis core.
 *
 * C99, no malloc, no globals, no I/O, reentrant: every function works only on the
 * objects it is given, so calls on different models/compensators may run concurrently
 * (one object must not be used from two contexts at once). Every array is owned by the
 * caller; its length is written next to it. A firmware project copies the files
 * pihyst*.h and pihyst_*.c of csrc as they are (docs/c-core.md).
 *
 * Two precisions with the same API: double (pihyst_model, pihyst_model_init, ...) and
 * single, for FPUs without double support such as the Cortex-M4F (pihyst_model_f32,
 * pihyst_model_init_f32, ...; every `double` of the API becomes `float`). Both are
 * declared by pihyst_api.h, included twice below; pihyst_*_f32.c are the single-
 * precision builds of the same sources.
 *
 * Model (docs/theory/operators.md): a bank of K generalized play operators
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
 * The operator state (f_k[t-1], K values) is explicit: read it, set it, save it;
 * a signal run in chunks gives exactly the output of one run.
 */
#ifndef PIHYST_H
#define PIHYST_H
#include <stddef.h>
#include <stdint.h>
#ifdef __cplusplus
extern "C" {
#endif

#define PIHYST_VERSION_MAJOR 0
#define PIHYST_VERSION_MINOR 2
#define PIHYST_ABI_VERSION 3 /* bump on any struct layout or signature change */

typedef enum {
    PIHYST_OK = 0,
    PIHYST_ENULL = -1,       /* a required pointer is NULL */
    PIHYST_ESIZE = -2,       /* n_ops == 0, a polyline without points, or polyline offsets
                                that do not start at 0 and increase */
    PIHYST_ENONFINITE = -3,  /* NaN or infinity in a parameter or state */
    PIHYST_ETHRESHOLD = -4,  /* thresholds negative or not strictly increasing */
    PIHYST_ESHAPE = -5,      /* multislope shape invalid: needs 0 < a < b, 0 <= h <= 1, U > 0 */
    PIHYST_EMULTISLOPE_R = -6, /* multislope threshold above (1 - a)U / (1 - a h) */
    PIHYST_EPOLYLINE = -7,   /* breakpoints not strictly increasing (or a subnormal apart),
                                envelope decreasing, or a segment's slope not finite */
    PIHYST_EENVELOPE = -8,   /* R > F somewhere on the input range */
    PIHYST_ERANGE = -9,      /* input range empty (u_min >= u_max) */
    PIHYST_ENEGATIVE_WEIGHT = -10, /* compensator: a weight is negative (model not monotone) */
    PIHYST_ELIMITS = -11,    /* compensator: voltage limits, slew limit or voltage invalid */
    PIHYST_EFAMILY = -12,    /* family is not one of pihyst_family */
    PIHYST_ESCRATCH = -13    /* compensator: scratch shorter than pihyst_compensator_scratch_len */
} pihyst_status;

typedef enum {
    PIHYST_CLASSICAL = 0,
    PIHYST_MULTISLOPE = 1,
    PIHYST_PWL = 2
} pihyst_family;

/** Per-sample flags of the compensator (bits; 0 = desired output reached). The one type
 *  of pihyst_compensator_step's and _run's flags. */
typedef uint8_t pihyst_flags;
/* out of reach: beyond the output at the voltage limit, whatever the slew limit; a sample
 * the slew limit cut short on its way there has PIHYST_COMP_SLEW too */
#define PIHYST_COMP_SAT_LOW ((pihyst_flags)1u)  /**< out of reach below: voltage at u_min */
#define PIHYST_COMP_SAT_HIGH ((pihyst_flags)2u) /**< out of reach above: voltage at u_max */
#define PIHYST_COMP_NAN ((pihyst_flags)4u)      /**< desired value NaN: last voltage held */
#define PIHYST_COMP_SLEW ((pihyst_flags)8u)     /**< not reached within the slew limit:
                                                     voltage moved by max_step */

/** Bits of pihyst_compensator.in_order (internal: which event lists arrive sorted). */
#define PIHYST_ORDER_RISING_KINKS 1u   /**< multislope rising kinks sorted by distance */
#define PIHYST_ORDER_FALLING_KINKS 2u  /**< multislope falling kinks sorted by distance */
#define PIHYST_ORDER_CLASSICAL 4u      /**< classical state 1-Lipschitz in r: crossings in
                                            operator order, read from the state */
#define PIHYST_ORDER_RAMPS 8u          /**< every polyline a saturated ramp: the ramp search,
                                            no event lists (pihyst_inverse.c) */
#define PIHYST_ORDER_RAMPS_AVX2 16u    /**< and the model step of the ramps with AVX2 */

/** Length of the coefficient scratch a model needs, in values of its precision. */
#define PIHYST_COEF_LEN(n_ops) (4 * (n_ops))

/** The compensator works on a copy of the operator state aligned to this many bytes when
 *  the model's state array is not (see pihyst_compensator). Define PIHYST_STATE_ALIGN to 0
 *  when building the core to turn the copy off (cores without data cache lines, e.g.
 *  Cortex-M4: the copy buys nothing there); it must be 0 or a power of two >= 16. */
#ifndef PIHYST_STATE_ALIGN
#define PIHYST_STATE_ALIGN 64
#endif

/** Scratch a compensator needs at most, in values of its precision, for K = n_ops
 *  operators and a model with n_points polyline breakpoints in total (rising plus
 *  falling; 0 for classical and multislope). pihyst_compensator_scratch_len gives the
 *  exact figure for a model. */
#define PIHYST_COMPENSATOR_SCRATCH_LEN(n_ops, n_points) (10 * (n_ops) + 8 * (n_points) + 12)
#define PIHYST_COMPENSATOR_SCRATCH_LEN_F32(n_ops, n_points) \
    (10 * (n_ops) + 8 * (n_points) + 20)

/** Compensator banks in structure-of-arrays layout (pihyst_compbank): channels are
 *  grouped PIHYST_SOA_LANES_OF(real) at a time (64 bytes of reals), each group a header of
 *  PIHYST_SOA_HEADER vectors and four vectors per operator. Work length in values of the
 *  precision for n channels whose fast (classical) channels have at most n_ops operators;
 *  pihyst_compbank_work_len gives the exact figure for a set of channels. */
#define PIHYST_SOA_LANES_OF(type) (64 / sizeof(type))
#define PIHYST_SOA_HEADER 8
#define PIHYST_COMPBANK_WORK_LEN_OF(type, n, n_ops)                                      \
    (((n) + PIHYST_SOA_LANES_OF(type) - 1) / PIHYST_SOA_LANES_OF(type) *                  \
         (PIHYST_SOA_HEADER + 4 * (((n_ops) + 3) / 4 * 4)) * PIHYST_SOA_LANES_OF(type) +  \
     64 / sizeof(type))
#define PIHYST_COMPBANK_WORK_LEN(n, n_ops) PIHYST_COMPBANK_WORK_LEN_OF(double, n, n_ops)
#define PIHYST_COMPBANK_WORK_LEN_F32(n, n_ops) PIHYST_COMPBANK_WORK_LEN_OF(float, n, n_ops)
/** Work length of a structure-of-arrays model bank (pihyst_modelbank) of n channels. */
#define PIHYST_MODELBANK_WORK_LEN_OF(type, n)                                            \
    (((n) + PIHYST_SOA_LANES_OF(type) - 1) / PIHYST_SOA_LANES_OF(type) * (2 + 3 * 16) *    \
         PIHYST_SOA_LANES_OF(type) +                                                      \
     64 / sizeof(type))
#define PIHYST_MODELBANK_WORK_LEN(n) PIHYST_MODELBANK_WORK_LEN_OF(double, n)
#define PIHYST_MODELBANK_WORK_LEN_F32(n) PIHYST_MODELBANK_WORK_LEN_OF(float, n)

/** Human-readable text of a status code (static storage). */
const char *pihyst_status_text(pihyst_status status);

/* The API in double precision ... */
#define PIHYST_REAL double
#define PIHYST_NAME(name) name
#include "pihyst_api.h"
#undef PIHYST_REAL
#undef PIHYST_NAME

/* ... and in single precision: the same with float and the suffix _f32. */
#define PIHYST_REAL float
#define PIHYST_NAME(name) name##_f32
#include "pihyst_api.h"
#undef PIHYST_REAL
#undef PIHYST_NAME

#ifdef __cplusplus
}
#endif
#endif /* PIHYST_H */
