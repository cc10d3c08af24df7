/*
 * data/coast: shorelines from GSHHG (Wessel & Smith) in GMT's binned NetCDF files, as Debian's
 * gmt-gshhg-low installs them (/usr/share/gmt-gshhg/binned_GSHHS_{c,l,i}.nc).
 *
 * The files cut the shoreline polygons into pieces per bin (a square of lat/lon); each piece is
 * a polyline of points stored relative to its bin's south-west corner.  The reader returns the
 * pieces that reach into a lat/lon box as polylines in degrees: enough to draw the coast, not to
 * fill land (that needs the bins' corner levels and is not done here).
 *
 * No GL.  NetCDF calls hold data_nc_lock.
 */
#ifndef ANVIL_DATA_COAST_H
#define ANVIL_DATA_COAST_H

#include <stdbool.h>

/* Shoreline levels in GSHHG. */
enum coast_level { COAST_LAND = 1, COAST_LAKE = 2, COAST_ISLAND_IN_LAKE = 3, COAST_POND = 4 };

/* Polylines: line l has points first[l] .. first[l] + count[l] - 1 of lat/lon. */
struct coast_lines {
    int n_lines, n_points;
    int *first, *count, *level;
    double *lat, *lon; /* degrees; longitudes shifted by multiples of 360 to lie nearest the box */
};

/* The file of a resolution ('c' crude, 'l' low, 'i' intermediate): $ANVIL_GSHHG_DIR or
 * /usr/share/gmt-gshhg, then binned_GSHHS_<r>.nc.  Static storage, overwritten by the next
 * call. */
const char *coast_file(char resolution);

/* Reads the shoreline pieces of PATH with level <= MAX_LEVEL that have a point inside BOX
 * [lat_min, lat_max, lon_min, lon_max] (degrees; the longitudes may be in either -180..180 or
 * 0..360).  A line leaving the box keeps one point outside on each side, so that it can be
 * clipped at the box edge.  OUT is initialised here (finish it with coast_lines_finish).
 * False after one log_warn naming the file when it is missing or not a GSHHG file (coastlines
 * are optional: callers go on without them). */
bool coast_read(const char *path, const double box[4], int max_level, struct coast_lines *out);
void coast_lines_finish(struct coast_lines *c);

#endif
