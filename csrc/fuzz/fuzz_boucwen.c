/* fuzz_boucwen.c - libFuzzer harness of pihyst_bw_* (pihyst_boucwen.h), in double and
 * single precision.
 *
 * Input: a Bouc-Wen model (shape, weights, range; numbers as fuzz_common.h reads them, so
 * invalid ones too), an initial state, the compensator's limits, slew limit and initial
 * voltage, then desired outputs (NaN, infinities and huge values included). Invariants:
 *   - init, reset and compensator init return status codes of pihyst.h; a model that
 *     init accepts has beta > |gamma|, beta + |gamma| <= 1000, 1 <= n <= 10;
 *   - the model's z stays within z_max (to rounding; or within the |z| a reset started
 *     from, which may exceed z_max by the core's slack) on any input, outputs finite;
 *   - every voltage is finite, inside [u_min, u_max] and within max_step of the last;
 *     NaN is flagged exactly when the desired value is NaN, and holds the voltage; a
 *     saturation flag puts the voltage at its limit;
 *   - step equals run bit for bit, and y_last is the output of a separate model stepped
 *     with the chosen voltages (state equal bit for bit);
 *   - a sample without flags meets the desired value: |y_last - y_d| <= 16 tol plus the
 *     output change of a few ulps of voltage at the steepest slope (input ranges of at
 *     least 1e-6), or else the voltage brackets y_d to a few ulps: within BRACKET_ULPS
 *     floats of it is a voltage whose output lies on the other side of y_d.
 *     The second form is the tolerance decided for z's integration error (issue 24): the
 *     model's output is the discrete map Y(u) of its RK4 substeps, whose count changes
 *     with the step's length and whose rounding adds up over up to 1 / H substeps (6400
 *     at beta + |gamma| = 200): Y jumps and wiggles by far more than 16 tol between
 *     adjacent floats (count x eps relative, in float and in double alike), so no
 *     voltage may meet y_d to tol. The exact inverse of the discrete map is then the
 *     float where Y crosses y_d, which the compensator's bracket (width <= 2 eps |u|)
 *     finds; a core that stops short of that fails either form.
 * Build and run: make -C csrc fuzz (see docs/c-core.md). */
#include "fuzz_common.h"

#include "pihyst_boucwen.h"

#ifdef FUZZ_F32
#define BW(name) name##_f32
#else
#define BW(name) name
#endif

#define N_MAX 64
/* the compensator stops bisecting at |b - a| <= 2 eps max(|a|, |b|): 4 floats at most */
#define BRACKET_ULPS 8

#ifdef FUZZ_F32
#define NEXT_FLOAT nextafterf
#else
#define NEXT_FLOAT nextafter
#endif

/* Whether a voltage within BRACKET_ULPS floats of u, stepped from the model state
 * ``before``, gives an output on the other side of yd than y_u (or on it). */
static int brackets(const BW(pihyst_bw_model) *before, real u, real yd, real y_u)
{
    real lo = u, hi = u;
    int k;
    for (k = 0; k < BRACKET_ULPS; ++k) {
        BW(pihyst_bw_model) a = *before, b = *before;
        lo = NEXT_FLOAT(lo, (real)-INFINITY);
        hi = NEXT_FLOAT(hi, (real)INFINITY);
        if (lo >= before->u_min &&
            ((double)BW(pihyst_bw_step)(&a, lo) - (double)yd) * ((double)y_u - (double)yd) <= 0.0)
            return 1;
        if (hi <= before->u_max &&
            ((double)BW(pihyst_bw_step)(&b, hi) - (double)yd) * ((double)y_u - (double)yd) <= 0.0)
            return 1;
    }
    return 0;
}

