/* The menu in the scene: its panel (a textured emissive quad) and the wand's ray (a line), as
 * opaque meshes the renderer draws in every view before the ray cast. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "session/menu_view.h"
#include "session/panel.h"
#include "common/log.h"
#include "gpu/gpu.h"
#include "menu/menu.h"

struct menu_view {
    struct renderer *renderer; /* borrowed */
    struct panel *panel;
    struct render_mesh *ray;
};

void menu_view_texel_radiance(const uint8_t rgba[4], float exposure, float out[3])
{
    panel_texel_radiance(rgba, exposure, out);
}

struct menu_view *menu_view_create(struct renderer *r)
{
    struct menu_view *v = calloc(1, sizeof(*v));
    if (!v) {
        log_error("menu: out of memory");
        return NULL;
    }
    v->renderer = r;
    struct render_vertex line[2] = {
        {.pos = {0, 0, 0}, .color = {3.0f, 2.4f, 0.6f, 1.0f}},
        {.pos = {0, 0, 1}, .color = {3.0f, 2.4f, 0.6f, 1.0f}},
    };
    const uint32_t line_idx[2] = {0, 1};
    v->panel = panel_create(r);
    v->ray = render_mesh_create(line, 2, line_idx, 2, true, true);
    if (!v->panel || !v->ray || !renderer_add_mesh(r, v->ray)) {
        menu_view_destroy(v, r);
        return NULL;
    }
    render_mesh_set_visible(v->ray, false);
    return v;
}

void menu_view_destroy(struct menu_view *v, struct renderer *r)
{
    if (!v)
        return;
    if (r && v->ray)
        renderer_remove_mesh(r, v->ray);
    render_mesh_destroy(v->ray);
    panel_destroy(v->panel, r);
    free(v);
}

void menu_view_state_of(struct menu *m, struct menu_view_state *out, const uint8_t **pixels)
{
    memset(out, 0, sizeof(*out));
    out->visible = menu_visible(m);
    *pixels = menu_pixels(m, &out->width, &out->height, &out->generation);
    menu_corners(m, out->corners);
    out->have_ray = menu_ray(m, out->ray_origin, out->ray_direction, &out->ray_hit);
}

bool menu_view_update(struct menu_view *v, struct menu *m, const float to_world[16],
                      float exposure)
{
    if (!menu_visible(m)) {
        panel_hide(v->panel);
        render_mesh_set_visible(v->ray, false);
        return true;
    }
    struct menu_view_state st;
    const uint8_t *px;
    menu_view_state_of(m, &st, &px);
    return menu_view_show(v, &st, px, to_world, exposure);
}

bool menu_view_show(struct menu_view *v, const struct menu_view_state *st,
                    const uint8_t *px, const float to_world[16], float exposure)
{
    if (!st->visible || !px) {
        panel_hide(v->panel);
        render_mesh_set_visible(v->ray, false);
        return true;
    }
    float x[3], y[3], c[3];
    for (int i = 0; i < 3; i++) {
        x[i] = st->corners[1][i] - st->corners[0][i];
        y[i] = st->corners[3][i] - st->corners[0][i];
        c[i] = 0.5f * (st->corners[0][i] + st->corners[2][i]);
    }
    if (!panel_show(v->panel, px, st->width, st->height, st->generation, c, x, y, to_world,
                    exposure))
        return false;
    bool have = st->have_ray;
    render_mesh_set_visible(v->ray, have);
    if (have) {
        const float *o = st->ray_origin, *d = st->ray_direction;
        float hit = st->ray_hit;
        float len = hit >= 0.0f ? hit : 2.0f * sqrtf(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        /* Any two axes across the ray (lines have no width). */
        float a[3] = {fabsf(d[0]) < 0.9f ? 1.0f : 0.0f, fabsf(d[0]) < 0.9f ? 0.0f : 1.0f, 0.0f};
        float b[3] = {d[1] * a[2] - d[2] * a[1], d[2] * a[0] - d[0] * a[2],
                      d[0] * a[1] - d[1] * a[0]};
        float dz[3] = {d[0] * len, d[1] * len, d[2] * len};
        float local[16], model[16];
        panel_basis(a, b, dz, o, local);
        panel_mat4_mul(to_world, local, model);
        render_mesh_set_model(v->ray, model);
    }
    return true;
}
