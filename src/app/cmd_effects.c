/* anvil effects: which effects a config simulates, and why (session/effects_report.h). */
#include <getopt.h>
#include <stdio.h>

#include "app/app.h"
#include "app/cmd_bench.h"
#include "common/log.h"
#include "config/config.h"
#include "session/effects_report.h"

#define MAX_SETS 64

static int usage(FILE *out)
{
    fprintf(out, "usage: anvil effects [CONFIG] [FILE...] [--display DISPLAY.cfg] [--run] "
                 "[--input SCRIPT] [--set PATH=VALUE]... [--quiet]\n"
                 "Prints each effect (effects.* in the config) as on or off with the reason,\n"
                 "decided from the scene as anvil render would (docs/effects.md).\n"
                 "  --display FILE  decide for these views (ground in view, HMD lens warp)\n"
                 "  --run           decide for anvil run: the sun can move, the view changes\n"
                 "  --input SCRIPT  decide for a scripted render (time may play)\n");
    return EXIT_USAGE;
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
    const char *config = NULL;
    char *display_sets[MAX_SETS];
    int n_display_sets;
    if (!app_route_sets(sets, &n_sets, display, display_sets, &n_display_sets))
        return EXIT_USAGE;
    struct config cfg;
    if (app_load_scene("effects", argv + optind, argc - optind, sets, n_sets, &cfg, &config) !=
        EXIT_OK)
        return EXIT_BAD_INPUT;
    struct display_config dcfg;
    if (display && (!app_load_display_config(display, display_sets, n_display_sets, &dcfg) ||
                    !app_frame_navigation(&cfg, &dcfg, NULL)))
        return EXIT_BAD_INPUT;
    struct effects_report rep;
    struct effects_report_desc d = {
        .display = display ? &dcfg : NULL, .run = run, .scripted = input != NULL};
    if (!effects_report_make(&cfg, &d, &rep))
        return EXIT_BAD_INPUT;
    const struct effects *e = &rep.effects;
    const char *what = config                                ? config
                       : argc > optind && cfg.data.file_count > 0 ? cfg.data.files[0]
                                                                  : "the built-in default scene";
    printf("effects of %s%s%s%s:\n", what, !config && cfg.data.file_count > 1 ? " ..." : "",
           display ? " on " : "", display ? display : "");
    for (int i = 0; i < EFFECT_COUNT; i++) {
        const char *mode = cfg.effects.mode[i] == EFFECT_AUTO     ? "auto"
                           : cfg.effects.mode[i] == EFFECT_ON     ? "on"
                           : cfg.effects.mode[i] == EFFECT_VOLUME ? "volume"
                                                                  : "off";
        printf("  %-14s %-3s  (%s) %s\n", effects_name(i), e->on[i] ? "on" : "off", mode,
               e->reason[i]);
    }
    printf("  light map      %s\n", e->light_builds);
    /* How the light map's nodes will lie (docs/lightmap.md, "Sheared grid"). */
    if (!rep.grid_ok)
        return EXIT_BAD_INPUT;
    if (rep.grid.sheared)
        printf("  light grid     sheared: horizontal node planes %.0f m apart (a flat volume; "
               "lightmap.grid = \"upright\" to stand them across the light)\n",
               rep.plane_m);
    else
        printf("  light grid     upright: node planes across the light%s\n",
               rep.light.grid == LIGHT_GRID_UPRIGHT ? " (lightmap.grid)" : "");
    return EXIT_OK;
}
