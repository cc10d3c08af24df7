/* The default storm's movie: frames per second drawn, and written through the encoder. */
#include "bench/movie.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "common/log.h"
#include "config/camera_path.h"
#include "config/config.h"
#include "display/display.h"
#include "session/animation.h"
#include "session/camera_path.h"
#include "session/output.h"
#include "session/scene.h"
#include "session/session.h"

#define FPS 24

/* Four keys round the storm's centre, 45 km out and 10 km up, over DURATION seconds. */
static void orbit_path(double duration, struct camera_path *p)
{
    memset(p, 0, sizeof(*p));
    const double c[3] = {30.0, 30.0, 6.0};
    const double around[5][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}, {-1, -1}};
    p->count = 5;
    for (int i = 0; i < p->count; i++) {
        struct camera_key *k = &p->keys[i];
        k->time_s = duration * i / (p->count - 1);
        k->position_km[0] = c[0] + 32.0 * around[i][0];
        k->position_km[1] = c[1] + 32.0 * around[i][1];
        k->position_km[2] = 10.0;
        memcpy(k->target_km, c, sizeof(c));
        k->up[2] = 1.0;
        k->fov_deg = 50.0;
    }
}

/* Frame by frame, each drawn alone and then drawn and written, side by side, so that the
 * machine's load falls on both alike: frames per second of each. */
static bool measure(struct display *d, struct session *s, const struct animation_desc *a,
                    struct frame_output *out, double *draw_fps, double *written_fps)
{
    double drawn_ms = 0.0, written_ms = 0.0;
    long n = animation_frames(a);
    for (long i = 0; i < n; i++) {
        struct animation_desc one = *a;
        one.first = one.last = a->first + (double)i;
        double t0 = time_now_ms();
        if (!animation_run(d, s, &one, NULL))
            return false;
        double t1 = time_now_ms();
        if (!animation_run(d, s, &one, out))
            return false;
        drawn_ms += t1 - t0;
        written_ms += time_now_ms() - t1;
    }
    *draw_fps = drawn_ms > 0.0 ? 1e3 * (double)n / drawn_ms : 0.0;
    *written_fps = written_ms > 0.0 ? 1e3 * (double)n / written_ms : 0.0;
    return true;
}

bool bench_movie(const struct bench_movie_desc *d, struct bench_movie_result *out)
{
    memset(out, 0, sizeof(*out));
    struct config *cfg = malloc(sizeof(*cfg));
    struct camera_path *path = malloc(sizeof(*path));
    struct display *disp = NULL;
    struct session *s = NULL;
    bool ok = false;
    if (!cfg || !path) {
        log_error("bench: out of memory");
        goto done;
    }
    config_defaults(cfg);
    if (d->quick) {
        cfg->render.width = 160;
        cfg->render.height = 120;
        cfg->scene.size[0] = cfg->scene.size[1] = 32;
        cfg->scene.size[2] = 16;
    }
    orbit_path(d->quick ? 0.5 : 2.0, path);
    struct display_config dcfg;
    display_config_defaults(&dcfg);
    dcfg.type = DISPLAY_TYPE_ORBIT;
    dcfg.window_size[0] = cfg->render.width;
    dcfg.window_size[1] = cfg->render.height;
    struct display_desc dd = {.offscreen = true, .context = d->context,
                              .height = cfg->render.height};
    scene_camera(cfg, &dd.camera);
    disp = display_create(&dcfg, &dd);
    if (!disp || !display_update(disp, 0.0))
        goto done;
    int rc;
    s = session_create(cfg, &(struct session_desc){.command = "bench", .display = &dcfg,
                                                    .views_move = true},
                       &rc);
    if (!s)
        goto done;
    struct animation_desc a = {.path = path, .fps = FPS,
                               .last = (double)(int)(camera_path_duration(path) * FPS)};
    out->frames = (int)animation_frames(&a);
    out->width = cfg->render.width;
    out->height = cfg->render.height;
    char movie[1200];
    snprintf(movie, sizeof(movie), "%s/bench-movie-%ld.mp4", d->out, (long)getpid());
    struct frame_output *o = frame_output_open(&(struct frame_output_desc){
        .path = movie, .fps = FPS, .exposure = (float)cfg->render.exposure});
    if (!o)
        goto done;
    /* One frame first: the shaders compiled and the light map built (the sun does not move),
     * so neither measurement pays for what the other does not. */
    struct animation_desc warm = a;
    warm.last = 0.0;
    if (!animation_run(disp, s, &warm, NULL) ||
        !measure(disp, s, &a, o, &out->draw_fps, &out->written_fps)) {
        frame_output_abort(o);
        goto done;
    }
    if (!frame_output_close(o))
        goto done;
    struct stat st;
    out->movie_bytes = stat(movie, &st) == 0 ? (double)st.st_size : 0.0;
    unlink(movie);
    out->light_builds = session_stats(s)->light_builds;

    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    fprintf(f, "<!-- written by anvil bench%s: do not edit -->\n", d->quick ? " --quick" : "");
    fprintf(f, "# What a movie of the default storm costs\n\n"
               "The built-in storm (`configs/default.cfg`: %d x %d x %d voxels, %d x %d "
               "pixels) flown round by a camera path of %d frames at %d frames a second, "
               "as `anvil render --path PATH -o storm.mp4` draws it: each frame drawn alone, "
               "then drawn, read back and encoded (H.264, CRF 18), side by side. Device: %s.\n\n",
            cfg->scene.size[0], cfg->scene.size[1], cfg->scene.size[2], out->width, out->height,
            out->frames, FPS, d->device);
    fprintf(f, "| frames | drawn, frames/s | written to the movie, frames/s | read-back and "
               "encoding, share of a written frame | light map builds | movie bytes |\n"
               "|---|---|---|---|---|---|\n");
    double share = out->draw_fps > 0.0 ? 1.0 - out->written_fps / out->draw_fps : 0.0;
    char share_text[32];
    if (share < 0.01) /* within the noise of the side-by-side timing */
        snprintf(share_text, sizeof(share_text), "under 1 %%");
    else
        snprintf(share_text, sizeof(share_text), "%.0f %%", 100.0 * share);
    fprintf(f, "| %d | %.2f | %.2f | %s | %u | %.0f |\n", out->frames, out->draw_fps,
            out->written_fps, share_text, out->light_builds, out->movie_bytes);
    fclose(f);
    char table[1200];
    snprintf(table, sizeof(table), "%s/movie-table.md", d->out);
    ok = file_write_atomic(table, buf, len);
    if (ok && d->report)
        fprintf(d->report, "%s", buf);
    free(buf);
done:
    session_destroy(s);
    display_destroy(disp);
    free(cfg);
    free(path);
    return ok;
}
