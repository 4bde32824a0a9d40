"""Writes the seed corpus of the fuzz harnesses (fuzz/corpus/<target>/), deterministically.

The seeds are valid programs in the harnesses' input format (fuzz_common.h and the
harness headers): the paper's models, small random classical, multislope and PWL banks,
and voltage or desired-output sequences with reversals, NaN and out-of-range values, so
the fuzzer starts from inputs that reach the model loops and the compensator's walks.

Run from csrc/: python3 fuzz/make_corpus.py
"""

import math
import pathlib
import random
import struct

HERE = pathlib.Path(__file__).resolve().parent


def num(v, lo, hi):
    """A number the harness reads as v in [lo, hi] (selector < 240, then 16 bits)."""
    q = round((v - lo) / (hi - lo) * 65535)
    return bytes([0]) + struct.pack(">H", max(0, min(65535, q)))


def special(kind):
    return bytes([{"nan": 240, "inf": 241, "-inf": 242, "big": 247}[kind]])


def params(family, r, w, u_min=0.0, u_max=150.0, offset=0.0, shape=(150.0, 0.8, 1.2, 0.5),
           monotone=False, pwl=None, init=None):
    """The parameter block of take_params (fuzz_common.h)."""
    k = len(w)
    out = bytes([family, k - 1, 0])
    out += num(u_min, -200, 100) + num(u_max - u_min, 0, 300) + num(offset, -10, 10)
    U, a, b, h = shape
    out += num(U, 0, 300) + num(a, 0, 1.2) + num(b - a, 0, 1) + num(h, 0, 1)
    prev = 0.0
    for i in range(k):
        out += num(r[i] - prev, 0, 30 if i else 10)
        prev = r[i]
        out += num(w[i], 0 if monotone else -1, 1)
    out += bytes([0])  # thresholds given
    if init is None:
        out += bytes([0])
    else:
        out += bytes([1]) + b"".join(num(v, -300, 300) for v in init)
    if family == 2:
        for points, shift, gap in pwl:
            (x0, y0), rest = points[0], points[1:]
            out += bytes([len(points) - 1]) + num(shift, 0, 40) + num(gap, 0, 20)
            out += num(x0, -250, 250) + num(y0, -100, 100)
            out += num(0, 0, 100) + num(0, 0, 60)
            x, y = x0, y0
            for xn, yn in rest:
                out += num(xn - x, 0, 100) + num(yn - y, 0, 60)
                x, y = xn, yn
    return out


def triangle(n, lo, hi):
    half = n // 2
    return [lo + (hi - lo) * i / half for i in range(half)] + \
           [hi - (hi - lo) * i / half for i in range(n - half)]


def random_bank(rng, family):
    k = rng.randint(1, 12)
    if family == 1:
        r = sorted(rng.uniform(0, 45) for _ in range(k))
    else:
        r = sorted(rng.uniform(0, 150) for _ in range(k))
    r[0] = 0.0 if rng.random() < 0.5 else r[0]
    for i in range(1, k):  # strictly increasing, increments <= 30
        r[i] = min(max(r[i], r[i - 1] + 0.5), r[i - 1] + 30)
    w = [rng.uniform(0, 0.3) for _ in range(k)]
    return r, w


def random_pwl(rng, k):
    pwl = []
    for _ in range(k):
        n = rng.randint(1, 5)
        x, y = rng.uniform(-50, 50), rng.uniform(-20, 20)
        pts = [(x, y)]
        for _ in range(n - 1):
            x += rng.uniform(1, 60)
            y += rng.uniform(0, 40)
            pts.append((x, y))
        pwl.append((pts, rng.uniform(0, 30), rng.uniform(0, 10)))
    return pwl


def model_seeds(rng):
    seeds = []
    classical = params(0, [0, 10, 30, 60], [0.008, 0.252, 0.019, 0.582])
    multislope = params(1, [0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028])
    for head in (classical, multislope):
        seeds.append(head + b"".join(num(v, -20, 170) for v in triangle(120, 0, 150)))
    for i in range(22):
        family = i % 3
        r, w = random_bank(rng, family)
        w = [v if rng.random() < 0.8 else -v for v in w]
        pwl = random_pwl(rng, len(w)) if family == 2 else None
        init = [rng.uniform(-50, 50) for _ in w] if rng.random() < 0.3 else None
        head = params(family, r, w, offset=rng.uniform(-5, 5), pwl=pwl, init=init)
        u = [rng.uniform(-20, 170) for _ in range(rng.randint(10, 80))]
        body = b"".join(num(v, -20, 170) for v in u)
        if i % 5 == 4:
            body += special("nan") + special("inf") + num(75, -20, 170)
        seeds.append(head + body)
    # validation paths: unknown family, NaN weight, bad shape, empty range
    seeds.append(bytes([3]) + classical[1:])
    seeds.append(params(1, [0, 20], [0.1, 0.1], shape=(150.0, 1.1, 1.2, 0.5)))
    seeds.append(params(0, [0, 20], [0.1, 0.1], u_min=10.0, u_max=10.0))
    return seeds


