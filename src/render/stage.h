/*
 * render/stage: a volume's arrays copied into a pixel-buffer object off the render thread.
 * The stage's own thread only writes the persistently mapped buffer (it never calls GL); the
 * render thread then uploads the textures from that buffer (render.c, the next volume), so
 * that the frame loop never waits for the driver to copy client memory.  Internal to render.
 *
 * The buffer holds one volume at a time, laid out as the textures take it: the extinction
 * (two floats a voxel, clamped for half floats), the tints (RGBA8), the layers' and the
 * slices' fields (four floats a voxel, a field per channel), the slices' surfaces (four floats
 * a column).  A further volume kind (a nest, a z-coordinate table) is one more region here.
 * Beside the copy the stage can make the volume's macro cells on the CPU (render_cells_cpu), a
 * z plane right after the copy of that plane, so that the render thread uploads a few MB of
 * cells instead of building them from the texture.
 */
#ifndef ANVIL_RENDER_STAGE_H
#define ANVIL_RENDER_STAGE_H

#include <pthread.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "data/volume.h"
#include "gpu/gpu.h"
#include "render/render.h"

#define RENDER_STAGE_NONE SIZE_MAX

/* Byte offsets of each region in the buffer (RENDER_STAGE_NONE: the volume has none). */
struct render_stage_layout {
    size_t beta, tint, layers, slices, surfaces;
    size_t bytes;
};

struct render_stage {
    struct gpu_upload_buffer pbo;
    struct render_stage_layout lay;
    pthread_t thread;
    bool started;
    pthread_mutex_t lock;
    pthread_cond_t cond;
    const struct ext_volume *job; /* being copied (borrowed); NULL when idle */
    bool copied;                  /* the last job's copy is complete */
    bool quit;
    bool half;        /* clamp the extinction to RENDER_HALF_MAX (half-float textures) */
    float *also;      /* the extinction copied here too (2 floats a voxel), or NULL */
    uint64_t fence;   /* after the uploads that read the buffer (0: none in flight) */
    bool paced;       /* the job is copied in slices by render_stage_copy_some, no thread */
    size_t copy_at;   /* paced: the voxels copied so far */
    bool cells;       /* the job's macro cells are made on the CPU with the copy */
    struct render_cells_cpu cpu_cells;
    double cells_ms; /* CPU time the cells took, all jobs so far (the thread's or the caller's) */
};

/* The regions VOL needs. */
void render_stage_layout_of(const struct ext_volume *vol, struct render_stage_layout *out);

/* Zeroes ST; the thread and the buffer are made on first use.  No GL. */
void render_stage_init(struct render_stage *st);
/* Waits for a copy in flight, ends the thread, frees the buffer.  Needs the GL context. */
void render_stage_finish(struct render_stage *st);

/* Starts copying VOL into the buffer on the stage's thread, or with PACED in slices on the
 * caller's (render_stage_copy_some), and its extinction, unclamped, into ALSO (2 floats a
 * voxel, or NULL); with CELLS (and not HALF) its macro cells too (render_stage_cells);
 * VOL and ALSO must stay valid and VOL unchanged until render_stage_copied returned true (or
 * render_stage_wait returned).  False when the buffer is still read by earlier uploads or a
 * copy is in flight (try again next frame), or on failure (logged, *FAILED set).  Needs the GL
 * context (the buffer may be remade). */
bool render_stage_begin(struct render_stage *st, const struct ext_volume *vol, float *also,
                        bool half, bool paced, bool cells, bool *failed);
/* PACED (render_stage_begin): the copy is not started on the thread but made on the caller's,
 * about BYTES of the buffer's (and ALSO's) bytes a call (at least one voxel; the columns'
 * surfaces with the last), *COPIED of them; true once the copy is complete.  Bit-identical to
 * the thread's copy.  No GL. */
bool render_stage_copy_some(struct render_stage *st, size_t bytes, size_t *copied);
/* Whether the copy started by render_stage_begin is complete (never waits). */
bool render_stage_copied(struct render_stage *st);
/* Waits for a copy in flight (before the volume it reads may go). */
void render_stage_wait(struct render_stage *st);
/* The uploads out of the buffer are issued: a fence follows them (the next begin waits for it)
 * and the volume is no longer read.  Needs the GL context. */
void render_stage_release(struct render_stage *st);
/* Once the copy is complete: the last job's macro cells (every level, render_cells_cpu's
 * layout), *COUNT of them, valid until the next render_stage_begin; NULL when they were not
 * made (HALF, not asked for, or no memory for them: the GPU builds them).  No GL. */
const float *render_stage_cells(const struct render_stage *st, size_t *count);
/* The CPU time the cells have taken so far, ms, all jobs together. */
double render_stage_cells_ms(struct render_stage *st);
/* Whether a copy is in flight. */
bool render_stage_busy(struct render_stage *st);

#endif
