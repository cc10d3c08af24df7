/* The macro-cell pyramid of empty-space skipping (render.h, "empty-space skipping"): level 0
 * from the extinction texture (shaders/cells_build.comp), each further level the maxima of
 * the one below (shaders/cells_reduce.comp), all in one storage buffer behind a header of the
 * levels' sizes, so that the eye pass and the light build read it without uniform arrays. */
#include "render/render.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "common/log.h"
#include "shaders/bindings.h"

/* The buffer's header: RENDER_CELL_LEVELS ivec4 (cells along x, y, z, the level's first
 * index) and one ivec4 (levels, voxels per cell edge, the walk's top level, 0), as the shaders
 * declare it. */
#define HEADER_INTS (4 * RENDER_CELL_LEVELS + 4)

bool render_cells_programs_init(struct render_cells_programs *p)
{
    memset(p, 0, sizeof(*p));
    return gpu_program_init(&p->build[0], "cells_build.comp", "#define TEMPORAL 0\n") &&
           gpu_program_init(&p->build[1], "cells_build.comp", "#define TEMPORAL 1\n") &&
           gpu_program_init(&p->build[2], "cells_build.comp",
                            "#define TEMPORAL 0\n#define STRETCHED 1\n") &&
           gpu_program_init(&p->build[3], "cells_build.comp",
                            "#define TEMPORAL 1\n#define STRETCHED 1\n") &&
           gpu_program_init(&p->reduce, "cells_reduce.comp", NULL);
}

void render_cells_programs_finish(struct render_cells_programs *p)
{
    for (int i = 0; i < 4; i++)
        gpu_program_finish(&p->build[i]);
    gpu_program_finish(&p->reduce);
}

void render_cells_layout(const int n[3], int cell_voxels, struct render_cells *c)
{
    memset(c->dims, 0, sizeof(c->dims));
    c->cell_voxels = cell_voxels;
    size_t count = 0;
    int d[3];
    for (int a = 0; a < 3; a++)
        d[a] = (n[a] + cell_voxels - 1) / cell_voxels;
    int level = 0;
    for (;;) {
        for (int a = 0; a < 3; a++)
            c->dims[level][a] = d[a];
        c->dims[level][3] = (int)count;
        count += (size_t)d[0] * d[1] * d[2];
        level++;
        if ((d[0] == 1 && d[1] == 1 && d[2] == 1) || level == RENDER_CELL_LEVELS)
            break;
        for (int a = 0; a < 3; a++)
            d[a] = (d[a] + 1) / 2;
    }
    c->levels = level;
    c->count = count;
    c->walk_top = level - 1;
    while (c->walk_top > 0 && (size_t)c->dims[c->walk_top - 1][0] * c->dims[c->walk_top - 1][1] *
                                      c->dims[c->walk_top - 1][2] <=
                                  RENDER_CELL_WALK_CELLS)
        c->walk_top--;
}

/* A cell row's levels go to cells_build.comp in a uniform array of 32 (stretched grids only). */
_Static_assert((GRID3_LEVELS_MAX + RENDER_CELL_VOXELS_STRETCHED - 1) /
                       RENDER_CELL_VOXELS_STRETCHED <= 32,
               "cell_levels[] holds every cell row");

/* The levels a trilinear sample within half a (mean) voxel of cell row CZ reads, on a
 * stretched GRID with cells CELL_VOXELS mean levels tall. */
static void row_levels(const struct grid3 *grid, int cell_voxels, int cz, int range[2])
{
    double h = cell_voxels * grid->spacing[2], z0 = grid->origin[2] + cz * h;
    grid3_z_voxel_range(grid, z0 - 0.5 * grid->spacing[2], z0 + h + 0.5 * grid->spacing[2],
                        &range[0], &range[1]);
}

