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

# ---- NetCDF: the header checked against the file before netcdf-c reads it ---------------
"$anvil" --quiet synth -o storm.nc --size 8x8x4 --steps 3 || fail=1
head -c 30000 storm.nc >cut.nc
expect_exit 1 "info on a synth file cut short" "$anvil" info cut.nc
check "it names the file and says truncated" stderr_has "cut.nc: 64-bit offset NetCDF header: .*truncated"
check "nothing was described" test ! -s out
head -c 14 storm.nc >tiny.nc
expect_exit 1 "info on the file's first 14 bytes" "$anvil" info tiny.nc
check "it says the header ends early" stderr_has "tiny.nc: .*the header ends early"
# 20000 x 20000 columns declared in 18 KB: opening is bounded by the budget (info's --memory).
ncgen -k nc4 -o huge.nc "$src/tests/data/hostile/wrf_20000x20000.cdl"
expect_exit 1 "info on 20000 x 20000 columns in 18 KB" timeout 20 "$anvil" info huge.nc
check "it gives the budget" stderr_has "huge.nc: opening a grid of 20000 x 20000 columns .* data.memory = 4096 MiB"
"$anvil" --quiet synth -o step.nc --size 40x40x20 || fail=1
expect_exit 1 "info --memory 1 on a 40 x 40 x 20 step" "$anvil" info --memory 1 step.nc
check "its step is above that budget" stderr_has "step.nc: one time step .* data.memory = 1 MiB"
expect_exit 1 "info --memory with no number" "$anvil" info --memory lots storm.nc
finish
