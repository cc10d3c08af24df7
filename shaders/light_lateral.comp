// Deep light map, multiple scattering with lateral escape: each voxel's extinction times its
// lateral escape rate along one horizontal axis (docs/lightmap.md, "Lateral escape").  The
// rate is 1 / w, w the optical width of the run of cloudy voxels that holds the voxel; clear
// voxels keep the 0 the texture was cleared to.  One invocation per stretch of SEGMENT voxels
// of a row: for every run that starts in its stretch it walks the run (into the next
// stretches if it goes on), summing its width from its lower end, then walks it again writing
// each voxel's rate; so the stretches of every row go in parallel.  Mirrors
// light_lateral_rates() in src/light/transport.c operation for operation in float32: the pass
// along x writes .r, the pass along y then writes .g beside it.
// SKIP 1: an empty macro cell (render/cells.c) holds no cloudy voxel: it is passed in one step.
// Cells are even in height, so on the model's levels a level's cell row is not its index over
// the cell's voxels: level_rows gives it (render_cells_level_rows; -1: none, read every voxel).

#include "bindings.h"

#ifndef SKIP
#define SKIP 0
#endif

// voxels a stretch of a row holds (eight 4^3 macro cells, four 8^3 ones on the model's levels)
#define SEGMENT 32

layout(local_size_x = 8, local_size_y = 1, local_size_z = 8) in;

layout(binding = BIND_LATERAL_TEX_BETA) uniform sampler3D beta_tex;       // texelFetch only
layout(rg32f, binding = BIND_LATERAL_IMG_RATES) uniform image3D rates_img; // beta / w: x, y
#if SKIP
layout(std430, binding = BIND_LATERAL_BUF_CELLS) readonly buffer macro_cells {
    ivec4 cell_dims[16]; // cells along x, y, z and the level's first index
    ivec4 cell_header;   // levels, voxels per cell edge
    float cell_max[];
};
#include "cells.glsl"
uniform ivec4 level_rows[64]; // level k's cell row: level_rows[k / 4][k % 4]
#endif

uniform ivec3 vol_n;
uniform int base_z;       // the first level of this dispatch (a build in pieces)
uniform int axis;         // 0: runs along x, 1: along y
uniform float spacing;    // metres between voxels along the axis
uniform float clear_beta; // LIGHT_CLEAR_BETA

float beta_at(ivec3 c)
{
    vec2 b = texelFetch(beta_tex, c, 0).rg;
    return b.x + b.y;
}

void main()
{
    // x: the row (y for runs along x, x for runs along y), y: the stretch, z: the level
    int len = vol_n[axis], rows = vol_n[1 - axis];
    ivec3 id = ivec3(gl_GlobalInvocationID) + ivec3(0, 0, base_z);
    int start = id.y * SEGMENT;
    if (id.x >= rows || start >= len || id.z >= vol_n.z)
        return;
    ivec3 step = axis == 0 ? ivec3(1, 0, 0) : ivec3(0, 1, 0);
    ivec3 row = axis == 0 ? ivec3(0, id.x, id.z) : ivec3(id.x, 0, id.z);
    int stop = min(start + SEGMENT, len);
#if SKIP
    int b = cell_header.y, cell_row = level_rows[id.z >> 2][id.z & 3];
    // A stretch is 2^L level-0 cells along the axis, one cell of level L: when that cell holds
    // nothing, no voxel of the stretch is cloudy, nor the voxel before it (a cell's value
    // covers one voxel around it), so the stretch writes nothing and is done at one read.
    int stretch_level = findMSB(SEGMENT / b);
    if (cell_row >= 0 && stretch_level < cell_header.x) {
        ivec3 c = ivec3((row + start * step).xy / b, cell_row) >> stretch_level;
        if (cell_max[cell_index(c, stretch_level)] <= 0.0)
            return;
    }
#endif
    int i = start;
    // A run that came in from the stretch before is that stretch's: pass it.
    if (i > 0 && beta_at(row + (i - 1) * step) >= clear_beta)
        while (i < len && beta_at(row + i * step) >= clear_beta)
            i++;
    while (i < stop) {
#if SKIP
        ivec3 cell = ivec3((row + i * step).xy / b, cell_row);
        if (cell_row >= 0 && cell_max[cell_index(cell, 0)] <= 0.0) {
            i = (i / b + 1) * b; // the rest of an empty cell: clear
            continue;
        }
#endif
        if (!(beta_at(row + i * step) >= clear_beta)) { // clear, or NaN
            i++;
            continue;
        }
        // A run starts at i: its width, then every voxel's rate.
        float w = 0.0;
        int end = i;
        for (; end < len; end++) {
            float be = beta_at(row + end * step);
            if (!(be >= clear_beta))
                break;
            w = w + min(be, 1e30) * spacing;
        }
        for (int m = i; m < end; m++) {
            ivec3 v = row + m * step;
            float rate = min(beta_at(v), 1e30) / w;
            if (axis == 0)
                imageStore(rates_img, v, vec4(rate, 0.0, 0.0, 0.0));
            else
                imageStore(rates_img, v, vec4(imageLoad(rates_img, v).r, rate, 0.0, 0.0));
        }
        i = end;
    }
}
