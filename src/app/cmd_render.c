/* anvil render (headless, to files) and anvil run (windows): options, then the frame loop. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "app/app.h"
#include "app/cluster_walls.h"
#include "cluster/cluster.h"
#include "app/loop.h"
#include "common/fatal.h"
#include "common/log.h"
#include "common/progress.h"
#include "config/display_config.h"
#include "display/display.h"
#include "config/camera_path.h"
#include "gpu/gpu.h"
#include "render/video.h"
#include "session/camera_path.h"
#include "session/output.h"
#include "session/scene.h"
#include "session/session.h"

struct render_options {
    const char *config;    /* the config among ARGS (after load_configs), or NULL */
    const char *command;   /* "render" or "run" */
    char **args;           /* CONFIG, FILES...: a config first, then data files (app_load_scene) */
    int n_args;
    const char *output;
    const char *stats;
    char *sets[64];
    int n_sets;
    const char *display;   /* --display FILE: views from a display config */
    double time;           /* --time SECONDS: where on a scripted head path */
    const char *input;     /* --input SCRIPT: scripted wand and keys (docs/menu.md) */
    const char *transfers; /* --transfers DIR: where the menu saves transfer functions */
    const char *wand;      /* --wand NAME: an OpenHMD controller as the wand ("null") */
    bool menu;             /* --menu: start with the menu shown (render) */
    const char *format;    /* --format png|pfm: the image files of a display render */
    const char *frames;    /* --frames all|A:B[:STEP]: an animation (render) */
    double fps;            /* --fps N: its frame rate (0: the default) */
    const char *codec;     /* --codec NAME: a movie's encoder */
    const char *path;      /* --path FILE: a camera path (render: fly it; run: keys add to it) */
    bool check_sync;       /* --check-sync: under mpirun, every rank's frame checked */
    const char *record;    /* --record FILE: every frame's input, head and clock */
};

/* --frames: "all" (FIRST 0, LAST -1: to the end) or "A:B[:STEP]". */
static bool parse_frames(const char *spec, long *first, long *last, long *step)
{
    *first = 0;
    *last = -1;
    *step = 1;
    if (!spec || strcmp(spec, "all") == 0)
        return true;
    char *end;
    long a = strtol(spec, &end, 10), b = a, c = 1;
    if (end == spec || *end != ':')
        goto bad;
    char *q = end + 1;
    b = strtol(q, &end, 10);
    if (end == q || (*end && *end != ':'))
        goto bad;
    if (*end == ':') {
        q = end + 1;
        c = strtol(q, &end, 10);
        if (end == q || *end)
            goto bad;
    }
    if (a < 0 || b < a || c < 1)
        goto bad;
    *first = a;
    *last = b;
    *step = c;
    return true;
bad:
    log_error("--frames %s: expected all or FIRST:LAST[:STEP] (0 <= FIRST <= LAST, STEP >= 1)",
              spec);
    return false;
}

