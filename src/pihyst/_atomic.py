"""Writing a file so that it appears only once it is complete, and nothing else remains.

Every file pihyst writes (models, records, reports) goes through :func:`write_atomically`:

- On Linux the content goes to an *unnamed* file in the target's folder (``O_TMPFILE``),
  which is linked into place only once complete: a process killed at any moment, even by
  SIGKILL, leaves nothing behind (the kernel frees the unnamed file). When the target
  already exists, the complete file is linked under a temporary name and renamed over
  it, a window of microseconds.
- Elsewhere (or on a filesystem without ``O_TMPFILE``) it goes to a named temporary file
  ``.pihyst-*.tmp`` in the same folder, renamed over the target at the end and removed
  on any error; temporaries of that name left by a killed writer are removed by the next
  write in that folder once they are an hour old.
- Errors are ``OSError`` whose ``filename`` is the path asked for (never a temporary
  name), with a plain reason: the folder does not exist, the path is a folder, ...
- A target that exists and is not a regular file (``/dev/null``, a named pipe) is written
  directly: there is nothing to replace atomically.
"""

import errno
import os
import stat
import tempfile
import time

TEMP_PREFIX = ".pihyst-"
TEMP_SUFFIX = ".tmp"
STALE_AFTER_S = 3600.0
_PROC_FD = "/proc/self/fd"


def write_atomically(path, data):
    """Write ``data`` (``str``, as UTF-8, or ``bytes``) to ``path``: the file appears only
    once complete, and an error or a kill leaves no partial or temporary file."""
    path = os.fspath(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    folder = _checked_folder(path)
    if _is_special(path):
        with open(path, "wb") as f:
            f.write(data)
        return
    _remove_stale_temporaries(folder)
    try:
        if not _write_unnamed(path, folder, data):
            _write_named(path, folder, data)
    except OSError as err:
        raise _named(err, path) from None


def check_target(path):
    """OSError (naming ``path``) now if ``path`` cannot be written later: its folder is
    missing or not a folder, or it is a folder itself. Lets a command fail before its
    work instead of after."""
    _checked_folder(os.fspath(path))


def _named(err, path):
    """``err`` reported under the path the caller asked for."""
    if isinstance(err, BrokenPipeError) or err.filename == path:
        return err
    return type(err)(err.errno, err.strerror or str(err), path)


def _checked_folder(path):
    """The target's folder, after checking that the target can be a file there."""
    if path == "" or path.endswith(os.sep):
        raise IsADirectoryError(errno.EISDIR, "is a folder, not a file name", path)
    folder = os.path.dirname(os.path.abspath(path))
    if os.path.isdir(path):
        raise IsADirectoryError(errno.EISDIR, "is a folder, not a file", path)
    given = os.path.dirname(path)  # the folder as the caller wrote it, for messages
    if not os.path.exists(folder):
        # the first missing component, for a precise message
        while given and not os.path.exists(os.path.dirname(given) or "."):
            given = os.path.dirname(given)
        raise FileNotFoundError(errno.ENOENT, f"cannot write: folder {given} does not exist",
                                path)
    if not os.path.isdir(folder):
        while given and not os.path.isdir(os.path.dirname(given) or "."):
            given = os.path.dirname(given)
        raise NotADirectoryError(errno.ENOTDIR, f"cannot write: {given} is not a folder",
                                 path)
    return folder


def _is_special(path):
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not stat.S_ISREG(mode)


def _write_unnamed(path, folder, data):
    """Write through an O_TMPFILE file; False if the system or filesystem has none."""
    flag = getattr(os, "O_TMPFILE", None)
    if flag is None or not os.path.isdir(_PROC_FD):
        return False
    try:
        fd = os.open(folder, flag | os.O_WRONLY | os.O_CLOEXEC, 0o666)
    except OSError as err:
        if err.errno in (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL, errno.ENOSYS):
            return False
        raise
    with os.fdopen(fd, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
        source = f"{_PROC_FD}/{f.fileno()}"
        try:
            _link_following(source, path)
            return True
        except FileExistsError:
            pass
        # the target exists: link under a temporary name, then rename over it
        for _ in range(100):
            tmp = os.path.join(folder, f"{TEMP_PREFIX}{os.urandom(6).hex()}{TEMP_SUFFIX}")
            try:
                _link_following(source, tmp)
                break
            except FileExistsError:
                continue
        else:
            raise FileExistsError(errno.EEXIST, "no free temporary name", path)
        try:
            os.replace(tmp, path)
        except BaseException:
            _unlink_quietly(tmp)
            raise
    return True


_AT_FDCWD = -100
_AT_SYMLINK_FOLLOW = 0x400
_libc = None


def _link_following(source, target):
    """linkat(source, target, AT_SYMLINK_FOLLOW): a hard link to what the /proc/self/fd
    entry points at (the unnamed file). os.link does not pass AT_SYMLINK_FOLLOW on every
    Python, so libc is called directly."""
    global _libc
    if _libc is None:
        import ctypes
        import ctypes.util
        _libc = ctypes.CDLL(ctypes.util.find_library("c"), use_errno=True)
    import ctypes
    if _libc.linkat(_AT_FDCWD, os.fsencode(source), _AT_FDCWD, os.fsencode(target),
                    _AT_SYMLINK_FOLLOW) != 0:
        code = ctypes.get_errno()
        raise OSError(code, os.strerror(code), target)


def _write_named(path, folder, data):
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=TEMP_PREFIX, suffix=TEMP_SUFFIX)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        # mkstemp makes the file private (0600); give it the mode a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        _unlink_quietly(tmp)
        raise


def _unlink_quietly(path):
    try:
        os.unlink(path)
    except OSError:
        pass


def _remove_stale_temporaries(folder):
    """Remove our temporaries that a killed writer left in ``folder`` (an hour old)."""
    limit = time.time() - STALE_AFTER_S
    uid = os.getuid() if hasattr(os, "getuid") else None
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    for entry in entries:
        name = entry.name
        if not (name.startswith(TEMP_PREFIX) and name.endswith(TEMP_SUFFIX)):
            continue
        try:
            st = entry.stat(follow_symlinks=False)
            if (stat.S_ISREG(st.st_mode) and st.st_mtime < limit
                    and uid in (None, st.st_uid)):
                os.unlink(entry.path)
        except OSError:
            continue
