// Empty-space skipping: level 0 of the macro-cell pyramid (render/cells.c).  One invocation
// per cell of CELL_VOXELS^3 voxels stores the largest extinction, ice plus water, of the
// voxels trilinear interpolation anywhere in the cell can read: the cell's own and one voxel
// around it (a point within half a voxel of the cell still reads only these), clamped to the
// volume like the sampler.  NaN and negative values read as 0, as the eye pass and the light
// build read them, so a cell holding 0 is one where every sample is exactly 0.
// TEMPORAL 1: the largest of two volumes of one grid (step k and step k + 1).
// STRETCHED 1: the volume's levels are the model's (data/volume.h) and the cells even in
// height, CELL_VOXELS mean levels tall: each cell row reads the levels cell_levels gives.

#include "bindings.h"

#ifndef TEMPORAL
#define TEMPORAL 0
#endif
#ifndef STRETCHED
#define STRETCHED 0
#endif

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(binding = BIND_CELLS_TEX_BETA) uniform sampler3D beta_tex; // texelFetch only
#if TEMPORAL
layout(binding = BIND_CELLS_TEX_BETA_NEXT) uniform sampler3D beta_next_tex;
#endif
layout(std430, binding = BIND_CELLS_BUF_CELLS) buffer macro_cells {
    ivec4 cell_dims[16]; // cells along x, y, z and the level's first index
    ivec4 cell_header;   // levels, voxels per cell edge
    float cell_max[];
};

uniform ivec3 vol_n;
uniform int base_z; // the first cell layer of this dispatch (a build in pieces)
uniform int base_y; // the first cell row of this dispatch (a build in pieces)
#if STRETCHED
uniform ivec2 cell_levels[32]; // per cell row: the first and last level it reads
#endif

float clean(vec2 b)
{
    return (b.x > 0.0 ? min(b.x, 1e30) : 0.0) + (b.y > 0.0 ? min(b.y, 1e30) : 0.0);
}

void main()
{
    ivec3 c = ivec3(gl_GlobalInvocationID) + ivec3(0, base_y, base_z);
    ivec3 dims = cell_dims[0].xyz;
    if (any(greaterThanEqual(c, dims)))
        return;
    int b = cell_header.y;
    ivec3 lo = max(c * b - 1, ivec3(0));
    ivec3 hi = min(c * b + b, vol_n - 1);
#if STRETCHED
    lo.z = cell_levels[c.z].x;
    hi.z = cell_levels[c.z].y;
#endif
    float m = 0.0;
    for (int z = lo.z; z <= hi.z; z++)
        for (int y = lo.y; y <= hi.y; y++)
            for (int x = lo.x; x <= hi.x; x++) {
                m = max(m, clean(texelFetch(beta_tex, ivec3(x, y, z), 0).rg));
#if TEMPORAL
                m = max(m, clean(texelFetch(beta_next_tex, ivec3(x, y, z), 0).rg));
#endif
            }
    cell_max[cell_dims[0].w + c.x + dims.x * (c.y + dims.y * c.z)] = m;
}
