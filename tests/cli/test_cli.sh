#!/bin/bash
# The command line as a user meets it: help, version, exit codes, messages with file:line,
# PNG/PFM/stats output, nothing half-written on failure, and a real window under Xvfb.
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.  Exits 77 when no GL context exists.
. "$(dirname "$0")/lib.sh"

expect_exit 0 "--help" "$anvil" --help
check "--help lists render and run" grep -q "render" "$tmp/out"
expect_exit 0 "--version" "$anvil" --version
check "--version prints the version" grep -q "^anvil [0-9]" "$tmp/out"
expect_exit 2 "no command" "$anvil"
expect_exit 2 "unknown command" "$anvil" frobnicate
expect_exit 2 "render without -o" "$anvil" render "$src/configs/default.cfg"
expect_exit 0 "--config-reference" "$anvil" --config-reference
check "reference lists light.elevation" grep -q "light.elevation" "$tmp/out"

# Bad configs: exit 1, one message naming file and line.
printf 'light = { elevation = 120.0; };\n' >"$tmp/range.cfg"
expect_exit 1 "out-of-range value" "$anvil" render "$tmp/range.cfg" -o "$tmp/x.png"
check "message names file:line and setting" stderr_has "range.cfg:1"
check "message names the setting" stderr_has "light.elevation"
printf 'light = {\n  elevation = ;\n};\n' >"$tmp/syntax.cfg"
expect_exit 1 "syntax error" "$anvil" render "$tmp/syntax.cfg" -o "$tmp/x.png"
check "syntax error names file:line" stderr_has "syntax.cfg:2"
expect_exit 1 "missing config" "$anvil" render "$tmp/missing.cfg" -o "$tmp/x.png"
check "missing file named" stderr_has "missing.cfg"
expect_exit 1 "bad --set" "$anvil" render "$src/configs/default.cfg" --set light.elevaton=3 \
    -o "$tmp/x.png"
check "--set error names the setting" stderr_has "light.elevaton"

expect_exit 1 "a synthetic scene over the memory budget" "$anvil" render \
    --set scene.size=[500,500,100] --set data.memory=100 -o "$tmp/x.png"
check "the message names the settings that fix it" stderr_has "lower scene.size or raise data.memory"

# GL from here on.
require_gl

small="--set scene.size=[48,48,24] --set render.width=160 --set render.height=120"
expect_exit 0 "render PNG with stats" "$anvil" render "$src/configs/default.cfg" $small \
    -o "$tmp/storm.png" --stats "$tmp/stats.json"
check "PNG written" bash -c "head -c 8 '$tmp/storm.png' | od -c | grep -q 'P   N   G'"
for key in views light_map_builds view_ms build_ms gpu_bytes nonfinite_pixels; do
    check "stats has $key" grep -q "\"$key\"" "$tmp/stats.json"
done
check "stats: one view" grep -q '"views": 1,' "$tmp/stats.json"
# What the rays did: every pixel counted once, a fraction of them marched (empty-space
# skipping), a few extinction samples each, and the volume's bytes (48 x 48 x 24 x 8).
check "stats: every ray counted" grep -q '"rays": 19200,' "$tmp/stats.json"
check "stats: the volume's bytes uploaded" grep -q '"upload_bytes": 442368,' "$tmp/stats.json"
marched=$(grep -o '"rays_marched": [0-9]*' "$tmp/stats.json" | grep -o '[0-9]*$')
check "stats: some rays marched, not all ($marched)" test "${marched:-0}" -gt 0 -a "${marched:-0}" -lt 19200
samples=$(grep -o '"beta_samples_per_pixel": [0-9.]*' "$tmp/stats.json" | grep -o '[0-9.]*$')
check "stats: extinction samples per pixel ($samples)" \
    awk -v v="${samples:-0}" 'BEGIN { exit !(v > 1 && v < 100) }'
check "stats: no non-finite pixels" grep -q '"nonfinite_pixels": 0,' "$tmp/stats.json"
expect_exit 0 "render PFM" "$anvil" render --quiet "$src/configs/default.cfg" $small \
    -o "$tmp/storm.pfm"
check "PFM header" bash -c "head -c 3 '$tmp/storm.pfm' | grep -q PF"
check "PFM size" bash -c "[ \$(stat -c %s '$tmp/storm.pfm') -gt \$((160*120*12)) ]"
check "quiet is quiet" bash -c "[ ! -s '$tmp/err' ]"
expect_exit 1 "unknown image extension" "$anvil" render "$src/configs/empty.cfg" \
    -o "$tmp/x.jpg"
