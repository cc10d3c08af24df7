/*
 * Single-screen backends: headless (offscreen views, any number of walls), desktop (one mono
 * window) and stereo (one window: side-by-side, red/cyan anaglyph, or quad-buffer where the
 * driver has it, anaglyph where it does not).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "display/display_impl.h"
#include "render/camera.h"

struct desktop {
    struct display base;
    enum display_stereo mode;    /* what is shown (after any fallback) */
    struct gpu_texture scratch;  /* tone-mapped image on its way to the window */
};

/* ---- headless ------------------------------------------------------------------------ */

static struct display *headless_create(const struct display *base)
{
    struct desktop *h = calloc(1, sizeof(*h));
    if (!h)
        return NULL;
    h->base = *base;
    h->base.desc.offscreen = true;
    if (!display_open_primary(&h->base, 0, 0, -1, false, NULL)) {
        free(h);
        return NULL;
    }
    return &h->base;
}

static void desktop_destroy(struct display *d)
{
    struct desktop *k = (struct desktop *)d;
    gpu_texture_finish(&k->scratch);
    display_close_primary(d);
    free(k);
}

static bool headless_layout(struct display *d, const struct display_pose *head,
                            const struct display_navigation *nav,
                            const struct display_camera *camera)
{
    int sizes[DISPLAY_MAX_WALLS][2];
    display_offscreen_sizes(d, sizes);
    view_set_layout(&d->set, &d->cfg, nav, head, (const int(*)[2])sizes);
    return true;
}

static bool headless_present(struct display *d, struct renderer *r, float exposure)
{
    return true;
}

const struct display_impl display_headless_impl = {
    .name = "headless",
    .description = "offscreen views only (every wall and eye to files): batch rendering, tests",
    .create = headless_create,
    .destroy = desktop_destroy,
    .layout = headless_layout,
    .present = headless_present,
};

/* ---- desktop and stereo -------------------------------------------------------------- */

/* Widens or narrows WALL about its centre so that width / height = ASPECT (a desktop window
 * can take any shape; the screen's height stays as configured). */
static void fit_aspect(struct display_wall *wall, double aspect)
{
    double right[3], up2 = 0.0, r2 = 0.0;
    for (int i = 0; i < 3; i++) {
        right[i] = wall->lower_right[i] - wall->lower_left[i];
        double u = wall->upper_left[i] - wall->lower_left[i];
        up2 += u * u;
        r2 += right[i] * right[i];
    }
    double scale = aspect * sqrt(up2) / sqrt(r2);
    for (int i = 0; i < 3; i++) {
        double centre = wall->lower_left[i] + 0.5 * right[i];
        double half = 0.5 * right[i] * scale;
        double shift = (centre - half) - wall->lower_left[i];
        wall->lower_left[i] += shift;
        wall->upper_left[i] += shift;
        wall->lower_right[i] = centre + half;
    }
}

static struct display *single_create(const struct display *base, bool stereo_type)
{
    struct desktop *k = calloc(1, sizeof(*k));
    if (!k)
        return NULL;
    k->base = *base;
    struct display *d = &k->base;
    if (d->cfg.wall_count > 1)
        log_warn("%s: a %s display shows the first wall (\"%s\") only", d->cfg.path,
                 d->impl->name, d->cfg.walls[0].name);
    d->cfg.wall_count = 1;
    k->mode = stereo_type ? d->cfg.walls[0].stereo : DISPLAY_STEREO_MONO;
    if (stereo_type && k->mode == DISPLAY_STEREO_PASSIVE) {
        log_warn("%s: display.mode = \"passive\" needs a cave display whose walls name two "
                 "outputs: showing side-by-side in one window",
                 d->cfg.path);
        k->mode = DISPLAY_STEREO_SIDE_BY_SIDE;
    }
    if (stereo_type && k->mode == DISPLAY_STEREO_MONO) {
        log_warn("%s: display.mode = \"mono\" on a stereo display: using \"anaglyph\"",
                 d->cfg.path);
        k->mode = DISPLAY_STEREO_ANAGLYPH;
    }
    d->cfg.walls[0].stereo = k->mode;
    bool quad = k->mode == DISPLAY_STEREO_QUAD_BUFFER;
    if (!display_open_primary(d, d->cfg.window_size[0], d->cfg.window_size[1], d->cfg.monitor,
                              quad && !d->desc.offscreen, "anvil")) {
        free(k);
        return NULL;
    }
    if (quad && !d->desc.offscreen && !gpu_context_has_stereo(d->context)) {
        log_warn("quad-buffer stereo: this driver offers no stereo framebuffer (Mesa has "
                 "none); showing a red/cyan anaglyph instead");
        k->mode = DISPLAY_STEREO_ANAGLYPH;
        d->cfg.walls[0].stereo = k->mode;
    }
    return d;
}

static struct display *desktop_create(const struct display *base)
{
    return single_create(base, false);
}

static struct display *stereo_create(const struct display *base)
{
    return single_create(base, true);
}

static bool single_layout(struct display *d, const struct display_pose *head,
                          const struct display_navigation *nav,
                          const struct display_camera *camera)
{
    struct desktop *k = (struct desktop *)d;
    int sizes[DISPLAY_MAX_WALLS][2];
    struct display_config cfg = d->cfg;
    if (d->desc.offscreen) {
        display_offscreen_sizes(d, sizes);
    } else {
        int w, h;
        gpu_context_size(d->context, &w, &h);
        if (w < 2 || h < 1)
            w = 2, h = 1; /* minimised: keep valid sizes */
        if (k->mode == DISPLAY_STEREO_SIDE_BY_SIDE)
            w /= 2;
        sizes[0][0] = w;
        sizes[0][1] = h;
        fit_aspect(&cfg.walls[0], (double)w / h);
    }
    view_set_layout(&d->set, &cfg, nav, head, (const int(*)[2])sizes);
    return true;
}

