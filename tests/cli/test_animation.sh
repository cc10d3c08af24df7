#!/bin/bash
# Animations as a user makes them: output names checked before any work, a progress line on
# a terminal (and none with --quiet), and in a window the screenshot, bookmark and camera path
# keys.  Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.
. "$(dirname "$0")/lib.sh"
small="--set scene.size=[24,24,12] --set render.width=48 --set render.height=36 --set lightmap.resolution=[16,16,16]"

expect_exit 1 "a movie into a folder that is not there" "$anvil" render $small -o "$tmp/none/x.mp4"
check "says which folder" stderr_has "none does not exist"
expect_exit 1 "numbered images without a number" "$anvil" render $small --frames all -o "$tmp/f.png"
check "says what a sequence name is" stderr_has "frame-%05d.png"
expect_exit 1 "two numbers" "$anvil" render $small -o "$tmp/f-%d-%d.png"
expect_exit 1 "--display with one image" "$anvil" render $small --display "$src/displays/cave4.cfg" -o "$tmp/x.png"
check "says -o names a folder" stderr_has "names a folder"
expect_exit 1 "a still into a folder that is not there" "$anvil" render $small -o "$tmp/none/x.png"
expect_exit 2 "--frames with run" "$anvil" run $small --frames all
expect_exit 1 "a bad frame range" "$anvil" render $small --frames 3:1 -o "$tmp/f-%d.png"
expect_exit 1 "a bad frame rate" "$anvil" render $small --fps 0 -o "$tmp/f.mp4"
check "one line says so, no usage after it" test "$(wc -l <"$tmp/err")" -eq 1
# The range is read before the data: a file that is not there is not what it stops at.
expect_exit 1 "a bad frame range before the data" "$anvil" render "$tmp/none.nc" \
    --frames 2:1 -o "$tmp/f-%d.png"
check "it names the range" stderr_has "\-\-frames 2:1: expected all or FIRST:LAST"
expect_exit 1 "an unknown encoder" "$anvil" render $small --codec nosuch -o "$tmp/f.mp4"
check "names the encoders there are" stderr_has "it has:"
check "no movie left behind" bash -c "! ls '$tmp'/f.mp4* 2>/dev/null | grep -q ."

require_gl
cat >"$tmp/fly.cfg" <<'PATH'
camera_path = { keys = (
  { time = 0.0; position = [2.0, -14.0, 4.0]; target = [30.0, 30.0, 7.0]; },
  { time = 8.0; position = [60.0, -5.0, 9.0]; target = [30.0, 30.0, 5.0]; }
); };
PATH
expect_exit 1 "the steps of a storm past its one step" "$anvil" render $small --frames 0:3 -o "$tmp/s-%d.png"
check "says which steps there are" stderr_has "time steps 0 to 0"

# Progress on a terminal: the status line with the frame count; nothing with --quiet.
if command -v script >/dev/null; then
    script -qfec "ANVIL_PROGRESS_QUIET_MS=0 '$anvil' render $small --path '$tmp/fly.cfg' --fps 10 -o '$tmp/fly.mp4'" \
        /dev/null >"$tmp/tty.txt" 2>&1
    check "progress: the frames counted on a terminal" grep -q "render: frame [0-9]* of 81" "$tmp/tty.txt"
    check "progress: the movie is there" test -s "$tmp/fly.mp4"
    script -qfec "ANVIL_PROGRESS_QUIET_MS=0 '$anvil' --quiet render $small --path '$tmp/fly.cfg' --fps 10 -o '$tmp/q.mp4'" \
        /dev/null >"$tmp/quiet.txt" 2>&1
    check "progress: nothing with --quiet" bash -c "! grep -q 'frame' '$tmp/quiet.txt'"
else
    echo "script(1) not installed: the terminal progress test was not run"
fi
ANVIL_PROGRESS_QUIET_MS=0 "$anvil" render $small --path "$tmp/fly.cfg" --fps 10 \
    -o "$tmp/plain.mp4" 2>"$tmp/plain.txt"
check "progress: plain lines off a terminal" grep -q "render: frame [0-9]* of 81" "$tmp/plain.txt"
check "progress: no terminal codes off a terminal" bash -c "! grep -q $'\r' '$tmp/plain.txt'"

# A window: screenshot, bookmark, two path keys and a flight, then quit.
if command -v xvfb-run >/dev/null; then
    printf '0 key screenshot\n1 key bookmark\n2 key path-key\n3 key turn-left\n4 key zoom-in\n5 key path-key\n6 key path-play\n120 key quit\n' >"$tmp/keys.txt"
    (cd "$tmp" && timeout 120 xvfb-run -a -s "-screen 0 800x600x24" "$anvil" run --quiet $small \
        --input keys.txt --path path.cfg >bookmark.out)
    check "run with the keys exits 0" test $? -eq 0
    check "screenshot: PNG and PFM" bash -c "ls '$tmp'/anvil-*-1.png '$tmp'/anvil-*-1.pfm >/dev/null"
    check "bookmark: the camera block printed" grep -q "camera = {" "$tmp/bookmark.out"
    check "bookmark: a file" test -f "$tmp/bookmark-1.cfg"
    (cd "$tmp" && "$anvil" render --quiet $small bookmark-1.cfg -o b.png)
    check "bookmark: it renders" test -s "$tmp/b.png"
    check "path: two keys saved" test "$(grep -c 'time =' "$tmp/path.cfg")" -eq 2
    (cd "$tmp" && "$anvil" render --quiet $small --path path.cfg --fps 2 -o 'k-%d.png')
    check "path: the saved path renders" test -f "$tmp/k-6.png"
else
    echo "xvfb-run not installed: the window test was not run"
fi
finish
