// For tests/tools/time_cells: one texelFetch of every voxel of the extinction texture and
// nothing else (a store no value reaches, so that the fetch stays), to time what a first read
// of a texture just uploaded costs apart from the macro cells' build (cells_build.comp).
#include "bindings.h"
layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;
layout(binding = BIND_CELLS_TEX_BETA) uniform sampler3D beta_tex;
layout(std430, binding = BIND_CELLS_BUF_CELLS) buffer macro_cells {
    ivec4 cell_dims[16];
    ivec4 cell_header;
    float cell_max[];
};
uniform ivec3 vol_n;
void main()
{
    ivec3 v = ivec3(gl_GlobalInvocationID);
    if (any(greaterThanEqual(v, vol_n)))
        return;
    vec2 b = texelFetch(beta_tex, v, 0).rg;
    if (b.x + b.y < -1.0)
        cell_max[0] = b.x;
}
