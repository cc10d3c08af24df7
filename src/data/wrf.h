/*
 * data/wrf: reads WRF model output (NetCDF) into field volumes on a regular height grid.
 *
 * One file with many times or many files (a list or glob patterns) are one time series,
 * ordered by their Times strings.  A step is read into a struct field_volume: the mass ratios
 * of the five hydrometeor species (a species the microphysics scheme did not write stays
 * NULL and reads as zero), optionally QVAPOR, absolute temperature and wind speed, and air
 * density from P, PB and T.  The model's
 * terrain-following mass levels are resampled per column onto regular heights above sea level
 * (docs/data.md says exactly how).  Bad values (NaN, Inf, negative mass ratios, NetCDF's
 * default fill, _FillValue / missing_value) become zero, are counted in struct wrf_stats and
 * reported with log_warn.
 *
 * Knows nothing of the config file (the caller fills struct wrf_desc), optics beyond air
 * density, or the GPU.  NetCDF calls are serialised through data_nc_lock (data/nclock.h), so a
 * reader may be used from a background thread; one struct wrf must not be used by two threads
 * at once.
 */
#ifndef ANVIL_DATA_WRF_H
#define ANVIL_DATA_WRF_H

#include <stdbool.h>
#include <stddef.h>

#include "data/volume.h"

#define WRF_DATE_LEN 19 /* "2005-08-28_12:00:00" */
#define WRF_G 9.81      /* gravity WRF uses to turn geopotential into height, m/s^2 */
#define WRF_T0 300.0    /* base potential temperature: theta = T + WRF_T0, K */

/* How to read a step.  Zero means default for every member except crop (wrf_desc_defaults
 * fills -1 there); call wrf_desc_defaults first and change what you need. */
struct wrf_desc {
    int levels;       /* regular height levels; 0 = as many as the file's mass levels */
    bool native_levels; /* instead of regular levels, the model's own (a stretched grid,
                           data/volume.h): the mass levels of the first step's mean column
                           between bottom_m and top_m, each column resampled onto their
                           heights; LEVELS is then unused, crop and stride along z select from
                           them */
    const struct grid3 *native_from; /* with native_levels: read onto this stretched grid's
                                        levels (and box) instead of this file's own (nests
                                        on their outermost domain's); borrowed, NULL = own */
    double top_m;     /* top of the height grid above sea level, m; 0 = the highest model top
                         (staggered top level) over all columns of the first time step, so
                         that every step of the series has the same grid */
    double bottom_m;  /* bottom of the height grid, m (default 0 = sea level) */
    int stride[3];    /* keep every stride-th column along x, y and every stride-th output
                         level along z; 0 or 1 = all */
    int crop[6];      /* [x0, x1, y0, y1, z0, z1]: index ranges kept, inclusive, x/y in the
                         file's mass columns, z in the output levels; -1 = from the start / to
                         the end.  Applied before stride. */
    double memory_mb; /* refuse a step whose arrays need more than this; 0 = no limit */
    bool qvapor;      /* also read QVAPOR (optional in the file) */
    bool temperature; /* also compute the absolute air temperature from P, PB and T */
    bool wind;        /* also compute the wind speed from U, V (and W when present), averaged
                         from their staggered points to the mass points; left NULL with one
                         log_warn when the file has no U or V */
    bool wind_components; /* also keep the wind's grid-relative components u, v, w at the mass
                             points and the vertical vorticity (field_volume u, v, w and
                             vorticity; implies wind) */
    bool level_heights; /* also keep each column's mass-level heights (field_volume level_z) */
    bool no_density;  /* leave rho_air NULL (standard atmosphere) instead of reading P/PB/T */
    int slab_rows;    /* rows of columns read, checked and resampled at a time; 0 = about 4096
                         columns.  The values read do not depend on it. */
};

void wrf_desc_defaults(struct wrf_desc *d);

/* The variables the reader touches, for statistics. */
enum wrf_var {
    WRF_QCLOUD, /* the first SPECIES_COUNT follow enum species */
    WRF_QRAIN,
    WRF_QICE,
    WRF_QSNOW,
    WRF_QGRAUP,
    WRF_QVAPOR,
    WRF_P,
    WRF_PB,
    WRF_T,
    WRF_PH,
    WRF_PHB,
    WRF_U, /* west_east_stag */
    WRF_V, /* south_north_stag */
    WRF_W, /* bottom_top_stag */
    WRF_VAR_COUNT
};

const char *wrf_var_name(enum wrf_var v);

/* Bad-value counts and the range of the good values of one variable in one step. */
struct wrf_var_stats {
    bool read;       /* the variable was read for this step */
    size_t count;    /* values read */
    size_t nan, inf; /* not finite */
    size_t fill;     /* NetCDF default fill, _FillValue or missing_value */
    size_t negative; /* mass ratios only: below zero */
    size_t absurd;   /* mass ratios only: above 1 kg/kg (and not a fill value) */
    double min, max; /* of the good values; 0 when there are none */
};

