#!/bin/bash
# anvil run and render on the openxr display through the test runtime (tests/xr/runtime.c,
# found through XR_RUNTIME_JSON): the runtime ending the session ends a run with exit 0, a
# render writes both eyes, the runtime finds no fault, and under Xvfb the Khronos validation
# layer sees the whole run; without a runtime, or with a stage the runtime lacks, one clear
# message and exit 4.  Arguments: the anvil binary, the source folder, the shared data folder.
. "$(dirname "$0")/lib.sh"
manifest=$(dirname "$anvil")/tests/xr/anvil_test_runtime.json
if [ ! -f "$manifest" ]; then
    echo "built without the OpenXR loader (no test runtime): skipping"
    exit 77
fi
require_gl
export XR_RUNTIME_JSON=$manifest
unset XR_ENABLE_API_LAYERS
report() { # report KEY: the value after "KEY " in the runtime's report
    sed -n "s/^$1 //p" "$tmp/report.txt"
}
small="--set scene.size=[32,32,16] --set lightmap.resolution=[24,24,24]"
display=$src/displays/openxr.cfg

# --- A run the runtime ends: the session stops at frame 20, the run exits 0.
printf 'size 64 48\n20 exit\n' >"$tmp/exit.txt"
ANVIL_XR_TEST_SCRIPT=$tmp/exit.txt ANVIL_XR_TEST_REPORT=$tmp/report.txt timeout 120 \
    "$anvil" run --quiet --display "$display" --set 'openxr.binding="egl"' $small \
    --stats "$tmp/run.json" 2>"$tmp/err"
check "a run the runtime stops exits 0" test $? -eq 0
check "the runtime found no fault" test "$(report faults)" = 0
check "the session went to EXITING" grep -q '^states .*STOPPING IDLE EXITING$' "$tmp/report.txt"
check "every frame begun was ended" test "$(report frames_waited)" = "$(report frames_ended)"
check "frames until the stop were submitted" test "$(report layers)" -ge 15
check "the run's frames are in --stats" grep -q '"frames": 2[0-9],' "$tmp/run.json"

# --- A still render through the runtime: both eyes written.
printf 'size 48 40\n' >"$tmp/still.txt"
expect_exit 0 "render through the runtime" env ANVIL_XR_TEST_SCRIPT="$tmp/still.txt" \
    ANVIL_XR_TEST_REPORT="$tmp/report.txt" "$anvil" render --quiet --display "$display" \
    $small -o "$tmp/eyes/"
check "the left and right eyes are written" test -s "$tmp/eyes/left.png" -a -s "$tmp/eyes/right.png"
check "the render's frame was submitted" test "$(report layers)" -ge 1
check "the render found no fault" test "$(report faults)" = 0

# --- Record and replay: a session recorded while the headset moved, replayed through a
# runtime whose headset stands still, draws the same eyes bit for bit: the recording's head and
# the eyes relative to it that the recording's runtime gave (this runtime's VIEW-space eyes carry
# the rounding of its head's turn, as a real runtime's may carry anything), with the runtime's
# frame loop still running.  At the domain fitted to the room (no navigation), at the storm
# 3.5 m ahead, and close, 0.5 m ahead, where the smallest difference in an eye shows.
printf 'size 48 40\n2 head 0.3 1.5 -0.2 20 -10 0\n5 head -0.2 1.7 0.1 -30 5 0\n' >"$tmp/moving.txt"
printf 'fps 10\n0 key play\n3 key sun-left\n7 key sun-up\n' >"$tmp/keys.txt"
printf 'size 48 40\n' >"$tmp/still.txt"
replay() { # replay NAME SETTINGS...: record with the moving headset, replay with the still one
    local name=$1
    shift
    expect_exit 0 "$name: a render recorded with a moving headset" \
        env ANVIL_XR_TEST_SCRIPT="$tmp/moving.txt" "$anvil" render --quiet --display "$display" \
        $small "$@" --input "$tmp/keys.txt" --record "$tmp/$name.txt" --format pfm \
        -o "$tmp/$name-rec/"
    check "$name: the recording holds the moving head" grep -q '^[5-9] head -0.2' "$tmp/$name.txt"
    check "$name: ... and the runtime's eyes beside it" grep -q '^[5-9] eyes -0.03' "$tmp/$name.txt"
    expect_exit 0 "$name: its replay through a still headset" \
        env ANVIL_XR_TEST_SCRIPT="$tmp/still.txt" ANVIL_XR_TEST_REPORT="$tmp/report.txt" \
        "$anvil" render --quiet --display "$display" $small "$@" --input "$tmp/$name.txt" \
        --format pfm -o "$tmp/$name-rep/"
    check "$name: the replay's left eye is the recorded one" \
        cmp -s "$tmp/$name-rec/left.pfm" "$tmp/$name-rep/left.pfm"
    check "$name: the replay's right eye is the recorded one" \
        cmp -s "$tmp/$name-rec/right.pfm" "$tmp/$name-rep/right.pfm"
    check "$name: the replay found no fault" test "$(report faults)" = 0
    expect_exit 0 "$name: the still headset without the recording" \
        env ANVIL_XR_TEST_SCRIPT="$tmp/still.txt" "$anvil" render --quiet --display "$display" \
        $small "$@" --input "$tmp/keys.txt" --format pfm -o "$tmp/$name-still/"
    check "$name: ... draws other eyes (the test can fail)" \
        bash -c "! cmp -s '$tmp/$name-rec/left.pfm' '$tmp/$name-still/left.pfm'"
}
replay fitted
replay far --set navigation.scale=1e-4 --set navigation.position=[0,0,-3.5]
replay close --set navigation.scale=2e-5 --set navigation.position=[0,1.2,-0.5]
# The recording's head with the still runtime's own eyes (its eyes lines taken out) is not the
# recorded picture at the fitted placement: the eyes lines are what makes the replay exact.
grep -v '^[0-9]* eyes ' "$tmp/fitted.txt" >"$tmp/no-eyes.txt"
expect_exit 0 "a replay without the eyes lines" env ANVIL_XR_TEST_SCRIPT="$tmp/still.txt" \
    "$anvil" render --quiet --display "$display" $small --input "$tmp/no-eyes.txt" --format pfm \
    -o "$tmp/no-eyes/"
