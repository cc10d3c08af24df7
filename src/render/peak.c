/* The device's peak rate of filtered 3D texture fetches (render.h, render_fetch_peak). */
#include <stdlib.h>

#include "render/render.h"
#include "shaders/bindings.h"

bool render_fetch_peak(double *per_second)
{
    struct gpu_program p;
    if (!gpu_program_init(&p, "fetch_peak.comp", NULL))
        return false;
    int vn[3] = {32, 32, 32}, size[2] = {1024, 1024};
    size_t voxels = 32 * 32 * 32;
    float *data = malloc(voxels * 2 * sizeof(float));
    bool ok = data != NULL;
    struct gpu_texture vol = {0}, out = {0};
    for (size_t i = 0; ok && i < 2 * voxels; i++)
        data[i] = (float)(i % 17) * 1e-3f;
    ok = ok && gpu_texture_init(&vol, 3, vn, GPU_RG32F, data);
    int osize[3] = {size[0], size[1], 1};
    ok = ok && gpu_texture_init(&out, 2, osize, GPU_R32F, NULL);
    double best = 0.0;
    const int fetches = 256;
    for (int rep = 0; ok && rep < 4; rep++) {
        gpu_uniform_ivec2(&p, "size", size);
        gpu_uniform_int(&p, "fetches", fetches);
        gpu_texture_bind(&vol, BIND_PEAK_TEX_VOLUME);
        gpu_image_bind(&out, BIND_PEAK_IMG_OUT, true);
        struct gpu_timer_queue q;
        gpu_timer_queue_init(&q, GPU_TIMER_AUTO);
        struct gpu_timings t = {0};
        gpu_timer_queue_begin(&q);
        gpu_dispatch(&p, size[0], size[1], 1);
        gpu_timer_queue_end(&q, &t);
        gpu_timer_queue_collect(&q, true);
        gpu_timer_queue_finish(&q);
        double rate =
            t.total_ms > 0 ? (double)size[0] * size[1] * fetches / (t.total_ms * 1e-3) : 0.0;
        if (rep > 0 && rate > best) /* the first compiles */
            best = rate;
    }
    gpu_texture_finish(&vol);
    gpu_texture_finish(&out);
    gpu_program_finish(&p);
    free(data);
    *per_second = best;
    return ok;
}