static int parse_options(int argc, char **argv, struct render_options *o, bool need_output)
{
    static const struct option longopts[] = {
        {"output", required_argument, NULL, 'o'},
        {"set", required_argument, NULL, 's'},
        {"stats", required_argument, NULL, 'S'},
        {"quiet", no_argument, NULL, 'q'},
        {"verbose", no_argument, NULL, 'v'},
        {"display", required_argument, NULL, 'D'},
        {"time", required_argument, NULL, 'T'},
        {"input", required_argument, NULL, 'I'},
        {"transfers", required_argument, NULL, 'F'},
        {"wand", required_argument, NULL, 'W'},
        {"menu", no_argument, NULL, 'M'},
        {"format", required_argument, NULL, 'P'},
        {"frames", required_argument, NULL, 'A'},
        {"fps", required_argument, NULL, 'R'},
        {"codec", required_argument, NULL, 'C'},
        {"path", required_argument, NULL, 'K'},
        {"check-sync", no_argument, NULL, 'Y'},
        {"record", required_argument, NULL, 'E'},
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    memset(o, 0, sizeof(*o));
    o->command = need_output ? "render" : "run";
    optind = 1;
    int c;
    while ((c = getopt_long(argc, argv, "o:qh", longopts, NULL)) != -1) {
        switch (c) {
        case 'o':
            o->output = optarg;
            break;
        case 's':
            if (o->n_sets == 64) {
                log_error("too many --set options (at most 64)");
                return EXIT_USAGE;
            }
            o->sets[o->n_sets++] = optarg;
            break;
        case 'S':
            o->stats = optarg;
            break;
        case 'q':
            log_set_level(LOG_ERROR);
            break;
        case 'v':
            log_set_level(LOG_DEBUG);
            break;
        case 'D':
            o->display = optarg;
            break;
        case 'T': {
            char *end;
            o->time = strtod(optarg, &end);
            if (*end || !isfinite(o->time)) {
                log_error("--time %s: expected a number of seconds", optarg);
                return EXIT_BAD_INPUT;
            }
            break;
        }
        case 'I':
            o->input = optarg;
            break;
        case 'F':
            o->transfers = optarg;
            break;
        case 'W':
            o->wand = optarg;
            break;
        case 'M':
            o->menu = true;
            break;
        case 'P':
            if (strcmp(optarg, "png") != 0 && strcmp(optarg, "pfm") != 0) {
                log_error("--format %s: expected png or pfm", optarg);
                return EXIT_BAD_INPUT;
            }
            o->format = optarg;
            break;
        case 'A':
            o->frames = optarg;
            break;
        case 'R': {
            char *end;
            o->fps = strtod(optarg, &end);
            if (*end || !(o->fps >= 1.0 && o->fps <= 1000.0)) {
                log_error("--fps %s: expected frames per second in [1, 1000]", optarg);
                return EXIT_BAD_INPUT;
            }
            break;
        }
        case 'C':
            o->codec = optarg;
            break;
        case 'K':
            o->path = optarg;
            break;
        case 'Y':
            o->check_sync = true;
            break;
        case 'E':
            o->record = optarg;
            break;
        case 'h':
            return -1;
        default:
            return EXIT_USAGE;
        }
    }
    o->args = argv + optind;
    o->n_args = argc - optind;
    if (need_output && !o->output && !(o->display && strcmp(o->display, "help") == 0)) {
        log_error(o->display ? "render: missing -o FOLDER/ (one image per view goes there)"
                             : "render: missing -o FILE.png or -o FILE.pfm");
        return EXIT_USAGE;
    }
    if (!need_output && (o->frames || o->fps > 0.0 || o->codec)) {
        log_error("run: --frames, --fps and --codec belong to render (an animation to files)");
        return EXIT_USAGE;
    }
    long first, last, step; /* checked here, before any work; used by animation() */
    if (o->frames && !parse_frames(o->frames, &first, &last, &step))
        return EXIT_BAD_INPUT;
    if (!need_output || !o->output)
        return EXIT_OK;
    /* An animation: numbered images or a movie, their folder there; checked before any work. */
    bool sequence = strchr(o->output, '%') != NULL || video_path_supported(o->output);
    if (o->frames || o->path || sequence) {
        if (!sequence) {
            log_error("%s: an animation (--frames, --path) needs numbered images "
                      "(out/frame-%%05d.png) or a movie (storm.mp4) after -o",
                      o->output);
            return EXIT_BAD_INPUT;
        }
        if (!frame_output_check(o->output) ||
            (video_path_supported(o->output) && !video_check(o->output, o->codec)))
            return EXIT_BAD_INPUT;
        return EXIT_OK;
    }
    if (o->display && image_path_supported(o->output)) {
        log_error("%s: with --display, -o names a folder for the views' images (out/), not one "
                  "image",
                  o->output);
        return EXIT_BAD_INPUT;
    }
    /* A file name the writers cannot serve is refused before any work is done, and so is a
     * folder that is not there. */
    if (!o->display && !image_path_supported(o->output)) {
        log_error("%s: unknown image type: expected a name ending in .png or .pfm, or an "
                  "animation's numbered images or movie",
                  o->output);
        return EXIT_BAD_INPUT;
    }
    if (!o->display && !frame_output_folder_exists(o->output))
        return EXIT_BAD_INPUT;
    return EXIT_OK;
}

/* What the animation's frames are, from the options and the session; *FPS its frame rate. */
static int animation(const struct render_options *o, struct session *s, struct loop_desc *ld,
                     struct camera_path *path)
{
    long first, last, step;
    if (!parse_frames(o->frames, &first, &last, &step))
        return EXIT_BAD_INPUT;
    const struct config *cfg = session_config(s);
    if (o->path) {
        if (o->display) {
            log_error("--path flies the scene's own camera: leave out --display");
            return EXIT_BAD_INPUT;
        }
        ld->kind = LOOP_PATH; /* PATH was read before the session (its steps decide playback) */
        ld->path = path;
        ld->fps = o->fps > 0.0 ? o->fps : 24.0;
        long count = (long)floor(camera_path_duration(path) * ld->fps + 1e-9) + 1;
        if (last < 0 || last >= count)
            last = count - 1;
        ld->first = (double)first;
        ld->last = (double)last;
        return first <= last ? EXIT_OK : EXIT_BAD_INPUT;
    }
    if (o->input) {
        ld->kind = LOOP_SCRIPT;
        ld->first = (double)first;
        ld->last = last < 0 ? 1e18 : (double)last;
        ld->fps = 1.0 / session_script_dt(s);
        return EXIT_OK;
    }
    int steps = session_step_count(s);
    if (last < 0)
        last = steps - 1;
    if (first >= steps || last >= steps) {
        log_error("--frames %s: the scene has the time steps 0 to %d", o->frames, steps - 1);
        return EXIT_BAD_INPUT;
    }
    ld->kind = LOOP_STEPS;
    ld->first = (double)first;
    ld->last = (double)last;
    double speed = cfg->playback.speed;
    /* The movie shows time going at playback.speed; with --fps above it and effects.temporal
     * the frames between two steps blend them. */
    ld->fps = o->fps > 0.0 ? o->fps : fmax(1.0, round(speed * step));
    ld->by = step == 1 && o->fps > 0.0 && session_blends_steps(s) ? speed / ld->fps
                                                                    : (double)step;
    return EXIT_OK;
}

static void print_key(const char *keys, const char *what, void *user)
{
    fprintf(user, "  %-22s %s\n", keys, what);
}

static int usage(FILE *out, bool run)
{
    if (run)
        fprintf(out,
                "usage: anvil run [CONFIG] [FILE...] [--display DISPLAY.cfg]\n"
                "                 [--set PATH=VALUE]...\n"
                "                 [--input SCRIPT] [--wand NAME] [--transfers DIR] [--time S]\n"
                "                 [--path CAMERA-PATH.cfg] [--record FILE] [--stats FILE.json]\n"
                "                 [--quiet]\n"
                "  --record FILE writes every frame's input, head pose and clock; --input FILE\n"
                "  replays it (docs/menu.md, \"Recordings\").\n"
                "  Under mpirun each rank draws some walls of --display (docs/displays.md,\n"
                "  \"Running a CAVE on a cluster\"); --check-sync checks every frame on every rank.\n"
                "  FILE...: data files, folders or quoted patterns ('wrfout_d01_*'), known by\n"
                "  their content, after an optional config for the rest (docs/data.md).\n"
                "  Without --display: one window of the scene's camera (camera.*; data without\n"
                "  one: framing the domain), orbiting its target.  The keys mean the same on\n"
                "  every display:\n");
    else
        fprintf(out,
                "usage: anvil render [CONFIG] [FILE...] -o FILE.png|FILE.pfm\n"
                "                    [--set PATH=VALUE]...\n"
                "                    [--input SCRIPT] [--menu] [--stats FILE.json] [--quiet]\n"
                "       anvil render [CONFIG] --display DISPLAY.cfg [--time SECONDS] "
                "-o FOLDER/ [--format png|pfm] [...]\n"
                "       anvil render [CONFIG] [--display D.cfg] --frames all|A:B[:STEP] "
                "[--fps N]\n"
                "                    -o out/frame-%%05d.png | -o storm.mp4 [--codec NAME]\n"
                "       anvil render [CONFIG] --path CAMERA-PATH.cfg [--fps N] -o fly.mp4\n"
                "       anvil render --display help\n"
                "  FILE...: data files, folders or quoted patterns ('wrfout_d01_*'), known by\n"
                "  their content, after an optional config for the rest (docs/data.md).\n"
                "  An animation writes every frame: the time steps FIRST..LAST (with --fps above\n"
                "  playback.speed and effects.temporal, blended frames between them), a camera\n"
                "  path, or a script's frames (--input).  Movie encoders here: %s\n"
                "  --record FILE writes every frame's input, head pose and clock; --input FILE\n"
                "  replays a recording (docs/menu.md, \"Recordings\").\n"
                "  Under mpirun each rank draws some walls of --display (docs/displays.md,\n"
                "  \"Running a CAVE on a cluster\"); --check-sync checks every frame on every rank.\n"
                "  A script (--input) plays these keys and the wand's buttons (docs/menu.md):\n",
                video_encoders());
    session_list_keys(print_key, out);
    fprintf(out, "  wand: trigger chooses in the menu, grab moves the world, menu shows it, "
                 "reset resets the view; stick: fly and turn\n");
    return out == stdout ? EXIT_OK : EXIT_USAGE;
}

static void print_backend(const char *name, const char *what, void *user)
{
    fprintf(user, "  %-10s %s\n", name, what);
}

/* Loads the scene config and the display config (or makes the orbit display's) with the
 * --set overrides: those naming display settings go to the display. */
static int load_configs(struct render_options *o, struct config *cfg,
                        struct display_config *dcfg, struct display_navigation *room)
{
    char *display_sets[64];
    int n_display_sets = 0;
    if (!app_route_sets(o->sets, &o->n_sets, o->display, display_sets, &n_display_sets))
        return EXIT_USAGE;
    if (app_load_scene(o->command, o->args, o->n_args, o->sets, o->n_sets,
                       cfg, &o->config) != EXIT_OK)
        return EXIT_BAD_INPUT;
    if (o->display) {
        if (!app_load_display_config(o->display, display_sets, n_display_sets, dcfg) ||
            !app_frame_navigation(cfg, dcfg, room))
            return EXIT_BAD_INPUT;
        if (!display_type_available(dcfg->type)) {
            log_error("%s: display.type = \"%s\": this anvil was built without that backend%s",
                      o->display, display_type_name(dcfg->type),
                      dcfg->type == DISPLAY_TYPE_OPENXR
                          ? " (the OpenXR loader was not found: install libopenxr-dev and "
                            "rebuild)"
                          : "");
            return EXIT_BAD_INPUT;
        }
        /* effects.distortion on or off overrides the display's hmd.warp; auto follows it. */
        enum effect_mode distortion = cfg->effects.mode[EFFECT_DISTORTION];
        if (distortion != EFFECT_AUTO)
            dcfg->hmd.warp = distortion == EFFECT_ON;
        return EXIT_OK;
    }
    display_config_defaults(dcfg);
    dcfg->type = DISPLAY_TYPE_ORBIT;
    dcfg->window_size[0] = cfg->render.width;
    dcfg->window_size[1] = cfg->render.height;
    return EXIT_OK;
}

/* --wand NAME: an OpenHMD controller as the wand, in place of the display's wand.*. */
static int apply_wand_option(const struct render_options *o, struct display_config *dcfg)
{
    if (!o->wand)
        return EXIT_OK;
    if (strlen(o->wand) >= sizeof(dcfg->wand.device)) {
        log_error("--wand %s: expected an OpenHMD product name of at most %zu characters",
                  o->wand, sizeof(dcfg->wand.device) - 1);
        return EXIT_BAD_INPUT;
    }
    dcfg->wand.source = DISPLAY_WAND_OPENHMD;
    snprintf(dcfg->wand.device, sizeof(dcfg->wand.device), "%s", o->wand);
    return EXIT_OK;
}

/* What --input brings besides events: a recording's head (then the display's head and wand
 * trackers stay closed: the recording carries what they gave), whether it was recorded by
 * anvil run, and how its menu started. */
struct replay {
    bool head, from_run;
    int menu_shown; /* -1: the script does not say */
};

static int inspect_input(const struct render_options *o, struct display_config *dcfg,
                         struct replay *r)
{
    memset(r, 0, sizeof(*r));
    r->menu_shown = -1;
    if (!o->input)
        return EXIT_OK;
    struct input_source *script = input_script_open(o->input);
    if (!script)
        return EXIT_BAD_INPUT;
    r->head = input_script_has_head(script);
    input_script_recorded(script, &r->from_run, &r->menu_shown);
    input_source_destroy(script);
    if (!r->head)
        return EXIT_OK;
    if (dcfg->head.source != DISPLAY_HEAD_FIXED || dcfg->wand.source != DISPLAY_WAND_NONE)
        log_info("%s: replaying its head and wand (the display's head.source \"%s\" and "
                 "wand.source \"%s\" stay closed)",
                 o->input, display_head_source_name(dcfg->head.source),
                 display_wand_source_name(dcfg->wand.source));
    dcfg->head.source = DISPLAY_HEAD_FIXED;
    dcfg->wand.source = DISPLAY_WAND_NONE;
    return EXIT_OK;
}

/* Writes what a render made: the one view as -o FILE, or every view into -o FOLDER/. */
static bool write_output(struct display *d, struct session *s, const struct render_options *o,
                         float exposure, struct session_stats *st)
{
    if (o->display)
        return display_write_images(d, o->output, o->format ? o->format : "png", exposure,
                                    &st->nonfinite_pixels);
    const struct view *v = display_view(d, 0);
    if (!v)
        return false;
    int w = v->target.size[0], h = v->target.size[1];
    bool ok;
    if (image_path_is_png(o->output)) {
        /* Tone mapped on the GPU: a quarter of the bytes come back, and no CPU pass. */
        uint8_t *rgba = malloc((size_t)w * h * 4);
        size_t nonfinite = 0;
        ok = rgba && renderer_tonemap_read(session_renderer(s), &v->target, exposure,
                                           rgba, &nonfinite) &&
             image_write_png8(rgba, w, h, o->output);
        st->nonfinite_pixels = nonfinite;
        free(rgba);
    } else {
        struct image img = {0};
        if (!renderer_read(&v->target, &img))
            return false;
        st->nonfinite_pixels = image_count_nonfinite(&img);
        ok = image_write(&img, o->output, exposure);
        image_finish(&img);
    }
    if (ok)
        log_info("wrote %s (%dx%d, view %.1f ms on %s)", o->output, w, h,
                 st->view_times.total_ms, st->device);
    return ok;
}

static int command(int argc, char **argv, bool run)
{
    double start = time_now_ms();
    struct render_options o;
    int rc = parse_options(argc, argv, &o, !run);
    if (rc < 0)
        return usage(stdout, run);
    if (rc == EXIT_BAD_INPUT)
        return rc;
    if (rc != EXIT_OK)
        return usage(stderr, run);
    if (o.display && strcmp(o.display, "help") == 0) {
        printf("display backends (display.type in a display config, see displays/*.cfg and "
               "docs/displays.md):\n");
        display_list(print_backend, stdout);
        return EXIT_OK;
    }
    struct config *cfg = malloc(sizeof(*cfg));
    struct display_config *dcfg = malloc(sizeof(*dcfg));
    struct camera_path *path = malloc(sizeof(*path));
    struct display *d = NULL;
    struct session *s = NULL;
    struct cluster_walls *cw = calloc(1, sizeof(*cw));
    bool gated = false;     /* every rank passes app_cluster_gate once, failed or not */
    double sync_ms = 0.0;   /* a cluster's rank: time in the swap barrier */
    struct input_recorder *recorder = NULL;
    rc = EXIT_FAILED;
    if (!cfg || !dcfg || !path || !cw) {
        log_error("out of memory");
        goto done;
    }
    struct replay replay;
    /* The room's fit is made before a cluster's rank keeps its own walls. */
    struct display_navigation room = {0};
    if ((rc = load_configs(&o, cfg, dcfg, &room)) != EXIT_OK || (rc = apply_wand_option(&o, dcfg)) ||
        (rc = inspect_input(&o, dcfg, &replay)))
        goto done;
    /* Under mpirun: this rank's walls (the effects are decided from all of them). */
    if ((rc = app_cluster_walls(o.display, dcfg, cw)) != EXIT_OK)
        goto done;
    bool have_path = false;
    if (o.path && !run) {
        if (!camera_path_load(o.path, path)) {
            rc = EXIT_BAD_INPUT;
            goto done;
        }
        have_path = true;
    }
    /* Time plays in a run, a script, an animation of the series or a path through it. */
    bool plays = run || o.input || (have_path && path->has_steps) ||
                 (!have_path && !run && o.output &&
                  (o.frames || strchr(o.output, '%') || video_path_supported(o.output)));

    enum display_failure why = DISPLAY_FAILED_NONE;
    struct display_desc dd = {.offscreen = !run, .height = cfg->render.height, .failure = &why};
    if (cw->active) {
        dd.gpu_device = cluster_local_rank(); /* one GPU per rank of a node */
        dd.partial = true;
        dd.before_swap = app_cluster_before_swap;
        dd.swap_user = &sync_ms;
        dd.swap_group = 1;
        dd.head_given = cluster_rank() != 0; /* rank 0's trackers are the cluster's */
    }
    scene_camera(cfg, &dd.camera);
    d = display_create(dcfg, &dd);
    if (!d) {
        /* 3 is for a missing OpenGL context only: a bad pose file or device is bad input, and
         * an OpenXR display fails for want of a runtime or a headset, not of a context. */
        rc = why == DISPLAY_FAILED_CONTEXT && dcfg->type != DISPLAY_TYPE_OPENXR ? EXIT_NO_GPU
             : why == DISPLAY_FAILED_INPUT                                        ? EXIT_BAD_INPUT
                                                                                  : EXIT_FAILED;
        goto done;
    }
    if (!display_update(d, o.time)) {
        rc = EXIT_FAILED;
        goto done;
    }
    struct render_view views[DISPLAY_MAX_VIEWS];
    int n = 0;
    static struct view_set all; /* a cluster: every rank's walls */
    if (cw->active && view_set_fixed(&cw->all, cfg->render.height, &all) > 0) {
        for (int i = 0; i < all.count; i++) {
            if (all.views[i].visible)
                views[n++] = all.views[i].rv;
        }
    }
    for (int i = 0; !cw->active && i < display_view_count(d); i++) {
        if (display_view(d, i)->visible)
            views[n++] = display_view(d, i)->rv;
    }
    /* A moving head may bring the ground into view later (a recorded one too); so may the
     * orbit camera of run. */
    bool views_move = display_head_moves(d) || replay.head || (run && !o.display);
    bool show_menu = run ? !o.input || o.menu : o.menu;
    if (replay.menu_shown >= 0)
        show_menu = replay.menu_shown;
    s = session_create(cfg,
                       &(struct session_desc){
                           .command = run ? "run" : "render",
                           .display = dcfg,
                           .room_navigation = o.display ? &room : NULL,
                           .views = views_move ? NULL : views,
                           .view_count = views_move ? 0 : n,
                           .views_move = views_move,
                           .interactive = run,
                           .playback = plays,
                           /* Rank 0's menu and script are the cluster's (the others show
                            * the menu rank 0 sends). */
                           .menu = (run || o.input || o.menu) && cluster_rank() == 0,
                           /* Every rank reads the probe's values at the point rank 0 picks. */
                           .probe = run || o.input || o.menu,
                           .show_menu = show_menu,
                           .replay_of_run = replay.from_run,
                           .script = cluster_rank() == 0 ? o.input : NULL,
                           .transfers_dir = o.transfers,
                           /* An interactive run times its views only when they are reported. */
                           .time_views = o.stats || !run,
                           /* tests: a slow disk (on one rank of a cluster, say) */
                           .load_delay_ms = getenv("ANVIL_TEST_LOAD_DELAY_MS")
                                                ? strtod(getenv("ANVIL_TEST_LOAD_DELAY_MS"), NULL)
                                                : 0.0,
                           .count_rays = o.stats != NULL,
                       },
                       &rc);
    if (!s) {
        rc = rc == 1 ? EXIT_BAD_INPUT : EXIT_FAILED;
        goto done;
    }
    if (o.display)
        log_info("display %s (%s): %d views", o.display, display_type_name(dcfg->type),
                 display_view_count(d));
    if (o.record && cluster_rank() == 0) { /* rank 0's input is the cluster's */
        recorder = input_recorder_open(o.record, run ? "run" : "render", show_menu);
        if (!recorder) {
            rc = EXIT_FAILED;
            goto done;
        }
    }
    const char *frames_env = getenv("ANVIL_RUN_FRAMES"); /* for automated runs */
    struct loop_desc ld = {
        .run = run,
        .time = o.time,
        .frames = frames_env ? strtol(frames_env, NULL, 10) : -1,
        .config_path = o.config,
        .data_from_args = o.n_args > (o.config ? 1 : 0),
        .display_path = o.display,
        .check_sync = o.check_sync,
        .recorder = recorder,
    };
    float exposure = (float)session_config(s)->render.exposure;
    bool animated = !run && o.output &&
                    (o.frames || o.path || strchr(o.output, '%') || video_path_supported(o.output));
    if (animated) {
        if ((rc = animation(&o, s, &ld, path)) != EXIT_OK)
            goto done;
        ld.output = frame_output_open(&(struct frame_output_desc){
            .path = o.output,
            .fps = (int)lround(ld.fps),
            .codec = o.codec,
            .exposure = exposure,
            .per_view = o.display != NULL,
        });
        if (!ld.output) {
            rc = EXIT_BAD_INPUT;
            goto done;
        }
    } else if (run && o.path) {
        /* The keys add to the path and fly it; a file that is not there yet is made. */
        struct stat st_path;
        bool have = stat(o.path, &st_path) == 0;
        if ((have && !camera_path_load(o.path, path)) ||
            !session_set_camera_path(s, have ? path : NULL, o.path)) {
            rc = EXIT_BAD_INPUT;
            goto done;
        }
    }
    /* A large still picture says how far it is, row by row. */
    struct progress pr;
    long rows = 0, pixels = 0;
    for (int i = 0; !run && !animated && i < display_view_count(d); i++) {
        rows += display_view(d, i)->rv.height;
        pixels += (long)display_view(d, i)->rv.width * display_view(d, i)->rv.height;
    }
    bool counted = pixels >= 4L << 20;
    if (counted) {
        progress_begin(&pr, "render", "row", (uint64_t)rows);
        session_set_progress(s, &pr);
    }
    /* Every rank has its walls, its data and its output open: they start together. */
    gated = true;
    if (!app_cluster_gate(true, cw)) {
        rc = EXIT_FAILED;
        goto done;
    }
    app_cluster_swap_group(d);
    double loop_start = time_now_ms();
    /* Ctrl-C or a SIGTERM ends a run as closing its window does: the recording and --stats
     * are written, the exit code still says what stopped it.  (A cluster's ranks each get the
     * signal from mpirun and end at once; a render abandons its files.) */
    bool graceful = run && !cluster_active();
    fatal_stop_gracefully(graceful);
    rc = loop_run(d, s, &ld);
    fatal_stop_gracefully(false);
    int stopped = graceful ? fatal_stop_requested() : 0;
    session_stats(s)->stopped_by = stopped ? fatal_signal_name(stopped) : NULL;
    session_stats(s)->loop_ms = time_now_ms() - loop_start;
    if (counted) {
        session_set_progress(s, NULL);
        progress_end(&pr);
    }
    bool recorded = input_recorder_close(recorder);
    recorder = NULL;
    if (!recorded && rc == EXIT_OK)
        rc = EXIT_FAILED;
    struct session_stats *st = session_stats(s);
    session_collect_timings(s, true);
    if (ld.output) {
        if (rc == EXIT_OK && !frame_output_close(ld.output))
            rc = EXIT_FAILED;
        else if (rc != EXIT_OK)
            frame_output_abort(ld.output);
    } else if (rc == EXIT_OK && !run && !write_output(d, s, &o, exposure, st)) {
        rc = EXIT_FAILED;
    }
    if (st->nonfinite_pixels)
        log_warn("%zu pixels are not finite", st->nonfinite_pixels);
    st->gpu_bytes = gpu_bytes_allocated();
    st->total_ms = time_now_ms() - start;
    st->sync_ms += sync_ms; /* the swap barrier's, beside the loop's own collectives */
    /* Every rank reaches here together (the loop ends on all): rank 0 gathers their stats. */
    if (o.stats && (rc == EXIT_OK || cw->active) &&
        !app_cluster_stats(st, cw, o.stats, rc == EXIT_OK))
        rc = rc == EXIT_OK ? EXIT_FAILED : rc;
    if (stopped && rc == EXIT_OK)
        rc = 128 + stopped;
done:
    if (!gated && cluster_active())
        app_cluster_gate(false, cw);
    input_recorder_close(recorder);
    if (d)
        gpu_context_make_current(display_context(d));
    session_destroy(s);
    display_destroy(d);
    free(cfg);
    free(dcfg);
    free(path);
    free(cw);
    return rc;
}

int cmd_render(int argc, char **argv)
{
    return command(argc, argv, false);
}

int cmd_run(int argc, char **argv)
{
    return command(argc, argv, true);
}