struct wrf_stats {
    struct wrf_var_stats var[WRF_VAR_COUNT];
    size_t below_terrain; /* output voxels below the model's ground (set to zero) */
    size_t above_top;     /* output voxels above the model top (set to zero) */
};

/* Bad values of one variable (nan + inf + fill + negative + absurd). */
size_t wrf_var_stats_bad(const struct wrf_var_stats *s);

/* What does not change from step to step.  Arrays are nx * ny, west_east fastest, taken from
 * the first time of the first file in time order. */
struct wrf_meta {
    int nx, ny, nz; /* mass grid: west_east, south_north, bottom_top */
    double dx, dy;  /* global DX, DY, m */
    int map_proj;   /* MAP_PROJ: 1 Lambert, 2 polar, 3 Mercator, 6 lat-lon; 0 unknown */
    int mp_physics; /* MP_PHYSICS; -1 unknown */
    double cen_lat, cen_lon, truelat1, truelat2, stand_lon; /* NAN when absent */
    bool has_species[SPECIES_COUNT];
    bool has_qvapor;
    bool has_wind; /* U and V with WRF's staggered shapes (W optional: has_w) */
    bool has_w;
    float *xlat, *xlong;                       /* degrees north / east; NULL when absent */
    float *hgt;                                /* terrain height, m; NULL when absent */
    float *landmask;                           /* 1 land, 0 water; NULL when absent */
    float *lu_index;                           /* land use category; NULL when absent */
    float *mapfac_m; /* MAPFAC_M, the map scale factor at the mass points; NULL when absent or
                        unusable (the vorticity is then on the map's grid) */
    char land_use[32];                         /* MMINLU: the categories ("USGS", "MODIS...") */
    double lat_min, lat_max, lon_min, lon_max; /* NAN when XLAT/XLONG are absent */
};

struct wrf;

/* Opens COUNT paths (each a file or a glob pattern; patterns expand in sorted order), checks
 * that they agree on the grid and the variables the reader needs, and orders all their time
 * steps by Times.  What opening allocates (the 2-D metadata, the model top's scratch, the
 * dates) must fit MEMORY_MB (as wrf_desc.memory_mb: 0 = no limit), judged from the
 * dimensions before anything is read.  Returns NULL after one log_error naming the file and
 * what is wrong.  The paths are copied.  Free with wrf_close. */
struct wrf *wrf_open(const char *const *paths, int count, double memory_mb);
void wrf_close(struct wrf *w); /* NULL is fine */

/* Valid until wrf_close. */
const struct wrf_meta *wrf_get_meta(const struct wrf *w);
/* Whether the domain moves: a moving nest, whose XLAT/XLONG at the last step differ from the
 * first's (by more than 1e-4 degrees). */
bool wrf_moves(const struct wrf *w);
/* STEP's metadata: for a domain that moves, the 2-D fields (XLAT, XLONG, HGT, LANDMASK,
 * LU_INDEX, MAPFAC_M) and the lat/lon range of that step, the rest as wrf_get_meta's; else (or
 * where the steps' fields did not fit opening's budget) wrf_get_meta's.  Valid until
 * wrf_close. */
const struct wrf_meta *wrf_step_meta(const struct wrf *w, int step);
int wrf_step_count(const struct wrf *w);
/* "YYYY-MM-DD_hh:mm:ss" as the file wrote it ("" when the file has no Times); valid until
 * wrf_close. */
const char *wrf_step_date(const struct wrf *w, int step);
/* The file a step comes from; valid until wrf_close. */
const char *wrf_step_path(const struct wrf *w, int step);

/* Bytes of the arrays a step read with D will allocate in OUT plus the reader's scratch
 * (what memory_mb is compared with; SIZE_MAX when that does not fit a size_t).  Returns 0 and
 * logs when D selects nothing. */
size_t wrf_step_bytes(const struct wrf *w, const struct wrf_desc *d);

/* The grid wrf_read_step puts a step read with D on, without reading a step (a camera framing
 * the data needs only this).  False (logged) when D selects nothing. */
bool wrf_grid(const struct wrf *w, const struct wrf_desc *d, struct grid3 *out);

/* Whether PATH is WRF output: a NetCDF file with the dimensions west_east, south_north,
 * bottom_top and bottom_top_stag and the variables PH and PHB.  Logs nothing. */
bool wrf_probe(const char *path);

/* Reads STEP into OUT (initialised here; the caller frees it with field_volume_finish).  STATS
 * (may be NULL) receives the bad-value counts; each bad count is also reported with one
 * log_warn per variable.  On failure OUT is zeroed, one log_error names the file and variable,
 * and false is returned.  The step is read a slab at a time by a thread per CPU, each taking
 * data_nc_lock for its reads: the caller must not hold that lock. */
bool wrf_read_step(struct wrf *w, int step, const struct wrf_desc *d, struct field_volume *out,
                   struct wrf_stats *stats);

