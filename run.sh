#!/usr/bin/env bash
# The main job: set up and build what it needs (scripts/setup.sh: the Python
# package, the FMUs for this machine), then run every SSP bench with its report
# (plots and the KPI table against the papers) and the kinematic demo, all under
# out/ (open out/index.html). The binaries for the other platforms and the test
# tools: ./test.sh, or scripts/setup.sh --all-platforms.
set -euo pipefail
cd "$(dirname "$0")"
t0=$SECONDS
bash scripts/setup.sh
t1=$SECONDS
.venv/bin/artibus demo --report out/demo          # first: the index links it
t2=$SECONDS
echo "run.sh: every bench with its report into out/ (about 2 min)"
.venv/bin/artibus run --all --report out
echo "run.sh: set-up $((t1 - t0)) s, demo $((t2 - t1)) s, benches $((SECONDS - t2)) s; open out/index.html"
