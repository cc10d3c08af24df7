#include "bench/playback.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bench/load.h"
#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "session/scene.h"
#include "session/session.h"

#define MAX_FRAMES 2000
#define WARM_LIMIT_MS 300000.0 /* the cache filling before the clock starts */
#define PLAY_LIMIT_MS 240000.0 /* one way of playing the series */

/* The CPU time of every thread of this process, ms.  On a CPU rasteriser the GPU's work is
 * this process's threads' too, and other jobs on a shared machine do not count. */
static double cpu_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    if (n == 0)
        return 0.0;
    qsort(v, (size_t)n, sizeof(*v), compare_doubles);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* One frame as anvil run draws it, waited for (so that its time is its work). */
static bool frame(struct session *s, struct display *disp, double dt, double time_s)
{
    struct frame_state f;
    bool redraw;
    bool ok = session_update(s, NULL, dt, time_s, &f, &redraw) && session_apply(s, &f, NULL) &&
              session_light(s) && display_sample_head(disp, f.time_s, &f.head) &&
              session_draw(s, disp, &f);
    gpu_finish();
    return ok;
}

/* Plays CFG's series once, staged or not, into OUT. */
static bool play(const struct bench_playback_desc *d, const struct config *cfg, bool staged,
                 struct bench_playback_run *out)
{
    memset(out, 0, sizeof(*out));
    struct display_config dcfg;
    display_config_defaults(&dcfg);
    dcfg.type = DISPLAY_TYPE_ORBIT;
    dcfg.window_size[0] = cfg->render.width;
    dcfg.window_size[1] = cfg->render.height;
    struct display_desc dd = {.offscreen = true, .context = d->context,
                              .height = cfg->render.height};
    scene_camera(cfg, &dd.camera);
    struct display *disp = display_create(&dcfg, &dd);
    struct session *s = NULL;
    double *normal = malloc(MAX_FRAMES * sizeof(double));
    bool ok = false;
    if (!normal || !disp || !display_update(disp, 0.0))
        goto done;
    int rc;
    s = session_create(cfg,
                       &(struct session_desc){.command = "run",
                                              .display = &dcfg,
                                              .views_move = true,
                                              .interactive = true,
                                              .playback = true,
                                              .unstaged = !staged,
                                              .probe = true},
                       &rc);
    if (!s)
        goto done;
    int steps = session_step_count(s);
    /* Every step in the cache and the next one readied: the clock then measures the frames. */
    double start = time_now_ms(), t = 0.0;
    for (int quiet = 0; quiet < 3;) {
        if (!frame(s, disp, 0.0, t))
            goto done;
        bool more = false;
        for (int k = 0; k < 64 && staged; k++) {
            if (!session_prepare(s, &more))
                goto done;
            if (!more)
                break;
        }
        quiet = session_stats(s)->cache_steps >= steps && !more ? quiet + 1 : 0;
        if (time_now_ms() - start > WARM_LIMIT_MS) {
            log_error("bench: playback: the series did not load within %.0f s",
                      WARM_LIMIT_MS / 1e3);
            goto done;
        }
        usleep(20000);
    }
    log_info("bench: playback (%s): %d steps cached, playing", staged ? "staged" : "in the frame",
             steps);
    session_set_playing(s, true);
    const struct render_stats *rs = renderer_stats(session_renderer(s));
    int shown = session_step_shown(s), normals = 0;
    double play_start = time_now_ms(), last = play_start, first_change = 0.0, last_change = 0.0;
    int steps_after_first = 0;
    double kind_start[SESSION_PIECE_KINDS]; /* the work by kind before the clock started */
    memcpy(kind_start, session_stats(s)->prepare_kind_ms, sizeof(kind_start));
    double light_start[LIGHT_BUILD_PHASES];
    memcpy(light_start, session_stats(s)->prepare_light_ms, sizeof(light_start));
    while (shown < steps - 1 && out->frames < MAX_FRAMES) {
        double t0 = time_now_ms(), c0 = cpu_now_ms();
        double bytes = (double)rs->upload_bytes;
        bool copying = renderer_stage_copying(session_renderer(s));
        unsigned builds = session_stats(s)->light_builds;
        if (!frame(s, disp, (t0 - last) * 1e-3, (t0 - play_start) * 1e-3))
            goto done;
        last = t0;
        double c1 = cpu_now_ms(), ms = c1 - c0;
        out->frames++;
        int advanced = session_step_shown(s) - shown;
        shown = session_step_shown(s);
        if (advanced != 0) {
            if (out->changes > 0) {
                out->gap_max_s = fmax(out->gap_max_s, (t0 - last_change) * 1e-3);
                steps_after_first += advanced;
            } else {
                first_change = t0;
            }
            last_change = t0;
            out->changes++;
            out->skipped += advanced > 1 ? advanced - 1 : 0;
            out->change_max_ms = fmax(out->change_max_ms, ms);
            out->change_bytes += (double)rs->upload_bytes - bytes;
            out->change_builds += session_stats(s)->light_builds - builds;
        } else {
            normal[normals++] = ms;
        }
        if (copying)
            out->copy_max_ms = fmax(out->copy_max_ms, ms);
        else if (advanced == 0)
            out->quiet_max_ms = fmax(out->quiet_max_ms, ms);
        out->max_ms = fmax(out->max_ms, ms);
        int step;
        double acc;
        bool playing;
        session_cursor(s, &step, &acc, &playing);
        if (playing && acc >= 1.0 - 1e-9)
            out->stalls++;
        bool more = false;
        if (!session_prepare(s, &more))
            goto done;
        double t2 = time_now_ms(), c2 = cpu_now_ms();
        if (c2 - c1 > out->prepare_max_ms) {
            /* What that stretch's longest piece was. */
            const struct session_stats *st = session_stats(s);
            out->prepare_max_ms = c2 - c1;
            out->prepare_piece = st->prepare_piece;
            out->prepare_piece_ms = st->prepare_piece_ms;
        }
        out->work_ms += c2 - c1;
        if (session_stats(s)->prepare_piece_ms > out->longest_piece_ms) {
            out->longest_piece = session_stats(s)->prepare_piece;
            out->longest_piece_ms = session_stats(s)->prepare_piece_ms;
        }
        out->interval_max_ms = fmax(out->interval_max_ms, c2 - c0);
        if (t2 - play_start > PLAY_LIMIT_MS) {
            log_error("bench: playback: %d of %d step changes within %.0f s", out->changes,
                      steps - 1, PLAY_LIMIT_MS / 1e3);
            goto done;
        }
    }
    if (steps_after_first > 0 && last_change > first_change)
        out->steps_per_s = steps_after_first / ((last_change - first_change) * 1e-3);
    out->median_ms = median(normal, normals);
    for (int k = 0; k < SESSION_PIECE_KINDS; k++)
        out->kind_ms[k] = session_stats(s)->prepare_kind_ms[k] - kind_start[k];
    for (int k = 0; k < LIGHT_BUILD_PHASES; k++)
        out->light_ms[k] = session_stats(s)->prepare_light_ms[k] - light_start[k];
    ok = shown == steps - 1;
    if (!ok)
        log_error("bench: playback: %d frames played to step %d of %d", out->frames, shown,
                  steps - 1);
done:
    session_destroy(s);
    display_destroy(disp);
    free(normal);
    return ok;
}

