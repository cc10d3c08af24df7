#include "optics/transfer.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static const char *const field_names[TRANSFER_FIELD_COUNT] = {
    "qvapor", "condensate", "temperature", "wind", "theta", "rh", "w", "vorticity"};
static const char *const field_labels[TRANSFER_FIELD_COUNT] = {
    "QVAPOR", "condensate", "temperature", "wind speed", "potential temperature",
    "relative humidity", "vertical velocity", "vorticity"};
static const char *const field_units[TRANSFER_FIELD_COUNT] = {
    "kg/kg", "kg/kg", "K", "m/s", "K", "%", "m/s", "1/s"};
static const char *const channel_names[TRANSFER_CHANNELS] = {"red", "green", "blue", "alpha"};

const char *transfer_field_name(enum transfer_field f)
{
    return f >= 0 && f < TRANSFER_FIELD_COUNT ? field_names[f] : "?";
}

const char *transfer_field_label(enum transfer_field f)
{
    return f >= 0 && f < TRANSFER_FIELD_COUNT ? field_labels[f] : "?";
}

const char *transfer_field_unit(enum transfer_field f)
{
    return f >= 0 && f < TRANSFER_FIELD_COUNT ? field_units[f] : "?";
}

void transfer_format_value(enum transfer_field f, double v, char *buf, int size)
{
    if (size <= 0)
        return;
    switch (f) {
    case TRANSFER_FIELD_TEMPERATURE:
        snprintf(buf, (size_t)size, "%.1f C", v - 273.15);
        break;
    case TRANSFER_FIELD_WIND:
        snprintf(buf, (size_t)size, "%.3g m/s", v);
        break;
    case TRANSFER_FIELD_THETA:
        snprintf(buf, (size_t)size, "%.1f K", v);
        break;
    case TRANSFER_FIELD_RH:
        snprintf(buf, (size_t)size, "%.0f %%", v);
        break;
    case TRANSFER_FIELD_W:
        snprintf(buf, (size_t)size, "%.2g m/s", v);
        break;
    case TRANSFER_FIELD_VORTICITY:
        snprintf(buf, (size_t)size, "%.2ge-3/s", v * 1e3);
        break;
    default:
        snprintf(buf, (size_t)size, "%.3g g/kg", v * 1000.0);
        break;
    }
}

bool transfer_field_from_name(const char *name, enum transfer_field *out)
{
    for (int f = 0; f < TRANSFER_FIELD_COUNT; f++) {
        if (strcmp(name, field_names[f]) == 0) {
            *out = (enum transfer_field)f;
            return true;
        }
    }
    return false;
}

const char *transfer_layer_mode_name(int mode)
{
    return mode == TRANSFER_LAYER_TINT ? "tint" : "emit";
}

const char *transfer_channel_name(enum transfer_channel c)
{
    return c >= 0 && c < TRANSFER_CHANNELS ? channel_names[c] : "?";
}

static void set_points(struct transfer_function *tf, int c, int n, const float *xv)
{
    tf->count[c] = n;
    for (int i = 0; i < n; i++)
        tf->points[c][i] = (struct transfer_point){xv[2 * i], xv[2 * i + 1]};
}

