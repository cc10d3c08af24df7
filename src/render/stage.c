/* A volume's arrays into a persistently mapped pixel buffer, copied on the stage's thread. */
#include "render/stage.h"

#include <string.h>

#include "common/log.h"
#include "render/render.h"

static size_t region(size_t *at, size_t bytes)
{
    size_t here = *at;
    *at += (bytes + 255) & ~(size_t)255; /* aligned for any texel size */
    return here;
}

static bool any(float *const v[4])
{
    return v[0] || v[1] || v[2] || v[3];
}

void render_stage_layout_of(const struct ext_volume *vol, struct render_stage_layout *out)
{
    const int *n = vol->grid.n;
    size_t voxels = (size_t)n[0] * n[1] * n[2], plane = (size_t)n[0] * n[1], at = 0;
    out->beta = region(&at, voxels * 2 * sizeof(float));
    out->tint = vol->tint ? region(&at, voxels * 4) : RENDER_STAGE_NONE;
    out->layers = any(vol->layer) ? region(&at, voxels * 4 * sizeof(float)) : RENDER_STAGE_NONE;
    out->slices = any(vol->slice) ? region(&at, voxels * 4 * sizeof(float)) : RENDER_STAGE_NONE;
    out->surfaces =
        any(vol->slice_surface) ? region(&at, plane * 4 * sizeof(float)) : RENDER_STAGE_NONE;
    out->bytes = at;
}

/* Four arrays of COUNT values (NULL: zeros) interleaved into OUT. */
static void interleave(float *out, float *const v[4], size_t count)
{
    for (size_t i = 0; i < count; i++)
        for (int c = 0; c < 4; c++)
            out[4 * i + c] = v[c] ? v[c][i] : 0.0f;
}

static void copy(const struct render_stage *st, const struct ext_volume *vol)
{
    const int *n = vol->grid.n;
    size_t voxels = (size_t)n[0] * n[1] * n[2], plane = (size_t)n[0] * n[1];
    char *base = st->pbo.map;
    float *beta = (float *)(base + st->lay.beta);
    if (st->half) {
        for (size_t i = 0; i < 2 * voxels; i++)
            beta[i] = vol->beta[i] > RENDER_HALF_MAX ? RENDER_HALF_MAX : vol->beta[i];
    } else {
        memcpy(beta, vol->beta, voxels * 2 * sizeof(float));
    }
    if (st->also)
        memcpy(st->also, vol->beta, voxels * 2 * sizeof(float));
    if (st->lay.tint != RENDER_STAGE_NONE)
        memcpy(base + st->lay.tint, vol->tint, voxels * 4);
    if (st->lay.layers != RENDER_STAGE_NONE)
        interleave((float *)(base + st->lay.layers), vol->layer, voxels);
    if (st->lay.slices != RENDER_STAGE_NONE)
        interleave((float *)(base + st->lay.slices), vol->slice, voxels);
    if (st->lay.surfaces != RENDER_STAGE_NONE)
        interleave((float *)(base + st->lay.surfaces), vol->slice_surface, plane);
}

static void *run(void *arg)
{
    struct render_stage *st = arg;
    pthread_mutex_lock(&st->lock);
    for (;;) {
        while (!st->quit && (!st->job || st->copied))
            pthread_cond_wait(&st->cond, &st->lock);
        if (st->quit)
            break;
        const struct ext_volume *vol = st->job;
        pthread_mutex_unlock(&st->lock);
        copy(st, vol); /* the render thread leaves the buffer and the layout alone meanwhile */
        pthread_mutex_lock(&st->lock);
        st->copied = true;
        pthread_cond_broadcast(&st->cond);
    }
    pthread_mutex_unlock(&st->lock);
    return NULL;
}

void render_stage_init(struct render_stage *st)
{
    memset(st, 0, sizeof(*st));
}

void render_stage_finish(struct render_stage *st)
{
    if (st->started) {
        pthread_mutex_lock(&st->lock);
        while (st->job && !st->copied)
            pthread_cond_wait(&st->cond, &st->lock);
        st->quit = true;
        pthread_cond_broadcast(&st->cond);
        pthread_mutex_unlock(&st->lock);
        pthread_join(st->thread, NULL);
        pthread_cond_destroy(&st->cond);
        pthread_mutex_destroy(&st->lock);
    }
    gpu_fence_delete(st->fence);
    gpu_upload_buffer_finish(&st->pbo);
    memset(st, 0, sizeof(*st));
}

bool render_stage_busy(struct render_stage *st)
{
    if (!st->started)
        return false;
    pthread_mutex_lock(&st->lock);
    bool busy = st->job && !st->copied;
    pthread_mutex_unlock(&st->lock);
    return busy;
}

bool render_stage_begin(struct render_stage *st, const struct ext_volume *vol, float *also,
                        bool half, bool *failed)
{
    *failed = false;
    if (render_stage_busy(st))
        return false;
    if (st->fence) {
        if (!gpu_fence_passed(st->fence))
            return false; /* the GPU still reads the last volume out of the buffer */
        gpu_fence_delete(st->fence);
        st->fence = 0;
    }
    if (!st->started) {
        if (pthread_mutex_init(&st->lock, NULL) != 0) {
            log_error("could not start the upload thread");
            *failed = true;
            return false;
        }
        if (pthread_cond_init(&st->cond, NULL) != 0) {
            pthread_mutex_destroy(&st->lock);
            log_error("could not start the upload thread");
            *failed = true;
            return false;
        }
        if (pthread_create(&st->thread, NULL, run, st) != 0) {
            pthread_cond_destroy(&st->cond);
            pthread_mutex_destroy(&st->lock);
            log_error("could not start the upload thread");
            *failed = true;
            return false;
        }
        st->started = true;
    }
    struct render_stage_layout lay;
    render_stage_layout_of(vol, &lay);
    if (st->pbo.bytes < lay.bytes) {
        gpu_upload_buffer_finish(&st->pbo);
        if (!gpu_upload_buffer_init(&st->pbo, lay.bytes)) {
            *failed = true;
            return false;
        }
    }
    pthread_mutex_lock(&st->lock);
    st->lay = lay;
    st->half = half;
    st->also = also;
    st->job = vol;
    st->copied = false;
    pthread_cond_broadcast(&st->cond);
    pthread_mutex_unlock(&st->lock);
    return true;
}

void render_stage_release(struct render_stage *st)
{
    gpu_fence_delete(st->fence);
    st->fence = gpu_fence_insert();
    if (!st->started)
        return;
    pthread_mutex_lock(&st->lock);
    st->job = NULL;
    st->copied = false;
    pthread_mutex_unlock(&st->lock);
}

bool render_stage_copied(struct render_stage *st)
{
    if (!st->started)
        return false;
    pthread_mutex_lock(&st->lock);
    bool done = st->job && st->copied;
    pthread_mutex_unlock(&st->lock);
    return done;
}

void render_stage_wait(struct render_stage *st)
{
    if (!st->started)
        return;
    pthread_mutex_lock(&st->lock);
    while (st->job && !st->copied)
        pthread_cond_wait(&st->cond, &st->lock);
    pthread_mutex_unlock(&st->lock);
}
