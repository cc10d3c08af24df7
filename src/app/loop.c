/*
 * The one frame loop of anvil render and anvil run, on one process or on the ranks of an
 * mpirun job.  Rank 0 (the only one without MPI) produces each frame: the input, the menu,
 * the script, the animation's next frame, the clock.  Every rank then consumes it: rank 0's
 * frame state, settings and menu reach the others, the volumes are brought to the frame's
 * step (held at the old one until every rank has the new), the light map is updated, rank 0
 * samples the head last and sends it, every rank draws its walls and they swap together.
 */
#include "app/loop.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <sys/stat.h>
#include <time.h>

#include "app/app.h"
#include "cluster/cluster.h"
#include "common/fatal.h"
#include "common/log.h"
#include "common/progress.h"
#include "render/image.h"
#include "session/animation.h"
#include "session/menu_view.h"

/* A script names frames up to INPUT_SCRIPT_FRAMES_MAX; playing it may take a little more. */
#define SCRIPT_FRAMES_MAX (INPUT_SCRIPT_FRAMES_MAX + 100000)

/* What rank 0 sends every frame. */
enum {
    SF_DRAW = 1u << 0,       /* the frame is drawn */
    SF_QUIT = 1u << 1,       /* the loop ends */
    SF_FAILED = 1u << 2,     /* ... because something failed */
    SF_SETTINGS = 1u << 3,   /* the look or quality changed: the settings follow */
    SF_MENU = 1u << 4,       /* the menu's meshes' state is in the frame */
    SF_MENU_IMAGE = 1u << 5, /* ... and its image follows */
    SF_WRITE = 1u << 6,      /* the frame is written (an animation's frame NUMBER) */
    SF_SETTLE = 1u << 7,     /* wait for the wanted volume first (the end of a script) */
};

struct shared_frame {
    uint8_t state[FRAME_STATE_BYTES];
    uint32_t flags;
    int32_t number;
    struct menu_view_state menu;
};

struct loop {
    const struct loop_desc *ld;
    struct display *d;
    struct session *s;
    bool root;
    /* rank 0's */
    double t0, last;
    bool dirty, idle;
    long frames_left, n;
    int stage;
    struct input_queue *events;
    struct animation_desc anim;
    long anim_count;
    struct display_camera base;
    struct progress pr;
    uint32_t settings_sent;
    unsigned menu_sent;
    bool menu_ever;
};

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

/* Adds the time since T (the start of a collective) to --stats' sync_ms. */
static void synced(struct loop *l, double t)
{
    session_stats(l->s)->sync_ms += time_now_ms() - t;
}

/* ---- rank 0: the next frame ---------------------------------------------------------------- */

/* A run: the input since the last frame, drawn when something changed. */
static bool produce_run(struct loop *l, struct frame_state *f, uint32_t *flags)
{
    if (session_quit_requested(l->s) || display_should_close(l->d) || l->frames_left == 0 ||
        fatal_stop_requested()) {
        *flags = SF_QUIT;
        return true;
    }
    input_queue_clear(l->events);
    display_poll_input(l->d, l->idle ? 0.03 : 0.0, l->events);
    double dt = frame_dt(l->s, &l->last);
    double time = l->ld->time + (time_now_ms() - l->t0) * 1e-3;
    bool redraw = false;
    if (!session_update(l->s, l->events, dt, time, f, &redraw))
        return false;
    if (l->dirty || redraw || display_head_moves(l->d) || l->frames_left > 0)
        *flags |= SF_DRAW;
    return true;
}

/* A render: the script's frames, each drawn (and written); then the settled picture. */
static bool produce_script(struct loop *l, struct frame_state *f, uint32_t *flags, int *number)
{
    bool writing = l->ld->output && l->ld->kind == LOOP_SCRIPT;
    double dt = 0.0;
    if (l->stage == 0 && session_script_done(l->s)) {
        progress_end(&l->pr);
        l->stage = 1;
        *flags |= SF_SETTLE;
    }
    if (l->stage == 2) {
        *flags = SF_QUIT;
        return true;
    }
    if (l->stage == 0) {
        if (l->n > SCRIPT_FRAMES_MAX) {
            log_error("the script has not ended after %d frames", SCRIPT_FRAMES_MAX);
            return false;
        }
        dt = frame_dt(l->s, &l->last);
        if (writing && l->n >= l->ld->first && l->n <= l->ld->last) {
            *flags |= SF_WRITE;
            *number = (int)(l->n - (long)l->ld->first);
        }
        if (l->pr.total < (uint64_t)l->n + 1) /* a volume still loading holds the end back */
            l->pr.total = (uint64_t)l->n + 1;
        progress_update(&l->pr, (uint64_t)l->n);
        l->n++;
    } else {
        l->stage = 2; /* the settled frame, written when nothing else was */
        if (writing && frame_output_frames(l->ld->output) == 0) {
            *flags |= SF_WRITE;
            *number = 0;
        }
    }
    bool redraw;
    *flags |= SF_DRAW;
    return session_update(l->s, NULL, dt, l->ld->time, f, &redraw);
}

