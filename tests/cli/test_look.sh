#!/bin/bash
# Look blocks (docs/analysis.md): a menu session scripted through --input changes the look (a
# species' tint and scale, the time step; then a transfer function, which shows at once) and
# presses Save view; the bookmark it writes renders the same image, bit for bit, in a batch
# render.  A look block of a wrong type is refused with file:line.  Arguments: the anvil
# binary, the source folder, the data folder.
. "$(dirname "$0")/lib.sh"
katrina="$data/wrf/katrina_2005_mercator_wsm3.nc"
if [ ! -r "$katrina" ]; then echo "no Katrina sample: skipping"; exit 77; fi
require_gl
# Uniform levels: the pictures below are compared bit for bit, and on the model's own levels a
# session and a batch render of the same view differ in the last bits at the low cloud bases
# that meet the terrain (the opaque pass's distance along a pixel's ray; docs/data.md).
small="--set render.width=160 --set render.height=120 --set lightmap.resolution=[32,32,32]
       --set data.vertical=uniform"
cfg="$src/configs/katrina.cfg"

# The cloud tinted and thickened, one step on, saved from the Time page.
cat >"$tmp/species.txt" <<'SCRIPT'
0 key menu
0 aim tab.transfer
1 button trigger down
2 button trigger up
3 aim transfer.pick.cloud
4 button trigger down
5 button trigger up
6 aim transfer.tint.blue 0.4 0.5
7 button trigger down
8 button trigger up
9 aim transfer.scale 0.5 0.5
10 button trigger down
11 aim transfer.scale 0.6 0.5
12 button trigger up
13 key forward
14 aim tab.time
15 button trigger down
16 button trigger up
17 aim time.save
18 button trigger down
19 button trigger up
20 key menu
SCRIPT
# A transfer function of the condensate: a point added, nothing else ticked.
cat >"$tmp/transfer.txt" <<'SCRIPT'
0 key menu
0 aim tab.transfer
1 button trigger down
2 button trigger up
3 aim transfer.function
4 button trigger down
5 button trigger up
6 aim transfer.field
7 button trigger down
8 button trigger up
9 aim transfer.canvas 0.7 0.8
10 button trigger down
11 button trigger up
12 aim tab.time
13 button trigger down
14 button trigger up
15 aim time.save
16 button trigger down
17 button trigger up
18 key menu
SCRIPT
# The Layers page: a temperature layer added, then a second turned to wind speed tinting the
# clouds at a quarter of its strength (the slider), saved.
cat >"$tmp/layers.txt" <<'SCRIPT'
0 key menu
0 aim tab.layers
1 button trigger down
2 button trigger up
3 aim layers.add
4 button trigger down
5 button trigger up
6 aim layers.add
7 button trigger down
8 button trigger up
9 aim layers.2.field
10 button trigger down
11 button trigger up
12 aim layers.2.mode
13 button trigger down
14 button trigger up
15 aim layers.opacity 0.5 0.5
16 button trigger down
17 aim layers.opacity 0.125 0.5
18 button trigger up
19 aim tab.time
20 button trigger down
21 button trigger up
22 aim time.save
23 button trigger down
24 button trigger up
25 key menu
SCRIPT
# The Slices page: a temperature slice added, moved down, tilted, with contours, saved (each
# drag starts inside its slider: a slider's very edge may fall a pixel outside it).
cat >"$tmp/slices.txt" <<'SCRIPT'
0 key menu
0 aim tab.slices
1 button trigger down
2 button trigger up
3 aim slices.add
4 button trigger down
5 button trigger up
6 aim slices.position 0.5 0.5
7 button trigger down
8 aim slices.position 0.2 0.5
9 button trigger up
10 aim slices.tilt 0.5 0.5
11 button trigger down
12 aim slices.tilt 0.7 0.5
13 button trigger up
14 aim slices.contours 0.05 0.5
15 button trigger down
16 aim slices.contours 0.5 0.5
17 button trigger up
18 aim tab.time
19 button trigger down
20 button trigger up
21 aim time.save
22 button trigger down
23 button trigger up
24 key menu
SCRIPT
printf '0 key menu\n1 key menu\n' >"$tmp/plain.txt"
(cd "$tmp" && "$anvil" render --quiet "$cfg" $small --input plain.txt -o plain.pfm)
n=0
for look in species transfer layers slices; do
    n=$((n + 1))
    (cd "$tmp" && "$anvil" render --quiet "$cfg" $small --input "$look.txt" \
        -o "$look-session.pfm" >"$look.out")
    check "$look: the scripted session exits 0" test $? -eq 0
    check "$look: Save view wrote bookmark-$n.cfg" test -f "$tmp/bookmark-$n.cfg"
    check "$look: the bookmark holds a look block" grep -q "^look = {" "$tmp/bookmark-$n.cfg"
    (cd "$tmp" && "$anvil" render --quiet "bookmark-$n.cfg" $small -o "$look-batch.pfm")
    check "$look: the bookmark renders" test -s "$tmp/$look-batch.pfm"
    check "$look: the same image as the session that saved it" \
        cmp -s "$tmp/$look-session.pfm" "$tmp/$look-batch.pfm"
    check "$look: not the plain picture" bash -c "! cmp -s '$tmp/plain.pfm' '$tmp/$look-batch.pfm'"
