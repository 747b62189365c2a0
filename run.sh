#!/usr/bin/env bash
# The main job: set up and build everything, then run the flagship demo/benches
# and write results and plots under out/.
set -euo pipefail
cd "$(dirname "$0")"
bash scripts/setup.sh
.venv/bin/artibus demo -o out
