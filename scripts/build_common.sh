# The start that scripts/build_sundials.sh, scripts/build_win64.sh,
# scripts/setup.sh and scripts/setup_test.sh share, sourced after `set -euo pipefail`:
#   the repository's root as the working directory, its path in ROOT;
#   CACHE           where third-party builds that do not change are kept, outside
#                   the clone: $ARTIBUS_CACHE, default ${XDG_CACHE_HOME:-~/.cache}/artibus
#                   (SUNDIALS for linux, win64 and aarch64, fmi-sim, the Wine prefix);
#                   `rm -rf` it to build everything again;
#   work_dir DIR    DIR (relative to the root unless absolute) made; prints its
#                   absolute path;
#   quiet CMD...    CMD run with its output into the file QUIET_LOG; on failure
#                   the log's last 40 lines and "QUIET_TAG: failed: CMD" on
#                   stderr (the caller sets QUIET_LOG and QUIET_TAG first);
#   step WHAT CMD...  "setup: WHAT" printed, CMD run, then "setup: ... done in N s";
#   apt_install PKG...  the Debian packages of PKG not yet installed, installed
#                   (with sudo when not root, SUDO); prints what and how long;
#   cache_key ARGS  12 hex digits naming a cache entry: a hash of ARGS, of every
#                   file an argument names (a toolchain file) and of the version
#                   of the compiler $CACHE_CC (default cc), so a change of any
#                   makes a new entry;
#   crate_source NAME VERSION DIR  the crate NAME (=VERSION) from crates.io, downloaded with
#                   cargo (its ordinary client: a throw-away Cargo.toml in DIR and `cargo
#                   fetch`; nothing is compiled) into cargo's registry; prints the folder
#                   it was unpacked in; QUIET_LOG and QUIET_TAG as for quiet; DIR removed;
#   cross_build DIR TOOLCHAIN CC JOBS  a cross build into DIR with cmake/TOOLCHAIN:
#                   SUNDIALS for it (scripts/build_sundials.sh, cached; CC names its
#                   compiler for the cache key), then every FMU's binary and its importer
#                   fmu_check_<Name> (and the FMI 3.0 binaries unless ARTIBUS_FMI3=OFF),
#                   from the same CMakeLists.txt (scripts/build_win64.sh, build_aarch64.sh);
#                   with ARTIBUS_CROSS_IMPORTERS=0 the FMUs' binaries alone, not the
#                   importers the tests run under Wine and qemu-user (./run.sh).
cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT="$PWD"
CACHE="${ARTIBUS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/artibus}"
mkdir -p "$CACHE"

work_dir() {
  local d="$1"
  case "$d" in /*) ;; *) d="$ROOT/$d" ;; esac
  mkdir -p "$d"
  printf '%s\n' "$d"
}

quiet() {
  "$@" >"$QUIET_LOG" 2>&1 || { tail -40 "$QUIET_LOG" >&2; echo "$QUIET_TAG: failed: $*" >&2; return 1; }
}

cache_key() {
  local a f
  {
    for a in "$@"; do
      printf '%s\n' "$a"
      f="${a#*=}"
      case "$f" in /*) [ -f "$f" ] && cat "$f" ;; esac
    done
    "${CACHE_CC:-cc}" --version 2>/dev/null | head -1
  } | sha256sum | cut -c1-12
}

step() {
  local what="$1" t0=$SECONDS; shift
  echo "setup: $what"
  "$@"
  echo "setup:   done in $((SECONDS - t0)) s"
}

SUDO=""
[ "$(id -u)" -ne 0 ] && SUDO="sudo"
apt_install() {
  local p missing=""
  for p in "$@"; do
    dpkg -s "$p" >/dev/null 2>&1 || missing="$missing $p"
  done
  [ -z "$missing" ] && return 0
  _apt() {
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "$@" >/dev/null
  }
  step "installing the Debian packages$missing (apt; a minute or two on a fresh machine)" _apt $missing
}

crate_source() {
  local name="$1" version="$2" crate="$3"
  rm -rf "$crate"
  mkdir -p "$crate/src"
  printf '[package]\nname = "artibus-crate-source"\nversion = "0.0.0"\nedition = "2021"\npublish = false\n\n[dependencies]\n%s = "=%s"\n' \
    "$name" "$version" >"$crate/Cargo.toml"
  echo 'fn main() {}' >"$crate/src/main.rs"
  quiet cargo fetch --manifest-path "$crate/Cargo.toml" >&2 || { rm -rf "$crate"; return 1; }
  # where cargo unpacked it (its registry under CARGO_HOME)
  cargo metadata --offline --format-version 1 --manifest-path "$crate/Cargo.toml" 2>/dev/null \
    | python3 -c 'import json, sys, os
m = json.load(sys.stdin)
p = next(p for p in m["packages"] if p["name"] == sys.argv[1])
print(os.path.dirname(p["manifest_path"]))' "$name"
  rm -rf "$crate"
}

cross_build() {
  local dir="$1" toolchain="$ROOT/cmake/$2" cc="$3" jobs="$4"
  local inst="$1/sundials-install" targets
  ARTIBUS_SUNDIALS_JOBS="$jobs" CACHE_CC="$cc" bash scripts/build_sundials.sh "$dir" \
    -DCMAKE_TOOLCHAIN_FILE="$toolchain"
  # configured every time (quick with its cache): the targets named below must exist even
  # when CMakeLists.txt gained an FMU since this folder was configured
  quiet cmake -S . -B "$dir" -DCMAKE_TOOLCHAIN_FILE="$toolchain" \
    -DCMAKE_BUILD_TYPE=Release -DCMAKE_FIND_ROOT_PATH="$inst" \
    -DSUNDIALS_DIR="$inst/lib/cmake/sundials" \
    -DEIGEN3_INCLUDE_DIR=/usr/include/eigen3   # Debian's libeigen3-dev (header-only)
  # only the FMUs and their importers (each fmu_check_<Name> needs its <Name>), or
  # with ARTIBUS_CROSS_IMPORTERS=0 the FMUs alone
  # (an FMI-LS-BUS node, add_fmu(<Name> LSBUS ...), is FMI 3.0 only: no fmu_check_<Name>)
  local check="fmu_check_"
  [ "${ARTIBUS_CROSS_IMPORTERS:-1}" = 0 ] && check=""
  targets="$(grep -v '^add_fmu([A-Za-z0-9_]* LSBUS' CMakeLists.txt | sed -n "s/^add_fmu(\([A-Za-z0-9_]*\).*/$check\1/p")"
  if ! grep -q '^ARTIBUS_FMI3:BOOL=OFF' "$dir/CMakeCache.txt"; then   # and the FMI 3.0 builds: <platform>/fmi3/
    targets="$targets $(sed -n 's/^add_fmu(\([A-Za-z0-9_]*\).*/\1_fmi3/p' CMakeLists.txt)"
    targets="$targets CanBus_fmi3 CanBus_Triggered_fmi3"   # FMI 3.0 only, not add_fmu (CMakeLists.txt, issues 24, 39)
  fi
  quiet cmake --build "$dir" -j"$jobs" --target $targets
}
