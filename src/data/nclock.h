/*
 * data/nclock: NetCDF-C is not thread safe, so every part of data/ that calls nc_* holds this
 * one process-wide lock for the whole of an operation (open, read a variable, write a step;
 * a WRF step is read a slab at a time, the lock taken for each read, so that other threads
 * compute meanwhile).  The lock is recursive: an operation may call another.
 */
#ifndef ANVIL_DATA_NCLOCK_H
#define ANVIL_DATA_NCLOCK_H

#include <stdbool.h>

void data_nc_lock(void);
void data_nc_unlock(void);
/* data_nc_lock for work on the file PATH (DOING: "reading", "writing"; both must stay valid
 * until the matching data_nc_unlock): a crash inside netcdf-c or HDF5 meanwhile is reported
 * as the library's, naming the file (common/fatal.h). */
void data_nc_lock_file(const char *path, const char *doing, bool writing);

#define DATA_NC_LIBRARY "netCDF-C (with HDF5)"

/* NetCDF files written atomically: created as a temporary sibling of PATH and moved onto PATH
 * only when complete, so a failed write never leaves a half-written file nor loses the old
 * one.  Each takes the lock itself and logs its failures. */

/* Creates the temporary sibling (*TMP, allocated here) with nc_create mode CMODE; *NCID is -1
 * on failure. */
bool data_nc_create_beside(const char *path, int cmode, char **tmp, int *ncid);
/* Closes *NCID and, when OK and STEPS > 0 (a file of no time steps is an error), renames *TMP
 * onto PATH (then frees *TMP and sets it NULL).  Returns whether the file is in place. */
bool data_nc_finish_beside(const char *path, char **tmp, int *ncid, bool ok, int steps);
/* Closes *NCID if it is open and removes and frees *TMP if it is still there. */
void data_nc_abandon(char **tmp, int *ncid);

#endif
