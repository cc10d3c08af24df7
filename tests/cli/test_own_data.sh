#!/bin/bash
# A meteorologist's own files in one command (docs/data.md): data files and quoted patterns as
# arguments of render, info, probe and effects, known by their content; a config first for
# the rest; each wrong input with its message and exit code; the Katrina and Lambert samples
# rendered with no config (framed, non-blank, finite); Shift+F (`key frame`) gives the framed
# view back after the camera moved; a classic NetCDF file cut short is refused naming the
# variable and the bytes missing.  Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.
. "$(dirname "$0")/lib.sh"

small="--set render.width=96 --set render.height=72 --set lightmap.resolution=[24,24,24]"

# Wrong inputs (no GL needed: all refused before a context is made).
expect_exit 1 "a pattern that matches nothing" "$anvil" render "$tmp/wrfout_d01_*" -o "$tmp/x.png"
check "it names the pattern" stderr_has "no file matches the pattern $tmp/wrfout_d01_\*"
printf 'this is not a scene\n' >"$tmp/notes.txt"
expect_exit 1 "a text file that is not a config" "$anvil" render "$tmp/notes.txt" -o "$tmp/x.png"
check "the config's message: file and line" stderr_has "notes.txt:1: syntax error"
printf '\x1f\x8b\x08\x00\x00\x00\x00\x00' >"$tmp/wrfout.gz"
expect_exit 1 "a gzip file" "$anvil" render "$tmp/wrfout.gz" -o "$tmp/x.png"
check "it says what it begins with" stderr_has "neither text (a scene config) nor NetCDF: it begins with the bytes 1f 8b 08 00 (gzip-compressed"
: >"$tmp/empty.nc"
expect_exit 1 "an empty file" "$anvil" render "$tmp/empty.nc" -o "$tmp/x.png"
check "it says it is empty" stderr_has "empty.nc: an empty file"
# A NetCDF file of another kind: an extinction file's variables renamed would be work; a
# NetCDF file made from CDL by ncgen, where it is installed.
if command -v ncgen >/dev/null; then
    printf 'netcdf era5 {\ndimensions:\n  latitude = 3 ;\n  time = 2 ;\nvariables:\n  float t2m(time, latitude) ;\n}\n' >"$tmp/era5.cdl"
    ncgen -o "$tmp/era5.nc" "$tmp/era5.cdl"
    expect_exit 1 "a NetCDF file of an unknown kind" "$anvil" render "$tmp/era5.nc" -o "$tmp/x.png"
    check "it says what it has" stderr_has "era5.nc: a NetCDF file that no reader of anvil takes (it has the dimensions latitude, time; the variables t2m)"
    check "and what was expected" stderr_has "expected WRF output (the dimensions west_east"
    expect_exit 1 "info on it" "$anvil" info "$tmp/era5.nc"
    check "info says the same" stderr_has "no reader of anvil takes"
fi

# Integrity: a classic (64-bit offset) file cut short in its data.
"$anvil" --quiet synth -o "$tmp/series.nc" --steps 3 --size 16x16x8 >/dev/null
size=$(stat -c %s "$tmp/series.nc")
keep=$((size - 1000))
head -c "$keep" "$tmp/series.nc" >"$tmp/cut.nc"
expect_exit 1 "a classic file cut short" "$anvil" render "$tmp/cut.nc" -o "$tmp/x.png"
check "it names the file, a variable and the bytes missing" \
    stderr_has "cut.nc: .*variable [A-Z_]*: .*(1000 bytes missing): truncated or damaged"
expect_exit 1 "info on it" "$anvil" info "$tmp/cut.nc"
check "info says the same" stderr_has "(1000 bytes missing)"

# Files, patterns and a config first, on a synthetic series.
cp "$tmp/series.nc" "$tmp/wrfout_d01_a"
"$anvil" --quiet synth -o "$tmp/wrfout_d01_b" --steps 2 --size 16x16x8 \
    --start 2000-01-01_00:30:00 >/dev/null
printf 'light = { elevation = 20.0; };\n' >"$tmp/look.cfg"
expect_exit 1 "a config after the data" "$anvil" effects "$tmp/wrfout_d01_a" "$tmp/look.cfg"
check "it says the config comes first" stderr_has "look.cfg is a text file (a scene config) among data files: the config comes first"
expect_exit 0 "info on a quoted pattern" "$anvil" info "$tmp/wrfout_d01_*"
check "it reads both files as one series" stdout_has "time steps  5"
expect_exit 0 "probe on a pattern" "$anvil" probe --quiet "$tmp/wrfout_d01_*" --at 25,-89,2000
check "probe reads the data" stdout_has "condensate"
expect_exit 0 "effects with a config first" "$anvil" effects --quiet "$tmp/look.cfg" "$tmp/wrfout_d01_a"
check "it names the config" stdout_has "effects of $tmp/look.cfg"
expect_exit 0 "effects of files alone" "$anvil" effects --quiet "$tmp/wrfout_d01_*"
check "it names the data, not the built-in scene" stdout_has "effects of $tmp/wrfout_d01_\*:"

require_gl
# A config then files: the config's settings (light.elevation 20), these files.
expect_exit 0 "render a config then files" "$anvil" render "$tmp/look.cfg" "$tmp/wrfout_d01_*" \
    $small -o "$tmp/a.pfm"
