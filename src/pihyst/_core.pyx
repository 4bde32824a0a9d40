# cython: boundscheck=False, wraparound=False
"""The only code that touches the C core. Private: use pihyst.model instead.

Every public method checks lengths and contiguity before it calls C, and
copies what it is given, so the caller's arrays are never modified.
"""
import numpy as np

cdef extern from "pihyst.h" nogil:
    int PIHYST_ABI_VERSION
    ctypedef enum pihyst_status:
        PIHYST_OK
    ctypedef enum pihyst_family:
        PIHYST_CLASSICAL
        PIHYST_MULTISLOPE
        PIHYST_PWL
    ctypedef struct pihyst_shape:
        double U
        double a
        double b
        double h
    ctypedef struct pihyst_pwl:
        const size_t *rise_start
        const double *rise_x
        const double *rise_y
        const size_t *fall_start
        const double *fall_x
        const double *fall_y
    ctypedef struct pihyst_model:
        size_t n_ops
        double *state
    size_t PIHYST_COEF_LEN(size_t n_ops)
    pihyst_status pihyst_model_init(pihyst_model *m, pihyst_family family, size_t n_ops,
                                    const double *thresholds, const double *weights,
                                    double offset, double u_min, double u_max,
                                    const pihyst_shape *shape, const pihyst_pwl *pwl,
                                    double *coef, double *state, const double *initial_state)
    void pihyst_model_reset(pihyst_model *m, const double *initial_state)
    double pihyst_model_step(pihyst_model *m, double u)
    void pihyst_model_run(pihyst_model *m, const double *u, double *y, size_t n)
    void pihyst_model_operators(pihyst_model *m, const double *u, double *phi, size_t n)
    void pihyst_model_gram(pihyst_model *m, const double *u, const double *d, size_t n,
                           double *gram, double *rhs, double *sums)
    void pihyst_model_envelopes(const pihyst_model *m, double u, double *rise, double *fall)
    const char *pihyst_status_text(pihyst_status status)

ABI_VERSION = PIHYST_ABI_VERSION
FAMILIES = {"classical": PIHYST_CLASSICAL, "multislope": PIHYST_MULTISLOPE, "pwl": PIHYST_PWL}


class CoreError(ValueError):
    """The C core rejected the parameters; the message says why."""


def _vector(x, n=None, name="array"):
    a = np.ascontiguousarray(x, dtype=np.float64)
    if a.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {a.shape}")
    if n is not None and a.shape[0] != n:
        raise ValueError(f"{name} must have {n} values, got {a.shape[0]}")
    return a


