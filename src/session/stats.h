/*
 * session/stats: what a run did, written by --stats FILE.json: views and their times, light
 * map builds, memory, playback and the time series cache.  Plain data; no GL.
 */
#ifndef ANVIL_SESSION_STATS_H
#define ANVIL_SESSION_STATS_H

#include <stdbool.h>
#include <stddef.h>

#include "gpu/gpu.h"
#include "light/light_gpu.h"
#include "render/render.h"

/* The kinds of piece staged playback readies the next step in, between frames
 * (session_prepare): the stage's start, a slice of the copy into the pixel buffer (or the
 * check for its end), an upload slab, a piece of the staged cells, of the pair's cells, of
 * the light build. */
enum session_piece_kind {
    SESSION_PIECE_START,
    SESSION_PIECE_COPY,
    SESSION_PIECE_UPLOAD,
    SESSION_PIECE_CELLS,
    SESSION_PIECE_PAIR,
    SESSION_PIECE_LIGHT,
    SESSION_PIECE_KINDS
};
/* "the copy", ...: the kind in words. */
const char *session_piece_kind_name(enum session_piece_kind kind);

struct session_stats {
    const char *command;
    const char *device;
    const char *stopped_by; /* "SIGTERM", ...: the signal that ended a run early, NULL: none */
    unsigned views;
    unsigned light_builds;
    /* The times of the timed views and light map builds (view_ms and build_ms in the file),
     * lent to the renderer and the light maps (renderer_set_timing, lightmaps_set_timing);
     * they arrive frames later, so collect them all before writing. */
    struct gpu_timings view_times, build_times;
    double light_bytes_dense, light_bytes_compressed;
    size_t gpu_bytes;
    size_t nonfinite_pixels;
    double volume_ms, upload_ms, total_ms;
    /* Playback: the time series cache and the frames. */
    unsigned frames;          /* frames drawn */
    int time_step;            /* the time step on screen at the end */
    unsigned cache_hits, cache_misses, cache_loads;
    int cache_steps;          /* steps in the cache now (the first one kept, not read again) */
    unsigned frames_waited;   /* frames that blocked on a load (only a scripted run's end) */
    unsigned frames_stale;    /* frames that showed an older step: the wanted one was loading */
    unsigned frames_held;     /* a cluster: frames every rank showed the older step because some
                                 rank was still loading the wanted one */
    unsigned volume_uploads;  /* volumes uploaded after the first (with effects.temporal
                                 also each next step's, into the second texture) */
    unsigned volume_swaps;    /* staged playback: step changes that swapped in a next volume
                                 readied between frames (nothing uploaded in their frame) */
    double load_ms, convert_ms, wait_ms, upload_ms_total;
    double prepare_ms;        /* staged playback: time readying the next step between frames */
    /* The longest piece of that work (in the CPU time of all the process's threads) in the
     * last session_prepare and in all: what it worked on (static text, NULL: none) and ms. */
    const char *prepare_piece, *prepare_piece_max;
    double prepare_piece_ms, prepare_piece_max_ms;
    double prepare_kind_ms[SESSION_PIECE_KINDS]; /* all of it by kind, CPU ms of the process */
    /* Of SESSION_PIECE_LIGHT, by the pass each piece worked on (light_gpu_build_phase). */
    double prepare_light_ms[LIGHT_BUILD_PHASES];
    double frame_ms_max;      /* longest frame of the loop */
    double loop_ms;           /* the frame loop, start to end (total_ms less the start) */
    double first_frame_ms;    /* its first frame (shaders compiled, the first light map) */
    double first_sync_ms;     /* sync_ms by the end of the first frame */
    double sync_ms;           /* a cluster's rank: time in the cluster's collectives (the frame
                                 broadcast, the step and failure agreements, the swap barrier;
                                 its wait for the slowest rank included) */
    /* What the views' rays did (render_counts), when counted; and the volume bytes uploaded. */
    bool counted;
    struct render_counts counts;
    double upload_bytes;
};

/* Counts a view drawn and a light map built; their times go to view_times and build_times. */
void session_stats_add_view(struct session_stats *st);
void session_stats_add_build(struct session_stats *st);
/* Writes ST as JSON to PATH (atomically); a time that has not arrived is written as null.
 * False (logged) on failure. */
bool session_stats_write(const struct session_stats *st, const char *path);
/* ST as one JSON object in *TEXT (the caller frees; *LEN bytes); with RANK >= 0 also the
 * cluster rank, the WALLS it draws and its sync_ms.  False (logged) out of memory. */
bool session_stats_json(const struct session_stats *st, int rank, const char *walls,
                        char **text, size_t *len);

#endif
