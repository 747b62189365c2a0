# The start that scripts/build_sundials.sh, scripts/build_win64.sh and
# scripts/setup.sh share, sourced after `set -euo pipefail`:
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
#   cache_key ARGS  12 hex digits naming a cache entry: a hash of ARGS, of every
#                   file an argument names (a toolchain file) and of the version
#                   of the compiler $CACHE_CC (default cc), so a change of any
#                   makes a new entry.
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
