# cython: boundscheck=False, wraparound=False
"""The binding of the C core's Bouc-Wen model and compensator (csrc/pihyst_boucwen.h),
with creep (csrc/pihyst_bw_creep.h).
Private: use pihyst.model.BoucWenModel and pihyst.inverse.BoucWenCompensator instead.

Every method checks lengths before it calls C and copies what it is given.
"""
import numpy as np

cdef extern from "pihyst.h" nogil:
    ctypedef enum pihyst_status:
        PIHYST_OK
    ctypedef unsigned char pihyst_flags

cdef extern from "pihyst_boucwen.h" nogil:
    const char *pihyst_bw_status_text(pihyst_status status)
    ctypedef struct pihyst_bw_params:
        double beta, gamma, n, hysteretic, linear, quadratic, offset
        double u_min, u_max, initial_u, initial_z
    ctypedef struct pihyst_bw_model:
        double u, z, z_max, h
    ctypedef struct pihyst_bw_compensator:
        pihyst_bw_model *model
        double u_min, u_max, max_step, y_last, scale
    pihyst_status pihyst_bw_init(pihyst_bw_model *m, const pihyst_bw_params *params)
    double pihyst_bw_rest_z(const pihyst_bw_model *m)
    pihyst_status pihyst_bw_reset(pihyst_bw_model *m, double u, double z)
    double pihyst_bw_advance(const pihyst_bw_model *m, double z, double dx)
    double pihyst_bw_output(const pihyst_bw_model *m, double u, double z)
    double pihyst_bw_step(pihyst_bw_model *m, double u)
    void pihyst_bw_run(pihyst_bw_model *m, const double *u, double *y, size_t n)
    pihyst_status pihyst_bw_compensator_init(pihyst_bw_compensator *c, pihyst_bw_model *m,
                                             double u_min, double u_max, double max_step,
                                             double u_initial)
    pihyst_status pihyst_bw_compensator_reset(pihyst_bw_compensator *c, double u, double z,
                                              double u_last)
    double pihyst_bw_compensator_step(pihyst_bw_compensator *c, double y_desired,
                                      pihyst_flags *flags)
    size_t pihyst_bw_compensator_run(pihyst_bw_compensator *c, const double *y_desired,
                                     double *u, double *y, pihyst_flags *flags, size_t n)

cdef extern from "pihyst_creep.h" nogil:
    ctypedef enum pihyst_creep_status:
        PIHYST_CREEP_OK
    ctypedef struct pihyst_creep:
        size_t n
    pihyst_creep_status pihyst_creep_init(pihyst_creep *c, size_t n, const double *tau,
                                          const double *gain, double dt, double *alpha,
                                          double *state, const double *initial_state)
    const char *pihyst_creep_status_text(pihyst_creep_status status)

cdef extern from "pihyst_bw_creep.h" nogil:
    size_t pihyst_bw_creep_compensator_run(pihyst_creep *cr, pihyst_bw_compensator *c,
                                           const double *y_desired, const double *dt,
                                           double *u, double *y, pihyst_flags *flags,
                                           size_t n)


class CoreError(ValueError):
    """The C core rejected the parameters; the message says why."""


cdef _check(pihyst_status status):
    if status != PIHYST_OK:
        raise CoreError(pihyst_bw_status_text(status).decode())


def _vector(x, name):
    a = np.ascontiguousarray(x, dtype=np.float64)
    if a.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {a.shape}")
    return a


cdef class BoucWen:
    """A validated Bouc-Wen model with its state (u, z).

    ``params``: beta, gamma, n, hysteretic, linear, quadratic, offset; ``input_range``
    (u_min, u_max); ``state`` (u, z).
    """
    cdef pihyst_bw_model m

    def __init__(self, double beta, double gamma, double n, double hysteretic, double linear,
                 double quadratic, double offset, input_range, state):
        cdef pihyst_bw_params p
        p.beta, p.gamma, p.n = beta, gamma, n
        p.hysteretic, p.linear, p.quadratic, p.offset = hysteretic, linear, quadratic, offset
        p.u_min, p.u_max = input_range
        p.initial_u, p.initial_z = state
        _check(pihyst_bw_init(&self.m, &p))

    @property
    def state(self):
        """(u, z) after the last input."""
        return (self.m.u, self.m.z)

    @state.setter
    def state(self, value):
        u, z = value
        _check(pihyst_bw_reset(&self.m, u, z))

    @property
    def rest_z(self):
        """z at rest at u_min after a full cycle from z = 0."""
        return pihyst_bw_rest_z(&self.m)

    def advance(self, double z, double dx):
        """z after the normalized input change dx (the state is not changed)."""
        return pihyst_bw_advance(&self.m, z, dx)

    def step(self, double u):
        return pihyst_bw_step(&self.m, u)

    def run(self, u):
        """Outputs for the inputs ``u`` (advancing the state)."""
        cdef const double[::1] u_v = _vector(u, "u")
        cdef Py_ssize_t n = u_v.shape[0]
        y = np.empty(n)
        cdef double[::1] y_v = y
        if n:
            with nogil:
                pihyst_bw_run(&self.m, &u_v[0], &y_v[0], n)
        return y

    def trajectory(self, u):
        """(y, z) for the inputs ``u``: outputs and the Bouc-Wen variable after each."""
        cdef const double[::1] u_v = _vector(u, "u")
        cdef Py_ssize_t n = u_v.shape[0], t
        y = np.empty(n)
        z = np.empty(n)
        cdef double[::1] y_v = y
        cdef double[::1] z_v = z
        with nogil:
            for t in range(n):
                y_v[t] = pihyst_bw_step(&self.m, u_v[t])
                z_v[t] = self.m.z
        return y, z


