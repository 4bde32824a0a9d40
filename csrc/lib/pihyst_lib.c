/* pihyst_lib.c - the shared library's plain C ABI over the core (pihyst_lib.h).
 * Unlike the core, it allocates: each handle owns copies of the parameters it was given.
 */
#include "pihyst_lib.h"

#include "pihyst.h"
#include "pihyst_boucwen.h"
#include "pihyst_creep.h"
#include "pihyst_bw_creep.h"

#include <locale.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

struct pihyst_lib_model {
    size_t n_ops;
    double *buffer; /* every double array below points into it */
    size_t *starts; /* rise_start (K + 1) then fall_start (K + 1), pwl only */
    pihyst_params params;
    double *initial_state;
    double *coef;
    double *state;
    pihyst_model model;
    double *scratch;
    pihyst_compensator comp;
    int comp_started;
    int boucwen;                /* a Bouc-Wen model: the members below, not those above */
    pihyst_bw_model bw;
    pihyst_bw_compensator bw_comp;
    double bw_initial[2];       /* (u, z) */
    size_t n_lags;              /* creep lags (0: none), at the fixed interval */
    double *creep_buffer;       /* tau, gain, alpha, state: n_lags values each */
    pihyst_creep creep;
};

#define BOUCWEN_FAMILY 3 /* the flat file's family code */
#define BOUCWEN_STATE_LEN 2
#define MAX_CREEP_LAGS 4096 /* a flat file's creep line with more is not a model's */

int32_t pihyst_lib_abi_version(void) { return PIHYST_LIB_ABI_VERSION; }

const char *pihyst_lib_status_text(int32_t status)
{
    switch (status) {
    case PIHYST_LIB_ENOMEM: return "out of memory";
    case PIHYST_LIB_EFILE: return "the model file cannot be opened or read";
    case PIHYST_LIB_EFORMAT: return "not a pihyst flat model file (pihyst export --flat)";
    case PIHYST_LIB_ENOCOMPENSATOR: return "compensator not started "
                                           "(pihyst_lib_compensator_start)";
    case PIHYST_LIB_ELENGTH: return "a length is negative or does not match the model";
    case PIHYST_LIB_EINPUT: return "an input sample is NaN or outside the input range";
    default:
        if (status <= PIHYST_LIB_ECREEP_BASE + PIHYST_CREEP_ENULL &&
            status >= PIHYST_LIB_ECREEP_BASE + PIHYST_CREEP_EDT)
            return pihyst_creep_status_text(
                (pihyst_creep_status)(status - PIHYST_LIB_ECREEP_BASE));
        return pihyst_status_text((pihyst_status)status);
    }
}

static void set_status(int32_t *status, int32_t value)
{
    if (status) *status = value;
}

void pihyst_lib_free(pihyst_lib_model *h)
{
    if (!h) return;
    free(h->buffer);
    free(h->starts);
    free(h->scratch);
    free(h->creep_buffer);
    free(h);
}