void transfer_defaults(struct transfer_function *tf, enum transfer_field field)
{
    memset(tf, 0, sizeof(*tf));
    snprintf(tf->name, sizeof(tf->name), "default");
    tf->field = field;
    if (field == TRANSFER_FIELD_QVAPOR) {
        tf->lo = 0.0;
        tf->hi = 0.012; /* 12 g/kg: a moist boundary layer */
    } else if (field == TRANSFER_FIELD_TEMPERATURE) {
        tf->lo = 200.0; /* K: the tropopause of the tropics */
        tf->hi = 310.0; /* a hot surface */
    } else if (field == TRANSFER_FIELD_WIND) {
        tf->lo = 0.0;
        tf->hi = 60.0; /* m/s: a major hurricane's eyewall */
    } else if (field == TRANSFER_FIELD_THETA) {
        tf->lo = 290.0; /* K: a tropical boundary layer */
        tf->hi = 370.0; /* the tropical tropopause */
    } else if (field == TRANSFER_FIELD_RH) {
        tf->lo = 0.0;
        tf->hi = 100.0; /* %: saturation */
    } else if (field == TRANSFER_FIELD_W) {
        tf->lo = -10.0; /* m/s: a convective downdraft */
        tf->hi = 10.0;  /* a thunderstorm's updraft */
    } else if (field == TRANSFER_FIELD_VORTICITY) {
        tf->lo = -2e-3; /* 1/s: twenty times f = 2 Omega sin 45 deg = 1.03e-4 */
        tf->hi = 2e-3;
    } else {
        tf->lo = 0.0;
        tf->hi = 0.005;
    }
    tf->density = 2e-3; /* 1/m: a 5 km column of alpha 0.1 has optical depth 1 */
    /* Blue for dry, white for moist; transparent in the lowest 30 % of the range. */
    set_points(tf, TRANSFER_RED, 2, (const float[]){0.0f, 0.3f, 1.0f, 1.0f});
    set_points(tf, TRANSFER_GREEN, 2, (const float[]){0.0f, 0.5f, 1.0f, 1.0f});
    set_points(tf, TRANSFER_BLUE, 1, (const float[]){0.0f, 1.0f});
    set_points(tf, TRANSFER_ALPHA, 3, (const float[]){0.0f, 0.0f, 0.3f, 0.0f, 1.0f, 0.5f});
}

float transfer_eval(const struct transfer_function *tf, enum transfer_channel c, float x)
{
    int n = tf->count[c];
    const struct transfer_point *p = tf->points[c];
    if (n <= 0)
        return 0.0f;
    if (!(x > p[0].x)) /* also NaN */
        return p[0].v;
    if (x >= p[n - 1].x)
        return p[n - 1].v;
    for (int i = 1; i < n; i++) {
        if (x <= p[i].x) {
            float w = p[i].x - p[i - 1].x;
            float t = w > 0.0f ? (x - p[i - 1].x) / w : 1.0f;
            return p[i - 1].v + t * (p[i].v - p[i - 1].v);
        }
    }
    return p[n - 1].v;
}

void transfer_eval_rgba(const struct transfer_function *tf, double s, float rgba[4])
{
    double span = tf->hi - tf->lo;
    float x = span > 0.0 ? (float)((s - tf->lo) / span) : 0.0f;
    for (int c = 0; c < TRANSFER_CHANNELS; c++)
        rgba[c] = transfer_eval(tf, (enum transfer_channel)c, x);
}

static float clamp01(float v)
{
    return v < 0.0f ? 0.0f : v > 1.0f ? 1.0f : v;
}

/* Moves point I of channel C to its sorted place; returns the new index. */
static int resort(struct transfer_function *tf, int c, int i)
{
    struct transfer_point *p = tf->points[c];
    while (i > 0 && p[i - 1].x > p[i].x) {
        struct transfer_point t = p[i - 1];
        p[i - 1] = p[i];
        p[i] = t;
        i--;
    }
    while (i + 1 < tf->count[c] && p[i + 1].x < p[i].x) {
        struct transfer_point t = p[i + 1];
        p[i + 1] = p[i];
        p[i] = t;
        i++;
    }
    return i;
}

int transfer_add_point(struct transfer_function *tf, enum transfer_channel c, float x, float v)
{
    if (c < 0 || c >= TRANSFER_CHANNELS || tf->count[c] >= TRANSFER_MAX_POINTS)
        return -1;
    int i = tf->count[c]++;
    tf->points[c][i] = (struct transfer_point){clamp01(x), clamp01(v)};
    return resort(tf, c, i);
}

int transfer_move_point(struct transfer_function *tf, enum transfer_channel c, int i, float x,
                        float v)
{
    if (c < 0 || c >= TRANSFER_CHANNELS || i < 0 || i >= tf->count[c])
        return -1;
    tf->points[c][i] = (struct transfer_point){clamp01(x), clamp01(v)};
    return resort(tf, c, i);
}

bool transfer_delete_point(struct transfer_function *tf, enum transfer_channel c, int i)
{
    if (c < 0 || c >= TRANSFER_CHANNELS || i < 0 || i >= tf->count[c] || tf->count[c] <= 1)
        return false;
    struct transfer_point *p = tf->points[c];
    memmove(&p[i], &p[i + 1], sizeof(p[0]) * (size_t)(tf->count[c] - i - 1));
    tf->count[c]--;
    return true;
}

