/* compensator_loop.c - the feedforward compensator as a controller runs it.
 *
 * Everything is static (no malloc): the paper's Table 1 multislope model, its
 * compensator with voltage and slew limits, and a 1 kHz control loop that turns a
 * desired displacement into the voltage for the amplifier. Here the "amplifier" is a
 * print-out; on a real controller it is a DAC write inside the timer interrupt.
 *
 * Build (from the repository root):
 *     cc -std=c99 -O2 -Icsrc examples/firmware/compensator_loop.c csrc/pihyst_*.c -lm
 * (pihyst_*_f32.c, the single-precision API, may be left out when it is not used).
 * `make -C csrc test` builds and runs it, and it checks its own result.
 */
#include "pihyst.h"

#include <math.h>
#include <stdio.h>

#define N_OPS 4

static const double thresholds[N_OPS] = {0.0, 20.0, 30.0, 40.0};      /* V */
static const double weights[N_OPS] = {0.196, 0.026, 0.046, 0.028};     /* um/V */
static const pihyst_params params = {
    .family = PIHYST_MULTISLOPE,
    .n_ops = N_OPS,
    .thresholds = thresholds,
    .weights = weights,
    .u_min = 0.0, /* V: the input range on which the model is valid */
    .u_max = 150.0,
    .shape = {.U = 150.0, .a = 0.8, .b = 1.2, .h = 0.5},
    /* .offset = 0 and .initial_state = NULL (operators at rest) when left out */
};

static double coef[PIHYST_COEF_LEN(N_OPS)];
static double state[N_OPS];
static double scratch[PIHYST_COMPENSATOR_SCRATCH_LEN(N_OPS, 0)];
static pihyst_model model;
static pihyst_compensator comp;

/* desired displacement at tick k: a 0 -> 30 -> 10 -> 35 um path (minor loop inside) */
static double desired_um(int k)
{
    static const double knots[4] = {0.0, 30.0, 10.0, 35.0};
    int leg = k / 1000, i = k % 1000;
    if (leg >= 3) return knots[3];
    return knots[leg] + (knots[leg + 1] - knots[leg]) * i / 1000.0;
}

int main(void)
{
    pihyst_status s;
    int k, slewed = 0, out_of_reach = 0, limits_broken = 0;
    double worst = 0.0, u_prev = 0.0;

    s = pihyst_model_init(&model, &params, coef, state);
    if (s != PIHYST_OK) {
        printf("model: %s\n", pihyst_status_text(s));
        return 1;
    }
    /* limits 0-150 V, at most 0.5 V per tick (500 V/s at 1 kHz), starting at 0 V */
    s = pihyst_compensator_init(&comp, &model, 0.0, 150.0, 0.5, 0.0, scratch,
                                sizeof scratch / sizeof scratch[0]);
    if (s != PIHYST_OK) {
        printf("compensator: %s\n", pihyst_status_text(s));
        return 1;
    }

    for (k = 0; k <= 3000; ++k) { /* the timer interrupt, once per millisecond */
        pihyst_flags flags;
        double y_d = desired_um(k);
        double volts = pihyst_compensator_step(&comp, y_d, &flags);
        /* dac_write(volts); */
        if (flags & PIHYST_COMP_SLEW) ++slewed;
        else if (flags) ++out_of_reach;
        else if (fabs(comp.y_last - y_d) > worst) worst = fabs(comp.y_last - y_d);
        if (volts < 0.0 || volts > 150.0 || fabs(volts - u_prev) > 0.5) ++limits_broken;
        u_prev = volts;
        if (k % 500 == 0)
            printf("t = %4d ms  desired %7.3f um  voltage %8.4f V  model %7.3f um\n", k, y_d,
                   volts, comp.y_last);
    }
    /* After each reversal the multislope model holds its output while the voltage
     * crosses the flat stretch (h r volts at the top): at 0.5 V per tick the
     * compensator needs some ticks to get across, and says so with PIHYST_COMP_SLEW. */
    printf("%d of 3001 samples slew-limited (crossing the flat stretch after a reversal), "
           "%d out of reach, %d outside the limits; every other sample met to %.1e um\n",
           slewed, out_of_reach, limits_broken, worst);
    return out_of_reach == 0 && limits_broken == 0 && worst < 1e-9 ? 0 : 1;
}
