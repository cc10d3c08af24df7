/*
 * data/ncopen: opening NetCDF files for reading without handing netcdf-c bytes it may choke
 * on.  netcdf-c trusts the header of a classic file: a dimension, a record count or a list
 * length that one flipped byte makes huge costs minutes and gigabytes, a length it cannot
 * allocate crashes it, and a file cut short reads as zeros.  So before nc_open the header of a
 * classic (CDF-1), 64-bit offset (CDF-2) or 64-bit data (CDF-5) file is parsed here, every
 * length checked against the bytes the file has, and every variable's data (the records
 * included) must lie inside the file.  HDF5 (NetCDF-4) files are handed to netcdf-c after the
 * signature check; their sizes are the readers' to check against their budgets before they
 * read (the dimensions' product first).  Anything else — a FIFO, a device, a URL, HDF4 — is
 * refused.
 *
 * The format is the one of netcdf-c's docs/file_format_specifications.md ("The NetCDF Classic
 * Format Specification", and its 64-bit offset section); CDF-5 widens the counts, sizes and
 * dimension lengths to 64 bits and adds five integer types (PnetCDF's CDF-5 specification,
 * https://cucis.ece.northwestern.edu/projects/PnetCDF/CDF-5.html).
 *
 * No GL, no config.  The checks need no lock; data_nc_open takes data_nc_lock for nc_open.
 */
#ifndef ANVIL_DATA_NCOPEN_H
#define ANVIL_DATA_NCOPEN_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/types.h>

enum data_nc_format {
    DATA_NC_CLASSIC = 1,      /* CDF-1 */
    DATA_NC_64BIT_OFFSET = 2, /* CDF-2: what anvil synth writes */
    DATA_NC_64BIT_DATA = 5,   /* CDF-5 */
    DATA_NC_HDF5 = 4,         /* NetCDF-4: what anvil convert writes */
};

/* What the check found.  NEED is the bytes the header says the file holds (the header and all
 * variables' data, every record included); 0 for HDF5. */
struct data_nc_layout {
    enum data_nc_format format;
    uint64_t file_size, need;
    dev_t dev;
    ino_t ino;
};

/* The name of a format ("64-bit offset"). */
const char *data_nc_format_name(enum data_nc_format f);

/* Checks the LEN bytes at DATA as a whole classic-format file (fuzzers and tests use this).
 * False with the reason in WHY when the header is malformed or promises more data than LEN;
 * else *NEED (may be NULL) receives the bytes the header needs. */
bool data_nc_check_classic(const void *data, size_t len, char *why, size_t why_size,
                           uint64_t *need);

/* Opens PATH read-only with nc_open once the checks above pass.  False with the reason in WHY
 * (nothing logged: the callers say whether it is an error or a warning), *NCID -1.  LAYOUT
 * (may be NULL) receives what was found. */
bool data_nc_open(const char *path, int *ncid, struct data_nc_layout *layout, char *why,
                  size_t why_size);

/* Whether the file at PATH still holds what its header promised when it was opened: false
 * with one log_error naming the file when it has been cut shorter since (netcdf-c would read
 * the missing part as zeros).  A file moved away or replaced is not checked (the open
 * descriptor still reads the old one). */
bool data_nc_still_whole(const char *path, const struct data_nc_layout *layout);

#endif
