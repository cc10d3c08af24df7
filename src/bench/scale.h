/*
 * bench/scale: what the eye pass and the light build cost as the volume grows and empties.
 * The default storm (also with its light map compressed, and stored in half floats), its box
 * left empty with the storm's effects (and light map) kept on, the same storm on a
 * 500 x 500 x 100 grid (Isabel's size), both storms with a level of detail (render.lod = 2),
 * and the Katrina sample where its data file is found: each drawn at W x H with empty-space
 * skipping and without it, at
 * 1280 x 1024 with it, and its light map built, in interleaved rounds (every scene once per
 * round, so that a shared machine's load drifts over all of them alike); beside the times,
 * what the rays did (render_counts of one view each way) and the bytes uploaded.
 *
 * Needs the GL context current.  Nothing here prints; progress goes to the log.
 * Must not know: windows, the command line.
 */
#ifndef ANVIL_BENCH_SCALE_H
#define ANVIL_BENCH_SCALE_H

#include <stdbool.h>
#include <stdio.h>

#include "bench/bench.h"

#define BENCH_SCALE_SCENES 8

/* render.lod of the level-of-detail rows: a step at least two pixels wide where it is. */
#define BENCH_SCALE_LOD_PIXELS "2"

enum bench_scale_kind {
    BENCH_SCALE_STORM,      /* the default storm */
    BENCH_SCALE_COMPRESSED, /* ... with its light map compressed at epsilon 1/255 */
    BENCH_SCALE_HALF,       /* ... stored in half floats (render.precision = "half") */
    BENCH_SCALE_EMPTY,      /* its box left empty, its effects and light map kept */
    BENCH_SCALE_LARGE,      /* on a 500 x 500 x 100 grid */
    BENCH_SCALE_LOD,        /* the default storm with a level of detail (render.lod = 2) */
    BENCH_SCALE_LARGE_LOD,  /* the 500 x 500 x 100 storm with it */
    BENCH_SCALE_KATRINA,    /* the Katrina sample, where its data is found */
};

struct bench_scale_row {
    enum bench_scale_kind kind;
    char name[64];
    int n[3];       /* voxels */
    int light_n[3]; /* light map nodes */
    bool shadows, multiple, lateral;
    double view_ms;        /* W x H, empty-space skipping on (medians of the rounds) */
    double view_noskip_ms; /* ... off */
    double large_ms;       /* 1280 x 1024, skipping on */
    double build_ms;       /* the light map */
    double upload_ms;      /* the volume and its macro cells */
    double upload_bytes;
    struct render_counts counts, counts_noskip; /* one W x H view */
    double cells_clear;                         /* share of level-0 cells holding nothing */
    double light_bytes;         /* the light map on the GPU */
    double image_error;         /* COMPRESSED, HALF: RMS over RMS against the storm's picture;
                                   LOD, LARGE_LOD: against the same storm's without it */
    double image_max;           /* ... the largest difference of a channel over the largest
                                   value of the picture it is compared with */
    double output_cpu_ms;       /* STORM: a large view to 8-bit pixels, read back as floats and
                                   tone-mapped on the CPU (median of the rounds) */
    double output_gpu_ms;       /* ... tone-mapped on the GPU and read back as bytes */
};

struct bench_scale_desc {
    bool quick;          /* small grids and images, one round */
    const char *configs; /* katrina.cfg's folder */
    int width, height;   /* 0: 640 x 480 (quick: 160 x 120) */
    int rounds;          /* 0: 5 (quick: 1) */
};

/* Measures the scenes into ROWS (at most BENCH_SCALE_SCENES; *N how many).  False (logged)
 * when a scene cannot be made or drawn. */
bool bench_scale(const struct bench_scale_desc *d, struct bench_scale_row *rows, int *n);

/* scale-table.md after its head: the rows, the ratios that say how the cost scales (the empty
 * box against the storm, the large grid against the small, with a level of detail and
 * without, the build against a 1280 x 1024 view), and how it was measured on DEVICE. */
void bench_write_scale_table(FILE *f, const struct bench_scale_desc *d,
                             const struct bench_scale_row *rows, int n, const char *device);

#endif
