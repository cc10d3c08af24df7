/*
 * bench/run: anvil bench's work, given its options.  The views benchmark (frame cost of 1, 2,
 * 8 and 12 views sharing one light map against a build per view, and optionally ParaView's
 * time for the same views), the quality sweep on the named scenes (bench/scenes.h) against
 * their Monte Carlo references, and the experiments of bench/experiments.h, written as
 * views-table.md, accuracy.csv, accuracy-table.md, accuracy.png, accuracy-self.png and
 * angles-table.md into one folder; and what a movie of the default storm costs
 * (movie-table.md, bench/movie.h); and a CAVE on 1, 2 and 4 ranks (cluster-table.md,
 * bench/cluster.h).
 *
 * It makes its own headless GL context.  It must not know the command line or where the
 * source tree lies: the folders (output, reference cache, configs) and the ParaView script
 * come in the options, and what a user reads on the terminal goes to the options' report
 * stream.
 */
#ifndef ANVIL_BENCH_RUN_H
#define ANVIL_BENCH_RUN_H

#include <stdbool.h>
#include <stdio.h>

#include "bench/scenes.h"

/* bench_options_defaults fills the defaults; zero means default where noted. */
struct bench_options {
    bool quick;           /* small scenes and images, one repeat: a CI-sized run */
    bool views, quality;  /* which benchmarks run (all three by default; at least one) */
    bool movie;           /* the default storm's movie: frames per second (bench/movie.h) */
    bool scale;           /* the eye pass and the light build as the volume grows and empties
                             (bench/scale.h, scale-table.md) */
    bool cluster;         /* cave4 and cave6 on 1, 2 and 4 ranks (bench/cluster.h); left out
                             with a warning where MPI or mpirun is missing, unless it is the
                             only one asked for */
    bool load;            /* --load-only: a 500 x 500 x 100 WRF step loaded against the plain
                             NetCDF read of its variables (bench/load.h, load-table.md); not
                             part of the default run */
    bool playback;        /* --playback-only: a 500 x 500 x 100 WRF series played with and
                             without staged step changes (bench/playback.h,
                             playback-table.md); not part of the default run */
    bool volume;          /* --volume-only: the layer and the wall of the experiments with the
                             diffuse light volume, pictures and Monte Carlo both on the CPU
                             (bench_volume_image, volume-table.md); no GL */
    bool device;          /* --gpu: the Isabel-sized storm on an HMD and a CAVE frame
                             (bench/device.h, gpu-table.md) */
    const char *displays; /* folder of cave4.cfg and cave6.cfg (the cluster and device
                             benchmarks) */
    bool paraview;        /* also time ParaView on the views (needs views and paraview_script) */
    const char *out;      /* folder for the tables and plots, created with its parents */
    const char *cache;    /* folder of the cached Monte Carlo references; NULL or "":
                             bench-cache beside the running program */
    const char *configs;  /* folder of the named scenes' configs (sphere.cfg, katrina.cfg) */
    const char *paraview_script; /* paraview_views.py */
    const char *images;          /* --images DIR: each swept scene's reference, its standard error
                                    and the pictures of the default and of the 3-D diffusion tier,
                                    PFM (bench_write_images); NULL: none */
    int spp;              /* reference samples per pixel (the sphere gets 64 times as many);
                             0: 256, 32 with quick */
    const char *scenes[BENCH_MAX_SCENES]; /* named scenes of the quality sweep; */
    int n_scenes;                         /* 0: every one of bench_scene_names */
    FILE *report;         /* where the progress lines and the tables are echoed (the
                             command's stdout); NULL: nowhere */
};

/* Zero, with both benchmarks on. */
void bench_options_defaults(struct bench_options *o);

enum bench_status {
    BENCH_DONE,
    BENCH_NO_GPU, /* no OpenGL 4.5 context could be made */
    BENCH_FAILED, /* a scene, a reference, a measurement or a write failed (logged) */
};

/* Runs what O asks for.  A scene whose data files are missing is left out of the sweep with
 * a warning (the Katrina sample lives outside the source tree).  O, OUT and CONFIGS must not
 * be NULL.  Writes files and the report; the GL context is its own and gone when it
 * returns. */
enum bench_status bench_run(const struct bench_options *o);

#endif
