#!/bin/bash
# CM1, CF and Isabel from the command line: synthetic files through `info` (grid, times,
# variables) and `render` (non-blank, the same picture as the WRF synth file of the same
# storm); stretched levels kept (info, render); wrong units and non-monotone heights are one
# message and exit 1; a folder of Isabel bricks through `info` and `render`, placed on the
# contest's lat/lon box with no map block.
# Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.  Exits 77 when no GL context exists.
. "$(dirname "$0")/lib.sh"
small="--set render.width=96 --set render.height=72 --set lightmap.resolution=[32,32,32]"
size="--size 24x20x16 --extent 60x50x16"

# Mean of a PFM and the largest difference between two, relative to the first's largest value.
pfm() {
    python3 - "$@" <<'EOF'
import struct, sys
def read(p):
    b = open(p, 'rb').read()
    head, rest = b.split(b'\n', 3)[:3], b.split(b'\n', 3)[3]
    w, h = map(int, head[1].split())
    e = '<' if float(head[2]) < 0 else '>'
    return struct.unpack(e + '%df' % (w * h * 3), rest[:w * h * 12])
a = read(sys.argv[1])
if len(sys.argv) == 2:
    print('%.6g' % (sum(a) / len(a)))
else:
    b = read(sys.argv[2])
    print('%.6g' % (max(abs(x - y) for x, y in zip(a, b)) / max(a)))
EOF
}

expect_exit 0 "synth --format cm1" "$anvil" synth --format cm1 $size --steps 2 -o "$tmp/c.nc"
expect_exit 0 "synth --format cf" "$anvil" synth --format cf $size --steps 2 \
    --start 2005-08-28_12:00:00 -o "$tmp/f.nc"
expect_exit 0 "synth (WRF)" "$anvil" synth $size --steps 2 -o "$tmp/w.nc"
expect_exit 1 "synth --format grib" "$anvil" synth --format grib -o "$tmp/x.nc"

expect_exit 0 "info on CM1 output" "$anvil" info "$tmp/c.nc"
check "CM1 output" stdout_has ": CM1 output"
check "grid 24 x 20 x 16" stdout_has "24 x 20 columns x 16 levels (xh x yh x zh), dx 2500 m, dy 2500 m"
check "levels" stdout_has "levels      0 to 16000 m (even, km)"
check "variables" stdout_has "cloud=qc rain=qr ice=qi snow=qs graupel=qg vapour=qv theta=th pressure=prs u=u v=v w=w"
check "2 steps" stdout_has "time steps  2"
check "second step at 600 s" stdout_has "1 t = 600 s"
check "theta range" stdout_has "    th  "

expect_exit 0 "info on CF" "$anvil" info "$tmp/f.nc"
check "CF" stdout_has ": CF NetCDF on height levels"
check "dates" stdout_has "1 t = 600 s 2005-08-28_12:10:00"
check "CF variables" stdout_has "temperature=ta pressure=pa u=ua v=va w=wa"

# Two CF files given late first: ordered by time; two CM1 files of the same times refused.
"$anvil" synth --format cf $size --steps 1 --start 2005-08-28_11:50:00 -o "$tmp/f0.nc" 2>/dev/null
expect_exit 0 "info on two CF files" "$anvil" info "$tmp/f.nc" "$tmp/f0.nc"
check "3 steps" stdout_has "time steps  3"
check "the earlier file first" stdout_has "0 t = 0 s 2005-08-28_11:50:00 (.*f0.nc)"
"$anvil" synth --format cm1 $size --steps 1 -o "$tmp/c0.nc" 2>/dev/null
expect_exit 1 "two CM1 files of the same time" "$anvil" info "$tmp/c.nc" "$tmp/c0.nc"
check "both named" stderr_has "c0.nc and .*c.nc both hold time 0 s\\|c.nc and .*c0.nc both hold time 0 s"

# The WRF file's terrain mesh and coastlines (it has XLAT/XLONG) are not in the others: off.
flat="--set map.terrain=false --set map.coastlines=false"
for f in w c f; do
    fmt=$(case $f in w) echo wrf ;; c) echo cm1 ;; f) echo cf ;; esac)
    expect_exit 0 "render data.format = $fmt" "$anvil" render --set scene.kind=data \
        --set data.format=$fmt --set "data.files=[\"$tmp/$f.nc\"]" $small $flat -o "$tmp/$f.pfm"
done
off=""
for s in cloud rain ice snow graupel; do off="$off --set species.$s.enabled=false"; done
expect_exit 0 "render CM1 with every species off" "$anvil" render --set scene.kind=data \
    --set data.format=cm1 --set "data.files=[\"$tmp/c.nc\"]" $small $flat $off -o "$tmp/clear.pfm"
