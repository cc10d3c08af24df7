#include "data/geo.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"

#define DEG (M_PI / 180.0)
#define NEWTON_ITERATIONS 40
#define NEWTON_TOLERANCE_DEG 1e-7
#define SEARCH_SAMPLES 48 /* per axis, for the coarse search */
#define INDEX_LIMIT 1e5   /* |index| beyond this: give up */

static double wrap_near(double lon, double centre)
{
    return lon + 360.0 * round((centre - lon) / 360.0);
}

bool geo_map_init_grid(struct geo_map *m, const float *xlat, const float *xlong, int nx, int ny,
                       double dx, double dy)
{
    memset(m, 0, sizeof(*m));
    if (nx < 2 || ny < 2 || !(dx > 0) || !(dy > 0)) {
        log_error("geo: a lat/lon grid needs at least 2 x 2 columns and positive spacing "
                  "(got %d x %d, %g x %g m)",
                  nx, ny, dx, dy);
        return false;
    }
    size_t n = (size_t)nx * ny;
    m->lat = malloc(n * sizeof(float));
    m->lon = malloc(n * sizeof(float));
    if (!m->lat || !m->lon) {
        log_error("geo: out of memory");
        geo_map_finish(m);
        return false;
    }
    double centre = xlong[(size_t)(ny / 2) * nx + nx / 2];
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(xlat[i]) || !isfinite(xlong[i]) || fabsf(xlat[i]) > 90.0f ||
            fabsf(xlong[i]) > 360.0f) {
            log_error("geo: XLAT/XLONG has a bad value at column %zu, row %zu (%g, %g)",
                      i % (size_t)nx, i / (size_t)nx, xlat[i], xlong[i]);
            geo_map_finish(m);
            return false;
        }
        m->lat[i] = xlat[i];
        m->lon[i] = (float)wrap_near(xlong[i], centre);
    }
    m->kind = GEO_GRID;
    m->nx = nx;
    m->ny = ny;
    m->dx = dx;
    m->dy = dy;
    return true;
}

void geo_map_init_local(struct geo_map *m, double lat0, double lon0)
{
    memset(m, 0, sizeof(*m));
    m->kind = GEO_LOCAL;
    m->lat0 = fmax(-85.0, fmin(85.0, lat0));
    m->lon0 = lon0;
}

void geo_map_finish(struct geo_map *m)
{
    if (!m)
        return;
    free(m->lat);
    free(m->lon);
    memset(m, 0, sizeof(*m));
}

/* The bilinear grid at fractional index (fi, fj), extrapolated linearly from the edge cells,
 * and its derivatives. */
static void grid_eval(const struct geo_map *m, double fi, double fj, double v[2], double d[4])
{
    int i = (int)floor(fi), j = (int)floor(fj);
    i = i < 0 ? 0 : i > m->nx - 2 ? m->nx - 2 : i;
    j = j < 0 ? 0 : j > m->ny - 2 ? m->ny - 2 : j;
    double u = fi - i, w = fj - j;
    size_t a = (size_t)j * m->nx + i, b = a + 1, c = a + m->nx, e = c + 1;
    const float *f[2] = {m->lat, m->lon};
    for (int k = 0; k < 2; k++) {
        double f00 = f[k][a], f10 = f[k][b], f01 = f[k][c], f11 = f[k][e];
        v[k] = f00 + u * (f10 - f00) + w * (f01 - f00) + u * w * (f11 - f10 - f01 + f00);
        d[2 * k] = (f10 - f00) + w * (f11 - f10 - f01 + f00);     /* d/di */
        d[2 * k + 1] = (f01 - f00) + u * (f11 - f10 - f01 + f00); /* d/dj */
    }
}

/* The next sampled index after I with step STEP on an axis of N: always ends with N - 1. */
static int next_sample(int i, int step, int n)
{
    if (i == n - 1)
        return n;
    return i + step < n ? i + step : n - 1;
}

/* The grid column nearest to (lat, lon) among a coarse sample of columns, in degrees with
 * longitude scaled by cos(lat). */
static void coarse_search(const struct geo_map *m, double lat, double lon, double ij[2])
{
    int si = m->nx / SEARCH_SAMPLES + 1, sj = m->ny / SEARCH_SAMPLES + 1;
    double best = INFINITY, c = cos(lat * DEG);
    ij[0] = ij[1] = 0.0;
    for (int j = 0; j < m->ny; j = next_sample(j, sj, m->ny)) {
        for (int i = 0; i < m->nx; i = next_sample(i, si, m->nx)) {
            size_t k = (size_t)j * m->nx + i;
            double a = m->lat[k] - lat, b = (m->lon[k] - lon) * c;
            double d = a * a + b * b;
            if (d < best) {
                best = d;
                ij[0] = i;
                ij[1] = j;
            }
        }
    }
}

