/*
 * light/light_gpu: the deep light map on the GPU.  Every slice's extinction at once
 * (shaders/light_slices.comp), then the dense light volume swept from the sun
 * (shaders/light_build.comp), mirroring light_map_build() (the CPU reference) in float32; the
 * compressed mode compresses that volume's columns on the GPU as the reference compressor
 * does (shaders/light_compress.comp, light_compress_column) and keeps the nodes in two storage
 * buffers that the eye pass searches, the diffuse light's (M and N together) beside them.  The map is rebuilt only when its key (sun, volume, optics,
 * settings) changes, whatever the number of views.  Every function needs the GL context
 * current.
 */
#ifndef ANVIL_LIGHT_GPU_H
#define ANVIL_LIGHT_GPU_H

#include <stdbool.h>
#include <stdint.h>

#include "gpu/gpu.h"
#include "light/light.h"
#include "render/render.h"

enum light_gpu_mode { LIGHT_GPU_DENSE, LIGHT_GPU_COMPRESSED };

struct light_gpu;

/* Compiles the build program.  NULL (logged) when it does not compile. */
struct light_gpu *light_gpu_create(void);
void light_gpu_destroy(struct light_gpu *lg);

/* What a build reads: the extinction texture the renderer holds (RG32F, ice and water β),
 * its grid, an identity for the volume's content (bump GENERATION when it changes), and the
 * volume's macro cells (renderer_cells; NULL: none), with which a sample in an empty cell
 * reads no voxel. */
struct light_gpu_source {
    const struct gpu_texture *beta;
    const struct grid3 *grid;
    uint64_t volume_id, generation;
    const struct render_cells *cells;
};

/* Rebuilds the light map when anything in its key changed since the last build; *BUILT (may
 * be NULL) says whether it did.  Returns false (logged) on failure. */
bool light_gpu_update(struct light_gpu *lg, const struct light_gpu_source *src,
                      const double sun[3], const struct light_settings *settings,
                      enum light_gpu_mode mode, bool *built);

/* The same build in pieces, for building a map between frames while another is shown: the
 * map is bit-identical to light_gpu_update's.  light_gpu_build_begin starts a build when the key
 * changed (*NEEDED), or keeps the one under way for the same key (its pieces so far stand;
 * SRC's textures are taken again); from the start the map LG held is gone.  Each
 * light_gpu_build_step does pieces (a few slices, levels or planes of one pass, or one of the
 * passes that stay whole: the columns' diffuse light, the diffuse light volume, compression),
 * waiting for each, while the next, as long as the last, still fits into BUDGET_MS; at least
 * one.  *DONE: the map is built (as a light_gpu_update that built it; a build in pieces is not
 * timed on the GPU).  light_gpu_update drops a build under way, and so does
 * light_gpu_build_cancel.  SRC's textures must live until the build is done or dropped. */
bool light_gpu_build_begin(struct light_gpu *lg, const struct light_gpu_source *src,
                           const double sun[3], const struct light_settings *settings,
                           enum light_gpu_mode mode, bool *needed);
bool light_gpu_build_step(struct light_gpu *lg, double budget_ms, bool *done);
bool light_gpu_building(const struct light_gpu *lg);
/* The pass the next light_gpu_build_step works on (the playback bench's breakdown of the work
 * between frames): LIGHT_BUILD_START when no build is under way (the next step begins one: its
 * textures, and its first piece), then the passes in their order. */
enum light_build_phase {
    LIGHT_BUILD_START,
    LIGHT_BUILD_RATES,
    LIGHT_BUILD_SLICES,
    LIGHT_BUILD_SWEEP,
    LIGHT_BUILD_DIFFUSE,
    LIGHT_BUILD_VOLUME,
    LIGHT_BUILD_COMPRESS,
    LIGHT_BUILD_PHASES
};
enum light_build_phase light_gpu_build_phase(const struct light_gpu *lg);
/* PHASE's pass in words: "start", "lateral rates", "slices", ... */
const char *light_build_phase_name(enum light_build_phase phase);
/* The pass the next piece works on, in a sentence's words: "the light build's start",
 * "light build: lateral rates", ... */
const char *light_gpu_build_doing(const struct light_gpu *lg);
void light_gpu_build_cancel(struct light_gpu *lg);

