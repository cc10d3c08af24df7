/* Values at a point of the data, and the first visible point along a ray. */
#include "data/probe.h"

#include <math.h>
#include <string.h>

#include "data/wrf_write.h"

double probe_sample_condensate(const struct probe_sample *s)
{
    double sum = 0.0;
    for (int f = 0; f < SPECIES_COUNT; f++)
        if (s->has_species[f])
            sum += s->q[f];
    return sum;
}

void probe_wind(double u, double v, double *speed, double *from_deg)
{
    *speed = hypot(u, v);
    if (*speed == 0.0) {
        *from_deg = 0.0;
        return;
    }
    /* The direction it comes from: the opposite of (u, v), clockwise from north. */
    double d = atan2(-u, -v) * 180.0 / M_PI;
    *from_deg = d < 0.0 ? d + 360.0 : d;
    if (*from_deg >= 360.0)
        *from_deg -= 360.0;
}

void probe_sample_from_wrf(const struct wrf_point *p, double z, struct probe_sample *out)
{
    memset(out, 0, sizeof(*out));
    for (int f = 0; f < SPECIES_COUNT; f++) {
        out->has_species[f] = p->has_species[f];
        out->q[f] = p->q[f];
    }
    out->has_qvapor = p->has_qvapor;
    out->qvapor = p->qvapor;
    double t_std, p_std;
    wrf_std_atmosphere(z, &t_std, &p_std);
    out->temperature_from = isfinite(p->temperature_k) ? PROBE_DATA : PROBE_STANDARD;
    out->temperature_k = isfinite(p->temperature_k) ? p->temperature_k : t_std;
    out->pressure_from = isfinite(p->pressure_pa) ? PROBE_DATA : PROBE_STANDARD;
    out->pressure_pa = isfinite(p->pressure_pa) ? p->pressure_pa : p_std;
    out->has_wind = p->has_wind;
    out->wind_earth_relative = p->earth_relative;
    out->has_w = p->has_w;
    out->u = p->u;
    out->v = p->v;
    out->w = p->w;
    out->has_ground = true;
    out->ground_m = p->ground_m;
}

/* Trilinear weights of P in GRID between voxel centres, clamped to the edge voxels: the lower
 * voxel I0 and the weight T of the next along each axis.  False outside the box. */
static bool cell_of(const struct grid3 *g, const double p[3], int i0[3], double t[3])
{
    for (int a = 0; a < 3; a++) {
        double rel = a < 2 ? (p[a] - g->origin[a]) / g->spacing[a] : grid3_z_to_voxel(g, p[a]);
        if (!(rel >= 0.0 && rel <= g->n[a]))
            return false;
        double f = rel - 0.5;
        if (f <= 0.0 || g->n[a] < 2) {
            i0[a] = 0;
            t[a] = 0.0;
        } else if (f >= g->n[a] - 1) {
            i0[a] = g->n[a] - 2;
            t[a] = 1.0;
        } else {
            i0[a] = (int)floor(f);
            t[a] = f - i0[a];
        }
    }
    return true;
}

/* The trilinear value of the array V (grid3_count values, STRIDE apart starting at V) at the
 * cell I0, T. */
static double trilinear(const struct grid3 *g, const float *v, int stride, const int i0[3],
                        const double t[3])
{
    double sum = 0.0;
    for (int c = 0; c < 8; c++) {
        int d[3] = {c & 1, (c >> 1) & 1, (c >> 2) & 1};
        double w = 1.0;
        int idx[3];
        for (int a = 0; a < 3; a++) {
            w *= d[a] ? t[a] : 1.0 - t[a];
            idx[a] = i0[a] + (g->n[a] > 1 ? d[a] : 0);
        }
        if (w == 0.0)
            continue;
        sum += w * v[(size_t)stride * grid3_index(g, idx[0], idx[1], idx[2])];
    }
    return sum;
}

