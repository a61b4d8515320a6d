"""scratch_folder: the layer file's folder in memory where there is room, removed afterwards, stale ones cleared."""
import os
import subprocess
import sys
import time

from meshlab_holefill.meshlab import scratch_folder as sf


def _dead_pid():
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


def test_the_memory_folder_is_taken_only_where_it_has_room_twice_over(tmp_path, monkeypatch):
    memory = tmp_path / "memory"
    memory.mkdir()
    monkeypatch.setattr(sf, "MEMORY_FOLDER", str(memory))
    room = sf.memory_folder_room(str(memory))
    assert room > 0 and sf.memory_folder_room(str(tmp_path / "missing")) == 0
    with sf.scratch_folder(room // 4) as folder:
        assert os.path.dirname(folder) == str(memory)
        assert os.path.basename(folder).startswith(f"holefill-{os.getpid()}-")
    assert not os.listdir(memory)  # removed afterwards
    with sf.scratch_folder(room) as folder:  # not twice the room: the temporary folder
        assert folder is not None and os.path.dirname(folder) != str(memory)
    monkeypatch.setattr(sf, "MEMORY_FOLDER", str(tmp_path / "missing"))
    with sf.scratch_folder(0) as folder:
        assert folder is not None and os.path.dirname(folder) != str(memory)


def test_folders_of_processes_that_are_gone_are_removed_an_hour_on_and_no_others(tmp_path, monkeypatch):
    memory = tmp_path / "memory"
    memory.mkdir()
    monkeypatch.setattr(sf, "MEMORY_FOLDER", str(memory))
    dead = _dead_pid()
    stale = memory / f"holefill-{dead}-k2x_9a"
    stale.mkdir()
    (stale / "filled.ply").write_bytes(b"ply")
    recent = memory / f"holefill-{dead}-recent"  # may be a live process of another PID namespace
    kept = [recent, memory / f"holefill-{os.getpid()}-abc123", memory / "holefill-notapid", memory / "other-1-abc"]
    for folder in kept[1:]:
        folder.mkdir()
    recent.mkdir()
    not_a_folder = memory / f"holefill-{dead}-file"
    not_a_folder.write_bytes(b"a file, not a folder")
    old = time.time() - sf.STALE_SECONDS - 60
    for path in [stale, not_a_folder] + kept[1:]:
        os.utime(path, (old, old))
    with sf.scratch_folder(0) as folder:
        assert os.path.dirname(folder) == str(memory) and not stale.exists()
        assert len(os.listdir(memory)) == len(kept) + 2  # this one's own folder too
    assert sorted(os.listdir(memory)) == sorted([k.name for k in kept] + [not_a_folder.name])
