/* The menu in the scene: its panel (a textured emissive quad) and the wand's ray (a line), as
 * opaque meshes the renderer draws in every view before the ray cast. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "session/menu_view.h"
#include "common/log.h"
#include "gpu/gpu.h"
#include "menu/menu.h"

/* Texels hold radiance / PANEL_GAIN (times 1 / exposure) so that the tone mapping, 1 - exp(-L)
 * then sRGB, shows the menu's own sRGB colours. */
#define PANEL_MAX_DISPLAY 0.99

struct menu_view {
    struct renderer *renderer; /* borrowed */
    struct render_mesh *panel, *ray;
    struct gpu_texture texture;
    uint8_t *texels;
    unsigned generation;
    bool uploaded;
    float exposure;
    uint8_t lut[256];
};

static float gain(float exposure)
{
    return (float)(-log(1.0 - PANEL_MAX_DISPLAY)) / exposure;
}

static double srgb_to_linear(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static void build_lut(struct menu_view *v)
{
    double g = -log(1.0 - PANEL_MAX_DISPLAY);
    for (int i = 0; i < 256; i++) {
        double d = srgb_to_linear(i / 255.0) * PANEL_MAX_DISPLAY;
        double t = -log(1.0 - d) / g;
        v->lut[i] = (uint8_t)(fmin(t, 1.0) * 255.0 + 0.5);
    }
}

void menu_view_texel_radiance(const uint8_t rgba[4], float exposure, float out[3])
{
    struct menu_view tmp;
    build_lut(&tmp);
    for (int c = 0; c < 3; c++)
        out[c] = tmp.lut[rgba[c]] / 255.0f * gain(exposure);
}

/* A unit quad whose vertex colour is the gain: texels times the gain are the radiance. */
static struct render_mesh *panel_mesh(float exposure)
{
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    struct render_vertex quad[4];
    const float pos[4][2] = {{-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
    float g = gain(exposure);
    for (int i = 0; i < 4; i++) {
        quad[i] = (struct render_vertex){
            .pos = {pos[i][0], pos[i][1], 0.0f},
            .normal = {0.0f, 0.0f, 1.0f},
            .color = {g, g, g, 1.0f},
            .uv = {pos[i][0] + 0.5f, 0.5f - pos[i][1]}, /* image row 0 is the top */
        };
    }
    return render_mesh_create(quad, 4, idx, 6, false, true);
}

struct menu_view *menu_view_create(struct renderer *r)
{
    struct menu_view *v = calloc(1, sizeof(*v));
    if (!v) {
        log_error("menu: out of memory");
        return NULL;
    }
    build_lut(v);
    v->exposure = 1.0f;
    v->renderer = r;
    struct render_vertex line[2] = {
        {.pos = {0, 0, 0}, .color = {3.0f, 2.4f, 0.6f, 1.0f}},
        {.pos = {0, 0, 1}, .color = {3.0f, 2.4f, 0.6f, 1.0f}},
    };
    const uint32_t line_idx[2] = {0, 1};
    v->panel = panel_mesh(v->exposure);
    v->ray = render_mesh_create(line, 2, line_idx, 2, true, true);
    if (!v->panel || !v->ray || !renderer_add_mesh(r, v->panel) ||
        !renderer_add_mesh(r, v->ray)) {
        menu_view_destroy(v, r);
        return NULL;
    }
    render_mesh_set_visible(v->panel, false);
    render_mesh_set_visible(v->ray, false);
    return v;
}

void menu_view_destroy(struct menu_view *v, struct renderer *r)
{
    if (!v)
        return;
    if (r) {
        renderer_remove_mesh(r, v->panel);
        renderer_remove_mesh(r, v->ray);
    }
    render_mesh_destroy(v->panel);
    render_mesh_destroy(v->ray);
    gpu_texture_finish(&v->texture);
    free(v->texels);
    free(v);
}

/* OUT = A * B, column-major 4x4. */
static void mul(const float a[16], const float b[16], float out[16])
{
    float t[16];
    for (int c = 0; c < 4; c++)
        for (int r = 0; r < 4; r++) {
            float s = 0.0f;
            for (int k = 0; k < 4; k++)
                s += a[k * 4 + r] * b[c * 4 + k];
            t[c * 4 + r] = s;
        }
    memcpy(out, t, sizeof(t));
}

static void basis(const float x[3], const float y[3], const float z[3], const float o[3],
                  float out[16])
{
    for (int i = 0; i < 3; i++) {
        out[i] = x[i];
        out[4 + i] = y[i];
        out[8 + i] = z[i];
        out[12 + i] = o[i];
    }
    out[3] = out[7] = out[11] = 0.0f;
    out[15] = 1.0f;
}

bool menu_view_update(struct menu_view *v, struct menu *m, const float to_world[16],
                          float exposure)
{
    if (exposure != v->exposure) {
        /* The gain lives in the vertex colours: a new exposure needs a new quad. */
        struct render_mesh *panel = panel_mesh(exposure);
        if (!panel)
            return false;
        render_mesh_set_texture(panel, v->texture.id ? &v->texture : NULL);
        renderer_remove_mesh(v->renderer, v->panel);
        render_mesh_destroy(v->panel);
        v->panel = panel;
        if (!renderer_add_mesh(v->renderer, panel))
            return false;
    }
    bool visible = menu_visible(m);
    render_mesh_set_visible(v->panel, visible);
    if (!visible) {
        render_mesh_set_visible(v->ray, false);
        return true;
    }
    int w, h;
    unsigned generation;
    const uint8_t *px = menu_pixels(m, &w, &h, &generation);
    if (!v->uploaded || generation != v->generation || exposure != v->exposure) {
        if (!v->texels || v->texture.size[0] != w || v->texture.size[1] != h) {
            free(v->texels);
            v->texels = malloc((size_t)w * (size_t)h * 4);
            gpu_texture_finish(&v->texture);
            int size[3] = {w, h, 1};
            if (!v->texels || !gpu_texture_init(&v->texture, 2, size, GPU_RGBA8, NULL)) {
                log_error("menu: cannot make the panel's texture");
                return false;
            }
            render_mesh_set_texture(v->panel, &v->texture);
        }
        for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
            for (int c = 0; c < 3; c++)
                v->texels[4 * i + c] = v->lut[px[4 * i + c]];
            v->texels[4 * i + 3] = px[4 * i + 3];
        }
        gpu_texture_upload(&v->texture, v->texels);
        v->generation = generation;
        v->exposure = exposure;
        v->uploaded = true;
    }
    float corners[4][3];
    menu_corners(m, corners);
    float x[3], y[3], z[3], c[3];
    for (int i = 0; i < 3; i++) {
        x[i] = corners[1][i] - corners[0][i];
        y[i] = corners[3][i] - corners[0][i];
        c[i] = 0.5f * (corners[0][i] + corners[2][i]);
    }
    z[0] = x[1] * y[2] - x[2] * y[1];
    z[1] = x[2] * y[0] - x[0] * y[2];
    z[2] = x[0] * y[1] - x[1] * y[0];
    float local[16], model[16];
    basis(x, y, z, c, local);
    mul(to_world, local, model);
    render_mesh_set_model(v->panel, model);

    float o[3], d[3], hit;
    bool have = menu_ray(m, o, d, &hit);
    render_mesh_set_visible(v->ray, have);
    if (have) {
        float len = hit >= 0.0f ? hit : 2.0f * sqrtf(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
        /* Any two axes across the ray (lines have no width). */
        float a[3] = {fabsf(d[0]) < 0.9f ? 1.0f : 0.0f, fabsf(d[0]) < 0.9f ? 0.0f : 1.0f, 0.0f};
        float b[3] = {d[1] * a[2] - d[2] * a[1], d[2] * a[0] - d[0] * a[2],
                      d[0] * a[1] - d[1] * a[0]};
        float dz[3] = {d[0] * len, d[1] * len, d[2] * len};
        basis(a, b, dz, o, local);
        mul(to_world, local, model);
        render_mesh_set_model(v->ray, model);
    }
    return true;
}