bool probe_sample_fields(const struct field_volume *fv, const double p[3],
                         struct probe_sample *out)
{
    memset(out, 0, sizeof(*out));
    int i0[3];
    double t[3];
    if (!cell_of(&fv->grid, p, i0, t))
        return false;
    for (int f = 0; f < SPECIES_COUNT; f++) {
        out->has_species[f] = fv->q[f] != NULL;
        out->q[f] = fv->q[f] ? trilinear(&fv->grid, fv->q[f], 1, i0, t) : 0.0;
    }
    out->has_qvapor = fv->qvapor != NULL;
    out->qvapor = fv->qvapor ? trilinear(&fv->grid, fv->qvapor, 1, i0, t) : 0.0;
    double t_std, p_std;
    wrf_std_atmosphere(p[2], &t_std, &p_std);
    out->temperature_from = fv->temperature ? PROBE_DATA : PROBE_STANDARD;
    out->temperature_k = fv->temperature ? trilinear(&fv->grid, fv->temperature, 1, i0, t) : t_std;
    out->pressure_from = fv->pressure ? PROBE_DATA : PROBE_STANDARD;
    out->pressure_pa = fv->pressure ? trilinear(&fv->grid, fv->pressure, 1, i0, t) : p_std;
    /* The readers' components are east and north (CF's eastward_wind, CM1's and Isabel's x
     * and y, which the frame takes as east and north). */
    out->has_wind = fv->u && fv->v;
    out->wind_earth_relative = out->has_wind;
    out->has_w = out->has_wind && fv->w;
    out->u = out->has_wind ? trilinear(&fv->grid, fv->u, 1, i0, t) : 0.0;
    out->v = out->has_wind ? trilinear(&fv->grid, fv->v, 1, i0, t) : 0.0;
    out->w = out->has_w ? trilinear(&fv->grid, fv->w, 1, i0, t) : 0.0;
    return true;
}

void probe_sample_beta(const struct ext_volume *v, const double p[3], double out[2])
{
    out[0] = out[1] = 0.0;
    int i0[3];
    double t[3];
    if (!v->beta || !cell_of(&v->grid, p, i0, t))
        return;
    for (int k = 0; k < 2; k++) {
        double b = trilinear(&v->grid, v->beta + k, 2, i0, t);
        out[k] = isfinite(b) && b > 0.0 ? b : 0.0;
    }
}

static double beta_at(const struct ext_volume *v, const double o[3], const double d[3], double t)
{
    double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]}, b[2];
    probe_sample_beta(v, p, b);
    return b[0] + b[1];
}

bool probe_first_visible(const struct ext_volume *v, const double o[3], const double d[3],
                         double t_max, double threshold, double *t_hit)
{
    if (!v->beta)
        return false;
    /* The box's slab test (a zero direction component: the ray runs inside or misses). */
    double t0 = 0.0, t1 = t_max, crossing = 0.0;
    for (int a = 0; a < 3; a++) {
        double lo = v->grid.origin[a], hi = lo + v->grid.n[a] * v->grid.spacing[a];
        if (fabs(d[a]) < 1e-20) {
            if (o[a] < lo || o[a] > hi)
                return false;
            continue;
        }
        double ta = (lo - o[a]) / d[a], tb = (hi - o[a]) / d[a];
        if (ta > tb) {
            double s = ta;
            ta = tb;
            tb = s;
        }
        t0 = fmax(t0, ta);
        t1 = fmin(t1, tb);
        crossing = fmax(crossing, fabs(d[a]) / (a < 2 ? v->grid.spacing[a]
                                                     : grid3_min_dz(&v->grid)));
    }
    if (!(t0 <= t1) || !(crossing > 0.0))
        return false;
    double step = 0.25 / crossing, prev = t0;
    if (beta_at(v, o, d, t0) > threshold) {
        *t_hit = t0;
        return true;
    }
    for (long i = 1;; i++) {
        double t = fmin(t0 + (double)i * step, t1);
        if (beta_at(v, o, d, t) > threshold) {
            double lo = prev, hi = t;
            while (hi - lo > 1e-4 * step) {
                double mid = 0.5 * (lo + hi);
                if (beta_at(v, o, d, mid) > threshold)
                    hi = mid;
                else
                    lo = mid;
            }
            *t_hit = hi;
            return true;
        }
        if (t >= t1)
            return false;
        prev = t;
    }
}