void render_cells_level_rows(const struct render_cells *c, const struct grid3 *grid, int *row)
{
    for (int k = 0; k < grid->n[2]; k++)
        row[k] = k / c->cell_voxels;
    if (!grid3_stretched(grid))
        return;
    /* Cells are even in height: the rows reading level k are not k / cell_voxels. */
    for (int k = 0; k < grid->n[2]; k++)
        row[k] = -1;
    for (int cz = c->dims[0][2] - 1; cz >= 0; cz--) {
        int range[2];
        row_levels(grid, c->cell_voxels, cz, range);
        for (int k = range[0]; k <= range[1]; k++)
            row[k] = cz;
    }
}

bool render_zmap_upload(const struct grid3 *grid, struct gpu_texture *tex,
                        const struct gpu_program *prog)
{
    int n = grid3_zmap_entries(grid);
    float *t = malloc((size_t)n * 4 * sizeof(float));
    if (!t) {
        log_error("out of memory for the height table");
        return false;
    }
    float *u = t + 2 * (size_t)n, *dz = u + n;
    grid3_zmap_fill(grid, n, u, dz);
    for (int i = 0; i < n; i++) { /* interleaved: r the coordinate, g the thickness */
        t[2 * i] = u[i];
        t[2 * i + 1] = dz[i];
    }
    const int size[3] = {n, 1, 1};
    bool ok = true;
    if (tex->id && tex->size[0] == n && tex->format == GPU_RG32F) {
        gpu_texture_upload(tex, t);
    } else {
        gpu_texture_finish(tex);
        ok = gpu_texture_init(tex, 1, size, GPU_RG32F, t);
    }
    free(t);
    if (ok && prog)
        render_zmap_uniforms(grid, tex, prog);
    return ok;
}

void render_zmap_uniforms(const struct grid3 *grid, const struct gpu_texture *tex,
                          const struct gpu_program *prog)
{
    gpu_uniform_int(prog, "zmap_n", tex->size[0]);
    gpu_uniform_float(prog, "zmap_inv_height", (float)(1.0 / (grid->n[2] * grid->spacing[2])));
}

bool render_cells_build_begin(struct render_cells *c, const struct gpu_texture *beta,
                              const struct grid3 *grid)
{
    bool stretched = grid && grid3_stretched(grid);
    struct render_cells layout = {0};
    render_cells_layout(beta->size, stretched ? RENDER_CELL_VOXELS_STRETCHED : RENDER_CELL_VOXELS,
                        &layout);
    size_t bytes = HEADER_INTS * sizeof(int) + layout.count * sizeof(float);
    if (!c->buf.id || c->buf.bytes != bytes) {
        gpu_buffer_finish(&c->buf);
        if (!gpu_buffer_init(&c->buf, bytes, NULL)) {
            c->levels = 0;
            return false;
        }
    }
    struct gpu_buffer buf = c->buf;
    *c = layout;
    c->buf = buf;
    c->built_layers = 0;
    c->built_rows = 0;
    int header[HEADER_INTS] = {0};
    memcpy(header, c->dims, sizeof(c->dims));
    header[4 * RENDER_CELL_LEVELS] = c->levels;
    header[4 * RENDER_CELL_LEVELS + 1] = c->cell_voxels;
    header[4 * RENDER_CELL_LEVELS + 2] = c->walk_top;
    gpu_buffer_upload(&c->buf, 0, sizeof(header), header);
    return true;
}

bool render_cells_build_step(struct render_cells *c, const struct render_cells_programs *p,
                             const struct gpu_texture *beta, const struct gpu_texture *next,
                             const struct grid3 *grid, int layers, bool *done)
{
    return render_cells_build_piece(c, p, beta, next, grid, layers, 0, done);
}