done
check "species: the tint and the step saved" bash -c \
    "grep -q 'data = { step = 1; };' '$tmp/bookmark-1.cfg' && grep -q 'cloud = { enabled = true; scale = 2.4' '$tmp/bookmark-1.cfg'"
check "transfer: the function in place, as layer 0, shown" bash -c \
    "grep -q 'layers = (' '$tmp/bookmark-2.cfg' && grep -q 'field = \"condensate\";' '$tmp/bookmark-2.cfg' && grep -q 'mode = \"emit\";' '$tmp/bookmark-2.cfg' && grep -q 'enabled = true;' '$tmp/bookmark-2.cfg'"
check "layers: two layers saved, the second wind speed tinting" bash -c \
    "grep -q 'field = \"temperature\";' '$tmp/bookmark-3.cfg' && grep -q 'field = \"wind\";' '$tmp/bookmark-3.cfg' && grep -q 'mode = \"tint\";' '$tmp/bookmark-3.cfg' && grep -q 'opacity = 2\.[0-9]*e-01;' '$tmp/bookmark-3.cfg'"
check "slices: a tilted slice with contours saved" bash -c \
    "grep -q 'slices = (' '$tmp/bookmark-4.cfg' && grep -q 'axis = \"plane\";' '$tmp/bookmark-4.cfg' && ! grep -q 'normal = \[0.0*e+00, 0.0*e+00, 1.0*e+00\]' '$tmp/bookmark-4.cfg' && ! grep -q 'contour_every = 0.0*e+00' '$tmp/bookmark-4.cfg'"
check "Save view printed the camera block too" grep -q "camera = {" "$tmp/species.out"

# The same transfer function named by its file renders alike (the group moved to tf.cfg).
sed -n '/^            transfer = {/,/^            };/p' "$tmp/bookmark-2.cfg" | sed 's/^            //' \
    >"$tmp/tf.cfg"
sed '/^            transfer = {/,/^            };/c\            transfer = "tf.cfg";' \
    "$tmp/bookmark-2.cfg" >"$tmp/byfile.cfg"
check "the bookmark now names tf.cfg" grep -q 'transfer = "tf.cfg";' "$tmp/byfile.cfg"
(cd "$tmp" && "$anvil" render --quiet byfile.cfg $small -o byfile.pfm)
check "look.transfer from a file renders as in place" cmp -s "$tmp/byfile.pfm" "$tmp/transfer-batch.pfm"

# An older file's look.transfer is read as layer 0: the same picture as the layer.
sed -n '/^            transfer = {/,/^            };/p' "$tmp/bookmark-2.cfg" | sed 's/^        //' \
    >"$tmp/old-tf.txt"
sed '/^    layers = (/,/^    );/d' "$tmp/bookmark-2.cfg" | sed '/^look = {/r '"$tmp/old-tf.txt" \
    >"$tmp/old.cfg"
check "an older file's look.transfer" grep -q '^    transfer = {' "$tmp/old.cfg"
(cd "$tmp" && "$anvil" render --quiet old.cfg $small -o old.pfm)
check "  renders as the layer it becomes" cmp -s "$tmp/old.pfm" "$tmp/transfer-batch.pfm"

# Two layers, one tinting the clouds by temperature: a different picture, and its bookmark
# made by hand renders without a message.
sed 's/^    layers = (/    layers = ( { field = "temperature"; mode = "tint"; opacity = 0.8; },/' \
    "$tmp/bookmark-2.cfg" >"$tmp/two.cfg"
(cd "$tmp" && "$anvil" render --quiet two.cfg $small -o two.pfm 2>"$tmp/err")
check "two layers render" test -s "$tmp/two.pfm"
check "  the tint changes the picture" bash -c "! cmp -s '$tmp/two.pfm' '$tmp/transfer-batch.pfm'"

# A scene with a slice (temperature at 3 km, contours every 5 K), a layer added in the menu,
# saved: the bookmark holds the layer and the slice and renders the session's picture.
printf '@include "%s"\nlook = { slices = ( { field = "temperature"; axis = "z"; position = 3.0; opacity = 0.8; contour_every = 5.0; } ); };\n' \
    "$cfg" >"$tmp/slice.cfg"
(cd "$tmp" && rm -f bookmark-*.cfg && "$anvil" render --quiet slice.cfg $small --input transfer.txt \
    -o slice-session.pfm >slice.out)
