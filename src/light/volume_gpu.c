/* The diffuse light volume on the GPU (light_volume_gpu.h). */
#include "light/light_volume_gpu.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "render/render.h" /* render_zmap_upload */
#include "shaders/bindings.h"

#define SCALARS_HEAD 16
/* Iterations between two reads of the solve's state: each read waits for the GPU.  Once
 * converged the passes return at once, so the iterations past it cost their dispatches only. */
#define CHECK_EVERY 8

/* PASS K's program; STRETCHED (PASS 1 only): the one that samples through the height table. */
static const struct gpu_program *pass(struct light_volume_gpu *v, int k, bool stretched)
{
    struct gpu_program *p = stretched ? &v->pass[6] : &v->pass[k - 1];
    if (!p->id) {
        char defines[256];
        snprintf(defines, sizeof(defines),
                 "#define PASS %d\n#define STRETCHED %d\n#define LIGHT_VOLUME_BOUNDARY_R %.17g\n"
                 "#define LIGHT_VOLUME_BRICK %d\n#define LIGHT_VOLUME_BRICK_SWEEPS %d\n"
                 "#define LIGHT_VOLUME_COARSE_SWEEPS %d\n",
                 k, stretched ? 1 : 0, LIGHT_VOLUME_BOUNDARY_R, LIGHT_VOLUME_BRICK,
                 LIGHT_VOLUME_BRICK_SWEEPS, LIGHT_VOLUME_COARSE_SWEEPS);
        if (!gpu_program_init(p, "light_volume.comp", defines))
            return NULL;
    }
    return p;
}

static void scratch_finish(struct light_volume_gpu *v)
{
    gpu_buffer_finish(&v->terms);
    gpu_buffer_finish(&v->system);
    gpu_buffer_finish(&v->vectors);
    gpu_buffer_finish(&v->scalars);
}

void light_volume_gpu_finish(struct light_volume_gpu *v)
{
    for (int k = 0; k < 7; k++)
        gpu_program_finish(&v->pass[k]);
    gpu_texture_finish(&v->field);
    gpu_texture_finish(&v->zmap);
    scratch_finish(v);
    memset(v, 0, sizeof(*v));
}

static void common_uniforms(const struct light_volume_gpu *v, const struct gpu_program *p)
{
    float size[3], origin[3];
    for (int a = 0; a < 3; a++) {
        size[a] = (float)v->grid.spacing[a];
        origin[a] = (float)v->grid.origin[a];
    }
    gpu_uniform_ivec3(p, "cells_n", v->grid.n);
    gpu_uniform_vec3(p, "cell_size", size);
    gpu_uniform_vec3(p, "box_origin", origin);
}

static void bind_buffers(const struct light_volume_gpu *v)
{
    gpu_buffer_bind(&v->terms, BIND_VOLUME_BUF_TERMS);
    gpu_buffer_bind(&v->system, BIND_VOLUME_BUF_SYSTEM);
    gpu_buffer_bind(&v->vectors, BIND_VOLUME_BUF_VECTORS);
    gpu_buffer_bind(&v->scalars, BIND_VOLUME_BUF_SCALARS);
}

static int bricks_count(const struct grid3 *g)
{
    int m = 1;
    for (int a = 0; a < 3; a++)
        m *= (g->n[a] + LIGHT_VOLUME_BRICK - 1) / LIGHT_VOLUME_BRICK;
    return m;
}

/* PASS 5, the update and the bricks' preconditioner (START: the first, from r = b). */
static void update(const struct light_volume_gpu *v, const struct gpu_program *p, int start)
{
    gpu_program_use(p);
    common_uniforms(v, p);
    gpu_uniform_int(p, "parity", v->iterations & 1);
    gpu_uniform_int(p, "start", start);
    gpu_dispatch(p, bricks_count(&v->grid), 1, 1);
}

/* PASS 4, the coarse correction and the iteration's scalars. */
static void coarse(const struct light_volume_gpu *v, const struct gpu_program *p, int start)
{
    gpu_program_use(p);
    common_uniforms(v, p);
    gpu_uniform_int(p, "start", start);
    gpu_uniform_float(p, "tolerance", (float)v->tolerance);
    gpu_dispatch(p, 1, 1, 1);
}

