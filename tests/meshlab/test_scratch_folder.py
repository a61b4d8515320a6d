"""scratch_folder: the layer file's folder in memory where there is room, removed afterwards, stale ones cleared."""
import os
import subprocess
import sys

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


def test_folders_of_processes_that_are_gone_are_removed_and_no_others(tmp_path, monkeypatch):
    memory = tmp_path / "memory"
    memory.mkdir()
    monkeypatch.setattr(sf, "MEMORY_FOLDER", str(memory))
    stale = memory / f"holefill-{_dead_pid()}-k2x_9a"
    (stale / "filled.ply").parent.mkdir()
    (stale / "filled.ply").write_bytes(b"ply")
    kept = [memory / f"holefill-{os.getpid()}-abc123", memory / "holefill-notapid", memory / "other-1-abc"]
    for folder in kept:
        folder.mkdir()
    not_a_folder = memory / f"holefill-{_dead_pid()}-file"
    not_a_folder.write_bytes(b"a file, not a folder")
    with sf.scratch_folder(0) as folder:
        assert os.path.dirname(folder) == str(memory) and not stale.exists()
        assert len(os.listdir(memory)) == len(kept) + 2  # this one's own folder too
    assert sorted(os.listdir(memory)) == sorted([k.name for k in kept] + [not_a_folder.name])
