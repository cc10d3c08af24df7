#!/bin/bash
# Classic transfer-function mode over the four scalar fields (docs/menu.md): the field button
# switches QVAPOR -> condensate -> temperature -> wind speed, each switch changes the image;
# Katrina (U, V, W, T in the file) renders temperature and wind speed with finite pixels; a
# file without U and V shows wind speed as zero with a warning, not a failure.
# Arguments: the anvil binary, the source folder, the shared data folder.
. "$(dirname "$0")/lib.sh"
json() { # json FILE KEY: the number after "KEY":
    sed -n "s/^ *\"$2\": \([-0-9.]*\),*$/\1/p" "$1"
}
small="--set render.width=160 --set render.height=120 --set lightmap.resolution=[32,32,32]"
require_gl

# A script that turns transfer mode on and presses the field button N times.
script() { # script N FILE
    {
        printf '0 key menu\n0 aim tab.transfer\n1 button trigger down\n2 button trigger up\n'
        printf '3 aim transfer.function\n4 button trigger down\n5 button trigger up\n'
        printf '6 aim transfer.mode\n7 button trigger down\n8 button trigger up\n'
        local f=10
        for ((i = 0; i < $1; i++)); do
            printf '%d aim transfer.field\n%d button trigger down\n%d button trigger up\n' \
                $f $((f + 1)) $((f + 2))
            f=$((f + 4))
        done
        printf '40 key menu\n'
    } >"$2"
}
names=(qvapor condensate temperature wind)

# --- A synthetic WRF file (anvil synth writes U, V, W and T).
"$anvil" synth -o "$tmp/storm.nc" --steps 1 --size 24x24x12 2>/dev/null
check "synth exits 0" test $? -eq 0
check "synth writes U, V, W" bash -c "ncdump -h '$tmp/storm.nc' | grep -q 'float U(Time, bottom_top, south_north, west_east_stag)' && ncdump -h '$tmp/storm.nc' | grep -q 'float W(Time, bottom_top_stag'"
printf 'scene = { kind = "data"; };\ndata = { format = "wrf"; files = ["storm.nc"]; };\n' \
    >"$tmp/storm.cfg"
for n in 0 1 2 3; do
    script $n "$tmp/f$n.txt"
    "$anvil" render --quiet "$tmp/storm.cfg" $small --input "$tmp/f$n.txt" \
        -o "$tmp/${names[$n]}.png" --stats "$tmp/${names[$n]}.json"
    check "${names[$n]} renders (exit 0)" test $? -eq 0
    check "${names[$n]}: no non-finite pixels" test "$(json "$tmp/${names[$n]}.json" nonfinite_pixels)" = 0
done
for n in 1 2 3; do
    a=${names[$((n - 1))]} b=${names[$n]}
    check "switching the field $a -> $b changes the image" \
        bash -c "! cmp -s '$tmp/$a.png' '$tmp/$b.png'"
done

# --- Katrina: temperature and wind speed from the real file, as floating-point images.
if [ -n "$data" ] && [ -f "$data/wrf/katrina_2005_mercator_wsm3.nc" ]; then
    sed "s|\.\./\.\./shared/data|$data|" "$src/configs/katrina.cfg" >"$tmp/katrina.cfg"
    for n in 2 3; do
        "$anvil" render --quiet "$tmp/katrina.cfg" $small --input "$tmp/f$n.txt" \
            -o "$tmp/k-${names[$n]}.pfm" --stats "$tmp/k-${names[$n]}.json" 2>"$tmp/err"
        check "Katrina ${names[$n]} renders (exit 0)" test $? -eq 0
        check "Katrina ${names[$n]}: no non-finite pixels" \
            test "$(json "$tmp/k-${names[$n]}.json" nonfinite_pixels)" = 0
        check "Katrina ${names[$n]}: no warnings" bash -c "! grep -q 'unavailable' '$tmp/err'"
    done
    check "Katrina: temperature and wind speed differ" \
        bash -c "! cmp -s '$tmp/k-temperature.pfm' '$tmp/k-wind.pfm'"
else
    echo "no Katrina sample: skipping its checks"
fi

# --- The built-in storm has no wind: wind speed is unavailable, with a message, not a crash.
"$anvil" render $small --set scene.size=[32,32,16] --input "$tmp/f3.txt" -o "$tmp/nowind.png" \
    2>"$tmp/err"
check "wind speed without U and V exits 0" test $? -eq 0
check "wind speed without U and V says so" grep -q "wind speed is unavailable" "$tmp/err"
finish
