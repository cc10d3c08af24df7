/* The overlay in the scene: its panel and the domain's box with km ticks. */
#include "session/overlay_view.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "render/terrain.h"
#include "session/panel.h"

#define FONT_PATH "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"
#define SEGMENTS_MAX 256
#define LABELS_MAX 32

static const float box_albedo[3] = {0.8f, 0.8f, 0.75f};

struct overlay_view {
    struct overlay *overlay;
    struct panel *panel;
    float c[3], x[3], y[3], to_world[16]; /* where the panel was put last */
    struct render_mesh *box;
    struct render_text *labels;
};

double overlay_tick_km(double extent_km)
{
    double raw = extent_km / 6.0, p = pow(10.0, floor(log10(raw)));
    double f = raw / p;
    return (f < 1.5 ? 1.0 : f < 3.5 ? 2.0 : f < 7.5 ? 5.0 : 10.0) * p;
}

static void segment(float *seg, int *n, const double a[3], const double b[3])
{
    if (*n >= SEGMENTS_MAX)
        return;
    float *o = seg + 6 * (*n)++;
    for (int i = 0; i < 3; i++) {
        o[i] = (float)a[i];
        o[3 + i] = (float)b[i];
    }
}

/* The box's twelve edges, ticks outward along its south and west floor edges, labels. */
static bool build_box(struct overlay_view *v, struct renderer *r)
{
    const struct grid3 *g = renderer_grid(r);
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = g->origin[a];
        hi[a] = g->origin[a] + g->n[a] * g->spacing[a];
    }
    float seg[6 * SEGMENTS_MAX];
    int n = 0;
    for (int e = 0; e < 12; e++) { /* the edges along each axis, at the four corners across */
        int axis = e / 4, c = e % 4;
        int u = (axis + 1) % 3, w = (axis + 2) % 3;
        double a[3], b[3];
        a[axis] = lo[axis];
        b[axis] = hi[axis];
        a[u] = b[u] = (c & 1) ? hi[u] : lo[u];
        a[w] = b[w] = (c & 2) ? hi[w] : lo[w];
        segment(seg, &n, a, b);
    }
    struct render_label labels[LABELS_MAX];
    int nl = 0;
    for (int axis = 0; axis < 2; axis++) {
        double extent_km = (hi[axis] - lo[axis]) / 1000.0;
        double tick = overlay_tick_km(extent_km), len = 0.015 * fmax(hi[0] - lo[0], hi[1] - lo[1]);
        for (double k = 0.0; k <= extent_km + 1e-9; k += tick) {
            double p[3] = {lo[0], lo[1], lo[2]}, q[3];
            p[axis] += k * 1000.0;
            memcpy(q, p, sizeof(q));
            q[1 - axis] -= len; /* outward: south of the south edge, west of the west one */
            segment(seg, &n, p, q);
            if (nl < LABELS_MAX) {
                struct render_label *l = &labels[nl++];
                l->pos[0] = q[0] - (axis == 1 ? 3.5 * len : 0.3 * len);
                l->pos[1] = q[1] - (axis == 0 ? 1.6 * len : 0.3 * len);
                l->pos[2] = lo[2] + 1.0;
                l->height_m = 1.2 * len;
                snprintf(l->text, sizeof(l->text), "%g%s", k, k == 0.0 ? " km" : "");
            }
        }
    }
    v->box = render_lines_mesh(seg, n, box_albedo);
    if (!v->box || !renderer_add_mesh(r, v->box))
        return false;
    v->labels = render_text_create(FONT_PATH, labels, nl, box_albedo);
    if (!v->labels)
        log_warn("overlay: the box's labels are left out");
    else if (!renderer_add_mesh(r, render_text_mesh(v->labels)))
        return false;
    return true;
}

struct overlay_view *overlay_view_create(struct renderer *r, const struct config *cfg)
{
    struct overlay_view *v = calloc(1, sizeof(*v));
    if (!v) {
        log_error("overlay: out of memory");
        return NULL;
    }
    v->overlay = overlay_create(NULL);
    v->panel = v->overlay ? panel_create(r) : NULL;
    if (!v->panel || (cfg->overlay.box && !build_box(v, r))) {
        overlay_view_destroy(v, r);
        return NULL;
    }
    return v;
}

void overlay_view_destroy(struct overlay_view *v, struct renderer *r)
{
    if (!v)
        return;
    if (r && v->box)
        renderer_remove_mesh(r, v->box);
    if (r && v->labels)
        renderer_remove_mesh(r, render_text_mesh(v->labels));
    render_mesh_destroy(v->box);
    render_text_destroy(v->labels);
    panel_destroy(v->panel, r);
    overlay_destroy(v->overlay);
    free(v);
}

const uint8_t *overlay_view_pixels(struct overlay_view *v, const struct overlay_model *m)
{
    return overlay_pixels(v->overlay, m, NULL);
}

const struct overlay *overlay_view_overlay(const struct overlay_view *v)
{
    return v->overlay;
}

static void place(struct overlay_view *v, const float c[3], const float x[3], const float y[3],
                  const float to_world[16])
{
    memcpy(v->c, c, sizeof(v->c));
    memcpy(v->x, x, sizeof(v->x));
    memcpy(v->y, y, sizeof(v->y));
    memcpy(v->to_world, to_world, sizeof(v->to_world));
}

void overlay_view_point(const struct overlay_view *v, float px, float py, double world[3])
{
    float u = px / OVERLAY_WIDTH - 0.5f, w = 0.5f - py / OVERLAY_HEIGHT;
    float p[3];
    for (int i = 0; i < 3; i++)
        p[i] = v->c[i] + u * v->x[i] + w * v->y[i];
    for (int i = 0; i < 3; i++)
        world[i] = v->to_world[i] * p[0] + v->to_world[4 + i] * p[1] + v->to_world[8 + i] * p[2] +
                   v->to_world[12 + i];
}

bool overlay_view_update(struct overlay_view *v, const struct overlay_model *m,
                         const struct display_camera *cam, int w, int h, const double head[3],
                         const float to_world[16], float exposure)
{
    unsigned gen = 0;
    const uint8_t *px = overlay_pixels(v->overlay, m, &gen);
    float aspect = (float)OVERLAY_HEIGHT / (float)OVERLAY_WIDTH;
    if (!cam) {
        /* In the room: left of the menu, a little below the eyes, facing the user. */
        const float width = 0.3f;
        const float c[3] = {(float)head[0] - 0.5f, (float)head[1] - 0.3f, (float)head[2] - 0.7f};
        const float x[3] = {width, 0, 0}, y[3] = {0, width * aspect, 0};
        place(v, c, x, y, to_world);
        return panel_show(v->panel, px, OVERLAY_WIDTH, OVERLAY_HEIGHT, gen, c, x, y, to_world,
                          exposure);
    }
    float c[3], x[3], y[3];
    panel_in_view_corner(cam, w, h, aspect, 0.55f, 0.7f, false, c, x, y); /* lower left */
    const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    place(v, c, x, y, identity);
    return panel_show(v->panel, px, OVERLAY_WIDTH, OVERLAY_HEIGHT, gen, c, x, y, identity,
                      exposure);
}
