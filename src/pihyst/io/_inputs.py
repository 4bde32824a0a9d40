"""Inputs that are not regular files (FIFOs, character devices, stdin, process
substitution): a record is refused with one line (it is read in several passes, which a
stream cannot give); a small file such as a model is read with a size limit and a
timeout, never waiting forever or filling the memory (``/dev/zero``)."""

import os
import select
import stat
import time

from pihyst.exceptions import RecordError

MODEL_LIMIT_BYTES = 64 << 20
STREAM_TIMEOUT_S = 10.0


def kind_of(path):
    """None for a regular file (or one that does not exist: opening it says so), else
    what it is: 'a FIFO', 'a character device', ..."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    if stat.S_ISREG(mode):
        return None
    if stat.S_ISDIR(mode):
        return "a folder"
    if stat.S_ISFIFO(mode):
        return "a FIFO (a pipe)"
    if stat.S_ISCHR(mode):
        return "a character device"
    if stat.S_ISBLK(mode):
        return "a block device"
    if stat.S_ISSOCK(mode):
        return "a socket"
    return "not a regular file"


def read_small(path, limit=MODEL_LIMIT_BYTES, timeout=STREAM_TIMEOUT_S):
    """The bytes of ``path``: a regular file read whole; a stream read up to ``limit``
    bytes and for at most ``timeout`` seconds. Raises OSError (a regular file that
    cannot be read) or RecordError (the stream's fault, one line)."""
    kind = kind_of(path)
    if kind is None:
        with open(path, "rb") as f:
            data = f.read(limit + 1)
        if len(data) > limit:
            raise RecordError(path, f"larger than {limit >> 20} MB: not a file of this kind")
        return data
    if kind == "a folder":
        raise RecordError(path, "is a folder, not a file")
    fifo = kind.startswith("a FIFO")
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    try:
        chunks, size, deadline = [], 0, time.monotonic() + timeout
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise RecordError(path, f"{kind}: nothing complete within {timeout:g} s (read "
                                 f"{size} bytes); write it to a file first")
            ready, _, _ = select.select([fd], [], [], min(left, 0.1))
            if not ready:
                continue
            try:
                chunk = os.read(fd, 1 << 16)
            except BlockingIOError:
                continue
            if not chunk:
                if fifo and not size:       # no writer yet: wait for one, up to the timeout
                    time.sleep(0.02)
                    continue
                return b"".join(chunks)
            chunks.append(chunk)
            size += len(chunk)
            if size > limit:
                raise RecordError(path, f"{kind} that gives more than {limit >> 20} MB: not a "
                                 "file of this kind")
    finally:
        os.close(fd)
