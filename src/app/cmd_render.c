/* anvil render (headless, to files) and anvil run (windows): options, then the frame loop. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "app/loop.h"
#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "session/scene.h"
#include "session/session.h"

struct render_options {
    const char *config;
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
};

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
        {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    memset(o, 0, sizeof(*o));
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
                return EXIT_USAGE;
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
                return EXIT_USAGE;
            }
            o->format = optarg;
            break;
        case 'h':
            return -1;
        default:
            return EXIT_USAGE;
        }
    }
    if (optind < argc)
        o->config = argv[optind++];
    if (optind < argc) {
        log_error("%s: unexpected argument \"%s\" (one config file at most)", argv[0],
                  argv[optind]);
        return EXIT_USAGE;
    }
    if (need_output && !o->output && !(o->display && strcmp(o->display, "help") == 0)) {
        log_error(o->display ? "render: missing -o FOLDER/ (one image per view goes there)"
                             : "render: missing -o FILE.png or -o FILE.pfm");
        return EXIT_USAGE;
    }
    /* A file name the writers cannot serve is refused before any work is done. */
    if (need_output && o->output && !o->display && !image_path_supported(o->output)) {
        log_error("%s: unknown image type: expected a name ending in .png or .pfm", o->output);
        return EXIT_BAD_INPUT;
    }
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
                "usage: anvil run [CONFIG] [--display DISPLAY.cfg] [--set PATH=VALUE]...\n"
                "                 [--input SCRIPT] [--wand NAME] [--transfers DIR] [--time S]\n"
                "                 [--stats FILE.json] [--quiet]\n"
                "  Without --display: one window of the scene's camera (camera.*), orbiting\n"
                "  its target.  The keys mean the same on every display:\n");
    else
        fprintf(out,
                "usage: anvil render [CONFIG] -o FILE.png|FILE.pfm [--set PATH=VALUE]...\n"
                "                    [--input SCRIPT] [--menu] [--stats FILE.json] [--quiet]\n"
                "       anvil render [CONFIG] --display DISPLAY.cfg [--time SECONDS] "
                "-o FOLDER/ [--format png|pfm] [...]\n"
                "       anvil render --display help\n"
                "  A script (--input) plays these keys and the wand's buttons (docs/menu.md):\n");
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
                        struct display_config *dcfg)
{
    char *display_sets[64];
    int n_display_sets = 0;
    if (!app_route_sets(o->sets, &o->n_sets, o->display, display_sets, &n_display_sets))
        return EXIT_USAGE;
    if (!config_load_overrides(o->config, o->sets, o->n_sets, cfg))
        return EXIT_BAD_INPUT;
    if (o->display) {
        if (!app_load_display_config(o->display, display_sets, n_display_sets, dcfg))
            return EXIT_BAD_INPUT;
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

/* Writes what a render made: the one view as -o FILE, or every view into -o FOLDER/. */
static bool write_output(struct display *d, const struct render_options *o, float exposure,
                         struct session_stats *st)
{
    if (o->display)
        return display_write_images(d, o->output, o->format ? o->format : "png", exposure,
                                    &st->nonfinite_pixels);
    struct image img = {0};
    const struct view *v = display_view(d, 0);
    if (!v || !renderer_read(&v->target, &img))
        return false;
    st->nonfinite_pixels = image_count_nonfinite(&img);
    bool ok = image_write(&img, o->output, exposure);
    if (ok)
        log_info("wrote %s (%dx%d, view %.1f ms on %s)", o->output, img.width, img.height,
                 st->view_times.total_ms, st->device);
    image_finish(&img);
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
    struct display *d = NULL;
    struct session *s = NULL;
    rc = EXIT_FAILED;
    if (!cfg || !dcfg) {
        log_error("out of memory");
        goto done;
    }
    if ((rc = load_configs(&o, cfg, dcfg)) != EXIT_OK)
        goto done;

    enum display_failure why = DISPLAY_FAILED_NONE;
    struct display_desc dd = {.offscreen = !run, .height = cfg->render.height, .failure = &why};
    scene_camera(cfg, &dd.camera);
    d = display_create(dcfg, &dd);
    if (!d) {
        /* 3 is for a missing OpenGL context only: a bad pose file or device is bad input. */
        rc = why == DISPLAY_FAILED_CONTEXT ? EXIT_NO_GPU
             : why == DISPLAY_FAILED_INPUT ? EXIT_BAD_INPUT
                                           : EXIT_FAILED;
        goto done;
    }
    if (!display_update(d, o.time)) {
        rc = EXIT_FAILED;
        goto done;
    }
    struct render_view views[DISPLAY_MAX_VIEWS];
    int n = 0;
    for (int i = 0; i < display_view_count(d); i++) {
        if (display_view(d, i)->visible)
            views[n++] = display_view(d, i)->rv;
    }
    /* A moving head may bring the ground into view later; so may the orbit camera of run. */
    bool views_move = display_head_moves(d) || (run && !o.display);
    s = session_create(cfg,
                       &(struct session_desc){
                           .command = run ? "run" : "render",
                           .display = dcfg,
                           .views = views_move ? NULL : views,
                           .view_count = views_move ? 0 : n,
                           .views_move = views_move,
                           .interactive = run,
                           .playback = run || o.input,
                           .menu = run || o.input || o.menu,
                           .show_menu = run ? !o.input || o.menu : o.menu,
                           .script = o.input,
                           .transfers_dir = o.transfers,
                           .wand = o.wand,
                           /* An interactive run times its views only when they are reported. */
                           .time_views = o.stats || !run,
                       },
                       &rc);
    if (!s) {
        rc = rc == 1 ? EXIT_BAD_INPUT : EXIT_FAILED;
        goto done;
    }
    if (o.display)
        log_info("display %s (%s): %d views", o.display, display_type_name(dcfg->type),
                 display_view_count(d));
    const char *frames_env = getenv("ANVIL_RUN_FRAMES"); /* for automated runs */
    rc = loop_run(d, s,
                  &(struct loop_desc){.run = run,
                                      .time = o.time,
                                      .frames = frames_env ? strtol(frames_env, NULL, 10) : -1});
    struct session_stats *st = session_stats(s);
    session_collect_timings(s, true);
    if (rc == EXIT_OK && !run &&
        !write_output(d, &o, (float)session_config(s)->render.exposure, st))
        rc = EXIT_FAILED;
    if (st->nonfinite_pixels)
        log_warn("%zu pixels are not finite", st->nonfinite_pixels);
    st->gpu_bytes = gpu_bytes_allocated();
    st->total_ms = time_now_ms() - start;
    if (rc == EXIT_OK && o.stats && !session_stats_write(st, o.stats))
        rc = EXIT_FAILED;
done:
    if (d)
        gpu_context_make_current(display_context(d));
    session_destroy(s);
    display_destroy(d);
    free(cfg);
    free(dcfg);
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
