#include "render/camera.h"

#include <math.h>
#include <string.h>

#include <cglm/cglm.h>

#define DEG (M_PI / 180.0)

void camera_look_at(const double eye[3], const double target[3], const double up[3],
                    double fov_deg, double near_m, double far_m, int width, int height,
                    struct render_view *view)
{
    vec3 e = {(float)eye[0], (float)eye[1], (float)eye[2]};
    vec3 t = {(float)target[0], (float)target[1], (float)target[2]};
    vec3 u = {(float)up[0], (float)up[1], (float)up[2]};
    mat4 v, p;
    glm_lookat(e, t, u, v);
    glm_perspective((float)(fov_deg * DEG), (float)width / (float)height, (float)near_m,
                    (float)far_m, p);
    memcpy(view->view, v, sizeof(v));
    memcpy(view->proj, p, sizeof(p));
    view->width = width;
    view->height = height;
}

void camera_direction(double azimuth_deg, double elevation_deg, double out[3])
{
    double az = azimuth_deg * DEG, el = elevation_deg * DEG;
    out[0] = sin(az) * cos(el);
    out[1] = cos(az) * cos(el);
    out[2] = sin(el);
}

void camera_orbit_from(const double eye[3], const double target[3], struct camera_orbit *o)
{
    double d[3] = {eye[0] - target[0], eye[1] - target[1], eye[2] - target[2]};
    double r = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int i = 0; i < 3; i++)
        o->target[i] = target[i];
    o->distance_m = r;
    o->elevation_deg = r > 0.0 ? asin(d[2] / r) / DEG : 0.0;
    o->azimuth_deg = atan2(d[0], d[1]) / DEG;
}

void camera_orbit_eye(const struct camera_orbit *o, double eye[3])
{
    double dir[3];
    camera_direction(o->azimuth_deg, o->elevation_deg, dir);
    for (int i = 0; i < 3; i++)
        eye[i] = o->target[i] + o->distance_m * dir[i];
}
