/*
 * Binding points shared by the C code that binds textures, images and storage buffers and
 * the shaders that declare them: `layout(binding = NAME)` in shaders/, the same NAME in the
 * gpu_texture_bind / gpu_image_bind / gpu_buffer_bind calls in src/.  C includes this file as
 * "shaders/bindings.h"; shaders as `#include "bindings.h"` (src/gpu/gpu.c pastes it in).
 *
 * Only `#define NAME N` lines and comments, so both languages read it.  There is no include
 * guard: repeating an identical #define is allowed in C and in GLSL, and the shader loader
 * pastes each file once anyway.
 *
 * Texture units, image units and storage buffer bindings are three separate name spaces
 * (BIND_*_TEX_*, BIND_*_IMG_*, BIND_*_BUF_*).  Within one program the numbers of one kind must
 * differ: the groups below say which names meet in which program, and tests/unit/
 * test_bindings.c checks it, and that no shader or bind call uses a bare number.
 */

/* ---- light map lookup (shaders/lightmap_lookup.glsl) -------------------------------------
 * Read by the eye pass and by the opaque pass; bound by light_gpu_bind.  A light map pair
 * (effects.temporal, LIGHTMAP_PAIR) binds step k's map at the plain names and step k + 1's at
 * the *_NEXT names, all at once: the eight must differ from each other and from the units of
 * the eye pass and the opaque pass. */
#define BIND_LIGHTMAP_TEX_LIGHT 2          /* LIGHTMAP 1: dense light volume, R32F */
#define BIND_LIGHTMAP_TEX_LIGHT_NEXT 8     /* ... of step k + 1 */
#define BIND_LIGHTMAP_TEX_DIFFUSE 9        /* MULTIPLE 1 and LIGHTMAP 1: diffuse light M, N;
                                              MULTIPLE 2 (either LIGHTMAP): the diffuse light
                                              volume, phi and F (RGBA32F) */
#define BIND_LIGHTMAP_TEX_DIFFUSE_NEXT 10  /* ... of step k + 1 */
#define BIND_LIGHTMAP_BUF_COLUMNS 0        /* LIGHTMAP 2: first node and count per column (of
                                              the light, then of the diffuse light) */
#define BIND_LIGHTMAP_BUF_NODES 1          /* LIGHTMAP 2: the light's nodes, then the diffuse
                                              light's */
#define BIND_LIGHTMAP_BUF_COLUMNS_NEXT 2   /* ... of step k + 1 */
#define BIND_LIGHTMAP_BUF_NODES_NEXT 3     /* ... of step k + 1 */

/* ---- eye pass (shaders/raycast.comp, renderer_draw) --------------------------------------
 * Besides its own units, the eye pass reads the light map's (above). */
#define BIND_EYE_TEX_BETA 0             /* RG32F extinction: ice and water phase */
#define BIND_EYE_TEX_PHASE 1            /* 1D eye phase table */
#define BIND_EYE_TEX_OPAQUE_COLOR 3     /* OPAQUE 1: radiance of the opaque geometry */
#define BIND_EYE_TEX_OPAQUE_DISTANCE 4  /* OPAQUE 1: its distance along the ray */
#define BIND_EYE_TEX_TINT 6             /* TINT 1: colour of the scattered light */
#define BIND_EYE_TEX_BETA_NEXT 7        /* TEMPORAL 1: extinction of step k + 1 */
#define BIND_EYE_TEX_LAYERS 11          /* LAYERS > 0: RGBA32F 3D, layer i's field in channel i */
#define BIND_EYE_TEX_LAYER_LUT 12       /* LAYERS or SLICES > 0: RGBA32F 2D colour maps, row i
                                           layer i's, row 4 + i slice i's */
#define BIND_EYE_TEX_SLICES 13          /* SLICES > 0: RGBA32F 3D, slice i's field in channel i */
#define BIND_EYE_TEX_SLICE_SURFACES 14  /* SLICES > 0: RGBA32F 2D, slice i's level surface (world
                                           z at each column) in channel i */
#define BIND_EYE_TEX_ZMAP 15            /* STRETCHED 1: the volume's height table (zmap.glsl) */
#define BIND_EYE_IMG_OUT 0              /* RGBA32F radiance and transmittance */
#define BIND_EYE_BUF_CELLS 4            /* SKIP 1: the macro-cell pyramid (cells.glsl) */
#define BIND_EYE_BUF_COUNTERS 5         /* COUNT 1: what the rays did */
#define BIND_EYE_BUF_RAYS 6             /* SKIP 1: the rays the second pass marches */

/* ---- macro cells: empty-space skipping (shaders/cells_build.comp, cells_reduce.comp) --- */
#define BIND_CELLS_TEX_BETA 0       /* the volume's extinction, texelFetch only */
#define BIND_CELLS_TEX_BETA_NEXT 1  /* TEMPORAL 1: step k + 1's */
#define BIND_CELLS_BUF_CELLS 0      /* the pyramid, written */
#define BIND_CELLS_BUF_SCRATCH 1    /* cells_distance.comp: two passes' distances */

