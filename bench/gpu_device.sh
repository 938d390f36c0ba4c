#!/usr/bin/env bash
# On a machine with an NVIDIA GPU, numba-cuda, numpy, SciPy and pytest, and no network (a GPU server): install
# translucency without its dependencies (its GPU side needs no others), run the GPU tests on the GPU itself, then
# bench/gpu.py (arguments pass through), whose results land in bench/results/gpu.json and gpu.md.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
python3 -m pip install -q --no-deps --no-build-isolation -e . >/dev/null
python3 -c "from translucency.scatter.gpu.probe import gpu_status; s = gpu_status(); print('GPU:', s.name or s.reason)"
python3 -m pytest -q -p no:cacheprovider tests/scatter/test_gpu.py
python3 bench/gpu.py "$@"
