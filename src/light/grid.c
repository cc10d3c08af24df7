/* The light-space grid: sun direction, frame across the light, bounds, texture mapping. */
#include <math.h>
#include <string.h>

#include "common/log.h"
#include "light/light.h"

#define PI 3.14159265358979323846

#define MAX_NODES 4096

/* sin and cos of an angle in degrees, exact at multiples of 90 degrees. */
static void sin_cos_deg(double deg, double *s, double *c)
{
    double r = fmod(deg, 360.0);
    if (r < 0.0)
        r += 360.0;
    if (r == 0.0) {
        *s = 0.0, *c = 1.0;
    } else if (r == 90.0) {
        *s = 1.0, *c = 0.0;
    } else if (r == 180.0) {
        *s = 0.0, *c = -1.0;
    } else if (r == 270.0) {
        *s = -1.0, *c = 0.0;
    } else {
        double a = r * (PI / 180.0);
        *s = sin(a);
        *c = cos(a);
    }
}

void light_sun_direction(double azimuth_deg, double elevation_deg, double out[3])
{
    double sa, ca, se, ce;
    sin_cos_deg(azimuth_deg, &sa, &ca);
    sin_cos_deg(elevation_deg, &se, &ce);
    out[0] = sa * ce;
    out[1] = ca * ce;
    out[2] = se;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static bool box_valid(const struct grid3 *b)
{
    for (int a = 0; a < 3; a++) {
        if (b->n[a] < 1 || !(b->spacing[a] > 0.0) || !isfinite(b->spacing[a]) ||
            !isfinite(b->origin[a]))
            return false;
    }
    return true;
}

/* Corner C (bits: x, y, z) of BOX, metres. */
static void box_corner(const struct grid3 *box, int c, double p[3])
{
    for (int a = 0; a < 3; a++)
        p[a] = box->origin[a] + ((c >> a) & 1) * box->n[a] * box->spacing[a];
}

/* Node spacing from the bounds; false (logged) when an axis has no extent. */
static bool set_steps(struct light_grid *g)
{
    for (int a = 0; a < 3; a++) {
        g->step[a] = (g->hi[a] - g->lo[a]) / (g->n[a] - 1);
        if (!(g->step[a] > 0.0)) {
            log_error("light map: volume box has no extent across the light");
            return false;
        }
    }
    return true;
}

/* M^-1 of the 3 x 3 matrix whose columns are A, B, C; false when singular. */
static bool invert_columns(const double a[3], const double b[3], const double c[3],
                           double inv[3][3])
{
    double bc[3], ca[3], ab[3];
    cross3(b, c, bc);
    cross3(c, a, ca);
    cross3(a, b, ab);
    double det = dot3(a, bc);
    if (!(fabs(det) > 0.0) || !isfinite(det))
        return false;
    for (int x = 0; x < 3; x++) {
        inv[0][x] = bc[x] / det;
        inv[1][x] = ca[x] / det;
        inv[2][x] = ab[x] / det;
    }
    return true;
}

/* The sheared grid: u horizontal across the light (already set), v horizontal along the
 * light's heading, node planes at equal heights from the sun's side of the box to the other,
 * columns along the light.  The first plane's extent covers where every box corner's column
 * enters it. */
static bool sheared_init(struct light_grid *g, const struct grid3 *box)
{
    const int *n = g->n;
    double wh = sqrt(g->w[0] * g->w[0] + g->w[1] * g->w[1]);
    g->sheared = true;
    g->v[0] = g->w[0] / wh;
    g->v[1] = g->w[1] / wh;
    g->v[2] = 0.0;
    double z0 = box->origin[2], z1 = z0 + box->n[2] * box->spacing[2];
    double first = g->w[2] < 0.0 ? z1 : z0; /* the light enters at the top when the sun is up */
    double height = z1 - z0;
    double path = height / fabs(g->w[2]); /* along the light, first plane to last */
    for (int a = 0; a < 2; a++) {
        g->lo[a] = INFINITY;
        g->hi[a] = -INFINITY;
    }
    for (int c = 0; c < 8; c++) {
        double p[3];
        box_corner(box, c, p);
        double t = (p[2] - first) / g->w[2]; /* p = entry + t w */
        double e[3] = {p[0] - t * g->w[0], p[1] - t * g->w[1], first};
        double du = dot3(g->u, e), dv = dot3(g->v, e);
        g->lo[0] = fmin(g->lo[0], du);
        g->hi[0] = fmax(g->hi[0], du);
        g->lo[1] = fmin(g->lo[1], dv);
        g->hi[1] = fmax(g->hi[1], dv);
    }
    g->lo[2] = 0.0;
    g->hi[2] = path;
    if (!set_steps(g))
        return false;
    double o[3], du[3], dv[3], dw[3];
    for (int a = 0; a < 3; a++) {
        o[a] = g->lo[0] * g->u[a] + g->lo[1] * g->v[a];
        du[a] = g->u[a] * g->step[0];
        dv[a] = g->v[a] * g->step[1];
        dw[a] = g->w[a] * g->step[2];
    }
    o[2] = first; /* u and v are horizontal */
    for (int a = 0; a < 3; a++) {
        g->origin[a] = (float)o[a];
        g->du[a] = (float)du[a];
        g->dv[a] = (float)dv[a];
        g->dw[a] = (float)dw[a];
    }
    /* tex = (M^-1 (p - o) + 0.5) / n, M = [du dv dw]. */
    double inv[3][3];
    if (!invert_columns(du, dv, dw, inv)) {
        log_error("light map: the light is parallel to the box's floor");
        return false;
    }
    float *m = g->world_to_tex;
    memset(m, 0, 16 * sizeof(float));
    for (int r = 0; r < 3; r++) {
        double t = 0.5;
        for (int col = 0; col < 3; col++) {
            m[col * 4 + r] = (float)(inv[r][col] / n[r]);
            t -= inv[r][col] * o[col];
        }
        m[12 + r] = (float)(t / n[r]);
    }
    m[15] = 1.0f;
    return true;
}

bool light_grid_init(struct light_grid *g, const double sun[3], const struct grid3 *box,
                     const int n[3], enum light_grid_kind kind)
{
    memset(g, 0, sizeof(*g));
    double len = sqrt(dot3(sun, sun));
    if (!isfinite(len) || !(len > 0.0)) {
        log_error("light map: sun direction (%g, %g, %g) is not a direction", sun[0], sun[1],
                  sun[2]);
        return false;
    }
    if (!box_valid(box)) {
        log_error("light map: volume box is degenerate (%d x %d x %d voxels)", box->n[0], box->n[1],
                  box->n[2]);
        return false;
    }
    for (int a = 0; a < 3; a++) {
        if (n[a] < 2 || n[a] > MAX_NODES) {
            log_error("light map: resolution %d x %d x %d: each must be in [2, %d]", n[0], n[1],
                      n[2], MAX_NODES);
            return false;
        }
    }

    for (int a = 0; a < 3; a++) {
        g->sun[a] = sun[a] / len;
        g->w[a] = -g->sun[a];
        g->n[a] = n[a];
    }
    /* u across the light: horizontal (z x w) unless w is near vertical, then x x w.  Either
     * cross product has length >= 0.43, so the normalisation is well conditioned. */
    static const double axis_z[3] = {0.0, 0.0, 1.0};
    static const double axis_x[3] = {1.0, 0.0, 0.0};
    const double *helper = fabs(g->w[2]) <= 0.9 ? axis_z : axis_x;
    cross3(helper, g->w, g->u);
    double ul = sqrt(dot3(g->u, g->u));
    for (int a = 0; a < 3; a++)
        g->u[a] /= ul;
    cross3(g->w, g->u, g->v); /* unit: w and u are orthonormal; then u x v = w */

    /* A box flat against the light's drift across its height gets horizontal node planes. */
    double bx = box->n[0] * box->spacing[0], by = box->n[1] * box->spacing[1];
    double bz = box->n[2] * box->spacing[2];
    double wz = fabs(g->w[2]), wh = sqrt(g->w[0] * g->w[0] + g->w[1] * g->w[1]);
    if (kind == LIGHT_GRID_AUTO && wz <= 0.9 && wz >= 0.05 && bz * wh / wz <= 0.25 * fmin(bx, by))
        return sheared_init(g, box);

    /* Bounds: the 8 box corners projected on u, v, w. */
    const double *axes[3] = {g->u, g->v, g->w};
    for (int a = 0; a < 3; a++) {
        g->lo[a] = INFINITY;
        g->hi[a] = -INFINITY;
    }
    for (int c = 0; c < 8; c++) {
        double p[3];
        box_corner(box, c, p);
        for (int a = 0; a < 3; a++) {
            double d = dot3(axes[a], p);
            g->lo[a] = fmin(g->lo[a], d);
            g->hi[a] = fmax(g->hi[a], d);
        }
    }
    if (!set_steps(g))
        return false;

    double origin[3];
    light_grid_node_world(g, 0, 0, 0, origin);
    for (int a = 0; a < 3; a++) {
        g->origin[a] = (float)origin[a];
        g->du[a] = (float)(g->u[a] * g->step[0]);
        g->dv[a] = (float)(g->v[a] * g->step[1]);
        g->dw[a] = (float)(g->w[a] * g->step[2]);
    }

    /* tex_a = ((axis_a . p - lo_a) / step_a + 0.5) / n_a, column-major. */
    float *m = g->world_to_tex;
    memset(m, 0, 16 * sizeof(float));
    for (int r = 0; r < 3; r++) {
        double s = 1.0 / (g->step[r] * n[r]);
        for (int col = 0; col < 3; col++)
            m[col * 4 + r] = (float)(axes[r][col] * s);
        m[12 + r] = (float)((0.5 - g->lo[r] / g->step[r]) / n[r]);
    }
    m[15] = 1.0f;
    return true;
}

void light_grid_node_world(const struct light_grid *g, double i, double j, double k, double out[3])
{
    if (g->sheared) {
        double c = k * g->step[2];
        double a = g->lo[0] + i * g->step[0], b = g->lo[1] + j * g->step[1];
        for (int x = 0; x < 3; x++)
            out[x] = a * g->u[x] + b * g->v[x] + c * g->w[x];
        out[2] += (double)g->origin[2]; /* u, v horizontal: the first plane's height */
        return;
    }
    double a = g->lo[0] + i * g->step[0];
    double b = g->lo[1] + j * g->step[1];
    double c = g->lo[2] + k * g->step[2];
    for (int x = 0; x < 3; x++)
        out[x] = a * g->u[x] + b * g->v[x] + c * g->w[x];
}

void light_grid_world_to_tex(const struct light_grid *g, const double p[3], double out[3])
{
    const float *m = g->world_to_tex;
    for (int r = 0; r < 3; r++)
        out[r] = m[r] * p[0] + m[4 + r] * p[1] + m[8 + r] * p[2] + m[12 + r];
}
