/* Experiment: what the staged step's macro cells cost on this driver, the compute or the first
 * read of a texture just uploaded from a pixel buffer. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "testutil.h"

#include "data/synth.h"
#include "gpu/gpu.h"
#include "optics/optics.h"
#include "render/render.h"
#include "shaders/bindings.h"

static double cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static double cells(struct render_cells *c, const struct render_cells_programs *p,
                    struct gpu_texture *t, const struct grid3 *g)
{
    gpu_finish();
    double t0 = cpu_ms();
    if (!render_cells_build(c, p, t, NULL, g))
        exit(1);
    gpu_finish();
    return cpu_ms() - t0;
}

int main(int argc, char **argv)
{
    int reps = argc > 1 ? atoi(argv[1]) : 5;
    struct gpu_context *ctx = test_gl_context_or_skip();
    struct synth_desc d;
    synth_desc_defaults(&d);
    d.n[0] = d.n[1] = 500;
    d.n[2] = 100;
    struct optics_params op;
    optics_params_defaults(&op);
    struct ext_volume vol = {0};
    if (!synth_extinction(&d, &op, &vol))
        return 1;
    const int *n = vol.grid.n;
    size_t voxels = (size_t)n[0] * n[1] * n[2], bytes = voxels * 8, plane = (size_t)n[0] * n[1] * 8;
    struct gpu_upload_buffer pbo;
    if (!gpu_upload_buffer_init(&pbo, bytes))
        return 1;
    memcpy(pbo.map, vol.beta, bytes);
    struct render_cells_programs p;
    struct gpu_program touch;
    if (!render_cells_programs_init(&p) || !gpu_program_init(&touch, "cells_touch.comp", NULL))
        return 1;
    struct gpu_texture tex[2] = {0};
    for (int i = 0; i < 2; i++)
        if (!gpu_texture_init(&tex[i], 3, n, GPU_RG32F, NULL))
            return 1;
    struct render_cells c = {0};
    double *up = calloc(4 * reps, sizeof(double)), *a = up + reps, *tb = a + reps, *b = tb + reps;
    double warm[64];
    for (int r = 0; r < reps; r++) {
        for (int v = 0; v < 2; v++) {
            struct gpu_texture *t = &tex[(2 * r + v) & 1];
            gpu_finish();
            double t0 = cpu_ms();
            for (int z = 0; z < n[2]; z += 32) {
                int layers = n[2] - z < 32 ? n[2] - z : 32;
                gpu_texture_upload_from(t, &pbo, (size_t)z * plane, z, layers);
            }
            gpu_finish();
            up[r] += (cpu_ms() - t0) / 2;
            if (v == 0) {
                a[r] = cells(&c, &p, t, &vol.grid); /* cells first */
            } else {
                gpu_finish();
                double t1 = cpu_ms();
                gpu_texture_bind(t, BIND_CELLS_TEX_BETA);
                gpu_buffer_bind(&c.buf, BIND_CELLS_BUF_CELLS);
                gpu_uniform_ivec3(&touch, "vol_n", n);
                gpu_dispatch(&touch, (n[0] + 3) / 4, (n[1] + 3) / 4, (n[2] + 3) / 4);
                gpu_finish();
                tb[r] = cpu_ms() - t1;
                b[r] = cells(&c, &p, t, &vol.grid);
            }
        }
        warm[r] = cells(&c, &p, &tex[1], &vol.grid); /* the same texture again */
        {
            double t2 = cpu_ms();
            struct render_cells lay;
            float *v = render_cells_cpu(&vol, NULL, 1, &lay);
            double t3 = cpu_ms();
            if (!render_cells_upload(&c, &tex[1], &vol.grid, v, lay.count))
                exit(1);
            gpu_finish();
            double t4 = cpu_ms();
            float *g = render_cells_read(&c);
            (void)render_cells_build(&c, &p, &tex[1], NULL, &vol.grid);
            float *h = render_cells_read(&c);
            printf("cpu cells %.1f ms, upload %.2f ms (%zu bytes), equal %d\n", t3 - t2, t4 - t3,
                   lay.count * sizeof(float), memcmp(g, h, lay.count * sizeof(float)) == 0);
            free(v);
            free(g);
            free(h);
        }
        printf(
            "round %d: upload %.0f, cells first %.0f | touch %.0f then cells %.0f | again %.0f\n",
            r, up[r], a[r], tb[r], b[r], warm[r]);
        fflush(stdout);
    }
    qsort(up, reps, sizeof(double), cmp);
    qsort(a, reps, sizeof(double), cmp);
    qsort(tb, reps, sizeof(double), cmp);
    qsort(b, reps, sizeof(double), cmp);
    qsort(warm, reps, sizeof(double), cmp);
    printf("medians, CPU ms: upload %.0f; cells first %.0f; touch %.0f + cells %.0f; cells again "
           "%.0f\n",
           up[reps / 2], a[reps / 2], tb[reps / 2], b[reps / 2], warm[reps / 2]);
    (void)ctx;
    return 0;
}