bool geo_map_grid_index(const struct geo_map *m, double lat, double lon, double ij[2])
{
    if (m->kind != GEO_GRID || !isfinite(lat) || !isfinite(lon))
        return false;
    double centre = m->lon[(size_t)(m->ny / 2) * m->nx + m->nx / 2];
    lon = wrap_near(lon, centre);
    double p[2];
    coarse_search(m, lat, lon, p);
    for (int it = 0; it < NEWTON_ITERATIONS; it++) {
        double v[2], d[4];
        grid_eval(m, p[0], p[1], v, d);
        double r0 = v[0] - lat, r1 = v[1] - lon;
        if (fabs(r0) < NEWTON_TOLERANCE_DEG && fabs(r1) < NEWTON_TOLERANCE_DEG) {
            ij[0] = p[0];
            ij[1] = p[1];
            return true;
        }
        double det = d[0] * d[3] - d[1] * d[2];
        if (!(fabs(det) > 1e-300))
            return false;
        double di = -(d[3] * r0 - d[1] * r1) / det;
        double dj = -(-d[2] * r0 + d[0] * r1) / det;
        /* Newton steps across cells: at most a few cells at a time, so that a step never
         * jumps past the cell whose bilinear patch holds the answer. */
        double len = fmax(fabs(di), fabs(dj));
        if (len > 4.0) {
            di *= 4.0 / len;
            dj *= 4.0 / len;
        }
        p[0] += di;
        p[1] += dj;
        if (fabs(p[0]) > INDEX_LIMIT || fabs(p[1]) > INDEX_LIMIT)
            return false;
    }
    return false;
}

static double merc_y(double lat_deg)
{
    return log(tan(M_PI / 4.0 + 0.5 * lat_deg * DEG));
}

bool geo_map_to_frame(const struct geo_map *m, double lat, double lon, double *x, double *y)
{
    double fx, fy;
    if (m->kind == GEO_GRID) {
        double ij[2];
        if (!geo_map_grid_index(m, lat, lon, ij))
            return false;
        fx = (ij[0] + 0.5) * m->dx;
        fy = (ij[1] + 0.5) * m->dy;
    } else if (m->kind == GEO_LOCAL) {
        if (!(fabs(lat) < 89.0) || !isfinite(lon))
            return false;
        double k = GEO_EARTH_RADIUS_M * cos(m->lat0 * DEG);
        fx = k * wrap_near(lon - m->lon0, 0.0) * DEG;
        fy = k * (merc_y(lat) - merc_y(m->lat0));
    } else {
        return false;
    }
    *x = fx - m->offset[0];
    *y = fy - m->offset[1];
    return true;
}

bool geo_map_to_latlon(const struct geo_map *m, double x, double y, double *lat, double *lon)
{
    x += m->offset[0];
    y += m->offset[1];
    if (m->kind == GEO_GRID) {
        double v[2], d[4];
        grid_eval(m, x / m->dx - 0.5, y / m->dy - 0.5, v, d);
        *lat = fmax(-90.0, fmin(90.0, v[0]));
        *lon = v[1];
        return true;
    }
    if (m->kind == GEO_LOCAL) {
        double k = GEO_EARTH_RADIUS_M * cos(m->lat0 * DEG);
        *lon = m->lon0 + x / k / DEG;
        *lat = (2.0 * atan(exp(y / k + merc_y(m->lat0))) - M_PI / 2.0) / DEG;
        return true;
    }
    return false;
}

bool geo_map_box(const struct geo_map *m, const double rect[4], double box[4])
{
    if (m->kind == GEO_NONE)
        return false;
    box[0] = box[2] = INFINITY;
    box[1] = box[3] = -INFINITY;
    const int n = 32;
    for (int s = 0; s <= n; s++) {
        double t = (double)s / n;
        const double pts[4][2] = {
            {rect[0] + t * (rect[1] - rect[0]), rect[2]},
            {rect[0] + t * (rect[1] - rect[0]), rect[3]},
            {rect[0], rect[2] + t * (rect[3] - rect[2])},
            {rect[1], rect[2] + t * (rect[3] - rect[2])},
        };
        for (int k = 0; k < 4; k++) {
            double lat, lon;
            if (!geo_map_to_latlon(m, pts[k][0], pts[k][1], &lat, &lon))
                return false;
            box[0] = fmin(box[0], lat);
            box[1] = fmax(box[1], lat);
            box[2] = fmin(box[2], lon);
            box[3] = fmax(box[3], lon);
        }
    }
    return true;
}

/* One axis of geo_format_range: A to B with the hemisphere letters POS and NEG. */
static int format_axis(char *out, size_t size, int digits, double a, double b, char pos, char neg)
{
    char ha = a < 0.0 ? neg : pos, hb = b < 0.0 ? neg : pos;
    if (ha == hb)
        return snprintf(out, size, "%.*f to %.*f %c", digits, fabs(a), digits, fabs(b), hb);
    return snprintf(out, size, "%.*f %c to %.*f %c", digits, fabs(a), ha, digits, fabs(b), hb);
}

void geo_format_range(char *out, size_t size, int digits, double lat_min, double lat_max,
                      double lon_min, double lon_max)
{
    if (size == 0)
        return;
    double w = remainder(lon_min, 360.0), e = remainder(lon_max, 360.0);
    int n = format_axis(out, size, digits, lat_min, lat_max, 'N', 'S');
    if (n < 0 || (size_t)n + 2 >= size)
        return;
    snprintf(out + n, size - (size_t)n, ", ");
    format_axis(out + n + 2, size - (size_t)n - 2, digits, w, e, 'E', 'W');
}
