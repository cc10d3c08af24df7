/* A CAVE on 1, 2 and 4 ranks: milliseconds a frame and the collectives' share. */
#include "bench/cluster.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bench/bench.h"
#include "cluster/cluster.h"
#include "common/log.h"

#define MAX_RANKS 4

/* One job's figures: the slowest rank's loop, every rank's collectives, per frame. */
struct job {
    int frames;
    double frame_ms;      /* the slowest rank's frame loop / frames */
    double collective_ms; /* the ranks' mean time in collectives / frames */
};

/* Every number after "KEY": in TEXT, in order, into OUT (at most MAX); how many. */
static int numbers(const char *text, const char *key, double *out, int max)
{
    char pat[64];
    snprintf(pat, sizeof(pat), "\"%s\": ", key);
    int n = 0;
    for (const char *p = strstr(text, pat); p && n < max; p = strstr(p + 1, pat))
        out[n++] = strtod(p + strlen(pat), NULL);
    return n;
}

/* Runs the program on DISPLAY with RANKS ranks (1: no mpirun), walls HEIGHT pixels high,
 * turning through the script of the temporary folder TMP. */
static bool run_job(const char *exe, const char *tmp, const char *display, int ranks,
                    int height, int light, struct job *out)
{
    char cmd[4 * PATH_MAX], launcher[128] = "";
    if (ranks > 1)
        snprintf(launcher, sizeof(launcher), "mpirun --oversubscribe --bind-to none -np %d ",
                 ranks);
    snprintf(cmd, sizeof(cmd),
             "cd '%s' && rm -rf out && mkdir out && %s'%s' --quiet render --display '%s' "
             "--input turn.txt -o out/ --stats stats.json --set render.height=%d "
             "--set 'lightmap.resolution=[%d,%d,%d]' >log.txt 2>&1",
             tmp, launcher, exe, display, height, light, light, light);
    int st = system(cmd);
    if (!WIFEXITED(st) || WEXITSTATUS(st) != 0) {
        char path[PATH_MAX + 16];
        snprintf(path, sizeof(path), "%s/log.txt", tmp);
        char *log = file_read_all(path, NULL);
        log_error("bench: %d rank%s on %s failed:\n%s", ranks, ranks == 1 ? "" : "s", display,
                  log ? log : "");
        free(log);
        return false;
    }
    char path[PATH_MAX + 16];
    snprintf(path, sizeof(path), "%s/stats.json", tmp);
    char *json = file_read_all(path, NULL);
    if (!json)
        return false;
    double loop[MAX_RANKS], first[MAX_RANKS], sync[MAX_RANKS], sync1[MAX_RANKS];
    double frames[MAX_RANKS];
    int nl = numbers(json, "loop_ms", loop, MAX_RANKS);
    int n1 = numbers(json, "first_frame_ms", first, MAX_RANKS);
    int ns = numbers(json, "sync_ms", sync, MAX_RANKS);
    int ns1 = numbers(json, "first_sync_ms", sync1, MAX_RANKS);
    int nf = numbers(json, "frames", frames, MAX_RANKS);
    free(json);
    if (nl != ranks || n1 != ranks || nf != ranks || (ranks > 1 && (ns != ranks || ns1 != ranks)) ||
        frames[0] < 3) {
        log_error("bench: %s: the stats of %d ranks were expected", path, ranks);
        return false;
    }
    /* The first frame (shaders, the light map) is left out of both. */
    out->frames = (int)frames[0] - 1;
    double worst = 0.0, sum = 0.0;
    for (int r = 0; r < ranks; r++) {
        worst = fmax(worst, loop[r] - first[r]);
        sum += ranks > 1 ? sync[r] - sync1[r] : 0.0;
    }
    out->frame_ms = worst / out->frames;
    out->collective_ms = sum / ranks / out->frames;
    return true;
}

/* The fastest of REPEATS runs (the machine's noise is one way: slower). */
static bool best_job(const char *exe, const char *tmp, const char *display, int ranks,
                     int height, int light, int repeats, struct job *out)
{
    for (int i = 0; i < repeats; i++) {
        struct job j;
        if (!run_job(exe, tmp, display, ranks, height, light, &j))
            return false;
        if (i == 0 || j.frame_ms < out->frame_ms)
            *out = j;
    }
    return true;
}

bool bench_cluster_possible(void)
{
    return cluster_available() && system("command -v mpirun >/dev/null 2>&1") == 0;
}