check "extension error explains" stderr_has ".png or .pfm"

# Real WRF output: the Katrina sample renders, finite, with one light map build.
katrina="$3/wrf/katrina_2005_mercator_wsm3.nc"
if [ -f "$katrina" ]; then
    expect_exit 0 "render Katrina" "$anvil" render --quiet "$src/configs/katrina.cfg" \
        --set "data.files=$katrina" --set data.step=2 --set render.width=96 \
        --set render.height=72 -o "$tmp/katrina.png" --stats "$tmp/katrina.json"
    check "Katrina: no non-finite pixels" grep -q '"nonfinite_pixels": 0,' "$tmp/katrina.json"
    check "Katrina: one light map build" grep -q '"light_map_builds": 1,' "$tmp/katrina.json"
    expect_exit 1 "a time step the file lacks" "$anvil" render "$src/configs/katrina.cfg" \
        --set "data.files=$katrina" --set data.step=7 -o "$tmp/x.png"
    check "the message names data.step and the range" stderr_has "data.step: expected a time step in \[0, 3\]"
else
    echo "Katrina sample not found beside the repository: not rendered"
fi

# A failed render or a failed write leaves the old file intact.
echo "precious" >"$tmp/keep.png"
"$anvil" render --quiet "$tmp/range.cfg" -o "$tmp/keep.png" 2>/dev/null
check "old file intact after a bad config" grep -q precious "$tmp/keep.png"
mkdir "$tmp/locked"
echo "precious" >"$tmp/locked/keep.png"
if chattr +i "$tmp/locked" 2>/dev/null; then
    "$anvil" render --quiet "$src/configs/empty.cfg" -o "$tmp/locked/keep.png" 2>"$tmp/err"
    rc=$?
    chattr -i "$tmp/locked"
    check "failed write exits 4" test $rc -eq 4
    check "failed write names the file" stderr_has "keep.png"
    check "old file intact after a failed write" grep -q precious "$tmp/locked/keep.png"
    check "no temporary file left" bash -c "[ \$(ls '$tmp/locked' | wc -l) -eq 1 ]"
else
    echo "chattr not supported here: failed-write check not run"
fi

# A window under Xvfb, a few frames.
if command -v xvfb-run >/dev/null; then
    ANVIL_RUN_FRAMES=2 timeout 120 xvfb-run -a -s "-screen 0 800x600x24" "$anvil" run --quiet \
        "$src/configs/default.cfg" $small --stats "$tmp/run.json" 2>"$tmp/err"
    rc=$?
    check "run in a window exits 0" test $rc -eq 0
    check "run drew two frames" grep -q '"views": 2,' "$tmp/run.json"
    # SIGTERM (or Ctrl-C) ends a run as closing its window does: the recording and --stats
    # are written, the exit code says what stopped it.
    # (anvil's own exit code is kept beside its pid: xvfb-run's may be that of its clean-up.)
    rm -f "$tmp/run.pid" "$tmp/run.pid.rc" "$tmp/run.json"
    timeout 120 xvfb-run -a -s "-screen 0 800x600x24" sh -c \
        '"$@" & echo $! >"$0"; wait $!; echo $? >"$0.rc"' "$tmp/run.pid" \
        "$anvil" run "$src/configs/default.cfg" $small --stats "$tmp/run.json" \
        --record "$tmp/run.rec" 2>"$tmp/err" &
    waiter=$! n=0
    # The first frame is drawn once the recording has its first frame's lines.
    until [ -s "$tmp/run.pid" ] && grep -qs "^1 " "$tmp/run.rec".tmp* || [ $n -ge 600 ]; do
        sleep 0.1
        n=$((n + 1))
    done
    kill -TERM "$(cat "$tmp/run.pid")"
    wait $waiter
    rc=$(cat "$tmp/run.pid.rc" 2>/dev/null)
    check "a run stopped by SIGTERM exits 143 (got $rc)" test "$rc" = 143
    check "it says how it ends" stderr_has "interrupted (SIGTERM): ending as if the window"
    check "its --stats are written and say so" grep -q '"stopped_by": "SIGTERM"' "$tmp/run.json"
    check "its recording is kept" grep -q "^recorded run" "$tmp/run.rec"
    expect_exit 0 "the recording replays" "$anvil" render "$src/configs/default.cfg" $small \
        --input "$tmp/run.rec" -o "$tmp/replayed.png"
else
    echo "xvfb-run not installed: window test not run"
fi

finish