bool bench_playback(const struct bench_playback_desc *d, struct bench_playback_result *out)
{
    memset(out, 0, sizeof(*out));
    const int big[3] = {500, 500, 100}, small[3] = {64, 64, 20};
    memcpy(out->n, d->quick ? small : big, sizeof(out->n));
    out->steps = d->quick ? 4 : 6;
    out->width = d->quick ? 160 : 320;
    out->height = d->quick ? 120 : 240;
    out->speed = 0.5;
    out->volume_mb = (double)out->n[0] * out->n[1] * out->n[2] * 8 / (1 << 20);
    char path[CONFIG_PATH_MAX];
    const char *dir = d->dir ? d->dir : getenv("TMPDIR");
    int len = snprintf(path, sizeof(path), "%.900s/anvil-bench-playback-%ld.nc",
                       dir && dir[0] ? dir : "/tmp", (long)getpid());
    if (len < 0 || len >= (int)sizeof(path)) {
        log_error("bench: playback: the folder for the series is too long a path");
        return false;
    }
    log_info("bench: playback: writing a %d x %d x %d series of %d steps to %s", out->n[0],
             out->n[1], out->n[2], out->steps, path);
    struct config *cfg = malloc(sizeof(*cfg));
    bool ok = false;
    if (!cfg) {
        log_error("bench: out of memory");
        return false;
    }
    if (!bench_write_storm_series(path, out->n, out->steps))
        goto done;
    config_defaults(cfg);
    cfg->scene.kind = SCENE_DATA;
    cfg->data.format = DATA_WRF;
    memcpy(cfg->data.files[0], path, sizeof(path));
    cfg->data.file_count = 1;
    cfg->data.prefetch = out->steps;
    cfg->data.cache_memory_mb = (out->steps + 2) * out->volume_mb + 256.0;
    cfg->playback.speed = out->speed;
    cfg->playback.loop = false;
    cfg->render.width = out->width;
    cfg->render.height = out->height;
    cfg->overlay.when = OVERLAY_NEVER;
    if (!config_validate(cfg))
        goto done;
    double lo[3], hi[3];
    if (!scene_domain_box(cfg, lo, hi))
        goto done;
    struct display_camera c;
    scene_frame_camera(lo, hi, cfg->camera.fov_deg, (double)out->width / out->height,
                       cfg->camera.near_m, &c);
    scene_camera_to_config(&c, &cfg->camera);
    /* Side by side: the way it was, then staged, in one run. */
    ok = play(d, cfg, false, &out->unstaged) && play(d, cfg, true, &out->staged);
done:
    remove(path);
    free(cfg);
    return ok;
}

