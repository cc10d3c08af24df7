#!/bin/bash
# A tracked CAVE as its engineer meets it, with the tracker on loopback (tests/support's
# fake_tracker: a DTrack sender, a VRPN server): anvil trackers prints the calibrated poses,
# rates and counts; bad addresses are refused naming file:line; a render recorded with a live,
# moving head replays bit for bit without the tracker; a run under Xvfb follows the head,
# shrugs off malformed datagrams and records what it saw; walls find their outputs by name.
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.  Exits 77 when no GL context exists.
. "$(dirname "$0")/lib.sh"
fake=${ANVIL_FAKE_TRACKER:-$(dirname "$anvil")/tests/fake_tracker}
cave_dtrack="$src/displays/cave4-dtrack.cfg"
cave_vrpn="$src/displays/cave4-vrpn.cfg"
pids=()
trap 'for p in "${pids[@]}"; do kill "$p" 2>/dev/null; done; rm -rf "$tmp"' EXIT

# DTrack (z up, mm): the head at x 100 then -200 (0.3 m to the left), the Flystick still;
# every third frame the head is not tracked.
cat >"$tmp/dtrack.txt" <<'EOF'
ts 100.0
6dcal 2
6d 1 [0 1.000][100.0 -500.0 1650.0][1 0 0 0 1 0 0 0 1]
6df2 1 1 [0 1.000 6 2][200.0 -900.0 1200.0][1 0 0 0 1 0 0 0 1][1 0.0 0.5]
---
ts 100.1
6dcal 2
6d 1 [0 1.000][-200.0 -500.0 1650.0][1 0 0 0 1 0 0 0 1]
6df2 1 1 [0 1.000 6 2][200.0 -900.0 1200.0][1 0 0 0 1 0 0 0 1][0 0.0 0.5]
---
ts 100.2
6dcal 2
6d 0
6df2 1 1 [0 -1.000 6 2][0 0 0][0 0 0 0 0 0 0 0 0][0 0.0 0.5]
EOF
start_dtrack() { # FILE SECONDS: a sender on a free port, its port in $port
    port=$("$fake" port)
    "$fake" dtrack "$port" "$1" 60 "$2" &
    pids+=($!)
}

expect_exit 2 "trackers without a display file" "$anvil" trackers
expect_exit 1 "trackers of a display without trackers" "$anvil" trackers \
    "$src/displays/cave4.cfg" --seconds 0.1
check "says neither is a tracker" stderr_has "neither head.source"
expect_exit 1 "the same with --display, as render takes it" "$anvil" trackers \
    --display "$src/displays/cave4.cfg" --seconds 0.1
check "the same file read" stderr_has "neither head.source"
printf '@include "%s"\nhead = {\n  address = "Head@tracker";\n};\n' \
    "$(cd "$src" && pwd)/displays/cave4-dtrack.cfg" >"$tmp/bad.cfg"
expect_exit 1 "a VRPN address for DTrack" "$anvil" trackers "$tmp/bad.cfg" --seconds 0.1
check "names file:line and setting" stderr_has 'bad.cfg:3: head.address: expected "PORT"'

# anvil trackers: the calibrated poses (axes x z -y, mm), the rates, the ids in the stream.
start_dtrack "$tmp/dtrack.txt" 4
expect_exit 0 "trackers on a DTrack stream" "$anvil" trackers "$cave_dtrack" \
    --set head.address=$port --set wand.address=$port --seconds 1.6 --interval 0.4
# (A report may fall on a frame that does not track the head: it then shows its last pose.)
state="[A-Za-z ()]*" # tracked, or NOT TRACKED (last pose)
check "head in room coordinates" \
    stdout_has "head  DTrack body 0 on port $port: $state  x \(0.100\|-0.200\) y 1.650 z 0.500 m"
check "wand in room coordinates" \
    stdout_has "wand  DTrack Flystick 0 on port $port: .* x 0.200 y 1.200 z 0.900 m"
check "the stick's fly axis" stdout_has "fly 0.50"
check "untracked frames counted" bash -c "grep -q 'untracked [1-9][0-9]* frames' '$tmp/out'"
check "the link's frames and ids" \
    stdout_has "link  DTrack port $port: receiving, .* 0 dropped, 0 malformed; seen: bodies 0, Flysticks 0"
check "poses per second" bash -c "grep -q 'deg  [1-9][0-9]* Hz' '$tmp/out'"

