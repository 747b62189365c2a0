#!/usr/bin/env bash
# The whole test suite: set up and build (the main job's set-up with every
# platform's binaries and the test tools: scripts/setup_test.sh), the C checks of every FMU (also in a
# build with AddressSanitizer and UBSan), pytest on every core, then the
# sanitizer pass. Each phase's time is printed, and a table of them at the end.
# Arguments go to both pytest runs (e.g. ./test.sh -m "not slow" for a quick loop:
# the end-to-end bench runs are marked slow; ./test.sh alone runs everything).
set -euo pipefail
cd "$(dirname "$0")"

PHASES=()
phase() {                   # phase NAME CMD...: run CMD, print and remember its time
  local name="$1" t0=$SECONDS; shift
  echo "== $name"
  "$@"
  PHASES+=("$(printf '%6d s  %s' $((SECONDS - t0)) "$name")")
  echo "== $name: $((SECONDS - t0)) s"
}
report() { echo "== phase times"; printf '%s\n' "${PHASES[@]}"; printf '%6d s  in all\n' "$SECONDS"; }
trap report EXIT

phase "set-up and build, every platform and the test tools (scripts/setup_test.sh)" bash scripts/setup_test.sh

phase "C checks of every FMU (release build)" \
  ctest --test-dir build --output-on-failure -j"$(nproc)"

asan_build() {
  cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DARTIBUS_SANITIZE=ON \
    -DSUNDIALS_DIR="$PWD/build-sundials/sundials-install/lib/cmake/sundials" >/dev/null   # setup.sh built it
  cmake --build build-asan -j"$(nproc)" >/dev/null
  ARTIBUS_FMU_DIR="$PWD/build-asan/fmus" .venv/bin/artibus pack >/dev/null   # benches with these FMUs
}
phase "AddressSanitizer + UBSan build" asan_build
phase "C checks of every FMU under AddressSanitizer + UBSan" \
  ctest --test-dir build-asan --output-on-failure -j"$(nproc)"

phase "pytest (every core)" \
  .venv/bin/python -m pytest -q -n auto --durations=25 "$@"

# The sanitizer pass: what the sanitizers add to the suite above, every FMU from
# the AddressSanitizer + UBSan build: the FMUs' C code and the C stepping core
# under the fuzzers and the state, call-order and misuse tests (the tests marked
# `sanitize` in tests/conftest.py; ARTIBUS_SANITIZER_PASS=1 deselects the rest).
# The Python interpreter is not
# instrumented: the sanitizer runtimes are preloaded; leaks are checked by the C
# checks above, where the whole process is ours. --capture=sys lets a sanitizer
# report reach the terminal before it aborts.
phase "sanitizer pass (the tests marked sanitize, AddressSanitizer + UBSan FMUs)" \
  env ARTIBUS_FMU_DIR="$PWD/build-asan/fmus" \
  LD_PRELOAD="$(gcc -print-file-name=libasan.so) $(gcc -print-file-name=libubsan.so)" \
  ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ARTIBUS_SANITIZER_PASS=1 .venv/bin/python -m pytest -q -n auto -p no:cacheprovider --capture=sys "$@"
