/*
 * data/isabel: raw bricks of floats as distributed for the IEEE Visualization 2004 contest
 * (hurricane Isabel): one file per field per time step, named FIELD + "f" + two-digit step
 * (from 01) + ".bin" (QCLOUDf01.bin, QRAINf01.bin, ...), big-endian float32, x fastest then y
 * then z (lowest level first).  Dimensions and physical extent are not in the files: they come
 * from the caller (data.isabel_size, data.isabel_extent).  Land points (1.0e35) and other bad
 * values (NaN, Inf, negative, above 1 kg/kg) become zero and are counted.  Besides the five
 * species, QVAPOR (vapour), TC (temperature, degrees Celsius) and U, V, W (wind, m/s) are read
 * when asked for; CLOUD, PRECIP (sums of species already read) and P (a pressure perturbation)
 * are described by isabel_brick_stats for `anvil info`.  Air density is not in the bricks
 * (their P is a perturbation of an unpublished base state): rho_air stays NULL, so the
 * standard atmosphere is used.  The bricks are read as they are (no gzip: unpack the .gz
 * files first).
 *
 * The contest published where the data lie (IEEE Visualization 2004 Contest, "Data Set",
 * http://vis.computer.org/vis2004contest/data.html): longitude 83 W to 62 W, latitude 23.7 N
 * to 41.7 N, height 0.035 km to 19.835 km, on 500 x 500 x 100 points.  isabel_geo places the
 * grid there, so no map block is needed.
 *
 * No GL, no config, no NetCDF.
 */
#ifndef ANVIL_DATA_ISABEL_H
#define ANVIL_DATA_ISABEL_H

#include <stdbool.h>
#include <stddef.h>

#include "data/volume.h"

#define ISABEL_LAND 1.0e35f

struct isabel_desc {
    const char *dir;    /* folder holding the bricks */
    int n[3];           /* voxels; 0 = 500 x 500 x 100 */
    double extent_m[3]; /* x, y: box size, m; z: from the lowest level's height to the
                           highest's, m (the published 19.8 km); 0 = 2000 km x 2000 km x
                           19.8 km */
    bool qvapor;        /* also read QVAPOR */
    bool temperature;   /* also read TC into field_volume.temperature (K) */
    bool wind;          /* also read U, V, W into field_volume.wind (speed, m/s) */
    bool wind_components; /* with WIND: also keep U, V, W as field_volume u, v, w */
    double memory_mb;   /* refuse a step whose arrays need more (data.memory); 0 = no limit */
};

/* The published box of the Isabel grid's points, degrees. */
#define ISABEL_LAT_SOUTH 23.7
#define ISABEL_LAT_NORTH 41.7
#define ISABEL_LON_WEST (-83.0)
#define ISABEL_LON_EAST (-62.0)

/* The published height of the lowest level, m: the levels lie at ISABEL_BOTTOM_M + k dz,
 * dz = extent_m[2] / (nz - 1), so the default 19.8 km puts the highest at 19835 m. */
#define ISABEL_BOTTOM_M 35.0

/* The grid the bricks are read onto: the box of extent_m in x and y from (0, 0); in z the
 * voxel centres at the levels' heights (above), so the box runs from half a level below the
 * lowest to half a level above the highest (one level: a layer extent_m[2] thick around
 * ISABEL_BOTTOM_M). */
void isabel_grid(const struct isabel_desc *d, struct grid3 *out);

/* Every field the contest distributed, the five species first (enum species order). */
#define ISABEL_FIELD_COUNT 13
extern const char *const isabel_fields[ISABEL_FIELD_COUNT];

/* The range of one brick (for anvil info). */
struct isabel_brick_stats {
    bool present;
    double min, max; /* of the good values */
    size_t land;     /* land (1.0e35) and other bad values (NaN, Inf) */
};

struct isabel_stats {
    size_t land; /* 1.0e35 */
    size_t nan, inf, negative, absurd;
    bool present[SPECIES_COUNT]; /* a brick was found for the species */
};

/* Number of consecutive steps (from f01) for which at least one species brick exists; 0 when
 * none (logged as an error naming the folder). */
int isabel_step_count(const struct isabel_desc *d);

/* Whether DIR is a folder holding the first step's brick of at least one species
 * (QCLOUDf01.bin, ...).  Logs nothing. */
bool isabel_probe(const char *dir);


/* Path of FIELD's brick for STEP (0-based: step 0 is f01) into BUF of SIZE bytes. */
void isabel_brick_path(const struct isabel_desc *d, const char *field, int step, char *buf,
                       size_t size);

/* Reads STEP (0-based) into OUT (initialised here; finish it with field_volume_finish): species
 * whose brick is missing stay NULL.  A step above D's memory budget is refused first.  A brick whose size is not n0 n1 n2 4 bytes, an unreadable
 * brick, or no brick at all → false after one log_error naming the file.  STATS may be NULL;
 * bad values are also reported with log_warn. */
bool isabel_read_step(const struct isabel_desc *d, int step, struct field_volume *out,
                      struct isabel_stats *stats);

/* Reads the brick of FIELD for STEP and describes its values into OUT (present false when the
 * brick is not there).  False after one log_error when it is there but unreadable or of the
 * wrong size. */
bool isabel_brick_stats(const struct isabel_desc *d, const char *field, int step,
                        struct isabel_brick_stats *out);

struct geo_map;
/* Places the grid on the published lat/lon box: column (i, j) at longitude
 * ISABEL_LON_WEST + i (ISABEL_LON_EAST - ISABEL_LON_WEST) / (nx - 1), likewise for latitude.
 * False (logged) when out of memory. */
bool isabel_geo(const struct isabel_desc *d, struct geo_map *out);

#endif
