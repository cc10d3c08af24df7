/*
 * data/probe: what the data holds at one point (docs/analysis.md, "Reading values").  The
 * values of a point (struct probe_sample) from a field volume, trilinear between voxel centres
 * (the procedural storm, Isabel bricks; WRF points come from the file's own levels,
 * wrf_read_point); the extinction at a point of an extinction volume as the eye pass samples
 * it; the first point along a ray where the extinction passes a threshold, marched on the CPU.
 * No GL, no config, no files.
 */
#ifndef ANVIL_DATA_PROBE_H
#define ANVIL_DATA_PROBE_H

#include <stdbool.h>

#include "data/volume.h"
#include "data/wrf.h"

/* Where a value came from. */
enum probe_from {
    PROBE_NONE,     /* the data has nothing for it */
    PROBE_DATA,     /* the data's own value */
    PROBE_STANDARD, /* the 1976 standard atmosphere at the point's height (the data lacks it) */
};

struct probe_sample {
    bool has_species[SPECIES_COUNT];
    double q[SPECIES_COUNT]; /* mass ratios, kg/kg */
    bool has_qvapor;
    double qvapor;           /* kg/kg */
    enum probe_from temperature_from, pressure_from;
    double temperature_k, pressure_pa;
    bool has_wind;           /* horizontal wind u (east), v (north) */
    bool wind_earth_relative; /* false: along the model grid's x and y (a rotated grid without
                                 COSALPHA, SINALPHA) */
    bool has_w;
    double u, v, w;          /* m/s */
    bool has_ground;
    double ground_m;         /* the model's ground there, m above sea level */
};

/* The sum of the species' mass ratios the sample holds, kg/kg. */
double probe_sample_condensate(const struct probe_sample *s);

/* The horizontal wind's speed (m/s) and the direction it blows from, degrees clockwise from
 * north (meteorological: 270 is a westerly); 0 for a calm. */
void probe_wind(double u, double v, double *speed, double *from_deg);

/* A WRF point as a sample (temperature from the standard atmosphere where P, PB, T were bad). */
void probe_sample_from_wrf(const struct wrf_point *p, double z, struct probe_sample *out);

/* FV's values at P (metres in FV's frame), trilinear between voxel centres and clamped to the
 * edge voxels inside the box: its species and QVAPOR, its temperature or else the standard
 * atmosphere's, the standard atmosphere's pressure (field volumes hold none), and the wind
 * where FV holds its components (u and v; w too where present).  False when
 * P lies outside the box. */
bool probe_sample_fields(const struct field_volume *fv, const double p[3],
                         struct probe_sample *out);

/* Extinction at P (metres) as the eye pass samples V: trilinear between voxel centres, clamped
 * to the edge voxels inside the box, zero outside it.  OUT[0] the ice phase's, OUT[1] the
 * water phase's, 1/m. */
void probe_sample_beta(const struct ext_volume *v, const double p[3], double out[2]);

/* The first distance T along the ray O + t D (D unit, metres) within [0, T_MAX] where V's
 * total extinction (both phases) exceeds THRESHOLD (1/m): sampled every quarter of a voxel's
 * crossing inside the box, the crossing then found to 1e-4 of a sample by bisection.  False
 * when the ray meets no such point. */
bool probe_first_visible(const struct ext_volume *v, const double o[3], const double d[3],
                         double t_max, double threshold, double *t);

#endif
