#!/bin/sh
# The pictures that must not change when the program's structure does: each case renders
# headless into OUT.  tests/gl/test_golden.c runs this script and compares every PFM it writes
# with the one of the same name in this folder (made by the same script, at the commit that
# the file's own history names).  Made before the session and the one frame loop replaced the
# four loops of old; menu.pfm again when panels came to show their own sRGB colours under the
# Reinhard tone mapping (they had been made for an older 1 - exp(-x) one), and when the menu
# gained its Probe page and Save view button, its Layers and Slices pages, the Time page's
# Frame button, and tabs as wide as their titles.  katrina.pfm is on uniform levels, as it was made; katrina-native.pfm, made
# when the model's own levels became the default, on those, and made again when empty-space
# skipping on those levels was made exact (the eye pass steps over clear cells as the plain
# march steps through them; the light build finds each level's cells by height).  The data cases keep the cameras
# they were made with (a scene of data without a camera is framed), the tracked displays their
# navigation.  All were made again when the rays came from the projection and the view
# inverted apart (shaders/common.glsl view_ray) instead of one float inverse of their product.
#   sh tests/data/golden/cases.sh ANVIL_BINARY SOURCE_DIR OUT_DIR
set -e
anvil=$1
src=$2
out=$3
mkdir -p "$out"
small="--set render.width=64 --set render.height=48"
"$anvil" render -q "$src/configs/default.cfg" $small -o "$out/default.pfm"
"$anvil" render -q "$src/configs/katrina.cfg" $small --set 'camera.position=[-60,-120,90]' \
    --set 'camera.target=[240,240,0]' --set camera.fov=45 --set camera.far=5000 \
    --set data.vertical=uniform -o "$out/katrina.pfm"
# The same on the model's own levels (data.vertical's default since they came).
"$anvil" render -q "$src/configs/katrina.cfg" $small --set 'camera.position=[-60,-120,90]' \
    --set 'camera.target=[240,240,0]' --set camera.fov=45 --set camera.far=5000 \
    -o "$out/katrina-native.pfm"
# The tracked displays keep the navigation they were made with (without one the domain is fitted
# to the room).
"$anvil" render -q "$src/configs/default.cfg" --set render.height=32 \
    --display "$src/displays/cave4.cfg" --set navigation.scale=1e-4 \
    --set 'navigation.origin=[30,30,0]' --set 'navigation.position=[0,0,-2]' \
    --format pfm -o "$out/cave4"
"$anvil" render -q "$src/configs/default.cfg" --set render.height=32 \
    --display "$src/displays/hmd.cfg" --set navigation.scale=1e-4 \
    --set 'navigation.origin=[30,30,0]' --set 'navigation.position=[0,0,-3.5]' \
    --format pfm -o "$out/hmd"
"$anvil" render -q "$src/configs/default.cfg" --set render.height=32 \
    --display "$src/displays/desktop-stereo.cfg" --format pfm -o "$out/stereo"
# The menu in the world (a still render with the menu shown).
"$anvil" render -q "$src/configs/default.cfg" --set render.width=96 --set render.height=72 \
    --set 'scene.size=[32,32,16]' --set 'lightmap.resolution=[32,32,32]' --menu \
    -o "$out/menu.pfm"
# Scripted playback of a WRF-convention series with temporal blending: the script pauses
# between two steps, so the picture is a blend of two volumes and two light maps.
"$anvil" --quiet synth -o "$out/series.nc" --steps 4 --size 16x16x8 >/dev/null
printf 'scene = { kind = "data"; };\ncamera = { fov = 50.0; };\ndata = { format = "wrf"; files = ["series.nc"]; };\nplayback = { speed = 1.0; loop = false; };\n' \
    >"$out/series.cfg"
printf 'fps 10\n0 key play\n14 key play\n' >"$out/play.txt"
"$anvil" render -q "$out/series.cfg" $small --set 'lightmap.resolution=[32,32,32]' \
    --input "$out/play.txt" -o "$out/playback.pfm"
rm -f "$out/series.nc" "$out/series.cfg" "$out/play.txt" "$out"/*/contact.pfm
