/*
 * bench/load: what a time step of a WRF file costs to load, against the plain NetCDF read of
 * the same variables (wrf_read_plain: one nc_get_vara each into memory, nothing else),
 * measured side by side in interleaved rounds (every step both ways each round, the order
 * alternating), with the peak memory of each above what the process held before it.  The
 * file is the procedural storm written here as a WRF series (500 x 500 x 100, Isabel's size;
 * quick: 64 x 64 x 20) and removed afterwards.
 *
 * No GL.  Nothing here prints; progress goes to the log.
 * Must not know: windows, the command line, the session.
 */
#ifndef ANVIL_BENCH_LOAD_H
#define ANVIL_BENCH_LOAD_H

#include <stdbool.h>
#include <stdio.h>

struct bench_load_desc {
    bool quick;      /* a small grid, one round */
    const char *dir; /* where the file is written (and removed); NULL: $TMPDIR, else /tmp */
    int rounds;      /* 0: 3 (quick: 1) */
};

struct bench_load_result {
    int n[3];          /* the file's mass grid */
    int steps, rounds; /* steps in the file, rounds over them */
    double step_mb;    /* what the plain read of one step reads, MiB */
    double plain_ms;   /* the plain read of a step (median over steps and rounds) */
    double load_ms;    /* the load of a step to extinction: read, checks, resampling,
                          optics (median) */
    double read_ms, convert_ms; /* ... its reading (with checks, resampling and, a WRF step
                                   being read slab by slab, extinction) and what follows it
                                   (medians: data_source_load's LOAD_MS, CONVERT_MS) */
    double ratio;               /* median over the pairs of load / plain, side by side */
    double vapour_ms, vapour_ratio;     /* the load with the menu's histogram of the water vapour
                                           (anvil run's), and its median ratio to the plain read */
    double plain_peak_mb, load_peak_mb; /* the largest peak memory of either, MiB above what
                                           the process held before it */
    double volume_mb;                   /* the extinction volume a load returns, MiB */
};

/* The procedural storm as a WRF series of STEPS steps on N mass points at PATH, the storm
 * moving on from step to step (200 x 200 x 16 km).  False (logged) on failure. */
bool bench_write_storm_series(const char *path, const int n[3], int steps);

/* Writes the file, measures, removes the file.  False (logged) on failure. */
bool bench_load(const struct bench_load_desc *d, struct bench_load_result *out);

/* The Markdown table of R (with DEVICE, the CPU's description, in its caption). */
void bench_write_load_table(FILE *f, const struct bench_load_desc *d,
                            const struct bench_load_result *r);

#endif
