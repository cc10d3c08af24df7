#!/bin/bash
# On an NVIDIA GPU machine, from the project folder with build-device/ (made by
# tests/tools/device-kit.sh) carried along: checks that EGL finds the GPU, renders the default
# storm, and runs `anvil bench --gpu`; gpu-table.md, the picture and the logs go to $OUT.
# DEVICE_KIT_SYSTEM_GL=1: the machine's own glvnd (no packages unpacked into /);
# DEVICE_BENCH_ARGS: more options for the bench (--quick: a try on any machine).
set -u
kit=build-device
out=${OUT:-/tmp/anvil-device}
mkdir -p "$out"
if [ -z "${DEVICE_KIT_SYSTEM_GL:-}" ]; then
    for f in "$kit"/gl/*.deb; do dpkg -x "$f" /; done
    ldconfig
fi
lib=$(mktemp -d)
tar -xJf "$kit/lib.tar.xz" -C "$lib"
export LD_LIBRARY_PATH="$lib/lib"
vendor=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
[ -e "$vendor" ] && export __EGL_VENDOR_LIBRARY_FILENAMES="$vendor"
export ANVIL_SHADER_DIR="$PWD/shaders"
{
    nvidia-smi -L
    uname -a
    echo "libraries not found:"
    ldd "$kit/anvil" | grep "not found"
} >"$out/machine.txt" 2>&1
timeout 120 "$kit/anvil" render -o "$out/storm.png" --stats "$out/render.json" \
    >"$out/render.log" 2>&1
echo "render rc $?" >>"$out/render.log"
timeout "${DEVICE_BENCH_TIMEOUT:-420}" "$kit/anvil" bench --gpu --displays displays -o "$out" \
    ${DEVICE_BENCH_ARGS:-} >"$out/bench.log" 2>&1
rc=$?
echo "bench rc $rc" >>"$out/bench.log"
tail -5 "$out/bench.log"
exit $rc
