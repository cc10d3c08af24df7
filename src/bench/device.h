/*
 * bench/device: anvil bench --gpu, what a GPU does with the Isabel-sized storm (500 x 500 x
 * 100 voxels over the default storm's 60 x 60 x 16 km) at the sizes users hold us to: an HMD
 * frame (two eyes of 1440 x 1600) and a four-wall CAVE (displays/cave4.cfg: eight views of
 * 1280 x 1024), all views of a frame sharing one light map, each also with a level of detail
 * (render.lod = 2: steps two pixels wide where a voxel looks smaller).  Per frame the GPU
 * milliseconds (timer queries), the light map's rebuild, and the texture fetches the rays took
 * (extinction samples and light map reads, counted) per second against the device's own peak,
 * measured by a fetch-only pass (shaders/fetch_peak.comp).
 *
 * Needs the GL context current.  Nothing here prints; progress goes to the log.
 * Must not know: windows, the command line.
 */
#ifndef ANVIL_BENCH_DEVICE_H
#define ANVIL_BENCH_DEVICE_H

#include <stdbool.h>
#include <stdio.h>

struct bench_device_desc {
    bool quick;           /* a small storm and small views, one frame: a CI-sized run */
    const char *displays; /* the folder of cave4.cfg */
    int frames;           /* frames timed per display; 0: 5 (quick: 1) */
};

#define BENCH_DEVICE_FRAMES 4

/* render.lod of the level-of-detail frames. */
#define BENCH_DEVICE_LOD 2.0f

struct bench_device_frame {
    char name[48]; /* "HMD", "cave4", "HMD, render.lod = 2", "cave4, render.lod = 2" */
    int views, width, height;
    double frame_ms;     /* GPU ms of all views of a frame (median) */
    double frame_spread; /* half the range of the frames */
    double fetches;      /* extinction samples + light map reads of one frame */
    double rays_marched; /* of the frame's pixels, those marched */
};

struct bench_device_result {
    char device[256];
    int n[3], light_n[3];
    struct bench_device_frame frames[BENCH_DEVICE_FRAMES];
    double build_ms;     /* the light map's rebuild (median) */
    double peak_fetches; /* fetches per second the fetch-only pass reached */
    double total_s;      /* wall time of the whole benchmark */
};

/* Runs the benchmark into OUT.  False (logged) when a scene, a display file or a draw fails. */
bool bench_device(const struct bench_device_desc *d, struct bench_device_result *out);

/* gpu-table.md after its head. */
void bench_write_device_table(FILE *f, const struct bench_device_desc *d,
                              const struct bench_device_result *r);

#endif
