/*
 * data/cf: NetCDF files on height levels described by the CF conventions (CF-1.8), such as
 * files other tools have already processed.  The quantities are found by their standard_name
 * (mass_fraction_of_cloud_liquid_water_in_air, ..._rain_..., ..._cloud_ice_..., ..._snow_...,
 * ..._graupel_..., air_temperature, air_potential_temperature, air_pressure, air_density,
 * eastward_wind, northward_wind, upward_air_velocity, specific_humidity), whatever the
 * variables are called; the axes by their axis attribute (X, Y, Z, T), a positive attribute
 * (the vertical) or the standard names of coordinates (projection_x_coordinate, longitude,
 * height, altitude, time).  x and y are regular, in m or km or in degrees (longitude and
 * latitude); heights in m or km, increasing or decreasing, positive up or down.  Units are
 * converted (hgrid_parse_units); an unknown unit is an error naming the variable and unit.
 *
 * The reading itself (levels, bad values, budget) is data/hgrid's.  No GL, no config.
 */
#ifndef ANVIL_DATA_CF_H
#define ANVIL_DATA_CF_H

#include <stdbool.h>

#include "data/hgrid.h"

/* The standard_name read as quantity V (NULL for none). */
const char *cf_standard_name(enum hgrid_var v);

/* Whether PATH is a CF file this reader takes, from its content: a vertical coordinate in
 * units of length and at least one variable with one of the standard names above.  Quiet. */
bool cf_probe(const char *path);

/* hgrid_open for CF files (see data/hgrid.h). */
struct hgrid *cf_open(const char *const *paths, int count, double memory_mb);

#endif