expect_exit 0 "the same with --set" "$anvil" render "$tmp/wrfout_d01_*" --set light.elevation=20 \
    $small -o "$tmp/b.pfm"
check "the config's settings applied to the files" cmp -s "$tmp/a.pfm" "$tmp/b.pfm"
expect_exit 0 "the same from data.files" "$anvil" render --set scene.kind=data \
    --set "data.files=[\"$tmp/wrfout_d01_*\"]" --set light.elevation=20 $small -o "$tmp/c.pfm"
check "files as arguments are data.files" cmp -s "$tmp/a.pfm" "$tmp/c.pfm"

# The samples, no config: framed (the log names the camera), finite, not blank.
for name in katrina_2005_mercator_wsm3 lambert_thompson_cropped; do
    f="$data/wrf/$name.nc"
    [ -f "$f" ] || continue
    expect_exit 0 "render $name with no config" "$anvil" render "$f" \
        --set render.width=160 --set render.height=120 -o "$tmp/$name.png" \
        --stats "$tmp/$name.json"
    check "$name: the camera frames the data" stderr_has "camera framing the data"
    check "$name: no non-finite pixels" grep -q '"nonfinite_pixels": 0,' "$tmp/$name.json"
    # The clouds against the same view without them (no ground, no map in either).
    bare="--set render.width=160 --set render.height=120 --set render.ground_on=false --set map.terrain=false --set map.coastlines=false"
    "$anvil" render --quiet "$f" $bare -o "$tmp/$name.pfm"
    "$anvil" render --quiet "$f" $bare --set species.cloud.enabled=false --set species.rain.enabled=false \
        --set species.ice.enabled=false --set species.snow.enabled=false \
        --set species.graupel.enabled=false -o "$tmp/$name-sky.pfm"
    check "$name: not blank (the picture is not the empty sky)" \
        bash -c "! cmp -s '$tmp/$name.pfm' '$tmp/$name-sky.pfm'"
done

# Shift+F: after the camera moved, the framed view again.
printf '0 key zoom-in\n1 key turn-left\n2 key turn-up\n' >"$tmp/moved.txt"
printf '0 key zoom-in\n1 key turn-left\n2 key turn-up\n3 key frame\n' >"$tmp/framed.txt"
"$anvil" render --quiet "$tmp/wrfout_d01_a" $small -o "$tmp/f0.pfm"
"$anvil" render --quiet "$tmp/wrfout_d01_a" $small --input "$tmp/moved.txt" -o "$tmp/f1.pfm"
"$anvil" render --quiet "$tmp/wrfout_d01_a" $small --input "$tmp/framed.txt" -o "$tmp/f2.pfm"
check "the keys moved the camera" bash -c "! cmp -s '$tmp/f0.pfm' '$tmp/f1.pfm'"
check "key frame gives the framed view again" cmp -s "$tmp/f0.pfm" "$tmp/f2.pfm"
# On a CAVE: the navigation fitted to the room again.
cave="--display $src/displays/cave4.cfg --format pfm --set render.height=32"
"$anvil" render --quiet "$tmp/wrfout_d01_a" $cave -o "$tmp/c0"
"$anvil" render --quiet "$tmp/wrfout_d01_a" $cave --input "$tmp/moved.txt" -o "$tmp/c1"
"$anvil" render --quiet "$tmp/wrfout_d01_a" $cave --input "$tmp/framed.txt" -o "$tmp/c2"
check "cave4: the keys moved the world" \
    bash -c "! cmp -s '$tmp/c0/front-left.pfm' '$tmp/c1/front-left.pfm'"
check "cave4: key frame fits it to the room again" \
    cmp -s "$tmp/c0/front-left.pfm" "$tmp/c2/front-left.pfm"
# Katrina, 480 km wide and 6 km tall, is a map 23 mm thick on cave4's floor: the log says how
# to lift it, and says nothing once it is lifted.
katrina="$data/wrf/katrina_2005_mercator_wsm3.nc"
expect_exit 0 "cave4: Katrina fitted to the room" "$anvil" render "$katrina" $cave -o "$tmp/k4"
check "says the domain is flat and how to lift it" \
    stderr_has "the domain stands 23 mm tall in the room: --set scene.height_exaggeration=10 lifts it to 228 mm"
expect_exit 0 "cave4: Katrina lifted ten times" "$anvil" render "$katrina" $cave \
    --set scene.height_exaggeration=10 -o "$tmp/k4"
check "no hint once lifted" bash -c "! grep -q 'the domain stands' '$tmp/err'"

# A bookmark of a session on files names them (after the config it includes).
printf '0 key bookmark\n' >"$tmp/mark.txt"
(cd "$tmp" && "$anvil" render --quiet look.cfg 'wrfout_d01_*' $small --input mark.txt \
    -o mark.pfm >/dev/null)
check "the bookmark was written" test -f "$tmp/bookmark-1.cfg"
check "it includes the config" grep -q "^@include \"$tmp/look.cfg\"" "$tmp/bookmark-1.cfg"
check "it names the files" grep -q "files = \[\"$tmp/wrfout_d01_\*\"\]" "$tmp/bookmark-1.cfg"
expect_exit 0 "the bookmark renders from elsewhere" "$anvil" render "$tmp/bookmark-1.cfg" \
    $small -o "$tmp/mark2.pfm"
check "it reads the files" stderr_has "time step 0 (2000-01-01_00:00:00)"
finish