if [ -f "$tmp/w.pfm" ] && [ -f "$tmp/c.pfm" ] && [ -f "$tmp/f.pfm" ] && [ -f "$tmp/clear.pfm" ]; then
    storm=$(pfm "$tmp/clear.pfm" "$tmp/c.pfm")
    echo "the CM1 storm against a clear sky: $storm (of the largest value)"
    check "the CM1 picture is not blank" python3 -c "import sys; sys.exit(0 if $storm > 0.05 else 1)"
    dc=$(pfm "$tmp/w.pfm" "$tmp/c.pfm")
    df=$(pfm "$tmp/w.pfm" "$tmp/f.pfm")
    echo "largest difference to the WRF picture: CM1 $dc, CF $df (of its largest value)"
    check "CM1 renders the WRF storm" python3 -c "import sys; sys.exit(0 if $dc < 1e-3 else 1)"
    check "CF renders the WRF storm" python3 -c "import sys; sys.exit(0 if $df < 1e-3 else 1)"
else
    require_gl
    echo "FAIL: no pictures"
    fail=1
fi

# Stretched levels (each 1.15 times as thick as the one below, CM1 zh/zf and CF z/z_bnds):
# info names the own levels; `render FILE` keeps them (data.vertical = "native", the
# default), and its picture differs from the even levels' ("uniform").
for fmt in cm1 cf; do
    expect_exit 0 "synth --format $fmt --stretch 1.15" "$anvil" synth --format $fmt $size \
        --stretch 1.15 -o "$tmp/s$fmt.nc"
    expect_exit 0 "info on stretched $fmt" "$anvil" info "$tmp/s$fmt.nc"
    check "$fmt: stretched" stdout_has "levels      0 to 16000 m (stretched, "
    check "$fmt: own levels said" stdout_has "own levels  16, centres 144 to 14[0-9]* m, the thinnest 298 m, kept as they are"
    expect_exit 0 "render stretched $fmt" "$anvil" render "$tmp/s$fmt.nc" $small $flat \
        -o "$tmp/s$fmt.pfm"
    expect_exit 0 "render stretched $fmt, uniform" "$anvil" render "$tmp/s$fmt.nc" $small $flat \
        --set data.vertical=uniform -o "$tmp/u$fmt.pfm"
    expect_exit 0 "render stretched $fmt to PNG" "$anvil" render "$tmp/s$fmt.nc" $small $flat \
        -o "$tmp/s$fmt.png"
    check "$fmt: a PNG" test -s "$tmp/s$fmt.png"
    if [ -f "$tmp/s$fmt.pfm" ] && [ -f "$tmp/u$fmt.pfm" ] && [ -f "$tmp/clear.pfm" ]; then
        storm=$(pfm "$tmp/clear.pfm" "$tmp/s$fmt.pfm")
        du=$(pfm "$tmp/s$fmt.pfm" "$tmp/u$fmt.pfm")
        echo "stretched $fmt: against a clear sky $storm, own levels against even ones $du"
        check "$fmt: the stretched picture is not blank" python3 -c "import sys; sys.exit(0 if $storm > 0.05 else 1)"
        check "$fmt: own levels are not the even ones" python3 -c "import sys; sys.exit(0 if $du > 1e-3 else 1)"
    fi
done
expect_exit 0 "synth --format cm1 --stretch 1 (even)" "$anvil" synth --format cm1 $size \
    --stretch 1 -o "$tmp/e1.nc"
expect_exit 0 "info on it" "$anvil" info "$tmp/e1.nc"
check "even: no own levels" sh -c "! grep -q 'own levels' '$tmp/out'"
expect_exit 2 "synth --stretch for WRF" "$anvil" synth $size --stretch 1.1 -o "$tmp/x.nc"
expect_exit 1 "synth --stretch 3" "$anvil" synth --format cm1 $size --stretch 3 -o "$tmp/x.nc"

# The probe's wind from CM1's staggered u, v, w and CF's eastward_wind, northward_wind and
# upward_air_velocity: the same storm, so the same speed and direction.
placed="--set map.use_origin=true --set map.origin=[30.0,-75.0]"
for f in c f; do
    fmt=$(case $f in c) echo cm1 ;; f) echo cf ;; esac)
    expect_exit 0 "probe $fmt" "$anvil" probe --set scene.kind=data --set data.format=$fmt \
        --set "data.files=[\"$tmp/$f.nc\"]" $placed --at 30.05,-74.95,3000 --quiet
    check "$fmt: the wind's speed and direction" stdout_has "wind           [0-9.]* m/s from [0-9]* deg$"
    check "$fmt: the vertical wind" stdout_has "vertical wind  [-+][0-9.]* m/s"
    grep "wind" "$tmp/out" >"$tmp/wind.$fmt"
