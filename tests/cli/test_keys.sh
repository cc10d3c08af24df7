#!/bin/bash
# One key map: the navigation and sun keys mean the same on the orbit camera (no --display)
# and on a tracked display, scripted through --input; `key quit` ends a run; run --help lists
# every key.  Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.
. "$(dirname "$0")/lib.sh"

expect_exit 0 "run --help" "$anvil" run --help
for k in "W " "R, Page Up" "Left" "J " "Space" "Tab, M" "Esc, Q" "Home" "mouse"; do
    check "run --help lists $k" stdout_has "  $k"
done
expect_exit 0 "render --help" "$anvil" render --help
check "render --help lists the keys a script may play" stdout_has "sun elevation"

require_gl
small="--set scene.size=[32,32,16] --set render.width=64 --set render.height=48 --set lightmap.resolution=[24,24,24]"
render() { # NAME SCRIPT-LINES [ARGS...]: renders with the script to $tmp/NAME.pfm or folder
    local name=$1 lines=$2
    shift 2
    printf "$lines" >"$tmp/$name.txt"
    "$anvil" render --quiet $small --input "$tmp/$name.txt" "$@"
}
same() { cmp -s "$1" "$2"; }

render none '0 key menu\n1 key menu\n' -o "$tmp/none.pfm"
for key in sun-left sun-up move-forward move-left move-up turn-left turn-up zoom-in; do
    render "$key" "0 key $key\n" -o "$tmp/$key.pfm"
    check "orbit: key $key changes the picture" bash -c "! cmp -s '$tmp/none.pfm' '$tmp/$key.pfm'"
done
# Opposite keys undo each other (the camera's orbit and the sun come back).
render undo '0 key turn-left\n1 key turn-right\n2 key sun-up\n3 key sun-down\n' -o "$tmp/undo.pfm"
check "orbit: turn-left then turn-right, sun-up then sun-down: the picture is back" \
    same "$tmp/none.pfm" "$tmp/undo.pfm"
render reset '0 key move-forward\n1 key zoom-in\n2 button reset down\n3 button reset up\n' \
    -o "$tmp/reset.pfm"
check "orbit: reset brings the camera back" same "$tmp/none.pfm" "$tmp/reset.pfm"

cave="--display $src/displays/cave4.cfg --format pfm"
render cnone '0 key menu\n1 key menu\n' $cave -o "$tmp/cnone"
for key in sun-left move-forward turn-left zoom-in; do
    render "c$key" "0 key $key\n" $cave -o "$tmp/c$key"
    check "cave4: key $key changes the front wall" \
        bash -c "! cmp -s '$tmp/cnone/front-left.pfm' '$tmp/c$key/front-left.pfm'"
done

if command -v xvfb-run >/dev/null; then
    printf '0 key sun-left\n3 key quit\n' >"$tmp/quit.txt"
    timeout 120 xvfb-run -a -s "-screen 0 800x600x24" "$anvil" run --quiet $small \
        --input "$tmp/quit.txt" --stats "$tmp/quit.json"
    check "run: key quit ends the run (exit 0)" test $? -eq 0
    check "run: it drew frames before it quit" grep -q '"frames": [1-9]' "$tmp/quit.json"
else
    echo "xvfb-run not installed: the window test was not run"
fi
finish
