#!/bin/bash
# Bad input found by fuzzing and fault injection: each case gets one clear message and its
# documented exit code (docs/user-guide.md), never a signal, a hang or silent zeros.
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.
. "$(dirname "$0")/lib.sh"
cd "$tmp" || exit 1
small=(--set render.width=8 --set render.height=8)
# Whether an OpenGL 4.5 context can be made (the cases that need one are skipped otherwise).
gl=1
"$anvil" render --quiet "$src/configs/empty.cfg" "${small[@]}" -o probe.png 2>/dev/null
[ $? -eq 3 ] && gl=0 && echo "no OpenGL context: the render cases are skipped"

# ---- text inputs: regular files only, at most 64 MiB ------------------------------------
mkfifo fifo
# A FIFO without a writer would block for ever, /dev/zero never ends: both refused at once.
expect_exit 1 "a config that is /dev/zero" timeout 20 "$anvil" render /dev/zero -o x.png
check "it says it is no regular file" stderr_has "/dev/zero: not a regular file (a character device)"
expect_exit 1 "a config that is a FIFO" timeout 20 "$anvil" render fifo -o x.png
check "it says it is a FIFO" stderr_has "fifo: not a regular file (a FIFO)"
printf 'scene = { kind = "empty"; };\n@include "fifo"\n' >inc.cfg
expect_exit 1 "an @include of a FIFO" timeout 20 "$anvil" render inc.cfg -o x.png
check "it names the including line" stderr_has "inc.cfg:2: @include: .*fifo: not a regular file"
truncate -s 65M big.cfg
expect_exit 1 "a 65 MiB config" timeout 20 "$anvil" render big.cfg -o x.png
check "it gives the limit" stderr_has "big.cfg: 68157440 bytes: larger than the 64 MiB"
if [ $gl -eq 1 ]; then
    expect_exit 1 "--input FIFO" timeout 60 "$anvil" render "$src/configs/empty.cfg" \
        "${small[@]}" --input fifo -o x.png
    check "it says so" stderr_has "fifo: not a regular file (a FIFO)"
fi

# ---- exit 3 only for a missing OpenGL context: a bad pose file or device is bad input --------
expect_exit 1 "an unknown OpenHMD device" "$anvil" render "$src/configs/empty.cfg" \
    --display "$src/displays/hmd.cfg" --set hmd.device=nosuch -o hmd/
check "it names the device" stderr_has 'no HMD named "nosuch"'
expect_exit 3 "run without a window system" env -u DISPLAY -u WAYLAND_DISPLAY "$anvil" run \
    "$src/configs/empty.cfg" --display "$src/displays/hmd.cfg"
if [ $gl -eq 1 ]; then
    printf '0 0 1.6 0 0 0 0\n1 0 1.6 0 zero 0 0\n' >bad.path
    printf 'display = { type = "headless"; };\nhead = { source = "path"; path = "bad.path"; };\n' \
        >pose.cfg
    expect_exit 1 "a bad head pose file" "$anvil" render "$src/configs/empty.cfg" \
        --display pose.cfg -o pose/
    check "it names the file and line" stderr_has "bad.path:2: expected 7 numbers"
    printf 'display = { type = "headless"; };\nhead = { source = "path"; path = "fifo"; };\n' \
        >fifo.cfg
    expect_exit 1 "a head path that is a FIFO" timeout 20 "$anvil" render \
        "$src/configs/empty.cfg" --display fifo.cfg -o pose/
    check "it says so" stderr_has "fifo: not a regular file (a FIFO)"
fi

# ---- scripts: every frame bounded, every widget known before the first frame ---------------
if [ $gl -eq 1 ]; then
    printf '0 key play\n9000000000000000000 key quit\n' >far.txt
    expect_exit 1 "a script frame of 9e18" timeout 60 "$anvil" render "$src/configs/empty.cfg" \
        "${small[@]}" --input far.txt -o far.png
    check "it names the line and the limit" stderr_has "far.txt:2: expected a frame number from 0 to 1000000"
    printf '0 key menu\n1 aim time.paly\n2 button trigger down\n' >typo.txt
    expect_exit 1 "a misspelled widget" "$anvil" render "$src/configs/empty.cfg" "${small[@]}" \
        --input typo.txt -o typo.png
    check "it names the line and the widget" stderr_has 'typo.txt:2: expected a widget of the menu .*"time.paly"'
    check "no picture is written" test ! -e typo.png
    printf '0 key menu\n1 aim light.azimuth\n' >other.txt
    expect_exit 0 "a widget of another page is known" "$anvil" render "$src/configs/empty.cfg" \
        "${small[@]}" --input other.txt -o other.png
