/* Camera paths in time: Catmull-Rom through the positions, slerp between the orientations. */
#include "session/camera_path.h"

#include <math.h>
#include <string.h>

#include <cglm/cglm.h>

double camera_path_duration(const struct camera_path *p)
{
    return p->count > 0 ? p->keys[p->count - 1].time_s : 0.0;
}

void camera_path_key(const struct display_camera *camera, double t, double step,
                     struct camera_key *out)
{
    memset(out, 0, sizeof(*out));
    out->time_s = t;
    for (int i = 0; i < 3; i++) {
        out->position_km[i] = camera->eye[i] / 1000.0;
        out->target_km[i] = camera->target[i] / 1000.0;
        out->up[i] = camera->up[i];
    }
    out->fov_deg = camera->fov_deg;
    out->step = step;
}

/* The key's view as a rotation (columns right, up, back: a camera looking along -z). */
static void orientation(const struct camera_key *k, versor q)
{
    double f[3], r[3], u[3], len = 0.0;
    for (int i = 0; i < 3; i++) {
        f[i] = k->target_km[i] - k->position_km[i];
        len += f[i] * f[i];
    }
    len = sqrt(len);
    for (int i = 0; i < 3; i++)
        f[i] /= len;
    r[0] = f[1] * k->up[2] - f[2] * k->up[1];
    r[1] = f[2] * k->up[0] - f[0] * k->up[2];
    r[2] = f[0] * k->up[1] - f[1] * k->up[0];
    double rl = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int i = 0; i < 3; i++)
        r[i] /= rl;
    u[0] = r[1] * f[2] - r[2] * f[1];
    u[1] = r[2] * f[0] - r[0] * f[2];
    u[2] = r[0] * f[1] - r[1] * f[0];
    mat3 m;
    for (int i = 0; i < 3; i++) {
        m[0][i] = (float)r[i];
        m[1][i] = (float)u[i];
        m[2][i] = (float)-f[i];
    }
    glm_mat3_quat(m, q);
}

static double distance_km(const struct camera_key *k)
{
    double d = 0.0;
    for (int i = 0; i < 3; i++)
        d += (k->target_km[i] - k->position_km[i]) * (k->target_km[i] - k->position_km[i]);
    return sqrt(d);
}

static void lerp3(const double a[3], const double b[3], double s, double out[3])
{
    for (int i = 0; i < 3; i++)
        out[i] = a[i] + s * (b[i] - a[i]);
}

/* The point at T of the Catmull-Rom segment between P1 (at T1) and P2 (at T2), with P0 (at
 * T0) and P3 (at T3) its neighbours: Barry and Goldman's pyramid of linear interpolations. */
static void catmull_rom(const double p[4][3], const double tk[4], double t, double out[3])
{
    double a1[3], a2[3], a3[3], b1[3], b2[3];
    lerp3(p[0], p[1], (t - tk[0]) / (tk[1] - tk[0]), a1);
    lerp3(p[1], p[2], (t - tk[1]) / (tk[2] - tk[1]), a2);
    lerp3(p[2], p[3], (t - tk[2]) / (tk[3] - tk[2]), a3);
    lerp3(a1, a2, (t - tk[0]) / (tk[2] - tk[0]), b1);
    lerp3(a2, a3, (t - tk[1]) / (tk[3] - tk[1]), b2);
    lerp3(b1, b2, (t - tk[1]) / (tk[2] - tk[1]), out);
}

static void from_key(const struct camera_key *k, const struct display_camera *base,
                     struct display_camera *out)
{
    *out = *base;
    for (int i = 0; i < 3; i++) {
        out->eye[i] = k->position_km[i] * 1000.0;
        out->target[i] = k->target_km[i] * 1000.0;
        out->up[i] = k->up[i];
    }
    out->fov_deg = k->fov_deg;
}

void camera_path_eval(const struct camera_path *p, double t, const struct display_camera *base,
                      struct display_camera *out, double *step)
{
    *out = *base;
    if (p->count < 1)
        return;
    int n = p->count;
    /* The keys themselves, and the hold before the first and after the last. */
    int at = -1;
    if (t <= p->keys[0].time_s)
        at = 0;
    else if (t >= p->keys[n - 1].time_s)
        at = n - 1;
    for (int i = 0; at < 0 && i < n; i++)
        if (p->keys[i].time_s == t)
            at = i;
    if (at >= 0) {
        from_key(&p->keys[at], base, out);
        if (step && p->has_steps)
            *step = p->keys[at].step;
        return;
    }
    int i = 0;
    while (i + 1 < n && p->keys[i + 1].time_s <= t)
        i++;
    const struct camera_key *k1 = &p->keys[i], *k2 = &p->keys[i + 1];
    /* Neighbours: the keys beyond, or at the ends the mirror of the next one (a straight
     * start and end). */
    double pts[4][3], tk[4];
    memcpy(pts[1], k1->position_km, sizeof(pts[1]));
    memcpy(pts[2], k2->position_km, sizeof(pts[2]));
    tk[1] = k1->time_s;
    tk[2] = k2->time_s;
    if (i > 0) {
        memcpy(pts[0], p->keys[i - 1].position_km, sizeof(pts[0]));
        tk[0] = p->keys[i - 1].time_s;
    } else {
        for (int a = 0; a < 3; a++)
            pts[0][a] = 2.0 * pts[1][a] - pts[2][a];
        tk[0] = 2.0 * tk[1] - tk[2];
    }
    if (i + 2 < n) {
        memcpy(pts[3], p->keys[i + 2].position_km, sizeof(pts[3]));
        tk[3] = p->keys[i + 2].time_s;
    } else {
        for (int a = 0; a < 3; a++)
            pts[3][a] = 2.0 * pts[2][a] - pts[1][a];
        tk[3] = 2.0 * tk[2] - tk[1];
    }
    double pos[3];
    catmull_rom(pts, tk, t, pos);
    double s = (t - tk[1]) / (tk[2] - tk[1]);
    versor q1, q2, q;
    orientation(k1, q1);
    orientation(k2, q2);
    if (glm_vec4_dot(q1, q2) < 0.0f) /* the short way round */
        glm_vec4_negate(q2);
    glm_quat_slerp(q1, q2, (float)s, q);
    mat4 m;
    glm_quat_mat4(q, m);
    double dist = distance_km(k1) + s * (distance_km(k2) - distance_km(k1));
    for (int a = 0; a < 3; a++) {
        out->eye[a] = pos[a] * 1000.0;
        out->target[a] = (pos[a] - (double)m[2][a] * dist) * 1000.0;
        out->up[a] = m[1][a];
    }
    out->fov_deg = k1->fov_deg + s * (k2->fov_deg - k1->fov_deg);
    if (step && p->has_steps)
        *step = k1->step + s * (k2->step - k1->step);
}