/* An animation: frame after frame of the series or the camera path, each written. */
static bool produce_animation(struct loop *l, struct frame_state *f, uint32_t *flags,
                              int *number)
{
    bool redraw;
    if (l->n >= l->anim_count) {
        progress_end(&l->pr);
        *flags = SF_QUIT;
        return true;
    }
    if (l->n == 0) { /* what a camera path leaves alone: the scene's camera */
        struct frame_state first;
        if (!session_update(l->s, NULL, 0.0, l->ld->time, &first, &redraw))
            return false;
        l->base = first.camera;
    }
    animation_set_frame(l->s, &l->anim, l->n, &l->base);
    *flags |= SF_DRAW | SF_WRITE;
    *number = (int)l->n;
    progress_update(&l->pr, (uint64_t)l->n);
    l->n++;
    return session_update(l->s, NULL, 0.0, l->ld->time, f, &redraw);
}

static bool produce(struct loop *l, struct frame_state *f, uint32_t *flags, int *number)
{
    *flags = 0;
    *number = 0;
    memset(f, 0, sizeof(*f));
    if (l->ld->run)
        return produce_run(l, f, flags);
    if (l->ld->kind == LOOP_STEPS || l->ld->kind == LOOP_PATH)
        return produce_animation(l, f, flags, number);
    return produce_script(l, f, flags, number);
}

/* --record (rank 0): the frame's events, clock, head (when drawn, and only a head that moves:
 * a fixed one is the display's), the eyes relative to it where the display's runtime gave them
 * (a replay through another runtime, or the same one standing still, draws these) and cursor. */
static void record(const struct loop *l, const struct frame_state *f, bool drawn)
{
    if (!l->ld->recorder || !l->root)
        return;
    struct input_record_frame r = {
        .frame = (long)f->frame,
        .time_s = f->time_s,
        .dt_s = f->dt_s,
        .have_head = drawn && (display_head_moves(l->d) || session_head_given(l->s)),
    };
    memcpy(r.head_position, f->head.position, sizeof(r.head_position));
    memcpy(r.head_rotation, f->head.rotation, sizeof(r.head_rotation));
    struct display_pose eyes[2];
    r.have_eyes = r.have_head && display_eyes_in_head(l->d, eyes);
    for (int e = 0; r.have_eyes && e < 2; e++) {
        memcpy(r.eye_position[e], eyes[e].position, sizeof(r.eye_position[e]));
        memcpy(r.eye_rotation[e], eyes[e].rotation, sizeof(r.eye_rotation[e]));
    }
    session_cursor(l->s, &r.step, &r.step_acc, &r.playing);
    input_recorder_frame(l->ld->recorder, &r, session_events(l->s));
}

/* ---- every rank: the frame shared, applied, drawn ---------------------------------------- */

