// Empty-space skipping: lookups in the macro-cell pyramid (render/cells.c, cells_build.comp).
// The including program declares the storage block `macro_cells` (cell_dims, cell_header,
// cell_max) at its own binding.  Level L's cells are 2^L level-0 cells of cell_header.y
// voxels on a side; a cell holding 0 or less is one in which every trilinear sample of the
// volume, taken anywhere within half a voxel of it, reads exactly 0.  A clear level-0 cell
// holds −d (cells_distance.comp): no cell within d − 1 cells of it along every axis holds
// anything.

// The index in cell_max of the cell of level L holding C (cells, clamped to the level).
int cell_index(ivec3 c, int level)
{
    ivec4 d = cell_dims[level];
    c = clamp(c, ivec3(0), d.xyz - 1);
    return d.w + c.x + d.x * (c.y + d.y * c.z);
}

// Whether the level-0 cell holding the voxel coordinate X (voxel units from the volume's
// corner) is clear: then the trilinear sample at X reads 0.
bool cell_clear_at_voxel(vec3 x)
{
    ivec3 c = ivec3(floor(x / float(cell_header.y)));
    return cell_max[cell_index(c, 0)] <= 0.0;
}

// Whether the whole volume holds nothing: its one top cell reads 0 (an empty box, or a step
// with no cloud), known from one read where the walk would read a row of level 0's cells.
bool cells_all_clear(inout uint cells)
{
    int root = cell_header.x - 1;
    if (any(notEqual(cell_dims[root].xyz, ivec3(1))))
        return false; // the pyramid stopped short of one cell (RENDER_CELL_LEVELS)
    cells++;
    return cell_max[cell_dims[root].w] <= 0.0;
}

// From T on, the ray ORIGIN + t DIR (INV_DIR: 1 / DIR, finite) crosses cells that hold
// nothing up to the returned parameter (T itself when T's level-0 cell is occupied, at most
// T_END); OCCUPIED_END is where the occupied level-0 cell it stopped at ends (the return value
// when it stopped at T_END).  BOX_MIN is the volume's corner, CELL_SIZE a level-0 cell in
// metres, NUDGE a distance far below half a voxel that steps a point off a cell's face.
// The walk reads level 0 only: a clear cell holds −d (cells_distance.comp), and the cube of
// 2 d − 1 cells around it holds nothing, so the ray leaps to where it leaves that cube (a
// cell holding 0, whose distance was not made, is a cube of one).  CELLS counts the cells it
// read.
float cells_skip(vec3 origin, vec3 dir, vec3 inv_dir, float t, float t_end, vec3 box_min,
                 vec3 cell_size, float nudge, out float occupied_end, inout uint cells)
{
    ivec3 last = cell_dims[0].xyz - 1;
    for (int it = 0; it < 1024 && t < t_end; it++) {
        float nt = max(nudge, 4e-7 * abs(t));
        vec3 p = origin + dir * (t + nt);
        ivec3 c = clamp(ivec3(floor((p - box_min) / cell_size)), ivec3(0), last);
        float m = cell_max[cell_index(c, 0)];
        cells++;
        float r = max(-m - 1.0, 0.0);
        vec3 lo = box_min + (vec3(c) - r) * cell_size;
        vec3 hi = box_min + (vec3(c) + 1.0 + r) * cell_size;
        vec3 ta = (lo - origin) * inv_dir, tb = (hi - origin) * inv_dir;
        vec3 tx = max(ta, tb);
        float exit = min(tx.x, min(tx.y, tx.z));
        if (m > 0.0) {
            occupied_end = max(exit, t + nt);
            return t;
        }
        t = max(exit, t + nt);
    }
    t = min(t, t_end);
    occupied_end = t;
    return t;
}