bool transfer_valid(const struct transfer_function *tf, char *why, int why_size)
{
    char buf[160];
    buf[0] = '\0';
    if (tf->field < 0 || tf->field >= TRANSFER_FIELD_COUNT)
        snprintf(buf, sizeof(buf), "unknown field");
    else if (!(tf->lo < tf->hi) || !isfinite(tf->lo) || !isfinite(tf->hi))
        snprintf(buf, sizeof(buf), "range: expected lo < hi, got [%g, %g]", tf->lo, tf->hi);
    else if (!(tf->density >= 0.0) || !isfinite(tf->density))
        snprintf(buf, sizeof(buf), "density: expected a number >= 0, got %g", tf->density);
    for (int c = 0; c < TRANSFER_CHANNELS && !buf[0]; c++) {
        int n = tf->count[c];
        if (n < 1 || n > TRANSFER_MAX_POINTS) {
            snprintf(buf, sizeof(buf), "%s: expected 1 to %d points, got %d", channel_names[c],
                     TRANSFER_MAX_POINTS, n);
            break;
        }
        for (int i = 0; i < n && !buf[0]; i++) {
            const struct transfer_point *p = &tf->points[c][i];
            if (!(p->x >= 0.0f && p->x <= 1.0f && p->v >= 0.0f && p->v <= 1.0f))
                snprintf(buf, sizeof(buf), "%s[%d]: expected x and value in [0, 1], got [%g, %g]",
                         channel_names[c], i, p->x, p->v);
            else if (i > 0 && p->x < tf->points[c][i - 1].x)
                snprintf(buf, sizeof(buf), "%s[%d]: points must be in ascending x",
                         channel_names[c], i);
        }
    }
    if (why && why_size > 0)
        snprintf(why, (size_t)why_size, "%s", buf);
    return !buf[0];
}

bool transfer_equal(const struct transfer_function *a, const struct transfer_function *b)
{
    if (strcmp(a->name, b->name) != 0 || a->field != b->field || a->lo != b->lo ||
        a->hi != b->hi || a->density != b->density)
        return false;
    for (int c = 0; c < TRANSFER_CHANNELS; c++) {
        if (a->count[c] != b->count[c])
            return false;
        for (int i = 0; i < a->count[c]; i++) {
            if (a->points[c][i].x != b->points[c][i].x || a->points[c][i].v != b->points[c][i].v)
                return false;
        }
    }
    return true;
}

void transfer_histogram_init(struct transfer_histogram *h, enum transfer_field field, double lo,
                             double hi)
{
    memset(h, 0, sizeof(*h));
    h->field = field;
    h->lo = lo;
    h->hi = hi;
}

/* Bin COUNT after N more values, held at UINT32_MAX. */
static uint32_t add_count(uint32_t count, uint64_t n)
{
    return n >= (uint64_t)(UINT32_MAX - count) ? UINT32_MAX : count + (uint32_t)n;
}

void transfer_histogram_add_times(struct transfer_histogram *h, double x, uint64_t n)
{
    if (n == 0)
        return;
    h->total += n;
    if (!isfinite(x)) {
        h->nonfinite += n;
        return;
    }
    if (x < h->lo) {
        h->below += n;
        return;
    }
    if (x > h->hi) {
        h->above += n;
        return;
    }
    double f = floor((x - h->lo) / (h->hi - h->lo) * TRANSFER_HISTOGRAM_BINS);
    int i = f >= TRANSFER_HISTOGRAM_BINS ? TRANSFER_HISTOGRAM_BINS - 1 : f < 0.0 ? 0 : (int)f;
    h->count[i] = add_count(h->count[i], n);
}

void transfer_histogram_add(struct transfer_histogram *h, double x)
{
    transfer_histogram_add_times(h, x, 1);
}

void transfer_histogram_merge(struct transfer_histogram *h, const struct transfer_histogram *from)
{
    for (int i = 0; i < TRANSFER_HISTOGRAM_BINS; i++)
        h->count[i] = add_count(h->count[i], from->count[i]);
    h->below += from->below;
    h->above += from->above;
    h->nonfinite += from->nonfinite;
    h->total += from->total;
}

uint32_t transfer_histogram_max(const struct transfer_histogram *h)
{
    uint32_t m = 0;
    for (int i = 0; i < TRANSFER_HISTOGRAM_BINS; i++)
        m = h->count[i] > m ? h->count[i] : m;
    return m;
}