static void check(const uint8_t *data, size_t size)
{
    reader r = {data, size};
    BW(pihyst_bw_params) p;
    BW(pihyst_bw_model) m, twin, run_model, before;
    BW(pihyst_bw_compensator) c, run_comp;
    pihyst_status s;
    real yd[N_MAX], u_run[N_MAX], y_run[N_MAX];
    pihyst_flags fl_run[N_MAX];
    double beta, span, slope_max, scale, u_prev, z_bound;
    size_t t, n, flagged = 0, flagged_run;

    beta = take_num(&r, 0.0, 60.0);
    p.beta = (real)beta;
    p.gamma = (real)(take_num(&r, -1.2, 1.2) * beta);
    p.n = (real)take_num(&r, 0.5, 11.0);
    p.hysteretic = (real)take_num(&r, -20.0, 20.0);
    p.linear = (real)take_num(&r, -10.0, 60.0);
    p.quadratic = (real)take_num(&r, -10.0, 10.0);
    p.offset = (real)take_num(&r, -10.0, 10.0);
    p.u_min = (real)take_num(&r, -200.0, 100.0);
    p.u_max = (real)((double)p.u_min + take_num(&r, 0.0, 300.0));
    p.initial_u = p.u_min;
    p.initial_z = (real)0.0;
    s = BW(pihyst_bw_init)(&m, &p);
    REQUIRE(known_status(s));
    if (s != PIHYST_OK) return;
    REQUIRE(m.beta > (real)fabs((double)m.gamma) && m.beta + (real)fabs((double)m.gamma) <=
            (real)PIHYST_BW_MAX_SHAPE && m.n >= (real)1.0 && m.n <= (real)PIHYST_BW_MAX_EXPONENT);
    if (m.beta + (real)fabs((double)m.gamma) > (real)200.0) return; /* slow; covered above */
    span = (double)m.u_max - (double)m.u_min;
    /* an initial state, possibly invalid */
    {
        /* read in sequence: the order of a call's arguments is the compiler's choice */
        const double u_reset = (double)m.u_min + take_num(&r, -0.1, 1.1) * span;
        const double z_reset = take_num(&r, -1.1, 1.1) * (double)m.z_max;
        s = BW(pihyst_bw_reset)(&m, (real)u_reset, (real)z_reset);
    }
    REQUIRE(known_status(s));
    /* reset accepts |z| up to z_max plus the rounding slack of a stored state (1e-9 in
     * double), and from there z only returns towards z_max: |z| is bounded by the larger */
    z_bound = fmax((double)m.z_max, fabs((double)m.z));
    /* the compensator: limits, slew, initial voltage */
    {
        const double lo = (double)m.u_min + take_num(&r, -0.1, 0.6) * span;
        const double hi = (double)m.u_max - take_num(&r, -0.1, 0.6) * span;
        const unsigned slew_kind = take_u8(&r);
        const double step = slew_kind < 128 ? take_num(&r, 0.0, span) : (double)INFINITY;
        const double u0 = lo + take_num(&r, -0.1, 1.1) * (hi - lo);
        s = BW(pihyst_bw_compensator_init)(&c, &m, (real)lo, (real)hi, (real)step, (real)u0);
        REQUIRE(known_status(s));
        if (s != PIHYST_OK) return;
    }
    scale = (double)c.scale;
    slope_max = (fabs((double)m.linear) + 2.0 * fabs((double)m.quadratic) +
                 fabs((double)m.hysteretic) * 2.0 * (double)m.beta /
                     ((double)m.beta + (double)m.gamma)) / span;
    twin = m;
    run_model = m;
    run_comp = c;
    run_comp.model = &run_model;
    n = take_u8(&r) % N_MAX + 1;
    for (t = 0; t < n; ++t) {
        const double y0 = (double)m.offset;
        yd[t] = (real)take_num(&r, y0 - 1.2 * scale, y0 + 1.2 * scale);
    }
    u_prev = (double)m.u;
    for (t = 0; t < n; ++t) {
        pihyst_flags fl = 0xff;
        const double u = (double)BW(pihyst_bw_compensator_step)(&c, yd[t], &fl);
        REQUIRE(isfinite(u) && u >= (double)c.u_min && u <= (double)c.u_max);
        REQUIRE((real)fabs((double)((real)u - (real)u_prev)) <= c.max_step);
        REQUIRE((fl & ~(PIHYST_COMP_SAT_LOW | PIHYST_COMP_SAT_HIGH | PIHYST_COMP_NAN |
                        PIHYST_COMP_SLEW)) == 0);
        REQUIRE(((fl & PIHYST_COMP_NAN) != 0) == (yd[t] != yd[t]));
        if (fl & PIHYST_COMP_NAN) REQUIRE(u == u_prev);
        /* out of reach: at the limit, or on the way there when the slew limit cut it short */
        if (fl & PIHYST_COMP_SAT_LOW) REQUIRE(u == (double)c.u_min || (fl & PIHYST_COMP_SLEW));
        if (fl & PIHYST_COMP_SAT_HIGH) REQUIRE(u == (double)c.u_max || (fl & PIHYST_COMP_SLEW));
        flagged += fl != 0;
        /* the separate model, stepped with the chosen voltage */
        before = twin;
        REQUIRE(BW(pihyst_bw_step)(&twin, (real)u) == c.y_last);
        REQUIRE(twin.u == m.u && twin.z == m.z);
        REQUIRE(fabs((double)m.z) <= z_bound * (1.0 + 64.0 * FUZZ_EPS) + FUZZ_TINY);
        /* (on a range of a few subnormals the bracket's adjacent floats are the whole
         * range: met to the float grid, which the slack below cannot express) */
        if (fl == 0 && isfinite((double)yd[t]) && span >= 1e-6) {
            const double tol = 4.0 * FUZZ_EPS * (fabs((double)yd[t]) + scale);
            REQUIRE(fabs((double)c.y_last - (double)yd[t]) <=
                        16.0 * tol + 8.0 * FUZZ_EPS * (fabs(u) + span) * slope_max + FUZZ_TINY ||
                    brackets(&before, (real)u, yd[t], c.y_last));
        }
        u_prev = u;
    }
    flagged_run = BW(pihyst_bw_compensator_run)(&run_comp, yd, u_run, y_run, fl_run, n);
    REQUIRE(flagged_run == flagged);
    REQUIRE(run_model.u == m.u && run_model.z == m.z && run_comp.y_last == c.y_last);
    (void)y_run;
    (void)u_run;
}

#ifdef FUZZ_F32
void check_boucwen_f32(const uint8_t *data, size_t size);
void check_boucwen_f32(const uint8_t *data, size_t size) { check(data, size); }
#else
void check_boucwen_f32(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    check(data, size);
    check_boucwen_f32(data, size);
    return 0;
}
#endif
