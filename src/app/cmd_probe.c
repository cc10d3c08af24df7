/* anvil probe: the values at one point of a scene's data, for scripts and tests. */
#include <getopt.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "app/app.h"
#include "common/log.h"
#include "config/config.h"
#include "data/probe.h"
#include "data/source.h"
#include "light/light.h"
#include "session/effects.h"
#include "session/lightmaps.h"
#include "session/player.h"
#include "session/probe.h"
#include "session/scene.h"

#define MAX_SETS 64

static int usage(FILE *out)
{
    fprintf(out,
            "usage: anvil probe [CONFIG] [FILE...] --at LAT,LON,HEIGHT_M [--step N] [--json]\n"
            "                   [--set PATH=VALUE]... [--quiet]\n"
            "  The values at one point of a scene's data (docs/analysis.md): where it is,\n"
            "  every species' mass ratio (g/kg), the condensate, temperature (C), pressure\n"
            "  (hPa), the wind (speed, the direction it blows from, vertical), the extinction\n"
            "  of the volume anvil render would draw there (1/km) and its light map's value.\n"
            "  CONFIG is a scene file; FILE... are data files or quoted patterns (WRF, an\n"
            "  extinction file, an Isabel folder), read with CONFIG's settings or the\n"
            "  defaults.  LAT, LON in degrees (north, east), HEIGHT_M metres above sea\n"
            "  level.  --step N: the time step (default data.step); --json: one JSON object.\n");
    return out == stdout ? EXIT_OK : EXIT_USAGE;
}

/* "LAT,LON,HEIGHT_M": three numbers, latitude within [-90, 90]. */
static bool parse_at(const char *s, double out[3])
{
    char *end;
    const char *p = s;
    for (int i = 0; i < 3; i++) {
        out[i] = strtod(p, &end);
        if (end == p || !isfinite(out[i]))
            goto bad;
        if (i < 2 && *end != ',')
            goto bad;
        p = end + (i < 2);
    }
    if (*end)
        goto bad;
    if (!(out[0] >= -90.0 && out[0] <= 90.0) || !(out[1] >= -360.0 && out[1] <= 360.0)) {
        log_error("probe: --at %s: expected a latitude in [-90, 90] and a longitude in "
                  "[-360, 360] degrees",
                  s);
        return false;
    }
    return true;
bad:
    log_error("probe: --at %s: expected LAT,LON,HEIGHT_M: three numbers (degrees north, "
              "degrees east, metres above sea level), e.g. --at 27.5,-88.4,3000",
              s);
    return false;
}

/* The light map anvil render would build for CFG's still picture (the CPU reference, which the
 * GPU build mirrors), sampled at WORLD. */
static bool light_at(const struct config *cfg, const struct ext_volume *vol, const double world[3],
                     struct probe_values *v)
{
    struct render_view view;
    scene_camera_view(cfg, cfg->render.width, cfg->render.height, &view);
    struct effects_context c = {
        .time_steps = 1, .views = &view, .view_count = 1, .views_known = true};
    struct effects_facts facts;
    if (!effects_gather(cfg, vol, &c, &facts))
        return false;
    struct effects e;
    effects_decide(cfg, &facts, &e);
    struct lightmaps_params lp;
    lightmaps_params_from(cfg, &e, cfg->light.azimuth_deg, cfg->light.elevation_deg, &lp);
    if (!lp.shadows)
        return true;
    struct light_map map = {0};
    if (!light_map_build(vol, lp.sun, &lp.light, &map))
        return false;
    double td[3];
    light_grid_world_to_tex(&map.grid, world, td);
    const float tex[3] = {(float)td[0], (float)td[1], (float)td[2]};
    v->have_light = true;
    v->light = light_map_sample(&map, tex);
    if (map.diffuse) {
        float md[2];
        light_map_sample_diffuse(&map, tex, md);
        v->have_diffuse = true;
        v->diffuse = md[0];
    }
    light_map_finish(&map);
    return true;
}

int cmd_probe(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"at", required_argument, NULL, 'a'},   {"step", required_argument, NULL, 't'},
        {"json", no_argument, NULL, 'j'},       {"set", required_argument, NULL, 's'},
        {"quiet", no_argument, NULL, 'q'},      {"help", no_argument, NULL, 'h'},
        {NULL, 0, NULL, 0},
    };
    const char *at = NULL, *step_text = NULL;
    bool json = false;
    char *sets[MAX_SETS];
    int n_sets = 0;
    optind = 1;
    int c;
    while ((c = getopt_long(argc, argv, "qh", longopts, NULL)) != -1) {
        switch (c) {
        case 'a':
            at = optarg;
            break;
        case 't':
            step_text = optarg;
            break;
        case 'j':
            json = true;
            break;
        case 's':
            if (n_sets == MAX_SETS) {
                log_error("too many --set options (at most %d)", MAX_SETS);
                return EXIT_USAGE;
            }
            sets[n_sets++] = optarg;
            break;
        case 'q':
            log_set_level(LOG_ERROR);
            break;
        case 'h':
            return usage(stdout);
        default:
            return usage(stderr);
        }
    }
    if (!at) {
        log_error("probe: missing --at LAT,LON,HEIGHT_M");
        return usage(stderr);
    }
    double where[3];
    if (!parse_at(at, where))
        return EXIT_BAD_INPUT;
    long step = -1;
    if (step_text && !app_option_long("probe", "--step", step_text, 0, 1000000, &step))
        return EXIT_BAD_INPUT;

    struct config *cfg = malloc(sizeof(*cfg));
    struct probe *pr = NULL;
    struct player *player = NULL;
    struct ext_volume vol = {0};
    int rc = EXIT_BAD_INPUT;
    if (!cfg) {
        log_error("out of memory");
        return EXIT_FAILED;
    }
    if (app_load_scene("probe", argv + optind, argc - optind, sets, n_sets, cfg, NULL) !=
        EXIT_OK)
        goto done;
    if (!(pr = probe_create(cfg)))
        goto done;
    int steps = probe_step_count(pr);
    if (step >= steps) {
        log_error("probe: --step %ld: the data has the time steps 0 to %d", step, steps - 1);
        goto done;
    }
    if (step >= 0)
        cfg->data.step = (int)step;
    else
        step = cfg->scene.kind == SCENE_DATA ? cfg->data.step : 0;
    double world[3];
    char why[192];
    if (!probe_world_at(pr, (int)step, where[0], where[1], where[2], world, why, sizeof(why))) {
        log_error("probe: --at %s: %s", at, why);
        goto done;
    }
    struct probe_values v;
    if (!probe_read(pr, (int)step, world, &v))
        goto done;
    if (!v.valid) {
        log_error("probe: --at %s: %s", at, v.why);
        goto done;
    }
    /* The volume anvil render would draw (the config's look), and its light map. */
    player = player_create(cfg, &(struct player_desc){.still = true});
    if (!player || !player_take_first(player, &vol))
        goto done;
    snprintf(v.date, sizeof(v.date), "%s", player_step_date(player, (int)step));
    probe_sample_beta(&vol, world, v.beta);
    if (!light_at(cfg, &vol, world, &v)) {
        rc = EXIT_FAILED;
        goto done;
    }
    if (json)
        probe_values_write_json(&v, stdout);
    else
        probe_values_write_text(&v, stdout);
    rc = fflush(stdout) == 0 ? EXIT_OK : EXIT_FAILED;
done:
    ext_volume_finish(&vol);
    player_destroy(player);
    probe_destroy(pr);
    free(cfg);
    return rc;
}
