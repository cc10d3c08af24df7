#!/bin/bash
# Makes build-device/: anvil for an NVIDIA GPU machine that has no Debian packages and can
# download nothing (an image of its own with the driver mounted), with every library it loads
# but the C and C++ runtimes' and OpenGL's dispatch, packed, and glvnd's packages, through which EGL
# finds the NVIDIA driver there.  Built without FFmpeg, MPI and OpenXR, which the GPU benchmark
# does not use.  Run from the project folder on the Debian 12 machine (after apt-get update);
# on the GPU machine, with build-device carried along: bash tests/tools/device-bench.sh
set -eu
kit=build-device
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
rm -rf "$kit"
mkdir -p "$kit/gl" "$work/lib"
cmake -S . -B "$work/build" -DCMAKE_BUILD_TYPE=Release -DANVIL_VIDEO=OFF -DANVIL_MPI=OFF \
    -DANVIL_OPENXR=OFF -DBUILD_TESTING=OFF >"$work/cmake.log"
cmake --build "$work/build" -j"$(nproc)" --target anvil >"$work/build.log"
cp "$work/build/anvil" "$kit/anvil"
strip "$kit/anvil"
ldd "$kit/anvil" | awk '$2 == "=>" && $3 ~ /^\// {print $1, $3}' | while read -r name path; do
    case $name in
    libc.so.* | libm.so.* | libpthread.so.* | libdl.so.* | librt.so.* | ld-linux*) ;;
    # The machine's own, newer and compatible: the GPU driver may need its version.
    libstdc++.so.* | libgcc_s.so.*) ;;
    libEGL.so.* | libGL.so.* | libGLX.so.* | libOpenGL.so.* | libGLdispatch.so.*) ;;
    *) cp -L "$path" "$work/lib/" ;;
    esac
done
tar -cJf "$kit/lib.tar.xz" -C "$work" lib
(cd "$kit/gl" && apt-get download -q libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2 \
    >/dev/null)
echo "device-kit: $kit: $(du -sh "$kit" | cut -f1) ($(ls "$work/lib" | wc -l) libraries)"
