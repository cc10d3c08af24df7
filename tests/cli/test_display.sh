#!/bin/bash
# anvil render/run --display: one image per wall and eye plus a contact sheet, --stats counts
# every view, bad display configs exit 1 naming file:line, and real windows under Xvfb.
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.  Exits 77 when no GL context exists.
. "$(dirname "$0")/lib.sh"
is_png() { head -c 8 "$1" | od -c | grep -q 'P   N   G'; }
png_size() { od -An -tu1 -j16 -N8 "$1" | awk '{print $3*256+$4 "x" $7*256+$8}'; }

expect_exit 0 "--display help" "$anvil" render --display help
for b in headless desktop stereo cave hmd; do
    check "help lists $b" grep -q "^  $b " "$tmp/out"
done
expect_exit 2 "render --display without -o" "$anvil" render --display "$src/displays/cave4.cfg"
check "says where the images go" stderr_has "FOLDER"

printf 'display = {\n  type = "cave";\n  mode = "polarised";\n};\n' >"$tmp/bad.cfg"
expect_exit 1 "bad display config" "$anvil" render --display "$tmp/bad.cfg" -o "$tmp/x"
check "names file:line and setting" stderr_has "bad.cfg:3: display.mode: expected one of"
expect_exit 1 "missing display config" "$anvil" render --display "$tmp/none.cfg" -o "$tmp/x"
check "names the missing file" stderr_has "none.cfg"

# GL from here on.
require_gl

small="--set scene.size=[32,32,16] --set render.height=48 --set lightmap.resolution=[32,32,32]"
expect_exit 0 "render --display cave4.cfg" "$anvil" render "$src/configs/default.cfg" $small \
    --display "$src/displays/cave4.cfg" -o "$tmp/cave4/" --stats "$tmp/cave4.json"
for wall in front left right floor; do
    for eye in left right; do
        check "cave4: $wall-$eye.png" is_png "$tmp/cave4/$wall-$eye.png"
    done
done
check "cave4: contact.png" is_png "$tmp/cave4/contact.png"
check "cave4: 48x48 walls" test "$(png_size "$tmp/cave4/front-left.png")" = "48x48"
check "cave4: contact sheet 4 walls x 2 eyes" \
    test "$(png_size "$tmp/cave4/contact.png")" = "202x102"
check "cave4: nothing else written" test "$(ls "$tmp/cave4" | wc -l)" -eq 9
check "cave4 stats: 8 views" grep -q '"views": 8,' "$tmp/cave4.json"
view_count() { sed -n 's/.*"view_ms": \[\(.*\)\].*/\1/p' "$1" | tr ',' '\n' | wc -l; }
check "cave4 stats: 8 view times" test "$(view_count "$tmp/cave4.json")" -eq 8
check "cave4 stats: no non-finite pixels" grep -q '"nonfinite_pixels": 0,' "$tmp/cave4.json"

expect_exit 0 "render --display hmd.cfg" "$anvil" render "$src/configs/default.cfg" $small \
    --display "$src/displays/hmd.cfg" -o "$tmp/hmd"
for f in left right screen contact; do check "hmd: $f.png" is_png "$tmp/hmd/$f.png"; done
expect_exit 0 "render --display desktop-stereo.cfg" "$anvil" render "$src/configs/default.cfg" \
    $small --display "$src/displays/desktop-stereo.cfg" -o "$tmp/stereo"
for f in screen-left screen-right screen; do
    check "stereo: $f.png" is_png "$tmp/stereo/$f.png"
done
expect_exit 0 "render --display desktop.cfg" "$anvil" render "$src/configs/default.cfg" $small \
    --display "$src/displays/desktop.cfg" -o "$tmp/desk"
check "desktop: screen.png" is_png "$tmp/desk/screen.png"

# A scripted head path moves the eyes: two times, two different images.
printf '0 0 1.6 0.5 0 0 0\n10 0.8 1.0 -0.5 40 -20 0\n' >"$tmp/walk.txt"
sed -e 's|source = "fixed";|source = "path"; path = "walk.txt";|' "$src/displays/cave4.cfg" \
    >"$tmp/walk.cfg"
"$anvil" render -q "$src/configs/default.cfg" $small --display "$tmp/walk.cfg" --time 0 \
    -o "$tmp/t0" && "$anvil" render -q "$src/configs/default.cfg" $small \
    --display "$tmp/walk.cfg" --time 10 -o "$tmp/t10"
check "head path renders" test -f "$tmp/t10/front-left.png"
check "head path moves the view" \
    bash -c "! cmp -s '$tmp/t0/front-left.png' '$tmp/t10/front-left.png'"

