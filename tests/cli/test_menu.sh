#!/bin/bash
# The menu driven by scripted input (docs/menu.md): playback through the time series cache,
# the transfer function editor (a moved control point changes the image with exactly one light
# map rebuild), saving and loading named transfer functions, the CAVE and the Null HMD.
# Arguments: the anvil binary, the source folder, the shared data folder.
. "$(dirname "$0")/lib.sh"
json() { # json FILE KEY: the number after "KEY":
    sed -n "s/^ *\"$2\": \([-0-9.]*\),*$/\1/p" "$1"
}
small="--set scene.size=[32,32,16] --set render.width=160 --set render.height=120 --set lightmap.resolution=[32,32,32]"

# No GL context: skip like the GL tests.
require_gl

# --- Playback of a synthetic WRF series: 1 step per second, 10 frames per second.
"$anvil" synth -o "$tmp/series.nc" --steps 6 --size 16x16x8 2>/dev/null
cat >"$tmp/series.cfg" <<CFG
scene = { kind = "data"; };
data = { format = "wrf"; files = ["series.nc"]; prefetch = 2; };
playback = { speed = 1.0; loop = false; };
CFG
printf 'fps 10\n0 key play\n30 key play\n45 key forward\n' >"$tmp/play.txt"
"$anvil" render --quiet "$tmp/series.cfg" $small --input "$tmp/play.txt" -o "$tmp/play.png" \
    --stats "$tmp/play.json" --set 'effects.temporal="off"'
check "scripted playback exits 0" test $? -eq 0
# Frames 0..29 play (30 ticks of 0.1 s at 1 step/s), 30 pauses, 45 steps forward once.
check "played 3 steps, paused, stepped to 4" test "$(json "$tmp/play.json" time_step)" = 4
check "steps came through the cache" test "$(json "$tmp/play.json" cache_loads)" -ge 4
check "one light map build per new step" test "$(json "$tmp/play.json" light_map_builds)" -eq \
    $(($(json "$tmp/play.json" volume_uploads) + 1))
# The first step is read once: the cache keeps the volume the session was made with, so
# stepping forward and back again reads step 1 alone (no prefetch: data.prefetch = 0).
printf 'fps 10\n0 key forward\n5 key back\n' >"$tmp/back.txt"
"$anvil" render --quiet "$tmp/series.cfg" $small --input "$tmp/back.txt" -o "$tmp/back.png" \
    --stats "$tmp/back.json" --set 'effects.temporal="off"' --set data.prefetch=0
check "stepped forward and back exits 0" test $? -eq 0
check "back on step 0" test "$(json "$tmp/back.json" time_step)" = 0
check "the first step is not read again" test "$(json "$tmp/back.json" cache_loads)" -eq 1
check "both steps in the cache" test "$(json "$tmp/back.json" cache_steps)" -eq 2
# Each step's build says the same of the map: one line at the default level, the rest with
# --verbose.
"$anvil" render "$tmp/series.cfg" $small --input "$tmp/play.txt" -o "$tmp/play.png" \
    --set 'effects.temporal="off"' 2>"$tmp/play.log"
check "a played series logs its light map once" test "$(grep -c 'light map 32x32x32' "$tmp/play.log")" -eq 1
"$anvil" render --verbose "$tmp/series.cfg" $small --input "$tmp/play.txt" -o "$tmp/play.png" \
    --set 'effects.temporal="off"' 2>"$tmp/play.log"
check "--verbose logs every build" test "$(grep -c 'light map 32x32x32' "$tmp/play.log")" -ge 4

# --- The same with temporal interpolation (auto: on for a scripted series).  One light map per
# step that reached the GPU, never one per frame: steps 0..4 shown and 5 held as the next one.
"$anvil" effects --quiet "$tmp/series.cfg" --input "$tmp/play.txt" >"$tmp/effects.txt"
check "temporal is on for scripted playback" grep -q "temporal  *on  *(auto)" "$tmp/effects.txt"
"$anvil" effects --quiet "$tmp/series.cfg" >"$tmp/effects.txt"
check "temporal is off for a still render" grep -q "temporal  *off .*still render" \
    "$tmp/effects.txt"
for mode in dense compressed; do
    "$anvil" render --quiet "$tmp/series.cfg" $small --input "$tmp/play.txt" \
        -o "$tmp/temporal-$mode.png" --stats "$tmp/temporal-$mode.json" \
        --set "lightmap.mode=\"$mode\""
    check "temporal playback ($mode) exits 0" test $? -eq 0
    check "temporal playback ($mode) ends on step 4" \
        test "$(json "$tmp/temporal-$mode.json" time_step)" = 4
    check "temporal ($mode): one build per step, 6 over 46 frames" \
        test "$(json "$tmp/temporal-$mode.json" light_map_builds)" -eq 6
