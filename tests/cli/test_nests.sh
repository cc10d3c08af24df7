#!/bin/bash
# A WRF parent and its nest in one scene (docs/data.md, "Nests"): written by anvil synth --nest,
# described by info (how each domain is placed: by its PARENT attributes or its XLAT/XLONG),
# rendered from both files as arguments, from a pattern and from a config's data.files; a nest
# outside its parent, a ratio the spacings contradict and a budget the composite exceeds are
# refused naming the file.  Arguments: ANVIL_BINARY SOURCE_DIR SHARED_DATA_DIR.
. "$(dirname "$0")/lib.sh"

small="--set render.width=96 --set render.height=72 --set lightmap.resolution=[24,24,24]"
cd "$tmp" || exit 1

expect_exit 0 "synth writes a parent and its nest" "$anvil" synth -o wrfout_d01.nc \
    --nest wrfout_d02.nc --size 24x24x16 --steps 2 --nest-box 15,15,9,9
check "the nest is where it was asked" stderr_has "nest wrfout_d02.nc: 27 x 27 columns of 833.333 m from column 15, 15"
expect_exit 0 "info on the pair" "$anvil" info wrfout_d01.nc wrfout_d02.nc
check "info says how they are composed" stdout_has "2 WRF domains in one scene, composed on 72 x 72 columns of 833.333 m"
check "and where the nest lies" stdout_has "d02 27 x 27 columns of 833.333 m in d01 from its column 15, 15 (ratio 3), placed by PARENT_ID, I/J_PARENT_START and PARENT_GRID_RATIO; XLAT/XLONG agree within [0-9] m"
check "then each domain" stdout_has "wrfout_d02.nc: WRF output"

expect_exit 0 "a nest without PARENT attributes" "$anvil" synth -o ll_d01.nc \
    --nest ll_d02.nc --size 24x24x16 --nest-box 3,5,6,9 --nest-latlon
expect_exit 0 "info on it" "$anvil" info ll_d02.nc ll_d01.nc
check "it is placed by its latitude and longitude, on the same columns" \
    stdout_has "d02 18 x 27 columns of 833.333 m in d01 from its column 3, 5 (ratio 3), placed by its XLAT/XLONG ([0-9] m off the grid)"

# A run's folder as it is: its history files by WRF's names (every domain), whatever else
# it holds; a folder of .nc files (its name's pattern characters taken as they are); a folder
# of neither, refused with what was expected.
mkdir -p run "odd [1]" none
cp wrfout_d01.nc run/wrfout_d01_2005-08-28_00:00:00
cp wrfout_d02.nc run/wrfout_d02_2005-08-28_00:00:00
echo "&time_control /" >run/namelist.input
echo "d01 2005-08-28_00:00:00 wrf: SUCCESS COMPLETE WRF" >run/rsl.out.0000
expect_exit 0 "info on a run's folder" "$anvil" info run/
check "it says what it took" stderr_has "run/: 2 files of WRF output (run/wrfout_d\*)"
check "both domains, composed" stdout_has "2 WRF domains in one scene, composed on 72 x 72 columns"
cp wrfout_d01.nc "odd [1]/parent.nc"
expect_exit 0 "info on a folder of .nc files" "$anvil" info "odd [1]"
check "it says what it took" stderr_has "odd \[1\]: 1 NetCDF file ("
check "the file is read" stdout_has "24 x 24 columns x 16 mass levels"
echo "notes" >none/README
expect_exit 1 "a folder of neither" "$anvil" info none
check "it says what was expected" stderr_has "none: a folder that no reader of anvil takes: expected a folder of Isabel bricks (QCLOUDf01.bin, QRAINf01.bin, ...), of WRF output (wrfout_d01_...) or of NetCDF files (\*.nc)"
echo "not data" >"odd [1]/notes.nc"
expect_exit 1 "a folder whose .nc files are not all data" "$anvil" info "odd [1]"
check "it names the file" stderr_has "notes.nc is a text file (a scene config) among data files"

# Rendering needs a GL context from here on.
require_gl
expect_exit 0 "render a run's folder" "$anvil" render run $small -o folder.png
check "the volume is the composite" stderr_has "volume 72x72x16"
expect_exit 0 "render with both files as arguments" "$anvil" render wrfout_d01.nc wrfout_d02.nc \
    $small -o both.png
check "the volume is the composite" stderr_has "volume 72x72x16"
check "the picture is written" test -s both.png
expect_exit 0 "render a pattern over both domains" "$anvil" render "wrfout_d0*" $small \
    --set data.step=1 -o pattern.png
check "the pattern is grouped by domain" stderr_has "volume 72x72x16"
cat >nests.cfg <<CFG
scene = { kind = "data"; };
data = { files = ["wrfout_d01.nc", "wrfout_d02.nc"]; };
CFG
expect_exit 0 "render from a config's data.files" "$anvil" render nests.cfg $small -o cfg.png
check "the config's files are grouped too" stderr_has "volume 72x72x16"

expect_exit 0 "a crop of the composite around the nest" "$anvil" render wrfout_d01.nc \
    wrfout_d02.nc --set 'data.crop=[36,71,36,71,-1,-1]' $small -o crop.png
check "the volume is that part" stderr_has "volume 36x36x16"

# Refused, naming the file.
"$anvil" --quiet synth -o small_d01.nc --size 18x18x16 --extent 45x45x16
expect_exit 1 "a nest outside its parent" "$anvil" render small_d01.nc wrfout_d02.nc $small -o x.png
check "it names the nest and the parent" stderr_has "wrfout_d02.nc: domain 2 (27 x 27 columns of 833.333 m) starts at column 15, 15 of small_d01.nc (18 x 18 columns of 2500 m) and does not fit inside it"
"$anvil" --quiet synth -o half_d01.nc --size 24x24x16 --extent 40x40x16
expect_exit 1 "a ratio the spacings contradict" "$anvil" info half_d01.nc wrfout_d02.nc
check "it names the nest, its ratio and the parent" stderr_has "wrfout_d02.nc: PARENT_GRID_RATIO 3, but DX 833.333 m against its parent's 1666.67 m (half_d01.nc) is a ratio of 2: inconsistent"
expect_exit 1 "a budget the composite exceeds" "$anvil" render wrfout_d01.nc wrfout_d02.nc \
    --set data.memory=2 $small -o x.png
check "it says what the domains need" stderr_has "wrfout_d01.nc and 1 nest: a time step of every domain and their composite on 72 x 72 x 16 voxels need 4 MiB, above the budget data.memory = 2 MiB"
expect_exit 0 "the parent alone fits it" "$anvil" render wrfout_d01.nc --set data.memory=2 \
    $small -o x.png
# Two runs on two map projections are not a parent and its nest, and are called so.
katrina="$data/wrf/katrina_2005_mercator_wsm3.nc" thompson="$data/wrf/lambert_thompson_cropped.nc"
if [ -r "$katrina" ] && [ -r "$thompson" ]; then
    expect_exit 1 "two runs given as domains" "$anvil" info "$katrina" "$thompson"
    check "it says their projections differ" stderr_has "are not domains of one run: their map projections differ (MAP_PROJ 1 against 3"
fi
finish
