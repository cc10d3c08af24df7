/*
 * bench/cluster: what drawing a CAVE on several ranks costs and gains.  The built-in storm on
 * displays/cave4.cfg and cave6.cfg, every frame turning the view (each wall redrawn, no light
 * map rebuilt), as `anvil render --display D --input SCRIPT` draws it in one process and as
 * `mpirun -np 2` and `-np 4` of it do: milliseconds a frame, their ratio to one process, and
 * the time each rank spends in the cluster's collectives (the frame broadcast, the agreements,
 * the barrier), measured again with walls of a few pixels, where there is little else.
 * Written as cluster-table.md.  Runs the program itself through mpirun (Open MPI).
 */
#ifndef ANVIL_BENCH_CLUSTER_H
#define ANVIL_BENCH_CLUSTER_H

#include <stdbool.h>
#include <stdio.h>

struct bench_cluster_desc {
    bool quick;           /* walls of 32 pixels, 6 frames, one repeat */
    const char *out;      /* the folder of cluster-table.md */
    const char *displays; /* the folder of cave4.cfg and cave6.cfg */
    const char *device;   /* the GPU's name, for the table */
    FILE *report;         /* the table is echoed here; NULL: not */
};

/* Whether this anvil has MPI and mpirun is on PATH (quietly). */
bool bench_cluster_possible(void);

/* Measures and writes cluster-table.md.  False (logged) on failure, or when this anvil was
 * built without MPI or mpirun is not on PATH (said so). */
bool bench_cluster(const struct bench_cluster_desc *d);

#endif
