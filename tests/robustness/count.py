"""Run the whole malformed-input corpus against every command and print the counts:
``python tests/robustness/count.py [--report] [-v]`` from the repository root.

``--report`` also feeds every record to ``pihyst report`` (slow: it fits and draws).
"""

import argparse
import collections
import os
import pickle
import resource
import shutil
import signal
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from harness import DESIRED, GOOD_MODEL, LOOP, VOLTS, argv_for, corpus_cases, judge, run  # noqa: E402
from option_cases import CASES  # noqa: E402


def option_argv(argv, tmp, out):
    subs = {"{model}": GOOD_MODEL, "{volts}": VOLTS, "{desired}": DESIRED, "{loop}": LOOP,
            "{out}": out, "{tmp}": tmp}
    result = []
    for a in argv:
        for k, v in subs.items():
            a = a.replace(k, v)
        result.append(a)
    return result


def prepare(tmp):
    with open(os.path.join(tmp, "file.txt"), "w") as f:
        f.write("not a folder\n")
    with open(os.path.join(tmp, "bad.csv"), "w") as f:
        f.write("voltage_V,displacement_um\n1,x\n")


def isolated(argv, expect, out, says=None, warns=None):
    """Run and judge one case in a forked child: limited to 3 GiB and 120 s, so that a
    case that allocates terabytes or never ends is counted instead of stopping the run."""
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        resource.setrlimit(resource.RLIMIT_AS, (3 << 30, resource.RLIM_INFINITY))
        signal.alarm(120)
        outcome = run(argv)
        problems = judge(outcome, expect, out, says, warns)
        with os.fdopen(write, "wb") as f:
            pickle.dump((outcome.status, problems), f)
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as f:
        data = f.read()
    _, how = os.waitpid(pid, 0)
    if data:
        return pickle.loads(data)
    why = (f"killed by signal {os.WTERMSIG(how)}" if os.WIFSIGNALED(how)
           else f"died with status {os.WEXITSTATUS(how)}")
    return None, [f"{why} (out of memory or time)"]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--report", action="store_true")
    ap.add_argument("-v", action="store_true")
    args = ap.parse_args()
    commands = ("predict", "fit", "compensate", "track") + (("report",) if args.report else ())
    tally = collections.Counter()
    failures = []
    for name, kind, command, expect, says, warns in corpus_cases(commands):
        tmp = tempfile.mkdtemp()
        out = os.path.join(tmp, "out.json" if command == "fit" else "out")
        if command not in ("fit", "report"):
            out += ".csv"
        from harness import CORPUS
        status, problems = isolated(argv_for(command, kind, os.path.join(CORPUS, name), out),
                                    expect, out, says, warns)
        tally["corpus runs"] += 1
        tally[f"exit {status}"] += 1
        if status is None:
            tally["tracebacks"] += 1
        if problems:
            tally["runs with problems"] += 1
            failures.append((f"{command} {name}", problems))
        shutil.rmtree(tmp)
    for argv, expect, says in CASES:
        tmp = tempfile.mkdtemp()
        prepare(tmp)
        out = os.path.join(tmp, "out" if argv and argv[0] in ("report", "demo") else "out.csv")
        full = option_argv(argv, tmp, out)
        status, problems = isolated(full, expect, out, says)
        tally["option runs"] += 1
        tally[f"exit {status}"] += 1
        if status is None:
            tally["tracebacks"] += 1
        if problems:
            tally["runs with problems"] += 1
            failures.append((" ".join(argv), problems))
        shutil.rmtree(tmp)
    for name, problems in failures:
        print(f"{name}:")
        for p in problems:
            print(f"    {p}")
    print()
    for k in sorted(tally):
        print(f"{k}: {tally[k]}")


if __name__ == "__main__":
    main()
