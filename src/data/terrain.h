/*
 * data/terrain: the ground under the storm as a height field in the volume frame, with a
 * surface kind per vertex (sea, land and its land use) for colouring.  Built from WRF's HGT,
 * LANDMASK and LU_INDEX; the renderer turns it into a mesh (render/terrain.h).
 *
 * Vertices sit on the model's mass columns, at ((i + 0.5) DX, (j + 0.5) DY) like the volume's
 * columns, for every column whose centre lies inside the volume's box; one more row and column
 * on each side put the border exactly on the box's faces (with the nearest column's values), so
 * the terrain covers the box.  Heights are metres above sea level, not exaggerated.
 * No GL, no files.
 */
#ifndef ANVIL_DATA_TERRAIN_H
#define ANVIL_DATA_TERRAIN_H

#include <stdbool.h>

#include "data/volume.h"
#include "data/wrf.h"

enum terrain_kind {
    TERRAIN_SEA,   /* water (LANDMASK 0, or a water land-use category) */
    TERRAIN_LAND,  /* land of unknown use */
    TERRAIN_CROP,
    TERRAIN_GRASS,
    TERRAIN_SHRUB,
    TERRAIN_FOREST,
    TERRAIN_WETLAND,
    TERRAIN_BARREN,
    TERRAIN_TUNDRA,
    TERRAIN_ICE,
    TERRAIN_URBAN,
    TERRAIN_KIND_COUNT
};

struct terrain {
    int nx, ny;           /* vertices */
    double *x, *y;        /* vertex positions along each axis, metres, increasing */
    float *height;        /* nx * ny, x fastest, metres above sea level */
    unsigned char *kind;  /* nx * ny, enum terrain_kind */
    bool has_landmask;    /* where sea/land came from: LANDMASK ... */
    bool has_land_use;    /* ... LU_INDEX ... */
                          /* ... or neither: HGT > 0.5 m is land (an approximation) */
};

/* The terrain of META's grid under the volume box BOX.  False with a log_warn (not an error:
 * the caller falls back to the flat ground) when META has no HGT or BOX covers no column. */
bool terrain_from_wrf(const struct wrf_meta *meta, const struct grid3 *box, struct terrain *out);
void terrain_finish(struct terrain *t); /* zeroed and NULL-safe */

/* The land-use category CATEGORY of the scheme named SCHEME (MMINLU: "USGS" 24/28 classes,
 * any name with "MODIS" the 20/21 IGBP classes) as a terrain kind. */
enum terrain_kind terrain_kind_of_land_use(const char *scheme, int category);

/* Linear RGB albedo of a surface of KIND at HEIGHT metres: the kind's colour, blended toward
 * bare rock above 2000 m and snow above 5000 m (height bands). */
void terrain_albedo(enum terrain_kind kind, double height_m, float rgb[3]);

/* Height (metres, bilinear) at frame position X, Y; the border value outside. */
double terrain_height_at(const struct terrain *t, double x, double y);

#endif
