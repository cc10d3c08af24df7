/*
 * CAVE: walls given by three corners each, every wall in its own window (fullscreen on its
 * output, named or placed on the desktop, or on its monitor) or in a viewport of one shared
 * window; each wall mono, side-by-side, anaglyph, quad-buffer or passive (each eye in its own
 * window on its own output: two projectors per wall).  All views are drawn and composed in
 * the primary context; the windows (sharing its textures) then only blit, and swap together:
 * only the last one waits for the vertical blank.
 */
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "display/display_impl.h"

#define MAX_WINDOWS (2 * DISPLAY_MAX_WALLS + 1)

struct cave {
    struct display base;
    struct gpu_context *windows[MAX_WINDOWS]; /* [0] is the primary context */
    int window_count;
    int wall_window[DISPLAY_MAX_WALLS];        /* which window shows each wall */
    int right_window[DISPLAY_MAX_WALLS];       /* passive walls: the right eye's window */
    enum display_stereo mode[DISPLAY_MAX_WALLS]; /* after any fallback */
    struct gpu_texture composed[DISPLAY_MAX_WALLS];
    struct gpu_texture ldr[DISPLAY_MAX_WALLS][2];
};

static bool has_viewport(const struct display_wall *w)
{
    return w->viewport[2] > 0 && w->viewport[3] > 0;
}

static void cave_destroy(struct display *d)
{
    struct cave *c = (struct cave *)d;
    if (d->context)
        gpu_context_make_current(d->context);
    for (int w = 0; w < DISPLAY_MAX_WALLS; w++) {
        gpu_texture_finish(&c->composed[w]);
        gpu_texture_finish(&c->ldr[w][0]);
        gpu_texture_finish(&c->ldr[w][1]);
    }
    for (int i = c->window_count - 1; i >= 1; i--)
        gpu_context_destroy(c->windows[i]);
    display_close_primary(d);
    free(c);
}

static struct display *cave_create(const struct display *base)
{
    struct cave *c = calloc(1, sizeof(*c));
    if (!c)
        return NULL;
    c->base = *base;
    struct display *d = &c->base;
    const struct display_config *cfg = &d->cfg;
    for (int w = 0; w < cfg->wall_count; w++)
        c->mode[w] = cfg->walls[w].stereo;
    if (d->desc.offscreen) {
        if (!display_open_primary(d, 0, 0, -1, false, NULL))
            goto error;
        c->windows[0] = d->context;
        c->window_count = 1;
        return d;
    }

    /* The shared window comes first when any wall lives in a viewport of it. */
    bool shared = false, shared_quad = false;
    for (int w = 0; w < cfg->wall_count; w++) {
        if (has_viewport(&cfg->walls[w])) {
            shared = true;
            shared_quad = shared_quad || c->mode[w] == DISPLAY_STEREO_QUAD_BUFFER;
        }
    }
    if (shared) {
        if (!display_open_primary(d, cfg->window_size[0], cfg->window_size[1], cfg->monitor,
                                  shared_quad, "anvil: cave"))
            goto error;
        c->windows[c->window_count++] = d->context;
    }
    for (int w = 0; w < cfg->wall_count; w++) {
        const struct display_wall *wall = &cfg->walls[w];
        c->right_window[w] = -1;
        if (has_viewport(wall)) {
            c->wall_window[w] = 0;
            continue;
        }
        int size[2];
        view_set_wall_size(cfg, w, cfg->window_size[1], size);
        bool passive = c->mode[w] == DISPLAY_STEREO_PASSIVE;
        for (int eye = 0; eye < (passive ? 2 : 1); eye++) {
            char title[80];
            snprintf(title, sizeof(title), "anvil: %s%s", wall->name,
                     !passive ? "" : eye == 0 ? " (left eye)" : " (right eye)");
            struct gpu_context_desc cd = {
                .backend = "glfw",
                .width = size[0],
                .height = size[1],
                .title = title,
                .monitor = eye == 0 ? wall->monitor : -1,
                .stereo = c->mode[w] == DISPLAY_STEREO_QUAD_BUFFER,
                .output = eye == 0 ? wall->output : wall->right_output,
                .rect_set = eye == 0 ? wall->window_set : wall->right_window_set,
            };
            memcpy(cd.rect, eye == 0 ? wall->window : wall->right_window, sizeof(cd.rect));
            if (c->window_count == 0) {
                if (!display_open_primary_on(d, &cd))
                    goto error;
                c->windows[c->window_count++] = d->context;
            } else {
                cd.share_window = gpu_context_window(d->context);
                struct gpu_context *ctx = gpu_context_create(&cd);
                if (!ctx) {
                    display_fail(d, DISPLAY_FAILED_CONTEXT);
                    goto error;
                }
                display_watch_window(d, gpu_context_window(ctx));
                display_join_swap_group(d, ctx);
                c->windows[c->window_count++] = ctx;
            }
            *(eye == 0 ? &c->wall_window[w] : &c->right_window[w]) = c->window_count - 1;
        }
    }
    for (int w = 0; w < cfg->wall_count; w++) {
        if (c->mode[w] == DISPLAY_STEREO_QUAD_BUFFER &&
            !gpu_context_has_stereo(c->windows[c->wall_window[w]])) {
            log_warn("wall %s: quad-buffer stereo: this driver offers no stereo framebuffer "
                     "(Mesa has none); showing a red/cyan anaglyph instead",
                     cfg->walls[w].name);
            c->mode[w] = DISPLAY_STEREO_ANAGLYPH;
        }
    }
    /* Swap together: only the last window waits for the vertical blank. */
    for (int i = 0; i < c->window_count; i++)
        gpu_context_swap_interval(c->windows[i], i == c->window_count - 1 ? 1 : 0);
    gpu_context_make_current(d->context);
    return d;

error:
    cave_destroy(d);
    return NULL;
}