check "slice: the scripted session exits 0" test $? -eq 0
check "slice: the bookmark holds the layer and the slice" bash -c \
    "grep -q 'field = \"condensate\";' '$tmp/bookmark-1.cfg' && grep -q 'slices = (' '$tmp/bookmark-1.cfg' && grep -q 'axis = \"plane\";' '$tmp/bookmark-1.cfg' && grep -q 'field = \"temperature\";' '$tmp/bookmark-1.cfg'"
(cd "$tmp" && "$anvil" render --quiet bookmark-1.cfg $small -o slice-batch.pfm)
check "slice: the same image as the session that saved it" \
    cmp -s "$tmp/slice-session.pfm" "$tmp/slice-batch.pfm"
check "slice: the slice is in the picture" \
    bash -c "! cmp -s '$tmp/slice-batch.pfm' '$tmp/transfer-batch.pfm'"
printf '@include "%s"\nlook = { slices = ( { axis = "plane"; normal = [0.0, 0.0, 0.0]; } ); };\n' \
    "$cfg" >"$tmp/flat.cfg"
expect_exit 1 "a slice without a normal" "$anvil" render "$tmp/flat.cfg" -o "$tmp/x.png"
check "  says so" stderr_has 'flat.cfg: look.slices.\[0\].normal: must not be \[0, 0, 0\]'

# A mouse drag outside the menu while the Slices page shows moves the slice (up: higher) and
# tilts it (right); no drag leaves it half way up the box.
drag_script() {
    printf '0 key menu\n0 aim tab.slices\n1 button trigger down\n2 button trigger up\n'
    printf '3 aim slices.add\n4 button trigger down\n5 button trigger up\n'
    printf '6 pose world 0 0 0 0 0 1\n7 button trigger down\n8 drag %s\n9 drag %s\n' "$1" "$2"
    printf '10 button trigger up\n11 aim tab.time\n12 button trigger down\n13 button trigger up\n'
    printf '14 aim time.save\n15 button trigger down\n16 button trigger up\n17 key menu\n'
}
slice_z() { sed -n 's/^ *point = \[[^,]*, [^,]*, \(.*\)\];/\1/p' "$1"; }
mkdir -p "$tmp/drag" "$tmp/still"
drag_script "0 -100" "50 0" >"$tmp/drag/in.txt"
drag_script "0 0" "0 0" >"$tmp/still/in.txt"
for d in drag still; do
    (cd "$tmp/$d" && "$anvil" render --quiet "$cfg" $small --input in.txt -o session.pfm \
        >/dev/null && "$anvil" render --quiet bookmark-1.cfg $small -o batch.pfm)
done
check "drag: the bookmark renders the session's picture" \
    cmp -s "$tmp/drag/session.pfm" "$tmp/drag/batch.pfm"
check "drag: the slice went up" awk -v a="$(slice_z "$tmp/drag/bookmark-1.cfg")" \
    -v b="$(slice_z "$tmp/still/bookmark-1.cfg")" 'BEGIN { exit !(a > b + 1.0) }'
check "drag: and tilted" bash -c "! grep -q 'normal = \[0.0*e+00, 0.0*e+00, 1.0*e+00\]' '$tmp/drag/bookmark-1.cfg'"
check "no drag: level" grep -q 'normal = \[0.0*e+00, 0.0*e+00, 1.0*e+00\]' "$tmp/still/bookmark-1.cfg"

# In the CAVE: the trigger held with the wand off the menu while the Slices page shows moves
# the slice along its normal by the wand's displacement along it: 3 mm up in the room at
# cave4's navigation scale (3.75e-6) is 800 m up in the world; the wand held still leaves it.
wand_script() {
    printf '0 aim tab.slices\n1 button trigger down\n2 button trigger up\n'
    printf '3 aim slices.add\n4 button trigger down\n5 button trigger up\n'
    printf '6 pose tracker 0 1.2 0 0 0 1\n7 button trigger down\n8 pose tracker 0 %s 0 0 0 1\n' "$1"
    printf '9 button trigger up\n10 aim tab.time\n11 button trigger down\n12 button trigger up\n'
    printf '13 aim time.save\n14 button trigger down\n15 button trigger up\n'
}
mkdir -p "$tmp/wand" "$tmp/wand-still"
wand_script 1.203 >"$tmp/wand/in.txt"
wand_script 1.2 >"$tmp/wand-still/in.txt"
for d in wand wand-still; do
    (cd "$tmp/$d" && "$anvil" render --quiet "$cfg" $small --display "$src/displays/cave4.cfg" \
        --menu --input in.txt -o out/ >/dev/null)
    check "$d: the CAVE session exits 0" test $? -eq 0