bool light_volume_gpu_build_begin(struct light_volume_gpu *v, const struct gpu_texture *beta,
                                  const struct grid3 *vol_grid, const struct gpu_texture *light,
                                  const struct light_grid *lgrid,
                                  const struct light_settings *s,
                                  const struct light_volume_desc *desc)
{
    v->solving = false;
    scratch_finish(v); /* a build in pieces dropped half way leaves its scratch */
    struct light_volume_desc d = desc ? *desc : (struct light_volume_desc){0};
    light_volume_desc_defaults(&d, vol_grid);
    double tol = fmax(d.tolerance, 1e-5);
    const struct gpu_program *p[6];
    for (int k = 1; k <= 6; k++) {
        if (!(p[k - 1] = pass(v, k, k == 1 && grid3_stretched(vol_grid))))
            return false;
    }
    light_volume_grid(vol_grid, &d, &v->grid);
    const int count = (int)grid3_count(&v->grid);
    const int bricks = bricks_count(&v->grid);
    if (!v->field.id || memcmp(v->field.size, v->grid.n, sizeof(v->grid.n)) != 0) {
        gpu_texture_finish(&v->field);
        if (!gpu_texture_init(&v->field, 3, v->grid.n, GPU_RGBA32F, NULL))
            return false;
    }
    if (!gpu_buffer_init(&v->terms, (size_t)count * 8 * sizeof(float), NULL) ||
        !gpu_buffer_init(&v->system, (size_t)count * 4 * sizeof(float), NULL) ||
        !gpu_buffer_init(&v->vectors, (size_t)count * 7 * sizeof(float), NULL)) {
        scratch_finish(v);
        return false;
    }
    /* The head zeroed (not converged, no iterations); per brick its sums, the coarse system
     * and e. */
    size_t scalars = (size_t)SCALARS_HEAD + 9 * (size_t)bricks;
    float *zero = calloc(scalars, sizeof(float));
    bool have = zero && gpu_buffer_init(&v->scalars, scalars * sizeof(float), zero);
    free(zero);
    if (!have) {
        scratch_finish(v);
        return false;
    }
    bind_buffers(v);

    /* PASS 1: the source and the extinction per cell. */
    float sdir[3], vol_origin[3], vol_inv[3];
    for (int a = 0; a < 3; a++) {
        sdir[a] = (float)lgrid->w[a]; /* the light's direction, unit */
        vol_origin[a] = (float)vol_grid->origin[a];
        vol_inv[a] = (float)(1.0 / vol_grid->spacing[a]);
    }
    double tr[2], loss[2], gs[2];
    light_volume_phase_terms(s, lgrid->sun, tr, loss, gs);
    const float trf[2] = {(float)tr[0], (float)tr[1]}, lossf[2] = {(float)loss[0], (float)loss[1]};
    const float gsf[2] = {(float)gs[0], (float)gs[1]};
    gpu_program_use(p[0]);
    common_uniforms(v, p[0]);
    gpu_texture_bind(beta, BIND_VOLUME_TEX_BETA);
    gpu_texture_bind(light, BIND_VOLUME_TEX_LIGHT);
    gpu_uniform_ivec3(p[0], "vol_n", vol_grid->n);
    gpu_uniform_vec3(p[0], "vol_origin", vol_origin);
    gpu_uniform_vec3(p[0], "vol_inv_spacing", vol_inv);
    gpu_uniform_mat4(p[0], "light_world_to_tex", lgrid->world_to_tex);
    gpu_uniform_ivec3(p[0], "light_n", lgrid->n);
    gpu_uniform_vec3(p[0], "sdir", sdir);
    gpu_uniform_vec2(p[0], "tr", trf);
    gpu_uniform_vec2(p[0], "loss", lossf);
    gpu_uniform_vec2(p[0], "gs", gsf);
    gpu_uniform_int(p[0], "sub", d.substeps);
    if (grid3_stretched(vol_grid)) {
        if (!render_zmap_upload(vol_grid, &v->zmap, p[0]))
            return false;
        gpu_texture_bind(&v->zmap, BIND_VOLUME_TEX_ZMAP);
    }
    gpu_dispatch(p[0], count, 1, 1);

    /* PASS 2: the system; then the coarse system and the iteration's start. */
    gpu_program_use(p[1]);
    common_uniforms(v, p[1]);
    gpu_dispatch(p[1], count, 1, 1);
    v->iterations = 0;
    v->residual = 0.0f;
    v->max_iterations = d.max_iterations;
    v->tolerance = tol;
    update(v, p[4], 1);
    coarse(v, p[3], 1);
    float head[SCALARS_HEAD];
    gpu_buffer_read(&v->scalars, 0, sizeof(head), head);
    v->converged = !(head[1] > 0.0f);
    v->solving = true;
    return true;
}

