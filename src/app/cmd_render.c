/* anvil render (headless, to files) and anvil run (a window). */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <GLFW/glfw3.h>

#include "app/app.h"
#include "app/interact.h"
#include "app/map.h"
#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "gpu/gpu.h"
#include "light/light.h"
#include "render/camera.h"

struct render_options {
    const char *config;
    const char *output;
    const char *stats;
    char *sets[64];
    int n_sets;
    const char *display; /* --display FILE: views from a display config */
    double time;         /* --time SECONDS: where on a scripted head path (with --display) */
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

/* What both commands share once a context is current. */
struct session {
    struct config cfg;
    struct renderer *renderer;
    struct render_settings settings;
    struct app_stats stats;
    struct app_light light;
    struct effects_facts facts; /* measured by session_start, views added by session_effects */
    struct effects effects;
    struct app_map *map; /* terrain, coastlines, graticule (app/map.h) */
    struct app_interact *interact; /* menu, input, playback (app/interact.h), or NULL */
    struct display_navigation nav_home; /* --display: the navigation a reset goes back to */
};

/* Decides the effects once the views are known (N of them; VIEWS NULL: they change while
 * running, so the ground counts as seen) and hands them to the light map and the eye pass. */
static void session_effects(struct session *s, const struct render_view *views, int n)
{
    s->facts.views_known = views != NULL;
    s->facts.ground_visible = false;
    for (int i = 0; views && i < n; i++)
        s->facts.ground_visible |= s->cfg.render.ground_on && effects_view_sees_ground(&views[i]);
    effects_decide(&s->cfg, &s->facts, &s->effects);
    for (int e = 0; e < EFFECT_COUNT; e++)
        log_debug("effect %s: %s (%s)", effects_name(e), s->effects.on[e] ? "on" : "off",
                  s->effects.reason[e]);
    app_light_set_effects(&s->light, &s->effects);
    effects_apply_render(&s->effects, &s->settings);
}

/* Moves the view and build times that arrived into the stats; with WAIT all of them, for the
 * report at the end of a run. */
static void session_timings(struct session *s, bool wait)
{
    if (s->renderer)
        renderer_collect_timings(s->renderer, wait);
    app_light_collect_timings(&s->light, wait);
}

/* Once per frame: collects the times that arrived (never waiting) and builds the light map if
 * the sun, volume or settings changed since the last build. */
static bool session_light(struct session *s)
{
    session_timings(s, false);
    return app_light_update(&s->light, &s->cfg, s->renderer, &s->stats);
}

static void session_finish(struct session *s)
{
    app_interact_destroy(s->interact); /* its meshes leave the renderer */
    s->interact = NULL;
    app_light_finish(&s->light);
    app_map_destroy(s->map, s->renderer);
    s->map = NULL;
    renderer_destroy(s->renderer);
    s->renderer = NULL;
}

static int session_start(struct session *s, const struct render_options *o)
{
    struct ext_volume vol = {0};
    double t = time_now_ms();
    if (!app_build_volume(&s->cfg, &vol))
        return EXIT_BAD_INPUT;
    s->stats.volume_ms = time_now_ms() - t;
    double sun[3];
    light_sun_direction(s->cfg.light.azimuth_deg, s->cfg.light.elevation_deg, sun);
    effects_facts_init(&s->facts);
    s->facts.time_steps = app_time_steps(&s->cfg);
    /* anvil run plays time; a render plays only when a script drives it. */
    s->facts.playback = strcmp(s->stats.command, "run") == 0 || o->input != NULL;
    if (!effects_measure_volume(&vol, sun, &s->cfg.optics.params, &s->facts)) {
        ext_volume_finish(&vol);
        return EXIT_BAD_INPUT;
    }
    log_info("volume %dx%dx%d (%.1f x %.1f x %.1f km) built in %.0f ms", vol.grid.n[0],
             vol.grid.n[1], vol.grid.n[2], vol.grid.n[0] * vol.grid.spacing[0] / 1000.0,
             vol.grid.n[1] * vol.grid.spacing[1] / 1000.0,
             vol.grid.n[2] * vol.grid.spacing[2] / 1000.0, s->stats.volume_ms);
    s->renderer = renderer_create();
    if (!s->renderer) {
        ext_volume_finish(&vol);
        return EXIT_FAILED;
    }
    /* An interactive run times its views only when they are reported: on a software driver
     * a timed view waits for itself (gpu.h, "timers"). */
    if (o->stats || strcmp(s->stats.command, "run") != 0)
        renderer_set_timing(s->renderer, &s->stats.view_times);
    bool ok = renderer_set_optics(s->renderer, &s->cfg.optics.params) &&
              renderer_set_volume(s->renderer, &vol);
    ext_volume_finish(&vol);
    if (!ok)
        return EXIT_FAILED;
    s->stats.upload_ms = renderer_stats(s->renderer)->upload_ms;
    if (!app_light_init(&s->light, &s->cfg))
        return EXIT_FAILED;
    app_light_set_timing(&s->light, &s->stats.build_times);
    s->map = app_map_create(&s->cfg, s->renderer);
    if (!s->map)
        return EXIT_FAILED;
    app_render_settings(&s->cfg, &s->settings);
    app_map_apply_settings(s->map, &s->settings);
    s->stats.device = gpu_renderer_name();
    return EXIT_OK;
}

static int usage_render(void)
{
    fprintf(stderr, "usage: anvil render [CONFIG] -o FILE.png|FILE.pfm [--set PATH=VALUE]... "
                    "[--stats FILE.json] [--quiet]\n"
                    "       anvil render [CONFIG] --display DISPLAY.cfg [--time SECONDS] "
                    "-o FOLDER/ [--format png|pfm] [...]\n"
                    "       anvil render --display help\n");
    return EXIT_USAGE;
}

/* ---- --display: many views, one light map ------------------------------------------------ */

static void print_backend(const char *name, const char *what, void *user)
{
    fprintf(user, "  %-10s %s\n", name, what);
}

static int display_help(void)
{
    printf("display backends (display.type in a display config, see displays/*.cfg and "
           "docs/displays.md):\n");
    display_list(print_backend, stdout);
    return EXIT_OK;
}

/* Opens the display and the session on its primary context. */
static int display_start(struct session *s, const struct render_options *o, bool offscreen,
                         struct display **out)
{
    *out = NULL;
    struct display_config dcfg;
    if (!display_config_load(o->display, &dcfg))
        return EXIT_BAD_INPUT;
    /* effects.distortion on or off overrides the display's hmd.warp; auto follows it. */
    enum effect_mode distortion = s->cfg.effects.mode[EFFECT_DISTORTION];
    if (distortion != EFFECT_AUTO)
        dcfg.hmd.warp = distortion == EFFECT_ON;
    struct display *d = display_create(&dcfg, &(struct display_desc){
        .offscreen = offscreen,
        .height = s->cfg.render.height,
    });
    if (!d)
        return offscreen ? EXIT_NO_GPU : EXIT_FAILED;
    *out = d;
    int rc = session_start(s, o);
    if (rc != EXIT_OK)
        return rc;
    if (!display_update(d, o->time))
        return EXIT_FAILED;
    s->facts.hmd = dcfg.type == DISPLAY_TYPE_HMD;
    s->facts.hmd_warp = dcfg.hmd.warp;
    struct render_view views[DISPLAY_MAX_VIEWS];
    int n = 0;
    for (int i = 0; i < display_view_count(d); i++) {
        if (display_view(d, i)->visible)
            views[n++] = display_view(d, i)->rv;
    }
    /* A moving head may bring the ground into view later. */
    session_effects(s, dcfg.head.source == DISPLAY_HEAD_FIXED ? views : NULL, n);
    log_info("display %s (%s): %d views", o->display, display_type_name(dcfg.type),
             display_view_count(d));
    return EXIT_OK;
}

/* One frame: the view loop draws (no light map build, no upload), then the display composes. */
static bool display_frame(struct session *s, struct display *d)
{
    if (!session_light(s))
        return false;
    if (!display_draw(d, s->renderer, &s->settings))
        return false;
    for (int i = 0; i < display_view_count(d); i++) {
        const struct view *v = display_view(d, i);
        if (v->visible)
            app_stats_add_view(&s->stats);
    }
    return display_present(d, s->renderer, (float)s->cfg.render.exposure);
}

/* ---- the menu, input and playback (app/interact.h) ---------------------------------- */

static int session_interact(struct session *s, const struct render_options *o, bool tracker,
                            void *window)
{
    s->interact = app_interact_create(&s->cfg, s->renderer, &s->light, &s->stats,
                                      &(struct app_interact_desc){
                                          .script = o->input,
                                          .transfers_dir = o->transfers,
                                          .tracker_space = tracker,
                                          .window = window,
                                          .wand = o->wand,
                                          .show_menu = window ? !o->input || o->menu : o->menu,
                                          .wait_for_volumes = !window,
                                      });
    return s->interact ? EXIT_OK : EXIT_BAD_INPUT;
}

/* Wall-clock seconds since the last call, or the script's frame time. */
static double frame_dt(struct session *s, double *last_ms)
{
    double now = time_now_ms(), dt = (now - *last_ms) * 1e-3;
    *last_ms = now;
    double script = s->interact ? app_interact_script_dt(s->interact) : 0.0;
    if (s->stats.frame_ms_max < dt * 1e3 && s->stats.frames > 1)
        s->stats.frame_ms_max = dt * 1e3;
    return script > 0.0 ? script : dt;
}

/* Input and menu for a display (tracker space); DIRTY is set when the views must be drawn. */
static bool display_interact(struct session *s, struct display *d, double dt, bool *dirty)
{
    if (!s->interact)
        return true;
    const struct display_config *dc = display_get_config(d);
    struct app_interact_frame f = {
        .dt = dt,
        .nav = display_navigation(d),
        .nav_home = &s->nav_home,
        .head = {(float)dc->head.position[0], (float)dc->head.position[1],
                 (float)dc->head.position[2]},
    };
    const struct view *v0 = display_view(d, 0);
    if (v0 && (dc->type == DISPLAY_TYPE_DESKTOP || dc->type == DISPLAY_TYPE_STEREO)) {
        f.have_camera = true;
        memcpy(f.view, v0->rv.view, sizeof(f.view));
        memcpy(f.proj, v0->rv.proj, sizeof(f.proj));
        f.width = v0->rv.width;
        f.height = v0->rv.height;
    }
    bool redraw = false, nav = false;
    if (!app_interact_frame(s->interact, &f, &s->settings, &redraw, &nav))
        return false;
    *dirty = *dirty || redraw || nav;
    return true;
}

/* anvil render --display --input: every frame of the script, then the settled result. */
static bool display_script(struct session *s, struct display *d, double time)
{
    double last = time_now_ms();
    for (long n = 0; !app_interact_script_done(s->interact); n++) {
        bool dirty = false;
        s->stats.frames++;
        if (n > 1000000 || !display_interact(s, d, frame_dt(s, &last), &dirty) ||
            !display_update(d, time) || !display_frame(s, d))
            return false;
    }
    bool dirty = false;
    return app_interact_settle(s->interact) && display_interact(s, d, 0.0, &dirty) &&
           display_update(d, time);
}

/* anvil render --input without --display: the script's frames on the config's camera (a
 * world-space menu), each drawn, then the settled result. */
static int view_script(struct session *s, const struct render_options *o,
                       const struct render_view *view, struct gpu_texture *target)
{
    int rc = session_interact(s, o, false, NULL);
    if (rc != EXIT_OK)
        return rc;
    struct app_interact_frame f = {.have_camera = true, .width = view->width,
                                   .height = view->height};
    memcpy(f.view, view->view, sizeof(f.view));
    memcpy(f.proj, view->proj, sizeof(f.proj));
    double last = time_now_ms();
    bool redraw, nav;
    for (long n = 0; o->input && !app_interact_script_done(s->interact); n++) {
        f.dt = frame_dt(s, &last);
        s->stats.frames++;
        if (n > 1000000 || !app_interact_frame(s->interact, &f, &s->settings, &redraw, &nav) ||
            !session_light(s) || !renderer_draw(s->renderer, &s->settings, view, target))
            return EXIT_FAILED;
    }
    f.dt = 0.0;
    if ((o->input && !app_interact_settle(s->interact)) ||
        !app_interact_frame(s->interact, &f, &s->settings, &redraw, &nav))
        return EXIT_FAILED;
    return EXIT_OK;
}

static int render_display(struct session *s, const struct render_options *o, double start)
{
    struct display *d = NULL;
    int rc = display_start(s, o, true, &d);
    if (rc == EXIT_OK && (o->input || o->menu)) {
        s->nav_home = *display_navigation(d);
        rc = session_interact(s, o, true, NULL);
        if (rc == EXIT_OK && o->input && !display_script(s, d, o->time))
            rc = EXIT_FAILED;
        if (rc == EXIT_OK && !o->input) {
            bool dirty = false;
            if (!display_interact(s, d, 0.0, &dirty) || !display_update(d, o->time))
                rc = EXIT_FAILED;
        }
    }
    if (rc == EXIT_OK) {
        rc = EXIT_FAILED;
        if (display_frame(s, d) &&
            display_write_images(d, o->output, o->format ? o->format : "png",
                                 (float)s->cfg.render.exposure,
                                 &s->stats.nonfinite_pixels))
            rc = EXIT_OK;
    }
    if (s->stats.nonfinite_pixels)
        log_warn("%zu pixels are not finite", s->stats.nonfinite_pixels);
    if (d) {
        session_timings(s, true);
        s->stats.gpu_bytes = gpu_bytes_allocated();
        s->stats.total_ms = time_now_ms() - start;
        if (rc == EXIT_OK && o->stats && !app_stats_write(&s->stats, o->stats))
            rc = EXIT_FAILED;
    }
    session_finish(s);
    display_destroy(d);
    return rc;
}

static int run_display(struct session *s, const struct render_options *o, double start)
{
    struct display *d = NULL;
    int rc = display_start(s, o, false, &d);
    if (rc == EXIT_OK) {
        s->nav_home = *display_navigation(d);
        rc = session_interact(s, o, true, gpu_context_window(display_context(d)));
    }
    const char *frames_env = getenv("ANVIL_RUN_FRAMES"); /* for automated runs */
    long frames_left = frames_env ? strtol(frames_env, NULL, 10) : -1;
    bool moving = d && display_get_config(d)->head.source != DISPLAY_HEAD_FIXED;
    double t0 = time_now_ms(), last = t0;
    bool dirty = true;
    while (rc == EXIT_OK && !display_should_close(d) && frames_left != 0) {
        if (display_navigation_changed(d))
            dirty = true;
        if (!display_interact(s, d, frame_dt(s, &last), &dirty)) {
            rc = EXIT_FAILED;
            break;
        }
        if (dirty || moving || frames_left > 0) {
            s->stats.frames++;
            if (!display_update(d, o->time + (time_now_ms() - t0) * 1e-3) ||
                !display_frame(s, d)) {
                rc = EXIT_FAILED;
                break;
            }
            dirty = false;
            if (frames_left > 0)
                frames_left--;
        }
        display_poll(d, moving || frames_left > 0 || dirty ? 0.0 : 0.03);
    }
    if (d) {
        session_timings(s, true);
        s->stats.gpu_bytes = gpu_bytes_allocated();
        s->stats.total_ms = time_now_ms() - start;
        if (rc == EXIT_OK && o->stats && !app_stats_write(&s->stats, o->stats))
            rc = EXIT_FAILED;
    }
    session_finish(s);
    display_destroy(d);
    return rc;
}

/* Parses the options and loads the config into S.  Returns -1 to go on, else the exit code
 * (help, usage errors, bad input). */
static int command_begin(int argc, char **argv, bool need_output, int (*usage)(void),
                         struct render_options *o, struct session *s)
{
    int rc = parse_options(argc, argv, o, need_output);
    if (rc < 0) {
        usage();
        return EXIT_OK;
    }
    if (rc == EXIT_BAD_INPUT)
        return rc;
    if (rc != EXIT_OK)
        return usage();
    if (o->display && strcmp(o->display, "help") == 0)
        return display_help();
    if (!app_load_config(o->config, o->sets, o->n_sets, &s->cfg))
        return EXIT_BAD_INPUT;
    return -1;
}

int cmd_render(int argc, char **argv)
{
    double start = time_now_ms();
    struct render_options o;
    struct session s = {.stats.command = "render"};
    int rc = command_begin(argc, argv, true, usage_render, &o, &s);
    if (rc >= 0)
        return rc;
    if (o.display)
        return render_display(&s, &o, start);

    struct gpu_context *ctx = gpu_context_create(&(struct gpu_context_desc){.backend = "egl"});
    if (!ctx)
        return EXIT_NO_GPU;
    rc = session_start(&s, &o);
    if (rc != EXIT_OK)
        goto done;

    struct render_view view;
    app_camera_view(&s.cfg, s.cfg.render.width, s.cfg.render.height, &view);
    session_effects(&s, &view, 1);
    struct gpu_texture target = {0};
    struct image img = {0};
    /* The script's frames are neither counted nor timed: the report is the settled view's. */
    renderer_set_timing(s.renderer, NULL);
    if ((o.input || o.menu) && (rc = view_script(&s, &o, &view, &target)) != EXIT_OK)
        goto done_target;
    renderer_set_timing(s.renderer, &s.stats.view_times);
    rc = EXIT_FAILED;
    if (!session_light(&s) || !renderer_draw(s.renderer, &s.settings, &view, &target))
        goto done_target;
    app_stats_add_view(&s.stats);
    if (!renderer_read(&target, &img))
        goto done_target;
    session_timings(&s, true); /* the read-back waited for the GPU already */
    s.stats.nonfinite_pixels = image_count_nonfinite(&img);
    if (s.stats.nonfinite_pixels)
        log_warn("%zu pixels are not finite", s.stats.nonfinite_pixels);
    if (!image_write(&img, o.output, (float)s.cfg.render.exposure)) {
        rc = EXIT_FAILED;
        goto done_image;
    }
    log_info("wrote %s (%dx%d, view %.1f ms on %s)", o.output, img.width, img.height,
             s.stats.view_times.total_ms, s.stats.device);
    s.stats.gpu_bytes = gpu_bytes_allocated();
    s.stats.total_ms = time_now_ms() - start;
    rc = EXIT_OK;
    if (o.stats && !app_stats_write(&s.stats, o.stats))
        rc = EXIT_FAILED;
done_image:
    image_finish(&img);
done_target:
    gpu_texture_finish(&target);
done:
    session_finish(&s);
    gpu_context_destroy(ctx);
    return rc;
}

/* ---- anvil run: one window, orbit and zoom with mouse and keys ------------------------- */

struct run_state {
    struct camera_orbit orbit, home;
    bool dragging;
    double last_x, last_y;
    bool dirty;
    double sun_az, sun_el;
    bool sun_dirty;
};

static void on_scroll(GLFWwindow *w, double dx, double dy)
{
    struct run_state *st = glfwGetWindowUserPointer(w);
    st->orbit.distance_m *= pow(0.9, dy);
    st->dirty = true;
}

static void on_button(GLFWwindow *w, int button, int action, int mods)
{
    struct run_state *st = glfwGetWindowUserPointer(w);
    if (button == GLFW_MOUSE_BUTTON_LEFT) {
        st->dragging = action == GLFW_PRESS;
        glfwGetCursorPos(w, &st->last_x, &st->last_y);
    }
}

static void on_cursor(GLFWwindow *w, double x, double y)
{
    struct run_state *st = glfwGetWindowUserPointer(w);
    if (!st->dragging)
        return;
    st->orbit.azimuth_deg += 0.3 * (x - st->last_x);
    st->orbit.elevation_deg += 0.3 * (y - st->last_y);
    if (st->orbit.elevation_deg > 89.0)
        st->orbit.elevation_deg = 89.0;
    if (st->orbit.elevation_deg < -89.0)
        st->orbit.elevation_deg = -89.0;
    st->last_x = x;
    st->last_y = y;
    st->dirty = true;
}

static void on_key(GLFWwindow *w, int key, int scancode, int action, int mods)
{
    struct run_state *st = glfwGetWindowUserPointer(w);
    if (action == GLFW_RELEASE)
        return;
    switch (key) {
    case GLFW_KEY_ESCAPE:
    case GLFW_KEY_Q:
        glfwSetWindowShouldClose(w, GLFW_TRUE);
        break;
    case GLFW_KEY_LEFT:
        st->orbit.azimuth_deg -= 5.0;
        break;
    case GLFW_KEY_RIGHT:
        st->orbit.azimuth_deg += 5.0;
        break;
    case GLFW_KEY_UP:
        st->orbit.elevation_deg = fmin(89.0, st->orbit.elevation_deg + 5.0);
        break;
    case GLFW_KEY_DOWN:
        st->orbit.elevation_deg = fmax(-89.0, st->orbit.elevation_deg - 5.0);
        break;
    case GLFW_KEY_EQUAL:
    case GLFW_KEY_KP_ADD:
    case GLFW_KEY_PAGE_UP:
        st->orbit.distance_m *= 0.9;
        break;
    case GLFW_KEY_MINUS:
    case GLFW_KEY_KP_SUBTRACT:
    case GLFW_KEY_PAGE_DOWN:
        st->orbit.distance_m /= 0.9;
        break;
    case GLFW_KEY_R:
        st->orbit = st->home;
        break;
    case GLFW_KEY_A:
        st->sun_az -= 5.0;
        st->sun_dirty = true;
        break;
    case GLFW_KEY_D:
        st->sun_az += 5.0;
        st->sun_dirty = true;
        break;
    case GLFW_KEY_W:
        st->sun_el = fmin(90.0, st->sun_el + 2.0);
        st->sun_dirty = true;
        break;
    case GLFW_KEY_S:
        st->sun_el = fmax(-10.0, st->sun_el - 2.0);
        st->sun_dirty = true;
        break;
    default:
        return;
    }
    st->dirty = true;
}

static int usage_run(void)
{
    fprintf(stderr,
            "usage: anvil run [CONFIG] [--set PATH=VALUE]... [--stats FILE.json] [--quiet]\n"
            "  mouse drag / arrows: orbit    wheel / + -: zoom    R: reset view\n"
            "  A D: sun azimuth    W S: sun elevation    Esc Q: quit\n"
            "       anvil run [CONFIG] --display DISPLAY.cfg [--time SECONDS] [...]\n"
            "  W S: fly forward/back    A D: sideways    R F: up/down    arrows: turn\n"
            "  + -: scale the storm    Esc Q: quit\n");
    return EXIT_USAGE;
}

int cmd_run(int argc, char **argv)
{
    double start = time_now_ms();
    struct render_options o;
    struct session s = {.stats.command = "run"};
    int rc = command_begin(argc, argv, false, usage_run, &o, &s);
    if (rc >= 0)
        return rc;
    if (o.display)
        return run_display(&s, &o, start);
    struct gpu_context *ctx = gpu_context_create(&(struct gpu_context_desc){
        .backend = "glfw",
        .width = s.cfg.render.width,
        .height = s.cfg.render.height,
        .title = "anvil",
        .monitor = -1,
    });
    if (!ctx)
        return EXIT_NO_GPU;
    rc = session_start(&s, &o);
    if (rc != EXIT_OK)
        goto done;
    s.facts.sun_moves = true; /* the keys move the sun */
    session_effects(&s, NULL, 0);

    struct run_state st = {.dirty = true};
    double eye[3], target[3];
    for (int i = 0; i < 3; i++) {
        eye[i] = s.cfg.camera.position_km[i] * 1000.0;
        target[i] = s.cfg.camera.target_km[i] * 1000.0;
    }
    camera_orbit_from(eye, target, &st.orbit);
    st.home = st.orbit;
    st.sun_az = s.cfg.light.azimuth_deg;
    st.sun_el = s.cfg.light.elevation_deg;
    GLFWwindow *win = gpu_context_window(ctx);
    glfwSetWindowUserPointer(win, &st);
    glfwSetScrollCallback(win, on_scroll);
    glfwSetMouseButtonCallback(win, on_button);
    glfwSetCursorPosCallback(win, on_cursor);
    glfwSetKeyCallback(win, on_key);
    rc = session_interact(&s, &o, false, win); /* chains the callbacks above */
    if (rc != EXIT_OK)
        goto done;
    const char *frames_env = getenv("ANVIL_RUN_FRAMES"); /* for automated runs */
    long frames_left = frames_env ? strtol(frames_env, NULL, 10) : -1;

    struct gpu_texture hdr = {0}, ldr = {0};
    double last = time_now_ms();
    rc = EXIT_OK;
    while (!glfwWindowShouldClose(win) && frames_left != 0) {
        if (st.sun_dirty) {
            s.cfg.light.azimuth_deg = st.sun_az;
            s.cfg.light.elevation_deg = st.sun_el;
            app_render_settings(&s.cfg, &s.settings);
            app_map_apply_settings(s.map, &s.settings);
            effects_apply_render(&s.effects, &s.settings);
            st.sun_dirty = false;
        }
        int w, h;
        gpu_context_size(ctx, &w, &h);
        if (frames_left > 0)
            st.dirty = true; /* automated runs draw every frame */
        struct render_view view;
        camera_orbit_eye(&st.orbit, eye);
        camera_look_at(eye, st.orbit.target, s.cfg.camera.up, s.cfg.camera.fov_deg,
                       s.cfg.camera.near_m, s.cfg.camera.far_km * 1000.0, w > 0 ? w : 1,
                       h > 0 ? h : 1, &view);
        struct app_interact_frame f = {.dt = frame_dt(&s, &last), .have_camera = true,
                                       .width = w, .height = h};
        memcpy(f.view, view.view, sizeof(f.view));
        memcpy(f.proj, view.proj, sizeof(f.proj));
        bool redraw = false, nav = false;
        if (!app_interact_frame(s.interact, &f, &s.settings, &redraw, &nav)) {
            rc = EXIT_FAILED;
            break;
        }
        st.dirty = st.dirty || redraw;
        if (st.dirty && w > 0 && h > 0) {
            s.stats.frames++;
            if (!session_light(&s)) {
                rc = EXIT_FAILED;
                break;
            }
            if (!renderer_draw(s.renderer, &s.settings, &view, &hdr) ||
                !renderer_tonemap(s.renderer, &hdr, (float)s.cfg.render.exposure, &ldr)) {
                rc = EXIT_FAILED;
                break;
            }
            app_stats_add_view(&s.stats);
            gpu_present(&ldr, 0, 0, w, h, 0);
            gpu_context_swap(ctx);
            st.dirty = false;
            if (frames_left > 0)
                frames_left--;
        }
        if (frames_left > 0 || redraw)
            glfwPollEvents();
        else
            glfwWaitEventsTimeout(0.03);
    }
    gpu_texture_finish(&hdr);
    gpu_texture_finish(&ldr);
    session_timings(&s, true);
    s.stats.gpu_bytes = gpu_bytes_allocated();
    s.stats.total_ms = time_now_ms() - start;
    if (o.stats && !app_stats_write(&s.stats, o.stats))
        rc = EXIT_FAILED;
done:
    session_finish(&s);
    gpu_context_destroy(ctx);
    return rc;
}
