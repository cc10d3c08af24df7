/*
 * data/cm1: output of CM1, the cloud model of Bryan and Fritsch (2002), in its NetCDF form
 * (output_format = 2): coordinates xh, yh (scalar points) and xf, yf, zf (staggered points)
 * and zh (or z) for the heights, in km or m as their units attribute says; the mass ratios qc,
 * qr, qi, qs, qg (and qv) in kg/kg; prs (Pa), th (potential temperature, K) and/or rho
 * (kg/m^3); u on xf, v on yf, w on zf; time in seconds.  One file per output time or many
 * times in one file, any number of files: one series ordered by time.
 *
 * The reading itself (levels, bad values, budget) is data/hgrid's.  No GL, no config.
 */
#ifndef ANVIL_DATA_CM1_H
#define ANVIL_DATA_CM1_H

#include <stdbool.h>

#include "data/hgrid.h"

/* Whether PATH is CM1 output, from its content (xh, yh and zh or z coordinates and one of
 * CM1's fields).  Quiet: logs nothing. */
bool cm1_probe(const char *path);

/* hgrid_open for CM1 files (see data/hgrid.h). */
struct hgrid *cm1_open(const char *const *paths, int count, double memory_mb);

#endif