bool light_volume_gpu_build_step(struct light_volume_gpu *v, int iterations, bool *done)
{
    *done = !v->solving;
    if (!v->solving)
        return true;
    const struct gpu_program *p[6];
    for (int k = 2; k <= 6; k++)
        p[k - 1] = &v->pass[k - 1]; /* made by light_volume_gpu_build_begin */
    bind_buffers(v); /* a frame may have come between two pieces */
    const int count = (int)grid3_count(&v->grid);
    float head[SCALARS_HEAD];
    double tol = v->tolerance;
    bool ok = v->converged, stop = v->converged;
    if (!stop) {
        for (int n = 0; !stop && v->iterations < v->max_iterations &&
                        (iterations <= 0 || n < iterations);
             n++) {
            int it = v->iterations + 1;
            v->iterations = it; /* its parity picks the p buffer */
            gpu_program_use(p[2]);
            common_uniforms(v, p[2]);
            gpu_uniform_int(p[2], "parity", it & 1);
            gpu_dispatch(p[2], bricks_count(&v->grid), 1, 1);
            update(v, p[4], 0);
            coarse(v, p[3], 0);
            if (it % CHECK_EVERY == 0 || it == v->max_iterations) {
                /* [6] the residual, [7] converged, [8] the iterations it took */
                gpu_buffer_read(&v->scalars, 0, sizeof(head), head);
                v->residual = head[6];
                if (head[7] != 0.0f) {
                    v->iterations = (int)head[8];
                    stop = true;
                    ok = isfinite(head[6]) && head[6] <= tol;
                }
            }
        }
    }
    if (!stop && v->iterations < v->max_iterations)
        return true; /* more iterations in the next piece */
    v->solving = false;
    v->converged = ok;
    *done = true;
    if (!ok) {
        log_error("light volume (GPU): the diffusion solve stopped at a relative residual of "
                  "%.3g after %d iterations (wanted %.3g)", (double)v->residual, v->iterations,
                  tol);
        scratch_finish(v);
        return false;
    }

    log_info("light volume: %dx%dx%d cells, %d iterations to a relative residual of %.2g",
             v->grid.n[0], v->grid.n[1], v->grid.n[2], v->iterations, (double)v->residual);
    /* PASS 6: the field. */
    gpu_program_use(p[5]);
    common_uniforms(v, p[5]);
    gpu_image_bind(&v->field, BIND_VOLUME_IMG_FIELD, true);
    gpu_dispatch(p[5], count, 1, 1);
    scratch_finish(v);
    return true;
}

bool light_volume_gpu_build(struct light_volume_gpu *v, const struct gpu_texture *beta,
                            const struct grid3 *vol_grid, const struct gpu_texture *light,
                            const struct light_grid *lgrid, const struct light_settings *s,
                            const struct light_volume_desc *desc)
{
    bool done = false;
    return light_volume_gpu_build_begin(v, beta, vol_grid, light, lgrid, s, desc) &&
           light_volume_gpu_build_step(v, 0, &done);
}

bool light_volume_gpu_read(const struct light_volume_gpu *v, struct light_volume *out)
{
    light_volume_finish(out);
    if (!v->field.id)
        return false;
    out->grid = v->grid;
    size_t bytes = grid3_count(&v->grid) * 4 * sizeof(float);
    out->field = malloc(bytes);
    if (!out->field) {
        log_error("light volume (GPU): out of memory for reading back %zu bytes", bytes);
        return false;
    }
    gpu_texture_read(&v->field, out->field, bytes);
    out->iterations = v->iterations;
    out->residual = v->residual;
    return true;
}
