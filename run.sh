#!/usr/bin/env bash
# The main job: set up and build everything, then run every SSP bench with its
# report (plots and the KPI table against the papers) and the kinematic demo,
# all under out/ (open out/index.html).
set -euo pipefail
cd "$(dirname "$0")"
bash scripts/setup.sh
.venv/bin/artibus run --all --report out
.venv/bin/artibus demo --report out/demo
