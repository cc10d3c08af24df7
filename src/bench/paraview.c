/* ParaView's views of the same volume, through pvbatch (paraview.h). */
#include "bench/paraview.h"

#include <limits.h>
#include <spawn.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "common/log.h"
#include "data/extfile.h"

extern char **environ;

/* Whether NAME is an executable on PATH. */
static bool on_path(const char *name)
{
    const char *path = getenv("PATH");
    while (path && *path) {
        size_t len = strcspn(path, ":");
        char file[PATH_MAX];
        snprintf(file, sizeof(file), "%.*s/%s", len ? (int)len : 1, len ? path : ".", name);
        if (access(file, X_OK) == 0)
            return true;
        path += len + (path[len] == ':');
    }
    return false;
}

bool bench_paraview_views(const struct bench_paraview_desc *d, const struct ext_volume *vol,
                          const struct bench_views_row *rows, int n)
{
    FILE *report = d->report;
    if (!on_path("pvbatch")) {
        if (report)
            fprintf(report, "ParaView not available (no pvbatch on PATH): the comparison with "
                            "ParaView is skipped\n");
        return true;
    }
    char volume[PATH_MAX + 32], sun[64], size[32], reps[16], anvil[1024];
    if (!bench_make_dir(d->cache_dir))
        return false;
    snprintf(volume, sizeof(volume), "%s/paraview-storm.nc", d->cache_dir);
    struct extfile_writer *ew = extfile_writer_create(volume, &vol->grid, "anvil bench",
                                                      "anvil bench --paraview", NULL);
    if (!ew || !extfile_writer_add(ew, vol, "") || !extfile_writer_finish(ew)) {
        extfile_writer_destroy(ew);
        return false;
    }
    snprintf(sun, sizeof(sun), "%g,%g", d->sun_azimuth_deg, d->sun_elevation_deg);
    snprintf(size, sizeof(size), "%dx%d", d->width, d->height);
    snprintf(reps, sizeof(reps), "%d", d->repeats);
    size_t len = 0;
    for (int i = 0; i < n && len < sizeof(anvil); i++)
        len += (size_t)snprintf(anvil + len, sizeof(anvil) - len, "%s%d:%.3f:%.3f:%.3f:%.3f",
                                i ? "," : "", rows[i].views, rows[i].shared_ms,
                                rows[i].static_ms, rows[i].rebuild_ms, rows[i].view_ms);
    /* pvbatch in Debian needs an X display (GLX); xvfb-run gives it one. */
    bool xvfb = !getenv("DISPLAY") && on_path("xvfb-run");
    char *argv[] = {"xvfb-run", "-a", "pvbatch", (char *)d->script, "--volume", volume,
                    "--sun", sun, "--size", size, "--repeats", reps, "--anvil", anvil,
                    "--out", (char *)d->out_dir, NULL};
    char **args = xvfb ? argv : argv + 2;
    if (report) {
        fprintf(report, "running %s%s (ParaView)\n", xvfb ? "xvfb-run -a " : "", "pvbatch");
        fflush(report);
    }
    pid_t pid;
    int err = posix_spawnp(&pid, args[0], NULL, NULL, args, environ);
    if (err) {
        log_error("bench: cannot run %s: %s", args[0], strerror(err));
        return false;
    }
    int status;
    if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        log_error("bench: %s failed (ParaView side of the views benchmark)", d->script);
        return false;
    }
    return true;
}
