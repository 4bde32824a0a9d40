# cython: boundscheck=False, wraparound=False
"""The only code that touches the C core. Private: use pihyst.model instead.

Every public method checks lengths and contiguity before it calls C, and
copies what it is given, so the caller's arrays are never modified.
"""
import numpy as np

from libc.string cimport memset

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
    ctypedef struct pihyst_params:
        pihyst_family family
        size_t n_ops
        const double *thresholds
        const double *weights
        double offset
        double u_min
        double u_max
        pihyst_shape shape
        pihyst_pwl pwl
        const double *initial_state
    ctypedef struct pihyst_model:
        size_t n_ops
        double *state
    size_t PIHYST_COEF_LEN(size_t n_ops)
    pihyst_status pihyst_model_init(pihyst_model *m, const pihyst_params *params, double *coef,
                                    double *state)
    void pihyst_model_reset(pihyst_model *m, const double *initial_state)
    double pihyst_model_step(pihyst_model *m, double u)
    void pihyst_model_run(pihyst_model *m, const double *u, double *y, size_t n)
    void pihyst_model_operators(pihyst_model *m, const double *u, double *phi, size_t n)
    void pihyst_model_gram(pihyst_model *m, const double *u, const double *d, size_t n,
                           double *gram, double *rhs, double *sums)
    void pihyst_model_envelopes(const pihyst_model *m, double u, double *rise, double *fall)
    const char *pihyst_status_text(pihyst_status status)

