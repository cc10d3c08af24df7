/* The one frame loop of anvil render and anvil run. */
#include "app/loop.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "app/app.h"
#include "common/log.h"
#include "common/progress.h"
#include "render/image.h"
#include "session/animation.h"

#define SCRIPT_FRAMES_MAX 1000000

/* Seconds since the last call (or the script's frame time); the longest frame for --stats. */
static double frame_dt(struct session *s, double *last_ms)
{
    double now = time_now_ms(), dt = (now - *last_ms) * 1e-3;
    *last_ms = now;
    struct session_stats *st = session_stats(s);
    if (st->frame_ms_max < dt * 1e3 && st->frames > 1)
        st->frame_ms_max = dt * 1e3;
    double script = session_script_dt(s);
    return script > 0.0 ? script : dt;
}

/* The frame state -> the GPU -> the light map -> the head, sampled last -> every view. */
static bool draw(struct display *d, struct session *s, struct frame_state *f)
{
    return session_light(s) && display_sample_head(d, f->time_s, &f->head) &&
           session_draw(s, d, f);
}

/* One frame of a render: every frame is drawn, the script's clock stands still. */
static bool render_frame(struct display *d, struct session *s, double dt, double time)
{
    struct frame_state f;
    bool redraw;
    return session_update(s, NULL, dt, time, &f, &redraw) && session_apply(s, &f, NULL) &&
           draw(d, s, &f);
}

/* A scripted render: the script's frames, each drawn (and those in FIRST..LAST written);
 * then the settled result, written when nothing else was. */
static int render_script(struct display *d, struct session *s, const struct loop_desc *ld)
{
    double last = time_now_ms();
    struct progress pr;
    bool writing = ld->output && ld->kind == LOOP_SCRIPT;
    progress_begin(&pr, "render", "frame", (uint64_t)session_script_frames(s));
    long n = 0;
    for (; !session_script_done(s); n++) {
        if (n > SCRIPT_FRAMES_MAX) {
            log_error("the script has not ended after %d frames", SCRIPT_FRAMES_MAX);
            return EXIT_FAILED;
        }
        if (!render_frame(d, s, frame_dt(s, &last), ld->time))
            return EXIT_FAILED;
        if (writing && n >= ld->first && n <= ld->last &&
            !frame_output_add(ld->output, d, (int)(n - (long)ld->first)))
            return EXIT_FAILED;
        if (pr.total < (uint64_t)n + 1) /* a volume still loading holds the end back */
            pr.total = (uint64_t)n + 1;
        progress_update(&pr, (uint64_t)n + 1);
    }
    progress_end(&pr);
    if (!session_settle(s) || !render_frame(d, s, 0.0, ld->time))
        return EXIT_FAILED;
    if (writing && frame_output_frames(ld->output) == 0 &&
        !frame_output_add(ld->output, d, 0))
        return EXIT_FAILED;
    return EXIT_OK;
}

/* A name in the working folder not taken yet: PREFIX-N.EXT (EXT "" for a folder). */
static void free_name(const char *prefix, const char *ext, char *out, size_t size)
{
    struct stat st;
    for (int n = 1; n < 10000; n++) {
        snprintf(out, size, "%s-%d%s", prefix, n, ext);
        if (stat(out, &st) != 0)
            return;
    }
}

