"""Run a command and pass its output through, saying what it is doing whenever it has been
silent for a while (8 s by default): the README's set-up commands (make demo, make test) never
leave the user looking at a silent terminal for longer than that.

    python3 tools/heartbeat.py [--every SECONDS] [--label TEXT] -- COMMAND [ARG ...]

The heartbeat line names the work in progress where it can be seen: the file a C compiler
is compiling, else the newest program the command started (read from /proc on Linux),
else the command's last line of output. The exit status is the command's. Standard library only: it
runs before the virtual environment exists.
"""

import argparse
import os
import select
import subprocess
import sys
import time


def _children(pid):
    """Process ids started by ``pid``, directly or not (Linux /proc; empty elsewhere)."""
    try:
        names = os.listdir("/proc")
    except OSError:
        return []
    parent = {}
    for name in names:
        if not name.isdigit():
            continue
        try:
            with open(f"/proc/{name}/stat", encoding="ascii", errors="replace") as f:
                stat = f.read()
        except OSError:
            continue
        # pid (comm) state ppid ...: comm may hold spaces and parentheses
        fields = stat[stat.rfind(")") + 2:].split()
        parent[int(name)] = int(fields[1])
    found, frontier = [], [pid]
    while frontier:
        p = frontier.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        found += kids
        frontier += kids
    return found


def _argv(pid):
    try:
        with open(f"/proc/{pid}/cmdline", "rb") as f:
            return [a.decode(errors="replace") for a in f.read().split(b"\0") if a]
    except OSError:
        return []


def doing(pid):
    """A few words on what the command ``pid`` is doing now ('' when nothing is known)."""
    procs = [(c, _argv(c)) for c in _children(pid)]
    procs = [(c, a) for c, a in procs if a]
    for _, argv in procs:            # a C compiler at work: name its source file
        if os.path.basename(argv[0]) in ("cc1", "cc1plus"):
            sources = [a for a in argv[1:] if a.endswith((".c", ".cpp", ".i"))]
            if sources:
                return f"compiling {os.path.relpath(sources[0])}"
    if not procs:
        return ""
    _, argv = max(procs)              # the newest process started
    words = [os.path.basename(argv[0])] + [a for a in argv[1:3] if len(a) < 60]
    return "running " + " ".join(words)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--every", type=float, default=8.0, metavar="SECONDS",
                   help="the longest silence (default 8 s: a line at least every 10 s)")
    p.add_argument("--label", default="make", help="prefix of the heartbeat lines")
    p.add_argument("command", nargs=argparse.REMAINDER)
    args = p.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        p.error("no command given")
    out = sys.stdout.buffer
    # "pip install", "python -m pytest"
    name = " ".join([os.path.basename(command[0])] + command[1:3 if command[1:2] == ["-m"] else 2])
    start = last = time.monotonic()
    at_line_start = True
    last_line = current = ""
    # Python programs below write at once rather than when a pipe's buffer fills
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env)
    fd = proc.stdout.fileno()
    try:
        while True:
            ready, _, _ = select.select([fd], [], [], min(1.0, args.every / 3))
            now = time.monotonic()
            if ready:
                chunk = os.read(fd, 65536)
                if not chunk:
                    break
                out.write(chunk)
                out.flush()
                at_line_start = chunk.endswith((b"\n", b"\r"))
                # the line being written (pytest's dots come a few at a time), else the last
                current = (current + chunk.decode(errors="replace")).replace("\r", "\n")
                lines = [x.strip() for x in current.split("\n")
                         if x.strip() and not x.startswith(f"{args.label}: ...")]
                last_line = lines[-1] if lines else last_line
                current = current.rsplit("\n", 1)[-1][-500:]
                last = now
            elif now - last >= args.every:
                what = doing(proc.pid) or (f"still at: {last_line[:70]}" if last_line else "")
                line = (f"{args.label}: ... {what or 'still working'} "
                        f"({now - start:.0f} s into {name})\n")
                out.write((b"" if at_line_start else b"\n") + line.encode())
                out.flush()
                at_line_start = True
                last = now
    except KeyboardInterrupt:      # Ctrl-C reached the command too: let it end, quietly
        out.write(proc.stdout.read())
        out.flush()
    status = proc.wait()
    return 128 - status if status < 0 else status    # killed by signal N: 128 + N


if __name__ == "__main__":
    sys.exit(main())