fi

# ---- saving a transfer function respects the file it would replace ---------------------
if [ $gl -eq 1 ]; then
    printf '0 key menu\n0 aim tab.transfer\n1 button trigger down\n2 button trigger up\n' >save.txt
    printf '3 aim transfer.function\n4 button trigger down\n5 button trigger up\n' >>save.txt
    printf '6 aim transfer.save\n7 button trigger down\n8 button trigger up\n' >>save.txt
    mkdir -p ro link
    echo "# mine" >ro/tf-1.cfg
    chmod 0444 ro/tf-1.cfg
    "$anvil" render "$src/configs/empty.cfg" "${small[@]}" --input save.txt --transfers ro \
        -o ro.png 2>"$tmp/err"
    check "a read-only tf-1.cfg is refused" stderr_has "ro/tf-1.cfg: read-only (mode 0444): not replaced"
    check "and left as it was" test "$(cat ro/tf-1.cfg)" = "# mine" -a "$(stat -c %a ro/tf-1.cfg)" = 444
    echo "# old" >real.cfg
    ln -s ../real.cfg link/tf-1.cfg
    "$anvil" render --quiet "$src/configs/empty.cfg" "${small[@]}" --input save.txt \
        --transfers link -o link.png
    check "a symlinked tf-1.cfg stays a link" test -L link/tf-1.cfg
    check "the file it points to holds the save" grep -q "transfer" real.cfg
fi

# ---- NetCDF: the header checked against the file before netcdf-c reads it ---------------
"$anvil" --quiet synth -o storm.nc --size 8x8x4 --steps 3 || fail=1
head -c 30000 storm.nc >cut.nc
expect_exit 1 "info on a synth file cut short" "$anvil" info cut.nc
check "it names the file and says truncated" stderr_has "cut.nc: 64-bit offset NetCDF header: .*truncated"
check "nothing was described" test ! -s out
head -c 14 storm.nc >tiny.nc
expect_exit 1 "info on the file's first 14 bytes" "$anvil" info tiny.nc
check "it says the header ends early" stderr_has "tiny.nc: .*the header ends early"
# A NetCDF-4 file HDF5 crashes on while netcdf-c opens it (found by fuzzing HDF5 inputs; it
# aborted anvil, exit 134): the crash is the library's, named with the file, exit 1.
gunzip -c "$src/tests/data/hostile/hdf5_crash.nc.gz" >h5crash.nc
expect_exit 1 "a file HDF5 crashes on" "$anvil" info h5crash.nc
check "it names the file" stderr_has "h5crash.nc"
check "and the library when it crashed" bash -c "! grep -q 'crashed' '$tmp/err' ||
    grep -q 'netCDF-C (with HDF5) crashed (SIG[A-Z]*) opening h5crash.nc' '$tmp/err'"
# 20000 x 20000 columns declared in 18 KB: opening is bounded by the budget (info's --memory).
ncgen -k nc4 -o huge.nc "$src/tests/data/hostile/wrf_20000x20000.cdl"
expect_exit 1 "info on 20000 x 20000 columns in 18 KB" timeout 20 "$anvil" info huge.nc
check "it gives the budget" stderr_has "huge.nc: opening a grid of 20000 x 20000 columns .* data.memory = 4096 MiB"
"$anvil" --quiet synth -o step.nc --size 40x40x20 || fail=1
expect_exit 1 "info --memory 1 on a 40 x 40 x 20 step" "$anvil" info --memory 1 step.nc
check "its step is above that budget" stderr_has "step.nc: one time step .* data.memory = 1 MiB"
expect_exit 1 "info --memory with no number" "$anvil" info --memory lots storm.nc

# ---- a full disk: HDF5 crashed in its exit handler after the failed write (exit 139) -------
# A file size limit with SIGXFSZ ignored makes writes fail as on a full disk.
echo "the old file" >full.nc
(trap '' XFSZ; ulimit -f 20; exec "$anvil" --quiet convert step.nc -o full.nc) 2>"$tmp/err"
rc=$?
check "convert onto a full disk exits 4 (got $rc)" test $rc -eq 4
check "it names the file and the library's error" stderr_has "full.nc.tmp.*NetCDF: HDF error"
check "no temporary file is left" test -z "$(compgen -G 'full.nc.tmp*')"
check "the old file is kept" grep -q "the old file" full.nc

