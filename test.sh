#!/usr/bin/env bash
# Set everything up, then run the test suite (arguments go to pytest), under a virtual X
# display so the tests that open a real window run too. The tests run on every core
# (pytest-xdist, "-n auto"; pass "-n 0" to run them in one process).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
"$root/scripts/setup.sh"
cd "$root"
exec xvfb-run -a -s "-screen 0 1280x1024x24" .venv/bin/python -m pytest -n auto "$@"
