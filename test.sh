#!/usr/bin/env bash
# The whole test suite: set up and build, the C checks of every FMU (also in a
# build with AddressSanitizer and UBSan), then pytest.
set -euo pipefail
cd "$(dirname "$0")"
bash scripts/setup.sh

echo "== C checks of every FMU (release build)"
ctest --test-dir build --output-on-failure

echo "== C checks of every FMU under AddressSanitizer + UBSan"
cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug -DARTIBUS_SANITIZE=ON \
  -DSUNDIALS_DIR="$PWD/build-sundials/sundials-install/lib/cmake/sundials" >/dev/null   # setup.sh built it
cmake --build build-asan -j"$(nproc)" >/dev/null
ARTIBUS_FMU_DIR="$PWD/build-asan/fmus" .venv/bin/artibus pack >/dev/null   # benches with these FMUs
ctest --test-dir build-asan --output-on-failure

echo "== pytest"
.venv/bin/python -m pytest -q "$@"

echo "== pytest again, every FMU from the AddressSanitizer + UBSan build"
# (the Python interpreter is not instrumented: the sanitizer runtimes are
# preloaded; leaks are checked by the C checks above, where the whole process is
# ours. --capture=sys lets a sanitizer report reach the terminal before it aborts.
# The long bench runs are left out here: they drive the same FMU code as the
# tests above, ten times slower under the sanitizers; the stepping core in C,
# build-asan/lib's, runs here on the two-FMU benches of tests/test_runner_core.py)
ARTIBUS_FMU_DIR="$PWD/build-asan/fmus" \
LD_PRELOAD="$(gcc -print-file-name=libasan.so) $(gcc -print-file-name=libubsan.so)" \
ASAN_OPTIONS=detect_leaks=0 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  .venv/bin/python -m pytest -q -p no:cacheprovider --capture=sys \
  -k "not binary_depends_only_on_system_libraries and not only_fmi_symbols_exported and not fmi_sim and not bus36m_hinge_forces_on_a_circle and not bench_bit_for_bit and not bench_variant_bit_for_bit" \
  --ignore=tests/test_benches.py --ignore=tests/test_benches_roads.py \
  --ignore=tests/test_bus36m_equilibrium.py --ignore=tests/test_steering_controllers_benches.py \
  --ignore=tests/test_damping_benches.py --ignore=tests/test_kc.py --ignore=tests/test_can.py --ignore=tests/test_can_faults.py --ignore=tests/test_can_backwards.py --ignore=tests/test_replay_can.py --ignore=tests/test_win64.py --ignore=tests/test_fmu_packaging.py --ignore=tests/test_sweep.py --ignore=tests/test_reports.py --ignore=tests/test_runner_safety.py --ignore=tests/test_cli.py --ignore=tests/test_simulate_partial.py --ignore=tests/test_issue15_audit.py "$@"