ABI_VERSION = PIHYST_ABI_VERSION
# rows of the operator matrix per BLAS update in Bank.gram (K x 2048 doubles: 256 KiB at K = 16)
GRAM_BLOCK = 2048
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
        cdef pihyst_params params
        cdef const double[::1] thr_v, w_v, init_v
        cdef double[::1] coef_v, state_v
        cdef const size_t[::1] rs_v, fs_v
        cdef const double[::1] rx_v, ry_v, fx_v, fy_v
        if family not in FAMILIES:
            raise ValueError(f"unknown family {family!r}; expected one of {sorted(FAMILIES)}")
        self._weights = _vector(weights, name="weights").copy()
        self.n_ops = self._weights.shape[0]
        if self.n_ops == 0:
            raise CoreError("a model needs at least one operator")
        self._coef = _aligned_zeros(4 * self.n_ops)
        self._state = _aligned_zeros(self.n_ops)
        memset(&params, 0, sizeof(params))
        params.family = FAMILIES[family]
        params.n_ops = self.n_ops
        if family != "pwl":
            self._thresholds = _vector(thresholds, self.n_ops, "thresholds").copy()
            thr_v = self._thresholds
            params.thresholds = &thr_v[0]
        if family == "multislope":
            params.shape.U, params.shape.a, params.shape.b, params.shape.h = shape
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
            params.pwl.rise_start = &rs_v[0]
            params.pwl.rise_x = &rx_v[0]
            params.pwl.rise_y = &ry_v[0]
            params.pwl.fall_start = &fs_v[0]
            params.pwl.fall_x = &fx_v[0]
            params.pwl.fall_y = &fy_v[0]
        if initial_state is not None:
            init_arr = _vector(initial_state, self.n_ops, "initial_state")
            init_v = init_arr
            params.initial_state = &init_v[0]
        w_v = self._weights
        coef_v = self._coef
        state_v = self._state
        params.weights = &w_v[0]
        params.offset = offset
        params.u_min = u_min
        params.u_max = u_max
        status = pihyst_model_init(&self.m, &params, &coef_v[0], &state_v[0])
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

    def gram(self, u, d, block=None):
        """(Phi^T Phi, Phi^T d, Phi^T 1) over the record, advancing the state.

        ``block=None``: pihyst_model_gram, the C core's sample-by-sample accumulation (as
        firmware calls it). ``block=n`` (e.g. GRAM_BLOCK): blocked, the C core writes the
        operator matrix of n samples at a time into one reused buffer and NumPy's BLAS
        accumulates G += Phi_b^T Phi_b (a symmetric rank-n update, exactly symmetric),
        rhs += Phi_b^T d_b and the column sums; the same sums ordered by block, so equal
        to rounding, not bit for bit."""
        cdef const double[::1] u_v = _vector(u, name="u")
        cdef const double[::1] d_v = _vector(d, u_v.shape[0], "d")
        cdef Py_ssize_t n = u_v.shape[0], a, z, nb
        cdef double[:, ::1] phi_v
        gram = np.zeros((self.n_ops, self.n_ops))
        rhs = np.zeros(self.n_ops)
        sums = np.zeros(self.n_ops)
        cdef double[:, ::1] g_v = gram
        cdef double[::1] r_v = rhs
        cdef double[::1] s_v = sums
        if block is None:
            if n:
                with nogil:
                    pihyst_model_gram(&self.m, &u_v[0], &d_v[0], n, &g_v[0, 0], &r_v[0],
                                      &s_v[0])
            return gram, rhs, sums
        nb = block
        if nb < 1:
            raise ValueError("block must be >= 1")
        if n == 0:
            return gram, rhs, sums
        d_arr = np.asarray(d_v)
        buf = np.empty((min(nb, n), self.n_ops))
        phi_v = buf
        for a in range(0, n, nb):
            z = min(a + nb, n)
            with nogil:
                pihyst_model_operators(&self.m, &u_v[a], &phi_v[0, 0], z - a)
            phi = buf[:z - a]
            gram += phi.T @ phi
            rhs += phi.T @ d_arr[a:z]
            sums += phi.sum(axis=0)
        return gram, rhs, sums

    def gram_segments(self, u, d, starts, stops, roles):
        """The normal equations of a record cut into consecutive segments, per role,
        advancing the state over each: segment i is u[starts[i]:stops[i]]; roles[i] 0
        only runs the operators (settling), 1 and 2 add the segment's sums to the first
        or second role's. Each segment's (Phi^T Phi, Phi^T d, Phi^T 1) starts from zero
        (pihyst_model_gram) and is then added to its role's, the numbers gram() per
        segment and a running sum give; sum(d) and d^T d are summed sample by sample.
        One call for a cut of thousands of cycles, where a call per segment spent
        20 us of Python on each.

        Returns ((G, rhs, sums, sum of d, d^T d, samples) of role 1, the same of 2)."""
        cdef const double[::1] u_v = _vector(u, name="u")
        cdef const double[::1] d_v = _vector(d, u_v.shape[0], "d")
        cdef const Py_ssize_t[::1] a_v = np.ascontiguousarray(starts, dtype=np.intp)
        cdef const Py_ssize_t[::1] z_v = np.ascontiguousarray(stops, dtype=np.intp)
        cdef const Py_ssize_t[::1] r_v = np.ascontiguousarray(roles, dtype=np.intp)
        cdef Py_ssize_t n_seg = a_v.shape[0], i, a, z, r, j, t, k = self.n_ops, longest = 1
        if z_v.shape[0] != n_seg or r_v.shape[0] != n_seg:
            raise ValueError("starts, stops and roles must have one entry per segment")
        for i in range(n_seg):
            if not (0 <= a_v[i] <= z_v[i] <= u_v.shape[0]) or not (0 <= r_v[i] <= 2):
                raise ValueError(f"segment {i}: [{a_v[i]}, {z_v[i]}) role {r_v[i]} is not "
                                 f"within the record's {u_v.shape[0]} samples and roles 0-2")
            longest = max(longest, z_v[i] - a_v[i])
        gram = np.zeros((2, k, k))
        rhs = np.zeros((2, k))
        sums = np.zeros((2, k))
        data = np.zeros((2, 2))
        counts = np.zeros(2, dtype=np.intp)
        g_seg = np.empty((k, k))
        r_seg = np.empty(k)
        s_seg = np.empty(k)
        settle = np.empty(longest)
        cdef double[:, :, ::1] g_v = gram
        cdef double[:, ::1] rhs_v = rhs
        cdef double[:, ::1] sums_v = sums
        cdef double[:, ::1] data_v = data
        cdef Py_ssize_t[::1] n_v = counts
        cdef double[:, ::1] gs_v = g_seg
        cdef double[::1] rs_v = r_seg
        cdef double[::1] ss_v = s_seg
        cdef double[::1] y_v = settle
        with nogil:
            for i in range(n_seg):
                a, z, r = a_v[i], z_v[i], r_v[i]
                if z == a:
                    continue
                if r == 0:
                    pihyst_model_run(&self.m, &u_v[a], &y_v[0], z - a)
                    continue
                r -= 1
                memset(&gs_v[0, 0], 0, k * k * sizeof(double))
                memset(&rs_v[0], 0, k * sizeof(double))
                memset(&ss_v[0], 0, k * sizeof(double))
                pihyst_model_gram(&self.m, &u_v[a], &d_v[a], z - a, &gs_v[0, 0], &rs_v[0],
                                  &ss_v[0])
                for j in range(k):
                    for t in range(k):
                        g_v[r, j, t] = g_v[r, j, t] + gs_v[j, t]
                    rhs_v[r, j] = rhs_v[r, j] + rs_v[j]
                    sums_v[r, j] = sums_v[r, j] + ss_v[j]
                for t in range(a, z):
                    data_v[r, 0] += d_v[t]
                    data_v[r, 1] += d_v[t] * d_v[t]
                n_v[r] += z - a
        return tuple((gram[q], rhs[q], sums[q], float(data[q, 0]), float(data[q, 1]),
                      int(counts[q])) for q in range(2))

    def envelopes(self, double u):
        """(R_k(u), F_k(u)) for every operator."""
        rise = np.empty(self.n_ops)
        fall = np.empty(self.n_ops)
        cdef double[::1] r_v = rise
        cdef double[::1] f_v = fall
        pihyst_model_envelopes(&self.m, u, &r_v[0], &f_v[0])
        return rise, fall


