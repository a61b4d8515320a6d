"""numba's kernel cache follows the package's kernel sources, checked once per process before the first fill."""
import meshlab_holefill
from meshlab_holefill.core import kernel_cache


def test_kernel_cache_is_dropped_when_a_kernel_source_changes(tmp_path, monkeypatch):
    from meshlab_holefill.core.kernel_cache import refresh_kernel_cache

    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    package = tmp_path / "pkg"
    (package / "sub" / "__pycache__").mkdir(parents=True)
    kernel = package / "sub" / "kernels.py"
    kernel.write_text("import numba\n")
    (package / "plain.py").write_text("x = 1\n")
    cached = package / "sub" / "__pycache__" / "kernels.f-3.py311.nbi"

    def cache_files():
        cached.write_text("index")
        (package / "sub" / "__pycache__" / "kernels.f-3.py311.1.nbc").write_text("code")

    cache_files()
    assert refresh_kernel_cache(str(package))  # no fingerprint yet: the cache's sources are unknown
    assert not cached.exists() and not list((package / "sub" / "__pycache__").glob("*.nbc"))
    cache_files()
    assert not refresh_kernel_cache(str(package)) and cached.exists()  # same sources: kept
    (package / "plain.py").write_text('"""Not compiled: numba does not run this."""\nx = 2\n')
    assert not refresh_kernel_cache(str(package)) and cached.exists()  # a file that does not import numba does not count
    kernel.write_text("import numba\n# changed\n")
    assert refresh_kernel_cache(str(package)) and not cached.exists()


def test_a_shared_numba_cache_folder_is_left_alone(tmp_path, monkeypatch):
    from meshlab_holefill.core.kernel_cache import refresh_kernel_cache

    shared = tmp_path / "numba-cache"
    shared.mkdir()
    (shared / "other_package.f-1.py311.nbi").write_text("index")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(shared))
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "kernels.py").write_text("import numba\n")
    assert not refresh_kernel_cache(str(package))
    assert (shared / "other_package.f-1.py311.nbi").exists()


def test_the_first_fill_of_a_process_refreshes_the_cache_and_later_fills_do_not(monkeypatch):
    from meshlab_holefill.array_api import _kernel_example

    calls = []
    monkeypatch.setattr(kernel_cache, "_REFRESHED", False)
    monkeypatch.setattr(kernel_cache, "refresh_kernel_cache", lambda root=None: calls.append(root) or False)
    V, F = _kernel_example()
    for _ in range(2):
        _, _, result = meshlab_holefill.fill_holes(V, F, "min_angle_bilateral", workers=1)
        assert result["closed_holes"] == 2
    assert calls == [None]


def test_the_package_fingerprint_counts_only_files_that_import_numba():
    digest = kernel_cache._kernel_sources_digest(kernel_cache.PACKAGE_ROOT)
    assert digest == kernel_cache._kernel_sources_digest(kernel_cache.PACKAGE_ROOT)
    assert not kernel_cache._USES_NUMBA.search(b'"""Kernels compiled by numba."""\n')
    assert kernel_cache._USES_NUMBA.search(b"import numpy\nfrom numba import njit\n")
