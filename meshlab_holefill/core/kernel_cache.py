"""numba's on-disk kernel cache kept in step with the package's kernel sources."""
from __future__ import annotations

import hashlib
import os
import re

__all__ = ["refresh_kernel_cache", "refresh_kernel_cache_once"]

PACKAGE_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_USES_NUMBA = re.compile(rb"^\s*(?:from numba\b|import numba\b)", re.MULTILINE)
_REFRESHED = False


def _kernel_sources_digest(root):
    """SHA-1 of the relative path and text of every ``.py`` file under ``root`` that imports numba."""
    digest = hashlib.sha1()
    for folder, _, files in sorted(os.walk(root)):
        for name in sorted(f for f in files if f.endswith(".py")):
            with open(os.path.join(folder, name), "rb") as fh:
                text = fh.read()
            if _USES_NUMBA.search(text):
                digest.update(os.path.relpath(os.path.join(folder, name), root).encode() + b"\0" + text)
    return digest.hexdigest()


def refresh_kernel_cache(root=None):
    """Drop numba's cached kernels when a kernel source of the package changed since they were cached.

    numba checks only the source file a cached function is defined in, while a compiled
    function carries the kernels it calls from other files inlined: after an update of those
    files alone it would load stale code. A fingerprint of every source file that imports
    numba is kept beside the cache (``__pycache__/numba-sources.sha1``); when it differs, or
    is missing, every cached kernel (``*.nbi``, ``*.nbc``) under ``root`` is removed, so the
    next run compiles afresh. Folders that cannot be written are left as they are, and so is
    a cache in ``NUMBA_CACHE_DIR`` (one folder shared by every package's kernels). A process
    that loads a kernel while another drops it compiles that kernel itself (numba reads a
    missing cache file as no cache).

    Parameters
    ----------
    root : str, optional
        The package folder (default: this package's).

    Returns
    -------
    bool
        Whether cached kernels were dropped.
    """
    if os.environ.get("NUMBA_CACHE_DIR"):  # one folder for every package's kernels: the user's to clear
        return False
    root = root or PACKAGE_ROOT
    digest = _kernel_sources_digest(root)
    stamp = os.path.join(root, "__pycache__", "numba-sources.sha1")
    try:
        with open(stamp) as fh:
            if fh.read().strip() == digest:
                return False
    except OSError:
        pass
    try:
        for folder, _, files in os.walk(root):
            if os.path.basename(folder) == "__pycache__":
                for name in files:
                    if name.endswith((".nbi", ".nbc")):
                        os.remove(os.path.join(folder, name))
        os.makedirs(os.path.dirname(stamp), exist_ok=True)
        with open(stamp, "w") as fh:
            fh.write(digest + "\n")
    except OSError:
        return False
    return True


def refresh_kernel_cache_once():
    """:func:`refresh_kernel_cache` of the package, the first time a process is about to run its kernels.

    Returns
    -------
    bool
        Whether cached kernels were dropped (always False after the first call).
    """
    global _REFRESHED
    if _REFRESHED:
        return False
    _REFRESHED = True
    return refresh_kernel_cache()