done

# --- Transfer function editor: the same script with and without moving a control point.
cat >"$tmp/tf.txt" <<'SCRIPT'
0 key menu
0 aim tab.transfer
1 button trigger down
2 button trigger up
3 aim transfer.function
4 button trigger down
5 button trigger up
6 aim transfer.mode
7 button trigger down
8 button trigger up
10 aim transfer.canvas 0.9875 0.5
40 key menu
SCRIPT
# (the menu is hidden again at the end, so only the volume can differ in the images)
head -n -1 "$tmp/tf.txt" >"$tmp/tfmove.txt"
cat >>"$tmp/tfmove.txt" <<'SCRIPT'
11 button trigger down
12 aim transfer.canvas 0.9 0.2
13 aim transfer.canvas 0.9875 0.05
14 button trigger up
40 key menu
SCRIPT
for n in tf tfmove; do
    "$anvil" render --quiet $small --input "$tmp/$n.txt" -o "$tmp/$n.png" --stats "$tmp/$n.json"
    check "$n script exits 0" test $? -eq 0
done
check "moving a control point changes the image" bash -c "! cmp -s '$tmp/tf.png' '$tmp/tfmove.png'"
check "moving a control point rebuilds the light map exactly once" test \
    "$(json "$tmp/tfmove.json" light_map_builds)" -eq $(($(json "$tmp/tf.json" light_map_builds) + 1))

# --- Save into slot 2, then load a corrupt slot 3: refused, the current function kept.
mkdir "$tmp/tfs"
head -n -1 "$tmp/tfmove.txt" >"$tmp/save.txt"
cat >>"$tmp/save.txt" <<'SCRIPT'
20 aim transfer.slot.2
21 button trigger down
22 button trigger up
23 aim transfer.save
24 button trigger down
25 button trigger up
30 aim transfer.slot.3
31 button trigger down
32 button trigger up
33 aim transfer.load
34 button trigger down
35 button trigger up
40 key menu
SCRIPT
printf 'transfer = {\n  field = "qvapor";\n  range = [0.0, 0.01];\n  density = 0.002;\n  red = ([0.0, 2.0]);\n};\n' \
    >"$tmp/tfs/tf-3.cfg"
"$anvil" render $small --input "$tmp/save.txt" --transfers "$tmp/tfs" -o "$tmp/save.png" \
    2>"$tmp/err"
check "save and failed load exit 0" test $? -eq 0
check "the saved file exists" test -f "$tmp/tfs/tf-2.cfg"
check "the saved file names its slot" grep -q 'name = "tf-2"' "$tmp/tfs/tf-2.cfg"
check "the corrupt file is refused with file:line" grep -q "tf-3.cfg:5: transfer.red\[0\]" "$tmp/err"
check "the current function is kept (image as before the load)" cmp -s "$tmp/tfmove.png" "$tmp/save.png"
# A saved file loads back into the same image.
cp "$tmp/tfs/tf-2.cfg" "$tmp/tfs/tf-4.cfg"
head -n -1 "$tmp/tf.txt" >"$tmp/reload.txt"
printf '20 aim transfer.slot.4\n21 button trigger down\n22 button trigger up\n23 aim transfer.load\n24 button trigger down\n25 button trigger up\n40 key menu\n' \
    >>"$tmp/reload.txt"
"$anvil" render --quiet $small --input "$tmp/reload.txt" --transfers "$tmp/tfs" -o "$tmp/reload.png"
check "a loaded function renders as the one saved" cmp -s "$tmp/tfmove.png" "$tmp/reload.png"

# --- The diffuse light toggled off on the Quality page: the picture becomes the one rendered
# with effects.multiple off, after exactly one more light map build.
cat >"$tmp/diffuse.txt" <<'SCRIPT'
0 key menu
0 aim tab.quality
1 button trigger down
2 button trigger up
3 aim quality.diffuse
4 button trigger down
5 button trigger up
10 key menu
SCRIPT
printf '0 key menu\n10 key menu\n' >"$tmp/nodiffuse.txt"
"$anvil" render --quiet $small --input "$tmp/diffuse.txt" -o "$tmp/diffuse.png" \
    --stats "$tmp/diffuse.json"
check "diffuse toggle script exits 0" test $? -eq 0
"$anvil" render --quiet $small --input "$tmp/nodiffuse.txt" -o "$tmp/plain.png" \
    --stats "$tmp/plain.json"
"$anvil" render --quiet $small --input "$tmp/nodiffuse.txt" -o "$tmp/single.png" \
    --set 'effects.multiple="off"'