bool render_cells_build_piece(struct render_cells *c, const struct render_cells_programs *p,
                              const struct gpu_texture *beta, const struct gpu_texture *next,
                              const struct grid3 *grid, int layers, int rows, bool *done)
{
    *done = false;
    if (c->built_layers >= c->dims[0][2]) {
        /* The coarser levels, each from the one below. */
        gpu_buffer_bind(&c->buf, BIND_CELLS_BUF_CELLS);
        for (int level = 1; level < c->levels; level++) {
            gpu_uniform_int(&p->reduce, "level", level);
            gpu_dispatch(&p->reduce, c->dims[level][0], c->dims[level][1], c->dims[level][2]);
        }
        *done = true;
        return true;
    }
    int from = c->built_layers, count = c->dims[0][2] - from;
    if (layers > 0 && layers < count)
        count = layers;
    int y0 = c->built_rows, ny = c->dims[0][1] - y0;
    if (rows > 0 && rows < ny)
        ny = rows;
    bool stretched = grid && grid3_stretched(grid);
    const struct gpu_program *b = &p->build[(next ? 1 : 0) | (stretched ? 2 : 0)];
    gpu_uniform_ivec3(b, "vol_n", beta->size);
    for (int cz = 0; stretched && cz < c->dims[0][2]; cz++) {
        int range[2];
        row_levels(grid, c->cell_voxels, cz, range);
        char name[32];
        snprintf(name, sizeof(name), "cell_levels[%d]", cz);
        gpu_uniform_ivec2(b, name, range);
    }
    gpu_uniform_int(b, "base_z", from);
    gpu_uniform_int(b, "base_y", y0);
    gpu_texture_bind(beta, BIND_CELLS_TEX_BETA);
    if (next)
        gpu_texture_bind(next, BIND_CELLS_TEX_BETA_NEXT);
    gpu_buffer_bind(&c->buf, BIND_CELLS_BUF_CELLS);
    gpu_dispatch(b, c->dims[0][0], ny, count);
    if (y0 + ny < c->dims[0][1]) {
        c->built_rows = y0 + ny; /* the same layers' next rows next */
    } else {
        c->built_layers = from + count;
        c->built_rows = 0;
    }
    return true;
}

bool render_cells_build(struct render_cells *c, const struct render_cells_programs *p,
                        const struct gpu_texture *beta, const struct gpu_texture *next,
                        const struct grid3 *grid)
{
    bool done = false;
    return render_cells_build_begin(c, beta, grid) &&
           render_cells_build_step(c, p, beta, next, grid, 0, &done) &&
           render_cells_build_step(c, p, beta, next, grid, 0, &done);
}

bool render_cells_max(struct render_cells *c, const struct render_cells *a,
                      const struct render_cells *b, const struct gpu_texture *beta,
                      const struct grid3 *grid)
{
    if (!render_cells_build_begin(c, beta, grid))
        return false;
    if (a->count != c->count || b->count != c->count) {
        log_error("macro cells: %zu and %zu cells do not make a pair of %zu", a->count, b->count,
                  c->count);
        return false;
    }
    float *x = render_cells_read(a), *y = render_cells_read(b);
    bool ok = x && y;
    if (ok) {
        /* Every level is a maximum over the same voxels: the maximum of the two. */
        for (size_t i = 0; i < c->count; i++)
            x[i] = y[i] > x[i] ? y[i] : x[i];
        gpu_buffer_upload(&c->buf, HEADER_INTS * sizeof(int), c->count * sizeof(float), x);
        c->built_layers = c->dims[0][2];
    }
    free(x);
    free(y);
    return ok;
}

void render_cells_finish(struct render_cells *c)
{
    gpu_buffer_finish(&c->buf);
    memset(c, 0, sizeof(*c));
}

void render_cells_bind(const struct render_cells *c, const struct gpu_program *prog,
                       unsigned binding, const struct grid3 *grid)
{
    float size[3];
    for (int a = 0; a < 3; a++)
        size[a] = (float)(c->cell_voxels * grid->spacing[a]);
    gpu_uniform_vec3(prog, "cell_size", size);
    gpu_buffer_bind(&c->buf, binding);
}

float *render_cells_read(const struct render_cells *c)
{
    if (!c->buf.id)
        return NULL;
    float *out = malloc(c->count * sizeof(float));
    if (!out) {
        log_error("out of memory reading %zu macro cells", c->count);
        return NULL;
    }
    gpu_buffer_read(&c->buf, HEADER_INTS * sizeof(int), c->count * sizeof(float), out);
    return out;
}