done
wand_z() { sed -n 's/^# *point = \[[^,]*, [^,]*, \(.*\)\];/\1/p' "$1"; }
check "wand: the slice went 0.8 km up" awk -v a="$(wand_z "$tmp/wand/bookmark-1.cfg")" \
    -v b="$(wand_z "$tmp/wand-still/bookmark-1.cfg")" 'BEGIN { d = a - b; exit !(d > 0.79 && d < 0.81) }'
# Rolled 20 degrees clockwise about its ray (the up (0, 1, 0) turned right-handed about the
# ray (0, 0, 1)) while held: the slice tilts 20 degrees, its normal's z cos 20 = 0.9397.
mkdir -p "$tmp/roll"
sed -e 's/^6 pose tracker 0 1.2 0 0 0 1$/6 pose tracker 0 1.2 0 0 0 1 0 1 0/' \
    -e 's/^8 pose tracker .*$/8 pose tracker 0 1.2 0 0 0 1 -0.342020143 0.939692621 0/' \
    "$tmp/wand-still/in.txt" >"$tmp/roll/in.txt"
(cd "$tmp/roll" && "$anvil" render --quiet "$cfg" $small --display "$src/displays/cave4.cfg" \
    --menu --input in.txt -o out/ >/dev/null)
check "roll: the CAVE session exits 0" test $? -eq 0
wand_nz() { sed -n 's/^# *normal = \[[^,]*, [^,]*, \(.*\)\];/\1/p' "$1"; }
check "roll: the slice tilted 20 degrees" awk -v n="$(wand_nz "$tmp/roll/bookmark-1.cfg")" \
    'BEGIN { exit !(n > 0.9392 && n < 0.9402) }'
check "roll: and did not move" awk -v a="$(wand_z "$tmp/roll/bookmark-1.cfg")" \
    -v b="$(wand_z "$tmp/wand-still/bookmark-1.cfg")" 'BEGIN { d = a - b; exit !(d > -0.01 && d < 0.01) }'

# Wrong types: one message with file:line, exit 1.
printf 'look = {\n  layers = (\n    { field = "temperature";\n      mode = "glow"; }\n  );\n};\n' \
    >"$tmp/glow.cfg"
expect_exit 1 "a layer mode that is not one" "$anvil" render "$tmp/glow.cfg" -o "$tmp/x.png"
check "  names file:line and the setting" stderr_has 'glow.cfg:4: look.layers.\[0\].mode: expected'
printf 'look = { layers = ( {}, {}, {}, {}, {} ); };\n' >"$tmp/five-layers.cfg"
expect_exit 1 "five layers" "$anvil" render "$tmp/five-layers.cfg" -o "$tmp/x.png"
check "  says at most 4" stderr_has 'five-layers.cfg:1: look.layers: expected 0 to 4 layers, got 5'
printf 'look = { transfer = "tf.cfg"; layers = ( {} ); };\n' >"$tmp/both.cfg"
expect_exit 1 "look.transfer and look.layers" "$anvil" render "$tmp/both.cfg" -o "$tmp/x.png"
check "  not both" stderr_has 'both.cfg: look.transfer: give the layers'"'"' functions in look.layers'

printf 'look = {\n    species = {\n        cloud = { tint = "red"; };\n    };\n};\n' >"$tmp/tint.cfg"
expect_exit 1 "a tint that is a word" "$anvil" render "$tmp/tint.cfg" -o "$tmp/x.png"
check "  names file:line and the setting" \
    stderr_has 'tint.cfg:3: look.species.cloud.tint: expected an array of 3 numbers in \[0, 1\], got "red"'
printf 'look = {\n  transfer = 5;\n};\n' >"$tmp/five.cfg"
expect_exit 1 "a transfer function that is a number" "$anvil" render "$tmp/five.cfg" -o "$tmp/x.png"
check "  names file:line" stderr_has "five.cfg:2: look.transfer: expected a transfer function"
printf 'look = {\n  transfer = {\n    field = "qvapor";\n    range = [0.0, 0.01];\n    density = 0.002;\n    red = ([0.0, 2.0]);\n  };\n};\n' \
    >"$tmp/point.cfg"
expect_exit 1 "an inline function with a bad point" "$anvil" render "$tmp/point.cfg" -o "$tmp/x.png"
check "  names the scene file's line" stderr_has "point.cfg:6: look.transfer.red\[0\]: expected x and value in \[0, 1\]"
printf 'look = { transfer = "absent.cfg"; };\n' >"$tmp/missing.cfg"
expect_exit 1 "a function file that is not there" "$anvil" render "$tmp/missing.cfg" -o "$tmp/x.png"
check "  names the scene file and the missing one" \
    stderr_has 'missing.cfg:1: look.transfer: cannot read the transfer function'
check "  once" test "$(grep -c error "$tmp/err")" -eq 1
finish
