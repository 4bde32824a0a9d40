"""Writing a file so that it appears only once it is complete.

Every file pihyst writes (models, records, reports) goes through
:func:`write_atomically`: the content goes to a temporary file in the target's folder,
which is renamed over the target at the end, so an error never leaves a partial file.
"""

import os
import tempfile


def write_atomically(path, data):
    """Write ``data`` (``str``, as UTF-8, or ``bytes``) to ``path`` through a temporary
    file in the same folder."""
    path = os.fspath(path)
    folder = os.path.dirname(os.path.abspath(path))
    fd, tmp = tempfile.mkstemp(dir=folder, prefix=".pihyst-", suffix=".tmp")
    try:
        if isinstance(data, str):
            with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
                f.write(data)
        else:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
        # mkstemp makes the file private (0600); give it the mode a plain open() would
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