# VRPN: the server's axes are z up too; the head at (0.12, -0.48, 1.65), turned 90 degrees.
cat >"$tmp/vrpn.txt" <<'EOF'
pose Head 0 0.12 -0.48 1.65 0 0 0.7071067811865476 0.7071067811865476
pose Wand 0 0.3 -0.9 1.2 0 0 0 1
button Wand 0 1
analog Wand 0.0 -0.5
EOF
"$fake" vrpn "$tmp/vrpn.port" "$tmp/vrpn.txt" 60 4 &
pids+=($!)
for i in $(seq 200); do [ -s "$tmp/vrpn.port" ] && break; sleep 0.05; done
vport=$(cat "$tmp/vrpn.port")
expect_exit 0 "trackers on a VRPN server" "$anvil" trackers "$cave_vrpn" \
    --set head.address=Head@127.0.0.1:$vport --set wand.address=Wand@127.0.0.1:$vport \
    --set wand.controls=Wand@127.0.0.1:$vport --seconds 1.2 --interval 0.6
check "VRPN head in room coordinates" stdout_has \
    "head  VRPN Head@127.0.0.1:$vport sensor 0: $state  x 0.120 y 1.650 z 0.480 m  heading 90.0 pitch 0.0 roll 0.0 deg"
check "VRPN wand's trigger and fly" stdout_has "buttons trigger (pressed: 0)  fly -0.50  turn 0.00"
check "one connection" stdout_has "link  VRPN 127.0.0.1:$vport: receiving, .* 1 connections"

# GL from here on.
require_gl
small="--set scene.size=[32,32,16] --set render.height=48 --set lightmap.resolution=[32,32,32]"
cat >"$tmp/script.txt" <<'EOF'
fps 10
0 key menu
1 aim time.play
2 button trigger down
3 button trigger up
5 key sun-left
EOF
# A render with a live, moving head, recorded; replayed without any tracker: the same images.
# The head walks 30 tracked poses, 20 mm apart (a different one every 1/60 s), so two drawn
# frames record the same head only if they fall on one datagram; the stick still, no buttons.
for i in $(seq 0 29); do
    printf 'ts %d.0\n6dcal 2\n6d 1 [0 1.000][%d.0 -500.0 1650.0][1 0 0 0 1 0 0 0 1]\n' \
        "$i" $((20 * i - 300))
    printf '6df2 1 1 [0 1.000 6 2][200.0 -900.0 1200.0][1 0 0 0 1 0 0 0 1][0 0.0 0.5]\n---\n'
done >"$tmp/dtrack-walk.txt"
start_dtrack "$tmp/dtrack-walk.txt" 20
expect_exit 0 "render a live tracked CAVE with --record" "$anvil" render \
    "$src/configs/default.cfg" $small --display "$cave_dtrack" --set head.address=$port \
    --set wand.address=$port --input "$tmp/script.txt" --record "$tmp/rec.txt" -o "$tmp/live/"
kill "${pids[-1]}" 2>/dev/null
check "a recording" grep -q "^recorded render" "$tmp/rec.txt"
check "no temporary file left" test -z "$(compgen -G "$tmp/rec.txt.tmp*")"
check "the head moved while recording" \
    test "$(grep ' head ' "$tmp/rec.txt" | cut -d' ' -f3- | sort -u | wc -l)" -ge 2
check "the wand's ray was recorded" grep -q "pose tracker 0.200000003 1.20000005 0.899999976" \
    "$tmp/rec.txt"
expect_exit 0 "replay the recording, no tracker" "$anvil" render "$src/configs/default.cfg" \
    $small --display "$cave_dtrack" --input "$tmp/rec.txt" -o "$tmp/replay/"
check "the replay says where the head comes from" stderr_has "replaying its head and wand"
same=1
for f in "$tmp"/live/*.png; do cmp -s "$f" "$tmp/replay/$(basename "$f")" || same=0; done
check "the replay is bit for bit the live render (9 images)" \
    test "$same" -eq 1 -a "$(ls "$tmp"/live/*.png | wc -l)" -eq 9
sed -e 's/^\(3 head\) .*/\1 0 1.6 0.5 0 0 0 2/' "$tmp/rec.txt" >"$tmp/badrec.txt"
expect_exit 1 "a recording with a bad head line" "$anvil" render "$src/configs/default.cfg" \
    $small --display "$cave_dtrack" --input "$tmp/badrec.txt" -o "$tmp/bad/"
check "names file:line" stderr_has "badrec.txt:[0-9]*: expected \"head X Y Z QX QY QZ QW\""

