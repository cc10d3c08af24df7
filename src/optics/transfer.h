/*
 * optics/transfer: a piecewise-linear RGBA transfer function for scalar fields (Dye 2007 §4.3):
 * four independent channels of control points (x in [0, 1] over the field's range [lo, hi],
 * value in [0, 1]), linearly interpolated and clamped outside their first and last point; and
 * the colour-mapped layers and slices that show fields through them.  Alpha becomes a layer's
 * extinction (alpha times DENSITY times its opacity, 1/m), red, green and blue its colour.
 * Pure numbers: no files (config/ reads and writes them), no GL, no volumes.
 */
#ifndef ANVIL_OPTICS_TRANSFER_H
#define ANVIL_OPTICS_TRANSFER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define TRANSFER_MAX_POINTS 32
#define TRANSFER_HISTOGRAM_BINS 64
#define TRANSFER_NAME_MAX 64

enum transfer_channel { TRANSFER_RED, TRANSFER_GREEN, TRANSFER_BLUE, TRANSFER_ALPHA,
                        TRANSFER_CHANNELS };

/* The scalar fields a transfer function can show. */
enum transfer_field {
    TRANSFER_FIELD_QVAPOR,     /* water vapour mixing ratio, kg/kg (the data's QVAPOR, else an
                                  exponential profile of 10 g/kg and 2.5 km scale height) */
    TRANSFER_FIELD_CONDENSATE, /* total condensate: the sum of the five species, kg/kg */
    TRANSFER_FIELD_TEMPERATURE, /* absolute air temperature, K (the data's P, PB, T, else the
                                   1976 standard atmosphere) */
    TRANSFER_FIELD_WIND,        /* wind speed |(U, V, W)|, m/s (zero where the data has no
                                   U and V) */
    TRANSFER_FIELD_THETA,       /* potential temperature, K (data/derived.h) */
    TRANSFER_FIELD_RH,          /* relative humidity over liquid water, % (data/derived.h) */
    TRANSFER_FIELD_W,           /* vertical velocity W, m/s, positive up (zero where the data
                                   has none) */
    TRANSFER_FIELD_VORTICITY,   /* vertical vorticity dv/dx - du/dy, 1/s (data/derived.h; zero
                                   where the data has no U and V) */
    TRANSFER_FIELD_COUNT
};

struct transfer_point {
    float x, v;
};

struct transfer_function {
    char name[TRANSFER_NAME_MAX];
    enum transfer_field field;
    double lo, hi;    /* field values at x = 0 and x = 1 */
    double density;   /* extinction at alpha = 1, 1/m */
    int count[TRANSFER_CHANNELS];
    struct transfer_point points[TRANSFER_CHANNELS][TRANSFER_MAX_POINTS]; /* x ascending */
};

/* A colour-mapped layer (docs/analysis.md): the scalar field TF.field, interpolated on the GPU
 * and then classified by TF (post-classification), composited with the clouds in the eye
 * pass.  EMIT: the layer emits its colour and absorbs with extinction alpha * TF.density *
 * OPACITY (1/m), unlit by the sun.  TINT: the clouds' scattered light is multiplied by
 * mix(1, rgb, alpha * OPACITY); the layer adds no medium of its own. */
#define TRANSFER_LAYER_MAX 4
enum transfer_layer_mode { TRANSFER_LAYER_EMIT, TRANSFER_LAYER_TINT };

struct transfer_layer {
    bool enabled;
    int mode;       /* enum transfer_layer_mode */
    double opacity; /* >= 0 */
    struct transfer_function tf;
};

/* A slice (docs/analysis.md): the plane NORMAL . p = NORMAL . POINT (world metres) through the
 * field TF.field, coloured by TF's red, green and blue (its alpha is not used) at OPACITY, with
 * contour lines every CONTOUR_EVERY field units (0: none) and at the CONTOUR_VALUES, composited with the clouds where
 * the ray crosses it. */
#define TRANSFER_SLICE_MAX 4
#define TRANSFER_CONTOUR_MAX 6 /* contour lines at given values, per slice */

