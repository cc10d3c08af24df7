#!/bin/bash
# The parts and what they may use (docs/architecture.md): no part includes a part above it,
# the libraries stay with the part that owns them, and every part's header says what it must
# not know.  Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR (only the source is read).
. "$(dirname "$0")/lib.sh"
cd "$src/src" || exit 1

# Each part and the parts it may include, bottom to top ("shaders": the binding numbers shared
# with GLSL, shaders/bindings.h, for the parts that bind textures and buffers).
declare -A allowed=(
    [common]=""
    [optics]="common"
    [config]="common optics"
    [data]="common optics"
    [gpu]="common"
    [input]="common"
    [cluster]="common"
    [render]="common optics data gpu shaders"
    [light]="common optics data gpu render shaders"
    [menu]="common optics input"
    [display]="common config gpu input render shaders"
    [reference]="common optics data render"
    [session]="common optics config data gpu input render light menu display reference"
    [bench]="common optics config data gpu input cluster render light menu display reference session"
    [app]="common optics config data gpu input render light menu display reference session bench cluster"
)
for part in */; do
    part=${part%/}
    check "$part is a known part" test -n "${allowed[$part]+set}"
done
upward() { # the includes of a part above, in the tree under $1: "file->part ..."
    local bad="" f part used
    for f in "$1"/*/*.[ch]; do
        part=${f#"$1"/}
        part=${part%%/*}
        for used in $(sed -n 's|^#include "\([a-z_]*\)/.*|\1|p' "$f" | sort -u); do
            [ "$used" = "$part" ] && continue
            case " ${allowed[$part]} " in *" $used "*) ;; *) bad="$bad ${f#"$1"/}->$used" ;; esac
        done
    done
    echo "$bad"
}
bad=$(upward .)
check "no part includes a part above it${bad:+ (found:$bad)}" test -z "$bad"
# The check itself can fail: a tree with render/ including session/ is caught.
mkdir -p "$tmp/tree/render" "$tmp/tree/session"
printf '#include "session/session.h"\n' >"$tmp/tree/render/a.c"
printf '#include "render/render.h"\n' >"$tmp/tree/session/b.c"
check "a planted upward include is caught" test "$(upward "$tmp/tree")" = " render/a.c->session"

# Libraries: each with its owners only (file or folder prefixes).
only() { # header-pattern description owners...
    local pattern=$1 what=$2
    shift 2
    local found=""
    for f in $(grep -l -E "^#include <($pattern)" */*.[ch]); do
        local ok=0
        for owner in "$@"; do case $f in $owner*) ok=1 ;; esac; done
        [ $ok -eq 1 ] || found="$found $f"
    done
    check "$what only in $*${found:+ (also in:$found)}" test -z "$found"
}
only 'epoxy/|EGL/|GL/|GLES' "OpenGL and EGL" gpu/
only 'GLFW/' "GLFW" gpu/ display/display.c
only 'libconfig\.h' "libconfig" config/
only 'netcdf\.h' "NetCDF" data/
only 'openhmd\.h' "OpenHMD" input/ display/head.c display/hmd.c
only 'openxr/' "OpenXR" display/openxr.c gpu/context_xr.c
only 'stb_truetype\.h' "stb_truetype" common/glyphs.c
only 'png\.h' "libpng" render/image.c
only 'libav|libswscale' "FFmpeg" render/video.c
only 'mpi\.h' "MPI" cluster/cluster.c

# Every part's main header says what it must not know.
declare -A header=(
    [common]=log.h [optics]=optics.h [config]=config.h [data]=volume.h [gpu]=gpu.h
    [input]=input.h [render]=render.h [light]=light.h [menu]=menu.h [display]=display.h
    [reference]=reference.h [session]=session.h [bench]=bench.h [app]=app.h
    [cluster]=cluster.h
)
for part in "${!header[@]}"; do
    check "$part/${header[$part]} says what it must not know" \
        grep -qi "must not know" "$part/${header[$part]}"
done
finish
