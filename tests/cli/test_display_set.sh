#!/bin/bash
# --set of display settings: with --display they go to the display config (after the file,
# checked with it) and change the pictures; without --display they are refused (exit 2);
# bad values and unknown names exit 1 with "--set PATH: expected ...".
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.  Exits 77 when no GL context exists.
. "$(dirname "$0")/lib.sh"

cfg="$src/configs/default.cfg"
cave="$src/displays/cave4.cfg"

expect_exit 2 "display setting without --display" "$anvil" render "$cfg" \
    --set display.eye_separation=0.07 -o "$tmp/x.png"
check "says it needs --display" \
    stderr_has "display.eye_separation is a display setting: it needs --display FILE"
check "nothing written" test ! -e "$tmp/x.png"
expect_exit 2 "a wall setting without --display (run)" "$anvil" run "$cfg" \
    --set walls.[0].mode=mono
check "names the wall setting" stderr_has "walls.\[0\].mode is a display setting"
expect_exit 2 "effects: display setting without --display" "$anvil" effects "$cfg" \
    --set hmd.warp=false
check "effects says it needs --display" stderr_has "hmd.warp is a display setting"

expect_exit 1 "out-of-range display --set" "$anvil" render "$cfg" --display "$cave" \
    --set display.eye_separation=2 -o "$tmp/bad/"
check "names --set, setting and range" \
    stderr_has "--set display.eye_separation: expected a number in \[0, 1\], got 2"
expect_exit 1 "misspelt display --set" "$anvil" render "$cfg" --display "$cave" \
    --set head.postion=[0,1,0] -o "$tmp/bad/"
check "suggests the setting" stderr_has "did you mean head.position?"
expect_exit 1 "a wall the display does not have" "$anvil" render "$cfg" --display "$cave" \
    --set walls.[4].mode=mono -o "$tmp/bad/"
check "says which walls exist" stderr_has "expected a wall index in \[0, 3\]"
expect_exit 1 "head.source=path without head.path" "$anvil" render "$cfg" --display "$cave" \
    --set head.source=path -o "$tmp/bad/"
check "validated after --set" stderr_has "head.path: expected a pose file"
check "no images for bad display --set" test ! -e "$tmp/bad"

# The display's --set decides what effects sees: hmd.warp=false turns the lens warp off.
expect_exit 0 "effects --display hmd.cfg --set hmd.warp=false" "$anvil" effects "$cfg" \
    --display "$src/displays/hmd.cfg" --set hmd.warp=false
check "effects reads the display --set" stdout_has "hmd.warp = false"

# GL from here on.
require_gl

small="--set scene.size=[32,32,16] --set render.height=32 --set lightmap.resolution=[32,32,32]"
render_cave() { # folder, then more options
    local out=$1
    shift
    "$anvil" render -q "$cfg" $small --display "$cave" -o "$tmp/$out/" "$@"
}
render_cave plain
check "plain render" test -f "$tmp/plain/front-left.png"
expect_exit 0 "render --display cave4.cfg with display --set" render_cave moved \
    --set display.eye_separation=0.07 --set 'head.position=[0,1.7,0.4]'
for wall in front left right floor; do
    for eye in left right; do
        check "override changes $wall-$eye.png" \
            bash -c "! cmp -s '$tmp/plain/$wall-$eye.png' '$tmp/moved/$wall-$eye.png'"
    done
done
# The file's own values given again change nothing: the override is what moved the views.
render_cave same --set display.eye_separation=0.065 --set 'head.position=[0.0,1.6,0.5]'
check "the file's values again: same pictures" \
    cmp -s "$tmp/plain/contact.png" "$tmp/same/contact.png"
# Scene and display --set mixed, in any order.
render_cave mixed --set display.eye_separation=0.07 --set render.height=24 \
    --set 'head.position=[0,1.7,0.4]'
check "scene --set still applies beside display --set" \
    test "$(od -An -tu1 -j16 -N8 "$tmp/mixed/front-left.png" | awk '{print $7*256+$8}')" = 24

# display.mode reaches every wall without its own mode; walls.[0].mode is that wall's own.
render_cave modes --set display.mode=mono --set walls.[0].mode=anaglyph
check "walls.[0] keeps its own mode: two eyes" \
    test -f "$tmp/modes/front-left.png" -a -f "$tmp/modes/front-right.png"
for wall in left right floor; do
    check "$wall follows display.mode=mono: one image" \
        test -f "$tmp/modes/$wall.png" -a ! -e "$tmp/modes/$wall-left.png"
done

finish
