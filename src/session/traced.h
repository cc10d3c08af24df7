/*
 * session/traced: a config's view path-traced by the Monte Carlo reference (reference/).  The
 * scene is the one anvil render draws: the volume from scene_build_volume, the lighting and
 * background of scene_render_settings (the renderer's sun radiance as the reference's
 * irradiance, its sky and ground), the config's camera at render.width x render.height.  What
 * the reference computes is in docs/reference.md.  No GL, no files: the caller writes the
 * images.
 */
#ifndef ANVIL_SESSION_TRACED_H
#define ANVIL_SESSION_TRACED_H

#include <stdbool.h>

#include "config/config.h"
#include "data/volume.h"
#include "reference/reference.h"
#include "render/image.h"

struct traced_desc {
    struct reference_image_desc image; /* samples per pixel, threads, seed, jitter */
    double albedo;                     /* single-scattering albedo in [0, 1] */
};

/* Renders CFG's view of VOL (built from CFG by scene_build_volume; borrowed) into MEAN and
 * ERR (initialised here, as reference_render's radiance and standard error).  *TRACE_MS (may
 * be NULL) receives the time of the tracing alone.  False (logged) on a bad description, out
 * of memory or a failed thread start; the images are then finished. */
bool traced_render(const struct config *cfg, const struct ext_volume *vol,
                   const struct traced_desc *d, struct image *mean, struct image *err,
                   double *trace_ms);

#endif
