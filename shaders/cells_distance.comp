// Empty-space skipping: the clear distances of level 0 of the macro-cell pyramid
// (render/cells.c).  A clear cell's value becomes −d, where d ≥ 1 is the Chebyshev distance, in
// cells, to the nearest occupied cell, at most CELL_DISTANCE_MAX + 1 (render.h): every cell of
// the cube of 2 d − 1 cells around it holds nothing, so a ray leaps the cube at one read
// (cells.glsl).  In the Chebyshev metric the distance is separable, one pass an axis, each
// g(i) = min over j of max(|i − j|, f(j)) along the axis' lines of cells, f the pass before:
// PASS 0 along x from the pyramid's occupancy (f = 0 in an occupied cell) into the scratch's
// first half, PASS 1 along y into its second half, PASS 2 along z back into level 0, where the
// occupied cells keep their maxima.  One invocation a line, which it sweeps forward and back:
// since f takes the values 0 … CELL_DISTANCE_MAX + 1, the latest cell of each value or less
// is all the sweep needs to remember.

#include "bindings.h"

layout(local_size_x = 64) in;

layout(std430, binding = BIND_CELLS_BUF_CELLS) buffer macro_cells {
    ivec4 cell_dims[16];
    ivec4 cell_header;
    float cell_max[];
};
layout(std430, binding = BIND_CELLS_BUF_SCRATCH) buffer scratch_cells {
    float scratch[];
};

uniform int pass;

#define FAR (CELL_DISTANCE_MAX + 1)

// The distance before this pass at level 0's cell J (N cells a level).
int source(int j, int n)
{
    if (pass == 0)
        return cell_max[cell_dims[0].w + j] > 0.0 ? 0 : FAR;
    return int(scratch[(pass - 1) * n + j]);
}

// This pass's distance at J as far as it is written (the forward sweep's).
int written(int j, int n)
{
    if (pass < 2)
        return int(scratch[pass * n + j]);
    float m = cell_max[cell_dims[0].w + j];
    return m > 0.0 ? 0 : int(-m);
}

void write(int j, int n, int g)
{
    if (pass < 2)
        scratch[pass * n + j] = float(g);
    else if (g > 0) // a clear cell (an occupied one has g = 0 and keeps its maximum)
        cell_max[cell_dims[0].w + j] = -float(g);
}

void main()
{
    ivec4 d = cell_dims[0];
    int n = d.x * d.y * d.z;
    // The line: along x, y or z, through the cells (u, v) of the other two axes.
    ivec3 dims = d.xyz;
    int len = pass == 0 ? dims.x : pass == 1 ? dims.y : dims.z;
    int nu = pass == 0 ? dims.y : dims.x;
    int nv = pass == 2 ? dims.y : dims.z;
    int line = int(gl_GlobalInvocationID.x);
    if (line >= nu * nv)
        return;
    int u = line % nu, v = line / nu;
    int base = pass == 0 ? d.x * (u + d.y * v) : pass == 1 ? u + d.x * d.y * v : u + d.x * v;
    int stride = pass == 0 ? 1 : pass == 1 ? d.x : d.x * d.y;
    // last[w]: how far back the latest cell of f ≤ w is (FAR or more: none near enough).
    int last[FAR + 1];
    for (int sweep = 0; sweep < 2; sweep++) {
        for (int w = 0; w <= FAR; w++)
            last[w] = FAR;
        for (int s = 0; s < len; s++) {
            int i = sweep == 0 ? s : len - 1 - s;
            int j = base + i * stride;
            int f = source(j, n);
            int g = sweep == 0 ? FAR : written(j, n);
            for (int w = 0; w <= FAR; w++) {
                last[w] = f <= w ? 0 : min(last[w] + 1, FAR);
                g = min(g, max(last[w], w));
            }
            write(j, n, g);
        }
    }
}