# anvil run under Xvfb: follows the head, refuses malformed datagrams with a warning, records.
if command -v xvfb-run >/dev/null; then
    { cat "$tmp/dtrack.txt"; printf -- '---\n6d 2 [0 1.0][1 2 3][1 0 0 0 1 0 0 0 1]\n'; } \
        >"$tmp/dtrack-bad.txt"
    start_dtrack "$tmp/dtrack-bad.txt" 60
    win="--set display.window_size=[64,64]" # monitor 0 is Xvfb's whole screen: small ones
    small_screen="-screen 0 320x240x24"
    ANVIL_RUN_FRAMES=12 timeout 120 xvfb-run -a -s "$small_screen" "$anvil" run \
        "$src/configs/default.cfg" $small $win --display "$cave_dtrack" \
        --set head.address=$port --set wand.address=$port --record "$tmp/run.txt" \
        2>"$tmp/err"
    check "run --display cave4-dtrack.cfg exits 0" test $? -eq 0
    kill "${pids[-1]}" 2>/dev/null
    check "the head's first pose is reported" stderr_has "head: DTrack body 0 on port $port: first pose"
    check "a malformed datagram is warned about" stderr_has "ignored a malformed datagram (line"
    check "the run followed the tracked head" \
        grep -q " head 0.100000001 1.64999998 0.5 \| head -0.200000003 1.64999998 0.5 " \
        "$tmp/run.txt"
    check "recorded by run" grep -q "^recorded run" "$tmp/run.txt"
    check "12 drawn frames recorded" test "$(grep -c ' head ' "$tmp/run.txt")" -ge 12
    expect_exit 0 "a run's recording replays headless" "$anvil" render \
        "$src/configs/default.cfg" $small --display "$cave_dtrack" --input "$tmp/run.txt" \
        -o "$tmp/run-replay/"

    # The same with a VRPN server: the head and the wand (its trigger held) in the recording.
    rm -f "$tmp/vrpn.port"
    "$fake" vrpn "$tmp/vrpn.port" "$tmp/vrpn.txt" 60 60 &
    pids+=($!)
    for i in $(seq 200); do [ -s "$tmp/vrpn.port" ] && break; sleep 0.05; done
    vport=$(cat "$tmp/vrpn.port")
    ANVIL_RUN_FRAMES=6 timeout 120 xvfb-run -a -s "$small_screen" "$anvil" run \
        "$src/configs/default.cfg" $small $win --display "$cave_vrpn" \
        --set head.address=Head@127.0.0.1:$vport --set wand.address=Wand@127.0.0.1:$vport \
        --set wand.controls=Wand@127.0.0.1:$vport --record "$tmp/vrpn-run.txt" 2>"$tmp/err"
    check "run --display cave4-vrpn.cfg exits 0" test $? -eq 0
    kill "${pids[-1]}" 2>/dev/null
    check "the VRPN run followed the head" \
        grep -q " head 0.119999997 1.64999998 0.479999989 [-0-9.e]* 0.707106769 [-0-9.e]* 0.707106769" \
        "$tmp/vrpn-run.txt"
    check "and the wand" grep -q " pose tracker 0.300000012 1.20000005 0.899999976 " \
        "$tmp/vrpn-run.txt"
    check "and its trigger" grep -q " button trigger down" "$tmp/vrpn-run.txt"

    # Walls by output name: an unknown one is explained with the outputs there are.
    sed -e 's/monitor = 0;/output = "NO-SUCH-1";/' "$src/displays/cave4.cfg" >"$tmp/named.cfg"
    ANVIL_RUN_FRAMES=1 timeout 120 xvfb-run -a -s "$small_screen" "$anvil" run \
        "$src/configs/default.cfg" $small $win --display "$tmp/named.cfg" 2>"$tmp/err"
    check "run with an unknown output exits 0" test $? -eq 0
    check "the unknown output is named" stderr_has 'output "NO-SUCH-1" is not connected (outputs: '
    name=$(sed -n 's/.*is not connected (outputs: \([^ ]*\) at .*/\1/p' "$tmp/err" | head -1)
    check "the outputs there are are listed" test -n "$name"
    # Passive stereo: the front wall's left eye on that output, found by its name, the right
    # eye in a window of its own where no output is.
    sed -e 's/{ name = "front"; monitor = 0;/{ name = "front"; mode = "passive"; output = "'"$name"'"; right_window = [0, 0, 64, 64];/' \
        "$src/displays/cave4.cfg" >"$tmp/passive.cfg"
    ANVIL_RUN_FRAMES=2 timeout 120 xvfb-run -a -s "$small_screen" "$anvil" run \
        "$src/configs/default.cfg" $small $win --display "$tmp/passive.cfg" --stats "$tmp/p.json" \
        2>"$tmp/err"
    check "a passive wall runs" test $? -eq 0
    check "the output \"$name\" is found by its name" bash -c "! grep -q 'not connected' '$tmp/err'"
    check "the passive wall's right eye has its window" stderr_has "no output is exactly at 0,0 64x64"
    check "8 views a frame" grep -q '"views": 16,' "$tmp/p.json"
else
    echo "xvfb-run not installed: run tests not run"
fi

finish