/* Stores the following dense maps in half floats (R16F light, RG16F diffuse light: half the
 * memory, about three decimal digits; the build's arithmetic stays in floats) or, HALF false
 * (the default), in floats.  A change rebuilds at the next update.  Compressed maps are
 * floats either way. */
void light_gpu_set_half(struct light_gpu *lg, bool half);

/* The hook for renderer_set_light: valid until destroy; reads the last built map. */
const struct render_light *light_gpu_render_light(struct light_gpu *lg);

/* Binds the last built map for the eye pass PROG: as the map of step k, or with NEXT as the
 * second of a pair (effects.temporal, LIGHTMAP_PAIR: the BIND_LIGHTMAP_*_NEXT units of
 * shaders/bindings.h, the uniforms named *_next). */
void light_gpu_bind(const struct light_gpu *lg, const struct gpu_program *prog, bool next);
/* The LIGHTMAP variant of the last build: 1 dense, 2 compressed, 0 none built yet. */
int light_gpu_variant(const struct light_gpu *lg);

/* Builds so far. */
unsigned light_gpu_builds(const struct light_gpu *lg);

/* Times every following build into LOG (NULL, the default: builds are not timed, and nothing
 * in a dense build waits for the GPU; a compressed one waits for its node count, the size of
 * its node buffer).  Timing does not wait either (gpu.h, "timers"), except on
 * software drivers: the times arrive in LOG with light_gpu_collect_timings.  LOG is borrowed:
 * it must stay valid until light_gpu_collect_timings(lg, true) returned or LG is destroyed. */
void light_gpu_set_timing(struct light_gpu *lg, struct gpu_timings *log);
/* Moves the build times the GPU has ready into their logs without waiting, or with WAIT all
 * of them.  Returns how many are still in flight. */
int light_gpu_collect_timings(struct light_gpu *lg, bool wait);
/* The milliseconds of the last build, if known: collects without waiting, and returns false
 * while the GPU has not finished the build (or when it was not timed, or none was made). */
bool light_gpu_last_build_ms(struct light_gpu *lg, double *ms);

/* Bytes of the dense map (the light volume, and the diffuse one when the last build had
 * multiple scattering; floats, halves when stored so: in compressed mode what it would take in
 * floats) and of the compressed map
 * (0 in dense mode: the columns, the nodes and the half-resolution diffuse light); with the
 * diffuse light volume its field is in both. */
void light_gpu_bytes(const struct light_gpu *lg, size_t *dense, size_t *compressed);

/* Reads the compressed map (compressed mode) back into OUT (initialised here, finish with
 * light_compressed_finish): the layout of the CPU reference's light_compressed_build. */
bool light_gpu_read_compressed(const struct light_gpu *lg, struct light_compressed *out);
/* The last built map at world point P as the eye pass reads it, trilinear between nodes
 * (light_map_sample): the beam into *BEAM and, when the build had multiple scattering, the
 * diffuse M and N into DIFFUSE with *HAVE_DIFFUSE.  Dense mode reads the 2 x 2 x 2 nodes around
 * P back from the GPU (waiting for the build); compressed mode evaluates the columns the build
 * keeps on the CPU.  False when no map has been built. */
bool light_gpu_sample(const struct light_gpu *lg, const double p[3], float *beam,
                      float diffuse[2], bool *have_diffuse);

/* Reads the dense light volume (and the diffuse one, with multiple scattering) back into MAP
 * (initialised here, finish with light_map_finish): the same layout as the CPU reference.  Dense mode only: compressed mode
 * frees the dense volume once its columns are compressed. */
bool light_gpu_read(const struct light_gpu *lg, struct light_map *map);
/* The volume's lateral escape rates the last build with lateral escape made (as
 * light_lateral_rates lays them out: two floats a voxel), malloc'd into *OUT; false (logged)
 * when it made none. */
bool light_gpu_read_rates(const struct light_gpu *lg, float **out);

/* The diffuse light volume of the last build (settings.multiple and settings.volume) read back
 * into OUT (zeroed or finished; finish with light_volume_finish): light_volume_build's layout.
 * False when the last build made none. */
struct light_volume;
bool light_gpu_read_volume(const struct light_gpu *lg, struct light_volume *out);

#endif
