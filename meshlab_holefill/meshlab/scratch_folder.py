"""The temporary folder a filled layer's file is written to: in memory where there is room, removed afterwards.

:func:`.meshset_io.replace_current_mesh` writes the filled mesh as a PLY file and loads it into the
MeshSet. The file goes to MEMORY_FOLDER (``/dev/shm``, held in memory) where that has room for it
twice over, else to the system's temporary folder. A process killed while its file exists (by the
system, out of memory) cannot remove it; in memory it would hold that memory until a reboot, so
each use first removes such folders of processes that are gone, an hour after they last changed.
"""
from __future__ import annotations

import contextlib
import os
import re
import shutil
import tempfile
import time

__all__ = ["MEMORY_FOLDER", "STALE_SECONDS", "memory_folder_room", "remove_stale_folders", "scratch_folder"]

# A folder held in memory: the layer file never reaches a disk. Used when it has room for the file twice over.
MEMORY_FOLDER = "/dev/shm"

_PREFIX = "holefill-"
# A folder is stale only this long after it was last changed: a live process keeps its folder for one layer's
# loading (seconds), and a process of another PID namespace sharing the folder (containers sharing /dev/shm)
# looks gone from here while it is not.
STALE_SECONDS = 3600.0
_NAME = re.compile(r"holefill-(\d+)-[A-Za-z0-9_]+")  # _PREFIX, the owner's process id, tempfile's random part


def memory_folder_room(folder):
    """Bytes free in ``folder`` when it is a folder this process can write and read back, else 0."""
    try:
        if not (os.path.isdir(folder) and os.access(folder, os.R_OK | os.W_OK | os.X_OK)):
            return 0
        stats = os.statvfs(folder)
    except (OSError, AttributeError):  # no statvfs off POSIX
        return 0
    return stats.f_bavail * stats.f_frsize


def _process_exists(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process, or no way to tell: assume it is alive
        return True
    return True


def remove_stale_folders(folder):
    """Remove the layer-file folders in ``folder`` whose process is gone.

    A folder's name carries the id of the process that made it (``holefill-<pid>-...``); only
    this user's folders are looked at, and one is removed only when no process has its id and
    it has not changed for STALE_SECONDS.
    """
    uid = getattr(os, "getuid", lambda: None)()
    cutoff = time.time() - STALE_SECONDS
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    for entry in entries:
        match = _NAME.fullmatch(entry.name)
        if match is None:
            continue
        try:
            stats = entry.stat(follow_symlinks=False)
            if not entry.is_dir(follow_symlinks=False) or stats.st_uid != uid or stats.st_mtime > cutoff:
                continue
        except OSError:
            continue
        if not _process_exists(int(match.group(1))):
            shutil.rmtree(entry.path, ignore_errors=True)


@contextlib.contextmanager
def scratch_folder(size=0):
    """A temporary folder for a layer file of ``size`` bytes, removed afterwards; None where none can be made.

    In MEMORY_FOLDER (its folders of processes that are gone removed first) when it has room for
    twice ``size``, else in the temporary folder.
    """
    places = [None]
    if memory_folder_room(MEMORY_FOLDER) > 2 * size:
        remove_stale_folders(MEMORY_FOLDER)
        places.insert(0, MEMORY_FOLDER)
    for place in places:
        try:
            folder = tempfile.TemporaryDirectory(prefix=f"{_PREFIX}{os.getpid()}-", dir=place,
                                                 ignore_cleanup_errors=True)
        except OSError:  # not usable after all: the next place, or none
            continue
        with folder as path:
            yield path
        return
    yield None
