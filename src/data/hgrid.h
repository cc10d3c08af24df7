/*
 * data/hgrid: NetCDF output on height levels over a regular horizontal grid, the common part of
 * the CM1 reader (data/cm1.h) and the generic CF reader (data/cf.h).  Each front end says which
 * variable of a file is which quantity, in which units and on which (staggered) dimensions;
 * this part orders the time steps of one or many files, checks that the files agree, and reads
 * a step into a struct field_volume on the regular height grid WRF steps are read onto:
 * mass ratios in kg/kg, absolute temperature, wind speed and air density, on the file's own
 * levels where they are uneven and the caller asks for them (copied, no column resampled:
 * the levels are the same in every column), else each column resampled from the file's
 * levels onto even ones as wrf_resample_column does it.
 *
 * Every file is opened through data_nc_open (the header checked before netcdf-c reads it), a
 * step is refused when its arrays exceed the memory budget, and grids outside the plausible
 * ranges of data/volume.h are refused as damage.  NetCDF calls hold data_nc_lock; one struct
 * hgrid must not be used by two threads at once.  No GL, no config.
 */
#ifndef ANVIL_DATA_HGRID_H
#define ANVIL_DATA_HGRID_H

#include <stdbool.h>
#include <stddef.h>

#include "data/volume.h"
#include "data/wrf.h"

enum hgrid_kind { HGRID_CM1, HGRID_CF };

/* The quantities a file may hold.  The first SPECIES_COUNT follow enum species. */
enum hgrid_var {
    HGRID_CLOUD,
    HGRID_RAIN,
    HGRID_ICE,
    HGRID_SNOW,
    HGRID_GRAUPEL,
    HGRID_VAPOR,
    HGRID_TEMPERATURE, /* absolute air temperature */
    HGRID_THETA,       /* potential temperature */
    HGRID_PRESSURE,
    HGRID_DENSITY,
    HGRID_U, /* eastward wind */
    HGRID_V, /* northward wind */
    HGRID_W, /* upward wind */
    HGRID_VAR_COUNT
};

/* What a front end found for one quantity of one file. */
struct hgrid_field {
    int varid;            /* -1: the file does not hold it */
    char name[257];       /* the variable's name in the file (NC_MAX_NAME + 1) */
    double scale, offset; /* value in SI = raw * scale + offset */
    int stagger;          /* -1 on the mass points; 0, 1, 2: one more point along x, y, z */
};

/* What does not change from step to step (from the first file in time order). */
struct hgrid_meta {
    enum hgrid_kind kind;
    int nx, ny, nz;    /* mass points along x, y and the file's levels */
    double dx, dy;     /* m */
    double x0, y0;     /* the file's coordinate of the westmost (southmost) mass point, m
                          (lat/lon: 0) */
    double bottom_m, top_m; /* the lowest and highest cell face of the levels */
    double *z;              /* the nz mass-level heights, increasing, m */
    bool stretched;         /* the levels are not evenly spaced */
    bool reversed;          /* the file stores them from the top down */
    bool flip[2];           /* the file stores x (y) decreasing: from the east (north) */
    bool latlon;            /* x, y were longitude, latitude (degrees, regular) */
    double lon0, lat0, dlon, dlat; /* latlon: the south-west mass point and the spacing,
                                      degrees */
    struct hgrid_field field[HGRID_VAR_COUNT];
    char axis_names[3][257]; /* the coordinate variables of x, y, z (NC_MAX_NAME + 1) */
    char x_units[64], z_units[64];
};

/* Names of the quantities ("cloud", ..., "temperature", "theta", "pressure", ...). */
const char *hgrid_var_label(enum hgrid_var v);

/* Parses a units string for quantity V into SI (raw * *SCALE + *OFFSET).  False when UNITS is
 * not a unit of that quantity ("furlongs" for a mass ratio).  Accepted: mass ratios kg kg-1,
 * kg/kg, 1, empty, g kg-1, g/kg; temperatures K, degC, Celsius; pressure Pa, hPa, mbar, kPa;
 * density kg m-3; wind m s-1, m/s. */
bool hgrid_parse_units(enum hgrid_var v, const char *units, double *scale, double *offset);
/* The same for a length (m, km, metres, ...). */
bool hgrid_parse_length(const char *units, double *scale);

/* What a front end must provide: given an open file, fill FIELD (all of HGRID_VAR_COUNT,
 * varid -1 for absent ones), the x, y, z and time coordinate variables (-1 for no time
 * variable) and their dimension ids; TIMEDIM -1 when the data have no time dimension.  Returns
 * false after one log_error naming PATH. */
