/* A volume's arrays into a persistently mapped pixel buffer, copied on the stage's thread (or in
 * paced slices on the caller's), and its macro cells made on the CPU with the copy. */
#include "render/stage.h"

#include <string.h>
#include <time.h>

#include "common/log.h"
#include "common/parallel.h"
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

/* Bytes of the buffer (and of ALSO) one voxel of VOL takes, its columns' surfaces aside. */
static size_t voxel_bytes(const struct render_stage *st)
{
    size_t b = 2 * sizeof(float) * (st->also ? 2 : 1);
    if (st->lay.tint != RENDER_STAGE_NONE)
        b += 4;
    if (st->lay.layers != RENDER_STAGE_NONE)
        b += 4 * sizeof(float);
    if (st->lay.slices != RENDER_STAGE_NONE)
        b += 4 * sizeof(float);
    return b;
}

/* Voxels FROM .. TO of VOL into the buffer (and ALSO); the surfaces with the last voxel. */
static void copy_range(const struct render_stage *st, const struct ext_volume *vol, size_t from,
                       size_t to)
{
    const int *n = vol->grid.n;
    size_t voxels = (size_t)n[0] * n[1] * n[2], plane = (size_t)n[0] * n[1], count = to - from;
    char *base = st->pbo.map;
    float *beta = (float *)(base + st->lay.beta);
    if (st->half) {
        for (size_t i = 2 * from; i < 2 * to; i++)
            beta[i] = vol->beta[i] > RENDER_HALF_MAX ? RENDER_HALF_MAX : vol->beta[i];
    } else {
        memcpy(beta + 2 * from, vol->beta + 2 * from, count * 2 * sizeof(float));
    }
    if (st->also)
        memcpy(st->also + 2 * from, vol->beta + 2 * from, count * 2 * sizeof(float));
    if (st->lay.tint != RENDER_STAGE_NONE)
        memcpy(base + st->lay.tint + 4 * from, vol->tint + 4 * from, count * 4);
    float *const *v;
    float *part[4];
    if (st->lay.layers != RENDER_STAGE_NONE) {
        v = vol->layer;
        for (int c = 0; c < 4; c++)
            part[c] = v[c] ? v[c] + from : NULL;
        interleave((float *)(base + st->lay.layers) + 4 * from, part, count);
    }
    if (st->lay.slices != RENDER_STAGE_NONE) {
        v = vol->slice;
        for (int c = 0; c < 4; c++)
            part[c] = v[c] ? v[c] + from : NULL;
        interleave((float *)(base + st->lay.slices) + 4 * from, part, count);
    }
    if (to == voxels && st->lay.surfaces != RENDER_STAGE_NONE)
        interleave((float *)(base + st->lay.surfaces), vol->slice_surface, plane);
}

static size_t volume_voxels(const struct ext_volume *vol)
{
    return (size_t)vol->grid.n[0] * vol->grid.n[1] * vol->grid.n[2];
}

static double thread_cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* copy_range, and with the cells each z plane completed reduced while it is in the cache, the
 * cells' levels after the last; the cells' CPU time is added to *CELLS_MS. */
static void copy_and_reduce(struct render_stage *st, const struct ext_volume *vol, size_t from,
                            size_t to, double *cells_ms)
{
    if (!st->cells) {
        copy_range(st, vol, from, to);
        return;
    }
    size_t plane = (size_t)vol->grid.n[0] * vol->grid.n[1], voxels = volume_voxels(vol);
    while (from < to) {
        size_t end = (from / plane + 1) * plane;
        if (end > to)
            end = to;
        copy_range(st, vol, from, end);
        if (end % plane == 0) {
            double t = thread_cpu_ms();
            int z = (int)(end / plane) - 1;
            render_cells_cpu_planes(&st->cpu_cells, vol->beta, z, z + 1);
            if (end == voxels)
                render_cells_cpu_levels(&st->cpu_cells);
            *cells_ms += thread_cpu_ms() - t;
        }
        from = end;
    }
}