void bench_write_playback_table(FILE *f, const struct bench_playback_desc *d,
                                const struct bench_playback_result *r)
{
    const struct bench_playback_run *runs[2] = {&r->unstaged, &r->staged};
    const char *names[2] = {"in the frame (before)", "staged between frames"};
    fprintf(f, "| measure | %s | %s |\n| --- | ---: | ---: |\n", names[0], names[1]);
#define ROW(label, fmt, ...)                                                                       \
    do {                                                                                          \
        fprintf(f, "| %s |", label);                                                              \
        for (int i = 0; i < 2; i++) {                                                             \
            const struct bench_playback_run *u = runs[i];                                         \
            fprintf(f, " " fmt " |", __VA_ARGS__);                                                 \
        }                                                                                         \
        fprintf(f, "\n");                                                                         \
    } while (0)
    ROW("frames played / step changes among them", "%d / %d", u->frames, u->changes);
    ROW("steps skipped (the cursor moved on two at once)", "%d", u->skipped);
    ROW("steps per second (first to last step change)", "%.2f", u->steps_per_s);
    ROW("the longest time between two step changes, s", "%.2f", u->gap_max_s);
    ROW("a normal frame, CPU ms (median)", "%.0f", u->median_ms);
    ROW("the longest frame, CPU ms", "%.0f", u->max_ms);
    ROW("**the longest frame ÷ a normal one**", "**%.2f**",
        u->median_ms > 0.0 ? u->max_ms / u->median_ms : 0.0);
    ROW("the longest step-change frame ÷ a normal one", "%.2f",
        u->median_ms > 0.0 ? u->change_max_ms / u->median_ms : 0.0);
    ROW("the longest frame while the stage's copy was under way ÷ a normal one", "%.2f",
        u->median_ms > 0.0 ? u->copy_max_ms / u->median_ms : 0.0);
    ROW("the longest of the other frames ÷ a normal one", "%.2f",
        u->median_ms > 0.0 ? u->quiet_max_ms / u->median_ms : 0.0);
    ROW("bytes uploaded in step-change frames", "%.0f", u->change_bytes);
    ROW("light maps built in step-change frames", "%u", u->change_builds);
    ROW("the longest work between two frames, CPU ms", "%.0f", u->prepare_max_ms);
    ROW("the longest stretch's longest piece", "%s", u->prepare_piece ? u->prepare_piece : "—");
    ROW("that piece, CPU ms", "%.0f", u->prepare_piece_ms);
    ROW("the longest piece while playing", "%s", u->longest_piece ? u->longest_piece : "—");
    ROW("that piece, CPU ms", "%.0f", u->longest_piece_ms);
    ROW("the work between frames per step change, CPU ms", "%.0f",
        u->changes > 0 ? u->work_ms / u->changes : 0.0);
    for (int k = 0; k < SESSION_PIECE_KINDS; k++) {
        char label[96];
        snprintf(label, sizeof(label), "of which %s, CPU ms",
                 session_piece_kind_name((enum session_piece_kind)k));
        ROW(label, "%.0f", u->changes > 0 ? u->kind_ms[k] / u->changes : 0.0);
    }
    /* The light build by its passes, those the staged run spent time in. */
    for (int k = 0; k < LIGHT_BUILD_PHASES; k++) {
        const struct bench_playback_run *st = runs[1];
        if (st->changes == 0 || st->light_ms[k] / st->changes < 0.5)
            continue; /* a pass it went through in no time (or not at all) */
        const char *name = k == LIGHT_BUILD_START
                               ? "its start (its textures, and its first piece)"
                               : light_build_phase_name((enum light_build_phase)k);
        char label[96];
        snprintf(label, sizeof(label), "of the light build, %s, CPU ms", name);
        ROW(label, "%.0f", u->changes > 0 ? u->light_ms[k] / u->changes : 0.0);
    }
    ROW("the longest frame with the work after it ÷ a normal frame", "%.2f",
        u->median_ms > 0.0 ? u->interval_max_ms / u->median_ms : 0.0);
    ROW("frames the cursor waited for a step (stalls)", "%u", u->stalls);
#undef ROW
    const struct bench_playback_run *s = &r->staged;
    /* At playback.speed 0.5 the cursor asks for a step every 2 s: the rate is met when it never
     * had to wait for one and never jumped over one. */
    bool rate = s->changes > 1 && s->skipped == 0 && s->stalls == 0, smooth = s->median_ms > 0.0 &&
                                                s->max_ms <= 1.2 * s->median_ms;
    fprintf(f,
            "\nThe procedural storm as a WRF series of %d steps on %d × %d × %d mass points "
            "(%.0f MiB of extinction a step), every step in the time series cache before the "
            "clock starts, played at playback.speed = %.1f on an orbit view of %d × %d "
            "pixels, each frame waited for (`glFinish`).  Frames are timed in the CPU time of "
            "all the process's threads (llvmpipe's included), so that other jobs on the "
            "machine do not count; the cursor moves by the wall clock, as in anvil run.  A "
            "normal frame is the median of the frames that kept their step.  Device: %s.  Goal: ≥ 1 step per 2 s (the cursor, asking "
            "for one every 2 s, never waited and never jumped a step): %s; no frame over 1.2 × a normal "
            "frame: %s.\n",
            r->steps, r->n[0], r->n[1], r->n[2], r->volume_mb, r->speed, r->width, r->height,
            d->device ? d->device : "unknown", rate ? "met" : "not met",
            smooth ? "met" : "not met");
}