# ---- signals: SIGINT and SIGTERM remove the temporary file and keep the old one -----------
# Runs COMMAND... in the background (SIGINT not ignored, as it is for a script's background
# jobs), waits for its temporary file OUT.tmp*, sends SIG, and leaves the exit code in $rc.
interrupt() { # SIG OUT COMMAND...
    local sig=$1 out=$2
    shift 2
    env --default-signal=INT "$@" 2>"$tmp/err" &
    local pid=$! n=0
    until compgen -G "$out.tmp*" >/dev/null || ! kill -0 $pid 2>/dev/null || [ $n -ge 2000 ]; do
        sleep 0.01
        n=$((n + 1))
    done
    kill -"$sig" $pid
    wait $pid
    rc=$?
}
"$anvil" --quiet synth -o series.nc --size 64x64x32 --steps 8 || fail=1
for sig in INT TERM; do
    code=$([ $sig = INT ] && echo 130 || echo 143)
    echo "the old file" >kept.nc
    interrupt $sig kept.nc "$anvil" synth -o kept.nc --size 128x128x32 --steps 10000
    check "synth stopped by SIG$sig exits $code (got $rc)" test $rc -eq $code
    check "it says so and what it removed" stderr_has "interrupted (SIG$sig); removed kept.nc.tmp"
    check "no temporary file is left" test -z "$(compgen -G 'kept.nc.tmp*')"
    check "the old file is kept" grep -q "the old file" kept.nc
    interrupt $sig kept.nc "$anvil" convert series.nc -o kept.nc
    check "convert stopped by SIG$sig exits $code (got $rc)" test $rc -eq $code
    check "no temporary file is left" test -z "$(compgen -G 'kept.nc.tmp*')"
    check "the old file is kept" grep -q "the old file" kept.nc
done
if [ $gl -eq 1 ]; then
    # A movie and a recording are written beside their files too.
    echo "the old movie" >kept.mp4
    echo "the old recording" >kept.txt
    printf 'fps 10\n0 key play\n100000 key play\n' >long.txt
    interrupt INT kept.mp4 "$anvil" render "$src/configs/default.cfg" "${small[@]}" \
        --input long.txt --record kept.txt -o kept.mp4
    check "a movie stopped by SIGINT exits 130 (got $rc)" test $rc -eq 130
    check "it names the movie's temporary file" stderr_has "removed .*kept.mp4.tmp"
    check "and the recording's" stderr_has "removed .*kept.txt.tmp"
    check "no temporary file is left" test -z "$(compgen -G 'kept.*.tmp*')"
    check "the old movie is kept" grep -q "the old movie" kept.mp4
    check "the old recording is kept" grep -q "the old recording" kept.txt
fi
rm -f series.nc

# ---- option values: exit 1 with one message (docs/user-guide.md, "Exit codes") ----------
expect_exit 1 "render --time that is no number" "$anvil" render --time abc -o x.png
expect_exit 1 "render --format jpg" "$anvil" render --format jpg -o x.png
expect_exit 1 "synth --steps 0" "$anvil" synth --steps 0 -o x.nc
expect_exit 1 "synth --size 8x8" "$anvil" synth --size 8x8 -o x.nc
expect_exit 1 "trackers --seconds -1" "$anvil" trackers "$src/displays/cave4-dtrack.cfg" --seconds -1
check "no usage after it" test "$(wc -l <"$tmp/err")" -eq 1
expect_exit 1 "synth into a picture's name" "$anvil" synth -o x.png
check "it says synth writes NetCDF" stderr_has "x.png: synth writes NetCDF"
expect_exit 1 "--set with no setting before the =" "$anvil" render --set =3 -o x.png
check "it says what is missing" stderr_has "no setting before the '='"
check "nothing was written" test ! -e x.png -a ! -e x.nc

# ---- output names: refused before the work, which for a reference may take hours ----------
# With a billion samples a pixel the trace would never end: the checks must come first.
expect_exit 1 "a reference into a folder that is not there" timeout 20 "$anvil" reference \
    "${small[@]}" --spp 1000000000 -o nodir/ref.pfm
check "it names the folder" stderr_has "the folder nodir does not exist"
expect_exit 1 "a reference into an unknown image type" timeout 20 "$anvil" reference \
    "${small[@]}" --spp 1000000000 -o ref.jpg
check "it says what names it takes" stderr_has "ref.jpg: unknown image type: expected a name ending in .pfm"
expect_exit 1 "a reference of one sample a pixel (no standard error)" "$anvil" reference \
    "${small[@]}" --spp 1 -o ref.pfm
check "it asks for two" stderr_has "expected an integer in \[2,"
check "no image is written" test ! -e ref.pfm -a ! -e ref.stderr.pfm
echo "a file" >afile
expect_exit 1 "a picture into a folder that is a file" "$anvil" render "${small[@]}" -o afile/x.png
check "it says the file is no folder" stderr_has "afile/x.png: afile is not a folder"
finish
