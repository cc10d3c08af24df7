/*
 * data/hgrid_write: writes field volumes as CM1-convention or CF-convention NetCDF on height
 * levels (what `anvil synth --format cm1|cf` produces), so the CM1 and CF readers can be
 * tested on files whose content is known, and the same storm compared across formats.
 *
 * CM1: dimensions time, zh, yh, xh, zf, yf, xf; coordinates in km; qc, qr, qi, qs, qg (the
 * species present), qv in kg/kg; prs (Pa) and th (K) of the 1976 standard atmosphere through
 * Poisson's equation with CM1's constants; u on xf, v on yf, w on zf from wrf_synth_wind;
 * time in seconds.  CF: dimensions time, z, y, x with x, y, z (and z_bnds) coordinates, the
 * species and specific humidity by standard_name, air_temperature, air_pressure and the wind
 * components on the mass points; time in seconds since the start date.  The levels are the
 * volume's cell centres (a stretched grid's own level centres, its faces half way between
 * them), so a reader gets the mass ratios back exactly.
 *
 * No GL, no config.  NetCDF calls hold data_nc_lock.
 */
#ifndef ANVIL_DATA_HGRID_WRITE_H
#define ANVIL_DATA_HGRID_WRITE_H

#include <stdbool.h>

#include "data/hgrid.h"
#include "data/volume.h"

/* Zero means default for every member. */
struct hgrid_write_desc {
    enum hgrid_kind kind;
    const char *start;   /* CF: the date of time 0, "YYYY-MM-DD_hh:mm:ss" (default 2000-01-01) */
    bool coords_km;      /* CF: x, y, z in km (CM1 always writes km) */
    bool g_per_kg;       /* CF: mass ratios in g kg-1 */
    bool pressure_hpa;   /* CF: pressure in hPa */
    bool positive_down;  /* CF: the vertical coordinate is minus the height, positive = down */
    bool top_down;       /* CF: levels stored from the top down */
    bool latlon;         /* CF: x, y as longitude, latitude (degrees, regular) */
    bool north_first;    /* CF: y stored decreasing (rows from the north) */
    double cen_lat, cen_lon; /* CF latlon: the domain centre, degrees */
    unsigned omit;       /* CF and CM1: bit f set leaves species f out of the file */
};

struct hgrid_writer;

/* Starts writing PATH (a temporary file beside it replaces PATH only when hgrid_writer_finish
 * succeeds).  Every step must have GRID.  NULL after logging. */
struct hgrid_writer *hgrid_writer_create(const char *path, const struct grid3 *grid,
                                         const struct hgrid_write_desc *d);
/* Appends a step at SECONDS after the start.  The first step fixes which species are
 * written. */
bool hgrid_writer_add(struct hgrid_writer *w, const struct field_volume *v, double seconds);
bool hgrid_writer_finish(struct hgrid_writer *w); /* closes, moves into place, frees */
void hgrid_writer_destroy(struct hgrid_writer *w); /* abandons; NULL is fine */

#endif