done
check "CM1 and CF: the same wind" cmp "$tmp/wind.cm1" "$tmp/wind.cf"
# On stretched levels too (the probe samples through the levels' height mapping).
for fmt in cm1 cf; do
    expect_exit 0 "probe stretched $fmt" "$anvil" probe --set scene.kind=data \
        --set data.format=$fmt --set "data.files=[\"$tmp/s$fmt.nc\"]" $placed \
        --at 30.05,-74.95,3000 --quiet
    check "$fmt stretched: the wind" stdout_has "wind           [0-9.]* m/s from [0-9]* deg$"
    grep "wind" "$tmp/out" >"$tmp/swind.$fmt"
done
check "CM1 and CF stretched: the same wind" cmp "$tmp/swind.cm1" "$tmp/swind.cf"

# Bad input: a unit that is not one, heights that turn back.
cdl() { # UNITS_OF_RAIN HEIGHTS
    cat <<EOF
netcdf bad {
dimensions: x = 3 ; y = 2 ; z = 3 ; h2 = 1 ;
variables:
  double x(x) ; x:units = "km" ; x:axis = "X" ;
  double y(y) ; y:units = "km" ; y:axis = "Y" ;
  double h2(h2) ; h2:units = "m" ; h2:axis = "Z" ;
  double z(z) ; z:units = "m" ; z:positive = "up" ;
  float t2m(y, x) ; t2m:standard_name = "air_temperature" ; t2m:units = "K" ;
  float qr(z, y, x) ; qr:standard_name = "mass_fraction_of_rain_in_air" ; qr:units = "$1" ;
data:
  x = 0, 1, 2 ; y = 0, 1 ; z = $2 ; h2 = 2 ; t2m = 300, 300, 300, 300, 300, 300 ;
  qr = 0, 0, 1e-3, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0 ;
}
EOF
}
if command -v ncgen >/dev/null; then
    cdl "g kg-1" "100, 300, 500" | ncgen -o "$tmp/good.nc"
    cdl "furlongs" "100, 300, 500" | ncgen -o "$tmp/units.nc"
    cdl "kg kg-1" "100, 300, 200" | ncgen -o "$tmp/mono.nc"
    expect_exit 0 "a small CF file" "$anvil" info "$tmp/good.nc"
    check "missing species named" stdout_has "absent (read as zero): cloud ice snow graupel"
    check "the levels, not the 2 m height; t2m passed over" stdout_has "variables   rain=qr$"
    check "3 levels from 0 to 600 m" stdout_has "levels      0 to 600 m (even, m)"
    check "g/kg converted" stdout_has "qr  *0 \.\. 1e-06 "
    # Uneven levels, the lowest on the ground face of its bounds: not a stretched grid's
    # (whose centres lie inside the box), so the even levels, and info says why.
    printf 'netcdf face {\ndimensions: x = 2 ; y = 2 ; z = 3 ; nv = 2 ;\nvariables:\n  double x(x) ; x:units = "km" ; x:axis = "X" ;\n  double y(y) ; y:units = "km" ; y:axis = "Y" ;\n  double z(z) ; z:units = "m" ; z:axis = "Z" ; z:bounds = "zb" ;\n  double zb(z, nv) ;\n  float qc(z, y, x) ; qc:standard_name = "mass_fraction_of_cloud_liquid_water_in_air" ;\ndata:\n  x = 0, 1 ; y = 0, 1 ; z = 0, 100, 300 ; zb = 0, 50, 50, 200, 200, 400 ;\n  qc = 0, 0, 0, 0, 1e-4, 1e-4, 1e-4, 1e-4, 0, 0, 0, 0 ;\n}\n' | ncgen -o "$tmp/face.nc"
    expect_exit 0 "uneven levels, one on a face" "$anvil" info "$tmp/face.nc"
    check "not kept, said" stdout_has "own levels  not kept (more than 256, or a level on the lowest or highest face): the even levels"
    expect_exit 1 "a wrong unit" "$anvil" info "$tmp/units.nc"
    check "variable and unit named" stderr_has "units.nc: variable qr: units \"furlongs\" are not a unit of rain"
    expect_exit 1 "a wrong unit, render" "$anvil" render --set scene.kind=data \
        --set data.format=cf --set "data.files=[\"$tmp/units.nc\"]" $small -o "$tmp/u.png"
    check "render names it too" stderr_has "furlongs"
    expect_exit 1 "non-monotone heights" "$anvil" info "$tmp/mono.nc"
    check "heights not monotone" stderr_has "mono.nc: vertical coordinate z: heights not monotone"
    expect_exit 1 "non-monotone heights, render" "$anvil" render --set scene.kind=data \
        --set data.format=cf --set "data.files=[\"$tmp/mono.nc\"]" $small -o "$tmp/m.png"
    expect_exit 1 "a CF file read as CM1" "$anvil" render --set scene.kind=data \
        --set data.format=cm1 --set "data.files=[\"$tmp/good.nc\"]" $small -o "$tmp/g.png"
    check "not CM1 output" stderr_has "not CM1 output: no coordinate xh"
