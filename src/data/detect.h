/*
 * data/detect: what a path named on the command line is, from its content rather than its
 * name: a scene config (text), WRF or CM1 output, CF NetCDF on height levels, an anvil
 * extinction file, an Isabel folder, or something no reader takes.  Each reader's own probe
 * (wrf_probe, cm1_probe, cf_probe, extfile_probe, isabel_probe) decides for its format; a NetCDF file none of them takes is described (its
 * dimensions and variables) so that the message says what was found and what was expected.
 *
 * No GL, no config: the caller maps a kind onto data.format.
 */
#ifndef ANVIL_DATA_DETECT_H
#define ANVIL_DATA_DETECT_H

#include <stdbool.h>
#include <stddef.h>

enum data_kind {
    DATA_KIND_UNREADABLE, /* missing, unreadable or damaged (a cut-short NetCDF file): WHY */
    DATA_KIND_CONFIG,     /* a text file: a scene config */
    DATA_KIND_WRF,        /* WRF output (NetCDF) */
    DATA_KIND_CM1,        /* CM1 output (NetCDF) */
    DATA_KIND_CF,         /* CF NetCDF on height levels */
    DATA_KIND_EXTINCTION, /* an extinction file of anvil convert (NetCDF) */
    DATA_KIND_ISABEL,     /* a folder of Isabel bricks */
    DATA_KIND_UNKNOWN,    /* NetCDF, a folder or binary that no reader takes: WHY says what
                             was found and what was expected */
};

/* The name of a kind ("WRF output"). */
const char *data_kind_name(enum data_kind k);

/* What PATH is.  For DATA_KIND_UNREADABLE and DATA_KIND_UNKNOWN, WHY (WHY_SIZE bytes) holds
 * the reason, starting with PATH; otherwise it is "".  Logs nothing.  Thread-safe as the
 * readers' probes are (they take the NetCDF lock). */
enum data_kind data_detect(const char *path, char *why, size_t why_size);

/* Whether KIND is data (a reader's format) rather than a config or an error. */
bool data_kind_is_data(enum data_kind k);
/* Whether KIND's files make a series of several (WRF, CM1, CF) rather than one path holding
 * it all (an extinction file, an Isabel folder). */
bool data_kind_is_series(enum data_kind k);

/* A folder that is not an Isabel folder, named as its data: the glob pattern (into PATTERN,
 * SIZE bytes, DIR's own pattern characters escaped) of WRF's history files in it
 * (DIR/wrfout_d*, every domain) when it holds any, else of its files named .nc.
 * COUNT: how many files the pattern matches; WHAT: "files of WRF output" or "NetCDF files"
 * ("file of WRF output", "NetCDF file" for one).  False when DIR holds neither (or the
 * pattern does not fit).  What the files are is for data_detect to say, file by file. */
bool data_folder_pattern(const char *dir, char *pattern, size_t size, size_t *count,
                         const char **what);

#endif
