/* anvil effects: which effects a config simulates, and why (app/effects.h). */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "app/app.h"
#include "app/cmd_bench.h"
#include "app/effects.h"
#include "common/log.h"
#include "config/display_config.h"
#include "display/display.h"
#include "light/light.h"
#include "render/camera.h"

#define MAX_SETS 64

static int usage(FILE *out)
{
    fprintf(out, "usage: anvil effects [CONFIG] [--display DISPLAY.cfg] [--run] "
                 "[--input SCRIPT] [--set PATH=VALUE]... [--quiet]\n"
                 "Prints each effect (effects.* in the config) as on or off with the reason,\n"
                 "decided from the scene as anvil render would (docs/effects.md).\n"
                 "  --display FILE  decide for these views (ground in view, HMD lens warp)\n"
                 "  --run           decide for anvil run: the sun can move, the view changes\n"
                 "  --input SCRIPT  decide for a scripted render (time may play)\n");
    return EXIT_USAGE;
}

/* The views of a display config whose head does not move (NULL count 0 otherwise: an HMD's
 * matrices come from its device, a path moves). */
static int display_views(const struct display_config *dcfg, int height, struct view_set *set)
{
    if (dcfg->type == DISPLAY_TYPE_HMD || dcfg->head.source != DISPLAY_HEAD_FIXED)
        return 0;
    int sizes[DISPLAY_MAX_WALLS][2];
    for (int w = 0; w < dcfg->wall_count; w++)
        view_set_wall_size(dcfg, w, height, sizes[w]);
    struct display_pose head;
    display_pose_from_euler(dcfg->head.position, dcfg->head.orientation_deg, &head);
    memset(set, 0, sizeof(*set));
    view_set_layout(set, dcfg, &head, (const int(*)[2])sizes);
    return set->count;
}

int cmd_effects(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"set", required_argument, NULL, 's'},     {"display", required_argument, NULL, 'D'},
        {"run", no_argument, NULL, 'r'},           {"quiet", no_argument, NULL, 'q'},
        {"input", required_argument, NULL, 'i'},
        {"help", no_argument, NULL, 'h'},          {NULL, 0, NULL, 0},
    };
    char *sets[MAX_SETS];
    int n_sets = 0;
    const char *display = NULL;
    bool run = false;
    const char *input = NULL;
    optind = 1;
    int c;
    while ((c = getopt_long(argc, argv, "qh", longopts, NULL)) != -1) {
        switch (c) {
        case 's':
            if (n_sets == MAX_SETS) {
                log_error("too many --set options (at most %d)", MAX_SETS);
                return EXIT_USAGE;
            }
            sets[n_sets++] = optarg;
            break;
        case 'D':
            display = optarg;
            break;
        case 'r':
            run = true;
            break;
        case 'i':
            input = optarg;
            break;
        case 'q':
            log_set_level(LOG_ERROR);
            break;
        case 'h':
            usage(stdout);
            return EXIT_OK;
        default:
            return usage(stderr);
        }
    }
    const char *config = optind < argc ? argv[optind++] : NULL;
    if (optind < argc) {
        log_error("effects: unexpected argument \"%s\" (one config file at most)", argv[optind]);
        return usage(stderr);
    }
    char *display_sets[MAX_SETS];
    int n_display_sets;
    if (!app_route_sets(sets, &n_sets, display, display_sets, &n_display_sets))
        return EXIT_USAGE;
    struct config cfg;
    if (!app_load_config(config, sets, n_sets, &cfg))
        return EXIT_BAD_INPUT;
    struct ext_volume vol = {0};
    if (!app_build_volume(&cfg, &vol))
        return EXIT_BAD_INPUT;
    struct effects_facts facts;
    effects_facts_init(&facts);
    double sun[3];
    light_sun_direction(cfg.light.azimuth_deg, cfg.light.elevation_deg, sun);
    bool ok = effects_measure_volume(&vol, sun, &cfg.optics.params, &facts);
    const struct grid3 box = vol.grid;
    ext_volume_finish(&vol);
    if (!ok)
        return EXIT_BAD_INPUT;
    facts.time_steps = app_time_steps(&cfg);
    facts.sun_moves = run && !display;
    facts.playback = run || input;

    static struct view_set set;
    struct render_view views[DISPLAY_MAX_VIEWS];
    int n = 0;
    bool known = !run;
    if (display) {
        struct display_config dcfg;
        if (!app_load_display_config(display, display_sets, n_display_sets, &dcfg))
            return EXIT_BAD_INPUT;
        facts.hmd = dcfg.type == DISPLAY_TYPE_HMD;
        facts.hmd_warp = dcfg.hmd.warp;
        int count = display_views(&dcfg, cfg.render.height, &set);
        known = count > 0;
        for (int i = 0; i < count; i++) {
            if (set.views[i].visible)
                views[n++] = set.views[i].rv;
        }
    } else if (known) {
        app_camera_view(&cfg, cfg.render.width, cfg.render.height, &views[0]);
        n = 1;
    }
    facts.views_known = known;
    for (int i = 0; i < n; i++)
        facts.ground_visible |= cfg.render.ground_on && effects_view_sees_ground(&views[i]);

    struct effects e;
    effects_decide(&cfg, &facts, &e);
    printf("effects of %s%s%s:\n", config ? config : "the built-in default scene",
           display ? " on " : "", display ? display : "");
    for (int i = 0; i < EFFECT_COUNT; i++) {
        const char *mode = cfg.effects.mode[i] == EFFECT_AUTO ? "auto"
                           : cfg.effects.mode[i] == EFFECT_ON ? "on"
                                                              : "off";
        printf("  %-14s %-3s  (%s) %s\n", effects_name(i), e.on[i] ? "on" : "off", mode,
               e.reason[i]);
    }
    printf("  light map      %s\n", e.light_builds);
    /* How the light map's nodes will lie (docs/lightmap.md, "Sheared grid"). */
    struct light_settings ls;
    effects_light_settings(&cfg, &e, &ls);
    struct light_grid grid;
    if (!light_grid_init(&grid, sun, &box, ls.resolution, ls.grid))
        return EXIT_BAD_INPUT;
    double plane_m = grid.step[2] * fabs(grid.w[2]);
    if (grid.sheared)
        printf("  light grid     sheared: horizontal node planes %.0f m apart (a flat volume; "
               "lightmap.grid = \"upright\" to stand them across the light)\n",
               plane_m);
    else
        printf("  light grid     upright: node planes across the light%s\n",
               ls.grid == LIGHT_GRID_UPRIGHT ? " (lightmap.grid)" : "");
    return EXIT_OK;
}
