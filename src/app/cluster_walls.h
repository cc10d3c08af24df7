/*
 * app/cluster_walls: anvil render and run under mpirun (cluster/cluster.h).  Each rank draws
 * the walls its display config gives it; every rank starts, swaps and ends together; --stats
 * gathers every rank's on rank 0.  Without a cluster each of these does the one-process thing.
 */
#ifndef ANVIL_APP_CLUSTER_WALLS_H
#define ANVIL_APP_CLUSTER_WALLS_H

#include <stdbool.h>

#include "config/display_config.h"
#include "display/display.h"
#include "session/stats.h"

struct cluster_walls {
    bool active;                /* a cluster of more than one rank */
    struct display_config all;  /* the display with every wall (views for the effects) */
    char names[256];            /* this rank's walls, "front, left" */
    bool refused;               /* app_cluster_walls refused the job (every rank alike) */
};

/* Keeps in CFG (loaded from DISPLAY_PATH, NULL: none) the walls of this rank, the whole
 * display in OUT.  Refuses (logged, an exit code) a cluster without a display of walls, a
 * headset, a walls.[i].rank beyond the job and a rank without a wall: every rank decides
 * alike, so all of them stop together. */
int app_cluster_walls(const char *display_path, struct display_config *cfg,
                      struct cluster_walls *out);

/* Whether every rank started (OK is this rank's word).  A rank that did not says which it
 * is and its walls; then every rank stops.  Each rank calls it once, failed or not. */
bool app_cluster_gate(bool ok, const struct cluster_walls *cw);

/* display_desc.before_swap of a rank: its GPU done, then the barrier of all ranks (USER: a
 * double of milliseconds it adds its wait to). */
void app_cluster_before_swap(void *user);

/* Says once (rank 0) whether the windows swap in a swap group or after the barrier alone. */
void app_cluster_swap_group(const struct display *d);

/* Writes --stats PATH: one process's, or on a cluster every rank's in "ranks" (rank 0
 * writes, only when every rank's work was done: WORKED). */
bool app_cluster_stats(const struct session_stats *st, const struct cluster_walls *cw,
                       const char *path, bool worked);

#endif
