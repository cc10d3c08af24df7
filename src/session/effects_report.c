/* anvil effects' decisions and light grid for a config (effects_report.h). */
#include "session/effects_report.h"

#include <math.h>
#include <string.h>

#include "config/display_config.h"
#include "display/display.h"
#include "session/scene.h"

bool effects_report_make(const struct config *cfg, const struct effects_report_desc *d,
                         struct effects_report *out)
{
    memset(out, 0, sizeof(*out));
    struct ext_volume vol = {0};
    if (!scene_build_volume(cfg, &vol))
        return false;
    static struct view_set set;
    struct render_view views[DISPLAY_MAX_VIEWS];
    int n = 0;
    bool known = !d->run;
    if (d->display) {
        int count = view_set_fixed(d->display, cfg->render.height, &set);
        known = count > 0;
        for (int i = 0; i < count; i++) {
            if (set.views[i].visible)
                views[n++] = set.views[i].rv;
        }
    } else if (known) {
        scene_camera_view(cfg, cfg->render.width, cfg->render.height, &views[0]);
        n = 1;
    }
    struct effects_context c = {
        .time_steps = scene_time_steps(cfg),
        .playback = d->run || d->scripted,
        .sun_moves = d->run,
        .display = d->display,
        .views = views,
        .view_count = n,
        .views_known = known,
    };
    struct effects_facts facts;
    double sun[3];
    light_sun_direction(cfg->light.azimuth_deg, cfg->light.elevation_deg, sun);
    bool ok = effects_gather(cfg, &vol, &c, &facts);
    const struct grid3 box = vol.grid;
    ext_volume_finish(&vol);
    if (!ok)
        return false;

    effects_decide(cfg, &facts, &out->effects);
    effects_light_settings(cfg, &out->effects, &out->light);
    out->grid_ok = light_grid_init(&out->grid, sun, &box, out->light.resolution, out->light.grid);
    if (out->grid_ok)
        out->plane_m = out->grid.step[2] * fabs(out->grid.w[2]);
    return true;
}