bool bench_cluster(const struct bench_cluster_desc *d)
{
    if (!cluster_available()) {
        log_error("bench: the cluster benchmark needs anvil built with MPI (libopenmpi-dev)");
        return false;
    }
    if (system("command -v mpirun >/dev/null 2>&1") != 0) {
        log_error("bench: the cluster benchmark needs mpirun on PATH (openmpi-bin)");
        return false;
    }
    char exe[PATH_MAX];
    ssize_t len = readlink("/proc/self/exe", exe, sizeof(exe) - 1);
    if (len <= 0) {
        log_error("bench: where this anvil lies is unknown (/proc/self/exe)");
        return false;
    }
    exe[len] = '\0';
    if (geteuid() == 0) { /* Open MPI refuses root unless told twice */
        setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 0);
        setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 0);
    }
    char tmp[] = "/tmp/anvil-bench-cluster-XXXXXX";
    if (!mkdtemp(tmp)) {
        log_error("bench: no temporary folder for the cluster benchmark");
        return false;
    }
    int frames = d->quick ? 6 : 24, height = d->quick ? 32 : 128, light = d->quick ? 24 : 64;
    int repeats = d->quick ? 1 : 2;
    char script[PATH_MAX + 16];
    snprintf(script, sizeof(script), "%s/turn.txt", tmp);
    FILE *f = fopen(script, "w");
    if (!f) {
        log_error("%s: cannot write", script);
        return false;
    }
    fprintf(f, "# every frame turns the view: each wall drawn again, the light map kept\n");
    for (int i = 0; i < frames; i++)
        fprintf(f, "%d key turn-left\n", i);
    fclose(f);

    static const char *const names[] = {"cave4", "cave6"};
    static const int rank_counts[] = {1, 2, MAX_RANKS};
    struct job jobs[2][3], tiny[2][3];
    bool ok = true;
    for (int k = 0; ok && k < 2; k++) {
        char display[PATH_MAX];
        snprintf(display, sizeof(display), "%s/%s.cfg", d->displays, names[k]);
        for (int r = 0; ok && r < 3; r++) {
            if (d->report)
                fprintf(d->report, "cluster: %s on %d rank%s\n", names[k], rank_counts[r],
                        rank_counts[r] == 1 ? "" : "s");
            ok = best_job(exe, tmp, display, rank_counts[r], height, light, repeats,
                          &jobs[k][r]) &&
                 best_job(exe, tmp, display, rank_counts[r], 4, 8, repeats, &tiny[k][r]);
        }
    }
    char rm[PATH_MAX + 16];
    snprintf(rm, sizeof(rm), "rm -rf '%s'", tmp);
    if (system(rm) != 0)
        log_warn("bench: %s was not removed", tmp);
    if (!ok)
        return false;

    char *buf = NULL;
    size_t blen = 0;
    f = open_memstream(&buf, &blen);
    if (!f) {
        log_error("bench: out of memory");
        return false;
    }
    fprintf(f, "<!-- written by anvil bench%s: do not edit -->\n", d->quick ? " --quick" : "");
    fprintf(f,
            "# A CAVE on several ranks\n\n"
            "The built-in storm on `displays/cave4.cfg` (4 stereo walls: 8 views) and "
            "`displays/cave6.cfg` (6 stereo walls: 12 views), walls %d pixels high, a %d^3 "
            "light map, %d frames that each turn the view (every wall drawn again, the light "
            "map kept; the first frame, which builds it, left out), as `anvil render --display D --input SCRIPT` draws them in one process "
            "and `mpirun --oversubscribe -np N` of it on this one machine (each rank its "
            "walls, its own data and light map, the frame state from rank 0).  A frame is "
            "the slowest rank's frame loop over the frames; the collectives are the mean "
            "rank's time in the frame broadcast, the agreements and the barrier, per frame "
            "(its wait for slower ranks included).  The fastest of %d runs.  Device: %s.\n\n",
            height, light, frames, repeats, d->device);
    fprintf(f, "| display | ranks | ms a frame | to one process | collectives, ms a frame | "
               "with walls of 4 pixels: ms a frame | collectives, ms a frame |\n"
               "|---|---|---|---|---|---|---|\n");
    for (int k = 0; k < 2; k++)
        for (int r = 0; r < 3; r++) {
            const struct job *j = &jobs[k][r], *t = &tiny[k][r];
            fprintf(f, "| %s | %d | %.1f | %.2f | %.2f | %.2f | %.2f |\n", names[k],
                    rank_counts[r], j->frame_ms, j->frame_ms / jobs[k][0].frame_ms,
                    j->collective_ms, t->frame_ms, t->collective_ms);
        }
    fprintf(f, "\nOn one machine the ranks share its %ld cores and its one GPU%s: what the "
               "table shows is what sharing the walls out costs there (the collectives; with "
               "walls of 4 pixels, little else), and whether several processes keep the cores "
               "busier than one does (a ratio below 1: one process left them idle between its "
               "views).  On a cluster each rank has a node and a GPU of its own, and a frame "
               "takes the slowest rank's walls plus the collectives.\n",
            sysconf(_SC_NPROCESSORS_ONLN),
            strstr(d->device, "llvmpipe") ? " (here a CPU rasteriser: the times are only "
                                            "meaningful as ratios)"
                                          : "");
    fclose(f);
    char table[PATH_MAX + 32];
    snprintf(table, sizeof(table), "%s/cluster-table.md", d->out);
    ok = file_write_atomic(table, buf, blen);
    if (ok && d->report)
        fprintf(d->report, "%s", buf);
    free(buf);
    return ok;
}