static bool single_present(struct display *d, struct renderer *r, float exposure)
{
    struct desktop *k = (struct desktop *)d;
    struct view *left = &d->set.views[0];
    struct view *right = d->set.count > 1 ? &d->set.views[1] : left;
    if (!left->target.id || !right->target.id)
        return d->desc.offscreen; /* nothing drawn: the eye is behind the screen */
    int w = left->target.size[0], h = left->target.size[1];
    const struct gpu_texture *shown = &left->target;
    switch (k->mode) {
    case DISPLAY_STEREO_MONO:
    case DISPLAY_STEREO_QUAD_BUFFER:
    case DISPLAY_STEREO_PASSIVE: /* not shown here: single_create makes it side-by-side */
        d->output_count = 0;
        break;
    case DISPLAY_STEREO_SIDE_BY_SIDE: {
        struct display_output *o = display_output_ensure(d, 0, "screen", 2 * w, h);
        if (!o || !display_compose(d, &left->target, NULL, 0, &o->hdr, 0, 0) ||
            !display_compose(d, &right->target, NULL, 0, &o->hdr, w, 0))
            return false;
        shown = &o->hdr;
        break;
    }
    case DISPLAY_STEREO_ANAGLYPH: {
        struct display_output *o = display_output_ensure(d, 0, "screen", w, h);
        if (!o || !display_compose(d, &left->target, &right->target, 1, &o->hdr, 0, 0))
            return false;
        shown = &o->hdr;
        break;
    }
    }
    if (d->desc.offscreen)
        return true;
    if (k->mode != DISPLAY_STEREO_QUAD_BUFFER)
        return display_show_window(d, r, shown, exposure, &k->scratch);
    int fw, fh;
    gpu_context_size(d->context, &fw, &fh);
    if (!display_show(r, &left->target, exposure, &k->scratch, 0, 0, fw, fh, 1) ||
        !display_show(r, &right->target, exposure, &k->scratch, 0, 0, fw, fh, 2))
        return false;
    display_before_swap(d);
    gpu_context_swap(d->context);
    return true;
}

const struct display_impl display_desktop_impl = {
    .name = "desktop",
    .description = "one mono window on the desktop (the screen as a wall, a fixed head)",
    .create = desktop_create,
    .destroy = desktop_destroy,
    .layout = single_layout,
    .present = single_present,
};

const struct display_impl display_stereo_impl = {
    .name = "stereo",
    .description = "one window in stereo: side-by-side, red/cyan anaglyph, or quad-buffer "
                   "(GLFW_STEREO; anaglyph where the driver has none)",
    .create = stereo_create,
    .destroy = desktop_destroy,
    .layout = single_layout,
    .present = single_present,
};

/* ---- orbit: the scene's own camera ------------------------------------------------------ */

/* One mono view of the world camera the caller gives (anvil run and render without
 * --display): a window of display.window_size (the scene's render.width x render.height), or
 * offscreen an image of that size. */
static struct display *orbit_create(const struct display *base)
{
    struct desktop *k = calloc(1, sizeof(*k));
    if (!k)
        return NULL;
    k->base = *base;
    struct display *d = &k->base;
    d->cfg.wall_count = 0;
    k->mode = DISPLAY_STEREO_MONO;
    if (!display_open_primary(d, d->cfg.window_size[0], d->cfg.window_size[1], d->cfg.monitor,
                              false, "anvil")) {
        free(k);
        return NULL;
    }
    return d;
}

static bool orbit_layout(struct display *d, const struct display_pose *head,
                         const struct display_navigation *nav, const struct display_camera *camera)
{
    int w = d->cfg.window_size[0], h = d->cfg.window_size[1];
    if (!d->desc.offscreen)
        gpu_context_size(d->context, &w, &h);
    struct view *v = &d->set.views[0];
    snprintf(v->name, sizeof(v->name), "view");
    v->wall = 0;
    v->eye = VIEW_EYE_MONO;
    v->visible = w > 0 && h > 0; /* a minimised window draws nothing */
    camera_look_at(camera->eye, camera->target, camera->up, camera->fov_deg, camera->near_m,
                   camera->far_m, w > 0 ? w : 1, h > 0 ? h : 1, &v->rv);
    for (int i = 0; i < 3; i++)
        v->eye_tracker[i] = (float)camera->eye[i];
    d->set.count = 1;
    return true;
}

static bool orbit_present(struct display *d, struct renderer *r, float exposure)
{
    struct desktop *k = (struct desktop *)d;
    const struct view *v = &d->set.views[0];
    if (d->desc.offscreen || !v->visible || !v->target.id)
        return true;
    return display_show_window(d, r, &v->target, exposure, &k->scratch);
}

const struct display_impl display_orbit_impl = {
    .name = "orbit",
    .description = "one window of the scene's own camera (camera.*), orbiting its target: "
                   "anvil run and render without --display",
    .create = orbit_create,
    .destroy = desktop_destroy,
    .layout = orbit_layout,
    .present = orbit_present,
};
