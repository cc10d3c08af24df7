/* The probe in the scene: its panel of values and a cross where it reads. */
#include "session/probe_view.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "session/panel.h"

struct probe_view {
    struct readout *readout;
    struct panel *panel;
    struct render_mesh *cross;
    float c[3], x[3], y[3], to_world[16]; /* where the panel was put last */
};

/* Three emissive lines through the origin, one unit long, in the wand ray's yellow. */
static struct render_mesh *cross_mesh(void)
{
    struct render_vertex v[6];
    uint32_t idx[6];
    for (int a = 0; a < 3; a++)
        for (int e = 0; e < 2; e++) {
            struct render_vertex *p = &v[2 * a + e];
            memset(p, 0, sizeof(*p));
            p->pos[a] = e ? 0.5f : -0.5f;
            const float col[4] = {3.0f, 2.4f, 0.6f, 1.0f};
            memcpy(p->color, col, sizeof(col));
            idx[2 * a + e] = (uint32_t)(2 * a + e);
        }
    return render_mesh_create(v, 6, idx, 6, true, true);
}

struct probe_view *probe_view_create(struct renderer *r)
{
    struct probe_view *v = calloc(1, sizeof(*v));
    if (!v) {
        log_error("probe: out of memory");
        return NULL;
    }
    v->readout = readout_create(NULL);
    v->panel = v->readout ? panel_create(r) : NULL;
    v->cross = v->panel ? cross_mesh() : NULL;
    if (!v->cross || !renderer_add_mesh(r, v->cross)) {
        probe_view_destroy(v, r);
        return NULL;
    }
    render_mesh_set_visible(v->cross, false);
    return v;
}

void probe_view_destroy(struct probe_view *v, struct renderer *r)
{
    if (!v)
        return;
    if (r && v->cross)
        renderer_remove_mesh(r, v->cross);
    render_mesh_destroy(v->cross);
    panel_destroy(v->panel, r);
    readout_destroy(v->readout);
    free(v);
}

void probe_view_hide(struct probe_view *v)
{
    panel_hide(v->panel);
    render_mesh_set_visible(v->cross, false);
}

const uint8_t *probe_view_pixels(struct probe_view *v, const struct readout_model *m)
{
    return readout_pixels(v->readout, m, NULL);
}

void probe_view_point(const struct probe_view *v, float px, float py, double world[3])
{
    float u = px / READOUT_WIDTH - 0.5f, w = 0.5f - py / READOUT_HEIGHT;
    float p[3];
    for (int i = 0; i < 3; i++)
        p[i] = v->c[i] + u * v->x[i] + w * v->y[i];
    for (int i = 0; i < 3; i++)
        world[i] = v->to_world[i] * p[0] + v->to_world[4 + i] * p[1] + v->to_world[8 + i] * p[2] +
                   v->to_world[12 + i];
}

static bool show(struct probe_view *v, const uint8_t *px, unsigned gen, const float c[3],
                 const float x[3], const float y[3], const float to_world[16], float exposure)
{
    memcpy(v->c, c, sizeof(v->c));
    memcpy(v->x, x, sizeof(v->x));
    memcpy(v->y, y, sizeof(v->y));
    memcpy(v->to_world, to_world, sizeof(v->to_world));
    return panel_show(v->panel, px, READOUT_WIDTH, READOUT_HEIGHT, gen, c, x, y, to_world,
                      exposure);
}

bool probe_view_update(struct probe_view *v, const struct readout_model *m,
                       const double *point, double size_m, const struct display_camera *cam,
                       int w, int h, const double head[3], const float to_world[16],
                       float exposure)
{
    if (point && size_m > 0.0) {
        float s = (float)size_m;
        const float model[16] = {s, 0, 0, 0, 0, s, 0, 0, 0, 0, s, 0,
                                 (float)point[0], (float)point[1], (float)point[2], 1};
        render_mesh_set_model(v->cross, model);
        render_mesh_set_visible(v->cross, true);
    } else {
        render_mesh_set_visible(v->cross, false);
    }
    unsigned gen = 0;
    const uint8_t *px = readout_pixels(v->readout, m, &gen);
    float aspect = (float)READOUT_HEIGHT / (float)READOUT_WIDTH;
    if (!cam) {
        /* In the room: above the overlay's panel, left of the menu, facing the user. */
        const float width = 0.3f;
        const float c[3] = {(float)head[0] - 0.5f, (float)head[1] - 0.205f + 0.5f * width * aspect,
                            (float)head[2] - 0.7f};
        const float x[3] = {width, 0, 0}, y[3] = {0, width * aspect, 0};
        return show(v, px, gen, c, x, y, to_world, exposure);
    }
    float c[3], x[3], y[3];
    panel_in_view_corner(cam, w, h, aspect, 0.75f, 0.95f, true, c, x, y); /* upper left */
    const float identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    return show(v, px, gen, c, x, y, identity, exposure);
}
