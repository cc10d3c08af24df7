/*
 * data/isabel: raw bricks of floats as distributed for the IEEE Visualization 2004 contest
 * (hurricane Isabel): one file per field per time step, named FIELD + "f" + two-digit step
 * (from 01) + ".bin" (QCLOUDf01.bin, QRAINf01.bin, ...), big-endian float32, x fastest then y
 * then z (lowest level first).  Dimensions and physical extent are not in the files: they come
 * from the caller (data.isabel_size, data.isabel_extent).  Land points (1.0e35) and other bad
 * values (NaN, Inf, negative, above 1 kg/kg) become zero and are counted.  Air density is not
 * in the bricks (their P is a perturbation): rho_air stays NULL, so the standard atmosphere is
 * used.  The bricks are read as they are (no gzip: unpack the .gz files first).
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
    double extent_m[3]; /* box size, m; 0 = 2000 km x 2000 km x 20 km */
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

/* The grid isabel_read_step puts a step of D on. */
void isabel_grid(const struct isabel_desc *d, struct grid3 *out);

/* Path of FIELD's brick for STEP (0-based: step 0 is f01) into BUF of SIZE bytes. */
void isabel_brick_path(const struct isabel_desc *d, const char *field, int step, char *buf,
                       size_t size);

/* Reads STEP (0-based) into OUT (initialised here; finish it with field_volume_finish): species
 * whose brick is missing stay NULL.  A brick whose size is not n0 n1 n2 4 bytes, an unreadable
 * brick, or no brick at all → false after one log_error naming the file.  STATS may be NULL;
 * bad values are also reported with log_warn. */
bool isabel_read_step(const struct isabel_desc *d, int step, struct field_volume *out,
                      struct isabel_stats *stats);

#endif