/* P: the views as they are, PNG and PFM, in the working folder. */
static void screenshot(struct display *d, struct session *s)
{
    char stamp[64], name[96];
    time_t now = time(NULL);
    strftime(stamp, sizeof(stamp), "anvil-%Y%m%d-%H%M%S", localtime(&now));
    float exposure = (float)session_config(s)->render.exposure;
    bool ok = true;
    if (display_uses_camera(d)) {
        struct image img = {0};
        free_name(stamp, ".png", name, sizeof(name));
        ok = renderer_read(&display_view(d, 0)->target, &img) && image_write(&img, name, exposure);
        char pfm[100];
        snprintf(pfm, sizeof(pfm), "%.*s.pfm", (int)(strlen(name) - 4), name);
        ok = ok && image_write(&img, pfm, exposure);
        image_finish(&img);
        if (ok)
            log_info("screenshot: %s and %s", name, pfm);
    } else {
        free_name(stamp, "", name, sizeof(name));
        ok = display_write_images(d, name, "png", exposure, NULL) &&
             display_write_images(d, name, "pfm", exposure, NULL);
        if (ok)
            log_info("screenshot: %s/ (every view, PNG and PFM)", name);
    }
    if (!ok)
        log_warn("screenshot: not written (see above)");
}

/* C: the view as a block to paste, and a bookmark file that renders it again. */
static void bookmark(struct session *s, const struct loop_desc *ld)
{
    char view[1024], sun[256], name[64], text[4096];
    session_view_text(s, view, sizeof(view));
    session_sun_text(s, sun, sizeof(sun));
    bool tracker = session_uses_tracker(s);
    printf("%s%s", view, tracker ? "" : sun);
    fflush(stdout);
    const char *include = tracker ? ld->display_path : ld->config_path;
    char full[PATH_MAX] = "";
    if (include && !realpath(include, full))
        snprintf(full, sizeof(full), "%s", include);
    free_name("bookmark", ".cfg", name, sizeof(name));
    snprintf(text, sizeof(text), "# anvil bookmark: %s\n%s%s%s%s%s",
             tracker ? "the navigation of a display (anvil render SCENE --display THIS)"
                     : "a view of a scene (anvil render THIS -o view.png)",
             full[0] ? "@include \"" : "", full, full[0] ? "\"\n" : "", view, tracker ? "" : sun);
    if (file_write_atomic(name, text, strlen(text)))
        log_info("bookmark: %s", name);
}

int loop_run(struct display *d, struct session *s, const struct loop_desc *ld)
{
    if (!ld->run && (ld->kind == LOOP_STEPS || ld->kind == LOOP_PATH)) {
        struct animation_desc a = {.path = ld->kind == LOOP_PATH ? ld->path : NULL,
                                   .first = ld->first,
                                   .last = ld->last,
                                   .by = ld->by,
                                   .fps = ld->fps,
                                   .time = ld->time};
        return animation_run(d, s, &a, ld->output) ? EXIT_OK : EXIT_FAILED;
    }
    if (!ld->run)
        return render_script(d, s, ld);

    double t0 = time_now_ms(), last = t0;
    bool moving = display_head_moves(d), dirty = true, idle = false;
    long frames_left = ld->frames;
    struct input_queue *events = malloc(sizeof(*events));
    if (!events) {
        log_error("out of memory");
        return EXIT_FAILED;
    }
    int rc = EXIT_OK;
    while (!session_quit_requested(s) && !display_should_close(d) && frames_left != 0) {
        input_queue_clear(events);
        display_poll_input(d, idle ? 0.03 : 0.0, events);
        double dt = frame_dt(s, &last);
        double time = ld->time + (time_now_ms() - t0) * 1e-3;
        struct frame_state f;
        bool redraw = false, changed = false;
        if (!session_update(s, events, dt, time, &f, &redraw) || !session_apply(s, &f, &changed)) {
            rc = EXIT_FAILED;
            break;
        }
        unsigned requests = session_take_requests(s);
        bool drawn = dirty || redraw || changed || moving || frames_left > 0;
        if (drawn) {
            if (!draw(d, s, &f)) {
                rc = EXIT_FAILED;
                break;
            }
            dirty = false;
            if (frames_left > 0)
                frames_left--;
        }
        if (requests & SESSION_REQUEST_SCREENSHOT)
            screenshot(d, s);
        if (requests & SESSION_REQUEST_BOOKMARK)
            bookmark(s, ld);
        idle = !drawn;
    }
    free(events);
    return rc;
}