# A recording of a turned head replays bit for bit on the HMD (OpenHMD's Null device) and on a
# CAVE, whose eyes follow from the recorded head and the display's own separation: at the
# domain fitted to the room and close, 0.5 m ahead, in PFM (every bit of every view).
printf '0 0.3 1.5 -0.2 20 -10 0\n' >"$tmp/turned.txt"
printf 'fps 10\n0 key play\n3 key sun-left\n' >"$tmp/keys.txt"
for d in hmd cave4; do
    for placement in fitted close; do
        nav=
        [ "$placement" = close ] &&
            nav="--set navigation.scale=2e-5 --set navigation.position=[0,1.2,-0.5]"
        out=$tmp/rr-$d-$placement
        expect_exit 0 "$d, $placement: a render of a turned head recorded" "$anvil" render -q \
            "$src/configs/default.cfg" $small $nav --display "$src/displays/$d.cfg" \
            --set 'head.source="path"' --set "head.path=\"$tmp/turned.txt\"" \
            --input "$tmp/keys.txt" --record "$out.txt" --format pfm -o "$out-rec/"
        expect_exit 0 "$d, $placement: its replay" "$anvil" render -q "$src/configs/default.cfg" \
            $small $nav --display "$src/displays/$d.cfg" --input "$out.txt" --format pfm \
            -o "$out-rep/"
        expect_exit 0 "$d, $placement: the display's own head" "$anvil" render -q \
            "$src/configs/default.cfg" $small $nav --display "$src/displays/$d.cfg" \
            --input "$tmp/keys.txt" --format pfm -o "$out-own/"
        same=0 other=0 n=0
        for f in "$out-rec"/*.pfm; do
            n=$((n + 1))
            cmp -s "$f" "$out-rep/$(basename "$f")" && same=$((same + 1))
            cmp -s "$f" "$out-own/$(basename "$f")" || other=$((other + 1))
        done
        check "$d, $placement: every view of the replay is the recorded one ($same of $n)" \
            test "$same" -eq "$n" -a "$n" -ge 2
        check "$d, $placement: ... and the display's own head draws others (the test can fail)" \
            test "$other" -ge 2
    done
done

# Twelve views, one light map.  Until the light map is built by the app, the count is checked
# only where a single view reports one build.
expect_exit 0 "12 views (cave6)" "$anvil" render "$src/configs/default.cfg" $small \
    --set lightmap.mode=dense --display "$src/displays/cave6.cfg" -o "$tmp/cave6" \
    --stats "$tmp/cave6.json"
check "cave6 stats: 12 views" grep -q '"views": 12,' "$tmp/cave6.json"
"$anvil" render -q "$src/configs/default.cfg" $small --set lightmap.mode=dense \
    -o "$tmp/one.png" --stats "$tmp/one.json"
if grep -q '"light_map_builds": 1,' "$tmp/one.json"; then
    check "light_map_builds_once_for_12_views" grep -q '"light_map_builds": 1,' "$tmp/cave6.json"
else
    check "12 views build no light map per view" grep -q '"light_map_builds": 0,' "$tmp/cave6.json"
    echo "note: the app builds no light map yet: light_map_builds_once_for_12_views not run"
fi

# Windows under Xvfb: one per cave4 wall (quad-buffer falls back with a message), and the HMD.
if command -v xvfb-run >/dev/null; then
    ANVIL_RUN_FRAMES=2 timeout 120 xvfb-run -a -s "-screen 0 1024x768x24" "$anvil" run \
        "$src/configs/default.cfg" $small --display "$src/displays/cave4.cfg" \
        --stats "$tmp/run.json" 2>"$tmp/err"
    check "run --display cave4.cfg exits 0" test $? -eq 0
    check "quad-buffer fallback is explained" stderr_has "no stereo framebuffer"
    check "run drew 2 frames x 8 views" grep -q '"views": 16,' "$tmp/run.json"
    ANVIL_RUN_FRAMES=2 timeout 120 xvfb-run -a -s "-screen 0 1280x800x24" "$anvil" run --quiet \
        "$src/configs/default.cfg" $small --display "$src/displays/hmd.cfg" \
        --stats "$tmp/hmd.json" 2>"$tmp/err"
    check "run --display hmd.cfg exits 0" test $? -eq 0
    check "hmd run drew 2 frames x 2 eyes" grep -q '"views": 4,' "$tmp/hmd.json"
else
    echo "xvfb-run not installed: window tests not run"
fi

finish
