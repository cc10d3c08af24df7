# Shared by the command-line tests, sourced with the test's own arguments:
#   . "$(dirname "$0")/lib.sh"      (ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR)
# Gives $anvil, $src, $data, a temporary folder $tmp removed at exit, and the checks below;
# every failed check sets $fail, and finish exits with it.
set -u
anvil=$1
src=$2
data=${3:-}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

check() { # description, then a command that must succeed
    local what=$1
    shift
    if "$@"; then echo "ok: $what"; else echo "FAIL: $what"; fail=1; fi
}

expect_exit() { # code, description, command...: stdout to $tmp/out, stderr to $tmp/err
    local code=$1 what=$2
    shift 2
    "$@" >"$tmp/out" 2>"$tmp/err"
    local rc=$?
    if [ "$rc" -eq "$code" ]; then echo "ok: $what (exit $rc)"; else
        echo "FAIL: $what: exit $rc, expected $code"; cat "$tmp/err"; fail=1; fi
}

stderr_has() { grep -q -- "$1" "$tmp/err" || { echo "  stderr lacks \"$1\":"; cat "$tmp/err"; return 1; }; }
stdout_has() { grep -q -- "$1" "$tmp/out" || { echo "  output lacks \"$1\":"; cat "$tmp/out"; return 1; }; }

# Exits 77 (CTest: skipped) when no OpenGL 4.5 context can be made (anvil exits 3).
require_gl() {
    "$anvil" render --quiet "$src/configs/empty.cfg" --set render.width=8 \
        --set render.height=8 -o "$tmp/probe.png" 2>/dev/null
    if [ $? -eq 3 ]; then echo "no OpenGL context: skipping"; exit 77; fi
}

finish() {
    [ $fail -eq 0 ] && echo "all checks passed"
    exit $fail
}