cdef class BoucWenCompensator:
    """The exact compensator of a :class:`BoucWen` (which it takes over: every voltage it
    chooses advances that model's state)."""
    cdef pihyst_bw_compensator c
    cdef BoucWen model
    cdef readonly unsigned last_flags

    def __init__(self, BoucWen model, double u_min, double u_max, double max_step,
                 double initial_voltage):
        self.model = model
        _check(pihyst_bw_compensator_init(&self.c, &model.m, u_min, u_max, max_step,
                                          initial_voltage))
        self.last_flags = 0

    @property
    def state(self):
        return self.model.state

    @property
    def voltage(self):
        return self.model.m.u

    @property
    def output(self):
        """The model output at the last voltage."""
        return self.c.y_last

    @property
    def limits(self):
        return (self.c.u_min, self.c.u_max)

    def reset(self, state, double voltage):
        """Set the state (u, z), then apply ``voltage``."""
        u, z = state
        _check(pihyst_bw_compensator_reset(&self.c, u, z, voltage))
        self.last_flags = 0

    def step(self, double y_desired):
        cdef pihyst_flags flags
        u = pihyst_bw_compensator_step(&self.c, y_desired, &flags)
        self.last_flags = flags
        return u

    def run(self, y_desired):
        """(voltage, output, flags) arrays for a block of desired outputs."""
        cdef const double[::1] d_v = _vector(y_desired, "y_desired")
        cdef Py_ssize_t n = d_v.shape[0]
        u = np.empty(n)
        y = np.empty(n)
        flags = np.zeros(n, dtype=np.uint8)
        cdef double[::1] u_v = u
        cdef double[::1] y_v = y
        cdef pihyst_flags[::1] f_v = flags
        if n:
            with nogil:
                pihyst_bw_compensator_run(&self.c, &d_v[0], &u_v[0], &y_v[0], &f_v[0], n)
            self.last_flags = f_v[n - 1]
        return u, y, flags


cdef class CreepCompensator:
    """The creep lags of pihyst_creep.h with their state z_i, compensating through a
    :class:`BoucWenCompensator` (csrc/pihyst_bw_creep.h): each sample's hysteresis target
    goes to it, and the lags advance by the output it reached."""
    cdef pihyst_creep c
    cdef readonly size_t n
    cdef object _tau, _gain, _alpha, _state

    def __init__(self, tau, gain, double dt, initial_state):
        cdef const double[::1] tau_v, gain_v, init_v
        cdef double[::1] alpha_v, state_v
        self._tau = _vector(tau, "tau").copy()
        self.n = self._tau.shape[0]
        self._gain = _vector(gain, "gain").copy()
        init = _vector(initial_state, "creep state")
        if self.n == 0 or self._gain.shape[0] != self.n or init.shape[0] != self.n:
            raise ValueError(f"creep needs one gain and one state per time constant "
                             f"({self.n})")
        self._alpha = np.zeros(self.n)
        self._state = np.zeros(self.n)
        tau_v, gain_v, init_v = self._tau, self._gain, init
        alpha_v, state_v = self._alpha, self._state
        status = pihyst_creep_init(&self.c, self.n, &tau_v[0], &gain_v[0], dt, &alpha_v[0],
                                   &state_v[0], &init_v[0])
        if status != PIHYST_CREEP_OK:
            raise CoreError(pihyst_creep_status_text(status).decode())

    @property
    def state(self):
        """A copy of the lag states z_i[t-1]."""
        return self._state.copy()

    def compensate(self, BoucWenCompensator comp, y_desired, dt=None):
        """(voltage, output, flags) for a block of desired outputs of the model with creep
        (intervals ``dt`` per sample, None: the fixed one)."""
        cdef const double[::1] d_v = _vector(y_desired, "y_desired")
        cdef Py_ssize_t n = d_v.shape[0]
        cdef const double[::1] dt_v
        cdef const double *dt_p = NULL
        u = np.empty(n)
        y = np.empty(n)
        flags = np.zeros(n, dtype=np.uint8)
        cdef double[::1] u_v = u
        cdef double[::1] y_v = y
        cdef pihyst_flags[::1] f_v = flags
        if dt is not None:
            dt_v = _vector(dt, "dt")
            if dt_v.shape[0] != n:
                raise ValueError(f"dt must have one interval per sample ({n}), got "
                                 f"{dt_v.shape[0]}")
            dt_p = &dt_v[0] if n else NULL
        if n:
            with nogil:
                pihyst_bw_creep_compensator_run(&self.c, &comp.c, &d_v[0], dt_p, &u_v[0],
                                                &y_v[0], &f_v[0], n)
            comp.last_flags = f_v[n - 1]
        return u, y, flags
