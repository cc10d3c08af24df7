/*
 * light/volume_gpu: the diffuse light volume (light_volume.h) built on the GPU by
 * shaders/light_volume.comp, after the dense light map it reads, for the eye pass to read
 * (effects.multiple = "volume", MULTIPLE 2 in shaders/lightmap_lookup.glsl).  Same grid, same
 * source and the same discrete system as light_volume_build; solved in floats by conjugate
 * gradients with light_volume_build's bricks' preconditioner (LIGHT_VOLUME_PRECOND_BRICKS
 * whatever the desc says), whose scalars stay on the GPU (the CPU reads the state back every
 * few iterations to know when to stop).  Every function needs the GL
 * context current.
 */
#ifndef ANVIL_LIGHT_VOLUME_GPU_H
#define ANVIL_LIGHT_VOLUME_GPU_H

#include <stdbool.h>

#include "gpu/gpu.h"
#include "light/light.h"
#include "light/light_volume.h"

struct light_volume_gpu {
    struct gpu_program pass[7];  /* PASS 1 .. 6, made on first use; [6] PASS 1 on the model's
                                    own levels (STRETCHED) */
    struct gpu_texture zmap;     /* the volume's height table, for [7] */
    struct gpu_texture field;    /* RGBA32F phi and F per cell over the volume box */
    struct gpu_buffer terms, system, vectors, scalars; /* build scratch, freed after it */
    struct grid3 grid;           /* the cells */
    int iterations;              /* of the last build */
    float residual;              /* relative residual it reached */
    /* The build under way (light_volume_gpu_build_begin / _step). */
    bool solving;                /* begun, the field not made yet */
    bool converged;              /* the residual is down to the tolerance */
    int max_iterations;
    double tolerance;
};

/* Builds the field for the extinction texture BETA (RG32F on VOL_GRID), the dense light map
 * LIGHT (R32F or R16F nodes on LGRID) of settings S, with D's grid and tolerance (NULL:
 * defaults; the GPU stops at a relative residual of max(tolerance, 1e-5): floats).  False
 * (logged) on failure or when the solve does not converge. */
bool light_volume_gpu_build(struct light_volume_gpu *v, const struct gpu_texture *beta,
                            const struct grid3 *vol_grid, const struct gpu_texture *light,
                            const struct light_grid *lgrid, const struct light_settings *s,
                            const struct light_volume_desc *d);

/* The same build in pieces: _begin makes the source and the system (the first piece), each
 * _step runs ITERATIONS more iterations of the solve (0: to the end), and the one that ends it
 * makes the field and sets *DONE.  The field is the one light_volume_gpu_build makes, bit for
 * bit.  BETA and LIGHT are read by _begin only; anything may run on the GPU between pieces.
 * False (logged) as light_volume_gpu_build. */
bool light_volume_gpu_build_begin(struct light_volume_gpu *v, const struct gpu_texture *beta,
                                  const struct grid3 *vol_grid, const struct gpu_texture *light,
                                  const struct light_grid *lgrid,
                                  const struct light_settings *s,
                                  const struct light_volume_desc *d);
bool light_volume_gpu_build_step(struct light_volume_gpu *v, int iterations, bool *done);

/* Reads the field back into OUT (zeroed or finished; finish with light_volume_finish): the
 * layout of light_volume_build's. */
bool light_volume_gpu_read(const struct light_volume_gpu *v, struct light_volume *out);

/* Frees everything; a zeroed V is fine. */
void light_volume_gpu_finish(struct light_volume_gpu *v);

#endif
