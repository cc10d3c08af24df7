/*
 * bench/playback: what playing a WRF series costs per frame.  The procedural storm written as
 * a WRF series (500 x 500 x 100 mass points, Isabel's size; quick: 64 x 64 x 20) is played as
 * anvil run plays it, frame by frame through the session on an offscreen orbit view, twice
 * side by side: with staged playback (the next step readied between frames, session_prepare)
 * and the way it was before (each step change uploads and builds its light map in its own
 * frame).  Every step is in the time series cache before the clock starts, so that what is
 * measured is the frame loop, not the loader (whose cost bench/load measures).
 *
 * Needs the GL context current.  Nothing here prints; progress goes to the log.
 * Must not know: windows, the command line.
 */
#ifndef ANVIL_BENCH_PLAYBACK_H
#define ANVIL_BENCH_PLAYBACK_H

#include <stdbool.h>
#include <stdio.h>

#include "session/stats.h"

struct gpu_context;

struct bench_playback_desc {
    bool quick;      /* the small grid, a small image */
    const char *dir; /* where the series is written (and removed); NULL: $TMPDIR, else /tmp */
    struct gpu_context *context;
    const char *device;
};

/* One way of playing the series. */
struct bench_playback_run {
    int frames;             /* frames drawn while playing */
    int changes;            /* frames that changed the step */
    int skipped;            /* steps never shown: the cursor moved two or more at once */
    double steps_per_s;     /* between the first and the last step change */
    double gap_max_s;       /* the longest time between two step changes */
    /* Frame times are CPU ms of the whole process (its threads, llvmpipe's too). */
    double median_ms;       /* a normal frame: the median of the frames that kept their step */
    double max_ms;          /* the longest frame */
    double change_max_ms;   /* the longest frame that changed the step */
    double copy_max_ms;     /* the longest frame the stage's copy thread may have overlapped */
    double quiet_max_ms;    /* the longest frame that neither changed the step nor overlapped
                               a copy */
    double interval_max_ms; /* the longest frame plus the work after it, before the next */
    double prepare_max_ms;  /* the longest work between two frames */
    const char *prepare_piece; /* its longest piece (session_stats.prepare_piece), NULL: none */
    double prepare_piece_ms;
    const char *longest_piece; /* the longest piece while playing, and its CPU ms */
    double longest_piece_ms;
    double work_ms;                      /* all the work between frames while playing */
    double kind_ms[SESSION_PIECE_KINDS]; /* the same by kind (session_stats.prepare_kind_ms) */
    double light_ms[LIGHT_BUILD_PHASES]; /* the light build's by pass (prepare_light_ms) */
    unsigned stalls;        /* frames whose step was due but not ready (the cursor waited) */
    double change_bytes;    /* volume bytes uploaded inside step-change frames, in all */
    unsigned change_builds; /* light map builds inside step-change frames, in all */
};

struct bench_playback_result {
    int n[3], steps, width, height;
    double speed;         /* playback.speed, steps per second */
    double volume_mb;     /* one step's extinction volume, MiB */
    struct bench_playback_run staged, unstaged;
};

/* Writes the series, plays it both ways, removes it.  False (logged) on failure. */
bool bench_playback(const struct bench_playback_desc *d, struct bench_playback_result *out);
/* The table (playback-table.md's body). */
void bench_write_playback_table(FILE *f, const struct bench_playback_desc *d,
                                const struct bench_playback_result *r);

#endif
