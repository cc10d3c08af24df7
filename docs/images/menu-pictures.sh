#!/bin/sh
# Draws the menu pictures of docs/menu.md from Hurricane Katrina (configs/katrina.cfg, the
# files in ../shared/data), one scripted render a page: run from the project folder after a
# build,  sh docs/images/menu-pictures.sh [build/anvil]
set -eu
anvil=${1:-build/anvil}
out=docs/images
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# SCRIPT-NAME WIDTH HEIGHT WIDGET[:U]...: a script pressing each widget in turn (U: where
# along it, 0 to 1), then a render of it with the menu shown.
page() {
    name=$1 w=$2 h=$3
    shift 3
    f=0
    : >"$work/$name.txt"
    for widget in "$@"; do
        case $widget in
        *:*) aim="${widget%%:*} ${widget#*:} 0.5" ;;
        *) aim=$widget ;;
        esac
        printf '%d aim %s\n%d button trigger down\n%d button trigger up\n' \
            "$f" "$aim" $((f + 1)) $((f + 2)) >>"$work/$name.txt"
        f=$((f + 3))
    done
    "$anvil" render configs/katrina.cfg --menu --input "$work/$name.txt" --quiet \
        --set render.width="$w" --set render.height="$h" -o "$out/menu-$name.png"
}

page time 480 360 time.forward
page fields 480 360 tab.fields fields.rain
page layers 640 400 tab.layers layers.add layers.add layers.2.field layers.2.mode \
    layers.opacity:0.3
page slices 640 400 tab.slices slices.add slices.1.field slices.position:0.3 \
    slices.contours:0.35
page species 480 360 tab.transfer transfer.species transfer.pick.cloud \
    transfer.tint.blue:0.7 transfer.tint.green:0.85
page transfer 480 360 tab.transfer transfer.function transfer.mode
page light 480 360 tab.light light.elevation:0.3
page quality 480 360 tab.quality

# The panel in two walls of the CAVE, left eye, from the Time page's script.
printf '0 aim time.forward\n1 button trigger down\n2 button trigger up\n' >"$work/cave.txt"
"$anvil" render configs/katrina.cfg --display displays/cave4.cfg --menu --input "$work/cave.txt" \
    --quiet --set render.width=240 --set render.height=240 -o "$work/cave/"
cp "$work/cave/front-left.png" "$out/menu-cave-front.png"
cp "$work/cave/floor-left.png" "$out/menu-cave-floor.png"
