"""Calibrates the compensator cost model of pihyst.identify._latency: times the C
compensators of a set of models (classical K = 2..128, multislope, modified-PI-like pwl,
KP kernel grids, Bouc-Wen shapes, with and without creep), fits the model's coefficients
by non-negative least squares to the median timings, and prints them (to paste into
identify/_latency.py) beside the estimate the current coefficients give.

    python benchmarks/calibrate_latency.py

The fit never times anything: it uses the estimate; this script is how the estimate
was made and how to check it on another machine.
"""

import numpy as np
from scipy.optimize import nnls

import pihyst
from pihyst.identify import KrasnoselskiiPokrovskii
from pihyst.identify._latency import estimate_latency, measure_latency, structure
from pihyst.model import BoucWenModel, Creep

CREEP = Creep(tau=[0.1, 1.0, 10.0], gain=[0.01, 0.02, 0.03], dt=1e-3)


def classical(k, rng):
    r = np.r_[0.0, np.sort(rng.uniform(1, 75, k - 1))]
    return pihyst.ClassicalPI(r, rng.uniform(0.05, 0.5, k))


def multislope(k, rng):
    r = np.r_[0.0, np.sort(rng.uniform(1, 45, k - 1))]
    return pihyst.MultislopePI(r, rng.uniform(0.05, 0.5, k))


def kernels(grid, rng):
    fam = KrasnoselskiiPokrovskii(grid=grid)
    pairs = fam.pairs()
    rising, falling = fam._polylines(pairs, 150.0)
    return pihyst.PiecewiseLinearPI(rising, falling, rng.uniform(0.0, 0.05, len(pairs)))


def models():
    rng = np.random.default_rng(1)
    out = [(f"classical-K{k}", classical(k, rng)) for k in (2, 4, 8, 16, 32, 64, 128)]
    out += [(f"multislope-K{k}", multislope(k, rng)) for k in (4, 8, 16)]
    out += [(f"kp-grid{g}", kernels(g, rng)) for g in (4, 8, 12, 16)]
    out += [(f"{name}+creep", m.replace(creep=CREEP)) for name, m in out[1:6:2]]
    for beta, ratio in [(1.0, 0.0), (5.0, 0.5), (20.0, -0.5), (60.0, 0.8), (110.0, 0.8)]:
        bw = BoucWenModel(beta=beta, gamma=beta * ratio, hysteretic=-8.0, linear=40.0)
        out.append((f"bouc-wen-{beta + abs(beta * ratio):g}", bw))
    out.append(("bouc-wen-7.5+creep", out[-4][1].replace(creep=CREEP)))
    return out


def median_latency(model, runs=5):
    lats = [measure_latency(model, seed=s) for s in range(runs)]
    return (float(np.median([x.typical for x in lats])),
            float(np.median([x.worst for x in lats])))


def rounded(names, coef):
    return {k: float(f"{c:.2g}") for k, c in zip(names, coef)}


def main():
    rows = [(name, m, structure(m), median_latency(m)) for name, m in models()]
    pi = [r for r in rows if r[1].family != "bouc-wen"]
    bw = [r for r in rows if r[1].family == "bouc-wen"]
    X = np.array([[1.0, s["operators"], s["vertices"], s["lags"]] for _, _, s, _ in pi])
    for i, which in enumerate(("typical", "worst")):
        t = np.array([lat[i] for *_, lat in pi])
        coef = nnls(X / t[:, None], np.ones(t.size))[0]      # relative error weighting
        print(f"PI_{which.upper()} = {rounded(('base', 'operator', 'vertex', 'lag'), coef)}")
    for i, which in enumerate(("typical", "worst")):
        Xb = np.array([[1.0, s[f"substeps_{which}"], s["lags"]] for _, _, s, _ in bw])
        tb = np.array([lat[i] for *_, lat in bw])
        coef = nnls(Xb / tb[:, None], np.ones(tb.size))[0]
        print(f"BW_{which.upper()} = {rounded(('base', 'substep', 'lag'), coef)}")
    print(f"\n{'model':<22}{'measured us (typ / worst)':>28}{'estimated us':>22}{'ratio':>14}")
    worst_ratio = 1.0
    for name, m, _, (typ, worst) in rows:
        e = estimate_latency(m)
        r = (e.typical / typ, e.worst / worst)
        worst_ratio = max(worst_ratio, *r, *(1 / x for x in r))
        print(f"{name:<22}{1e6 * typ:>13.3g} / {1e6 * worst:<12.3g}{1e6 * e.typical:>9.3g} / "
              f"{1e6 * e.worst:<10.3g}{r[0]:>6.2f} / {r[1]:.2f}")
    print(f"\nestimate within a factor {worst_ratio:.2f} of the measurement on this machine")


if __name__ == "__main__":
    main()
