#!/usr/bin/env bash
# Set everything up, then run the main job (`python -m translucency`, arguments passed through).
# With no arguments it bakes the embedded default scan.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
"$root/scripts/setup.sh"
exec "$root/.venv/bin/python" -m translucency "$@"
