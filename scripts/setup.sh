#!/usr/bin/env bash
# Set up everything translucency needs on a Debian machine, idempotently:
#   1. system libraries (apt): OpenGL for pymeshlab, EGL for off-screen VTK, OpenMP for numba,
#      the X11 libraries Qt's window needs (the desktop viewer), Xvfb for the tests that open a real window,
#      and Python's venv module;
#   2. a virtual environment in .venv with the package (editable), its test and Dask extras and the
#      reference extra (Mitsuba 3, for the path-traced check; its scalar variant needs no system library);
#   3. the solver's kernels compiled into numba's cache, so that the first real run does not wait for
#      the compiler (skipped when the cache already holds them).
# A second run does nothing unless pyproject.toml changed or the kernels' cache is empty.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"

system_packages=(libgl1 libopengl0 libegl1 libgomp1 xvfb xauth
    libxkbcommon-x11-0 libxcb-cursor0 libxcb-icccm4 libxcb-keysyms1 libxcb-image0 libxcb-render-util0
    libxcb-shape0 libxcb-randr0 libxcb-xinerama0 libxcb-xkb1 libdbus-1-3 libfontconfig1)
missing=()
for pkg in "${system_packages[@]}"; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
        missing+=("$pkg")
    fi
done
python=${PYTHON:-python3}
if ! "$python" -c "import venv, ensurepip" 2>/dev/null; then
    missing+=(python3 python3-venv)
    python=python3
fi
if ((${#missing[@]})); then
    if [[ $(id -u) -ne 0 ]]; then
        echo "setup: missing system packages: ${missing[*]}" >&2
        echo "setup: install them with: sudo apt-get install -y ${missing[*]}" >&2
        exit 1
    fi
    echo "setup: installing system packages: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

if [[ ! -x .venv/bin/python ]]; then
    echo "setup: creating .venv"
    "$python" -m venv .venv
fi
stamp=.venv/.translucency-setup
want="$(sha256sum pyproject.toml | cut -d' ' -f1)"
if [[ ! -f $stamp || "$(cat "$stamp")" != "$want" ]]; then
    echo "setup: installing Python packages into .venv (about a minute the first time)"
    # pip's own notes (the build back-end's warning about editable installs, the index's) are kept in a
    # log and shown only when the installation fails
    log="$(mktemp)"
    if ! { .venv/bin/python -m pip install -q --upgrade pip && .venv/bin/python -m pip install -q -e ".[test,dask,reference]"; } >"$log" 2>&1; then
        cat "$log" >&2
        rm -f "$log"
        echo "setup: installing the Python packages failed (pip's output above)" >&2
        exit 1
    fi
    rm -f "$log"
    echo "$want" > "$stamp"
fi
.venv/bin/python -m translucency.app.warmup