/* Rank 0's frame, settings and menu to every rank.  False when the bytes are not a frame. */
static bool share(struct loop *l, struct shared_frame *sf, struct frame_state *f)
{
    const uint8_t *menu_pixels = NULL;
    if (l->root) {
        frame_state_write(f, sf->state);
        if (f->settings_revision != l->settings_sent) {
            sf->flags |= SF_SETTINGS;
            l->settings_sent = f->settings_revision;
        }
        if (cluster_active() && session_menu_state(l->s, &sf->menu, &menu_pixels)) {
            sf->flags |= SF_MENU;
            if (!l->menu_ever || sf->menu.generation != l->menu_sent)
                sf->flags |= SF_MENU_IMAGE;
            l->menu_sent = sf->menu.generation;
            l->menu_ever = true;
        }
    }
    if (!cluster_active())
        return true;
    double t = time_now_ms();
    cluster_broadcast(sf, sizeof(*sf));
    if (sf->flags & SF_SETTINGS) {
        struct session_settings set;
        session_get_settings(l->s, &set);
        cluster_broadcast(&set, sizeof(set));
        if (!l->root)
            session_set_settings(l->s, &set);
    }
    if (sf->flags & SF_MENU) {
        size_t bytes = (size_t)sf->menu.width * (size_t)sf->menu.height * 4;
        uint8_t *img = NULL;
        if (sf->flags & SF_MENU_IMAGE) {
            img = l->root ? (uint8_t *)menu_pixels : malloc(bytes);
            if (!img)
                cluster_abort(EXIT_FAILED);
            cluster_broadcast(img, bytes);
        }
        bool ok = l->root || session_show_menu_state(l->s, &sf->menu, img);
        if (!l->root)
            free(img);
        if (!ok) { /* the others are already drawing: end the job, naming this rank */
            log_error("rank %d: the menu from rank 0 could not be shown", cluster_rank());
            cluster_abort(EXIT_FAILED);
        }
    }
    synced(l, t);
    if (!l->root && !(sf->flags & SF_QUIT) && !frame_state_read(sf->state, FRAME_STATE_BYTES, f)) {
        log_error("rank %d: rank 0's frame state is not one (a different anvil?)",
                  cluster_rank());
        cluster_abort(EXIT_FAILED);
    }
    return true;
}

/* The step every rank has: the frame's, or on a run the one shown before while some rank is
 * still loading it (never one wall at another time). */
static void hold(struct loop *l, struct frame_state *f)
{
    if (!cluster_active() || !l->ld->run)
        return;
    int next = f->time_step + 1 < session_step_count(l->s) ? f->time_step + 1 : f->time_step;
    uint32_t mine = (session_step_loaded(l->s, f->time_step) ? 1u : 0u) |
                    (f->step_fraction == 0.0f || session_step_loaded(l->s, next) ? 2u : 0u);
    double t = time_now_ms();
    uint32_t all = cluster_and(mine);
    synced(l, t);
    if (!(all & 1u)) {
        /* Shown: the old step; loading, on every rank that lacks it: the wanted one. */
        if (!(mine & 1u))
            session_want_step(l->s, f->time_step);
        if (f->time_step != session_step_shown(l->s))
            session_stats(l->s)->frames_held++;
        f->time_step = session_step_shown(l->s);
        f->step_fraction = 0.0f;
    } else if (!(all & 2u)) {
        f->step_fraction = 0.0f;
    }
}

/* --check-sync: every rank's frame and what else makes its pictures, equal to rank 0's. */
static void check_sync(struct loop *l, const struct shared_frame *sf)
{
    uint64_t key = cluster_hash(session_sync_key(l->s), sf->state, sizeof(sf->state));
    uint64_t keys[4096];
    int n = cluster_size() <= 4096 ? cluster_size() : 4096;
    cluster_gather_u64(key, keys);
    for (int r = 1; l->root && r < n; r++) {
        if (keys[r] != keys[0]) {
            log_error("--check-sync: rank %d is out of step with rank 0 (its config, data, "
                      "settings or the step it shows differ)",
                      r);
            cluster_abort(EXIT_FAILED);
        }
    }
}

static bool consume(struct loop *l, struct shared_frame *sf, struct frame_state *f)
{
    bool ok = true, changed = false;
    if (sf->flags & SF_SETTLE)
        ok = session_settle(l->s);
    hold(l, f);
    ok = ok && session_apply(l->s, f, &changed);
    /* A volume that arrived on any rank is drawn on all. */
    double t = time_now_ms();
    if (cluster_active() && l->ld->run && !cluster_all(!changed))
        changed = true;
    synced(l, t);
    bool draw = (sf->flags & SF_DRAW) || changed;
    if (draw) {
        ok = ok && session_light(l->s);
        /* The head, sampled last, on rank 0 (unless a recording gave it): its trackers are the
         * cluster's. */
        if (l->root && !session_head_given(l->s)) {
            ok = ok && display_sample_head(l->d, f->time_s, &f->head);
        } else if (l->root && display_paces_frames(l->d)) {
            struct display_pose runtime; /* its frame begun; the recording's head drawn */
            ok = ok && display_sample_head(l->d, f->time_s, &runtime);
        }
        t = time_now_ms();
        cluster_broadcast(&f->head, sizeof(f->head));
        synced(l, t);
        display_give_eyes(l->d, session_eyes_given(l->s)); /* a recording's, with its head */
        ok = ok && session_draw(l->s, l->d, f);
        if (ok && (sf->flags & SF_WRITE))
            ok = frame_output_add(l->ld->output, l->d, sf->number);
        if (l->root)
            l->dirty = false;
    }
    if (ok)
        record(l, f, draw);
    if (l->root && l->frames_left > 0 && draw)
        l->frames_left--;
    l->idle = !draw;
    /* Between frames: the next step readied, so that its step change is a swap. */
    bool more = false;
    ok = ok && session_prepare(l->s, &more);
    if (more)
        l->idle = false;
    /* A rank that failed ends the job's loop on every rank, naming itself. */
    t = time_now_ms();
    bool all_ok = !cluster_active() || cluster_all(ok);
    synced(l, t);
    if (!all_ok) {
        if (!ok)
            log_error("rank %d failed (see above); the cluster stops", cluster_rank());
        return false;
    }
    if (l->ld->check_sync)
        check_sync(l, sf);
    return ok;
}