cdef class Bank:
    """A validated operator bank with weights, offset and an operator state.

    Holds its own copies of every parameter array; the C struct points into them.
    """
    cdef pihyst_model m
    cdef readonly size_t n_ops
    cdef object _thresholds, _weights, _coef, _state
    cdef object _rise_start, _rise_x, _rise_y, _fall_start, _fall_x, _fall_y

    def __init__(self, str family, thresholds, weights, double offset, double u_min,
                 double u_max, shape=None, rising=None, falling=None, initial_state=None):
        """rising/falling: for family "pwl", lists of K (x, y) breakpoint arrays."""
        cdef pihyst_shape c_shape
        cdef pihyst_pwl c_pwl
        cdef const double[::1] thr_v, w_v, init_v
        cdef double[::1] coef_v, state_v
        cdef const size_t[::1] rs_v, fs_v
        cdef const double[::1] rx_v, ry_v, fx_v, fy_v
        cdef const double *thr_p = NULL
        cdef const double *init_p = NULL
        cdef pihyst_shape *shape_p = NULL
        cdef pihyst_pwl *pwl_p = NULL
        if family not in FAMILIES:
            raise ValueError(f"unknown family {family!r}; expected one of {sorted(FAMILIES)}")
        self._weights = _vector(weights, name="weights").copy()
        self.n_ops = self._weights.shape[0]
        if self.n_ops == 0:
            raise CoreError("a model needs at least one operator")
        self._coef = np.zeros(4 * self.n_ops)
        self._state = np.zeros(self.n_ops)
        if family != "pwl":
            self._thresholds = _vector(thresholds, self.n_ops, "thresholds").copy()
            thr_v = self._thresholds
            thr_p = &thr_v[0]
        if family == "multislope":
            c_shape.U, c_shape.a, c_shape.b, c_shape.h = shape
            shape_p = &c_shape
        if family == "pwl":
            if len(rising) != self.n_ops or len(falling) != self.n_ops:
                raise ValueError("pwl needs one rising and one falling polyline per weight")
            self._rise_start, self._rise_x, self._rise_y = _concat(rising, "rising")
            self._fall_start, self._fall_x, self._fall_y = _concat(falling, "falling")
            rs_v = self._rise_start
            fs_v = self._fall_start
            rx_v = self._rise_x
            ry_v = self._rise_y
            fx_v = self._fall_x
            fy_v = self._fall_y
            c_pwl.rise_start = &rs_v[0]
            c_pwl.rise_x = &rx_v[0]
            c_pwl.rise_y = &ry_v[0]
            c_pwl.fall_start = &fs_v[0]
            c_pwl.fall_x = &fx_v[0]
            c_pwl.fall_y = &fy_v[0]
            pwl_p = &c_pwl
        if initial_state is not None:
            init_arr = _vector(initial_state, self.n_ops, "initial_state")
            init_v = init_arr
            init_p = &init_v[0]
        w_v = self._weights
        coef_v = self._coef
        state_v = self._state
        status = pihyst_model_init(&self.m, FAMILIES[family], self.n_ops, thr_p, &w_v[0],
                                   offset, u_min, u_max, shape_p, pwl_p, &coef_v[0],
                                   &state_v[0], init_p)
        if status != PIHYST_OK:
            raise CoreError(pihyst_status_text(status).decode())

    @property
    def state(self):
        """A copy of the operator outputs f_k[t-1]."""
        return self._state.copy()

    @state.setter
    def state(self, value):
        cdef const double[::1] v = _checked_state(value, self.n_ops)
        pihyst_model_reset(&self.m, &v[0])

    def reset(self, initial_state=None):
        cdef const double[::1] v
        if initial_state is None:
            pihyst_model_reset(&self.m, NULL)
        else:
            v = _checked_state(initial_state, self.n_ops)
            pihyst_model_reset(&self.m, &v[0])

    def step(self, double u):
        return pihyst_model_step(&self.m, u)

    def run(self, u):
        cdef const double[::1] u_v = _vector(u, name="u")
        y = np.empty(u_v.shape[0])
        cdef double[::1] y_v = y
        if u_v.shape[0]:
            with nogil:
                pihyst_model_run(&self.m, &u_v[0], &y_v[0], u_v.shape[0])
        return y

    def operators(self, u):
        cdef const double[::1] u_v = _vector(u, name="u")
        phi = np.empty((u_v.shape[0], self.n_ops))
        cdef double[:, ::1] phi_v = phi
        if u_v.shape[0]:
            with nogil:
                pihyst_model_operators(&self.m, &u_v[0], &phi_v[0, 0], u_v.shape[0])
        return phi

    def gram(self, u, d):
        """(Phi^T Phi, Phi^T d, Phi^T 1) over the record, advancing the state."""
        cdef const double[::1] u_v = _vector(u, name="u")
        cdef const double[::1] d_v = _vector(d, u_v.shape[0], "d")
        gram = np.zeros((self.n_ops, self.n_ops))
        rhs = np.zeros(self.n_ops)
        sums = np.zeros(self.n_ops)
        cdef double[:, ::1] g_v = gram
        cdef double[::1] r_v = rhs
        cdef double[::1] s_v = sums
        if u_v.shape[0]:
            with nogil:
                pihyst_model_gram(&self.m, &u_v[0], &d_v[0], u_v.shape[0], &g_v[0, 0], &r_v[0],
                                  &s_v[0])
        return gram, rhs, sums

    def envelopes(self, double u):
        """(R_k(u), F_k(u)) for every operator."""
        rise = np.empty(self.n_ops)
        fall = np.empty(self.n_ops)
        cdef double[::1] r_v = rise
        cdef double[::1] f_v = fall
        pihyst_model_envelopes(&self.m, u, &r_v[0], &f_v[0])
        return rise, fall


def _checked_state(value, n):
    v = _vector(value, n, "state")
    if not np.all(np.isfinite(v)):
        raise ValueError("state must be finite")
    return v


def _concat(polylines, name):
    # (no negative indexing here: this module is compiled with wraparound=False)
    starts = [0]
    xs, ys = [], []
    total = 0
    for k, (x, y) in enumerate(polylines):
        x = _vector(x, name=f"{name}[{k}] x")
        y = _vector(y, x.shape[0], f"{name}[{k}] y")
        if x.shape[0] == 0:
            raise CoreError(f"{name}[{k}] has no breakpoints")
        xs.append(x)
        ys.append(y)
        total += x.shape[0]
        starts.append(total)
    return (np.asarray(starts, dtype=np.uintp), np.ascontiguousarray(np.concatenate(xs)),
            np.ascontiguousarray(np.concatenate(ys)))
