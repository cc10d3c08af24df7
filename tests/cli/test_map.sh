#!/bin/bash
# The storm in its place from the command line: Katrina with terrain, coastlines and graticule;
# a missing GSHHG folder or an unplaced synthetic scene is a message, exit 0 and a flat ground.
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.  Exits 77 when no GL context exists.
set -u
anvil=$1
src=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0
expect_exit() { # code, description, command...
    local code=$1 what=$2
    shift 2
    "$@" >"$tmp/out" 2>"$tmp/err"
    local rc=$?
    if [ "$rc" -eq "$code" ]; then echo "ok: $what (exit $rc)"; else
        echo "FAIL: $what: exit $rc, expected $code"; cat "$tmp/err"; fail=1; fi
}
stderr_has() {
    grep -q -- "$1" "$tmp/err" || { echo "FAIL: stderr lacks \"$1\":"; cat "$tmp/err"; fail=1; }
}
small="--set render.width=96 --set render.height=72 --set lightmap.resolution=[32,32,32]"

if ! "$anvil" render --quiet "$src/configs/empty.cfg" $small -o "$tmp/probe.png" 2>/dev/null; then
    [ $? -eq 3 ] && { echo "no OpenGL context: skipped"; exit 77; }
fi

expect_exit 0 "Katrina with terrain, coastlines and graticule" \
    "$anvil" render "$src/configs/katrina.cfg" $small --set map.graticule=true \
    --set scene.height_exaggeration=5 -o "$tmp/k.png"
stderr_has "map: terrain 50 x 50 vertices (land/sea from HGT > 0.5 m), heights x 5"
stderr_has "coastline segments from"
stderr_has "graticule every 2 degrees"

ANVIL_GSHHG_DIR="$tmp/nowhere" expect_exit 0 "no GSHHG files: a warning" \
    "$anvil" render "$src/configs/katrina.cfg" $small -o "$tmp/k2.png"
stderr_has "nowhere/binned_GSHHS_i.nc: cannot read the coastlines"
stderr_has "no coastlines"

expect_exit 0 "the synthetic storm has no lat/lon: no map" \
    "$anvil" render --set scene.size=[16,16,8] $small --set map.graticule=true -o "$tmp/s.png"
stderr_has "no XLAT/XLONG and map.use_origin is off"

expect_exit 0 "the synthetic storm placed over Florida" \
    "$anvil" render "$src/configs/storm-florida.cfg" --set scene.size=[16,16,8] $small \
    -o "$tmp/f.png"
stderr_has "graticule every 0.25 degrees"

expect_exit 1 "a bad exaggeration names the setting" \
    "$anvil" render --set scene.height_exaggeration=0 $small -o "$tmp/x.png"
stderr_has "scene.height_exaggeration"

exit $fail