/* ---- rank 0's keys: screenshots and bookmarks ------------------------------------------- */

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

/* The data named on the command line as scene-file settings, after the included config so that
 * they replace its data.files: scene.kind, and data.format and data.files put first into the
 * look's data group (LOOK, SIZE bytes: the look text of session_look_text, which has one). */
static void data_into_look(const struct config *cfg, char *look, size_t size)
{
    static const char *const formats[] = {"wrf", "isabel", "extinction"};
    char fields[CONFIG_MAX_FILES * 64 + 256];
    size_t at = (size_t)snprintf(fields, sizeof(fields), "format = \"%s\"; files = [",
                                 formats[cfg->data.format]);
    for (int i = 0; i < cfg->data.file_count && at < sizeof(fields); i++) {
        char full[PATH_MAX], cwd[PATH_MAX];
        const char *f = cfg->data.files[i];
        if (!strpbrk(f, "*?[") && realpath(f, full))
            f = full;
        else if (f[0] != '/' && getcwd(cwd, sizeof(cwd)) &&
                 snprintf(full, sizeof(full), "%s/%s", cwd, f) < (int)sizeof(full))
            f = full; /* a pattern, from the folder it was given in */
        at += (size_t)snprintf(fields + at, sizeof(fields) - at, "%s\"%s\"", i ? ", " : "", f);
    }
    if (at >= sizeof(fields) - 4) {
        log_warn("bookmark: the data files do not fit: it names the config's");
        return;
    }
    snprintf(fields + at, sizeof(fields) - at, "]; ");
    static const char group[] = "data = { ";
    char *d = strstr(look, group);
    size_t len = strlen(look), add = strlen(fields);
    static const char scene[] = "scene = { kind = \"data\"; };\n";
    if (!d || len + add + sizeof(scene) >= size) {
        log_warn("bookmark: no room for the data files: it names the config's");
        return;
    }
    d += sizeof(group) - 1;
    memmove(d + add, d, strlen(d) + 1);
    memcpy(d, fields, add);
    memmove(look + sizeof(scene) - 1, look, strlen(look) + 1);
    memcpy(look, scene, sizeof(scene) - 1);
}

/* C and the menu's Save view: the view as a block to paste, and a bookmark file that renders
 * what the session shows again (the view, the sun, the time step, the look, the quality the
 * menu changed). */
