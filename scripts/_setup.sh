# Sourced by scripts/demo and scripts/test: create .venv if missing and install the package.
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$ROOT"
PYTHON="${PYTHON:-python3.11}"
command -v "$PYTHON" >/dev/null 2>&1 || PYTHON=python3
if [ ! -x .venv/bin/python ]; then
    "$PYTHON" -m venv .venv
fi
# Reinstall only when the project definition changed since the last install.
stamp=.venv/.installed-$(sha1sum pyproject.toml | cut -c1-12)
if [ ! -f "$stamp" ]; then
    .venv/bin/python -m pip install --quiet --upgrade pip
    .venv/bin/python -m pip install --quiet -e ".[test,bench]"
    touch "$stamp"
fi
# The filters' numba kernels, compiled once into numba's on-disk cache (after an install or an
# update of the sources; a few seconds when the cache is current).
.venv/bin/meshlab-holefill compile --quiet
# MeshLab 2020.09's meshlabserver (Debian package meshlab) and xvfb-run, for the tests that run
# scripts through the real MeshLab: installed when running as root with apt-get and missing.
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1 \
        && ! { command -v meshlabserver && command -v xvfb-run; } >/dev/null 2>&1; then
    { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq meshlab xvfb; } \
        >/dev/null 2>&1 || echo "scripts/_setup.sh: could not install meshlab and xvfb; the meshlabserver tests are skipped" >&2
fi