def _aligned_zeros(n, alignment=64):
    """n zeros starting on a cache line: the C loops store the state and load it back a
    sample later, which is twice as fast when no vector store straddles two lines."""
    buf = np.zeros(n + alignment // 8)
    start = (-buf.ctypes.data % alignment) // 8
    return buf[start:start + n]


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


# ---------------------------------------------------------------- compensator (inverse)

cdef extern from "pihyst.h" nogil:
    ctypedef unsigned char pihyst_flags
    enum:
        PIHYST_COMP_SAT_LOW
        PIHYST_COMP_SAT_HIGH
        PIHYST_COMP_NAN
        PIHYST_COMP_SLEW
    ctypedef struct pihyst_compensator:
        double u_min
        double u_max
        double max_step
        double u_last
        double y_last
        double tol
    size_t pihyst_compensator_scratch_len(const pihyst_model *m)
    pihyst_status pihyst_compensator_init(pihyst_compensator *c, pihyst_model *m, double u_min,
                                          double u_max, double max_step, double u_initial,
                                          double *scratch, size_t scratch_len)
    pihyst_status pihyst_compensator_reset(pihyst_compensator *c, const double *state,
                                           double u_last)
    double pihyst_compensator_step(pihyst_compensator *c, double y_desired, pihyst_flags *flags)
    size_t pihyst_compensator_run(pihyst_compensator *c, const double *y_desired, double *u,
                                  double *y, pihyst_flags *flags, size_t n)

FLAG_SATURATED_LOW = PIHYST_COMP_SAT_LOW
FLAG_SATURATED_HIGH = PIHYST_COMP_SAT_HIGH
FLAG_NAN = PIHYST_COMP_NAN
FLAG_SLEW = PIHYST_COMP_SLEW


cdef class Compensator:
    """Exact streaming inverse of a :class:`Bank` with non-negative weights.

    Takes over ``bank``: every voltage it chooses is applied to the bank's state.
    ``u_min``/``u_max`` are the voltage limits (inside the bank's input range),
    ``max_step`` the largest |u[t] - u[t-1]| (``inf`` for none), ``initial_voltage``
    the voltage before the first sample (applied to the bank's current state).
    """
    cdef pihyst_compensator c
    cdef Bank bank
    cdef object _scratch
    cdef readonly unsigned last_flags

    def __init__(self, Bank bank, double u_min, double u_max, double max_step,
                 double initial_voltage):
        cdef double[::1] s_v
        self.bank = bank
        self._scratch = np.zeros(max(pihyst_compensator_scratch_len(&bank.m), 1))
        s_v = self._scratch
        status = pihyst_compensator_init(&self.c, &bank.m, u_min, u_max, max_step,
                                         initial_voltage, &s_v[0], s_v.shape[0])
        if status != PIHYST_OK:
            raise CoreError(pihyst_status_text(status).decode())
        self.last_flags = 0

    @property
    def state(self):
        """A copy of the operator state (after the last voltage)."""
        return self.bank.state

    @property
    def voltage(self):
        """The last voltage."""
        return self.c.u_last

    @property
    def output(self):
        """The model output at the last voltage."""
        return self.c.y_last

    @property
    def limits(self):
        return (self.c.u_min, self.c.u_max)

    @property
    def max_step(self):
        return self.c.max_step

    @property
    def tolerance(self):
        """|y_d - y| at or below which the voltage holds (rounding of the output)."""
        return self.c.tol

    def reset(self, state, double voltage):
        """Set the operator state (None: zeros) and the last voltage, applying it."""
        cdef const double[::1] v
        cdef const double *p = NULL
        if state is not None:
            v = _vector(state, self.bank.n_ops, "state")
            p = &v[0]
        status = pihyst_compensator_reset(&self.c, p, voltage)
        if status != PIHYST_OK:
            raise CoreError(pihyst_status_text(status).decode())
        self.last_flags = 0

    def step(self, double y_desired):
        """The voltage for one desired output; flags in ``last_flags``."""
        cdef pihyst_flags flags
        u = pihyst_compensator_step(&self.c, y_desired, &flags)
        self.last_flags = flags
        return u

    def run(self, y_desired):
        """(voltage, output, flags) arrays for a block of desired outputs."""
        cdef const double[::1] d_v = _vector(y_desired, name="y_desired")
        cdef Py_ssize_t n = d_v.shape[0]
        u = np.empty(n)
        y = np.empty(n)
        flags = np.zeros(n, dtype=np.uint8)
        cdef double[::1] u_v = u
        cdef double[::1] y_v = y
        cdef pihyst_flags[::1] f_v = flags
        if n:
            with nogil:
                pihyst_compensator_run(&self.c, &d_v[0], &u_v[0], &y_v[0], &f_v[0], n)
            self.last_flags = f_v[n - 1]
        return u, y, flags


# ---------------------------------------------------------------- banks of channels

cdef extern from "pihyst.h" nogil:
    void pihyst_bank_step(pihyst_model *const *models, size_t n, const double *u, double *y)
    size_t pihyst_bank_compensate(pihyst_compensator *const *comps, size_t n,
                                  const double *y_desired, double *u, double *y,
                                  pihyst_flags *flags)


cdef class BankArray:
    """N :class:`Bank` objects stepped together, one input per channel per call.

    Steps the banks' own C structs (no copies), so a channel's state is its bank's.
    """
    cdef readonly tuple banks
    cdef object _ptrs
    cdef readonly Py_ssize_t n

    def __init__(self, banks):
        cdef Bank b
        cdef size_t[::1] p_v
        self.banks = tuple(banks)
        self.n = len(self.banks)
        if len({id(b) for b in self.banks}) != self.n:
            raise ValueError("the channels must be distinct banks")
        self._ptrs = np.zeros(max(self.n, 1), dtype=np.uintp)
        p_v = self._ptrs
        for i, obj in enumerate(self.banks):
            b = <Bank?>obj
            p_v[i] = <size_t>&b.m

    def run(self, u):
        """y[t, i] for u[t, i] (T x N, row t one tick), advancing every channel."""
        u_a = np.ascontiguousarray(u, dtype=np.float64)
        if u_a.ndim != 2 or u_a.shape[1] != self.n:
            raise ValueError(f"input must have shape (T, {self.n}), got {u_a.shape}")
        cdef const double[:, ::1] u_v = u_a
        y = np.empty(u_a.shape)
        cdef double[:, ::1] y_v = y
        cdef size_t[::1] p_v = self._ptrs
        cdef Py_ssize_t t, T = u_a.shape[0]
        if self.n:
            with nogil:
                for t in range(T):
                    pihyst_bank_step(<pihyst_model *const *>&p_v[0], self.n, &u_v[t, 0],
                                     &y_v[t, 0])
        return y


cdef extern from "pihyst.h" nogil:
    ctypedef struct pihyst_modelbank:
        size_t n
        size_t n_fast
    size_t pihyst_modelbank_work_len(pihyst_model *const *models, size_t n)
    pihyst_status pihyst_modelbank_init(pihyst_modelbank *b, pihyst_model *const *models,
                                        size_t n, double *work, size_t work_len)
    void pihyst_modelbank_step(pihyst_modelbank *b, const double *u, double *y)
    void pihyst_modelbank_sync(pihyst_modelbank *b)


cdef class BankSoA:
    """N :class:`Bank` objects stepped from a structure-of-arrays copy of their states
    (pihyst_modelbank): classical banks of K <= 16 L at a time, bit for bit as
    :class:`BankArray`. The banks' states are stale until :meth:`sync`; after a bank is
    stepped or its state set outside this object, call :meth:`reload`."""
    cdef pihyst_modelbank b
    cdef readonly tuple banks
    cdef object _ptrs, _work
    cdef readonly Py_ssize_t n

    def __init__(self, banks):
        cdef Bank bk
        cdef size_t[::1] p_v
        self.banks = tuple(banks)
        self.n = len(self.banks)
        if len({id(bk) for bk in self.banks}) != self.n:
            raise ValueError("the channels must be distinct banks")
        self._ptrs = np.zeros(max(self.n, 1), dtype=np.uintp)
        p_v = self._ptrs
        for i, obj in enumerate(self.banks):
            bk = <Bank?>obj
            p_v[i] = <size_t>&bk.m
        self._work = np.zeros(max(pihyst_modelbank_work_len(
            <pihyst_model *const *>&p_v[0], self.n), 1))
        self.reload()

    def reload(self):
        """Take the banks' current states."""
        cdef size_t[::1] p_v = self._ptrs
        cdef double[::1] w_v = self._work
        status = pihyst_modelbank_init(&self.b, <pihyst_model *const *>&p_v[0], self.n,
                                       &w_v[0], w_v.shape[0])
        if status != PIHYST_OK:
            raise CoreError(pihyst_status_text(status).decode())

    def sync(self):
        """Write the states back to the banks."""
        pihyst_modelbank_sync(&self.b)

    @property
    def n_fast(self):
        """Channels stepped in the structure-of-arrays groups."""
        return self.b.n_fast

    def run(self, u):
        """y[t, i] for u[t, i] (T x N, row t one tick), advancing every channel."""
        u_a = np.ascontiguousarray(u, dtype=np.float64)
        if u_a.ndim != 2 or u_a.shape[1] != self.n:
            raise ValueError(f"input must have shape (T, {self.n}), got {u_a.shape}")
        cdef const double[:, ::1] u_v = u_a
        y = np.empty(u_a.shape)
        cdef double[:, ::1] y_v = y
        cdef Py_ssize_t t, T = u_a.shape[0]
        if self.n:
            with nogil:
                for t in range(T):
                    pihyst_modelbank_step(&self.b, &u_v[t, 0], &y_v[t, 0])
        return y


cdef class CompensatorArray:
    """N :class:`Compensator` objects run together, one desired value per channel per
    call. Steps the compensators' own C structs (no copies)."""
    cdef readonly tuple compensators
    cdef object _ptrs
    cdef readonly Py_ssize_t n

    def __init__(self, compensators):
        cdef Compensator c
        cdef size_t[::1] p_v
        self.compensators = tuple(compensators)
        self.n = len(self.compensators)
        if len({id(c) for c in self.compensators}) != self.n:
            raise ValueError("the channels must be distinct compensators")
        self._ptrs = np.zeros(max(self.n, 1), dtype=np.uintp)
        p_v = self._ptrs
        for i, obj in enumerate(self.compensators):
            c = <Compensator?>obj
            p_v[i] = <size_t>&c.c

    def step_into(self, y_desired, double[::1] u, double[::1] y, pihyst_flags[::1] flags):
        """One tick into caller-owned arrays (N each); returns the count flagged."""
        cdef const double[::1] d_v = _vector(y_desired, self.n, "y_desired")
        cdef size_t[::1] p_v = self._ptrs
        cdef size_t count = 0
        if u.shape[0] != self.n or y.shape[0] != self.n or flags.shape[0] != self.n:
            raise ValueError(f"u, y and flags must have {self.n} values")
        if self.n:
            with nogil:
                count = pihyst_bank_compensate(<pihyst_compensator *const *>&p_v[0], self.n,
                                               &d_v[0], &u[0], &y[0], &flags[0])
            self._set_last_flags(flags)
        return count

    def run(self, y_desired):
        """(u, y, flags), each T x N, for desired values T x N (row t one tick)."""
        d_a = np.ascontiguousarray(y_desired, dtype=np.float64)
        if d_a.ndim != 2 or d_a.shape[1] != self.n:
            raise ValueError(f"y_desired must have shape (T, {self.n}), got {d_a.shape}")
        cdef const double[:, ::1] d_v = d_a
        u = np.empty(d_a.shape)
        y = np.empty(d_a.shape)
        flags = np.zeros(d_a.shape, dtype=np.uint8)
        cdef double[:, ::1] u_v = u
        cdef double[:, ::1] y_v = y
        cdef pihyst_flags[:, ::1] f_v = flags
        cdef size_t[::1] p_v = self._ptrs
        cdef Py_ssize_t t, T = d_a.shape[0]
        if self.n and T:
            with nogil:
                for t in range(T):
                    pihyst_bank_compensate(<pihyst_compensator *const *>&p_v[0], self.n,
                                           &d_v[t, 0], &u_v[t, 0], &y_v[t, 0], &f_v[t, 0])
            self._set_last_flags(flags[T - 1])
        return u, y, flags

    def _set_last_flags(self, flags):
        cdef Compensator c
        for i, obj in enumerate(self.compensators):
            c = <Compensator>obj
            c.last_flags = flags[i]


cdef extern from "pihyst.h" nogil:
    ctypedef struct pihyst_compbank:
        size_t n
        size_t n_ops
        size_t n_fast
    size_t pihyst_compbank_work_len(pihyst_compensator *const *comps, size_t n)
    pihyst_status pihyst_compbank_init(pihyst_compbank *b, pihyst_compensator *const *comps,
                                       size_t n, double *work, size_t work_len)
    size_t pihyst_compbank_compensate(pihyst_compbank *b, const double *y_desired, double *u,
                                      double *y, pihyst_flags *flags)
    void pihyst_compbank_sync(pihyst_compbank *b)


cdef class CompensatorSoA:
    """N :class:`Compensator` objects run from a structure-of-arrays copy of their state
    (pihyst_compbank): classical channels step their exact inverse, vectorized across
    channels; the others, and every tick that would leave a limit, run the compensator.
    The compensators are stale until :meth:`sync`; after a compensator is stepped or
    reset outside this object, call :meth:`reload`."""
    cdef pihyst_compbank b
    cdef readonly tuple compensators
    cdef object _ptrs, _work
    cdef readonly Py_ssize_t n

    def __init__(self, compensators):
        cdef Compensator c
        cdef size_t[::1] p_v
        self.compensators = tuple(compensators)
        self.n = len(self.compensators)
        if len({id(c) for c in self.compensators}) != self.n:
            raise ValueError("the channels must be distinct compensators")
        self._ptrs = np.zeros(max(self.n, 1), dtype=np.uintp)
        p_v = self._ptrs
        for i, obj in enumerate(self.compensators):
            c = <Compensator?>obj
            p_v[i] = <size_t>&c.c
        self._work = np.zeros(max(pihyst_compbank_work_len(
            <pihyst_compensator *const *>&p_v[0], self.n), 1))
        self.reload()

    def reload(self):
        """Take the compensators' current states and voltages."""
        cdef size_t[::1] p_v = self._ptrs
        cdef double[::1] w_v = self._work
        status = pihyst_compbank_init(&self.b, <pihyst_compensator *const *>&p_v[0], self.n,
                                      &w_v[0], w_v.shape[0])
        if status != PIHYST_OK:
            raise CoreError(pihyst_status_text(status).decode())

    def sync(self):
        """Write the fast channels' states back to their compensators."""
        pihyst_compbank_sync(&self.b)

    @property
    def n_fast(self):
        """Channels on the fast path (classical inverse)."""
        return self.b.n_fast

    def step_into(self, y_desired, double[::1] u, double[::1] y, pihyst_flags[::1] flags):
        """One tick into caller-owned arrays (N each); returns the count flagged."""
        cdef const double[::1] d_v = _vector(y_desired, self.n, "y_desired")
        cdef size_t count = 0
        if u.shape[0] != self.n or y.shape[0] != self.n or flags.shape[0] != self.n:
            raise ValueError(f"u, y and flags must have {self.n} values")
        if self.n:
            with nogil:
                count = pihyst_compbank_compensate(&self.b, &d_v[0], &u[0], &y[0], &flags[0])
            self._set_last_flags(flags)
        return count

    def run(self, y_desired):
        """(u, y, flags), each T x N, for desired values T x N (row t one tick)."""
        d_a = np.ascontiguousarray(y_desired, dtype=np.float64)
        if d_a.ndim != 2 or d_a.shape[1] != self.n:
            raise ValueError(f"y_desired must have shape (T, {self.n}), got {d_a.shape}")
        cdef const double[:, ::1] d_v = d_a
        u = np.empty(d_a.shape)
        y = np.empty(d_a.shape)
        flags = np.zeros(d_a.shape, dtype=np.uint8)
        cdef double[:, ::1] u_v = u
        cdef double[:, ::1] y_v = y
        cdef pihyst_flags[:, ::1] f_v = flags
        cdef Py_ssize_t t, T = d_a.shape[0]
        if self.n and T:
            with nogil:
                for t in range(T):
                    pihyst_compbank_compensate(&self.b, &d_v[t, 0], &u_v[t, 0], &y_v[t, 0],
                                               &f_v[t, 0])
            self._set_last_flags(flags[T - 1])
        return u, y, flags

    def _set_last_flags(self, flags):
        cdef Compensator c
        for i, obj in enumerate(self.compensators):
            c = <Compensator>obj
            c.last_flags = flags[i]


# ---------------------------------------------------------------- creep (pihyst_creep.h)

cdef extern from "pihyst_creep.h" nogil:
    ctypedef enum pihyst_creep_status:
        PIHYST_CREEP_OK
    ctypedef struct pihyst_creep:
        size_t n
        double dt
        double beta
    pihyst_creep_status pihyst_creep_init(pihyst_creep *c, size_t n, const double *tau,
                                          const double *gain, double dt, double *alpha,
                                          double *state, const double *initial_state)
    double pihyst_creep_target(const pihyst_creep *c, double y_desired)
    double pihyst_creep_step(pihyst_creep *c, double h)
    double pihyst_creep_target_dt(const pihyst_creep *c, double dt, double y_desired)
    double pihyst_creep_step_dt(pihyst_creep *c, double dt, double h)
    void pihyst_creep_run(pihyst_creep *c, const double *h, const double *dt, double *y,
                          size_t n)
    size_t pihyst_creep_compensator_run(pihyst_creep *cr, pihyst_compensator *c,
                                        const double *y_desired, const double *dt,
                                        double *u, double *y, pihyst_flags *flags,
                                        size_t n)
    const char *pihyst_creep_status_text(pihyst_creep_status status)


cdef class Creep:
    """Creep lags z_i driven by a hysteresis output h, with their state (pihyst_creep.h).

    ``dt`` is the fixed interval; the methods take per-sample intervals ``dt`` (an
    array, or a number for one sample) or use the fixed one when it is None.
    """
    cdef pihyst_creep c
    cdef readonly size_t n
    cdef object _tau, _gain, _alpha, _state

    def __init__(self, tau, gain, double dt, initial_state=None):
        cdef const double[::1] tau_v, gain_v, init_v
        cdef double[::1] alpha_v, state_v
        cdef const double *init_p = NULL
        self._tau = _vector(tau, name="tau").copy()
        self.n = self._tau.shape[0]
        self._gain = _vector(gain, self.n, "gain").copy()
        self._alpha = np.zeros(max(self.n, 1))
        self._state = np.zeros(max(self.n, 1))
        if initial_state is not None:
            init_v = _vector(initial_state, self.n, "creep state")
            init_p = &init_v[0] if self.n else NULL
        tau_v, gain_v = self._tau, self._gain
        alpha_v, state_v = self._alpha, self._state
        status = pihyst_creep_init(&self.c, self.n, &tau_v[0] if self.n else NULL,
                                   &gain_v[0] if self.n else NULL, dt, &alpha_v[0],
                                   &state_v[0], init_p)
        if status != PIHYST_CREEP_OK:
            raise CoreError(pihyst_creep_status_text(status).decode())

    @property
    def state(self):
        """A copy of the lag states z_i[t-1]."""
        return self._state[:self.n].copy()

    @state.setter
    def state(self, value):
        self._state[:self.n] = _checked_state(value, self.n)

    @property
    def beta(self):
        """sum_i g_i (1 - alpha_i) for the fixed interval."""
        return self.c.beta

    def target(self, double y_desired, dt=None):
        """The hysteresis output that gives y_desired at the next sample."""
        if dt is None:
            return pihyst_creep_target(&self.c, y_desired)
        return pihyst_creep_target_dt(&self.c, float(dt), y_desired)

    def step(self, double h, dt=None):
        """Advance the lags by the hysteresis output h; return the output."""
        if dt is None:
            return pihyst_creep_step(&self.c, h)
        return pihyst_creep_step_dt(&self.c, float(dt), h)

    def run(self, h, dt=None):
        """Outputs for a block of hysteresis outputs (intervals dt, None: fixed)."""
        cdef const double[::1] h_v = _vector(h, name="h")
        cdef Py_ssize_t n = h_v.shape[0]
        cdef const double[::1] dt_v
        cdef const double *dt_p = NULL
        y = np.empty(n)
        cdef double[::1] y_v = y
        if dt is not None:
            dt_v = _vector(dt, n, "dt")
            dt_p = &dt_v[0] if n else NULL
        if n:
            with nogil:
                pihyst_creep_run(&self.c, &h_v[0], dt_p, &y_v[0], n)
        return y

    def lag_states(self, h, dt=None):
        """The N x n matrix of lag states z_i[t] after each sample of h (identification
        needs them; the output is not formed)."""
        cdef const double[::1] h_v = _vector(h, name="h")
        cdef Py_ssize_t n = h_v.shape[0], t, i
        cdef const double[::1] dt_v
        cdef bint fixed = dt is None
        cdef double[::1] st = self._state
        z = np.empty((n, self.n))
        cdef double[:, ::1] z_v = z
        if not fixed:
            dt_v = _vector(dt, n, "dt")
        with nogil:
            for t in range(n):
                if fixed:
                    pihyst_creep_step(&self.c, h_v[t])
                else:
                    pihyst_creep_step_dt(&self.c, dt_v[t], h_v[t])
                for i in range(<Py_ssize_t>self.n):
                    z_v[t, i] = st[i]
        return z

    def compensate(self, Compensator comp, y_desired, dt=None):
        """(voltage, output, flags) for a block of desired outputs of the model with
        creep: each sample's hysteresis target goes to ``comp``."""
        cdef const double[::1] d_v = _vector(y_desired, name="y_desired")
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
            dt_v = _vector(dt, n, "dt")
            dt_p = &dt_v[0] if n else NULL
        if n:
            with nogil:
                pihyst_creep_compensator_run(&self.c, &comp.c, &d_v[0], dt_p, &u_v[0],
                                             &y_v[0], &f_v[0], n)
            comp.last_flags = f_v[n - 1]
        return u, y, flags
