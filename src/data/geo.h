/*
 * data/geo: where the volume frame lies on the earth.  Maps latitude/longitude to the frame's
 * metres (x east, y north, ground plane) and back, so that coastlines and a graticule can be
 * drawn under the storm (Nes §5.5.1).
 *
 * For WRF data the map is the model's own XLAT/XLONG grid: mass column (i, j) is centred at
 * ((i + 0.5) DX, (j + 0.5) DY), positions between columns are bilinear in the grid, and a
 * lat/lon is placed by inverting that bilinear map (a coarse search, then Newton's method).
 * This is exact at the columns for any WRF projection and needs no projection formulas.
 * Beyond the outermost columns the edge cells are extrapolated linearly (approximate: a few
 * km of error 300 km out on a Mercator grid).  Data without XLAT/XLONG can be given an origin
 * instead: a Mercator projection true at that latitude, on WRF's sphere.
 *
 * A manual offset (Nes Fig. 5.17) moves the data on the map: every map position is shifted by
 * minus the offset, so the volume and its terrain stay where they are in the frame.
 * No GL, no files.
 */
#ifndef ANVIL_DATA_GEO_H
#define ANVIL_DATA_GEO_H

#include <stdbool.h>
#include <stddef.h>

#define GEO_EARTH_RADIUS_M 6370000.0 /* WRF's sphere */

enum geo_kind { GEO_NONE, GEO_GRID, GEO_LOCAL };

struct geo_map {
    enum geo_kind kind;
    /* GEO_GRID: the mass grid (copies, west_east fastest; longitudes unwrapped around the
     * grid's centre so that a domain across the date line is continuous) */
    int nx, ny;
    float *lat, *lon;
    double dx, dy;
    /* GEO_LOCAL: the frame origin and the Mercator scale there */
    double lat0, lon0;
    double offset[2]; /* metres the data moves east, north on the map */
};

/* A map from a WRF mass grid (NX x NY >= 2 x 2 columns, spacing DX, DY metres).  The arrays
 * are copied.  False (logged) on a bad grid (non-finite or absurd values) or no memory.
 * Finish with geo_map_finish. */
bool geo_map_init_grid(struct geo_map *m, const float *xlat, const float *xlong, int nx, int ny,
                       double dx, double dy);
/* A map with the frame origin (0, 0) at LAT0, LON0 degrees (|LAT0| < 85). */
void geo_map_init_local(struct geo_map *m, double lat0, double lon0);
void geo_map_finish(struct geo_map *m); /* zeroed and NULL-safe */

/* Lat/lon (degrees) -> frame metres.  False when the point cannot be placed (no map, or the
 * grid inverse does not converge: far outside the grid). */
bool geo_map_to_frame(const struct geo_map *m, double lat, double lon, double *x, double *y);
/* Frame metres -> lat/lon (degrees, longitude in the grid's unwrapped range). */
bool geo_map_to_latlon(const struct geo_map *m, double x, double y, double *lat, double *lon);

/* GEO_GRID: the fractional mass-grid index (i, j) where the bilinear grid equals LAT, LON
 * (column centres are integers).  False when it does not converge. */
bool geo_map_grid_index(const struct geo_map *m, double lat, double lon, double ij[2]);

/* The lat/lon box of the frame rectangle [x0, x1] x [y0, y1] (its border sampled), degrees. */
bool geo_map_box(const struct geo_map *m, const double rect[4], double box[4]);

/* "21.80 to 25.67 N, 91.65 to 87.43 W" (DIGITS decimals; "5.00 S to 3.00 N" across the
 * equator, longitudes taken into -180 .. 180) into OUT of SIZE bytes. */
void geo_format_range(char *out, size_t size, int digits, double lat_min, double lat_max,
                      double lon_min, double lon_max);

#endif
