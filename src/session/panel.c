/* An image on a quad in the scene, in its own colours. */
#include "session/panel.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cglm/cglm.h>

#include "common/log.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "render/camera.h"

/* Texels hold the radiance that the tone mapping (Reinhard's x / (1 + x) of exposure times
 * radiance, then sRGB: image_tonemap) turns back into the image's own sRGB colour, as floats.
 * White is kept just below the operator's asymptote. */
#define PANEL_MAX_DISPLAY 0.999

struct panel {
    struct renderer *renderer; /* borrowed */
    struct render_mesh *mesh;
    struct gpu_texture texture;
    float *texels;
    unsigned generation;
    bool uploaded;
    float exposure;
    float lut[256]; /* radiance at exposure 1 for each sRGB level */
};

static double srgb_to_linear(double c)
{
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static void build_lut(float lut[256])
{
    for (int i = 0; i < 256; i++) {
        double d = srgb_to_linear(i / 255.0) * PANEL_MAX_DISPLAY;
        lut[i] = (float)(d / (1.0 - d)); /* x / (1 + x) = d */
    }
}

void panel_texel_radiance(const uint8_t rgba[4], float exposure, float out[3])
{
    float lut[256];
    build_lut(lut);
    for (int c = 0; c < 3; c++)
        out[c] = lut[rgba[c]] / exposure;
}

/* A unit quad, white: the texels are the radiance. */
static struct render_mesh *quad_mesh(void)
{
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    struct render_vertex quad[4];
    const float pos[4][2] = {{-0.5f, -0.5f}, {0.5f, -0.5f}, {0.5f, 0.5f}, {-0.5f, 0.5f}};
    for (int i = 0; i < 4; i++) {
        quad[i] = (struct render_vertex){
            .pos = {pos[i][0], pos[i][1], 0.0f},
            .normal = {0.0f, 0.0f, 1.0f},
            .color = {1.0f, 1.0f, 1.0f, 1.0f},
            .uv = {pos[i][0] + 0.5f, 0.5f - pos[i][1]}, /* image row 0 is the top */
        };
    }
    return render_mesh_create(quad, 4, idx, 6, false, true);
}

struct panel *panel_create(struct renderer *r)
{
    struct panel *p = calloc(1, sizeof(*p));
    if (!p) {
        log_error("panel: out of memory");
        return NULL;
    }
    build_lut(p->lut);
    p->exposure = 1.0f;
    p->renderer = r;
    p->mesh = quad_mesh();
    if (!p->mesh || !renderer_add_mesh(r, p->mesh)) {
        panel_destroy(p, r);
        return NULL;
    }
    render_mesh_set_visible(p->mesh, false);
    return p;
}

void panel_destroy(struct panel *p, struct renderer *r)
{
    if (!p)
        return;
    if (r && p->mesh)
        renderer_remove_mesh(r, p->mesh);
    render_mesh_destroy(p->mesh);
    gpu_texture_finish(&p->texture);
    free(p->texels);
    free(p);
}

void panel_hide(struct panel *p)
{
    render_mesh_set_visible(p->mesh, false);
}

void panel_mat4_mul(const float a[16], const float b[16], float out[16])
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

void panel_basis(const float x[3], const float y[3], const float z[3], const float o[3],
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

bool panel_show(struct panel *p, const uint8_t *px, int w, int h, unsigned generation,
                const float c[3], const float x[3], const float y[3], const float to_world[16],
                float exposure)
{
    render_mesh_set_visible(p->mesh, true);
    if (!p->uploaded || generation != p->generation || exposure != p->exposure) {
        if (!p->texels || p->texture.size[0] != w || p->texture.size[1] != h) {
            free(p->texels);
            p->texels = malloc((size_t)w * (size_t)h * 4 * sizeof(float));
            gpu_texture_finish(&p->texture);
            int size[3] = {w, h, 1};
            if (!p->texels || !gpu_texture_init(&p->texture, 2, size, GPU_RGBA32F, NULL)) {
                log_error("panel: cannot make its texture");
                return false;
            }
            render_mesh_set_texture(p->mesh, &p->texture);
        }
        for (size_t i = 0; i < (size_t)w * (size_t)h; i++) {
            for (int k = 0; k < 3; k++)
                p->texels[4 * i + k] = p->lut[px[4 * i + k]] / exposure;
            p->texels[4 * i + 3] = px[4 * i + 3] / 255.0f;
        }
        gpu_texture_upload(&p->texture, p->texels);
        p->generation = generation;
        p->exposure = exposure;
        p->uploaded = true;
    }
    float z[3] = {x[1] * y[2] - x[2] * y[1], x[2] * y[0] - x[0] * y[2],
                  x[0] * y[1] - x[1] * y[0]};
    float local[16], model[16];
    panel_basis(x, y, z, c, local);
    panel_mat4_mul(to_world, local, model);
    render_mesh_set_model(p->mesh, model);
    return true;
}

void panel_in_view_corner(const struct display_camera *cam, int w, int h, float aspect,
                          float max_w, float max_h, bool upper, float c[3], float right[3],
                          float up[3])
{
    struct render_view rv;
    camera_look_at(cam->eye, cam->target, cam->up, cam->fov_deg, cam->near_m, cam->far_m,
                   w > 0 ? w : 1, h > 0 ? h : 1, &rv);
    mat4 view, inv;
    memcpy(view, rv.view, sizeof(view));
    glm_mat4_inv(view, inv);
    float near = rv.proj[14] / (rv.proj[10] - 1.0f);
    float dist = 3.0f * fabsf(near);
    float half_h = dist / rv.proj[5], half_w = dist / rv.proj[0];
    float width = fminf(max_w * half_w, max_h * half_h / aspect);
    float v = upper ? 1.0f : -1.0f;
    for (int i = 0; i < 3; i++) {
        right[i] = inv[0][i] * width;
        up[i] = inv[1][i] * width * aspect;
        c[i] = inv[3][i] - inv[2][i] * dist - inv[0][i] * (half_w * 0.97f - 0.5f * width) +
               v * inv[1][i] * (half_h * 0.95f - 0.5f * width * aspect);
    }
}