static int all_finite(const double *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

pihyst_lib_model *pihyst_lib_create(int32_t family, int32_t n_ops, const double *thresholds,
                                    const double *weights, double offset, double u_min,
                                    double u_max, const double *shape, const int32_t *rise_len,
                                    const double *rise_x, const double *rise_y,
                                    const int32_t *fall_len, const double *fall_x,
                                    const double *fall_y, const double *initial_state,
                                    int32_t *status)
{
    static const double paper_shape[4] = {150.0, 0.8, 1.2, 0.5};
    pihyst_lib_model *h;
    size_t k, i, n_rise = 0, n_fall = 0, total;
    double *p;
    pihyst_status s;

    if (n_ops <= 0) {
        set_status(status, PIHYST_ESIZE);
        return NULL;
    }
    if (family < PIHYST_CLASSICAL || family > PIHYST_PWL) {
        set_status(status, PIHYST_EFAMILY);
        return NULL;
    }
    if (!weights || (family != PIHYST_PWL && !thresholds) ||
        (family == PIHYST_PWL && (!rise_len || !rise_x || !rise_y || !fall_len || !fall_x ||
                                  !fall_y))) {
        set_status(status, PIHYST_ENULL);
        return NULL;
    }
    k = (size_t)n_ops;
    if (family == PIHYST_PWL) {
        for (i = 0; i < k; ++i) {
            if (rise_len[i] <= 0 || fall_len[i] <= 0) {
                set_status(status, PIHYST_ESIZE);
                return NULL;
            }
            n_rise += (size_t)rise_len[i];
            n_fall += (size_t)fall_len[i];
        }
    }
    h = calloc(1, sizeof *h);
    /* thresholds, weights, initial state, coef, state, then the polyline points */
    total = 3 * k + PIHYST_COEF_LEN(k) + k + 2 * (n_rise + n_fall);
    if (h) h->buffer = malloc(total * sizeof(double));
    if (h && family == PIHYST_PWL) h->starts = malloc(2 * (k + 1) * sizeof(size_t));
    if (!h || !h->buffer || (family == PIHYST_PWL && !h->starts)) {
        pihyst_lib_free(h);
        set_status(status, PIHYST_LIB_ENOMEM);
        return NULL;
    }
    h->n_ops = k;
    p = h->buffer;
    if (thresholds && family != PIHYST_PWL) memcpy(p, thresholds, k * sizeof *p);
    else memset(p, 0, k * sizeof *p);
    h->params.thresholds = family == PIHYST_PWL ? NULL : p;
    p += k;
    memcpy(p, weights, k * sizeof *p);
    h->params.weights = p;
    p += k;
    if (initial_state) memcpy(p, initial_state, k * sizeof *p);
    else memset(p, 0, k * sizeof *p);
    h->initial_state = p;
    p += k;
    h->coef = p;
    p += PIHYST_COEF_LEN(k);
    h->state = p;
    p += k;
    if (family == PIHYST_PWL) {
        size_t *rs = h->starts, *fs = h->starts + k + 1;
        rs[0] = fs[0] = 0;
        for (i = 0; i < k; ++i) {
            rs[i + 1] = rs[i] + (size_t)rise_len[i];
            fs[i + 1] = fs[i] + (size_t)fall_len[i];
        }
        memcpy(p, rise_x, n_rise * sizeof *p);
        memcpy(p + n_rise, rise_y, n_rise * sizeof *p);
        memcpy(p + 2 * n_rise, fall_x, n_fall * sizeof *p);
        memcpy(p + 2 * n_rise + n_fall, fall_y, n_fall * sizeof *p);
        h->params.pwl.rise_start = rs;
        h->params.pwl.rise_x = p;
        h->params.pwl.rise_y = p + n_rise;
        h->params.pwl.fall_start = fs;
        h->params.pwl.fall_x = p + 2 * n_rise;
        h->params.pwl.fall_y = p + 2 * n_rise + n_fall;
    }
    if (!shape) shape = paper_shape;
    h->params.family = (pihyst_family)family;
    h->params.n_ops = k;
    h->params.offset = offset;
    h->params.u_min = u_min;
    h->params.u_max = u_max;
    h->params.shape.U = shape[0];
    h->params.shape.a = shape[1];
    h->params.shape.b = shape[2];
    h->params.shape.h = shape[3];
    h->params.initial_state = h->initial_state;
    s = pihyst_model_init(&h->model, &h->params, h->coef, h->state);
    if (s != PIHYST_OK) {
        pihyst_lib_free(h);
        set_status(status, s);
        return NULL;
    }
    set_status(status, PIHYST_OK);
    return h;
}

pihyst_lib_model *pihyst_lib_create_boucwen(const double *params, int32_t *status)
{
    pihyst_lib_model *h;
    pihyst_bw_params p;
    pihyst_status s;
    if (!params) {
        set_status(status, PIHYST_ENULL);
        return NULL;
    }
    p.beta = params[0];
    p.gamma = params[1];
    p.n = params[2];
    p.hysteretic = params[3];
    p.linear = params[4];
    p.quadratic = params[5];
    p.offset = params[6];
    p.u_min = params[7];
    p.u_max = params[8];
    p.initial_u = params[9];
    p.initial_z = params[10];
    h = calloc(1, sizeof *h);
    if (!h) {
        set_status(status, PIHYST_LIB_ENOMEM);
        return NULL;
    }
    s = pihyst_bw_init(&h->bw, &p);
    if (s != PIHYST_OK) {
        pihyst_lib_free(h);
        set_status(status, s);
        return NULL;
    }
    h->boucwen = 1;
    h->n_ops = 1;
    h->bw_initial[0] = p.initial_u;
    h->bw_initial[1] = p.initial_z;
    set_status(status, PIHYST_OK);
    return h;
}

/* ---------------------------------------------------------------- creep */

/* H = offset + sum_k w_k f_k: the hysteresis output of the operator state, where the
 * creep lags settle (pihyst_creep.h) */
static double hysteresis_output(const pihyst_lib_model *h)
{
    size_t k;
    double sum = 0.0;
    if (h->boucwen) return pihyst_bw_output(&h->bw, h->bw.u, h->bw.z);
    for (k = 0; k < h->n_ops; ++k) sum += h->params.weights[k] * h->state[k];
    return h->params.offset + sum;
}

int32_t pihyst_lib_set_creep(pihyst_lib_model *h, const double *tau, const double *gain,
                             int32_t n, double dt)
{
    size_t k;
    double *buffer;
    pihyst_creep lags;
    pihyst_creep_status s;
    if (!h) return PIHYST_ENULL;
    if (n < 0) return PIHYST_LIB_ELENGTH;
    if (n > 0 && (!tau || !gain)) return PIHYST_ENULL;
    if (n == 0) {
        h->comp_started = 0;
        free(h->creep_buffer);
        h->creep_buffer = NULL;
        h->n_lags = 0;
        return PIHYST_OK;
    }
    k = (size_t)n;
    buffer = malloc(4 * k * sizeof *buffer);
    if (!buffer) return PIHYST_LIB_ENOMEM;
    memcpy(buffer, tau, k * sizeof *buffer);
    memcpy(buffer + k, gain, k * sizeof *buffer);
    s = pihyst_creep_init(&lags, k, buffer, buffer + k, dt, buffer + 2 * k, buffer + 3 * k,
                          NULL);
    if (s != PIHYST_CREEP_OK) {
        free(buffer);
        return PIHYST_LIB_ECREEP_BASE + s;
    }
    free(h->creep_buffer);
    h->creep_buffer = buffer;
    h->creep = lags;
    h->n_lags = k;
    h->comp_started = 0;
    pihyst_creep_settle(&h->creep, hysteresis_output(h));
    return PIHYST_OK;
}

int32_t pihyst_lib_n_creep_lags(const pihyst_lib_model *h)
{
    return h ? (int32_t)h->n_lags : PIHYST_ENULL;
}

int32_t pihyst_lib_get_creep_state(const pihyst_lib_model *h, double *z, int32_t n)
{
    if (!h || (n > 0 && !z)) return PIHYST_ENULL;
    if (n != (int32_t)h->n_lags) return PIHYST_LIB_ELENGTH;
    if (n > 0) memcpy(z, h->creep.state, h->n_lags * sizeof *z);
    return PIHYST_OK;
}

int32_t pihyst_lib_set_creep_state(pihyst_lib_model *h, const double *z, int32_t n)
{
    if (!h) return PIHYST_ENULL;
    if (z && n != (int32_t)h->n_lags) return PIHYST_LIB_ELENGTH;
    if (z && !all_finite(z, h->n_lags)) return PIHYST_ENONFINITE;
    if (h->n_lags == 0) return PIHYST_OK;
    if (z) memcpy(h->creep.state, z, h->n_lags * sizeof *z);
    else pihyst_creep_settle(&h->creep, hysteresis_output(h));
    return PIHYST_OK;
}

/* ---------------------------------------------------------------- flat model files */

/* One number of the file, read whatever the process's LC_NUMERIC: the file always has
 * '.' as the decimal point (strtod reads the locale's). */
static int read_number(FILE *f, double *out)
{
    char token[64], *end;
    const char *point = localeconv()->decimal_point;
    size_t i;
    if (fscanf(f, "%63s", token) != 1) return 0;
    if (point && point[0] && point[0] != '.')
        for (i = 0; token[i]; ++i)
            if (token[i] == '.') token[i] = point[0];
    *out = strtod(token, &end);
    return *end == '\0' && isfinite(*out);
}

static int read_numbers(FILE *f, double *out, size_t n)
{
    size_t i;
    for (i = 0; i < n; ++i)
        if (!read_number(f, &out[i])) return 0;
    return 1;
}

static int read_count(FILE *f, int32_t *out)
{
    long v;
    if (fscanf(f, "%ld", &v) != 1 || v <= 0 || v > 100000000L) return 0;
    *out = (int32_t)v;
    return 1;
}

/* The lines after the model's numbers, each at most once: "creep n tau_1..tau_n
 * g_1..g_n dt" (the lags, into *tail: 2n values tau then gain, freed by the caller) and
 * "delay d" (the caller applies a delay: read and ignored). Files of version 1 have at
 * most the delay line. */
typedef struct {
    int32_t n_lags;
    double *lags;
    double dt;
} flat_tail;

static int read_tail(FILE *f, flat_tail *tail)
{
    char word[16];
    int got, delay_seen = 0;
    while ((got = fscanf(f, "%15s", word)) == 1) {
        if (strcmp(word, "delay") == 0 && !delay_seen) {
            long d;
            if (fscanf(f, "%ld", &d) != 1 || d < 0) return 0;
            delay_seen = 1;
        } else if (strcmp(word, "creep") == 0 && !tail->lags) {
            if (!read_count(f, &tail->n_lags) || tail->n_lags > MAX_CREEP_LAGS) return 0;
            tail->lags = malloc(2 * (size_t)tail->n_lags * sizeof *tail->lags);
            if (!tail->lags || !read_numbers(f, tail->lags, 2 * (size_t)tail->n_lags) ||
                !read_number(f, &tail->dt))
                return 0;
        } else {
            return 0;
        }
    }
    return got == EOF;
}

/* h with the tail's creep lags (h itself without them); NULL, with the lags' status,
 * when they are invalid (h is freed). */
static pihyst_lib_model *with_creep_of(pihyst_lib_model *h, const flat_tail *tail,
                                       int32_t *status)
{
    int32_t s;
    if (!h || !tail->n_lags) return h;
    s = pihyst_lib_set_creep(h, tail->lags, tail->lags + tail->n_lags, tail->n_lags, tail->dt);
    if (s == PIHYST_OK) return h;
    pihyst_lib_free(h);
    set_status(status, s);
    return NULL;
}

pihyst_lib_model *pihyst_lib_load(const char *path, int32_t *status)
{
    FILE *f;
    char magic[16];
    int version = 0;
    int32_t family = -1, k = 0, i, *rise_len = NULL, *fall_len = NULL;
    double head[3], shape[4], *thr = NULL, *w = NULL, *s0 = NULL, *pts = NULL;
    size_t n_pts = 0, cap = 0;
    int ok;
    pihyst_lib_model *h = NULL;
    flat_tail tail = {0, NULL, 0.0};

    if (!path) {
        set_status(status, PIHYST_ENULL);
        return NULL;
    }
    f = fopen(path, "r");
    if (!f) {
        set_status(status, PIHYST_LIB_EFILE);
        return NULL;
    }
    ok = fscanf(f, "%15s %d", magic, &version) == 2 && strcmp(magic, "pihyst-flat") == 0 &&
         (version == 1 || version == 2) && fscanf(f, "%d", &family) == 1 &&
         read_count(f, &k) &&
         read_numbers(f, head, 3);
    if (ok && family == BOUCWEN_FAMILY) {
        /* "offset u_min u_max", "beta gamma n", "hysteretic linear quadratic", "u z" */
        double bw[11];
        ok = k == 1 && read_numbers(f, bw, 3) && read_numbers(f, bw + 3, 3) &&
             read_numbers(f, bw + 9, 2) && read_tail(f, &tail);
        fclose(f);
        if (!ok) {
            free(tail.lags);
            set_status(status, PIHYST_LIB_EFORMAT);
            return NULL;
        }
        bw[6] = head[0];
        bw[7] = head[1];
        bw[8] = head[2];
        h = pihyst_lib_create_boucwen(bw, status);
        h = with_creep_of(h, &tail, status);
        free(tail.lags);
        return h;
    }
    ok = ok && read_numbers(f, shape, 4);
    if (ok) {
        thr = malloc((size_t)k * sizeof *thr);
        w = malloc((size_t)k * sizeof *w);
        s0 = malloc((size_t)k * sizeof *s0);
        rise_len = malloc((size_t)k * sizeof *rise_len);
        fall_len = malloc((size_t)k * sizeof *fall_len);
        ok = thr && w && s0 && rise_len && fall_len;
    }
    if (ok && family == PIHYST_PWL) {
        /* 2K polylines "n x_1..x_n y_1..y_n": the x and y of each stored side by side */
        for (i = 0; ok && i < 2 * k; ++i) {
            int32_t n;
            ok = read_count(f, &n);
            if (!ok) break;
            if (n_pts + 2 * (size_t)n > cap) {
                double *grown;
                cap = 2 * (cap + 2 * (size_t)n);
                grown = realloc(pts, cap * sizeof *pts);
                if (!grown) {
                    ok = 0;
                    break;
                }
                pts = grown;
            }
            ok = read_numbers(f, pts + n_pts, 2 * (size_t)n);
            n_pts += 2 * (size_t)n;
            if (i < k) rise_len[i] = n;
            else fall_len[i - k] = n;
        }
    } else if (ok) {
        ok = read_numbers(f, thr, (size_t)k);
    }
    ok = ok && read_numbers(f, w, (size_t)k) && read_numbers(f, s0, (size_t)k) &&
         read_tail(f, &tail);
    fclose(f);
    if (ok && family == PIHYST_PWL) {
        /* regroup [x y] per polyline into the concatenated x and y arrays create wants */
        size_t n_rise = 0, n_fall = 0, at = 0, r = 0, q = 0;
        double *xy = malloc(n_pts * sizeof *xy);
        for (i = 0; i < k; ++i) n_rise += (size_t)rise_len[i];
        for (i = 0; i < k; ++i) n_fall += (size_t)fall_len[i];
        if (!xy) {
            ok = 0;
        } else {
            for (i = 0; i < 2 * k; ++i) {
                size_t n = (size_t)(i < k ? rise_len[i] : fall_len[i - k]);
                double *x = i < k ? xy + r : xy + 2 * n_rise + q;
                double *y = i < k ? xy + n_rise + r : xy + 2 * n_rise + n_fall + q;
                memcpy(x, pts + at, n * sizeof *x);
                memcpy(y, pts + at + n, n * sizeof *y);
                at += 2 * n;
                if (i < k) r += n;
                else q += n;
            }
            h = pihyst_lib_create(family, k, NULL, w, head[0], head[1], head[2], shape,
                                  rise_len, xy, xy + n_rise, fall_len, xy + 2 * n_rise,
                                  xy + 2 * n_rise + n_fall, s0, status);
            free(xy);
        }
    } else if (ok) {
        h = pihyst_lib_create(family, k, thr, w, head[0], head[1], head[2], shape, NULL, NULL,
                              NULL, NULL, NULL, NULL, s0, status);
    }
    h = with_creep_of(h, &tail, status);
    if (!ok) set_status(status, PIHYST_LIB_EFORMAT);
    free(tail.lags);
    free(thr);
    free(w);
    free(s0);
    free(rise_len);
    free(fall_len);
    free(pts);
    return h;
}

/* ---------------------------------------------------------------- running */

int32_t pihyst_lib_n_operators(const pihyst_lib_model *h)
{
    return h ? (int32_t)h->n_ops : PIHYST_ENULL;
}

int32_t pihyst_lib_predict(pihyst_lib_model *h, const double *u, double *y, int32_t n)
{
    int32_t t;
    if (!h || (n > 0 && (!u || !y))) return PIHYST_ENULL;
    if (n < 0) return PIHYST_LIB_ELENGTH;
    if (h->boucwen) {
        for (t = 0; t < n; ++t)
            if (!(u[t] >= h->bw.u_min && u[t] <= h->bw.u_max)) return PIHYST_LIB_EINPUT;
        h->comp_started = 0;
        if (h->n_lags) pihyst_bw_creep_run(&h->creep, &h->bw, u, NULL, y, (size_t)n);
        else pihyst_bw_run(&h->bw, u, y, (size_t)n);
        return PIHYST_OK;
    }
    for (t = 0; t < n; ++t)
        if (!(u[t] >= h->model.u_min && u[t] <= h->model.u_max)) return PIHYST_LIB_EINPUT;
    h->comp_started = 0;
    pihyst_model_run(&h->model, u, y, (size_t)n);
    if (h->n_lags) pihyst_creep_run(&h->creep, y, NULL, y, (size_t)n); /* y = (C3) of H */
    return PIHYST_OK;
}

int32_t pihyst_lib_get_state(const pihyst_lib_model *h, double *state, int32_t n)
{
    if (!h || !state) return PIHYST_ENULL;
    if (h->boucwen) {
        if (n != BOUCWEN_STATE_LEN) return PIHYST_LIB_ELENGTH;
        state[0] = h->bw.u;
        state[1] = h->bw.z;
        return PIHYST_OK;
    }
    if (n != (int32_t)h->n_ops) return PIHYST_LIB_ELENGTH;
    memcpy(state, h->state, h->n_ops * sizeof *state);
    return PIHYST_OK;
}

int32_t pihyst_lib_reset(pihyst_lib_model *h, const double *state, int32_t n)
{
    if (!h) return PIHYST_ENULL;
    if (h->boucwen) {
        const double *s = state ? state : h->bw_initial;
        pihyst_status status;
        if (state && n != BOUCWEN_STATE_LEN) return PIHYST_LIB_ELENGTH;
        status = pihyst_bw_reset(&h->bw, s[0], s[1]);
        if (status != PIHYST_OK) return status;
        h->comp_started = 0;
        if (h->n_lags) pihyst_creep_settle(&h->creep, hysteresis_output(h));
        return PIHYST_OK;
    }
    if (state && n != (int32_t)h->n_ops) return PIHYST_LIB_ELENGTH;
    if (state && !all_finite(state, h->n_ops)) return PIHYST_ENONFINITE;
    h->comp_started = 0;
    pihyst_model_reset(&h->model, state ? state : h->initial_state);
    if (h->n_lags) pihyst_creep_settle(&h->creep, hysteresis_output(h));
    return PIHYST_OK;
}

int32_t pihyst_lib_compensator_start(pihyst_lib_model *h, double u_min, double u_max,
                                     double max_step, double u_initial)
{
    size_t len;
    pihyst_status s;
    if (!h) return PIHYST_ENULL;
    if (!(max_step > 0) || isinf(max_step)) max_step = INFINITY;
    if (h->boucwen) {
        h->comp_started = 0;
        s = pihyst_bw_compensator_init(&h->bw_comp, &h->bw, u_min, u_max, max_step, u_initial);
        if (s != PIHYST_OK) return s;
        if (h->n_lags) pihyst_creep_settle(&h->creep, h->bw_comp.y_last);
        h->comp_started = 1;
        return PIHYST_OK;
    }
    len = pihyst_compensator_scratch_len(&h->model);
    free(h->scratch);
    h->scratch = malloc(len * sizeof *h->scratch);
    h->comp_started = 0;
    if (!h->scratch) return PIHYST_LIB_ENOMEM;
    s = pihyst_compensator_init(&h->comp, &h->model, u_min, u_max, max_step, u_initial,
                                h->scratch, len);
    if (s != PIHYST_OK) return s;
    if (h->n_lags) pihyst_creep_settle(&h->creep, h->comp.y_last);
    h->comp_started = 1;
    return PIHYST_OK;
}

int32_t pihyst_lib_compensate(pihyst_lib_model *h, const double *y_desired, double *u,
                              uint8_t *flags, int32_t n)
{
    if (!h || (n > 0 && (!y_desired || !u))) return PIHYST_ENULL;
    if (n < 0) return PIHYST_LIB_ELENGTH;
    if (!h->comp_started) return PIHYST_LIB_ENOCOMPENSATOR;
    if (h->boucwen && h->n_lags)
        return (int32_t)pihyst_bw_creep_compensator_run(&h->creep, &h->bw_comp, y_desired,
                                                        NULL, u, NULL, flags, (size_t)n);
    if (h->boucwen)
        return (int32_t)pihyst_bw_compensator_run(&h->bw_comp, y_desired, u, NULL, flags,
                                                  (size_t)n);
    if (h->n_lags)
        return (int32_t)pihyst_creep_compensator_run(&h->creep, &h->comp, y_desired, NULL, u,
                                                     NULL, flags, (size_t)n);
    return (int32_t)pihyst_compensator_run(&h->comp, y_desired, u, NULL, flags, (size_t)n);
}
