// Empty-space skipping: level L of the macro-cell pyramid (render/cells.c) from level L - 1,
// each cell the largest of the 2 x 2 x 2 cells below it (fewer at the far faces).

#include "bindings.h"

layout(local_size_x = 4, local_size_y = 4, local_size_z = 4) in;

layout(std430, binding = BIND_CELLS_BUF_CELLS) buffer macro_cells {
    ivec4 cell_dims[16];
    ivec4 cell_header;
    float cell_max[];
};

uniform int level;

void main()
{
    ivec3 c = ivec3(gl_GlobalInvocationID);
    ivec4 d = cell_dims[level], below = cell_dims[level - 1];
    if (any(greaterThanEqual(c, d.xyz)))
        return;
    ivec3 lo = 2 * c, hi = min(2 * c + 1, below.xyz - 1);
    float m = 0.0;
    for (int z = lo.z; z <= hi.z; z++)
        for (int y = lo.y; y <= hi.y; y++)
            for (int x = lo.x; x <= hi.x; x++)
                m = max(m, cell_max[below.w + x + below.x * (y + below.y * z)]);
    cell_max[d.w + c.x + d.x * (c.y + d.y * c.z)] = m;
}
