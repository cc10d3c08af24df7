#!/bin/bash
# anvil effects and anvil bench as a user meets them: decisions with reasons for the shipped
# scenes, option errors, and a quick benchmark writing its tables and plots.
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.  Exits 77 when no GL context exists.
set -u
anvil=$1
src=$2
data=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
check() { # description, then a command that must succeed
    local what=$1
    shift
    if "$@"; then echo "ok: $what"; else echo "FAIL: $what"; fail=1; fi
}
expect_exit() { # code, description, command...
    local code=$1 what=$2
    shift 2
    "$@" >"$tmp/out" 2>"$tmp/err"
    local rc=$?
    if [ "$rc" -eq "$code" ]; then echo "ok: $what (exit $rc)"; else
        echo "FAIL: $what: exit $rc, expected $code"; cat "$tmp/err"; fail=1; fi
}
has() { grep -q -- "$1" "$tmp/out" || { echo "  output lacks \"$1\":"; cat "$tmp/out"; return 1; }; }

# The default storm: everything but the unimplemented effects and the HMD warp is on.
expect_exit 0 "effects of the default scene" "$anvil" effects
check "shadows on" has "shadows        on"
check "forward on, with the optical depth" has "forward        on   (auto) auto: largest optical depth"
check "phase on: ice and water" has "ice and water species both present"
check "no HMD: no distortion" has "distortion     off"
check "light map built once" has "built once, ever"
# Empty: nothing casts a shadow, and what needs shadows says so.
expect_exit 0 "effects of the empty scene" "$anvil" effects "$src/configs/empty.cfg"
check "empty: shadows off" has "shadows        off"
check "empty: ground shadow needs shadows" has "needs effects.shadows"
# A thin slab: optically thin along the light, so no forward scattering.
expect_exit 0 "thin slab" "$anvil" effects "$src/configs/slab.cfg" --set scene.tau=0.003
check "thin: forward off" has "forward        off  (auto) auto: optically thin"
# Overrides, and the HMD.
expect_exit 0 "forced" "$anvil" effects --set effects.phase=off --set effects.ground_shadow=on
check "phase off in the config" has "phase          off  (off) off in the config"
expect_exit 0 "hmd" "$anvil" effects "$src/configs/sphere.cfg" --display "$src/displays/hmd.cfg"
check "hmd: distortion on" has "distortion     on"
check "sphere: one phase" has "phase          off  (auto) auto: no ice"
if [ -f "$data/wrf/katrina_2005_mercator_wsm3.nc" ]; then
    expect_exit 0 "katrina" "$anvil" effects -q "$src/configs/katrina.cfg"
    check "katrina: water phase for all" has "the water phase for all"
    check "katrina: four time steps" has "4 steps"
fi
expect_exit 1 "bad effect value" "$anvil" effects --set effects.forward=maybe
expect_exit 2 "effects: two configs" "$anvil" effects a.cfg b.cfg

expect_exit 0 "bench --help" "$anvil" bench --help
expect_exit 1 "bench: unknown scene" "$anvil" bench --scene nowhere
expect_exit 2 "bench: exclusive options" "$anvil" bench --views-only --quality-only

# A CI-sized quality run on the sphere: tables, CSV and both plots.
"$anvil" bench --quick --quality-only --scene sphere -o "$tmp/b" --cache "$tmp/cache" \
    >"$tmp/out" 2>"$tmp/err"
rc=$?
if [ "$rc" -eq 3 ]; then echo "skip: no GL context"; exit 77; fi
check "quick bench exits 0" test "$rc" -eq 0
for f in accuracy.csv accuracy-table.md accuracy.png accuracy-self.png; do
    check "bench wrote $f" test -s "$tmp/b/$f"
done
check "CSV has the default row" grep -q "^sphere,default," "$tmp/b/accuracy.csv"
check "table records the device" grep -q "Device: " "$tmp/b/accuracy-table.md"
check "reference cached" test -n "$(ls "$tmp/cache"/ref-sphere-32-*.pfm 2>/dev/null)"
exit $fail
