/*
 * bench/movie: what a movie of the default storm costs.  The built-in storm flown round by a
 * camera path, drawn frame by frame through the session as anvil render --path does, once
 * drawn only and once written to an H.264 movie: frames per second of each, and so the share
 * of the read-back and the encoder.  Written as movie-table.md.  Needs the GL context current.
 */
#ifndef ANVIL_BENCH_MOVIE_H
#define ANVIL_BENCH_MOVIE_H

#include <stdbool.h>
#include <stdio.h>

struct bench_movie_desc {
    bool quick;       /* 160 x 120, a 32 x 32 x 16 storm, half a second */
    const char *out;  /* the folder of movie-table.md (and the movie, removed after) */
    const char *device;
    struct gpu_context *context;
    FILE *report;     /* the table is echoed here; NULL: not */
};

struct bench_movie_result {
    int frames, width, height;
    double draw_fps, written_fps; /* drawn only; drawn, read back and encoded */
    double movie_bytes;
    unsigned light_builds;
};

/* Measures and writes movie-table.md.  False (logged) on failure. */
bool bench_movie(const struct bench_movie_desc *d, struct bench_movie_result *out);

#endif
