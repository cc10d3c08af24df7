/* A config's view through the Monte Carlo reference (traced.h). */
#include "session/traced.h"

#include <string.h>

#include "common/log.h"
#include "common/progress.h"
#include "session/scene.h"

bool traced_render(const struct config *cfg, const struct ext_volume *vol,
                   const struct traced_desc *d, struct image *mean, struct image *err,
                   double *trace_ms)
{
    memset(mean, 0, sizeof(*mean));
    memset(err, 0, sizeof(*err));
    struct render_settings settings;
    scene_render_settings(cfg, &settings);
    struct reference_desc desc;
    reference_desc_from_render(&settings, &cfg->optics.params, &desc);
    desc.albedo = d->albedo;
    struct render_view view;
    scene_camera_view(cfg, cfg->render.width, cfg->render.height, &view);
    struct reference *ref = reference_create(vol, &desc);
    if (!ref)
        return false;
    double t = time_now_ms();
    struct progress pr;
    progress_begin(&pr, "reference", "row", (uint64_t)view.height);
    struct reference_image_desc id = d->image;
    id.progress = &pr;
    bool ok = reference_render(ref, &view, &id, mean, err);
    progress_end(&pr);
    if (trace_ms)
        *trace_ms = time_now_ms() - t;
    reference_destroy(ref);
    return ok;
}
