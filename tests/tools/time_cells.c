/* Times what the staged step's macro cells cost on the device, on the procedural storm at
 * 500 x 500 x 100 (the playback bench's size), in the CPU time of the process: the upload of
 * the extinction from a pixel buffer (in slabs of 32 layers), the GPU's build of the cells
 * right after it, the same build after a pass that reads every texel once
 * (shaders/cells_touch.comp: what a conversion of the texture paid at its first read would
 * cost), the build again on a texture read before, and the CPU's cells (render_cells_cpu) with
 * their upload, checked equal to the GPU's.  Rounds interleaved, medians.
 * Usage: time_cells [ROUNDS] (not a test: timings). */
#include <stdbool.h>
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

/* The CPU's cells of VOL, timed into *MS, uploaded into C and checked against the GPU's build
 * from T (VOL's texture); false when they differ. */
static bool cpu_cells(struct render_cells *c, const struct render_cells_programs *p,
                      struct gpu_texture *t, const struct ext_volume *vol, double *ms)
{
    double t0 = cpu_ms();
    struct render_cells lay;
    float *v = render_cells_cpu(vol, NULL, 1, &lay);
    *ms = cpu_ms() - t0;
    if (!v || !render_cells_upload(c, t, &vol->grid, v, lay.count))
        exit(1);
    gpu_finish();
    double up = cpu_ms() - t0 - *ms;
    float *got = render_cells_read(c);
    if (!render_cells_build(c, p, t, NULL, &vol->grid))
        exit(1);
    float *want = render_cells_read(c);
    bool equal = got && want && memcmp(got, want, lay.count * sizeof(float)) == 0;
    free(v);
    free(got);
    free(want);
    /* The two halves apart. */
    struct render_cells_cpu w = {0};
    if (!render_cells_cpu_begin(&w, &vol->grid, 1))
        exit(1);
    double t1 = cpu_ms();
    render_cells_cpu_planes(&w, vol->beta, 0, vol->grid.n[2]);
    double t2 = cpu_ms();
    render_cells_cpu_levels(&w);
    printf("cpu cells %.1f ms (planes %.1f, levels %.2f), upload %.2f ms (%zu bytes)\n", *ms,
           t2 - t1, cpu_ms() - t2, up, lay.count * sizeof(float));
    render_cells_cpu_finish(&w);
    if (!equal)
        fprintf(stderr, "time_cells: the CPU's cells are not the GPU's\n");
    return equal;
}

int main(int argc, char **argv)
{
    int reps = argc > 1 ? atoi(argv[1]) : 5;
    if (reps < 1) {
        fprintf(stderr, "usage: time_cells [ROUNDS] (ROUNDS at least 1)\n");
        return 2;
    }
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
    double *warm = calloc(2 * reps, sizeof(double)), *cpu = warm + reps;
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
        if (!cpu_cells(&c, &p, &tex[1], &vol, &cpu[r]))
            return 1;
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
    qsort(cpu, reps, sizeof(double), cmp);
    printf("medians, CPU ms: upload %.0f; cells first %.0f; touch %.0f + cells %.0f; cells again "
           "%.0f; CPU cells %.1f\n",
           up[reps / 2], a[reps / 2], tb[reps / 2], b[reps / 2], warm[reps / 2], cpu[reps / 2]);
    (void)ctx;
    return 0;
}
