/*
 * The math of views: poses, the navigation transform, Kooima's generalized perspective for a
 * screen given by three corners, and the layout of walls and eyes into a view set.  No GL.
 */
#include "display/display.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <cglm/cglm.h>

#define DEG ((float)(M_PI / 180.0))

void display_pose_from_euler(const double position[3], const double hpr_deg[3],
                             struct display_pose *out)
{
    versor qh, qp, qr, q;
    glm_quatv(qh, (float)hpr_deg[0] * DEG, (vec3){0.0f, 1.0f, 0.0f});
    glm_quatv(qp, (float)hpr_deg[1] * DEG, (vec3){1.0f, 0.0f, 0.0f});
    glm_quatv(qr, (float)hpr_deg[2] * DEG, (vec3){0.0f, 0.0f, 1.0f});
    glm_quat_mul(qh, qp, q);
    glm_quat_mul(q, qr, q);
    glm_quat_normalize(q);
    for (int i = 0; i < 3; i++)
        out->position[i] = (float)position[i];
    memcpy(out->rotation, q, sizeof(float) * 4);
}

void display_navigation_matrix(const struct display_navigation *nav, float out[16])
{
    /* World axes to tracker axes: east -> x, north -> -z, up -> y. */
    mat4 axes = {{1, 0, 0, 0}, {0, 0, -1, 0}, {0, 1, 0, 0}, {0, 0, 0, 1}};
    mat4 m, r;
    glm_translate_make(m, (vec3){(float)nav->position[0], (float)nav->position[1],
                                 (float)nav->position[2]});
    const double *o = nav->orientation_deg;
    glm_rotate_make(r, (float)o[2] * DEG, (vec3){0.0f, 0.0f, 1.0f});
    glm_rotate(r, (float)o[1] * DEG, (vec3){1.0f, 0.0f, 0.0f});
    glm_rotate(r, (float)o[0] * DEG, (vec3){0.0f, 1.0f, 0.0f});
    glm_mat4_mul(m, r, m);
    glm_scale_uni(m, (float)nav->scale);
    glm_mat4_mul(m, axes, m);
    glm_translate(m, (vec3){(float)(-nav->origin_km[0] * 1000.0),
                            (float)(-nav->origin_km[1] * 1000.0),
                            (float)(-nav->origin_km[2] * 1000.0)});
    memcpy(out, m, sizeof(m));
}

void display_pose_eyes(const struct display_pose *head, double separation, float left[3],
                       float right[3])
{
    versor q;
    memcpy(q, head->rotation, sizeof(q));
    vec3 axis;
    glm_quat_rotatev(q, (vec3){1.0f, 0.0f, 0.0f}, axis);
    float h = (float)(0.5 * separation);
    for (int i = 0; i < 3; i++) {
        left[i] = head->position[i] - h * axis[i];
        right[i] = head->position[i] + h * axis[i];
    }
}

void display_pose_compose(const struct display_pose *a, const struct display_pose *b,
                          struct display_pose *out)
{
    versor qa, qb, q;
    vec3 p;
    memcpy(qa, a->rotation, sizeof(qa));
    memcpy(qb, b->rotation, sizeof(qb));
    glm_quat_rotatev(qa, (float *)b->position, p);
    glm_quat_mul(qa, qb, q);
    glm_quat_normalize(q);
    for (int i = 0; i < 3; i++)
        out->position[i] = a->position[i] + p[i];
    memcpy(out->rotation, q, sizeof(q));
}

void display_pose_invert(const struct display_pose *p, struct display_pose *out)
{
    versor q, qi;
    vec3 t;
    memcpy(q, p->rotation, sizeof(q));
    glm_quat_inv(q, qi);
    glm_quat_rotatev(qi, (float *)p->position, t);
    for (int i = 0; i < 3; i++)
        out->position[i] = -t[i];
    memcpy(out->rotation, qi, sizeof(qi));
}

void display_pose_view(const struct display_pose *eye, const float nav[16], float view[16])
{
    mat4 pose, inv, n, v;
    versor q;
    memcpy(q, eye->rotation, sizeof(q));
    glm_quat_mat4(q, pose);
    for (int i = 0; i < 3; i++)
        pose[3][i] = eye->position[i];
    glm_mat4_inv(pose, inv);
    memcpy(n, nav, sizeof(n));
    glm_mat4_mul(inv, n, v);
    memcpy(view, v, sizeof(v));
}

void display_fov_projection(float left, float right, float up, float down, float near,
                            float far, float out[16])
{
    mat4 p;
    glm_frustum(near * tanf(left), near * tanf(right), near * tanf(down), near * tanf(up),
                near, far, p);
    memcpy(out, p, sizeof(p));
}

static void to_vec3(const double *d, vec3 out)
{
    out[0] = (float)d[0];
    out[1] = (float)d[1];
    out[2] = (float)d[2];
}

