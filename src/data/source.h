/*
 * data/source: one interface over the on-disk formats (WRF NetCDF, Isabel bricks, extinction
 * files, CM1 NetCDF, CF NetCDF on height levels) that yields a time step as an extinction volume, with the time spent
 * reading and converting.  The time series cache (data/series.h) and the commands load steps
 * through it.  No GL, no config: the caller fills struct data_source_desc (app/cmd_data.h has
 * the mapping from struct config).
 */
#ifndef ANVIL_DATA_SOURCE_H
#define ANVIL_DATA_SOURCE_H

#include <stdbool.h>

#include "data/detail.h"
#include "data/hgrid.h"
#include "data/isabel.h"
#include "data/volume.h"
#include "data/wrf.h"

enum data_source_format {
    DATA_SOURCE_WRF,
    DATA_SOURCE_ISABEL,
    DATA_SOURCE_EXTINCTION,
    DATA_SOURCE_CM1, /* data/cm1.h */
    DATA_SOURCE_CF,  /* data/cf.h */
};

struct data_source_desc {
    enum data_source_format format;
    const char *const *files; /* WRF, CM1, CF: files or glob patterns; Isabel: the folder
                                 (files[0]); extinction: one file (files[0]) */
    int file_count;
    struct wrf_desc wrf;          /* WRF reading (call wrf_desc_defaults); its memory_mb is
                                     every format's budget */
    struct isabel_desc isabel;    /* Isabel sizes (dir is taken from files[0]) */
    struct optics_params optics;  /* mass ratio -> extinction (all but extinction files) */
    struct species_select select; /* per-species toggles and scales (the same) */
    struct detail_desc detail;    /* procedural detail (zero: off) */
    double height_scale;          /* height exaggeration (ext_volume_stretch_height); 0 = 1 */
    bool wind_components;         /* CM1, CF, Isabel: where the wind is read, also keep its
                                     components (field_volume u, v, w: the probe's direction);
                                     WRF's probe reads its points itself (wrf_read_point) */
    bool pressure;                /* CM1, CF: keep the file's air pressure (field_volume
                                     pressure: the probe's) */
};

struct data_source;

/* Opens the files D names (D's pointers must stay valid until data_source_close).  NULL
 * after one log_error. */
struct data_source *data_source_open(const struct data_source_desc *d);
void data_source_close(struct data_source *s); /* NULL is fine */

int data_source_step_count(const struct data_source *s);
const char *data_source_step_date(const struct data_source *s, int step); /* "" if unknown */

/* The grid a step loads onto (data_source_load), the height scale applied, without reading a
 * step.  False (logged) when the description selects nothing. */
bool data_source_grid(const struct data_source *s, struct grid3 *out);

/* Whether STEP can be read straight to extinction (data_source_load_ext): WRF without nests. */
bool data_source_can_load_ext(const struct data_source *s);

/* Reads STEP straight to extinction with OPTICS and SEL (wrf_read_step_ext: the numbers
 * ext_volume_from_fields makes of data_source_load_fields, without the fields), no detail, no
 * height scale; OUT is initialised here (the caller finishes it).  VAPOUR (NULL: none, and
 * QVAPOR is not read), initialised over its range, counts the water vapour as the histogram
 * of the fields' would (wrf_read_step_ext).  Only where data_source_can_load_ext. */
bool data_source_load_ext(struct data_source *s, int step, const struct optics_params *optics,
                          const struct species_select *sel, struct transfer_histogram *vapour,
                          struct ext_volume *out);

/* Loads STEP as extinction into OUT, with the description's detail and height scale applied
 * (initialised here; the caller finishes it).  LOAD_MS and CONVERT_MS (may be NULL) receive
 * the milliseconds spent reading and converting; WRF files without nests or detail are read
 * straight to extinction (wrf_read_step_ext), and LOAD_MS then covers both.  Not to be called
 * from two threads at once on one source. */
bool data_source_load(struct data_source *s, int step, struct ext_volume *out, double *load_ms,
                      double *convert_ms);

/* Loads STEP's mass ratios (false and logged for extinction files). */
bool data_source_load_fields(struct data_source *s, int step, struct field_volume *out);
/* The same, also with the absolute temperature and wind speed when asked and the files hold
 * what they come from (WRF: P, PB, T, U, V, W; CM1: th and prs, u, v, w; CF: air_temperature,
 * the wind components; Isabel: TC, U, V, W); else those stay NULL.  Safe to call with the
 * flags changing from call to call. */
bool data_source_load_fields_extra(struct data_source *s, int step, bool temperature, bool wind,
                                   struct field_volume *out);

/* The fields beyond the mass ratios (and air density) a load reads: each only when asked
 * (WRF; other formats leave them NULL). */
struct data_fields_want {
    bool qvapor, temperature, wind;
    bool wind_components; /* u, v, w and (WRF) the vertical vorticity, where the data has the
                             wind (implies wind; every format) */
    bool level_heights;   /* WRF: each column's mass-level heights (field_volume level_z) */
};
/* As data_source_load_fields_extra, QVAPOR read only when WANT asks (or the description's
 * wrf.qvapor does). */
bool data_source_load_fields_want(struct data_source *s, int step,
                                  const struct data_fields_want *want, struct field_volume *out);

/* Whether PATH begins as a NetCDF file does (classic, 64-bit offset, CDF-5 or HDF5), read
 * from its first bytes: a data file rather than a config.  False for a file that cannot be
 * read. */
bool data_file_is_netcdf(const char *path);

/* The WRF reader behind S, or NULL for other formats (for metadata: lat/lon, terrain). */
struct wrf *data_source_wrf(struct data_source *s);
/* The WRF domains behind S when its files are a parent and its nests (data/nest.h; then
 * data_source_wrf is the outermost domain's reader and a step is their composite), else NULL. */
struct nest_set;
struct nest_set *data_source_nests(struct data_source *s);
/* WRF: what the files hold at P for STEP (wrf_read_point with the description's selection; with
 * nests, the finest domain there, nest_read_point).  WRF_POINT_ERROR (logged) for other
 * formats. */
enum wrf_point_result data_source_read_point(struct data_source *s, int step, const double p[3],
                                             struct wrf_point *out);
/* The CM1 or CF reader behind S, or NULL for other formats. */
struct hgrid *data_source_hgrid(struct data_source *s);

struct geo_map;
/* Where S's grid lies on the earth when the data say it without a map block: WRF's XLAT and
 * XLONG, Isabel's published box, a CF file on longitude and latitude.  False (OUT zeroed) when
 * they do not. */
bool data_source_geo(struct data_source *s, struct geo_map *out);

#endif
