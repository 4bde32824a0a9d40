"""Benchmark of the forward model's K = 16 kernel against the best hand-vectorized C
(issue item 4): bench_simd.c (next to this file) holds AVX2 + FMA intrinsic kernels
written for K = 16 (classical and multislope: state, envelope constants and weights in
registers for the whole block, a tree for the weighted sum). The harness is compiled
with gcc -O3 -mavx2 -mfma; the core's sources are compiled as the Python extension
compiles them (-O3, no -march: the hot loops pick their instruction set at load time),
and pihyst_model_run is timed against the hand kernel on the same 10^5-sample walk in
the same process, best of 300 alternating runs. Prints ns per sample and the ratio.

Target (issue item 4): core <= 1.3x the hand kernel at K = 16, classical and multislope.

Run: python benchmarks/bench_simd.py
"""

import pathlib
import shutil
import subprocess
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent


def build(folder):
    gcc = shutil.which("gcc")
    if gcc is None:
        return None
    objs = []
    for src in sorted((ROOT / "csrc").glob("pihyst_*.c")):
        obj = folder / (src.stem + ".o")
        subprocess.run([gcc, "-std=c99", "-O3", "-ffp-contract=fast", f"-I{ROOT / 'csrc'}",
                        "-c", str(src), "-o", str(obj)], check=True)
        objs.append(str(obj))
    exe = folder / "bench_simd"
    subprocess.run([gcc, "-std=c11", "-O3", "-mavx2", "-mfma", "-D_POSIX_C_SOURCE=200112L",
                    f"-I{ROOT / 'csrc'}", str(HERE / "bench_simd.c"), *objs, "-lm", "-o",
                    str(exe)], check=True)
    return exe


def main():
    with open("/proc/cpuinfo") as f:
        flags = f.read()
    if " avx2 " not in flags or " fma " not in flags:
        print("bench_simd: this CPU has no AVX2 + FMA; nothing to compare")
        return
    with tempfile.TemporaryDirectory() as tmp:
        exe = build(pathlib.Path(tmp))
        if exe is None:
            print("bench_simd: gcc not found")
            return
        print("forward model, K = 16, 10^5 samples, best of 300: pihyst_model_run against "
              "hand-written AVX2 + FMA")
        print(f"   {'family':<11} {'core ns':>8} {'hand ns':>8} {'ratio':>6}  max |dy|")
        for family, name in ((0, "classical"), (1, "multislope")):
            out = subprocess.run([str(exe), str(family), "100000", "300"], check=True,
                                 capture_output=True, text=True).stdout.split()
            core, hand, err = map(float, out)
            print(f"   {name:<11} {core:>8.2f} {hand:>8.2f} {core / hand:>5.2f}x  {err:.1e}"
                  "   (target <= 1.30x)")


if __name__ == "__main__":
    main()
