/*
 * session/probe: reading values at a point of a scene (docs/analysis.md, "Reading values").
 * A probe holds its own handle on the scene's data — a second reader of its WRF files, or the
 * field volume of the procedural storm or of an Isabel step, made when first asked — and the
 * scene's latitude/longitude placement, and gives what a point holds: where it is, the
 * species' mass ratios, the condensate, temperature, pressure and wind.  The caller adds what
 * it holds itself, the extinction of the volume on screen and the light map's value.  The
 * values as a panel's rows, as text and as JSON.  No GL.
 */
#ifndef ANVIL_SESSION_PROBE_H
#define ANVIL_SESSION_PROBE_H

#include <stdbool.h>
#include <stdio.h>

#include "config/config.h"
#include "data/geo.h"
#include "data/probe.h"
#include "menu/readout.h"

/* How the wand or pointer picks the point. */
enum probe_mode {
    PROBE_FIRST_VISIBLE, /* the first point along the ray where the extinction passes the
                            threshold */
    PROBE_AT_DISTANCE,   /* the point a set distance along the ray */
    PROBE_MODE_COUNT
};

/* The probe's part of the session's settings (they reach a cluster's ranks with them). */
struct probe_settings {
    bool on;
    int mode;           /* enum probe_mode */
    double threshold;   /* 1/m */
    double distance_m;  /* world metres from the ray's origin */
};

/* The config's probe.* (off until the menu or the key turns it on, unless probe.on). */
void probe_settings_from_config(const struct config *cfg, struct probe_settings *out);
const char *probe_mode_name(int mode); /* "first visible", "at a distance" */

struct probe_values {
    bool valid;           /* a point was probed (else WHY says why not) */
    char why[160];
    double world[3];      /* metres, the session's frame (heights exaggerated) */
    double data[3];       /* the data's frame: x, y as world, height above sea level, m */
    bool placed;          /* lat/lon known */
    double lat, lon;
    int step;
    char date[32];        /* "2005-08-28_06:00:00", "" when the data has no dates */
    bool fields;          /* the data has values at points (not an extinction file) */
    struct probe_sample s;
    bool at_top; /* above this column's model top but inside the volume, where the
                    volume holds its top level's values: S is read there, at TOP_M */
    double top_m;
    double beta[2];       /* extinction of the volume on screen: ice, water phase, 1/m */
    bool have_light;      /* a light map was built */
    double light;         /* its beam at the point: direct and forward-scattered sunlight,
                             relative to the sun's */
    bool have_diffuse;
    double diffuse;       /* multiple scattering's diffuse light M there, relative to the sun */
};

struct probe;

/* The probe of CFG's scene: a WRF scene's files are opened again here (its own reader, used
 * from one thread).  NULL (logged) when they cannot be.  Free with probe_destroy. */
struct probe *probe_create(const struct config *cfg);
void probe_destroy(struct probe *p); /* NULL is fine */

/* The time steps the probe's data holds (1 for synthetic scenes). */
int probe_step_count(const struct probe *p);

/* The scene's placement (kind GEO_NONE when it has none). */
const struct geo_map *probe_geo(const struct probe *p);

/* The world point at LAT, LON (degrees) and HEIGHT_M above sea level at STEP (a domain that
 * moves is placed where that step has it).  False with WHY when the scene has no lat/lon or
 * the point cannot be placed. */
bool probe_world_at(struct probe *p, int step, double lat, double lon, double height_m,
                    double world[3], char *why, size_t why_size);

/* The values of STEP at WORLD (metres) into OUT (extinction and light left zero for the
 * caller): OUT->valid false with OUT->why for a point outside the data, below the ground or
 * above the model top.  False (logged) only when the data cannot be read. */
bool probe_read(struct probe *p, int step, const double world[3], struct probe_values *out);

/* The values as the panel's rows (title and rows into M). */
void probe_values_readout(const struct probe_values *v, struct readout_model *m);
/* The same as "label: value" lines; and as one JSON object (SI units with the unit in each
 * name, null for what the data lacks). */
void probe_values_write_text(const struct probe_values *v, FILE *out);
void probe_values_write_json(const struct probe_values *v, FILE *out);

#endif