struct transfer_slice {
    bool enabled;
    double point[3];     /* metres */
    double normal[3];    /* unit */
    double opacity;      /* [0, 1] */
    double contour_every; /* field units; 0: no lines */
    double contour_values[TRANSFER_CONTOUR_MAX]; /* lines also at these field values ... */
    int contour_count;                           /* ... the first this many */
    int level;            /* >= 1: the surface of the model's mass level LEVEL, 1 the lowest
                             (terrain following; ext_volume.slice_surface), in place of the
                             plane; 0: the plane */
    struct transfer_function tf;
};

/* "emit", "tint"; false for an unknown name. */
const char *transfer_layer_mode_name(int mode);

/* A default for FIELD: a grey ramp with alpha rising over the upper half of the range. */
void transfer_defaults(struct transfer_function *tf, enum transfer_field field);

/* "qvapor", "condensate", "temperature", "wind", "theta", "rh", "w", "vorticity";
 * transfer_field_from_name
 * returns false for an unknown name. */
const char *transfer_field_name(enum transfer_field f);
bool transfer_field_from_name(const char *name, enum transfer_field *out);
/* What the menu shows: "QVAPOR", "condensate", "temperature", "wind speed", "potential
 * temperature", "relative humidity", "vertical velocity", "vorticity". */
const char *transfer_field_label(enum transfer_field f);
/* The unit of the field's values ("kg/kg", "K", "m/s", "%", "1/s"). */
const char *transfer_field_unit(enum transfer_field f);
/* A value of field F as a label, ASCII: mixing ratios in g/kg ("12 g/kg"), temperature in
 * degrees Celsius ("-73.2 C"), wind speed in m/s ("60 m/s"), potential temperature in K ("300 K"),
 * relative humidity in per cent ("85 %"), vertical velocity in m/s ("-1.5 m/s"), vorticity in
 * units of 1e-3/s ("2.5e-3/s"). */
void transfer_format_value(enum transfer_field f, double v, char *buf, int size);
const char *transfer_channel_name(enum transfer_channel c); /* "red", ... "alpha" */

/* Channel C at X in [0, 1] (clamped at the ends; 0 without points). */
float transfer_eval(const struct transfer_function *tf, enum transfer_channel c, float x);
/* All four channels for the field value S. */
void transfer_eval_rgba(const struct transfer_function *tf, double s, float rgba[4]);

/* Editing.  Each keeps the points sorted and returns the point's new index, or -1 when the
 * edit is refused (channel full; a channel keeps at least one point). */
int transfer_add_point(struct transfer_function *tf, enum transfer_channel c, float x, float v);
int transfer_move_point(struct transfer_function *tf, enum transfer_channel c, int i, float x,
                        float v);
bool transfer_delete_point(struct transfer_function *tf, enum transfer_channel c, int i);

/* Checks the invariants (counts in range, x ascending in [0, 1], values in [0, 1], lo < hi,
 * density >= 0).  On failure writes what is wrong into WHY (may be NULL). */
bool transfer_valid(const struct transfer_function *tf, char *why, int why_size);

bool transfer_equal(const struct transfer_function *a, const struct transfer_function *b);

/* How a field's values fall over a transfer function's range (the editor's histogram): bin i
 * counts the values x with floor((x - lo) / (hi - lo) * TRANSFER_HISTOGRAM_BINS) = i, the value
 * hi in the last bin; values below lo, above hi, and NaN are counted apart. */
struct transfer_histogram {
    enum transfer_field field; /* what was counted */
    double lo, hi;
    uint32_t count[TRANSFER_HISTOGRAM_BINS];
    uint64_t below, above, nonfinite, total;
};

/* Empties H for FIELD over [LO, HI] (lo < hi). */
void transfer_histogram_init(struct transfer_histogram *h, enum transfer_field field, double lo,
                             double hi);
/* Counts the value X into H. */
void transfer_histogram_add(struct transfer_histogram *h, double x);
/* Counts the value X into H N times (as N calls of transfer_histogram_add). */
void transfer_histogram_add_times(struct transfer_histogram *h, double x, uint64_t n);
/* Adds what FROM counted (over the same field and range) to H. */
void transfer_histogram_merge(struct transfer_histogram *h, const struct transfer_histogram *from);
/* The largest bin count. */
uint32_t transfer_histogram_max(const struct transfer_histogram *h);

#endif
