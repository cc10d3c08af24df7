#!/bin/bash
# anvil probe as a user runs it (docs/analysis.md): a config or the data files themselves, text
# and JSON, and every bad --at, --step or point refused with one message and exit code 1 (a
# missing --at: usage, 2).  The values themselves are checked against the NetCDF file in
# tests/unit/test_probe.c.  Arguments: the anvil binary, the source folder, the data folder.
. "$(dirname "$0")/lib.sh"
katrina="$data/wrf/katrina_2005_mercator_wsm3.nc"
if [ ! -r "$katrina" ]; then echo "no Katrina sample: skipping"; exit 77; fi
cfg="$src/configs/katrina.cfg"

expect_exit 0 "a point of a config" "$anvil" --quiet probe "$cfg" --at 24,-89,3000
check "the text names the position" stdout_has "24.000 N, 89.000 W"
check "the text has every species" bash -c "grep -q 'cloud' '$tmp/out' && grep -q 'graupel  *not in the data' '$tmp/out'"
check "the text has temperature and pressure" bash -c "grep -q 'temperature  *[-0-9.]* C' '$tmp/out' && grep -q 'pressure  *[0-9.]* hPa' '$tmp/out'"
check "the text has the wind and the light map" bash -c "grep -q 'wind  *[0-9.]* m/s from [0-9]* deg' '$tmp/out' && grep -q 'sunlight  *[0-9.]* of the sun' '$tmp/out'"

expect_exit 0 "the data files themselves, JSON, step 2" "$anvil" --quiet probe "$katrina" \
    --at 24,-89,3000 --step 2 --json
check "JSON: the step and its date" bash -c "grep -q '\"step\": 2,' '$tmp/out' && grep -q '\"date\": \"2005-08-28_18:00:00\"' '$tmp/out'"
check "JSON: a species the scheme lacks is null" stdout_has '"ice": null'
check "JSON: temperature from the data" stdout_has '"temperature_source": "data"'
if command -v python3 >/dev/null; then
    check "JSON: it parses" python3 -c "import json,sys; json.load(open('$tmp/out'))"
fi
# The files and the config agree on the data (the config's sun makes another light map).
"$anvil" --quiet probe "$cfg" --at 24,-89,3000 --step 2 --json >"$tmp/cfg.json"
grep -v '"light"\|"diffuse"' "$tmp/out" >"$tmp/a.json"
grep -v '"light"\|"diffuse"' "$tmp/cfg.json" >"$tmp/b.json"
check "a config and its files give the same values" cmp -s "$tmp/a.json" "$tmp/b.json"

# The procedural storm has no lat/lon unless placed with map.use_origin.
expect_exit 1 "the storm without a placement" "$anvil" --quiet probe --at 25,-80,2000
check "  says how to place it" stderr_has "map.use_origin"
expect_exit 0 "the storm placed at map.origin" "$anvil" --quiet probe --at 25.2,-79.8,3000 \
    --set map.use_origin=true --json
check "  its temperature is the standard atmosphere's" \
    stdout_has '"temperature_source": "standard atmosphere"'

# Katrina is a moving nest: a point its last step covers and its first does not is found at
# the last step and said to be outside at the first; info says it moves; a movie of its steps
# makes the map (terrain, coastlines) again for each step.
expect_exit 0 "a point of the nest's last step" "$anvil" --quiet probe "$katrina" \
    --at 26.3,-90.5,3000 --step 3
check "  placed there" stdout_has "26.300 N, 90.500 W"
expect_exit 1 "the same point at the first step" "$anvil" --quiet probe "$katrina" \
    --at 26.3,-90.5,3000 --step 0
check "  outside that step's columns" stderr_has "its columns lie at 21.80 to 25.67 N, 91.65 to 87.43 W at this step"
expect_exit 0 "info on the moving nest" "$anvil" --quiet info "$katrina"
check "  says it moves and where to" stdout_has "moves       a moving nest: 22.803 to 26.642 N, 93.003 to 88.775 W at the last step (3)"
expect_exit 0 "its steps as frames" "$anvil" render "$katrina" --verbose --set render.width=32 \
    --set render.height=24 --frames 0:3 -o "$tmp/k-%d.png"
check "  a map for each step shown" test "$(grep -c 'map: terrain' "$tmp/err")" -eq 4

# Bad input: one message each, exit 1.
expect_exit 1 "--at with two numbers" "$anvil" probe "$cfg" --at 24,-89
check "  says what --at is" stderr_has "expected LAT,LON,HEIGHT_M: three numbers"
expect_exit 1 "--at with a word" "$anvil" probe "$cfg" --at 24,-89,high
check "  says what --at is" stderr_has "probe: --at 24,-89,high: expected LAT,LON,HEIGHT_M"
expect_exit 1 "a latitude past the pole" "$anvil" probe "$cfg" --at 95,-89,100
check "  names the range" stderr_has "latitude in \[-90, 90\]"
expect_exit 1 "a point outside the domain" "$anvil" --quiet probe "$cfg" --at 30,-80,1000
check "  says where the data lies" stderr_has "outside the data (its columns lie at 21.80 to 25.67 N"
expect_exit 1 "a point below the ground" "$anvil" --quiet probe "$cfg" --at 24,-89,-50
check "  says so" stderr_has "below the ground"
# Below the whole height grid as just below the ground: the column's own ground is named,
# not the domain's lowest (the Tibetan plateau, ground at 5293 m where the grid starts at 5044).
thompson="$data/wrf/lambert_thompson_cropped.nc"
if [ -r "$thompson" ]; then
    expect_exit 1 "a point below the height grid" "$anvil" --quiet probe "$thompson" --at 30,87,5000
    check "  names this column's ground" stderr_has "below the ground (5293 m above sea level there"
    expect_exit 1 "a point below the ground, inside the grid" "$anvil" --quiet probe "$thompson" \
        --at 30,87,5100
    check "  names the same ground" stderr_has "below the ground (5293 m above sea level there"
fi
# Between this column's model top (6065 m) and the volume's (the highest, 6068 m on the
# model's own levels), where the volume holds the column's top level: its values, said so.
expect_exit 0 "a point above the column's top, inside the volume" "$anvil" --quiet probe \
    "$katrina" --at 24,-89,6066
check "  the values at the column's top" stdout_has "6066 m (above the model top here: the values at 6065 m)"
expect_exit 1 "a point above the data" "$anvil" --quiet probe "$cfg" --at 24,-89,40000
check "  says so" stderr_has "above the top of the data"
expect_exit 1 "a step the data lacks" "$anvil" --quiet probe "$cfg" --at 24,-89,3000 --step 4
check "  names the steps" stderr_has "the data has the time steps 0 to 3"
expect_exit 1 "a step that is no number" "$anvil" --quiet probe "$cfg" --at 24,-89,3000 --step x
expect_exit 2 "no --at" "$anvil" probe "$cfg"
printf 'look = {\n  transfer = 5;\n};\n' >"$tmp/bad.cfg"
expect_exit 1 "a config with a bad look" "$anvil" probe "$tmp/bad.cfg" --at 24,-89,3000
check "  names file:line" stderr_has "bad.cfg:2: look.transfer: expected a transfer function"
expect_exit 1 "a file that is not there" "$anvil" probe "$tmp/none.nc" --at 24,-89,3000
finish
