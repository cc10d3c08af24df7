/*
 * HMD through OpenHMD: per-eye view and projection matrices from the device, one render target
 * per eye, then the lens pre-distortion with the device's own lens model and parameters
 * (universal distortion and aberration coefficients, lens separation, panel size), ported to
 * shaders/hmd_warp.comp: OpenHMD's own GLSL is #version 120 with fixed-function built-ins,
 * which a 4.5 core context does not compile.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cglm/cglm.h>
#include <openhmd.h>

#include "common/log.h"
#include "display/display_impl.h"
#include "shaders/bindings.h"

struct hmd {
    struct display base;
    ohmd_device *device; /* shared with a head tracker on the same device (input_ohmd_open) */
    int resolution[2];       /* panel pixels */
    float screen_size[2];    /* panel metres */
    float lens_separation;   /* metres */
    float lens_vertical;     /* metres */
    float ipd;               /* metres */
    float aspect;            /* of one eye */
    float distortion[4];     /* [a, b, c, d] */
    float aberration[3];
    struct gpu_program warp;
    struct gpu_texture scratch;
};

static void hmd_destroy(struct display *d)
{
    struct hmd *h = (struct hmd *)d;
    if (d->context) {
        gpu_context_make_current(d->context);
        gpu_program_finish(&h->warp);
        gpu_texture_finish(&h->scratch);
    }
    display_close_primary(d);
    input_ohmd_close(h->device);
    free(h);
}

static struct display *hmd_create(const struct display *base)
{
    struct hmd *h = calloc(1, sizeof(*h));
    if (!h)
        return NULL;
    h->base = *base;
    struct display *d = &h->base;
    const struct display_config *cfg = &d->cfg;
    h->device = input_ohmd_open(cfg->hmd.device, OHMD_DEVICE_CLASS_HMD);
    if (!h->device) {
        display_fail(d, DISPLAY_FAILED_INPUT); /* no such device */
        goto error;
    }
    ohmd_device_geti(h->device, OHMD_SCREEN_HORIZONTAL_RESOLUTION, &h->resolution[0]);
    ohmd_device_geti(h->device, OHMD_SCREEN_VERTICAL_RESOLUTION, &h->resolution[1]);
    ohmd_device_getf(h->device, OHMD_SCREEN_HORIZONTAL_SIZE, &h->screen_size[0]);
    ohmd_device_getf(h->device, OHMD_SCREEN_VERTICAL_SIZE, &h->screen_size[1]);
    ohmd_device_getf(h->device, OHMD_LENS_HORIZONTAL_SEPARATION, &h->lens_separation);
    ohmd_device_getf(h->device, OHMD_LENS_VERTICAL_POSITION, &h->lens_vertical);
    ohmd_device_getf(h->device, OHMD_EYE_IPD, &h->ipd);
    ohmd_device_getf(h->device, OHMD_LEFT_EYE_ASPECT_RATIO, &h->aspect);
    ohmd_device_getf(h->device, OHMD_UNIVERSAL_DISTORTION_K, h->distortion);
    ohmd_device_getf(h->device, OHMD_UNIVERSAL_ABERRATION_K, h->aberration);
    for (int i = 0; i < 4 && cfg->hmd.distortion_set; i++)
        h->distortion[i] = (float)cfg->hmd.distortion[i];
    for (int i = 0; i < 3 && cfg->hmd.aberration_set; i++)
        h->aberration[i] = (float)cfg->hmd.aberration[i];
    if (!(h->screen_size[0] > 0.0f && h->screen_size[1] > 0.0f && h->aspect > 0.0f)) {
        log_error("OpenHMD: the device reports no panel size");
        display_fail(d, DISPLAY_FAILED_INPUT);
        goto error;
    }
    float near = (float)cfg->near_m, far = (float)cfg->far_m;
    ohmd_device_setf(h->device, OHMD_PROJECTION_ZNEAR, &near);
    ohmd_device_setf(h->device, OHMD_PROJECTION_ZFAR, &far);
    if (!d->desc.offscreen && cfg->head.source != DISPLAY_HEAD_OPENHMD)
        log_info("HMD: head pose from %s, not from the device",
                 display_head_source_name(cfg->head.source));
    else if (cfg->head.source == DISPLAY_HEAD_OPENHMD && strcmp(cfg->head.device, "null") == 0 &&
             strcmp(cfg->hmd.device, "null") != 0)
        log_warn("%s: head.device = \"null\" with hmd.device = \"%s\": the head follows the "
                 "Null device, not the headset (set head.device to the headset's name)",
                 cfg->path, cfg->hmd.device);
    int w = cfg->window_size[0], hh = cfg->window_size[1];
    if (!display_open_primary(d, w, hh, cfg->monitor, false, "anvil: hmd"))
        goto error;
    if (!gpu_program_init(&h->warp, "hmd_warp.comp", NULL))
        goto error;
    log_info("HMD: panel %dx%d, %.4f x %.4f m, lens separation %.4f m, distortion [%g %g %g %g]",
             h->resolution[0], h->resolution[1], h->screen_size[0], h->screen_size[1],
             h->lens_separation, h->distortion[0], h->distortion[1], h->distortion[2],
             h->distortion[3]);
    return d;

error:
    hmd_destroy(d);
    return NULL;
}

