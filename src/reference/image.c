/*
 * reference/image: Monte Carlo images of a view, rows shared out over threads, each pixel
 * with its own random stream (reference.h).
 */
#include "reference/reference.h"

#include <assert.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "common/log.h"
#include "common/mat4d.h"
#include "common/parallel.h"
#include "common/progress.h"

static void normalize3(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
}

/* ---- images ------------------------------------------------------------------------------ */

struct render_job {
    const struct reference *ref;
    const struct reference_image_desc *d;
    double inv[16]; /* clip -> world, row-major */
    int width, height;
    struct image *mean, *err;
    atomic_int next_row;
    atomic_int rows_done;
};

static void unproject(const double inv[16], double x, double y, double z, double out[3])
{
    double v[4] = {x, y, z, 1.0}, r[4];
    for (int i = 0; i < 4; i++)
        r[i] = inv[4 * i] * v[0] + inv[4 * i + 1] * v[1] + inv[4 * i + 2] * v[2] + inv[4 * i + 3];
    for (int i = 0; i < 3; i++)
        out[i] = r[i] / r[3];
}

/* The renderer's camera ray through (PX, PY) in pixels: from the near plane toward the far
 * plane (shaders/raycast.comp). */
static void camera_ray(const struct render_job *job, double px, double py, double o[3], double d[3])
{
    double nx = px / job->width * 2.0 - 1.0, ny = py / job->height * 2.0 - 1.0, f[3];
    unproject(job->inv, nx, ny, -1.0, o);
    unproject(job->inv, nx, ny, 1.0, f);
    for (int i = 0; i < 3; i++)
        d[i] = f[i] - o[i];
    normalize3(d);
}

static void render_pixel(const struct render_job *job, int x, int y)
{
    const struct reference_image_desc *d = job->d;
    struct reference_rng rng;
    reference_rng_seed(&rng, d->seed, (uint64_t)y * (uint64_t)job->width + (uint64_t)x);
    double o[3], dir[3];
    camera_ray(job, x + 0.5, y + 0.5, o, dir);
    /* Welford's running mean and sum of squared deviations, per channel (RGB, alpha). */
    double mean[4] = {0}, m2[4] = {0};
    for (int s = 0; s < d->spp; s++) {
        if (d->jitter)
            camera_ray(job, x + reference_rng_uniform(&rng), y + reference_rng_uniform(&rng), o,
                       dir);
        double l[3];
        bool pass;
        reference_radiance(job->ref, o, dir, &rng, l, &pass);
        double v[4] = {l[0], l[1], l[2], pass ? 1.0 : 0.0};
        for (int c = 0; c < 4; c++) {
            double delta = v[c] - mean[c];
            mean[c] += delta / (s + 1);
            m2[c] += delta * (v[c] - mean[c]);
        }
    }
    size_t i = 4 * ((size_t)y * (size_t)job->width + (size_t)x);
    for (int c = 0; c < 4; c++) {
        job->mean->rgba[i + c] = (float)mean[c];
        double var = d->spp > 1 ? m2[c] / ((double)d->spp * (d->spp - 1)) : 0.0;
        job->err->rgba[i + c] = (float)sqrt(var > 0.0 ? var : 0.0);
    }
}

static void *render_worker(void *arg)
{
    struct render_job *job = arg;
    parallel_name_thread("anvil-reference");
    for (;;) {
        int y = atomic_fetch_add(&job->next_row, 1);
        if (y >= job->height)
            return NULL;
        for (int x = 0; x < job->width; x++)
            render_pixel(job, x, y);
        int done = atomic_fetch_add(&job->rows_done, 1) + 1;
        if (job->d->progress)
            progress_update(job->d->progress, (uint64_t)done);
    }
}

bool reference_render(const struct reference *ref, const struct render_view *view,
                      const struct reference_image_desc *d, struct image *radiance,
                      struct image *stderr_img)
{
    assert(ref && view && d && radiance && stderr_img);
    assert(d->spp >= 1);
    memset(radiance, 0, sizeof(*radiance));
    memset(stderr_img, 0, sizeof(*stderr_img));
    struct render_job job = {.ref = ref,
                             .d = d,
                             .width = view->width,
                             .height = view->height,
                             .mean = radiance,
                             .err = stderr_img};
    atomic_init(&job.next_row, 0);
    atomic_init(&job.rows_done, 0);
    /* clip = proj * view; the matrices are column-major. */
    double m[16];
    for (int i = 0; i < 4; i++) {
        for (int j = 0; j < 4; j++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++)
                s += (double)view->proj[4 * k + i] * view->view[4 * j + k];
            m[4 * i + j] = s;
        }
    }
    if (!mat4d_invert(m, job.inv)) {
        log_error("reference: the camera matrices are singular");
        return false;
    }
    if (!image_init(radiance, view->width, view->height))
        return false;
    if (!image_init(stderr_img, view->width, view->height))
        goto error_mean;

    int threads = d->threads;
    if (threads <= 0) {
        long n = sysconf(_SC_NPROCESSORS_ONLN);
        threads = n > 0 ? (int)n : 1;
    }
    if (threads > view->height)
        threads = view->height > 0 ? view->height : 1;
    pthread_t *tid = calloc((size_t)threads, sizeof(*tid));
    if (!tid) {
        log_error("reference: out of memory");
        goto error_err;
    }
    int started = 0;
    for (; started < threads - 1; started++) {
        if (pthread_create(&tid[started], NULL, render_worker, &job) != 0) {
            log_warn("reference: could not start thread %d; going on with %d", started + 1,
                     started + 1);
            break;
        }
    }
    render_worker(&job); /* the calling thread works too */
    for (int i = 0; i < started; i++)
        pthread_join(tid[i], NULL);
    free(tid);
    return true;

error_err:
    image_finish(stderr_img);
error_mean:
    image_finish(radiance);
    return false;
}
