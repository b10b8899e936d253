"""Input files read whole into memory are bounded: a regular file of at most a size limit.

A description given as ``--description /dev/zero`` (or a FIFO, a directory, a 10 GB file by
mistake) would otherwise be read without end; :func:`check_regular_file` refuses it first with
one line naming the path and the limit.
"""
from __future__ import annotations

import os
import stat

from .errors import CablelabError

#: the largest description file read (a description is a few kB of YAML)
DESCRIPTION_MAX_BYTES = 16 * 1024 * 1024


def check_regular_file(path, what: str, max_bytes: int) -> int:
    """Size in bytes of ``path`` if it is a regular file of at most ``max_bytes``.

    Raises:
        CablelabError: not found, not a regular file (device, FIFO, directory), or too large.
    """
    try:
        st = os.stat(path)
    except FileNotFoundError:
        raise CablelabError(f"{path}: {what} file not found") from None
    except OSError as exc:
        raise CablelabError(f"{path}: cannot read {what} ({exc.strerror})") from None
    except ValueError:          # a NUL byte in the name (e.g. junk text taken for a path)
        raise CablelabError(f"{path!r}: not a {what} file name (it holds a NUL byte)") from None
    if not stat.S_ISREG(st.st_mode):
        kind = "a directory" if stat.S_ISDIR(st.st_mode) else "a device or pipe, not a regular file"
        raise CablelabError(f"{path}: {what} is {kind}; give a YAML file")
    if st.st_size > max_bytes:
        raise CablelabError(f"{path}: {what} file is {st.st_size / 2**20:.1f} MiB, more than the "
                            f"{max_bytes / 2**20:.0f} MiB a {what} may have")
    return st.st_size
