"""Benchmark of the Gram matrix (issue item 3, C side), in the same run (best CPU time of
5, one thread):
- C rank-1: Bank.gram(u, d), i.e. pihyst_model_gram, the C core's sample-by-sample
  updates (what firmware calls, and what pihyst.identify uses today);
- blocked: Bank.gram(u, d, block=GRAM_BLOCK): the C core writes the operator matrix in
  blocks of 2048 rows into one reused buffer and NumPy's BLAS accumulates
  G += Phi_b^T Phi_b;
- the reference the issue names: the whole operator matrix plus one Phi^T Phi.

Models: classical and multislope K = 16 and 64 on N = 200,000 samples, and a KP-like
piecewise-linear model (K = 132 saturated ramps, 4 points each) on 20,000 samples.
Target: the Gram matrix no slower than the operator matrix plus one Phi^T Phi.

Run: python benchmarks/bench_gram.py
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # one core, as the C loops

import numpy as np  # noqa: E402
from timing import best_cpu_time  # noqa: E402

from pihyst import _core  # noqa: E402

U = 150.0



def bank(family, k, rng):
    w = rng.uniform(0, 0.1, k)
    if family == "classical":
        return _core.Bank("classical", np.linspace(0, U, k, endpoint=False), w, 0.0, 0.0, U)
    if family == "multislope":
        return _core.Bank("multislope", np.linspace(0, 50, k, endpoint=False), w, 0.0, 0.0,
                          U, shape=(U, 0.8, 1.2, 0.5))
    # KP-like: R(v) = sat((v - c_j)/w + 1/2), F(v) = sat((v - c_i)/w + 1/2) on a grid
    width = U / 12
    grid = np.linspace(0, U, 17)
    pairs = [(i, j) for i in range(17) for j in range(i, 17)][:k]
    rising, falling = [], []
    for ci, cj in ((grid[i], grid[j]) for i, j in pairs):
        for c, out in ((cj, rising), (ci, falling)):
            x = np.array([c - width / 2 - 1, c - width / 2, c + width / 2, c + width / 2 + 1])
            out.append((x, np.array([0.0, 0.0, 1.0, 1.0])))
    return _core.Bank("pwl", None, w, 0.0, -20.0, U + 20.0, rising=rising, falling=falling)


def main():
    rng = np.random.default_rng(0)
    print("Gram matrix (G, Phi^T d, Phi^T 1), best CPU time of 5")
    print(f"   {'model':<11} {'K':>4} {'N':>8} {'C rank-1':>10} {'blocked':>10} "
          f"{'Phi, P^T P':>11}   before/ref  after/ref  max rel diff")
    for family, k, n in (("classical", 16, 200_000), ("multislope", 16, 200_000),
                         ("classical", 64, 200_000), ("multislope", 64, 200_000),
                         ("pwl (KP)", 132, 20_000)):
        b = bank(family.split()[0], k, rng)
        u = np.abs(np.cumsum(rng.normal(0, 2.0, n)) % (2 * U) - U)
        u = U - u
        d = np.sin(u / 10)

        def old(b=b, u=u, d=d):
            b.reset()
            return b.gram(u, d)

        def new(b=b, u=u, d=d):
            b.reset()
            return b.gram(u, d, block=_core.GRAM_BLOCK)

        def ref(b=b, u=u, d=d):
            b.reset()
            phi = b.operators(u)
            return phi.T @ phi, phi.T @ d, phi.sum(axis=0)

        t_old, t_new, t_ref = (best_cpu_time(f, 5) for f in (old, new, ref))
        g_old, g_new = old()[0], new()[0]
        diff = np.max(np.abs(g_new - g_old)) / np.max(np.abs(g_old))
        print(f"   {family:<11} {k:>4} {n:>8} {1e3 * t_old:>8.1f}ms {1e3 * t_new:>8.1f}ms "
              f"{1e3 * t_ref:>9.1f}ms   {t_old / t_ref:>9.2f}x {t_new / t_ref:>9.2f}x  "
              f"{diff:.1e}")


if __name__ == "__main__":
    main()