check "... differs from the recording (the runtime's eyes are not the recorded ones)" \
    bash -c "! cmp -s '$tmp/fitted-rec/left.pfm' '$tmp/no-eyes/left.pfm'"

# --- The effects: the runtime warps, anvil does not.
expect_exit 0 "anvil effects for the openxr display" "$anvil" effects --quiet --display "$display"
check "distortion is off: the runtime warps" stdout_has "distortion *off .*OpenXR runtime warps"

# --- No runtime; a stage the runtime lacks.
expect_exit 4 "no runtime" env XR_RUNTIME_JSON="$tmp/none.json" "$anvil" run --quiet \
    --display "$display" --set 'openxr.binding="egl"'
check "no runtime: named, with what to do" stderr_has "no runtime could be loaded"
printf 'stage off\n' >"$tmp/nostage.txt"
expect_exit 4 "a stage the runtime lacks" env ANVIL_XR_TEST_SCRIPT="$tmp/nostage.txt" \
    "$anvil" run --quiet --display "$display" --set 'openxr.binding="egl"' \
    --set 'openxr.space="stage"'
check "no stage: named" stderr_has 'openxr.space = "stage": the runtime has no stage'
expect_exit 1 "openxr.resolution_scale out of range" "$anvil" run --quiet --display "$display" \
    --set openxr.resolution_scale=5
check "the range is named" stderr_has "openxr.resolution_scale"

# --- Under Xvfb: the xlib binding (a GLX mirror window), with the Khronos validation layer.
if command -v xvfb-run >/dev/null &&
    [ -f /usr/share/openxr/1/api_layers/explicit.d/XrApiLayer_core_validation.x86_64-linux-gnu.json ]; then
    ANVIL_XR_TEST_SCRIPT=$tmp/exit.txt ANVIL_XR_TEST_REPORT=$tmp/report.txt \
        XR_ENABLE_API_LAYERS=XR_APILAYER_LUNARG_core_validation \
        XR_CORE_VALIDATION_EXPORT_TYPE=text XR_CORE_VALIDATION_FILE_NAME=$tmp/layer.txt \
        timeout 120 xvfb-run -a -s "-noreset -screen 0 1024x768x24" "$anvil" run --quiet \
        --display "$display" --set 'openxr.binding="xlib"' $small 2>"$tmp/err"
    check "a validated xlib run exits 0" test $? -eq 0
    check "the validation layer was loaded" grep -q "Core Validation" "$tmp/err"
    check "the binding was xlib" test "$(report binding)" = xlib
    check "the validation layer reported no error" \
        bash -c "! grep -s VALID_ERROR '$tmp/layer.txt'"
    check "the xlib run found no fault" test "$(report faults)" = 0
else
    echo "xvfb-run or the validation layer missing: the validated run was not made"
fi
finish
