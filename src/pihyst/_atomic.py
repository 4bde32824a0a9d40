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
import shutil
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
    if isinstance(data, str):
        data = data.encode("utf-8")
    with AtomicFile(path) as f:
        f.write(data)


class AtomicFile:
    """A file written piece by piece (:meth:`write`) that appears at ``path`` only at
    :meth:`commit`, complete: the streamed writers (CSV records of any length) use it as
    :func:`write_atomically` does. Until then the content is in an unnamed file
    (``O_TMPFILE``; nothing is left by a kill, SIGKILL included) or, where the system
    has none, in a hidden ``.pihyst-*.tmp`` removed by :meth:`abort`. A target that is
    a device or a named pipe is written to directly, as a stream (it is never replaced
    by a regular file). In a ``with`` block: committed at its end, aborted on an
    exception (Ctrl-C and SIGTERM included). Errors are ``OSError`` naming ``path``."""

    def __init__(self, path):
        self.path = os.fspath(path)
        self._tmp = None                  # the named temporary (fallback only)
        self._done = False
        folder = _checked_folder(self.path)
        # a symbolic link is written through: the file it points at is replaced
        self._target = os.path.realpath(self.path) if os.path.islink(self.path) else self.path
        try:
            if _is_special(self._target):
                self.direct = True
                self._file = open(self._target, "wb")
                return
            self.direct = False
            folder = os.path.dirname(os.path.abspath(self._target))
            self._folder = folder
            _remove_stale_temporaries(folder)
            fd = _open_unnamed(folder)
            if fd is None:
                fd, self._tmp = tempfile.mkstemp(dir=folder, prefix=TEMP_PREFIX,
                                                 suffix=TEMP_SUFFIX)
            self._file = os.fdopen(fd, "wb")
        except OSError as err:
            if err.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
                # said of the folder the caller named, never of our temporary's name
                given = os.path.dirname(self.path) or "."
                raise type(err)(err.errno, f"cannot write: folder {given} is not writable "
                                f"({err.strerror or err})", self.path) from None
            raise _named(err, self.path) from None

    def write(self, data):
        try:
            self._file.write(data)
        except OSError as err:
            raise _named(err, self.path) from None

    def commit(self):
        """Put the complete file in place (once)."""
        if self._done:
            return
        self._done = True
        try:
            if self.direct:
                self._file.close()
                return
            self._file.flush()
            os.fsync(self._file.fileno())
            if self._tmp is None:
                _link_into_place(self._file.fileno(), self._folder, self._target)
                self._file.close()
            else:
                self._file.close()
                # mkstemp makes the file private (0600); give it the mode open() would
                umask = os.umask(0)
                os.umask(umask)
                os.chmod(self._tmp, 0o666 & ~umask)
                os.replace(self._tmp, self._target)
                self._tmp = None
        except BaseException as err:
            self._discard()
            if isinstance(err, OSError):
                raise _named(err, self.path) from None
            raise

    def abort(self):
        """Give the file up: nothing appears, no temporary remains."""
        if not self._done:
            self._done = True
            self._discard()

    def _discard(self):
        try:
            self._file.close()
        except OSError:
            pass
        if self._tmp is not None:
            _unlink_quietly(self._tmp)
            self._tmp = None

    def __enter__(self):
        return self

    def __exit__(self, kind, value, tb):
        if kind is None:
            self.commit()
        else:
            self.abort()
        return False


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


def _open_unnamed(folder):
    """A descriptor of an O_TMPFILE file in ``folder``; None if the system or the
    filesystem has none."""
    flag = getattr(os, "O_TMPFILE", None)
    if flag is None or not os.path.isdir(_PROC_FD):
        return None
    try:
        return os.open(folder, flag | os.O_WRONLY | os.O_CLOEXEC, 0o666)
    except OSError as err:
        if err.errno in (errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL, errno.ENOSYS):
            return None
        raise


def _link_into_place(fd, folder, path):
    """Give the unnamed file ``fd`` the name ``path`` (replacing what is there)."""
    source = f"{_PROC_FD}/{fd}"
    try:
        _link_following(source, path)
        return
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
            if st.st_mtime >= limit or uid not in (None, st.st_uid):
                continue
            if stat.S_ISREG(st.st_mode):
                os.unlink(entry.path)
            elif stat.S_ISDIR(st.st_mode):         # a report folder being built
                shutil.rmtree(entry.path, ignore_errors=True)
        except OSError:
            continue


class AtomicFolder:
    """A folder of files that appears complete or not at all: the files are written into
    a hidden ``.pihyst-*.tmp`` folder beside ``path`` (:attr:`build`), renamed to
    ``path`` at the end of the ``with`` block; an exception (Ctrl-C and SIGTERM
    included) removes it. Missing parent folders are created. When ``path`` already
    exists and is not empty, the new files replace their namesakes in it one by one
    (each whole) and the rest stays. A folder
    left by a killed process is removed by the next write beside it once an hour old.
    Errors are ``OSError`` naming ``path``."""

    def __init__(self, path):
        self.path = os.fspath(path).rstrip(os.sep) or os.sep
        parent = os.path.dirname(os.path.abspath(self.path))
        if os.path.exists(self.path) and not os.path.isdir(self.path):
            raise NotADirectoryError(errno.ENOTDIR, "exists and is not a folder", self.path)
        try:
            os.makedirs(parent, exist_ok=True)
        except OSError as err:
            raise _named(err, self.path) from None
        _remove_stale_temporaries(parent)
        try:
            self.build = tempfile.mkdtemp(dir=parent, prefix=TEMP_PREFIX, suffix=TEMP_SUFFIX)
        except OSError as err:
            raise _named(err, self.path) from None

    def __enter__(self):
        return self.build

    def __exit__(self, kind, value, tb):
        if kind is not None:
            shutil.rmtree(self.build, ignore_errors=True)
            return False
        try:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(self.build, 0o777 & ~umask)
            try:
                os.rename(self.build, self.path)   # absent, or an empty folder
                return False
            except OSError as err:
                if err.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                    raise
            for name in sorted(os.listdir(self.build)):
                os.replace(os.path.join(self.build, name), os.path.join(self.path, name))
            os.rmdir(self.build)
        except BaseException as err:
            shutil.rmtree(self.build, ignore_errors=True)
            if isinstance(err, OSError):
                raise _named(err, self.path) from None
            raise
        return False
