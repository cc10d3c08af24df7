/*
 * data/nest: the domains of one WRF run (a parent d01 and its nests d02, d03 ...) as one
 * volume.  The files of a series are grouped by domain (their GRID_ID attribute, else `_dNN_`
 * in the file name); each domain is a WRF series of its own (data/wrf.h), placed in the
 * outermost domain's frame by its PARENT_ID, I_PARENT_START, J_PARENT_START and
 * PARENT_GRID_RATIO attributes, or by its XLAT/XLONG through the outermost domain's map
 * (data/geo.h) where the attributes are absent or name a domain not given.
 *
 * A step is composed onto one grid: the outermost domain's extent at the finest domain's
 * spacing, on the heights of the outermost domain.  Every domain, coarsest first, writes its
 * box: its values bilinear between its own column centres (clamped at its edges, as the eye
 * pass samples a volume), blended into what lies below over one cell of the domain it sits in
 * at its edge.  Since the nests' spacings divide the parent's, a nest's columns land on the
 * composite's columns exactly and keep their values; with an odd ratio the parent's columns
 * do too, so outside the nests trilinear sampling of the composite reads what trilinear
 * sampling of the parent reads (docs/data.md, "Nests").
 *
 * Knows nothing of the config, the GPU or optics.  NetCDF calls hold data_nc_lock.
 */
#ifndef ANVIL_DATA_NEST_H
#define ANVIL_DATA_NEST_H

#include <stdbool.h>
#include <stddef.h>

#include "data/volume.h"
#include "data/wrf.h"

#define NEST_DOMAIN_MAX 8

/* Where each domain lies on the composite grid: plain numbers (nest_compose needs nothing
 * else, so it can be tested without files). */
struct nest_layout {
    int count;         /* domains, coarsest first: [0] the outermost */
    struct grid3 grid; /* the composite: the outermost domain's box at the finest spacing, or
                          the part of it data.crop keeps */
    int levels;        /* the heights every domain is read on (wrf_desc levels, bottom_m,
                          top_m): the outermost's before a crop along z */
    struct grid3 heights; /* the outermost's grid before a crop along z: on the model's own
                             levels (stretched) every domain is read onto its levels */
    double bottom_m, top_m;
    struct nest_place {
        int offset[2]; /* the domain's west and south edge, in composite columns from the
                          composite's (negative, or beyond it, where a crop cuts the domain) */
        int scale;     /* composite columns per column of the domain (1 for the finest) */
        int blend;     /* composite columns over which its edge blends into what lies below
                          (one column of the domain it sits in); 0 for the outermost */
    } place[NEST_DOMAIN_MAX];
};

/* Composes IN[0 .. L->count - 1] (the domains' fields in L's order, on the composite's
 * heights: same n[2], origin and spacing along z) onto L->grid, each where its box and the
 * grid overlap (a domain outside the grid is passed over; its IN may be empty).  A species or
 * QVAPOR that a domain lacks reads as zero there; air density, temperature, the wind, vorticity and
 * the level heights are kept only when every domain has them (else NULL: the standard atmosphere
 * for the density).  OUT is initialised here; the caller finishes it.  False (logged) when a
 * domain's grid does not fit L or out of memory. */
bool nest_compose(const struct nest_layout *l, const struct field_volume *in,
                  struct field_volume *out);

/* One domain of a set, as placed. */
struct nest_domain {
    struct wrf *wrf;  /* its series; owned by the set */
    const char *path; /* its first file (for messages); valid until nest_close */
    int grid_id;      /* GRID_ID (or the `_dNN_` of the file name) */
    int parent_id;    /* PARENT_ID it is placed in, 0 for the outermost and by lat/lon */
    int ratio;        /* its columns per column of the domain it is placed in */
    int start[2];     /* I_PARENT_START, J_PARENT_START (1-based, the parent's columns) as
                         used, or as found from lat/lon */
    bool by_latlon;   /* placed from XLAT/XLONG rather than the PARENT attributes */
    double misfit_m;  /* by lat/lon: how far its corner lay from the composite column edge
                         it was put on; by attributes: how far from there its XLAT/XLONG
                         put it (NAN without them), m */
};

struct nest_set;

/* Groups PATHS (files or glob patterns) by domain and opens each domain's series
 * (wrf_open(MEMORY_MB)).  When all the files are one domain (their names all carry one `_dNN_`,
 * or else their GRID_IDs agree) it returns NULL with *SINGLE true, having logged nothing and
 * kept nothing open (open them as one series).  Else NULL with *SINGLE false
 * after one log_error naming the file (a nest outside its parent, a ratio the spacings
 * contradict, a domain that cannot be placed, more than NEST_DOMAIN_MAX domains).  The paths
 * are copied. */
struct nest_set *nest_open(const char *const *paths, int count, double memory_mb, bool *single);
void nest_close(struct nest_set *s); /* NULL is fine */

int nest_domain_count(const struct nest_set *s);
/* Domain I in the layout's order (0 the outermost); valid until nest_close. */
const struct nest_domain *nest_domain(const struct nest_set *s, int i);
/* The outermost domain's series: the time steps, dates, metadata, map and terrain. */
struct wrf *nest_outer(struct nest_set *s);

/* The layout and composite grid for a read with D.  With nests D's crop along x and y counts
 * the composite's columns (at the finest spacing), along z the output levels as for one
 * domain; a stride is refused (it would undo the nests' resolution).  False (logged). */
bool nest_layout(const struct nest_set *s, const struct wrf_desc *d, struct nest_layout *out);

/* Bytes a step read with D needs: every domain's step (wrf_step_bytes) and the composite's
 * arrays.  SIZE_MAX when that does not fit a size_t, 0 (logged) when D selects nothing. */
size_t nest_step_bytes(const struct nest_set *s, const struct wrf_desc *d);

/* Reads the outermost domain's STEP and each nest's step of the same Times (a nest without one
 * is left out of that step, with one log_warn), all on the outermost domain's heights, and
 * composes them into OUT (initialised here).  STATS (may be NULL) receives the outermost
 * domain's counts.  Refused (logged) when nest_step_bytes(D) exceeds D->memory_mb. */
bool nest_read_step(struct nest_set *s, int step, const struct wrf_desc *d,
                    struct field_volume *out, struct wrf_stats *stats);

/* What the files hold at P (metres in the outermost domain's frame, as wrf_read_point takes
 * it) at the outermost's STEP: read from the finest domain whose box holds P and that has a
 * step at that time (wrf_read_point on its columns, on the composite's heights).  Outside the
 * composite's grid (a crop included): WRF_POINT_OUTSIDE. */
enum wrf_point_result nest_read_point(struct nest_set *s, int step, const struct wrf_desc *d,
                                      const double p[3], struct wrf_point *out);

/* For writing a parent and its nest from one field (anvil synth --nest): the fields of FINE
 * (a volume at the nest's spacing over the whole parent domain) on the parent's grid, RATIO
 * times coarser (each column the mean of FINE's columns nearest its centre: its one central
 * column for an odd ratio), when BOX is NULL; else on the nest's, FINE's columns
 * BOX[0] <= i < BOX[0] + BOX[2], BOX[1] <= j < BOX[1] + BOX[3] as they are.  Mass ratios,
 * QVAPOR and air density are carried.  OUT is initialised here.  False (logged) on a box
 * outside FINE, a size RATIO does not divide or out of memory. */
bool nest_cut(const struct field_volume *fine, int ratio, const int *box, struct field_volume *out);

/* How domain I is placed, one line for `anvil info` (no newline). */
void nest_describe(const struct nest_set *s, int i, char *out, size_t size);

#endif
