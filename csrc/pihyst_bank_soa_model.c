/* pihyst_bank_soa_model.c - a model bank laid out structure-of-arrays (pihyst_modelbank,
 * the "Model banks, structure-of-arrays" section of pihyst_api.h; docs/c-core.md).
 *
 * Classical channels with K <= 16 operators are stepped L at a time (L = 64 bytes of
 * reals: 8 doubles, 16 floats), one lane per channel, by (1)-(2) of pihyst.h:
 *
 *     f_k <- max(u - r_k, min(u + r_k, f_k)),   y = offset + sum_k w_k f_k
 *
 * with the operations of the single model's K <= 16 kernel (run_classical_small in
 * pihyst_model.c) in the same order, so that each lane gives bit for bit what
 * pihyst_model_step gives: the operators padded to 16 (r = -0, w = 0: a padded operator
 * follows u and adds a zero), the products of operators k, k + 4, k + 8, k + 12 summed
 * as ((p_k + p_{k+4}) + (p_{k+8} + p_{k+12})) for k < 4, and those four as
 * (s_0 + s_2) + (s_1 + s_3), added to the offset. (The same expressions contract to the
 * same fused multiply-adds under -ffp-contract=fast in both.) The single model takes
 * that kernel only with compiler vector extensions; without them (PIHYST_NO_VECTOR_EXT,
 * other compilers) every channel is stepped by pihyst_model_step, as are channels of
 * other families or with K > 16, in the same call.
 *
 * Layout: a group is a header of two vectors (offset, mode) and three vectors per
 * operator k < 16: r_k, w_k, f_k. The groups lie one after another on a 64-byte
 * boundary. The fast channels' states live in the groups between pihyst_modelbank_init
 * and pihyst_modelbank_sync (which copies them back to the models).
 */
#include "pihyst.h"
#include "pihyst_internal.h"

#include <stdint.h>
#include <string.h>

#define L PIHYST_SOA_LANES_OF(real)
#define ALIGN_BYTES 64
#define N_OPS 16 /* operators per group: the single model's kernel pads to 16 */
#define HEADER 2
enum { H_OFFSET, H_MODE };
enum { OP_R, OP_W, OP_F, OP_VECTORS };
#define GROUP_LEN ((HEADER + OP_VECTORS * N_OPS) * L)

#if defined(__GNUC__) && !defined(PIHYST_NO_VECTOR_EXT)
#define PIHYST_SOA_MODEL_FAST 1
#endif

static int has_fast_path(const pihyst_model *m)
{
#ifdef PIHYST_SOA_MODEL_FAST
    return m->family == PIHYST_CLASSICAL && m->n_ops <= N_OPS;
#else
    (void)m;
    return 0;
#endif
}

size_t pihyst_modelbank_work_len(pihyst_model *const *models, size_t n)
{
    (void)models;
    return (n + L - 1) / L * GROUP_LEN + ALIGN_BYTES / sizeof(real);
}

pihyst_status pihyst_modelbank_init(pihyst_modelbank *b, pihyst_model *const *models, size_t n,
                                    real *work, size_t work_len)
{
    size_t i, k;
    uintptr_t at;
    if (!b || !models || (!work && n > 0)) return PIHYST_ENULL;
    for (i = 0; i < n; ++i)
        if (!models[i]) return PIHYST_ENULL;
    if (n > 0 && work_len < pihyst_modelbank_work_len(models, n)) return PIHYST_ESCRATCH;
    b->models = models;
    b->n = n;
    b->n_fast = 0;
    at = ((uintptr_t)work + ALIGN_BYTES - 1) / ALIGN_BYTES * ALIGN_BYTES;
    b->groups = (real *)at;
    for (i = 0; i < (n + L - 1) / L * L; ++i) {
        real *grp = b->groups + i / L * GROUP_LEN, *ops = grp + HEADER * L;
        const size_t l = i % L;
        const pihyst_model *m = i < n ? models[i] : NULL;
        const int fast = m && has_fast_path(m);
        for (k = 0; k < N_OPS; ++k) {
            const int real_op = fast && k < m->n_ops;
            /* a padded r is -0, so that u - r is the single model's padded u + 0 (u = -0
             * then gives +0 in both, and the bits of y agree) */
            ops[(OP_VECTORS * k + OP_R) * L + l] = real_op ? m->thresholds[k] : RC(-0.0);
            ops[(OP_VECTORS * k + OP_W) * L + l] = real_op ? m->weights[k] : RC(0.0);
            ops[(OP_VECTORS * k + OP_F) * L + l] = real_op ? m->state[k] : RC(0.0);
        }
        grp[H_OFFSET * L + l] = fast ? m->offset : RC(0.0);
        grp[H_MODE * L + l] = fast ? RC(1.0) : RC(0.0);
        b->n_fast += (size_t)fast;
    }
    return PIHYST_OK;
}

