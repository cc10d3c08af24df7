/*
 * data/wrf_write: writes field volumes as a WRF-convention NetCDF file (what `anvil synth`
 * produces), so realistic-size series exist without downloads and the WRF reader can be
 * tested on them.
 *
 * The file has WRF's dimensions (Time, DateStrLen, west_east, south_north, bottom_top,
 * bottom_top_stag, west_east_stag, south_north_stag), variables (QCLOUD ... QGRAUP for the
 * species present, QVAPOR, P, PB, T, PH, PHB, U, V, W, HGT, LANDMASK, XLAT, XLONG, Times) with
 * FieldType/MemoryOrder/description/units/stagger attributes, and the global attributes a WRF
 * reader looks for (DX, DY, MAP_PROJ = 3 Mercator, CEN_LAT, CEN_LON, TRUELAT1/2, STAND_LON,
 * MP_PHYSICS, *_GRID_DIMENSION).
 *
 * Vertical levels: the staggered levels are the volume's cell faces, origin_z + k dz, with
 * PHB = g z and PH = 0, so the mass levels sit exactly on the cell centres and reading the file
 * back with wrf_read_step (levels = nz, bottom = origin_z, top = automatic) returns the mass
 * ratios unchanged.  A stretched grid (data/volume.h) gives the model's own uneven levels: the
 * faces from origin_z up, each level's centre half way between its faces (so the faces are
 * f[k + 1] = 2 z_centre[k] - f[k]; a grid whose centres are the midpoints of the faces wanted
 * reads back with native_levels and top = automatic as it was written).  Pressure and temperature are the 1976 US standard atmosphere (PB = p(z),
 * P = 0); where the volume has rho_air, T is chosen so that P, PB, T give that density.
 * QVAPOR is the volume's or, when absent, 10 g/kg falling off with a 2.5 km scale height.
 * U, V and W are wrf_synth_wind on WRF's staggered points (U on the west/east cell faces, V on
 * the south/north faces, W on the staggered levels).
 *
 * No GL, no config.  NetCDF calls hold data_nc_lock.
 */
#ifndef ANVIL_DATA_WRF_WRITE_H
#define ANVIL_DATA_WRF_WRITE_H

#include <stdbool.h>

#include "data/volume.h"

/* Zero means default for every member. */
struct wrf_write_desc {
    double cen_lat, cen_lon; /* domain centre, degrees (default 0, 0: pass the real one) */
    int mp_physics;          /* MP_PHYSICS; 0 = 8 (Thompson) when an ice species is present,
                                else 3 (WSM3) */
    const char *title;       /* TITLE; default "OUTPUT FROM ANVIL SYNTH" */
    /* A domain of a nested run (data/nest.h): grid_id > 0 writes GRID_ID and, unless
     * latlon_only, PARENT_ID, I_PARENT_START, J_PARENT_START (1-based parent columns) and
     * PARENT_GRID_RATIO as given; XLAT/XLONG then place the grid's west and south edge
     * map_corner_m metres east and north of the map centre (cen_lat, cen_lon), so that a
     * parent and its nests share one map.  grid_id 0: none of these, the grid centred on the
     * map centre. */
    int grid_id, parent_id, i_parent_start, j_parent_start, parent_grid_ratio;
    bool latlon_only;
    double map_corner_m[2];
};

struct wrf_writer;

/* Starts writing PATH (a temporary file in the same folder replaces PATH only when
 * wrf_writer_finish succeeds).  Every step must have GRID.  Returns NULL after logging. */
struct wrf_writer *wrf_writer_create(const char *path, const struct grid3 *grid,
                                     const struct wrf_write_desc *d);

/* Appends one time step.  DATE is "YYYY-MM-DD_hh:mm:ss".  The first step fixes which species
 * the file has; later steps must have the same ones. */
bool wrf_writer_add(struct wrf_writer *w, const struct field_volume *v, const char *date);

/* Closes, moves the file into place and frees W.  False (logged) when anything failed. */
bool wrf_writer_finish(struct wrf_writer *w);

/* Abandons the file and frees W; NULL is fine. */
void wrf_writer_destroy(struct wrf_writer *w);

/* 1976 US standard atmosphere temperature [K] and pressure [Pa] at geometric height Z [m]
 * (troposphere and stratosphere; clamped to 0-47 km). */
void wrf_std_atmosphere(double z, double *temperature, double *pressure);

/* The synthetic wind written as U, V, W, m/s, at X, Y metres from GRID's west/south edge and
 * height Z (m above sea level): a westerly 5 m/s plus a Rankine vortex around the domain's
 * centre (30 m/s at a radius of 15 % of the shorter side, fading to zero at 15 km), and an
 * updraft of up to 2 m/s in its core, zero at the bottom and top of the grid. */
void wrf_synth_wind(const struct grid3 *grid, double x, double y, double z, double *u,
                    double *v, double *wz);

#endif
