/* anvil render and run under mpirun: which walls this rank draws, the start every rank must
 * pass together, the swap, the stats gathered on rank 0. */
#include "app/cluster_walls.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "cluster/cluster.h"
#include "common/log.h"
#include "gpu/gpu.h"

/* The walls CFG gives rank R of SIZE, as "front, left" into OUT. */
static void wall_names(const struct display_config *cfg, int r, int size, char *out, size_t len)
{
    size_t used = 0;
    out[0] = '\0';
    for (int w = 0; w < cfg->wall_count && used < len; w++) {
        int owner = cfg->walls[w].rank >= 0 ? cfg->walls[w].rank : w % size;
        if (owner == r)
            used += (size_t)snprintf(out + used, len - used, "%s%s", used ? ", " : "",
                                     cfg->walls[w].name);
    }
}

/* A refusal every rank reaches alike: said once, by rank 0. */
#define refuse(...)                                                                           \
    do {                                                                                      \
        out->refused = true;                                                                  \
        if (cluster_rank() == 0)                                                              \
            log_error(__VA_ARGS__);                                                           \
    } while (0)

int app_cluster_walls(const char *display_path, struct display_config *cfg,
                      struct cluster_walls *out)
{
    memset(out, 0, sizeof(*out));
    int rank = cluster_rank(), size = cluster_size();
    if (!cluster_active())
        return EXIT_OK;
    if (!display_path) {
        refuse("under mpirun every rank draws walls of a display: give --display "
                  "DISPLAY.cfg (a cave, stereo, desktop or headless display)");
        return EXIT_USAGE;
    }
    if (cfg->type == DISPLAY_TYPE_HMD || cfg->type == DISPLAY_TYPE_OPENXR) {
        refuse("%s: display.type = \"%s\" is one headset on one GPU: run it without mpirun",
                  display_path, display_type_name(cfg->type));
        return EXIT_BAD_INPUT;
    }
    for (int w = 0; w < cfg->wall_count; w++) {
        if (cfg->walls[w].rank >= size) {
            refuse("%s:%d: walls.[%d].rank = %d, but this job has %d rank%s (0 to %d)",
                      display_path, cfg->walls[w].line, w, cfg->walls[w].rank, size,
                      size == 1 ? "" : "s", size - 1);
            return EXIT_BAD_INPUT;
        }
    }
    for (int r = 0; r < size; r++) {
        char names[256];
        wall_names(cfg, r, size, names, sizeof(names));
        if (!names[0]) {
            refuse("%s: rank %d of %d has no wall to draw (%d wall%s): start at most %d "
                      "ranks, or give each rank a wall with walls.[i].rank",
                      display_path, r, size, cfg->wall_count, cfg->wall_count == 1 ? "" : "s",
                      cfg->wall_count);
            return EXIT_BAD_INPUT;
        }
    }
    wall_names(cfg, rank, size, out->names, sizeof(out->names));
    out->all = *cfg;
    out->active = true;
    display_config_walls_of_rank(cfg, rank, size);
    log_info("cluster: %d ranks; rank 0 draws %s", size, out->names);
    return EXIT_OK;
}

bool app_cluster_gate(bool ok, const struct cluster_walls *cw)
{
    if (!cluster_active())
        return ok;
    bool said = cw && cw->refused; /* by rank 0, for every rank */
    if (!ok && !said && cw && cw->active)
        log_error("rank %d (walls %s) could not start (see above): the cluster stops",
                  cluster_rank(), cw->names);
    else if (!ok && !said)
        log_error("rank %d could not start (see above): the cluster stops", cluster_rank());
    return cluster_all(ok);
}

void app_cluster_before_swap(void *user)
{
    double *sync_ms = user, t = time_now_ms();
    gpu_finish();      /* every rank's walls are drawn ... */
    cluster_barrier(); /* ... before any of them swaps */
    *sync_ms += time_now_ms() - t;
}

void app_cluster_swap_group(const struct display *d)
{
    if (!cluster_active())
        return;
    bool grouped = cluster_all(display_swap_grouped(d));
    if (cluster_rank() != 0)
        return;
    if (grouped)
        log_info("cluster: every window is in swap group 1 (GLX_NV_swap_group): the walls "
                 "swap together on the framelock");
    else
        log_info("cluster: no swap group (GLX_NV_swap_group) on every rank: the walls swap "
                 "after an MPI barrier alone");
}

bool app_cluster_stats(const struct session_stats *st, const struct cluster_walls *cw,
                       const char *path, bool worked)
{
    char *mine = NULL;
    size_t len = 0;
    bool ok = worked && session_stats_json(st, cw->active ? cluster_rank() : -1,
                                 cw->active ? cw->names : NULL, &mine, &len);
    if (!cluster_active()) {
        ok = ok && file_write_atomic(path, mine, len);
        free(mine);
        return ok;
    }
    char **texts = cluster_gather_text(ok ? mine : "");
    free(mine);
    bool all = cluster_all(ok);
    if (cluster_rank() != 0)
        return all;
    char *buf = NULL;
    size_t blen = 0;
    FILE *f = open_memstream(&buf, &blen);
    if (!f || !texts) {
        if (f)
            fclose(f);
        free(buf);
        cluster_free_texts(texts);
        log_error("%s: out of memory", path);
        return false;
    }
    fprintf(f, "{\n  \"command\": \"%s\",\n  \"cluster_ranks\": %d,\n  \"ranks\": [\n",
            st->command ? st->command : "", cluster_size());
    for (int r = 0; r < cluster_size(); r++)
        fprintf(f, "%s%s", texts[r], r + 1 < cluster_size() ? ",\n" : "\n");
    fprintf(f, "  ]\n}\n");
    fclose(f);
    cluster_free_texts(texts);
    ok = all && file_write_atomic(path, buf, blen);
    free(buf);
    return ok;
}