static void bookmark(struct session *s, const struct loop_desc *ld)
{
    enum { LOOK_MAX = 98304 }; /* any look: session_look_text */
    char view[1024], sun[256], name[64];
    char *look = malloc(LOOK_MAX), *text = malloc(LOOK_MAX + 4096);
    if (!look || !text) {
        free(look);
        free(text);
        log_warn("bookmark: out of memory: not written");
        return;
    }
    session_view_text(s, view, sizeof(view));
    session_sun_text(s, sun, sizeof(sun));
    session_look_text(s, look, LOOK_MAX);
    bool tracker = session_uses_tracker(s);
    printf("%s%s", view, tracker ? "" : sun);
    fflush(stdout);
    const char *include = tracker ? ld->display_path : ld->config_path;
    char full[PATH_MAX] = "";
    if (include && !realpath(include, full))
        snprintf(full, sizeof(full), "%s", include);
    free_name("bookmark", ".cfg", name, sizeof(name));
    /* A tracked display's bookmark is a display file: the look belongs to the scene, so it is
     * left there as comments to copy. */
    snprintf(text, LOOK_MAX + 4096, "# anvil bookmark: %s\n%s%s%s%s%s",
             tracker ? "the navigation of a display (anvil render SCENE --display THIS)"
                     : "a view of a scene (anvil render THIS -o view.png)",
             full[0] ? "@include \"" : "", full, full[0] ? "\"\n" : "", view, tracker ? "" : sun);
    if (!tracker) {
        if (ld->data_from_args)
            data_into_look(session_config(s), look, LOOK_MAX);
        strncat(text, look, LOOK_MAX + 4096 - strlen(text) - 1);
    } else {
        strncat(text, "# the scene's look and time, for its scene file:\n",
                LOOK_MAX + 4096 - strlen(text) - 1);
        for (char *line = look; *line;) {
            char *end = strchr(line, '\n');
            size_t n = end ? (size_t)(end - line + 1) : strlen(line);
            size_t at = strlen(text);
            if (at + n + 3 >= (size_t)LOOK_MAX + 4096)
                break;
            snprintf(text + at, LOOK_MAX + 4096 - at, "# %.*s", (int)n, line);
            line += n;
        }
    }
    char status[128];
    if (file_write_atomic(name, text, strlen(text))) {
        log_info("bookmark: %s", name);
        snprintf(status, sizeof(status), "saved %s", name);
    } else {
        snprintf(status, sizeof(status), "not saved: %s", log_last_error());
    }
    session_set_status(s, status);
    free(look);
    free(text);
}

int loop_run(struct display *d, struct session *s, const struct loop_desc *ld)
{
    struct loop l = {.ld = ld, .d = d, .s = s, .root = cluster_rank() == 0, .dirty = true};
    l.t0 = l.last = time_now_ms();
    l.frames_left = ld->run ? ld->frames : -1;
    l.events = malloc(sizeof(*l.events));
    if (!l.events) {
        log_error("out of memory");
        return EXIT_FAILED;
    }
    struct session_settings set;
    session_get_settings(s, &set);
    l.settings_sent = set.revision;
    if (!ld->run && (ld->kind == LOOP_STEPS || ld->kind == LOOP_PATH)) {
        l.anim = (struct animation_desc){.path = ld->kind == LOOP_PATH ? ld->path : NULL,
                                         .first = ld->first,
                                         .last = ld->last,
                                         .by = ld->by,
                                         .fps = ld->fps,
                                         .time = ld->time};
        l.anim_count = animation_frames(&l.anim);
        progress_begin(&l.pr, "render", "frame", (uint64_t)l.anim_count);
    } else if (!ld->run) {
        progress_begin(&l.pr, "render", "frame", (uint64_t)session_script_frames(s));
    }
    int rc = EXIT_OK;
    double start = time_now_ms();
    for (bool first = true;; first = false) {
        struct shared_frame sf;
        struct frame_state f;
        memset(&sf, 0, sizeof(sf));
        memset(&f, 0, sizeof(f));
        if (!l.root && ld->run) { /* the windows stay alive; rank 0's input is the cluster's */
            input_queue_clear(l.events);
            display_poll_input(d, 0.0, l.events);
        }
        bool ok = !l.root || produce(&l, &f, &sf.flags, &sf.number);
        if (!ok)
            sf.flags = SF_QUIT | SF_FAILED;
        if (!share(&l, &sf, &f)) {
            rc = EXIT_FAILED;
            break;
        }
        if (sf.flags & SF_QUIT) {
            if (sf.flags & SF_FAILED)
                rc = EXIT_FAILED;
            break;
        }
        if (!consume(&l, &sf, &f)) {
            rc = EXIT_FAILED;
            break;
        }
        if (first) { /* shaders compiled, the light map built: --stats keeps it apart */
            session_stats(s)->first_frame_ms = time_now_ms() - start;
            session_stats(s)->first_sync_ms = session_stats(s)->sync_ms;
        }
        if (l.root) { /* a run's keys, or a script's (its "Save view" too) */
            unsigned requests = session_take_requests(s);
            if (requests & SESSION_REQUEST_SCREENSHOT)
                screenshot(d, s);
            if (requests & SESSION_REQUEST_BOOKMARK)
                bookmark(s, ld);
        }
    }
    if (!ld->run)
        progress_end(&l.pr);
    free(l.events);
    return rc;
}