check "diffuse off from the menu draws what effects.multiple off draws" \
    cmp -s "$tmp/diffuse.png" "$tmp/single.png"
check "the diffuse light shows in the default picture" \
    bash -c "! cmp -s '$tmp/plain.png' '$tmp/single.png'"
check "toggling the diffuse light rebuilds the light map once" test \
    "$(json "$tmp/diffuse.json" light_map_builds)" -eq $(($(json "$tmp/plain.json" light_map_builds) + 1))

# --- The level of detail set on the Quality page: the picture changes (160 x 120 pixels are
# wider than the small storm's steps), fewer extinction samples are taken, and Save view's
# bookmark holds render.lod and renders the session's picture.
mkdir -p "$tmp/lod"
cat >"$tmp/lod/in.txt" <<'SCRIPT'
0 key menu
0 aim tab.quality
1 button trigger down
2 button trigger up
3 aim quality.lod 0.4 0.5
4 button trigger down
5 button trigger up
6 aim tab.time
7 button trigger down
8 button trigger up
9 aim time.save
10 button trigger down
11 button trigger up
12 key menu
SCRIPT
(cd "$tmp/lod" && "$anvil" render --quiet $small --input in.txt -o session.pfm \
    --stats session.json >/dev/null)
check "lod script exits 0" test $? -eq 0
check "lod: the bookmark holds render.lod" grep -q '^render = { lod = [1-9]' "$tmp/lod/bookmark-1.cfg"
(cd "$tmp/lod" && "$anvil" render --quiet bookmark-1.cfg $small -o batch.pfm \
    --stats batch.json)
check "lod: the bookmark renders the session's picture" \
    cmp -s "$tmp/lod/session.pfm" "$tmp/lod/batch.pfm"
"$anvil" render --quiet $small --input "$tmp/nodiffuse.txt" -o "$tmp/lod/plain.pfm" \
    --stats "$tmp/lod/plain.json"
check "lod: not the plain picture" bash -c "! cmp -s '$tmp/lod/plain.pfm' '$tmp/lod/batch.pfm'"
check "lod: fewer extinction samples than the plain picture" awk \
    -v a="$(json "$tmp/lod/batch.json" beta_samples)" -v b="$(json "$tmp/lod/plain.json" beta_samples)" \
    'BEGIN { exit !(a < b) }'

# --- A bad script is refused with file:line.
printf '0 key play\n1 wiggle\n' >"$tmp/bad.txt"
"$anvil" render --quiet $small --input "$tmp/bad.txt" -o "$tmp/bad.png" 2>"$tmp/err"
check "a bad script exits 1" test $? -eq 1
check "a bad script names file:line" grep -q "bad.txt:2:" "$tmp/err"

# --- The CAVE and the Null HMD, offscreen, with the menu shown.
printf '0 aim tab.light\n1 button trigger down\n2 button trigger up\n' >"$tmp/light.txt"
"$anvil" render --quiet $small --display "$src/displays/cave4.cfg" --menu \
    --input "$tmp/light.txt" -o "$tmp/cave/"
check "cave4 with the menu exits 0" test $? -eq 0
"$anvil" render --quiet $small --display "$src/displays/hmd.cfg" --menu --input "$tmp/light.txt" \
    -o "$tmp/hmd/"
check "the Null HMD with the menu exits 0" test $? -eq 0

# --- A window under Xvfb: the desktop wand and playback for a few frames.
if command -v xvfb-run >/dev/null; then
    printf '0 key play\n' >"$tmp/run.txt"
    ANVIL_RUN_FRAMES=4 timeout 120 xvfb-run -a -s "-screen 0 800x600x24" "$anvil" run --quiet \
        "$tmp/series.cfg" $small --input "$tmp/run.txt" --stats "$tmp/run.json"
    check "run with a script in a window exits 0" test $? -eq 0
    check "run never blocked a frame on a load" test "$(json "$tmp/run.json" frames_waited)" -eq 0
    # A script's aims in a window: the pointer, which does not move, does not take them back
    # before the trigger acts (the level of detail set on the Quality page, then Save view).
    mkdir -p "$tmp/runlod"
    sed 's/^12 key menu$/12 key menu\n14 key quit/' "$tmp/lod/in.txt" >"$tmp/runlod/in.txt"
    (cd "$tmp/runlod" && timeout 120 xvfb-run -a -s "-screen 0 800x600x24" "$anvil" run --quiet \
        $small --input in.txt >/dev/null)
    check "run: a script's aims and clicks on the menu in a window" \
        grep -q '^render = { lod = [1-9]' "$tmp/runlod/bookmark-1.cfg"
fi

finish