/* ---- opaque pass (shaders/opaque.vert, opaque.frag) ---------------------------------------
 * Reads the light map's units too.  renderer_draw binds the eye pass's units before it draws
 * the opaque geometry, so the mesh texture's unit must differ from those as well. */
#define BIND_OPAQUE_TEX_MESH 5  /* RGBA8 texture of a textured mesh (text) */

/* ---- tone mapping (shaders/tonemap.comp) ---------------------------------------------- */
#define BIND_TONEMAP_IMG_IN 0   /* RGBA32F radiance */
#define BIND_TONEMAP_IMG_OUT 1  /* RGBA8 display sRGB (PACKED 1: R32UI, the bytes of a file) */
#define BIND_TONEMAP_BUF_NONFINITE 0  /* PACKED 1: pixels with a non-finite value */

/* ---- light build: every slice's extinction at once (shaders/light_slices.comp) -------- */
#define BIND_SLICES_TEX_BETA 0   /* the volume's extinction, texelFetch only */
#define BIND_SLICES_TEX_RATES 1  /* MULTIPLE and LATERAL: lateral escape rates */
#define BIND_SLICES_IMG_SLICE 0  /* each slice's tau, ice share (escape rates), written */
#define BIND_SLICES_BUF_CELLS 0  /* SKIP 1: the volume's macro cells (cells.glsl) */
#define BIND_SLICES_TEX_ZMAP 2   /* STRETCHED 1: the volume's height table (zmap.glsl) */

/* ---- light build: the beam's sweep from the sun (shaders/light_build.comp) ------------ */
#define BIND_BUILD_TEX_SLICE 0  /* the slices of light_slices.comp, texelFetch only */
#define BIND_BUILD_IMG_LIGHT 0  /* R32F node volume, read and written */

/* ---- light build: the diffuse column pass (shaders/light_diffuse.comp) ---------------- */
#define BIND_DIFFUSE_IMG_LIGHT 0    /* the beam at each node, read */
#define BIND_DIFFUSE_IMG_SLICE 1    /* the slices of the beam pass, read */
#define BIND_DIFFUSE_IMG_ADDING 2   /* scratch, read and written */
#define BIND_DIFFUSE_IMG_DIFFUSE 3  /* RG32F diffuse light, written */

/* ---- light build: compression on the GPU (shaders/light_compress.comp, light_scan.comp) */
#define BIND_COMPRESS_IMG_VALUES 0   /* the dense light (or diffuse light) volume, read */
#define BIND_COMPRESS_BUF_COLUMNS 0  /* first node and count per column */
#define BIND_COMPRESS_BUF_NODES 1    /* PASS 2: the nodes, written */
#define BIND_SCAN_BUF_COLUMNS 0      /* counts in, first nodes out */

/* ---- light build: the lateral escape rates (shaders/light_lateral.comp) --------------- */
#define BIND_LATERAL_TEX_BETA 0   /* the volume's extinction, texelFetch only */
#define BIND_LATERAL_IMG_RATES 0  /* RG32F rates along x and y, read and written */
#define BIND_LATERAL_BUF_CELLS 0  /* SKIP 1: the volume's macro cells (cells.glsl) */

/* ---- light build: the diffuse light volume (shaders/light_volume.comp) ---------------- */
#define BIND_VOLUME_TEX_BETA 0      /* PASS 1: the volume's extinction, texelFetch only */
#define BIND_VOLUME_TEX_LIGHT 1     /* PASS 1: the dense light map, texelFetch only */
#define BIND_VOLUME_TEX_ZMAP 2      /* PASS 1, STRETCHED 1: the volume's height table (zmap.glsl) */
#define BIND_VOLUME_IMG_FIELD 0     /* PASS 6: RGBA32F phi and net flux per cell, written */
#define BIND_VOLUME_BUF_TERMS 0     /* per cell: source, its moments, transport extinction */
#define BIND_VOLUME_BUF_SYSTEM 1    /* per cell: diagonal and conductances */
#define BIND_VOLUME_BUF_VECTORS 2   /* the solve's vectors b, x, r, z, p (two), q */
#define BIND_VOLUME_BUF_SCALARS 3   /* the solve's scalars, per-brick sums, coarse system */

/* ---- the peak fetch rate of anvil bench --gpu (shaders/fetch_peak.comp) -------------- */
#define BIND_PEAK_TEX_VOLUME 0
#define BIND_PEAK_IMG_OUT 0

/* ---- stereo composition (shaders/display_compose.comp) -------------------------------- */
#define BIND_COMPOSE_TEX_LEFT 0
#define BIND_COMPOSE_TEX_RIGHT 1
#define BIND_COMPOSE_IMG_OUT 0

/* ---- HMD lens warp (shaders/hmd_warp.comp) -------------------------------------------- */
#define BIND_WARP_TEX_EYE 0
#define BIND_WARP_IMG_OUT 0
