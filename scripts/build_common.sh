# The start that scripts/build_sundials.sh and scripts/build_win64.sh share,
# sourced by both after `set -euo pipefail`:
#   the repository's root as the working directory, its path in ROOT;
#   work_dir DIR    DIR (relative to the root unless absolute) made; prints its
#                   absolute path;
#   quiet CMD...    CMD run with its output into the file QUIET_LOG; on failure
#                   the log's last 40 lines and "QUIET_TAG: failed: CMD" on
#                   stderr (the caller sets QUIET_LOG and QUIET_TAG first).
cd "$(dirname "${BASH_SOURCE[0]}")/.."
ROOT="$PWD"

work_dir() {
  local d="$1"
  case "$d" in /*) ;; *) d="$ROOT/$d" ;; esac
  mkdir -p "$d"
  printf '%s\n' "$d"
}

quiet() {
  "$@" >"$QUIET_LOG" 2>&1 || { tail -40 "$QUIET_LOG" >&2; echo "$QUIET_TAG: failed: $*" >&2; return 1; }
}