/* Reads STEP straight to extinction: what wrf_read_step(D) followed by
 * ext_volume_from_fields(OPTICS, SEL) makes, the same numbers, without holding the step's
 * fields (each slab of columns is read, checked, resampled and turned into extinction before
 * the next).  Reads only the species that add extinction, and P, PB and T unless
 * D->no_density: D's qvapor, temperature, wind and level heights are not read.  VAPOUR (NULL:
 * none), initialised by the caller over its range, counts the water vapour on the output grid
 * as derived_field makes it of the fields (TRANSFER_FIELD_QVAPOR: the file's QVAPOR, read,
 * checked and resampled slab by slab like the species, else the stand-in profile).  OUT is
 * initialised here (the caller frees it with ext_volume_finish); STATS and failures as
 * wrf_read_step. */
bool wrf_read_step_ext(struct wrf *w, int step, const struct wrf_desc *d,
                       const struct optics_params *optics, const struct species_select *sel,
                       struct transfer_histogram *vapour, struct ext_volume *out,
                       struct wrf_stats *stats);

/* What wrf_read_step(D) would check of STEP, without resampling or keeping anything (anvil
 * info): every value of the variables it reads is checked, the heights too, and STATS gets
 * the same counts and ranges (but below_terrain and above_top stay 0), with the same warnings
 * and errors.  The budget D->memory_mb is wrf_read_step's, so a step the scan passes is one
 * that can be read.  False (logged) on failure. */
bool wrf_scan_step(struct wrf *w, int step, const struct wrf_desc *d, struct wrf_stats *stats);

/* The yardstick of the load path (anvil bench --load-only): reads the variables
 * wrf_read_step(D) would read for STEP (the species the file has, QVAPOR when D asks, PH, PHB,
 * P, PB, T, and U, V, W for the wind) over D's selection with one nc_get_vara / nc_get_vars
 * each into memory, keeps them all until the last is read, and frees them: no checks, no
 * resampling.  *BYTES (may be NULL) receives the bytes read.  False (logged) on a read error
 * or out of memory. */
bool wrf_read_plain(struct wrf *w, int step, const struct wrf_desc *d, double *bytes);

/* What the file holds at one point of a step (the probe, docs/analysis.md). */
struct wrf_point {
    bool has_species[SPECIES_COUNT];
    double q[SPECIES_COUNT];  /* mass ratios, kg/kg (0 for a species the file lacks) */
    bool has_qvapor;
    double qvapor;            /* kg/kg */
    double pressure_pa;       /* P + PB */
    double theta_k;           /* T + WRF_T0 */
    double temperature_k;     /* theta (p / p0)^(R_d / c_p), or NAN where P, PB or T are bad */
    bool has_wind;            /* U and V in the file */
    bool has_w;
    double u, v, w;           /* m/s: U and V averaged over their two faces to the mass points,
                                 W over its two levels; U, V earth-relative when
                                 earth_relative (else along the grid's x and y) */
    bool earth_relative;      /* COSALPHA and SINALPHA turned U, V east and north, or the
                                 projection (Mercator, lat-lon) needs no turn */
    double ground_m, top_m;   /* the model's ground (lowest staggered level) and top there */
};

enum wrf_point_result {
    WRF_POINT_OK,
    WRF_POINT_OUTSIDE, /* X, Y beyond the volume's box */
    WRF_POINT_BELOW,   /* below the model's ground there (out->ground_m says where it is) */
    WRF_POINT_ABOVE,   /* above the model top there (out->top_m) */
    WRF_POINT_ERROR,   /* the file could not be read (logged) */
};

/* STEP's values at P as the field volume wrf_read_step(D) makes holds them there: P is X, Y
 * metres in the data frame (mass column (i, j) centred at ((i + 0.5) DX, (j + 0.5) DY)) and Z
 * metres above sea level; the values are trilinear between that volume's voxel centres,
 * clamped to its edge voxels (as the eye pass samples the extinction made from it), each
 * voxel's value resampled from the model's levels as wrf_read_step does it
 * (wrf_resample_column).  Only the 2 x 2 columns around P are read, with the selection's
 * stride: cheap enough for every frame the probe moves.  A point below the model's ground or
 * above its top there (bilinear across the columns) is refused (out->ground_m, out->top_m say
 * where they are), and so is one outside the volume's box.  Bad values are replaced as
 * wrf_read_step replaces them, without a warning; pressure is resampled like the rest. */
enum wrf_point_result wrf_read_point(struct wrf *w, int step, const struct wrf_desc *d,
                                     const double p[3], struct wrf_point *out);

/* Resamples one column given on NZ mass levels at heights Z (increasing) with values V onto
 * N output levels centred at z0 + (k + 0.5) dz: linear in height between the two enclosing
 * levels; from the ground Z_GROUND up to the first level the first level's value (clamp); from
 * the last level up to the model top Z_TOP the last level's value; below the ground and above
 * the top OUTSIDE.  A target within 1e-4 dz of a level takes that level's value exactly.
 * Returns the number of outputs set to OUTSIDE (below ground in *BELOW, may be NULL). */
int wrf_resample_column(const double *z, const float *v, int nz, double z_ground, double z_top,
                        double z0, double dz, int n, float outside, float *out, int *below);

#endif