#ifdef PIHYST_SOA_MODEL_FAST
typedef real vlane __attribute__((vector_size(L * sizeof(real))));

/* (1)-(2) for the L lanes of a group at inputs u (per lane); the clamp is the single
 * model's v < h ? v : h, v > l ? v : l per lane, and the sum its tree (see above),
 * written as the same expression of products so that it contracts alike */
PIHYST_HOT
static void model_lanes(real *PIHYST_RESTRICT ops, const real *PIHYST_RESTRICT u_in,
                        const real *PIHYST_RESTRICT offset_in, real *PIHYST_RESTRICT y_out)
{
    vlane *v = (vlane *)__builtin_assume_aligned(ops, 64);
    vlane u, off, s0, s1, s2, s3, y;
    size_t k, i;
    memcpy(&u, u_in, sizeof u);
    memcpy(&off, offset_in, sizeof off);
    for (k = 0; k < N_OPS; ++k) {
        vlane *o = v + OP_VECTORS * k;
        vlane f = o[OP_F], hi = u + o[OP_R], lo = u - o[OP_R];
        for (i = 0; i < L; ++i) {
            real x = f[i];
            x = x < hi[i] ? x : hi[i];
            f[i] = x > lo[i] ? x : lo[i];
        }
        o[OP_F] = f;
    }
#define W_(k) v[OP_VECTORS * (k) + OP_W]
#define F_(k) v[OP_VECTORS * (k) + OP_F]
    s0 = ((W_(0) * F_(0)) + (W_(4) * F_(4))) + ((W_(8) * F_(8)) + (W_(12) * F_(12)));
    s1 = ((W_(1) * F_(1)) + (W_(5) * F_(5))) + ((W_(9) * F_(9)) + (W_(13) * F_(13)));
    s2 = ((W_(2) * F_(2)) + (W_(6) * F_(6))) + ((W_(10) * F_(10)) + (W_(14) * F_(14)));
    s3 = ((W_(3) * F_(3)) + (W_(7) * F_(7))) + ((W_(11) * F_(11)) + (W_(15) * F_(15)));
#undef W_
#undef F_
    y = off + ((s0 + s2) + (s1 + s3));
    memcpy(y_out, &y, sizeof y);
}
#endif

void pihyst_modelbank_step(pihyst_modelbank *b, const real *u, real *y)
{
    const size_t n = b->n;
    size_t g, l;
    for (g = 0; g < (n + L - 1) / L; ++g) {
        real *grp = b->groups + g * GROUP_LEN;
        const size_t i0 = g * L, lanes = n - i0 < L ? n - i0 : L;
#ifdef PIHYST_SOA_MODEL_FAST
        real ug[L], yg[L];
        for (l = 0; l < L; ++l) ug[l] = l < lanes ? u[i0 + l] : RC(0.0);
        model_lanes(grp + HEADER * L, ug, grp + H_OFFSET * L, yg);
        for (l = 0; l < lanes; ++l)
            y[i0 + l] = grp[H_MODE * L + l] != RC(0.0)
                            ? yg[l]
                            : pihyst_model_step(b->models[i0 + l], ug[l]);
#else
        for (l = 0; l < lanes; ++l) y[i0 + l] = pihyst_model_step(b->models[i0 + l], u[i0 + l]);
        (void)grp;
#endif
    }
}

void pihyst_modelbank_sync(pihyst_modelbank *b)
{
    size_t i, k;
    for (i = 0; i < b->n; ++i) {
        const real *grp = b->groups + i / L * GROUP_LEN, *ops = grp + HEADER * L;
        const size_t l = i % L;
        pihyst_model *m = b->models[i];
        if (grp[H_MODE * L + l] == RC(0.0)) continue;
        for (k = 0; k < m->n_ops; ++k) m->state[k] = ops[(OP_VECTORS * k + OP_F) * L + l];
    }
}
