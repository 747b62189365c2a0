#!/usr/bin/env bash
# The whole test suite: set up and build, the C checks of every FMU (also in a
# build with AddressSanitizer and UBSan), then pytest.
set -euo pipefail
cd "$(dirname "$0")"
bash scripts/setup.sh

echo "== C checks of every FMU (release build)"
ctest --test-dir build --output-on-failure

echo "== C checks of every FMU under AddressSanitizer + UBSan"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DARTIBUS_SANITIZE=ON >/dev/null
cmake --build build-asan -j"$(nproc)" >/dev/null
ctest --test-dir build-asan --output-on-failure

echo "== pytest"
.venv/bin/python -m pytest -q "$@"
