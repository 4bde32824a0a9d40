/* boucwen_loop.c - the Bouc-Wen compensator as a controller runs it.
 *
 * Everything is static (no malloc): a Bouc-Wen model with remanence (docs/theory/
 * bouc-wen.md; the struct holds its state, nothing else is needed), its exact compensator
 * with voltage and slew limits, and a 1 kHz control loop that turns a desired displacement
 * into the voltage for the amplifier (here a print-out; on a controller a DAC write in the
 * timer interrupt). `pihyst export MODEL.json --c` writes the params of a fitted model.
 *
 * Build (from the repository root):
 *     cc -std=c99 -O2 -Icsrc examples/firmware/boucwen_loop.c csrc/pihyst_boucwen.c \
 *        csrc/pihyst_model.c -lm
 * `make -C csrc test` builds and runs it, and it checks its own result.
 */
#include "pihyst_boucwen.h"

#include <math.h>
#include <stdio.h>

static const pihyst_bw_params params = {
    .beta = 5.0, .gamma = 1.0, .n = 1.0, /* shape on the normalized input */
    .hysteretic = -8.0,                  /* um per unit of z */
    .linear = 40.0,                      /* um at the top of the range */
    .offset = 0.3,                       /* um */
    .u_min = 0.0, .u_max = 150.0,        /* V */
    .initial_u = 0.0, .initial_z = 0.0,  /* virgin; set to the rest state below */
};

static pihyst_bw_model model;
static pihyst_bw_compensator comp;

/* desired displacement at tick k: a 2 -> 30 -> 10 -> 35 um path (minor loop inside) */
static double desired_um(int k)
{
    static const double knots[4] = {2.0, 30.0, 10.0, 35.0};
    int leg = k / 1000, i = k % 1000;
    if (leg >= 3) return knots[3];
    return knots[leg] + (knots[leg + 1] - knots[leg]) * i / 1000.0;
}

int main(void)
{
    pihyst_status s;
    int k, slewed = 0, out_of_reach = 0, limits_broken = 0;
    double worst = 0.0, u_prev = 0.0;

    s = pihyst_bw_init(&model, &params);
    /* at rest at 0 V after a full 0 -> 150 -> 0 V cycle (the Python model's default) */
    if (s == PIHYST_OK) s = pihyst_bw_reset(&model, 0.0, pihyst_bw_rest_z(&model));
    if (s != PIHYST_OK) {
        printf("model: %s\n", pihyst_status_text(s));
        return 1;
    }
    /* limits 0-150 V, at most 0.5 V per tick (500 V/s at 1 kHz), starting at 0 V */
    s = pihyst_bw_compensator_init(&comp, &model, 0.0, 150.0, 0.5, 0.0);
    if (s != PIHYST_OK) {
        printf("compensator: %s\n", pihyst_status_text(s));
        return 1;
    }

    for (k = 0; k <= 3000; ++k) { /* the timer interrupt, once per millisecond */
        pihyst_flags flags;
        double y_d = desired_um(k);
        double volts = pihyst_bw_compensator_step(&comp, y_d, &flags);
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
    /* The first ticks move from 0 V towards the 2 um start at 0.5 V per tick
     * (PIHYST_COMP_SLEW); after that every sample is met. */
    printf("%d of 3001 samples slew-limited (the start), %d out of reach, %d outside the "
           "limits; every other sample met to %.1e um\n",
           slewed, out_of_reach, limits_broken, worst);
    return out_of_reach == 0 && limits_broken == 0 && worst < 1e-9 && slewed < 10 ? 0 : 1;
}