static bool cave_layout(struct display *d, const struct display_pose *head,
                        const struct display_navigation *nav,
                        const struct display_camera *camera)
{
    struct cave *c = (struct cave *)d;
    int sizes[DISPLAY_MAX_WALLS][2];
    display_offscreen_sizes(d, sizes);
    if (!d->desc.offscreen) {
        for (int w = 0; w < d->cfg.wall_count; w++) {
            const struct display_wall *wall = &d->cfg.walls[w];
            if (wall->size[0] == 0 && has_viewport(wall)) {
                sizes[w][0] = wall->viewport[2];
                sizes[w][1] = wall->viewport[3];
            } else if (wall->size[0] == 0) {
                gpu_context_size(c->windows[c->wall_window[w]], &sizes[w][0], &sizes[w][1]);
            }
            if (c->mode[w] == DISPLAY_STEREO_SIDE_BY_SIDE)
                sizes[w][0] /= 2;
            if (sizes[w][0] < 1)
                sizes[w][0] = 1;
            if (sizes[w][1] < 1)
                sizes[w][1] = 1;
        }
    }
    view_set_layout(&d->set, &d->cfg, nav, head, (const int(*)[2])sizes);
    return true;
}

static bool ensure(struct gpu_texture *t, int w, int h)
{
    if (t->id && t->size[0] == w && t->size[1] == h)
        return true;
    gpu_texture_finish(t);
    int size[3] = {w, h, 1};
    return gpu_texture_init(t, 2, size, GPU_RGBA32F, NULL);
}

static bool cave_present(struct display *d, struct renderer *r, float exposure)
{
    struct cave *c = (struct cave *)d;
    if (d->desc.offscreen)
        return true;
    /* Compose and tone map every wall in the primary context. */
    int shown[DISPLAY_MAX_WALLS] = {0};
    for (int w = 0; w < d->cfg.wall_count; w++) {
        const struct gpu_texture *eye[2] = {NULL, NULL};
        for (int i = 0; i < d->set.count; i++) {
            const struct view *v = &d->set.views[i];
            if (v->wall == w && v->visible && v->target.id)
                eye[v->eye == VIEW_EYE_RIGHT ? 1 : 0] = &v->target;
        }
        if (!eye[0])
            continue;
        const struct gpu_texture *src[2] = {eye[0], NULL};
        switch (c->mode[w]) {
        case DISPLAY_STEREO_MONO:
            break;
        case DISPLAY_STEREO_QUAD_BUFFER:
        case DISPLAY_STEREO_PASSIVE:
            src[1] = eye[1];
            break;
        case DISPLAY_STEREO_SIDE_BY_SIDE:
        case DISPLAY_STEREO_ANAGLYPH: {
            if (!eye[1])
                break;
            bool sbs = c->mode[w] == DISPLAY_STEREO_SIDE_BY_SIDE;
            int cw = eye[0]->size[0] * (sbs ? 2 : 1), ch = eye[0]->size[1];
            if (!ensure(&c->composed[w], cw, ch))
                return false;
            bool ok = sbs ? display_compose(d, eye[0], NULL, 0, &c->composed[w], 0, 0) &&
                                display_compose(d, eye[1], NULL, 0, &c->composed[w],
                                                eye[0]->size[0], 0)
                          : display_compose(d, eye[0], eye[1], 1, &c->composed[w], 0, 0);
            if (!ok)
                return false;
            src[0] = &c->composed[w];
            break;
        }
        }
        for (int e = 0; e < 2; e++) {
            if (src[e] && !renderer_tonemap(r, src[e], exposure, &c->ldr[w][e]))
                return false;
        }
        shown[w] = src[1] ? 2 : 1;
    }
    gpu_finish(); /* the other windows' contexts read these textures */
    for (int i = 0; i < c->window_count; i++) {
        gpu_context_make_current(c->windows[i]);
        int fw, fh;
        gpu_context_size(c->windows[i], &fw, &fh);
        gpu_clear_default(0.0f, 0.0f, 0.0f);
        for (int w = 0; w < d->cfg.wall_count; w++) {
            if (shown[w] && c->right_window[w] == i) { /* passive: the right eye alone */
                gpu_present(&c->ldr[w][shown[w] == 2 ? 1 : 0], 0, 0, fw, fh, 0);
                continue;
            }
            if (c->wall_window[w] != i || !shown[w])
                continue;
            const struct display_wall *wall = &d->cfg.walls[w];
            if (c->right_window[w] >= 0) {
                gpu_present(&c->ldr[w][0], 0, 0, fw, fh, 0);
                continue;
            }
            int x = 0, y = 0, ww = fw, wh = fh;
            if (has_viewport(wall)) {
                x = wall->viewport[0];
                y = wall->viewport[1];
                ww = wall->viewport[2];
                wh = wall->viewport[3];
            }
            if (shown[w] == 2) {
                gpu_present(&c->ldr[w][0], x, y, ww, wh, 1);
                gpu_present(&c->ldr[w][1], x, y, ww, wh, 2);
            } else {
                gpu_present(&c->ldr[w][0], x, y, ww, wh, 0);
            }
        }
    }
    display_before_swap(d);
    for (int i = 0; i < c->window_count; i++)
        gpu_context_swap(c->windows[i]);
    gpu_context_make_current(d->context);
    return true;
}

const struct display_impl display_cave_impl = {
    .name = "cave",
    .description = "CAVE walls (three corners each, generalized perspective, head-tracked "
                   "stereo): one window per wall on its monitor, or viewports of one window",
    .create = cave_create,
    .destroy = cave_destroy,
    .layout = cave_layout,
    .present = cave_present,
};