bool display_wall_projection(const struct display_wall *wall, const float eye[3], float near,
                             float far, float view[16], float proj[16], float extent[4])
{
    vec3 pa, pb, pc, pe, vr, vu, vn, va, vb, vc;
    to_vec3(wall->lower_left, pa);
    to_vec3(wall->lower_right, pb);
    to_vec3(wall->upper_left, pc);
    glm_vec3_copy((float *)eye, pe);
    /* The screen's orthonormal basis: right, up, normal toward the viewer. */
    glm_vec3_sub(pb, pa, vr);
    glm_vec3_sub(pc, pa, vu);
    glm_vec3_normalize(vr);
    glm_vec3_normalize(vu);
    glm_vec3_cross(vr, vu, vn);
    glm_vec3_normalize(vn);
    /* Corners relative to the eye; the eye's distance to the screen's plane. */
    glm_vec3_sub(pa, pe, va);
    glm_vec3_sub(pb, pe, vb);
    glm_vec3_sub(pc, pe, vc);
    float d = -glm_vec3_dot(va, vn);
    if (!(d > 1e-6f))
        return false;
    /* Frustum extents at the near plane: the screen's edges scaled by near / d. */
    float k = near / d;
    float l = glm_vec3_dot(vr, va) * k, r = glm_vec3_dot(vr, vb) * k;
    float b = glm_vec3_dot(vu, va) * k, t = glm_vec3_dot(vu, vc) * k;
    mat4 p;
    glm_frustum(l, r, b, t, near, far, p);
    memcpy(proj, p, sizeof(p));
    /* Rotate tracker space into the screen's basis after moving the eye to the origin. */
    mat4 v = GLM_MAT4_IDENTITY_INIT;
    for (int i = 0; i < 3; i++) {
        v[i][0] = vr[i];
        v[i][1] = vu[i];
        v[i][2] = vn[i];
    }
    v[3][0] = -glm_vec3_dot(vr, pe);
    v[3][1] = -glm_vec3_dot(vu, pe);
    v[3][2] = -glm_vec3_dot(vn, pe);
    memcpy(view, v, sizeof(v));
    if (extent) {
        extent[0] = l;
        extent[1] = r;
        extent[2] = b;
        extent[3] = t;
    }
    return true;
}

static double wall_aspect(const struct display_wall *w)
{
    double e1 = 0.0, e2 = 0.0;
    for (int i = 0; i < 3; i++) {
        double a = w->lower_right[i] - w->lower_left[i], b = w->upper_left[i] - w->lower_left[i];
        e1 += a * a;
        e2 += b * b;
    }
    return sqrt(e1 / e2);
}

void view_set_wall_size(const struct display_config *cfg, int w, int height, int out[2])
{
    const struct display_wall *wall = &cfg->walls[w];
    if (wall->size[0] > 0 && wall->size[1] > 0) {
        out[0] = wall->size[0];
        out[1] = wall->size[1];
        return;
    }
    out[1] = height > 0 ? height : 1;
    int width = (int)lround(out[1] * wall_aspect(wall));
    out[0] = width > 0 ? width : 1;
}

static void set_view(struct view *v, const char *name, int wall, enum view_eye eye)
{
    if (strcmp(v->name, name) != 0 || v->wall != wall || v->eye != eye) {
        snprintf(v->name, sizeof(v->name), "%s", name);
        v->wall = wall;
        v->eye = eye;
    }
}

void view_set_layout(struct view_set *set, const struct display_config *cfg,
                     const struct display_navigation *navigation, const struct display_pose *head,
                     const int (*sizes)[2])
{
    mat4 nav;
    display_navigation_matrix(navigation, (float *)nav);
    float eyes[2][3];
    display_pose_eyes(head, cfg->eye_separation, eyes[0], eyes[1]);
    int n = 0;
    for (int w = 0; w < cfg->wall_count && n + 2 <= DISPLAY_MAX_VIEWS; w++) {
        const struct display_wall *wall = &cfg->walls[w];
        bool stereo = wall->stereo != DISPLAY_STEREO_MONO;
        for (int e = 0; e < (stereo ? 2 : 1); e++) {
            struct view *v = &set->views[n++];
            char name[48];
            if (stereo)
                snprintf(name, sizeof(name), "%s-%s", wall->name, e == 0 ? "left" : "right");
            else
                snprintf(name, sizeof(name), "%s", wall->name);
            set_view(v, name, w, stereo ? (e == 0 ? VIEW_EYE_LEFT : VIEW_EYE_RIGHT)
                                        : VIEW_EYE_MONO);
            const float *eye = stereo ? eyes[e] : head->position;
            memcpy(v->eye_tracker, eye, sizeof(v->eye_tracker));
            mat4 wall_view, view; /* cglm needs its matrices aligned: locals, then copies */
            v->visible = display_wall_projection(wall, eye, (float)cfg->near_m,
                                                 (float)cfg->far_m, (float *)wall_view,
                                                 v->rv.proj, v->extent);
            glm_mat4_mul(wall_view, nav, view);
            memcpy(v->rv.view, view, sizeof(view));
            v->rv.width = sizes[w][0];
            v->rv.height = sizes[w][1];
        }
    }
    set->count = n;
}

int view_set_fixed(const struct display_config *cfg, int height, struct view_set *set)
{
    memset(set, 0, sizeof(*set));
    if (cfg->type == DISPLAY_TYPE_HMD || cfg->type == DISPLAY_TYPE_OPENXR ||
        cfg->type == DISPLAY_TYPE_ORBIT || cfg->head.source != DISPLAY_HEAD_FIXED)
        return 0;
    int sizes[DISPLAY_MAX_WALLS][2];
    for (int w = 0; w < cfg->wall_count; w++)
        view_set_wall_size(cfg, w, height, sizes[w]);
    struct display_pose head;
    display_pose_from_euler(cfg->head.position, cfg->head.orientation_deg, &head);
    view_set_layout(set, cfg, &cfg->navigation, &head, (const int(*)[2])sizes);
    return set->count;
}

void view_set_finish(struct view_set *set)
{
    if (!set)
        return;
    for (int i = 0; i < DISPLAY_MAX_VIEWS; i++)
        gpu_texture_finish(&set->views[i].target);
    set->count = 0;
}