fi

# Isabel: every brick of two steps, 8 x 6 x 4 points.
mkdir -p "$tmp/isabel"
python3 - "$tmp/isabel" <<'EOF'
import struct, sys
d = sys.argv[1]
n = 8 * 6 * 4
for step in (1, 2):
    for f in ["QCLOUD", "QRAIN", "QICE", "QSNOW", "QGRAUP", "QVAPOR", "CLOUD", "PRECIP", "P",
              "TC", "U", "V", "W"]:
        if f == "TC":
            v = [20.0 - 5.0 * (i // 48) for i in range(n)]
        elif f in ("U", "V", "W"):
            v = [{"U": 3.0, "V": -4.0, "W": 0.5}[f]] * n
        elif f == "P":
            v = [-300.0 + i for i in range(n)]
        else:
            v = [1e-3 * step if (i % 48) in (20, 21, 27, 28) and i // 48 in (1, 2) else 0.0
                 for i in range(n)]
        v[0] = 1e35
        open("%s/%sf%02d.bin" % (d, f, step), "wb").write(struct.pack(">%df" % n, *v))
EOF
expect_exit 0 "info on an Isabel folder" "$anvil" info --isabel-size 8x6x4 "$tmp/isabel"
check "Isabel" stdout_has "Isabel bricks"
check "2 steps" stdout_has "time steps  2"
check "the published box" stdout_has "23.7 to 41.7 N, -83.0 to -62.0 E"
check "the published heights" stdout_has "heights     35 to 19835 m, every 6600 m"
for b in QCLOUD QRAIN QICE QSNOW QGRAUP QVAPOR CLOUD PRECIP P TC U V W; do
    check "brick $b" stdout_has "    $b "
done
check "TC range" stdout_has "TC  *5 \.\. 20 "
check "the second step's bricks" stdout_has "1 f02  all 13 bricks"
head -c 100 "$tmp/isabel/TCf01.bin" >"$tmp/isabel/TCf03.bin"
cp "$tmp/isabel/QCLOUDf01.bin" "$tmp/isabel/QCLOUDf03.bin"
expect_exit 1 "a later brick of the wrong size" "$anvil" info --isabel-size 8x6x4 "$tmp/isabel"
check "named" stderr_has "TCf03.bin: 100 bytes, expected 768"
rm "$tmp/isabel/TCf03.bin" "$tmp/isabel/QCLOUDf03.bin"
expect_exit 1 "an Isabel folder of the wrong size" "$anvil" info "$tmp/isabel"
check "names data.isabel_size" stderr_has "data.isabel_size"

expect_exit 0 "render Isabel placed without a map block" "$anvil" render --set scene.kind=data \
    --set data.format=isabel --set "data.files=[\"$tmp/isabel\"]" \
    --set data.isabel_size=[8,6,4] --set data.isabel_extent=[2000.0,2000.0,19.8] \
    --set map.graticule=true $small -o "$tmp/i.png"
check "graticule on the Isabel box" stderr_has "map: graticule every 5 degrees"
expect_exit 0 "probe an Isabel point by lat/lon, TC as temperature" "$anvil" probe \
    --set scene.kind=data --set data.format=isabel --set "data.files=[\"$tmp/isabel\"]" \
    --set data.isabel_size=[8,6,4] --set data.isabel_extent=[2000.0,2000.0,19.8] \
    --at 30,-75,2475 --quiet
check "placed" stdout_has "30.000 N, 75.000 W"
check "TC read" stdout_has "temperature    18.2 C"
check "QVAPOR read" stdout_has "vapour         0.00 g/kg"
check "the wind from U and V" stdout_has "wind           5.0 m/s from 323 deg$"
check "the vertical wind from W" stdout_has "vertical wind  +0.50 m/s"
# The levels at their published heights: 35 m, then every 19.8 km / 3 up to 19835 m.
for at in 35:20.0 6635:15.0 19835:5.0; do
    expect_exit 0 "probe Isabel's level at ${at%%:*} m" "$anvil" probe \
        --set scene.kind=data --set data.format=isabel --set "data.files=[\"$tmp/isabel\"]" \
        --set data.isabel_size=[8,6,4] --set data.isabel_extent=[2000.0,2000.0,19.8] \
        --at "30,-75,${at%%:*}" --quiet
    check "TC of that level" stdout_has "temperature    ${at##*:} C"
done

finish
