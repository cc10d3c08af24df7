#!/bin/bash
# The storm in its place from the command line: Katrina with terrain, coastlines and graticule;
# a missing GSHHG folder or an unplaced synthetic scene is a message, exit 0 and a flat ground.
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.  Exits 77 when no GL context exists.
. "$(dirname "$0")/lib.sh"
small="--set render.width=96 --set render.height=72 --set lightmap.resolution=[32,32,32]"

require_gl

expect_exit 0 "Katrina with terrain, coastlines and graticule" \
    "$anvil" render "$src/configs/katrina.cfg" $small --set map.graticule=true \
    --set scene.height_exaggeration=5 -o "$tmp/k.png"
check "map: terrain 50 x 50 vertices (land/sea from HGT > 0.5 m), heights x 5" stderr_has "map: terrain 50 x 50 vertices (land/sea from HGT > 0.5 m), heights x 5"
check "coastline segments from" stderr_has "coastline segments from"
check "graticule every 2 degrees" stderr_has "graticule every 2 degrees"

ANVIL_GSHHG_DIR="$tmp/nowhere" expect_exit 0 "no GSHHG files: a warning" \
    "$anvil" render "$src/configs/katrina.cfg" $small -o "$tmp/k2.png"
check "nowhere/binned_GSHHS_i.nc: cannot read the coastlines" stderr_has "nowhere/binned_GSHHS_i.nc: cannot read the coastlines"
check "no coastlines" stderr_has "no coastlines"

expect_exit 0 "the synthetic storm has no lat/lon: no map" \
    "$anvil" render --set scene.size=[16,16,8] $small --set map.graticule=true -o "$tmp/s.png"
check "no XLAT/XLONG and map.use_origin is off" stderr_has "no XLAT/XLONG and map.use_origin is off"

expect_exit 0 "the synthetic storm placed over Florida" \
    "$anvil" render "$src/configs/storm-florida.cfg" --set scene.size=[16,16,8] $small \
    -o "$tmp/f.png"
check "graticule every 0.25 degrees" stderr_has "graticule every 0.25 degrees"

expect_exit 1 "a bad exaggeration names the setting" \
    "$anvil" render --set scene.height_exaggeration=0 $small -o "$tmp/x.png"
check "scene.height_exaggeration" stderr_has "scene.height_exaggeration"

finish