struct hgrid_layout {
    struct hgrid_field field[HGRID_VAR_COUNT];
    int axis_var[3], axis_dim[3];
    int stag_dim[3]; /* the staggered dimension of each axis, -1 when none */
    int face_var[3]; /* a variable of the cell faces along each axis (CM1 zf), -1 when none */
    int bounds_var[3]; /* CF bounds (n x 2), -1 when none */
    int time_var, time_dim;
    double z_sign; /* 1, or -1 for a vertical axis with positive = "down" */
    bool latlon;   /* x and y are longitude and latitude in degrees */
};
typedef bool (*hgrid_identify_fn)(int ncid, const char *path, struct hgrid_layout *out);

/* Takes variable VARID of the open file as quantity V into L->field[V]: it must be float or
 * double on (time, z, y, x) or (z, y, x) with L's dimensions, the dimension of axis STAGGER
 * (-1: none) replaced by that axis's staggered one, and its units attribute one of V's
 * (hgrid_parse_units; a missing attribute is SI when UNITS_OPTIONAL).  False after one
 * log_error naming PATH, the variable and what was expected. */
bool hgrid_take_field(int ncid, const char *path, int varid, enum hgrid_var v, int stagger,
                      bool units_optional, struct hgrid_layout *l);

struct hgrid;

/* Opens COUNT paths (files or glob patterns, expanded in sorted order) of kind KIND, with
 * IDENTIFY naming the variables of each.  What opening allocates must fit MEMORY_MB (0: no
 * limit).  NULL after one log_error.  The paths are copied; free with hgrid_close. */
struct hgrid *hgrid_open(enum hgrid_kind kind, hgrid_identify_fn identify,
                         const char *const *paths, int count, double memory_mb);
void hgrid_close(struct hgrid *h); /* NULL is fine */

const struct hgrid_meta *hgrid_get_meta(const struct hgrid *h);
int hgrid_step_count(const struct hgrid *h);
/* "YYYY-MM-DD_hh:mm:ss" when the time units name a date, else ""; valid until hgrid_close. */
const char *hgrid_step_date(const struct hgrid *h, int step);
/* Seconds since the first step for dated series ("since" a date: CF), since the model's start
 * otherwise (CM1's time), the step's index without a time variable. */
double hgrid_step_seconds(const struct hgrid *h, int step);
const char *hgrid_step_path(const struct hgrid *h, int step);

struct hgrid_desc {
    double memory_mb; /* refuse a step whose arrays need more; 0 = no limit */
    bool qvapor, temperature, wind;
    bool wind_components; /* with WIND: also keep u, v and w (field_volume u, v, w) */
    bool pressure;        /* keep the air pressure (field_volume pressure) where the file has it */
    bool no_density;
    bool native_levels; /* uneven levels stay the file's own (hgrid_grid) */
};

struct hgrid_stats {
    struct wrf_var_stats var[HGRID_VAR_COUNT];
};

/* Bytes a step read with D allocates (outputs and scratch). */
size_t hgrid_step_bytes(const struct hgrid *h, const struct hgrid_desc *d);

/* The grid hgrid_read_step puts every step on, from the files' coordinates (no step read):
 * nx x ny columns of dx x dy from (0, 0), nz levels from the lowest to the highest cell face:
 * with NATIVE_LEVELS and uneven levels the file's own (a stretched grid, data/volume.h, its
 * centres the file's heights), else even ones. */
void hgrid_grid(const struct hgrid *h, bool native_levels, struct grid3 *out);
/* Whether hgrid_grid with NATIVE_LEVELS keeps the file's own levels: they are uneven, at
 * most GRID3_LEVELS_MAX, and none on the lowest or highest cell face. */
bool hgrid_native(const struct hgrid *h, bool native_levels);

/* Reads STEP into OUT (initialised here; finish with field_volume_finish): the species the
 * files hold (others NULL: zero), density (from the file's density, else from pressure and
 * temperature or potential temperature, else NULL: the standard atmosphere), and as D asks
 * vapour, temperature and wind speed (and its components), on hgrid_grid's grid.  Bad values
 * as the WRF reader treats them; a quantity all bad in the step is an error.  False after one
 * log_error. */
bool hgrid_read_step(struct hgrid *h, int step, const struct hgrid_desc *d,
                     struct field_volume *out, struct hgrid_stats *stats);

/* A lat/lon grid of the mass columns (nx * ny, x fastest) when the file's axes were
 * longitude and latitude: *LAT and *LON allocated here (the caller frees them); false
 * otherwise. */
bool hgrid_latlon(const struct hgrid *h, float **lat, float **lon);

/* Converts SECONDS since 1970-01-01 into "YYYY-MM-DD_hh:mm:ss" (proleptic Gregorian). */
void hgrid_format_date(double seconds, char out[32]);

#endif
