#include "data/derived.h"

#include <math.h>
#include <string.h>

#include "data/wrf_write.h"

#define RD 287.0      /* J/(kg K), dry air (Wallace and Hobbs 2006, §3.1) */
#define CP 1004.5     /* J/(kg K), dry air at constant pressure (as WRF's cp) */
#define P0 100000.0   /* Pa */
#define EPSILON 0.622 /* R_d / R_v */

double derived_pressure(double rho, double t)
{
    if (!isfinite(rho) || !isfinite(t) || rho <= 0.0 || t <= 0.0)
        return NAN;
    return rho * RD * t;
}

double derived_theta(double t, double p)
{
    if (!isfinite(t) || !isfinite(p) || t <= 0.0 || p <= 0.0)
        return NAN;
    return t * pow(P0 / p, RD / CP);
}

double derived_rh(double t, double p, double q)
{
    if (!isfinite(t) || !isfinite(p) || !isfinite(q) || t <= 30.0 || p <= 0.0)
        return NAN;
    if (q < 0.0)
        q = 0.0;
    double e = p * q / (EPSILON + q);                            /* Pa */
    double es = 611.2 * exp(17.67 * (t - 273.15) / (t - 29.65)); /* Pa */
    return 100.0 * e / es;
}

void derived_vorticity_plane(const float *u, const float *v, const float *map, int nx, int ny,
                             double dx, double dy, float *out)
{
    for (int j = 0; j < ny; j++) {
        int j0 = j > 0 ? j - 1 : 0, j1 = j < ny - 1 ? j + 1 : ny - 1;
        for (int i = 0; i < nx; i++) {
            int i0 = i > 0 ? i - 1 : 0, i1 = i < nx - 1 ? i + 1 : nx - 1;
            size_t c = (size_t)j * nx + i, e = (size_t)j * nx + i1, w = (size_t)j * nx + i0;
            size_t n = (size_t)j1 * nx + i, s = (size_t)j0 * nx + i;
            double m = map ? map[c] : 1.0;
            double me = map ? map[e] : 1.0, mw = map ? map[w] : 1.0;
            double mn = map ? map[n] : 1.0, ms = map ? map[s] : 1.0;
            double dvdx =
                i1 > i0 ? ((double)v[e] / me - (double)v[w] / mw) / ((i1 - i0) * dx) : 0.0;
            double dudy =
                j1 > j0 ? ((double)u[n] / mn - (double)u[s] / ms) / ((j1 - j0) * dy) : 0.0;
            out[c] = (float)(m * m * (dvdx - dudy));
        }
    }
}

bool derived_field_available(const struct field_volume *fv, enum transfer_field field)
{
    switch (field) {
    case TRANSFER_FIELD_QVAPOR:
        return fv->qvapor != NULL;
    case TRANSFER_FIELD_TEMPERATURE:
        return fv->temperature != NULL;
    case TRANSFER_FIELD_WIND:
        return fv->wind != NULL;
    case TRANSFER_FIELD_W:
        return fv->w != NULL;
    case TRANSFER_FIELD_VORTICITY:
        return fv->vorticity != NULL || (fv->u && fv->v);
    case TRANSFER_FIELD_THETA:
        return fv->temperature && fv->rho_air;
    case TRANSFER_FIELD_RH:
        return fv->temperature && fv->rho_air && fv->qvapor;
    default:
        return true;
    }
}

double derived_vapour_standard(double z_m)
{
    return 0.010 * exp(-z_m / 2500.0);
}

void derived_field(const struct field_volume *fv, enum transfer_field field, float *out)
{
    const struct grid3 *g = &fv->grid;
    if (field == TRANSFER_FIELD_VORTICITY || field == TRANSFER_FIELD_W) {
        const float *have = field == TRANSFER_FIELD_W ? fv->w : fv->vorticity;
        size_t n = grid3_count(g), plane = (size_t)g->n[0] * (size_t)g->n[1];
        if (have) {
            memcpy(out, have, n * sizeof(float));
        } else if (field == TRANSFER_FIELD_VORTICITY && fv->u && fv->v) {
            for (int k = 0; k < g->n[2]; k++)
                derived_vorticity_plane(fv->u + k * plane, fv->v + k * plane, NULL, g->n[0],
                                        g->n[1], g->spacing[0], g->spacing[1], out + k * plane);
        } else {
            memset(out, 0, n * sizeof(float));
        }
        return;
    }
    size_t idx = 0, layer = (size_t)g->n[0] * (size_t)g->n[1];
    for (int k = 0; k < g->n[2]; k++) {
        double z = grid3_centre_z(g, k);
        double vapour_std = derived_vapour_standard(z), t_std, p_std;
        wrf_std_atmosphere(z, &t_std, &p_std);
        for (size_t ij = 0; ij < layer; ij++, idx++) {
            double t = fv->temperature ? fv->temperature[idx] : t_std;
            double q = fv->qvapor ? fv->qvapor[idx] : vapour_std;
            double p =
                fv->rho_air && fv->temperature ? derived_pressure(fv->rho_air[idx], t) : p_std;
            if (!isfinite(p))
                p = p_std;
            double v;
            switch (field) {
            case TRANSFER_FIELD_QVAPOR:
                v = q;
                break;
            case TRANSFER_FIELD_TEMPERATURE:
                v = t;
                break;
            case TRANSFER_FIELD_WIND:
                v = fv->wind ? fv->wind[idx] : 0.0;
                break;
            case TRANSFER_FIELD_THETA:
                v = derived_theta(t, p);
                break;
            case TRANSFER_FIELD_RH:
                v = derived_rh(t, p, q);
                break;
            default: {
                v = 0.0;
                for (int f = 0; f < SPECIES_COUNT; f++) {
                    float m = fv->q[f] ? fv->q[f][idx] : 0.0f;
                    if (isfinite(m) && m > 0.0f)
                        v += m;
                }
            }
            }
            out[idx] = (float)v;
        }
    }
}