def comp_ops(rng, n, with_resets=True):
    out = b""
    for _ in range(n):
        roll = rng.random()
        if roll < 0.8:
            # desired around the last output: the harness reads [y_last - s, y_last + s]
            out += bytes([rng.randrange(13)]) + num(rng.uniform(-0.3, 0.3), -1, 1)
        elif roll < 0.85:
            out += bytes([0]) + special(rng.choice(["nan", "inf", "-inf", "big"]))
        elif roll < 0.95 or not with_resets:
            out += bytes([13])  # flush
        else:
            out += bytes([15, rng.randrange(2)]) + num(rng.uniform(0, 1), 0, 1)
            out += b"".join(num(rng.uniform(-50, 50), -300, 300) for _ in range(12))
    return out


def limits(lo=None, hi=None, step=None, u0=0.0, lo_b=0.0, hi_b=150.0):
    out = bytes([1]) if lo is None else bytes([0]) + num(lo, lo_b - 10, hi_b)
    out += bytes([1]) if hi is None else bytes([0]) + num(hi, lo_b, hi_b + 10)
    out += bytes([1]) if step is None else bytes([0]) + num(step, 0, 20)
    lo_u = lo_b if lo is None else lo
    hi_u = hi_b if hi is None else hi
    out += num(u0, lo_u, hi_u) + bytes([0])
    return out


def compensator_seeds(rng):
    seeds = []
    classical = params(0, [0, 10, 30, 60], [0.008, 0.252, 0.019, 0.582], monotone=True)
    multislope = params(1, [0, 20, 30, 40], [0.196, 0.026, 0.046, 0.028], monotone=True)
    for head in (classical, multislope):
        seeds.append(bytes([3]) + head + limits() + comp_ops(rng, 150))
        seeds.append(bytes([1]) + head + limits(10.0, 120.0, 0.5, 10.0) + comp_ops(rng, 150))
    for i in range(24):
        family = i % 3
        r, w = random_bank(rng, family)
        pwl = random_pwl(rng, len(w)) if family == 2 else None
        head = params(family, r, w, offset=rng.uniform(-2, 2), monotone=True, pwl=pwl)
        step = None if i % 4 else rng.uniform(0.1, 5)
        seeds.append(bytes([rng.randrange(7)]) + head + limits(step=step) +
                     comp_ops(rng, rng.randint(20, 200)))
    # a short scratch and a negative weight: refused
    seeds.append(bytes([0]) + classical + limits()[:-1] + bytes([7]))
    seeds.append(bytes([0]) + params(0, [0, 10], [0.2, -0.1]) + limits())
    return seeds


def boucwen_seeds(rng):
    """Programs of fuzz_boucwen.c: monotone Bouc-Wen models (n from 1 to 4, gamma of
    either sign), a valid initial state, limits, a slew limit now and then, and desired
    outputs (fractions of the harness's +-1.2 output scale) as triangles, walks and
    special values."""
    seeds = []
    for i in range(16):
        beta = rng.uniform(0.5, 50)
        frac = rng.uniform(-0.9, 0.9)
        d = 2 / (1 + frac)
        a = rng.uniform(-10, 10)
        c2 = rng.uniform(-5, 5)
        c1 = min(59.0, max(0.0, -2 * c2) - min(a, 0.0) * d + rng.uniform(0.5, 20))
        out = num(beta, 0, 60) + num(frac, -1.2, 1.2) + num(rng.choice([1, 1, 2, 3.5]), 0.5, 11)
        out += num(a, -20, 20) + num(c1, -10, 60) + num(c2, -10, 10) + num(0.0, -10, 10)
        out += num(rng.uniform(-50, 50), -200, 100) + num(rng.uniform(20, 200), 0, 300)
        out += num(rng.uniform(0, 1), -0.1, 1.1) + num(rng.uniform(-0.9, 0.9), -1.1, 1.1)
        out += num(rng.uniform(0, 0.2), -0.1, 0.6) + num(rng.uniform(0, 0.2), -0.1, 0.6)
        if i % 3 == 0:
            out += bytes([0]) + num(rng.uniform(1, 20), 0, 300)
        else:
            out += bytes([200])
        out += num(rng.uniform(0, 1), -0.1, 1.1)
        n = rng.randint(8, 63)
        out += bytes([n - 1])
        for t in range(n):
            if rng.random() < 0.06:
                out += special(rng.choice(["nan", "inf", "-inf", "big"]))
            else:
                q = 0.5 + 0.4 * math.sin(t / 5.0) if i % 2 else rng.uniform(0, 1)
                out += num(q, 0, 1)
        seeds.append(out)
    return seeds


def main():
    rng = random.Random(20261130)
    for target, seeds in (("model", model_seeds(rng)), ("compensator", compensator_seeds(rng)),
                          ("boucwen", boucwen_seeds(rng))):
        folder = HERE / "corpus" / target
        folder.mkdir(parents=True, exist_ok=True)
        for old in folder.glob("seed-*"):
            old.unlink()
        for i, seed in enumerate(seeds):
            (folder / f"seed-{i:03d}").write_bytes(seed)
        print(f"{target}: {len(seeds)} seeds, {sum(map(len, seeds))} bytes")


if __name__ == "__main__":
    main()
