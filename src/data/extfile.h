/*
 * data/extfile: precomputed extinction volumes (Nes §5.6) in a CF-1.8 NetCDF file, one ice-
 * phase and one water-phase volume per time step, that the renderer loads directly
 * (data.format = "extinction").  Layout: dimensions time (unlimited), z, y, x, nv = 2; float
 * beta_ice(time, z, y, x) and beta_water(time, z, y, x) in m-1; coordinates x, y, z (cell
 * centres, m) with x_bnds, y_bnds, z_bnds (cell bounds, m); time (seconds since the first
 * date) and char Times(time, date_len).  What is lost against the mass ratios: the species
 * (only the phase sums remain), so per-species toggles and scales are fixed at conversion time.
 *
 * No GL, no config.  NetCDF calls hold data_nc_lock.
 */
#ifndef ANVIL_DATA_EXTFILE_H
#define ANVIL_DATA_EXTFILE_H

#include <stdbool.h>
#include <stddef.h>

#include "data/volume.h"

struct extfile_writer;

/* Starts writing PATH: the data goes to a temporary file in the same folder that replaces
 * PATH only when extfile_writer_finish succeeds, so a failed conversion never destroys an
 * existing file.  Every step must have GRID.  SOURCE (e.g. the input files) and HISTORY (the
 * command line) go into the global attributes of the same names; SPECIES_NOTE (may be NULL)
 * into "anvil_species", saying which species were enabled and scaled.  Strings are copied.
 * Returns NULL after logging. */
struct extfile_writer *extfile_writer_create(const char *path, const struct grid3 *grid,
                                             const char *source, const char *history,
                                             const char *species_note);

/* Appends one step.  DATE is "YYYY-MM-DD_hh:mm:ss" or "" (then the time coordinate counts
 * steps in seconds from 1970-01-01).  V->grid must equal the writer's grid. */
bool extfile_writer_add(struct extfile_writer *w, const struct ext_volume *v, const char *date);

/* Closes and moves the file into place; frees W.  False (logged) when anything failed, and
 * then the original PATH is untouched. */
bool extfile_writer_finish(struct extfile_writer *w);

/* Abandons the file (the temporary is removed) and frees W.  NULL is fine. */
void extfile_writer_destroy(struct extfile_writer *w);

struct extfile;

/* Whether PATH is a NetCDF file with a beta_ice variable (an extinction file).  Logs
 * nothing. */
bool extfile_probe(const char *path);

/* Opens an extinction file and checks its layout; a step must fit MEMORY_MB (MiB, judged from
 * the dimensions before anything is read; 0 = no limit).  NULL after one log_error naming the
 * file and variable.  Free with extfile_close. */
struct extfile *extfile_open(const char *path, double memory_mb);
void extfile_close(struct extfile *f); /* NULL is fine */

int extfile_step_count(const struct extfile *f);
const char *extfile_step_date(const struct extfile *f, int step); /* valid until close */
const struct grid3 *extfile_grid(const struct extfile *f);        /* valid until close */

/* Bad values found in a step: NaN, Inf, negative, fill → zero. */
struct extfile_stats {
    size_t nan, inf, negative, fill;
};

/* Reads STEP into OUT (initialised here; the caller finishes it).  STATS may be NULL; bad
 * values are also reported with log_warn.  False (logged, OUT zeroed) on failure. */
bool extfile_read_step(struct extfile *f, int step, struct ext_volume *out,
                       struct extfile_stats *stats);

/* Seconds since 1970-01-01 of a "YYYY-MM-DD_hh:mm:ss" (or "YYYY-MM-DD hh:mm:ss") date; false
 * when it is not one. */
bool extfile_parse_date(const char *date, double *seconds);

#endif