static bool hmd_layout(struct display *d, const struct display_pose *head,
                       const struct display_navigation *nav, const struct display_camera *camera)
{
    struct hmd *h = (struct hmd *)d;
    int size[2];
    if (d->desc.offscreen) {
        size[1] = d->desc.height;
        size[0] = (int)lroundf((float)size[1] * h->aspect);
    } else {
        gpu_context_size(d->context, &size[0], &size[1]);
        size[0] /= 2;
    }
    if (size[0] < 1)
        size[0] = 1;
    if (size[1] < 1)
        size[1] = 1;
    mat4 nav_m; /* cglm needs its matrices aligned: locals, then copies */
    display_navigation_matrix(nav, (float *)nav_m);
    input_ohmd_update();
    /* The eyes from the head pose (the device's own when head.source = "openhmd"), the
     * device's lenses and IPD: the same matrices OpenHMD's eye model gives, from a pose that
     * the frame state can carry. */
    float eyes[2][3];
    display_pose_eyes(head, h->ipd, eyes[0], eyes[1]);
    for (int e = 0; e < 2; e++) {
        struct view *v = &d->set.views[e];
        snprintf(v->name, sizeof(v->name), "%s", e == 0 ? "left" : "right");
        v->wall = 0;
        v->eye = e == 0 ? VIEW_EYE_LEFT : VIEW_EYE_RIGHT;
        v->visible = true;
        v->rv.width = size[0];
        v->rv.height = size[1];
        mat4 eye_view, view, pose;
        float proj[16];
        ohmd_device_getf(h->device,
                         e == 0 ? OHMD_LEFT_EYE_GL_PROJECTION_MATRIX
                                : OHMD_RIGHT_EYE_GL_PROJECTION_MATRIX,
                         proj);
        versor q;
        memcpy(q, head->rotation, sizeof(q));
        glm_quat_mat4(q, pose);
        for (int i = 0; i < 3; i++)
            pose[3][i] = eyes[e][i];
        glm_mat4_inv(pose, eye_view);
        memcpy(v->eye_tracker, eyes[e], sizeof(v->eye_tracker));
        glm_mat4_mul(eye_view, nav_m, view);
        memcpy(v->rv.view, view, sizeof(view));
        memcpy(v->rv.proj, proj, sizeof(proj));
    }
    d->set.count = 2;
    return true;
}

/* Warps EYE into OUT at X (the eye's half of the panel). */
static void warp_eye(struct hmd *h, const struct gpu_texture *eye, int e, struct gpu_texture *out,
                     int x)
{
    /* Each eye sees half the panel; the lens centres sit LENS_SEPARATION apart, mirrored. */
    float viewport[2] = {0.5f * h->screen_size[0], h->screen_size[1]};
    float centre[2] = {e == 0 ? viewport[0] - 0.5f * h->lens_separation
                              : 0.5f * h->lens_separation,
                       h->lens_vertical};
    float left_x = viewport[0] - 0.5f * h->lens_separation, right_x = 0.5f * h->lens_separation;
    float scale = fmaxf(left_x, right_x);
    int size[2] = {eye->size[0], eye->size[1]}, offset[2] = {x, 0};
    gpu_uniform_ivec2(&h->warp, "size", size);
    gpu_uniform_ivec2(&h->warp, "offset", offset);
    gpu_uniform_vec2(&h->warp, "viewport_scale", viewport);
    gpu_uniform_vec2(&h->warp, "lens_center", centre);
    gpu_uniform_float(&h->warp, "warp_scale", scale);
    gpu_uniform_vec4(&h->warp, "warp_param", h->distortion);
    gpu_uniform_vec3(&h->warp, "aberration", h->aberration);
    gpu_texture_bind(eye, BIND_WARP_TEX_EYE);
    gpu_image_bind(out, BIND_WARP_IMG_OUT, true);
    gpu_dispatch(&h->warp, size[0], size[1], 1);
}

static bool hmd_present(struct display *d, struct renderer *r, float exposure)
{
    struct hmd *h = (struct hmd *)d;
    const struct gpu_texture *left = &d->set.views[0].target, *right = &d->set.views[1].target;
    if (!left->id || !right->id)
        return true;
    int w = left->size[0], hh = left->size[1];
    struct display_output *o = display_output_ensure(d, 0, "screen", 2 * w, hh);
    if (!o)
        return false;
    if (d->cfg.hmd.warp) {
        warp_eye(h, left, 0, &o->hdr, 0);
        warp_eye(h, right, 1, &o->hdr, w);
    } else if (!display_compose(d, left, NULL, 0, &o->hdr, 0, 0) ||
               !display_compose(d, right, NULL, 0, &o->hdr, w, 0)) {
        return false;
    }
    if (d->desc.offscreen)
        return true;
    return display_show_window(d, r, &o->hdr, exposure, &h->scratch);
}

const struct display_impl display_hmd_impl = {
    .name = "hmd",
    .description = "head-mounted display through OpenHMD (by product name, or the Null HMD): "
                   "the device's per-eye projections and IPD, the head's pose, the device's "
                   "lens warp",
    .create = hmd_create,
    .destroy = hmd_destroy,
    .layout = hmd_layout,
    .present = hmd_present,
};