static void *run(void *arg)
{
    struct render_stage *st = arg;
    parallel_name_thread("anvil-stage");
    pthread_mutex_lock(&st->lock);
    for (;;) {
        while (!st->quit && (!st->job || st->copied || st->paced))
            pthread_cond_wait(&st->cond, &st->lock);
        if (st->quit)
            break;
        const struct ext_volume *vol = st->job;
        pthread_mutex_unlock(&st->lock);
        /* The render thread leaves the buffer, the layout and the cells alone meanwhile. */
        double cells_ms = 0.0;
        copy_and_reduce(st, vol, 0, volume_voxels(vol), &cells_ms);
        pthread_mutex_lock(&st->lock);
        st->cells_ms += cells_ms;
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
        while (st->job && !st->copied && !st->paced)
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
    render_cells_cpu_finish(&st->cpu_cells);
    memset(st, 0, sizeof(*st));
}

bool render_stage_busy(struct render_stage *st)
{
    if (st->paced)
        return st->job && !st->copied;
    if (!st->started)
        return false;
    pthread_mutex_lock(&st->lock);
    bool busy = st->job && !st->copied;
    pthread_mutex_unlock(&st->lock);
    return busy;
}

bool render_stage_begin(struct render_stage *st, const struct ext_volume *vol, float *also,
                        bool half, bool paced, bool cells, bool *failed)
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
    if (!st->started && !paced) {
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
    /* Without memory for the cells the GPU builds them, as from a half-float texture. */
    bool with_cells = cells && !half && render_cells_cpu_begin(&st->cpu_cells, &vol->grid, 1);
    if (cells && !half && !with_cells)
        log_warn("no memory for the next step's macro cells on the CPU: the GPU builds them");
    if (st->started)
        pthread_mutex_lock(&st->lock);
    st->cells = with_cells;
    st->lay = lay;
    st->half = half;
    st->also = also;
    st->paced = paced;
    st->copy_at = 0;
    st->job = vol;
    st->copied = false;
    if (st->started) {
        pthread_cond_broadcast(&st->cond);
        pthread_mutex_unlock(&st->lock);
    }
    return true;
}

bool render_stage_copy_some(struct render_stage *st, size_t bytes, size_t *copied)
{
    *copied = 0;
    if (!st->paced || !st->job)
        return false;
    if (st->copied)
        return true;
    size_t voxels = volume_voxels(st->job), per = voxel_bytes(st);
    size_t count = bytes / per < 1 ? 1 : bytes / per;
    if (count > voxels - st->copy_at)
        count = voxels - st->copy_at;
    copy_and_reduce(st, st->job, st->copy_at, st->copy_at + count, &st->cells_ms);
    st->copy_at += count;
    *copied = count * per;
    st->copied = st->copy_at == voxels;
    return st->copied;
}

void render_stage_release(struct render_stage *st)
{
    gpu_fence_delete(st->fence);
    st->fence = gpu_fence_insert();
    if (st->started)
        pthread_mutex_lock(&st->lock);
    st->job = NULL;
    st->copied = false;
    if (st->started)
        pthread_mutex_unlock(&st->lock);
}

bool render_stage_copied(struct render_stage *st)
{
    if (st->paced)
        return st->job && st->copied;
    if (!st->started)
        return false;
    pthread_mutex_lock(&st->lock);
    bool done = st->job && st->copied;
    pthread_mutex_unlock(&st->lock);
    return done;
}

const float *render_stage_cells(const struct render_stage *st, size_t *count)
{
    *count = st->cells ? st->cpu_cells.layout.count : 0;
    return st->cells ? st->cpu_cells.cells : NULL;
}

double render_stage_cells_ms(struct render_stage *st)
{
    if (!st->started)
        return st->cells_ms;
    pthread_mutex_lock(&st->lock);
    double ms = st->cells_ms;
    pthread_mutex_unlock(&st->lock);
    return ms;
}

void render_stage_wait(struct render_stage *st)
{
    if (st->paced)
        return; /* nothing in flight: the copy goes in slices on the caller's thread */
    if (!st->started)
        return;
    pthread_mutex_lock(&st->lock);
    while (st->job && !st->copied)
        pthread_cond_wait(&st->cond, &st->lock);
    pthread_mutex_unlock(&st->lock);
}
