/*
 * data/derived: scalar fields derived from what a reader gives (temperature, air density,
 * QVAPOR, the wind speed), on the field volume's grid: what a colour-mapped layer shows
 * (optics/transfer.h, enum transfer_field).  Each formula is cited where it is written.  Pure
 * numbers over arrays: no files, no GL.
 */
#ifndef ANVIL_DATA_DERIVED_H
#define ANVIL_DATA_DERIVED_H

#include <stdbool.h>

#include "data/volume.h"
#include "optics/transfer.h"

/* Pressure from air density and temperature by the ideal gas law p = rho R_d T (Wallace and
 * Hobbs 2006, eq. 3.3, dry air); Pa.  NAN for a non-positive or non-finite input. */
double derived_pressure(double rho_kg_m3, double t_k);
/* Potential temperature theta = T (p0 / p)^(R_d / c_p), p0 = 1000 hPa (Poisson's equation,
 * Wallace and Hobbs 2006, §3.4); K.  NAN for bad input. */
double derived_theta(double t_k, double p_pa);
/* Relative humidity over liquid water, per cent: 100 e / e_s with the vapour pressure
 * e = p q / (epsilon + q) from the mixing ratio q (Wallace and Hobbs 2006, §3.5, epsilon =
 * 0.622) and the saturation vapour pressure e_s = 6.112 exp(17.67 (T - 273.15) /
 * (T - 29.65)) hPa (Bolton 1980, eq. 10).  NAN for bad input. */
double derived_rh(double t_k, double p_pa, double q_kg_kg);

/* The water vapour mixing ratio, kg/kg, at height Z_M (m) where the data has none: 10 g/kg
 * falling off with a 2.5 km scale height (TRANSFER_FIELD_QVAPOR's stand-in). */
double derived_vapour_standard(double z_m);

/* Vertical vorticity zeta = dv/dx - du/dy, 1/s, on one horizontal plane of NX x NY points
 * (x fastest) spaced DX, DY metres, from U and V at the same points into OUT: centred
 * differences (v[i+1] - v[i-1]) / 2dx - (u[j+1] - u[j-1]) / 2dy inside, one-sided at the edges,
 * zero along an axis of one point.  With U and V the means of an Arakawa C grid's face winds
 * (WRF's staggered U and V), the centred form equals the mean of the four vorticities at the
 * cell's corners, where the C grid defines them (Arakawa and Lamb 1977).  With MAP (the map
 * scale factor m at the same points; NULL: m = 1), DX and DY are distances on the map, and
 * zeta = m^2 (d(v/m)/dx - d(u/m)/dy), the same differences over v/m and u/m (Haltiner and
 * Williams 1980: the vorticity on a conformal map projection). */
void derived_vorticity_plane(const float *u, const float *v, const float *map, int nx, int ny,
                             double dx, double dy, float *out);

/* Whether FV holds what FIELD is computed from (else derived_field uses the stand-ins below). */
bool derived_field_available(const struct field_volume *fv, enum transfer_field field);

/* FIELD on FV's grid into OUT (grid3_count values, the caller's).  What FV lacks is replaced:
 * QVAPOR by 10 g/kg at the ground falling with a 2.5 km scale height, temperature and pressure
 * by the 1976 standard atmosphere at the voxel centre's height, the wind by zero.  The vertical
 * vorticity is FV's own (the reader's, on its model levels) where it has one, else
 * derived_vorticity_plane over FV's u and v on each level of the grid. */
void derived_field(const struct field_volume *fv, enum transfer_field field, float *out);

#endif
